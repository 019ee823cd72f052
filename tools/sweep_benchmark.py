"""Measure summary-only sweeps (issue 30, item 7) and write docs/sweeps.md.

Repository tooling (not installed): ``python tools/sweep_benchmark.py [--cases N]
[--memory-cases M]`` runs the variability study's sweep machinery
(:func:`deckpound.compare.studies.variability.sweep_rows`: one summary row per case, no histories) on
the built-in benchmark with N seeds of its 20 s synthetic record, on 1 and on 2 worker
processes, each into an empty row cache, and reports

* cases per second (compile time excluded: the kernels are loaded before the clock starts);
* the overhead over the step loops: workers × wall time / Σ loop time − 1 (record synthesis,
  result assembly, row cache, inter-process traffic);
* the peak resident memory of the parent and of the largest worker during a sweep of M cases.

Timings depend on the machine and on what else it runs: run it on an otherwise idle machine.
The numbers are measurements, not pass/fail tests.
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

from deckpound.compare.engines import run_engine
from deckpound.compare.pool import pool_scope
from deckpound.compare.studies.variability import seed_cases, sweep_rows
from deckpound.models.scene_io import load_scene

PAGE = Path(__file__).resolve().parents[1] / "docs" / "sweeps.md"


def sweep(scene, cases: int, workers: int) -> dict:
    scenes = [sc for _, _, sc in seed_cases(scene, cases)]
    with tempfile.TemporaryDirectory() as cache, pool_scope():
        t0 = time.perf_counter()
        rows, computed = sweep_rows(
            scenes, "compliance", Path(cache), "bench", workers=workers, progress=False
        )
        wall = time.perf_counter() - t0
    loop = float(np.nansum([r.get("loop_time", np.nan) for r in rows.values()]))
    return {
        "workers": workers,
        "cases": computed,
        "wall": wall,
        "rate": computed / wall,
        "overhead": workers * wall / loop - 1.0,
        "finished": sum(r.get("status") == "success" for r in rows.values()),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=400)
    ap.add_argument("--memory-cases", type=int, default=2000)
    args = ap.parse_args()
    scene = load_scene("saiidi-4span")
    run_engine("compliance", scene)  # load the kernels before any clock starts
    runs = [sweep(scene, args.cases, w) for w in (1, 2)]
    big = sweep(scene, args.memory_cases, 2)
    parent = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    child = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    lines = [
        "# Summary-only sweeps, measured",
        "",
        "Written by `python tools/sweep_benchmark.py` (repository tooling) on the built-in",
        "benchmark: the compliance engine, 20 s synthetic records with different seeds, one",
        "summary row per case (peaks over every step, closures, seat margins, status; no",
        "histories), each sweep into an empty row cache. Machine-dependent measurements.",
        "",
        "| workers | cases | wall [s] | cases/s | overhead over the step loops |",
        "|---|---|---|---|---|",
    ]
    for r in [*runs, big]:
        lines.append(
            f"| {r['workers']} | {r['cases']} | {r['wall']:.1f} | {r['rate']:.1f} | "
            f"{100 * r['overhead']:.0f} % |"
        )
    lines += [
        "",
        f"Peak resident memory after these sweeps: parent {parent:.0f} MB, largest worker "
        f"{child:.0f} MB (the {args.memory_cases}-case sweep keeps one small row per case).",
        "",
    ]
    PAGE.write_text("\n".join(lines), encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

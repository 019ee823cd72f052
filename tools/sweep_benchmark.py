"""The sweep benchmark of issues 30 (item 7) and 33 (item 5): step loops against the reference
loop, summary-only sweeps on local workers and on a Dask cluster, and memory, measured in one
sitting; writes docs/results/sweeps.json and docs/sweeps.md.

Repository tooling (not installed)::

    python tools/sweep_benchmark.py                  # the full benchmark (an idle machine)
    python tools/sweep_benchmark.py --quick          # a check that it works (small, short)
    python tools/sweep_benchmark.py --render         # the page again from the stored file

It measures, one after the other in one process (so the ratios share the machine's state):

1. summary-only sweeps (:func:`deckpound.compare.studies.variability.sweep_rows`: one summary
   row per case, no histories, each sweep into an empty row cache) of N seeds of the 20 s
   synthetic record with the compliance engine: in this process (1 worker), on the local pool
   of 2 workers and on a local Dask cluster of two single-threaded worker processes; and an
   IDA on the local pool (synthetic station pairs written as PEER AT2 files, each scaled by
   one factor to levels of Sa(T₁): reading, processing and scaling records is in every case).
   Before the clock starts the kernels are loaded and the workers have run a few cases of
   other seeds or another pair (the steady rate of a sweep). Overhead over the step loops:
   workers × wall / Σ loop − 1. The sweeps come first, while this process has run nothing
   but the warm-up run, as the process of a ``deckpound`` command: the loop measurement
   compiles the lean numba port in this process, and an in-process sweep measured after it
   ran slower than the same sweep before it;
2. µs/step of the C reference loop, of the compliance engine and of the nonsmooth engine on
   the built-in benchmark (``benchmarks/reference_loop/run.py``'s :func:`measure`: interleaved
   rounds, medians) and their ratios, per step and over the record; and what the compliance
   loop does beyond the reference, each with its cost: the engine without its energy columns,
   with one output row and with neither, and the reference with the whole residual at the
   converged iterate (its ``REF_FULL_RESIDUAL`` build);
3. a sweep of M cases on 2 local workers in a fresh process, end to end (the cases built, the
   pool started, the sweep): its wall time, the peak resident memory of that process
   (``VmHWM``: its own address space, not ``ru_maxrss``, which a fresh process inherits) and of its largest worker (``RUSAGE_CHILDREN``, read after the pool's
   workers are joined, i.e. reaped; and ``VmHWM`` of the living workers before that);
4. the peak memory of one run against its output length
   (:func:`deckpound.compare.bench.memory.peak_rss`, a fresh process per run) for both analytic
   engines and records of several lengths at the default output rate, beside the raw output
   (rows × columns × 8 B).

The page (:func:`render`, from the stored file only) states every target of the two issues
next to its measured value with a verdict computed from the file; ``tests/docs/
test_docs_sweeps.py`` renders the stored file again and fails when the page differs. Timings
depend on the machine and on what else it runs: run the full benchmark on an idle machine.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.util
import json
import math
import multiprocessing
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from docs_blocks import DOCS, RESULTS, ROOT

from deckpound.compare.bench.memory import peak_resident_mb, peak_rss
from deckpound.compare.engines import run_engine
from deckpound.compare.pool import pool_scope
from deckpound.compare.studies.ida import ida_cases, synthetic_pairs
from deckpound.compare.studies.variability import FINISHED, seed_cases, sweep_rows
from deckpound.models.file_io import atomic_write_text
from deckpound.models.iir import load_compiled_filter
from deckpound.models.scene_io import load_scene

PAGE = DOCS / "sweeps.md"
#: the measurement behind the page
RESULTS_FILE = RESULTS / "sweeps.json"
REFERENCE_LOOP = ROOT / "benchmarks" / "reference_loop" / "run.py"
#: version of the measurement file's layout
FORMAT = 2
SCENE = "saiidi-4span"
#: the engine of the sweeps (the issues' targets are for the compliance engine)
SWEEP_ENGINE = "compliance"
#: the engines whose memory is measured against output length
MEMORY_ENGINES = ("compliance", "nonsmooth")
#: local workers of the sweeps (the issues' "2 cores")
WORKERS = 2
#: warm-up cases per worker before a timed sweep (other seeds than the timed ones)
WARM_CASES_PER_WORKER = 4
FULL = {"cases": 400, "memory_cases": 10_000, "rounds": 5, "repeats": 3,
        "durations": (20.0, 80.0, 320.0), "ida_pairs": 22, "ida_levels": 10}  # fmt: skip
QUICK = {"cases": 24, "memory_cases": 48, "rounds": 1, "repeats": 1,
         "durations": (5.0, 10.0, 20.0), "ida_pairs": 2, "ida_levels": 3}  # fmt: skip
#: the intensity measure of the IDA sweep and its levels: IDA_STEP, 2·IDA_STEP, ... [g]
IDA_IM = "sa-t1"
IDA_STEP = 0.1
#: where the IDA sweep ran (its row of the sweep table)
IDA_WHERE = "IDA on AT2 pairs, local pool"
MB = 1024.0 * 1024.0

# the targets of the issues (the sizes they are stated for, and the limits)
#: issue 30, item 7: summary-only sweeps cost at most this over the step loops
MAX_OVERHEAD = 0.15
#: issue 30, item 7: cases/s on 2 cores for the compliance engine
MIN_RATE = 30.0
#: issue 30, item 7: the memory of a sweep of TARGET_CASES cases [MB]
MAX_SWEEP_MB = 1024.0
#: issue 33, done when: TARGET_CASES runs in at most this [s] on 2 cores
MAX_SWEEP_SECONDS = 90.0
TARGET_CASES = 10_000
#: issue 33, done when: a Dask cluster of two workers within 15 % of the local pool
MAX_DASK_RATIO = 1.15
#: issue 33, done when: the loops within 1.5× of the reference loop
MAX_LOOP_RATIO = 1.5
#: issue 33, done when: a record of LONG_RECORD s at the default output rate in under this [MB]
MAX_LONG_RECORD_MB = 300.0
LONG_RECORD = 320.0
#: issue 33, item 3: peak memory at most about twice the raw output plus a constant
MAX_MEMORY_SLOPE = 2.0


# --------------------------------------------------------------------------- measurement
def reference_loop():
    """benchmarks/reference_loop/run.py as a module (the benchmarks are not installed)."""
    spec = importlib.util.spec_from_file_location("reference_loop_run", REFERENCE_LOOP)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses resolve the module by name
    spec.loader.exec_module(module)
    return module


def measure_loops(scene, rounds: int, repeats: int) -> dict:
    """µs/step and loop times [s] of the reference, compliance and nonsmooth loops (every
    timed round), of the variants that :func:`extras` compares, and how far the reference's
    deck peaks are from the compliance engine's."""
    ref = reference_loop()
    times = ref.measure(scene, rounds=rounds, repeats=repeats, variants=True)
    steps = times.problem.steps
    peaks = ref.reference_peaks(times.reports["reference"])
    last = times.compliance[-1]
    nonsmooth = times.nonsmooth[-1].meta
    return {
        "steps": steps,
        "dt": times.problem.dt,
        "ndof": times.ndof,
        "reference_us": times.reference_us(),
        "reference_loop_s": times.reference_seconds["reference"],
        "compliance_us": [r.meta["us_per_step"] for r in times.compliance],
        "compliance_loop_s": [r.meta["loop_time"] for r in times.compliance],
        "nonsmooth_us": [r.meta["us_per_step"] for r in times.nonsmooth],
        "nonsmooth_loop_s": [r.meta["loop_time"] for r in times.nonsmooth],
        "full_residual_us": times.reference_us(ref.FULL_RESIDUAL),
        "lean_us": times.reference_us(ref.LEAN),
        "lean_loop_s": times.reference_seconds[ref.LEAN],
        "no_energy_us": [r.meta["us_per_step"] for r in times.compliance_no_energy],
        "one_row_us": [r.meta["us_per_step"] for r in times.compliance_one_row],
        "bare_us": [r.meta["us_per_step"] for r in times.compliance_bare],
        "nonsmooth_steps": nonsmooth["steps"],
        "nonsmooth_h": nonsmooth["settings"]["h"],
        "peak_difference": max(
            ref.relative_difference(peaks[c], last.peak(c)) for c in ref.DECK_COLUMNS
        ),
    }


def _warm_then_timed(
    warm: list, scenes: list, folder: Path, workers: int, scheduler: str | None = None
) -> dict:
    """Sweep ``warm`` (the workers started, the kernels loaded), then time the sweep of
    ``scenes`` on the same workers, each into an empty row cache below ``folder``: workers,
    cases computed, wall time [s], Σ step loops [s] and cases finished."""
    opts = {"workers": workers, "scheduler": scheduler, "progress": False}
    sweep_rows(warm, SWEEP_ENGINE, folder / "warm", "warm", **opts)
    t0 = time.perf_counter()
    rows, computed = sweep_rows(scenes, SWEEP_ENGINE, folder / "timed", "bench", **opts)
    wall = time.perf_counter() - t0
    return {
        "workers": workers,
        "cases": computed,
        "wall": wall,
        # a refused or failed case has no finite loop time: it adds none
        "loop": math.fsum(v for r in rows.values() if math.isfinite(v := r.get("loop_time", 0.0))),
        "finished": sum(r.get("status") in FINISHED for r in rows.values()),
    }


def _timed_sweep(scene, cases: int, scheduler: str | None, workers: int) -> dict:
    """A sweep of ``cases`` seeds after a warm-up of other seeds on the same workers."""
    warm = seed_cases(
        scene.replace({"excitation.seed": scene.excitation.seed + cases}),
        WARM_CASES_PER_WORKER * workers,
    )
    scenes = [sc for _, _, sc in seed_cases(scene, cases)]
    with tempfile.TemporaryDirectory(prefix="deckpound-sweep-") as cache:
        return _warm_then_timed([sc for _, _, sc in warm], scenes, Path(cache), workers, scheduler)


def ida_sweep(scene, pairs: int, levels: int) -> dict:
    """A timed IDA on the local pool: ``pairs`` synthetic station pairs written as PEER AT2
    files (:func:`~deckpound.compare.studies.ida.synthetic_pairs`, the scene's record length),
    each scaled by one factor to ``levels`` levels of Sa(T₁) (the IDA's cases: reading,
    processing and scaling real records is part of each case), after a warm-up on another
    pair's levels."""
    duration = scene.excitation.duration
    grid = [IDA_STEP * (k + 1) for k in range(levels)]
    with tempfile.TemporaryDirectory(prefix="deckpound-ida-") as tmp:
        warm = synthetic_pairs(scene, Path(tmp) / "warm", 1, 10_000, duration)
        timed = synthetic_pairs(scene, Path(tmp) / "timed", pairs, 0, duration)
        warm_scenes = [sc for _, sc in ida_cases(scene, warm, IDA_IM, grid)]
        scenes = [sc for _, sc in ida_cases(scene, timed, IDA_IM, grid)]
        with pool_scope():
            out = _warm_then_timed(warm_scenes, scenes, Path(tmp), WORKERS)
    return {"where": IDA_WHERE, "pairs": pairs, "levels": levels, **out}


def local_sweep(scene, cases: int, workers: int) -> dict:
    """A timed sweep on ``workers`` local workers (1: in this process)."""
    with pool_scope():  # the warm-up's workers run the timed sweep
        out = _timed_sweep(scene, cases, None, workers)
    return {"where": "this process" if workers == 1 else "local pool", **out}


def dask_sweep(scene, cases: int) -> dict:
    """A timed sweep on a local Dask cluster of WORKERS single-threaded worker processes."""
    import logging

    from distributed import LocalCluster

    with LocalCluster(
        n_workers=WORKERS,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,  # no web server: the machine is shared
        silence_logs=logging.ERROR,
    ) as cluster:
        out = _timed_sweep(scene, cases, cluster.scheduler_address, WORKERS)
    return {"where": "Dask LocalCluster", **out}


def children_hwm_mb() -> list[float]:
    """The peak resident memory (``VmHWM``) of every living child process of this one [MB]
    (Linux ``/proc``; the children of all of its threads)."""
    pids = set()
    for listing in Path("/proc/self/task").glob("*/children"):
        pids.update(int(p) for p in listing.read_text().split())
    peaks = []
    for pid in sorted(pids):
        try:
            status = Path(f"/proc/{pid}/status").read_text()
        except OSError:
            continue  # ended meanwhile
        peaks += [
            int(ln.split()[1]) / 1024.0 for ln in status.splitlines() if ln.startswith("VmHWM:")
        ]
    return peaks


def memory_sweep_here(cases: int) -> dict:
    """A sweep of ``cases`` seeds on WORKERS local workers in this (fresh) process, end to end:
    wall time [s], this process's peak RSS and the largest worker's [MB], the latter read twice:
    ``VmHWM`` of the living workers when the sweep is done, and ``RUSAGE_CHILDREN`` (the
    largest reaped child) once the pool's workers are joined."""
    scene = load_scene(SCENE)
    with tempfile.TemporaryDirectory(prefix="deckpound-sweep-") as cache:
        t0 = time.perf_counter()
        with pool_scope():  # closing the scope joins (reaps) its workers
            scenes = [sc for _, _, sc in seed_cases(scene, cases)]
            rows, computed = sweep_rows(
                scenes, SWEEP_ENGINE, Path(cache), "memory", workers=WORKERS, progress=False
            )
            wall = time.perf_counter() - t0
            living = children_hwm_mb()
    if multiprocessing.active_children():
        raise RuntimeError("the sweep's workers are still running: their peak cannot be read")
    return {
        "cases": computed,
        "workers": WORKERS,
        "wall": wall,
        "finished": sum(r.get("status") in FINISHED for r in rows.values()),
        # RUSAGE_CHILDREN: the largest reaped child (KiB on Linux)
        "parent_mb": peak_resident_mb(),
        "worker_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0,
        "worker_hwm_mb": living,
    }


def memory_sweep(cases: int) -> dict:
    """:func:`memory_sweep_here` in a fresh process (nothing of this one counts)."""
    proc = subprocess.run(
        [sys.executable, str(Path(__file__).resolve()), "--memory-child", str(cases)],
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"the memory sweep failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def output_columns(engine: str) -> int:
    """Number of output columns of ``engine`` on the benchmark scene (independent of the
    record's length)."""
    short = load_scene(SCENE, ["excitation.duration=0.5", "run.duration=0.5"])
    return len(run_engine(engine, short).columns)


def output_memory(durations) -> list[dict]:
    """Peak RSS of one run per engine and record length D [s] (``excitation.duration`` =
    ``run.duration`` = D, default output rate), with its output's rows and columns."""
    out = []
    for engine in MEMORY_ENGINES:
        columns = output_columns(engine)
        for d in durations:
            m = peak_rss(engine, [f"excitation.duration={d:g}", f"run.duration={d:g}"], SCENE)
            keys = ("rows", "status", "peak_mb", "baseline_mb", "run_mb")
            out.append(
                {"engine": engine, "duration": d, "columns": columns, **{k: m[k] for k in keys}}
            )
    return out


def git_commit() -> str:
    """The repository's commit (``git rev-parse --short HEAD``), with ``-dirty`` when a file
    other than this tool's own outputs (the page and its measurement file, which an earlier
    sitting rewrote and which change nothing measured) differs from it; ``unknown`` without
    git."""
    try:
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
        )
        changed = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=ROOT,
            capture_output=True,
            text=True,
        )
    except OSError:
        return "unknown"
    commit = head.stdout.strip()
    if not commit:
        return "unknown"
    own = {PAGE.resolve(), RESULTS_FILE.resolve()}
    paths = [line[3:].strip() for line in changed.stdout.splitlines() if line.strip()]
    dirty = any((ROOT / p).resolve() not in own for p in paths)
    return commit + ("-dirty" if dirty else "")


def measure(settings: dict, quick: bool, say: Callable[[str], None] = print) -> dict:
    """Every measurement of the page, in one sitting (the module docstring)."""
    scene = load_scene(SCENE)
    load_before = os.getloadavg()
    started = time.perf_counter()
    run_engine(SWEEP_ENGINE, scene)  # the kernels loaded (or compiled) before any clock
    load_compiled_filter()  # the sweeps' scipy.signal now: the pools fork with it
    sweeps = []
    for workers in (1, WORKERS):
        say(f"summary-only sweep of {settings['cases']} cases, {workers} local worker(s)")
        sweeps.append(local_sweep(scene, settings["cases"], workers))
    say(f"summary-only sweep of {settings['cases']} cases on a local Dask cluster")
    sweeps.append(dask_sweep(scene, settings["cases"]))
    pairs, levels = settings["ida_pairs"], settings["ida_levels"]
    say(f"IDA of {pairs} AT2 pairs x {levels} levels, {WORKERS} local workers")
    sweeps.append(ida_sweep(scene, pairs, levels))
    # after the sweeps: it compiles the lean numba port in this process (module docstring)
    say("step loops against the reference loop")
    loops = measure_loops(scene, settings["rounds"], settings["repeats"])
    say(f"a sweep of {settings['memory_cases']} cases in a fresh process (memory)")
    big = memory_sweep(settings["memory_cases"])
    say("peak memory against output length")
    runs = output_memory(settings["durations"])
    context = {
        "date": datetime.date.today().isoformat(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "commit": git_commit(),
        "scene": SCENE,
        "record_duration": scene.excitation.duration,
        "output_dt": scene.run.output_dt,
        "quick": quick,
        "settings": {**settings, "durations": list(settings["durations"])},
        "load_before": load_before[0],
        "load_after": os.getloadavg()[0],
        "minutes": (time.perf_counter() - started) / 60.0,
    }
    return {
        "format": FORMAT,
        "context": context,
        "loops": loops,
        "sweeps": sweeps,
        "memory_sweep": big,
        "output_memory": runs,
    }


# --------------------------------------------------------------------------- the page
def _num(v: float, digits: int = 3) -> str:
    """``v`` to ``digits`` significant digits, at least the units."""
    return f"{v:.0f}" if abs(v) >= 10 ** (digits - 1) else f"{v:.{digits}g}"


def _verdict(value: float | None, limit: float, at_most: bool = True) -> str:
    if value is None:
        return "not measured"
    return "met" if (value <= limit if at_most else value >= limit) else "not met"


#: the rows of the seed sweeps on local workers (1: this process)
LOCAL_WHERE = ("this process", "local pool")


def overhead(sweep: dict) -> float:
    """A sweep's cost over its step loops: workers × wall / Σ loop − 1."""
    return sweep["workers"] * sweep["wall"] / sweep["loop"] - 1.0


def loop_figures(loops: dict) -> dict[str, dict[str, float]]:
    """Per loop (reference, its algorithm in numba, compliance, nonsmooth): µs/step (median,
    minimum), loop over the record [s] (median), and the ratios of the medians to the
    reference's."""
    out = {}
    for name in ("reference", "lean", "compliance", "nonsmooth"):
        us, loop = loops[f"{name}_us"], loops[f"{name}_loop_s"]
        out[name] = {
            "us": statistics.median(us),
            "us_min": min(us),
            "loop": statistics.median(loop),
        }
    for fig in out.values():
        fig["per_step"] = fig["us"] / out["reference"]["us"]
        fig["per_record"] = fig["loop"] / out["reference"]["loop"]
    return out


def memory_slope(runs: list[dict], engine: str) -> float | None:
    """Growth of the peak RSS per byte of raw output between the shortest and the longest
    record of ``engine`` [MB/MB]; None with fewer than two lengths."""
    mine = sorted((r for r in runs if r["engine"] == engine), key=lambda r: r["duration"])
    if len(mine) < 2:
        return None
    a, b = mine[0], mine[-1]
    return (b["peak_mb"] - a["peak_mb"]) / (raw_mb(b) - raw_mb(a))


def raw_mb(run: dict) -> float:
    """The raw output of a run: rows × columns × 8 B [MB]."""
    return run["rows"] * run["columns"] * 8 / MB


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    """A Markdown table: the header, its rule, one line per row of cells."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return lines + ["| " + " | ".join(cells) + " |" for cells in rows]


def _loop_lines(loops: dict) -> list[str]:
    figs = loop_figures(loops)
    steps = {
        "reference": (loops["dt"], loops["steps"]),
        "lean": (loops["dt"], loops["steps"]),
        "compliance": (loops["dt"], loops["steps"]),
    }
    steps["nonsmooth"] = (loops["nonsmooth_h"], loops["nonsmooth_steps"])
    label = {"reference": "reference (C, gcc -O3)",
             "lean": "the reference's algorithm in numba (`lean_numba.py`)",
             "compliance": "compliance", "nonsmooth": "nonsmooth (its own step)"}  # fmt: skip
    header = [
        "step loop",
        "step [s]",
        "steps",
        "µs/step (median)",
        "µs/step (min)",
        "× reference per step",
        "loop over the record [s]",
        "× reference over the record",
    ]
    rows = []
    for name, f in figs.items():
        h, n = steps[name]
        rows.append(
            [
                label[name],
                f"{h:g}",
                f"{n}",
                f"{f['us']:.3f}",
                f"{f['us_min']:.3f}",
                f"{f['per_step']:.2f}",
                f"{f['loop']:.4f}",
                f"{f['per_record']:.2f}",
            ]
        )
    return _table(header, rows)


def extras(loops: dict) -> list[tuple[str, str, float]]:
    """What the compliance loop does beyond the reference: (what, measured as, µs/step) from
    the medians of the stored rounds; the last row is the whole excess over the reference."""
    med = {k: statistics.median(loops[f"{k}_us"]) for k in
           ("reference", "compliance", "no_energy", "one_row", "bare", "full_residual",
            "lean")}  # fmt: skip
    comp, ref = med["compliance"], med["reference"]
    full_residual, compiler = med["full_residual"] - ref, med["lean"] - ref
    return [
        ("energy work terms and the energy columns",
         "compliance − compliance without energy columns (`channels=[]`)",
         comp - med["no_energy"]),
        ("output rows",
         "compliance − compliance with one output row",
         comp - med["one_row"]),
        ("the two together",
         "compliance − compliance with neither",
         comp - med["bare"]),
        ("the whole residual (springs, contacts) at a converged iterate that moved, where the "
         "reference sets only the materials' trial deformations (emulated: its cost in the C "
         "loop)",
         "reference with `REF_FULL_RESIDUAL` − reference",
         full_residual),
        ("numba's code against gcc's for the reference's own algorithm (not an extra: the "
         "compiler's share)",
         "the reference's algorithm in numba − reference",
         compiler),
        ("the rest: peaks and closures of every result column and seat margins at every "
         "step, the saved step start of the sub-step fallback, the record's interpolation, "
         "the contact-law dispatch, counters, the interrupt flag, and the engine's structure "
         "(bundles of arrays, stages shared by every scene option) against the lean loop's "
         "flat arrays",
         "compliance with neither − reference − the two rows above",
         med["bare"] - ref - full_residual - compiler),
        ("all of it: the compliance loop's excess over the reference",
         "compliance − reference",
         comp - ref),
    ]  # fmt: skip


def numba_floor(loops: dict) -> float:
    """(lean loop in numba + the energy columns' and output rows' cost) / reference, per step,
    from the rounds' medians: the ratio of a numba loop with no structural cost beyond what
    the engine must compute (module docstring of ``benchmarks/reference_loop/run.py``)."""
    med = {k: statistics.median(loops[f"{k}_us"]) for k in
           ("reference", "compliance", "bare", "lean")}  # fmt: skip
    return (med["lean"] + med["compliance"] - med["bare"]) / med["reference"]


def _extra_lines(loops: dict) -> list[str]:
    rows = extras(loops)
    total = rows[-1][2]
    header = ["what the compliance loop does beyond the reference", "measured as",
              "µs/step (median)", "share of the excess"]  # fmt: skip
    cells = [[what, how, f"{us:.3f}", f"{100 * us / total:.0f} %" if total > 0 else "–"]
             for what, how, us in rows]  # fmt: skip
    return _table(header, cells)


def _sweep_lines(sweeps: list[dict]) -> list[str]:
    header = [
        "where",
        "workers",
        "cases",
        "finished",
        "wall [s]",
        "cases/s",
        "Σ step loops [s]",
        "overhead over the step loops",
    ]
    rows = [
        [
            s["where"],
            f"{s['workers']}",
            f"{s['cases']}",
            f"{s['finished']}",
            f"{s['wall']:.1f}",
            f"{s['cases'] / s['wall']:.1f}",
            f"{s['loop']:.1f}",
            f"{100 * overhead(s):.0f} %",
        ]
        for s in sweeps
    ]
    return _table(header, rows)


def _memory_lines(runs: list[dict]) -> list[str]:
    header = [
        "engine",
        "record [s]",
        "status",
        "output rows",
        "columns",
        "raw output [MB]",
        "peak RSS [MB]",
        "after imports and warm-up [MB]",
        "the run's own [MB]",
        "run's own / raw",
    ]
    rows = [
        [
            r["engine"],
            f"{r['duration']:g}",
            r["status"],
            f"{r['rows']}",
            f"{r['columns']}",
            _num(raw_mb(r)),
            f"{r['peak_mb']:.0f}",
            f"{r['baseline_mb']:.0f}",
            f"{r['run_mb']:.0f}",
            f"{r['run_mb'] / raw_mb(r):.1f}",
        ]
        for r in runs
    ]
    return _table(header, rows)


def targets(m: dict) -> list[tuple[str, str, str, str]]:
    """(issue, target, measured, verdict) of every target of the two issues, from the stored
    measurement ``m``."""
    figs = loop_figures(m["loops"])
    local = {s["workers"]: s for s in m["sweeps"] if s["where"] in LOCAL_WHERE}
    dask = next(s for s in m["sweeps"] if s["where"] == "Dask LocalCluster")
    ida = [s for s in m["sweeps"] if s["where"] == IDA_WHERE]
    big = m["memory_sweep"]
    full_size = big["cases"] >= TARGET_CASES
    size = f"{big['cases']} cases" + ("" if full_size else f", fewer than {TARGET_CASES}")
    sweep_mb = big["parent_mb"] + big["workers"] * big["worker_mb"]
    out = []
    for s in (*local.values(), dask, *ida):
        where = "in this process" if s["workers"] == 1 else f"{s['where']}, {s['workers']} workers"
        out.append(
            (
                "30 (7)",
                f"summary-only sweeps cost at most {100 * MAX_OVERHEAD:.0f} % over the "
                f"step loops ({where})",
                f"{100 * overhead(s):.0f} %",
                _verdict(overhead(s), MAX_OVERHEAD),
            )
        )
    rate = local[WORKERS]["cases"] / local[WORKERS]["wall"]
    out.append(
        (
            "30 (7)",
            f"at least {MIN_RATE:g} cases/s on 2 cores, compliance engine, "
            f"{m['context']['record_duration']:g} s records (local pool)",
            f"{rate:.1f} cases/s",
            _verdict(rate, MIN_RATE, at_most=False),
        )
    )
    out.append(
        (
            "30 (7)",
            f"a {TARGET_CASES:,}-case sweep stays below {MAX_SWEEP_MB / 1024:g} GB of "
            "memory (this process + workers × largest worker)",
            f"{sweep_mb:.0f} MB ({size})",
            _verdict(sweep_mb if full_size else None, MAX_SWEEP_MB),
        )
    )
    out.append(
        (
            "33",
            f"{TARGET_CASES:,} runs ({m['context']['record_duration']:g} s records, "
            f"summary-only, compliance) in at most "
            f"{MAX_SWEEP_SECONDS:g} s on 2 cores",
            f"{big['wall']:.1f} s ({size})",
            _verdict(big["wall"] if full_size else None, MAX_SWEEP_SECONDS),
        )
    )
    ratio = dask["wall"] / local[WORKERS]["wall"]
    out.append(
        (
            "33",
            f"the same sweep on a local Dask cluster of two workers within "
            f"{100 * (MAX_DASK_RATIO - 1):.0f} % of the local pool (wall time ratio)",
            f"{ratio:.2f} ({dask['cases']} cases)",
            _verdict(ratio, MAX_DASK_RATIO),
        )
    )
    out.append(
        (
            "33",
            f"the compliance loop within {MAX_LOOP_RATIO:g}× of the reference loop per step",
            f"{figs['compliance']['per_step']:.2f}×",
            _verdict(figs["compliance"]["per_step"], MAX_LOOP_RATIO),
        )
    )
    for basis, key in (("per step (its own step)", "per_step"), ("over the record", "per_record")):
        out.append(
            (
                "33",
                f"the nonsmooth loop within {MAX_LOOP_RATIO:g}× of the compliance reference "
                f"loop, {basis}",
                f"{figs['nonsmooth'][key]:.2f}×",
                _verdict(figs["nonsmooth"][key], MAX_LOOP_RATIO),
            )
        )
    for engine in MEMORY_ENGINES:
        long = [
            r for r in m["output_memory"] if r["engine"] == engine and r["duration"] == LONG_RECORD
        ]
        out.append(
            (
                "33",
                f"a {LONG_RECORD:g} s record at the default output rate runs in under "
                f"{MAX_LONG_RECORD_MB:g} MB ({engine})",
                f"{long[0]['peak_mb']:.0f} MB" if long else "no such record measured",
                _verdict(long[0]["peak_mb"] if long else None, MAX_LONG_RECORD_MB),
            )
        )
        slope = memory_slope(m["output_memory"], engine)
        out.append(
            (
                "33 (3)",
                f"a run's peak memory at most about {MAX_MEMORY_SLOPE:g}× its raw output "
                f"plus a constant ({engine}: growth per MB of raw output)",
                "–" if slope is None else f"{slope:.1f} MB/MB",
                _verdict(slope, MAX_MEMORY_SLOPE),
            )
        )
    return out


def render(m: dict) -> str:
    """docs/sweeps.md from the stored measurement ``m`` (every number computed from it)."""
    if m.get("format") != FORMAT:
        raise ValueError(f"sweeps.json: format {m.get('format')!r}, this tool reads {FORMAT}")
    c, loops, big = m["context"], m["loops"], m["memory_sweep"]
    local2 = next(s for s in m["sweeps"] if s["where"] == "local pool")
    dask = next(s for s in m["sweeps"] if s["where"] == "Dask LocalCluster")
    quick = (
        [
            "",
            "**A quick run (`--quick`)**: few cases, one round, short records for the memory "
            "table; it checks that the benchmark works, its numbers test no target at its size.",
        ]
        if c["quick"]
        else []
    )
    lines = [
        "# Summary-only sweeps and step loops, measured",
        "",
        "Written by `python tools/sweep_benchmark.py` (repository tooling) from "
        "`docs/results/sweeps.json`; every number and verdict below is computed from that file "
        "(`tests/docs/test_docs_sweeps.py` renders it again). Measured in one sitting of "
        f"{c['minutes']:.1f} min on {c['date']}: {c['machine']}, {c['cpus']} CPUs, Python "
        f"{c['python']}, commit {c['commit']}, load average (1 min) {c['load_before']:.2f} "
        f"before and {c['load_after']:.2f} after. Machine-dependent measurements, not tests.",
        *quick,
        "",
        "## Targets",
        "",
        *_table(["issue", "target", "measured", "verdict"], [list(row) for row in targets(m)]),
        "",
        "## Step loops against the reference loop",
        "",
        f"The built-in benchmark ({c['scene']}, its {c['record_duration']:g} s synthetic "
        f"record, {loops['ndof']} DOF), timed by `benchmarks/reference_loop/run.py`'s "
        f"`measure` in {c['settings']['rounds']} interleaved round(s) (each: the reference loop "
        f"and its variants {c['settings']['repeats']}× each, each engine once): the step loop "
        "alone, medians. The "
        "reference is the lean C loop of the compliance engine's problem (what it leaves out: "
        "`benchmarks/reference_loop/README.md`); its peak deck "
        "displacements and rotation differ from the compliance engine's by at most "
        f"{loops['peak_difference']:.1e} (relative).",
        "",
        *_loop_lines(loops),
        "",
        "What the compliance loop does that the reference leaves out, and what each costs, "
        "measured in the same rounds (each a difference of medians; the first two overlap with "
        "the third, and the items need not add up exactly). Without energy columns and output "
        "rows the compliance loop runs at "
        f"{statistics.median(loops['bare_us']) / statistics.median(loops['reference_us']):.2f}× "
        "the reference per step. The reference's own algorithm written in numba "
        "(`benchmarks/reference_loop/lean_numba.py`: the C loop statement for statement, "
        "flat arrays, the same answer bit for bit, `tests/test_reference_loop.py`) runs at "
        f"{statistics.median(loops['lean_us']) / statistics.median(loops['reference_us']):.2f}×: "
        "that part of the excess is the compiler's, the rest is the engine's. That algorithm "
        "in numba plus the measured cost of the energy columns and output rows, which the "
        "engine's answer needs (the energy balance, the results), is "
        f"{numba_floor(loops):.2f}× the reference per step: a numba loop of this problem that "
        "keeps them and costs nothing else of its own would run there.",
        "",
        *_extra_lines(loops),
        "",
        "## Summary-only sweeps",
        "",
        f"{local2['cases']} seeds of the {c['record_duration']:g} s synthetic record with the "
        f"{SWEEP_ENGINE} engine, one summary row per case (peaks over every step, closures, seat "
        "margins, status; no histories), each sweep into an empty row cache, after "
        f"{WARM_CASES_PER_WORKER} warm-up cases per worker (kernels loaded, workers started). "
        "Overhead: workers × wall / Σ step loops − 1 (record synthesis, result assembly, row "
        "cache, inter-process traffic, idle workers). The Dask cluster is "
        f"`distributed.LocalCluster(n_workers={WORKERS}, threads_per_worker=1, processes=True)`; "
        f"its wall time is {dask['wall'] / local2['wall']:.2f}× the local pool's.",
        *_ida_sentence(m["sweeps"]),
        "",
        *_sweep_lines(m["sweeps"]),
        "",
        f"A sweep of {big['cases']} cases on {big['workers']} local workers in a fresh process, "
        "end to end (the cases built, the pool started, the sweep): "
        f"{big['wall']:.1f} s ({big['cases'] / big['wall']:.1f} cases/s, {big['finished']} "
        f"finished); peak resident memory of that process {big['parent_mb']:.0f} MB and of its "
        f"largest worker {big['worker_mb']:.0f} MB (`RUSAGE_CHILDREN` after the workers were "
        "joined; `VmHWM` of the living workers at the sweep's end: "
        f"{', '.join(f'{v:.0f}' for v in big['worker_hwm_mb']) or 'none read'} MB), at most "
        f"{big['parent_mb'] + big['workers'] * big['worker_mb']:.0f} MB together (an upper "
        "bound: the peaks need not coincide, and forked workers share pages with the process "
        "that forked them).",
        *_budget_sentence(m),
        "",
        "## Peak memory against output length",
        "",
        "One run per engine and record length (`excitation.duration` = `run.duration`), at the "
        f"default output rate (every {c['output_dt']:g} s), in a fresh process "
        "(`deckpound.compare.bench.memory.peak_rss`): its peak resident memory, the process's "
        "after the imports and a tiny warm-up run, and the difference (what the run itself "
        "held at its peak); raw output = rows × columns × 8 B (MB = 2²⁰ B).",
        "",
        *_memory_lines(m["output_memory"]),
        "",
    ]
    for engine in MEMORY_ENGINES:
        slope = memory_slope(m["output_memory"], engine)
        if slope is not None:
            lines.append(
                f"- {engine}: the peak grows by {slope:.1f} MB per MB of raw output between the "
                "shortest and the longest record."
            )
    return "\n".join(lines) + "\n"


def step_budget(m: dict) -> dict[str, float]:
    """What issue 33's time for TARGET_CASES runs asks of a step: the budget per step [µs]
    (the time on the pool's workers shared by every step of every run, loops and all else),
    that budget over the reference loop's µs/step, and the seconds the step loops alone take
    for TARGET_CASES runs on the pool's workers at the reference's speed and at MAX_LOOP_RATIO
    times it (the steps of the benchmark's record, this sitting's reference)."""
    loops, workers = m["loops"], m["memory_sweep"]["workers"]
    ref_us = statistics.median(loops["reference_us"])
    budget_us = MAX_SWEEP_SECONDS * workers / (TARGET_CASES * loops["steps"]) * 1e6
    reference_s = TARGET_CASES * loops["steps"] * ref_us * 1e-6 / workers
    return {
        "budget_us": budget_us,
        "budget_over_reference": budget_us / ref_us,
        "reference_s": reference_s,
        "at_loop_target_s": MAX_LOOP_RATIO * reference_s,
    }


def _budget_sentence(m: dict) -> list[str]:
    """The arithmetic of the 90 s target against the reference loop measured here."""
    b, workers = step_budget(m), m["memory_sweep"]["workers"]
    return [
        "",
        f"What {MAX_SWEEP_SECONDS:g} s for {TARGET_CASES:,} runs asks of a step: "
        f"{MAX_SWEEP_SECONDS:g} s on {workers} workers shared by "
        f"{TARGET_CASES:,} × {m['loops']['steps']} steps is {b['budget_us']:.3f} µs per step "
        f"for the step loop and everything else of a case, {b['budget_over_reference']:.2f}× "
        "the reference loop measured above. The step loops of those runs alone take "
        f"{b['reference_s']:.0f} s at the reference's speed and {b['at_loop_target_s']:.0f} s "
        f"at {MAX_LOOP_RATIO:g}× it (issue 33's loop target): one loop per run, however lean, "
        "meets the time only within "
        f"{b['budget_over_reference']:.2f}× the reference with nothing else to pay.",
    ]


def _ida_sentence(sweeps: list[dict]) -> list[str]:
    """What the IDA row measured (none when the stored measurement has no IDA sweep)."""
    ida = next((s for s in sweeps if s["where"] == IDA_WHERE), None)
    if ida is None:
        return []
    top = IDA_STEP * ida["levels"]
    return [
        "",
        f"The IDA row: {ida['pairs']} synthetic station pairs written as PEER AT2 files, each "
        f"pair scaled by one factor to {ida['levels']} levels of Sa(T₁) "
        f"({IDA_STEP:g} to {top:g} g), {SWEEP_ENGINE} engine, summary rows: every case reads "
        "its two files, processes and scales the pair, after a warm-up on another pair. "
        f"{ida['finished']} of {ida['cases']} cases finished with an answer (success, doubtful "
        "or unseated; unseated runs stop early).",
    ]


def load(path: Path = RESULTS_FILE) -> dict:
    """The stored measurement."""
    return json.loads(Path(path).read_text(encoding="utf-8"))


def publish(m: dict, results: Path = RESULTS_FILE, page: Path = PAGE) -> None:
    """Store the measurement and write the page rendered from the stored file."""
    atomic_write_text(results, json.dumps(m, indent=1) + "\n", field="--results")
    atomic_write_text(page, render(load(results)), field="--page")


def _positive(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def _durations(text: str) -> tuple[float, ...]:
    values = tuple(float(v) for v in text.split(","))
    if len(set(values)) != len(values) or len(values) < 2 or any(v <= 0 for v in values):
        raise argparse.ArgumentTypeError(
            f"two or more different positive lengths [s], got {text!r}"
        )
    return values


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small case counts, short records")
    ap.add_argument("--cases", type=_positive, help="cases of the timed sweeps (400)")
    ap.add_argument("--memory-cases", type=_positive, help="cases of the memory sweep (10000)")
    ap.add_argument("--rounds", type=_positive, help="rounds of the step loops (5)")
    ap.add_argument("--repeats", type=_positive, help="reference loops per round (3)")
    ap.add_argument("--durations", type=_durations, help="record lengths [s] (20,80,320)")
    ap.add_argument("--ida-pairs", type=_positive, help="record pairs of the IDA sweep (22)")
    ap.add_argument("--ida-levels", type=_positive, help="levels of the IDA sweep (10)")
    ap.add_argument("--results", type=Path, default=RESULTS_FILE, help="measurement file")
    ap.add_argument("--page", type=Path, default=PAGE, help="the page written")
    ap.add_argument("--render", action="store_true", help="only render --results to --page")
    ap.add_argument("--memory-child", type=_positive, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.memory_child:
        print(json.dumps(memory_sweep_here(args.memory_child)))
        return 0
    if args.render:
        atomic_write_text(args.page, render(load(args.results)), field="--page")
        return 0
    settings = dict(QUICK if args.quick else FULL)
    for key in settings:
        if getattr(args, key) is not None:
            settings[key] = getattr(args, key)
    if settings["cases"] < WORKERS:
        ap.error(f"--cases must be >= {WORKERS} (one per worker), got {settings['cases']}")
    try:
        m = measure(settings, args.quick, lambda text: print(text, file=sys.stderr, flush=True))
    except (RuntimeError, OSError, ImportError) as err:  # the reference loop, a child, Dask
        print(f"sweep_benchmark: {err}", file=sys.stderr)
        return 1
    publish(m, args.results, args.page)
    print(args.page.read_text(encoding="utf-8"))
    return 0


if __name__ == "__main__":
    sys.exit(main())

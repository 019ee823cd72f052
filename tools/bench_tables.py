"""Publish the performance tables of docs/performance.md: measure (or take a folder already
measured) and write the generated blocks and their files in docs/results.

Repository tooling (not installed with the package); it calls the package's measurement
functions, the ones ``deckpound bench`` and ``deckpound stress`` run:

    python tools/bench_tables.py                      # re-render every block from docs/results
    python tools/bench_tables.py work-precision       # full work–precision benchmark (long)
    python tools/bench_tables.py speed                # whole-command speed table
    python tools/bench_tables.py skips                # the compliance engine's skips on and off
    python tools/bench_tables.py stress               # the stability grid
    python tools/bench_tables.py work-precision --from DIR   # publish `deckpound bench -o DIR`

``--from DIR`` publishes a folder written by the matching command (``deckpound bench``,
``deckpound bench --skips``, ``deckpound stress``; ``speed.md`` of ``deckpound bench``) instead
of measuring again. Time the speed and work–precision tables on an idle machine: they are
timings. ``tests/docs/`` renders the committed files again and fails when a block is stale.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import skips_stress
import work_precision
from docs_blocks import RESULTS, write_block

from deckpound.compare.bench import speed
from deckpound.compare.bench.skips import run_skips
from deckpound.compare.bench.stress import run_stress
from deckpound.compare.bench.work_precision import run_bench
from deckpound.compare.engines import engine_names
from deckpound.models.file_io import atomic_write_text
from deckpound.models.scene_io import load_scene

#: the page of every block this tool writes
PAGE = work_precision.PAGE
#: the stored speed table (the block as ``deckpound bench`` wrote it in its ``speed.md``)
SPEED_FILE = RESULTS / "speed.md"
SCENE = "saiidi-4span"


def stored_speed_block(results: Path = RESULTS) -> str:
    """The speed-table block of the stored ``speed.md``."""
    return (Path(results) / SPEED_FILE.name).read_text(encoding="utf-8").strip("\n")


def rerender(page: Path = PAGE, results: Path = RESULTS) -> Path:
    """Write every block of ``page`` again from the files stored in ``results``."""
    table, context = work_precision.load(results)
    write_block(
        page, work_precision.BEGIN, work_precision.END, work_precision.render(table, context)
    )
    skips, steps = skips_stress.load_skips(results)
    write_block(
        page,
        skips_stress.SKIPS_BEGIN,
        skips_stress.SKIPS_END,
        skips_stress.render_skips(skips, steps),
    )
    stress = skips_stress.load_stress(results)
    write_block(
        page, skips_stress.STRESS_BEGIN, skips_stress.STRESS_END, skips_stress.render_stress(stress)
    )
    return write_block(page, speed.BEGIN, speed.END, stored_speed_block(results))


def publish_speed(folder: Path, page: Path = PAGE, results: Path = RESULTS) -> Path:
    """Copy ``speed.md`` of ``folder`` into ``results`` and its block into ``page``."""
    block = (Path(folder) / "speed.md").read_text(encoding="utf-8").strip("\n")
    if not block.startswith(speed.BEGIN.split(":")[0]) or not block.endswith(speed.END):
        raise SystemExit(f"{folder}/speed.md is not a speed table of `deckpound bench`")
    atomic_write_text(Path(results) / SPEED_FILE.name, block + "\n", field=str(SPEED_FILE))
    return write_block(page, speed.BEGIN, speed.END, block)


def measure(what: str, folder: Path) -> None:
    """Run the measurement ``what`` on the benchmark scene, writing its files into ``folder``."""
    scene = load_scene(SCENE)
    if what == "work-precision":
        run_bench(scene, folder)
    elif what == "skips":
        run_skips(scene, folder)
    elif what == "stress":
        run_stress(scene, folder, engines=engine_names())
    else:
        rows, context = speed.measure(
            SCENE, progress=lambda t: print(f"bench_tables: {t}", file=sys.stderr, flush=True)
        )
        atomic_write_text(folder / "speed.md", speed.markdown(rows, context) + "\n")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "table",
        nargs="?",
        choices=("work-precision", "speed", "skips", "stress"),
        help="measure and publish this table (none: re-render every block from docs/results)",
    )
    p.add_argument("--from", dest="source", type=Path, help="publish this measured folder")
    a = p.parse_args(argv)
    if a.table is None:
        print(f"wrote {rerender()}")
        return 0
    publish = {
        "work-precision": work_precision.publish,
        "skips": skips_stress.publish_skips,
        "stress": skips_stress.publish_stress,
        "speed": publish_speed,
    }[a.table]
    if a.source is not None:
        print(f"wrote {publish(a.source)}")
        return 0
    with tempfile.TemporaryDirectory(prefix="deckpound-bench-") as tmp:
        measure(a.table, Path(tmp))
        print(f"wrote {publish(Path(tmp))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The speed table of ``deckpound bench`` (compare/bench/speed.py): its ratios, its line on how it was
measured and the machine-speed reference. (docs/performance.md's copy of it is checked in
tests/docs/test_docs_pages.py.)"""

import numpy as np

from deckpound.compare.bench import speed


def _fake(engines):
    rows = [
        speed.EngineSpeed(
            e,
            first=4.2 / (i + 1),
            warm=4.0 / (i + 1),
            in_process=2.1 / (i + 1),
            us_per_step=50.0 / (i + 1),
            kernel_load=0.05 * i,
            no_setup=30.0 + i,
        )
        for i, e in enumerate(engines)
    ]
    ctx = {
        "load_before": (0.5, 0, 0),
        "load_after": (0.9, 0, 0),
        "reference_ns": (140.0, 150.0),
        "cpus": 2,
        "machine": "x86_64",
        "python": "3.11.7",
        "date": "2026-01-01",
        "scene": "saiidi-4span",
        "overrides": [],
        "repeats": 3,
    }
    return rows, ctx


def test_bytecode_sentence_follows_the_measurement():
    rows, ctx = _fake(["opensees", "compliance"])
    assert "bytecode" not in speed.markdown(rows, ctx)
    read = speed.markdown(rows, {**ctx, "bytecode_cache": False, "bytecode_stale": 0})
    assert "the processes read the bytecode that `deckpound compile` wrote" in read
    stale = speed.markdown(rows, {**ctx, "bytecode_cache": False, "bytecode_stale": 3})
    assert "3 deckpound modules had no current bytecode" in stale


def test_markdown_ratios():
    rows, ctx = _fake(["opensees", "compliance"])
    block = speed.markdown(rows, ctx)
    line = next(ln for ln in block.splitlines() if ln.startswith("| compliance"))
    cells = line.strip("| ").split(" | ")
    assert cells[3] == "2" and cells[5] == "2"  # 4.0 / 2.0 and 2.1 / 1.05
    nan_row = speed.EngineSpeed("x")
    assert "–" in speed.markdown([nan_row], ctx) and np.isnan(nan_row.warm)


def test_reference_loop_measures_time_per_iteration():
    """The machine-speed reference is a positive, finite time per pass of a 7×7 elimination:
    ~140 flops and ~100 loads and stores, so ≥ 10 ns on any core and far below a millisecond."""
    ns = speed.reference_loop_ns(repeats=2)
    assert np.isfinite(ns) and 10.0 < ns < 1e5

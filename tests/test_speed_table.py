"""The README's speed table is the output of ``deckpound bench --quick --write-readme``
(compare/speed.py): the block carries the command's marker and has exactly the command's
format. Values differ from machine to machine and are not checked."""

import re
from pathlib import Path

import numpy as np

from deckpound.compare import speed
from deckpound.compare.engines import engine_names

README = Path(__file__).resolve().parents[1] / "README.md"


def _shape(block: str) -> list[str]:
    """The block with every number replaced by N (what must not change)."""
    return [re.sub(r"-?\d+(\.\d+)?(e[-+]?\d+)?", "N", line) for line in block.splitlines()]


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


def test_readme_block_is_the_commands_output():
    text = README.read_text()
    assert speed.BEGIN in text and speed.END in text, "README has no speed-table block"
    start = text.index(speed.BEGIN)
    block = text[start : text.index(speed.END, start) + len(speed.END)]
    rows, ctx = _fake(engine_names())
    # the line under the table says how Python's bytecode cache stood while measuring
    bytecode = ({}, {"bytecode_cache": False, "bytecode_stale": 0}, {"bytecode_cache": False})
    expected = [_shape(speed.markdown(rows, {**ctx, **b})) for b in bytecode]
    assert _shape(block) in expected, (
        "the README's speed table is not the output of `deckpound bench --quick --write-readme`"
    )
    rows = [ln for ln in block.splitlines() if ln.startswith("| ") and "engine" not in ln]
    assert [r.split(" | ")[0][2:] for r in rows] == list(engine_names())


def test_bytecode_sentence_follows_the_measurement():
    rows, ctx = _fake(["opensees", "compliance"])
    assert "bytecode" not in speed.markdown(rows, ctx)
    read = speed.markdown(rows, {**ctx, "bytecode_cache": False, "bytecode_stale": 0})
    assert "the processes read the bytecode that `deckpound compile` wrote" in read
    stale = speed.markdown(rows, {**ctx, "bytecode_cache": False, "bytecode_stale": 3})
    assert "3 deckpound modules had no current bytecode" in stale


def test_markdown_ratios_and_replacement(tmp_path):
    rows, ctx = _fake(["opensees", "compliance"])
    block = speed.markdown(rows, ctx)
    line = next(ln for ln in block.splitlines() if ln.startswith("| compliance"))
    cells = line.strip("| ").split(" | ")
    assert cells[3] == "2" and cells[5] == "2"  # 4.0 / 2.0 and 2.1 / 1.05
    readme = tmp_path / "README.md"
    readme.write_text(f"intro\n\n{speed.BEGIN}\nold\n{speed.END}\n\nrest\n")
    speed.write_readme(readme, block)
    assert readme.read_text() == f"intro\n\n{block}\n\nrest\n"
    speed.write_readme(readme, block)  # idempotent
    assert readme.read_text().count(speed.BEGIN) == 1
    nan_row = speed.EngineSpeed("x")
    assert "–" in speed.markdown([nan_row], ctx) and np.isnan(nan_row.warm)


def test_reference_loop_measures_time_per_iteration():
    """The machine-speed reference is a positive, finite time per pass of a 7×7 elimination:
    ~140 flops and ~100 loads and stores, so ≥ 10 ns on any core and far below a millisecond."""
    ns = speed.reference_loop_ns(repeats=2)
    assert np.isfinite(ns) and 10.0 < ns < 1e5

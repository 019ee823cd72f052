"""docs/performance.md's work–precision block is the rendering of the committed
``docs/results/bench.csv`` (tools/work_precision.py, published by ``python tools/bench_tables.py
work-precision``): re-rendered here, it must be the page's block character for character, so no
number of it (table or sentence) can be edited by hand or outlive the measurement it quotes. The
sentences are checked on small tables whose answers are known."""

import json

import numpy as np
import pandas as pd
import pytest
import work_precision as wp
from docs_blocks import RESULTS, block_of

from deckpound.cli import main


def test_page_block_is_the_rendering_of_the_committed_results():
    table, context = wp.load(RESULTS)
    assert not context.get("quick"), "the work-precision table must be a full run"
    block = block_of(wp.PAGE.read_text(encoding="utf-8"), wp.BEGIN, wp.END)
    assert block is not None, f"{wp.PAGE.name} has no work-precision block"
    assert block == wp.render(table, context), (
        "the work-precision block of docs/performance.md is not the rendering of "
        "docs/results/bench.csv: run `python tools/bench_tables.py`"
    )


def _row(scene, config, engine, wall, steps, err, ratio=np.nan, bound="", family=None, **kw):
    return dict(
        scene=scene,
        config=config,
        engine=engine,
        family=family or ("nonsmooth" if engine == "nonsmooth" else "compliance"),
        status=kw.get("status", "success"),
        wall=wall,
        us_per_step=1e6 * wall / steps,
        err_primary=err,
        speedup_vs_opensees_equal_error=ratio,
        speedup_bound=bound,
        overrides=kw.get("overrides", ""),
    )


CONTEXT = {
    "date": "2026-01-01",
    "cpus": 2,
    "machine": "x86_64",
    "python": "3.11.7",
    "repeats": 3,
    "reference_ns": [150.0, 160.0],
    "defaults": {"opensees": {"dt": 5e-4}, "compliance": {"dt": 5e-4}, "nonsmooth": {"h": 1e-3}},
}


def _table(**over):
    rows = [
        _row("bench", "opensees dt=0.002", "opensees", 0.60, 10_000, 9.0e-5, 1.0, "="),
        _row("bench", "opensees dt=0.0005", "opensees", 2.0, 40_000, 1.7e-5, 1.0, "="),
        _row("bench", "compliance newmark dt=0.002", "compliance", 0.02, 10_000, 9.0e-5 + 3e-11),
        _row("bench", "compliance newmark dt=0.0005", "compliance", 0.05, 40_000, 1.7e-5, 40, "="),
        _row("bench", "compliance adaptive rtol=0.001", "compliance", 0.3, 5_000, 2e-2, 2, ">="),
        _row("bench", "nonsmooth h=0.004", "nonsmooth", 0.015, 5_000, 2e-2),
        _row("bench", "nonsmooth h=0.001", "nonsmooth", 0.03, 20_000, 5e-4),
    ]
    rows += over.get("extra", [])
    return pd.DataFrame(rows)


def test_table_lines_join_each_family_and_mark_defaults_and_bounds():
    block = wp.render(_table(), CONTEXT)
    lines = block.splitlines()
    assert lines[0] == wp.BEGIN and lines[-1] == wp.END
    rows = [ln for ln in lines if ln.startswith("| bench |")]
    assert len(rows) == 4  # opensees, newmark, adaptive, nonsmooth
    assert rows[0].startswith("| bench | opensees dt = 2e-3 / 5e-4 (default) | 0.6 / 2 | 60 / 50 |")
    assert rows[0].endswith("| 1 |")
    assert "compliance newmark dt = 2e-3 / 5e-4 (default)" in rows[1]
    assert rows[1].endswith("| – / 40 |")
    assert rows[2].endswith("| ≥ 2 |")
    assert "nonsmooth h = 4e-3 / 1e-3 (default)" in rows[3] and rows[3].endswith("(rigid model) |")
    assert "Measured 2026-01-01: 2 cores" in block and "150 ns per pass before and 160" in block


def test_headline_takes_the_fastest_configuration_within_one_percent():
    block = wp.render(_table(), CONTEXT)
    # nonsmooth h=0.004 (2 %) and adaptive (2 %) do not qualify; the fastest that do:
    # opensees dt=0.002 0.6 s, newmark dt=0.002 0.02 s (30x), nonsmooth h=0.001 0.03 s (20x)
    assert (
        "takes: `opensees dt=0.002` 0.6 s; `compliance newmark dt=0.002` 0.02 s (30×); "
        "`nonsmooth h=0.001` 0.03 s (20×)" in block
    )


def test_clone_agreement_is_the_largest_error_difference_at_common_steps():
    block = wp.render(_table(), CONTEXT)
    line = next(ln for ln in block.splitlines() if ln.startswith("- `bench`"))
    assert "the primary errors agree to ≤ 1e-09 (of the peak) at dt = 2e-3, 5e-4" in line
    assert "costs 30–40× less" in line
    apart = _table()
    apart.loc[apart["config"] == "compliance newmark dt=0.002", "err_primary"] = 9.0e-5 + 2e-6
    line = next(ln for ln in wp.render(apart, CONTEXT).splitlines() if ln.startswith("- `bench`"))
    assert "agree to ≤ 1e-09 (of the peak) at dt = 5e-4; at dt = 2e-3 they differ by 2e-6" in line


def test_a_friction_model_difference_is_said_not_hidden():
    extra = [
        _row("stick", "opensees dt=0.002", "opensees", 0.3, 5_000, 2e-3, 1.0, "=",
             overrides="opensees.dt=0.002 contact.friction_mode=contact2d"),
        _row("stick", "compliance newmark dt=0.002", "compliance", 0.01, 5_000, 4e-3, 30, "="),
    ]  # fmt: skip
    block = wp.render(_table(extra=extra), CONTEXT)
    line = next(ln for ln in block.splitlines() if ln.startswith("- `stick`"))
    assert "zeroLengthContact2D" in line and "differ by the model" in line


def test_failed_configurations_are_listed():
    extra = [_row("bench", "nonsmooth h=0.0005", "nonsmooth", np.nan, 1, np.nan, status="timeout")]
    block = wp.render(_table(extra=extra), CONTEXT)
    assert "Failed configurations: bench `nonsmooth h=0.0005` (timeout)." in block


def test_a_table_that_is_not_bench_csv_is_refused():
    with pytest.raises(ValueError, match="no column 'err_primary'"):
        wp.render(_table().drop(columns=["err_primary"]), CONTEXT)
    with pytest.raises(ValueError, match="empty"):
        wp.render(_table().iloc[:0], CONTEXT)


def test_publish_replaces_only_its_block_and_copies_the_sources(tmp_path):
    src = tmp_path / "run"
    src.mkdir()
    _table().to_csv(src / "bench.csv", index=False)
    (src / "bench_context.json").write_text(json.dumps(CONTEXT))
    (src / "work_precision.png").write_bytes(b"png")
    page = tmp_path / "performance.md"
    page.write_text(f"intro\n\n{wp.BEGIN}\nold\n{wp.END}\n\noutro\n")
    wp.publish(src, page, tmp_path / "results")
    text = page.read_text()
    assert text.startswith("intro\n\n") and text.endswith("\n\noutro\n") and "old" not in text
    table, context = wp.load(tmp_path / "results")
    assert wp.render(table, context) in text
    assert (tmp_path / "results" / "work_precision.png").read_bytes() == b"png"


def test_the_cli_has_no_docs_writer(capsys, tmp_path):
    """Publishing the docs is the repository's tooling, not a user's option."""
    code = main(["bench", "--write-readme", "README.md", "-o", str(tmp_path / "o")])
    assert code == 2 and "--write-readme" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()

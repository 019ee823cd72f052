"""docs/sweeps.md is the rendering of the stored measurement ``docs/results/sweeps.json``
(``tools/sweep_benchmark.py``, issues 30 item 7 and 33 item 5): rendered again here, it must be
the page character for character, so no number or verdict of it can be edited by hand or outlive
the measurement it quotes. The verdicts and the tables' shape are checked on small measurements
whose answers are known; nothing here is timed."""

from __future__ import annotations

import copy
import itertools
import json

import pytest
import sweep_benchmark as sb


def test_page_is_the_rendering_of_the_stored_measurement():
    stored = sb.load(sb.RESULTS_FILE)
    assert sb.PAGE.read_text(encoding="utf-8") == sb.render(stored), (
        "docs/sweeps.md is not the rendering of docs/results/sweeps.json: run "
        "`python tools/sweep_benchmark.py --render` (or measure again)"
    )


def _sweep(where: str, workers: int, cases: int, wall: float, loop: float) -> dict:
    return {"where": where, "workers": workers, "cases": cases, "wall": wall, "loop": loop,
            "finished": cases}  # fmt: skip


def _memory_runs(durations=(20.0, 80.0, 320.0), peaks=(250.0, 270.0, 350.0)) -> list[dict]:
    runs = []
    for engine, columns in (("compliance", 52), ("nonsmooth", 64)):
        for d, peak in zip(durations, peaks, strict=True):
            rows = int(round(d / 0.005)) + 1
            runs.append({"engine": engine, "duration": d, "columns": columns, "rows": rows,
                         "status": "success", "peak_mb": peak, "baseline_mb": 240.0,
                         "run_mb": peak - 240.0})  # fmt: skip
    return runs


def _measurement() -> dict:
    """A full-size measurement with round numbers: 1 worker 20 % over its loops, the pool
    40 cases/s and 10 % over, Dask 25 % over and 1.25× the pool's wall time, the compliance
    loop 1.4× the reference per step, the nonsmooth loop 1.6× per its own step and 0.8× over
    the record."""
    return {
        "format": sb.FORMAT,
        "context": {
            "date": "2026-01-01",
            "machine": "x86_64",
            "cpus": 2,
            "python": "3.11.7",
            "commit": "abc1234",
            "scene": "saiidi-4span",
            "record_duration": 20.0,
            "output_dt": 0.005,
            "quick": False,
            "load_before": 0.1,
            "load_after": 0.2,
            "minutes": 9.5,
            "settings": {
                "cases": 400,
                "memory_cases": 10000,
                "rounds": 5,
                "repeats": 3,
                "durations": [20.0, 80.0, 320.0],
            },
        },
        "loops": {
            "steps": 40000,
            "dt": 5e-4,
            "ndof": 7,
            "nonsmooth_steps": 20000,
            "nonsmooth_h": 1e-3,
            "reference_us": [0.5, 0.4, 0.6],
            "reference_loop_s": [0.02, 0.016, 0.024],
            "compliance_us": [0.7, 0.56, 0.84],
            "compliance_loop_s": [0.028, 0.0224, 0.0336],
            "nonsmooth_us": [0.8, 0.64, 0.96],
            "nonsmooth_loop_s": [0.016, 0.0128, 0.0192],
            "peak_difference": 2e-16,
            "full_residual_us": [0.55, 0.45, 0.65],
            "no_energy_us": [0.62, 0.5, 0.7],
            "one_row_us": [0.66, 0.5, 0.7],
            "bare_us": [0.58, 0.5, 0.7],
            "lean_us": [0.52, 0.5, 0.6],
            "lean_loop_s": [0.0208, 0.02, 0.024],
        },
        "sweeps": [
            _sweep("this process", 1, 400, 24.0, 20.0),
            _sweep("local pool", 2, 400, 10.0, 2 * 10.0 / 1.1),
            _sweep("Dask LocalCluster", 2, 400, 12.5, 20.0),
            {**_sweep(sb.IDA_WHERE, 2, 220, 4.0, 8.0 / 1.12), "pairs": 22, "levels": 10},
        ],
        "memory_sweep": {
            "cases": 10000,
            "workers": 2,
            "wall": 85.0,
            "finished": 10000,
            "parent_mb": 400.0,
            "worker_mb": 200.0,
            "worker_hwm_mb": [190.0, 200.0],
        },
        "output_memory": _memory_runs(),
    }


def _targets(m: dict) -> dict[str, tuple[str, str]]:
    """{target: (measured, verdict)} of the page's Targets table."""
    text = sb.render(m)
    table = text.split("## Targets")[1].split("\n## ")[0]
    rows = [ln for ln in table.splitlines() if ln.startswith("| ") and "---" not in ln]
    cells = [[c.strip() for c in ln.strip("|").split("|")] for ln in rows]
    assert cells[0] == ["issue", "target", "measured", "verdict"]
    return {c[1]: (c[2], c[3]) for c in cells[1:]}


def _find(targets: dict, *words: str) -> tuple[str, str]:
    hits = [v for k, v in targets.items() if all(w in k for w in words)]
    assert len(hits) == 1, (words, list(targets))
    return hits[0]


def test_every_target_of_both_issues_is_stated_with_a_computed_verdict():
    t = _targets(_measurement())
    assert len(t) == 15
    assert {v for _, v in t.values()} <= {"met", "not met", "not measured"}
    assert _find(t, "step loops (in this process)") == ("20 %", "not met")
    assert _find(t, "step loops (local pool") == ("10 %", "met")
    assert _find(t, "step loops (Dask") == ("25 %", "not met")  # 2 × 12.5 / 20 − 1
    assert _find(t, "step loops (IDA on AT2 pairs") == ("12 %", "met")
    assert _find(t, "30 cases/s") == ("40.0 cases/s", "met")
    assert _find(t, "1 GB") == ("800 MB (10000 cases)", "met")  # 400 + 2 × 200
    assert _find(t, "90 s") == ("85.0 s (10000 cases)", "met")
    assert _find(t, "Dask cluster of two workers") == ("1.25 (400 cases)", "not met")
    assert _find(t, "compliance loop", "per step") == ("1.40×", "met")
    assert _find(t, "nonsmooth loop", "per step") == ("1.60×", "not met")
    assert _find(t, "nonsmooth loop", "over the record") == ("0.80×", "met")
    assert _find(t, "300 MB", "(compliance)") == ("350 MB", "not met")
    # (350 − 250) MB over (64001 − 4001) rows × 52 columns × 8 B
    slope = 100.0 / (60000 * 52 * 8 / sb.MB)
    assert _find(t, "raw output", "compliance:") == (f"{slope:.1f} MB/MB", "not met")


def test_a_small_sweep_or_short_records_leave_the_size_targets_not_measured():
    m = _measurement()
    m["memory_sweep"].update(cases=48, wall=4.0, finished=48)
    m["output_memory"] = _memory_runs((5.0, 10.0, 20.0), (250.0, 250.0, 250.5))
    t = _targets(m)
    assert _find(t, "1 GB") == ("800 MB (48 cases, fewer than 10000)", "not measured")
    assert _find(t, "90 s") == ("4.0 s (48 cases, fewer than 10000)", "not measured")
    assert _find(t, "300 MB", "(nonsmooth)") == ("no such record measured", "not measured")
    assert _find(t, "raw output", "nonsmooth:")[1] == "met"


def test_the_pages_tables_have_their_columns_and_a_quick_run_says_so():
    m = _measurement()
    text = sb.render(m)
    lines = text.splitlines()
    headers = [ln for ln, nxt in itertools.pairwise(lines) if nxt.startswith("|---")]
    assert headers[1].startswith("| step loop | step [s] | steps | µs/step (median) |")
    assert headers[2].startswith("| what the compliance loop does beyond the reference |")
    assert headers[3].startswith("| where | workers | cases | finished | wall [s] | cases/s |")
    assert headers[4].startswith("| engine | record [s] | status | output rows | columns |")
    loop_rows = [
        ln.split(" | ")[0] for ln in text.splitlines() if ln.startswith("| ") and "C," in ln
    ]
    assert loop_rows == ["| reference (C, gcc -O3)"]
    assert len([ln for ln in text.splitlines() if ln.startswith("| compliance | ")]) == 1 + 3
    assert (
        "| the reference's algorithm in numba (`lean_numba.py`) | 0.0005 | 40000 | 0.520 |" in text
    )
    assert "quick run" not in text
    m["context"]["quick"] = True
    assert "**A quick run (`--quick`)**" in sb.render(m)


def test_what_the_loop_does_beyond_the_reference_is_costed_from_the_rounds_medians():
    """Medians [µs/step]: reference 0.5, compliance 0.7, without energy 0.62, one row 0.66,
    neither 0.58, the reference with the whole residual 0.55, the reference's algorithm in
    numba 0.52: an excess of 0.2."""
    rows = {what.split(" (")[0].split(":")[0]: (us, share) for what, _, us, share in (
        [c.strip() for c in ln.strip("|").split("|")]
        for ln in sb.render(_measurement()).split("beyond the reference |")[1].splitlines()[2:9]
    )}  # fmt: skip
    assert rows == {
        "energy work terms and the energy columns": ("0.080", "40 %"),
        "output rows": ("0.040", "20 %"),
        "the two together": ("0.120", "60 %"),
        "the whole residual": ("0.050", "25 %"),
        "numba's code against gcc's for the reference's own algorithm": ("0.020", "10 %"),
        "the rest": ("0.010", "5 %"),
        "all of it": ("0.200", "100 %"),
    }
    text = sb.render(_measurement())
    assert "the compliance loop runs at 1.16× the reference per step" in text
    assert (
        "flat arrays, the same answer bit for bit, `tests/test_reference_loop.py`) runs at 1.04×"
        in text
    )
    # the floor: (0.52 + 0.7 − 0.58) / 0.5
    assert sb.numba_floor(_measurement()["loops"]) == pytest.approx(1.28)
    floor = "output rows, which the engine's answer needs (the energy balance, the results), is "
    assert floor + "1.28× the reference per step" in " ".join(text.split())


def test_the_ida_row_is_described_and_an_older_measurement_without_it_renders():
    m = _measurement()
    text = sb.render(m)
    assert "The IDA row: 22 synthetic station pairs" in text and "0.1 to 1 g" in text
    assert "| IDA on AT2 pairs, local pool | 2 | 220 | 220 |" in text
    m["sweeps"] = [s for s in m["sweeps"] if s["where"] != sb.IDA_WHERE]
    t = _targets(m)
    assert len(t) == 14 and "IDA row" not in sb.render(m)


def test_render_refuses_another_layout_and_the_stored_file_is_json():
    m = copy.deepcopy(_measurement())
    m["format"] = sb.FORMAT + 1
    with pytest.raises(ValueError, match="format"):
        sb.render(m)
    assert json.loads(sb.RESULTS_FILE.read_text(encoding="utf-8"))["format"] == sb.FORMAT


@pytest.mark.parametrize(
    "argv",
    [["--cases", "0"], ["--cases", "1"], ["--durations", "20"], ["--durations", "20,20"],
     ["--memory-cases", "-3"]],
)  # fmt: skip
def test_bad_arguments_stop_before_measuring(argv, capsys):
    with pytest.raises(SystemExit) as stop:
        sb.main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "error:" in err and ("must be" in err or "positive" in err)


def test_render_only_writes_the_page_of_a_results_file(tmp_path):
    results = tmp_path / "sweeps.json"
    results.write_text(json.dumps(_measurement()), encoding="utf-8")
    page = tmp_path / "sweeps.md"
    assert sb.main(["--render", "--results", str(results), "--page", str(page)]) == 0
    assert page.read_text(encoding="utf-8") == sb.render(_measurement())


def test_the_step_budget_of_the_90_s_target_is_its_arithmetic():
    """90 s on 2 workers for 10,000 runs of 40,000 steps leave 0.45 µs per step; the reference
    at 0.5 µs/step (median) makes that 0.9× it, its loops alone 100 s and 150 s at 1.5×."""
    b = sb.step_budget(_measurement())
    assert b["budget_us"] == pytest.approx(0.45, rel=1e-12)
    assert b["budget_over_reference"] == pytest.approx(0.9, rel=1e-12)
    assert b["reference_s"] == pytest.approx(100.0, rel=1e-12)
    assert b["at_loop_target_s"] == pytest.approx(150.0, rel=1e-12)
    assert "0.450 µs per step" in sb.render(_measurement())

"""Files that open plainly (issue 32, item 1): every CSV table deckpound writes is read by a
plain ``pandas.read_csv(path)`` into numeric columns whose names carry their unit
(``deck_theta [rad]``), time bases carry no round-off digits, and folders written by earlier
versions (units in a ``# units:`` comment line) are still read."""

from __future__ import annotations

import io
import warnings

import numpy as np
import pandas as pd
import pytest
from _record_helpers import quake, write_at2

from deckpound import cli
from deckpound.analytic.compliance.adaptive import step_size_summary
from deckpound.compare.align import align, common_time_base, write_tables
from deckpound.compare.bench.skips import STEP_UNITS
from deckpound.compare.bench.stress import run_stress
from deckpound.compare.report.outputs import write_csv
from deckpound.compare.result_cache import ResultCache
from deckpound.models.columns import column_unit, standard_columns
from deckpound.models.file_io import split_unit_label
from deckpound.models.result import Result, read_table, rounded_time
from deckpound.models.scene_io import load_scene

SHORT = ["--set", "excitation.duration=2.0"]
#: columns of long tables that are in the unit of their row (named in the row's ``unit`` column)
PER_ROW_UNIT = {
    "value",
    "peak",
    "peak_ref",
    "residual",
    "residual_ref",
    "median",
    "p16",
    "p84",
    "mean",
    "std",
    "min",
    "max",
}


def _old_format(result: Result) -> bytes:
    """A result CSV as versions before issue 32 wrote it: a ``# units:`` comment line above a
    plain header, the time column as computed."""
    names = list(result.columns)
    head = "# units: " + ",".join(column_unit(n) for n in names) + "\n" + ",".join(names) + "\n"
    rows = "".join(
        ",".join(repr(float(result[n][i])) for n in names) + "\n" for i in range(len(result.t))
    )
    return (head + rows).encode()


def _result(dt: float = 0.005, n: int = 401) -> Result:
    names = standard_columns(["bent1", "bent2", "bent3"])
    t = np.arange(n) * dt  # k·Δt: 0.17500000000000002 at k = 35
    rng = np.random.default_rng(3)
    cols = {c: (t if c == "t" else rng.standard_normal(n)) for c in names}
    return Result(engine="compliance", columns=cols, meta={"steps": n - 1})


def check_plain(path) -> list[str]:
    """What is wrong with ``path`` as a plain table (empty: nothing)."""
    frame = pd.read_csv(path)
    problems = []
    long = "unit" in frame.columns
    for header in frame.columns:
        name, unit = split_unit_label(str(header))
        column = frame[header]
        # an empty column (a text column with no entry: ``variant`` of a sweep without
        # variants) reads as NaN: it holds no number, so it needs no unit
        numeric = (
            pd.api.types.is_numeric_dtype(column)
            and not pd.api.types.is_bool_dtype(column)
            and column.notna().any()
        )
        if str(header).startswith(("#", "Unnamed")):
            problems.append(f"{path.name}: header cell {header!r}")
        elif unit is not None and not numeric and column.notna().any():
            problems.append(f"{path.name}: {header!r} has a unit but reads as {column.dtype}")
        elif numeric and unit is None and not (long and name in PER_ROW_UNIT):
            problems.append(f"{path.name}: numeric column {header!r} has no [unit]")
    return problems


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    """A folder holding what ``run``, ``compare``, ``study``, ``study variability``, ``ida``
    and ``msa`` write for a short record and a tiny synthetic suite of two pairs."""
    root = tmp_path_factory.mktemp("plain")
    suite = root / "suite"
    suite.mkdir()
    for i in range(2):
        write_at2(suite / f"RSN{100 + i}_TEST_ST{i}000.AT2", quake(n=300, seed=2 * i, f=1.5 + i))
        write_at2(suite / f"RSN{100 + i}_TEST_ST{i}090.AT2", quake(n=300, seed=2 * i + 1))
    sweep = ["--records", str(suite), "--im", "pga", "--workers", "1", "--no-progress"]
    commands = [
        ["run", "saiidi-4span", "--engine", "compliance", *SHORT, "-o", str(root / "run")],
        [
            "compare",
            "saiidi-4span",
            "--engines",
            "compliance,nonsmooth",
            "--reference",
            "compliance",
            *SHORT,
            "--no-progress",
            "-o",
            str(root / "compare"),
        ],
        ["study", "stiffness", "saiidi-4span", "--quick", *SHORT, "--no-progress"]
        + ["-o", str(root / "study")],
        ["study", "variability", "saiidi-4span", "--cases", "2", *SHORT, "--workers", "1"]
        + ["--no-progress", "-o", str(root / "variability")],
        ["ida", "saiidi-4span", "--levels", "0.2,0.4", *sweep, "-o", str(root / "ida")],
        ["msa", "saiidi-4span", "--stripes", "0.2,0.4", *sweep, "-o", str(root / "msa")],
    ]
    for argv in commands:
        assert cli.main(argv) == 0, argv
    return root


def test_every_table_opens_plainly_with_units(outputs):
    tables = sorted(outputs.rglob("*.csv"))
    names = {p.name for p in tables}
    for expected in (
        "compliance.csv",
        "nonsmooth.csv",
        "metrics.csv",
        "aligned_long.csv",
        "aligned_compliance.csv",
        "stiffness.csv",
        "variability.csv",
        "variability_summary.csv",
        "ida.csv",
        "fragility.csv",
    ):
        assert expected in names, expected
    problems = [msg for p in tables if p.parent.name != "suite" for msg in check_plain(p)]
    assert problems == []
    run = pd.read_csv(outputs / "run" / "compliance.csv")
    assert list(run.columns[:4]) == [
        "t [s]",
        "deck_x_abs [m]",
        "deck_y_abs [m]",
        "deck_theta [rad]",
    ]
    assert all(d == np.float64 for d in run.dtypes)
    metrics = pd.read_csv(outputs / "compare" / "metrics.csv")
    theta = metrics[metrics["quantity"] == "deck_theta"]
    assert set(theta["unit"]) == {"rad"} and {"t_peak [s]", "nrmse [-]"} <= set(metrics.columns)
    ida = pd.read_csv(outputs / "ida" / "ida.csv")
    assert {"level [g]", "peak_theta [rad]", "seat_margin [m]", "unseated"} <= set(ida.columns)
    frag = pd.read_csv(outputs / "msa" / "fragility.csv")
    assert {"median [g]", "beta [-]", "engine", "method"} <= set(frag.columns)


def test_the_check_finds_a_table_without_units(tmp_path):
    """The walk above can fail: a numeric column without a unit, a comment line, a unit on
    text are each reported."""
    (tmp_path / "a.csv").write_text("engine,peak_theta\ncompliance,0.1\n")
    (tmp_path / "b.csv").write_text("# units: s\nt\n0.0\n")
    (tmp_path / "c.csv").write_text("engine [s],t [s]\nx,0.0\n")
    assert len(check_plain(tmp_path / "a.csv")) == 1
    assert len(check_plain(tmp_path / "b.csv")) == 1
    assert len(check_plain(tmp_path / "c.csv")) == 1


def test_time_columns_have_no_roundoff_digits(outputs, tmp_path):
    """The result file's and the aligned tables' time columns are the decimals of the grid."""
    for path in (
        outputs / "run" / "compliance.csv",
        outputs / "compare" / "aligned_compliance.csv",
        outputs / "compare" / "aligned_long.csv",
    ):
        text = pd.read_csv(path, dtype=str)["t [s]"]
        assert text.str.len().max() <= len("1.995"), (path.name, text[text.str.len() > 5][:3])
    r = _result()
    assert r["t"][35] == 0.17500000000000002  # the computed column keeps its round-off
    r.write(tmp_path)
    written = pd.read_csv(tmp_path / "compliance.csv", dtype=str)["t [s]"]
    assert written[35] == "0.175" and written.str.len().max() <= 5
    # the aligned base: a median step with round-off is taken as the decimal it stands for
    noisy = Result("a", {"t": np.arange(201) * 0.004999999999999893, "x": np.zeros(201)}, {})
    base = common_time_base({"a": noisy, "b": r})
    assert base[1] == 0.005 and all(len(repr(float(v))) <= 5 for v in base)
    frames = align({"a": r, "b": r})
    assert np.array_equal(frames["a"]["deck_theta"], r["deck_theta"])  # same grid: untouched


def test_rounding_touches_only_roundoff():
    """Times off a decimal grid (Δt = 1/30 s, event times of an adaptive engine) are kept bit
    for bit; on a decimal grid only the last-place digits of k·Δt go."""
    t = np.arange(3001) / 30
    assert np.array_equal(rounded_time(t), t)
    t = np.arange(4001) * 0.005
    r = rounded_time(t)
    assert np.max(np.abs(r - t) / np.spacing(t.clip(min=1e-300))) <= 1
    assert (r != t).sum() > 100  # there was round-off to take out
    events = np.sort(np.concatenate([t, np.random.default_rng(1).uniform(0, 20, 50)]))
    kept = np.isin(events, t, invert=True)
    assert np.array_equal(rounded_time(events)[kept], events[kept])


def test_results_of_the_previous_format_are_read(tmp_path, recwarn):
    """A folder written by an earlier version (units in a ``# units:`` comment line, plain
    header) is read by Result.read, by the result cache and by read_table, without a warning;
    the new file reads back bit for bit except the time column's round-off."""
    r = _result(n=5)
    folder = tmp_path / "old"
    folder.mkdir()
    (folder / "compliance.csv").write_bytes(_old_format(r))
    (folder / "compliance.json").write_bytes(r.json_bytes())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = Result.read(folder, "compliance")
        frame = read_table(folder / "compliance.csv")
    for c in r.columns:
        assert np.array_equal(back[c], r[c]), c
    assert frame.attrs["units"]["deck_theta"] == "rad" and frame.attrs["units"]["fn_c1"] == "kN"
    assert list(frame.columns) == list(r.columns)
    # the new format: units in the header, every column but t exact
    new = read_table(io.BytesIO(r.csv_bytes()))
    assert new.attrs["units"]["t"] == "s" and list(new.columns) == list(r.columns)
    for c in r.columns:
        assert np.array_equal(new[c], r[c] if c != "t" else rounded_time(r["t"])), c
    # the result cache stores the time exactly: a cached result is bit-identical
    cache = ResultCache(tmp_path / "cache")
    big = _result()
    cache.put("k", big)
    got = cache.get("k", "compliance")
    assert all(np.array_equal(got[c], big[c]) for c in big.columns)
    assert not [w for w in recwarn if "units" in str(w.message)]


def test_write_tables_units_in_header_and_parquet(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    r = _result(n=21)
    written = write_tables(align({"compliance": r}, columns=["deck_theta", "gap_c1"]), tmp_path)
    assert {p.name for p in written} >= {"aligned_compliance.csv", "aligned_compliance.parquet"}
    assert list(pd.read_csv(tmp_path / "aligned_compliance.csv").columns) == [
        "t [s]",
        "deck_theta [rad]",
        "gap_c1 [m]",
    ]
    schema = pq.read_schema(tmp_path / "aligned_compliance.parquet")
    assert schema.field("deck_theta").metadata[b"unit"] == b"rad"


def test_fragility_fit_reads_headers_with_units(tmp_path, capsys):
    path = tmp_path / "stripes.csv"
    path.write_text("im [g],n [-],exceed [-]\n0.2,10,1\n0.4,10,4\n0.8,10,9\n")
    assert cli.main(["fragility", "fit", str(path), "--json"]) == 0
    assert '"median"' in capsys.readouterr().out


def test_export_vtk_reads_a_folder_of_the_previous_format(outputs, tmp_path):
    """``deckpound export-vtk`` on a run folder rewritten in the old format (comment line,
    plain header) writes the same files as on the new one."""
    new = outputs / "run"
    old = tmp_path / "old"
    old.mkdir()
    r = Result.read(new, "compliance")
    (old / "compliance.csv").write_bytes(_old_format(r))
    (old / "compliance.json").write_bytes((new / "compliance.json").read_bytes())
    for folder, target in ((new, tmp_path / "vtk_new"), (old, tmp_path / "vtk_old")):
        assert cli.main(["export-vtk", str(folder), "--every", "50", "-o", str(target)]) == 0
    written = sorted(p.name for p in (tmp_path / "vtk_new").rglob("*") if p.is_file())
    assert written and written == sorted(
        p.name for p in (tmp_path / "vtk_old").rglob("*") if p.is_file()
    )


def test_report_writer_units_numbers_only_and_names_counts(tmp_path):
    """The report's writer labels numbers only (a study's text column keeps its name even
    where the study's units name it) and gives counts, shares and times their unit when the
    caller names none (the paper's cache counts, run numbers)."""
    frame = pd.DataFrame(
        {
            "run": [1, 2],
            "engine": ["opensees", "compliance"],
            "stiffness": ["initial", "secant"],
            "hits": [3, 0],
            "stick_share": [0.5, 0.25],
            "share_acute": [0.6, 0.7],
            "first_time": [0.8, 0.9],
            "peak_theta": [1e-3, 2e-3],
        }
    )
    write_csv(frame, tmp_path / "t.csv", {"stiffness": "kN/m", "peak_theta": "rad"})
    back = pd.read_csv(tmp_path / "t.csv")
    assert list(back.columns) == [
        "run [-]",
        "engine",
        "stiffness",
        "hits [-]",
        "stick_share [-]",
        "share_acute [-]",
        "first_time [s]",
        "peak_theta [rad]",
    ]
    assert check_plain(tmp_path / "t.csv") == []


def test_stress_table_opens_plainly(tmp_path):
    """``deckpound stress``'s table: one cell, one engine, numbers with units."""
    cell = {"stiffness": 1e6, "dt": 1e-3, "pga": 0.5, "gap": 0.0127}
    run_stress(
        load_scene("saiidi-4span"),
        tmp_path,
        engines=("compliance",),
        duration=0.5,
        timeout=45.0,
        progress=False,
        cells=[cell],
    )
    assert check_plain(tmp_path / "stress.csv") == []
    head = set(pd.read_csv(tmp_path / "stress.csv").columns)
    assert {"stiffness [kN/m]", "max_penetration [m]", "wall [s]", "status"} <= head


def test_adaptive_steps_layout_has_every_unit(tmp_path):
    """adaptive_steps.csv (the skips measurement, a timing run not repeated here): its row
    layout, as compare/bench/skips.py builds it from the adaptive engine's ``step_sizes``, written
    with STEP_UNITS, opens plainly."""
    stats = step_size_summary(np.ones((2, 40)), np.ones((2, 3)))["free"]
    row = dict(scene="benchmark", commit_cap="default", commit_step=1e-4, where="free", **stats)
    row.update(wall=1.0, rtol=1e-6)
    write_csv(pd.DataFrame([row]), tmp_path / "adaptive_steps.csv", STEP_UNITS)
    assert check_plain(tmp_path / "adaptive_steps.csv") == []

"""IDA and multiple-stripe analysis over a record suite, with fragility curves (issue 30,
item 4): every record pair scaled by one factor per level, summary rows cached and resumed,
statuses counted, fragility fitted from capacities (IDA) and from stripes (MSA)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from _record_helpers import quake, write_at2

from deckpound import cli
from deckpound.compare.studies.ida import fragility_table, limit_states, parse_levels
from deckpound.models.errors import SceneError
from deckpound.models.result import read_table

PAIRS = 4
#: a short seat so that the suite unseats within its levels (the benchmark's seat never does)
SEATS = ["--set", "seats[0].support_length=0.015", "--set", "seats[1].support_length=0.015"]


@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    """PAIRS PEER-named station pairs of different synthetic motions (5 s at 100 Hz)."""
    folder = tmp_path_factory.mktemp("suite")
    for i in range(PAIRS):
        write_at2(folder / f"RSN{100 + i}_TEST_ST{i}000.AT2", quake(n=500, seed=2 * i, f=1.5 + i))
        write_at2(folder / f"RSN{100 + i}_TEST_ST{i}090.AT2", quake(n=500, seed=2 * i + 1))
    return folder


def _sweep(tmp_path, suite, command, levels, *extra):
    out = tmp_path / command
    args = [command, "saiidi-4span", "--records", str(suite), "--im", "pga"]
    args += ["--levels" if command == "ida" else "--stripes", levels, *SEATS, *extra]
    code = cli.main([*args, "--workers", "1", "--no-progress", "-o", str(out)])
    return code, out


def test_levels_parse_and_bad_levels_are_refused():
    assert parse_levels("0.1:0.5:0.1", "--levels") == [0.1, 0.2, 0.3, 0.4, 0.5]
    assert parse_levels("0.2,0.4,0.8", "--stripes") == [0.2, 0.4, 0.8]
    for bad in ("0.5:0.1:0.1", "0.1:0.5:0", "a,b", "0.4,0.2", "0,0.1", "nan"):
        with pytest.raises(SceneError):
            parse_levels(bad, "--levels")


def test_ida_runs_every_pair_at_every_level_and_fits_unseating(tmp_path, suite, capsys):
    levels = "0.1:1.5:0.1"
    code, out = _sweep(tmp_path, suite, "ida", levels, "--theta-limit", "0.002")
    printed = capsys.readouterr().out
    assert code == 0
    table = read_table(out / "ida.csv")
    assert len(table) == PAIRS * 15
    assert table["record"].nunique() == PAIRS
    # one factor per pair: every case's geometric-mean PGA is its level (provenance)
    assert set(np.round(table["level"], 9)) == {round(0.1 * k, 9) for k in range(1, 16)}
    assert table["unseated"].any() and not table["unseated"].all()
    assert set(table["status"]) <= {"success", "unseated", "doubtful", "failed"}
    assert (out / "ida.png").stat().st_size > 0 and (out / "fragility.png").stat().st_size > 0
    # an unseated case stops at the seat's edge: its seat-width demand is the support length
    hit = table[table["unseated"]]
    np.testing.assert_allclose(hit["seat_demand"], 0.015, rtol=0.05)
    frag = read_table(out / "fragility.csv")
    row = frag[(frag["limit_state"] == "unseating") & (frag["method"] == "ida")].iloc[0]
    assert 0.1 <= row["median"] <= 1.5 and row["beta"] > 0
    assert "compliance, unseating: median" in printed and f"{PAIRS * 15} cases" in printed
    # a repeated sweep takes every row from the cache
    assert _sweep(tmp_path, suite, "ida", levels, "--theta-limit", "0.002")[0] == 0
    meta = json.loads((out / "ida.json").read_text())
    assert meta["from_cache"] == meta["cases"] == PAIRS * 15


def test_msa_fits_stripes_and_counts_what_it_leaves_out(tmp_path, suite, capsys):
    code, out = _sweep(tmp_path, suite, "msa", "0.2,0.4,0.6,0.8,1.0")
    assert code == 0
    frag = read_table(out / "fragility.csv")
    msa = frag[frag["method"] == "msa"].iloc[0]
    assert msa["cases"] + msa["left_out"] == PAIRS * 5
    assert "unseating:" in capsys.readouterr().out


def test_fragility_of_rows_leaves_out_unfinished_cases():
    """Failed and doubtful cases enter no fit and are counted."""
    rows = []
    for rec in range(6):
        cap = 0.3 + 0.1 * rec
        for level in (0.2, 0.4, 0.6, 0.8, 1.0):
            rows.append(
                {
                    "engine": "compliance",
                    "record_key": f"r{rec}",
                    "level": level,
                    "status": "success",
                    "unseated": level >= cap,
                }
            )
    rows.append(
        {
            "engine": "compliance",
            "record_key": "bad",
            "level": 0.2,
            "status": "failed",
            "unseated": False,
        }
    )
    rows.append(
        {
            "engine": "compliance",
            "record_key": "dbt",
            "level": 0.4,
            "status": "doubtful",
            "unseated": True,
        }
    )
    frag = fragility_table(pd.DataFrame(rows), limit_states(None))
    assert len(frag) == 2
    for _, r in frag.iterrows():
        assert r["left_out"] == 2 and r["cases"] == 30
        assert 0.3 < r["median"] < 1.0 and r["beta"] > 0


def test_a_lone_component_in_the_suite_exits_2(tmp_path):
    folder = tmp_path / "lone"
    folder.mkdir()
    write_at2(folder / "RSN1_X_ST000.AT2", quake(n=200))
    code = cli.main(
        ["ida", "saiidi-4span", "--records", str(folder), "--levels", "0.1,0.2"]
        + ["-o", str(tmp_path / "o")]
    )
    assert code == 2


def test_ida_on_a_local_dask_cluster_of_two_workers_equals_the_local_pool(tmp_path, suite):
    distributed = pytest.importorskip("dask.distributed")
    levels = "0.4,0.8"
    assert _sweep(tmp_path / "local", suite, "ida", levels)[0] == 0
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        out = tmp_path / "dask"
        args = ["ida", "saiidi-4span", "--records", str(suite), "--im", "pga", "--levels"]
        args += [levels, *SEATS, "--scheduler", cluster.scheduler_address, "--no-progress"]
        assert cli.main([*args, "-o", str(out)]) == 0
    local = read_table(tmp_path / "local" / "ida" / "ida.csv")
    remote = read_table(out / "ida.csv")
    for q in ("peak_theta", "seat_margin", "gap_closures"):
        np.testing.assert_array_equal(remote[q], local[q])


def test_a_suite_of_22_pairs_by_10_levels_in_two_engines_end_to_end(tmp_path, capsys):
    """Issue 30's suite: 22 synthetic station pairs x 10 levels on the benchmark with the
    compliance and nonsmooth engines; a sweep stopped early (the first 5 levels) is taken up
    by the full one without recomputing what it finished."""
    from _record_helpers import synthetic_suite

    folder = synthetic_suite(tmp_path / "suite", 22, seed=100, duration=10.0)
    cache = str(tmp_path / "cache")
    base = ["ida", "saiidi-4span", "--records", str(folder), "--im", "sa-t1"]
    base += ["--engines", "compliance,nonsmooth", *SEATS, "--cache", cache, "--no-progress"]
    assert cli.main([*base, "--levels", "0.2:1.0:0.2", "-o", str(tmp_path / "half")]) == 0
    assert cli.main([*base, "--levels", "0.2:2.0:0.2", "-o", str(tmp_path / "full")]) == 0
    meta = json.loads((tmp_path / "full" / "ida.json").read_text())
    assert meta["cases"] == 2 * 22 * 10 and meta["from_cache"] == 2 * 22 * 5
    frag = read_table(tmp_path / "full" / "fragility.csv")
    assert set(frag["engine"]) == {"compliance", "nonsmooth"}
    printed = capsys.readouterr().out
    assert "compliance, unseating:" in printed and "nonsmooth, unseating:" in printed


def test_an_unseated_case_exceeds_the_rotation_limit_state():
    """The run stops where the deck loses its seat: its rotation so far is not its demand."""
    from deckpound.compare.studies.ida import with_rotation_flag

    table = pd.DataFrame({"peak_theta": [0.001, 0.006, 0.001], "unseated": [False, False, True]})
    assert with_rotation_flag(table, 0.005)["theta_exceeded"].tolist() == [False, True, True]


def test_vary_friction_runs_the_sweep_per_value_and_fits_each(tmp_path, suite, capsys):
    """``--vary contact.friction=0,0.4``: every case once per value (its own scene, so its own
    cached row), a ``variant`` column, fragility rows per engine × variant."""
    vary = ["--vary", "contact.friction=0,0.4", "--set", "contact.friction_mode=slip"]
    code, out = _sweep(tmp_path, suite, "ida", "0.2:1.0:0.2", *vary)
    printed = capsys.readouterr().out
    assert code == 0
    table = read_table(out / "ida.csv")
    assert len(table) == 2 * PAIRS * 5
    assert table.groupby("variant").size().to_dict() == {
        "contact.friction=0": PAIRS * 5,
        "contact.friction=0.4": PAIRS * 5,
    }
    assert table["case"].is_unique
    meta = json.loads((out / "ida.json").read_text())
    assert meta["computed"] == 2 * PAIRS * 5  # no case of one value is taken for the other
    assert meta["variants"]["contact.friction=0.4"] == ["contact.friction=0.4"]
    # friction changes the response: the two values do not give the same rows
    a, b = (g.sort_values(["record_key", "level"]) for _, g in table.groupby("variant"))
    assert not np.allclose(a["peak_theta"].to_numpy(), b["peak_theta"].to_numpy())
    frag = read_table(out / "fragility.csv")
    assert len(frag) == 2 * 1 * 2  # variants × limit states × methods
    assert set(frag["variant"]) == {"contact.friction=0", "contact.friction=0.4"}
    assert "compliance (contact.friction=0.4), unseating:" in printed
    assert (out / "fragility.png").stat().st_size > 0


def test_vary_gap_shorthand_sets_both_seats(tmp_path):
    from deckpound.compare.studies.ida import parse_vary
    from deckpound.models.scene_io import load_scene

    scene = load_scene("saiidi-4span")
    variants = parse_vary("gap=0.0127,0.025", scene)
    assert variants == [
        ("gap=0.0127", ("seats[0].gap=0.0127", "seats[1].gap=0.0127")),
        ("gap=0.025", ("seats[0].gap=0.025", "seats[1].gap=0.025")),
    ]


@pytest.mark.parametrize(
    "vary",
    [
        "contact.no_such_field=0,1",
        "contact.friction=0,abc",
        "contact.friction=0,-1",
        "contact.friction",
        "contact.friction=0,,1",
        "contact.friction=0,0",
        "contact.friction=" + ",".join(str(0.01 * k) for k in range(11)),
    ],
)
def test_bad_vary_exits_2_naming_the_option(tmp_path, suite, capsys, vary):
    slip = ["--set", "contact.friction_mode=slip"]
    code, out = _sweep(tmp_path, suite, "ida", "0.2,0.4", "--vary", vary, *slip)
    err = capsys.readouterr().err
    assert code == 2
    assert "--vary" in err and "Traceback" not in err
    assert not (out / "ida.csv").exists()


def test_varying_friction_without_a_friction_mode_exits_2(tmp_path, suite, capsys):
    """The default friction_mode 'none' ignores mu: every value would give the same rows."""
    code, _ = _sweep(tmp_path, suite, "ida", "0.2,0.4", "--vary", "contact.friction=0,0.3")
    err = capsys.readouterr().err
    assert code == 2 and "--vary" in err and "friction_mode" in err


def test_synthetic_pairs_are_a_readable_suite_of_distinct_motions(tmp_path):
    """The generator's first-bent motions of seeds 7, 8 as AT2 pairs: read back as two
    station pairs whose x components differ and match the generator to the file's 8 digits."""
    from deckpound.compare.studies.ida import synthetic_pairs
    from deckpound.compare.studies.variability import record_cases
    from deckpound.models.excitation import support_motion
    from deckpound.models.records import read_at2
    from deckpound.models.scene_io import load_scene

    scene = load_scene("saiidi-4span")
    folder = synthetic_pairs(scene, tmp_path / "suite", 2, seed=7, duration=4.0)
    assert len(record_cases(scene, folder, False)) == 2
    first = read_at2(folder / "RSN1_SYNTH_ST1000.AT2")
    second = read_at2(folder / "RSN2_SYNTH_ST2000.AT2")
    motion = support_motion(
        load_scene("saiidi-4span", ["excitation.seed=7", "excitation.duration=4.0"])
    )
    np.testing.assert_allclose(first.values, motion.acc("bent1_x") / 9.80665, rtol=1e-6, atol=1e-9)
    assert not np.allclose(first.values[: len(second.values)], second.values[: len(first.values)])

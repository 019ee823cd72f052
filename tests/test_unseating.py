"""Seat margins and unseating, the same in every engine (issue 30, item 1).

The seat (support) length N of an abutment seat (``seats[i].support_length``, AASHTO LRFD's
seat width) is the length of seat under the deck end along the face normal, measured from the
deck end's initial position. A corner's seat margin is m_c(t) = N − (g_c(t) − g_c(0)); the
first step at which it is negative ends the run with status ``"unseated"`` (an answer, not a
failure), in the compliance engine (Newmark and adaptive loops), the nonsmooth engine and
OpenSees alike.

Closed form: a free deck (no bents, no damping, supports at rest) moving away from seat 1 at
v opens the gaps of c1 and c2 as g − g(0) = v t exactly, so they unseat at t* = N / v; every
engine stops at the first step ending at or after t*.
"""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from deckpound.compare.engines import run_engine
from deckpound.models.errors import SceneError
from deckpound.models.result import STATUS_UNSEATED, Result
from deckpound.models.scene_io import load_scene

SCENE = Path(__file__).parent / "data" / "corner_impact.toml"
#: deck speed away from seat 1 [m/s] and seat 1's support length [m]: t* = N / v = 0.10246 s
#: falls between the steps of every engine (1e-5 s and 1e-4 s)
V, N = 0.5, 0.05123
FREE = [
    "initial.deck=[0.0,0.0,0.0]",
    f"initial.deck_velocity=[{V},0.0,0.0]",
    "seats[1].gap=0.3",  # seat 2 is never reached (the deck travels 0.1 m)
    f"seats[0].support_length={N}",
    "run.duration=0.2",
]
ENGINES = [
    ("compliance", ()),
    ("compliance", ("compliance.integrator=adaptive",)),
    ("nonsmooth", ()),
    ("opensees", ()),
]
IDS = ["newmark", "adaptive", "nonsmooth", "opensees"]


def _run(engine: str, scene, *overrides: str) -> Result:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ignored options of the textbook scene
        return run_engine(engine, load_scene(scene, list(overrides)))


def _step(r: Result) -> float:
    """The step an engine ran [s]: its own (after the contact-step rule), or for the
    adaptive loop the output step, which bounds its steps (every row is a breakpoint)."""
    if r.meta.get("integrator") == "adaptive":
        return 1e-4
    return r.meta.get("dt") or r.meta["settings"].get("h") or r.meta["settings"]["dt"]


# -- the scene field ------------------------------------------------------------------------


def test_support_length_is_optional_and_checked():
    sc = load_scene(SCENE)
    assert all(s.support_length is None for s in sc.seats)  # not set: not checked
    with pytest.raises(SceneError, match=r"seats\[0\]\.support_length.*> 0"):
        load_scene(SCENE, ["seats[0].support_length=0"])
    r = _run("nonsmooth", SCENE, *FREE[:3], "run.duration=0.2")
    assert r.ok and not r.unseated
    assert r.meta["seat_margin_min"] == {}
    assert r.meta["seat_margin_basis"].startswith("not checked")
    # the opening is measured all the same (the seat-width demand): v t at the end
    assert r.meta["gap_opening_max"]["c1"][0] == pytest.approx(V * 0.2, rel=1e-9)


@pytest.mark.parametrize("name", ["saiidi-4span", "skew-30"])
def test_built_in_support_lengths_follow_the_stated_aashto_assumption(name):
    """The notes' arithmetic: N = (8 + 0.02 L + 0.08 H)(1 + 0.000125 S²) in (AASHTO LRFD
    Eq. 4.7.4.4-1) at prototype scale (L = 4 x 33.5 m, H = 4 x mean(6, 8, 5) ft), x 1.5
    (seismic zones 2-4), scaled by 1/4: 0.179 m straight, 0.1994 m at the 30° skew."""
    sc = load_scene(name)
    ft = 0.3048
    length_ft = 4 * sc.deck.length / ft
    height_ft = 4 * (6 + 8 + 5) / 3
    n_in = (8 + 0.02 * length_ft + 0.08 * height_ft) * (1 + 0.000125 * sc.deck.skew**2)
    model = 1.5 * n_in * 0.0254 / 4
    assert model == pytest.approx(0.179 if name == "saiidi-4span" else 0.1994, abs=5e-4)
    # the skewed scene keeps the benchmark's value (the skew the only change; its note says so)
    assert {s.support_length for s in sc.seats} == {0.18}
    assert "0.18 m" in sc.notes["seats[0].support_length"]
    assert f"{model:.3g}" in sc.notes["seats[0].support_length"]
    for i in (0, 1):
        assert sc.notes[f"seats[{i}].support_length"].startswith("ASSUMPTION")


# -- the closed form, every engine ----------------------------------------------------------


@pytest.mark.parametrize(("engine", "extra"), ENGINES, ids=IDS)
def test_free_deck_unseats_at_n_over_v(engine, extra):
    if engine == "opensees":
        pytest.importorskip("openseespy.opensees")
    r = _run(engine, SCENE, *FREE, *extra)
    m = r.meta
    t_star, h = N / V, _step(r)
    assert m["status"] == STATUS_UNSEATED and r.unseated and not r.ok
    assert m["failure"] is None
    assert m["unseated_corner"] == "c1"  # c1 and c2 open together; the first is named
    # the first step ending at or after t*, to one step
    assert t_star <= m["unseated_time"] < t_star + h + 1e-12
    assert m["unseated_step"] == m["steps"]
    assert "unseated" in m["message"] and "seats[0].support_length" in m["message"]
    # margins of the corners facing seat 1 (seat 2 has no support length: not checked)
    assert set(m["seat_margin_min"]) == {"c1", "c2"}
    margin, when = m["seat_margin_min"]["c1"]
    assert -V * h - 1e-12 < margin < 0.0 and when == m["unseated_time"]
    # the output stops before the unseating step, and its rows are the free flight v t
    assert r.t[-1] < m["unseated_time"]
    assert np.allclose(r["gap_c1"] - r["gap_c1"][0], V * r.t, rtol=0, atol=1e-12)


def test_unseating_leaves_the_rows_before_it_unchanged():
    """Stopping changes nothing before the stop: the rows of the unseated run are the first
    rows of the same run without a support length, bit for bit (compliance engine)."""
    cut = _run("compliance", SCENE, *FREE)
    full = _run("compliance", SCENE, *FREE[:3], "run.duration=0.2")
    assert cut.unseated and full.ok
    n = len(cut.t)
    assert 0 < n < len(full.t)
    for col in cut.columns:
        assert np.array_equal(cut[col], full[col][:n]), col


# -- the benchmark --------------------------------------------------------------------------


def test_benchmark_margins_agree_between_the_clone_and_opensees():
    """No unseating on the benchmark (largest opening 0.087 m, less than half of N = 0.18 m,
    as its note says); the clone's margins equal OpenSees's to round-off, time for time,
    corner by corner."""
    pytest.importorskip("openseespy.opensees")
    ops = _run("opensees", "saiidi-4span")
    clone = _run("compliance", "saiidi-4span")
    for r in (ops, clone):
        assert r.ok and not r.unseated
        assert r.meta["seat_margin_basis"] == "every step"
        for c, (opening, _) in r.meta["gap_opening_max"].items():
            assert 0.0 < opening < 0.5 * 0.18, c
        largest = max(o for o, _ in r.meta["gap_opening_max"].values())
        assert largest == pytest.approx(0.087, abs=5e-4)
    assert set(ops.meta["seat_margin_min"]) == {"c1", "c2", "c3", "c4"}
    for c, (margin, when) in ops.meta["seat_margin_min"].items():
        other, other_when = clone.meta["seat_margin_min"][c]
        assert other == pytest.approx(margin, abs=1e-10), c
        assert other_when == pytest.approx(when, abs=1e-9), c
        # the margin is N minus the largest gap's opening, at least what the rows show
        rows_opening = float(np.max(clone[f"gap_{c}"]) - clone[f"gap_{c}"][0])
        assert other <= 0.18 - rows_opening + 1e-15, c


def test_benchmark_unseats_on_a_narrow_seat_in_every_engine():
    """A 5 mm seat: every engine stops with 'unseated'; the clone and OpenSees at the same
    step (they agree to round-off), the nonsmooth engine within five of its 1 ms steps."""
    pytest.importorskip("openseespy.opensees")
    narrow = ("run.duration=6.0", "seats[0].support_length=0.005", "seats[1].support_length=0.005")
    runs = {e: _run(e, "saiidi-4span", *narrow) for e in ("compliance", "opensees", "nonsmooth")}
    for e, r in runs.items():
        assert r.meta["status"] == STATUS_UNSEATED, (e, r.meta["message"])
        assert r.meta["seat_margin_min"][r.meta["unseated_corner"]][0] < 0.0, e
    clone, ops = runs["compliance"].meta, runs["opensees"].meta
    assert clone["unseated_corner"] == ops["unseated_corner"]
    assert clone["unseated_time"] == pytest.approx(ops["unseated_time"], abs=1e-9)
    assert clone["unseated_step"] == ops["unseated_step"]
    # rigid contact against penalty contact: 0.612 s against 0.6115 s (corner c3)
    assert runs["nonsmooth"].meta["unseated_corner"] == clone["unseated_corner"]
    assert runs["nonsmooth"].meta["unseated_time"] == pytest.approx(
        clone["unseated_time"], abs=0.005
    )


def test_a_run_that_does_not_unseat_is_unchanged_by_the_check():
    """The tracking reads its own arrays only: with N = 0.18 m (never reached) the columns are
    those of the run without a support length (not checked), bit for bit, and the status
    stays success."""
    sc = load_scene("saiidi-4span", ["run.duration=2.0"])
    bare = sc.replace(seats=tuple(dataclasses.replace(s, support_length=None) for s in sc.seats))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        checked, unchecked = run_engine("compliance", sc), run_engine("compliance", bare)
    assert checked.ok and unchecked.ok and not checked.unseated
    assert set(checked.meta["seat_margin_min"]) == {"c1", "c2", "c3", "c4"}
    assert unchecked.meta["seat_margin_min"] == {}
    for col in checked.columns:
        assert np.array_equal(checked[col], unchecked[col]), col
    assert checked.meta["peaks"] == unchecked.meta["peaks"]
    assert checked.meta["gap_opening_max"] == unchecked.meta["gap_opening_max"]


# -- the command line -----------------------------------------------------------------------


def test_cli_run_says_unseated_and_exits_0(tmp_path):
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "deckpound", "run", str(SCENE), "--engine", "nonsmooth"]
    for o in FREE:
        cmd += ["--set", o]
    p = subprocess.run(cmd + ["-o", str(out)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    line = p.stdout.strip().splitlines()[-1]
    assert line.startswith("nonsmooth: unseated") and "corner c1 unseated at t = 0.1025 s" in line
    meta = json.loads((out / "nonsmooth.json").read_text(encoding="utf-8"))
    assert meta["status"] == "unseated" and meta["unseated"] is True
    assert math.isclose(meta["unseated_time"], 0.1025, abs_tol=1e-12)


def test_exported_python_script_unseats_as_the_engine(tmp_path):
    """The exported OpenSees Python script runs the engine's step loop (copied verbatim): it
    stops at the same step, writes the same margins into opensees.stats.json and exits 0."""
    pytest.importorskip("openseespy.opensees")
    from deckpound.opensees_build.export import export_script

    sc = load_scene(SCENE, FREE)
    r = _run("opensees", SCENE, *FREE)
    py = export_script(sc, "py", tmp_path / "model.py")
    out = tmp_path / "results"
    cp = subprocess.run(
        [sys.executable, str(py), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    assert cp.stdout.startswith("unseated corner c1 unseated at t = 0.1025 s")
    st = json.loads((out / "opensees.stats.json").read_text(encoding="utf-8"))
    assert st["status"] == "unseated" and st["steps"] == r.meta["steps"]
    assert st["unseated"] == [r.meta["unseated_corner"], r.meta["unseated_time"]]
    for c in ("c1", "c2", "c3", "c4"):
        assert st["gap_openings"][c] == r.meta["gap_opening_max"][c], c


def test_seat_margins_from_the_rows_when_an_engine_does_not_track_them():
    """Contract point 11 is optional: without every-step openings the epilogue takes them from
    the output rows (basis said) and flags the unseating it sees there."""
    from deckpound.models.engine_contract import RunOutput, seat_margins
    from deckpound.models.plan import plan_of

    sc = load_scene("saiidi-4span")  # N = 0.18 m at both seats
    t = np.array([0.0, 1.0, 2.0])
    cols = {"t": t, "gap_c1": np.array([0.01, 0.05, 0.02]), "gap_c2": np.array([0.01, 0.3, 0.0])}
    cols |= {"gap_c3": np.full(3, 0.01), "gap_c4": np.array([0.01, 0.0, -0.001])}
    q = seat_margins(sc, plan_of(sc), cols, RunOutput(columns=cols, steps=2))
    assert q["seat_margin_basis"] == "output rows"
    assert q["gap_opening_max"]["c1"] == [pytest.approx(0.04), 1.0]
    assert q["gap_opening_max"]["c4"] == [0.0, 0.0]  # the gap only closed: opening 0 at t = 0
    assert q["seat_margin_min"]["c1"] == [pytest.approx(0.14), 1.0]
    assert q["seat_margin_min"]["c2"] == [pytest.approx(0.18 - 0.29), 1.0]
    assert q["unseated"] and q["unseated_corner"] == "c2" and q["unseated_time"] == 1.0


def test_a_sequence_run_keeps_the_seat_left_by_the_earlier_runs():
    """A carried residual opening uses up seat: run k's support length is N − (g_k − g₀), so
    its margins count from the original seat (and a deck pushed back gains seat)."""
    from deckpound.models.sequence import initial_state, scene_for_run

    sc = load_scene("saiidi-4span")
    state = dataclasses.replace(initial_state(sc), gaps=(0.0227, 0.0027))
    run = scene_for_run(sc, 0.5, state)
    assert run.seats[0].gap == 0.0227 and run.seats[1].gap == 0.0027
    assert run.seats[0].support_length == pytest.approx(0.18 - 0.01, abs=1e-15)
    assert run.seats[1].support_length == pytest.approx(0.18 + 0.01, abs=1e-15)
    bare = sc.replace(seats=tuple(dataclasses.replace(s, support_length=None) for s in sc.seats))
    assert scene_for_run(bare, 0.5, state).seats[0].support_length is None

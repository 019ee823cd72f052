"""Summary-only runs (issue 30 item 4, issue 33 item 3): a sweep's run keeps no histories, yet
says what a full run says — every-step peaks, gap closures, seat margins, the energy check and
the status — and a full run holds its histories once (the engines' columns are views of their
output table, handed to the Result without a copy)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from _free_vibration import free_vibration

import deckpound as dp
from deckpound.models.columns import ENERGY_COLUMNS
from deckpound.models.result import Result
from deckpound.models.scene_io import load_scene

SHORT = ["run.duration=3", "excitation.duration=3", "seats[0].support_length=0.3"]
CASES = {
    "compliance": (),
    "adaptive": ("compliance.integrator=adaptive",),
    "nonsmooth": (),
    "friction": ("contact.friction=0.3",),
}


def quiet_run(scene, engine, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return dp.run(scene, engine=engine, **kw)


def pair(case: str, *extra: str):
    engine = "nonsmooth" if case == "nonsmooth" else "compliance"
    scene = load_scene("saiidi-4span", [*SHORT, *CASES[case], *extra])
    return quiet_run(scene, engine), quiet_run(scene, engine, summary_only=True)


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_summary_says_what_the_full_run_says(case):
    full, summary = pair(case)
    assert not summary.has_histories and full.has_histories
    assert len(summary.t) == 0 and list(summary.columns) == ["t"]
    assert summary.meta["status"] == full.meta["status"] == "success"
    peaks = full.meta["peaks"]
    assert set(summary.meta["peaks"]) == set(peaks)
    for name, (value, when) in peaks.items():
        # the full run may raise a derived column's peak to its row value (other round-off)
        assert summary.peak(name) == pytest.approx(value, rel=1e-12, abs=1e-300), name
        assert summary.peak_time(name) == pytest.approx(when, abs=1e-12), name
    for key in ("gap_closures_per_corner", "seat_margin_min", "gap_opening_max", "unseated"):
        assert summary.meta[key] == full.meta[key], key
    for key in ("energy_check", "energy_created", "max_penetration", "steps", "duration"):
        assert summary.meta[key] == full.meta[key], key
    energies = [k for k in ENERGY_COLUMNS if k in full.columns]
    assert summary.meta["final_energies"] == {k: float(full[k][-1]) for k in energies}
    assert "scene" in full.meta and "scene" not in summary.meta
    # a summary row has no place for the record's intensity measures: not computed
    assert (
        full.meta["record"]["intensity"]["x"]["pga"] > 0
        and summary.meta["record"]["intensity"] is None
    )


def test_a_summary_of_a_doubtful_run_is_doubtful():
    """The issue-28 free vibration at the default step creates energy at its contacts: the
    summary reads the energy columns of the loop's rows before it drops them."""
    scene = free_vibration("excitation.duration=4")
    full = quiet_run(scene, "compliance")
    summary = quiet_run(scene, "compliance", summary_only=True)
    assert full.doubtful and summary.doubtful
    assert summary.meta["energy_created"] == full.meta["energy_created"]
    assert summary.meta["energy_created_time"] == full.meta["energy_created_time"]


def test_an_unseated_summary_stops_where_the_full_run_stops():
    full, summary = pair("compliance", "seats[0].support_length=0.002")
    assert full.unseated and summary.unseated
    for key in ("unseated_corner", "unseated_time", "unseated_step", "status", "message"):
        assert summary.meta[key] == full.meta[key], key


def test_a_summary_shows_no_rows():
    _, summary = pair("compliance")
    facts = summary.summary()
    assert facts["rows"] == "none (summary only)" and facts["duration"] == "3 s"
    assert "peak θ_d" in facts
    with pytest.raises(KeyError, match="energy_input"):
        summary.peak("energy_input")  # not tracked at every step: it needs the rows


@pytest.mark.parametrize("case", ["compliance", "nonsmooth", "friction"])
def test_a_summary_run_stores_only_the_rows_its_checks_read(case):
    """Engine contract point 12: the loop stores t and the energy columns, nothing else; the
    adaptive integrator stores every column (it keeps no summary rows)."""
    engine = dp.get_engine("nonsmooth" if case == "nonsmooth" else "compliance")
    scene = load_scene("saiidi-4span", [*SHORT, *CASES[case]])
    settings = engine.settings_of(scene)
    plan = dp.plan_of(scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        motion = dp.support_motion(scene)
        out = engine._run(plan, scene, settings, motion, summary_rows=True)
        full = engine._run(plan, scene, settings, motion)
    energies = [c for c in full.columns if c.startswith("energy_")]
    assert out.summary_rows and not full.summary_rows
    assert list(out.columns) == ["t", *energies] and len(energies) >= 8
    for name in out.columns:
        np.testing.assert_array_equal(out.columns[name], full.columns[name])
    assert out.max_penetration == full.max_penetration and out.peaks == full.peaks


def test_summary_rows_without_every_step_measurements_are_refused():
    scene = load_scene("saiidi-4span", SHORT)
    engine = dp.get_engine("compliance")

    class Forgetful(type(engine)):
        def _run(self, *args, **kw):
            out = super()._run(*args, **kw)
            return dataclasses.replace(out, peaks=None)

    with warnings.catch_warnings(), pytest.raises(RuntimeError, match="point 12"):
        warnings.simplefilter("ignore")
        Forgetful().run(scene, summary_only=True)


def test_the_adaptive_integrator_keeps_every_row_of_a_summary():
    _, summary = pair("adaptive")
    assert summary.meta["max_penetration_basis"] == "every step"
    assert "max_penetration_rows" in summary.meta  # it stored the gaps


@pytest.mark.parametrize("engine", ["compliance", "nonsmooth"])
def test_a_run_holds_its_histories_once(engine):
    """Every engine column is a read-only view of one output table, kept by the Result."""
    scene = load_scene("saiidi-4span", ["run.duration=1", "excitation.duration=1"])
    r = quiet_run(scene, engine)
    bases = {id(r[c].base) for c in ("t", "deck_x_abs", "gap_c1", "energy_input")}
    assert len(bases) == 1 and r["t"].base is not None
    assert not any(col.flags.writeable for col in r.columns.values())


def test_a_result_copies_only_what_it_was_not_handed_read_only():
    handed = np.arange(4.0)
    handed.flags.writeable = False
    mine = np.arange(4.0)
    r = Result("measured", {"t": handed, "x": mine})
    assert r["t"] is handed
    assert r["x"] is not mine and not np.shares_memory(r["x"], mine)
    mine[0] = 99.0
    assert r["x"][0] == 0.0

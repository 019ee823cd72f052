"""Support motion interpolated in the compiled loop (analytic/kernels/support_motion.py): bit-identical
to np.interp / SupportMotion.resample, and the compliance engine keeps no per-step arrays."""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.analytic.kernels.support_motion import (
    record_at,
    record_at_times,
    record_slopes,
    support_record,
)
from deckpound.models.columns import standard_columns
from deckpound.models.excitation import support_motion
from deckpound.models.scene_io import load_scene


def test_record_at_is_np_interp_bit_for_bit():
    rng = np.random.default_rng(3)
    tb = np.cumsum(rng.uniform(1e-3, 1e-2, 400))
    tb -= tb[0]
    D = rng.standard_normal((400, 3))
    V = rng.standard_normal((400, 3))
    SD, SV = record_slopes(tb, D, V)
    for dt in (1e-5, 3.3e-4, 5e-4, 7e-3, 0.05):
        n = int(round((tb[-1] + 0.2) / dt))  # runs past the end: last value held
        UG = np.empty((n + 1, 3))
        VG = np.empty((n + 1, 3))
        record_at_times(tb, D, V, SD, SV, dt, 0, n + 1, UG, VG)
        t = np.arange(n + 1) * dt
        for k in range(3):
            assert np.array_equal(UG[:, k], np.interp(t, tb, D[:, k]))
            assert np.array_equal(VG[:, k], np.interp(t, tb, V[:, k]))
    # samples hit exactly, any hint works
    ug, vg = np.empty(3), np.empty(3)
    for j in (0, 399, 57):
        record_at(tb, D, V, SD, SV, tb[123], j, ug, vg)
        assert np.array_equal(ug, D[123]) and np.array_equal(vg, V[123])


def test_scene_motion_matches_resample():
    sc = load_scene("saiidi-4span", ["excitation.duration=2.0"])
    m = support_motion(sc)
    from deckpound.models.plan import support_channels

    ch = support_channels(sc)
    tb, D, V = support_record(m, ch)
    res = m.resample(5e-4, 2.0)
    UG, VG = res.matrices(ch)
    A, B = np.empty_like(UG), np.empty_like(VG)
    record_at_times(tb, D, V, *record_slopes(tb, D, V), 5e-4, 0, UG.shape[0], A, B)
    assert np.array_equal(A, UG) and np.array_equal(B, VG)


def test_compliance_channels_and_skips_keep_results():
    from deckpound.analytic.compliance.engine import SKIPS, run_compliance

    sc = load_scene("saiidi-4span", ["run.duration=1.5", "contact.law=kelvin-voigt"])
    full = run_compliance(sc)
    # the standard columns are always stored (engine contract); ``channels`` selects the extras,
    # so without an energy column no energy bookkeeping is done
    part = run_compliance(sc, channels=["deck_theta", "fn_c1"])
    assert list(part.columns) == standard_columns([b.name for b in sc.bents])
    assert "energy_input" not in part.columns and "energy_input" in full.columns
    for c in part.columns:
        assert np.array_equal(part.columns[c], full.columns[c])
    for name in SKIPS:
        r = run_compliance(sc, _skips={name: False})
        assert r.ok
        for c in full.columns:
            assert np.array_equal(r.columns[c], full.columns[c]), (name, c)
    with pytest.raises(ValueError):
        run_compliance(sc, channels=["nope"])


def test_unmoved_iterates_are_most_converged_steps_and_change_nothing():
    """The benchmark's steps converge at Newton's second iterate, whose round-off increment
    (~1e-23 m against u ~ 1e-2 m) leaves u bitwise unchanged: the skip fires at most steps,
    and its results are the forces-re-evaluated ones bit for bit."""
    from deckpound.analytic.compliance.engine import run_compliance

    sc = load_scene("saiidi-4span", ["run.duration=3.0"])
    on = run_compliance(sc)
    off = run_compliance(sc, _skips={"unmoved_iterate": False})
    steps = on.meta["steps"]
    assert on.meta["unmoved_iterates"] > 0.5 * steps, on.meta["unmoved_iterates"]
    assert off.meta["unmoved_iterates"] == 0
    assert on.meta["newton_iterations"] == off.meta["newton_iterations"]
    assert on.meta["gap_closures"] == off.meta["gap_closures"] > 0
    for c in on.columns:
        assert np.array_equal(on.columns[c], off.columns[c]), c


def test_adaptive_reports_step_sizes_in_and_out_of_contact():
    from deckpound.analytic.compliance.engine import run_compliance

    # commit_step lifted so the error control alone sets the steps (after a yield the default
    # caps them at 1e-4 s in and out of contact alike)
    sc = load_scene(
        "saiidi-4span",
        ["run.duration=2.0", "compliance.integrator=adaptive", "compliance.commit_step=0.01"],
    )
    st = run_compliance(sc).meta["step_sizes"]
    assert st["free"]["steps"] > 0 and st["contact"]["steps"] > 0
    assert abs(st["free"]["time"] + st["contact"]["time"] - 2.0) < 1e-9
    assert st["contact"]["median"] < st["free"]["median"]  # short steps in contact

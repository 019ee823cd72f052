"""Compliance engine without contact: independent solution, Newmark order 2, adaptive accuracy."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from _compliance_helpers import (
    base_scene,
    motion_from,
    with_bents,
    with_compliance,
    with_run,
    with_seats,
)
from scipy.integrate import solve_ivp

from deckpound.analytic.compliance.engine import run_compliance
from deckpound.analytic.kernels.system import pack_system
from deckpound.models.damping import damping_model
from deckpound.models.plan import plan_of

A = 0.02
W1, W2 = 2 * np.pi * 1.5, 2 * np.pi * 2.3
T_END = 2.0


def _ug(t):
    return A * (1 - np.cos(W1 * t)), A * (1 - np.cos(W2 * t))


def _vg(t):
    return A * W1 * np.sin(W1 * t), A * W2 * np.sin(W2 * t)


@pytest.fixture(scope="module")
def smooth():
    sc = with_seats(with_bents(base_scene(), elastic=True), gap=10.0)
    sc = with_run(sc, duration=T_END, output_dt=0.02)
    ps = pack_system(plan_of(sc), damping_model(sc, plan_of(sc)))
    t = np.arange(0, int(round(T_END / 1e-4)) + 1) * 1e-4
    (dx, dy), (vx, vy) = _ug(t), _vg(t)
    disp, vel = {}, {}
    for ch in ps.channels:
        disp[ch], vel[ch] = (dy, vy) if ch.endswith("_y") else (dx, vx)
    motion = motion_from(sc, t, disp, vel)
    # independent reference: the linear ODE with the analytic support motion, DOP853
    B, S = ps.arrays.B, ps.arrays.S
    M = ps.arrays.mass
    K0, C = ps.K0, ps.C
    k0 = ps.arrays.k0
    crate = ps.arrays.crate
    sel_y = np.array([ch.endswith("_y") for ch in ps.channels])

    def g(t):
        ux, uy = _ug(t)
        vx, vy = _vg(t)
        return np.where(sel_y, uy, ux), np.where(sel_y, vy, vx)

    def f(t, y):
        u, v = y[:7], y[7:]
        ugt, vgt = g(t)
        F = B.T @ (k0 * (B @ u - S @ ugt) + crate * (B @ v - S @ vgt)) + ps.a0 * M * v
        return np.concatenate([v, -F / M])

    tt = np.arange(0, int(round(T_END / 0.02)) + 1) * 0.02
    sol = solve_ivp(f, (0, T_END), np.zeros(14), method="DOP853", rtol=1e-12, atol=1e-14, t_eval=tt)
    ref = {
        "deck_x_abs": sol.y[4],
        "deck_y_abs": sol.y[5],
        "deck_theta": sol.y[6],
        "seat1_x_abs": sol.y[0],
    }
    _ = K0, C
    return sc, motion, ref


def _err(res, ref):
    return max(np.max(np.abs(res[k] - ref[k])) / np.max(np.abs(ref[k])) for k in ref)


def test_newmark_matches_independent_solution_and_is_second_order(smooth):
    sc, motion, ref = smooth
    sc = sc.replace(
        run=dataclasses.replace(sc.run, steps_per_contact_period=0.0)
    )  # the given steps
    dts = [4e-3, 2e-3, 1e-3, 5e-4]
    errs = []
    for dt in dts:
        r = run_compliance(with_compliance(sc, dt=dt, tolerance=1e-12), motion)
        assert r.ok
        assert r.meta["gap_closures"] == 0
        errs.append(_err(r, ref))
    p = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    print("newmark errors", errs, "observed order", p)
    assert 1.9 < p < 2.1
    assert errs[-1] < 1e-4


def test_adaptive_error_within_tolerance(smooth):
    sc, motion, ref = smooth
    r = run_compliance(
        with_compliance(sc, integrator="adaptive", rtol=1e-9, atol=1e-12, max_step=0.005), motion
    )
    assert r.ok
    e = _err(r, ref)
    print("adaptive error", e, r.meta["message"])
    # (the remaining ~1e-7 is the piecewise-linear sampling of the motion at 1e-4 s)
    assert e < 1e-6


def test_failed_step_is_reported_without_nan():
    sc = with_run(base_scene(), duration=2.0)
    sc = with_compliance(sc, max_iterations=1, tolerance=1e-14)
    r = run_compliance(sc)
    assert r.meta["status"] == "failed"
    assert r.meta["failed_step"] >= 1 and r.meta["failed_time"] > 0
    assert all(np.all(np.isfinite(v)) for v in r.columns.values())
    from deckpound.models.errors import EngineFailure

    with pytest.raises(EngineFailure):
        run_compliance(sc, raise_on_failure=True)


def test_non_finite_initial_state_is_refused():
    sc = with_compliance(with_run(base_scene(), duration=0.5), integrator="adaptive")
    u0 = np.zeros(7)
    u0[5] = np.nan
    for integrator in ("adaptive", "newmark"):
        with pytest.raises(ValueError, match="initial_state u0 must be 7 finite numbers"):
            run_compliance(
                with_compliance(sc, integrator=integrator), initial_state=(u0, np.zeros(7))
            )
    with pytest.raises(ValueError, match="initial_state v0"):
        run_compliance(sc, initial_state=(np.zeros(7), np.zeros(6)))


def test_failure_time_of_an_adaptive_run_is_its_own():
    """Adaptive steps vary: the failure is reported at the time given, not step × dt."""
    from deckpound.compare.engines import get_engine
    from deckpound.models.engine_contract import RunOutput, Status, finish
    from deckpound.models.excitation import support_motion

    sc = with_run(base_scene(), duration=0.5)
    motion = support_motion(sc)
    ok = run_compliance(sc, motion)
    cols = {k: np.asarray(v) for k, v in ok.columns.items()}
    out = RunOutput(
        columns=cols,
        status=Status.NOT_CONVERGED,
        message="step size underflow",
        failed_step=1234,
        failed_time=3.25,
    )
    meta = finish(
        get_engine("compliance"), sc, sc.compliance, motion, plan_of(sc), out, 0.1, []
    ).meta
    assert meta["status"] == "failed" and meta["failed_step"] == 1234
    assert meta["failed_time"] == 3.25 and meta["message"].endswith("(t = 3.25 s)")


@pytest.mark.parametrize("dofs", [(), (0, 1, 4)])
def test_spring_without_one_or_two_dofs_is_refused(dofs):
    """The spring kernels read a row's first non-zero unconditionally and at most two: a
    spring whose deformation has no DOF or more than two is refused when packed, by name."""
    sc = base_scene()
    plan = plan_of(sc)
    bad = dataclasses.replace(plan.springs[0], dofs=dofs, coefs=tuple(1.0 for _ in dofs))
    plan = dataclasses.replace(plan, springs=(bad, *plan.springs[1:]))
    with pytest.raises(ValueError, match=rf"spring {bad.name}: .*1 or 2 DOFs, got {len(dofs)}"):
        pack_system(plan, damping_model(sc, plan))

"""Nonsmooth (Moreau–Jean) engine: single impacts against closed-form rigid-body solutions.

Scenes: the benchmark deck (real mass and inertia) in free flight (bents of stiffness 1e-9
kN/m, no damping) towards seat 1, whose mass and inertia are made 1e12 (t, t·m²). The smooth
forces are then ~1e-13 of the impulses, so the step in which the corner(s) become active is a
pure impact: U_free = U⁻ and the post-impact velocity is the one of the planar impulse problem
with the 7-DOF mass matrix. The closed forms below are derived here independently of the
engine (hand-written contact rows for the linear kinematics).
"""

from __future__ import annotations

import contextlib
import itertools

import numpy as np
import pytest
from _compliance_helpers import (
    base_scene,
    rest_motion,
    with_bents,
    with_contact,
    with_run,
    with_seats,
)

from deckpound.analytic.nonsmooth.engine import run_nonsmooth

GAP = 0.05
H = 1.0e-4


def impact_scene(e: float, mu: float, duration: float, h: float = H, theta: float = 0.5):
    sc = base_scene("damping.ratio=0.0", f"nonsmooth.h={h!r}", f"nonsmooth.theta={theta!r}")
    sc = with_bents(sc, kx=1e-9, ky=1e-9)
    sc = with_seats(sc, mass=1e12, inertia=1e12, cx=0.0, ctheta=0.0, gap=GAP)
    sc = with_contact(sc, restitution=e, friction=mu, friction_mode="slip" if mu > 0 else "none")
    return with_run(sc, duration=duration, output_dt=h)


def run(sc, u0, v0, duration):
    with pytest.warns(UserWarning) if sc.contact.has_friction else contextlib.nullcontext():
        r = run_nonsmooth(sc, rest_motion(sc, duration), initial_state=(u0, v0))
    assert r.ok, r.meta["message"]
    return r


def mass_inverse(sc):
    s, d = sc.seats[0], sc.deck
    return np.diag(1.0 / np.array([s.mass, s.inertia, 1.0, 1.0, d.mass, d.mass, d.inertia]))


def left_rows(sc, yc):
    """Contact rows of a left-face corner at y = yc (linear kinematics, DOFs
    x1, th1, x2, th2, xd, yd, thd): g = g0 + (xd − yc thd) − (x1 − yc th1), U_T = ẏd + xc θ̇d."""
    xc = -0.5 * sc.deck.length
    wn = np.array([-1.0, yc, 0.0, 0.0, 1.0, 0.0, -yc])
    wt = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0, xc])
    return wn, wt


def closed_form_single(Minv, wn, wt, U, e, mu):
    """Newton + Coulomb impact at one point: the stick candidate, else the unique consistent
    slip direction. Returns (kind, P_N, P_T, U⁺)."""
    gNN, gTT, gNT = wn @ Minv @ wn, wt @ Minv @ wt, wn @ Minv @ wt
    uN, uT = wn @ U, wt @ U
    assert uN < 0
    qN = (1.0 + e) * uN
    det = gNN * gTT - gNT**2
    PN = -(gTT * qN - gNT * uT) / det
    PT = -(-gNT * qN + gNN * uT) / det
    if not (PN > 0 and abs(PT) <= mu * PN):
        sols = []
        for s in (1.0, -1.0):
            PN = -qN / (gNN - s * mu * gNT)
            uTp = uT + (gNT - s * mu * gTT) * PN
            if PN > 0 and s * uTp > 0:
                sols.append((PN, -s * mu * PN))
        assert len(sols) == 1
        (PN, PT), kind = sols[0], "slip"
    else:
        kind = "stick"
    return kind, PN, PT, U + Minv @ (wn * PN + wt * PT)


@pytest.mark.parametrize("e", [0.0, 0.6, 1.0])
def test_symmetric_frictionless_impact_rebounds_at_minus_e_v(e):
    v_in = 0.5
    T = 0.12  # impact at t ≈ 0.1 s, then free flight
    sc = impact_scene(e, 0.0, T)
    u0, v0 = np.zeros(7), np.zeros(7)
    v0[4] = -v_in
    r = run(sc, u0, v0, T)
    vf = np.array(r.meta["final_v"])
    # relative normal velocity of the face: exactly -e times the approach velocity
    wn, _ = left_rows(sc, 0.0)
    assert abs(wn @ vf - e * v_in) <= 1e-12 * v_in
    # the deck itself: -e v up to the seat/deck mass ratio (1.4e-10)
    assert vf[4] == pytest.approx(e * v_in, rel=0, abs=1e-9 * v_in)
    # no rotation, no transverse motion; equal impulses at c1, c2; nothing at seat 2
    assert np.max(np.abs(r["deck_theta"])) <= 1e-15 and abs(vf[6]) <= 1e-15
    assert np.max(np.abs(r["deck_y_abs"])) == 0.0
    p1, p2 = r["pn_c1"].sum(), r["pn_c2"].sum()
    assert p1 == pytest.approx(p2, rel=1e-12)
    m = sc.deck.mass
    assert p1 + p2 == pytest.approx((1.0 + e) * m * v_in, rel=1e-9)
    assert np.all(r["pn_c3"] == 0) and np.all(r["pn_c4"] == 0)
    assert r.meta["gap_closures"] == 2
    # the impact is one step (no persistent contact impulse): impulse in exactly one row
    assert np.count_nonzero(r["pn_c1"]) == 1
    # energy: impact loss = (1 - e^2) T_normal, balance closes
    dT = 0.5 * m * v_in**2 * (1.0 - e**2)
    assert r["energy_impact"][-1] == pytest.approx(dT, rel=1e-8)
    assert abs(r["energy_error"][-1]) <= 1e-12 * 0.5 * m * v_in**2


# (v0 = [.., xd, yd, thd]) sliding: large transverse velocity; sticking: small one
ECCENTRIC = {
    "slip": (np.array([-0.5, 1.0, 0.002]), 0.6, 0.1),
    "stick": (np.array([-0.5, 0.01, -0.001]), 0.6, 0.8),
    "stick_e0": (np.array([-0.4, -0.02, 0.0]), 0.0, 0.5),
}


@pytest.mark.parametrize("case", list(ECCENTRIC))
def test_eccentric_single_corner_impact_matches_closed_form(case):
    vd, e, mu = ECCENTRIC[case]
    th0 = 0.01  # c2 (y = +W/2) strikes, c1 stays open
    yc = 0.5 * base_scene().deck.width
    t_hit = (GAP - yc * th0) / abs(vd[0])
    T = round((t_hit + 0.005) / H) * H  # a little after the impact step
    sc = impact_scene(e, mu, T)
    u0, v0 = np.zeros(7), np.zeros(7)
    u0[6] = th0
    v0[4:] = vd
    r = run(sc, u0, v0, T)
    assert np.count_nonzero(r["pn_c2"]) == 1 and np.all(r["pn_c1"] == 0)
    wn, wt = left_rows(sc, yc)
    # pre-impact state: free flight with the initial velocity (forces ~1e-13 of impulses)
    kind, PN, PT, Up = closed_form_single(mass_inverse(sc), wn, wt, v0, e, mu)
    assert kind == case.split("_")[0]
    vf = np.array(r.meta["final_v"])
    scale = np.max(np.abs(v0))
    np.testing.assert_allclose(vf, Up, rtol=0, atol=1e-10 * scale)
    assert r["pn_c2"].sum() == pytest.approx(PN, rel=1e-10)
    assert r["pt_c2"].sum() == pytest.approx(PT, rel=1e-10, abs=1e-10 * PN)
    i = np.flatnonzero(r["pn_c2"])[0]
    assert r["state_c2"][i] == (1 if kind == "stick" else 2)
    assert r.meta["max_complementarity"] <= 1e-10 * scale
    assert r.meta["max_cone_residual"] <= 1e-10 * scale


def closed_form_face(Minv, rows, wt, U, e, mu):
    """Two corners of one face, shared tangent row: enumerate (corner closed?) × (stick,
    slip ±) and return every consistent (P_N (2,), total P_T, U⁺)."""
    uNm = np.array([w @ U for w in rows])
    found = []
    for closed in itertools.product([True, False], repeat=2):
        actv = [i for i in range(2) if closed[i]]
        if not actv:
            continue
        for mode in ("stick", 1.0, -1.0):
            cols = [rows[i] for i in actv]
            cols = cols + [wt] if mode == "stick" else [c - mode * mu * wt for c in cols]
            eqs = [rows[i] for i in actv] + ([wt] if mode == "stick" else [])
            A = np.array([[q @ Minv @ c for c in cols] for q in eqs])
            b = np.array(
                [-(1 + e) * uNm[i] for i in actv] + ([-(wt @ U)] if mode == "stick" else [])
            )
            x = np.linalg.solve(A, b)
            Pn = np.zeros(2)
            Pn[actv] = x[: len(actv)]
            Pt = x[-1] if mode == "stick" else -mode * mu * Pn.sum()
            Up = U + Minv @ (rows[0] * Pn[0] + rows[1] * Pn[1] + wt * Pt)
            ok = bool(np.all(Pn[actv] >= 0))
            for i in range(2):
                if not closed[i]:
                    ok &= rows[i] @ Up + e * uNm[i] >= 0
            ok &= abs(Pt) <= mu * Pn.sum() if mode == "stick" else mode * (wt @ Up) > 0
            if ok:
                found.append((Pn, Pt, Up))
    return found


@pytest.mark.parametrize(
    "vd,e,mu",
    [
        ((-0.5, 0.02, 0.0), 0.6, 0.5),  # stick
        ((-0.5, 0.6, 0.0), 0.6, 0.3),  # slip
        ((-0.5, -0.6, 0.0), 0.2, 0.3),  # slip, other way
        ((-0.5, 0.0, 0.0), 1.0, 0.4),
    ],
)  # no tangential motion
def test_face_impact_totals_match_closed_form(vd, e, mu):
    """Both corners of the left face strike together (θ = θ̇ = 0). The face's impulses and the
    post-impact velocities are unique; the per-corner split of the tangential impulse is not
    (both corners share one tangent row), so only its total is checked."""
    T = round((GAP / abs(vd[0]) + 0.005) / H) * H
    sc = impact_scene(e, mu, T)
    u0, v0 = np.zeros(7), np.zeros(7)
    v0[4:] = vd
    r = run(sc, u0, v0, T)
    yc = 0.5 * sc.deck.width
    rows = [left_rows(sc, -yc)[0], left_rows(sc, yc)[0]]
    wt = left_rows(sc, yc)[1]
    found = closed_form_face(mass_inverse(sc), rows, wt, v0, e, mu)
    assert found
    for f in found[1:]:
        np.testing.assert_allclose(f[2], found[0][2], rtol=1e-9, atol=1e-12)
    Pn, Pt, Up = found[0]
    vf = np.array(r.meta["final_v"])
    np.testing.assert_allclose(vf, Up, rtol=0, atol=1e-10 * 0.5)
    ptot = r["pn_c1"].sum() + r["pn_c2"].sum()
    assert ptot == pytest.approx(Pn.sum(), rel=1e-10)
    np.testing.assert_allclose(
        [r["pn_c1"].sum(), r["pn_c2"].sum()], Pn, rtol=0, atol=1e-10 * Pn.sum()
    )
    assert r["pt_c1"].sum() + r["pt_c2"].sum() == pytest.approx(Pt, rel=0, abs=1e-10 * Pn.sum())

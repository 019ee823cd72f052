"""Tests for deckpound.analytic.nonsmooth.frictional_contact (planar frictional impact
impulses on the velocity level)."""

import itertools

import numpy as np
import pytest
from _contact_helpers import (
    B_DECK,
    I_DECK,
    L_DECK,
    M_DECK,
    build,
    check_laws,
    corner_jacobian,
    kinetic,
    solve_for,
)

from deckpound.analytic.kernels.lcp import lcp_lemke
from deckpound.analytic.nonsmooth.contact_checks import (
    STATUS_ENUM,
    STATUS_FAILED,
    STATUS_LEMKE,
    STATUS_LEMKE_ST,
)
from deckpound.analytic.nonsmooth.frictional_contact import (
    CONTACT_OPEN,
    CONTACT_SLIP,
    CONTACT_STICK,
    MODE_ENUM,
    MODE_LEMKE_ST,
    delassus,
    solve_contact_impulses,
    solve_contact_impulses_into,
)

# -------------------------------------------------------------- (a) point mass


@pytest.mark.parametrize("e", [0.0, 0.3, 0.75, 1.0])
@pytest.mark.parametrize("mu", [0.0, 0.4])
def test_point_mass_newton_exact(e, mu):
    m = 3.7
    Mmat = np.diag([m, m])
    WN = np.array([[0.0], [1.0]])  # wall below, normal +y
    WT = np.array([[1.0], [0.0]])
    U = np.array([0.0, -2.3])
    r = solve_for(Mmat, WN, WT, U, [e], [mu])
    assert r["status"] == STATUS_LEMKE
    assert abs(r["uNp"][0] - (-e * -2.3)) <= 1e-15 * 2.3
    assert abs(r["PN"][0] - (1 + e) * m * 2.3) <= 1e-14 * m * 2.3
    assert abs(r["PT"][0]) <= 1e-15 * r["PN"][0]
    assert r["state"][0] == CONTACT_STICK  # P_N > 0 and U_T+ = 0
    np.testing.assert_allclose(r["Up"], [0.0, 2.3 * e], rtol=0, atol=1e-14)


def test_point_mass_separating_is_open():
    Mmat = np.diag([1.0, 1.0])
    WN = np.array([[0.0], [1.0]])
    WT = np.array([[1.0], [0.0]])
    r = solve_for(Mmat, WN, WT, np.array([0.5, 0.2]), [0.5], [0.3])
    assert r["status"] == STATUS_LEMKE
    assert r["PN"][0] == 0.0 and r["PT"][0] == 0.0
    assert r["state"][0] == CONTACT_OPEN


def test_point_mass_oblique_slip_and_stick():
    m = 2.0
    Mmat = np.diag([m, m])
    WN = np.array([[0.0], [1.0]])
    WT = np.array([[1.0], [0.0]])
    e, mu = 0.5, 0.3
    # slip: P_N = (1+e) m |v_y|, P_T = -mu P_N, v_x+ = v_x - mu (1+e) |v_y|
    r = solve_for(Mmat, WN, WT, np.array([2.0, -1.0]), [e], [mu])
    assert r["state"][0] == CONTACT_SLIP
    np.testing.assert_allclose(r["PT"][0], -mu * (1 + e) * m, rtol=1e-14)
    np.testing.assert_allclose(r["Up"], [2.0 - mu * 1.5, 0.5], rtol=1e-14)
    # stick: |v_x| small
    r = solve_for(Mmat, WN, WT, np.array([0.1, -1.0]), [e], [mu])
    assert r["state"][0] == CONTACT_STICK
    np.testing.assert_allclose(r["PT"][0], -0.1 * m, rtol=1e-14)
    np.testing.assert_allclose(r["Up"], [0.0, 0.5], atol=1e-15)


# ------------------------------------------------ (b) eccentric planar impact


def closed_form_single(m, I, r, n, U, e, mu):
    """Closed-form planar rigid-body impact at one point, Newton + Coulomb,
    U_free = U^-: stick candidate, else the consistent slip direction."""
    wn, wt = corner_jacobian(np.asarray(r, float), n)
    aN, aT = wn[2], wt[2]
    gNN = 1.0 / m + aN * aN / I
    gTT = 1.0 / m + aT * aT / I
    gNT = aN * aT / I
    uN = wn @ U
    uT = wt @ U
    assert uN < 0
    qN = (1.0 + e) * uN
    det = gNN * gTT - gNT * gNT
    PN = -(gTT * qN - gNT * uT) / det
    PT = -(-gNT * qN + gNN * uT) / det
    if PN > 0 and abs(PT) <= mu * PN:
        return "stick", PN, PT
    sols = []
    for s in (1.0, -1.0):
        den = gNN - s * mu * gNT
        PN = -qN / den
        uTp = uT + (gNT - s * mu * gTT) * PN
        if PN > 0 and s * uTp > 0:
            sols.append(("slip", PN, -s * mu * PN))
    assert len(sols) == 1
    return sols[0]


BODIES = [
    # (m, I, r, n, U-)
    (M_DECK, I_DECK, (L_DECK / 2, B_DECK / 2), (-1.0, 0.0), (0.8, 0.05, 0.001)),
    (M_DECK, I_DECK, (L_DECK / 2, B_DECK / 2), (-1.0, 0.0), (0.8, 0.6, -0.01)),
    (M_DECK, I_DECK, (L_DECK / 2, -B_DECK / 2), (-1.0, 0.0), (0.3, -0.4, 0.02)),
    (M_DECK, I_DECK, (-L_DECK / 2, B_DECK / 2), (0.0, -1.0), (0.1, 0.5, 0.0)),
    (2.0, 0.5, (0.7, -0.3), (np.cos(2.0), np.sin(2.0)), (0.5, -1.0, 0.3)),
    (2.0, 0.5, (0.7, -0.3), (np.cos(2.0), np.sin(2.0)), (2.0, -1.0, 0.3)),
]


@pytest.mark.parametrize("body", BODIES)
@pytest.mark.parametrize("e", [0.0, 0.6, 1.0])
@pytest.mark.parametrize("mu", [0.0, 0.2, 0.7])
def test_eccentric_impact_closed_form(body, e, mu):
    m, I, r, n, U = body
    U = np.asarray(U, float)
    Mmat = np.diag([m, m, I])
    WN, WT = build(Mmat, [(r, n)])
    res = solve_for(Mmat, WN, WT, U, [e], [mu])
    kind, PN, PT = closed_form_single(m, I, r, n, U, e, mu)
    assert res["status"] == STATUS_LEMKE
    Ps = abs(PN)
    assert abs(res["PN"][0] - PN) <= 1e-10 * Ps
    assert abs(res["PT"][0] - PT) <= 1e-10 * Ps
    if mu > 0:
        assert res["state"][0] == (CONTACT_STICK if kind == "stick" else CONTACT_SLIP)
    # post-impact velocity from the closed-form impulses
    wn, wt = corner_jacobian(np.asarray(r, float), n)
    Up = U + np.linalg.solve(Mmat, wn * PN + wt * PT)
    np.testing.assert_allclose(res["Up"], Up, rtol=0, atol=1e-10 * np.abs(U).max())
    assert abs(res["uNp"][0] + e * (wn @ U)) <= 1e-12 * np.abs(U).max()


def test_both_regimes_covered():
    kinds = set()
    for m, I, r, n, U in BODIES:
        kinds.add(closed_form_single(m, I, r, n, np.asarray(U, float), 0.6, 0.2)[0])
    assert kinds == {"stick", "slip"}


# ------------------------------------------------ (c) two corners of one face


def closed_form_face_pair(m, I, U, e, mu):
    """Deck end face x = +L/2 against an abutment (normal -x), corners
    (L/2, +-B/2) sharing one tangent column.  Enumerate (corner open/closed) x
    (stick, slip+, slip-) and return the consistent case: P_N (2,), total P_T,
    U+."""
    r = [(L_DECK / 2, B_DECK / 2), (L_DECK / 2, -B_DECK / 2)]
    n = (-1.0, 0.0)
    wn = [corner_jacobian(np.array(ri), n)[0] for ri in r]
    wt = corner_jacobian(np.array(r[0]), n)[1]
    assert np.allclose(wt, corner_jacobian(np.array(r[1]), n)[1])
    Minv = np.diag([1 / m, 1 / m, 1 / I])
    uNm = np.array([w @ U for w in wn])
    found = []
    for closed in itertools.product([True, False], repeat=2):
        act = [i for i in range(2) if closed[i]]
        if not act:
            continue
        for mode in ("stick", 1.0, -1.0):
            # unknowns: P_N (active), plus P_T total if stick
            cols = [wn[i] for i in act]
            if mode == "stick":
                cols = cols + [wt]
            else:
                cols = [c - mode * mu * wt for c in cols]
            C = np.array(cols).T  # generalised impulse per unknown
            rows = [wn[i] for i in act] + ([wt] if mode == "stick" else [])
            A = np.array([[rw @ Minv @ c for c in C.T] for rw in rows])
            b = np.array(
                [-(1 + e) * uNm[i] for i in act] + ([-(wt @ U)] if mode == "stick" else [])
            )
            x = np.linalg.solve(A, b)
            Pn = np.zeros(2)
            Pn[act] = x[: len(act)]
            Pt = x[-1] if mode == "stick" else -mode * mu * Pn.sum()
            Up = U + Minv @ (wn[0] * Pn[0] + wn[1] * Pn[1] + wt * Pt)
            ok = np.all(Pn[act] >= 0)
            for i in range(2):
                if not closed[i]:
                    ok &= wn[i] @ Up + e * uNm[i] >= 0
            if mode == "stick":
                ok &= abs(Pt) <= mu * Pn.sum()
            else:
                ok &= mode * (wt @ Up) > 0
            if ok:
                found.append((Pn, Pt, Up, mode))
    assert len(found) >= 1
    for f in found[1:]:  # the physical answer is unique
        np.testing.assert_allclose(f[2], found[0][2], rtol=1e-9, atol=1e-12)
    return found[0]


FACE_CASES = [
    ((0.5, 0.0, 0.0), 0.6, 0.5),  # equal approach, no tangential motion
    ((0.5, 0.02, 0.0), 0.6, 0.5),  # small tangential motion: stick
    ((0.5, 0.6, 0.0), 0.6, 0.3),  # large tangential motion: slip
    ((0.5, -0.6, 0.0), 0.2, 0.3),
    ((0.4, 0.1, 0.004), 0.5, 0.6),  # with rotation
    ((0.5, 0.0, 0.0), 1.0, 0.0),  # frictionless elastic
]


@pytest.mark.parametrize("case", FACE_CASES)
def test_face_pair_totals(case):
    U, e, mu = case
    U = np.asarray(U, float)
    Mmat = np.diag([M_DECK, M_DECK, I_DECK])
    contacts = [((L_DECK / 2, B_DECK / 2), (-1.0, 0.0)), ((L_DECK / 2, -B_DECK / 2), (-1.0, 0.0))]
    WN, WT = build(Mmat, contacts)
    G = delassus(Mmat, WN, WT)
    assert np.linalg.matrix_rank(G, tol=1e-12 * np.abs(G).max()) == 3  # singular
    res = solve_for(Mmat, WN, WT, U, [e, e], [mu, mu])
    assert res["status"] == STATUS_LEMKE
    Pn, Pt, Up, _ = closed_form_face_pair(M_DECK, I_DECK, U, e, mu)
    Ps = Pn.sum()
    np.testing.assert_allclose(res["PN"], Pn, rtol=0, atol=1e-10 * Ps)
    assert abs(res["PT"].sum() - Pt) <= 1e-10 * Ps
    np.testing.assert_allclose(res["Up"], Up, rtol=0, atol=1e-10 * np.abs(U).max())
    # canonical split: proportional to mu P_N, each within its cone
    if mu > 0:
        np.testing.assert_allclose(
            res["PT"], Pt * res["PN"] / res["PN"].sum(), rtol=0, atol=1e-10 * Ps
        )
    check_laws(res, [e, e], [mu, mu], 1e-9 * np.abs(U).max())
    if U[1] == 0.0 and U[2] == 0.0:
        np.testing.assert_allclose(res["PN"], 0.5 * (1 + e) * M_DECK * U[0], rtol=1e-12)
        np.testing.assert_allclose(res["Up"], [-e * U[0], 0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(
    "mode,status", [(MODE_LEMKE_ST, STATUS_LEMKE_ST), (MODE_ENUM, STATUS_ENUM)]
)
def test_face_pair_fallback_methods_agree(mode, status):
    Mmat = np.diag([M_DECK, M_DECK, I_DECK])
    contacts = [((L_DECK / 2, B_DECK / 2), (-1.0, 0.0)), ((L_DECK / 2, -B_DECK / 2), (-1.0, 0.0))]
    WN, WT = build(Mmat, contacts)
    for U, e, mu in FACE_CASES:
        U = np.asarray(U, float)
        ref = solve_for(Mmat, WN, WT, U, [e, e], [mu, mu])
        res = solve_for(Mmat, WN, WT, U, [e, e], [mu, mu], mode=mode)
        assert res["status"] == (status if mu > 0 or mode == MODE_ENUM else STATUS_LEMKE_ST)
        np.testing.assert_allclose(res["Up"], ref["Up"], rtol=0, atol=1e-10 * np.abs(U).max())
        assert abs(res["PT"].sum() - ref["PT"].sum()) <= 1e-10 * ref["PN"].sum()


def test_four_contacts_singular_delassus():
    """Abutment face (2 corners) + transverse shear keys at both ends on the
    3-DOF deck: 4 contacts, G (8x8) of rank 3; one corner carries two contacts
    whose tangent is the other's normal."""
    Mmat = np.diag([M_DECK, M_DECK, I_DECK])
    contacts = [
        ((L_DECK / 2, B_DECK / 2), (-1.0, 0.0)),
        ((L_DECK / 2, -B_DECK / 2), (-1.0, 0.0)),
        ((L_DECK / 2, B_DECK / 2), (0.0, -1.0)),
        ((-L_DECK / 2, B_DECK / 2), (0.0, -1.0)),
    ]
    WN, WT = build(Mmat, contacts)
    for U in ([1.0, 0.5, 0.02], [1.0, 0.05, 0.0], [0.3, 0.3, -0.01], [0.2, 1.0, 0.0]):
        U = np.asarray(U, float)
        for e, mu in ((0.0, 0.5), (0.6, 0.5), (1.0, 0.9), (0.4, 0.0)):
            res = solve_for(Mmat, WN, WT, U, [e] * 4, [mu] * 4)
            assert res["status"] in (STATUS_LEMKE, STATUS_LEMKE_ST, STATUS_ENUM)
            check_laws(res, [e] * 4, [mu] * 4, 1e-9 * np.abs(U).max())


def test_into_matches_wrapper_and_mu_zero_reduction():
    rng = np.random.default_rng(5)
    Mmat = np.diag([M_DECK, M_DECK, I_DECK])
    contacts = [
        ((L_DECK / 2, B_DECK / 2), (-1.0, 0.0)),
        ((L_DECK / 2, -B_DECK / 2), (-1.0, 0.0)),
        ((-L_DECK / 2, B_DECK / 2), (0.0, -1.0)),
    ]
    WN, WT = build(Mmat, contacts)
    G = delassus(Mmat, WN, WT)
    U = np.array([0.7, 0.4, 0.01])
    uN, uT = WN.T @ U, WT.T @ U
    e = rng.uniform(0, 1, 3)
    mu = np.array([0.3, 0.0, 0.5])
    ref = solve_contact_impulses(G, uN, uT, uN, e, mu, 0)
    PN, PT, a, b = (np.full(3, np.nan) for _ in range(4))
    state = np.full(3, -7, dtype=np.int64)
    status, comp, cone = solve_contact_impulses_into(
        G, uN, uT, uN, e, mu, PN, PT, a, b, state, 0, 1e-9
    )
    for x, y in zip((PN, PT, a, b, state), ref[:5]):
        np.testing.assert_array_equal(x, y)
    assert (status, comp, cone) == ref[5:]
    assert PT[1] == 0.0
    # mu = 0 everywhere: normal-only LCP G_NN P + uN + e uN- (n = nc)
    mu0 = np.zeros(3)
    res = solve_contact_impulses(G, uN, uT, uN, e, mu0, 0)
    z, _w, st_, _ = lcp_lemke(G[:3, :3].copy(), uN + e * uN)
    assert st_ == 0
    np.testing.assert_allclose(res[0], z, rtol=1e-12, atol=1e-12 * z.max())
    np.testing.assert_array_equal(res[1], 0.0)


def test_no_contacts():
    z = np.zeros(0)
    out = solve_contact_impulses(np.zeros((0, 0)), z, z, z, z, z, 0)
    assert out[5] == STATUS_LEMKE and out[0].shape == (0,)


# ---------------------------------------- documented limitations of the law


def test_wedge_newton_infeasible_reports_failure():
    """Point mass in a 90-degree corner, approaching both walls, mu1 mu2 > 1:
    with e > 0 Newton + Coulomb has no solution (self-locking wedge; solving
    the both-slip case gives P_N < 0, stick contradicts U_N+ = -e U_N- > 0).
    The solver must say so (status 3) and not crash; with e = 0 it solves."""
    Mmat = np.diag([1.0, 1.0])
    WN = np.array([[1.0, 0.0], [0.0, 1.0]])  # walls x = 0 and y = 0
    WT = np.array([[0.0, -1.0], [1.0, 0.0]])
    G = delassus(Mmat, WN, WT)
    U = np.array([-1.0, -0.7])
    uN, uT = WN.T @ U, WT.T @ U
    mu = np.array([1.5, 1.2])
    out = solve_contact_impulses(G, uN, uT, uN, np.array([0.5, 0.5]), mu, 0)
    assert out[5] == STATUS_FAILED
    assert max(out[6], out[7]) > 1e-3
    out = solve_contact_impulses(G, uN, uT, uN, np.zeros(2), mu, 0)
    assert out[5] == STATUS_LEMKE
    np.testing.assert_allclose(out[2:4], 0.0, atol=1e-15)


def test_kane_paradox_energy_gain_with_e_one():
    """Newton (e = 1) + Coulomb ending in stick at an eccentric corner can
    increase kinetic energy (Kane & Levinson 1985): a property of the impact
    law, reproduced here so nobody mistakes it for a solver bug."""
    m, I = M_DECK, I_DECK
    Mmat = np.diag([m, m, I])
    WN, WT = build(Mmat, [((L_DECK / 2, B_DECK / 2), (-1.0, 0.0))])
    U = np.array([1.0, -0.1, 0.0])
    res = solve_for(Mmat, WN, WT, U, [1.0], [0.5])
    assert res["status"] == STATUS_LEMKE and res["state"][0] == CONTACT_STICK
    assert kinetic(Mmat, res["Up"]) > kinetic(Mmat, U) * (1 + 1e-6)
    kind, PN, PT = closed_form_single(m, I, (L_DECK / 2, B_DECK / 2), (-1.0, 0.0), U, 1.0, 0.5)
    assert kind == "stick" and abs(res["PT"][0] - PT) <= 1e-10 * PN

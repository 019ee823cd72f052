"""Helpers of the frictional-contact tests: planar rigid deck, contact Jacobians, a solve
wrapper and a direct check of the contact laws (Newton impact, Coulomb friction)."""

from __future__ import annotations

import numpy as np

from deckpound.analytic.nonsmooth.frictional_contact import (
    CONTACT_SLIP,
    CONTACT_STICK,
    delassus,
    solve_contact_impulses,
    velocity_update,
)

# deck of the reference bridge: 33.5 m x 2.4 m in plan, 140.5 t, 13,090 t m^2
L_DECK, B_DECK = 33.5, 2.4
M_DECK, I_DECK = 140.5e3, 13.09e6


def corner_jacobian(r, n):
    """Jacobian rows of a point at r (body frame = global, theta = 0) of a
    planar rigid body with DOFs (x, y, theta): v_p = (vx - w r_y, vy + w r_x).
    Normal n points from the obstacle into the body; t = (-n_y, n_x)."""
    n = np.asarray(n, float)
    t = np.array([-n[1], n[0]])
    aN = -n[0] * r[1] + n[1] * r[0]
    aT = -t[0] * r[1] + t[1] * r[0]
    return np.array([n[0], n[1], aN]), np.array([t[0], t[1], aT])


def build(Mmat, contacts):
    nc = len(contacts)
    WN = np.zeros((Mmat.shape[0], nc))
    WT = np.zeros((Mmat.shape[0], nc))
    for j, (r, n) in enumerate(contacts):
        wn, wt = corner_jacobian(np.asarray(r, float), n)
        WN[:3, j] = wn
        WT[:3, j] = wt
    return WN, WT


def solve_for(Mmat, WN, WT, U_minus, e, mu, U_free=None, mode=0):
    if U_free is None:
        U_free = U_minus
    G = delassus(Mmat, WN, WT)
    uNf = WN.T @ U_free
    uTf = WT.T @ U_free
    uNm = WN.T @ U_minus
    out = solve_contact_impulses(
        G, uNf, uTf, uNm, np.asarray(e, float), np.asarray(mu, float), mode
    )
    PN, PT, uNp, uTp, state, status, comp, cone = out
    Up = velocity_update(Mmat, WN, WT, U_free, PN, PT)
    return dict(
        PN=PN,
        PT=PT,
        uNp=uNp,
        uTp=uTp,
        state=state,
        status=status,
        comp=comp,
        cone=cone,
        Up=Up,
        G=G,
        uNm=uNm,
        uNf=uNf,
        uTf=uTf,
    )


def check_laws(res, e, mu, tol):
    """Contact laws checked directly on the returned quantities."""
    PN, PT, uNp, uTp = res["PN"], res["PT"], res["uNp"], res["uTp"]
    e = np.asarray(e, float)
    mu = np.asarray(mu, float)
    Pscale = tol / max(np.diag(res["G"]).max(), 1e-300)
    xi = uNp + e * res["uNm"]
    assert np.all(-Pscale <= PN)
    assert np.all(xi >= -tol)
    # complementarity: xi_N = 0 or P_N = 0 at every contact
    assert np.all(np.minimum(np.abs(xi) / tol, np.abs(PN) / Pscale) <= 1.0)
    assert np.all(np.abs(PT) <= mu * PN + Pscale)
    for i in range(len(PN)):
        if res["state"][i] == CONTACT_SLIP and mu[i] > 0:
            # slip opposite to the friction impulse, friction saturated
            assert PT[i] * uTp[i] < 0.0
            assert abs(abs(PT[i]) - mu[i] * PN[i]) <= Pscale
        if res["state"][i] == CONTACT_STICK:
            assert abs(uTp[i]) <= tol
        if PN[i] > Pscale and abs(uTp[i]) > tol and mu[i] > 0:
            assert res["state"][i] == CONTACT_SLIP
    # velocities consistent with the generalised update
    G = res["G"]
    nc = len(PN)
    np.testing.assert_allclose(
        uNp, res["uNf"] + G[:nc, :nc] @ PN + G[:nc, nc:] @ PT, rtol=0, atol=tol
    )
    assert res["comp"] <= tol and res["cone"] <= tol


def kinetic(Mmat, U):
    return 0.5 * U @ Mmat @ U

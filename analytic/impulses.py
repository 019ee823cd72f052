"""The contact impulses of one Moreau–Jean step (:mod:`deckpound.analytic.moreau_jean`).

Given the factors of the step's iteration matrix Ŵ = M + θhC + θ²h²K_t, the rows W_N, W_T of
the active corners, the free velocity v_free and the start-of-step velocity v_k, build the
Delassus matrix G = W Ŵ⁻¹ Wᵀ and the free contact velocities W v_free, solve the planar
frictional impact problem of :mod:`deckpound.analytic.frictional_contact` (Newton impact,
set-valued Coulomb friction) and update the velocity v = v_free + Ŵ⁻¹ Wᵀ P.

This is the one part of the nonsmooth step loop that allocates (its LCP sizes depend on the
number of active corners), so it keeps numba's runtime (``_nrt=True``) even when called from a
kernel compiled without it (:mod:`deckpound.analytic._jit`).
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic._jit import compiled
from deckpound.analytic.dense import lu_solve
from deckpound.analytic.frictional_contact import solve_contact_impulses_into

__all__ = ["solve_active_impulses"]


@compiled(_nrt=True)  # allocates: keeps numba's runtime when called from a kernel
def solve_active_impulses(
    LU, piv, WN, WT, act, nact, v0, vfree, ecoef, esep, mu, mode, rtol, P_N, P_T, state, vnew
):
    """Solve the frictional impact problem of the active corners act[:nact].

    G = W Ŵ⁻¹ Wᵀ, u_free = W v_free, U_N⁻ = W_N v0; vnew = v_free + Ŵ⁻¹ Wᵀ P. Restitution
    ``ecoef`` for approaching corners (U_N⁻ ≤ 0), ``esep`` for separating ones.
    P_N, P_T, state (4,) are written per corner (zero / open for inactive corners).
    Returns (status, comp_res, cone_res).
    """
    nc = nact
    X = np.empty((2 * nc, 7))  # rows: Ŵ⁻¹ w for each column w of W
    Wr = np.empty((2 * nc, 7))
    col = np.empty(7)
    for a in range(nc):
        c = act[a]
        for j in range(7):
            Wr[a, j] = WN[c, j]
            Wr[nc + a, j] = WT[c, j]
    for r in range(2 * nc):
        for j in range(7):
            col[j] = Wr[r, j]
        lu_solve(LU, piv, col, col)
        for j in range(7):
            X[r, j] = col[j]
    G = np.empty((2 * nc, 2 * nc))
    for r in range(2 * nc):
        for s in range(r, 2 * nc):
            acc = 0.0
            for j in range(7):
                acc += Wr[r, j] * X[s, j]
            G[r, s] = acc
            G[s, r] = acc
    uNf = np.empty(nc)
    uTf = np.empty(nc)
    uNm = np.empty(nc)
    ea = np.empty(nc)
    ma = np.empty(nc)
    for a in range(nc):
        sN = 0.0
        sT = 0.0
        sm = 0.0
        for j in range(7):
            sN += Wr[a, j] * vfree[j]
            sT += Wr[nc + a, j] * vfree[j]
            sm += Wr[a, j] * v0[j]
        uNf[a] = sN
        uTf[a] = sT
        uNm[a] = sm
        ea[a] = ecoef if sm <= 0.0 else esep
        ma[a] = mu
    pN = np.zeros(nc)
    pT = np.zeros(nc)
    uNp = np.zeros(nc)
    uTp = np.zeros(nc)
    st = np.zeros(nc, dtype=np.int64)
    status, comp, cone = solve_contact_impulses_into(
        G, uNf, uTf, uNm, ea, ma, pN, pT, uNp, uTp, st, mode, rtol
    )
    for c in range(4):
        P_N[c] = 0.0
        P_T[c] = 0.0
        state[c] = 0
    for j in range(7):
        vnew[j] = vfree[j]
    for a in range(nc):
        c = act[a]
        P_N[c] = pN[a]
        P_T[c] = pT[a]
        state[c] = st[a]
        for j in range(7):
            vnew[j] += X[a, j] * pN[a] + X[nc + a, j] * pT[a]
    return status, comp, cone

"""The contact impulses of one Moreau–Jean step (:mod:`deckpound.analytic.nonsmooth.moreau_jean`).

Given the factors of the step's iteration matrix Ŵ = M + θhC + θ²h²K_t, the rows W_N, W_T of
the active corners, the free velocity v_free and the start-of-step velocity v_k, build the
Delassus matrix G = W Ŵ⁻¹ Wᵀ and the free contact velocities W v_free, solve the planar
frictional impact problem of :mod:`deckpound.analytic.nonsmooth.frictional_contact` (Newton impact,
set-valued Coulomb friction) and update the velocity v = v_free + Ŵ⁻¹ Wᵀ P.

The LCP sizes depend on the number of active corners; every array the solve needs is a view
of the :data:`ImpulseWork` allocated once per run (:func:`impulse_work`, sized for every
corner of the model), so the step loop's contact solve allocates nothing and runs without numba's runtime
(:mod:`deckpound.analytic._jit`): before, its ~40 small allocations per solve and their
reference counting were about a sixth of the nonsmooth engine's loop time on the benchmark.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from deckpound.analytic._jit import kernel
from deckpound.analytic.kernels.dense import lu_solve
from deckpound.analytic.kernels.size_tags import dof_slots
from deckpound.analytic.nonsmooth.frictional_contact import (
    contact_solve_work,
    solve_contact_impulses_with,
)

__all__ = ["ImpulseWork", "impulse_work", "size_tag", "solve_active_impulses"]

#: Scratch of :func:`solve_active_impulses` for up to nc active corners and n_dof DOFs: X, Wr
#: (2nc, n_dof) rows Ŵ⁻¹ w and w of W = [W_N; W_T]; G (2nc, 2nc) Delassus matrix;
#: per corner (nc,) uNf, uTf free contact velocities, uNm pre-impact normal velocity, ea, ma
#: restitution and friction, pN, pT impulses, uNp, uTp post-impact velocities, st int64 states;
#: ``contact`` the frictional solve's scratch (:data:`.frictional_contact.ContactSolveWork`);
#: ``dof_slots`` the size tag of n_dof (:func:`size_tag`).
ImpulseWork = namedtuple(
    "ImpulseWork",
    [
        "X",
        "Wr",
        "G",
        "uNf",
        "uTf",
        "uNm",
        "ea",
        "ma",
        "pN",
        "pT",
        "uNp",
        "uTp",
        "st",
        "contact",
        "dof_slots",
    ],
)


def size_tag(n: int) -> tuple:
    """A size as a compile-time constant of the kernels: a tuple of ``n`` zeros, whose length
    is part of its numba type (``UniTuple(int64, n)``), so ``len(tag)`` in a kernel is a
    constant. A kernel given the tag is compiled once per size; its loops over that size then
    have a fixed trip count that LLVM unrolls, as it did for the former module constants
    (N_DOF, N_CORNERS), instead of a count read from an array's shape at run time."""
    return (0,) * int(n)


def impulse_work(n_corners: int, n_dof: int) -> ImpulseWork:
    """The scratch of :func:`solve_active_impulses` for up to ``n_corners`` active corners of
    a model with ``n_dof`` DOFs."""
    nc = int(n_corners)
    nd = int(n_dof)
    per_corner = {
        k: np.zeros(nc) for k in ("uNf", "uTf", "uNm", "ea", "ma", "pN", "pT", "uNp", "uTp")
    }
    return ImpulseWork(
        X=np.zeros((2 * nc, nd)),
        Wr=np.zeros((2 * nc, nd)),
        G=np.zeros((2 * nc, 2 * nc)),
        st=np.zeros(nc, dtype=np.int64),
        contact=contact_solve_work(nc),
        dof_slots=dof_slots(nd),
        **per_corner,
    )


@kernel
def solve_active_impulses(
    LU, piv, WN, WT, act, nact, v0, vfree, ecoef, esep, mu, mode, rtol, P_N, P_T, state, vnew, work
):
    """Solve the frictional impact problem of the active corners act[:nact].

    G = W Ŵ⁻¹ Wᵀ, u_free = W v_free, U_N⁻ = W_N v0; vnew = v_free + Ŵ⁻¹ Wᵀ P. Per corner
    (n_corners,): restitution ``ecoef`` where it approaches (U_N⁻ ≤ 0), ``esep`` where it
    separates, friction coefficient ``mu`` (each corner's contact table: a joint's may differ
    from the abutments').
    P_N, P_T, state (n_corners,) are written per corner (zero / open for inactive corners);
    the DOF count is the size tag ``work.dof_slots``, the corner count P_N's length.
    ``work``: the :data:`ImpulseWork` (:func:`impulse_work`). Returns (status, comp_res,
    cone_res).
    """
    nc = nact
    n_dof = len(work.dof_slots)
    X = work.X[: 2 * nc]  # rows: Ŵ⁻¹ w for each column w of W
    Wr = work.Wr[: 2 * nc]
    for a in range(nc):
        c = act[a]
        for j in range(n_dof):
            Wr[a, j] = WN[c, j]
            Wr[nc + a, j] = WT[c, j]
    for r in range(2 * nc):
        lu_solve(LU, piv, Wr[r], X[r], work.dof_slots)
    G = work.G[: 2 * nc, : 2 * nc]
    for r in range(2 * nc):
        for s in range(r, 2 * nc):
            acc = 0.0
            for j in range(n_dof):
                acc += Wr[r, j] * X[s, j]
            G[r, s] = acc
            G[s, r] = acc
    uNf = work.uNf[:nc]
    uTf = work.uTf[:nc]
    uNm = work.uNm[:nc]
    ea = work.ea[:nc]
    ma = work.ma[:nc]
    for a in range(nc):
        sN = 0.0
        sT = 0.0
        sm = 0.0
        for j in range(n_dof):
            sN += Wr[a, j] * vfree[j]
            sT += Wr[nc + a, j] * vfree[j]
            sm += Wr[a, j] * v0[j]
        uNf[a] = sN
        uTf[a] = sT
        uNm[a] = sm
        c = act[a]
        ea[a] = ecoef[c] if sm <= 0.0 else esep[c]
        ma[a] = mu[c]
    pN = work.pN[:nc]
    pT = work.pT[:nc]
    uNp = work.uNp[:nc]
    uTp = work.uTp[:nc]
    st = work.st[:nc]  # outputs: the solve writes every entry
    status, comp, cone = solve_contact_impulses_with(
        G, uNf, uTf, uNm, ea, ma, pN, pT, uNp, uTp, st, mode, rtol, work.contact
    )
    for c in range(P_N.shape[0]):
        P_N[c] = 0.0
        P_T[c] = 0.0
        state[c] = 0
    for j in range(n_dof):
        vnew[j] = vfree[j]
    for a in range(nc):
        c = act[a]
        P_N[c] = pN[a]
        P_T[c] = pT[a]
        state[c] = st[a]
        for j in range(n_dof):
            vnew[j] += X[a, j] * pN[a] + X[nc + a, j] * pT[a]
    return status, comp, cone

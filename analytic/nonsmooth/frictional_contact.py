r"""Planar frictional impact / contact impulses on the velocity level (numba).

This is the one-step contact solve of deckpound's Moreau-Jean engine: for the
``nc`` (<= 4 in practice, any nc works) active contacts of a time step, find
the normal and tangential impulses.

Equations
---------
Generalised velocities U (deck: x, y, theta, plus extra DOFs), iteration
matrix M (mass matrix, or the Moreau-Jean iteration matrix
M + theta h C + theta^2 h^2 K; any invertible matrix), contact Jacobians
W_N, W_T of shape (ndof, nc)::

    M (U+ - U_free) = W_N P_N + W_T P_T
    U_N+ = W_N^T U+ + b_N ,   U_T+ = W_T^T U+ + b_T        (b: moving supports)

With the Delassus matrix G = W^T M^-1 W, W = [W_N  W_T] (shape (2nc, 2nc),
rows/columns ordered N_0..N_{nc-1}, T_0..T_{nc-1}) and the *free* contact
velocities u_free = W^T U_free + b (what the contact velocities would be
without contact impulses)::

    U_N+ = uN_free + G_NN P_N + G_NT P_T
    U_T+ = uT_free + G_TN P_N + G_TT P_T

Contact laws, per contact i:

* Newton impact:  xi_N = U_N+ + e U_N-  >= 0,  P_N >= 0,  xi_N P_N = 0,
  with U_N- the pre-impact normal velocity and e in [0, 1].
* Planar Coulomb: -U_T+ in mu P_N d|P_T|, i.e. |P_T| <= mu P_N, U_T+ = 0 if
  |P_T| < mu P_N (stick), and U_T+ = -s |U_T+| when P_T = s mu P_N (slip
  opposite to the friction impulse).

Sign conventions: U_N > 0 separates, U_N < 0 approaches; P_N >= 0 pushes the
bodies apart along the W_N column.  P_T and U_T are both measured along the
same tangent t (the W_T column): P_T > 0 is a friction impulse along +t,
U_T > 0 is slip along +t, so in slip P_T * U_T+ < 0.

Solution (the LCP forms are written out in :mod:`deckpound.analytic.nonsmooth.coulomb_lcp`)
-----------------------------------------------------------------------------------
1. Lemke on the 3-unknown LCP (P_N, P_R = mu P_N + P_T, v-) of Glocker & Pfeiffer
   (status 0 when it verifies); its matrix is not copositive in general, so
2. Lemke on the Stewart-Trinkle / Anitescu-Potra form (P_N, beta+, beta-,
   lambda), copositive for symmetric PSD G (status 1);
3. exhaustive enumeration of the 3-unknown LCP (n <= 12), status 2.

Every candidate is verified against the contact laws directly (velocities
recomputed from G); status 3 means no candidate verified and the best one is
returned.  Returned residuals, both in velocity units:

* comp_res = max_i |min(xi_N,i , G_NN,ii P_N,i)|  (Signorini-Newton
  complementarity; also measures P_N < 0 and xi_N < 0);
* ``cone_res = max_i |g P_T,i - proj_[-g mu P_N,i , g mu P_N,i](g P_T,i - U_T+,i)|``
  with g = G_TT,ii: the natural-map residual of the Coulomb law, zero iff
  |P_T| <= mu P_N and -U_T+ is in the normal cone of the friction interval.

Non-uniqueness (documented, and tested): when two corners of one deck face
are in contact their tangent columns in W_T coincide (same tangent, same
lever arm along the face normal), G is singular (e.g. 4 corners on a 3-DOF
deck) and the split of the tangential impulse between the corners is not
unique; the split of normal impulses can also be non-unique for 4 contacts
on 3 DOFs.  The face totals sum(P_T), the generalised impulse W P, hence U+
and all contact velocities, are unique whenever W_N P_N + W_T P_T is
determined (the case for one deck face on one abutment).  Lemke returns one
valid vertex solution; do not post-process individual corner tangential
impulses, use face totals.  For contacts with identical tangent columns the
solver returns the canonical split P_T,i = (sum P_T) mu_i P_N,i /
sum(mu_j P_N,j), which preserves the cone, the velocities and the totals.

Energy: with U_free = U- and e = 0, or with mu = 0 and U_N- <= 0, the impact
does not increase the kinetic energy.  With friction and e > 0 Newton's law
combined with Coulomb friction is *not* energetically consistent in general
(Kane's paradox: an eccentric impact with large mu that ends in stick can
gain energy, Kane & Levinson 1985, Glocker 2004).  This is a property of the
impact law, not of the solver.

References
----------
C. Glocker, F. Pfeiffer, "Dynamical systems with unilateral contacts",
    Nonlinear Dynamics 3 (1992) 245-259; F. Pfeiffer, C. Glocker,
    "Multibody Dynamics with Unilateral Contacts", Wiley 1996.
R. I. Leine, H. Nijmeijer, "Dynamics and Bifurcations of Non-Smooth
    Mechanical Systems", Springer 2004, Ch. 7.
V. Acary, B. Brogliato, "Numerical Methods for Nonsmooth Dynamical Systems",
    Springer 2008, Ch. 10 and 12.
D. E. Stewart, J. C. Trinkle, "An implicit time-stepping scheme for rigid
    body dynamics with inelastic collisions and Coulomb friction", IJNME 39
    (1996); M. Anitescu, F. A. Potra, "Formulating dynamic multi-rigid-body
    contact problems with friction as solvable linear complementarity
    problems", Nonlinear Dynamics 14 (1997) 231-247.
C. Glocker, "Concepts for modeling impacts without friction", Acta Mech.
    168 (2004) 1-19.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from deckpound.analytic._jit import compiled, kernel
from deckpound.analytic.kernels.lcp import ENUM_MAX_N, lcp_enumerate_into, lcp_lemke_into, lcp_work
from deckpound.analytic.nonsmooth.contact_checks import (
    STATUS_ENUM,
    STATUS_FAILED,
    STATUS_LEMKE,
    STATUS_LEMKE_ST,
    contact_velocities,
    evaluate_candidate,
    impulse_scale,
    keep_if_better,
    split_shared_tangents,
)
from deckpound.analytic.nonsmooth.coulomb_lcp import (
    build_lcp3_into,
    build_lcp_st_into,
    extract3,
    extract_st,
)

__all__ = [
    "CONTACT_OPEN",
    "CONTACT_SLIP",
    "CONTACT_STICK",
    "MODE_AUTO",
    "MODE_ENUM",
    "MODE_LEMKE3",
    "MODE_LEMKE_ST",
    "ContactSolveWork",
    "contact_solve_work",
    "delassus",
    "solve_contact_impulses",
    "solve_contact_impulses_into",
    "solve_contact_impulses_with",
    "velocity_update",
]

CONTACT_OPEN = 0
CONTACT_STICK = 1
CONTACT_SLIP = 2


MODE_AUTO = 0
MODE_LEMKE3 = 1
MODE_LEMKE_ST = 2
MODE_ENUM = 3

_VTOL = 1e-9  # default relative acceptance tolerance (velocity units)


@compiled
def delassus(M, W_N, W_T):
    """G = W^T M^-1 W with W = [W_N  W_T]; M (ndof, ndof) invertible,
    W_N, W_T (ndof, nc).  Returns G (2nc, 2nc), order N_0..N_{nc-1},
    T_0..T_{nc-1}."""
    ndof, nc = W_N.shape
    W = np.empty((ndof, 2 * nc))
    W[:, :nc] = W_N
    W[:, nc:] = W_T
    X = np.linalg.solve(np.ascontiguousarray(M), W)
    return W.T @ X


@compiled
def velocity_update(M, W_N, W_T, U_free, P_N, P_T):
    """U+ = U_free + M^-1 (W_N P_N + W_T P_T)."""
    r = W_N @ P_N + W_T @ P_T
    return U_free + np.linalg.solve(np.ascontiguousarray(M), r)


#: Scratch of :func:`solve_contact_impulses_with` for up to nc contacts
#: (:func:`contact_solve_work`): per contact (nc,) qN, bN, bT, cN, cT, vN, vT float and fidx,
#: group int64; best (4,); the LCPs A3 (3nc, 3nc), q3 (3nc,), Ast (4nc, 4nc), qst (4nc,), their
#: solution z, w (4nc,) and the LCP solvers' scratch ``lcp`` (:data:`.lcp.LcpWork`, size 4nc).
ContactSolveWork = namedtuple(
    "ContactSolveWork",
    [
        "qN",
        "bN",
        "bT",
        "cN",
        "cT",
        "vN",
        "vT",
        "fidx",
        "group",
        "best",
        "A3",
        "q3",
        "Ast",
        "qst",
        "z",
        "w",
        "lcp",
    ],
)


def contact_solve_work(nc):
    """The scratch of :func:`solve_contact_impulses_with` for up to ``nc`` contacts (zeroed;
    plain Python, see :func:`deckpound.analytic.kernels.lcp.lcp_work`)."""
    n3 = 3 * nc
    nst = 4 * nc
    return ContactSolveWork(
        np.zeros(nc),
        np.zeros(nc),
        np.zeros(nc),
        np.zeros(nc),
        np.zeros(nc),
        np.zeros(nc),
        np.zeros(nc),
        np.zeros(nc, dtype=np.int64),
        np.zeros(nc, dtype=np.int64),
        np.zeros(4),
        np.zeros((n3, n3)),
        np.zeros(n3),
        np.zeros((nst, nst)),
        np.zeros(nst),
        np.zeros(nst),
        np.zeros(nst),
        lcp_work(nst),
    )


def solve_contact_impulses_into(
    G, uN_free, uT_free, uN_minus, e, mu, P_N, P_T, uN_plus, uT_plus, state, mode=0, rtol=1e-9
):
    """Frictional impact impulses for nc active contacts, written into the
    output arrays.

    Parameters
    ----------
    G : (2nc, 2nc) Delassus matrix W^T M^-1 W, order [N_0..N_nc-1, T_0..].
    uN_free, uT_free : (nc,) contact velocities of the contact-free motion
        (including moving-support offsets b_N, b_T).
    uN_minus : (nc,) pre-impact normal velocities U_N- (Newton law target
        U_N+ >= -e U_N-).
    e, mu : (nc,) restitution in [0, 1] and friction coefficient >= 0.
    P_N, P_T, uN_plus, uT_plus : (nc,) float64 outputs.
    state : (nc,) int64 output, 0 open, 1 stick, 2 slip.
    mode : 0 auto (3-unknown Lemke -> Stewart-Trinkle Lemke -> enumeration),
        1 / 2 / 3 force one method (testing).
    rtol : acceptance tolerance relative to the velocity scale
        max(|uN_free|, |uT_free|, |e uN_minus|).

    Returns
    -------
    (status, comp_res, cone_res): status 0/1/2 verified (by method 3-unknown
    Lemke / Stewart-Trinkle Lemke / enumeration), 3 failed (best candidate
    returned); residuals in velocity units.

    Allocates its scratch (:func:`contact_solve_work`) and calls
    :func:`solve_contact_impulses_with`, which a step loop calls with a preallocated one.
    """
    return solve_contact_impulses_with(
        G,
        uN_free,
        uT_free,
        uN_minus,
        e,
        mu,
        P_N,
        P_T,
        uN_plus,
        uT_plus,
        state,
        mode,
        rtol,
        contact_solve_work(uN_free.shape[0]),
    )


@kernel
def solve_contact_impulses_with(
    G, uN_free, uT_free, uN_minus, e, mu, P_N, P_T, uN_plus, uT_plus, state, mode, rtol, work
):
    """:func:`solve_contact_impulses_into` with its scratch ``work``
    (:func:`contact_solve_work` for ≥ nc contacts): no allocation."""
    nc = uN_free.shape[0]
    if nc == 0:
        return STATUS_LEMKE, 0.0, 0.0
    vscale = 0.0
    for i in range(nc):
        vscale = max(vscale, abs(uN_free[i]), abs(uT_free[i]), abs(e[i] * uN_minus[i]))
    tolv = rtol * vscale
    if vscale == 0.0:
        tolv = 1e-300
    s = impulse_scale(G, nc)
    qN = work.qN[:nc]
    for i in range(nc):
        qN[i] = uN_free[i] + e[i] * uN_minus[i]
    fidx = work.fidx[:nc]
    nf = 0
    for i in range(nc):
        if mu[i] > 0.0:
            fidx[nf] = i
            nf += 1

    bN = work.bN[:nc]
    bT = work.bT[:nc]
    for i in range(nc):
        bN[i] = 0.0
        bT[i] = 0.0
    cN = work.cN[:nc]
    cT = work.cT[:nc]
    vN = work.vN[:nc]
    vT = work.vT[:nc]
    best = work.best  # residual, comp, cone, status
    best[0] = np.inf
    best[1] = np.inf
    best[2] = np.inf
    best[3] = STATUS_FAILED
    done = False

    # 1. Lemke, 3-unknown formulation
    n3 = nc + 2 * nf
    A3 = work.A3[:n3, :n3]
    q3 = work.q3[:n3]
    build_lcp3_into(G, qN, uT_free, mu, fidx, nf, s, A3, q3)
    z = work.z[:n3]
    w = work.w[:n3]
    if mode in (MODE_AUTO, MODE_LEMKE3):
        lcp_lemke_into(A3, q3, z, w, work.lcp, 0, 1e-12)
        extract3(z, mu, fidx, nf, s, cN, cT)
        done = keep_if_better(
            G, uN_free, uT_free, uN_minus, e, mu, cN, cT, vN, vT, bN, bT, best, STATUS_LEMKE, tolv
        )
    # 2. Lemke, Stewart-Trinkle formulation (copositive); frictionless, the ST form is the
    # normal LCP (asked for explicitly with MODE_LEMKE_ST)
    with_friction = (not done) and nf > 0 and (mode in (MODE_AUTO, MODE_LEMKE_ST))
    if with_friction or (mode == MODE_LEMKE_ST and nf == 0):
        if with_friction:
            nst = nc + 3 * nf
            Ast = work.Ast[:nst, :nst]
            qst = work.qst[:nst]
            build_lcp_st_into(G, qN, uT_free, mu, fidx, nf, s, Ast, qst)
            zst = work.z[:nst]
            lcp_lemke_into(Ast, qst, zst, work.w[:nst], work.lcp, 0, 1e-12)
            extract_st(zst, fidx, nf, s, cN, cT)
        else:
            lcp_lemke_into(A3, q3, z, w, work.lcp, 0, 1e-12)
            extract3(z, mu, fidx, nf, s, cN, cT)
        done = keep_if_better(
            G,
            uN_free,
            uT_free,
            uN_minus,
            e,
            mu,
            cN,
            cT,
            vN,
            vT,
            bN,
            bT,
            best,
            STATUS_LEMKE_ST,
            tolv,
        )
    # 3. enumeration of the 3-unknown LCP
    if (not done) and (mode in (MODE_AUTO, MODE_ENUM)) and nc + 2 * nf <= ENUM_MAX_N:
        lcp_enumerate_into(A3, q3, z, w, work.lcp, 1e-10)
        extract3(z, mu, fidx, nf, s, cN, cT)
        keep_if_better(
            G, uN_free, uT_free, uN_minus, e, mu, cN, cT, vN, vT, bN, bT, best, STATUS_ENUM, tolv
        )
    best_comp, best_cone = _canonical_split(
        G, uN_free, uT_free, uN_minus, e, mu, nf, tolv, work, cN, cT, vN, vT, bN, bT
    )
    _contact_outputs(
        G, uN_free, uT_free, bN, bT, P_N, P_T, uN_plus, uT_plus, state, rtol, s, vscale, tolv
    )
    return int(best[3]), best_comp, best_cone


@kernel(inline="always")
def _canonical_split(G, uN_free, uT_free, uN_minus, e, mu, nf, tolv, work, cN, cT, vN, vT, bN, bT):
    """Canonical split of the tangential impulses among contacts with identical tangent
    columns (two corners of one face), kept when it verifies at least as well as the best
    candidate (bN, bT; residuals in ``work.best``). Returns the (comp, cone) residuals of the
    result."""
    best = work.best
    best_comp = best[1]
    best_cone = best[2]
    if nf <= 1:
        return best_comp, best_cone
    nc = uN_free.shape[0]
    for i in range(nc):
        cN[i] = bN[i]
        cT[i] = bT[i]
    if split_shared_tangents(G, mu, cN, cT, work.group):
        comp, cone = evaluate_candidate(G, uN_free, uT_free, uN_minus, e, mu, cN, cT, vN, vT)
        if max(comp, cone) <= max(best[0], tolv):
            for i in range(nc):
                bT[i] = cT[i]
            best_comp = comp
            best_cone = cone
    return best_comp, best_cone


@kernel(inline="always")
def _contact_outputs(
    G, uN_free, uT_free, bN, bT, P_N, P_T, uN_plus, uT_plus, state, rtol, s, vscale, tolv
):
    """The impulses bN, bT into P_N, P_T, the post-impact contact velocities and the contact
    states (open when P_N ≤ rtol·s·vscale, stick when |U_T+| ≤ tolv, else slip)."""
    nc = uN_free.shape[0]
    for i in range(nc):
        P_N[i] = bN[i]
        P_T[i] = bT[i]
    contact_velocities(G, uN_free, uT_free, P_N, P_T, uN_plus, uT_plus)
    ptol = rtol * s * vscale
    for i in range(nc):
        if P_N[i] <= ptol:
            state[i] = CONTACT_OPEN
        elif abs(uT_plus[i]) <= tolv:
            state[i] = CONTACT_STICK
        else:
            state[i] = CONTACT_SLIP


def solve_contact_impulses(G, uN_free, uT_free, uN_minus, e, mu, mode=0, rtol=1e-9):
    """Allocating wrapper of :func:`solve_contact_impulses_into`.

    Returns ``(P_N, P_T, uN_plus, uT_plus, state, status, comp_res,
    cone_res)``; arrays of shape (nc,), state int64.
    """
    nc = uN_free.shape[0]
    P_N = np.zeros(nc)
    P_T = np.zeros(nc)
    uN_plus = np.zeros(nc)
    uT_plus = np.zeros(nc)
    state = np.zeros(nc, dtype=np.int64)
    status, comp, cone = solve_contact_impulses_into(
        G, uN_free, uT_free, uN_minus, e, mu, P_N, P_T, uN_plus, uT_plus, state, mode, rtol
    )
    return P_N, P_T, uN_plus, uT_plus, state, status, comp, cone

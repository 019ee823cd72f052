"""Linear complementarity problem (LCP) solvers, numba-compiled.

Problem LCP(q, M): find z in R^n such that

    w = M z + q,    0 <= w  _|_  z >= 0     (z_i >= 0, w_i >= 0, z_i w_i = 0).

Functions (float64 arrays; each solver is an ``…_into`` numba kernel that writes into given
arrays and takes its scratch from a preallocated :func:`lcp_work`, so the nonsmooth step loop
solves its contacts without allocating — the allocating functions below are thin Python
wrappers of those, same arithmetic):

``lcp_lemke(M, q, max_pivots=0, tol=1e-12) -> (z, w, status, n_pivots)``
    Lemke's complementary pivoting method (Lemke 1965) with the covering
    vector d = (1, ..., 1) and a lexicographic minimum-ratio test (Cottle,
    Pang & Stone 1992, Sec. 4.4 and 4.9) so that degenerate problems cannot
    cycle.  The tableau solution is polished by one direct solve on the final
    complementary basis (``M_aa z_a = -q_a``) and the better of the two is
    returned.  ``status``: 0 solved, 1 ray termination (no solution found;
    for copositive-plus M this certifies infeasibility, CPS Thm 4.4.13),
    2 pivot limit reached.  ``max_pivots <= 0`` selects 50 (n + 1).
    Internally q is scaled to unit max-norm (the LCP is positively
    homogeneous in q), tolerances are relative.

``lcp_enumerate(M, q, tol=1e-10) -> (z, w, status, residual)``
    Exhaustive enumeration of the 2^n complementary bases (n <= 12): for each
    index set a, solve M_aa z_a = -q_a (complete-pivoting Gaussian
    elimination; a rank-deficient but consistent system gives a basic
    solution, so singular problems are handled), set z_i = 0 off a and keep the
    candidate with the smallest natural residual max_i |min(z_i, w_i)|.
    Exact oracle for small problems.  ``status`` 0 if residual <= tol (1 +
    max|q|), 1 otherwise, 3 if n > 12 (nothing done).

``lcp_residual(z, w) -> (natural, fischer_burmeister)``
    natural = max_i |min(z_i, w_i)| (zero iff (z, w) is complementary and
    feasible); fischer_burmeister = || phi_FB(z, w) ||_2 with
    phi_FB(a, b) = a + b - sqrt(a^2 + b^2).  The caller supplies w = M z + q.

References
----------
C. E. Lemke, "Bimatrix equilibrium points and mathematical programming",
    Management Science 11 (1965) 681-689.
R. W. Cottle, J.-S. Pang, R. E. Stone, "The Linear Complementarity Problem",
    Academic Press 1992 (SIAM Classics 2009): Algorithm 4.4.5 (Lemke's method
    with a covering vector), Sec. 4.9 (lexicographic degeneracy resolution),
    Thm 4.4.13 (processability for copositive-plus matrices).
K. G. Murty, "Linear Complementarity, Linear and Nonlinear Programming",
    Heldermann 1988, Ch. 2.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from deckpound.analytic._jit import kernel
from deckpound.analytic.kernels.dense import solve_dense_cp_into

__all__ = [
    "LEMKE_MAX_PIVOTS",
    "LEMKE_RAY",
    "LEMKE_SOLVED",
    "LcpWork",
    "lcp_enumerate",
    "lcp_enumerate_into",
    "lcp_lemke",
    "lcp_lemke_into",
    "lcp_residual",
    "lcp_work",
]

LEMKE_SOLVED = 0
LEMKE_RAY = 1
LEMKE_MAX_PIVOTS = 2
ENUM_TOO_LARGE = 3

ENUM_MAX_N = 12


@kernel
def lcp_residual(z, w):
    """Complementarity residuals of a candidate (z, w = M z + q).

    Returns ``(natural, fb)`` with natural = max_i |min(z_i, w_i)| and
    fb = sqrt(sum_i phi_FB(z_i, w_i)^2), phi_FB(a, b) = a + b - sqrt(a^2+b^2).
    Both vanish iff 0 <= z _|_ w >= 0.
    """
    nat = 0.0
    fb2 = 0.0
    for i in range(z.shape[0]):
        a = z[i]
        b = w[i]
        m = min(b, a)
        nat = max(nat, abs(m))
        phi = a + b - np.sqrt(a * a + b * b)
        fb2 += phi * phi
    return nat, np.sqrt(fb2)


#: Scratch arrays of the allocation-free solvers (:func:`lcp_work`): for an LCP of size ≤ n,
#: T (n, 2n + 2) Lemke tableau; A (n, n), b, x, y (n,) float the dense sub-solves; zp, wp (n,)
#: the polished candidate; z, w (n,) the enumeration's candidate; basis, rows, cand, idx,
#: perm (n,) int64; mask (n,) bool.
LcpWork = namedtuple(
    "LcpWork",
    ["T", "A", "b", "x", "y", "zp", "wp", "z", "w", "basis", "rows", "cand", "idx", "perm", "mask"],
)


def lcp_work(n):
    """Scratch for LCPs of size ≤ n (:data:`LcpWork`, zeroed; allocated once per run or per
    call of an allocating wrapper — the ``…_into`` solvers write into views of it). Plain
    Python, like the allocating wrappers: nothing compiled calls them, and a compiled builder
    cost a fresh process a load from numba's cache (~0.2 s for the nonsmooth engine's)."""
    return LcpWork(
        np.zeros((n, 2 * n + 2)),
        np.zeros((n, n)),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.bool_),
    )


@kernel
def _polish(M, q, basic_z, z, ws):
    """Direct solve on the complementary basis: z_a = -M_aa^{-1} q_a, z = 0
    off a.  ``basic_z`` is a boolean mask; ``ws`` the :data:`LcpWork`.  Writes z; returns
    consistency."""
    n = q.shape[0]
    idx = ws.idx
    m = 0
    for i in range(n):
        if basic_z[i]:
            idx[m] = i
            m += 1
    A = ws.A[:m, :m]
    b = ws.b[:m]
    x = ws.x[:m]
    for r in range(m):
        b[r] = -q[idx[r]]
        for c in range(m):
            A[r, c] = M[idx[r], idx[c]]
    rank, ok = solve_dense_cp_into(A, b, x, 1e-14, ws.perm, ws.y)
    for i in range(n):
        z[i] = 0.0
    for r in range(m):
        z[idx[r]] = x[r]
    return ok and rank == m


@kernel
def _pivot(T, r, c):
    """Gauss-Jordan pivot of tableau T on element (r, c)."""
    nr, nc = T.shape
    p = T[r, c]
    inv = 1.0 / p
    for j in range(nc):
        T[r, j] *= inv
    T[r, c] = 1.0
    for i in range(nr):
        if i != r:
            f = T[i, c]
            if f != 0.0:
                for j in range(nc):
                    T[i, j] -= f * T[r, j]
                T[i, c] = 0.0


@kernel
def _lex_select(T, rows, nrows, c, n, rtol, cand):
    """Among candidate rows (first nrows entries of ``rows``, all tied in the
    minimum ratio), pick the lexicographic minimum of T[i, 0:n] / T[i, c]
    (rows of the basis inverse, Cottle-Pang-Stone Sec. 4.9); ``cand`` scratch (≥ nrows,)."""
    for k in range(nrows):
        cand[k] = rows[k]
    nc = nrows
    for j in range(n):
        if nc <= 1:
            break
        vmin = np.inf
        vmax = -np.inf
        for k in range(nc):
            i = cand[k]
            v = T[i, j] / T[i, c]
            vmin = min(vmin, v)
            vmax = max(vmax, v)
        tol = rtol * max(1.0, abs(vmin))
        nn = 0
        for k in range(nc):
            i = cand[k]
            v = T[i, j] / T[i, c]
            if v <= vmin + tol:
                cand[nn] = i
                nn += 1
        nc = nn
    return cand[0]


def lcp_lemke(M, q, max_pivots=0, tol=1e-12):
    """Lemke's method for w = M z + q, 0 <= w _|_ z >= 0.

    Parameters
    ----------
    M : (n, n) float64
    q : (n,) float64
    max_pivots : int, <= 0 selects 50 (n + 1)
    tol : relative tolerance for pivot elements and ratio ties.

    Returns
    -------
    z, w : (n,) float64, w = M z + q recomputed from z
    status : 0 solved, 1 ray termination, 2 pivot limit
    n_pivots : number of pivots performed

    Covering vector d = 1; lexicographic minimum-ratio rule; when z0 is among
    the tied blocking rows it leaves (terminating).  References: Lemke (1965);
    Cottle, Pang & Stone (1992) Algorithm 4.4.5 and Sec. 4.9.  The allocating wrapper of
    :func:`lcp_lemke_into`.
    """
    n = q.shape[0]
    z = np.zeros(n)
    w = np.empty(n)
    status, npiv = lcp_lemke_into(M, q, z, w, lcp_work(n), max_pivots, tol)
    return z, w, status, npiv


@kernel(inline="always")
def _lemke_tableau(M, q, T, basis, qscale):
    """The initial tableau T (n, 2n + 2) of Lemke's method for w − M z − d z0 = q / qscale
    with d = 1; columns [w_0..w_{n-1}, z_0..z_{n-1}, z0, rhs] (variable ids 0..n−1 → w_i,
    n..2n−1 → z_i, 2n → z0); the basis is w (basis[i] = variable id basic in row i)."""
    n = q.shape[0]
    for i in range(n):
        for j in range(T.shape[1]):
            T[i, j] = 0.0
    for i in range(n):
        T[i, i] = 1.0
        for j in range(n):
            T[i, n + j] = -M[i, j]
        T[i, 2 * n] = -1.0
        T[i, 2 * n + 1] = q[i] / qscale
    for i in range(n):
        basis[i] = i


@kernel(inline="always")
def _lemke_first_row(T, rows, cand, n, qm, tol):
    """The row z0 enters in: argmin of the scaled q (minimum ``qm``), ties broken
    lexicographically. In the initial tableau the z0 column is −d = −1 in every row and the
    basis inverse is I, so the lexicographic minimum of (q_i, e_iᵀ) over the tied rows is the
    row whose entries T[i, 0:n] stay smallest, i.e. the largest index."""
    nt = 0
    for i in range(n):
        if T[i, 2 * n + 1] <= qm + tol:
            rows[nt] = i
            nt += 1
    if nt == 1:
        return rows[0]
    for k in range(nt):
        cand[k] = rows[k]
    ncand = nt
    for j in range(n):
        if ncand <= 1:
            break
        vmin = np.inf
        for k in range(ncand):
            vmin = min(vmin, T[cand[k], j])
        nn = 0
        for k in range(ncand):
            if T[cand[k], j] <= vmin + tol:
                cand[nn] = cand[k]
                nn += 1
        ncand = nn
    return cand[0]


@kernel(inline="always")
def _lemke_blocking_row(T, basis, rows, cand, c, n, ptol, tol):
    """Minimum-ratio test for the entering column ``c``: the blocking row (z0's row when it
    is among the tied rows, so that it leaves and the method terminates; otherwise the
    lexicographic minimum, :func:`_lex_select`). Returns −1 when no row blocks (a ray)."""
    rhs = 2 * n + 1
    rmin = np.inf
    for i in range(n):
        a = T[i, c]
        if a > ptol:
            rmin = min(rmin, T[i, rhs] / a)
    if rmin == np.inf:
        return -1
    rtie = tol * max(1.0, abs(rmin)) * 10.0
    nt = 0
    z0row = -1
    for i in range(n):
        a = T[i, c]
        if a > ptol and T[i, rhs] / a <= rmin + rtie:
            rows[nt] = i
            nt += 1
            if basis[i] == 2 * n:
                z0row = i
    if z0row >= 0:
        return z0row
    if nt == 1:
        return rows[0]
    return _lex_select(T, rows, nt, c, n, tol, cand)


@kernel(inline="always")
def _lemke_solution(M, q, T, basis, z, w, qscale):
    """z from the tableau (the basic z_i, clipped at 0, unscaled), w = M z + q."""
    n = q.shape[0]
    for i in range(n):
        v = basis[i]
        val = T[i, 2 * n + 1] * qscale
        if v >= n and v < 2 * n:
            z[v - n] = max(0.0, val)
    _lcp_w(M, q, z, w)


@kernel(inline="always")
def _lcp_w(M, q, z, w):
    """w = M z + q."""
    n = q.shape[0]
    for i in range(n):
        s = q[i]
        for j in range(n):
            s += M[i, j] * z[j]
        w[i] = s


@kernel(inline="always")
def _lemke_polish(M, q, basis, z, w, ws):
    """Polish on the final complementary basis (:func:`_polish`, clipped at 0); keeps the
    polished (z, w) when its natural residual is not larger."""
    n = q.shape[0]
    mask = ws.mask
    for i in range(n):
        mask[i] = False
    for i in range(n):
        v = basis[i]
        if v >= n and v < 2 * n:
            mask[v - n] = True
    zp = ws.zp[:n]
    if not _polish(M, q, mask, zp, ws):
        return
    for i in range(n):
        zp[i] = max(zp[i], 0.0)
    wp = ws.wp[:n]
    _lcp_w(M, q, zp, wp)
    r0, _ = lcp_residual(z, w)
    r1, _ = lcp_residual(zp, wp)
    if r1 <= r0:
        for i in range(n):
            z[i] = zp[i]
            w[i] = wp[i]


@kernel
def lcp_lemke_into(M, q, z, w, ws, max_pivots, tol):
    """:func:`lcp_lemke` writing z, w (n,) with the scratch ``ws`` (:func:`lcp_work` of size
    ≥ n); returns (status, n_pivots). The stages (tableau, first pivot row, blocking row,
    solution, polish) are inlined."""
    n = q.shape[0]
    for i in range(n):
        z[i] = 0.0
    if max_pivots <= 0:
        max_pivots = 50 * (n + 1)
    qmin = 0.0
    qscale = 0.0
    for i in range(n):
        qmin = min(qmin, q[i])
        qscale = max(qscale, abs(q[i]))
    if qmin >= 0.0:
        for i in range(n):
            w[i] = q[i]
        return LEMKE_SOLVED, 0
    mscale = 0.0
    for i in range(n):
        for j in range(n):
            mscale = max(mscale, abs(M[i, j]))
    T = ws.T[:n, : 2 * n + 2]
    basis = ws.basis
    _lemke_tableau(M, q, T, basis, qscale)
    z0 = 2 * n  # z0 enters first
    r = _lemke_first_row(T, ws.rows, ws.cand, n, qmin / qscale, tol)
    leaving = basis[r]
    _pivot(T, r, z0)
    basis[r] = z0
    npiv = 1
    status = LEMKE_MAX_PIVOTS
    ptol = tol * max(1.0, mscale)
    while npiv < max_pivots:
        # the complement of the leaving variable enters
        c = leaving + n if leaving < n else leaving - n
        r = _lemke_blocking_row(T, basis, ws.rows, ws.cand, c, n, ptol, tol)
        if r < 0:
            status = LEMKE_RAY
            break
        leaving = basis[r]
        _pivot(T, r, c)
        basis[r] = c
        npiv += 1
        if leaving == z0:
            status = LEMKE_SOLVED
            break
    _lemke_solution(M, q, T, basis, z, w, qscale)
    if status == LEMKE_SOLVED:
        _lemke_polish(M, q, basis, z, w, ws)
    return status, npiv


def lcp_enumerate(M, q, tol=1e-10):
    """Solve LCP(q, M) by enumerating all 2^n complementary index sets.

    For n <= 12.  Returns ``(z, w, status, residual)``: the candidate with the
    smallest natural residual max|min(z, w)|; status 0 if residual <=
    tol (1 + max|q|), 1 if no candidate meets it, 3 if n > 12 (z = 0).
    Singular principal submatrices are solved in the basic-solution sense
    (complete pivoting, free unknowns set to zero), so degenerate problems
    whose solutions live on singular bases are still found when a basic
    solution exists.  Cost ~ 2^n n^3 / 3 flops.  The allocating wrapper of
    :func:`lcp_enumerate_into`.
    """
    n = q.shape[0]
    zbest = np.zeros(n)
    wbest = np.empty(n)
    status, best = lcp_enumerate_into(M, q, zbest, wbest, lcp_work(n), tol)
    return zbest, wbest, status, best


@kernel
def lcp_enumerate_into(M, q, zbest, wbest, ws, tol):
    """:func:`lcp_enumerate` writing zbest, wbest (n,) with the scratch ``ws``
    (:func:`lcp_work` of size ≥ n); returns (status, residual)."""
    n = q.shape[0]
    for i in range(n):
        zbest[i] = 0.0
        wbest[i] = q[i]
    qscale = 0.0
    for i in range(n):
        qscale = max(qscale, abs(q[i]))
    if n > ENUM_MAX_N:
        nat, _ = lcp_residual(zbest, wbest)
        return ENUM_TOO_LARGE, nat
    best, _ = lcp_residual(zbest, wbest)
    thr = tol * (1.0 + qscale)
    if best <= 1e-3 * thr:
        return 0, best
    idx = ws.idx
    z = ws.z[:n]
    w = ws.w[:n]
    for mask in range(1, 1 << n):
        m = 0
        for i in range(n):
            if (mask >> i) & 1:
                idx[m] = i
                m += 1
        As = ws.A[:m, :m]
        bs = ws.b[:m]
        xs = ws.x[:m]
        for r in range(m):
            bs[r] = -q[idx[r]]
            for c in range(m):
                As[r, c] = M[idx[r], idx[c]]
        # inconsistent (singular) systems yield a candidate whose residual
        # is large; the residual comparison below rejects it.
        solve_dense_cp_into(As, bs, xs, 1e-13, ws.perm, ws.y)
        for i in range(n):
            z[i] = 0.0
        for r in range(m):
            z[idx[r]] = xs[r]
        for i in range(n):
            s = q[i]
            for j in range(n):
                s += M[i, j] * z[j]
            w[i] = s
        nat, _ = lcp_residual(z, w)
        if nat < best:
            best = nat
            for i in range(n):
                zbest[i] = z[i]
                wbest[i] = w[i]
            if best <= 1e-3 * thr:
                break
    status = 0 if best <= thr else 1
    return status, best

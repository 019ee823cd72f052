"""Small dense linear algebra for the step loops (numba): LU with partial pivoting, and a
rank-revealing solve with complete pivoting for the contact problems' small systems.

The 7×7 iteration matrices of the analytic engines are factored and solved here in place,
without allocation, so the compiled step loops never call into LAPACK's Python layer. The size
is the compile-time constant :data:`~deckpound.models.plan.N_DOF` (every matrix of the step
loops is N_DOF × N_DOF), so LLVM unrolls the loops: the factorisation takes about half the time
of the same code with the size read from the array (measured by a micro-benchmark), with the
same operations in the same order (identical factors).
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic._jit import compiled, kernel
from deckpound.models.plan import N_DOF


@kernel
def lu_factor(A, piv):
    """In-place LU with partial pivoting of an N_DOF × N_DOF matrix. Returns False if singular."""
    n = N_DOF
    for k in range(n):
        p = k
        amax = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > amax:
                amax = abs(A[i, k])
                p = i
        piv[k] = p
        if amax == 0.0 or not np.isfinite(amax):
            return False
        if p != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            A[i, k] *= inv
            lik = A[i, k]
            if lik != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= lik * A[k, j]
    return True


@kernel
def lu_solve(LU, piv, b, x):
    """Solve with the factors of :func:`lu_factor` (x may alias b; N_DOF long)."""
    n = N_DOF
    for i in range(n):
        x[i] = b[i]
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = x[k]
            x[k] = x[p]
            x[p] = tmp
    for i in range(n):
        s = x[i]
        for j in range(i):
            s -= LU[i, j] * x[j]
        x[i] = s
    for i in range(n - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, n):
            s -= LU[i, j] * x[j]
        x[i] = s / LU[i, i]


@compiled
def solve_dense_cp(A, b, x, rtol):
    """Solve A x = b in place (x is output) by Gaussian elimination with
    complete pivoting.  A (m x m) and b (m,) are overwritten.

    Rank-revealing: pivots below ``rtol * max|A|`` are treated as zero; the
    corresponding unknowns are set to 0 (a basic solution).  Returns
    ``(rank, consistent)`` where consistent is False if the dropped equations
    have residual right-hand sides larger than ``rtol`` times the scale of b
    (then x is a least-effort basic solution, not a solution).
    """
    m = A.shape[0]
    return solve_dense_cp_into(A, b, x, rtol, np.empty(m, dtype=np.int64), np.empty(m))


@kernel
def solve_dense_cp_into(A, b, x, rtol, perm, y):
    """:func:`solve_dense_cp` with its scratch given: perm (≥ m,) int64, y (≥ m,)."""
    m = A.shape[0]
    for i in range(m):
        perm[i] = i
    amax = 0.0
    bmax = 0.0
    for i in range(m):
        bmax = max(bmax, abs(b[i]))
        for j in range(m):
            amax = max(amax, abs(A[i, j]))
    for i in range(m):
        x[i] = 0.0
    if m == 0:
        return 0, True
    if amax == 0.0:
        return 0, bmax == 0.0
    ptol = rtol * amax
    rank = m
    for k in range(m):
        # complete pivot search
        best = 0.0
        pr = k
        pc = k
        for i in range(k, m):
            for j in range(k, m):
                v = abs(A[i, j])
                if v > best:
                    best = v
                    pr = i
                    pc = j
        if best <= ptol:
            rank = k
            break
        if pr != k:
            for j in range(m):
                t = A[k, j]
                A[k, j] = A[pr, j]
                A[pr, j] = t
            t = b[k]
            b[k] = b[pr]
            b[pr] = t
        if pc != k:
            for i in range(m):
                t = A[i, k]
                A[i, k] = A[i, pc]
                A[i, pc] = t
            ti = perm[k]
            perm[k] = perm[pc]
            perm[pc] = ti
        piv = A[k, k]
        for i in range(k + 1, m):
            f = A[i, k] / piv
            if f != 0.0:
                A[i, k] = 0.0
                for j in range(k + 1, m):
                    A[i, j] -= f * A[k, j]
                b[i] -= f * b[k]
    consistent = True
    btol = 1e3 * rtol * bmax
    for i in range(rank, m):
        if abs(b[i]) > btol:
            consistent = False
    for k in range(m):
        y[k] = 0.0
    for k in range(rank - 1, -1, -1):
        s = b[k]
        for j in range(k + 1, rank):
            s -= A[k, j] * y[j]
        y[k] = s / A[k, k]
    for k in range(m):
        x[perm[k]] = y[k]
    return rank, consistent

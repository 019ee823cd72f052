"""Small dense linear algebra for the step loops (numba): LU with partial pivoting, and a
rank-revealing solve with complete pivoting for the contact problems' small systems.

The iteration matrices of the analytic engines (n_dof × n_dof) are factored and solved here in
place, without allocation, so the compiled step loops never call into LAPACK's Python layer.
The size comes from the caller as a *size tag*: a tuple whose length is the matrix size
(``SystemArrays.dofs`` = (0, …, n_dof − 1), :func:`deckpound.analytic.nonsmooth.impulses.size_tag`).
numba types a tuple by its length, so ``len(tag)`` is a compile-time constant: the LU is
compiled once per model size, and its short loops have a fixed trip count that LLVM unrolls
(as it did when the size was a module constant; a size read from the array's shape at run
time does not unroll). The operations and their order are the same for every size.
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic._jit import compiled, kernel

__all__ = ["lu_factor", "lu_solve", "solve_dense_cp", "solve_dense_cp_into"]


@kernel
def lu_factor(A, piv, size):
    """In-place LU with partial pivoting (PA = LU, unit lower L below the diagonal) of the
    n × n matrix A, n = len(size) (a size tag, see the module docstring); piv (n,) int64 the
    row permutation: row k of the factors is row piv[k] of A (the row exchanges composed, so
    :func:`lu_solve` applies them in one pass). The diagonal holds the pivots' reciprocals
    1/u_kk, which the elimination computes anyway (L's column k is scaled by it): the back
    substitution multiplies by them instead of dividing, a chain of n dependent divisions
    that bounds a small solve's latency (the result is the quotient's to within one rounding,
    as OpenBLAS's triangular-solve kernels do with their inverted diagonals). Returns
    False if a pivot is zero or not finite (singular)."""
    n = len(size)
    for i in range(n):
        piv[i] = i
    for k in range(n):
        p = k
        amax = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > amax:
                amax = abs(A[i, k])
                p = i
        if amax == 0.0 or not np.isfinite(amax):
            return False
        if p != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
            tmp_row = piv[k]
            piv[k] = piv[p]
            piv[p] = tmp_row
        inv = 1.0 / A[k, k]
        A[k, k] = inv
        for i in range(k + 1, n):
            A[i, k] *= inv
            lik = A[i, k]
            if lik != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= lik * A[k, j]
    return True


@kernel(inline="always")
def lu_solve(LU, piv, b, x, size):
    """Solve A x = b with the factors LU, piv of :func:`lu_factor`; n = len(size), the size
    tag the factors were computed with. x must not alias b: the forward substitution reads
    b through the permutation, L y = P b with (P b)_i = b[piv[i]], while it writes y into x
    (the same operations, in the same order, as exchanging the rows of b one by one first);
    then U x = y in place, with the pivots' reciprocals the factors hold on their diagonal.
    Inlined into its callers (a handful of lines; a call would pass four arrays by value)."""
    n = len(size)
    for i in range(n):
        s = b[piv[i]]
        for j in range(i):
            s -= LU[i, j] * x[j]
        x[i] = s
    for i in range(n - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, n):
            s -= LU[i, j] * x[j]
        x[i] = s * LU[i, i]


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


# The stages of solve_dense_cp_into, inlined into it (one compiled function, as before). The
# system size m varies from call to call (the number of active contact unknowns), so it is
# read from A's shape.


@kernel(inline="always")
def _abs_max(A, b, m):
    """(max |A_ij|, max |b_i|) over the m × m system."""
    amax = 0.0
    bmax = 0.0
    for i in range(m):
        bmax = max(bmax, abs(b[i]))
        for j in range(m):
            amax = max(amax, abs(A[i, j]))
    return amax, bmax


@kernel(inline="always")
def _complete_pivot(A, k, m):
    """The largest |A_ij| of the trailing block i, j ≥ k: (value, row, column); the first in
    row-major order among equals, (0, k, k) for a zero block."""
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
    return best, pr, pc


@kernel(inline="always")
def _swap_rows(A, b, k, pr, m):
    """Rows k and pr of A and b exchanged."""
    for j in range(m):
        t = A[k, j]
        A[k, j] = A[pr, j]
        A[pr, j] = t
    t = b[k]
    b[k] = b[pr]
    b[pr] = t


@kernel(inline="always")
def _swap_columns(A, perm, k, pc, m):
    """Columns k and pc of A exchanged, and the unknowns' order perm with them."""
    for i in range(m):
        t = A[i, k]
        A[i, k] = A[i, pc]
        A[i, pc] = t
    ti = perm[k]
    perm[k] = perm[pc]
    perm[pc] = ti


@kernel(inline="always")
def _eliminate_below(A, b, k, m):
    """Zero column k below the pivot A_kk: row_i −= (A_ik / A_kk) row_k, b likewise."""
    piv = A[k, k]
    for i in range(k + 1, m):
        f = A[i, k] / piv
        if f != 0.0:
            A[i, k] = 0.0
            for j in range(k + 1, m):
                A[i, j] -= f * A[k, j]
            b[i] -= f * b[k]


@kernel(inline="always")
def _dropped_rows_consistent(b, rank, m, btol):
    """True when the right-hand sides of the rows beyond the rank are all within btol."""
    consistent = True
    for i in range(rank, m):
        if abs(b[i]) > btol:
            consistent = False
    return consistent


@kernel(inline="always")
def _back_substitute(A, b, x, perm, y, rank, m):
    """Upper-triangular solve of the leading rank × rank block into y (the other unknowns 0),
    then x in the original order of the unknowns: x[perm[k]] = y[k]."""
    for k in range(m):
        y[k] = 0.0
    for k in range(rank - 1, -1, -1):
        s = b[k]
        for j in range(k + 1, rank):
            s -= A[k, j] * y[j]
        y[k] = s / A[k, k]
    for k in range(m):
        x[perm[k]] = y[k]


@kernel
def solve_dense_cp_into(A, b, x, rtol, perm, y):
    """:func:`solve_dense_cp` with its scratch given: perm (≥ m,) int64, y (≥ m,)."""
    m = A.shape[0]
    for i in range(m):
        perm[i] = i
    amax, bmax = _abs_max(A, b, m)
    for i in range(m):
        x[i] = 0.0
    if m == 0:
        return 0, True
    if amax == 0.0:
        return 0, bmax == 0.0
    ptol = rtol * amax
    rank = m
    for k in range(m):
        best, pr, pc = _complete_pivot(A, k, m)
        if best <= ptol:
            rank = k
            break
        if pr != k:
            _swap_rows(A, b, k, pr, m)
        if pc != k:
            _swap_columns(A, perm, k, pc, m)
        _eliminate_below(A, b, k, m)
    consistent = _dropped_rows_consistent(b, rank, m, 1e3 * rtol * bmax)
    _back_substitute(A, b, x, perm, y, rank, m)
    return rank, consistent

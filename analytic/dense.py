"""Small dense linear algebra for the step loops (numba): LU with partial pivoting.

The 7×7 iteration matrices of the analytic engines are factored and solved here in place,
without allocation, so the compiled step loops never call into LAPACK's Python layer. The size
is the compile-time constant :data:`~deckpound.models.plan.N_DOF` (every matrix of the step
loops is N_DOF × N_DOF), so LLVM unrolls the loops: the factorisation takes about half the time
of the same code with the size read from the array (measured by a micro-benchmark), with the
same operations in the same order (identical factors).
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic._jit import kernel
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

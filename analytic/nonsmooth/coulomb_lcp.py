r"""The two LCP forms of the planar frictional impact problem (used by
:mod:`deckpound.analytic.nonsmooth.frictional_contact`, where the problem, the sign conventions and the
order of the solvers are stated).

Both take the Delassus matrix G (2nc × 2nc, order N_0..N_nc-1, T_0..), qN = uN_free + e uN-,
the free tangential velocities, the friction coefficients mu (nc,), the list fidx[:nf] of the
frictional contacts and the impulse scale s (impulses are solved as P / s so that the LCP
matrix is O(1)); the extractors map an LCP solution z back to (P_N, P_T).

LCP formulation (primary; three unknowns per frictional contact, Glocker &
Pfeiffer 1992, Pfeiffer & Glocker 1996, Leine & Nijmeijer 2004 Sec. 7.3)
----------------------------------------------------------------------------
Split the friction interval and the slip velocity::

    P_R = mu P_N + P_T >= 0,  P_L = mu P_N - P_T = 2 mu P_N - P_R >= 0,
    U_T+ = v+ - v-,   v+, v- >= 0,   v+ P_R = 0,  v- P_L = 0.

Unknowns z = (P_N, P_R, v-), slacks w = (xi_N, v+, P_L)::

    [xi_N]   [G_NN - G_NT mu   G_NT  0] [P_N]   [uN_free + e uN-]
    [v+  ] = [G_TN - G_TT mu   G_TT  I] [P_R] + [uT_free        ]
    [P_L ]   [2 mu             -I    0] [v- ]   [0              ]

(mu = diag(mu_i)).  Contacts with mu_i = 0 carry only their P_N unknown
(P_T = 0), so mu = 0 everywhere reduces to the normal-only LCP
G_NN P_N + uN_free + e uN- = xi_N, n = nc.  Impulses are scaled by
1 / mean(diag G_NN) so that the LCP matrix is O(1) (Delassus entries of a
140 t deck are ~1e-5 1/kg).

This matrix is *not* copositive in general (z^T A z contains
mu P_N^T (G_TN P_N + G_TT P_T), which can be negative), so Lemke's
processability theorem does not cover it.

Stewart-Trinkle / Anitescu-Potra formulation (the fall-back)
------------------------------------------------------------
Four unknowns (P_N, beta+, beta-, lambda), P_T = beta+ - beta-, lambda = |U_T+|::

    [xi_N   ]   [G_NN   G_NT  -G_NT  0] [P_N  ]   [uN_free + e uN-]
    [l + U_T] = [G_TN   G_TT  -G_TT  1] [beta+] + [ uT_free       ]
    [l - U_T]   [-G_TN -G_TT   G_TT  1] [beta-]   [-uT_free       ]
    [slack  ]   [mu     -1     -1    0] [lambda]  [0              ]

whose matrix is copositive for symmetric PSD G (Anitescu & Potra 1997).
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic._jit import compiled, kernel

__all__ = [
    "build_lcp3",
    "build_lcp3_into",
    "build_lcp_st",
    "build_lcp_st_into",
    "extract3",
    "extract_st",
]


@kernel
def _zero(A, q, n):
    """A[:n, :n] = 0, q[:n] = 0 (the builders write only the non-zeros)."""
    for i in range(n):
        q[i] = 0.0
        for j in range(n):
            A[i, j] = 0.0


@compiled
def build_lcp3(G, qN, uT_free, mu, fidx, nf, s):
    """3-unknown LCP (scaled impulses).  fidx[k] = contact of k-th
    frictional contact.  Returns (A, q), size nc + 2 nf."""
    n = qN.shape[0] + 2 * nf
    A = np.empty((n, n))
    q = np.empty(n)
    build_lcp3_into(G, qN, uT_free, mu, fidx, nf, s, A, q)
    return A, q


@kernel
def build_lcp3_into(G, qN, uT_free, mu, fidx, nf, s, A, q):
    """:func:`build_lcp3` into A (n, n), q (n,), n = nc + 2 nf (overwritten)."""
    nc = qN.shape[0]
    _zero(A, q, nc + 2 * nf)
    # friction coefficient per contact (0 for frictionless)
    for i in range(nc):
        q[i] = qN[i]
        for j in range(nc):
            A[i, j] = s * G[i, j]
    for l in range(nf):
        j = fidx[l]
        for i in range(nc):
            A[i, j] -= s * mu[j] * G[i, nc + j]
            A[i, nc + l] = s * G[i, nc + j]
    for k in range(nf):
        i = fidx[k]
        r = nc + k
        q[r] = uT_free[i]
        for j in range(nc):
            A[r, j] = s * G[nc + i, j]
        for l in range(nf):
            j = fidx[l]
            A[r, j] -= s * mu[j] * G[nc + i, nc + j]
            A[r, nc + l] = s * G[nc + i, nc + j]
        A[r, nc + nf + k] = 1.0
        r2 = nc + nf + k
        A[r2, i] = 2.0 * mu[i]
        A[r2, nc + k] = -1.0


@kernel
def extract3(z, mu, fidx, nf, s, P_N, P_T):
    nc = P_N.shape[0]
    for i in range(nc):
        P_N[i] = s * z[i]
        P_T[i] = 0.0
    for k in range(nf):
        i = fidx[k]
        P_T[i] = s * (z[nc + k] - mu[i] * z[i])


@compiled
def build_lcp_st(G, qN, uT_free, mu, fidx, nf, s):
    """Stewart-Trinkle / Anitescu-Potra LCP: unknowns (P_N, b+, b-, lam).  Returns (A, q),
    size nc + 3 nf."""
    n = qN.shape[0] + 3 * nf
    A = np.empty((n, n))
    q = np.empty(n)
    build_lcp_st_into(G, qN, uT_free, mu, fidx, nf, s, A, q)
    return A, q


@kernel
def build_lcp_st_into(G, qN, uT_free, mu, fidx, nf, s, A, q):
    """:func:`build_lcp_st` into A (n, n), q (n,), n = nc + 3 nf (overwritten)."""
    nc = qN.shape[0]
    _zero(A, q, nc + 3 * nf)
    for i in range(nc):
        q[i] = qN[i]
        for j in range(nc):
            A[i, j] = s * G[i, j]
        for l in range(nf):
            j = fidx[l]
            A[i, nc + l] = s * G[i, nc + j]
            A[i, nc + nf + l] = -s * G[i, nc + j]
    for k in range(nf):
        i = fidx[k]
        rp = nc + k
        rm = nc + nf + k
        rl = nc + 2 * nf + k
        q[rp] = uT_free[i]
        q[rm] = -uT_free[i]
        for j in range(nc):
            A[rp, j] = s * G[nc + i, j]
            A[rm, j] = -s * G[nc + i, j]
        for l in range(nf):
            j = fidx[l]
            g = s * G[nc + i, nc + j]
            A[rp, nc + l] = g
            A[rp, nc + nf + l] = -g
            A[rm, nc + l] = -g
            A[rm, nc + nf + l] = g
        A[rp, nc + 2 * nf + k] = 1.0
        A[rm, nc + 2 * nf + k] = 1.0
        A[rl, i] = mu[i]
        A[rl, nc + k] = -1.0
        A[rl, nc + nf + k] = -1.0


@kernel
def extract_st(z, fidx, nf, s, P_N, P_T):
    nc = P_N.shape[0]
    for i in range(nc):
        P_N[i] = s * z[i]
        P_T[i] = 0.0
    for k in range(nf):
        i = fidx[k]
        P_T[i] = s * (z[nc + k] - z[nc + nf + k])

"""Checks of candidate contact impulses against the contact laws (numba kernels).

The frictional impact solve of :mod:`deckpound.analytic.nonsmooth.frictional_contact` tries several LCP
formulations and keeps the first candidate these checks verify (else the best one): contact
velocities recomputed from the Delassus matrix G, the Signorini–Newton complementarity and
Coulomb cone residuals (definitions in that module's docstring), the bookkeeping of the best
candidate, and the canonical split of the tangential impulse among contacts whose tangent
columns coincide. Status codes of the solve are defined here (re-exported there).
"""

from __future__ import annotations

from deckpound.analytic._jit import kernel

__all__ = [
    "STATUS_ENUM",
    "STATUS_FAILED",
    "STATUS_LEMKE",
    "STATUS_LEMKE_ST",
    "contact_residuals",
    "contact_velocities",
    "evaluate_candidate",
    "impulse_scale",
    "keep_if_better",
    "split_shared_tangents",
]

STATUS_LEMKE = 0  # verified, Lemke on the 3-unknown LCP
STATUS_LEMKE_ST = 1  # verified, Lemke on the Stewart-Trinkle LCP
STATUS_ENUM = 2  # verified, enumeration
STATUS_FAILED = 3  # nothing verified; best candidate returned


@kernel
def contact_velocities(G, uN_free, uT_free, P_N, P_T, uN_plus, uT_plus):
    """Post-impact contact velocities U+ = u_free + G P into uN_plus, uT_plus (nc,) [m/s]."""
    nc = uN_free.shape[0]
    for i in range(nc):
        sN = uN_free[i]
        sT = uT_free[i]
        for j in range(nc):
            sN += G[i, j] * P_N[j] + G[i, nc + j] * P_T[j]
            sT += G[nc + i, j] * P_N[j] + G[nc + i, nc + j] * P_T[j]
        uN_plus[i] = sN
        uT_plus[i] = sT


@kernel
def contact_residuals(G, uN_minus, e, mu, P_N, P_T, uN_plus, uT_plus):
    """(comp_res, cone_res) in velocity units (definitions: :mod:`.frictional_contact`)."""
    nc = P_N.shape[0]
    comp = 0.0
    cone = 0.0
    for i in range(nc):
        gN = G[i, i]
        if not gN > 0.0:
            gN = 1.0
        xi = uN_plus[i] + e[i] * uN_minus[i]
        a = gN * P_N[i]
        m = min(xi, a)
        comp = max(comp, abs(m))
        gT = G[nc + i, nc + i]
        if not gT > 0.0:
            gT = gN
        bound = gT * mu[i] * (max(0.0, P_N[i]))
        y = gT * P_T[i] - uT_plus[i]
        if y > bound:
            y = bound
        elif y < -bound:
            y = -bound
        r = abs(gT * P_T[i] - y)
        cone = max(cone, r)
    return comp, cone


@kernel
def impulse_scale(G, nc):
    """1 / mean(diag G_NN): the impulse scale that makes the LCPs' unknowns O(velocity)
    (1 when the diagonal is not positive)."""
    s = 0.0
    for i in range(nc):
        s += G[i, i]
    s /= nc
    if not s > 0.0:
        return 1.0
    return 1.0 / s


@kernel
def evaluate_candidate(G, uN_free, uT_free, uN_minus, e, mu, P_N, P_T, uN_plus, uT_plus):
    """Contact velocities of the impulses (P_N, P_T) and their (comp_res, cone_res)."""
    contact_velocities(G, uN_free, uT_free, P_N, P_T, uN_plus, uT_plus)
    comp, cone = contact_residuals(G, uN_minus, e, mu, P_N, P_T, uN_plus, uT_plus)
    return comp, cone


@kernel
def keep_if_better(
    G, uN_free, uT_free, uN_minus, e, mu, cN, cT, vN, vT, bN, bT, best, verified_status, tolv
):
    """Check the candidate impulses (cN, cT) against the contact laws; keep them in (bN, bT)
    when their residual max(comp, cone) beats ``best[0]``, with best = [residual, comp, cone,
    status]: ``verified_status`` if the residual is ≤ tolv, else STATUS_FAILED. Returns True
    when the candidate is verified."""
    comp, cone = evaluate_candidate(G, uN_free, uT_free, uN_minus, e, mu, cN, cT, vN, vT)
    r = max(comp, cone)
    if r < best[0]:
        best[0] = r
        best[1] = comp
        best[2] = cone
        best[3] = verified_status if r <= tolv else STATUS_FAILED
        for i in range(cN.shape[0]):
            bN[i] = cN[i]
            bT[i] = cT[i]
    return r <= tolv


@kernel
def split_shared_tangents(G, mu, P_N, P_T, group):
    """Contacts whose tangent columns of W coincide (||W_Ti - W_Tj||^2_M^-1
    = G_TiTi + G_TjTj - 2 G_TiTj = 0) share one tangential velocity; only
    the sum of their P_T is determined.  Redistribute the sum in proportion
    to mu_i P_N,i (cone- and velocity-preserving, deterministic).  Returns
    True if anything was changed.  ``group`` (≥ nc,) int64 scratch."""
    nc = P_N.shape[0]
    for i in range(nc):
        group[i] = -1
    changed = False
    for i in range(nc):
        if group[i] >= 0 or not mu[i] > 0.0:
            continue
        group[i] = i
        gi = G[nc + i, nc + i]
        m = 1
        for j in range(i + 1, nc):
            if group[j] >= 0 or not mu[j] > 0.0:
                continue
            gj = G[nc + j, nc + j]
            d = gi + gj - 2.0 * G[nc + i, nc + j]
            if abs(d) <= 1e-12 * (gi + gj):
                group[j] = i
                m += 1
        if m < 2:
            continue
        tot = 0.0
        cap = 0.0
        for j in range(i, nc):
            if group[j] == i:
                tot += P_T[j]
                pn = max(0.0, P_N[j])
                cap += mu[j] * pn
        if not cap > 0.0:
            continue
        for j in range(i, nc):
            if group[j] == i:
                pn = max(0.0, P_N[j])
                P_T[j] = tot * (mu[j] * pn / cap)
        changed = True
    return changed

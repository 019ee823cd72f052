"""Contact forces and tangents on the 7 DOF from the per-corner laws (numba kernels).

The step loops of the compliance engine call these once per force evaluation: the gap check
(:func:`eval_contacts`, inlined; the laws are skipped while every corner is open), the laws of
the closed corners (:func:`eval_closed`: normal law, friction law, generalised force
F_c = Σ W_Nᵀ λ_N + W_Tᵀ λ_T), the contact part of Newton's tangent (:func:`contact_tangent`)
and the gaps and rates alone (:func:`gaps_and_rates`). The laws themselves, one corner at a
time, are :mod:`deckpound.analytic.contact_laws`; the kinematics (gaps, W_N, W_T, Hessian)
:mod:`deckpound.analytic.kinematics`. ``contact`` is the Contact bundle and ``cw`` the
ContactWork of :mod:`deckpound.analytic.bundles`.
"""

from __future__ import annotations

from numba import njit

from deckpound.analytic._jit import kernel
from deckpound.analytic.contact_laws import (
    FRICTION_CONTACT2D,
    P_FMODE,
    S_TFT,
    friction_law,
    normal_law,
)
from deckpound.analytic.kinematics import (
    contact_kinematics,
    gap_hessian,
    linear_gap,
    linear_gap_rate,
)

__all__ = ["contact_tangent", "eval_closed", "eval_contacts", "gap_rates", "gaps_and_rates"]


@njit(cache=True, inline="always")
def _linear_gaps(u, v, corners, g, gd):
    """Gaps and gap rates of the small-rotation kinematics (kinematics.contact_kinematics)."""
    for c in range(4):
        g[c] = linear_gap(corners[c], u)
        gd[c] = linear_gap_rate(corners[c], v)


@kernel(inline="always")
def gap_rates(contact, v, cw):
    """Gap rates cw.gd = W_N u̇ of the four corners at the u of the last evaluation (its
    Jacobian cw.WN when nonlinear), the same operations as :func:`eval_contacts` (linear
    kinematics); :func:`gaps_and_rates` uses it for the nonlinear one."""
    if not contact.nonlinear:
        for c in range(4):
            cw.gd[c] = linear_gap_rate(contact.corners[c], v)
    else:
        for c in range(4):
            s = 0.0
            for j in range(7):
                s += cw.WN[c, j] * v[j]
            cw.gd[c] = s


@kernel
def gaps_and_rates(contact, u, v, cw):
    """Gaps cw.g and rates cw.gd = W_N u̇ of the four corners (fills cw.WN, cw.WT when
    nonlinear). ``contact``: the Contact bundle, ``cw``: ContactWork
    (:mod:`deckpound.analytic.bundles`)."""
    if not contact.nonlinear:
        _linear_gaps(u, v, contact.corners, cw.g, cw.gd)
    else:
        contact_kinematics(u, contact.corners, True, cw.g, cw.WN, cw.WT)
        gap_rates(contact, v, cw)


@kernel
def eval_closed(contact, cs, cw, u, v, un):
    """Evaluate the laws of the corners flagged in cw.evaluated (all closed ones for nonlinear
    kinematics) at the trial (u, u̇); fills cw (see :func:`eval_contacts`). Returns the
    number of closed corners."""
    cp = contact.params
    geom = contact.corners
    g, gd, WN, WT, fc, lam, lt, der, evaluated = (
        cw.g,
        cw.gd,
        cw.WN,
        cw.WT,
        cw.fc,
        cw.lam,
        cw.lt,
        cw.der,
        cw.evaluated,
    )
    if contact.nonlinear:
        gaps_and_rates(contact, u, v, cw)
        for j in range(7):
            fc[j] = 0.0
        for c in range(4):
            lam[c] = 0.0
            lt[c] = 0.0
            evaluated[c] = g[c] <= 0.0
    else:
        contact_kinematics(u, geom, False, g, WN, WT)
    nclosed = 0
    for c in range(4):
        for k in range(7):
            der[c, k] = 0.0
        if not evaluated[c]:
            continue
        closed, lam[c], der[c, 0], der[c, 1] = normal_law(cp[c], cs[c], g[c], gd[c])
        if closed:
            nclosed += 1
        if cp[c, P_FMODE] != 0.0:
            ds = 0.0
            ut = 0.0
            for j in range(7):
                ds += WT[c, j] * (u[j] - un[j])
                ut += WT[c, j] * v[j]
            arg = ds
            if cp[c, P_FMODE] == FRICTION_CONTACT2D:
                # the element's ξ: total displacements (linear kinematics, constant W_T)
                arg = 0.0
                for j in range(7):
                    arg += WT[c, j] * u[j]
            _, lt[c], der[c, 2], der[c, 3], der[c, 4] = friction_law(cp[c], cs[c], lam[c], arg, ut)
            der[c, 5] = ds
            der[c, 6] = ut
        else:
            cs[c, S_TFT] = 0.0
        for j in range(7):
            fc[j] += WN[c, j] * lam[c] + WT[c, j] * lt[c]
    return nclosed


@kernel(inline="always")
def eval_contacts(contact, cs, cw, u, v, un):
    """Gap check (call-free, cheap); returns 0 when every corner is open (fc, lam, lt zeroed),
    −1 when :func:`eval_closed` must evaluate the laws (some g ≤ 0, or nonlinear kinematics).

    Contact forces at the trial (u, u̇); un: displacement at the start of the step; cs: the
    corner states (4, N_CS); ``cw`` (ContactWork of :mod:`deckpound.analytic.bundles`) is
    filled: g, gd (4,), fc (7,) = Σ W_Nᵀ λ_N + W_Tᵀ λ_T, lam, lt (4,), der (4, 7): per corner
    [∂λ_N/∂g, ∂λ_N/∂ġ, ∂λ_T/∂Δs, ∂λ_T/∂U_T, ∂λ_T/∂λ_N, Δs, U_T], evaluated (4,) bool, and WN,
    WT (when some corner is closed). Corners with g > 0 are open for every law and are skipped
    (the laws are not evaluated at all while every gap is open).
    """
    nonlinear = contact.nonlinear
    anyc = nonlinear
    if not nonlinear:
        geom = contact.corners
        g, gd, lam, lt, evaluated, fc = cw.g, cw.gd, cw.lam, cw.lt, cw.evaluated, cw.fc
        for c in range(4):
            gc = linear_gap(geom[c], u)
            g[c] = gc
            gd[c] = linear_gap_rate(geom[c], v)
            lam[c] = 0.0
            lt[c] = 0.0
            evaluated[c] = gc <= 0.0
            if gc <= 0.0:
                anyc = True
        for j in range(7):
            fc[j] = 0.0
    if not anyc:
        return 0
    return -1


@kernel
def contact_tangent(contact, cw, u, c2, Keff, H):
    """Add −∂F_c/∂u − c2 ∂F_c/∂u̇ to Keff (Newmark: ∂u̇/∂u = c2); H (7, 7) scratch.

    Includes the geometric term −λ_N ∂²g/∂u² for nonlinear kinematics; the derivative of W_T
    (friction, nonlinear kinematics only) is neglected (quasi-Newton; the converged solution
    is unaffected).
    """
    lam, der, evaluated, WN, WT = cw.lam, cw.der, cw.evaluated, cw.WN, cw.WT
    for c in range(4):
        if not evaluated[c]:
            continue
        kn = -(der[c, 0] + c2 * der[c, 1])
        kt = der[c, 2] + c2 * der[c, 3]
        tn = der[c, 4] * (der[c, 0] + c2 * der[c, 1])
        if kn != 0.0 or kt != 0.0 or tn != 0.0:
            for i in range(7):
                wni = WN[c, i]
                wti = WT[c, i]
                if wni == 0.0 and wti == 0.0:
                    continue
                for j in range(7):
                    Keff[i, j] += kn * wni * WN[c, j] - wti * (kt * WT[c, j] + tn * WN[c, j])
        if contact.nonlinear and lam[c] != 0.0:
            gap_hessian(u, contact.corners, c, H)
            for i in range(7):
                for j in range(7):
                    Keff[i, j] -= lam[c] * H[i, j]

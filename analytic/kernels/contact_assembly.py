"""Contact forces and tangents on the DOF from the per-corner laws (numba kernels).

The step loops of the compliance engine call these once per force evaluation: the gap check
(:func:`eval_contacts`, inlined; the laws are skipped while every corner is open), the laws of
the closed corners (:func:`eval_closed`: normal law, friction law, generalised force
F_c = Σ W_Nᵀ λ_N + W_Tᵀ λ_T), the contact part of Newton's tangent (:func:`contact_tangent`)
and the gaps and rates alone (:func:`gaps_and_rates`). The laws themselves, one corner at a
time, are :mod:`deckpound.analytic.kernels.contact_laws`; the kinematics (gaps, W_N, W_T, Hessian)
:mod:`deckpound.analytic.kernels.kinematics`. ``contact`` is the Contact bundle and ``cw`` the
ContactWork of :mod:`deckpound.analytic.bundles`.

Sizes come from the bundles: the corner count is ``len(cw.corners)`` and the DOF count
``len(dofs)``, ``dofs`` the system's size tag (``SystemArrays.dofs``); both are tuple lengths,
compile-time constants of the kernels (:func:`deckpound.analytic.nonsmooth.impulses.size_tag`), so the
short corner and DOF loops unroll as over literals while a model of another size (several deck
segments) brings its own counts.
"""

from __future__ import annotations

from numba import njit

from deckpound.analytic._jit import kernel
from deckpound.analytic.kernels.contact_laws import (
    FRICTION_CONTACT2D,
    P_FMODE,
    S_TFT,
    friction_law,
    normal_law,
)
from deckpound.analytic.kernels.kinematics import (
    contact_kinematics,
    gap_hessian,
    linear_gap_and_rate,
    linear_gap_rate,
)

__all__ = [
    "N_LAW_DERIVATIVES",
    "N_TANGENT_DERIVATIVES",
    "contact_tangent",
    "eval_closed",
    "eval_contacts",
    "gap_rates",
    "gaps_and_rates",
    "linear_rows",
]

#: Columns of ``ContactWork.der`` a corner's laws fill (:func:`eval_contacts`): ∂λ_N/∂g,
#: ∂λ_N/∂ġ, ∂λ_T/∂Δs, ∂λ_T/∂U_T, ∂λ_T/∂λ_N, Δs, U_T (a count of law quantities, not of DOF).
N_LAW_DERIVATIVES = 7
#: The first columns of ``ContactWork.der`` that :func:`contact_tangent` reads (∂λ_N/∂g,
#: ∂λ_N/∂ġ, ∂λ_T/∂Δs, ∂λ_T/∂U_T, ∂λ_T/∂λ_N): with the step, the corners evaluated and, for
#: linear kinematics, the constant rows W_N, W_T, they fix the contact part of the tangent.
N_TANGENT_DERIVATIVES = 5


@njit(cache=True, inline="always")
def _linear_gaps(u, v, corners, cw):
    """Gaps cw.g and rates cw.gd of the small-rotation kinematics
    (kinematics.contact_kinematics), the corners of ``cw.corners``."""
    g, gd = cw.g, cw.gd
    for c in range(len(cw.corners)):
        g[c], gd[c] = linear_gap_and_rate(corners[c], u, v)


@kernel(inline="always")
def gap_rates(contact, v, cw, dofs):
    """Gap rates cw.gd = W_N u̇ of the corners at the u of the last evaluation (its Jacobian
    cw.WN when nonlinear), the same operations as :func:`eval_contacts` (linear kinematics);
    :func:`gaps_and_rates` uses it for the nonlinear one. ``dofs``: the DOF size tag."""
    if not contact.nonlinear:
        for c in range(len(cw.corners)):
            cw.gd[c] = linear_gap_rate(contact.corners[c], v)
    else:
        for c in range(len(cw.corners)):
            s = 0.0
            for j in range(len(dofs)):
                s += cw.WN[c, j] * v[j]
            cw.gd[c] = s


@kernel
def gaps_and_rates(contact, u, v, cw, dofs):
    """Gaps cw.g and rates cw.gd = W_N u̇ of the corners (fills cw.WN, cw.WT when nonlinear).
    ``contact``: the Contact bundle, ``cw``: ContactWork (:mod:`deckpound.analytic.bundles`),
    ``dofs``: the DOF size tag (``SystemArrays.dofs``)."""
    if not contact.nonlinear:
        _linear_gaps(u, v, contact.corners, cw)
    else:
        contact_kinematics(u, contact.corners, True, cw.g, cw.WN, cw.WT, cw.corners, dofs)
        gap_rates(contact, v, cw, dofs)


@kernel
def linear_rows(contact, cw, u, dofs):
    """The constant rows W_N, W_T (cw.WN, cw.WT) of linear (small-rotation) kinematics, once at
    the start of a run (u: the initial displacement), before :func:`eval_closed` reads them;
    nothing for nonlinear kinematics, whose rows :func:`eval_closed` forms at every
    evaluation. ``dofs``: the DOF size tag. (The gaps it also writes are overwritten by the
    first evaluation.)"""
    if not contact.nonlinear:
        contact_kinematics(u, contact.corners, False, cw.g, cw.WN, cw.WT, cw.corners, dofs)


@kernel(inline="always")
def eval_closed(contact, cs, cw, u, v, un, dofs):
    """Evaluate the laws of the corners flagged in cw.evaluated (all closed ones for nonlinear
    kinematics) at the trial (u, u̇); fills cw (see :func:`eval_contacts`). Returns the
    number of closed corners.

    Linear kinematics: the gaps and rates are those :func:`eval_contacts` just computed at
    this (u, u̇), and the rows W_N, W_T the constant ones :func:`linear_rows` filled at the
    start of the run (neither depends on u, so they are not formed again at every evaluation).
    Inlined into the force evaluations (a call would pass the Contact and ContactWork bundles
    by value at every evaluation in contact).
    """
    corners = cw.corners
    n_dof = len(dofs)
    cp = contact.params
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
        gaps_and_rates(contact, u, v, cw, dofs)
        for j in range(n_dof):
            fc[j] = 0.0
        for c in range(len(corners)):
            lam[c] = 0.0
            lt[c] = 0.0
            evaluated[c] = g[c] <= 0.0
    nclosed = 0
    for c in range(len(corners)):
        for k in range(N_LAW_DERIVATIVES):
            der[c, k] = 0.0
        if not evaluated[c]:
            continue
        closed, lam[c], der[c, 0], der[c, 1] = normal_law(cp[c], cs[c], g[c], gd[c])
        if closed:
            nclosed += 1
        if cp[c, P_FMODE] != 0.0:
            ds = 0.0
            ut = 0.0
            for j in range(n_dof):
                ds += WT[c, j] * (u[j] - un[j])
                ut += WT[c, j] * v[j]
            arg = ds
            if cp[c, P_FMODE] == FRICTION_CONTACT2D:
                # the element's ξ: total displacements (linear kinematics, constant W_T)
                arg = 0.0
                for j in range(n_dof):
                    arg += WT[c, j] * u[j]
            _, lt[c], der[c, 2], der[c, 3], der[c, 4] = friction_law(cp[c], cs[c], lam[c], arg, ut)
            der[c, 5] = ds
            der[c, 6] = ut
        else:
            cs[c, S_TFT] = 0.0
        for j in range(n_dof):
            fc[j] += WN[c, j] * lam[c] + WT[c, j] * lt[c]
    return nclosed


@kernel(inline="always")
def eval_contacts(contact, cs, cw, u, v, un, dofs):
    """Gap check (call-free, cheap); returns 0 when every corner is open (fc, lam, lt zeroed),
    −1 when :func:`eval_closed` must evaluate the laws (some g ≤ 0, or nonlinear kinematics).

    Contact forces at the trial (u, u̇); un: displacement at the start of the step; cs: the
    corner states (n_corners, N_CS); ``cw`` (ContactWork of :mod:`deckpound.analytic.bundles`,
    n_corners = len(cw.corners)) is filled: g, gd (n_corners,), fc (n_dof,) = Σ W_Nᵀ λ_N +
    W_Tᵀ λ_T, lam, lt (n_corners,), der (n_corners, ≥ :data:`N_LAW_DERIVATIVES`): per corner
    [∂λ_N/∂g, ∂λ_N/∂ġ, ∂λ_T/∂Δs, ∂λ_T/∂U_T, ∂λ_T/∂λ_N, Δs, U_T], evaluated (n_corners,) bool,
    and WN, WT (when some corner is closed); n_dof = len(dofs), the DOF size tag. Corners with
    g > 0 are open for every law and are skipped (the laws are not evaluated at all while every
    gap is open).
    """
    nonlinear = contact.nonlinear
    anyc = nonlinear
    if not nonlinear:
        geom = contact.corners
        g, gd, lam, lt, evaluated, fc = cw.g, cw.gd, cw.lam, cw.lt, cw.evaluated, cw.fc
        for c in range(len(cw.corners)):
            gc, gd[c] = linear_gap_and_rate(geom[c], u, v)
            g[c] = gc
            lam[c] = 0.0
            lt[c] = 0.0
            evaluated[c] = gc <= 0.0
            if gc <= 0.0:
                anyc = True
        for j in range(len(dofs)):
            fc[j] = 0.0
    if not anyc:
        return 0
    return -1


@kernel
def contact_tangent(contact, cw, u, c2, Keff, H, dofs):
    """Add −∂F_c/∂u − c2 ∂F_c/∂u̇ to Keff (Newmark: ∂u̇/∂u = c2); H (n_dof, n_dof) scratch,
    n_dof = len(dofs) (the DOF size tag).

    Includes the geometric term −λ_N ∂²g/∂u² for nonlinear kinematics; the derivative of W_T
    (friction, nonlinear kinematics only) is neglected (quasi-Newton; the converged solution
    is unaffected).
    """
    lam, der, evaluated, WN, WT = cw.lam, cw.der, cw.evaluated, cw.WN, cw.WT
    n_dof = len(dofs)
    for c in range(len(cw.corners)):
        if not evaluated[c]:
            continue
        kn = -(der[c, 0] + c2 * der[c, 1])
        kt = der[c, 2] + c2 * der[c, 3]
        tn = der[c, 4] * (der[c, 0] + c2 * der[c, 1])
        if kn != 0.0 or kt != 0.0 or tn != 0.0:
            for i in range(n_dof):
                wni = WN[c, i]
                wti = WT[c, i]
                if wni == 0.0 and wti == 0.0:
                    continue
                for j in range(n_dof):
                    Keff[i, j] += kn * wni * WN[c, j] - wti * (kt * WT[c, j] + tn * WN[c, j])
        if contact.nonlinear and lam[c] != 0.0:
            gap_hessian(u, contact.corners, c, H, dofs)
            for i in range(n_dof):
                for j in range(n_dof):
                    Keff[i, j] -= lam[c] * H[i, j]

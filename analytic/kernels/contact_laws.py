"""Compliant normal contact laws and regularised / elastic-plastic friction, in numba.

One corner at a time: the engine gives the gap g (g < 0 penetration, δ = −g), its rate ġ and,
for friction, the tangential relative velocity U_T and the tangential relative displacement
increment Δs of the step; the law returns the normal force λ_N (compression > 0), the tangential
force λ_T (force on the deck along +t, i.e. +y for linear kinematics) and their derivatives for
Newton. The generalised contact force on the DOF is W_Nᵀ λ_N + W_Tᵀ λ_T (right-hand side).
Per-corner arrays have one row per corner of the plan (:func:`pack_contact`,
:func:`new_contact_state`); the kernels loop over those rows.

The laws and friction models, their codes, parameters and OpenSees counterparts are rows of
:mod:`deckpound.models.contact_laws_table`; the kernels dispatch on the named codes ``LAW_*`` and
``FRICTION_*`` derived from it, one branch per row, and a code without a branch gives a
non-finite force (the run fails; :func:`.contact_law_checks.check_kernel_branches` refuses it
before the run).

Normal laws (``scene.contact.law``), each the arithmetic of the OpenSees material the OpenSees
engine uses (strain ε = g − g₀, OpenSees gap = −g₀, so ε − gap = g):

* ``linear`` — OpenSees ``ElasticPPGap(k, Fy→∞, −g₀)``: λ = −k g for g ≤ 0, else 0
  (closed at g = 0 exactly, tangent k).
* ``kelvin-voigt`` — OpenSees ``ViscoelasticGap(k, c, −g₀)``: λ = −k g − c ġ for g < 0, else 0,
  c from :func:`deckpound.models.contact_params.kelvin_voigt_damping`. ViscoelasticGap does NOT
  clip tension: near the end of the restitution phase λ may be negative until the gap reopens
  (that is what makes the restitution exactly e for the linear oscillator). Default: this
  OpenSees-identical behaviour; ``clip=True`` (engine keyword ``kv_clip``) uses max(λ, 0).
* ``hertz`` — λ = k (−g)^n for g < 0.
* ``hertz-damp`` — λ = k δ^n (1 + D δ̇ / v⁻), D = 3(1 − e²)/4 (Lankarani–Nikravesh), clipped at 0;
  v⁻ is the approach velocity δ̇ committed at the last open state before the impact (at the
  located closure event in the adaptive integrator), floored at ``V_IMPACT_MIN``.
* ``hertzdamp`` — OpenSees ``Hertzdamp(k, ξ_n, −g₀, n)`` exactly (Muthukumar & DesRoches
  2006; Ye et al. 2009): λ = (k + ξ δ̇) δ^n for g < 0 with ξ = ξ_n k / v_i, ξ_n = 3(1 − e²)/4,
  v_i = δ̇ = −ġ of the first closed *trial* after an open committed state (recomputed at every
  Newton iteration of that step, kept afterwards; not set when δ̇ ≤ 0 there); ξ is reset when a
  trial opens after a closed commit, and is neither committed nor reverted (a material
  member). No clipping: λ < 0 near separation. It differs from ``hertz-damp`` in v_i (the
  trial rate of the first closed step, not the committed approach velocity), the clipping and
  the floor of v_i. OpenSees reports the tangent −n(k + ξδ̇)δ^(n−1) of the stress with respect
  to the strain, i.e. +n(k + ξδ̇)δ^(n−1) as ∂λ/∂g — the opposite sign of the force's
  derivative — and no damping tangent (``opensees_tangent``); Newton still converges on this
  model because the contact tangent is small against the mass term 4M/Δt².
* ``bilinear`` — OpenSees ``ImpactMaterial(K1, K2, −δ_y, −g₀)`` (Muthukumar): loading with K1
  from the committed stress, capped by the line K1 δ_y + K2 (δ − δ_y); unloading with K1, floored
  by the line K2 δ; open (0) for g ≥ 0. On the first contact step the increment is measured from
  the closure point g = 0 (continuous force); ImpactMaterial measures it from the last open
  strain, which makes the force jump at closure and Newton fail on the benchmark (OpenSees fails
  at the same step) — ``pack_contact(..., impact_opensees=True)`` reproduces that exactly. A
  zero increment keeps the previous trial stress and tangent, as in OpenSees.

Friction (``scene.contact.friction_mode``):

* ``slip`` — λ_T = −μ λ_N⁺ tanh(U_T / v₀): Coulomb without sticking.
* ``stick`` — the project's own elastic-plastic tangential spring (return mapping): trial
  λ_T = λ_T,n − k_t Δs (Δs the tangential relative displacement of the step); if
  |trial| ≤ μ λ_N⁺ stick, else slide with λ_T = μ λ_N⁺ sign(trial) (the committed force stays
  on the slip surface). The tangential force is released when the corner opens. OpenSees has
  no element with this law.
* ``contact2d`` — OpenSees ``zeroLengthContact2D`` (Wang & Sitar; ZeroLengthContact2D.cpp,
  ``formResidAndTangent`` / ``commitState``), step for step. With s = t·(u_deck corner −
  u_seat point) the total tangential relative displacement (the element's ξ, from the
  reference configuration) and s_p the committed stick point (0 initially): in contact
  (g ≤ 0, pressure p = k δ = λ_N) the trial force is λ_T = −k_t (s − s_p); Φ = |λ_T| − μ p ≤ 0
  sticks (tangent ∂λ_T/∂s = −k_t), else it slides with λ_T = μ p sign(−(s − s_p)) and the
  consistent, non-symmetric tangent ∂λ_T/∂g = μ sign · ∂p/∂g (the element's
  −μ K_n (t/|t|) T Nᵀ). The element keeps no committed force: at a commit whose last
  evaluation slid, s_p := s (so the next step's trial restarts from λ_T = 0, and the force the
  element reports after that commit is 0); a stick or open commit keeps s_p, also while the
  corner is open (the stick point is never reset on separation). The committed force stored
  in the state (``S_CFT``, the engine's ``ft`` column) is the element's force at the committed
  state, i.e. 0 after a sliding commit, as OpenSees reports it; the force that acted during the
  step (μ λ_N) enters the equations of motion and the energy work.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deckpound.analytic._jit import kernel
from deckpound.models import contact_params
from deckpound.models.contact_laws_table import CONTACT_LAW_TABLE, FRICTION_CODES, LAW_CODES
from deckpound.models.plan import Plan, plan_of
from deckpound.models.scene import Scene

__all__ = [
    "N_CP",
    "N_CS",
    "V_IMPACT_MIN",
    "contact_commit",
    "contact_revert",
    "contact_stored_energy",
    "friction_law",
    "new_contact_state",
    "normal_law",
    "pack_contact",
]

# the kernel codes, by name (numba freezes them into the compiled branches)
LAW_LINEAR = LAW_CODES["linear"]
LAW_KELVIN_VOIGT = LAW_CODES["kelvin-voigt"]
LAW_HERTZ = LAW_CODES["hertz"]
LAW_HERTZ_DAMP = LAW_CODES["hertz-damp"]
LAW_BILINEAR = LAW_CODES["bilinear"]
LAW_FLORES = LAW_CODES["flores"]
LAW_HERTZDAMP = LAW_CODES["hertzdamp"]
FRICTION_NONE = FRICTION_CODES["none"]
FRICTION_SLIP = FRICTION_CODES["slip"]
FRICTION_STICK = FRICTION_CODES["stick"]
FRICTION_CONTACT2D = FRICTION_CODES["contact2d"]
V_IMPACT_MIN = 1.0e-3  # m/s, floor of the Hunt–Crossley approach velocity


@njit(cache=True, inline="always")
def has_stick_spring(mode):
    """True for the friction codes with an elastic stick spring k_t (stick, contact2d)."""
    return mode in (FRICTION_STICK, FRICTION_CONTACT2D)


# parameters per corner (cp[c, :]): law code, k, exponent n, Kelvin–Voigt c, Hunt–Crossley
# factor, K2, δ_y, μ, friction code, k_t, v₀, clip flag, ImpactMaterial quirk flag,
# restitution e, rate-event flag (the law's ContactLaw.rate_event), OpenSees-tangent flag
(
    P_LAW,
    P_K,
    P_N,
    P_C,
    P_D,
    P_K2,
    P_DY,
    P_MU,
    P_FMODE,
    P_KT,
    P_V0,
    P_CLIP,
    P_IMPQ,
    P_E,
    P_EVENT,
    P_OTAN,
) = range(16)
N_CP = 16
# state per corner (cs[c, :]); S_CSTICK, S_TS, S_TSLIDE are contact2d's: committed stick point
# s_p, trial total tangential displacement s and the trial slide flag; S_XI: the Hertzdamp
# damping coefficient ξ, a material member that OpenSees neither commits nor reverts (set at
# the first closed trial of an impact)
(
    S_CG,
    S_CGD,
    S_CLAM,
    S_CFT,
    S_CCLOSED,
    S_CVIMP,
    S_TLAM,
    S_TTAN,
    S_TFT,
    S_TVIMP,
    S_TCLOSED,
    S_CSTICK,
    S_TS,
    S_TSLIDE,
    S_XI,
) = range(15)
N_CS = 15


def pack_contact(
    scene: Scene,
    plan: Plan | None = None,
    *,
    kv_clip: bool = False,
    impact_opensees: bool = False,
    opensees_tangent: bool = False,
) -> np.ndarray:
    """Per-corner parameter array (n_corners, N_CP) of the scene's contact law and friction,
    one row per corner of ``plan`` (default: the scene's plan, :func:`deckpound.models.plan.
    plan_of`); each corner gets its contact table's law and friction
    (:func:`deckpound.models.contact_params.corner_contacts`: a joint's own, else the scene's).

    ``impact_opensees`` keeps ImpactMaterial's first-contact quirk in the bilinear law (the
    increment taken from the last open strain, so the force jumps at closure and Newton can
    fail exactly where OpenSees fails); the default measures the first increment from the
    closure point g = 0, the continuous Muthukumar law.

    ``opensees_tangent`` (``compliance.contact_tangent = "opensees"``) gives Newton the
    tangent the OpenSees materials report instead of the law's derivatives — the same forces,
    so the converged answer differs only within the Newton tolerance, but the iterates are
    OpenSees's (round-off agreement): ViscoelasticGap (kelvin-voigt) has no damping tangent
    (∂λ/∂ġ = 0), Hertzdamp (hertz, hertzdamp) reports its stiffness with the opposite sign
    (+n(k + ξ δ̇) δ^(n−1) as ∂λ/∂g) and no damping tangent.
    """
    plan = plan_of(scene) if plan is None else plan
    cp = np.zeros((len(plan.corners), N_CP))
    cp[:, P_C] = contact_params.kelvin_voigt_damping(scene, plan)
    for row, ct in zip(cp, contact_params.corner_contacts(scene, plan), strict=True):
        law = CONTACT_LAW_TABLE[LAW_CODES[ct.law]]
        row[P_LAW] = law.code
        row[P_EVENT] = 1.0 if law.rate_event else 0.0
        row[P_E] = ct.restitution
        row[P_K] = ct.stiffness
        row[P_N] = ct.exponent
        row[P_D] = law.hysteresis(ct.restitution) if law.hysteresis is not None else 0.0
        row[P_K2] = ct.bilinear_ratio * ct.stiffness
        row[P_DY] = ct.bilinear_yield
        row[P_MU] = ct.friction
        row[P_FMODE] = FRICTION_CODES[ct.friction_mode] if ct.friction > 0.0 else 0
        row[P_KT] = ct.tangential_stiffness
        row[P_V0] = ct.slip_velocity
    cp[:, P_CLIP] = 1.0 if kv_clip else 0.0
    cp[:, P_IMPQ] = 1.0 if impact_opensees else 0.0
    cp[:, P_OTAN] = 1.0 if opensees_tangent else 0.0
    return cp


def new_contact_state(gaps0) -> np.ndarray:
    """Virgin corner states (n_corners, N_CS) with committed gaps ``gaps0`` (n_corners,)."""
    cs = np.zeros((len(gaps0), N_CS))
    cs[:, S_CG] = gaps0
    return cs


# One kernel per normal law (or family), inlined into :func:`normal_law`, which dispatches on
# the law code: the compiled dispatch is one function, as when the branches were written in
# it. Each returns (closed, λ_N, ∂λ_N/∂g, ∂λ_N/∂ġ) and writes the law's own trial members of
# the corner state; normal_law writes the trial force and the closed flag.


@kernel(inline="always")
def _linear_force(cp, g):
    """OpenSees ElasticPPGap with Fy → ∞: λ = −k g for g ≤ 0 (closed at g = 0 exactly)."""
    if g <= 0.0:
        return True, -cp[P_K] * g, -cp[P_K], 0.0
    return False, 0.0, 0.0, 0.0


@kernel(inline="always")
def _kelvin_voigt_force(cp, g, gd):
    """OpenSees ViscoelasticGap: λ = −k g − c ġ for g < 0, tension kept unless clipped
    (P_CLIP); no damping tangent with OpenSees's tangent (P_OTAN)."""
    if g < 0.0:
        lam = cp[P_K] * (-g) + cp[P_C] * (-gd)
        dg = -cp[P_K]
        dgd = -cp[P_C] if cp[P_OTAN] == 0.0 else 0.0  # ViscoelasticGap: no damping tangent
        if cp[P_CLIP] != 0.0 and lam < 0.0:
            return True, 0.0, 0.0, 0.0
        return True, lam, dg, dgd
    return False, 0.0, 0.0, 0.0


@kernel(inline="always")
def _hertz_force(cp, g):
    """λ = k δ^n for δ = −g > 0; OpenSees's tangent (P_OTAN) with Hertzdamp's sign."""
    if g < 0.0:
        n = cp[P_N]
        dlt = -g
        lam = cp[P_K] * dlt**n
        dg = -n * cp[P_K] * dlt ** (n - 1.0)
        if cp[P_OTAN] != 0.0:
            dg = -dg  # Hertzdamp's tangent sign (see hertzdamp)
        return True, lam, dg, 0.0
    return False, 0.0, 0.0, 0.0


@kernel(inline="always")
def _hertzdamp_force(cp, cs, g, gd):
    """OpenSees Hertzdamp, its arithmetic: λ = (k + ξ δ̇) δ^n, ξ = ξ_n k / v_i set at the
    first closed trial of an impact (S_XI), reset when a trial opens after a closed commit."""
    n = cp[P_N]
    if g >= 0.0:
        if cs[S_CCLOSED] != 0.0:  # "commitTangent != 0": the impact is over
            cs[S_XI] = 0.0
        return False, 0.0, 0.0, 0.0
    if cs[S_CCLOSED] == 0.0 and gd < 0.0:  # a new impact: ξ from this trial's rate
        cs[S_XI] = cp[P_D] * cp[P_K] / (-gd)
    xi = cs[S_XI]
    dlt = -g
    fac = cp[P_K] + xi * (-gd)
    lam = fac * dlt**n  # no clipping: tension near separation
    if cp[P_OTAN] != 0.0:
        return True, lam, n * fac * dlt ** (n - 1.0), 0.0  # Hertzdamp's tangent, sign as is
    return True, lam, -n * fac * dlt ** (n - 1.0), -xi * dlt**n


@kernel(inline="always")
def _hunt_crossley_force(cp, cs, g, gd):
    """Hunt–Crossley type (hertz-damp, flores): λ = k δ^n (1 + D δ̇ / v⁻) clipped at 0, D =
    cp[P_D], v⁻ the committed approach velocity at the impact (floored, kept in S_TVIMP)."""
    if g < 0.0:
        if cs[S_CCLOSED] == 0.0:
            vimp = -cs[S_CGD]
            vimp = max(vimp, V_IMPACT_MIN)
        else:
            vimp = cs[S_CVIMP]
        cs[S_TVIMP] = vimp
        n = cp[P_N]
        dlt = -g
        dn = dlt**n
        fac = 1.0 + cp[P_D] * (-gd) / vimp
        lam = cp[P_K] * dn * fac
        if lam > 0.0:
            dg = -n * cp[P_K] * dlt ** (n - 1.0) * fac
            dgd = -cp[P_K] * dn * cp[P_D] / vimp
            return True, lam, dg, dgd
        return True, 0.0, 0.0, 0.0
    return False, 0.0, 0.0, 0.0


@kernel(inline="always")
def _bilinear_stress(k1, k2, dy, g, dstrain, cstress):
    """ImpactMaterial's closed trial for a non-zero strain increment dstrain (stress = −λ,
    strain g, yield strain dy < 0, committed stress cstress): (stress, tangent), loading with
    K1 capped by the line K1 δ_y + K2 (δ − δ_y), unloading with K1 floored by the line K2 δ."""
    if dstrain < 0.0:
        lim = k1 * dy + k2 * (g - dy)
        if cstress + k1 * dstrain < lim:
            return lim, k2
        return cstress + k1 * dstrain, k1
    lim = k2 * g
    if cstress + k1 * dstrain > lim:
        return lim, k2
    return cstress + k1 * dstrain, k1


@kernel(inline="always")
def _bilinear_force(cp, cs, g):
    """OpenSees ImpactMaterial (Muthukumar), stress = −λ; the trial tangent kept in S_TTAN."""
    g_committed = cs[S_CG]
    if cp[P_IMPQ] == 0.0 and g_committed > 0.0:
        g_committed = 0.0  # first contact: load from the closure point (continuous law)
    dstrain = g - g_committed
    if g >= 0.0:
        closed = False
        stress = 0.0
        tan = 0.0
    elif dstrain < 0.0 or dstrain > 0.0:
        closed = True
        stress, tan = _bilinear_stress(cp[P_K], cp[P_K2], -cp[P_DY], g, dstrain, -cs[S_CLAM])
    else:  # OpenSees: a zero increment keeps the trial values
        closed = True
        stress = -cs[S_TLAM]
        tan = cs[S_TTAN]
    cs[S_TTAN] = tan
    return closed, -stress, -tan, 0.0


@kernel
def normal_law(cp, cs, g, gd):
    """Trial normal force of one corner. cp, cs: that corner's rows.

    Returns (closed, λ_N, ∂λ_N/∂g, ∂λ_N/∂ġ); closed is True when the corner is closed. One
    branch per law code, each the law's kernel above; a code without a branch gives a
    non-finite force.
    """
    law = int(cp[P_LAW])
    if law == LAW_LINEAR:
        closed, lam, dg, dgd = _linear_force(cp, g)
    elif law == LAW_KELVIN_VOIGT:
        closed, lam, dg, dgd = _kelvin_voigt_force(cp, g, gd)
    elif law == LAW_HERTZ:
        closed, lam, dg, dgd = _hertz_force(cp, g)
    elif law == LAW_HERTZDAMP:
        closed, lam, dg, dgd = _hertzdamp_force(cp, cs, g, gd)
    elif law in (LAW_HERTZ_DAMP, LAW_FLORES):
        closed, lam, dg, dgd = _hunt_crossley_force(cp, cs, g, gd)
    elif law == LAW_BILINEAR:
        closed, lam, dg, dgd = _bilinear_force(cp, cs, g)
    else:  # no branch for this code: fail, loudly
        closed, lam, dg, dgd = True, np.nan, np.nan, np.nan
    cs[S_TLAM] = lam
    cs[S_TCLOSED] = 1.0 if closed else 0.0
    return closed, lam, dg, dgd


@kernel
def friction_law(cp, cs, lam_n, ds, ut):
    """Trial tangential force of one corner (force on the deck along +t).

    lam_n : trial normal force; ds : tangential relative displacement increment of the step
    (stick mode) or, for contact2d, the total tangential relative displacement s (the
    element's ξ; see the module docstring); ut : tangential relative velocity (slip mode).
    Returns (state, λ_T, ∂λ_T/∂Δs, ∂λ_T/∂U_T, ∂λ_T/∂λ_N); state 0 open/no friction, 1 stick,
    2 slip.
    """
    mode = int(cp[P_FMODE])
    state = 0
    lt = 0.0
    d_ds = 0.0
    d_ut = 0.0
    d_lam = 0.0
    mu = cp[P_MU]
    if mode == FRICTION_NONE:
        pass
    elif mode == FRICTION_SLIP:
        if lam_n > 0.0:
            th = np.tanh(ut / cp[P_V0])
            lt = -mu * lam_n * th
            d_ut = -mu * lam_n * (1.0 - th * th) / cp[P_V0]
            d_lam = -mu * th
            state = 2
    elif mode == FRICTION_STICK:
        if lam_n > 0.0:
            trial = cs[S_CFT] - cp[P_KT] * ds
            lim = mu * lam_n
            if abs(trial) <= lim:
                lt = trial
                d_ds = -cp[P_KT]
                state = 1
            else:
                sg = 1.0 if trial > 0.0 else -1.0
                lt = sg * lim
                d_lam = sg * mu
                state = 2
    elif mode == FRICTION_CONTACT2D:  # zeroLengthContact2D::formResidAndTangent
        cs[S_TS] = ds
        cs[S_TSLIDE] = 0.0
        if lam_n > 0.0 or cs[S_TCLOSED] != 0.0:  # contactDetect: gap ≥ 0 (g ≤ 0)
            trial = -cp[P_KT] * (ds - cs[S_CSTICK])
            lim = mu * lam_n
            if abs(trial) - lim <= 0.0:  # Φ ≤ 0: stick
                lt = trial
                d_ds = -cp[P_KT]
                state = 1
            else:  # slide (ContactFlag = 2)
                sg = 1.0 if trial > 0.0 else -1.0
                lt = sg * lim
                d_lam = sg * mu
                state = 2
                cs[S_TSLIDE] = 1.0
    else:  # no branch for this code: fail, loudly
        lt = np.nan
        d_ds = np.nan
        d_ut = np.nan
        d_lam = np.nan
    cs[S_TFT] = lt
    return state, lt, d_ds, d_ut, d_lam


@kernel
def contact_commit(cs, g, gd, evaluated):
    """Commit the corners after a converged step; g, gd: converged gaps and rates (n_corners,)
    of the n_corners rows of ``cs``.

    ``evaluated[c]`` False means the law was skipped (corner open by a margin): its trial is the
    open state. Committed gaps are updated for every corner (the bilinear law and the impact
    velocity need them, as OpenSees updates every element every step). contact2d
    (``ZeroLengthContact2D::commitState``): a corner whose last evaluation slid moves its stick
    point to the trial s, and its committed force becomes the element's force there (0).
    """
    for c in range(cs.shape[0]):
        if not evaluated[c]:
            cs[c, S_TLAM] = 0.0
            cs[c, S_TFT] = 0.0
            cs[c, S_TCLOSED] = 0.0
            cs[c, S_TTAN] = 0.0
            cs[c, S_TSLIDE] = 0.0
        if cs[c, S_TSLIDE] != 0.0:
            cs[c, S_CSTICK] = cs[c, S_TS]
            cs[c, S_TFT] = 0.0
            cs[c, S_TSLIDE] = 0.0
        cs[c, S_CG] = g[c]
        cs[c, S_CGD] = gd[c]
        cs[c, S_CLAM] = cs[c, S_TLAM]
        cs[c, S_CFT] = cs[c, S_TFT]
        cs[c, S_CCLOSED] = cs[c, S_TCLOSED]
        cs[c, S_CVIMP] = cs[c, S_TVIMP]


@kernel
def contact_revert(cs):
    """Trial := committed (OpenSees revertToLastCommit; the bilinear tangent is kept), every
    corner (row of ``cs``)."""
    for c in range(cs.shape[0]):
        cs[c, S_TLAM] = cs[c, S_CLAM]
        cs[c, S_TFT] = cs[c, S_CFT]
        cs[c, S_TCLOSED] = cs[c, S_CCLOSED]
        cs[c, S_TVIMP] = cs[c, S_CVIMP]


@kernel
def contact_stored_energy(cp, cs):
    """Recoverable energy in the committed contact springs and stick springs of every corner
    (row of ``cs``) [kJ]."""
    e = 0.0
    for c in range(cs.shape[0]):
        law = int(cp[c, P_LAW])
        g = cs[c, S_CG]
        lam = cs[c, S_CLAM]
        if lam > 0.0 and g < 0.0:
            k = cp[c, P_K]
            if law in (LAW_LINEAR, LAW_KELVIN_VOIGT):
                e += 0.5 * k * g * g
            elif law in (LAW_HERTZ, LAW_HERTZ_DAMP, LAW_FLORES, LAW_HERTZDAMP):
                n = cp[c, P_N]
                e += k * (-g) ** (n + 1.0) / (n + 1.0)
            elif law == LAW_BILINEAR:
                # unload along K1 from (g, -lam) to the K2 line through the origin, then along it
                k2 = cp[c, P_K2]
                if k > k2:
                    gs = (k * g + lam) / (k - k2)
                    gs = min(gs, 0.0)
                else:
                    gs = g
                lam_s = -k2 * gs
                e += 0.5 * (lam + lam_s) * (gs - g) + 0.5 * k2 * gs * gs
            else:  # no branch for this code
                e = np.nan
        if has_stick_spring(cp[c, P_FMODE]) and cs[c, S_CFT] != 0.0:
            e += 0.5 * cs[c, S_CFT] ** 2 / cp[c, P_KT]
    return e

"""Contact-law parameters derived from the scene, shared by every compliance implementation.

The damping of the damped laws comes from the restitution coefficient e:

* Kelvin–Voigt (spring + dashpot), Anagnostopoulos (1988), EESD 16:
  c = 2 ζ √(k m_eff),  ζ = −ln e / √(π² + ln² e)   (ζ → 1 as e → 0).
* Hertz-damp (Hunt–Crossley type), Lankarani & Nikravesh (1990), J. Mech. Des. 112:
  F = k_h δ^n (1 + (3(1 − e²)/4) δ̇ / v⁻),  v⁻ the approach velocity when the impact starts.

m_eff of a corner is the mass the contact sees at rest: m_eff = 1 / (w_N M⁻¹ w_Nᵀ), w_N the
corner's row of ∂g_N/∂u (:meth:`deckpound.models.plan.Plan.effective_masses`).

The contact period T_c = 2π √(m_eff / k_eff) of the stiffest corner (k_eff the contact
stiffness; for the Hertz laws the secant stiffness k δ^(n−1) at δ = :data:`HERTZ_SECANT_DEPTH`)
sets the step of the fixed-step penalty engines (:func:`contact_resolving_step`): one rule,
read by the compliance clone and the OpenSees engine alike, so the two keep running the same
steps and agreeing to round-off.
"""

from __future__ import annotations

import numpy as np

from .contact_laws_table import contact_law
from .plan import Corner, Plan, plan_of
from .scene import Contact, Scene

#: penetration at which the Hertz secant stiffness is taken for the contact period [m]
HERTZ_SECANT_DEPTH = 0.01


def corner_contacts(scene: Scene, plan: Plan | None = None) -> list[Contact]:
    """The contact table of each corner of ``plan`` (default: the scene's): a joint corner's
    joint's (:meth:`~deckpound.models.scene.Scene.joint_contact`), the scene's ``contact``
    at the abutments."""
    plan = plan_of(scene) if plan is None else plan
    return [corner_contact(scene, c) for c in plan.corners]


def corner_contact(scene: Scene, corner: Corner) -> Contact:
    """The contact table of one corner of the scene's plan: its joint's
    (:meth:`~deckpound.models.scene.Scene.joint_contact`) at a joint, else the scene's."""
    return scene.joint_contact(corner.joint) if corner.joint >= 0 else scene.contact


def effective_masses(scene: Scene, plan: Plan | None = None) -> np.ndarray:
    """Effective mass of each corner contact [t]: 1 / (w_N M⁻¹ w_Nᵀ), on ``plan`` when the
    caller has the scene's plan model (default: made from the scene)."""
    return (plan_of(scene) if plan is None else plan).effective_masses()


def kelvin_voigt_ratio(e: float) -> float:
    """Damping ratio ζ giving restitution e for a linear spring-dashpot impact (Anagnostopoulos)."""
    if e <= 0.0:
        return 1.0
    le = np.log(e)
    return float(-le / np.sqrt(np.pi**2 + le**2))


def kelvin_voigt_damping(scene: Scene, plan: Plan | None = None) -> np.ndarray:
    """Dashpot of each corner of ``plan`` (default: the scene's) [kN·s/m]: c = 2 ζ(e) √(k m_eff),
    e and k of the corner's contact table (:func:`corner_contacts`)."""
    plan = plan_of(scene) if plan is None else plan
    tables = corner_contacts(scene, plan)
    z = np.array([kelvin_voigt_ratio(ct.restitution) for ct in tables])
    k = np.array([ct.stiffness for ct in tables])
    return 2.0 * z * np.sqrt(k * effective_masses(scene, plan))


def contact_period(scene: Scene, plan: Plan | None = None) -> float:
    """Period of the stiffest corner's contact oscillation, T_c = 2π √(m_eff / k_eff) [s].

    k_eff is the corner's ``stiffness`` (K1 of the bilinear law; each corner's contact table,
    :func:`corner_contacts`); for the Hertz-type laws (those whose force reads
    ``contact.exponent`` in the law table: hertz, hertz-damp, hertzdamp, flores) the secant
    stiffness k δ^(n−1) at δ = :data:`HERTZ_SECANT_DEPTH`. The shortest over the corners; NaN
    when there is no contact stiffness or no moving mass. ``plan``: the scene's plan model
    when the caller has it (default: made from the scene).
    """
    plan = plan_of(scene) if plan is None else plan
    m_eff = effective_masses(scene, plan)
    periods = []
    for ct, m in zip(corner_contacts(scene, plan), m_eff, strict=True):
        k = ct.stiffness
        if "contact.exponent" in contact_law(ct.law).params:  # λ ∝ δ^n: the Hertz-type laws
            k = k * HERTZ_SECANT_DEPTH ** (ct.exponent - 1.0)
        if k > 0 and m > 0:
            periods.append(float(2.0 * np.pi * np.sqrt(m / k)))
    return min(periods) if periods else float("nan")


def contact_resolving_step(scene: Scene, dt: float, plan: Plan | None = None) -> float:
    """The step a fixed-step penalty engine runs [s]: ``dt``, or shorter where the contact needs it.

    With n = ``run.steps_per_contact_period`` > 0 and T_c = :func:`contact_period`, a step
    dt > T_c / n is replaced by ``output_dt / ceil(output_dt / (T_c / n))`` — the longest step
    ≤ T_c / n that still divides the output step, so the stored rows stay on the output
    times — or by T_c / n itself when the output step is shorter. n = 0 keeps ``dt``.
    ``plan``: the scene's plan model when the caller has it.
    """
    n = scene.run.steps_per_contact_period
    if n <= 0.0:
        return float(dt)
    period = contact_period(scene, plan)
    if not np.isfinite(period) or dt <= period / n:
        return float(dt)
    limit = period / n
    out = scene.run.output_dt
    if out <= limit:
        return float(limit)
    return float(out / np.ceil(out / limit))

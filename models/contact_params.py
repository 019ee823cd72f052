"""Contact-law parameters derived from the scene, shared by every compliance implementation.

The damping of the damped laws comes from the restitution coefficient e:

* Kelvin–Voigt (spring + dashpot), Anagnostopoulos (1988), EESD 16:
  c = 2 ζ √(k m_eff),  ζ = −ln e / √(π² + ln² e)   (ζ → 1 as e → 0).
* Hertz-damp (Hunt–Crossley type), Lankarani & Nikravesh (1990), J. Mech. Des. 112:
  F = k_h δ^n (1 + (3(1 − e²)/4) δ̇ / v⁻),  v⁻ the approach velocity when the impact starts.

m_eff of a corner is the mass the contact sees at rest: m_eff = 1 / (w_N M⁻¹ w_Nᵀ), w_N the
corner's row of ∂g_N/∂u (:meth:`deckpound.models.plan.Plan.effective_masses`).
"""

from __future__ import annotations

import numpy as np

from .plan import plan_of
from .scene import Scene


def effective_masses(scene: Scene) -> np.ndarray:
    """Effective mass of each corner contact [t]: 1 / (w_N M⁻¹ w_Nᵀ)."""
    return plan_of(scene).effective_masses()


def kelvin_voigt_ratio(e: float) -> float:
    """Damping ratio ζ giving restitution e for a linear spring-dashpot impact (Anagnostopoulos)."""
    if e <= 0.0:
        return 1.0
    le = np.log(e)
    return float(-le / np.sqrt(np.pi**2 + le**2))


def kelvin_voigt_damping(scene: Scene) -> np.ndarray:
    """Dashpot of each corner [kN·s/m]: c = 2 ζ(e) √(k m_eff)."""
    z = kelvin_voigt_ratio(scene.contact.restitution)
    return 2.0 * z * np.sqrt(scene.contact.stiffness * effective_masses(scene))

"""Damping of the plan model: one definition every engine implements.

Rayleigh damping C = a0·M + a1·K_R with the ratio ζ matched at two frequencies
(Chopra, Dynamics of Structures, Eq. 11.4.9 with equal ratios):

    a0 = 2ζ ω_i ω_j / (ω_i + ω_j),   a1 = 2ζ / (ω_i + ω_j).

K_R is the stiffness-proportional part: a1 times the *initial* stiffness k0 of every spring of
the plan model (bents and seat springs; never the gap elements or the deck sticks) acting on
the springs' deformation rates ḋ = B u̇ − S u̇_g. The mass-proportional part a0·M acts on the
absolute velocities of the deck and seats (what OpenSees does under ``MultipleSupport``).
Explicit dashpots (the seats' identified c_x, c_θ) add to each spring's rate coefficient:

    F_damping = a0 M u̇ + Bᵀ [(β_i k0_i + c_i) ḋ_i],   β_i = a1 for the springs that carry the
    stiffness-proportional part.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import SceneError
from .plan import Plan
from .scene import Scene

__all__ = ["DampingModel", "damping_model", "rayleigh_coefficients"]


@dataclass(frozen=True)
class DampingModel:
    """The damping every engine applies (see the module docstring).

    Attributes
    ----------
    a0 : mass-proportional coefficient [1/s]; a1 : stiffness-proportional coefficient [s].
    omega : the two matched circular frequencies [rad/s] (NaN when not derived from modes).
    beta : (n_springs,) stiffness-proportional coefficient of each spring (a1 or 0) [s].
    dashpots : (n_springs,) explicit dashpots [kN·s/m, kN·m·s/rad].
    """

    a0: float
    a1: float
    omega: tuple[float, float]
    beta: np.ndarray
    dashpots: np.ndarray

    def rate_coefficients(self, plan: Plan) -> np.ndarray:
        """β_i·k0_i + c_i of every spring: the coefficient of its deformation rate [kN·s/m]."""
        return self.beta * plan.k0 + self.dashpots

    def matrix(self, plan: Plan) -> np.ndarray:
        """The constant damping matrix a0 M + Bᵀ diag(β k0 + c) B (7×7)."""
        B, _ = plan.spring_matrices
        return np.diag(self.a0 * plan.mass) + B.T @ (self.rate_coefficients(plan)[:, None] * B)


def rayleigh_coefficients(scene: Scene, plan: Plan | None = None
                          ) -> tuple[float, float, tuple[float, float]]:
    """Rayleigh a0 [1/s] and a1 [s] giving ratio ζ at ω_i and ω_j; returns (a0, a1, (ω_i, ω_j))."""
    d = scene.damping
    if d.method == "modes":
        from .mechanics import natural_modes

        omega = natural_modes(scene, plan).omega
        i, j = d.modes
        if max(i, j) > len(omega):
            raise SceneError("damping.modes",
                             f"mode numbers must be <= {len(omega)}, got {list(d.modes)}")
        wi, wj = omega[i - 1], omega[j - 1]
    else:
        wi, wj = (2.0 * np.pi * f for f in d.frequencies)
    z = d.ratio
    if z == 0.0:
        # no damping: a0 = a1 = 0 whatever the frequencies (also for a free deck, bents = [],
        # whose rigid-body modes have ω = 0 and would give 0/0)
        return 0.0, 0.0, (float(wi), float(wj))
    return 2.0 * z * wi * wj / (wi + wj), 2.0 * z / (wi + wj), (float(wi), float(wj))


def damping_model(scene: Scene, plan: Plan) -> DampingModel:
    """The scene's damping on its plan model."""
    a0, a1, omega = rayleigh_coefficients(scene, plan)
    beta = np.full(plan.n_springs, a1, dtype=float)
    return DampingModel(a0=float(a0), a1=float(a1), omega=omega, beta=beta,
                        dashpots=plan.dashpots)

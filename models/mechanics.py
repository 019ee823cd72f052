"""Linear mechanics of the 7-DOF plan model: mass, initial stiffness, contact-free modes.

The layout of the model (DOFs, springs, corners, channels) is defined once in
:mod:`deckpound.models.plan`; this module only does linear algebra on it. Names of that
layout are re-exported here for the callers that import them from this module.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .plan import (
    DECK_THETA,
    DECK_X,
    DECK_Y,
    DOF_NAMES,
    N_DOF,
    SEAT_THETA,
    SEAT_X,
    Plan,
    plan_of,
    support_channels,
)
from .scene import Scene

__all__ = [
    "DECK_THETA",
    "DECK_X",
    "DECK_Y",
    "DOF_NAMES",
    "N_DOF",
    "SEAT_THETA",
    "SEAT_X",
    "Modes",
    "initial_stiffness",
    "mass_matrix",
    "natural_modes",
    "rayleigh_coefficients",
    "spring_matrices",
    "support_channels",
]


def mass_matrix(scene: Scene) -> np.ndarray:
    """Diagonal 7×7 mass matrix [t, t·m²]; masses at the seats' pivots and the deck centre."""
    return plan_of(scene).mass_matrix


def spring_matrices(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """(B, S): spring deformations d = B u − S u_g (see :attr:`Plan.spring_matrices`)."""
    return plan_of(scene).spring_matrices


def initial_stiffness(scene: Scene) -> np.ndarray:
    """K0 = Bᵀ diag(k0) B: the elastic stiffness of bents and seats (contact excluded)."""
    return plan_of(scene).initial_stiffness


@dataclass(frozen=True)
class Modes:
    """Natural modes of the contact-free elastic model (ascending frequency)."""

    omega: np.ndarray  # rad/s
    shapes: np.ndarray  # (7, 7), columns mass-normalised

    @property
    def periods(self) -> np.ndarray:
        """2π/ω [s]; inf for a rigid-body mode (ω = 0, e.g. a deck without bents)."""
        with np.errstate(divide="ignore"):
            return 2.0 * np.pi / self.omega

    @property
    def frequencies(self) -> np.ndarray:
        return self.omega / (2.0 * np.pi)


def natural_modes(scene: Scene, plan: Plan | None = None) -> Modes:
    """Solve K0 φ = ω² M φ (generalised symmetric eigenproblem).

    M is diagonal (lumped masses and inertias), so the problem is reduced to the standard one
    of M^-½ K0 M^-½ and solved by numpy (``scipy.linalg`` costs 0.3–0.5 s to import, more
    than a compliance run); the shapes φ = M^-½ v are mass-normalised.
    """
    plan = plan if plan is not None else plan_of(scene)
    m = np.diag(plan.mass_matrix)
    if np.count_nonzero(plan.mass_matrix - np.diag(m)) or not np.all(m > 0):
        raise ValueError("natural_modes expects a positive diagonal mass matrix")
    s = 1.0 / np.sqrt(m)
    w2, v = np.linalg.eigh(s[:, None] * plan.initial_stiffness * s[None, :])
    phi = s[:, None] * v
    return Modes(omega=np.sqrt(np.maximum(w2, 0.0)), shapes=phi)


def rayleigh_coefficients(scene: Scene) -> tuple[float, float, tuple[float, float]]:
    """Rayleigh a0 [1/s], a1 [s] and the matched frequencies (see :mod:`.damping`)."""
    from .damping import rayleigh_coefficients as _rc

    return _rc(scene)

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
    SEAT_THETA,
    SEAT_X,
    Plan,
    plan_of,
)
from .scene import Scene

__all__ = [
    "ENERGY_GROUPS",
    "Modes",
    "energy_groups",
    "energy_shares",
    "initial_stiffness",
    "mass_matrix",
    "mode_label",
    "mode_labels",
    "natural_modes",
    "spring_matrices",
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


#: the parts a mode's kinetic energy is shared among: (key, label in a mode's name, DOFs)
ENERGY_GROUPS = (
    ("deck_x", "deck x", (DECK_X,)),
    ("deck_y", "deck y", (DECK_Y,)),
    ("deck_theta", "deck θ (torsion)", (DECK_THETA,)),
    ("seats", "seats", (*SEAT_X, *SEAT_THETA)),
)


def energy_groups(plan: Plan) -> tuple[tuple[str, str, tuple[int, ...]], ...]:
    """:data:`ENERGY_GROUPS` of ``plan``: each deck segment's x, y and θ, then the seats (a
    one-segment deck: :data:`ENERGY_GROUPS` itself)."""
    if len(plan.segments) == 1:
        return ENERGY_GROUPS
    groups = []
    for seg in plan.segments:
        x, y, th = seg.dofs
        groups += [
            (f"{seg.name}_x", f"{seg.name} x", (x,)),
            (f"{seg.name}_y", f"{seg.name} y", (y,)),
            (f"{seg.name}_theta", f"{seg.name} θ (torsion)", (th,)),
        ]
    return (*groups, ENERGY_GROUPS[-1])


#: a share below this is left out of a mode's label (the dominant share is always named)
LABEL_SHARE_MIN = 0.05


def energy_shares(shapes: np.ndarray, masses: np.ndarray, groups=ENERGY_GROUPS) -> np.ndarray:
    """Kinetic-energy shares of each mode among ``groups`` (:data:`ENERGY_GROUPS`, or
    :func:`energy_groups` of a plan), shape (n_groups, n_modes).

    A mode φ vibrating at ω carries the kinetic energy ½ ω² φᵀ M φ at its peak velocity; with
    M diagonal its DOF i holds ½ ω² M_ii φ_i², so the share of a group G is
    Σ_{i∈G} M_ii φ_i² / φᵀ M φ (dimensionless; each column sums to 1). This names a mode by
    what moves, which the largest entry of φ does not: the deck's rotation θ [rad] and its
    translations [m] are not comparable, and a seat's light mass moves far for little energy.

    ``shapes``: (n_dof, n) columns in the plan's DOF order (any normalisation); ``masses``:
    the n_dof diagonal masses [t, t·m²] (``np.diag`` of :func:`mass_matrix`).
    """
    phi = np.asarray(shapes, dtype=float)
    m = np.asarray(masses, dtype=float)
    n_dof = 1 + max(d for _, _, dofs in groups for d in dofs)
    if phi.ndim != 2 or phi.shape[0] != n_dof or m.shape != (n_dof,):
        raise ValueError(
            f"energy_shares expects shapes ({n_dof}, n) and {n_dof} masses, got {phi.shape} "
            f"and {m.shape}"
        )
    energy = m[:, None] * phi**2
    total = energy.sum(axis=0)
    if not np.all(total > 0):
        raise ValueError("energy_shares: a mode shape has no kinetic energy (all zero)")
    return np.array([energy[list(dofs)].sum(axis=0) for _, _, dofs in groups]) / total


def mode_label(shares: np.ndarray, groups=ENERGY_GROUPS) -> str:
    """'deck θ (torsion) 68 %, deck y 31 %': the groups by falling share, the dominant one
    first, others from :data:`LABEL_SHARE_MIN` up (``shares``: one column of
    :func:`energy_shares`)."""
    order = np.argsort(-np.asarray(shares), kind="stable")
    named = [k for k in order if k == order[0] or shares[k] >= LABEL_SHARE_MIN]
    return ", ".join(f"{groups[k][1]} {100 * shares[k]:.0f} %" for k in named)


def mode_labels(shapes: np.ndarray, masses: np.ndarray, groups=ENERGY_GROUPS) -> list[str]:
    """:func:`mode_label` of every mode (columns of ``shapes``; see :func:`energy_shares`)."""
    shares = energy_shares(shapes, masses, groups)
    return [mode_label(shares[:, k], groups) for k in range(shares.shape[1])]

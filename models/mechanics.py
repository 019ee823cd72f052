"""Linear mechanics of the 7-DOF plan model, shared by every engine.

DOFs (paper Fig. 1b,c): u = [x₁, θ₁, x₂, θ₂, x_d, y_d, θ_d] — seat 1 (left), seat 2 (right),
deck. Units: m, rad, t, t·m², kN/m, kN·m/rad.

The deck point above bent b (at x_b, 0 in deck coordinates) moves by
(x_d, y_d + x_b θ_d) for small rotations; a bent spring deforms by that point's displacement
minus its shake table's. A seat spring deforms by (x_s − x_actuator, θ_s). This module gives
the matrices of those relations, the initial (elastic) stiffness K0 of bents and seats, the
mass matrix, the contact-free natural modes, and the Rayleigh coefficients that every engine
uses: C = a0·M + a1·K0 (DESIGN: mass part on absolute velocities, stiffness part on spring
deformation rates).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from .scene import Scene

DOF_NAMES = ("seat1_x", "seat1_theta", "seat2_x", "seat2_theta", "deck_x", "deck_y", "deck_theta")
N_DOF = 7
SEAT_X = (0, 2)
SEAT_THETA = (1, 3)
DECK_X, DECK_Y, DECK_THETA = 4, 5, 6


def support_channels(scene: Scene) -> tuple[str, ...]:
    """Names of the support motion channels, in engine order: bents (x, y), then seats (x)."""
    names = []
    for b in scene.bents:
        names += [f"{b.name}_x", f"{b.name}_y"]
    return tuple(names) + ("seat1_x", "seat2_x")


def mass_matrix(scene: Scene) -> np.ndarray:
    """Diagonal 7×7 mass matrix [t, t·m²]; masses at the seats' reference points and deck centre."""
    s1, s2, d = scene.seats[0], scene.seats[1], scene.deck
    return np.diag([s1.mass, s1.inertia, s2.mass, s2.inertia, d.mass, d.mass, d.inertia])


def spring_matrices(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Kinematic matrices of the springs: deformation = B @ u − S @ support_displacement.

    Springs in order: for each bent (x, y); then seat1 x, seat1 θ, seat2 x, seat2 θ.
    Support channels as in :func:`support_channels`.

    Returns
    -------
    B : (n_springs, 7) array, S : (n_springs, n_channels) array.
    """
    nb = len(scene.bents)
    ns = 2 * nb + 4
    nch = 2 * nb + 2
    B = np.zeros((ns, N_DOF))
    S = np.zeros((ns, nch))
    for i, xb in enumerate(scene.bent_x):
        B[2 * i, DECK_X] = 1.0
        B[2 * i + 1, DECK_Y] = 1.0
        B[2 * i + 1, DECK_THETA] = xb
        S[2 * i, 2 * i] = 1.0
        S[2 * i + 1, 2 * i + 1] = 1.0
    for j in range(2):
        B[2 * nb + 2 * j, SEAT_X[j]] = 1.0
        B[2 * nb + 2 * j + 1, SEAT_THETA[j]] = 1.0
        S[2 * nb + 2 * j, 2 * nb + j] = 1.0
    return B, S


def spring_stiffness(scene: Scene) -> np.ndarray:
    """Initial stiffness of each spring (bents x, y; seats x, θ) [kN/m, kN·m/rad]."""
    k = []
    for b in scene.bents:
        k += [b.x.stiffness, b.y.stiffness]
    for s in scene.seats:
        k += [s.kx, s.ktheta]
    return np.array(k)


def spring_damping(scene: Scene) -> np.ndarray:
    """Explicit dashpot of each spring (only the seats have one) [kN·s/m, kN·m·s/rad]."""
    c = [0.0] * (2 * len(scene.bents))
    for s in scene.seats:
        c += [s.cx, s.ctheta]
    return np.array(c)


def initial_stiffness(scene: Scene) -> np.ndarray:
    """K0 = Bᵀ diag(k0) B: the elastic stiffness of bents and seats (contact excluded)."""
    B, _ = spring_matrices(scene)
    return B.T @ (spring_stiffness(scene)[:, None] * B)


@dataclass(frozen=True)
class Modes:
    """Natural modes of the contact-free elastic model (ascending frequency)."""

    omega: np.ndarray      # rad/s
    shapes: np.ndarray     # (7, 7), columns mass-normalised

    @property
    def periods(self) -> np.ndarray:
        return 2.0 * np.pi / self.omega

    @property
    def frequencies(self) -> np.ndarray:
        return self.omega / (2.0 * np.pi)


def natural_modes(scene: Scene) -> Modes:
    """Solve K0 φ = ω² M φ (generalised symmetric eigenproblem)."""
    w2, phi = scipy.linalg.eigh(initial_stiffness(scene), mass_matrix(scene))
    return Modes(omega=np.sqrt(np.maximum(w2, 0.0)), shapes=phi)


def rayleigh_coefficients(scene: Scene) -> tuple[float, float, tuple[float, float]]:
    """Rayleigh a0 [1/s] and a1 [s] giving ratio ζ at ω_i and ω_j.

    a0 = 2ζ ω_i ω_j / (ω_i + ω_j),  a1 = 2ζ / (ω_i + ω_j)  (Chopra, Dynamics of Structures,
    Eq. 11.4.9 with equal ratios). Returns (a0, a1, (ω_i, ω_j)).
    """
    d = scene.damping
    if d.method == "modes":
        omega = natural_modes(scene).omega
        i, j = d.modes
        if max(i, j) > len(omega):
            from .errors import SceneError
            raise SceneError("damping.modes", f"mode numbers must be <= {len(omega)}, got {list(d.modes)}")
        wi, wj = omega[i - 1], omega[j - 1]
    else:
        wi, wj = (2.0 * np.pi * f for f in d.frequencies)
    z = d.ratio
    return 2.0 * z * wi * wj / (wi + wj), 2.0 * z / (wi + wj), (float(wi), float(wj))

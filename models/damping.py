"""Damping of the plan model: one definition every engine implements.

Rayleigh coefficients with the ratio ζ matched at two frequencies (Chopra, Dynamics of
Structures, Eq. 11.4.9 with equal ratios):

    a0 = 2ζ ω_i ω_j / (ω_i + ω_j),   a1 = 2ζ / (ω_i + ω_j)

(``damping.method = "none"``: a0 = a1 = 0; the explicit dashpots still act). The scene's
``damping`` table chooses (:class:`deckpound.models.scene.Damping`):

* ``members`` — the springs whose deformation rates carry the stiffness-proportional part:
  ``bents`` (default), ``bents+seats`` (the behaviour before issue 12), ``none``. Gap elements
  and deck sticks never carry it.
* ``stiffness`` — which stiffness multiplies a1 (OpenSees ``rayleigh αM βK βKinit βKc`` with
  ``-doRayleigh 1`` on the chosen zeroLength elements, Element.cpp / ZeroLength.cpp):
  ``initial`` k0 (βKinit); ``current`` the trial tangent k_t of the Newton iteration (βK: the
  damping force β k_t ḋ and the Newton tangent's γ/(βΔt)·β k_t both use the tangent at the
  last trial state; no derivative of k_t enters the tangent); ``committed`` the tangent k_c
  stored at the last commit (βKc: ``Element::commitState`` copies the trial tangent before
  the materials commit; k_c = k0 before the first commit).
* ``mass`` — the mass-proportional part a0 M acts on ``absolute`` velocities (OpenSees's
  global αM under MultipleSupport) or on velocities ``relative`` to the supports: the deck's x
  and y relative to each bent table (a0 m/n to each of the n tables, so the total is
  a0 m (u̇ − mean table velocity)), its rotation absolute (the tables do not rotate, so a0 I/n
  to each table's fixed rotation), each seat's x relative to its actuator and its rotation
  absolute. These relative parts are dashpots between a DOF and a support channel
  (:class:`MassDamper`); OpenSees builds them as zeroLength Viscous elements from support
  reference nodes that follow the tables' imposed motion.

The damping force on the 7 DOF is then

    F_d = a0_abs M u̇ + Σ_dampers c_m (u̇_j − u̇_g,ch) e_j
          + Bᵀ [(β0_i k0_i + βK_i k_t,i + βKc_i k_c,i + c_i) ḋ_i],   ḋ = B u̇ − S u̇_g,

with β0, βK, βKc = a1 or 0 per spring as chosen and c_i the explicit dashpots (the seats'
identified c_x, c_θ; ``bents[i].cx``, ``cy``, 0 unless given — OpenSees: Viscous zeroLength
elements beside the springs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import SceneError
from .mechanics import natural_modes
from .plan import SEAT_THETA, SEAT_X, Plan
from .scene import Scene

__all__ = [
    "DampingModel",
    "MassDamper",
    "damping_model",
    "rayleigh_coefficients",
    "refuse_tangent_damping",
    "tangent_dependent",
]


@dataclass(frozen=True)
class MassDamper:
    """A mass-proportional dashpot on velocities relative to a support (``mass = relative``).

    dof : the DOF index (0..6); channel : support channel index (−1: a support that does not
    move in that DOF, i.e. a rotation); c : coefficient a0·m/n [kN·s/m or kN·m·s/rad].
    """

    dof: int
    channel: int
    c: float


@dataclass(frozen=True)
class DampingModel:
    """The damping every engine applies (see the module docstring).

    Attributes
    ----------
    a0 : mass-proportional coefficient [1/s]; a1 : stiffness-proportional coefficient [s].
    omega : the two matched circular frequencies [rad/s] (NaN when ``method = none``).
    beta : (n_springs,) coefficient of the initial stiffness k0 per spring (a1 or 0) [s].
    beta_current, beta_committed : (n_springs,) coefficients of the trial and the committed
        tangent per spring [s].
    dashpots : (n_springs,) explicit dashpots [kN·s/m, kN·m·s/rad].
    mass : ``"absolute"`` or ``"relative"``; mass_dampers : the relative part's dashpots.
    members, stiffness : the scene's choices (for messages and logs).
    damped : (n_springs,) True for the springs the scene's ``members`` name: those that
        carry the stiffness-proportional part (whatever a1 is; OpenSees ``-doRayleigh 1``).
    """

    a0: float
    a1: float
    omega: tuple[float, float]
    beta: np.ndarray
    dashpots: np.ndarray
    beta_current: np.ndarray | None = None
    beta_committed: np.ndarray | None = None
    mass: str = "absolute"
    mass_dampers: tuple[MassDamper, ...] = ()
    members: str = "bents+seats"
    stiffness: str = "initial"
    damped: np.ndarray | None = None

    @property
    def a0_absolute(self) -> float:
        """The coefficient of a0 M u̇ on absolute velocities (0 when the mass part is relative)."""
        return self.a0 if self.mass == "absolute" else 0.0

    @property
    def tangent_dependent(self) -> bool:
        """True when some spring is damped on its current or committed tangent."""
        return any(
            b is not None and np.any(b != 0.0) for b in (self.beta_current, self.beta_committed)
        )

    def rate_coefficients(self, plan: Plan) -> np.ndarray:
        """β0_i·k0_i + c_i of every spring: its constant deformation-rate coefficient [kN·s/m]."""
        return self.beta * plan.k0 + self.dashpots

    def matrix(self, plan: Plan) -> np.ndarray:
        """The damping matrix at the initial state (k_t = k_c = k0), 7×7 [kN·s/m]:
        a0_abs M + Σ c_m e_j e_jᵀ + Bᵀ diag(β0 k0 + βK k0 + βKc k0 + c) B."""
        B, _ = plan.spring_matrices
        rate = self.rate_coefficients(plan)
        for b in (self.beta_current, self.beta_committed):
            if b is not None:
                rate = rate + b * plan.k0
        C = np.diag(self.a0_absolute * plan.mass) + B.T @ (rate[:, None] * B)
        for m in self.mass_dampers:
            C[m.dof, m.dof] += m.c
        return C


def rayleigh_coefficients(
    scene: Scene, plan: Plan | None = None
) -> tuple[float, float, tuple[float, float]]:
    """Rayleigh a0 [1/s] and a1 [s] giving ratio ζ at ω_i and ω_j; returns (a0, a1, (ω_i, ω_j)).

    ``method = none``: (0, 0, (nan, nan))."""
    d = scene.damping
    if d.method == "none":
        return 0.0, 0.0, (float("nan"), float("nan"))
    if d.method == "modes":
        omega = natural_modes(scene, plan).omega
        i, j = d.modes
        if max(i, j) > len(omega):
            raise SceneError(
                "damping.modes", f"mode numbers must be <= {len(omega)}, got {list(d.modes)}"
            )
        wi, wj = omega[i - 1], omega[j - 1]
    else:
        wi, wj = (2.0 * np.pi * f for f in d.frequencies)
    z = d.ratio
    if z == 0.0:
        # no damping: a0 = a1 = 0 whatever the frequencies (also for a free deck, bents = [],
        # whose rigid-body modes have ω = 0 and would give 0/0)
        return 0.0, 0.0, (float(wi), float(wj))
    return 2.0 * z * wi * wj / (wi + wj), 2.0 * z / (wi + wj), (float(wi), float(wj))


def _members_mask(scene: Scene, plan: Plan) -> np.ndarray:
    """Which plan springs carry the stiffness-proportional part (bent springs are the first
    ``plan.n_bent_springs`` rows, the seat springs the rest)."""
    members = scene.damping.members
    on = np.zeros(plan.n_springs, dtype=bool)
    if members in ("bents", "bents+seats"):
        on[: plan.n_bent_springs] = True
    if members == "bents+seats":
        on[plan.n_bent_springs :] = True
    return on


def relative_mass_dampers(plan: Plan, a0: float) -> tuple[MassDamper, ...]:
    """The dashpots of the mass-proportional part on relative velocities (module docstring):
    each deck segment to the tables of its bents (x, y and the table's fixed rotation; a
    segment on no bent to every table), each seat to its actuator (x, and the actuator's fixed
    rotation). Without bents the deck part acts on absolute velocities (one dashpot to a fixed
    point per DOF)."""
    out: list[MassDamper] = []
    for seg in plan.segments:
        tx = plan.segment_table_channels(seg.index, "x")
        ty = plan.segment_table_channels(seg.index, "y")
        n = len(tx)
        sx, sy, st = seg.dofs
        for dof, chans in ((sx, tx), (sy, ty), (st, [-1] * n)):
            if n == 0:
                out.append(MassDamper(dof, -1, a0 * plan.mass[dof]))
                continue
            for ch in chans:
                out.append(MassDamper(dof, ch, a0 * plan.mass[dof] / n))
    for seat in range(2):
        ch = plan.channels.index(f"seat{seat + 1}_x")
        out.append(MassDamper(SEAT_X[seat], ch, a0 * plan.mass[SEAT_X[seat]]))
        out.append(MassDamper(SEAT_THETA[seat], -1, a0 * plan.mass[SEAT_THETA[seat]]))
    return tuple(out)


def tangent_dependent(scene: Scene) -> bool:
    """True when the scene's stiffness-proportional damping uses a tangent that changes during
    the run (``stiffness`` committed or current on some members with a non-zero ratio)."""
    d = scene.damping
    return d.stiffness != "initial" and d.members != "none" and d.method != "none" and d.ratio > 0.0


def refuse_tangent_damping(scene: Scene, engine: str, why: str) -> None:
    """SceneError for an engine that implements only initial-stiffness damping."""
    if tangent_dependent(scene):
        raise SceneError(
            "damping.stiffness",
            f"the {engine} engine cannot damp on the "
            f"{scene.damping.stiffness} tangent ({why}); use stiffness = "
            "'initial', or the compliance engine's newmark integrator or the "
            "OpenSees engine",
        )


def damping_model(scene: Scene, plan: Plan) -> DampingModel:
    """The scene's damping on its plan model."""
    d = scene.damping
    a0, a1, omega = rayleigh_coefficients(scene, plan)
    on = _members_mask(scene, plan)
    coef = np.where(on, a1, 0.0).astype(float)
    zero = np.zeros(plan.n_springs)
    beta = coef if d.stiffness == "initial" else zero
    beta_current = coef if d.stiffness == "current" else zero.copy()
    beta_committed = coef if d.stiffness == "committed" else zero.copy()
    dampers = relative_mass_dampers(plan, a0) if d.mass == "relative" and a0 != 0.0 else ()
    return DampingModel(
        a0=float(a0),
        a1=float(a1),
        omega=omega,
        beta=beta,
        dashpots=plan.dashpots,
        beta_current=beta_current,
        beta_committed=beta_committed,
        mass=d.mass,
        mass_dampers=dampers,
        members=d.members,
        stiffness=d.stiffness,
        damped=on,
    )

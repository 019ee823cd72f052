"""A deck that starts displaced or moving, in OpenSees (``scene.initial``).

OpenSees has no initial-condition command for this model: the deck's nodes are given the
rigid-body displacement and velocity of the initial state with ``setNodeDisp`` /
``setNodeVel -commit``, and the equilibrium acceleration of that state with ``setNodeAccel``
(Newmark otherwise starts from ü = 0, right only from rest), as the analytic engines start.
:func:`refuse_initial_displacement` names what such a start needs. Functions of an ``ops``
session (:class:`deckpound.opensees_build.ops.OpsSession`), called by
:func:`deckpound.opensees_build.engine.build`.
"""

from __future__ import annotations

import numpy as np

from deckpound.models.damping import DampingModel
from deckpound.models.errors import SceneError
from deckpound.models.plan import DECK_THETA, DECK_X, DECK_Y, Plan, plan_of
from deckpound.models.scene import Scene


def _rigid_body_field(ops, set_node, prefixes: tuple[str, ...], cx, cy, ct) -> None:
    """Set, committed, the rigid-body field (cx − ct·y, cy + ct·x, ct) of the deck at the
    node ``deck`` and every node named with one of ``prefixes``, at the node's coordinates
    (``set_node``: ops.setNodeDisp, setNodeVel or setNodeAccel)."""
    raw = ops.raw
    for name, tag in ops.tags("node").items():
        if name == "deck" or name.startswith(prefixes):
            x, y = raw.nodeCoord(tag)
            for dof, value in ((1, cx - ct * y), (2, cy + ct * x), (3, ct)):
                set_node(tag, dof, value, "-commit")


def set_initial_displacement(ops, scene: Scene) -> None:
    """Give every node of the deck the rigid-body displacement of ``scene.initial.deck`` =
    (x, y, θ) in the small-rotation map of the rigidLinks (x − θ y, y + θ x, θ at the node's
    coordinates), committed, before the analysis starts: the retained centre node and the
    constrained corner and bent nodes alike, so the Transformation handler (which updates
    constrained nodes incrementally in 3.7) starts from a consistent state. Rigid mode only."""
    dx, dy, th = scene.initial.deck
    if not (dx or dy or th):
        return
    ops.comment(f"initial deck displacement {dx!r} m, {dy!r} m, {th!r} rad")
    _rigid_body_field(ops, ops.setNodeDisp, ("deck ",), dx, dy, th)


def set_initial_acceleration(ops, scene: Scene, motion, plan: Plan, damping: DampingModel) -> None:
    """Start Newmark from the equilibrium acceleration of the initial state, as the clone does
    (a₀ = M⁻¹(−Bᵀ[k0∘d₀ + crate∘ḋ₀] − a0·M u̇₀), d₀ = B u₀ − S u_g(0)); OpenSees otherwise
    starts from ü = 0, right only from rest. Springs are elastic at the start and every gap
    open (the engine refuses other initial states), so these forces are exact. Deck nodes get
    the rigid-body acceleration (a_x − α y, a_y + α x, α) of the rigidLink map; the seats
    start at rest with their actuators, unloaded. ``plan``, ``damping``: the model built."""
    if scene.initial.at_rest:
        return
    u0, v0 = plan.initial_state(scene.initial)
    B, S = plan.spring_matrices
    ug = np.array([motion.disp[ch][0] for ch in plan.channels])
    vg = np.array([motion.vel[ch][0] for ch in plan.channels])
    rate = damping.rate_coefficients(plan)
    f = B.T @ (plan.k0 * (B @ u0 - S @ ug) + rate * (B @ v0 - S @ vg))
    acc = -(f + damping.a0 * plan.mass * v0) / plan.mass
    ax, ay, al = acc[DECK_X], acc[DECK_Y], acc[DECK_THETA]
    if not (ax or ay or al):
        return
    ops.comment(
        f"initial deck acceleration {ax!r} m/s2, {ay!r} m/s2, {al!r} rad/s2 "
        "(equilibrium of the initial state)"
    )
    _rigid_body_field(ops, ops.setNodeAccel, ("deck ",), ax, ay, al)


def set_initial_velocity(ops, scene: Scene) -> None:
    """Give every node of the deck the rigid-body velocity of ``scene.initial.deck_velocity``
    (v_x − ω y, v_y + ω x at the node's coordinates), committed, before the analysis starts.
    OpenSees then starts Newmark with zero acceleration, as from rest."""
    vx, vy, om = scene.initial.deck_velocity
    if not (vx or vy or om):
        return
    ops.comment(f"initial deck velocity {vx!r} m/s, {vy!r} m/s, {om!r} rad/s")
    _rigid_body_field(ops, ops.setNodeVel, ("deck ", "stick "), vx, vy, om)


def refuse_initial_displacement(scene: Scene, settings) -> None:
    """What a displaced start needs in OpenSees (:func:`set_initial_displacement`): rigid
    mode (every deck node is set by the rigid-body map; a stick deck would start with
    unbalanced sticks), every gap open and every bent elastic at the start (the equilibrium
    acceleration is then exact, :func:`set_initial_acceleration`)."""
    where = f"the OpenSees engine starts the deck displaced (got {list(scene.initial.deck)}) "
    if settings.mode != "rigid":
        raise SceneError(
            "initial.deck",
            where + "in rigid mode only (opensees.mode = "
            "'rigid'): in stick mode the sticks would start deformed; use "
            "rigid mode, the compliance or the nonsmooth engine",
        )
    plan = plan_of(scene)
    u0, _ = plan.initial_state(scene.initial)
    gaps = plan.linear_gaps(u0)[0]
    if np.any(gaps <= 0.0):
        raise SceneError(
            "initial.deck",
            where + "only with every gap open at the start; it "
            f"closes gap(s) {[c.name for c, g in zip(plan.corners, gaps) if g <= 0]}",
        )
    B, _ = plan.spring_matrices
    d0 = B @ u0
    for s, d in zip(plan.springs, d0):
        if s.kind == "takeda" and abs(d) >= s.takeda[1]:
            raise SceneError(
                "initial.deck",
                where + f"only with the bents elastic at the "
                f"start; spring {s.name} starts at {d:.4g} m, beyond its yield "
                f"displacement {s.takeda[1]:.4g} m",
            )

"""A deck that starts displaced or moving, in OpenSees (``scene.initial``, or each deck
segment's ``displacement`` and ``velocity``: the plan's :class:`~deckpound.models.plan.SegmentPlan`).

OpenSees has no initial-condition command for this model: the deck's nodes are given the
rigid-body displacement and velocity of the initial state with ``setNodeDisp`` /
``setNodeVel -commit``, and the equilibrium acceleration of that state with ``setNodeAccel``
(Newmark otherwise starts from ü = 0, right only from rest), as the analytic engines start. A
deck of segments sets each segment's field on the nodes that move with it
(``ModelInfo.body_nodes``), about its own centre.
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


def _segment_fields(ops, set_node, info, fields, what: str, unit: str) -> None:
    """Set, committed, each deck segment's rigid-body field (cx − ct·(y − Y), cy + ct·(x − X),
    ct) at every node that moves with it (``info.body_nodes``: its centre (X, Y) at rest and
    its nodes), ``fields`` one (cx, cy, ct) per segment; a segment whose field is zero is left
    alone."""
    raw = ops.raw
    for k, ((ox, oy), nodes) in enumerate(info.body_nodes):
        cx, cy, ct = (float(v) for v in fields[k])
        if not (cx or cy or ct):
            continue
        ops.comment(f"initial {what} of segment {k + 1}: {cx!r}, {cy!r}, {ct!r} {unit}")
        for tag in nodes:
            x, y = raw.nodeCoord(tag)
            rx, ry = x - ox, y - oy
            for dof, value in ((1, cx - ct * ry), (2, cy + ct * rx), (3, ct)):
                set_node(tag, dof, value, "-commit")


def _segments(plan: Plan) -> bool:
    return len(plan.segments) > 1


def set_initial_displacement(ops, scene: Scene, plan: Plan | None = None, info=None) -> None:
    """Give every node of the deck the rigid-body displacement of ``scene.initial.deck`` =
    (x, y, θ) in the small-rotation map of the rigidLinks (x − θ y, y + θ x, θ at the node's
    coordinates), committed, before the analysis starts: the retained centre node and the
    constrained corner and bent nodes alike, so the Transformation handler (which updates
    constrained nodes incrementally in 3.7) starts from a consistent state. Rigid mode only.
    A deck of segments (``plan`` and the built model's ``info``): each segment's
    ``displacement`` about its own centre."""
    if plan is not None and _segments(plan):
        fields = [seg.displacement for seg in plan.segments]
        _segment_fields(ops, ops.setNodeDisp, info, fields, "displacement", "m, m, rad")
        return
    dx, dy, th = scene.initial.deck
    if not (dx or dy or th):
        return
    ops.comment(f"initial deck displacement {dx!r} m, {dy!r} m, {th!r} rad")
    _rigid_body_field(ops, ops.setNodeDisp, ("deck ",), dx, dy, th)


def set_initial_acceleration(
    ops, scene: Scene, motion, plan: Plan, damping: DampingModel, info=None
) -> None:
    """Start Newmark from the equilibrium acceleration of the initial state, as the clone does
    (a₀ = M⁻¹(−Bᵀ[k0∘d₀ + crate∘ḋ₀] − a0·M u̇₀), d₀ = B u₀ − S u_g(0)); OpenSees otherwise
    starts from ü = 0, right only from rest. Springs are elastic at the start and every gap
    open (the engine refuses other initial states), so these forces are exact. Deck nodes get
    the rigid-body acceleration (a_x − α y, a_y + α x, α) of the rigidLink map (per segment
    about its centre, ``info``: the built model); the seats start at rest with their
    actuators, unloaded. ``plan``, ``damping``: the model built."""
    state = plan.initial_state(scene.initial)
    if state is None:
        return
    u0, v0 = state
    B, S = plan.spring_matrices
    ug = np.array([motion.disp[ch][0] for ch in plan.channels])
    vg = np.array([motion.vel[ch][0] for ch in plan.channels])
    rate = damping.rate_coefficients(plan)
    f = B.T @ (plan.k0 * (B @ u0 - S @ ug) + rate * (B @ v0 - S @ vg))
    acc = -(f + damping.a0 * plan.mass * v0) / plan.mass
    if _segments(plan):
        fields = [acc[list(seg.dofs)] for seg in plan.segments]
        _segment_fields(ops, ops.setNodeAccel, info, fields, "acceleration", "m/s2, m/s2, rad/s2")
        return
    ax, ay, al = acc[DECK_X], acc[DECK_Y], acc[DECK_THETA]
    if not (ax or ay or al):
        return
    ops.comment(
        f"initial deck acceleration {ax!r} m/s2, {ay!r} m/s2, {al!r} rad/s2 "
        "(equilibrium of the initial state)"
    )
    _rigid_body_field(ops, ops.setNodeAccel, ("deck ",), ax, ay, al)


def set_initial_velocity(ops, scene: Scene, plan: Plan | None = None, info=None) -> None:
    """Give every node of the deck the rigid-body velocity of ``scene.initial.deck_velocity``
    (v_x − ω y, v_y + ω x at the node's coordinates), committed, before the analysis starts
    (a deck of segments: each segment's ``velocity`` about its own centre, ``plan`` and the
    built model's ``info``). OpenSees then starts Newmark with zero acceleration, as from
    rest, unless :func:`set_initial_acceleration` sets the state's."""
    if plan is not None and _segments(plan):
        fields = [seg.velocity for seg in plan.segments]
        _segment_fields(ops, ops.setNodeVel, info, fields, "velocity", "m/s, m/s, rad/s")
        return
    vx, vy, om = scene.initial.deck_velocity
    if not (vx or vy or om):
        return
    ops.comment(f"initial deck velocity {vx!r} m/s, {vy!r} m/s, {om!r} rad/s")
    _rigid_body_field(ops, ops.setNodeVel, ("deck ", "stick "), vx, vy, om)


def displaced(scene: Scene) -> bool:
    """Whether the scene starts the deck (or one of its segments) displaced."""
    if any(scene.initial.deck):
        return True
    return any(any(s.displacement) for s in scene.segments or ())


def refuse_initial_displacement(scene: Scene, settings) -> None:
    """What a displaced start needs in OpenSees (:func:`set_initial_displacement`): rigid
    mode (every deck node is set by the rigid-body map; a stick deck would start with
    unbalanced sticks), every gap open and every bent elastic at the start (the equilibrium
    acceleration is then exact, :func:`set_initial_acceleration`)."""
    if scene.segments is None:
        field, got = "initial.deck", list(scene.initial.deck)
    else:
        k = next(i for i, s in enumerate(scene.segments) if any(s.displacement))
        field, got = f"segments[{k}].displacement", list(scene.segments[k].displacement)
    where = f"the OpenSees engine starts the deck displaced (got {got}) "
    if settings.mode != "rigid":
        raise SceneError(
            field,
            where + "in rigid mode only (opensees.mode = "
            "'rigid'): in stick mode the sticks would start deformed; use "
            "rigid mode, the compliance or the nonsmooth engine",
        )
    plan = plan_of(scene)
    u0, _ = plan.initial_state(scene.initial)
    gaps = plan.linear_gaps(u0)[0]
    if np.any(gaps <= 0.0):
        raise SceneError(
            field,
            where + "only with every gap open at the start; it "
            f"closes gap(s) {[c.name for c, g in zip(plan.corners, gaps) if g <= 0]}",
        )
    B, _ = plan.spring_matrices
    d0 = B @ u0
    for s, d in zip(plan.springs, d0):
        if s.kind == "takeda" and abs(d) >= s.takeda[1]:
            raise SceneError(
                field,
                where + f"only with the bents elastic at the "
                f"start; spring {s.name} starts at {d:.4g} m, beyond its yield "
                f"displacement {s.takeda[1]:.4g} m",
            )

"""Scene → OpenSees model commands (plan view: ndm 2, ndf 3; kN, m, t, s).

Nodes (tags by name through :meth:`OpsSession.tag`):

* ``deck`` — deck centre (0, 0) carrying all the deck mass (M_d, M_d, I_d);
* ``deck c1..c4`` — deck corners at (±L/2 + y_c tan φ, y_c), y_c = ±W/2 (c1 (−,−), c2 (−,+),
  c3 (+,−), c4 (+,+)), the plan model's corner table (φ = ``deck.skew``, 0 for a straight deck);
* the deck node above each bent at (x_b, 0) (the centre node itself when x_b = 0);
* ``seat1``/``seat2`` — the seats' pivots (contact-face mid-points) (∓L/2, 0) with mass
  (m_s, 0, I_s); with friction they sit at the physical pivot F₀ = (∓L/2, 0) − g₀ n (n the
  face's gap-opening normal; ∓(L/2 + g₀) for a straight deck) so that zeroLengthContact2D,
  whose gap includes the node coordinates, sees the clear gap g₀ along n;
* ``seat1 c1``, ... — seat points facing the deck corners, at pivot + lever r = (y_c tan φ, y_c)
  (the plan's ``Corner.lever``), rigidLinked (beam) to their seat node — or fixed, for a
  ``seats[i].fixed`` rigid abutment (its actuator is then at rest);
* ``actuator1``/``actuator2`` — at the seat nodes, imposed x motion, y and θ fixed;
* ``table <bent>`` — at (x_b, 0), imposed x and y motion, θ fixed.

A deck of segments (``scene.segments``, the plan's :class:`~deckpound.models.plan.SegmentPlan`
bodies) has one centre node per segment, ``segment <name>`` (mass m, m, I), at the position
:func:`.geometry.segment_origins` gives it (the plan model's: consecutive segments g₀ apart
along their joint's normal), and every node of a segment — its corners ``deck <corner>``,
its bent nodes ``deck <bent>``, its sticks ``stick <name> <k>`` — at the segment's centre
plus its position in the segment's frame. At each joint the two corners ``j<k>_c1``,
``j<k>_c2`` (the striking segment's left-end corners) meet facing points ``facing <corner>``
on the other segment's right end face, at the corner's position at rest minus g₀ n
(rigidLinked to that segment's centre, or joined to its stick axis end in stick mode), with
the gap element between them as at a seat. A one-segment deck keeps the nodes, tags and
command log above.

Mode ``rigid``: rigidLink beams from the centre to the corners and bent nodes (exactly the 7
DOF of the analytic engines, plus massless seat-y DOFs held by a guide spring). Mode
``stick``: elasticBeamColumn sticks along the axis (``stick_elements`` equal elements per half,
plus nodes at the bent stations), transverse sticks from the deck ends to the corners;
E = ``deck.stick_modulus``, section of a deck W wide and W/8 deep (A = W²/8, I = W⁴/96 about
the vertical axis) — with E = 3e9 kN/m² (100× concrete) the sticks are near-rigid; the sticks
are massless and excluded from Rayleigh damping (``region -eleOnly ... -rayleigh 0 0 0 0``).

Seat guide: a rigidLink retained node must not be ``fix``ed (it breaks the Transformation
handler in 3.7), so each seat's y DOF is held by a stiff zeroLength spring (:data:`GUIDE_STIFFNESS`)
from its actuator, without Rayleigh damping; the seat has no y mass.

Springs (the plan model's :class:`~deckpound.models.plan.Spring` rows): bents — zeroLength
table → deck bent node, Hysteretic (Takeda stand-in) in x and y; seats — zeroLength actuator →
seat, Elastic k in x and θ, and a second zeroLength with Viscous(c, α = 1) dashpots (no
Rayleigh on it: see :func:`define_seat_springs`). Damping (the damping model
:class:`deckpound.models.damping.DampingModel` of the scene's ``[damping]``): ``rayleigh αM βK
βKinit βKc`` (:func:`.damping.rayleigh_factors`: a1 on the stiffness the model names),
``-doRayleigh 1`` on the elements of its damped springs (:func:`.damping.rayleigh_members`:
the bents by default, the seat springs too with ``bents+seats``); αM = a0 on the absolute
velocities of the deck and seat nodes, or, with ``mass = relative``, its Viscous dashpots from
support reference nodes (:func:`.damping.mass_dampers`). Gap elements, guides and sticks take
no Rayleigh damping.

:func:`build_model` defines the model stage by stage, in the order of the command log:
:func:`define_deck`, :func:`define_seats`, :func:`define_bents`, :func:`define_seat_springs`,
:func:`define_seat_guides`, :func:`define_contacts`, :func:`define_damping`,
:func:`define_excitation`.

Gaps: see :func:`.gaps.gap_mapping` — the ONE place where the positive physical gap g₀ and the
closing direction are mapped to OpenSees' node order, element orientation and negative
(compression) parameters. Skewed decks (φ ≠ 0): the gap elements act along the face normal
(zeroLength ``-orient``, zeroLengthContact2D ``-normal``), the seats still slide along x; the
seat guide spring then carries the normal force's y component n_y·f_N, so its stiffness is
:data:`SKEW_GUIDE_STIFFNESS` (see there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from deckpound.models.contact_laws_table import (
    BILINEAR_MIN_SUBSTEPS,
    BILINEAR_OPENSEES_REASON,
    contact_law,
    friction_model,
)
from deckpound.models.contact_params import corner_contacts
from deckpound.models.damping import DampingModel, damping_model
from deckpound.models.errors import SceneError
from deckpound.models.plan import Plan, plan_of
from deckpound.models.scene import Scene, joint_contact_error

from .damping import (
    MEMBERS_TEXT,
    MassDamperElement,
    ReferenceNode,
    mass_dampers,
    rayleigh_factors,
    rayleigh_members,
)
from .gaps import contact_normal, gap_mapping
from .geometry import placed, seat_pivot, segment_origins, stick_section, stick_stations
from .ops import ArrayArg, OpsSession

#: stiffness of the seat y guide springs [kN/m] (seat y stays ~ F_t / k ≈ 0)
GUIDE_STIFFNESS = 1.0e10
#: guide stiffness of a skewed deck's seats [kN/m]. The plan model's seats cannot move in y;
#: OpenSees cannot ``fix`` them (a retained node of a rigidLink, see the module docstring), so
#: a guide spring holds them. With skew the normal force has a y component n_y f_N = sin φ f_N
#: on the seat (zero for a straight deck), and a 1e10 guide would put a series compliance
#: n_y²/k_guide ≈ 2.5e-11 m/kN (φ = 30°) behind each 1e6 kN/m contact: a 2.5e-5 relative
#: difference from the plan model. 1e16 makes it 2.5e-11, below the round-off the clone
#: comparison resolves (1e-9 of each column's peak), and the massless y DOF it restrains is
#: only coupled through the contacts (LU pivots on it harmlessly; checked by the skew
#: clone-vs-OpenSees test). Kept separate so a straight deck's command log is unchanged.
SKEW_GUIDE_STIFFNESS = 1.0e16
#: samples of the last value appended to every support record (a Path series returns 0 at and
#: after its last sample; time advances by repeated addition of dt and may overshoot)
RECORD_PAD = 16


@dataclass
class ModelInfo:
    """Tags the runner needs to read the model's state, and the damping it was built with.

    The geometry (gaps g₀, sides, normals n, tangents t of the corners) is the plan model's
    corner table (:class:`deckpound.models.plan.Corner`), not repeated here. ``deck``: the
    first segment's centre node (the deck centre of a one-segment deck); ``bodies``: every
    segment's centre node, in plan order; ``deck_corners``: the corner nodes and
    ``seat_corners`` the points they face (a seat point, or a facing point on the next
    segment), both in the plan's corner order; ``body_nodes``: per segment, the global
    position of its centre at rest and every node that moves with it (centre first);
    ``mass_dampers``: the relative mass damping's elements (:func:`.damping.mass_dampers`).
    """

    mode: str
    deck: int
    seats: tuple[int, int]
    deck_corners: tuple[int, ...]
    seat_corners: tuple[int, ...]
    gap_elements: tuple[int, ...]
    bent_names: tuple[str, ...]
    bent_elements: tuple[int, ...]
    #: per corner (plan order): its element is zeroLengthContact2D (its contact table has
    #: friction), else a zeroLength gap element
    corner_friction: tuple[bool, ...]
    damping: DampingModel
    stick_elements: tuple[int, ...] = ()
    bodies: tuple[int, ...] = ()
    body_nodes: tuple[tuple[tuple[float, float], tuple[int, ...]], ...] = ()
    mass_dampers: tuple[MassDamperElement, ...] = ()
    notes: list[str] = field(default_factory=list)


@dataclass
class DeckNodes:
    """The deck's tags: the first segment's centre node (the deck centre of a one-segment
    deck), the corner nodes (plan order), the deck node above each bent (plan order), the
    stick elements (stick mode; empty in rigid mode), every segment's centre node, the
    segments' global positions at rest (:func:`.geometry.segment_origins`; None for one
    segment), the facing point of each joint corner (corner index → node) and every node of
    each segment (centre first)."""

    centre: int
    corners: list[int]
    bents: list[int]
    sticks: list[int]
    bodies: list[int] = field(default_factory=list)
    origins: list[tuple[float, float]] | None = None
    facing: dict[int, int] = field(default_factory=dict)
    members: list[list[int]] = field(default_factory=list)

    def origin(self, segment: int) -> tuple[float, float] | None:
        """Global position of segment ``segment``'s centre (None: a one-segment deck)."""
        return None if self.origins is None else self.origins[segment]

    def add(self, segment: int, node: int) -> None:
        """Count ``node`` among the nodes that move with segment ``segment``."""
        if node not in self.members[segment]:
            self.members[segment].append(node)


@dataclass
class SeatNodes:
    """The seats' tags: pivot node and actuator node per seat, the seat point facing each
    abutment corner (corner index → node)."""

    pivots: list[int]
    actuators: list[int]
    points: dict[int, int]


# -- checks -------------------------------------------------------------------------------


def refuse_scene(scene: Scene) -> None:
    """Refuse (SceneError) what the OpenSees model cannot express, naming the alternatives.

    The "option does nothing" warnings are derived by the engine contract from
    :meth:`deckpound.opensees_build.engine.OpenSeesEngine.reads`.
    """
    _refuse_contact(scene, scene.contact)
    # a joint's own table, named at the joint (the exports build without Engine.validate)
    for k, joint in enumerate(scene.joints or ()):
        if joint.contact is not None and joint.contact.given():
            try:
                _refuse_contact(scene, scene.joint_contact(k))
            except SceneError as err:
                raise joint_contact_error(err, k) from None


def _refuse_contact(scene: Scene, c) -> None:
    """:func:`refuse_scene` on one contact table ``c`` (the scene's or a joint's)."""
    law = contact_law(c.law)
    if law.opensees is None:
        raise SceneError("contact.law", law.opensees_refusal)
    o = scene.opensees
    if c.law == "bilinear" and (o.substeps < BILINEAR_MIN_SUBSTEPS or o.fallback != "substep"):
        raise SceneError(
            "opensees.substeps",
            BILINEAR_OPENSEES_REASON.format(
                min=BILINEAR_MIN_SUBSTEPS,
                got=o.substeps
                if o.fallback == "substep"
                else f"{o.substeps} with fallback = {o.fallback!r}",
            ),
        )
    if c.has_friction:
        model = friction_model(c.friction_mode)
        if model.opensees is None:
            raise SceneError("contact.friction_mode", model.opensees_refusal)
        if c.law not in model.opensees_laws:
            raise SceneError(
                "contact.law",
                f"OpenSees cannot combine the {c.law!r} law with "
                "friction: zeroLengthContact2D is a linear penalty contact; use "
                "law = 'linear' with friction",
            )


def padded(values: np.ndarray) -> np.ndarray:
    return np.concatenate([values, np.full(RECORD_PAD, values[-1])])


# -- the model ----------------------------------------------------------------------------


def build_model(
    ops: OpsSession,
    scene: Scene,
    motion=None,
    *,
    gaps: bool = True,
    supports: str = "motion",
    plan: Plan | None = None,
    damping: DampingModel | None = None,
) -> ModelInfo:
    """Define nodes, masses, constraints, materials, elements, damping and (optionally) the
    multiple-support excitation, stage by stage (the functions below, in this order: their
    commands and tags make the command log).

    Parameters
    ----------
    motion : resampled :class:`SupportMotion` on the analysis step (needed for
        ``supports = "motion"``).
    gaps : False leaves the gap elements out (contact-free model, e.g. for eigen).
    supports : ``"motion"`` — MultipleSupport imposed motion; ``"fixed"`` — supports fixed.
    plan, damping : the plan model and its damping model (default: the scene's).
    """
    refuse_scene(scene)
    if plan is None:
        plan = plan_of(scene)
    if damping is None:
        damping = damping_model(scene, plan)
    # the abutment corners' friction places the seats' pivots and stiffens their guides
    friction = gaps and scene.contact.has_friction
    damped_bents, damped_seats = rayleigh_members(plan, damping)
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    deck = define_deck(ops, scene, plan)
    seats = define_seats(ops, scene, plan, friction, supports, deck)
    bent_eles, tables = define_bents(ops, plan, deck, damped_bents, supports)
    define_seat_springs(ops, plan, seats, damped_seats)
    # with friction the guide also carries the tangential force: 1e10 would add a series
    # compliance 1/k_guide behind the 1e6 stick spring (a 1e-4 relative difference from the
    # plan model, whose seats do not move in y); the skew guide makes it round-off
    define_seat_guides(ops, seats, scene.deck.skew != 0.0 or friction)
    gap_eles = define_contacts(ops, scene, plan, deck, seats) if gaps else []
    ref_nodes, dampers = define_damping(ops, plan, damping, deck, seats, supports)
    if supports == "motion":
        if motion is None:
            raise ValueError("build_model needs the resampled motion for supports='motion'")
        define_excitation(ops, plan, motion, tables + seats.actuators, ref_nodes)
    return ModelInfo(
        mode=scene.opensees.mode,
        deck=deck.centre,
        seats=tuple(seats.pivots),
        deck_corners=tuple(deck.corners),
        seat_corners=tuple(facing_points(plan, deck, seats)),
        gap_elements=tuple(gap_eles),
        bent_names=plan.bent_names,
        bent_elements=tuple(bent_eles),
        corner_friction=tuple(gaps and ct.has_friction for ct in corner_contacts(scene, plan)),
        damping=damping,
        stick_elements=tuple(deck.sticks),
        bodies=tuple(deck.bodies),
        body_nodes=tuple(
            (deck.origin(k) or (0.0, 0.0), tuple(nodes)) for k, nodes in enumerate(deck.members)
        ),
        mass_dampers=tuple(dampers),
    )


def define_deck(ops: OpsSession, scene: Scene, plan: Plan) -> DeckNodes:
    """The deck's centre node(s) with the deck mass (one per segment, each with its own),
    its corner nodes (the plan's corner table), the facing points of the joints, and the
    rigid links (``rigid``) or the sticks (``stick``) that join them."""
    d = scene.deck
    origins = segment_origins(plan)
    if origins is None:
        ops.comment("deck: centre node with all the deck mass")
        centre = ops.tag("node", "deck")
        ops.node(centre, 0.0, 0.0)
        ops.mass(centre, d.mass, d.mass, d.inertia)
        bodies = [centre]
    else:
        ops.comment(
            f"deck of {len(plan.segments)} segments: a centre node per segment with its mass"
        )
        bodies = []
        for seg, (ox, oy) in zip(plan.segments, origins):
            n = ops.tag("node", f"segment {seg.name}")
            ops.node(n, ox, oy)
            ops.mass(n, *(float(plan.mass[dof]) for dof in seg.dofs))
            bodies.append(n)
    deck = DeckNodes(bodies[0], [], [], [], bodies, origins, {}, [[b] for b in bodies])
    for corner in plan.corners:
        n = ops.tag("node", f"deck {corner.name}")
        ops.node(n, *placed(deck.origin(corner.body), corner.x, corner.y))
        deck.corners.append(n)
        deck.add(corner.body, n)
    joints = [c for c in plan.corners if c.joint >= 0]
    if joints:
        ops.comment("joints: the facing points on the other segment's end face, g0 along -n")
        for corner in joints:
            px, py = placed(deck.origin(corner.body), corner.x, corner.y)
            nx, ny = corner.normal
            n = ops.tag("node", f"facing {corner.name}")
            ops.node(n, px - corner.gap * nx, py - corner.gap * ny)
            deck.facing[corner.index] = n
            deck.add(corner.joint, n)  # joint k faces segment k (0-based)
    if scene.opensees.mode == "rigid":
        define_rigid_deck(ops, scene, plan, deck)
    else:
        define_stick_deck(ops, scene, plan, deck)
    return deck


def bent_bodies(plan: Plan) -> list[int]:
    """The segment each bent carries, in bent order (the plan's ``SegmentPlan.bents``)."""
    body = {k: seg.index for seg in plan.segments for k in seg.bents}
    return [body[k] for k in range(len(plan.bent_names))]


def define_rigid_deck(ops: OpsSession, scene: Scene, plan: Plan, deck: DeckNodes) -> None:
    """Rigid mode: a deck node above each bent (its segment's centre node for a bent at the
    centre) and rigidLink beams from each segment's centre to its corners, those nodes and
    the facing points on its end face."""
    tol = 1e-9 * scene.deck.length
    for name, xb, body in zip(plan.bent_names, plan.bent_x, bent_bodies(plan)):
        centre = deck.bodies[body]
        if abs(xb) <= tol:
            deck.bents.append(centre)
        else:
            n = ops.tag("node", f"deck {name}")
            ops.node(n, *placed(deck.origin(body), xb, 0.0))
            deck.bents.append(n)
            deck.add(body, n)
    ops.comment(
        "rigid deck: rigidLink beams from the centre"
        if len(deck.bodies) == 1
        else "rigid segments: rigidLink beams from each segment's centre"
    )
    bodies = bent_bodies(plan)
    for k, centre in enumerate(deck.bodies):
        corners = [n for c, n in zip(plan.corners, deck.corners) if c.body == k]
        bents = [n for n, b in zip(deck.bents, bodies) if b == k and n != centre]
        facing = [n for i, n in deck.facing.items() if plan.corners[i].joint == k]
        for n in corners + bents + facing:
            ops.rigidLink("beam", centre, n)


def define_stick_deck(ops: OpsSession, scene: Scene, plan: Plan, deck: DeckNodes) -> None:
    """Stick mode: per segment, elasticBeamColumn sticks along its axis (nodes at
    :func:`stick_stations`) and from its ends to its corners and to the facing points on its
    end face; each bent acts on the nearest axis node of its segment."""
    d = scene.deck
    ops.comment(f"stick deck: E = {d.stick_modulus:g} kN/m2, A = W^2/8, I = W^4/96 (near-rigid)")
    transf = ops.tag("transf", "deck")
    ops.geomTransf("Linear", transf)
    one = len(plan.segments) == 1
    stations, axes = [], []
    for seg, centre in zip(plan.segments, deck.bodies):
        area, inertia = stick_section(2.0 * seg.half_width)  # W of the segment
        prefix = "stick" if one else f"stick {seg.name}"
        xs = stick_stations(scene, plan, seg.index)
        axis = []
        for k, x in enumerate(xs):
            if x == 0.0:
                axis.append(centre)
                continue
            n = ops.tag("node", f"{prefix} {k}")
            ops.node(n, *placed(deck.origin(seg.index), x, 0.0))
            axis.append(n)
            deck.add(seg.index, n)
        for k in range(len(axis) - 1):
            e = ops.tag("element", f"{prefix} {k}")
            ops.element(
                "elasticBeamColumn", e, axis[k], axis[k + 1], area, d.stick_modulus, inertia, transf
            )
            deck.sticks.append(e)
        for corner, n in zip(plan.corners, deck.corners):
            if corner.body != seg.index:
                continue
            # the right end of the deck (seat 2) or the left end (seat 1, or a joint's
            # striking segment)
            end = axis[-1] if corner.seat == 1 else axis[0]
            e = ops.tag("element", f"stick {corner.name}")
            ops.element("elasticBeamColumn", e, end, n, area, d.stick_modulus, inertia, transf)
            deck.sticks.append(e)
        for i, n in deck.facing.items():
            corner = plan.corners[i]
            if corner.joint != seg.index:
                continue
            e = ops.tag("element", f"stick facing {corner.name}")
            ops.element("elasticBeamColumn", e, axis[-1], n, area, d.stick_modulus, inertia, transf)
            deck.sticks.append(e)
        stations.append(xs)
        axes.append(axis)
    for xb, body in zip(plan.bent_x, bent_bodies(plan)):
        xs = stations[body]
        k = min(range(len(xs)), key=lambda k: abs(xs[k] - xb))
        deck.bents.append(axes[body][k])


def define_seats(
    ops: OpsSession, scene: Scene, plan: Plan, friction: bool, supports: str, deck: DeckNodes
) -> SeatNodes:
    """Per seat: its pivot node with the seat mass, its actuator node (x imposed or fixed, y
    and θ fixed), and the seat points facing its corners at pivot + lever, rigidLinked to the
    pivot — or fixed, for a rigid abutment (``Corner.seat_fixed``). The pivot sits in the
    frame of the deck segment the seat faces (:func:`.geometry.seat_pivot`)."""
    seats = SeatNodes([], [], {})
    for j, seat in enumerate(scene.seats):
        body = next(c.body for c in plan.corners if c.seat == j)
        xf, yf = placed(deck.origin(body), *seat_pivot(plan, j, friction))
        ops.comment(f"seat {j + 1}: contact-face mid-point, guided in y by a stiff spring")
        n = ops.tag("node", f"seat{j + 1}")
        ops.node(n, xf, yf)
        ops.mass(n, seat.mass, 0.0, seat.inertia)
        seats.pivots.append(n)
        a = ops.tag("node", f"actuator{j + 1}")
        ops.node(a, xf, yf)
        ops.fix(a, 1 if supports == "fixed" else 0, 1, 1)
        seats.actuators.append(a)
        for corner in (c for c in plan.corners if c.seat == j):
            sc = ops.tag("node", f"seat{j + 1} {corner.name}")
            rx, ry = corner.lever
            ops.node(sc, xf + rx, yf + ry)
            if corner.seat_fixed:
                # rigid abutment (actuator at rest, checked by the scene): the seat point is
                # fixed, not linked to the seat node, so the contact force never reaches the
                # seat — the plan model's zero seat columns of W_N, W_T, exactly
                ops.fix(sc, 1, 1, 1)
            else:
                ops.rigidLink("beam", n, sc)
            seats.points[corner.index] = sc
    return seats


def facing_points(plan: Plan, deck: DeckNodes, seats: SeatNodes) -> list[int]:
    """The node each corner meets, in the plan's corner order: its seat point, or at a joint
    the facing point on the other segment's end face."""
    return [seats.points[c.index] if c.joint < 0 else deck.facing[c.index] for c in plan.corners]


def define_bents(
    ops: OpsSession, plan: Plan, deck: DeckNodes, damped: list[bool], supports: str
) -> tuple[list[int], list[int]]:
    """Per bent: its shake-table node (under the deck node above the bent), a zeroLength
    table → deck node with the Hysteretic materials of its x and y plan springs
    (``-doRayleigh 1`` when ``damped``), and its explicit dashpots (the springs' ``dashpot``)
    in an element of their own. Returns (bent elements, table nodes)."""
    elements, tables = [], []
    rows = zip(plan.bent_names, plan.bent_x, deck.bents, bent_bodies(plan))
    for k, (name, xb, dn, body) in enumerate(rows):
        springs = plan.springs[2 * k : 2 * k + 2]  # (x, y), Plan.springs order
        tn = ops.tag("node", f"table {name}")
        ops.node(tn, *placed(deck.origin(body), xb, 0.0))
        ops.fix(tn, *((1, 1, 1) if supports == "fixed" else (0, 0, 1)))
        tables.append(tn)
        mats = []
        for spring in springs:
            m = ops.tag("material", f"{name} {spring.direction}")
            ops.uniaxialMaterial("Hysteretic", m, *spring.takeda)
            mats.append(m)
        e = ops.tag("element", f"bent {name}")
        rayleigh = ("-doRayleigh", 1) if damped[k] else ()
        ops.element("zeroLength", e, tn, dn, "-mat", *mats, "-dir", 1, 2, *rayleigh)
        elements.append(e)
        # explicit bent dashpots (bents[i].cx, cy), in their own element like the seats'
        dash = [(dirn, s) for dirn, s in zip((1, 2), springs) if s.dashpot > 0.0]
        if dash:
            dmats = []
            for _dirn, spring in dash:
                m = ops.tag("material", f"{name} c{spring.direction}")
                ops.uniaxialMaterial("Viscous", m, spring.dashpot, 1.0)
                dmats.append(m)
            e = ops.tag("element", f"bent {name} dashpot")
            ops.element("zeroLength", e, tn, dn, "-mat", *dmats, "-dir", *(d for d, _ in dash))
    return elements, tables


def define_seat_springs(ops: OpsSession, plan: Plan, seats: SeatNodes, damped: list[bool]) -> None:
    """Per seat: a zeroLength actuator → seat with Elastic materials of its x and θ plan
    springs (``-doRayleigh 1`` when ``damped``) and a second one with their dashpots: with
    ``-doRayleigh 1`` a zeroLength (3.7) drops its materials' damping tangent from the damping
    matrix (Newton then converges linearly)."""
    n_bent = plan.n_bent_springs
    for j, (act, pivot) in enumerate(zip(seats.actuators, seats.pivots)):
        kx, kt = plan.springs[n_bent + 2 * j : n_bent + 2 * j + 2]  # (x, θ), Plan.springs order
        mx = ops.tag("material", f"seat{j + 1} kx")
        ops.uniaxialMaterial("Elastic", mx, kx.k0)
        mt = ops.tag("material", f"seat{j + 1} ktheta")
        ops.uniaxialMaterial("Elastic", mt, kt.k0)
        e = ops.tag("element", f"seat{j + 1} spring")
        rayleigh = ("-doRayleigh", 1) if damped[j] else ()
        ops.element("zeroLength", e, act, pivot, "-mat", mx, mt, "-dir", 1, 3, *rayleigh)
        cx = ops.tag("material", f"seat{j + 1} cx")
        ops.uniaxialMaterial("Viscous", cx, kx.dashpot, 1.0)
        ct = ops.tag("material", f"seat{j + 1} ctheta")
        ops.uniaxialMaterial("Viscous", ct, kt.dashpot, 1.0)
        e = ops.tag("element", f"seat{j + 1} dashpot")
        ops.element("zeroLength", e, act, pivot, "-mat", cx, ct, "-dir", 1, 3)


def define_seat_guides(ops: OpsSession, seats: SeatNodes, stiff: bool) -> None:
    """The seats' y guides: zeroLength actuator → seat in y, Elastic :data:`GUIDE_STIFFNESS`
    or, ``stiff`` (skew or friction), :data:`SKEW_GUIDE_STIFFNESS`."""
    mg = ops.tag("material", "seat guide")
    ops.uniaxialMaterial("Elastic", mg, SKEW_GUIDE_STIFFNESS if stiff else GUIDE_STIFFNESS)
    for j, (act, pivot) in enumerate(zip(seats.actuators, seats.pivots)):
        e = ops.tag("element", f"seat{j + 1} guide")
        ops.element("zeroLength", e, act, pivot, "-mat", mg, "-dir", 2)


def define_contacts(
    ops: OpsSession, scene: Scene, plan: Plan, deck: DeckNodes, seats: SeatNodes
) -> list[int]:
    """The gap element of every corner, between its corner node and the node it meets
    (:func:`facing_points`): zeroLengthContact2D with friction, else a zeroLength with the
    law's gap material (:func:`.gaps.gap_mapping`). Returns the element tags. Each corner takes
    its contact table (:func:`~deckpound.models.contact_params.corner_contacts`: a joint's own,
    else the scene's): zeroLengthContact2D where that table has friction."""
    ct = scene.contact
    ops.comment(
        f"contact at the corners: law {ct.law}"
        + (", zeroLengthContact2D with friction" if ct.has_friction else "")
    )
    for where, jc in scene.contact_tables()[1:]:
        ops.comment(
            f"{where}: law {jc.law}"
            + (", zeroLengthContact2D with friction" if jc.has_friction else "")
        )
    elements = []
    tables = corner_contacts(scene, plan)
    for corner, dk, st in zip(plan.corners, deck.corners, facing_points(plan, deck, seats)):
        e = ops.tag("element", f"gap {corner.name}")
        ct = tables[corner.index]
        if ct.has_friction:
            # i = seat (facing) point, j = deck corner; zeroLengthContact2D (3.7) measures the
            # gap as n_c·(x_i + u_i − x_j − u_j) (verified), so n_c = −n points from the deck
            # to the seat: −x at seat 1 and at a joint, +x at seat 2 for a straight deck. Its
            # nodes are g₀ apart along n (it warns that L > tolerance: harmless, the gap is
            # the geometric one).
            nx, ny = contact_normal(corner)
            ops.element(
                "zeroLengthContact2D",
                e,
                st,
                dk,
                ct.stiffness,
                ct.tangential_stiffness,
                ct.friction,
                "-normal",
                nx,
                ny,
            )
        else:
            spec = gap_mapping(scene, corner, dk, st, ops.tag("material", f"gap {corner.name}"))
            ops.uniaxialMaterial(spec.material, *spec.args)
            orient = ("-orient", *spec.orient) if spec.orient is not None else ()
            ops.element(
                "zeroLength", e, spec.i_node, spec.j_node, "-mat", spec.args[0], "-dir", 1, *orient
            )
        elements.append(e)
    return elements


def define_damping(
    ops: OpsSession,
    plan: Plan,
    damping: DampingModel,
    deck: DeckNodes,
    seats: SeatNodes,
    supports: str,
) -> tuple[list[ReferenceNode], list[MassDamperElement]]:
    """``rayleigh`` with the damping model's factors (:func:`.damping.rayleigh_factors`), the
    relative mass dampers (:func:`.damping.mass_dampers`) and the sticks' region without
    Rayleigh damping. Returns the mass dampers' reference nodes and elements."""
    wi, wj = damping.omega
    ops.comment(
        f"Rayleigh: a0 M ({damping.mass} velocities) + a1 K ({damping.stiffness} stiffness of "
        f"the {MEMBERS_TEXT[damping.members]}, -doRayleigh 1); "
        + (
            f"matched at {wi:.6g} and {wj:.6g} rad/s"
            if not math.isnan(wi)  # method none: (nan, nan)
            else "method none: no Rayleigh damping"
        )
    )
    ops.rayleigh(*rayleigh_factors(damping))
    refs, elements = mass_dampers(
        ops, plan, damping, deck.bodies, deck.origins, seats.pivots, seats.actuators, supports
    )
    if deck.sticks:
        ops.region(
            ops.tag("region", "sticks"), "-eleOnly", *deck.sticks, "-rayleigh", 0.0, 0.0, 0.0, 0.0
        )
    return refs, elements


def define_excitation(
    ops: OpsSession,
    plan: Plan,
    motion,
    support_nodes: list[int],
    ref_nodes: list[ReferenceNode],
) -> None:
    """MultipleSupport excitation: per support channel (``plan.channels``: the tables' x and
    y, then the actuators' x) a Path displacement and velocity series of the resampled record
    (padded, :func:`padded`), a groundMotion and its imposedMotion on the support node (and on
    the relative mass dampers' reference nodes that follow that table). ``support_nodes``: the
    table nodes in bent order, then the two actuators."""
    n_tables = len(plan.bent_names)
    where = [(tn, dof) for tn in support_nodes[:n_tables] for dof in (1, 2)]
    where += [(act, 1) for act in support_nodes[n_tables:]]
    # reference nodes of the relative mass damping follow their table's motion
    also: dict[int, list[tuple[int, int]]] = {}
    for ref in ref_nodes:
        also.setdefault(ref.channel_x, []).append((ref.node, 1))
        also.setdefault(ref.channel_y, []).append((ref.node, 2))
    dt = float(motion.t[1] - motion.t[0])
    ops.comment("multiple-support excitation: imposed displacement and velocity")
    ops.pattern("MultipleSupport", ops.tag("pattern", "supports"))
    D, V = motion.matrices(plan.channels)
    for k, (ch, (node, dof)) in enumerate(zip(plan.channels, where)):
        ts_d = ops.tag("timeSeries", f"{ch} disp")
        ops.timeSeries("Path", ts_d, "-dt", dt, ArrayArg(f"{ch}_disp", padded(D[:, k])))
        ts_v = ops.tag("timeSeries", f"{ch} vel")
        ops.timeSeries("Path", ts_v, "-dt", dt, ArrayArg(f"{ch}_vel", padded(V[:, k])))
        gm = ops.tag("groundMotion", ch)
        ops.groundMotion(gm, "Plain", "-disp", ts_d, "-vel", ts_v)
        ops.imposedMotion(node, dof, gm)
        for rn, rdof in also.get(k, ()):
            ops.imposedMotion(rn, rdof, gm)


def analysis_commands(scene: Scene) -> list[tuple]:
    """The analysis definition as (command, *args) tuples (re-issued by the substep fallback)."""
    s = scene.opensees
    return [
        ("constraints", "Transformation"),
        ("numberer", "RCM"),
        ("system", s.system),
        ("test", s.test, s.tolerance, s.max_iterations),
        ("algorithm", s.algorithm),
        ("integrator", "Newmark", s.gamma, s.beta),
        ("analysis", "Transient"),
    ]

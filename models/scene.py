"""The scene: one engine-independent description of a deck-abutment pounding problem.

Units are SI with tonnes throughout: kN, m, t, s, rad (1 kN = 1 t·m/s²). Axes: x longitudinal
(bridge axis), y transverse, θ in-plane rotation about the vertical, counter-clockwise positive.
The deck centre is at x = 0 and the deck spans x ∈ [−L/2, L/2], y ∈ [−W/2, W/2]; bent stations
are given from the left (x = −L/2) end, seat 1 is the left seat, seat 2 the right one.

The records are frozen and validate themselves on construction; the scene knows nothing about
the engines that run it (the engine settings are plain data read by the engines).
"""

from __future__ import annotations

import dataclasses
import functools
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from .contact_laws_table import FRICTION_CODES, LAW_CODES, contact_law
from .errors import SceneError
from .fields import from_mapping, set_path, spec, to_mapping, validate
from .html_table import html_table, short_text
from .scene_excitation import (
    Excitation,
    Sequence,
    check_sequence_pgas,
)
from .scene_settings import (
    MAX_STEPS,
    ComplianceSettings,
    NonsmoothSettings,
    OpenSeesSettings,
    RunSettings,
)

__all__ = [
    "CONTACT_LAWS",
    "DAMPING_MASS",
    "DAMPING_MEMBERS",
    "DAMPING_STIFFNESS",
    "FRICTION_MODES",
    "GEOMETRIES",
    "MAX_SKEW",
    "SUPPORTS_PER_BENT",
    "Bent",
    "Contact",
    "Damping",
    "Deck",
    "Initial",
    "Joint",
    "JointContact",
    "Scene",
    "Seat",
    "Segment",
    "TakedaSpring",
    "joint_contact_error",
]

CONTACT_LAWS = tuple(LAW_CODES)  # the rows of contact_laws_table, in code order
FRICTION_MODES = tuple(FRICTION_CODES)
DAMPING_MEMBERS = ("bents", "bents+seats", "none")
DAMPING_STIFFNESS = ("initial", "committed", "current")
DAMPING_MASS = ("absolute", "relative")
GEOMETRIES = ("linear", "nonlinear")
SUPPORTS_PER_BENT = ("x", "y")
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,31}$")


#: largest skew angle [degrees]: acute corners sharper than 15° are far outside bridge practice
MAX_SKEW = 75.0


@dataclass(frozen=True, kw_only=True)
class Deck:
    """Rigid deck in plan: size, mass and polar inertia about its centre, and its skew.

    Skew φ (``skew``, in **degrees** in the scene, radians inside the engines): the deck is a
    parallelogram whose end faces are the lines x = ±L/2 + y tan φ, so the corners sit at
    (±L/2 + y_c tan φ, y_c), y_c = ±W/2 (c1 and c4 acute for φ > 0); L is measured along the
    axis between the end faces' mid-points and W across it (plan area L·W; mass and inertia
    are given, not rescaled). The seats' contact faces are parallel to the end faces, but the
    seats still **slide along the bridge axis x** and rotate about their face mid-point; the
    gap ``seats[i].gap`` is measured **along the face normal** n = (cos φ, −sin φ) (x
    clearance gap / cos φ). The plan model's corner table turns this into positions, normals
    and tangents (:mod:`deckpound.models.plan`).
    """

    length: float = spec(unit="m", doc="deck length along x", gt=0.0)
    width: float = spec(unit="m", doc="deck width along y", gt=0.0)
    mass: float = spec(unit="t", doc="deck mass M_d", gt=0.0)
    inertia: float = spec(unit="t*m^2", doc="deck polar mass moment of inertia I_d", gt=0.0)
    stick_modulus: float = spec(
        3.0e9,
        unit="kN/m^2",
        doc="Young's modulus of the stiff stick elements (OpenSees stick mode)",
        gt=0.0,
    )
    skew: float = spec(
        0.0,
        unit="deg",
        doc="skew angle φ of the end faces from the transverse "
        "axis (degrees; 0 = straight deck); the gap is measured along the face "
        "normal",
        ge=0.0,
        lt=MAX_SKEW,
    )

    def __post_init__(self) -> None:
        validate(self)


@dataclass(frozen=True, kw_only=True)
class TakedaSpring:
    """Takeda-type (peak-oriented, OpenSees Hysteretic stand-in) bent spring in one direction.

    Backbone: elastic to (yield_force / stiffness, yield_force), then hardening with slope
    post_yield_ratio · stiffness up to ultimate_displacement (the second Hysteretic point);
    unloading stiffness stiffness · μ^(−beta).
    """

    stiffness: float = spec(unit="kN/m", doc="initial (post-crack) stiffness k0", gt=0.0)
    yield_force: float = spec(unit="kN", doc="yield force F_y", gt=0.0)
    post_yield_ratio: float = spec(
        0.05, unit="-", doc="post-yield to initial stiffness ratio", ge=0.0, lt=1.0
    )
    beta: float = spec(0.5, unit="-", doc="Takeda unloading-stiffness exponent", ge=0.0, le=2.0)
    ultimate_displacement: float = spec(
        0.3, unit="m", doc="deformation of the second backbone point", gt=0.0
    )

    def __post_init__(self) -> None:
        validate(self)
        if self.ultimate_displacement <= self.yield_displacement:
            raise SceneError(
                "ultimate_displacement",
                f"must exceed the yield displacement {self.yield_displacement:.6g} m, "
                f"got {self.ultimate_displacement}",
            )

    @property
    def yield_displacement(self) -> float:
        """Yield displacement F_y / k0 [m]."""
        return self.yield_force / self.stiffness


@dataclass(frozen=True, kw_only=True)
class Bent:
    """A two-column bent: a Takeda spring per horizontal direction between deck and shake table."""

    name: str = spec(doc="label used in result columns (bent1_fx, ...)")
    station: float = spec(unit="m", doc="distance from the deck's left end (x = -L/2)", ge=0.0)
    x: TakedaSpring = spec(doc="longitudinal spring")
    y: TakedaSpring = spec(doc="transverse spring")
    cx: float = spec(
        0.0,
        unit="kN*s/m",
        doc="explicit dashpot deck-table in x (e.g. from a "
        "system identification; adds to any Rayleigh damping)",
        ge=0.0,
    )
    cy: float = spec(0.0, unit="kN*s/m", doc="explicit dashpot deck-table in y", ge=0.0)
    segment: str | None = spec(
        None,
        doc="name of the deck segment the bent carries (Scene.segments); none: the segment "
        "whose span holds the station (a bent at a joint's station must name one)",
    )

    def __post_init__(self) -> None:
        validate(self)


@dataclass(frozen=True, kw_only=True)
class Seat:
    """An abutment seat: rigid body guided in y, on its actuator through springs and dashpots.

    The seat moves in x and rotates about the mid-point of its contact face; its spring and
    dashpot act on the deformation between the seat and its actuator.

    ``fixed = true`` makes it a rigid abutment: the contact forces do not act on the seat (the
    seat columns of W_N, W_T are zero in the analytic engines; OpenSees fixes the seat's contact
    points instead of linking them to the seat node), so the seat stays exactly where its
    actuator holds it. This is exact only while the actuator is at rest — a seat following a
    moving actuator rigidly would need its DOFs prescribed in every engine's step loop, which
    they do not do — so the scene refuses a fixed seat under longitudinal support motion.
    """

    name: str = spec(doc="label")
    mass: float = spec(unit="t", doc="seat mass", gt=0.0)
    inertia: float = spec(
        unit="t*m^2", doc="seat polar inertia about the contact-face mid-point", gt=0.0
    )
    kx: float = spec(unit="kN/m", doc="translational spring to the actuator", gt=0.0)
    ktheta: float = spec(unit="kN*m/rad", doc="rotational spring", gt=0.0)
    cx: float = spec(unit="kN*s/m", doc="translational dashpot", ge=0.0)
    ctheta: float = spec(unit="kN*m*s/rad", doc="rotational dashpot", ge=0.0)
    gap: float = spec(unit="m", doc="initial clear gap between deck end and seat face", ge=0.0)
    support_length: float | None = spec(
        None,
        unit="m",
        doc="seat (support) length N under the deck end, along the face normal, measured "
        "from the deck end's initial position (AASHTO LRFD 4.7.4.4 seat width): a corner "
        "facing this seat is unseated when its gap has opened by more than N since t = 0 "
        "(seat margin N - (g - g0) < 0) and the run ends with status 'unseated'; none (the "
        "default): the margin is not checked, since the seat width depends on the bridge's "
        "spans, column heights, skew and scale and no one number fits every scene",
        gt=0.0,
    )
    fixed: bool = spec(
        False,
        doc="rigid abutment: the seat stays on its actuator and the "
        "contact forces do not move it (needs the actuators at rest: "
        "excitation.kind = 'none' or longitudinal_ratio = 0)",
    )

    def __post_init__(self) -> None:
        validate(self)


@dataclass(frozen=True, kw_only=True)
class Contact:
    """Deck-seat contact at the four deck corners (compliance laws; nonsmooth uses e and mu)."""

    law: str = spec(
        "linear", doc="normal contact law of the compliance engines", choices=CONTACT_LAWS
    )
    stiffness: float = spec(
        1.0e6,
        unit="kN/m (hertz: kN/m^exponent)",
        doc="normal contact stiffness per corner (K1 for bilinear)",
        gt=0.0,
    )
    exponent: float = spec(1.5, unit="-", doc="Hertz exponent", gt=0.0)
    restitution: float = spec(
        0.6, unit="-", doc="coefficient of restitution e (damped laws, nonsmooth)", ge=0.0, le=1.0
    )
    bilinear_ratio: float = spec(
        0.35, unit="-", doc="K2/K1 of the Muthukumar bilinear law", gt=0.0, le=1.0
    )
    bilinear_yield: float = spec(
        0.001, unit="m", doc="yield deformation of the bilinear law", gt=0.0
    )
    friction: float = spec(0.0, unit="-", doc="Coulomb friction coefficient mu", ge=0.0)
    friction_mode: str = spec(
        "none",
        doc="none | slip (no sticking) | stick (the project's "
        "return-mapping stick spring) | contact2d (OpenSees "
        "zeroLengthContact2D's algorithm; what OpenSees expresses and "
        "the package uses when it switches friction on)",
        choices=FRICTION_MODES,
    )
    tangential_stiffness: float = spec(
        1.0e6, unit="kN/m", doc="tangential stick spring per corner (stick mode)", gt=0.0
    )
    slip_velocity: float = spec(
        1.0e-3, unit="m/s", doc="regularisation velocity of the slip mode (tanh(v/v0))", gt=0.0
    )
    geometry: str = spec("linear", doc="contact kinematics", choices=GEOMETRIES)

    def __post_init__(self) -> None:
        validate(self)
        refuse = contact_law(self.law).refuse
        problem = refuse(self) if refuse is not None else None
        if problem is not None:
            raise SceneError(*problem)

    @property
    def has_friction(self) -> bool:
        """True when friction does work: mu > 0 and a friction mode is selected."""
        return self.friction > 0.0 and self.friction_mode != "none"


def _joint_field(name: str) -> Any:
    """The spec of :class:`Contact`'s field ``name`` as an optional joint field (default none:
    the scene's value): the same unit, range and choices, one declaration of each."""
    meta = Contact.__dataclass_fields__[name].metadata
    limits = {k: meta[k] for k in ("unit", "gt", "ge", "lt", "le", "choices")}
    return spec(None, doc=f"{meta['doc']} (none: contact.{name})", **limits)


@dataclass(frozen=True, kw_only=True)
class JointContact:
    """The contact of one joint's corners where it differs from the scene's ``contact`` table.

    A field given replaces the scene's value at that joint; a field left out (none) takes the
    scene's, so ``--set contact.stiffness=...`` still reaches every joint that does not give
    its own. A deck–deck joint (concrete on concrete, an elastomeric filler, a shear key) often
    has a stiffness, restitution or friction of its own, unlike the deck–abutment seats. The
    contact kinematics (``contact.geometry``) is one choice for the whole model and is not
    here. Every engine applies these per corner or refuses, with the reason, what it cannot
    express (the engines' ``refuse``, run on the joint's table).
    """

    law: str | None = _joint_field("law")
    stiffness: float | None = _joint_field("stiffness")
    exponent: float | None = _joint_field("exponent")
    restitution: float | None = _joint_field("restitution")
    bilinear_ratio: float | None = _joint_field("bilinear_ratio")
    bilinear_yield: float | None = _joint_field("bilinear_yield")
    friction: float | None = _joint_field("friction")
    friction_mode: str | None = _joint_field("friction_mode")
    tangential_stiffness: float | None = _joint_field("tangential_stiffness")
    slip_velocity: float | None = _joint_field("slip_velocity")

    def __post_init__(self) -> None:
        validate(self)

    def given(self) -> dict[str, Any]:
        """The fields the joint gives, by name."""
        return {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if getattr(self, f.name) is not None
        }


@dataclass(frozen=True, kw_only=True)
class Segment:
    """One rigid deck segment (frame) of a deck made of several (``Scene.segments``).

    Segments are listed left to right and laid end to end along x: segment i spans
    [−L/2 + Σ_{j<i} L_j, −L/2 + Σ_{j≤i} L_j] of the deck's length L = Σ L_j (the joint gaps
    are clearances measured along the joint's face normal and do not shift the stations). A
    segment's end faces are parallel to the abutment faces (``deck.skew``) at the abutments
    and to its joint's faces (``joints[i].skew``) at a joint; its ``width`` (default
    ``deck.width``) is centred on the bridge axis, so two segments of different widths meet
    where their end faces overlap (the joint's corners at ± the narrower half-width). Mass and
    polar inertia (about the segment's own centre, the mid-point of its axis) are
    given, not derived: a frame's mass depends on its girders, diaphragms and cap beams.
    ``displacement`` and ``velocity`` give its initial state (absolute, [x, y, θ] of its
    centre, at rest by default): the scene's ``initial.deck`` table is for a one-segment deck.
    """

    name: str = spec(doc="label used in result columns (<name>_x_abs, <name>_theta, ...)")
    length: float = spec(unit="m", doc="length along x between the end faces' mid-points", gt=0.0)
    mass: float = spec(unit="t", doc="segment mass", gt=0.0)
    inertia: float = spec(unit="t*m^2", doc="polar mass moment of inertia about its centre", gt=0.0)
    width: float | None = spec(
        None, unit="m", doc="width along y, centred on the bridge axis (none: deck.width)", gt=0.0
    )
    displacement: tuple[float, ...] = spec(
        (0.0, 0.0, 0.0), unit="m, m, rad", doc="initial displacement of its centre [x, y, theta]"
    )
    velocity: tuple[float, ...] = spec(
        (0.0, 0.0, 0.0), unit="m/s, m/s, rad/s", doc="initial velocity [v_x, v_y, omega]"
    )

    def __post_init__(self) -> None:
        validate(self)
        for name in ("displacement", "velocity"):
            value = getattr(self, name)
            if len(value) != 3:
                raise SceneError(name, f"must hold 3 numbers [x, y, theta], got {list(value)}")


@dataclass(frozen=True, kw_only=True)
class Joint:
    """An expansion joint or in-span hinge between segments i and i + 1 (``Scene.joints[i]``).

    The right end face of segment i and the left end face of segment i + 1 face each other
    across the clear gap ``gap``, measured along the face normal; segment i + 1's two end
    corners strike segment i's face (the corner table of :mod:`deckpound.models.plan`, both
    bodies moving). ``support_length`` is the seat (support) length under the joint: the
    margin N − (g − g₀) of each joint corner is checked like an abutment seat's (a run whose
    margin becomes negative ends 'unseated'). The joint's corners take the scene's
    ``contact`` table (law, stiffness, restitution, friction), as the abutment corners do,
    with the fields ``contact`` gives in place of the scene's (:meth:`Scene.joint_contact`).
    """

    gap: float = spec(unit="m", doc="initial clear gap between the segment ends", ge=0.0)
    skew: float | None = spec(
        None,
        unit="deg",
        doc="skew angle of the joint's faces (none: deck.skew, the abutment faces' skew)",
        ge=0.0,
        lt=MAX_SKEW,
    )
    support_length: float | None = spec(
        None,
        unit="m",
        doc="seat (support) length under the joint, along the face normal, measured from the "
        "segment end's initial position; none (the default): the margin is not checked",
        gt=0.0,
    )
    contact: JointContact | None = spec(
        None,
        doc="the joint's own contact fields (law, stiffness, restitution, friction, ...); "
        "none (the default): the scene's contact table",
    )

    def __post_init__(self) -> None:
        validate(self)


@dataclass(frozen=True, kw_only=True)
class Damping:
    """Damping of the plan model, every choice explicit (see :mod:`deckpound.models.damping`).

    Rayleigh damping a0·M + a1·K with the ratio matched at two frequencies (``method`` modes or
    frequencies; ``none``: no Rayleigh damping, the explicit dashpots still act). The
    stiffness-proportional part acts on the deformation rates of the springs named by
    ``members`` (never the gap elements) with the ``stiffness`` it names (OpenSees ``rayleigh
    αM βK βKinit βKc``: current → βK, initial → βKinit, committed → βKc, element by element
    with ``-doRayleigh``). The mass-proportional part acts on the ``mass`` velocities:
    absolute (what OpenSees's global αM does under MultipleSupport) or relative to the
    supports (deck x, y relative to the bent tables, seats x to their actuators; rotations
    are absolute because no support rotates). Defaults: 8 % on the deck–bent system only, the
    seats damped by their identified dashpots only (Rayleigh on the seat springs would make
    them 1.55× / 2.35× critically damped), initial stiffness, absolute velocities.
    """

    ratio: float = spec(0.08, unit="-", doc="damping ratio at both frequencies", ge=0.0, lt=1.0)
    method: str = spec(
        "modes",
        doc="modes: natural modes of the contact-free elastic model; "
        "frequencies: given values; none: no Rayleigh damping (explicit dashpots "
        "still act)",
        choices=("modes", "frequencies", "none"),
    )
    modes: tuple[int, ...] = spec((1, 3), doc="the two mode numbers (1-based, by frequency)", ge=1)
    frequencies: tuple[float, ...] = spec(
        (2.0, 5.0), unit="Hz", doc="the two frequencies (method = frequencies)", gt=0.0
    )
    members: str = spec(
        "bents",
        doc="springs carrying the stiffness-proportional part: bents "
        "(the deck-bent system; the seats keep their identified dashpots "
        "only), bents+seats, none",
        choices=DAMPING_MEMBERS,
    )
    stiffness: str = spec(
        "initial",
        doc="stiffness of the stiffness-proportional part: "
        "initial (OpenSees betaKinit), committed (betaKc: the tangent at the "
        "last commit), current (betaK: the trial tangent)",
        choices=DAMPING_STIFFNESS,
    )
    mass: str = spec(
        "absolute",
        doc="velocities of the mass-proportional part: absolute "
        "(OpenSees alphaM under MultipleSupport) or relative to the supports",
        choices=DAMPING_MASS,
    )

    def __post_init__(self) -> None:
        validate(self)
        for name in ("modes", "frequencies"):
            value = getattr(self, name)
            if len(value) != 2 or value[0] == value[1]:
                raise SceneError(name, f"must hold two different values, got {list(value)}")


@dataclass(frozen=True, kw_only=True)
class Initial:
    """Initial state of the deck; the seats start at rest on their actuators.

    ``deck`` is the displacement of the deck centre from its rest position and ``deck_velocity``
    its velocity (absolute, at t = 0, when the supports are at their first record sample — at
    rest for every built-in record). Default: at rest. Non-zero values pose textbook problems
    such as a deck striking an abutment at a corner.
    """

    deck: tuple[float, ...] = spec(
        (0.0, 0.0, 0.0), unit="m, m, rad", doc="initial deck displacement [x, y, theta]"
    )
    deck_velocity: tuple[float, ...] = spec(
        (0.0, 0.0, 0.0), unit="m/s, m/s, rad/s", doc="initial deck velocity [v_x, v_y, omega]"
    )

    def __post_init__(self) -> None:
        validate(self)
        for name in ("deck", "deck_velocity"):
            value = getattr(self, name)
            if len(value) != 3:
                raise SceneError(name, f"must hold 3 numbers [x, y, theta], got {list(value)}")

    @property
    def at_rest(self) -> bool:
        return not any(self.deck) and not any(self.deck_velocity)


@dataclass(frozen=True, kw_only=True)
class Scene:
    """A complete deck-abutment pounding problem; engines take it and return a Result."""

    name: str = spec(doc="scene name")
    description: str = spec("", doc="free text")
    allow_extreme: bool = spec(
        False,
        doc="accept magnitudes no bridge has, which the plausibility checks refuse otherwise "
        "(a deck or gap given in mm, a deck mass in kg, a dimension or mass beyond any "
        "structure, friction far above any surface: deckpound.models.plausibility); for "
        "numerical experiments. The PGA has its own excitation.allow_extreme",
    )
    deck: Deck = spec(doc="the deck")
    bents: tuple[Bent, ...] = spec(doc="the bents, left to right")
    segments: tuple[Segment, ...] | None = spec(
        None,
        doc="the deck's rigid segments (frames), left to right, for a deck of two or more; "
        "none (the default): the deck is one rigid body (deck.length, deck.mass, deck.inertia)",
    )
    joints: tuple[Joint, ...] | None = spec(
        None, doc="the joints between consecutive segments (one fewer than the segments)"
    )
    seats: tuple[Seat, ...] = spec(doc="seat 1 (left) and seat 2 (right)")
    contact: Contact = spec(default_factory=Contact, doc="deck-seat contact")
    damping: Damping = spec(default_factory=Damping, doc="Rayleigh damping")
    excitation: Excitation = spec(default_factory=Excitation, doc="support motion")
    run: RunSettings = spec(default_factory=RunSettings, doc="shared run settings")
    initial: Initial = spec(default_factory=Initial, doc="initial state of the deck")
    opensees: OpenSeesSettings = spec(default_factory=OpenSeesSettings, doc="OpenSees engine")
    compliance: ComplianceSettings = spec(
        default_factory=ComplianceSettings, doc="compliance engine"
    )
    nonsmooth: NonsmoothSettings = spec(default_factory=NonsmoothSettings, doc="nonsmooth engine")
    sequence: Sequence = spec(default_factory=Sequence, doc="test sequence")
    notes: dict[str, str] = spec(
        default_factory=dict, doc="source or assumption of each value, keyed by dotted path"
    )

    def __post_init__(self) -> None:
        validate(self)
        if len(self.seats) != 2:
            raise SceneError(
                "seats", f"must hold exactly 2 seats (left, right), got {len(self.seats)}"
            )
        names = [b.name for b in self.bents]
        if len(set(names)) != len(names):
            raise SceneError("bents", f"names must be unique, got {names}")
        for i, name in enumerate(names):
            # bent names become result columns and support channels (<name>_fx, <name>_x)
            if not _NAME.match(name) or name in ("seat1", "seat2", "deck"):
                raise SceneError(
                    f"bents[{i}].name",
                    "must be a word of letters, digits and _ "
                    f"(not 'seat1', 'seat2' or 'deck'), got {name!r}",
                )
        for i, b in enumerate(self.bents):
            if not 0.0 <= b.station <= self.deck.length:
                raise SceneError(
                    f"bents[{i}].station",
                    f"must lie on the deck, in [0, {self.deck.length}] m, got {b.station}",
                )
        self._check_segments()
        self._check_free_deck()
        self._check_fixed_seats()
        for key in self.notes:
            _check_path(self, key)
        check_sequence_pgas(self)
        self._check_step_counts()

    def _check_segments(self) -> None:
        """A deck of segments: two or more, one joint fewer, lengths adding up to deck.length,
        mass and inertia consistent with the deck's, every bent on one segment."""
        segs, joints = self.segments, self.joints
        if segs is None:
            if joints is not None:
                raise SceneError("joints", "joints need segments: give segments (two or more)")
            for i, b in enumerate(self.bents):
                if b.segment is not None:
                    raise SceneError(
                        f"bents[{i}].segment",
                        f"names segment {b.segment!r}, but the scene has no segments",
                    )
            return
        if len(segs) < 2:
            raise SceneError(
                "segments",
                f"must hold two or more segments, got {len(segs)} (a one-segment deck is the "
                "deck table alone: leave segments out)",
            )
        n_joints = 0 if joints is None else len(joints)
        if n_joints != len(segs) - 1:
            raise SceneError(
                "joints",
                f"must hold one joint between each pair of consecutive segments: "
                f"{len(segs) - 1} for {len(segs)} segments, got {n_joints}",
            )
        for k in range(n_joints):
            self.joint_contact(k)
        names = [s.name for s in segs]
        bent_names = {b.name for b in self.bents}
        for i, name in enumerate(names):
            if (
                not _NAME.match(name)
                or name in ("seat1", "seat2", "deck")
                or name in bent_names
                or names.index(name) != i
            ):
                raise SceneError(
                    f"segments[{i}].name",
                    "must be a unique word of letters, digits and _ (not 'seat1', 'seat2', "
                    f"'deck' or a bent's name), got {name!r}",
                )
        _check_sum("deck.length", self.deck.length, [s.length for s in segs], "segment lengths")
        _check_sum("deck.mass", self.deck.mass, [s.mass for s in segs], "segment masses")
        _check_sum(
            "deck.inertia",
            self.deck.inertia,
            [s.inertia + s.mass * c**2 for s, c in zip(segs, self.segment_centres)],
            "segment inertias about the deck centre (Σ I_i + m_i x_i²)",
        )
        for i in range(len(self.bents)):
            self.segment_of_bent(i)
        if not self.initial.at_rest:
            raise SceneError(
                "initial",
                "initial.deck and initial.deck_velocity describe a one-segment deck; give "
                "segments[i].displacement and segments[i].velocity instead",
            )

    def joint_contact(self, k: int) -> Contact:
        """The contact table of joint ``k``'s corners: the scene's ``contact`` with the fields
        ``joints[k].contact`` gives in their place (validated as a Contact; a refusal names
        the joint's field)."""
        own = self.joints[k].contact if self.joints is not None else None
        given = own.given() if own is not None else {}
        if not given:
            return self.contact
        try:
            return dataclasses.replace(self.contact, **given)
        except SceneError as err:
            raise joint_contact_error(err, k) from None

    def contact_tables(self) -> list[tuple[str, Contact]]:
        """Every contact table the scene's corners use, with where it is given: the scene's
        ``contact``, then each joint that gives contact fields of its own."""
        out = [("contact", self.contact)]
        for k, joint in enumerate(self.joints or ()):
            if joint.contact is not None and joint.contact.given():
                out.append((f"joints[{k}].contact", self.joint_contact(k)))
        return out

    @property
    def segment_centres(self) -> tuple[float, ...]:
        """x of each segment's centre from the deck centre [m] (one segment: (0.0,))."""
        if self.segments is None:
            return (0.0,)
        out, left = [], -0.5 * self.deck.length
        for s in self.segments:
            out.append(left + 0.5 * s.length)
            left += s.length
        return tuple(out)

    def segment_of_bent(self, index: int) -> int:
        """Index of the segment bent ``index`` carries (0 for a one-segment deck)."""
        b = self.bents[index]
        if self.segments is None:
            return 0
        names = [s.name for s in self.segments]
        if b.segment is not None:
            if b.segment not in names:
                raise SceneError(
                    f"bents[{index}].segment",
                    f"names no segment: {b.segment!r}; the segments are {', '.join(names)}",
                )
            k = names.index(b.segment)
            left = sum(s.length for s in self.segments[:k])
            if not left <= b.station <= left + self.segments[k].length:
                raise SceneError(
                    f"bents[{index}].station",
                    f"{b.station} m lies outside segment {b.segment!r}, which spans "
                    f"[{left:g}, {left + self.segments[k].length:g}] m from the deck's left end",
                )
            return k
        left = 0.0
        for k, s in enumerate(self.segments):
            right = left + s.length
            if left < b.station < right or (k == 0 and b.station == left):
                return k
            if b.station == right and k == len(self.segments) - 1:
                return k
            if b.station == right:
                raise SceneError(
                    f"bents[{index}].segment",
                    f"bent {b.name!r} stands at the joint between segments {s.name!r} and "
                    f"{self.segments[k + 1].name!r} ({b.station} m): name the segment it carries",
                )
            left = right
        raise SceneError(f"bents[{index}].station", f"lies beyond the deck: {b.station} m")

    def _check_free_deck(self) -> None:
        """``bents = []`` leaves the deck free in plan: the contact-free model then has three
        rigid-body modes (deck x, y, θ at zero frequency), so Rayleigh damping matched at modes
        1-3 is undefined (ω = 0); refuse it unless the ratio is 0."""
        d = self.damping
        if not self.bents and d.method == "modes" and d.ratio > 0.0 and min(d.modes) <= 3:
            raise SceneError(
                "damping.method",
                "'modes' needs the natural frequencies of the "
                "contact-free model, but with bents = [] the deck is free in "
                "plan: modes 1-3 are its rigid-body modes at zero frequency; give "
                "damping.method = 'frequencies' (with damping.frequencies), modes "
                f"above 3, or damping.ratio = 0 (got modes {list(d.modes)})",
            )

    def _check_fixed_seats(self) -> None:
        """A fixed seat is exact only with its actuator at rest (see :class:`Seat`)."""
        exc = self.excitation
        at_rest = exc.kind == "none" or (
            exc.kind in ("synthetic", "pulse") and exc.longitudinal_ratio == 0.0
        )
        for i, seat in enumerate(self.seats):
            if seat.fixed and not at_rest:
                raise SceneError(
                    f"seats[{i}].fixed",
                    "a fixed (rigid) seat needs its actuator "
                    "at rest: excitation.kind = 'none', or a synthetic/pulse "
                    "record with longitudinal_ratio = 0 (the engines cannot "
                    "prescribe a moving seat); use stiff seat springs instead, "
                    f"got excitation.kind = {exc.kind!r}",
                )

    def _check_step_counts(self) -> None:
        """Refuse steps so small that a run could not fit in memory or time (MAX_STEPS)."""
        duration = self.run.duration
        if duration is None and self.excitation.kind in ("synthetic", "pulse", "none"):
            duration = self.excitation.duration
        if duration is None:
            return  # a loaded record: checked when it is resampled
        for field, step in (
            ("run.output_dt", self.run.output_dt),
            ("opensees.dt", self.opensees.dt),
            ("compliance.dt", self.compliance.dt),
            ("nonsmooth.h", self.nonsmooth.h),
        ):
            if duration / step > MAX_STEPS:
                raise SceneError(
                    field,
                    f"gives {duration / step:.3g} steps over {duration:g} s; at "
                    f"most {MAX_STEPS:.0e} are allowed, so it must be >= "
                    f"{duration / MAX_STEPS:.3g} s, got {step}",
                )

    def replace(self, paths: Mapping[str, Any] | None = None, /, **changes) -> Scene:
        """A copy with fields replaced, validated again.

        ``changes`` replace top-level fields (``scene.replace(name="b")``); ``paths`` maps
        dotted field paths, the syntax of ``--set``, to values:
        ``scene.replace({"contact.stiffness": 2e6, "bents[1].y.beta": 0.3})``. A value may be
        a number, string, bool, list or a description record (``Contact(...)``). A path that
        names no field, an index out of range or a value out of its range is refused with a
        SceneError naming the path.
        """
        scene = dataclasses.replace(self, **changes) if changes else self
        if not paths:
            return scene
        if not isinstance(paths, Mapping):
            raise SceneError(
                "replace",
                "takes a mapping of dotted paths to values "
                f"({{'contact.stiffness': 2e6}}), got {type(paths).__name__}",
            )
        data = to_mapping(scene)
        for path, value in paths.items():
            set_path(data, str(path), _plain(value), source=f"replace({path!r})")
        return from_mapping(Scene, data)

    # -- short text for consoles and notebooks ---------------------------------------
    def summary(self) -> dict[str, str]:
        """The scene's key facts as short texts (name, deck, bents, gaps, contact, record):
        what :meth:`__repr__` and :meth:`_repr_html_` show."""
        gaps = "/".join(f"{1e3 * s.gap:g}" for s in self.seats)
        skew = f", skew {self.deck.skew:g}°" if self.deck.skew else ""
        # the laws whose force is K·δ^n carry K in kN/m^n (contact.stiffness)
        uses_exponent = "contact.exponent" in contact_law(self.contact.law).params
        k_unit = f"kN/m^{self.contact.exponent:g}" if uses_exponent else "kN/m"
        segments = (
            f", {len(self.segments)} segments, joint gaps "
            + "/".join(f"{1e3 * j.gap:g}" for j in self.joints or ())
            + " mm"
            if self.segments is not None
            else ""
        )
        # a joint's own contact fields, as given (the rest is the scene's)
        joints = "".join(
            f"; joints[{k}]: "
            + ", ".join(
                f"{name} {value:g}" if isinstance(value, float) else f"{name} {value}"
                for name, value in j.contact.given().items()
            )
            for k, j in enumerate(self.joints or ())
            if j.contact is not None and j.contact.given()
        )
        return {
            "name": self.name,
            "deck": f"{self.deck.length:g} × {self.deck.width:g} m, {self.deck.mass:g} t{skew}"
            + segments,
            "bents": f"{len(self.bents)}",
            "gaps": f"{gaps} mm",
            "contact": f"{self.contact.law}, k = {self.contact.stiffness:g} {k_unit}"
            + (f", μ = {self.contact.friction:g}" if self.contact.has_friction else "")
            + joints,
            "record": self.excitation.kind,
        }

    def __repr__(self) -> str:
        facts = self.summary()
        return (
            f"Scene({short_text(facts['name'])!r}, deck {facts['deck']}, {facts['bents']} bents, "
            f"gaps {facts['gaps']}, contact {facts['contact']}, record {facts['record']})"
        )

    def _repr_html_(self) -> str:
        """An HTML table of :meth:`summary` for notebooks (every text escaped)."""
        return html_table("Scene", self.summary())


def joint_contact_error(err: SceneError, k: int) -> SceneError:
    """``err``, raised on joint ``k``'s contact table (:meth:`Scene.joint_contact`, or an
    engine's refusal of it), with the field named where the joint gives it: ``restitution``
    or ``contact.restitution`` → ``joints[k].contact.restitution``; a refusal that names
    another table (``compliance.integrator``) keeps its field and says which joint asked."""
    field = err.field
    names = {f.name for f in dataclasses.fields(Contact)}
    if not field or field == "contact":
        return SceneError(f"joints[{k}].contact", err.reason)
    if field.startswith("contact."):
        return SceneError(f"joints[{k}].{field}", err.reason)
    if field in names:
        return SceneError(f"joints[{k}].contact.{field}", err.reason)
    return SceneError(field, f"{err.reason} (at joint {k}: joints[{k}].contact)")


def _check_sum(field: str, value: float, parts: list[float], what: str) -> None:
    """Refuse a deck value that differs from the sum of its segments' (relative 1e-9)."""
    total = float(sum(parts))
    if abs(value - total) > 1e-9 * max(abs(value), abs(total)):
        raise SceneError(
            field,
            f"must equal the sum of the {what}, {total:.12g}, for a deck of segments; got "
            f"{value:.12g}",
        )


def _plain(value: Any) -> Any:
    """A value for :meth:`Scene.replace` as the nested mapping holds it: description records
    and tuples as tables and lists, numpy scalars as Python numbers."""
    if getattr(value, "shape", None) == () and hasattr(value, "item"):
        return value.item()
    return to_mapping(value)


@functools.cache
def _field_names(cls: type) -> frozenset[str]:
    """The field names of a description class (asked for every notes key of every scene)."""
    return frozenset(f.name for f in dataclasses.fields(cls))


def _check_path(scene: Scene, key: str) -> None:
    """Check that a notes key names an existing field (``bents[0].x.stiffness``)."""
    obj = scene
    for part in key.replace("]", "").split("."):
        name, _, index = part.partition("[")
        if not dataclasses.is_dataclass(obj) or name not in _field_names(type(obj)):
            raise SceneError(f"notes.{key}", "names no field of the scene")
        obj = getattr(obj, name)
        if index:
            try:
                obj = obj[int(index)]
            except (ValueError, IndexError, TypeError):
                raise SceneError(f"notes.{key}", "names no field of the scene") from None

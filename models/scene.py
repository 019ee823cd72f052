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
import re
from dataclasses import dataclass

from ._fields import spec, validate
from .contact_laws_table import FRICTION_CODES, LAW_CODES, contact_law
from .errors import SceneError

CONTACT_LAWS = tuple(LAW_CODES)  # the rows of contact_laws_table, in code order
FRICTION_MODES = tuple(FRICTION_CODES)
DAMPING_MEMBERS = ("bents", "bents+seats", "none")
DAMPING_STIFFNESS = ("initial", "committed", "current")
DAMPING_MASS = ("absolute", "relative")
GEOMETRIES = ("linear", "nonlinear")
#: the nonsmooth engine's impact laws (:func:`deckpound.analytic.nonsmooth.separating_restitution`)
IMPACT_LAWS = ("newton", "energy-safe")
SUPPORTS_PER_BENT = ("x", "y")
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,31}$")
#: largest number of time steps one run may take (a 60 s record at 1e-5 s is 6e6)
MAX_STEPS = 50_000_000
#: largest number of Newton iterations per step (more means the step does not converge)
MAX_ITERATIONS = 10_000


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


#: largest PGA [g] accepted in any direction unless ``excitation.allow_extreme`` (recorded
#: ground motions stay below about 4 g; more is a wrong unit or a typing error)
EXTREME_PGA = 5.0
#: largest PGA [g] accepted even with ``allow_extreme`` (no physical value; overflow ahead)
ABSURD_PGA = 1000.0
RECORD_KINDS = ("csv", "at2", "text")


@dataclass(frozen=True, kw_only=True)
class Excitation:
    """Multi-support excitation: 3 shake tables (x, y) and 2 seat actuators (x).

    kind = synthetic: a seeded earthquake-like record (filtered white noise, envelope, and the
    generator's built-in baseline correction: ``highpass``, taper) scaled to ``pga``
    (transverse) and ``longitudinal_ratio`` · pga (x);
    kind = at2: PEER AT2 acceleration records [g] ``file_x`` and ``file_y``;
    kind = text: two-column records (time [s], acceleration [``acc_unit``]) ``file_x``,
    ``file_y``; for both, one of the two may be left out (that direction is at rest);
    kind = csv: ``file`` with ``time_column`` and either ground accelerations ``acc_x``,
    ``acc_y`` [``acc_unit``] or, per support channel, displacements ``<channel>_disp`` and
    optionally ``<channel>_vel`` [``disp_unit``] (channels bent1_x, bent1_y, ..., seat1_x,
    seat2_x);
    kind = pulse: one longitudinal displacement pulse d = D(1 − cos 2πt/T)/2 for t ≤ T
    (``pulse_period`` T), max acceleration pga · longitudinal_ratio, no transverse motion —
    the canonical single-impact input;
    kind = none: every support at rest for ``duration`` seconds (or ``run.duration``) — free
    vibration from the ``[initial]`` state, the textbook impact problems.

    Records (at2, text, csv) are applied at every table (x and y), the actuators follow x;
    they are time-scaled by ``time_scale``, processed by ``processing`` (default none: real
    records are already processed) and scaled by ``scaling`` (default pga: to ``pga`` in y and
    ``longitudinal_ratio`` · pga in x, like the synthetic record, so a sequence or study run
    labelled 0.5 g is driven at 0.5 g). See :mod:`deckpound.models.record_motion`. Any
    direction above ``EXTREME_PGA`` g is refused unless ``allow_extreme``.
    """

    kind: str = spec(
        "synthetic",
        doc="record source",
        choices=("synthetic", "csv", "at2", "text", "pulse", "none"),
    )
    pga: float = spec(
        0.5,
        unit="g",
        doc="transverse peak ground acceleration (run label; > 5 g needs allow_extreme)",
        gt=0.0,
        le=100.0,
    )
    longitudinal_ratio: float = spec(
        1.2, unit="-", doc="longitudinal PGA / transverse PGA", ge=0.0, le=10.0
    )
    seed: int = spec(1994, doc="random seed of the synthetic record", ge=0)
    duration: float = spec(20.0, unit="s", doc="synthetic record length", gt=0.0, le=600.0)
    dt: float = spec(0.005, unit="s", doc="synthetic record sampling step", gt=0.0, le=0.1)
    dominant_frequency: float = spec(
        3.5, unit="Hz", doc="Kanai-Tajimi ground frequency of the synthetic record", gt=0.0
    )
    ground_damping: float = spec(
        0.6, unit="-", doc="Kanai-Tajimi ground damping ratio", gt=0.0, lt=5.0
    )
    highpass: float = spec(
        0.5,
        unit="Hz",
        doc="high-pass corner: the synthetic generator's "
        "baseline correction, and records with processing = highpass "
        "(model time)",
        gt=0.0,
    )
    lag: float = spec(0.0, unit="s", doc="time lag between successive bent tables", ge=0.0)
    incoherence: float = spec(
        0.0,
        unit="-",
        doc="fraction of independent noise at each table (0 = coherent)",
        ge=0.0,
        le=1.0,
    )
    file: str | None = spec(None, doc="CSV file (kind = csv), relative to the scene file")
    time_column: str = spec("t", doc="CSV time column")
    disp_unit: str = spec("m", doc="CSV displacement unit", choices=("m", "cm", "mm", "in"))
    acc_unit: str = spec(
        "g",
        doc="acceleration unit of text and CSV records (AT2: always g)",
        choices=("g", "m/s^2", "cm/s^2"),
    )
    file_x: str | None = spec(
        None, doc="x (longitudinal) record (kind = at2 or text), relative to the scene file"
    )
    file_y: str | None = spec(
        None, doc="y (transverse) record (kind = at2 or text), relative to the scene file"
    )
    scaling: str = spec(
        "pga",
        doc="records: pga = to pga (y) and longitudinal_ratio*pga (x); "
        "factor = times scale; none = as read",
        choices=("pga", "factor", "none"),
    )
    scale: float = spec(1.0, unit="-", doc="factor applied to records (scaling = factor)", gt=0.0)
    time_scale: float = spec(
        1.0,
        unit="-",
        doc="similitude time scale of records: t_model = "
        "time_scale*t (accelerations kept: v x time_scale, "
        "d x time_scale^2)",
        gt=0.0,
        le=10.0,
    )
    processing: str = spec(
        "none",
        doc="records: none = integrate as given; baseline = remove "
        "a fitted polynomial baseline; highpass = zero-phase Butterworth at "
        "highpass Hz",
        choices=("none", "baseline", "highpass"),
    )
    allow_extreme: bool = spec(False, doc="accept a PGA above 5 g in any direction")
    pulse_period: float = spec(0.5, unit="s", doc="period of the pulse (kind = pulse)", gt=0.0)

    def __post_init__(self) -> None:
        validate(self)
        if self.kind == "csv" and not self.file:
            raise SceneError("file", "is required when kind = 'csv'")
        if self.kind in ("at2", "text") and not (self.file_x or self.file_y):
            raise SceneError(
                "file_x",
                f"or file_y is required when kind = {self.kind!r} (one "
                "record per direction; a direction without one is at rest)",
            )
        record = self.kind in RECORD_KINDS
        for name, value, default, why in (
            ("scaling", self.scaling, "pga", "generated records are made at pga"),
            ("time_scale", self.time_scale, 1.0, "generated records are made at model time"),
            (
                "processing",
                self.processing,
                "none",
                "the synthetic generator has its own baseline correction (highpass)",
            ),
        ):
            if not record and value != default:
                raise SceneError(
                    name,
                    f"applies to records (kind = csv, at2, text), not to kind "
                    f"= {self.kind!r} ({why}); must be {default!r}, got {value!r}",
                )
        if record and self.incoherence > 0.0:
            raise SceneError(
                "incoherence",
                f"applies to the synthetic record only (a record is "
                f"applied at every table, delayed by lag); must be 0.0 for kind = "
                f"{self.kind!r}, got {self.incoherence}",
            )
        if self.scale != 1.0 and self.scaling != "factor":
            raise SceneError(
                "scale",
                f"is used only with scaling = 'factor' (scaling is "
                f"{self.scaling!r}); must be 1.0, got {self.scale}",
            )
        if self.kind == "at2" and self.acc_unit != "g":
            raise SceneError(
                "acc_unit",
                f"must be 'g' for AT2 records (the format's unit), got {self.acc_unit!r}",
            )
        self.check_pga(self.pga, "pga")

    def check_pga(self, pga: float, field: str) -> None:
        """Refuse a label ``pga`` [g] whose transverse or longitudinal target exceeds
        EXTREME_PGA, unless allow_extreme (records scaled otherwise are checked when loaded)."""
        if self.allow_extreme or self.scaling != "pga":
            return
        for what, value in (("transverse", pga), ("longitudinal", pga * self.longitudinal_ratio)):
            if value > EXTREME_PGA:
                extra = (
                    ""
                    if what == "transverse"
                    else f" = {pga:g} g x longitudinal_ratio {self.longitudinal_ratio:g}"
                )
                raise SceneError(
                    field,
                    f"gives a {what} PGA of {value:g} g{extra}; at most "
                    f"{EXTREME_PGA:g} g is allowed unless excitation.allow_extreme = "
                    f"true, got {pga}",
                )


def check_sequence_pgas(scene: Scene) -> None:
    """Validate every run of the sequence up front: each label through the excitation's PGA
    check (a 6 g run is refused naming ``sequence.pgas[i]``, not half-way through a run)."""
    for i, pga in enumerate(scene.sequence.pgas):
        scene.excitation.check_pga(pga, f"sequence.pgas[{i}]")


@dataclass(frozen=True, kw_only=True)
class RunSettings:
    """What every engine shares: how long to run and how often to store output."""

    duration: float | None = spec(
        None, unit="s", doc="analysis length (default: the record length)", gt=0.0
    )
    output_dt: float = spec(0.005, unit="s", doc="output step of the stored result", gt=0.0)

    def __post_init__(self) -> None:
        validate(self)


@dataclass(frozen=True, kw_only=True)
class OpenSeesSettings:
    """Settings of the OpenSees engine (plain data; the scene does not import OpenSees)."""

    mode: str = spec(
        "rigid",
        doc="rigid: 7-DOF rigid bodies via constraints; stick: stiff elastic sticks (paper)",
        choices=("rigid", "stick"),
    )
    dt: float = spec(5.0e-4, unit="s", doc="analysis time step", gt=0.0)
    gamma: float = spec(0.5, unit="-", doc="Newmark gamma", gt=0.0, le=1.0)
    beta: float = spec(0.25, unit="-", doc="Newmark beta", gt=0.0, le=0.5)
    algorithm: str = spec(
        "Newton",
        doc="solution algorithm",
        choices=("Newton", "ModifiedNewton", "KrylovNewton", "NewtonLineSearch"),
    )
    test: str = spec(
        "NormDispIncr",
        doc="convergence test",
        choices=("NormDispIncr", "EnergyIncr", "NormUnbalance"),
    )
    tolerance: float = spec(1.0e-10, unit="m", doc="convergence tolerance", gt=0.0)
    max_iterations: int = spec(50, doc="Newton iterations per step", ge=1, le=MAX_ITERATIONS)
    system: str = spec(
        "BandGeneral",
        doc="linear system",
        choices=("BandGeneral", "UmfPack", "FullGeneral", "SparseGeneral"),
    )
    fallback: str = spec(
        "substep",
        doc="on a failed step: none, or rebuild the analysis and sub-step",
        choices=("none", "substep"),
    )
    substeps: int = spec(10, doc="sub-steps per step in the fallback", ge=2, le=1000)
    stick_elements: int = spec(4, doc="elements per deck half in stick mode", ge=1, le=100)

    def __post_init__(self) -> None:
        validate(self)


@dataclass(frozen=True, kw_only=True)
class ComplianceSettings:
    """Settings of the pure-Python compliance engine."""

    integrator: str = spec(
        "newmark",
        doc="newmark: fixed-step Newmark-Newton (OpenSees clone); "
        "adaptive: error-controlled with event location",
        choices=("newmark", "adaptive"),
    )
    dt: float = spec(5.0e-4, unit="s", doc="time step (newmark)", gt=0.0)
    tolerance: float = spec(1.0e-10, unit="m", doc="Newton NormDispIncr tolerance", gt=0.0)
    max_iterations: int = spec(50, doc="Newton iterations per step", ge=1, le=MAX_ITERATIONS)
    rtol: float = spec(1.0e-6, unit="-", doc="relative tolerance (adaptive)", gt=0.0)
    atol: float = spec(1.0e-9, unit="m", doc="absolute tolerance (adaptive)", gt=0.0)
    max_step: float = spec(0.01, unit="s", doc="largest step (adaptive)", gt=0.0)
    commit_step: float = spec(
        1.0e-4,
        unit="s",
        doc="largest step (adaptive) once a Takeda spring has yielded: "
        "the Hysteretic state depends on where it is committed",
        gt=0.0,
    )
    contact_tangent: str = spec(
        "consistent",
        doc="Newton's contact tangent (newmark): "
        "consistent = the laws' derivatives; opensees = what the OpenSees "
        "materials report (ViscoelasticGap: no damping tangent; "
        "Hertzdamp: opposite sign, no damping tangent) — the same "
        "forces, OpenSees's Newton iterates (round-off agreement)",
        choices=("consistent", "opensees"),
    )
    max_steps: int = spec(
        10_000_000,
        doc="step budget (adaptive): Runge-Kutta steps tried, "
        "accepted or rejected, before the run stops with status step_budget; "
        "about 50x the 0.2 million steps of the 20 s benchmark, 1-3 min of "
        "loop at 6-20 us per step",
        ge=1,
        le=10**12,
    )

    def __post_init__(self) -> None:
        validate(self)


@dataclass(frozen=True, kw_only=True)
class NonsmoothSettings:
    """Settings of the nonsmooth (Moreau-Jean) engine."""

    h: float = spec(1.0e-3, unit="s", doc="time step", gt=0.0)
    theta: float = spec(0.5, unit="-", doc="theta of the Moreau-Jean scheme", ge=0.5, le=1.0)
    solver: str = spec("lemke", doc="contact problem solver", choices=("lemke", "enumeration"))
    tolerance: float = spec(1.0e-10, unit="-", doc="complementarity tolerance", gt=0.0)
    max_iterations: int = spec(
        50, doc="Newton iterations per step for the Takeda springs", ge=1, le=MAX_ITERATIONS
    )
    impact_law: str = spec(
        "newton",
        doc="newton: Newton's law 0 <= U_N+ + e U_N- at every "
        "active corner (Siconos' Moreau-Jean); energy-safe: restitution "
        "max(e, (1-theta)/theta) at active corners already separating "
        "(U_N- > 0), so no normal impulse does positive work",
        choices=IMPACT_LAWS,
    )

    def __post_init__(self) -> None:
        validate(self)


@dataclass(frozen=True, kw_only=True)
class Sequence:
    """The experiment's sequence of runs on one specimen, carrying damage from run to run.

    Start-of-run gap: each seat's gap minus the residual closing displacement of the previous
    run (deck end relative to the seat face, averaged over the face's two corners), floored at 0.
    Bent stiffness: k_next = min(k, k0·μ^(−β)) with μ = peak |deformation| / yield deformation
    of the previous run (the Takeda unloading stiffness at that peak), per bent and direction.
    """

    pgas: tuple[float, ...] = spec(
        (0.075, 0.15, 0.25, 0.5, 0.75, 1.0, 1.0),
        unit="g",
        doc="transverse PGA label of each run",
        gt=0.0,
    )
    carry_gap: bool = spec(True, doc="start each run from the previous run's residual gap")
    carry_stiffness: bool = spec(True, doc="degrade bent stiffness by the previous peak")

    def __post_init__(self) -> None:
        validate(self)
        if not self.pgas:
            raise SceneError("pgas", "must hold at least one run")


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
    deck: Deck = spec(doc="the deck")
    bents: tuple[Bent, ...] = spec(doc="the bents, left to right")
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
        self._check_free_deck()
        self._check_fixed_seats()
        for key in self.notes:
            _check_path(self, key)
        check_sequence_pgas(self)
        self._check_step_counts()

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

    # -- derived geometry (the plan model is the one definition) ------------------------
    @property
    def bent_x(self) -> tuple[float, ...]:
        """Bent positions in deck coordinates, x = station − L/2 [m] (see the plan model)."""
        from .plan import plan_of

        return plan_of(self).bent_x

    @property
    def corners(self) -> tuple[tuple[float, float], ...]:
        """Corner coordinates (x_c, y_c) [m] of c1 … c4 (see the plan model's corner table)."""
        from .plan import plan_of

        return tuple((c.x, c.y) for c in plan_of(self).corners)

    def replace(self, **changes) -> Scene:
        """A copy with top-level fields replaced (validated again)."""
        return dataclasses.replace(self, **changes)


def _check_path(scene: Scene, key: str) -> None:
    """Check that a notes key names an existing field (``bents[0].x.stiffness``)."""
    obj = scene
    for part in key.replace("]", "").split("."):
        name, _, index = part.partition("[")
        if not dataclasses.is_dataclass(obj) or name not in {
            f.name for f in dataclasses.fields(obj)
        }:
            raise SceneError(f"notes.{key}", "names no field of the scene")
        obj = getattr(obj, name)
        if index:
            try:
                obj = obj[int(index)]
            except (ValueError, IndexError, TypeError):
                raise SceneError(f"notes.{key}", "names no field of the scene") from None

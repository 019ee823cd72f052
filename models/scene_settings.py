"""The engine settings sections of a scene: plain data each engine reads (``[run]``,
``[opensees]``, ``[compliance]``, ``[nonsmooth]``).

The scene does not import the engines; the result cache hashes each engine's section apart
from the physics, so changing one engine's settings re-runs only that engine.
"""

from __future__ import annotations

from dataclasses import dataclass

from .fields import spec, validate

#: largest number of time steps one run may take (a 60 s record at 1e-5 s is 6e6)
MAX_STEPS = 50_000_000
#: largest number of Newton iterations per step (more means the step does not converge)
MAX_ITERATIONS = 10_000
#: the nonsmooth engine's impact laws (:func:`deckpound.analytic.nonsmooth.engine.separating_restitution`)
IMPACT_LAWS = ("newton", "energy-safe")
#: what the analytic engines' step loops do with subnormal numbers (:mod:`deckpound.analytic.fp_mode`)
SUBNORMAL_MODES = ("flush", "keep")
#: magnitude above which "flush" and "keep" results are bit-identical (tests/test_fp_mode.py)
SUBNORMALS_UNCHANGED_ABOVE = 1.0e-250
_SUBNORMALS_DOC = (
    "numbers below 2.2e-308 in the step loop: flush = set to zero (x86 FTZ/DAZ: results "
    "change only below 1e-250, and a freely decaying DOF no longer takes the processor's "
    "slow path for subnormals); keep = IEEE gradual underflow, as OpenSees"
)


@dataclass(frozen=True, kw_only=True)
class RunSettings:
    """What every engine shares: how long to run and how often to store output."""

    duration: float | None = spec(
        None, unit="s", doc="analysis length (default: the record length)", gt=0.0
    )
    output_dt: float = spec(0.005, unit="s", doc="output step of the stored result", gt=0.0)
    steps_per_contact_period: float = spec(
        3.5,
        unit="-",
        doc="fewest steps per contact oscillation period 2π√(m_eff/k) of the fixed-step "
        "penalty engines (compliance newmark, OpenSees): a longer dt is shortened to resolve "
        "the contact; 0 runs dt as given",
        ge=0.0,
        le=1000.0,
    )
    energy_tolerance: float = spec(
        0.01,
        unit="-",
        doc="energy a contact may create (negative contact or friction dissipation), or the "
        "work-energy balance may miss, as a fraction of the input energy before a run is "
        "'doubtful'",
        gt=0.0,
        le=1.0,
    )
    accept_doubtful: bool = spec(
        False,
        doc="a doubtful run (energy created by a contact) still exits 0 and counts as a "
        "success in studies",
    )

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
    subnormals: str = spec("flush", doc=_SUBNORMALS_DOC, choices=SUBNORMAL_MODES)

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
    subnormals: str = spec("flush", doc=_SUBNORMALS_DOC, choices=SUBNORMAL_MODES)

    def __post_init__(self) -> None:
        validate(self)

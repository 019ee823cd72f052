"""The ``[excitation]`` and ``[sequence]`` sections of a scene: which ground motion drives the
supports, how a record is processed and scaled, the PGA checks, and the runs of the test
sequence.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from .errors import SceneError
from .fields import spec, validate

if TYPE_CHECKING:
    from .scene import Scene

#: largest PGA [g] accepted in any direction unless ``excitation.allow_extreme`` (recorded
#: ground motions stay below about 4 g; more is a wrong unit or a typing error)
EXTREME_PGA = 5.0
#: largest PGA [g] accepted even with ``allow_extreme`` (no physical value; overflow ahead)
ABSURD_PGA = 1000.0
RECORD_KINDS = ("csv", "at2", "text")
#: scalings of a record pair by one factor to a target intensity measure (component ratio kept)
PAIR_SCALINGS = ("pair-pga", "pair-pgv", "pair-sa", "pair-rotd50")
#: the field holding each pair scaling's target, and its unit
PAIR_TARGETS = {
    "pair-pga": ("pga", "g"),
    "pair-pgv": ("target_pgv", "m/s"),
    "pair-sa": ("target_sa", "g"),
    "pair-rotd50": ("target_sa", "g"),
}


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
    records are already processed) and scaled by ``scaling`` (default pga: each component to
    its own target, ``pga`` in y and ``longitudinal_ratio`` · pga in x, like the synthetic
    record, so a sequence or study run labelled 0.5 g is driven at 0.5 g; the pair scalings
    ``pair-pga``, ``pair-pgv``, ``pair-sa``, ``pair-rotd50`` multiply both components by one
    factor to a target intensity measure and keep the record's component ratio, for suites of
    real record pairs). See :mod:`deckpound.models.record_motion`. Any direction above
    ``EXTREME_PGA`` g is refused unless ``allow_extreme``. The intensity measures of the
    applied motion (:mod:`deckpound.models.intensity`, at ``im_period``) are kept in its
    provenance.
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
    lag: float = spec(
        0.0,
        unit="s",
        doc="time lag between successive bent tables (bents at one station share a table)",
        ge=0.0,
    )
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
        doc="records: pga = each component to its own target, pga (y) and "
        "longitudinal_ratio*pga (x), replacing the record's component ratio; pair-pga, "
        "pair-pgv, pair-sa, pair-rotd50 = both components times one factor (their ratio "
        "kept) so that the pair's geometric-mean PGA = pga, geometric-mean PGV = target_pgv, "
        "geometric-mean Sa(im_period, 5 %) = target_sa or RotD50(im_period) = target_sa; "
        "factor = times scale; none = as read",
        choices=PAIR_SCALINGS + ("pga", "factor", "none"),
    )
    target_pgv: float | None = spec(
        None,
        unit="m/s",
        doc="geometric-mean PGV of the pair (scaling = pair-pgv; no default: a velocity "
        "target is the user's choice, no PGA label implies one)",
        gt=0.0,
        le=100.0,
    )
    target_sa: float | None = spec(
        None,
        unit="g",
        doc="geometric-mean Sa or RotD50 at im_period (scaling = pair-sa, pair-rotd50; no "
        "default: a spectral target depends on the site and period, not on the PGA label)",
        gt=0.0,
        le=100.0,
    )
    im_period: float | None = spec(
        None,
        unit="s",
        doc="period of the spectral intensity measures (Sa, RotD) kept in the record "
        "provenance and of scaling = pair-sa, pair-rotd50 (model time); none (the "
        "default): T1 of the contact-free model, the longest natural period that "
        "'deckpound modes' lists, at which the bridge responds most",
        gt=0.0,
        le=100.0,
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
        self._check_pair_scaling()
        if self.kind == "at2" and self.acc_unit != "g":
            raise SceneError(
                "acc_unit",
                f"must be 'g' for AT2 records (the format's unit), got {self.acc_unit!r}",
            )
        self.check_pga(self.pga, "pga")

    def _check_pair_scaling(self) -> None:
        """A pair scaling needs a record with two components and its target; a target given
        for another scaling would be silently ignored, so it is refused."""
        if self.scaling in PAIR_SCALINGS:
            if self.kind not in ("at2", "text", "csv"):
                return  # refused above: scaling applies to records only
            if self.kind in ("at2", "text") and not (self.file_x and self.file_y):
                raise SceneError(
                    "scaling",
                    f"{self.scaling!r} scales a pair of components by one factor; it needs "
                    "both file_x and file_y (a single component: use scaling = 'pga' or "
                    "'factor')",
                )
            name, unit = PAIR_TARGETS[self.scaling]
            if getattr(self, name) is None:
                raise SceneError(
                    name,
                    f"is required with scaling = {self.scaling!r} (the target in {unit}); "
                    "it has no default",
                )
        for name in ("target_pgv", "target_sa"):
            if getattr(self, name) is not None and (
                self.scaling not in PAIR_SCALINGS or PAIR_TARGETS[self.scaling][0] != name
            ):
                users = [k for k, (f, _) in PAIR_TARGETS.items() if f == name]
                raise SceneError(
                    name,
                    f"is used only with scaling = {' or '.join(map(repr, users))} (scaling is "
                    f"{self.scaling!r}); leave it out, got {getattr(self, name)}",
                )

    def check_pga(self, pga: float, field: str) -> None:
        """Refuse a label ``pga`` [g] whose transverse or longitudinal target exceeds
        EXTREME_PGA, unless allow_extreme (records scaled otherwise are checked when loaded)."""
        if self.allow_extreme or self.scaling not in ("pga", "pair-pga"):
            return
        if self.scaling == "pair-pga":
            if pga > EXTREME_PGA:
                raise SceneError(
                    field,
                    f"gives a geometric-mean PGA of {pga:g} g; at most {EXTREME_PGA:g} g "
                    f"is allowed unless excitation.allow_extreme = true, got {pga}",
                )
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

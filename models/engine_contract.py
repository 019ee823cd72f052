"""The engine contract: what an engine declares and implements, and the shared epilogue.

An engine is a subclass of :class:`Engine` registered by name in :mod:`deckpound.compare.engines`.
A new engine is one module plus one registry entry. It must:

1. Declare ``name`` (its registry key), ``title`` (one line), ``Settings`` (a frozen,
   self-validating settings dataclass, see :mod:`deckpound.models.fields`), ``settings_field``
   (the scene table holding its settings, or ``None``: then the defaults unless the caller passes
   ``settings=``), ``step_field`` (the settings field that is its time step) and ``style``
   (matplotlib line style and legend label for figures).
2. Implement :meth:`Engine.reads`: the engine-dependent scene options (:data:`OPTION_FIELDS`)
   its run depends on for this scene. Every option that differs from its default and is not
   read is warned about once (:class:`OptionIgnored`) — the "option does nothing" warnings are
   derived from this declaration, never written by hand.
3. Optionally implement :meth:`Engine.refuse`: raise :class:`~deckpound.models.errors.SceneError`
   for what the engine cannot express, with the reason and the alternatives. It runs before any
   work (``deckpound scene validate`` and every run call it).
4. Optionally implement :meth:`Engine.notes`: sentences on how the engine interprets options it
   does read differently from the others (warned as :class:`OptionIgnored` too).
5. Implement :meth:`Engine._run` ``(plan, scene, settings, motion, **options) -> RunOutput``: run
   for :func:`deckpound.models.motion.analysis_duration` seconds, store output every
   :func:`output_stride` steps starting at t = 0, and return the engine columns
   (:data:`ENGINE_COLUMNS` of the plan: time, absolute displacements, absolute velocities, gaps,
   normal and tangential contact forces, bent spring forces — ``fn`` ≥ 0 is compression, ``ft``
   the force on the deck along the corner's face tangent) plus any extras, and its statistics
   with one meaning each (:class:`RunOutput`).
6. Never return NaN silently: a failure (no convergence, unsolved contact problem, non-finite
   state, exhausted step budget, interrupt) ends the run with ``status`` ≠ SUCCESS, the output
   up to the failure, and the step and time where it happened.
7. Report compile time apart: time spent compiling or loading compiled kernels goes into
   ``RunOutput.compile_time`` (see :func:`deckpound.analytic._jit.ensure_compiled`), never into
   the run time.
8. Optionally measure the largest penetration over **every** step (``RunOutput.
   max_penetration``, and ``max_complementarity_residual`` for a complementarity problem);
   without it the epilogue takes the penetration from the output rows and says so
   (``meta["max_penetration_basis"]``). The epilogue turns a penetration beyond
   :data:`PENETRATION_WARN_FRACTION` of the gap into a :class:`QualityWarning`.
9. Report the work–energy balance as columns (``energy_input`` and the cumulative
   dissipation columns of :data:`CONTACT_DISSIPATION_COLUMNS`, ``energy_error``): the epilogue
   checks it (:func:`energy_quality`) and a finished run whose contacts created energy, or
   whose balance does not close, ends ``"doubtful"``, not ``"success"``. A fixed-step penalty
   engine takes its step from :meth:`Engine.fixed_step` (the contact-step rule).
10. Optionally measure, at every step, the peak of each standard column and the gap closures
    (``RunOutput.peaks``, ``RunOutput.gap_closures_per_corner``; the analytic engines with
    :mod:`deckpound.analytic.kernels.peaks`, OpenSees in its step loop): the epilogue puts them into
    ``meta["peaks"]`` and ``meta["gap_closures"]`` (:meth:`deckpound.models.result.Result.peak`
    reads them); without them it takes both from the output rows and says so
    (``meta["peaks_basis"]``, ``meta["gap_closures_basis"]``).

11. Optionally measure, at every step, the largest gap opening g_c − g_c(0) of each corner
    (``RunOutput.gap_openings``) and stop the step loop after the first step at which a
    corner's seat margin N − (g_c − g_c(0)) is negative, N the support length of the seat it
    faces (``seats[i].support_length``; not set: not checked), returning ``Status.UNSEATED``
    with the output up to there and ``RunOutput.unseated`` = (corner, time). Unseating is an
    answer, not a failure: the epilogue sets ``meta["status"] = "unseated"`` and fills
    ``meta["seat_margin_min"]``, ``meta["unseated"]`` and friends (:func:`seat_margins`).
    What happens after unseating (the deck falls) is outside the model.

12. Optionally store only the rows a summary needs: an engine that keeps points 8, 10 and 11
    sets ``summary_rows = True`` and its ``_run`` takes the keyword ``summary_rows``; when
    :meth:`Engine.run` passes True (``summary_only``, the sweeps) it stores only ``t`` and its
    energy columns (what the epilogue's energy check reads from rows) and returns
    ``RunOutput.summary_rows = True``: a sweep's run writes no histories it would drop.

:meth:`Engine.run` (not overridden) does the rest the same way for every engine: validation,
support motion, timing, and the epilogue :func:`finish`, which adds the columns computed from
the plan and the support motion (displacements relative to the supports, bent deformations),
puts the engine's every-step peaks and gap closures into the metadata (point 10), and builds the
metadata (status, message, failure step/time, statistics, wall and compile time, hashes,
settings, record provenance, warnings). With ``summary_only=True`` (the sweeps) it keeps no
histories: the statistics, checks and status come from the engine's every-step measurements
(points 8, 10 and 11) and the energy columns of its rows (an engine of point 12 stores no other
column; another engine's rows are dropped); an engine that keeps the contract's optional
points gets the same answer either way (``tests/test_summary_only.py``).
"""

from __future__ import annotations

import dataclasses
import enum
import time
import warnings
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from deckpound.models.columns import ENERGY_COLUMNS, column_names
from deckpound.models.contact_params import contact_resolving_step
from deckpound.models.errors import DoubtfulResult, EngineFailure, SceneError
from deckpound.models.excitation import support_motion
from deckpound.models.fields import to_mapping
from deckpound.models.plan import Plan, plan_of
from deckpound.models.result import (
    STATUS_DOUBTFUL,
    STATUS_FAILED,
    STATUS_SUCCESS,
    STATUS_UNSEATED,
    Result,
    gap_closures,
    physics_hash,
    row_peak,
    scene_hash,
    settings_hash,
)
from deckpound.models.scene import Contact, Deck, Scene, joint_contact_error
from deckpound.models.scene_settings import RunSettings
from deckpound.models.version import VERSION

__all__ = [
    "CONTACT_DISSIPATION_COLUMNS",
    "OPTION_FIELDS",
    "PENETRATION_WARN_FRACTION",
    "Engine",
    "OptionIgnored",
    "QualityWarning",
    "RunOutput",
    "Status",
    "energy_quality",
    "engine_columns",
    "finish",
    "ignored_options",
    "joint_contact_scenes",
    "output_stride",
    "seat_margins",
]


class OptionIgnored(UserWarning):
    """A scene option that does nothing in the engine that runs the scene."""


class QualityWarning(UserWarning):
    """A run finished but its answer is doubtful (e.g. penetration beyond
    :data:`PENETRATION_WARN_FRACTION` of the gap); also listed in ``meta["warnings"]``."""


class Status(str, enum.Enum):  # noqa: UP042 (str() must stay "Status.X" for messages)
    """How a run ended (``Result.meta["failure"]`` holds the name for a failed run)."""

    SUCCESS = "success"
    NOT_CONVERGED = "not_converged"
    SINGULAR = "singular"
    NONFINITE = "nonfinite"
    CONTACT_UNSOLVED = "contact_unsolved"
    STEP_BUDGET = "step_budget"
    INTERRUPTED = "interrupted"
    #: a deck corner lost its seat: an answer, not a numerical failure (point 11)
    UNSEATED = "unseated"

    @property
    def text(self) -> str:
        return _STATUS_TEXT[self]


_STATUS_TEXT = {
    Status.SUCCESS: "finished",
    Status.NOT_CONVERGED: "the iteration did not converge",
    Status.SINGULAR: "singular iteration matrix",
    Status.NONFINITE: "non-finite state",
    Status.CONTACT_UNSOLVED: "contact problem not solved (no verified solution)",
    Status.STEP_BUDGET: "step budget exhausted",
    Status.INTERRUPTED: "interrupted",
    Status.UNSEATED: "a deck corner lost its seat",
}

#: Scene options whose meaning depends on the engine (the "option ignored" warnings look here).
OPTION_FIELDS = tuple(f"contact.{f.name}" for f in dataclasses.fields(Contact)) + (
    "deck.stick_modulus",
    "run.steps_per_contact_period",
)
_OPTION_DEFAULTS = {
    "contact": {f.name: f.default for f in dataclasses.fields(Contact)},
    "deck": {f.name: f.default for f in dataclasses.fields(Deck)},
    "run": {f.name: f.default for f in dataclasses.fields(RunSettings)},
}


def engine_columns(plan: Plan) -> list[str]:
    """Columns an engine's ``_run`` returns: t, absolute displacements and velocities, gaps,
    fn, ft and the bent spring forces (the epilogue adds the rest of the standard columns)."""
    corners = [c.name for c in plan.corners]
    cols = ["t"] + [n for n, _ in plan.dof_columns] + [n for n, _ in plan.velocity_columns]
    cols += [f"gap_{c}" for c in corners] + [f"fn_{c}" for c in corners]
    cols += [f"ft_{c}" for c in corners]
    for b in plan.bent_names:
        cols += [f"{b}_fx", f"{b}_fy"]
    return cols


def output_stride(dt: float, output_dt: float) -> int:
    """Steps between stored outputs: round(output_dt / dt), at least 1."""
    return max(1, int(round(output_dt / dt)))


@dataclass
class RunOutput:
    """What an engine's ``_run`` returns (see the contract, point 5).

    Attributes
    ----------
    columns : engine columns (:func:`engine_columns`) plus extras, equal lengths.
    status : how the run ended; message : success summary or the failure reason (the epilogue
        appends the step and time).
    failed_step, failed_time : where a failed run stopped [-, s].
    steps : time steps completed; newton_iterations : Newton iterations of the smooth
        (Takeda) problem, summed over steps; contact_solves : contact problems solved (nonsmooth
        LCPs); failed_steps : steps that failed at least once (rescued or not);
        rescued_steps : failed steps rescued by sub-stepping.
    compile_time : compiling / loading kernels [s]; loop_time : the step loop alone [s].
    max_penetration : largest penetration max(0, −g) over the corners at **every** accepted
        step [m], or None when the engine does not measure it per step (the epilogue then
        takes it from the output rows and says so in ``meta["max_penetration_basis"]``).
    max_complementarity_residual : largest residual of the contact laws' complementarity over
        every contact solve, in the engine's unit (m/s for the nonsmooth engine's velocity-
        level Newton law), or None when the engine has no such problem (penalty contact
        violates complementarity by construction: its measure is the penetration).
    peaks : ``{column: (peak, time [s])}`` over **every** step (sub-steps and adaptive steps
        included): the largest |x| of each standard column the engine tracks (for a gap the
        smallest, most negative value), independent of the output rate
        (:mod:`deckpound.analytic.kernels.peaks`); None when the engine does not track them (the
        epilogue then says ``meta["peaks_basis"] = "output rows"``).
    gap_closures_per_corner : ``{"c1": n, ...}`` closures counted at every step with the one
        contact test (:func:`deckpound.models.result.in_contact`); None: counted on the
        output rows (``meta["gap_closures_basis"]``).
    gap_openings : ``{"c1": (opening [m], time [s]), ...}`` the largest gap opening
        g_c − g_c(0) over every step and when (point 11); None: taken from the output rows.
    unseated : ``(corner, time [s])`` of the first step at which a seat margin was negative
        (with ``status = Status.UNSEATED``), or None.
    summary_rows : the columns are only ``t`` and the energy columns (point 12).
    extra : engine-specific metadata (documented by the engine).
    """

    columns: dict[str, np.ndarray]
    status: Status = Status.SUCCESS
    message: str = ""
    failed_step: int | None = None
    failed_time: float | None = None
    steps: int = 0
    newton_iterations: int = 0
    contact_solves: int = 0
    failed_steps: int = 0
    rescued_steps: int = 0
    compile_time: float = 0.0
    loop_time: float = 0.0
    max_penetration: float | None = None
    max_complementarity_residual: float | None = None
    peaks: dict[str, tuple[float, float]] | None = None
    gap_closures_per_corner: dict[str, int] | None = None
    gap_openings: dict[str, tuple[float, float]] | None = None
    unseated: tuple[str, float] | None = None
    summary_rows: bool = False
    extra: dict[str, Any] = field(default_factory=dict)


def ignored_options(engine: Engine, scene: Scene, settings: Any) -> list[str]:
    """Engine-dependent options set away from their default that the engine does not read."""
    read = engine.reads(scene, settings)
    out = []
    for path in OPTION_FIELDS:
        table, name = path.split(".")
        value = getattr(getattr(scene, table), name)
        default = _OPTION_DEFAULTS[table][name]
        if value != default and path not in read:
            out.append(path)
    return out


class Engine:
    """Base class of the engines; see the module docstring for the numbered contract."""

    name: ClassVar[str] = ""
    title: ClassVar[str] = ""
    Settings: ClassVar[type] = type(None)
    settings_field: ClassVar[str | None] = None
    step_field: ClassVar[str] = "dt"
    style: ClassVar[dict[str, Any]] = {}
    #: True for penalty (compliant) contact, whose fixed step must resolve a contact duration
    compliant_contact: ClassVar[bool] = True
    #: True when ``_run`` takes ``summary_rows`` (point 12)
    summary_rows: ClassVar[bool] = False

    # -- declarations ---------------------------------------------------------------------
    def settings_of(self, scene: Scene) -> Any:
        """The engine's settings in ``scene`` (its table), or the defaults."""
        if self.settings_field is not None and hasattr(scene, self.settings_field):
            return getattr(scene, self.settings_field)
        return self.Settings()

    def step_of(self, settings: Any) -> float:
        """The engine's time step [s] in ``settings``."""
        return float(getattr(settings, self.step_field))

    def fixed_step(self, scene: Scene, settings: Any) -> float | None:
        """The fixed time step [s] a run of ``scene`` with ``settings`` takes; None for an
        adaptive one. A penalty-contact engine shortens its step to resolve the contact
        (:func:`~deckpound.models.contact_params.contact_resolving_step`, the one rule shared
        with every other fixed-step penalty engine)."""
        h = self.step_of(settings)
        return contact_resolving_step(scene, h) if self.compliant_contact else h

    def reads(self, scene: Scene, settings: Any) -> set[str]:
        """Engine-dependent options (:data:`OPTION_FIELDS`) the run depends on (point 2)."""
        return set()

    def refuse(self, scene: Scene, settings: Any) -> None:
        """Raise SceneError for what the engine cannot express (point 3)."""

    def notes(self, scene: Scene, settings: Any) -> list[str]:
        """How the engine interprets options differently from the others (point 4)."""
        return []

    # -- validation -------------------------------------------------------------------------
    def validate(self, scene: Scene, settings: Any = None, *, warn: bool = True) -> list[str]:
        """Refuse what the engine cannot express; return (and warn) the option notes."""
        settings = self.settings_of(scene) if settings is None else settings
        if not isinstance(settings, self.Settings):
            raise SceneError(
                self.settings_field or self.name,
                f"expects {self.Settings.__name__} settings, got {type(settings).__name__}",
            )
        self.refuse(scene, settings)
        joints = joint_contact_scenes(scene)
        for k, jscene in joints:
            try:
                self.refuse(jscene, settings)
            except SceneError as err:
                raise joint_contact_error(err, k) from None
        msgs = [
            f"{p} = {_value(scene, p)!r} does nothing in the {self.name} engine"
            + _why(self, p, scene)
            for p in ignored_options(self, scene, settings)
        ]
        notes = self.notes(scene, settings)
        msgs += [f"{self.name} engine: {n}" for n in notes]
        for k, jscene in joints:
            msgs += self._joint_messages(scene, k, jscene, settings, notes)
        if warn:
            for m in msgs:
                warnings.warn(m, OptionIgnored, stacklevel=3)
        return msgs

    def _joint_messages(
        self, scene: Scene, k: int, jscene: Scene, settings: Any, notes: list[str]
    ) -> list[str]:
        """The option messages of joint ``k``'s own contact fields (``jscene``: the scene as the
        joint's corners see it): each field it gives that the engine does not read, and the
        engine's notes its table adds to the scene's ``notes``."""
        read = self.reads(jscene, settings)
        at = f"joints[{k}].contact."
        out = [
            f"{at}{name} = {value!r} does nothing in the {self.name} engine"
            + _why(self, f"contact.{name}", jscene).replace("contact.", at)
            for name, value in scene.joints[k].contact.given().items()
            if f"contact.{name}" not in read
        ]
        out += [
            f"{self.name} engine: {n} (at joints[{k}])"
            for n in self.notes(jscene, settings)
            if n not in notes
        ]
        return out

    # -- running ----------------------------------------------------------------------------
    def run(
        self,
        scene: Scene,
        settings: Any = None,
        motion=None,
        *,
        raise_on_failure: bool = False,
        summary_only: bool = False,
        **options: Any,
    ) -> Result:
        """Run the engine on ``scene`` and return its Result (the shared template).

        ``summary_only``: return a result without histories (:func:`finish`), for sweeps that
        keep one row of peaks, closures, seat margins and status per case; the support motion
        it makes skips the record's intensity measures (``meta["record"]["intensity"]`` is
        None)."""

        t0 = time.perf_counter()
        settings = self.settings_of(scene) if settings is None else settings
        msgs = self.validate(scene, settings)
        if motion is None:
            # a summary keeps no record provenance a user reads: no intensity measures
            motion = support_motion(scene, intensity=not summary_only)
        plan = plan_of(scene)
        if summary_only and self.summary_rows:
            options["summary_rows"] = True
        out = self._run(plan, scene, settings, motion, **options)
        total = time.perf_counter() - t0
        return finish(
            self,
            scene,
            settings,
            motion,
            plan,
            out,
            total,
            msgs,
            raise_on_failure=raise_on_failure,
            summary_only=summary_only,
        )

    def _run(self, plan: Plan, scene: Scene, settings: Any, motion, **options: Any) -> RunOutput:
        raise NotImplementedError(f"engine {self.name!r} does not implement _run")


def joint_contact_scenes(scene: Scene) -> list[tuple[int, Scene]]:
    """``(k, the scene as joint k's corners see it)`` for each joint with contact fields of its
    own: the scene with ``contact`` replaced by :meth:`~deckpound.models.scene.Scene.
    joint_contact` — what an engine's ``refuse`` and ``reads`` check for that joint."""
    return [
        (k, scene.replace(contact=scene.joint_contact(k)))
        for k, joint in enumerate(scene.joints or ())
        if joint.contact is not None and joint.contact.given()
    ]


def _value(scene: Scene, path: str) -> Any:
    table, name = path.split(".")
    return getattr(getattr(scene, table), name)


def _why(engine: Engine, path: str, scene: Scene) -> str:
    ct = scene.contact
    if path == "contact.friction" and ct.friction_mode == "none":
        return " (contact.friction_mode = 'none')"
    if path == "contact.friction_mode" and ct.friction == 0.0:
        return " (contact.friction = 0)"
    return ""


def _relative_columns(plan: Plan, motion, cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Displacements relative to the supports and bent deformations at the output times.

    The support motion is interpolated linearly between its own samples (``np.interp``, the
    same arithmetic as the engines' compiled interpolator), held after the record ends.
    """
    t = cols["t"]
    ug = (
        np.column_stack([np.interp(t, motion.t, motion.disp[ch]) for ch in plan.channels])
        if len(t)
        else np.zeros((0, len(plan.channels)))
    )
    out: dict[str, np.ndarray] = {}
    for seg in plan.segments:
        tx = plan.segment_table_channels(seg.index, "x")
        ty = plan.segment_table_channels(seg.index, "y")
        mean_x = ug[:, tx].mean(axis=1) if tx else np.zeros(len(t))
        mean_y = ug[:, ty].mean(axis=1) if ty else np.zeros(len(t))
        out[f"{seg.name}_x_rel"] = cols[f"{seg.name}_x_abs"] - mean_x
        out[f"{seg.name}_y_rel"] = cols[f"{seg.name}_y_abs"] - mean_y
    for j in (1, 2):
        out[f"seat{j}_x_rel"] = cols[f"seat{j}_x_abs"] - ug[:, plan.channels.index(f"seat{j}_x")]
    U = np.zeros((len(t), plan.n_dof))
    for name, dof in plan.dof_columns:
        U[:, dof] = cols[name]
    d = plan.deformations(U, ug)
    for i, b in enumerate(plan.bent_names):
        out[f"{b}_dx"] = d[:, 2 * i]
        out[f"{b}_dy"] = d[:, 2 * i + 1]
    for column in out.values():
        column.flags.writeable = False  # handed to the Result as they are (no copy)
    return out


#: Quality warning thresholds (issue 16): a penetration larger than this fraction of the
#: smallest initial clear gap is reported as a warning in the result metadata (and so in the
#: report). Penalty (compliant) engines: 10 % — the penetration is the contact spring's
#: deformation; beyond a tenth of the gap the contact is too soft for the gap the scene
#: resolves. On the benchmark's 7-run sequence (k = 1e6 kN/m) the largest is 5.4 % (run 7:
#: 0.38 mm of the carried 7.0 mm gap), so 5 % would flag the paper's own stiffness. Rigid
#: contact (nonsmooth): 20 % — penetration is a discretisation artefact O(h·v) of the
#: velocity-level scheme (sequence at h = 1e-3 s: at most 7.1 %), while the runs issue 16
#: found wrong (h = 0.05 s: 72 mm into a 12.7 mm gap) are far beyond it.
PENETRATION_WARN_FRACTION = {True: 0.10, False: 0.20}


def _check_columns(engine: Engine, plan: Plan, cols: dict, out: RunOutput, light: bool) -> None:
    """Refuse an engine's output that breaks the contract: an engine column missing (point 5),
    or summary rows (point 12) without the every-step measurements that replace the rest."""
    if out.summary_rows:
        if not light or out.max_penetration is None:
            raise RuntimeError(
                f"engine {engine.name!r} returned summary rows without its every-step peaks, "
                "openings and penetration (engine contract, point 12)"
            )
        need = ["t"]
    else:
        need = engine_columns(plan)
    missing = [c for c in need if c not in cols]
    if missing:
        raise RuntimeError(
            f"engine {engine.name!r} returned no column {missing[0]!r} (engine contract, point 5)"
        )


def _contact_quality(engine: Engine, scene: Scene, plan: Plan, cols: dict, out: RunOutput) -> dict:
    """``max_penetration`` [m] (per step when the engine measures it, else on the output
    rows), its basis, ``max_complementarity_residual`` and the penetration quality warning."""
    names = [f"gap_{c.name}" for c in plan.corners]
    gaps = [cols[k] for k in names if k in cols and len(cols[k])]
    rows_pen = max((float(max(0.0, -np.min(g))) for g in gaps), default=0.0)
    if out.max_penetration is not None:
        pen, basis = max(float(out.max_penetration), rows_pen), "every step"
    else:
        pen, basis = rows_pen, "output rows"
    q: dict[str, Any] = {"max_penetration": pen, "max_penetration_basis": basis}
    if not out.summary_rows:  # summary rows hold no gaps (point 12)
        q["max_penetration_rows"] = rows_pen
    if out.max_complementarity_residual is not None:
        q["max_complementarity_residual"] = float(out.max_complementarity_residual)
    g0 = min([seat.gap for seat in scene.seats] + [j.gap for j in scene.joints or ()])
    frac = PENETRATION_WARN_FRACTION[bool(engine.compliant_contact)]
    if g0 > 0.0 and pen > frac * g0:
        why = (
            "the contact stiffness is too low for this gap"
            if engine.compliant_contact
            else "the time step is too long (penetration is O(h·v) in a rigid-contact scheme)"
        )
        q["quality_warnings"] = [
            f"penetration {pen:.3g} m exceeds {frac:.0%} of the smallest "
            f"initial gap {g0:.3g} m ({basis}): {why}"
        ]
    return q


#: Cumulative dissipation columns [kJ] of the contacts (compliance and OpenSees:
#: ``energy_contact_dissipated``; nonsmooth: ``energy_impact``) and of friction: their sum must
#: not fall below zero — a contact that gives back more work than it took created energy.
CONTACT_DISSIPATION_COLUMNS = ("energy_contact_dissipated", "energy_impact", "energy_friction")


def _share(part: float, whole: float) -> str:
    """``part`` against ``whole`` in words: "12.5 % of" or "132× " (for the messages)."""
    r = part / whole
    return f"{100 * r:.3g} % of" if r < 1.0 else f"{r:.3g}×"


def energy_quality(scene: Scene, cols: dict[str, np.ndarray]) -> dict[str, Any]:
    """The work–energy check of a run's output rows.

    With E_ref = max |energy_input| (the work of the supports plus the initial mechanical
    energy) and tol = ``run.energy_tolerance``, the run is doubtful when

    * the contacts created energy: −min_t Σ dissipation(t) > tol · E_ref over
      :data:`CONTACT_DISSIPATION_COLUMNS` (a penalty contact stepped too coarsely gives back
      more work than it took on separation), or
    * the balance does not close: max |energy_error| > tol · E_ref.

    The dissipation columns are cumulative, so energy created at any step persists into
    the rows that follow. Returns ``energy_check`` (``"passed"``, ``"failed"`` or why it
    was not made), ``energy_created`` [kJ] and its time, and ``doubtful`` (sentences).
    """
    have = [c for c in CONTACT_DISSIPATION_COLUMNS if c in cols]
    if "energy_input" not in cols or not have or not len(cols["energy_input"]):
        return {"energy_check": "not made (the result has no energy columns)"}
    t = cols["t"]
    e_ref = float(np.max(np.abs(cols["energy_input"])))
    tol = scene.run.energy_tolerance
    dissipated = np.sum([cols[c] for c in have], axis=0)
    created = float(max(0.0, -np.min(dissipated)))
    q: dict[str, Any] = {"energy_reference": e_ref, "energy_created": created}
    doubtful = []
    if e_ref > 0.0 and created > tol * e_ref:
        first = int(np.argmax(-dissipated > tol * e_ref))
        q["energy_created_time"] = float(t[first])
        doubtful.append(
            f"the contacts created {created:.4g} kJ of energy ({_share(created, e_ref)} the "
            f"input {e_ref:.4g} kJ; more than run.energy_tolerance = {tol:g} of it from "
            f"t = {t[first]:.6g} s): the step does not resolve the contact — shorten it "
            "(run.steps_per_contact_period, the engine's dt) or use the adaptive integrator "
            "or the nonsmooth engine"
        )
    if "energy_error" in cols:
        miss = float(np.max(np.abs(cols["energy_error"])))
        q["energy_balance_error"] = miss
        if e_ref > 0.0 and miss > tol * e_ref:
            at = float(t[int(np.argmax(np.abs(cols["energy_error"])))])
            doubtful.append(
                f"the work-energy balance misses {miss:.4g} kJ ({_share(miss, e_ref)} the "
                f"input, at t = {at:.6g} s; run.energy_tolerance = {tol:g})"
            )
    q["energy_check"] = "failed" if doubtful else "passed"
    if doubtful:
        q["doubtful"] = doubtful
    return q


def _step_statistics(columns: dict[str, np.ndarray], out: RunOutput) -> dict[str, Any]:
    """``peaks`` ({column: [peak, time]}, JSON-safe) and the gap closures of a run, with their
    bases (``"every step"`` or ``"output rows"``).

    The engine's every-step peaks (:attr:`RunOutput.peaks`) are kept unless an output row
    exceeds one (a column the epilogue derives, e.g. a relative displacement, is computed from
    the rows with other round-off than the engine's per-step value): the peak is then the row's,
    so it never falls below a stored value. Closures: the engine's per-step count, else
    :func:`deckpound.models.result.gap_closures` of the rows."""
    q: dict[str, Any] = {}
    if out.peaks is not None:
        peaks = {}
        for name, (value, when) in out.peaks.items():
            if name in columns and len(columns[name]):
                rv, rt = row_peak(name, columns["t"], columns[name])
                beyond = rv < value if name.startswith("gap_") else rv > value
                if beyond:
                    value, when = rv, rt
            peaks[name] = [float(value), float(when)]
        q["peaks"] = peaks
        q["peaks_basis"] = "every step"
    else:
        q["peaks_basis"] = "output rows"
    if out.gap_closures_per_corner is not None:
        per, basis = {c: int(n) for c, n in out.gap_closures_per_corner.items()}, "every step"
    else:
        per, basis = gap_closures(columns), "output rows"
    q["gap_closures"] = sum(per.values())
    q["gap_closures_per_corner"] = per
    q["gap_closures_basis"] = basis
    return q


def seat_margins(scene: Scene, plan: Plan, columns: dict[str, np.ndarray], out: RunOutput):
    """The seat margins of a run (contract point 11), for ``meta``.

    The support length N of a seat (``seats[i].support_length``, AASHTO's seat width) is the
    length of seat under the deck end along the face normal, measured from the deck end's
    initial position; the opening of corner c is g_c(t) − g_c(0) (> 0 when the deck end moves
    away from the backwall) and its seat margin m_c(t) = N − (g_c(t) − g_c(0)), smallest at
    the largest opening. For a run from rest g_c(0) is the corner table's as-built gap g₀; a
    deck started displaced (``initial.deck``) counts from where it starts, and a sequence run
    from its carried gap with the seat the earlier runs left (:mod:`deckpound.models.
    sequence`). Returns ``gap_opening_max`` ({corner: [opening m, time s]}, every
    corner: the seat-width demand), ``seat_margin_min`` ({corner: [margin m, time s]}, the
    corners whose seat has a support length), ``seat_margin_basis`` (``"every step"``,
    ``"output rows"`` or why it was not checked) and ``unseated`` (bool), with
    ``unseated_corner``, ``unseated_time`` [s] and ``unseated_step`` when True."""
    if out.gap_openings is not None:
        openings = {c: (float(o), float(t)) for c, (o, t) in out.gap_openings.items()}
        basis = "every step"
    else:
        openings, basis = {}, "output rows"
        for c in (corner.name for corner in plan.corners):
            g = columns[f"gap_{c}"]
            if len(g):
                k = int(np.argmax(g))
                openings[c] = (float(g[k] - g[0]), float(columns["t"][k]))
    margins = {}
    for corner in plan.corners:
        length = corner.support_length
        if length is not None and corner.name in openings:
            opening, when = openings[corner.name]
            margins[corner.name] = [float(length) - opening, when]
    if not margins:
        basis = "not checked (no seats[i].support_length or joints[i].support_length)"
    q: dict[str, Any] = {
        "gap_opening_max": {c: [o, t] for c, (o, t) in openings.items()},
        "seat_margin_min": margins,
        "seat_margin_basis": basis,
    }
    first = out.unseated
    if first is None:
        negative = [(m, c) for c, (m, _) in margins.items() if m < 0.0]
        if negative:  # an engine that does not stop (rows basis): the worst corner
            c = min(negative)[1]
            first = (c, margins[c][1])
    q["unseated"] = first is not None
    if first is not None:
        q["unseated_corner"], q["unseated_time"] = first[0], float(first[1])
        q["unseated_step"] = int(out.steps)
    return q


def _unseated_message(scene: Scene, plan: Plan, meta: dict[str, Any]) -> str:
    """The status line's sentence for an unseated run."""
    c = meta["unseated_corner"]
    seat = next(k.seat for k in plan.corners if k.name == c)
    margin = meta["seat_margin_min"].get(c, [float("nan")])[0]
    return (
        f"corner {c} unseated at t = {meta['unseated_time']:.6g} s (step "
        f"{meta['unseated_step']}): its gap opened beyond seats[{seat}].support_length = "
        f"{scene.seats[seat].support_length:g} m (seat margin {margin:.4g} m); the run stops "
        "there, what follows (the deck falling) is not modelled"
    )


def finish(
    engine: Engine,
    scene: Scene,
    settings: Any,
    motion,
    plan: Plan,
    out: RunOutput,
    total_time: float,
    notes: list[str],
    *,
    raise_on_failure: bool = False,
    summary_only: bool = False,
) -> Result:
    """The shared epilogue: standard columns in order, statistics, status and metadata.

    ``summary_only`` (sweeps): the same checks, statistics and status, taken from the engine's
    every-step measurements (penetration, peaks, closures, openings; contract points 8, 10
    and 11) and its output rows (the energy balance; an engine of point 12 stores only ``t``
    and the energy columns), but the result keeps no histories: its
    only column is an empty ``t``, ``meta["histories"]`` is False, ``meta["final_energies"]``
    holds the energy columns' last values [kJ], and the scene itself, its hash and the
    relative columns are not made (the caller keys the case). An engine that does not measure
    its peaks at every step gets the full epilogue, whose rows are then dropped."""
    cols = dict(out.columns)
    # without the engine's every-step measurements the statistics come from the rows
    light = summary_only and out.peaks is not None and out.gap_openings is not None
    _check_columns(engine, plan, cols, out, light)
    if light:
        columns: dict[str, np.ndarray] = {}
    else:
        cols.update(_relative_columns(plan, motion, cols))
        order = column_names(plan)
        columns = {k: cols[k] for k in order}
        columns.update({k: v for k, v in cols.items() if k not in columns})
    ok = out.status == Status.SUCCESS
    # unseating ends a run with an answer (point 11): no failure, its rows are checked as a
    # finished run's
    unseated = out.status == Status.UNSEATED
    finished = ok or unseated
    steps = max(out.steps, 1)
    run_time = max(total_time - out.compile_time, 0.0)
    meta: dict[str, Any] = {
        "engine": engine.name,
        "status": STATUS_SUCCESS if ok else (STATUS_UNSEATED if unseated else STATUS_FAILED),
        "failure": None if finished else out.status.value,
        "message": out.message,
        "steps": int(out.steps),
        "newton_iterations": int(out.newton_iterations),
        "contact_solves": int(out.contact_solves),
        "failures": int(out.failed_steps),
        "rescued_by_substeps": int(out.rescued_steps),
        "wall_time": run_time,
        "compile_time": float(out.compile_time),
        "loop_time": float(out.loop_time),
        "us_per_step": 1e6 * float(out.loop_time or run_time) / steps,
        "duration": float(cols["t"][-1]) if len(cols["t"]) else 0.0,
        "settings": to_mapping(settings) if dataclasses.is_dataclass(settings) else settings,
        "version": VERSION,
        "bent_names": list(plan.bent_names),
        "warnings": list(notes),
        "histories": not summary_only,
    }
    if not light:
        meta["scene_hash"] = scene_hash(scene)
        meta["physics_hash"] = physics_hash(scene)
        meta["settings_hash"] = settings_hash(settings)
        # the whole scene: a result folder is self-describing, whichever way the engine was
        # called (a VTK export or a re-run needs nothing else)
        meta["scene"] = to_mapping(scene)
    provenance = getattr(motion, "provenance", None)
    if provenance:
        meta["record"] = provenance
    meta.update(out.extra)
    meta.update(_contact_quality(engine, scene, plan, cols, out))
    meta.update(_step_statistics(columns, out))
    meta.update(seat_margins(scene, plan, columns, out))
    if unseated:
        meta["message"] = _unseated_message(scene, plan, meta)
    for text in meta.get("quality_warnings", []):
        meta["warnings"].append(text)
        warnings.warn(f"{engine.name} engine: {text}", QualityWarning, stacklevel=3)
    if finished:
        meta.update(energy_quality(scene, cols))
    for text in meta.get("doubtful", []):
        meta["warnings"].append(text)
        warnings.warn(f"{engine.name} engine: {text}", QualityWarning, stacklevel=3)
    if meta.get("doubtful"):
        meta["status"] = STATUS_DOUBTFUL
        meta["accepted"] = bool(scene.run.accept_doubtful)
        meta["message"] = "; ".join(meta["doubtful"])
    if not finished:
        t_fail = out.failed_time if out.failed_time is not None else float("nan")
        meta["failed_step"] = int(out.failed_step or 0)
        meta["failed_time"] = t_fail
        reason = out.message or out.status.text
        meta["message"] = f"{reason} at step {meta['failed_step']} (t = {t_fail:.6g} s)"
    if summary_only:
        meta["final_energies"] = {
            k: float(cols[k][-1]) for k in ENERGY_COLUMNS if k in cols and len(cols[k])
        }
        columns = {"t": np.empty(0)}
    result = Result(engine=engine.name, columns=columns, meta=meta)
    if not finished and raise_on_failure:
        raise EngineFailure(f"{engine.name} engine: {meta['message']}")
    if result.doubtful and raise_on_failure and not scene.run.accept_doubtful:
        raise DoubtfulResult(f"{engine.name} engine: {meta['message']}")
    return result

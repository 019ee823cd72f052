"""Plausibility of a valid scene: can the engines' steps and the output resolve the answer?

Field validation (:mod:`._fields`) checks each value alone; this module checks values against
each other and against the physics of the contact-free model, before any engine runs:

=========================  ================================================================
analysis vs step           fewer than :data:`MIN_STEPS` engine steps in the analysis (record
                           or run.duration; a step longer than the record gives none):
                           refused, naming both values
fundamental period T1      a step longer than T1 / 2 cannot represent even the slowest mode:
                           refused
shortest period T_min      fewer than :data:`STEPS_PER_PERIOD` steps per T_min: warning (the
                           highest modes are distorted; implicit schemes stay stable)
contact duration t_c       t_c ≈ π √(m_eff / k) (half a period of the stiffest corner's
                           contact oscillation; :func:`~.contact_params.effective_masses`):
                           a fixed step longer than t_c skips through impacts: warning with
                           the step that would resolve them (compliant engines only)
output step                longer than the analysis (only t = 0 stored): refused; fewer than
                           :data:`MIN_OUTPUT_ROWS` rows: warning; more than
                           :data:`MAX_OUTPUT_ROWS` rows (memory): refused; longer than a
                           quarter of a deck mode's period (:func:`output_resolution`):
                           warning naming the periods the rows cannot resolve
magnitudes                 values no bridge has (a gap or deck size in mm, a deck mass in kg,
                           a stiffness in N/m, a dimension of 1e30, μ = 100): warnings, and
                           refusals naming the value probably meant unless allow_extreme
                           (:mod:`.magnitudes`; checked first, the others assume sound values)
=========================  ================================================================

The findings are data (:class:`Finding`, :class:`Plausibility`); :func:`enforce` turns them
into warnings (:class:`PlausibilityWarning`) and a :class:`~.errors.SceneError` for the CLI
and, later, the engines' shared validation. The engines' steps are read from the engine
registry (each engine declares its step field and whether its contact is compliant).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from .contact_params import contact_period
from .engine_contract import Engine
from .errors import SceneError
from .excitation import support_motion
from .magnitudes import magnitude_findings
from .mechanics import energy_groups, energy_shares, mode_label, natural_modes
from .motion import analysis_duration
from .plan import plan_of
from .scene import Scene
from .scene_settings import MAX_STEPS, RunSettings

#: fewest steps an analysis may hold (fewer resolve no history at all)
MIN_STEPS = 10
#: fewest steps per shortest natural period before a warning
STEPS_PER_PERIOD = 10
#: fewest output rows before a warning (a history needs a few points)
MIN_OUTPUT_ROWS = 10
#: most output rows per run (≈ 0.5 GB in memory at 30 columns, ~1 GB of CSV)
MAX_OUTPUT_ROWS = 2_000_000


class PlausibilityWarning(UserWarning):
    """A plausibility finding that does not refuse the scene (:func:`enforce`)."""


@dataclass(frozen=True)
class Finding:
    """One plausibility problem: ``level`` is ``"error"`` (refused) or ``"warning"``."""

    level: str
    field: str
    message: str


@dataclass
class Plausibility:
    """All findings for one scene, plus the numbers they were computed from."""

    findings: list[Finding] = field(default_factory=list)
    duration: float = math.nan
    periods: tuple[float, ...] = ()
    contact_duration: float = math.nan
    #: ``(step field, given [s], run [s])`` of each step the contact-step rule shortens
    shortened: tuple[tuple[str, float, float], ...] = ()

    @property
    def errors(self) -> list[Finding]:
        return [f for f in self.findings if f.level == "error"]

    @property
    def warnings(self) -> list[Finding]:
        return [f for f in self.findings if f.level == "warning"]

    @property
    def ok(self) -> bool:
        return not self.errors


def engine_steps(
    scene: Scene, engines: Iterable[Engine]
) -> list[tuple[str, str, float, bool, float]]:
    """``(engine, step field, step given [s], compliant contact?, step run [s])`` of each
    fixed-step engine: the step its settings give, and the one it runs
    (:meth:`deckpound.models.engine_contract.Engine.fixed_step`: shorter where the contact-step rule
    shortens it). The given step is checked against the record and the modes (a step the
    rule happens to shorten is still a slip when it cannot represent T1), the run step against
    the contact and the output."""
    out = []
    for e in engines:
        name = e.name
        settings = e.settings_of(scene)
        run = e.fixed_step(scene, settings)
        if run is not None:
            where = f"{e.settings_field}.{e.step_field}" if e.settings_field else e.step_field
            out.append((name, where, e.step_of(settings), e.compliant_contact, run))
    return out


def contact_duration(scene: Scene) -> float:
    """Duration of the shortest corner contact, π √(m_eff / k_eff) [s].

    k_eff is the contact stiffness (K1 of the bilinear law); for the Hertz laws the secant
    stiffness k·δ^(n−1) at δ = :data:`~.contact_params.HERTZ_SECANT_DEPTH`: half of
    :func:`~.contact_params.contact_period`.
    """
    return 0.5 * contact_period(scene)


#: steps per contact period the warning of an unresolved contact recommends: the contact-step
#: rule's default (:func:`~.contact_params.contact_resolving_step`), so that the advice and the
#: step the engines take by default are one
RESOLVING_STEPS = RunSettings().steps_per_contact_period

#: fewest output rows per natural period of a deck mode before a warning (T/4: a quarter
#: period between rows, the coarsest sampling that still shows the swing's extremes)
ROWS_PER_DECK_PERIOD = 4


def output_resolution(scene: Scene) -> Finding | None:
    """A warning when ``run.output_dt`` is longer than T / :data:`ROWS_PER_DECK_PERIOD` of a
    deck mode of the contact-free model (:func:`~.mechanics.natural_modes`; a deck mode: the
    deck's x, y, θ carry most of its mass-normalised kinetic energy, Σ_deck m φ² ≥ ½), naming
    the periods the rows cannot resolve; None otherwise.

    The stored histories then alias the deck's swing; the peaks and gap closures the engines
    report are taken at every step (:meth:`deckpound.models.result.Result.peak`) and do not
    depend on the output step."""

    plan = plan_of(scene)
    modes = natural_modes(scene, plan)
    groups = energy_groups(plan)
    shares = energy_shares(modes.shapes, np.diag(plan.mass_matrix), groups)
    deck = [i for i, (key, _, _) in enumerate(groups) if key != "seats"]
    out_dt = scene.run.output_dt
    missed = []
    for k, T in enumerate(modes.periods):
        if math.isfinite(T) and shares[deck, k].sum() >= 0.5:
            if out_dt > T / ROWS_PER_DECK_PERIOD:
                # named by its kinetic-energy shares, as `deckpound modes` names it
                missed.append((float(T), k + 1, mode_label(shares[:, k], groups)))
    if not missed:
        return None
    names = "; ".join(
        f"{T:.3g} s (mode {k}: {what})" for T, k, what in sorted(missed, reverse=True)
    )
    shortest = min(T for T, _, _ in missed)
    return Finding(
        "warning",
        "run.output_dt",
        f"run.output_dt = {out_dt:g} s is longer than a quarter of the deck's natural "
        f"period{'s' if len(missed) > 1 else ''} {names}: the stored rows cannot resolve "
        f"the deck's swing (the histories alias; peaks and gap closures are taken at every "
        f"step); use run.output_dt <= {shortest / ROWS_PER_DECK_PERIOD:.3g} s",
    )


def _source(scene: Scene, motion) -> str:
    if scene.run.duration is not None:
        return f"run.duration = {scene.run.duration:g} s"
    return f"the record length {motion.duration:g} s"


def check(scene: Scene, motion=None, *, engines: Iterable[Engine]) -> Plausibility:
    """Every plausibility finding for ``scene`` run by ``engines`` (the engine objects, for
    example ``[deckpound.get_engine(n) for n in names]``; see the module table)."""

    engines = tuple(engines)
    if motion is None:
        motion = support_motion(scene)
    report = Plausibility(duration=analysis_duration(scene, motion))
    add = report.findings.append
    report.findings += [Finding(*found) for found in magnitude_findings(scene)]
    if report.errors:
        return report  # the checks below assume values a bridge can have
    D, src = report.duration, _source(scene, motion)
    steps = engine_steps(scene, engines)

    for _, name, h, _, _ in steps:
        if h * MIN_STEPS > D:
            where = "run.duration" if scene.run.duration is not None else name
            add(
                Finding(
                    "error",
                    where,
                    f"the analysis ({src}) holds only {D / h:.3g} steps of "
                    f"{name} = {h:g} s (at least {MIN_STEPS} are needed to resolve a "
                    f"history); give a step <= {D / MIN_STEPS:.3g} s or a longer "
                    "analysis",
                )
            )
    report.shortened = tuple((name, given, h) for _, name, given, _, h in steps if h < given)
    for _, name, given, _, h in steps:
        if h < given and D / h > MAX_STEPS:
            add(
                Finding(
                    "error",
                    "run.steps_per_contact_period",
                    f"the contact-step rule shortens {name} = {given:g} s to {h:.3g} s "
                    f"(contact.stiffness = {scene.contact.stiffness:g}): {D / h:.3g} steps "
                    f"over {D:g} s, at most {MAX_STEPS:.0e} are allowed; lower "
                    "run.steps_per_contact_period (0 runs the given step), soften the "
                    "contact or shorten the analysis",
                )
            )
    if any(f.level == "error" for f in report.findings):
        return report  # the other checks assume at least one step

    periods = natural_modes(scene).periods
    report.periods = tuple(float(T) for T in periods)
    if not scene.bents:
        # bents = []: the deck is free in plan, its three rigid-body modes (x, y, θ; the
        # first three, ω = 0) have no period to resolve
        periods = periods[3:]
    if not np.all(np.isfinite(periods)):
        add(
            Finding(
                "error",
                "scene",
                "the masses and stiffnesses give non-finite natural "
                f"periods ({', '.join(f'{T:g}' for T in periods)} s): a mechanism or "
                "extreme values; check them",
            )
        )
        return report
    t1, tmin = float(np.max(periods)), float(np.min(periods))
    for _, name, h, _, _ in steps:
        if h > t1 / 2:
            add(
                Finding(
                    "error",
                    name,
                    f"{name} = {h:g} s cannot represent even the "
                    f"fundamental period T1 = {t1:.4g} s of the contact-free model "
                    f"(at least 2 steps per period); it must be <= {t1 / 2:.4g} s",
                )
            )
        elif h > tmin / STEPS_PER_PERIOD:
            add(
                Finding(
                    "warning",
                    name,
                    f"{name} = {h:g} s resolves the shortest natural "
                    f"period T = {tmin:.4g} s with only {tmin / h:.3g} steps (>= "
                    f"{STEPS_PER_PERIOD} recommended, i.e. <= "
                    f"{tmin / STEPS_PER_PERIOD:.3g} s): the highest modes are distorted",
                )
            )

    tc = contact_duration(scene)
    report.contact_duration = tc
    if math.isfinite(tc):
        for _, name, _, compliant, h in steps:
            if compliant and h > tc:
                add(
                    Finding(
                        "warning",
                        name,
                        f"contacts last about {tc:.3g} s "
                        f"(contact.stiffness = {scene.contact.stiffness:g}, the lightest "
                        f"corner's effective mass), shorter than {name} = {h:g} s: impacts "
                        f"are not resolved and their forces depend on the step; use a step "
                        f"<= {2.0 * tc / RESOLVING_STEPS:.3g} s (what "
                        f"run.steps_per_contact_period = {RESOLVING_STEPS:g}, its default, "
                        "gives), compliance.integrator = 'adaptive', or the nonsmooth engine "
                        "(rigid limit)",
                    )
                )

    out_dt = scene.run.output_dt
    if out_dt > D:
        add(
            Finding(
                "error",
                "run.output_dt",
                f"run.output_dt = {out_dt:g} s is longer than the "
                f"analysis ({src}): the result would hold the single row t = 0; it must be "
                f"<= {D / MIN_OUTPUT_ROWS:.3g} s for {MIN_OUTPUT_ROWS} rows",
            )
        )
    else:
        # each engine stores every round(output_dt / h)-th step (engines.output_stride)
        stored = [max(1, round(out_dt / h)) * h for *_, h in steps] or [out_dt]
        most, fewest = int(D / min(stored)) + 1, int(D / max(stored)) + 1
        coarse = output_resolution(scene)
        if coarse is not None:
            add(coarse)
        if most > MAX_OUTPUT_ROWS:
            add(
                Finding(
                    "error",
                    "run.output_dt",
                    f"run.output_dt = {out_dt:g} s over {D:g} s "
                    f"stores {most:.3g} rows per run (at most {MAX_OUTPUT_ROWS:.0e}); it "
                    f"must be >= {D / MAX_OUTPUT_ROWS:.3g} s",
                )
            )
        elif fewest < MIN_OUTPUT_ROWS:
            add(
                Finding(
                    "warning",
                    "run.output_dt",
                    f"run.output_dt = {out_dt:g} s over "
                    f"{D:g} s stores only {fewest} rows (the histories between them are lost; peaks "
                    "and gap closures are still taken at every step); "
                    f"use <= {D / MIN_OUTPUT_ROWS:.3g} s",
                )
            )
        for _, name, _, _, h in steps:
            if out_dt < 0.5 * h:
                add(
                    Finding(
                        "warning",
                        "run.output_dt",
                        f"run.output_dt = {out_dt:g} s is "
                        f"shorter than {name} = {h:g} s: output is stored every step "
                        f"({h:g} s) instead",
                    )
                )
    return report


def enforce(scene: Scene, motion=None, *, engines: Iterable[Engine]) -> Plausibility:
    """:func:`check`, then warn about each warning and raise the first error as SceneError."""
    report = check(scene, motion, engines=engines)
    for f in report.warnings:
        warnings.warn(f"{f.field}: {f.message}", PlausibilityWarning, stacklevel=2)
    if report.errors:
        first = report.errors[0]
        raise SceneError(first.field, first.message)
    return report

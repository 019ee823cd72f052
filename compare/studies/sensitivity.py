"""The paper's sensitivity studies (Section 3), one function of the scene each.

A study turns a scene into cases (engine + modified scene), runs them through the cache and
the parallel runner, and writes a table (CSV, units in the header) and a figure (PNG; PDF on
request). Every study starts from a stated :class:`StartState`: the scene as given
(``virgin``) or the gap and bent stiffness the sequence carries into one of its runs (``run7``:
runs 1–6 of the sequence driven by the reference engine, then run 7's PGA), see
:func:`start_state`. Studies marked ``carried`` (friction, sticking, stiffness, law) are run by
``deckpound paper`` from both the strongest run's carried state and the virgin state;
``deckpound study NAME SCENE`` runs the scene as given unless ``--state runK`` is asked.

==============  ============================================================================
stiffness       peak deck rotation vs contact stiffness (≥ 4 decades), nonsmooth = rigid limit
friction        friction on/off (μ sweep, sticking law), compliance and nonsmooth
sticking        Coulomb with vs without sticking, compliance
law             contact law: linear, Kelvin–Voigt, Hertz, Hertz-damp, bilinear
geometry        geometrically linear vs nonlinear contact kinematics
opensees-mode   OpenSees stick vs rigid deck
skew            skew angle 0–60° with and without friction, every engine (:mod:`.skew`)
joint           joint gap × wave-passage lag of a deck of segments, every engine (:mod:`.joint`)
sequence        the 7-run sequence with carried gap and stiffness, every engine
==============  ============================================================================

Compliance cases resolve the contact: their step is at most the contact period / 20
(:func:`contact_step`), so stiff cases stay accurate rather than merely stable.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.cases import Case, run_cases
from deckpound.compare.engines import DEFAULT_REFERENCE
from deckpound.compare.report.figures import study_figure
from deckpound.compare.report.outputs import folder, write_csv
from deckpound.compare.result_cache import ResultCache
from deckpound.compare.studies.case_rows import ROW_UNITS, case_row, contact_step
from deckpound.compare.studies.damping import (
    damping_cases,
    damping_figure,
    damping_headlines,
    damping_row,
)
from deckpound.compare.studies.joint import (
    joint_cases,
    joint_figure,
    joint_headlines,
    joint_row,
    joint_units,
)
from deckpound.compare.studies.sequence_run import state_before, strongest_run
from deckpound.compare.studies.skew import skew_cases, skew_figure, skew_headlines, skew_row
from deckpound.models.contact_laws_table import DEFAULT_FRICTION, LAW_CODES
from deckpound.models.errors import SceneError
from deckpound.models.result import Result
from deckpound.models.scene import Scene
from deckpound.models.scene_io import modified

ENGINES_ALL = ("opensees", "compliance", "nonsmooth")


def _compliance(scene: Scene, *overrides: str) -> Scene:
    s = modified(scene, *overrides)
    return modified(s, f"compliance.dt={contact_step(s)!r}")


# -- the state a study starts from -------------------------------------------------------


@dataclass(frozen=True)
class StartState:
    """The state a study's cases start from.

    label : ``virgin`` (the scene as given) or ``run<k>`` (carried into run k).
    scene : the scene the study's case builders receive (for ``run<k>``: the sequence's gaps
        and bent stiffness after runs 1 … k − 1, excitation at run k's PGA).
    run, engine : run k (1-based) and the engine whose sequence carried the state.
    base : the scene as given (its gaps and stiffness are the reference of the description).
    """

    label: str
    scene: Scene
    base: Scene
    run: int | None = None
    engine: str | None = None

    @property
    def carried(self) -> bool:
        return self.run is not None

    def stiffness_ratios(self) -> list[float]:
        """Carried / original bent stiffness, every bent and direction [-]."""
        return [
            getattr(b, a).stiffness / getattr(b0, a).stiffness
            for b, b0 in zip(self.scene.bents, self.base.bents)
            for a in ("x", "y")
        ]


_RUN = re.compile(r"run(\d+)")


def start_state(
    scene: Scene,
    spec: str = "virgin",
    *,
    engine: str | None = None,
    cache_folder: str | Path | None = None,
    sequence: list | None = None,
) -> StartState:
    """Resolve ``virgin``, ``strongest`` or ``run<k>`` into a :class:`StartState`.

    A carried state comes from ``sequence`` (the :class:`~.sequence_run.SequenceRun` list of
    one engine, when the caller has run it) or else from running the sequence's first k − 1
    runs with ``engine`` (default: the reference engine) through the cache in
    ``cache_folder``.
    """

    if spec == "virgin":
        return StartState("virgin", scene, scene)
    if spec == "strongest":
        k = strongest_run(scene)
    else:
        m = _RUN.fullmatch(spec)
        if m is None:
            raise SceneError(
                "--state", f"must be 'virgin', 'strongest' or 'run<k>' (e.g. run7), got {spec!r}"
            )
        k = int(m.group(1))
    if sequence is not None and len(sequence) >= k:
        run = sequence[k - 1]
        return StartState(f"run{k}", run.scene, scene, k, run.result.engine)
    engine = engine or DEFAULT_REFERENCE
    _, run_scene = state_before(scene, k, engine, cache_folder)
    return StartState(f"run{k}", run_scene, scene, k, engine)


# -- case builders -----------------------------------------------------------------------


def stiffness_cases(scene: Scene, quick: bool = False) -> list[Case]:
    ks = [1e4, 1e6, 1e8] if quick else [1e4, 1e5, 1e6, 1e7, 1e8]
    cases = [
        Case(
            f"compliance k={k:.0e}",
            "compliance",
            _compliance(scene, f"contact.stiffness={k!r}", "contact.law=linear"),
            {"stiffness": k},
        )
        for k in ks
    ]
    cases.append(Case("nonsmooth (rigid limit)", "nonsmooth", scene, {"stiffness": np.inf}))
    return cases


def friction_cases(scene: Scene, quick: bool = False) -> list[Case]:
    mus = [0.0, 0.2] if quick else [0.0, 0.1, 0.2, 0.3, 0.5]
    cases = []
    for mu in mus:
        mode = DEFAULT_FRICTION if mu > 0 else "none"
        ov = (f"contact.friction={mu!r}", f"contact.friction_mode={mode}")
        # newmark: the contact2d algorithm is OpenSees's fixed-step one (the engine refuses it
        # with the adaptive integrator)
        cases.append(
            Case(
                f"compliance mu={mu}",
                "compliance",
                _compliance(scene, *ov, "compliance.integrator=newmark"),
                {"mu": mu},
            )
        )
        cases.append(Case(f"nonsmooth mu={mu}", "nonsmooth", modified(scene, *ov), {"mu": mu}))
    return cases


def sticking_cases(scene: Scene, quick: bool = False) -> list[Case]:
    """Sliding only (slip), the project's stick law and OpenSees's zeroLengthContact2D
    algorithm (contact2d) at equal μ, compliance engine (newmark: contact2d needs it)."""
    mus = [0.2] if quick else [0.1, 0.2, 0.4]
    return [
        Case(
            f"compliance {mode} mu={mu}",
            "compliance",
            _compliance(
                scene,
                f"contact.friction={mu!r}",
                f"contact.friction_mode={mode}",
                "compliance.integrator=newmark",
            ),
            {"mu": mu, "friction_mode": mode},
        )
        for mu in mus
        for mode in ("slip", "stick", "contact2d")
    ]


def law_cases(scene: Scene, quick: bool = False) -> list[Case]:
    """Every law with the error-controlled ``adaptive`` integrator (events at closure, opening
    and the bilinear law's load/unload switches): differences are then the laws', not the
    discretisation's — and Newton on the bilinear law's kinks can stall at a fixed step."""

    laws = tuple(LAW_CODES)  # every row of the contact-law table
    return [
        Case(
            f"compliance {law}",
            "compliance",
            _compliance(scene, f"contact.law={law}", "compliance.integrator=adaptive"),
            {"law": law},
        )
        for law in laws
    ]


def geometry_cases(scene: Scene, quick: bool = False) -> list[Case]:
    # the project's stick law: contact2d (zeroLengthContact2D) has a fixed normal and tangent,
    # so it cannot run with the nonlinear kinematics this study compares
    mu = scene.contact.friction if scene.contact.has_friction else 0.2
    ov = (f"contact.friction={mu!r}", "contact.friction_mode=stick")
    cases = []
    for geo in ("linear", "nonlinear"):
        cases.append(
            Case(
                f"compliance {geo}",
                "compliance",
                _compliance(scene, *ov, f"contact.geometry={geo}"),
                {"geometry": geo},
            )
        )
        cases.append(
            Case(
                f"nonsmooth {geo}",
                "nonsmooth",
                modified(scene, *ov, f"contact.geometry={geo}"),
                {"geometry": geo},
            )
        )
    return cases


def opensees_mode_cases(scene: Scene, quick: bool = False) -> list[Case]:
    return [
        Case(f"opensees {m}", "opensees", modified(scene, f"opensees.mode={m}"), {"mode": m})
        for m in ("rigid", "stick")
    ]


@dataclass(frozen=True)
class Study:
    """A sensitivity study: ``cases(scene, quick)`` builds its cases from the start state's
    scene; ``x`` is the parameter on the figure's horizontal axis (``unit`` its unit);
    ``carried``: ``deckpound paper`` runs it from the strongest run's carried state as well
    as from the virgin state. Optionally its own table row (default :func:`case_row`), figure
    (default :func:`.figures.study_figure`, same signature), ``summary(table) -> list[str]``:
    sentences stating the result from the table's numbers, for the report, the units of its
    table and the scenes it applies to."""

    name: str
    title: str
    cases: Callable[[Scene, bool], list[Case]]
    x: str
    unit: str = ""
    carried: bool = False
    row: Callable[[Case, Result], dict] | None = None
    figure: Callable | None = None
    summary: Callable[[pd.DataFrame], list[str]] | None = None
    #: the units of the table's own columns (default: those of :func:`case_row`)
    units: Callable[[pd.DataFrame], dict[str, str]] | None = None
    #: whether the study applies to a scene (default: every scene); ``deckpound paper``
    #: leaves out the studies that do not apply to its scene
    applies: Callable[[Scene], bool] | None = None

    def applies_to(self, scene: Scene) -> bool:
        return self.applies is None or self.applies(scene)


STUDIES: dict[str, Study] = {
    s.name: s
    for s in (
        Study("stiffness", "Contact stiffness", stiffness_cases, "stiffness", "kN/m", True),
        Study("friction", "Friction on/off", friction_cases, "mu", "-", True),
        Study(
            "sticking",
            "Coulomb friction with and without sticking",
            sticking_cases,
            "mu",
            "-",
            True,
        ),
        Study("law", "Contact law", law_cases, "law", "", True),
        Study("geometry", "Geometrically linear vs nonlinear contact", geometry_cases, "geometry"),
        Study("opensees-mode", "OpenSees stick vs rigid deck", opensees_mode_cases, "mode"),
        Study(
            "skew",
            "Skewed deck: skew angle, with and without friction",
            skew_cases,
            "skew",
            "deg",
            row=skew_row,
            figure=skew_figure,
            summary=skew_headlines,
        ),
        Study(
            "damping",
            "Damping choices: members × stiffness × mass velocities",
            damping_cases,
            "damping",
            row=damping_row,
            figure=damping_figure,
            summary=damping_headlines,
        ),
        Study(
            "joint",
            "Deck segments: joint gap and wave-passage lag",
            joint_cases,
            "joint_gap",
            "m",
            row=joint_row,
            figure=joint_figure,
            summary=joint_headlines,
            units=joint_units,
            applies=lambda scene: bool(scene.joints),
        ),
    )
}
STUDY_NAMES = tuple(STUDIES) + ("sequence",)


def get_study(name: str) -> Study:
    if name not in STUDIES:
        raise SceneError(
            "study", f"unknown study {name!r}; valid studies: {', '.join(STUDY_NAMES)}"
        )
    return STUDIES[name]


def study_results(
    name: str,
    start: StartState,
    *,
    quick: bool = False,
    cache: ResultCache | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
) -> tuple[list[Case], dict[str, Result], pd.DataFrame]:
    """Run a study from a start state: its cases, their results and its table."""
    study = get_study(name)
    cases = study.cases(start.scene, quick)
    results = run_cases(
        cases,
        cache=cache,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        title=f"study {name} ({start.label})",
    )
    if study.row is not None:
        rows = [{**study.row(c, results[c.label]), "state": start.label} for c in cases]
    else:
        rows = [case_row(c, results[c.label], start.label) for c in cases]
    return cases, results, pd.DataFrame(rows)


def study_units(name: str, table: pd.DataFrame) -> dict[str, str]:
    """Units of a study table's columns."""
    study = get_study(name)
    if study.units is not None:
        return study.units(table)
    units = {k: v for k, v in ROW_UNITS.items() if k in table}
    if study.unit and study.x in table:
        units[study.x] = study.unit
    return units


def run_study(
    name: str,
    scene: Scene,
    out: str | Path,
    *,
    quick: bool = False,
    cache: ResultCache | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    state: str | StartState = "virgin",
    state_engine: str | None = None,
    formats: tuple[str, ...] = (),
) -> tuple[pd.DataFrame, dict]:
    """Run a study from ``state`` (default: the scene as given) and write ``<name>.csv`` and
    ``<name>.png`` (``<name>_<state>.*`` for a carried state; ``formats`` adds e.g. PDF) in
    ``out``; return the table and the results."""
    if not isinstance(state, StartState):
        cache_folder = cache.folder if cache is not None else None
        state = start_state(scene, state, engine=state_engine, cache_folder=cache_folder)
    cases, results, table = study_results(
        name,
        state,
        quick=quick,
        cache=cache,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
    )
    out = folder(out)
    stem = name if not state.carried else f"{name}_{state.label}"
    write_csv(table, out / f"{stem}.csv", study_units(name, table))
    study = get_study(name)
    (study.figure or study_figure)(
        study,
        state.scene,
        cases,
        results,
        table,
        out / f"{stem}.png",
        formats=formats,
        subtitle=state_caption(state),
    )
    return table, results


def state_caption(state: StartState) -> str:
    """One line naming a start state (for figure titles)."""
    if not state.carried:
        return "virgin state (the scene as given)"
    return f"state carried into run {state.run} by the {state.engine} sequence"

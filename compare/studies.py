"""The paper's sensitivity studies (Section 3), one function of the scene each.

A study turns a scene into cases (engine + modified scene), runs them through the cache and
the parallel runner, and writes a table (CSV) and a figure (PNG and PDF):

==============  ============================================================================
stiffness       peak deck rotation vs contact stiffness (≥ 4 decades), nonsmooth = rigid limit
friction        friction on/off (μ sweep, sticking law), compliance and nonsmooth
sticking        Coulomb with vs without sticking, compliance
law             contact law: linear, Kelvin–Voigt, Hertz, Hertz-damp, bilinear
geometry        geometrically linear vs nonlinear contact kinematics
opensees-mode   OpenSees stick vs rigid deck
sequence        the 7-run sequence with carried gap and stiffness, every engine
==============  ============================================================================

Compliance cases resolve the contact: their step is at most the contact period / 20
(:func:`contact_step`), so stiff cases stay accurate rather than merely stable.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from deckpound.models._fields import to_mapping
from deckpound.models.contact_params import effective_masses
from deckpound.models.errors import SceneError
from deckpound.models.result import Result
from deckpound.models.scene import Scene
from deckpound.models.scene_io import apply_overrides, scene_from_mapping

from .cases import Case, ResultCache, run_cases
from .metrics import peak

ENGINES_ALL = ("opensees", "compliance", "nonsmooth")


def modified(scene: Scene, *overrides: str) -> Scene:
    """A copy of the scene with ``path=value`` overrides applied and validated."""
    return scene_from_mapping(apply_overrides(to_mapping(scene), overrides))


def contact_step(scene: Scene, per_period: int = 20) -> float:
    """Compliance time step resolving the stiffest contact oscillation (linearised) [s]."""
    k = scene.contact.stiffness
    if scene.contact.law in ("hertz", "hertz-damp"):
        k = k * np.sqrt(0.01)  # secant stiffness at 10 mm penetration, an upper estimate
    period = 2.0 * np.pi * np.sqrt(float(np.min(effective_masses(scene))) / k)
    return float(min(scene.compliance.dt, period / per_period))


def _compliance(scene: Scene, *overrides: str) -> Scene:
    s = modified(scene, *overrides)
    return modified(s, f"compliance.dt={contact_step(s)!r}")


def case_row(case: Case, result: Result) -> dict:
    """Headline numbers of one case."""
    row = dict(label=case.label, engine=case.engine, **case.params)
    row.update(
        peak_theta=peak(result["deck_theta"]), peak_x=peak(result["deck_x_rel"]),
        peak_y=peak(result["deck_y_rel"]),
        peak_fn=max(peak(result[f"fn_c{c}"]) for c in range(1, 5)),
        gap_closures=result.gap_closures,
        wall_time=result.meta.get("wall_time", float("nan")), status=result.meta.get("status"),
    )
    return row


# -- case builders -----------------------------------------------------------------------

def stiffness_cases(scene: Scene, quick: bool = False) -> list[Case]:
    ks = [1e4, 1e6, 1e8] if quick else [1e4, 1e5, 1e6, 1e7, 1e8]
    cases = [Case(f"compliance k={k:.0e}", "compliance",
                  _compliance(scene, f"contact.stiffness={k!r}", "contact.law=linear"),
                  {"stiffness": k}) for k in ks]
    cases.append(Case("nonsmooth (rigid limit)", "nonsmooth", scene, {"stiffness": np.inf}))
    return cases


def friction_cases(scene: Scene, quick: bool = False) -> list[Case]:
    mus = [0.0, 0.2] if quick else [0.0, 0.1, 0.2, 0.3, 0.5]
    cases = []
    for mu in mus:
        mode = "stick" if mu > 0 else "none"
        ov = (f"contact.friction={mu!r}", f"contact.friction_mode={mode}")
        cases.append(Case(f"compliance mu={mu}", "compliance", _compliance(scene, *ov),
                          {"mu": mu}))
        cases.append(Case(f"nonsmooth mu={mu}", "nonsmooth", modified(scene, *ov), {"mu": mu}))
    return cases


def sticking_cases(scene: Scene, quick: bool = False) -> list[Case]:
    mus = [0.2] if quick else [0.1, 0.2, 0.4]
    return [Case(f"compliance {mode} mu={mu}", "compliance",
                 _compliance(scene, f"contact.friction={mu!r}", f"contact.friction_mode={mode}"),
                 {"mu": mu, "friction_mode": mode})
            for mu in mus for mode in ("slip", "stick")]


def law_cases(scene: Scene, quick: bool = False) -> list[Case]:
    """Every law with the error-controlled ``adaptive`` integrator (events at closure, opening
    and the bilinear law's load/unload switches): differences are then the laws', not the
    discretisation's — and Newton on the bilinear law's kinks can stall at a fixed step."""
    from deckpound.models.contact_laws_table import LAW_CODES

    laws = tuple(LAW_CODES)       # every row of the contact-law table
    return [Case(f"compliance {law}", "compliance",
                 _compliance(scene, f"contact.law={law}", "compliance.integrator=adaptive"),
                 {"law": law}) for law in laws]


def geometry_cases(scene: Scene, quick: bool = False) -> list[Case]:
    mu = scene.contact.friction if scene.contact.has_friction else 0.2
    ov = (f"contact.friction={mu!r}", "contact.friction_mode=stick")
    cases = []
    for geo in ("linear", "nonlinear"):
        cases.append(Case(f"compliance {geo}", "compliance",
                          _compliance(scene, *ov, f"contact.geometry={geo}"), {"geometry": geo}))
        cases.append(Case(f"nonsmooth {geo}", "nonsmooth",
                          modified(scene, *ov, f"contact.geometry={geo}"), {"geometry": geo}))
    return cases


def opensees_mode_cases(scene: Scene, quick: bool = False) -> list[Case]:
    return [Case(f"opensees {m}", "opensees", modified(scene, f"opensees.mode={m}"), {"mode": m})
            for m in ("rigid", "stick")]


@dataclass(frozen=True)
class Study:
    name: str
    title: str
    cases: Callable[[Scene, bool], list[Case]]
    x: str            # parameter on the figure's horizontal axis


STUDIES: dict[str, Study] = {s.name: s for s in (
    Study("stiffness", "Contact stiffness", stiffness_cases, "stiffness"),
    Study("friction", "Friction on/off", friction_cases, "mu"),
    Study("sticking", "Coulomb friction with and without sticking", sticking_cases, "mu"),
    Study("law", "Contact law", law_cases, "law"),
    Study("geometry", "Geometrically linear vs nonlinear contact", geometry_cases, "geometry"),
    Study("opensees-mode", "OpenSees stick vs rigid deck", opensees_mode_cases, "mode"),
)}
STUDY_NAMES = tuple(STUDIES) + ("sequence",)


def get_study(name: str) -> Study:
    if name not in STUDIES:
        raise SceneError("study", f"unknown study {name!r}; valid studies: {', '.join(STUDY_NAMES)}")
    return STUDIES[name]


def run_study(name: str, scene: Scene, out: str | Path, *, quick: bool = False,
              cache: ResultCache | None = None, workers: int | None = None,
              scheduler: str | None = None, progress: bool = True) -> tuple[pd.DataFrame, dict]:
    """Run a study, write ``<name>.csv`` and ``<name>.png/.pdf`` in ``out``; return the table."""
    from .figures import study_figure

    study = get_study(name)
    cases = study.cases(scene, quick)
    results = run_cases(cases, cache=cache, workers=workers, scheduler=scheduler,
                        progress=progress, title=f"study {name}")
    table = pd.DataFrame([case_row(c, results[c.label]) for c in cases])
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    table.to_csv(out / f"{name}.csv", index=False)
    study_figure(study, scene, cases, results, table, out / f"{name}.png")
    return table, results

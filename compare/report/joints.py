"""The paper's section "Pounding between deck segments" (issue 31, item 5): the joint study
(:mod:`deckpound.compare.studies.joint`) on a deck of segments, and what the joint gap and the
wave-passage lag do to the joints, the rotations and the seat margins.

The paper's scene is a one-body deck (``deckpound paper`` refuses a deck of segments). For the
built-in benchmark the section runs the built-in ``two-frame`` scene (the same bridge with an
expansion joint over its middle bent) on the benchmark's record length, so that the main job
shows the deck–deck pounding the paper names beside the deck–abutment pounding it studies; for
a user's scene there is no section (``deckpound study joint`` runs a deck of segments).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from deckpound.compare.report.outputs import write_csv
from deckpound.compare.report.render import CONTACT_FORCE, MM, MRAD, Figure, Table, view
from deckpound.compare.studies.sensitivity import (
    StartState,
    get_study,
    state_caption,
    study_results,
    study_units,
)
from deckpound.models.scene import Scene
from deckpound.models.scene_io import load_scene

__all__ = ["BENCHMARK", "JointsRun", "joints_scene", "joints_section", "run_joints"]

#: the built-in one-body benchmark whose report shows the joint study of :data:`TWO_FRAME`
BENCHMARK = "saiidi-4span"
TWO_FRAME = "two-frame"
FIGURE = "figures/study_joint.png"
TABLE = "tables/study_joint.csv"


@dataclass
class JointsRun:
    """What the section is written from: the scene the study ran on and its table."""

    scene: Scene
    table: pd.DataFrame


def joints_scene(scene: Scene) -> Scene | None:
    """The scene the section's study runs on, or None for a scene other than the benchmark
    (module docstring). The stand-in takes the paper scene's record length."""
    if scene.name != BENCHMARK or scene.segments is not None:
        return None
    two = load_scene(TWO_FRAME)
    changes = {"excitation.duration": scene.excitation.duration}
    if scene.run.duration is not None:
        changes["run.duration"] = scene.run.duration
    return two.replace(changes)


def run_joints(
    scene: Scene,
    out: Path,
    *,
    quick: bool,
    cache,
    workers: int | None,
    scheduler: str | None,
    progress: bool,
    formats: tuple[str, ...] = (),
) -> JointsRun | None:
    """Run the joint study for the section (None: no section); write its table and figure."""
    sc = joints_scene(scene)
    if sc is None:
        return None
    state = StartState("virgin", sc, sc)
    cases, results, table = study_results(
        "joint",
        state,
        quick=quick,
        cache=cache,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
    )
    write_csv(table, out / TABLE, study_units("joint", table))
    study = get_study("joint")
    study.figure(
        study,
        sc,
        cases,
        results,
        table,
        out / FIGURE,
        formats=formats,
        subtitle=state_caption(state),
    )
    return JointsRun(sc, table)


def joints_section(run: JointsRun | None) -> list:
    """The items of the section."""
    if run is None:
        return []
    t = run.table
    where = (
        f"The benchmark is one rigid deck; this section runs the built-in scene "
        f"{run.scene.name!r}, the same bridge with an expansion joint over its middle bent "
        "(every assumed value is in its notes), on the benchmark's record length."
    )
    engines = " and ".join(dict.fromkeys(t["engine"]))
    gaps = ", ".join(f"{1e3 * g:g}" for g in sorted(t["joint_gap"].unique()))
    lags = ", ".join(f"{lag:g}" for lag in sorted(t["lag"].unique()))
    segment_thetas = [c for c in t.columns if str(c).startswith("peak_theta_")]
    return [
        f"{where} The {engines} engines ran every joint gap ({gaps} mm) with every lag between "
        f"successive tables ({lags} s): {len(t)} cases.",
        *get_study("joint").summary(t),
        Figure(
            FIGURE,
            f"Joint force [{CONTACT_FORCE.unit}], largest segment rotation [mrad], joint gap "
            "closures and largest joint opening [mm] against the joint gap, one line per engine "
            "and lag (darker: longer lag).",
        ),
        Table(
            view(
                t,
                [
                    ("engine", "engine", 1),
                    ("joint_gap", "joint gap [mm]", MM),
                    ("lag", "lag [s]", 1),
                    ("peak_fn_joint", f"joint force [{CONTACT_FORCE.unit}]", CONTACT_FORCE.scale),
                    ("joint_closures", "joint closures", 1),
                    ("joint_opening_max", "joint opening [mm]", MM),
                    ("joint_margin_min", "joint seat margin [mm]", MM),
                    ("abutment_margin_min", "abutment seat margin [mm]", MM),
                    *[(c, f"θ {c[len('peak_theta_') :]} [mrad]", MRAD) for c in segment_thetas],
                    ("status", "status", 1),
                ],
            ),
            f"{TABLE}; forces over every step (the nonsmooth engine's is its step impulse / h); "
            "seat margins: support length − the largest gap opening.",
        ),
    ]

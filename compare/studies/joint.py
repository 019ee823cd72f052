"""``deckpound study joint SCENE``: the joint gap and the wave-passage lag of a deck of segments.

Issue 31: the source paper names pounding "between adjacent deck segments" next to the
deck–abutment pounding it studies, and the field's evidence places the damage at expansion
joints and in-span hinges, where wave passage enlarges the joint's relative motion (Hao &
Chouw 2008; Wang et al. 2004). The cases are the joints' clear gap (every joint of the scene
set to the same value) × ``excitation.lag`` (the delay between successive bent tables; bents at
one station share their table), every engine that expresses the scene. Each row holds what a
designer reads at a joint and at the abutments: the normal force and the gap closures at the
joints, the largest joint opening and the smallest joint seat margin, the smallest abutment
seat margin, and the peak rotation of each segment (and the largest of them), all over every
step (:meth:`deckpound.models.result.Result.peak` and the result's seat-margin metadata).
The nonsmooth engine's normal force is its step impulse over the step (rigid contact has no
force history), so its joint force scales with 1/h and is compared across cases, not with
the penalty engines' forces.

The scene must be a deck of segments (``segments`` and ``joints``; the built-in ``two-frame``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.cases import Case, engine_expresses
from deckpound.compare.engines import engine_names, engine_style
from deckpound.compare.report.render import CONTACT_FORCE
from deckpound.models.errors import SceneError
from deckpound.models.plan import plan_of
from deckpound.models.result import Result
from deckpound.models.scene import Scene

__all__ = [
    "JOINT_GAPS",
    "JOINT_LAGS",
    "JOINT_UNITS",
    "joint_cases",
    "joint_figure",
    "joint_headlines",
    "joint_row",
    "joint_units",
]

#: the joint gaps of the full study [m]: closed, a quarter, half, one and two inches and four
JOINT_GAPS = (0.0, 0.00635, 0.0127, 0.0254, 0.0508, 0.1016)
#: the lags between successive tables of the full study [s]
JOINT_LAGS = (0.0, 0.025, 0.05, 0.1, 0.2)
QUICK_GAPS = (0.0, 0.0127, 0.0508)
QUICK_LAGS = (0.0, 0.1)

#: units of the columns of :func:`joint_row` (besides the per-segment ``peak_theta_<name>``)
JOINT_UNITS = {
    "joint_gap": "m",
    "lag": "s",
    "peak_theta": "rad",
    "peak_fn_joint": "kN",
    "peak_fn_abutment": "kN",
    "joint_closures": "-",
    "abutment_closures": "-",
    "joint_opening_max": "m",
    "joint_margin_min": "m",
    "abutment_margin_min": "m",
    "gap_closures": "-",
    "wall_time": "s",
}


def _check_segments(scene: Scene) -> None:
    if not scene.joints:
        raise SceneError(
            "segments",
            f"the joint study needs a deck of segments (segments and joints; e.g. the "
            f"built-in 'two-frame'); scene {scene.name!r} has one rigid deck",
        )


def joint_cases(scene: Scene, quick: bool = False) -> list[Case]:
    """Joint gap × lag × engine (module docstring): every joint's gap set to the case's, the
    rest of the scene as given; an engine that refuses the scene is left out (logged)."""
    _check_segments(scene)
    gaps, lags = (QUICK_GAPS, QUICK_LAGS) if quick else (JOINT_GAPS, JOINT_LAGS)
    cases = []
    for lag in lags:
        for gap in gaps:
            changes = {f"joints[{k}].gap": gap for k in range(len(scene.joints))}
            changes["excitation.lag"] = lag
            sc = scene.replace(changes)
            label = f"gap {1e3 * gap:g} mm, lag {lag:g} s"
            for engine in engine_names():
                if engine_expresses(engine, sc, "joint"):
                    params = {"joint_gap": gap, "lag": lag}
                    cases.append(Case(f"{engine} {label}", engine, sc, params))
    return cases


def _joint_corners(scene: Scene) -> tuple[list[str], list[str]]:
    """The names of the joint corners and of the abutment corners."""
    corners = plan_of(scene).corners
    return [c.name for c in corners if c.joint >= 0], [c.name for c in corners if c.joint < 0]


def _smallest(values: dict, names: list[str]) -> float:
    """The smallest first entry of ``values[name]`` ([value, time] lists) over ``names``; NaN
    when none is there (a margin not checked)."""
    found = [float(values[n][0]) for n in names if n in values]
    return min(found) if found else float("nan")


def joint_row(case: Case, result: Result) -> dict:
    """The headline numbers of one case (module docstring; forces [kN], lengths [m], θ [rad])."""
    scene = case.scene
    joint, abutment = _joint_corners(scene)
    meta = result.meta
    per_corner = meta.get("gap_closures_per_corner", {})
    openings = meta.get("gap_opening_max", {})
    margins = meta.get("seat_margin_min", {})
    segments = [seg.name for seg in plan_of(scene).segments]
    thetas = {f"peak_theta_{n}": result.peak(f"{n}_theta") for n in segments}
    row = dict(label=case.label, engine=case.engine, **case.params)
    row.update(
        peak_theta=max(thetas.values()),
        **thetas,
        peak_fn_joint=max(result.peak(f"fn_{c}") for c in joint),
        peak_fn_abutment=max(result.peak(f"fn_{c}") for c in abutment),
        joint_closures=sum(int(per_corner.get(c, 0)) for c in joint),
        abutment_closures=sum(int(per_corner.get(c, 0)) for c in abutment),
        joint_opening_max=max(float(openings[c][0]) for c in joint if c in openings),
        joint_margin_min=_smallest(margins, joint),
        abutment_margin_min=_smallest(margins, abutment),
        gap_closures=result.gap_closures,
        wall_time=meta.get("wall_time", float("nan")),
        status=meta.get("status"),
    )
    return row


def joint_units(table: pd.DataFrame) -> dict[str, str]:
    """Units of a joint-study table's columns."""
    units = {k: v for k, v in JOINT_UNITS.items() if k in table}
    units.update({k: "rad" for k in table if str(k).startswith("peak_theta_")})
    return units


#: the four panels of :func:`joint_figure`: (column, axis label, scale)
PANELS = (
    ("peak_fn_joint", f"peak joint force [{CONTACT_FORCE.unit}]", CONTACT_FORCE.scale),
    ("peak_theta", "largest segment peak θ [mrad]", 1e3),
    ("joint_closures", "joint gap closures [-]", 1.0),
    ("joint_opening_max", "largest joint opening [mm]", 1e3),
)


def joint_figure(
    study,
    scene: Scene,
    cases,
    results,
    table: pd.DataFrame,
    path: str | Path,
    formats: tuple[str, ...] = (),
    subtitle: str = "",
) -> list[Path]:
    """Four panels against the joint gap [mm] (:data:`PANELS`): one line per engine and lag,
    the lag by shade (the darker, the longer), the engine by its style."""
    from deckpound.compare.report.style import new_figure, outside_legend, save

    fig, axes = new_figure(2, 2, width=9.0, height=2.6, sharex=True)
    lags = sorted(table["lag"].unique())
    for engine, g in table.groupby("engine", sort=False):
        style = engine_style(engine) if engine in engine_names() else {}
        for i, lag in enumerate(lags):
            h = g[g["lag"] == lag].sort_values("joint_gap")
            shade = 0.25 + 0.75 * (i + 1) / len(lags)
            for k, (col, _, scale) in enumerate(PANELS):
                ax = axes[k // 2, k % 2]
                ax.plot(
                    1e3 * h["joint_gap"],
                    scale * h[col],
                    color=style.get("color", "k"),
                    alpha=shade,
                    linestyle=style.get("linestyle", "-"),
                    marker="o",
                    markersize=3,
                    label=f"{style.get('label', engine)}, lag {lag:g} s" if k == 1 else None,
                )
    for k, (_, label, _) in enumerate(PANELS):
        axes[k // 2, k % 2].set_ylabel(label, fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("joint gap [mm]")
    axes[0, 0].set_title(
        (study.title if study is not None else "joint") + (f" — {subtitle}" if subtitle else ""),
        fontsize=8,
    )
    outside_legend(axes[0, 1])
    return save(fig, path, scene.name, formats)


def _range(g: pd.DataFrame, col: str, scale: float, unit: str, fmt: str = ".3g") -> str:
    """'low (its case) to high (its case)'; a zero is named as no contact at the joint."""
    lo, hi = g[col].idxmin(), g[col].idxmax()

    def value(k) -> str:
        v = scale * g.loc[k, col]
        return "0, no joint contact," if v == 0 else f"{v:{fmt}} {unit}"

    return (
        f"{value(lo)} (gap {1e3 * g.loc[lo, 'joint_gap']:g} mm, lag {g.loc[lo, 'lag']:g} s) to "
        f"{value(hi)} (gap {1e3 * g.loc[hi, 'joint_gap']:g} mm, lag {g.loc[hi, 'lag']:g} s)"
    )


def joint_headlines(table: pd.DataFrame) -> list[str]:
    """Per engine, from the table's numbers: the range of the joint force, of the largest
    segment rotation and of the joint opening over the cases (each end named by its case),
    and how the lag moves the joint force at the scene's own gaps (the mean over gaps of the
    longest lag's force over the zero lag's)."""
    out = []
    ok = table[table["status"].isin(["success", "unseated"])]
    for engine, g in ok.groupby("engine", sort=False):
        parts = [
            "peak joint force "
            + _range(g, "peak_fn_joint", CONTACT_FORCE.scale, CONTACT_FORCE.unit),
            "largest segment rotation " + _range(g, "peak_theta", 1e3, "mrad"),
            "largest joint opening " + _range(g, "joint_opening_max", 1e3, "mm"),
        ]
        lags = sorted(g["lag"].unique())
        if len(lags) > 1:
            first = g[g["lag"] == lags[0]].set_index("joint_gap")["peak_fn_joint"]
            last = g[g["lag"] == lags[-1]].set_index("joint_gap")["peak_fn_joint"]
            both = first.index.intersection(last.index)
            ratios = (last[both] / first[both]).replace([np.inf, -np.inf], np.nan).dropna()
            if len(ratios):
                parts.append(
                    f"a lag of {lags[-1]:g} s against none multiplies the joint force by "
                    f"{ratios.mean():.3g} on average over the gaps "
                    f"({ratios.min():.3g}–{ratios.max():.3g})"
                )
        unseated = int((g["status"] == "unseated").sum())
        if unseated:
            parts.append(f"{unseated} of {len(g)} cases unseat")
        out.append(f"{engine}: " + "; ".join(parts) + ".")
    return out

"""``deckpound study damping SCENE``: how much each damping choice moves the answer.

Issue 12: the paper says only "Rayleigh damping, 8 %", yet three choices left implicit change
the benchmark by tens of percent. The cases are ``damping.members`` (bents | bents+seats |
none) × ``damping.stiffness`` (initial | committed | current) × ``damping.mass`` (absolute |
relative), every engine that expresses the case (the nonsmooth engine refuses the committed and
current tangents; a refused case is left out with its reason in the log). ``quick``: the three
members at the initial stiffness and absolute velocities, plus committed, current and relative
on the bents. Each row: the case's choices, peak deck rotation, peak normal gap force and the
number of gap closures (with :func:`deckpound.compare.studies.sensitivity.case_row`'s other peaks); the
report states, per engine, how far each choice moves these from the scene's own damping.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from deckpound.compare.cases import Case, engine_expresses
from deckpound.compare.engines import engine_names, engine_style
from deckpound.compare.report.render import CONTACT_FORCE
from deckpound.compare.studies.case_rows import case_row
from deckpound.models.result import Result
from deckpound.models.scene import DAMPING_MASS, DAMPING_MEMBERS, DAMPING_STIFFNESS, Scene
from deckpound.models.scene_io import modified

__all__ = ["damping_cases", "damping_figure", "damping_headlines", "damping_row"]


QUICK = (
    ("bents", "initial", "absolute"),
    ("bents+seats", "initial", "absolute"),
    ("none", "initial", "absolute"),
    ("bents", "committed", "absolute"),
    ("bents", "current", "absolute"),
    ("bents", "initial", "relative"),
)


def _choices(quick: bool) -> list[tuple[str, str, str]]:
    if quick:
        return list(QUICK)
    return [
        (m, s, a)
        for m in DAMPING_MEMBERS
        for s in DAMPING_STIFFNESS
        for a in DAMPING_MASS
        # the stiffness choice does nothing without stiffness-proportional members
        if not (m == "none" and s != "initial")
    ]


def damping_cases(scene: Scene, quick: bool = False) -> list[Case]:
    """members × stiffness × mass × engine (module docstring); the other damping fields
    (ratio, method) as the scene has them."""

    cases = []
    for members, stiffness, mass in _choices(quick):
        sc = modified(
            scene,
            f"damping.members={members}",
            f"damping.stiffness={stiffness}",
            f"damping.mass={mass}",
        )
        label = f"{members}·{stiffness}·{mass}"
        for engine in engine_names():
            if engine_expresses(engine, sc, "damping"):
                cases.append(
                    Case(
                        f"{engine} {label}",
                        engine,
                        sc,
                        {
                            "damping": label,
                            "members": members,
                            "stiffness": stiffness,
                            "mass": mass,
                        },
                    )
                )
    return cases


def damping_row(case: Case, result: Result) -> dict:
    """The common headline numbers (peak rotation, peak gap force ``peak_fn``, gap closures)."""

    return case_row(case, result)


def damping_figure(
    study,
    scene: Scene,
    cases,
    results,
    table: pd.DataFrame,
    path: str | Path,
    formats: tuple[str, ...] = (),
    subtitle: str = "",
) -> list[Path]:
    """Peak deck rotation (top) and peak normal gap force (bottom, in the report's contact-force
    unit :data:`~deckpound.compare.report.render.CONTACT_FORCE`) per damping case, one marker
    series per engine (markers only: the cases are choices, not a continuum)."""
    from deckpound.compare.report.style import new_figure, outside_legend, save, series_styles

    labels = list(dict.fromkeys(table["damping"]))
    fig, axes = new_figure(2, 1, width=9.0, height=2.6)
    groups = list(table.groupby("engine", sort=False))
    names = [str(engine) for engine, _ in groups]
    styles = series_styles(
        [engine_style(e).get("label", e) if e in engine_names() else e for e in names],
        [e if e in engine_names() else None for e in names],
    )
    force = CONTACT_FORCE
    for k, ((_, g), st) in enumerate(zip(groups, styles)):
        x = [labels.index(lab) + 0.12 * (k - 1) for lab in g["damping"]]
        for ax, q, scale in ((axes[0, 0], "peak_theta", 1e3), (axes[1, 0], "peak_fn", force.scale)):
            ax.plot(x, scale * g[q], **{**st, "linestyle": "none"})
    axes[0, 0].set_ylabel("peak θ_d [mrad]")
    axes[1, 0].set_ylabel(f"peak gap force [{force.unit}]")
    axes[1, 0].set_xticks(range(len(labels)))
    axes[1, 0].set_xticklabels(labels, rotation=35, ha="right", fontsize=6)
    axes[0, 0].set_xticks(range(len(labels)))
    axes[0, 0].set_xticklabels([])
    axes[0, 0].set_title(
        (study.title if study is not None else "damping") + (f" — {subtitle}" if subtitle else ""),
        fontsize=8,
    )
    outside_legend(axes[0, 0])
    return save(fig, path, scene.name, formats)


def damping_headlines(table: pd.DataFrame) -> list[str]:
    """Per engine: the reference case (the first, the scene's own members at the initial
    stiffness and absolute velocities) and the range over the other choices of peak
    rotation, peak gap force and gap closures, each choice that moves them most named."""
    out = []
    ok = table[table["status"] == "success"]
    for engine, g in ok.groupby("engine", sort=False):
        ref = g.iloc[0]
        parts = []
        for q, name, unit, scale in (
            ("peak_theta", "peak rotation", "mrad", 1e3),
            ("peak_fn", "peak gap force", CONTACT_FORCE.unit, CONTACT_FORCE.scale),
        ):
            ratio = g[q] / ref[q] if ref[q] > 0 else None
            if ratio is None or not ratio.notna().any():
                # a reference of zero (no contact in a short or weak record) has no ratios
                parts.append(
                    f"{name} {scale * ref[q]:.4g} {unit} in the reference case, "
                    f"{scale * g[q].min():.4g}–{scale * g[q].max():.4g} {unit} over the choices"
                )
                continue
            lo, hi = ratio.idxmin(), ratio.idxmax()
            parts.append(
                f"{name} {scale * ref[q]:.4g} {unit} ×{ratio[lo]:.3g} "
                f"({g.loc[lo, 'damping']}) to ×{ratio[hi]:.3g} "
                f"({g.loc[hi, 'damping']})"
            )
        parts.append(
            f"gap closures {int(ref['gap_closures'])} "
            f"({int(g['gap_closures'].min())}–{int(g['gap_closures'].max())})"
        )
        out.append(f"{engine}, from {ref['damping']}: " + "; ".join(parts) + ".")
    return out

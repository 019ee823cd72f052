"""Paper-style figures of results (matplotlib; PNG, other formats such as PDF on request; one
style, greyscale-readable).

Displacements are drawn relative to the supports (the deck relative to the shake tables, a seat
relative to its actuator) unless a column named ``*_abs`` is asked for; every axis names which
and its unit. matplotlib is imported by the functions that draw (through :mod:`.style`), so a
run whose figures are all reused (:mod:`.figure_cache`) does not load it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.engines import engine_names, engine_style
from deckpound.compare.mechanism import contact_moments, mechanism_row
from deckpound.compare.report.figure_cache import reusable
from deckpound.compare.report.render import BENT_FORCE, CONTACT_FORCE
from deckpound.compare.report.text import TOL
from deckpound.models.plan import plan_of
from deckpound.models.result import Result
from deckpound.models.scene import Scene

LABELS = {
    "deck_theta": ("deck rotation θ_d", 1e3, "mrad"),
    "deck_y_rel": ("deck y_d rel. tables", 1e3, "mm"),
    "deck_x_rel": ("deck x_d rel. tables", 1e3, "mm"),
    "deck_y_abs": ("deck y_d absolute", 1e3, "mm"),
    "deck_x_abs": ("deck x_d absolute", 1e3, "mm"),
    "seat1_x_rel": ("seat 1 x rel. actuator", 1e3, "mm"),
    "seat2_x_rel": ("seat 2 x rel. actuator", 1e3, "mm"),
}


def column_label(column: str) -> tuple[str, float, str]:
    """(axis label, scale, unit) of a history column: :data:`LABELS`, a deck segment's
    ``<seg>_theta`` / ``<seg>_x_rel`` / ``<seg>_y_rel`` / gap, or the column's own name."""
    if column in LABELS:
        return LABELS[column]
    for suffix, what, scale, unit in (
        ("_theta", "rotation θ", 1e3, "mrad"),
        ("_y_rel", "y rel. tables", 1e3, "mm"),
        ("_x_rel", "x rel. tables", 1e3, "mm"),
    ):
        if column.endswith(suffix):
            return f"{column[: -len(suffix)]} {what}", scale, unit
    if column.startswith("gap_"):
        return f"gap {column[4:]}", 1e3, "mm"
    return column, 1.0, ""


@reusable
def histories(
    results: dict[str, Result],
    scene: Scene,
    path: str | Path,
    quantities: tuple[str, ...] = ("deck_theta", "deck_y_rel"),
    title: str = "",
    formats: tuple[str, ...] = (),
) -> list[Path]:
    """Time histories of quantities overlaid per engine/case (paper Figs. 4–6 style)."""
    from deckpound.compare.report.style import new_figure, outside_legend, save, series_styles

    fig, axes = new_figure(len(quantities), 1, width=7.5, height=2.2, sharex=True)
    styles = series_styles(list(results), points=[len(r.t) for r in results.values()])
    for i, q in enumerate(quantities):
        name, scale, unit = column_label(q)
        ax = axes[i, 0]
        for st, r in zip(styles, results.values()):
            if q in r.columns:
                ax.plot(r.t, scale * r[q], **st)
        ax.set_ylabel(f"{name} [{unit}]")
    outside_legend(axes[0, 0])
    if title:
        axes[0, 0].set_title(title)
    axes[-1, 0].set_xlabel("time [s]")
    return save(fig, path, scene.name, formats)


@reusable
def contact_forces(
    results: dict[str, Result],
    scene: Scene,
    path: str | Path,
    title: str = "",
    formats: tuple[str, ...] = (),
) -> list[Path]:
    """Normal contact force per corner, one column of panels per face (c1, c2 at seat 1; the
    corners of each joint of a deck of segments; c3, c4 at seat 2), in the report's
    contact-force unit (:data:`~.render.CONTACT_FORCE`)."""
    from deckpound.compare.report.style import new_figure, outside_legend, save, series_styles

    faces = corner_faces(plan_of(scene))
    fig, axes = new_figure(2, len(faces), width=4.0 * len(faces), height=2.0, sharex=True)
    styles = series_styles(list(results), points=[len(r.t) for r in results.values()])
    for col, (face, corners) in enumerate(faces):
        for row, c in enumerate(corners):
            ax = axes[row, col]
            for st, r in zip(styles, results.values()):
                ax.plot(r.t, CONTACT_FORCE.scale * r[f"fn_{c}"], **st)
            ax.set_title(f"corner {c} ({face})")
            ax.set_ylabel(f"normal force fn [{CONTACT_FORCE.unit}]")
        axes[-1, col].set_xlabel("time [s]")
    outside_legend(axes[0, -1])
    if title:
        fig.suptitle(title, fontsize=9)
    return save(fig, path, scene.name, formats)


def corner_faces(plan) -> list[tuple[str, tuple[str, ...]]]:
    """The plan's corners by the face they strike: ``[("seat 1", ("c1", "c2")), ("joint 1",
    ("j1_c1", "j1_c2")), …, ("seat 2", ("c3", "c4"))]``, in order along the bridge."""
    faces: dict[str, list[str]] = {}
    for c in plan.corners:
        face = f"joint {c.joint + 1}" if c.joint >= 0 else f"seat {c.seat + 1}"
        faces.setdefault(face, []).append(c.name)
    return [(face, tuple(names)) for face, names in faces.items()]


@reusable
def peak_vs_pga(
    table: pd.DataFrame,
    scene: Scene,
    path: str | Path,
    quantity: str = "peak_theta",
    formats: tuple[str, ...] = (),
) -> list[Path]:
    """Peak deck rotation vs run PGA over the sequence, one line per engine and friction
    assumption (``case`` column: engine name, then a variant tag; paper Fig. 7)."""
    from deckpound.compare.report.style import new_figure, outside_legend, save, series_styles

    fig, axes = new_figure(1, 1, width=6.5, height=3.2)
    ax = axes[0, 0]
    key = "case" if "case" in table else "engine"
    groups = list(table.groupby(key, sort=False))
    labels, engines = [], []
    for case, _ in groups:
        base, _, variant = str(case).partition(" ")
        engine = base if base in engine_names() else None
        name = engine_style(base)["label"] if engine else str(case)
        labels.append(f"{name}, {variant}" if variant and engine else name)
        engines.append(engine)
    # the same engine under another assumption: its marker hollow, another line style
    for st, (_, g) in zip(series_styles(labels, engines), groups):
        ax.plot(g["run"], 1e3 * g[quantity], **st)
    runs = table.drop_duplicates("run")
    ax.set_xticks(runs["run"])
    ax.set_xticklabels([f"{r}\n{p:g} g" for r, p in zip(runs["run"], runs["pga"])])
    ax.set_xlabel("run (transverse PGA label)")
    ax.set_ylabel("peak deck rotation |θ_d| [mrad]")
    outside_legend(ax)
    return save(fig, path, scene.name, formats)


@reusable
def friction_ratio(
    effect: pd.DataFrame,
    scene: Scene,
    path: str | Path,
    tol: float | None = None,
    formats: tuple[str, ...] = (),
) -> list[Path]:
    """Peak rotation with friction / without, per run and engine (1 = no effect; the band is
    the ±tol within which the report calls the change negligible)."""
    from deckpound.compare.report.style import new_figure, outside_legend, save, series_styles

    tol = TOL if tol is None else tol
    fig, axes = new_figure(1, 1, width=6.5, height=3.0)
    ax = axes[0, 0]
    ax.axhspan(1 - tol, 1 + tol, color="#dddddd", zorder=0)
    ax.axhline(1.0, color="#777777", linewidth=0.8)
    groups = list(effect.groupby("engine", sort=False))
    names = [str(engine) for engine, _ in groups]
    labels = [engine_style(e)["label"] if e in engine_names() else e for e in names]
    engines = [e if e in engine_names() else None for e in names]
    for st, (_, g) in zip(series_styles(labels, engines), groups):
        ax.plot(g["run"], g["ratio"], **st)
    runs = effect.drop_duplicates("run")
    ax.set_xticks(runs["run"])
    ax.set_xticklabels([f"{r}\n{p:g} g" for r, p in zip(runs["run"], runs["pga"])])
    ax.set_xlabel("run (transverse PGA label)")
    mu = effect["mu"].iloc[0] if len(effect) else 0.0
    ax.set_ylabel(f"peak θ_d with μ = {mu:g} / without [-]")
    outside_legend(ax)
    return save(fig, path, scene.name, formats)


@reusable
def friction_mechanism(
    pairs: dict, path: str | Path, title: str = "", formats: tuple[str, ...] = ()
) -> list[Path]:
    """Per engine, a sequence run without and with friction (``pairs``: engine →
    (SequenceRun μ = 0, SequenceRun μ > 0), either order): deck rotation of both (top) and
    the moment of the tangential contact forces about the deck centre with friction
    (bottom, in the report's contact-force unit times metres: :data:`~.render.CONTACT_FORCE`),
    the excursion that reaches the frictional peak shaded. A run with friction is drawn in the
    same style in both panels."""
    from deckpound.compare.report.style import new_figure, outside_legend, save, series_styles

    fig, axes = new_figure(2, 1, width=7.5, height=2.3, sharex=True)
    ordered = {
        engine: sorted(runs, key=lambda r: r.scene.contact.friction)
        for engine, runs in pairs.items()
    }
    series = [(engine, run) for engine, runs in ordered.items() for run in runs]
    labels = [
        f"{engine_style(engine).get('label', engine)}, μ = {run.scene.contact.friction:g}"
        for engine, run in series
    ]
    styles = series_styles(
        labels, [engine for engine, _ in series], points=[len(run.result.t) for _, run in series]
    )
    shaded = False
    for (engine, run), st in zip(series, styles):
        r = run.result
        axes[0, 0].plot(r.t, 1e3 * r["deck_theta"], **st)
        if run is not ordered[engine][-1]:
            continue
        row = mechanism_row(r, run.scene)
        if np.isfinite(row["friction_impulse"]):
            mt, _ = contact_moments(r, run.scene)
            axes[1, 0].plot(r.t, CONTACT_FORCE.scale * mt, **st)
            if not shaded:
                for ax in axes[:, 0]:
                    ax.axvspan(row["t_start"], row["t_peak"], color="#eeeeee", zorder=0)
                shaded = True
    axes[0, 0].set_ylabel("deck rotation θ_d [mrad]")
    outside_legend(axes[0, 0], fontsize=6)
    axes[1, 0].set_ylabel(f"friction moment about\ndeck centre [{CONTACT_FORCE.unit}·m]")
    axes[1, 0].set_xlabel("time [s]")
    outside_legend(axes[1, 0], fontsize=6)
    if title:
        axes[0, 0].set_title(
            f"{title}: shaded, the excursion that reaches the frictional peak", fontsize=8
        )
    scene = next(iter(pairs.values()))[0].scene
    return save(fig, path, scene.name, formats)


@reusable
def study_figure(
    study,
    scene: Scene,
    cases,
    results: dict[str, Result],
    table: pd.DataFrame,
    path: str | Path,
    formats: tuple[str, ...] = (),
    subtitle: str = "",
) -> list[Path]:
    """Left: the study's headline (peak rotation vs parameter); right: rotation histories,
    one per case. A case at an infinite parameter (the rigid limit of the stiffness study) is a
    horizontal line on the left, marked at the other cases' parameters."""
    from deckpound.compare.report.style import new_figure, outside_legend, save, series_styles

    fig, axes = new_figure(1, 2, width=10.0, height=3.2)
    ax = axes[0, 0]
    x = study.x
    if x in ("stiffness", "mu"):
        keys = ["engine"] + (["friction_mode"] if "friction_mode" in table else [])
        series = []  # (label, engine, rows, horizontal line)
        for engine, g in table.groupby(keys, sort=False):
            label = " ".join(engine) if isinstance(engine, tuple) else str(engine)
            finite = np.isfinite(g[x].astype(float))
            if finite.any():
                series.append((label, label.split()[0], g[finite], False))
            for _, row in g[~finite].iterrows():
                series.append((str(row["label"]), label.split()[0], row, True))
        styles = series_styles(
            [s[0] for s in series], [e if e in engine_names() else None for _, e, _, _ in series]
        )
        xs = np.unique(table[x].astype(float))
        xs = xs[np.isfinite(xs)]
        for (_, _, rows, flat), st in zip(series, styles):
            if flat and len(xs):  # marked at the other cases' parameters
                ax.plot(xs, np.full(len(xs), 1e3 * rows["peak_theta"]), **st)
            elif flat:
                ax.axhline(1e3 * rows["peak_theta"], **st)
            else:
                ax.plot(rows[x].astype(float), 1e3 * rows["peak_theta"], **st)
        if x == "stiffness":
            ax.set_xscale("log")
            ax.set_xlabel("contact stiffness [kN/m]")
        else:
            ax.set_xlabel("friction coefficient μ [-]")
    else:
        labels = table["label"].tolist()
        ax.bar(
            range(len(labels)),
            1e3 * table["peak_theta"],
            color="#888888",
            edgecolor="k",
            hatch="//",
        )
        ax.set_xticks(range(len(labels)))
        ax.set_xticklabels(labels, rotation=30, ha="right", fontsize=7)
    ax.set_ylabel("peak deck rotation [mrad]")
    ax.set_title(study.title + (f"\n{subtitle}" if subtitle else ""), fontsize=8)
    outside_legend(ax, fontsize=6)
    ax2 = axes[0, 1]
    styles = series_styles(
        [c.label for c in cases],
        [c.engine for c in cases],
        points=[len(results[c.label].t) for c in cases],
    )
    for c, st in zip(cases, styles):
        r = results[c.label]
        ax2.plot(r.t, 1e3 * r["deck_theta"], **{**st, "linewidth": 0.9})
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("deck rotation [mrad]")
    outside_legend(ax2, fontsize=6)
    return save(fig, path, scene.name, formats)


@reusable
def hysteresis(
    result: Result, scene: Scene, path: str | Path, title: str = "", formats: tuple[str, ...] = ()
) -> list[Path]:
    """Bent force–deformation loops (Takeda springs), x and y, one panel per bent (the result's
    ``<bent>_fx``/``<bent>_dx`` columns: nothing is recomputed from the excitation)."""
    from deckpound.compare.report.style import new_figure, save

    fig, axes = new_figure(2, len(scene.bents), width=3.0 * len(scene.bents), height=2.4)
    for i, b in enumerate(scene.bents):
        for j, axis in enumerate(("x", "y")):
            ax = axes[j, i]
            ax.plot(
                1e3 * result[f"{b.name}_d{axis}"],
                BENT_FORCE.scale * result[f"{b.name}_f{axis}"],
                color="k",
                linewidth=0.7,
            )
            ax.set_title(f"{b.name} {axis}")
            ax.set_xlabel("deformation [mm]")
            ax.set_ylabel(f"bent force [{BENT_FORCE.unit}]")
    if title:
        fig.suptitle(title, fontsize=9)
    return save(fig, path, scene.name, formats)


#: the state columns a plan-view outline of a one-segment deck reads (:func:`outline_columns`):
#: displacements relative to the supports, so the picture shows the gaps and the rotation
#: rather than the ground's translation
OUTLINE_COLUMNS = (
    "deck_x_rel",
    "deck_y_rel",
    "deck_theta",
    "seat1_x_rel",
    "seat1_theta",
    "seat2_x_rel",
    "seat2_theta",
)


def outline_columns(plan) -> tuple[str, ...]:
    """The state columns :func:`outlines` reads for ``plan``: each deck segment's x, y
    relative to its tables and θ, then the seats' (:data:`OUTLINE_COLUMNS` for one segment)."""
    bodies = tuple(f"{seg.name}_{q}" for seg in plan.segments for q in ("x_rel", "y_rel", "theta"))
    return bodies + OUTLINE_COLUMNS[3:]


def rotation_columns(plan) -> tuple[str, ...]:
    """The deck rotation columns of ``plan``: ``deck_theta``, or each segment's θ."""
    return tuple(f"{seg.name}_theta" for seg in plan.segments)


def _face_points(points: list, hw: float) -> list:
    """The two points of an end face (y ascending) moved along the face to y = ∓hw, the
    segment's own half width: a joint between segments of different widths has its corners
    where the faces overlap, not at the wider segment's corners [m]."""
    (x1, y1), (x2, y2) = points
    if y1 == -hw and y2 == hw:
        return points
    slope = (x2 - x1) / (y2 - y1)
    return [(x1 + (-hw - y1) * slope, -hw), (x1 + (hw - y1) * slope, hw)]


def _segment_box(plan, seg) -> np.ndarray:
    """A segment's outline at rest in its own frame (closed polygon, metres): its left face
    corners, then its right face points (the facing points of the next joint's corners, or the
    corners at seat 2), each face at the segment's own width (:func:`_face_points`)."""
    mine = [c for c in plan.corners if c.body == seg.index]
    left = [c for c in mine if c.seat == 0 or c.joint >= 0]
    right = [c for c in mine if c.seat == 1]
    if right:
        rpts = [(c.x, c.y) for c in right]
    else:  # the next joint's corners strike this segment's right face at their levers
        nxt = [c for c in plan.corners if c.joint >= 0 and c.facing_dofs == seg.dofs]
        rpts = [c.lever for c in nxt]
    hw = seg.half_width
    (l1, l2), (r1, r2) = _face_points([(c.x, c.y) for c in left], hw), _face_points(rpts, hw)
    return np.array([l1, r1, r2, l2, l1])


def outlines(scene: Scene, row: dict[str, float], scale: float) -> dict[str, np.ndarray]:
    """Deck (or segment) and seat outlines (closed polygons, metres) at one state,
    displacements × scale.

    Each deck segment is its corner polygon (a parallelogram for a skewed deck) moved by its
    displacement relative to the shake tables and placed at its centre; each seat is a block
    behind its contact face (the facing points of its two corners, g₀ behind the deck end
    along the normal), moved by its displacement relative to its actuator and rotated about
    its pivot.
    """
    plan = plan_of(scene)
    out = {}
    positions = plan.segment_positions()
    for seg in plan.segments:
        th = scale * row[f"{seg.name}_theta"]
        c, s = np.cos(th), np.sin(th)
        box = _segment_box(plan, seg)
        x0, y0 = positions[seg.index]
        out[seg.name] = np.column_stack(
            [
                x0 + scale * row[f"{seg.name}_x_rel"] + c * box[:, 0] - s * box[:, 1],
                y0 + scale * row[f"{seg.name}_y_rel"] + s * box[:, 0] + c * box[:, 1],
            ]
        )
    k = {cn.name: cn for cn in plan.corners}
    depth, overhang = 0.6, 0.3
    for j in (1, 2):
        a, b = (k["c1"], k["c2"]) if j == 1 else (k["c3"], k["c4"])
        centre = np.array(positions[a.body])
        n, t = np.array(a.normal), np.array(a.tangent)
        fa = np.array([a.x, a.y]) + centre - a.gap * n - overhang * t
        fb = np.array([b.x, b.y]) + centre - b.gap * n + overhang * t
        seat = np.array([fa, fb, fb - depth * n, fa - depth * n, fa])
        pivot = 0.5 * (np.array([a.x, a.y]) + np.array([b.x, b.y])) + centre - a.gap * n
        ts = scale * row[f"seat{j}_theta"]
        cs, ss = np.cos(ts), np.sin(ts)
        rel = seat - pivot
        out[f"seat{j}"] = np.column_stack(
            [
                pivot[0] + scale * row[f"seat{j}_x_rel"] + cs * rel[:, 0] - ss * rel[:, 1],
                pivot[1] + ss * rel[:, 0] + cs * rel[:, 1],
            ]
        )
    return out


#: displacement magnification of the plan view
PLAN_SCALE = 100.0


@reusable
def plan_snapshot(
    results: dict[str, Result],
    scene: Scene,
    path: str | Path,
    scale: float = PLAN_SCALE,
    formats: tuple[str, ...] = (),
) -> list[Path]:
    """Plan view of deck and seats at each engine's peak rotation (displacements × scale): the
    output row of the largest |θ_d| (for a deck of segments: of the segment that turns most;
    the drawn state is a stored row; the title gives its time and rotation, which the
    every-step peak :meth:`Result.peak` may exceed between rows)."""
    from deckpound.compare.report.style import new_figure, save

    plan = plan_of(scene)
    rotations = rotation_columns(plan)
    fig, axes = new_figure(len(results), 1, width=8.0, height=2.0)
    for i, (label, r) in enumerate(results.items()):
        theta = max(rotations, key=lambda q: float(np.max(np.abs(r[q]))))
        k = int(np.argmax(np.abs(r[theta])))
        row = {q: r[q][k] for q in outline_columns(plan)}
        ax = axes[i, 0]
        rest = outlines(scene, dict.fromkeys(row, 0.0), 1.0)
        for poly in rest.values():
            ax.plot(poly[:, 0], poly[:, 1], color="#bbbbbb", linewidth=0.8, linestyle="--")
        for name, poly in outlines(scene, row, scale).items():
            ax.fill(
                poly[:, 0],
                poly[:, 1],
                facecolor="#888888" if name.startswith("seat") else "#dddddd",
                edgecolor="k",
                linewidth=1.0,
                alpha=0.8,
            )
        ax.set_aspect("equal")
        which = "θ_d" if theta == "deck_theta" else f"θ {theta[: -len('_theta')]}"
        ax.set_title(
            f"{label}: t = {r.t[k]:.2f} s, {which} = {1e3 * row[theta]:.2f} mrad "
            f"(displacements relative to the supports × {scale:g})"
        )
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    return save(fig, path, scene.name, formats)

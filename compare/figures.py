"""Paper-style figures of results (matplotlib; PNG and PDF; one style, greyscale-readable)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.engines import engine_names
from deckpound.models.plan import plan_of
from deckpound.models.result import Result
from deckpound.models.scene import Scene

from .style import CYCLE, engine_style, new_figure, save

FORMATS = ("pdf",)
LABELS = {
    "deck_theta": ("deck rotation θ_d", 1e3, "mrad"),
    "deck_y_rel": ("deck transverse y_d rel. tables", 1e3, "mm"),
    "deck_x_rel": ("deck longitudinal x_d rel. tables", 1e3, "mm"),
}


def _style_for(label: str, k: int) -> dict:
    engine = label.split()[0]
    st = engine_style(engine)
    if engine not in engine_names() and engine != "measured":
        st = dict(CYCLE[k % len(CYCLE)])
        st.pop("marker", None)
        st.pop("markersize", None)
    st["label"] = label
    return st


def histories(results: dict[str, Result], scene: Scene, path: str | Path,
              quantities: tuple[str, ...] = ("deck_theta", "deck_y_rel"), title: str = "") -> list[Path]:
    """Time histories of quantities overlaid per engine/case (paper Figs. 4–6 style)."""
    fig, axes = new_figure(len(quantities), 1, width=7.5, height=2.2, sharex=True)
    for i, q in enumerate(quantities):
        name, scale, unit = LABELS.get(q, (q, 1.0, ""))
        ax = axes[i, 0]
        for k, (label, r) in enumerate(results.items()):
            if q in r.columns:
                ax.plot(r.t, scale * r[q], **_style_for(label, k))
        ax.set_ylabel(f"{name} [{unit}]")
    axes[0, 0].legend(loc="upper right", ncol=min(3, len(results)))
    if title:
        axes[0, 0].set_title(title)
    axes[-1, 0].set_xlabel("time [s]")
    return save(fig, path, scene.name, FORMATS)


def contact_forces(results: dict[str, Result], scene: Scene, path: str | Path,
                   title: str = "") -> list[Path]:
    """Normal contact force per corner (c1, c2 at seat 1; c3, c4 at seat 2)."""
    fig, axes = new_figure(2, 2, width=8.0, height=2.0, sharex=True)
    for c in range(4):
        ax = axes[c % 2, c // 2]
        for k, (label, r) in enumerate(results.items()):
            ax.plot(r.t, 1e-3 * r[f"fn_c{c + 1}"], **_style_for(label, k))
        ax.set_title(f"corner c{c + 1} (seat {1 + c // 2})")
        ax.set_ylabel("normal force [MN]")
    axes[-1, 0].set_xlabel("time [s]")
    axes[-1, 1].set_xlabel("time [s]")
    axes[0, 0].legend(loc="upper right", fontsize=7)
    if title:
        fig.suptitle(title, fontsize=9)
    return save(fig, path, scene.name, FORMATS)


def peak_vs_pga(table: pd.DataFrame, scene: Scene, path: str | Path,
                quantity: str = "peak_theta") -> list[Path]:
    """Peak deck rotation vs run PGA over the sequence, one line per engine (paper Fig. 7)."""
    fig, axes = new_figure(1, 1, width=5.5, height=3.2)
    ax = axes[0, 0]
    markers = {e: CYCLE[k % len(CYCLE)]["marker"] for k, e in enumerate(engine_names())}
    for engine, g in table.groupby("engine", sort=False):
        base, _, variant = engine.partition(" ")
        st = engine_style(base)
        if variant:  # the same engine under another assumption: hollow markers, thinner line
            st.update(label=f"{st['label']}, {variant}", markerfacecolor="white",
                      linewidth=0.9)
        ax.plot(g["run"], 1e3 * g[quantity], marker=markers.get(base, "x"), **st)
    runs = table.drop_duplicates("run")
    ax.set_xticks(runs["run"])
    ax.set_xticklabels([f"{r}\n{p:g} g" for r, p in zip(runs["run"], runs["pga"])])
    ax.set_xlabel("run (transverse PGA)")
    ax.set_ylabel("peak deck rotation [mrad]")
    ax.legend()
    return save(fig, path, scene.name, FORMATS)


def study_figure(study, scene: Scene, cases, results: dict[str, Result], table: pd.DataFrame,
                 path: str | Path) -> list[Path]:
    """Left: the study's headline (peak rotation vs parameter); right: rotation histories."""
    fig, axes = new_figure(1, 2, width=9.0, height=3.2)
    ax = axes[0, 0]
    x = study.x
    if x in ("stiffness", "mu"):
        for k, (engine, g) in enumerate(table.groupby(["engine"] + (["friction_mode"] if "friction_mode" in table else []), sort=False)):
            label = " ".join(engine) if isinstance(engine, tuple) else engine
            finite = g[np.isfinite(g[x].astype(float))]
            eng = label.split()[0]
            st = engine_style(eng)
            st["label"] = label
            if len(finite):
                ax.plot(finite[x].astype(float), 1e3 * finite["peak_theta"],
                        marker=CYCLE[k % len(CYCLE)]["marker"], **st)
            inf = g[~np.isfinite(g[x].astype(float))]
            for _, row in inf.iterrows():
                ax.axhline(1e3 * row["peak_theta"], **{**st, "label": f"{row['label']}"})
        if x == "stiffness":
            ax.set_xscale("log")
            ax.set_xlabel("contact stiffness [kN/m]")
        else:
            ax.set_xlabel("friction coefficient μ [-]")
    else:
        labels = table["label"].tolist()
        ax.bar(range(len(labels)), 1e3 * table["peak_theta"], color="#888888", edgecolor="k",
               hatch="//")
        ax.set_xticks(range(len(labels)))
        ax.set_xticklabels(labels, rotation=30, ha="right", fontsize=7)
    ax.set_ylabel("peak deck rotation [mrad]")
    ax.set_title(study.title)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
    ax2 = axes[0, 1]
    for k, c in enumerate(cases):
        r = results[c.label]
        st = dict(CYCLE[k % len(CYCLE)])
        st.pop("marker")
        st.pop("markersize")
        ax2.plot(r.t, 1e3 * r["deck_theta"], label=c.label, linewidth=0.9, **st)
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("deck rotation [mrad]")
    ax2.legend(fontsize=6, ncol=2)
    return save(fig, path, scene.name, FORMATS)


def hysteresis(result: Result, scene: Scene, path: str | Path, title: str = "") -> list[Path]:
    """Bent force–deformation loops (Takeda springs), x and y, one panel per bent (the result's
    ``<bent>_fx``/``<bent>_dx`` columns: nothing is recomputed from the excitation)."""
    fig, axes = new_figure(2, len(scene.bents), width=3.0 * len(scene.bents), height=2.4)
    for i, b in enumerate(scene.bents):
        for j, axis in enumerate(("x", "y")):
            ax = axes[j, i]
            ax.plot(1e3 * result[f"{b.name}_d{axis}"], result[f"{b.name}_f{axis}"], color="k",
                    linewidth=0.7)
            ax.set_title(f"{b.name} {axis}")
            ax.set_xlabel("deformation [mm]")
            ax.set_ylabel("force [kN]")
    if title:
        fig.suptitle(title, fontsize=9)
    return save(fig, path, scene.name, FORMATS)


#: the state columns a plan-view outline reads: displacements relative to the supports, so the
#: picture shows the gaps and the rotation rather than the ground's translation
OUTLINE_COLUMNS = ("deck_x_rel", "deck_y_rel", "deck_theta", "seat1_x_rel", "seat1_theta",
                   "seat2_x_rel", "seat2_theta")


def outlines(scene: Scene, row: dict[str, float], scale: float) -> dict[str, np.ndarray]:
    """Deck and seat outlines (closed polygons, metres) at one state, displacements × scale.

    The deck is the plan model's corner polygon (a parallelogram for a skewed deck) moved by
    its displacement relative to the shake tables; each seat is a block behind its contact face
    (the facing points of its two corners, g₀ behind the deck end along the normal), moved by
    its displacement relative to its actuator and rotated about its pivot.
    """
    plan = plan_of(scene)
    th = scale * row["deck_theta"]
    c, s = np.cos(th), np.sin(th)
    k = {cn.name: cn for cn in plan.corners}
    box = np.array([[k[n].x, k[n].y] for n in ("c1", "c3", "c4", "c2", "c1")])
    deck = np.column_stack([scale * row["deck_x_rel"] + c * box[:, 0] - s * box[:, 1],
                            scale * row["deck_y_rel"] + s * box[:, 0] + c * box[:, 1]])
    out = {"deck": deck}
    depth, overhang = 0.6, 0.3
    for j in (1, 2):
        a, b = (k["c1"], k["c2"]) if j == 1 else (k["c3"], k["c4"])
        n, t = np.array(a.normal), np.array(a.tangent)
        fa = np.array([a.x, a.y]) - a.gap * n - overhang * t
        fb = np.array([b.x, b.y]) - b.gap * n + overhang * t
        seat = np.array([fa, fb, fb - depth * n, fa - depth * n, fa])
        pivot = 0.5 * (np.array([a.x, a.y]) + np.array([b.x, b.y])) - a.gap * n
        ts = scale * row[f"seat{j}_theta"]
        cs, ss = np.cos(ts), np.sin(ts)
        rel = seat - pivot
        out[f"seat{j}"] = np.column_stack([
            pivot[0] + scale * row[f"seat{j}_x_rel"] + cs * rel[:, 0] - ss * rel[:, 1],
            pivot[1] + ss * rel[:, 0] + cs * rel[:, 1]])
    return out


def plan_snapshot(results: dict[str, Result], scene: Scene, path: str | Path,
                  scale: float = 100.0) -> list[Path]:
    """Plan view of deck and seats at each engine's peak rotation (displacements × scale)."""
    fig, axes = new_figure(len(results), 1, width=8.0, height=2.0)
    for i, (label, r) in enumerate(results.items()):
        k = int(np.argmax(np.abs(r["deck_theta"])))
        row = {q: r[q][k] for q in OUTLINE_COLUMNS}
        ax = axes[i, 0]
        rest = outlines(scene, {q: 0.0 for q in row}, 1.0)
        for name, poly in rest.items():
            ax.plot(poly[:, 0], poly[:, 1], color="#bbbbbb", linewidth=0.8, linestyle="--")
        for name, poly in outlines(scene, row, scale).items():
            ax.fill(poly[:, 0], poly[:, 1], facecolor="#dddddd" if name == "deck" else "#888888",
                    edgecolor="k", linewidth=1.0, alpha=0.8)
        ax.set_aspect("equal")
        ax.set_title(f"{label}: t = {r.t[k]:.2f} s, θ_d = {1e3 * row['deck_theta']:.2f} mrad "
                     f"(displacements relative to the supports × {scale:g})")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    return save(fig, path, scene.name, FORMATS)

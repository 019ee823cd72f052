"""One figure style for every deckpound plot: readable in greyscale, units on every axis.

Every series of a figure (an engine, a case, an engine under another assumption) is told apart
by its line style *and* its marker, not by colour alone (:func:`series_styles`: no two series of
a figure share a (line style, marker) pair), so a greyscale print keeps them distinct; an
engine's colour, line style, width and label come from the registry
(:func:`deckpound.compare.engines.engine_style`) and its marker from its place in it, so an
engine looks the same in every figure. Markers on a dense line (a time history) are spaced
evenly along its points (``markevery``), so the line stays readable. Legends stand beside the data, never on
it (:func:`outside_legend`). Every figure is saved atomically
(:func:`deckpound.models.file_io.atomic_path`), and text that may carry user strings (the
scene-name stamp, titles, axis labels, legends) is drawn literally, without mathtext: a scene
named ``$\\frac{$`` must not break a figure.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from deckpound.compare.engines import engine_names, engine_style
from deckpound.models.file_io import atomic_path

#: colours of series that are not an engine, in the order they receive them
COLORS = ("#000000", "#1f5fa8", "#c0392b", "#27ae60", "#7f7f7f", "#8e44ad")
#: the line styles of :func:`series_styles` (named ones: matplotlib reports them as given)
LINESTYLES = ("-", "--", ":", "-.")
#: markers that stay apart in greyscale; an engine's is the one at its place in the registry
MARKERS = ("o", "s", "^", "D", "v", "x", "P", "<", ">", "h", "*", "d")
#: the marker of measured data (not an engine of the registry)
MEASURED_MARKER = "*"
#: marker size [pt]
MARKERSIZE = 4.0
#: markers along a dense line of a figure of up to four lines; more lines carry fewer each, at
#: least MIN_MARKS
MARKS_PER_LINE = 12
MIN_MARKS = 5

#: colour, line style and marker by position, for figures outside the report (the benchmark
#: plots of :mod:`deckpound.compare.bench`); the report's figures use :func:`series_styles`
CYCLE = [
    {"color": c, "linestyle": s, "marker": m, "markersize": MARKERSIZE}
    for c, s, m in zip(COLORS, LINESTYLES + ((0, (5, 1)), (0, (3, 1, 1, 1))), MARKERS)
]

RC = {
    "figure.dpi": 110,
    "savefig.dpi": 150,
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "lines.linewidth": 1.2,
}


def new_figure(
    nrows: int = 1, ncols: int = 1, *, width: float = 7.0, height: float = 2.2, **kwargs
):
    """A figure in the deckpound style (height per row in inches)."""
    with plt.rc_context(RC):
        fig, axes = plt.subplots(
            nrows, ncols, figsize=(width, height * nrows), squeeze=False, **kwargs
        )
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
    return fig, axes


def engine_of(label: str) -> str | None:
    """The engine a series label names by its first word (``"compliance mu=0.2"``), or
    ``"measured"``; None for a label that names neither."""
    first = str(label).split(" ", 1)[0].rstrip(",")
    return first if first in engine_names() or first == "measured" else None


def engine_marker(engine: str) -> str:
    """An engine's marker: the one at its place in the registry (the same in every figure)."""
    if engine == "measured":
        return MEASURED_MARKER
    names = engine_names()
    return MARKERS[names.index(engine) % len(MARKERS)] if engine in names else MARKERS[-1]


def series_styles(
    labels: Sequence[str],
    engines: Sequence[str | None] | None = None,
    *,
    points: int | Sequence[int] | None = None,
) -> list[dict[str, Any]]:
    """Line keyword arguments for the series of one figure (one per label, in order), no two
    with the same (line style, marker) pair.

    ``engines`` names the engine each series was computed with (default :func:`engine_of` of
    its label; None for a series that is no engine's). The first series of an engine takes
    the registry's colour, line style and width (:func:`~deckpound.compare.engines.engine_style`)
    and the engine's marker (:func:`engine_marker`); a further series of the same engine (the
    engine under another assumption) keeps its colour and marker, drawn hollow, and takes a
    line style no series of the figure has yet, or else the first that keeps the pair free.
    Other series take colour, line style and marker by position. A pair taken already moves
    the marker on. ``points``: the number of points of each series (one number for all) when
    they are dense lines (time histories): about :data:`MARKS_PER_LINE` markers per line,
    evenly spaced over its points (``markevery``; fewer per line when a figure has more than
    four, at least :data:`MIN_MARKS`; evenly in time, where a spacing along the drawn path
    would crowd them on impact spikes), each series offset so that coinciding lines do not
    hide each other's markers. None: every point carries a marker.
    """
    labels = [str(label) for label in labels]
    if engines is None:
        engines = [engine_of(label) for label in labels]
    if len(engines) != len(labels):
        raise ValueError(f"{len(labels)} labels but {len(engines)} engines")
    styles: list[dict[str, Any] | None] = [None] * len(labels)
    pairs: set[tuple[Any, str]] = set()
    used_lines: set[Any] = set()

    owned = {engine_marker(e) for e in engines if e is not None}

    def take(i: int, base: dict[str, Any], lines: Sequence[Any], marker: str) -> None:
        """Give series i the first free pair: its line styles in order, then later markers
        (first those no engine of the figure owns)."""
        start = MARKERS.index(marker) if marker in MARKERS else 0
        later = [MARKERS[(start + j) % len(MARKERS)] for j in range(1, len(MARKERS))]
        markers = [marker] + [m for m in later if m not in owned] + [m for m in later if m in owned]
        for m in markers:
            for ls in lines:
                if (ls, m) not in pairs:
                    pairs.add((ls, m))
                    used_lines.add(ls)
                    styles[i] = {**base, "linestyle": ls, "marker": m}
                    return
        raise ValueError(f"more than {len(LINESTYLES) * len(MARKERS)} series in one figure")

    # the first series of each engine: the registry's style, so an engine looks alike everywhere
    first: dict[str, int] = {}
    for i, engine in enumerate(engines):
        if engine is not None and engine not in first:
            first[engine] = i
            st = engine_style(engine)
            st.pop("label", None)
            own = st.pop("linestyle", "-")
            take(i, st, [own, *LINESTYLES], engine_marker(engine))
    others = 0
    for i, engine in enumerate(engines):
        if styles[i] is not None:
            continue
        if engine is not None:
            st = engine_style(engine)
            st.pop("label", None)
            st.pop("linestyle", None)
            st["markerfacecolor"] = "white"
            fresh = [ls for ls in LINESTYLES if ls not in used_lines]
            take(i, st, fresh + list(LINESTYLES), engine_marker(engine))
        else:
            k = others
            others += 1
            lines = LINESTYLES[k % len(LINESTYLES) :] + LINESTYLES[: k % len(LINESTYLES)]
            take(i, {"color": COLORS[k % len(COLORS)]}, lines, MARKERS[k % len(MARKERS)])
    if points is not None and not isinstance(points, Sequence):
        points = [int(points)] * len(labels)
    if points is not None and len(points) != len(labels):
        raise ValueError(f"{len(labels)} labels but {len(points)} point counts")
    # many dense lines: fewer markers each, so the lines stay readable
    marks = max(MIN_MARKS, round(MARKS_PER_LINE * min(1.0, 4 / max(len(labels), 1))))
    out = []
    for i, (label, st) in enumerate(zip(labels, styles)):
        st = {**st, "markersize": MARKERSIZE, "label": label}
        if points is not None:
            step = max(1, int(points[i]) // marks)
            st["markevery"] = ((step * i) // len(labels), step)
        out.append(st)
    return out


def outside_legend(ax, *, fontsize: float = 7, ncol: int = 1, title: str | None = None):
    """The legend of ``ax``'s labelled artists beside its data area, never on it: its upper
    left corner at the axes' upper right corner (the layout of :func:`save` makes room for
    it). Returns the legend, or None when nothing is labelled."""
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return None
    return ax.legend(
        handles,
        labels,
        loc="upper left",
        bbox_to_anchor=(1.02, 1.0),
        borderaxespad=0.0,
        frameon=False,
        fontsize=fontsize,
        ncol=ncol,
        title=title,
        title_fontsize=fontsize,
    )


def stamp_text(name: str, limit: int = 80) -> str:
    """A scene name as one printable line for a figure: control characters shown as ``?``,
    cut to ``limit`` characters (a longer stamp would not fit the figure)."""
    text = "".join(c if c.isprintable() else "?" for c in str(name))
    return text if len(text) <= limit else text[: limit - 1] + "…"


def literal_text(fig) -> None:
    """Draw the figure's user-facing text literally (no mathtext): figure texts, titles, axis
    labels and legend entries. Tick labels keep mathtext (log-axis exponents use it)."""
    texts = list(fig.texts)
    if getattr(fig, "_suptitle", None) is not None:
        texts.append(fig._suptitle)
    for ax in fig.axes:
        texts += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label]
        legend = ax.get_legend()
        if legend is not None:
            texts += list(legend.get_texts())
            if legend.get_title() is not None:
                texts.append(legend.get_title())
    for t in texts:
        t.set_parse_math(False)


def save(fig, path: str | Path, scene_name: str, formats: tuple[str, ...] = ()) -> list[Path]:
    """Stamp the scene name, save to ``path`` (and the other ``formats``) atomically, close the
    figure (also when saving fails)."""
    path = Path(path)
    try:
        fig.text(
            0.995,
            0.005,
            f"scene: {stamp_text(scene_name)}",
            ha="right",
            va="bottom",
            fontsize=7,
            color="#555555",
            parse_math=False,
        )
        literal_text(fig)
        fig.tight_layout(rect=(0, 0.02, 1, 1))
        written = []
        for p in [path] + [path.with_suffix(f".{f}") for f in formats if f".{f}" != path.suffix]:
            with plt.rc_context(RC), atomic_path(p) as tmp:
                fig.savefig(tmp, format=p.suffix[1:].lower() or None)
            written.append(p)
    finally:
        plt.close(fig)
    return written

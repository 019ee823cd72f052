"""One figure style for every deckpound plot: readable in greyscale, units on every axis.

Engines are told apart by line style and grey level as well as colour, so a greyscale print
keeps them distinct. Every figure is saved atomically (:func:`deckpound.models.file_io.atomic_path`), and
text that may carry user strings (the scene-name stamp, titles, axis labels, legends) is drawn
literally, without mathtext: a scene named ``$\\frac{$`` must not break a figure.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from deckpound.models.file_io import atomic_path

CYCLE = [
    {"color": c, "linestyle": s, "marker": m, "markersize": 4}
    for c, s, m in (
        ("#000000", "-", "o"),
        ("#1f5fa8", "--", "s"),
        ("#c0392b", ":", "^"),
        ("#27ae60", "-.", "D"),
        ("#7f7f7f", (0, (5, 1)), "v"),
        ("#8e44ad", (0, (3, 1, 1, 1)), "x"),
    )
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

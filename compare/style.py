"""One figure style for every deckpound plot: readable in greyscale, units on every axis.

Engines are told apart by line style and grey level as well as colour, so a greyscale print
keeps them distinct.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

CYCLE = [dict(color=c, linestyle=s, marker=m, markersize=4)
         for c, s, m in (("#000000", "-", "o"), ("#1f5fa8", "--", "s"), ("#c0392b", ":", "^"),
                         ("#27ae60", "-.", "D"), ("#7f7f7f", (0, (5, 1)), "v"),
                         ("#8e44ad", (0, (3, 1, 1, 1)), "x"))]

RC = {
    "figure.dpi": 110, "savefig.dpi": 150, "font.size": 9, "axes.titlesize": 9,
    "axes.labelsize": 9, "legend.fontsize": 8, "axes.grid": True, "grid.alpha": 0.3,
    "axes.spines.top": False, "axes.spines.right": False, "lines.linewidth": 1.2,
}


def engine_style(engine: str) -> dict:
    """Line style of an engine, declared by the engine itself (:mod:`deckpound.engines`);
    ``measured`` and unknown labels get neutral styles."""
    from deckpound.engines import engine_style as _registry_style

    return _registry_style(engine)


def new_figure(nrows: int = 1, ncols: int = 1, *, width: float = 7.0, height: float = 2.2,
               **kwargs):
    """A figure in the deckpound style (height per row in inches)."""
    with plt.rc_context(RC):
        fig, axes = plt.subplots(nrows, ncols, figsize=(width, height * nrows), squeeze=False,
                                 **kwargs)
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
    return fig, axes


def save(fig, path: str | Path, scene_name: str, formats: tuple[str, ...] = ()) -> list[Path]:
    """Stamp the scene name, save to ``path`` (and the other ``formats``), close the figure."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.text(0.995, 0.005, f"scene: {scene_name}", ha="right", va="bottom", fontsize=7,
             color="#555555")
    fig.tight_layout(rect=(0, 0.02, 1, 1))
    written = []
    for p in [path] + [path.with_suffix(f".{f}") for f in formats if f".{f}" != path.suffix]:
        with plt.rc_context(RC):
            fig.savefig(p)
        written.append(p)
    plt.close(fig)
    return written

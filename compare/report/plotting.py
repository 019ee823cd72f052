"""Figures of inputs: the multi-support excitation."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from deckpound.compare.report.style import new_figure, outside_legend, save, series_styles
from deckpound.models.motion import G, SupportMotion
from deckpound.models.scene import Scene


def plot_excitation(scene: Scene, motion: SupportMotion, path: str | Path) -> list[Path]:
    """Displacement, velocity and acceleration of every support channel (x and y columns)."""
    fig, axes = new_figure(3, 2, width=8.0, height=2.0, sharex=True)
    for col, axis in enumerate(("x", "y")):
        channels = [c for c in motion.channels if c.endswith(f"_{axis}")]
        styles = series_styles(channels, [None] * len(channels), points=len(motion.t))
        for ch, st in zip(channels, styles):
            axes[0, col].plot(motion.t, 1e3 * motion.disp[ch], **st)
            axes[1, col].plot(motion.t, motion.vel[ch], **{**st, "label": "_nolegend_"})
            axes[2, col].plot(motion.t, motion.acc(ch) / G, **{**st, "label": "_nolegend_"})
        pga = max(np.max(np.abs(motion.acc(c))) for c in channels) / G
        axes[0, col].set_title(
            f"{'longitudinal x' if axis == 'x' else 'transverse y'} (PGA {pga:.3g} g)"
        )
        outside_legend(axes[0, col])
        axes[0, col].set_ylabel("displacement [mm]")
        axes[1, col].set_ylabel("velocity [m/s]")
        axes[2, col].set_ylabel("acceleration [g]")
        axes[2, col].set_xlabel("time [s]")
    return save(fig, path, scene.name)

"""Small scene builders shared by tests."""

from __future__ import annotations

from deckpound.models.scene_io import load_scene


def short_benchmark(duration: float, *overrides: str):
    """The benchmark with a ``duration``-second synthetic record (same PGA), plus overrides."""
    return load_scene("saiidi-4span", [f"excitation.duration={duration!r}", *overrides])

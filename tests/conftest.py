"""Shared fixtures: the benchmark scene and short variants of it."""

from __future__ import annotations

import pytest

from deckpound.models.scene_io import load_scene


@pytest.fixture(scope="session")
def bench_scene():
    """The built-in benchmark scene, unchanged."""
    return load_scene("saiidi-4span")


def short_scene(duration: float = 2.0, *overrides: str):
    """The benchmark shortened to ``duration`` seconds of record, with extra overrides."""
    return load_scene("saiidi-4span", [f"excitation.duration={duration}", *overrides])

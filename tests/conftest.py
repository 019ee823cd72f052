"""Shared fixtures: the benchmark scene and short variants of it."""

from __future__ import annotations

import pytest

from deckpound.models.scene_io import load_scene


@pytest.fixture(scope="session")
def bench_scene():
    """The built-in benchmark scene, unchanged."""
    return load_scene("saiidi-4span")

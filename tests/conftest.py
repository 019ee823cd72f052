"""Shared fixtures: the benchmark scene and short variants of it."""

from __future__ import annotations

import signal

import pytest

from deckpound.models.scene_io import load_scene


@pytest.fixture(scope="session")
def bench_scene():
    """The built-in benchmark scene, unchanged."""
    return load_scene("saiidi-4span")


def pytest_configure(config):
    """The Ctrl-C tests send SIGINT as a terminal does. A suite started as a background job
    (``nohup``, ``cmd &`` in a script) inherits SIGINT *ignored*, and so would every process it
    starts: restore Python's handler (children then start with the default disposition)."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)

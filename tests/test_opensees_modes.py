"""Natural modes of the contact-free OpenSees model vs deckpound.models.mechanics."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest

pytest.importorskip("openseespy.opensees")

from deckpound.models import mechanics
from deckpound.models.scene_io import load_scene
from deckpound.opensees_build.modes import opensees_modes


@pytest.fixture(scope="module")
def bench():
    return load_scene("saiidi-4span")


def test_rigid_modes_equal_the_7dof_model(bench):
    ref = mechanics.natural_modes(bench)
    m = opensees_modes(bench)
    np.testing.assert_allclose(m.periods, ref.periods, rtol=1e-8)
    for k in range(3):  # deck modes: distinct frequencies, shapes equal up to sign
        # (the seat modes come in equal-frequency pairs: any combination is a valid shape)
        a, b = m.shapes[:, k], ref.shapes[:, k]
        assert min(np.abs(a - b).max(), np.abs(a + b).max()) < 1e-6 * np.abs(b).max()


def test_stick_modes_close_to_rigid(bench):
    ref = mechanics.natural_modes(bench)
    m = opensees_modes(bench.replace(opensees=dc.replace(bench.opensees, mode="stick")))
    # the near-rigid sticks lengthen the periods slightly, never shorten them
    assert np.all(m.periods >= ref.periods * (1 - 1e-9))
    np.testing.assert_allclose(m.periods, ref.periods, rtol=2e-3)

"""Modes named by their kinetic-energy shares (issue 32, item 3): deck x, y, θ and the seats."""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.cli import main
from deckpound.models import mechanics, plan
from deckpound.models.scene_io import load_scene

GROUP = {key: i for i, (key, _, _) in enumerate(mechanics.ENERGY_GROUPS)}


@pytest.fixture(scope="module")
def bench():
    return load_scene("saiidi-4span")


def _shares(scene):
    modes = mechanics.natural_modes(scene)
    return modes, mechanics.energy_shares(modes.shapes, np.diag(mechanics.mass_matrix(scene)))


def test_benchmark_mode_1_is_torsional(bench):
    modes, shares = _shares(bench)
    np.testing.assert_allclose(shares.sum(axis=0), 1.0, rtol=0, atol=1e-12)
    assert np.all(shares >= 0)
    # mode 1 (0.611 s): its largest shape entry is deck y [m], but most of its energy is θ
    assert abs(modes.periods[0] - 0.611) < 1e-3
    assert int(np.argmax(np.abs(modes.shapes[:, 0]))) == plan.DECK_Y
    assert 0.6 < shares[GROUP["deck_theta"], 0] < 0.75
    assert 0.25 < shares[GROUP["deck_y"], 0] < 0.4
    label = mechanics.mode_label(shares[:, 0])
    theta, y = 100 * shares[GROUP["deck_theta"], 0], 100 * shares[GROUP["deck_y"], 0]
    assert label == f"deck θ (torsion) {theta:.0f} %, deck y {y:.0f} %"
    # the seats' modes are the seats'
    assert all(shares[GROUP["seats"], k] > 0.99 for k in range(3, 7))


def test_symmetric_bridge_has_pure_translation_and_torsion(bench):
    """Equal bents placed symmetrically about mid-span (7.3, 16.75, 26.2 m on a 33.5 m deck):
    transverse translation and torsion uncouple, each mode is one part alone."""
    equal = load_scene("saiidi-4span", ["bents[1].y.stiffness=7000", "bents[2].y.stiffness=7000"])
    _, shares = _shares(equal)
    labels = [mechanics.mode_label(shares[:, k]) for k in range(shares.shape[1])]
    assert "deck y 100 %" in labels
    assert "deck θ (torsion) 100 %" in labels
    k = labels.index("deck y 100 %")
    assert shares[GROUP["deck_y"], k] > 1 - 1e-9
    # the asymmetric benchmark has no pure transverse mode: the same check can fail
    _, coupled = _shares(bench)
    assert not any(coupled[GROUP["deck_y"], j] > 0.99 for j in range(coupled.shape[1]))


def test_shares_by_hand():
    """Σ M_ii φ_i² per part over φᵀMφ, with the inertia making a small rotation dominant."""
    masses = np.array([2.0, 0.5, 2.0, 0.5, 100.0, 100.0, 10_000.0])
    phi = np.zeros((7, 1))
    phi[plan.DECK_Y, 0] = 0.1  # m: energy 100 · 0.01 = 1
    phi[plan.DECK_THETA, 0] = 0.02  # rad: energy 10 000 · 4e-4 = 4
    phi[plan.SEAT_X[0], 0] = 0.0  # seats at rest
    shares = mechanics.energy_shares(phi, masses)[:, 0]
    np.testing.assert_allclose(shares, [0.0, 0.2, 0.8, 0.0], rtol=1e-14)
    assert mechanics.mode_label(shares) == "deck θ (torsion) 80 %, deck y 20 %"
    # a share below 5 % is left out of the name; the dominant one never is
    phi[plan.DECK_Y, 0] = 0.01
    assert mechanics.mode_labels(phi, masses) == ["deck θ (torsion) 100 %"]


def test_bad_shapes_refused():
    with pytest.raises(ValueError, match=r"shapes \(7, n\)"):
        mechanics.energy_shares(np.ones((3, 3)), np.ones(3))
    with pytest.raises(ValueError, match="no kinetic energy"):
        mechanics.energy_shares(np.zeros((7, 1)), np.ones(7))


@pytest.mark.parametrize("engine", ["analytic", "opensees"])
def test_cli_names_mode_1_torsional(capsys, engine, bench):
    if engine == "opensees":
        pytest.importorskip("openseespy.opensees")
    assert main(["modes", "saiidi-4span", "--engine", engine]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "kinetic energy" in lines[0]
    _, shares = _shares(bench)
    assert lines[1].split()[:2] == ["1", "0.61101"]
    assert lines[1].endswith(mechanics.mode_label(shares[:, 0]))
    assert "deck θ (torsion) 68 %" in lines[1]

"""The compliance engine's Newmark clone against the OpenSees engine (rigid mode).

Benchmark scene, frictionless linear gap (ElasticPPGap), both engines at dt = 5e-4 s with a
NormDispIncr tolerance of 1e-12: every standard column agrees to round-off (≤ 1e-8 of its peak
over the first 5 s; measured ~2e-9 over 5 s with the default damping of issue 12, with
identical Newton iteration counts).
"""

from __future__ import annotations

import importlib.util

import pytest

from deckpound.models.scene_io import load_scene

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("deckpound.opensees_build.engine") is None
    or importlib.util.find_spec("openseespy") is None,
    reason="OpenSees engine not available",
)


def _scene(duration=None):
    ov = ["opensees.tolerance=1e-12", "compliance.tolerance=1e-12", "opensees.mode=rigid"]
    if duration is not None:
        ov.append(f"run.duration={duration}")
    return load_scene("saiidi-4span", ov)


def test_clone_agrees_with_opensees_first_5_s():
    from deckpound.compare.verify.clone import verify_clone

    rep = verify_clone(_scene(5.0))
    print(
        "largest deviation:",
        rep["worst"],
        "speed ratio:",
        rep["speed_ratio"],
        "iterations:",
        rep["iterations"],
    )
    assert rep["status"] == {"opensees": "success", "compliance": "success"}
    # 1e-8 since issue 12 (the default damping leaves the seats to their dashpots: ~2e-9
    # of round-off in the contact forces, 4e-10 with Rayleigh on the seat springs)
    assert rep["worst"][1] <= 1e-8, rep["deviation"]
    assert rep["worst_velocity"][1] <= 1e-8, rep["deviation"]  # 2/dt amplification, see verify
    assert rep["iterations"]["opensees"] == rep["iterations"]["compliance"]


@pytest.mark.slow
def test_clone_agrees_with_opensees_whole_record():
    from deckpound.compare.verify.clone import verify_clone

    rep = verify_clone(_scene())
    print(
        "largest deviation:",
        rep["worst"],
        "speed ratio:",
        rep["speed_ratio"],
        "us/step:",
        rep["us_per_step"],
    )
    assert rep["worst"][1] <= 1e-6, rep["deviation"]


@pytest.mark.slow
def test_clone_speed_at_dt_1e4():
    from deckpound.analytic.compliance.engine import run_compliance

    sc = load_scene("saiidi-4span", ["compliance.dt=1e-4"])
    run_compliance(sc)
    r = run_compliance(sc)
    print("us per step (benchmark, dt = 1e-4):", r.meta["us_per_step"])
    assert r.ok and r.meta["us_per_step"] < 5.0


def test_stiff_contact_makes_the_response_itself_undetermined():
    """Issue 28 asks the clone to equal OpenSees at k = 1e8 kN/m to the matrix's tolerance.
    The response is not determined that well: the clone itself, on the record scaled by
    1 + 1e-13, moves beyond the tolerance within 3 s at k = 1e7 (Newton iteration counts flip
    on round-off and the impacts amplify it), as far as the engines are apart; at the
    paper's 1e6 the same change moves it by round-off only, and the engines agree."""
    from deckpound.compare.verify.clone import verify_clone
    from deckpound.compare.verify.matrix import TOLERANCE

    short = ["run.duration=3", "excitation.duration=3"]
    soft = verify_clone(load_scene("saiidi-4span", short), twin=True)
    assert soft["twin_worst"][1] < 1e-3 * TOLERANCE and soft["worst"][1] <= TOLERANCE
    stiff = verify_clone(load_scene("saiidi-4span", [*short, "contact.stiffness=1e7"]), twin=True)
    assert stiff["status"] == {"opensees": "success", "compliance": "success"}
    assert stiff["twin_worst"][1] > 100 * TOLERANCE
    assert stiff["worst"][1] <= 10 * stiff["twin_worst"][1]

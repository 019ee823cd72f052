"""The OpenSees engine's work–energy balance (deckpound.opensees_build.energy, issue 28 item 1).

Every energy column of the OpenSees result is computed from the OpenSees model's own state at
every converged (sub)step, with the meanings of the compliance engine's. The two engines agree
to round-off on the benchmark's displacements (tests/test_clone_vs_opensees.py), and so do the
energies built from the two states: measured ≤ 1.1e-12 of the input energy over 3 s for every
case below, asserted at 1e-10. With Newmark's average acceleration the balance closes up to the
Newton residual (measured ≤ 2e-14 of the input with the linear gap, 1.2e-12 with the Hertz
law), also through rescued sub-steps; free vibration without contact or damping keeps its
energy to round-off.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

pytest.importorskip("openseespy.opensees")

from _free_vibration import undamped

from deckpound.analytic.compliance.engine import run_compliance
from deckpound.analytic.kernels.hysteretic import HystereticMaterial
from deckpound.models.columns import ENERGY_COLUMNS
from deckpound.models.plan import takeda_hysteretic_args
from deckpound.models.scene_io import load_scene
from deckpound.opensees_build.energy import takeda_constants, takeda_unloading_stiffness
from deckpound.opensees_build.engine import run_opensees

#: both engines stepped to the same converged states (tests/test_clone_vs_opensees.py)
TIGHT = ["opensees.tolerance=1e-12", "compliance.tolerance=1e-12", "opensees.mode=rigid"]
#: no excitation, no damping anywhere (seat dashpots included), elastic bents, for 1 s
UNDAMPED = undamped(1)


def quiet(run, scene, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run(scene, **kw)


def closure(r) -> float:
    """max |energy_error| / max |energy_input| of a result."""
    return float(np.max(np.abs(r["energy_error"])) / np.max(np.abs(r["energy_input"])))


def test_result_has_the_compliance_engines_energy_columns_and_closure():
    r = quiet(run_opensees, load_scene("saiidi-4span", ["run.duration=0.5"]))
    assert r.ok
    for c in ENERGY_COLUMNS:
        assert c in r.columns and len(r[c]) == len(r.t) and np.all(np.isfinite(r[c]))
    assert r["energy_input"][0] == 0.0  # from rest
    assert r.meta["energy_closure"] == pytest.approx(closure(r), rel=1e-12, abs=1e-300)
    assert r.meta["energy_closure"] < 1e-12


CASES = {
    "benchmark": ("saiidi-4span", []),
    # tangent-dependent Rayleigh on bents and seats, mass part on relative velocities (mass
    # dampers), explicit bent dashpots: every damping element kind of the model
    "damping": (
        "saiidi-4span",
        [
            "damping.stiffness=committed",
            "damping.members=bents+seats",
            "damping.mass=relative",
            "bents[0].cx=50",
            "bents[2].cy=40",
        ],
    ),
    "current tangent": ("saiidi-4span", ["damping.stiffness=current"]),
    "hertzdamp": ("saiidi-4span", ["contact.law=hertzdamp"]),
    # zeroLengthContact2D: the tangential force of a step that slid is inferred (energy.py)
    "contact2d": ("saiidi-4span", ["contact.friction=0.3", "contact.friction_mode=contact2d"]),
    "skew contact2d": ("skew-30", ["contact.friction=0.3", "contact.friction_mode=contact2d"]),
}


@pytest.mark.parametrize("case", list(CASES))
def test_energy_columns_equal_the_clones(case):

    name, overrides = CASES[case]
    sc = load_scene(name, [*TIGHT, "run.duration=3", *overrides])
    ro = quiet(run_opensees, sc)
    rc = quiet(run_compliance, sc)
    assert ro.ok and rc.ok
    assert len(ro.t) == len(rc.t)
    e_in = float(np.max(np.abs(rc["energy_input"])))
    dev = {c: float(np.max(np.abs(ro[c] - rc[c]))) / e_in for c in ENERGY_COLUMNS}
    assert max(dev.values()) <= 1e-10, dev
    # closes up to the Newton residual: ≤ 2e-14 with the linear gap, 1.2e-12 with Hertz
    assert closure(ro) <= 1e-11
    # the cases reach the terms they are about: contact (and slip) within the 3 s
    assert np.max(ro["energy_contact_stored"]) > 0.0
    if "contact2d" in case:
        assert ro["energy_friction"][-1] > 0.01 * e_in


class FailAt:
    """ops wrapper whose analyze calls numbered in ``at`` fail (an impossible tolerance), so
    that the engine rescues those steps by sub-stepping (as tests/test_opensees_engine.py)."""

    def __init__(self, raw, at):
        self.raw, self.at, self.calls = raw, set(at), 0

    def __getattr__(self, name):
        return getattr(self.raw, name)

    def analyze(self, n, dt):
        self.calls += 1
        if self.calls in self.at:
            self.raw.test("NormDispIncr", 1e-30, 1)
        return self.raw.analyze(n, dt)


def test_balance_closes_through_rescued_substeps():
    sc = load_scene("saiidi-4span", [*TIGHT, "run.duration=1"])
    base = quiet(run_opensees, sc)
    r = quiet(run_opensees, sc, _ops_wrapper=lambda raw: FailAt(raw, (300, 900, 1500)))
    assert r.ok and r.meta["rescued_by_substeps"] == 3
    assert closure(r) <= 1e-12
    # the sub-stepped steps integrate the same motion a little differently: same energies
    # to the size of that difference, while a sub-step left out of the work would miss the
    # work of a whole step
    e_in = float(np.max(np.abs(base["energy_input"])))
    for c in ENERGY_COLUMNS:
        assert np.max(np.abs(r[c] - base[c])) <= 1e-4 * e_in, c


def test_stick_mode_balance_closes():
    # the sticks' Rayleigh damping (which openseespy 3.7.1 keeps despite the model's
    # 'region -rayleigh 0 0 0 0') and their elastic energy are in the balance
    r = quiet(run_opensees, load_scene("saiidi-4span", ["opensees.mode=stick", "run.duration=1"]))
    assert r.ok
    assert closure(r) <= 1e-12


def test_free_vibration_without_contact_keeps_its_energy():
    # a displaced and moving deck, no excitation, no damping: the supports do no work and
    # kinetic + strain energy stay the initial energy (the average-acceleration scheme
    # conserves the energy of a linear system); the start exercises the elastic forces of
    # the displaced state, which the materials report only after the first step
    sc = load_scene(
        "saiidi-4span",
        [
            *UNDAMPED,
            "opensees.tolerance=1e-12",
            "initial.deck=[0.001,0.002,0.0001]",
            "initial.deck_velocity=[0.0,0.05,0.001]",
        ],
    )
    r = quiet(run_opensees, sc)
    assert r.ok
    assert min(np.min(r[f"gap_c{c}"]) for c in range(1, 5)) > 0.0  # no contact
    e0 = r["energy_input"][0]
    assert e0 > 0.0 and np.all(r["energy_input"] == e0)
    total = r["energy_kinetic"] + r["energy_strain"]
    assert total[0] == pytest.approx(e0, rel=1e-14)
    assert np.max(np.abs(total - e0)) <= 1e-12 * e0
    assert np.max(r["energy_strain"]) > 0.1 * e0  # energy does go back and forth
    for c in ("energy_viscous", "energy_hysteretic", "energy_contact_dissipated"):
        assert np.max(np.abs(r[c])) <= 1e-12 * e0, c


def test_damped_start_from_a_displaced_moving_deck_equals_the_clone():
    # the forces at t = 0 (elastic springs at the initial displacement, dashpots at the
    # initial velocity: a bent dashpot moves with the deck) start the trapezoidal work

    sc = load_scene(
        "saiidi-4span",
        [
            *UNDAMPED,
            *TIGHT,
            "damping.ratio=0.05",
            "seats[0].cx=100",
            "bents[0].cx=50",
            "initial.deck=[0.001,0.002,0.0001]",
            "initial.deck_velocity=[0.1,0.05,0.001]",
        ],
    )
    ro, rc = quiet(run_opensees, sc), quiet(run_compliance, sc)
    assert ro.ok and rc.ok
    e0 = rc["energy_input"][0]
    assert ro["energy_input"][0] == pytest.approx(e0, rel=1e-14)
    assert closure(ro) <= 1e-12
    assert ro["energy_viscous"][-1] > 0.5 * e0
    for c in ENERGY_COLUMNS:
        assert np.max(np.abs(ro[c] - rc[c])) <= 1e-10 * e0, c


def test_unresolved_contact_shows_as_negative_contact_dissipation():
    # the free vibration with impacts at a step that does not resolve the contact:
    # the balance still closes, the energy the gap gives back on separation beyond what it
    # took shows as negative contact dissipation (the linear gap's stored energy ½ k g² is
    # exact, so the dissipation is exactly work − stored)
    sc = load_scene(
        "saiidi-4span",
        [
            *UNDAMPED,
            "run.steps_per_contact_period=0",
            "opensees.dt=5e-4",
            "initial.deck_velocity=[0.25,0.05,0.002]",
        ],
    )
    r = quiet(run_opensees, sc)
    e0 = r["energy_input"][0]
    assert min(np.min(r[f"gap_c{c}"]) for c in range(1, 5)) < 0.0  # impacts
    assert closure(r) <= 1e-12
    assert np.min(r["energy_contact_dissipated"]) < -0.01 * e0


def test_takeda_unloading_stiffness_is_the_materials():
    # the stiffness the stored energy f²/(2 k_u) of a bent uses is the one the Hysteretic
    # material (its bit-for-bit clone) unloads along: elastic, and after an excursion to 4 e1

    sc = load_scene("saiidi-4span")
    for b in sc.bents:
        for spring in (b.x, b.y):
            args = takeda_hysteretic_args(spring)
            const = takeda_constants(args)
            e1p = const[0]
            for peak in (0.5 * e1p, 4.0 * e1p, -4.0 * e1p):
                m = HystereticMaterial(*args)
                m.set_trial_strain(peak).commit()
                m.set_trial_strain(peak * (1.0 - 1e-6)).commit()  # unloading
                ku = takeda_unloading_stiffness(const, max(peak, 0.0), min(peak, 0.0), m.stress)
                assert ku == pytest.approx(m.tangent, rel=1e-12), (spring, peak)

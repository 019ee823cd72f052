"""Issue 12 (item 1): every damping choice of the scene is the same model in every engine.

For each choice (``damping.members``, ``stiffness``, ``mass``, ``method = none``) the clone
(compliance, newmark) agrees with OpenSees (rigid) to round-off on the benchmark with pounding
and yielding, with identical Newton iteration counts (measured ≤ 2.3e-9 of each column's peak
over 3 s); the energy balance closes for each; the nonsmooth engine applies the same constant
damping matrix as the clone; engines refuse what they cannot express.
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from deckpound.analytic.compliance.engine import run_compliance
from deckpound.analytic.kernels.system import pack_system
from deckpound.compare.engines import get_engine, run_engine
from deckpound.compare.verify.clone import verify_clone
from deckpound.models.damping import damping_model
from deckpound.models.errors import SceneError
from deckpound.models.plan import plan_of
from deckpound.models.scene_io import load_scene
from deckpound.opensees_build.damping import rayleigh_members
from deckpound.opensees_build.engine import build
from deckpound.opensees_build.ops import OpsSession

CHOICES = [
    (),  # the default: bents, initial, absolute
    ("damping.members=bents+seats",),  # the behaviour before issue 12
    ("damping.members=none",),
    ("damping.method=none",),
    ("damping.stiffness=committed",),
    ("damping.stiffness=current",),
    ("damping.mass=relative",),
    ("damping.members=bents+seats", "damping.stiffness=current", "damping.mass=relative"),
    ("bents[0].cx=150", "bents[2].cy=300"),  # explicit bent dashpots (Viscous elements)
]


def _scene(*ov, duration=3.0):
    return load_scene(
        "saiidi-4span",
        ["opensees.tolerance=1e-12", "compliance.tolerance=1e-12", f"run.duration={duration}", *ov],
    )


@pytest.mark.skipif(importlib.util.find_spec("openseespy") is None, reason="no openseespy")
@pytest.mark.parametrize("ov", CHOICES, ids=lambda ov: "+".join(ov) or "default")
def test_clone_agrees_with_opensees_for_each_damping_choice(ov):

    rep = verify_clone(_scene(*ov))
    print(ov, "largest deviation:", rep["worst"], rep["worst_velocity"], rep["iterations"])
    assert rep["status"] == {"opensees": "success", "compliance": "success"}
    assert rep["worst"][1] <= 1e-8, rep["deviation"]
    assert rep["worst_velocity"][1] <= 1e-8, rep["deviation"]
    assert rep["iterations"]["opensees"] == rep["iterations"]["compliance"]


def test_damping_choices_change_the_answer():
    """The choices are not silently equivalent: each moves the deck response (checked on the
    clone, which agrees with OpenSees above)."""

    peak = {}
    for ov in CHOICES[:7] + CHOICES[8:]:
        r = run_compliance(_scene(*ov))
        assert r.ok
        peak[ov] = (np.max(np.abs(r["fn_c1"])), np.max(np.abs(r["deck_theta"])))
    base = peak[()]
    for ov, p in peak.items():
        if ov:
            assert abs(p[0] / base[0] - 1.0) > 1e-4 or abs(p[1] / base[1] - 1.0) > 1e-4, ov


@pytest.mark.parametrize("ov", CHOICES, ids=lambda ov: "+".join(ov) or "default")
def test_energy_balance_closes_for_each_damping_choice(ov):

    r = run_compliance(_scene(*ov, duration=4.0))
    assert r.ok
    ein = np.max(np.abs(r["energy_input"]))
    closure = np.max(np.abs(r["energy_error"])) / ein
    print(ov, "energy closure", closure, "viscous", r["energy_viscous"][-1])
    assert closure < 1e-9
    if ov != ("damping.method=none",) and ov != ("damping.members=none",):
        assert r["energy_viscous"][-1] > 0


def test_relative_mass_damping_is_the_same_matrix_in_clone_and_nonsmooth():
    """Both engines pack the damping through :func:`deckpound.analytic.kernels.system.pack_system`:
    the relative mass part appears as dashpots against the supports, and the total damping
    matrix equals the model's (a0 M on the diagonal either way)."""

    for mass in ("absolute", "relative"):
        sc = _scene(f"damping.mass={mass}")
        plan = plan_of(sc)
        dm = damping_model(sc, plan)
        ps = pack_system(plan, dm)
        np.testing.assert_allclose(ps.C, dm.matrix(plan), rtol=1e-13, atol=1e-9)
        absolute = damping_model(_scene(), plan).matrix(plan)
        np.testing.assert_allclose(ps.C, absolute, rtol=1e-12, atol=1e-9)
        if mass == "relative":
            assert ps.a0 == 0.0 and len(dm.mass_dampers) == 3 * len(sc.bents) + 4
            # dashpots act against the table / actuator channels (S has their entries)
            assert np.count_nonzero(ps.arrays.schan[plan.n_springs :] >= 0) == 2 * len(sc.bents) + 2


def test_engines_refuse_what_they_cannot_express():

    for name, ov in (("nonsmooth", ()), ("compliance", ("compliance.integrator=adaptive",))):
        eng = get_engine(name)
        sc = _scene("damping.stiffness=current", *ov)
        with pytest.raises(SceneError, match=r"damping\.stiffness"):
            eng.refuse(sc, eng.settings_of(sc))
        eng.refuse(_scene("damping.mass=relative", *ov), eng.settings_of(sc))


@pytest.mark.parametrize(
    "ov",
    [("damping.mass=relative",), ("damping.members=bents+seats",), ("damping.method=none",)],
    ids=lambda ov: ov[0],
)
def test_nonsmooth_engine_applies_the_same_damping(ov):
    """The nonsmooth engine's smooth forces come from the same packing: with each choice its
    energy balance closes, and its peak transverse deck displacement (set by the bents and the
    damping, hardly by the contact law) follows the clone's to 1e-3 — and moves with the
    choice as the clone's does."""

    base = {e: run_engine(e, _scene(duration=4.0)) for e in ("compliance", "nonsmooth")}
    got = {e: run_engine(e, _scene(*ov, duration=4.0)) for e in ("compliance", "nonsmooth")}
    ns = got["nonsmooth"]
    assert ns.ok and abs(ns.meta["energy_error"]) < 1e-9 * np.max(np.abs(ns["energy_input"]))
    y = {e: np.max(np.abs(r["deck_y_rel"])) for e, r in got.items()}
    y0 = {e: np.max(np.abs(r["deck_y_rel"])) for e, r in base.items()}
    assert abs(y["nonsmooth"] / y["compliance"] - 1.0) < 1e-3, y
    shift = {e: y[e] / y0[e] - 1.0 for e in y}
    if abs(shift["compliance"]) > 1e-2:  # a choice that moves y: both move alike
        assert abs(shift["nonsmooth"] - shift["compliance"]) < 0.1 * abs(shift["compliance"])
    else:  # (Rayleigh on the seats hardly moves the deck)
        assert abs(shift["nonsmooth"]) < 1e-3, shift


@pytest.mark.skipif(importlib.util.find_spec("openseespy") is None, reason="no openseespy")
@pytest.mark.parametrize(
    "members,bents,seats",
    [("bents", True, False), ("bents+seats", True, True), ("none", False, False)],
)
@pytest.mark.parametrize("method", ["modes", "none"])
def test_opensees_damps_the_elements_of_the_damping_models_springs(members, bents, seats, method):
    """OpenSees puts ``-doRayleigh 1`` on the spring elements of the damping model's damped
    springs (``DampingModel.damped``), also when a1 = 0 (method none)."""
    sc = _scene(f"damping.members={members}", f"damping.method={method}")
    plan = plan_of(sc)
    dm = damping_model(sc, plan)
    assert list(dm.damped) == [bents] * plan.n_bent_springs + [seats] * 4
    assert rayleigh_members(plan, dm) == ([bents] * len(plan.bent_names), [seats] * 2)
    with OpsSession() as ops:
        build(ops, sc)
        tags = ops.tags("element")
        damped = {c.args[1] for c in ops.log if c.name == "element" and "-doRayleigh" in c.args}
    expected = {tags[f"bent {b}"] for b in plan.bent_names if bents}
    expected |= {tags[f"seat{j} spring"] for j in (1, 2) if seats}
    assert damped == expected

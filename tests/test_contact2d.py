"""Issue 12 (item 2): friction model ``contact2d`` is OpenSees's zeroLengthContact2D algorithm.

The kernel's state machine (ZeroLengthContact2D.cpp: ``formResidAndTangent`` decides stick or
slide from the trial; ``commitState`` moves the stick point to the trial slip displacement
after a sliding evaluation and never resets it when the corner opens), the engines' refusals,
and the whole-model equivalence with OpenSees to round-off.
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from deckpound.analytic.kernels import contact_laws as cl
from deckpound.compare.engines import get_engine
from deckpound.compare.verify.clone import verify_clone
from deckpound.models.errors import SceneError
from deckpound.models.scene_io import load_scene

KN, KT, MU = 1.0e6, 1.0e5, 0.3


def _row():
    sc = load_scene(
        "saiidi-4span",
        [
            f"contact.stiffness={KN}",
            f"contact.friction={MU}",
            "contact.friction_mode=contact2d",
            f"contact.tangential_stiffness={KT}",
        ],
    )
    return cl.pack_contact(sc)


def _eval(cp, cs, g, s):
    """One evaluation of corner 0 at gap g [m] and total tangential displacement s [m]."""
    closed, lam, _, _ = cl.normal_law(cp[0], cs[0], g, 0.0)
    state, lt, d_ds, _, d_lam = cl.friction_law(cp[0], cs[0], lam, s, 0.0)
    return closed, lam, state, lt, d_ds, d_lam


def _commit(cs, g, evaluated=True):
    cl.contact_commit(cs, np.full(4, g), np.zeros(4), np.array([evaluated] * 4))


def test_stick_then_slide_moves_the_stick_point_and_reports_zero():
    cp = _row()
    cs = cl.new_contact_state(np.full(4, 0.01))
    g = -1e-3  # p = 1000 kN, μ p = 300 kN
    closed, lam, state, lt, d_ds, _ = _eval(cp, cs, g, 1e-3)
    assert closed and lam == pytest.approx(1000.0)
    assert state == 1 and lt == pytest.approx(-KT * 1e-3) and d_ds == -KT  # stick: −k_t s
    _commit(cs, g)
    assert cs[0, cl.S_CSTICK] == 0.0  # a stick commit keeps the stick point
    assert cs[0, cl.S_CFT] == pytest.approx(-100.0)
    # slide: |k_t (s − s_p)| = 500 > 300 → λ_T = −μ p, consistent tangent ∂λ_T/∂λ_N = −μ
    _, _, state, lt, d_ds, d_lam = _eval(cp, cs, g, 5e-3)
    assert state == 2 and lt == pytest.approx(-MU * 1000.0) and d_lam == -MU and d_ds == 0.0
    _commit(cs, g)
    assert cs[0, cl.S_CSTICK] == 5e-3  # commitState: stickPt = ξ after a slide
    assert cs[0, cl.S_CFT] == 0.0  # the force OpenSees reports after that commit
    # the next step restarts from the new stick point (no memory of μ p)
    _, _, state, lt, *_ = _eval(cp, cs, g, 5.5e-3)
    assert state == 1 and lt == pytest.approx(-KT * 0.5e-3)


def test_stick_point_survives_opening_unlike_the_stick_law():
    cp = _row()
    cs = cl.new_contact_state(np.full(4, 0.01))
    _eval(cp, cs, -1e-3, 1e-3)
    _commit(cs, -1e-3)  # stuck with λ_T = −100 kN
    closed, lam, state, lt, *_ = _eval(cp, cs, 1e-3, 2e-3)  # open: no force at all
    assert not closed and lam == 0.0 and state == 0 and lt == 0.0
    _commit(cs, 1e-3, evaluated=False)
    # closes again at s = 1.5e-3: the old stick point (0) still acts
    _, _, state, lt, *_ = _eval(cp, cs, -1e-3, 1.5e-3)
    assert state == 1 and lt == pytest.approx(-KT * 1.5e-3)
    # the project's stick law starts from zero force on reclosure (its increment only)
    st = cp.copy()
    st[:, cl.P_FMODE] = cl.FRICTION_STICK
    cs2 = cl.new_contact_state(np.full(4, 0.01))
    _, lt2, *_ = cl.friction_law(st[0], cs2[0], 1000.0, 0.5e-3, 0.0)
    assert lt2 == pytest.approx(-KT * 0.5e-3)


def test_engines_say_which_friction_models_they_express():

    stick = load_scene("saiidi-4span", ["contact.friction=0.2", "contact.friction_mode=stick"])
    eng = get_engine("opensees")
    with pytest.raises(SceneError, match="contact2d"):
        eng.refuse(stick, eng.settings_of(stick))
    c2d = load_scene("saiidi-4span", ["contact.friction=0.2", "contact.friction_mode=contact2d"])
    eng.refuse(c2d, eng.settings_of(c2d))
    comp = get_engine("compliance")
    for ov, field in (
        (["compliance.integrator=adaptive"], "compliance.integrator"),
        (["contact.geometry=nonlinear"], "contact.geometry"),
    ):
        sc = load_scene(
            "saiidi-4span", ["contact.friction=0.2", "contact.friction_mode=contact2d", *ov]
        )
        with pytest.raises(SceneError, match=field.replace(".", r"\.")):
            comp.refuse(sc, comp.settings_of(sc))


@pytest.mark.skipif(importlib.util.find_spec("openseespy") is None, reason="no openseespy")
def test_clone_agrees_with_opensees_with_friction():
    """μ = 0.2, pounding with sticking and sliding over the first 5 s: every column to
    round-off (measured 4.5e-10 of its peak), identical Newton iteration counts. The project's
    own stick law differs from OpenSees by 5 % in rotation and 115 % in friction force."""

    sc = load_scene(
        "saiidi-4span",
        [
            "opensees.tolerance=1e-12",
            "compliance.tolerance=1e-12",
            "run.duration=5.0",
            "contact.friction=0.2",
            "contact.friction_mode=contact2d",
        ],
    )
    rep = verify_clone(sc)
    print("largest deviation:", rep["worst"], rep["worst_velocity"], rep["iterations"])
    assert rep["status"] == {"opensees": "success", "compliance": "success"}
    assert rep["worst"][1] <= 1e-8, rep["deviation"]
    assert rep["worst_velocity"][1] <= 1e-8, rep["deviation"]
    assert rep["iterations"]["opensees"] == rep["iterations"]["compliance"]
    # friction acted (and slid: the reported force drops to 0 after sliding commits)
    assert rep["peaks"]["ft_c1"] > 10.0 and rep["peaks"]["ft_c3"] > 10.0

"""Contact laws in OpenSees, clone ≡ OpenSees for every law the OpenSees engine accepts
(issue 12, item 3).

* ``kelvin-voigt`` → ViscoelasticGap: the same force; the material reports the tangent k only
  (no damping tangent), so the clone with ``compliance.contact_tangent = "opensees"`` (what
  ``deckpound verify clone`` uses) takes OpenSees's Newton iterates and agrees to round-off;
  with the consistent tangent it converges along another path (a difference within the Newton
  tolerance, amplified by the record).
* ``hertz`` → Hertzdamp(k, ξ_n = 0, −g₀, n): force k δ^n exactly; Hertzdamp reports its
  tangent with the opposite sign (checked on the material below).
* ``hertzdamp`` → Hertzdamp(k, 3(1 − e²)/4, −g₀, n): the material's own arithmetic (impact
  velocity from the first closed trial, no clipping) in the clone.
* ``bilinear`` (ImpactMaterial) and ``hertz-damp`` are refused at validation with the reason
  (``tests/test_opensees_export.py``).
"""

from __future__ import annotations

import importlib.util
import warnings

import numpy as np
import pytest

from deckpound.analytic.kernels import contact_laws as cl
from deckpound.compare.engines import run_engine
from deckpound.compare.verify.clone import verify_clone
from deckpound.models.scene_io import load_scene
from deckpound.opensees_build.ops import OpsSession

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("openseespy") is None, reason="openseespy not installed"
)


def _bench(law: str, duration: float = 5.0, **extra):
    ov = [
        "opensees.tolerance=1e-12",
        "compliance.tolerance=1e-12",
        "opensees.mode=rigid",
        f"run.duration={duration}",
        f"contact.law={law}",
    ]
    ov += [f"{k}={v}" for k, v in extra.items()]
    return load_scene("saiidi-4span", ov)


@pytest.mark.parametrize("law", ["kelvin-voigt", "hertz", "hertzdamp"])
def test_clone_agrees_with_opensees_for_the_law(law):

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = verify_clone(_bench(law))
    print(
        f"{law}: largest deviation {rep['worst']}, velocities {rep['worst_velocity']}, "
        f"iterations {rep['iterations']}"
    )
    assert rep["status"] == {"opensees": "success", "compliance": "success"}
    # Hertz: the same Newton iterates, round-off. Kelvin–Voigt and Hertzdamp: the two Newton
    # paths differ by a few iterations where a gap reopens (README, known limitations), which
    # amplifies round-off (measured 3.0e-7 for Hertzdamp with the default damping): the verify
    # tolerance then applies
    tol = 1e-8 if law == "hertz" else 1e-6
    assert rep["worst"][1] <= tol, rep["deviation"]
    assert rep["worst_velocity"][1] <= tol, rep["deviation"]
    # identical Newton iteration counts for hertz (and the linear gap); Kelvin–Voigt and
    # Hertzdamp reach the same answers (above) in different counts (measured over 5 s with
    # Rayleigh on the seats too: 47,935 vs 48,185 and 109,452 vs 133,702; with the seats damped
    # by their dashpots only, Hertzdamp 134,382 vs 172,782). Kelvin–Voigt: first in the step
    # ending at 1.6475 s (OpenSees 24 iterations, the clone 50 + sub-steps): its force jumps
    # by c·ġ when the gap reopens and round-off in the gap decides Newton's chattering path
    its = rep["iterations"]
    if law == "hertz":
        assert its["opensees"] == its["compliance"]
    else:
        assert abs(its["opensees"] - its["compliance"]) <= 0.35 * its["opensees"]


def test_hertzdamp_material_arithmetic_is_the_clones():
    """Drive openseespy's Hertzdamp directly (testUniaxialMaterial; in 3.7 ``setStrain``
    sets the trial state and commits it — measured: a second approaching closed state keeps
    the ξ of the first) and the clone's kernel branch along the same states, committed after
    each: stress and tangent agree, the tangent's sign included (OpenSees reports
    +n(k + ξδ̇)δ^(n−1) as −dσ/dε); ξ = ξ_n k/δ̇ is set when an approaching state follows an
    open one, kept while closed, reset when the gap opens."""

    sc = _bench("hertzdamp", **{"contact.restitution": 0.4})
    cp = cl.pack_contact(sc, opensees_tangent=True)[0]
    g0 = 0.01
    k, n, xi_n = cp[cl.P_K], cp[cl.P_N], cp[cl.P_D]
    path = [
        (0.002, -0.3),
        (-0.001, -0.2),
        (-0.0012, -0.25),
        (-0.002, 0.1),
        (-0.0015, 0.2),
        (0.001, 0.3),
        (-0.0005, -0.4),
        (-0.0007, 0.0),
        (-0.0002, 0.5),
    ]
    cs4 = cl.new_contact_state(np.full(4, g0))  # contact_commit works on all 4 corners
    cs = cs4[0]
    with OpsSession() as ops:
        raw = ops.raw
        raw.model("basic", "-ndm", 1, "-ndf", 1)
        raw.uniaxialMaterial("Hertzdamp", 1, k, xi_n, -g0, n)
        raw.testUniaxialMaterial(1)
        for g, gd in path:
            raw.setStrain(g - g0, gd)
            closed, lam, dg, _ = cl.normal_law(cp, cs, g, gd)
            assert closed == (g < 0.0)
            assert -raw.getStress() == pytest.approx(lam, rel=1e-12, abs=1e-9), (g, gd)
            assert -raw.getTangent() == pytest.approx(dg, rel=1e-12, abs=1e-9), (g, gd)
            cl.contact_commit(cs4, np.full(4, g), np.full(4, gd), np.ones(4, dtype=bool))


def test_bilinear_runs_with_fine_substeps_close_to_the_continuous_law():
    """ImpactMaterial (law = 'bilinear', opensees.substeps = 1000): the closing steps fail and
    are rescued by 1000 sub-steps. The motion is the clone's continuous Muthukumar law's to
    ~2e-4 (first 3 s, with the seats damped by their dashpots only (issue 12 default): peak
    deck x 2.1e-4; with Rayleigh on the seats too it was 7.2e-5), but the gap force is not: the jump K1·(committed strain − gap) of the closing
    sub-step adds a spike (first 3 s: peak gap force 236 kN against the continuous law's 176
    kN, +34 %) — documented, not cloned."""

    sc = load_scene(
        "saiidi-4span", ["contact.law=bilinear", "opensees.substeps=1000", "run.duration=3.0"]
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ro = run_engine("opensees", sc)
        rc = run_engine("compliance", sc)
    assert ro.ok and rc.ok
    assert ro.meta["rescued_by_substeps"] >= 1  # the closing steps need them
    for col in ("deck_theta", "deck_x_abs"):
        po, pc = np.max(np.abs(ro[col])), np.max(np.abs(rc[col]))
        print(col, po, pc, abs(po - pc) / pc)
        assert abs(po - pc) <= 5e-4 * pc
    fo = max(np.max(ro[f"fn_c{c}"]) for c in range(1, 5))
    fc = max(np.max(rc[f"fn_c{c}"]) for c in range(1, 5))
    print("peak gap force", fo, fc, abs(fo - fc) / fc)
    assert fo > fc  # the closing-step spike of ImpactMaterial

r"""Oracles for a deck of several segments (issue 31, item 4), in the analytic engines.

Every case is a free chain of segments (``tests/_segment_scenes.py``: no bents, no damping, no
support motion, the abutment seats 1 m away), so only the joints act. Sign convention of the
corner table (``models/plan.py``): at joint k the corners of the RIGHT segment k + 1 strike the
right face of segment k, and the gap opens along n = (cos φ, −sin φ); for a straight joint and
y = θ = 0 motion the joint's gap rate is U_N = v_{k+1} − v_k (closing when negative). Segment
velocities are read from the result columns ``<seg>_vx_abs``, ``<seg>_vy_abs``, ``<seg>_omega``.

1. Two-body Newton impact (straight joint, both corners close together). Momentum and
   Newton's law U_N⁺ = −e U_N⁻ give

       v₁' = (m₁v₁ + m₂v₂ + m₂ e (v₂ − v₁)) / (m₁ + m₂),
       v₂' = (m₁v₁ + m₂v₂ + m₁ e (v₁ − v₂)) / (m₁ + m₂)

   (v₂' − v₁' = −e (v₂ − v₁); Σ m v unchanged). The Moreau–Jean step solves Newton's law at
   both corners in one LCP, exactly. The compliance engine's Kelvin–Voigt dashpot is
   c = 2ζ(e)√(k m_eff), ζ(e) = −ln e / √(π² + ln² e), with m_eff = 1/(1/m₁ + 1/m₂ + (W/2)²/I₁
   + (W/2)²/I₂) the mass ONE corner sees (both bodies). A face impact loads the two corners
   together, μ δ̈ + 2c δ̇ + 2k δ = 0 with μ = m₁m₂/(m₁ + m₂), whose restitution
   e_face = exp(−π ζ_f / √(1 − ζ_f²)), ζ_f = c / √(2kμ) = ζ √(2 m_eff/μ) differs from e for
   0 < e < 1 (0.378 for e = 0.5 here: a property of the per-corner calibration, as for a deck
   face at an abutment, ``test_engine_contract.py``), and equals it for e = 0 (overdamped: the
   bodies end at their common velocity) and e = 1 (no dashpot). The compliance runs are
   checked against Newton's closed form with e_face, and a single-corner impact (one corner of
   a rotated segment strikes alone) checks that the calibration gives e itself there.

   Compliance tolerances. Newmark: the contact force switches on and off between steps; at
   each of the two switches the force 2kδ + 2cδ̇ acts for at most one step with |δ| ≤ |U| dt,
   an impulse error ≤ (2c + 2k dt)|U| dt, so the relative-velocity error is
   ≤ 2 (C dt + K dt²)/μ · |U⁻| (C = 2c, K = 2k: the face); the run at dt/16 must also be at
   least 4x closer than the run at dt (first order with the dashpot's jump, second order for
   e = 1). Adaptive (Dormand–Prince with the gap events located): the switches are exact and
   the error follows the error control, ≤ 1e3 rtol, at least 100x smaller at rtol = 1e-10
   than at 1e-6 when the dashpot acts. For e = 0 both integrators reach the common velocity to
   the exponential decay of the overdamped contact, run long enough for e^(−s t) < 1e-12.

2. A chain of three equal segments, joint 2 touching (gap 0), segment 1 striking segment 2 at
   v (U_N = −v at joint 1). All four corners in one LCP: with both joints active,
   v₂' − v₁' = e v, v₃' = v₂', m(v₁' + v₂' + v₃') = m v, so v' = ((1 − 2e), (1 + e), (1 + e)) v/3
   and the joint impulses P₁ = m (2 + 2e) v/3 ≥ P₂ = m (1 + e) v/3 ≥ 0 (consistent with
   v₂' = (P₁ − P₂)/m): (−1/3, 2/3, 2/3) v for e = 1, v/3 each for e = 0. A sequence of pairwise
   impacts (any open gap at joint 2) gives (0, 0, v) for e = 1 instead. The nonsmooth engine
   resolves an open gap δ > 0 as that sequence for any δ (joint 2 is inactive when joint 1
   strikes: its mid-step gap is δ > 0 with segments 2 and 3 at rest), the compliance engine once
   δ exceeds the travel of segment 2 during the first contact, v T_half/2 with
   T_half = π√(μ/(2k)): below it the contacts overlap, and its answer approaches the sequence
   as δ grows.

3. A free chain conserves Σ m v (x and y) through its impacts, and its angular momentum about
   a fixed point: for the small-rotation kinematics H = Σ I ω + m (X₀ v_y − Y₀ v_x) with the rest
   centres (X₀, Y₀) (the contact forces act at the corners' rest positions, where the two
   faces' points lie on one line along n), exactly conserved by both engines (a linear
   invariant of their schemes); for the exact kinematics with the current centres, which the
   Moreau–Jean impulses conserve exactly (the impulse acts at one point of both bodies and the
   θ = ½ position update keeps H between q_M and q_{k+1}).

4. e = 1 keeps the kinetic energy: nonsmooth to round-off (the two-body impact and the
   chain's simultaneous LCP impact, whose answer conserves it: 1/9 + 4/9 + 4/9 = 1), compliance
   with the linear law to the contact switch's error, ≤ 2 K dt²/μ relative.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from _segment_scenes import free_chain, kinetic_energy, momenta, plate_inertia, velocities

import deckpound as dp
from deckpound.models.scene_io import load_scene

# the joints' gaps are set by the oracles, not by the contact stiffness or the step: the quality
# warnings about penetrations beyond 10 % (compliance) or 20 % (nonsmooth) of the smallest gap
# say nothing about these checks
pytestmark = [
    pytest.mark.filterwarnings("ignore:compliance engine. penetration"),
    pytest.mark.filterwarnings("ignore:nonsmooth engine. penetration"),
]

EPS = np.finfo(float).eps
#: round-off of the nonsmooth engine's velocities: 64 ulps of the largest velocity
ROUND_OFF = 64 * EPS
_FRAMES = load_scene("two-frame")
#: the two-frame scene's contact stiffness per corner [kN/m], deck width [m], the length [m]
#: and mass [t] of its first frame (the chains' segments are plates of that width)
K_CORNER = _FRAMES.contact.stiffness
WIDTH = _FRAMES.deck.width
FRAME, M1 = _FRAMES.segments[0].length, _FRAMES.segments[0].mass
DT = 5.0e-4  # the compliance engine's default step [s]


def newton_pair(m1: float, m2: float, v1: float, v2: float, e: float) -> np.ndarray:
    """Velocities after a central Newton impact of two bodies (module docstring, item 1)."""
    p = m1 * v1 + m2 * v2
    return np.array([p + m2 * e * (v2 - v1), p + m1 * e * (v1 - v2)]) / (m1 + m2)


def kelvin_voigt_zeta(e: float) -> float:
    """Damping ratio of the Kelvin–Voigt calibration (Anagnostopoulos 1988)."""
    if e <= 0.0:
        return 1.0
    return -math.log(e) / math.sqrt(math.pi**2 + math.log(e) ** 2)


def corner_mass(m1: float, m2: float, length: float) -> float:
    """Mass one straight-joint corner (y = ±W/2) sees, both bodies free [t]."""
    y2 = (0.5 * WIDTH) ** 2
    return 1.0 / (1 / m1 + 1 / m2 + y2 / plate_inertia(m1, length) + y2 / plate_inertia(m2, length))


def face_contact(e: float, m1: float, m2: float, length: float) -> tuple[float, float, float]:
    """(e_face, ζ_f, ω_f) of a face impact with the Kelvin–Voigt law calibrated to e (item 1):
    μ δ̈ + 2c δ̇ + 2k δ = 0, c = 2ζ(e)√(k m_eff)."""
    mu = m1 * m2 / (m1 + m2)
    c = 2.0 * kelvin_voigt_zeta(e) * math.sqrt(K_CORNER * corner_mass(m1, m2, length))
    zeta = c / math.sqrt(2.0 * K_CORNER * mu)
    omega = math.sqrt(2.0 * K_CORNER / mu)
    if zeta >= 1.0:
        return 0.0, zeta, omega
    return math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta**2)), zeta, omega


def pairwise_sequence(masses, speeds, gaps, e: float, max_impacts: int = 100_000) -> np.ndarray:
    """Velocities after the sequence of pairwise Newton impacts of bodies in a row (exact free
    flight between them; ``gaps[k]`` between bodies k and k + 1, closing when v_k > v_{k+1})."""
    m = np.asarray(masses, float)
    v = np.asarray(speeds, float).copy()
    g = np.asarray(gaps, float).copy()
    for _ in range(max_impacts):
        rate = v[:-1] - v[1:]
        with np.errstate(divide="ignore"):
            times = np.where(rate > 0.0, g / np.where(rate > 0.0, rate, 1.0), np.inf)
        k = int(np.argmin(times))
        if not np.isfinite(times[k]):
            return v
        g -= rate * times[k]
        g[k] = 0.0
        v[k : k + 2] = newton_pair(m[k], m[k + 1], v[k], v[k + 1], e)
    raise AssertionError("the impact sequence did not end")


def run(scene, engine: str = "nonsmooth"):
    result = dp.run(scene, engine=engine)
    assert result.ok, result.meta["message"]
    return result


# -- 1. two-body Newton impact ----------------------------------------------------------------

V1, V2, JOINT_GAP = 0.1, -0.5, 0.005  # segment 2 strikes segment 1 at 0.6 m/s after 8.3 ms


def two_body(ratio: float, e: float | None, duration: float, settings=None):
    """Segment 2 (m₂ = ratio m₁) launched at V2 against segment 1 moving at V1; restitution
    e (None: the scene's, for the linear law of the compliance engine, which does not read it)."""
    restitution = {} if e is None else {"contact.restitution": e}
    return free_chain(
        (M1, ratio * M1),
        ((V1, 0.0, 0.0), (V2, 0.0, 0.0)),
        (JOINT_GAP,),
        lengths=(FRAME, FRAME),
        settings={
            **restitution,
            "excitation.duration": duration,
            "run.output_dt": 1e-3,
            **(settings or {}),
        },
    )


def x_velocities(result, scene) -> np.ndarray:
    return velocities(result, scene)[:, 0]


@pytest.mark.parametrize("ratio", [1.0, 3.0, 1.0 / 3.0])
@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_nonsmooth_two_body_impact_is_newtons_closed_form(e, ratio):
    sc = two_body(ratio, e, 0.05, {"nonsmooth.h": 1e-4})
    r = run(sc)
    v = velocities(r, sc)
    expected = newton_pair(M1, ratio * M1, V1, V2, e)
    np.testing.assert_allclose(v[:, 0], expected, rtol=0, atol=ROUND_OFF * abs(V2))
    # a straight face: no transverse motion, no rotation (the two corners' impulses equal)
    assert np.all(v[:, 1] == 0.0) and np.all(np.abs(v[:, 2]) <= ROUND_OFF * abs(V2))
    assert r["pn_j1_c1"].sum() > 0.0  # the joint did strike


def compliance_error(ratio: float, e: float, settings) -> float:
    """Largest velocity error of a Kelvin–Voigt face impact against Newton's closed form with
    e_face, relative to the approach speed."""
    m2 = ratio * M1
    e_face, zeta, omega = face_contact(e, M1, m2, FRAME)
    duration = 0.05
    if zeta >= 1.0:  # overdamped: the relative velocity decays as e^(−s t)
        s = omega * (zeta - math.sqrt(zeta**2 - 1.0))
        duration = JOINT_GAP / (V1 - V2) + 28.0 / s
    sc = two_body(ratio, e, duration, {"contact.law": "kelvin-voigt", **settings})
    r = run(sc, "compliance")
    expected = newton_pair(M1, m2, V1, V2, e_face)
    return float(np.max(np.abs(x_velocities(r, sc) - expected)) / (V1 - V2))


@pytest.mark.parametrize("ratio", [1.0, 3.0, 1.0 / 3.0])
@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_compliance_newmark_two_body_impact_converges_to_the_closed_form(e, ratio):
    m2 = ratio * M1
    e_face, _, _ = face_contact(e, M1, m2, FRAME)
    mu = M1 * m2 / (M1 + m2)
    c_face = 4.0 * kelvin_voigt_zeta(e) * math.sqrt(K_CORNER * corner_mass(M1, m2, FRAME))
    c_face *= e < 1.0  # e = 1: no dashpot
    errors = []
    for dt in (DT, DT / 16):
        err = compliance_error(ratio, e, {"compliance.dt": dt})
        bound = 2.0 * (c_face * dt + 2.0 * K_CORNER * dt**2) / mu
        print(f"e = {e}, m2/m1 = {ratio:.3g}, e_face = {e_face:.4f}, dt = {dt:.3g}: {err:.2e}")
        assert err <= (bound if e > 0.0 else 1e-9)
        errors.append(err)
    if e > 0.0:
        assert errors[1] <= errors[0] / 4  # tightens with the contact step
    if 0.0 < e < 1.0:  # the calibration's face restitution, not e (module docstring)
        assert abs(e_face - e) > 0.1


@pytest.mark.parametrize("ratio", [1.0, 3.0])
@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_compliance_adaptive_two_body_impact_follows_its_error_control(e, ratio):
    settings = {"compliance.integrator": "adaptive"}
    errors = []
    for rtol in (1e-6, 1e-10):
        err = compliance_error(
            ratio, e, {**settings, "compliance.rtol": rtol, "compliance.atol": 1e-3 * rtol}
        )
        print(f"e = {e}, m2/m1 = {ratio:.3g}, rtol = {rtol:.0e}: {err:.2e}")
        assert err <= 1e3 * rtol
        errors.append(err)
    assert errors[1] <= max(errors[0] / 100, 1e-11)  # tightens with the error control


#: a rotated segment 2 (θ₀ = 0.01 rad): corner j1_c2 (y = +W/2) 1 mm from the face, j1_c1 25 mm
THETA0, ECCENTRIC_GAP = 0.01, 0.013
W_C2 = np.array([-1.0, 0.5 * WIDTH, 1.0, -0.5 * WIDTH])  # ∂g/∂(x₁, θ₁, x₂, θ₂) of j1_c2
ECCENTRIC_V = ((0.1, 0.0, 0.003), (-0.4, 0.0, -0.002))


def single_corner_closed_form(ratio: float, e: float) -> tuple[np.ndarray, float]:
    """(x₁, θ₁, x₂, θ₂) velocities after corner j1_c2 strikes alone, P = −(1 + e) U_N⁻ / G,
    G = w M⁻¹ wᵀ, v⁺ = v⁻ + M⁻¹ wᵀ P (y untouched: n = (1, 0)); and U_N⁻ [m/s]."""
    m2 = ratio * M1
    minv = 1.0 / np.array([M1, plate_inertia(M1, FRAME), m2, plate_inertia(m2, FRAME)])
    v = np.array([ECCENTRIC_V[0][0], ECCENTRIC_V[0][2], ECCENTRIC_V[1][0], ECCENTRIC_V[1][2]])
    u_n = W_C2 @ v
    assert u_n < 0.0
    impulse = -(1.0 + e) * u_n / (W_C2 @ (minv * W_C2))
    return v + minv * W_C2 * impulse, float(u_n)


@pytest.mark.parametrize(
    ("engine", "settings", "tolerance"),
    [
        ("nonsmooth", {"nonsmooth.h": 1e-4}, ROUND_OFF),
        (
            "compliance",
            {
                "compliance.integrator": "adaptive",
                "compliance.rtol": 1e-10,
                "compliance.atol": 1e-13,
            },
            1e-7,  # 1e3 rtol
        ),
    ],
    ids=["nonsmooth", "adaptive"],
)
@pytest.mark.parametrize("ratio", [1.0, 3.0])
@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_single_corner_two_body_impact_is_the_closed_form(e, ratio, engine, settings, tolerance):
    """One corner strikes alone: the Kelvin–Voigt dashpot calibrated by that corner's m_eff
    (both bodies) gives e itself; Newton's law in the nonsmooth engine; both bodies turn."""
    sc = free_chain(
        (M1, ratio * M1),
        ECCENTRIC_V,
        (ECCENTRIC_GAP,),
        lengths=(FRAME, FRAME),
        displacements=((0.0, 0.0, 0.0), (0.0, 0.0, THETA0)),
        settings={
            "contact.restitution": e,
            "contact.law": "kelvin-voigt" if engine == "compliance" else "linear",
            "excitation.duration": 0.25,  # e = 0: the critically damped corner settles
            "run.output_dt": 1e-3,
            **settings,
        },
    )
    r = run(sc, engine)
    assert np.all(r["fn_j1_c1"] == 0.0) and np.any(r["fn_j1_c2"] > 0.0)  # j1_c2 alone
    v = velocities(r, sc)
    got = np.array([v[0, 0], v[0, 2], v[1, 0], v[1, 2]])
    expected, u_n = single_corner_closed_form(ratio, e)
    scale = abs(u_n)
    print(f"{engine} e = {e}, m2/m1 = {ratio:g}: {np.max(np.abs(got - expected)) / scale:.2e}")
    np.testing.assert_allclose(got, expected, rtol=0, atol=tolerance * scale)
    assert np.all(v[:, 1] == 0.0)


# -- 2. three equal segments struck simultaneously --------------------------------------------

V, CHAIN_GAP, CHAIN_L = 0.5, 0.00123, 11.0  # segment 1 strikes at 0.5 m/s after 2.46 ms


def chain3(e: float, second_gap: float, engine: str, duration: float = 0.05, settings=None):
    """Three equal segments, joint 1 closing at V, joint 2's gap ``second_gap``; the compliance
    engine runs e = 1 only, with the linear law (which has no restitution)."""
    if engine == "nonsmooth":
        contact = {"contact.restitution": e}
    else:
        assert e == 1.0
        contact = {"contact.law": "linear"}
    return free_chain(
        (M1, M1, M1),
        ((V, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
        (CHAIN_GAP, second_gap),
        lengths=(CHAIN_L,) * 3,
        settings={
            **contact,
            "excitation.duration": duration,
            "run.output_dt": 1e-4,
            "nonsmooth.h": 1e-4,
            **(settings or {}),
        },
    )


def lcp_chain(e: float) -> np.ndarray:
    """v'/v of the simultaneous impact (module docstring, item 2)."""
    return np.array([1.0 - 2.0 * e, 1.0 + e, 1.0 + e]) / 3.0


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_chain_struck_with_touching_second_joint_is_one_lcp(e):
    sc = chain3(e, 0.0, "nonsmooth")
    r = run(sc)
    v = velocities(r, sc)
    np.testing.assert_allclose(v[:, 0] / V, lcp_chain(e), rtol=0, atol=ROUND_OFF)
    assert np.all(v[:, 1] == 0.0) and np.all(np.abs(v[:, 2]) <= ROUND_OFF * V)
    # the joints' impulses, all four corners in one solve: P₁ = m(2+2e)v/3, P₂ = m(1+e)v/3
    p1 = r["pn_j1_c1"].sum() + r["pn_j1_c2"].sum()
    p2 = r["pn_j2_c1"].sum() + r["pn_j2_c2"].sum()
    np.testing.assert_allclose([p1, p2], M1 * V * np.array([2 + 2 * e, 1 + e]) / 3, rtol=1e-13)
    sequence = pairwise_sequence((M1,) * 3, (1.0, 0.0, 0.0), (0.0, 1e-3), e)
    if e > 0.0:  # not what a sequence of pairwise impacts gives
        assert np.max(np.abs(sequence - lcp_chain(e))) > 0.25
    else:  # e = 0: the sequence of plastic impacts converges to the same v/3
        np.testing.assert_allclose(sequence, lcp_chain(0.0), atol=1e-12)


def test_pairwise_sequences_of_the_oracle():
    """The event-driven reference itself: (0, 0, 1) for e = 1, (0.203125, 0.234375, 0.5625)
    for e = 0.5 (1→2, 2→3, 1→2 again), momentum kept."""
    np.testing.assert_array_equal(
        pairwise_sequence((1, 1, 1), (1, 0, 0), (0, 1e-3), 1.0), [0, 0, 1]
    )
    half = pairwise_sequence((1, 1, 1), (1, 0, 0), (0, 1e-3), 0.5)
    np.testing.assert_allclose(half, [0.203125, 0.234375, 0.5625], rtol=0, atol=1e-15)
    heavy = pairwise_sequence((1, 3, 2), (1, 0, -0.5), (1e-3, 2e-3), 0.7)
    assert np.dot((1, 3, 2), heavy) == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("second_gap", [1e-6, 1e-3])
@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_nonsmooth_chain_with_an_open_second_joint_is_the_pairwise_sequence(e, second_gap):
    sc = chain3(e, second_gap, "nonsmooth")
    r = run(sc)
    v = velocities(r, sc)[:, 0] / V
    sequence = pairwise_sequence((M1,) * 3, (1.0, 0.0, 0.0), (CHAIN_GAP, second_gap), e)
    np.testing.assert_allclose(v, sequence, rtol=0, atol=ROUND_OFF)


def test_compliance_chain_approaches_the_pairwise_sequence_as_the_second_gap_opens():
    """e = 1 (linear law, Newmark at dt = DT/10): the distance to (0, 0, v) falls as joint 2's gap
    grows and reaches the switch error once the gap exceeds v T_half/2 (the contacts no longer
    overlap); at gap 0 the penalty chain is neither the sequence nor the LCP answer."""
    mu = 0.5 * M1
    t_half = math.pi * math.sqrt(mu / (2.0 * K_CORNER))
    overlap = V * t_half / 2.0  # segment 2's travel during the first contact: 3.3 mm
    dt = DT / 10
    sequence = np.array([0.0, 0.0, 1.0])
    distances = []
    for gap in (0.0, 0.3 * overlap, 0.6 * overlap, 1.3 * overlap, 3.0 * overlap):
        sc = chain3(1.0, gap, "compliance", 0.1, {"compliance.dt": dt})
        v = velocities(run(sc, "compliance"), sc)[:, 0] / V
        distances.append(np.max(np.abs(v - sequence)))
        print(f"gap {gap * 1e3:.2f} mm: v'/v = {np.round(v, 6)}, {distances[-1]:.2e}")
        if gap == 0.0:
            assert np.max(np.abs(v - lcp_chain(1.0))) > 0.1
    assert all(a > b for a, b in itertools.pairwise(distances[:4]))
    switch_error = 2.0 * (2.0 * 2.0 * K_CORNER * dt**2) / mu  # two impacts, item 4's bound
    assert distances[0] > 0.1
    assert max(distances[3:]) <= switch_error


# -- 3. momentum of a free chain --------------------------------------------------------------

MASSES, LENGTHS = (60.0, 90.0, 45.0), (9.0, 12.0, 10.5)
LAUNCH = ((0.4, 0.05, 0.002), (0.0, -0.03, 0.0), (-0.3, 0.0, -0.001))
POINT = (3.0, -2.0)  # a fixed point off the deck axis [m]
#: round-off accumulated over the ~2,000 steps of a run (a modelling error would be ≥ 1e-7: the
#: joint gap's offset left out of the rest centres makes the angular momentum drift by 3e-4)
MOMENTUM_ROUND_OFF = 1e-13


@pytest.mark.parametrize("widths", [(), (3.6, 1.8, 2.4)], ids=["one-width", "three-widths"])
@pytest.mark.parametrize("skews", [(None, None), (15.0, 30.0)], ids=["straight", "skewed"])
@pytest.mark.parametrize(
    ("engine", "integrator", "geometry"),
    [
        ("nonsmooth", "newmark", "linear"),
        ("nonsmooth", "newmark", "nonlinear"),
        ("compliance", "newmark", "linear"),
        ("compliance", "adaptive", "linear"),
    ],
)
def test_free_chain_keeps_its_momenta_through_the_impacts(
    engine, integrator, geometry, skews, widths
):
    """Eccentric impacts (the segments spin and drift sideways, so single corners strike):
    Σ m v_x, Σ m v_y and the angular momentum about a fixed point to round-off (item 3); also
    with segments of three widths (each joint's corners where the two faces overlap)."""
    sc = free_chain(
        MASSES,
        LAUNCH,
        (0.004, 0.006),
        lengths=LENGTHS,
        skews=skews,
        settings={
            "contact.restitution": 0.5,
            "contact.law": "kelvin-voigt" if engine == "compliance" else "linear",
            "contact.geometry": geometry,
            "compliance.integrator": integrator,
            "excitation.duration": 0.2,
            "run.output_dt": 1e-4,
            "nonsmooth.h": 1e-4,
            **{f"segments[{i}].width": w for i, w in enumerate(widths)},
        },
    )
    r = run(sc, engine)
    strikes = sum(
        int(np.sum(np.diff((r[f"fn_j{k}_c{c}"] > 0.0).astype(int)) == 1))
        for k in (1, 2)
        for c in (1, 2)
    )
    assert strikes >= 2
    v0 = np.array(LAUNCH)
    assert np.max(np.abs(velocities(r, sc) - v0)) > 0.05  # the impacts changed the motion
    p_scale = sum(m * math.hypot(vx, vy) for m, (vx, vy, _) in zip(MASSES, LAUNCH))
    h = momenta(r, sc, POINT, moving=geometry == "nonlinear")
    drift = np.max(np.abs(h - h[0]), axis=0)
    print(f"{engine}/{integrator}/{geometry}: P {drift[:2] / p_scale}, H {drift[2] / abs(h[0, 2])}")
    assert np.all(drift[:2] <= MOMENTUM_ROUND_OFF * p_scale)
    assert drift[2] <= MOMENTUM_ROUND_OFF * abs(h[0, 2])


# -- 4. kinetic energy of elastic impacts -----------------------------------------------------


def test_nonsmooth_elastic_impacts_keep_the_kinetic_energy():
    """e = 1: the two-body impact and the chain's simultaneous and sequential impacts."""
    cases = [
        two_body(3.0, 1.0, 0.05, {"nonsmooth.h": 1e-4}),
        chain3(1.0, 0.0, "nonsmooth"),
        chain3(1.0, 1e-3, "nonsmooth"),
    ]
    for sc in cases:
        r = run(sc)
        energy = kinetic_energy(r, sc)
        assert r["pn_j1_c1"].sum() > 0.0
        np.testing.assert_allclose(energy, energy[0], rtol=16 * EPS, atol=0)


@pytest.mark.parametrize("ratio", [1.0, 3.0])
def test_compliance_elastic_impact_keeps_the_kinetic_energy_to_the_switch_error(ratio):
    """Linear law, Newmark: |ΔE|/E ≤ 2 K dt²/μ (K = 2k the face's stiffness), tighter at dt/16."""
    m2 = ratio * M1
    mu = M1 * m2 / (M1 + m2)
    errors = []
    for dt in (DT, DT / 16):
        sc = two_body(ratio, None, 0.05, {"compliance.dt": dt})
        energy = kinetic_energy(run(sc, "compliance"), sc)
        err = abs(energy[-1] / energy[0] - 1.0)
        print(f"m2/m1 = {ratio:g}, dt = {dt:.3g}: |dE|/E = {err:.2e}")
        assert err <= 2.0 * 2.0 * K_CORNER * dt**2 / mu
        errors.append(err)
    assert errors[1] <= errors[0] / 4

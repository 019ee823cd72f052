"""Skewed-deck geometry (issue 15, item 1): the scene field, the plan's corner table and the
linear and nonlinear contact kinematics for φ ≠ 0.

The reference geometry is written here independently of the plan model (DESIGN, "Skewed
decks"): end faces x = ±L/2 + y tan φ, corners (±L/2 + y_c tan φ, y_c), the right face's
outward normal (cos φ, −sin φ), tangent (sin φ, cos φ); the gap is measured along the normal.
The nonlinear gap of a corner is g = n(θ_s)·(P(u) − F(u)) with the deck corner
P = (x_d, y_d) + R(θ_d)(x_c, y_c), the seat face through the pivot F = F₀ + (x_s, 0) (the seats
slide along x) and its normal n(θ_s) = R(θ_s) n₀; W_N = ∂g/∂u, the Hessian ∂²g/∂u² and
W_T = t(θ_s)·∂(P − F)/∂u are checked against central differences of that function.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from deckpound.analytic.kernels.kinematics import contact_kinematics, gap_hessian, pack_corners
from deckpound.analytic.nonsmooth.impulses import size_tag
from deckpound.models.errors import SceneError
from deckpound.models.plan import plan_of
from deckpound.models.scene_io import load_scene

SKEWS = (0.0, 15.0, 30.0, 45.0, 60.0)


def scene_at(phi_deg: float, *more: str):
    return load_scene("saiidi-4span", [f"deck.skew={phi_deg!r}", *more])


def reference_corners(scene):
    """(x, y, gap-opening normal n, tangent t, seat pivot F₀) of c1..c4 from the DESIGN text."""
    phi = math.radians(scene.deck.skew)
    hl, hw = scene.deck.length / 2, scene.deck.width / 2
    out = []
    for xs, ys in ((-1, -1), (-1, 1), (1, -1), (1, 1)):
        y = ys * hw
        x = xs * hl + y * math.tan(phi)
        outward = np.array([math.cos(phi), -math.sin(phi)]) * xs  # outward normal of the face
        n = -outward  # gap opens into the deck
        g0 = scene.seats[0 if xs < 0 else 1].gap
        pivot = np.array([xs * hl, 0.0]) - g0 * n  # seat face mid-point
        out.append((x, y, n, np.array([math.sin(phi), math.cos(phi)]), pivot, g0))
    return out


def rot(a):
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def exact_gap(scene, u, c):
    """Nonlinear gap of corner c (0..3) from the reference geometry [m]."""
    x, y, n0, _, f0, _ = reference_corners(scene)[c]
    sx, st = (0, 1) if c < 2 else (2, 3)
    p = np.array([u[4], u[5]]) + rot(u[6]) @ np.array([x, y])
    f = f0 + np.array([u[sx], 0.0])
    return float((rot(u[st]) @ n0) @ (p - f))


def relative_position(scene, u, c):
    x, y, _, _, f0, _ = reference_corners(scene)[c]
    sx = 0 if c < 2 else 2
    return np.array([u[4], u[5]]) + rot(u[6]) @ np.array([x, y]) - (f0 + np.array([u[sx], 0.0]))


def kin(corners, u, nonlinear):
    g, wn, wt = np.zeros(4), np.zeros((4, 7)), np.zeros((4, 7))
    contact_kinematics(u, corners, nonlinear, g, wn, wt, size_tag(4), size_tag(7))
    return g, wn, wt


# -- the scene field -----------------------------------------------------------------------


def test_skew_defaults_to_a_straight_deck_and_is_validated():
    assert load_scene("saiidi-4span").deck.skew == 0.0
    for bad in (-1.0, 75.0, 89.0, float("nan")):
        with pytest.raises(SceneError, match="deck.skew"):
            scene_at(bad)
    assert scene_at(74.9).deck.skew == 74.9


# -- the corner table ----------------------------------------------------------------------


@pytest.mark.parametrize("phi", SKEWS)
def test_corner_table_is_the_parallelogram_of_the_design(phi):
    sc = scene_at(phi)
    plan = plan_of(sc)
    for corner, (x, y, n, t, _, g0) in zip(plan.corners, reference_corners(sc)):
        assert (corner.x, corner.y) == pytest.approx((x, y), abs=1e-14)
        assert corner.normal == pytest.approx(tuple(n), abs=1e-15)
        assert corner.tangent == pytest.approx(tuple(t), abs=1e-15)
        assert np.dot(n, t) == pytest.approx(0.0, abs=1e-15)
        assert corner.gap == g0
        # each corner lies on its end face x = ±L/2 + y tan φ
        side = -1 if corner.seat == 0 else 1
        assert corner.x == pytest.approx(
            side * sc.deck.length / 2 + corner.y * math.tan(math.radians(phi)), abs=1e-14
        )
    # the face's two corners differ by a vector along the tangent (the faces are parallel)
    for a, b in ((0, 1), (2, 3)):
        ca, cb = plan.corners[a], plan.corners[b]
        d = np.array([cb.x - ca.x, cb.y - ca.y])
        assert np.dot(d, ca.normal) == pytest.approx(0.0, abs=1e-13)


def test_straight_deck_table_is_bit_identical():
    """φ = 0 gives exactly the straight-deck numbers (no round-off in x, n, t or the lever)."""
    plan = plan_of(scene_at(0.0))
    hl, hw = 33.5 / 2, 2.4 / 2
    expect = [
        (-hl, -hw, (1.0, -0.0), (0.0, 1.0)),
        (-hl, hw, (1.0, -0.0), (0.0, 1.0)),
        (hl, -hw, (-1.0, 0.0), (0.0, 1.0)),
        (hl, hw, (-1.0, 0.0), (0.0, 1.0)),
    ]
    for c, (x, y, n, t) in zip(plan.corners, expect):
        assert (c.x, c.y, c.normal, c.tangent) == (x, y, n, t)
        assert c.lever == (0.0, y)


@pytest.mark.parametrize("phi", SKEWS)
def test_rest_gaps_and_rigid_motions(phi):
    """At rest both kinematics give g₀; moving deck and seat together along x, or the deck
    along the face tangent, leaves the linear gap unchanged (the gap is measured along n)."""
    sc = scene_at(phi, "seats[1].gap=0.02")
    corners = pack_corners(plan_of(sc))
    u0 = np.zeros(7)
    for nonlinear in (False, True):
        g, _, _ = kin(corners, u0, nonlinear)
        # the nonlinear gap subtracts coordinates of ~17 m: round-off ~ 17 eps ≈ 4e-15 m
        np.testing.assert_allclose(g, [0.0127, 0.0127, 0.02, 0.02], rtol=0, atol=1e-14)
    ph = math.radians(phi)
    u = np.zeros(7)
    u[[0, 2, 4]] = 0.3  # everything 0.3 m along x
    np.testing.assert_allclose(
        kin(corners, u, False)[0], [0.0127, 0.0127, 0.02, 0.02], rtol=0, atol=1e-14
    )
    u = np.zeros(7)
    u[4], u[5] = 0.2 * math.sin(ph), 0.2 * math.cos(ph)  # deck along the face tangent
    np.testing.assert_allclose(
        kin(corners, u, False)[0], [0.0127, 0.0127, 0.02, 0.02], rtol=0, atol=1e-14
    )
    u = np.zeros(7)
    u[4] = -0.001  # deck 1 mm towards seat 1
    g = kin(corners, u, False)[0]
    np.testing.assert_allclose(g[:2], 0.0127 - 0.001 * math.cos(ph), rtol=0, atol=1e-14)
    np.testing.assert_allclose(g[2:], 0.02 + 0.001 * math.cos(ph), rtol=0, atol=1e-14)


# -- nonlinear kinematics against finite differences ---------------------------------------------


def _states(rng, n=6):
    for _ in range(n):
        u = np.zeros(7)
        u[[0, 2, 4, 5]] = rng.uniform(-0.05, 0.05, 4)
        u[[1, 3, 6]] = rng.uniform(-0.08, 0.08, 3)  # rotations up to 4.6°
        yield u


@pytest.mark.parametrize("phi", SKEWS)
def test_nonlinear_gap_rows_and_hessian_against_finite_differences(phi):
    sc = scene_at(phi)
    corners = pack_corners(plan_of(sc))
    rng = np.random.default_rng(int(phi) + 15)
    h = 1e-6
    worst = {"g": 0.0, "wn": 0.0, "wt": 0.0, "hess": 0.0}
    for u in _states(rng):
        g, wn, wt = kin(corners, u, True)
        for c in range(4):
            worst["g"] = max(worst["g"], abs(g[c] - exact_gap(sc, u, c)))
            st = 1 if c < 2 else 3
            t = rot(u[st]) @ reference_corners(sc)[c][3]
            H = np.zeros((7, 7))
            gap_hessian(u, corners, c, H, size_tag(7))
            for j in range(7):
                e = np.zeros(7)
                e[j] = h
                fd = (exact_gap(sc, u + e, c) - exact_gap(sc, u - e, c)) / (2 * h)
                worst["wn"] = max(worst["wn"], abs(wn[c, j] - fd))
                dp = (relative_position(sc, u + e, c) - relative_position(sc, u - e, c)) / (2 * h)
                worst["wt"] = max(worst["wt"], abs(wt[c, j] - t @ dp))
                _, wn_p, _ = kin(corners, u + e, True)
                _, wn_m, _ = kin(corners, u - e, True)
                fd_row = (wn_p[c] - wn_m[c]) / (2 * h)
                worst["hess"] = max(worst["hess"], float(np.max(np.abs(H[:, j] - fd_row))))
            assert np.allclose(H, H.T, rtol=0, atol=0)
    print(f"phi = {phi}: {worst}")
    assert worst["g"] <= 1e-14  # coordinates of ~17 m: 17 eps ≈ 4e-15
    # central differences: O(h²) truncation (levers ~17 m) plus round-off ~1e-16 · 17 / h
    assert worst["wn"] <= 1e-8 and worst["wt"] <= 1e-8
    assert worst["hess"] <= 1e-7


@pytest.mark.parametrize("phi", SKEWS)
def test_linear_rows_are_the_nonlinear_rows_at_rest(phi):
    corners = pack_corners(plan_of(scene_at(phi)))
    _, wn_l, wt_l = kin(corners, np.zeros(7), False)
    _, wn_n, wt_n = kin(corners, np.zeros(7), True)
    np.testing.assert_allclose(wn_l, wn_n, rtol=0, atol=1e-14)
    np.testing.assert_allclose(wt_l, wt_n, rtol=0, atol=1e-14)
    np.testing.assert_allclose(wn_l, plan_of(scene_at(phi)).normal_rows(), rtol=0, atol=0)

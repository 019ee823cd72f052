"""Tests for deckpound.analytic.kernels.lcp (Lemke, enumeration, residuals)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deckpound.analytic.kernels.lcp import (
    LEMKE_RAY,
    LEMKE_SOLVED,
    lcp_enumerate,
    lcp_lemke,
    lcp_residual,
)


def _check_solution(M, q, z, w, tol=1e-12):
    scale = 1.0 + np.abs(q).max()
    # round-off in w = Mz + q grows with |M| |z| (pivoting on singular degenerate bases)
    roundoff = 1e-13 * scale * (1 + np.abs(M).max()) * (1 + np.abs(z).max())
    np.testing.assert_allclose(w, M @ z + q, rtol=0, atol=roundoff)
    nat, fb = lcp_residual(z, w)
    size = scale + np.abs(M).max() * np.abs(z).max()  # magnitude of the terms summed in w
    assert nat <= tol * size, nat
    assert fb <= 10 * tol * size * np.sqrt(len(q)), fb


# ---------------------------------------------------------------- textbook


def test_trivial_q_nonnegative():
    M = np.array([[1.0, 2.0], [3.0, 4.0]])
    q = np.array([1.0, 0.0])
    z, w, status, npiv = lcp_lemke(M, q)
    assert status == LEMKE_SOLVED and npiv == 0
    np.testing.assert_array_equal(z, 0.0)
    np.testing.assert_array_equal(w, q)


def test_2x2_interior_hand_solution():
    # 2 z1 + z2 = 5, z1 + 2 z2 = 6  ->  z = (4/3, 7/3), w = 0
    M = np.array([[2.0, 1.0], [1.0, 2.0]])
    q = np.array([-5.0, -6.0])
    for solver in ("lemke", "enum"):
        if solver == "lemke":
            z, w, status, _ = lcp_lemke(M, q)
        else:
            z, w, status, _ = lcp_enumerate(M, q)
        assert status == 0
        np.testing.assert_allclose(z, [4.0 / 3.0, 7.0 / 3.0], rtol=1e-14)
        np.testing.assert_allclose(w, 0.0, atol=1e-14)


def test_2x2_mixed_hand_solution():
    # z2 = 0 branch: 2 z1 - 5 = 0 -> z1 = 2.5, w2 = 2.5 + 1 = 3.5
    M = np.array([[2.0, 1.0], [1.0, 2.0]])
    q = np.array([-5.0, 1.0])
    z, w, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_SOLVED
    np.testing.assert_allclose(z, [2.5, 0.0], atol=1e-14)
    np.testing.assert_allclose(w, [0.0, 3.5], atol=1e-14)


def test_3x3_hand_solution():
    # M = [[4,-1,0],[-1,4,-1],[0,-1,4]] (a Stieltjes / P-matrix), q = (-3, 6, -3)
    # guess z2 = 0: 4 z1 = 3, 4 z3 = 3 -> z = (3/4, 0, 3/4), w2 = -3/4 + 6 - 3/4 = 4.5
    M = np.array([[4.0, -1.0, 0.0], [-1.0, 4.0, -1.0], [0.0, -1.0, 4.0]])
    q = np.array([-3.0, 6.0, -3.0])
    z, w, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_SOLVED
    np.testing.assert_allclose(z, [0.75, 0.0, 0.75], atol=1e-14)
    np.testing.assert_allclose(w, [0.0, 4.5, 0.0], atol=1e-14)
    ze, _we, st_, _ = lcp_enumerate(M, q)
    assert st_ == 0
    np.testing.assert_allclose(ze, z, atol=1e-14)


@pytest.mark.parametrize("n", [3, 6, 10])
@pytest.mark.parametrize("upper", [False, True])
def test_murty_triangular(n, upper):
    """Murty's (1978) triangular P-matrices, m_ii = 1, m_ij = 2 on one side,
    q = -1: all initial ratios tie (degenerate first step).  Unique solution:
    z = e_1 (lower) or z = e_n (upper) (Murty 1988, Ch. 6; CPS Sec. 6.9)."""
    M = np.eye(n)
    for i in range(n):
        for j in range(n):
            if (j < i and not upper) or (j > i and upper):
                M[i, j] = 2.0
    q = -np.ones(n)
    z, w, status, npiv = lcp_lemke(M, q, 1 << (n + 2))
    assert status == LEMKE_SOLVED
    if not upper:  # Murty: exponential path length 2^n with d = 1
        assert npiv == 2**n
    expect = np.zeros(n)
    expect[-1 if upper else 0] = 1.0
    np.testing.assert_allclose(z, expect, atol=1e-12)
    _check_solution(M, q, z, w)


def test_degenerate_zero_q_component():
    # z3 = w3 = 0 at the solution (degenerate vertex)
    M = np.eye(3)
    q = np.array([-1.0, -1.0, 0.0])
    z, w, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_SOLVED
    np.testing.assert_allclose(z, [1.0, 1.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(w, 0.0, atol=1e-14)


def test_degenerate_singular_psd_nonunique():
    # M = [[1,1],[1,1]] PSD singular; solutions: z1 + z2 = 1, z >= 0
    M = np.array([[1.0, 1.0], [1.0, 1.0]])
    q = np.array([-1.0, -1.0])
    z, w, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_SOLVED
    assert abs(z.sum() - 1.0) < 1e-14 and z.min() >= 0.0
    _check_solution(M, q, z, w)
    ze, we, st_, _ = lcp_enumerate(M, q)
    assert st_ == 0
    _check_solution(M, q, ze, we)


def test_degenerate_repeated_rows():
    # three identical constraints (like coincident corner contacts)
    M = np.ones((3, 3)) * 2.0
    q = np.array([-2.0, -2.0, -2.0])
    z, w, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_SOLVED
    assert abs(z.sum() - 1.0) < 1e-14
    _check_solution(M, q, z, w)


def test_psd_copositive_plus():
    # M = [[1,-1],[-1,1]], q = (-1, 2): z = (1, 0), w = (0, 1)
    M = np.array([[1.0, -1.0], [-1.0, 1.0]])
    q = np.array([-1.0, 2.0])
    z, w, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_SOLVED
    _check_solution(M, q, z, w)
    np.testing.assert_allclose(z - np.array([1.0, 0.0]), z[1] * np.array([1.0, 1.0]), atol=1e-14)


def test_ray_termination_infeasible_skew():
    # M skew-symmetric (copositive-plus), w2 = -z1 - 1 < 0 always: infeasible,
    # Lemke must end on a secondary ray (CPS Thm 4.4.13).
    M = np.array([[0.0, 1.0], [-1.0, 0.0]])
    q = np.array([-1.0, -1.0])
    _z, _w, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_RAY
    _ze, _we, st_, res = lcp_enumerate(M, q)
    assert st_ == 1 and res > 0.5


def test_ray_termination_negative_definite():
    M = -np.eye(2)
    q = np.array([-1.0, -1.0])
    _, _, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_RAY


def test_max_pivots_status():
    # Murty's lower-triangular example needs 2^n pivots
    n = 6
    M = np.eye(n) + 2.0 * np.tril(np.ones((n, n)), -1)
    q = -np.ones(n)
    _, _, status, npiv = lcp_lemke(M, q, 10)
    assert status == 2 and npiv == 10


def test_enumeration_too_large():
    _z, _w, status, _res = lcp_enumerate(np.eye(13), -np.ones(13))
    assert status == 3


def test_residual_values():
    nat, fb = lcp_residual(np.array([1.0, 0.0]), np.array([0.0, 2.0]))
    assert nat == 0.0 and fb == 0.0
    nat, fb = lcp_residual(np.array([-1.0, 2.0]), np.array([3.0, 0.0]))
    assert nat == 1.0
    assert abs(fb - (np.sqrt(10.0) - 2.0)) < 1e-15


# ---------------------------------------------------------------- properties


def _random_p_matrix(rng, n):
    A = rng.normal(size=(n, n))
    S = rng.normal(size=(n, n))
    kind = rng.integers(3)
    if kind == 0:
        return A.T @ A + 1e-3 * np.eye(n)
    if kind == 1:  # positive definite plus skew: P-matrix, non-symmetric
        return A.T @ A + 0.1 * np.eye(n) + rng.uniform(0, 3) * (S - S.T)
    # diagonally dominant non-symmetric
    return A + np.diag(np.abs(A).sum(axis=1) + 0.1)


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 10), logq=st.floats(-3.0, 3.0))
def test_lemke_p_matrix_matches_enumeration(seed, n, logq):
    rng = np.random.default_rng(seed)
    M = _random_p_matrix(rng, n)
    q = rng.normal(size=n) * 10.0**logq
    z, w, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_SOLVED
    _check_solution(M, q, z, w, tol=1e-12)
    ze, _we, st_, _ = lcp_enumerate(M, q)
    assert st_ == 0
    # P-matrix: unique solution
    zs = 1.0 + np.abs(ze).max()
    np.testing.assert_allclose(z, ze, rtol=0, atol=1e-9 * zs)


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 10))
def test_lemke_psd_singular_feasible(seed, n):
    """Copositive-plus (PSD, singular, integer => degenerate) LCPs built to be
    feasible: Lemke must solve them (CPS Thm 4.4.13)."""
    rng = np.random.default_rng(seed)
    A = rng.integers(-2, 3, size=(max(1, n - 2), n)).astype(float)
    S = rng.integers(-1, 2, size=(n, n)).astype(float)
    M = A.T @ A + (S - S.T) * rng.integers(0, 2)
    x = np.maximum(rng.integers(-1, 3, size=n), 0).astype(float)
    y = np.where(x > 0, 0.0, rng.integers(0, 2, size=n).astype(float))
    q = y - M @ x
    z, w, status, _ = lcp_lemke(M, q)
    assert status == LEMKE_SOLVED
    _check_solution(M, q, z, w, tol=1e-12)

"""The step loops' dense solvers (deckpound.analytic.kernels.dense) for any model size (issue 29, item 3).

The LU of the iteration matrices takes its size from a size tag (a tuple whose length is the
size, a compile-time constant of the kernels), not from a module constant, so a model with more
DOF than the one-deck plan (several deck segments) is factored and solved whole. The
rank-revealing solve of the contact problems takes any m from its arrays.
"""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.analytic.kernels.dense import (
    lu_factor,
    lu_solve,
    solve_dense_cp,
    solve_dense_cp_into,
)
from deckpound.analytic.nonsmooth.impulses import size_tag
from deckpound.models.plan import N_DOF


def _spd(rng, n):
    A = rng.standard_normal((n, n))
    return A @ A.T + 0.1 * np.eye(n)


@pytest.mark.parametrize("n", [1, 2, 3, 5, N_DOF, 9, 13, 20])
def test_lu_solves_random_spd_systems_of_every_size(n):
    rng = np.random.default_rng(100 + n)
    for _ in range(5):
        A = _spd(rng, n)
        b = rng.standard_normal(n)
        LU, piv, x = A.copy(), np.zeros(n, dtype=np.int64), np.zeros(n)
        assert lu_factor(LU, piv, size_tag(n))
        lu_solve(LU, piv, b, x, size_tag(n))
        want = np.linalg.solve(A, b)
        np.testing.assert_allclose(x, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
        # the same answer, bit for bit, as exchanging b's rows one swap at a time first and
        # multiplying by the pivots' reciprocals the factors hold on their diagonal
        y = b[piv].copy()
        L, U = np.tril(LU, -1), np.triu(LU)
        for i in range(n):
            s = y[i]
            for j in range(i):
                s -= L[i, j] * y[j]
            y[i] = s
        for i in range(n - 1, -1, -1):
            s = y[i]
            for j in range(i + 1, n):
                s -= U[i, j] * y[j]
            y[i] = s * U[i, i]
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("n", [4, N_DOF, 11])
def test_lu_factors_are_the_row_swapped_product_of_unit_l_and_u(n):
    """P A = L U with the recorded row permutation (row k of the factors is row piv[k] of A)
    and U's pivots stored as their reciprocals, on a matrix that needs pivoting."""
    rng = np.random.default_rng(n)
    A = rng.standard_normal((n, n))
    A[0, 0] = 0.0  # the first pivot must come from another row
    LU, piv = A.copy(), np.zeros(n, dtype=np.int64)
    assert lu_factor(LU, piv, size_tag(n))
    assert piv[0] != 0
    assert sorted(piv.tolist()) == list(range(n))  # a permutation
    L = np.tril(LU, -1) + np.eye(n)
    U = np.triu(LU, 1) + np.diag(1.0 / np.diag(LU))  # the diagonal holds 1 / u_kk
    np.testing.assert_allclose(L @ U, A[piv], atol=1e-12 * np.abs(A).max())


def test_the_size_is_the_tags_not_the_arrays():
    """A 9 × 9 array factored with a tag of 7 is the leading 7 × 7 block's LU, the rest
    untouched: the size comes from the tag."""
    rng = np.random.default_rng(3)
    A = _spd(rng, 9)
    LU, piv = A.copy(), np.full(9, -1, dtype=np.int64)
    assert lu_factor(LU, piv, size_tag(7))
    np.testing.assert_array_equal(LU[7:], A[7:])
    np.testing.assert_array_equal(LU[:, 7:], A[:, 7:])
    assert np.all(piv[7:] == -1)
    b, x = rng.standard_normal(9), np.zeros(9)
    lu_solve(LU, piv, b, x, size_tag(7))
    np.testing.assert_allclose(x[:7], np.linalg.solve(A[:7, :7], b[:7]), rtol=1e-9, atol=1e-12)
    assert np.all(x[7:] == 0.0)


@pytest.mark.parametrize("n", [3, 10])
def test_lu_reports_a_singular_matrix(n):
    A = _spd(np.random.default_rng(n), n)
    A[:, -1] = A[:, 0]  # two equal columns
    A[-1] = 0.0
    assert not lu_factor(A.copy(), np.zeros(n, dtype=np.int64), size_tag(n))
    A = np.eye(n)
    A[1, 1] = np.nan
    assert not lu_factor(A, np.zeros(n, dtype=np.int64), size_tag(n))


@pytest.mark.parametrize("m", [1, 2, 6, 15])
def test_complete_pivoting_solves_full_rank_systems(m):
    rng = np.random.default_rng(m)
    A = rng.standard_normal((m, m))
    b = rng.standard_normal(m)
    x = np.full(m, np.nan)
    rank, consistent = solve_dense_cp(A.copy(), b.copy(), x, 1e-12)
    assert (rank, consistent) == (m, True)
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("m", [3, 8])
def test_complete_pivoting_reveals_the_rank(m):
    """A row that is the sum of two others: rank m − 1; a right-hand side that follows the same
    sum is consistent and solved exactly (a basic solution), one that does not is flagged."""
    rng = np.random.default_rng(10 + m)
    A = rng.standard_normal((m, m))
    A[-1] = A[0] + A[1]
    b = rng.standard_normal(m)
    b[-1] = b[0] + b[1]
    x = np.zeros(m)
    perm, y = np.zeros(m + 2, dtype=np.int64), np.zeros(m + 2)  # scratch may be longer
    rank, consistent = solve_dense_cp_into(A.copy(), b.copy(), x, 1e-12, perm, y)
    assert (rank, consistent) == (m - 1, True)
    np.testing.assert_allclose(A @ x, b, atol=1e-9)
    assert np.count_nonzero(x) == m - 1  # the dropped unknown is 0
    b[-1] += 1.0
    rank, consistent = solve_dense_cp(A.copy(), b.copy(), x, 1e-12)
    assert (rank, consistent) == (m - 1, False)


def test_complete_pivoting_degenerate_systems():
    x = np.full(3, 5.0)
    assert solve_dense_cp(np.zeros((3, 3)), np.zeros(3), x, 1e-12) == (0, True)
    assert np.all(x == 0.0)
    assert solve_dense_cp(np.zeros((3, 3)), np.ones(3), x, 1e-12) == (0, False)
    assert solve_dense_cp(np.zeros((0, 0)), np.zeros(0), np.zeros(0), 1e-12) == (0, True)

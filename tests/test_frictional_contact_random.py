"""Randomised properties of deckpound.analytic.nonsmooth.frictional_contact (hypothesis): the contact
laws hold, the fall-back methods give valid solutions, and impacts with e = 0 dissipate."""

import numpy as np
from _contact_helpers import B_DECK, I_DECK, L_DECK, M_DECK, build, check_laws, kinetic, solve_for
from hypothesis import given, settings
from hypothesis import strategies as st

from deckpound.analytic.nonsmooth.contact_checks import STATUS_ENUM, STATUS_LEMKE, STATUS_LEMKE_ST
from deckpound.analytic.nonsmooth.frictional_contact import MODE_ENUM, MODE_LEMKE_ST

# ------------------------------------------------------ (d) random properties

DECK_CONTACTS = [
    ((L_DECK / 2, B_DECK / 2), (-1.0, 0.0)),
    ((L_DECK / 2, -B_DECK / 2), (-1.0, 0.0)),
    ((L_DECK / 2, B_DECK / 2), (0.0, -1.0)),
    ((-L_DECK / 2, B_DECK / 2), (0.0, -1.0)),
]


def _random_deck_problem(rng, nc):
    """3-DOF deck (+ 4 extra DOFs, 7 in all as in the engine) with a full SPD
    iteration matrix; contacts from one abutment face and the shear keys of
    one side (kinematically compatible set)."""
    Mmat = np.zeros((7, 7))
    Mmat[:3, :3] = np.diag([M_DECK, M_DECK, I_DECK])
    Mmat[3:, 3:] = np.diag(rng.uniform(1e4, 1e6, 4))
    A = rng.normal(size=(7, 7)) * rng.uniform(0, 0.3)
    D = np.sqrt(np.diag(Mmat))
    Mmat = Mmat + (D[:, None] * (A @ A.T) * D[None, :]) / 7
    sel = rng.choice(4, size=nc, replace=False)
    WN, WT = build(Mmat, [DECK_CONTACTS[i] for i in sel])
    # the contacts also see the extra DOFs (pier / abutment flexibility)
    WN[3:, :] = rng.normal(size=(4, nc)) * 0.2
    WT[3:, :] = rng.normal(size=(4, nc)) * 0.2
    return Mmat, WN, WT


@settings(max_examples=250, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    nc=st.integers(1, 4),
    e_zero=st.booleans(),
    mu_max=st.sampled_from([0.0, 0.3, 1.0]),
    free_differs=st.booleans(),
)
def test_random_contact_properties(seed, nc, e_zero, mu_max, free_differs):
    rng = np.random.default_rng(seed)
    Mmat, WN, WT = _random_deck_problem(rng, nc)
    U = rng.normal(size=7) * np.r_[1.0, 1.0, 0.05, 0.1 * np.ones(4)]
    Uf = U + (rng.normal(size=7) * 0.1 if free_differs else 0.0)
    e = np.zeros(nc) if e_zero else rng.uniform(0, 1, nc)
    mu = rng.uniform(0, mu_max, nc)
    res = solve_for(Mmat, WN, WT, U, e, mu, U_free=Uf)
    vs = max(
        np.abs(res["uNf"]).max(), np.abs(res["uTf"]).max(), np.abs(e * res["uNm"]).max(), 1e-300
    )
    assert res["status"] in (STATUS_LEMKE, STATUS_LEMKE_ST, STATUS_ENUM)
    check_laws(res, e, mu, 1e-9 * vs)
    np.testing.assert_allclose(WN.T @ res["Up"], res["uNp"], rtol=0, atol=1e-9 * vs)
    np.testing.assert_allclose(WT.T @ res["Up"], res["uTp"], rtol=0, atol=1e-9 * vs)
    if not free_differs and (e_zero or mu_max == 0.0):
        # no energy gain: e = 0 (any mu), or frictionless with U_N- <= 0 at
        # every contact carrying impulse
        if e_zero or np.all(res["uNm"][res["PN"] > 0] <= 0):
            T0 = kinetic(Mmat, U)
            assert kinetic(Mmat, res["Up"]) <= T0 * (1 + 1e-12)


@settings(max_examples=100, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    nc=st.integers(1, 4),
    mode=st.sampled_from([MODE_LEMKE_ST, MODE_ENUM]),
)
def test_random_fallback_methods_valid(seed, nc, mode):
    rng = np.random.default_rng(seed)
    Mmat, WN, WT = _random_deck_problem(rng, nc)
    U = rng.normal(size=7) * np.r_[1.0, 1.0, 0.05, 0.1 * np.ones(4)]
    e = rng.uniform(0, 1, nc)
    mu = rng.uniform(0, 1, nc)
    res = solve_for(Mmat, WN, WT, U, e, mu, mode=mode)
    vs = max(np.abs(res["uNf"]).max(), np.abs(res["uTf"]).max(), 1e-300)
    assert res["status"] == (STATUS_LEMKE_ST if mode == MODE_LEMKE_ST else STATUS_ENUM)
    check_laws(res, e, mu, 1e-9 * vs)


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), nc=st.integers(1, 4))
def test_random_generic_jacobians_e_zero_dissipative(seed, nc):
    """Arbitrary SPD 7x7 M and arbitrary W, e = 0, U_free = U-: always
    solvable (Anitescu-Potra) and never gains kinetic energy."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(7, 7))
    Mmat = A @ A.T + 0.5 * np.eye(7)
    WN = rng.normal(size=(7, nc))
    WT = rng.normal(size=(7, nc))
    U = rng.normal(size=7)
    mu = rng.uniform(0, 1.5, nc)
    res = solve_for(Mmat, WN, WT, U, np.zeros(nc), mu)
    vs = max(np.abs(res["uNf"]).max(), np.abs(res["uTf"]).max(), 1e-300)
    assert res["status"] in (STATUS_LEMKE, STATUS_LEMKE_ST, STATUS_ENUM)
    check_laws(res, np.zeros(nc), mu, 1e-9 * vs)
    assert kinetic(Mmat, res["Up"]) <= kinetic(Mmat, U) * (1 + 1e-12) + 1e-15

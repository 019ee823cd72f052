"""The nonsmooth engine's contact stage takes its sizes from its arrays (issue 29, item 3).

The next capability (several deck segments, all active contacts of all joints in one LCP) needs
more than the four corners of one deck: the impulse solve of a Moreau–Jean step and the loop's
workspace are sized by their arguments, not by a module constant. Checked here on six corners,
three of them active, against the contact laws and the momentum balance of the step, for the
plan's DOF count and for a larger model (the dense LU takes its size from the size tag, as the
loop does).
"""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.analytic.kernels.dense import lu_factor
from deckpound.analytic.nonsmooth.contact_checks import STATUS_FAILED
from deckpound.analytic.nonsmooth.frictional_contact import MODE_AUTO
from deckpound.analytic.nonsmooth.impulses import impulse_work, size_tag, solve_active_impulses
from deckpound.analytic.nonsmooth.moreau_jean_work import moreau_jean_workspace
from deckpound.models.plan import N_DOF


@pytest.mark.parametrize("n_dof", [N_DOF, N_DOF + 4])
def test_impulses_of_three_active_corners_out_of_six(n_dof):
    rng = np.random.default_rng(7)
    n_corners, mu, e = 6, 0.3, 0.5
    A = rng.standard_normal((n_dof, n_dof))
    W_hat = A @ A.T + n_dof * np.eye(n_dof)  # the iteration matrix Ŵ (SPD)
    LU, piv = W_hat.copy(), np.zeros(n_dof, dtype=np.int64)
    assert lu_factor(LU, piv, size_tag(n_dof))
    WN = rng.standard_normal((n_corners, n_dof))
    WT = rng.standard_normal((n_corners, n_dof))
    act = np.array([1, 3, 4, 0, 0, 0], dtype=np.int64)
    # the active corners approach at about 1 m/s, with some sliding
    v0 = np.linalg.lstsq(WN[act[:3]], -np.ones(3), rcond=None)[0]
    v0 += 0.05 * rng.standard_normal(n_dof)
    vfree = v0.copy()
    P_N, P_T = np.full(n_corners, np.nan), np.full(n_corners, np.nan)
    state, vnew = np.full(n_corners, -1, dtype=np.int64), np.zeros(n_dof)
    status, comp, cone = solve_active_impulses(
        LU,
        piv,
        WN,
        WT,
        act,
        3,
        v0,
        vfree,
        np.full(n_corners, e),
        np.full(n_corners, e),
        np.full(n_corners, mu),
        MODE_AUTO,
        1e-10,
        P_N,
        P_T,
        state,
        vnew,
        impulse_work(n_corners, n_dof),
    )
    assert status != STATUS_FAILED
    inactive = [0, 2, 5]
    assert np.all(P_N[inactive] == 0.0) and np.all(P_T[inactive] == 0.0)
    assert np.all(state[inactive] == 0)
    # momentum balance of the step: Ŵ (v+ − v_free) = W_Nᵀ P_N + W_Tᵀ P_T
    np.testing.assert_allclose(W_hat @ (vnew - vfree), WN.T @ P_N + WT.T @ P_T, atol=1e-10)
    a = act[:3]
    uN_minus, uN_plus, uT_plus = WN[a] @ v0, WN[a] @ vnew, WT[a] @ vnew
    scale = np.max(np.abs(uN_minus))
    assert np.all(uN_minus < 0.0)
    # Newton's impact law and Coulomb's cone at the active corners
    xi = uN_plus + e * uN_minus
    assert np.all(P_N[a] >= 0.0) and np.all(xi >= -1e-9 * scale)
    assert np.all(np.abs(P_N[a] * xi) <= 1e-9 * scale * np.max(P_N[a]))
    assert np.all(np.abs(P_T[a]) <= mu * P_N[a] * (1.0 + 1e-9))
    assert np.any(P_N[a] > 0.0)
    assert max(comp, cone) <= 1e-9 * scale  # the solve's own verified residuals
    slip = np.abs(uT_plus) > 1e-9 * scale
    np.testing.assert_allclose(P_T[a][slip], -mu * P_N[a][slip] * np.sign(uT_plus[slip]))


@pytest.mark.parametrize("n_dof", [N_DOF, N_DOF + 2])
def test_workspace_is_sized_by_its_arguments(n_dof):
    ns, nch, n_corners = 5, 3, 6
    u0 = np.zeros(n_dof)
    work = moreau_jean_workspace(u0, u0.copy(), np.zeros((ns, 17)), ns, nch, n_corners)
    assert work.dof.q.shape == (n_dof,) and work.dof.LU.shape == (n_dof, n_dof)
    assert work.spring.d.shape == (ns,) and np.all(np.isnan(work.spring.kt_fact))
    assert work.corner.gap.shape == (n_corners,)
    assert work.corner.WN.shape == (n_corners, n_dof)
    assert work.ug.shape == (nch,) and work.final.shape == (2, n_dof)
    assert work.impulse.X.shape == (2 * n_corners, n_dof)
    assert work.impulse.G.shape == (2 * n_corners, 2 * n_corners)
    assert len(work.dof_slots) == len(work.impulse.dof_slots) == n_dof
    assert len(work.corner_slots) == n_corners

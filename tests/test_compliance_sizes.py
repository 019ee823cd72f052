"""The compliance engine's loops take their sizes and offsets from their bundles (issue 29, item 3).

The next capability (several deck segments) brings more DOF and more corners than the one-deck
plan model: the Newmark and Dormand–Prince workspaces are sized by their arguments, the work
totals and energy columns are named offsets, and a failed run says the one status text of the
engine contract.
"""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.analytic.compliance.dormand_prince_work import adaptive_workspace
from deckpound.analytic.compliance.newmark_work import newmark_workspace
from deckpound.analytic.compliance.work_energy import (
    E_CONTACT_DISSIPATED,
    E_CONTACT_STORED,
    E_ERROR,
    E_FRICTION,
    E_HYSTERETIC,
    E_INPUT,
    E_KINETIC,
    E_STRAIN,
    E_VISCOUS,
    N_ENERGY,
    N_WORK,
    W_CONTACT,
    W_FRICTION,
    W_INPUT,
    W_SPRINGS,
    W_VISCOUS,
    energy_columns,
)
from deckpound.analytic.kernels import contact_laws as cl
from deckpound.analytic.kernels.system import initial_dofs
from deckpound.api import load_scene, run
from deckpound.models.columns import ENERGY_COLUMNS
from deckpound.models.engine_contract import Status


def test_workspaces_are_sized_by_their_arguments():
    """Nine DOF, six corners, five springs, three channels: no array keeps the 7 or the 4."""
    n_dof, n_corners, ns, nch, nbs = 9, 6, 5, 3, 2
    u0, v0 = np.zeros(n_dof), np.zeros(n_dof)
    cstate = np.zeros((n_corners, cl.N_CS))  # one row per corner
    hstate = np.zeros((ns, 21))
    nm = newmark_workspace(u0, v0, hstate, cstate, ns, nch)
    assert nm.dof.u.shape == (n_dof,) and nm.mat.LU.shape == (n_dof, n_dof)
    assert nm.cw.WN.shape == (n_corners, n_dof) and len(nm.cw.corners) == n_corners
    assert nm.lam_prev.shape == (n_corners,) and nm.spring.kt.shape == (ns,)
    assert nm.support.ug1.shape == (nch,) and nm.W.shape == (N_WORK,)
    ad = adaptive_workspace(u0, v0, hstate, cstate, ns, nch, nbs)
    assert ad.y.shape == (2 * n_dof + N_WORK,) and ad.K.shape == (7, 2 * n_dof + N_WORK)
    # event values: gaps, Takeda rates, gap rates and stick slips
    assert ad.ev0.shape == (n_corners + nbs + 2 * n_corners,)
    assert ad.cw.WT.shape == (n_corners, n_dof) and ad.uc.shape == (n_dof,)


def test_initial_dofs_take_the_model_size():
    u0, v0 = initial_dofs((np.arange(9.0), np.ones(9)), 9)
    assert u0.tolist() == list(range(9)) and v0.tolist() == [1.0] * 9
    with pytest.raises(ValueError, match="initial_state u0 must be 9 finite numbers"):
        initial_dofs((np.zeros(7), np.zeros(9)), 9)


def test_energy_columns_close_the_work_balance():
    """Every column at its named offset; hysteretic + strain = spring work, the contact and
    friction columns share the contact and friction work, and error = input − the rest."""
    assert len(ENERGY_COLUMNS) == N_ENERGY
    names = {
        E_INPUT: "energy_input",
        E_KINETIC: "energy_kinetic",
        E_STRAIN: "energy_strain",
        E_VISCOUS: "energy_viscous",
        E_HYSTERETIC: "energy_hysteretic",
        E_CONTACT_STORED: "energy_contact_stored",
        E_CONTACT_DISSIPATED: "energy_contact_dissipated",
        E_FRICTION: "energy_friction",
        E_ERROR: "energy_error",
    }
    assert [names[k] for k in range(N_ENERGY)] == list(ENERGY_COLUMNS)
    W = np.zeros(N_WORK)
    W[W_INPUT], W[W_SPRINGS], W[W_VISCOUS], W[W_CONTACT], W[W_FRICTION] = 10.0, 4.0, 3.0, 1.5, 0.5
    ke, es, ec, efs = 2.0, 2.5, 0.75, 0.25
    base = 3
    out = np.full(base + N_ENERGY, np.nan)
    energy_columns(out, base, W, ke, es, ec, efs)
    e = out[base:]
    assert np.all(np.isnan(out[:base]))
    assert e[E_INPUT] == W[W_INPUT] and e[E_KINETIC] == ke and e[E_VISCOUS] == W[W_VISCOUS]
    assert e[E_STRAIN] + e[E_HYSTERETIC] == W[W_SPRINGS]
    contact = e[E_CONTACT_STORED] + e[E_CONTACT_DISSIPATED] + e[E_FRICTION]
    assert contact == pytest.approx(W[W_CONTACT] + W[W_FRICTION])
    others = sum(e[k] for k in range(N_ENERGY) if k not in (E_INPUT, E_ERROR))
    assert e[E_ERROR] == pytest.approx(e[E_INPUT] - others)


def test_a_failed_newmark_run_says_the_contract_status_text():
    """One status text table (models.engine_contract.Status.text): the Newton loop adds only
    which test failed."""
    scene = load_scene(
        "saiidi-4span",
        set={
            "excitation.duration": 0.2,
            "compliance.tolerance": 1e-30,
            "compliance.max_iterations": 2,
        },
    )
    res = run(scene, engine="compliance", substeps=1)
    assert res.meta["failure"] == Status.NOT_CONVERGED.value
    assert res.meta["message"].startswith(Status.NOT_CONVERGED.text + " (Newton, NormDispIncr")

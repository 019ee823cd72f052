"""The Newmark–Newton loop's options, workspace and output rows (:mod:`.newmark`).

:data:`NewmarkOptions` (the loop's scalars), the workspace bundles and
:func:`newmark_workspace` that allocates them (the loop itself runs without numba's runtime and
cannot allocate), and the per-row kernels: :func:`output_energies` (the energy columns from
the running work totals), :func:`store_row` (one row of the result table) and :func:`fill_row`
(its engine columns, also every step's row of the peaks).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic._jit import kernel
from deckpound.analytic.compliance.work_energy import (
    N_ENERGY,
    N_WORK,
    energy_columns,
    stick_spring_energy,
)
from deckpound.analytic.kernels import contact_laws as cl
from deckpound.analytic.kernels.contact_assembly import N_TANGENT_DERIVATIVES
from deckpound.analytic.kernels.system import (
    end_column,
    spring_stored_energy,
    store_standard,
    tangential_force_column,
)

__all__ = [
    "NewmarkOptions",
    "NewmarkWork",
    "fill_row",
    "newmark_workspace",
    "output_energies",
    "store_row",
]

#: The scalars of :func:`newmark_run`: ``nsteps`` steps of ``dt`` [s]; Newton ``tol`` [m]
#: (NormDispIncr) and ``maxit``; output every ``stride`` steps; ``substeps`` of the fallback
#: for a failed step (≤ 1: none); the work-saving skips (bool, True = on, the default; results
#: are identical either way, see ``compliance.SKIPS``): ``skip_contact`` (contact laws and
#: contact tangent skipped while every gap is open), ``reuse_factors`` (the tangent
#: factorisation reused while the matrix is bitwise the last one), ``skip_unmoved`` (no force
#: evaluation at a converged iterate whose last increment left every displacement bitwise
#: unchanged: only the spring and gap rates are updated); ``want_energy`` (energy work
#: terms accumulated; False when no energy column is requested); ``flush_subnormals``
#: (``compliance.subnormals = "flush"``, :mod:`deckpound.analytic.fp_mode`).
NewmarkOptions = namedtuple(
    "NewmarkOptions",
    [
        "nsteps",
        "dt",
        "tol",
        "maxit",
        "stride",
        "substeps",
        "skip_contact",
        "reuse_factors",
        "skip_unmoved",
        "want_energy",
        "flush_subnormals",
    ],
)
# workspace rows by shape: (n_dof,) DOF vectors, (n_dof, n_dof) matrices, (n_dof,) pivots, (ns,)
# per spring, (n_corners,) per corner, (n_channels,) supports
_V7 = ("u", "v", "a", "un", "vn", "an", "us", "vs", "as_", "du", "R", "f")
_M77 = ("K", "Keff", "LU", "H", "Kel", "LUel")
_PIV = ("piv", "pivel")
_NS = ("fs", "kt", "kt_fact", "d_prev", "dd_prev", "fs_prev", "d_new", "dd_new", "cv_prev")
_V4 = ("lam_prev", "lt_prev", "g_prev")
_CH = ("ug", "vg", "ugo", "ug0", "vg0", "ug1", "vg1")
#: DOF vectors (n_dof,): u, v, a trial state, un, vn, an start of the (sub)step, us, vs, as_ start
#: of the step, du Newton increment, R residual, f internal force.
NewmarkDofs = namedtuple("NewmarkDofs", _V7)
#: (n_dof, n_dof) matrices: K, Keff, LU (tangent, effective tangent, its factors), H gap Hessian, Kel,
#: LUel (elastic effective tangent and factors); row permutations piv, pivel (n_dof,) int64
#: (:func:`deckpound.analytic.kernels.dense.lu_factor`); the contact part of the key of the
#: factors held in LU: ev_fact (n_corners,) bool the corners whose contact tangent they contain,
#: der_fact (n_corners, N_TANGENT_DERIVATIVES) those corners' law derivatives
#: (:data:`deckpound.analytic.kernels.contact_assembly.N_TANGENT_DERIVATIVES`).
NewmarkMatrices = namedtuple("NewmarkMatrices", _M77 + _PIV + ("ev_fact", "der_fact"))
#: Per spring (ns,): fs, kt forces and tangents, kt_fact tangents of the factors held in LU,
#: d/dd/fs_prev last committed, d/dd_new trial deformations and rates, cv_prev the last committed
#: tangent-dependent damping coefficient βK k_t + βKc k_c.
NewmarkSprings = namedtuple("NewmarkSprings", _NS)
#: Supports (n_channels,): ug, vg trial, ugo last (sub)step, ug0, vg0 start and ug1, vg1 end of
#: the step.
NewmarkSupports = namedtuple("NewmarkSupports", _CH)
#: The workspace of :func:`newmark_run` (:func:`newmark_workspace`), one named field per array,
#: grouped by shape (a group is loaded as one value in the compiled code: small groups keep
#: the compile short): u0, v0 initial state; hstate (ns, N_STATE) Takeda states, cstate
#: (n_corners, N_CS) corner states; cw the ContactWork; dof, mat, spring, support the groups
#: above; lam/lt/g_prev last committed contact forces and gaps (n_corners,); W (N_WORK,) running
#: work totals [kJ] (offsets ``W_*`` of :mod:`.work_energy`); energy (N_ENERGY,) the output
#: energies.
NewmarkWork = namedtuple(
    "NewmarkWork",
    ("u0", "v0", "hstate", "cstate", "cw", "dof", "mat", "spring", "support")
    + _V4
    + ("W", "energy"),
)


def newmark_workspace(u0, v0, hstate, cstate, ns: int, nch: int) -> NewmarkWork:
    """The workspace of :func:`newmark_run` (zeroed; ns springs, nch support channels) around
    the initial state u0, v0 (n_dof,) and the virgin material and corner states (cstate: one
    row per corner). Allocated here because the kernel runs without numba's runtime."""
    nd = u0.shape[0]
    nc = cstate.shape[0]
    return NewmarkWork(
        u0=u0,
        v0=v0,
        hstate=hstate,
        cstate=cstate,
        cw=bd.new_contact_work(nc, nd),
        dof=NewmarkDofs(**bd.row_views(_V7, nd)),
        mat=NewmarkMatrices(
            **bd.row_views(_M77, nd, nd),
            **bd.row_views(_PIV, nd, dtype=np.int64),
            ev_fact=np.zeros(nc, dtype=np.bool_),
            der_fact=np.zeros((nc, N_TANGENT_DERIVATIVES)),
        ),
        spring=NewmarkSprings(**bd.row_views(_NS, ns)),
        support=NewmarkSupports(**bd.row_views(_CH, nch)),
        **bd.row_views(_V4, nc),
        W=np.zeros(N_WORK),
        energy=np.zeros(N_ENERGY),
    )


@kernel(inline="always")
def fill_row(buf, layout, t, u, v, cw, cs, fs):
    """The engine columns of the state (t, u, v) into ``buf`` in ``layout``
    (:func:`deckpound.analytic.kernels.system.store_standard`): every output row, and every
    step's row of the peaks (:mod:`.peaks`)."""
    store_standard(buf, layout, t, u, v, cw.g, cw.lam, cw.lt, fs)
    # ft: the committed tangential force (the trial one for every model but contact2d, whose
    # element reports 0 after a sliding commit, as OpenSees's recorders see it)
    c_ft = tangential_force_column(layout)
    for c in range(len(cw.corners)):
        buf[c_ft + c] = cs[c, cl.S_CFT]


@kernel
def store_row(output, row, t, u, v, cw, cs, fs, energy):
    """Output row ``row``: the full row into ``output.row`` (engine columns in the layout
    ``output.peaks.layout``, then the energies), the selected columns into ``output.table``."""
    buf = output.row
    layout = output.peaks.layout
    fill_row(buf, layout, t, u, v, cw, cs, fs)
    base = end_column(layout)
    for k in range(energy.shape[0]):
        buf[base + k] = energy[k]
    sel = output.select
    table = output.table
    for q in range(sel.shape[0]):
        table[row, q] = buf[sel[q]]


@kernel
def output_energies(sa, hstate, cp, cs, u, v, ug, W, energy):
    """Output energies (:func:`.work_energy.energy_columns`) from the running work totals W
    at the committed state (u, u̇, supports ug)."""
    ke = 0.0
    for j in range(len(sa.dofs)):
        ke += 0.5 * sa.mass[j] * v[j] * v[j]
    es = spring_stored_energy(sa, hstate, u, ug)
    ec = cl.contact_stored_energy(cp, cs)
    energy_columns(energy, 0, W, ke, es, ec, stick_spring_energy(cp, cs))

"""The Moreau–Jean loop's options, workspace and output rows (:mod:`.moreau_jean`).

:data:`MoreauJeanOptions` (the loop's scalars), the workspace bundles and
:func:`moreau_jean_workspace` that allocates them (the loop runs without numba's runtime and
cannot allocate; the contact solve's scratch included), and the two per-output-row kernels:
:func:`output_energies` (the energy columns from the running work totals) and
:func:`store_row` (one row of the result table).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic._jit import kernel
from deckpound.analytic.impulses import impulse_work
from deckpound.analytic.nonsmooth import ENERGY_COLUMNS
from deckpound.analytic.system import C_BENT as _C_BENT
from deckpound.analytic.system import spring_stored_energy, store_standard

__all__ = [
    "N_ENERGY",
    "MoreauJeanOptions",
    "MoreauJeanWork",
    "moreau_jean_workspace",
    "output_energies",
    "store_row",
]

N_ENERGY = len(ENERGY_COLUMNS)

#: The scalars of :func:`moreau_jean_run`: ``nsteps`` steps of length ``h`` [s], ``theta``;
#: restitution ``ecoef`` of approaching corners and ``esep`` of separating ones
#: (:func:`deckpound.analytic.nonsmooth.separating_restitution`); friction coefficient ``mu``;
#: contact solver ``mode`` (:mod:`deckpound.analytic.frictional_contact` ``MODE_*``); ``rtol``
#: relative acceptance of the contact solution; ``ftol`` [kN] Newton acceptance of the spring
#: forces and ``maxit`` Newton iterations; output every ``stride`` steps; ``flush_subnormals``
#: (``nonsmooth.subnormals = "flush"``, :mod:`deckpound.analytic.fp_mode`).
MoreauJeanOptions = namedtuple(
    "MoreauJeanOptions",
    [
        "nsteps",
        "h",
        "theta",
        "ecoef",
        "esep",
        "mu",
        "mode",
        "rtol",
        "ftol",
        "maxit",
        "stride",
        "flush_subnormals",
    ],
)
_V7 = ("q", "v", "qk", "vk", "qM", "vfree", "vnew", "R", "dv", "Fk", "f")
_NS = (
    "kt_fact",
    "d_k",
    "dd_k",
    "fs_k",
    "kt_k",
    "d_lin",
    "fs_lin",
    "kt_lin",
    "d",
    "dd",
    "fs",
    "kt",
    "sdu",
    "sdv",
)
_V4 = ("gap", "gapo", "P_N", "P_T", "pn_acc", "pt_acc", "fn_out", "ft_out")
_CH = ("ug", "vg", "ugo", "vgo")
_CORNER = _V4 + ("WN", "WT", "WNo", "WTo", "act", "state", "was_active")
#: DOF vectors (7,): q, v iterate, qk, vk start of step, qM mid-step prediction, vfree, vnew
#: free and post-contact velocities, R residual, dv, Fk smooth force at the start, f at the
#: iterate; K, LU tangent and iteration-matrix factors (7, 7), piv (7,) int64.
MoreauJeanDofs = namedtuple("MoreauJeanDofs", _V7 + ("K", "LU", "piv"))
#: Per spring (ns,): kt_fact tangents of the factors held (NaN: none), committed d_k, dd_k,
#: fs_k, kt_k, linearisation point d_lin, fs_lin, kt_lin, iterate d, dd, fs, kt, and sdu, sdv =
#: S Δu_g, S Δu̇_g.
MoreauJeanSprings = namedtuple("MoreauJeanSprings", _NS)
#: Per corner (4,): gap (mid-step), gapo (output), impulses P_N, P_T, accumulated pn_acc,
#: pt_acc, output forces fn_out, ft_out; rows WN, WT (mid-step) and WNo, WTo (output) (4, 7);
#: act, state int64 active corners and contact states, was_active bool.
MoreauJeanCorners = namedtuple("MoreauJeanCorners", _CORNER)
#: The workspace of :func:`moreau_jean_run` (:func:`moreau_jean_workspace`), one named field
#: per array, grouped (a group is loaded as one value in the compiled code: small groups keep
#: the compile short): u0, v0 initial state; hstate (ns, 17) Takeda states; final (2, 7)
#: displacement and velocity at the last accepted step; dof, spring, corner the groups above;
#: ug, vg, ugo, vgo supports now and at the last step; W (6,) running work totals [kJ];
#: energy (N_ENERGY,); impulse the contact solve's scratch (:func:`.impulses.impulse_work`).
MoreauJeanWork = namedtuple(
    "MoreauJeanWork",
    ("u0", "v0", "hstate", "final", "dof", "spring", "corner") + _CH + ("W", "energy", "impulse"),
)


@kernel
def output_energies(sa, hstate, q, v, ug, W, energy):
    """Output energies from the running totals W = [input, spring work, viscous, impact,
    friction, numerical]."""
    ke = 0.0
    for j in range(7):
        ke += 0.5 * sa.mass[j] * v[j] * v[j]
    es = spring_stored_energy(sa, hstate, q, ug)
    energy[0] = W[0]
    energy[1] = ke
    energy[2] = es
    energy[3] = W[2]
    energy[4] = W[1] - es
    energy[5] = W[3]
    energy[6] = W[4]
    energy[7] = W[5]
    energy[8] = W[0] - (ke + W[1] + W[2] + W[3] + W[4] + W[5])


@kernel
def store_row(output, row, t, q, v, g, fn, ft, fs, nbs, pn, pt, state, energy):
    """Output row ``row``: standard columns, impulses, contact states and energies into the
    full-row buffer ``output.row``, the selected columns into ``output.table``."""
    buf = output.row
    store_standard(buf, t, q, v, g, fn, ft, fs, nbs)
    base = _C_BENT + nbs
    for c in range(4):
        buf[base + c] = pn[c]
        buf[base + 4 + c] = pt[c]
        buf[base + 8 + c] = state[c]
    base += 12
    for k in range(energy.shape[0]):
        buf[base + k] = energy[k]
    sel = output.select
    table = output.table
    for k in range(sel.shape[0]):
        table[row, k] = buf[sel[k]]


def moreau_jean_workspace(u0, v0, hstate, ns: int, nch: int) -> MoreauJeanWork:
    """The workspace of :func:`moreau_jean_run` (ns springs, nch support channels) around the
    initial state u0, v0 (7,) and the virgin Takeda states. Allocated here because the kernel
    runs without numba's runtime."""
    wns = bd.row_views(_NS, ns)
    wns["kt_fact"][:] = np.nan  # no factorisation held yet
    dof = MoreauJeanDofs(
        **bd.row_views(_V7, 7), **bd.row_views(("K", "LU"), 7, 7), piv=np.zeros(7, dtype=np.int64)
    )
    corner = MoreauJeanCorners(
        **bd.row_views(_V4, 4),
        **bd.row_views(("WN", "WT", "WNo", "WTo"), 4, 7),
        **bd.row_views(("act", "state"), 4, dtype=np.int64),
        was_active=np.zeros(4, dtype=np.bool_),
    )
    return MoreauJeanWork(
        u0=u0,
        v0=v0,
        hstate=hstate,
        final=np.zeros((2, 7)),
        dof=dof,
        spring=MoreauJeanSprings(**wns),
        corner=corner,
        **bd.row_views(_CH, nch),
        W=np.zeros(6),
        energy=np.zeros(N_ENERGY),
        impulse=impulse_work(4),
    )

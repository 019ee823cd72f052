"""The scalars and the workspace of the Dormand–Prince loop (:func:`.dormand_prince.adaptive_run`).

The accepted-step-size histogram,
:data:`AdaptiveOptions` and :func:`adaptive_workspace` (every array the loop uses, allocated
once per run: the loop itself cannot allocate, see :mod:`deckpound.analytic._jit`).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic.compliance.work_energy import N_WORK

__all__ = [
    "HSTAT_MAX",
    "HSTAT_MIN",
    "HSTAT_SUM",
    "H_BINS_PER_DECADE",
    "H_LOG_MIN",
    "H_NBINS",
    "ROW_CONTACT",
    "ROW_FREE",
    "AdaptiveOptions",
    "AdaptiveWork",
    "adaptive_workspace",
]

# accepted-step-size statistics: log10(h) histogram, H_BINS_PER_DECADE bins per decade from
# 10**H_LOG_MIN to 1 s, row 0 = out of contact, row 1 = in contact (a gap ≤ 0 at either end)
H_LOG_MIN = -14.0
H_BINS_PER_DECADE = 20
H_NBINS = int(-H_LOG_MIN) * H_BINS_PER_DECADE
#: rows of the step-size statistics (hist, hstat): steps out of contact, in contact
ROW_FREE, ROW_CONTACT = 0, 1
#: columns of hstat: smallest, largest and summed accepted step [s]
HSTAT_MIN, HSTAT_MAX, HSTAT_SUM = range(3)


#: The scalars of :func:`adaptive_run`: end time ``t_end`` and output interval ``out_dt`` [s];
#: error tolerances ``rtol`` [-] and ``atol`` [m, m/s]; largest step ``max_step`` and, once a
#: Takeda spring has yielded, ``commit_step`` [s]; step budget ``max_steps`` (Runge–Kutta steps
#: tried, accepted or rejected: each costs the same work); ``flush_subnormals``
#: (``compliance.subnormals = "flush"``, :mod:`deckpound.analytic.fp_mode`).
AdaptiveOptions = namedtuple(
    "AdaptiveOptions",
    [
        "t_end",
        "out_dt",
        "rtol",
        "atol",
        "max_step",
        "commit_step",
        "max_steps",
        "flush_subnormals",
    ],
)
_NS = ("d", "dd", "fs", "kt")
_NT = ("y", "k1", "ytmp", "ynew", "yev")
#: The workspace of :func:`adaptive_run` (:func:`adaptive_workspace`): u0, v0 initial state;
#: hstate, cstate material and corner states; cw the ContactWork; uc (n_dof,) displacement at the
#: last commit; ug, vg supports; d, dd, fs, kt (ns,) spring deformations, rates, forces,
#: tangents; f (n_dof,) internal force; y, k1, ytmp, ynew, yev (2 n_dof + N_WORK,) state [u,
#: u̇, work totals (:mod:`.work_energy`)], its rate, stage / new / interpolated states; K (7,
#: 2 n_dof + N_WORK) the rates of the seven stages; ev0, ev1 event values at the step's ends
#: (n_corners + nbs + 2 n_corners, :func:`.dormand_prince._events`); hist (2, H_NBINS) int64
#: and hstat (2, 3) accepted-step-size statistics (rows ``ROW_FREE``, ``ROW_CONTACT``; hstat
#: columns ``HSTAT_MIN``, ``HSTAT_MAX``, ``HSTAT_SUM``).
AdaptiveWork = namedtuple(
    "AdaptiveWork",
    ("u0", "v0", "hstate", "cstate", "cw", "uc", "ug", "vg", "f")
    + _NS
    + _NT
    + ("K", "ev0", "ev1", "hist", "hstat"),
)


def adaptive_workspace(u0, v0, hstate, cstate, ns: int, nch: int, nbs: int) -> AdaptiveWork:
    """The workspace of :func:`adaptive_run` (zeroed) around the initial state u0, v0 (n_dof,)
    and the virgin material and corner states (cstate: one row per corner); ns springs, nch
    channels, nbs bent springs."""
    nd = u0.shape[0]
    nc = cstate.shape[0]
    nt = 2 * nd + N_WORK
    nev = nc + nbs + 2 * nc
    return AdaptiveWork(
        u0=u0,
        v0=v0,
        hstate=hstate,
        cstate=cstate,
        cw=bd.new_contact_work(nc, nd),
        uc=np.zeros(nd),
        ug=np.zeros(nch),
        vg=np.zeros(nch),
        f=np.zeros(nd),
        **bd.row_views(_NS, ns),
        **bd.row_views(_NT, nt),
        K=np.zeros((7, nt)),
        ev0=np.zeros(nev),
        ev1=np.zeros(nev),
        hist=np.zeros((2, H_NBINS), dtype=np.int64),
        hstat=np.zeros((2, 3)),
    )

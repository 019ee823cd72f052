"""The Moreau–Jean loop's options, workspace, named offsets and output rows (:mod:`.moreau_jean`).

:data:`MoreauJeanOptions` (the loop's scalars), the workspace bundles and
:func:`moreau_jean_workspace` that allocates them (the loop runs without numba's runtime and
cannot allocate; the contact solve's scratch included), the named offsets of the running work
totals (``W_*``) and of the energy columns (``E_*``), and the two per-output-row kernels:
:func:`output_energies` (the energy columns from the running work totals) and
:func:`store_row` (one row of the result table). The array sizes (DOFs, corners, springs,
support channels) are those of the arrays given to :func:`moreau_jean_workspace`; the kernels
read them from the arrays' shapes.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic._jit import kernel
from deckpound.analytic.kernels.size_tags import corner_slots, dof_slots
from deckpound.analytic.kernels.system import end_column, spring_stored_energy, store_standard
from deckpound.analytic.nonsmooth.impulses import impulse_work

__all__ = [
    "ENERGY_COLUMNS",
    "FINAL_U",
    "FINAL_V",
    "N_ENERGY",
    "N_WORK",
    "MoreauJeanOptions",
    "MoreauJeanWork",
    "impulse_columns",
    "moreau_jean_workspace",
    "output_energies",
    "store_row",
]

#: Energy columns of the nonsmooth result, in the order the kernel writes them [kJ].
ENERGY_COLUMNS = (
    "energy_input",
    "energy_kinetic",
    "energy_strain",
    "energy_viscous",
    "energy_hysteretic",
    "energy_impact",
    "energy_friction",
    "energy_numerical",
    "energy_error",
)
N_ENERGY = len(ENERGY_COLUMNS)
(E_INPUT, E_KINETIC, E_STRAIN, E_VISCOUS, E_HYSTERETIC, E_IMPACT, E_FRICTION, E_NUMERICAL,
 E_ERROR) = range(N_ENERGY)  # fmt: skip


def impulse_columns(corner_names) -> tuple[str, ...]:
    """Per-corner extras of the nonsmooth result, in kernel order (:func:`store_row`): the
    impulses ``pn_<corner>``, ``pt_<corner>`` and the contact states ``state_<corner>`` of the
    corners named ``corner_names`` (the plan's ``Corner.name``, in the corners' order)."""
    names = tuple(corner_names)
    return tuple(f"{kind}_{c}" for kind in ("pn", "pt", "state") for c in names)


#: The running work totals ``work.W`` [kJ], by name: work of the support reactions plus the
#: initial mechanical energy (input), spring work Σ Δdᵀ f_s,θ, viscous work, impact and
#: friction work of the impulses, numerical dissipation Σ (θ − ½) Δvᵀ M Δv.
W_NAMES = ("input", "spring", "viscous", "impact", "friction", "numerical")
N_WORK = len(W_NAMES)
W_INPUT, W_SPRING, W_VISCOUS, W_IMPACT, W_FRICTION, W_NUMERICAL = range(N_WORK)
#: Rows of ``work.final``: displacement and velocity at the last accepted step.
FINAL_U, FINAL_V = 0, 1

#: The options of :func:`moreau_jean_run`: ``nsteps`` steps of length ``h`` [s], ``theta``;
#: per corner (n_corners,) arrays: restitution ``ecoef`` of an approaching corner and ``esep``
#: of a separating one (:func:`deckpound.analytic.nonsmooth.engine.separating_restitution`),
#: friction coefficient ``mu``;
#: contact solver ``mode`` (:mod:`deckpound.analytic.nonsmooth.frictional_contact` ``MODE_*``); ``rtol``
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
_DOF_VECTORS = ("q", "v", "qk", "vk", "qM", "vfree", "vnew", "R", "dv", "Fk", "f")
_SPRING_VECTORS = (
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
_CORNER_VECTORS = ("gap", "gapo", "P_N", "P_T", "pn_acc", "pt_acc", "fn_out", "ft_out")
_CHANNEL_VECTORS = ("ug", "vg", "ugo", "vgo")
_CORNER_FIELDS = _CORNER_VECTORS + ("WN", "WT", "WNo", "WTo", "act", "state", "was_active")
#: DOF vectors (n_dof,): q, v iterate, qk, vk start of step, qM mid-step prediction, vfree,
#: vnew free and post-contact velocities, R residual, dv, Fk smooth force at the start, f at
#: the iterate; K, LU tangent and iteration-matrix factors (n_dof, n_dof), piv (n_dof,) int64.
MoreauJeanDofs = namedtuple("MoreauJeanDofs", _DOF_VECTORS + ("K", "LU", "piv"))
#: Per spring (ns,): kt_fact tangents of the factors held (NaN: none), committed d_k, dd_k,
#: fs_k, kt_k, linearisation point d_lin, fs_lin, kt_lin, iterate d, dd, fs, kt, and sdu, sdv =
#: S Δu_g, S Δu̇_g.
MoreauJeanSprings = namedtuple("MoreauJeanSprings", _SPRING_VECTORS)
#: Per corner (n_corners,): gap (mid-step), gapo (output), impulses P_N, P_T, accumulated
#: pn_acc, pt_acc, output forces fn_out, ft_out; rows WN, WT (mid-step) and WNo, WTo (output)
#: (n_corners, n_dof); act, state int64 active corners and contact states, was_active bool.
MoreauJeanCorners = namedtuple("MoreauJeanCorners", _CORNER_FIELDS)
#: The workspace of :func:`moreau_jean_run` (:func:`moreau_jean_workspace`), one named field
#: per array, grouped (a group is loaded as one value in the compiled code: small groups keep
#: the compile short): u0, v0 initial state; hstate (ns, N_STATE) Takeda states; final (2, n_dof)
#: displacement and velocity at the last accepted step; dof, spring, corner the groups above;
#: ug, vg, ugo, vgo supports now and at the last step; W (N_WORK,) running work totals [kJ]
#: (``W_*``); energy (N_ENERGY,) (``E_*``); impulse the contact solve's scratch
#: (:func:`.impulses.impulse_work`).
#: ``dof_slots``, ``corner_slots``: the size tags (:mod:`deckpound.analytic.kernels.size_tags`) of n_dof and n_corners.
MoreauJeanWork = namedtuple(
    "MoreauJeanWork",
    ("u0", "v0", "hstate", "final", "dof", "spring", "corner")
    + _CHANNEL_VECTORS
    + ("W", "energy", "impulse", "dof_slots", "corner_slots"),
)


@kernel
def output_energies(sa, hstate, q, v, ug, W, energy):
    """The energy columns (``E_*``) from the running work totals W (``W_*``) [kJ]: kinetic
    ½ vᵀMv and strain energy at the state, hysteretic = spring work − strain, error = input −
    all the others."""
    ke = 0.0
    for j in range(v.shape[0]):
        ke += 0.5 * sa.mass[j] * v[j] * v[j]
    es = spring_stored_energy(sa, hstate, q, ug)
    energy[E_INPUT] = W[W_INPUT]
    energy[E_KINETIC] = ke
    energy[E_STRAIN] = es
    energy[E_VISCOUS] = W[W_VISCOUS]
    energy[E_HYSTERETIC] = W[W_SPRING] - es
    energy[E_IMPACT] = W[W_IMPACT]
    energy[E_FRICTION] = W[W_FRICTION]
    energy[E_NUMERICAL] = W[W_NUMERICAL]
    energy[E_ERROR] = W[W_INPUT] - (
        ke + W[W_SPRING] + W[W_VISCOUS] + W[W_IMPACT] + W[W_FRICTION] + W[W_NUMERICAL]
    )


@kernel
def store_row(output, row, t, q, v, g, fn, ft, fs, pn, pt, state, energy):
    """Output row ``row``: the engine columns in the layout ``output.peaks.layout``, then per
    corner the impulses pn, pt and the contact states (:func:`impulse_columns`) and the
    energies (:data:`ENERGY_COLUMNS`) into the full-row buffer ``output.row``, the selected
    columns into ``output.table``."""
    buf = output.row
    layout = output.peaks.layout
    store_standard(buf, layout, t, q, v, g, fn, ft, fs)
    n_corners = len(layout.corners)
    base = end_column(layout)
    for c in range(n_corners):
        buf[base + c] = pn[c]
        buf[base + n_corners + c] = pt[c]
        buf[base + 2 * n_corners + c] = state[c]
    base += 3 * n_corners
    for k in range(energy.shape[0]):
        buf[base + k] = energy[k]
    sel = output.select
    table = output.table
    for k in range(sel.shape[0]):
        table[row, k] = buf[sel[k]]


def moreau_jean_workspace(u0, v0, hstate, ns: int, nch: int, n_corners: int) -> MoreauJeanWork:
    """The workspace of :func:`moreau_jean_run` for ``ns`` springs, ``nch`` support channels
    and ``n_corners`` contact corners around the initial state u0, v0 (n_dof,) and the virgin
    Takeda states. Allocated here because the kernel runs without numba's runtime. Any n_dof:
    the loop, the dense LU of the iteration matrix and the contact solve take it from the size
    tag ``dof_slots`` (compiled once per model size)."""
    n_dof = u0.shape[0]
    springs = bd.row_views(_SPRING_VECTORS, ns)
    springs["kt_fact"][:] = np.nan  # no factorisation held yet
    dof = MoreauJeanDofs(
        **bd.row_views(_DOF_VECTORS, n_dof),
        **bd.row_views(("K", "LU"), n_dof, n_dof),
        piv=np.zeros(n_dof, dtype=np.int64),
    )
    corner = MoreauJeanCorners(
        **bd.row_views(_CORNER_VECTORS, n_corners),
        **bd.row_views(("WN", "WT", "WNo", "WTo"), n_corners, n_dof),
        **bd.row_views(("act", "state"), n_corners, dtype=np.int64),
        was_active=np.zeros(n_corners, dtype=np.bool_),
    )
    return MoreauJeanWork(
        u0=u0,
        v0=v0,
        hstate=hstate,
        final=np.zeros((2, n_dof)),  # rows FINAL_U, FINAL_V
        dof=dof,
        spring=MoreauJeanSprings(**springs),
        corner=corner,
        **bd.row_views(_CHANNEL_VECTORS, nch),
        W=np.zeros(N_WORK),
        energy=np.zeros(N_ENERGY),
        impulse=impulse_work(n_corners, n_dof),
        dof_slots=dof_slots(n_dof),
        corner_slots=corner_slots(n_corners),
    )

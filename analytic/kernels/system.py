"""Smooth (contact-free) forces of the 7-DOF model, packed once and evaluated in numba.

This module is the one implementation of the bent and seat springs, their dashpots and the
Rayleigh damping that the compliance engine (:mod:`deckpound.analytic.compliance.engine`) and the
nonsmooth engine share. It knows nothing about contact.

Model (the same as the OpenSees engine, see :mod:`deckpound.models.mechanics`)
------------------------------------------------------------------------------
DOFs u = [x₁, θ₁, x₂, θ₂, x_d, y_d, θ_d]. Spring deformations and rates

    d = B u − S u_g(t),        ḋ = B u̇ − S u̇_g(t)

(u_g, u̇_g: support displacement and velocity per channel of
:func:`deckpound.models.mechanics.support_channels`). The generalised internal force is

    F(u, u̇) = Bᵀ [ f_s(d) + (β0 k0 + βK k_t + βKc k_c + c_dash) ḋ ] + a0_abs · M u̇

with f_s the OpenSees ``Hysteretic`` clone (Takeda stand-in, ``element_copy=True``) for the bent
springs and linear k0·d for the seat springs; β0 k0, βK k_t, βKc k_c the stiffness-proportional
Rayleigh part on the spring deformation rates with the initial, current (trial) or committed
tangent of the members the scene names (:mod:`deckpound.models.damping`: OpenSees ``rayleigh
αM βK βKinit βKc`` with ``-doRayleigh 1`` on those zeroLength elements), and a0_abs·M the mass
part on absolute velocities. The mass part on relative velocities (``damping.mass =
relative``) is packed as extra dashpot-only rows after the plan's springs (k0 = 0, a DOF
against a support channel; :class:`deckpound.models.damping.MassDamper`), so every kernel
treats it as one more dashpot. The equation of motion is ``M ü + F(u, u̇) = (contact forces)``.

Usage (Python side)::

    ps = pack_system(plan, damping)    # once per run
    sa, hstate = ps.arrays, ps.new_state()
    # in a kernel, at a trial (u, u̇) and support motion (u_g, u̇_g):
    spring_deformations(sa, u, v, ug, vg, d, dd)            # d, ḋ
    spring_update_materials(sa.hparams, hstate, sa.kind, d)  # Takeda trial states
    spring_assemble(sa, hstate, d, dd, v, f, fs, kt)         # F, f_s, k_t
    spring_tangent(sa, kt, K)                                # K = Bᵀ diag(k_t) B
    spring_commit(sa, hstate)          # after a converged / accepted step
    spring_revert(sa, hstate)          # to discard a trial

``ps.C`` is the constant damping matrix ∂F/∂u̇ = a0 M + Bᵀ diag(a1 k0 + c_dash) B; ``K`` from
:func:`spring_tangent` is ∂F/∂u = Bᵀ diag(k_t) B with k_t the material tangents.

Units: m, rad, t, kN, s (kN = t·m/s²).
"""

from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass

import numpy as np

from deckpound.analytic._jit import kernel
from deckpound.analytic.kernels.hysteretic import pack_hysteretic
from deckpound.analytic.kernels.hysteretic_kernel import (
    hyst_commit,
    hyst_init_state,
    hyst_revert,
    hyst_set_trial,
)
from deckpound.analytic.kernels.hysteretic_layout import (
    C_ROTMAX,
    C_ROTMIN,
    C_STRAIN,
    C_STRESS,
    N_PARAMS,
    N_STATE,
    P_BETA,
    P_E1N,
    P_E1P,
    P_EUN,
    P_EUP,
    T_STRESS,
    T_TANGENT,
)
from deckpound.analytic.kernels.size_tags import corner_slots, dof_slots, index_tag
from deckpound.models.damping import DampingModel
from deckpound.models.plan import DOF_NAMES, Plan

__all__ = [
    "KIND_HYSTERETIC",
    "KIND_LINEAR",
    "SCAL_A0",
    "SCAL_A1",
    "SCAL_TANGENT_DAMPING",
    "PackedSystem",
    "RowLayout",
    "SystemArrays",
    "b_row_dot",
    "b_row_outer",
    "b_row_scatter",
    "bent_column",
    "end_column",
    "gap_column",
    "initial_dofs",
    "normal_force_column",
    "pack_system",
    "row_layout",
    "spring_assemble",
    "spring_commit",
    "spring_damping_tangent",
    "spring_deformations",
    "spring_revert",
    "spring_stored_energy",
    "spring_tangent",
    "spring_update_materials",
    "store_standard",
    "tangential_force_column",
    "velocity_column",
]

KIND_LINEAR = 0
KIND_HYSTERETIC = 1
#: Offsets of ``SystemArrays.scal``: the mass-proportional Rayleigh coefficient on absolute
#: velocities a0_abs [1/s], the stiffness-proportional one on the initial stiffness a1 [s], and
#: 1.0 when the damping depends on the current or committed tangent (βK or βKc ≠ 0), else 0.0.
SCAL_A0, SCAL_A1, SCAL_TANGENT_DAMPING = range(3)

#: The flat arrays the numba kernels take (a numba-compatible namedtuple).
#:
#: Sizes come from the arrays: n_dof = mass.shape[0], ns = k0.shape[0] springs.
#: mass (n_dof,) diagonal of M; B (ns, n_dof), S (ns, nch) dense kinematic matrices; bidx
#: (ns, 2) uint64, bval (ns, 2), bnnz (ns,) int: the ≤ 2 non-zeros of each row of B; schan
#: (ns,) int (−1: none), sval (ns,): the ≤ 1 non-zero of each row of S; k0 (ns,) initial
#: stiffness; cdash (ns,) explicit dashpot; crate (ns,) = a1·k0 + cdash, the total rate
#: coefficient of each spring; kind (ns,) int (0 linear, 1 Hysteretic); hparams (ns, 26)
#: Hysteretic params (zero rows for linear springs); scal (3,) = [a0_abs, a1, tangent-dependent
#: flag] (offsets ``SCAL_*``); C (n_dof, n_dof) the constant damping matrix a0_abs M + Bᵀ
#: diag(crate) B [kN·s/m]; nbs (int) the number of bent springs (the first rows of B); bk, bkc
#: (ns,) the coefficients of the current and the committed tangent [s]; kc (ns,) the committed
#: tangent k_c (state: written by :func:`spring_commit`), cvar (ns,) βK k_t + βKc k_c at the
#: last trial (state: written by :func:`spring_assemble`). The ``system`` bundle of the step
#: loops (:mod:`deckpound.analytic.bundles`). dofs: the tuple (0, …, n_dof − 1); numba types a
#: tuple by its length, so ``len(sa.dofs)`` is a compile-time constant of the kernels (loops
#: over the DOF unroll as over a literal) while the count still comes from the bundle.
SystemArrays = namedtuple(
    "SystemArrays",
    [
        "mass",
        "B",
        "S",
        "bidx",
        "bval",
        "bnnz",
        "schan",
        "sval",
        "k0",
        "cdash",
        "crate",
        "kind",
        "hparams",
        "scal",
        "C",
        "nbs",
        "bk",
        "bkc",
        "kc",
        "cvar",
        "dofs",
    ],
)


@dataclass(frozen=True)
class PackedSystem:
    """A scene packed for the kernels (build with :func:`pack_system`).

    Attributes
    ----------
    arrays : SystemArrays, the read-only inputs of the kernels.
    C : (n_dof, n_dof) constant damping matrix a0 M + Bᵀ diag(a1 k0 + c_dash) B.
    K0 : (n_dof, n_dof) initial stiffness Bᵀ diag(k0) B.
    a0, a1 : Rayleigh coefficients; omega : the two matched circular frequencies.
    spring_names : labels of the springs (``bent1_x``, ..., ``seat2_theta``).
    channels : support channel names, the order of u_g.
    n_bent_springs : 2 × number of bents (the first rows of B).
    """

    arrays: SystemArrays
    C: np.ndarray
    K0: np.ndarray
    a0: float
    a1: float
    omega: tuple[float, float]
    spring_names: tuple[str, ...]
    channels: tuple[str, ...]
    n_bent_springs: int

    @property
    def n_springs(self) -> int:
        return len(self.spring_names)

    def new_state(self) -> np.ndarray:
        """Fresh (virgin) material state, shape (n_springs, N_STATE); rows of linear springs unused."""
        st = np.zeros((self.n_springs, N_STATE))
        for i in range(self.n_springs):
            if self.arrays.kind[i] == KIND_HYSTERETIC:
                st[i] = hyst_init_state(self.arrays.hparams[i])
        return st


def pack_system(plan: Plan, damping: DampingModel) -> PackedSystem:
    """Pack the plan model's mass, springs, dashpots, damping and Takeda materials.

    The relative mass dampers (if any) follow the plan's springs as dashpot-only rows."""
    B, S = plan.spring_matrices
    dampers = damping.mass_dampers
    nd = len(dampers)
    k0 = np.concatenate([plan.k0, np.zeros(nd)])
    mass = plan.mass.copy()
    ns = plan.n_springs + nd
    # unsigned DOF indices: numba wraps a signed index that might be negative (x[-1]) with
    # extra instructions on every access, and the spring loops index u, v, f and K through
    # bidx in every force evaluation (the same values: results are bit-identical)
    bidx = np.zeros((ns, 2), dtype=np.uint64)
    bval = np.zeros((ns, 2))
    bnnz = np.zeros(ns, dtype=np.int64)
    schan = -np.ones(ns, dtype=np.int64)
    sval = np.zeros(ns)
    kind = np.zeros(ns, dtype=np.int64)
    hparams = np.zeros((ns, N_PARAMS))
    for i, spring in enumerate(plan.springs):
        if not 1 <= len(spring.dofs) <= 2:
            # the kernels read a row's first non-zero unconditionally (spring_deformations)
            raise ValueError(
                f"spring {spring.name}: its deformation needs 1 or 2 DOFs, got {len(spring.dofs)}"
            )
        bnnz[i] = len(spring.dofs)
        bidx[i, : len(spring.dofs)] = spring.dofs
        bval[i, : len(spring.dofs)] = spring.coefs
        if spring.channel >= 0:
            schan[i] = spring.channel
            sval[i] = spring.channel_coef
        if spring.kind == "takeda":
            kind[i] = KIND_HYSTERETIC
            hparams[i] = pack_hysteretic(*spring.takeda, element_copy=True)
    B = np.vstack([B, np.zeros((nd, B.shape[1]))])
    S = np.vstack([S, np.zeros((nd, S.shape[1]))])
    for r, m in enumerate(dampers):
        i = plan.n_springs + r
        B[i, m.dof] = 1.0
        bnnz[i] = 1
        bidx[i, 0] = m.dof
        bval[i, 0] = 1.0
        if m.channel >= 0:
            S[i, m.channel] = 1.0
            schan[i] = m.channel
            sval[i] = 1.0
    pad = np.zeros(nd)
    cdash = np.concatenate([damping.dashpots.astype(float), [m.c for m in dampers]])
    crate = np.concatenate([damping.rate_coefficients(plan), [m.c for m in dampers]])
    bk = np.concatenate([_or_zero(damping.beta_current, plan), pad])
    bkc = np.concatenate([_or_zero(damping.beta_committed, plan), pad])
    a0, a1 = damping.a0_absolute, damping.a1
    var = 1.0 if damping.tangent_dependent else 0.0
    C = np.diag(a0 * mass) + B.T @ (crate[:, None] * B)
    arrays = SystemArrays(
        mass=mass,
        B=np.ascontiguousarray(B),
        S=np.ascontiguousarray(S),
        bidx=bidx,
        bval=bval,
        bnnz=bnnz,
        schan=schan,
        sval=sval,
        k0=k0.astype(float),
        cdash=cdash,
        crate=crate,
        kind=kind,
        hparams=hparams,
        scal=np.array([a0, a1, var]),
        C=np.ascontiguousarray(C),
        nbs=int(plan.n_bent_springs),
        bk=bk,
        bkc=bkc,
        kc=k0.astype(float).copy(),
        cvar=np.zeros(ns),
        dofs=dof_slots(mass.shape[0]),
    )
    K0 = B.T @ (k0[:, None] * B)
    return PackedSystem(
        arrays=arrays,
        C=C,
        K0=K0,
        a0=float(a0),
        a1=float(a1),
        omega=(float(damping.omega[0]), float(damping.omega[1])),
        spring_names=tuple(sp.name for sp in plan.springs)
        + tuple(f"mass damper {k + 1}" for k in range(nd)),
        channels=plan.channels,
        n_bent_springs=plan.n_bent_springs,
    )


def _or_zero(beta, plan: Plan) -> np.ndarray:
    return np.zeros(plan.n_springs) if beta is None else np.asarray(beta, dtype=float)


# --------------------------------------------------------------------------- kernels
# The per-evaluation kernels are inlined into the step loops: called, each took the whole
# ``sa`` bundle (20 arrays, ~150 machine words) by value, and building those argument lists was
# the hottest lines of the Newmark loop in a perf profile (results are bit-identical).
@kernel(inline="always")
def b_row_dot(sa, i, x):
    """(B x)_i = Σ_q bval[i, q]·x[bidx[i, q]], summed from 0.0 in the order of the row's ≤ 2
    non-zeros: the operations of a loop over them, written out (no loop of run-time length in
    the force evaluations; the same bits)."""
    s = 0.0 + sa.bval[i, 0] * x[sa.bidx[i, 0]]
    if sa.bnnz[i] > 1:
        s += sa.bval[i, 1] * x[sa.bidx[i, 1]]
    return s


@kernel(inline="always")
def b_row_scatter(sa, i, y, value):
    """y += B[i, :]ᵀ·value (the row's ≤ 2 non-zeros in order, as :func:`b_row_dot`)."""
    y[sa.bidx[i, 0]] += sa.bval[i, 0] * value
    if sa.bnnz[i] > 1:
        y[sa.bidx[i, 1]] += sa.bval[i, 1] * value


@kernel(inline="always")
def b_row_outer(sa, i, K, coef):
    """K += B[i, :]ᵀ·coef·B[i, :]: each of the ≤ 4 entries once, (bval[i, q]·coef)·bval[i, r]
    in the order q, r of a double loop over the row's non-zeros."""
    j0 = sa.bidx[i, 0]
    b0 = sa.bval[i, 0]
    c0 = b0 * coef
    if sa.bnnz[i] > 1:
        j1 = sa.bidx[i, 1]
        b1 = sa.bval[i, 1]
        c1 = b1 * coef
        K[j0, j0] += c0 * b0
        K[j0, j1] += c0 * b1
        K[j1, j0] += c1 * b0
        K[j1, j1] += c1 * b1
    else:
        K[j0, j0] += c0 * b0


@kernel(inline="always")
def spring_deformations(sa, u, v, ug, vg, d, dd):
    """Fill d = B u − S u_g and dd = B u̇ − S u̇_g (shape (ns,))."""
    ns = sa.k0.shape[0]
    for i in range(ns):
        di = b_row_dot(sa, i, u)
        vi = b_row_dot(sa, i, v)
        if sa.schan[i] >= 0:
            ch = np.uint64(sa.schan[i])  # unsigned: no wrap-around of a negative index
            di -= sa.sval[i] * ug[ch]
            vi -= sa.sval[i] * vg[ch]
        d[i] = di
        dd[i] = vi


@kernel
def spring_update_materials(hparams, hstate, kind, d):
    """Set the trial deformation d[i] of every Hysteretic spring (trial state in hstate).

    One compiled call per force evaluation with the Takeda update inlined into its loop over
    the springs (:func:`.hysteretic_kernel.hyst_set_trial` is ``inline="always"``): a call
    per spring would pass two array views each time, and inlining this loop into every force
    evaluation of every integrator would multiply the Takeda branches in their compiled code
    (compile time and memory)."""
    for i in range(kind.shape[0]):
        if kind[i] == 1:
            hyst_set_trial(hparams[i], hstate[i], d[i])


@kernel(inline="always")
def spring_assemble(sa, hstate, d, dd, v, f, fs, kt):
    """Spring forces from deformations d, rates dd and the materials' trial state.

    f (n_dof,) out = Bᵀ[f_s + (crate + βK k_t + βKc k_c)·ḋ] + a0 M u̇; fs, kt (ns,) out:
    restoring force and tangent; sa.cvar (ns,) out: βK k_t + βKc k_c (tangent-dependent damping
    only). Returns the number of springs whose tangent differs from k0.
    """
    a0 = sa.scal[SCAL_A0]
    var = sa.scal[SCAL_TANGENT_DAMPING] != 0.0
    for j in range(len(sa.dofs)):
        f[j] = a0 * sa.mass[j] * v[j]
    nonel = 0
    for i in range(sa.k0.shape[0]):
        if sa.kind[i] == 1:
            fsi = hstate[i, T_STRESS]
            kti = hstate[i, T_TANGENT]
        else:
            kti = sa.k0[i]
            fsi = kti * d[i]
        if kti != sa.k0[i]:
            nonel += 1
        fs[i] = fsi
        kt[i] = kti
        fi = fsi + sa.crate[i] * dd[i]
        if var:
            cv = sa.bk[i] * kti + sa.bkc[i] * sa.kc[i]
            sa.cvar[i] = cv
            fi += cv * dd[i]
        b_row_scatter(sa, i, f, fi)
    return nonel


@kernel(inline="always")
def spring_tangent(sa, kt, K):
    """K = Bᵀ diag(kt) B (n_dof × n_dof, overwritten)."""
    nd = len(sa.dofs)
    for j in range(nd):
        for k in range(nd):
            K[j, k] = 0.0
    for i in range(sa.k0.shape[0]):
        b_row_outer(sa, i, K, kt[i])


@kernel(inline="always")
def spring_damping_tangent(sa, c2, Keff):
    """Keff += c2 · Bᵀ diag(βK k_t + βKc k_c) B at the last trial (OpenSees's getDamp with the
    current and the committed tangent; nothing when the damping is tangent-independent)."""
    if sa.scal[SCAL_TANGENT_DAMPING] == 0.0:
        return
    for i in range(sa.k0.shape[0]):
        cv = c2 * sa.cvar[i]
        if cv != 0.0:
            b_row_outer(sa, i, Keff, cv)


@kernel
def spring_commit(sa, hstate):
    """Commit the trial state of every Hysteretic spring (OpenSees commitState); with
    committed-tangent damping, k_c := the trial tangent first (``Element::commitState`` runs
    before the materials commit)."""
    if sa.scal[SCAL_TANGENT_DAMPING] != 0.0:
        for i in range(sa.k0.shape[0]):
            if sa.kind[i] == 1:
                sa.kc[i] = hstate[i, T_TANGENT]
    for i in range(sa.k0.shape[0]):
        if sa.kind[i] == 1:
            hyst_commit(hstate[i])


@kernel
def spring_revert(sa, hstate):
    """Revert every Hysteretic spring to its last committed state."""
    for i in range(sa.k0.shape[0]):
        if sa.kind[i] == 1:
            hyst_revert(hstate[i])


@kernel
def _unloading_stiffness(p, st, stress):
    """Takeda unloading stiffness E_u·max(1, μ^β)^(−1) at the committed excursion."""
    if stress >= 0.0:
        ratio = st[C_ROTMAX] / p[P_E1P]
        e = p[P_EUP]
    else:
        ratio = st[C_ROTMIN] / p[P_E1N]
        e = p[P_EUN]
    k = 1.0
    if ratio > 1.0:
        k = ratio ** p[P_BETA]
        k = max(k, 1.0)
    return e / k


@kernel
def spring_stored_energy(sa, hstate, u, ug):
    """Recoverable (elastic) energy of the springs at the committed state [kJ].

    Linear springs: ½ k0 d². Takeda springs: f_s² / (2 k_u), the energy released by unloading
    along the current unloading stiffness k_u = k0 μ^(−β) (the rest of ∫ f_s dd is hysteresis).
    """
    e = 0.0
    ns = sa.k0.shape[0]
    for i in range(ns):
        if sa.kind[i] == 1:
            s = hstate[i, C_STRESS]
            ku = _unloading_stiffness(sa.hparams[i], hstate[i], s)
            e += 0.5 * s * s / ku
        else:
            di = b_row_dot(sa, i, u)
            ch = sa.schan[i]
            if ch >= 0:
                di -= sa.sval[i] * ug[ch]
            e += 0.5 * sa.k0[i] * di * di
    return e


_ = C_STRAIN  # (index kept importable for callers reading the committed deformation)


def initial_dofs(initial_state, n_dof: int) -> tuple[np.ndarray, np.ndarray]:
    """(u0, v0) of the ``n_dof`` DOF (``SystemArrays.mass.shape[0]``) from an engine's
    ``initial_state = (u0, v0)`` keyword (None: rest).

    Raises ValueError unless both are ``n_dof`` finite numbers [m, rad; m/s, rad/s].
    """
    u0 = np.zeros(n_dof)
    v0 = np.zeros(n_dof)
    if initial_state is not None:
        # the DOF names are the plan model's; a model of another size has no names here
        order = f" (DOF order {', '.join(DOF_NAMES)})" if n_dof == len(DOF_NAMES) else ""
        for name, dst, src in (("u0", u0, initial_state[0]), ("v0", v0, initial_state[1])):
            arr = np.asarray(src, dtype=float)
            if arr.shape != (n_dof,) or not np.all(np.isfinite(arr)):
                raise ValueError(
                    f"initial_state {name} must be {n_dof} finite numbers{order}; "
                    f"got {arr.tolist()!r}"
                )
            dst[:] = arr
    return u0, v0


# Output row layout of the analytic engines' compiled loops, in the order of
# deckpound.models.engine_contract.engine_columns: time, the absolute displacement columns, the
# velocity columns, gaps, normal and tangential forces, then the bent forces. Only the first two
# offsets are fixed; the others follow from the counts of a RowLayout (the offset functions
# below), so a model with more DOF or corners (several deck segments) gets its own layout.
C_T = 0
C_U = 1

#: The layout of the engine columns of an output row (:func:`row_layout`; the ``layout`` field
#: of :data:`deckpound.analytic.kernels.peaks.Peaks`): ``dof_columns`` the DOF index of each
#: displacement (and velocity) column, in column order; ``corners`` the size tag (0, …,
#: n_corners − 1) of the corners (gap, normal and tangential force columns); ``nbs`` the
#: number of bent-force columns (the bent springs). Both tuples are typed by their length, so
#: the column counts are compile-time constants of the kernels (the offsets fold to literals).
RowLayout = namedtuple("RowLayout", ["dof_columns", "corners", "nbs"])


def row_layout(plan: Plan) -> RowLayout:
    """The :data:`RowLayout` of ``plan``'s engine columns: its corners and bent springs, and
    the displacement columns of :attr:`deckpound.models.plan.Plan.dof_columns` (the columns
    :func:`deckpound.models.engine_contract.engine_columns` names), which must cover the plan's
    DOF once each (ValueError otherwise: a plan of another size needs its own columns)."""
    dofs = [int(dof) for _, dof in plan.dof_columns]
    n_dof = int(plan.mass.shape[0])
    corners = corner_slots(len(plan.corners))
    # the layout's tags are tuples exactly when the loop's are (one compiled type per model)
    dof_columns = index_tag(dofs, isinstance(dof_slots(n_dof), tuple))
    if sorted(dofs) != list(range(n_dof)):
        raise ValueError(
            f"the displacement columns (Plan.dof_columns) read DOF "
            f"{list(dof_columns)}; the plan has {n_dof} DOF, each needs one column"
        )
    return RowLayout(
        dof_columns=dof_columns,
        corners=corners,
        nbs=int(plan.n_bent_springs),
    )


# Each offset is written out in full (no call of another offset kernel), so that Python code
# sizing a row can call its ``py_func`` without loading a compiled kernel.
@kernel(inline="always")
def velocity_column(layout):
    """First velocity column of a row in ``layout`` (after time and the displacements)."""
    return C_U + len(layout.dof_columns)


@kernel(inline="always")
def gap_column(layout):
    """First gap column (after the displacements and the velocities)."""
    return C_U + 2 * len(layout.dof_columns)


@kernel(inline="always")
def normal_force_column(layout):
    """First normal-force column (after the n_corners gaps)."""
    return C_U + 2 * len(layout.dof_columns) + len(layout.corners)


@kernel(inline="always")
def tangential_force_column(layout):
    """First tangential-force column (after the n_corners normal forces)."""
    return C_U + 2 * len(layout.dof_columns) + 2 * len(layout.corners)


@kernel(inline="always")
def bent_column(layout):
    """First bent-force column (after the n_corners tangential forces)."""
    return C_U + 2 * len(layout.dof_columns) + 3 * len(layout.corners)


@kernel(inline="always")
def end_column(layout):
    """One past the last engine column (after the ``nbs`` bent forces): where an engine's own
    columns (impulses, energies) and the peaks' extra columns start."""
    return C_U + 2 * len(layout.dof_columns) + 3 * len(layout.corners) + layout.nbs


@kernel
def store_standard(row, layout, t, u, v, g, fn, ft, fs):
    """Fill the engine columns of one output row in ``layout`` (:data:`RowLayout`): time,
    absolute displacements and velocities, gaps, normal and tangential contact forces, bent
    forces (the first ``layout.nbs`` of ``fs``)."""
    c_v = velocity_column(layout)
    c_gap = gap_column(layout)
    c_fn = normal_force_column(layout)
    c_ft = tangential_force_column(layout)
    c_bent = bent_column(layout)
    row[C_T] = t
    for k in range(len(layout.dof_columns)):
        j = layout.dof_columns[k]
        row[C_U + k] = u[j]
        row[c_v + k] = v[j]
    for c in range(len(layout.corners)):
        row[c_gap + c] = g[c]
        row[c_fn + c] = fn[c]
        row[c_ft + c] = ft[c]
    for i in range(layout.nbs):
        row[c_bent + i] = fs[i]

r"""The Moreau–Jean step loop of the nonsmooth engine.

Driven by :func:`deckpound.analytic.nonsmooth.engine.run_nonsmooth`; the model, the output columns
and the energy bookkeeping are described there.

Time discretisation (Moreau–Jean θ-scheme, Jean 1999, Acary & Brogliato 2008 Ch. 10)
------------------------------------------------------------------------------------
Step k → k+1 (h = ``nonsmooth.h``, θ = ``nonsmooth.theta`` ∈ [½, 1], default ½)::

    M (v_{k+1} − v_k) = −h [θ F_{k+1} + (1 − θ) F_k] + W_Nᵀ P_N + W_Tᵀ P_T
    q_{k+1} = q_k + h [(1 − θ) v_k + θ v_{k+1}]
    F_k = F(q_k, v_k, t_k),  F_{k+1} = F(q_{k+1}, v_{k+1}, t_{k+1})

* **Implicit** (θ-weighted end values): every smooth force — spring restoring forces (Takeda
  and seats), seat dashpots, Rayleigh damping (both the a0·M and the a1·K0 parts), and the
  support motion u_g, u̇_g that drives them (taken at t_k and t_{k+1}). The contact impulses
  P are fully implicit (they act on v_{k+1}).
* **Explicit**: the active set (a corner is active when its gap at the predicted mid-step
  position q_M = q_k + h/2·v_k is ≤ 0), the contact Jacobians W_N, W_T (evaluated at q_M;
  constant for linear kinematics), and the pre-impact velocities U_N⁻ = W_N v_k.

The nonlinear (Takeda) equation is solved by Newton's method on v_{k+1} with the contact
problem re-solved inside every iteration (Siconos' MoreauJeanOSI Newton loop). Iteration 0 is
the *linearised θ-method*: with K_t = Bᵀ diag(k_t) B the material tangents of the committed
state and the exact linearisation of F about (q_k, v_k, t_k),

    F_{k+1} ≈ F_k + K_t Δq + C Δv − Bᵀ[k_t ∘ S Δu_g + crate ∘ S Δu̇_g],   Δq = h v_k + θ h Δv,

(C = a0 M + Bᵀ diag(crate) B is constant), so

    Ŵ = M + θ h C + θ² h² K_t,
    v_free = v_k + Ŵ⁻¹ [ −h F_k − θ h² K_t v_k + θ h Bᵀ(k_t ∘ S Δu_g + crate ∘ S Δu̇_g) ],
    v_{k+1} = v_free + Ŵ⁻¹ (W_Nᵀ P_N + W_Tᵀ P_T).

The springs are then evaluated at (q_{k+1}, v_{k+1}, t_{k+1}) (Takeda trial state from the
committed history). The residual of the θ-equation is exactly θ h Bᵀ r with the per-spring
linearisation mismatch r_i = f_s,i(d_{k+1}) − f_s,i(d_lin) − k_t,i (d_{k+1} − d_lin); the step is
accepted when max|r_i| ≤ ``nonsmooth.tolerance`` × (largest Takeda yield force) — for linear
springs and for Takeda springs that stay on one branch the linearised step is exact and no
further iteration is made. Otherwise Newton iterates (tangent, free velocity and contact
problem recomputed at the current iterate, active set kept) up to ``nonsmooth.max_iterations``;
non-convergence fails the step. The Takeda history is committed once per accepted step with
q_{k+1} = q_k + h[(1−θ)v_k + θv_{k+1}]. For θ = ½ and linear springs the smooth part is the
trapezoidal rule (second order, energy-conserving); with impacts the scheme is first order.

The contact problem of the (≤ 4) active corners is the planar frictional impact problem of
:mod:`deckpound.analytic.nonsmooth.frictional_contact` with the Delassus matrix G = W Ŵ⁻¹ Wᵀ, free
contact velocities W v_free and U_N⁻ = W_N v_k, solved exactly (Lemke with Stewart–Trinkle
Lemke and enumeration fall-backs for ``solver = lemke``; enumeration only for
``solver = enumeration``) and verified against the contact laws (relative tolerance
``nonsmooth.tolerance``); an unverified solve fails the run at that step. Steps without an
active corner skip the contact solve; frictionless runs (μ = 0) carry only normal unknowns.

Active but separating corners. A corner can be active (g(q_M) ≤ 0) while it already separates
(U_N⁻ > 0, typically the step after an impact or in persistent contact with the seat springs
pushing). Newton's law there (U_N⁺ ≥ −e U_N⁻; ``nonsmooth.impact_law = "newton"``, the
default, as Siconos) lets a positive P_N do positive work ½ P_N (1 − e) U_N⁻ on v_m for θ = ½,
i.e. gain energy (0.2 % of the impact dissipation on the benchmark, see docs/verification.md). With
``impact_law = "energy-safe"`` such corners use the restitution max(e, (1 − θ)/θ) instead
(``esep``, :func:`deckpound.analytic.nonsmooth.engine.separating_restitution`;
= 1 for θ = ½, = e for θ = 1): then P_N > 0 implies θU_N⁺ + (1−θ)U_N⁻ ≤ 0 (= 0 for θ = ½) and
the normal impulse does no positive work, so for frictionless contact every step is
dissipative (tested); approaching corners (U_N⁻ ≤ 0, the
impacts) keep Newton's law unchanged. Friction keeps the standard law on U_T⁺; its work on
v_m is −μP_N|U_T⁺| ≤ 0 for θ = 1 but not sign-definite for θ < 1, and with e > 0 Newton's law
combined with Coulomb friction can gain energy in an impact (Kane's paradox, see
:mod:`deckpound.analytic.nonsmooth.frictional_contact`).
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic._jit import kernel
from deckpound.analytic.bundles import (
    RUN_CONTACT_UNSOLVED,
    RUN_INTERRUPTED,
    RUN_NONFINITE,
    RUN_NOT_CONVERGED,
    RUN_OK,
    RUN_SINGULAR,
    RUN_UNSEATED,
)
from deckpound.analytic.fp_mode import flush_enter, flush_leave
from deckpound.analytic.kernels.dense import lu_factor, lu_solve
from deckpound.analytic.kernels.kinematics import contact_kinematics, linear_gap
from deckpound.analytic.kernels.peaks import track_state
from deckpound.analytic.kernels.support_motion import record_at
from deckpound.analytic.kernels.system import (
    KIND_HYSTERETIC,
    b_row_dot,
    b_row_scatter,
    spring_assemble,
    spring_commit,
    spring_deformations,
    spring_stored_energy,
    spring_tangent,
    spring_update_materials,
)
from deckpound.analytic.nonsmooth.contact_checks import STATUS_FAILED
from deckpound.analytic.nonsmooth.impulses import solve_active_impulses
from deckpound.analytic.nonsmooth.moreau_jean_work import (
    FINAL_U,
    FINAL_V,
    W_FRICTION,
    W_IMPACT,
    W_INPUT,
    W_NUMERICAL,
    W_SPRING,
    W_VISCOUS,
    output_energies,
    store_row,
)

__all__ = ["moreau_jean_run"]

# The loop is a short driver (:func:`moreau_jean_run`) over stages that take the bundles:
# start, predict (support motion, active set), solve (Newton on v_{k+1} with the contact
# problem), commit (springs, work totals, impulses), store (peaks, output rows), finish. The
# per-step stages are inlined into the driver (numba IR inlining, ``inline="always"``), so the
# loop compiles to one function as before. Sizes come from the bundles: springs and support
# channels from their arrays, DOFs and corners from the workspace's size tags
# (``work.dof_slots``, ``work.corner_slots``: compile-time constants, so the loop is compiled
# per model size and its short DOF and corner loops unroll).


@kernel(inline="always")
def _iteration_matrix(sa, Cmat, kt, h, theta, K, LU, piv, dof_slots):
    """LU of Ŵ = M + θhC + θ²h² Bᵀ diag(kt) B (K scratch), n_dof = len(dof_slots) (the size
    tag). Returns False if singular."""
    n_dof = len(dof_slots)
    spring_tangent(sa, kt, K)
    c1 = theta * h
    c2 = c1 * c1
    for i in range(n_dof):
        for j in range(n_dof):
            LU[i, j] = c1 * Cmat[i, j] + c2 * K[i, j]
        LU[i, i] += sa.mass[i]
    return lu_factor(LU, piv, dof_slots)


@kernel(inline="always")
def _copy_state(final, q, v, n_dof):
    """The state a run reports as its last: displacement q and velocity v into the rows
    FINAL_U, FINAL_V of ``final``."""
    for j in range(n_dof):
        final[FINAL_U, j] = q[j]
        final[FINAL_V, j] = v[j]


@kernel(inline="always")
def _corner_rows(contact, q, gap, WN, WT, work):
    """Gaps and rows WN, WT at q (:func:`.kinematics.contact_kinematics`), the corner and DOF
    counts of the workspace's size tags."""
    contact_kinematics(
        q, contact.corners, contact.nonlinear, gap, WN, WT, work.corner_slots, work.dof_slots
    )


@kernel(inline="always")
def _corner_gaps(contact, q, gap, WN, WT, work):
    """Gaps at q; rows WN, WT too for nonlinear kinematics (constant for linear kinematics,
    filled before the loop, so only the gaps change)."""
    if contact.nonlinear:
        _corner_rows(contact, q, gap, WN, WT, work)
    else:
        for c in range(len(work.corner_slots)):
            gap[c] = linear_gap(contact.corners[c], q)


@kernel
def _start(system, contact, record, output, work):
    """Initial state: springs at (u0, v0, t = 0) committed, work totals, contact rows, output
    row 0, peaks of step 0. Returns the record hint."""
    sa = system
    dof, spr, cor = work.dof, work.spring, work.corner
    q, v, W = dof.q, dof.v, work.W
    jrec = record_at(
        record.t, record.disp, record.vel, record.dslope, record.vslope, 0.0, 0, work.ug, work.vg
    )
    for j in range(q.shape[0]):
        q[j] = work.u0[j]
        v[j] = work.v0[j]
    spring_deformations(sa, q, v, work.ug, work.vg, spr.d_k, spr.dd_k)
    spring_update_materials(sa.hparams, work.hstate, sa.kind, spr.d_k)
    spring_assemble(sa, work.hstate, spr.d_k, spr.dd_k, v, dof.Fk, spr.fs_k, spr.kt_k)
    spring_commit(sa, work.hstate)
    es0 = spring_stored_energy(sa, work.hstate, q, work.ug)
    ke0 = 0.0
    for j in range(q.shape[0]):
        ke0 += 0.5 * sa.mass[j] * v[j] * v[j]
    W[W_INPUT] = ke0 + es0
    W[W_SPRING] = es0
    _corner_rows(contact, q, cor.gapo, cor.WNo, cor.WTo, work)
    _corner_rows(contact, q, cor.gap, cor.WN, cor.WT, work)
    output_energies(sa, work.hstate, q, v, work.ug, W, work.energy)
    store_row(
        output,
        0,
        0.0,
        q,
        v,
        cor.gapo,
        cor.fn_out,
        cor.ft_out,
        spr.fs_k,
        cor.pn_acc,
        cor.pt_acc,
        cor.state,
        work.energy,
    )
    # peaks and gap closures of every step (.peaks): the step's forces are its impulses / h
    pk = output.peaks
    track_state(pk, 0.0, q, v, cor.gapo, pk.force[0], pk.force[1], spr.fs_k, work.ug, spr.d_k)
    return jrec


@kernel(inline="always")
def _predict(system, contact, record, work, h, t1, jrec, count):
    """Support motion at t_{n+1} and its increment per spring (S Δu_g, S Δu̇_g), start of
    step q_k, v_k, mid-step prediction q_M = q_k + h/2 v_k and the active set at q_M (a corner
    is active when its gap is ≤ 0; activations counted). Returns (record hint, active
    corners)."""
    sa = system
    dof, spr, cor = work.dof, work.spring, work.corner
    ug, vg, ugo, vgo = work.ug, work.vg, work.ugo, work.vgo
    for k in range(ug.shape[0]):
        ugo[k] = ug[k]
        vgo[k] = vg[k]
    jrec = record_at(
        record.t, record.disp, record.vel, record.dslope, record.vslope, t1, jrec, ug, vg
    )
    for i in range(spr.sdu.shape[0]):
        ch = sa.schan[i]
        if ch >= 0:
            spr.sdu[i] = sa.sval[i] * (ug[ch] - ugo[ch])
            spr.sdv[i] = sa.sval[i] * (vg[ch] - vgo[ch])
        else:
            spr.sdu[i] = 0.0
            spr.sdv[i] = 0.0
    q, v = dof.q, dof.v
    n_corners = len(work.corner_slots)
    for j in range(len(work.dof_slots)):
        dof.qk[j] = q[j]
        dof.vk[j] = v[j]
        dof.qM[j] = q[j] + 0.5 * h * v[j]
    _corner_gaps(contact, dof.qM, cor.gap, cor.WN, cor.WT, work)
    nact = 0
    for c in range(n_corners):
        if cor.gap[c] <= 0.0:
            cor.act[nact] = c
            nact += 1
            if not cor.was_active[c]:
                count[bd.CNT_EVENTS] += 1
            cor.was_active[c] = True
        else:
            cor.was_active[c] = False
    if nact > 0:
        count[bd.CNT_CONTACT_STEPS] += 1
    return jrec, nact


@kernel(inline="always")
def _linearise(system, work, h, th):
    """Iteration 0: the residual of the linearisation about the committed state,
    R = h F_k + θh Bᵀ[k_t ∘ (h B v_k − SΔu_g) − crate ∘ SΔu̇_g], linearisation point = the
    committed springs, iterate v = v_k."""
    sa = system
    dof, spr = work.dof, work.spring
    R, vk = dof.R, dof.vk
    n_dof = len(work.dof_slots)
    for j in range(n_dof):
        R[j] = h * dof.Fk[j]
    for i in range(spr.d_k.shape[0]):
        bv = b_row_dot(sa, i, vk)
        t_i = th * h * (spr.kt_k[i] * (h * bv - spr.sdu[i]) - sa.crate[i] * spr.sdv[i])
        b_row_scatter(sa, i, R, t_i)
        spr.d_lin[i] = spr.d_k[i]
        spr.fs_lin[i] = spr.fs_k[i]
        spr.kt_lin[i] = spr.kt_k[i]
    for j in range(n_dof):
        dof.v[j] = vk[j]


@kernel(inline="always")
def _factor(system, work, h, theta, count):
    """Iteration matrix Ŵ for the tangents of the linearisation point, refactored only when a
    tangent changed. Returns False if it is singular."""
    dof, spr = work.dof, work.spring
    kt_lin, kt_fact = spr.kt_lin, spr.kt_fact
    for i in range(kt_lin.shape[0]):
        if kt_lin[i] != kt_fact[i]:
            if not _iteration_matrix(
                system, system.C, kt_lin, h, theta, dof.K, dof.LU, dof.piv, work.dof_slots
            ):
                return False
            count[bd.CNT_FACTORISATIONS] += 1
            for k in range(kt_lin.shape[0]):
                kt_fact[k] = kt_lin[k]
            return True
    return True


@kernel(inline="always")
def _velocity(work, opt, nact, stats):
    """Free velocity v_free = v − Ŵ⁻¹ R, then the contact impulses of the active corners and
    v = v_free + Ŵ⁻¹ Wᵀ P (:func:`.impulses.solve_active_impulses`). Returns RUN_OK or
    RUN_CONTACT_UNSOLVED."""
    dof, cor = work.dof, work.corner
    v, vfree = dof.v, dof.vfree
    n_dof = len(work.dof_slots)
    lu_solve(dof.LU, dof.piv, dof.R, dof.dv, work.dof_slots)
    for j in range(n_dof):
        vfree[j] = v[j] - dof.dv[j]
    if nact == 0:
        for j in range(n_dof):
            v[j] = vfree[j]
        return RUN_OK
    cst, comp, cone = solve_active_impulses(
        dof.LU,
        dof.piv,
        cor.WN,
        cor.WT,
        cor.act,
        nact,
        dof.vk,
        vfree,
        opt.ecoef,
        opt.esep,
        opt.mu,
        opt.mode,
        opt.rtol,
        cor.P_N,
        cor.P_T,
        cor.state,
        dof.vnew,
        work.impulse,
    )
    stats.count[bd.CNT_SOLVES] += 1
    if cst == STATUS_FAILED:
        return RUN_CONTACT_UNSOLVED
    value = stats.value
    value[bd.VAL_MAX_COMP] = max(value[bd.VAL_MAX_COMP], comp)
    value[bd.VAL_MAX_CONE] = max(value[bd.VAL_MAX_CONE], cone)
    for j in range(n_dof):
        v[j] = dof.vnew[j]
    return RUN_OK


@kernel(inline="always")
def _springs_at_iterate(system, work, h, th, th1):
    """q = q_k + h[(1 − θ) v_k + θ v], the springs at (q, v, t_{n+1}) (Takeda trial state from
    the committed history). Returns the largest Takeda linearisation mismatch
    max|f_s(d) − f_s(d_lin) − k_t,lin (d − d_lin)| [kN]."""
    sa = system
    dof, spr = work.dof, work.spring
    q, v = dof.q, dof.v
    for j in range(len(work.dof_slots)):
        q[j] = dof.qk[j] + h * (th1 * dof.vk[j] + th * v[j])
    spring_deformations(sa, q, v, work.ug, work.vg, spr.d, spr.dd)
    spring_update_materials(sa.hparams, work.hstate, sa.kind, spr.d)
    spring_assemble(sa, work.hstate, spr.d, spr.dd, v, dof.f, spr.fs, spr.kt)
    rmax = 0.0
    for i in range(spr.d.shape[0]):
        if sa.kind[i] == KIND_HYSTERETIC:
            r_i = abs(spr.fs[i] - spr.fs_lin[i] - spr.kt_lin[i] * (spr.d[i] - spr.d_lin[i]))
            rmax = max(rmax, r_i)
    return rmax


@kernel(inline="always")
def _newton_residual(system, work, h, th, th1):
    """Newton: the residual of the θ-equation at the iterate (contact impulse excluded),
    R = M (v − v_k) + h[(1 − θ) F_k + θ f], and the iterate as the new linearisation point."""
    dof, spr = work.dof, work.spring
    for j in range(len(work.dof_slots)):
        dof.R[j] = system.mass[j] * (dof.v[j] - dof.vk[j]) + h * (th1 * dof.Fk[j] + th * dof.f[j])
    for i in range(spr.d.shape[0]):
        spr.d_lin[i] = spr.d[i]
        spr.fs_lin[i] = spr.fs[i]
        spr.kt_lin[i] = spr.kt[i]


@kernel(inline="always")
def _solve(system, work, opt, nact, stats):
    """The step's equation: linearised θ-step, then Newton iterations (tangent, free velocity
    and contact problem at the current iterate, active set kept) until the Takeda mismatch is
    ≤ opt.ftol. Returns RUN_OK or the failure (RUN_SINGULAR, RUN_CONTACT_UNSOLVED,
    RUN_NONFINITE, RUN_NOT_CONVERGED, RUN_INTERRUPTED)."""
    h, th = opt.h, opt.theta
    th1 = 1.0 - th
    count = stats.count
    _linearise(system, work, h, th)
    it = 0
    status = RUN_OK
    while True:
        if not _factor(system, work, h, th, count):
            status = RUN_SINGULAR
            break
        status = _velocity(work, opt, nact, stats)
        if status != RUN_OK:
            break
        rmax = _springs_at_iterate(system, work, h, th, th1)
        it += 1
        if not np.isfinite(rmax):
            status = RUN_NONFINITE
            break
        if rmax <= opt.ftol:
            break
        if it >= opt.maxit:
            status = RUN_NOT_CONVERGED
            break
        if stats.halt[0] != 0:
            status = RUN_INTERRUPTED
            break
        _newton_residual(system, work, h, th, th1)
    count[bd.CNT_NEWTON] += it
    count[bd.CNT_MAX_IT] = max(count[bd.CNT_MAX_IT], it)
    if status == RUN_OK:
        q, v = work.dof.q, work.dof.v
        for j in range(len(work.dof_slots)):
            if not np.isfinite(v[j]) or not np.isfinite(q[j]):
                status = RUN_NONFINITE
    return status


@kernel(inline="always")
def _commit(system, work, h, th):
    """Commit the accepted step: Takeda history, the exact work of the θ-scheme over the step
    (support input, spring, viscous, numerical), the spring and force state of step k+1."""
    sa = system
    dof, spr, W = work.dof, work.spring, work.W
    th1 = 1.0 - th
    spring_commit(sa, work.hstate)
    for i in range(spr.d.shape[0]):
        fth = th * spr.fs[i] + th1 * spr.fs_k[i]
        cth = sa.crate[i] * (th * spr.dd[i] + th1 * spr.dd_k[i])
        dlt = spr.d[i] - spr.d_k[i]
        W[W_INPUT] -= spr.sdu[i] * (fth + cth)
        W[W_SPRING] += dlt * fth
        W[W_VISCOUS] += dlt * cth
        spr.d_k[i] = spr.d[i]
        spr.dd_k[i] = spr.dd[i]
        spr.fs_k[i] = spr.fs[i]
        spr.kt_k[i] = spr.kt[i]
    a0 = sa.scal[0]  # mass-proportional Rayleigh coefficient (SystemArrays.scal)
    num = 0.0
    q, v, qk, vk = dof.q, dof.v, dof.qk, dof.vk
    for j in range(len(work.dof_slots)):
        vm = th1 * vk[j] + th * v[j]
        W[W_VISCOUS] += a0 * sa.mass[j] * (q[j] - qk[j]) * vm
        dvj = v[j] - vk[j]
        num += sa.mass[j] * dvj * dvj
        dof.Fk[j] = dof.f[j]
    W[W_NUMERICAL] += (th - 0.5) * num


@kernel(inline="always")
def _commit_contact(contact, work, peaks, nact, th, inv_h, value):
    """Penetration at q_{k+1} (every step: the output rows see one step in `stride`), the
    impulses' work on v_m = (1 − θ)v_k + θv_{k+1}, the impulses accumulated for the output
    and the step's forces P / h for the peaks."""
    dof, cor, W = work.dof, work.corner, work.W
    n_corners = len(work.corner_slots)
    _corner_gaps(contact, dof.q, cor.gapo, cor.WNo, cor.WTo, work)
    fn_step, ft_step = peaks.force[0], peaks.force[1]
    for c in range(n_corners):
        value[bd.VAL_MAX_PEN] = max(value[bd.VAL_MAX_PEN], -cor.gapo[c])
        fn_step[c] = 0.0
        ft_step[c] = 0.0
    if nact == 0:
        for c in range(n_corners):
            cor.state[c] = 0
        return
    th1 = 1.0 - th
    for a in range(nact):
        c = cor.act[a]
        uN = 0.0
        uT = 0.0
        for j in range(len(work.dof_slots)):
            vm = th1 * dof.vk[j] + th * dof.v[j]
            uN += cor.WN[c, j] * vm
            uT += cor.WT[c, j] * vm
        W[W_IMPACT] -= cor.P_N[c] * uN
        W[W_FRICTION] -= cor.P_T[c] * uT
        cor.pn_acc[c] += cor.P_N[c]
        cor.pt_acc[c] += cor.P_T[c]
        fn_step[c] = cor.P_N[c] * inv_h
        ft_step[c] = cor.P_T[c] * inv_h


@kernel(inline="always")
def _store(system, contact, output, work, row, t1, inv_out):
    """Output row ``row`` at t_{n+1}: contact kinematics at q, forces = impulses accumulated
    over the output interval × inv_out, energies; the accumulators restart."""
    sa = system
    dof, cor = work.dof, work.corner
    _corner_rows(contact, dof.q, cor.gapo, cor.WNo, cor.WTo, work)
    for c in range(len(work.corner_slots)):
        cor.fn_out[c] = cor.pn_acc[c] * inv_out
        cor.ft_out[c] = cor.pt_acc[c] * inv_out
    output_energies(sa, work.hstate, dof.q, dof.v, work.ug, work.W, work.energy)
    store_row(
        output,
        row,
        t1,
        dof.q,
        dof.v,
        cor.gapo,
        cor.fn_out,
        cor.ft_out,
        work.spring.fs,
        cor.pn_acc,
        cor.pt_acc,
        cor.state,
        work.energy,
    )
    for c in range(len(work.corner_slots)):
        cor.pn_acc[c] = 0.0
        cor.pt_acc[c] = 0.0


@kernel
def _finish(stats, status, row, failed, nsteps, h):
    """The run's status, rows, failed step and steps completed (all, the unseating step
    included, or those before the failed one) and the time reached."""
    done = nsteps if status == RUN_OK else (failed if status == RUN_UNSEATED else failed - 1)
    cnt = stats.count
    cnt[bd.CNT_STATUS] = status
    cnt[bd.CNT_ROWS] = row
    cnt[bd.CNT_FAILED_STEP] = failed
    cnt[bd.CNT_STEPS] = done
    stats.value[bd.VAL_TIME] = done * h


@kernel(nogil=True)
def moreau_jean_run(system, contact, record, opt, output, work, stats):
    """The Moreau–Jean step loop over ``opt.nsteps`` steps of length opt.h.

    Bundles of :mod:`deckpound.analytic.bundles` (``system``, ``contact`` — its corner table
    and kinematics flag —, ``record``, ``output``, ``stats``), scalars
    :data:`MoreauJeanOptions`, workspace :data:`MoreauJeanWork`.

    Support motion: the record of :func:`deckpound.analytic.kernels.support_motion.support_record`,
    interpolated at t_n = n·h in the loop (identical to ``motion.resample(h)``, bounded memory).

    Fills ``output.table`` (one row per output), ``stats.count``: status (RUN_OK,
    RUN_NOT_CONVERGED, RUN_CONTACT_UNSOLVED, RUN_NONFINITE, RUN_SINGULAR, RUN_INTERRUPTED),
    rows written, failed step, steps, contact solves, contact events (corner activations),
    contact steps, Newton iterations, max iterations of a step, iteration-matrix
    factorisations; ``stats.value``: max complementarity and cone residuals, max penetration
    over every accepted step [m];
    ``work.final`` (2, n_dof) = displacement and velocity at the last accepted step;
    ``output.peaks``: peaks and gap closures over every step (:mod:`.peaks`; the forces of a
    step are its impulses divided by h).
    ``stats.halt[0]`` ≠ 0 stops the loop at the next Newton iteration (RUN_INTERRUPTED). A
    step at which a corner's seat margin becomes negative (:func:`deckpound.analytic.kernels.peaks.
    track_state`) ends the loop with RUN_UNSEATED (failed step = steps = that step, its output
    row not written).
    """
    # subnormal numbers flushed to zero while the loop runs (opt.flush_subnormals,
    # deckpound.analytic.fp_mode); restored before the return
    saved = flush_enter(opt.flush_subnormals)
    stats.count[:] = 0
    stats.value[:] = 0.0
    h = opt.h
    inv_h = 1.0 / h
    inv_out = 1.0 / (opt.stride * h)
    jrec = _start(system, contact, record, output, work)
    dof = work.dof
    n_dof = len(work.dof_slots)
    status = RUN_OK
    failed = 0
    row = 1
    for n in range(opt.nsteps):
        if stats.halt[0] != 0:
            status = RUN_INTERRUPTED
            failed = n + 1
            _copy_state(work.final, dof.q, dof.v, n_dof)
            break
        t1 = (n + 1) * h
        jrec, nact = _predict(system, contact, record, work, h, t1, jrec, stats.count)
        status = _solve(system, work, opt, nact, stats)
        if status != RUN_OK:
            _copy_state(work.final, dof.qk, dof.vk, n_dof)
            failed = n + 1
            break
        _commit(system, work, h, opt.theta)
        _commit_contact(contact, work, output.peaks, nact, opt.theta, inv_h, stats.value)
        pk = output.peaks
        if track_state(
            pk,
            t1,
            dof.q,
            dof.v,
            work.corner.gapo,
            pk.force[0],
            pk.force[1],
            work.spring.fs,
            work.ug,
            work.spring.d,
        ):
            # a seat margin became negative (.peaks): the answer ends with this step
            status = RUN_UNSEATED
            failed = n + 1
            break
        if (n + 1) % opt.stride == 0:
            _store(system, contact, output, work, row, t1, inv_out)
            row += 1
    if status in (RUN_OK, RUN_UNSEATED):
        _copy_state(work.final, dof.q, dof.v, n_dof)
    _finish(stats, status, row, failed, opt.nsteps, h)
    flush_leave(saved)

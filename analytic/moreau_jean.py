r"""The Moreau–Jean step loop of the nonsmooth engine.

Driven by :func:`deckpound.analytic.nonsmooth.run_nonsmooth`; the model, the output columns
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
:mod:`deckpound.analytic.frictional_contact` with the Delassus matrix G = W Ŵ⁻¹ Wᵀ, free
contact velocities W v_free and U_N⁻ = W_N v_k, solved exactly (Lemke with Stewart–Trinkle
Lemke and enumeration fall-backs for ``solver = lemke``; enumeration only for
``solver = enumeration``) and verified against the contact laws (relative tolerance
``nonsmooth.tolerance``); an unverified solve fails the run at that step. Steps without an
active corner skip the contact solve; frictionless runs (μ = 0) carry only normal unknowns.

Active but separating corners. A corner can be active (g(q_M) ≤ 0) while it already separates
(U_N⁻ > 0, typically the step after an impact or in persistent contact with the seat springs
pushing). Newton's law there (U_N⁺ ≥ −e U_N⁻; ``nonsmooth.impact_law = "newton"``, the
default, as Siconos) lets a positive P_N do positive work ½ P_N (1 − e) U_N⁻ on v_m for θ = ½,
i.e. gain energy (0.2 % of the impact dissipation on the benchmark, see the README). With
``impact_law = "energy-safe"`` such corners use the restitution max(e, (1 − θ)/θ) instead
(``esep``, :func:`deckpound.analytic.nonsmooth.separating_restitution`;
= 1 for θ = ½, = e for θ = 1): then P_N > 0 implies θU_N⁺ + (1−θ)U_N⁻ ≤ 0 (= 0 for θ = ½) and
the normal impulse does no positive work, so for frictionless contact every step is
dissipative (tested); approaching corners (U_N⁻ ≤ 0, the
impacts) keep Newton's law unchanged. Friction keeps the standard law on U_T⁺; its work on
v_m is −μP_N|U_T⁺| ≤ 0 for θ = 1 but not sign-definite for θ < 1, and with e > 0 Newton's law
combined with Coulomb friction can gain energy in an impact (Kane's paradox, see
:mod:`deckpound.analytic.frictional_contact`).
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
from deckpound.analytic.dense import lu_factor, lu_solve
from deckpound.analytic.fp_mode import flush_enter, flush_leave
from deckpound.analytic.frictional_contact import STATUS_FAILED
from deckpound.analytic.impulses import solve_active_impulses
from deckpound.analytic.kinematics import contact_kinematics, linear_gap
from deckpound.analytic.moreau_jean_work import (
    N_ENERGY,
    MoreauJeanOptions,
    MoreauJeanWork,
    moreau_jean_workspace,
    output_energies,
    store_row,
)
from deckpound.analytic.nonsmooth import ENERGY_COLUMNS
from deckpound.analytic.peaks import track_step
from deckpound.analytic.support_motion import record_at
from deckpound.analytic.system import (
    spring_assemble,
    spring_commit,
    spring_deformations,
    spring_stored_energy,
    spring_tangent,
    spring_update_materials,
    store_standard,
)

__all__ = [
    "ENERGY_COLUMNS",
    "N_ENERGY",
    "MoreauJeanOptions",
    "MoreauJeanWork",
    "moreau_jean_run",
    "moreau_jean_workspace",
]


@kernel
def _iteration_matrix(sa, Cmat, kt, h, theta, K, LU, piv):
    """LU of Ŵ = M + θhC + θ²h² Bᵀ diag(kt) B (K scratch). Returns False if singular."""
    spring_tangent(sa, kt, K)
    c1 = theta * h
    c2 = c1 * c1
    for i in range(7):
        for j in range(7):
            LU[i, j] = c1 * Cmat[i, j] + c2 * K[i, j]
        LU[i, i] += sa.mass[i]
    return lu_factor(LU, piv)


@kernel(nogil=True)
def moreau_jean_run(system, contact, record, opt, output, work, stats):
    """The Moreau–Jean step loop over ``opt.nsteps`` steps of length opt.h.

    Bundles of :mod:`deckpound.analytic.bundles` (``system``, ``contact`` — its corner table
    and kinematics flag —, ``record``, ``output``, ``stats``), scalars
    :data:`MoreauJeanOptions`, workspace :data:`MoreauJeanWork`.

    Support motion: the record of :func:`deckpound.analytic.support_motion.support_record`,
    interpolated at t_n = n·h in the loop (identical to ``motion.resample(h)``, bounded memory).

    Fills ``output.table`` (one row per output), ``stats.count``: status (RUN_OK,
    RUN_NOT_CONVERGED, RUN_CONTACT_UNSOLVED, RUN_NONFINITE, RUN_SINGULAR, RUN_INTERRUPTED),
    rows written, failed step, steps, contact solves, contact events (corner activations),
    contact steps, Newton iterations, max iterations of a step, iteration-matrix
    factorisations; ``stats.value``: max complementarity and cone residuals, max penetration
    over every accepted step [m];
    ``work.final`` (2, 7) = displacement and velocity at the last accepted step;
    ``output.peaks``: peaks and gap closures over every step (:mod:`.peaks`; the forces of a
    step are its impulses divided by h).
    ``stats.halt[0]`` ≠ 0 stops the loop at the next Newton iteration (RUN_INTERRUPTED). A
    step at which a corner's seat margin becomes negative (:func:`deckpound.analytic.peaks.
    track_step`) ends the loop with RUN_UNSEATED (failed step = steps = that step, its output
    row not written).
    """
    # subnormal numbers flushed to zero while the loop runs (opt.flush_subnormals,
    # deckpound.analytic.fp_mode); every return below restores the thread's mode first
    saved = flush_enter(opt.flush_subnormals)
    sa = system
    Cmat = sa.C
    nbs = sa.nbs
    geom = contact.corners
    nonlinear = contact.nonlinear
    tb, DG, VGR, SDG, SVG = record.t, record.disp, record.vel, record.dslope, record.vslope
    nsteps, h, theta, ecoef, esep, mu = opt.nsteps, opt.h, opt.theta, opt.ecoef, opt.esep, opt.mu
    mode, rtol, ftol, maxit, stride = opt.mode, opt.rtol, opt.ftol, opt.maxit, opt.stride
    halt = stats.halt
    ns = sa.k0.shape[0]
    nch = DG.shape[1]
    mass = sa.mass
    hp = sa.hparams
    kind = sa.kind
    a0 = sa.scal[0]
    wk = work
    hstate, uv_end, u0, v0 = wk.hstate, wk.final, wk.u0, wk.v0
    dof, spr, cor = wk.dof, wk.spring, wk.corner
    q, v, qk, vk, qM, vfree, vnew, R, dv, Fk, f = (
        dof.q,
        dof.v,
        dof.qk,
        dof.vk,
        dof.qM,
        dof.vfree,
        dof.vnew,
        dof.R,
        dof.dv,
        dof.Fk,
        dof.f,
    )
    K, LU, piv = dof.K, dof.LU, dof.piv
    # spring quantities: committed start of step (k), linearisation point (lin), new iterate;
    # kt_fact: tangents of the factors held in LU (NaN: none); sdu, sdv: S Δu_g, S Δu̇_g
    (kt_fact, d_k, dd_k, fs_k, kt_k, d_lin, fs_lin, kt_lin, d, dd, fs, kt, sdu, sdv) = (
        spr.kt_fact,
        spr.d_k,
        spr.dd_k,
        spr.fs_k,
        spr.kt_k,
        spr.d_lin,
        spr.fs_lin,
        spr.kt_lin,
        spr.d,
        spr.dd,
        spr.fs,
        spr.kt,
        spr.sdu,
        spr.sdv,
    )
    gap, gapo, P_N, P_T, pn_acc, pt_acc, fn_out, ft_out = (
        cor.gap,
        cor.gapo,
        cor.P_N,
        cor.P_T,
        cor.pn_acc,
        cor.pt_acc,
        cor.fn_out,
        cor.ft_out,
    )
    WN, WT, WNo, WTo = cor.WN, cor.WT, cor.WNo, cor.WTo
    act, state, was_active = cor.act, cor.state, cor.was_active
    ug, vg, ugo, vgo = wk.ug, wk.vg, wk.ugo, wk.vgo
    W, energy = wk.W, wk.energy
    th = theta
    th1 = 1.0 - theta
    # ---- initial state
    jrec = record_at(tb, DG, VGR, SDG, SVG, 0.0, 0, ug, vg)
    for j in range(7):
        q[j] = u0[j]
        v[j] = v0[j]
    spring_deformations(sa, q, v, ug, vg, d_k, dd_k)
    spring_update_materials(hp, hstate, kind, d_k)
    spring_assemble(sa, hstate, d_k, dd_k, v, Fk, fs_k, kt_k)
    spring_commit(sa, hstate)
    es0 = spring_stored_energy(sa, hstate, q, ug)
    ke0 = 0.0
    for j in range(7):
        ke0 += 0.5 * mass[j] * v[j] * v[j]
    W[0] = ke0 + es0
    W[1] = es0
    contact_kinematics(q, geom, nonlinear, gapo, WNo, WTo)
    contact_kinematics(q, geom, nonlinear, gap, WN, WT)
    output_energies(sa, hstate, q, v, ug, W, energy)
    store_row(output, 0, 0.0, q, v, gapo, fn_out, ft_out, fs_k, nbs, pn_acc, pt_acc, state, energy)
    # peaks and gap closures of every step (.peaks): the step's forces are its impulses / h
    pk = output.peaks
    fn_step, ft_step = pk.force[0], pk.force[1]
    inv_h = 1.0 / h
    store_standard(pk.row, 0.0, q, v, gapo, fn_step, ft_step, fs_k, nbs)
    track_step(pk, 0.0, q, ug, d_k, nbs)
    row = 1
    solves = 0
    events = 0
    csteps = 0
    newton = 0
    maxit_seen = 0
    nfact = 0
    max_comp = 0.0
    max_cone = 0.0
    max_pen = 0.0
    status = RUN_OK
    failed = 0
    inv_out = 1.0 / (stride * h)
    for n in range(nsteps):
        if halt[0] != 0:
            status = RUN_INTERRUPTED
            failed = n + 1
            for j in range(7):
                uv_end[0, j] = q[j]
                uv_end[1, j] = v[j]
            break
        # ---- support motion at t_{n+1} and its increment (per spring)
        for k in range(nch):
            ugo[k] = ug[k]
            vgo[k] = vg[k]
        jrec = record_at(tb, DG, VGR, SDG, SVG, (n + 1) * h, jrec, ug, vg)
        for i in range(ns):
            ch = sa.schan[i]
            if ch >= 0:
                sdu[i] = sa.sval[i] * (ug[ch] - ugo[ch])
                sdv[i] = sa.sval[i] * (vg[ch] - vgo[ch])
            else:
                sdu[i] = 0.0
                sdv[i] = 0.0
        for j in range(7):
            qk[j] = q[j]
            vk[j] = v[j]
            qM[j] = q[j] + 0.5 * h * v[j]
        # ---- active set at the predicted mid-step position (linear kinematics: W_N, W_T are
        # constant, filled before the loop, so only the gaps change)
        if nonlinear:
            contact_kinematics(qM, geom, nonlinear, gap, WN, WT)
        else:
            for c in range(4):
                gap[c] = linear_gap(geom[c], qM)
        nact = 0
        for c in range(4):
            if gap[c] <= 0.0:
                act[nact] = c
                nact += 1
                if not was_active[c]:
                    events += 1
                was_active[c] = True
            else:
                was_active[c] = False
        if nact > 0:
            csteps += 1
        # ---- iteration 0: residual of the linearisation about the committed state
        # R = h F_k + θh Bᵀ[k_t ∘ (h B v_k − SΔu_g) − crate ∘ SΔu̇_g]
        for j in range(7):
            R[j] = h * Fk[j]
        for i in range(ns):
            bv = 0.0
            for r in range(sa.bnnz[i]):
                bv += sa.bval[i, r] * vk[sa.bidx[i, r]]
            t_i = th * h * (kt_k[i] * (h * bv - sdu[i]) - sa.crate[i] * sdv[i])
            for r in range(sa.bnnz[i]):
                R[sa.bidx[i, r]] += sa.bval[i, r] * t_i
            d_lin[i] = d_k[i]
            fs_lin[i] = fs_k[i]
            kt_lin[i] = kt_k[i]
        for j in range(7):
            v[j] = vk[j]
        it = 0
        converged = False
        while True:
            # ---- iteration matrix (refactored only when a tangent changed)
            same = True
            for i in range(ns):
                if kt_lin[i] != kt_fact[i]:
                    same = False
                    break
            if not same:
                if not _iteration_matrix(sa, Cmat, kt_lin, h, theta, K, LU, piv):
                    status = RUN_SINGULAR
                    break
                nfact += 1
                for i in range(ns):
                    kt_fact[i] = kt_lin[i]
            # ---- free velocity v_free = v − Ŵ⁻¹ R
            lu_solve(LU, piv, R, dv)
            for j in range(7):
                vfree[j] = v[j] - dv[j]
            # ---- contact
            if nact > 0:
                cst, comp, cone = solve_active_impulses(
                    LU,
                    piv,
                    WN,
                    WT,
                    act,
                    nact,
                    vk,
                    vfree,
                    ecoef,
                    esep,
                    mu,
                    mode,
                    rtol,
                    P_N,
                    P_T,
                    state,
                    vnew,
                    wk.impulse,
                )
                solves += 1
                if cst == STATUS_FAILED:
                    status = RUN_CONTACT_UNSOLVED
                    break
                max_comp = max(max_comp, comp)
                max_cone = max(max_cone, cone)
                for j in range(7):
                    v[j] = vnew[j]
            else:
                for j in range(7):
                    v[j] = vfree[j]
            for j in range(7):
                q[j] = qk[j] + h * (th1 * vk[j] + th * v[j])
            # ---- springs at the new iterate
            spring_deformations(sa, q, v, ug, vg, d, dd)
            spring_update_materials(hp, hstate, kind, d)
            spring_assemble(sa, hstate, d, dd, v, f, fs, kt)
            it += 1
            rmax = 0.0
            for i in range(ns):
                if kind[i] == 1:
                    r_i = abs(fs[i] - fs_lin[i] - kt_lin[i] * (d[i] - d_lin[i]))
                    rmax = max(rmax, r_i)
            if not np.isfinite(rmax):
                status = RUN_NONFINITE
                break
            if rmax <= ftol:
                converged = True
                break
            if it >= maxit:
                status = RUN_NOT_CONVERGED
                break
            if halt[0] != 0:
                status = RUN_INTERRUPTED
                break
            # ---- Newton: residual of the θ-equation at the iterate (contact impulse excluded)
            for j in range(7):
                R[j] = mass[j] * (v[j] - vk[j]) + h * (th1 * Fk[j] + th * f[j])
            for i in range(ns):
                d_lin[i] = d[i]
                fs_lin[i] = fs[i]
                kt_lin[i] = kt[i]
        newton += it
        maxit_seen = max(maxit_seen, it)
        if converged:
            for j in range(7):
                if not np.isfinite(v[j]) or not np.isfinite(q[j]):
                    status = RUN_NONFINITE
        if status != RUN_OK:
            for j in range(7):
                uv_end[0, j] = qk[j]
                uv_end[1, j] = vk[j]
            failed = n + 1
            break
        spring_commit(sa, hstate)
        # ---- energy (exact work of the θ-scheme over the step)
        for i in range(ns):
            fth = th * fs[i] + th1 * fs_k[i]
            cth = sa.crate[i] * (th * dd[i] + th1 * dd_k[i])
            dlt = d[i] - d_k[i]
            W[0] -= sdu[i] * (fth + cth)
            W[1] += dlt * fth
            W[2] += dlt * cth
            d_k[i] = d[i]
            dd_k[i] = dd[i]
            fs_k[i] = fs[i]
            kt_k[i] = kt[i]
        num = 0.0
        for j in range(7):
            vm = th1 * vk[j] + th * v[j]
            W[2] += a0 * mass[j] * (q[j] - qk[j]) * vm
            dvj = v[j] - vk[j]
            num += mass[j] * dvj * dvj
            Fk[j] = f[j]
        W[5] += (th - 0.5) * num
        # ---- penetration at q_{k+1}, every step (the output rows see one step in `stride`)
        if nonlinear:
            contact_kinematics(q, geom, nonlinear, gapo, WNo, WTo)
        else:
            for c in range(4):
                gapo[c] = linear_gap(geom[c], q)
        for c in range(4):
            max_pen = max(max_pen, -gapo[c])
            fn_step[c] = 0.0
            ft_step[c] = 0.0
        if nact > 0:
            for a in range(nact):
                c = act[a]
                uN = 0.0
                uT = 0.0
                for j in range(7):
                    vm = th1 * vk[j] + th * v[j]
                    uN += WN[c, j] * vm
                    uT += WT[c, j] * vm
                W[3] -= P_N[c] * uN
                W[4] -= P_T[c] * uT
                pn_acc[c] += P_N[c]
                pt_acc[c] += P_T[c]
                fn_step[c] = P_N[c] * inv_h
                ft_step[c] = P_T[c] * inv_h
        else:
            for c in range(4):
                state[c] = 0
        store_standard(pk.row, (n + 1) * h, q, v, gapo, fn_step, ft_step, fs, nbs)
        if track_step(pk, (n + 1) * h, q, ug, d, nbs):
            # a seat margin became negative (.peaks): the answer ends with this step
            status = RUN_UNSEATED
            failed = n + 1
            break
        # ---- output
        if (n + 1) % stride == 0:
            contact_kinematics(q, geom, nonlinear, gapo, WNo, WTo)
            for c in range(4):
                fn_out[c] = pn_acc[c] * inv_out
                ft_out[c] = pt_acc[c] * inv_out
            output_energies(sa, hstate, q, v, ug, W, energy)
            store_row(
                output,
                row,
                (n + 1) * h,
                q,
                v,
                gapo,
                fn_out,
                ft_out,
                fs,
                nbs,
                pn_acc,
                pt_acc,
                state,
                energy,
            )
            row += 1
            for c in range(4):
                pn_acc[c] = 0.0
                pt_acc[c] = 0.0
    if status in (RUN_OK, RUN_UNSEATED):
        for j in range(7):
            uv_end[0, j] = q[j]
            uv_end[1, j] = v[j]
    # steps completed: all, the unseating step included, or those before the failed one
    done = nsteps if status == RUN_OK else (failed if status == RUN_UNSEATED else failed - 1)
    cnt = stats.count
    cnt[bd.CNT_STATUS] = status
    cnt[bd.CNT_ROWS] = row
    cnt[bd.CNT_FAILED_STEP] = failed
    cnt[bd.CNT_STEPS] = done
    cnt[bd.CNT_SOLVES] = solves
    cnt[bd.CNT_EVENTS] = events
    cnt[bd.CNT_CONTACT_STEPS] = csteps
    cnt[bd.CNT_NEWTON] = newton
    cnt[bd.CNT_MAX_IT] = maxit_seen
    cnt[bd.CNT_FACTORISATIONS] = nfact
    stats.value[bd.VAL_MAX_COMP] = max_comp
    stats.value[bd.VAL_MAX_CONE] = max_cone
    stats.value[bd.VAL_MAX_PEN] = max_pen
    stats.value[bd.VAL_TIME] = done * h
    flush_leave(saved)

"""The Newmark–Newton step loop of the compliance engine (``compliance.integrator = newmark``).

Driven by :func:`deckpound.analytic.compliance.engine.run_compliance`; the model and the result
columns are described there.

The OpenSees transient algorithm, step for step: Newmark γ = ½, β = ¼
(``integrator('Newmark', 0.5, 0.25)``, displacement form), full Newton
(``algorithm('Newton')``), ``test('NormDispIncr', tol, max_iterations)``:

* ``Newmark::newStep``: constant-displacement predictor u⁰ = u_n,
  u̇⁰ = (1 − γ/β) u̇_n + Δt (1 − γ/(2β)) ü_n, ü⁰ = (1 − 1/(2β)) ü_n − u̇_n/(βΔt); supports at
  t_{n+1}; residual.
* each iteration: tangent K_t + γ/(βΔt) C_t + 1/(βΔt²) M at the last trial state, solve,
  ``Newmark::update`` (u += Δu, u̇ += γ/(βΔt) Δu, ü += Δu/(βΔt²)), residual, test
  ‖Δu‖₂ ≤ tol (``CTestNormDispIncr``: ≤, the 2-norm of the whole increment vector, failure
  after ``max_iterations`` solves).
* materials committed after convergence; ü₀ = 0 at t = 0 (OpenSees starts from rest; the
  records start at rest).
* a step that does not converge is redone from its start in 10 sub-steps (the OpenSees
  engine's ``fallback = "substep"``); counted in ``failures`` / ``rescued_by_substeps``.

The whole step loop is one numba kernel compiled without numba's runtime (:mod:`._jit`) that
takes the named bundles of :mod:`.bundles` (workspace from
:func:`.newmark_work.newmark_workspace`, scalars
in :data:`.newmark_work.NewmarkOptions`); the contact laws are skipped while every corner's
gap is open (g > 0, where every law gives zero force) and the tangent factorisation is reused
while the matrix is bitwise the one factorised (identical matrix → identical factors, so results
do not change): the elastic one, or the last one while its key stays (the step, the spring
tangents and, for linear contact kinematics, the evaluated corners and their law derivatives,
:func:`_held_factors_fit`), in contact too. ``stats`` counts the factorisations and the reuses.
Output every :func:`deckpound.compare.engines.output_stride` steps.

:func:`newmark_run` is a short driver over stages, each a kernel inlined into it
(``inline="always"``: one compiled loop, no calls that pass the bundles by value): at the
start :func:`_start`; per step :func:`_begin_step` and :func:`_step` (one attempt, or the
sub-step fallback after :func:`_revert_step`); per (sub)step :func:`_predict`,
:func:`_form_unbalance`, the Newton iteration :func:`_newton` (:func:`_solve` and
:func:`_update`), :func:`_commit` and :func:`_accumulate_work`; :func:`_store_output` writes a
row. Array sizes (DOF, corners, springs, channels) are those of the bundles' arrays.
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic._jit import kernel
from deckpound.analytic.bundles import (
    RUN_INTERRUPTED,
    RUN_NONFINITE,
    RUN_NOT_CONVERGED,
    RUN_OK,
    RUN_SINGULAR,
    RUN_UNSEATED,
)
from deckpound.analytic.compliance.newmark_work import output_energies, store_row
from deckpound.analytic.compliance.work_energy import (
    W_CONTACT,
    W_FRICTION,
    W_INPUT,
    W_SPRINGS,
    W_VISCOUS,
)
from deckpound.analytic.fp_mode import flush_enter, flush_leave
from deckpound.analytic.kernels import contact_assembly as ca
from deckpound.analytic.kernels import contact_laws as cl
from deckpound.analytic.kernels.contact_assembly import N_TANGENT_DERIVATIVES
from deckpound.analytic.kernels.dense import lu_factor, lu_solve
from deckpound.analytic.kernels.peaks import track_state
from deckpound.analytic.kernels.support_motion import record_at
from deckpound.analytic.kernels.system import (
    SCAL_A0,
    SCAL_TANGENT_DAMPING,
    spring_assemble,
    spring_commit,
    spring_damping_tangent,
    spring_deformations,
    spring_revert,
    spring_stored_energy,
    spring_tangent,
    spring_update_materials,
)

__all__ = ["BETA", "GAMMA", "newmark_run"]

GAMMA, BETA = 0.5, 0.25


@kernel(inline="always")
def _form_unbalance(sa, contact, hstate, cs, cw, dof, spr, sup, skip_contact):
    """OpenSees ``formUnbalance`` at the trial (u, u̇, ü) of ``dof`` and the supports (u_g,
    u̇_g) of ``sup``.

    Springs: trial material state, F (into dof.f), restoring forces spr.fs and tangents spr.kt.
    Contacts: the gap check, then the laws of the closed corners (every corner when
    ``skip_contact`` is off, linear kinematics). Residual R = F_c − F − M ü. dof.un:
    displacement at the step start. Returns (number of springs off their elastic tangent, any
    corner evaluated).
    """
    u, v = dof.u, dof.v
    d, dd = spr.d_new, spr.dd_new
    spring_deformations(sa, u, v, sup.ug, sup.vg, d, dd)
    spring_update_materials(sa.hparams, hstate, sa.kind, d)
    nonel = spring_assemble(sa, hstate, d, dd, v, dof.f, spr.fs, spr.kt)
    ncl = ca.eval_contacts(contact, cs, cw, u, v, dof.un, sa.dofs)
    evaluated = cw.evaluated
    if not skip_contact and not contact.nonlinear:
        for c in range(len(cw.corners)):
            evaluated[c] = True
        ncl = -1
    if ncl < 0:
        ca.eval_closed(contact, cs, cw, u, v, dof.un, sa.dofs)
    R, f, a = dof.R, dof.f, dof.a
    for j in range(len(sa.dofs)):
        R[j] = cw.fc[j] - f[j] - sa.mass[j] * a[j]
    any_evaluated = False
    for c in range(len(cw.corners)):
        any_evaluated = any_evaluated or evaluated[c]
    return nonel, any_evaluated


@kernel
def _set_stats(stats, status, rows, failed, steps, dt):
    """Write how the loop ended: status, rows written, failed step and steps completed; time
    reached = steps · dt [s]. (The loop adds its counts to ``stats.count`` as it goes.)"""
    stats.value[bd.VAL_TIME] = steps * dt
    cnt = stats.count
    cnt[bd.CNT_STATUS] = status
    cnt[bd.CNT_ROWS] = rows
    cnt[bd.CNT_FAILED_STEP] = failed
    cnt[bd.CNT_STEPS] = steps


@kernel(inline="always")
def _effective_tangent(sa, K, c2, c3, Keff):
    """Keff = K + c2 C + c3 M (Newmark's effective tangent, c2 = γ/(βh), c3 = 1/(βh²))."""
    n = len(sa.dofs)
    for i in range(n):
        for j in range(n):
            Keff[i, j] = K[i, j] + c2 * sa.C[i, j]
        Keff[i, i] += c3 * sa.mass[i]


@kernel(inline="always")
def _copy(src, dst, n):
    """dst[:n] = src[:n] (no allocation; n a compile-time constant where it can be)."""
    for i in range(n):
        dst[i] = src[i]


@kernel(inline="always")
def _copy_matrix(src, dst, n):
    """dst[:n, :n] = src[:n, :n] (no allocation)."""
    for i in range(n):
        for j in range(n):
            dst[i, j] = src[i, j]


@kernel(inline="always")
def _elastic_factors(sa, mat, dt):
    """Kel, the effective tangent of the main step with every spring elastic, and its factors
    (LUel, pivel); False if singular."""
    spring_tangent(sa, sa.k0, mat.K)
    _effective_tangent(sa, mat.K, GAMMA / (BETA * dt), 1.0 / (BETA * dt * dt), mat.Kel)
    _copy_matrix(mat.Kel, mat.LUel, len(sa.dofs))
    return lu_factor(mat.LUel, mat.pivel, sa.dofs)


@kernel(inline="always")
def _remember_committed(sa, work):
    """The committed contact forces and gaps, spring forces, deformations, rates and
    tangent-dependent damping coefficients, for the next step's trapezoidal work."""
    cw, spr = work.cw, work.spring
    nc, ns = len(cw.corners), spr.fs.shape[0]
    _copy(cw.lam, work.lam_prev, nc)
    _copy(cw.lt, work.lt_prev, nc)
    _copy(cw.g, work.g_prev, nc)
    _copy(spr.fs, spr.fs_prev, ns)
    _copy(spr.d_new, spr.d_prev, ns)
    _copy(spr.dd_new, spr.dd_prev, ns)
    _copy(sa.cvar, spr.cv_prev, ns)


@kernel(inline="always")
def _start(sa, contact, record, opt, output, work):
    """The state at t = 0: supports, u0, v0, ü₀ from M ü₀ = F_c − F (zero at rest, as
    OpenSees), materials and contacts committed, the initial mechanical energy counted as
    input, output row 0 and the peaks. Returns the record hint."""
    dof, sup, cw, W = work.dof, work.support, work.cw, work.W
    hstate, cs = work.hstate, work.cstate
    jrec = record_at(
        record.t, record.disp, record.vel, record.dslope, record.vslope, 0.0, 0, sup.ug1, sup.vg1
    )
    nd, nch = len(sa.dofs), sup.ug.shape[0]
    _copy(sup.ug1, sup.ug, nch)
    _copy(sup.vg1, sup.vg, nch)
    _copy(work.u0, dof.u, nd)
    _copy(work.v0, dof.v, nd)
    _copy(work.u0, dof.un, nd)
    ca.linear_rows(contact, cw, work.u0, sa.dofs)
    _form_unbalance(sa, contact, hstate, cs, cw, dof, work.spring, sup, opt.skip_contact)
    for j in range(nd):
        dof.a[j] = (cw.fc[j] - dof.f[j]) / sa.mass[j]
    spring_commit(sa, hstate)
    cl.contact_commit(cs, cw.g, cw.gd, cw.evaluated)
    _remember_committed(sa, work)
    es0 = spring_stored_energy(sa, hstate, dof.u, sup.ug)
    ec0 = cl.contact_stored_energy(contact.params, cs)
    ke0 = 0.0
    for j in range(nd):
        ke0 += 0.5 * sa.mass[j] * dof.v[j] * dof.v[j]
    W[W_INPUT] = ke0 + es0 + ec0
    W[W_SPRINGS] = es0
    W[W_CONTACT] = ec0
    _store_output(sa, contact, work, output, 0, 0.0, True)
    _track_peaks(output.peaks, 0.0, dof, cw, cs, work.spring, sup)
    return jrec


@kernel(inline="always")
def _track_peaks(pk, t, dof, cw, cs, spr, sup):
    """The peaks and closures of the committed state at t [s] (:func:`.peaks.track_state`):
    the columns :func:`.newmark_work.fill_row` writes (the committed tangential force
    ``cs[:, S_CFT]``, as the output rows). Returns True when a seat margin became negative."""
    return track_state(
        pk, t, dof.u, dof.v, cw.g, cw.lam, cs[:, cl.S_CFT], spr.fs, sup.ug, spr.d_new
    )


@kernel(inline="always")
def _store_output(sa, contact, work, output, row, t, energy):
    """Output row ``row`` at time t (energy columns updated first when ``energy``)."""
    dof = work.dof
    if energy:
        output_energies(
            sa,
            work.hstate,
            contact.params,
            work.cstate,
            dof.u,
            dof.v,
            work.support.ug,
            work.W,
            work.energy,
        )
    store_row(output, row, t, dof.u, dof.v, work.cw, work.cstate, work.spring.fs, work.energy)


@kernel(inline="always")
def _begin_step(nd, record, work, t1, jrec):
    """Keep the state at the step start (for a sub-stepped redo) and move the end-of-step
    supports to t1 [s]. Returns the record hint."""
    dof, sup = work.dof, work.support
    nch = sup.ug.shape[0]
    _copy(dof.u, dof.us, nd)
    _copy(dof.v, dof.vs, nd)
    _copy(dof.a, dof.as_, nd)
    _copy(sup.ug1, sup.ug0, nch)
    _copy(sup.vg1, sup.vg0, nch)
    return record_at(
        record.t, record.disp, record.vel, record.dslope, record.vslope, t1, jrec, sup.ug1, sup.vg1
    )


@kernel(inline="always")
def _revert_step(sa, work):
    """Back to the start of the step: trial materials and corners reverted, state and
    supports restored."""
    dof, sup = work.dof, work.support
    nd, nch = len(sa.dofs), sup.ug.shape[0]
    spring_revert(sa, work.hstate)
    cl.contact_revert(work.cstate)
    _copy(dof.us, dof.u, nd)
    _copy(dof.vs, dof.v, nd)
    _copy(dof.as_, dof.a, nd)
    _copy(sup.ug0, sup.ug, nch)
    _copy(sup.vg0, sup.vg, nch)


@kernel(inline="always")
def _predict(nd, work, nsub, ksub, h):
    """``Newmark::newStep`` of sub-step ksub of nsub (step h [s]): supports at its end
    (linearly interpolated between the step's ends when sub-stepping), start state kept in
    un, vn, an, constant-displacement predictor of u̇ and ü."""
    dof, sup = work.dof, work.support
    ug, vg = sup.ug, sup.vg
    for k in range(ug.shape[0]):
        sup.ugo[k] = ug[k]
        if nsub == 1:
            ug[k] = sup.ug1[k]
            vg[k] = sup.vg1[k]
        else:
            w = (ksub + 1.0) / nsub
            ug[k] = sup.ug0[k] + w * (sup.ug1[k] - sup.ug0[k])
            vg[k] = sup.vg0[k] + w * (sup.vg1[k] - sup.vg0[k])
    _copy(dof.u, dof.un, nd)
    _copy(dof.v, dof.vn, nd)
    _copy(dof.a, dof.an, nd)
    a1p = 1.0 - GAMMA / BETA
    a2p = h * (1.0 - 0.5 * GAMMA / BETA)
    a3p = -1.0 / (BETA * h)
    a4p = 1.0 - 0.5 / BETA
    v, a, vn, an = dof.v, dof.a, dof.vn, dof.an
    for j in range(nd):
        v[j] = a1p * vn[j] + a2p * an[j]
        a[j] = a4p * an[j] + a3p * vn[j]


@kernel(inline="always")
def _same_tangents(kt, kt_fact):
    """True when every spring tangent is bitwise the one of the held factors."""
    same = True
    for i in range(kt.shape[0]):
        if kt[i] != kt_fact[i]:
            same = False
            break
    return same


@kernel(inline="always")
def _same_contact_key(cw, ev_fact, der_fact):
    """True when the corners evaluated at the last trial are those whose contact tangent the
    held factors contain (``ev_fact``), each with the same law derivatives ∂λ/∂(g, ġ, Δs, U_T,
    λ_N) (``der_fact``, :data:`.contact_assembly.N_TANGENT_DERIVATIVES`).

    Equal as numbers is enough: the derivatives enter Keff only through sums onto entries
    that are never −0 (they start from K + c2 C + c3 M, whose zeros are +0, and x + y = 0 is
    +0), so a −0 in place of a +0 changes no bit of Keff."""
    for c in range(len(cw.corners)):
        ev = cw.evaluated[c]
        if ev != ev_fact[c]:
            return False
        if ev:
            for k in range(N_TANGENT_DERIVATIVES):
                if cw.der[c, k] != der_fact[c, k]:
                    return False
    return True


@kernel(inline="always")
def _hold_contact_key(cw, ev_fact, der_fact):
    """Record the contact part of the key of the factors just formed (:func:`_same_contact_key`)."""
    for c in range(len(cw.corners)):
        ev = cw.evaluated[c]
        ev_fact[c] = ev
        if ev:
            for k in range(N_TANGENT_DERIVATIVES):
                der_fact[c, k] = cw.der[c, k]


@kernel(inline="always")
def _held_factors_fit(contact, work, h, anyev, lu_held, lu_h):
    """True when the factors held in LU are those of the effective tangent at the last trial
    state, bit for bit: Keff = K(k_t) + c2 C + c3 M + Σ_c (contact tangent of corner c) is a
    function of the step h, the spring tangents k_t, the corners evaluated and their law
    derivatives, and of W_N, W_T, which are constant for linear kinematics. With nonlinear
    kinematics and a corner evaluated, W_N and the geometric term λ_N ∂²g/∂u² change with u:
    never reused. (Tangent-dependent damping, whose matrix also changes with k_t and k_c,
    turns every reuse off in :func:`_run_steps`.)"""
    if not lu_held or lu_h != h:
        return False
    if anyev and contact.nonlinear:
        return False
    if not _same_tangents(work.spring.kt, work.spring.kt_fact):
        return False
    return _same_contact_key(work.cw, work.mat.ev_fact, work.mat.der_fact)


@kernel(inline="always")
def _solve(sa, contact, work, stats, h, nsub, nonel, anyev, reuse, lu_held, lu_h):
    """formTangent + solve: du = Keff⁻¹ R at the last trial state.

    The factors are reused when the matrix is bitwise the one they factor (``reuse``): the
    elastic factors of the main step when every spring is elastic and no corner is evaluated,
    or the factors held in LU (``lu_held``, of the step ``lu_h``) when their key matches
    (:func:`_held_factors_fit`), in contact too. Otherwise Keff is assembled and factorised
    (``stats`` counts factorisations, reuses and reuses of factors with contact terms).
    Returns (factorised or reused without a singular pivot, lu_held, lu_h) of the factors now
    held in LU.
    """
    mat, spr, dof = work.mat, work.spring, work.dof
    cnt = stats.count
    if reuse:
        if not anyev and nonel == 0 and nsub == 1:
            lu_solve(mat.LUel, mat.pivel, dof.R, dof.du, sa.dofs)
            cnt[bd.CNT_REUSED] += 1
            return True, lu_held, lu_h
        if _held_factors_fit(contact, work, h, anyev, lu_held, lu_h):
            lu_solve(mat.LU, mat.piv, dof.R, dof.du, sa.dofs)
            cnt[bd.CNT_REUSED] += 1
            if anyev:
                cnt[bd.CNT_CONTACT_REUSED] += 1
            return True, lu_held, lu_h
    c2 = GAMMA / (BETA * h)
    spring_tangent(sa, spr.kt, mat.K)
    _effective_tangent(sa, mat.K, c2, 1.0 / (BETA * h * h), mat.Keff)
    spring_damping_tangent(sa, c2, mat.Keff)
    if anyev:
        ca.contact_tangent(contact, work.cw, dof.u, c2, mat.Keff, mat.H, sa.dofs)
    _copy_matrix(mat.Keff, mat.LU, len(sa.dofs))
    _copy(spr.kt, spr.kt_fact, spr.kt.shape[0])
    _hold_contact_key(work.cw, mat.ev_fact, mat.der_fact)
    cnt[bd.CNT_FACTORISATIONS] += 1
    if not lu_factor(mat.LU, mat.piv, sa.dofs):
        return False, False, h
    lu_solve(mat.LU, mat.piv, dof.R, dof.du, sa.dofs)
    return True, True, h


@kernel(inline="always")
def _update(nd, dof, h):
    """``Newmark::update``: u += Δu, u̇ += γ/(βh) Δu, ü += Δu/(βh²). Returns (‖Δu‖₂, whether
    any displacement changed bitwise)."""
    c2 = GAMMA / (BETA * h)
    c3 = 1.0 / (BETA * h * h)
    u, v, a, du = dof.u, dof.v, dof.a, dof.du
    nrm = 0.0
    moved = False
    for j in range(nd):
        uj = u[j] + du[j]
        moved = moved or uj != u[j]
        u[j] = uj
        v[j] += c2 * du[j]
        a[j] += c3 * du[j]
        nrm += du[j] * du[j]
    return np.sqrt(nrm), moved


@kernel(inline="always")
def _newton(sa, contact, opt, work, stats, h, nsub, reuse, lu_held, lu_h):
    """The unbalance at the predictor, then Newton iterations until ‖Δu‖₂ ≤ tol
    (``CTestNormDispIncr``), ``opt.maxit`` solves, a singular matrix, a non-finite increment
    or the halt flag; each iteration solves, updates and forms the unbalance at the new
    iterate before the test (the predictor's unbalance and the iterates' share one copy of
    :func:`_form_unbalance` in the compiled loop). Returns (status, iterations, any corner
    evaluated at the last evaluation, lu_held, lu_h)."""
    dof, spr, sup, cw = work.dof, work.spring, work.support, work.cw
    it = 0
    nrm = 0.0
    nonel = 0
    anyev = False
    evaluate = True
    while True:
        if evaluate:
            nonel, anyev = _form_unbalance(
                sa, contact, work.hstate, work.cstate, cw, dof, spr, sup, opt.skip_contact
            )
        if it > 0:
            if not np.isfinite(nrm):
                return RUN_NONFINITE, it, anyev, lu_held, lu_h
            if nrm <= opt.tol:
                return RUN_OK, it, anyev, lu_held, lu_h
            if it >= opt.maxit:
                return RUN_NOT_CONVERGED, it, anyev, lu_held, lu_h
            if stats.halt[0] != 0:
                return RUN_INTERRUPTED, it, anyev, lu_held, lu_h
        ok, lu_held, lu_h = _solve(
            sa, contact, work, stats, h, nsub, nonel, anyev, reuse, lu_held, lu_h
        )
        if not ok:
            return RUN_SINGULAR, it, anyev, lu_held, lu_h
        nrm, moved = _update(len(sa.dofs), dof, h)
        it += 1
        evaluate = not (opt.skip_unmoved and not moved and not anyev and nrm <= opt.tol)
        if not evaluate:
            # converged, and the increment (round-off of a step that stayed on its branches)
            # left u bitwise as it was: the materials, spring forces and gaps are those just
            # evaluated; only the rates follow the new u̇
            spring_deformations(sa, dof.u, dof.v, sup.ug, sup.vg, spr.d_new, spr.dd_new)
            ca.gap_rates(contact, dof.v, cw, sa.dofs)
            stats.count[bd.CNT_UNMOVED] += 1


@kernel(inline="always")
def _commit(sa, contact, work, output, stats, anyev, t_now):
    """Commit a converged (sub)step ending at t_now [s]: materials, contact events (a corner
    that closed), gaps (nonlinear kinematics, when no corner was evaluated), corner states,
    the largest penetration and the peaks of every column at every converged (sub)step.
    Returns True when a seat margin became negative (:func:`.peaks.track_state`)."""
    cs, cw, dof = work.cstate, work.cw, work.dof
    spring_commit(sa, work.hstate)
    for c in range(len(cw.corners)):
        if cs[c, cl.S_CCLOSED] == 0.0 and cs[c, cl.S_TCLOSED] != 0.0 and cw.evaluated[c]:
            stats.count[bd.CNT_EVENTS] += 1
    if contact.nonlinear and not anyev:
        ca.gaps_and_rates(contact, dof.u, dof.v, cw, sa.dofs)
    cl.contact_commit(cs, cw.g, cw.gd, cw.evaluated)
    for c in range(len(cw.corners)):
        if -cw.g[c] > stats.value[bd.VAL_MAX_PEN]:
            stats.value[bd.VAL_MAX_PEN] = -cw.g[c]
    return _track_peaks(output.peaks, t_now, dof, cw, cs, work.spring, work.support)


@kernel(inline="always")
def _accumulate_work(sa, work):
    """Trapezoidal work of the converged (sub)step into ``work.W`` (offsets ``W_*``): support
    input, spring, viscous (dashpots, Rayleigh), contact and friction; the committed values
    move on for the next step."""
    spr, sup, dof, cw, W = work.spring, work.support, work.dof, work.cw, work.W
    var = sa.scal[SCAL_TANGENT_DAMPING] != 0.0
    fs, d_prev, dd_prev, fs_prev = spr.fs, spr.d_prev, spr.dd_prev, spr.fs_prev
    for i in range(fs.shape[0]):
        di = spr.d_new[i]
        vi = spr.dd_new[i]
        ch = sa.schan[i]
        if ch >= 0:
            ftot_o = fs_prev[i] + sa.crate[i] * dd_prev[i]
            ftot_n = fs[i] + sa.crate[i] * vi
            if var:
                ftot_o += spr.cv_prev[i] * dd_prev[i]
                ftot_n += sa.cvar[i] * vi
            W[W_INPUT] -= sa.sval[i] * (sup.ug[ch] - sup.ugo[ch]) * 0.5 * (ftot_o + ftot_n)
        dlt = di - d_prev[i]
        W[W_SPRINGS] += dlt * 0.5 * (fs_prev[i] + fs[i])
        W[W_VISCOUS] += dlt * 0.5 * sa.crate[i] * (dd_prev[i] + vi)
        if var:
            W[W_VISCOUS] += dlt * 0.5 * (spr.cv_prev[i] * dd_prev[i] + sa.cvar[i] * vi)
            spr.cv_prev[i] = sa.cvar[i]
        d_prev[i] = di
        dd_prev[i] = vi
        fs_prev[i] = fs[i]
    a0 = sa.scal[SCAL_A0]
    nd = len(sa.dofs)
    u, un, v, vn = dof.u, dof.un, dof.v, dof.vn
    for j in range(nd):
        W[W_VISCOUS] += (u[j] - un[j]) * a0 * sa.mass[j] * 0.5 * (vn[j] + v[j])
    lam, lt, g = cw.lam, cw.lt, cw.g
    for c in range(len(cw.corners)):
        W[W_CONTACT] -= 0.5 * (work.lam_prev[c] + lam[c]) * (g[c] - work.g_prev[c])
        if lt[c] != 0.0 or work.lt_prev[c] != 0.0:
            ds = 0.0
            for j in range(nd):
                ds += cw.WT[c, j] * (u[j] - un[j])
            W[W_FRICTION] -= 0.5 * (work.lt_prev[c] + lt[c]) * ds
        work.lam_prev[c] = lam[c]
        work.lt_prev[c] = lt[c]
        work.g_prev[c] = g[c]


@kernel(inline="always")
def _attempt(sa, contact, opt, output, work, stats, n, nsub, reuse, lu_held, lu_h):
    """Step n (from t_n = n·dt) in nsub equal sub-steps: predict, form the unbalance, Newton,
    commit, work. Returns (status, a seat margin became negative, lu_held, lu_h); stops
    at the first sub-step that does not converge."""
    dt = opt.dt
    h = dt / nsub
    cnt = stats.count
    unseated = False
    for ksub in range(nsub):
        _predict(len(sa.dofs), work, nsub, ksub, h)
        status, it, anyev, lu_held, lu_h = _newton(
            sa, contact, opt, work, stats, h, nsub, reuse, lu_held, lu_h
        )
        cnt[bd.CNT_NEWTON] += it
        cnt[bd.CNT_MAX_IT] = max(cnt[bd.CNT_MAX_IT], it)
        if status != RUN_OK:
            return status, unseated, lu_held, lu_h
        t_now = (n + 1) * dt if ksub == nsub - 1 else n * dt + (ksub + 1) * h
        if _commit(sa, contact, work, output, stats, anyev, t_now):
            unseated = True
        if opt.want_energy:
            _accumulate_work(sa, work)
    return RUN_OK, unseated, lu_held, lu_h


@kernel(inline="always")
def _step(sa, contact, opt, output, work, stats, n, reuse, lu_held, lu_h):
    """Step n in one attempt; if it fails (not by a non-finite state or the halt flag) it is
    redone from its start in ``opt.substeps`` sub-steps (OpenSees engine ``fallback =
    "substep"``). Returns (status, unseated, lu_held, lu_h) as :func:`_attempt`."""
    nsub = 1
    while True:
        # one copy of the (sub)step code in the compiled loop: the attempts share it
        status, unseated, lu_held, lu_h = _attempt(
            sa, contact, opt, output, work, stats, n, nsub, reuse, lu_held, lu_h
        )
        if status == RUN_OK:
            if nsub > 1:
                stats.count[bd.CNT_RESCUED] += 1
            return status, unseated, lu_held, lu_h
        if nsub > 1 or opt.substeps <= 1 or status in (RUN_NONFINITE, RUN_INTERRUPTED):
            return status, unseated, lu_held, lu_h
        _revert_step(sa, work)
        nsub = opt.substeps


@kernel(inline="always")
def _run_steps(sa, contact, record, opt, output, work, stats):
    """The steps after the start: each begun, stepped, and stored every ``opt.stride``; ends
    the run's statistics (:func:`_set_stats`) at the first failure, unseating or halt."""
    dt = opt.dt
    jrec = _start(sa, contact, record, opt, output, work)
    # tangent-dependent damping: the matrix changes with k_t and k_c, never the elastic one
    reuse = opt.reuse_factors and sa.scal[SCAL_TANGENT_DAMPING] == 0.0
    lu_held = False  # LU holds factors whose key is recorded (_held_factors_fit)
    lu_h = 0.0  # the step of the factors in LU [s]
    row = 1
    for n in range(opt.nsteps):
        if stats.halt[0] != 0:
            _set_stats(stats, RUN_INTERRUPTED, row, n + 1, n, dt)
            return
        jrec = _begin_step(len(sa.dofs), record, work, (n + 1) * dt, jrec)
        status, unseated, lu_held, lu_h = _step(
            sa, contact, opt, output, work, stats, n, reuse, lu_held, lu_h
        )
        if status != RUN_OK:
            _set_stats(stats, status, row, n + 1, n, dt)
            return
        if unseated:
            # a seat margin became negative in this step (.peaks): the answer ends here
            _set_stats(stats, RUN_UNSEATED, row, n + 1, n + 1, dt)
            return
        if (n + 1) % opt.stride == 0:
            _store_output(sa, contact, work, output, row, (n + 1) * dt, opt.want_energy)
            row += 1
    _set_stats(stats, RUN_OK, row, 0, opt.nsteps, dt)


@kernel(nogil=True)
def newmark_run(system, contact, record, opt, output, work, stats):
    """Run the OpenSees-clone Newmark–Newton loop over ``opt.nsteps`` steps of size opt.dt.

    Bundles of :mod:`deckpound.analytic.bundles`: ``system`` (SystemArrays), ``contact``
    (Contact), ``record`` (Record), ``opt`` (:data:`.newmark_work.NewmarkOptions`), ``output`` (Output: the
    selected columns of the full row of :func:`deckpound.analytic.compliance.engine.output_columns`),
    ``work`` (:data:`.newmark_work.NewmarkWork`), ``stats`` (Stats).

    Support motion: the record's own samples, interpolated at t_n = n·dt in the loop exactly as
    ``np.interp`` (memory independent of the number of steps).

    work.u0, work.v0: initial displacement and velocity (n_dof,); the initial acceleration
    solves M ü₀ = F_c − F (zero when starting at rest with the supports at rest, as OpenSees).
    A step that fails is redone from its start in ``opt.substeps`` sub-steps (supports
    linearly interpolated), as the OpenSees engine's ``fallback = "substep"``.

    Fills ``output.table`` (one row per output), ``output.peaks`` (the peaks of every column
    and the gap closures over every converged (sub)step, :mod:`.peaks`) and ``stats.count``:
    status (RUN_OK, RUN_NOT_CONVERGED, RUN_SINGULAR, RUN_NONFINITE, RUN_INTERRUPTED), rows
    written, failed step, steps completed, Newton iterations, contact events, factorisations
    reused (same matrix; those with contact terms also in ``contact_factor_reuses``),
    factorisations formed in the steps, max iterations of a step, steps rescued by
    sub-stepping. A step at
    which a corner's seat margin becomes negative (:func:`deckpound.analytic.kernels.peaks.track_state`)
    is completed (all its sub-steps) and the loop stops there with RUN_UNSEATED (failed step =
    steps = that step, its output row not written). ``stats.halt[0]`` ≠ 0 stops the loop at the
    next Newton iteration (status RUN_INTERRUPTED).
    """
    # subnormal numbers flushed to zero while the loop runs (opt.flush_subnormals,
    # deckpound.analytic.fp_mode); the thread's mode is restored on the way out
    saved = flush_enter(opt.flush_subnormals)
    if _elastic_factors(system, work.mat, opt.dt):
        _run_steps(system, contact, record, opt, output, work, stats)
    else:
        _set_stats(stats, RUN_SINGULAR, 0, 0, 0, opt.dt)
    flush_leave(saved)

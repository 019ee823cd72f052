"""The Newmark–Newton step loop of the compliance engine (``compliance.integrator = newmark``).

Driven by :func:`deckpound.analytic.compliance.run_compliance`; the model and the result
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
takes the named bundles of :mod:`.bundles` (workspace from :func:`newmark_workspace`, scalars
in :data:`NewmarkOptions`); the contact laws are skipped while every corner's
gap is open (g > 0, where every law gives zero force) and the tangent factorisation is reused
while it is bitwise the elastic one (identical matrix → identical factors, so results do not
change). Output every :func:`deckpound.compare.engines.output_stride` steps.
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic import contact_assembly as ca
from deckpound.analytic import contact_laws as cl
from deckpound.analytic._jit import kernel
from deckpound.analytic.bundles import (
    RUN_INTERRUPTED,
    RUN_NONFINITE,
    RUN_NOT_CONVERGED,
    RUN_OK,
    RUN_SINGULAR,
    RUN_UNSEATED,
)
from deckpound.analytic.compliance import ENERGY_COLUMNS
from deckpound.analytic.dense import lu_factor, lu_solve
from deckpound.analytic.fp_mode import flush_enter, flush_leave
from deckpound.analytic.newmark_work import (
    N_ENERGY,
    NewmarkOptions,
    NewmarkWork,
    fill_row,
    newmark_workspace,
    output_energies,
    store_row,
)
from deckpound.analytic.peaks import track_step
from deckpound.analytic.support_motion import record_at
from deckpound.analytic.system import (
    spring_assemble,
    spring_commit,
    spring_damping_tangent,
    spring_deformations,
    spring_revert,
    spring_stored_energy,
    spring_tangent,
    spring_update_materials,
)

__all__ = [
    "BETA",
    "ENERGY_COLUMNS",
    "GAMMA",
    "N_ENERGY",
    "NewmarkOptions",
    "NewmarkWork",
    "newmark_run",
    "newmark_workspace",
]

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
    ncl = ca.eval_contacts(contact, cs, cw, u, v, dof.un)
    evaluated = cw.evaluated
    if not skip_contact and not contact.nonlinear:
        for c in range(4):
            evaluated[c] = True
        ncl = -1
    if ncl < 0:
        ca.eval_closed(contact, cs, cw, u, v, dof.un)
    R, f, a = dof.R, dof.f, dof.a
    for j in range(7):
        R[j] = cw.fc[j] - f[j] - sa.mass[j] * a[j]
    return nonel, evaluated[0] or evaluated[1] or evaluated[2] or evaluated[3]


@kernel
def _set_stats(
    stats, status, rows, failed, steps, total_it, events, reused, maxit_seen, rescued, dt
):
    """Write the loop's statistics (time reached = steps · dt [s])."""
    stats.value[bd.VAL_TIME] = steps * dt
    cnt = stats.count
    cnt[bd.CNT_STATUS] = status
    cnt[bd.CNT_ROWS] = rows
    cnt[bd.CNT_FAILED_STEP] = failed
    cnt[bd.CNT_STEPS] = steps
    cnt[bd.CNT_NEWTON] = total_it
    cnt[bd.CNT_EVENTS] = events
    cnt[bd.CNT_REUSED] = reused
    cnt[bd.CNT_MAX_IT] = maxit_seen
    cnt[bd.CNT_RESCUED] = rescued


@kernel(nogil=True)
def newmark_run(system, contact, record, opt, output, work, stats):
    """Run the OpenSees-clone Newmark–Newton loop over ``opt.nsteps`` steps of size opt.dt.

    Bundles of :mod:`deckpound.analytic.bundles`: ``system`` (SystemArrays), ``contact``
    (Contact), ``record`` (Record), ``opt`` (:data:`NewmarkOptions`), ``output`` (Output: the
    selected columns of the full row of :func:`deckpound.analytic.compliance.output_columns`),
    ``work`` (:data:`NewmarkWork`), ``stats`` (Stats).

    Support motion: the record's own samples, interpolated at t_n = n·dt in the loop exactly as
    ``np.interp`` (memory independent of the number of steps).

    work.u0, work.v0: initial displacement and velocity (7,); the initial acceleration solves
    M ü₀ = F_c − F (zero when starting at rest with the supports at rest, as OpenSees).
    A step that fails is redone from its start in ``opt.substeps`` sub-steps (supports
    linearly interpolated), as the OpenSees engine's ``fallback = "substep"``.

    Fills ``output.table`` (one row per output), ``output.peaks`` (the peaks of every column
    and the gap closures over every converged (sub)step, :mod:`.peaks`) and ``stats.count``: status (RUN_OK,
    RUN_NOT_CONVERGED, RUN_SINGULAR, RUN_NONFINITE, RUN_INTERRUPTED), rows written, failed
    step, steps completed, Newton iterations, contact events, factorisations reused (same
    matrix), max iterations of a step, steps rescued by sub-stepping. A step at which a
    corner's seat margin becomes negative (:func:`deckpound.analytic.peaks.track_step`) is
    completed (all its sub-steps) and the loop stops there with RUN_UNSEATED (failed step =
    steps = that step, its output row not written). ``stats.halt[0]`` ≠ 0
    stops the loop at the next Newton iteration (status RUN_INTERRUPTED).
    """
    # subnormal numbers flushed to zero while the loop runs (opt.flush_subnormals,
    # deckpound.analytic.fp_mode); every return below restores the thread's mode first
    saved = flush_enter(opt.flush_subnormals)
    sa = system
    Cmat = sa.C
    nbs = sa.nbs
    cp = contact.params
    nonlinear = contact.nonlinear
    tb, DG, VGR, SDG, SVG = record.t, record.disp, record.vel, record.dslope, record.vslope
    nsteps, dt, tol, maxit, stride = opt.nsteps, opt.dt, opt.tol, opt.maxit, opt.stride
    substeps = opt.substeps
    ns = sa.k0.shape[0]
    nch = DG.shape[1]
    skip_contact = opt.skip_contact
    skip_unmoved = opt.skip_unmoved
    # tangent-dependent damping: the matrix changes with k_t and k_c, never the elastic one
    reuse_factors = opt.reuse_factors and sa.scal[2] == 0.0
    want_energy = opt.want_energy
    halt = stats.halt
    wk = work
    hstate, cs, cw = wk.hstate, wk.cstate, wk.cw
    dof, mat, spr, sup = wk.dof, wk.mat, wk.spring, wk.support
    mass = sa.mass
    u, v, a, un, vn, an, us, vs, as_, du, R, f = (
        dof.u,
        dof.v,
        dof.a,
        dof.un,
        dof.vn,
        dof.an,
        dof.us,
        dof.vs,
        dof.as_,
        dof.du,
        dof.R,
        dof.f,
    )
    K, Keff, LU, H, Kel, LUel = mat.K, mat.Keff, mat.LU, mat.H, mat.Kel, mat.LUel
    piv, pivel = mat.piv, mat.pivel
    fs, kt, kt_fact, d_prev, dd_prev, fs_prev, d_new, dd_new = (
        spr.fs,
        spr.kt,
        spr.kt_fact,
        spr.d_prev,
        spr.dd_prev,
        spr.fs_prev,
        spr.d_new,
        spr.dd_new,
    )
    g, gd, lam, lt, evaluated = cw.g, cw.gd, cw.lam, cw.lt, cw.evaluated
    lam_prev, lt_prev, g_prev = wk.lam_prev, wk.lt_prev, wk.g_prev
    WT = cw.WT
    # supports: at the trial, at the last (sub)step, at t_n and t_{n+1} (start and end of step)
    ug, vg, ugo, ug0, vg0, ug1, vg1 = (sup.ug, sup.vg, sup.ugo, sup.ug0, sup.vg0, sup.ug1, sup.vg1)
    W, energy = wk.W, wk.energy
    # kt_fact: spring tangents of the factors held in LU; Kel, LUel, pivel: the elastic
    # effective tangent of the main step and its factors
    lu_springs_only = False  # LU holds a factorisation without contact terms
    lu_h = 0.0  # step of the factors held in LU
    c2 = GAMMA / (BETA * dt)
    c3 = 1.0 / (BETA * dt * dt)
    spring_tangent(sa, sa.k0, K)
    for i in range(7):
        for j in range(7):
            Kel[i, j] = K[i, j] + c2 * Cmat[i, j]
        Kel[i, i] += c3 * mass[i]
    for i in range(7):
        for j in range(7):
            LUel[i, j] = Kel[i, j]
    if not lu_factor(LUel, pivel):
        _set_stats(stats, RUN_SINGULAR, 0, 0, 0, 0, 0, 0, 0, 0, dt)
        flush_leave(saved)
        return
    jrec = record_at(tb, DG, VGR, SDG, SVG, 0.0, 0, ug1, vg1)
    for k in range(nch):
        ug[k] = ug1[k]
        vg[k] = vg1[k]
    # initial state (OpenSees: at rest, ü₀ = 0 — the same as equilibrium then)
    for j in range(7):
        u[j] = wk.u0[j]
        v[j] = wk.v0[j]
        un[j] = wk.u0[j]
    _form_unbalance(sa, contact, hstate, cs, cw, dof, spr, sup, skip_contact)
    for j in range(7):
        a[j] = (cw.fc[j] - f[j]) / mass[j]
    spring_commit(sa, hstate)
    cl.contact_commit(cs, g, gd, evaluated)
    for c in range(4):
        lam_prev[c] = lam[c]
        lt_prev[c] = lt[c]
        g_prev[c] = g[c]
    for i in range(ns):
        fs_prev[i] = fs[i]
        d_prev[i] = d_new[i]
        dd_prev[i] = dd_new[i]
        spr.cv_prev[i] = sa.cvar[i]
    # initial mechanical energy counts as input (zero from rest)
    es0 = spring_stored_energy(sa, hstate, u, ug)
    ec0 = cl.contact_stored_energy(cp, cs)
    ke0 = 0.0
    for j in range(7):
        ke0 += 0.5 * mass[j] * v[j] * v[j]
    W[0] = ke0 + es0 + ec0
    W[1] = es0
    W[3] = ec0
    output_energies(sa, hstate, cp, cs, u, v, ug, W, energy)
    store_row(output, 0, 0.0, u, v, cw, cs, fs, nbs, energy)
    pk = output.peaks
    fill_row(pk.row, 0.0, u, v, cw, cs, fs, nbs)
    track_step(pk, 0.0, u, ug, d_new, nbs)
    row = 1
    total_it = 0
    events = 0
    reused = 0
    maxit_seen = 0
    rescued = 0
    status = RUN_OK
    unseated = False
    for n in range(nsteps):
        if halt[0] != 0:
            _set_stats(
                stats,
                RUN_INTERRUPTED,
                row,
                n + 1,
                n,
                total_it,
                events,
                reused,
                maxit_seen,
                rescued,
                dt,
            )
            flush_leave(saved)
            return
        for j in range(7):
            us[j] = u[j]
            vs[j] = v[j]
            as_[j] = a[j]
        for k in range(nch):
            ug0[k] = ug1[k]
            vg0[k] = vg1[k]
        jrec = record_at(tb, DG, VGR, SDG, SVG, (n + 1) * dt, jrec, ug1, vg1)
        nsub = 1
        while True:
            h = dt / nsub
            c2 = GAMMA / (BETA * h)
            c3 = 1.0 / (BETA * h * h)
            a1p = 1.0 - GAMMA / BETA
            a2p = h * (1.0 - 0.5 * GAMMA / BETA)
            a3p = -1.0 / (BETA * h)
            a4p = 1.0 - 0.5 / BETA
            sub_ok = True
            for ksub in range(nsub):
                # --- Newmark::newStep
                for k in range(nch):
                    ugo[k] = ug[k]
                    if nsub == 1:
                        ug[k] = ug1[k]
                        vg[k] = vg1[k]
                    else:
                        w = (ksub + 1.0) / nsub
                        ug[k] = ug0[k] + w * (ug1[k] - ug0[k])
                        vg[k] = vg0[k] + w * (vg1[k] - vg0[k])
                for j in range(7):
                    un[j] = u[j]
                    vn[j] = v[j]
                    an[j] = a[j]
                for j in range(7):
                    v[j] = a1p * vn[j] + a2p * an[j]
                    a[j] = a4p * an[j] + a3p * vn[j]
                nonel, anyev = _form_unbalance(
                    sa, contact, hstate, cs, cw, dof, spr, sup, skip_contact
                )
                it = 0
                converged = False
                while True:
                    # --- formTangent + solve (factors reused when the matrix is the same)
                    same = False
                    if reuse_factors and not anyev:
                        if nonel == 0 and nsub == 1:
                            same = True
                            lu_solve(LUel, pivel, R, du)
                        elif lu_springs_only and lu_h == h:
                            same = True
                            for i in range(ns):
                                if kt[i] != kt_fact[i]:
                                    same = False
                                    break
                            if same:
                                lu_solve(LU, piv, R, du)
                    if same:
                        reused += 1
                    else:
                        spring_tangent(sa, kt, K)
                        for i in range(7):
                            for j in range(7):
                                Keff[i, j] = K[i, j] + c2 * Cmat[i, j]
                            Keff[i, i] += c3 * mass[i]
                        spring_damping_tangent(sa, c2, Keff)
                        if anyev:
                            ca.contact_tangent(contact, cw, u, c2, Keff, H)
                        for i in range(7):
                            for j in range(7):
                                LU[i, j] = Keff[i, j]
                        lu_springs_only = not anyev
                        lu_h = h
                        for i in range(ns):
                            kt_fact[i] = kt[i]
                        if not lu_factor(LU, piv):
                            lu_springs_only = False
                            status = RUN_SINGULAR
                            break
                        lu_solve(LU, piv, R, du)
                    # --- Newmark::update
                    nrm = 0.0
                    moved = False
                    for j in range(7):
                        uj = u[j] + du[j]
                        moved = moved or uj != u[j]
                        u[j] = uj
                        v[j] += c2 * du[j]
                        a[j] += c3 * du[j]
                        nrm += du[j] * du[j]
                    nrm = np.sqrt(nrm)
                    if skip_unmoved and not moved and not anyev and nrm <= tol:
                        # converged, and the increment (round-off of a step that stayed on
                        # its branches) left u bitwise as it was: the materials, spring forces
                        # and gaps are those just evaluated; only the rates follow the new u̇
                        spring_deformations(sa, u, v, sup.ug, sup.vg, d_new, dd_new)
                        ca.gap_rates(contact, v, cw)
                        stats.count[bd.CNT_UNMOVED] += 1
                    else:
                        nonel, anyev = _form_unbalance(
                            sa, contact, hstate, cs, cw, dof, spr, sup, skip_contact
                        )
                    it += 1
                    if not np.isfinite(nrm):
                        status = RUN_NONFINITE
                        break
                    if nrm <= tol:
                        converged = True
                        break
                    if it >= maxit:
                        status = RUN_NOT_CONVERGED
                        break
                    if halt[0] != 0:
                        status = RUN_INTERRUPTED
                        break
                total_it += it
                maxit_seen = max(maxit_seen, it)
                if not converged:
                    sub_ok = False
                    break
                status = RUN_OK
                # --- commit
                spring_commit(sa, hstate)
                for c in range(4):
                    if cs[c, cl.S_CCLOSED] == 0.0 and cs[c, cl.S_TCLOSED] != 0.0 and evaluated[c]:
                        events += 1
                if nonlinear and not anyev:
                    ca.gaps_and_rates(contact, u, v, cw)
                cl.contact_commit(cs, g, gd, evaluated)
                # penetration at every converged (sub)step, not only on output rows
                for c in range(4):
                    if -g[c] > stats.value[bd.VAL_MAX_PEN]:
                        stats.value[bd.VAL_MAX_PEN] = -g[c]
                # peaks of every column and gap closures at every converged (sub)step
                t_now = (n + 1) * dt if ksub == nsub - 1 else n * dt + (ksub + 1) * h
                fill_row(pk.row, t_now, u, v, cw, cs, fs, nbs)
                if track_step(pk, t_now, u, ug, d_new, nbs):
                    unseated = True
                # --- energy (trapezoidal work over the (sub)step)
                if not want_energy:
                    continue
                var = sa.scal[2] != 0.0
                for i in range(ns):
                    di = d_new[i]
                    vi = dd_new[i]
                    ch = sa.schan[i]
                    if ch >= 0:
                        ftot_o = fs_prev[i] + sa.crate[i] * dd_prev[i]
                        ftot_n = fs[i] + sa.crate[i] * vi
                        if var:
                            ftot_o += spr.cv_prev[i] * dd_prev[i]
                            ftot_n += sa.cvar[i] * vi
                        W[0] -= sa.sval[i] * (ug[ch] - ugo[ch]) * 0.5 * (ftot_o + ftot_n)
                    dlt = di - d_prev[i]
                    W[1] += dlt * 0.5 * (fs_prev[i] + fs[i])
                    W[2] += dlt * 0.5 * sa.crate[i] * (dd_prev[i] + vi)
                    if var:
                        W[2] += dlt * 0.5 * (spr.cv_prev[i] * dd_prev[i] + sa.cvar[i] * vi)
                        spr.cv_prev[i] = sa.cvar[i]
                    d_prev[i] = di
                    dd_prev[i] = vi
                    fs_prev[i] = fs[i]
                a0 = sa.scal[0]
                for j in range(7):
                    W[2] += (u[j] - un[j]) * a0 * mass[j] * 0.5 * (vn[j] + v[j])
                for c in range(4):
                    W[3] -= 0.5 * (lam_prev[c] + lam[c]) * (g[c] - g_prev[c])
                    if lt[c] != 0.0 or lt_prev[c] != 0.0:
                        ds = 0.0
                        for j in range(7):
                            ds += WT[c, j] * (u[j] - un[j])
                        W[4] -= 0.5 * (lt_prev[c] + lt[c]) * ds
                    lam_prev[c] = lam[c]
                    lt_prev[c] = lt[c]
                    g_prev[c] = g[c]
            if sub_ok:
                if nsub > 1:
                    rescued += 1
                break
            if nsub > 1 or substeps <= 1 or status in (RUN_NONFINITE, RUN_INTERRUPTED):
                break
            # --- revert to the start of the step and sub-step it
            spring_revert(sa, hstate)
            cl.contact_revert(cs)
            for j in range(7):
                u[j] = us[j]
                v[j] = vs[j]
                a[j] = as_[j]
            for k in range(nch):
                ug[k] = ug0[k]
                vg[k] = vg0[k]
            nsub = substeps
        if status != RUN_OK:
            _set_stats(
                stats, status, row, n + 1, n, total_it, events, reused, maxit_seen, rescued, dt
            )
            flush_leave(saved)
            return
        if unseated:
            # a seat margin became negative in this step (.peaks): the answer ends here
            _set_stats(
                stats,
                RUN_UNSEATED,
                row,
                n + 1,
                n + 1,
                total_it,
                events,
                reused,
                maxit_seen,
                rescued,
                dt,
            )
            flush_leave(saved)
            return
        # --- output
        if (n + 1) % stride == 0:
            if want_energy:
                output_energies(sa, hstate, cp, cs, u, v, ug, W, energy)
            store_row(output, row, (n + 1) * dt, u, v, cw, cs, fs, nbs, energy)
            row += 1
    _set_stats(stats, RUN_OK, row, 0, nsteps, total_it, events, reused, maxit_seen, rescued, dt)
    flush_leave(saved)

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

The whole step loop is one numba kernel compiled without numba's runtime (:mod:`._jit`, in
arrays from :func:`newmark_workspace`); the contact laws are skipped while every corner's
gap is open (g > 0, where every law gives zero force) and the tangent factorisation is reused
while it is bitwise the elastic one (identical matrix → identical factors, so results do not
change). Output every :func:`deckpound.engines.output_stride` steps.
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic import contact_laws as cl
from deckpound.analytic._jit import kernel
from deckpound.analytic.compliance import ENERGY_COLUMNS
from deckpound.analytic.dense import lu_factor, lu_solve
from deckpound.analytic.support_motion import record_at
from deckpound.analytic.system import C_BENT as _C_BENT
from deckpound.analytic.system import spring_assemble, spring_commit, spring_deformations, \
    spring_revert, spring_stored_energy, spring_tangent, spring_update_materials, store_standard

__all__ = ["newmark_run", "newmark_workspace", "ENERGY_COLUMNS", "N_ENERGY", "GAMMA", "BETA",
           "F_CONTACT_SKIP", "F_FACTOR_REUSE", "F_ENERGY", "N_FLAGS"]

N_ENERGY = len(ENERGY_COLUMNS)
GAMMA, BETA = 0.5, 0.25
# work-saving skips of the kernel (flags array; 1 = skip active, the default), see
# deckpound.analytic.compliance.SKIPS
F_CONTACT_SKIP, F_FACTOR_REUSE, F_ENERGY = 0, 1, 2
N_FLAGS = 3


@kernel
def _store(out, row, t, u, v, g, lam, lt, fs, nbs, energy, buf, colsel):
    """Output row ``row``: the full row into ``buf``, then the selected columns into ``out``."""
    store_standard(buf, t, u, v, g, lam, lt, fs, nbs)
    base = _C_BENT + nbs
    for k in range(energy.shape[0]):
        buf[base + k] = energy[k]
    for q in range(colsel.shape[0]):
        out[row, q] = buf[colsel[q]]


@kernel
def _energies(sa, hstate, cp, cs, u, v, ug, W, energy):
    """Output energies from the running work totals W = [input, springs, viscous, contact,
    friction]."""
    ke = 0.0
    for j in range(7):
        ke += 0.5 * sa.mass[j] * v[j] * v[j]
    es = spring_stored_energy(sa, hstate, u, ug)
    ec = cl.contact_stored_energy(cp, cs)
    efs = 0.0                                        # stick-spring part of ec
    for c in range(4):
        if cp[c, cl.P_FMODE] == 2 and cs[c, cl.S_CFT] != 0.0:
            efs += 0.5 * cs[c, cl.S_CFT] ** 2 / cp[c, cl.P_KT]
    energy[0] = W[0]
    energy[1] = ke
    energy[2] = es
    energy[3] = W[2]
    energy[4] = W[1] - es
    energy[5] = ec
    energy[6] = W[3] - (ec - efs)
    energy[7] = W[4] - efs
    energy[8] = W[0] - (ke + W[1] + W[2] + W[3] + W[4])


def newmark_workspace(ns: int, nch: int, nbs: int) -> tuple:
    """The arrays :func:`newmark_run` works in (zeroed): ns springs, nch support channels, nbs
    bent springs. Allocated here because the kernel runs without numba's runtime."""
    return (np.zeros(_C_BENT + nbs + N_ENERGY), np.zeros((13, 7)), np.zeros((6, 7, 7)),
            np.zeros((2, 7), dtype=np.int64), np.zeros((8, ns)), np.zeros((7, 4)),
            np.zeros((3, 4, 7)), np.zeros(4, dtype=np.bool_), np.zeros((7, nch)), np.zeros(5),
            np.zeros(N_ENERGY))


@kernel(inline="always")
def _form_unbalance(sa, hstate, cp, cs, geom, nonlinear, skip_contact, u, v, a, un, ug, vg,
                    d, dd, f, fs, kt, g, gd, WN, WT, fc, lam, lt, der, evaluated, R):
    """OpenSees ``formUnbalance`` at the trial (u, u̇, ü) and supports (u_g, u̇_g).

    Springs: trial material state, F (into f), restoring forces fs and tangents kt. Contacts:
    the gap check, then the laws of the closed corners (every corner when ``skip_contact`` is
    off, linear kinematics). Residual R = F_c − F − M ü. un: displacement at the step start.
    Returns (number of springs off their elastic tangent, any corner evaluated).
    """
    spring_deformations(sa, u, v, ug, vg, d, dd)
    spring_update_materials(sa.hparams, hstate, sa.kind, d)
    nonel = spring_assemble(sa, hstate, d, dd, v, f, fs, kt)
    ncl = cl.eval_contacts(cp, cs, u, v, un, geom, nonlinear, g, gd, WN, WT, fc, lam, lt, der,
                           evaluated)
    if not skip_contact and not nonlinear:
        for c in range(4):
            evaluated[c] = True
        ncl = -1
    if ncl < 0:
        cl.eval_closed(cp, cs, u, v, un, geom, nonlinear, g, gd, WN, WT, fc, lam, lt, der,
                       evaluated)
    for j in range(7):
        R[j] = fc[j] - f[j] - sa.mass[j] * a[j]
    return nonel, evaluated[0] or evaluated[1] or evaluated[2] or evaluated[3]


@kernel
def newmark_run(sa, Cmat, hstate, cp, cs, geom, nonlinear, tb, DG, VGR, nsteps, dt, tol, maxit,
                stride, nbs, out, info, u0, v0, substeps, flags, colsel, work):
    """Run the OpenSees-clone Newmark–Newton loop over ``nsteps`` steps of size dt.

    Support motion: the record's own samples (tb, DG, VGR from
    :func:`deckpound.analytic.support_motion.support_record`), interpolated at t_n = n·dt in
    the loop exactly as ``np.interp`` (memory independent of the number of steps).

    ``flags`` (int64, :data:`N_FLAGS`): the work-saving skips, 1 = on (default), 0 = off for
    measurement (results identical either way): [F_CONTACT_SKIP] contact laws and contact
    tangent skipped while every gap is open; [F_FACTOR_REUSE] the tangent factorisation
    reused while the matrix is bitwise the last one (elastic Takeda springs, no contact);
    [F_ENERGY] energy work terms accumulated (0: energies not requested, not computed).
    ``colsel`` (int64): indices of the stored columns in the full column order of
    :func:`output_columns`; ``out`` has one column per entry.

    u0, v0: initial displacement and velocity (7,); the initial acceleration solves
    M ü₀ = F_c − F (zero when starting at rest with the supports at rest, as OpenSees).
    A step that fails is redone from its start in ``substeps`` sub-steps (supports linearly
    interpolated), as the OpenSees engine's ``fallback = "substep"``; ``substeps`` ≤ 1 disables
    that.

    Fills ``out`` (one row per output) and ``info`` = [status (0 ok, 1 no convergence,
    2 singular tangent, 3 non-finite), rows written, failed step, iterations, contact events,
    factorisations reused (same matrix), max iterations of a step, steps rescued by
    sub-stepping].
    """
    ns = sa.k0.shape[0]
    nch = DG.shape[1]
    skip_contact = flags[F_CONTACT_SKIP] != 0
    reuse_factors = flags[F_FACTOR_REUSE] != 0
    want_energy = flags[F_ENERGY] != 0
    # workspace (allocated by newmark_workspace: this kernel runs without numba's runtime)
    buf, w7, w77, wpiv, wns, w4, w47, evaluated, wch, W, energy = work
    mass = sa.mass
    u, v, a, un, vn, an, us, vs, as_, du, R, f, fc = (w7[0], w7[1], w7[2], w7[3], w7[4], w7[5],
                                                      w7[6], w7[7], w7[8], w7[9], w7[10],
                                                      w7[11], w7[12])
    K, Keff, LU, H, Kel, LUel = w77[0], w77[1], w77[2], w77[3], w77[4], w77[5]
    piv, pivel = wpiv[0], wpiv[1]
    fs, kt, kt_fact, d_prev, dd_prev, fs_prev, d_new, dd_new = (wns[0], wns[1], wns[2], wns[3],
                                                                wns[4], wns[5], wns[6], wns[7])
    g, gd, lam, lt, lam_prev, lt_prev, g_prev = w4[0], w4[1], w4[2], w4[3], w4[4], w4[5], w4[6]
    WN, WT, der = w47[0], w47[1], w47[2]
    # supports: at the trial, at the last (sub)step, at t_n and t_{n+1} (start and end of step)
    ug, vg, ugo, ug0, vg0, ug1, vg1 = wch[0], wch[1], wch[2], wch[3], wch[4], wch[5], wch[6]
    # kt_fact: spring tangents of the factors held in LU; Kel, LUel, pivel: the elastic
    # effective tangent of the main step and its factors
    lu_springs_only = False         # LU holds a factorisation without contact terms
    lu_h = 0.0                      # step of the factors held in LU
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
        info[0] = 2
        return
    jrec = record_at(tb, DG, VGR, 0.0, 0, ug1, vg1)
    for k in range(nch):
        ug[k] = ug1[k]
        vg[k] = vg1[k]
    # initial state (OpenSees: at rest, ü₀ = 0 — the same as equilibrium then)
    for j in range(7):
        u[j] = u0[j]
        v[j] = v0[j]
        un[j] = u0[j]
    _form_unbalance(sa, hstate, cp, cs, geom, nonlinear, skip_contact, u, v, a, un, ug, vg,
                    d_new, dd_new, f, fs, kt, g, gd, WN, WT, fc, lam, lt, der, evaluated, R)
    for j in range(7):
        a[j] = (fc[j] - f[j]) / mass[j]
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
    # initial mechanical energy counts as input (zero from rest)
    es0 = spring_stored_energy(sa, hstate, u, ug)
    ec0 = cl.contact_stored_energy(cp, cs)
    ke0 = 0.0
    for j in range(7):
        ke0 += 0.5 * mass[j] * v[j] * v[j]
    W[0] = ke0 + es0 + ec0
    W[1] = es0
    W[3] = ec0
    _energies(sa, hstate, cp, cs, u, v, ug, W, energy)
    _store(out, 0, 0.0, u, v, g, lam, lt, fs, nbs, energy, buf, colsel)
    row = 1
    total_it = 0
    events = 0
    reused = 0
    maxit_seen = 0
    rescued = 0
    status = 0
    for n in range(nsteps):
        for j in range(7):
            us[j] = u[j]
            vs[j] = v[j]
            as_[j] = a[j]
        for k in range(nch):
            ug0[k] = ug1[k]
            vg0[k] = vg1[k]
        jrec = record_at(tb, DG, VGR, (n + 1) * dt, jrec, ug1, vg1)
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
                nonel, anyev = _form_unbalance(sa, hstate, cp, cs, geom, nonlinear, skip_contact,
                                               u, v, a, un, ug, vg, d_new, dd_new, f, fs, kt, g,
                                               gd, WN, WT, fc, lam, lt, der, evaluated, R)
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
                        if anyev:
                            cl.contact_tangent(cp, u, geom, nonlinear, lam, der, evaluated, WN,
                                               WT, c2, Keff, H)
                        for i in range(7):
                            for j in range(7):
                                LU[i, j] = Keff[i, j]
                        lu_springs_only = not anyev
                        lu_h = h
                        for i in range(ns):
                            kt_fact[i] = kt[i]
                        if not lu_factor(LU, piv):
                            lu_springs_only = False
                            status = 2
                            break
                        lu_solve(LU, piv, R, du)
                    # --- Newmark::update
                    nrm = 0.0
                    for j in range(7):
                        u[j] += du[j]
                        v[j] += c2 * du[j]
                        a[j] += c3 * du[j]
                        nrm += du[j] * du[j]
                    nrm = np.sqrt(nrm)
                    nonel, anyev = _form_unbalance(sa, hstate, cp, cs, geom, nonlinear,
                                                   skip_contact, u, v, a, un, ug, vg, d_new,
                                                   dd_new, f, fs, kt, g, gd, WN, WT, fc, lam, lt,
                                                   der, evaluated, R)
                    it += 1
                    if not np.isfinite(nrm):
                        status = 3
                        break
                    if nrm <= tol:
                        converged = True
                        break
                    if it >= maxit:
                        status = 1
                        break
                total_it += it
                if it > maxit_seen:
                    maxit_seen = it
                if not converged:
                    sub_ok = False
                    break
                status = 0
                # --- commit
                spring_commit(sa, hstate)
                for c in range(4):
                    if cs[c, cl.S_CCLOSED] == 0.0 and cs[c, cl.S_TCLOSED] != 0.0 and evaluated[c]:
                        events += 1
                if nonlinear and not anyev:
                    cl.gaps_and_rates(u, v, geom, nonlinear, g, gd, WN, WT)
                cl.contact_commit(cs, g, gd, evaluated)
                # --- energy (trapezoidal work over the (sub)step)
                if not want_energy:
                    continue
                for i in range(ns):
                    di = d_new[i]
                    vi = dd_new[i]
                    ch = sa.schan[i]
                    if ch >= 0:
                        ftot_o = fs_prev[i] + sa.crate[i] * dd_prev[i]
                        ftot_n = fs[i] + sa.crate[i] * vi
                        W[0] -= sa.sval[i] * (ug[ch] - ugo[ch]) * 0.5 * (ftot_o + ftot_n)
                    dlt = di - d_prev[i]
                    W[1] += dlt * 0.5 * (fs_prev[i] + fs[i])
                    W[2] += dlt * 0.5 * sa.crate[i] * (dd_prev[i] + vi)
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
            if nsub > 1 or substeps <= 1 or status == 3:
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
        if status != 0:
            info[0] = status
            info[1] = row
            info[2] = n + 1
            info[3] = total_it
            info[4] = events
            info[6] = maxit_seen
            info[7] = rescued
            return
        # --- output
        if (n + 1) % stride == 0:
            if want_energy:
                _energies(sa, hstate, cp, cs, u, v, ug, W, energy)
            _store(out, row, (n + 1) * dt, u, v, g, lam, lt, fs, nbs, energy, buf,
                       colsel)
            row += 1
    info[0] = 0
    info[1] = row
    info[3] = total_it
    info[4] = events
    info[5] = reused
    info[6] = maxit_seen
    info[7] = rescued

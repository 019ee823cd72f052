"""The Dormand–Prince 5(4) step loop with event location of the adaptive compliance integrator.

Driven by :func:`deckpound.analytic.adaptive.run_adaptive`, where the scheme, the breakpoints,
the events and the commit rule are described. One numba function (:func:`adaptive_run`) runs
the whole record; the right-hand side, the event functions, the Hermite interpolant and one
Runge–Kutta step are kernels (:mod:`deckpound.analytic._jit`, no numba runtime: every array is
in the workspace of
:func:`deckpound.analytic.dormand_prince_work.adaptive_workspace`). It takes the named bundles of
:mod:`deckpound.analytic.bundles`; its scalars are
:data:`deckpound.analytic.dormand_prince_work.AdaptiveOptions`. The tableau is a
module constant (numba freezes global arrays into the compiled code).
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic import contact_assembly as ca
from deckpound.analytic import contact_laws as cl
from deckpound.analytic._hysteretic_kernel import C_ROTMAX, C_ROTMIN, T_STRESS
from deckpound.analytic._jit import kernel
from deckpound.analytic.bundles import (
    RUN_INTERRUPTED,
    RUN_NONFINITE,
    RUN_OK,
    RUN_STEP_BUDGET,
    RUN_STEP_UNDERFLOW,
    RUN_UNSEATED,
)
from deckpound.analytic.dormand_prince_work import H_BINS_PER_DECADE, H_LOG_MIN, H_NBINS, NT, NY
from deckpound.analytic.fp_mode import flush_enter, flush_leave
from deckpound.analytic.peaks import track_step
from deckpound.analytic.system import (
    C_BENT,
    spring_assemble,
    spring_commit,
    spring_deformations,
    spring_stored_energy,
    spring_update_materials,
    store_standard,
)

__all__ = ["TABLEAU", "adaptive_run"]

# Dormand–Prince 5(4) tableau
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = np.zeros((7, 7))
_A[1, 0] = 1 / 5
_A[2, :2] = [3 / 40, 9 / 40]
_A[3, :3] = [44 / 45, -56 / 15, 32 / 9]
_A[4, :4] = [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729]
_A[5, :5] = [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656]
_A[6, :6] = [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]
_B5 = _A[6].copy()
_E = _B5 - np.array(
    [5179 / 57600, 0.0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40]
)


@kernel
def _support(t, tb, D, V, ug, vg):
    """Support disp/vel at t (linear interpolation on the record time base tb)."""
    n = tb.shape[0]
    if t <= tb[0]:
        k = 0
        w = 0.0
    elif t >= tb[n - 1]:
        k = n - 2
        w = 1.0
    else:
        lo = 0
        hi = n - 1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if tb[mid] <= t:
                lo = mid
            else:
                hi = mid
        k = lo
        w = (t - tb[k]) / (tb[k + 1] - tb[k])
    for j in range(D.shape[1]):
        ug[j] = D[k, j] + w * (D[k + 1, j] - D[k, j])
        vg[j] = V[k, j] + w * (V[k + 1, j] - V[k, j])


@kernel
def _rhs(t, y, sa, contact, record, ws, dy):
    """dy = [u̇, ü, powers] at (t, y); trial material/contact states relative to committed."""
    ns = sa.k0.shape[0]
    cw = ws.cw
    u = y[0:7]
    v = y[7:14]
    ug = ws.ug
    vg = ws.vg
    _support(t, record.t, record.disp, record.vel, ug, vg)
    spring_deformations(sa, u, v, ug, vg, ws.d, ws.dd)
    spring_update_materials(sa.hparams, ws.hstate, sa.kind, ws.d)
    spring_assemble(sa, ws.hstate, ws.d, ws.dd, v, ws.f, ws.fs, ws.kt)
    n = ca.eval_contacts(contact, ws.cstate, cw, u, v, ws.uc)
    if n < 0:
        ca.eval_closed(contact, ws.cstate, cw, u, v, ws.uc)
    for j in range(7):
        dy[j] = v[j]
        dy[7 + j] = (cw.fc[j] - ws.f[j]) / sa.mass[j]
    # powers: input (supports), springs (f_s ḋ), viscous, contact (λ_N δ̇), friction (−λ_T U_T)
    pin = 0.0
    psp = 0.0
    pvi = 0.0
    for i in range(ns):
        ftot = ws.fs[i] + sa.crate[i] * ws.dd[i]
        ch = sa.schan[i]
        if ch >= 0:
            pin -= sa.sval[i] * vg[ch] * ftot
        psp += ws.fs[i] * ws.dd[i]
        pvi += sa.crate[i] * ws.dd[i] * ws.dd[i]
    a0 = sa.scal[0]
    for j in range(7):
        pvi += a0 * sa.mass[j] * v[j] * v[j]
    pco = 0.0
    pfr = 0.0
    for c in range(4):
        pco -= cw.lam[c] * cw.gd[c]
        if cw.lt[c] != 0.0:
            ut = 0.0
            for j in range(7):
                ut += cw.WT[c, j] * v[j]
            pfr -= cw.lt[c] * ut
    dy[14] = pin
    dy[15] = psp
    dy[16] = pvi
    dy[17] = pco
    dy[18] = pfr


@kernel
def _events(y, sa, contact, ws, ev):
    """Event function values at a state: gaps (4), Takeda ḋ (nbs), ġ (4, bilinear), U_T (4,
    stick friction); unused entries 0. ws.dd: the spring rates of the last :func:`_rhs` call."""
    cp = contact.params
    cw = ws.cw
    nbs = sa.nbs
    u = y[0:7]
    v = y[7:14]
    ca.gaps_and_rates(contact, u, v, cw)
    for c in range(4):
        ev[c] = cw.g[c]
    for i in range(nbs):
        ev[4 + i] = ws.dd[i]
    k = 4 + nbs
    for c in range(4):
        ev[k + c] = cw.gd[c] if (cp[c, cl.P_EVENT] != 0.0 and cw.g[c] < 0.0) else 0.0
        ut = 0.0
        if cp[c, cl.P_FMODE] == cl.FRICTION_STICK and cw.g[c] < 0.0:
            for j in range(7):
                ut += cw.WT[c, j] * v[j]
        ev[k + 4 + c] = ut


@kernel
def _hermite(y0, f0, y1, f1, h, th):
    h00 = 2 * th**3 - 3 * th**2 + 1
    h10 = th**3 - 2 * th**2 + th
    h01 = -2 * th**3 + 3 * th**2
    h11 = th**3 - th**2
    return h00 * y0 + h10 * h * f0 + h01 * y1 + h11 * h * f1


@kernel
def _event_value(kind_idx, y, sa, contact, record, t, ws):
    """Value of event kind_idx at an interpolated state y (t for the supports)."""
    cw = ws.cw
    u = y[0:7]
    v = y[7:14]
    ca.gaps_and_rates(contact, u, v, cw)
    nbs2 = kind_idx - 4
    if kind_idx < 4:
        return cw.g[kind_idx]
    ns_ev = sa.nbs
    if nbs2 < ns_ev:
        _support(t, record.t, record.disp, record.vel, ws.ug, ws.vg)
        spring_deformations(sa, u, v, ws.ug, ws.vg, ws.d, ws.dd)
        return ws.dd[nbs2]
    c = nbs2 - ns_ev
    if c < 4:
        return cw.gd[c]
    c -= 4
    ut = 0.0
    for j in range(7):
        ut += cw.WT[c, j] * v[j]
    return ut


@kernel
def _rk_step(t, y, h, sa, contact, record, ws, atol, rtol):
    """One DP5(4) step from (t, y) with slope ws.k1; returns the scaled error norm (ws.ynew
    filled, ws.K[6] = f(t+h, ynew))."""
    K, k1, ytmp, ynew = ws.K, ws.k1, ws.ytmp, ws.ynew
    for j in range(NT):
        K[0, j] = k1[j]
    for s in range(1, 7):
        for j in range(NT):
            acc = y[j]
            for r in range(s):
                acc += h * _A[s, r] * K[r, j]
            ytmp[j] = acc
        if s == 6:
            for j in range(NT):
                ynew[j] = ytmp[j]
        _rhs(t + _C[s] * h, ytmp, sa, contact, record, ws, K[s])
    err = 0.0
    for j in range(NY):
        e = 0.0
        for s in range(7):
            e += h * _E[s] * K[s, j]
        sc = atol + rtol * max(abs(y[j]), abs(ynew[j]))
        err += (e / sc) ** 2
    return np.sqrt(err / NY)


@kernel
def _any_yielded(sa, hstate):
    """True once any Takeda (Hysteretic) spring has been deformed past its first backbone point.

    From then on the material's state depends on where it is committed, even along monotonic
    paths (OpenSees Hysteretic arithmetic), so the loop caps its steps at ``commit_step``.
    """
    for i in range(hstate.shape[0]):
        if sa.kind[i] == 1 and (
            hstate[i, C_ROTMAX] > sa.hparams[i, 1] or hstate[i, C_ROTMIN] < sa.hparams[i, 7]
        ):
            return True
    return False


@kernel(nogil=True)
def adaptive_run(system, contact, record, opt, output, work, stats):
    """The adaptive loop over [0, opt.t_end] (bundles of :mod:`deckpound.analytic.bundles`,
    scalars :data:`.dormand_prince_work.AdaptiveOptions`, workspace
    :data:`.dormand_prince_work.AdaptiveWork`).

    Fills ``output.table`` (rows at k·out_dt), ``output.peaks`` (peaks and gap closures over
    every accepted step, :mod:`.peaks`) and ``stats``: count = status (RUN_OK,
    RUN_STEP_UNDERFLOW, RUN_NONFINITE, RUN_STEP_BUDGET, RUN_INTERRUPTED), rows, steps
    (accepted), rejected, events, rhs calls; value[VAL_TIME] = the time reached [s],
    value[VAL_MAX_PEN] the largest penetration over the accepted steps [m]; work.hist,
    work.hstat: accepted step sizes. ``stats.halt[0]`` ≠ 0 stops the loop before the next step
    attempt (RUN_INTERRUPTED); so does ``opt.max_steps`` attempts (RUN_STEP_BUDGET), and an
    accepted step at which a seat margin becomes negative (RUN_UNSEATED, after that step).
    """
    # subnormal numbers flushed to zero while the loop runs (opt.flush_subnormals,
    # deckpound.analytic.fp_mode); every return below restores the thread's mode first
    saved = flush_enter(opt.flush_subnormals)
    sa = system
    ws = work
    hstate, cs, cw = ws.hstate, ws.cstate, ws.cw
    y, k1, ytmp, ynew, yev, uc = ws.y, ws.k1, ws.ytmp, ws.ynew, ws.yev, ws.uc
    ev0, ev1, hist, hstat = ws.ev0, ws.ev1, ws.hist, ws.hstat
    t_end, out_dt, rtol, atol = opt.t_end, opt.out_dt, opt.rtol, opt.atol
    max_step, commit_step = opt.max_step, opt.commit_step
    tb = record.t
    halt = stats.halt
    for j in range(7):
        y[j] = ws.u0[j]
        y[7 + j] = ws.v0[j]
    for j in range(7):
        uc[j] = y[j]
    nev = ev0.shape[0]
    tiny = 1e-13
    t = 0.0
    _rhs(t, y, sa, contact, record, ws, k1)
    spring_commit(sa, hstate)
    cl.contact_commit(cs, cw.g, cw.gd, cw.evaluated)
    # initial energy
    ke = 0.0
    for j in range(7):
        ke += 0.5 * sa.mass[j] * y[7 + j] ** 2
    es0 = spring_stored_energy(sa, hstate, y[0:7], ws.ug)
    ec0 = cl.contact_stored_energy(contact.params, cs)
    y[14] = ke + es0 + ec0
    y[15] = es0
    y[17] = ec0
    _adaptive_store(sa, contact, ws, output, 0, 0.0)
    _adaptive_track(sa, ws, output.peaks, 0.0)
    row = 1
    nout = output.table.shape[0]
    h = min(max_step, out_dt, 1e-4)
    yielded = _any_yielded(sa, hstate)
    status = RUN_OK
    steps = 0
    rejected = 0
    events = 0
    calls = 1
    kseg = 0
    ntb = tb.shape[0]
    _events(y, sa, contact, ws, ev0)
    while t < t_end - tiny * max(1.0, t_end):
        if halt[0] != 0:
            status = RUN_INTERRUPTED
            break
        if steps + rejected >= opt.max_steps:
            status = RUN_STEP_BUDGET
            break
        # next breakpoint: record sample or output time
        while kseg < ntb and tb[kseg] <= t + tiny * max(1.0, t):
            kseg += 1
        tbreak = t_end
        if kseg < ntb and tb[kseg] < tbreak:
            tbreak = tb[kseg]
        tout = row * out_dt
        tbreak = min(tbreak, tout)
        hmax = min(max_step, tbreak - t)
        if yielded and hmax > commit_step:
            hmax = commit_step
        h = min(h, hmax)
        hit_break = abs((t + h) - tbreak) <= tiny * max(1.0, tbreak)
        if h <= 1e-14:
            status = RUN_STEP_UNDERFLOW
            break
        err = _rk_step(t, y, h, sa, contact, record, ws, atol, rtol)
        calls += 6
        if not np.isfinite(err):
            err = 1e10
        if err > 1.0:
            rejected += 1
            h *= max(0.2, 0.9 * err**-0.2)
            continue
        # events inside (t, t+h]
        _rhs(t + h, ynew, sa, contact, record, ws, ytmp)
        calls += 1
        _events(ynew, sa, contact, ws, ev1)
        th_ev = 2.0
        for q in range(nev):
            a_, b_ = ev0[q], ev1[q]
            if (a_ == 0.0 or (a_ < 0.0) == (b_ < 0.0)) and not (b_ == 0.0 and a_ != 0.0):
                continue  # no sign change in (t, t+h] (a zero at t+h counts)
            # bisection on the Hermite interpolant
            lo = 0.0
            hi = 1.0
            flo = a_
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                for j in range(NY):
                    yev[j] = _hermite(y[j], k1[j], ynew[j], ytmp[j], h, mid)
                fm = _event_value(q, yev, sa, contact, record, t + mid * h, ws)
                if (fm < 0.0) == (flo < 0.0) and fm != 0.0:
                    lo = mid
                    flo = fm
                else:
                    hi = mid
                if (hi - lo) * h < 1e-13:
                    break
            th_ev = min(th_ev, hi)
        if th_ev < 1.0 and th_ev * h > 1e-12:
            he = th_ev * h
            _rk_step(t, y, he, sa, contact, record, ws, atol, rtol)
            calls += 6
            events += 1
            h_acc = he
            hit_break = False
        else:
            h_acc = h
        # accept: state at t + h_acc, commit materials and contacts there
        t_start = t
        in_contact = ev0[0] <= 0.0 or ev0[1] <= 0.0 or ev0[2] <= 0.0 or ev0[3] <= 0.0
        t = t + h_acc
        if hit_break:
            t = tbreak
        for j in range(NT):
            y[j] = ynew[j]
        _rhs(t, y, sa, contact, record, ws, k1)
        calls += 1
        spring_commit(sa, hstate)
        cl.contact_commit(cs, cw.g, cw.gd, cw.evaluated)
        for c in range(4):  # penetration at every accepted step
            if -cw.g[c] > stats.value[bd.VAL_MAX_PEN]:
                stats.value[bd.VAL_MAX_PEN] = -cw.g[c]
        if not yielded:
            yielded = _any_yielded(sa, hstate)
        for j in range(7):
            uc[j] = y[j]
        _rhs(t, y, sa, contact, record, ws, k1)
        calls += 1
        _events(y, sa, contact, ws, ev0)
        steps += 1
        unseated = _adaptive_track(sa, ws, output.peaks, t)
        if ev0[0] <= 0.0 or ev0[1] <= 0.0 or ev0[2] <= 0.0 or ev0[3] <= 0.0:
            in_contact = True
        hs = t - t_start
        ic = 1 if in_contact else 0
        if hs > 0.0:
            b = int((np.log10(hs) - H_LOG_MIN) * H_BINS_PER_DECADE)
            b = max(b, 0)
            if b >= H_NBINS:
                b = H_NBINS - 1
            hist[ic, b] += 1
            if hstat[ic, 0] == 0.0 or hs < hstat[ic, 0]:
                hstat[ic, 0] = hs
            hstat[ic, 1] = max(hstat[ic, 1], hs)
            hstat[ic, 2] += hs
        finite = True
        for j in range(NT):
            if not np.isfinite(y[j]):
                finite = False
        if not finite:
            status = RUN_NONFINITE
            break
        if unseated:  # a seat margin became negative at this step (.peaks): the answer ends
            status = RUN_UNSEATED
            break
        if row < nout and abs(t - row * out_dt) <= 1e-9 * out_dt:
            _adaptive_store(sa, contact, ws, output, row, row * out_dt)
            row += 1
        if err > 0.0:
            fac = 0.9 * err**-0.2
            fac = min(fac, 5.0)
            fac = max(fac, 0.2)
            hn = h * fac
        else:
            hn = h * 5.0
        if h_acc < h and hn > h:
            hn = h
        h = hn
    cnt = stats.count
    cnt[bd.CNT_STATUS] = status
    cnt[bd.CNT_ROWS] = row
    cnt[bd.CNT_STEPS] = steps
    cnt[bd.CNT_FAILED_STEP] = (
        0 if status == RUN_OK else (steps if status == RUN_UNSEATED else steps + 1)
    )
    cnt[bd.CNT_REJECTED] = rejected
    cnt[bd.CNT_EVENTS] = events
    cnt[bd.CNT_RHS_CALLS] = calls
    stats.value[bd.VAL_TIME] = t
    flush_leave(saved)


@kernel
def _adaptive_track(sa, ws, pk, t):
    """Peaks and gap closures of the accepted step ending at t (:mod:`.peaks`): the engine
    columns as :func:`_adaptive_store` writes them, from the state of the last :func:`_rhs`
    call at (t, y); True when a seat margin became negative (:func:`.peaks.track_step`)."""
    y = ws.y
    cw = ws.cw
    store_standard(pk.row, t, y[0:7], y[7:14], cw.g, cw.lam, cw.lt, ws.hstate[:, T_STRESS], sa.nbs)
    return track_step(pk, t, y[0:7], ws.ug, ws.d, sa.nbs)


@kernel
def _adaptive_store(sa, contact, ws, output, row, t):
    """Output row ``row`` at time t: the full row into ``output.row`` (standard columns, then
    the energies from the integrals y[14:19]), the selected columns into ``output.table``."""
    cp = contact.params
    cs = ws.cstate
    cw = ws.cw
    hstate = ws.hstate
    y = ws.y
    buf = output.row
    nbs = sa.nbs
    store_standard(buf, t, y[0:7], y[7:14], cw.g, cw.lam, cw.lt, hstate[:, T_STRESS], nbs)
    base = C_BENT + nbs
    ke = 0.0
    for j in range(7):
        ke += 0.5 * sa.mass[j] * y[7 + j] ** 2
    es = spring_stored_energy(sa, hstate, y[0:7], ws.ug)
    ec = cl.contact_stored_energy(cp, cs)
    efs = 0.0
    for c in range(4):
        if cl.has_stick_spring(cp[c, cl.P_FMODE]) and cs[c, cl.S_CFT] != 0.0:
            efs += 0.5 * cs[c, cl.S_CFT] ** 2 / cp[c, cl.P_KT]
    W0, W1, W2, W3, W4 = y[14], y[15], y[16], y[17], y[18]
    buf[base + 0] = W0
    buf[base + 1] = ke
    buf[base + 2] = es
    buf[base + 3] = W2
    buf[base + 4] = W1 - es
    buf[base + 5] = ec
    buf[base + 6] = W3 - (ec - efs)
    buf[base + 7] = W4 - efs
    buf[base + 8] = W0 - (ke + W1 + W2 + W3 + W4)
    sel = output.select
    table = output.table
    for q in range(sel.shape[0]):
        table[row, q] = buf[sel[q]]


#: (A, C, B5, E) of the tableau (module constants of the kernels)
TABLEAU = (_A, _C, _B5, _E)

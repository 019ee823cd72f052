"""The Dormand–Prince 5(4) step loop with event location of the adaptive compliance integrator.

Driven by :func:`deckpound.analytic.compliance.adaptive.run_adaptive`, where the scheme, the breakpoints,
the events and the commit rule are described. One numba function (:func:`adaptive_run`) runs
the whole record; the right-hand side, the event functions, the Hermite interpolant and one
Runge–Kutta step are kernels (:mod:`deckpound.analytic._jit`, no numba runtime: every array is
in the workspace of
:func:`deckpound.analytic.compliance.dormand_prince_work.adaptive_workspace`). It takes the named bundles of
:mod:`deckpound.analytic.bundles`; its scalars are
:data:`deckpound.analytic.compliance.dormand_prince_work.AdaptiveOptions`. The tableau is a
module constant (numba freezes global arrays into the compiled code).

:func:`adaptive_run` is a short driver over stages inlined into it (``inline="always"``):
:func:`_start`, then per step attempt :func:`_next_break` (the step limit), :func:`_rk_step`,
:func:`_locate_event` (the first event in the step, the step redone to it), :func:`_accept`
(commit at the step's end), :func:`_count_step_size`, :func:`_adaptive_store` on output times
and :func:`_next_step_size`.

State vector y = [u (n_dof), u̇ (n_dof), work totals (N_WORK)]: n_dof from the system bundle
(``len(dofs)``, a compile-time constant), the work totals at ``y[2 n_dof + W_*]`` (offsets of
:mod:`deckpound.analytic.compliance.work_energy`).
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic._jit import kernel
from deckpound.analytic.bundles import (
    RUN_INTERRUPTED,
    RUN_NONFINITE,
    RUN_OK,
    RUN_STEP_BUDGET,
    RUN_STEP_UNDERFLOW,
    RUN_UNSEATED,
)
from deckpound.analytic.compliance.dormand_prince_work import (
    H_BINS_PER_DECADE,
    H_LOG_MIN,
    H_NBINS,
    HSTAT_MAX,
    HSTAT_MIN,
    HSTAT_SUM,
    ROW_CONTACT,
    ROW_FREE,
)
from deckpound.analytic.compliance.work_energy import (
    N_WORK,
    W_CONTACT,
    W_FRICTION,
    W_INPUT,
    W_SPRINGS,
    W_VISCOUS,
    energy_columns,
    stick_spring_energy,
)
from deckpound.analytic.fp_mode import flush_enter, flush_leave
from deckpound.analytic.kernels import contact_assembly as ca
from deckpound.analytic.kernels import contact_laws as cl
from deckpound.analytic.kernels.hysteretic_layout import C_ROTMAX, C_ROTMIN, P_E1N, P_E1P, T_STRESS
from deckpound.analytic.kernels.peaks import track_state
from deckpound.analytic.kernels.system import (
    KIND_HYSTERETIC,
    SCAL_A0,
    end_column,
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
#: relative tolerance of time comparisons (breakpoints, the end time) [-]
_TINY = 1e-13


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
    nd = len(sa.dofs)
    ny = 2 * nd
    cw = ws.cw
    u = y[0:nd]
    v = y[nd:ny]
    ug = ws.ug
    vg = ws.vg
    _support(t, record.t, record.disp, record.vel, ug, vg)
    spring_deformations(sa, u, v, ug, vg, ws.d, ws.dd)
    spring_update_materials(sa.hparams, ws.hstate, sa.kind, ws.d)
    spring_assemble(sa, ws.hstate, ws.d, ws.dd, v, ws.f, ws.fs, ws.kt)
    n = ca.eval_contacts(contact, ws.cstate, cw, u, v, ws.uc, sa.dofs)
    if n < 0:
        ca.eval_closed(contact, ws.cstate, cw, u, v, ws.uc, sa.dofs)
    for j in range(nd):
        dy[j] = v[j]
        dy[nd + j] = (cw.fc[j] - ws.f[j]) / sa.mass[j]
    # powers: input (supports), springs (f_s ḋ), viscous, contact (λ_N δ̇), friction (−λ_T U_T)
    pin = 0.0
    psp = 0.0
    pvi = 0.0
    for i in range(ws.d.shape[0]):
        ftot = ws.fs[i] + sa.crate[i] * ws.dd[i]
        ch = sa.schan[i]
        if ch >= 0:
            pin -= sa.sval[i] * vg[ch] * ftot
        psp += ws.fs[i] * ws.dd[i]
        pvi += sa.crate[i] * ws.dd[i] * ws.dd[i]
    a0 = sa.scal[SCAL_A0]
    for j in range(nd):
        pvi += a0 * sa.mass[j] * v[j] * v[j]
    pco = 0.0
    pfr = 0.0
    for c in range(len(cw.corners)):
        pco -= cw.lam[c] * cw.gd[c]
        if cw.lt[c] != 0.0:
            ut = 0.0
            for j in range(nd):
                ut += cw.WT[c, j] * v[j]
            pfr -= cw.lt[c] * ut
    dy[ny + W_INPUT] = pin
    dy[ny + W_SPRINGS] = psp
    dy[ny + W_VISCOUS] = pvi
    dy[ny + W_CONTACT] = pco
    dy[ny + W_FRICTION] = pfr


@kernel
def _events(y, sa, contact, ws, ev):
    """Event function values at a state: gaps (n_corners), Takeda ḋ (nbs), ġ (n_corners,
    bilinear), U_T (n_corners, stick friction); unused entries 0. ws.dd: the spring rates of
    the last :func:`_rhs` call."""
    cp = contact.params
    cw = ws.cw
    nbs = sa.nbs
    nd = len(sa.dofs)
    nc = len(cw.corners)
    u = y[0:nd]
    v = y[nd : 2 * nd]
    ca.gaps_and_rates(contact, u, v, cw, sa.dofs)
    for c in range(nc):
        ev[c] = cw.g[c]
    for i in range(nbs):
        ev[nc + i] = ws.dd[i]
    k = nc + nbs
    for c in range(nc):
        ev[k + c] = cw.gd[c] if (cp[c, cl.P_EVENT] != 0.0 and cw.g[c] < 0.0) else 0.0
        ut = 0.0
        if cp[c, cl.P_FMODE] == cl.FRICTION_STICK and cw.g[c] < 0.0:
            for j in range(nd):
                ut += cw.WT[c, j] * v[j]
        ev[k + nc + c] = ut


@kernel
def _hermite(y0, f0, y1, f1, h, th):
    h00 = 2 * th**3 - 3 * th**2 + 1
    h10 = th**3 - 2 * th**2 + th
    h01 = -2 * th**3 + 3 * th**2
    h11 = th**3 - th**2
    return h00 * y0 + h10 * h * f0 + h01 * y1 + h11 * h * f1


@kernel
def _event_value(kind_idx, y, sa, contact, record, t, ws):
    """Value of event kind_idx (layout of :func:`_events`) at an interpolated state y (t for
    the supports)."""
    cw = ws.cw
    nd = len(sa.dofs)
    nc = len(cw.corners)
    u = y[0:nd]
    v = y[nd : 2 * nd]
    ca.gaps_and_rates(contact, u, v, cw, sa.dofs)
    nbs2 = kind_idx - nc
    if kind_idx < nc:
        return cw.g[kind_idx]
    ns_ev = sa.nbs
    if nbs2 < ns_ev:
        _support(t, record.t, record.disp, record.vel, ws.ug, ws.vg)
        spring_deformations(sa, u, v, ws.ug, ws.vg, ws.d, ws.dd)
        return ws.dd[nbs2]
    c = nbs2 - ns_ev
    if c < nc:
        return cw.gd[c]
    c -= nc
    ut = 0.0
    for j in range(nd):
        ut += cw.WT[c, j] * v[j]
    return ut


@kernel
def _rk_step(t, y, h, sa, contact, record, ws, atol, rtol):
    """One DP5(4) step from (t, y) with slope ws.k1; returns the scaled error norm over u, u̇
    (ws.ynew filled, ws.K[6] = f(t+h, ynew))."""
    K, k1, ytmp, ynew = ws.K, ws.k1, ws.ytmp, ws.ynew
    ny = 2 * len(sa.dofs)
    nt = ny + N_WORK
    for j in range(nt):
        K[0, j] = k1[j]
    for s in range(1, 7):
        for j in range(nt):
            acc = y[j]
            for r in range(s):
                acc += h * _A[s, r] * K[r, j]
            ytmp[j] = acc
        if s == 6:
            for j in range(nt):
                ynew[j] = ytmp[j]
        _rhs(t + _C[s] * h, ytmp, sa, contact, record, ws, K[s])
    err = 0.0
    for j in range(ny):
        e = 0.0
        for s in range(7):
            e += h * _E[s] * K[s, j]
        sc = atol + rtol * max(abs(y[j]), abs(ynew[j]))
        err += (e / sc) ** 2
    return np.sqrt(err / ny)


@kernel
def _any_yielded(sa, hstate):
    """True once any Takeda (Hysteretic) spring has been deformed past its first backbone point.

    From then on the material's state depends on where it is committed, even along monotonic
    paths (OpenSees Hysteretic arithmetic), so the loop caps its steps at ``commit_step``.
    """
    for i in range(hstate.shape[0]):
        if sa.kind[i] == KIND_HYSTERETIC and (
            hstate[i, C_ROTMAX] > sa.hparams[i, P_E1P] or hstate[i, C_ROTMIN] < sa.hparams[i, P_E1N]
        ):
            return True
    return False


@kernel(inline="always")
def _kinetic_energy(sa, y):
    """½ u̇ᵀ M u̇ of the state y [kJ]."""
    nd = len(sa.dofs)
    ke = 0.0
    for j in range(nd):
        ke += 0.5 * sa.mass[j] * y[nd + j] ** 2
    return ke


@kernel(inline="always")
def _start(sa, contact, record, output, ws, stats):
    """The state at t = 0 from ws.u0, ws.v0: slope, materials and corners committed, the
    initial mechanical energy counted as input, output row 0, the peaks and the events."""
    y = ws.y
    nd = len(sa.dofs)
    ny = 2 * nd
    for j in range(nd):
        y[j] = ws.u0[j]
        y[nd + j] = ws.v0[j]
    for j in range(nd):
        ws.uc[j] = y[j]
    ca.linear_rows(contact, ws.cw, ws.u0, sa.dofs)
    _rhs(0.0, y, sa, contact, record, ws, ws.k1)
    stats.count[bd.CNT_RHS_CALLS] += 1
    spring_commit(sa, ws.hstate)
    cl.contact_commit(ws.cstate, ws.cw.g, ws.cw.gd, ws.cw.evaluated)
    ke = _kinetic_energy(sa, y)
    es0 = spring_stored_energy(sa, ws.hstate, y[0:nd], ws.ug)
    ec0 = cl.contact_stored_energy(contact.params, ws.cstate)
    y[ny + W_INPUT] = ke + es0 + ec0
    y[ny + W_SPRINGS] = es0
    y[ny + W_CONTACT] = ec0
    _adaptive_store(sa, contact, ws, output, 0, 0.0)
    _adaptive_track(sa, ws, output.peaks, 0.0)
    _events(y, sa, contact, ws, ws.ev0)


@kernel(inline="always")
def _next_break(tb, t, kseg, t_end, tout):
    """The next breakpoint after t: the next record sample (index hint kseg), the output time
    tout or t_end, whichever comes first. Returns (breakpoint [s], kseg)."""
    ntb = tb.shape[0]
    while kseg < ntb and tb[kseg] <= t + _TINY * max(1.0, t):
        kseg += 1
    tbreak = t_end
    if kseg < ntb and tb[kseg] < tbreak:
        tbreak = tb[kseg]
    return min(tbreak, tout), kseg


@kernel(inline="always")
def _bisect_event(q, flo, sa, contact, record, ws, t, h):
    """Where event q changes sign in (t, t + h] on the cubic Hermite interpolant of the step
    (flo: its value at t), as a fraction of h (the end of the last bracket)."""
    y, k1, ynew, ytmp, yev = ws.y, ws.k1, ws.ynew, ws.ytmp, ws.yev
    ny = 2 * len(sa.dofs)
    lo = 0.0
    hi = 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        for j in range(ny):
            yev[j] = _hermite(y[j], k1[j], ynew[j], ytmp[j], h, mid)
        fm = _event_value(q, yev, sa, contact, record, t + mid * h, ws)
        if (fm < 0.0) == (flo < 0.0) and fm != 0.0:
            lo = mid
            flo = fm
        else:
            hi = mid
        if (hi - lo) * h < 1e-13:
            break
    return hi


@kernel(inline="always")
def _locate_event(sa, contact, record, ws, stats, t, h, atol, rtol):
    """Events in (t, t + h] of an accepted trial step (sign changes between ws.ev0 and the
    values at its end; a zero at t + h counts): the step is redone from t to the first one.
    Returns (accepted step [s], whether an event ended it)."""
    ev0, ev1 = ws.ev0, ws.ev1
    cnt = stats.count
    _rhs(t + h, ws.ynew, sa, contact, record, ws, ws.ytmp)
    cnt[bd.CNT_RHS_CALLS] += 1
    _events(ws.ynew, sa, contact, ws, ev1)
    th_ev = 2.0
    for q in range(ev0.shape[0]):
        a_, b_ = ev0[q], ev1[q]
        if (a_ == 0.0 or (a_ < 0.0) == (b_ < 0.0)) and not (b_ == 0.0 and a_ != 0.0):
            continue  # no sign change in (t, t+h] (a zero at t+h counts)
        th_ev = min(th_ev, _bisect_event(q, a_, sa, contact, record, ws, t, h))
    if th_ev < 1.0 and th_ev * h > 1e-12:
        he = th_ev * h
        _rk_step(t, ws.y, he, sa, contact, record, ws, atol, rtol)
        cnt[bd.CNT_RHS_CALLS] += 6
        cnt[bd.CNT_EVENTS] += 1
        return he, True
    return h, False


@kernel(inline="always")
def _accept(sa, contact, record, ws, stats, output, t, yielded):
    """Accept the step ending at t (state ws.ynew): materials and corners committed there,
    the largest penetration, the yield flag, the slope and events at the new state, the step
    counted and its peaks tracked. Returns (a seat margin became negative, yielded)."""
    y, cw = ws.y, ws.cw
    cnt = stats.count
    nd = len(sa.dofs)
    for j in range(2 * nd + N_WORK):
        y[j] = ws.ynew[j]
    _rhs(t, y, sa, contact, record, ws, ws.k1)
    cnt[bd.CNT_RHS_CALLS] += 1
    spring_commit(sa, ws.hstate)
    cl.contact_commit(ws.cstate, cw.g, cw.gd, cw.evaluated)
    for c in range(len(cw.corners)):  # penetration at every accepted step
        if -cw.g[c] > stats.value[bd.VAL_MAX_PEN]:
            stats.value[bd.VAL_MAX_PEN] = -cw.g[c]
    if not yielded:
        yielded = _any_yielded(sa, ws.hstate)
    for j in range(nd):
        ws.uc[j] = y[j]
    _rhs(t, y, sa, contact, record, ws, ws.k1)
    cnt[bd.CNT_RHS_CALLS] += 1
    _events(y, sa, contact, ws, ws.ev0)
    cnt[bd.CNT_STEPS] += 1
    return _adaptive_track(sa, ws, output.peaks, t), yielded


@kernel(inline="always")
def _in_contact(ws):
    """True when a corner's gap is ≤ 0 in the event values ws.ev0 (the gaps come first)."""
    closed = False
    for c in range(len(ws.cw.corners)):
        closed = closed or ws.ev0[c] <= 0.0
    return closed


@kernel(inline="always")
def _count_step_size(ws, hs, in_contact):
    """Accepted step size hs [s] into the histogram and [min, max, sum] of its row (0 out of
    contact, 1 in contact)."""
    if hs <= 0.0:
        return
    ic = ROW_CONTACT if in_contact else ROW_FREE
    b = int((np.log10(hs) - H_LOG_MIN) * H_BINS_PER_DECADE)
    b = max(b, 0)
    if b >= H_NBINS:
        b = H_NBINS - 1
    ws.hist[ic, b] += 1
    hstat = ws.hstat
    if hstat[ic, HSTAT_MIN] == 0.0 or hs < hstat[ic, HSTAT_MIN]:
        hstat[ic, HSTAT_MIN] = hs
    hstat[ic, HSTAT_MAX] = max(hstat[ic, HSTAT_MAX], hs)
    hstat[ic, HSTAT_SUM] += hs


@kernel(inline="always")
def _all_finite(y):
    """True when every entry of y is finite."""
    finite = True
    for j in range(y.shape[0]):
        if not np.isfinite(y[j]):
            finite = False
    return finite


@kernel(inline="always")
def _next_step_size(h, err, h_acc):
    """Error control: h · 0.9 err^(−1/5), the factor within [0.2, 5]; not above h after a step
    shortened to an event."""
    if err > 0.0:
        fac = 0.9 * err**-0.2
        fac = min(fac, 5.0)
        fac = max(fac, 0.2)
        hn = h * fac
    else:
        hn = h * 5.0
    if h_acc < h and hn > h:
        hn = h
    return hn


@kernel(inline="always")
def _integrate(sa, contact, record, opt, output, ws, stats):
    """The steps over [0, opt.t_end]. Returns (status, time reached [s], rows written)."""
    t_end, out_dt = opt.t_end, opt.out_dt
    cnt = stats.count
    nout = output.table.shape[0]
    t = 0.0
    _start(sa, contact, record, output, ws, stats)
    row = 1
    h = min(opt.max_step, out_dt, 1e-4)
    yielded = _any_yielded(sa, ws.hstate)
    kseg = 0
    # the last trial step's error estimate was not finite: a step shrunk to nothing for that
    # reason meets a state or record that is not finite, not a stiff stretch
    nonfinite = False
    while t < t_end - _TINY * max(1.0, t_end):
        if stats.halt[0] != 0:
            return RUN_INTERRUPTED, t, row
        if cnt[bd.CNT_STEPS] + cnt[bd.CNT_REJECTED] >= opt.max_steps:
            return RUN_STEP_BUDGET, t, row
        tbreak, kseg = _next_break(record.t, t, kseg, t_end, row * out_dt)
        hmax = min(opt.max_step, tbreak - t)
        if yielded and hmax > opt.commit_step:
            hmax = opt.commit_step
        h = min(h, hmax)
        hit_break = abs((t + h) - tbreak) <= _TINY * max(1.0, tbreak)
        if h <= 1e-14:
            return (RUN_NONFINITE if nonfinite else RUN_STEP_UNDERFLOW), t, row
        err = _rk_step(t, ws.y, h, sa, contact, record, ws, opt.atol, opt.rtol)
        cnt[bd.CNT_RHS_CALLS] += 6
        nonfinite = not np.isfinite(err)
        if nonfinite:
            err = 1e10
        if err > 1.0:
            cnt[bd.CNT_REJECTED] += 1
            h *= max(0.2, 0.9 * err**-0.2)
            continue
        h_acc, at_event = _locate_event(sa, contact, record, ws, stats, t, h, opt.atol, opt.rtol)
        t_start = t
        in_contact = _in_contact(ws)
        t = tbreak if hit_break and not at_event else t + h_acc
        unseated, yielded = _accept(sa, contact, record, ws, stats, output, t, yielded)
        _count_step_size(ws, t - t_start, in_contact or _in_contact(ws))
        if not _all_finite(ws.y):
            return RUN_NONFINITE, t, row
        if unseated:  # a seat margin became negative at this step (.peaks): the answer ends
            return RUN_UNSEATED, t, row
        if row < nout and abs(t - row * out_dt) <= 1e-9 * out_dt:
            _adaptive_store(sa, contact, ws, output, row, row * out_dt)
            row += 1
        h = _next_step_size(h, err, h_acc)
    return RUN_OK, t, row


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
    # deckpound.analytic.fp_mode); the thread's mode is restored on the way out
    saved = flush_enter(opt.flush_subnormals)
    status, t, row = _integrate(system, contact, record, opt, output, work, stats)
    cnt = stats.count
    steps = cnt[bd.CNT_STEPS]
    cnt[bd.CNT_STATUS] = status
    cnt[bd.CNT_ROWS] = row
    cnt[bd.CNT_FAILED_STEP] = (
        0 if status == RUN_OK else (steps if status == RUN_UNSEATED else steps + 1)
    )
    stats.value[bd.VAL_TIME] = t
    flush_leave(saved)


@kernel
def _adaptive_track(sa, ws, pk, t):
    """Peaks and gap closures of the accepted step ending at t (:mod:`.peaks`): the engine
    columns as :func:`_adaptive_store` writes them, from the state of the last :func:`_rhs`
    call at (t, y); True when a seat margin became negative (:func:`.peaks.track_state`)."""
    y = ws.y
    cw = ws.cw
    nd = len(sa.dofs)
    return track_state(
        pk, t, y[0:nd], y[nd : 2 * nd], cw.g, cw.lam, cw.lt, ws.hstate[:, T_STRESS], ws.ug, ws.d
    )


@kernel
def _adaptive_store(sa, contact, ws, output, row, t):
    """Output row ``row`` at time t: the full row into ``output.row`` (standard columns, then
    the energies from the work totals y[2 n_dof:], :func:`.work_energy.energy_columns`), the
    selected columns into ``output.table``."""
    cp = contact.params
    cs = ws.cstate
    cw = ws.cw
    hstate = ws.hstate
    y = ws.y
    buf = output.row
    layout = output.peaks.layout
    nd = len(sa.dofs)
    store_standard(
        buf, layout, t, y[0:nd], y[nd : 2 * nd], cw.g, cw.lam, cw.lt, hstate[:, T_STRESS]
    )
    ke = _kinetic_energy(sa, y)
    es = spring_stored_energy(sa, hstate, y[0:nd], ws.ug)
    ec = cl.contact_stored_energy(cp, cs)
    energy_columns(buf, end_column(layout), y[2 * nd :], ke, es, ec, stick_spring_energy(cp, cs))
    sel = output.select
    table = output.table
    for q in range(sel.shape[0]):
        table[row, q] = buf[sel[q]]


#: (A, C, B5, E) of the tableau (module constants of the kernels)
TABLEAU = (_A, _C, _B5, _E)

"""Adaptive reference integrator of the compliance engine (``scene.compliance.integrator =
"adaptive"``).

Scheme: explicit embedded Runge–Kutta Dormand–Prince 5(4) on y = [u, u̇] (first-order form of
the same equation of motion as the Newmark clone; forces from :mod:`deckpound.analytic.system`
and :mod:`deckpound.analytic.contact_laws`), local error control with
``rtol``/``atol`` (scaled RMS norm over all 14 components, atol in m and m/s), step ≤
``max_step``, the whole loop compiled with numba. The problem is mildly stiff at most
(highest rates ~10³ 1/s for the benchmark: seat rotation, contact); the explicit scheme's
stability limit is then ~10⁻³ s and the error control keeps it stable automatically.

Breakpoints: every record sample (the support motion is piecewise linear between samples) and
every output time is hit exactly, so outputs need no interpolation.

Events (located by cubic Hermite interpolation over the accepted step, then the step is redone
from its start to the event time and committed there):

* gap closure / opening of each corner (g_N = 0): force kinks (linear, Hertz, bilinear) or jumps
  (Kelvin–Voigt) are never inside a step, and the Hunt–Crossley approach velocity is the one at
  closure;
* velocity reversal ḋ = 0 of every Takeda (Hysteretic) spring: the history-dependent springs
  are committed exactly at their reversal points, so every step sees a monotonic deformation
  path and the material law (evaluated as a trial from the committed state, as OpenSees does)
  is exact along it — the accuracy is then that of the RK error control, no O(h) history error;
* with the bilinear law: ġ = 0 while closed (loading/unloading switch); with stick friction:
  U_T = 0 while closed (slip reversal).

History-dependent states (Takeda, bilinear, stick friction, Hunt–Crossley v⁻) are committed at
each accepted step only. Energies are integrated as extra ODE components (excluded from the
error norm) from the power of each force, so ``energy_error`` measures the integration error.
"""

from __future__ import annotations

import time as _time

import numpy as np

from deckpound.analytic._jit import ensure_compiled
from deckpound.analytic.compliance import ENERGY_COLUMNS, pack_run
from deckpound.analytic.dormand_prince import H_BINS_PER_DECADE, H_LOG_MIN, H_NBINS, TABLEAU, \
    adaptive_run, workspace
from deckpound.analytic.system import initial_dofs
from deckpound.engine_contract import RunOutput, Status, engine_columns
from deckpound.models.excitation import analysis_duration

__all__ = ["run_adaptive"]


def _hist_median(counts: np.ndarray) -> float:
    """Median step size from a log10 histogram (geometric centre of the median bin)."""
    total = int(counts.sum())
    if total == 0:
        return float("nan")
    b = int(np.searchsorted(np.cumsum(counts), 0.5 * total))
    return float(10.0 ** (H_LOG_MIN + (b + 0.5) / H_BINS_PER_DECADE))


def step_size_summary(hist: np.ndarray, hstat: np.ndarray) -> dict:
    """Accepted step sizes out of / in contact: count, median (from a log histogram with
    H_BINS_PER_DECADE bins per decade, ±6 %), min, max, mean, and the time covered [s]."""
    out = {}
    for ic, name in ((0, "free"), (1, "contact")):
        n = int(hist[ic].sum())
        out[name] = {"steps": n, "median": _hist_median(hist[ic]),
                     "min": float(hstat[ic, 0]) if n else float("nan"),
                     "max": float(hstat[ic, 1]) if n else float("nan"),
                     "mean": float(hstat[ic, 2] / n) if n else float("nan"),
                     "time": float(hstat[ic, 2])}
    return out


def run_adaptive(plan, scene, settings, motion, *, kv_clip: bool = False,
                 initial_state=None) -> RunOutput:
    """Adaptive compliance run (see the module docstring); called by the compliance engine."""
    cset = settings
    duration = analysis_duration(scene, motion)
    # the record at its own samples, resampled on its finest step (breakpoints every sample)
    dtr = float(np.min(np.diff(motion.t)))
    res = motion.resample(dtr, duration)
    ps, _, cp, cs, corners = pack_run(plan, scene, res, kv_clip=kv_clip)
    UG, VG = res.matrices(ps.channels)
    tb = np.arange(UG.shape[0]) * dtr
    out_dt = scene.run.output_dt
    nout = int(round(duration / out_dt)) + 1
    cols = engine_columns(plan) + list(ENERGY_COLUMNS)
    out = np.zeros((nout, len(cols)))
    info = np.zeros(6, dtype=np.int64)
    nbs = ps.n_bent_springs
    ws = workspace(ps.n_springs, UG.shape[1], nbs)
    hstate = ps.new_state()
    u0, v0 = initial_dofs(initial_state)
    hist = np.zeros((2, H_NBINS), dtype=np.int64)
    hstat = np.zeros((2, 3))
    args = (ps.arrays, hstate, cp, cs, corners, scene.contact.geometry == "nonlinear", tb, UG,
            VG, (nout - 1) * out_dt, out_dt, nbs, cset.rtol, cset.atol, cset.max_step,
            cset.commit_step, out, info, ws, u0, v0, *TABLEAU, hist, hstat)
    compile_time = ensure_compiled(adaptive_run, *args)
    t1 = _time.perf_counter()
    adaptive_run(*args)
    loop = _time.perf_counter() - t1
    rows = int(info[1])
    columns = {k: out[:rows, i].copy() for i, k in enumerate(cols)}
    ein = np.max(np.abs(columns["energy_input"])) if rows else 0.0
    ok = info[0] == 0 and rows == nout
    extra = {
        "integrator": "adaptive", "kv_clip": kv_clip,
        "scheme": "Dormand-Prince 5(4) with events",
        "rejected_steps": int(info[3]), "events": int(info[4]), "rhs_calls": int(info[5]),
        "energy_closure": float(np.max(np.abs(columns["energy_error"])) / ein) if ein > 0
        else 0.0,
        "energy_columns": list(ENERGY_COLUMNS),
        "step_sizes": step_size_summary(hist, hstat),
    }
    t_fail = (rows - 1) * out_dt if rows else 0.0
    return RunOutput(
        columns=columns,
        status=Status.SUCCESS if ok else (Status.NOT_CONVERGED if info[0] == 1
                                          else Status.NONFINITE),
        message=(f"{int(info[2])} steps ({int(info[3])} rejected, {int(info[4])} events)" if ok
                 else "step size underflow" if info[0] == 1 else "non-finite state"),
        failed_step=None if ok else int(info[2]), failed_time=None if ok else t_fail,
        steps=int(info[2]), failed_steps=0 if ok else 1, compile_time=compile_time,
        loop_time=loop, extra=extra)

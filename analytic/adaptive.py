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

from deckpound.analytic.compliance import ENERGY_COLUMNS, output_columns, prepare
from deckpound.analytic.dormand_prince import H_BINS_PER_DECADE, H_LOG_MIN, H_NBINS, TABLEAU, \
    adaptive_run, workspace
from deckpound.analytic.system import initial_dofs
from deckpound.models.excitation import SupportMotion, support_motion
from deckpound.models.result import Result, scene_hash, set_status
from deckpound.models.scene import Scene

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


def run_adaptive(scene: Scene, motion: SupportMotion | None = None, *,
                 raise_on_failure: bool = False, kv_clip: bool = False,
                 initial_state=None) -> Result:
    """Adaptive compliance run (see the module docstring); engine contract as
    :func:`deckpound.analytic.compliance.run_compliance`."""
    t0 = _time.perf_counter()
    cset = scene.compliance
    if motion is None:
        motion = support_motion(scene)
    dtr = float(np.min(np.diff(motion.t)))
    ps, UG, VG, cp, cs, geom, duration = prepare(scene, motion, dtr, kv_clip=kv_clip)
    tb = np.arange(UG.shape[0]) * dtr
    out_dt = scene.run.output_dt
    nout = int(round(duration / out_dt)) + 1
    cols = output_columns(scene)
    out = np.zeros((nout, len(cols)))
    info = np.zeros(6, dtype=np.int64)
    nbs = ps.n_bent_springs
    ws = workspace(ps.n_springs, UG.shape[1], nbs)
    hstate = ps.new_state()
    u0, v0 = initial_dofs(initial_state)
    hist = np.zeros((2, H_NBINS), dtype=np.int64)
    hstat = np.zeros((2, 3))
    t1 = _time.perf_counter()
    adaptive_run(ps.arrays, hstate, cp, cs, geom, scene.contact.geometry == "nonlinear", tb, UG,
                 VG, (nout - 1) * out_dt, out_dt, nbs, cset.rtol, cset.atol, cset.max_step,
                 cset.commit_step, out,
                 info, ws, u0, v0, *TABLEAU, hist, hstat)
    t2 = _time.perf_counter()
    rows = int(info[1])
    columns = {k: out[:rows, i].copy() for i, k in enumerate(cols)}
    ein = np.max(np.abs(columns["energy_input"])) if rows else 0.0
    meta = {
        "engine": "compliance", "integrator": "adaptive",
        "settings": {"rtol": cset.rtol, "atol": cset.atol, "max_step": cset.max_step,
                     "commit_step": cset.commit_step,
                     "kv_clip": kv_clip, "scheme": "Dormand-Prince 5(4) with events"},
        "scene_hash": scene_hash(scene), "wall_time": t2 - t0, "loop_time": t2 - t1,
        "steps": int(info[2]), "rejected_steps": int(info[3]), "events": int(info[4]),
        "rhs_calls": int(info[5]), "iterations": 0, "failures": 0 if info[0] == 0 else 1,
        "contact_events": int(np.sum(np.diff((columns["fn_c1"] != 0).astype(int)) > 0) +
                              np.sum(np.diff((columns["fn_c2"] != 0).astype(int)) > 0) +
                              np.sum(np.diff((columns["fn_c3"] != 0).astype(int)) > 0) +
                              np.sum(np.diff((columns["fn_c4"] != 0).astype(int)) > 0))
        if rows > 1 else 0,
        "duration": duration,
        "energy_closure": float(np.max(np.abs(columns["energy_error"])) / ein) if ein > 0 else 0.0,
        "energy_columns": list(ENERGY_COLUMNS),
        "step_sizes": step_size_summary(hist, hstat),
    }
    ok = info[0] == 0 and rows == nout
    set_status(meta, engine="compliance (adaptive)", ok=ok, step=int(info[2]),
               time=(rows - 1) * out_dt if rows else 0.0,
               message=(f"{int(info[2])} steps ({int(info[3])} rejected, {int(info[4])} events)"
                        if ok else
                        "step size underflow" if info[0] == 1 else "non-finite state"),
               raise_on_failure=raise_on_failure)
    return Result(engine="compliance", columns=columns, meta=meta)

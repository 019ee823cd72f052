"""Adaptive reference integrator of the compliance engine (``scene.compliance.integrator =
"adaptive"``).

Scheme: explicit embedded Runge–Kutta Dormand–Prince 5(4) on y = [u, u̇] (first-order form of
the same equation of motion as the Newmark clone; forces from :mod:`deckpound.analytic.kernels.system`
and :mod:`deckpound.analytic.kernels.contact_laws`), local error control with
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

from deckpound.analytic import bundles as bd
from deckpound.analytic import interruptible
from deckpound.analytic._jit import ensure_compiled
from deckpound.analytic.compliance.dormand_prince import adaptive_run
from deckpound.analytic.compliance.dormand_prince_work import (
    H_BINS_PER_DECADE,
    H_LOG_MIN,
    HSTAT_MAX,
    HSTAT_MIN,
    HSTAT_SUM,
    ROW_CONTACT,
    ROW_FREE,
    AdaptiveOptions,
    adaptive_workspace,
)
from deckpound.analytic.compliance.pack import pack_run
from deckpound.analytic.kernels.peaks import run_output_fields, run_peaks
from deckpound.analytic.kernels.system import initial_dofs
from deckpound.models.columns import ENERGY_COLUMNS
from deckpound.models.engine_contract import RunOutput, Status, engine_columns
from deckpound.models.motion import analysis_duration

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
    for ic, name in ((ROW_FREE, "free"), (ROW_CONTACT, "contact")):
        n = int(hist[ic].sum())
        out[name] = {
            "steps": n,
            "median": _hist_median(hist[ic]),
            "min": float(hstat[ic, HSTAT_MIN]) if n else float("nan"),
            "max": float(hstat[ic, HSTAT_MAX]) if n else float("nan"),
            "mean": float(hstat[ic, HSTAT_SUM] / n) if n else float("nan"),
            "time": float(hstat[ic, HSTAT_SUM]),
        }
    return out


def run_adaptive(
    plan,
    scene,
    settings,
    motion,
    *,
    kv_clip: bool = False,
    initial_state=None,
    on_interrupt: str = "raise",
) -> RunOutput:
    """Adaptive compliance run (see the module docstring); called by the compliance engine
    (``on_interrupt``: see :meth:`deckpound.analytic.compliance.engine.ComplianceEngine._run`)."""
    cset = settings
    duration = analysis_duration(scene, motion)
    # the record at its own samples, resampled on its finest step (breakpoints every sample)
    dtr = float(np.min(np.diff(motion.t)))
    res = motion.resample(dtr, duration)
    ps, _, cp, cs, corners = pack_run(plan, scene, res, kv_clip=kv_clip)
    UG, VG = res.matrices(ps.channels)
    tb = np.arange(UG.shape[0]) * dtr
    out_dt = scene.run.output_dt
    nout = round(duration / out_dt) + 1
    cols = engine_columns(plan) + list(ENERGY_COLUMNS)
    peaks = run_peaks(plan, ps)
    output = bd.Output(
        bd.output_table(nout, len(cols)),
        np.arange(len(cols), dtype=np.int64),
        np.zeros(len(cols)),
        peaks,
    )
    u0, v0 = initial_dofs(initial_state, ps.arrays.mass.shape[0])
    work = adaptive_workspace(
        u0, v0, ps.new_state(), cs, ps.n_springs, UG.shape[1], ps.n_bent_springs
    )
    opts = AdaptiveOptions(
        t_end=(nout - 1) * out_dt,
        out_dt=float(out_dt),
        rtol=float(cset.rtol),
        atol=float(cset.atol),
        max_step=float(cset.max_step),
        commit_step=float(cset.commit_step),
        max_steps=int(cset.max_steps),
        flush_subnormals=cset.subnormals == "flush",
    )
    contact = bd.Contact(corners, cp, scene.contact.geometry == "nonlinear")
    stats = bd.new_stats()
    args = (ps.arrays, contact, bd.record(tb, UG, VG), opts, output, work, stats)
    compile_time = ensure_compiled(adaptive_run, *args)
    t1 = _time.perf_counter()
    interrupted = interruptible.run_loop(adaptive_run, args, stats)
    loop = _time.perf_counter() - t1
    if interrupted and on_interrupt == "raise":
        raise KeyboardInterrupt
    st = bd.stats_dict(stats)
    rows = st["rows"]
    columns = bd.result_columns(output.table, rows, cols)
    ein = np.max(np.abs(columns["energy_input"])) if rows else 0.0
    code = st["status"]
    ok = code == bd.RUN_OK and rows == nout
    status = (
        Status.SUCCESS if ok else (bd.status_of(code) if code != bd.RUN_OK else Status.NONFINITE)
    )
    finished = ok or status == Status.UNSEATED  # unseating is an answer, not a failure
    extra = {
        "integrator": "adaptive",
        "kv_clip": kv_clip,
        "scheme": "Dormand-Prince 5(4) with events",
        "rejected_steps": st["rejected_steps"],
        "events": st["contact_events"],
        "rhs_calls": st["rhs_calls"],
        "energy_closure": float(np.max(np.abs(columns["energy_error"])) / ein) if ein > 0 else 0.0,
        "energy_columns": list(ENERGY_COLUMNS),
        "step_sizes": step_size_summary(work.hist, work.hstat),
    }
    if ok:
        message = (
            f"{st['steps']} steps ({st['rejected_steps']} rejected, {st['contact_events']} events)"
        )
    elif code == bd.RUN_STEP_BUDGET:
        message = (
            f"step budget exhausted: compliance.max_steps = {cset.max_steps} steps tried "
            f"reached t = {st['time']:.6g} s of {opts.t_end:g} s"
        )
    elif code == bd.RUN_STEP_UNDERFLOW:
        message = f"{status.text}: step size underflow (below 1e-14 s)"
    else:
        message = status.text
    return RunOutput(
        columns=columns,
        status=status,
        message=message,
        failed_step=None if finished else st["failed_step"],
        failed_time=None if finished else st["time"],
        steps=st["steps"],
        failed_steps=0 if finished else 1,
        compile_time=compile_time,
        loop_time=loop,
        max_penetration=st["max_penetration"],
        **run_output_fields(peaks, plan),
        extra=extra,
    )

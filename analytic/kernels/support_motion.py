"""Support motion at the engine's step, interpolated inside the compiled loop (bounded memory).

Engines used to resample the whole record onto their own step
(:meth:`deckpound.models.motion.SupportMotion.resample`), i.e. arrays of
``n_steps × n_channels`` for displacement and velocity: 6 million steps × 8 channels × 2 ×
8 bytes ≈ 0.8 GB for a 60 s record at dt = 1e-5 s. Instead, keep the record at its own samples
(a few thousand rows) and interpolate at t_n = n·dt inside the step loop:

    tb, D, V = support_record(motion, channels)      # once per run (Python)
    SD, SV = record_slopes(tb, D, V)                  # once per run (Python)
    j = 0
    j = record_at(tb, D, V, SD, SV, n * dt, j, ug, vg)  # per step (numba); j: search hint

:func:`record_at` is bit-for-bit the arithmetic of ``np.interp(t, tb, column)`` (NumPy's
``arr_interp``: slope = (y[j+1] − y[j]) / (x[j+1] − x[j]), value = slope·(t − x[j]) + y[j];
exactly y[j] at a sample; the first / last value held before / after the record), so an
engine that switches from ``motion.resample(dt, duration)`` to it produces identical
results (tested in ``tests/test_support_motion.py``). The slopes are the same IEEE divisions
computed once per segment by :func:`record_slopes` instead of at every step (2 per channel and
step: 16 divisions on the benchmark). The hint ``j`` makes sequential calls O(1); any hint is
valid (the search moves both ways).
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic._jit import kernel

__all__ = ["record_at", "record_at_times", "record_slopes", "support_record"]


def support_record(motion, channels) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(tb, D, V): the record's own time base (n,) and displacement / velocity (n, n_channels)
    in the given channel order, contiguous float64 (what :func:`record_at` takes)."""
    tb = np.ascontiguousarray(np.asarray(motion.t, dtype=np.float64))
    D, V = motion.matrices(tuple(channels))
    return tb, np.ascontiguousarray(D, dtype=np.float64), np.ascontiguousarray(V, dtype=np.float64)


def record_slopes(tb, D, V) -> tuple[np.ndarray, np.ndarray]:
    """(SD, SV), shape of D: the slopes (y[j+1] − y[j]) / (x[j+1] − x[j]) of every segment j of
    the record (the divisions of ``np.interp``, elementwise the same IEEE operations); the last
    row, after the last sample, is zero (never read)."""
    SD = np.empty_like(D)
    SV = np.empty_like(V)
    SD[-1:] = 0.0
    SV[-1:] = 0.0
    if tb.shape[0] > 1:
        dx = (tb[1:] - tb[:-1])[:, None]
        # in place: the same subtraction and division as (y[j+1] - y[j]) / dx, no temporaries
        for y, slope in ((D, SD), (V, SV)):
            np.subtract(y[1:], y[:-1], out=slope[:-1])
            np.divide(slope[:-1], dx, out=slope[:-1])
    return SD, SV


@kernel(inline="always")
def record_at(tb, D, V, SD, SV, t, j, ug, vg):
    """Fill ug, vg (n_channels,) with the support motion at time t; returns the new hint.
    Inlined into the step loops (once per step; a call would pass seven arrays by value).

    SD, SV: :func:`record_slopes` of the record. Identical to ``np.interp(t, tb, D[:, k])``
    (and V) for every channel k.
    """
    n = tb.shape[0]
    nch = D.shape[1]
    if t >= tb[n - 1]:  # at or after the last sample: last value held
        for k in range(nch):
            ug[k] = D[n - 1, k]
            vg[k] = V[n - 1, k]
        return n - 1
    if t < tb[0]:  # before the record: first value held
        for k in range(nch):
            ug[k] = D[0, k]
            vg[k] = V[0, k]
        return 0
    j = max(j, 0)
    j = min(j, n - 2)
    while tb[j] > t:
        j -= 1
    while tb[j + 1] <= t:
        j += 1
    # now tb[j] <= t < tb[j+1]
    if tb[j] == t:
        for k in range(nch):
            ug[k] = D[j, k]
            vg[k] = V[j, k]
        return j
    x = t - tb[j]
    for k in range(nch):
        ug[k] = SD[j, k] * x + D[j, k]
        vg[k] = SV[j, k] * x + V[j, k]
    return j


@kernel
def record_at_times(tb, D, V, SD, SV, dt, n0, n1, UG, VG):
    """Rows n0..n1−1 of the resampled motion at t = n·dt into UG, VG (n1 − n0, n_channels):
    a bounded-size block version of ``motion.resample`` (for engines that step in chunks)."""
    j = 0
    for n in range(n0, n1):
        j = record_at(tb, D, V, SD, SV, n * dt, j, UG[n - n0], VG[n - n0])

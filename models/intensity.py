"""Intensity measures of a ground-motion record and of a horizontal record pair (numpy only).

For one acceleration history a [m/s²] sampled at a constant step Δt from rest, with the
velocity v [m/s] and displacement d [m] the motion applies:

* PGA = max |a|, PGV = max |v|, PGD = max |d|;
* Arias intensity I_A = π/(2g) ∫ a² dt [m/s] (Arias 1970) and the cumulative absolute
  velocity CAV = ∫ |a| dt [m/s] (EPRI TR-100082, 1991), both by the trapezoidal rule on the
  samples;
* the 5–95 % significant duration D5-95 [s] (Trifunac & Brady 1975): the time between 5 % and
  95 % of the final Arias intensity on its cumulative (trapezoidal) curve, interpolated
  linearly between samples;
* the pseudo-spectral acceleration Sa(T, ζ) = ω² max |u| (ω = 2π/T) of the linear oscillator
  ü + 2ζωu̇ + ω²u = −a(t), with a piecewise linear between samples: the exact recurrence of
  Nigam & Jennings (1969), :func:`oscillator_displacements`.

For a horizontal pair (x, y) at period T: the geometric mean √(Sa_x · Sa_y) and RotD50,
RotD100 (Boore 2010, BSSA 100(4):1830): the two oscillator responses combined as
u(θ) = u_x cos θ + u_y sin θ for θ = 0°, 1°, …, 179°, Sa(θ) = ω² max_t |u(θ)|; RotD50 is the
median (50th percentile, linear interpolation between order statistics, as numpy's
``percentile``) and RotD100 the largest of the 180 values.

The record motions call :func:`pair_measures` once per applied pair; the result goes into the
motion's provenance under ``intensity`` (:data:`UNITS`).
"""

from __future__ import annotations

import math

import numpy as np

G = 9.80665  # standard gravity [m/s²]
DAMPING = 0.05  # damping ratio of the response spectra (the engineering convention)
ROTD_ANGLES = np.deg2rad(np.arange(180.0))  # 0°, 1°, …, 179° (Boore 2010)
#: samples per block of the blocked recurrence (see :func:`oscillator_displacements`)
BLOCK = 64
#: most elements of one rotated-response array held at once (RotD over long records)
ROTD_CHUNK = 4_000_000

#: unit of each measure as kept in the provenance
UNITS = {
    "pga": "g",
    "pgv": "m/s",
    "pgd": "m",
    "arias": "m/s",
    "cav": "m/s",
    "d5_95": "s",
    "sa": "g",
    "sa_geomean": "g",
    "rotd50": "g",
    "rotd100": "g",
    "period": "s",
    "damping": "-",
}


def _check_oscillators(periods: np.ndarray, damping: float) -> None:
    if not np.all(np.isfinite(periods)) or not np.all(periods > 0.0):
        raise ValueError(f"oscillator periods must be finite and > 0 s, got {periods}")
    if not 0.0 <= damping < 1.0:
        raise ValueError(f"damping ratio must lie in [0, 1), got {damping}")


def free_transition(omega: np.ndarray, damping: float, time: np.ndarray) -> np.ndarray:
    """Φ(t) = exp(F t), F = [[0, 1], [−ω², −2ζω]]: the oscillator's free motion over ``time``.

    Closed form of the under-damped oscillator (ω_d = ω√(1 − ζ²)):
    Φ = e^{−ζωt} [[c + ζω s/ω_d, s/ω_d], [−ω² s/ω_d, c − ζω s/ω_d]], c = cos ω_d t,
    s = sin ω_d t. Broadcasts ``omega`` (K,) against ``time`` (M,) to shape (K, M, 2, 2).
    """
    w = np.asarray(omega, float)[:, None]
    t = np.asarray(time, float)[None, :]
    wd = w * math.sqrt(1.0 - damping * damping)
    e = np.exp(-damping * w * t)
    c, s = np.cos(wd * t), np.sin(wd * t) / wd
    out = np.empty(np.broadcast_shapes(w.shape, t.shape) + (2, 2))
    out[..., 0, 0] = e * (c + damping * w * s)
    out[..., 0, 1] = e * s
    out[..., 1, 0] = -e * w * w * s
    out[..., 1, 1] = e * (c - damping * w * s)
    return out


def load_matrices(omega: np.ndarray, damping: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(P, Q), each (K, 2): z_{n+1} = Φ z_n + P a_n + Q a_{n+1} for z = (u, u̇) under
    ü + 2ζωu̇ + ω²u = −a(t) with a linear between a_n and a_{n+1} (Nigam & Jennings 1969).

    With G = (0, −1) the load vector, Γ = ∫₀^Δt e^{Fσ} dσ G = F⁻¹(Φ − I) G and
    J = ∫₀^Δt σ e^{Fσ} dσ G = [Δt F⁻¹ Φ − F⁻²(Φ − I)] G, the hold of the linear load gives
    P = J/Δt (weight of a_n) and Q = Γ − J/Δt (weight of a_{n+1}); F⁻¹ = [[−2ζ/ω, −1/ω²],
    [1, 0]].
    """
    w = np.asarray(omega, float)
    phi = free_transition(w, damping, np.array([dt]))[:, 0]
    finv = np.zeros_like(phi)
    finv[:, 0, 0] = -2.0 * damping / w
    finv[:, 0, 1] = -1.0 / (w * w)
    finv[:, 1, 0] = 1.0
    load = np.array([0.0, -1.0])
    eye = np.eye(2)
    gamma = finv @ (phi - eye) @ load
    moment = (dt * finv @ phi - finv @ finv @ (phi - eye)) @ load
    return moment / dt, gamma - moment / dt


def oscillator_displacements(
    acc: np.ndarray, dt: float, periods, damping: float = DAMPING
) -> np.ndarray:
    """Relative displacements u [m], shape (K, n), of oscillators of ``periods`` [s] (K,) at
    rest at t = 0 under the ground acceleration ``acc`` [m/s²] (n,), linear between samples.

    The exact recurrence z_{n+1} = Φ z_n + f_n (f_n = P a_n + Q a_{n+1},
    :func:`load_matrices`) is evaluated in blocks of ``BLOCK`` samples so that no Python loop
    runs per sample: inside a block starting at state s, z_j = Φ(jΔt) s + Σ_{i<j}
    Φ((j − 1 − i)Δt) f_i — a lower-triangular convolution with the closed-form kernel
    (:func:`free_transition`), one matrix product over all blocks of an oscillator — and the
    blocks are chained by their end states. The same sums in another order: equal to the
    sample-by-sample recurrence to round-off.
    """
    a = np.asarray(acc, float)
    periods = np.atleast_1d(np.asarray(periods, float))
    _check_oscillators(periods, damping)
    n = len(a)
    omega = 2.0 * np.pi / periods
    k = len(omega)
    if n < 2:
        return np.zeros((k, n))
    p_load, q_load = load_matrices(omega, damping, dt)
    forcing = p_load[:, None, :] * a[None, :-1, None] + q_load[:, None, :] * a[None, 1:, None]
    nb = -(-(n - 1) // BLOCK)
    padded = np.zeros((k, nb * BLOCK, 2))
    padded[:, : n - 1] = forcing
    blocks = padded.reshape(k, nb, BLOCK, 2)
    # kernel[:, m] = Φ(mΔt), m = 0..BLOCK; conv[:, j, i] = Φ((j − 1 − i)Δt) for i < j
    kernel = free_transition(omega, damping, dt * np.arange(BLOCK + 1))
    lag = np.arange(BLOCK + 1)[:, None] - 1 - np.arange(BLOCK)[None, :]
    conv = np.where((lag >= 0)[None, :, :, None, None], kernel[:, np.maximum(lag, 0)], 0.0)
    # particular part of every block, one matrix product per oscillator (2-D products: a
    # stacked 3-D matmul runs several times slower under a threaded BLAS on a busy machine)
    conv_t = conv.transpose(0, 2, 4, 1, 3).reshape(k, 2 * BLOCK, 2 * (BLOCK + 1))
    flat = blocks.reshape(k, nb, 2 * BLOCK)
    part = np.stack([flat[i] @ conv_t[i] for i in range(k)]).reshape(k, nb, BLOCK + 1, 2)
    # chain the blocks by their end states: s_{b+1} = Φ(LΔt) s_b + part_b(L)
    step = kernel[:, BLOCK]
    ends = part[:, :, BLOCK]
    starts = np.zeros((k, nb, 2))
    s0, s1 = np.zeros(k), np.zeros(k)
    for b in range(nb):
        starts[:, b, 0], starts[:, b, 1] = s0, s1
        s0, s1 = (
            step[:, 0, 0] * s0 + step[:, 0, 1] * s1 + ends[:, b, 0],
            step[:, 1, 0] * s0 + step[:, 1, 1] * s1 + ends[:, b, 1],
        )
    free_t = kernel[:, :BLOCK].transpose(0, 3, 1, 2).reshape(k, 2, 2 * BLOCK)
    free = np.stack([starts[i] @ free_t[i] for i in range(k)])
    z = (free.reshape(k, nb, BLOCK, 2) + part[:, :, :BLOCK]).reshape(k, nb * BLOCK, 2)
    state = np.stack([s0, s1], axis=1)
    u = np.empty((k, n))
    u[:, : n - 1] = z[:, : n - 1, 0]
    u[:, n - 1] = state[:, 0] if (n - 1) % BLOCK == 0 else z[:, n - 1, 0]
    return u


def spectral_acceleration(
    acc: np.ndarray, dt: float, periods, damping: float = DAMPING
) -> np.ndarray:
    """Pseudo-spectral accelerations Sa = ω² max |u| [m/s²] at ``periods`` [s] (K,)."""
    periods = np.atleast_1d(np.asarray(periods, float))
    u = oscillator_displacements(acc, dt, periods, damping)
    omega = 2.0 * np.pi / periods
    return omega**2 * (np.max(np.abs(u), axis=1) if u.shape[1] else 0.0)


def rotd(
    u_x: np.ndarray, u_y: np.ndarray, period: float, percentiles=(50.0, 100.0)
) -> tuple[float, ...]:
    """RotD percentiles [m/s²] of the pair's oscillator displacements ``u_x``, ``u_y`` [m] at
    ``period`` [s]: Sa(θ) = ω² max_t |u_x cos θ + u_y sin θ| over θ = 0°..179° in 1° steps."""
    omega = 2.0 * np.pi / period
    u_x, u_y = _rotd_candidates(np.asarray(u_x, float), np.asarray(u_y, float))
    peaks = _rotated_peaks(u_x, u_y)
    return tuple(float(omega**2 * np.percentile(peaks, p)) for p in percentiles)


def _rotated_peaks(u_x: np.ndarray, u_y: np.ndarray) -> np.ndarray:
    """max_t |u_x cos θ + u_y sin θ| for every angle of ROTD_ANGLES (chunked in memory)."""
    peaks = np.zeros(len(ROTD_ANGLES))
    if not len(u_x):
        return peaks
    chunk = max(1, ROTD_CHUNK // len(u_x))
    for lo in range(0, len(ROTD_ANGLES), chunk):
        th = ROTD_ANGLES[lo : lo + chunk]
        rotated = np.cos(th)[:, None] * u_x[None, :] + np.sin(th)[:, None] * u_y[None, :]
        peaks[lo : lo + chunk] = np.max(np.abs(rotated), axis=1)
    return peaks


def _rotd_candidates(u_x: np.ndarray, u_y: np.ndarray, keep: int = 256):
    """The samples that can hold the peak of some rotation, every other dropped (exact).

    |u_x cos θ + u_y sin θ| ≤ r = √(u_x² + u_y²) at every sample, and the peak at θ is at
    least the peak over any subset; so with L = min_θ (peak over the ``keep`` samples of
    largest r), a sample with r < L is the peak of no rotation.
    """
    r = np.hypot(u_x, u_y)
    if len(r) <= keep:
        return u_x, u_y
    top = np.argpartition(r, -keep)[-keep:]
    bound = float(np.min(_rotated_peaks(u_x[top], u_y[top])))
    mask = r >= bound
    return u_x[mask], u_y[mask]


def arias_curve(acc: np.ndarray, dt: float) -> np.ndarray:
    """Cumulative Arias intensity π/(2g) ∫₀^t a² dt [m/s] at every sample (trapezoidal)."""
    a2 = np.asarray(acc, float) ** 2
    return np.pi / (2.0 * G) * np.concatenate([[0.0], np.cumsum(0.5 * (a2[1:] + a2[:-1]) * dt)])


def significant_duration(
    acc: np.ndarray, dt: float, start: float = 0.05, end: float = 0.95
) -> float | None:
    """Time [s] between ``start`` and ``end`` fractions of the final Arias intensity, on the
    cumulative curve interpolated linearly; None for a record without motion."""
    curve = arias_curve(acc, dt)
    total = curve[-1]
    if not total > 0.0:
        return None
    t = np.arange(len(curve)) * dt
    t_start, t_end = np.interp([start * total, end * total], curve, t)
    return float(t_end - t_start)


def component_measures(
    acc: np.ndarray, vel: np.ndarray, disp: np.ndarray, dt: float, period: float | None
) -> dict:
    """PGA [g], PGV [m/s], PGD [m], Arias intensity [m/s], CAV [m/s], D5-95 [s] and
    Sa(period, 5 %) [g] (None without a period) of one component (units: :data:`UNITS`)."""
    a = np.asarray(acc, float)
    absolute = np.abs(a)
    sa = (
        float(spectral_acceleration(a, dt, [period])[0]) / G
        if period is not None and len(a)
        else None
    )
    return {
        "pga": float(np.max(absolute)) / G if len(a) else 0.0,
        "pgv": float(np.max(np.abs(vel))) if len(vel) else 0.0,
        "pgd": float(np.max(np.abs(disp))) if len(disp) else 0.0,
        "arias": float(arias_curve(a, dt)[-1]) if len(a) else 0.0,
        "cav": float(np.sum(0.5 * (absolute[1:] + absolute[:-1])) * dt),
        "d5_95": significant_duration(a, dt),
        "sa": sa,
    }


def pair_measures(
    dt: float,
    acc: dict[str, np.ndarray],
    vel: dict[str, np.ndarray],
    disp: dict[str, np.ndarray],
    period: float | None,
    damping: float = DAMPING,
) -> dict:
    """Intensity measures of a horizontal pair (``acc``, ``vel``, ``disp``: axis "x", "y" →
    (n,) arrays [m/s²], [m/s], [m] on one time base of step ``dt`` [s]) at ``period`` [s]:
    ``{"period", "damping", "x": {...}, "y": {...}, "sa_geomean", "rotd50", "rotd100",
    "units"}`` (component keys: :func:`component_measures`); the spectral values are None
    without a period."""
    out: dict = {"period": period, "damping": damping}
    u = {}
    for axis in ("x", "y"):
        a = np.asarray(acc[axis], float)
        out[axis] = component_measures(a, vel[axis], disp[axis], dt, None)
        if period is not None:
            u[axis] = oscillator_displacements(a, dt, [period], damping)[0]
            peak = float(np.max(np.abs(u[axis]))) if len(a) else 0.0
            out[axis]["sa"] = (2.0 * np.pi / period) ** 2 * peak / G
    if period is None:
        out.update(sa_geomean=None, rotd50=None, rotd100=None)
    else:
        out["sa_geomean"] = math.sqrt(out["x"]["sa"] * out["y"]["sa"])
        r50, r100 = rotd(u["x"], u["y"], period)
        out["rotd50"], out["rotd100"] = r50 / G, r100 / G
    out["units"] = dict(UNITS)
    return out

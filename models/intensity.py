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

import functools
import math

import numpy as np

G = 9.80665  # standard gravity [m/s²]
DAMPING = 0.05  # damping ratio of the response spectra (the engineering convention)
ROTD_ANGLES = np.deg2rad(np.arange(180.0))  # 0°, 1°, …, 179° (Boore 2010)
#: samples per block of the blocked recurrence (see :func:`oscillator_displacements`)
BLOCK = 64
#: most elements of one rotated-response array held at once (RotD over long records)
ROTD_CHUNK = 4_000_000
#: consecutive angles sharing one bound in the candidate search (see :func:`_rotd_candidates`)
ROTD_GROUP = 10
#: responses of at most this many samples are rotated whole, without a candidate search
ROTD_KEEP = 64
_ROTD_COS, _ROTD_SIN = np.cos(ROTD_ANGLES), np.sin(ROTD_ANGLES)
_GROUP_CENTRES = np.deg2rad(np.arange(180.0).reshape(-1, ROTD_GROUP).mean(axis=1))
_GROUP_COS, _GROUP_SIN = np.cos(_GROUP_CENTRES), np.sin(_GROUP_CENTRES)
_GROUP_HALF_SIN = math.sin(math.radians(0.5 * (ROTD_GROUP - 1)))

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
    if not all(math.isfinite(p) and p > 0.0 for p in periods.tolist()):
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
    k = len(periods)
    if n < 2:
        return np.zeros((k, n))
    p_load, q_load, conv_t, step, free_t = (
        _one_oscillator(float(periods[0]), float(damping), float(dt))
        if k == 1
        else block_operators(periods, damping, dt)
    )
    # the forcing f_n = P a_n + Q a_{n+1} of each oscillator and state component, zero-padded
    # to whole blocks
    nb = -(-(n - 1) // BLOCK)
    padded = np.zeros((k, nb * BLOCK, 2))
    for i in range(k):
        for c in range(2):
            np.multiply(p_load[i, c], a[:-1], out=padded[i, : n - 1, c])
            padded[i, : n - 1, c] += q_load[i, c] * a[1:]
    flat = padded.reshape(k, nb, 2 * BLOCK)
    # particular part of every block, one matrix product per oscillator (2-D products: a
    # stacked 3-D matmul runs several times slower under a threaded BLAS on a busy machine)
    part = np.empty((k, nb, 2 * (BLOCK + 1)))
    for i in range(k):
        np.matmul(flat[i], conv_t[i], out=part[i])
    part = part.reshape(k, nb, BLOCK + 1, 2)
    # chain the blocks by their end states: s_{b+1} = Φ(LΔt) s_b + part_b(L), in Python
    # floats (the same products and sums as numpy's, without a numpy call per block)
    ends = part[:, :, BLOCK].tolist()
    chained = []
    for i in range(k):
        (f00, f01), (f10, f11) = step[i]
        s0 = s1 = 0.0
        starts = []
        for e0, e1 in ends[i]:
            starts.append((s0, s1))
            s0, s1 = f00 * s0 + f01 * s1 + e0, f10 * s0 + f11 * s1 + e1
        chained.append((starts, s0))
    free = np.empty((k, nb, 2 * BLOCK))
    for i in range(k):
        np.matmul(np.array(chained[i][0]), free_t[i], out=free[i])
    # z = free + particular motion, of which only the displacement u is kept
    u_blocks = free.reshape(k, nb, BLOCK, 2)[..., 0] + part[:, :, :BLOCK, 0]
    u = np.empty((k, n))
    u[:, : n - 1] = u_blocks.reshape(k, nb * BLOCK)[:, : n - 1]
    if (n - 1) % BLOCK == 0:
        u[:, n - 1] = [end for _, end in chained]
    else:
        u[:, n - 1] = u_blocks.reshape(k, nb * BLOCK)[:, n - 1]
    return u


def block_operators(periods: np.ndarray, damping: float, dt: float) -> tuple:
    """The matrices of :func:`oscillator_displacements` for oscillators of ``periods`` [s]
    (K,) and ``damping`` at the step ``dt`` [s].

    Returns (P, Q) of :func:`load_matrices`, each (K, 2); the block convolution (K, 2·BLOCK,
    2·(BLOCK + 1)) whose row 2i + c, column 2j + r is Φ((j − 1 − i)Δt)[r, c] for i < j, else
    0; Φ(BLOCK·Δt) as nested lists of floats (K, 2, 2); and the free motion over a block
    (K, 2, 2·BLOCK), column 2m + r of row c being Φ(mΔt)[r, c].
    """
    omega = 2.0 * np.pi / np.asarray(periods, float)
    k = len(omega)
    p_load, q_load = load_matrices(omega, damping, dt)
    # kernel[:, m] = Φ(mΔt), m = 0..BLOCK; conv[:, j, i] = Φ((j − 1 − i)Δt) for i < j
    kernel = free_transition(omega, damping, dt * np.arange(BLOCK + 1))
    lag = np.arange(BLOCK + 1)[:, None] - 1 - np.arange(BLOCK)[None, :]
    conv = np.where((lag >= 0)[None, :, :, None, None], kernel[:, np.maximum(lag, 0)], 0.0)
    conv_t = conv.transpose(0, 2, 4, 1, 3).reshape(k, 2 * BLOCK, 2 * (BLOCK + 1))
    free_t = kernel[:, :BLOCK].transpose(0, 3, 1, 2).reshape(k, 2, 2 * BLOCK)
    return p_load, q_load, conv_t, kernel[:, BLOCK].tolist(), free_t


@functools.lru_cache(maxsize=16)
def _one_oscillator(period: float, damping: float, dt: float) -> tuple:
    """:func:`block_operators` of one oscillator, kept per (period, damping, dt): a sweep of
    one structure asks for the same oscillator every case (read-only arrays)."""
    operators = block_operators(np.array([period]), damping, dt)
    for x in operators:
        if isinstance(x, np.ndarray):
            x.flags.writeable = False
    return operators


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
    return tuple(float(omega**2 * p) for p in np.percentile(peaks, percentiles))


def _rotated_peaks(u_x: np.ndarray, u_y: np.ndarray) -> np.ndarray:
    """max_t |u_x cos θ + u_y sin θ| for every angle of ROTD_ANGLES (chunked in memory)."""
    if not len(u_x):
        return np.zeros(len(ROTD_ANGLES))
    peaks = np.empty(len(ROTD_ANGLES))
    chunk = max(1, ROTD_CHUNK // len(u_x))
    for lo in range(0, len(ROTD_ANGLES), chunk):
        rotated = np.multiply.outer(_ROTD_COS[lo : lo + chunk], u_x)
        rotated += np.multiply.outer(_ROTD_SIN[lo : lo + chunk], u_y)
        peaks[lo : lo + chunk] = np.abs(rotated, out=rotated).max(axis=1)
    return peaks


def _rotd_candidates(u_x: np.ndarray, u_y: np.ndarray):
    """The samples that can hold the peak of some rotation, every other dropped (exact).

    The peak at θ is at least the peak over any subset of samples (the witnesses below).
    First by radius: |u_x cos θ + u_y sin θ| ≤ r = √(u_x² + u_y²) at every sample, so with
    L = min_θ (peak over the samples of largest r, |u_x|, |u_y|, |u_x + u_y| and |u_x − u_y|),
    a sample with r < L is the peak of no rotation. Then by groups of ``ROTD_GROUP``
    consecutive angles, of centre θ_c and half-width h: for θ = θ_c + δ (|δ| ≤ h),
    u(θ) = u(θ_c) cos δ + u⊥(θ_c) sin δ with u⊥(θ_c) = −u_x sin θ_c + u_y cos θ_c, so
    |u(θ)| ≤ U = |u(θ_c)| + |u⊥(θ_c)| sin h at every sample; with L_c the least, over a
    group's angles, of the peak over the witnesses (each group's sample of largest
    |u(θ_c)|), a sample with U < L_c is the peak of no angle of that group, and one below it
    for every group is dropped. Both comparisons allow 10⁻¹² of the largest r for round-off.
    A pair at rest in one axis keeps one sample: |u(θ)| is then |cos θ| or |sin θ| times the
    other axis' |u|, largest (rounding being monotone) where that |u| is.
    """
    if len(u_x) <= ROTD_KEEP:
        return u_x, u_y
    for moving, still in ((u_x, u_y), (u_y, u_x)):
        if not still.any():
            peak = int(np.argmax(np.abs(moving)))
            return u_x[peak : peak + 1], u_y[peak : peak + 1]
    radius = np.sqrt(u_x * u_x + u_y * u_y)
    tolerance = 1e-12 * float(np.max(radius))
    witnesses = [np.argmax(radius)]
    witnesses += [np.argmax(np.abs(w)) for w in (u_x, u_y, u_x + u_y, u_x - u_y)]
    bound = float(np.min(_rotated_peaks(u_x[witnesses], u_y[witnesses])))
    keep = radius >= bound - tolerance
    u_x, u_y = u_x[keep], u_y[keep]
    centre = np.multiply.outer(_GROUP_COS, u_x)
    centre += np.multiply.outer(_GROUP_SIN, u_y)
    np.abs(centre, out=centre)
    witnesses = np.argmax(centre, axis=1)
    lower = _rotated_peaks(u_x[witnesses], u_y[witnesses])
    needed = lower.reshape(-1, ROTD_GROUP).min(axis=1) - tolerance
    across = np.multiply.outer(_GROUP_COS, u_y)
    across -= np.multiply.outer(_GROUP_SIN, u_x)
    np.abs(across, out=across)
    across *= _GROUP_HALF_SIN
    centre += across
    keep = np.any(centre >= needed[:, None], axis=0)
    return u_x[keep], u_y[keep]


def arias_curve(acc: np.ndarray, dt: float) -> np.ndarray:
    """Cumulative Arias intensity π/(2g) ∫₀^t a² dt [m/s] at every sample (trapezoidal)."""
    a2 = np.asarray(acc, float) ** 2
    return np.pi / (2.0 * G) * np.concatenate([[0.0], np.cumsum(0.5 * (a2[1:] + a2[:-1]) * dt)])


def significant_duration(
    acc: np.ndarray, dt: float, start: float = 0.05, end: float = 0.95
) -> float | None:
    """Time [s] between ``start`` and ``end`` fractions of the final Arias intensity, on the
    cumulative curve interpolated linearly; None for a record without motion."""
    return _curve_duration(arias_curve(acc, dt), dt, start, end)


def _curve_duration(curve: np.ndarray, dt: float, start: float, end: float) -> float | None:
    """:func:`significant_duration` from the cumulative Arias curve ``curve`` [m/s]."""
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
    curve = arias_curve(a, dt)
    return {
        "pga": float(np.max(absolute)) / G if len(a) else 0.0,
        "pgv": float(np.max(np.abs(vel))) if len(vel) else 0.0,
        "pgd": float(np.max(np.abs(disp))) if len(disp) else 0.0,
        "arias": float(curve[-1]) if len(a) else 0.0,
        "cav": float(np.sum(0.5 * (absolute[1:] + absolute[:-1])) * dt),
        "d5_95": _curve_duration(curve, dt, 0.05, 0.95),
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

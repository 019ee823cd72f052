"""The seeded synthetic support record (``excitation.kind = "synthetic"``).

Seeded white noise through a Kanai–Tajimi filter under a Jennings-type envelope, one component
per direction (and per table with ``incoherence`` > 0), scaled to its PGA, then the
generator's own baseline correction (:func:`baseline_corrected`: zero-phase high-pass, double
integration, taper). Tables k are delayed by k·``lag`` (the wave passage helpers of
:mod:`deckpound.models.excitation`). Called by :func:`deckpound.models.excitation.support_motion`.
"""

from __future__ import annotations

import functools

import numpy as np

from deckpound.models.scene import Scene
from deckpound.models.scene_excitation import Excitation

from .errors import SceneError
from .motion import (
    G,
    SupportMotion,
    check_lag,
    make_provenance,
    shift_record,
    synthetic_samples,
    table_positions,
)
from .record_motion import highpass_padded

# -- signal processing ---------------------------------------------------------------------


def _fft_size(n: int) -> int:
    """The FFT length of an n-sample signal: the power of two of at least 2n (no wrap-around)."""
    return 1 << int(np.ceil(np.log2(2 * n)))


@functools.lru_cache(maxsize=4)
def _derivative_factor(nfft: int, dt: float) -> np.ndarray:
    """iω [rad/s] at the ``nfft``-point real FFT's frequencies for the step ``dt`` [s]
    (read-only; one per record length and step)."""
    w = 2.0 * np.pi * np.fft.rfftfreq(nfft, dt)
    factor = 1j * w
    factor.flags.writeable = False
    return factor


def _spectral_derivative(x: np.ndarray, dt: float) -> np.ndarray:
    """d/dt of a signal (or of each row of an array of signals) that starts and ends at
    rest, by FFT on a zero-padded copy: x' = IFFT(iω · FFT(x))."""
    n = x.shape[-1]
    nfft = _fft_size(n)
    X = np.fft.rfft(x, nfft)
    return np.fft.irfft(_derivative_factor(nfft, dt) * X, nfft)[..., :n]


@functools.lru_cache(maxsize=4)
def _taper(n: int, frac: float = 0.05) -> np.ndarray:
    """Tukey-type cosine taper rising over the first and falling over the last frac·n samples
    (read-only; one per record length)."""
    w = np.ones(n)
    m = max(2, int(frac * n))
    ramp = 0.5 * (1.0 - np.cos(np.pi * np.arange(m) / m))
    w[:m] = ramp
    w[-m:] = ramp[::-1]
    w.flags.writeable = False
    return w


def _trapezoid_integral(x: np.ndarray, dt: float) -> np.ndarray:
    """∫ x dt from the first sample, by the trapezoidal rule along the last axis:
    X_0 = 0, X_k = Σ_{j<k} 0.5·(x_j + x_{j+1})·dt."""
    out = np.empty(x.shape)
    out[..., 0] = 0.0
    steps = x[..., 1:] + x[..., :-1]
    steps *= 0.5
    steps *= dt
    np.cumsum(steps, axis=-1, out=out[..., 1:])
    return out


def baseline_corrected(acc: np.ndarray, dt: float, highpass: float) -> tuple[np.ndarray, ...]:
    """Displacement, velocity and acceleration from the synthetic generator's raw signal
    ``acc`` (n,), or from each row of ``acc`` (m, n) (every row gives the bits it gives alone).

    Part of the generator (users' records are processed only as their scene's
    ``processing`` says, in :mod:`deckpound.models.record_motion`).

    Zero-phase 4th-order Butterworth high-pass at ``highpass`` Hz, double integration
    (trapezoidal), a cosine taper on the displacement, and velocity and acceleration
    re-derived spectrally from the tapered displacement. The three are then consistent and
    the record starts and ends at rest (final displacement and velocity exactly zero).
    """
    pad = np.shape(acc)[-1]
    # integrated over the padded signal from its start, pre-event filter transient included,
    # then cut; the running sums stop at the record's end (the trailing pad is not needed)
    a = highpass_padded(acc, dt, highpass, "the record")[..., : 2 * pad]
    v = _trapezoid_integral(a, dt)
    d = _trapezoid_integral(v, dt)[..., pad:]
    # the chord of each row, one linspace per row (as one signal alone gets it)
    chord = np.array([np.linspace(row[0], row[-1], pad) for row in d.reshape(-1, pad)])
    d -= chord.reshape(d.shape)
    d *= _taper(pad)
    v = _spectral_derivative(d, dt)
    a = _spectral_derivative(v, dt)
    return d, v, a


def _envelope(t: np.ndarray, duration: float) -> np.ndarray:
    """Jennings-type envelope: quadratic rise, strong phase, exponential decay to ~3 %."""
    t1, t2 = 0.08 * duration, 0.35 * duration
    c = np.log(1.0 / 0.03) / (duration - t2)
    return np.where(t < t1, (t / t1) ** 2, np.where(t <= t2, 1.0, np.exp(-c * (t - t2))))


@functools.lru_cache(maxsize=4)
def _sampled_envelope(n: int, dt: float, duration: float) -> np.ndarray:
    """:func:`_envelope` at t = k·dt, k = 0..n − 1 (read-only; one per record)."""
    envelope = _envelope(np.arange(n) * dt, duration)
    envelope.flags.writeable = False
    return envelope


@functools.lru_cache(maxsize=4)
def _kanai_tajimi_response(nfft: int, dt: float, fg: float, zg: float) -> np.ndarray:
    """H(ω) = (ω_g² + 2iζ_gω_gω) / (ω_g² − ω² + 2iζ_gω_gω), ω_g = 2π·fg, at the ``nfft``-point
    real FFT's frequencies (read-only; one per record length, step and ground)."""
    w = 2.0 * np.pi * np.fft.rfftfreq(nfft, dt)
    wg = 2.0 * np.pi * fg
    H = (wg**2 + 2j * zg * wg * w) / (wg**2 - w**2 + 2j * zg * wg * w)
    H.flags.writeable = False
    return H


def _kanai_tajimi(noise: np.ndarray, dt: float, fg: float, zg: float) -> np.ndarray:
    """Filter white noise (n,) or rows of white noise (m, n) through the Kanai-Tajimi ground
    filter (frequency domain)."""
    n = noise.shape[-1]
    nfft = _fft_size(n)
    H = _kanai_tajimi_response(nfft, dt, fg, zg)
    return np.fft.irfft(H * np.fft.rfft(noise, nfft), nfft)[..., :n]


def mixed_noise(exc: Excitation, key: list[int], common: np.ndarray) -> np.ndarray:
    """White noise √(1 − g)·common + √g·w, g = ``incoherence``, w drawn from the generator
    seeded with ``key``: ``common`` is shared by the components of one direction, w makes
    them partly independent. With g = 0 and no zero sample in ``common`` this is ``common``
    itself, bit for bit (1·c + 0·w = c for c ≠ 0), so w is not drawn."""
    g = exc.incoherence
    if g == 0.0 and common.all():
        return common
    noise = np.random.default_rng(key).standard_normal(len(common))
    return np.sqrt(1.0 - g) * common + np.sqrt(g) * noise


def synthetic_components(
    exc: Excitation, pgas: list[float], noise: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.float64]]:
    """Earthquake-like components from the rows of white noise ``noise`` (m, n), row i scaled
    so that max|a| = pgas[i] [g] exactly.

    Returns d, v, a (m, n) in m, m/s, m/s² and each row's peak before scaling; a row without
    a finite, positive peak is left unscaled (see :func:`check_peak`).
    """
    raw = _kanai_tajimi(noise, exc.dt, exc.dominant_frequency, exc.ground_damping)
    raw *= _sampled_envelope(noise.shape[-1], exc.dt, exc.duration)
    d, v, a = baseline_corrected(raw, exc.dt, exc.highpass)
    peaks = list(np.max(np.abs(a), axis=-1))
    scale = np.array([pga * G / peak if _usable(peak) else 1.0 for pga, peak in zip(pgas, peaks)])[
        :, None
    ]
    return d * scale, v * scale, a * scale, peaks


def _usable(peak: np.float64) -> bool:
    return bool(np.isfinite(peak) and peak > 0.0)


def check_peak(exc: Excitation, peak: np.float64) -> None:
    """Refuse a generated component whose peak acceleration before scaling is not finite and
    positive (no scaling can give it its PGA)."""
    if not _usable(peak):
        raise SceneError(
            "excitation.dominant_frequency",
            f"gives no usable record with highpass = {exc.highpass} Hz and dt = "
            f"{exc.dt} s (peak acceleration {peak}), got {exc.dominant_frequency} Hz",
        )


def synthetic_motion(scene: Scene) -> SupportMotion:
    """The seeded synthetic biaxial multi-support record of the scene.

    Transverse (y) PGA = excitation.pga, longitudinal (x) = longitudinal_ratio · pga. Tables are
    identical unless ``incoherence`` > 0 (partly independent noise) or ``lag`` > 0 (table k is
    delayed by k·lag). The actuators follow the x motion of the nearest table.
    """
    exc = scene.excitation
    n = synthetic_samples(exc)
    # the common noise of x, then of y: one draw of both is the stream of two draws
    drawn = np.random.default_rng(exc.seed).standard_normal((2, n))
    common = {"x": drawn[0], "y": drawn[1]}
    pgas = {"x": exc.pga * exc.longitudinal_ratio, "y": exc.pga}
    t = np.arange(n) * exc.dt
    # every component, generated together (rows): one per moving direction, then with
    # incoherence one per table and moving direction, each from its own seeded noise
    moving = [axis for axis in ("x", "y") if pgas[axis] > 0]
    rows = [(axis, None) for axis in moving]
    tables = table_positions(scene)
    if exc.incoherence > 0:
        rows += [(axis, k) for k in range(max(tables, default=-1) + 1) for axis in moving]
    mixed = [
        mixed_noise(exc, [exc.seed, ord(axis)] + ([] if k is None else [k + 1]), common[axis])
        for axis, k in rows
    ]
    together = len(mixed) == 2 and mixed[0] is common["x"] and mixed[1] is common["y"]
    noise = drawn if together else np.array(mixed)
    d_rows, v_rows, a_rows, peaks = synthetic_components(
        exc, [pgas[axis] for axis, _ in rows], noise
    )
    component = {row: (d_rows[i], v_rows[i], a_rows[i]) for i, row in enumerate(rows)}
    for axis in ("x", "y"):
        if pgas[axis] <= 0:
            component[(axis, None)] = (np.zeros(n), np.zeros(n), np.zeros(n))
    # refusals in the order of the generation one component at a time: the components of
    # the directions, the lag, then the tables' own components
    for peak in peaks[: len(moving)]:
        check_peak(exc, peak)
    lag_steps = check_lag(scene, exc.dt, n)
    for peak in peaks[len(moving) :]:
        check_peak(exc, peak)
    disp: dict[str, np.ndarray] = {}
    vel: dict[str, np.ndarray] = {}
    acc: dict[str, np.ndarray] = {}
    for k, bent in zip(tables, scene.bents):
        for axis in ("x", "y"):
            d, v, a = component.get((axis, k), component[(axis, None)])
            disp[f"{bent.name}_{axis}"] = shift_record(d, k * lag_steps)
            vel[f"{bent.name}_{axis}"] = shift_record(v, k * lag_steps)
            acc[f"{bent.name}_{axis}"] = shift_record(a, k * lag_steps)
    # the actuators follow their nearest table: the same arrays, as the tables without lag
    # share one component (a motion's arrays are never changed in place)
    first, last = scene.bents[0].name, scene.bents[-1].name
    disp["seat1_x"], vel["seat1_x"] = disp[f"{first}_x"], vel[f"{first}_x"]
    disp["seat2_x"], vel["seat2_x"] = disp[f"{last}_x"], vel[f"{last}_x"]
    acc["seat1_x"], acc["seat2_x"] = acc[f"{first}_x"], acc[f"{last}_x"]
    for arrays in (disp, vel, acc):
        for x in arrays.values():
            x.flags.writeable = False
    prov = make_provenance(
        exc,
        files={},
        header={},
        npts={"x": n, "y": n},
        dt_record=exc.dt,
        dt=exc.dt,
        duration=float(t[-1]),
        targets=pgas,
        factors={},
        notes=[],
        seed=exc.seed,
        processing=f"generator (Kanai-Tajimi {exc.dominant_frequency:g} Hz, envelope; built-in "
        f"baseline correction: highpass {exc.highpass:g} Hz, taper)",
    )
    return SupportMotion(t=t, disp=disp, vel=vel, acc_exact=acc, provenance=prov)

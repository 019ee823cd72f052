"""The seeded synthetic support record (``excitation.kind = "synthetic"``).

Seeded white noise through a Kanai–Tajimi filter under a Jennings-type envelope, one component
per direction (and per table with ``incoherence`` > 0), scaled to its PGA, then the
generator's own baseline correction (:func:`baseline_corrected`: zero-phase high-pass, double
integration, taper). Tables k are delayed by k·``lag`` (the wave passage helpers of
:mod:`deckpound.models.excitation`). Called by :func:`deckpound.models.excitation.support_motion`.
"""

from __future__ import annotations

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
)
from .record_motion import highpass_padded

# -- signal processing ---------------------------------------------------------------------


def _spectral_derivative(x: np.ndarray, dt: float) -> np.ndarray:
    """d/dt of a signal that starts and ends at rest, by FFT on a zero-padded copy."""
    n = len(x)
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    X = np.fft.rfft(x, nfft)
    w = 2.0 * np.pi * np.fft.rfftfreq(nfft, dt)
    return np.fft.irfft(1j * w * X, nfft)[:n]


def _taper(n: int, frac: float = 0.05) -> np.ndarray:
    """Tukey-type cosine taper rising over the first and falling over the last frac·n samples."""
    w = np.ones(n)
    m = max(2, int(frac * n))
    ramp = 0.5 * (1.0 - np.cos(np.pi * np.arange(m) / m))
    w[:m] = ramp
    w[-m:] = ramp[::-1]
    return w


def baseline_corrected(acc: np.ndarray, dt: float, highpass: float) -> tuple[np.ndarray, ...]:
    """Displacement, velocity and acceleration from the synthetic generator's raw signal.

    Part of the generator (users' records are processed only as their scene's
    ``processing`` says, in :mod:`deckpound.models.record_motion`).

    Zero-phase 4th-order Butterworth high-pass at ``highpass`` Hz, double integration
    (trapezoidal), a cosine taper on the displacement, and velocity and acceleration
    re-derived spectrally from the tapered displacement. The three are then consistent and
    the record starts and ends at rest (final displacement and velocity exactly zero).
    """
    pad = len(acc)
    # integrated over the padded signal, pre-event filter transient included, then cut
    a = highpass_padded(acc, dt, highpass, "the record")
    v = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * dt)])
    d = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)])
    d = d[pad : 2 * pad]
    d = (d - np.linspace(d[0], d[-1], len(d))) * _taper(len(d))
    v = _spectral_derivative(d, dt)
    a = _spectral_derivative(v, dt)
    return d, v, a


def _envelope(t: np.ndarray, duration: float) -> np.ndarray:
    """Jennings-type envelope: quadratic rise, strong phase, exponential decay to ~3 %."""
    t1, t2 = 0.08 * duration, 0.35 * duration
    c = np.log(1.0 / 0.03) / (duration - t2)
    return np.where(t < t1, (t / t1) ** 2, np.where(t <= t2, 1.0, np.exp(-c * (t - t2))))


def _kanai_tajimi(noise: np.ndarray, dt: float, fg: float, zg: float) -> np.ndarray:
    """Filter white noise through the Kanai-Tajimi ground filter (frequency domain)."""
    n = len(noise)
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    w = 2.0 * np.pi * np.fft.rfftfreq(nfft, dt)
    wg = 2.0 * np.pi * fg
    H = (wg**2 + 2j * zg * wg * w) / (wg**2 - w**2 + 2j * zg * wg * w)
    return np.fft.irfft(H * np.fft.rfft(noise, nfft), nfft)[:n]


def synthetic_component(
    exc: Excitation, pga: float, rng: np.random.Generator, common: np.ndarray | None = None
) -> tuple[np.ndarray, ...]:
    """One earthquake-like component scaled so that max|a| = pga [g] exactly.

    Returns (t, d, v, a) in s, m, m/s, m/s². ``common`` (a white-noise sample) is mixed in
    with weight √(1 − incoherence) to make correlated components at several tables.
    """
    n = round(exc.duration / exc.dt) + 1
    t = np.arange(n) * exc.dt
    noise = rng.standard_normal(n)
    if common is not None:
        g = exc.incoherence
        noise = np.sqrt(1.0 - g) * common + np.sqrt(g) * noise
    raw = _kanai_tajimi(noise, exc.dt, exc.dominant_frequency, exc.ground_damping)
    raw *= _envelope(t, exc.duration)
    d, v, a = baseline_corrected(raw, exc.dt, exc.highpass)
    peak = np.max(np.abs(a))
    if not (np.isfinite(peak) and peak > 0.0):
        raise SceneError(
            "excitation.dominant_frequency",
            f"gives no usable record with highpass = {exc.highpass} Hz and dt = "
            f"{exc.dt} s (peak acceleration {peak}), got {exc.dominant_frequency} Hz",
        )
    s = pga * G / peak
    return t, d * s, v * s, a * s


def synthetic_motion(scene: Scene) -> SupportMotion:
    """The seeded synthetic biaxial multi-support record of the scene.

    Transverse (y) PGA = excitation.pga, longitudinal (x) = longitudinal_ratio · pga. Tables are
    identical unless ``incoherence`` > 0 (partly independent noise) or ``lag`` > 0 (table k is
    delayed by k·lag). The actuators follow the x motion of the nearest table.
    """
    exc = scene.excitation
    n = synthetic_samples(exc)
    rng = np.random.default_rng(exc.seed)
    common = {"x": rng.standard_normal(n), "y": rng.standard_normal(n)}
    pgas = {"x": exc.pga * exc.longitudinal_ratio, "y": exc.pga}
    disp: dict[str, np.ndarray] = {}
    vel: dict[str, np.ndarray] = {}
    acc: dict[str, np.ndarray] = {}
    t = np.arange(n) * exc.dt
    base: dict[str, tuple] = {}
    for axis in ("x", "y"):
        sub = np.random.default_rng([exc.seed, ord(axis)])
        base[axis] = (
            synthetic_component(exc, pgas[axis], sub, common[axis])
            if pgas[axis] > 0
            else (t, np.zeros(n), np.zeros(n), np.zeros(n))
        )
    lag_steps = check_lag(scene, exc.dt, n)
    for k, bent in enumerate(scene.bents):
        for axis in ("x", "y"):
            if exc.incoherence > 0 and pgas[axis] > 0:
                sub = np.random.default_rng([exc.seed, ord(axis), k + 1])
                _, d, v, a = synthetic_component(exc, pgas[axis], sub, common[axis])
            else:
                _, d, v, a = base[axis]
            disp[f"{bent.name}_{axis}"] = shift_record(d, k * lag_steps)
            vel[f"{bent.name}_{axis}"] = shift_record(v, k * lag_steps)
            acc[f"{bent.name}_{axis}"] = shift_record(a, k * lag_steps)
    first, last = scene.bents[0].name, scene.bents[-1].name
    disp["seat1_x"], vel["seat1_x"] = disp[f"{first}_x"].copy(), vel[f"{first}_x"].copy()
    disp["seat2_x"], vel["seat2_x"] = disp[f"{last}_x"].copy(), vel[f"{last}_x"].copy()
    acc["seat1_x"], acc["seat2_x"] = acc[f"{first}_x"].copy(), acc[f"{last}_x"].copy()
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

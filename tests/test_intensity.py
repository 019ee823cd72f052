"""Intensity measures (issue 30, item 2): closed forms, the exact oscillator recurrence, and
agreement with independent implementations (eqsig, pyrotd; test-only dependencies)."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest
from _record_helpers import record_scene, write_text

from deckpound.models import intensity as im
from deckpound.models.excitation import support_motion
from deckpound.models.mechanics import natural_modes
from deckpound.models.motion import intensity_period
from deckpound.models.record_motion import integrate

G = 9.80665
ZETA = 0.05


def reference_displacements(a: np.ndarray, dt: float, period: float, zeta: float) -> np.ndarray:
    """The recurrence sample by sample, its matrices from the exponential of the augmented
    first-order-hold matrix [[F, G, 0], [0, 0, 1/Δt], [0, 0, 0]] (scipy.linalg.expm): an
    independent derivation of Nigam & Jennings' coefficients."""
    from scipy.linalg import expm

    w = 2 * np.pi / period
    aug = np.zeros((4, 4))
    aug[:2, :2] = [[0.0, 1.0], [-w * w, -2 * zeta * w]]
    aug[:2, 2] = [0.0, -1.0]
    aug[2, 3] = 1.0 / dt
    e = expm(aug * dt)
    phi, g1, g2 = e[:2, :2], e[:2, 2], e[:2, 3]
    z = np.zeros(2)
    u = [0.0]
    for n in range(len(a) - 1):
        z = phi @ z + (g1 - g2) * a[n] + g2 * a[n + 1]
        u.append(z[0])
    return np.array(u)


@pytest.mark.parametrize("n", [2, 3, 64, 65, 66, 129, 700])
def test_blocked_recurrence_equals_sample_by_sample(n):
    """Across block boundaries and for every period, the blocked evaluation is the recurrence
    to round-off."""
    a = np.random.default_rng(n).standard_normal(n)
    periods = [0.02, 0.5, 4.0]
    u = im.oscillator_displacements(a, 0.01, periods, ZETA)
    for k, T in enumerate(periods):
        ref = reference_displacements(a, 0.01, T, ZETA)
        assert np.max(np.abs(u[k] - ref)) <= 1e-12 * max(1.0, np.max(np.abs(ref)))


def sine_scene(tmp_path, amp_g=0.3, freq=2.0, duration=10.0, dt=0.0025, *sets):
    t = np.arange(round(duration / dt) + 1) * dt
    a = amp_g * np.sin(2 * np.pi * freq * t)
    fx = write_text(tmp_path / "sine_x.txt", t, a)
    fy = write_text(tmp_path / "sine_y.txt", t, 0.5 * a)
    return record_scene("text", fx, fy, None, "excitation.scaling=none", *sets)


def test_pure_sine_closed_forms(tmp_path):
    """a = A sin Ωt over whole cycles (peaks on the grid), from rest: PGA = A, PGV = 2A/Ω (v = A(1 − cos Ωt)/Ω),
    I_A = π/(2g) · A² D/2, CAV = 2AD/π; the y component at half the amplitude: half the
    peaks and CAV, a quarter of the Arias intensity."""
    amp, freq, duration = 0.3, 2.0, 10.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the drift note of a sine's displacement
        motion = support_motion(sine_scene(tmp_path, amp, freq, duration))
    ims = motion.provenance["intensity"]
    A, w = amp * G, 2 * np.pi * freq
    x, y = ims["x"], ims["y"]
    assert x["pga"] == pytest.approx(amp, rel=1e-12)
    assert x["pgv"] == pytest.approx(2 * A / w, rel=2e-4)
    assert x["arias"] == pytest.approx(np.pi / (2 * G) * A * A * duration / 2, rel=1e-9)
    assert x["cav"] == pytest.approx(2 * A * duration / np.pi, rel=2e-4)
    assert y["pga"] == pytest.approx(0.5 * amp, rel=1e-12)
    assert y["arias"] == pytest.approx(0.25 * x["arias"], rel=1e-12)
    assert y["cav"] == pytest.approx(0.5 * x["cav"], rel=1e-12)
    assert ims["units"]["arias"] == "m/s" and ims["units"]["sa"] == "g"


def test_sdof_at_resonance_reaches_the_steady_amplitude():
    """A sine at the oscillator's own frequency: the steady amplitude u = A/(2ζω²), so
    Sa = ω² u = A/(2ζ) once the transient e^{−ζωt} has died (e^{−25} after 40 s here)."""
    period, dt, A = 0.5, 0.002, 2.0
    t = np.arange(round(40.0 / dt) + 1) * dt
    a = A * np.sin(2 * np.pi * t / period)
    sa = im.spectral_acceleration(a, dt, [period], ZETA)[0]
    assert sa == pytest.approx(A / (2 * ZETA), rel=2e-4)
    # off resonance (frequency ratio r = 0.1), once the transient has died: the steady
    # amplitude A/ω² · 1/√((1 − r²)² + (2ζr)²)
    stiff = period / 10
    u = im.oscillator_displacements(a, dt, [stiff], ZETA)[0]
    steady = (2 * np.pi / stiff) ** 2 * np.max(np.abs(u[t > 20.0]))
    r = 0.1
    assert steady == pytest.approx(A / math.sqrt((1 - r * r) ** 2 + (2 * ZETA * r) ** 2), 1e-3)


def test_constant_acceleration_pulse():
    """a = A on [0, t_p], then 0 (a linear drop over one step): the oscillator's first peak
    is A/ω² (1 + e^{−ζπ/√(1−ζ²)}) at t = π/ω_d (on the grid here); ∫|a| and the velocity
    are A (t_p + Δt/2) exactly (the drop's triangle); Arias and D5-95 follow the trapezoidal
    rule on the samples: π/(2g) A² (t_p + Δt/2) and 0.9 (t_p + Δt/2)."""
    dt, A, t_p = 0.001, 3.0, 1.0
    damped_period = 0.4  # first peak at 0.2 s = 200 steps
    period = damped_period * math.sqrt(1 - ZETA**2)
    a = np.zeros(3001)
    a[: round(t_p / dt) + 1] = A
    v, d = integrate(a, dt)
    out = im.component_measures(a, v, d, dt, period)
    peak = A * (1 + math.exp(-ZETA * math.pi / math.sqrt(1 - ZETA**2)))
    assert out["sa"] * G == pytest.approx(peak, rel=1e-9)
    area = A * (t_p + dt / 2)
    assert out["cav"] == pytest.approx(area, rel=1e-12)
    assert out["pgv"] == pytest.approx(area, rel=1e-12)
    assert out["arias"] == pytest.approx(np.pi / (2 * G) * A * A * (t_p + dt / 2), rel=1e-12)
    assert out["d5_95"] == pytest.approx(0.9 * (t_p + dt / 2), rel=1e-9)
    assert out["pga"] == pytest.approx(A / G)


def test_rotd_pruning_equals_every_sample():
    """RotD from the candidate samples alone equals the brute-force maximum over every
    sample and angle; RotD100 is at least each component's Sa (0° and 90° are rotations)."""
    rng = np.random.default_rng(3)
    a = rng.standard_normal((2, 3000))
    u = (
        im.oscillator_displacements(a[0], 0.01, [0.7])[0],
        im.oscillator_displacements(a[1], 0.01, [0.7])[0],
    )
    th = np.deg2rad(np.arange(180.0))
    brute = np.max(np.abs(np.cos(th)[:, None] * u[0] + np.sin(th)[:, None] * u[1]), axis=1)
    w2 = (2 * np.pi / 0.7) ** 2
    r50, r100 = im.rotd(u[0], u[1], 0.7)
    assert r50 == w2 * np.percentile(brute, 50)
    assert r100 == w2 * np.max(brute)
    assert r100 >= w2 * max(np.max(np.abs(u[0])), np.max(np.abs(u[1])))


def brute_rotated_peaks(u_x: np.ndarray, u_y: np.ndarray) -> np.ndarray:
    """max_t |u_x cos θ + u_y sin θ| over every sample at θ = 0°..179° (Boore 2010)."""
    th = np.deg2rad(np.arange(180.0))
    return np.max(np.abs(np.cos(th)[:, None] * u_x + np.sin(th)[:, None] * u_y), axis=1)


@pytest.mark.parametrize(
    "shape", ["isotropic", "polarised", "one-axis", "collinear", "ties", "orbit", "tiny"]
)
def test_rotd_candidates_hold_every_angles_peak(shape):
    """The candidate search keeps, for every angle, a sample with the peak over all samples:
    the 180 peaks from the candidates equal the brute force to the last bit, for motions
    polarised along one direction (where a radius bound alone keeps most samples), at rest
    in one axis, collinear, with tied values, an elliptic orbit and at tiny amplitude."""
    rng = np.random.default_rng(len(shape))
    for n in (65, 500, 4001):
        u_x, u_y = rng.standard_normal((2, n))
        if shape == "polarised":
            u_y = 0.3 * u_x + 0.01 * u_y
        elif shape == "one-axis":
            u_x, u_y = (np.zeros(n), u_y) if n % 2 else (u_x, -0.0 * u_y)
        elif shape == "collinear":
            u_y = -2.0 * u_x
        elif shape == "ties":
            u_x, u_y = np.round(u_x, 1), np.round(u_y, 1)
        elif shape == "orbit":
            t = np.linspace(0.0, 30.0, n)
            u_x, u_y = np.sin(t) * np.exp(-0.05 * t), 0.2 * np.cos(1.01 * t)
        elif shape == "tiny":
            u_x, u_y = 1e-12 * u_x, 1e-12 * u_y
        c_x, c_y = im._rotd_candidates(u_x, u_y)
        assert len(c_x) < n
        np.testing.assert_array_equal(im._rotated_peaks(c_x, c_y), brute_rotated_peaks(u_x, u_y))


def test_block_operators_follow_period_damping_and_step():
    """The remembered recurrence matrices are those of the oscillator asked for: another
    period, damping or step gives the displacements of a fresh sample-by-sample
    recurrence, not those of an oscillator computed before; several oscillators at once
    (not remembered) give each one's displacements."""
    a = np.random.default_rng(5).standard_normal(300)
    cases = ((0.5, 0.05, 0.01), (0.8, 0.05, 0.01), (0.8, 0.02, 0.01), (0.8, 0.02, 0.005))
    for period, zeta, dt in (*cases, cases[0]):
        u = im.oscillator_displacements(a, dt, [period], zeta)[0]
        ref = reference_displacements(a, dt, period, zeta)
        assert np.max(np.abs(u - ref)) <= 1e-12 * np.max(np.abs(ref))
    several = im.oscillator_displacements(a, 0.01, [0.5, 0.8], 0.02)
    for k, period in enumerate((0.5, 0.8)):
        np.testing.assert_array_equal(
            several[k], im.oscillator_displacements(a, 0.01, [period], 0.02)[0]
        )


def test_t1_is_recomputed_for_another_structure(bench_scene):
    """The remembered T1 belongs to its structure: a heavier deck, a softer bent or a softer
    seat give their own (longer) period, equal to that of the modes; another record of
    the same structure (a sweep's cases) gives the same period; a given im_period wins."""
    from deckpound.models.scene_io import modified

    def t1(scene):
        return float(np.max(natural_modes(scene).periods))

    base = intensity_period(bench_scene)
    assert base == t1(bench_scene)
    heavier = modified(bench_scene, f"deck.mass={2 * bench_scene.deck.mass}")
    assert intensity_period(heavier) == t1(heavier) > base
    bent = bench_scene.bents[0]
    softer_bent = dataclasses.replace(
        bent, y=dataclasses.replace(bent.y, stiffness=0.5 * bent.y.stiffness)
    )
    softer = bench_scene.replace(bents=(softer_bent, *bench_scene.bents[1:]))
    assert intensity_period(softer) == t1(softer) != base
    seat = bench_scene.seats[0]
    soft_seat = dataclasses.replace(seat, kx=1e-3 * seat.kx)  # its sliding mode becomes T1
    loose = bench_scene.replace(seats=(soft_seat, bench_scene.seats[1]))
    assert intensity_period(loose) == t1(loose) != base
    reseeded = bench_scene.replace(
        excitation=bench_scene.excitation.__class__(seed=bench_scene.excitation.seed + 1)
    )
    assert intensity_period(reseeded) == base
    assert intensity_period(bench_scene) == base  # still known after the others
    given = bench_scene.replace(excitation=bench_scene.excitation.__class__(im_period=0.9))
    assert intensity_period(given) == 0.9


@pytest.fixture(scope="module")
def bench_motion():
    from deckpound.models.scene_io import load_scene

    scene = load_scene("saiidi-4span")
    return scene, support_motion(scene)


def test_default_period_is_t1_and_kept_in_the_provenance(bench_motion):
    scene, motion = bench_motion
    ims = motion.provenance["intensity"]
    assert ims["period"] == pytest.approx(float(np.max(natural_modes(scene).periods)))
    assert ims["period"] == intensity_period(scene)
    assert ims["sa_geomean"] == pytest.approx(math.sqrt(ims["x"]["sa"] * ims["y"]["sa"]))
    assert ims["rotd50"] <= ims["rotd100"]
    other = support_motion(scene.replace(excitation=scene.excitation.__class__(im_period=1.5)))
    assert other.provenance["intensity"]["period"] == 1.5


def test_agreement_with_eqsig_and_pyrotd(bench_motion):
    """The benchmark's synthetic pair against eqsig (Nigam-Jennings spectra, Arias, CAV,
    significant duration) and pyrotd (frequency-domain oscillators, RotD): within 0.5 %."""
    import eqsig
    import pyrotd

    _, motion = bench_motion
    ims = motion.provenance["intensity"]
    dt = float(motion.t[1] - motion.t[0])
    acc = {"x": motion.acc("bent1_x"), "y": motion.acc("bent1_y")}
    period = ims["period"]
    periods = np.array([0.1, 0.3, period, 1.0, 2.5])
    for axis, a in acc.items():
        ours = im.spectral_acceleration(a, dt, periods) / G
        theirs = eqsig.sdof.pseudo_response_spectra(a, dt, periods, ZETA)[2] / G
        np.testing.assert_allclose(ours, theirs, rtol=5e-3)
        psa = pyrotd.calc_spec_accels(dt, a / G, [1 / period], ZETA)
        assert ims[axis]["sa"] == pytest.approx(float(psa[0][1]), rel=5e-3)
        sig = eqsig.AccSignal(a, dt)
        # eqsig's Arias uses g = 9.81 m/s²
        assert ims[axis]["arias"] == pytest.approx(
            eqsig.im.calc_arias_intensity(sig)[-1] * 9.81 / G, rel=5e-3
        )
        assert ims[axis]["cav"] == pytest.approx(eqsig.im.calc_cav(sig)[-1], rel=5e-3)
        assert ims[axis]["d5_95"] == pytest.approx(eqsig.im.calc_sig_dur_vals(a, dt), rel=5e-3)
    rot = pyrotd.calc_rotated_spec_accels(
        dt, acc["x"] / G, acc["y"] / G, [1 / period], ZETA, percentiles=[50, 100]
    )
    assert ims["rotd50"] == pytest.approx(float(rot[0][2]), rel=5e-3)
    assert ims["rotd100"] == pytest.approx(float(rot[1][2]), rel=5e-3)


def test_a_record_pair_carries_its_intensity(tmp_path):
    """A file-based pair: the measures of the applied (scaled) motion, in the provenance that
    lands in Result.meta['record']."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        motion = support_motion(sine_scene(tmp_path, 0.3, 2.0, 10.0))
    ims = motion.provenance["intensity"]
    assert ims["where"] == "table bent1"
    assert ims["x"]["pga"] == pytest.approx(motion.provenance["applied_pga"]["x"])
    assert ims["y"]["sa"] == pytest.approx(0.5 * ims["x"]["sa"], rel=1e-12)

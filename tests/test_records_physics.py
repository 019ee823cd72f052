"""Records: integration, processing, scaling and similitude time scaling measured (issue 13).

Oracles: closed-form integrals of a sine; exact linearity of scaling; the similitude laws
(t × s, a × 1, v × s, d × s²); the frequency response of a zero-phase Butterworth filter.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _record_helpers import quake, record_scene, write_at2, write_text
from hypothesis import given, settings
from hypothesis import strategies as st

from deckpound.models.excitation import support_motion
from deckpound.models.motion import G, RecordWarning
from deckpound.models.record_motion import DRIFT_FRACTION, integrate, remove_baseline


def _motion(scene):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = support_motion(scene)
    return m, [str(w.message) for w in caught if issubclass(w.category, RecordWarning)]


def _sine_errors(tmp_path, dt, amp=2.0, f=1.0, duration=4.0):
    """Errors of v and d from a = amp·sin(ωt) [m/s²] read from a text file, processing none."""
    w = 2 * np.pi * f
    t = np.arange(round(duration / dt) + 1) * dt
    p = write_text(tmp_path / f"sine_{dt}.txt", t, amp * np.sin(w * t))
    m, warned = _motion(
        record_scene("text", p, None, None, "excitation.scaling=none", "excitation.acc_unit=m/s^2")
    )
    v_exact = amp / w * (1 - np.cos(w * m.t))
    d_exact = amp / w * m.t - amp / w**2 * np.sin(w * m.t)
    return (
        np.max(np.abs(m.vel["bent1_x"] - v_exact)),
        np.max(np.abs(m.disp["bent1_x"] - d_exact)),
        warned,
    )


def test_integration_of_a_sine_is_second_order_and_within_the_trapezoid_bound(tmp_path):
    """Trapezoidal rule: the error of v is the end-point term dt²/12·(a'(t) − a'(0)), at most
    dt²·A·ω/6 (to O(dt⁴)); the displacement error accumulates it, ≤ T·dt²·A·ω/6; order 2."""
    amp, w, T, dt = 2.0, 2 * np.pi, 4.0, 0.01
    ev1, ed1, warned = _sine_errors(tmp_path, dt)
    ev2, ed2, _ = _sine_errors(tmp_path, dt / 2)
    bound = dt**2 * amp * w / 6 * (1 + (w * dt) ** 2)  # leading term + O(dt⁴) allowance
    assert ev1 <= bound and ed1 <= T * bound
    assert np.log2(ev1 / ev2) == pytest.approx(2.0, abs=0.05)
    assert np.log2(ed1 / ed2) == pytest.approx(2.0, abs=0.05)
    # a sine starting from rest drifts (d grows like A t/ω): stated, not refused, not filtered
    drift = [w for w in warned if "drifts" in w]
    assert len(drift) == 1 and "with processing = 'none' the displacement ends at" in drift[0]
    assert "the record drifts; consider processing = 'baseline' or 'highpass'" in drift[0]


def test_no_hidden_processing_records_are_integrated_as_given(tmp_path):
    """Issue 13: a 0.5 Hz high-pass was applied to AT2 input without notice."""
    ax, ay = quake(seed=1), quake(seed=2)
    px, py = write_at2(tmp_path / "x.at2", ax), write_at2(tmp_path / "y.at2", ay)
    m, warned = _motion(record_scene("at2", px, py, None, "excitation.scaling=none"))
    assert warned == []
    np.testing.assert_allclose(m.acc("bent1_x"), ax * G, rtol=1e-7, atol=1e-12)
    v, d = integrate(m.acc("bent1_y"), 0.01)
    np.testing.assert_array_equal(m.vel["bent1_y"], v)
    np.testing.assert_array_equal(m.disp["bent1_y"], d)
    assert (
        m.provenance["processing"] == "none (trapezoidal integration of the acceleration as given)"
    )


@pytest.mark.parametrize("target,ratio", [(0.075, 1.2), (0.5, 1.2), (1.0, 0.3), (2.0, 2.0)])
def test_scaling_to_pga_is_exact_per_direction(tmp_path, target, ratio):
    px = write_at2(tmp_path / "x.at2", quake(peak=0.31, seed=1))
    py = write_at2(tmp_path / "y.at2", quake(peak=0.17, seed=2))
    m, _ = _motion(
        record_scene(
            "at2",
            px,
            py,
            None,
            f"excitation.pga={target}",
            f"excitation.longitudinal_ratio={ratio}",
        )
    )
    for ch in m.channels:
        want = target * (ratio if ch.endswith("_x") else 1.0)
        assert np.max(np.abs(m.acc(ch))) / G == pytest.approx(want, rel=1e-12)
    assert m.provenance["applied_pga"] == {
        "x": pytest.approx(target * ratio, rel=1e-12),
        "y": pytest.approx(target, rel=1e-12),
    }
    assert m.provenance["scale_factor"]["y"] == pytest.approx(target / 0.17, rel=1e-6)


def test_scaling_by_factor_is_exactly_linear(tmp_path):
    px, py = write_at2(tmp_path / "x.at2", quake(seed=1)), write_at2(tmp_path / "y.at2", quake())
    base, _ = _motion(record_scene("at2", px, py, None, "excitation.scaling=none"))
    m, _ = _motion(
        record_scene("at2", px, py, None, "excitation.scaling=factor", "excitation.scale=2.5")
    )
    for ch in m.channels:  # equal to rounding: the factor multiplies a before integration
        for got, ref in ((m.disp[ch], base.disp[ch]), (m.vel[ch], base.vel[ch])):
            np.testing.assert_allclose(got, 2.5 * ref, rtol=1e-12, atol=1e-12 * np.max(np.abs(got)))
    assert m.provenance["scale_factor"] == {"x": 2.5, "y": 2.5}
    assert m.provenance["applied_pga"]["x"] == pytest.approx(2.5 * 0.3, rel=1e-7)


@settings(max_examples=25, deadline=None)
@given(
    amplitude=st.floats(1e-3, 4.0),
    pga=st.floats(0.01, 4.0),
    ratio=st.one_of(st.just(0.0), st.floats(0.01, 1.25)),
)
def test_motion_scaled_to_pga_does_not_depend_on_the_record_amplitude(
    tmp_path_factory, amplitude, pga, ratio
):
    """Unit-scaling invariance: a record × c gives the same motion once scaled to its PGA."""
    folder = tmp_path_factory.mktemp("inv")
    a = quake(300)
    ref = write_at2(folder / "ref.at2", a)
    big = write_at2(folder / "big.at2", a * amplitude)
    sets = (f"excitation.pga={pga!r}", f"excitation.longitudinal_ratio={ratio!r}")
    m1, _ = _motion(record_scene("at2", ref, ref, None, *sets))
    m2, _ = _motion(record_scene("at2", big, big, None, *sets))
    for ch in m1.channels:
        scale = max(np.max(np.abs(m1.disp[ch])), 1e-300)
        # values printed with 8 digits: rounding (5e-8) accumulates in the double integral
        assert np.max(np.abs(m1.disp[ch] - m2.disp[ch])) <= 1e-5 * scale
    assert m2.provenance["applied_pga"]["y"] == pytest.approx(pga, rel=1e-12)


def test_similitude_time_scale_maps_duration_and_peaks(tmp_path):
    """1/4 scale with equal accelerations: t × 0.5, a × 1, v × 0.5, d × 0.25."""
    px, py = write_at2(tmp_path / "x.at2", quake(seed=1)), write_at2(tmp_path / "y.at2", quake())
    proto, _ = _motion(record_scene("at2", px, py, None))
    model, _ = _motion(record_scene("at2", px, py, None, "excitation.time_scale=0.5"))
    assert model.duration == pytest.approx(0.5 * proto.duration, rel=1e-12)
    np.testing.assert_allclose(model.t, 0.5 * proto.t, rtol=1e-12)
    for ch in proto.channels:
        np.testing.assert_allclose(model.acc(ch), proto.acc(ch), rtol=1e-12, atol=0)
        np.testing.assert_allclose(model.vel[ch], 0.5 * proto.vel[ch], rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(model.disp[ch], 0.25 * proto.disp[ch], rtol=1e-12, atol=1e-15)
    assert model.provenance["dt"] == pytest.approx(0.005) and model.provenance["dt_record"] == 0.01
    assert model.provenance["time_scale"] == 0.5
    assert model.provenance["applied_pga"] == pytest.approx(proto.provenance["applied_pga"])


def test_baseline_processing_removes_a_polynomial_drift(tmp_path):
    """A record with a small offset and trend (0.5 % and 0.3 % of its peak) drifts when
    integrated as given; processing = baseline recovers the clean record's displacement."""
    n, dt = 2000, 0.01
    clean = quake(n, dt)
    s = np.arange(n) / n
    px = write_at2(tmp_path / "x.at2", clean + 0.0015 + 0.001 * s - 0.0008 * s**2)
    py = write_at2(tmp_path / "y.at2", clean)
    sets = ("excitation.scaling=none",)
    raw, warned_raw = _motion(record_scene("at2", px, py, None, *sets))
    fixed, warned = _motion(
        record_scene("at2", px, py, None, *sets, "excitation.processing=baseline")
    )
    d_true = raw.disp["bent1_y"]  # the clean component, integrated as given
    peak = np.max(np.abs(d_true))
    assert abs(raw.disp["bent1_x"][-1]) > DRIFT_FRACTION * np.max(np.abs(raw.disp["bent1_x"]))
    assert any("excitation.file_x" in w and "the record drifts" in w for w in warned_raw)
    assert np.max(np.abs(fixed.disp["bent1_x"] - d_true)) < 0.05 * peak
    assert not any("excitation.file_x" in w and "drifts" in w for w in warned)
    assert fixed.provenance["processing"].startswith("baseline (degree-2")
    # removing a baseline from a clean record changes it little
    np.testing.assert_allclose(remove_baseline(clean, dt), clean, atol=0.02 * np.abs(clean).max())


def test_highpass_processing_keeps_the_passband_and_removes_the_long_period(tmp_path):
    """Zero-phase 4th-order Butterworth at 0.5 Hz: |H(5 Hz)|² ≈ 1, |H(0.05 Hz)|² = 1/(1+10^8)."""
    dt, n = 0.01, 12000
    t = np.arange(n) * dt
    taper = np.sin(np.pi * t / t[-1]) ** 2
    a = taper * (0.2 * np.sin(2 * np.pi * 5.0 * t) + 0.1 * np.sin(2 * np.pi * 0.05 * t))
    p = write_text(tmp_path / "x.txt", t, a)
    m, _ = _motion(
        record_scene(
            "text",
            p,
            None,
            None,
            "excitation.scaling=none",
            "excitation.processing=highpass",
            "excitation.highpass=0.5",
        )
    )
    mid = slice(n // 3, 2 * n // 3)
    basis = np.column_stack(
        [taper[mid] * f(2 * np.pi * fr * t[mid]) for fr in (5.0, 0.05) for f in (np.sin, np.cos)]
    )
    c, *_ = np.linalg.lstsq(basis, m.acc("bent1_x")[mid] / G, rcond=None)
    assert np.hypot(c[0], c[1]) == pytest.approx(0.2, rel=1e-3)
    assert np.hypot(c[2], c[3]) < 1e-3 * 0.1
    assert m.provenance["processing"] == "highpass 0.5 Hz (4th-order zero-phase Butterworth)"

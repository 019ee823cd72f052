"""Excitation: synthetic generator, displacement CSV, pulse, resampling (issue 2); the
record readers and their processing and scaling are in test_records*.py (issue 13)."""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.models.errors import SceneError
from deckpound.models.excitation import support_motion
from deckpound.models.motion import G, SupportMotion
from deckpound.models.plan import support_channels
from deckpound.models.scene_io import load_scene


def test_same_seed_same_record_other_seed_other_record():
    a = support_motion(load_scene("saiidi-4span"))
    b = support_motion(load_scene("saiidi-4span"))
    c = support_motion(load_scene("saiidi-4span", ["excitation.seed=7"]))
    for ch in a.channels:
        np.testing.assert_array_equal(a.disp[ch], b.disp[ch])
    assert not np.allclose(a.disp["bent1_y"], c.disp["bent1_y"])


@pytest.mark.parametrize("pga", [0.075, 0.5, 1.0])
def test_pga_exact_biaxial_and_ends_at_rest(pga):
    m = support_motion(load_scene("saiidi-4span", [f"excitation.pga={pga}"]))
    assert np.max(np.abs(m.acc("bent1_y"))) / G == pytest.approx(pga, rel=1e-12)
    assert np.max(np.abs(m.acc("bent1_x"))) / G == pytest.approx(1.2 * pga, rel=1e-12)
    peak_v = np.max(np.abs(m.vel["bent1_x"]))
    peak_d = np.max(np.abs(m.disp["bent1_x"]))
    for ch in m.channels:
        assert abs(m.disp[ch][-1]) <= 1e-6 * peak_d
        assert abs(m.vel[ch][-1]) <= 1e-4 * peak_v


def test_velocity_is_derivative_of_displacement():
    m = support_motion(load_scene("saiidi-4span"))
    d, v = m.disp["bent2_x"], m.vel["bent2_x"]
    dt = m.t[1] - m.t[0]
    central = (d[2:] - d[:-2]) / (2 * dt)
    # central differences err by (w dt)^2/6 ~ 1e-2 for the content of this record
    assert np.max(np.abs(central - v[1:-1])) < 2e-2 * np.max(np.abs(v))


def test_spectrum_is_earthquake_like():
    """Energy concentrated around the Kanai-Tajimi frequency, little below the high-pass."""
    m = support_motion(load_scene("saiidi-4span"))
    a = m.acc("bent1_y")
    f = np.fft.rfftfreq(len(a), m.t[1])
    p = np.abs(np.fft.rfft(a)) ** 2

    def band(lo, hi):
        return p[(f >= lo) & (f < hi)].sum() / p.sum()

    assert band(1.0, 10.0) > 0.7
    assert band(0.0, 0.3) < 0.01
    assert 1.5 < f[np.argmax(p)] < 8.0


def test_tables_identical_unless_lag_or_incoherence():
    m = support_motion(load_scene("saiidi-4span"))
    np.testing.assert_array_equal(m.disp["bent1_y"], m.disp["bent3_y"])
    np.testing.assert_array_equal(m.disp["seat1_x"], m.disp["bent1_x"])
    lag = support_motion(load_scene("saiidi-4span", ["excitation.lag=0.1"]))
    np.testing.assert_array_equal(lag.disp["bent2_y"][20:], lag.disp["bent1_y"][:-20])
    inc = support_motion(load_scene("saiidi-4span", ["excitation.incoherence=0.3"]))
    r = np.corrcoef(inc.acc("bent1_y"), inc.acc("bent3_y"))[0, 1]
    assert 0.3 < r < 0.95


def test_resample_exact_on_linear_data():
    t = np.array([0.0, 0.3, 1.0, 2.0])
    d = {"a": 2.0 * t + 1.0}
    m = SupportMotion(t=t, disp=d, vel={"a": np.full(4, 2.0)})
    r = m.resample(0.01)
    np.testing.assert_allclose(r.disp["a"], 2.0 * r.t + 1.0, rtol=0, atol=1e-14)
    assert len(r.t) == 201 and r.t[-1] == pytest.approx(2.0)
    longer = m.resample(0.5, duration=3.0)
    assert longer.disp["a"][-1] == d["a"][-1]  # held after the record ends


def _write_csv(path, scene, n=50, dt=0.01, drop=None, extra=None, t_override=None):
    t = np.arange(n) * dt if t_override is None else t_override
    cols = {"t": t}
    for i, ch in enumerate(support_channels(scene)):
        cols[f"{ch}_disp"] = 1e-3 * np.sin(t * (i + 1))
        cols[f"{ch}_vel"] = 1e-3 * (i + 1) * np.cos(t * (i + 1))
    if drop:
        cols.pop(drop)
    if extra:
        cols[extra] = t
    import pandas as pd

    pd.DataFrame(cols).to_csv(path, index=False)


def _csv_scene(path, unit="m"):
    return load_scene(
        "saiidi-4span",
        [
            "excitation.kind=csv",
            f"excitation.file='{path}'",
            f"excitation.disp_unit={unit}",
            "excitation.scaling=none",
        ],
    )


def test_csv_loader_reads_every_support(tmp_path):
    p = tmp_path / "rec.csv"
    scene = _csv_scene(p)
    _write_csv(p, scene)
    m = support_motion(scene)
    assert set(m.channels) == set(support_channels(scene))
    np.testing.assert_allclose(m.disp["bent1_x"], 1e-3 * np.sin(m.t))
    mm = support_motion(_csv_scene(p, "mm"))
    np.testing.assert_allclose(mm.disp["seat2_x"], 1e-3 * m.disp["seat2_x"])


@pytest.mark.parametrize(
    "case,match",
    [
        ({"drop": "bent2_y_disp"}, "support 'bent2_y' has no record"),
        ({"extra": "bent9_x_disp"}, "unknown column 'bent9_x_disp'"),
        (
            {"t_override": np.array([0.0, 0.1, 0.1, 0.2] + [0.3 + 0.1 * i for i in range(46)])},
            "duplicate",
        ),
        (
            {"t_override": np.array([0.0, 0.2, 0.1] + [0.3 + 0.1 * i for i in range(47)])},
            "decreasing",
        ),
    ],
)
def test_csv_refusals(tmp_path, case, match):
    p = tmp_path / "rec.csv"
    scene = _csv_scene(p)
    _write_csv(p, scene, **case)
    with pytest.raises(SceneError, match=match):
        support_motion(scene)


def test_csv_mismatched_length_refused(tmp_path):
    p = tmp_path / "rec.csv"
    scene = _csv_scene(p)
    _write_csv(p, scene)
    lines = p.read_text().splitlines()
    lines[-1] = ",".join(lines[-1].split(",")[:5])  # a short last row
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(SceneError, match="missing or not finite"):
        support_motion(scene)


def test_pulse_is_one_longitudinal_cycle_at_rest_after():
    s = load_scene(
        "saiidi-4span",
        [
            "excitation.kind=pulse",
            "excitation.pga=0.5",
            "excitation.duration=2",
            "excitation.pulse_period=0.4",
        ],
    )
    m = support_motion(s)
    assert np.max(np.abs(m.acc("bent2_x"))) / G == pytest.approx(0.6, rel=1e-12)
    assert np.all(m.disp["bent2_y"] == 0) and m.disp["seat1_x"][-1] == 0.0
    w = 2 * np.pi / 0.4
    assert m.disp["bent1_x"].max() == pytest.approx(2 * 0.6 * G / w**2, rel=1e-3)


def test_generator_refuses_a_highpass_corner_outside_the_record_band():
    """The synthetic generator shares the records' high-pass (record_motion.highpass_padded):
    a corner at or above the Nyquist frequency is refused by field, with the band."""
    sc = load_scene("saiidi-4span", ["excitation.highpass=1000"])
    with pytest.raises(SceneError, match="excitation.highpass") as err:
        support_motion(sc)
    assert "Nyquist frequency 100 Hz of the record, got 1000.0" in str(err.value)


def _clear_generator_memos():
    from deckpound.models import iir, synthetic_motion

    for memo in (
        synthetic_motion._derivative_factor,
        synthetic_motion._taper,
        synthetic_motion._sampled_envelope,
        synthetic_motion._kanai_tajimi_response,
        iir._butter_highpass_design,
        iir._step_state,
    ):
        memo.cache_clear()


def test_remembered_generator_spectra_follow_the_record():
    """The generator keeps its spectra, envelope, taper and filter per record; each record
    generated after others (memos filled by records of the same length with another step,
    duration, ground filter or high-pass) equals the one generated from empty memos."""
    sets = [
        [],
        ["excitation.duration=10"],  # 2001 samples at 0.005 s
        ["excitation.duration=20", "excitation.dt=0.01"],  # 2001 samples at 0.01 s
        ["excitation.duration=20", "excitation.dt=0.01", "excitation.dominant_frequency=4"],
        ["excitation.duration=20", "excitation.dt=0.01", "excitation.ground_damping=0.3"],
        ["excitation.duration=20", "excitation.dt=0.01", "excitation.highpass=0.4"],
    ]
    scenes = [load_scene("saiidi-4span", s) for s in sets]
    warm = [support_motion(s) for s in scenes]
    for scene, motion in zip(scenes, warm):
        _clear_generator_memos()
        fresh = support_motion(scene)
        for ch in motion.channels:
            np.testing.assert_array_equal(motion.disp[ch], fresh.disp[ch])
            np.testing.assert_array_equal(motion.acc(ch), fresh.acc(ch))


def test_components_generated_together_equal_one_at_a_time():
    """The generator filters all components of a record as rows of one array; each row is
    the component generated alone, for the directions and, with incoherence, the tables."""
    from deckpound.models.synthetic_motion import mixed_noise, synthetic_components

    scene = load_scene("saiidi-4span", ["excitation.incoherence=0.3"])
    exc = scene.excitation
    n = round(exc.duration / exc.dt) + 1
    rng = np.random.default_rng(3)
    noise = np.array([mixed_noise(exc, [5, k], rng.standard_normal(n)) for k in range(3)])
    together = synthetic_components(exc, [0.2, 0.5, 0.9], noise)
    for i, pga in enumerate((0.2, 0.5, 0.9)):
        alone = synthetic_components(exc, [pga], noise[i : i + 1])
        for a, b in zip(together[:3], alone[:3]):
            np.testing.assert_array_equal(a[i], b[0])
        assert np.max(np.abs(together[2][i])) == pytest.approx(pga * G, rel=1e-12)

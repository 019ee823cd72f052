"""A CSV record's velocity columns against its displacement columns, and any scaling of a user's
record said (issue 28, item 4).

Consistently processed records pass the velocity check with room on both sides of the
tolerance: the benchmark's synthetic motion written as CSV, and PEER-like AT2 records
integrated by deckpound (several steps, spectra and processings) written as CSV. A velocity
column of 1000 m/s next to centimetres of displacement, one in cm/s, of the wrong sign or
shifted by a few samples is refused, naming the channel, the time and both values.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pandas as pd
import pytest
from _record_helpers import quake, record_scene, write_at2

from deckpound.cli import main
from deckpound.models.errors import SceneError
from deckpound.models.excitation import support_motion
from deckpound.models.motion import RecordWarning
from deckpound.models.plan import support_channels
from deckpound.models.record_checks import velocity_tolerance
from deckpound.models.scene_io import load_scene


def _quiet_motion(scene):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return support_motion(scene)


def _write_disp_csv(path, motion, channels, change=None):
    """``t``, ``<support>_disp`` and ``<support>_vel`` of ``motion`` as a CSV; ``change(cols)``
    edits the columns first."""
    cols = {"t": motion.t}
    for c in channels:
        cols[f"{c}_disp"] = motion.disp[c]
        cols[f"{c}_vel"] = motion.vel[c]
    if change is not None:
        change(cols)
    pd.DataFrame(cols).to_csv(path, index=False)
    return path


def _csv_scene(path, *overrides):
    return record_scene("csv", None, None, path, *overrides)


def _worst_share(motion) -> float:
    """Largest |v − v_d| over the tolerance, over every support (1 is the limit)."""
    peak = max(float(np.max(np.abs(np.gradient(motion.disp[c], motion.t)))) for c in motion.disp)
    shares = []
    for c in motion.disp:
        v_d, tol = velocity_tolerance(motion.t, motion.disp[c], peak)
        shares.append(float(np.max(np.abs(motion.vel[c] - v_d))) / tol)
    return max(shares)


@pytest.fixture(scope="module")
def bench_motion():
    return _quiet_motion(load_scene("saiidi-4span"))


@pytest.fixture(scope="module")
def channels():
    return support_channels(load_scene("saiidi-4span"))


def test_the_benchmark_record_written_as_csv_passes_with_room(tmp_path, bench_motion, channels):
    """The tolerance's docstring: the benchmark's motion uses 3 % of it."""
    assert round(_worst_share(bench_motion), 2) == 0.03
    p = _write_disp_csv(tmp_path / "bench.csv", bench_motion, channels)
    m = _quiet_motion(_csv_scene(p, "excitation.scaling=none"))
    np.testing.assert_array_equal(m.vel["bent1_x"], bench_motion.vel["bent1_x"])


def _peer_like(tmp_path, dt, kind):
    """An AT2 record 40 s long at step dt: 'quake' (an enveloped chirp with smoothed noise, as
    processed records are) or 'white' (broadband noise up to the Nyquist frequency)."""
    n = int(40 / dt)
    if kind == "quake":
        acc = quake(n=n, dt=dt, f=1.0, peak=0.4, seed=1)
    else:
        t = np.arange(n) * dt
        acc = np.random.default_rng(3).standard_normal(n) * np.sin(np.pi * t / t[-1]) ** 2
        acc = 0.5 * acc / np.max(np.abs(acc))
    return write_at2(tmp_path / f"{kind}-{dt}.at2", acc, dt=dt)


@pytest.mark.parametrize("dt", [0.005, 0.01, 0.02])
@pytest.mark.parametrize("kind", ["quake", "white"])
@pytest.mark.parametrize(
    "processing",
    [
        (),
        ("excitation.time_scale=0.5",),
        ("excitation.processing=baseline",),
        ("excitation.processing=highpass", "excitation.highpass=0.1"),
    ],
)
def test_peer_like_records_integrated_by_deckpound_pass(tmp_path, channels, dt, kind, processing):
    """A record integrated by deckpound and written as displacement + velocity CSV uses at most
    35 % of the tolerance (the docstring's number), and is read back unchanged."""
    p = _peer_like(tmp_path, dt, kind)
    motion = _quiet_motion(record_scene("at2", p, p, None, *processing))
    assert _worst_share(motion) <= 0.35
    csv = _write_disp_csv(tmp_path / "r.csv", motion, channels)
    back = _quiet_motion(_csv_scene(csv, "excitation.scaling=none"))
    np.testing.assert_array_equal(back.disp["seat2_x"], motion.disp["seat2_x"])


def test_a_velocity_of_1000_m_per_s_is_refused_naming_channel_time_and_values(
    tmp_path, bench_motion, channels
):
    def fast(cols):
        cols["bent1_x_vel"] = np.full(len(cols["t"]), 1000.0)

    p = _write_disp_csv(tmp_path / "bad.csv", bench_motion, channels, fast)
    with pytest.raises(SceneError) as err:
        support_motion(_csv_scene(p))
    text = str(err.value)
    assert text.startswith("excitation.file: ")
    assert "column 'bent1_x_vel' holds 1000 m/s at t = 0 s" in text
    assert "the displacement column 'bent1_x_disp' changes at" in text
    assert "they differ by more than 0.0867 m/s" in text


@pytest.mark.parametrize(
    "how,where",
    [
        ("cm/s", "bent2_y_vel"),  # a velocity in another unit
        ("sign", "seat1_x_vel"),  # the wrong sign
        ("shift", "bent3_x_vel"),  # two samples late
        ("half", "bent1_y_vel"),  # another record's (half the motion)
    ],
)
def test_inconsistent_velocity_columns_are_refused(tmp_path, bench_motion, channels, how, where):
    def change(cols):
        v = cols[where]
        cols[where] = {
            "cm/s": 100.0 * v,
            "sign": -v,
            "shift": np.concatenate([[0.0, 0.0], v[:-2]]),
            "half": 0.5 * v,
        }[how]

    p = _write_disp_csv(tmp_path / "bad.csv", bench_motion, channels, change)
    with pytest.raises(SceneError, match=f"column '{where}' holds"):
        support_motion(_csv_scene(p))


def test_a_csv_without_velocity_columns_derives_them(tmp_path, bench_motion, channels):
    def drop(cols):
        for c in channels:
            del cols[f"{c}_vel"]

    p = _write_disp_csv(tmp_path / "d.csv", bench_motion, channels, drop)
    m = _quiet_motion(_csv_scene(p, "excitation.scaling=none"))
    np.testing.assert_allclose(
        m.vel["bent2_x"], np.gradient(bench_motion.disp["bent2_x"], bench_motion.t)
    )


def test_cli_refuses_the_1000_m_per_s_record_with_exit_2(tmp_path, bench_motion, channels, capsys):
    def fast(cols):
        cols["bent1_x_vel"] = np.full(len(cols["t"]), 1000.0)

    p = _write_disp_csv(tmp_path / "bad.csv", bench_motion, channels, fast)
    sets = ["--set", "excitation.kind=csv", "--set", f"excitation.file={json.dumps(str(p))}"]
    out = tmp_path / "out"
    code = main(["run", "saiidi-4span", *sets, "--engine", "nonsmooth", "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and not out.exists()
    assert len(err) == 1 and "column 'bent1_x_vel' holds 1000 m/s" in err[0]


# -- scaling said --------------------------------------------------------------------------


def _scaled_csv(tmp_path, bench_motion, channels, factor):
    """The benchmark's motion as CSV, and a scene whose pga and longitudinal_ratio make
    scaling = 'pga' scale both directions by ``factor``."""
    p = _write_disp_csv(tmp_path / "rec.csv", bench_motion, channels)
    read = _quiet_motion(_csv_scene(p, "excitation.scaling=none"))
    as_read = read.provenance["pga_before_scaling"]
    ratio = as_read["x"] / as_read["y"]
    return p, (
        f"excitation.pga={as_read['y'] * factor!r}",
        f"excitation.longitudinal_ratio={ratio!r}",
    )


def test_a_small_rescaling_is_warned_and_kept_in_the_provenance(tmp_path, bench_motion, channels):
    p, sets = _scaled_csv(tmp_path, bench_motion, channels, 1.00018)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = support_motion(_csv_scene(p, *sets))
    said = [str(w.message) for w in caught if issubclass(w.category, RecordWarning)]
    assert len(said) == 1
    assert said[0].startswith(
        "excitation.scaling: the record is scaled, longitudinal (x) × 1.00018 (PGA "
    )
    assert "transverse (y) × 1.00018 (PGA" in said[0] and "scaling = 'pga'" in said[0]
    prov = m.provenance
    assert prov["warnings"] == said
    assert prov["scale_factor"]["y"] == pytest.approx(1.00018, rel=1e-12)
    assert prov["target_pga"]["y"] == pytest.approx(prov["pga_before_scaling"]["y"] * 1.00018)


def test_a_scaling_below_six_digits_is_still_said(tmp_path, bench_motion, channels):
    p, sets = _scaled_csv(tmp_path, bench_motion, channels, 1.0 + 3e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = support_motion(_csv_scene(p, *sets))
    assert "transverse (y) × (1 + 3e-09)" in m.provenance["warnings"][-1]


def test_an_unscaled_record_says_nothing(tmp_path, bench_motion, channels):
    p = _write_disp_csv(tmp_path / "rec.csv", bench_motion, channels)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = support_motion(_csv_scene(p, "excitation.scaling=none"))
    assert [w for w in caught if issubclass(w.category, RecordWarning)] == []
    assert m.provenance["warnings"] == [] and m.provenance["scale_factor"] == {"x": 1.0, "y": 1.0}


def test_the_run_line_says_the_scaling(tmp_path, bench_motion, channels, capsys):
    p, sets = _scaled_csv(tmp_path, bench_motion, channels, 1.00018)
    args = ["excitation.kind=csv", f"excitation.file={json.dumps(str(p))}", *sets]
    args += ["run.duration=0.5"]
    out = tmp_path / "out"
    argv = ["run", "saiidi-4span", "--engine", "nonsmooth", "-o", str(out)]
    with pytest.warns(RecordWarning, match="excitation.scaling: the record is scaled"):
        code = main(argv + [a for s in args for a in ("--set", s)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    (line,) = captured.out.strip().splitlines()
    assert "; record scaled x × 1.00018 to " in line and ", y × 1.00018 to " in line
    record = json.loads((out / "nonsmooth.json").read_text())["record"]
    assert record["scale_factor"]["x"] == pytest.approx(1.00018, rel=1e-12)
    assert record["warnings"][-1].startswith("excitation.scaling: the record is scaled")
    # unscaled: the line says nothing of it
    code = main(argv[:-1] + [str(tmp_path / "plain"), "--set", "run.duration=0.5"])
    assert code == 0 and "scaled" not in capsys.readouterr().out

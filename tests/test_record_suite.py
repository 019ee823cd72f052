"""Record suites (issue 30, item 3): a folder read as record pairs by station, the manifest,
the 90° rotation, one-factor scaling of a pair, and the variability study over pairs."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
from _record_helpers import quake, record_scene, write_acc_csv, write_at2

from deckpound.compare.cases import case_key, record_digests
from deckpound.compare.studies.variability import record_cases, run_variability
from deckpound.models.errors import SceneError
from deckpound.models.excitation import support_motion
from deckpound.models.record_suite import component_of, read_suite
from deckpound.models.scene_io import load_scene

# a CLS000/CLS090-like station: component PGAs 0.67 g and 0.50 g, ratio 1.34
PGA_000, PGA_090 = 0.67, 0.50


def peer_pair(folder: Path, prefix: str = "RSN753_LOMAP_CLS", a="000", b="090", seed=1):
    fx = write_at2(folder / f"{prefix}{a}.AT2", quake(seed=seed, peak=PGA_000))
    fy = write_at2(folder / f"{prefix}{b}.AT2", quake(seed=seed + 1, peak=PGA_090))
    return fx, fy


def suite_folder(tmp_path: Path) -> Path:
    """A PEER pair with its vertical component, and a NAME_x / NAME_y pair."""
    folder = tmp_path / "suite"
    folder.mkdir()
    peer_pair(folder)
    write_at2(folder / "RSN753_LOMAP_CLS-UP.AT2", quake(seed=9, peak=0.2))
    write_at2(folder / "quake_x.at2", quake(seed=3, peak=0.3))
    write_at2(folder / "quake_y.at2", quake(seed=4, peak=0.2))
    return folder


def test_component_names():
    assert component_of("RSN753_LOMAP_CLS000") == ("RSN753_LOMAP_CLS", "000")
    assert component_of("RSN6_IMPVALL.I_I-ELC180") == ("RSN6_IMPVALL.I_I-ELC", "180")
    assert component_of("RSN6_IMPVALL.I_I-ELC-UP") == ("RSN6_IMPVALL.I_I-ELC", "UP")
    assert component_of("RSN1_EVT_STA_H2") == ("RSN1_EVT_STA", "H2")
    assert component_of("CI.PAS_HNE") == ("CI.PAS", "HNE")
    assert component_of("STA-V") == ("STA", "V")
    assert component_of("elcentro") is None


def test_folder_pairs_peer_and_xy_names_and_ignores_verticals(tmp_path):
    suite = read_suite(suite_folder(tmp_path))
    assert [(p.name, p.rule) for p in suite.pairs] == [
        ("RSN753_LOMAP_CLS", "peer"),
        ("quake", "xy"),
    ]
    peer, xy = suite.pairs
    assert (peer.file_x.name, peer.file_y.name) == (
        "RSN753_LOMAP_CLS000.AT2",
        "RSN753_LOMAP_CLS090.AT2",
    )
    assert (xy.file_x.name, xy.file_y.name) == ("quake_x.at2", "quake_y.at2")
    assert len(suite.notes) == 1 and "RSN753_LOMAP_CLS-UP.AT2" in suite.notes[0]


@pytest.mark.parametrize(
    ("names", "x"),
    [(("STA_H2", "STA_H1"), "STA_H1"), (("CI.PAS_HNN", "CI.PAS_HNE"), "CI.PAS_HNE")],
)
def test_channel_names_pair_in_a_fixed_order(tmp_path, names, x):
    for i, name in enumerate(names):
        write_at2(tmp_path / f"{name}.at2", quake(seed=i))
    (pair,) = read_suite(tmp_path).pairs
    assert pair.file_x.stem == x


def test_a_lone_component_is_refused_naming_the_file(tmp_path):
    folder = suite_folder(tmp_path)
    write_at2(folder / "RSN999_EVT_ABC090.AT2", quake(seed=5))
    with pytest.raises(SceneError, match=r"RSN999_EVT_ABC090\.AT2.*no partner"):
        read_suite(folder)
    (folder / "RSN999_EVT_ABC090.AT2").unlink()
    write_at2(folder / "lonely_y.at2", quake(seed=6))
    with pytest.raises(SceneError, match=r"lonely_y\.at2.*lonely_x\.at2 is missing"):
        read_suite(folder)
    (folder / "lonely_y.at2").unlink()
    write_at2(folder / "elcentro.at2", quake(seed=7))
    with pytest.raises(SceneError, match=r"elcentro\.at2: no component in its name"):
        read_suite(folder)


def test_cli_exits_2_with_one_line_for_a_lone_component(tmp_path):
    folder = tmp_path / "lone"
    folder.mkdir()
    write_at2(folder / "RSN999_EVT_ABC090.AT2", quake(seed=5))
    cli = Path(sys.executable).with_name("deckpound")
    proc = subprocess.run(
        [
            str(cli),
            "study",
            "variability",
            "saiidi-4span",
            "--records",
            str(folder),
            "-o",
            str(tmp_path / "out"),
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "RSN999_EVT_ABC090.AT2" in lines[0] and "no partner" in lines[0]


def test_manifest_pairs_names_that_do_not_pair(tmp_path):
    folder = suite_folder(tmp_path)
    write_at2(folder / "elcentro_a.at2", quake(seed=7))
    write_at2(folder / "elcentro_b.at2", quake(seed=8))
    (folder / "manifest.csv").write_text(
        "pair,file_x,file_y\nelcentro,elcentro_b.at2,elcentro_a.at2\n"
    )
    pairs = {p.name: p for p in read_suite(folder).pairs}
    assert set(pairs) == {"RSN753_LOMAP_CLS", "quake", "elcentro"}
    assert (pairs["elcentro"].file_x.name, pairs["elcentro"].rule) == ("elcentro_b.at2", "manifest")
    (folder / "manifest.csv").write_text("pair,file_x\nelcentro,elcentro_b.at2\n")
    with pytest.raises(SceneError, match="missing file_y"):
        read_suite(folder)
    (folder / "manifest.csv").write_text("pair,file_x,file_y\ne,elcentro_b.at2,nowhere.at2\n")
    with pytest.raises(SceneError, match="'nowhere.at2' is not a file of the folder"):
        read_suite(folder)


def test_rotation_swaps_the_components(tmp_path):
    folder = suite_folder(tmp_path)
    pairs = read_suite(folder, rotate=True).pairs
    assert [(p.name, p.rotated) for p in pairs] == [
        ("RSN753_LOMAP_CLS", False),
        ("RSN753_LOMAP_CLS", True),
        ("quake", False),
        ("quake", True),
    ]
    assert (pairs[1].file_x, pairs[1].file_y) == (pairs[0].file_y, pairs[0].file_x)
    cases = record_cases(load_scene("saiidi-4span"), folder, rotate=True)
    exc0, exc1 = cases[0][2].excitation, cases[1][2].excitation
    assert (exc1.file_x, exc1.file_y) == (exc0.file_y, exc0.file_x)
    assert cases[1][0] == "record RSN753_LOMAP_CLS (rotated 90°)"


def applied(tmp_path, *sets):
    fx, fy = peer_pair(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return support_motion(record_scene("at2", fx, fy, None, *sets)).provenance


def test_one_factor_scaling_keeps_the_component_ratio(tmp_path):
    """pair-pga: both components × one factor, the geometric-mean PGA at pga and the ratio
    1.34 kept; per-component scaling (pga) replaces it by longitudinal_ratio (1.2)."""
    prov = applied(tmp_path, "excitation.scaling=pair-pga", "excitation.pga=0.4")
    x, y = prov["applied_pga"]["x"], prov["applied_pga"]["y"]
    assert x / y == pytest.approx(PGA_000 / PGA_090, rel=1e-12)
    assert math.sqrt(x * y) == pytest.approx(0.4, rel=1e-12)
    assert prov["scale_factor"]["x"] == prov["scale_factor"]["y"]
    assert prov["pair_scaling"]["measure"] == "pga"
    assert any("components' ratio is kept" in w for w in prov["warnings"])
    per = applied(tmp_path, "excitation.scaling=pga", "excitation.pga=0.4")["applied_pga"]
    assert per["x"] / per["y"] == pytest.approx(1.2, rel=1e-12)


@pytest.mark.parametrize(
    ("scaling", "target", "measure"),
    [
        (
            "pair-pgv",
            "excitation.target_pgv=0.3",
            lambda i: math.sqrt(i["x"]["pgv"] * i["y"]["pgv"]),
        ),
        ("pair-sa", "excitation.target_sa=0.8", lambda i: i["sa_geomean"]),
        ("pair-rotd50", "excitation.target_sa=0.8", lambda i: i["rotd50"]),
    ],
)
def test_pair_scaling_meets_its_target(tmp_path, scaling, target, measure):
    prov = applied(tmp_path, f"excitation.scaling={scaling}", target)
    ims = prov["intensity"]
    assert measure(ims) == pytest.approx(float(target.split("=")[1]), rel=1e-9)
    assert ims["x"]["pga"] / ims["y"]["pga"] == pytest.approx(PGA_000 / PGA_090, rel=1e-12)


def test_a_pair_scaled_to_many_levels_meets_each_with_one_measurement(tmp_path):
    """An IDA scales one pair to many levels: its measure is kept per pair content, step and
    period (record_motion._pair_measure), so every level's factor is level / the same measure,
    and another period or another pair is measured anew."""
    factors = {}
    for level in (0.2, 0.8, 0.5):
        prov = applied(tmp_path, "excitation.scaling=pair-sa", f"excitation.target_sa={level}")
        assert prov["intensity"]["sa_geomean"] == pytest.approx(level, rel=1e-9)
        factors[level] = prov["pair_scaling"]["factor"]
        assert prov["pair_scaling"]["before"] == pytest.approx(level / factors[level], rel=1e-15)
    assert factors[0.8] / factors[0.2] == pytest.approx(4.0, rel=1e-15)
    sets = ("excitation.scaling=pair-sa", "excitation.target_sa=0.5")
    other_period = applied(tmp_path, *sets, "excitation.im_period=0.3")
    assert other_period["intensity"]["sa_geomean"] == pytest.approx(0.5, rel=1e-9)
    assert other_period["pair_scaling"]["factor"] != factors[0.5]
    other = tmp_path / "other"
    other.mkdir()
    fx, fy = peer_pair(other, seed=7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prov = support_motion(record_scene("at2", fx, fy, None, *sets)).provenance
    assert prov["intensity"]["sa_geomean"] == pytest.approx(0.5, rel=1e-9)
    assert prov["pair_scaling"]["factor"] != factors[0.5]


def test_pair_scaling_refusals(tmp_path):
    fx, fy = peer_pair(tmp_path)
    with pytest.raises(SceneError, match="scaling.*applies to records"):
        load_scene("saiidi-4span", ["excitation.scaling=pair-sa", "excitation.target_sa=0.5"])
    with pytest.raises(SceneError, match="target_sa.*is required"):
        record_scene("at2", fx, fy, None, "excitation.scaling=pair-sa")
    with pytest.raises(SceneError, match="needs both file_x and file_y"):
        record_scene("at2", fx, None, None, "excitation.scaling=pair-pga")
    with pytest.raises(SceneError, match="target_sa.*used only with scaling"):
        record_scene("at2", fx, fy, None, "excitation.target_sa=0.5")


def test_pair_scaling_needs_two_acceleration_components(tmp_path):
    """A CSV with one acceleration column, or of support displacements, is no pair."""
    t = [0.01 * i for i in range(800)]
    one = write_acc_csv(tmp_path / "one.csv", t, ax=list(quake(seed=1)))
    scene = record_scene(
        "csv", None, None, one, "excitation.scaling=pair-pga", "excitation.pga=0.3"
    )
    with pytest.raises(SceneError, match="the CSV has no transverse"):
        support_motion(scene)
    lines = ["t,bent1_disp"] + [f"{ti},0.0" for ti in t]
    disp = tmp_path / "disp.csv"
    disp.write_text("\n".join(lines) + "\n")
    scene = record_scene("csv", None, None, disp, "excitation.scaling=pair-pga")
    with pytest.raises(SceneError, match="holds support displacements"):
        support_motion(scene)


def test_variability_over_two_pairs_runs_two_cases_with_x_and_y(tmp_path):
    folder = suite_folder(tmp_path)
    scene = load_scene("saiidi-4span", ["run.duration=1.0"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        table, _ = run_variability(
            scene, tmp_path / "out", records=folder, workers=1, progress=False
        )
    assert len(table) == 2
    assert list(table["record"]) == ["RSN753_LOMAP_CLS", "quake"]
    assert all(table["file_x"] != table["file_y"])
    assert set(table["status"]) <= {"success", "doubtful"}


def test_case_keys_read_each_record_once_per_batch_and_follow_an_edit(tmp_path):
    """The keys of a sweep's cases name the bytes of their record files: made as one batch
    (each file read once for every case that applies it, as an IDA's levels do), they equal
    the keys made one case at a time; a file edited in place gives the next batch new keys;
    a file that cannot be read adds no digest, and the run refuses it with its own message."""
    fx, fy = peer_pair(tmp_path)
    levels = [
        record_scene("at2", fx, fy, None, "excitation.scaling=factor", f"excitation.scale={s}")
        for s in (0.5, 1, 2)
    ]
    read: dict = {}
    batch = [case_key("compliance", sc, read) for sc in levels]
    assert batch == [case_key("compliance", sc) for sc in levels]
    assert len(set(batch)) == 3 and sorted(read) == sorted([str(fx), str(fy)])
    write_at2(fx, quake(seed=7, peak=PGA_000))  # edited in place
    again = [case_key("compliance", sc, {}) for sc in levels]
    assert not set(again) & set(batch)
    assert again[1] != case_key(
        "compliance", record_scene("at2", fx, fy, None, "excitation.scaling=factor"), read
    )
    fy.unlink()
    assert record_digests(levels[0], {}) == {"file_x": record_digests(levels[0])["file_x"]}

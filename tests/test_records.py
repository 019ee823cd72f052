"""Real records as inputs: readers, tolerances, provenance, hardening (issues 13 and 16).

Every quirk of real downloads is built here as a file: AT2 in both header generations, a value
more than NPTS, components of unequal length, one direction only, different steps, huge PGA,
huge files, non-numeric tokens, files that are no record, paths outside the scene's folder.
Each test checks the warning text, the provenance and the applied scaling, or the refusal.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tracemalloc
import warnings

import numpy as np
import pytest
from _record_helpers import DT, STATION, quake, record_scene, write_acc_csv, write_at2, write_text

from deckpound.models import records
from deckpound.models.errors import SceneError
from deckpound.models.excitation import support_motion
from deckpound.models.kept import Kept
from deckpound.models.motion import G, RecordWarning
from deckpound.models.records import MAX_SAMPLES, read_at2, read_text
from deckpound.models.scene_io import RecordPathWarning, load_scene, scene_to_toml

PROVENANCE_KEYS = {
    "kind",
    "files",
    "header",
    "npts",
    "dt_record",
    "time_scale",
    "dt",
    "duration",
    "processing",
    "scaling",
    "target_pga",
    "scale_factor",
    "applied_pga",
    "pair_scaling",
    "intensity",
    "seed",
    "warnings",
    "units",
    "pga_before_scaling",
}
SCALED = "excitation.scaling: the record is scaled, "
WHY = (
    ": scaling = 'pga' scales each direction to its target (transverse to pga, longitudinal "
    "to longitudinal_ratio × pga; scaling = 'none' keeps the record as read)"
)


def motion_and_warnings(scene):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = support_motion(scene)
    return m, [str(w.message) for w in caught if issubclass(w.category, RecordWarning)]


# -- AT2 headers ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "line4",
    [
        "NPTS=   800, DT=   .0100 SEC",  # NGA-West2
        "NPTS=800,DT=0.01 SEC",  # no spaces
        "npts = 800 , dt = 1.0E-02 sec",  # lower case, exponent
        "NPTS: 800  DT: .01",  # colons, no comma
        "  800   0.0100    NPTS, DT",  # older PEER files
        "800 .01 NPTS,DT",
        "800, 0.01, NPTS, DT",
    ],
)
def test_at2_header_generations_read_the_same(tmp_path, line4):
    acc = quake()
    rec = read_at2(write_at2(tmp_path / "x.at2", acc, line4=line4))
    assert rec.npts == 800 and rec.dt == pytest.approx(0.01, rel=1e-15)
    np.testing.assert_allclose(rec.values, acc, rtol=1e-7, atol=1e-12)
    assert rec.header == STATION and rec.notes == []


def test_at2_old_fortran_values_without_leading_zero(tmp_path):
    acc = quake()
    rec = read_at2(write_at2(tmp_path / "x.at2", acc, style="old"))
    lines = (tmp_path / "x.at2").read_text().splitlines()
    assert lines[3].endswith("NPTS, DT") and " .1" not in lines[3]
    body = "\n".join(lines[4:])
    assert "0." not in body and " ." in body  # '-.1234567E-02': no leading zero
    np.testing.assert_allclose(rec.values, acc, rtol=1e-6, atol=1e-12)


def test_at2_one_value_more_than_npts_is_used_and_said(tmp_path):
    """Northridge downloads hold one value more than NPTS: the first NPTS are used."""
    acc = quake()
    px = write_at2(tmp_path / "x.at2", list(acc) + [0.123], npts=800)
    py = write_at2(tmp_path / "y.at2", acc)
    m, warned = motion_and_warnings(record_scene("at2", px, py))
    expected = (
        f"excitation.file_x ({px.resolve()}): holds 801 values but NPTS = 800: the first "
        "800 are used, the last 1 ignored"
    )
    # the scaling to the default targets (pga 1 g, x 1.2 g) is said last
    scaled = (
        f"{SCALED}longitudinal (x) × 4 (PGA 0.3 g to 1.2 g), transverse (y) × 3.33333 "
        f"(PGA 0.3 g to 1 g){WHY}"
    )
    assert warned == [expected, scaled]
    assert m.provenance["warnings"] == [expected, scaled]
    assert m.provenance["npts"] == {"x": 800, "y": 800} and len(m.t) == 800


def test_at2_fewer_values_than_npts_is_refused(tmp_path):
    """A cut download: the missing part may be the strong motion, so no guess is made."""
    p = write_at2(tmp_path / "x.at2", quake(), npts=900)
    with pytest.raises(
        SceneError,
        match=r"NPTS=900 but the file holds 800 values \(a cut "
        r"download\?\); if the file is complete, correct NPTS",
    ):
        read_at2(p)


def test_at2_many_more_values_than_npts_is_refused(tmp_path):
    p = write_at2(tmp_path / "x.at2", quake(), npts=100)
    with pytest.raises(SceneError, match=r"\(700 more\); at most 10 extra values are tolerated"):
        read_at2(p)


def test_velocity_series_and_other_units_refused(tmp_path):
    p = write_at2(tmp_path / "x.vt2", quake(), unit_line="VELOCITY TIME SERIES IN UNITS OF CM/S")
    with pytest.raises(SceneError, match="is a velocity time series"):
        read_at2(p)
    p = write_at2(tmp_path / "x.at2", quake(), unit_line="ACCELERATION IN UNITS OF CM/S/S")
    with pytest.raises(SceneError, match="gives the unit 'CM/S/S'; AT2 records are read in g"):
        read_at2(p)


# -- components ----------------------------------------------------------------------------


def test_unequal_components_padded_with_zeros_and_said(tmp_path):
    """One station's components differ by a few samples (7999 vs 7995): the shorter is
    padded with zeros at its end, every recorded sample is kept."""
    ax, ay = quake(7999, 0.005, seed=1), quake(7995, 0.005, seed=2)
    px = write_at2(tmp_path / "x.at2", ax, dt=0.005)
    py = write_at2(tmp_path / "y.at2", ay, dt=0.005)
    m, warned = motion_and_warnings(record_scene("at2", px, py, None, "excitation.scaling=none"))
    expected = (
        f"excitation.file_y ({py.resolve()}): the transverse (y) component has 7995 "
        "samples, 4 fewer than the longitudinal (x) one (7999): padded with zeros at the "
        "end (0.02 s at rest)"
    )
    assert warned == [expected] and m.provenance["warnings"] == [expected]
    assert len(m.t) == 7999 and m.t[-1] == pytest.approx(7998 * 0.005)
    np.testing.assert_allclose(m.acc("bent2_y")[:7995], ay * G, rtol=1e-7, atol=1e-12)
    assert np.all(m.acc("bent2_y")[7995:] == 0.0)
    assert m.provenance["npts"] == {"x": 7999, "y": 7995}


def test_one_direction_only_is_at_rest_and_said(tmp_path):
    py = write_at2(tmp_path / "y.at2", quake())
    m, warned = motion_and_warnings(record_scene("at2", None, py, None, "excitation.pga=0.4"))
    assert warned == [
        (
            "excitation.file_x is not given: the longitudinal (x) direction is at "
            "rest (its PGA target is not applied)"
        ),
        f"{SCALED}transverse (y) × 1.33333 (PGA 0.3 g to 0.4 g){WHY}",
    ]
    for ch in ("bent1_x", "bent3_x", "seat1_x", "seat2_x"):
        assert np.all(m.disp[ch] == 0.0) and np.all(m.vel[ch] == 0.0)
    assert m.provenance["applied_pga"] == {"x": 0.0, "y": pytest.approx(0.4, rel=1e-12)}
    assert set(m.provenance["files"]) == {"y"}


def test_different_steps_refused(tmp_path):
    px = write_at2(tmp_path / "x.at2", quake(), dt=0.01)
    py = write_at2(tmp_path / "y.at2", quake(), dt=0.005)
    with pytest.raises(
        SceneError,
        match=r"excitation.file_y: the record's step DT = 0.005 s "
        r"differs from the x record's 0.01 s",
    ):
        support_motion(record_scene("at2", px, py))


# -- text and CSV --------------------------------------------------------------------------


def test_text_record_comments_titles_separators_and_shifted_start(tmp_path):
    a = quake()
    t = 2.5 + np.arange(len(a)) * DT
    p = write_text(
        tmp_path / "y.txt",
        t,
        a * 100 * G,
        sep=", ",
        header=["# Station ABC, event XYZ", "% second comment", "time, acc"],
    )
    rec = read_text(p)
    assert rec.header == "Station ABC, event XYZ" and rec.npts == len(a)
    assert rec.dt == pytest.approx(DT, rel=1e-9)
    m, warned = motion_and_warnings(
        record_scene("text", None, p, None, "excitation.scaling=none", "excitation.acc_unit=cm/s^2")
    )
    assert warned == [
        (
            f"excitation.file_y ({p.resolve()}): time starts at 2.5 s; the record "
            "is shifted to start at 0 s"
        ),
        "excitation.file_x is not given: the longitudinal (x) direction is at rest",
    ]
    np.testing.assert_allclose(m.acc("bent1_y"), a * G, rtol=1e-12)
    assert m.t[0] == 0.0


def test_text_record_uneven_time_refused_naming_the_line(tmp_path):
    t = np.arange(100) * DT
    t[40] += 0.3 * DT
    p = write_text(tmp_path / "x.txt", t, quake(100), header=["# x"])
    with pytest.raises(SceneError, match=r"evenly spaced \(step 0.01 s\); line 42 is 0.003 s off"):
        read_text(p)


def test_csv_accelerations_unequal_and_one_direction(tmp_path):
    ax, ay = quake(500, seed=1), quake(497, seed=2)
    t = np.arange(500) * DT
    p = write_acc_csv(tmp_path / "r.csv", t, ax, ay)
    m, warned = motion_and_warnings(record_scene("csv", None, None, p, "excitation.scaling=none"))
    assert warned == [
        (
            f"excitation.file ({p.resolve()}), column acc_y: the transverse (y) "
            "component has 497 samples, 3 fewer than the longitudinal (x) one (500): "
            "padded with zeros at the end (0.03 s at rest)"
        )
    ]
    np.testing.assert_allclose(m.acc("bent1_x"), ax * G, rtol=1e-12)
    assert m.provenance["files"]["x"] == m.provenance["files"]["y"]
    only_x = write_acc_csv(tmp_path / "x.csv", t, ax)
    m, warned = motion_and_warnings(record_scene("csv", None, None, only_x))
    assert warned == [
        (
            "the CSV has no acc_y column: the transverse (y) direction is at rest "
            "(its PGA target is not applied)"
        ),
        f"{SCALED}longitudinal (x) × 4 (PGA 0.3 g to 1.2 g){WHY}",
    ]
    assert m.provenance["applied_pga"]["y"] == 0.0


def test_csv_empty_cell_inside_a_component_refused(tmp_path):
    t = np.arange(100) * DT
    p = write_acc_csv(tmp_path / "r.csv", t, quake(100), quake(100))
    lines = p.read_text().splitlines()
    cells = lines[30].split(",")
    cells[2] = ""
    lines[30] = ",".join(cells)
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(SceneError, match=r"row 31, column 'acc_y' is empty inside the record"):
        support_motion(record_scene("csv", None, None, p))


@pytest.mark.parametrize(
    "kind,token", [("at2", "abc"), ("at2", "1.2.3"), ("text", "nan"), ("csv", "0x1f")]
)
def test_non_numeric_token_quoted_with_its_line(tmp_path, kind, token):
    a = quake(100)
    if kind == "at2":
        p = write_at2(tmp_path / "x.at2", a)
        lines = p.read_text().splitlines()
        lines[10] = lines[10][:15] + f" {token} " + lines[10][30:]
        where = "line 11"
    elif kind == "text":
        p = write_text(tmp_path / "x.txt", np.arange(100) * DT, a)
        lines = p.read_text().splitlines()
        lines[10] = f"0.1 {token}"
        where = "line 11"
    else:
        p = write_acc_csv(tmp_path / "x.csv", np.arange(100) * DT, a, a)
        lines = p.read_text().splitlines()
        lines[10] = lines[10].rsplit(",", 1)[0] + f",{token}"
        where = "row 11, column 'acc_y'"
    p.write_text("\n".join(lines) + "\n")
    field = "excitation.file" if kind == "csv" else "excitation.file_x"
    scene = record_scene(kind, p if kind != "csv" else None, None, p if kind == "csv" else None)
    with pytest.raises(SceneError) as err:
        support_motion(scene)
    assert err.value.field == field
    assert f"{where} holds '{token}'" in str(err.value) and "not finite or not a number" in str(
        err.value
    )


# -- hardening (issue 16) ------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["at2", "text", "csv"])
def test_huge_pga_refused_naming_unit_and_direction_unless_forced(tmp_path, kind):
    """587 g (CSV) and 565 g (AT2) records were accepted (issue 16): refused unless forced."""
    a = quake(peak=565.0)
    t = np.arange(len(a)) * DT
    if kind == "at2":
        args = ("at2", write_at2(tmp_path / "x.at2", a), None, None)
    elif kind == "text":
        args = ("text", write_text(tmp_path / "x.txt", t, a), None, None)
    else:
        args = ("csv", None, None, write_acc_csv(tmp_path / "x.csv", t, a))
    field = "excitation.file" if kind == "csv" else "excitation.file_x"
    with pytest.raises(
        SceneError,
        match=rf"^{field}: the longitudinal \(x\) record reads as a "
        r"PGA of 565 g \(values in g\); more than 5 g is refused",
    ):
        support_motion(record_scene(*args))
    m = support_motion(
        record_scene(*args, "excitation.allow_extreme=true", "excitation.scaling=none")
    )
    assert m.provenance["applied_pga"]["x"] == pytest.approx(565.0, rel=1e-7)


def test_scaled_beyond_5g_refused_after_scaling(tmp_path):
    p = write_at2(tmp_path / "x.at2", quake(peak=0.5))
    with pytest.raises(
        SceneError,
        match=r"excitation.file_x: gives a longitudinal \(x\) PGA of "
        r"10 g after scaling \(scaling = 'factor', scale = 20\)",
    ):
        support_motion(
            record_scene("at2", p, None, None, "excitation.scaling=factor", "excitation.scale=20")
        )


def test_ten_million_row_csv_refused_cheaply(tmp_path):
    """A 10-million-row CSV validated with 3.95 GB (issue 16): refused after reading ~2e6 rows
    worth of bytes, in chunks, without parsing a value."""
    p = tmp_path / "huge.csv"
    with open(p, "wb") as fh:
        fh.write(b"t,acc_x\n")
        fh.write(b"0.0,0.0\n" * 10_000_000)
    tracemalloc.start()
    try:
        with pytest.raises(SceneError, match=f"holds more than {MAX_SAMPLES + 1:,} lines"):
            support_motion(record_scene("csv", None, None, p))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 40e6, f"refusal used {peak / 1e6:.0f} MB"


def test_at2_npts_beyond_limit_refused_before_reading_values(tmp_path):
    p = write_at2(tmp_path / "x.at2", quake(), npts=50_000_000)
    with pytest.raises(SceneError, match="NPTS gives 50,000,000 samples; at most 2,000,000"):
        read_at2(p)


@pytest.mark.parametrize("kind", ["at2", "text", "csv"])
def test_a_file_that_is_no_record_is_never_quoted(tmp_path, kind):
    """Errors quoted lines of any file named as a record (issue 16), e.g. a system file."""
    secret = tmp_path / "secrets.txt"
    secret.write_text(
        "root:x:0:0:root:/root:/bin/bash\nAPI_KEY=hunter2 NPTS\npassword 12\ntoken,abc\n" * 3
    )
    args = (kind, None, None, secret) if kind == "csv" else (kind, secret, None, None)
    with pytest.raises(SceneError) as err:
        support_motion(record_scene(*args))
    msg = str(err.value)
    assert str(secret.resolve()) in msg
    for leak in ("root", "bash", "API_KEY", "hunter2", "password", "token"):
        assert leak not in msg.replace(str(secret.resolve()), ""), msg


def test_binary_file_refused(tmp_path):
    p = tmp_path / "x.at2"
    p.write_bytes(b"\x00\x01\x02" * 100)
    with pytest.raises(SceneError, match="is not a text file"):
        read_at2(p)


def test_relative_record_path_resolved_and_outside_folder_noticed(tmp_path):
    scenes, data = tmp_path / "scenes", tmp_path / "data"
    scenes.mkdir(), data.mkdir()
    write_at2(data / "x.at2", quake())
    write_at2(scenes / "y.at2", quake(seed=3))
    text = scene_to_toml(
        load_scene(
            "saiidi-4span",
            [
                "excitation.kind=at2",
                "excitation.file_x='../data/x.at2'",
                "excitation.file_y='y.at2'",
            ],
        )
    )
    (scenes / "s.toml").write_text(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_scene(scenes / "s.toml")
    notices = [str(w.message) for w in caught if issubclass(w.category, RecordPathWarning)]
    assert notices == [
        (
            f"excitation.file_x: the relative path '../data/x.at2' reaches outside "
            f"the scene's folder '{scenes.resolve()}'; it is read from "
            f"'{(data / 'x.at2').resolve()}'"
        )
    ]
    assert scene.excitation.file_x == str((data / "x.at2").resolve())
    assert scene.excitation.file_y == str((scenes / "y.at2").resolve())
    m = support_motion(scene)
    assert m.provenance["files"]["x"]["path"] == str((data / "x.at2").resolve())


def test_missing_record_shown_resolved(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SceneError, match=f"'{tmp_path.resolve()}/nothere.at2' does not exist"):
        support_motion(record_scene("at2", "nothere.at2"))


# -- provenance ----------------------------------------------------------------------------


def test_provenance_keys_checksums_and_json(tmp_path):
    px = write_at2(tmp_path / "x.at2", quake(seed=1))
    py = write_at2(tmp_path / "y.at2", quake(seed=2), style="old")
    m = support_motion(record_scene("at2", px, py, None, "excitation.pga=0.6"))
    prov = json.loads(json.dumps(m.provenance))
    assert set(prov) == PROVENANCE_KEYS
    for axis, path in (("x", px), ("y", py)):
        assert prov["files"][axis] == {
            "path": str(path.resolve()),
            "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
            "bytes": path.stat().st_size,
        }
        assert prov["header"][axis] == STATION
    assert prov["kind"] == "at2" and prov["dt_record"] == 0.01 and prov["dt"] == 0.01
    assert prov["duration"] == pytest.approx(7.99) and prov["time_scale"] == 1.0
    assert prov["processing"].startswith("none") and prov["scaling"] == "pga"
    assert prov["target_pga"] == {"x": pytest.approx(0.72), "y": 0.6}
    assert prov["applied_pga"] == {
        "x": pytest.approx(0.72, rel=1e-12),
        "y": pytest.approx(0.6, rel=1e-12),
    }
    assert prov["scale_factor"] == {"x": pytest.approx(0.72 / 0.3), "y": pytest.approx(2.0)}
    assert prov["pga_before_scaling"] == {"x": pytest.approx(0.3), "y": pytest.approx(0.3)}
    assert prov["units"]["pga_before_scaling"] == "g"
    assert prov["warnings"][-1].startswith(f"{SCALED}longitudinal (x) × 2.4 (PGA 0.3 g to 0.72 g)")
    # a generated motion is made at its PGA, never scaled: no PGA before scaling
    synthetic = support_motion(load_scene("saiidi-4span")).provenance
    assert set(synthetic) == PROVENANCE_KEYS - {"pga_before_scaling"}


def test_header_line_sanitised_to_one_line(tmp_path):
    p = write_at2(tmp_path / "x.at2", quake())
    lines = p.read_text().split("\n")
    lines[1] = "Station\tA\x1b[31m  red" + " x" * 200
    p.write_text("\n".join(lines))
    header = read_at2(p).header
    assert header.startswith("Station A [31m red x") and len(header) == 120
    assert header.isprintable()


@pytest.mark.parametrize(
    "path,reason",
    [("a\\u0000b.at2", "embedded null byte"), ("~no_such_user_xyz/x.at2", "home directory")],
)
def test_unusable_path_refused_in_one_line(tmp_path, path, reason):
    with pytest.raises(
        SceneError,
        match=rf"^excitation.file_x: is not a usable file path "
        rf"\(.*{reason}",
    ):
        support_motion(
            load_scene("saiidi-4span", ["excitation.kind=at2", f'excitation.file_x="{path}"'])
        )
    (tmp_path / "s.toml").write_text(
        scene_to_toml(load_scene("saiidi-4span")).replace(
            'kind = "synthetic"', f'kind = "at2"\nfile_x = "{path}"'
        )
    )
    with pytest.raises(SceneError, match=r"^excitation.file_x: is not a usable file path"):
        load_scene(tmp_path / "s.toml")


def test_a_file_read_again_is_parsed_once_and_an_edited_one_again(tmp_path):
    """Sweeps apply one pair at many levels: the parse is kept per file content (records.
    _parsed), each reader gets its own notes, and new bytes at the same path are read anew."""
    path = write_at2(tmp_path / "a.at2", quake(), extra=["0.0"])
    first, second = read_at2(path), read_at2(path)
    assert first is not second and first.notes == second.notes and len(first.notes) == 1
    first.note("a caller's own sentence")
    assert len(second.notes) == 1 and len(read_at2(path).notes) == 1
    np.testing.assert_array_equal(first.values, second.values)
    assert not first.values.flags.writeable  # shared: nobody may change it in place
    write_at2(path, 2.0 * quake())
    edited = read_at2(path)
    assert edited.sha256 != first.sha256 and edited.notes == []
    np.testing.assert_allclose(edited.values, 2.0 * first.values[: len(edited.values)], rtol=1e-6)
    # the same bytes under another field name: messages name that field
    assert read_at2(path, "excitation.file_y").label.startswith("excitation.file_y")


def test_the_parsed_records_kept_stay_within_their_byte_budget(tmp_path, monkeypatch):
    budget = 3 * 800 * 8  # three 800-sample records
    kept = Kept(budget, lambda rec: rec.values.nbytes)
    monkeypatch.setattr(records, "PARSED", kept)
    paths = [write_at2(tmp_path / f"r{i}.at2", quake(seed=i)) for i in range(5)]
    for p in paths:
        read_at2(p)
        assert kept.total <= budget
    assert [k[2] for k in kept.order()] == [str(p) for p in paths[2:]]  # the latest three
    read_at2(paths[2])  # read again: the most recent now
    read_at2(paths[0])
    assert [k[2] for k in kept.order()] == [str(p) for p in (paths[4], paths[2], paths[0])]
    big = write_at2(tmp_path / "big.at2", quake(n=4 * 800))
    assert len(read_at2(big).values) == 3200 and not kept.order()  # larger than the budget


def test_at2_with_fortran_double_exponents(tmp_path):
    values = quake()
    path = write_at2(tmp_path / "d.at2", values)
    text = path.read_text().splitlines()
    body = [line.replace("E", "D") for line in text[4:]]
    path.write_text("\n".join(text[:4] + body) + "\n")
    np.testing.assert_allclose(read_at2(path).values, values, rtol=1e-6)


def test_records_read_by_many_threads_at_once(tmp_path, monkeypatch):
    """A Dask worker with several threads reads and evicts records concurrently: every read
    gets its own file's values, and nothing raises."""
    from concurrent.futures import ThreadPoolExecutor

    # a budget of two records: evictions all the time
    monkeypatch.setattr(records, "PARSED", Kept(2 * 800 * 8, lambda rec: rec.values.nbytes))
    paths = [write_at2(tmp_path / f"r{i}.at2", quake(seed=i)) for i in range(6)]
    expected = {str(p): read_at2(p).values.copy() for p in paths}

    def read(i: int) -> bool:
        p = paths[i % len(paths)]
        return bool(np.array_equal(read_at2(p).values, expected[str(p)]))

    # switch threads every microsecond: the check-then-act steps of an unguarded cache race
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        with ThreadPoolExecutor(8) as pool:
            assert all(pool.map(read, range(600)))
    finally:
        sys.setswitchinterval(interval)

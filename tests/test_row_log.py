"""A sweep's row log (deckpound.compare.row_log): whole lines read back, cut or foreign lines
skipped and their cases computed again, never written through a link; sweeps resume from it."""

from __future__ import annotations

import json
import os

import pytest

from deckpound.compare.row_log import LOG_NAME, RowLog
from deckpound.compare.studies.variability import seed_cases, sweep_rows
from deckpound.models.errors import SceneError
from deckpound.models.scene_io import load_scene


def test_rows_are_read_back_and_a_later_line_wins(tmp_path):
    with RowLog(tmp_path / "rows") as log:
        log.append("a", {"status": "success", "peak": 1.0})
        log.append("b", {"status": "doubtful"})
        log.append("a", {"status": "success", "peak": 2.0})
    assert RowLog(tmp_path / "rows").read() == {
        "a": {"status": "success", "peak": 2.0},
        "b": {"status": "doubtful"},
    }
    assert RowLog(tmp_path / "absent").read() == {}


def test_a_cut_or_foreign_line_is_skipped_and_the_next_row_starts_a_line(tmp_path):
    path = tmp_path / LOG_NAME
    whole = json.dumps({"key": "a", "row": {"status": "success"}})
    cut = json.dumps({"key": "b", "row": {"status": "success"}})[:-7]
    foreign = ["not json", "[1, 2]", json.dumps({"key": 3, "row": {}}), "{}"]
    path.write_text("\n".join([whole, *foreign, cut]))  # a kill cut the last line short
    assert RowLog(tmp_path).read() == {"a": {"status": "success"}}
    with RowLog(tmp_path) as log:
        log.append("c", {"status": "unseated"})
    assert RowLog(tmp_path).read() == {"a": {"status": "success"}, "c": {"status": "unseated"}}
    assert path.read_text().endswith("\n") and path.read_text().count(cut) == 1


def test_two_writers_append_whole_lines(tmp_path):
    with RowLog(tmp_path) as one, RowLog(tmp_path) as two:
        for k in range(50):
            (one if k % 2 else two).append(f"k{k}", {"status": "success", "i": k})
    rows = RowLog(tmp_path).read()
    assert sorted(rows) == sorted(f"k{k}" for k in range(50))
    assert all(rows[f"k{k}"]["i"] == k for k in range(50))


def test_a_linked_log_is_refused_and_its_target_left_alone(tmp_path):
    target = tmp_path / "elsewhere.txt"
    target.write_text("mine\n")
    folder = tmp_path / "rows"
    folder.mkdir()
    os.symlink(target, folder / LOG_NAME)
    with pytest.raises(SceneError, match="--cache"), RowLog(folder) as log:
        log.append("a", {"status": "success"})
    assert target.read_text() == "mine\n"


def test_a_sweep_resumes_from_its_log(tmp_path):
    scene = load_scene("saiidi-4span", ["excitation.duration=1.0", "run.duration=1.0"])
    scenes = [sc for _, _, sc in seed_cases(scene, 3)]
    rows_dir = tmp_path / "rows"
    first, computed = sweep_rows(scenes, "compliance", rows_dir, "t", workers=1, progress=False)
    assert computed == 3 and [p.name for p in rows_dir.iterdir()] == [LOG_NAME]
    again, computed = sweep_rows(scenes, "compliance", rows_dir, "t", workers=1, progress=False)
    assert computed == 0 and json.dumps(again) == json.dumps(first)  # NaN fields too
    log = rows_dir / LOG_NAME
    log.write_bytes(log.read_bytes()[:-20])  # a power cut took the end of the last row
    resumed, computed = sweep_rows(scenes, "compliance", rows_dir, "t", workers=1, progress=False)
    assert computed == 1
    assert {i: r["peak_theta"] for i, r in resumed.items()} == {
        i: r["peak_theta"] for i, r in first.items()
    }

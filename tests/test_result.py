"""Common result: columns, units, atomic files, round trip (issue 2)."""

from __future__ import annotations

import gc
import hashlib
import json

import numpy as np
import pytest

from deckpound.models.columns import column_unit, standard_columns
from deckpound.models.fields import to_mapping
from deckpound.models.result import Result, physics_hash, physics_mapping, scene_hash
from deckpound.models.scene_io import load_scene, modified


def _result():
    cols = standard_columns(["bent1", "bent2", "bent3"])
    n = 11
    data = {c: np.linspace(0, 1, n) * (i + 1) / 3.0 for i, c in enumerate(cols)}
    return Result(engine="compliance", columns=data, meta={"steps": 10, "wall_time": 0.5})


def test_standard_columns_and_units():
    cols = standard_columns(["bent1"])
    assert cols[:8] == [
        "t",
        "deck_x_abs",
        "deck_y_abs",
        "deck_theta",
        "seat1_x_abs",
        "seat1_theta",
        "seat2_x_abs",
        "seat2_theta",
    ]
    assert "gap_c4" in cols and "fn_c1" in cols and "ft_c3" in cols and "bent1_fy" in cols
    assert column_unit("deck_theta") == "rad" and column_unit("fn_c2") == "kN"
    assert column_unit("gap_c1") == "m" and column_unit("bent1_fx") == "kN"


def test_write_read_round_trip(tmp_path):
    r = _result()
    csv_path, json_path = r.write(tmp_path)
    assert csv_path.name == "compliance.csv" and json_path.name == "compliance.json"
    back = Result.read(tmp_path, "compliance")
    for k in r.columns:
        np.testing.assert_array_equal(back[k], r[k])
    assert back.meta["units"]["deck_theta"] == "rad" and back.meta["steps"] == 10
    assert not list(tmp_path.glob(".*part"))


def test_interrupted_write_leaves_no_partial_file(tmp_path, monkeypatch):
    r = _result()
    import os

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        r.write(tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_scene_hash_changes_with_any_field(bench_scene):
    other = bench_scene.replace(description="x")
    assert scene_hash(bench_scene) == scene_hash(bench_scene.replace())
    assert scene_hash(bench_scene) != scene_hash(other)


def test_a_scene_is_hashed_once_and_a_changed_copy_anew():
    """scene_hash and physics_hash remember a frozen scene's hashes while it lives (a sweep asks
    for them several times per case); a modified copy is hashed anew, and the answers equal the
    canonical JSON's SHA-256."""

    def sha(mapping):
        text = json.dumps(mapping, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    scene = load_scene("saiidi-4span")
    assert scene_hash(scene) == scene_hash(scene) == sha(to_mapping(scene))
    assert physics_hash(scene) == sha(physics_mapping(scene))
    other = modified(scene, f"deck.mass={scene.deck.mass * 2}")
    assert physics_hash(other) != physics_hash(scene)
    assert physics_hash(other) == sha(physics_mapping(other))
    before = physics_hash(other)
    del other
    gc.collect()
    again = modified(scene, f"deck.mass={scene.deck.mass * 3}")  # may reuse the freed id
    assert physics_hash(again) == sha(physics_mapping(again)) != before

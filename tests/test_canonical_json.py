"""The hashes' canonical JSON is built from remembered texts of the scene's frozen tables
(:func:`deckpound.models.result.canonical_json`): it must be the very text of the plain
definition — ``json.dumps(to_mapping(obj), sort_keys=True, separators=(",", ":"))`` — so that
cache keys do not change, and never a stale text of another scene."""

from __future__ import annotations

import dataclasses
import enum
import json

import pytest

from deckpound.compare.engines import engine_names, get_engine
from deckpound.models.fields import to_mapping
from deckpound.models.result import (
    NON_PHYSICS,
    canonical_json,
    physics_hash,
    physics_mapping,
    scene_hash,
    settings_hash,
)
from deckpound.models.scene_io import builtin_scene_names, load_scene

# a mass every scene can change alone (a deck of segments ties deck.mass to its segments')
VARIANTS = ([], ["excitation.lag=0.05"], ["contact.friction=0.3"], ["seats[0].mass=0.4"])


def plain(obj) -> str:
    return json.dumps(to_mapping(obj), sort_keys=True, separators=(",", ":"))


@pytest.mark.parametrize("name", builtin_scene_names())
@pytest.mark.parametrize("overrides", VARIANTS, ids=["as-is", "lag", "friction", "mass"])
def test_the_text_is_the_plain_definition(name, overrides):
    scene = load_scene(name, overrides)
    assert canonical_json(scene) == plain(scene)
    physics = {k: v for k, v in to_mapping(scene).items() if k not in NON_PHYSICS}
    assert physics == physics_mapping(scene)
    assert canonical_json(physics) == json.dumps(physics, sort_keys=True, separators=(",", ":"))
    for engine in engine_names():
        settings = get_engine(engine).settings_of(scene)
        if dataclasses.is_dataclass(settings):
            assert canonical_json(settings) == plain(settings)


def test_mixed_values_as_json_writes_them():
    value = {"b": (1, 2.5, None), "a": {"z": True, "y": [1e-300, "x\u202e\n"]}, 3: "three"}
    expected = json.dumps(
        {"b": [1, 2.5, None], "a": {"z": True, "y": [1e-300, "x\u202e\n"]}, "3": "three"},
        sort_keys=True,
        separators=(",", ":"),
    )
    assert canonical_json(value) == expected


@pytest.mark.parametrize(
    "value",
    ["", 'x\u202e\n"\\', "é", True, False, 0, -7, 10**30, 2.5, -0.0, 1e-300, 5e300, 0.1, None],
)
def test_a_scalar_as_json_dumps_writes_it(value):
    """The scalars' shortcut (exact built-in types) writes what json.dumps writes."""
    assert canonical_json(value) == json.dumps(value)
    assert canonical_json({"k": [value]}) == json.dumps({"k": [value]}, separators=(",", ":"))


@pytest.mark.parametrize("value", [float("nan"), float("inf"), float("-inf")])
def test_a_non_finite_float_is_the_string_of_its_name(value):
    assert canonical_json(value) == json.dumps(str(value))


def test_an_enum_member_is_its_value():
    class Kind(enum.StrEnum):
        A = "a-kind"

    assert canonical_json({"k": Kind.A}) == '{"k":"a-kind"}'


def test_scenes_sharing_tables_keep_their_own_hashes():
    """Cases of a seed sweep share every table but the excitation: the remembered texts of
    the shared tables must not make two cases equal, nor a case differ from a fresh copy."""
    base = load_scene("saiidi-4span")
    seeds = [  # as the variability study makes them
        base.replace(excitation=dataclasses.replace(base.excitation, seed=base.excitation.seed + i))
        for i in range(4)
    ]
    assert seeds[1].deck is seeds[2].deck  # the tables are shared, the texts remembered
    hashes = [physics_hash(s) for s in seeds]
    assert len(set(hashes)) == 4
    for s, h in zip(seeds, hashes, strict=True):
        fresh = load_scene("saiidi-4span", [f"excitation.seed={s.excitation.seed}"])
        assert physics_hash(fresh) == h and scene_hash(fresh) == scene_hash(s)
    heavier = seeds[1].replace({"deck.mass": seeds[1].deck.mass * 1.01})
    assert physics_hash(heavier) != hashes[1]
    assert settings_hash(get_engine("compliance").settings_of(heavier)) == settings_hash(
        get_engine("compliance").settings_of(seeds[1])
    )

"""Scene description: paper values, TOML round trip, schema, overrides, refusals (issue 2)."""

from __future__ import annotations

import json
import math

import jsonschema
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deckpound.models.errors import SceneError
from deckpound.models.fields import to_mapping
from deckpound.models.plan import plan_of
from deckpound.models.scene_io import (
    apply_overrides,
    builtin_scene_names,
    load_scene,
    scene_from_mapping,
    scene_from_toml,
    scene_schema,
    scene_to_toml,
)


def test_benchmark_paper_values(bench_scene):
    """Every value the paper gives is the paper's (seats: totals split in two)."""
    s = bench_scene
    assert s.deck.mass == 140.5 and s.deck.inertia == 13090.0
    assert s.deck.stick_modulus == 3.0e9  # 3e6 MPa in kN/m^2
    assert math.isclose(sum(x.mass for x in s.seats), 0.65)
    assert math.isclose(sum(x.inertia for x in s.seats), 0.31)
    assert math.isclose(sum(x.kx for x in s.seats), 17513.0)
    assert math.isclose(sum(x.ktheta for x in s.seats), 49934.0)
    assert math.isclose(sum(x.cx for x in s.seats), 213.0)
    assert math.isclose(sum(x.ctheta for x in s.seats), 248.0)
    assert all(x.gap == 0.0127 for x in s.seats)
    assert s.damping.ratio == 0.08
    assert s.sequence.pgas[0] == 0.075 and s.sequence.pgas[-1] == s.sequence.pgas[-2] == 1.0
    assert len(s.sequence.pgas) == 7
    assert s.excitation.longitudinal_ratio == 1.2


def test_benchmark_notes_mark_sources_and_assumptions(bench_scene):
    notes = bench_scene.notes
    for key in ("deck.mass", "deck.inertia", "seats[0].kx", "damping.ratio"):
        assert notes[key].startswith("PAPER")
    for key in (
        "deck.length",
        "deck.width",
        "bents[0].station",
        "bents[1].x.stiffness",
        "contact.stiffness",
        "contact.restitution",
    ):
        assert notes[key].startswith("ASSUMPTION")


def test_benchmark_is_asymmetric(bench_scene):
    """Unequal bents: the centre of transverse stiffness is off the deck centre."""
    k = [b.y.stiffness for b in bench_scene.bents]
    x = plan_of(bench_scene).bent_x
    assert abs(sum(ki * xi for ki, xi in zip(k, x)) / sum(k)) > 0.5  # m


def test_toml_round_trip_exact(bench_scene):
    text = scene_to_toml(bench_scene)
    again = scene_from_toml(text)
    assert again == bench_scene
    assert scene_to_toml(again) == text


@settings(max_examples=40, deadline=None)
@given(
    k=st.floats(1e3, 1e12, allow_nan=False),
    e=st.one_of(st.just(0.0), st.floats(1e-9, 1.0)),
    g=st.one_of(st.just(0.0), st.floats(1e-9, 0.5)),
)
def test_round_trip_arbitrary_floats(bench_scene, k, e, g):
    s = load_scene(
        "saiidi-4span",
        [f"contact.stiffness={k!r}", f"contact.restitution={e!r}", f"seats[1].gap={g!r}"],
    )
    assert scene_from_toml(scene_to_toml(s)) == s
    assert s.contact.stiffness == k and s.seats[1].gap == g


def test_schema_validates_benchmark(bench_scene):
    schema = scene_schema()
    jsonschema.validate(to_mapping(bench_scene), schema)
    bad = to_mapping(bench_scene)
    bad["contact"]["restitution"] = 1.5
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(bad, schema)
    json.dumps(schema)


def test_overrides_dotted_paths():
    s = load_scene(
        "saiidi-4span",
        [
            "contact.stiffness=2e6",
            "bents[1].y.beta=0.3",
            "contact.law=hertz",
            "damping.modes=[1, 2]",
        ],
    )
    assert s.contact.stiffness == 2e6 and s.bents[1].y.beta == 0.3
    assert s.contact.law == "hertz" and s.damping.modes == (1, 2)


BAD = [
    (["deck.mass=0"], "deck.mass", "> 0.0 t"),
    (["deck.inertia=-1"], "deck.inertia", "> 0.0"),
    (["bents[0].x.stiffness=0"], "bents[0].x.stiffness", "kN/m"),
    (["seats[0].gap=-0.02"], "seats[0].gap", ">= 0.0 m, got -0.02"),
    (["contact.restitution=1.3"], "contact.restitution", "<= 1.0"),
    (["contact.friction=-0.1"], "contact.friction", ">= 0.0"),
    (["deck.mass=nan"], "deck.mass", "finite"),
    (["contact.stiffness=inf"], "contact.stiffness", "finite"),
    (["contact.stifness=1"], "contact.stifness", "did you mean 'stiffness'"),
    (["contact.law=hertzz"], "contact.law", "allowed: linear, kelvin-voigt"),
    (["bents[0].station=99"], "bents[0].station", "must lie on the deck"),
    (["excitation.kind=csv"], "excitation.file", "required"),
]


@pytest.mark.parametrize("overrides,field,text", BAD)
def test_bad_values_refused_with_field_and_range(overrides, field, text):
    with pytest.raises(SceneError) as info:
        load_scene("saiidi-4span", overrides)
    msg = str(info.value)
    assert msg.startswith(field) and text in msg and "\n" not in msg


def test_unknown_scene_lists_valid_ones():
    with pytest.raises(SceneError, match="built-in scenes: saiidi-4span"):
        load_scene("no-such-scene")
    assert "saiidi-4span" in builtin_scene_names()


def test_unknown_top_level_key_refused(bench_scene):
    data = to_mapping(bench_scene)
    data["contacts"] = {}
    with pytest.raises(SceneError, match="did you mean 'contact'"):
        scene_from_mapping(data)


def test_notes_must_name_fields(bench_scene):
    data = to_mapping(bench_scene)
    data["notes"]["deck.colour"] = "ASSUMPTION: blue"
    with pytest.raises(SceneError, match="notes.deck.colour"):
        scene_from_mapping(data)


def test_override_index_out_of_range():
    with pytest.raises(SceneError, match="out of range"):
        apply_overrides({"bents": [{}]}, ["bents[3].station=1"])


@pytest.mark.parametrize(
    "overrides,field",
    [
        (["bents[0].name=seat1"], "bents[0].name"),
        (["bents[1].name='a,b'"], "bents[1].name"),
        (["compliance.dt=1e-9"], "compliance.dt"),
        (["run.output_dt=1e-12"], "run.output_dt"),
        (["opensees.substeps=100000"], "opensees.substeps"),
    ],
)
def test_names_and_step_counts_refused(overrides, field):
    """Fuzzing found bent names that collide with seat channels and steps too small to run."""
    with pytest.raises(SceneError) as info:
        load_scene("saiidi-4span", overrides)
    assert str(info.value).startswith(field)

"""Magnitudes a bridge can have (issue 28, item 4): the usual unit slips named with the value
probably meant, absurd values refused unless ``allow_extreme``, and ``--set`` overrides holding
a control character refused. Every built-in scene, test scene and study case passes clean."""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path

import pytest

from deckpound.cli import main
from deckpound.compare.engines import engine_names, get_engine
from deckpound.compare.studies.sensitivity import STUDIES
from deckpound.models import plausibility
from deckpound.models.errors import SceneError
from deckpound.models.magnitudes import STIFFNESS_WARN, magnitude_findings
from deckpound.models.scene_io import builtin_scene_names, load_scene

DATA = Path(__file__).parent / "data"


ALL_ENGINES = [get_engine(name) for name in engine_names()]


def _findings(*overrides):
    return plausibility.check(
        load_scene("saiidi-4span", list(overrides)), engines=[get_engine("nonsmooth")]
    )


def _only(report, level):
    return [(f.field, f.message) for f in report.findings if f.level == level]


# -- nothing that is real is flagged --------------------------------------------------------


@pytest.mark.parametrize("name", builtin_scene_names())
def test_built_in_scenes_have_sound_magnitudes(name):
    scene = load_scene(name)
    assert magnitude_findings(scene) == []
    assert plausibility.check(scene, engines=ALL_ENGINES).ok


@pytest.mark.parametrize("path", sorted(DATA.glob("*.toml")), ids=lambda p: p.name)
def test_test_scenes_have_sound_magnitudes(path):
    scene = load_scene(path)
    assert magnitude_findings(scene) == []
    assert plausibility.check(scene, engines=ALL_ENGINES).ok


@pytest.mark.parametrize(
    "study,name",
    [
        (study, name)
        for study in sorted(STUDIES)
        for name in builtin_scene_names()
        if STUDIES[study].applies_to(load_scene(name))  # the joint study: a deck of segments
    ],
)
def test_no_case_of_a_built_in_study_is_flagged(study, name):
    """The stiffness study sweeps the contact up to 1e8 kN/m, the friction studies μ up to
    0.5: none of their cases is refused or warned about."""
    logging.disable(logging.WARNING)  # the damping study logs the cases an engine leaves out
    try:
        cases = STUDIES[study].cases(load_scene(name), False)
    finally:
        logging.disable(logging.NOTSET)
    assert cases and all(magnitude_findings(c.scene) == [] for c in cases)


# -- unit slips ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "override,field,text",
    [
        ("seats[0].gap=12.7", "seats[0].gap", "it looks like mm, did you mean 0.0127 m?"),
        ("seats[1].gap=50", "seats[1].gap", "did you mean 0.05 m?"),
        ("deck.width=2400", "deck.width", "it looks like mm, did you mean 2.4 m?"),
        ("deck.length=33500", "deck.length", "it looks like mm, did you mean 33.5 m?"),
        ("deck.mass=140500", "deck.mass", "it looks like kg, did you mean 140.5 t?"),
    ],
)
def test_unmistakable_unit_slips_are_refused_with_the_value_meant(override, field, text):
    report = _findings(override)
    ((where, message),) = _only(report, "error")
    assert where == field and text in message
    assert "allow_extreme = true runs it anyway" in message


def test_the_deck_mass_in_kg_names_its_mass_per_area():
    ((_, message),) = _only(_findings("deck.mass=140500"), "error")
    assert "140500 t on a deck of 33.5 m × 2.4 m is 1748 t per m² of deck" in message


@pytest.mark.parametrize(
    "override,field,text",
    [
        ("seats[0].gap=1.0", "seats[0].gap", "1 m is wider than usual"),
        ("deck.width=150", "deck.width", "is it in mm?"),
        ("deck.length=3000", "deck.length", "is it in mm?"),
        ("deck.mass=3000", "deck.mass", "37.31 t per m² of deck"),
        ("contact.stiffness=1e12", "contact.stiffness", "is it in N/m? (kN/m meant: 1e+09)"),
        ("contact.tangential_stiffness=1e14", "contact.tangential_stiffness", "N/m?"),
        ("bents[0].x.stiffness=7e6", "bents[0].x.stiffness", "2.33e+03× the softest"),
        ("contact.friction=1.5", "contact.friction", "μ = 1.5 is more than"),
    ],
)
def test_odd_values_are_warnings(override, field, text):
    report = _findings(override)
    assert report.ok
    found = [m for f, m in _only(report, "warning") if f == field]
    assert len(found) == 1 and text in found[0]


def _bents(factor):
    """--set values scaling every bent spring of the benchmark (stiffness and yield force)
    by ``factor``."""
    springs = ((7e3, 160.0), (3e3, 120.0), (12e3, 200.0))
    return [
        f"bents[{i}].{a}.{name}={value * factor!r}"
        for i, spring in enumerate(springs)
        for a in "xy"
        for name, value in zip(("stiffness", "yield_force"), spring)
    ]


def test_bents_in_n_per_m_give_a_deck_period_no_bridge_has():
    (message,) = [m for f, m in _only(_findings(*_bents(1000.0)), "warning") if f == "bents"]
    assert "0.0193 s (deck_theta)" in message and "in N/m" in message


def test_bents_in_mn_per_m_give_a_deck_period_no_bridge_has():
    (message,) = [m for f, m in _only(_findings(*_bents(0.001)), "warning") if f == "bents"]
    assert "fundamental period in the contact-free model is 19.3 s" in message
    assert "bent stiffnesses in MN/m, or a deck mass in kg?" in message


def test_an_inertia_beyond_bridges_is_one_warning():
    """The inertia's own warning; the 157 s rotation period it gives is not warned again."""
    ((field, message),) = _only(_findings("deck.inertia=1e9"), "warning")
    assert field == "deck.inertia" and "3.962e+04 t·m² of the whole deck mass" in message


def test_stiff_contact_is_never_refused():
    for k in (1e8, 1e10, STIFFNESS_WARN * 10, 1e14):
        assert _findings(f"contact.stiffness={k!r}").ok


# -- absurd magnitudes and allow_extreme -------------------------------------------------------


@pytest.mark.parametrize(
    "override,field,text",
    [
        ("deck.width=1e30", "deck.width", "1e+30 m is beyond any bridge deck (at most 200 m)"),
        ("deck.width=3e5", "deck.width", "300000 m is beyond any bridge deck (at most 200 m)"),
        ("deck.length=1e30", "deck.length", "beyond any bridge deck (at most 10000 m)"),
        ("contact.friction=100", "contact.friction", "μ = 100 is beyond any pair of dry"),
        ("deck.mass=2e12", "deck.mass", "2e+12 t is beyond any bridge (at most 1e+07 t"),
        ("seats[0].mass=1e9", "seats[0].mass", "beyond any bridge"),
        ("bents[1].y.ultimate_displacement=1e5", "bents[1].y.ultimate_displacement", "10000 m"),
        ("initial.deck=[2e4, 0.0, 0.0]", "initial.deck[0]", "beyond any structure"),
    ],
)
def test_absurd_values_are_refused_unless_allow_extreme(override, field, text):
    ((where, message),) = _only(_findings(override), "error")
    assert where == field and text in message and "did you mean" not in message
    forced = magnitude_findings(load_scene("saiidi-4span", [override, "allow_extreme=true"]))
    assert [(level, f) for level, f, _ in forced] == [("warning", field)]
    assert text in forced[0][2] and "run anyway: allow_extreme = true" in forced[0][2]


def test_a_deck_mass_beyond_any_bridge_says_the_kg_it_may_be():
    ((_, message),) = _only(_findings("deck.mass=2e7"), "error")
    assert "2e+07 t is beyond any bridge" in message and "did you mean 20000 t?" in message


def test_allow_extreme_is_a_scene_option_with_its_reason():
    scene = load_scene("saiidi-4span")
    assert scene.allow_extreme is False and "allow_extreme" in scene.notes
    fields = {f.name: f for f in dataclasses.fields(scene)}
    assert "accept magnitudes no bridge has" in fields["allow_extreme"].metadata["doc"]
    assert load_scene("skew-30").notes["allow_extreme"] == scene.notes["allow_extreme"]


def test_enforce_raises_the_slip_and_warns_odd_values():
    with pytest.raises(SceneError, match=r"^seats\[0\]\.gap: 12\.7 m is wider"):
        plausibility.enforce(load_scene("saiidi-4span", ["seats[0].gap=12.7"]), engines=ALL_ENGINES)
    with pytest.warns(plausibility.PlausibilityWarning, match="contact.friction: μ = 1.5"):
        plausibility.enforce(
            load_scene("saiidi-4span", ["contact.friction=1.5"]), engines=ALL_ENGINES
        )


@pytest.mark.parametrize(
    "override",
    ["seats[0].gap=12.7", "deck.mass=140500", "deck.width=1e30", "contact.friction=100"],
)
def test_cli_refuses_slips_and_absurd_values_before_running(override, tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["run", "saiidi-4span", "--engine", "nonsmooth", "-o", str(out)]
    code = main(argv + ["--set", "excitation.duration=0.3", "--set", override])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and not out.exists()
    assert len(err) == 1 and err[0].startswith("deckpound: error: ")


def test_cli_validate_with_allow_extreme_warns_and_passes(capsys):
    with pytest.warns(plausibility.PlausibilityWarning, match="did you mean 0.0127 m"):
        code = main(
            ["scene", "validate", "saiidi-4span", "--set", "seats[0].gap=12.7"]
            + ["--set", "allow_extreme=true"]
        )
    assert code == 0 and ": valid;" in capsys.readouterr().out


# -- control characters in --set -----------------------------------------------------------


@pytest.mark.parametrize(
    "override,shown,where",
    [
        ("deck.length=33.5\nfoo=1", r"'deck.length=33.5\nfoo=1'", "value (U+000A line feed"),
        ("deck.length=33.5\r", r"'deck.length=33.5\r'", "value (U+000D carriage return"),
        ('description="a\x1b[2Jb"', r"""'description="a\x1b[2Jb"'""", "value (U+001B escape"),
        ("deck.len\tgth=33.5", r"'deck.len\tgth=33.5'", "key (U+0009 character tabulation"),
        ("name=x\x85", r"'name=x\x85'", "value (U+0085 control character"),
        ('description="a\u2028b"', r"""'description="a\u2028b"'""", "value (U+2028 line separator"),
    ],
)
def test_an_override_with_a_control_character_is_refused(override, shown, where):
    with pytest.raises(SceneError) as err:
        load_scene("saiidi-4span", [override])
    text = str(err.value)
    assert text.startswith(f"--set: override {shown} holds a control character in its {where}")
    assert text.isprintable()


def test_a_newline_no_longer_drops_the_rest_of_an_override(capsys):
    code = main(["scene", "validate", "saiidi-4span", "--set", "deck.length=33.5\nfoo=1"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "override 'deck.length=33.5\\nfoo=1' holds a control character" in err


def test_printable_unicode_overrides_are_kept():
    scene = load_scene("saiidi-4span", ['description="pont · Brücke · 橋 — ok"'])
    assert scene.description == "pont · Brücke · 橋 — ok"

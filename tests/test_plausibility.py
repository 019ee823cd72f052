"""Plausibility checks (issue 16): steps against the analysis, the natural periods and the
contact duration; the output rate against the analysis and memory."""

from __future__ import annotations

import math

import numpy as np
import pytest

from deckpound.cli import main
from deckpound.compare.engines import engine_names, get_engine
from deckpound.models import plausibility
from deckpound.models.contact_params import effective_masses
from deckpound.models.errors import SceneError
from deckpound.models.mechanics import natural_modes
from deckpound.models.scene_io import load_scene

ALL_ENGINES = [get_engine(name) for name in engine_names()]


def _scene(*overrides):
    return load_scene("saiidi-4span", list(overrides))


def _as_given(*overrides):
    """The benchmark with the engines' steps as given: no shortening to resolve the contact
    (run.steps_per_contact_period = 0), so the checks see the step the test sets."""
    return _scene("run.steps_per_contact_period=0", *overrides)


def _only(report, level):
    return [(f.field, f.message) for f in report.findings if f.level == level]


def test_the_benchmark_is_plausible_for_every_engine(bench_scene):
    report = plausibility.check(bench_scene, engines=ALL_ENGINES)
    assert report.findings == [] and report.ok
    assert report.duration == 20.0
    np.testing.assert_allclose(report.periods, natural_modes(bench_scene).periods)
    m = float(np.min(effective_masses(bench_scene)))
    assert math.isclose(report.contact_duration, math.pi * math.sqrt(m / 1e6), rel_tol=1e-12)


def test_a_step_longer_than_the_record_is_refused_naming_both():
    report = plausibility.check(_as_given("opensees.dt=30"), engines=ALL_ENGINES)
    ((field, message),) = _only(report, "error")
    assert field == "opensees.dt"
    assert "opensees.dt = 30 s" in message and "record length 20 s" in message


def test_a_run_shorter_than_one_step_names_run_duration():
    report = plausibility.check(_scene("run.duration=1e-4"), engines=[get_engine("opensees")])
    ((field, message),) = _only(report, "error")
    assert field == "run.duration" and "run.duration = 0.0001 s" in message
    assert "opensees.dt = 0.0005 s" in message


def test_fewer_than_ten_steps_are_refused():
    s = _scene("excitation.duration=0.3", "nonsmooth.h=0.05")
    ((field, message),) = _only(plausibility.check(s, engines=[get_engine("nonsmooth")]), "error")
    assert field == "nonsmooth.h" and "6 steps" in message and "<= 0.03 s" in message


def test_a_step_beyond_half_the_fundamental_period_is_refused():
    report = plausibility.check(_as_given("opensees.dt=0.4"), engines=[get_engine("opensees")])
    ((field, message),) = _only(report, "error")
    assert field == "opensees.dt" and "T1 = 0.611" in message and "<= 0.3055" in message


def test_few_steps_per_shortest_period_warn():
    report = plausibility.check(_scene("nonsmooth.h=0.003"), engines=[get_engine("nonsmooth")])
    assert report.ok
    ((field, message),) = _only(report, "warning")
    assert field == "nonsmooth.h" and "T = 0.01566 s" in message and "5.22 steps" in message


def test_contacts_shorter_than_a_step_warn_for_compliant_engines_only():
    s = _as_given("contact.stiffness=1e10")
    warned = {f for f, _ in _only(plausibility.check(s, engines=ALL_ENGINES), "warning")}
    assert warned == {"opensees.dt", "compliance.dt"}  # nonsmooth contact is rigid
    message = _only(plausibility.check(s, engines=[get_engine("opensees")]), "warning")[0][1]
    assert "contacts last about 8.93e-06 s" in message and "adaptive" in message
    adaptive = s.replace(compliance=s.compliance.__class__(integrator="adaptive"))
    assert _only(plausibility.check(adaptive, engines=[get_engine("compliance")]), "warning") == []


@pytest.mark.parametrize(
    "output_dt,level,text",
    [
        ("1e25", "error", "single row t = 0"),
        ("100", "error", "single row t = 0"),
        ("2.5", "warning", "stores only 9 rows"),
        ("1e-6", "warning", "output is stored every step"),
    ],
)
def test_output_step(output_dt, level, text):
    report = plausibility.check(
        _scene(f"run.output_dt={output_dt}"), engines=[get_engine("opensees")]
    )
    found = [message for field, message in _only(report, level) if field == "run.output_dt"]
    assert any(text in message for message in found)


def test_output_rows_bounded_before_allocating():
    s = _scene("excitation.duration=600", "opensees.dt=1e-4", "run.output_dt=1e-4")
    ((field, message),) = _only(plausibility.check(s, engines=[get_engine("opensees")]), "error")
    assert field == "run.output_dt" and "6e+06 rows" in message and ">= 0.0003 s" in message


def test_only_the_engines_run_are_checked():
    s = _as_given("opensees.dt=30")
    assert plausibility.check(s, engines=[get_engine("nonsmooth")]).ok
    with pytest.raises(SceneError, match="opensees.dt"):
        plausibility.enforce(s, engines=ALL_ENGINES)


def test_enforce_warns_then_raises():
    with pytest.warns(UserWarning, match="nonsmooth.h"):
        plausibility.enforce(_scene("nonsmooth.h=0.003"), engines=[get_engine("nonsmooth")])


def test_cli_validate_and_run_use_the_checks(capsys, tmp_path):
    with pytest.warns(UserWarning, match="nonsmooth.h = 0.003 s resolves the shortest"):
        code = main(["scene", "validate", "saiidi-4span", "--set", "nonsmooth.h=0.003"])
    out, err = capsys.readouterr()
    assert code == 0 and ": valid;" in out
    code = main(
        [
            "run",
            "saiidi-4span",
            "--set",
            "run.output_dt=100",
            "--engine",
            "nonsmooth",
            "-o",
            str(tmp_path / "out"),
        ]
    )
    _, err = capsys.readouterr()
    assert code == 2 and err.startswith("deckpound: error: run.output_dt: run.output_dt = 100 s")
    assert not (tmp_path / "out").exists()

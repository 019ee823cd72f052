"""A sequence driven by a real record applies its labels; sequence inputs validated up front.

Issue 13: with an AT2 or CSV record the sequence drove the unscaled record under the labels
0.075 g ... 1 g. Issue 16: sequence PGAs above 5 g and carried damage that breaks a bent's
backbone validated and then stopped half-way naming the wrong field.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from _record_helpers import quake, record_scene, write_at2

from deckpound.models.errors import SceneError
from deckpound.models.excitation import support_motion
from deckpound.models.motion import G
from deckpound.models.scene_io import load_scene
from deckpound.models.sequence import check_runs, initial_state, scene_for_run


@pytest.fixture
def unequal_pair(tmp_path):
    """Two components of one station, 7999 and 7995 samples at 0.005 s, peaks 0.44 / 0.31 g."""
    px = write_at2(tmp_path / "x.at2", quake(7999, 0.005, peak=0.44, seed=1), dt=0.005)
    py = write_at2(tmp_path / "y.at2", quake(7995, 0.005, peak=0.31, seed=2), dt=0.005)
    return px, py


def test_sequence_applies_every_label_to_a_real_unequal_pair(unequal_pair):
    """Done-when of issue 13: applied PGAs equal the labels (to 1 %), measured on the motion."""
    scene = record_scene("at2", *unequal_pair)
    state = initial_state(scene)
    peaks_y = []
    for pga in scene.sequence.pgas:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = support_motion(scene_for_run(scene, pga, state))
        applied = m.provenance["applied_pga"]
        assert applied["y"] == pytest.approx(pga, rel=0.01)
        assert applied["x"] == pytest.approx(1.2 * pga, rel=0.01)
        measured_y = max(np.max(np.abs(m.acc(c))) for c in m.channels if c.endswith("_y")) / G
        assert measured_y == pytest.approx(applied["y"], rel=1e-12)
        padded, scaled = m.provenance["warnings"]  # the tolerance, then the scaling said
        assert "padded with zeros" in padded
        assert scaled.startswith("excitation.scaling: the record is scaled, longitudinal (x) × ")
        assert f"g to {pga:g} g)" in scaled
        peaks_y.append(np.max(np.abs(m.disp["bent1_y"])))
    # the runs differ as their labels do (issue 13: runs 4-7 gave the same response)
    np.testing.assert_allclose(
        np.array(peaks_y) / peaks_y[-1],
        np.array(scene.sequence.pgas) / scene.sequence.pgas[-1],
        rtol=1e-12,
    )


def test_sequence_through_an_engine_labels_what_was_applied(unequal_pair):
    """End to end with the compliance engine on a shortened record: each run's scene, as the
    sequence runner built it, drives the record at its label."""
    from deckpound.compare.studies.sequence_run import run_sequence

    scene = record_scene(
        "at2",
        *unequal_pair,
        None,
        "sequence.pgas=[0.25, 1.0]",
        "run.duration=1.0",
        "compliance.dt=0.002",
        "run.output_dt=0.01",
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        runs = run_sequence(scene, "compliance")
        assert [r.result.ok for r in runs] == [True, True]
        for run in runs:
            applied = support_motion(run.scene).provenance["applied_pga"]
            assert applied["y"] == pytest.approx(run.pga, rel=0.01)
    # elastic here: the transverse bent force follows the label (1.0 / 0.25 = 4)
    forces = [np.max(np.abs(r.result["bent1_fy"])) for r in runs]
    assert forces[1] == pytest.approx(4 * forces[0], rel=0.05)


@pytest.mark.parametrize("scaling", ["none", "factor"])
def test_sequence_refuses_a_record_it_cannot_scale_to_its_labels(unequal_pair, scaling):
    """scaling = none or factor would drive one motion under seven labels: refused before any
    run (not relabelled: the sequence's labels are its PGAs)."""
    scene = record_scene("at2", *unequal_pair, None, f"excitation.scaling={scaling}")
    with pytest.raises(
        SceneError,
        match=rf"^excitation.scaling: is '{scaling}', but a sequence "
        "scales the record to each run's PGA",
    ):
        scene_for_run(scene, 0.5, initial_state(scene))
    check_runs(record_scene("at2", *unequal_pair))  # the default, pga, is accepted


def test_sequence_pga_above_5g_refused_at_validation_naming_the_run():
    with pytest.raises(
        SceneError,
        match=r"^sequence.pgas\[2\]: gives a transverse PGA of 6 g; "
        r"at most 5 g is allowed unless excitation.allow_extreme",
    ):
        load_scene("saiidi-4span", ["sequence.pgas=[0.5, 1.0, 6.0]"])
    with pytest.raises(
        SceneError,
        match=r"^sequence.pgas\[1\]: gives a longitudinal PGA of 5.4 g "
        r"= 4.5 g x longitudinal_ratio 1.2",
    ):
        load_scene("saiidi-4span", ["sequence.pgas=[0.5, 4.5]"])
    forced = load_scene(
        "saiidi-4span", ["sequence.pgas=[0.5, 6.0]", "excitation.allow_extreme=true"]
    )
    assert forced.sequence.pgas[1] == 6.0


def test_extreme_label_refused_unless_forced():
    with pytest.raises(SceneError, match=r"^excitation.pga: gives a longitudinal PGA of 5.4 g"):
        load_scene("saiidi-4span", ["excitation.pga=4.5"])
    m = support_motion(
        load_scene(
            "saiidi-4span",
            ["excitation.pga=6", "excitation.duration=2", "excitation.allow_extreme=true"],
        )
    )
    assert m.provenance["applied_pga"] == {"x": pytest.approx(7.2), "y": pytest.approx(6.0)}


def test_carried_stiffness_breaking_a_backbone_names_the_bent():
    scene = load_scene("saiidi-4span")
    state = initial_state(scene)
    soft = list(state.stiffness)
    soft[1] = (100.0, soft[1][1])  # F_y / k = 120 / 100 = 1.2 m > ultimate 0.3 m
    state = dataclasses.replace(state, stiffness=tuple(soft))
    with pytest.raises(
        SceneError,
        match=r"^bents\[1\].x.ultimate_displacement: is 0.3 m, but the "
        r"stiffness carried into the 0.75 g run, 100 kN/m, puts "
        r"the yield displacement at 1.2 m beyond it",
    ):
        scene_for_run(scene, 0.75, state)


@pytest.mark.parametrize(
    "override,field,text",
    [
        ("excitation.scaling=none", "excitation.scaling", "applies to records"),
        (
            "excitation.time_scale=0.5",
            "excitation.time_scale",
            "generated records are made at model",
        ),
        (
            "excitation.processing=highpass",
            "excitation.processing",
            "has its own baseline correction",
        ),
        ("excitation.scale=2", "excitation.scale", "is used only with scaling = 'factor'"),
    ],
)
def test_record_options_refused_where_they_would_do_nothing(override, field, text):
    with pytest.raises(SceneError, match=rf"^{field}: .*{text}"):
        load_scene("saiidi-4span", [override])


def test_at2_unit_is_g(unequal_pair):
    with pytest.raises(SceneError, match=r"^excitation.acc_unit: must be 'g' for AT2 records"):
        record_scene("at2", *unequal_pair, None, "excitation.acc_unit=cm/s^2")


def test_incoherence_refused_for_records(unequal_pair):
    with pytest.raises(
        SceneError,
        match=r"^excitation.incoherence: applies to the synthetic "
        r"record only",
    ):
        record_scene("at2", *unequal_pair, None, "excitation.incoherence=0.3")


def test_benchmark_notes_give_a_reason_for_every_record_default(bench_scene):
    """Each new excitation option carries its default's reason in the scene's notes."""
    for key in (
        "scaling",
        "scale",
        "time_scale",
        "processing",
        "acc_unit",
        "allow_extreme",
        "highpass",
    ):
        note = bench_scene.notes[f"excitation.{key}"]
        assert note.startswith("ASSUMPTION: ") and len(note) > 40, key

"""The report's sentences come from its tables (issue 13, item 4): change a table, the sentence
changes; read a sentence back, it agrees with the table. Also the inputs' account (provenance,
notes) and the friction mechanism on results whose answer is known."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from _report_helpers import check_clauses, claims, expand_runs, mu_values

from deckpound.compare.mechanism import mechanism_row, stick_states, tangential_output
from deckpound.compare.report import inputs as report_inputs
from deckpound.compare.report import text as report_text
from deckpound.compare.report.text import (
    direction,
    friction_effect,
    headline_sentences,
    runs_text,
    sequence_friction_sentences,
    study_friction_effect,
    study_friction_sentences,
)
from deckpound.compare.studies.sensitivity import StartState
from deckpound.models.result import Result
from deckpound.models.scene_io import load_scene

# peak rotations [rad] of a 7-run sequence without / with friction, per engine: friction
# raises runs 6-7, lowers 3 and 5, leaves 1, 2, 4 (the benchmark's pattern)
PLAIN = [0.46e-3, 0.93e-3, 1.43e-3, 1.40e-3, 3.47e-3, 2.64e-3, 2.72e-3]
ROUGH = [0.46e-3, 0.92e-3, 1.36e-3, 1.41e-3, 2.63e-3, 6.06e-3, 6.94e-3]
PGAS = [0.075, 0.15, 0.25, 0.5, 0.75, 1.0, 1.0]


def sequence(plain=PLAIN, rough=ROUGH, engines=("opensees", "compliance")) -> pd.DataFrame:
    rows = []
    for e in engines:
        for mu, thetas in ((0.0, plain), (0.2, rough)):
            for k, (pga, th) in enumerate(zip(PGAS, thetas)):
                rows.append(
                    {
                        "run": k + 1,
                        "pga": pga,
                        "engine": e,
                        "case": e if mu == 0 else f"{e} μ=0.2",
                        "mu": mu,
                        "friction_mode": "stick" if mu else "none",
                        "peak_theta": th,
                        "gap_closures": 0 if k == 0 else 4 * k,
                        "status": "success",
                    }
                )
    return pd.DataFrame(rows)


def truth(seq: pd.DataFrame, engine: str) -> dict[int, float]:
    g = seq[seq["engine"] == engine]
    plain = g[g["mu"] == 0].set_index("run")["peak_theta"]
    rough = g[g["mu"] > 0].set_index("run")["peak_theta"]
    return (rough / plain).to_dict()


def test_runs_text_and_directions():
    assert runs_text([6, 7]) == "runs 6–7"
    assert runs_text([4, 1, 2]) == "runs 1–2 and 4"
    assert runs_text([3, 5, 7]) == "runs 3, 5 and 7"
    assert runs_text([5]) == "run 5"
    assert expand_runs("runs 1–2 and 4") == {1, 2, 4}
    assert (direction(1.03), direction(0.97), direction(1.01), direction(np.nan)) == (
        "raises",
        "lowers",
        "unchanged",
        "undetermined",
    )
    assert mu_values("μ = 0.1, 0.2 and 0.5") == {0.1, 0.2, 0.5}


def test_sequence_sentences_agree_with_the_table():
    seq = sequence()
    sentences = sequence_friction_sentences(friction_effect(seq))
    assert len(sentences) == 2
    s = sentences[0]
    assert s.startswith(
        "OpenSees: friction (μ = 0.2, with sticking) raises the peak rotation "
        "in runs 6–7 (×2.30–2.55), lowers it in runs 3 and 5 "
        "(×0.758–0.951)"
    )
    for engine, sentence in zip(("opensees", "compliance"), sentences):
        check_clauses(claims(sentence), truth(seq, engine), expand_runs)


def test_changing_the_table_changes_the_sentences():
    """No templated number: other inputs, other words and numbers."""
    before = sequence_friction_sentences(friction_effect(sequence()))
    rough = list(ROUGH)
    rough[6] = 2.0e-3  # friction now lowers run 7
    rough[4] = 4.0e-3  # and raises run 5
    seq = sequence(rough=rough)
    after = sequence_friction_sentences(friction_effect(seq))
    assert after != before
    assert "raises the peak rotation in runs 5–6" in after[0]
    assert "lowers it in runs 3 and 7" in after[0]
    check_clauses(claims(after[0]), truth(seq, "opensees"), expand_runs)
    h0 = headline_sentences(sequence(), friction_effect(sequence()), 7, "opensees")
    h1 = headline_sentences(seq, friction_effect(seq), 7, "opensees")
    assert any("raises the peak rotation in OpenSees and compliance clone (×2.55)" in s for s in h0)
    assert any(
        "lowers the peak rotation in OpenSees and compliance clone (×0.735)" in s for s in h1
    )
    assert any("2.72 mrad" in s for s in h0) and not any("6.94 mrad" in s for s in h1)


def test_headline_names_the_virgin_state_when_it_goes_the_other_way():
    seq = sequence()
    study = pd.DataFrame(
        [
            {
                "label": f"{e} mu={mu}",
                "engine": e,
                "mu": mu,
                "state": "virgin",
                "status": "success",
                "peak_theta": th,
            }
            for e in ("compliance", "nonsmooth")
            for mu, th in ((0.0, 3.62e-3), (0.2, 3.24e-3))
        ]
    )
    virgin = study_friction_effect(study)
    lines = headline_sentences(seq, friction_effect(seq), 7, "opensees", virgin=virgin)
    line = next(s for s in lines if s.startswith("From the virgin state"))
    assert "lowers the peak rotation in compliance clone and nonsmooth (×0.895)" in line
    assert line.endswith("the opposite of the carried state.")
    check_clauses(
        claims(line),
        {"compliance": 3.24 / 3.62, "nonsmooth": 3.24 / 3.62},
        lambda t: {"compliance" if "compliance" in k else k for k in expand_engines(t)},
    )


def expand_engines(text: str) -> set[str]:
    return {k.replace(" clone", "") for k in text.replace(" and ", ", ").split(", ")}


def test_study_sentences_agree_with_the_study_table():
    rows = []
    for e, base in (("compliance", 2.72e-3), ("nonsmooth", 2.71e-3)):
        for mu, f in ((0.0, 1.0), (0.1, 1.9), (0.2, 2.55), (0.3, 1.01), (0.5, 0.9)):
            rows.append(
                {
                    "label": f"{e} mu={mu}",
                    "engine": e,
                    "mu": mu,
                    "state": "run7",
                    "peak_theta": base * f,
                    "status": "success",
                }
            )
    table = pd.DataFrame(rows)
    sentences = study_friction_sentences(study_friction_effect(table))
    assert "raises the peak rotation at μ = 0.1 and 0.2 (×1.90–2.55)" in sentences[0]
    assert "lowers it at μ = 0.5 (×0.900)" in sentences[0]
    for engine, s in zip(("compliance", "nonsmooth"), sentences):
        g = table[table["engine"] == engine].set_index("mu")["peak_theta"]
        check_clauses(claims(s), {mu: g[mu] / g[0.0] for mu in g.index if mu > 0}, mu_values)


def test_state_sentences_name_the_state_and_its_numbers():
    scene = load_scene("saiidi-4span")
    seats = tuple(dataclasses.replace(s, gap=g) for s, g in zip(scene.seats, (0.007, 0.0184)))
    bents = (
        dataclasses.replace(
            scene.bents[0], x=dataclasses.replace(scene.bents[0].x, stiffness=3500.0)
        ),
    ) + scene.bents[1:]
    carried = StartState("run7", scene.replace(seats=seats, bents=bents), scene, 7, "opensees")
    s = report_text.state_sentence(carried)
    assert s.startswith(
        "Starts from the state carried into run 7 by the opensees sequence "
        "(after runs 1–6): gaps 7.00 mm at seat 1 and 18.40 mm at seat 2, bent "
        "stiffness 50–100 % of the scene's"
    )
    v = report_text.state_sentence(StartState("virgin", scene, scene))
    assert v.startswith("Starts from the virgin state: the scene as given (gaps 12.70 mm")


# -- inputs: provenance and notes -----------------------------------------------------------


def at2_provenance() -> dict:
    return {
        "kind": "at2",
        "files": {
            "x": {"path": "/data/CCN090.AT2", "sha256": "ab" * 32, "bytes": 123456},
            "y": {"path": "/data/CCN360.AT2", "sha256": "cd" * 32, "bytes": 123400},
        },
        "header": {"x": "Northridge-01, Century City CC North, 090"},
        "npts": {"x": 7999, "y": 7995},
        "dt_record": 0.01,
        "time_scale": 0.5,
        "dt": 0.005,
        "duration": 39.99,
        "processing": "none",
        "scaling": "pga",
        "target_pga": {"x": 1.2, "y": 1.0},
        "scale_factor": {"x": 4.2, "y": 3.1},
        "applied_pga": {"x": 1.2, "y": 1.0},
        "seed": None,
        "warnings": ["x has 4 samples more than y; y padded with zeros"],
    }


def test_an_at2_scene_is_described_by_its_files_never_as_synthetic():
    scene = load_scene("saiidi-4span")
    text = " ".join(report_inputs.excitation_sentences(scene, at2_provenance()))
    assert "PEER AT2 record files" in text and "/data/CCN090.AT2" in text
    assert "ab" * 32 in text and "cd" * 32 in text
    assert "Time scale 0.5 (record step 0.01 s, model step 0.005 s)" in text
    assert "39.99 s" in text and "padded with zeros" in text
    assert "synthetic" not in text.lower() and "20 s" not in text
    synth = " ".join(
        report_inputs.excitation_sentences(
            scene,
            {
                "kind": "synthetic",
                "seed": 1994,
                "processing": "generator X",
                "duration": 20.0,
                "dt": 0.005,
            },
        )
    )
    assert "synthetic" in synth and "seed 1994" in synth and "20 s" in synth


def test_scaling_sentence_flags_labels_not_applied():
    runs = [
        (1, 0.5, {"applied_pga": {"x": 0.6, "y": 0.5}}),
        (2, 1.0, {"applied_pga": {"x": 1.2, "y": 0.9}}),
    ]
    s = report_inputs.scaling_sentence(report_inputs.record_table(runs), 1.2)
    assert "differs from the run's label by more than 1 % in run(s) 2 (up to 10" in s
    ok = report_inputs.scaling_sentence(report_inputs.record_table(runs[:1]), 1.2)
    assert ok.startswith("Applied transverse PGA equals the run's label in every run")


def test_notes_are_the_authors_and_stale_ones_are_marked():
    builtin = load_scene("saiidi-4span")
    scene = load_scene("saiidi-4span", ["excitation.duration=5.0"])
    table = report_inputs.notes_table(scene, builtin)
    row = table[table["field"] == "excitation.duration"].iloc[0]
    assert row["value"] == "5" and "20 s" in row["note"]
    assert row["written_for"] == "20 (built-in saiidi-4span)"
    assert (table[table["field"] != "excitation.duration"]["written_for"] == "").all()


# -- mechanism ---------------------------------------------------------------------------------


def _result(scene, theta, ft1=None, fn1=None, states=None) -> Result:
    n = len(theta)
    t = np.arange(n) * 0.01
    cols = {"t": t, "deck_theta": np.asarray(theta, float)}
    for c in range(1, 5):
        cols[f"gap_c{c}"] = np.full(n, 0.01)
        cols[f"fn_c{c}"] = np.zeros(n)
        cols[f"ft_c{c}"] = np.zeros(n)
    if fn1 is not None:
        cols["fn_c1"] = np.asarray(fn1, float)
        cols["gap_c1"] = np.where(cols["fn_c1"] > 0, -1e-4, 0.01)
        cols["ft_c1"] = np.asarray(ft1, float)
    if states is not None:
        for c in range(1, 5):
            cols[f"state_c{c}"] = np.asarray(states, float) if c == 1 else np.zeros(n)
    return Result("test", cols)


def test_friction_impulse_sign_and_stick_share():
    """Corner c1 at x = −L/2 pushed by +y friction: moment −(L/2)·ft (clockwise), towards a
    negative peak rotation; half of the contact rows at the Coulomb limit (slip)."""
    scene = load_scene("saiidi-4span", ["contact.friction=0.2", "contact.friction_mode=stick"])
    n = 101
    theta = -np.sin(np.linspace(0, np.pi, n)) * 1e-3  # one negative excursion
    fn = np.where((np.arange(n) > 20) & (np.arange(n) <= 60), 100.0, 0.0)
    ft = np.where(np.arange(n) <= 40, 20.0, 10.0) * (fn > 0)  # 20 = μ·fn: slip, then stick
    row = mechanism_row(_result(scene, theta, ft, fn), scene)
    half = scene.deck.length / 2
    # trapezoid over the excursion, rows 0..50: ramp 20→21, 20 kN over 21..40, ramp, 10 kN to 50
    impulse = 0.5 * 20 * 0.01 + 19 * 20 * 0.01 + 0.5 * 30 * 0.01 + 9 * 10 * 0.01
    assert row["friction_impulse"] == pytest.approx(half * impulse, rel=1e-12)
    assert row["t_start"] == 0.0 and row["t_peak"] == pytest.approx(0.5)
    assert row["stick_source"] == "coulomb"
    assert row["stick_share_c1"] == pytest.approx(0.5, abs=0.03)
    assert row["first_contact_row_c1"] == pytest.approx(0.21)
    assert row["corners_at_peak"] == "c1" and row["face_at_peak"] == "seat 1"
    flipped = mechanism_row(_result(scene, -theta, ft, fn), scene)
    assert flipped["friction_impulse"] == pytest.approx(-row["friction_impulse"])


def test_state_columns_win_and_zero_tangential_output_is_not_read():
    scene = load_scene("saiidi-4span", ["contact.friction=0.2", "contact.friction_mode=stick"])
    n = 50
    fn = np.full(n, 100.0)
    states = np.where(np.arange(n) < 10, 1.0, 2.0)
    r = _result(scene, np.zeros(n), np.full(n, 20.0), fn, states)
    got, source = stick_states(r, 0.2)
    assert source == "state" and np.mean(got[:, 0] == 1) == pytest.approx(0.2)
    silent = _result(scene, np.linspace(0, 1e-3, n), np.zeros(n), fn)
    assert tangential_output(silent, 0.2) == (False, 1.0)
    row = mechanism_row(silent, scene)
    assert np.isnan(row["friction_impulse"]) and row["stick_source"] == "n/a"
    said = report_text.unread_impulse_sentence(pd.DataFrame([{**row, "engine": "opensees"}]))
    assert "OpenSees (ft = 0 in 100 % of the rows with a normal force)" in said
    read = mechanism_row(_result(scene, np.zeros(n), np.full(n, 20.0), fn), scene)
    assert report_text.unread_impulse_sentence(pd.DataFrame([{**read, "engine": "opensees"}])) == ""


def test_impulse_agreement_reads_the_right_excursion():
    effect = pd.DataFrame(
        [
            {"engine": "compliance", "run": 5, "direction": "lowers", "ratio": 0.76},
            {"engine": "compliance", "run": 7, "direction": "raises", "ratio": 2.55},
            {"engine": "compliance", "run": 6, "direction": "raises", "ratio": 2.3},
        ]
    )
    mech = pd.DataFrame(
        [
            {
                "engine": "compliance",
                "run": 5,
                "mu": 0.2,
                "friction_impulse": 5.0,
                "friction_impulse_ref": -12.0,
            },
            {
                "engine": "compliance",
                "run": 7,
                "mu": 0.2,
                "friction_impulse": 505.0,
                "friction_impulse_ref": 3.0,
            },
            {
                "engine": "compliance",
                "run": 6,
                "mu": 0.2,
                "friction_impulse": -1.0,
                "friction_impulse_ref": 1.0,
            },
        ]
    )
    (s,) = report_text.impulse_agreement_sentences(effect, mech)
    assert "of the 3 run(s)" in s and "explains the change in 2" in s
    assert "(runs 5 and 7)" in s and "it does not in run 6" in s


def test_sticking_sentence_pairs_stick_with_slip():
    rows = [
        {
            "label": f"compliance {m} mu={mu}",
            "engine": "compliance",
            "mu": mu,
            "friction_mode": m,
            "peak_theta": th,
            "status": "success",
        }
        for mu, th_slip, th_stick in (
            (0.1, 3.277e-3, 3.298e-3),
            (0.2, 3.138e-3, 3.243e-3),
            (0.4, 3.004e-3, 3.045e-3),
        )
        for m, th in (("slip", th_slip), ("stick", th_stick))
    ]
    s = report_text.mode_pair_sentence(pd.DataFrame(rows))
    # issue 12: the sticking study now has two sticking models, named in the sentence
    assert s == (
        "Against sliding only, the project's stick law raises the peak rotation at "
        "μ = 0.2 (×1.03) and changes it by less than 2 % at μ = 0.1 and 0.4."
    )
    check_clauses(
        claims(s), {0.1: 3.298 / 3.277, 0.2: 3.243 / 3.138, 0.4: 3.045 / 3.004}, mu_values
    )
    assert report_text.mode_pair_sentence(pd.DataFrame(rows[:1])) == ""
    c2d = [
        dict(r, friction_mode="contact2d", peak_theta=r["peak_theta"] * 0.9)
        for r in rows
        if r["friction_mode"] == "stick"
    ]
    s2 = report_text.mode_pair_sentence(pd.DataFrame(rows + c2d))
    assert s2.startswith(s + " Against sliding only, OpenSees's zeroLengthContact2D algorithm")


def _unseating_frag(medians: dict[str, float], beta: float = 0.3) -> pd.DataFrame:
    rows = []
    for engine, median in medians.items():
        for state, factor in (("unseating", 1.0), ("peak θ_d > 0.005 rad", 0.9)):
            for method in ("ida", "msa"):
                rows.append(
                    {
                        "engine": engine,
                        "limit_state": state,
                        "method": method,
                        "median": median * factor,
                        "beta": beta,
                        "cases": 48,
                        "left_out": 0,
                    }
                )
    return pd.DataFrame(rows)


def test_unseating_sentence_says_same_when_the_medians_agree_within_their_error():
    """|ln(m_a/m_b)| against sqrt(β_a² + β_b²)/sqrt(n): 2 % apart with 8 records is the same."""
    from deckpound.compare.report.unseating import approach_sentence

    s = approach_sentence(_unseating_frag({"compliance": 2.80, "nonsmooth": 2.86}), 8)
    assert s.count("does not measurably change") == 2
    assert "2.8 g (compliance) against 2.86 g (nonsmooth)" in s
    assert "15 % standard error of 8 records" in s  # sqrt(0.3² + 0.3²)/sqrt(8) = 0.15


def test_unseating_sentence_names_the_engine_that_unseats_earlier():
    from deckpound.compare.report.unseating import approach_sentence

    s = approach_sentence(_unseating_frag({"compliance": 2.0, "nonsmooth": 3.0}), 8)
    assert "does not" not in s and s.count("the compliance engine reaches it at lower") == 2
    assert "41 % apart, beyond the 15 %" in s  # ln(3/2) = 0.405
    flipped = approach_sentence(_unseating_frag({"compliance": 3.0, "nonsmooth": 2.0}), 8)
    assert "the nonsmooth engine reaches it at lower" in flipped
    # many more records shrink the error: the same 2 % becomes a difference
    close = _unseating_frag({"compliance": 2.80, "nonsmooth": 2.86})
    assert "does not" not in approach_sentence(close, 2000)


def test_unseating_sentence_without_two_fits_says_it_cannot_judge():
    from deckpound.compare.report.unseating import approach_sentence

    frag = _unseating_frag({"compliance": 2.8, "nonsmooth": 2.9})
    frag.loc[frag["engine"] == "nonsmooth", "median"] = np.nan
    assert "cannot be judged" in approach_sentence(frag, 8)

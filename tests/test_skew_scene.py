"""The built-in scene ``skew-30`` (issue 15, item 4): the benchmark with a 30° skew, every
skew-specific value noted as an assumption, and runnable by every registered engine through
``deckpound run skew-30 --engine E``."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from deckpound.cli import main
from deckpound.compare.engines import engine_names
from deckpound.models.result import read_table
from deckpound.models.scene_io import builtin_scene_names, load_scene


def test_skew_30_is_the_benchmark_with_a_30_degree_skew():
    assert "skew-30" in builtin_scene_names()
    sk, bench = load_scene("skew-30"), load_scene("saiidi-4span")
    assert sk.deck.skew == 30.0 and bench.deck.skew == 0.0
    same = dataclasses.replace(
        sk,
        name=bench.name,
        description=bench.description,
        deck=dataclasses.replace(sk.deck, skew=0.0),
        notes=bench.notes,
    )
    assert same == bench
    # every skew-related choice carries its reason, marked as an assumption
    for key in (
        "deck.skew",
        "deck.length",
        "deck.width",
        "deck.inertia",
        "seats[0].gap",
        "seats[1].gap",
        "seats[0].inertia",
    ):
        assert sk.notes[key].startswith("ASSUMPTION:"), key
    assert "degrees" in sk.notes["deck.skew"] and "normal" in sk.notes["seats[0].gap"]
    assert "slide along the bridge axis" in sk.notes["seats[0].mass"]


@pytest.mark.parametrize("engine", engine_names())
def test_run_skew_30_with_every_engine(engine, tmp_path, capsys):
    code = main(
        [
            "run",
            "skew-30",
            "--engine",
            engine,
            "--set",
            "run.duration=2.0",
            "-o",
            str(tmp_path / engine),
        ]
    )
    out = capsys.readouterr()
    assert code == 0, out.err[-2000:]
    data = read_table(tmp_path / engine / f"{engine}.csv")
    assert np.all(np.isfinite(data["deck_theta"]))
    assert data["t"].iloc[-1] == pytest.approx(2.0)


def test_skew_study_table_on_a_tiny_scene(tmp_path):
    """The skew study's own columns on a 1 s record: every angle × friction × engine, the
    first corner and the impulse share of the acute corners, stick + slip = 1 with friction
    (NaN without), and OpenSees = its clone without friction (same step, same model)."""
    from deckpound.compare.studies.sensitivity import run_study
    from deckpound.compare.studies.skew import skew_headlines

    tiny = load_scene(
        "saiidi-4span", ["excitation.duration=1.0", "run.output_dt=0.01", "nonsmooth.h=0.001"]
    )
    table, _ = run_study("skew", tiny, tmp_path, quick=True, workers=2, progress=False)
    assert (table["status"] == "success").all()
    assert sorted(table["skew"].unique()) == [0.0, 30.0, 60.0]
    assert len(table) == 3 * 2 * len(engine_names())
    assert set(table["first_corner"]) <= {"c1", "c2", "c3", "c4"}
    assert ((table["share_acute"] >= 0) & (table["share_acute"] <= 1)).all()
    fr = table[table["mu"] > 0]
    known = fr[fr["stick_share"].notna()]
    assert set(known["engine"]) >= {"nonsmooth"}
    np.testing.assert_allclose(known["stick_share"] + known["slip_share"], 1.0, rtol=1e-12)
    # OpenSees reads f_T after the commit, which zeroes a sliding zeroLengthContact2D's force;
    # since issue 12 the study's friction is contact2d, which the clone reports the same way
    assert fr[fr["stick_share"].isna()]["stick_source"].str.startswith("n/a").all()
    assert table[table["mu"] == 0]["stick_share"].isna().all()
    free = table[table["mu"] == 0].set_index(["engine", "skew"])
    for phi in (0.0, 30.0, 60.0):
        a, b = (
            free.loc[("opensees", phi), "peak_theta"],
            free.loc[("compliance", phi), "peak_theta"],
        )
        assert a == pytest.approx(b, rel=1e-6)
    words = skew_headlines(table)
    assert len(words) == 2 * len(engine_names()) + 1 and "First corner" in words[-1]

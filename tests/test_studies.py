"""Studies, cache, resume, Dask and the report on a tiny scene (issue 6); the state a study
starts from (issue 13, item 4)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from deckpound.cli import main
from deckpound.compare import cases as cases_mod
from deckpound.compare.cases import Case, run_cases
from deckpound.compare.result_cache import ResultCache
from deckpound.compare.studies.sensitivity import (
    STUDIES,
    STUDY_NAMES,
    Study,
    friction_cases,
    run_study,
    start_state,
)
from deckpound.compare.studies.sequence_run import run_sequence
from deckpound.models.errors import SceneError
from deckpound.models.scene_io import load_scene, modified

TINY = [
    "excitation.duration=1.0",
    "excitation.pga=1.0",
    "run.output_dt=0.01",
    "opensees.dt=0.001",
    "compliance.dt=0.001",
    "nonsmooth.h=0.001",
]


@pytest.fixture(scope="module")
def tiny():
    return load_scene("saiidi-4span", TINY)


def _cases(tiny):
    return [
        Case(f"opensees g={g}", "opensees", modified(tiny, f"seats[0].gap={g}"), {"gap": g})
        for g in (0.005, 0.0127)
    ]


def test_cache_miss_then_hit(tiny, tmp_path):
    cache = ResultCache(tmp_path)
    first = run_cases(_cases(tiny), cache=cache, workers=1, progress=False)
    assert cache.misses == 2 and cache.hits == 0
    again = ResultCache(tmp_path)
    second = run_cases(_cases(tiny), cache=again, workers=1, progress=False)
    assert again.hits == 2 and again.misses == 0
    for k in first:
        np.testing.assert_allclose(
            second[k]["deck_theta"], first[k]["deck_theta"], rtol=0, atol=1e-15
        )


def test_resume_after_interrupted_run(tiny, tmp_path, monkeypatch):
    """A run killed after its first case resumes with that case from the cache."""
    real = cases_mod.run_case
    calls = []

    def dying(engine, scene, *options):
        calls.append(scene)
        if len(calls) == 2:
            raise KeyboardInterrupt  # the user kills the study during case 2
        return real(engine, scene, *options)

    monkeypatch.setattr(cases_mod, "run_case", dying)
    with pytest.raises(KeyboardInterrupt):
        run_cases(_cases(tiny), cache=ResultCache(tmp_path), workers=1, progress=False)
    assert len([p for p in tmp_path.iterdir() if not p.name.startswith(".")]) == 1
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # nothing half-written
    monkeypatch.setattr(cases_mod, "run_case", real)
    cache = ResultCache(tmp_path)
    out = run_cases(_cases(tiny), cache=cache, workers=1, progress=False)
    assert cache.hits == 1 and cache.misses == 1 and len(out) == 2


def test_local_dask_cluster_equals_serial(tiny, tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    serial = run_cases(_cases(tiny), workers=1, progress=False)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        parallel = run_cases(_cases(tiny), scheduler=cluster.scheduler_address, progress=False)
    for k in serial:
        np.testing.assert_array_equal(parallel[k]["deck_theta"], serial[k]["deck_theta"])


@pytest.mark.parametrize("name", list(STUDIES))
def test_each_study_on_tiny_scene(name, tiny, tmp_path):
    if not STUDIES[name].applies_to(tiny):  # the joint study: the tiny deck of segments
        tiny = load_scene("two-frame", TINY)
    table, results = run_study(name, tiny, tmp_path, quick=True, workers=2, progress=False)
    assert (tmp_path / f"{name}.csv").is_file() and (tmp_path / f"{name}.png").stat().st_size > 5000
    assert not (tmp_path / f"{name}.pdf").exists()  # PDF only when asked
    assert len(table) == len(results) >= 2
    assert (table["status"] == "success").all(), table[["label", "status"]]
    assert np.all(np.isfinite(table["peak_theta"]))
    assert (table["state"] == "virgin").all()  # the scene as given unless a state is asked
    back = pd.read_csv(tmp_path / f"{name}.csv")
    assert list(back["label"]) == list(table["label"])
    assert "peak_theta [rad]" in back.columns
    assert "peak_y_rel [m]" in back.columns or "peak_fn_joint [kN]" in back.columns


SEQ2 = TINY + ["sequence.pgas=[0.5, 1.0]"]


def test_a_study_from_a_carried_state(tmp_path):
    """--state run2: the gaps and bent stiffness the sequence carries into run 2, at run 2's
    PGA; stated in the table and the file names."""
    scene = load_scene("saiidi-4span", SEQ2)
    cache = ResultCache(tmp_path / "cache")
    runs = run_sequence(scene, "compliance", tmp_path / "cache")
    state = start_state(scene, "run2", engine="compliance", cache_folder=tmp_path / "cache")
    assert state.carried and state.run == 2 and state.label == "run2"
    assert state.scene.excitation.pga == 1.0
    assert [s.gap for s in state.scene.seats] == list(runs[1].state.gaps)
    assert state.scene.seats[0].gap != scene.seats[0].gap
    strongest = start_state(scene, "strongest", sequence=runs)  # from a sequence already run
    assert (strongest.label, strongest.engine) == ("run2", "compliance")
    assert strongest.scene == runs[1].scene == state.scene
    table, _ = run_study(
        "friction",
        scene,
        tmp_path / "out",
        quick=True,
        cache=cache,
        workers=1,
        progress=False,
        state=state,
        formats=("pdf",),
    )
    assert (table["state"] == "run2").all()
    np.testing.assert_allclose(table["gap1_start"], runs[1].state.gaps[0], rtol=0)
    assert (tmp_path / "out" / "friction_run2.csv").is_file()
    assert (tmp_path / "out" / "friction_run2.pdf").is_file()
    virgin, _ = run_study(
        "friction", scene, tmp_path / "out", quick=True, cache=cache, workers=1, progress=False
    )
    assert (virgin["gap1_start"] == 0.0127).all()
    assert not np.allclose(virgin["peak_theta"], table["peak_theta"])


def test_state_names_are_checked():
    scene = load_scene("saiidi-4span", SEQ2)
    assert start_state(scene).label == "virgin" and not start_state(scene).carried
    with pytest.raises(SceneError, match="runs 1 to 2"):
        start_state(scene, "run3", engine="compliance")
    with pytest.raises(SceneError, match="virgin"):
        start_state(scene, "after-run-2")


def test_study_cli_with_a_state(tmp_path, capsys):
    out = tmp_path / "s"
    args = [
        "study",
        "friction",
        "saiidi-4span",
        "--quick",
        "--state",
        "run2",
        "--state-engine",
        "compliance",
        "-o",
        str(out),
        "--no-progress",
        "--workers",
        "1",
    ]
    assert main(args + [a for o in SEQ2 for a in ("--set", o)]) == 0
    printed = capsys.readouterr().out
    assert "run2" in printed and "peak_theta [rad]" in printed
    assert (out / "friction_run2.csv").is_file() and (out / "friction_run2.png").is_file()


def test_a_study_registered_the_old_way_runs_from_the_virgin_state():
    """Another engineer adds studies as Study(name, title, cases, x): still valid, virgin only."""
    s = Study("extra", "An extra study", friction_cases, "mu")
    assert not s.carried and s.unit == ""
    assert {n for n, st in STUDIES.items() if st.carried} >= {
        "friction",
        "sticking",
        "stiffness",
        "law",
    }


def test_damping_study_cases_and_sentences(tiny):
    """Issue 12: the damping study crosses members × stiffness × mass for every engine that
    expresses the case (the nonsmooth engine refuses the committed and current tangents), and
    its sentences are the table's numbers."""
    from deckpound.compare.studies.damping import damping_cases, damping_headlines

    cases = damping_cases(tiny, quick=False)
    labels = {c.params["damping"] for c in cases}
    assert len(labels) == 3 * 3 * 2 - 4  # members none: the stiffness does nothing
    by_engine = {
        e: {c.params["damping"] for c in cases if c.engine == e}
        for e in ("opensees", "compliance", "nonsmooth")
    }
    assert by_engine["opensees"] == by_engine["compliance"] == labels
    assert all("initial" in lab or lab.startswith("none") for lab in by_engine["nonsmooth"])
    table = pd.DataFrame(
        [
            {
                "engine": "opensees",
                "damping": "bents·initial·absolute",
                "peak_theta": 2e-3,
                "peak_fn": 1000.0,
                "gap_closures": 10,
                "status": "success",
            },
            {
                "engine": "opensees",
                "damping": "bents+seats·initial·absolute",
                "peak_theta": 2.2e-3,
                "peak_fn": 700.0,
                "gap_closures": 5,
                "status": "success",
            },
        ]
    )
    (s,) = damping_headlines(table)
    assert s == (
        "opensees, from bents·initial·absolute: peak rotation 2 mrad ×1 "
        "(bents·initial·absolute) to ×1.1 (bents+seats·initial·absolute); peak gap "
        "force 1 MN ×0.7 (bents+seats·initial·absolute) to ×1 "
        "(bents·initial·absolute); gap closures 10 (5–10)."
    )
    # no contact in the reference case (a short or weak record): no ratio to a zero force
    table.loc[0, "peak_fn"] = 0.0
    (s,) = damping_headlines(table)
    assert "peak gap force 0 MN in the reference case, 0–0.7 MN over the choices;" in s


def test_the_study_help_names_every_registered_study(capsys):
    """The CLI starts without pandas, so ``deckpound study --help`` names the studies in words
    instead of reading the registry: they must be the same set."""
    assert main(["study", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    listed = text.split("positional arguments: NAME ", 1)[1].split(" SCENE", 1)[0]
    named = {w.strip(" ,") for w in listed.replace(" or ", ", ").split(",")}
    assert named == {*STUDY_NAMES, "variability"}

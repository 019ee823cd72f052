"""Studies, cache, resume, Dask and the report on a tiny scene (issue 6)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from deckpound.compare import cases as cases_mod
from deckpound.compare.cases import Case, ResultCache, run_cases
from deckpound.compare.studies import STUDIES, modified, run_study
from deckpound.models.scene_io import load_scene

TINY = ["excitation.duration=1.0", "excitation.pga=1.0", "run.output_dt=0.01",
        "opensees.dt=0.001", "compliance.dt=0.001", "nonsmooth.h=0.001"]


@pytest.fixture(scope="module")
def tiny():
    return load_scene("saiidi-4span", TINY)


def _cases(tiny):
    return [Case(f"opensees g={g}", "opensees", modified(tiny, f"seats[0].gap={g}"), {"gap": g})
            for g in (0.005, 0.0127)]


def test_cache_miss_then_hit(tiny, tmp_path):
    cache = ResultCache(tmp_path)
    first = run_cases(_cases(tiny), cache=cache, workers=1, progress=False)
    assert cache.misses == 2 and cache.hits == 0
    again = ResultCache(tmp_path)
    second = run_cases(_cases(tiny), cache=again, workers=1, progress=False)
    assert again.hits == 2 and again.misses == 0
    for k in first:
        np.testing.assert_allclose(second[k]["deck_theta"], first[k]["deck_theta"], rtol=0,
                                   atol=1e-15)


def test_resume_after_interrupted_run(tiny, tmp_path, monkeypatch):
    """A run killed after its first case resumes with that case from the cache."""
    real = cases_mod.run_case
    calls = []

    def dying(engine, scene):
        calls.append(scene)
        if len(calls) == 2:
            raise KeyboardInterrupt  # the user kills the study during case 2
        return real(engine, scene)

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
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        parallel = run_cases(_cases(tiny), scheduler=cluster.scheduler_address, progress=False)
    for k in serial:
        np.testing.assert_array_equal(parallel[k]["deck_theta"], serial[k]["deck_theta"])


@pytest.mark.parametrize("name", list(STUDIES))
def test_each_study_on_tiny_scene(name, tiny, tmp_path):
    table, results = run_study(name, tiny, tmp_path, quick=True, workers=2, progress=False)
    assert (tmp_path / f"{name}.csv").is_file() and (tmp_path / f"{name}.png").stat().st_size > 5000
    assert (tmp_path / f"{name}.pdf").stat().st_size > 1000
    assert len(table) == len(results) >= 2
    assert (table["status"] == "success").all(), table[["label", "status"]]
    assert np.all(np.isfinite(table["peak_theta"]))
    back = pd.read_csv(tmp_path / f"{name}.csv")
    assert list(back["label"]) == list(table["label"])

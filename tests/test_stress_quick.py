"""A quick subset of the stress grid (compare/bench/stress.py): every cell ends finished with finite
output or with a clear failure status — never NaN silently, never a hang — and the table and
heat maps are written."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from deckpound.compare.bench.stress import run_stress
from deckpound.models.scene_io import load_scene

CELLS = [
    dict(stiffness=1e10, dt=1e-2),
    dict(gap=0.0),
    dict(friction=0.8),
    dict(restitution=0.0),
    dict(pga=2.0),
]
CLEAR = {"success", "failed", "timeout", "crashed", "refused"}


def _nonsmooth_available() -> bool:
    try:
        return importlib.util.find_spec("deckpound.analytic.nonsmooth.engine") is not None
    except ImportError:
        return False


@pytest.mark.parametrize(
    "engine",
    [
        "opensees",
        "compliance",
        pytest.param(
            "nonsmooth",
            marks=pytest.mark.skipif(
                not _nonsmooth_available(),
                reason="deckpound.analytic.nonsmooth.engine not written yet",
            ),
        ),
    ],
)
def test_stress_quick_cells_end_clearly(engine, tmp_path):
    table = run_stress(
        load_scene("saiidi-4span"),
        tmp_path,
        engines=(engine,),
        duration=0.5,
        timeout=45.0,
        progress=False,
        cells=CELLS,
    )
    print(
        table[
            [
                "engine",
                "stiffness",
                "dt",
                "pga",
                "gap",
                "friction",
                "restitution",
                "status",
                "finite",
                "max_penetration",
                "energy_error",
                "failed_time",
                "wall",
                "message",
            ]
        ].to_string()
    )
    assert len(table) == len(CELLS)
    for _, r in table.iterrows():
        assert r["status"] in CLEAR, (r["status"], r["message"])  # "non-finite" = bug
        if r["status"] == "success":
            assert r["finite"] and np.isclose(r["t_end"], 0.5), r.to_dict()
        elif r["status"] == "failed":
            assert r["message"] and np.isfinite(r["failed_time"]), r.to_dict()
        else:
            assert r["message"], r.to_dict()
    if engine in ("opensees", "compliance"):  # these two are expected to finish here
        assert (table["status"] == "success").all(), table[["status", "message"]]
    assert (tmp_path / "stress.csv").is_file()
    assert (tmp_path / "stress_stiffness_dt.png").is_file()
    assert (tmp_path / "stress_sweeps.png").is_file()

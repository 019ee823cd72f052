"""One way to run an engine (issue 29, item 4): every entry point — ``dp.run``, the registry's
``run_engine``, ``get_engine(name).run`` and the engines' own ``run_compliance`` /
``run_nonsmooth`` / ``run_opensees`` — gives the same complete Result, whose folder every command
accepts (``deckpound export-vtk`` needs the scene in the metadata)."""

from __future__ import annotations

import numpy as np
import pytest

import deckpound as dp
from deckpound.analytic.compliance.engine import run_compliance
from deckpound.analytic.nonsmooth.engine import run_nonsmooth
from deckpound.cli import main as cli_main
from deckpound.compare.engines import get_engine, run_engine
from deckpound.models.fields import to_mapping
from deckpound.models.result import Result
from deckpound.opensees_build.engine import run_opensees

OWN = {"compliance": run_compliance, "nonsmooth": run_nonsmooth, "opensees": run_opensees}
VOLATILE = {"wall_time", "loop_time", "compile_time", "us_per_step", "build_time"}


def _entry_points(name, scene):
    return {
        "dp.run": lambda: dp.run(scene, engine=name),
        "run_engine": lambda: run_engine(name, scene),
        "get_engine().run": lambda: get_engine(name).run(scene),
        f"run_{name}": lambda: OWN[name](scene),
    }


@pytest.mark.parametrize("name", ["compliance", "nonsmooth", "opensees"])
def test_every_entry_point_gives_the_same_complete_result(tmp_path, name):
    scene = dp.load_scene("saiidi-4span", set={"run.duration": 0.3})
    results = {how: run() for how, run in _entry_points(name, scene).items()}
    first = results["dp.run"]
    assert first.meta["scene"] == to_mapping(scene)
    for how, result in results.items():
        assert result.columns.keys() == first.columns.keys(), how
        for column, values in result.columns.items():
            assert np.array_equal(values, first.columns[column], equal_nan=True), (how, column)
        stable = {k: v for k, v in result.meta.items() if k not in VOLATILE}
        assert stable == {k: v for k, v in first.meta.items() if k not in VOLATILE}, how
        folder = tmp_path / how.replace("()", "").replace(".", "_")
        result.write(folder)
        assert Result.read(folder, name).meta["scene"] == to_mapping(scene)
        assert (
            cli_main(["export-vtk", str(folder), "-o", str(tmp_path / f"vtk-{folder.name}")]) == 0
        )

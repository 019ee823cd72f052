"""The Tcl export runs in a plain Tcl OpenSees interpreter and reproduces the in-process run (issue 3).

The interpreter is the `opensees` PyPI package (the xara/OpenSeesRT build, `python -m opensees
script.tcl`), an OpenSees independent of openseespy: agreement to round-off shows the exported
script is complete (model, records, analysis and the result writer).
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from deckpound.engines import run_engine
from deckpound.opensees_build.export import export_script
from tests_helpers_scene import short_benchmark

pytestmark = pytest.mark.skipif(importlib.util.find_spec("opensees") is None,
                                reason="the Tcl OpenSees interpreter (pip package 'opensees') "
                                       "is not installed; ./run.sh test installs it")


def test_tcl_script_reproduces_in_process_run(tmp_path):
    scene = short_benchmark(2.0)
    script = export_script(scene, "tcl", tmp_path / "model.tcl")
    proc = subprocess.run([sys.executable, "-m", "opensees", str(script)], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    tcl = pd.read_csv(tmp_path / "model.csv")
    ref = run_engine("opensees", scene)
    assert len(tcl) == len(ref.t)
    worst = 0.0
    for col in tcl.columns:
        peak = max(np.max(np.abs(ref[col])), 1e-12)
        worst = max(worst, np.max(np.abs(tcl[col].to_numpy() - ref[col])) / peak)
    print(f"largest deviation Tcl vs in-process: {worst:.2e} of the column peak")
    assert worst < 1e-9
    assert np.max(np.abs(ref["fn_c1"]) + np.abs(ref["fn_c3"])) > 0  # the run pounds

"""Golden command log, script export and model refusals of deckpound.opensees_build."""

from __future__ import annotations

import dataclasses as dc
import shlex
import subprocess
import sys
import warnings

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("openseespy.opensees")

from deckpound.models.errors import SceneError  # noqa: E402
from deckpound.models.scene import RunSettings  # noqa: E402
from deckpound.models.scene_io import load_scene  # noqa: E402
from deckpound.opensees_build import engine, export  # noqa: E402
from deckpound.opensees_build.model import gap_mapping  # noqa: E402
from deckpound.opensees_build.ops import ArrayArg, OpsSession, render_commands  # noqa: E402


@pytest.fixture(scope="module")
def bench():
    return load_scene("saiidi-4span")


def test_golden_command_log(bench):
    """The benchmark's command log is frozen; regenerate with
    ``python -m deckpound.opensees_build.export --regen-golden`` after a deliberate change."""
    expected = export.golden_path().read_text()
    got = export.golden_text(bench)
    assert got == expected, "command log changed: review and run --regen-golden"


def test_ops_session_wipes_and_tags():
    with OpsSession() as ops:
        assert ops.tag("node", "a") == 1 and ops.tag("node", "b") == 2
        assert ops.tag("node", "a") == 1 and ops.tag("element", "a") == 1
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        ops.node(ops.tag("node", "a"), 0.0, 1.5)
        assert ops.raw.getNodeTags() == [1]
        ops.nodeDisp(1)                       # queries are not logged
        with pytest.raises(RuntimeError):
            with OpsSession():
                pass
        assert [c.name for c in ops.log] == ["wipe", "model", "node"]
        assert render_commands(ops.log, "py").splitlines()[-1] == "ops.node(1, 0.0, 1.5)"
        assert render_commands(ops.log, "tcl").splitlines()[-1] == "node 1 0.0 1.5"
    with OpsSession() as ops:
        assert ops.raw.getNodeTags() == []


@pytest.fixture(scope="module")
def exported(bench, tmp_path_factory):
    sc = bench.replace(run=RunSettings(duration=1.0, output_dt=bench.run.output_dt))
    folder = tmp_path_factory.mktemp("export")
    py = export.export_script(sc, "py", folder / "model.py")
    tcl = export.export_script(sc, "tcl", folder / "model.tcl")
    return sc, py, tcl


def test_exported_python_reproduces_in_process_run(exported):
    sc, py, _ = exported
    r = engine.run_opensees(sc)
    cp = subprocess.run([sys.executable, str(py)], capture_output=True, text=True, timeout=120)
    assert cp.returncode == 0, cp.stderr[-2000:]
    df = pd.read_csv(py.with_suffix(".csv"), dtype=float)
    # the script writes the engine's own columns (the epilogue adds relative displacements and
    # bent deformations in process)
    assert list(df.columns) == [c for c in r.columns if c in df.columns]
    assert list(df.columns)[:8] == list(r.columns)[:8] and len(df.columns) > 30
    assert len(df) == len(r.t)
    for c in df.columns:
        a, b = df[c].to_numpy(), r[c]
        assert np.all(np.abs(a - b) <= 1e-12 * max(1.0, np.abs(b).max())), c


def _tcl_tokens(line: str) -> list[str]:
    return shlex.split(line.replace("[file join $here ", "").replace("]", ""))


def test_exported_tcl_holds_the_same_commands(exported):
    sc, _, tcl = exported
    text = tcl.read_text()
    body = text.split("# --- model and analysis ---\n")[1].split("# --- end model ---")[0]
    lines = body.splitlines()
    log = engine.command_log(sc)
    assert len(lines) == len(log)
    for line, cmd in zip(lines, log):
        if cmd.name == "#":
            assert line.startswith("#")
            continue
        tok = _tcl_tokens(line)
        assert tok[0] == cmd.name
        k = 1
        for a in cmd.args:
            if isinstance(a, ArrayArg):
                assert tok[k] == "-filePath"
                vals = np.loadtxt(tcl.parent / tok[k + 1])
                assert np.array_equal(vals, a.values)
                k += 2
            elif isinstance(a, str):
                assert tok[k] == a
                k += 1
            else:
                assert float(tok[k]) == float(a), (line, a)
                k += 1
        assert k == len(tok), line
    assert "analyze 1 $dt" in text and "wipeAnalysis" in text


# -- sign convention and refusals ---------------------------------------------------------------

def test_gap_mapping_signs(bench):
    for c in range(4):
        spec = gap_mapping(bench, c, deck_node=100, seat_node=200, mat_tag=7)
        assert spec.material == "ElasticPPGap"
        assert spec.args[2] < 0 and spec.args[3] == -bench.seats[0].gap
        assert (spec.i_node, spec.j_node) == ((200, 100) if c < 2 else (100, 200))
    sc = bench.replace(contact=dc.replace(bench.contact, law="bilinear"))
    spec = gap_mapping(sc, 0, 1, 2, 3)
    assert spec.material == "ImpactMaterial" and spec.args[3] < 0 and spec.args[4] < 0


@pytest.mark.parametrize("law", ["hertz", "hertz-damp"])
def test_refuses_hertz(bench, law):
    sc = bench.replace(contact=dc.replace(bench.contact, law=law))
    with pytest.raises(SceneError, match="OpenSees cannot express"):
        engine.run_opensees(sc)


def test_refuses_slip_friction(bench):
    sc = bench.replace(contact=dc.replace(bench.contact, friction=0.2, friction_mode="slip"))
    with pytest.raises(SceneError, match="cannot express 'slip'"):
        engine.run_opensees(sc)


@pytest.mark.parametrize("law", ["bilinear", "kelvin-voigt"])
def test_refuses_law_with_friction(bench, law):
    sc = bench.replace(contact=dc.replace(bench.contact, law=law, friction=0.2,
                                          friction_mode="stick"))
    with pytest.raises(SceneError, match="cannot combine"):
        engine.run_opensees(sc)


def test_warns_about_options_that_do_nothing(bench):
    sc = bench.replace(contact=dc.replace(bench.contact, geometry="nonlinear"),
                       run=RunSettings(duration=0.01))
    with pytest.warns(UserWarning, match="geometry"):
        engine.run_opensees(sc)
    sc = bench.replace(contact=dc.replace(bench.contact, friction=0.3),
                       run=RunSettings(duration=0.01))
    with pytest.warns(UserWarning, match="friction"):
        engine.run_opensees(sc)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        engine.run_opensees(bench.replace(run=RunSettings(duration=0.01)))

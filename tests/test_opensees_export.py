"""Golden command log, script export and model refusals of deckpound.opensees_build."""

from __future__ import annotations

import dataclasses as dc
import hashlib
import json
import shlex
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from deckpound.models.columns import column_names, column_unit
from deckpound.models.engine_contract import engine_columns
from deckpound.models.plan import plan_of
from deckpound.models.result import read_table

pytest.importorskip("openseespy.opensees")

import importlib.util
import os
import stat

from deckpound.models.errors import SceneError
from deckpound.models.result import scene_hash
from deckpound.models.scene_io import load_scene
from deckpound.models.scene_settings import RunSettings
from deckpound.opensees_build import engine, export, recorders
from deckpound.opensees_build.gaps import gap_mapping
from deckpound.opensees_build.ops import ArrayArg, OpsSession, render_commands

#: the benchmark's golden command log (written by tools/golden_files.py)
GOLDEN = Path(__file__).resolve().parents[1] / "data" / "golden" / "saiidi-4span.opensees.log"


@pytest.fixture(scope="module")
def bench():
    return load_scene("saiidi-4span")


def test_golden_command_log(bench):
    """The benchmark's command log is frozen; regenerate with ``python tools/golden_files.py
    golden`` after a deliberate change."""
    expected = GOLDEN.read_text()
    got = export.golden_text(bench)
    assert got == expected, "command log changed: review and run tools/golden_files.py golden"


def test_ops_session_wipes_and_tags():
    with OpsSession() as ops:
        assert ops.tag("node", "a") == 1 and ops.tag("node", "b") == 2
        assert ops.tag("node", "a") == 1 and ops.tag("element", "a") == 1
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        ops.node(ops.tag("node", "a"), 0.0, 1.5)
        assert ops.raw.getNodeTags() == [1]
        ops.nodeDisp(1)  # queries are not logged
        with pytest.raises(RuntimeError), OpsSession():
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


def test_exported_python_csv_reproduces_in_process_run(exported, tmp_path):
    """The optional --csv output is deckpound's own CSV, the sampled columns bit for bit."""
    sc, py, _ = exported
    r = engine.run_opensees(sc)
    cp = subprocess.run(
        [sys.executable, str(py), "--csv", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    df = read_table(tmp_path / "opensees.csv")
    # the result's columns; the derived ones (relative, bent deformations) are compared to
    # round-off in tests/test_export_columns.py
    assert list(df.columns) == column_names(plan_of(sc))
    assert df.attrs["units"] == {c: column_unit(c) for c in df.columns}  # in the header
    assert len(df) == len(r.t)
    for c in engine_columns(plan_of(sc)):
        assert np.array_equal(df[c].to_numpy(), r[c]), c


def _tcl_tokens(line: str) -> list[str]:
    return shlex.split(line.replace("[file join $dataDir ", "").replace("]", ""))


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
                vals = np.loadtxt(tcl.parent / "model_data" / tok[k + 1])
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


def test_data_folder_manifest(exported):
    """One data folder; the manifest names every record's support, dof, dt, unit, count and
    SHA-256, and they agree with the files and the commands."""
    sc, py, tcl = exported
    folder = py.parent / "model_data"
    manifest = json.loads((folder / "manifest.json").read_text())
    assert sorted(p.name for p in folder.iterdir()) == sorted(
        [r["file"] for r in manifest["records"]] + ["manifest.json"]
    )
    assert manifest["scene"] == {"name": sc.name, "sha256": scene_hash(sc)}
    assert manifest["units"]["force"] == "kN" and manifest["units"]["mass"] == "t"
    recs = manifest["records"]
    assert len(recs) == 2 * (2 * len(sc.bents) + 2)
    log = engine.command_log(sc)
    imposed = {(c.args[0], c.args[1]) for c in log if c.name == "imposedMotion"}
    for r in recs:
        data = (folder / r["file"]).read_bytes()
        assert hashlib.sha256(data).hexdigest() == r["sha256"]
        assert len(data.splitlines()) == r["count"]
        assert (r["node"], r["dof"]) in imposed
        assert r["unit"] == {"displacement": "m", "velocity": "m/s"}[r["quantity"]]
        assert r["dt"] == 0.005 and r["file"] in tcl.read_text() and r["file"] in py.read_text()
    chans = {(r["channel"], r["node_name"], r["dof"]) for r in recs}
    assert ("bent2_y", "table bent2", 2) in chans and ("seat2_x", "actuator2", 1) in chans
    assert [m["column"] for m in manifest["recorders"]["columns"]] == engine_columns(plan_of(sc))


def test_header_states_units_tags_signs_damping_and_fallback(exported):
    """The header is generated from the commands: every tag of the registry, the Rayleigh
    factors and the elements that take them, the analysis and the fallback."""
    sc, py, tcl = exported
    text = tcl.read_text()
    head = text.split("\nset here ")[0]
    assert all(line.startswith("#") or not line for line in head.splitlines())
    with OpsSession() as ops:
        engine.build(ops, sc)
        tags = {k: ops.tags(k) for k in ops.kinds()}
        log = list(ops.log)
    flat = " ".join(line.lstrip("# ") for line in head.splitlines())
    for kind, reg in tags.items():
        for name, tag in reg.items():
            assert f"{kind} {tag} '{name}'" in head, (kind, name)
    ray = next(c for c in log if c.name == "rayleigh")
    assert (
        f"alphaM = {ray.args[0]:.12g}" in flat
        and f"betaKinit (initial stiffness) = {ray.args[2]:.12g}" in flat
    )
    # issue 12: the seat springs carry no Rayleigh damping by default (damping.members = bents)
    assert "-doRayleigh 1: 1 bent bent1, 2 bent bent2, 3 bent bent3 " in flat
    assert "zeroLengthContact2D): 4 seat1 spring, 5 seat1 dashpot" in flat
    assert "Units: force kN, length m, mass t" in head
    assert f"scene sha256: {scene_hash(sc)}" in head
    assert "test NormDispIncr 1e-10 50; algorithm Newton; integrator Newmark 0.5 0.25" in flat
    assert "sub-steps of dt/10" in flat and "fn = -stress" in flat
    assert "gap_c1 = 0.0127 + gap_c1.out[1]" in head and "fn_c3 = -fn_c3.out[1]" in head
    # the fallback is code in the script, not only words
    assert "proc defineAnalysis" in text and "set h [expr {$dt / $nSub}]" in text
    assert "def run_steps(" in py.read_text()


def test_recorder_step_separates_output_steps_from_sub_steps():
    """Simulate OpenSees' recorder rule (with and without its 1e-5 relative tolerance) over a
    run whose steps 7 and 10 fall back to 10 sub-steps: the -dT of :func:`recorder_step` records
    exactly the output steps; -dT = stride*dt (the obvious choice) does not."""
    plan = {"dt": 5e-4, "stride": 5, "fallback": "substep", "substeps": 10}

    def recorded_steps(dT, rtol):
        times, t = [0.0], 0.0
        for n in range(1, 41):
            subs = 10 if n in (7, 10) else 1
            for _ in range(subs):
                t += plan["dt"] / subs
                times.append(t)
        out, nxt = [], 0.0
        for t in times:
            if t - nxt >= -rtol * dT:
                out.append(t)
                nxt = t + dT
        return out

    expect = [n * plan["dt"] for n in range(0, 41, 5)]
    dT = recorders.recorder_step(plan)
    for rtol in (0.0, 1e-5):
        assert np.allclose(recorded_steps(dT, rtol), expect, rtol=0, atol=1e-12)
    naive = recorded_steps(plan["stride"] * plan["dt"], 0.0)
    assert len(naive) != len(expect) or not np.allclose(naive, expect, rtol=0, atol=1e-12)
    with pytest.raises(SceneError, match="run.output_dt"):
        recorders.recorder_step({**plan, "stride": 1000, "substeps": 1000})


def test_recorded_velocities_are_the_newmark_velocities(bench, tmp_path):
    """The velocity recorders hold the absolute velocities: with an output every step,
    Newmark's average-acceleration rule gives (u[n+1] - u[n])/dt = (v[n] + v[n+1])/2."""
    sc = bench.replace(run=RunSettings(duration=0.3, output_dt=bench.opensees.dt))
    py = export.export_script(sc, "py", tmp_path / "v.py")
    cp = subprocess.run(
        [sys.executable, str(py), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    dt = sc.opensees.dt
    for col, vcol in (
        ("deck_x_abs", "deck_vx_abs"),
        ("deck_y_abs", "deck_vy_abs"),
        ("deck_theta", "deck_omega"),
        ("seat1_x_abs", "seat1_vx_abs"),
        ("seat2_x_abs", "seat2_vx_abs"),
    ):
        u = np.loadtxt(tmp_path / "out" / f"{col}.out")[:, 1]
        v = np.loadtxt(tmp_path / "out" / f"{vcol}.out")[:, 1]
        assert len(u) == len(v) == 601
        err = np.abs(np.diff(u) / dt - 0.5 * (v[1:] + v[:-1])).max()
        assert np.abs(v).max() > 0 and err <= 1e-8 * np.abs(v).max(), (col, err)


def test_opsvis_plots_the_exported_model(exported):
    """Smoke test: the exported Python model is a normal OpenSees model for opsvis. Supports
    are not drawn: opsvis 1.3.7 only knows the fixity lists [1, 2, 3], [1, 2], [1], [2] in 2-D
    and fails on these nodes, whose imposed motions are constraints too ([2, 3, 1])."""
    opsvis = pytest.importorskip("opsvis")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, py, _ = exported
    spec = importlib.util.spec_from_file_location("exported_model", py)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    with OpsSession() as ops:  # owns (and wipes) the global domain around the plot
        module.build()
        nodes, eles = ops.raw.getNodeTags(), ops.raw.getEleTags()
        ax = opsvis.plot_model(node_supports=False)
        labels = {t.get_text() for t in ax.texts}
        plt.close("all")
    assert len(nodes) == 18 and len(eles) == 13
    assert {str(n) for n in nodes} | {str(e) for e in eles} <= labels


def test_export_replaces_files_and_never_writes_through_a_symlink(bench, tmp_path):
    """Re-exporting replaces the script and the whole data folder; a symlink at the script path
    is refused (deckpound never writes through links, deckpound.models.file_io), its target untouched;
    files get the usual permissions (not mkstemp's 0600)."""

    sc = bench.replace(run=RunSettings(duration=0.02))
    target = tmp_path / "target.txt"
    target.write_text("keep")
    (tmp_path / "m.py").symlink_to(target)
    (tmp_path / "m_data").mkdir()
    (tmp_path / "m_data" / "stale.txt").write_text("old")
    with pytest.raises(SceneError, match="symbolic link"):
        export.export_script(sc, "py", tmp_path / "m.py")
    assert target.read_text() == "keep" and (tmp_path / "m.py").is_symlink()
    (tmp_path / "m.py").unlink()
    py = export.export_script(sc, "py", tmp_path / "m.py")
    assert not (tmp_path / "m_data" / "stale.txt").exists()
    assert (tmp_path / "m_data" / "manifest.json").exists()
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(py.stat().st_mode) == 0o666 & ~mask
    assert stat.S_IMODE((tmp_path / "m_data").stat().st_mode) == 0o777 & ~mask
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.py", "m_data", "target.txt"]


# -- sign convention and refusals ---------------------------------------------------------------


def test_gap_mapping_signs(bench):
    for c, corner in enumerate(plan_of(bench).corners):
        spec = gap_mapping(bench, corner, deck_node=100, seat_node=200, mat_tag=7)
        assert spec.material == "ElasticPPGap"
        assert spec.args[2] < 0 and spec.args[3] == -bench.seats[0].gap
        assert (spec.i_node, spec.j_node) == ((200, 100) if c < 2 else (100, 200))
    sc = bench.replace(contact=dc.replace(bench.contact, law="bilinear"))
    spec = gap_mapping(sc, plan_of(sc).corners[0], 1, 2, 3)
    assert spec.material == "ImpactMaterial" and spec.args[3] < 0 and spec.args[4] < 0


@pytest.mark.parametrize(
    "law,why",
    [
        ("hertz-damp", "OpenSees cannot express the 'hertz-damp'"),
        ("bilinear", r"only with opensees.substeps >= 1000"),
    ],
)
def test_refuses_hertz_damp_and_bilinear(bench, law, why):
    """Issue 12: hertz-damp is not Hertzdamp's law (law = 'hertzdamp' is); ImpactMaterial
    fails at the first impact with the default 10 sub-steps, so bilinear is refused before
    any work unless opensees.substeps >= 1000, with the reason."""
    sc = bench.replace(contact=dc.replace(bench.contact, law=law))
    with pytest.raises(SceneError, match=why):
        engine.run_opensees(sc)


def test_refuses_slip_friction(bench):
    sc = bench.replace(contact=dc.replace(bench.contact, friction=0.2, friction_mode="slip"))
    with pytest.raises(SceneError, match="cannot express 'slip'"):
        engine.run_opensees(sc)


@pytest.mark.parametrize("law", ["kelvin-voigt", "hertz", "hertzdamp", "bilinear"])
def test_refuses_law_with_friction(bench, law):
    sc = bench.replace(
        contact=dc.replace(bench.contact, law=law, friction=0.2, friction_mode="contact2d"),
        opensees=dc.replace(bench.opensees, substeps=1000),
    )
    with pytest.raises(SceneError, match="cannot combine"):
        engine.run_opensees(sc)


def test_warns_about_options_that_do_nothing(bench):
    sc = bench.replace(
        contact=dc.replace(bench.contact, geometry="nonlinear"), run=RunSettings(duration=0.01)
    )
    with pytest.warns(UserWarning, match="geometry"):
        engine.run_opensees(sc)
    sc = bench.replace(
        contact=dc.replace(bench.contact, friction=0.3), run=RunSettings(duration=0.01)
    )
    with pytest.warns(UserWarning, match="friction"):
        engine.run_opensees(sc)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        engine.run_opensees(bench.replace(run=RunSettings(duration=0.01)))

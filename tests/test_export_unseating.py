"""The exported OpenSees scripts check the seat margins as the engine does (issue 30, item 1).

A corner's seat margin is m_c(t) = N − (g_c(t) − g_c(0)), N the support length of the seat it
faces (``seats[i].support_length``); the engine checks it at every converged step and sub-step
and stops after the first step at which it is negative, status ``"unseated"``, storing no row
of that step. The exported Python and Tcl scripts must give the same stop (corner, time, step),
the same smallest margin of each corner and its time, and recorder files holding exactly the
engine's rows.

Scene: the free deck of tests/test_unseating.py (no bents, no damping, supports at rest, moving
away from seat 1 at v = 0.5 m/s, N = 0.05123 m): c1 and c2 unseat at the first step ending at or
after t* = N / v = 0.10246 s. With an output every step, the unseating step is an output step,
whose commit OpenSees records. The "sub-steps" variant makes every step fail and be rescued
by the sub-step fallback (one Newton iteration against a displacement-increment tolerance that
a whole step's increment, v dt = 5e-5 m, exceeds and a sub-step's, 5e-6 m, does not), so the
corner unseats at a sub-step time.

The Tcl script runs in the `opensees` PyPI package's interpreter (an OpenSees build other than
openseespy: numbers agree to round-off, not bit for bit), when it is installed.
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from deckpound.compare.engines import run_engine
from deckpound.models.result import STATUS_UNSEATED, Result
from deckpound.models.scene_io import load_scene
from deckpound.opensees_build.export import export_script, script_text
from deckpound.opensees_build.quoting import tcl_word
from deckpound.opensees_build.recorders import read_columns

pytest.importorskip("openseespy.opensees")

HAS_TCL = importlib.util.find_spec("opensees") is not None
needs_tcl = pytest.mark.skipif(
    not HAS_TCL,
    reason="the Tcl OpenSees interpreter (pip package 'opensees') is not installed; "
    "./run.sh test installs it",
)

SCENE = Path(__file__).parent / "data" / "corner_impact.toml"
#: deck speed away from seat 1 [m/s] and seat 1's support length [m]
V, N = 0.5, 0.05123
FREE = [
    "initial.deck=[0.0,0.0,0.0]",
    f"initial.deck_velocity=[{V},0.0,0.0]",
    "seats[1].gap=0.3",  # seat 2 is never reached (the deck travels 0.1 m)
    "run.duration=0.2",
]
VARIANTS = {
    "every-step": (),
    "sub-steps": ("opensees.tolerance=1e-5", "opensees.max_iterations=1"),
}
#: the prefix of the scripts' seat-margin line when some corner is checked
MARGIN_LINE = "seat_margin_min (margin m, time s): "


def _engine(scene) -> Result:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ignored options of the textbook scene, failed steps
        return run_engine("opensees", scene)


def _run_py(script: Path, out: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(script), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )


def _run_tcl(script: Path) -> subprocess.CompletedProcess:
    """Source ``script`` in the Tcl OpenSees interpreter (path quoted for Tcl)."""
    return subprocess.run(
        [sys.executable, "-m", "opensees", "-"],
        input=f"source {tcl_word(str(script))}\n",
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )


def seat_margin_line(stdout: str) -> dict[str, list[float]] | str:
    """The seat-margin line a script printed: {corner: [margin m, time s]}, or the basis text
    when no corner is checked."""
    (line,) = [x for x in stdout.splitlines() if x.startswith("seat_margin_min")]
    if not line.startswith(MARGIN_LINE):
        return line.removeprefix("seat_margin_min: ")
    out = {}
    for cell in line.removeprefix(MARGIN_LINE).split(", "):
        corner, margin, when = cell.split(" ")
        out[corner] = [float(margin), float(when)]
    return out


def _recorded(script: Path, out_dir: Path) -> dict[str, np.ndarray]:
    manifest = json.loads((script.parent / f"{script.stem}_data" / "manifest.json").read_text())
    return read_columns(out_dir, manifest["recorders"]["columns"])


def _loop_message(meta: dict) -> str:
    """The engine loop's sentence of the stop (the epilogue's message starts with it)."""
    return (
        f"corner {meta['unseated_corner']} unseated at t = {meta['unseated_time']:.6g} s "
        f"(step {meta['unseated_step']})"
    )


@pytest.fixture(scope="module", params=sorted(VARIANTS))
def unseated(request, tmp_path_factory):
    """(variant, scene, the engine's run, export folder) of a run that unseats."""
    scene = load_scene(SCENE, [*FREE, f"seats[0].support_length={N}", *VARIANTS[request.param]])
    ref = _engine(scene)
    return request.param, scene, ref, tmp_path_factory.mktemp(f"unseat-{request.param}")


def test_the_engine_unseats_at_the_step_the_scripts_must_find(unseated):
    variant, _, ref, _ = unseated
    m = ref.meta
    assert m["status"] == STATUS_UNSEATED and m["unseated_corner"] == "c1"
    assert m["message"].startswith(_loop_message(m) + ":")
    assert N / V <= m["unseated_time"] < N / V + m["dt"]
    assert m["steps"] == m["unseated_step"] == round(N / V / m["dt"] + 0.5)
    assert set(m["seat_margin_min"]) == {"c1", "c2"} and m["seat_margin_min"]["c1"][0] < 0.0
    # the unseating step is an output step: OpenSees records its commit
    assert m["dt"] == m["scene"]["run"]["output_dt"]
    if variant == "sub-steps":  # every step rescued; the stop falls at a sub-step's time
        assert m["failures"] == m["rescued_by_substeps"] == m["steps"]
        sub = m["dt"] / m["settings"]["substeps"]
        assert m["unseated_time"] < m["steps"] * m["dt"] - 0.5 * sub
    else:
        assert m["failures"] == 0 and m["unseated_time"] == m["steps"] * m["dt"]


def test_python_script_stops_and_reports_as_the_engine(unseated):
    """Same library, same code: the stop, the margins and the recorder rows bit for bit."""
    _, scene, ref, folder = unseated
    m = ref.meta
    script = export_script(scene, "py", folder / "model.py")
    out = folder / "py"
    cp = _run_py(script, out)
    assert cp.returncode == 0, cp.stderr[-2000:]
    st = json.loads((out / "opensees.stats.json").read_text(encoding="utf-8"))
    assert st["status"] == "unseated" and st["steps"] == m["unseated_step"]
    assert st["unseated"] == [m["unseated_corner"], m["unseated_time"]]
    assert st["message"] == _loop_message(m)
    assert st["seat_margin_min"] == m["seat_margin_min"]
    assert st["seat_margin_basis"] == m["seat_margin_basis"] == "every step"
    assert cp.stdout.startswith(f"unseated {_loop_message(m)} gap_closures: 0\n")
    assert seat_margin_line(cp.stdout) == m["seat_margin_min"]  # printed as repr: exact
    got = _recorded(script, out)
    for c in got:
        assert len(got[c]) == len(ref[c]), (c, len(got[c]), len(ref[c]))
        if c != "t":  # OpenSees adds dt step by step, deckpound writes n*dt
            assert np.array_equal(got[c], ref[c]), c
    assert np.max(np.abs(got["t"] - ref.t)) < 1e-12


@needs_tcl
def test_tcl_script_stops_and_reports_as_the_engine(unseated):
    """Another OpenSees build: the same stop (corner, time, step) and margins to round-off,
    the recorder files cut to the engine's rows."""
    _, scene, ref, folder = unseated
    m = ref.meta
    script = export_script(scene, "tcl", folder / "model.tcl")
    cp = _run_tcl(script)
    assert cp.returncode == 0, (cp.stdout + cp.stderr)[-2000:]
    lines = cp.stdout.splitlines()
    status = next(x for x in lines if x.startswith(("success,", "unseated,", "failed,")))
    failures = m["failures"]
    assert status == (
        f"unseated, failures: {failures}, rescued by sub-steps: {failures}, gap_closures: 0"
    )
    assert lines[lines.index(status) + 1] == _loop_message(m)
    margins = seat_margin_line(cp.stdout)
    assert set(margins) == set(m["seat_margin_min"])
    for c, (margin, when) in m["seat_margin_min"].items():
        assert margins[c][0] == pytest.approx(margin, abs=1e-12), c
        assert margins[c][1] == when, c  # the time of the largest gap: that step's n*dt
    got = _recorded(script, folder / "model_results")
    for c in got:
        assert len(got[c]) == len(ref[c]), (c, len(got[c]), len(ref[c]))
        peak = max(float(np.max(np.abs(ref[c]))), 1e-300)
        assert float(np.max(np.abs(got[c] - ref[c]))) / peak <= 1e-10, c


# -- runs that do not unseat -------------------------------------------------------------------

NOT_UNSEATED = {
    # N = 1 m is never reached: every margin is reported, the run succeeds
    "checked": ("seats[0].support_length=1.0", "seats[1].support_length=1.0"),
    # no support length: nothing checked, the engine's basis text
    "unchecked": (),
}


@pytest.mark.parametrize("case", sorted(NOT_UNSEATED))
def test_scripts_report_the_margins_of_a_run_that_does_not_unseat(case, tmp_path):
    scene = load_scene(SCENE, [*FREE[:3], "run.duration=0.05", *NOT_UNSEATED[case]])
    ref = _engine(scene)
    m = ref.meta
    assert ref.ok and not ref.unseated
    expected = m["seat_margin_min"] or m["seat_margin_basis"]
    if case == "checked":
        assert set(m["seat_margin_min"]) == {"c1", "c2", "c3", "c4"}
        # c1, c2 open by v T at the end; c3, c4 close (largest gap at t = 0)
        assert m["seat_margin_min"]["c1"] == [
            pytest.approx(1.0 - V * 0.05, abs=1e-12),
            pytest.approx(0.05, abs=1e-12),
        ]
        assert m["seat_margin_min"]["c3"] == [1.0, 0.0]
    else:
        assert m["seat_margin_min"] == {} and expected.startswith("not checked")
    script = export_script(scene, "py", tmp_path / "model.py")
    cp = _run_py(script, tmp_path / "py")
    assert cp.returncode == 0, cp.stderr[-2000:]
    st = json.loads((tmp_path / "py" / "opensees.stats.json").read_text(encoding="utf-8"))
    assert st["status"] == "success" and st["unseated"] is None
    assert st["seat_margin_min"] == m["seat_margin_min"]
    assert st["seat_margin_basis"] == m["seat_margin_basis"]
    assert seat_margin_line(cp.stdout) == expected
    if not HAS_TCL:
        return
    tcl = export_script(scene, "tcl", tmp_path / "model.tcl")
    cp = _run_tcl(tcl)
    assert cp.returncode == 0, (cp.stdout + cp.stderr)[-2000:]
    assert "success, failures: 0, rescued by sub-steps: 0, gap_closures: 0" in cp.stdout
    assert "unseated" not in cp.stdout
    margins = seat_margin_line(cp.stdout)
    if case == "unchecked":
        assert margins == expected
    else:
        assert set(margins) == set(expected)
        for c, (margin, when) in expected.items():
            assert margins[c] == [pytest.approx(margin, abs=1e-12), when], c


# -- the script text ---------------------------------------------------------------------------


def test_scripts_state_the_support_lengths_and_carry_them_to_the_loop():
    """The header states N per corner; the Tcl loop's list holds it, the empty word for a
    corner that is not checked; the Python step plan holds it as the engine's."""
    scene = load_scene(SCENE, [*FREE, f"seats[0].support_length={N}"])
    tcl, _ = script_text(scene, "tcl", "model")
    assert f"N: c1 {N} m, c2 {N} m, c3 none (not checked), c4 none (not checked)." in " ".join(
        line.removeprefix("#").strip() for line in tcl.splitlines() if line.startswith("#")
    )
    assert f"set seatLengths {{{N!r} {N!r} {{}} {{}}}}" in tcl.splitlines()
    py, _ = script_text(scene, "py", "model")
    assert f"'support_lengths': [{N!r}, {N!r}, None, None]" in py

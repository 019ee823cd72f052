"""Round trip of the exports (issue 17): run the exported Tcl and Python scripts from a folder
whose path holds spaces and non-ASCII characters, read their OpenSees recorder files back through
the manifest's column maps and compare with the in-process OpenSees run.

The Tcl interpreter is the `opensees` PyPI package (the xara/OpenSeesRT build), an OpenSees
independent of openseespy: agreement to round-off shows the exported script is complete (model,
records, analysis, recorders). Its launcher (`python -m opensees FILE`) evaluates
`info script FILE` unquoted and so cannot take a path with spaces; the scripts are therefore
`source`d through standard input with a properly quoted path, as in any Tcl OpenSees shell.

The scene pounds (the gaps close) and has one step that fails and is rescued by the sub-step
fallback, on an output step (stride 5): the recorders must still give exactly one row per
deckpound row (their -dT margin is half a sub-step).
"""

from __future__ import annotations

import importlib.util
import json
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest
from tests_helpers_scene import short_benchmark

from deckpound.compare.engines import run_engine
from deckpound.models.columns import column_names, column_unit
from deckpound.models.engine_contract import engine_columns
from deckpound.models.plan import plan_of
from deckpound.models.result import read_table
from deckpound.models.scene_io import scene_from_mapping
from deckpound.opensees_build.export import export_script
from deckpound.opensees_build.quoting import tcl_word
from deckpound.opensees_build.recorders import read_columns

HAS_TCL = importlib.util.find_spec("opensees") is not None
needs_tcl = pytest.mark.skipif(
    not HAS_TCL,
    reason="the Tcl OpenSees interpreter (pip package "
    "'opensees') is not installed; ./run.sh test installs it",
)
pytest.importorskip("openseespy.opensees")

#: 2 s of the benchmark with Newton capped at 3 iterations: step 2105 (t = 1.0525 s) fails and
#: is rescued by sub-steps; an output every 5 steps puts that step on an output row. The
#: scenario was tuned with Rayleigh damping on the seat springs too, the default before issue 12
#: (with the new default, four steps fail, none on an output row): kept, as this file tests the
#: exports, not the damping
OVERRIDES = ("opensees.max_iterations=3", "run.output_dt=0.0025", "damping.members=bents+seats")


def run_tcl(script, **kw) -> subprocess.CompletedProcess:
    """Source ``script`` in the Tcl OpenSees interpreter (path quoted for Tcl)."""
    return subprocess.run(
        [sys.executable, "-m", "opensees", "-"],
        input=f"source {tcl_word(str(script))}\n",
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        **kw,
    )


def recorded(script, out_dir) -> dict[str, np.ndarray]:
    """deckpound's columns from the recorder files, through the manifest of ``script``."""
    manifest = json.loads((script.parent / f"{script.stem}_data" / "manifest.json").read_text())
    return read_columns(out_dir, manifest["recorders"]["columns"])


def deviation(got: dict, ref) -> dict[str, float]:
    """Largest |got - ref| of each column over the column's peak."""
    # the recorders cover exactly the engine's own columns (the rest is derived in process)
    assert set(got) == set(engine_columns(plan_of(scene_from_mapping(ref.meta["scene"]))))
    out = {}
    for c in got:
        assert len(got[c]) == len(ref[c]), (c, len(got[c]), len(ref[c]))
        peak = max(float(np.max(np.abs(ref[c]))), 1e-300)
        out[c] = float(np.max(np.abs(got[c] - ref[c]))) / peak
    return out


@pytest.fixture(scope="module")
def trip(tmp_path_factory):
    scene = short_benchmark(2.0, *OVERRIDES)
    folder = tmp_path_factory.mktemp("export") / "round trip é ü 橋"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the failed step warns
        ref = run_engine("opensees", scene)
    return scene, folder, ref


def test_scene_pounds_and_rescues_a_step_on_an_output_row(trip):
    _, _, ref = trip
    assert ref.ok and ref.meta["failures"] == 1 and ref.meta["rescued_by_substeps"] == 1
    step = int(re.match(r"step (\d+)", ref.meta["step_log"][0]).group(1))
    assert step % 5 == 0, "the rescued step must fall on an output row to test alignment"
    assert np.max(ref["fn_c1"]) > 0 and np.max(ref["fn_c3"]) > 0


def test_python_recorders_equal_the_in_process_run(trip):
    scene, folder, ref = trip
    script = export_script(scene, "py", folder / "modèle 1.py")
    out = folder / "py out"
    cp = subprocess.run(
        [sys.executable, str(script), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    stats = json.loads((out / "opensees.stats.json").read_text())
    assert (stats["failures"], stats["rescued"]) == (1, 1)
    got = recorded(script, out)
    dev = deviation(got, ref)
    print("Python recorders vs in-process, worst per column:", max(dev.values()))
    # the same code on the same library: bit for bit, except the time column (OpenSees adds
    # dt step by step, deckpound writes n*dt)
    for c in got:
        if c != "t":
            assert np.array_equal(got[c], ref[c]), (c, dev[c])
    assert dev["t"] < 1e-12


@needs_tcl
def test_tcl_recorders_match_the_in_process_run(trip):
    scene, folder, ref = trip
    script = export_script(scene, "tcl", folder / "modèle 1.tcl")
    cp = run_tcl(script, cwd=folder)
    assert cp.returncode == 0, (cp.stdout + cp.stderr)[-2000:]
    assert "success, failures: 1, rescued by sub-steps: 1" in cp.stdout
    dev = deviation(recorded(script, folder / "modèle 1_results"), ref)
    worst = max(dev.values())
    print(
        f"Tcl recorders vs in-process: worst {worst:.2e} of the column peak "
        f"({max(dev, key=dev.get)})"
    )
    assert worst <= 1e-10


@needs_tcl
def test_tcl_csv_block_reproduces_deckpound_csv(trip, tmp_path):
    """The optional writeCsv block writes deckpound's columns as the engine samples them."""

    scene, folder, ref = trip
    script = export_script(scene, "tcl", folder / "csv.tcl")
    out = tmp_path / "csv out"
    cp = subprocess.run(
        [sys.executable, "-m", "opensees", "-"],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        input=f"set writeCsv 1\nset outDir {tcl_word(str(out))}\nsource {tcl_word(str(script))}\n",
    )
    assert cp.returncode == 0, (cp.stdout + cp.stderr)[-2000:]
    df = read_table(out / "opensees.csv")
    assert list(df.columns) == column_names(plan_of(scene))  # derived ones: test_export_columns
    assert df.attrs["units"] == {c: column_unit(c) for c in df.columns}  # in the header
    dev = deviation({c: df[c].to_numpy() for c in engine_columns(plan_of(scene))}, ref)
    assert max(dev.values()) <= 1e-10, dev
    assert (out / "deck_x_abs.out").exists()  # outDir set before source is honoured


VARIANTS = {
    # zeroLengthContact2D: gaps from the corner nodes, fn and ft from the element forces
    "friction": ("contact.friction=0.2", "contact.friction_mode=contact2d"),
    # step 148 fails without a fallback: both scripts stop there and exit 1, the recorders
    # hold exactly the rows deckpound stored up to the failure
    "failure": ("opensees.max_iterations=2", "opensees.fallback=none"),
}


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_exports_of_variants_match_the_in_process_run(variant, tmp_path):
    scene = short_benchmark(2.0, *VARIANTS[variant])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = run_engine("opensees", scene)
    assert ref.ok == (variant != "failure")
    if variant == "friction":
        assert np.max(np.abs(ref["ft_c1"])) > 1.0  # the corners stick and slip
    folder = tmp_path / "vari é"
    py = export_script(scene, "py", folder / "v.py")
    cp = subprocess.run(
        [sys.executable, str(py), "--out", str(folder / "py")],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert cp.returncode == (0 if ref.ok else 1), cp.stderr[-2000:]
    got = recorded(py, folder / "py")
    for c in got:
        if c != "t":
            assert np.array_equal(got[c], ref[c]), c
    if not HAS_TCL:
        return
    tcl = export_script(scene, "tcl", folder / "v.tcl")
    cp = run_tcl(tcl)
    assert cp.returncode == (0 if ref.ok else 1), (cp.stdout + cp.stderr)[-2000:]
    dev = deviation(recorded(tcl, folder / "v_results"), ref)
    print(f"{variant}: Tcl recorders vs in-process, worst {max(dev.values()):.2e}")
    # two OpenSees builds: round-off. With friction (issue 12: seat guide 1e16 so the clone
    # matches; seats damped by their dashpots only) the contact forces carry ~3e-10 of it
    assert max(dev.values()) <= (1e-9 if variant == "friction" else 1e-10)

"""The exported scripts' CSV holds every column of the in-process result (issue 32, item 5):
the displacements relative to the supports (``deck_x_rel``, ``seat1_x_rel``, ...) and the bent
deformations (``bent1_dx``, ...), derived in the script from the support displacement records
of its data folder, as :func:`deckpound.models.engine_contract.finish` derives them."""

from __future__ import annotations

import importlib.util
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from tests_helpers_scene import short_benchmark

from deckpound.models.columns import column_names, column_unit
from deckpound.models.engine_contract import engine_columns
from deckpound.models.excitation import support_motion
from deckpound.models.plan import DOF_COLUMNS, plan_of
from deckpound.models.result import read_table
from deckpound.opensees_build.export_py import interp_record

pytest.importorskip("openseespy.opensees")

from deckpound.opensees_build import engine
from deckpound.opensees_build.export import export_script
from deckpound.opensees_build.quoting import tcl_word

HAS_TCL = importlib.util.find_spec("opensees") is not None

#: a 1.5 s record in a run that goes on after it (the records are held at their last value)
SCENES = {
    "benchmark": (),
    # skewed: the corners and the bents' transverse springs couple x, y and θ
    "skew 30°": ("deck.skew=30.0",),
}
DERIVED = ["deck_x_rel", "deck_y_rel", "seat1_x_rel", "seat2_x_rel"]


def _derived(plan) -> list[str]:
    return DERIVED + [f"{b}_d{a}" for b in plan.bent_names for a in ("x", "y")]


def _expected(scene, df: pd.DataFrame) -> dict[str, np.ndarray]:
    """The derived columns from the CSV's own absolute columns, independently of the script:
    np.interp of the support motion, table means, d = B u − S u_g."""
    plan, motion = plan_of(scene), support_motion(scene)
    t = df["t"].to_numpy()
    ug = np.column_stack([np.interp(t, motion.t, motion.disp[ch]) for ch in plan.channels])
    x = [plan.channels.index(f"{b}_x") for b in plan.bent_names]
    y = [plan.channels.index(f"{b}_y") for b in plan.bent_names]
    out = {
        "deck_x_rel": df["deck_x_abs"].to_numpy() - ug[:, x].mean(axis=1),
        "deck_y_rel": df["deck_y_abs"].to_numpy() - ug[:, y].mean(axis=1),
    }
    for j in (1, 2):
        out[f"seat{j}_x_rel"] = (
            df[f"seat{j}_x_abs"].to_numpy() - ug[:, plan.channels.index(f"seat{j}_x")]
        )
    U = np.zeros((len(t), 7))
    for name, dof in DOF_COLUMNS:
        U[:, dof] = df[name].to_numpy()
    d = plan.deformations(U, ug)
    for i, b in enumerate(plan.bent_names):
        out[f"{b}_dx"], out[f"{b}_dy"] = d[:, 2 * i], d[:, 2 * i + 1]
    return out


def _worst(got: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(got - ref))) / max(float(np.max(np.abs(ref))), 1e-300)


@pytest.fixture(scope="module", params=list(SCENES))
def case(request):
    scene = short_benchmark(1.5, "run.duration=2.0", *SCENES[request.param])
    return scene, engine.run_opensees(scene)


def test_interp_record_is_np_interp():
    """Knots, points between them, before the record and after its end: np.interp's values."""
    rng = np.random.default_rng(7)
    dt = 0.005
    values = list(rng.normal(size=40))
    xp = np.arange(len(values)) * dt
    ts = np.concatenate([xp, rng.uniform(-0.01, 0.25, 300), [0.0, xp[-1], 1e-17, 0.3]])
    got = np.array([interp_record(values, dt, float(t)) for t in ts])
    ref = np.interp(ts, xp, values)
    assert np.max(np.abs(got - ref)) <= 1e-15 * np.max(np.abs(values))
    assert np.array_equal(got[: len(xp)], values)  # on a knot: the sample itself


def test_python_export_csv_has_the_result_columns(case, tmp_path):
    scene, ref = case
    plan = plan_of(scene)
    script = export_script(scene, "py", tmp_path / "model.py")
    cp = subprocess.run(
        [sys.executable, str(script), "--csv", "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    df = read_table(tmp_path / "out" / "opensees.csv")
    assert list(df.columns) == column_names(plan)  # the in-process result's columns, in order
    assert df.attrs["units"] == {c: column_unit(c) for c in df.columns}  # in the header
    assert set(_derived(plan)) <= set(df.columns) and len(df) == len(ref.t)
    for c in engine_columns(plan):  # sampled by the same code on the same library
        assert np.array_equal(df[c].to_numpy(), ref[c]), c
    for c in _derived(plan):
        assert np.max(np.abs(ref[c])) > 0, c  # the column moves: the check can fail
        assert _worst(df[c].to_numpy(), ref[c]) <= 1e-13, c
    # the script holds the records after they end, as the engine does: rows past the record
    assert df["t"].iloc[-1] > 1.5


@pytest.mark.skipif(not HAS_TCL, reason="the Tcl OpenSees interpreter (pip 'opensees') is absent")
def test_tcl_export_csv_has_the_result_columns(case, tmp_path):
    scene, ref = case
    plan = plan_of(scene)
    script = export_script(scene, "tcl", tmp_path / "model.tcl")
    out = tmp_path / "out"
    cp = subprocess.run(
        [sys.executable, "-m", "opensees", "-"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        input=f"set writeCsv 1\nset outDir {tcl_word(str(out))}\nsource {tcl_word(str(script))}\n",
    )
    assert cp.returncode == 0, (cp.stdout + cp.stderr)[-2000:]
    df = read_table(out / "opensees.csv")
    assert list(df.columns) == column_names(plan)
    assert df.attrs["units"] == {c: column_unit(c) for c in df.columns}  # in the header
    own = _expected(scene, df)  # the Tcl arithmetic on its own rows
    for c in _derived(plan):
        assert _worst(df[c].to_numpy(), own[c]) <= 1e-13, c
        # another OpenSees build: the absolute columns agree to round-off, so do these
        assert _worst(df[c].to_numpy(), ref[c]) <= 1e-9, c

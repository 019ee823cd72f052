"""The lean C reference loop of ``benchmarks/reference_loop`` solves the compliance engine's
problem (issue 33): on a short record with pounding and yielding bents its peaks agree with the
engine's, and what makes it lean (factors reused while the contact state and the springs'
tangents stay, no residual at a converged iterate) does not change its answer; its algorithm
written in numba (``lean_numba.py``) gives the same answer bit for bit. Nothing here is
timed: ``benchmarks/reference_loop/run.py`` measures the speed.
"""

from __future__ import annotations

import importlib.util
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

import deckpound as dp

ROOT = Path(__file__).resolve().parents[1]
DRIVER = ROOT / "benchmarks" / "reference_loop" / "run.py"
needs_gcc = pytest.mark.skipif(
    shutil.which("gcc") is None, reason="gcc is not installed: the C reference cannot be compiled"
)
#: a record with 43 gap closures and every bent beyond its yield force (checked below)
SHORT = {"excitation.duration": 4.0}


def _driver():
    """benchmarks/reference_loop/run.py as a module (the benchmarks are not installed)."""
    spec = importlib.util.spec_from_file_location("reference_loop_run", DRIVER)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve the module by name
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def short_case(tmp_path_factory):
    """(driver, scene, compliance result, input file, folder, number of DOF) of the short
    record."""
    ref = _driver()
    scene = dp.load_scene("saiidi-4span", set=SHORT)
    motion = dp.support_motion(scene)
    result = dp.run(scene, engine="compliance", motion=motion)
    folder = tmp_path_factory.mktemp("reference_loop")
    inputs = folder / "inputs.f64"
    problem = ref.problem_of(scene, motion, result)
    ndof = ref.write_inputs(problem, inputs)
    return ref, scene, result, inputs, folder, ndof


@needs_gcc
def test_reference_peaks_agree_with_the_compliance_engine(short_case):
    ref, scene, result, inputs, folder, ndof = short_case
    # the comparison covers both nonlinearities: pounding and yielded bents
    assert result.meta["gap_closures"] > 0
    for i, bent in enumerate(scene.bents, start=1):
        assert result.peak(f"bent{i}_fx") > bent.x.yield_force
        assert result.peak(f"bent{i}_fy") > bent.y.yield_force
    report = ref.run_reference(ref.compile_reference(folder, ndof), inputs)
    assert report["steps"] == result.meta["steps"]
    peaks = ref.reference_peaks(report)
    for column in ("deck_x_abs", "deck_y_abs", "deck_theta"):
        assert ref.relative_difference(peaks[column], result.peak(column)) < 5e-3, column
    # the same Newton iterations: the same algorithm and convergence test
    assert report["newton_iterations"] == pytest.approx(result.meta["newton_iterations"], rel=0.02)


@needs_gcc
def test_the_numba_port_gives_the_c_loops_answer_bit_for_bit(short_case):
    """lean_numba.py is reference.c statement for statement: the same status, Newton
    iterations, factorisations and peaks (with their times) to the last bit, so its speed
    against the C loop's is numba's code against gcc's on the same arithmetic."""
    ref, _, _, inputs, folder, ndof = short_case
    c_loop = ref.run_reference(ref.compile_reference(folder, ndof), inputs)
    lean = ref.lean_numba()
    port = lean.run_lean(lean.load_inputs(inputs), repeats=1)
    for key in ("status", "steps", "newton_iterations", "factorisations", "max_step_iterations",
                "peak", "peak_time"):  # fmt: skip
        assert port[key] == c_loop[key], key
    assert len(port["loop_seconds"]) == 1


def test_the_numba_port_refuses_a_foreign_input_file(tmp_path):
    lean = _driver().lean_numba()
    path = tmp_path / "foreign.f64"
    np.array([1.0, 2.0, 3.0]).astype("<f8").tofile(path)
    with pytest.raises(ValueError, match="not an input file"):
        lean.load_inputs(path)


@needs_gcc
def test_lean_choices_change_nothing(short_case):
    """Refactorising at every iteration in contact and forming the residual at the converged
    iterate (what deckpound does) give the reference's answer bit for bit: a reused factor is
    that of the same matrix, and the converged iterate's materials are set either way."""
    ref, _, _, inputs, folder, ndof = short_case
    lean = ref.run_reference(ref.compile_reference(folder, ndof), inputs)
    both = ("REF_REFACTOR_CONTACT", "REF_FULL_RESIDUAL")
    full = ref.run_reference(ref.compile_reference(folder, ndof, both), inputs)
    assert full["peak"] == lean["peak"]
    assert full["newton_iterations"] == lean["newton_iterations"]
    assert full["factorisations"] > lean["factorisations"]


@needs_gcc
def test_reference_refuses_a_foreign_input_file(short_case, tmp_path):
    ref, _, _, _, folder, ndof = short_case
    exe = ref.compile_reference(folder, ndof)
    bad = tmp_path / "bad.f64"
    bad.write_bytes(b"\0" * 64)
    with pytest.raises(ref.ReferenceError, match="not an input file of this format"):
        ref.run_reference(exe, bad)


@pytest.mark.parametrize(
    ("path", "value"),
    [
        ("contact.law", "hertz"),
        ("contact.geometry", "nonlinear"),
        ("damping.stiffness", "committed"),
        ("compliance.integrator", "adaptive"),
    ],
)
def test_reference_refuses_what_it_does_not_implement(path, value):
    ref = _driver()
    scene = dp.load_scene("saiidi-4span", set={path: value})
    with pytest.raises(ref.ReferenceError, match=path.replace(".", r"\.")):
        ref.check_scene(scene)

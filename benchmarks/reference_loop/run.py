"""Compare deckpound's step loops with a lean hand-written C loop of the same problem (issue 33).

Usage (from the repository root, with the project's virtual environment)::

    .venv/bin/python benchmarks/reference_loop/run.py                # saiidi-4span, 5 rounds
    .venv/bin/python benchmarks/reference_loop/run.py --rounds 9 --variants
    .venv/bin/python benchmarks/reference_loop/run.py --set excitation.duration=5

What it does: runs the compliance engine once (warm-up: numba's kernels load or compile; not
timed) and takes the problem from that run and the scene: the step dt, the number of steps, the
Newton tolerance and iteration cap, Newmark's γ and β (the result's metadata), the plan model's
masses, springs, Takeda (OpenSees ``Hysteretic``) parameters, gap rows and initial gaps
(:func:`deckpound.plan_of`), the damping matrix (:func:`deckpound.models.damping.damping_model`)
and the support motion at the engine's steps (:func:`deckpound.support_motion`, resampled). It
writes them to a float64 file (layout: the header of ``reference.c``), compiles ``reference.c``
with ``gcc -O3 -march=native`` in a temporary folder and then, in ``--rounds`` rounds, runs the
reference, the compliance engine and the nonsmooth engine one after the other (so the three see
the same machine load), and prints

* µs/step of each (median over the rounds; the step loop alone: the reference times its loop
  with ``clock_gettime``, deckpound reports the loop's time as ``meta["us_per_step"]``),
* their ratio to the reference,
* Newton iterations per step and factorisations of each,
* the relative difference of the peaks of the deck's displacements and rotation (every step).

``--variants`` also builds the reference with the switches that emulate what deckpound's loop
does in addition (``REF_REFACTOR_CONTACT``, ``REF_FULL_RESIDUAL``) and runs the compliance engine
without its energy columns (``channels=[]``), with one output row (``run.output_dt`` = the
record) and with neither: what each costs; and it runs the reference's own algorithm written
in numba (``lean_numba.py``, the same answer bit for bit): how far numba's code is from gcc's
on the lean loop itself.

:func:`measure` does the timed rounds and returns them (:class:`LoopTimes`); ``main`` prints
them, and ``tools/sweep_benchmark.py`` puts them on docs/sweeps.md beside the sweeps.

The reference solves the compliance engine's problem only for what it implements: linear
contact law, no friction, linear contact kinematics, initial-stiffness damping, the Newmark
integrator; another scene is refused with the field and the value that it cannot run.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import deckpound as dp
from deckpound.models.damping import damping_model
from deckpound.models.plan import DOF_COLUMNS

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "reference.c"
#: the reference's algorithm in numba (the same loop, statement for statement)
LEAN_NUMBA = HERE / "lean_numba.py"
#: the label of its loop times in LoopTimes.reference_seconds and reports
LEAN = "reference's algorithm in numba"
#: the label of the build that forms the whole residual at the converged iterate, as the
#: compliance loop does (a key of VARIANTS)
FULL_RESIDUAL = "reference + residual at the converged iterate"
#: the first value of the input file (``REF_FORMAT`` in reference.c)
REF_FORMAT = 33001.0
#: the switches of reference.c that emulate what deckpound's loop does in addition
VARIANTS = {
    "reference + refactor while in contact": ("REF_REFACTOR_CONTACT",),
    FULL_RESIDUAL: ("REF_FULL_RESIDUAL",),
    "reference + both": ("REF_REFACTOR_CONTACT", "REF_FULL_RESIDUAL"),
}
#: the peaks compared (the deck's absolute displacements and rotation)
DECK_COLUMNS = ("deck_x_abs", "deck_y_abs", "deck_theta")


class ReferenceError(RuntimeError):
    """The reference cannot run this scene, could not be built, or failed."""


@dataclass(frozen=True)
class Problem:
    """What the reference integrates: the scene and the loop's settings of a compliance run
    (dt [s], steps, Newton tolerance [m] and cap, Newmark γ and β, subnormals flushed)."""

    scene: object
    motion: object
    dt: float
    steps: int
    tolerance: float
    max_iterations: int
    gamma: float
    beta: float
    flush_subnormals: bool


def check_scene(scene) -> None:
    """Refuse what the reference does not implement (a ReferenceError naming the field)."""
    wrong = []
    if scene.compliance.integrator != "newmark":
        wrong.append(("compliance.integrator", scene.compliance.integrator, "newmark"))
    if scene.contact.law != "linear":
        wrong.append(("contact.law", scene.contact.law, "linear"))
    if scene.contact.friction > 0.0 and scene.contact.friction_mode != "none":
        wrong.append(("contact.friction", scene.contact.friction, "0"))
    if scene.contact.geometry != "linear":
        wrong.append(("contact.geometry", scene.contact.geometry, "linear"))
    if scene.damping.stiffness != "initial" and scene.damping.members != "none":
        wrong.append(("damping.stiffness", scene.damping.stiffness, "initial"))
    if wrong:
        field, value, allowed = wrong[0]
        raise ReferenceError(
            f"the reference loop cannot run {field} = {value!r}; it implements {allowed!r} only"
        )


def problem_of(scene, motion, compliance_result) -> Problem:
    """The problem of a finished compliance run of ``scene`` driven by ``motion``."""
    meta = compliance_result.meta
    if meta["status"] != "success" or meta.get("rescued_by_substeps", 0):
        raise ReferenceError(
            f"the compliance run did not finish in whole steps (status {meta['status']!r}, "
            f"{meta.get('rescued_by_substeps', 0)} steps sub-stepped): the reference has no "
            "sub-stepping fallback"
        )
    settings = meta["settings"]
    return Problem(
        scene=scene,
        motion=motion,
        dt=float(meta["dt"]),
        steps=int(meta["steps"]),
        tolerance=float(settings["tolerance"]),
        max_iterations=int(settings["max_iterations"]),
        gamma=float(meta["gamma"]),
        beta=float(meta["beta"]),
        flush_subnormals=settings["subnormals"] == "flush",
    )


def input_values(problem: Problem) -> tuple[int, np.ndarray]:
    """(number of DOF, the input file's float64 values) of ``problem`` (reference.c's layout).

    Linear springs go into K and K_g (F = K u − K_g u_g), the hysteretic ones stay springs;
    C is the damping matrix and C_g = Bᵀ diag(rate) S (+ the relative mass dampers) its
    support part; the corners' gap rows w_c and gaps g0_c are those of linear kinematics.
    """
    scene = problem.scene
    check_scene(scene)
    plan = dp.plan_of(scene)
    damping = damping_model(scene, plan)
    B, S = plan.spring_matrices
    nd, nch = B.shape[1], S.shape[1]
    k0 = plan.k0
    linear = np.array([s.kind == "linear" for s in plan.springs])
    K = B[linear].T @ (k0[linear, None] * B[linear])
    Kg = B[linear].T @ (k0[linear, None] * S[linear])
    C = damping.matrix(plan)
    Cg = B.T @ (damping.rate_coefficients(plan)[:, None] * S)
    for m in damping.mass_dampers:
        if m.channel >= 0:
            Cg[m.dof, m.channel] += m.c
    hyst = []
    for s in plan.springs:
        if s.kind == "linear":
            continue
        if s.kind != "takeda" or len(s.dofs) > 2 or len(s.takeda) != 13:
            raise ReferenceError(f"spring {s.name}: the reference has no {s.kind!r} spring")
        dofs = (list(s.dofs) + [0, 0])[:2]
        coefs = (list(s.coefs) + [0.0, 0.0])[:2]
        hyst.append([len(s.dofs), *dofs, *coefs, s.channel, s.channel_coef, *map(float, s.takeda)])
    rows = plan.normal_rows()
    corners = [[g0, scene.contact.stiffness, *row] for g0, row in zip(plan.gaps, rows)]
    initial = plan.initial_state(scene.initial)
    u0, v0 = (np.zeros(nd), np.zeros(nd)) if initial is None else initial
    rec = problem.motion.resample(problem.dt, problem.steps * problem.dt)
    UG, VG = rec.matrices(plan.channels)
    if UG.shape[0] != problem.steps + 1:
        raise ReferenceError(
            f"the resampled motion has {UG.shape[0]} samples for {problem.steps} steps"
        )
    header = [
        REF_FORMAT,
        nd,
        len(hyst),
        nch,
        len(corners),
        problem.steps,
        problem.max_iterations,
        problem.dt,
        problem.tolerance,
        problem.gamma,
        problem.beta,
        1.0 if problem.flush_subnormals else 0.0,
    ]
    parts = [header, plan.mass, K, Kg, C, Cg, hyst, corners, u0, v0, UG, VG]
    values = np.concatenate([np.asarray(p, dtype=np.float64).ravel() for p in parts])
    return nd, values


def lean_numba():
    """lean_numba.py as a module (the benchmarks are not installed)."""
    spec = importlib.util.spec_from_file_location("reference_loop_lean_numba", LEAN_NUMBA)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclass resolves the module by name
    spec.loader.exec_module(module)
    return module


def write_inputs(problem: Problem, path: Path) -> int:
    """Write the input file of ``problem`` to ``path``; returns the number of DOF."""
    nd, values = input_values(problem)
    values.astype("<f8").tofile(path)
    return nd


def compile_reference(folder: Path, ndof: int, defines: tuple[str, ...] = ()) -> Path:
    """``gcc -O3 -march=native`` of reference.c for ``ndof`` DOF into ``folder``."""
    gcc = shutil.which("gcc")
    if gcc is None:
        raise ReferenceError("gcc is not installed: the reference loop cannot be compiled")
    exe = folder / ("reference" + "".join(f"_{d.lower()}" for d in defines))
    # -std=c11 (ISO C): gcc then does not contract a·b + c into fused multiply-adds, whose
    # single rounding would make the round-off differ from the compliance engine's (numba
    # does not contract either)
    cmd = [gcc, "-O3", "-march=native", "-std=c11", f"-DNDOF={ndof}"]
    cmd += [f"-D{d}" for d in defines] + [str(SOURCE), "-o", str(exe), "-lm"]
    out = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise ReferenceError(f"gcc failed: {out.stderr.strip()[-2000:]}")
    return exe


def run_reference(exe: Path, inputs: Path, repeats: int = 1) -> dict:
    """Run the compiled reference ``repeats`` times on ``inputs``; its JSON report."""
    out = subprocess.run(
        [str(exe), str(inputs), str(repeats)], capture_output=True, text=True, check=False
    )
    if out.returncode == 2 or not out.stdout.strip():
        raise ReferenceError(f"the reference failed: {out.stderr.strip()}")
    report = json.loads(out.stdout)
    if report["status"] != "ok":
        raise ReferenceError(
            f"the reference stopped at step {report['failed_step']}: {report['status']}"
        )
    return report


def reference_peaks(report: dict) -> dict[str, float]:
    """The reference's peak |x| of every displacement column (every step)."""
    return {col: report["peak"][dof] for col, dof in DOF_COLUMNS}


def relative_difference(a: float, b: float) -> float:
    """|a − b| / |b| (0 when both are 0)."""
    return 0.0 if a == b else abs(a - b) / abs(b)


def _row(label: str, us: list[float], ref_us: float, newton: float, facts, step: float) -> str:
    """One line of the table: µs/step median and minimum, ratio of the medians, Newton
    iterations per step, factorisations, step [s]."""
    med = statistics.median(us)
    facts_text = "" if facts is None else str(facts)
    return (
        f"{label:<46} {med:7.3f} {min(us):7.3f} {med / ref_us:6.2f}× "
        f"{newton:8.3f} {facts_text:>9} {step:8g}"
    )


def _engine_line(label: str, results: list, ref_us: float) -> str:
    """The table line of an engine's runs (their ``meta``: µs/step of the loop alone)."""
    meta = results[-1].meta
    steps, newton = meta["steps"], meta["newton_iterations"]
    step = meta["dt"] if "dt" in meta else meta["settings"]["h"]
    facts = meta.get("factorisations")
    if facts is None and "elastic_factor_reuses" in meta:
        facts = newton - meta["elastic_factor_reuses"]  # one solve per Newton iteration
    us = [r.meta["us_per_step"] for r in results]
    return _row(label, us, ref_us, newton / steps, facts, step)


@dataclass
class LoopTimes:
    """The timed rounds of :func:`measure`: the problem, the reference builds' loop times [s]
    (every timed repeat of every round) and last reports (also of :data:`LEAN`, the
    reference's algorithm in numba, with the variants), and the engines' results of every
    round (``meta["us_per_step"]``, ``meta["loop_time"]``: the step loop alone); with the
    variants also without energy columns, with one output row, and with neither (bare)."""

    problem: Problem
    ndof: int
    reference_seconds: dict[str, list[float]]
    reports: dict[str, dict]
    compliance: list
    nonsmooth: list
    compliance_no_energy: list
    compliance_one_row: list
    compliance_bare: list
    load_before: tuple[float, float, float]
    load_after: tuple[float, float, float]

    def reference_us(self, label: str = "reference") -> list[float]:
        """µs/step of every timed loop of the reference build ``label``."""
        return [1e6 * t / self.problem.steps for t in self.reference_seconds[label]]


def measure(
    scene, *, rounds: int = 5, repeats: int = 3, variants: bool = False, nonsmooth: bool = True
) -> LoopTimes:
    """Time the reference loop and the engines on ``scene`` in ``rounds`` interleaved rounds
    (each round: every reference build ``repeats`` times, then the compliance engine, then the
    nonsmooth engine), after one untimed run of each engine (numba loads or compiles). Raises
    ReferenceError when the reference cannot run the scene or fails."""
    if rounds < 1 or repeats < 1:
        raise ValueError(f"rounds and repeats must be >= 1, got {rounds} and {repeats}")
    check_scene(scene)
    motion = dp.support_motion(scene)
    load_before = os.getloadavg()
    warm = dp.run(scene, engine="compliance", motion=motion)  # numba loads or compiles
    if nonsmooth:
        dp.run(scene, engine="nonsmooth", motion=motion)
    problem = problem_of(scene, motion, warm)

    with tempfile.TemporaryDirectory(prefix="deckpound-reference-") as tmp:
        folder = Path(tmp)
        inputs = folder / "inputs.f64"
        nd = write_inputs(problem, inputs)
        builds = {"reference": compile_reference(folder, nd)}
        if variants:
            for label, defines in VARIANTS.items():
                builds[label] = compile_reference(folder, nd, defines)
            lean = lean_numba()
            lean_model = lean.load_inputs(inputs)
        scene_one_row = scene.replace({"run.output_dt": problem.steps * problem.dt})
        ref_times: dict[str, list[float]] = {k: [] for k in builds} | (
            {LEAN: []} if variants else {}
        )
        reports: dict[str, dict] = {}
        comp, nons, comp_noenergy, comp_onerow, comp_bare = [], [], [], [], []
        for _ in range(rounds):
            for label, exe in builds.items():
                # one loop more than timed: the first touches the input's pages
                rep = run_reference(exe, inputs, repeats + 1)
                ref_times[label] += rep["loop_seconds"][1:]
                reports[label] = rep
            if variants:  # its first loop compiles (once) and touches the pages: not timed
                rep = lean.run_lean(lean_model, repeats)
                ref_times[LEAN] += rep["loop_seconds"]
                reports[LEAN] = rep
            comp.append(dp.run(scene, engine="compliance", motion=motion))
            if variants:
                comp_noenergy.append(dp.run(scene, engine="compliance", motion=motion, channels=[]))
                comp_onerow.append(dp.run(scene_one_row, engine="compliance", motion=motion))
                comp_bare.append(
                    dp.run(scene_one_row, engine="compliance", motion=motion, channels=[])
                )
            if nonsmooth:
                nons.append(dp.run(scene, engine="nonsmooth", motion=motion))
    return LoopTimes(
        problem=problem,
        ndof=nd,
        reference_seconds=ref_times,
        reports=reports,
        compliance=comp,
        nonsmooth=nons,
        compliance_no_energy=comp_noenergy,
        compliance_one_row=comp_onerow,
        compliance_bare=comp_bare,
        load_before=load_before,
        load_after=os.getloadavg(),
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="saiidi-4span", help="built-in scene or TOML file")
    parser.add_argument(
        "--set", action="append", default=[], metavar="PATH=VALUE", help="scene override"
    )
    parser.add_argument("--rounds", type=int, default=5, help="timed rounds (median)")
    parser.add_argument("--repeats", type=int, default=3, help="reference loops per round")
    parser.add_argument("--variants", action="store_true", help="measure the emulated extras")
    parser.add_argument("--no-nonsmooth", action="store_true", help="skip the nonsmooth engine")
    args = parser.parse_args(argv)
    if args.rounds < 1 or args.repeats < 1:
        parser.error("--rounds and --repeats must be >= 1")

    scene = dp.load_scene(args.scene, set=args.set or None)
    try:
        check_scene(scene)
    except ReferenceError as exc:
        print(f"run.py: {exc}", file=sys.stderr)
        return 2
    times = measure(
        scene,
        rounds=args.rounds,
        repeats=args.repeats,
        variants=args.variants,
        nonsmooth=not args.no_nonsmooth,
    )
    problem, nd, reports = times.problem, times.ndof, times.reports
    comp, nons = times.compliance, times.nonsmooth
    load_before, load_after = times.load_before, times.load_after

    ref = reports["reference"]
    steps = problem.steps

    def ref_line(label: str) -> str:
        rep = reports[label]
        return _row(
            label,
            times.reference_us(label),
            ref_us,
            rep["newton_iterations"] / steps,
            rep["factorisations"],
            problem.dt,
        )

    ref_us = statistics.median(times.reference_us())
    print(f"scene {scene.name}: {steps} steps of {problem.dt:g} s, {nd} DOF")
    print(
        f"load average (1 min) {load_before[0]:.2f} before, {load_after[0]:.2f} after; the "
        f"machine may be shared: medians of {args.rounds} rounds, interleaved"
    )
    print(
        f"{'step loop':<46} {'µs/step':>7} {'min':>7} {'× ref':>7} {'Newton/':>8} "
        f"{'factor-':>9} {'step':>8}"
    )
    print(f"{'':<46} {'median':>7} {'':>7} {'':>7} {'step':>8} {'isations':>9} {'[s]':>8}")
    print(ref_line("reference"))
    print(_engine_line("compliance", comp, ref_us))
    if args.variants:
        for label in VARIANTS:
            print(ref_line(label))
        print(ref_line(LEAN))
        print(_engine_line("compliance, no energy columns", times.compliance_no_energy, ref_us))
        print(_engine_line("compliance, one output row", times.compliance_one_row, ref_us))
        print(_engine_line("compliance, neither", times.compliance_bare, ref_us))
    if nons:
        print(_engine_line("nonsmooth (its own step)", nons, ref_us))
        nons_s = statistics.median(r.meta["loop_time"] for r in nons)
        ref_s = ref_us * 1e-6 * steps
        print(
            f"nonsmooth loop over the record: {nons_s:.4f} s, {nons_s / ref_s:.2f}× the "
            f"reference's {ref_s:.4f} s"
        )
    peaks = reference_peaks(ref)
    last = comp[-1]
    print("peaks over every step: reference, compliance, relative difference")
    for col in DECK_COLUMNS:
        print(
            f"  {col:<12} {peaks[col]:.9g}  {last.peak(col):.9g}  "
            f"{relative_difference(peaks[col], last.peak(col)):.1e}"
        )
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ReferenceError as exc:
        print(f"run.py: {exc}", file=sys.stderr)
        sys.exit(1)

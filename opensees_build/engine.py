"""The OpenSees engine: :class:`OpenSeesEngine` (registry name ``opensees``).

Follows the engine contract of :mod:`deckpound.models.engine_contract`; :func:`run_opensees` is the
same as a function. openseespy is imported only when a model is built. The step loop (:func:`run_steps`) and
the state sampling (:func:`sample_row`) are plain functions of an ``ops`` object (the
openseespy module or anything with its functions) and the step plan, a dict of tags and
constants (:func:`step_plan`; their argument ``plan``, ``PLAN`` in the script — the plan model
:class:`~deckpound.models.plan.Plan` it is made from is another thing); :mod:`.export` copies
their source verbatim into the exported Python script, so the script and the in-process run
execute the same code.

Result columns (sign conventions):

* ``deck_x_abs``, ``deck_y_abs``, ``deck_theta`` — centre node displacement (absolute) [m, m,
  rad], θ counter-clockwise; velocities ``deck_vx_abs``, ``deck_vy_abs``, ``deck_omega`` (a
  deck of segments: ``<segment>_x_abs`` ... per segment centre node, in the plan's order);
* ``seat1_x_abs``/``seat1_theta``, ``seat2_…`` — seat node (contact-face mid-point) [m, rad]
  and their velocities;
* ``gap_<corner>`` (c1..c4, and j<k>_c1, j<k>_c2 at the joints of a deck of segments) —
  g = g₀ + n·(u_deck corner − u_seat point) with n the corner's gap-opening
  normal of the plan's corner table (``plan["normals"]``; n = (side, 0), side +1 for c1, c2 at
  seat 1 and at the joints, −1 for c3, c4, for a straight deck, where only the x
  displacements are read; at a joint the "seat point" is the facing point on the other
  segment); negative = penetration;
* ``fn_c*`` — normal contact force ≥ 0 in compression [kN] (−stress of the gap material, or the
  contact element's force on the deck projected on n);
* ``ft_c*`` — tangential contact force acting ON THE DECK corner along the face tangent
  t = (sin φ, cos φ) (+y for a straight deck) [kN] (0 without friction);
* ``<bent>_fx/_fy`` — Hysteretic material stress of the bent spring for the deformation
  deck − table [kN] (+ = the deck is pulled back towards −x / −y).
"""

from __future__ import annotations

import math
import time
import warnings
from typing import ClassVar

import numpy as np

from deckpound.models.contact_laws_table import contact_law, friction_model
from deckpound.models.contact_params import contact_resolving_step
from deckpound.models.damping import damping_model
from deckpound.models.engine_contract import (
    Engine,
    RunOutput,
    Status,
    engine_columns,
    output_stride,
)
from deckpound.models.excitation import support_motion
from deckpound.models.motion import analysis_duration
from deckpound.models.plan import Plan, plan_of
from deckpound.models.result import peak_columns
from deckpound.models.scene import Scene
from deckpound.models.scene_settings import OpenSeesSettings

from . import initial_state
from .energy import EnergyBalance, energy_closure
from .model import ModelInfo, analysis_commands, bent_bodies, build_model, refuse_scene
from .ops import OpsSession, openseespy_version

ENGINE = "opensees"


# ------------------------------------------------------------------------------------------
# Runtime functions: self-contained (math only), copied into the exported Python script.
# ------------------------------------------------------------------------------------------


def define_analysis(ops, plan):
    """(Re)define the analysis objects from plan['analysis'] (list of command tuples)."""
    for cmd in plan["analysis"]:
        getattr(ops, cmd[0])(*cmd[1:])


def corner_gaps(ops, plan):
    """Physical gaps g = g0 + n.(u_deck corner - u_seat point) of the corners [m], n the
    gap-opening normal ``plan['normals'][c]`` (a straight deck has n_y = 0: x displacements only)."""
    out = []
    for c in range(len(plan["g0"])):
        nx, ny = plan["normals"][c]
        dk, st = plan["deck_corners"][c], plan["seat_corners"][c]
        g = plan["g0"][c] + nx * (ops.nodeDisp(dk, 1) - ops.nodeDisp(st, 1))
        if ny != 0.0:
            g += ny * (ops.nodeDisp(dk, 2) - ops.nodeDisp(st, 2))
        out.append(g)
    return out


def contact_forces(ops, plan):
    """(fn, ft) of the corners [kN]: fn >= 0 compression, ft the force on the deck along the
    face tangent ``plan['tangents'][c]`` (+y for a straight deck)."""
    fn, ft = [], []
    for c in range(len(plan["g0"])):
        e = plan["gap_elements"][c] if plan["gap_elements"] else 0
        if not e:
            fn.append(0.0)
            ft.append(0.0)
        elif plan["corner_friction"][c]:
            f = ops.eleResponse(e, "force")  # resisting forces [Fx_i, Fy_i, M_i, Fx_j, Fy_j, M_j]
            # the force ON the deck (node j) is minus its resisting force; compression pushes
            # the deck along the gap-opening normal n (+x at seat 1, -x at seat 2 when straight)
            nx, ny = plan["normals"][c]
            tx, ty = plan["tangents"][c]
            fn.append(-(nx * f[3] + ny * f[4]) + 0.0)
            ft.append(-(tx * f[3] + ty * f[4]) + 0.0)
        else:
            fn.append(-ops.eleResponse(e, "basicForce")[0] + 0.0)
            ft.append(0.0)
    return fn, ft


def sample_row(ops, plan, t):
    """One output row in the order of plan['columns']: t, each deck segment's centre (x, y,
    theta), the seats (x, theta), their velocities in the same order, the corners' gaps,
    normal and tangential forces, the bents' forces (x, y)."""
    s1 = ops.nodeDisp(plan["seats"][0])
    s2 = ops.nodeDisp(plan["seats"][1])
    v1 = ops.nodeVel(plan["seats"][0])
    v2 = ops.nodeVel(plan["seats"][1])
    row = [t]
    for body in plan["bodies"]:
        dk = ops.nodeDisp(body)
        row += [dk[0], dk[1], dk[2]]
    row += [s1[0], s1[2], s2[0], s2[2]]
    for body in plan["bodies"]:
        vk = ops.nodeVel(body)
        row += [vk[0], vk[1], vk[2]]
    row += [v1[0], v1[2], v2[0], v2[2]]
    row += corner_gaps(ops, plan)
    fn, ft = contact_forces(ops, plan)
    row += fn + ft
    for e in plan["bent_elements"]:
        f = ops.eleResponse(e, "basicForce")
        row += [f[0], f[1]]
    return row


def new_tracker(ops, plan):
    """The peaks and gap closures over every step (:func:`track_step`), started at t = 0.

    Columns plan['peak_columns']: the engine columns (:func:`sample_row`), the displacements
    relative to the supports (each deck segment's x, y to the mean motion of its tables
    plan['segment_tables'], seats to their actuators) and the bent deformations (deck point
    above the bent - table, x then y, per bent), as the epilogue derives them from the output
    rows. 'value' is the largest |x| of each column so
    far (for the gaps the smallest, most negative value), 'time' its first time [s];
    'closures' counts per corner (plan['corners']) the steps at which the corner goes from out of contact to in
    contact (gap <= 0 or fn > 0), a corner in contact at t = 0 counting one. Per corner,
    'gap_open' is the largest gap so far and 'gap_open_time' its first time, 'gap_start' the
    gap at t = 0; 'unseated' = [corner, time] of the first step at which the opening
    g - g(0) exceeded the support length ``plan['support_lengths'][c]`` of the seat under it (None:
    not checked), else None (deckpound.analytic.kernels.peaks, the same rule)."""
    cols = plan["peak_columns"]
    nc = len(plan["corners"])
    g0 = cols.index("gap_" + plan["corners"][0])
    value = [0.0] * len(cols)
    for c in range(nc):
        value[g0 + c] = math.inf
    tr = {
        "value": value,
        "time": [0.0] * len(cols),
        "gap": g0,
        "fn": cols.index("fn_" + plan["corners"][0]),
        "abs": list(range(1, g0)) + list(range(g0 + nc, len(cols))),
        "inside": [False] * nc,
        "closures": [0] * nc,
        "gap_open": [-math.inf] * nc,
        "gap_open_time": [0.0] * nc,
        "gap_start": [0.0] * nc,
        "unseated": None,
    }
    track_step(ops, plan, tr, 0.0)
    return tr


def track_step(ops, plan, tr, t):
    """Update the tracker of :func:`new_tracker` with the converged state at time t [s]."""
    row = sample_row(ops, plan, t)
    tables = plan["tables"]
    ux = [ops.nodeDisp(tn, 1) for tn in tables]
    uy = [ops.nodeDisp(tn, 2) for tn in tables]
    for s, own in enumerate(plan["segment_tables"]):
        mx = sum(ux[k] for k in own) / len(own) if own else 0.0
        my = sum(uy[k] for k in own) / len(own) if own else 0.0
        row += [row[1 + 3 * s] - mx, row[2 + 3 * s] - my]
    a1, a2 = plan["actuators"]
    seat1 = 1 + 3 * len(plan["bodies"])  # the column of seat 1's x
    row += [row[seat1] - ops.nodeDisp(a1, 1), row[seat1 + 2] - ops.nodeDisp(a2, 1)]
    for k, (xb, s) in enumerate(zip(plan["bent_x"], plan["bent_bodies"])):
        row += [row[1 + 3 * s] - ux[k], row[2 + 3 * s] + xb * row[3 + 3 * s] - uy[k]]
    value, when, g0, f0 = tr["value"], tr["time"], tr["gap"], tr["fn"]
    for k in tr["abs"]:
        a = abs(row[k])
        if a > value[k]:
            value[k] = a
            when[k] = t
    for c in range(len(plan["corners"])):
        g = row[g0 + c]
        if g < value[g0 + c]:
            value[g0 + c] = g
            when[g0 + c] = t
        now = bool(plan["gap_elements"]) and (g <= 0.0 or row[f0 + c] > 0.0)
        if now and not tr["inside"][c]:
            tr["closures"][c] += 1
        tr["inside"][c] = now
        # the largest gap and the seat margin N - (g - g(0)) (the first call gives g(0))
        if g > tr["gap_open"][c]:
            if tr["gap_open"][c] == -math.inf:
                tr["gap_start"][c] = g
            tr["gap_open"][c] = g
            tr["gap_open_time"][c] = t
            support = plan["support_lengths"][c]
            if support is not None and g - tr["gap_start"][c] > support:
                if tr["unseated"] is None:
                    tr["unseated"] = [plan["corners"][c], t]


def run_steps(ops, plan, log=None, on_step=None):
    """Step the defined model plan['n_steps'] times with analyze(1, dt).

    ``on_step(ops, n)``, if given, is called after every converged analyze of step n (the
    step, or each sub-step of a rescued step): the energy balance of :mod:`.energy`.

    Every return code is checked; a failed step counts as a failure and, with
    plan['fallback'] == 'substep', is retried (the failed analyze has reverted the domain to
    its last commit) after rebuilding the analysis objects (wipeAnalysis + define_analysis:
    the Transformation handler otherwise keeps a stale increment on constrained nodes; there
    is no revertToLastCommit command in openseespy 3.7) with plan['substeps']
    sub-steps, each checked. A non-finite state is a failure. A step (with all its sub-steps)
    after which a corner is unseated (:func:`track_step`) ends the loop with status
    'unseated', its output row not written. Returns a dict with the rows and the statistics,
    among them 'peaks' ({column: [peak, time]}), 'gap_closures' (total and per corner),
    'gap_openings' ({corner: [largest g - g(0), time]}) and 'unseated' ([corner, time] or
    None) over every converged step and sub-step (:func:`new_tracker`).
    """
    dt = plan["dt"]
    n_steps = plan["n_steps"]
    stride = plan["stride"]
    rows = [sample_row(ops, plan, 0.0)]
    tr = new_tracker(ops, plan)
    stats = {
        "steps": 0,
        "iterations": 0,
        "failures": 0,
        "rescued": 0,
        "status": "success",
        "message": "",
        "failed_time": None,
        "failed_step": None,
    }
    for n in range(1, n_steps + 1):
        ok = ops.analyze(1, dt)
        if ok == 0:
            stats["iterations"] += ops.testIter()
            if on_step is not None:
                on_step(ops, n)
            track_step(ops, plan, tr, n * dt)
        else:
            stats["failures"] += 1
            if log is not None:
                log(f"step {n} (t = {n * dt:.6g} s) failed with code {ok}")
            if plan["fallback"] == "substep":
                ops.wipeAnalysis()
                define_analysis(ops, plan)
                h = dt / plan["substeps"]
                for _k in range(plan["substeps"]):
                    ok = ops.analyze(1, h)
                    if ok != 0:
                        break
                    stats["iterations"] += ops.testIter()
                    if on_step is not None:
                        on_step(ops, n)
                    last = _k == plan["substeps"] - 1
                    track_step(ops, plan, tr, n * dt if last else (n - 1) * dt + (_k + 1) * h)
                ops.wipeAnalysis()
                define_analysis(ops, plan)
                if ok == 0:
                    stats["rescued"] += 1
        if ok == 0:
            for body in plan["bodies"]:
                if not all(math.isfinite(v) for v in ops.nodeDisp(body)):
                    ok = -100
        if ok != 0:
            stats["status"] = "failed"
            stats["failed_step"] = n
            stats["failed_time"] = n * dt
            stats["message"] = (
                f"step {n} (t = {n * dt:.6g} s) did not converge"
                + (
                    f" even with {plan['substeps']} sub-steps"
                    if plan["fallback"] == "substep"
                    else ""
                )
                if ok != -100
                else f"non-finite state at step {n} (t = {n * dt:.6g} s)"
            )
            break
        stats["steps"] = n
        if tr["unseated"] is not None:
            corner, when = tr["unseated"]
            stats["status"] = "unseated"
            stats["message"] = f"corner {corner} unseated at t = {when:.6g} s (step {n})"
            break
        if n % stride == 0:
            row = sample_row(ops, plan, n * dt)
            if not all(math.isfinite(v) for v in row):
                stats["status"] = "failed"
                stats["failed_step"] = n
                stats["failed_time"] = n * dt
                stats["message"] = f"non-finite state at step {n} (t = {n * dt:.6g} s)"
                break
            rows.append(row)
    stats["gap_closures"] = sum(tr["closures"])
    names = plan["corners"]
    stats["gap_closures_per_corner"] = {name: tr["closures"][c] for c, name in enumerate(names)}
    stats["gap_openings"] = {
        name: [tr["gap_open"][c] - tr["gap_start"][c], tr["gap_open_time"][c]]
        for c, name in enumerate(names)
    }
    stats["unseated"] = tr["unseated"]
    stats["peaks"] = {
        name: [tr["value"][k], tr["time"][k]]
        for k, name in enumerate(plan["peak_columns"])
        if k > 0 and math.isfinite(tr["value"][k])
    }
    return {"rows": rows, "stats": stats}


# ------------------------------------------------------------------------------------------
# In-process driver
# ------------------------------------------------------------------------------------------


def step_plan(scene: Scene, plan: Plan, info: ModelInfo, duration: float) -> dict:
    """The step plan: tags and constants of the step loop, JSON-able (the exported scripts
    hold it as ``PLAN``; the runtime functions above take it as ``plan``). It is not the plan
    model: the corners' gaps, sides, normals and tangents, the bent stations, the columns and
    the seat each corner faces are copied from ``plan`` (:class:`Plan`), the tags from the
    built model ``info``. ``bodies``: the deck segments' centre nodes; ``segment_tables``: per
    segment the indices (in bent order) of the tables its relative displacement is measured
    from (:meth:`~deckpound.models.plan.Plan.segment_table_channels`); ``bent_bodies``: the
    segment each bent carries."""
    dt = contact_resolving_step(scene, scene.opensees.dt)
    columns = engine_columns(plan)
    x_channels = plan.table_channels("x")
    return {
        "dt": dt,
        "n_steps": int(round(duration / dt)),
        "stride": output_stride(dt, scene.run.output_dt),
        "fallback": scene.opensees.fallback,
        "substeps": scene.opensees.substeps,
        "bodies": list(info.bodies),
        "seats": list(info.seats),
        "corners": [c.name for c in plan.corners],
        "deck_corners": list(info.deck_corners),
        "seat_corners": list(info.seat_corners),
        "gap_elements": list(info.gap_elements),
        "g0": [c.gap for c in plan.corners],
        "sides": [c.side for c in plan.corners],
        "normals": [list(c.normal) for c in plan.corners],
        "tangents": [list(c.tangent) for c in plan.corners],
        "bent_elements": list(info.bent_elements),
        "corner_friction": list(info.corner_friction),
        "analysis": [list(c) for c in analysis_commands(scene)],
        "columns": columns,
        "bent_x": list(plan.bent_x),
        "bent_bodies": bent_bodies(plan),
        "segment_tables": [
            [x_channels.index(ch) for ch in plan.segment_table_channels(seg.index, "x")]
            for seg in plan.segments
        ],
        "peak_columns": peak_columns(columns, plan.bent_names, plan.relative_columns),
        # the support length under each corner [m] (None: unseating not checked)
        "support_lengths": [c.support_length for c in plan.corners],
    }


def build(ops, scene: Scene, motion=None, plan: Plan | None = None):
    """Build model + analysis in an open session on the plan model ``plan`` (default: the
    scene's); returns (info, the step plan of :func:`step_plan`)."""
    if plan is None:
        plan = plan_of(scene)
    if motion is None:
        motion = support_motion(scene)
    duration = analysis_duration(scene, motion)
    dt = contact_resolving_step(scene, scene.opensees.dt)
    # Path series interpolate linearly, exactly as the record is meant between samples: give
    # OpenSees the record at its own (uniform) step when that is coarser than the analysis
    # step, so memory does not grow with the number of steps (6e6 steps at dt = 1e-5).
    rec = np.diff(motion.t)
    uniform = len(rec) > 0 and np.allclose(rec, rec[0], rtol=1e-9, atol=0.0)
    step = float(rec[0]) if uniform and dt < rec[0] <= duration else dt
    res = motion.resample(step, duration)
    damping = damping_model(scene, plan)
    info = build_model(ops, scene, res, plan=plan, damping=damping)
    steps = step_plan(scene, plan, info, duration)
    # the support nodes whose displacements the step loop reads (relative columns)
    nodes = ops.tags("node")
    steps["tables"] = [nodes[f"table {b}"] for b in info.bent_names]
    steps["actuators"] = [nodes["actuator1"], nodes["actuator2"]]
    ops.comment("analysis")
    for cmd in steps["analysis"]:
        ops.call(*cmd)
    # part of the build (not of the run) so that the exported scripts start from the same
    # initial state as the in-process run (issue 12: textbook scenes)
    initial_state.set_initial_displacement(ops, scene, plan, info)
    initial_state.set_initial_velocity(ops, scene, plan, info)
    initial_state.set_initial_acceleration(ops, scene, res, plan, damping, info)
    return info, steps


def command_log(scene: Scene, motion=None):
    """The benchmark-style command log of the scene (model + analysis, no stepping)."""
    with OpsSession() as ops:
        build(ops, scene, motion)
        return list(ops.log)


def run_status(stats: dict, state_finite: bool) -> Status:
    """How the step loop ended, from the statistics of :func:`run_steps` and the numbers of
    the last state: a failed run whose last state holds a non-finite number is
    :attr:`Status.NONFINITE`, else :attr:`Status.NOT_CONVERGED` (a failed ``analyze``
    reverts the domain to its last commit, which the loop found finite)."""
    if stats["status"] == "success":
        return Status.SUCCESS
    if stats["status"] == "unseated":
        return Status.UNSEATED
    return Status.NOT_CONVERGED if state_finite else Status.NONFINITE


def state_is_finite(ops, plan: dict, t: float) -> bool:
    """True when every number of the output row of the current state (:func:`sample_row`)
    is finite."""
    return all(math.isfinite(v) for v in sample_row(ops, plan, t))


class OpenSeesEngine(Engine):
    """The paper's OpenSees stick model, run through openseespy (module docstring)."""

    name = ENGINE
    title = "OpenSees stick model (openseespy)"
    Settings = OpenSeesSettings
    settings_field = "opensees"
    step_field = "dt"
    style: ClassVar[dict] = dict(color="#000000", linestyle="-", linewidth=1.4, label="OpenSees")

    def reads(self, scene: Scene, settings) -> set[str]:
        """The law's and the friction model's parameters, from their rows of
        :mod:`deckpound.models.contact_laws_table` (a model OpenSees refuses is refused before
        this matters, :func:`.model.refuse_scene`)."""
        ct = scene.contact
        read = {"contact.law", "contact.stiffness", "run.steps_per_contact_period"}
        read |= set(contact_law(ct.law).params)
        if ct.friction_mode != "none":
            read.add("contact.friction")
        if ct.friction > 0.0:
            read.add("contact.friction_mode")
            read |= set(friction_model(ct.friction_mode).params)
        if settings.mode == "stick":
            read.add("deck.stick_modulus")
        return read

    def refuse(self, scene: Scene, settings) -> None:
        refuse_scene(scene)
        if initial_state.displaced(scene):
            initial_state.refuse_initial_displacement(scene, settings)

    def _run(
        self, plan: Plan, scene: Scene, settings, motion, *, _before_run=None, _ops_wrapper=None
    ) -> RunOutput:
        """``_before_run(ops_raw, info, steps)`` and ``_ops_wrapper(ops_raw) -> ops`` are test
        hooks (set initial velocities; inject a failing step)."""
        if settings is not scene.opensees:
            scene = scene.replace(opensees=settings)
        messages: list[str] = []
        t0 = time.perf_counter()
        with OpsSession() as ops:
            info, steps = build(ops, scene, motion, plan)
            raw = ops.raw
            if _before_run is not None:
                _before_run(raw, info, steps)
            runner_ops = _ops_wrapper(raw) if _ops_wrapper is not None else raw
            balance = EnergyBalance(raw, scene, plan, info, steps, ops.tags("element"))
            t1 = time.perf_counter()
            out = run_steps(runner_ops, steps, log=messages.append, on_step=balance)
            loop = time.perf_counter() - t1
            st = out["stats"]
            end = st["failed_time"] if st["failed_time"] is not None else 0.0
            finite = st["status"] != "failed" or state_is_finite(runner_ops, steps, end)
            status = run_status(st, finite)
        cols = steps["columns"]
        arr = np.array(out["rows"], dtype=float).reshape(-1, len(cols))
        columns = {c: arr[:, k].copy() for k, c in enumerate(cols)}
        columns.update(balance.columns(len(arr)))  # the energy columns [kJ], every step's work
        if st["failures"]:
            warnings.warn(
                f"OpenSees: {st['failures']} failed step(s), {st['rescued']} rescued "
                "by sub-stepping",
                stacklevel=4,
            )
        return RunOutput(
            columns=columns,
            status=status,
            message=run_message(status, st, settings),
            failed_step=st["failed_step"],
            failed_time=st["failed_time"],
            steps=st["steps"],
            newton_iterations=st["iterations"],
            failed_steps=st["failures"],
            rescued_steps=st["rescued"],
            loop_time=loop,
            peaks={k: (v[0], v[1]) for k, v in st["peaks"].items()},
            # the deepest penetration over every converged step and sub-step (the gap peaks)
            max_penetration=max(
                [0.0] + [-v[0] for k, v in st["peaks"].items() if k.startswith("gap_")]
            ),
            gap_closures_per_corner=st["gap_closures_per_corner"],
            gap_openings={k: (v[0], v[1]) for k, v in st["gap_openings"].items()},
            unseated=None if st["unseated"] is None else tuple(st["unseated"]),
            extra={
                "openseespy": openseespy_version(),
                "dt": steps["dt"],
                "build_time": t1 - t0,
                "step_log": messages[:100],
                "energy_closure": energy_closure(columns),
            },
        )


def run_message(status: Status, stats: dict, settings: OpenSeesSettings) -> str:
    """The run's message: empty on success, the loop's own for unseating (which corner,
    when), else the status text of :class:`Status` (with the sub-steps the fallback tried)."""
    if status is Status.SUCCESS:
        return ""
    if status is Status.UNSEATED:
        return stats["message"]
    if status is Status.NOT_CONVERGED and settings.fallback == "substep":
        return f"{status.text} even with {settings.substeps} sub-steps"
    return status.text


def run_opensees(scene: Scene, motion=None, *, raise_on_failure: bool = False, **options):
    """Run the scene in OpenSees (keywords of :meth:`OpenSeesEngine._run`)."""
    return OpenSeesEngine().run(scene, None, motion, raise_on_failure=raise_on_failure, **options)

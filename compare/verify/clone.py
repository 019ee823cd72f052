"""Cross-verification of the compliance engine's Newmark clone against the OpenSees engine.

:func:`verify_clone` runs the same scene through ``deckpound.opensees_build.engine.run_opensees``
(rigid mode) and :func:`deckpound.analytic.compliance.engine.run_compliance` (``newmark``) with the same
step and Newton tolerance and reports, per standard result column, the largest deviation
relative to the column's peak, plus the speed ratio. On the benchmark (frictionless linear gap,
tolerance 1e-12) the two agree to ~1e-9 of the peaks over the whole record with identical
Newton iteration counts. Velocities are compared separately (``worst_velocity``): Newmark's
u̇_{n+1} = (2/Δt)(u_{n+1} − u_n) − u̇_n amplifies the round-off of the displacements by 2/Δt,
so the light, stiff seat rotations agree to ~1e-9 of their peak velocity rather than ~1e-11.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from deckpound.models.columns import column_names, column_unit
from deckpound.models.excitation import support_motion
from deckpound.models.plan import plan_of
from deckpound.models.scene import Scene
from deckpound.opensees_build.engine import run_opensees

__all__ = ["TWIN_SCALE", "column_deviations", "opensees_friction", "twin_motion", "verify_clone"]

#: relative change of the support motion of the clone's twin run (:func:`verify_clone`): a
#: few hundred ulps, far below anything a record or a model determines
TWIN_SCALE = 1e-13


def column_deviations(a, b, columns) -> dict[str, float]:
    """max |a − b| / max |a| per column over the common length (0 for all-zero columns)."""
    out = {}
    for c in columns:
        x, y = np.asarray(a[c]), np.asarray(b[c])
        n = min(len(x), len(y))
        peak = float(np.max(np.abs(x[:n]))) if n else 0.0
        dev = float(np.max(np.abs(x[:n] - y[:n]))) if n else 0.0
        out[c] = dev / peak if peak > 0 else dev
    return out


def opensees_friction(scene: Scene) -> tuple[Scene, list[str]]:
    """The scene OpenSees can verify, and a note for every change made.

    The project's ``stick`` law has no OpenSees element (the OpenSees engine refuses it); the
    clone verifies the friction algorithm OpenSees does have, zeroLengthContact2D, which the
    compliance engine runs as ``contact2d``. So ``friction_mode = stick`` is verified as
    ``contact2d``, and the returned note says so (never silently)."""
    wheres = [
        where
        for where, ct in scene.contact_tables()
        if ct.has_friction and ct.friction_mode == "stick"
    ]
    if not wheres:
        return scene, []
    sc = scene.replace(dict.fromkeys((f"{w}.friction_mode" for w in wheres), "contact2d"))
    return sc, [
        "friction_mode = 'stick'"
        + ("" if w == "contact" else f" at {w}")
        + " (the project's stick law) has no OpenSees counterpart; verifying friction_mode = "
        "'contact2d' (OpenSees's zeroLengthContact2D algorithm, in both engines) instead"
        for w in wheres
    ]


def twin_motion(motion, scale: float = TWIN_SCALE):
    """``motion`` with every support displacement and velocity multiplied by 1 + ``scale``."""
    factor = 1.0 + scale
    return dataclasses.replace(
        motion,
        disp={ch: x * factor for ch, x in motion.disp.items()},
        vel={ch: v * factor for ch, v in motion.vel.items()},
        acc_exact=None
        if motion.acc_exact is None
        else {ch: a * factor for ch, a in motion.acc_exact.items()},
    )


def verify_clone(
    scene: Scene,
    motion=None,
    *,
    tolerance: float | None = 1e-12,
    twin: bool = False,
    twin_scale: float = TWIN_SCALE,
) -> dict:
    """Run OpenSees (rigid) and the Newmark clone on ``scene``; report their agreement.

    The clone takes the OpenSees step, tolerance and iteration limit (``tolerance`` overrides
    both when given) and the OpenSees materials' contact tangents
    (``compliance.contact_tangent = "opensees"``: the same Newton iterates).
    ``friction_mode = stick`` is verified as ``contact2d`` (:func:`opensees_friction`). Returns
    ``{"notes": [...], "peaks": {column: OpenSees peak}, "deviation": {column: rel. dev.},
    "worst": (column, dev),
    "speed_ratio": OpenSees wall time / clone wall time (clone compiled beforehand),
    "us_per_step": {...}, "iterations": {...}, "status": {...}}``.

    ``twin``: also run the clone on the support motion scaled by 1 + ``twin_scale`` (default
    :data:`TWIN_SCALE`) and report how far that moves the clone itself (``"twin_deviation"``,
    ``"twin_worst"``, same measure; ``"twin_scale"``): how well the scene's response is
    determined at all. Stiff contact makes it
    sensitive — a step's Newton iteration count flips on round-off, and the impacts that
    follow amplify the difference — so a deviation between the engines above the tolerance
    is only a disagreement of the models when the twin stays within it.
    """
    from deckpound.analytic.compliance.engine import run_compliance

    scene, notes = opensees_friction(scene)
    os_set = scene.opensees
    if tolerance is not None:
        os_set = dataclasses.replace(os_set, tolerance=tolerance)
    os_set = dataclasses.replace(os_set, mode="rigid")
    cp_set = dataclasses.replace(
        scene.compliance,
        integrator="newmark",
        dt=os_set.dt,
        tolerance=os_set.tolerance,
        max_iterations=os_set.max_iterations,
        contact_tangent="opensees",
    )
    sc = scene.replace(opensees=os_set, compliance=cp_set)
    if motion is None:
        motion = support_motion(sc)
    # numba compiles (or loads) the clone's kernels on first use: a short run first keeps that
    # one-off cost out of the timed comparison
    run_compliance(sc.replace(run=dataclasses.replace(sc.run, duration=0.01)), motion)
    ro = run_opensees(sc, motion)
    rc = run_compliance(sc, motion)
    cols = [c for c in column_names(plan_of(sc)) if c != "t"]  # a deck of segments' too
    dev = column_deviations(ro.columns, rc.columns, cols)
    velocity = {c for c in cols if column_unit(c) in ("m/s", "rad/s")}
    worst = max(((c, d) for c, d in dev.items() if c not in velocity), key=lambda kv: kv[1])
    worst_velocity = max(((c, d) for c, d in dev.items() if c in velocity), key=lambda kv: kv[1])
    steps = max(int(ro.meta.get("steps", 1)), 1)
    extra = {}
    if twin:
        rt = run_compliance(sc, twin_motion(motion, twin_scale))
        twin_dev = column_deviations(rc.columns, rt.columns, cols)
        extra = {
            "twin_scale": twin_scale,
            "twin_deviation": twin_dev,
            "twin_worst": max(
                ((c, d) for c, d in twin_dev.items() if c not in velocity), key=lambda kv: kv[1]
            ),
        }
    return {
        **extra,
        "notes": notes,
        "peaks": {c: float(np.max(np.abs(np.asarray(ro.columns[c])))) for c in cols},
        "deviation": dev,
        "worst": worst,
        "worst_velocity": worst_velocity,
        "speed_ratio": ro.meta["wall_time"] / rc.meta["wall_time"],
        "us_per_step": {
            "opensees": 1e6 * ro.meta["wall_time"] / steps,
            "compliance": rc.meta["us_per_step"],
        },
        "iterations": {
            "opensees": ro.meta.get("newton_iterations"),
            "compliance": rc.meta.get("newton_iterations"),
        },
        "status": {"opensees": ro.meta["status"], "compliance": rc.meta["status"]},
        # how and when each failed run stopped (None: it finished)
        "failed": {
            name: (r.meta["failure"], r.meta.get("failed_step"), r.meta.get("failed_time"))
            if r.meta.get("failure")
            else None
            for name, r in (("opensees", ro), ("compliance", rc))
        },
        # where and when each run stopped unseated (None: it did not)
        "unseated": {
            name: (r.meta["unseated_corner"], r.meta["unseated_time"])
            if r.meta.get("unseated")
            else None
            for name, r in (("opensees", ro), ("compliance", rc))
        },
    }

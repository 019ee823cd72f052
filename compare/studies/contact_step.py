"""Does the default step resolve the contact? The contact-step rule, measured (issue 28).

The fixed-step penalty engines take at most T_c / ``run.steps_per_contact_period`` per step
(:func:`deckpound.models.contact_params.contact_resolving_step`). For each contact stiffness k
of a scene, :func:`contact_step_table` runs the compliance engine (the OpenSees clone: the same
step, the same answer to round-off up to the first impact) at its default step and at a tenth
of it, and measures

* ``step`` [s] — the default step the rule gives, and ``steps_per_period`` = T_c / step;
* ``created`` — energy created at the contacts over the input energy
  (:func:`deckpound.models.engine_contract.energy_quality`), at the default step and at the tenth;
* ``peak_theta`` [rad] — the peak deck rotation over every step at the default step, and
  ``theta_error`` — its relative difference from the run at a tenth of the step;
* what the rule does not promise, measured the same way: ``force_error``, the relative
  difference of the largest contact force (over the corners, every step) from the tenth-step
  run, and the gap closures at both steps (``closures``, ``closures_tenth``). A few steps per
  contact period resolve the energy exchanged and the deck's motion, not the shape of each
  force pulse: its peak and whether a grazing contact counts as a closure need more.

The rule's stated error (docs/user-guide.md, "Is the answer right?"): at the default step no energy is
created beyond ``run.energy_tolerance`` and the peak rotation is within :data:`PEAK_TOLERANCE`
of the tenth-step run. ``deckpound verify contact-step SCENE`` prints the table and exits 1
when a row misses it; ``docs/contact_step.md`` holds the benchmark's table, written by
``tools/contact_step_table.py`` and checked by ``tests/test_contact_step_table.py``.
"""

from __future__ import annotations

import dataclasses
import warnings

from deckpound.compare.engines import run_engine
from deckpound.models.contact_params import contact_period
from deckpound.models.plan import CORNER_NAMES
from deckpound.models.scene import Scene

__all__ = ["PEAK_TOLERANCE", "STIFFNESSES", "contact_step_table", "failures", "format_table"]

#: contact stiffnesses of the table [kN/m]: the paper's and two and four decades stiffer
STIFFNESSES = (1.0e6, 1.0e7, 1.0e8)
#: largest relative peak-rotation difference from the tenth-step run the rule may leave
PEAK_TOLERANCE = 0.01


def _run_at(scene: Scene, k: float, dt: float | None) -> object:
    contact = dataclasses.replace(scene.contact, stiffness=k)
    sc = scene.replace(contact=contact)
    if dt is not None:  # a given step, run as given
        sc = sc.replace(
            compliance=dataclasses.replace(sc.compliance, integrator="newmark", dt=dt),
            run=dataclasses.replace(sc.run, steps_per_contact_period=0.0),
        )
    else:
        sc = sc.replace(compliance=dataclasses.replace(sc.compliance, integrator="newmark"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run_engine("compliance", sc), sc


def contact_step_table(scene: Scene, stiffnesses=STIFFNESSES) -> list[dict]:
    """One row per contact stiffness (module docstring)."""
    rows = []
    for k in stiffnesses:
        default, sc = _run_at(scene, float(k), None)
        step = float(default.meta["dt"])
        fine, _ = _run_at(scene, float(k), step / 10.0)
        m, mf = default.meta, fine.meta
        ref = fine.peak("deck_theta")
        force, force_tenth = (max(r.peak(f"fn_{c}") for c in CORNER_NAMES) for r in (default, fine))
        rows.append(
            {
                "stiffness": float(k),
                "step": step,
                "steps_per_period": contact_period(sc) / step,
                "status": m["status"],
                "created": m.get("energy_created", float("nan")) / m["energy_reference"],
                "created_tenth": mf.get("energy_created", float("nan")) / mf["energy_reference"],
                "peak_theta": default.peak("deck_theta"),
                "theta_error": abs(default.peak("deck_theta") - ref) / ref,
                "tolerance": sc.run.energy_tolerance,
                "force_error": abs(force - force_tenth) / force_tenth,
                "closures": int(m["gap_closures"]),
                "closures_tenth": int(mf["gap_closures"]),
            }
        )
    return rows


def failures(rows: list[dict]) -> list[str]:
    """The rows that miss the rule's stated error, in words (empty when every row meets it)."""
    out = []
    for r in rows:
        if r["status"] != "success" or r["created"] > r["tolerance"]:
            out.append(f"k = {r['stiffness']:g}: {r['status']}, energy created {r['created']:.3g}")
        if r["theta_error"] > PEAK_TOLERANCE:
            out.append(
                f"k = {r['stiffness']:g}: peak rotation {r['theta_error']:.3g} from the "
                f"tenth-step run (> {PEAK_TOLERANCE:g})"
            )
    return out


def format_table(rows: list[dict]) -> str:
    """The rows as a Markdown table (3 significant digits)."""
    lines = [
        "| k [kN/m] | default step [s] | steps per T_c | status | energy created / input "
        "(default; tenth step) | peak θ_d [mrad] | θ_d vs tenth step | peak contact force vs "
        "tenth step | gap closures (default; tenth step) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['stiffness']:.0e} | {r['step']:.3g} | {r['steps_per_period']:.3g} | "
            f"{r['status']} | {r['created']:.2e}; {r['created_tenth']:.2e} | "
            f"{1e3 * r['peak_theta']:.4g} | {r['theta_error']:.2e} | {r['force_error']:.2e} | "
            f"{r['closures']}; {r['closures_tenth']} |"
        )
    return "\n".join(lines)

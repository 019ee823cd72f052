"""The headline numbers of one case of a study (its table row) and the contact-resolving
compliance step the studies run at."""

from __future__ import annotations

from deckpound.compare.cases import Case
from deckpound.models.contact_params import contact_period
from deckpound.models.result import Result
from deckpound.models.scene import Scene


def contact_step(scene: Scene, per_period: int = 20) -> float:
    """Compliance time step resolving the stiffest contact oscillation (linearised) [s]:
    ``per_period`` steps per :func:`~deckpound.models.contact_params.contact_period`."""
    return float(min(scene.compliance.dt, contact_period(scene) / per_period))


#: units of the columns of :func:`case_row` (and of the sequence table, which adds its own)
ROW_UNITS = {
    "peak_theta": "rad",
    "peak_x_rel": "m",
    "peak_y_rel": "m",
    "peak_x_abs": "m",
    "peak_y_abs": "m",
    "peak_fn": "kN",
    "gap1_start": "m",
    "gap2_start": "m",
    "wall_time": "s",
    "compile_time": "s",
    "gap_closures": "-",
    "stiffness": "kN/m",
    "mu": "-",
}


def case_row(case: Case, result: Result, state: str = "virgin") -> dict:
    """Headline numbers of one case: peaks of the deck displacements relative to the supports
    (``_rel``) and absolute (``_abs``), of the rotation and of the normal gap force, over every
    step (:meth:`Result.peak`), the gap closures (every step), the start state and gaps, the run
    time without compilation (``wall_time``) and the compilation time apart."""
    row = dict(label=case.label, engine=case.engine, **case.params)
    row.update(
        state=state,
        gap1_start=case.scene.seats[0].gap,
        gap2_start=case.scene.seats[1].gap,
        peak_theta=result.peak("deck_theta"),
        peak_x_rel=result.peak("deck_x_rel"),
        peak_y_rel=result.peak("deck_y_rel"),
        peak_x_abs=result.peak("deck_x_abs"),
        peak_y_abs=result.peak("deck_y_abs"),
        peak_fn=max(result.peak(f"fn_c{c}") for c in range(1, 5)),
        gap_closures=result.gap_closures,
        wall_time=result.meta.get("wall_time", float("nan")),
        compile_time=result.meta.get("compile_time", float("nan")),
        status=result.meta.get("status"),
    )
    return row

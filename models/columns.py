"""The result columns every engine writes: names, units, meanings and labels.

Output order: time, absolute displacements (:data:`deckpound.models.plan.DOF_COLUMNS`), the
relative displacements, absolute velocities, then per corner the gap, normal and tangential
force, and per bent the spring forces and deformations. Units are SI with kN (m, rad, s, kN,
kN·s, kJ); :func:`column_unit` also names those of the engine-specific extras.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from .plan import CORNER_NAMES, Plan, deck_column_names

__all__ = [
    "ENERGY_COLUMNS",
    "Column",
    "column_names",
    "column_unit",
    "plan_columns",
    "result_columns",
    "standard_columns",
]

#: The work–energy balance columns of the penalty engines (compliance, OpenSees) [kJ], in
#: order: ``energy_input`` (work of the support reactions −∫ f_springᵀ S du_g plus the initial
#: mechanical energy), ``energy_kinetic``, ``energy_strain`` (recoverable energy of the bent and
#: seat springs), ``energy_viscous`` (Rayleigh and dashpots), ``energy_hysteretic`` (Takeda),
#: ``energy_contact_stored``, ``energy_contact_dissipated``, ``energy_friction`` (dissipated by
#: slip) and ``energy_error`` = input − all the others. Work terms are trapezoidal over each step.
ENERGY_COLUMNS = (
    "energy_input",
    "energy_kinetic",
    "energy_strain",
    "energy_viscous",
    "energy_hysteretic",
    "energy_contact_stored",
    "energy_contact_dissipated",
    "energy_friction",
    "energy_error",
)


@dataclass(frozen=True)
class Column:
    """One result column: name, unit, one-line meaning and its labels (for named dimensions)."""

    name: str
    unit: str
    doc: str
    group: str
    labels: tuple[tuple[str, str], ...] = ()


def _unit_of(name: str) -> str:
    if name == "t":
        return "s"
    if name.endswith(("_theta",)):
        return "rad"
    if name.endswith("_omega"):
        return "rad/s"
    if name.startswith(("deck_v", "seat1_v", "seat2_v")) or name.endswith(("_vx_abs", "_vy_abs")):
        return "m/s"
    if name.endswith(("_x_abs", "_y_abs", "_x_rel", "_y_rel")):
        return "m"
    if name.startswith(("gap_", "deck_", "seat", "ux_", "uy_")) or name.endswith(("_dx", "_dy")):
        return "m"
    if name.startswith(("fn_", "ft_")) or name.endswith(("_fx", "_fy")):
        return "kN"
    if name.startswith(("pn_", "pt_")):
        return "kN*s"
    if name.startswith("state_"):
        return "0 open, 1 stick, 2 slip"
    if name.startswith("energy_"):
        return "kJ"
    return "-"


def column_unit(name: str) -> str:
    """SI unit of a result column, from its name (engine-specific extras included)."""
    return _unit_of(name)


def standard_columns(bent_names, bodies=("deck",), corners=CORNER_NAMES) -> list[str]:
    """Names of the columns every engine's result holds, in order (:func:`result_columns`)."""
    return [c.name for c in result_columns(tuple(bent_names), tuple(bodies), tuple(corners))]


def _body_of(name: str, bodies: tuple[str, ...]) -> str:
    """The body a DOF column belongs to: a segment's name (the longest that prefixes the
    column, since names may contain _) or seat1/seat2."""
    hits = [b for b in bodies if name.startswith(f"{b}_")]
    return max(hits, key=len) if hits else name.split("_")[0]


@functools.lru_cache(maxsize=64)
def result_columns(
    bent_names: tuple[str, ...],
    bodies: tuple[str, ...] = ("deck",),
    corners: tuple[str, ...] = CORNER_NAMES,
) -> tuple[Column, ...]:
    """The standard columns of a model with these bents, deck bodies (``("deck",)``, or the
    segments' names) and corners, in output order (frozen columns, made once per model
    layout: every run of a sweep asks for them)."""
    dof, vel, rel = deck_column_names(bodies)
    cols = [Column("t", "s", "time", "time")]
    for name in dof:
        part = _body_of(name, bodies)
        cols.append(
            Column(
                name,
                _unit_of(name),
                f"{part} displacement, absolute",
                "absolute",
                (("body", part),),
            )
        )
    for name in rel:
        part = _body_of(name, bodies)
        if part == "deck":
            what = "the mean shake-table motion"
        elif part in bodies:
            what = "the mean motion of its bents' tables"
        else:
            what = "its actuator"
        cols.append(
            Column(
                name, "m", f"{part} displacement relative to {what}", "relative", (("body", part),)
            )
        )
    for name in vel:
        part = _body_of(name, bodies)
        cols.append(
            Column(
                name, _unit_of(name), f"{part} velocity, absolute", "velocity", (("body", part),)
            )
        )
    cols += _corner_columns(corners)
    cols += _bent_columns(bent_names)
    return tuple(cols)


def _corner_columns(corners: tuple[str, ...]) -> list[Column]:
    cols = []
    for c in corners:
        cols.append(
            Column(
                f"gap_{c}", "m", f"gap at corner {c} (< 0: penetration)", "gap", (("corner", c),)
            )
        )
    for c in corners:
        cols.append(
            Column(
                f"fn_{c}",
                "kN",
                f"normal contact force at {c} (compression > 0)",
                "normal_force",
                (("corner", c),),
            )
        )
    for c in corners:
        cols.append(
            Column(
                f"ft_{c}",
                "kN",
                f"tangential contact force on the deck at {c} along the face tangent",
                "tangential_force",
                (("corner", c),),
            )
        )
    return cols


def _bent_columns(bent_names: tuple[str, ...]) -> list[Column]:
    cols = []
    for b in bent_names:
        for d in ("x", "y"):
            cols.append(
                Column(
                    f"{b}_f{d}",
                    "kN",
                    f"bent {b} spring force in {d}",
                    "bent_force",
                    (("bent", b), ("direction", d)),
                )
            )
    for b in bent_names:
        for d in ("x", "y"):
            cols.append(
                Column(
                    f"{b}_d{d}",
                    "m",
                    f"bent {b} spring deformation in {d} (deck point above the bent − table)",
                    "bent_deformation",
                    (("bent", b), ("direction", d)),
                )
            )
    return cols


def plan_columns(plan: Plan) -> tuple[Column, ...]:
    """The standard columns of ``plan``: :func:`result_columns` of its bents, segments and
    corners."""
    return result_columns(
        plan.bent_names, tuple(s.name for s in plan.segments), tuple(c.name for c in plan.corners)
    )


def column_names(plan: Plan) -> list[str]:
    """Names of the standard result columns of ``plan`` (every engine writes them), in
    output order: :func:`result_columns` of its bents, segments and corners."""
    return [c.name for c in plan_columns(plan)]

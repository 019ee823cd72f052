"""The result columns every engine writes: names, units, meanings and labels.

Output order: time, absolute displacements (:data:`deckpound.models.plan.DOF_COLUMNS`), the
relative displacements, absolute velocities, then per corner the gap, normal and tangential
force, and per bent the spring forces and deformations. Units are SI with kN (m, rad, s, kN,
kN·s, kJ); :func:`column_unit` also names those of the engine-specific extras.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from .plan import CORNER_NAMES, DOF_COLUMNS, RELATIVE_COLUMNS, VELOCITY_COLUMNS, Plan

__all__ = [
    "ENERGY_COLUMNS",
    "Column",
    "column_names",
    "column_unit",
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
    if name.startswith(("deck_v", "seat1_v", "seat2_v")):
        return "m/s"
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


def standard_columns(bent_names) -> list[str]:
    """Names of the columns every engine's result holds, in order (see :meth:`deckpound.models.plan.Plan.columns`)."""
    return [c.name for c in result_columns(tuple(bent_names))]


@functools.lru_cache(maxsize=64)
def result_columns(bent_names: tuple[str, ...]) -> tuple[Column, ...]:
    """The standard columns of a model with these bents, in output order (frozen columns,
    made once per set of bent names: every run of a sweep asks for them)."""
    cols = [Column("t", "s", "time", "time")]
    for name, _ in DOF_COLUMNS:
        part = name.split("_")[0]
        cols.append(
            Column(
                name,
                _unit_of(name),
                f"{part} displacement, absolute",
                "absolute",
                (("body", part),),
            )
        )
    for name in RELATIVE_COLUMNS:
        part = name.split("_")[0]
        what = "the mean shake-table motion" if part == "deck" else "its actuator"
        cols.append(
            Column(
                name, "m", f"{part} displacement relative to {what}", "relative", (("body", part),)
            )
        )
    for name, _ in VELOCITY_COLUMNS:
        part = name.split("_")[0]
        cols.append(
            Column(
                name, _unit_of(name), f"{part} velocity, absolute", "velocity", (("body", part),)
            )
        )
    for c in CORNER_NAMES:
        cols.append(
            Column(
                f"gap_{c}", "m", f"gap at corner {c} (< 0: penetration)", "gap", (("corner", c),)
            )
        )
    for c in CORNER_NAMES:
        cols.append(
            Column(
                f"fn_{c}",
                "kN",
                f"normal contact force at {c} (compression > 0)",
                "normal_force",
                (("corner", c),),
            )
        )
    for c in CORNER_NAMES:
        cols.append(
            Column(
                f"ft_{c}",
                "kN",
                f"tangential contact force on the deck at {c} along the face tangent",
                "tangential_force",
                (("corner", c),),
            )
        )
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
    return tuple(cols)


def column_names(plan: Plan) -> list[str]:
    """Names of the standard result columns of ``plan`` (every engine writes them), in
    output order: :func:`result_columns` of its bents."""
    return [c.name for c in result_columns(plan.bent_names)]

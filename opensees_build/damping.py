"""Damping of the OpenSees model, read from the damping model every engine applies
(:class:`deckpound.models.damping.DampingModel`, the scene's ``[damping]``): the ``rayleigh``
factors, the spring elements that take them, and the mass-proportional dashpots on relative
velocities. Used by :func:`deckpound.opensees_build.model.build_model` and
:class:`deckpound.opensees_build.energy.EnergyBalance`.
"""

from __future__ import annotations

from dataclasses import dataclass

from deckpound.models.damping import DampingModel
from deckpound.models.plan import SEAT_THETA, SEAT_X, Plan

from .ops import OpsSession

__all__ = [
    "MEMBERS_TEXT",
    "MassDamperElement",
    "ReferenceNode",
    "mass_dampers",
    "rayleigh_factors",
    "rayleigh_members",
]

#: the springs of each ``damping.members`` choice, in words (the command log's comment)
MEMBERS_TEXT = {
    "bents": "bent springs",
    "bents+seats": "bent and seat springs",
    "none": "no springs",
}


def rayleigh_members(plan: Plan, damping: DampingModel) -> tuple[list[bool], list[bool]]:
    """(per bent, per seat) whether its spring element takes the stiffness-proportional part
    (``-doRayleigh 1``): one of its plan springs is damped (``damping.damped``). The plan's
    springs come in pairs, (x, y) per bent, then (x, θ) per seat (:class:`Plan`)."""
    on = damping.damped
    pairs = [bool(on[k] or on[k + 1]) for k in range(0, plan.n_springs, 2)]
    n_bents = len(plan.bent_names)
    return pairs[:n_bents], pairs[n_bents:]


def rayleigh_factors(damping: DampingModel) -> tuple[float, float, float, float]:
    """``rayleigh αM βK βKinit βKc``: αM = a0 on absolute velocities (0 when the mass part is
    relative: dashpots then carry it, :func:`mass_dampers`), a1 on the tangent the damping
    model names (current → βK, initial → βKinit, committed → βKc)."""
    a1 = damping.a1
    st = damping.stiffness
    return (
        damping.a0_absolute,
        a1 if st == "current" else 0.0,
        a1 if st == "initial" else 0.0,
        a1 if st == "committed" else 0.0,
    )


@dataclass(frozen=True)
class MassDamperElement:
    """One zeroLength of the relative mass damping (:func:`mass_dampers`): its element tag,
    the global DOFs of its directions (0 x, 1 y, 2 θ) and their Viscous coefficients c
    [kN·s/m, kN·m·s/rad]."""

    element: int
    dofs: tuple[int, ...]
    c: tuple[float, ...]


@dataclass(frozen=True)
class ReferenceNode:
    """A reference node of the relative mass damping that follows a shake table: its tag and
    the support channels (indices in ``Plan.channels``) of the table's x and y motion."""

    node: int
    channel_x: int
    channel_y: int


def mass_dampers(
    ops: OpsSession,
    plan: Plan,
    damping: DampingModel,
    bodies: list[int],
    origins,
    seats,
    acts,
    supports: str,
) -> tuple[list[ReferenceNode], list[MassDamperElement]]:
    """The mass-proportional part on relative velocities (``damping.mass = relative``): the
    damping model's dashpots (:attr:`DampingModel.mass_dampers`, in DOF order: per deck
    segment its x, y, θ once per table of its bents, then seat x, θ per seat) as zeroLength
    elements with Viscous(c, α = 1) materials — one per segment and table in x, y, θ from a
    reference node at the segment's centre (imposed x and y motion of that table, θ fixed; a
    fixed node without bents) to the segment's centre node (``bodies``; ``origins`` their
    positions, :func:`.geometry.segment_origins`), and one from each seat's actuator to the
    seat (x, θ). No Rayleigh on them. Returns the reference nodes that follow a table (their
    motion is imposed with the tables') and the elements, in this order. A one-segment deck
    keeps its names (``deck ref <bent>``, ``deck mass damper <bent>``)."""
    if not damping.mass_dampers:
        return [], []
    T = ops.tag
    ops.comment(
        "mass-proportional damping on relative velocities: Viscous dashpots to the supports"
    )
    refs: list[ReferenceNode] = []
    elements: list[MassDamperElement] = []
    several = len(plan.segments) > 1
    for seg, centre in zip(plan.segments, bodies):
        sx, sy, st = seg.dofs
        by_dof = {dof: [m for m in damping.mass_dampers if m.dof == dof] for dof in (sx, sy, st)}
        for k, m_theta in enumerate(by_dof[st]):
            mx, my = by_dof[sx][k], by_dof[sy][k]
            bent = plan.channels[mx.channel][: -len("_x")] if mx.channel >= 0 else None
            name = bent if bent is not None else "fixed"
            if several:
                name = f"{seg.name} {name}"
            rn = T("node", f"deck ref {name}")
            ox, oy = (0.0, 0.0) if origins is None else origins[seg.index]
            ops.node(rn, ox, oy)
            moving = bent is not None and supports == "motion"
            ops.fix(rn, 0 if moving else 1, 0 if moving else 1, 1)
            if bent is not None:
                refs.append(ReferenceNode(rn, mx.channel, my.channel))
            mats = []
            for dirn, c in (("x", mx.c), ("y", my.c), ("theta", m_theta.c)):
                m = T("material", f"deck mass damper {name} {dirn}")
                ops.uniaxialMaterial("Viscous", m, c, 1.0)
                mats.append(m)
            e = T("element", f"deck mass damper {name}")
            ops.element("zeroLength", e, rn, centre, "-mat", *mats, "-dir", 1, 2, 3)
            elements.append(MassDamperElement(e, (0, 1, 2), (mx.c, my.c, m_theta.c)))
    for j in range(2):
        mats = []
        cs = []
        for dirn, dof in (("x", SEAT_X[j]), ("theta", SEAT_THETA[j])):
            (c,) = [m.c for m in damping.mass_dampers if m.dof == dof]
            m = T("material", f"seat{j + 1} mass damper {dirn}")
            ops.uniaxialMaterial("Viscous", m, c, 1.0)
            mats.append(m)
            cs.append(c)
        e = T("element", f"seat{j + 1} mass damper")
        ops.element("zeroLength", e, acts[j], seats[j], "-mat", *mats, "-dir", 1, 3)
        elements.append(MassDamperElement(e, (0, 2), tuple(cs)))
    return refs, elements

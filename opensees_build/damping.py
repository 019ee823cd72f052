"""Damping of the OpenSees model, read from the damping model every engine applies
(:class:`deckpound.models.damping.DampingModel`, the scene's ``[damping]``): the ``rayleigh``
factors, the spring elements that take them, and the mass-proportional dashpots on relative
velocities. Used by :func:`deckpound.opensees_build.model.build_model` and
:class:`deckpound.opensees_build.energy.EnergyBalance`.
"""

from __future__ import annotations

from deckpound.models.damping import DampingModel
from deckpound.models.plan import DECK_THETA, DECK_X, DECK_Y, SEAT_THETA, SEAT_X, Plan

from .ops import OpsSession

__all__ = ["MEMBERS_TEXT", "mass_dampers", "rayleigh_factors", "rayleigh_members"]

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


def mass_dampers(
    ops: OpsSession, plan: Plan, damping: DampingModel, deck: int, seats, acts, supports: str
) -> list[int]:
    """The mass-proportional part on relative velocities (``damping.mass = relative``): the
    damping model's dashpots (:attr:`DampingModel.mass_dampers`, in DOF order: deck x, y, θ
    once per bent table, then seat x, θ per seat) as zeroLength elements with Viscous(c,
    α = 1) materials — one per bent table in x, y, θ from a reference node at the deck centre
    (imposed x and y motion of that table, θ fixed; a fixed node without bents) to the deck
    centre, and one from each seat's actuator to the seat (x, θ). No Rayleigh on them. Returns
    the reference nodes (one per bent, in bent order; their motion is imposed with the
    tables')."""
    if not damping.mass_dampers:
        return []
    T = ops.tag
    deck_c = {
        dof: [m.c for m in damping.mass_dampers if m.dof == dof]
        for dof in (DECK_X, DECK_Y, DECK_THETA)
    }
    ops.comment(
        "mass-proportional damping on relative velocities: Viscous dashpots to the supports"
    )
    refs = []
    for k, c_theta in enumerate(deck_c[DECK_THETA]):
        bent = plan.bent_names[k] if plan.bent_names else None
        name = bent if bent is not None else "fixed"
        rn = T("node", f"deck ref {name}")
        ops.node(rn, 0.0, 0.0)
        moving = bent is not None and supports == "motion"
        ops.fix(rn, 0 if moving else 1, 0 if moving else 1, 1)
        if bent is not None:
            refs.append(rn)
        mats = []
        for dirn, c in (("x", deck_c[DECK_X][k]), ("y", deck_c[DECK_Y][k]), ("theta", c_theta)):
            m = T("material", f"deck mass damper {name} {dirn}")
            ops.uniaxialMaterial("Viscous", m, c, 1.0)
            mats.append(m)
        e = T("element", f"deck mass damper {name}")
        ops.element("zeroLength", e, rn, deck, "-mat", *mats, "-dir", 1, 2, 3)
    for j in range(2):
        mats = []
        for dirn, dof in (("x", SEAT_X[j]), ("theta", SEAT_THETA[j])):
            (c,) = [m.c for m in damping.mass_dampers if m.dof == dof]
            m = T("material", f"seat{j + 1} mass damper {dirn}")
            ops.uniaxialMaterial("Viscous", m, c, 1.0)
            mats.append(m)
        e = T("element", f"seat{j + 1} mass damper")
        ops.element("zeroLength", e, acts[j], seats[j], "-mat", *mats, "-dir", 1, 3)
    return refs

"""Damping of the OpenSees model: the ``rayleigh`` factors and the members that take them, and
the mass-proportional dashpots on relative velocities (the scene's ``[damping]``, as
:mod:`deckpound.models.damping` defines it for every engine). Used by
:func:`deckpound.opensees_build.model.build_model`.
"""

from __future__ import annotations

from deckpound.models.plan import plan_of
from deckpound.models.scene import Scene

from .ops import OpsSession

__all__ = ["mass_dampers", "rayleigh_factors", "rayleigh_members"]


def rayleigh_members(scene: Scene) -> tuple[bool, bool]:
    """(bents, seat springs) take the stiffness-proportional part (``-doRayleigh 1``)."""
    d = scene.damping
    return d.members in ("bents", "bents+seats"), d.members == "bents+seats"


def rayleigh_factors(scene: Scene, damping) -> tuple[float, float, float, float]:
    """``rayleigh αM βK βKinit βKc``: αM = a0 on absolute velocities (0 when the mass part is
    relative: dashpots then carry it, :func:`mass_dampers`), a1 on the tangent the scene names
    (current → βK, initial → βKinit, committed → βKc)."""
    a1 = damping.a1
    st = scene.damping.stiffness
    return (
        damping.a0_absolute,
        a1 if st == "current" else 0.0,
        a1 if st == "initial" else 0.0,
        a1 if st == "committed" else 0.0,
    )


def mass_dampers(
    ops: OpsSession, scene: Scene, damping, deck: int, seats, acts, supports: str
) -> list[int]:
    """The mass-proportional part on relative velocities (``damping.mass = relative``): a
    zeroLength with Viscous(a0 m / n, α = 1) materials in x, y, θ from a reference node per bent
    table — at the deck centre, imposed x and y motion of that table, θ fixed — to the deck
    centre, and one from each seat's actuator to the seat (x, θ); the same dashpots as
    :func:`deckpound.models.damping.relative_mass_dampers`. No Rayleigh on them. Returns the
    reference nodes (one per bent, in bent order; their motion is imposed with the tables')."""
    if not damping.mass_dampers:
        return []
    T = ops.tag
    plan_mass = plan_of(scene).mass
    nb = len(scene.bents)
    a0 = damping.a0
    ops.comment(
        "mass-proportional damping on relative velocities: Viscous dashpots to the supports"
    )
    refs = []
    for _k, b in enumerate(scene.bents or [None]):
        name = b.name if b is not None else "fixed"
        rn = T("node", f"deck ref {name}")
        ops.node(rn, 0.0, 0.0)
        moving = b is not None and supports == "motion"
        ops.fix(rn, 0 if moving else 1, 0 if moving else 1, 1)
        if b is not None:
            refs.append(rn)
        n = max(nb, 1)
        mats = []
        for dirn, dof in (("x", 4), ("y", 5), ("theta", 6)):
            m = T("material", f"deck mass damper {name} {dirn}")
            ops.uniaxialMaterial("Viscous", m, a0 * plan_mass[dof] / n, 1.0)
            mats.append(m)
        e = T("element", f"deck mass damper {name}")
        ops.element("zeroLength", e, rn, deck, "-mat", *mats, "-dir", 1, 2, 3)
    for j in range(2):
        mats = []
        for dirn, dof in (("x", 2 * j), ("theta", 2 * j + 1)):
            m = T("material", f"seat{j + 1} mass damper {dirn}")
            ops.uniaxialMaterial("Viscous", m, a0 * plan_mass[dof], 1.0)
            mats.append(m)
        e = T("element", f"seat{j + 1} mass damper")
        ops.element("zeroLength", e, acts[j], seats[j], "-mat", *mats, "-dir", 1, 3)
    return refs

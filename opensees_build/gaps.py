"""The gap elements of the OpenSees model: the ONE place where deckpound's positive physical
gap g₀ and closing direction are mapped to OpenSees' node order, element orientation and
negative (compression) material parameters (:func:`gap_mapping`), for the zeroLength gap
materials and zeroLengthContact2D (:func:`contact_normal`). Used by
:func:`deckpound.opensees_build.model.build_model`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from deckpound.models.contact_laws_table import contact_law
from deckpound.models.contact_params import corner_contact, kelvin_voigt_damping
from deckpound.models.errors import SceneError
from deckpound.models.plan import Corner
from deckpound.models.scene import Scene

__all__ = [
    "HUGE_FORCE",
    "GapSpec",
    "contact_normal",
    "corner_orientation",
    "gap_mapping",
    "gap_orientation",
]

#: "infinite" yield force of the linear gap (ElasticPPGap) [kN]
HUGE_FORCE = 1.0e20


@dataclass(frozen=True)
class GapSpec:
    """One corner's gap element: node order, orientation and material (OpenSees signs).

    ``orient``: the six numbers of zeroLength ``-orient x1 x2 x3 yp1 yp2 yp3``, or None for
    OpenSees' default (local x = global X), which is what a straight deck uses.
    """

    i_node: int
    j_node: int
    material: str
    args: tuple[float, ...]
    orient: tuple[float, ...] | None = None


def gap_orientation(scene: Scene) -> tuple[float, ...] | None:
    """zeroLength ``-orient`` of the abutment corners' gap elements: local x = a = (cos φ,
    −sin φ), the right end face's outward normal (= side·n for every corner, n the
    gap-opening normal), local y' = t = (sin φ, cos φ) (so local z = a × t = +Z and direction
    3 stays the plan rotation). None for a straight deck: OpenSees' default orientation is
    then the same a = X. A joint with a skew of its own: :func:`corner_orientation`."""
    if scene.deck.skew == 0.0:
        return None
    phi = math.radians(scene.deck.skew)
    cs, sn = math.cos(phi), math.sin(phi)
    return (cs, -sn, 0.0, sn, cs, 0.0)


def corner_orientation(corner: Corner) -> tuple[float, ...] | None:
    """zeroLength ``-orient`` of one corner's gap element, from the plan's corner table:
    local x = a = side·n = (cos φ, −sin φ) with φ the skew of the corner's face (the
    abutments' or the joint's), local y' = the face tangent t; None for a straight face
    (a = X, OpenSees' default).
    For an abutment corner these are :func:`gap_orientation`'s numbers exactly (side·n and
    t are the same products of cos φ and sin φ)."""
    nx, ny = corner.normal
    if ny == 0.0:
        return None
    side = corner.side
    tx, ty = corner.tangent
    return (side * nx, side * ny, 0.0, tx, ty, 0.0)


def gap_mapping(
    scene: Scene, corner: Corner, deck_node: int, seat_node: int, mat_tag: int
) -> GapSpec:
    """Node order, orientation and OpenSees material of the plan's corner ``corner``.

    Physical gap (positive when open), measured along the corner's gap-opening normal n of the
    plan's corner table: g = g₀ + n·(u_deck − u_seat); n = side·a with a = (cos φ, −sin φ),
    side = +1 for c1, c2 (seat 1, left) and the joint corners, −1 for c3, c4 (``Corner.side``;
    a = X for a straight face, :func:`corner_orientation`), g₀ = ``Corner.gap``. At a joint
    the "deck" node is the striking segment's corner and the "seat" node the facing point on
    the other segment's end face. The
    zeroLength element's direction-1 strain is a·(u_j − u_i) with a its local x axis
    (:func:`gap_orientation`; checked against openseespy in ``tests/test_skew_opensees.py``),
    so the nodes are ordered (seat, deck) for side +1 and (deck, seat) for side −1:
    strain = side·a·(u_deck − u_seat) = g − g₀, and closing is negative (compression). The
    materials take a negative gap −g₀ (and negative yield values), so their stress is ≤ 0 and
    the contact force fn = −stress ≥ 0 acts on the deck along n. The material is the law's
    OpenSees counterpart in the contact-law table (:mod:`deckpound.models.contact_laws_table`),
    with the corner's contact table (a joint's own, else the scene's).
    """
    g0 = corner.gap
    i, j = (seat_node, deck_node) if corner.side > 0 else (deck_node, seat_node)
    orient = corner_orientation(corner)
    c = corner_contact(scene, corner)
    law = contact_law(c.law)
    material = law.opensees
    if material == "ElasticPPGap":
        return GapSpec(i, j, material, (mat_tag, c.stiffness, -HUGE_FORCE, -g0), orient)
    if material == "ImpactMaterial":
        k2 = c.bilinear_ratio * c.stiffness
        return GapSpec(i, j, material, (mat_tag, c.stiffness, k2, -c.bilinear_yield, -g0), orient)
    if material == "ViscoelasticGap":
        damp = float(kelvin_voigt_damping(scene)[corner.index])
        return GapSpec(i, j, material, (mat_tag, c.stiffness, damp, -g0), orient)
    if material == "Hertzdamp":
        # Hertzdamp(Kh, ξ_n, gap, n): ξ_n = 0 is the undamped Hertz law k δ^n exactly; the
        # clone's 'hertzdamp' law is this material's arithmetic (contact_laws.py)
        xi_n = law.hysteresis(c.restitution) if law.hysteresis is not None else 0.0
        return GapSpec(i, j, material, (mat_tag, c.stiffness, xi_n, -g0, c.exponent), orient)
    raise SceneError("contact.law", f"OpenSees cannot express the {c.law!r} law")


def contact_normal(corner) -> tuple[float, float]:
    """zeroLengthContact2D ``-normal`` of a corner: −n, from the deck corner towards the seat
    (the element's gap is −(−n)·(X_j + u_j − X_i − u_i) with i = seat point, j = deck corner,
    so it is g₀ + n·(u_deck − u_seat) when the nodes sit g₀ apart along n). ``+ 0.0`` keeps a
    straight deck's (±1, 0) free of a −0.0 in the command log."""
    nx, ny = corner.normal
    return (-nx + 0.0, -ny + 0.0)

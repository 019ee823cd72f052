"""Node positions and sections of the OpenSees model (:func:`.model.build_model`).

The deck sticks' section (stick mode), the stations of their nodes, and where each seat's node
(its pivot) sits for the zeroLength and the zeroLengthContact2D gap elements [m, m², m⁴].
"""

from __future__ import annotations

from deckpound.models.plan import Plan
from deckpound.models.scene import Scene


def stick_section(scene: Scene) -> tuple[float, float]:
    """(A [m²], I [m⁴]) of the deck sticks: a section W wide and W/8 deep, bending in plan."""
    w = scene.deck.width
    return w * w / 8.0, w**4 / 96.0


def stick_stations(scene: Scene, plan: Plan) -> list[float]:
    """x of the stick nodes: ``stick_elements`` equal elements per half plus the bent stations
    of the plan model."""
    hl = 0.5 * scene.deck.length
    n = scene.opensees.stick_elements
    xs = [-hl + k * hl / n for k in range(n + 1)] + [k * hl / n for k in range(1, n + 1)]
    tol = 1e-9 * scene.deck.length
    for xb in plan.bent_x:
        if all(abs(xb - x) > tol for x in xs):
            xs.append(xb)
    xs = sorted(xs)
    xs[min(range(len(xs)), key=lambda k: abs(xs[k]))] = 0.0
    return xs


def seat_pivot(plan, seat: int, friction: bool) -> tuple[float, float]:
    """Coordinates of seat ``seat``'s node (its pivot) [m].

    Without friction the gap elements are zeroLength (node coordinates do not enter them), so
    the node sits at the deck face's mid-point (∓L/2, 0); only the lever to the seat points
    (the plan's ``Corner.lever``) matters. With friction (zeroLengthContact2D, whose gap
    includes the coordinates) it sits at the physical pivot F₀ = (∓L/2, 0) − g₀ n, n the face's
    gap-opening normal — ∓(L/2 + g₀) for a straight deck, written so that the arithmetic (and
    the command log) of a straight deck is unchanged.
    """
    corner = plan.corners[0 if seat == 0 else 2]
    mid = -plan.half_length if seat == 0 else plan.half_length
    if not friction:
        return mid, 0.0
    nx, ny = corner.normal
    if ny == 0.0:
        return -(plan.half_length + corner.gap) if seat == 0 else plan.half_length + corner.gap, 0.0
    return mid - corner.gap * nx, 0.0 - corner.gap * ny

"""Node positions and sections of the OpenSees model (:func:`.model.build_model`).

The deck sticks' section (stick mode), the stations of their nodes, where each deck segment's
centre sits (:func:`segment_origins`) and where each seat's node (its pivot) sits for the
zeroLength and the zeroLengthContact2D gap elements [m, m², m⁴].
"""

from __future__ import annotations

from deckpound.models.plan import Plan
from deckpound.models.scene import Scene


def stick_section(width: float) -> tuple[float, float]:
    """(A [m²], I [m⁴]) of a deck segment's sticks: a section W = ``width`` [m] wide and W/8
    deep, bending in plan."""
    w = width
    return w * w / 8.0, w**4 / 96.0


def stick_stations(scene: Scene, plan: Plan, segment: int = 0) -> list[float]:
    """x of the stick nodes of deck segment ``segment`` in its own frame [m]:
    ``stick_elements`` equal elements per half plus the stations of the bents it carries (the
    plan model's ``bent_x``); the station nearest the centre is the centre, x = 0."""
    seg = plan.segments[segment]
    # a one-segment deck: L/2 of the scene (the very number the plan's half length holds)
    hl = 0.5 * scene.deck.length if len(plan.segments) == 1 else seg.half_length
    n = scene.opensees.stick_elements
    xs = [-hl + k * hl / n for k in range(n + 1)] + [k * hl / n for k in range(1, n + 1)]
    tol = 1e-9 * scene.deck.length
    for k in seg.bents:
        xb = plan.bent_x[k]
        if all(abs(xb - x) > tol for x in xs):
            xs.append(xb)
    xs = sorted(xs)
    xs[min(range(len(xs)), key=lambda k: abs(xs[k]))] = 0.0
    return xs


def segment_origins(plan: Plan) -> list[tuple[float, float]] | None:
    """Global position at rest of each deck segment's centre node [m]; None for a one-segment
    deck (its centre is the origin and every position is its own frame's).

    The first segment sits at its plan centre (``SegmentPlan.centre``, y = 0); each next one is
    placed where the plan model puts it: the joint's facing segment's centre is the corner's
    ``pivot`` in the striking segment's frame, so the striking segment's centre is the facing
    one's minus that pivot. The segments are then g₀ apart along each joint's normal n: a
    joint corner P₀ and its facing point P₀ − g₀ n (on the facing segment's end face) are g₀
    apart, which zeroLengthContact2D reads from the coordinates, and the facing point's lever
    about its segment's centre is the plan's ``Corner.lever`` r, so the rigidLink moves it as
    the plan's kinematics do (u_Q = (x_o − r_y θ_o, y_o + r_x θ_o)), tangential slip included.
    """
    if len(plan.segments) <= 1:
        return None
    return plan.segment_positions()


def placed(origin: tuple[float, float] | None, x: float, y: float) -> tuple[float, float]:
    """Global coordinates of the point (x, y) of a segment's frame whose centre is at
    ``origin`` (None: a one-segment deck, whose frame is the global one: (x, y) unchanged)."""
    if origin is None:
        return x, y
    return origin[0] + x, origin[1] + y


def seat_pivot(plan, seat: int, friction: bool) -> tuple[float, float]:
    """Coordinates of seat ``seat``'s node (its pivot) in the frame of the deck segment it
    faces [m] (the deck's own frame for a one-segment deck).

    Without friction the gap elements are zeroLength (node coordinates do not enter them), so
    the node sits at the deck face's mid-point (∓L/2, 0); only the lever to the seat points
    (the plan's ``Corner.lever``) matters. With friction (zeroLengthContact2D, whose gap
    includes the coordinates) it sits at the physical pivot F₀ = (∓L/2, 0) − g₀ n, n the face's
    gap-opening normal — ∓(L/2 + g₀) for a straight deck, written so that the arithmetic (and
    the command log) of a straight deck is unchanged. L is the length of the end segment.
    """
    corner = next(c for c in plan.corners if c.seat == seat)
    hl = plan.half_length if len(plan.segments) <= 1 else plan.segments[corner.body].half_length
    mid = -hl if seat == 0 else hl
    if not friction:
        return mid, 0.0
    nx, ny = corner.normal
    if ny == 0.0:
        return -(hl + corner.gap) if seat == 0 else hl + corner.gap, 0.0
    return mid - corner.gap * nx, 0.0 - corner.gap * ny

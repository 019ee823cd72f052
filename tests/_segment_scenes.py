r"""Free chains of deck segments for the oracle tests of ``tests/test_segment_oracles.py``.

A chain is the built-in ``two-frame`` scene with its bents removed (``bents = ()``), no
damping (``damping.ratio = 0``; the seats' dashpots act on the seats only), no support motion
(``excitation.kind = "none"``) and both abutment seats 1 m away with no seat-length check, so
between its joints the segments fly freely and only the joint contacts act. Each segment is a
uniform plate of the deck's width W: inertia m (L² + W²) / 12 about its centre. The deck table
takes the sums the scene requires (length, mass, Σ I_i + m_i x_i²).

Geometry of the contact model (``models/plan.py``, ``_joint_corners``): at joint k the facing
segment k's centre lies, at rest, at O₀ = B₀ − ((L_k + L_{k+1})/2 + g₀ n_x, g₀ n_y) from the
striking segment k + 1's centre B₀ (the faces are g₀ apart along n = (cos φ, −sin φ)), while
``Scene.segment_centres`` lays the segments end to end without the gaps. The momenta about a
fixed point are taken in the contact model's geometry (:func:`rest_centres`), in which the
contact forces of a joint act at one point of both bodies.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from deckpound.models.scene import Joint, Scene, Segment
from deckpound.models.scene_io import load_scene

#: the abutment seats' gap [m]: far beyond any segment's travel in these runs
SEAT_GAP = 1.0
#: the deck width of the two-frame scene, every segment's width [m]
WIDTH = load_scene("two-frame").deck.width


def plate_inertia(mass: float, length: float) -> float:
    """Polar inertia of a uniform plate segment (width :data:`WIDTH`) about its centre [t·m²]."""
    return mass * (length**2 + WIDTH**2) / 12.0


def free_chain(
    masses: Sequence[float],
    velocities: Sequence[Sequence[float]],
    gaps: Sequence[float],
    *,
    lengths: Sequence[float] | None = None,
    displacements: Sequence[Sequence[float]] | None = None,
    skews: Sequence[float | None] | None = None,
    settings: Mapping[str, Any] | None = None,
) -> Scene:
    """A free chain of segments ``s1``, ``s2`` … left to right.

    masses [t]; velocities [v_x, v_y, ω] per segment [m/s, m/s, rad/s]; gaps: the clear gap
    of each joint [m]; lengths [m] (default 11 m each); displacements [x, y, θ] per segment at
    t = 0 [m, m, rad] (default at rest position); skews: each joint's skew [deg] (default the
    deck's, 0); settings: dotted paths for :meth:`Scene.replace` (contact law, restitution,
    run duration, steps …).
    """
    base = load_scene("two-frame")
    n = len(masses)
    lengths = [11.0] * n if lengths is None else list(lengths)
    displacements = [(0.0, 0.0, 0.0)] * n if displacements is None else displacements
    skews = [None] * (n - 1) if skews is None else skews
    segments = tuple(
        Segment(
            name=f"s{i + 1}",
            length=float(length),
            mass=float(m),
            inertia=plate_inertia(float(m), float(length)),
            displacement=tuple(float(x) for x in u),
            velocity=tuple(float(x) for x in v),
        )
        for i, (m, length, u, v) in enumerate(zip(masses, lengths, displacements, velocities))
    )
    total = sum(lengths)
    centres, left = [], -0.5 * total
    for length in lengths:
        centres.append(left + 0.5 * length)
        left += length
    deck = dataclasses.replace(
        base.deck,
        length=total,
        mass=sum(s.mass for s in segments),
        inertia=sum(s.inertia + s.mass * c**2 for s, c in zip(segments, centres)),
    )
    seats = tuple(
        dataclasses.replace(seat, gap=SEAT_GAP, support_length=None) for seat in base.seats
    )
    scene = dataclasses.replace(
        base,
        name="free-chain",
        description="free segments meeting at their joints (oracle tests)",
        deck=deck,
        bents=(),
        segments=segments,
        joints=tuple(Joint(gap=float(g), skew=s) for g, s in zip(gaps, skews)),
        seats=seats,
        damping=dataclasses.replace(base.damping, ratio=0.0),
        notes={},
    )
    return scene.replace({"excitation.kind": "none", **(settings or {})})


def velocities(result, scene: Scene, row: int = -1) -> np.ndarray:
    """(n_segments, 3) velocities [v_x, v_y, ω] of the segments at output ``row``."""
    return np.array(
        [
            [result[f"{s.name}_{c}"][row] for c in ("vx_abs", "vy_abs", "omega")]
            for s in scene.segments
        ]
    )


def kinetic_energy(result, scene: Scene) -> np.ndarray:
    """Kinetic energy of the segments at every output row [kJ]: Σ ½ m (v_x² + v_y²) + ½ I ω²."""
    out = np.zeros(len(result.t))
    for s in scene.segments:
        vx, vy, om = (result[f"{s.name}_{c}"] for c in ("vx_abs", "vy_abs", "omega"))
        out += 0.5 * s.mass * (vx**2 + vy**2) + 0.5 * s.inertia * om**2
    return out


def rest_centres(scene: Scene) -> np.ndarray:
    """(n_segments, 2) centres at rest in the contact model's geometry [m], the first at the
    origin: each striking segment's centre ((L_k + L_{k+1})/2 + g₀ n_x, g₀ n_y) from the facing
    one's (module docstring)."""
    out = [np.zeros(2)]
    for k, joint in enumerate(scene.joints):
        phi = math.radians(scene.deck.skew if joint.skew is None else joint.skew)
        half = 0.5 * (scene.segments[k].length + scene.segments[k + 1].length)
        out.append(out[-1] + [half + joint.gap * math.cos(phi), -joint.gap * math.sin(phi)])
    return np.array(out)


def momenta(result, scene: Scene, point: Sequence[float], moving: bool) -> np.ndarray:
    """(n_rows, 3) linear momentum [P_x, P_y] [t·m/s] and angular momentum about the fixed
    ``point`` [t·m²/s] of the segments at every output row.

    H = Σ I_i ω_i + m_i (X_i v_y,i − Y_i v_x,i) with (X_i, Y_i) the centre relative to the
    point: at its rest position (``moving`` False: the invariant of the small-rotation model,
    whose contact forces act at the rest positions of the corners) or at its current one
    (``moving`` True: the angular momentum of the exact kinematics).
    """
    out = np.zeros((len(result.t), 3))
    for s, centre in zip(scene.segments, rest_centres(scene)):
        vx, vy, om = (result[f"{s.name}_{c}"] for c in ("vx_abs", "vy_abs", "omega"))
        x = centre[0] - point[0] + (result[f"{s.name}_x_abs"] if moving else 0.0)
        y = centre[1] - point[1] + (result[f"{s.name}_y_abs"] if moving else 0.0)
        out[:, 0] += s.mass * vx
        out[:, 1] += s.mass * vy
        out[:, 2] += s.inertia * om + s.mass * (x * vy - y * vx)
    return out

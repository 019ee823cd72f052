"""The plan model: the one description of the 7-DOF planar bridge model that every engine builds.

A :class:`Plan` is derived from a scene (:func:`plan_of`) and holds, written once:

* the degrees of freedom (paper Fig. 1b,c): u = [x₁, θ₁, x₂, θ₂, x_d, y_d, θ_d] — seat 1 (left),
  seat 2 (right), deck; masses at the seats' pivots (the mid-points of their contact faces) and
  at the deck centre;
* the **corner table** (:class:`Corner`): position of each deck corner, the seat it faces, the
  unit normal n along which its gap opens, the tangent t, the lever arm r of the facing seat
  point about the seat's pivot and the initial clear gap g₀ measured along n;
* the **springs** (:class:`Spring`): bent springs (Takeda, OpenSees ``Hysteretic`` stand-in) in x
  and y and seat springs in x and θ, each with its connectivity (deformation
  d = Σ b_j u_j − s·u_g[channel]), initial stiffness, dashpot and — for bents — the 13 numbers of
  the OpenSees ``Hysteretic`` material;
* the support channels (``<bent>_x``, ``<bent>_y`` per shake table, ``seat1_x``, ``seat2_x``);
* the result **columns** (:class:`deckpound.models.columns.Column`) with units and labels.

Geometry (DESIGN, skewed decks): with skew angle φ the deck is a parallelogram whose end faces
are the lines x = ±L/2 + y·tan φ; the corners sit at (±L/2 + y_c tan φ, y_c), y_c = ∓W/2.
The right face's outward normal is (cos φ, −sin φ) and the left face's is its opposite; a gap
opens when the deck corner moves *into* the deck, so the gap-opening normals are
n = (cos φ, −sin φ) for the left corners and n = (−cos φ, sin φ) for the right ones, and the
tangent is t = (sin φ, cos φ) for both faces (t = +y for a straight deck). The seats slide along
the bridge axis (x) and rotate about the mid-point of their contact face.

Geometrically linear contact kinematics (small rotations), for corner c facing seat s::

    g_N = g₀ + n · (u_P − u_S),     u_P = (x_d − y_c θ_d, y_d + x_c θ_d),
                                    u_S = (x_s − r_y θ_s, r_x θ_s)
    U_T = t · (u̇_P − u̇_S) = t · u̇_P − t_x ẋ_s     (t · (−r_y, r_x) = 0: r lies along the face)

with r = (y_c tan φ, y_c) the facing seat point relative to the seat pivot. For φ = 0 these are
the paper's g_N = g₀ ± [(x_d − y_c θ_d) − (x_s − y_c θ_s)] and U_T = ẏ_d + x_c θ̇_d.

Units: m, rad, t, t·m², kN, s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache, cached_property

import numpy as np

from .scene import Scene, TakedaSpring

__all__ = [
    "BODY_QUANTITIES",
    "CORNER_NAMES",
    "DECK_THETA",
    "DECK_X",
    "DECK_Y",
    "DOF_NAMES",
    "N_CORNERS",
    "N_DOF",
    "SEAT_THETA",
    "SEAT_X",
    "Corner",
    "Plan",
    "SegmentPlan",
    "Spring",
    "deck_column_names",
    "plan_of",
    "support_channels",
    "takeda_hysteretic_args",
]

DOF_NAMES = ("seat1_x", "seat1_theta", "seat2_x", "seat2_theta", "deck_x", "deck_y", "deck_theta")
N_DOF = 7
SEAT_X = (0, 2)
SEAT_THETA = (1, 3)
DECK_X, DECK_Y, DECK_THETA = 4, 5, 6
N_CORNERS = 4
CORNER_NAMES = ("c1", "c2", "c3", "c4")

#: Absolute displacement / rotation columns in output order, with the DOF each one reads.
#: θ has no ``_abs`` suffix: the supports do not rotate, so absolute and relative rotation agree.
DOF_COLUMNS = (
    ("deck_x_abs", DECK_X),
    ("deck_y_abs", DECK_Y),
    ("deck_theta", DECK_THETA),
    ("seat1_x_abs", 0),
    ("seat1_theta", 1),
    ("seat2_x_abs", 2),
    ("seat2_theta", 3),
)
#: Absolute velocity columns, in the same order as :data:`DOF_COLUMNS`.
VELOCITY_COLUMNS = (
    ("deck_vx_abs", DECK_X),
    ("deck_vy_abs", DECK_Y),
    ("deck_omega", DECK_THETA),
    ("seat1_vx_abs", 0),
    ("seat1_omega", 1),
    ("seat2_vx_abs", 2),
    ("seat2_omega", 3),
)
#: Displacements relative to the supports: the deck centre relative to the mean motion of the
#: shake tables (the table motion itself for coherent input), each seat relative to its actuator.
RELATIVE_COLUMNS = ("deck_x_rel", "deck_y_rel", "seat1_x_rel", "seat2_x_rel")


#: the quantities of each deck body's own columns ``<body>_<quantity>``: displacements,
#: velocities, displacements relative to its tables (:func:`deck_column_names`)
BODY_QUANTITIES = (("x_abs", "y_abs", "theta"), ("vx_abs", "vy_abs", "omega"), ("x_rel", "y_rel"))


@cache  # read for every column list of every run: a sweep would build them anew
def deck_column_names(bodies: tuple[str, ...]) -> tuple[tuple[str, ...], ...]:
    """(displacement, velocity, relative) column names of a deck of these bodies (``("deck",)``
    or the segments' names): ``<body>_x_abs``, ``_y_abs``, ``_theta``; ``<body>_vx_abs``,
    ``_vy_abs``, ``_omega``; ``<body>_x_rel``, ``_y_rel``; each followed by the seats' (the
    one-body deck's: :data:`DOF_COLUMNS`, :data:`VELOCITY_COLUMNS`, :data:`RELATIVE_COLUMNS`)."""
    own = [tuple(f"{b}_{q}" for b in bodies for q in suffixes) for suffixes in BODY_QUANTITIES]
    return (
        own[0] + tuple(n for n, _ in DOF_COLUMNS[3:]),
        own[1] + tuple(n for n, _ in VELOCITY_COLUMNS[3:]),
        own[2] + RELATIVE_COLUMNS[2:],
    )


@dataclass(frozen=True)
class Corner:
    """One deck corner and the face it meets (see the module docstring for the equations).

    Attributes
    ----------
    name : ``c1`` … ``c4`` at the abutments; c1 (−L/2, −W/2) and c2 (−L/2, W/2) face seat 1,
        c3 and c4 seat 2 (for a skewed deck the x coordinates shift by y_c tan φ); ``j<k>_c1``,
        ``j<k>_c2`` (y = −W/2, +W/2) at joint k of a deck of segments: the left-end corners of
        segment k + 1 (1-based k) striking the right end face of segment k.
    index : position in the plan's corner table.
    seat : 0 (left seat), 1 (right seat) or −1 (a joint corner: the facing body is a segment).
    x, y : corner position at rest in its segment's frame (origin at the segment centre) [m].
    normal : unit vector along which the gap opens (the corner moving along it opens the gap).
    tangent : unit tangent of the facing face; the tangential force is reported along it.
    lever : facing point relative to the facing body's reference point [m]: the seat's pivot
        (its contact-face mid-point), or the facing segment's centre.
    gap : initial clear gap g₀ measured along the normal [m].
    seat_fixed : the facing seat is a rigid abutment (``seats[i].fixed``): the contact force
        does not act on it, so the seat columns of W_N and W_T are zero (the seat, whose
        actuator is then at rest, stays at rest exactly).
    body : index of the segment the corner belongs to (0 for a one-segment deck).
    body_dofs : its DOF indices (x, y, θ).
    joint : index of the joint (0-based), −1 at an abutment.
    facing_dofs : DOF indices (x, y, θ) of the facing body; y is −1 for a seat (it is guided
        in y).
    pivot : the facing body's reference point at rest in the corner's segment frame [m]: the
        seat pivot, or the facing segment's centre.
    support_length : seat (support) length under the corner [m], None: not checked.
    """

    name: str
    index: int
    seat: int
    x: float
    y: float
    normal: tuple[float, float]
    tangent: tuple[float, float]
    lever: tuple[float, float]
    gap: float
    seat_fixed: bool = False
    body: int = 0
    body_dofs: tuple[int, int, int] = (DECK_X, DECK_Y, DECK_THETA)
    joint: int = -1
    facing_dofs: tuple[int, int, int] = (0, -1, 1)
    pivot: tuple[float, float] = (0.0, 0.0)
    support_length: float | None = None

    @property
    def side(self) -> float:
        """−1 for a corner facing seat 2 (right), +1 otherwise (the sign of n_x)."""
        return -1.0 if self.seat == 1 else 1.0

    def normal_row(self, n_dof: int = N_DOF) -> np.ndarray:
        """∂g_N/∂u at rest (linear kinematics), shape (n_dof,)."""
        nx, ny = self.normal
        rx, ry = self.lever
        sx, sy, st = self.facing_dofs
        bx, by, bt = self.body_dofs
        w = np.zeros(n_dof)
        w[bx], w[by] = nx, ny
        w[bt] = -nx * self.y + ny * self.x
        if not self.seat_fixed:
            w[sx] = -nx
            w[st] = nx * ry - ny * rx
            if sy >= 0:
                w[sy] = -ny
        return w

    def tangent_row(self, n_dof: int = N_DOF) -> np.ndarray:
        """∂U_T/∂u̇ (linear kinematics), shape (n_dof,)."""
        tx, ty = self.tangent
        rx, ry = self.lever
        sx, sy, st = self.facing_dofs
        bx, by, bt = self.body_dofs
        w = np.zeros(n_dof)
        w[bx], w[by] = tx, ty
        w[bt] = -tx * self.y + ty * self.x
        if not self.seat_fixed:
            w[sx] = -tx
            if sy >= 0:  # a facing segment: its point moves along t too (r is not along t)
                w[sy] = -ty
                w[st] = tx * ry - ty * rx
        return w


@dataclass(frozen=True)
class Spring:
    """A spring between the bridge and a support (a bent direction or a seat direction).

    Deformation d = Σ_k coefs[k]·u[dofs[k]] − channel_coef·u_g[channel] (channel −1: none).

    Attributes
    ----------
    name : ``<bent>_x``, ``<bent>_y``, ``seat1_x``, ``seat1_theta``, …
    member : ``"bent"`` or ``"seat"``.
    owner : bent or seat name.
    direction : ``"x"``, ``"y"`` or ``"theta"``.
    kind : ``"takeda"`` (OpenSees Hysteretic) or ``"linear"``.
    k0 : initial stiffness [kN/m or kN·m/rad]; dashpot : explicit dashpot [kN·s/m or kN·m·s/rad].
    takeda : the 13 numbers after the tag of ``uniaxialMaterial Hysteretic`` (None if linear).
    """

    name: str
    member: str
    owner: str
    direction: str
    kind: str
    dofs: tuple[int, ...]
    coefs: tuple[float, ...]
    channel: int
    channel_coef: float
    k0: float
    dashpot: float
    takeda: tuple[float, ...] | None = None


def takeda_hysteretic_args(spring: TakedaSpring) -> tuple[float, ...]:
    """The 13 numbers after the tag of OpenSees ``uniaxialMaterial Hysteretic`` for a bent spring.

    2-point symmetric backbone (F_y, F_y/k0), (F_y + r k0 (d_u − d_y), d_u); pinchX = pinchY = 1,
    damage1 = damage2 = 0, beta (Takeda unloading exponent). Every engine builds this material.
    """
    k0, fy, r, du = (
        spring.stiffness,
        spring.yield_force,
        spring.post_yield_ratio,
        spring.ultimate_displacement,
    )
    dy = fy / k0
    fu = fy + r * k0 * (du - dy)
    return (fy, dy, fu, du, -fy, -dy, -fu, -du, 1.0, 1.0, 0.0, 0.0, spring.beta)


def support_channels(scene: Scene) -> tuple[str, ...]:
    """Names of the support motion channels, in engine order: bents (x, y), then seats (x)."""
    names: list[str] = []
    for b in scene.bents:
        names += [f"{b.name}_x", f"{b.name}_y"]
    return tuple(names) + ("seat1_x", "seat2_x")


@dataclass(frozen=True)
class SegmentPlan:
    """One rigid body of the deck in the plan model.

    Attributes
    ----------
    name : ``deck`` for a one-segment deck, else the segment's name (the prefix of its result
        columns).
    index : 0-based position, left to right.
    dofs : its DOF indices (x, y, θ).
    centre : x of its centre from the deck centre at rest [m].
    half_length : half its length [m].
    half_width : half its width [m] (``segments[i].width``, else ``deck.width``).
    displacement, velocity : its initial state [m, m, rad; m/s, m/s, rad/s] (zeros for a
        one-segment deck, whose state is the scene's ``initial`` table).
    bents : indices of the bents it carries (scene order).
    """

    name: str
    index: int
    dofs: tuple[int, int, int]
    centre: float
    half_length: float
    half_width: float
    displacement: tuple[float, ...] = (0.0, 0.0, 0.0)
    velocity: tuple[float, ...] = (0.0, 0.0, 0.0)
    bents: tuple[int, ...] = ()


@dataclass(frozen=True, eq=False)
class Plan:
    """The 7-DOF plan model of a scene (build with :func:`plan_of`; see the module docstring).

    Attributes
    ----------
    mass : (7,) diagonal of the mass matrix [t, t·m²].
    corners : the four corners, c1 … c4.
    springs : bents (x, y each, in scene order), then seat1 x, θ, seat2 x, θ.
    channels : support channel names (the order of u_g).
    bent_names : bent names in scene order; bent_x : bent positions in their segment's frame
        (x_b = station − L/2 for a one-segment deck) [m].
    half_length : L/2 [m]; skew : φ [rad] (the abutment faces').
    segments : the deck's rigid bodies (:class:`SegmentPlan`; one for a one-segment deck).
    """

    mass: np.ndarray
    corners: tuple[Corner, ...]
    springs: tuple[Spring, ...]
    channels: tuple[str, ...]
    bent_names: tuple[str, ...]
    bent_x: tuple[float, ...]
    half_length: float
    skew: float
    segments: tuple[SegmentPlan, ...] = ()

    @property
    def n_dof(self) -> int:
        """Number of DOF: 4 (the seats) + 3 per segment."""
        return int(self.mass.shape[0])

    @property
    def dof_names(self) -> tuple[str, ...]:
        """Name of each DOF (:data:`DOF_NAMES` for a one-segment deck)."""
        return DOF_NAMES[:4] + tuple(
            f"{s.name}_{d}" for s in self.segments for d in ("x", "y", "theta")
        )

    @property
    def dof_columns(self) -> tuple[tuple[str, int], ...]:
        """Absolute displacement columns and the DOF each reads (:data:`DOF_COLUMNS` for a
        one-segment deck): each segment's x, y, θ, then the seats."""
        return tuple(zip(deck_column_names(self._bodies)[0], self._column_dofs))

    @property
    def velocity_columns(self) -> tuple[tuple[str, int], ...]:
        """Absolute velocity columns, in the order of :attr:`dof_columns`."""
        return tuple(zip(deck_column_names(self._bodies)[1], self._column_dofs))

    @property
    def relative_columns(self) -> tuple[str, ...]:
        """Displacements relative to the supports (:data:`RELATIVE_COLUMNS` for a one-segment
        deck): each segment's x, y relative to the mean motion of its bents' tables, then each
        seat relative to its actuator."""
        return deck_column_names(self._bodies)[2]

    @property
    def _bodies(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.segments)

    @property
    def _column_dofs(self) -> tuple[int, ...]:
        """The DOF of each displacement column: the segments' x, y, θ, then the seats'."""
        return tuple(d for s in self.segments for d in s.dofs) + tuple(
            dof for _, dof in DOF_COLUMNS[3:]
        )

    # -- springs -----------------------------------------------------------------------------
    @property
    def n_springs(self) -> int:
        return len(self.springs)

    @property
    def n_bent_springs(self) -> int:
        return 2 * len(self.bent_names)

    @cached_property
    def spring_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """(B, S): deformations d = B u − S u_g, shapes (n_springs, 7), (n_springs, n_channels)."""
        B = np.zeros((self.n_springs, self.n_dof))
        S = np.zeros((self.n_springs, len(self.channels)))
        for i, s in enumerate(self.springs):
            for j, b in zip(s.dofs, s.coefs):
                B[i, j] = b
            if s.channel >= 0:
                S[i, s.channel] = s.channel_coef
        return B, S

    @property
    def k0(self) -> np.ndarray:
        """Initial stiffness of each spring [kN/m, kN·m/rad]."""
        return np.array([s.k0 for s in self.springs], dtype=float)

    @property
    def dashpots(self) -> np.ndarray:
        """Explicit dashpot of each spring [kN·s/m, kN·m·s/rad]."""
        return np.array([s.dashpot for s in self.springs], dtype=float)

    @property
    def mass_matrix(self) -> np.ndarray:
        return np.diag(self.mass)

    @property
    def initial_stiffness(self) -> np.ndarray:
        """K0 = Bᵀ diag(k0) B (contact excluded)."""
        B, _ = self.spring_matrices
        return B.T @ (self.k0[:, None] * B)

    # -- contact -----------------------------------------------------------------------------
    @property
    def gaps(self) -> tuple[float, ...]:
        return tuple(c.gap for c in self.corners)

    def normal_rows(self) -> np.ndarray:
        """W_N at rest (linear kinematics), shape (n_corners, n_dof)."""
        return np.array([c.normal_row(self.n_dof) for c in self.corners])

    def linear_gaps(self, u: np.ndarray) -> np.ndarray:
        """Gaps of the corners for each row of u (n, n_dof), linear kinematics [m]."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        return np.array([c.gap for c in self.corners])[None, :] + u @ self.normal_rows().T

    def effective_masses(self) -> np.ndarray:
        """Mass each corner contact sees at rest [t]: 1 / (w_N M⁻¹ w_Nᵀ)."""
        W = self.normal_rows()
        return 1.0 / np.einsum("ci,ij,cj->c", W, np.diag(1.0 / self.mass), W)

    def deformations(self, U: np.ndarray, UG: np.ndarray) -> np.ndarray:
        """Spring deformations d = B u − S u_g for rows of U (n, n_dof) and UG (n, n_channels)."""
        B, S = self.spring_matrices
        return U @ B.T - UG @ S.T

    def initial_state(self, initial) -> tuple[np.ndarray, np.ndarray] | None:
        """(u0, v0) of the DOFs from a scene's ``initial`` table (one segment) or its segments'
        ``displacement`` and ``velocity``, or None when everything starts at rest."""
        moving = [s for s in self.segments if any(s.displacement) or any(s.velocity)]
        if initial.at_rest and not moving:
            return None
        u0, v0 = np.zeros(self.n_dof), np.zeros(self.n_dof)
        if not initial.at_rest:
            u0[[DECK_X, DECK_Y, DECK_THETA]] = initial.deck
            v0[[DECK_X, DECK_Y, DECK_THETA]] = initial.deck_velocity
        for seg in moving:
            u0[list(seg.dofs)] = seg.displacement
            v0[list(seg.dofs)] = seg.velocity
        return u0, v0

    def table_channels(self, axis: str) -> list[int]:
        """Indices of the shake-table channels along ``axis`` (``x`` or ``y``)."""
        return [self.channels.index(f"{b}_{axis}") for b in self.bent_names]

    def segment_positions(self) -> list[tuple[float, float]]:
        """Each segment's centre at rest [m] as the contact model places it: the first at its
        station's centre, each next one beyond the joint's clear gap, O_{k+1} = O_k − O₀ with
        O₀ the facing centre in the striking segment's frame (``Corner.pivot``), so the joint
        faces stand g₀ apart along their normal (the stations lay the segments end to end)."""
        out = [(self.segments[0].centre, 0.0)]
        for seg in self.segments[1:]:
            corner = next(c for c in self.corners if c.body == seg.index and c.joint >= 0)
            x, y = out[-1]
            out.append((x - corner.pivot[0], y - corner.pivot[1]))
        return out

    def segment_table_channels(self, segment: int, axis: str) -> list[int]:
        """The shake-table channels along ``axis`` that a segment's relative displacement is
        measured from: those of the bents it carries, or every table for a segment that
        carries none (a drop-in span on hinges: it moves with the bridge as a whole)."""
        bents = self.segments[segment].bents
        if not bents:
            return self.table_channels(axis)
        return [self.channels.index(f"{self.bent_names[i]}_{axis}") for i in bents]


def _segment_plans(scene: Scene) -> tuple[SegmentPlan, ...]:
    """The deck's rigid bodies: the deck itself, or the scene's segments (DOF 4 + 3i …)."""
    carried = [scene.segment_of_bent(i) for i in range(len(scene.bents))]
    if scene.segments is None:
        dofs = (DECK_X, DECK_Y, DECK_THETA)
        everything = tuple(range(len(scene.bents)))
        return (
            SegmentPlan(
                "deck",
                0,
                dofs,
                0.0,
                0.5 * scene.deck.length,
                0.5 * scene.deck.width,
                bents=everything,
            ),
        )
    return tuple(
        SegmentPlan(
            s.name,
            i,
            (4 + 3 * i, 5 + 3 * i, 6 + 3 * i),
            centre,
            0.5 * s.length,
            0.5 * (scene.deck.width if s.width is None else s.width),
            s.displacement,
            s.velocity,
            tuple(k for k, seg in enumerate(carried) if seg == i),
        )
        for i, (s, centre) in enumerate(zip(scene.segments, scene.segment_centres))
    )


def _face_frame(phi_deg: float) -> tuple[float, float, float]:
    """(tan φ, cos φ, sin φ) of a face skewed by φ degrees."""
    phi = math.radians(phi_deg)
    return math.tan(phi), math.cos(phi), math.sin(phi)


def _corner_table(
    scene: Scene, gaps: tuple[float, float], segments: tuple[SegmentPlan, ...]
) -> tuple[Corner, ...]:
    """The abutment corners (c1, c2 on the first segment's left end, c3, c4 on the last
    one's right end) and, for a deck of segments, two corners per joint, in order along x."""
    tn, cs, sn = _face_frame(scene.deck.skew)
    first, last = segments[0], segments[-1]
    out: list[Corner] = []
    for k, (xs, ys) in enumerate(((-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0))):
        seat = 0 if xs < 0 else 1
        body = first if seat == 0 else last
        if k == 2:
            out += _joint_corners(scene, segments, len(out))
        yc = ys * body.half_width
        xc = xs * body.half_length + yc * tn
        side = 1.0 if seat == 0 else -1.0
        # φ = 0 gives exactly n = (±1, 0), t = (0, 1), r = (0, y_c): the straight-deck formulae
        normal = (side * cs, -side * sn)
        gap = float(gaps[seat])
        mid = -body.half_length if seat == 0 else body.half_length
        out.append(
            Corner(
                name=CORNER_NAMES[k],
                index=len(out),
                seat=seat,
                x=xc,
                y=yc,
                normal=normal,
                tangent=(sn, cs),
                lever=(yc * tn, yc),
                gap=gap,
                seat_fixed=bool(scene.seats[seat].fixed),
                body=body.index,
                body_dofs=body.dofs,
                facing_dofs=(SEAT_X[seat], -1, SEAT_THETA[seat]),
                # the seat pivot: the deck end face's mid-point moved by the gap against n
                pivot=(mid - gap * normal[0], 0.0 - gap * normal[1]),
                support_length=scene.seats[seat].support_length,
            )
        )
    return tuple(out)


def _joint_corners(scene: Scene, segments: tuple[SegmentPlan, ...], start: int) -> list[Corner]:
    """The corners of every joint: segment k + 1's left-end corners (y = ∓W/2, W the narrower
    of the two segments' widths: where their end faces overlap) striking segment k's right
    end face across the joint's gap, both bodies moving.

    In the striking segment's frame the facing point at rest is Q₀ = P₀ − g₀ n, the lever r
    is Q₀ relative to the facing segment's centre, (L_k/2 + y tan φ, y), and that centre
    is O₀ = Q₀ − r: the segments lie end to end and the gap is a clearance along n."""
    out: list[Corner] = []
    for k, joint in enumerate(scene.joints or ()):
        facing, body = segments[k], segments[k + 1]
        hw = min(facing.half_width, body.half_width)
        tn, cs, sn = _face_frame(scene.deck.skew if joint.skew is None else joint.skew)
        normal = (cs, -sn)
        for m, ys in enumerate((-1.0, 1.0)):
            yc = ys * hw
            xc = -body.half_length + yc * tn
            lever = (facing.half_length + yc * tn, yc)
            qx, qy = xc - joint.gap * normal[0], yc - joint.gap * normal[1]
            out.append(
                Corner(
                    name=f"j{k + 1}_c{m + 1}",
                    index=start + len(out),
                    seat=-1,
                    x=xc,
                    y=yc,
                    normal=normal,
                    tangent=(sn, cs),
                    lever=lever,
                    gap=float(joint.gap),
                    body=body.index,
                    body_dofs=body.dofs,
                    joint=k,
                    facing_dofs=facing.dofs,
                    pivot=(qx - lever[0], qy - lever[1]),
                    support_length=joint.support_length,
                )
            )
    return out


def _bent_x(scene: Scene, segments: tuple[SegmentPlan, ...]) -> tuple[float, ...]:
    """Each bent's x in the frame of the segment it carries [m] (station − L/2 − centre)."""
    hl = 0.5 * scene.deck.length
    out = []
    for i, b in enumerate(scene.bents):
        seg = segments[scene.segment_of_bent(i)]
        out.append(b.station - hl if len(segments) == 1 else b.station - hl - seg.centre)
    return tuple(out)


def _springs(scene: Scene, segments: tuple[SegmentPlan, ...]) -> tuple[Spring, ...]:
    out = []
    nb = len(scene.bents)
    bent_x = _bent_x(scene, segments)
    for i, b in enumerate(scene.bents):
        xb = bent_x[i]
        sx, sy, st = segments[scene.segment_of_bent(i)].dofs
        out.append(
            Spring(
                f"{b.name}_x",
                "bent",
                b.name,
                "x",
                "takeda",
                (sx,),
                (1.0,),
                2 * i,
                1.0,
                b.x.stiffness,
                b.cx,
                takeda_hysteretic_args(b.x),
            )
        )
        out.append(
            Spring(
                f"{b.name}_y",
                "bent",
                b.name,
                "y",
                "takeda",
                (sy, st),
                (1.0, xb),
                2 * i + 1,
                1.0,
                b.y.stiffness,
                b.cy,
                takeda_hysteretic_args(b.y),
            )
        )
    for j, s in enumerate(scene.seats):
        name = f"seat{j + 1}"
        out.append(
            Spring(
                f"{name}_x",
                "seat",
                s.name,
                "x",
                "linear",
                (SEAT_X[j],),
                (1.0,),
                2 * nb + j,
                1.0,
                s.kx,
                s.cx,
            )
        )
        out.append(
            Spring(
                f"{name}_theta",
                "seat",
                s.name,
                "theta",
                "linear",
                (SEAT_THETA[j],),
                (1.0,),
                -1,
                0.0,
                s.ktheta,
                s.ctheta,
            )
        )
    return tuple(out)


def plan_of(scene: Scene, gaps: tuple[float, float] | None = None) -> Plan:
    """The plan model of ``scene``; ``gaps`` overrides the seats' initial gaps [m]."""
    g = gaps if gaps is not None else (scene.seats[0].gap, scene.seats[1].gap)
    s1, s2, d = scene.seats[0], scene.seats[1], scene.deck
    segments = _segment_plans(scene)
    if scene.segments is None:
        bodies = [d.mass, d.mass, d.inertia]
    else:
        bodies = [v for s in scene.segments for v in (s.mass, s.mass, s.inertia)]
    return Plan(
        mass=np.array([s1.mass, s1.inertia, s2.mass, s2.inertia, *bodies], dtype=float),
        corners=_corner_table(scene, (float(g[0]), float(g[1])), segments),
        springs=_springs(scene, segments),
        channels=support_channels(scene),
        bent_names=tuple(b.name for b in scene.bents),
        bent_x=_bent_x(scene, segments),
        half_length=0.5 * d.length,
        skew=math.radians(scene.deck.skew),
        segments=segments,
    )

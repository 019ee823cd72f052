"""Contact kinematics of the plan model: gaps g_N and direction matrices W_N, W_T.

The corner table of :mod:`deckpound.models.plan` is packed once into a
(n_corners, :data:`N_K`) array (:func:`pack_corners`, columns named by the ``K_*`` constants)
that the kernels read; the equations are those of the plan model (DOFs
u = [x₁, θ₁, x₂, θ₂, x_d, y_d, θ_d]):

Geometrically linear (small rotations), corner at (x, y) with gap-opening normal n, tangent t
and facing seat point r (relative to the seat pivot)::

    g_N = g₀ + n_x [(x_d − y θ_d) − (x_s − r_y θ_s)] + n_y [(y_d + x θ_d) − r_x θ_s]
    U_T = t_x (ẋ_d − y θ̇_d) + t_y (ẏ_d + x θ̇_d) − t_x ẋ_s

(written so that a straight deck, n = (±1, 0), t = (0, 1), r = (0, y), performs exactly the
floating-point operations of the paper's g_N = g₀ ± [(x_d − y θ_d) − (x_s − y θ_s)]).

Geometrically nonlinear (paper Fig. 2b): the deck corner at
P = (x_d + x cos θ_d − y sin θ_d, y_d + x sin θ_d + y cos θ_d); the seat face is the line
through the seat pivot F = F₀ + (x_s, 0) (the seats slide along x) with the rest normal n₀ and
tangent t₀ rotated by θ_s: n = R(θ_s) n₀, t = R(θ_s) t₀; g_N = n·(P − F),
U_T = t·Ṗ − t_x ẋ_s (the term θ̇_s g_N of the face's rotation is dropped: it vanishes in
contact).

W_N[c] = ∂g_N/∂u and W_T[c] = ∂U_T/∂u̇ are rows (shape (n_corners, n_dof)); the generalised
contact force is W_Nᵀ λ_N + W_Tᵀ λ_T with λ_N ≥ 0 compression. The functions are numba kernels
on flat arrays, usable inside the engines' step loops and from Python alike. Each corner names
the DOF of its seat (columns ``K_SX``, ``K_ST``); the deck DOF are the plan's. The corner and
DOF counts are the lengths of the size tags the kernels take (``corner_slots``, ``dof_slots``:
any tuples of n_corners and n_dof entries, e.g. ``ContactWork.corners`` and
``SystemArrays.dofs``, or :func:`deckpound.analytic.nonsmooth.impulses.size_tag`), compile-time
constants of the compiled loops, so a model with more corners or DOF (several deck segments)
runs through the same kernels.
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic._jit import kernel
from deckpound.models.plan import Plan

__all__ = [
    "K_G0",
    "K_ST",
    "K_SX",
    "N_K",
    "contact_kinematics",
    "gap_hessian",
    "linear_gap",
    "linear_gap_and_rate",
    "linear_gap_rate",
    "pack_corners",
]

#: columns of the packed corner table: position, gap, normal, tangent, lever arm, the facing
#: body's reference point at rest (seat pivot or facing segment centre, in the corner's segment
#: frame), the DOF indices of the facing body (x, θ), K_FREE = 0 for a fixed (rigid) seat, 1
#: otherwise (the contact then puts no force on the seat: its W_N, W_T columns are zero), the
#: DOF indices (x, y, θ) of the corner's own segment and the facing body's y DOF (−1: a seat,
#: guided in y; otherwise a segment at a joint)
(
    K_X,
    K_Y,
    K_G0,
    K_NX,
    K_NY,
    K_TX,
    K_TY,
    K_RX,
    K_RY,
    K_PX,
    K_PY,
    K_SX,
    K_ST,
    K_FREE,
    K_BX,
    K_BY,
    K_BT,
    K_SY,
) = range(18)
N_K = 18


def pack_corners(plan: Plan) -> np.ndarray:
    """The plan's corner table as a (n_corners, N_K) float array (``K_*`` column constants).

    The seat pivot at rest is the mid-point of the seat's contact face: the deck end face's
    mid-point moved by the gap against the normal, F₀ = (∓L/2, 0) − g₀ n (``Corner.pivot``);
    at a joint the facing segment's centre at rest.
    """
    out = np.zeros((len(plan.corners), N_K))
    for c in plan.corners:
        row = out[c.index]
        row[K_X], row[K_Y], row[K_G0] = c.x, c.y, c.gap
        row[K_NX], row[K_NY] = c.normal
        row[K_TX], row[K_TY] = c.tangent
        row[K_RX], row[K_RY] = c.lever
        row[K_PX], row[K_PY] = c.pivot
        row[K_SX], row[K_SY], row[K_ST] = c.facing_dofs
        row[K_FREE] = 0.0 if c.seat_fixed else 1.0
        row[K_BX], row[K_BY], row[K_BT] = c.body_dofs
    return out


@kernel(inline="always")
def _corner_dofs(k):
    """The DOF indices of row k of the corner table: (sx, st, bx, by, bt, sy); sy −1 for a
    seat (guided in y). The others are never negative: unsigned, so that indexing with them
    needs no wrap-around of negative indices (the same elements)."""
    sy = -1 if k[K_SY] < 0.0 else int(k[K_SY])
    sx, st = np.uint64(k[K_SX]), np.uint64(k[K_ST])
    return sx, st, np.uint64(k[K_BX]), np.uint64(k[K_BY]), np.uint64(k[K_BT]), sy


@kernel(inline="always")
def _normal_terms(k, x, sx, st, bx, by, bt, sy):
    """The two terms of W_N x for one corner (row k, DOF indices of :func:`_corner_dofs`):
    n_x (Δ of the x motions at the corner) and n_y (Δ of the y motions), linear kinematics."""
    along_x = k[K_NX] * ((x[bx] - k[K_Y] * x[bt]) - (x[sx] - k[K_RY] * x[st]))
    if sy < 0:  # a seat: guided in y
        return along_x, k[K_NY] * ((x[by] + k[K_X] * x[bt]) - k[K_RX] * x[st])
    return along_x, k[K_NY] * ((x[by] + k[K_X] * x[bt]) - (x[sy] + k[K_RX] * x[st]))


@kernel(inline="always")
def linear_gap(k, u):
    """Gap of one corner (row k of the corner table) for displacement u, linear kinematics:
    g = g₀ + W_N u."""
    sx, st, bx, by, bt, sy = _corner_dofs(k)
    along_x, along_y = _normal_terms(k, u, sx, st, bx, by, bt, sy)
    return k[K_G0] + along_x + along_y


@kernel(inline="always")
def linear_gap_rate(k, v):
    """ġ_N = W_N u̇ of one corner, linear kinematics (the gap formula without g₀)."""
    sx, st, bx, by, bt, sy = _corner_dofs(k)
    along_x, along_y = _normal_terms(k, v, sx, st, bx, by, bt, sy)
    return along_x + along_y


@kernel(inline="always")
def linear_gap_and_rate(k, u, v):
    """(:func:`linear_gap`, :func:`linear_gap_rate`) of one corner, its DOF indices read once:
    the same operations, for the force evaluations that need both."""
    sx, st, bx, by, bt, sy = _corner_dofs(k)
    gx, gy = _normal_terms(k, u, sx, st, bx, by, bt, sy)
    rx, ry = _normal_terms(k, v, sx, st, bx, by, bt, sy)
    return k[K_G0] + gx + gy, rx + ry


@kernel
def contact_kinematics(u, corners, nonlinear, gap, WN, WT, corner_slots, dof_slots):
    """Fill gap (n_corners,), WN (n_corners, n_dof) and WT (n_corners, n_dof) for
    displacement u (n_dof,).

    Parameters
    ----------
    u : (n_dof,) absolute displacements [m, rad].
    corners : the corner table of :func:`pack_corners`.
    nonlinear : bool, exact (True) or small-rotation (False) kinematics.
    corner_slots, dof_slots : size tags, tuples of n_corners and n_dof entries (module
        docstring).
    """
    for c in range(len(corner_slots)):
        k = corners[c]
        for j in range(len(dof_slots)):
            WN[c, j] = 0.0
            WT[c, j] = 0.0
        if k[K_SY] >= 0.0:
            _segment_corner_kinematics(u, k, nonlinear, c, gap, WN, WT)
        elif not nonlinear:
            _seat_corner_linear(u, k, c, gap, WN, WT)
        else:
            _seat_corner_nonlinear(u, k, c, gap, WN, WT)


@kernel(inline="always")
def _seat_corner_linear(u, k, c, gap, WN, WT):
    """Row c of gap, W_N, W_T for a corner facing a seat, small rotations."""
    xc, yc = k[K_X], k[K_Y]
    sx = int(k[K_SX])
    st = int(k[K_ST])
    bx, by, bt = int(k[K_BX]), int(k[K_BY]), int(k[K_BT])
    nx, ny, tx, ty = k[K_NX], k[K_NY], k[K_TX], k[K_TY]
    gap[c] = linear_gap(k, u)
    WN[c, bx] = nx
    WN[c, by] = ny
    WN[c, bt] = -nx * yc + ny * xc
    WN[c, sx] = -nx
    WN[c, st] = nx * k[K_RY] - ny * k[K_RX]
    WT[c, bx] = tx
    WT[c, by] = ty
    WT[c, bt] = -tx * yc + ty * xc
    WT[c, sx] = -tx
    if k[K_FREE] == 0.0:  # fixed seat: the contact does not load it
        WN[c, sx] = 0.0
        WN[c, st] = 0.0
        WT[c, sx] = 0.0


@kernel(inline="always")
def _seat_corner_nonlinear(u, k, c, gap, WN, WT):
    """Row c of gap, W_N, W_T for a corner facing a seat, exact kinematics (module
    docstring)."""
    xc, yc = k[K_X], k[K_Y]
    sx = int(k[K_SX])
    st = int(k[K_ST])
    bx, by, bt = int(k[K_BX]), int(k[K_BY]), int(k[K_BT])
    th, ths = u[bt], u[st]
    ct, sn = np.cos(th), np.sin(th)
    px = u[bx] + xc * ct - yc * sn
    py = u[by] + xc * sn + yc * ct
    dpx = -xc * sn - yc * ct  # ∂P_x/∂θ_d
    dpy = xc * ct - yc * sn  # ∂P_y/∂θ_d
    cs, ss = np.cos(ths), np.sin(ths)
    nx = k[K_NX] * cs - k[K_NY] * ss  # n = R(θ_s) n₀
    ny = k[K_NX] * ss + k[K_NY] * cs
    tx = k[K_TX] * cs - k[K_TY] * ss  # t = R(θ_s) t₀
    ty = k[K_TX] * ss + k[K_TY] * cs
    rx = px - (k[K_PX] + u[sx])
    ry = py - k[K_PY]
    gap[c] = nx * rx + ny * ry
    WN[c, bx] = nx
    WN[c, by] = ny
    WN[c, bt] = nx * dpx + ny * dpy
    WN[c, sx] = -nx
    WN[c, st] = -ny * rx + nx * ry  # (∂n/∂θ_s)·(P − F), ∂n/∂θ_s = (−n_y, n_x)
    WT[c, bx] = tx
    WT[c, by] = ty
    WT[c, bt] = tx * dpx + ty * dpy
    WT[c, sx] = -tx
    if k[K_FREE] == 0.0:
        WN[c, sx] = 0.0
        WN[c, st] = 0.0
        WT[c, sx] = 0.0


@kernel(inline="always")
def _segment_corner_kinematics(u, k, nonlinear, c, gap, WN, WT):
    """Row c of gap, W_N, W_T for a joint corner: segment b's corner P against the facing
    segment o's end face, both moving in x, y and θ.

    Small rotations: g_N = g₀ + n·(u_P − u_Q), u_Q = (x_o − r_y θ_o, y_o + r_x θ_o) the
    facing point's motion (r the lever about o's centre), U_T = t·(u̇_P − u̇_Q). Exact: with
    the face's normal and tangent rotated by θ_o, n = R(θ_o) n₀, and D = P − (O₀ + (x_o, y_o))
    the corner relative to o's centre, g_N = n·D − n₀·r (the facing point R(θ_o) r rides on
    the face, n·R(θ_o) r = n₀·r), W_N[θ_o] = (∂n/∂θ_o)·D, and U_T = t·Ṗ − t·(ẋ_o, ẏ_o)
    − θ̇_o t₀·(−r_y, r_x) (the facing point's velocity along the face)."""
    xc, yc = k[K_X], k[K_Y]
    rx, ry = k[K_RX], k[K_RY]
    sx, sy, st = int(k[K_SX]), int(k[K_SY]), int(k[K_ST])
    bx, by, bt = int(k[K_BX]), int(k[K_BY]), int(k[K_BT])
    if not nonlinear:
        nx, ny, tx, ty = k[K_NX], k[K_NY], k[K_TX], k[K_TY]
        gap[c] = linear_gap(k, u)
        dpx, dpy = -yc, xc
        wst = nx * ry - ny * rx
    else:
        th, tho = u[bt], u[st]
        ct, sn = np.cos(th), np.sin(th)
        px = u[bx] + xc * ct - yc * sn
        py = u[by] + xc * sn + yc * ct
        dpx = -xc * sn - yc * ct
        dpy = xc * ct - yc * sn
        co, so = np.cos(tho), np.sin(tho)
        nx = k[K_NX] * co - k[K_NY] * so
        ny = k[K_NX] * so + k[K_NY] * co
        tx = k[K_TX] * co - k[K_TY] * so
        ty = k[K_TX] * so + k[K_TY] * co
        dx = px - (k[K_PX] + u[sx])
        dy = py - (k[K_PY] + u[sy])
        gap[c] = nx * dx + ny * dy - (k[K_NX] * rx + k[K_NY] * ry)
        wst = -ny * dx + nx * dy
    WN[c, bx] = nx
    WN[c, by] = ny
    WN[c, bt] = nx * dpx + ny * dpy
    WN[c, sx] = -nx
    WN[c, sy] = -ny
    WN[c, st] = wst
    WT[c, bx] = tx
    WT[c, by] = ty
    WT[c, bt] = tx * dpx + ty * dpy
    WT[c, sx] = -tx
    WT[c, sy] = -ty
    WT[c, st] = k[K_TX] * ry - k[K_TY] * rx


@kernel
def gap_hessian(u, corners, c, H, dof_slots):
    """∂²g_N/∂u² of corner c for the geometrically nonlinear kinematics (n_dof × n_dof,
    filled; n_dof = len(dof_slots), the DOF size tag)."""
    n_dof = len(dof_slots)
    k = corners[c]
    xc, yc = k[K_X], k[K_Y]
    sx = int(k[K_SX])
    st = int(k[K_ST])
    bx, by, bt = int(k[K_BX]), int(k[K_BY]), int(k[K_BT])
    for i in range(n_dof):
        for j in range(n_dof):
            H[i, j] = 0.0
    th, ths = u[bt], u[st]
    ct, sn = np.cos(th), np.sin(th)
    cs_, ss = np.cos(ths), np.sin(ths)
    px = u[bx] + xc * ct - yc * sn
    py = u[by] + xc * sn + yc * ct
    dpx = -xc * sn - yc * ct
    dpy = xc * ct - yc * sn
    d2px = -xc * ct + yc * sn
    d2py = -xc * sn - yc * ct
    nx = k[K_NX] * cs_ - k[K_NY] * ss
    ny = k[K_NX] * ss + k[K_NY] * cs_
    rx = px - (k[K_PX] + u[sx])
    ry = py - k[K_PY]
    if k[K_SY] >= 0.0:  # a joint corner: the facing segment moves in y too
        ry = ry - u[int(k[K_SY])]
    dnx, dny = -ny, nx  # ∂n/∂θ_s
    H[bt, bt] = nx * d2px + ny * d2py
    H[bx, st] = dnx
    H[by, st] = dny
    H[bt, st] = dnx * dpx + dny * dpy
    H[sx, st] = -dnx
    H[st, st] = -(nx * rx + ny * ry)  # ∂²n/∂θ_s² = −n
    for i in (bx, by, bt, sx):
        H[st, i] = H[i, st]
    if k[K_SY] >= 0.0:
        sy = int(k[K_SY])
        H[sy, st] = -dny
        H[st, sy] = -dny
    if k[K_FREE] == 0.0:  # fixed seat: no seat rows or columns
        for i in range(n_dof):
            H[sx, i] = 0.0
            H[i, sx] = 0.0
            H[st, i] = 0.0
            H[i, st] = 0.0

"""Contact kinematics of the 7-DOF plan model: gaps g_N and direction matrices W_N, W_T.

DOFs u = [x₁, θ₁, x₂, θ₂, x_d, y_d, θ_d] (see :mod:`deckpound.models.mechanics`). Corners
c1 (−L/2, −W/2), c2 (−L/2, W/2) face seat 1; c3 (L/2, −W/2), c4 (L/2, W/2) face seat 2.

Geometrically linear (DESIGN, paper Eq. 1 with fixed directions)::

    left corner:  g_N = g₀ + (x_d − y_c θ_d) − (x₁ − y_c θ₁)
    right corner: g_N = g₀ − (x_d − y_c θ_d) + (x₂ − y_c θ₂)
    tangential velocity U_T = ẏ_d + x_c θ̇_d   (seats are guided in y)

Geometrically nonlinear (paper Fig. 2b): the deck corner at
P = (x_d + x_c cos θ_d − y_c sin θ_d, y_d + x_c sin θ_d + y_c cos θ_d) and the seat face a line
through F (the face mid-point, x = ∓(L/2 + g₀) + x_s) with unit normal n (towards the deck)
and tangent t = (−sin θ_s, cos θ_s):  g_N = n·(P − F);  U_T = t·Ṗ + ẋ_s sin θ_s (the face's
own velocity along t at the contact point reduces to that term).

W_N[c] = ∂g_N/∂u and W_T[c] = ∂U_T/∂u̇ are rows here (shape (4, 7)); the generalised contact
force is W_Nᵀ λ_N + W_Tᵀ λ_T with λ_N ≥ 0 compression. Functions are numba-compiled and take
flat arrays, so they run inside the engines' step loops and from Python alike.
"""

from __future__ import annotations

import numpy as np
from deckpound.analytic._jit import kernel

from deckpound.models.scene import Scene

N_CORNERS = 4
# DOF indices
X1, T1, X2, T2, XD, YD, TD = range(7)


def pack_geometry(scene: Scene, gaps: tuple[float, float] | None = None) -> np.ndarray:
    """Flat geometry array: [x_c(4), y_c(4), g₀(4), side(4), L/2].

    side is +1 for corners facing seat 1 (left) and −1 for seat 2; ``gaps`` overrides the
    seats' initial gaps [m].
    """
    g = gaps if gaps is not None else (scene.seats[0].gap, scene.seats[1].gap)
    xc = [c[0] for c in scene.corners]
    yc = [c[1] for c in scene.corners]
    g0 = [g[0], g[0], g[1], g[1]]
    side = [1.0, 1.0, -1.0, -1.0]
    return np.array(xc + yc + g0 + side + [0.5 * scene.deck.length], dtype=np.float64)


@kernel
def contact_kinematics(u, geom, nonlinear, gap, WN, WT):
    """Fill gap (4,), WN (4, 7) and WT (4, 7) for displacement u (7,).

    Parameters
    ----------
    u : (7,) absolute displacements [m, rad].
    geom : array from :func:`pack_geometry`.
    nonlinear : bool, exact (True) or small-rotation (False) kinematics.
    """
    hl = geom[16]
    for c in range(4):
        xc, yc, g0, side = geom[c], geom[4 + c], geom[8 + c], geom[12 + c]
        sx = X1 if side > 0 else X2
        st = T1 if side > 0 else T2
        for j in range(7):
            WN[c, j] = 0.0
            WT[c, j] = 0.0
        if not nonlinear:
            gap[c] = g0 + side * ((u[XD] - yc * u[TD]) - (u[sx] - yc * u[st]))
            WN[c, XD] = side
            WN[c, TD] = -side * yc
            WN[c, sx] = -side
            WN[c, st] = side * yc
            WT[c, YD] = 1.0
            WT[c, TD] = xc
        else:
            th, ths = u[TD], u[st]
            ct, sn = np.cos(th), np.sin(th)
            px = u[XD] + xc * ct - yc * sn
            py = u[YD] + xc * sn + yc * ct
            dpx = -xc * sn - yc * ct          # ∂P_x/∂θ_d
            dpy = xc * ct - yc * sn           # ∂P_y/∂θ_d
            cs, ss = np.cos(ths), np.sin(ths)
            fx = -side * (hl + g0) + u[sx]
            nx, ny = side * cs, side * ss     # unit normal towards the deck
            rx, ry = px - fx, py
            gap[c] = nx * rx + ny * ry
            WN[c, XD] = nx
            WN[c, YD] = ny
            WN[c, TD] = nx * dpx + ny * dpy
            WN[c, sx] = -nx
            WN[c, st] = side * (-ss * rx + cs * ry)
            tx, ty = -ss, cs
            WT[c, XD] = tx
            WT[c, YD] = ty
            WT[c, TD] = tx * dpx + ty * dpy
            WT[c, sx] = ss


def corner_gaps(scene: Scene, u: np.ndarray, nonlinear: bool = False,
                gaps: tuple[float, float] | None = None) -> np.ndarray:
    """Gaps of the four corners for each row of u (n, 7) [m] (vectorised convenience)."""
    u = np.atleast_2d(np.asarray(u, dtype=float))
    geom = pack_geometry(scene, gaps)
    out = np.empty((u.shape[0], 4))
    WN = np.empty((4, 7))
    WT = np.empty((4, 7))
    for i in range(u.shape[0]):
        contact_kinematics(u[i], geom, nonlinear, out[i], WN, WT)
    return out

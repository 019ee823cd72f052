"""The contact kernels take their corner and DOF counts from their bundles (issue 29, item 3).

The next capability (several deck segments) brings more corners and DOF than the one-deck plan
model. Checked here on a hand-built model of six corners on nine DOF: the plan's four corners,
then c3 and c4 once more, facing a third seat (x, θ = DOF 7, 8) that moves exactly as seat 2
(DOF 2, 3). The extra corners' gaps, normal and tangential rows, Hessians, contact forces and
Newton tangent must then be those of c3 and c4 with the seat columns moved, the first four
corners those of the plan model, and the per-step peaks must track all six corners.
"""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.analytic.bundles import Contact, new_contact_work
from deckpound.analytic.kernels import contact_assembly as ca
from deckpound.analytic.kernels import contact_laws as cl
from deckpound.analytic.kernels.kinematics import (
    K_G0,
    K_ST,
    K_SX,
    contact_kinematics,
    gap_hessian,
    pack_corners,
)
from deckpound.analytic.kernels.peaks import N_RELATIVE, new_peaks, peak_row_size, track_step
from deckpound.analytic.kernels.system import (
    RowLayout,
    bent_column,
    end_column,
    gap_column,
    normal_force_column,
    row_layout,
)
from deckpound.analytic.nonsmooth.impulses import size_tag
from deckpound.models.plan import plan_of
from deckpound.models.scene_io import load_scene

N_DOF, N_CORNERS = 9, 6
SEAT2, SEAT3 = [2, 3], [7, 8]  # (x, θ) DOF of the second seat and of the added third one
OTHERS = [0, 1, 4, 5, 6]  # first seat and deck DOF


def scene(*more: str):
    return load_scene("saiidi-4span", ["deck.skew=30.0", *more])


def six_corner_table(sc):
    """Corner table of six corners: the plan's four, then c3 and c4 facing the third seat."""
    plan_table = pack_corners(plan_of(sc))
    extra = plan_table[2:4].copy()
    extra[:, K_SX], extra[:, K_ST] = SEAT3
    return plan_table, np.vstack([plan_table, extra])


def nine_dof(u7):
    """The 9-DOF state of a 7-DOF one, the third seat where seat 2 is."""
    u = np.zeros(N_DOF)
    u[:7] = u7
    u[SEAT3] = u7[SEAT2]
    return u


def assert_extra_rows_are_moved_copies(rows9, rows7):
    """Rows (6, 9) against the plan model's (4, 7): c1..c4 the same (zero on the third seat),
    c5, c6 those of c3, c4 with the seat-2 columns moved to the third seat."""
    np.testing.assert_array_equal(rows9[:4, :7], rows7)
    np.testing.assert_array_equal(rows9[:4, SEAT3], 0.0)
    np.testing.assert_array_equal(rows9[4:, OTHERS], rows7[2:, OTHERS])
    np.testing.assert_array_equal(rows9[4:, SEAT3], rows7[2:, SEAT2])
    np.testing.assert_array_equal(rows9[4:, SEAT2], 0.0)


def kinematics(table, u, nonlinear):
    nc, nd = table.shape[0], u.shape[0]
    g, wn, wt = np.zeros(nc), np.zeros((nc, nd)), np.zeros((nc, nd))
    contact_kinematics(u, table, nonlinear, g, wn, wt, size_tag(nc), size_tag(nd))
    return g, wn, wt


@pytest.mark.parametrize("nonlinear", [False, True])
def test_gaps_rows_and_hessians_of_six_corners_on_nine_dof(nonlinear):
    sc = scene("seats[1].gap=0.02")
    table4, table6 = six_corner_table(sc)
    rng = np.random.default_rng(29)
    for _ in range(4):
        u7 = rng.uniform(-0.05, 0.05, 7)
        g4, wn4, wt4 = kinematics(table4, u7, nonlinear)
        g6, wn6, wt6 = kinematics(table6, nine_dof(u7), nonlinear)
        np.testing.assert_array_equal(g6, np.concatenate([g4, g4[2:]]))
        assert np.all(wn4[2:, SEAT2] != 0.0)  # the seat-2 columns carry something to move
        assert_extra_rows_are_moved_copies(wn6, wn4)
        assert_extra_rows_are_moved_copies(wt6, wt4)
        if nonlinear:
            for c9, c7 in ((2, 2), (4, 2), (5, 3)):
                H7, H9 = np.zeros((7, 7)), np.full((N_DOF, N_DOF), np.nan)
                gap_hessian(u7, table4, c7, H7, size_tag(7))
                gap_hessian(nine_dof(u7), table6, c9, H9, size_tag(N_DOF))
                seat = SEAT2 if c9 < 4 else SEAT3
                idx = [0, 1, *seat, 4, 5, 6]  # the 7-DOF order with that corner's seat
                np.testing.assert_array_equal(H9[np.ix_(idx, idx)], H7)
                rest = np.setdiff1d(np.arange(N_DOF), idx)
                assert np.all(H9[rest] == 0.0) and np.all(H9[:, rest] == 0.0)
    # at rest: the extra corners' gap is the seat gap g₀ they were given
    g6, _, _ = kinematics(table6, np.zeros(N_DOF), nonlinear)
    np.testing.assert_allclose(g6[4:], table6[4:, K_G0], rtol=0, atol=1e-14)


def contact_forces(sc, table, u, v, nonlinear):
    """(ContactWork, corner states) after the gap check and the laws at (u, u̇)."""
    nc, nd = table.shape[0], u.shape[0]
    cp4 = cl.pack_contact(sc)
    cp = cp4[[0, 1, 2, 3, 2, 3][:nc]]
    cs = np.zeros((nc, cl.N_CS))
    cs[:, cl.S_CG] = table[:, K_G0]
    contact = Contact(table, cp, nonlinear)
    cw = new_contact_work(nc, nd)
    dofs = tuple(range(nd))
    ca.linear_rows(contact, cw, u, dofs)  # as the loops do at the start of a run
    if ca.eval_contacts(contact, cs, cw, u, v, np.zeros(nd), dofs) < 0:
        ca.eval_closed(contact, cs, cw, u, v, np.zeros(nd), dofs)
    return contact, cw


@pytest.mark.parametrize(
    "geometry, friction",
    [("linear", ["contact.friction=0.3", "contact.friction_mode=slip"]), ("nonlinear", [])],
)
def test_contact_forces_and_tangent_of_six_corners_on_nine_dof(geometry, friction):
    """The right end pushed 2 mm into seat 2 (and the third seat) while sliding: c3..c6 closed
    and equal in pairs, c1, c2 open; F_c = W_Nᵀ λ_N + W_Tᵀ λ_T, the third seat loaded as seat
    2; Newton's contact tangent is −∂F_c/∂u (central differences)."""
    sc = scene(f"contact.geometry={geometry}", *friction)
    nonlinear = geometry == "nonlinear"
    table4, table6 = six_corner_table(sc)
    u7, v7 = np.zeros(7), np.zeros(7)
    u7[4], u7[6] = 0.02, 1e-5  # deck x [m], θ [rad]: the right end 1-2 mm into its seats
    v7[5] = 0.05  # the deck slides along y [m/s]
    u9, v9 = nine_dof(u7), nine_dof(v7)
    _, cw4 = contact_forces(sc, table4, u7, v7, nonlinear)
    contact6, cw6 = contact_forces(sc, table6, u9, v9, nonlinear)
    np.testing.assert_array_equal(cw6.g, np.concatenate([cw4.g, cw4.g[2:]]))
    assert np.all(cw6.lam[2:] > 0.0) and np.all(cw6.lam[:2] == 0.0)
    np.testing.assert_array_equal(cw6.lam, np.concatenate([cw4.lam, cw4.lam[2:]]))
    np.testing.assert_array_equal(cw6.lt, np.concatenate([cw4.lt, cw4.lt[2:]]))
    assert (np.all(cw6.lt[2:] != 0.0)) == bool(friction)
    assert_extra_rows_are_moved_copies(cw6.WN, cw4.WN)
    fc = cw6.WN.T @ cw6.lam + cw6.WT.T @ cw6.lt
    np.testing.assert_allclose(cw6.fc, fc, rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(cw6.fc[SEAT3], cw6.fc[SEAT2])  # the third seat as seat 2
    np.testing.assert_allclose(cw6.fc[4:7], 2.0 * cw4.fc[4:7], rtol=1e-12)  # deck: both pairs
    # Newton's tangent: Keff += −∂F_c/∂u (c2 = 0: the rate terms left out)
    Keff = np.zeros((N_DOF, N_DOF))
    ca.contact_tangent(contact6, cw6, u9, 0.0, Keff, np.zeros((N_DOF, N_DOF)), tuple(range(9)))
    h = 1e-8
    fd = np.zeros((N_DOF, N_DOF))
    for j in range(N_DOF):
        e = np.zeros(N_DOF)
        e[j] = h
        fp = contact_forces(sc, table6, u9 + e, v9, nonlinear)[1].fc
        fm = contact_forces(sc, table6, u9 - e, v9, nonlinear)[1].fc
        fd[:, j] = -(fp - fm) / (2 * h)
    scale = np.max(np.abs(Keff))
    assert scale > 0.0
    np.testing.assert_allclose(Keff, fd, rtol=0, atol=1e-6 * scale)
    np.testing.assert_array_equal(Keff[np.ix_(SEAT3, SEAT3)], Keff[np.ix_(SEAT2, SEAT2)])


def test_peaks_track_six_corners():
    """The peak layout of six corners (gaps, then six normal and six tangential forces, bents,
    relative displacements, bent deformations): closures, deepest gaps and the unseating of a
    fifth and sixth corner counted as of the first four."""
    plan_layout = row_layout(plan_of(scene()))
    layout = RowLayout(plan_layout.dof_columns, size_tag(N_CORNERS), 2)
    channels = ["bent1_x", "bent1_y", "seat1_x", "seat2_x"]
    support = np.array([np.inf, np.inf, np.inf, np.inf, np.inf, 0.05])
    pk = new_peaks(layout, channels, ["bent1"], support)
    c_gap, c_fn, c_bent = gap_column(layout), normal_force_column(layout), bent_column(layout)
    assert (c_fn, c_bent) == (c_gap + 6, c_gap + 18)
    assert c_gap == gap_column(plan_layout)  # the same DOF columns as the plan's
    assert pk.row.shape == (c_bent + 2 * 2 + N_RELATIVE,) == (peak_row_size(layout),)
    assert len(pk.layout.corners) == N_CORNERS and end_column(layout) == c_bent + 2
    u, ug, d = np.zeros(7), np.zeros(4), np.array([0.001, -0.002])

    def step(t, gaps, fn):
        pk.row[:] = 0.0
        pk.row[c_gap : c_gap + N_CORNERS] = gaps
        pk.row[c_fn : c_fn + N_CORNERS] = fn
        return track_step(pk, t, u, ug, d)

    open6 = np.full(N_CORNERS, 0.01)
    assert not step(0.0, open6, np.zeros(N_CORNERS))
    # c5 closes with a penetration of 1 mm; c6 touches with g > 0 but carries a force
    gaps = open6.copy()
    gaps[4] = -0.001
    fn = np.zeros(N_CORNERS)
    fn[5] = 3.0
    assert not step(0.1, gaps, fn)
    assert pk.closures.tolist() == [0, 0, 0, 0, 1, 1]
    assert pk.value[c_gap + 4] == -0.001 and pk.time[c_gap + 4] == 0.1
    assert pk.value[c_fn + 5] == 3.0  # the sixth normal-force column
    # the bent deformations follow the relative displacements
    np.testing.assert_array_equal(pk.row[c_bent + 2 + N_RELATIVE :], d)
    # c6 opens by 6 cm > its 5 cm seat: unseated at t = 0.2
    gaps = open6.copy()
    gaps[5] = 0.01 + 0.06
    assert step(0.2, gaps, np.zeros(N_CORNERS))
    assert int(pk.unseat[0]) == 6 and pk.unseat_time[0] == 0.2
    assert pk.gap_open[5] == gaps[5] and pk.gap_start[5] == 0.01

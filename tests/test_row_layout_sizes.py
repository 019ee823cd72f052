"""Per-corner arrays, output-row offsets and the peaks' readers take their sizes from the plan
(issue 29, item 3).

The next capability (several deck segments) brings more corners and DOF than the one-deck plan
model. Checked here on a hand-built plan of six corners: the plan's four, then one at the middle
of each deck end (y = 0, facing seat 1 and seat 2), and on a row layout of nine DOF. The contact
parameters, the corner states and their commit, revert and stored energy, the engine columns of
a row and the peaks with their per-corner readers must cover every corner of the plan, and the
offsets of a row must agree with the column names of the models layer for the plan model.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from deckpound.analytic.bundles import new_contact_work
from deckpound.analytic.kernels import contact_laws as cl
from deckpound.analytic.kernels.contact_assembly import N_LAW_DERIVATIVES
from deckpound.analytic.kernels.kinematics import K_G0, contact_kinematics, pack_corners
from deckpound.analytic.kernels.peaks import (
    new_peaks,
    run_output_fields,
    run_peaks,
    step_closures,
    step_openings,
    step_unseated,
    track_step,
)
from deckpound.analytic.kernels.system import (
    C_T,
    C_U,
    RowLayout,
    bent_column,
    end_column,
    gap_column,
    initial_dofs,
    normal_force_column,
    pack_system,
    row_layout,
    store_standard,
    tangential_force_column,
    velocity_column,
)
from deckpound.analytic.nonsmooth.impulses import size_tag
from deckpound.analytic.nonsmooth.moreau_jean_work import impulse_columns
from deckpound.models.contact_params import kelvin_voigt_damping
from deckpound.models.damping import damping_model
from deckpound.models.engine_contract import engine_columns
from deckpound.models.plan import DOF_COLUMNS, VELOCITY_COLUMNS, plan_of
from deckpound.models.scene_io import load_scene


def scene():
    return load_scene("saiidi-4span", ["contact.friction=0.3", "contact.friction_mode=stick"])


def six_corner_plan(plan):
    """The plan with a fifth and a sixth corner at the middle of the left and the right deck
    end (y = 0, lever arm 0), each facing the seat of that end."""
    mid = [
        dataclasses.replace(plan.corners[k], name=f"c{5 + i}", index=4 + i, y=0.0, lever=(0.0, 0.0))
        for i, k in enumerate((0, 2))
    ]
    return dataclasses.replace(plan, corners=plan.corners + tuple(mid))


def column_names(plan, layout):
    """The engine-column names of a row in ``layout`` for ``plan``'s corners and bents (the
    order of :func:`deckpound.models.engine_contract.engine_columns`)."""
    names = [c.name for c in plan.corners]
    cols = ["t"] + [n for n, _ in DOF_COLUMNS] + [n for n, _ in VELOCITY_COLUMNS]
    for kind in ("gap", "fn", "ft"):
        cols += [f"{kind}_{c}" for c in names]
    for b in plan.bent_names:
        cols += [f"{b}_fx", f"{b}_fy"]
    assert len(cols) == end_column(layout)
    return cols


def test_offsets_of_the_plan_model_are_its_column_names():
    """For the plan model the offsets land on the names of the models layer."""
    plan = plan_of(scene())
    layout = row_layout(plan)
    cols = engine_columns(plan)
    assert layout.dof_columns == tuple(dof for _, dof in DOF_COLUMNS)
    assert len(layout.corners) == 4 and layout.nbs == plan.n_bent_springs == 6
    assert (C_T, C_U) == (0, 1) and cols[C_T] == "t" and cols[C_U] == "deck_x_abs"
    assert cols[velocity_column(layout)] == "deck_vx_abs"
    assert cols[gap_column(layout)] == "gap_c1"
    assert cols[normal_force_column(layout)] == "fn_c1"
    assert cols[tangential_force_column(layout)] == "ft_c1"
    assert cols[bent_column(layout)] == "bent1_fx"
    assert end_column(layout) == len(cols)


def test_contact_parameters_and_states_cover_six_corners():
    """pack_contact gives one row per corner of the plan it is given; the corner states,
    their commit, revert and stored energy cover all six."""
    sc = scene()
    plan6 = six_corner_plan(plan_of(sc))
    cp, cp4 = cl.pack_contact(sc, plan6), cl.pack_contact(sc)
    assert cp.shape == (6, cl.N_CP) and cp4.shape == (4, cl.N_CP)
    np.testing.assert_array_equal(cp[:4], cp4)  # the plan's corners as packed for the scene
    others = [k for k in range(cl.N_CP) if k != cl.P_C]
    np.testing.assert_array_equal(cp[4:, others], cp4[:2, others])  # the scene's law
    # Kelvin–Voigt dashpot 2ζ√(k m_eff): a mid-end corner has no rotation lever, so it sees
    # more mass than an end corner
    np.testing.assert_array_equal(cp[:, cl.P_C], kelvin_voigt_damping(sc, plan6))
    assert cp[4, cl.P_C] > cp[0, cl.P_C] and cp[5, cl.P_C] > cp[2, cl.P_C]
    table = pack_corners(plan6)
    cs = cl.new_contact_state(table[:, K_G0])
    assert cs.shape == (6, cl.N_CS)
    np.testing.assert_array_equal(cs[:, cl.S_CG], [c.gap for c in plan6.corners])
    # the mid-end corners, linear kinematics: the mean gap of the two corners of their end
    u = np.array([0.0, 0.0, 0.0, 0.0, 0.004, 0.001, 2e-4])
    g, wn, wt = np.zeros(6), np.zeros((6, 7)), np.zeros((6, 7))
    contact_kinematics(u, table, False, g, wn, wt, size_tag(6), size_tag(7))
    np.testing.assert_allclose(g[4:], [0.5 * (g[0] + g[1]), 0.5 * (g[2] + g[3])], rtol=1e-12)
    # commit: every corner takes its converged gap, rate and trial force
    k = cp[0, cl.P_K]
    gaps = np.array([0.01, 0.01, 0.01, 0.01, -0.001, -0.002])
    cs[:, cl.S_TLAM] = np.maximum(-k * gaps, 0.0)
    cl.contact_commit(cs, gaps, np.full(6, -0.1), np.ones(6, dtype=np.bool_))
    np.testing.assert_array_equal(cs[:, cl.S_CG], gaps)
    np.testing.assert_array_equal(cs[:, cl.S_CGD], -0.1)
    np.testing.assert_array_equal(cs[:, cl.S_CLAM], np.maximum(-k * gaps, 0.0))
    # stored energy of the linear law: ½ k g² of the two closed corners (the fifth and sixth)
    assert cl.contact_stored_energy(cp, cs) == pytest.approx(0.5 * k * (0.001**2 + 0.002**2))
    # revert: trial := committed, every corner
    cs[:, cl.S_TLAM] = 7.0
    cl.contact_revert(cs)
    np.testing.assert_array_equal(cs[:, cl.S_TLAM], cs[:, cl.S_CLAM])


def test_contact_work_sizes_its_law_derivatives_by_the_laws():
    """The law derivatives are N_LAW_DERIVATIVES columns per corner whatever the DOF count
    (a 3-DOF model still needs all seven law quantities)."""
    for n_corners, n_dof in ((6, 9), (2, 3)):
        cw = new_contact_work(n_corners, n_dof)
        assert cw.der.shape == (n_corners, N_LAW_DERIVATIVES)
        assert cw.WN.shape == cw.WT.shape == (n_corners, n_dof) and cw.fc.shape == (n_dof,)
        assert len(cw.corners) == n_corners


def test_a_row_of_six_corners_and_its_peaks():
    """store_standard writes each value under its column name for six corners; the peaks track
    them and the readers name the plan's six corners (the sixth unseated)."""
    sc = scene()
    plan6 = six_corner_plan(plan_of(sc))
    layout = row_layout(plan6)
    cols = column_names(plan6, layout)
    names = [c.name for c in plan6.corners]
    assert cols.index("gap_c6") == gap_column(layout) + 5
    assert cols.index("fn_c1") == normal_force_column(layout)
    assert cols.index("ft_c1") == tangential_force_column(layout)
    assert cols.index("bent1_fx") == bent_column(layout)
    ps = pack_system(plan6, damping_model(sc, plan6))
    support = np.array([np.inf] * 5 + [0.05])
    pk = new_peaks(layout, ps.channels, plan6.bent_names, support)
    rng = np.random.default_rng(29)
    u, v = rng.normal(size=7), rng.normal(size=7)
    fs = rng.normal(size=ps.n_springs)
    ug = np.zeros(len(ps.channels))
    d = rng.normal(size=ps.n_springs)

    def step(t, g, fn):
        ft = -0.5 * fn
        store_standard(pk.row, layout, t, u, v, g, fn, ft, fs)
        row = pk.row
        assert row[cols.index("t")] == t
        for name, dof in DOF_COLUMNS:
            assert row[cols.index(name)] == u[dof]
        for name, dof in VELOCITY_COLUMNS:
            assert row[cols.index(name)] == v[dof]
        for k, c in enumerate(names):
            assert row[cols.index(f"gap_{c}")] == g[k]
            assert row[cols.index(f"fn_{c}")] == fn[k]
            assert row[cols.index(f"ft_{c}")] == ft[k]
        for i, b in enumerate(plan6.bent_names):
            assert row[cols.index(f"{b}_fx")] == fs[2 * i]
            assert row[cols.index(f"{b}_fy")] == fs[2 * i + 1]
        return track_step(pk, t, u, ug, d)

    g0 = np.full(6, 0.0127)
    assert not step(0.0, g0, np.zeros(6))
    g1 = g0.copy()
    g1[4] = -0.001  # c5 closes
    fn1 = np.zeros(6)
    fn1[4] = 20.0
    assert not step(0.1, g1, fn1)
    g2 = g0.copy()
    g2[5] += 0.06  # c6 opens by 6 cm on its 5 cm seat
    assert step(0.2, g2, np.zeros(6))
    closures = step_closures(pk, names)
    assert closures == {"c1": 0, "c2": 0, "c3": 0, "c4": 0, "c5": 1, "c6": 0}
    openings = step_openings(pk, names)
    assert list(openings) == names
    assert openings["c6"] == (pytest.approx(0.06, rel=1e-12), 0.2)
    assert openings["c5"] == (0.0, 0.0)  # its largest gap is its first
    assert step_unseated(pk, names) == ("c6", 0.2)
    assert pk.value[cols.index("gap_c5")] == -0.001
    assert pk.value[cols.index("fn_c5")] == 20.0
    assert pk.value[cols.index("ft_c5")] == 10.0
    with pytest.raises(ValueError, match="one per corner of the peaks"):
        step_closures(pk, names[:4])
    with pytest.raises(ValueError, match="support lengths: one per corner"):
        new_peaks(layout, ps.channels, plan6.bent_names, support[:4])


def test_the_engines_name_the_columns_of_every_corner_of_the_plan():
    """The drivers size the rows by the models layer's names, which follow the plan's corner
    table (several deck segments add corners): a six-corner plan gets six corners' columns,
    and a plan whose DOF the names do not cover is refused before any loop writes past a row."""
    sc = scene()
    plan = plan_of(sc)
    ps = pack_system(plan, damping_model(sc, plan))
    pk = run_peaks(plan, ps)
    assert pk.row.shape[0] > end_column(pk.layout) == len(engine_columns(plan))
    assert set(run_output_fields(pk, plan)["gap_closures_per_corner"]) == {"c1", "c2", "c3", "c4"}
    plan6 = six_corner_plan(plan)
    pk6 = run_peaks(plan6, pack_system(plan6, damping_model(sc, plan6)))
    assert end_column(pk6.layout) == len(engine_columns(plan6)) == end_column(pk.layout) + 6
    assert "fn_c6" in engine_columns(plan6)
    assert set(run_output_fields(pk6, plan6)["gap_closures_per_corner"]) == {
        f"c{k}" for k in range(1, 7)
    }
    plan9 = dataclasses.replace(plan, mass=np.ones(9))
    with pytest.raises(ValueError, match="the plan has 9 DOF"):
        run_peaks(plan9, ps)


def test_nine_dof_layout_and_its_refusal_without_columns():
    """A row layout of nine DOF puts the two extra DOF after the plan's seven displacement and
    velocity columns; row_layout refuses a plan whose DOF the column names do not cover."""
    dofs9 = tuple(dof for _, dof in DOF_COLUMNS) + (7, 8)
    layout = RowLayout(dofs9, size_tag(4), 2)
    assert (velocity_column(layout), gap_column(layout)) == (10, 19)
    assert end_column(layout) == 19 + 12 + 2
    row = np.full(end_column(layout), np.nan)
    u, v = np.arange(9.0), 10.0 + np.arange(9.0)
    g, fn, ft, fs = np.full(4, 0.5), np.full(4, 1.5), np.full(4, 2.5), np.array([3.0, 4.0, 9.0])
    store_standard(row, layout, 0.25, u, v, g, fn, ft, fs)
    np.testing.assert_array_equal(row[C_U:10], u[list(dofs9)])
    np.testing.assert_array_equal(row[10:19], v[list(dofs9)])
    np.testing.assert_array_equal(row[19:], [0.5] * 4 + [1.5] * 4 + [2.5] * 4 + [3.0, 4.0])
    plan9 = dataclasses.replace(plan_of(scene()), mass=np.ones(9))
    with pytest.raises(ValueError, match="the plan has 9 DOF"):
        row_layout(plan9)


def test_per_corner_names_and_initial_state_follow_the_model():
    names = ["c1", "c2", "c3", "c4", "c5", "c6"]
    cols = impulse_columns(names)
    assert len(cols) == 18 and cols[5] == "pn_c6" and cols[11] == "pt_c6" and cols[17] == "state_c6"
    with pytest.raises(ValueError, match=r"7 finite numbers \(DOF order seat1_x, "):
        initial_dofs((np.zeros(6), np.zeros(7)), 7)
    with pytest.raises(ValueError, match=r"9 finite numbers; got"):
        initial_dofs((np.zeros(7), np.zeros(9)), 9)

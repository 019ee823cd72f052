"""A deck of several segments (issue 31): the scene's checks, the plan's corner table and
kinematics, the result columns, the table lags, and the commands that read them (compare,
the ParaView export, the joint study)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import deckpound as dp
from deckpound.analytic.kernels.kinematics import contact_kinematics, gap_hessian, pack_corners
from deckpound.analytic.nonsmooth.impulses import size_tag
from deckpound.compare.compare_run import compare_quantities, run_compare
from deckpound.compare.report.figures import outlines
from deckpound.compare.report.vtk import check_result_folder, export_vtk, state_columns
from deckpound.compare.studies.joint import joint_cases, joint_headlines, joint_row
from deckpound.models.columns import column_names
from deckpound.models.errors import SceneError
from deckpound.models.excitation import support_motion
from deckpound.models.motion import table_positions
from deckpound.models.plan import plan_of
from deckpound.models.scene import Joint, Segment
from deckpound.models.scene_io import load_scene


@pytest.fixture(scope="module")
def two_frame():
    return load_scene("two-frame", ["run.duration=2", "excitation.duration=2"])


def three_frames(skew: float = 0.0, joint_skew: float | None = None):
    """The two-frame bridge cut once more: three frames of 10, 11.5 and 12 m on the
    benchmark's three bents plus one more, so that each frame stands on two bents."""
    base = load_scene("saiidi-4span", ["run.duration=2", "excitation.duration=2"])
    lengths, width, mass = (10.0, 11.5, 12.0), base.deck.width, base.deck.mass
    masses = [mass * L / 33.5 for L in lengths]
    masses[-1] = mass - sum(masses[:-1])
    segs = tuple(
        Segment(name=f"f{i + 1}", length=L, mass=m, inertia=m * (L * L + width * width) / 12)
        for i, (L, m) in enumerate(zip(lengths, masses))
    )
    b = base.bents
    stations = (3.0, 8.0, 13.0, 19.0, 24.0, 31.0)
    bents = tuple(
        dataclasses.replace(b[i % 3], name=f"b{i + 1}", station=st) for i, st in enumerate(stations)
    )
    centres = [-16.75 + 5.0, -16.75 + 10.0 + 5.75, -16.75 + 21.5 + 6.0]
    inertia = sum(s.inertia + s.mass * c * c for s, c in zip(segs, centres))
    return dataclasses.replace(
        base,
        name="three-frames",
        deck=dataclasses.replace(base.deck, inertia=inertia, skew=skew),
        bents=bents,
        segments=segs,
        joints=(Joint(gap=0.01, skew=joint_skew), Joint(gap=0.02, support_length=0.2)),
        notes={},
    )


def test_the_scene_refuses_inconsistent_segments(two_frame):
    """Each inconsistency is named by its field, with the value that would fit."""
    segs = two_frame.segments
    with pytest.raises(SceneError, match=r"joints.*one joint between each pair.*1 for 2.*got 0"):
        dataclasses.replace(two_frame, joints=())
    with pytest.raises(SceneError, match=r"segments.*two or more"):
        dataclasses.replace(two_frame, segments=segs[:1], joints=())
    with pytest.raises(SceneError, match=r"deck\.length.*sum of the segment lengths, 33\.5"):
        two_frame.replace({"deck.length": 34.0, "bents[3].station": 26.2})
    with pytest.raises(SceneError, match=r"deck\.mass.*segment masses, 140\.5"):
        two_frame.replace({"deck.mass": 141.0})
    with pytest.raises(SceneError, match=r"deck\.inertia.*about the deck centre"):
        two_frame.replace({"deck.inertia": 13090.0})
    with pytest.raises(SceneError, match=r"bents\[1\]\.segment.*joint between segments"):
        two_frame.replace({"bents[1].segment": None})
    with pytest.raises(SceneError, match=r"bents\[0\]\.segment.*names no segment"):
        two_frame.replace({"bents[0].segment": "frame9"})
    with pytest.raises(SceneError, match=r"bents\[0\]\.station.*outside segment 'frame2'"):
        two_frame.replace({"bents[0].segment": "frame2"})
    with pytest.raises(SceneError, match=r"segments\[1\]\.name.*unique word"):
        two_frame.replace({"segments[1].name": "frame1"})
    with pytest.raises(SceneError, match=r"initial.*segments\[i\]\.velocity"):
        two_frame.replace({"initial.deck_velocity": [0.1, 0.0, 0.0]})
    one = load_scene("saiidi-4span")
    with pytest.raises(SceneError, match=r"joints need segments"):
        dataclasses.replace(one, joints=(Joint(gap=0.01),))
    with pytest.raises(SceneError, match=r"bents\[0\]\.segment.*no segments"):
        one.replace({"bents[0].segment": "frame1"})


def test_plan_of_a_deck_of_segments():
    """DOF 4 + 3N, corners along x (seat 1, each joint, seat 2), joint corners on the striking
    segment's left end facing the previous segment, bents on their segment's DOF."""
    sc = three_frames()
    plan = plan_of(sc)
    assert plan.n_dof == 13 and plan.mass.shape == (13,)
    assert [c.name for c in plan.corners] == [
        "c1", "c2", "j1_c1", "j1_c2", "j2_c1", "j2_c2", "c3", "c4"
    ]  # fmt: skip
    j = plan.corners[2]
    assert (j.body, j.joint, j.seat) == (1, 0, -1)
    assert j.body_dofs == (7, 8, 9) and j.facing_dofs == (4, 5, 6)
    assert j.x == pytest.approx(-5.75) and j.lever == pytest.approx((5.0, -1.2))
    assert plan.corners[-1].body_dofs == (10, 11, 12) and plan.corners[-1].facing_dofs == (2, -1, 3)
    assert [c.support_length for c in plan.corners] == [
        0.18,
        0.18,
        None,
        None,
        0.2,
        0.2,
        0.18,
        0.18,
    ]
    # b3 at 13.0 m stands on f2 (10–21.5 m, centre at −16.75 + 10 + 5.75 = −1.0 m)
    k = plan.bent_names.index("b3")
    assert plan.bent_x[k] == pytest.approx(13.0 - 16.75 + 1.0)
    assert plan.springs[2 * k].dofs == (7,) and plan.springs[2 * k + 1].dofs == (8, 9)
    assert plan.segments[1].bents == (2, 3)
    names = column_names(plan)
    for col in ("f2_x_abs", "f3_theta", "f1_vy_abs", "f2_omega", "f3_y_rel", "gap_j2_c1"):
        assert col in names
    assert "deck_theta" not in names


@pytest.mark.parametrize("skew", [0.0, 25.0])
def test_joint_kinematics_rows_are_the_derivatives_of_the_gap(skew):
    """W_N is ∂g/∂u and the Hessian its derivative (central differences), for the joint
    corners with both bodies moving, linear and exact kinematics; W_T·u̇ is the rate of the
    facing point's motion along the face (the linear model's)."""
    plan = plan_of(three_frames(skew, joint_skew=skew / 2))
    table = pack_corners(plan)
    nc, nd = len(plan.corners), plan.n_dof
    rng = np.random.default_rng(7)
    u = 1e-2 * rng.standard_normal(nd)
    gap, WN, WT = np.zeros(nc), np.zeros((nc, nd)), np.zeros((nc, nd))
    for nonlinear in (False, True):
        contact_kinematics(u, table, nonlinear, gap, WN, WT, size_tag(nc), size_tag(nd))
        base_wn = WN.copy()
        h = 1e-6
        for j in range(nd):
            g2 = np.zeros(nc)
            du = np.zeros(nd)
            du[j] = h
            gp, gm = np.zeros(nc), np.zeros(nc)
            contact_kinematics(u + du, table, nonlinear, gp, WN, WT, size_tag(nc), size_tag(nd))
            contact_kinematics(u - du, table, nonlinear, gm, WN, WT, size_tag(nc), size_tag(nd))
            g2[:] = (gp - gm) / (2 * h)
            np.testing.assert_allclose(base_wn[:, j], g2, atol=1e-8)
        if nonlinear:
            for c in range(nc):
                H = np.zeros((nd, nd))
                gap_hessian(u, table, c, H, size_tag(nd))
                np.testing.assert_allclose(H, H.T, atol=0)
                for j in range(nd):
                    du = np.zeros(nd)
                    du[j] = 1e-6
                    wp, wm = np.zeros((nc, nd)), np.zeros((nc, nd))
                    contact_kinematics(u + du, table, True, gap, wp, WT, size_tag(nc), size_tag(nd))
                    contact_kinematics(u - du, table, True, gap, wm, WT, size_tag(nc), size_tag(nd))
                    np.testing.assert_allclose(H[:, j], (wp[c] - wm[c]) / 2e-6, atol=1e-6)
    # at rest the gaps are the joints' and the rows the plan's own
    contact_kinematics(np.zeros(nd), table, False, gap, WN, WT, size_tag(nc), size_tag(nd))
    np.testing.assert_allclose(gap, [c.gap for c in plan.corners], atol=1e-15)
    np.testing.assert_array_equal(WN, plan.normal_rows())
    np.testing.assert_array_equal(WT, [c.tangent_row(nd) for c in plan.corners])


def test_a_rigid_body_motion_of_the_whole_deck_leaves_every_joint_gap():
    """Translating and rotating all segments and seats together as one rigid body (small
    rotation, linear kinematics) changes no gap: the joints' rows are consistent with the
    segments' positions."""
    sc = three_frames(skew=20.0, joint_skew=10.0)
    plan = plan_of(sc)
    dth = 1e-3
    u = np.zeros(plan.n_dof)
    for seg in plan.segments:
        x, y, th = seg.dofs
        u[x], u[y], u[th] = 0.01, 0.02 + seg.centre * dth, dth
    joint = [c.index for c in plan.corners if c.joint >= 0]
    np.testing.assert_allclose(plan.linear_gaps(u)[0, joint], [plan.corners[k].gap for k in joint])


def test_bents_at_one_station_share_their_table():
    """The two halves of a pier under a joint get one motion: the lag counts tables, not
    bents; bents at distinct stations keep their index (existing scenes unchanged)."""
    sc = load_scene("two-frame", ["excitation.lag=0.1", "run.duration=3", "excitation.duration=3"])
    assert table_positions(sc) == [0, 1, 1, 2]
    assert table_positions(load_scene("saiidi-4span")) == [0, 1, 2]
    m = support_motion(sc)
    np.testing.assert_array_equal(m.disp["bent2a_x"], m.disp["bent2b_x"])
    assert not np.array_equal(m.disp["bent1_x"], m.disp["bent2a_x"])
    shift = round(0.1 / sc.excitation.dt)
    np.testing.assert_array_equal(m.disp["bent3_y"][2 * shift :], m.disp["bent1_y"][: -2 * shift])


def test_two_frame_runs_compare_and_export(two_frame, tmp_path):
    """The analytic engines run the two-frame scene; compare aligns every segment's quantities,
    the plan view and the ParaView export outline each frame."""
    out = tmp_path / "cmp"
    text = run_compare(two_frame, ["compliance", "nonsmooth"], out, progress=False)
    assert "frame1" in text and "frame2" in text
    for name in ("histories.png", "contact_forces.png", "plan_at_peak_rotation.png"):
        assert (out / "figures" / name).stat().st_size > 0
    header = (out / "aligned_compliance.csv").read_text().splitlines()[0]
    quantities = compare_quantities(plan_of(two_frame))
    assert "frame2_theta" in quantities and "gap_j1_c1" in quantities
    assert header.split(",")[1:] == [f"{q} [{'rad' if 'theta' in q else 'm'}]" for q in quantities]
    results = check_result_folder(out)
    assert set(results) == {"compliance", "nonsmooth"}
    written = export_vtk(out, tmp_path / "vtk")
    import meshio

    with meshio.xdmf.TimeSeriesReader(written[0]) as reader:
        points, cells = reader.read_points_cells()
    assert points.shape[0] == 4 * 4  # two frames and two seats, four points each
    assert len(cells[0].data) == 4


def test_the_joint_study_rows_and_headlines(two_frame):
    """The joint study's cases vary every joint's gap and the lag; its rows read the joint
    corners' forces, closures, openings and margins, and its headlines quote the table."""
    cases = [c for c in joint_cases(two_frame, quick=True) if c.engine != "opensees"]
    assert {c.params["joint_gap"] for c in cases} == {0.0, 0.0127, 0.0508}
    picked = [c for c in cases if c.params["lag"] == 0.0]
    rows = []
    for case in picked:
        r = dp.run(case.scene, engine=case.engine)
        row = joint_row(case, r)
        joint = [f"j1_c{k}" for k in (1, 2)]
        assert row["peak_fn_joint"] == max(r.peak(f"fn_{c}") for c in joint)
        per = r.meta["gap_closures_per_corner"]
        assert row["joint_closures"] == per["j1_c1"] + per["j1_c2"]
        assert row["joint_margin_min"] == pytest.approx(
            0.18 - max(r.meta["gap_opening_max"][c][0] for c in joint)
        )
        assert row["peak_theta"] == max(r.peak("frame1_theta"), r.peak("frame2_theta"))
        rows.append(row)
    import pandas as pd

    lines = joint_headlines(pd.DataFrame(rows))
    assert len(lines) == 2 and all("peak joint force" in line for line in lines)
    with pytest.raises(SceneError, match="needs a deck of segments"):
        joint_cases(load_scene("saiidi-4span"), quick=True)


def test_the_papers_joint_section_runs_the_two_frame_bridge_for_the_benchmark(tmp_path):
    """deckpound paper shows the joint study of the built-in two-frame bridge on the
    benchmark's record length, no section for another scene, and refuses a deck of segments."""
    from deckpound.compare.report.joints import joints_scene, joints_section, run_joints
    from deckpound.compare.report.paper import run_paper
    from deckpound.compare.report.render import Figure, Table
    from deckpound.compare.result_cache import ResultCache

    bench = load_scene("saiidi-4span", ["excitation.duration=3", "run.duration=3"])
    sc = joints_scene(bench)
    assert sc.name == "two-frame" and sc.excitation.duration == 3.0 and sc.run.duration == 3.0
    assert joints_scene(bench.replace(name="my-bridge")) is None
    assert joints_scene(load_scene("two-frame")) is None
    with pytest.raises(SceneError, match="deckpound paper reproduces.*'deckpound study joint'"):
        run_paper(load_scene("two-frame"), tmp_path / "paper", quick=True, progress=False)
    out = tmp_path / "report"
    (out / "tables").mkdir(parents=True)
    (out / "figures").mkdir()
    run = run_joints(
        bench.replace({"excitation.duration": 1.0, "run.duration": 1.0}),
        out,
        quick=True,
        cache=ResultCache(tmp_path / "cache"),
        workers=1,
        scheduler=None,
        progress=False,
    )
    assert (out / "tables" / "study_joint.csv").is_file()
    assert (out / "figures" / "study_joint.png").is_file()
    items = joints_section(run)
    assert "'two-frame'" in items[0] and f"{len(run.table)} cases" in items[0]
    assert any(isinstance(i, Figure) for i in items)
    table = next(i for i in items if isinstance(i, Table)).frame
    assert len(table) == len(run.table)
    assert {"θ frame1 [mrad]", "θ frame2 [mrad]", "joint seat margin [mm]"} <= set(table.columns)


def test_the_outlines_keep_the_joint_gap(two_frame):
    """At rest the drawn frames stand the joint's clear gap apart (the contact model's layout,
    Plan.segment_positions), and the seats their gap behind the deck ends."""
    from deckpound.compare.report.figures import outline_columns, outlines

    plan = plan_of(two_frame)
    polys = outlines(two_frame, dict.fromkeys(outline_columns(plan), 0.0), 1.0)
    right_of_frame1 = polys["frame1"][:, 0].max()
    left_of_frame2 = polys["frame2"][:, 0].min()
    assert left_of_frame2 - right_of_frame1 == pytest.approx(0.0127, abs=1e-12)
    assert polys["frame1"][:, 0].min() - polys["seat1"][:, 0].max() == pytest.approx(0.0127)
    assert polys["seat2"][:, 0].min() - left_of_frame2 == pytest.approx(16.75 + 0.0127)
    assert plan.segment_positions()[1] == pytest.approx((8.375 + 0.0127, 0.0))


@pytest.mark.parametrize(
    "overrides",
    [
        [f"contact.law={law}"]
        for law in ("linear", "kelvin-voigt", "hertz", "hertz-damp", "hertzdamp", "bilinear")
    ]
    + [
        ["contact.friction=0.3", f"contact.friction_mode={mode}"]
        for mode in ("slip", "stick", "contact2d")
    ]
    + [["contact.geometry=nonlinear", "contact.friction=0.3", "contact.friction_mode=stick"]]
    + [["compliance.integrator=adaptive", "contact.friction=0.3", "contact.friction_mode=slip"]],
)
def test_every_law_and_friction_model_runs_a_deck_of_segments(overrides):
    """The compliance engine puts every contact law and friction model on the joint corners:
    the run succeeds (no energy created at a contact), pounds at the joint, and its work-energy
    balance closes."""
    sc = load_scene("two-frame", ["run.duration=4", "excitation.duration=4", *overrides])
    r = dp.run(sc, engine="compliance")
    assert r.meta["status"] == "success", r.meta["message"]
    per = r.meta["gap_closures_per_corner"]
    assert per["j1_c1"] + per["j1_c2"] > 0
    assert r.peak("fn_j1_c1") > 0.0
    if "energy_error" in r.columns:
        assert np.max(np.abs(r["energy_error"])) <= 0.01 * np.max(np.abs(r["energy_input"]))


def test_a_deck_of_segments_in_xarray_has_a_segment_dimension(two_frame):
    """Each segment's columns stack into one variable over (time, segment); the corners'
    over (time, corner), joint corners included."""
    r = dp.run(two_frame, engine="nonsmooth")
    ds = r.to_xarray()
    assert list(ds.coords["segment"].values) == ["frame1", "frame2"]
    np.testing.assert_array_equal(ds["segment_theta"].sel(segment="frame2"), r["frame2_theta"])
    np.testing.assert_array_equal(ds["segment_x_rel"].sel(segment="frame1"), r["frame1_x_rel"])
    assert ds["segment_omega"].attrs["units"] == "rad/s"
    assert "j1_c2" in list(ds.coords["corner"].values)
    np.testing.assert_array_equal(ds["fn"].sel(corner="j1_c1"), r["fn_j1_c1"])
    assert "frame1_theta" not in ds


def test_the_work_precision_errors_of_a_deck_of_segments(two_frame):
    """deckpound bench on a deck of segments: each error is the largest over the segments."""
    from deckpound.compare.bench.work_precision import errors
    from deckpound.compare.metrics import peak

    ref = dp.run(two_frame, engine="compliance")
    r = dp.run(two_frame, engine="nonsmooth")
    e = errors(r, ref, "deck_x_rel")
    by_segment = [
        abs(peak(r[f"{s}_theta"]) - peak(ref[f"{s}_theta"])) / peak(ref[f"{s}_theta"])
        for s in ("frame1", "frame2")
    ]
    assert e["err_peak_theta"] == max(by_segment)
    assert e["err_primary"] == e["err_peak_x"] > 0.0
    assert errors(ref, ref)["err_peak_theta"] == 0.0


def test_segments_of_different_widths_meet_where_their_end_faces_overlap():
    """segments[i].width (default deck.width), centred on the bridge axis: the abutment
    corners at the end segments' own half widths, a joint's corners at the narrower one's;
    the outlines (figures, ParaView) draw each segment at its own width; the OpenSees sticks
    take their segment's section."""
    for widths, ends, joint in (((2.4, 3.6), (1.2, 1.8), 1.2), ((3.6, 2.0), (1.8, 1.0), 1.0)):
        sc = load_scene("two-frame", [f"segments[{i}].width={w}" for i, w in enumerate(widths)])
        plan = plan_of(sc)
        y = {c.name: c.y for c in plan.corners}
        assert (y["c1"], y["c2"]) == (-ends[0], ends[0])
        assert (y["c3"], y["c4"]) == (-ends[1], ends[1])
        assert (y["j1_c1"], y["j1_c2"]) == (-joint, joint)
        assert [s.half_width for s in plan.segments] == [0.5 * w for w in widths]
        boxes = outlines(sc, dict.fromkeys(state_columns(sc), 0.0), 1.0)
        for seg, w in zip(plan.segments, widths):
            assert np.ptp(boxes[seg.name][:, 1]) == pytest.approx(w, abs=1e-12)
            assert np.ptp(boxes[seg.name][:, 0]) == pytest.approx(2 * seg.half_length, abs=1e-12)
    # the default: every segment deck.width wide, the corners as before
    plain = plan_of(load_scene("two-frame"))
    assert {abs(c.y) for c in plain.corners} == {0.5 * load_scene("two-frame").deck.width}

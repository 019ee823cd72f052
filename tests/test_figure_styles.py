"""The report's figures read like a paper's (issue 32, item 6): every case or engine of a
figure has its own (line style, marker) pair, so it stays distinct in greyscale; markers on a
dense line are spaced along it; legends stand beside the data, never on it, and inside the
figure; contact forces are drawn in the report's one contact-force unit.

Each figure function is drawn from small synthetic inputs and the figure is inspected after
:func:`deckpound.compare.report.style.save` laid it out and wrote it.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from deckpound.compare.engines import engine_names, engine_style
from deckpound.compare.report import figures, plotting, style
from deckpound.compare.report.render import BENT_FORCE, CONTACT_FORCE
from deckpound.compare.studies.damping import damping_figure
from deckpound.compare.studies.ida import (
    fragility_figure,
    fragility_table,
    limit_states,
    with_rotation_flag,
)
from deckpound.compare.studies.sensitivity import STUDIES
from deckpound.compare.studies.sequence_run import SequenceRun
from deckpound.compare.studies.skew import skew_figure
from deckpound.compare.studies.variability import figure as variability_figure
from deckpound.models.excitation import support_motion
from deckpound.models.result import Result
from deckpound.models.scene_io import load_scene, modified

ENGINES = ("opensees", "compliance", "nonsmooth")
#: a line with more points than this is dense: its markers must be spaced (markevery)
DENSE = 50


@pytest.fixture
def drawn(monkeypatch):
    """The figures saved during a test, laid out and written as the report writes them."""
    figs = []
    real = style.save

    def keep(fig, path, scene_name, formats=()):
        written = real(fig, path, scene_name, formats)
        figs.append(fig)
        return written

    monkeypatch.setattr(style, "save", keep)
    monkeypatch.setattr(plotting, "save", keep)  # imported at the module's top
    return figs


@pytest.fixture(scope="module")
def scene():
    return load_scene("saiidi-4span", ["excitation.duration=2.0"])


def _result(engine: str, phase: float, n: int = 401, amp: float = 1.0) -> Result:
    """A result with every column the figures read: rotation, displacements, corner gaps and
    forces (tangential 0.1 of the normal), bent force and deformation."""
    t = np.linspace(0.0, 2.0, n)
    wave = np.sin(2 * np.pi * t + phase)
    cols = {
        "t": t,
        "deck_theta": amp * 1e-3 * wave,
        "deck_y_rel": amp * 2e-3 * wave,
        "deck_x_rel": amp * 1e-3 * np.cos(2 * np.pi * t + phase),
    }
    for c in range(1, 5):
        fn = np.clip(300.0 * amp * np.sin(4 * np.pi * t + phase + c), 0.0, None)
        cols[f"fn_c{c}"] = fn
        cols[f"ft_c{c}"] = 0.1 * fn
        cols[f"gap_c{c}"] = np.where(fn > 0, -1e-4, 5e-3)
    for b in ("bent1", "bent2", "bent3"):
        for a in ("x", "y"):
            cols[f"{b}_d{a}"] = 1e-3 * wave
            cols[f"{b}_f{a}"] = 200.0 * np.tanh(wave)
    for j in (1, 2):
        cols[f"seat{j}_x_rel"] = 1e-4 * wave
        cols[f"seat{j}_theta"] = 0.0 * wave
    return Result(engine, cols)


def _series(ax):
    """The labelled lines of an axes (what its legend lists)."""
    return [ln for ln in ax.get_lines() if not ln.get_label().startswith("_")]


def check_figure(fig, *, min_series: int = 2, cases: bool = True) -> int:
    """Every axes: distinct (line style, marker) pairs among its labelled lines, each with a
    marker, spaced along a dense line (``cases``: the labelled lines are cases, not a band and
    its median); every legend outside every axes' data area and inside the figure. Returns the
    largest number of labelled lines on one axes."""
    canvas = FigureCanvasAgg(fig)  # a closed figure's canvas draws no more
    canvas.draw()
    renderer = canvas.get_renderer()
    boxes = [ax.get_window_extent(renderer) for ax in fig.axes]
    most = 0
    for ax in fig.axes:
        lines = _series(ax)
        most = max(most, len(lines))
        pairs = [(ln.get_linestyle(), ln.get_marker()) for ln in lines]
        assert len(set(pairs)) == len(pairs), pairs
        for ln in lines if cases else []:
            assert ln.get_marker() not in ("None", "", None, " "), ln.get_label()
            if len(ln.get_xdata()) > DENSE:  # markers evenly over its points, not on every one
                start, step = ln.get_markevery()
                marks = len(range(start, len(ln.get_xdata()), step))
                assert style.MIN_MARKS - 1 <= marks <= style.MARKS_PER_LINE + 1, ln.get_label()
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    legends += list(fig.legends)
    assert legends or most < min_series, "a figure of several series has no legend"
    for legend in legends:
        box = legend.get_window_extent(renderer)
        for ax_box in boxes:
            overlap = box.intersection(box, ax_box)
            area = 0.0 if overlap is None else overlap.width * overlap.height
            assert area < 1.0, (legend.get_texts()[0].get_text(), box, ax_box)
        assert box.x0 >= fig.bbox.x0 - 1 and box.x1 <= fig.bbox.x1 + 1, (box, fig.bbox)
        assert box.y0 >= fig.bbox.y0 - 1 and box.y1 <= fig.bbox.y1 + 1, (box, fig.bbox)
    return most


# -- the helper ---------------------------------------------------------------------------------


def test_series_styles_keep_the_engines_and_never_repeat_a_pair():
    """The first series of an engine is the registry's style with the engine's marker; the
    same engine under other assumptions keeps colour and marker, hollow, on another line
    style; nothing repeats a (line style, marker) pair, even for more series than styles."""
    labels = [
        f"{e} mu={mu}" for mu in (0.0, 0.1, 0.2, 0.3, 0.5) for e in ("compliance", "nonsmooth")
    ]
    styles = style.series_styles(labels)
    pairs = [(s["linestyle"], s["marker"]) for s in styles]
    assert len(set(pairs)) == len(pairs) == 10
    for e in ("compliance", "nonsmooth"):
        mine = [s for s, lab in zip(styles, labels) if lab.startswith(e)]
        registry = engine_style(e)
        assert mine[0]["linestyle"] == registry["linestyle"]
        assert mine[0]["color"] == registry["color"]
        assert mine[0]["marker"] == style.engine_marker(e)
        assert "markerfacecolor" not in mine[0]
        assert {s["color"] for s in mine} == {registry["color"]}
        assert all(s["markerfacecolor"] == "white" for s in mine[1:])
        # the first variant takes a line style no series had yet
        assert mine[1]["linestyle"] not in {
            registry["linestyle"] for registry in map(engine_style, ("compliance", "nonsmooth"))
        }
    # engines keep their marker across figures, whatever else a figure holds
    alone = style.series_styles(["nonsmooth"])[0]
    assert (alone["linestyle"], alone["marker"]) == (
        engine_style("nonsmooth")["linestyle"],
        style.engine_marker("nonsmooth"),
    )
    assert len({style.engine_marker(e) for e in engine_names()}) == len(engine_names())
    # cases that are no engine's: by position, still all distinct
    many = style.series_styles([f"table {k}" for k in range(20)], [None] * 20, points=1000)
    assert len({(s["linestyle"], s["marker"]) for s in many}) == 20
    assert len({s["markevery"] for s in many}) == 20  # offset: coinciding lines show both
    assert all(1000 // s["markevery"][1] == style.MIN_MARKS for s in many)  # many: fewer each
    few = style.series_styles(["opensees", "compliance"], points=[4001, 801])
    assert [1 + (n - 1) // s["markevery"][1] for s, n in zip(few, (4001, 801))] == [
        style.MARKS_PER_LINE + 1
    ] * 2  # about MARKS_PER_LINE, evenly over each line's own points
    assert all("markevery" not in s for s in styles)  # sparse: a marker on every point
    with pytest.raises(ValueError, match="labels but"):
        style.series_styles(["a", "b"], [None])
    with pytest.raises(ValueError, match="point counts"):
        style.series_styles(["a", "b"], points=[10])


# -- the report's figures -----------------------------------------------------------------------


def test_histories_and_contact_forces(drawn, scene, tmp_path):
    results = {e: _result(e, 0.2 * k) for k, e in enumerate(ENGINES)}
    results["compliance μ=0.2"] = _result("compliance", 0.9)
    figures.histories(results, scene, tmp_path / "h.png")
    figures.contact_forces(results, scene, tmp_path / "f.png")
    hist, forces = drawn
    assert check_figure(hist) == 4 and check_figure(forces) == 4
    peak = max(float(np.max(r["fn_c1"])) for r in results.values())
    top = max(float(np.max(ln.get_ydata())) for ln in _series(forces.axes[0]))
    assert top == pytest.approx(CONTACT_FORCE.scale * peak)
    assert all(f"[{CONTACT_FORCE.unit}]" in ax.get_ylabel() for ax in forces.axes)


def test_peak_and_ratio_along_the_sequence(drawn, scene, tmp_path):
    rows = []
    for case in (*ENGINES, *(f"{e} μ=0.2" for e in ENGINES)):
        for run in range(1, 8):
            rows.append({"run": run, "pga": 0.1 * run, "case": case, "peak_theta": 1e-3 * run})
    figures.peak_vs_pga(pd.DataFrame(rows), scene, tmp_path / "p.png")
    effect = pd.DataFrame(
        [
            {"engine": e, "run": run, "pga": 0.1 * run, "mu": 0.2, "ratio": 1 + 0.01 * run}
            for e in ENGINES
            for run in range(1, 8)
        ]
    )
    figures.friction_ratio(effect, scene, tmp_path / "r.png")
    peak, ratio = drawn
    assert check_figure(peak) == 6 and check_figure(ratio) == 3


def test_friction_mechanism_styles_match_across_panels(drawn, scene, tmp_path):
    rough_scene = modified(scene, "contact.friction=0.2", "contact.friction_mode=stick")
    pairs = {
        e: (
            SequenceRun(7, 1.0, None, scene, _result(e, 0.1 * k)),
            SequenceRun(7, 1.0, None, rough_scene, _result(e, 0.5 + 0.1 * k, amp=1.5)),
        )
        for k, e in enumerate(ENGINES)
    }
    figures.friction_mechanism(pairs, tmp_path / "m.png", title="run 7")
    (fig,) = drawn
    assert check_figure(fig) == 6
    top, bottom = (_series(ax) for ax in fig.axes[:2])
    assert len(bottom) == 3
    look = {ln.get_label(): (ln.get_linestyle(), ln.get_marker()) for ln in top}
    for ln in bottom:  # the run with friction looks the same in both panels
        assert ln.get_label().endswith("μ = 0.2")
        assert look[ln.get_label()] == (ln.get_linestyle(), ln.get_marker())
    assert f"[{CONTACT_FORCE.unit}·m]" in fig.axes[1].get_ylabel()


@pytest.mark.parametrize("name", ["friction", "stiffness", "law"])
def test_study_figures(drawn, scene, tmp_path, name):
    """The full friction study has ten cases (five μ, two engines): more than any fixed cycle
    of line styles, each still its own pair; the stiffness study's rigid limit is a marked
    horizontal line."""
    cases = STUDIES[name].cases(scene, False)
    results = {c.label: _result(c.engine, 0.1 * k) for k, c in enumerate(cases)}
    rows = []
    for k, c in enumerate(cases):
        rows.append(
            {"label": c.label, "engine": c.engine, **c.params, "peak_theta": 1e-3 + k * 1e-4}
        )
    figures.study_figure(
        STUDIES[name], scene, cases, results, pd.DataFrame(rows), tmp_path / "s.png"
    )
    (fig,) = drawn
    assert check_figure(fig) == len(cases)
    if name == "stiffness":
        rigid = next(ln for ln in _series(fig.axes[0]) if "rigid" in ln.get_label())
        assert len(set(rigid.get_ydata())) == 1 and len(rigid.get_xdata()) > 1


def test_hysteresis_in_the_bent_force_unit(drawn, scene, tmp_path):
    figures.hysteresis(_result("opensees", 0.0), scene, tmp_path / "b.png")
    (fig,) = drawn
    assert all(ax.get_ylabel() == f"bent force [{BENT_FORCE.unit}]" for ax in fig.axes)


def test_excitation_channels(drawn, scene, tmp_path):
    plotting.plot_excitation(scene, support_motion(scene), tmp_path / "e.png")
    (fig,) = drawn
    assert check_figure(fig) >= 2


# -- the studies' own figures ----------------------------------------------------------------


def test_damping_and_skew_figures(drawn, scene, tmp_path):
    damping = pd.DataFrame(
        [
            {"engine": e, "damping": d, "peak_theta": 1e-3 * (k + 1), "peak_fn": 300.0 * (j + 1)}
            for k, e in enumerate(ENGINES)
            for j, d in enumerate(("bents·initial·absolute", "none·initial·absolute"))
        ]
    )
    damping_figure(None, scene, [], {}, damping, tmp_path / "d.png")
    skew = pd.DataFrame(
        [
            {
                "engine": e,
                "mu": mu,
                "friction": "stick" if mu else "none",
                "skew": phi,
                "peak_theta": 1e-3 * (1 + phi / 60),
                "peak_y_rel": 1e-3,
            }
            for e in ENGINES
            for mu in (0.0, 0.2)
            for phi in (0.0, 30.0, 60.0)
        ]
    )
    skew_figure(None, scene, [], {}, skew, tmp_path / "k.png")
    dfig, kfig = drawn
    canvas = FigureCanvasAgg(dfig)
    canvas.draw()
    renderer = canvas.get_renderer()
    for ax in dfig.axes:  # markers only: the cases are choices, one marker per engine
        markers = [ln.get_marker() for ln in _series(ax)]
        assert len(set(markers)) == len(markers) == 3
    legend = dfig.axes[0].get_legend().get_window_extent(renderer)
    assert all(
        legend.intersection(legend, ax.get_window_extent(renderer)) is None
        or legend.intersection(legend, ax.get_window_extent(renderer)).width < 1
        for ax in dfig.axes
    )
    assert f"[{CONTACT_FORCE.unit}]" in dfig.axes[1].get_ylabel()
    top = max(float(np.max(ln.get_ydata())) for ln in _series(dfig.axes[1]))
    assert top == pytest.approx(CONTACT_FORCE.scale * 600.0)
    assert check_figure(kfig) == 6


def test_fragility_and_variability_figures(drawn, scene, tmp_path):
    rng = np.random.default_rng(3)
    levels = (1.0, 2.0, 3.0, 4.0)
    rows = []
    for e in ("compliance", "nonsmooth"):
        for variant in ("μ=0", "μ=0.3"):
            for rec in range(6):
                capacity = rng.uniform(1.5, 4.5)
                for level in levels:
                    rows.append(
                        {
                            "engine": e,
                            "variant": variant,
                            "record_key": f"r{rec}",
                            "level": level,
                            "status": "success",
                            "unseated": level >= capacity,
                            "peak_theta": 2e-3 * level / capacity,
                        }
                    )
    table = with_rotation_flag(pd.DataFrame(rows), 0.002)
    states = limit_states(0.002)
    fragility_figure(
        table, fragility_table(table, states), states, "sa-t1", "x", tmp_path / "f.png"
    )
    cases = pd.DataFrame(
        {
            "engine": "compliance",
            "status": "success",
            "peak_theta": rng.uniform(1e-3, 3e-3, 20),
            "peak_y": rng.uniform(1e-3, 3e-3, 20),
            "gap_closures": rng.integers(0, 50, 20),
        }
    )
    summary = pd.DataFrame(
        [
            {
                "quantity": q,
                "median": cases[q].median(),
                "p16": cases[q].quantile(0.16),
                "p84": cases[q].quantile(0.84),
            }
            for q in ("peak_theta", "peak_y", "gap_closures")
        ]
    )
    variability_figure(cases, summary, scene, tmp_path / "v.png")
    frag, var = drawn
    assert check_figure(frag) == 4
    check_figure(var, min_series=1, cases=False)

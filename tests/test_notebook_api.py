"""The notebook-grade API (issue 32, item 2): short ``repr`` and escaped ``_repr_html_`` of
scenes, results and comparisons; nested ``Scene.replace``; ``Result.plot`` and
``Comparison.plot``; warnings attributed to the caller's line; ``dp.compare`` reusing the
results it is given."""

from __future__ import annotations

import warnings

import pytest

import deckpound as dp
from deckpound.models.errors import SceneError

HOSTILE = "<script>alert('x')</script> & co"


@pytest.fixture(scope="module")
def scene():
    return dp.load_scene("saiidi-4span", set={"run.duration": 1.0})


@pytest.fixture(scope="module")
def result(scene):
    return dp.run(scene, engine="compliance")


@pytest.fixture(scope="module")
def comparison(scene):
    return dp.compare(scene, engines=["compliance", "nonsmooth"])


# -- repr and _repr_html_ -----------------------------------------------------------------


def test_scene_repr_is_one_short_line_with_the_key_facts(scene):
    text = repr(scene)
    assert len(text) < 300 and "\n" not in text
    assert "saiidi-4span" in text
    assert f"{len(scene.bents)} bents" in text
    assert f"{1e3 * scene.seats[0].gap:g}" in text  # gap in mm
    assert scene.contact.law in text and f"{scene.contact.stiffness:g}" in text
    assert scene.excitation.kind in text


def test_scene_repr_stays_short_for_a_long_name(scene):
    long = scene.replace(name="x" * 5000)
    assert len(repr(long)) < 300


def test_scene_html_escapes_a_hostile_name(scene):
    page = scene.replace(name=HOSTILE)._repr_html_()
    assert "<script>" not in page
    assert "&lt;script&gt;" in page and "&amp; co" in page
    assert "<table>" in page  # the table itself is markup


def test_result_repr_is_short_and_holds_the_key_facts(result):
    text = repr(result)
    assert len(text) < 300 and "\n" not in text
    assert "array" not in text  # no column dump
    assert "'compliance'" in text and "status success" in text
    assert f"rows {len(result.t)}" in text and f"columns {len(result.columns)}" in text
    assert f"duration {result.t[-1] - result.t[0]:g} s" in text
    assert f"peak θ_d {result.peak('deck_theta'):.4g} rad" in text
    assert f"gap closures {result.gap_closures}" in text


def test_result_html_escapes_the_message(result):
    failed = result.with_meta(status="failed", message=HOSTILE)
    page = failed._repr_html_()
    assert "<script>" not in page and "&lt;script&gt;" in page
    assert "failed" in page


def test_comparison_repr_and_html(comparison):
    text = repr(comparison)
    assert len(text) < 300 and "\n" not in text
    assert "compliance" in text and "nonsmooth" in text and "DataFrame" not in text
    page = comparison._repr_html_()
    assert page.count("<tr>") == 1 + len(comparison.results)  # header + one row per engine
    ratio = comparison.metrics.query("engine == 'nonsmooth' and quantity == 'deck_theta'")
    assert f"{float(ratio['peak_ratio'].iloc[0]):.3g}" in page


# -- nested Scene.replace -------------------------------------------------------------------


def test_replace_sets_nested_paths_and_keeps_everything_else(scene):
    new = scene.replace({"contact.stiffness": 2e6, "bents[1].y.beta": 0.3})
    assert new.contact.stiffness == 2e6 and new.bents[1].y.beta == 0.3
    assert scene.contact.stiffness != 2e6 and scene.bents[1].y.beta != 0.3  # a copy
    assert new.bents[1].x == scene.bents[1].x and new.bents[0] == scene.bents[0]
    assert new.replace({"contact.stiffness": scene.contact.stiffness}).contact == scene.contact
    assert new.replace({"bents[1].y.beta": scene.bents[1].y.beta}) == scene.replace(
        {"contact.stiffness": 2e6}
    )


def test_replace_paths_match_load_scene_set():
    changes = {"contact.stiffness": 2e6, "bents[1].y.beta": 0.3, "contact.law": "hertz"}
    base = dp.load_scene("saiidi-4span")
    assert base.replace(changes) == dp.load_scene("saiidi-4span", set=changes)


def test_replace_takes_records_numpy_numbers_and_keywords(scene):
    import numpy as np

    from deckpound.models.scene import Contact

    new = scene.replace(
        {"contact": Contact(stiffness=3e6), "deck.mass": np.float64(150.0)}, name="b"
    )
    assert new.contact.stiffness == 3e6 and new.deck.mass == 150.0 and new.name == "b"
    assert type(new.deck.mass) is float
    assert scene.replace(name="c").name == "c"  # the keyword form is unchanged


@pytest.mark.parametrize(
    ("paths", "field", "words"),
    [
        ({"contact.stifness": 1e6}, "contact.stifness", "did you mean 'stiffness'"),
        ({"bents[9].y.beta": 0.3}, "bents[9].y.beta", "index 9 is out of range"),
        ({"contact.stiffness": -1.0}, "contact.stiffness", "must be > 0"),
        ({"bents[1].y.beta": "x"}, "bents[1].y.beta", "must be a number"),
        ({"deck.length.x": 1.0}, "deck.length.x", "names no field"),
        ({"a..b": 1.0}, "replace('a..b')", "malformed path"),
    ],
)
def test_replace_refuses_bad_paths_naming_them(scene, paths, field, words):
    with pytest.raises(SceneError) as info:
        scene.replace(paths)
    assert info.value.field == field and words in str(info.value)


def test_replace_refuses_a_non_mapping(scene):
    with pytest.raises(SceneError, match="mapping of dotted paths"):
        scene.replace(["contact.stiffness=2e6"])


# -- Result.plot and Comparison.plot ----------------------------------------------------------


def test_result_plot_returns_a_figure_with_units_and_the_data(result):
    import numpy as np
    from matplotlib.figure import Figure

    fig = result.plot(("deck_theta", "gap_c1", "bent1_fx"))
    assert isinstance(fig, Figure)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["deck_theta [mrad]", "gap_c1 [mm]", "bent1_fx [kN]"]
    assert fig.axes[-1].get_xlabel() == "time [s]"
    line = fig.axes[0].lines[0]
    assert np.array_equal(line.get_xdata(), result.t)
    assert np.allclose(line.get_ydata(), 1e3 * result["deck_theta"])  # rad drawn in mrad
    assert np.allclose(fig.axes[2].lines[0].get_ydata(), result["bent1_fx"])  # kN as is


def test_result_plot_overlays_on_a_given_axes(result):
    first = result.plot()
    again = result.plot(ax=first.axes[0], label="again", color="red")
    assert again is first and len(first.axes) == 1
    assert [ln.get_label() for ln in first.axes[0].lines] == ["compliance", "again"]
    with pytest.raises(KeyError, match="no column 'deck_thta'"):
        result.plot("deck_thta")


def test_comparison_plot_histories_and_peaks(comparison):
    from matplotlib.figure import Figure

    fig = comparison.plot("histories", quantities=["deck_theta", "deck_y_rel"])
    assert isinstance(fig, Figure)
    assert [ax.get_ylabel() for ax in fig.axes] == ["deck_theta [mrad]", "deck_y_rel [mm]"]
    for ax in fig.axes:
        assert len(ax.lines) == len(comparison.results)  # one line per engine
    styles = {ln.get_linestyle() for ln in fig.axes[0].lines}
    assert len(styles) == len(comparison.results)  # engines told apart without colour
    peaks = comparison.plot("peaks", quantities=["deck_theta"])
    bars = peaks.axes[0].patches
    assert peaks.axes[0].get_ylabel() == "peak deck_theta [mrad]"
    assert [b.get_height() for b in bars] == pytest.approx(
        [1e3 * r.peak("deck_theta") for r in comparison.results.values()]
    )
    with pytest.raises(ValueError, match="kind must be one of"):
        comparison.plot("spectra")
    with pytest.raises(ValueError, match="not in every result"):
        comparison.plot(quantities=["no_such_column"])


# -- warnings attributed to the caller ---------------------------------------------------------


def test_run_warnings_point_at_the_callers_line(scene):
    import warnings

    from deckpound.models.engine_contract import OptionIgnored

    hertz = scene.replace({"contact.law": "hertz", "run.duration": 0.2})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dp.run(hertz, engine="nonsmooth")  # the nonsmooth engine ignores the compliant law
    ignored = [w for w in caught if issubclass(w.category, OptionIgnored)]
    assert ignored, [str(w.message) for w in caught]
    assert all(w.filename == __file__ for w in caught), [(w.filename, w.lineno) for w in caught]


def test_run_warnings_obey_the_callers_filters(scene):
    import warnings

    hertz = scene.replace({"contact.law": "hertz", "run.duration": 0.2})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the caller's filter still decides
        with pytest.raises(Warning, match="does nothing in the nonsmooth engine"):
            dp.run(hertz, engine="nonsmooth")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("ignore")
        dp.run(hertz, engine="nonsmooth")
    assert not caught


def test_compare_warnings_point_at_the_callers_line(scene, monkeypatch):
    """dp.compare shows each engine warning once per process (compare.cases.surface_warnings);
    its memory of shown messages is emptied so that this test sees them whatever ran before."""
    import warnings

    from deckpound.compare import cases

    monkeypatch.setattr(cases, "_SHOWN", set())
    hertz = scene.replace({"contact.law": "hertz", "run.duration": 0.2})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dp.compare(hertz, engines=["compliance", "nonsmooth"])
    assert any("does nothing in the nonsmooth engine" in str(w.message) for w in caught)
    assert all(w.filename == __file__ for w in caught), [(w.filename, w.lineno) for w in caught]


# -- the example notebook -----------------------------------------------------------------------


def test_example_notebook_runs_and_shows_tables_and_figures():
    """docs/example.ipynb executed by nbclient in a real IPython kernel (ipykernel, this
    interpreter), as a reader would run it: every cell must run; scenes, results and
    comparisons show as HTML tables, ``plot`` calls as PNG figures."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "docs" / "example.ipynb"
    nb = nbformat.read(path, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")  # stored clean
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3").execute()
    code = [c for c in nb.cells if c.cell_type == "code"]
    for cell in code:
        kinds = [o.output_type for o in cell.outputs]
        assert "error" not in kinds, cell.source
    shown = {c.source.splitlines()[-1]: c.outputs[0].get("data", {}) for c in code if c.outputs}
    assert "text/html" in shown["scene"] and "saiidi-4span" in shown["scene"]["text/html"]
    assert "text/html" in shown["res"] and "compliance" in shown["res"]["text/html"]
    assert "text/html" in shown["cmp"] and "nonsmooth" in shown["cmp"]["text/html"]
    figures = [src for src, data in shown.items() if ".plot(" in src]
    assert len(figures) >= 4 and all("image/png" in shown[src] for src in figures)


def test_compare_reuses_the_results_it_is_given_and_refuses_another_scenes():
    """Issue 32: dp.compare does not run again an engine whose result the caller passes."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = dp.load_scene("saiidi-4span", set={"run.duration": 1.0})
        mine = {e: dp.run(sc, engine=e) for e in ("compliance", "nonsmooth")}
        c = dp.compare(sc, engines=["compliance", "nonsmooth"], results=mine)
        assert all(c.results[e] is mine[e] for e in mine)  # nothing was run again
        other = dp.load_scene("saiidi-4span", set={"run.duration": 1.0, "seats[0].gap": 0.02})
        with pytest.raises(SceneError, match=r"results\['compliance'\]"):
            dp.compare(other, engines=["compliance"], results={"compliance": mine["compliance"]})
        summary = dp.run(sc, engine="compliance", summary_only=True)
        with pytest.raises(SceneError, match="summary-only result"):
            dp.compare(sc, engines=["compliance"], results={"compliance": summary})

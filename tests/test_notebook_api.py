"""The notebook-grade API (issue 32, item 2): short ``repr`` and escaped ``_repr_html_`` of
scenes, results and comparisons; nested ``Scene.replace``; ``Result.plot`` and
``Comparison.plot``; warnings attributed to the caller's line."""

from __future__ import annotations

import pytest

import deckpound as dp

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

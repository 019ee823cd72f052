"""The nonsmooth engine's impact law as a named option, measured (issue 12).

``deckpound verify impact-law saiidi-4span`` prints the table docs/verification.md quotes
between the ``impact-law-table`` markers (``python tools/verify_tables.py impact-law``); this
test re-runs the measurement (:func:`deckpound.compare.studies.impact_law.impact_law_table`) and checks
that the page's block is exactly what it prints (here, not under tests/docs: the measurement
is shared with the physics checks), and that the measurement supports the default
(``nonsmooth.impact_law = "newton"``): smaller penetration and closer agreement with the
compliance clone (OpenSees to round-off) with and without friction, the discrete energy balance
closed for both laws, and the energy-safe variant the only one whose impulses give no energy
back.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest

from deckpound.compare.studies.impact_law import FRICTION_LABEL, format_table, impact_law_table
from deckpound.models.engine_contract import PENETRATION_WARN_FRACTION
from deckpound.models.scene_io import load_scene
from deckpound.models.scene_settings import NonsmoothSettings

PAGE = Path(__file__).resolve().parents[1] / "docs" / "verification.md"


@pytest.fixture(scope="module")
def rows():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return impact_law_table(load_scene("saiidi-4span"))


def test_verification_page_quotes_the_measurement(rows):
    text = PAGE.read_text(encoding="utf-8")
    m = re.search(r"<!-- impact-law-table[^>]*-->\n(.*?)\n<!-- /impact-law-table -->", text, re.S)
    assert m, "docs/verification.md has no impact-law-table block"
    assert m.group(1).strip() == format_table(rows).strip()


def test_measurement_supports_the_default(rows):
    """The rule docs/verification.md states: the default is the law that follows the clone (OpenSees to
    round-off) at least as closely, with and without friction, provided its energy balance
    closes and its penetration stays below the nonsmooth quality threshold. Newton's law is
    also the standard Moreau–Jean law; the energy-safe one is the only one whose impulses give
    no energy back, and without friction it penetrates more."""
    assert NonsmoothSettings().impact_law == "newton"
    by = {(r["friction"], r["impact_law"]): r for r in rows}
    assert all(r["status"] == "success" for r in rows)
    gap = min(s.gap for s in load_scene("saiidi-4span").seats)
    for fr in ("none", FRICTION_LABEL):
        newton, safe = by[(fr, "newton")], by[(fr, "energy-safe")]
        assert newton["nrmse_theta"] <= 1.01 * safe["nrmse_theta"]
        for r in (newton, safe):
            assert r["energy_closure"] < 1e-12
            assert r["max_penetration"] >= r["max_penetration_rows"]
            assert r["max_penetration"] < PENETRATION_WARN_FRACTION[False] * gap
        assert safe["impact_gain"] <= 1e-12 < newton["impact_gain"] < 1e-2
    assert (
        by[("none", "newton")]["max_penetration"] < by[("none", "energy-safe")]["max_penetration"]
    )

"""docs/contact_step.md is the contact-step rule's table as the code computes it now, and every
row meets the rule's stated error (issue 28, item 2)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

from deckpound.compare.studies.contact_step import contact_step_table, failures
from deckpound.models.scene_io import load_scene

TOOL = Path(__file__).resolve().parents[1] / "tools" / "contact_step_table.py"


def _tool():
    spec = importlib.util.spec_from_file_location("contact_step_table", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_docs_page_is_the_current_table():
    tool = _tool()
    assert tool.PAGE.read_text(encoding="utf-8") == tool.page_text(), (
        "docs/contact_step.md is stale: run python tools/contact_step_table.py"
    )


def test_a_rule_turned_off_misses_the_stated_error():
    """The check can fail: the paper's 0.5 ms at k = 1e8 creates energy and is refused."""
    scene = load_scene(
        "saiidi-4span", ["run.steps_per_contact_period=0.2", "excitation.duration=6"]
    )
    rows = contact_step_table(scene, stiffnesses=(1e8,))
    assert rows[0]["step"] == scene.compliance.dt
    assert failures(rows)

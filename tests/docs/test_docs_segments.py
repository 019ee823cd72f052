"""docs/segments.md's cost block is the rendering of the stored measurement
``docs/results/segments.json`` (``tools/segments_benchmark.py``, issue 31 item 6), and its
verdicts follow from the numbers; the benchmark's bridges differ only in their number of frames.
Nothing here is timed."""

from __future__ import annotations

import copy
import json

import pytest
import segments_benchmark as sb
from docs_blocks import block_of

from deckpound.models.plan import plan_of


def test_page_block_is_the_rendering_of_the_stored_measurement():
    stored = json.loads(sb.FILE.read_text(encoding="utf-8"))
    page = sb.PAGE.read_text(encoding="utf-8")
    assert block_of(page, sb.BEGIN, sb.END) == sb.render(stored), (
        "docs/segments.md's cost block is not the rendering of docs/results/segments.json: run "
        "`python tools/segments_benchmark.py --render` (or measure again)"
    )


def _data(costs: dict) -> dict:
    rows = [
        {"segments": n, "engine": e, "us_per_step": costs[(n, e)], "steps": 40000,
         "iterations_per_step": 2.0, "gap_closures": 10, "dof": 4 + 3 * n,
         "corners": 2 * n + 2, "bents": 2 * n, "status": "success"}
        for n in sb.SEGMENTS for e in sb.ENGINES
    ]  # fmt: skip
    return {"when": "now", "machine": "m", "repeats": 1, "rows": rows}


def test_the_verdicts_follow_the_numbers():
    ok = _data({(n, e): float(n) for n in sb.SEGMENTS for e in sb.ENGINES})
    text = sb.render(ok)
    assert "compliance: 3 segments cost 3.00× one per step (not met" in text
    assert "linear growth" in text
    fast = copy.deepcopy(ok)
    for r in fast["rows"]:
        r["us_per_step"] = {1: 1.0, 2: 1.5, 3: 2.0}[r["segments"]]
    assert "2.00× one per step (met: at most 2.5×)" in sb.render(fast)
    steep = copy.deepcopy(ok)
    for r in steep["rows"]:
        r["us_per_step"] = {1: 1.0, 2: 1.2, 3: 2.4}[r["segments"]]
    assert "faster than linear" in sb.render(steep)


@pytest.mark.parametrize("n", sb.SEGMENTS)
def test_the_benchmark_bridges_differ_only_in_their_frames(n):
    """Same deck, same total bent stiffness and strength, two bents per frame."""
    sc = sb.frames_scene(n)
    plan = plan_of(sc)
    assert plan.n_dof == 4 + 3 * n and len(plan.corners) == 2 * n + 2
    assert len(sc.bents) == 2 * n
    assert sum(b.x.stiffness for b in sc.bents) == pytest.approx(22000.0)
    assert sum(b.y.yield_force for b in sc.bents) == pytest.approx(480.0)
    assert sc.deck.mass == pytest.approx(140.5)
    assert [len(s.bents) for s in plan.segments] == [2] * n

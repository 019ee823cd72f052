"""Write docs/contact_step.md: the contact-step rule measured on the built-in benchmark.

Repository tooling (not installed with the package): ``python tools/contact_step_table.py``
runs :func:`deckpound.compare.studies.contact_step.contact_step_table` on ``saiidi-4span`` and writes
the page; ``tests/test_contact_step_table.py`` recomputes the table and fails when the page is
stale.
"""

from __future__ import annotations

import sys
from pathlib import Path

from deckpound.compare.studies.contact_step import contact_step_table, failures, format_table
from deckpound.models.scene_io import load_scene

PAGE = Path(__file__).resolve().parents[1] / "docs" / "contact_step.md"
SCENE = "saiidi-4span"
HEADER = """# The contact-step rule, measured

The fixed-step penalty engines (compliance `newmark`, OpenSees) take at most
T_c / `run.steps_per_contact_period` per step (default 3.5; T_c = 2π √(m_eff / k), the period
of the stiffest corner contact). On the built-in benchmark (`{scene}`, 20 s record), the
compliance engine at each contact stiffness k at its default step and at a tenth of it:
energy created at the contacts over the input energy (the run is `doubtful` above
`run.energy_tolerance`, 1 %) and the peak deck rotation over every step. The last two columns
are what the rule does not promise, measured the same way: the largest contact force and the
number of gap closures. A few steps per contact period resolve the energy exchanged and the
deck's motion, not the shape of each force pulse; for contact forces or closure counts, run
more steps per period (`run.steps_per_contact_period`) and compare.

Written by `python tools/contact_step_table.py`; `deckpound verify contact-step {scene}` prints
the same table and exits 1 when a row misses the stated error (no energy created beyond the
tolerance, peak rotation within 1 % of the tenth-step run); `tests/test_contact_step_table.py`
fails when this page is stale.

"""


def page_text() -> str:
    rows = contact_step_table(load_scene(SCENE))
    bad = failures(rows)
    verdict = "Every row meets the stated error." if not bad else "FAILS: " + "; ".join(bad)
    return HEADER.format(scene=SCENE) + format_table(rows) + "\n\n" + verdict + "\n"


if __name__ == "__main__":
    PAGE.write_text(page_text(), encoding="utf-8")
    print(f"wrote {PAGE}")
    sys.exit(0)

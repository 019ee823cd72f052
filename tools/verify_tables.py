"""Publish the verification tables of docs/verification.md: the clone-vs-OpenSees matrix and
the nonsmooth impact-law table, measured on the built-in benchmark.

Repository tooling (not installed with the package); it calls the functions behind
``deckpound verify clone`` and ``deckpound verify impact-law``:

    python tools/verify_tables.py matrix        # compliance newmark vs OpenSees, every case
    python tools/verify_tables.py impact-law    # Newton vs energy-safe, without and with friction

``matrix`` exits 1 (and writes the table all the same) when a case exceeds its tolerance.
``tests/test_verify_matrix.py`` and ``tests/test_impact_law.py`` check the page's blocks.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from docs_blocks import DOCS, block_of, write_block

from deckpound.compare.studies import impact_law
from deckpound.compare.verify import matrix as verify_matrix
from deckpound.models.scene_io import load_scene

PAGE = DOCS / "verification.md"
SCENE = "saiidi-4span"


def matrix_block(page: Path = PAGE) -> str | None:
    """The verification-matrix block of ``page`` (None when it has none)."""
    return block_of(page.read_text(encoding="utf-8"), verify_matrix.BEGIN, verify_matrix.END)


def impact_law_block(page: Path = PAGE) -> str | None:
    """The impact-law block of ``page`` (None when it has none)."""
    return block_of(page.read_text(encoding="utf-8"), impact_law.BEGIN, impact_law.END)


def publish_matrix(page: Path = PAGE, log=print) -> int:
    """Run the whole matrix on the benchmark and write its table; 1 when a case fails."""
    scene = load_scene(SCENE)
    results = verify_matrix.run_matrix(scene, log=log)
    block = verify_matrix.table_block(results, scene, quick=False)
    log(f"wrote {write_block(page, verify_matrix.BEGIN, verify_matrix.END, block)}")
    return 0 if all(r.ok for r in results) else 1


def publish_impact_law(page: Path = PAGE, log=print) -> int:
    """Measure the impact-law table on the benchmark and write it."""
    rows = impact_law.impact_law_table(load_scene(SCENE))
    block = f"{impact_law.BEGIN}\n{impact_law.format_table(rows)}\n{impact_law.END}"
    log(f"wrote {write_block(page, impact_law.BEGIN, impact_law.END, block)}")
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("table", choices=("matrix", "impact-law"))
    a = p.parse_args(argv)
    if a.table == "matrix":
        return publish_matrix(log=lambda t: print(t, flush=True))
    return publish_impact_law()


if __name__ == "__main__":
    raise SystemExit(main())

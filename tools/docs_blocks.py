"""Generated blocks of the documentation pages: a tool's output between two HTML comment markers.

Repository tooling (not installed with the package). Every number the docs quote from a
measurement lives in such a block, written by the tool that publishes it (``tools/*.py``) and
checked by a test under ``tests/docs/``, never edited by hand. The block's first marker starts
with ``<!-- NAME`` (the rest of that line says which tool writes it) and its last is
``<!-- /NAME -->`` (or the end marker the block's module names).
"""

from __future__ import annotations

from pathlib import Path

from deckpound.models.file_io import atomic_write_text

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: where the measurement files behind the docs' blocks live
RESULTS = DOCS / "results"


def block_of(text: str, begin: str, end: str) -> str | None:
    """The block of ``text`` from ``begin``'s tag (its text before the first colon) to ``end``,
    markers included; None when the page has no such block."""
    head = begin.split(":")[0]
    if head not in text or end not in text:
        return None
    start = text.index(head)
    return text[start : text.index(end, start) + len(end)]


def replace_block(text: str, begin: str, end: str, block: str) -> str:
    """``text`` with the block from ``begin``'s tag to ``end`` replaced by ``block`` (appended
    when ``text`` has none)."""
    old = block_of(text, begin, end)
    if old is not None:
        start = text.index(old)
        return text[:start] + block + text[start + len(old) :]
    return text.rstrip("\n") + "\n\n" + block + "\n"


def write_block(path: str | Path, begin: str, end: str, block: str) -> Path:
    """Put ``block`` into the page at ``path`` in place of the previous one (atomically)."""
    path = Path(path)
    text = replace_block(path.read_text(encoding="utf-8"), begin, end, block)
    return atomic_write_text(path, text, field=str(path))

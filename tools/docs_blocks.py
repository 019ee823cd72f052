"""Generated blocks of the README: a command's output between two HTML comment markers.

Every number the README quotes from a measurement lives in such a block, written by the command
that measures it (``--write-readme``) and checked by a test, never edited by hand. The block's
first marker starts with ``<!-- NAME`` (the rest of that line says which command writes it) and
its last is ``<!-- /NAME -->``.
"""

from __future__ import annotations

from pathlib import Path


def replace_block(text: str, begin: str, end: str, block: str) -> str:
    """``text`` with the block from ``begin``'s tag (its text before the first colon) to ``end``
    replaced by ``block`` (appended when ``text`` has none)."""
    head = begin.split(":")[0]
    if head in text and end in text:
        start = text.index(head)
        stop = text.index(end, start) + len(end)
        return text[:start] + block + text[stop:]
    return text.rstrip("\n") + "\n\n" + block + "\n"


def write_block(path: str | Path, begin: str, end: str, block: str) -> Path:
    """Put ``block`` into the README at ``path`` in place of the previous one (atomically)."""
    from deckpound.models.file_io import atomic_write_text

    path = Path(path)
    text = replace_block(path.read_text(encoding="utf-8"), begin, end, block)
    return atomic_write_text(path, text, field="--write-readme")

"""Text from the user's input as it is shown on a terminal (issue 28, item 5).

A scene name, a path, a record or field name is echoed in the CLI's human-readable lines. Raw,
a control character in it acts on the terminal instead of being read: ESC starts an escape
sequence (colours, cursor moves, a window title), CR returns to the start of the line so that
the rest overwrites what was printed, BEL rings, and the bidirectional controls (U+202A–U+202E,
U+2066–U+2069, U+200E/U+200F) reorder the text that follows (``gnp.exe`` shown as ``exe.png``).
:func:`terminal_text` shows every such character in Python's escape form (``\\x1b``, ``\\r``,
``\\u202e``). The CLI writes every user-given name and path through it, and every message on
stderr (:func:`deckpound.cli.main`). ``scene show`` prints TOML, whose basic strings may hold
such characters raw: :func:`terminal_toml` writes them as TOML escapes, which read back as the
same characters.
"""

from __future__ import annotations

__all__ = ["terminal_text", "terminal_toml"]


def _shown(ch: str) -> str:
    """One character as it is shown: itself if printable, else its Python escape."""
    if ch.isprintable():
        return ch
    return repr(ch)[1:-1]  # '\x1b', '\r', '\u202e', '\U000e0041': the escape between quotes


def terminal_text(text: object, *, keep_newlines: bool = False) -> str:
    """``str(text)`` with every character that is not printable escaped, so that nothing in it
    acts on the terminal.

    Not printable is Python's :meth:`str.isprintable` (the characters :func:`repr` escapes):
    the C0 controls (ESC, CR, BEL, NUL, TAB, LF, ...), DEL and the C1 controls, the format
    characters (the bidirectional controls, zero-width characters, U+FEFF), line and paragraph
    separators, spaces other than U+0020, private-use, surrogate and unassigned code points.
    ``keep_newlines``: LF stays a line break (for text of several lines that deckpound itself
    composed); every other character is escaped as always."""
    text = str(text)
    if keep_newlines:
        return "\n".join(terminal_text(line) for line in text.split("\n"))
    if text.isprintable():
        return text
    return "".join(_shown(ch) for ch in text)


def terminal_toml(text: str) -> str:
    """TOML text written by ``tomli_w`` with every character that is not printable, except the
    line breaks, written as a TOML escape (``\\uXXXX``, ``\\UXXXXXXXX``). Lossless: ``tomli_w``
    writes such characters (TAB, C1 and bidi controls, separators; it escapes the other C0
    controls and DEL itself) only inside basic strings, where the escape stands for the same
    character."""
    if all(line.isprintable() for line in text.split("\n")):
        return text
    return "".join(
        ch
        if ch == "\n" or ch.isprintable()
        else f"\\u{ord(ch):04x}"
        if ord(ch) <= 0xFFFF
        else f"\\U{ord(ch):08x}"
        for ch in text
    )

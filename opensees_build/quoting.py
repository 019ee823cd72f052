"""Quoting of free text for the generated Tcl and Python scripts (issue 16, item 1).

Every string that reaches an exported script passes through one of these functions:

* :func:`tcl_word` — a Tcl word that the parser reads back as exactly ``s``: a bare word when
  ``s`` holds only ``[A-Za-z0-9_.+-]`` (so ordinary commands read as usual), otherwise a
  double-quoted word with ``\\ " $ [ ] { }`` and every non-printable or non-ASCII character
  backslash-escaped (``\\uXXXX``), so neither substitution nor a word or command break can
  happen inside it, and a braced body (``if {...} {...}``, ``proc``) holding the word still
  ends at its own closing brace. Tcl 8.6 has no characters outside the Basic Multilingual
  Plane: such a string is refused (:class:`ValueError`) rather than silently changed.
* :func:`tcl_path_word` — a relative file or folder name as the Tcl word of ``file join $dir
  NAME``: :func:`tcl_word`, with ``./`` put before a name that starts with ``~`` (Tcl 8.6 reads
  ``~x`` as the home folder of user ``x``, and ``file join`` drops everything before it).
* :func:`py_str` — a Python string literal (``ascii()``: ASCII only, quotes escaped).
* :func:`comment_text` — text for a ``#`` comment line in either language: printable ASCII on
  one line; a backslash is doubled (so a line can never end in a Tcl line continuation), braces
  are escaped for Tcl (so a comment cannot unbalance a braced body), anything else becomes
  ``\\uXXXX``. Comments therefore cannot end early or run on into the next line.
* :func:`safe_file_name` — a file name of ``[A-Za-z0-9_.-]`` only.

Python scripts carry scene text only in comments below line 2 (lines 1–2 could hold an encoding
declaration, which changes how the rest of the file is decoded).
"""

from __future__ import annotations

import hashlib
import re

__all__ = ["comment_text", "py_str", "safe_file_name", "tcl_path_word", "tcl_word", "wrap_comment"]

_BARE = re.compile(r"[A-Za-z0-9_.+\-]+")
_FILE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]*")
_TCL_ESC = {
    "\\": "\\\\",
    '"': '\\"',
    "$": "\\$",
    "[": "\\[",
    "]": "\\]",
    # a quoted word can sit inside a braced body (an ``if`` or ``proc`` body): Tcl finds the
    # end of that body by counting braces without regard to quotes, so a bare brace in the
    # word would end the body early and run the rest of the word as commands; an escaped
    # brace is not counted and reads back as the brace
    "{": "\\{",
    "}": "\\}",
    "\n": "\\n",
    "\t": "\\t",
    "\r": "\\r",
}


def _uescape(ch: str) -> str:
    code = ord(ch)
    return f"\\u{code:04x}" if code <= 0xFFFF else f"\\U{code:08x}"


def tcl_word(s: str) -> str:
    """``s`` as one Tcl word whose value is exactly ``s`` (see the module docstring)."""
    s = str(s)
    if _BARE.fullmatch(s):
        return s
    out = []
    for ch in s:
        if ch in _TCL_ESC:
            out.append(_TCL_ESC[ch])
        elif " " <= ch <= "~":
            out.append(ch)
        elif ord(ch) > 0xFFFF:
            raise ValueError(
                f"Tcl 8.6 cannot represent the character {ch!r} (U+{ord(ch):X}, "
                "outside the Basic Multilingual Plane)"
            )
        else:
            out.append(_uescape(ch))
    return '"' + "".join(out) + '"'


def tcl_path_word(name: str) -> str:
    """``name`` (a relative path) as a Tcl word for ``file join $dir NAME`` (see the module
    docstring); ``file join`` removes the ``./`` again, so the joined path is ``$dir/NAME``."""
    name = str(name)
    return tcl_word(f"./{name}" if name.startswith("~") else name)


def py_str(s: str) -> str:
    """``s`` as an ASCII Python string literal."""
    return ascii(str(s))


def comment_text(s: str, lang: str = "py") -> str:
    """``s`` as the text of one comment line in ``lang`` ("tcl" or "py"): printable ASCII,
    no line break, backslashes doubled, (Tcl) braces escaped, other characters ``\\uXXXX``."""
    out = []
    for ch in str(s):
        if ch == "\\":
            out.append("\\\\")
        elif lang == "tcl" and ch in "{}":
            out.append("\\" + ch)
        elif " " <= ch <= "~":
            out.append(ch)
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        else:
            out.append(_uescape(ch))
    return "".join(out)


def wrap_comment(s: str, width: int = 92, limit: int = 4000) -> list[str]:
    """Free text split into lines of at most about ``width`` characters (on spaces), at most
    ``limit`` characters in all (the rest is cut, and the cut said). Not yet escaped."""
    s = str(s)
    cut = len(s) > limit
    s = s[:limit]
    lines: list[str] = []
    for para in s.splitlines() or [""]:
        words = para.split(" ")
        line = ""
        for w in words:
            while len(w) > width:
                if line:
                    lines.append(line)
                    line = ""
                lines.append(w[:width])
                w = w[width:]
            if line and len(line) + 1 + len(w) > width:
                lines.append(line)
                line = w
            else:
                line = f"{line} {w}" if line else w
        lines.append(line)
    if cut:
        lines.append(f"[... cut: {limit} characters shown]")
    return lines


def safe_file_name(name: str) -> str:
    """``name`` if it is a plain file name (``[A-Za-z0-9_.-]``, not starting with ``.`` or
    ``-``); otherwise the plain characters kept, the others replaced by ``_`` and an 8-digit
    hash of the original appended (two different names never collide)."""
    name = str(name)
    if _FILE.fullmatch(name):
        return name
    kept = re.sub(r"[^A-Za-z0-9_.\-]", "_", name).lstrip(".-")[:48] or "file"
    return f"{kept}_{hashlib.sha256(name.encode('utf-8', 'surrogatepass')).hexdigest()[:8]}"

"""The script family of the CLI fuzz corpus (:mod:`tests._fuzz_corpus`): hostile text that
reaches a generated OpenSees script or the terminal (issue 28, item 5).

script   ``export`` (Tcl and Python) to hostile file names — braces that end a braced Tcl body,
         ``[exec ...]``, ``$``, quotes, backslashes, newlines, ``~``, control and bidi
         characters, characters Tcl 8.6 cannot hold — and ``scene validate`` / ``export`` of a
         scene file whose name and description carry the same text

Expected outcomes: every export succeeds (exit 0) except a Tcl export to a name with a character
outside the Basic Multilingual Plane, refused (exit 2, ``--output``); every hostile scene is
valid (exit 0). What the corpus runner checks for every case (one error line, no partial
output) is completed by ``tests/test_script_quoting.py``, which runs this family's scripts in
a logging sandbox (the model's commands and nothing else) and checks that no control character
reaches stdout or stderr raw.
"""

from __future__ import annotations

import tomli_w
from _fuzz_corpus import BENCH_TOML, SHORT, Case

#: file name stems: each would run code, break the script or fool the terminal if written raw
HOSTILE_STEMS = [
    "x} ; exec touch PWNED ; {",  # ran `touch PWNED` before braces were escaped
    "a}b{",  # did not parse
    "}",
    "{",
    "{*}",
    "[exec touch PWNED]",
    "$env(HOME) ${x}",
    '"; exec touch PWNED; set a "',
    "end \\",
    "a\\\nexec touch PWNED",
    "line\nexec touch PWNED",
    "cr\rexec touch PWNED",
    "# comment",
    "; exec touch PWNED ;",
    "~x",
    "~",
    "-rf",
    ".hidden",
    "'''\nimport os; os.system('touch PWNED')\n'''",
    '"""',
    "# -*- coding: utf-7 -*-",
    "\x1b[2J\x1b]0;owned\x07title",
    "\u202egnp.exe",
    "sep \u2028 \u2029 \x85 end",
    "Brücke 橋",
    "emoji 😀",  # outside the Basic Multilingual Plane: Tcl 8.6 cannot open it
    "x" * 180,
]
#: scene names and descriptions (set through a scene file: --set refuses control characters)
HOSTILE_NAMES = [
    "\x1b[2J\x1b]0;owned\x07evil\rname\u202egnp.exe",
    "x} ; exec touch PWNED ; {",
    "a\nexec touch PWNED\n# \\",
    "nul \x00 del \x7f c1 \x9b bidi \u2066\u200e",
    "$x [exec touch PWNED] '''\"\"\" \\",
]


def _scene_file(name: str) -> bytes:
    """The short benchmark's TOML with ``name`` as its name and description."""
    out, top = [], True
    for line in BENCH_TOML.splitlines(keepends=True):
        top &= not line.startswith("[")  # the scene's own keys come before the first table
        if top and line.startswith("name = "):
            line = tomli_w.dumps({"name": name})
        elif top and line.startswith("description = "):
            line = tomli_w.dumps({"description": f"{name}\n{name}"})
        out.append(line)
    return "".join(out).encode("utf-8")


def script_family() -> list[Case]:
    cases = []
    for i, stem in enumerate(HOSTILE_STEMS):
        for fmt in ("tcl", "py"):
            beyond_bmp = any(ord(c) > 0xFFFF for c in stem)
            target = f"{{tmp}}/{stem}.{fmt}"
            cases.append(
                Case(
                    f"script:stem-{i}:{fmt}",
                    "script",
                    ("export", "saiidi-4span", *SHORT, "--format", fmt, "-o", target),
                    target=target,
                    target_kind="file",
                    expect=(2,) if fmt == "tcl" and beyond_bmp else (0,),
                )
            )
    for i, name in enumerate(HOSTILE_NAMES):
        files = (("scene.toml", _scene_file(name)),)
        cases.append(
            Case(
                f"script:name-{i}:validate",
                "script",
                ("scene", "validate", "{tmp}/scene.toml"),
                files=files,
                expect=(0,),
            )
        )
        for fmt in ("tcl", "py"):
            target = f"{{tmp}}/model.{fmt}"
            cases.append(
                Case(
                    f"script:name-{i}:{fmt}",
                    "script",
                    ("export", "{tmp}/scene.toml", "--format", fmt, "-o", target),
                    files=files,
                    target=target,
                    target_kind="file",
                    expect=(0,),
                )
            )
    return cases

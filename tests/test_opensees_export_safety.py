"""No code injection through exports (issue 16, item 1).

Scene text (name, description, notes, seat labels) and the output path reach the exported
scripts. Hostile values — newlines, triple quotes, ``[exec ...]``, ``$``, braces, ``;``,
backslash-newline, an encoding declaration, NUL, form feed, unicode line separators — must leave
the scripts' code unchanged: the Python script parses to the same syntax tree as with plain text,
the Tcl script has the same non-comment text and every comment ends at its own line (checked in
the Tcl interpreter), and running the scripts creates none of the marker files the hostile text
asks for.
"""

from __future__ import annotations

import ast
import dataclasses as dc
import importlib.util
import subprocess
import sys

import pytest
from hypothesis import given
from hypothesis import strategies as st

from deckpound.models.errors import SceneError
from deckpound.models.scene_io import load_scene
from deckpound.models.scene_settings import RunSettings
from deckpound.opensees_build import export
from deckpound.opensees_build.quoting import comment_text, py_str, safe_file_name, tcl_word

pytest.importorskip("openseespy.opensees")
needs_tcl = pytest.mark.skipif(
    importlib.util.find_spec("opensees") is None,
    reason="the Tcl OpenSees interpreter (pip package 'opensees') is "
    "not installed; ./run.sh test installs it",
)


def hostile(marker_dir) -> list[str]:
    """Strings that would run code (each touches a file in marker_dir) if pasted unescaped."""
    m = str(marker_dir)
    return [
        f'x"""\nimport os; os.system("touch {m}/py1")\n"""',
        f"x'''\nopen({m!r} + '/py2', 'w')\n'''",
        f"name\n[exec touch {m}/tcl1]\nexec touch {m}/tcl2",
        f"}} ; exec touch {m}/tcl3 ; {{",
        f"end \\\nexec touch {m}/tcl4",
        "trailing backslash \\",
        f"$env(HOME) [file mkdir {m}/tcl5] ${{x}} \\$ \\[",
        "# -*- coding: utf-7 -*-\n+AAo-import os+AAo-",
        f"nul \x00 ff \x0c cr \r vt \x0b sep \u2028 \u2029 \x85 end\rexec touch {m}/tcl6",
        "unicode: 橋梁 é ü ß Ω 😀 \ufeff",
        f'"; exec touch {m}/tcl7; set a "',
    ]


def scene_with(texts: list[str]):
    sc = load_scene("saiidi-4span").replace(run=RunSettings(duration=0.05))
    notes = dict(sc.notes)
    for key, text in zip(sorted(notes), texts):
        notes[key] = text
    seats = tuple(dc.replace(s, name=t) for s, t in zip(sc.seats, texts[-2:]))
    return sc.replace(name=texts[0], description="\n".join(texts), notes=notes, seats=seats)


def benign_texts(n: int) -> list[str]:
    return [f"plain text {k}" for k in range(n)]


# -- the quoting functions -----------------------------------------------------------------------


@needs_tcl
def test_tcl_word_reads_back_exactly_in_tcl(tmp_path):
    """Every string survives as one Tcl word, unchanged, with no substitution run."""
    words = hostile(tmp_path)[:-2] + ["", "plain", "a b", "{", "}", "\\", "é", "\u2028", "\t;#"]
    words = [w for w in words if all(ord(c) <= 0xFFFF for c in w)]
    lines = ["set fh [open [lindex $argv 0] w]"]
    lines += [
        f"puts $fh h:[binary encode hex [encoding convertto utf-8 {tcl_word(w)}]]" for w in words
    ]
    lines.append("close $fh")
    out = tmp_path / "words.txt"
    script = tmp_path / "words.tcl"
    script.write_text("\n".join(lines) + "\n", encoding="ascii")
    cp = subprocess.run(
        [sys.executable, "-m", "opensees", "-"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        input=f"set argv [list {tcl_word(str(out))}]\nsource {tcl_word(str(script))}\n",
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    got = [bytes.fromhex(h[2:]).decode("utf-8") for h in out.read_text().splitlines()]
    assert got == words, [(a, b) for a, b in zip(got, words) if a != b]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["words.tcl", "words.txt"]


def test_tcl_word_refuses_characters_tcl_cannot_hold():
    with pytest.raises(ValueError, match="Basic Multilingual Plane"):
        tcl_word("a😀b")


@given(st.text())
def test_comment_text_is_one_printable_line(s):
    for lang in ("tcl", "py"):
        c = comment_text(s, lang)
        assert all(" " <= ch <= "~" for ch in c)
        # backslashes come in escape pairs: a line never ends in a Tcl continuation
        stripped = c.replace("\\\\", "")
        assert not stripped.endswith("\\")
        if lang == "tcl":
            assert "{" not in stripped.replace("\\{", "") and "}" not in stripped.replace("\\}", "")


@given(st.text())
def test_python_literals_read_back(s):
    assert ast.literal_eval(py_str(s)) == s


def test_safe_file_name():
    assert safe_file_name("bent1_x_disp") == "bent1_x_disp"
    a, b = safe_file_name("../etc/passwd"), safe_file_name("..\\etc\\passwd")
    assert a != b and "/" not in a and not a.startswith(".")
    assert safe_file_name("a b") != safe_file_name("a_b")


# -- whole scripts -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def markers(tmp_path_factory):
    return tmp_path_factory.mktemp("markers")


@pytest.fixture(scope="module")
def scripts(tmp_path_factory, markers):
    texts = hostile(markers)
    out = {}
    for kind, tx in (("hostile", texts), ("benign", benign_texts(len(texts)))):
        folder = tmp_path_factory.mktemp(kind)
        out[kind] = {
            fmt: export.export_script(scene_with(tx), fmt, folder / f"model.{fmt}")
            for fmt in ("py", "tcl")
        }
    return out


def _code_lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if not line.lstrip().startswith("#")]


def test_hostile_text_leaves_the_python_code_unchanged(scripts):
    hostile_py = scripts["hostile"]["py"].read_text(encoding="ascii")
    benign_py = scripts["benign"]["py"].read_text(encoding="ascii")
    assert "橋" not in hostile_py and "import os;" in hostile_py  # it is there, as a comment
    # comments are not in the tree: equal trees = the hostile text changed no code
    assert ast.dump(ast.parse(hostile_py)) == ast.dump(ast.parse(benign_py))
    top = [type(n).__name__ for n in ast.parse(hostile_py).body]
    assert top.count("Import") + top.count("ImportFrom") == 7 and top[-1] == "If"
    assert hostile_py.splitlines()[:2] == benign_py.splitlines()[:2]  # no encoding declaration


def test_hostile_text_leaves_the_tcl_code_unchanged(scripts):
    hostile_tcl = scripts["hostile"]["tcl"].read_text(encoding="ascii")
    benign_tcl = scripts["benign"]["tcl"].read_text(encoding="ascii")
    assert _code_lines(hostile_tcl) == _code_lines(benign_tcl)
    assert "exec touch" in hostile_tcl  # present, as comment text


@needs_tcl
def test_tcl_comments_end_at_their_line(tmp_path, markers):
    """Each hostile comment, at top level and inside a braced proc body, is read by Tcl as
    one comment: the command after it runs, nothing else does."""
    lines = ["set n 0"]
    for t in hostile(markers):
        lines += [f"# {comment_text(t, 'tcl')}", "incr n"]
        lines += [
            "proc p {} {",
            f"    # {comment_text(t, 'tcl')}",
            "    return ok",
            "}",
            "if {[p] eq {ok}} { incr n }",
        ]
    lines.append('puts "count $n"')
    script = tmp_path / "comments.tcl"
    script.write_text("\n".join(lines) + "\n", encoding="ascii")
    cp = subprocess.run(
        [sys.executable, "-m", "opensees", "-"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        input=f"source {tcl_word(str(script))}\n",
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    assert f"count {2 * len(hostile(markers))}" in cp.stdout
    assert list(markers.iterdir()) == []


def test_hostile_python_script_runs_the_model_only(scripts, markers, tmp_path):
    cp = subprocess.run(
        [sys.executable, str(scripts["hostile"]["py"]), "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    assert list(markers.iterdir()) == []
    assert (tmp_path / "deck_x_abs.out").read_text().count("\n") == 11


@needs_tcl
def test_hostile_tcl_script_runs_the_model_only(scripts, markers, tmp_path):
    outs = {}
    for kind in ("hostile", "benign"):
        out = tmp_path / kind
        cp = subprocess.run(
            [sys.executable, "-m", "opensees", "-"],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
            input=f"set outDir {tcl_word(str(out))}\n"
            f"source {tcl_word(str(scripts[kind]['tcl']))}\n",
        )
        assert cp.returncode == 0, cp.stderr[-2000:]
        outs[kind] = {p.name: p.read_bytes() for p in out.iterdir()}
    assert list(markers.iterdir()) == []
    assert outs["hostile"] == outs["benign"] and len(outs["hostile"]) == 28


# -- hostile output paths ------------------------------------------------------------------------

#: a file name that runs code if pasted unescaped (the scripts run with the marker folder as
#: their working directory, so a relative marker is enough)
HOSTILE_STEM = "m $x [exec touch o1] \"q\" {b} ; é ''' \\ [open o2 w]"


def test_hostile_output_path_python(tmp_path, markers):
    sc = load_scene("saiidi-4span").replace(run=RunSettings(duration=0.02))
    script = export.export_script(sc, "py", tmp_path / "dir é" / f"{HOSTILE_STEM}.py")
    cp = subprocess.run(
        [sys.executable, str(script)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        cwd=markers,
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    assert (script.parent / f"{script.stem}_results" / "deck_x_abs.out").exists()
    assert list(markers.iterdir()) == []


#: file names reported to run code or break the Tcl script: unbalanced braces end the braced
#: ``if`` body that holds the output folder's name
BRACE_STEMS = ["x} ; exec touch PWNED ; {", "a}b{"]


@needs_tcl
@pytest.mark.parametrize("stem", [HOSTILE_STEM, *BRACE_STEMS])
def test_hostile_output_path_tcl(tmp_path, markers, stem):
    sc = load_scene("saiidi-4span").replace(run=RunSettings(duration=0.02))
    script = export.export_script(sc, "tcl", tmp_path / "dir é" / f"{stem}.tcl")
    cp = subprocess.run(
        [sys.executable, "-m", "opensees", "-"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        cwd=markers,
        input=f"source {tcl_word(str(script))}\n",
    )
    assert cp.returncode == 0, (cp.stdout + cp.stderr)[-2000:]
    assert (script.parent / f"{script.stem}_results" / "deck_x_abs.out").exists()
    assert list(markers.iterdir()) == []


def test_tcl_export_refuses_a_path_tcl_cannot_open(tmp_path):
    sc = load_scene("saiidi-4span").replace(run=RunSettings(duration=0.02))
    with pytest.raises(SceneError, match="--output"):
        export.export_script(sc, "tcl", tmp_path / "a😀.tcl")
    assert list(tmp_path.iterdir()) == []

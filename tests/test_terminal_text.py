"""Hostile names never reach the terminal raw (issue 28, item 5).

A scene name, a file name or a path with ESC (escape sequences), CR (overwrites the line), BEL
or the bidirectional controls (reorder what follows) is echoed by the CLI with those characters
escaped (``\\x1b``, ``\\r``, ``\\u202e``), on stdout and stderr alike.
"""

from __future__ import annotations

import tomli_w
from hypothesis import given
from hypothesis import strategies as st

from deckpound._terminal import terminal_text
from deckpound.cli import main
from deckpound.models.scene_io import load_scene, scene_from_toml, scene_to_toml

SHORT = ["--set", "excitation.duration=2"]
#: an erase-screen and a window-title sequence, BEL, CR, RLO, C1 CSI, LRI, LRM, DEL, NUL
HOSTILE = "\x1b[2J\x1b]0;owned\x07evil\rname\u202egnp.exe\x9b\u2066\u200e\x7f\x00end"
RAW = set("\x1b\x07\r\u202e\x9b\u2066\u200e\x7f\x00")


def assert_nothing_raw(*texts: str) -> None:
    for text in texts:
        found = sorted({f"U+{ord(c):04X}" for c in text if c in RAW or not _shown_ok(c)})
        assert not found, (found, text)


def _shown_ok(c: str) -> bool:
    return c in "\n\t" or c.isprintable()


def test_terminal_text_escapes_controls_and_keeps_text():
    shown = terminal_text(HOSTILE)
    assert shown == (
        "\\x1b[2J\\x1b]0;owned\\x07evil\\rname\\u202egnp.exe\\x9b\\u2066\\u200e\\x7f\\x00end"
    )
    assert terminal_text("Brücke 橋 saiidi-4span / ü") == "Brücke 橋 saiidi-4span / ü"
    assert terminal_text("a\nb\tc") == "a\\nb\\tc"
    assert terminal_text("a\nb\x1b", keep_newlines=True) == "a\nb\\x1b"


@given(st.text())
def test_terminal_text_is_printable(s):
    assert terminal_text(s).isprintable()
    assert "\n" not in terminal_text(s)


def cli(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def hostile_scene_file(folder, name: str = HOSTILE):
    text = scene_to_toml(load_scene("saiidi-4span"))
    line = next(x for x in text.splitlines() if x.startswith("name = "))
    path = folder / "hostile.toml"
    path.write_text(text.replace(line, tomli_w.dumps({"name": name}).strip()), encoding="utf-8")
    assert load_scene(str(path)).name == name
    return path


def test_scene_validate_escapes_the_scene_name(tmp_path, capsys):
    path = hostile_scene_file(tmp_path)
    code, out, err = cli(capsys, "scene", "validate", str(path), *SHORT)
    assert code == 0, err
    assert_nothing_raw(out, err)
    assert out.startswith("\\x1b[2J\\x1b]0;owned\\x07evil\\rname\\u202egnp.exe"), out


def test_errors_escape_paths_and_names(tmp_path, capsys):
    path = hostile_scene_file(tmp_path)
    # a bad value in the hostile scene, a missing file with a hostile name, a file that is
    # not TOML: exit 2, one line, nothing raw
    for argv in (
        ["scene", "validate", str(path), "--set", "deck.mass=-1"],
        ["scene", "validate", str(tmp_path / f"{HOSTILE.replace(chr(0), '')}.toml")],
        ["scene", "validate", str(path), "--set", f"name={HOSTILE.replace(chr(0), '')}"],
    ):
        code, out, err = cli(capsys, *argv)
        assert code == 2 and len(err.splitlines()) == 1, err
        assert_nothing_raw(out, err)


def test_export_escapes_the_file_name_it_names(tmp_path, capsys):
    stem = "a\x1b]0;owned\x07\u202egnp"
    code, out, err = cli(
        capsys, "export", "saiidi-4span", "--format", "py", "-o", str(tmp_path / f"{stem}.py")
    )
    assert code == 0, err
    assert (tmp_path / f"{stem}.py").is_file()  # the file has the name asked for
    assert_nothing_raw(out, err)
    assert "a\\x1b]0;owned\\x07\\u202egnp.py" in out, out


def test_scene_show_writes_controls_as_toml_escapes(tmp_path, capsys):
    """``scene show`` prints the same scene (it reads back equal) with nothing raw: the
    characters TOML allows raw in a string (TAB, C1, bidi, a tag character) are escaped."""
    name = HOSTILE.replace("\x00", "") + "\ttab \x85 \u2028 \U000e0041"
    path = hostile_scene_file(tmp_path, name)
    code, out, err = cli(capsys, "scene", "show", str(path))
    assert code == 0, err
    assert_nothing_raw(out, err)
    assert scene_from_toml(out) == load_scene(str(path))
    assert "\\u202e" in out and "\\U000e0041" in out

"""The command-line contract (issue: bad input).

Good input: ``--version``, ``--help`` of every (sub)command, ``scene list|show|validate|schema``
and ``excitation plot`` exit 0. Bad input: exit status 2, exactly one stderr line
``deckpound: error: <field>: <what is wrong, the value, what is allowed>``, no traceback and
nothing written to the ``-o`` file or folder. The CLI runs in-process through ``main(argv)``
(fast); ``tests/test_cli_process.py`` checks the real process's exit status.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
from pathlib import Path

import pytest
from _cli_cases import BAD_SETS

from deckpound import __version__
from deckpound.cli import build_parser, main
from deckpound.compare.engines import ENGINES
from deckpound.models.scene_io import builtin_scene_names, load_scene, scene_from_toml

SHORT = ["--set", "excitation.duration=2"]


def cli(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def assert_refused(code: int, err: str, field: str, *texts: str) -> None:
    """Exit 2 and exactly one stderr line naming ``field`` (and containing ``texts``)."""
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"deckpound: error: {field}"), lines[0]
    for text in texts:
        assert text in lines[0], lines[0]
    assert "Traceback" not in err


# -- good input ----------------------------------------------------------------------------


def test_version(capsys):
    code, out, err = cli(capsys, "--version")
    assert code == 0 and out.strip() == f"deckpound {__version__}" and not err


def _command_paths(parser: argparse.ArgumentParser, prefix=()) -> list[tuple[str, ...]]:
    paths = [prefix]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                paths += _command_paths(sub, prefix + (name,))
    return paths


COMMANDS = _command_paths(build_parser())


def test_every_command_is_listed():
    names = {p[0] for p in COMMANDS if p}
    assert {"scene", "excitation", "run", "export", "modes", "verify"} <= names
    assert ("scene", "validate") in COMMANDS and ("excitation", "plot") in COMMANDS


@pytest.mark.parametrize("path", COMMANDS, ids=lambda p: " ".join(p) or "deckpound")
def test_help_of_every_command(capsys, path):
    code, out, err = cli(capsys, *path, "--help")
    assert code == 0 and not err
    assert out.startswith("usage: deckpound") and "--help" in out


def test_scene_list(capsys):
    code, out, err = cli(capsys, "scene", "list")
    assert code == 0 and not err
    names = [line.split("\t")[0] for line in out.splitlines()]
    assert names == builtin_scene_names() and "saiidi-4span" in names


def test_scene_show_round_trips_through_validate(capsys, tmp_path):
    code, out, err = cli(capsys, "scene", "show", "saiidi-4span")
    assert code == 0 and not err
    assert scene_from_toml(out) == load_scene("saiidi-4span")
    path = tmp_path / "bench.toml"
    path.write_text(out)
    code, out2, err = cli(capsys, "scene", "validate", str(path))
    assert code == 0 and not err
    assert out2.startswith("saiidi-4span: valid; 3 bents")
    code, out3, _ = cli(capsys, "scene", "show", str(path))
    assert code == 0 and out3 == out  # show of the shown file: the same text


def test_scene_show_applies_overrides(capsys):
    code, out, _ = cli(
        capsys,
        "scene",
        "show",
        "saiidi-4span",
        "--set",
        "contact.law=hertz",
        "--set",
        "seats[1].gap=0.02",
    )
    s = scene_from_toml(out)
    assert code == 0 and s.contact.law == "hertz" and s.seats[1].gap == 0.02


def test_scene_schema_is_json(capsys):
    code, out, err = cli(capsys, "scene", "schema")
    assert code == 0 and not err
    schema = json.loads(out)
    assert schema["type"] == "object" and schema["additionalProperties"] is False
    assert {"deck", "bents", "seats", "contact", "excitation"} <= set(schema["properties"])
    assert schema["properties"]["contact"]["properties"]["restitution"]["maximum"] == 1.0


def test_excitation_plot_writes_png(capsys, tmp_path):
    out_png = tmp_path / "sub" / "exc.png"
    code, out, err = cli(capsys, "excitation", "plot", "saiidi-4span", *SHORT, "-o", str(out_png))
    assert code == 0 and not err and f"wrote {out_png}" in out
    data = out_png.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and len(data) > 5000


# -- bad input: one line naming the field, exit 2, nothing written ------------------------


def _args(case, tmp_path: Path) -> list[str]:
    return case(tmp_path) if callable(case) else list(case)


@pytest.mark.parametrize(
    "case,field,texts", [(c[1], c[2], c[3:]) for c in BAD_SETS], ids=[c[0] for c in BAD_SETS]
)
def test_bad_input_validate(capsys, tmp_path, case, field, texts):
    code, out, err = cli(
        capsys, "scene", "validate", "saiidi-4span", *SHORT, *_args(case, tmp_path)
    )
    assert_refused(code, err, field, *texts)
    assert not out


PLOT_CASES = [c for c in BAD_SETS if c[0] != "damping-mode-too-high"]  # plot needs no modes


@pytest.mark.parametrize(
    "case,field,texts", [(c[1], c[2], c[3:]) for c in PLOT_CASES], ids=[c[0] for c in PLOT_CASES]
)
def test_bad_input_plot_writes_nothing(capsys, tmp_path, case, field, texts):
    args = _args(case, tmp_path)
    out_dir = tmp_path / "out"
    code, _out, err = cli(
        capsys, "excitation", "plot", "saiidi-4span", *SHORT, *args, "-o", str(out_dir / "exc.png")
    )
    assert_refused(code, err, field, *texts)
    assert not out_dir.exists()


def _engine_available(name: str) -> bool:
    module = ENGINES[name].split(":")[0]
    try:
        return importlib.util.find_spec(module) is not None
    except ModuleNotFoundError:
        return False


RUN_ENGINES = [
    pytest.param(
        e, marks=pytest.mark.skipif(not _engine_available(e), reason=f"engine {e} not built yet")
    )
    for e in ("compliance", "opensees")
]


@pytest.mark.parametrize("engine", RUN_ENGINES)
@pytest.mark.parametrize(
    "case,field,texts", [(c[1], c[2], c[3:]) for c in BAD_SETS], ids=[c[0] for c in BAD_SETS]
)
def test_bad_input_run_writes_nothing(capsys, tmp_path, case, field, texts, engine):
    args = _args(case, tmp_path)
    out_dir = tmp_path / "out"
    code, _out, err = cli(
        capsys, "run", "saiidi-4span", *SHORT, *args, "--engine", engine, "-o", str(out_dir)
    )
    assert_refused(code, err, field, *texts)
    assert not out_dir.exists()


def _bench_text() -> str:
    from deckpound.models.scene_io import builtin_scene_text

    return builtin_scene_text("saiidi-4span")


BAD_FILES = [
    (
        "misspelt-key",
        lambda t: t.replace("[deck]\nlength", "[deck]\nlenght"),
        "deck.lenght",
        "did you mean 'length'",
    ),
    (
        "unknown-table",
        lambda t: t + "\n[contacts]\nlaw = 'linear'\n",
        "contacts",
        "did you mean 'contact'",
    ),
    (
        "unknown-key-in-array-table",
        lambda t: t.replace('name = "bent2"', 'name = "bent2"\nheight = 2'),
        "bents[1].height",
        "unknown key",
    ),
    (
        "negative-gap",
        lambda t: t.replace("gap = 0.0127", "gap = -0.0127", 1),
        "seats[0].gap",
        ">= 0.0 m",
    ),
    ("nan-mass", lambda t: t.replace("mass = 140.5", "mass = nan"), "deck.mass", "finite"),
    (
        "string-for-number",
        lambda t: t.replace("mass = 140.5", 'mass = "heavy"'),
        "deck.mass",
        "must be a number in t, got 'heavy'",
    ),
    (
        "missing-required",
        lambda t: t.replace("mass = 140.5\n", ""),
        "deck.mass",
        "required but missing",
    ),
    (
        "duplicate-key",
        lambda t: t.replace("mass = 140.5", "mass = 140.5\nmass = 1.0"),
        "/",
        "not valid TOML",
    ),
    (
        "one-seat",
        lambda t: t.replace('[[seats]]\nname = "seat2"', '[seat2]\nname = "seat2"'),
        "seat2",
        "unknown key",
    ),
]


@pytest.mark.parametrize(
    "mutate,field,texts", [(c[1], c[2], c[3:]) for c in BAD_FILES], ids=[c[0] for c in BAD_FILES]
)
def test_bad_scene_file(capsys, tmp_path, mutate, field, texts):
    text = mutate(_bench_text())
    assert text != _bench_text()
    path = tmp_path / "scene.toml"
    path.write_text(text)
    out_png = tmp_path / "exc.png"
    for argv in (
        ["scene", "validate", str(path)],
        ["excitation", "plot", str(path), "-o", str(out_png)],
    ):
        code, _out, err = cli(capsys, *argv)
        assert_refused(code, err, field, *texts)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]


def test_unreadable_scene_file(capsys, tmp_path):
    path = tmp_path / "scene.toml"
    path.write_bytes(b"\xff\xfe\x00junk")
    code, _, err = cli(capsys, "scene", "validate", str(path))
    assert_refused(code, err, "scene", "cannot read")
    code, _, err = cli(capsys, "scene", "validate", str(tmp_path / "absent.toml"))
    assert_refused(code, err, "scene", "does not exist")


@pytest.mark.parametrize(
    "command", [["scene", "validate"], ["scene", "show"], ["excitation", "plot"], ["run"]]
)
def test_unknown_scene_lists_valid_ones(capsys, tmp_path, command):
    extra = {
        "excitation": ["-o", str(tmp_path / "o.png")],
        "run": ["--engine", "compliance", "-o", str(tmp_path / "o")],
    }.get(command[0], [])
    code, _out, err = cli(capsys, *command, "saiidi-5span", *extra)
    assert_refused(
        code,
        err,
        "scene",
        "unknown scene 'saiidi-5span'",
        "built-in scenes: " + ", ".join(builtin_scene_names()),
    )
    assert list(tmp_path.iterdir()) == []


def test_unknown_engine_lists_valid_ones(capsys, tmp_path):
    out_dir = tmp_path / "out"
    code, _out, err = cli(capsys, "run", "saiidi-4span", "--engine", "foo", "-o", str(out_dir))
    assert_refused(
        code, err, "engine", "unknown engine 'foo'", "valid engines: " + ", ".join(ENGINES)
    )
    assert not out_dir.exists()


@pytest.mark.parametrize(
    "argv,text",
    [
        (["scene", "frobnicate"], "invalid choice: 'frobnicate'"),
        (["scene", "validate"], "required: SCENE"),
        (["run", "saiidi-4span", "-o", "x"], "required: --engine"),
        (["excitation", "plot", "saiidi-4span"], "required: -o/--output"),
        (["scene", "validate", "saiidi-4span", "--colour"], "unrecognized arguments: --colour"),
    ],
)
def test_usage_errors_are_one_line(capsys, argv, text):
    code, _out, err = cli(capsys, *argv)
    assert code == 2 and len(err.splitlines()) == 1 and text in err
    assert err.startswith("deckpound: error: deckpound")


@pytest.mark.parametrize("name", ["exc.txt", "folder.png"])
def test_plot_output_name_refused(capsys, tmp_path, name):
    (tmp_path / "folder.png").mkdir()
    target = tmp_path / name
    code, _, err = cli(capsys, "excitation", "plot", "saiidi-4span", *SHORT, "-o", str(target))
    assert_refused(code, err, "--output")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder.png"]
    assert list((tmp_path / "folder.png").iterdir()) == []


def test_plot_output_under_a_file_refused(capsys, tmp_path):
    (tmp_path / "afile").write_text("x")
    code, _, err = cli(
        capsys,
        "excitation",
        "plot",
        "saiidi-4span",
        *SHORT,
        "-o",
        str(tmp_path / "afile" / "exc.png"),
    )
    assert_refused(code, err, "--output", "cannot write")

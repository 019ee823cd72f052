"""Exported scripts run the model's commands and nothing else, whatever the text (issue 28.5).

Arbitrary Unicode (braces, brackets, ``$``, quotes, backslashes, newlines, NUL, ``~``, bidi and
line-separator characters) is put into every string that reaches an exported script: the scene
name, description, notes and seat labels, the output file stem (so the data and results folder
names), and the support-record and channel names. Each exported script is then run in a
sandbox that records what it calls:

* Tcl: the script is ``source``-d by plain ``tclsh`` in which every OpenSees command is a proc
  that logs its words, and ``exec``, ``open``, ``source``, ``file`` (but ``join``, ``dirname``
  and ``normalize``), ``exit``, ``puts`` and an ``unknown`` handler log instead of acting. The
  OpenSees calls must be exactly deckpound's command log (:func:`engine.command_log`, strings
  read back unchanged, record paths in the data folder), then the recorders, ``record``,
  ``analyze`` per step and ``wipe``; the only other calls are ``file mkdir`` of the results
  folder and the status line.
* Python: the syntax tree must equal that of a plain-text export once string constants are
  blanked (no new code), and ``build()`` and ``add_recorders()``, run against a fake
  ``openseespy.opensees``, must call exactly the command log and the recorders.

The corpus's script family (:mod:`tests._fuzz_scripts`: the two reported file names among
others) goes through the CLI itself: each case must end with the exit status the corpus states,
print no control character raw, and the scripts it writes must pass the same sandbox.
"""

from __future__ import annotations

import ast
import contextlib
import dataclasses as dc
import io
import os
import shutil
import subprocess
import sys
import tempfile
import types
from pathlib import Path

import pytest
from _fuzz_run import materialise
from _fuzz_scripts import script_family
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from deckpound.cli import main
from deckpound.models.errors import SceneError
from deckpound.models.result import scene_hash
from deckpound.models.scene_io import load_scene
from deckpound.models.scene_settings import RunSettings
from deckpound.opensees_build import engine, export
from deckpound.opensees_build.export_py import UNCHECKED_SEATS
from deckpound.opensees_build.ops import ArrayArg, OpsSession
from deckpound.opensees_build.recorders import PRECISION

pytest.importorskip("openseespy.opensees")
TCLSH = shutil.which("tclsh")

#: characters that have a meaning in Tcl or Python source, or on a terminal
SPECIAL = list("{}[]$\"'\\;#~ \t\n\r\x00\x0b\x0c\x1c\x1e\x85\u2028\u2029\u202e\ufeff") + [
    "\\\n",
    "}}",
    "{{",
    "\U0001f600",
]
TEXT = st.lists(
    st.one_of(st.sampled_from(SPECIAL), st.characters(exclude_categories=["Cs"])), max_size=24
).map("".join)
#: a file name stem: no "/" or NUL (no file name holds them)
STEM = TEXT.map(lambda s: s.replace("/", "_").replace("\x00", "_")).filter(
    lambda s: (
        Path(f"{s}.tcl").stem == s
        and Path(f"{s}.py").stem == s
        and len(f"{s}_results".encode()) <= 200
    )
)

#: the reported file names: the first ran `exec touch PWNED`, the second did not parse
BRACE_STEMS = ["x} ; exec touch PWNED ; {", "a}b{"]

#: Tcl commands a script must not reach; the sandbox logs them instead (file and puts are
#: wrapped: see HARNESS)
DANGEROUS = (
    "exec open source socket cd load exit interp glob close chan fconfigure rename eval "
    "uplevel subst after package namespace trace vwait update pwd"
)

HARNESS = r"""
rename rename ::realRename
::realRename file ::realFile
::realRename puts ::realPuts
::realRename source ::realSource
::realRename exit ::realExit
set ::calls {}
proc ::logCall {kind args} { lappend ::calls [linsert $args 0 $kind] }
foreach name $env(DP_OPS) {
    proc $name args [format {::logCall ops %s {*}$args; return 0} [list $name]]
}
proc file {sub args} {
    ::logCall tcl file $sub {*}$args
    if {$sub in {join dirname normalize}} { return [::realFile $sub {*}$args] }
    return {}
}
proc puts args { ::logCall tcl puts {*}$args }
proc unknown args { ::logCall unknown {*}$args; return {} }
foreach name $env(DP_DANGEROUS) {
    if {[info commands $name] ne {}} { ::realRename $name {} }
    proc $name args [format {::logCall danger %s {*}$args; return {}} [list $name]]
}
set failed [catch {::realSource $env(DP_SCRIPT)} msg]
foreach call $::calls {
    set words {}
    foreach w $call { lappend words [binary encode hex [encoding convertto utf-8 $w]] }
    ::realPuts [join $words " "]
}
if {$failed} { ::realPuts stderr "script error: $msg"; ::realExit 2 }
"""


def base_scene():
    return load_scene("saiidi-4span").replace(run=RunSettings(duration=0.02))


def hostile_scene(text: str):
    """The benchmark with ``text`` in its name, description, every note and the seat labels."""
    sc = base_scene()
    notes = {k: f"{text}{k}{text}" for k in sc.notes}
    seats = tuple(dc.replace(s, name=f"{text}{j}") for j, s in enumerate(sc.seats))
    return sc.replace(name=text, description=f"{text}\n{text}", notes=notes, seats=seats)


class _HostileRecordNames:
    """While active, every support record (ArrayArg) and its timeSeries / groundMotion tag
    names carry ``text``: the record names reach the scripts as file names and comments."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.patch = pytest.MonkeyPatch()

    def __enter__(self):
        call, tag = OpsSession.call, OpsSession.tag
        text = self.text

        def renamed_call(ops, name, *args):
            args = tuple(
                ArrayArg(f"{text}|{a.name}", a.values) if isinstance(a, ArrayArg) else a
                for a in args
            )
            return call(ops, name, *args)

        def renamed_tag(ops, kind, name):
            if kind in ("timeSeries", "groundMotion"):
                name = f"{text}|{name}"
            return tag(ops, kind, name)

        self.patch.setattr(OpsSession, "call", renamed_call)
        self.patch.setattr(OpsSession, "tag", renamed_tag)
        return self

    def __exit__(self, *exc) -> None:
        self.patch.undo()


def model_calls(sc, parts, data_dir: str) -> list[list]:
    """deckpound's command log as (name, arguments...): strings unchanged, numbers as numbers,
    a support record as ``-filePath`` and its file in ``data_dir``."""
    calls = []
    for c in engine.command_log(sc):
        if c.name == "#":
            continue
        words = [c.name]
        for a in c.args:
            if isinstance(a, ArrayArg):
                words += ["-filePath", os.path.join(data_dir, parts.file_of[a.name])]
            else:
                words.append(a)
        calls.append(words)
    return calls


def recorder_calls(parts, out_dir: str) -> list[list]:
    """The standard recorders, writing into ``out_dir``."""
    return [
        ["recorder", r.kind, "-file", os.path.join(out_dir, r.file), "-time", "-precision"]
        + [PRECISION, "-dT", parts.rec_dt, *r.args()]
        for r in parts.recorders
    ]


def step_calls(parts) -> list[list]:
    """``record`` at t = 0, one ``analyze`` per step (none fails in the sandbox), ``wipe``."""
    return [["record"]] + [["analyze", 1, parts.plan["dt"]]] * parts.plan["n_steps"] + [["wipe"]]


def _same(got, want) -> bool:
    """A call made by a script equals the expected one (numbers compared as numbers: Tcl
    passes text, and -dT is computed by the script)."""
    if len(got) != len(want):
        return False
    for g, w in zip(got, want):
        if isinstance(w, str):
            if g != w:
                return False
        elif isinstance(w, float) and isinstance(g, str) and "." not in g and "e" not in g:
            return False  # a float written as an integer would change its meaning in Tcl
        elif abs(float(g) - float(w)) > 1e-15 * max(1.0, abs(float(w))):
            return False
    return True


def assert_calls(got: list[list], want: list[list]) -> None:
    assert len(got) == len(want), (len(got), len(want))
    for k, (g, w) in enumerate(zip(got, want)):
        assert _same(g, w), f"call {k}: {g} != {w}"


# -- Tcl ---------------------------------------------------------------------------------------


#: the status line of a sandboxed run: no step fails, and no gap closes (queries answer nothing)
STATUS_LINE = "success, failures: 0, rescued by sub-steps: 0, gap_closures: 0"
#: OpenSees commands that only read the model's state (logged, answered with nothing)
QUERIES = frozenset({"nodeDisp", "nodeVel", "eleResponse", "testIter", "getTime"})


def is_sandbox_seat_line(line: str, plan: dict) -> bool:
    """``line`` is the seat-margin line of a sandboxed run: nothing moves (the queries answer
    0), so each checked corner keeps its whole support length, its largest gap at t = 0; with
    no support length, the engine's words for it."""
    lengths = {f"c{c + 1}": n for c, n in enumerate(plan["support_lengths"]) if n is not None}
    if not lengths:
        return line == f"seat_margin_min: {UNCHECKED_SEATS}"
    head = "seat_margin_min (margin m, time s): "
    if not line.startswith(head):
        return False
    cells = [cell.split(" ") for cell in line.removeprefix(head).split(", ")]
    got = {cell[0]: [float(x) for x in cell[1:]] for cell in cells}
    return got == {c: [n, 0.0] for c, n in lengths.items()}


def run_tcl_sandbox(script: Path, ops_names: set[str]) -> tuple[list[list], list[list]]:
    """(OpenSees calls, other calls) of ``script`` sourced in the logging sandbox."""
    env = dict(os.environ)
    env.update(
        LC_ALL="C.UTF-8",
        DP_SCRIPT=str(script),
        DP_OPS=" ".join(sorted(ops_names)),
        DP_DANGEROUS=DANGEROUS,
    )
    cp = subprocess.run(
        [TCLSH],
        input=HARNESS,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        env=env,
        cwd=script.parent,
    )
    assert cp.returncode == 0, cp.stderr[-2000:]
    calls = [
        [bytes.fromhex(w).decode("utf-8") for w in line.split(" ")]
        for line in cp.stdout.splitlines()
    ]
    return [c[1:] for c in calls if c[0] == "ops"], [c for c in calls if c[0] != "ops"]


def verify_tcl_script(sc, script: Path) -> None:
    """``script`` (the Tcl export of ``sc``) calls exactly deckpound's command log, the
    recorders and the step loop's commands, and of the rest only its path helpers, ``file
    mkdir`` of its results folder, the status line and the seat-margin line."""
    parts, _ = export.export_parts(sc, "tcl", script.stem)
    here = os.path.realpath(script.parent)
    want = model_calls(sc, parts, os.path.join(here, parts.data_dir))
    want += recorder_calls(parts, os.path.join(here, parts.out_dir)) + step_calls(parts)
    names = {c[0] for c in want} | {"wipeAnalysis"} | QUERIES
    names |= {c[0] for c in parts.plan["analysis"]}
    ops_calls, other = run_tcl_sandbox(script, names)
    # the step loop's read-only state queries (the gap-closure count) change nothing
    assert_calls([c for c in ops_calls if c[0] not in QUERIES], want)
    for c in other:
        assert c[0] == "tcl", c
        if c[1:3] == ["file", "mkdir"]:
            assert c[3:] == [os.path.join(here, parts.out_dir)], c
        elif c[1] == "file":
            assert c[2] in ("join", "dirname", "normalize"), c
        else:
            assert c[1] == "puts", c
    printed = [c[2:] for c in other if c[1] == "puts"]
    assert len(printed) == 2 and printed[0] == [STATUS_LINE], printed
    assert len(printed[1]) == 1 and is_sandbox_seat_line(printed[1][0], parts.plan), printed


def beyond_bmp(path: Path) -> bool:
    """Tcl 8.6 cannot hold a character outside the Basic Multilingual Plane."""
    return any(ord(ch) > 0xFFFF for ch in str(path.resolve()))


# -- Python ------------------------------------------------------------------------------------


def _blank_strings(tree: ast.AST) -> str:
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            node.value = ""
    return ast.dump(tree)


class _FakeOpenSees(types.ModuleType):
    """``openseespy.opensees`` that records every call and returns 0."""

    def __init__(self) -> None:
        super().__init__("openseespy.opensees")
        self.calls: list[list] = []

    def __getattr__(self, name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        return lambda *args: self.calls.append([name, *args]) or 0


def run_python_build(script: Path, out: Path) -> list[list]:
    """The calls of ``build()`` and ``add_recorders(out)`` of ``script`` (fake OpenSees)."""
    fake = _FakeOpenSees()
    package = types.ModuleType("openseespy")
    package.opensees = fake
    namespace = {"__name__": "exported_script", "__file__": str(script)}
    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(sys.modules, "openseespy", package)
        mp.setitem(sys.modules, "openseespy.opensees", fake)
        exec(compile(script.read_text(encoding="ascii"), str(script), "exec"), namespace)
        namespace["build"]()
        namespace["add_recorders"](str(out))
    return fake.calls


def plain_text(sc):
    """``sc`` with plain text wherever the tests put hostile text."""
    notes = dict.fromkeys(sc.notes, "plain note")
    seats = tuple(dc.replace(s, name=f"seat{j + 1}") for j, s in enumerate(sc.seats))
    return sc.replace(name="plain", description="plain", notes=notes, seats=seats)


_PLAIN_TREES: dict[str, str] = {}


def plain_python_tree(sc) -> str:
    """The blanked syntax tree of the Python export of ``plain_text(sc)`` (record names as
    deckpound gives them: call this outside :class:`_HostileRecordNames`)."""
    plain = plain_text(sc)
    key = scene_hash(plain)
    if key not in _PLAIN_TREES:
        with tempfile.TemporaryDirectory() as tmp:
            script = export.export_script(plain, "py", Path(tmp) / "model.py")
            _PLAIN_TREES[key] = _blank_strings(ast.parse(script.read_text(encoding="ascii")))
    return _PLAIN_TREES[key]


def verify_python_script(sc, script: Path, plain_tree: str) -> None:
    """``script`` (the Python export of ``sc``) is ASCII, has the code of a plain-text export
    (``plain_tree``) and its ``build()`` and ``add_recorders()`` call exactly deckpound's
    command log and the recorders."""
    text = script.read_text(encoding="ascii")  # ASCII only: no encoding trick, no bidi text
    assert _blank_strings(ast.parse(text)) == plain_tree  # no code added or removed
    parts, _ = export.export_parts(sc, "py", script.stem)
    here = os.path.dirname(os.path.abspath(script))
    out = str(script.parent / "py-out")
    want = model_calls(sc, parts, os.path.join(here, parts.data_dir)) + recorder_calls(parts, out)
    assert_calls(run_python_build(script, out), want)


# -- the property ------------------------------------------------------------------------------


@pytest.mark.skipif(TCLSH is None, reason="tclsh (Tcl 8.6) is not installed")
@settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(text=TEXT, stem=STEM, record=TEXT)
@example(text="plain", stem=BRACE_STEMS[0], record="r")
@example(text="plain", stem=BRACE_STEMS[1], record="r")
@example(text="}{ [exec touch PWNED] $x \\", stem="~x", record="} ; exec touch PWNED ; {")
def test_exported_scripts_run_the_model_and_nothing_else(text, stem, record):
    sc = hostile_scene(text)
    plain_tree = plain_python_tree(sc)
    with tempfile.TemporaryDirectory() as tmp, _HostileRecordNames(record):
        folder = Path(tmp) / "out"
        folder.mkdir()
        tcl = folder / f"{stem}.tcl"
        if beyond_bmp(tcl):
            with pytest.raises(SceneError, match="--output"):
                export.export_script(sc, "tcl", tcl)
            assert list(folder.iterdir()) == []
        else:
            verify_tcl_script(sc, export.export_script(sc, "tcl", tcl))
        verify_python_script(sc, export.export_script(sc, "py", folder / f"{stem}.py"), plain_tree)
        assert "PWNED" not in {p.name for p in Path(tmp).rglob("*")}


# -- the corpus's script family ----------------------------------------------------------------


def _printable_lines(text: str) -> bool:
    return all(line.isprintable() for line in text.split("\n"))


#: the family's Python exports to hostile file names run with -m slow only: the property test
#: above covers them by default, the Tcl ones and the hostile scenes run here
FAMILY = [
    pytest.param(c, marks=pytest.mark.slow)
    if c.id.startswith("script:stem-") and c.id.endswith(":py")
    else c
    for c in script_family()
]


@pytest.mark.skipif(TCLSH is None, reason="tclsh (Tcl 8.6) is not installed")
@pytest.mark.parametrize("case", FAMILY, ids=lambda c: c.id)
def test_corpus_script_family(case, tmp_path):
    """Each hostile export or scene of the corpus ends as the corpus expects, prints no
    control character raw, and the scripts it writes run the model and nothing else."""
    argv = materialise(case, tmp_path / "case", None)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    assert code in case.expect, err.getvalue()
    assert _printable_lines(out.getvalue()) and _printable_lines(err.getvalue()), (out, err)
    if code == 0 and argv[0] == "export":
        sets = [argv[k + 1] for k, a in enumerate(argv) if a == "--set"]
        sc = load_scene(argv[1], sets)
        script = Path(argv[-1])
        if script.suffix == ".tcl":
            verify_tcl_script(sc, script)
        else:
            verify_python_script(sc, script, plain_python_tree(sc))
    assert "PWNED" not in {p.name for p in tmp_path.rglob("*")}

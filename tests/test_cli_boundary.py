"""The CLI's one error boundary and the crashes of issue 16, each as a regression test.

Exit statuses (cli module docstring): 0 success, 1 engine failure, 2 bad input, 3 I/O or
resource failure, 4 internal error, 130 interrupted; always at most one stderr line and never
a traceback (unless DECKPOUND_DEBUG=1).
"""

from __future__ import annotations

import errno
import io
import json
import os
import subprocess
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest

import deckpound._cli_scene as cli_scene
import deckpound.models.file_io as dio
from deckpound.cli import EXIT_CODES_HELP, main
from deckpound.compare import engines
from deckpound.models.file_io import INCOMPLETE

TINY = ["--set", "excitation.duration=0.3", "--set", "run.output_dt=0.01"]


def cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue()


def one_line(err: str, start: str = "deckpound: error: ") -> str:
    """The one error line of stderr (deckpound's warnings before it are allowed)."""
    lines = [ln for ln in err.splitlines() if not ln.startswith("deckpound: warning:")]
    assert len(lines) == 1 and lines[0].startswith(start), err
    assert "Traceback" not in err
    return lines[0]


# -- the boundary ---------------------------------------------------------------------------


def test_help_documents_the_exit_statuses():
    code, out, _ = cli("--help")
    assert code == 0 and EXIT_CODES_HELP in out
    for status in ("0 ", "1 ", "2 ", "3 ", "4 ", "130"):
        assert f"\n  {status}" in out


@pytest.mark.parametrize(
    "exc,code,text",
    [
        (
            OSError(errno.EROFS, "Read-only file system", "/x/out"),
            3,
            "I/O error on '/x/out': Read-only file system",
        ),
        (
            OSError(errno.ENOSPC, "No space left on device", "/x/a.csv"),
            3,
            "I/O error on '/x/a.csv': no space left on the device",
        ),
        (MemoryError(), 3, "out of memory"),
        (RecursionError(), 3, "nested too deeply"),
        (ZeroDivisionError("boom"), 4, "internal error: ZeroDivisionError: boom (this is a bug"),
        (KeyboardInterrupt(), 130, "deckpound: interrupted"),
    ],
)
def test_every_exception_becomes_one_line_and_a_status(monkeypatch, exc, code, text):
    def raising(args):
        raise exc

    monkeypatch.setattr(cli_scene, "_list", raising)
    got, _out, err = cli("scene", "list")
    assert got == code
    assert text in one_line(err, "deckpound: ")


def test_debug_env_shows_the_traceback_of_a_bug(monkeypatch):
    def raising(args):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(cli_scene, "_list", raising)
    monkeypatch.setenv("DECKPOUND_DEBUG", "1")
    with pytest.raises(ZeroDivisionError):
        main(["scene", "list"])


def test_library_chatter_on_stderr_is_held_back_unless_debugging(monkeypatch):
    """OpenSees prints its solver messages on stderr; a failure must still be one line."""
    from deckpound.models.errors import EngineFailure

    def chatty(args):
        sys.stderr.write(
            "WARNING: CTestNormDispIncr::test() - failed to converge \nafter: 1 iterations\n"
        )
        sys.stderr.write("OpenSees > analyze failed, ")
        sys.stderr.write("returned: -3 error flag\n")
        print("\rcases [####] 1/1", file=sys.stderr)  # a progress bar passes
        raise EngineFailure("step 1 (t = 0.0005 s) did not converge")

    monkeypatch.setattr(cli_scene, "_list", chatty)
    code, _, err = cli("scene", "list")
    assert code == 1
    failure = "deckpound: engine failure: step 1 (t = 0.0005 s) did not converge"
    assert err.split("\n")[:-1] == ["\rcases [####] 1/1", failure]
    monkeypatch.setenv("DECKPOUND_DEBUG", "1")
    code, _, err = cli("scene", "list")
    assert code == 1 and "analyze failed, returned: -3" in err and err.count("\n") == 5


def test_stdout_full_is_an_io_error(monkeypatch):
    class Full(io.StringIO):
        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

    err = io.StringIO()
    with redirect_stdout(Full()), redirect_stderr(err):
        code = main(["scene", "show", "saiidi-4span"])
    assert code == 3
    assert one_line(err.getvalue()) == (
        "deckpound: error: cannot write the output to stdout: no space left on the device"
    )


# -- the crashes of the issue -------------------------------------------------------------


@pytest.mark.parametrize(
    "setting,field,text",
    [
        ("opensees.max_iterations=9223372036854775808", "opensees.max_iterations", "<= 10000"),
        ("compliance.max_iterations=1e308", "compliance.max_iterations", "got 1e+308"),
        ("nonsmooth.max_iterations=" + "9" * 400, "nonsmooth.max_iterations", "400 digits"),
        ("excitation.seed=1e20", "excitation.seed", "<= 9007199254740992"),
        ("run.output_dt=1e25", "run.output_dt", "single row t = 0"),
        ("run.output_dt=100", "run.output_dt", "single row t = 0"),
        ("run.duration=1e-4", "run.duration", "opensees.dt = 0.0005 s"),
        ("opensees.dt=30", "opensees.dt", "opensees.dt = 30 s"),
    ],
)
@pytest.mark.parametrize("command", ["validate", "run"])
def test_scenes_that_validated_and_then_crashed_are_refused(
    tmp_path, setting, field, text, command
):
    argv = (
        ["scene", "validate", "saiidi-4span", "--set", setting]
        if command == "validate"
        else [
            "run",
            "saiidi-4span",
            "--set",
            setting,
            "--engine",
            "opensees",
            "-o",
            str(tmp_path / "out"),
        ]
    )
    code, _out, err = cli(*argv)
    assert code == 2
    line = one_line(err)
    assert line.startswith(f"deckpound: error: {field}: ") and text in line
    assert not (tmp_path / "out").exists()


def test_a_record_shorter_than_one_step_names_both(tmp_path):
    """A CSV record of 0.3 ms (16 samples) against the 0.5 ms OpenSees step."""
    from deckpound.models.plan import support_channels
    from deckpound.models.scene_io import load_scene

    t = np.arange(16) * 2e-5
    chans = support_channels(load_scene("saiidi-4span"))
    rows = [",".join(["t"] + [f"{c}_disp" for c in chans])]
    rows += [",".join([repr(float(x))] + ["0.0"] * len(chans)) for x in t]
    (tmp_path / "r.csv").write_text("\n".join(rows) + "\n")
    code, _, err = cli(
        "run",
        "saiidi-4span",
        "--set",
        "excitation.kind=csv",
        "--set",
        f"excitation.file={json.dumps(str(tmp_path / 'r.csv'))}",
        "--set",
        "excitation.scaling=none",
        "--engine",
        "opensees",
        "-o",
        str(tmp_path / "out"),
    )
    assert code == 2
    line = one_line(err)
    assert "opensees.dt: " in line and "record length 0.0003 s" in line and "0.0005 s" in line


@pytest.mark.parametrize("where", ["file", "set"])
def test_deeply_nested_toml_is_refused(tmp_path, where):
    deep = "[" * 100_000 + "]" * 100_000
    if where == "file":
        (tmp_path / "s.toml").write_text(f'name = "x"\nv = {deep}\n')
        code, _, err = cli("scene", "validate", str(tmp_path / "s.toml"))
    else:
        code, _, err = cli("scene", "validate", "saiidi-4span", "--set", f"deck.mass={deep}")
    assert code == 2 and "too deeply" in one_line(err)


@pytest.mark.parametrize(
    "address,code,text",
    [
        ("foo", 2, "must be a Dask scheduler address"),
        ("tcp://h:99999", 2, "[1, 65535]"),
        ("tcp://127.0.0.1:1", 3, "cannot reach the Dask scheduler at tcp://127.0.0.1:1"),
    ],
)
def test_bad_scheduler_address(tmp_path, monkeypatch, address, code, text):
    from deckpound.compare import cases

    monkeypatch.setattr(cases, "CONNECT_TIMEOUT", 1.0)
    got, _, err = cli(
        "compare",
        "saiidi-4span",
        *TINY,
        "--engines",
        "nonsmooth",
        "--no-progress",
        "--scheduler",
        address,
        "-o",
        str(tmp_path / "out"),
    )
    assert got == code and text in one_line(err)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("value", ["nan", "inf", "-1", "0"])
def test_stress_timeout_must_be_a_positive_number(tmp_path, value):
    code, _, err = cli("stress", "--quick", "--timeout", value, "-o", str(tmp_path / "out"))
    assert code == 2 and "--timeout: must be a finite number of seconds > 0" in one_line(err)
    assert not (tmp_path / "out").exists()


@pytest.fixture(scope="module")
def tiny_result(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("res") / "res"
    assert main(["run", "saiidi-4span", *TINY, "--engine", "nonsmooth", "-o", str(out)]) == 0
    return out


@pytest.mark.parametrize(
    "damage,text",
    [
        (("nonsmooth.json", b'{"x":'), "nonsmooth.json is not valid JSON"),
        (("nonsmooth.json", b'{"engine": "nonsmooth"}'), "carries no scene"),
        (("nonsmooth.json", b'{"scene": {"deck": 1}}'), "its scene is invalid"),
        (("nonsmooth.csv", b"t,deck_x\n0,1\n"), "lacks the column 'deck_x_rel'"),
        (("nonsmooth.csv", b"\x00\xff" * 50), "is not a table of numbers"),
    ],
)
def test_export_vtk_refuses_damaged_results(tmp_path, tiny_result, damage, text):
    import shutil

    res = tmp_path / "res"
    shutil.copytree(tiny_result, res)
    (res / damage[0]).write_bytes(damage[1])
    code, _, err = cli("export-vtk", str(res), "-o", str(tmp_path / "vtk"))
    assert code == 2 and text in one_line(err)
    assert not (tmp_path / "vtk").exists()


HOSTILE_NAMES = ["$\\frac{$", "$x^$", "$", "a\nb", "nul\x00in", "x" * 3000]


@pytest.mark.parametrize("name", HOSTILE_NAMES, ids=range(len(HOSTILE_NAMES)))
def test_every_figure_renders_any_scene_name(tmp_path, tiny_result, name):
    """A name with TeX broke every figure after all engines ran."""
    from deckpound.compare.report import figures
    from deckpound.compare.report.plotting import plot_excitation
    from deckpound.models.excitation import support_motion
    from deckpound.models.result import Result
    from deckpound.models.scene_io import load_scene

    scene = load_scene("saiidi-4span", ["excitation.duration=0.3"]).replace(name=name)
    r = Result.read(tiny_result, "nonsmooth")
    results = {"nonsmooth": r, f"nonsmooth {name}": r}
    table = __import__("pandas").DataFrame(
        {"engine": ["nonsmooth"] * 2, "run": [1, 2], "pga": [0.1, 0.2], "peak_theta": [1e-3, 2e-3]}
    )
    written = []
    written += plot_excitation(scene, support_motion(scene), tmp_path / "exc.png")
    written += figures.histories(results, scene, tmp_path / "h.png", title=name)
    written += figures.contact_forces(results, scene, tmp_path / "c.png", title=name)
    written += figures.peak_vs_pga(table, scene, tmp_path / "p.png")
    written += figures.plan_snapshot(results, scene, tmp_path / "s.png")
    for p in written:
        assert p.stat().st_size > 1000


# -- outputs: links, read-only, partial ---------------------------------------------------


@pytest.mark.parametrize(
    "command",
    [
        ["run", "saiidi-4span", *TINY, "--engine", "nonsmooth", "-o", "{link}"],
        ["export", "saiidi-4span", *TINY, "--format", "py", "-o", "{filelink}"],
        ["excitation", "plot", "saiidi-4span", *TINY, "-o", "{filelink}.png"],
        ["paper", "--quick", *TINY, "-o", "{link}"],
        ["export-vtk", "{res}", "-o", "{link}"],
        ["compare", "saiidi-4span", *TINY, "--engines", "nonsmooth", "-o", "{link}"],
    ],
)
def test_outputs_never_go_through_symbolic_links(tmp_path, tiny_result, command):
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real")
    (tmp_path / "victim.png").write_text("victim")
    (tmp_path / "victim").write_text("victim")
    (tmp_path / "filelink").symlink_to(tmp_path / "victim")
    (tmp_path / "filelink.png").symlink_to(tmp_path / "victim.png")
    argv = [
        a.format(link=tmp_path / "link", filelink=tmp_path / "filelink", res=tiny_result)
        for a in command
    ]
    code, _, err = cli(*argv)
    assert code == 2 and "symbolic link" in one_line(err)
    assert not list((tmp_path / "real").iterdir())
    assert (tmp_path / "victim").read_text() == "victim"
    assert (tmp_path / "victim.png").read_text() == "victim"


def test_unwritable_output_is_an_io_error(tmp_path):
    for target in ("/proc/deckpound-test/out", "/sys/deckpound-test/out"):
        code, _, err = cli("run", "saiidi-4span", *TINY, "--engine", "nonsmooth", "-o", target)
        assert code == 3 and target.rsplit("/", 1)[0] in one_line(err)


def test_export_on_a_full_disk_writes_no_file(tmp_path, monkeypatch):
    real, calls = dio._write_fd, []

    def fills_up(fd, data, **kw):
        calls.append(1)
        if len(calls) == 5:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(fd, data, **kw)

    monkeypatch.setattr(dio, "_write_fd", fills_up)
    code, _, err = cli(
        "export", "saiidi-4span", *TINY, "--format", "tcl", "-o", str(tmp_path / "exp" / "m.tcl")
    )
    assert code == 3 and "no space left" in one_line(err)
    assert not (tmp_path / "exp").exists()  # the folder it created for the export is gone


def test_run_failing_mid_write_leaves_no_half_result(tmp_path, monkeypatch):
    real, calls = dio._write_fd, []

    def second_fails(fd, data, **kw):
        calls.append(1)
        if len(calls) == 3:  # the marker, the CSV, then the JSON fails
            raise OSError(errno.ENOSPC, "No space left on device")
        real(fd, data, **kw)

    monkeypatch.setattr(dio, "_write_fd", second_fails)
    code, _, err = cli(
        "run", "saiidi-4span", *TINY, "--engine", "nonsmooth", "-o", str(tmp_path / "out")
    )
    assert code == 3 and one_line(err)
    assert not (tmp_path / "out").exists()  # nothing of value written: no folder at all


def test_study_failing_is_marked_incomplete_then_resumes_from_the_cache(tmp_path, monkeypatch):
    """A study killed while drawing its figure keeps its cases; the re-run resumes."""
    from deckpound.compare.studies import sensitivity as studies

    def dies(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "s" / "f.png"))

    monkeypatch.setattr(studies, "study_figure", dies)  # where the study calls it
    argv = [
        "study",
        "friction",
        "saiidi-4span",
        "--quick",
        *TINY,
        "--workers",
        "1",
        "--no-progress",
        "-o",
        str(tmp_path / "s"),
    ]
    code, _, err = cli(*argv)
    assert code == 3 and "no space left" in one_line(err)
    marker = (tmp_path / "s" / INCOMPLETE).read_text()
    assert "failed" in marker and "study friction: OSError" in marker
    assert len(list((tmp_path / "s" / "cache").iterdir())) == 4  # every case kept
    monkeypatch.undo()
    from deckpound.compare import cases

    def no_recompute(*a, **k):
        raise RuntimeError("a cached case was recomputed")

    monkeypatch.setattr(cases, "run_case", no_recompute)
    code, _, err = cli(*argv)
    assert code == 0, err
    assert not (tmp_path / "s" / INCOMPLETE).exists() and (tmp_path / "s" / "friction.png").exists()


@pytest.mark.slow
def test_paper_failing_is_marked_incomplete_then_resumes(tmp_path, monkeypatch):
    """A failed paper keeps its cache and says so; the re-run resumes and unmarks the folder."""
    from deckpound.compare.report import sections as report_sections

    def dies(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "p" / "x"))

    monkeypatch.setattr(report_sections, "write_report", dies)
    argv = [
        "paper",
        "--quick",
        "--studies",
        "friction",
        *TINY,
        "--workers",
        "1",
        "--no-progress",
        "-o",
        str(tmp_path / "p"),
    ]
    code, _, err = cli(*argv)
    assert code == 3 and one_line(err)
    marker = (tmp_path / "p" / INCOMPLETE).read_text()
    assert "failed" in marker and "paper: OSError" in marker
    assert len(list((tmp_path / "p" / "cache").iterdir())) > 10
    monkeypatch.undo()
    code, _out, err = cli(*argv)
    assert code == 0, err
    assert not (tmp_path / "p" / INCOMPLETE).exists() and (tmp_path / "p" / "report.html").exists()


def _process(args, cwd):
    return subprocess.Popen(
        [sys.executable, "-m", "deckpound", *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _two_at_once(args, cwd, timeout):
    """Start the same command twice on one output folder: the folder is locked, so each ends
    in success or (if they overlapped) is refused naming the other's PID; never a crash."""
    procs = [_process(args, cwd) for _ in range(2)]
    errs = [p.communicate(timeout=timeout)[1] for p in procs]
    for p, other, err in zip(procs, procs[::-1], errs):
        assert p.returncode in (0, 2) and "Traceback" not in err, err
        if p.returncode == 2:
            assert "is in use by 'deckpound " in one_line(err) and f"PID {other.pid}," in err
    assert 0 in [p.returncode for p in procs]


def test_two_compares_on_one_folder_do_not_crash(tmp_path):
    args = ["compare", "saiidi-4span", *TINY, "--engines", "compliance,nonsmooth"]
    _two_at_once([*args, "--workers", "1", "--no-progress", "-o", "out"], tmp_path, 600)
    assert not (tmp_path / "out" / INCOMPLETE).exists()
    assert (tmp_path / "out" / "metrics.csv").is_file()


@pytest.mark.slow
def test_two_papers_on_one_folder_do_not_crash(tmp_path):
    _two_at_once(["paper", "--quick", *TINY, "--no-progress", "-o", "rep"], tmp_path, 1800)
    assert not (tmp_path / "rep" / INCOMPLETE).exists()
    assert (tmp_path / "rep" / "report.html").is_file()
    assert not [p for p in (tmp_path / "rep").rglob("*") if dio.is_temporary(p.name)]
    assert (tmp_path / "rep" / "report.html").is_file()
    assert not [p for p in (tmp_path / "rep").rglob("*") if dio.is_temporary(p.name)]


def test_engine_memory_error_is_an_io_error_and_writes_nothing(tmp_path, monkeypatch):
    def oom(*a, **k):
        raise MemoryError

    monkeypatch.setattr(engines, "run_engine", oom)
    code, _, err = cli(
        "run", "saiidi-4span", *TINY, "--engine", "nonsmooth", "-o", str(tmp_path / "out")
    )
    assert code == 3 and "out of memory" in one_line(err)
    assert not (tmp_path / "out").exists()
    assert os.listdir(tmp_path) == []

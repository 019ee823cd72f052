"""The command-line contract in a real ``python -m deckpound`` process: exit status 2 and one
error line for bad input, ``--version``; ``deckpound verify clone`` (issue 4); closed stdout
and stderr, and libraries that cannot be loaded (issue 28)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from deckpound import __version__

PROGRESS_LINE = re.compile(r"^deckpound [^:]+: (stopped at )?\d+/\d+ done")


def _process(tmp_path: Path, *argv: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "deckpound", *argv],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_process_bad_value_exit_status_2(tmp_path):
    out_png = tmp_path / "exc.png"
    p = _process(
        tmp_path,
        "excitation",
        "plot",
        "saiidi-4span",
        "--set",
        "contact.restitution=1.3",
        "-o",
        str(out_png),
    )
    assert p.returncode == 2, p.stderr
    assert p.stderr.splitlines() == [
        "deckpound: error: contact.restitution: must be <= 1.0, got 1.3"
    ]
    assert "Traceback" not in p.stderr + p.stdout and not out_png.exists()


def test_process_unknown_engine_and_version(tmp_path):
    p = _process(tmp_path, "run", "saiidi-4span", "--engine", "foo", "-o", "out")
    assert p.returncode == 2 and len(p.stderr.splitlines()) == 1
    assert "valid engines: opensees, compliance, nonsmooth" in p.stderr
    assert "Traceback" not in p.stderr and not (tmp_path / "out").exists()
    p = _process(tmp_path, "--version")
    assert p.returncode == 0 and p.stdout.strip() == f"deckpound {__version__}"


def test_verify_clone_cli_reports_agreement_and_speed(capsys):
    """`deckpound verify clone` prints the largest deviation and both speeds (issue 4)."""
    from deckpound.cli import main as cli_main

    assert cli_main(["verify", "clone", "saiidi-4span", "--set", "excitation.duration=1.0"]) == 0
    out = capsys.readouterr().out
    line = next(ln for ln in out.splitlines() if ln.startswith("largest deviation"))
    # the 1e-9 physics criterion is tests/test_clone_vs_opensees.py; this short, pounding-heavy
    # record amplifies OpenSees's accumulated-time interpolation of the records to ~4e-8
    assert float(line.split(":")[1].split()[0]) < 1e-6
    assert "us/step" in out


# -- closed standard streams and libraries that cannot be loaded (issue 28) -----------------


def _closed(tmp_path: Path, redirect: str, *argv: str) -> subprocess.CompletedProcess:
    """``python -m deckpound ARGV`` with a standard stream closed by the shell (``>&-``,
    ``2>&-``), as a user's script or a cron job may start it."""
    return subprocess.run(
        ["sh", "-c", f'exec "$0" "$@" {redirect}', sys.executable, "-m", "deckpound", *argv],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_closed_stdout_is_an_io_failure_in_one_line(tmp_path):
    """`deckpound scene list >&-` ended in 'internal error' and a traceback, exit 1."""
    p = _closed(tmp_path, ">&-", "scene", "list")
    assert p.returncode == 3, p.stderr
    assert p.stderr.splitlines() == [
        "deckpound: error: cannot write the output to stdout: it is closed (give a file or "
        "/dev/null instead)"
    ]
    # bad input stays bad input, whatever stdout is
    p = _closed(tmp_path, ">&-", "scene", "validate", "nosuch.toml")
    assert p.returncode == 2 and len(p.stderr.splitlines()) == 1, p.stderr


def test_closed_stderr_changes_no_exit_status(tmp_path):
    """`deckpound scene validate nosuch.toml 2>&-` exited 1 instead of 2."""
    for argv, code in ((["scene", "validate", "nosuch.toml"], 2), (["scene", "list"], 0)):
        assert _process(tmp_path, *argv).returncode == code
        p = _closed(tmp_path, "2>&-", *argv)
        assert p.returncode == code and p.stderr == "", p.stderr
    p = _closed(tmp_path, ">&- 2>&-", "scene", "list")
    assert p.returncode == 3 and p.stderr == ""


def _fake_package(root: Path, dotted: str, body: str) -> None:
    """A package ``dotted`` under ``root`` whose innermost ``__init__`` is ``body``."""
    parts = dotted.split(".")
    root.joinpath(*parts).mkdir(parents=True)
    for i in range(1, len(parts)):
        root.joinpath(*parts[:i], "__init__.py").touch()
    root.joinpath(*parts, "__init__.py").write_text(body)


# openseespy's package turns every failure of its binary into this RuntimeError (bare except)
OPENSEESPY_FAILING = """
try:
    raise {error}
except:  # noqa: E722
    raise RuntimeError("Failed to import openseespy on Linux.")
"""
LIBRARY_FAILURES = {  # case: (package, __init__ body, command, words the line must hold)
    "openseespy-memory": (
        "openseespy.opensees",
        OPENSEESPY_FAILING.format(
            error='ImportError("opensees.so: failed to map segment from shared object")'
        ),
        ["run", "saiidi-4span", "--engine", "opensees", "-o", "out"],
        ("not enough memory to load the library 'openseespy'", "ulimit -v"),
    ),
    "openseespy-oom": (
        "openseespy.opensees",
        OPENSEESPY_FAILING.format(error="MemoryError()"),
        ["run", "saiidi-4span", "--engine", "opensees", "-o", "out"],
        ("not enough memory to load the library 'openseespy'", "OpenSees engine"),
    ),
    "openseespy-broken": (
        "openseespy.opensees",
        OPENSEESPY_FAILING.format(error='ImportError("libgfortran.so.5: cannot open shared")'),
        ["run", "saiidi-4span", "--engine", "opensees", "-o", "out"],
        ("'openseespy' (needed for the OpenSees engine) cannot be loaded", "libgfortran"),
    ),
    "matplotlib": (
        "matplotlib",
        'raise ImportError("libstdc++.so.6: cannot open", name="matplotlib._c_internal_utils")',
        ["excitation", "plot", "saiidi-4span", "-o", "out.png"],
        ("'matplotlib' (needed for figures) cannot be loaded", "pip install"),
    ),
    "dask": (
        "dask",
        "",  # an installation without dask.distributed
        ["compare", "saiidi-4span", "--scheduler", "tcp://127.0.0.1:1", "-o", "out"],
        ("'dask' (needed for --scheduler) cannot be loaded", "dask[distributed]"),
    ),
}


@pytest.mark.parametrize("case", list(LIBRARY_FAILURES))
def test_a_library_that_cannot_be_loaded_is_a_resource_failure(tmp_path, case):
    """Under `ulimit -v 409600` the OpenSees engine exited 4 ('internal error: Failed to
    import openseespy'): a library that cannot be loaded — no memory to map it, missing,
    broken — is exit status 3 with one line naming it and what to do; nothing is written."""
    package, body, argv, words = LIBRARY_FAILURES[case]
    _fake_package(tmp_path / "site", package, body)
    env = {**os.environ, "PYTHONPATH": str(tmp_path / "site")}
    p = subprocess.run(
        [sys.executable, "-m", "deckpound", *argv, "--set", "excitation.duration=0.3"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert p.returncode == 3, p.stderr
    # progress lines off a terminal (compare.progress: 'deckpound X: [stopped at ]k/n done') aside
    lines = [x for x in p.stderr.splitlines() if not PROGRESS_LINE.match(x)]
    assert len(lines) == 1 and lines[0].startswith("deckpound: error: "), p.stderr
    assert all(w in lines[0] for w in words), lines[0]
    assert sorted(x.name for x in tmp_path.iterdir()) == ["site"]


#: run in a child: the modules a run loads before the OpenSees engine, then an address-space
#: limit just above what is mapped, then the CLI (the issue's `ulimit -v 409600`, which left
#: the real openseespy about 80 MiB: MPI_Init ended the process with status 15 and raw MPI text)
_TIGHT_LIMIT = """
import resource, sys
import deckpound.cli, deckpound.compare.engines, deckpound.models.excitation, scipy.linalg
import deckpound.analytic.compliance.engine  # noqa: F401  (numba, llvmlite)

with open("/proc/self/status") as f:
    mapped = next(int(x.split()[1]) for x in f if x.startswith("VmSize:")) * 1024
limit = mapped + 80 * 2**20
resource.setrlimit(resource.RLIMIT_AS, (limit, resource.getrlimit(resource.RLIMIT_AS)[1]))
sys.exit(deckpound.cli.main(sys.argv[1:]))
"""


def test_a_tight_address_space_limit_is_refused_before_openseespy_loads(tmp_path):
    p = subprocess.run(
        [sys.executable, "-c", _TIGHT_LIMIT, "run", "saiidi-4span", "--engine", "opensees"]
        + ["--set", "excitation.duration=0.3", "-o", str(tmp_path / "out")],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 3, p.stderr
    lines = [x for x in p.stderr.splitlines() if not PROGRESS_LINE.match(x)]
    assert len(lines) == 1 and lines[0].startswith("deckpound: error: "), p.stderr
    assert "ulimit -v" in lines[0] and "MiB of address space" in lines[0], lines[0]
    assert not (tmp_path / "out").exists()

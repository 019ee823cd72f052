"""The command-line contract in a real ``python -m deckpound`` process: exit status 2 and one
error line for bad input, ``--version``; and ``deckpound verify clone`` (issue 4)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from deckpound import __version__


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

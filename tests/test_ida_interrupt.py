"""Ctrl-C during ``deckpound ida`` (issue 30, item 4): every worker stops, one line says what
was kept, the folder is marked incomplete, and the same command resumes with only the missing
cases."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import pytest
from _process_helpers import cached_rows, running, start_in_own_group, wait_for_rows
from _record_helpers import quake, write_at2

from deckpound.models.file_io import is_temporary

PAIRS = 12
LEVELS = "0.1:3.0:0.1"  # 30 levels: 360 cases of 30 s records, minutes of work
CASES = PAIRS * 30


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc needed")
def test_ctrl_c_stops_an_ida_cleanly_and_it_resumes(tmp_path):
    suite = tmp_path / "suite"
    suite.mkdir()
    for i in range(PAIRS):
        write_at2(suite / f"RSN{200 + i}_TEST_ST{i}000.AT2", quake(n=3000, seed=7 * i, f=1.0 + i))
        write_at2(suite / f"RSN{200 + i}_TEST_ST{i}090.AT2", quake(n=3000, seed=7 * i + 1))
    argv = [sys.executable, "-m", "deckpound", "ida", "saiidi-4span", "--records", str(suite)]
    argv += ["--im", "pga", "--levels", LEVELS, "--engines", "compliance"]
    argv += ["--workers", "2", "--no-progress", "-o", "out"]
    proc = start_in_own_group(argv, tmp_path)  # as a terminal runs it
    rows = tmp_path / "out" / "cache" / "rows"
    workers = wait_for_rows(proc, rows)
    assert proc.poll() is None and len(workers) >= 2, "the sweep ended before the interrupt"
    assert not (tmp_path / "out" / "ida.json").exists()  # interrupted inside the sweep
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err + out, err
    assert lines[0].startswith("deckpound: interrupted: ")
    assert "run the same command again to resume" in lines[0]
    assert not running(workers)  # every worker is gone
    assert (tmp_path / "out" / "INCOMPLETE").is_file()
    # the rows written whole: each a line of the row log, appended in one write
    cached = cached_rows(rows)
    assert cached >= 3
    done = subprocess.run(argv, cwd=tmp_path, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    report = json.loads((tmp_path / "out" / "ida.json").read_text())
    assert report["from_cache"] == cached and report["computed"] == CASES - cached
    assert not (tmp_path / "out" / "INCOMPLETE").exists()
    assert not [p.name for p in rows.rglob("*") if is_temporary(p.name)]  # none left behind

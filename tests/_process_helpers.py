"""Processes seen through Linux's /proc: the children of a process and whether one still runs
(the interrupt and worker-lifetime tests)."""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

from deckpound.compare.row_log import LOG_NAME, RowLog


def children(pid: int) -> list[int]:
    """PIDs of the direct children of ``pid`` (empty when it has none or is gone)."""
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as fh:
            return [int(p) for p in fh.read().split()]
    except OSError:
        return []


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie or a dead process does not)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] not in ("Z", "X")
    except FileNotFoundError:
        return False


def running(pids: list[int], timeout: float = 10.0) -> list[int]:
    """Those of ``pids`` still running after up to ``timeout`` s (polled: a loaded machine
    takes its time to reap a killed worker or a process left orphaned)."""
    deadline = time.monotonic() + timeout
    while True:
        left = [p for p in pids if alive(p)]
        if not left or time.monotonic() >= deadline:
            return left
        time.sleep(0.1)


def start_in_own_group(argv: list[str], cwd) -> subprocess.Popen:
    """Start a command in a process group of its own, as a terminal runs one: a Ctrl-C sent to
    the group (``os.killpg``) reaches it and every worker it started."""
    return subprocess.Popen(
        argv,
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def wait_for_rows(
    proc: subprocess.Popen, rows, at_least: int = 3, timeout: float = 300
) -> list[int]:
    """Wait until a sweep has cached ``at_least`` rows (lines of the row logs below ``rows``)
    or ended; the PIDs of its workers at that moment."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        if rows.is_dir() and cached_rows(rows) >= at_least:
            break
        time.sleep(0.2)
    return children(proc.pid)


def cached_rows(rows) -> int:
    """The rows cached below the folder ``rows``: the whole lines of its row logs."""
    return sum(len(RowLog(log.parent).read()) for log in Path(rows).rglob(LOG_NAME))

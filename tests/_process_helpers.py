"""Processes seen through Linux's /proc: the children of a process and whether one still runs
(the interrupt and worker-lifetime tests)."""

from __future__ import annotations


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

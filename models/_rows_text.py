"""CSV rows of floats as text, optionally on two cores.

Each value is written as ``repr(float)`` — the shortest text that reads back as the same double —
which costs about a microsecond per value in CPython: 0.15–0.3 s for a 20 s benchmark result
(4,001 rows × 52 columns), a quarter of a warm ``deckpound run``. With ``parallel=True`` a forked
child formats the second half of the rows while this process formats the first (same text, byte
for byte); the child only formats and writes into a pipe, then ends with ``os._exit``. Used for
the one result file of ``deckpound run``; anything that fails (no ``fork``, a child that does not
finish) falls back to formatting here.
"""

from __future__ import annotations

import contextlib
import os
import signal

__all__ = ["format_rows"]

#: below this many values one process is faster than forking
PARALLEL_MIN_VALUES = 50_000


def _text(rows: list[list[float]]) -> str:
    return "".join(",".join(map(repr, row)) + "\n" for row in rows)


def format_rows(rows: list[list[float]], parallel: bool = False) -> str:
    """The rows as CSV lines (each ending with a newline)."""
    n_values = len(rows) * (len(rows[0]) if rows else 0)
    if (
        not parallel
        or n_values < PARALLEL_MIN_VALUES
        or not hasattr(os, "fork")
        or (os.cpu_count() or 1) < 2
    ):
        return _text(rows)
    half = len(rows) // 2
    try:
        read_fd, write_fd = os.pipe()
        pid = os.fork()
    except OSError:
        return _text(rows)
    if pid == 0:  # the child: format, write, leave without any clean-up of the parent's state
        code = 1
        try:
            os.close(read_fd)
            signal.signal(signal.SIGINT, signal.SIG_DFL)  # a Ctrl-C ends it like the parent
            view = memoryview(_text(rows[half:]).encode())
            while view:
                view = view[os.write(write_fd, view) :]
            code = 0
        finally:
            os._exit(code)
    os.close(write_fd)
    done = False
    try:
        first = _text(rows[:half])
        chunks = []
        while chunk := os.read(read_fd, 1 << 20):
            chunks.append(chunk)
        _, status = os.waitpid(pid, 0)
        done = True
    finally:
        os.close(read_fd)
        if not done:  # an exception here (Ctrl-C): the child must not outlive this call
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
    if status != 0:
        return first + _text(rows[half:])
    return first + b"".join(chunks).decode()

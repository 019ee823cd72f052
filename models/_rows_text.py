"""CSV rows of floats as text: ``repr(float)`` of every value, fast.

Each value is written as ``repr(float)`` — the shortest text that reads back as the same double.
Python's ``repr`` costs about a microsecond per value: 0.15–0.3 s for a 20 s benchmark result
(4,001 rows × 52 columns), a quarter of a warm ``deckpound run``.

:func:`format_array` gives the same bytes from ``orjson``, which writes the shortest round-trip
digits (Ryu) in compiled code. Its text differs from ``repr`` in two places only: exponents of
one digit (``3e-7`` where ``repr`` writes ``3e-07``) and values of order 1e-5, which it writes
positionally (``0.00003``, ``repr``: ``3e-05``). It also writes non-finite values as ``null``.
Those values (non-finite, or 1e-10 ≤ |x| < 1e-4) are therefore given to it as their ``repr``
strings, and the quotes are taken off afterwards. ``tests/test_rows_text.py`` checks the bytes
against ``repr`` over the whole double range, the special values and real results.

Without ``orjson`` (or for lists of rows) :func:`format_rows` uses ``repr``; with
``parallel=True`` a forked child formats the second half of the rows while this process formats
the first (same text, byte for byte); the child only formats and writes into a pipe, then ends
with ``os._exit``. Anything that fails (no ``fork``, a child that does not finish) falls back to
formatting here.
"""

from __future__ import annotations

import contextlib
import os
import signal

import numpy as np

__all__ = ["format_array", "format_rows"]

#: ``orjson`` and ``repr`` write a finite double's text differently only for magnitudes in
#: [REPR_BELOW_FROM, REPR_BELOW) (one-digit exponents, the positional 1e-5 decade); those values
#: are given to ``orjson`` as ``repr`` strings
REPR_BELOW = 1.0e-4
REPR_BELOW_FROM = 1.0e-10

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


def format_array(table: np.ndarray, parallel: bool = False) -> str:
    """The rows of a 2-D float array as CSV lines, each value as ``repr(float)`` would write it
    (module docstring). Uses ``orjson`` when it is installed, else :func:`format_rows`."""
    table = np.asarray(table, dtype=float)
    try:
        import orjson
    except ImportError:
        return format_rows(table.tolist(), parallel=parallel)
    if table.ndim != 2 or table.shape[0] == 0 or table.shape[1] == 0:
        return format_rows(table.tolist())
    rows = table.tolist()
    magnitude = np.abs(table)
    with np.errstate(invalid="ignore"):
        as_repr = ~np.isfinite(table) | ((magnitude >= REPR_BELOW_FROM) & (magnitude < REPR_BELOW))
    for i, j in zip(*(idx.tolist() for idx in np.nonzero(as_repr)), strict=True):
        rows[i][j] = repr(rows[i][j])
    # [[a,b],[c,d]] → "a,b\nc,d\n"; the only strings are the repr texts, so every quote is theirs
    text = orjson.dumps(rows).replace(b'"', b"").replace(b"],[", b"\n")
    return text[2:-2].decode() + "\n"

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

Without ``orjson`` (an install that skipped the dependency) :func:`format_rows` writes the same
text with ``repr``.
"""

from __future__ import annotations

import numpy as np

try:  # a dependency; the Python formatter stands in where it is missing
    import orjson
except ImportError:  # pragma: no cover
    orjson = None

__all__ = ["format_array", "format_rows"]

#: ``orjson`` and ``repr`` write a finite double's text differently only for magnitudes in
#: [REPR_BELOW_FROM, REPR_BELOW) (one-digit exponents, the positional 1e-5 decade); those values
#: are given to ``orjson`` as ``repr`` strings
REPR_BELOW = 1.0e-4
REPR_BELOW_FROM = 1.0e-10


def format_rows(rows: list[list[float]]) -> str:
    """The rows as CSV lines (each ending with a newline), with Python's ``repr``."""
    return "".join(",".join(map(repr, row)) + "\n" for row in rows)


def format_array(table: np.ndarray) -> str:
    """The rows of a 2-D float array as CSV lines, each value as ``repr(float)`` would write it
    (module docstring). Uses ``orjson`` when it is installed, else :func:`format_rows`."""
    table = np.asarray(table, dtype=float)
    if orjson is None or table.ndim != 2 or table.size == 0:
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

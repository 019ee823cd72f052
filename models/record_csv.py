"""Reading CSV earthquake records: a header line naming the columns, then one row per time.

The rules of :mod:`deckpound.models.records` hold here too (sizes checked before the values
are parsed, nothing of an unrecognised file quoted, every tolerance a note); the columns are
turned into motion by :mod:`deckpound.models.record_motion`.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import SceneError
from .records import MAX_SAMPLES, RecordFile, check_count, excerpt, read_capped

MAX_CSV_CELLS = 24_000_000  # rows x columns of a CSV record (190 MB as float64)


@dataclass
class CsvRecord:
    """A CSV record as read: the file, its time column [s] and its numeric columns."""

    file: RecordFile
    t: np.ndarray
    columns: dict[str, np.ndarray]  # may hold trailing NaN (a shorter component)
    mode: str  # "acceleration" (acc_x / acc_y) or "displacement" (<support>_disp [+ _vel])


ACC_COLUMNS = ("acc_x", "acc_y")


def read_csv_record(
    path: str | Path | None, time_column: str, field_name: str = "excitation.file"
) -> CsvRecord:
    """Read a CSV record: a header line, then one row per time stamp.

    Columns: ``time_column`` [s] and either ground accelerations ``acc_x``, ``acc_y``
    (``acc_unit``; either may be missing, and the shorter may end with empty cells) or support
    displacements ``<support>_disp`` [+ ``_vel``] (``disp_unit``); the check of the column set
    against the scene is the caller's. Size (bytes, rows, rows x columns) is checked before
    the values are parsed.
    """
    import pandas as pd  # only CSV records need it (0.3-0.6 s to import)

    raw, rec = read_capped(path, field_name, "CSV record", MAX_SAMPLES + 1)
    text = raw.decode("utf-8", errors="replace")
    first = text.split("\n", 1)[0]
    names = [c.strip() for c in first.split(",")]
    if time_column not in names:  # not recognised as a record: quote nothing of it
        raise SceneError(
            "excitation.time_column",
            f"{rec.path!r}: no column of the header (first "
            f"line) is named {time_column!r}; a CSV record starts with a header "
            "naming the time column and the record columns",
        )
    rows = text.count("\n") + (0 if text.endswith("\n") else 1) - 1
    if rows * len(names) > MAX_CSV_CELLS:
        raise SceneError(
            field_name,
            f"{rec.path!r} holds {rows:,} rows of {len(names)} columns; "
            f"at most {MAX_CSV_CELLS:,} values are read",
        )

    try:
        frame = pd.read_csv(
            io.StringIO(text), dtype=str, keep_default_na=False, skipinitialspace=True
        )
    except Exception as err:
        first_line = (str(err).strip().splitlines() or [type(err).__name__])[0]
        raise SceneError(field_name, f"cannot read CSV {rec.path!r}: {first_line[:80]}") from None
    if not isinstance(frame.index, pd.RangeIndex):  # data rows longer than the header
        raise SceneError(
            field_name,
            f"{rec.path!r}: the data rows hold more values than the "
            f"header has columns ({len(frame.columns)})",
        )
    frame.columns = [str(c).strip() for c in frame.columns]
    if len(set(frame.columns)) != len(frame.columns):
        raise SceneError(field_name, f"{rec.path!r}: the header names a column twice")
    mode = "acceleration" if any(c in ACC_COLUMNS for c in frame.columns) else "displacement"
    rec.npts = len(frame)
    if mode == "acceleration":
        check_count(len(frame), rec, "the file holds")
    columns = {}
    for name in frame.columns:
        cells = frame[name].str.strip()
        values = pd.to_numeric(cells.where(cells != ""), errors="coerce").to_numpy(dtype=float)
        bad = np.flatnonzero((cells != "").to_numpy() & ~np.isfinite(values))
        if bad.size:
            i = int(bad[0])
            cell = cells.iloc[i]
            what = (
                "a true/false value, numbers expected"
                if cell.lower() in ("true", "false")
                else "not finite or not a number"
            )
            raise SceneError(
                field_name,
                f"{rec.path!r}: row {i + 2}, column {excerpt(name)} holds {excerpt(cell)}: {what}",
            )
        columns[name] = values
    t = columns.pop(time_column)
    return CsvRecord(rec, t, columns, mode)

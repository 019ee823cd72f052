"""A sweep's cached summary rows: one appended log of JSON lines per cache folder.

A sweep (:func:`deckpound.compare.studies.variability.sweep_rows`: the variability study, IDA,
multiple-stripe analysis) keeps the row of every finished case, so that a sweep stopped by
Ctrl-C, a kill or a power cut resumes with the cases it had not finished. The rows of one cache
folder are the lines of its file :data:`LOG_NAME`, each ``{"key": case key, "row": {...}}``,
appended with one ``write`` each to a file opened with ``O_APPEND``
(:func:`deckpound.models.file_io.open_append`: whole lines also when two processes sweep into
one folder, never through a link). A file per row cost a file creation and a rename per case,
more than the rest of a case's bookkeeping; a 10,000-case sweep left 10,000 files.

Reading takes every line that is a whole record; a line that is not (the last one a kill cut
short, or bytes that are not such a record) is skipped, and its case is computed again. A later
line of the same key wins. Nothing is flushed to the disk (no ``fsync``): after a power cut the
log may lose its last rows, which are computed again.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from deckpound.models.errors import SceneError
from deckpound.models.file_io import open_append, write_all

__all__ = ["LOG_NAME", "RowLog"]

#: the log file of a cache folder
LOG_NAME = "rows.jsonl"


class RowLog:
    """The row log of the cache folder ``folder`` (created at the first :meth:`append`);
    ``field`` names the option that gave the folder in error messages. Use as a context: the
    file is closed at its end."""

    def __init__(self, folder: str | Path, field: str = "--cache"):
        self.folder = Path(folder)
        self.path = self.folder / LOG_NAME
        self.field = field
        self._fd: int | None = None

    def read(self) -> dict[str, dict]:
        """{key: row} of every whole line of the log (none when it does not exist)."""
        try:
            data = self.path.read_bytes()
        except FileNotFoundError:
            return {}
        except OSError as err:
            raise SceneError(
                self.field, f"cannot read {str(self.path)!r}: {err.strerror or err}"
            ) from None
        rows: dict[str, dict] = {}
        for line in data.split(b"\n")[:-1]:  # the part after the last newline is cut short
            try:
                record = json.loads(line)
            except ValueError:
                continue
            if (
                isinstance(record, dict)
                and isinstance(record.get("key"), str)
                and isinstance(record.get("row"), dict)
            ):
                rows[record["key"]] = record["row"]
        return rows

    def append(self, key: str, row: dict) -> None:
        """Append the row of case ``key`` as one line (one ``write``)."""
        start = b""
        if self._fd is None:
            start = b"" if self._ends_whole() else b"\n"  # a cut line stays apart
            self._fd = open_append(self.path, self.field)
        write_all(self._fd, start + (json.dumps({"key": key, "row": row}) + "\n").encode("utf-8"))

    def _ends_whole(self) -> bool:
        """Whether the log is absent, empty or ends with a newline."""
        try:
            with open(self.path, "rb") as fh:
                if fh.seek(0, os.SEEK_END) == 0:
                    return True
                fh.seek(-1, os.SEEK_END)
                return fh.read(1) == b"\n"
        except OSError:
            return True  # absent (or unreadable: open_append says why)

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> RowLog:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

"""Writing the report's files: the one place the comparison layer creates output files.

Every table, text and VTK file of ``paper``, ``study`` and ``export-vtk`` is written through
:func:`folder`, :func:`target` and :func:`write_text`, which follow the file policy of
:mod:`deckpound.models.file_io`: written to a temporary file and renamed into place (atomic), never
through a symbolic link, with the user's umask.

Tables carry their units: CSV files name them in the header (``peak_theta [rad]``; a
dimensionless number ``[-]``; a text or flag column such as ``engine`` has none), so a plain
``pandas.read_csv(path)`` reads them (:func:`deckpound.models.result.read_table` gives the plain
names and the units in ``attrs``). A long table whose value column holds quantities of different
units (``aligned_long``, ``variability_summary``) says each row's unit in its ``unit`` column. Parquet
files in the schema metadata (``units``: JSON column → unit, and each field's own ``unit``
entry), so ``pandas.read_parquet`` gives the plain column names and
``pyarrow.parquet.read_schema(path).metadata`` the units.
"""

from __future__ import annotations

import contextlib
import json
import re
from collections.abc import Iterator
from pathlib import Path

import pandas as pd

from deckpound.models.file_io import atomic_path, atomic_write_text, ensure_folder, unit_label
from deckpound.models.file_io import write_csv as file_io_write_csv


def folder(path: str | Path) -> Path:
    """Create folder ``path`` (and its parents) unless it exists; return it (a link refused)."""

    return ensure_folder(path)


@contextlib.contextmanager
def target(path: str | Path) -> Iterator[Path]:
    """A temporary file name a library (pandas, matplotlib, meshio) writes ``path`` to; it is
    renamed to ``path`` when the block ends without error (:func:`deckpound.models.file_io.atomic_path`)."""

    folder(Path(path).parent)
    with atomic_path(path) as tmp:
        yield tmp


def write_text(path: str | Path, text: str) -> Path:
    """Write a text file (UTF-8) atomically."""

    folder(Path(path).parent)
    return Path(atomic_write_text(path, text))


def unit_header(frame: pd.DataFrame, units: dict[str, str]) -> pd.DataFrame:
    """The frame with ``name [unit]`` headers for the columns that have a unit."""
    return frame.rename(columns={c: unit_label(c, units.get(c)) for c in frame.columns})


#: columns that count things (dimensionless, ``[-]``) wherever a table of deckpound has them
COUNT_COLUMNS = frozenset(
    {"run", "case", "cases", "hits", "misses", "steps", "left_out", "n", "gap_closures"}
)


def vocabulary_unit(name: str) -> str | None:
    """The unit a column name has across deckpound's tables, for a writer that names none:
    counts (:data:`COUNT_COLUMNS`, ``closures_c1``…) and shares (``*_share``, ``share_*``)
    ``-``, times (``*_time``: ``first_time``, ``wall_time``) ``s``; None for any other name."""
    if name in COUNT_COLUMNS or re.fullmatch(r"closures_c\d+", name):
        return "-"
    if name.endswith("_share") or name.startswith("share_"):
        return "-"
    if name.endswith("_time"):
        return "s"
    return None


def write_csv(frame: pd.DataFrame, path: str | Path, units: dict[str, str]) -> Path:
    """A CSV table whose header states each numeric column's unit (``peak_theta [rad]``;
    :func:`deckpound.models.file_io.write_csv`): the unit ``units`` gives, else the
    column name's unit across deckpound's tables (:func:`vocabulary_unit`)."""
    folder(Path(path).parent)
    named = {c: units.get(c) or vocabulary_unit(str(c)) for c in frame.columns}
    return file_io_write_csv(frame, path, {c: u for c, u in named.items() if u})


def write_parquet(
    frame: pd.DataFrame,
    path: str | Path,
    units: dict[str, str],
    descriptions: dict[str, str] | None = None,
) -> Path:
    """A Parquet table with plain column names and the units in the schema metadata."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(frame, preserve_index=False)
    descriptions = descriptions or {}
    fields = []
    for f in table.schema:
        meta = {}
        if units.get(f.name):
            meta[b"unit"] = units[f.name].encode()
        if descriptions.get(f.name):
            meta[b"description"] = descriptions[f.name].encode()
        fields.append(f.with_metadata(meta) if meta else f)
    schema_meta = dict(table.schema.metadata or {})
    schema_meta[b"units"] = json.dumps(
        {c: units[c] for c in frame.columns if units.get(c)}
    ).encode()
    table = table.cast(pa.schema(fields, metadata=schema_meta))
    with target(path) as p:
        pq.write_table(table, p)
    return Path(path)


def parquet_units(path: str | Path) -> dict[str, str]:
    """The ``units`` map of a Parquet file written by :func:`write_parquet`."""
    import pyarrow.parquet as pq

    meta = pq.read_schema(path).metadata or {}
    return json.loads(meta.get(b"units", b"{}"))


def folder_size(path: str | Path, exclude: tuple[str, ...] = ()) -> int:
    """Bytes of the regular files below ``path``, top-level entries named in ``exclude``
    left out (the result cache is not part of a report)."""
    total = 0
    root = Path(path)
    for p in root.rglob("*"):
        if p.relative_to(root).parts[0] in exclude or p.is_symlink() or not p.is_file():
            continue
        total += p.stat().st_size
    return total

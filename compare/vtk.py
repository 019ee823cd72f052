"""ParaView export: deck and seat outlines over time as a VTK time series (meshio).

For each result in a folder (``<engine>.csv`` + ``<engine>.json`` with the scene in its
metadata, as ``deckpound run`` writes it) this writes ``<engine>/frame_NNNNN.vtu`` (polygons
of the deck and both seats, true scale, with point data ``displacement`` and cell data
``body``) and ``<engine>.pvd``, the collection ParaView opens as one time series.

The input is checked whole before anything is written (:func:`check_result_folder`): files
that are not valid JSON or CSV, a missing or invalid scene, missing columns, non-finite values
or a time base that does not increase are refused by name (exit status 2). Every file is
written atomically.
"""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np
from deckpound.models.errors import SceneError
from deckpound.models.result import Result
from deckpound.models.scene_io import scene_from_mapping

from deckpound._io import atomic_path, atomic_write_text, ensure_folder

from .figures import OUTLINE_COLUMNS, outlines

BODIES = ("deck", "seat1", "seat2")
STATE = OUTLINE_COLUMNS
#: most frames one export may write per result (each frame is one file)
MAX_FRAMES = 100_000


def result_engines(folder: Path) -> list[str]:
    return sorted(p.stem for p in folder.glob("*.json") if (folder / f"{p.stem}.csv").is_file())


def frame_mesh(scene, row: dict[str, float]) -> meshio.Mesh:
    """One frame: each body's outline as a polygon (true-scale displacements)."""
    polys = outlines(scene, row, 1.0)
    rest = outlines(scene, {k: 0.0 for k in row}, 1.0)
    points, cells, body, disp = [], [], [], []
    for b, name in enumerate(BODIES):
        p = polys[name][:-1]
        start = len(points)
        points.extend(p)
        disp.extend(p - rest[name][:-1])
        cells.append(list(range(start, start + len(p))))
        body.append(b)
    pts = np.column_stack([np.asarray(points), np.zeros(len(points))])
    d = np.column_stack([np.asarray(disp), np.zeros(len(disp))])
    return meshio.Mesh(pts, [("polygon", np.array(cells))], point_data={"displacement": d},
                       cell_data={"body": [np.array(body, dtype=float)]})


def check_result_folder(result_dir: str | Path, every: int = 1) -> dict[str, tuple]:
    """Load and check every result in ``result_dir``: ``{engine: (Result, Scene)}``.

    Refuses (SceneError, field ``RESULT_DIR`` or ``--every``) a folder without results,
    damaged files, a missing or invalid scene, missing or non-finite columns, a time base that
    does not increase, and more than :data:`MAX_FRAMES` frames.
    """
    result_dir = Path(result_dir)
    if not result_dir.is_dir():
        raise SceneError("RESULT_DIR", f"{str(result_dir)!r} is not a folder")
    if not 1 <= every <= 10 ** 9:
        raise SceneError("--every", f"must be in [1, 1e9], got {every}")
    engines = result_engines(result_dir)
    if not engines:
        raise SceneError("RESULT_DIR", f"{str(result_dir)!r} holds no <engine>.csv/.json result")
    out = {}
    for engine in engines:
        try:
            r = Result.read(result_dir, engine)
        except SceneError as err:
            raise SceneError("RESULT_DIR", err.reason) from None
        except ValueError as err:  # columns of unequal length and the like
            raise SceneError("RESULT_DIR", f"{engine}: {err}") from None
        if not isinstance(r.meta.get("scene"), dict):
            raise SceneError("RESULT_DIR", f"{engine}.json carries no scene (write results with "
                             "'deckpound run' or 'deckpound compare')")
        try:
            scene = scene_from_mapping(r.meta["scene"])
        except SceneError as err:
            raise SceneError("RESULT_DIR", f"{engine}.json: its scene is invalid: {err}") from None
        missing = [q for q in STATE if q not in r.columns]
        if missing:
            raise SceneError("RESULT_DIR", f"{engine}.csv lacks the column {missing[0]!r}")
        if len(r.t) < 1:
            raise SceneError("RESULT_DIR", f"{engine}.csv holds no rows")
        for q in ("t",) + STATE:
            bad = np.flatnonzero(~np.isfinite(r[q]))
            if len(bad):
                raise SceneError("RESULT_DIR", f"{engine}.csv: column {q!r} is not finite in "
                                 f"row {int(bad[0]) + 2} ({r[q][bad[0]]})")
        if len(r.t) > 1 and not np.all(np.diff(r.t) > 0):
            raise SceneError("RESULT_DIR", f"{engine}.csv: the time column 't' does not increase")
        frames = (len(r.t) + every - 1) // every
        if frames > MAX_FRAMES:
            raise SceneError("--every", f"gives {frames} frames for {engine} (one file each; at "
                             f"most {MAX_FRAMES}); use --every >= {len(r.t) // MAX_FRAMES + 1}")
        out[engine] = (r, scene)
    return out


def export_vtk(result_dir: str | Path, out: str | Path, every: int = 1,
               results: dict[str, tuple] | None = None) -> list[Path]:
    """Write the VTK series of every result in ``result_dir``; returns the .pvd files.

    ``results``: the output of :func:`check_result_folder` when the caller already has it."""
    if results is None:
        results = check_result_folder(result_dir, every)
    out = ensure_folder(out)
    written = []
    for engine, (r, scene) in results.items():
        folder = ensure_folder(out / engine)
        entries = []
        for k in range(0, len(r.t), every):
            row = {q: float(r[q][k]) for q in OUTLINE_COLUMNS}
            name = f"frame_{k:06d}.vtu"
            with atomic_path(folder / name) as tmp:
                meshio.write(tmp, frame_mesh(scene, row), file_format="vtu")
            entries.append(f'    <DataSet timestep={quoteattr(repr(float(r.t[k])))} '
                           f'part="0" file={quoteattr(f"{engine}/{name}")}/>')
        pvd = out / f"{engine}.pvd"
        atomic_write_text(pvd, '<?xml version="1.0"?>\n<VTKFile type="Collection" '
                          'version="0.1">\n  <Collection>\n' + "\n".join(entries)
                          + "\n  </Collection>\n</VTKFile>\n")
        written.append(pvd)
    return written

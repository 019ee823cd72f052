"""ParaView export: deck and seat outlines over time as a VTK time series (meshio).

For each result in a folder (``<engine>.csv`` + ``<engine>.json`` with the scene in its
metadata, as ``deckpound run`` writes it) this writes ``<engine>/frame_NNNNN.vtu`` (polygons
of the deck and both seats, true scale, with point data ``displacement`` and cell data
``body``) and ``<engine>.pvd``, the collection ParaView opens as one time series.
"""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np

from deckpound.models.errors import SceneError
from deckpound.models.result import Result
from deckpound.models.scene_io import scene_from_mapping

from .figures import OUTLINE_COLUMNS, outlines

BODIES = ("deck", "seat1", "seat2")


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


def export_vtk(result_dir: str | Path, out: str | Path, every: int = 1) -> list[Path]:
    """Write the VTK series of every result in ``result_dir``; returns the .pvd files."""
    result_dir, out = Path(result_dir), Path(out)
    if not result_dir.is_dir():
        raise SceneError("RESULT_DIR", f"{str(result_dir)!r} is not a folder")
    if every < 1:
        raise SceneError("--every", f"must be >= 1, got {every}")
    engines = result_engines(result_dir)
    if not engines:
        raise SceneError("RESULT_DIR", f"{str(result_dir)!r} holds no <engine>.csv/.json result")
    written = []
    for engine in engines:
        r = Result.read(result_dir, engine)
        if "scene" not in r.meta:
            raise SceneError("RESULT_DIR", f"{engine}.json carries no scene (write results with "
                             "'deckpound run' or 'deckpound compare')")
        scene = scene_from_mapping(r.meta["scene"])
        folder = out / engine
        folder.mkdir(parents=True, exist_ok=True)
        entries = []
        for k in range(0, len(r.t), every):
            row = {q: float(r[q][k]) for q in OUTLINE_COLUMNS}
            name = f"frame_{k:06d}.vtu"
            meshio.write(folder / name, frame_mesh(scene, row))
            entries.append(f'    <DataSet timestep={quoteattr(repr(float(r.t[k])))} '
                           f'part="0" file={quoteattr(f"{engine}/{name}")}/>')
        pvd = out / f"{engine}.pvd"
        pvd.write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                       "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")
        written.append(pvd)
    return written

"""ParaView export: deck and seat outlines over time (meshio).

For each result in a folder (``<engine>.csv`` + ``<engine>.json`` with the scene in its
metadata, as ``deckpound run`` and ``deckpound compare`` write them):

* ``fmt = "xdmf"`` (default): ONE file, ``<engine>.xdmf``, an XDMF temporal collection with
  its data inline (no companion files), that ParaView opens in one step as a time series. The
  geometry is the outline of the deck (or of each deck segment) and both seats at rest
  (quadrilaterals, metres); each time step carries the point data ``displacement`` (relative
  to the supports: the deck to the shake tables, a seat to its actuator, true scale [m]; apply
  *Warp By Vector* with a scale factor of about 100 to see the gaps and the rotation),
  ``displacement_abs`` (absolute [m]) and the cell data ``body`` (0 deck — or the segments
  0 … N−1 —, then seat 1, seat 2). meshio reads it back with
  :class:`meshio.xdmf.TimeSeriesReader`.
* ``fmt = "pvd"``: the older layout, only when asked: ``<engine>/frame_NNNNNN.vtu`` (displaced
  outlines, true scale, one file per output time) and ``<engine>.pvd`` collecting them.

The input is checked whole before anything is written (:func:`check_result_folder`): files
that are not valid JSON or CSV, a missing or invalid scene, missing columns, non-finite values
or a time base that does not increase are refused by name (exit status 2). Every file is
written atomically (:mod:`.outputs`, backed by :mod:`deckpound.models.file_io`).
"""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np

from deckpound.compare.report.figures import outline_columns, outlines
from deckpound.compare.report.outputs import folder as make_folder
from deckpound.compare.report.outputs import target, write_text
from deckpound.models.errors import SceneError
from deckpound.models.plan import plan_of
from deckpound.models.result import Result
from deckpound.models.scene_io import scene_from_mapping

FORMATS = ("xdmf", "pvd")
#: most frames one ``pvd`` export may write per result (each frame is one file)
MAX_FRAMES = 100_000


def result_engines(folder: Path) -> list[str]:
    return sorted(p.stem for p in folder.glob("*.json") if (folder / f"{p.stem}.csv").is_file())


def bodies(scene) -> tuple[str, ...]:
    """The outlined bodies in cell order: the deck (or each deck segment), seat 1, seat 2."""
    return tuple(seg.name for seg in plan_of(scene).segments) + ("seat1", "seat2")


def state_columns(scene) -> tuple[str, ...]:
    """The relative state columns an outline reads (:func:`~.figures.outline_columns`)."""
    return outline_columns(plan_of(scene))


def absolute_column(column: str) -> str:
    """The absolute counterpart of an outline column (θ is the same: the supports do not
    rotate): ``deck_x_rel`` → ``deck_x_abs``."""
    return column[: -len("_rel")] + "_abs" if column.endswith("_rel") else column


def _points(scene, row: dict[str, float]) -> np.ndarray:
    """The outline points (each body's 4 corners, in :func:`bodies` order) at one state [m]."""
    polys = outlines(scene, row, 1.0)
    return np.concatenate([polys[name][:-1] for name in bodies(scene)])


def _cells(n_bodies: int) -> np.ndarray:
    return np.arange(4 * n_bodies).reshape(n_bodies, 4)


def frame_mesh(scene, row: dict[str, float]) -> meshio.Mesh:
    """One frame: each body's outline as a polygon (true-scale displacements)."""
    p = _points(scene, row)
    rest = _points(scene, dict.fromkeys(row, 0.0))
    pts = np.column_stack([p, np.zeros(len(p))])
    d = np.column_stack([p - rest, np.zeros(len(p))])
    n = len(bodies(scene))
    return meshio.Mesh(
        pts,
        [("polygon", _cells(n))],
        point_data={"displacement": d},
        cell_data={"body": [np.arange(n, dtype=float)]},
    )


def _rows(scene, r: Result, k: int) -> tuple[dict[str, float], dict[str, float]]:
    state = state_columns(scene)
    rel = {q: float(r[q][k]) for q in state}
    absolute = {q: float(r[absolute_column(q)][k]) for q in state}
    return rel, absolute


def write_xdmf(scene, r: Result, path: Path, every: int = 1) -> Path:
    """The XDMF time series of one result (see the module docstring)."""
    rest = _points(scene, dict.fromkeys(state_columns(scene), 0.0))
    z = np.zeros((len(rest), 1))
    n = len(bodies(scene))
    body = np.arange(n, dtype=np.float32)
    with target(path) as p, meshio.xdmf.TimeSeriesWriter(p, data_format="XML") as writer:
        writer.write_points_cells(np.hstack([rest, z]), [("quad", _cells(n))])
        for k in range(0, len(r.t), every):
            rel, absolute = _rows(scene, r, k)
            d_rel = np.hstack([_points(scene, rel) - rest, z]).astype(np.float32)
            d_abs = np.hstack([_points(scene, absolute) - rest, z]).astype(np.float32)
            writer.write_data(
                float(r.t[k]),
                point_data={"displacement": d_rel, "displacement_abs": d_abs},
                cell_data={"body": [body]},
            )
    return path


def write_pvd(scene, r: Result, out: Path, engine: str, every: int = 1) -> Path:
    """One .vtu per output time and the .pvd collection (see the module docstring)."""
    frames = make_folder(out / engine)
    entries = []
    for k in range(0, len(r.t), every):
        rel, _ = _rows(scene, r, k)
        name = f"frame_{k:06d}.vtu"
        with target(frames / name) as p:
            meshio.write(p, frame_mesh(scene, rel))
        entries.append(
            f"    <DataSet timestep={quoteattr(repr(float(r.t[k])))} "
            f'part="0" file={quoteattr(f"{engine}/{name}")}/>'
        )
    return write_text(
        out / f"{engine}.pvd",
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
        "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n",
    )


def check_result_folder(
    result_dir: str | Path, every: int = 1, fmt: str = "xdmf"
) -> dict[str, tuple]:
    """Load and check every result in ``result_dir``: ``{engine: (Result, Scene)}``.

    Refuses (SceneError, field ``RESULT_DIR`` or ``--every``) a folder without results,
    damaged files, a missing or invalid scene, missing or non-finite columns, a time base that
    does not increase, and more than :data:`MAX_FRAMES` frames.
    """
    result_dir = Path(result_dir)
    if not result_dir.is_dir():
        raise SceneError("RESULT_DIR", f"{str(result_dir)!r} is not a folder")
    if not 1 <= every <= 10**9:
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
            raise SceneError(
                "RESULT_DIR",
                f"{engine}.json carries no scene (write results with "
                "'deckpound run' or 'deckpound compare')",
            )
        try:
            scene = scene_from_mapping(r.meta["scene"])
        except SceneError as err:
            raise SceneError("RESULT_DIR", f"{engine}.json: its scene is invalid: {err}") from None
        state = state_columns(scene)
        missing = [
            q for q in state + tuple(absolute_column(q) for q in state) if q not in r.columns
        ]
        if missing:
            raise SceneError("RESULT_DIR", f"{engine}.csv lacks the column {missing[0]!r}")
        if len(r.t) < 1:
            raise SceneError("RESULT_DIR", f"{engine}.csv holds no rows")
        for q in ("t",) + state:
            bad = np.flatnonzero(~np.isfinite(r[q]))
            if len(bad):
                raise SceneError(
                    "RESULT_DIR",
                    f"{engine}.csv: column {q!r} is not finite in "
                    f"row {int(bad[0]) + 2} ({r[q][bad[0]]})",
                )
        if len(r.t) > 1 and not np.all(np.diff(r.t) > 0):
            raise SceneError("RESULT_DIR", f"{engine}.csv: the time column 't' does not increase")
        frames = (len(r.t) + every - 1) // every
        if fmt == "pvd" and frames > MAX_FRAMES:
            raise SceneError(
                "--every",
                f"gives {frames} frames for {engine} (one file each; at "
                f"most {MAX_FRAMES}); use --every >= {len(r.t) // MAX_FRAMES + 1}",
            )
        out[engine] = (r, scene)
    return out


def export_vtk(
    result_dir: str | Path,
    out: str | Path,
    every: int = 1,
    fmt: str = "xdmf",
    results: dict[str, tuple] | None = None,
) -> list[Path]:
    """Write the time series of every result in ``result_dir``; returns the files ParaView
    opens (``<engine>.xdmf``, or ``<engine>.pvd`` with ``fmt = "pvd"``).

    The input is checked whole before anything is written (:func:`check_result_folder`;
    ``results``: its output when the caller already has it)."""
    if fmt not in FORMATS:
        raise SceneError("--format", f"must be one of {', '.join(FORMATS)}, got {fmt!r}")
    if results is None:
        results = check_result_folder(result_dir, every, fmt)
    out = make_folder(out)
    written = []
    for engine, (r, scene) in results.items():
        if fmt == "xdmf":
            written.append(write_xdmf(scene, r, out / f"{engine}.xdmf", every))
        else:
            written.append(write_pvd(scene, r, out, engine, every))
    return written

"""Record-to-record variability: one engine over many ground motions of one scene.

``deckpound study variability SCENE --cases N`` runs the scene with N seeds of its synthetic
record (``excitation.seed``, ``seed + 1``, ...); ``--records DIR`` runs it with every record
pair of a folder instead (``*.at2`` as AT2, ``*.txt``/``*.dat`` as two-column text records),
read by :func:`deckpound.models.record_suite.read_suite`: PEER names pair by station
(``RSN753_LOMAP_CLS000`` / ``CLS090``), ``NAME_x`` / ``NAME_y`` pair as named, a
``manifest.csv`` pairs the rest, vertical components are left out, a lone horizontal component
is refused; each pair's components go on x (longitudinal) and y (transverse), and with
``rotate`` (``--rotate90``) also swapped. The pairs are scaled as the scene says (by default
each component to its own target; ``excitation.scaling = 'pair-…'`` scales a pair by one
factor and keeps its component ratio). Per case it writes a row: peak deck rotation, peak transverse and
longitudinal deck displacement relative to the tables, gap closures (total and per corner),
status and times; then the summary statistics (median, 16 % and 84 % fractiles, mean, standard
deviation, min, max of each quantity over the finished cases) and a figure (empirical
distributions with the median and the 16/84 % band).

Speed: the cases run in long-lived workers (:mod:`.pool`, or the Dask cluster given
``--scheduler``) that load the kernels once; a worker returns only the row, never the
histories, and the rows are cached one small JSON file each (``CACHE/variability/<key>.json``,
written atomically), so an interrupted study resumes where it stopped and a repeated one
returns at once.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.cases import case_key, interrupted, map_parallel, run_case
from deckpound.compare.progress import Progress
from deckpound.compare.report.outputs import write_csv
from deckpound.compare.row_log import RowLog
from deckpound.models.errors import SceneError
from deckpound.models.file_io import atomic_write_text, ensure_folder
from deckpound.models.motion import RecordWarning
from deckpound.models.record_suite import read_suite
from deckpound.models.scene import Scene
from deckpound.models.scene_io import modified

#: quantities of a row that the summary describes
QUANTITIES = ("peak_theta", "peak_y", "peak_x", "gap_closures")
UNITS = {"peak_theta": "rad", "peak_y": "m", "peak_x": "m", "gap_closures": "-"}
#: units of the numeric columns of a case table (the case columns and :func:`case_row`'s row;
#: ``closures_c1``… are ``-`` too, :func:`table_units`); text and flag columns have none
CASE_UNITS = {
    **UNITS,
    "case": "-",
    "seed": "-",
    "wall_time": "s",
    "compile_time": "s",
    "steps": "-",
    "loop_time": "s",
    "unseated_time": "s",
    "seat_margin": "m",
    "seat_demand": "m",
    "process_time": "s",
}
#: units of the summary's columns that have one unit for every row (the statistics are in the
#: unit of the row's quantity, named in its ``unit`` column)
SUMMARY_UNITS = {"n": "-"}
#: version of the row format (part of the row cache key)
ROW_FORMAT = 2  # 2: seat margin and demand, unseated flag, loop time
MAX_CASES = 1_000_000


def seed_cases(scene: Scene, cases: int) -> list[tuple[str, dict, Scene]]:
    """``cases`` copies of the scene with seeds ``excitation.seed + i`` of its synthetic
    record: (label, params, scene)."""

    if scene.excitation.kind != "synthetic":
        raise SceneError(
            "--cases",
            f"varies the seed of the synthetic record; the scene's "
            f"excitation.kind is {scene.excitation.kind!r}: give --records DIR",
        )
    if not 1 <= cases <= MAX_CASES:
        raise SceneError("--cases", f"must be in [1, {MAX_CASES}], got {cases}")
    base = scene.excitation.seed
    out = []
    for i in range(cases):
        exc = dataclasses.replace(scene.excitation, seed=base + i)
        out.append(
            (f"seed {base + i}", {"seed": base + i, "record": ""}, scene.replace(excitation=exc))
        )
    return out


def record_cases(
    scene: Scene, folder: str | Path, rotate: bool = False
) -> list[tuple[str, dict, Scene]]:
    """One case per record pair of ``folder`` (:func:`deckpound.models.record_suite.read_suite`:
    PEER component names, ``NAME_x``/``NAME_y``, or ``manifest.csv``), each pair's components
    on x and y; with ``rotate`` also each pair with its components swapped."""

    suite = read_suite(folder, rotate=rotate)
    for note in suite.notes:
        warnings.warn(f"--records: {note}", RecordWarning, stacklevel=2)
    out = []
    for pair in suite.pairs:
        params = {
            "seed": None,
            "record": pair.name,
            "rotated": pair.rotated,
            "file_x": pair.file_x.name,
            "file_y": pair.file_y.name,
        }
        out.append((f"record {pair.label}", params, modified(scene, *pair.overrides())))
    return out


def case_row(engine: str, scene: Scene) -> dict:
    """Run one case (in a worker) and return its row; a refused or failed case gives a row
    with its status and message, never an exception."""

    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = run_case(engine, scene, summary_only=True)
    except SceneError as err:
        return {"status": "refused", "message": str(err), "process_time": 0.0}
    per = r.meta.get("gap_closures_per_corner", {})
    # a deck of segments: the segment that turns (moves) most
    bodies = ["deck"] if scene.segments is None else [s.name for s in scene.segments]
    row = {
        "peak_theta": max(r.peak(f"{b}_theta") for b in bodies),  # every step (Result.peak)
        "peak_y": max(r.peak(f"{b}_y_rel") for b in bodies),
        "peak_x": max(r.peak(f"{b}_x_rel") for b in bodies),
        "gap_closures": int(r.meta.get("gap_closures", 0)),
        **{f"closures_{c}": int(v) for c, v in sorted(per.items())},
        "status": str(r.meta.get("status")),
        "message": str(r.meta.get("message", "")),
        "wall_time": float(r.meta.get("wall_time", np.nan)),
        "compile_time": float(r.meta.get("compile_time", 0.0)),
        "steps": int(r.meta.get("steps", 0)),
        "loop_time": float(r.meta.get("loop_time", np.nan)),
        "unseated": bool(r.meta.get("unseated", False)),
        "unseated_time": float(r.meta.get("unseated_time", np.nan)),
        "seat_margin": _smallest_margin(r.meta.get("seat_margin_min")),
        "seat_demand": -_smallest_margin(
            {c: [-v[0], v[1]] for c, v in (r.meta.get("gap_opening_max") or {}).items()}
        ),
    }
    row["process_time"] = time.perf_counter() - t0
    return row


def _smallest_margin(margins) -> float:
    """The smallest seat margin [m] over the corners (``meta["seat_margin_min"]``: {corner:
    [margin, time]}); NaN when the scene gives no support length. ``seat_demand`` is the
    largest opening of a deck end from its seat over the corners (``gap_opening_max``), the
    seat width the record asks for."""
    values = [float(v[0]) for v in (margins or {}).values() if v is not None]
    return min(values) if values else float("nan")


def row_key(engine: str, scene: Scene, read: dict[str, str | None] | None = None) -> str:
    """Cache key of a case's row: the result cache's key, the row format (``read``: the record
    files' digests of the batch of keys, :func:`~deckpound.compare.cases.record_digests`)."""

    text = f"{case_key(engine, scene, read)}:variability-row:{ROW_FORMAT}"
    return hashlib.sha256(text.encode()).hexdigest()


#: statuses of a finished case, cached and not recomputed: a doubtful case (energy created at a
#: contact) and an unseated one (a corner lost its seat; the run stops there) are deterministic
#: answers too; their rows keep their status and the summary leaves them out
FINISHED = ("success", "doubtful", "unseated")


def sweep_rows(
    scenes: list[Scene],
    engine: str,
    rows_dir: Path,
    title: str,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
) -> tuple[dict[int, dict], int]:
    """Run ``engine`` on every scene for its summary row (:func:`case_row`, in the workers of
    :mod:`.pool` or a Dask cluster: no histories travel), the row of every finished case
    appended to the row log of ``rows_dir`` (:mod:`deckpound.compare.row_log`; finished cases
    are read back, not recomputed: Ctrl-C loses only the cases running). Returns ({index:
    row}, number of cases computed now)."""

    read: dict[str, str | None] = {}  # each record file read once for all the keys
    keys = [row_key(engine, sc, read) for sc in scenes]
    log = RowLog(rows_dir)
    cached = log.read()
    rows: dict[int, dict] = {
        i: cached[k]
        for i, k in enumerate(keys)
        if k in cached and cached[k].get("status") in FINISHED
    }
    todo = [i for i in range(len(scenes)) if i not in rows]
    bar = Progress(len(scenes), title, progress)
    bar.skip(len(rows))  # cached rows: done, not in the rate

    def done(i: int, row: dict) -> None:
        rows[i] = row
        if row.get("status") in FINISHED:
            log.append(keys[i], row)
        bar.advance()

    with log:
        try:
            map_parallel(todo, lambda i: (engine, scenes[i]), case_row, done, workers, scheduler)
        except KeyboardInterrupt as err:
            bar.close()
            raise interrupted(err, title, len(rows), len(scenes), rows_dir) from None
    bar.close()
    return rows, len(todo)


def run_variability(
    scene: Scene,
    out: str | Path,
    *,
    engine: str = "compliance",
    cases: int | None = None,
    records: str | Path | None = None,
    rotate: bool = False,
    cache_dir: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
):
    """Run the study, write ``variability.csv``, ``variability_summary.csv`` (units in the
    header, :func:`table_units`; the summary's statistics in its ``unit`` column's unit) and
    ``variability.png`` in ``out``; return (table, summary)."""

    if (cases is None) == (records is None):
        raise SceneError(
            "--cases", "give either --cases N (seeds of the synthetic record) or --records DIR"
        )
    if rotate and records is None:
        raise SceneError("--rotate90", "rotates the pairs of --records DIR; give --records")
    specs = (
        record_cases(scene, records, rotate) if records is not None else seed_cases(scene, cases)
    )
    out = ensure_folder(out)
    rows_dir = ensure_folder(Path(cache_dir) if cache_dir else out / "cache", "--cache")
    t0 = time.perf_counter()
    rows, computed = sweep_rows(
        [sc for _, _, sc in specs],
        engine,
        ensure_folder(rows_dir / "variability", "--cache"),
        "study variability",
        workers=workers,
        scheduler=scheduler,
        progress=progress,
    )
    table = pd.DataFrame(
        [
            {"case": i, "label": specs[i][0], "engine": engine, **specs[i][1], **rows[i]}
            for i in range(len(specs))
        ]
    )
    summary = summarize(table)
    summary.attrs["wall"] = time.perf_counter() - t0
    write_csv(table, out / "variability.csv", table_units(table))
    write_csv(summary, out / "variability_summary.csv", SUMMARY_UNITS)
    figure(table, summary, scene, out / "variability.png")
    atomic_write_text(
        out / "variability.json",
        json.dumps(
            {
                "cases": len(specs),
                "computed": computed,
                "from_cache": len(specs) - computed,
                "engine": engine,
                "wall_time": summary.attrs["wall"],
                "workers": workers,
                "scheduler": scheduler,
                "cpu_count": os.cpu_count(),
            },
            indent=2,
        ),
    )
    return table, summary


def table_units(table) -> dict[str, str]:
    """Units of a case table's columns (:data:`CASE_UNITS`; ``closures_c1``… counts)."""
    units = {c: u for c, u in CASE_UNITS.items() if c in table}
    units.update({c: "-" for c in table.columns if str(c).startswith("closures_")})
    return units


def summarize(table) -> object:
    """Median, 16 % / 84 % fractiles, mean, std, min, max per quantity (finished cases)."""

    ok = table[table["status"] == "success"] if "status" in table else table
    rows = []
    for q in QUANTITIES:
        x = ok[q].to_numpy(float) if q in ok and len(ok) else np.zeros(0)
        stats = {"quantity": q, "unit": UNITS[q], "n": len(x)}
        if len(x):
            stats.update(
                median=float(np.median(x)),
                p16=float(np.percentile(x, 16)),
                p84=float(np.percentile(x, 84)),
                mean=float(np.mean(x)),
                std=float(np.std(x, ddof=1)) if len(x) > 1 else 0.0,
                min=float(np.min(x)),
                max=float(np.max(x)),
            )
        rows.append(stats)
    frame = pd.DataFrame(rows)
    status = table.get("status")
    for name in ("doubtful", "unseated"):
        frame.attrs[name] = int((status == name).sum()) if status is not None else 0
    frame.attrs["failed"] = (
        int(len(table) - len(ok)) - frame.attrs["doubtful"] - frame.attrs["unseated"]
    )
    return frame


def figure(table, summary, scene: Scene, path: Path) -> list[Path]:
    """Empirical distributions of peak rotation, transverse displacement and gap closures,
    with the median and the 16–84 % band (the legend beside the last panel, off the data)."""
    from deckpound.compare.report.style import new_figure, outside_legend, save

    ok = table[table["status"] == "success"]
    panels = (
        ("peak_theta", 1e3, "peak deck rotation [mrad]"),
        ("peak_y", 1e3, "peak transverse displacement [mm]"),
        ("gap_closures", 1.0, "gap closures [-]"),
    )
    fig, axes = new_figure(1, 3, width=10.0, height=3.0)
    stats = summary.set_index("quantity")
    for ax, (q, scale, label) in zip(axes[0], panels):
        x = np.sort(ok[q].to_numpy(float)) * scale if len(ok) else np.zeros(0)
        if len(x):
            ax.step(x, np.arange(1, len(x) + 1) / len(x), where="post", color="#000000")
            s = stats.loc[q]
            ax.axvspan(
                s["p16"] * scale, s["p84"] * scale, color="#1f5fa8", alpha=0.15, label="16-84 %"
            )
            ax.axvline(s["median"] * scale, color="#c0392b", linestyle="--", label="median")
        ax.set_xlabel(label)
        ax.set_ylabel("fraction of cases [-]")
    outside_legend(axes[0, -1])  # the same band and median in every panel
    axes[0, 0].set_title(
        f"{len(ok)} of {len(table)} cases, {table['engine'].iloc[0]} engine"
        if len(table)
        else "no case"
    )
    return save(fig, path, scene.name)

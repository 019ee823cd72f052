"""Export the OpenSees model of a scene as a runnable Tcl or Python script, and the golden log.

``export_script(scene, "tcl" | "py", path)`` writes ``path`` and ONE data folder beside it,
``<stem>_data/``: one text file per support record (one value a line, 17 significant digits, so
OpenSees reads back the very doubles used in process) and ``manifest.json`` (for each record its
channel, support node and dof, quantity and unit, time step, count and SHA-256; the recorder
files and how deckpound's columns follow from them; units; scene name and hash). The script
holds an audit header (:mod:`.export_header`), the same model and analysis commands as the
in-process run, standard OpenSees recorders named after deckpound's result columns
(:mod:`.recorders`) and the engine's step loop with its sub-step fallback (:mod:`.export_tcl`,
:mod:`.export_py`). Scene text is quoted or escaped for the script's language
(:mod:`.quoting`). Files are written to a temporary name and renamed into place.

Golden command log: :func:`golden_text` renders a scene's command log with floats printed to
12 significant digits and support records abbreviated to their length and a SHA-256; the
repository keeps the benchmark's as ``data/golden/saiidi-4span.opensees.log`` (written by
``python tools/golden_files.py``, repository tooling, not installed).
"""

from __future__ import annotations

import argparse
import hashlib
import json
from pathlib import Path

from deckpound.models.errors import SceneError
from deckpound.models.file_io import atomic_write_files
from deckpound.models.result import scene_hash
from deckpound.models.scene_io import load_scene
from deckpound.models.version import VERSION

from . import engine
from .export_header import UNITS, ExportParts
from .export_py import py_script
from .export_tcl import tcl_script
from .ops import ArrayArg, Command, OpsSession, render_commands
from .quoting import safe_file_name, tcl_word
from .recorders import PRECISION, manifest_entries, recorder_step, standard_recorders

MANIFEST_FORMAT = "deckpound-opensees-export-data/1"


def golden_text(scene, motion=None) -> str:
    """The golden rendering of the scene's command log."""
    log = engine.command_log(scene, motion)
    return render_commands(log, "log", golden=True)


# -- the parts of an export ------------------------------------------------------------------


def _records(log: list[Command], tags: dict, file_of: dict[str, str]) -> list[dict]:
    """One manifest entry per support record, from the timeSeries / groundMotion /
    imposedMotion commands of the log."""
    series, motions, where = {}, {}, {}
    for c in log:
        if c.name == "timeSeries" and any(isinstance(a, ArrayArg) for a in c.args):
            arr = next(a for a in c.args if isinstance(a, ArrayArg))
            series[c.args[1]] = (arr, float(c.args[list(c.args).index("-dt") + 1]))
        elif c.name == "groundMotion":
            a = list(c.args)
            motions[c.args[0]] = (a[a.index("-disp") + 1], a[a.index("-vel") + 1])
        elif c.name == "imposedMotion":
            where[c.args[2]] = (c.args[0], c.args[1])
    node_names = {t: n for n, t in tags.get("node", {}).items()}
    gm_names = {t: n for n, t in tags.get("groundMotion", {}).items()}
    out = []
    for gm, (ts_d, ts_v) in motions.items():
        node, dof = where[gm]
        for ts, quantity, unit in ((ts_d, "displacement", "m"), (ts_v, "velocity", "m/s")):
            arr, dt = series[ts]
            text = arr.file_text()
            out.append(
                {
                    "file": file_of[arr.name],
                    "channel": gm_names.get(gm, str(gm)),
                    "quantity": quantity,
                    "unit": unit,
                    "time_series": ts,
                    "ground_motion": gm,
                    "node": node,
                    "node_name": node_names.get(node, "?"),
                    "dof": dof,
                    "dt": dt,
                    "count": len(arr.values),
                    "sha256": hashlib.sha256(text.encode()).hexdigest(),
                }
            )
    return out


def export_parts(scene, fmt: str, stem: str, motion=None) -> tuple[ExportParts, dict[str, str]]:
    """(the parts of the ``fmt`` script, {data file name: text})."""
    if fmt not in ("tcl", "py"):
        raise SceneError("--format", f"must be 'tcl' or 'py', got {fmt!r}")
    with OpsSession() as ops:
        _, plan = engine.build(ops, scene, motion)
        log = list(ops.log)
        tags = {kind: ops.tags(kind) for kind in ops.kinds()}
    arrays = [a for c in log for a in c.args if isinstance(a, ArrayArg)]
    file_of = {a.name: safe_file_name(a.name) + ".txt" for a in arrays}
    if len(set(file_of.values())) != len(file_of):
        raise AssertionError("two support records map to one file name")
    files = {file_of[a.name]: a.file_text() for a in arrays}
    recs, maps = standard_recorders(plan, [b.name for b in scene.bents])
    parts = ExportParts(
        scene=scene,
        fmt=fmt,
        stem=stem,
        log=log,
        tags=tags,
        plan=plan,
        records=_records(log, tags, file_of),
        file_of=file_of,
        recorders=recs,
        maps=maps,
        rec_dt=recorder_step(plan),
        scene_hash=scene_hash(scene),
        data_dir=f"{stem}_data",
        out_dir=f"{stem}_results",
    )
    files["manifest.json"] = json.dumps(manifest(parts), indent=2, ensure_ascii=True) + "\n"
    return parts, files


def manifest(p: ExportParts) -> dict:
    """The data folder's manifest (JSON-able)."""
    return {
        "format": MANIFEST_FORMAT,
        "generator": f"deckpound {VERSION}",
        "scene": {"name": p.scene.name, "sha256": p.scene_hash},
        "units": {
            "force": "kN",
            "length": "m",
            "mass": "t",
            "time": "s",
            "angle": "rad",
            "text": UNITS,
        },
        "records": p.records,
        "recorders": {
            "dT": p.rec_dt,
            "precision": PRECISION,
            "dt": p.plan["dt"],
            "stride": p.plan["stride"],
            **manifest_entries(p.recorders, p.maps),
        },
    }


def script_text(scene, fmt: str, stem: str, motion=None) -> tuple[str, dict[str, str]]:
    """(script text, {data file name: text})."""
    parts, files = export_parts(scene, fmt, stem, motion)
    return (tcl_script(parts) if fmt == "tcl" else py_script(parts)), files


# -- writing -------------------------------------------------------------------------------


def _check_output(path: Path, fmt: str) -> None:
    if path.is_dir():
        raise SceneError("--output", f"{str(path)!r} is a folder; give a file name")
    if fmt == "tcl":
        try:
            tcl_word(str(path.resolve()))
        except ValueError as err:
            raise SceneError(
                "--output",
                f"{str(path)!r} cannot be used by a Tcl script: {err}; "
                "choose a path without such characters",
            ) from None
    data = path.parent / f"{path.stem}_data"
    if data.is_symlink() or (data.exists() and not data.is_dir()):
        raise SceneError(
            "--output",
            f"{str(data)!r} (the data folder of {path.name!r}) exists "
            "and is not a plain folder; remove it or choose another name",
        )


def export_script(scene, fmt: str, path, motion=None) -> Path:
    """Write a complete, runnable ``fmt`` ("tcl" | "py") script for the scene to ``path`` and
    its data folder ``<stem>_data/`` beside it. Returns the script path."""
    path = Path(path)
    _check_output(path, fmt)
    text, files = script_text(scene, fmt, path.stem, motion)
    data = path.parent / f"{path.stem}_data"
    made = not data.exists()
    try:
        # all files or none (deckpound.models.file_io): a full disk leaves no record cut short and no
        # script without its records; a symbolic link or device in their place is handled there
        atomic_write_files({**{data / n: c for n, c in files.items()}, path: text})
    except BaseException:
        if made and data.is_dir() and not any(data.iterdir()):
            data.rmdir()
        raise
    for old in data.iterdir():  # data files of an earlier export that this one has not
        if old.is_file() and old.name not in files:
            old.unlink()
    return path


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m deckpound.opensees_build.export", description=__doc__.splitlines()[0]
    )
    p.add_argument("--scene", default="saiidi-4span", help="built-in scene name or TOML file")
    p.add_argument("--format", choices=("tcl", "py"), default="py")
    p.add_argument("--out", required=True, help="script path to write")
    a = p.parse_args(argv)
    print(export_script(load_scene(a.scene), a.format, a.out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

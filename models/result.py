"""The one result type every engine returns, and its files.

A :class:`Result` holds time series on the engine's output time base (columns named as in
:func:`standard_columns`, SI units with tonnes) plus metadata: engine, engine settings, scene
hash, version, wall time, steps, iterations, contact events, status and message. Files:
``DIR/<engine>.csv`` (the columns) and ``DIR/<engine>.json`` (the metadata), written as a pair
all or nothing (temporary files renamed into place, :mod:`deckpound._io`), so an interruption
or a full disk leaves no partial file; a symbolic link in their place is refused.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ._fields import to_mapping
from .errors import SceneError

N_CORNERS = 4
STATUS_SUCCESS = "success"
STATUS_FAILED = "failed"


def standard_columns(bent_names: list[str] | tuple[str, ...]) -> list[str]:
    """Column names every engine writes, in order."""
    cols = ["t", "deck_x", "deck_y", "deck_theta", "seat1_x", "seat1_theta", "seat2_x",
            "seat2_theta"]
    cols += [f"gap_c{c}" for c in range(1, N_CORNERS + 1)]
    cols += [f"fn_c{c}" for c in range(1, N_CORNERS + 1)]
    cols += [f"ft_c{c}" for c in range(1, N_CORNERS + 1)]
    for b in bent_names:
        cols += [f"{b}_fx", f"{b}_fy"]
    return cols


def column_unit(name: str) -> str:
    """SI unit of a result column, from its name."""
    if name == "t":
        return "s"
    if name.endswith("_theta"):
        return "rad"
    if name.startswith(("gap_", "deck_", "seat", "ux_", "uy_")) or name.endswith(("_dx", "_dy")):
        return "m"
    if name.startswith(("fn_", "ft_")) or name.endswith(("_fx", "_fy")):
        return "kN"
    if name.startswith(("pn_", "pt_")):
        return "kN*s"
    if name.startswith("state_"):
        return "0 open, 1 stick, 2 slip"
    if name.startswith("energy_"):
        return "kJ"
    return "-"


def scene_hash(scene: Any) -> str:
    """SHA-256 of the scene's canonical JSON (every field, notes included)."""
    text = json.dumps(to_mapping(scene), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


@dataclass
class Result:
    """Time series of one engine run plus metadata.

    Attributes
    ----------
    engine:
        ``"opensees"``, ``"compliance"`` or ``"nonsmooth"``.
    columns:
        Column name → 1-D float array, all the same length; ``"t"`` first [s].
    meta:
        Metadata (settings, scene hash, wall_time [s], steps, iterations, contact_events,
        failures, status, message, failed_time [s], units).
    """

    engine: str
    columns: dict[str, np.ndarray]
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if "t" not in self.columns:
            raise ValueError("a Result needs a 't' column")
        n = len(self.columns["t"])
        for k, v in self.columns.items():
            arr = np.asarray(v, dtype=float)
            if arr.shape != (n,):
                raise ValueError(f"column {k!r} has shape {arr.shape}, expected ({n},)")
            self.columns[k] = arr
        self.meta.setdefault("engine", self.engine)
        self.meta.setdefault("status", STATUS_SUCCESS)
        self.meta.setdefault("message", "")
        self.meta["units"] = {k: column_unit(k) for k in self.columns}

    # -- access ----------------------------------------------------------------------
    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    @property
    def t(self) -> np.ndarray:
        return self.columns["t"]

    @property
    def ok(self) -> bool:
        return self.meta.get("status") == STATUS_SUCCESS

    def to_frame(self) -> pd.DataFrame:
        return pd.DataFrame(self.columns)

    # -- files -----------------------------------------------------------------------
    def write(self, folder: str | Path) -> tuple[Path, Path]:
        """Write ``<engine>.csv`` and ``<engine>.json`` into ``folder``, both or neither."""
        from deckpound._io import atomic_write_files, ensure_folder

        folder = ensure_folder(folder, "result folder")
        csv_path, json_path = folder / f"{self.engine}.csv", folder / f"{self.engine}.json"
        atomic_write_files({csv_path: self.csv_bytes(), json_path: self.json_bytes()},
                           field="result folder")
        return csv_path, json_path

    def csv_bytes(self) -> bytes:
        """The columns as CSV text (17 significant digits: floats round-trip exactly)."""
        return self.to_frame().to_csv(index=False, float_format="%.17g").encode()

    def json_bytes(self) -> bytes:
        """The metadata as JSON text."""
        return json.dumps(_jsonable(self.meta), indent=2, sort_keys=True).encode()

    @classmethod
    def read(cls, folder: str | Path, engine: str) -> Result:
        """Load a result written by :meth:`write` (a damaged file is refused by name)."""
        folder = Path(folder)
        csv_path, json_path = folder / f"{engine}.csv", folder / f"{engine}.json"
        for p in (csv_path, json_path):
            if not p.is_file():
                raise SceneError("result", f"file {str(p)!r} does not exist")
        try:
            csv_data, json_data = csv_path.read_bytes(), json_path.read_bytes()
        except OSError as err:
            raise SceneError("result", f"cannot read {str(folder)!r}: {err.strerror or err}") \
                from None
        return cls.from_bytes(engine, csv_data, json_data, source=str(folder))

    @classmethod
    def from_bytes(cls, engine: str, csv_data: bytes, json_data: bytes,
                   source: str = "result") -> Result:
        """A result from the contents of its two files; SceneError names what is damaged."""
        try:
            meta = json.loads(json_data.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as err:
            raise SceneError("result", f"{source}: {engine}.json is not valid JSON "
                             f"({str(err)[:120]})") from None
        if not isinstance(meta, dict):
            raise SceneError("result", f"{source}: {engine}.json must hold an object, got "
                             f"{type(meta).__name__}")
        try:
            frame = pd.read_csv(io.BytesIO(csv_data))
            cols = {str(k): frame[k].to_numpy(dtype=float) for k in frame.columns}
        except (ValueError, TypeError, pd.errors.ParserError, pd.errors.EmptyDataError,
                UnicodeDecodeError) as err:
            raise SceneError("result", f"{source}: {engine}.csv is not a table of numbers "
                             f"({str(err).splitlines()[0][:120] if str(err) else err!r})") from None
        if "t" not in cols:
            raise SceneError("result", f"{source}: {engine}.csv has no time column 't'")
        return cls(engine=engine, columns=cols, meta=meta)


def _jsonable(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj):
        return _jsonable(to_mapping(obj))
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, float) and not np.isfinite(obj):
        return str(obj)
    return obj


def set_status(meta: dict[str, Any], *, engine: str, ok: bool, message: str, step: int = 0,
               dt: float = 0.0, time: float | None = None, raise_on_failure: bool = False) -> None:
    """Fill ``status``/``message`` (and, on failure, ``failed_step``/``failed_time``) per the
    engine contract; on failure with ``raise_on_failure`` raise EngineFailure.

    ``message`` is the success summary, or on failure the reason (``"Newton did not
    converge"``), to which the step and time are appended. The failure time is ``step · dt``
    (fixed-step engines) unless ``time`` is given (adaptive steps) [s].
    """
    if ok:
        meta["status"] = STATUS_SUCCESS
        meta["message"] = message
        return
    t = step * dt if time is None else time
    meta["status"] = STATUS_FAILED
    meta["failed_step"] = step
    meta["failed_time"] = t
    meta["message"] = f"{message} at step {step} (t = {t:.6g} s)"
    if raise_on_failure:
        from .errors import EngineFailure

        raise EngineFailure(f"{engine} engine: {meta['message']}")

"""The one labelled result type every engine returns, and its files.

A :class:`Result` is frozen: the engine name, time-series columns on the engine's output time
base (SI units with tonnes; the standard columns of :mod:`deckpound.models.plan` first, then the
engine's extras) and metadata. Its units come from the plan model's column table
(:func:`column_unit`). Views: :meth:`Result.to_frame` (pandas, time as the index, units in
``attrs``) and :meth:`Result.to_xarray` (named dimensions time, corner, bent, direction).

Metadata every engine fills through the shared epilogue (:func:`deckpound.models.engine_contract.finish`):
``status`` (``"success"``; ``"doubtful"``: finished, but a quality check failed, see
``doubtful``; ``"unseated"``: a corner lost its seat and the run stopped there, see
``unseated``; or ``"failed"``), ``failure`` (a :class:`~deckpound.models.engine_contract.Status`
name), ``message``, ``failed_step``/``failed_time`` on failure, ``steps``, ``newton_iterations``,
``contact_solves``, ``gap_closures`` (see :func:`gap_closures`; ``gap_closures_basis``),
``peaks`` (``{column: [peak, time]}`` over every step, :meth:`Result.peak`; ``peaks_basis``),
``gap_opening_max`` (``{corner: [largest g − g(0) m, time s]}``, the seat-width demand),
``seat_margin_min`` (``{corner: [N − opening m, time s]}`` for the seats with a
``support_length``; ``seat_margin_basis``), ``unseated`` (with ``unseated_corner``,
``unseated_time``, ``unseated_step``; :func:`deckpound.models.engine_contract.seat_margins`),
``failures``, ``wall_time`` (run time without compilation) and ``compile_time`` [s],
``scene_hash``, ``physics_hash``, ``settings``, ``settings_hash``, ``version``, ``units``.

Files: ``DIR/<engine>.csv`` (the columns; each header cell names its unit, ``deck_theta [rad]``,
so a plain ``pandas.read_csv`` gives float columns; the time column rounded to the step's
resolution, :func:`rounded_time`) and ``DIR/<engine>.json`` (the metadata), written as a pair all or nothing (temporary files renamed
into place, :mod:`deckpound.models.file_io`), so an interruption or a full disk leaves no partial file; a
symbolic link in their place is refused. :meth:`Result.read` and :func:`read_table` also read the
files of earlier versions, whose units stood in a ``# units:`` comment line above a plain header.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import math
import weakref
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from deckpound.models.file_io import (
    atomic_write_files,
    csv_cell,
    ensure_folder,
    split_unit_label,
    unit_label,
)

from ._rows_text import format_array
from .columns import column_unit
from .errors import SceneError
from .fields import to_mapping
from .html_table import html_table, short_text
from .plan import BODY_QUANTITIES, CORNER_NAMES, RELATIVE_COLUMNS

if TYPE_CHECKING:  # annotations only
    import pandas as pd

__all__ = [
    "N_CORNERS",
    "STATUS_DOUBTFUL",
    "STATUS_FAILED",
    "STATUS_SUCCESS",
    "STATUS_UNSEATED",
    "TIME_DIGITS",
    "Result",
    "closure_times",
    "decimal_step",
    "display_unit",
    "gap_closures",
    "in_contact",
    "peak_columns",
    "physics_hash",
    "physics_mapping",
    "read_table",
    "rounded_time",
    "row_peak",
    "scene_hash",
    "settings_hash",
]

N_CORNERS = 4
STATUS_SUCCESS = "success"
STATUS_FAILED = "failed"
#: finished, but a quality check failed (``meta["doubtful"]`` says which and where)
STATUS_DOUBTFUL = "doubtful"
#: a deck corner lost its seat (its gap opened by more than ``seats[i].support_length``): the
#: run stopped at that step with its answer, not a numerical failure (``meta["unseated"]``)
STATUS_UNSEATED = "unseated"

#: Scene tables that do not change what an engine computes: engine settings (hashed separately,
#: per engine), the test sequence (a driver of runs), free text.
NON_PHYSICS = ("opensees", "compliance", "nonsmooth", "sequence", "notes", "description")


def _hash(obj: Any) -> str:
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()


#: the canonical JSON texts of live frozen descriptions, by (id, kind): a frozen description
#: never changes, and the cases of a sweep share all of the scene's tables but one (a seed, a
#: record), each asked for several times (cache keys, provenance); an entry goes when its
#: object is collected, so a new object never meets an old id's entry
_LIVE_TEXTS: dict[tuple[int, str], str] = {}


def _remembered(obj: Any, kind: str, make) -> str:
    """``make(obj)``, remembered for a frozen dataclass ``obj`` while it lives."""
    params = getattr(type(obj), "__dataclass_params__", None)
    if params is None or not params.frozen:
        return make(obj)
    key = (id(obj), kind)
    text = _LIVE_TEXTS.get(key)
    if text is None:
        text = make(obj)
        try:
            weakref.finalize(obj, _LIVE_TEXTS.pop, key, None)
        except TypeError:  # no weak references (slots): not remembered
            return text
        _LIVE_TEXTS[key] = text
    return text


def _fields_of(obj: Any) -> dict[str, Any]:
    """A description's fields as :func:`~deckpound.models.fields.to_mapping` keeps them (None
    dropped), values not converted."""
    out = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if v is not None:
            out[f.name] = v
    return out


def _mapping_text(items: dict) -> str:
    keys = sorted((str(k), k) for k in items)
    return "{" + ",".join(f"{_ascii_string(s)}:{canonical_json(items[k])}" for s, k in keys) + "}"


#: json's own string encoder (``ensure_ascii``: the C one where it is built)
_ascii_string = json.encoder.encode_basestring_ascii


def _float_text(x: float) -> str:
    """A float as ``json.dumps(_jsonable(x))`` writes it: its repr, a non-finite one as the
    string of its name."""
    return float.__repr__(x) if math.isfinite(x) else _ascii_string(str(x))


#: the text of a value of exactly these built-in types, as ``json.dumps`` writes it (the
#: scalars of a scene's tables: a fresh table of a sweep's case is mostly these, and one
#: ``json.dumps`` call per value cost more than its case's cache key needs; subclasses, as
#: enum members, take the general path)
_SCALAR_TEXT = {
    str: _ascii_string,
    bool: lambda b: "true" if b else "false",
    int: int.__repr__,
    float: _float_text,
    type(None): lambda _: "null",
}


def canonical_json(obj: Any) -> str:
    """The canonical JSON text of ``obj`` that the hashes are taken of:
    ``json.dumps(_jsonable(obj), sort_keys=True, separators=(",", ":"))`` with descriptions
    (dataclasses) as :func:`~deckpound.models.fields.to_mapping` writes them, built from the
    texts of its parts; the text of a frozen description is made once per object
    (:data:`_LIVE_TEXTS`), so the cases of a sweep, which share all of the scene's tables but
    one, cost one table each."""
    scalar = _SCALAR_TEXT.get(type(obj))
    if scalar is not None:
        return scalar(obj)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return _remembered(obj, "json", lambda o: _mapping_text(_fields_of(o)))
    if isinstance(obj, dict):
        return _mapping_text(obj)
    if isinstance(obj, (list, tuple)):
        return "[" + ",".join(canonical_json(v) for v in obj) + "]"
    return json.dumps(_jsonable(obj), sort_keys=True, separators=(",", ":"))


def scene_hash(scene: Any) -> str:
    """SHA-256 of the scene's canonical JSON (every field, notes included): provenance."""
    return _remembered(scene, "scene", _hash)


def physics_mapping(scene: Any) -> dict[str, Any]:
    """The scene without engine settings, sequence and free text: what every engine models."""
    return {k: v for k, v in to_mapping(scene).items() if k not in NON_PHYSICS}


def _physics_hash_of(scene: Any) -> str:
    parts = _fields_of(scene) if dataclasses.is_dataclass(scene) else to_mapping(scene)
    return _hash({k: v for k, v in parts.items() if k not in NON_PHYSICS})


def physics_hash(scene: Any) -> str:
    """SHA-256 of :func:`physics_mapping`: the part of a cache key shared by every engine."""
    return _remembered(scene, "physics", _physics_hash_of)


def settings_hash(settings: Any) -> str:
    """SHA-256 of an engine's settings (a dataclass or mapping)."""
    return _hash(settings)


def closure_times(t: np.ndarray, gap: np.ndarray, fn: np.ndarray | None = None) -> np.ndarray:
    """Times of the gap closures of one corner [s] (see :func:`gap_closures`)."""
    closed = in_contact({"gap_c": gap} | ({"fn_c": fn} if fn is not None else {}), "c")
    if not len(closed):
        return t[:0]
    onset = np.concatenate([[closed[0]], closed[1:] & ~closed[:-1]])
    return t[onset]


def in_contact(columns: dict[str, np.ndarray], corner: str) -> np.ndarray | None:
    """Whether a corner is in contact at each output row: its gap is closed (g ≤ 0) or it
    carried a normal force over the row (fn > 0; for the nonsmooth engine fn is the impulse of
    the output interval divided by its length, so a rigid impact that leaves g ≥ 0 counts).

    The one contact test: the engines apply it at every step
    (:func:`deckpound.analytic.kernels.peaks.in_contact_now`, and the OpenSees loop and the exported
    scripts with the same two comparisons). For every penalty law the force is zero while
    g > 0, so it is g ≤ 0 there; the force term is for rigid contact, whose impact impulse can
    reverse the approach within a step and leave g ≥ 0 at both ends of it."""
    g = columns.get(f"gap_{corner}")
    if g is None:
        return None
    closed = g <= 0.0
    fn = columns.get(f"fn_{corner}")
    if fn is not None:
        closed = closed | (fn > 0.0)
    return closed


def gap_closures(columns: dict[str, np.ndarray]) -> dict[str, int]:
    """Gap closures per corner on output rows: the rows at which a corner goes from out of
    contact to in contact (:func:`in_contact`), the first row counting when it starts in
    contact.

    The definition of ``gap_closures`` is this, applied at **every step**: the engines count
    it in their step loops (``meta["gap_closures_basis"] = "every step"``; a closure between
    two output rows is not lost, so the count does not depend on ``run.output_dt``). This
    function is the fallback for results without that count (measured data, old results:
    basis ``"output rows"``)."""
    out = {}
    corners = [k[4:] for k in columns if k.startswith("gap_")] or list(CORNER_NAMES)
    for c in corners:
        closed = in_contact(columns, c)
        if closed is None or not len(closed):
            out[c] = 0
            continue
        out[c] = int(closed[0]) + int(np.count_nonzero(closed[1:] & ~closed[:-1]))
    return out


#: a deck segment's own columns ``<segment>_<quantity>`` (:meth:`Result.to_xarray` stacks them)
SEGMENT_QUANTITIES = tuple(q for group in BODY_QUANTITIES for q in group)


def peak_columns(engine_columns, bent_names, relative=RELATIVE_COLUMNS) -> list[str]:
    """The columns whose peaks the engines track at every step, in their order: the engine
    columns (``t`` first, :func:`deckpound.models.engine_contract.engine_columns`), the relative
    displacements (``relative``: the plan's :attr:`~deckpound.models.plan.Plan.relative_columns`,
    :data:`deckpound.models.plan.RELATIVE_COLUMNS` for a one-segment deck), then the bent
    deformations ``<bent>_dx``, ``<bent>_dy`` (the columns the epilogue derives from the output
    rows)."""
    out = list(engine_columns) + list(relative)
    for b in bent_names:
        out += [f"{b}_dx", f"{b}_dy"]
    return out


def _frozen_column(values: Any) -> np.ndarray:
    """A result column as a read-only float array.

    A read-only float64 array is taken as it is, without a copy: the engines hand over views of
    their output table (:func:`deckpound.analytic.bundles.result_columns`) and so a run holds
    its histories once; whoever hands over a read-only array promises not to change it through
    another view. Anything else (a writeable array, a list) is copied, so the caller's object
    and the result never share memory."""
    if isinstance(values, np.ndarray) and values.dtype == np.float64 and not values.flags.writeable:
        return values
    return np.array(values, dtype=float)


def row_peak(name: str, t: np.ndarray, x: np.ndarray) -> tuple[float, float]:
    """(peak, time [s]) of a column on its rows: the largest |x| and its first time; for a
    gap column (``gap_*``) the smallest (most negative) value. (nan, nan) without rows."""
    if not len(x):
        return float("nan"), float("nan")
    k = int(np.argmin(x)) if name.startswith("gap_") else int(np.argmax(np.abs(x)))
    return (float(x[k]) if name.startswith("gap_") else float(abs(x[k]))), float(t[k])


@dataclass(frozen=True)
class Result:
    """Time series of one engine run plus metadata (frozen; columns are read-only arrays).

    Attributes
    ----------
    engine : the engine's registry name (or ``"measured"``).
    columns : column name → 1-D float array, all the same length; ``"t"`` first [s].
    meta : metadata (see the module docstring); ``meta["units"]`` maps every column to its unit.
    """

    engine: str
    columns: dict[str, np.ndarray]
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if "t" not in self.columns:
            raise ValueError("a Result needs a 't' column")
        n = len(self.columns["t"])
        cols = {}
        for k, v in self.columns.items():
            arr = _frozen_column(v)
            if arr.shape != (n,):
                raise ValueError(f"column {k!r} has shape {arr.shape}, expected ({n},)")
            arr.flags.writeable = False
            cols[k] = arr
        meta = dict(self.meta)
        meta.setdefault("engine", self.engine)
        meta.setdefault("status", STATUS_SUCCESS)
        meta.setdefault("message", "")
        meta["units"] = {k: column_unit(k) for k in cols}
        if "gap_c1" in cols and "gap_closures" not in meta:
            per = gap_closures(cols)
            meta["gap_closures"] = sum(per.values())
            meta["gap_closures_per_corner"] = per
            meta["gap_closures_basis"] = "output rows"
        object.__setattr__(self, "columns", cols)
        object.__setattr__(self, "meta", meta)

    # -- access ----------------------------------------------------------------------
    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    @property
    def t(self) -> np.ndarray:
        return self.columns["t"]

    @property
    def ok(self) -> bool:
        """True for a run that finished and passed every quality check."""
        return self.meta.get("status") == STATUS_SUCCESS

    @property
    def finished(self) -> bool:
        """True for a run that reached an answer: ``success``, ``doubtful`` (a quality check
        failed) or ``unseated`` (a corner lost its seat; the run stops there)."""
        return self.meta.get("status") in (STATUS_SUCCESS, STATUS_DOUBTFUL, STATUS_UNSEATED)

    @property
    def doubtful(self) -> bool:
        """True for a run that finished but failed a quality check (``meta["doubtful"]``)."""
        return self.meta.get("status") == STATUS_DOUBTFUL

    @property
    def unseated(self) -> bool:
        """True for a run that stopped because a deck corner lost its seat
        (``meta["unseated_corner"]``, ``meta["unseated_time"]``; the status is
        ``"unseated"`` unless a quality check made it ``"doubtful"``)."""
        return bool(self.meta.get("unseated", False))

    @property
    def has_histories(self) -> bool:
        """False for a summary-only run (``Engine.run(..., summary_only=True)``): no rows, its
        peaks, closures, seat margins and final energies are in ``meta``."""
        return bool(self.meta.get("histories", True))

    @property
    def units(self) -> dict[str, str]:
        return dict(self.meta["units"])

    @property
    def gap_closures(self) -> int:
        """Total gap closures (every step when the engine counted them, else on the output
        rows: ``meta["gap_closures_basis"]``; see :func:`gap_closures`)."""
        return int(self.meta.get("gap_closures", 0))

    # -- short text for consoles and notebooks ---------------------------------------
    def summary(self) -> dict[str, str]:
        """The run's key facts as short texts: engine, status, duration [s], rows, column
        count, peak deck rotation θ_d [rad] (:meth:`peak`) and gap closures; what
        :meth:`__repr__` and :meth:`_repr_html_` show."""
        t = self.t
        facts = {
            "engine": self.engine,
            "status": str(self.meta.get("status")),
            "duration": f"{t[-1] - t[0]:g} s" if len(t) else f"{self.meta.get('duration', 0):g} s",
            "rows": f"{len(t)}" if self.has_histories else "none (summary only)",
            "columns": f"{len(self.columns)}",
        }
        if "deck_theta" in self.columns or "deck_theta" in (self.meta.get("peaks") or {}):
            facts["peak θ_d"] = f"{self.peak('deck_theta'):.4g} rad"
        if "gap_closures" in self.meta:
            facts["gap closures"] = f"{self.gap_closures}"
        message = str(self.meta.get("message") or "")
        if message and not self.ok:
            facts["message"] = message
        return facts

    def __repr__(self) -> str:
        facts = self.summary()
        facts.pop("message", None)  # free text of any length: in the HTML table only
        head = f"Result({short_text(facts.pop('engine'))!r}"
        return head + "".join(f", {k} {v}" for k, v in facts.items()) + ")"

    def _repr_html_(self) -> str:
        """An HTML table of :meth:`summary` for notebooks (every text escaped)."""
        return html_table("Result", self.summary())

    # -- figures ---------------------------------------------------------------------
    def plot(self, columns=("deck_theta",), ax=None, *, label: str | None = None, **line: Any):
        """Time histories of ``columns`` as a matplotlib figure (returned, not shown).

        Without ``ax``, one panel per column sharing the time axis; with ``ax``, every column
        on that axes (to overlay runs: ``r2.plot(ax=r1.plot().axes[0])``). Lengths are drawn
        in mm and angles in mrad (:func:`display_unit`), the unit in each axis label; ``label``
        names the line (default: the engine, plus the column when several share one axes);
        ``line`` goes to ``Axes.plot`` (color, linestyle, ...). The figure is not registered
        with pyplot (no ``plt.show``, no figure left open in a loop); a notebook displays it.
        """
        from matplotlib.figure import Figure

        names = (columns,) if isinstance(columns, str) else tuple(columns)
        if not names:
            raise ValueError("plot needs at least one column")
        for c in names:
            if c not in self.columns:
                raise KeyError(
                    f"no column {c!r} in the {self.engine} result; it has: "
                    + ", ".join(k for k in self.columns if k != "t")
                )
        if ax is None:
            fig = Figure(figsize=(7.0, 0.6 + 2.0 * len(names)), layout="constrained")
            axes = list(fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0])
        else:
            fig, axes = ax.figure, [ax] * len(names)
        shared = ax is not None and len(names) > 1
        for a, c in zip(axes, names, strict=True):
            scale, unit = display_unit(column_unit(c))
            text = label if label is not None else self.engine
            a.plot(self.t, scale * self.columns[c], label=f"{text} {c}" if shared else text, **line)
            a.set_ylabel(f"{c} [{unit}]" if not shared else f"[{unit}]")
            a.grid(True, alpha=0.3)
            a.legend(loc="upper right")
        axes[-1].set_xlabel("time [s]")
        return fig

    # -- peaks -----------------------------------------------------------------------
    def _step_peak(self, column: str):
        peaks = self.meta.get("peaks")
        entry = peaks.get(column) if isinstance(peaks, dict) else None
        if column not in self.columns and (self.has_histories or entry is None):
            raise KeyError(f"no column {column!r} in the {self.engine} result")
        return entry if entry is not None and len(entry) == 2 else None

    def peak(self, column: str) -> float:
        """The peak of a column: the largest |x| (for a gap, ``gap_*``, the smallest, most
        negative value: the deepest penetration) over **every step** of the run when the engine
        measured it (``meta["peaks"]``), else over the output rows (measured data, old results,
        columns an engine does not track: energies, impulses); :meth:`peak_basis` says which.
        NaN for a result without rows."""
        entry = self._step_peak(column)
        if entry is not None:
            return float(entry[0])
        return row_peak(column, self.t, self.columns[column])[0]

    def peak_time(self, column: str) -> float:
        """The first time [s] at which :meth:`peak` is reached (same basis)."""
        entry = self._step_peak(column)
        if entry is not None:
            return float(entry[1])
        return row_peak(column, self.t, self.columns[column])[1]

    def peak_basis(self, column: str) -> str:
        """``"every step"`` or ``"output rows"``: what :meth:`peak` of ``column`` is taken
        over."""
        return "every step" if self._step_peak(column) is not None else "output rows"

    def with_meta(self, **changes: Any) -> Result:
        """A copy with metadata entries added or replaced."""
        return Result(engine=self.engine, columns=self.columns, meta={**self.meta, **changes})

    def to_frame(self):
        """pandas DataFrame with time [s] as the index; ``attrs`` holds units, engine, status."""
        import pandas as pd  # tables only (0.3-0.6 s to import; a run does not need it)

        frame = pd.DataFrame(
            {k: v for k, v in self.columns.items() if k != "t"}, index=pd.Index(self.t, name="t")
        )
        frame.attrs = {
            "units": self.units,
            "engine": self.engine,
            "status": self.meta.get("status"),
            # {column: [peak, time]} over every step (Result.peak); the rows may miss them
            "peaks": dict(self.meta.get("peaks") or {}),
        }
        return frame

    def to_xarray(self):
        """xarray Dataset with named dimensions ``time``, ``corner``, ``bent``, ``direction``
        (and ``segment`` for a deck of segments).

        Per-corner columns (``gap_c1``…, ``fn_``, ``ft_``, ``pn_``, ``pt_``, ``state_``) become
        one variable over (time, corner); bent forces and deformations (``<bent>_fx``…) one
        variable each over (time, bent, direction); a deck of segments' columns
        (``<segment>_theta``…) one variable each over (time, segment), named
        ``segment_<quantity>`` (``segment_theta``, ``segment_x_rel``, …); everything else a
        variable over time. Units are in each variable's ``attrs["units"]``.
        """

        t = self.t
        units = self.meta["units"]
        data_vars: dict[str, Any] = {}
        used: set[str] = {"t"}
        corners = [k[4:] for k in self.columns if k.startswith("gap_")] or list(CORNER_NAMES)
        prefixes = sorted(
            {k[: -len(c) - 1] for k in self.columns for c in corners if k.endswith(f"_{c}")}
        )
        for p in prefixes:
            names = [f"{p}_{c}" for c in corners]
            if all(n in self.columns for n in names):
                data_vars[p] = (
                    ("time", "corner"),
                    np.column_stack([self[n] for n in names]),
                    {"units": units[names[0]]},
                )
                used.update(names)
        segments = [s["name"] for s in (self.meta.get("scene") or {}).get("segments") or ()]
        for q in SEGMENT_QUANTITIES if segments else ():
            names = [f"{s}_{q}" for s in segments]
            if all(n in self.columns for n in names):
                data_vars[f"segment_{q}"] = (
                    ("time", "segment"),
                    np.column_stack([self[n] for n in names]),
                    {"units": units[names[0]]},
                )
                used.update(names)
        bents = [b for b in self.meta.get("bent_names", []) if f"{b}_fx" in self.columns]
        for kind, stem in (("f", "bent_force"), ("d", "bent_deformation")):
            names = [[f"{b}_{kind}x", f"{b}_{kind}y"] for b in bents]
            if bents and all(n in self.columns for pair in names for n in pair):
                arr = np.stack([np.column_stack([self[n] for n in pair]) for pair in names], axis=1)
                data_vars[stem] = (
                    ("time", "bent", "direction"),
                    arr,
                    {"units": units[names[0][0]]},
                )
                used.update(n for pair in names for n in pair)
        for k, v in self.columns.items():
            if k not in used:
                data_vars[k] = (("time",), v, {"units": units[k]})
        coords: dict[str, Any] = {"time": ("time", t, {"units": "s"}), "corner": corners}
        if segments:
            coords["segment"] = segments
        if bents:
            coords["bent"] = bents
            coords["direction"] = ["x", "y"]
        import xarray as xr  # notebooks only (pulls in pandas: 0.3 s a run does not need)

        ds = xr.Dataset(data_vars, coords=coords)
        ds.attrs = {
            "engine": self.engine,
            "status": str(self.meta.get("status")),
            "message": str(self.meta.get("message", "")),
        }
        return ds

    # -- files -----------------------------------------------------------------------
    def write(self, folder: str | Path) -> tuple[Path, Path]:
        """Write ``<engine>.csv`` and ``<engine>.json`` into ``folder``, both or neither."""

        folder = ensure_folder(folder, "result folder")
        csv_path, json_path = folder / f"{self.engine}.csv", folder / f"{self.engine}.json"
        atomic_write_files(
            {csv_path: self.csv_bytes(), json_path: self.json_bytes()},
            field="result folder",
        )
        return csv_path, json_path

    def csv_bytes(self, exact_time: bool = False) -> bytes:
        """The columns as CSV: the header (``t [s],deck_x_abs [m],…``: each column's unit in
        its name, :func:`deckpound.models.file_io.unit_label`), then the rows (the shortest text
        of each double that reads back as the same double: ``repr``'s text, written by
        ``orjson``, see :mod:`._rows_text`). The time column is written rounded to the step's
        resolution (:func:`rounded_time`: ``0.175``, not the ``0.17500000000000002`` of k·Δt);
        ``exact_time`` writes it as computed (the result cache, whose results must come back
        bit-identical). Every other column is written exactly."""

        names = list(self.columns)
        head = ",".join(csv_cell(unit_label(n, column_unit(n))) for n in names)
        cols = [self.columns[n] for n in names]
        if "t" in self.columns and not exact_time:
            cols[names.index("t")] = rounded_time(self.columns["t"])
        arr = np.column_stack(cols) if names else np.empty((0, 0))
        body = format_array(arr)
        return (head + "\n" + body).encode()

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
            raise SceneError(
                "result", f"cannot read {str(folder)!r}: {err.strerror or err}"
            ) from None
        return cls.from_bytes(engine, csv_data, json_data, source=str(folder))

    @classmethod
    def from_bytes(
        cls, engine: str, csv_data: bytes, json_data: bytes, source: str = "result"
    ) -> Result:
        """A result from the contents of its two files; SceneError names what is damaged."""
        import pandas as pd  # tables only (0.3-0.6 s to import; a run does not need it)

        try:
            meta = json.loads(json_data.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as err:
            raise SceneError(
                "result", f"{source}: {engine}.json is not valid JSON ({str(err)[:120]})"
            ) from None
        if not isinstance(meta, dict):
            raise SceneError(
                "result", f"{source}: {engine}.json must hold an object, got {type(meta).__name__}"
            )
        try:
            frame = read_table(io.BytesIO(csv_data))
            cols = {str(k): frame[k].to_numpy(dtype=float) for k in frame.columns}
        except (
            ValueError,
            TypeError,
            pd.errors.ParserError,
            pd.errors.EmptyDataError,
            UnicodeDecodeError,
        ) as err:
            raise SceneError(
                "result",
                f"{source}: {engine}.csv is not a table of numbers "
                f"({str(err).splitlines()[0][:120] if str(err) else err!r})",
            ) from None
        if "t" not in cols:
            raise SceneError("result", f"{source}: {engine}.csv has no time column 't'")
        return cls(engine=engine, columns=cols, meta=meta)


#: significant digits of the output step kept in a written time column (:func:`rounded_time`)
TIME_DIGITS = 12
#: a step is a decimal one when it has at most this many significant digits (0.005, 0.01, 0.002)
#: up to round-off (relative 1e-9): only such grids are rounded
STEP_DIGITS = 6
#: round-off of k·Δt a rounded time may remove, in units in the last place of the time
ROUNDOFF_ULPS = 8


def decimal_step(step: float) -> float | None:
    """``step`` [s] as the decimal it stands for (``0.004999999999999893`` → ``0.005``): its
    :data:`STEP_DIGITS` significant digits, if they are within 1e-9·Δt of it, else None (a step
    such as 1/30 s has no short decimal)."""
    if not (np.isfinite(step) and step > 0):
        return None
    short = float(f"{step:.{STEP_DIGITS}g}")
    return short if abs(short - step) <= 1e-9 * step else None


def rounded_time(t: np.ndarray, step: float | None = None) -> np.ndarray:
    """A time base [s] with the round-off of k·Δt taken out: a time within
    :data:`ROUNDOFF_ULPS` units in the last place of a grid time k·Δt is written as that grid
    time rounded to :data:`TIME_DIGITS` (12) significant digits of the step, i.e. to the decimal
    place 10^(⌊log10 Δt⌋ − 11) (``0.17500000000000002`` → ``0.175`` for Δt = 0.005 s). Times
    off the grid (an adaptive engine's event rows) and grids whose step is not a short decimal
    (:func:`decimal_step`; Δt = 1/30 s) are kept bit for bit. ``step`` defaults to the median
    spacing of ``t``. The decimal place is capped so that the largest |t| keeps 15 significant
    digits. Applied where time bases are written or made (result files, the aligned base), never
    inside the engines."""

    t = np.asarray(t, dtype=float)
    if step is None:
        step = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    step = decimal_step(step)
    largest = float(np.max(np.abs(t))) if len(t) else 0.0
    if step is None or not np.isfinite(largest):
        return t.copy()
    decimals = TIME_DIGITS - 1 - int(np.floor(np.log10(step)))
    if largest > 0:
        decimals = min(decimals, 14 - int(np.floor(np.log10(largest))))
    grid = np.round(np.rint(t / step) * step, decimals)
    on_grid = np.abs(grid - t) <= ROUNDOFF_ULPS * np.spacing(np.abs(t))
    return np.where(on_grid, grid, t)


def read_table(source, **read_csv_options) -> pd.DataFrame:
    """A CSV table deckpound wrote (a path or a binary stream) with plain column names
    (``deck_theta``) and the units in ``frame.attrs["units"]`` (name → unit).

    Reads both header formats: ``name [unit]`` cells (this version) and a plain header below a
    ``# units: s,m,…`` comment line (result files of earlier versions), without a warning.
    ``read_csv_options`` go to :func:`pandas.read_csv` (``keep_default_na=False``)."""
    import pandas as pd  # tables only (0.3-0.6 s to import; a run does not need it)

    if isinstance(source, (str, Path)):
        source = io.BytesIO(Path(source).read_bytes())
    data = source.read()
    first = data.split(b"\n", 1)[0].strip()
    old_units: list[str] = []
    if first.startswith(b"#") and first[1:].strip().startswith(b"units:"):
        old_units = first[1:].strip()[len(b"units:") :].decode("utf-8").strip().split(",")
    frame = pd.read_csv(io.BytesIO(data), skiprows=1 if old_units else None, **read_csv_options)
    if old_units and len(old_units) != len(frame.columns):
        # a unit with commas of its own (the contact states') split the comment line
        old_units = [column_unit(str(c)) for c in frame.columns]
    names, units = [], {}
    for i, header in enumerate(frame.columns):
        name, unit = split_unit_label(str(header))
        if unit is None and i < len(old_units) and old_units[i].strip():
            unit = old_units[i].strip()
        names.append(name)
        if unit is not None:
            units[name] = unit
    frame.columns = names
    frame.attrs["units"] = units
    return frame


#: units drawn in figures at a readable scale: SI unit → (factor, shown unit)
DISPLAY_UNITS = {"m": (1e3, "mm"), "rad": (1e3, "mrad"), "m/s": (1e3, "mm/s")}


def display_unit(unit: str) -> tuple[float, str]:
    """(factor, unit) a column in SI ``unit`` is drawn in: lengths in mm, angles in mrad (the
    paper figures' units, :mod:`deckpound.compare.report.figures`); other units as they are."""
    return DISPLAY_UNITS.get(unit, (1.0, unit))


def _jsonable(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return _jsonable(to_mapping(obj))
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return _jsonable(obj.item())
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, float) and not np.isfinite(obj):
        return str(obj)
    if hasattr(obj, "value") and hasattr(obj, "name") and isinstance(obj.value, str):
        return obj.value  # enum members
    return obj

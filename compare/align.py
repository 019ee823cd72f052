"""Put results of different engines on one time base.

Rules
-----
* Common base: t_k = k·dt from 0 to the earliest end time among the results; dt defaults to
  the finest output step among them; a decimal dt is taken as such (``0.005``) and t_k are
  rounded to the step's resolution (12 significant digits of dt,
  :func:`deckpound.models.result.rounded_time`), so the base has no round-off digits.
* Kinematic columns (displacements, rotations, gaps, spring forces): linear interpolation
  when the base is at least as fine as the source. When the base is coarser, each base sample
  takes the source sample of largest magnitude in its bin [t_k − dt/2, t_k + dt/2): the series
  keeps its peaks exactly instead of interpolating them away.
* Contact forces (``fn_*``, ``ft_*``): averaged over each bin so that the impulse ∫λ dt is
  conserved (the source is integrated as a piecewise-linear signal, the bin average is the
  integral over the bin divided by its length). Impulse columns (``pn_*``, ``pt_*``: impulse
  per output interval of the nonsmooth engine) are summed into bins.

Tables: :func:`long_table` (engine, t, quantity, value) and :func:`wide_tables`
(one frame per engine), written by :func:`write_tables` as Parquet and/or CSV with units.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.report.outputs import folder as make_folder
from deckpound.compare.report.outputs import write_csv, write_parquet
from deckpound.models.columns import column_unit
from deckpound.models.result import Result, decimal_step, rounded_time

FORCE_PREFIXES = ("fn_", "ft_")
IMPULSE_PREFIXES = ("pn_", "pt_")


def common_time_base(results: dict[str, Result], dt: float | None = None) -> np.ndarray:
    """t_k = k·dt, k = 0.., up to the earliest end time of the results [s].

    The default dt is the finest median output step, taken as the decimal it stands for
    (:func:`~deckpound.models.result.decimal_step`: ``0.005``, not the ``0.004999999999999893``
    a median of differences of k·Δt gives), and each t_k is rounded to the step's resolution
    (:func:`~deckpound.models.result.rounded_time`), so the base holds the grid's decimal times."""
    if not results:
        raise ValueError("no results to align")
    steps = [float(np.median(np.diff(r.t))) for r in results.values() if len(r.t) > 1]
    if dt is None:
        dt = decimal_step(min(steps)) or min(steps)
    end = min(r.t[-1] for r in results.values())
    n = int(np.floor(end / dt + 1e-9))
    return rounded_time(np.arange(n + 1) * dt, dt)


def _cumulative_integral(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(0.5 * (x[1:] + x[:-1]) * np.diff(t))])


def bin_average(t_src: np.ndarray, x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Average of a piecewise-linear signal over bins centred on t (impulse-conserving)."""
    dt = t[1] - t[0] if len(t) > 1 else 1.0
    edges = np.concatenate([[t[0] - 0.5 * dt], 0.5 * (t[1:] + t[:-1]), [t[-1] + 0.5 * dt]])
    edges = np.clip(edges, t_src[0], t_src[-1])
    F = _cumulative_integral(t_src, x)
    I = np.interp(edges, t_src, F)
    width = np.diff(edges)
    with np.errstate(invalid="ignore", divide="ignore"):
        avg = np.where(width > 0, np.diff(I) / np.where(width > 0, width, 1.0), 0.0)
    return avg


def bin_sum(t_src: np.ndarray, x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Sum of samples falling in each bin centred on t (for impulses per interval)."""
    dt = t[1] - t[0] if len(t) > 1 else 1.0
    idx = np.floor((t_src - t[0]) / dt + 0.5).astype(int)
    keep = (idx >= 0) & (idx < len(t))
    return np.bincount(idx[keep], weights=x[keep], minlength=len(t))[: len(t)]


def peak_preserving(t_src: np.ndarray, x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Linear interpolation, or largest-magnitude sample per bin when t is coarser."""
    src_dt = float(np.median(np.diff(t_src))) if len(t_src) > 1 else 0.0
    dt = t[1] - t[0] if len(t) > 1 else 0.0
    if dt <= src_dt * (1 + 1e-9):
        return np.interp(t, t_src, x)
    idx = np.floor((t_src - t[0]) / dt + 0.5).astype(int)
    out = np.interp(t, t_src, x)
    keep = (idx >= 0) & (idx < len(t))
    order = np.argsort(np.abs(x[keep]), kind="stable")  # later (larger) writes win
    out[idx[keep][order]] = x[keep][order]
    return out


def align_column(name: str, t_src: np.ndarray, x: np.ndarray, t: np.ndarray) -> np.ndarray:
    if name.startswith(FORCE_PREFIXES):
        return bin_average(t_src, x, t)
    if name.startswith(IMPULSE_PREFIXES):
        return bin_sum(t_src, x, t)
    return peak_preserving(t_src, x, t)


def align(
    results: dict[str, Result], dt: float | None = None, columns: list[str] | None = None
) -> dict[str, pd.DataFrame]:
    """Wide frames (one per engine/label) on the common time base."""
    t = common_time_base(results, dt)
    if columns is None:
        sets = [set(r.columns) - {"t"} for r in results.values()]
        first = [c for c in next(iter(results.values())).columns if c != "t"]
        columns = [c for c in first if all(c in s for s in sets)]
    out = {}
    for label, r in results.items():
        data = {"t": t}
        # the source times at the base's resolution: a source on the base's grid is sampled
        # at its own rows, not blended with a neighbour over k·Δt's round-off
        t_src = rounded_time(r.t)
        for c in columns:
            data[c] = align_column(c, t_src, r[c], t)
        out[label] = pd.DataFrame(data)
    return out


def long_table(aligned: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """(engine, t, quantity, value) rows from aligned wide frames."""
    parts = []
    for label, frame in aligned.items():
        m = frame.melt(id_vars="t", var_name="quantity", value_name="value")
        m.insert(0, "engine", label)
        parts.append(m)
    return pd.concat(parts, ignore_index=True)


def write_tables(
    aligned: dict[str, pd.DataFrame],
    folder: str | Path,
    formats: tuple[str, ...] = ("parquet", "csv"),
    long: bool = True,
) -> list[Path]:
    """``aligned_<engine>`` (wide) and, with ``long``, ``aligned_long`` tables in ``folder``,
    in each of ``formats`` (``parquet``: units in the schema metadata; ``csv``: units in the
    header, ``deck_theta [rad]``; the long table's ``value`` column has the unit of its row's
    quantity, listed in a ``unit`` column)."""

    out = make_folder(folder)
    unknown = set(formats) - {"parquet", "csv"}
    if unknown:
        raise ValueError(f"unknown table format(s) {sorted(unknown)}; use parquet or csv")
    frames = {f"aligned_{k}": v for k, v in aligned.items()}
    if long:
        table = long_table(aligned)
        table.insert(3, "unit", table["quantity"].map(column_unit))
        frames = {"aligned_long": table, **frames}
    written = []
    for name, frame in frames.items():
        units = {
            c: column_unit(c)
            for c in frame.columns
            if c not in ("engine", "quantity", "unit", "value")
        }
        for fmt in formats:
            p = out / f"{name}.{fmt}"
            if fmt == "parquet":
                write_parquet(frame, p, units)
            else:
                write_csv(frame, p, units)
            written.append(p)
    return written

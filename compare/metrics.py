"""Comparison metrics between two time series (engine vs reference, or vs measured data).

For a quantity x (test) and r (reference) on one time base t:

* peak            P(x) = max |x| over **every step** of the run (:meth:`Result.peak
                  <deckpound.models.result.Result.peak>`; for a gap the smallest, most
                  negative value; the output rows only for results without every-step
                  peaks: measured data, old results); ``peak_ratio`` = P(x) / P(r)
* time of peak    t at which P(x) is reached (:meth:`Result.peak_time`, same basis)
* NRMSE           √(mean((x − r)²)) / max |r| on the aligned rows
* correlation     Pearson ρ(x, r) (NaN when either is constant)
* residual        mean of x over the last 2 % of the record (permanent offset)
* gap closures    steps at which a corner goes from out of contact to in contact, counted at
  every step by the engines (``meta["gap_closures"]``, the one definition:
  :func:`deckpound.models.result.gap_closures`); their times on the output rows

Table columns: ``peak``, ``peak_ref``, ``residual`` and ``residual_ref`` are in the unit of the
row's quantity, named in its ``unit`` column; the others have one unit each (:data:`METRIC_UNITS`).

Peaks and times are each engine's own, over every step, so neither alignment nor the output rate
can blunt them; NRMSE and correlation compare the aligned rows.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from deckpound.models.columns import column_unit
from deckpound.models.errors import SceneError
from deckpound.models.motion import check_time_base
from deckpound.models.result import Result, closure_times

#: units of the metric table's columns that have one unit for every row
METRIC_UNITS = {
    "t_peak": "s",
    "t_peak_ref": "s",
    "nrmse": "-",
    "correlation": "-",
    "peak_ratio": "-",
}


def peak(x: np.ndarray) -> float:
    """max |x| of an array (rows); a result's peak is :meth:`Result.peak`, over every step."""
    return float(np.max(np.abs(x))) if len(x) else float("nan")


def time_of_peak(t: np.ndarray, x: np.ndarray) -> float:
    return float(t[int(np.argmax(np.abs(x)))])


def nrmse(x: np.ndarray, r: np.ndarray) -> float:
    p = peak(r)
    return float(np.sqrt(np.mean((x - r) ** 2)) / p) if p > 0 else float("nan")


def correlation(x: np.ndarray, r: np.ndarray) -> float:
    if np.std(x) == 0 or np.std(r) == 0:
        return float("nan")
    return float(np.corrcoef(x, r)[0, 1])


def residual(x: np.ndarray, frac: float = 0.02) -> float:
    n = max(1, int(frac * len(x)))
    return float(np.mean(x[-n:]))


def closure_times_per_corner(result: Result) -> dict[str, list[float]]:
    """Per corner, the times of the output rows at which it comes into contact [s]
    (:func:`deckpound.models.result.closure_times`): the closures as the rows show them. The
    engines' count, at every step, is ``result.meta["gap_closures_per_corner"]``; a closure
    that opens again between two rows is in that count but not among these times, so the
    report calls the first of them the *first contact row*, not a closure."""
    return {
        f"c{c}": closure_times(
            result.t, result[f"gap_c{c}"], result.columns.get(f"fn_c{c}")
        ).tolist()
        for c in range(1, 5)
        if f"gap_c{c}" in result.columns
    }


def summary(result: Result, quantities: list[str]) -> dict[str, float]:
    """Peak and time of peak (over every step, :meth:`Result.peak`) and residual (the last
    output rows) of quantities of a result."""
    out = {}
    for q in quantities:
        out[f"peak_{q}"] = result.peak(q)
        out[f"tpeak_{q}"] = result.peak_time(q)
        out[f"residual_{q}"] = residual(result[q])
    out["gap_closures"] = result.gap_closures
    return out


def compare_pair(
    test: Result,
    ref: Result,
    aligned_test: pd.DataFrame,
    aligned_ref: pd.DataFrame,
    quantities: list[str],
) -> pd.DataFrame:
    """One row per quantity: peaks and peak times (over every step, :meth:`Result.peak`), peak
    ratio, NRMSE and correlation (aligned rows), residuals; ``unit`` is the quantity's unit (of
    the peaks and residuals); ``peak_basis`` says what the two peaks were taken over."""
    rows = []
    for q in quantities:
        x, r = aligned_test[q].to_numpy(), aligned_ref[q].to_numpy()
        px, pr = test.peak(q), ref.peak(q)
        basis = {test.peak_basis(q), ref.peak_basis(q)}
        rows.append(
            {
                "quantity": q,
                "unit": column_unit(q),
                "peak": px,
                "peak_ref": pr,
                "peak_ratio": px / pr if pr != 0 else float("nan"),
                "t_peak": test.peak_time(q),
                "t_peak_ref": ref.peak_time(q),
                "peak_basis": basis.pop() if len(basis) == 1 else "mixed",
                "nrmse": nrmse(x, r),
                "correlation": correlation(x, r),
                "residual": residual(test[q]),
                "residual_ref": residual(ref[q]),
            }
        )
    return pd.DataFrame(rows)


def metrics_against(
    results: dict[str, Result],
    aligned: dict[str, pd.DataFrame],
    reference: str,
    quantities: list[str] | None = None,
) -> pd.DataFrame:
    """:func:`compare_pair` of every result against ``reference``, one frame (columns engine,
    reference, quantity, ...); quantities default to the aligned columns."""
    rows = []
    for label in results:
        if label == reference:
            continue
        qs = (
            quantities
            if quantities is not None
            else [q for q in aligned[label].columns if q != "t"]
        )
        m = compare_pair(
            results[label], results[reference], aligned[label], aligned[reference], list(qs)
        )
        m.insert(0, "reference", reference)
        m.insert(0, "engine", label)
        rows.append(m)
    return pd.concat(rows, ignore_index=True) if rows else pd.DataFrame()


def measured_result(path, t_column: str = "t") -> Result:
    """Measured data a user supplies as CSV (columns named as result columns) as a Result."""

    try:
        frame = pd.read_csv(path)
    except Exception as err:
        raise SceneError(
            "--measured", f"cannot read CSV {str(path)!r}: {str(err).splitlines()[0]}"
        ) from None
    if t_column not in frame:
        raise SceneError("--measured", f"{str(path)!r} has no {t_column!r} column")
    try:
        cols = {c: frame[c].to_numpy(dtype=float) for c in frame.columns}
    except ValueError as err:
        raise SceneError("--measured", f"{str(path)!r}: non-numeric value ({err})") from None
    for c, v in cols.items():
        if not np.all(np.isfinite(v)):
            raise SceneError(
                "--measured", f"{str(path)!r}: column {c!r} has missing or non-finite values"
            )
    check_time_base(cols[t_column], "--measured")
    cols["t"] = cols.pop(t_column)
    return Result(engine="measured", columns=cols, meta={"source": str(path)})

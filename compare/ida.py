"""Incremental dynamic analysis (IDA) and multiple-stripe analysis (MSA) over a record suite,
and the fragility curves they give (issue 30).

Every record pair of a folder (:func:`deckpound.models.record_suite.read_suite`: PEER station
names, ``NAME_x``/``NAME_y``, ``manifest.csv``; with ``rotate`` also each pair turned by 90°) is
scaled by **one** factor per pair to each intensity level (``excitation.scaling = pair-…``, which
keeps the pair's component ratio; :data:`IMS`) and run by one engine for its summary row only
(:func:`deckpound.compare.variability.sweep_rows`: peaks over every step, gap closures, status,
seat margins and the unseating flag where the engine reports them; no histories). Rows are
cached one JSON file per case, so a sweep interrupted by Ctrl-C resumes without recomputing the
cases it finished; a doubtful or failed case is kept with its status and counted, never dropped
silently.

Fragility (:mod:`.fragility`, lognormal by maximum likelihood) for each limit state of
:func:`limit_states` — unseating of any corner, the peak deck rotation above a value:

* IDA: each record's capacity is the first level at which it exceeds the limit (records that
  never do are right-censored at their highest level run);
* MSA: at each stripe, the records that exceed it out of the records that finished
  (binomial likelihood).

Cases that did not finish (failed, refused) or are doubtful are left out of both and counted
in the fragility table (``left_out``).
"""

from __future__ import annotations

import itertools
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from deckpound.models.errors import SceneError
from deckpound.models.scene import Scene

from .variability import sweep_rows

__all__ = [
    "IMS",
    "LimitState",
    "fragility_table",
    "ida_cases",
    "limit_states",
    "parse_levels",
    "run_ida",
]

#: intensity measures of the command line → (excitation.scaling, target field, unit)
IMS = {
    "pga": ("pair-pga", "pga", "g"),
    "pgv": ("pair-pgv", "target_pgv", "m/s"),
    "sa-t1": ("pair-sa", "target_sa", "g"),
    "rotd50": ("pair-rotd50", "target_sa", "g"),
}
#: most levels × pairs of one sweep (a typo such as 0.001 steps would otherwise plan millions)
MAX_CASES = 200_000
#: statuses whose rows enter the fragility fits
FITTED = ("success", "unseated")


@dataclass(frozen=True)
class LimitState:
    """A limit state of the sweep's rows: ``column`` > ``threshold``, or a flag ``column``
    (``threshold`` None) being true."""

    name: str
    column: str
    threshold: float | None = None

    def exceeded(self, row: dict) -> bool:
        value = row.get(self.column)
        if self.threshold is None:
            return bool(value)
        return value is not None and float(value) > self.threshold


def limit_states(theta_limit: float | None) -> list[LimitState]:
    """Unseating, and the peak deck rotation above ``theta_limit`` [rad] when given."""
    out = [LimitState("unseating", "unseated")]
    if theta_limit is not None:
        out.append(LimitState(f"peak θ_d > {theta_limit:g} rad", "peak_theta", theta_limit))
    return out


def parse_levels(text: str, option: str) -> list[float]:
    """``"0.1:2.0:0.1"`` (start:stop:step, stop included) or ``"0.2,0.4,0.8"`` → levels (> 0,
    increasing, distinct)."""
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if not step > 0 or not stop >= start:
                raise ValueError
            n = math.floor((stop - start) / step + 1e-9) + 1
            levels = [start + i * step for i in range(n)]
        else:
            levels = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise SceneError(
            option,
            f"{text!r} is neither start:stop:step (step > 0, stop >= start) nor a list "
            "a,b,c of numbers",
        ) from None
    if not levels or any(not (math.isfinite(v) and v > 0) for v in levels):
        raise SceneError(option, f"{text!r}: the levels must be finite and > 0")
    if any(b <= a for a, b in itertools.pairwise(levels)):
        raise SceneError(option, f"{text!r}: the levels must increase")
    return [float(round(v, 12)) for v in levels]


def ida_cases(
    scene: Scene, records: str | Path, im: str, levels: list[float], rotate: bool = False
) -> list[tuple[dict, Scene]]:
    """(params, scene) per record pair and level: the pair on x and y, scaled by one factor
    so that its ``im`` equals the level."""
    from .studies import modified
    from .variability import record_cases

    if im not in IMS:
        raise SceneError("--im", f"unknown intensity measure {im!r}; valid: {', '.join(IMS)}")
    scaling, field, _ = IMS[im]
    pairs = record_cases(scene, records, rotate)
    if len(pairs) * len(levels) > MAX_CASES:
        raise SceneError(
            "--levels",
            f"{len(pairs)} pairs × {len(levels)} levels = {len(pairs) * len(levels)} cases; "
            f"at most {MAX_CASES} are allowed",
        )
    out = []
    for _, params, base in pairs:
        for level in levels:
            sc = modified(base, f"excitation.scaling={scaling}", f"excitation.{field}={level!r}")
            out.append(({**params, "im": im, "level": level}, sc))
    return out


def _fit_row(state: LimitState, method: str, rows: list[dict], levels) -> dict:
    from . import fragility

    row = {"limit_state": state.name, "method": method, "median": np.nan, "beta": np.nan}
    ok = [r for r in rows if r.get("status") in FITTED]
    row["cases"], row["left_out"] = len(ok), len(rows) - len(ok)
    try:
        if method == "msa":
            n = [sum(1 for r in ok if r["level"] == x) for x in levels]
            z = [sum(1 for r in ok if r["level"] == x and state.exceeded(r)) for x in levels]
            keep = [i for i in range(len(levels)) if n[i] > 0]
            fit = fragility.fit_stripes(
                np.array(levels)[keep], np.array(n)[keep], np.array(z)[keep]
            )
        else:
            cap, censored = [], []
            for rec in sorted({r["record_key"] for r in ok}):
                mine = sorted((r for r in ok if r["record_key"] == rec), key=lambda r: r["level"])
                hit = [r["level"] for r in mine if state.exceeded(r)]
                cap.append(hit[0] if hit else mine[-1]["level"])
                censored.append(not hit)
            fit = fragility.fit_ida(np.array(cap), np.array(censored, dtype=bool))
        row.update(median=float(fit.median), beta=float(fit.beta), note="")
    except (ValueError, SceneError) as err:
        row["note"] = f"not fitted: {err}"
    return row


def fragility_table(rows: list[dict], levels: list[float], states: list[LimitState]):
    """One row per limit state and method (``ida`` from capacities, ``msa`` from stripes)."""
    import pandas as pd

    return pd.DataFrame([_fit_row(s, m, rows, levels) for s in states for m in ("ida", "msa")])


def run_ida(
    scene: Scene,
    out: str | Path,
    *,
    records: str | Path,
    im: str,
    levels: list[float],
    engine: str = "compliance",
    theta_limit: float | None = None,
    rotate: bool = False,
    cache_dir: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    title: str = "ida",
):
    """Run the sweep; write ``ida.csv`` (one summary row per record and level),
    ``fragility.csv`` and ``ida.json`` into ``out``; return (table, fragility table)."""
    import pandas as pd

    from deckpound._io import atomic_write_text, ensure_folder, write_csv

    specs = ida_cases(scene, records, im, levels, rotate)
    out = ensure_folder(out)
    rows_dir = ensure_folder(Path(cache_dir) if cache_dir else out / "cache", "--cache")
    t0 = time.perf_counter()
    rows, computed = sweep_rows(
        [sc for _, sc in specs],
        engine,
        ensure_folder(rows_dir / "rows", "--cache"),
        title,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
    )
    records_rows = []
    for i, (params, _) in enumerate(specs):
        key = f"{params['record']}{' (rotated)' if params.get('rotated') else ''}"
        records_rows.append({"case": i, "engine": engine, **params, "record_key": key, **rows[i]})
    table = pd.DataFrame(records_rows)
    frag = fragility_table(records_rows, levels, limit_states(theta_limit))
    unit = IMS[im][2]
    write_csv(table, out / "ida.csv")
    write_csv(frag, out / "fragility.csv")
    status = table["status"].value_counts().to_dict() if len(table) else {}
    atomic_write_text(
        out / "ida.json",
        json.dumps(
            {
                "engine": engine,
                "im": im,
                "im_unit": unit,
                "levels": levels,
                "cases": len(specs),
                "computed": computed,
                "from_cache": len(specs) - computed,
                "status": {str(k): int(v) for k, v in status.items()},
                "wall_time": time.perf_counter() - t0,
                "workers": workers,
                "scheduler": scheduler,
            },
            indent=2,
        ),
    )
    return table, frag

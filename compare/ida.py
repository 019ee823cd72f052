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
from pathlib import Path

import numpy as np

from deckpound.models.errors import SceneError
from deckpound.models.scene import Scene

from .fragility import (
    LimitState,
    count_exceedances,
    fit_ida,
    fit_stripes,
    fragility_curve,
    ida_capacities,
)
from .variability import sweep_rows

__all__ = [
    "IMS",
    "fragility_figure",
    "fragility_table",
    "ida_cases",
    "ida_figure",
    "limit_states",
    "parse_levels",
    "run_ida",
    "with_rotation_flag",
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


def limit_states(theta_limit: float | None) -> list[tuple[str, LimitState]]:
    """(name, limit state) of a sweep: unseating of any corner, and, when ``theta_limit``
    [rad] is given, the peak deck rotation above it *or* unseating (an unseated run stops
    where the deck loses its seat, so its rotation is not its demand: it counts as exceeding
    every limit state, the usual collapse convention of IDA), read from the flag column
    ``theta_exceeded`` that :func:`with_rotation_flag` adds."""
    out = [("unseating", LimitState("unseated"))]
    if theta_limit is not None:
        out.append((f"peak θ_d > {theta_limit:g} rad", LimitState("theta_exceeded")))
    return out


def with_rotation_flag(table, theta_limit: float | None):
    """``table`` with the flag ``theta_exceeded`` = peak θ_d > ``theta_limit`` or unseated."""
    if theta_limit is None:
        return table
    unseated = table["unseated"].astype(bool)
    return table.assign(theta_exceeded=(table["peak_theta"] > theta_limit) | unseated)


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


def _fit(state: LimitState, method: str, ok):
    if method == "msa":
        counts = count_exceedances(ok, state, im_column="level")
        return fit_stripes(counts["im"], counts["n"], counts["exceed"])
    caps = ida_capacities(ok, state, im_column="level", record_column="record_key")
    return fit_ida(caps["capacity"], caps["censored"])


def fragility_table(table, states: list[tuple[str, LimitState]]):
    """One row per engine, limit state and method (``ida`` from each record's capacity,
    censored at its highest level; ``msa`` from the stripes' binomial counts) over the cases
    that finished with an answer (:data:`FITTED`); the others are counted in ``left_out``."""
    import pandas as pd

    rows = []
    for engine, mine in table.groupby("engine", sort=False):
        ok = mine[mine["status"].isin(FITTED)]
        for name, state in states:
            for method in ("ida", "msa"):
                row = {"engine": engine, "limit_state": name, "method": method}
                row.update(median=np.nan, beta=np.nan, cases=len(ok))
                row["left_out"] = len(mine) - len(ok)
                try:
                    fit = _fit(state, method, ok)
                    row.update(median=float(fit.median), beta=float(fit.beta), note="")
                except SceneError as err:
                    row["note"] = f"not fitted: {err}"
                rows.append(row)
    return pd.DataFrame(rows)


def run_ida(
    scene: Scene,
    out: str | Path,
    *,
    records: str | Path,
    im: str,
    levels: list[float],
    engines: tuple[str, ...] = ("compliance",),
    theta_limit: float | None = None,
    rotate: bool = False,
    cache_dir: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    title: str = "ida",
):
    """Run the sweep with every engine; write ``ida.csv`` (one summary row per engine, record
    and level), ``fragility.csv``, ``ida.json`` and the figures ``ida.png`` and
    ``fragility.png`` into ``out``; return (table, fragility table)."""
    import pandas as pd

    from deckpound._io import atomic_write_text, ensure_folder, write_csv

    specs = ida_cases(scene, records, im, levels, rotate)
    out = ensure_folder(out)
    rows_dir = ensure_folder(Path(cache_dir) if cache_dir else out / "cache", "--cache")
    t0 = time.perf_counter()
    table_rows, computed = [], 0
    for engine in engines:
        rows, done = sweep_rows(
            [sc for _, sc in specs],
            engine,
            ensure_folder(rows_dir / "rows", "--cache"),
            f"{title} {engine}",
            workers=workers,
            scheduler=scheduler,
            progress=progress,
        )
        computed += done
        for i, (params, _) in enumerate(specs):
            key = f"{params['record']}{' (rotated)' if params.get('rotated') else ''}"
            table_rows.append({"engine": engine, "case": i, **params, "record_key": key, **rows[i]})
    table = with_rotation_flag(pd.DataFrame(table_rows), theta_limit)
    states = limit_states(theta_limit)
    frag = fragility_table(table, states)
    unit = IMS[im][2]
    write_csv(table, out / "ida.csv")
    write_csv(frag, out / "fragility.csv")
    ida_figure(table, im, scene.name, out / "ida.png")
    fragility_figure(table, frag, states, im, scene.name, out / "fragility.png")
    status = table["status"].value_counts().to_dict() if len(table) else {}
    atomic_write_text(
        out / "ida.json",
        json.dumps(
            {
                "engines": list(engines),
                "im": im,
                "im_unit": unit,
                "levels": levels,
                "cases": len(table),
                "computed": computed,
                "from_cache": len(table) - computed,
                "status": {str(k): int(v) for k, v in status.items()},
                "wall_time": time.perf_counter() - t0,
                "workers": workers,
                "scheduler": scheduler,
            },
            indent=2,
        ),
    )
    return table, frag


def ida_figure(table, im: str, scene_name: str, path: Path) -> list[Path]:
    """IDA curves, one panel per engine: the level against each record's seat-width demand
    [mm] (the largest opening of a deck end from its seat) and, beside it, its peak deck
    rotation [mrad]; an unseated case is marked × (the run stops there, so its rotation is
    the rotation reached by then)."""
    from .style import new_figure, save

    engines = list(dict.fromkeys(table["engine"]))
    edps = (("seat_demand", 1e3, "seat-width demand [mm]"), ("peak_theta", 1e3, "peak θ_d [mrad]"))
    fig, axes = new_figure(1, 2 * len(engines), width=3.0 * 2 * len(engines), height=3.0)
    for k, engine in enumerate(engines):
        mine = table[table["engine"] == engine]
        for j, (col, scale, label) in enumerate(edps):
            ax = axes[0][2 * k + j]
            for _, rec in mine.groupby("record_key", sort=True):
                rec = rec.sort_values("level")
                ax.plot(scale * rec[col], rec["level"], "-", color="#555555", lw=0.8)
                hit = rec[rec["unseated"].astype(bool)]
                ax.plot(scale * hit[col], hit["level"], "x", color="#c0392b", ms=4)
            ax.set_title(f"{engine}: {label.split(' [')[0]}", fontsize=9)
            ax.set_xlabel(label)
    axes[0][0].set_ylabel(f"{im} [{IMS[im][2]}]")
    return save(fig, path, scene_name)


def fragility_figure(table, frag, states, im: str, scene_name: str, path: Path) -> list[Path]:
    """Fragility curves (IDA fits) per limit state, one curve per engine with its 90 %
    bootstrap band over records; the stripes' observed fractions as markers."""
    from .fragility import bootstrap_ida
    from .style import new_figure, save

    levels = np.sort(table["level"].unique())
    grid = np.geomspace(levels[0] / 2, levels[-1] * 2, 60)
    fig, axes = new_figure(1, len(states), width=3.6 * len(states), height=3.0)
    colors = ("#1f4e79", "#c0392b", "#2e7d32", "#7b1fa2")
    for ax, (name, state) in zip(axes[0], states):
        for k, engine in enumerate(dict.fromkeys(table["engine"])):
            mine = table[(table["engine"] == engine) & table["status"].isin(FITTED)]
            color = colors[k % len(colors)]
            row = frag[
                (frag["engine"] == engine)
                & (frag["limit_state"] == name)
                & (frag["method"] == "ida")
            ]
            if len(mine):
                counts = count_exceedances(mine, state, im_column="level")
                ax.plot(
                    counts["im"],
                    counts["exceed"] / counts["n"],
                    "o",
                    ms=3,
                    color=color,
                    mfc="white",
                )
            if not len(row) or not np.isfinite(row["median"].iloc[0]):
                continue
            caps = ida_capacities(mine, state, im_column="level", record_column="record_key")
            try:
                band = bootstrap_ida(caps["capacity"], caps["censored"], grid, 200, seed=0)
                ax.fill_between(grid, band.lower, band.upper, color=color, alpha=0.15, lw=0)
            except SceneError:
                pass  # too few records to resample: the curve alone
            m, b = row["median"].iloc[0], row["beta"].iloc[0]
            ax.plot(
                grid,
                fragility_curve(grid, m, b),
                "-",
                color=color,
                lw=1.2,
                label=f"{engine}: median {m:.3g}, β {b:.2f}",
            )
        ax.set_xscale("log")
        ax.set_ylim(-0.02, 1.02)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel(f"{im} [{IMS[im][2]}]")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="upper left", frameon=False)
        else:
            ax.text(
                0.5,
                0.5,
                "not fitted (fragility.csv says why)",
                ha="center",
                fontsize=7,
                transform=ax.transAxes,
            )
    axes[0][0].set_ylabel("P(limit state exceeded)")
    return save(fig, path, scene_name)

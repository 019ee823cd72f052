"""Incremental dynamic analysis (IDA) and multiple-stripe analysis (MSA) over a record suite,
and the fragility curves they give (issue 30).

Every record pair of a folder (:func:`deckpound.models.record_suite.read_suite`: PEER station
names, ``NAME_x``/``NAME_y``, ``manifest.csv``; with ``rotate`` also each pair turned by 90°) is
scaled by **one** factor per pair to each intensity level (``excitation.scaling = pair-…``, which
keeps the pair's component ratio; :data:`IMS`) and run by one engine for its summary row only
(:func:`deckpound.compare.studies.variability.sweep_rows`: peaks over every step, gap closures, status,
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

import dataclasses
import itertools
import json
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.engines import engine_names
from deckpound.compare.report.figure_cache import reusable
from deckpound.compare.report.outputs import write_csv
from deckpound.compare.studies.fragility import (
    LimitState,
    bootstrap_ida,
    count_exceedances,
    fit_ida,
    fit_stripes,
    fragility_curve,
    ida_capacities,
)
from deckpound.compare.studies.variability import record_cases, sweep_rows, table_units
from deckpound.models.errors import SceneError
from deckpound.models.excitation import support_motion
from deckpound.models.file_io import atomic_write_text, ensure_folder
from deckpound.models.scene import Scene
from deckpound.models.scene_io import modified

__all__ = [
    "IMS",
    "fragility_figure",
    "fragility_table",
    "fragility_units",
    "ida_cases",
    "ida_figure",
    "limit_states",
    "parse_levels",
    "parse_vary",
    "run_ida",
    "synthetic_pairs",
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
#: most values of one ``--vary`` (each value runs the whole sweep once per engine)
MAX_VARIANTS = 10
#: ``--vary`` shorthands → the scene paths each value is written to
VARY_SHORTHANDS = {"gap": ("seats[0].gap", "seats[1].gap")}


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


def parse_vary(text: str, scene: Scene) -> list[tuple[str, tuple[str, ...]]]:
    """``"PATH=V1,V2,..."`` → (label ``PATH=V``, scene overrides) per value, each checked on
    ``scene``; the shorthand ``gap=…`` sets both seats' gap (:data:`VARY_SHORTHANDS`). At most
    :data:`MAX_VARIANTS` distinct values."""

    if "=" not in text:
        raise SceneError("--vary", f"expects PATH=V1,V2,..., got {text!r}")
    path, raw = (part.strip() for part in text.split("=", 1))
    values = [v.strip() for v in raw.split(",")]
    if not path or not values or any(not v for v in values):
        raise SceneError("--vary", f"expects PATH=V1,V2,... with no empty value, got {text!r}")
    if len(values) > MAX_VARIANTS:
        raise SceneError("--vary", f"{len(values)} values; at most {MAX_VARIANTS} are allowed")
    if len(set(values)) != len(values):
        raise SceneError("--vary", f"{text!r}: the values must be distinct")
    if path == "contact.friction" and scene.contact.friction_mode == "none":
        raise SceneError(
            "--vary",
            "contact.friction does nothing while contact.friction_mode is 'none'; choose a "
            "mode, e.g. --set contact.friction_mode=slip",
        )
    paths = VARY_SHORTHANDS.get(path, (path,))
    out = []
    for value in values:
        overrides = tuple(f"{p}={value}" for p in paths)
        try:
            modified(scene, *overrides)
        except SceneError as err:
            raise SceneError("--vary", f"{path}={value}: {err}") from None
        out.append((f"{path}={value}", overrides))
    return out


def synthetic_pairs(
    scene: Scene, folder: str | Path, pairs: int, seed: int = 0, duration: float = 20.0
) -> Path:
    """Write ``pairs`` PEER-named AT2 station pairs (``RSN<i>_SYNTH_ST<i>000/090``) drawn from
    the built-in synthetic generator of ``scene`` with seeds ``seed``, ``seed + 1``, ...: the
    first bent's table acceleration in x and y of each seed [g] (a = ü / 9.80665 m/s²), at
    the generator's step. Returns the folder."""

    folder = ensure_folder(folder)
    for i in range(pairs):
        sc = modified(
            scene, f"excitation.seed={seed + i}", f"excitation.duration={float(duration)!r}"
        )
        motion = support_motion(sc)
        dt = float(motion.t[1] - motion.t[0])
        for comp, channel in (("000", "bent1_x"), ("090", "bent1_y")):
            _write_at2(
                folder / f"RSN{i + 1}_SYNTH_ST{i + 1}{comp}.AT2",
                motion.acc(channel) / 9.80665,
                dt,
            )
    return folder


def _write_at2(path: Path, acc_g, dt: float) -> None:
    """A PEER NGA-West2 AT2 file of the acceleration ``acc_g`` [g] at step ``dt`` [s]."""

    acc = [float(v) for v in acc_g]
    body = ["".join(f"{v:15.7E}" for v in acc[i : i + 5]) for i in range(0, len(acc), 5)]
    head = [
        "PEER NGA STRONG MOTION DATABASE RECORD",
        "deckpound synthetic station (built-in generator)",
        "ACCELERATION TIME SERIES IN UNITS OF G",
        f"NPTS=   {len(acc)}, DT=   {dt:.4f} SEC",
    ]
    atomic_write_text(path, "\n".join(head + body) + "\n")


def ida_cases(
    scene: Scene, records: str | Path, im: str, levels: list[float], rotate: bool = False
) -> list[tuple[dict, Scene]]:
    """(params, scene) per record pair and level: the pair on x and y, scaled by one factor
    so that its ``im`` equals the level."""

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
            # the pair's scene with its excitation replaced (validated again): the levels share
            # every other part, whose hashes a sweep's case keys then compute once
            exc = dataclasses.replace(base.excitation, scaling=scaling, **{field: float(level)})
            out.append(({**params, "im": im, "level": level}, base.replace(excitation=exc)))
    return out


def _fit(state: LimitState, method: str, ok):
    if method == "msa":
        counts = count_exceedances(ok, state, im_column="level")
        return fit_stripes(counts["im"], counts["n"], counts["exceed"])
    caps = ida_capacities(ok, state, im_column="level", record_column="record_key")
    return fit_ida(caps["capacity"], caps["censored"])


def fragility_table(table, states: list[tuple[str, LimitState]]):
    """One row per engine (and ``variant``, when the table has that column), limit state and
    method (``ida`` from each record's capacity,
    censored at its highest level; ``msa`` from the stripes' binomial counts) over the cases
    that finished with an answer (:data:`FITTED`); the others are counted in ``left_out``."""

    rows = []
    keys = ["engine", "variant"] if "variant" in table else ["engine"]
    for group, mine in table.groupby(keys, sort=False):
        ok = mine[mine["status"].isin(FITTED)]
        head = dict(zip(keys, group))
        for name, state in states:
            for method in ("ida", "msa"):
                row = {**head, "limit_state": name, "method": method}
                row.update(median=np.nan, beta=np.nan, cases=len(ok))
                row["left_out"] = len(mine) - len(ok)
                try:
                    fit = _fit(state, method, ok)
                    row.update(median=float(fit.median), beta=float(fit.beta), note="")
                except SceneError as err:
                    row["note"] = f"not fitted: {err}"
                rows.append(row)
    return pd.DataFrame(rows)


def fragility_units(im_unit: str) -> dict[str, str]:
    """Units of :func:`fragility_table`'s columns: the median in the IM's unit."""
    return {"median": im_unit, "beta": "-", "cases": "-", "left_out": "-"}


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
    variants: list[tuple[str, tuple[str, ...]]] | None = None,
):
    """Run the sweep with every engine, once per variant ((label, scene overrides), e.g. from
    :func:`parse_vary`; none: the scene as given, label ``""``); write ``ida.csv`` (one summary
    row per engine, variant, record and level), ``fragility.csv`` (per engine × variant ×
    limit state × method), ``ida.json`` and the figures ``ida.png`` and ``fragility.png``
    into ``out``; return (table, fragility table). Rows are cached by engine and scene, so a
    variant's value is part of its cases' keys."""

    variants = list(variants) if variants else [("", ())]
    specs = [
        (
            label,
            ida_cases(
                modified(scene, *overrides) if overrides else scene, records, im, levels, rotate
            ),
        )
        for label, overrides in variants
    ]
    if sum(len(cases) for _, cases in specs) > MAX_CASES:
        raise SceneError(
            "--vary",
            f"{len(variants)} variants × {len(specs[0][1])} cases exceed the {MAX_CASES} "
            "cases allowed",
        )
    out = ensure_folder(out)
    rows_dir = ensure_folder(Path(cache_dir) if cache_dir else out / "cache", "--cache")
    t0 = time.perf_counter()
    table_rows, computed = [], 0
    for engine in engines:
        case = 0
        for label, cases in specs:
            rows, done = sweep_rows(
                [sc for _, sc in cases],
                engine,
                ensure_folder(rows_dir / "rows", "--cache"),
                f"{title} {engine}{' ' + label if label else ''}",
                workers=workers,
                scheduler=scheduler,
                progress=progress,
            )
            computed += done
            for i, (params, _) in enumerate(cases):
                key = f"{params['record']}{' (rotated)' if params.get('rotated') else ''}"
                table_rows.append(
                    {
                        "engine": engine,
                        "variant": label,
                        "case": case,
                        **params,
                        "record_key": key,
                        **rows[i],
                    }
                )
                case += 1
    table = with_rotation_flag(pd.DataFrame(table_rows), theta_limit)
    states = limit_states(theta_limit)
    frag = fragility_table(table, states)
    unit = IMS[im][2]
    write_csv(table, out / "ida.csv", {**table_units(table), "level": unit})
    write_csv(frag, out / "fragility.csv", fragility_units(unit))
    ida_figure(table, im, scene.name, out / "ida.png")
    fragility_figure(table, frag, states, im, scene.name, out / "fragility.png")
    status = table["status"].value_counts().to_dict() if len(table) else {}
    atomic_write_text(
        out / "ida.json",
        json.dumps(
            {
                "engines": list(engines),
                "variants": {label: list(overrides) for label, overrides in variants},
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


@reusable
def ida_figure(table, im: str, scene_name: str, path: Path) -> list[Path]:
    """IDA curves, one panel per engine: the level against each record's seat-width demand
    [mm] (the largest opening of a deck end from its seat) and, beside it, its peak deck
    rotation [mrad]; an unseated case is marked × (the run stops there, so its rotation is
    the rotation reached by then)."""
    from deckpound.compare.report.style import new_figure, save

    engines = list(dict.fromkeys(table["engine"]))
    edps = (("seat_demand", 1e3, "seat-width demand [mm]"), ("peak_theta", 1e3, "peak θ_d [mrad]"))
    fig, axes = new_figure(1, 2 * len(engines), width=3.0 * 2 * len(engines), height=3.0)
    for k, engine in enumerate(engines):
        mine = table[table["engine"] == engine]
        for j, (col, scale, label) in enumerate(edps):
            ax = axes[0][2 * k + j]
            by = ["variant", "record_key"] if "variant" in mine else ["record_key"]
            for _, rec in mine.groupby(by, sort=True):
                rec = rec.sort_values("level")
                ax.plot(scale * rec[col], rec["level"], "-", color="#555555", lw=0.8)
                hit = rec[rec["unseated"].astype(bool)]
                ax.plot(scale * hit[col], hit["level"], "x", color="#c0392b", ms=4)
            ax.set_title(f"{engine}: {label.split(' [')[0]}", fontsize=9)
            ax.set_xlabel(label)
    axes[0][0].set_ylabel(f"{im} [{IMS[im][2]}]")
    return save(fig, path, scene_name)


@reusable
def fragility_figure(table, frag, states, im: str, scene_name: str, path: Path) -> list[Path]:
    """Fragility curves (IDA fits) per limit state, one curve per engine and variant (each its
    own line style and marker, :func:`~deckpound.compare.report.style.series_styles`), with its
    90 % bootstrap band over records when no variant is swept; the stripes' observed fractions
    as the curve's marker, larger, without a line; the legend beside the panels, off the
    data."""
    from matplotlib.ticker import NullFormatter

    from deckpound.compare.report.style import (
        MARKERSIZE,
        new_figure,
        outside_legend,
        save,
        series_styles,
    )

    levels = np.sort(table["level"].unique())
    grid = np.geomspace(levels[0] / 2, levels[-1] * 2, 60)
    if "variant" not in table:
        table = table.assign(variant="")
    if "variant" not in frag:
        frag = frag.assign(variant="")
    variants = list(dict.fromkeys(table["variant"]))
    fig, axes = new_figure(1, len(states), width=3.6 * len(states) + 2.4, height=3.0)
    series = [(e, v) for e in dict.fromkeys(table["engine"]) for v in variants]
    styles = dict(
        zip(
            series,
            series_styles(
                [f"{e}, {v}" if v else str(e) for e, v in series],
                [e if e in engine_names() else None for e, _ in series],
                points=len(grid),
            ),
        )
    )
    for ax, (name, state) in zip(axes[0], states):
        for engine, variant in series:
            st = styles[(engine, variant)]
            color = st["color"]
            mine = table[
                (table["engine"] == engine)
                & (table["variant"] == variant)
                & table["status"].isin(FITTED)
            ]
            row = frag[
                (frag["engine"] == engine)
                & (frag["variant"] == variant)
                & (frag["limit_state"] == name)
                & (frag["method"] == "ida")
            ]
            if len(mine):
                counts = count_exceedances(mine, state, im_column="level")
                ax.plot(
                    counts["im"],
                    counts["exceed"] / counts["n"],
                    linestyle="none",
                    marker=st["marker"],
                    ms=MARKERSIZE + 2.5,
                    color=color,
                    mfc=st.get("markerfacecolor", color),
                )
            if not len(row) or not np.isfinite(row["median"].iloc[0]):
                continue
            if len(variants) == 1:
                caps = ida_capacities(mine, state, im_column="level", record_column="record_key")
                try:
                    band = bootstrap_ida(caps["capacity"], caps["censored"], grid, 200, seed=0)
                    ax.fill_between(grid, band.lower, band.upper, color=color, alpha=0.15, lw=0)
                except SceneError:
                    pass  # too few records to resample: the curve alone
            m, b = row["median"].iloc[0], row["beta"].iloc[0]
            who = f"{engine}, {variant}" if variant else engine
            ax.plot(
                grid,
                fragility_curve(grid, m, b),
                **{**st, "linewidth": 1.2, "label": f"{who}: median {m:.3g}, β {b:.2f}"},
            )
        ax.set_xscale("log")
        # the levels as plain numbers: a log axis labels its minor ticks on top of each other
        ax.set_xticks(levels, [f"{v:g}" for v in levels])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_ylim(-0.02, 1.02)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel(f"{im} [{IMS[im][2]}]")
        if outside_legend(ax, fontsize=6) is None:
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

"""``deckpound compare``: several engines on one scene, aligned, compared and plotted."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from deckpound.compare.align import align, write_tables
from deckpound.compare.cases import Case, run_cases
from deckpound.compare.engines import DEFAULT_REFERENCE
from deckpound.compare.metrics import METRIC_UNITS, metrics_against, summary
from deckpound.compare.report import figures
from deckpound.compare.report.outputs import write_csv
from deckpound.compare.result_cache import ResultCache
from deckpound.models.plan import Plan, plan_of
from deckpound.models.result import Result
from deckpound.models.scene import Scene

#: the quantities aligned and compared for a one-segment deck (:func:`compare_quantities`)
QUANTITIES = [
    "deck_theta",
    "deck_y_rel",
    "deck_x_rel",
    "seat1_x_rel",
    "seat2_x_rel",
    "gap_c1",
    "gap_c3",
]


def compare_quantities(plan: Plan) -> list[str]:
    """The quantities ``deckpound compare`` aligns, compares and plots: :data:`QUANTITIES`
    for a one-segment deck; for a deck of segments each segment's θ, y and x relative to its
    tables, the seats, and the first corner's gap at each face (seat 1, every joint, seat 2)."""
    if len(plan.segments) == 1:
        return list(QUANTITIES)
    out = [f"{seg.name}_{q}" for q in ("theta", "y_rel", "x_rel") for seg in plan.segments]
    out += ["seat1_x_rel", "seat2_x_rel"]
    firsts = {}
    for c in plan.corners:
        firsts.setdefault((c.seat, c.joint), c.name)
    return out + [f"gap_{name}" for name in firsts.values()]


def run_compare(
    scene: Scene,
    engines: list[str],
    out: str | Path,
    *,
    measured: Result | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    cache_dir: str | Path | None = None,
    progress: bool = True,
    reference: str | None = None,
) -> str:
    """Run, write results, aligned tables, metrics (vs ``reference`` — default the registry's
    reference engine if it runs, else the first — and vs measured data) and figures into
    ``out``; returns a printable summary."""
    out = Path(out)
    cache = ResultCache(cache_dir if cache_dir is not None else out / "cache")
    ref = reference or (DEFAULT_REFERENCE if DEFAULT_REFERENCE in engines else engines[0])
    if ref not in engines:
        engines = [ref] + list(engines)
    cases = [Case(e, e, scene) for e in engines]
    results = run_cases(
        cases, cache=cache, workers=workers, scheduler=scheduler, progress=progress, title="engines"
    )
    for r in results.values():
        r.write(out)
    everything = dict(results)
    if measured is not None:
        everything["measured"] = measured
    plan = plan_of(scene)
    quantities = compare_quantities(plan)
    aligned = align(
        everything,
        columns=[q for q in quantities if all(q in r.columns for r in everything.values())],
    )
    write_tables(aligned, out)
    parts = [metrics_against(everything, aligned, ref)]
    if measured is not None:
        parts.append(metrics_against(everything, aligned, "measured"))
    metrics = (
        pd.concat([p for p in parts if len(p)], ignore_index=True)
        if any(len(p) for p in parts)
        else pd.DataFrame()
    )
    write_csv(metrics, out / "metrics.csv", METRIC_UNITS)
    figs = out / "figures"
    shown = [f"{seg.name}_{q}" for seg in plan.segments for q in ("theta", "y_rel")]
    figures.histories(everything, scene, figs / "histories.png", tuple(shown))
    figures.contact_forces(results, scene, figs / "contact_forces.png")
    figures.plan_snapshot(results, scene, figs / "plan_at_peak_rotation.png")
    lines = []
    names = [seg.name for seg in plan.segments]
    for label, r in results.items():
        s = summary(r, [f"{n}_{q}" for n in names for q in ("theta", "y_rel")])
        if names == ["deck"]:
            peaks = (
                f"peak θ {1e3 * s['peak_deck_theta']:.3f} mrad, peak y rel. tables "
                f"{1e3 * s['peak_deck_y_rel']:.2f} mm"
            )
        else:
            peaks = (
                "peak θ "
                + ", ".join(f"{n} {1e3 * s[f'peak_{n}_theta']:.3f}" for n in names)
                + " mrad, peak y rel. tables "
                + ", ".join(f"{n} {1e3 * s[f'peak_{n}_y_rel']:.2f}" for n in names)
                + " mm"
            )
        lines.append(
            f"{label:11s} {r.meta.get('status')}: {peaks}, {s['gap_closures']} gap closures, "
            f"run {r.meta.get('wall_time', float('nan')):.2f} s (+ compile "
            f"{r.meta.get('compile_time', 0.0):.2f} s)"
        )
    lines.append(f"metrics against {ref}; wrote {out}")
    return "\n".join(lines)

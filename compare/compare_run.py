"""``deckpound compare``: several engines on one scene, aligned, compared and plotted."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from deckpound._io import write_csv
from deckpound.models.result import Result
from deckpound.models.scene import Scene

from . import figures
from .align import align, write_tables
from .cases import Case, ResultCache, run_cases
from .metrics import compare_pair, summary

QUANTITIES = ["deck_theta", "deck_y", "deck_x", "seat1_x", "seat2_x", "gap_c1", "gap_c3"]


def run_compare(scene: Scene, engines: list[str], out: str | Path, *,
                measured: Result | None = None, workers: int | None = None,
                scheduler: str | None = None, cache_dir: str | Path | None = None,
                progress: bool = True) -> str:
    """Run, write results, aligned tables, metrics (vs the first engine and vs measured data)
    and figures into ``out``; returns a printable summary."""
    out = Path(out)
    cache = ResultCache(cache_dir if cache_dir is not None else out / "cache")
    cases = [Case(e, e, scene) for e in engines]
    results = run_cases(cases, cache=cache, workers=workers, scheduler=scheduler,
                        progress=progress, title="engines")
    for r in results.values():
        r.write(out)
    everything = dict(results)
    if measured is not None:
        everything["measured"] = measured
    aligned = align(everything, columns=[q for q in QUANTITIES
                                         if all(q in r.columns for r in everything.values())])
    write_tables(aligned, out)
    rows = []
    refs = [engines[0]] + (["measured"] if measured is not None else [])
    for ref in refs:
        for label in everything:
            if label == ref:
                continue
            qs = [q for q in aligned[label].columns if q != "t"]
            m = compare_pair(everything[label], everything[ref], aligned[label], aligned[ref], qs)
            m.insert(0, "reference", ref)
            m.insert(0, "engine", label)
            rows.append(m)
    metrics = pd.concat(rows, ignore_index=True) if rows else pd.DataFrame()
    write_csv(metrics, out / "metrics.csv")
    figs = out / "figures"
    figures.histories(everything, scene, figs / "histories.png")
    figures.contact_forces(results, scene, figs / "contact_forces.png")
    figures.plan_snapshot(results, scene, figs / "plan_at_peak_rotation.png")
    lines = []
    for label, r in results.items():
        s = summary(r, ["deck_theta", "deck_y"])
        lines.append(f"{label:11s} {r.meta.get('status')}: peak θ {1e3 * s['peak_deck_theta']:.3f} mrad, "
                     f"peak y {1e3 * s['peak_deck_y']:.2f} mm, {s['contact_events']} closures, "
                     f"{r.meta.get('wall_time', float('nan')):.2f} s")
    lines.append(f"wrote {out}")
    return "\n".join(lines)

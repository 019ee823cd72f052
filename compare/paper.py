"""The main job: the paper's comparisons and studies on a scene, as a report folder.

``deckpound paper [-o DIR]`` runs, on the built-in benchmark by default,

1. the 7-run test sequence with all three engines (gap and bent stiffness carried),
2. per run: aligned histories, metrics of each engine against OpenSees, figures,
3. the sensitivity studies of :mod:`deckpound.compare.studies`,

and writes figures (PNG + PDF), tables (CSV, Parquet) and ``report.md`` / ``report.html``
stating what was run, the settings, the headline comparisons and which inputs are assumptions.
"""

from __future__ import annotations

import html
import platform
import time
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound import __version__
from deckpound._io import atomic_write_text, ensure_folder, write_csv
from deckpound.engines import DEFAULT_REFERENCE, engine_names, engine_style
from deckpound.models.result import scene_hash
from deckpound.models.scene import Scene
from deckpound.models.scene_io import scene_to_toml

from . import figures
from .align import align, write_tables
from .cases import ResultCache
from .metrics import compare_pair, peak
from .sequence_run import run_sequences
from .studies import STUDIES, run_study

QUANTITIES = ["deck_theta", "deck_y_rel", "deck_x_rel", "seat1_x_rel", "seat2_x_rel"]


def friction_variant(scene: Scene) -> tuple[Scene, str]:
    """The scene with the other friction assumption: μ = 0.2 with sticking if it has none,
    frictionless otherwise; and a short label for it."""
    from .studies import modified

    if scene.contact.has_friction:
        return modified(scene, "contact.friction=0.0", "contact.friction_mode=none"), "μ=0"
    return modified(scene, "contact.friction=0.2", "contact.friction_mode=stick"), "μ=0.2"


def sequence_table(sequences: dict) -> pd.DataFrame:
    rows = []
    for engine, runs in sequences.items():
        for run in runs:
            r = run.result
            row = dict(run=run.index, pga=run.pga, engine=engine, status=r.meta.get("status"),
                       gap1_start=run.state.gaps[0], gap2_start=run.state.gaps[1])
            for b, (kx, ky) in zip(run.scene.bents, run.state.stiffness):
                row[f"{b.name}_kx"], row[f"{b.name}_ky"] = kx, ky
            row.update(peak_theta=peak(r["deck_theta"]), peak_y=peak(r["deck_y_rel"]),
                       peak_x=peak(r["deck_x_rel"]),
                       peak_fn=max(peak(r[f"fn_c{c}"]) for c in range(1, 5)),
                       gap_closures=r.gap_closures,
                       wall_time=r.meta.get("wall_time", np.nan))
            rows.append(row)
    return pd.DataFrame(rows)


def run_paper(scene: Scene, out: str | Path, *, quick: bool = False, workers: int | None = None,
              scheduler: str | None = None, cache_dir: str | Path | None = None,
              studies: tuple[str, ...] | None = None, progress: bool = True,
              engines: tuple[str, ...] | None = None, reference: str = DEFAULT_REFERENCE) -> Path:
    """Run the whole comparison and write the report folder; returns the report.md path.

    ``engines`` (default: every registered engine) run the sequence; the others are compared
    against ``reference``.
    """
    t0 = time.perf_counter()
    ENGINES = tuple(engines) if engines is not None else engine_names()
    if reference not in ENGINES:
        ENGINES = (reference,) + ENGINES
    out = ensure_folder(out)
    cache_dir = Path(cache_dir) if cache_dir is not None else out / "cache"
    cache = ResultCache(cache_dir)
    figs, tables = ensure_folder(out / "figures"), ensure_folder(out / "tables")
    atomic_write_text(out / "scene.toml", scene_to_toml(scene))

    # 1. the sequence, every engine; and again with the other friction assumption (the paper's
    #    question: frictionless gap elements, common practice, vs frictional contact)
    sequences = run_sequences(scene, list(ENGINES), cache_dir, workers, scheduler, progress)
    variant, tag = friction_variant(scene)
    other = run_sequences(variant, list(ENGINES), cache_dir, workers, scheduler, progress)
    seq = sequence_table({**sequences, **{f"{e} {tag}": runs for e, runs in other.items()}})
    write_csv(seq, tables / "sequence.csv")
    figures.peak_vs_pga(seq, scene, figs / "peak_rotation_vs_pga.png")

    # 2. per run: histories, alignment, metrics against OpenSees
    metric_rows = []
    n_runs = min(len(v) for v in sequences.values())
    for i in range(n_runs):
        results = {e: sequences[e][i].result for e in ENGINES}
        run = sequences[reference][i]
        tag = f"run{run.index}"
        figures.histories(results, run.scene, figs / f"{tag}_histories.png",
                          title=f"run {run.index}: {run.pga:g} g transverse")
        aligned = align(results)
        write_tables(aligned, tables / tag)
        for e in (e for e in ENGINES if e != reference):
            m = compare_pair(results[e], results[reference], aligned[e], aligned[reference],
                             QUANTITIES)
            m.insert(0, "engine", e)
            m.insert(0, "run", run.index)
            metric_rows.append(m)
    metrics = pd.concat(metric_rows, ignore_index=True) if metric_rows else pd.DataFrame()
    write_csv(metrics, tables / "metrics_vs_opensees.csv")
    last = n_runs - 1
    strongest = {e: sequences[e][last].result for e in ENGINES}
    s_scene = sequences[reference][last].scene
    figures.contact_forces(strongest, s_scene, figs / "contact_forces_strongest.png",
                           title=f"run {last + 1}: normal contact force per corner")
    figures.hysteresis(strongest[reference], s_scene, figs / "bent_hysteresis_strongest.png",
                       title=f"run {last + 1}: bent hysteresis ({reference} engine)")
    figures.plan_snapshot(strongest, s_scene, figs / "plan_at_peak_rotation.png")

    # 3. studies
    study_tables = {}
    for name in (studies if studies is not None else tuple(STUDIES)):
        table, _ = run_study(name, scene, figs, quick=quick, cache=cache, workers=workers,
                             scheduler=scheduler, progress=progress)
        write_csv(table, tables / f"study_{name}.csv")  # the table belongs with the tables
        (figs / f"{name}.csv").unlink(missing_ok=True)
        study_tables[name] = table

    wall = time.perf_counter() - t0
    return write_report(out, scene, seq, metrics, study_tables, wall, cache, reference)


# -- report --------------------------------------------------------------------------------

def _md_table(frame: pd.DataFrame, floatfmt: str = ".4g") -> str:
    cols = list(frame.columns)
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for _, row in frame.iterrows():
        cells = [format(v, floatfmt) if isinstance(v, (float, np.floating)) else str(v)
                 for v in row]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def headline_sentences(seq: pd.DataFrame, reference: str = DEFAULT_REFERENCE) -> list[str]:
    """The paper's comparison in words: peak rotation of the strongest run per engine/variant."""
    last = seq[seq["run"] == seq["run"].max()].set_index("engine")
    base = last.loc[reference, "peak_theta"] if reference in last.index else np.nan
    out = [f"Strongest run ({last['pga'].iloc[0]:g} g, run {int(seq['run'].max())}): peak deck "
           "rotation " + "; ".join(f"{e} {1e3 * r['peak_theta']:.3f} mrad"
                                   f" ({r['peak_theta'] / base:.3f} × {reference})"
                                   for e, r in last.iterrows()) + "."]
    closes = seq[seq["gap_closures"] > 0].groupby("engine")["run"].min()
    if len(closes):
        out.append("First run in which the gaps close: " + ", ".join(
            f"{e} run {int(r)}" for e, r in closes.items()) + ".")
    return out


def write_report(out: Path, scene: Scene, seq: pd.DataFrame, metrics: pd.DataFrame,
                 studies: dict[str, pd.DataFrame], wall: float, cache: ResultCache,
                 reference: str = DEFAULT_REFERENCE) -> Path:
    """report.md and report.html from the tables (figures referenced relatively)."""
    seq_view = seq[["run", "pga", "engine", "gap1_start", "gap2_start", "peak_theta", "peak_y",
                    "gap_closures", "wall_time", "status"]].copy()
    seq_view["peak_theta"] = 1e3 * seq_view["peak_theta"]
    seq_view["peak_y"] = 1e3 * seq_view["peak_y"]
    seq_view = seq_view.rename(columns={"peak_theta": "peak θ [mrad]",
                                        "peak_y": "peak y rel. tables [mm]",
                                        "gap1_start": "gap1 [m]", "gap2_start": "gap2 [m]",
                                        "wall_time": "wall [s]"})
    assumptions = {k: v for k, v in scene.notes.items() if v.upper().startswith("ASSUMPTION")}
    sources = {k: v for k, v in scene.notes.items() if not v.upper().startswith("ASSUMPTION")}
    sections: list[tuple[str, list]] = []
    sections.append(("What was run", [
        f"Scene **{scene.name}** (hash `{scene_hash(scene)[:16]}`), deckpound {__version__}, "
        f"on {platform.machine()} / Python {platform.python_version()}; total wall time "
        f"{wall:.1f} s (cache hits {cache.hits}, misses {cache.misses}).",
        f"Engines: OpenSees ({scene.opensees.mode} mode, dt = {scene.opensees.dt:g} s, "
        f"{scene.opensees.algorithm}/{scene.opensees.test} {scene.opensees.tolerance:g}), "
        f"compliance clone ({scene.compliance.integrator}, dt = {scene.compliance.dt:g} s), "
        f"nonsmooth Moreau–Jean (h = {scene.nonsmooth.h:g} s, θ = {scene.nonsmooth.theta:g}, "
        f"{scene.nonsmooth.solver}).",
        f"Contact: {scene.contact.law}, k = {scene.contact.stiffness:g} kN/m, "
        f"e = {scene.contact.restitution:g}, μ = {scene.contact.friction:g} "
        f"({scene.contact.friction_mode}), {scene.contact.geometry} geometry. Damping: "
        f"Rayleigh {100 * scene.damping.ratio:g} % ({scene.damping.method} {list(scene.damping.modes)}).",
        f"Sequence: PGA {', '.join(f'{p:g}' for p in scene.sequence.pgas)} g transverse "
        f"(longitudinal × {scene.excitation.longitudinal_ratio:g}); gap carried: "
        f"{scene.sequence.carry_gap}, stiffness carried: {scene.sequence.carry_stiffness}.",
    ]))
    sections.append(("Headline: the 7-run sequence", headline_sentences(seq, reference) + [
        "![peak rotation vs PGA](figures/peak_rotation_vs_pga.png)",
        ("table", seq_view),
    ]))
    if len(metrics):
        strong = metrics[metrics["run"] == metrics["run"].max()]
        ref_label = engine_style(reference)["label"]
        sections.append((f"Engines against {ref_label} (strongest run)", [
            f"Peak ratio = engine peak / {ref_label} peak; NRMSE normalised by the {ref_label} "
            "peak. Displacements are relative to the supports (shake tables, actuators).",
            ("table", strong[["engine", "quantity", "peak", "peak_ref", "peak_ratio", "nrmse",
                              "correlation"]]),
            f"![histories](figures/run{int(metrics['run'].max())}_histories.png)",
            "![contact forces](figures/contact_forces_strongest.png)",
            "![hysteresis](figures/bent_hysteresis_strongest.png)",
            "![plan](figures/plan_at_peak_rotation.png)",
        ]))
    for name, table in studies.items():
        view = table.drop(columns=[c for c in ("status",) if c in table]).copy()
        view["peak_theta"] = 1e3 * view["peak_theta"]
        view = view.rename(columns={"peak_theta": "peak θ [mrad]"})
        sections.append((f"Study: {STUDIES[name].title}", [
            f"![{name}](figures/{name}.png)", ("table", view)]))
    sections.append(("Inputs that are assumptions", [
        "These values are not given by the paper; each carries its reason in the scene file.",
        ("table", pd.DataFrame({"field": list(assumptions), "note": list(assumptions.values())})),
    ]))
    sections.append(("Inputs from the paper and the test", [
        ("table", pd.DataFrame({"field": list(sources), "note": list(sources.values())})),
    ]))

    md = [f"# deckpound report: {scene.name}", ""]
    body = [f"<h1>deckpound report: {html.escape(scene.name)}</h1>"]
    for title, items in sections:
        md += [f"## {title}", ""]
        body.append(f"<h2>{html.escape(title)}</h2>")
        for item in items:
            if isinstance(item, tuple):
                md += [_md_table(item[1]), ""]
                body.append(item[1].to_html(index=False, float_format=lambda v: f"{v:.4g}",
                                            border=0, classes="t"))
            elif item.startswith("!["):
                alt, src = item[2:].split("](")
                md += [item, ""]
                body.append(f'<p><img src="{html.escape(src[:-1])}" alt="{html.escape(alt)}" '
                            'style="max-width:100%"></p>')
            else:
                md += [item, ""]
                body.append(f"<p>{html.escape(item).replace('**', '')}</p>")
    atomic_write_text(out / "report.md", "\n".join(md))
    style = ("body{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#111}"
             "table.t{border-collapse:collapse;font-size:12px}"
             "table.t td,table.t th{border:1px solid #999;padding:2px 6px}")
    atomic_write_text(
        out / "report.html",
        f"<!doctype html><html><head><meta charset='utf-8'><title>deckpound report</title>"
        f"<style>{style}</style></head><body>{''.join(body)}</body></html>")
    return out / "report.md"

"""The main job: the paper's comparisons and studies on a scene, as a report folder.

``deckpound paper [-o DIR]`` runs, on the built-in benchmark by default,

1. the 7-run test sequence with every registered engine (gap and bent stiffness carried), twice:
   with the scene's friction and with the other assumption (frictionless gap elements as in
   common practice against μ = 0.2 with sticking);
2. per run: metrics of each engine against the reference engine, a history figure, and the
   friction mechanism (:mod:`.mechanism`) of every result;
3. the sensitivity studies of :mod:`.studies`, those marked ``carried`` from both the strongest
   run's carried state and the virgin state, the others from the virgin state;
4. a small IDA on synthetic station pairs per simulation approach: will the deck unseat
   (:mod:`.report_unseating`)?

and writes ``report.md`` / ``report.html`` (:mod:`.report_sections`: every number and direction
in the text generated from the tables), ``figures/*.png`` (``formats`` adds e.g. PDF) and
``tables/*.csv`` (units in the headers; displacements relative to the supports unless a column
says ``_abs``). Full aligned histories per run (Parquet with units in the schema metadata, and
wide CSV) only with ``full_histories``. The result cache (default ``DIR/cache``) is not part of
the report; its hits and misses per engine are.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.align import align, write_tables
from deckpound.compare.engines import DEFAULT_REFERENCE, engine_names
from deckpound.compare.mechanism import MECHANISM_UNITS, mechanism_row
from deckpound.compare.metrics import METRIC_UNITS, closure_times_per_corner, compare_pair
from deckpound.compare.progress import Progress
from deckpound.compare.report import figures
from deckpound.compare.report.figure_cache import MANIFEST_NAME, FigureManifest, reuse_figures
from deckpound.compare.report.joints import JointsRun, run_joints
from deckpound.compare.report.outputs import folder, folder_size, write_csv, write_text
from deckpound.compare.report.sections import write_report
from deckpound.compare.report.text import friction_effect
from deckpound.compare.report.unseating import UnseatingRun, run_unseating
from deckpound.compare.result_cache import ResultCache
from deckpound.compare.studies.case_rows import ROW_UNITS
from deckpound.compare.studies.sensitivity import (
    STUDIES,
    StartState,
    start_state,
    state_caption,
    study_results,
    study_units,
)
from deckpound.compare.studies.sequence_run import SequenceRun, run_sequences, strongest_run
from deckpound.models.contact_laws_table import DEFAULT_FRICTION
from deckpound.models.errors import SceneError
from deckpound.models.scene import Scene
from deckpound.models.scene_io import modified, scene_to_toml

QUANTITIES = ["deck_theta", "deck_y_rel", "deck_x_rel", "seat1_x_rel", "seat2_x_rel"]
EFFECT_UNITS = {"pga": "g", "mu": "-", "peak_theta_0": "rad", "peak_theta_mu": "rad", "ratio": "-"}


class CountingCache(ResultCache):
    """The result cache, counting its hits and misses per engine (``per_engine``)."""

    def __init__(self, folder_: str | Path):
        super().__init__(folder_)
        self.per_engine: dict[str, list[int]] = {}

    def get(self, key: str, engine: str):
        result = super().get(key, engine)
        counts = self.per_engine.setdefault(engine, [0, 0])
        counts[0 if result is not None else 1] += 1
        return result


def friction_variant(scene: Scene) -> tuple[Scene, str]:
    """The scene with the other friction assumption: μ = 0.2 with OpenSees's zeroLengthContact2D
    friction (:data:`~deckpound.models.contact_laws_table.DEFAULT_FRICTION`) if it has none,
    frictionless otherwise; and a short label for it."""

    if scene.contact.has_friction:
        return modified(scene, "contact.friction=0.0", "contact.friction_mode=none"), "μ=0"

    return (
        modified(scene, "contact.friction=0.2", f"contact.friction_mode={DEFAULT_FRICTION}"),
        "μ=0.2",
    )


def sequence_table(sequences: dict[str, list[SequenceRun]]) -> pd.DataFrame:
    """One row per (case, run): ``case`` is the key of ``sequences`` (an engine name, or an
    engine and a variant tag); peaks of displacements relative to the supports (``_rel``) and
    absolute (``_abs``); the applied PGA from the result's record provenance; run time without
    compilation and compilation time apart; whether the result came from the cache. Gap
    closures are the engine's count at every step (``gap_closures``, per corner
    ``closures_c1`` …: ``meta["gap_closures_per_corner"]``); ``first_contact_row`` is the time
    of the first output row with a corner in contact, a row-based time named apart."""
    rows = []
    for case, runs in sequences.items():
        for run in runs:
            r = run.result
            applied = (r.meta.get("record") or {}).get("applied_pga") or {}
            contact = run.scene.contact
            row = {
                "run": run.index,
                "pga": run.pga,
                "case": case,
                "engine": r.engine,
                "mu": contact.friction,
                "friction_mode": contact.friction_mode,
                "status": r.meta.get("status"),
                "applied_pga_x": applied.get("x", np.nan),
                "applied_pga_y": applied.get("y", np.nan),
                "gap1_start": run.state.gaps[0],
                "gap2_start": run.state.gaps[1],
            }
            for b, (kx, ky) in zip(run.scene.bents, run.state.stiffness):
                row[f"{b.name}_kx"], row[f"{b.name}_ky"] = kx, ky
            firsts = [t[0] for t in closure_times_per_corner(r).values() if t]
            per_corner = r.meta.get("gap_closures_per_corner") or {}
            row.update(
                peak_theta=r.peak("deck_theta"),  # every step (Result.peak)
                peak_y_rel=r.peak("deck_y_rel"),
                peak_x_rel=r.peak("deck_x_rel"),
                peak_y_abs=r.peak("deck_y_abs"),
                peak_x_abs=r.peak("deck_x_abs"),
                peak_fn=max(r.peak(f"fn_c{c}") for c in range(1, 5)),
                gap_closures=r.gap_closures,  # the engine's count, at every step
                **{f"closures_{c}": int(n) for c, n in sorted(per_corner.items())},
                first_contact_row=min(firsts) if firsts else np.nan,
                wall_time=r.meta.get("wall_time", np.nan),
                compile_time=r.meta.get("compile_time", np.nan),
                steps=r.meta.get("steps", 0),
                cached=run.cached,
            )
            rows.append(row)
    return pd.DataFrame(rows)


def sequence_units(seq: pd.DataFrame) -> dict[str, str]:
    units = {
        **ROW_UNITS,
        "pga": "g",
        "applied_pga_x": "g",
        "applied_pga_y": "g",
        "first_contact_row": "s",
        "steps": "-",
    }
    units.update({c: "kN/m" for c in seq.columns if c.endswith(("_kx", "_ky"))})
    return {k: v for k, v in units.items() if k in seq}


@dataclass
class StudyRun:
    """One study from one start state: its table and the frictional results' mechanism."""

    name: str
    state: StartState
    table: pd.DataFrame
    figure: str


@dataclass
class PaperData:
    """Everything the report is written from (see :mod:`.report_sections`)."""

    scene: Scene
    out: Path
    engines: tuple[str, ...]
    reference: str
    variant_tag: str
    sequences: dict[str, list[SequenceRun]]
    seq: pd.DataFrame
    effect: pd.DataFrame
    metrics: pd.DataFrame
    mech: pd.DataFrame
    strongest: int
    studies: list[StudyRun] = field(default_factory=list)
    carried_note: str = ""
    cache_counts: pd.DataFrame = field(default_factory=pd.DataFrame)
    formats: tuple[str, ...] = ()
    full_histories: bool = False
    wall: float = 0.0
    sizes: dict[str, int] = field(default_factory=dict)
    unseating: UnseatingRun | None = None
    joints: JointsRun | None = None
    #: figures drawn by this run, and reused unchanged from an earlier run into the folder
    figures_drawn: int = 0
    figures_reused: int = 0


def _mech_rows(source: str, state: str, run: int | None, results, scenes) -> list[dict]:
    """Mechanism rows of finished results; a frictional one is read against the frictionless
    result of the same engine among ``results``."""
    plain = {
        r.engine: r
        for label, r in results.items()
        if r.ok and not scenes[label].contact.friction > 0
    }
    rows = []
    for label, r in results.items():
        if r.ok:
            ref = plain.get(r.engine) if scenes[label].contact.friction > 0 else None
            rows.append(
                dict(
                    source=source,
                    state=state,
                    run=run,
                    case=label,
                    engine=r.engine,
                    **mechanism_row(r, scenes[label], reference=ref),
                )
            )
    return rows


#: the stages of :func:`run_paper` its log lines count (sequences, per-run figures and
#: metrics, strongest-run figures, studies, report)
PAPER_STAGES = 5


def run_paper(
    scene: Scene,
    out: str | Path,
    *,
    quick: bool = False,
    workers: int | None = None,
    scheduler: str | None = None,
    cache_dir: str | Path | None = None,
    studies: tuple[str, ...] | None = None,
    progress: bool = True,
    engines: tuple[str, ...] | None = None,
    reference: str = DEFAULT_REFERENCE,
    full_histories: bool = False,
    formats: tuple[str, ...] = (),
    redraw: bool = False,
) -> Path:
    """Run the whole comparison and write the report folder; returns the report.md path.

    ``engines`` (default: every registered engine) run the sequence; the others are compared
    against ``reference``. ``formats`` adds figure formats to PNG (e.g. ``("pdf",)``).
    A figure whose inputs are those it was drawn from into this folder before, and whose files
    are intact, is not drawn again (:mod:`.figure_cache`; fingerprints in
    ``out/figure_inputs.json``); ``redraw`` draws every figure.
    Off a terminal, the paper's stages report between the runs' own progress lines (figures and
    the report are drawn without a progress of their own): a log shows a line at least every
    :data:`~deckpound.compare.progress.PROGRESS_INTERVAL` s.
    """
    if scene.segments is not None:
        raise SceneError(
            "segments",
            "deckpound paper reproduces the paper's study of a one-body deck (its sequence, "
            "figures and studies read the deck's rotation); for a deck of segments run "
            "'deckpound compare' and 'deckpound study joint'",
        )
    stages = Progress(PAPER_STAGES, "paper", progress, log_only=True, eta=False)
    try:
        with reuse_figures(Path(out) / MANIFEST_NAME, reuse=not redraw) as manifest:
            return _paper(
                manifest,
                stages,
                scene,
                out,
                quick=quick,
                workers=workers,
                scheduler=scheduler,
                cache_dir=cache_dir,
                studies=studies,
                progress=progress,
                engines=engines,
                reference=reference,
                full_histories=full_histories,
                formats=formats,
            )
    finally:
        stages.close()


def _paper(
    manifest: FigureManifest,
    stages: Progress,
    scene: Scene,
    out: str | Path,
    *,
    quick: bool,
    workers: int | None,
    scheduler: str | None,
    cache_dir: str | Path | None,
    studies: tuple[str, ...] | None,
    progress: bool,
    engines: tuple[str, ...] | None,
    reference: str,
    full_histories: bool,
    formats: tuple[str, ...],
) -> Path:
    """:func:`run_paper`'s work, reporting its stages to ``stages`` and the figures it drew
    or reused to ``manifest``."""
    t0 = time.perf_counter()
    names = tuple(engines) if engines is not None else engine_names()
    if reference not in names:
        names = (reference,) + names
    out = folder(out)
    cache_dir = Path(cache_dir) if cache_dir is not None else out / "cache"
    cache = CountingCache(cache_dir)
    figs, tables = folder(out / "figures"), folder(out / "tables")
    write_text(out / "scene.toml", scene_to_toml(scene))

    # 1. the sequence, every engine, with both friction assumptions
    stages.note = "the sequences"
    base = run_sequences(scene, list(names), cache_dir, workers, scheduler, progress)
    variant, tag = friction_variant(scene)
    other = run_sequences(variant, list(names), cache_dir, workers, scheduler, progress)
    sequences = {**base, **{f"{e} {tag}": runs for e, runs in other.items()}}
    seq = sequence_table(sequences)
    write_csv(seq, tables / "sequence.csv", sequence_units(seq))
    figures.peak_vs_pga(seq, scene, figs / "peak_rotation_vs_pga.png", formats=formats)
    effect = friction_effect(seq)
    write_csv(effect, tables / "friction_effect_sequence.csv", EFFECT_UNITS)
    if len(effect):
        figures.friction_ratio(effect, scene, figs / "friction_ratio_vs_run.png", formats=formats)

    # 2. per run: metrics against the reference, histories, mechanism
    stages.note = "the runs' figures and metrics"
    stages.advance()
    metric_rows, mech_rows = [], []
    n_runs = min(len(v) for v in sequences.values())
    for i in range(n_runs):
        stages.note = f"run {i + 1} of {n_runs}: figures and metrics"
        results = {e: base[e][i].result for e in names}
        run = base[reference][i]
        figures.histories(
            results,
            run.scene,
            figs / f"run{run.index}_histories.png",
            title=f"run {run.index}: {run.pga:g} g transverse",
            formats=formats,
        )
        aligned = align(results)
        if full_histories:
            write_tables(aligned, tables / f"run{run.index}", formats=("parquet",), long=True)
            write_tables(aligned, tables / f"run{run.index}", formats=("csv",), long=False)
        for e in (e for e in names if e != reference):
            m = compare_pair(
                results[e], results[reference], aligned[e], aligned[reference], QUANTITIES
            )
            m.insert(0, "engine", e)
            m.insert(0, "run", run.index)
            metric_rows.append(m)
        both = {c: runs[i] for c, runs in sequences.items()}
        mech_rows += _mech_rows(
            "sequence",
            f"run{run.index}",
            run.index,
            {c: r.result for c, r in both.items()},
            {c: r.scene for c, r in both.items()},
        )
    metrics = pd.concat(metric_rows, ignore_index=True) if metric_rows else pd.DataFrame()
    write_csv(metrics, tables / f"metrics_vs_{reference}.csv", METRIC_UNITS)

    stages.note = "the strongest run's figures"
    stages.advance()
    k = strongest_run(scene)
    if n_runs >= k:
        strong = {e: base[e][k - 1].result for e in names}
        s_scene = base[reference][k - 1].scene
        figures.contact_forces(
            strong,
            s_scene,
            figs / "contact_forces_strongest.png",
            title=f"run {k}: normal contact force per corner",
            formats=formats,
        )
        figures.hysteresis(
            strong[reference],
            s_scene,
            figs / "bent_hysteresis_strongest.png",
            title=f"run {k}: bent hysteresis ({reference} engine)",
            formats=formats,
        )
        figures.plan_snapshot(strong, s_scene, figs / "plan_at_peak_rotation.png", formats=formats)
        pairs = {e: (base[e][k - 1], other[e][k - 1]) for e in names}
        figures.friction_mechanism(
            pairs, figs / "friction_mechanism_strongest.png", title=f"run {k}", formats=formats
        )

    # 3. studies, from the stated start states
    stages.note = "the studies"
    stages.advance()
    states = [start_state(scene, "virgin")]
    carried_note = ""
    ref_runs = base[reference]
    if len(ref_runs) >= k and all(r.result.ok for r in ref_runs[: k - 1]):
        states.insert(0, start_state(scene, f"run{k}", sequence=ref_runs))
    else:
        carried_note = (
            f"The {reference} sequence did not reach run {k}, so no study starts "
            "from its carried state."
        )
    study_runs = []
    chosen = (
        studies if studies is not None else [n for n in STUDIES if STUDIES[n].applies_to(scene)]
    )
    for name in chosen:
        for st in states if STUDIES[name].carried else states[-1:]:
            stages.note = f"study {name} ({st.label})"
            cases, results, table = study_results(
                name,
                st,
                quick=quick,
                cache=cache,
                workers=workers,
                scheduler=scheduler,
                progress=progress,
            )
            write_csv(table, tables / f"study_{name}_{st.label}.csv", study_units(name, table))
            fig = f"study_{name}_{st.label}.png"
            figures.study_figure(
                STUDIES[name],
                st.scene,
                cases,
                results,
                table,
                figs / fig,
                formats=formats,
                subtitle=state_caption(st),
            )
            study_runs.append(StudyRun(name, st, table, fig))
            if name == "friction":
                mech_rows += _mech_rows(
                    "friction study", st.label, st.run, results, {c.label: c.scene for c in cases}
                )
    joints = None
    if studies is None or "joint" in studies:
        stages.note = "pounding between deck segments (joint study)"
        joints = run_joints(
            scene,
            out,
            quick=quick,
            cache=cache,
            workers=workers,
            scheduler=scheduler,
            progress=progress,
            formats=formats,
        )
    stages.note = "will the deck unseat? (IDA)"
    unseating = run_unseating(
        scene,
        out,
        cache_dir,
        engines=names,
        quick=quick,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
    )
    stages.note = "the report"
    stages.advance()
    mech = pd.DataFrame(mech_rows)
    write_csv(mech, tables / "friction_mechanism.csv", MECHANISM_UNITS)

    counts = {e: [0, 0] for e in names}
    for runs in sequences.values():
        for r in runs:
            counts.setdefault(r.result.engine, [0, 0])[0 if r.cached else 1] += 1
    for e, (h, m) in cache.per_engine.items():
        counts.setdefault(e, [0, 0])
        counts[e][0] += h
        counts[e][1] += m
    cache_counts = pd.DataFrame(
        [{"engine": e, "hits": h, "misses": m} for e, (h, m) in counts.items()]
    )
    write_csv(cache_counts, tables / "cache_counts.csv", {})

    data = PaperData(
        scene=scene,
        out=out,
        engines=names,
        reference=reference,
        variant_tag=tag,
        sequences=sequences,
        seq=seq,
        effect=effect,
        metrics=metrics,
        mech=mech,
        strongest=k,
        studies=study_runs,
        carried_note=carried_note,
        cache_counts=cache_counts,
        formats=formats,
        full_histories=full_histories,
        unseating=unseating,
        joints=joints,
    )
    data.sizes = {
        "report": folder_size(out, exclude=("cache",)),
        "cache": folder_size(cache_dir) if cache_dir.is_dir() else 0,
    }
    data.figures_drawn, data.figures_reused = len(manifest.drawn), len(manifest.reused)
    data.wall = time.perf_counter() - t0
    report = write_report(data)
    stages.advance()
    return report

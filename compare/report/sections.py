"""The report of ``deckpound paper``: its sections, built from the job's tables and results.

Nothing here types a number: every value and every direction of an effect comes from the
tables (:mod:`.text`, :mod:`.inputs`); descriptions of the excitation come from
the record provenance each result carries; the scene's notes are shown as its author's words.
"""

from __future__ import annotations

import platform

import numpy as np
import pandas as pd

from deckpound.compare.engines import get_engine
from deckpound.compare.report import figures
from deckpound.compare.report import inputs as inputs
from deckpound.compare.report import text as text
from deckpound.compare.report.friction import friction
from deckpound.compare.report.joints import joints_section
from deckpound.compare.report.render import (
    BENT_FORCE,
    CONTACT_FORCE,
    MM,
    MRAD,
    Bullets,
    Figure,
    Table,
    render,
    units_sentence,
    view,
)
from deckpound.compare.report.unseating import unseating_section
from deckpound.compare.studies.sensitivity import STUDIES
from deckpound.models.engine_contract import PENETRATION_WARN_FRACTION
from deckpound.models.fields import to_mapping
from deckpound.models.result import scene_hash
from deckpound.models.version import VERSION

STUDY_COLUMNS = [
    ("label", "case", 1),
    ("engine", "engine", 1),
    ("state", "start state", 1),
    ("gap1_start", "gap 1 at start [mm]", MM),
    ("gap2_start", "gap 2 at start [mm]", MM),
    ("peak_theta", "peak θ_d [mrad]", MRAD),
    ("peak_x_rel", "peak x_d rel. tables [mm]", MM),
    ("peak_y_rel", "peak y_d rel. tables [mm]", MM),
    ("peak_fn", f"peak fn [{CONTACT_FORCE.unit}]", CONTACT_FORCE.scale),
    ("gap_closures", "gap closures", 1),
    ("wall_time", "run time [s]", 1),
    ("status", "status", 1),
]


def _settings_text(engine: str, scene) -> str:
    settings = get_engine(engine).settings_of(scene)
    items = to_mapping(settings) if hasattr(settings, "__dataclass_fields__") else {}
    return ", ".join(f"{k} = {v}" for k, v in items.items())


def what_was_run(d) -> list:
    s = d.scene
    c = s.contact
    items = [
        (
            f"Scene **{s.name}** (hash `{scene_hash(s)[:16]}`), deckpound {VERSION}, on "
            f"{platform.machine()} / Python {platform.python_version()}; the whole job took "
            f"{d.wall:.1f} s of wall time."
        ),
        units_sentence(),
        text.closure_definition_sentence(s.run.output_dt),
        f"Engines (reference: {text.engine_label(d.reference)}):",
        Bullets(
            tuple(f"{text.engine_label(e)} (`{e}`): {_settings_text(e, s)}" for e in d.engines)
        ),
        (
            f"Contact: {c.law} law, k = {c.stiffness:g} kN/m, e = {c.restitution:g}, μ = "
            f"{c.friction:g} (friction mode {c.friction_mode}), {c.geometry} geometry. Damping: "
            f"Rayleigh {100 * s.damping.ratio:g} % ({s.damping.method} {list(s.damping.modes)})."
        ),
        (
            f"Sequence: PGA labels {', '.join(f'{p:g}' for p in s.sequence.pgas)} g transverse "
            f"(longitudinal × {s.excitation.longitudinal_ratio:g}); gap carried from run to run: "
            f"{s.sequence.carry_gap}; bent stiffness carried: {s.sequence.carry_stiffness}. Every "
            f"run is computed with the scene's contact and again with the other friction assumption "
            f"({d.variant_tag})."
        ),
    ]
    cost = []
    runs = d.seq.groupby("engine", sort=False)[["wall_time", "compile_time"]].sum()
    for e in d.cache_counts["engine"]:
        row = d.cache_counts[d.cache_counts["engine"] == e].iloc[0]
        study_wall = sum(
            float(r.table.loc[r.table["engine"] == e, "wall_time"].sum()) for r in d.studies
        )
        cost.append(
            {
                "engine": e,
                "cache hits": int(row["hits"]),
                "cache misses (computed now)": int(row["misses"]),
                "sequence run time [s]": runs["wall_time"].get(e, np.nan),
                "study run time [s]": study_wall,
                "sequence compile time [s]": runs["compile_time"].get(e, np.nan),
            }
        )
    items.append(
        "Result cache, per engine: "
        + "; ".join(
            f"{text.engine_label(r['engine'])} {int(r['hits'])} hits, {int(r['misses'])} misses"
            for _, r in d.cache_counts.iterrows()
        )
        + ". A miss is a case computed by this job."
    )
    items.append(
        Table(
            pd.DataFrame(cost),
            "Cost per engine. Run times exclude compilation "
            "(numba kernels, OpenSees model build) and are as measured when each case "
            "was computed (also for cache hits); compile time is shown apart.",
        )
    )
    items.append(_quality_sentence(d))
    return items


def _quality_sentence(d) -> str:
    """The results' quality warnings (issue 16: penetration beyond a stated fraction of the
    gap, measured at every step), or that there were none."""

    found = [
        f"{case} run {r.index}: {w}"
        for case, runs in d.sequences.items()
        for r in runs
        for w in r.result.meta.get("quality_warnings", [])
    ]
    limits = (
        f"penetration beyond {PENETRATION_WARN_FRACTION[True]:.0%} (penalty engines) or "
        f"{PENETRATION_WARN_FRACTION[False]:.0%} (nonsmooth) of the smallest initial gap, "
        "measured at every step"
    )
    if not found:
        return f"Quality warnings: none in the sequence runs ({limits})."
    return f"Quality warnings ({limits}): " + "; ".join(found) + "."


def excitation(d) -> list:
    ref_runs = d.sequences[d.reference]
    prov = ref_runs[0].result.meta.get("record") or {} if ref_runs else {}
    table = inputs.record_table([(r.index, r.pga, r.result.meta.get("record")) for r in ref_runs])
    items = inputs.excitation_sentences(d.scene, prov)
    items.append(inputs.scaling_sentence(table, d.scene.excitation.longitudinal_ratio))
    cols = [
        ("run", "run", 1),
        ("pga", "label [g]", 1),
        ("target_pga_y", "target y [g]", 1),
        ("applied_pga_y", "applied y [g]", 1),
        ("target_pga_x", "target x [g]", 1),
        ("applied_pga_x", "applied x [g]", 1),
        ("scale_factor_y", "scale factor y [-]", 1),
        ("scale_factor_x", "scale factor x [-]", 1),
        ("duration", "duration [s]", 1),
    ]
    items.append(
        inputs.same_motion_sentence(
            {c: [r.result.meta.get("record") for r in runs] for c, runs in d.sequences.items()}
        )
    )
    items.append(
        Table(
            view(table, cols),
            f"Excitation of each run of the {d.reference} "
            "sequence, from the record provenance of its result; applied = max |a| "
            "over the direction's supports, measured on the motion.",
        )
    )
    files = inputs.files_table(prov)
    if len(files):
        items.append(Table(files, "Record files (resolved paths) and their SHA-256."))
    if any(r.state.label == "virgin" for r in d.studies):
        items.append(
            f"Studies from the virgin state run the scene as given: transverse PGA "
            f"label {d.scene.excitation.pga:g} g."
        )
    return items


def headline(d) -> list:
    virgin = _study_effect(d, "virgin")
    items = text.headline_sentences(d.seq, d.effect, d.strongest, d.reference, d.metrics, virgin)
    items.append(
        Figure(
            "figures/peak_rotation_vs_pga.png",
            "Peak deck rotation |θ_d| [mrad] in each run of the sequence, per engine; "
            f"hollow markers: {d.variant_tag}.",
        )
    )
    pivot = d.seq.pivot_table(
        index=["run", "pga"], columns="case", values="peak_theta", sort=False
    ).reset_index()
    pivot.columns = ["run", "PGA label [g]"] + [f"{c} peak θ_d [mrad]" for c in pivot.columns[2:]]
    pivot.iloc[:, 2:] = MRAD * pivot.iloc[:, 2:]
    items.append(
        Table(
            pivot,
            "Peak deck rotation per run and case [mrad] (tables/sequence.csv "
            "has gaps, bent stiffness, relative and absolute peaks, applied PGA, "
            "run and compile times).",
        )
    )
    return items


def _study_effect(d, state: str) -> pd.DataFrame | None:
    for r in d.studies:
        if r.name == "friction" and r.state.label == state:
            return text.study_friction_effect(r.table)
    return None


def engines_vs_reference(d) -> list:
    ref = text.engine_label(d.reference)
    m = d.metrics[d.metrics["run"] == d.strongest].copy() if len(d.metrics) else d.metrics
    items = []
    if len(m):
        scale = m["quantity"].map(lambda q: MRAD if q.endswith("theta") else MM)
        m["unit"] = m["quantity"].map(lambda q: "mrad" if q.endswith("theta") else "mm")
        m["peak"] *= scale
        m["peak_ref"] *= scale
        items.append(
            Table(
                view(
                    m,
                    [
                        ("engine", "engine", 1),
                        ("quantity", "quantity", 1),
                        ("unit", "unit", 1),
                        ("peak", "peak", 1),
                        ("peak_ref", f"peak {ref}", 1),
                        ("peak_ratio", "peak ratio [-]", 1),
                        ("nrmse", "NRMSE [-]", 1),
                        ("correlation", "correlation [-]", 1),
                    ],
                ),
                f"Run {d.strongest}, no friction: peak ratio = engine peak / {ref} "
                f"peak; NRMSE normalised by the {ref} peak. Displacements (_rel) are "
                "relative to the supports: the deck to the shake tables, a seat to "
                "its actuator.",
            )
        )
    items += [
        Figure(
            f"figures/run{d.strongest}_histories.png",
            f"Run {d.strongest}: deck rotation θ_d [mrad] and transverse displacement "
            "y_d relative to the shake tables [mm], per engine.",
        ),
        Figure(
            "figures/contact_forces_strongest.png",
            f"Run {d.strongest}: normal contact force fn per corner [{CONTACT_FORCE.unit}].",
        ),
        Figure(
            "figures/bent_hysteresis_strongest.png",
            f"Run {d.strongest}: bent force [{BENT_FORCE.unit}] against bent deformation "
            "(deck point "
            f"above the bent relative to its table) [mm], {ref} engine.",
        ),
        Figure(
            "figures/plan_at_peak_rotation.png",
            f"Run {d.strongest}: plan view at each engine's peak rotation; deck and seat "
            "displacements relative to their supports (tables, actuators) × "
            f"{figures.PLAN_SCALE:g}, so "
            "the gaps and the rotation are visible; dashed: at rest.",
        ),
    ]
    return items


def study_sections(d) -> list[tuple[str, list]]:
    out = []
    for r in d.studies:
        st = r.state
        items = [text.state_sentence(st), text.study_spread_sentence(r.table)]
        if STUDIES[r.name].summary is not None:  # the study's own sentences from its table
            items += STUDIES[r.name].summary(r.table)
        pair = text.mode_pair_sentence(r.table)
        if pair:
            items.append(pair)
        if not st.carried:
            carried = [c for c in d.studies if c.name == r.name and c.state.carried]
            if carried:
                items.append(
                    text.state_comparison_sentence(carried[0].table, r.table, carried[0].state.run)
                )
        items.append(
            Figure(
                f"figures/{r.figure}",
                f"{STUDIES[r.name].title}, from "
                f"{text.state_name(st.label)}: peak "
                "deck rotation |θ_d| [mrad] per case (left) and θ_d histories "
                "[mrad] (right).",
            )
        )
        items.append(
            Table(
                view(r.table, STUDY_COLUMNS[:2] + _param_columns(r) + STUDY_COLUMNS[2:]),
                f"tables/study_{r.name}_{st.label}.csv; displacements relative to "
                "the shake tables (absolute peaks in the CSV); run time without "
                "compilation.",
            )
        )
        out.append((f"Study: {STUDIES[r.name].title}, from {text.state_name(st.label)}", items))
    if d.carried_note:
        out.append(("Studies from a carried state", [d.carried_note]))
    return out


def _param_columns(r) -> list[tuple[str, str, float]]:
    study = STUDIES[r.name]
    fixed = {c for c, _, _ in STUDY_COLUMNS} | {"peak_x_abs", "peak_y_abs", "compile_time"}
    cols = []
    for c in r.table.columns:
        if c not in fixed:
            unit = study.unit if c == study.x and study.unit else ""
            cols.append((c, f"{c} [{unit}]" if unit else c, 1))
    return cols


def outputs(d) -> list:
    mb = 1e-6
    return [
        (
            f"This folder holds {d.sizes['report'] * mb:.2f} MB of figures, tables and scene "
            f"before the report text; the result cache (cache/ unless --cache names another "
            f"folder) holds {d.sizes['cache'] * mb:.1f} MB and is not part of the report."
        ),
        Bullets(
            (
                (
                    "tables/*.csv: units in the column headers (SI: m, rad, kN, s, g); peaks of "
                    "displacements relative to the supports (_rel) and absolute (_abs)."
                ),
                "figures/*.png"
                + (f" (also {', '.join(d.formats)})" if d.formats else " (PDF with --pdf)")
                + f". This run drew {d.figures_drawn} figures and reused {d.figures_reused} "
                "whose inputs and files were those of their last drawing into this folder "
                "(fingerprints in figure_inputs.json; --redraw draws every figure).",
                (
                    "tables/runK/aligned_*.parquet|csv: full aligned histories (units in the "
                    "Parquet schema metadata and the CSV headers)."
                    if d.full_histories
                    else "Full aligned histories per run: deckpound paper --full-histories."
                ),
                (
                    "ParaView: deckpound export-vtk on a folder written by deckpound run or "
                    "compare (one XDMF time series per engine)."
                ),
            )
        ),
    ]


def notes(d) -> list:
    table = inputs.notes_table(d.scene, inputs.builtin_twin(d.scene))
    items = [
        (
            "These are the scene author's own notes on its values (sources and assumptions), "
            "shown as written next to the value each field was run with. deckpound does not "
            "check them; a note on a value that differs from the built-in scene of the same "
            "name says what it was written for."
        )
    ]
    stale = table[table["written_for"] != ""]
    if len(stale):
        items.append(
            f"{len(stale)} note(s) were written for another value: "
            + ", ".join(stale["field"])
            + "."
        )
    items.append(Table(table))
    return items


def write_report(d):
    """Build every section and write report.md and report.html."""
    sections = [
        ("What was run", what_was_run(d)),
        ("Excitation", excitation(d)),
        ("Headline: the sequence", headline(d)),
        ("Friction: where it raises and where it lowers the rotation", friction(d)),
        (
            f"Engines against {text.engine_label(d.reference)} (strongest run)",
            engines_vs_reference(d),
        ),
    ]
    sections += study_sections(d)
    sections.append(("Will the deck unseat?", unseating_section(d.unseating)))
    if d.joints is not None:
        sections.append(("Pounding between deck segments", joints_section(d.joints)))
    sections.append(
        (
            "Every run of the sequence",
            [
                Figure(
                    f"figures/run{r.index}_histories.png",
                    f"Run {r.index} ({r.pga:g} g): deck rotation θ_d [mrad] and transverse "
                    "displacement y_d relative to the shake tables [mm], per engine, no friction.",
                )
                for r in d.sequences[d.reference]
                if (d.out / "figures" / f"run{r.index}_histories.png").is_file()
            ],
        )
    )
    sections += [("Outputs", outputs(d)), ("The scene's notes", notes(d))]
    return render(f"deckpound report: {d.scene.name}", sections, d.out)

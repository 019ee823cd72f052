"""The paper's section "Will the deck unseat?" (issue 30, item 6): a small IDA of the scene on
synthetic station pairs, per simulation approach, and whether the approach changes the
fragility.

The pairs come from the built-in generator (:func:`.ida.synthetic_pairs`, written as AT2 into
the job's cache), each scaled by one factor to every Sa(T1) level (:func:`.ida.run_ida`, rows
cached); the fragility of unseating and of the peak deck rotation above
:data:`THETA_LIMIT` is fitted per engine from each record's capacity (IDA, censored at the
highest level). :func:`approach_sentence` compares the engines' medians against the
uncertainty of a median fitted from that many records.
"""

from __future__ import annotations

import filecmp
import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from deckpound.compare.report.outputs import write_csv
from deckpound.compare.report.render import Figure, Table, view
from deckpound.compare.studies.ida import IMS, fragility_units, run_ida, synthetic_pairs
from deckpound.compare.studies.variability import table_units
from deckpound.models.contact_laws_table import DEFAULT_FRICTION
from deckpound.models.scene_io import modified

#: the engines the section compares (the sweep needs summary rows, which these give quickly)
ENGINES = ("compliance", "nonsmooth")
#: limit of the rotation limit state [rad]
THETA_LIMIT = 0.005
#: the friction coefficient the section sets against none (compliance engine only)
FRICTION = 0.3
#: intensity measure of the sweep: the pair's geometric-mean Sa(T1, 5 %) [g]
IM = "sa-t1"


@dataclass(frozen=True)
class UnseatingPlan:
    """The sweep's size: station pairs, Sa(T1) levels [g] (chosen to bracket the benchmark's
    capacities: on 22 pairs of 20 s records its unseating median is about 2.8 g and its
    rotation one about 2.5 g), record duration [s] and the generator's first seed."""

    pairs: int
    levels: tuple[float, ...]
    duration: float
    seed: int = 100


FULL = UnseatingPlan(8, (1.0, 1.75, 2.5, 3.25, 4.0, 5.0), 20.0)
QUICK = UnseatingPlan(4, (1.0, 2.0, 3.0, 4.0), 10.0)


@dataclass
class UnseatingRun:
    """What the section is written from: the sweep's rows, its fragility table, the number of
    record pairs and the figure files (relative to the report folder)."""

    table: pd.DataFrame
    frag: pd.DataFrame
    records: int
    figures: tuple[str, ...]
    plan: UnseatingPlan
    #: the compliance engine's fragility with μ = 0 and μ = :data:`FRICTION` (None: not run)
    friction_frag: pd.DataFrame | None = None


def run_unseating(
    scene,
    out: Path,
    cache_dir: Path,
    *,
    engines: tuple[str, ...],
    quick: bool,
    workers: int | None,
    scheduler: str | None,
    progress: bool,
) -> UnseatingRun | None:
    """Run the IDA of the section with those of :data:`ENGINES` that are in ``engines``
    (none: no section, ``None``); copy its figures into ``out/figures`` and its tables into
    ``out/tables`` (``unseating_ida.csv``, ``unseating_fragility.csv``)."""
    mine = tuple(e for e in ENGINES if e in engines)
    if not mine:
        return None
    plan = QUICK if quick else FULL
    generator = modified(scene, "excitation.kind=synthetic")
    records = synthetic_pairs(
        generator,
        cache_dir / f"unseating_records_{plan.pairs}x{plan.duration:g}s_seed{plan.seed}",
        plan.pairs,
        plan.seed,
        plan.duration,
    )
    work = cache_dir / "unseating_ida"
    table, frag = run_ida(
        scene,
        work,
        records=records,
        im=IM,
        levels=list(plan.levels),
        engines=mine,
        theta_limit=THETA_LIMIT,
        cache_dir=cache_dir,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        title="unseating",
    )
    figures = ("figures/unseating_fragility.png", "figures/unseating_ida.png")
    copy_figure(work / "fragility.png", out / figures[0])
    copy_figure(work / "ida.png", out / figures[1])
    unit = IMS[IM][2]
    write_csv(
        table.drop(columns=["file_x", "file_y"], errors="ignore"),
        out / "tables" / "unseating_ida.csv",
        {**table_units(table), "level": unit},
    )
    write_csv(frag, out / "tables" / "unseating_fragility.csv", fragility_units(unit))
    run = UnseatingRun(table, frag, table["record_key"].nunique(), figures, plan)
    if "compliance" in mine:
        run.friction_frag = _friction_sweep(
            scene, out, cache_dir, records, plan, workers, scheduler, progress
        )
        run.figures += ("figures/unseating_fragility_friction.png",)
    return run


def copy_figure(source: Path, target: Path) -> None:
    """Copy a figure of the sweep's folder into the report, leaving an identical copy
    untouched (a re-run that reused the figure rewrites nothing)."""
    if target.is_file() and filecmp.cmp(source, target, shallow=False):
        return
    shutil.copyfile(source, target)


def _friction_sweep(scene, out, cache_dir, records, plan, workers, scheduler, progress):
    """The same sweep with the compliance engine, frictionless and with μ = :data:`FRICTION`
    in the friction mode the package uses when it switches friction on; its fragility table
    into ``tables/unseating_fragility_friction.csv``, its figure into ``figures``."""

    work = cache_dir / "unseating_friction"
    variants = [
        ("μ=0", ("contact.friction=0.0", "contact.friction_mode=none")),
        (
            f"μ={FRICTION:g}",
            (f"contact.friction={FRICTION!r}", f"contact.friction_mode={DEFAULT_FRICTION}"),
        ),
    ]
    _, frag = run_ida(
        scene,
        work,
        records=records,
        im=IM,
        levels=list(plan.levels),
        engines=("compliance",),
        theta_limit=THETA_LIMIT,
        cache_dir=cache_dir,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        title="unseating friction",
        variants=variants,
    )
    copy_figure(work / "fragility.png", out / "figures" / "unseating_fragility_friction.png")
    write_csv(
        frag, out / "tables" / "unseating_fragility_friction.csv", fragility_units(IMS[IM][2])
    )
    return frag


def approach_sentence(frag: pd.DataFrame, records: int, unit: str = "g", by: str = "engine") -> str:
    """Does the simulation approach (``by="engine"``) or the friction (``by="variant"``)
    change the fragility? Per limit state, the IDA medians m_a, m_b [``unit``] of the first
    two ``by`` groups are compared through |ln(m_a/m_b)| against the standard error of that
    difference, sqrt(β_a² + β_b²)/sqrt(n) for n records (the lognormal median's standard
    error β/√n): within it the probability does not change measurably."""
    what = "simulation approach" if by == "engine" else "friction"
    ida = frag[(frag["method"] == "ida") & frag["median"].notna()]
    clauses = []
    for state, rows in ida.groupby("limit_state", sort=False):
        if len(rows) < 2:
            continue
        a, b = rows.iloc[0], rows.iloc[1]
        diff = abs(math.log(a["median"] / b["median"]))
        se = math.hypot(a["beta"], b["beta"]) / math.sqrt(records)
        medians = (
            f"median {a['median']:.3g} {unit} ({a[by]}) against {b['median']:.3g} {unit} ({b[by]})"
        )
        if diff <= se:
            clauses.append(
                f"for {state} it does not measurably change the probability ({medians}: "
                f"{100 * diff:.0f} % apart, within the {100 * se:.0f} % standard error of "
                f"{records} records)"
            )
        else:
            lower = a if a["median"] < b["median"] else b
            who = f"the {lower[by]} engine" if by == "engine" else f"with {lower[by]} the deck"
            clauses.append(
                f"for {state} it does: {who} reaches it at lower intensities ({medians}: "
                f"{100 * diff:.0f} % apart, beyond the {100 * se:.0f} % standard error of "
                f"{records} records)"
            )
    if not clauses:
        return (
            f"The {what} cannot be judged here: fewer than two fitted fragilities to compare "
            "(the fragility table says why)."
        )
    text = "; ".join(clauses)
    return f"Does the {what} change the probability? {text[0].upper()}{text[1:]}."


def unseating_section(run: UnseatingRun | None) -> list:
    """The items of the section "Will the deck unseat?"."""
    if run is None:
        return [
            "Not run: the paper's engines include none of "
            + ", ".join(ENGINES)
            + ", which this sweep uses."
        ]
    unit = IMS[IM][2]
    plan = run.plan
    counts = run.table["status"].value_counts().to_dict()
    status = ", ".join(f"{v} {k}" for k, v in sorted(counts.items()))
    levels = ", ".join(f"{v:g}" for v in plan.levels)
    ida = run.frag[run.frag["method"] == "ida"]
    return [
        (
            f"{run.records} synthetic station pairs of the built-in generator "
            f"({plan.duration:g} s, seeds from {plan.seed}), each scaled by one factor to "
            f"Sa(T1) = {levels} {unit}, with the "
            + " and ".join(dict.fromkeys(run.table["engine"]))
            + f" engines: {len(run.table)} cases ({status}). A record's capacity is the first "
            "level at which it exceeds the limit state (censored at the highest level); an "
            "unseated case also exceeds the rotation limit."
        ),
        approach_sentence(run.frag, run.records, unit),
        Figure(
            run.figures[0],
            f"Fragility of unseating and of peak θ_d > {THETA_LIMIT:g} rad against Sa(T1) "
            f"[{unit}], lognormal fits of the IDA capacities per engine (band: 90 % bootstrap "
            "over records); large markers: observed fractions per level.",
        ),
        Figure(
            run.figures[1],
            "IDA curves: Sa(T1) against each record's seat-width demand [mm] and peak θ_d "
            "[mrad]; ×: unseated.",
        ),
        *_friction_items(run),
        Table(
            view(
                ida,
                [
                    ("engine", "engine", 1),
                    ("limit_state", "limit state", 1),
                    ("median", f"median [{unit}]", 1),
                    ("beta", "β [-]", 1),
                    ("cases", "cases", 1),
                    ("left_out", "left out", 1),
                ],
            ),
            "tables/unseating_fragility.csv (also the MSA fits of the same rows); "
            "tables/unseating_ida.csv has every case.",
        ),
    ]


def _friction_items(run: UnseatingRun) -> list:
    if run.friction_frag is None:
        return []
    unit = IMS[IM][2]
    return [
        approach_sentence(run.friction_frag, run.records, unit, by="variant"),
        Figure(
            "figures/unseating_fragility_friction.png",
            f"The same sweep with the compliance engine, frictionless (μ = 0) and with "
            f"μ = {FRICTION:g} (tables/unseating_fragility_friction.csv): fragility of "
            "unseating and of the rotation limit against Sa(T1) [" + unit + "].",
        ),
    ]

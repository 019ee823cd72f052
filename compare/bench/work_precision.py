"""Work–precision benchmark: wall time against error for every engine and setting.

For each canonical scene (the benchmark, a single impact, a sticking-friction case, a long
record) and each configuration (engine + step or tolerance), the benchmark measures the
median wall time over ``repeats`` runs and the error against a converged reference:

* compliance-family configurations (OpenSees, compliance newmark/adaptive) against the
  ``adaptive`` compliance integrator at tight tolerance with dense Takeda commits (same model,
  so the error is pure discretisation error; see :data:`REFERENCES`);
* nonsmooth configurations against the nonsmooth engine at a very small step (rigid limit).

Errors: relative error of the peak deck rotation and of the peak transverse displacement,
and the NRMSE of the rotation history on a common time base (:mod:`.metrics`). The speed
ratio to OpenSees at equal error interpolates OpenSees's own work–precision curve (log–log)
at the configuration's primary error (peak rotation; peak deck x for the rotation-free
single pulse, see :data:`PRIMARY`), or gives a bound outside OpenSees's measured range
(column ``speedup_bound``). Output: ``bench.csv``, ``bench_context.json`` (date, machine,
repeats, the machine-speed reference before and after, the scene's default steps) and
``work_precision.png``; ``python tools/bench_tables.py work-precision`` (repository tooling)
renders them into docs/performance.md.
Timings are measurements, not pass/fail tests.
"""

from __future__ import annotations

import json
import os
import platform
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.align import align
from deckpound.compare.bench.speed import reference_loop_ns
from deckpound.compare.guarded import run_guarded
from deckpound.compare.metrics import nrmse, peak
from deckpound.compare.progress import Progress
from deckpound.compare.report.outputs import write_csv
from deckpound.compare.warmup import ITEMS, warm
from deckpound.models.file_io import atomic_write_text
from deckpound.models.scene import Scene
from deckpound.models.scene_io import modified


@dataclass(frozen=True)
class Config:
    label: str
    engine: str
    overrides: tuple[str, ...]
    family: str  # "compliance" (reference: adaptive) or "nonsmooth"


def scenes(base: Scene, quick: bool) -> dict[str, Scene]:
    """The canonical scenes (shortened in quick mode)."""
    d = 5.0 if quick else None
    out = {
        "benchmark": modified(base, *([f"excitation.duration={d!r}"] if d else [])),
        "single-impact": modified(
            base,
            "excitation.kind=pulse",
            "excitation.pga=0.4",
            "excitation.duration=2.0",
            "excitation.pulse_period=0.5",
        ),
        "sticking": modified(
            base,
            "contact.friction=0.4",
            "contact.friction_mode=stick",
            f"excitation.duration={3.0 if quick else 10.0!r}",
        ),
    }
    if not quick:
        out["long"] = modified(base, "excitation.duration=60.0")
    return out


def configs(quick: bool) -> list[Config]:
    steps = [1e-3, 2.5e-4] if quick else [2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4]
    # each row runs the step it names: the contact-step rule (run.steps_per_contact_period)
    # would shorten the coarse ones
    fixed = "run.steps_per_contact_period=0"
    out = [
        Config(f"opensees dt={h:g}", "opensees", (f"opensees.dt={h!r}", fixed), "compliance")
        for h in steps
    ]
    out += [
        Config(
            f"compliance newmark dt={h:g}",
            "compliance",
            ("compliance.integrator=newmark", f"compliance.dt={h!r}", fixed),
            "compliance",
        )
        for h in steps + ([] if quick else [5e-5])
    ]
    out += [
        Config(
            f"compliance adaptive rtol={r:g}",
            "compliance",
            (
                "compliance.integrator=adaptive",
                f"compliance.rtol={r!r}",
                f"compliance.atol={r * 1e-3!r}",
            ),
            "compliance",
        )
        for r in ([1e-4] if quick else [1e-3, 1e-4, 1e-5])
    ]
    out += [
        Config(f"nonsmooth h={h:g}", "nonsmooth", (f"nonsmooth.h={h!r}",), "nonsmooth")
        for h in ([2e-3, 5e-4] if quick else [4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4])
    ]
    return out


#: Converged references. The compliance family uses the adaptive integrator at tight tolerance
#: with the Takeda state committed every 1e-5 s once a spring has yielded (OpenSees's Hysteretic
#: material depends on where it is committed, even along monotonic paths, so the model's
#: converged answer is the dense-commit limit); on the benchmark it agrees with Newmark at
#: dt = 2e-5 to 1.5e-7 of the peak rotation.
REFERENCES = {
    "compliance": (
        "compliance.integrator=adaptive",
        "compliance.rtol=1e-08",
        "compliance.atol=1e-11",
        "compliance.commit_step=1e-05",
    ),
    "nonsmooth": ("nonsmooth.h=2e-05",),
}


#: The response whose peak error is the x axis of the work–precision plot and of the speed
#: ratio: the deck rotation, except for the single longitudinal pulse (a symmetric,
#: rotation-free response, where the peak rotation is round-off) — there the deck x.
PRIMARY = {"single-impact": "deck_x_rel"}
#: units of bench.csv's numeric columns (errors relative to the reference's peak, speed-up a
#: ratio; us: microseconds)
BENCH_UNITS = {
    "wall": "s",
    "steps": "-",
    "us_per_step": "us",
    "iterations": "-",
    "compile_time": "s",
    "err_peak_theta": "-",
    "err_peak_y": "-",
    "err_peak_x": "-",
    "nrmse_theta": "-",
    "err_primary": "-",
    "speedup_vs_opensees_equal_error": "-",
}


def _rel_peak_error(result, ref, col) -> float:
    pr = peak(ref[col])
    return abs(peak(result[col]) - pr) / pr if pr > 0 else np.nan


def _bodies(result) -> list[str]:
    """The deck's bodies in a result: ``deck``, or each segment of a deck of segments."""
    return [c[: -len("_theta")] for c in result.columns if c.endswith("_theta")
            and not c.startswith("seat")]  # fmt: skip


def errors(result, ref, primary: str = "deck_theta") -> dict[str, float]:
    """Relative peak errors, rotation-history NRMSE and the primary error ``err_primary`` (the
    relative peak error of ``primary``) of a result against a reference; for a deck of
    segments each error is the largest over the segments, a primary ``deck_<q>`` too."""
    bodies = _bodies(ref)
    cols = [f"{b}_{q}" for b in bodies for q in ("theta", "y_rel", "x_rel")]
    al = align({"x": result, "ref": ref}, columns=cols)

    def worst(q: str) -> float:
        return max(_rel_peak_error(result, ref, f"{b}_{q}") for b in bodies)

    out = {
        "err_peak_theta": worst("theta"),
        "err_peak_y": worst("y_rel"),
        "err_peak_x": worst("x_rel"),
        "nrmse_theta": max(
            nrmse(al["x"][f"{b}_theta"].to_numpy(), al["ref"][f"{b}_theta"].to_numpy())
            for b in bodies
        ),
    }
    out["err_primary"] = (
        worst(primary[len("deck_") :])
        if primary.startswith("deck_") and bodies != ["deck"]
        else _rel_peak_error(result, ref, primary)
    )
    out["primary"] = primary
    return out


def timed(engine: str, scene: Scene, repeats: int, timeout: float):
    """Median wall time (engine-reported, after a warm-up run in the same child process, so
    neither process start nor numba cache loading / OpenSees loading counts) of ``repeats``
    runs."""
    walls, outcome = [], None
    for _ in range(repeats):
        outcome = run_guarded(engine, scene, timeout, warm=True)
        if outcome.result is None:
            return outcome, np.nan
        walls.append(outcome.result.meta.get("wall_time", outcome.wall))
    return outcome, float(np.median(walls))


def speed_ratio_at_equal_error(table: pd.DataFrame) -> tuple[pd.Series, pd.Series]:
    """(ratio, kind): t_OpenSees(err) / t_config with OpenSees's time interpolated log–log at
    the configuration's primary error ``err_primary`` (kind "="). Outside OpenSees's measured
    error range the nearest end gives a bound: an error below OpenSees's smallest is reached
    by OpenSees no faster than at its most accurate setting (kind ">=", a lower bound of the
    speed-up), an error above its largest no slower than at its fastest (kind "<=").
    Compliance-family configurations only (same model as OpenSees)."""
    ratios = pd.Series(np.nan, index=table.index)
    kinds = pd.Series("", index=table.index, dtype=object)
    if "err_primary" not in table:
        return ratios, kinds
    for _scene_name, g in table.groupby("scene"):
        os_ = g[(g["engine"] == "opensees") & (g["family"] == "compliance")]
        os_ = os_[
            np.isfinite(os_["err_primary"].astype(float))
            & (os_["err_primary"] > 0)
            & np.isfinite(os_["wall"].astype(float))
        ]
        if len(os_) < 1:
            continue
        os_ = os_.sort_values("err_primary")
        le, lt = np.log(os_["err_primary"].to_numpy(float)), np.log(os_["wall"].to_numpy(float))
        for i, row in g.iterrows():
            e = row["err_primary"]
            if (
                row["family"] != "compliance"
                or not np.isfinite(e)
                or e <= 0
                or not np.isfinite(row["wall"])
            ):
                continue
            x = np.log(e)
            if len(le) >= 2 and le[0] <= x <= le[-1]:
                ratios[i] = float(np.exp(np.interp(x, le, lt)) / row["wall"])
                kinds[i] = "="
            elif x < le[0]:
                ratios[i] = float(np.exp(lt[0]) / row["wall"])
                kinds[i] = ">="
            elif x > le[-1]:
                ratios[i] = float(np.exp(lt[-1]) / row["wall"])
                kinds[i] = "<="
            else:
                ratios[i] = float(np.exp(lt[0]) / row["wall"])
                kinds[i] = "="
    return ratios, kinds


def run_bench(
    base: Scene,
    out: str | Path,
    *,
    quick: bool = False,
    repeats: int | None = None,
    timeout: float = 900.0,
    progress: bool = True,
) -> pd.DataFrame:
    """Run the work–precision benchmark; write bench.csv and figures into ``out``."""

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    repeats = repeats if repeats is not None else (1 if quick else 3)
    # the analytic kernels are loaded once, here: every guarded child is forked with them
    warm([it for it in ITEMS if it.engine in ("compliance", "nonsmooth")])
    reference_before = reference_loop_ns()
    cfgs = configs(quick)
    sc = scenes(base, quick)
    bar = Progress(len(sc) * (len(cfgs) + len(REFERENCES)), "bench", progress)
    rows = []
    t0 = time.perf_counter()
    for name, scene in sc.items():
        refs = {}
        for fam, ov in REFERENCES.items():
            outcome = run_guarded(
                "compliance" if fam == "compliance" else "nonsmooth", modified(scene, *ov), timeout
            )
            refs[fam] = outcome.result if outcome.result is not None and outcome.result.ok else None
            bar.advance()
        for cfg in cfgs:
            ov = cfg.overrides
            if (
                cfg.engine == "opensees"
                and scene.contact.has_friction
                and scene.contact.friction_mode == "stick"
            ):
                # OpenSees has no element with the project's stick law (issue 12): its
                # sticking friction is zeroLengthContact2D, as it always was in this table, so
                # its "error" against the stick-law reference is a model difference
                ov = ov + ("contact.friction_mode=contact2d",)
            outcome, wall = timed(cfg.engine, modified(scene, *ov), repeats, timeout)
            row = dict(
                scene=name,
                config=cfg.label,
                engine=cfg.engine,
                family=cfg.family,
                status=outcome.status,
                wall=wall,
                overrides=" ".join(ov),
            )
            r = outcome.result
            if r is not None:
                steps = r.meta.get("steps", np.nan)
                row.update(
                    steps=steps,
                    us_per_step=1e6 * wall / steps if steps else np.nan,
                    iterations=r.meta.get("iterations", np.nan),
                    compile_time=r.meta.get("compile_time", np.nan),
                )
                ref = refs.get(cfg.family)
                if ref is not None and r.ok:
                    row.update(errors(r, ref, PRIMARY.get(name, "deck_theta")))
            rows.append(row)
            bar.advance()
    table = pd.DataFrame(rows)
    if "err_primary" not in table:
        table["err_primary"] = np.nan
    ratio, kind = speed_ratio_at_equal_error(table)
    table["speedup_vs_opensees_equal_error"] = ratio
    table["speedup_bound"] = kind
    table.attrs["wall"] = time.perf_counter() - t0
    write_csv(table, out / "bench.csv", BENCH_UNITS)
    context = {
        "date": time.strftime("%Y-%m-%d"),
        "cpus": os.cpu_count(),
        "machine": platform.machine(),
        "python": platform.python_version(),
        "repeats": repeats,
        "quick": quick,
        "scene": base.name,
        "reference_ns": [reference_before, reference_loop_ns()],
        "defaults": {
            "opensees": {"dt": base.opensees.dt},
            "compliance": {"dt": base.compliance.dt},
            "nonsmooth": {"h": base.nonsmooth.h},
        },
    }
    atomic_write_text(out / "bench_context.json", json.dumps(context, indent=1) + "\n")
    figures(table, base, out)
    return table


def figures(table: pd.DataFrame, scene: Scene, out: Path) -> list[Path]:
    """Log–log work–precision plots (wall time vs peak-rotation error), one panel per scene."""
    from deckpound.compare.report.style import CYCLE, new_figure, save

    names = list(dict.fromkeys(table["scene"]))
    fig, axes = new_figure(1, len(names), width=3.6 * len(names), height=3.2)
    for j, name in enumerate(names):
        ax = axes[0, j]
        g = table[table["scene"] == name]
        groups = g.groupby(g["config"].str.replace(r"[ =][^ ]*$", "", regex=True), sort=False)
        for k, (label, sub) in enumerate(groups):
            if "err_primary" not in sub:
                continue
            sub = sub[
                np.isfinite(sub["err_primary"].astype(float))
                & np.isfinite(sub["wall"].astype(float))
            ]
            if not len(sub):
                continue
            st = dict(CYCLE[k % len(CYCLE)])
            ax.loglog(
                np.maximum(sub["err_primary"].astype(float), 1e-16), sub["wall"], label=label, **st
            )
        ax.axvline(0.01, color="#999999", linestyle=":", linewidth=0.8)
        primary = PRIMARY.get(name, "deck_theta").replace("deck_", "deck ")
        ax.set_xlabel(f"relative error of peak {primary} [-]")
        ax.set_ylabel("wall time [s]")
        ax.set_title(name)
        ax.legend(fontsize=6)
    return save(fig, out / "work_precision.png", scene.name, ("pdf",))

"""Work–precision benchmark: wall time against error for every engine and setting.

For each canonical scene (the benchmark, a single impact, a sticking-friction case, a long
record) and each configuration (engine + step or tolerance), the benchmark measures the
median wall time over ``repeats`` runs and the error against a converged reference:

* compliance-family configurations (OpenSees, compliance newmark/adaptive) against the
  ``adaptive`` compliance integrator at tight tolerance (same model, so the error is pure
  discretisation error);
* nonsmooth configurations against the nonsmooth engine at a very small step (rigid limit).

Errors: relative error of the peak deck rotation and of the peak transverse displacement,
and the NRMSE of the rotation history on a common time base (:mod:`.metrics`). The speed
ratio to OpenSees at equal error interpolates OpenSees's own work–precision curve (log–log)
at the configuration's peak-rotation error. Output: ``bench.csv`` and ``bench_<scene>.png``.
Timings are measurements, not pass/fail tests.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.models.scene import Scene

from .align import align
from .guarded import run_guarded
from .metrics import nrmse, peak
from .studies import modified


@dataclass(frozen=True)
class Config:
    label: str
    engine: str
    overrides: tuple[str, ...]
    family: str          # "compliance" (reference: adaptive) or "nonsmooth"


def scenes(base: Scene, quick: bool) -> dict[str, Scene]:
    """The canonical scenes (shortened in quick mode)."""
    d = 5.0 if quick else None
    out = {
        "benchmark": modified(base, *( [f"excitation.duration={d!r}"] if d else [])),
        "single-impact": modified(base, "excitation.kind=pulse", "excitation.pga=0.4",
                                  "excitation.duration=2.0", "excitation.pulse_period=0.5"),
        "sticking": modified(base, "contact.friction=0.4", "contact.friction_mode=stick",
                             f"excitation.duration={3.0 if quick else 10.0!r}"),
    }
    if not quick:
        out["long"] = modified(base, "excitation.duration=60.0")
    return out


def configs(quick: bool) -> list[Config]:
    steps = [1e-3, 2.5e-4] if quick else [2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4]
    out = [Config(f"opensees dt={h:g}", "opensees", (f"opensees.dt={h!r}",), "compliance")
           for h in steps]
    out += [Config(f"compliance newmark dt={h:g}", "compliance",
                   ("compliance.integrator=newmark", f"compliance.dt={h!r}"), "compliance")
            for h in steps + ([] if quick else [5e-5])]
    out += [Config(f"compliance adaptive rtol={r:g}", "compliance",
                   ("compliance.integrator=adaptive", f"compliance.rtol={r!r}",
                    f"compliance.atol={r * 1e-3!r}"), "compliance")
            for r in ([1e-4] if quick else [1e-3, 1e-4, 1e-5])]
    out += [Config(f"nonsmooth h={h:g}", "nonsmooth", (f"nonsmooth.h={h!r}",), "nonsmooth")
            for h in ([2e-3, 5e-4] if quick else [4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4])]
    return out


REFERENCES = {
    "compliance": ("compliance.integrator=adaptive", "compliance.rtol=1e-08",
                   "compliance.atol=1e-11"),
    "nonsmooth": ("nonsmooth.h=2e-05",),
}


def errors(result, ref) -> dict[str, float]:
    """Relative peak errors and rotation-history NRMSE of a result against a reference."""
    al = align({"x": result, "ref": ref}, columns=["deck_theta", "deck_y"])
    pr, py = peak(ref["deck_theta"]), peak(ref["deck_y"])
    return {
        "err_peak_theta": abs(peak(result["deck_theta"]) - pr) / pr if pr > 0 else np.nan,
        "err_peak_y": abs(peak(result["deck_y"]) - py) / py if py > 0 else np.nan,
        "nrmse_theta": nrmse(al["x"]["deck_theta"].to_numpy(), al["ref"]["deck_theta"].to_numpy()),
    }


def timed(engine: str, scene: Scene, repeats: int, timeout: float):
    """Median wall time (engine-reported, excluding process start) of ``repeats`` runs."""
    walls, outcome = [], None
    for _ in range(repeats):
        outcome = run_guarded(engine, scene, timeout)
        if outcome.result is None:
            return outcome, np.nan
        walls.append(outcome.result.meta.get("wall_time", outcome.wall))
    return outcome, float(np.median(walls))


def speed_ratio_at_equal_error(table: pd.DataFrame) -> pd.Series:
    """t_OpenSees(err) / t_config, OpenSees's time interpolated log–log at the same error."""
    ratios = pd.Series(np.nan, index=table.index)
    for scene_name, g in table.groupby("scene"):
        os_ = g[(g["engine"] == "opensees") & (g["family"] == "compliance")]
        os_ = os_[np.isfinite(os_["err_peak_theta"]) & (os_["err_peak_theta"] > 0)]
        if len(os_) < 2:
            continue
        os_ = os_.sort_values("err_peak_theta")
        le, lt = np.log(os_["err_peak_theta"].to_numpy()), np.log(os_["wall"].to_numpy())
        for i, row in g.iterrows():
            e = row["err_peak_theta"]
            if row["family"] != "compliance" or not np.isfinite(e) or e <= 0:
                continue
            if le[0] <= np.log(e) <= le[-1]:
                ratios[i] = float(np.exp(np.interp(np.log(e), le, lt)) / row["wall"])
    return ratios


def run_bench(base: Scene, out: str | Path, *, quick: bool = False, repeats: int | None = None,
              timeout: float = 900.0, progress: bool = True) -> pd.DataFrame:
    """Run the work–precision benchmark; write bench.csv and figures into ``out``."""
    from .cases import Progress

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    repeats = repeats if repeats is not None else (1 if quick else 3)
    cfgs = configs(quick)
    sc = scenes(base, quick)
    bar = Progress(len(sc) * (len(cfgs) + len(REFERENCES)), "bench", progress)
    rows = []
    t0 = time.perf_counter()
    for name, scene in sc.items():
        refs = {}
        for fam, ov in REFERENCES.items():
            outcome = run_guarded("compliance" if fam == "compliance" else "nonsmooth",
                                  modified(scene, *ov), timeout)
            refs[fam] = outcome.result if outcome.result is not None and outcome.result.ok else None
            bar.advance()
        for cfg in cfgs:
            outcome, wall = timed(cfg.engine, modified(scene, *cfg.overrides), repeats, timeout)
            row = dict(scene=name, config=cfg.label, engine=cfg.engine, family=cfg.family,
                       status=outcome.status, wall=wall)
            r = outcome.result
            if r is not None:
                steps = r.meta.get("steps", np.nan)
                row.update(steps=steps, us_per_step=1e6 * wall / steps if steps else np.nan,
                           iterations=r.meta.get("iterations", np.nan))
                ref = refs.get(cfg.family)
                if ref is not None and r.ok:
                    row.update(errors(r, ref))
            rows.append(row)
            bar.advance()
    table = pd.DataFrame(rows)
    table["speedup_vs_opensees_equal_error"] = speed_ratio_at_equal_error(table)
    table.attrs["wall"] = time.perf_counter() - t0
    table.to_csv(out / "bench.csv", index=False)
    figures(table, base, out)
    return table


def figures(table: pd.DataFrame, scene: Scene, out: Path) -> list[Path]:
    """Log–log work–precision plots (wall time vs peak-rotation error), one panel per scene."""
    from .style import CYCLE, new_figure, save

    names = list(dict.fromkeys(table["scene"]))
    fig, axes = new_figure(1, len(names), width=3.6 * len(names), height=3.2)
    for j, name in enumerate(names):
        ax = axes[0, j]
        g = table[table["scene"] == name]
        groups = g.groupby(g["config"].str.replace(r"[ =][^ ]*$", "", regex=True), sort=False)
        for k, (label, sub) in enumerate(groups):
            sub = sub[np.isfinite(sub.get("err_peak_theta", pd.Series(dtype=float)))]
            if not len(sub):
                continue
            st = dict(CYCLE[k % len(CYCLE)])
            ax.loglog(np.maximum(sub["err_peak_theta"], 1e-16), sub["wall"], label=label, **st)
        ax.axvline(0.01, color="#999999", linestyle=":", linewidth=0.8)
        ax.set_xlabel("error in peak deck rotation [-]")
        ax.set_ylabel("wall time [s]")
        ax.set_title(name)
        ax.legend(fontsize=6)
    return save(fig, out / "work_precision.png", scene.name, ("pdf",))

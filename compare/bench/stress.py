"""Numerical stability stress test: every engine over a grid of hard settings.

Grid (around the benchmark, on a short record): a two-way grid of contact stiffness
(1e4 … 1e10 kN/m) × time step (1e-5 … 1e-2 s, each engine's own step), plus one-way sweeps of
PGA (0.05 … 2 g), gap (0 … 0.1 m, including 0 = initial contact), friction (0 … 0.8) and
restitution (0 … 1). For each engine and cell the table records: finished or not (status),
whether every output is finite, the largest penetration max(−g_N), the energy-balance error
(engines that track energy), the nonsmooth complementarity residual, wall time, and the
failure message with its time. Each cell runs in a guarded child process with a time limit,
so a cell ends with finite results or a clear failure status — never NaN silently, never a
hang. Output: ``stress.csv`` and heat maps ``stress_*.png``.
"""

from __future__ import annotations

import itertools
import time
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.engines import engine_names, get_engine
from deckpound.compare.guarded import GuardedOutcome, run_guarded
from deckpound.compare.progress import Progress
from deckpound.compare.report.outputs import write_csv
from deckpound.models.contact_laws_table import DEFAULT_FRICTION
from deckpound.models.scene import Scene
from deckpound.models.scene_io import modified


def step_field(engine: str) -> str:
    """Dotted scene path of an engine's time step (declared by the engine)."""
    e = get_engine(engine)
    return f"{e.settings_field}.{e.step_field}"


FULL = dict(
    stiffness=[1e4, 1e6, 1e8, 1e10],
    dt=[1e-5, 1e-4, 1e-3, 1e-2],
    pga=[0.05, 0.5, 1.0, 2.0],
    gap=[0.0, 0.0127, 0.1],
    friction=[0.0, 0.2, 0.8],
    restitution=[0.0, 0.6, 1.0],
)
#: units of the table's numeric columns (energy_error: relative to the input energy;
#: complementarity: the nonsmooth engine's largest verified residual)
STRESS_UNITS = {
    "stiffness": "kN/m",
    "dt": "s",
    "pga": "g",
    "gap": "m",
    "friction": "-",
    "restitution": "-",
    "wall": "s",
    "max_penetration": "m",
    "energy_error": "-",
    "complementarity": "m/s",
    "failed_time": "s",
    "failed_step": "-",
    "t_end": "s",
}
QUICK = dict(
    stiffness=[1e4, 1e10], dt=[1e-4, 1e-2], pga=[2.0], gap=[0.0], friction=[0.8], restitution=[0.0]
)


def grid(quick: bool = False) -> list[dict]:
    """Cells as dicts of the parameters that differ from the base scene."""
    g = QUICK if quick else FULL
    cells = [dict(stiffness=k, dt=dt) for k, dt in itertools.product(g["stiffness"], g["dt"])]
    for name in ("pga", "gap", "friction", "restitution"):
        cells += [{name: v} for v in g[name]]
    return cells


def cell_scene(base: Scene, engine: str, cell: dict, duration: float) -> Scene:
    """The base scene with one cell's settings; output every 5 ms (or every step if coarser)."""
    step = cell.get("dt")
    ov = [f"excitation.duration={duration!r}", f"run.output_dt={max(0.005, step or 0.0)!r}"]
    if "stiffness" in cell:
        ov.append(f"contact.stiffness={cell['stiffness']!r}")
    if step is not None:  # the cell's own step: the contact-step rule would shorten it
        ov += [f"{step_field(engine)}={step!r}", "run.steps_per_contact_period=0"]
    if "pga" in cell:
        ov.append(f"excitation.pga={cell['pga']!r}")
    if "gap" in cell:
        ov += [f"seats[0].gap={cell['gap']!r}", f"seats[1].gap={cell['gap']!r}"]
    if "friction" in cell:
        mu = cell["friction"]

        mode = DEFAULT_FRICTION if mu > 0 else "none"
        ov += [f"contact.friction={mu!r}", f"contact.friction_mode={mode}"]
    if "restitution" in cell:
        ov.append(f"contact.restitution={cell['restitution']!r}")
    return modified(base, *ov)


def _row(engine: str, cell: dict, outcome) -> dict:
    row = dict(engine=engine, **{k: cell.get(k, np.nan) for k in FULL})
    row.update(status=outcome.status, wall=outcome.wall, message=outcome.message[:200])
    r = outcome.result
    if r is None:
        row.update(
            finite=False,
            max_penetration=np.nan,
            energy_error=np.nan,
            complementarity=np.nan,
            failed_time=np.nan,
            failed_step=np.nan,
            t_end=np.nan,
        )
        return row
    data = np.column_stack(list(r.columns.values()))
    gaps = np.column_stack([r[f"gap_c{c}"] for c in range(1, 5)])
    row.update(
        finite=bool(np.all(np.isfinite(data))),
        max_penetration=float(max(0.0, -np.min(gaps))) if len(gaps) else np.nan,
        energy_error=_energy_error(r),
        complementarity=float(r.meta.get("max_complementarity", np.nan)),
        failed_time=_num(r.meta.get("failed_time")),
        failed_step=_num(r.meta.get("failed_step")),
        t_end=float(r.t[-1]) if len(r.t) else np.nan,
    )
    if row["status"] == "success" and not row["finite"]:
        # an engine must never return non-finite output as a success (engine contract)
        row["status"] = "non-finite"
        row["message"] = ("reported success but the output holds NaN/inf: " + row["message"])[:200]
    return row


def _num(value) -> float:
    return float(value) if value is not None else np.nan


def _energy_error(r) -> float:
    """Energy-balance error relative to the input, max|energy_error| / max|energy_input| from
    the columns (every engine that tracks energy has both), else the engine's own relative
    ``energy_closure``; NaN for a result without an energy balance."""
    if "energy_error" in r.columns and "energy_input" in r.columns and len(r.t):
        with np.errstate(all="ignore"):
            ein = float(np.max(np.abs(r["energy_input"])))
            return float(np.max(np.abs(r["energy_error"]))) / ein if ein > 0 else np.nan
    if r.meta.get("energy_closure") is not None:
        return float(r.meta["energy_closure"])
    return np.nan


def run_stress(
    base: Scene,
    out: str | Path,
    *,
    quick: bool = False,
    engines: tuple[str, ...] | None = None,
    duration: float | None = None,
    timeout: float = 300.0,
    progress: bool = True,
    cells: list[dict] | None = None,
) -> pd.DataFrame:
    """Run the grid (or the given ``cells``), write stress.csv and heat maps into ``out``;
    return the table.

    Status per cell: ``success`` (finished; output checked finite), ``failed`` (the engine's
    own failure status, with ``failed_time`` / ``failed_step``), ``non-finite`` (reported
    success with NaN/inf in the output: an engine bug, never hidden), ``timeout``,
    ``crashed`` (exception or dead child, message kept) or ``refused`` (the scene validation
    rejected the cell)."""

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    duration = duration if duration is not None else (1.0 if quick else 5.0)
    cells = grid(quick) if cells is None else cells
    rows = []
    engines = tuple(engines) if engines is not None else engine_names()
    bar = Progress(len(cells) * len(engines), "stress", progress)
    t0 = time.perf_counter()
    for cell in cells:
        for engine in engines:
            try:
                scene = cell_scene(base, engine, cell, duration)
            except Exception as err:  # a cell the scene itself refuses is a result, too
                outcome = GuardedOutcome("refused", None, str(err), 0.0)
            else:
                outcome = run_guarded(engine, scene, timeout)
            rows.append(_row(engine, cell, outcome))
            bar.advance()
    table = pd.DataFrame(rows)
    table.attrs["wall"] = time.perf_counter() - t0
    write_csv(table, out / "stress.csv", STRESS_UNITS)
    heat_maps(table, base, out)
    return table


def heat_maps(table: pd.DataFrame, scene: Scene, out: Path) -> list[Path]:
    """Stiffness × step maps of outcome and penetration per engine; one-way sweeps as a grid."""
    from matplotlib.colors import ListedColormap, LogNorm

    from deckpound.compare.report.style import new_figure, save

    status_cmap = ListedColormap(["#f4a6a6", "#a8dba8"])  # 0 FAIL (red), 1 ok (green)
    written = []
    two_way = table.dropna(subset=["stiffness", "dt"])
    engines = list(dict.fromkeys(table["engine"]))
    if len(two_way):
        fig, axes = new_figure(2, len(engines), width=3.3 * len(engines), height=2.8)
        ks = sorted(two_way["stiffness"].unique())
        dts = sorted(two_way["dt"].unique())
        for j, e in enumerate(engines):
            sub = two_way[two_way["engine"] == e]
            ok = np.full((len(dts), len(ks)), np.nan)
            pen = np.full((len(dts), len(ks)), np.nan)
            for _, r in sub.iterrows():
                i, k = dts.index(r["dt"]), ks.index(r["stiffness"])
                ok[i, k] = 1.0 if (r["status"] == "success" and r["finite"]) else 0.0
                pen[i, k] = 1e3 * r["max_penetration"]
            for row, (data, title) in enumerate(
                ((ok, "finished with finite output"), (pen, "max penetration [mm]"))
            ):
                ax = axes[row, j]
                ax.grid(False)
                norm = None
                if row == 0:
                    im = ax.imshow(
                        data, cmap=status_cmap, origin="lower", aspect="auto", vmin=0, vmax=1
                    )
                else:
                    pos = data[np.isfinite(data) & (data > 0)]
                    norm = (
                        LogNorm(vmin=pos.min(), vmax=max(pos.max(), pos.min() * 10))
                        if len(pos)
                        else None
                    )
                    im = ax.imshow(
                        np.where(data > 0, data, np.nan),
                        cmap="Blues",
                        origin="lower",
                        aspect="auto",
                        norm=norm,
                    )
                for (i, k), v in np.ndenumerate(data):
                    label = (
                        "—"
                        if not np.isfinite(v)
                        else (("ok" if v else "FAIL") if row == 0 else f"{v:.3g}")
                    )
                    dark = (
                        row == 1 and norm is not None and np.isfinite(v) and v > 0 and norm(v) > 0.6
                    )
                    ax.text(
                        k,
                        i,
                        label,
                        ha="center",
                        va="center",
                        fontsize=6,
                        color="white" if dark else "black",
                    )
                ax.set_xticks(range(len(ks)))
                ax.set_xticklabels([f"{k:.0e}" for k in ks], fontsize=6)
                ax.set_yticks(range(len(dts)))
                ax.set_yticklabels([f"{d:.0e}" for d in dts], fontsize=6)
                ax.set_xlabel("contact stiffness [kN/m]")
                ax.set_ylabel("time step [s]")
                ax.set_title(f"{e}: {title}", fontsize=8)
                if row == 1:
                    fig.colorbar(im, ax=ax, shrink=0.8)
        written += save(fig, out / "stress_stiffness_dt.png", scene.name)
    sweeps = [c for c in ("pga", "gap", "friction", "restitution") if table[c].notna().any()]
    if sweeps:
        fig, axes = new_figure(1, len(sweeps), width=2.6 * len(sweeps), height=2.6)
        for j, c in enumerate(sweeps):
            sub = table[table[c].notna()]
            vals = sorted(sub[c].unique())
            data = np.full((len(engines), len(vals)), np.nan)
            for _, r in sub.iterrows():
                data[engines.index(r["engine"]), vals.index(r[c])] = (
                    1.0 if (r["status"] == "success" and r["finite"]) else 0.0
                )
            ax = axes[0, j]
            ax.grid(False)
            ax.imshow(data, cmap=status_cmap, vmin=0, vmax=1, aspect="auto")
            for (i, k), v in np.ndenumerate(data):
                label = "—" if not np.isfinite(v) else ("ok" if v == 1 else "FAIL")
                ax.text(k, i, label, ha="center", va="center", fontsize=6, color="black")
            ax.set_xticks(range(len(vals)))
            ax.set_xticklabels([f"{v:g}" for v in vals], fontsize=7)
            ax.set_yticks(range(len(engines)))
            ax.set_yticklabels(engines, fontsize=7)
            ax.set_xlabel(c)
        written += save(fig, out / "stress_sweeps.png", scene.name)
    return written

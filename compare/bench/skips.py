"""What each work-saving skip of the compliance engine saves, measured (``deckpound bench --skips``).

For a few scenes — the benchmark, a contact-free variant (gaps so wide that no corner ever
closes), an elastic variant (low PGA: the Takeda springs never yield) and a frictional one
(μ = 0.4, stick) next to the frictionless benchmark — the Newmark integrator runs with every
skip on (the default) and with one skip turned off
(:data:`deckpound.analytic.compliance.engine.SKIPS`, the private ``_skips`` keyword), and the table
gives both times (best of ``repeats`` in-process runs after a warm-up, numba compiled, the
support record built once and not timed), the
saving and the largest absolute difference between the two results over every column (must
be 0: a skip never changes a result). Further rows:

* ``channels`` — only ``deck_theta`` stored (no energy bookkeeping) against every column
  (difference over the stored column);
* ``takeda_pow`` — the Hysteretic kernel's own elastic short-circuit (``pow`` skipped while
  the ductility is ≤ 1), off in a child process with ``DECKPOUND_TAKEDA_SHORTCUT=0`` and its
  own numba cache (the flag is a compile-time constant);
* ``geometry`` — the nonlinear kinematics against the linear one: not a skip with identical
  results but the price of asking for the geometric-nonlinear terms (difference reported for
  information).
* ``subnormals`` — ``compliance.subnormals = "flush"`` (the default) against ``"keep"``
  (:mod:`deckpound.analytic.fp_mode`): not a skip either; the results differ only below
  1e-250 (the largest difference over every column is reported).

The adaptive integrator's step-size distribution in and out of contact (median, min, max of
the accepted steps, from its ``step_sizes`` metadata) is reported for the same scenes, twice:
with the default cap ``compliance.commit_step`` after the first Takeda yield (the converged
answer of the model needs dense commits, see :mod:`deckpound.analytic.compliance.adaptive`) and with the
cap lifted to ``compliance.max_step``, where the error control and the contact events alone
set the steps.
Output: ``skips.csv`` and ``adaptive_steps.csv``. Timings are measurements, not tests.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.report.outputs import write_csv
from deckpound.models.excitation import support_motion
from deckpound.models.fields import to_mapping
from deckpound.models.scene import Scene
from deckpound.models.scene_io import modified
from deckpound.models.scene_settings import SUBNORMALS_UNCHANGED_ABOVE

#: (row, the alternative's override, columns of max_abs_diff (None: every column), note): the
#: rows that time a modelling or floating-point choice against its default
CHOICES = (
    (
        "geometry",
        "contact.geometry=nonlinear",
        ["deck_theta"],
        "linear vs nonlinear kinematics: a different model; max_abs_diff is that of "
        "deck_theta [rad], for information",
    ),
    (
        "subnormals",
        "compliance.subnormals=keep",
        None,
        "subnormal numbers flushed to zero (the default) vs kept: a floating-point "
        "choice, not a skip; max_abs_diff over every column",
    ),
)


#: units of adaptive_steps.csv's numeric columns (the step statistics and ``time``, the
#: simulated time the steps cover, in s)
STEP_UNITS = {
    "commit_step": "s",
    "steps": "-",
    "median": "s",
    "min": "s",
    "max": "s",
    "mean": "s",
    "time": "s",
    "wall": "s",
    "rtol": "-",
}


def skip_scenes(base: Scene, quick: bool) -> dict[str, Scene]:
    d = 10.0 if quick else 20.0
    dur = f"run.duration={d!r}"
    return {
        "benchmark": modified(base, dur),
        "contact-free": modified(base, dur, "seats[0].gap=1.0", "seats[1].gap=1.0"),
        "elastic": modified(base, dur, "excitation.pga=0.05"),
        "friction": modified(base, dur, "contact.friction=0.4", "contact.friction_mode=stick"),
    }


def _timed(fn, repeats: int):
    """(result, best wall time of ``repeats`` runs) — the minimum is the least noisy estimate
    of a deterministic computation's cost on a shared machine."""
    walls, r = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        r = fn()
        walls.append(time.perf_counter() - t0)
    return r, float(np.min(walls))


def _paired(fn_a, fn_b, repeats: int):
    """Interleaved timing of two variants (a, b, a, b, ...): best of each, so that drifting
    machine load biases neither. Returns (result_a, t_a, result_b, t_b)."""
    ta, tb = [], []
    ra = rb = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        ra = fn_a()
        t1 = time.perf_counter()
        rb = fn_b()
        t2 = time.perf_counter()
        ta.append(t1 - t0)
        tb.append(t2 - t1)
    return ra, float(np.min(ta)), rb, float(np.min(tb))


def max_diff(a, b, columns=None) -> float:
    """Largest |a − b| over the given (default: all common) columns; inf if lengths differ."""
    cols = columns or [c for c in a.columns if c in b.columns]
    out = 0.0
    for c in cols:
        x, y = np.asarray(a.columns[c]), np.asarray(b.columns[c])
        if x.shape != y.shape:
            return float("inf")
        if len(x):
            out = max(out, float(np.max(np.abs(x - y))))
    return out


#: rows of skips.csv that are choices with (slightly) different results, not skips
NOT_SKIPS = ("geometry", "subnormals")


def skip_failures(skips: pd.DataFrame) -> pd.DataFrame:
    """The rows of ``skips.csv`` whose claim fails: a skip that changed a result, or flushed
    subnormals that changed one by more than ``SUBNORMALS_UNCHANGED_ABOVE`` (1e-250;
    ``geometry`` is a model choice: any difference is information)."""
    changed = ~skips["identical"].astype(bool)
    skip = ~skips["skip"].isin(NOT_SKIPS)
    flush = (skips["skip"] == "subnormals") & (skips["max_abs_diff"] > SUBNORMALS_UNCHANGED_ABOVE)
    return skips[(skip & changed) | flush]


_TAKEDA_CHILD = r"""
import json, sys, time, warnings
import numpy as np
warnings.simplefilter("ignore")
from deckpound.analytic.kernels import hysteretic_kernel as hk
from deckpound.analytic.compliance.engine import run_compliance
from deckpound.models.scene_io import scene_from_mapping
from deckpound.models.excitation import support_motion
assert not hk.ELASTIC_SHORTCUT
spec = json.loads(open(sys.argv[1]).read())
out = {}
for name, mapping in spec["scenes"].items():
    sc = scene_from_mapping(mapping)
    run_compliance(sc)                      # compile / warm
    walls = []
    m = support_motion(sc)
    for _ in range(spec["repeats"]):
        t0 = time.perf_counter(); r = run_compliance(sc, m); walls.append(time.perf_counter() - t0)
    np.savez(spec["folder"] + f"/{name}.npz", **r.columns)
    out[name] = float(np.min(walls))
print(json.dumps(out))
"""


def _takeda_off(scenes: dict[str, Scene], repeats: int, timeout: float) -> dict:
    """Times and results with the kernel's pow short-circuit off (child process)."""

    with tempfile.TemporaryDirectory(prefix="deckpound-skips-") as tmp:
        spec = {
            "scenes": {k: to_mapping(s) for k, s in scenes.items()},
            "repeats": repeats,
            "folder": tmp,
        }
        (Path(tmp) / "spec.json").write_text(json.dumps(spec))
        env = dict(
            os.environ,
            DECKPOUND_TAKEDA_SHORTCUT="0",
            NUMBA_CACHE_DIR=str(Path(tmp) / "numba-cache"),
        )
        proc = subprocess.run(
            [sys.executable, "-c", _TAKEDA_CHILD, str(Path(tmp) / "spec.json")],
            capture_output=True,
            text=True,
            env=env,
            timeout=timeout,
        )
        if proc.returncode != 0:
            raise RuntimeError(proc.stderr[-1500:])
        walls = json.loads(proc.stdout.strip().splitlines()[-1])
        cols = {k: dict(np.load(Path(tmp) / f"{k}.npz")) for k in scenes}
    return {k: (walls[k], cols[k]) for k in scenes}


def run_skips(
    base: Scene,
    out: str | Path,
    *,
    quick: bool = False,
    repeats: int | None = None,
    takeda: bool = True,
    timeout: float = 1800.0,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Measure every skip (see the module docstring); write skips.csv, adaptive_steps.csv."""
    from deckpound.analytic.compliance.engine import SKIPS, run_compliance

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    repeats = repeats if repeats is not None else (3 if quick else 5)
    scenes = skip_scenes(base, quick)
    rows = []
    steps_rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, sc in scenes.items():
            sc = modified(sc, "compliance.integrator=newmark")
            m = support_motion(sc)  # built once: the record is not timed
            run_compliance(sc, m)  # compile / warm
            ref, t_on = _timed(lambda: run_compliance(sc, m), repeats)
            n = max(int(ref.meta["steps"]), 1)

            def add(skip, t_with, t_without, diff, note=""):
                rows.append(
                    dict(
                        scene=name,
                        skip=skip,
                        time_with=t_with,
                        time_without=t_without,
                        saving=1.0 - t_with / t_without,
                        speedup=t_without / t_with,
                        us_per_step_with=1e6 * t_with / n,
                        us_per_step_without=1e6 * t_without / n,
                        max_abs_diff=diff,
                        identical=diff == 0.0,
                        gap_closures=ref.gap_closures,
                        note=note,
                    )
                )

            for skip in SKIPS:
                _a, t_a, r, t_off = _paired(
                    lambda: run_compliance(sc, m),
                    lambda: run_compliance(sc, m, _skips={skip: False}),
                    repeats,
                )
                add(skip, t_a, t_off, max_diff(ref, r))
            r, t_ch, _a, t_a = _paired(
                lambda: run_compliance(sc, m, channels=["deck_theta"]),
                lambda: run_compliance(sc, m),
                repeats,
            )
            add(
                "channels",
                t_ch,
                t_a,
                max_diff(ref, r, ["t", "deck_theta"]),
                "deck_theta only vs every column",
            )
            # choices with other results, not skips: the default against the alternative
            for label, override, diff_cols, note in CHOICES:
                other = modified(sc, override)
                run_compliance(other, m)  # compile / warm
                _a, t_a, r, t_other = _paired(
                    lambda: run_compliance(sc, m), lambda: run_compliance(other, m), repeats
                )
                add(label, t_a, t_other, max_diff(ref, r, diff_cols), note)
            ad = modified(sc, "compliance.integrator=adaptive")
            lifted = modified(ad, f"compliance.commit_step={ad.compliance.max_step!r}")
            for cap, scn in (("default", ad), ("lifted", lifted)):
                ra = run_compliance(scn, m)
                for where, st in ra.meta["step_sizes"].items():
                    steps_rows.append(
                        dict(
                            scene=name,
                            commit_cap=cap,
                            commit_step=scn.compliance.commit_step,
                            where=where,
                            **st,
                            wall=ra.meta["wall_time"],
                            rtol=scn.compliance.rtol,
                        )
                    )
            if takeda:
                rows.append(dict(scene=name, skip="takeda_pow", time_with=t_on, _ref=ref))
    if takeda:
        off = _takeda_off(
            {k: modified(s, "compliance.integrator=newmark") for k, s in scenes.items()},
            repeats,
            timeout,
        )
        for row in rows:
            if row.get("skip") == "takeda_pow":
                ref = row.pop("_ref")
                t_off, cols = off[row["scene"]]
                diff = 0.0
                for c, v in cols.items():
                    diff = max(diff, float(np.max(np.abs(v - ref.columns[c]))))
                n = max(int(ref.meta["steps"]), 1)
                row.update(
                    time_without=t_off,
                    saving=1.0 - row["time_with"] / t_off,
                    speedup=t_off / row["time_with"],
                    us_per_step_with=1e6 * row["time_with"] / n,
                    us_per_step_without=1e6 * t_off / n,
                    max_abs_diff=diff,
                    identical=diff == 0.0,
                    gap_closures=ref.gap_closures,
                    note="Hysteretic kernel pow short-circuit (child process)",
                )
    table = pd.DataFrame(rows)
    steps = pd.DataFrame(steps_rows)
    table.to_csv(out / "skips.csv", index=False)
    write_csv(steps, out / "adaptive_steps.csv", STEP_UNITS)
    return table, steps

"""Peak resident memory of an engine run, measured in a fresh subprocess.

``peak_rss(engine, overrides)`` runs ``deckpound.compare.engines.run_engine(engine, scene)`` in a new
Python process (so nothing from the caller counts) and returns that process's peak resident
set size (:func:`peak_resident_mb`) together with the
baseline after the imports and one tiny warm-up run (numba compilation or cache loading,
OpenSees loading), the run's wall time, steps and status. The difference ``peak − baseline``
is what the run itself allocated at its peak.

The compliance engine's memory does not grow with the number of steps: the support motion
is interpolated from the record's own samples inside the compiled loop
(:mod:`deckpound.analytic.kernels.support_motion`) and only the decimated output is stored.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
from pathlib import Path

_CHILD = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
from deckpound.compare.bench.memory import peak_resident_mb
from deckpound.compare.engines import run_engine
from deckpound.models.scene_io import load_scene
engine, scene_name, overrides, warm = json.loads(sys.argv[1])
if warm:
    run_engine(engine, load_scene(scene_name, overrides + ["run.duration=0.05"]))
base = peak_resident_mb()
scene = load_scene(scene_name, overrides)
t0 = time.perf_counter()
r = run_engine(engine, scene)
wall = time.perf_counter() - t0
peak = peak_resident_mb()
print(json.dumps({"baseline_mb": base, "peak_mb": peak,
                  "run_mb": peak - base, "wall": wall,
                  "steps": r.meta.get("steps"), "rows": len(r.t),
                  "status": r.meta.get("status"), "message": r.meta.get("message")}))
"""


def peak_resident_mb() -> float:
    """This process's peak resident set size [MB]: ``VmHWM`` of ``/proc/self/status`` on Linux.

    Not ``getrusage(RUSAGE_SELF).ru_maxrss``: Linux keeps that across fork and exec, so a fresh
    process started by a large one reports its parent's peak (every run measured 297 MB when
    started from a sweep benchmark of that size); ``VmHWM`` belongs to the process's own address
    space, which exec replaces. Elsewhere, ``ru_maxrss`` (KiB on Linux, bytes on macOS).
    """
    try:
        status = Path("/proc/self/status").read_text()
    except OSError:
        scale = 1024.0 * 1024.0 if sys.platform == "darwin" else 1024.0
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / scale
    return next(
        int(ln.split()[1]) / 1024.0 for ln in status.splitlines() if ln.startswith("VmHWM:")
    )


def peak_rss(
    engine: str,
    overrides: list[str] | tuple[str, ...] = (),
    scene: str = "saiidi-4span",
    *,
    warm: bool = True,
    timeout: float = 3600.0,
) -> dict:
    """Peak RSS [MB] of one run in a fresh process (see the module docstring)."""
    arg = json.dumps([engine, scene, list(overrides), warm])
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, arg], capture_output=True, text=True, timeout=timeout
    )
    if proc.returncode != 0:
        raise RuntimeError(f"memory child failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


#: The 6-million-step case of the issue: a 60 s record at dt = 1e-5 s, output every 10 ms.
LONG_RUN = ("excitation.duration=60.0", "compliance.dt=1e-05", "run.output_dt=0.01")


def main() -> int:  # pragma: no cover - manual measurement

    p = argparse.ArgumentParser(description="peak RSS of the 6M-step compliance run")
    p.add_argument("--engine", default="compliance")
    p.add_argument("--set", dest="overrides", action="append", default=None)
    a = p.parse_args()
    print(json.dumps(peak_rss(a.engine, a.overrides or list(LONG_RUN)), indent=1))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

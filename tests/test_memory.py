"""Bounded memory: the compliance engine's peak RSS does not grow with the number of steps.

Each measurement runs in a fresh subprocess (:func:`deckpound.compare.bench.memory.peak_rss`):
peak RSS after one warm-up run (imports, numba cache) is the baseline, and ``run_mb`` is what
the measured run added on top. Resampling the support motion onto the step would cost
n_steps × 8 channels × 2 × 8 B (128 MB per million steps, more with temporaries).
"""

from __future__ import annotations

import pytest

from deckpound.compare.bench.memory import LONG_RUN, peak_rss


def test_memory_does_not_grow_with_steps():
    common = ["compliance.dt=1e-05", "run.output_dt=0.01"]
    small = peak_rss("compliance", ["excitation.duration=1.0"] + common)  # 1e5 steps
    large = peak_rss("compliance", ["excitation.duration=10.0"] + common)  # 1e6 steps
    print("1e5 steps:", small, "\n1e6 steps:", large)
    assert small["status"] == large["status"] == "success"
    assert large["steps"] == 10 * small["steps"] == 1_000_000
    # per-step arrays would add >= 128 MB for the extra 9e5 steps; allow allocator noise
    assert large["run_mb"] - small["run_mb"] < 16.0


@pytest.mark.slow
def test_six_million_steps_bounded_memory():
    """60 s record at dt = 1e-5 s (6e6 steps), output every 10 ms: measured ~278 MB peak of
    which ~275 MB is the interpreter with numpy/scipy/pandas/numba loaded and ~3 MB the run;
    the old resampled support arrays alone would be 768 MB."""
    r = peak_rss("compliance", list(LONG_RUN))
    print(r)
    assert r["status"] == "success" and r["steps"] == 6_000_000 and r["rows"] == 6001
    assert r["peak_mb"] < 600.0
    assert r["run_mb"] < 64.0

"""Subnormal numbers in the analytic step loops (``compliance.subnormals``,
``nonsmooth.subnormals``; :mod:`deckpound.analytic.fp_mode`).

On the benchmark the free seat rotations decay through the subnormal range once pounding stops
(t > 13.6 s). "keep" stores those numbers; "flush" stores zeros, and every value above
UNCHANGED_ABOVE in magnitude is bit-identical between the two. The thread that ran a loop gets
its floating-point mode back, also after a run that fails.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

from deckpound.analytic import fp_mode
from deckpound.compare.engines import run_engine
from deckpound.models.errors import SceneError
from deckpound.models.scene_io import load_scene

pytestmark = pytest.mark.skipif(
    not fp_mode.FLUSH_AVAILABLE, reason="flushing subnormals needs x86-64's MXCSR"
)

TINY = fp_mode.SMALLEST_NORMAL

#: (engine, settings section, extra overrides): the three analytic integrators
INTEGRATORS = [
    ("compliance", "compliance", []),
    ("compliance", "compliance", ["compliance.integrator=adaptive"]),
    ("nonsmooth", "nonsmooth", []),
]


def _subnormal(x: np.ndarray) -> np.ndarray:
    return (x != 0.0) & (np.abs(x) < TINY)


def _subnormals_survive_in_this_thread() -> bool:
    """IEEE gradual underflow in the calling thread (numpy computes in it)."""
    x = np.array([1.0e-310, 3.0e-300])
    return bool((x * 0.5)[0] != 0.0) and bool((x[1] * 1.0e-9) != 0.0)


@pytest.fixture(scope="module")
def runs():
    out = {}
    for engine, section, sets in INTEGRATORS:
        for mode in ("keep", "flush"):
            scene = load_scene("saiidi-4span", [*sets, f"{section}.subnormals={mode}"])
            out[(engine, tuple(sets), mode)] = run_engine(engine, scene)
    return out


@pytest.mark.parametrize("engine, section, sets", INTEGRATORS)
def test_flush_changes_only_what_is_below_1e_250(runs, engine, section, sets):
    keep = runs[(engine, tuple(sets), "keep")]
    flush = runs[(engine, tuple(sets), "flush")]
    assert keep.meta["status"] == flush.meta["status"] == "success"
    kept = sum(int(_subnormal(x).sum()) for x in keep.columns.values())
    assert kept > 100, "the benchmark's seat rotations should reach the subnormal range"
    assert _subnormal(keep.columns["seat2_theta"]).any()
    for name, xk in keep.columns.items():
        xf = flush.columns[name]
        assert not _subnormal(xf).any(), f"{name}: a subnormal number survived 'flush'"
        big = np.abs(xk) > fp_mode.UNCHANGED_ABOVE
        assert np.array_equal(xf[big], xk[big]), f"{name}: a value above 1e-250 changed"
        assert np.all(np.abs(xf[~big] - xk[~big]) <= fp_mode.UNCHANGED_ABOVE), name


def test_flush_is_the_default_and_recorded_in_the_settings(runs):
    scene = load_scene("saiidi-4span")
    assert scene.compliance.subnormals == scene.nonsmooth.subnormals == "flush"
    assert runs[("compliance", (), "flush")].meta["settings"]["subnormals"] == "flush"
    assert runs[("nonsmooth", (), "keep")].meta["settings"]["subnormals"] == "keep"


@pytest.mark.parametrize(
    "engine, sets",
    [
        ("compliance", []),
        ("nonsmooth", []),
        ("compliance", ["compliance.integrator=adaptive"]),
        # a run that stops early (one Newton iteration cannot converge): the loop leaves
        # through its failure exit
        ("compliance", ["compliance.max_iterations=1"]),
    ],
)
def test_the_threads_floating_point_mode_is_restored(engine, sets):
    """Runs in the main thread (the loop runs in a helper thread) and in a worker thread
    (the loop runs in that thread itself, as in the sweep workers)."""
    scene = load_scene("saiidi-4span", [*sets, "run.duration=0.5"])
    assert _subnormals_survive_in_this_thread()
    run_engine(engine, scene)
    assert _subnormals_survive_in_this_thread()
    seen: list[bool] = []

    def worker():
        run_engine(engine, scene)
        seen.append(_subnormals_survive_in_this_thread())

    t = threading.Thread(target=worker)
    t.start()
    t.join()
    assert seen == [True]


@pytest.mark.parametrize("engine", ["compliance", "nonsmooth"])
def test_the_mode_is_restored_after_an_interrupted_run(monkeypatch, engine):
    """The loop stops at its first interrupt check (the halt flag set before it starts) and
    leaves through its interrupt exit, in a worker thread that then computes with subnormals."""
    from deckpound.analytic import bundles as bd

    new_stats = bd.new_stats

    def halted():
        stats = new_stats()
        stats.halt[0] = 1
        return stats

    monkeypatch.setattr(bd, "new_stats", halted)
    scene = load_scene("saiidi-4span", ["run.duration=0.5"])
    seen: list[tuple[str, bool]] = []

    def worker():
        r = run_engine(engine, scene, on_interrupt="return")
        seen.append((r.meta["failure"], _subnormals_survive_in_this_thread()))

    t = threading.Thread(target=worker)
    t.start()
    t.join()
    assert seen == [("interrupted", True)]


def test_the_mode_is_restored_after_a_singular_start(monkeypatch):
    """The Newmark loop's first exit: the elastic effective tangent K + c₂C + c₃M cannot be
    factorised (here every mass, stiffness and damping coefficient is zero), so the loop stops
    before its first step and returns the thread's mode on the way out."""
    from deckpound.analytic.compliance import pack
    from deckpound.analytic.kernels import system

    pack_system = system.pack_system

    def degenerate(plan, damping):
        ps = pack_system(plan, damping)
        for name in ("mass", "k0", "crate", "cdash", "C"):
            getattr(ps.arrays, name)[...] = 0.0
        return ps

    monkeypatch.setattr(system, "pack_system", degenerate)
    monkeypatch.setattr(pack, "MODELS_KEPT", 0)  # packed now, not taken from an earlier run
    scene = load_scene("saiidi-4span", ["run.duration=0.5"])
    seen: list[tuple[str, str, bool]] = []

    def worker():
        r = run_engine("compliance", scene, on_interrupt="return")
        seen.append((r.meta["failure"], r.meta["status"], _subnormals_survive_in_this_thread()))

    t = threading.Thread(target=worker)
    t.start()
    t.join()
    assert len(seen) == 1
    failure, status, survive = seen[0]
    assert "singular" in str(failure), (failure, status)
    assert survive


def test_a_bad_value_names_the_field_and_the_choices():
    with pytest.raises(SceneError) as err:
        load_scene("saiidi-4span", ["nonsmooth.subnormals=drop"])
    text = str(err.value)
    assert "nonsmooth.subnormals" in text and "flush" in text and "keep" in text


def test_a_machine_that_cannot_flush_says_so(monkeypatch):
    monkeypatch.setattr(fp_mode, "FLUSH_AVAILABLE", False)
    (note,) = fp_mode.flush_note("compliance.subnormals", "flush")
    assert "compliance.subnormals = 'flush'" in note and "keep subnormal" in note
    assert fp_mode.flush_note("compliance.subnormals", "keep") == []

"""Bounded work (issue 16 item 5): Ctrl-C stops every analytic engine within a second, the
adaptive integrator has a step budget, and output tables are sized before they are allocated.

The compiled loops poll ``Stats.halt`` once per Newton iteration / Runge–Kutta attempt while
:func:`deckpound.analytic.interruptible.run_loop` waits for them in the main thread
(:mod:`deckpound.analytic.bundles`).

No test here interrupts the test runner's own thread: ``_thread.interrupt_main()`` on a timer
raised KeyboardInterrupt wherever the main thread was when it fired — on a loaded machine
inside pytest's own frames, which ended the whole session. The Ctrl-C test sends SIGINT to a
child process; the in-process tests set the halt flag the compiled loops poll.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from deckpound.analytic import bundles, interruptible
from deckpound.compare.engines import run_engine
from deckpound.models.errors import SceneError
from deckpound.models.scene_io import load_scene

# long runs (minutes if not interrupted): 4e7 Newmark / Moreau-Jean steps, stiff adaptive
LONG = {
    "compliance": (
        "compliance",
        ["excitation.duration=400", "compliance.dt=1e-5", "run.output_dt=0.01"],
    ),
    "adaptive": (
        "compliance",
        [
            "compliance.integrator=adaptive",
            "contact.stiffness=1e12",
            "excitation.duration=60",
            "run.output_dt=0.01",
        ],
    ),
    "nonsmooth": (
        "nonsmooth",
        ["excitation.duration=400", "nonsmooth.h=1e-5", "run.output_dt=0.01"],
    ),
}

CHILD = r"""
import signal, sys, time, warnings
warnings.simplefilter("ignore")
from deckpound.cli import main
path, engine, overrides = sys.argv[1], sys.argv[2], sys.argv[3:]
if path == "threaded":  # a program's own SIGTERM handler, as the CLI's: the loop in a thread
    def on_sigterm(signum, frame):
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, on_sigterm)
sets = [a for o in overrides for a in ("--set", o)]
# warm-up: compile or load the kernels, so that the long run starts at once
main(["run", "saiidi-4span", "--engine", engine, "--set", "run.duration=0.05",
      *[a for o in overrides if o.startswith("compliance.integrator") for a in ("--set", o)],
      "-o", sys.argv[0] + ".warm"])
print("ready", flush=True)
sys.exit(main(["run", "saiidi-4span", "--engine", engine, *sets, "-o", sys.argv[0] + ".out"]))
"""


@pytest.mark.parametrize(
    "which,path", [(w, "watched") for w in LONG] + [("compliance", "threaded")]
)
def test_ctrl_c_stops_a_long_run_long_before_it_would_end(which, path, tmp_path):
    """The long run holds at least 40 s of step loop (4e7 steps at ~1 µs, more under load);
    Ctrl-C must end it within one Newton iteration, on both of run_loop's main-thread paths
    (the loop watched in the main thread; in a helper thread where the program has a SIGTERM
    handler of its own). The bounds are loose on purpose (a loaded machine may be slow to
    schedule the child): a loop that ignored the flag would run for its whole record, far
    beyond them."""
    engine, overrides = LONG[which]
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    errfile = tmp_path / "stderr.txt"
    with open(errfile, "w") as err_out:
        proc = subprocess.Popen(
            [sys.executable, str(script), path, engine, *overrides],
            stdout=subprocess.PIPE,
            stderr=err_out,
            text=True,
            cwd=tmp_path,
        )
    try:
        for line in proc.stdout:  # the warm-up run prints its summary first
            if line.strip() == "ready":
                break
        assert proc.poll() is None, errfile.read_text()
        time.sleep(1.5)  # well inside the long loop
        assert proc.poll() is None, "the long run ended before it was interrupted"
        t0 = time.perf_counter()
        os.kill(proc.pid, signal.SIGINT)
        latency = None
        while latency is None and time.perf_counter() - t0 < 30.0:
            if "deckpound: interrupted" in errfile.read_text():
                latency = time.perf_counter() - t0  # the loop stopped, the CLI said so
            else:
                time.sleep(0.01)
        code = proc.wait(timeout=30)
        exited = time.perf_counter() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = errfile.read_text()
    print(
        f"{which} ({path}): 'interrupted' {latency} s after SIGINT, process gone after {exited:.2f} s "
        f"(interpreter teardown), exit {code}"
    )
    assert code == 130, err
    assert "Traceback" not in err, err
    assert latency is not None and latency < 10.0
    assert exited < 30.0


#: the output row after which the in-process tests stop a long run (0.2 s of its record)
HALT_ROW = 20


def _ctrl_c_after_row(monkeypatch, row: int) -> list[int]:
    """Make the engines' loops stop as Ctrl-C stops them, without a signal: once a loop has
    written output row ``row``, a watcher thread sets ``Stats.halt`` — the flag that
    :func:`~deckpound.analytic.interruptible.run_loop` sets on Ctrl-C and the compiled loop polls —
    and the loop's runner then reports an interrupt, as run_loop does after a Ctrl-C. Returns
    the list of loops halted so (their number of output rows allocated)."""
    real, halted = interruptible.run_loop, []

    def run_loop(loop, args, stats):
        table, done = args[4].table, threading.Event()

        def watch():
            while not done.is_set():
                if row < len(table) and np.any(table[row] != 0.0):
                    stats.halt[0] = 1
                    halted.append(len(table))
                    return
                done.wait(0.001)

        watcher = threading.Thread(target=watch, daemon=True)
        watcher.start()
        try:
            real(loop, args, stats)
        finally:
            done.set()
            watcher.join()
        return bundles.stats_dict(stats)["status"] == bundles.RUN_INTERRUPTED

    monkeypatch.setattr(interruptible, "run_loop", run_loop)
    return halted


@pytest.mark.parametrize("which", list(LONG))
def test_interrupt_can_return_the_rows_so_far(which, monkeypatch):
    """``on_interrupt="return"``: status interrupted, the rows computed so far, finite."""
    engine, overrides = LONG[which]
    scene = load_scene("saiidi-4span", overrides)
    run_engine(engine, load_scene("saiidi-4span", ["run.duration=0.05"] + overrides[:1]))
    halted = _ctrl_c_after_row(monkeypatch, HALT_ROW)
    res = run_engine(engine, scene, on_interrupt="return")
    assert res.meta["failure"] == "interrupted", res.meta["message"]
    assert len(halted) == 1
    t = np.asarray(res.columns["t"])
    # every row up to the halt is kept, and the run stopped long before its end
    assert HALT_ROW < len(t) < halted[0] // 2 and np.all(np.diff(t) > 0)
    # the time reached is a sum of steps, the rows' times are multiples of the output step: a
    # halt just after a row may leave the first a few ulps of accumulated round-off below it
    assert res.meta["failed_time"] >= t[-1] - 1e-9
    for k in ("deck_x_abs", "gap_c1", "bent1_fx"):
        assert np.all(np.isfinite(res.columns[k])), k


def test_interrupt_raises_keyboard_interrupt_by_default(monkeypatch):
    engine, overrides = LONG["compliance"]
    scene = load_scene("saiidi-4span", overrides)
    run_engine(engine, load_scene("saiidi-4span", ["run.duration=0.05"]))
    halted = _ctrl_c_after_row(monkeypatch, HALT_ROW)
    with pytest.raises(KeyboardInterrupt):
        run_engine(engine, scene)
    assert len(halted) == 1


@pytest.mark.parametrize(
    "engine,integrator",
    [("compliance", "newmark"), ("compliance", "adaptive"), ("nonsmooth", None)],
)
def test_the_loop_thread_changes_no_result(engine, integrator):
    """The compiled loop watched in the main thread (the default), in the helper thread (a
    program's own SIGTERM handler) and called directly (SIGINT ignored) give bit-identical
    results."""
    ov = ["run.duration=3"] + ([f"compliance.integrator={integrator}"] if integrator else [])
    scene = load_scene("saiidi-4span", ov + ["contact.friction=0.2", "contact.friction_mode=stick"])
    watched = run_engine(engine, scene)
    with _handlers(signal.default_int_handler, _raise_interrupt):
        threaded = run_engine(engine, scene)
    with _handlers(signal.SIG_IGN, signal.SIG_DFL):
        direct = run_engine(engine, scene)
    assert watched.meta["gap_closures"] == direct.meta["gap_closures"] > 0
    for other in (threaded, direct):
        for k, v in watched.columns.items():
            assert np.array_equal(np.asarray(v), np.asarray(other.columns[k]), equal_nan=True), k


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt


@contextlib.contextmanager
def _handlers(on_sigint, on_sigterm):
    """SIGINT and SIGTERM handled so inside, as before outside."""
    old = signal.signal(signal.SIGINT, on_sigint), signal.signal(signal.SIGTERM, on_sigterm)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old[0])
        signal.signal(signal.SIGTERM, old[1])


def test_where_the_loop_runs():
    """run_loop's paths: with Python's default SIGINT handler and no SIGTERM handler the loop
    runs in the calling (main) thread, watched; with a program's own handler of another signal
    (the CLI's SIGTERM, an alarm), which must run during the loop, or with the signal wake-up
    descriptor held by someone else (whose descriptor stays), in a helper thread; with SIGINT
    ignored (a sweep's worker) in the calling thread."""
    stats = bundles.new_stats()
    ran_in = []

    def loop():
        ran_in.append(threading.get_ident())

    def where(on_sigint, on_sigterm) -> bool:
        with _handlers(on_sigint, on_sigterm):
            assert interruptible.run_loop(loop, (), stats) is False
        return ran_in[-1] == threading.get_ident()

    assert where(signal.default_int_handler, signal.SIG_DFL)
    assert signal.set_wakeup_fd(-1) == -1  # taken only while the loop ran
    assert not where(signal.default_int_handler, _raise_interrupt)
    previous = signal.signal(signal.SIGALRM, _raise_interrupt)  # e.g. a program's timeout
    try:
        assert not where(signal.default_int_handler, signal.SIG_DFL)
    finally:
        signal.signal(signal.SIGALRM, previous)
    assert where(signal.SIG_IGN, signal.SIG_DFL)
    theirs, other = socket.socketpair()
    theirs.setblocking(False)
    signal.set_wakeup_fd(theirs.fileno())
    try:
        assert not where(signal.default_int_handler, signal.SIG_DFL)
        assert signal.set_wakeup_fd(-1) == theirs.fileno()
    finally:
        signal.set_wakeup_fd(-1)
        theirs.close()
        other.close()
    assert stats.halt[0] == 0


def test_adaptive_step_budget_stops_with_the_time_reached():
    scene = load_scene(
        "saiidi-4span",
        ["compliance.integrator=adaptive", "run.duration=2", "compliance.max_steps=3000"],
    )
    res = run_engine("compliance", scene)
    assert res.meta["failure"] == "step_budget"
    assert "compliance.max_steps = 3000" in res.meta["message"]
    assert res.meta["steps"] + res.meta["rejected_steps"] == 3000
    t_end = res.meta["failed_time"]
    assert 0.0 < t_end < 2.0 and f"t = {t_end:.6g} s" in res.meta["message"]
    assert res.columns["t"][-1] <= t_end


def test_output_table_is_sized_before_allocating():
    """10⁷ rows of ~45 columns (3.4 GiB) are refused up front, naming run.output_dt."""
    scene = load_scene(
        "saiidi-4span", ["excitation.duration=100", "compliance.dt=1e-5", "run.output_dt=1e-5"]
    )
    t0 = time.perf_counter()
    with pytest.raises(SceneError, match=r"run\.output_dt.*GiB"):
        run_engine("compliance", scene)
    with pytest.raises(SceneError, match=r"run\.output_dt"):
        run_engine("nonsmooth", scene.replace(nonsmooth=scene.nonsmooth.__class__(h=1e-5)))
    assert time.perf_counter() - t0 < 30.0

"""Run a case in a child process with a wall-clock limit, so nothing can hang or crash us.

Used by the stress test and the benchmark: a case either returns a Result, or becomes a
record of why it did not (``timeout``, ``crashed`` with the exception text) — never a hang,
never an uncaught exception in the caller.
"""

from __future__ import annotations

import dataclasses
import multiprocessing as mp
import signal
import time
import traceback
from dataclasses import dataclass

from deckpound.compare.cases import run_case
from deckpound.models.result import Result
from deckpound.models.scene import Scene


@dataclass
class GuardedOutcome:
    """What happened to one guarded run."""

    status: str  # "success", "failed" (engine status), "timeout", "crashed"
    result: Result | None
    message: str
    wall: float


def _child(conn, engine: str, scene: Scene, warm: bool = False) -> None:
    # the CLI's SIGTERM handler is forked with the parent's memory; a child told to terminate
    # (multiprocessing ends daemonic children so at exit) does so at once
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        if warm:
            run_case(engine, warm_scene(scene))
        r = run_case(engine, scene)
        conn.send(("ok", r.engine, r.columns, r.meta))
    except BaseException as err:  # report everything to the parent, including SystemExit
        conn.send(("error", f"{type(err).__name__}: {err}", traceback.format_exc(limit=3), None))
    finally:
        conn.close()


def warm_scene(scene: Scene) -> Scene:
    """A very short run of the scene (a few output steps): loads or compiles every kernel."""

    short = min(scene.run.duration or scene.excitation.duration, 4 * scene.run.output_dt, 0.05)
    return scene.replace(run=dataclasses.replace(scene.run, duration=short))


def run_guarded(engine: str, scene: Scene, timeout: float, *, warm: bool = False) -> GuardedOutcome:
    """Run ``engine`` on ``scene`` in a forked child; kill it after ``timeout`` seconds.

    ``warm``: first run a very short version of the scene in the same child (numba cache
    loading / compilation, OpenSees loading), so that the engine-reported ``wall_time`` of the
    real run measures the computation only (the benchmark's timings)."""
    ctx = mp.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    t0 = time.perf_counter()
    proc = ctx.Process(target=_child, args=(child, engine, scene, warm), daemon=True)
    proc.start()
    child.close()
    msg = None
    if parent.poll(timeout):
        try:
            msg = parent.recv()
        except EOFError:
            msg = None
    wall = time.perf_counter() - t0
    if proc.is_alive() and msg is None:
        proc.kill()
        proc.join()
        return GuardedOutcome("timeout", None, f"no result after {timeout:g} s (killed)", wall)
    proc.join(5)
    if msg is None:
        return GuardedOutcome("crashed", None, f"child exited with code {proc.exitcode}", wall)
    if msg[0] == "error":
        return GuardedOutcome("crashed", None, msg[1], wall)
    _, name, columns, meta = msg
    result = Result(engine=name, columns=columns, meta=meta)
    return GuardedOutcome(meta.get("status", "success"), result, meta.get("message", ""), wall)

"""Cases (engine + fully resolved scene), their cache, and the parallel runner.

Every finished case is stored under its key: the SHA-256 of the engine name, the scene's
physics (:func:`deckpound.models.result.physics_hash`: the scene without engine settings,
sequence and free text), the record files' digests, *that engine's* settings and the
deckpound version — so changing one engine's settings (say ``nonsmooth.h``) re-runs that
engine's cases only — in a :class:`~deckpound.compare.result_cache.ResultCache` (re-exported
here), so an interrupted study resumes without recomputing and a repeated one returns at once.
Warnings an engine raises in a worker travel with its result (``meta["warnings"]``) and are
shown once each in the main process (:func:`surface_warnings`), never swallowed. Cases run in
parallel on local processes (default: one per core; the workers die with the process that
started them, :mod:`._workers`) or on a Dask distributed cluster (``scheduler="tcp://host:port"``;
a malformed address is refused, an unreachable one is an OSError naming it), with their
progress on stderr (:mod:`.progress`: a bar on a terminal, a line at a steady pace in a log).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import os
import re
import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from deckpound.compare._heap import keep_freed_memory
from deckpound.compare.engines import get_engine, run_engine
from deckpound.compare.pool import (
    Interrupted,
    gc_frozen,
    map_local,
    one_blas_thread,
)
from deckpound.compare.progress import Progress
from deckpound.compare.result_cache import ResultCache
from deckpound.models.errors import SceneError
from deckpound.models.file_io import file_digest
from deckpound.models.iir import SCIPY_AFTER, load_compiled_filter
from deckpound.models.result import Result, physics_hash, settings_hash
from deckpound.models.scene import Scene
from deckpound.models.version import VERSION

__all__ = [
    "Case",
    "batch_size",
    "case_key",
    "check_scheduler_address",
    "engine_expresses",
    "map_parallel",
    "run_batch",
    "run_case",
    "run_cases",
    "summary_key",
    "task_batches",
]

#: seconds to wait for a Dask scheduler before giving up (exit status 3 on the CLI)
CONNECT_TIMEOUT = 20.0
#: the most cases one task carries to a worker (a batch: one round trip, one pickled list;
#: tens of cases, so that a cluster's per-task cost is paid once per tens of runs), and how
#: many batches of that size each worker gets at least while there are enough items
MAX_BATCH = 32
BATCHES_PER_WORKER = 8


@dataclass(frozen=True)
class Case:
    """One engine run of one scene, with the parameter values that define it in a study."""

    label: str
    engine: str
    scene: Scene
    params: dict[str, Any] = field(default_factory=dict, compare=False, hash=False)

    @property
    def key(self) -> str:
        return case_key(self.engine, self.scene)


def record_digests(scene: Scene, read: dict[str, str | None] | None = None) -> dict[str, str]:
    """SHA-256 of every record file the scene reads: a record edited in place changes the key
    (the scene only names the file).

    ``read``: the digests of files already read for the same batch of keys (path → digest, or
    None for a file that could not be read), filled as files are read. The keys of a sweep are
    made together, before its first case runs; its cases share their files (an IDA applies each
    pair at every level), and a file is then read and hashed once per sweep, not once per case.
    The keys describe the files as they were when the batch was made, as they would one read
    earlier."""
    read = {} if read is None else read
    out = {}
    for name in ("file", "file_x", "file_y"):
        path = getattr(scene.excitation, name, None)
        if path:
            if path not in read:
                read[path] = _file_digest(path)
            if read[path] is not None:
                out[name] = read[path]
    return out


def _file_digest(path: str) -> str | None:
    """:func:`~deckpound.models.file_io.file_digest`, or None when the file cannot be read
    (the run refuses the scene with its own message)."""
    try:
        return file_digest(path)
    except OSError:
        return None


def case_key(engine: str, scene: Scene, read: dict[str, str | None] | None = None) -> str:
    """The cache key: SHA-256 of engine name, physics hash, the record files' digests, that
    engine's settings and the version (``read``: see :func:`record_digests`)."""

    settings = get_engine(engine).settings_of(scene)
    text = json.dumps(
        {
            "engine": engine,
            "physics": physics_hash(scene),
            "records": record_digests(scene, read),
            "settings": settings_hash(settings),
            "version": VERSION,
        },
        sort_keys=True,
        separators=(",", ":"),
    )
    return hashlib.sha256(text.encode()).hexdigest()


def engine_expresses(engine: str, scene: Scene, study: str) -> bool:
    """Whether ``engine`` runs ``scene`` (its validation-time refusals); a refused case of a
    study is left out with a logged warning that names the reason."""

    eng = get_engine(engine)
    try:
        eng.refuse(scene, eng.settings_of(scene))
    except SceneError as err:
        logging.getLogger(__name__).warning(
            "%s study: %s leaves out %s: %s", study, engine, scene.name, err
        )
        return False
    return True


def run_case(engine: str, scene: Scene, summary_only: bool = False) -> Result:
    """Run one case in this process (the worker function; picklable arguments);
    ``summary_only``: a result without histories (``Engine.run``'s option, for sweeps).

    Every warning raised during the run is recorded in ``meta["warnings"]`` (the engine's own
    option notes are there already) so that the main process can show it
    (:func:`surface_warnings`) — a worker's stderr is not the user's.
    """

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run_engine(engine, scene, summary_only=summary_only)
    notes = list(result.meta.get("warnings", []))
    notes += [str(w.message) for w in caught if str(w.message) not in notes]
    return result.with_meta(warnings=notes)


_SHOWN: set[str] = set()


def surface_warnings(results: Iterable[Result], where: str = "") -> None:
    """Warn (once per distinct message in this process) about every warning carried by the
    results — the "option does nothing" notes of the engines and their run warnings."""
    for r in results:
        for msg in r.meta.get("warnings", []):
            if msg not in _SHOWN:
                _SHOWN.add(msg)
                warnings.warn(f"{where}{msg}" if where else msg, stacklevel=2)


def interrupted(
    err: KeyboardInterrupt,
    title: str,
    done: int,
    total: int,
    folder,
    what: str = "cases",
    item: str = "case",
) -> KeyboardInterrupt:
    """The interrupt to raise after a sweep was stopped: an :class:`Interrupted` saying what is
    cached and how to resume (an inner sweep's message is kept as it is)."""
    if isinstance(err, Interrupted) or folder is None:
        return err
    return Interrupted(
        f"{title}: {done} of {total} {what} finished; every finished {item} is "
        f"cached in {folder}: run the same command again to resume"
    )


def summary_key(key: str) -> str:
    """The cache key of a case's summary-only result: never the full result's key, so that
    a cache holding the one is never asked for the other."""
    return hashlib.sha256(f"{key}:summary-only".encode()).hexdigest()


def run_cases(
    cases: Iterable[Case],
    *,
    cache: ResultCache | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    title: str = "cases",
    summary_only: bool = False,
) -> dict[str, Result]:
    """Run cases (cached ones are loaded), in parallel; results keyed by case label.
    ``summary_only``: results without histories (``Engine.run``), cached under their own
    keys (:func:`summary_key`)."""
    cases = list(cases)
    results: dict[str, Result] = {}
    todo = []

    def key_of(case: Case) -> str:
        return summary_key(case.key) if summary_only else case.key

    for c in cases:
        hit = cache.get(key_of(c), c.engine) if cache is not None else None
        if hit is not None:
            results[c.label] = hit
        else:
            todo.append(c)
    bar = Progress(len(cases), title, progress)
    bar.skip(len(cases) - len(todo))  # cached: done, not in the rate

    def finish(case: Case, result: Result) -> None:
        if cache is not None and result.finished:  # finished answers
            cache.put(key_of(case), result)
        results[case.label] = result
        bar.advance()

    try:
        map_parallel(
            todo, lambda c: (c.engine, c.scene, summary_only), run_case, finish, workers, scheduler
        )
    except KeyboardInterrupt as err:
        bar.close()
        raise interrupted(
            err, title, len(results), len(cases), cache.folder if cache is not None else None
        ) from None
    finally:
        bar.close()
    surface_warnings(results.values())
    return {c.label: results[c.label] for c in cases}


def map_parallel(
    items: list,
    args_of: Callable,
    func: Callable,
    on_done: Callable,
    workers: int | None,
    scheduler: str | None,
) -> None:
    """Apply func(*args_of(item)) to items on Dask, a process pool, or in this process.

    Workers take the items in batches (:func:`batch_size`): a task is one round trip however
    many cases it carries, and a case of a sweep takes tens of milliseconds, which a task per
    case would spend again on scheduling and transfer. ``on_done`` still sees every item.
    In this process and as a Dask client (whose messages, with a local cluster's scheduler's,
    and the rows coming back otherwise set off full collections of every object this process
    holds, on the cores the workers need) the map runs with the process's older objects out
    of the garbage collector's way (:func:`.pool.gc_frozen`), as every worker's batch does.
    Not so the local pool's parent: its workers are forked from it, and forked from a frozen
    parent the pool ran slower on the sweep benchmark (``tools/sweep_benchmark.py``).
    """
    if not items:
        return
    if scheduler:
        with gc_frozen():
            _map_dask(items, args_of, func, on_done, check_scheduler_address(scheduler))
        return
    n = workers if workers is not None else (os.cpu_count() or 1)
    if n <= 1 or len(items) == 1:
        sweep = len(items) >= SCIPY_AFTER
        if sweep:  # its import now, not at its 16th record
            load_compiled_filter()
        with one_blas_thread() if sweep else contextlib.nullcontext(), gc_frozen():
            for it in items:
                on_done(it, func(*args_of(it)))
        return
    batches = task_batches(items, batch_size(len(items), n), n)
    map_local(batches, _batch_args(args_of, func), run_batch, _batch_done(on_done), n)


def batch_size(items: int, workers: int) -> int:
    """Cases per task: at most :data:`MAX_BATCH`, and at least :data:`BATCHES_PER_WORKER`
    tasks per worker while there are enough items (1 for short maps)."""
    return max(1, min(MAX_BATCH, items // (BATCHES_PER_WORKER * max(1, workers))))


def run_batch(func: Callable, arguments: list[tuple]) -> list:
    """The worker side of a batch: ``[func(*args) for args in arguments]``, with the worker's
    older objects out of the garbage collector's way (:func:`.pool.gc_frozen`)."""
    with gc_frozen():
        return [func(*args) for args in arguments]


def task_batches(items: list, size: int, workers: int = 1) -> list[tuple]:
    """``items`` in tasks of at most ``size``, shrinking towards the end: each takes
    ⌈remaining / (2 × workers)⌉ items (guided self-scheduling, Polychronopoulos & Kuck 1987,
    with half its share per task), so the first tasks carry ``size`` and the last ones a single item: at the
    end of a map no worker waits for another's whole batch, in about n / size + 2 workers
    log₂(size) tasks."""
    out, start, n = [], 0, len(items)
    while start < n:
        take = max(1, min(size, -(-(n - start) // (2 * workers))))
        out.append(tuple(items[start : start + take]))
        start += take
    return out


def _batch_args(args_of: Callable, func: Callable) -> Callable:
    return lambda batch: (func, [args_of(it) for it in batch])


def _batch_done(on_done: Callable) -> Callable:
    def done(batch: tuple, values: list) -> None:
        for it, value in zip(batch, values, strict=True):
            on_done(it, value)

    return done


_ADDRESS = re.compile(
    r"^(?:(tcp|tls|ws|wss|ucx)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.\-]+)"
    r"(?::(\d{1,5}))?/?$"
)


def check_scheduler_address(address: str) -> str:
    """Refuse a malformed Dask scheduler address (SceneError naming ``--scheduler``)."""
    if isinstance(address, str) and address.startswith("inproc://") and len(address) > 9:
        return address  # in-process schedulers (tests) have their own address form
    m = _ADDRESS.match(address.strip()) if isinstance(address, str) else None
    if m is None or m.group(3) is None:
        raise SceneError(
            "--scheduler",
            f"must be a Dask scheduler address such as "
            f"tcp://127.0.0.1:8786 (scheme://host:port), got {address!r}",
        )
    if m.group(3) is not None and not 0 < int(m.group(3)) < 65536:
        raise SceneError("--scheduler", f"port must be in [1, 65535], got {m.group(3)}")
    return address.strip()


def _map_dask(
    items: list, args_of: Callable, func: Callable, on_done: Callable, scheduler: str
) -> None:
    from dask.distributed import Client
    from dask.distributed import as_completed as dask_completed

    try:
        client = Client(scheduler, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError) as err:
        raise ConnectionError(
            f"cannot reach the Dask scheduler at {scheduler} within {CONNECT_TIMEOUT:g} s ({err})"
        ) from None
    with client:
        # every worker loads cached kernels the fast way; a worker keeps them for its lifetime
        client.run(_dask_worker_setup)
        threads = sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values())
        batches = task_batches(items, batch_size(len(items), threads), threads)
        arguments, done = _batch_args(args_of, func), _batch_done(on_done)
        futures = {client.submit(run_batch, *arguments(b), pure=False): b for b in batches}
        try:
            for fut in dask_completed(futures):
                done(futures[fut], fut.result())
        except BaseException:
            # an error or Ctrl-C: drop the queued cases from the cluster (a worker's running
            # case ends on its own; the cluster is not ours to kill)
            client.cancel(list(futures), force=True)
            raise


def _dask_worker_setup() -> bool:
    from deckpound.analytic.kernel_load import install

    one_blas_thread()  # several workers share the machine's cores (see the function)
    keep_freed_memory()  # its tasks run in a thread, whose heap returned pages at every case
    load_compiled_filter()  # a long-lived worker: scipy.signal now, not mid-sweep
    return install()

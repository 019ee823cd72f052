"""Long-lived workers for the sweeps of one command, and clean interrupts.

A sweep's cases run in worker processes. Starting a worker costs its imports and loading the
compiled kernels (about a second); a command such as ``paper`` maps cases many times (two
sequences, six studies). Inside :func:`pool_scope` (the CLI opens one around every command;
:func:`deckpound.api.run_batch` around its batch) the first parallel map starts the pool and
the later ones reuse it, so each worker imports and loads its kernels once per command. Outside a
scope a map starts its own pool and stops it when done.

Workers (:func:`worker_init`) die with their parent (:mod:`._workers`), ignore SIGINT — a Ctrl-C
in a terminal reaches the whole process group; the parent alone decides — take SIGTERM's default
action (the CLI turns SIGTERM into a Ctrl-C in the parent only), load cached kernels the fast
way (:mod:`deckpound.analytic.kernel_load`) and keep the BLAS library to one thread
(:func:`one_blas_thread`).

Interrupts: on Ctrl-C (or any error) while a map runs, the parent kills every worker at once
(SIGKILL: a worker inside a compiled loop cannot be asked), cancels what is queued and re-raises;
callers that keep a cache turn it into :class:`Interrupted`, whose text says what is cached and
how to resume — the CLI prints it as its one line and exits 130.
"""

from __future__ import annotations

import contextlib
import gc
import os
import signal
import sys
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

from threadpoolctl import threadpool_limits

from deckpound.compare._heap import keep_freed_memory
from deckpound.compare._workers import die_with_parent
from deckpound.models.iir import SCIPY_AFTER, load_compiled_filter

__all__ = [
    "Interrupted",
    "gc_frozen",
    "map_local",
    "one_blas_thread",
    "pool_scope",
    "worker_init",
]

#: seconds to wait for killed workers to be reaped
REAP_TIMEOUT = 5.0


class Interrupted(KeyboardInterrupt):
    """A Ctrl-C, with one sentence on what is cached and how to resume (``str(err)``)."""


def one_blas_thread():
    """Keep this process's BLAS (OpenBLAS, MKL) and OpenMP pools to one thread, from now on;
    the returned limiter, used as a context (``with one_blas_thread():``), restores them at its
    end (a sweep run in the caller's own process).

    A sweep runs one case per worker and core. A case's matrix products (its output columns,
    e.g. the bent deformations B·u of every row) are large enough for OpenBLAS to wake its
    thread pool, whose threads then busy-wait on the other cores, where the other workers run
    their step loops: two workers ran at the speed of one (``tools/sweep_benchmark.py``)."""

    return threadpool_limits(limits=1)


@contextlib.contextmanager
def gc_frozen() -> Iterator[None]:
    """Inside: Python's cyclic garbage collector leaves the objects that existed at entry alone
    (``gc.freeze``; ``gc.unfreeze`` at the end puts them back in its oldest generation).

    A sweep allocates a few hundred container objects per case, so every few hundred cases the
    collector runs a full collection, which visits every object of the process: the imported
    numba, numpy, scipy (and distributed in a Dask worker), about 10⁵ objects, for longer than
    a case's step loop. None of them becomes garbage because of the sweep; the cases' own
    objects are still collected as before (reference counting frees most of them at once).
    Where the process has frozen objects already (its owner's choice), nothing is changed."""
    if gc.get_freeze_count():
        yield
        return
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def worker_init(parent_pid: int) -> None:
    """Pool initializer: die with the parent, leave SIGINT to it, one BLAS thread, freed memory
    kept for the next case (:mod:`._heap`), load kernels fast."""

    die_with_parent(parent_pid)
    one_blas_thread()
    keep_freed_memory()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # the CLI's SIGTERM handler (forked with the parent) is the parent's: a worker told to
    # terminate does so at once
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    from deckpound.analytic.kernel_load import install

    install()


class _Scope:
    def __init__(self):
        self.active = 0
        self.pool = None
        self.size = 0
        #: the scope's workers were forked with scipy.signal loaded (deckpound.models.iir)
        self.filtered = False


_SCOPE = _Scope()


@contextlib.contextmanager
def pool_scope() -> Iterator[None]:
    """Keep the local pool of the first parallel map for the later ones until the scope ends
    (nested scopes share the outermost one's pool)."""
    _SCOPE.active += 1
    try:
        yield
    except BaseException:
        if _SCOPE.active == 1:
            _close(kill=True)  # an error or Ctrl-C: workers killed, nothing waited for
        raise
    finally:
        _SCOPE.active -= 1
        if _SCOPE.active == 0:
            _close(kill=False)


def _new_pool(n: int):
    return ProcessPoolExecutor(max_workers=n, initializer=worker_init, initargs=(os.getpid(),))


def _close(kill: bool) -> None:
    pool, _SCOPE.pool, _SCOPE.size = _SCOPE.pool, None, 0
    if pool is not None:
        _stop(pool, kill)


def _stop(pool, kill: bool) -> None:
    """Shut a pool down; ``kill``: SIGKILL its workers first and never wait for queued work."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    if kill:
        for proc in procs:
            with contextlib.suppress(Exception):
                proc.kill()
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in procs:
            with contextlib.suppress(Exception):
                proc.join(REAP_TIMEOUT)
        return
    pool.shutdown(wait=True)


def _acquire(n: int):
    """(pool, owned): the scope's pool when it has ``n`` workers, else a new one; ``owned``:
    the caller stops it when done."""
    if _SCOPE.active:
        if _SCOPE.pool is not None and _SCOPE.size != n:
            _close(kill=False)
        if _SCOPE.pool is None:
            _SCOPE.pool, _SCOPE.size = _new_pool(n), n
            _SCOPE.filtered = "scipy.signal" in sys.modules
        return _SCOPE.pool, False
    return _new_pool(n), True


def map_local(items: list, args_of: Callable, func: Callable, on_done: Callable, n: int) -> None:
    """Apply ``func(*args_of(item))`` on ``n`` local worker processes; ``on_done(item, value)``
    in this process as each finishes (in completion order). An exception of ``func`` or of
    ``on_done``, and Ctrl-C, kill the workers and propagate."""

    if len(items) >= SCIPY_AFTER:
        # a sweep: scipy.signal's import now, in this process, so that the workers forked for
        # it inherit it instead of each importing it at its 16th record (a stall mid-sweep);
        # a scope's pool forked before the import is replaced
        load_compiled_filter()
        if _SCOPE.pool is not None and not _SCOPE.filtered:
            _close(kill=False)
    pool, owned = _acquire(min(n, len(items)) if not _SCOPE.active else n)
    # the workers are forked during the first submit: SIGINT and SIGTERM blocked meanwhile, so
    # that no worker can take either before its initializer has set what it does with them
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        futures = {pool.submit(func, *args_of(it)): it for it in items}
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
    try:
        pending = set(futures)
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                on_done(futures[fut], fut.result())
    except BaseException:
        if pool is _SCOPE.pool:
            _SCOPE.pool, _SCOPE.size = None, 0
        _stop(pool, kill=True)
        raise
    if owned:
        _stop(pool, kill=False)

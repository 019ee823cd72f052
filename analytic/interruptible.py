"""Running a compiled step loop so that Ctrl-C stops it within one iteration.

A compiled loop does not return to the interpreter until it ends, so a Python signal handler
(Ctrl-C → KeyboardInterrupt) cannot run meanwhile. Every loop polls ``stats.halt[0]`` once per
Newton iteration / Runge–Kutta step attempt and, when it is set, ends with status
``RUN_INTERRUPTED``, its output rows written so far intact (:mod:`deckpound.analytic.bundles`).
:func:`run_loop` arranges for Ctrl-C to set that flag, in one of three ways:

* **Called directly** outside the main thread (no signal handler runs there) and where SIGINT
  is ignored (``SIG_IGN``: a sweep's worker process, which its parent stops): no
  KeyboardInterrupt can come.
* **Watched** in the main thread while SIGINT has Python's default handler and no other
  signal a Python handler (the usual case of a script): the loop runs in the main thread
  with the interpreter lock released (the loops are compiled ``nogil``). Python's C-level
  signal handler writes the number of every signal it receives to the wake-up descriptor
  (``signal.set_wakeup_fd``), here the write end of a pipe whose read end a watcher thread
  of this process reads: on a SIGINT it sets the running loop's halt flag. When the loop has
  stopped, the pending KeyboardInterrupt is raised in the main thread and caught here. The
  descriptor is taken only while the loop runs and only if no one else holds it.
* **Threaded** otherwise (a program's own signal handler, as the CLI's for SIGTERM, which must
  run during the loop, not after it; a wake-up descriptor held by someone else, as an asyncio
  loop's): the loop runs in a helper thread while the main thread waits, running the
  program's handlers, and turns a KeyboardInterrupt into the halt flag.

The first two need no thread start and no wake-up of a waiting thread at the loop's end, which
the measured loop time would include. None of the three changes the loop's arithmetic.
"""

from __future__ import annotations

import os
import signal
import threading

__all__ = ["run_loop"]


class _Watch:
    """This process's watcher: the pipe (read and write descriptors), the process that made it
    (a forked child makes its own), and the stats of the loop now running."""

    def __init__(self):
        self.pid = None
        self.pipe: tuple[int, int] | None = None
        self.stats = None


_WATCH = _Watch()
#: what getsignal reports for a signal without a Python handler
_NOT_PYTHON = (signal.SIG_DFL, signal.SIG_IGN, None)
#: the signals other than SIGINT that a Python handler can be installed for
_OTHER_SIGNALS = tuple(
    s
    for s in signal.valid_signals()
    if s not in (signal.SIGINT, getattr(signal, "SIGKILL", None), getattr(signal, "SIGSTOP", None))
)


def run_loop(loop, args, stats) -> bool:
    """Run the compiled ``loop(*args)`` so that Ctrl-C stops it within one iteration (module
    docstring); True if it was interrupted. ``stats``: the loop's Stats bundle (its ``halt``
    flag is set on Ctrl-C)."""
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    ):
        loop(*args)
        return False
    if _python_handles_only_sigint():
        fd = _watch_fd()
        previous = signal.set_wakeup_fd(fd, warn_on_full_buffer=False)
        if previous in (-1, fd):
            return _run_watched(loop, args, stats)
        signal.set_wakeup_fd(previous)  # someone else's: theirs stays
    return _run_threaded(loop, args, stats)


def _python_handles_only_sigint() -> bool:
    """Whether SIGINT has Python's default handler (KeyboardInterrupt) and no other signal a
    Python handler: a program's own handler (the CLI's SIGTERM, an alarm's timeout) would
    otherwise wait for the loop's end to run, so it keeps the helper thread, where it runs
    while the loop does."""
    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        return False
    return all(signal.getsignal(s) in _NOT_PYTHON for s in _OTHER_SIGNALS)


def _watch_fd() -> int:
    """The write end of this process's watcher pipe, made (with its thread) at first use and
    again in a forked child."""
    if _WATCH.pid != os.getpid():
        if _WATCH.pipe is not None:  # the parent's, inherited by a fork: not ours to read
            for fd in _WATCH.pipe:
                os.close(fd)
        reader, writer = os.pipe()
        os.set_blocking(writer, False)  # set_wakeup_fd needs a non-blocking descriptor
        _WATCH.pipe, _WATCH.pid = (reader, writer), os.getpid()
        threading.Thread(
            target=_watch, args=(reader,), name="deckpound-sigint", daemon=True
        ).start()
    return _WATCH.pipe[1]


def _watch(reader: int) -> None:
    """The watcher thread: every signal number written to the wake-up descriptor is one byte;
    a SIGINT halts the loop that runs now (none: nothing to do)."""
    while True:
        try:
            numbers = os.read(reader, 256)
        except OSError:
            return
        if not numbers:
            return
        stats = _WATCH.stats
        if signal.SIGINT in numbers and stats is not None:
            stats.halt[0] = 1


def _run_watched(loop, args, stats) -> bool:
    """The loop in this (main) thread, the watcher halting it on SIGINT; the KeyboardInterrupt
    that follows, raised when the loop has returned, is caught."""
    interrupted = False
    try:
        _WATCH.stats = stats
        try:
            loop(*args)
        finally:
            _WATCH.stats = None
            signal.set_wakeup_fd(-1)
    except KeyboardInterrupt:
        interrupted = True
    return interrupted


def _run_threaded(loop, args, stats) -> bool:
    """The loop in a helper thread while this one waits; a KeyboardInterrupt here sets the halt
    flag and waits for the loop to stop."""
    failure: list[BaseException] = []
    done = threading.Event()

    def target():
        try:
            loop(*args)
        except BaseException as exc:
            failure.append(exc)
        finally:
            done.set()

    # waiting on an Event, not Thread.join: a join interrupted by KeyboardInterrupt marks the
    # thread finished although it still runs (CPython 3.11, the bpo-45274 lock handling)
    worker = threading.Thread(target=target, name="deckpound-loop", daemon=True)
    interrupted = False
    worker.start()
    try:
        while not done.wait(0.05):
            pass
    except KeyboardInterrupt:
        interrupted = True
        stats.halt[0] = 1
        while not done.wait(0.05):  # the loop stops within one iteration
            pass
    if failure:
        raise failure[0]
    return interrupted

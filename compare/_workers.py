"""Worker processes that die with their parent.

A process pool's workers outlive a parent killed with SIGKILL (or by the OOM killer): they
finish their queued cases and keep writing into the cache for tens of seconds. The pool
initializer :func:`die_with_parent` prevents that twice over:

1. on Linux, ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` makes the kernel kill the worker the moment
   its parent exits (also inside a compiled numba loop, which a Python-level check could not
   interrupt);
2. everywhere, a daemon thread polls the parent's pid every :data:`POLL` seconds and ends the
   worker with ``os._exit`` once the parent is gone (a fallback where prctl is missing).

Caveat of (1): Linux delivers the signal when the *thread* that forked the worker exits, so
pools must be created by a thread that outlives them (the runner creates them in the calling
thread and shuts them down before returning).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import sys
import threading
import time

PR_SET_PDEATHSIG = 1
#: seconds between two checks of the parent's pid by the watchdog thread
POLL = 0.5


def _set_pdeathsig() -> bool:
    """Ask the Linux kernel to SIGKILL this process when its parent exits."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch(parent_pid: int) -> None:
    while True:
        if os.getppid() != parent_pid:
            os._exit(1)
        time.sleep(POLL)


def die_with_parent(parent_pid: int) -> None:
    """Pool initializer: end this worker as soon as process ``parent_pid`` is gone."""
    _set_pdeathsig()
    if os.getppid() != parent_pid:  # the parent died before the request took effect
        os._exit(1)
    threading.Thread(
        target=_watch, args=(parent_pid,), name="deckpound-parent-watch", daemon=True
    ).start()

"""Fast loading of cached numba kernels: skip numba's full context set-up on a cache hit.

Before numba loads a compiled function from its on-disk cache it "refreshes" its typing and
target contexts: it imports about 60 modules of numba's own (linear algebra, random numbers,
typed containers, ...) and installs every registered typing template and lowering — 0.3–1.0 s
on this machine, more than the whole compliance run of the benchmark, spent on every process
start although a cached kernel needs none of it. A cached kernel is machine code plus the
description of its calling convention; rebuilding it needs the code generator, the runtime's
symbols (NRT) and numba's C helpers, which the target context has from its construction.

:func:`install` wraps numba's ``Cache.load_overload``: on a lookup it initialises the runtime
(NRT; cheap, idempotent) and tries the cached entry without the refresh. Everything else stays
numba's: a miss, a stale entry or any error while rebuilding falls back to numba's own path
(refresh, then load or compile), and every compilation refreshes the contexts itself (numba's
compiler does so before typing), so a process that compiles later is unaffected.

``DECKPOUND_NUMBA_FASTLOAD=0`` turns it off. It is installed by the engine registry before an
engine module is imported (:func:`deckpound.engines.get_engine`), by ``deckpound compile`` and
by the sweep workers. The test-suite runs every engine through it.
"""

from __future__ import annotations

import os

__all__ = ["install", "installed"]

_STATE = {"installed": False}


def installed() -> bool:
    """Whether the fast path is active in this process."""
    return _STATE["installed"]


def install() -> bool:
    """Wrap numba's cache lookup (once per process); returns whether the fast path is active.

    Does nothing when ``DECKPOUND_NUMBA_FASTLOAD=0`` or when numba's cache class does not have
    the methods it relies on (another numba version: numba's own path is used).
    """
    if _STATE["installed"]:
        return True
    if os.environ.get("DECKPOUND_NUMBA_FASTLOAD", "1").strip() == "0":
        return False
    try:
        from numba.core import caching
        from numba.core.runtime import rtsys
    except ImportError:
        return False
    cache_cls = getattr(caching, "Cache", None)
    needed = ("load_overload", "_load_overload", "_guard_against_spurious_io_errors")
    if cache_cls is None or not all(hasattr(cache_cls, n) for n in needed):
        return False
    original = cache_cls.load_overload

    def load_overload(self, sig, target_context):
        try:
            rtsys.initialize(target_context)
            with self._guard_against_spurious_io_errors():
                cres = self._load_overload(sig, target_context)
            if cres is not None:
                return cres
        except Exception:
            pass
        return original(self, sig, target_context)

    load_overload.__doc__ = original.__doc__
    load_overload.__wrapped__ = original
    cache_cls.load_overload = load_overload
    _STATE["installed"] = True
    return True

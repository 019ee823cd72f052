"""Fast loading of cached numba kernels: skip numba's full context set-up on a cache hit.

Before numba loads a compiled function from its on-disk cache it "refreshes" its typing and
target contexts: it imports about 60 modules of numba's own (linear algebra, random numbers,
typed containers, ...) and installs every registered typing template and lowering — 0.3–1.0 s
on this machine, more than the whole compliance run of the benchmark, spent on every process
start although a cached kernel needs none of it. A cached kernel is machine code plus the
description of its calling convention; rebuilding it needs the code generator, the runtime's
symbols (NRT) and numba's C helpers, which the target context has from its construction.

:func:`install` wraps numba's ``Cache.load_overload``: on a lookup it reads the cached entry and
rebuilds it without the refresh. numba's runtime (NRT) is initialised first only when the
entry's machine code refers to it (:func:`uses_runtime`): the initialisation JIT-compiles the
runtime's own functions in every process (part of the "kernel load" column of ``deckpound
bench``'s speed table), and the step loops, compiled without the runtime
(:mod:`deckpound.analytic._jit`), never call them. A library whose code names an NRT symbol that
was never registered would stop the process inside LLVM (an unresolved symbol is a fatal error
there, not an exception), so the test is conservative: any occurrence of "nrt", in any case, in
the object code initialises the runtime. Everything else stays numba's: a miss, a stale entry or
any error while rebuilding falls back to numba's own path (refresh, then load or compile), and
every compilation refreshes the contexts itself (numba's compiler does so before typing), so a
process that compiles later is unaffected.

``DECKPOUND_NUMBA_FASTLOAD=0`` turns it off. It is installed by the engine registry before an
engine module is imported (:func:`deckpound.compare.engines.get_engine`), by ``deckpound compile`` and
by the sweep workers. The test-suite runs every engine through it.
"""

from __future__ import annotations

import os

__all__ = ["install", "installed", "uses_runtime"]

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
            with self._guard_against_spurious_io_errors():
                cres = _load_without_refresh(self, sig, target_context, rtsys)
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


def _load_without_refresh(cache, sig, target_context, rtsys):
    """numba's ``Cache._load_overload`` with the runtime initialised only when the entry needs
    it. Returns the rebuilt compile result, or None (disabled cache, no entry)."""
    if not cache._enabled:
        return None
    data = cache._cache_file.load(cache._index_key(sig, target_context.codegen()))
    if data is None:
        return None
    if uses_runtime(data[0]):
        rtsys.initialize(target_context)
    return cache._impl.rebuild(target_context, data)


def uses_runtime(libdata) -> bool:
    """Whether a cached library (numba's ``serialize_using_object_code`` state: name, kind,
    (object code, bitcode)) may refer to numba's runtime: True unless it is object code in which
    "nrt" does not occur in any case (the runtime's symbols are ``NRT_*`` and ``_nrt_*``)."""
    try:
        _name, kind, data = libdata
        code = bytes(data[0])
    except (TypeError, ValueError, IndexError):
        return True
    return kind != "object" or b"nrt" in code.lower()

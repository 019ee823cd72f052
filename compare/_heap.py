"""The C heap of a sweep worker: freed memory kept for the next case (glibc ``mallopt``).

A sweep case allocates and frees the same few megabytes again and again (its record, the
filter's padded copies, the FFT buffers, the output table). glibc's malloc hands a freed block
at the top of a heap back to the kernel once more than ``M_TRIM_THRESHOLD`` is free there, and
serves a block above ``M_MMAP_THRESHOLD`` by a fresh ``mmap`` that ``free`` unmaps; either way
the next case touches fresh pages, one page fault (and a page of zeros written by the kernel)
per 4 KiB. Its dynamic thresholds adapt to this pattern in the main thread, but a thread's
own arena (a Dask worker runs its tasks in a thread) kept returning pages and faulting them in
again at every case of the benchmark (``tests/test_heap.py`` counts the faults with and
without these settings; ``tools/sweep_benchmark.py`` measures the sweeps).

:func:`keep_freed_memory` sets the three thresholds once, for the worker's lifetime; freed
memory stays in the process up to ``M_TRIM_THRESHOLD`` above what a case needs at its peak
(pages that were never touched are not resident). It is called in processes deckpound starts
or is given for its sweeps (the local pool's workers and the Dask workers, whose set-up runs
it), never in the caller's own process. Elsewhere than on Linux with glibc it does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import sys

__all__ = ["HEAP_SETTINGS", "keep_freed_memory"]

# glibc's malloc.h parameter numbers
M_TRIM_THRESHOLD = -1
M_TOP_PAD = -2
M_MMAP_THRESHOLD = -3

#: (parameter, bytes): blocks up to 32 MiB (glibc's largest mmap threshold on 64 bits) from the
#: heap, up to 128 MiB free at its top kept, heaps grown 64 MiB at a time (virtual: untouched
#: pages cost no memory)
HEAP_SETTINGS = (
    (M_MMAP_THRESHOLD, 32 << 20),
    (M_TRIM_THRESHOLD, 128 << 20),
    (M_TOP_PAD, 64 << 20),
)


def keep_freed_memory() -> bool:
    """Set :data:`HEAP_SETTINGS` with glibc's ``mallopt`` for this process (every thread's
    arena); True if every setting was accepted, False where there is no glibc ``mallopt``
    (nothing is changed)."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
        if not hasattr(libc, "gnu_get_libc_version"):  # another C library's mallopt
            return False
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    return all(mallopt(param, value) == 1 for param, value in HEAP_SETTINGS)

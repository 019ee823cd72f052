"""The sweep workers' C heap settings (deckpound.compare._heap): freed memory is reused, not
handed back to the kernel and faulted in again at the next case."""

from __future__ import annotations

import ctypes.util
import subprocess
import sys

import pytest

from deckpound.compare import cases, pool
from deckpound.compare._heap import HEAP_SETTINGS, keep_freed_memory

glibc = pytest.mark.skipif(
    not sys.platform.startswith("linux") or "libc.so" not in (ctypes.util.find_library("c") or ""),
    reason="glibc's mallopt only",
)

# rounds of 4 MiB of short-lived, touched blocks of 1 MiB (the size glibc's dynamic mmap
# threshold has risen to): the page faults of a round, averaged over the last 15 of 20
PROBE = """
import resource, sys
import numpy as np
from deckpound.compare._heap import keep_freed_memory
if sys.argv[1] == "kept":
    assert keep_freed_memory()
np.ones(1 << 17)
faults = []
for _ in range(20):
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    blocks = [np.ones(1 << 17) for _ in range(4)]
    del blocks
    faults.append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
print(sum(faults[5:]) / 15)
"""


def _faults_per_round(mode: str) -> float:
    out = subprocess.run(
        [sys.executable, "-c", PROBE, mode], capture_output=True, text=True, check=True
    )
    return float(out.stdout.strip())


@glibc
def test_freed_blocks_are_reused_without_page_faults():
    # glibc's defaults trim the 4 MiB freed at the top of the heap after every round (about
    # one fault per 4 KiB page when the next round touches them again); kept, none
    default = _faults_per_round("default")
    kept = _faults_per_round("kept")
    assert default > 500, default
    assert kept < 10, kept


@glibc
def test_every_setting_is_accepted_in_a_fresh_process():
    code = "from deckpound.compare._heap import keep_freed_memory; print(keep_freed_memory())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"
    # blocks up to glibc's largest mmap threshold on 64 bits come from the heap
    assert dict(HEAP_SETTINGS)[-3] == 32 << 20


def test_elsewhere_than_linux_nothing_is_changed(monkeypatch):
    monkeypatch.setattr(sys, "platform", "darwin")
    assert keep_freed_memory() is False


def test_the_sweep_workers_set_it_and_the_callers_process_does_not(monkeypatch):
    calls = []
    monkeypatch.setattr(pool, "keep_freed_memory", lambda: calls.append("pool") or True)
    monkeypatch.setattr(cases, "keep_freed_memory", lambda: calls.append("dask") or True)
    monkeypatch.setattr(pool, "die_with_parent", lambda pid: None)
    monkeypatch.setattr(pool.signal, "signal", lambda *a: None)
    monkeypatch.setattr(pool.signal, "pthread_sigmask", lambda *a: None)
    monkeypatch.setattr(cases, "load_compiled_filter", lambda: None)
    monkeypatch.setattr("deckpound.analytic.kernel_load.install", lambda: True)
    with pool.one_blas_thread():  # the initializer's limit, undone for this test process
        pool.worker_init(0)
        cases._dask_worker_setup()
    assert calls == ["pool", "dask"]
    # an in-process sweep runs in the caller's own process: its heap stays the caller's
    calls.clear()
    cases.map_parallel([1, 2], lambda i: (i,), lambda i: i, lambda i, v: None, 1, None)
    assert calls == []

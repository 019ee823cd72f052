"""numba's private APIs that deckpound uses as fast paths either work or fall back to numba's own
path with identical results (issue 29, item 7; numba is bounded above in pyproject.toml to the
range these tests ran on).

- ``Cache.load_overload`` (analytic/kernel_load.py): loading a cached kernel without numba's
  context refresh. Its identical results are tests/test_kernel_load.py; here: a numba whose
  cache class lacks the methods it wraps is left alone.
- ``numba._dispatcher.compute_fingerprint`` (analytic/_jit.py): the compiled-already check of
  ``ensure_compiled``. Without it (absent, or failing), every call takes numba.typeof's path.
- ``numba.core.cgutils`` (analytic/fp_mode.py, the flush-to-zero switch): its fallback, a
  machine that cannot flush, is tests/test_fp_mode.py::test_a_machine_that_cannot_flush_says_so.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import deckpound as dp
from deckpound.analytic import _jit

WITHOUT_THE_CACHE_METHODS = """
import json, numpy as np
import numba.core.caching as caching
class Cache:  # a numba without the methods the fast load wraps
    pass
caching.Cache = Cache
from deckpound.analytic.kernel_load import install, installed
assert install() is False and not installed()
import deckpound as dp
r = dp.run(dp.load_scene("saiidi-4span", set={"run.duration": 0.5}), engine="compliance")
print(json.dumps({k: np.asarray(v).tolist() for k, v in r.columns.items()}))
"""


def _columns(result) -> dict:
    return {k: np.asarray(v) for k, v in result.columns.items()}


def _same(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k], equal_nan=True) for k in a)


@pytest.fixture(scope="module")
def reference():
    scene = dp.load_scene("saiidi-4span", set={"run.duration": 0.5})
    return scene, {e: _columns(dp.run(scene, engine=e)) for e in ("compliance", "nonsmooth")}


def test_a_numba_without_the_cache_methods_keeps_its_own_loading(reference):
    p = subprocess.run(
        [sys.executable, "-c", WITHOUT_THE_CACHE_METHODS],
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    assert p.returncode == 0, p.stderr[-2000:]
    columns = {k: np.asarray(v) for k, v in json.loads(p.stdout.splitlines()[-1]).items()}
    assert _same(columns, reference[1]["compliance"])


@pytest.mark.parametrize("fingerprint", [None, "raises"], ids=["absent", "failing"])
def test_without_numbas_fingerprint_the_kernels_run_the_same(monkeypatch, reference, fingerprint):
    def failing(_value):
        raise TypeError("no fingerprint for this type")

    monkeypatch.setattr(_jit, "compute_fingerprint", failing if fingerprint else None)
    monkeypatch.setattr(_jit, "_READY", set())
    scene, expected = reference
    for engine, columns in expected.items():
        assert _same(_columns(dp.run(scene, engine=engine)), columns)
    assert set() == _jit._READY  # every call took numba.typeof's path

"""Cached kernels load without numba's full context set-up (src/deckpound/_kernel_load.py),
with results identical to numba's own loading path."""

import json
import os
import subprocess
import sys

import pytest

CODE = """
import json, sys
import numpy as np
import deckpound as dp
scene = dp.load_scene("saiidi-4span", set={"run.duration": 0.5})
out = {}
for engine in ("compliance", "nonsmooth"):
    r = dp.run(scene, engine=engine)
    out[engine] = {k: np.asarray(v).tolist() for k, v in r.columns.items()}
from deckpound.analytic.kernel_load import installed
from numba.core.runtime import rtsys
print(json.dumps({"installed": installed(), "refreshed": "numba.np.linalg" in sys.modules,
                  "runtime": rtsys._init, "columns": out}))
"""


def _run(fast: bool) -> dict:
    env = dict(os.environ, DECKPOUND_NUMBA_FASTLOAD="1" if fast else "0")
    p = subprocess.run(
        [sys.executable, "-c", CODE],
        capture_output=True,
        text=True,
        env=env,
        timeout=900,
        check=False,
    )
    assert p.returncode == 0, p.stderr[-2000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


@pytest.mark.skipif(os.environ.get("DECKPOUND_NUMBA_FASTLOAD") == "0", reason="turned off")
def test_fast_load_skips_the_refresh_and_gives_identical_results():
    slow = _run(False)  # numba's own path (also fills the cache when it is cold)
    fast = _run(True)
    assert not slow["installed"] and slow["refreshed"]
    assert fast["installed"] and not fast["refreshed"]  # numba's registries were not loaded
    assert not fast["runtime"]  # the step loops do not use numba's runtime: not initialised
    assert fast["columns"] == slow["columns"]


def test_a_cached_kernel_that_allocates_gets_the_runtime():
    """A cached kernel whose code calls numba's runtime (an allocating one) initialises it
    before its code is linked: unresolved, its NRT symbols would stop the process in LLVM."""
    code = (
        "from deckpound.analytic.kernel_load import install; install()\n"
        "import numpy as np\n"
        "from numba.core.runtime import rtsys\n"
        "from deckpound.analytic.kernels.dense import solve_dense_cp\n"
        "A = np.array([[2.0, 0.0], [0.0, 4.0]]); b = np.array([2.0, 4.0]); x = np.zeros(2)\n"
        "print(solve_dense_cp(A, b, x, 1e-12), x.tolist(), rtsys._init)"
    )
    for _ in range(2):  # the second process loads the kernel from the cache the first filled
        p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        assert p.returncode == 0, p.stderr[-2000:]
    assert p.stdout.strip() == "(2, True) [1.0, 1.0] True"


def test_uses_runtime_is_conservative():
    from deckpound.analytic.kernel_load import uses_runtime

    assert not uses_runtime(("lib", "object", (b"\x7fELF...numba_gil_ensure", b"bc")))
    assert uses_runtime(("lib", "object", (b"\x7fELF...NRT_decref", b"bc")))
    assert uses_runtime(("lib", "object", (b"..._nrt_get_sample_external_allocator", b"bc")))
    assert uses_runtime(("lib", "bitcode", b"BC"))  # not object code: cannot tell
    assert uses_runtime(None) and uses_runtime(("lib", "object"))


def test_compiling_after_a_fast_load_still_works():
    """A kernel missing from the cache after fast loads: numba's compiler refreshes itself."""
    code = (
        "from deckpound.analytic.kernel_load import install; install()\n"
        "import numba\n"
        "@numba.njit\n"
        "def f(x):\n    return x.sum() + 1.0\n"
        "import numpy as np; print(f(np.ones(3)))"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert p.stdout.strip() == "4.0"


LOADED = """
import gc, json
import deckpound as dp
from numba.core.dispatcher import Dispatcher
scene = dp.load_scene("saiidi-4span", set={"run.duration": 0.5})
out = {}
for engine in ("compliance", "nonsmooth"):
    dp.run(scene, engine=engine)
    out[engine] = sorted(
        d.py_func.__qualname__
        for d in gc.get_objects()
        if isinstance(d, Dispatcher) and d.py_func.__module__.startswith("deckpound") and d.overloads
    )
print(json.dumps(out))
"""


def test_a_run_loads_only_its_step_loop():
    """Each numba function called from Python is a separate load from the on-disk cache (0.05 to
    0.2 s in a fresh process): a run calls only its engine's step loop; the state and workspace
    builders around it are plain Python."""
    p = subprocess.run(
        [sys.executable, "-c", LOADED], capture_output=True, text=True, timeout=900, check=False
    )
    assert p.returncode == 0, p.stderr[-2000:]
    loaded = json.loads(p.stdout.strip().splitlines()[-1])
    assert loaded["compliance"] == ["newmark_run"]
    assert loaded["nonsmooth"] == ["moreau_jean_run", "newmark_run"]

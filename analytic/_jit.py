"""The compile decorator of deckpound's per-step kernels: numba without reference counting.

Every numba function that takes arrays increments the arrays' reference counts on entry and
decrements them on exit (and around every view it takes, e.g. ``hstate[i]``). Each of these is an
atomic add through a function pointer, ~5–10 ns. numba's LLVM pass that removes the matched pairs
misses them as soon as an array's last use depends on a branch (an early ``return``, an
``if``/``else`` that reads the array on one side only), because LLVM first merges the decrements
of the branches into one ``phi``. The Takeda kernel is all branches: measured on the benchmark
scene, ~60 % of the Newmark loop's time went to reference counting (6 Hysteretic springs, three
force evaluations per step: 374 ns per evaluation with, 35 ns without).

:func:`kernel` compiles a function with numba's runtime (NRT) switched off (``_nrt=False``, a
documented-in-code numba flag used by its own test-suite; see numba issue #2350, "refcount op in
branching code affects performance"). Such a function cannot allocate (``np.empty``, ``np.zeros``,
``.copy()``, array expressions); numba refuses to compile it if it tries, so the rule is checked,
not assumed. It may take views of arrays and call other kernels. numba passes the caller's
runtime flag on to callees that do not set it: a function that allocates and is called from a
kernel must say ``njit(_nrt=True)`` explicitly (as the nonsmooth engine's contact solve does).
Allocation belongs in the engine's driver (``newmark_workspace``, ``moreau_jean_workspace``).
Arrays passed in stay owned by the caller: without reference counting a kernel must not keep
them beyond the call, and it must not *return* an array (not even one it was given): an NRT
caller takes a returned array as a new reference and releases it, which frees the caller's
array under it (a crash). Kernels write into the arrays they are given and return scalars or
tuples of scalars.

Both decorators compile with ``error_model="numpy"``: a float division follows IEEE 754
(x/0 is ±inf, 0/0 NaN) instead of numba's default, which tests every divisor for zero to raise
``ZeroDivisionError`` (a compare and a branch per division on the step path, the Takeda kernel's
included: it is inlined and compiled with its caller's flags). Where a division by zero could
come from the state, the step loops' finiteness test of the Newton increment (or of the state)
ends the run with ``RUN_NONFINITE`` instead of an exception from inside the kernel. An integer
``//`` or ``%`` by zero gives 0 under this model: the kernels' integer divisors (output strides,
counts) are at least 1 by construction.

Use ``@kernel`` in place of ``@njit(cache=True)`` for functions on the per-step path;
``@kernel(inline="always")`` etc. pass options through.
"""

from __future__ import annotations

import hashlib
import os
import time
from importlib.util import find_spec
from pathlib import Path

import numba
from numba import njit, types

try:  # numba's private C fingerprint of an argument's type: a fast path, not a requirement
    from numba._dispatcher import compute_fingerprint
except ImportError:  # pragma: no cover - another numba: numba.typeof below does the work
    compute_fingerprint = None

__all__ = [
    "compiled",
    "ensure_compiled",
    "kernel",
    "plain_argument_types",
    "use_source_keyed_cache",
]

_HERE = Path(__file__).resolve().parent


def kernel(fn=None, **options):
    """``numba.njit(cache=True, _nrt=False, error_model="numpy", **options)``, one
    specialisation per argument types (:func:`plain_argument_types`): see the module
    docstring."""
    opts = {"cache": True, "_nrt": False}
    opts.update(options)
    return compiled(fn, **opts)


def compiled(fn=None, **options):
    """``numba.njit(cache=True, error_model="numpy", **options)`` with
    :func:`plain_argument_types` (for the functions that allocate, which keep numba's
    runtime)."""
    opts = {"cache": True, "error_model": "numpy"}
    opts.update(options)
    if fn is None:
        return lambda f: plain_argument_types(njit(**opts)(f))
    return plain_argument_types(njit(**opts)(fn))


def plain_argument_types(dispatcher):
    """Compile calls from other compiled functions for the plain types of their arguments.

    A constant argument (``f(x, 0)``, ``g(u, True)``, a module constant, or a variable while
    type inference has seen only its initial constant) reaches a numba callee as a literal
    type (``Literal[int](0)``), and numba compiles the callee once per literal value and once
    more for the plain type: 10 compilations of one statistics writer, 3 of the contact
    kinematics, 2 of the contact-impulse solve (measured from an empty cache). The kernels do
    not dispatch on literal values, so calls are typed with :func:`numba.types.unliteral`
    argument types: one compilation, the same machine code for every call site (the
    constants are cast at the call). Returns the dispatcher.
    """
    resolve = dispatcher.get_call_template

    def get_call_template(args, kws):
        return resolve(
            tuple(types.unliteral(a) for a in args), {k: types.unliteral(v) for k, v in kws.items()}
        )

    dispatcher.get_call_template = get_call_template
    return dispatcher


def use_source_keyed_cache() -> Path | None:
    """Put numba's on-disk cache of the analytic kernels in a directory keyed by their sources.

    numba checks a cached function against its *own* file only; a kernel it calls from another
    module is compiled into it, so after a change to e.g. ``hysteretic_kernel.py`` the cached
    Newmark loop of ``compliance.py`` would still run the old Takeda arithmetic, silently. Keying
    the cache directory by a hash of every source file of this package, of the modules whose
    constants the kernels freeze (:data:`FROZEN_MODULES`) and of the environment switches the
    kernels freeze at compile time makes any change start a fresh cache.

    The directory is ``$XDG_CACHE_HOME/deckpound/numba/<hash>`` (default ``~/.cache``). A
    ``NUMBA_CACHE_DIR`` set by the user wins; an unwritable location leaves numba's default.
    Called by the package ``__init__`` before any kernel is decorated. Returns the directory
    used, or None.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    h = hashlib.sha256()
    for src in sorted(_HERE.rglob("*.py")) + _frozen_sources():
        h.update(str(src.relative_to(src.parents[1])).encode())
        h.update(src.read_bytes())
    h.update(os.environ.get("DECKPOUND_TAKEDA_SHORTCUT", "1").encode())
    h.update(numba.__version__.encode())
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    target = base / "deckpound" / "numba" / h.hexdigest()[:16]
    try:
        target.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    if not os.access(target, os.W_OK):
        return None
    numba.config.CACHE_DIR = str(target)
    return target


#: Modules outside this package whose constants the kernels freeze at compile time (DOF
#: indices and output layout of the plan model; the contact-law codes): part of the cache key.
FROZEN_MODULES = ("deckpound.models.plan", "deckpound.models.contact_laws_table")


def _frozen_sources() -> list[Path]:
    out = []
    for name in FROZEN_MODULES:
        spec = find_spec(name)
        if spec is not None and spec.origin:
            out.append(Path(spec.origin))
    return out


def ensure_compiled(dispatcher, *args) -> float:
    """Compile (or load from numba's on-disk cache) ``dispatcher`` for the types of ``args``.

    Returns the seconds it took: close to zero when the kernel is already compiled for these
    types in this process. Engines call it before their timed loop, so that compile time is
    reported apart from run time (engine contract, point 7) and the loop's first call never
    compiles.
    """
    t0 = time.perf_counter()
    # numba.typeof of the bundles (nested named tuples of ~100 arrays) takes ~10 ms in Python,
    # every run; numba's own C fingerprint of the arguments (what its dispatcher uses to pick a
    # compiled version) identifies the same types in microseconds, so a process that has
    # compiled or loaded the kernel for these types returns at once
    try:
        key = (id(dispatcher), tuple(compute_fingerprint(a) for a in args))
    except Exception:  # no fingerprint (a type numba cannot fingerprint, or another numba)
        key = None
    if key is None or key not in _READY:
        dispatcher.compile(tuple(numba.typeof(a) for a in args))
        if key is not None:
            _READY.add(key)
    return time.perf_counter() - t0


#: (dispatcher id, argument fingerprints) that :func:`ensure_compiled` has compiled or loaded
_READY: set = set()

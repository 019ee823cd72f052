"""``deckpound compile``: compile every kernel a user can reach, once, off the critical path.

numba compiles a kernel for the argument types it is called with and keeps the machine code in
its on-disk cache (``~/.cache/deckpound/numba/<hash of the kernels' sources>``, see
:func:`deckpound.analytic._jit.use_source_keyed_cache`). Which types a run produces depends on
the scene and the engine settings, and the kernels' signatures change as the kernels do; so the
warm-up does not list signatures: it *runs* each analytic engine on tiny versions of the
benchmark that cover the type specialisations a user can reach (:data:`ITEMS`: linear and
nonlinear contact geometry, each friction mode, the newmark and adaptive integrators, the
nonsmooth engine's lemke and enumeration solvers, a deck of several segments; the Hysteretic
material used by ``deckpound verify takeda``). Each item runs in this process through the public engine
registry, exactly as a user's run would, so whatever those runs compile is what the users'
runs load.

The numba compile events are counted per item (``compiled``: kernels numba had to compile,
0 when everything came from the cache). ``./run.sh`` runs the command once after installing
(its stamp file holds a hash of the kernels' sources; a change re-runs it), ``pip install``
users run ``deckpound compile`` once (README, docs/user-guide.md).
"""

from __future__ import annotations

import compileall
import importlib
import importlib.util
import struct
import time
import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

from deckpound.compare.engines import run_engine
from deckpound.models.scene_io import load_scene

__all__ = [
    "ITEMS",
    "PACKAGES",
    "Item",
    "WarmResult",
    "byte_compile",
    "cache_location",
    "stale_bytecode",
    "warm",
    "warm_item",
]

#: length of the warm-up runs [s]: a few output steps; compiling does not depend on it
WARM_DURATION = 0.02

_FRICTION = ("contact.friction=0.2",)


#: the scene of the warm-up runs of a deck of segments: every N ≥ 2 shares its kernels
#: (:mod:`deckpound.analytic.kernels.size_tags`)
SEGMENTS_SCENE = "two-frame"


@dataclass(frozen=True)
class Item:
    """One warm-up run: an engine on ``scene`` (the benchmark by default) with ``overrides``
    (``engine = "takeda"``: the standalone Hysteretic material of ``deckpound verify
    takeda``)."""

    engine: str
    label: str
    overrides: tuple[str, ...] = ()
    scene: str = "saiidi-4span"


ITEMS: tuple[Item, ...] = (
    Item("compliance", "newmark, linear geometry, frictionless"),
    Item(
        "compliance",
        "newmark, nonlinear geometry, slip friction",
        ("contact.geometry=nonlinear", *_FRICTION, "contact.friction_mode=slip"),
    ),
    Item(
        "compliance",
        "newmark, linear geometry, stick friction",
        (*_FRICTION, "contact.friction_mode=stick"),
    ),
    Item(
        "compliance", "adaptive, linear geometry, frictionless", ("compliance.integrator=adaptive",)
    ),
    Item(
        "compliance",
        "adaptive, nonlinear geometry, stick friction",
        (
            "compliance.integrator=adaptive",
            "contact.geometry=nonlinear",
            *_FRICTION,
            "contact.friction_mode=stick",
        ),
    ),
    Item("nonsmooth", "lemke, linear geometry, frictionless"),
    Item(
        "nonsmooth",
        "lemke, nonlinear geometry, friction",
        ("contact.geometry=nonlinear", *_FRICTION, "contact.friction_mode=stick"),
    ),
    Item(
        "nonsmooth",
        "enumeration, linear geometry, friction",
        ("nonsmooth.solver=enumeration", *_FRICTION, "contact.friction_mode=stick"),
    ),
    # a deck of segments: one specialisation per loop serves every N ≥ 2 (the variants above
    # share it: they differ in values, not in the kernels' argument types)
    Item("compliance", "newmark, deck of segments", (), SEGMENTS_SCENE),
    Item(
        "compliance",
        "adaptive, deck of segments",
        ("compliance.integrator=adaptive",),
        SEGMENTS_SCENE,
    ),
    Item("nonsmooth", "lemke, deck of segments", (), SEGMENTS_SCENE),
    Item("takeda", "Hysteretic material (verify takeda)"),
)


@dataclass(frozen=True)
class WarmResult:
    """What warming one item took: wall seconds, kernels compiled (0: all from the cache),
    the engine-reported compile/load time, the run's status and numba's caching warnings."""

    item: Item
    seconds: float
    compiled: int
    compile_time: float
    status: str
    notes: list[str] = field(default_factory=list)


def cache_location() -> str:
    """Where numba keeps the kernels (the source-keyed directory, or NUMBA_CACHE_DIR)."""
    import numba

    import deckpound.analytic  # noqa: F401  (places the source-keyed cache)

    return str(numba.config.CACHE_DIR or "numba's default (__pycache__ beside the sources)")


#: deckpound's packages: their modules are byte-compiled by :func:`byte_compile`
PACKAGES = (
    "deckpound",
    "deckpound.models",
    "deckpound.opensees_build",
    "deckpound.analytic",
    "deckpound.analytic.kernels",
    "deckpound.analytic.compliance",
    "deckpound.analytic.nonsmooth",
    "deckpound.compare",
    "deckpound.compare.report",
    "deckpound.compare.studies",
    "deckpound.compare.verify",
    "deckpound.compare.bench",
)


def byte_compile() -> int:
    """Write Python's bytecode cache (``__pycache__/*.pyc``) of every deckpound module.

    Python writes a module's bytecode when it first imports it, unless
    ``PYTHONDONTWRITEBYTECODE`` is set (common in containers and CI images); then every process
    compiles each deckpound module it imports from source again (``builtins.compile`` in a
    cProfile of a warm ``deckpound run``; ``deckpound bench --quick`` measures the processes
    with the variable as the user's environment has it). An editable
    install (``./run.sh``'s ``pip install -e``) gets no bytecode from pip, so the set-up writes
    it here; Python reads a ``.pyc`` whatever that variable says, and ignores one whose source
    has changed since. Returns the number of modules; raises OSError when a file cannot be
    written.
    """

    folders = _package_folders()
    for folder in folders:
        if not compileall.compile_dir(str(folder), maxlevels=0, quiet=2):
            raise OSError(f"could not byte-compile the modules in {folder}")
    return sum(len(list(folder.glob("*.py"))) for folder in folders)


def stale_bytecode() -> list[str]:
    """The deckpound modules whose bytecode cache is missing or does not match the source
    (Python then compiles them from source on import, and under ``PYTHONDONTWRITEBYTECODE``
    in every process). Empty after :func:`byte_compile`."""

    stale = []
    for folder in _package_folders():
        for src in sorted(folder.glob("*.py")):
            try:
                with open(importlib.util.cache_from_source(str(src)), "rb") as f:
                    head = f.read(16)
            except OSError:
                stale.append(str(src))
                continue
            st = src.stat()
            # timestamp-based .pyc header: magic, flags 0, source mtime, source size
            want = struct.pack("<III", 0, int(st.st_mtime) & 0xFFFFFFFF, st.st_size & 0xFFFFFFFF)
            if head[:4] != importlib.util.MAGIC_NUMBER or head[4:16] != want:
                stale.append(str(src))
    return stale


def _package_folders():
    return [Path(f) for name in PACKAGES for f in importlib.import_module(name).__path__]


class _CompileCounter:
    """Counts numba's compile events (a cache hit broadcasts none)."""

    def __init__(self):
        from numba.core import event

        class Listener(event.Listener):
            def __init__(self):
                self.compiled = set()

            def on_start(self, ev):
                pass

            def on_end(self, ev):
                data = ev.data or {}
                self.compiled.add((id(data.get("dispatcher")), str(data.get("args"))))

        self.listener = Listener()
        self._event = event

    def __enter__(self):
        self._event.register("numba:compile", self.listener)
        return self.listener

    def __exit__(self, *exc):
        self._event.unregister("numba:compile", self.listener)


def _scene(item: Item):
    return load_scene(item.scene, [f"run.duration={WARM_DURATION!r}", *item.overrides])


def _warm_takeda() -> None:
    from deckpound.analytic.kernels.hysteretic import HystereticMaterial
    from deckpound.compare.verify.takeda import PARAMETER_SETS

    for args in PARAMETER_SETS:
        m = HystereticMaterial(*args, element_copy=False)
        for strain in (0.0, 1e-4, abs(args[1]) * 3.0, -abs(args[1]) * 3.0):
            m.set_trial_strain(float(strain))
            m.commit()
        m.revert_to_last_commit()
        m.revert_to_start()
        _ = (m.stress, m.tangent, m.strain, m.initial_tangent, m.copy())


def warm_item(item: Item) -> WarmResult:
    """Run one item in this process; compile or load what it needs. numba's warnings that a
    kernel could not be cached (an unwritable cache folder) are kept in ``notes``."""

    from deckpound.analytic.kernel_load import install

    install()
    with _CompileCounter() as counter, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # the variants' option notes are dropped below
        t0 = time.perf_counter()
        if item.engine == "takeda":
            _warm_takeda()
            status, compile_time = "success", 0.0
        else:
            result = run_engine(item.engine, _scene(item))
            status = str(result.meta.get("status"))
            compile_time = float(result.meta.get("compile_time", 0.0))
        seconds = time.perf_counter() - t0
    notes = sorted(
        {
            " ".join(str(w.message).split())[:300]
            for w in caught
            if "cach" in str(w.message).lower() and type(w.message).__module__.startswith("numba")
        }
    )
    return WarmResult(item, seconds, len(counter.compiled), compile_time, status, notes)


def warm(
    items: Iterable[Item] | None = None,
    engines: Iterable[str] | None = None,
    report: Callable[[str, str], None] | None = None,
) -> list[WarmResult]:
    """Warm ``items`` (those of ``engines`` only, if given). ``report(start, end)`` is called
    before each item with the item's name and ``end = ""``, after it with ``start = ""`` and
    the outcome: together one line per item."""
    items = ITEMS if items is None else items
    wanted = None if engines is None else set(engines)
    chosen = [
        it
        for it in items
        if wanted is None
        or it.engine in wanted
        or (it.engine == "takeda" and "compliance" in wanted)
    ]
    out = []
    for k, item in enumerate(chosen, 1):
        if report is not None:
            report(f"[{k}/{len(chosen)}] {item.engine}: {item.label}: ", "")
        res = warm_item(item)
        out.append(res)
        if report is not None:
            what = (
                f"compiled {res.compiled} kernel{'s' * (res.compiled != 1)}"
                if res.compiled
                else "loaded from the cache"
            )
            report("", f"{res.seconds:.2f} s ({what}; {res.status})")
    return out

"""The engine registry: engines by name (scipy ``METHODS`` style).

:data:`ENGINES` maps a name to ``"module:Class"``; the module is imported on first use, so
OpenSees or numba load only when their engine runs. The contract every engine fulfils is in
:mod:`deckpound.models.engine_contract`. Adding an engine: write its module (a subclass of
:class:`~deckpound.models.engine_contract.Engine`) and add one line here — or, from outside the
package, call :func:`register`.

Everything that lists engines (CLI choices, the comparison layer, studies, figures, bench,
stress) reads them from here; the reference engine of a comparison is a parameter whose
default is :data:`DEFAULT_REFERENCE`.
"""

from __future__ import annotations

import importlib
from typing import Any

from deckpound.models.engine_contract import Engine
from deckpound.models.errors import SceneError

__all__ = [
    "DEFAULT_REFERENCE",
    "ENGINES",
    "engine_names",
    "engine_style",
    "get_engine",
    "register",
    "run_engine",
]

ENGINES: dict[str, str] = {
    "opensees": "deckpound.opensees_build.engine:OpenSeesEngine",
    "compliance": "deckpound.analytic.compliance.engine:ComplianceEngine",
    "nonsmooth": "deckpound.analytic.nonsmooth.engine:NonsmoothEngine",
}
#: The engine other engines are compared against unless a comparison names another.
DEFAULT_REFERENCE = "opensees"

_INSTANCES: dict[str, Engine] = {}


def engine_names() -> tuple[str, ...]:
    """Registered engine names, in registration order."""
    return tuple(ENGINES)


def register(name: str, engine: str | type[Engine]) -> None:
    """Register an engine class (or ``"module:Class"`` path) under ``name``."""
    if isinstance(engine, type):
        if not issubclass(engine, Engine):
            raise TypeError(f"{engine!r} is not an Engine subclass")
        ENGINES[name] = f"{engine.__module__}:{engine.__qualname__}"
        _INSTANCES[name] = engine()
    else:
        ENGINES[name] = engine
        _INSTANCES.pop(name, None)


def unregister(name: str) -> None:
    """Remove an engine (tests register temporary engines)."""
    ENGINES.pop(name, None)
    _INSTANCES.pop(name, None)


def get_engine(name: str) -> Engine:
    """The engine registered as ``name`` (unknown names list the valid ones)."""
    if name not in ENGINES:
        raise SceneError("engine", f"unknown engine {name!r}; valid engines: {', '.join(ENGINES)}")
    if name not in _INSTANCES:
        from deckpound.analytic.kernel_load import install

        install()  # cached numba kernels load without numba's full set-up (_kernel_load)
        module, cls = ENGINES[name].split(":")
        _INSTANCES[name] = getattr(importlib.import_module(module), cls)()
    return _INSTANCES[name]


def engine_style(name: str) -> dict[str, Any]:
    """Figure line style of an engine (a neutral one for unknown labels such as ``measured``)."""
    if name == "measured":
        return dict(color="#777777", linestyle="-.", linewidth=1.0, label="measured")
    if name in ENGINES:
        return dict(get_engine(name).style)
    return dict(color="#555555", linestyle="-", label=name)


def run_engine(name: str, scene, motion=None, *, settings=None, **kwargs):
    """Run engine ``name`` on ``scene``: :meth:`~deckpound.models.engine_contract.Engine.run`
    of the registered engine (its result carries the full scene in its metadata)."""
    return get_engine(name).run(scene, settings, motion, **kwargs)

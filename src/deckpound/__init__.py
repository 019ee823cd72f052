"""deckpound: seismic deck-abutment pounding of bridges, simulated three ways from one scene.

The front door for scripts and notebooks::

    import deckpound as dp

    scene = dp.load_scene("saiidi-4span", set={"contact.friction": 0.2,
                                                "contact.friction_mode": "contact2d"})
    res = dp.run(scene, engine="compliance")          # a frozen, labelled Result
    many = dp.run_batch([scene, scene2], engine="compliance", workers=2)  # kernels loaded once
    res.to_frame()                                    # pandas, time as index, units in attrs
    cmp = dp.compare(scene, engines=["opensees", "compliance", "nonsmooth"])
    cmp.metrics                                       # peaks, NRMSE, ... against the reference
    fig = cmp.plot("histories")                       # a matplotlib figure; res.plot() too
    stiff = scene.replace({"contact.stiffness": 2e6, "bents[1].y.beta": 0.3})  # --set paths

Names are imported on first use, so ``import deckpound`` stays cheap (numba, OpenSees,
matplotlib and pandas load only when something needs them).
"""

from __future__ import annotations

import importlib
import types

from deckpound.models.version import VERSION as __version__

__all__ = [
    "Comparison",
    "Result",
    "Scene",
    "__version__",
    "available_engines",
    "builtin_scenes",
    "compare",
    "get_engine",
    "load_scene",
    "plan_of",
    "register_engine",
    "run",
    "run_batch",
    "run_many",
    "support_motion",
]

_LAZY = {
    "Result": ("deckpound.models.result", "Result"),
    "Scene": ("deckpound.models.scene", "Scene"),
    "plan_of": ("deckpound.models.plan", "plan_of"),
    "support_motion": ("deckpound.models.excitation", "support_motion"),
    "get_engine": ("deckpound.compare.engines", "get_engine"),
    "register_engine": ("deckpound.compare.engines", "register"),
    "Comparison": ("deckpound.api", "Comparison"),
    "load_scene": ("deckpound.api", "load_scene"),
    "run": ("deckpound.api", "run"),
    "run_batch": ("deckpound.api", "run_batch"),
    "run_many": ("deckpound.api", "run_many"),
    "available_engines": ("deckpound.api", "available_engines"),
    "builtin_scenes": ("deckpound.api", "builtin_scenes"),
}


class _CallableModule(types.ModuleType):
    """``deckpound.compare`` is both the package :mod:`deckpound.compare` and the function
    :func:`deckpound.api.compare`: importing a submodule binds the package to the name, so the
    package itself forwards a call to the function (both spellings mean the same thing,
    whatever was imported first)."""

    def __call__(self, *args, **kwargs):
        from deckpound.api import compare

        return compare(*args, **kwargs)


importlib.import_module("deckpound.compare").__class__ = _CallableModule


def __getattr__(name: str):
    if name in _LAZY:
        module, attr = _LAZY[name]
        value = getattr(importlib.import_module(module), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'deckpound' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))

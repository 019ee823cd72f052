"""deckpound.compare: alignment, metrics, cases and their cache, studies, figures, report.

The package is also the front door's ``dp.compare``: ``import deckpound as dp;
dp.compare(scene, engines=[...])`` calls :func:`deckpound.api.compare`. Once this package is
imported, Python binds ``deckpound.compare`` to it rather than to that function, so the package
module itself is made callable (its class gains a ``__call__`` that forwards to the function):
both spellings then mean the same thing, whatever was imported first.
"""

import sys
import types


class _CallableModule(types.ModuleType):
    def __call__(self, *args, **kwargs):
        from deckpound.api import compare

        return compare(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule

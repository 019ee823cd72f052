"""deckpound.compare: alignment, metrics, cases and their cache, studies, figures, report.

The layer above the engines: it runs them (the engine registry, :mod:`.engines`), reads their
results and compares them. The front door's ``dp.compare`` (a function of :mod:`deckpound.api`)
shares this package's name; :mod:`deckpound` makes the package callable as that function.
"""

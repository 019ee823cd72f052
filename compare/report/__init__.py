"""The report of ``deckpound paper`` and every file the comparison layer draws or writes: the
main job (:mod:`.paper`), its sections, sentences and rendering, the figures and their style,
the reuse of unchanged figures, and the ParaView export."""

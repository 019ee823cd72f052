"""Cross-verification of the compliance clone against OpenSees (``deckpound verify``): the
Newmark clone on one case (:mod:`.clone`), over the matrix of modelling choices
(:mod:`.matrix`), and the Takeda (Hysteretic) clone (:mod:`.takeda`)."""

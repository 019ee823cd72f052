"""deckpound.compare."""

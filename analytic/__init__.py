"""deckpound.analytic."""

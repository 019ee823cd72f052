"""deckpound.opensees_build."""

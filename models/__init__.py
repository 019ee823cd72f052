"""deckpound.models."""

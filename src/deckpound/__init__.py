"""deckpound: seismic deck-abutment pounding of bridges, simulated three ways from one scene."""

__version__ = "0.1.0"

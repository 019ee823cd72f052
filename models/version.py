"""The version of deckpound: written into every result's provenance, report and exported script
(kept equal to ``pyproject.toml``'s by ``tests/test_packaging.py``)."""

VERSION = "0.2.0"

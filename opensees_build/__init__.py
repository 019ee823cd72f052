"""deckpound.opensees_build: the OpenSees engine, its model builder and the Tcl/Python exports."""

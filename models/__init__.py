"""deckpound.models: the engine-independent description (scene, plan model, excitation, result)."""

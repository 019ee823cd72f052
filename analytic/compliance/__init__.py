"""The compliance engine: penalty (compliant) contact on the plan model, integrated by the
Newmark–Newton loop (:mod:`.newmark`, the clone of the OpenSees model) or the adaptive
Dormand–Prince reference (:mod:`.adaptive`); the engine itself is :mod:`.engine`."""

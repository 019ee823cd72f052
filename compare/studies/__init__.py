"""Studies of a scene: the paper's sensitivity studies (:mod:`.sensitivity`), damping, skew,
record-to-record variability, IDA and fragility, the contact step and the impact law, and the
experiment's test sequence."""

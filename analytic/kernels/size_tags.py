"""Size tags: a model's DOF and corner counts as the compiled step loops see them.

The kernels take their counts from the length of a tag (``len(tag)``), never from a global.
For the one-body deck (:data:`ONE_BODY_DOF` DOF, :data:`ONE_BODY_CORNERS` corners) the tag is a
tuple, whose length is part of its numba type: the counts are compile-time constants and LLVM
unrolls the loops over them, which is what the benchmark runs at. Any other model — a deck of
several segments, whatever N — gets int64 arrays: one compiled specialisation of each loop then
serves every N (compiling a loop per N would cost a minute or more per integrator for each new
bridge), at the price of loops with run-time bounds.
"""

from __future__ import annotations

import numpy as np

from deckpound.models.plan import N_CORNERS, N_DOF

__all__ = ["ONE_BODY_CORNERS", "ONE_BODY_DOF", "corner_slots", "dof_slots", "index_tag"]

ONE_BODY_DOF = N_DOF
ONE_BODY_CORNERS = N_CORNERS


def _slots(n: int, constant: int) -> tuple | np.ndarray:
    n = int(n)
    return tuple(range(n)) if n == constant else np.arange(n, dtype=np.int64)


def dof_slots(n_dof: int) -> tuple | np.ndarray:
    """0 … n_dof − 1: a tuple for the one-body deck's DOF, else an int64 array."""
    return _slots(n_dof, ONE_BODY_DOF)


def corner_slots(n_corners: int) -> tuple | np.ndarray:
    """0 … n_corners − 1: a tuple for the one-body deck's corners, else an int64 array."""
    return _slots(n_corners, ONE_BODY_CORNERS)


def index_tag(values, static: bool) -> tuple | np.ndarray:
    """Indices the kernels read (e.g. the DOF of each displacement column): a tuple when the
    model's tags are tuples (``static``), else an int64 array."""
    return tuple(int(v) for v in values) if static else np.asarray(values, dtype=np.int64)

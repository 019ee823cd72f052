"""A state that stops being finite ends an analytic run as a failure, at the step it happens.

The kernels divide with numba's ``numpy`` error model (``analytic/_jit.py``): no divisor is
tested for zero ahead of a division, so a non-finite number in the state is not caught where it
is made; the step loops' finiteness test of the Newton increment (of the state, for the
adaptive integrator and the nonsmooth engine) catches it at the step it first reaches. A NaN
in the support record at one sample is such a number: no exception may escape the kernel, and
the run must end as ``failed`` with "non-finite state" at that sample's time.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from deckpound.compare.engines import get_engine
from deckpound.models.excitation import support_motion
from deckpound.models.scene_io import load_scene

#: the record's sample made NaN (the record's step is 0.005 s: t = 1 s)
SAMPLE = 200


@pytest.mark.parametrize(
    ("engine", "overrides"),
    [
        ("compliance", []),
        ("compliance", ["compliance.integrator=adaptive"]),
        ("nonsmooth", []),
    ],
    ids=["newmark", "adaptive", "nonsmooth"],
)
def test_a_nan_in_the_record_fails_the_run_at_its_time(engine, overrides):
    scene = load_scene("saiidi-4span", ["excitation.duration=2", "run.duration=2", *overrides])
    motion = support_motion(scene)
    disp = {c: np.array(v) for c, v in motion.disp.items()}
    for column in disp.values():
        column[SAMPLE] = np.nan
    t_nan = float(motion.t[SAMPLE])
    result = get_engine(engine).run(scene, motion=dataclasses.replace(motion, disp=disp))
    assert result.meta["status"] == "failed"
    assert "non-finite state" in result.meta["message"]
    # it stops in the record step that ends at the NaN sample (where the interpolation first
    # reads it), at the latest at the sample
    failed_at = result.meta["failed_time"]
    assert t_nan - float(motion.t[1]) - 1e-9 <= failed_at <= t_nan + 1e-9, failed_at

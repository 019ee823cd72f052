"""The step loops take their peaks from their state, without building a row (issue 33, item 1).

:func:`track_state` reads every column of the peak layout from the state a loop commits;
:func:`track_step` takes them from a row that ``store_standard`` wrote. Both must keep the same
statistics bit for bit: the peaks and their times, the deepest gaps, the closures, the largest
gaps and the unseating.
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic.kernels.peaks import new_peaks, track_state, track_step
from deckpound.analytic.kernels.system import pack_system, row_layout, store_standard
from deckpound.models.damping import damping_model
from deckpound.models.plan import plan_of
from deckpound.models.scene_io import load_scene

STATISTICS = (
    "value",
    "time",
    "inside",
    "closures",
    "gap_open",
    "gap_open_time",
    "gap_start",
    "unseat",
    "unseat_time",
)


def test_state_and_row_give_the_same_statistics_bit_for_bit():
    sc = load_scene("saiidi-4span")
    plan = plan_of(sc)
    ps = pack_system(plan, damping_model(sc, plan))
    layout = row_layout(plan)
    nc, nd, ns, nch = len(plan.corners), plan.mass.shape[0], ps.n_springs, len(ps.channels)
    support = np.array([np.inf, 0.03, np.inf, np.inf])  # corner c2 can unseat
    by_state = new_peaks(layout, ps.channels, plan.bent_names, support)
    by_row = new_peaks(layout, ps.channels, plan.bent_names, support)
    rng = np.random.default_rng(33)
    g0 = np.full(nc, 0.0127)
    unseated_at = []
    for step in range(400):
        t = 5e-4 * step
        u, v = rng.normal(scale=0.01, size=nd), rng.normal(scale=0.1, size=nd)
        # gaps that close and reopen, with forces while closed (and a touch with g > 0)
        g = g0 + rng.normal(scale=0.01, size=nc) + 1e-4 * step * np.array([0, 1, 0, 0])
        fn = np.where(g <= 0.0, -1e6 * g, 0.0)
        fn[3] = 5.0 if step % 7 == 0 else fn[3]
        ft = rng.normal(size=nc) * (fn > 0)
        fs, d = rng.normal(size=ns), rng.normal(scale=0.01, size=ns)
        ug = rng.normal(scale=0.01, size=nch)
        a = track_state(by_state, t, u, v, g, fn, ft, fs, ug, d)
        store_standard(by_row.row, layout, t, u, v, g, fn, ft, fs)
        b = track_step(by_row, t, u, ug, d)
        assert a == b
        if a:
            unseated_at.append(step)
    assert unseated_at and by_state.unseat[0] == 2  # the scenario reaches every branch
    assert by_state.closures.sum() > 10
    for name in STATISTICS:
        x, y = getattr(by_state, name), getattr(by_row, name)
        assert np.array_equal(x, y), name
        assert x.tobytes() == y.tobytes(), name  # the signs of zeros too

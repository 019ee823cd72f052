"""The adaptive integrator reaches the converged Newmark answer through yielding because it
commits the Takeda state densely once a spring has yielded (``compliance.commit_step``): the
Hysteretic material itself depends on commit spacing."""

from __future__ import annotations

import numpy as np

from deckpound.analytic.kernels.hysteretic import HystereticMaterial
from deckpound.compare.engines import run_engine
from deckpound.models.excitation import support_motion
from deckpound.models.plan import takeda_hysteretic_args
from deckpound.models.scene_io import load_scene
from deckpound.models.sequence import bent_deformations

YIELDING = ["excitation.duration=6.0", "seats[0].gap=1.0", "seats[1].gap=1.0"]


def test_adaptive_with_dense_commits_matches_converged_newmark():
    newmark = run_engine(
        "compliance", load_scene("saiidi-4span", YIELDING + ["compliance.dt=2e-05"])
    )
    adaptive = run_engine(
        "compliance",
        load_scene(
            "saiidi-4span",
            YIELDING
            + ["compliance.integrator=adaptive", "compliance.rtol=1e-08", "compliance.atol=1e-11"],
        ),
    )
    assert max(np.max(np.abs(newmark[f"bent{i}_fy"])) for i in (1, 2, 3)) > 120.0  # yielding
    # commits 1e-4 s apart vs 2e-5 s: the Hysteretic commit-spacing effect is ~2e-5 of the peak
    for col in ("deck_theta", "deck_y_abs", "bent2_fy"):
        peak = np.max(np.abs(newmark[col]))
        assert np.max(np.abs(adaptive[col] - newmark[col])) < 1e-4 * peak, col


def test_hysteretic_depends_on_commit_spacing():
    """Replaying one bent's history with sparse commits changes the force: the converged model
    answer is the commit-every-small-step limit (why the bench reference is fine Newmark)."""
    scene = load_scene("saiidi-4span", YIELDING + ["compliance.dt=2e-05", "run.output_dt=2e-05"])
    r = run_engine("compliance", scene)
    d = bent_deformations(scene, r, support_motion(scene))[:, 1, 1]
    args = takeda_hysteretic_args(scene.bents[1].y)
    dense, sparse = HystereticMaterial(*args), HystereticMaterial(*args)
    inc = np.diff(d, append=d[-1])
    f_dense, f_sparse = np.empty_like(d), np.empty_like(d)
    for i, x in enumerate(d):
        dense.set_trial_strain(x)
        f_dense[i] = dense.stress
        dense.commit()
        sparse.set_trial_strain(x)
        f_sparse[i] = sparse.stress
        if i % 250 == 0 or (i + 1 < len(d) and inc[i] * inc[i + 1] < 0):
            sparse.commit()
    np.testing.assert_array_equal(f_dense, r["bent2_fy"])  # the engine commits every step
    assert np.max(np.abs(f_sparse - f_dense)) > 1e-3 * np.max(np.abs(f_dense))

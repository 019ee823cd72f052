"""The Newmark loop reuses the effective tangent's factors in contact too (issue 33, item 1).

The factors held in LU are reused while their key stays: the step, the spring tangents and,
for linear contact kinematics, the evaluated corners and their law derivatives (the contact
rows W_N, W_T are constant there). The same key is the same matrix bit for bit, so a reused
factor is the one a refactorisation would give: every result column, the peaks and the counts
equal those of a run that factorises at every Newton iteration (``_skips={"factor_reuse":
False}``, the engine's measurement switch, not a scene option).
"""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.analytic.compliance.engine import run_compliance
from deckpound.api import load_scene

#: 4 s of the benchmark: the deck pounds both abutments and the bents yield
SHORT = ["excitation.duration=4"]


def _pair(scene_name: str, overrides: list[str]):
    sc = load_scene(scene_name, [*SHORT, *overrides])
    return run_compliance(sc), run_compliance(sc, _skips={"factor_reuse": False})


def _assert_same_results(reused, fresh):
    assert reused.meta["status"] == fresh.meta["status"] == "success"
    assert list(reused.columns) == list(fresh.columns)
    for name, col in fresh.columns.items():
        assert np.array_equal(reused.columns[name], col), name
    for key in ("peaks", "gap_closures_per_corner", "max_penetration", "newton_iterations"):
        assert reused.meta[key] == fresh.meta[key], key


@pytest.mark.parametrize(
    ("overrides", "reuses_in_contact"),
    [
        ([], True),  # linear law: constant ∂λ/∂g while the closed set stays
        (["contact.law=hertz"], True),  # ∂λ/∂g changes with g: reused only where it does not
        (["contact.friction=0.2", "contact.friction_mode=stick"], True),
        (["contact.law=hertzdamp"], False),  # ∂λ/∂ġ changes at every iterate
    ],
    ids=["linear", "hertz", "stick", "hertzdamp"],
)
def test_factors_reused_in_contact_give_the_refactorised_answer(overrides, reuses_in_contact):
    reused, fresh = _pair("saiidi-4span", overrides)
    assert sum(reused.meta["gap_closures_per_corner"].values()) > 0  # it pounds
    _assert_same_results(reused, fresh)
    meta, newton = reused.meta, reused.meta["newton_iterations"]
    # one solve per Newton iteration, each with fresh or reused factors
    assert meta["factorisations"] + meta["elastic_factor_reuses"] == newton
    assert fresh.meta["factorisations"] == newton and fresh.meta["elastic_factor_reuses"] == 0
    assert meta["factorisations"] < newton
    assert (meta["contact_factor_reuses"] > 0) == reuses_in_contact
    assert fresh.meta["contact_factor_reuses"] == 0


def test_nonlinear_kinematics_refactorise_in_contact():
    """W_N and the geometric term λ_N ∂²g/∂u² change with u: no factors with contact terms are
    reused, and the answer is the refactorised one."""
    reused, fresh = _pair("skew-30", ["contact.geometry=nonlinear"])
    assert sum(reused.meta["gap_closures_per_corner"].values()) > 0
    _assert_same_results(reused, fresh)
    assert reused.meta["contact_factor_reuses"] == 0
    assert reused.meta["factorisations"] < reused.meta["newton_iterations"]

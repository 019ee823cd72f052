"""The compliance engine's packed model kept across runs (deckpound.analytic.compliance.pack):
a run from a kept model gives the bits of a run packed afresh, every run owns its arrays, and
the key separates what the model depends on."""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.analytic.compliance import pack
from deckpound.analytic.compliance.engine import run_compliance
from deckpound.models.plan import plan_of
from deckpound.models.scene_io import load_scene

SCENE = "models/scenes/saiidi-4span.toml"


@pytest.fixture
def scene():
    # short records; the bents damped on their current tangent, which the loop writes into
    # the packed system's arrays at every step (and the contact laws Kelvin-Voigt, whose
    # damping the pack computes from the plan)
    return load_scene(SCENE).replace(
        {
            "excitation.duration": 3.0,
            "run.duration": 3.0,
            "excitation.pga": 0.8,
            "damping.stiffness": "current",
            "contact.law": "kelvin-voigt",
        }
    )


def _arrays(ps, cp, corners) -> list[np.ndarray]:
    out = [v for v in ps.arrays._asdict().values() if isinstance(v, np.ndarray)]
    return out + [ps.C, ps.K0, cp, corners]


def _same_bits(a, b) -> bool:
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def test_a_run_from_the_kept_model_gives_the_bits_of_a_fresh_pack(scene, monkeypatch):
    first = scene.replace({"excitation.seed": 11})
    second = scene.replace({"excitation.seed": 12})
    packed = []
    real = pack.system.pack_system
    monkeypatch.setattr(pack.system, "pack_system", lambda *a: packed.append(1) or real(*a))
    run_compliance(first)  # packs the model (unless an earlier test did) and keeps it
    packed.clear()
    kept = run_compliance(second)
    assert packed == []
    monkeypatch.setattr(pack, "MODELS_KEPT", 0)  # none kept: every run packs afresh
    fresh = run_compliance(second)
    assert packed == [1]
    assert kept.meta["status"] == fresh.meta["status"] == "success"
    assert kept.meta["gap_closures"] == fresh.meta["gap_closures"] > 0
    assert set(kept.columns) == set(fresh.columns)
    for name in fresh.columns:
        assert _same_bits(kept[name], fresh[name]), name
    for c in ("deck_theta", "deck_y_rel", "fn_c1"):
        assert kept.peak(c) == fresh.peak(c) and kept.peak_time(c) == fresh.peak_time(c)
    assert kept.meta["newton_iterations"] == fresh.meta["newton_iterations"]


def test_every_run_owns_its_arrays(scene):
    plan = plan_of(scene)
    one = _arrays(*pack.packed_model(plan, scene))
    two = _arrays(*pack.packed_model(plan, scene))
    for a, b in zip(one, two, strict=True):
        assert _same_bits(a, b)
        assert a.flags.writeable and not np.shares_memory(a, b)
    one[0][:] = -1.0  # a run that writes into its arrays leaves the next run's alone
    three = _arrays(*pack.packed_model(plan, scene))
    assert _same_bits(three[0], two[0])


def test_the_model_part_reads_nothing_of_the_excitation(scene, monkeypatch):
    # the key leaves the excitation out (NOT_MODEL): scenes that differ only there pack the
    # same arrays when packed afresh
    monkeypatch.setattr(pack, "MODELS_KEPT", 0)
    plan = plan_of(scene)
    packed = [
        _arrays(*pack.packed_model(plan, sc))
        for sc in (
            scene,
            scene.replace({"excitation.seed": 99, "excitation.pga": 0.3, "name": "other"}),
            scene.replace({"excitation.kind": "pulse"}),
            scene.replace({"excitation.kind": "none"}),
        )
    ]
    for other in packed[1:]:
        for a, b in zip(packed[0], other, strict=True):
            assert _same_bits(a, b)
    assert "excitation" in pack.NOT_MODEL


def test_a_plan_of_other_gaps_or_another_contact_is_another_model(scene):
    plan = plan_of(scene)
    wide = plan_of(scene, gaps=(0.05, 0.06))
    _, cp, corners = pack.packed_model(plan, scene)
    _, _, corners_wide = pack.packed_model(wide, scene)
    assert not np.array_equal(corners, corners_wide)
    stiffer = scene.replace({"contact.stiffness": 2.0 * scene.contact.stiffness})
    _, cp_stiff, _ = pack.packed_model(plan_of(stiffer), stiffer)
    assert not np.array_equal(cp, cp_stiff)
    assert pack.model_key(plan, scene, False) != pack.model_key(plan, scene, True)


def test_the_most_recent_models_are_kept(scene, monkeypatch):
    packed = []
    real = pack.system.pack_system
    monkeypatch.setattr(
        pack.system, "pack_system", lambda *a: packed.append(1) or real(*a), raising=True
    )
    monkeypatch.setattr(pack, "MODELS_KEPT", 2)
    models = [scene.replace({"contact.stiffness": k * 1e5}) for k in (1, 2, 3)]
    for sc in [*models, models[0], models[2]]:
        pack.packed_model(plan_of(sc), sc)
    # 1, 2, 3 packed (1 dropped), 1 packed again (2 dropped), 3 still kept
    assert len(packed) == 4

"""What both compliance integrators pack before their loops (:mod:`.newmark`, :mod:`.adaptive`).

:func:`pack_run` turns a plan, a scene and a support motion into the kernels' arrays once per
run: the system (:func:`deckpound.analytic.kernels.system.pack_system`), the support record at its own
samples, the per-corner contact-law parameters (their kernel branches checked), the corner
table and the virgin corner states.

The model part (system, contact parameters, corner table) does not depend on the support
motion, and a sweep runs one bridge under many records: :func:`packed_model` packs it at the
first run of a model (:func:`model_key`) in a process and hands every run its own copies of the
arrays (the loops write into some of them, and the engine sets Newton's contact switch in the
contact parameters). ``tests/test_compliance_pack.py`` checks that a run from the kept model
gives the bits of a run packed afresh.
"""

from __future__ import annotations

import dataclasses
from collections import OrderedDict

import numpy as np

from deckpound.analytic.kernels import contact_laws as cl
from deckpound.analytic.kernels import system
from deckpound.analytic.kernels.contact_law_checks import check_kernel_branches
from deckpound.analytic.kernels.kinematics import K_G0, pack_corners
from deckpound.analytic.kernels.support_motion import support_record
from deckpound.models.damping import damping_model
from deckpound.models.motion import SupportMotion
from deckpound.models.plan import Plan
from deckpound.models.scene import Scene

__all__ = ["MODELS_KEPT", "NOT_MODEL", "model_key", "pack_run", "packed_model"]

#: how many packed models a process keeps (the most recently used)
MODELS_KEPT = 8

#: scene fields the model part never reads: the support motion and the texts
NOT_MODEL = frozenset({"excitation", "notes", "name", "description"})

_KEPT: OrderedDict = OrderedDict()


def pack_run(plan: Plan, scene: Scene, motion: SupportMotion, *, kv_clip: bool = False):
    """Everything a compliance run needs, packed once: (ps, (tb, D, V), cp, cs, corners).

    The support record stays at its own samples (tb, D, V): memory independent of the number
    of steps (the kernels interpolate it, see :mod:`deckpound.analytic.kernels.support_motion`).
    ``kv_clip``: clip the Kelvin–Voigt force at zero (:func:`.contact_laws.pack_contact`).
    """
    ps, cp, corners = packed_model(plan, scene, kv_clip=kv_clip)
    record = support_record(motion, ps.channels)
    cs = cl.new_contact_state(corners[:, K_G0])
    return ps, record, cp, cs, corners


def model_key(plan: Plan, scene: Scene, kv_clip: bool) -> tuple:
    """What the model part is a function of: every scene field but :data:`NOT_MODEL` (frozen
    records, compared by value), the plan's content (a caller may pass a plan with other gaps
    than the scene's) and ``kv_clip``."""
    fields = tuple(
        getattr(scene, f.name) for f in dataclasses.fields(scene) if f.name not in NOT_MODEL
    )
    content = tuple(
        plan.mass.tobytes() if f.name == "mass" else getattr(plan, f.name)
        for f in dataclasses.fields(plan)
    )
    return fields, content, bool(kv_clip)


def packed_model(plan: Plan, scene: Scene, *, kv_clip: bool = False):
    """(ps, cp, corners): the system, the contact parameters and the corner table of the
    model, packed at its first run in this process (the :data:`MODELS_KEPT` most recent
    models are kept) and copied for every run: fresh, writable arrays with the same bits."""
    key = model_key(plan, scene, kv_clip)
    _keep_at_most(MODELS_KEPT)  # the bound, also where it was lowered since the last run
    try:
        kept = _KEPT.get(key)
    except TypeError:  # a field that cannot be hashed: packed afresh, not kept
        key, kept = None, None
    if kept is None:
        kept = _pack_model(plan, scene, kv_clip)
        if key is not None:
            _KEPT[key] = kept
            _keep_at_most(MODELS_KEPT)
    else:
        _KEPT.move_to_end(key)
    ps, cp, corners = kept
    arrays = ps.arrays._replace(
        **{k: v.copy() for k, v in ps.arrays._asdict().items() if isinstance(v, np.ndarray)}
    )
    ps = dataclasses.replace(ps, arrays=arrays, C=ps.C.copy(), K0=ps.K0.copy())
    return ps, cp.copy(), corners.copy()


def _keep_at_most(n: int) -> None:
    while len(_KEPT) > n:  # the least recently used first
        _KEPT.popitem(last=False)


def _pack_model(plan: Plan, scene: Scene, kv_clip: bool):
    ps = system.pack_system(plan, damping_model(scene, plan))
    cp = cl.pack_contact(scene, plan=plan, kv_clip=kv_clip)
    check_kernel_branches(cp)
    return ps, cp, pack_corners(plan)

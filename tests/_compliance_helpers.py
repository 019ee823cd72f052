"""Helpers of the compliance-engine tests: reduced scenes and analytic support motions."""

from __future__ import annotations

import dataclasses

import numpy as np

from deckpound.models import plan
from deckpound.models.motion import SupportMotion
from deckpound.models.scene import TakedaSpring
from deckpound.models.scene_io import load_scene


def elastic_spring(k: float) -> TakedaSpring:
    """A Takeda spring that never yields (huge yield force)."""
    fy = 1.0e6
    return TakedaSpring(stiffness=k, yield_force=fy, ultimate_displacement=10.0 * fy / k + 1.0)


def motion_from(scene, t, disp: dict, vel: dict) -> SupportMotion:
    """Motion with the given channel histories (missing channels at rest)."""
    z = np.zeros_like(t)
    chans = plan.support_channels(scene)
    return SupportMotion(
        t=t, disp={c: disp.get(c, z) for c in chans}, vel={c: vel.get(c, z) for c in chans}
    )


def rest_motion(scene, duration: float) -> SupportMotion:
    return motion_from(scene, np.array([0.0, duration]), {}, {})


def base_scene(*overrides: str):
    return load_scene("saiidi-4span", list(overrides))


def with_bents(scene, kx=None, ky=None, elastic=True):
    bents = []
    for b in scene.bents:
        x = elastic_spring(kx if kx is not None else b.x.stiffness) if elastic else b.x
        y = elastic_spring(ky if ky is not None else b.y.stiffness) if elastic else b.y
        bents.append(dataclasses.replace(b, x=x, y=y))
    return scene.replace(bents=tuple(bents))


def with_seats(scene, **changes):
    return scene.replace(seats=tuple(dataclasses.replace(s, **changes) for s in scene.seats))


def with_contact(scene, **changes):
    return scene.replace(contact=dataclasses.replace(scene.contact, **changes))


def with_compliance(scene, **changes):
    return scene.replace(compliance=dataclasses.replace(scene.compliance, **changes))


def with_run(scene, **changes):
    return scene.replace(run=dataclasses.replace(scene.run, **changes))

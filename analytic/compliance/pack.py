"""What both compliance integrators pack before their loops (:mod:`.newmark`, :mod:`.adaptive`).

:func:`pack_run` turns a plan, a scene and a support motion into the kernels' arrays once per
run: the system (:func:`deckpound.analytic.kernels.system.pack_system`), the support record at its own
samples, the per-corner contact-law parameters (their kernel branches checked), the corner
table and the virgin corner states.
"""

from __future__ import annotations

from deckpound.analytic.kernels import contact_laws as cl
from deckpound.analytic.kernels import system
from deckpound.analytic.kernels.contact_law_checks import check_kernel_branches
from deckpound.analytic.kernels.kinematics import K_G0, pack_corners
from deckpound.analytic.kernels.support_motion import support_record
from deckpound.models.damping import damping_model
from deckpound.models.motion import SupportMotion
from deckpound.models.plan import Plan
from deckpound.models.scene import Scene

__all__ = ["pack_run"]


def pack_run(plan: Plan, scene: Scene, motion: SupportMotion, *, kv_clip: bool = False):
    """Everything a compliance run needs, packed once: (ps, (tb, D, V), cp, cs, corners).

    The support record stays at its own samples (tb, D, V): memory independent of the number
    of steps (the kernels interpolate it, see :mod:`deckpound.analytic.kernels.support_motion`).
    ``kv_clip``: clip the Kelvin–Voigt force at zero (:func:`.contact_laws.pack_contact`).
    """
    ps = system.pack_system(plan, damping_model(scene, plan))
    record = support_record(motion, ps.channels)
    cp = cl.pack_contact(scene, plan=plan, kv_clip=kv_clip)
    check_kernel_branches(cp)
    corners = pack_corners(plan)
    cs = cl.new_contact_state(corners[:, K_G0])
    return ps, record, cp, cs, corners

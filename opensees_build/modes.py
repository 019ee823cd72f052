"""Natural modes of the contact-free OpenSees model (``eigen -fullGenLapack``).

The model is built without gap elements and with the supports fixed; the mass sits on the DOF
of the analytic model only (seat x, θ; each deck segment's centre x, y, θ: 7 for a one-segment
deck), so the default ARPACK solver fails and the dense generalised solver is used (massless
DOFs give infinite eigenvalues, which come after the finite ones). No analysis is defined: eigen runs on the bare domain, then
``wipeAnalysis`` (eigen together with MultipleSupport has returned zeros in 3.7).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from deckpound.models.plan import plan_of
from deckpound.models.scene import Scene

from .model import build_model
from .ops import OpsSession


@dataclass(frozen=True)
class OpenSeesModes:
    """Periods [s] (ascending) and mode shapes (n_dof × n, rows in the plan's DOF order,
    ``Plan.dof_names``, columns mass-normalised with the sign making the largest entry
    positive)."""

    periods: np.ndarray
    shapes: np.ndarray

    @property
    def omega(self) -> np.ndarray:
        return 2.0 * np.pi / self.periods

    def __iter__(self):
        """Unpacks as ``periods, shapes = opensees_modes(scene)``."""
        return iter((self.periods, self.shapes))


def opensees_modes(scene: Scene, n: int | None = None) -> OpenSeesModes:
    """The first ``n`` (≤ the plan's DOF count, default all of them: 7 for a one-segment deck)
    natural modes of the contact-free model in ``scene.opensees.mode``."""
    plan = plan_of(scene)
    n_dof = plan.n_dof
    if n is None:
        n = n_dof
    if not 1 <= n <= n_dof:
        raise ValueError(f"n must be in [1, {n_dof}], got {n}")
    with OpsSession() as ops:
        info = build_model(ops, scene, None, gaps=False, supports="fixed", plan=plan)
        raw = ops.raw
        lam = np.array(raw.eigen("-fullGenLapack", n_dof), dtype=float)[:n]
        where = [
            (info.seats[0], 1),
            (info.seats[0], 3),
            (info.seats[1], 1),
            (info.seats[1], 3),
        ] + [(body, dof) for body in info.bodies for dof in (1, 2, 3)]
        phi = np.array(
            [[raw.nodeEigenvector(node, m + 1, dof) for m in range(n)] for node, dof in where]
        )
        raw.wipeAnalysis()
    masses = plan.mass  # the plan model's diagonal mass, in its DOF order
    norm = np.sqrt(np.einsum("im,i,im->m", phi, masses, phi))
    phi = phi / norm
    sign = np.sign(phi[np.abs(phi).argmax(axis=0), np.arange(n)])
    phi = phi * sign
    return OpenSeesModes(periods=2.0 * np.pi / np.sqrt(lam), shapes=phi)

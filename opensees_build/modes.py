"""Natural modes of the contact-free OpenSees model (``eigen -fullGenLapack``).

The model is built without gap elements and with the supports fixed; the mass sits on the 7
DOF of the analytic model only (deck centre x, y, θ; seat x, θ), so the default ARPACK solver
fails and the dense generalised solver is used (massless DOFs give infinite eigenvalues, which
come after the 7 finite ones). No analysis is defined: eigen runs on the bare domain, then
``wipeAnalysis`` (eigen together with MultipleSupport has returned zeros in 3.7).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from deckpound.models.plan import DOF_NAMES, N_DOF, plan_of
from deckpound.models.scene import Scene

from .model import build_model
from .ops import OpsSession


@dataclass(frozen=True)
class OpenSeesModes:
    """Periods [s] (ascending) and mode shapes (7 × n, rows in mechanics.DOF_NAMES order,
    columns mass-normalised with the sign making the largest entry positive)."""

    periods: np.ndarray
    shapes: np.ndarray

    @property
    def omega(self) -> np.ndarray:
        return 2.0 * np.pi / self.periods

    def __iter__(self):
        """Unpacks as ``periods, shapes = opensees_modes(scene)``."""
        return iter((self.periods, self.shapes))


def opensees_modes(scene: Scene, n: int = N_DOF) -> OpenSeesModes:
    """The first ``n`` (≤ 7) natural modes of the contact-free model in ``scene.opensees.mode``."""
    if not 1 <= n <= N_DOF:
        raise ValueError(f"n must be in [1, {N_DOF}], got {n}")
    with OpsSession() as ops:
        info = build_model(ops, scene, None, gaps=False, supports="fixed")
        raw = ops.raw
        lam = np.array(raw.eigen("-fullGenLapack", N_DOF), dtype=float)[:n]
        where = [
            (info.seats[0], 1),
            (info.seats[0], 3),
            (info.seats[1], 1),
            (info.seats[1], 3),
            (info.deck, 1),
            (info.deck, 2),
            (info.deck, 3),
        ]
        phi = np.array(
            [[raw.nodeEigenvector(node, m + 1, dof) for m in range(n)] for node, dof in where]
        )
        raw.wipeAnalysis()
    masses = plan_of(scene).mass  # the plan model's diagonal mass, in DOF_NAMES order
    norm = np.sqrt(np.einsum("im,i,im->m", phi, masses, phi))
    phi = phi / norm
    sign = np.sign(phi[np.abs(phi).argmax(axis=0), np.arange(n)])
    phi = phi * sign
    assert len(DOF_NAMES) == N_DOF
    return OpenSeesModes(periods=2.0 * np.pi / np.sqrt(lam), shapes=phi)

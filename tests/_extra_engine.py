"""A fourth engine written as a newcomer would: this module plus one registry entry.

``LinearNewmarkEngine`` integrates the contact-free, linear-elastic plan model (bents at their
initial stiffness, no gap elements) with the average-acceleration Newmark method in plain
numpy. It exists to prove the engine contract: the registry-wide tests
(``tests/test_engine_contract.py``) register it with one line and run the same test body over
it as over the built-in engines.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from deckpound.models.damping import damping_model
from deckpound.models.engine_contract import (
    Engine,
    RunOutput,
    Status,
    engine_columns,
    output_stride,
)
from deckpound.models.fields import spec, validate
from deckpound.models.motion import analysis_duration


@dataclass(frozen=True, kw_only=True)
class LinearNewmarkSettings:
    """Settings of the test engine."""

    dt: float = spec(1.0e-3, unit="s", doc="time step", gt=0.0)

    def __post_init__(self) -> None:
        validate(self)


class LinearNewmarkEngine(Engine):
    """Contact-free linear Newmark (γ = ½, β = ¼) on the plan model, numpy only."""

    name = "linear-newmark"
    title = "contact-free linear Newmark (a test engine)"
    Settings = LinearNewmarkSettings
    settings_field = None
    step_field = "dt"
    style: ClassVar[dict] = dict(
        color="#27ae60", linestyle="-.", linewidth=1.0, label="linear Newmark"
    )

    def reads(self, scene, settings) -> set[str]:
        return set()  # no contact: every contact option is reported as ignored

    def _run(self, plan, scene, settings, motion) -> RunOutput:
        dt = settings.dt
        n = int(round(analysis_duration(scene, motion) / dt))
        stride = output_stride(dt, scene.run.output_dt)
        M = plan.mass_matrix
        B, S = plan.spring_matrices
        k0 = plan.k0
        damp = damping_model(scene, plan)
        C = damp.matrix(plan)
        K = plan.initial_stiffness
        crate = damp.rate_coefficients(plan)

        def load(t):
            ug = np.array([np.interp(t, motion.t, motion.disp[c]) for c in plan.channels])
            vg = np.array([np.interp(t, motion.t, motion.vel[c]) for c in plan.channels])
            return B.T @ (k0 * (S @ ug) + crate * (S @ vg)), ug

        u = np.zeros(7)
        v = np.zeros(7)
        p, ug = load(0.0)
        a = np.linalg.solve(M, p - C @ v - K @ u)
        Keff = K + 2.0 / dt * C + 4.0 / dt**2 * M
        cols = engine_columns(plan)
        rows = [self._row(plan, 0.0, u, v, ug, B, S, k0)]
        for step in range(1, n + 1):
            p, ug = load(step * dt)
            rhs = p + M @ (4.0 / dt**2 * u + 4.0 / dt * v + a) + C @ (2.0 / dt * u + v)
            un = np.linalg.solve(Keff, rhs)
            vn = 2.0 / dt * (un - u) - v
            a = 4.0 / dt**2 * (un - u) - 4.0 / dt * v - a
            u, v = un, vn
            if step % stride == 0:
                rows.append(self._row(plan, step * dt, u, v, ug, B, S, k0))
        arr = np.array(rows)
        return RunOutput(
            columns={c: arr[:, i] for i, c in enumerate(cols)},
            status=Status.SUCCESS,
            message=f"{n} steps",
            steps=n,
        )

    @staticmethod
    def _row(plan, t, u, v, ug, B, S, k0):
        from deckpound.models.plan import DOF_COLUMNS, VELOCITY_COLUMNS

        row = [t] + [u[d] for _, d in DOF_COLUMNS] + [v[d] for _, d in VELOCITY_COLUMNS]
        row += list(plan.linear_gaps(u)[0]) + [0.0] * 8
        fs = k0 * (B @ u - S @ ug)
        row += list(fs[: plan.n_bent_springs])
        return row

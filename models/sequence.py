"""The 7-run test sequence: one specimen, damage carried from one run to the next.

Rule (documented in :class:`deckpound.models.scene.Sequence`):

* start-of-run gap of a seat = the previous run's residual gap at that face, i.e. the mean of
  its two corner gaps over the last 2 % of the record (the record ends at rest), floored at 0;
  the seat's support length (``seats[i].support_length``, measured from the deck end's
  position at the start of a run) shrinks by the residual opening carried, N − (g − g₀), g₀
  the scene's gap, so the seat margins of a later run count from the original seat;
* bent stiffness per direction: k_next = min(k_prev, k0 · μ^(−β)), μ = max(1, peak |d| / d_y0),
  with k0 and d_y0 = F_y / k0 of the original scene — the Takeda unloading stiffness at the
  peak deformation reached so far; the yield force is kept.

Engines supply the peaks and residuals through their results; these functions only apply the
rule, so any engine (or measured data) can drive a sequence.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from deckpound.models.scene import Scene
from deckpound.models.scene_excitation import RECORD_KINDS, check_sequence_pgas

from .errors import SceneError
from .motion import SupportMotion
from .result import Result


@dataclass(frozen=True)
class SpecimenState:
    """What the specimen carries into a run: seat gaps [m] and bent stiffness [kN/m]."""

    gaps: tuple[float, float]
    stiffness: tuple[tuple[float, float], ...]  # per bent: (k_x, k_y)
    peak_deformation: tuple[tuple[float, float], ...]  # largest |d| so far, per bent (x, y) [m]


def initial_state(scene: Scene) -> SpecimenState:
    """The undamaged specimen of the scene."""
    return SpecimenState(
        gaps=(scene.seats[0].gap, scene.seats[1].gap),
        stiffness=tuple((b.x.stiffness, b.y.stiffness) for b in scene.bents),
        peak_deformation=tuple((0.0, 0.0) for _ in scene.bents),
    )


def check_runs(scene: Scene) -> None:
    """Refuse, before any run, a sequence whose labels would not be applied or not accepted.

    Every label passes the excitation's PGA check (``sequence.pgas[i]`` named); a record must
    be scaled to each run's PGA (``scaling = 'pga'``): with ``factor`` or ``none`` the record
    would be driven unchanged under every label, so such a sequence is refused rather than
    labelled with PGAs it does not apply.
    """
    exc = scene.excitation
    if exc.kind in RECORD_KINDS and exc.scaling != "pga":
        raise SceneError(
            "excitation.scaling",
            f"is {exc.scaling!r}, but a sequence scales the "
            "record to each run's PGA (sequence.pgas); set scaling = 'pga' (or run "
            "single runs with this scaling)",
        )
    check_sequence_pgas(scene)


def _remaining_support(length: float | None, gap: float, carried: float) -> float | None:
    """The support length [m] left under a deck end whose gap is ``carried`` instead of the
    scene's ``gap``: N − (carried − gap) (None: not checked). A run whose opening passed N
    ended unseated, and the residual opening never exceeds the largest, so it stays > 0."""
    return None if length is None else length - (carried - gap)


def scene_for_run(scene: Scene, pga: float, state: SpecimenState) -> Scene:
    """The scene of one run: excitation scaled to ``pga`` [g], gaps and stiffness from ``state``.

    Validates the whole sequence first (:func:`check_runs`). A carried stiffness so low that
    a bent's yield displacement F_y / k passes its ``ultimate_displacement`` is refused naming
    that bent and the run, not as a bad scene value.
    """
    check_runs(scene)
    seats = tuple(
        dataclasses.replace(s, gap=g, support_length=_remaining_support(s.support_length, s.gap, g))
        for s, g in zip(scene.seats, state.gaps)
    )
    for i, (b, ks) in enumerate(zip(scene.bents, state.stiffness)):
        for axis, k in zip(("x", "y"), ks):
            spring = getattr(b, axis)
            if spring.yield_force / k >= spring.ultimate_displacement:
                raise SceneError(
                    f"bents[{i}].{axis}.ultimate_displacement",
                    f"is {spring.ultimate_displacement:g} m, but the stiffness "
                    f"carried into the {pga:g} g run, {k:.6g} kN/m, puts the yield "
                    f"displacement at {spring.yield_force / k:.6g} m beyond it; "
                    "raise it or set sequence.carry_stiffness = false",
                )
    bents = tuple(
        dataclasses.replace(
            b, x=dataclasses.replace(b.x, stiffness=kx), y=dataclasses.replace(b.y, stiffness=ky)
        )
        for b, (kx, ky) in zip(scene.bents, state.stiffness)
    )
    exc = dataclasses.replace(scene.excitation, pga=pga)
    return scene.replace(seats=seats, bents=bents, excitation=exc)


def bent_deformations(
    scene: Scene, result: Result, motion: SupportMotion | None = None
) -> np.ndarray:
    """Bent spring deformations (deck point − table) at the result's times, shape
    (n, n_bents, 2): the result's ``<bent>_dx``/``<bent>_dy`` columns (every engine writes them
    from the plan model; ``motion`` is not needed and kept for old callers)."""
    out = np.empty((len(result.t), len(scene.bents), 2))
    for i, b in enumerate(scene.bents):
        out[:, i, 0] = result[f"{b.name}_dx"]
        out[:, i, 1] = result[f"{b.name}_dy"]
    return out


def next_state(
    original: Scene, state: SpecimenState, run_scene: Scene, result: Result, motion: SupportMotion
) -> SpecimenState:
    """Apply the carry rule after one run (see the module docstring)."""
    seq = original.sequence
    gaps = state.gaps
    if seq.carry_gap:
        tail = max(1, int(0.02 * len(result.t)))
        g1 = float(np.mean(0.5 * (result["gap_c1"][-tail:] + result["gap_c2"][-tail:])))
        g2 = float(np.mean(0.5 * (result["gap_c3"][-tail:] + result["gap_c4"][-tail:])))
        gaps = (max(0.0, g1), max(0.0, g2))
    peaks_now = np.max(np.abs(bent_deformations(run_scene, result, motion)), axis=0)
    peaks = tuple(
        (max(p[0], q[0]), max(p[1], q[1])) for p, q in zip(state.peak_deformation, peaks_now)
    )
    stiffness = state.stiffness
    if seq.carry_stiffness:
        new = []
        for b, (kx, ky), (px, py) in zip(original.bents, state.stiffness, peaks):
            k = []
            for spring, k_prev, peak in ((b.x, kx, px), (b.y, ky, py)):
                mu = max(1.0, peak / spring.yield_displacement)
                k.append(min(k_prev, spring.stiffness * mu ** (-spring.beta)))
            new.append((k[0], k[1]))
        stiffness = tuple(new)
    return SpecimenState(gaps=gaps, stiffness=stiffness, peak_deformation=peaks)

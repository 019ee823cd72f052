"""Checks and statements on a user's record: CSV velocities against their displacements, and
the scaling a record receives.

:func:`check_velocity_columns` refuses a CSV record whose ``<support>_vel`` column is not the
derivative of its ``<support>_disp`` column; :func:`scaling_note` is the sentence that states
any scaling of a record (a record warning, kept in the motion's provenance) and
:func:`scaling_summary` its short form for the line ``deckpound run`` prints. Used by
:mod:`deckpound.models.record_motion`.
"""

from __future__ import annotations

import numpy as np

from deckpound.models.scene_excitation import RECORD_KINDS, Excitation

from .errors import SceneError
from .record_csv import CsvRecord

AXIS_NAME = {"x": "longitudinal (x)", "y": "transverse (y)"}
#: share of a channel's peak velocity by which a CSV velocity column may differ from the
#: central difference of its displacement column, on top of max|a| · Δt
#: (:func:`check_velocity_columns`)
VELOCITY_TOLERANCE = 0.05


def _derivative(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """dx/dt by central differences on the time stamps t (second order; one-sided second-order
    differences at the two ends: np.gradient)."""
    return np.gradient(x, t, edge_order=2 if len(t) > 2 else 1)


def velocity_tolerance(
    t: np.ndarray, disp: np.ndarray, record_peak: float = 0.0
) -> tuple[np.ndarray, float]:
    """The velocity v_d of a displacement history by central differences and the tolerance
    a velocity column may differ from it by (:func:`check_velocity_columns`), in the
    record's units: VELOCITY_TOLERANCE · max(max|v_d|, 1e-3 · record_peak) + max|a_d| · Δt_max.
    """
    v_d = _derivative(disp, t)
    peak_v = max(float(np.max(np.abs(v_d))), 1e-3 * record_peak)
    peak_a = float(np.max(np.abs(_derivative(v_d, t))))
    return v_d, VELOCITY_TOLERANCE * peak_v + peak_a * float(np.max(np.diff(t)))


def check_velocity_columns(csv: CsvRecord, channels: tuple[str, ...], unit: str) -> None:
    """Refuse a velocity column that is not the derivative of its displacement column.

    On the record's own time base and in its own unit, the central difference
    v_d = (d[n+1] − d[n−1]) / (t[n+1] − t[n−1]) of ``<support>_disp`` is compared with
    ``<support>_vel``. A consistent pair differs only by a truncation error: a pair integrated
    from an acceleration by the trapezoidal rule (deckpound, most processing software) by
    (a[n+1] − a[n−1]) Δt / 8 ≤ max|a| Δt / 4; an exactly differentiated pair by Δt² |v''| / 6,
    less than max|a| Δt / 2 below half the Nyquist frequency. The tolerance is

        VELOCITY_TOLERANCE · max|v_d| + max|a_d| · Δt_max

    with a_d = dv_d/dt taken from the displacement alone (a wrong velocity cannot widen its own
    tolerance) and max|v_d| at least 1e-3 of the record's largest channel (a channel at rest).
    The second term holds either truncation error with a factor of 2 or more, the first the
    rounding of printed values. Consistent records pass with room: the benchmark's synthetic
    motion written as CSV uses 3 % of the tolerance, PEER-like records integrated by deckpound
    (dt 5-20 ms, broadband or smooth, time-scaled, baseline-corrected or filtered) at most
    35 % (tests/test_records_velocity.py). A velocity in another unit, of another record,
    with the wrong sign or shifted by a few samples is refused, naming the channel, the time
    and both values.
    """
    t = csv.t
    record_peak = max(
        float(np.max(np.abs(_derivative(csv.columns[f"{c}_disp"], t)))) for c in channels
    )
    for c in channels:
        given = csv.columns.get(f"{c}_vel")
        if given is None:
            continue
        v_d, tolerance = velocity_tolerance(t, csv.columns[f"{c}_disp"], record_peak)
        beyond = np.flatnonzero(np.abs(given - v_d) > tolerance)
        if beyond.size:
            i = int(beyond[0])
            raise SceneError(
                "excitation.file",
                f"{csv.file.path!r}: column '{c}_vel' holds {given[i]:.6g} {unit}/s at t = "
                f"{t[i]:g} s, where the displacement column '{c}_disp' changes at "
                f"{v_d[i]:.6g} {unit}/s (central difference); they differ by more than "
                f"{tolerance:.3g} {unit}/s ({100 * VELOCITY_TOLERANCE:g} % of the peak "
                "velocity plus peak acceleration × time step), so they are not one motion: a "
                "velocity in another unit, of another record or shifted in time? (leave the "
                "velocity column out to derive it from the displacement)",
            )


# -- scaling said --------------------------------------------------------------------------


def _factor_text(factor: float) -> str:
    """A scale factor with the digits that show it is not 1 (1.00018; 1 + 1.2e-09)."""
    text = f"{factor:.6g}"
    if text == "1" and factor != 1.0:
        text = f"(1 {'+' if factor > 1.0 else '-'} {abs(factor - 1.0):.2g})"
    return text


def scaling_note(exc: Excitation, peaks: dict, factors: dict, targets: dict) -> str | None:
    """The sentence saying how a user's record was scaled, or None when it was not (every
    factor exactly 1, or a direction at rest). However small, a scaling is stated: it is
    issued as a record warning and kept in the provenance (``warnings``, with
    ``pga_before_scaling``, ``target_pga`` and ``scale_factor``)."""
    parts = []
    for axis in ("x", "y"):
        f, peak = factors.get(axis), peaks.get(axis)
        if f is None or f == 1.0 or not peak:
            continue
        target = targets.get(axis)
        change = f" (PGA {peak:.6g} g to {target:g} g)" if target is not None else ""
        parts.append(f"{AXIS_NAME[axis]} × {_factor_text(f)}{change}")
    if not parts:
        return None
    why = (
        "scaling = 'pga' scales each direction to its target (transverse to pga, longitudinal "
        "to longitudinal_ratio × pga; scaling = 'none' keeps the record as read)"
        if exc.scaling == "pga"
        else f"scaling = 'factor', scale = {exc.scale:g}"
    )
    return f"excitation.scaling: the record is scaled, {', '.join(parts)}: {why}"


def scaling_summary(provenance: dict | None) -> str:
    """``record scaled x × 1.00912, y × 1.01792`` for a run's one-line report, from a result's
    ``meta["record"]``; empty when the motion is no user's record or was not scaled."""
    if not provenance or provenance.get("kind") not in RECORD_KINDS:
        return ""
    factors = provenance.get("scale_factor") or {}
    targets = provenance.get("target_pga") or {}
    parts = [
        f"{axis} × {_factor_text(f)}"
        + (f" to {targets[axis]:g} g" if targets.get(axis) is not None else "")
        for axis in ("x", "y")
        if (f := factors.get(axis)) is not None and f != 1.0
    ]
    return f"record scaled {', '.join(parts)}" if parts else ""

"""Multi-support excitation: support motions and their loaders.

Each support channel (``<bent>_x``, ``<bent>_y`` for every shake table, ``seat1_x`` and
``seat2_x`` for the actuators) has a displacement [m] and velocity [m/s] history on one time
base; accelerations [m/s²] are derived. Engines resample onto their own step with
:meth:`SupportMotion.resample` (linear interpolation, held constant after the record ends).

Sources: the pulse and supports at rest (here), the seeded synthetic record
(:mod:`deckpound.models.synthetic_motion`), users' records (AT2, text, CSV:
:mod:`deckpound.models.records` reads them, :mod:`deckpound.models.record_motion` turns them
into motion). :func:`support_motion` dispatches, measures the applied PGA per direction,
refuses more than ``EXTREME_PGA`` unless forced, and states every tolerance as a warning.
"""

from __future__ import annotations

import warnings

import numpy as np

from deckpound.models.plan import support_channels
from deckpound.models.scene import Scene
from deckpound.models.scene_excitation import ABSURD_PGA, EXTREME_PGA

from .errors import SceneError
from .intensity import pair_measures
from .motion import (
    G,
    RecordWarning,
    SupportMotion,
    intensity_period,
    make_provenance,
    synthetic_samples,
)
from .record_motion import acceleration_motion
from .synthetic_motion import synthetic_motion

# -- shared by the generated records and the record loaders -----------------------------


# -- loaders -------------------------------------------------------------------------------


def pulse_motion(scene: Scene) -> SupportMotion:
    """One longitudinal displacement pulse at every support (see Excitation, kind = pulse).

    d = D (1 − cos ωt)/2, v = D ω sin(ωt)/2, a = D ω² cos(ωt)/2 for t ≤ T (ω = 2π/T), rest
    afterwards; D = 2 a_max / ω² with a_max = pga · longitudinal_ratio · g. Starts and ends at
    rest (the acceleration jumps at t = 0 and T, as an actuator command may).
    """
    exc = scene.excitation
    n = synthetic_samples(exc)
    t = np.arange(n) * exc.dt
    w = 2.0 * np.pi / exc.pulse_period
    D = 2.0 * exc.pga * exc.longitudinal_ratio * G / w**2
    on = t <= exc.pulse_period
    d = np.where(on, 0.5 * D * (1.0 - np.cos(w * t)), 0.0)
    v = np.where(on, 0.5 * D * w * np.sin(w * t), 0.0)
    a = np.where(on, 0.5 * D * w * w * np.cos(w * t), 0.0)
    zero = np.zeros(n)
    disp, vel, acc = {}, {}, {}
    for ch in support_channels(scene):
        x = ch.endswith("_x")
        disp[ch], vel[ch], acc[ch] = (d, v, a) if x else (zero, zero, zero)
    prov = make_provenance(
        exc,
        files={},
        header={},
        npts={"x": n},
        dt_record=exc.dt,
        dt=exc.dt,
        duration=float(t[-1]),
        targets={"x": exc.pga * exc.longitudinal_ratio, "y": 0.0},
        factors={},
        notes=[],
        processing=f"generator (1 - cos pulse, period {exc.pulse_period:g} s)",
    )
    return SupportMotion(t=t, disp=disp, vel=vel, acc_exact=acc, provenance=prov)


def rest_motion(scene: Scene) -> SupportMotion:
    """Every support at rest (kind = none) over ``run.duration`` if given, else
    ``excitation.duration``: two samples of zero displacement and velocity (the engines hold
    the last sample, so the motion is exactly zero at every step)."""
    exc = scene.excitation
    duration = scene.run.duration if scene.run.duration is not None else exc.duration
    t = np.array([0.0, float(duration)])
    zero = np.zeros(2)
    chans = support_channels(scene)
    prov = make_provenance(
        exc,
        files={},
        header={},
        npts={},
        dt_record=None,
        dt=None,
        duration=float(duration),
        targets={"x": 0.0, "y": 0.0},
        factors={},
        notes=[],
        processing="none (supports at rest)",
    )
    return SupportMotion(
        t=t,
        disp=dict.fromkeys(chans, zero),
        vel=dict.fromkeys(chans, zero),
        acc_exact=dict.fromkeys(chans, zero),
        provenance=prov,
    )


def support_motion(scene: Scene, *, intensity: bool = True) -> SupportMotion:
    """The scene's support motion, whatever its source, with its provenance.

    ``intensity``: compute the applied pair's intensity measures (:func:`motion_intensity`,
    ``provenance["intensity"]``); False leaves them None, for a summary-only run, whose row has
    no place for them.

    Refuses a non-finite motion and, unless ``excitation.allow_extreme``, an applied PGA above
    ``EXTREME_PGA`` g in either direction (measured on the motion). Only then are the record's
    tolerances issued as :class:`RecordWarning` (an input refused prints one error, nothing
    more); they stay listed in ``provenance["warnings"]``.
    """
    exc = scene.excitation
    kind = exc.kind
    if kind == "synthetic":
        motion, field_name = synthetic_motion(scene), "excitation"
    elif kind == "pulse":
        motion, field_name = pulse_motion(scene), "excitation"
    elif kind == "none":
        motion, field_name = rest_motion(scene), "excitation"
    else:
        with np.errstate(all="ignore"):  # an overflow is refused below, not warned about
            motion = acceleration_motion(scene)
        field_name = "excitation.file" if kind == "csv" else "excitation.file_x"
    if not np.all(np.isfinite(motion.t)):
        raise SceneError(field_name, "the time stamps overflow to a non-finite value")
    for name, arrays in (("displacement", motion.disp), ("velocity", motion.vel)):
        for ch, x in arrays.items():
            if not np.all(np.isfinite(x)):
                raise SceneError(
                    field_name,
                    f"the {name} of support {ch!r} overflows to a "
                    f"non-finite value (scaling = {exc.scaling!r}; check the "
                    "record's magnitude and units)",
                )
    applied = motion.applied_pga()
    for axis, pga in applied.items():
        if pga > ABSURD_PGA or (pga > EXTREME_PGA and not exc.allow_extreme):
            where = field_name if kind not in ("at2", "text") else f"excitation.file_{axis}"
            name = "longitudinal (x)" if axis == "x" else "transverse (y)"
            limit = (
                f"more than {EXTREME_PGA:g} g is refused unless excitation.allow_extreme = true"
                if pga <= ABSURD_PGA
                else f"more than {ABSURD_PGA:g} g is refused"
            )
            raise SceneError(
                where,
                f"gives a {name} PGA of {pga:.4g} g after scaling (scaling = "
                f"{exc.scaling!r}, scale = {exc.scale:g}); {limit}",
            )
    motion.provenance["applied_pga"] = applied
    motion.provenance["intensity"] = motion_intensity(scene, motion) if intensity else None
    for text in motion.provenance.get("warnings", []):
        # one location for every call: a sequence or several engines print a sentence once
        warnings.warn(text, RecordWarning, stacklevel=1)
    return motion


def motion_intensity(scene: Scene, motion: SupportMotion) -> dict:
    """Intensity measures (:func:`deckpound.models.intensity.pair_measures`) of the motion of
    the first table (x, y; the other tables get the same record, delayed by the lag) at
    :func:`intensity_period`. A time base that is not uniform (a CSV of displacements) is
    interpolated linearly onto as many uniform samples first."""
    bent = scene.bents[0].name if scene.bents else None
    t = motion.t
    n = len(t)
    dt = float(t[-1] - t[0]) / (n - 1)
    uniform = bool(np.all(np.abs(np.diff(t) - dt) <= 1e-6 * dt))
    acc, vel, disp = {}, {}, {}
    for axis in ("x", "y"):
        ch = f"{bent}_{axis}" if bent else f"seat1_{axis}"
        if ch not in motion.disp:
            acc[axis] = vel[axis] = disp[axis] = np.zeros(n)
            continue
        acc[axis], vel[axis], disp[axis] = motion.acc(ch), motion.vel[ch], motion.disp[ch]
    if not uniform:
        grid = t[0] + np.arange(n) * dt
        for series in (acc, vel, disp):
            for axis in series:
                series[axis] = np.interp(grid, t, series[axis])
    out = pair_measures(dt, acc, vel, disp, intensity_period(scene))
    out["where"] = f"table {bent}" if bent else "seats"
    return out

"""The support motion record and what every motion source shares.

:class:`SupportMotion` holds each support channel's displacement [m] and velocity [m/s] on one
time base (accelerations [m/s²] derived) with its provenance; the helpers here are shared by
the motion sources (:mod:`.excitation` for the pulse and supports at rest and the dispatcher,
:mod:`.synthetic_motion`, :mod:`.record_motion`): sample-count limits, whole-step delays of the
tables (the lag of multi-support excitation), time-base checks, the provenance record, the
period of the spectral intensity measures and the run length.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass, field, fields

import numpy as np

from deckpound.models.scene import Scene
from deckpound.models.scene_excitation import Excitation
from deckpound.models.scene_settings import MAX_STEPS

from .errors import SceneError
from .mechanics import natural_modes
from .records import MAX_SAMPLES, MIN_SAMPLES

G = 9.80665  # standard gravity [m/s²]


class RecordWarning(UserWarning):
    """A tolerance applied to a user's record (also listed in the motion's provenance)."""


@dataclass(frozen=True)
class SupportMotion:
    """Displacement and velocity of every support channel on a common time base.

    Attributes
    ----------
    t : (n,) array [s], strictly increasing, starting at 0.
    disp, vel : dict channel → (n,) array [m], [m/s].
    acc_exact : dict channel → (n,) array [m/s²], the source's own acceleration when known.
    provenance : JSON-able dict saying what the motion is (copied into results and reports).
        Its keys, always all present (``None`` where they do not apply):

        ``kind`` (synthetic | pulse | at2 | text | csv); ``files`` (label x / y / csv →
        {``path`` resolved, ``sha256`` of the file's bytes, ``bytes``}); ``header`` (label →
        station/event line, one sanitised line); ``npts`` (label → samples declared or held);
        ``dt_record`` [s] as read; ``time_scale`` [-]; ``dt`` [s] after time scaling;
        ``duration`` [s]; ``processing``; ``scaling`` (pga | factor | none); ``target_pga``
        (x, y → [g] or None); ``scale_factor`` (x, y → [-] or None); ``applied_pga`` (x, y →
        [g], max |a| over the direction's supports, measured on this motion); ``seed``
        (synthetic); ``warnings`` (every tolerance, one sentence each); ``units``;
        ``pair_scaling`` (scaling = pair-*: measure, target, unit, value before, factor,
        period; else None); ``intensity`` (the applied pair's intensity measures at the
        first table, :func:`motion_intensity`, filled by :func:`support_motion`).
    """

    t: np.ndarray
    disp: dict[str, np.ndarray]
    vel: dict[str, np.ndarray]
    acc_exact: dict[str, np.ndarray] | None = None
    provenance: dict = field(default_factory=dict, compare=False)

    @property
    def channels(self) -> tuple[str, ...]:
        return tuple(self.disp)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def acc(self, channel: str) -> np.ndarray:
        """Acceleration [m/s²]: the generator's exact one if known, else from the velocity
        by second-order differences."""
        if self.acc_exact is not None and channel in self.acc_exact:
            return self.acc_exact[channel]
        return np.gradient(self.vel[channel], self.t)

    def resample(self, dt: float, duration: float | None = None) -> SupportMotion:
        """Motion at t_n = n·dt, n = 0..N, N = round(duration/dt), by linear interpolation.

        Exact for piecewise-linear data; after the record ends the last displacement and
        velocity are held (rest for the generated records and for records that end at rest; a
        drifting record is stated in a warning when it is loaded).
        """
        if not dt > 0:
            raise SceneError("dt", f"must be > 0 s, got {dt}")
        total = self.duration if duration is None else duration

        if total / dt > MAX_STEPS:
            raise SceneError(
                "dt",
                f"gives {total / dt:.3g} steps over {total:g} s; at most "
                f"{MAX_STEPS:.0e} are allowed",
            )
        n = round(total / dt)
        t = np.arange(n + 1) * dt
        disp = {k: np.interp(t, self.t, v) for k, v in self.disp.items()}
        vel = {k: np.interp(t, self.t, v) for k, v in self.vel.items()}
        return SupportMotion(t=t, disp=disp, vel=vel, provenance=self.provenance)

    def matrices(self, channels: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
        """(n, n_channels) displacement and velocity arrays in the given channel order."""
        missing = [c for c in channels if c not in self.disp]
        if missing:
            raise SceneError("excitation", f"no record for support {missing[0]!r}")
        D = np.column_stack([self.disp[c] for c in channels])
        V = np.column_stack([self.vel[c] for c in channels])
        return np.ascontiguousarray(D), np.ascontiguousarray(V)

    def applied_pga(self) -> dict[str, float]:
        """Peak |acceleration| per direction over its supports [g] (x: tables and seats)."""
        out = {}
        for axis in ("x", "y"):
            peaks = [
                float(np.max(np.abs(self.acc(c)))) for c in self.disp if c.endswith(f"_{axis}")
            ]
            out[axis] = max(peaks, default=0.0) / G
        return out


def make_provenance(
    exc: Excitation,
    *,
    files: dict,
    header: dict,
    npts: dict,
    dt_record: float | None,
    dt: float | None,
    duration: float,
    processing: str,
    targets: dict,
    factors: dict,
    notes: list[str],
    seed: int | None = None,
) -> dict:
    """The provenance dict (keys in :class:`SupportMotion`); ``applied_pga`` is filled by
    :func:`support_motion` from the finished motion."""
    both = ("x", "y")
    return {
        "kind": exc.kind,
        "files": files,
        "header": header,
        "npts": npts,
        "dt_record": dt_record,
        "time_scale": exc.time_scale,
        "dt": dt,
        "duration": duration,
        "processing": processing,
        "scaling": exc.scaling,
        "target_pga": {a: targets.get(a) for a in both},
        "scale_factor": {a: factors.get(a) for a in both},
        "applied_pga": None,
        "pair_scaling": None,
        "intensity": None,
        "seed": seed,
        "warnings": list(notes),
        "units": {
            "dt_record": "s",
            "dt": "s",
            "duration": "s",
            "target_pga": "g",
            "applied_pga": "g",
            "time_scale": "-",
            "scale_factor": "-",
        },
    }


def check_samples(n: float, short_field: str, long_field: str, what: str) -> None:
    """Refuse records too short for the baseline correction or too long to hold."""
    if n < MIN_SAMPLES:
        raise SceneError(
            short_field, f"{what} gives {n:g} samples; at least {MIN_SAMPLES} are needed"
        )
    if n > MAX_SAMPLES:
        raise SceneError(
            long_field, f"{what} gives {n:.3g} samples; at most {MAX_SAMPLES:g} are allowed"
        )


def synthetic_samples(exc: Excitation) -> int:
    """Sample count of a generated record (synthetic, pulse), refused when absurd."""
    check_samples(
        round(exc.duration / exc.dt) + 1.0,
        "excitation.duration",
        "excitation.dt",
        f"duration {exc.duration} s at dt = {exc.dt} s",
    )
    return round(exc.duration / exc.dt) + 1


def shift_record(x: np.ndarray, steps: int) -> np.ndarray:
    """Delay a record by a whole number of samples (zeros in front, same length)."""
    if steps <= 0:
        return x
    steps = min(steps, len(x))
    return np.concatenate([np.zeros(steps), x[: len(x) - steps]])


def table_positions(scene: Scene) -> list[int]:
    """Each bent's table k (delayed by k·lag, with its own noise under incoherence): the rank
    of its station among the distinct stations in scene order. Bents at one station — the
    two halves of a pier under a deck joint — stand on one table and get one motion; for
    bents at distinct stations k is the bent's index."""
    tables: dict[float, int] = {}
    return [tables.setdefault(b.station, len(tables)) for b in scene.bents]


def check_lag(scene: Scene, dt: float, n: int) -> int:
    """Lag in whole steps; refuses a lag that delays the last table beyond the record."""
    exc = scene.excitation
    steps = round(exc.lag / dt)
    n_tables = max(table_positions(scene), default=0) + 1
    last = (n_tables - 1) * steps
    if last >= n:
        limit = (n - 1) * dt / max(1, n_tables - 1)
        raise SceneError(
            "excitation.lag",
            f"delays the last table by {last * dt:g} s, beyond the record length "
            f"{(n - 1) * dt:g} s; must be < {limit:g} s, got {exc.lag}",
        )
    return steps


def check_time_base(t: np.ndarray, field: str) -> None:
    """Refuse non-finite, duplicate or decreasing time stamps."""
    if len(t) < 2:
        raise SceneError(field, f"needs at least 2 time stamps, got {len(t)}")
    if not np.all(np.isfinite(t)):
        i = int(np.argmin(np.isfinite(t)))
        raise SceneError(field, f"time stamp {i} is not finite ({t[i]})")
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0)) + 1
        kind = "duplicate" if dt[i - 1] == 0 else "decreasing"
        raise SceneError(
            field, f"time stamps must increase strictly; stamp {i} ({t[i]} s) is {kind}"
        )


#: the scene's sections but its excitation: everything the contact-free modes can depend on
_STRUCTURE = operator.attrgetter(*(f.name for f in fields(Scene) if f.name != "excitation"))
#: structures whose T1 is remembered (a sweep asks for one structure's period every case)
T1_MEMO_SIZE = 8
_T1_MEMO: list[tuple[tuple, float | None]] = []


def intensity_period(scene: Scene) -> float | None:
    """Period [s] of the spectral intensity measures: ``excitation.im_period`` if given, else
    T1 of the contact-free model (the longest finite natural period, as ``deckpound modes``
    lists it); None when no mode has a finite period.

    T1 is remembered for the last :data:`T1_MEMO_SIZE` structures, each keyed on every section
    of the scene but its excitation (compared by value; the sections a sweep's cases share are
    the same objects, so the lookup costs a few identity tests)."""
    if scene.excitation.im_period is not None:
        return float(scene.excitation.im_period)
    key = _STRUCTURE(scene)
    for known, period in _T1_MEMO:
        if known == key:
            return period
    periods = natural_modes(scene).periods
    finite = periods[np.isfinite(periods) & (periods > 0.0)]
    period = float(np.max(finite)) if len(finite) else None
    _T1_MEMO.insert(0, (key, period))
    del _T1_MEMO[T1_MEMO_SIZE:]
    return period


def analysis_duration(scene: Scene, motion: SupportMotion) -> float:
    """Run length: ``run.duration`` if given, else the record length [s]."""
    return scene.run.duration if scene.run.duration is not None else motion.duration

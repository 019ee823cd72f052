"""Support motion from a user's record: components, time scaling, processing, scaling.

Steps, in this order, each stated in the motion's provenance
(:attr:`deckpound.models.motion.SupportMotion.provenance`):

1. **read** (:mod:`deckpound.models.records`): AT2 in g, text and CSV in ``acc_unit``;
2. **components**: the x (longitudinal) and y (transverse) accelerations. A direction without
   a record is at rest. Components of unequal length are **padded with zeros at the end** to
   the longer one — every recorded sample is kept, and a record's end is quiet, so the added
   samples are the rest the ground was at; truncating would drop recorded motion. Components
   with different sampling steps are **refused** (one station's components share their DT;
   different steps mean files of different records were paired, and resampling an
   accelerogram would change its peaks);
3. **time scaling** (similitude, ``time_scale`` = s): t_model = s · t. Accelerations are kept,
   so velocities scale by s and displacements by s² (1/4-scale model: s = √(1/4) = 0.5,
   velocities × 0.5, displacements × 0.25 = the length scale); frequencies scale by 1/s;
4. **processing** (``processing``), on the model time base:
   ``none`` — the acceleration as given, integrated by the trapezoidal rule from rest
   (v(0) = d(0) = 0; second-order accurate; records from PEER are already processed);
   ``baseline`` — a polynomial acceleration baseline of degree ``BASELINE_DEGREE`` is removed,
   its coefficients fitted by least squares to the trapezoidal displacement (the drift the
   baseline causes), then integrated as for ``none``;
   ``highpass`` — zero-phase (forward-backward) 4th-order Butterworth high-pass at
   ``highpass`` Hz on the zero-padded acceleration, then integrated as for ``none``.
   Whatever the processing, a displacement ending beyond ``DRIFT_FRACTION`` of its peak is
   stated in a warning (not refused: a fling step can be real);
5. **scaling** (``scaling``): ``pga`` — each direction to its target, y to ``pga`` and x to
   ``longitudinal_ratio · pga`` [g], the factor target / max|a| measured on the processed
   acceleration (what the engines receive; the record's own component ratio is replaced);
   ``pair-pga``, ``pair-pgv``, ``pair-sa``, ``pair-rotd50`` — both directions × one factor
   (:func:`pair_factor`: the record's component ratio is kept) that brings the pair's
   geometric-mean PGA, geometric-mean PGV, geometric-mean Sa(T) or RotD50(T) to its target
   (stated in the provenance under ``pair_scaling``); ``factor`` — both directions ×
   ``scale``; ``none`` — as read. Any factor other than exactly 1 is stated, however small
   (:func:`~.record_checks.scaling_note`: a record warning, kept in the provenance with
   ``pga_before_scaling``).

The motion's acceleration (``acc_exact``) is the processed, scaled acceleration; velocity and
displacement are its trapezoidal integrals, so the three agree exactly on the record's grid.
"""

from __future__ import annotations

import hashlib

import numpy as np

from deckpound.models.plan import support_channels
from deckpound.models.scene import Scene
from deckpound.models.scene_excitation import ABSURD_PGA, EXTREME_PGA, Excitation

from .errors import SceneError
from .iir import butter_highpass_sos, sosfiltfilt
from .intensity import pair_measures
from .kept import Kept
from .motion import (
    G,
    SupportMotion,
    check_lag,
    check_time_base,
    intensity_period,
    make_provenance,
    shift_record,
    table_positions,
)
from .record_checks import AXIS_NAME, check_velocity_columns, scaling_note
from .record_csv import CsvRecord, read_csv_record
from .records import (
    MIN_SAMPLES,
    RecordFile,
    read_at2,
    read_text,
    uniform_step,
)
from .scene_excitation import PAIR_SCALINGS, PAIR_TARGETS

ACC_UNITS = {"g": G, "m/s^2": 1.0, "cm/s^2": 0.01}  # to m/s²
LENGTH_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}  # to m
BASELINE_DEGREE = 2  # quadratic acceleration baseline = quartic displacement drift
DRIFT_FRACTION = 0.2  # final |d| above this fraction of peak |d| is reported as drift
#: measures of processed, unscaled pairs kept per process (:func:`pair_factor`: a sweep scales
#: one pair to many levels and measures it once), keyed by the measure, step, period and the
#: SHA-256 of both components' samples
MEASURED = Kept(64)


def integrate(a: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Velocity and displacement from acceleration by the trapezoidal rule, from rest.

    v_{n+1} = v_n + (a_n + a_{n+1}) dt/2, d_{n+1} = d_n + (v_n + v_{n+1}) dt/2; the error of
    each is O(dt²) for a smooth acceleration.
    """
    v = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * dt)])
    d = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)])
    return v, d


def remove_baseline(a: np.ndarray, dt: float, degree: int = BASELINE_DEGREE) -> np.ndarray:
    """Acceleration minus the polynomial Σ c_k t^k (k ≤ degree) whose displacement fits the
    record's displacement best (least squares); the integration is linear, so the corrected
    record's displacement is d − Σ c_k D[t^k] with D the trapezoidal double integral."""
    t = np.arange(len(a)) * dt / (len(a) * dt)  # normalised time: a well-conditioned basis
    basis = np.column_stack([t**k for k in range(degree + 1)])
    drift = np.column_stack([integrate(basis[:, k], dt)[1] for k in range(degree + 1)])
    coef, *_ = np.linalg.lstsq(drift, integrate(a, dt)[1], rcond=None)
    return a - basis @ coef


def highpass_padded(a: np.ndarray, dt: float, corner: float, record: str) -> np.ndarray:
    """Zero-phase 4th-order Butterworth high-pass at ``corner`` Hz of ``a`` (n,) (or of each
    row of ``a`` (m, n)) padded with one record length of zeros on each side; returns the
    whole padded signal (3n samples), pads included. ``record`` names the record in the
    refusal of a corner outside (1e-6·Nyquist, Nyquist) (the filter design is singular
    below). Shared by the users' records
    (:func:`highpass_filtered`) and the synthetic generator
    (:func:`deckpound.models.synthetic_motion.baseline_corrected`).
    """
    nyq = 0.5 / dt
    if not 1e-6 * nyq <= corner < nyq:
        raise SceneError(
            "excitation.highpass",
            f"must lie between {1e-6 * nyq:g} Hz and the Nyquist frequency {nyq:g} Hz "
            f"of {record}, got {corner}",
        )
    sos = butter_highpass_sos(4, corner / nyq)
    pad = np.zeros(np.shape(a))  # a (n,) signal or (m, n) rows, filtered along the last axis
    return sosfiltfilt(sos, np.concatenate([pad, a, pad], axis=-1))


def highpass_filtered(a: np.ndarray, dt: float, corner: float) -> np.ndarray:
    """Zero-phase 4th-order Butterworth high-pass at ``corner`` Hz (zero padding both sides).

    The pads (one record length each) hold the filter's transients; they are cut off again,
    so v and d start from rest at t = 0.
    """
    n = len(a)
    return highpass_padded(a, dt, corner, "the record (after time scaling)")[n : 2 * n]


def processing_label(exc: Excitation) -> str:
    """The processing as recorded in the provenance."""
    if exc.processing == "baseline":
        return f"baseline (degree-{BASELINE_DEGREE} acceleration polynomial, least squares on d)"
    if exc.processing == "highpass":
        return f"highpass {exc.highpass:g} Hz (4th-order zero-phase Butterworth)"
    return "none (trapezoidal integration of the acceleration as given)"


def _components(
    scene: Scene,
) -> tuple[dict[str, np.ndarray], dict[str, RecordFile], float, list[str]]:
    """Accelerations [m/s²] per direction present, their files, the step [s], global notes."""
    exc = scene.excitation
    notes: list[str] = []
    files: dict[str, RecordFile] = {}
    acc: dict[str, np.ndarray] = {}
    reader = read_at2 if exc.kind == "at2" else read_text
    unit = ACC_UNITS["g" if exc.kind == "at2" else exc.acc_unit]
    for axis, path in (("x", exc.file_x), ("y", exc.file_y)):
        if path:
            files[axis] = reader(path, f"excitation.file_{axis}")
            with np.errstate(over="ignore"):  # an overflow is refused by _check_raw_pga
                acc[axis] = files[axis].values * unit
    dt = _common_step(
        {a: f.dt for a, f in files.items()}, {a: f"excitation.file_{a}" for a in files}
    )
    return acc, files, dt, notes


def _common_step(steps: dict[str, float], fields: dict[str, str]) -> float:
    """The components' sampling step; refuses different ones."""
    if len(steps) == 2 and abs(steps["x"] - steps["y"]) > 1e-6 * steps["x"]:
        raise SceneError(
            fields["y"],
            f"the record's step DT = {steps['y']:g} s differs from the "
            f"x record's {steps['x']:g} s; both directions must share their "
            "sampling step (components of one station do)",
        )
    return next(iter(steps.values()))


def _check_raw_pga(
    exc: Excitation, peaks: dict[str, float], fields: dict[str, str], how: str
) -> None:
    """Refuse a record whose PGA as read [g] exceeds EXTREME_PGA (a wrong unit, or noise), or
    ABSURD_PGA even when forced (beyond any physical value; it would overflow downstream)."""
    for axis, peak in peaks.items():
        if not np.isfinite(peak):
            raise SceneError(
                fields[axis],
                f"the {AXIS_NAME[axis]} acceleration overflows to a "
                f"non-finite value ({how}); check the record's magnitude and unit",
            )
        if peak > ABSURD_PGA:
            raise SceneError(
                fields[axis],
                f"the {AXIS_NAME[axis]} record reads as a PGA of "
                f"{peak:.4g} g ({how}): beyond any physical value (at most "
                f"{ABSURD_PGA:g} g even with allow_extreme); check the record's unit",
            )
        if peak > EXTREME_PGA and not exc.allow_extreme:
            raise SceneError(
                fields[axis],
                f"the {AXIS_NAME[axis]} record reads as a PGA of "
                f"{peak:.4g} g ({how}); more than {EXTREME_PGA:g} g is refused: "
                "check the record's unit, or set excitation.allow_extreme = true "
                "to force it",
            )


def _equal_lengths(
    acc: dict[str, np.ndarray], files: dict[str, RecordFile], dt: float, label
) -> int:
    """Pad the shorter component with zeros at the end; returns the common length."""
    n = max(len(a) for a in acc.values())
    for axis, a in acc.items():
        if len(a) < n:
            other = "y" if axis == "x" else "x"
            files[axis].notes.append(
                f"{label(axis)}: the {AXIS_NAME[axis]} component has {len(a)} samples, "
                f"{n - len(a)} fewer than the {AXIS_NAME[other]} one ({n}): padded with zeros "
                f"at the end ({(n - len(a)) * dt:g} s at rest)"
            )
            acc[axis] = np.concatenate([a, np.zeros(n - len(a))])
    return n


def _drift_note(d: np.ndarray, exc: Excitation, where: str) -> str | None:
    """A sentence when the displacement ends beyond DRIFT_FRACTION of its peak. Stated as a
    fraction only, which scaling does not change, so a sequence repeats one sentence."""
    peak = float(np.max(np.abs(d)))
    if peak > 0.0 and abs(d[-1]) > DRIFT_FRACTION * peak:
        hint = (
            "; consider processing = 'baseline' or 'highpass'" if exc.processing == "none" else ""
        )
        return (
            f"{where}: with processing = {exc.processing!r} the displacement ends at "
            f"{100 * abs(d[-1]) / peak:.0f} % of its peak (more than "
            f"{100 * DRIFT_FRACTION:g} %): the record drifts{hint}"
        )
    return None


def pair_factor(
    exc: Excitation, acc: dict[str, np.ndarray], dt: float, period: float | None, where: str
) -> tuple[float, dict]:
    """One scale factor for both components (``scaling`` = pair-*), and what it scaled.

    The measure of the processed, unscaled pair (accelerations [m/s²] on the model step
    ``dt`` [s]; velocities their trapezoidal integrals): pair-pga √(PGA_x PGA_y) [g],
    pair-pgv √(PGV_x PGV_y) [m/s], pair-sa √(Sa_x Sa_y) at ``period`` (5 %) [g], pair-rotd50
    RotD50 at ``period`` [g]. Every one is proportional to a common factor of both
    components, so factor = target / measure meets the target exactly and keeps the
    components' ratio. Returns (factor, {measure, target, unit, before, factor, period}).
    """

    name, unit = PAIR_TARGETS[exc.scaling]
    target = float(getattr(exc, name))
    missing = [a for a in ("x", "y") if a not in acc]
    if missing:
        raise SceneError(
            "excitation.scaling",
            f"{exc.scaling!r} scales a pair of components by one factor; {where} has no "
            f"{AXIS_NAME[missing[0]]} component (use scaling = 'pga' or 'factor')",
        )
    spectral = exc.scaling in ("pair-sa", "pair-rotd50")
    if spectral and period is None:
        raise SceneError(
            "excitation.im_period",
            f"scaling = {exc.scaling!r} needs a period and the scene has no finite natural "
            "period to default to; give excitation.im_period",
        )
    before = _pair_measure(exc.scaling, acc, dt, period if spectral else None)
    if not before > 0.0:
        raise SceneError(
            "excitation.scaling",
            f"{exc.scaling!r}: the pair's measure is zero after processing (one component "
            f"at rest gives a zero geometric mean); it cannot be scaled to {target:g} {unit}",
        )
    factor = target / float(before)
    info = {
        "measure": exc.scaling[len("pair-") :],
        "target": target,
        "unit": unit,
        "before": float(before),
        "factor": factor,
        "period": period if spectral else None,
    }
    return factor, info


def _pair_measure(
    scaling: str, acc: dict[str, np.ndarray], dt: float, period: float | None
) -> float:
    """The measure ``scaling`` (pair-pga, -pgv, -sa, -rotd50) of the unscaled pair (see
    :func:`pair_factor`), computed once per pair content, step and period in a process."""
    key = (scaling, dt, period) + tuple(
        hashlib.sha256(np.ascontiguousarray(acc[a]).tobytes()).hexdigest() for a in ("x", "y")
    )
    kept = MEASURED.get(key)
    if kept is not None:
        return kept
    vel, disp = {}, {}
    for axis, a in acc.items():
        vel[axis], disp[axis] = integrate(a, dt)
    ims = pair_measures(dt, acc, vel, disp, period)
    before = {
        "pair-pga": np.sqrt(ims["x"]["pga"] * ims["y"]["pga"]),
        "pair-pgv": np.sqrt(ims["x"]["pgv"] * ims["y"]["pgv"]),
        "pair-sa": ims["sa_geomean"],
        "pair-rotd50": ims["rotd50"],
    }[scaling]
    before = float(before)
    MEASURED.put(key, before)
    return before


def pair_scaling_note(info: dict) -> str | None:
    """The sentence saying how a pair was scaled by one factor (None for exactly 1)."""
    if info["factor"] == 1.0:
        return None
    at = f" at T = {info['period']:.4g} s" if info["period"] is not None else ""
    return (
        f"excitation.scaling: the record pair is scaled by one factor × "
        f"{info['factor']:.6g} ({info['measure']}{at} {info['before']:.6g} to "
        f"{info['target']:g} {info['unit']}); the components' ratio is kept"
    )


def _factors(exc: Excitation, peaks: dict[str, float], fields: dict[str, str]) -> tuple[dict, dict]:
    """Scale factor and target PGA [g] per direction present (per-component scalings)."""
    targets = {"x": exc.pga * exc.longitudinal_ratio, "y": exc.pga}
    factors, wanted = {}, {}
    for axis, peak in peaks.items():
        if exc.scaling == "pga":
            if peak == 0.0 and targets[axis] > 0.0:
                raise SceneError(
                    fields[axis],
                    f"the {AXIS_NAME[axis]} record is zero after "
                    f"processing; it cannot be scaled to {targets[axis]:g} g",
                )
            factors[axis] = targets[axis] / peak if peak > 0.0 else 0.0
            wanted[axis] = targets[axis]
        else:
            factors[axis] = exc.scale if exc.scaling == "factor" else 1.0
            wanted[axis] = None
    return factors, wanted


def acceleration_motion(scene: Scene) -> SupportMotion:
    """Motion of a biaxial acceleration record (AT2, text, or CSV with acc_x / acc_y)."""
    exc = scene.excitation
    if exc.kind == "csv":
        csv = read_csv_record(exc.file, exc.time_column)
        if csv.mode == "displacement":
            return displacement_motion(scene, csv)
        acc, files, dt, notes = _csv_components(exc, csv)
    else:
        acc, files, dt, notes = _components(scene)
    fields = {a: f.field for a, f in files.items()}

    def label(axis: str) -> str:
        return files[axis].label + (f", column acc_{axis}" if exc.kind == "csv" else "")

    for axis in ("x", "y"):
        if axis not in acc:
            src = "file_x" if axis == "x" else "file_y"
            what = (
                f"excitation.{src} is not given"
                if exc.kind != "csv"
                else f"the CSV has no acc_{axis} column"
            )
            notes.append(
                f"{what}: the {AXIS_NAME[axis]} direction is at rest"
                + (" (its PGA target is not applied)" if exc.scaling == "pga" else "")
            )
    unit = "g" if exc.kind == "at2" else exc.acc_unit
    _check_raw_pga(
        exc, {a: float(np.max(np.abs(x))) / G for a, x in acc.items()}, fields, f"values in {unit}"
    )
    n = _equal_lengths(acc, files, dt, label)
    dt_model = dt * exc.time_scale
    base: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    peaks = {}
    for axis, a in acc.items():
        if exc.processing == "baseline":
            a = remove_baseline(a, dt_model)
        elif exc.processing == "highpass":
            a = highpass_filtered(a, dt_model, exc.highpass)
        acc[axis] = a
        peaks[axis] = float(np.max(np.abs(a))) / G
    pair_info = None
    if exc.scaling in PAIR_SCALINGS:
        where = "the CSV" if exc.kind == "csv" else "the record"
        factor, pair_info = pair_factor(exc, acc, dt_model, intensity_period(scene), where)
        factors, targets = dict.fromkeys(acc, factor), {}
        scaled = pair_scaling_note(pair_info)
    else:
        factors, targets = _factors(exc, peaks, fields)
        scaled = scaling_note(exc, peaks, factors, targets)
    for axis, a in acc.items():
        a = a * factors[axis]
        v, d = integrate(a, dt_model)
        drift = _drift_note(d, exc, label(axis))
        if drift:
            notes.append(drift)
        base[axis] = (d, v, a)
    zero = np.zeros(n)
    for axis in ("x", "y"):
        base.setdefault(axis, (zero, zero, zero))
    t = np.arange(n) * dt_model
    disp, vel, acc_out = _tables(scene, base, dt_model, n)
    unique = {f.path: f for f in files.values()}
    all_notes = [w for f in unique.values() for w in f.notes] + notes + ([scaled] if scaled else [])
    prov = make_provenance(
        exc,
        files={a: f.info() for a, f in files.items()},
        header={a: f.header for a, f in files.items()},
        npts={a: f.npts for a, f in files.items()},
        dt_record=dt,
        dt=dt_model,
        duration=float(t[-1]),
        processing=processing_label(exc),
        targets=targets,
        factors=factors,
        notes=all_notes,
    )
    _record_peaks(prov, peaks)
    prov["pair_scaling"] = pair_info
    return SupportMotion(t=t, disp=disp, vel=vel, acc_exact=acc_out, provenance=prov)


def _record_peaks(prov: dict, peaks: dict) -> None:
    """Keep the record's PGA before scaling [g] per direction in the provenance (with
    ``target_pga`` and ``scale_factor``: what was scaled, to what, by how much)."""
    prov["pga_before_scaling"] = {a: peaks.get(a) for a in ("x", "y")}
    prov["units"]["pga_before_scaling"] = "g"


def _tables(scene: Scene, base: dict, dt: float, n: int) -> tuple[dict, dict, dict]:
    """The same motion at every table (delayed by k·lag at table k); seats follow the x motion
    of the nearest table."""
    lag_steps = check_lag(scene, dt, n)
    disp, vel, acc = {}, {}, {}
    for k, bent in zip(table_positions(scene), scene.bents):
        for axis in ("x", "y"):
            d, v, a = base[axis]
            ch = f"{bent.name}_{axis}"
            disp[ch], vel[ch], acc[ch] = (shift_record(x, k * lag_steps) for x in (d, v, a))
    for seat, bent in (("seat1_x", scene.bents[0]), ("seat2_x", scene.bents[-1])):
        src = f"{bent.name}_x"
        disp[seat], vel[seat], acc[seat] = disp[src], vel[src], acc[src]
    return disp, vel, acc


def _csv_components(exc: Excitation, csv: CsvRecord):
    """acc_x / acc_y columns of a CSV record [m/s²]: trailing empty cells end a component."""
    rec, t = csv.file, csv.t
    unknown = [c for c in csv.columns if c not in ("acc_x", "acc_y")]
    if unknown:
        raise SceneError(
            "excitation.file",
            f"{rec.path!r}: unknown column {unknown[0][:24]!r}; "
            f"an acceleration CSV holds {exc.time_column!r}, acc_x and acc_y",
        )
    if not np.all(np.isfinite(t)):
        i = int(np.argmin(np.isfinite(t)))
        raise SceneError("excitation.file", f"{rec.path!r}: row {i + 2} has no time stamp")
    acc, files = {}, {}
    for name, col in csv.columns.items():
        axis = name[-1]
        ok = np.isfinite(col)
        n = int(np.flatnonzero(ok)[-1]) + 1 if ok.any() else 0
        if not ok[:n].all():
            i = int(np.argmin(ok[:n]))
            raise SceneError(
                "excitation.file",
                f"{rec.path!r}: row {i + 2}, column {name!r} is "
                "empty inside the record (only a shorter component may end early)",
            )
        if n < MIN_SAMPLES:
            raise SceneError(
                "excitation.file",
                f"{rec.path!r}: column {name!r} holds {n} values; "
                f"at least {MIN_SAMPLES} are needed",
            )
        with np.errstate(over="ignore"):  # an overflow is refused by _check_raw_pga
            acc[axis] = col[:n] * ACC_UNITS[exc.acc_unit]
        files[axis] = rec
    dt = uniform_step(t, rec, lambda i: f"row {i + 2}")
    return acc, files, dt, []


def displacement_motion(scene: Scene, csv: CsvRecord) -> SupportMotion:
    """Motion of a CSV of support displacements ``<support>_disp`` [+ ``_vel``] (``disp_unit``).

    Every support needs a displacement column; unknown columns are refused (a misspelt name
    would otherwise be ignored). A missing velocity is derived by second-order differences; a
    given one must be the derivative of its displacement
    (:func:`~.record_checks.check_velocity_columns`).
    Time scaling: t × s, d × s², v × s (accelerations kept). Scaling to a PGA uses the
    acceleration the engines see, dv/dt by second-order differences. Processing must be
    ``none``: displacement histories (actuator commands) are used as given.
    """

    exc, rec, field = scene.excitation, csv.file, "excitation.file"
    if exc.scaling in PAIR_SCALINGS:
        raise SceneError(
            "excitation.scaling",
            f"{exc.scaling!r} scales a ground-acceleration pair; {rec.path!r} holds support "
            "displacements (use scaling = 'pga', 'factor' or 'none')",
        )
    if exc.processing != "none":
        raise SceneError(
            "excitation.processing",
            f"{rec.path!r} holds displacements, used as "
            f"given; processing must be 'none', got {exc.processing!r}",
        )
    channels = support_channels(scene)
    allowed = {f"{c}_disp" for c in channels} | {f"{c}_vel" for c in channels}
    for col in csv.columns:
        if col not in allowed:
            raise SceneError(
                field,
                f"unknown column {col[:24]!r}; expected {exc.time_column!r} "
                "and acc_x / acc_y, or <support>_disp / <support>_vel for supports "
                f"{', '.join(channels)}",
            )
    for c in channels:
        if f"{c}_disp" not in csv.columns:
            raise SceneError(field, f"support {c!r} has no record (column '{c}_disp' missing)")
    check_time_base(csv.t, field)
    for name, col in {exc.time_column: csv.t, **csv.columns}.items():
        if not np.all(np.isfinite(col)):
            row = int(np.argmin(np.isfinite(col)))
            raise SceneError(
                field,
                f"value in row {row + 2}, column {name[:24]!r} is missing or "
                "not finite (records of mismatched length?)",
            )
    check_velocity_columns(csv, channels, exc.disp_unit)
    if csv.t[0] != 0.0:
        rec.note(f"time starts at {csv.t[0]:g} s; the record is shifted to start at 0 s")
    s = exc.time_scale
    f = LENGTH_UNITS[exc.disp_unit]
    with np.errstate(all="ignore"):  # overflow is refused by support_motion
        t = (csv.t - csv.t[0]) * s
        if not np.all(np.isfinite(t)):
            raise SceneError(field, "the time stamps overflow to a non-finite value")
        disp = {c: csv.columns[f"{c}_disp"] * f * s * s for c in channels}
        vel = {
            c: (
                csv.columns[f"{c}_vel"] * f * s
                if f"{c}_vel" in csv.columns
                else np.gradient(disp[c], t)
            )
            for c in channels
        }
        peaks = {
            axis: max(
                float(np.max(np.abs(np.gradient(vel[c], t))))
                for c in channels
                if c.endswith(f"_{axis}")
            )
            / G
            for axis in ("x", "y")
        }
    fields = {"x": field, "y": field}
    _check_raw_pga(
        exc, peaks, fields, f"derived from displacements in {exc.disp_unit}, time scale {s:g}"
    )
    factors, targets = _factors(exc, peaks, fields)
    scaled = scaling_note(exc, peaks, factors, targets)
    for c in channels:
        k = factors[c[-1]]
        disp[c], vel[c] = disp[c] * k, vel[c] * k
    steps = np.diff(t)
    uniform = bool(np.all(np.abs(steps - steps.mean()) <= 0.01 * steps.mean()))
    prov = make_provenance(
        exc,
        files={"csv": rec.info()},
        header={},
        npts={"csv": rec.npts},
        dt_record=float(steps.mean() / s) if uniform else None,
        dt=float(steps.mean()) if uniform else None,
        duration=float(t[-1]),
        processing="none (displacements used as given)",
        targets=targets,
        factors=factors,
        notes=list(rec.notes) + ([scaled] if scaled else []),
    )
    _record_peaks(prov, peaks)
    return SupportMotion(t=t, disp=disp, vel=vel, provenance=prov)

"""Writers of record files with the quirks real downloads have (issue 13), and scenes using them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from deckpound.models.scene_io import load_scene

DT = 0.01
STATION = "Northridge-01, 1/17/1994, LA - Century City CC North, 090"


def quake(
    n: int = 800, dt: float = DT, f: float = 2.0, peak: float = 0.3, seed: int = 0
) -> np.ndarray:
    """An earthquake-like, processed acceleration [g] with max|a| = peak: the second
    derivative of a displacement (enveloped chirp plus a little smoothed noise) that starts and
    ends at rest, so its trapezoidal integral does not drift."""
    t = np.arange(n) * dt
    s = t / t[-1]
    env = (np.sin(np.pi * s) ** 2) * np.exp(-3 * s)
    noise = np.convolve(np.random.default_rng(seed).standard_normal(n), np.ones(5) / 5, "same")
    d = env * (np.sin(2 * np.pi * f * t * (1 + 0.3 * s)) + 0.1 * noise)
    a = np.gradient(np.gradient(d, dt), dt)
    return peak * a / np.max(np.abs(a))


def fortran(v: float) -> str:
    """A value as old Fortran writes it: '-.1234567E-02' (no leading zero), 15 wide."""
    s = f"{v:.6E}"  # -1.234567E-03 -> -.1234567E-02
    sign = "-" if s.startswith("-") else " "
    mant, exp = s.lstrip("-").split("E")
    digits = mant.replace(".", "")
    e = int(exp) + 1 if v != 0.0 else 0
    return f"{sign}.{digits}E{e:+03d}".rjust(15)


def write_at2(
    path: Path,
    acc,
    dt: float = DT,
    style: str = "nga",
    npts: int | None = None,
    line4: str | None = None,
    extra: list[str] | None = None,
    unit_line: str = "ACCELERATION TIME SERIES IN UNITS OF G",
) -> Path:
    """A PEER AT2 file: 'nga' (NGA-West2: NPTS=, DT=) or 'old' ('n dt NPTS, DT') header."""
    acc = list(acc)
    n = len(acc) if npts is None else npts
    if line4 is None:
        line4 = (
            f"NPTS=   {n}, DT=   {dt:.4f} SEC"
            if style == "nga"
            else f"  {n}   {dt:.4f}    NPTS, DT"
        )
    fmt = (lambda v: f"{v:15.7E}") if style == "nga" else fortran
    body = ["".join(fmt(v) for v in acc[i : i + 5]) for i in range(0, len(acc), 5)]
    head = ["PEER NGA STRONG MOTION DATABASE RECORD", STATION, unit_line, line4]
    path.write_text("\n".join(head + body + (extra or [])) + "\n")
    return path


def write_text(path: Path, t, a, sep: str = " ", header: list[str] | None = None) -> Path:
    rows = [f"{float(ti)!r}{sep}{float(ai)!r}" for ti, ai in zip(t, a)]
    path.write_text("\n".join((header or []) + rows) + "\n")
    return path


def write_acc_csv(path: Path, t, ax=None, ay=None) -> Path:
    """A CSV of ground accelerations; a shorter column ends with empty cells."""
    cols = {"t": list(t)}
    if ax is not None:
        cols["acc_x"] = list(ax)
    if ay is not None:
        cols["acc_y"] = list(ay)
    rows = [",".join(cols)]
    for k in range(len(t)):
        rows.append(",".join(repr(float(v[k])) if k < len(v) else "" for v in cols.values()))
    path.write_text("\n".join(rows) + "\n")
    return path


def record_scene(kind: str = "at2", file_x=None, file_y=None, file=None, *overrides: str):
    """The benchmark with a record (absolute paths) and extra ``path=value`` overrides."""
    sets = [f"excitation.kind={kind}"]
    for key, value in (("file_x", file_x), ("file_y", file_y), ("file", file)):
        if value is not None:
            sets.append(f"excitation.{key}={json.dumps(str(value))}")
    return load_scene("saiidi-4span", sets + list(overrides))


def synthetic_suite(folder: Path, pairs: int, seed: int = 0, duration: float = 20.0) -> Path:
    """``pairs`` PEER-named AT2 station pairs of the benchmark's synthetic generator
    (:func:`deckpound.compare.studies.ida.synthetic_pairs`)."""
    from deckpound.compare.studies.ida import synthetic_pairs

    return synthetic_pairs(load_scene("saiidi-4span"), folder, pairs, seed, duration)

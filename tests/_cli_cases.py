"""Bad-input cases of the CLI tests (``tests/test_cli.py``): each a scene override (or a CSV
record written with one defect) that every command must refuse with exit 2 and one line
naming the field."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from deckpound.models.plan import support_channels
from deckpound.models.scene import CONTACT_LAWS
from deckpound.models.scene_io import load_scene


def _csv_scene_args(tmp_path: Path, mutate) -> list[str]:
    """--set arguments for a CSV record of the benchmark, written with ``mutate`` applied."""
    channels = support_channels(load_scene("saiidi-4span"))
    t = np.arange(30) * 0.01
    cols = {"t": list(t)}
    for i, c in enumerate(channels):
        cols[f"{c}_disp"] = list(1e-3 * np.sin((i + 1) * t))
        cols[f"{c}_vel"] = list(1e-3 * (i + 1) * np.cos((i + 1) * t))
    mutate(cols)
    rows = [",".join(cols)]
    for k in range(max(len(v) for v in cols.values())):
        rows.append(",".join(repr(float(v[k])) if k < len(v) else "" for v in cols.values()))
    path = tmp_path / "records" / "rec.csv"
    path.parent.mkdir(exist_ok=True)
    path.write_text("\n".join(rows) + "\n")
    return ["--set", "excitation.kind=csv", "--set", f"excitation.file={json.dumps(str(path))}"]


def _decreasing(cols):
    cols["t"][5], cols["t"][6] = cols["t"][6], cols["t"][5]


def _duplicate(cols):
    cols["t"][7] = cols["t"][6]


def _short_column(cols):
    cols["bent2_x_vel"] = cols["bent2_x_vel"][:-3]


def _no_record(cols):
    del cols["bent3_y_disp"], cols["bent3_y_vel"]


def _unknown_column(cols):
    cols["bent1_x_dips"] = cols["bent1_x_disp"]


def _nan_cell(cols):
    cols["seat1_x_disp"][4] = float("nan")


# (case id, extra arguments or a callable(tmp_path) -> arguments, field, texts in the message)
BAD_SETS = [
    ("mass-zero", ["--set", "deck.mass=0"], "deck.mass", "must be > 0.0 t, got 0.0"),
    ("inertia-negative", ["--set", "seats[0].inertia=-0.1"], "seats[0].inertia", "> 0.0", "-0.1"),
    ("deck-inertia-zero", ["--set", "deck.inertia=0"], "deck.inertia", "> 0.0"),
    (
        "stiffness-negative",
        ["--set", "bents[1].y.stiffness=-5"],
        "bents[1].y.stiffness",
        "> 0.0 kN/m",
        "-5",
    ),
    ("seat-stiffness-zero", ["--set", "seats[1].kx=0"], "seats[1].kx", "> 0.0 kN/m"),
    ("contact-stiffness-zero", ["--set", "contact.stiffness=0"], "contact.stiffness", "> 0.0"),
    ("gap-negative", ["--set", "seats[1].gap=-0.01"], "seats[1].gap", ">= 0.0 m, got -0.01"),
    (
        "restitution-above-1",
        ["--set", "contact.restitution=1.5"],
        "contact.restitution",
        "<= 1.0",
        "1.5",
    ),
    (
        "restitution-below-0",
        ["--set", "contact.restitution=-0.2"],
        "contact.restitution",
        ">= 0.0",
        "-0.2",
    ),
    ("friction-negative", ["--set", "contact.friction=-0.3"], "contact.friction", ">= 0.0", "-0.3"),
    ("mass-nan", ["--set", "deck.mass=nan"], "deck.mass", "finite", "nan"),
    ("stiffness-inf", ["--set", "contact.stiffness=inf"], "contact.stiffness", "finite", "inf"),
    ("gap-minus-inf", ["--set", "seats[0].gap=-inf"], "seats[0].gap", "finite"),
    ("mass-huge", ["--set", "deck.mass=1e300"], "deck.mass", "1e+30"),
    ("mass-huge-int", ["--set", "deck.mass=1" + "0" * 400], "deck.mass", "too large"),
    (
        "unknown-law",
        ["--set", "contact.law=hertzz"],
        "contact.law",
        "'hertzz'",
        "allowed: " + ", ".join(CONTACT_LAWS),  # every row of the contact-law table
    ),
    (
        "misspelt-key-set",
        ["--set", "contact.stifness=2e6"],
        "contact.stifness",
        "did you mean 'stiffness'",
    ),
    (
        "unknown-key-set",
        ["--set", "deck.colour=1"],
        "deck.colour",
        "unknown key",
        "allowed: length, width",
    ),
    ("index-out-of-range", ["--set", "bents[5].station=1"], "bents[5].station", "out of range"),
    ("set-without-equals", ["--set", "deck.mass"], "--set", "PATH=VALUE"),
    ("damping-mode-too-high", ["--set", "damping.modes=[1, 9]"], "damping.modes", "<= 7"),
    (
        "record-too-short",
        ["--set", "excitation.duration=0.01"],
        "excitation.duration",
        "at least 16",
    ),
    ("lag-beyond-record", ["--set", "excitation.lag=30"], "excitation.lag", "beyond the record"),
    (
        "csv-decreasing-time",
        lambda p: _csv_scene_args(p, _decreasing),
        "excitation.file",
        "decreasing",
    ),
    (
        "csv-duplicate-time",
        lambda p: _csv_scene_args(p, _duplicate),
        "excitation.file",
        "duplicate",
    ),
    (
        "csv-mismatched-length",
        lambda p: _csv_scene_args(p, _short_column),
        "excitation.file",
        "'bent2_x_vel'",
        "missing or not finite",
    ),
    (
        "csv-support-without-record",
        lambda p: _csv_scene_args(p, _no_record),
        "excitation.file",
        "support 'bent3_y' has no record",
    ),
    (
        "csv-unknown-column",
        lambda p: _csv_scene_args(p, _unknown_column),
        "excitation.file",
        "unknown column 'bent1_x_dips'",
    ),
    (
        "csv-nan",
        lambda p: _csv_scene_args(p, _nan_cell),
        "excitation.file",
        "'seat1_x_disp'",
        "not finite",
    ),
    (
        "csv-missing-file",
        ["--set", "excitation.kind=csv", "--set", "excitation.file=nofile.csv"],
        "excitation.file",
        "does not exist",
    ),
]

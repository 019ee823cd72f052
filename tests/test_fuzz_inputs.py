"""Hypothesis-driven malformed inputs against the loaders and the CLI (issue: bad input).

Every malformed scene (TOML), record (CSV, PEER AT2, two-column text) or ``--set`` override
must end in exit status 0 (it happened to be valid) or exit status 2 with exactly one stderr
line starting ``deckpound: error:`` — never an exception escaping ``main``, never exit status 1, never a
traceback. When a malformed record is accepted, the loaded motion must be finite.

Bounded for CI: 100 examples per property, no deadline; the whole file runs in well under a
minute. The CLI runs in-process (``main(argv)``) with stdout/stderr redirected.
"""

from __future__ import annotations

import io
import json
import os
import sys
import warnings
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest
from _fuzz_corpus import BAD_PATHS
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from deckpound.cli import main
from deckpound.models.fields import to_mapping
from deckpound.models.plan import support_channels
from deckpound.models.scene_io import load_scene

# DECKPOUND_FUZZ_EXAMPLES=3000 for a long hunt; 100 per property by default
FUZZ = settings(
    max_examples=int(os.environ.get("DECKPOUND_FUZZ_EXAMPLES", "100")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
SHORT = "excitation.duration=2"  # keep the synthetic record short: fast validation


def _show_on_stderr(message, category, filename, lineno, file=None, line=None):
    sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    """main(argv) in-process: (exit status, stdout, stderr). Exceptions propagate (= a bug).

    Warnings are printed on stderr as the real command prints them (pytest would otherwise
    collect them), so that a warning next to an error counts as a second line.
    """
    out, err = io.StringIO(), io.StringIO()
    with warnings.catch_warnings(), redirect_stdout(out), redirect_stderr(err):
        warnings.showwarning = _show_on_stderr
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def assert_contract(code: int, err: str, what: object = "", *, statistics: bool = True) -> None:
    """Exit 0 (stderr: warnings only) or exit 2 with one line 'deckpound: error: ...'.

    ``statistics``: record the outcome for ``pytest --hypothesis-show-statistics``.
    """
    if statistics:
        event(f"exit {code}")
        if code == 2 and ": " in err[18:]:
            event("refused: " + err[18:].split(": ", 1)[0].split("[")[0][:40])
    assert "Traceback" not in err, f"{what}: traceback on stderr:\n{err}"
    lines = err.splitlines()
    if code == 0:
        assert all(l.startswith("deckpound: warning:") for l in lines), f"{what}: {err!r}"
        return
    assert code == 2, f"{what}: exit status {code}, stderr {err!r}"
    assert len(lines) == 1, f"{what}: expected one stderr line, got {err!r}"
    assert lines[0].startswith("deckpound: error: "), f"{what}: {err!r}"
    assert len(lines[0]) > len("deckpound: error: ") + 5


# -- shared value strategies ---------------------------------------------------------------

SPECIAL_VALUES = [
    "nan",
    "inf",
    "-inf",
    "+inf",
    "-nan",
    "-1",
    "0",
    "-0.0",
    "1e308",
    "1e400",
    "-1e400",
    "1e-320",
    "5e-324",
    "1" + "0" * 30,
    "1" + "0" * 400,
    "[]",
    "[[]]",
    "[1]",
    "[1, 2, 3]",
    "[nan, 1]",
    "[1e400, 2]",
    "{}",
    "{a = 1}",
    '""',
    '" "',
    "true",
    "false",
    '"x"',
    '"linear"',
    "1979-05-27",
    "07:32:00",
    "0x10",
    "0o7",
    "0b1",
    "1_000",
    "'''a\nb'''",
    '"\\u0000"',
    '"a\\nb"',
    '["a", 1]',
    "9" * 25,
]

toml_values = st.one_of(
    st.sampled_from(SPECIAL_VALUES),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(min_value=-(10**30), max_value=10**30).map(str),
    st.text(max_size=12).map(json.dumps),  # a valid TOML string
    st.text(max_size=12),  # junk (often not TOML at all)
)


# -- (a) TOML scene files ------------------------------------------------------------------


@pytest.fixture(scope="module")
def bench_toml() -> str:
    code, out, err = run_cli(["scene", "show", "saiidi-4span", "--set", SHORT])
    assert code == 0 and not err
    return out


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


def _toml_mutation(data: st.DataObject, lines: list[str]) -> list[str]:
    kind = data.draw(
        st.sampled_from(
            ["delete", "replace", "replace", "duplicate", "insert", "truncate", "bytes", "swap"]
        )
    )
    lines = list(lines)
    i = data.draw(st.integers(0, max(0, len(lines) - 1)))
    if kind == "delete" and lines:
        del lines[i]
    elif kind == "replace":
        keyed = [j for j, l in enumerate(lines) if " = " in l]
        if keyed:
            j = data.draw(st.sampled_from(keyed))
            key = lines[j].split(" = ", 1)[0]
            lines[j] = f"{key} = {data.draw(toml_values)}"
    elif kind == "duplicate" and lines:
        lines.insert(i, lines[i])
    elif kind == "insert":
        key = data.draw(st.from_regex(r"[a-z_][a-z_0-9]{0,12}", fullmatch=True))
        lines.insert(i, f"{key} = {data.draw(toml_values)}")
    elif kind == "truncate":
        text = "\n".join(lines)
        cut = data.draw(st.integers(0, len(text)))
        lines = text[:cut].split("\n")
    elif kind == "bytes":
        junk = data.draw(st.binary(min_size=1, max_size=20)).decode("latin-1")
        lines.insert(i, junk)
    elif kind == "swap" and len(lines) > 1:
        k = data.draw(st.integers(0, len(lines) - 1))
        lines[i], lines[k] = lines[k], lines[i]
    return lines


@FUZZ
@given(data=st.data())
def test_mutated_scene_toml(bench_toml, workdir, data):
    lines = bench_toml.splitlines()
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        lines = _toml_mutation(data, lines)
    raw = "\n".join(lines).encode("utf-8", "surrogateescape")
    if data.draw(st.integers(0, 9), label="whole file random bytes") == 0:
        raw = data.draw(st.binary(max_size=200))
    path = workdir / "scene.toml"
    path.write_bytes(raw)
    code, out, err = run_cli(["scene", "validate", str(path)])
    assert_contract(code, err, raw[:300])
    if code == 0:
        assert ": valid;" in out


# -- records: see test_records_fuzz.py (CSV, PEER AT2, two-column text) ---------------------


@pytest.fixture(scope="module")
def channels() -> tuple[str, ...]:
    return support_channels(load_scene("saiidi-4span"))


AT2_HEADER = [
    "PEER NGA STRONG MOTION DATABASE RECORD",
    "Northridge-01, 1/17/1994, LA - Century City CC North, 090",
    "ACCELERATION TIME SERIES IN UNITS OF G",
]


# -- (d) --set overrides -------------------------------------------------------------------


def _dotted_paths(obj, prefix: str = "") -> list[str]:
    out = []
    if isinstance(obj, dict):
        for k, v in obj.items():
            out += _dotted_paths(v, f"{prefix}.{k}" if prefix else k)
    elif isinstance(obj, list) and obj and isinstance(obj[0], dict):
        for i, v in enumerate(obj):
            out += _dotted_paths(v, f"{prefix}[{i}]")
    else:
        out.append(prefix)
    return out


VALID_PATHS = [
    p for p in _dotted_paths(to_mapping(load_scene("saiidi-4span"))) if not p.startswith("notes.")
]
# paths whose random values could make a validation expensive (huge records) stay legal but
# are drawn less often: they are in the list once like every other path.

path_strategy = st.one_of(
    st.sampled_from(VALID_PATHS),
    st.sampled_from(VALID_PATHS).map(lambda p: p[:-1]),  # misspelt last letter
    st.sampled_from(VALID_PATHS).map(lambda p: p + ".x"),  # below a leaf
    st.sampled_from(VALID_PATHS).map(lambda p: p.replace("[0]", "[7]")),
    st.sampled_from(VALID_PATHS).map(lambda p: p.rsplit(".", 1)[0]),  # a whole table
    st.sampled_from([*BAD_PATHS, "deck.mass ", "damping.modes[0]", "damping.modes[5]"]),
    st.text(max_size=15),
)


@FUZZ
@given(
    overrides=st.lists(st.tuples(path_strategy, toml_values), min_size=1, max_size=3),
    no_equals=st.booleans(),
)
def test_random_set_overrides(overrides, no_equals):
    items = [f"{p}={v}" for p, v in overrides]
    if no_equals:
        items[0] = items[0].replace("=", "")
    args = ["scene", "validate", "saiidi-4span", "--set", SHORT]
    for item in items:
        args += ["--set", item]
    code, _out, err = run_cli(args)
    assert_contract(code, err, items)


# -- regressions: the crashes and silent NaN the fuzzing found -----------------------------


def _at2(path: Path, values, header4: str | None = None, dt: str = ".0100") -> Path:
    values = list(values)
    body = ["  ".join(f"{v: .7E}" for v in values[i : i + 5]) for i in range(0, len(values), 5)]
    line4 = header4 if header4 is not None else f"NPTS=   {len(values)}, DT=   {dt} SEC"
    path.write_text("\n".join(AT2_HEADER + [line4] + body) + "\n")
    return path


def _wave(n: int = 200) -> np.ndarray:
    t = np.arange(n) * 0.01
    return 0.3 * np.sin(2 * np.pi * 2.0 * t) * np.exp(-(((t - 1.0) / 0.5) ** 2))


def _csv(path: Path, text: str) -> list[str]:
    path.write_text(text)
    return ["--set", "excitation.kind=csv", "--set", f"excitation.file={json.dumps(str(path))}"]


def _csv_text(channels, t, extra_cell: bool = False, bool_col: bool = False) -> str:
    header = ["t"] + [f"{c}_disp" for c in channels]
    rows = [",".join(header)]
    for _k, tk in enumerate(t):
        cells = [repr(tk)] + ["0.001"] * len(channels)
        if bool_col:
            cells[1] = "True"
        if extra_cell:
            cells.append("0.5")
        rows.append(",".join(cells))
    return "\n".join(rows) + "\n"


REGRESSIONS = [
    # (id, builder(tmp_path, channels) -> extra args, field, text) ; was: what happened before
    (
        "int-too-large-for-float",
        lambda p, c: ["--set", "deck.mass=1" + "0" * 400],
        "deck.mass",
        "too large",
    ),  # OverflowError
    (
        "subnormal-inertia",
        lambda p, c: ["--set", "deck.inertia=1e-320"],
        "deck.inertia",
        "1e-30",
    ),  # silent NaN periods
    (
        "tiny-dt",
        lambda p, c: ["--set", "excitation.dt=1e-12"],
        "excitation.dt",
        "at most",
    ),  # ValueError (size)
    (
        "record-shorter-than-filter",
        lambda p, c: ["--set", "excitation.duration=0.02"],
        "excitation.duration",
        "at least 16",
    ),  # scipy ValueError
    (
        "pulse-tiny-dt",
        lambda p, c: ["--set", "excitation.kind=pulse", "--set", "excitation.dt=1e-9"],
        "excitation.dt",
        "at most",
    ),  # MemoryError
    (
        "highpass-below-filter-range",
        lambda p, c: ["--set", "excitation.highpass=1e-9"],
        "excitation.highpass",
        "must lie between",
    ),  # LinAlgError
    (
        "dominant-frequency-huge",
        lambda p, c: ["--set", "excitation.dominant_frequency=1e300"],
        "excitation.dominant_frequency",
        "1e+30",
    ),  # OverflowError
    (
        "lag-beyond-record",
        lambda p, c: ["--set", "excitation.lag=5"],
        "excitation.lag",
        "beyond the record",
    ),  # arrays of wrong length
    (
        "damping-mode-beyond-7",
        lambda p, c: ["--set", "damping.modes=[2, 8]"],
        "damping.modes",
        "<= 7",
    ),  # accepted by validate
    (
        "at2-dt-not-a-number",
        lambda p, c: _at2_args(_at2(p / "x.at2", _wave(), dt="1.2.3"), p),
        "excitation.file_x",
        "line 4 must give NPTS and DT as numbers",
    ),  # ValueError
    (
        "at2-too-few-values",
        lambda p, c: _at2_args(_at2(p / "x.at2", _wave(5)), p),
        "excitation.file_x",
        "at least 16",
    ),  # scipy ValueError
    (
        "at2-overflow",
        lambda p, c: _at2_args(_at2(p / "x.at2", _wave() * 1e308), p),
        "excitation.file_x",
        "non-finite",
    ),  # warning + silent NaN
    (
        "csv-time-overflow",
        lambda p, c: _csv(p / "r.csv", _csv_text(c, [-1.5e308, 0.0, 1.5e308])),
        "excitation.file",
        "non-finite",
    ),  # silent inf time base
    (
        "csv-rows-longer-than-header",
        lambda p, c: _csv(p / "r.csv", _csv_text(c, [0.0, 0.01, 0.02], extra_cell=True)),
        "excitation.file",
        "more values than the header",
    ),  # columns shifted silently
    (
        "csv-true-false-column",
        lambda p, c: _csv(p / "r.csv", _csv_text(c, [0.0, 0.01, 0.02], bool_col=True)),
        "excitation.file",
        "true/false",
    ),  # read as 1.0
]


def _at2_args(path_x: Path, folder: Path) -> list[str]:
    path_y = _at2(folder / "y.at2", _wave())
    return [
        "--set",
        "excitation.kind=at2",
        "--set",
        f"excitation.file_x={json.dumps(str(path_x))}",
        "--set",
        f"excitation.file_y={json.dumps(str(path_y))}",
    ]


@pytest.mark.parametrize(
    "build,field,text", [r[1:] for r in REGRESSIONS], ids=[r[0] for r in REGRESSIONS]
)
def test_found_by_fuzzing(tmp_path, channels, build, field, text):
    args = ["scene", "validate", "saiidi-4span", "--set", SHORT, *build(tmp_path, channels)]
    code, out, err = run_cli(args)
    assert_contract(code, err, args, statistics=False)
    assert code == 2, out
    assert err.startswith(f"deckpound: error: {field}: ") and text in err, err

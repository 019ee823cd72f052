"""Hypothesis-driven malformed records against the loaders and the CLI (issues 13 and 16).

CSV (support displacements or ground accelerations, a shorter component), PEER AT2 (both
header generations, values beyond NPTS, an unequal or missing partner component, processing
and time scaling) and two-column text records, mutated: each must end in exit status 0 with
warnings only (a tolerance, stated) or exit status 2 with exactly one ``deckpound: error:``
line; an accepted record gives a finite motion. Same contract and budget as
``test_fuzz_inputs.py`` (100 examples per property; DECKPOUND_FUZZ_EXAMPLES for a long hunt).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_fuzz_inputs import AT2_HEADER, FUZZ, assert_contract, run_cli

from deckpound.models.excitation import support_motion
from deckpound.models.plan import support_channels
from deckpound.models.scene_io import load_scene


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz_records")


# -- (b) CSV records -----------------------------------------------------------------------


@pytest.fixture(scope="module")
def channels() -> tuple[str, ...]:
    return support_channels(load_scene("saiidi-4span"))


def _base_csv(channels, n: int = 40, dt: float = 0.01) -> list[list[str]]:
    t = np.arange(n) * dt
    header = ["t"] + [f"{c}_{q}" for c in channels for q in ("disp", "vel")]
    rows = [header]
    for k in range(n):
        row = [repr(float(t[k]))]
        for i, _ in enumerate(channels):
            w = i + 1
            row += [repr(1e-3 * np.sin(w * t[k])), repr(1e-3 * w * np.cos(w * t[k]))]
        rows.append(row)
    return rows


def _base_acc_csv(n: int = 60, dt: float = 0.01) -> list[list[str]]:
    """A CSV of ground accelerations [g]: t, acc_x, acc_y."""
    t = np.arange(n) * dt
    a = 0.3 * np.sin(2 * np.pi * 2.0 * t) * np.exp(-(((t - 0.3) / 0.15) ** 2))
    return [["t", "acc_x", "acc_y"]] + [
        [repr(float(t[k])), repr(float(a[k])), repr(float(-0.5 * a[k]))] for k in range(n)
    ]


CELL_JUNK = [
    "nan",
    "NaN",
    "inf",
    "-inf",
    "",
    " ",
    "abc",
    "1e400",
    "-1e400",
    "1e308",
    "1e-320",
    "0x1",
    "True",
    "false",
    "1,2",
    '"1"',
    "1.2.3",
    "--1",
    "1e",
    "é",
    "\x00",
    "∞",
    "1_000",
    "NULL",
    "#",
    "'",
    '"',
]


def _csv_mutation(data: st.DataObject, rows: list[list[str]]) -> list[list[str]]:
    kind = data.draw(
        st.sampled_from(
            [
                "drop_col",
                "cell",
                "cell",
                "shuffle_t",
                "dup_t",
                "swap_t",
                "short_row",
                "long_row",
                "extra_col",
                "drop_rows",
                "rename_col",
                "huge_t",
            ]
        )
    )
    rows = [list(r) for r in rows]
    if not rows or not rows[0]:
        return rows
    ncol = len(rows[0])
    if kind == "drop_col" and ncol > 1:
        j = data.draw(st.integers(0, ncol - 1))
        rows = [r[:j] + r[j + 1 :] for r in rows]
    elif kind == "cell" and len(rows) > 1:
        i = data.draw(st.integers(1, len(rows) - 1))
        j = data.draw(st.integers(0, len(rows[i]) - 1)) if rows[i] else 0
        value = data.draw(
            st.one_of(st.sampled_from(CELL_JUNK), st.text(max_size=6), st.floats().map(repr))
        )
        if rows[i]:
            rows[i][j] = value
    elif kind in ("shuffle_t", "dup_t", "swap_t", "huge_t") and len(rows) > 2:
        t = [r[0] if r else "" for r in rows[1:]]
        if kind == "shuffle_t":
            t = data.draw(st.permutations(t))
        elif kind == "dup_t":
            i = data.draw(st.integers(1, len(t) - 1))
            t[i] = t[i - 1]
        elif kind == "swap_t":
            i = data.draw(st.integers(1, len(t) - 1))
            t[i], t[i - 1] = t[i - 1], t[i]
        else:
            t = [f"{x}e306" for x in t]
        for r, x in zip(rows[1:], t):
            if r:
                r[0] = x
    elif kind == "short_row" and len(rows) > 1:
        i = data.draw(st.integers(1, len(rows) - 1))
        rows[i] = rows[i][: data.draw(st.integers(0, len(rows[i])))]
    elif kind == "long_row" and len(rows) > 1:
        i = data.draw(st.integers(1, len(rows) - 1))
        rows[i] = rows[i] + ["0.0"] * data.draw(st.integers(1, 3))
    elif kind == "extra_col":
        name = data.draw(
            st.sampled_from(["bent9_x_disp", "t", "bent1_x_disp", "Unnamed: 0", "", "x"])
        )
        rows[0].append(name)
        for r in rows[1:]:
            r.append("0.0")
    elif kind == "drop_rows":
        keep = data.draw(st.integers(0, len(rows)))
        rows = rows[:keep]
    elif kind == "rename_col" and ncol:
        j = data.draw(st.integers(0, ncol - 1))
        rows[0][j] = data.draw(st.text(max_size=8))
    return rows


@FUZZ
@given(data=st.data())
def test_malformed_csv_record(channels, workdir, data):
    acc_mode = data.draw(st.booleans(), label="acceleration columns")
    rows = _base_acc_csv() if acc_mode else _base_csv(channels)
    if acc_mode and data.draw(st.booleans(), label="shorter acc_y"):
        cut = data.draw(st.integers(1, len(rows) - 1))
        rows = [r if k <= cut else r[:2] + [""] for k, r in enumerate(rows)]
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        rows = _csv_mutation(data, rows)
    text = "".join(",".join(r) + "\n" for r in rows).encode("utf-8", "surrogateescape")
    special = data.draw(st.sampled_from(["none"] * 6 + ["empty", "junk", "truncate", "header"]))
    if special == "empty":
        text = b""
    elif special == "junk":
        text = data.draw(st.binary(max_size=300))
    elif special == "truncate":
        text = text[: data.draw(st.integers(0, len(text)))]
    elif special == "header":
        text = text.split(b"\n", 1)[0] + b"\n"
    path = workdir / "record.csv"
    path.write_bytes(text)
    unit = data.draw(st.sampled_from(["m", "mm", "in"]))
    acc_unit = data.draw(st.sampled_from(["g", "m/s^2", "cm/s^2"]))
    args = [
        "scene",
        "validate",
        "saiidi-4span",
        "--set",
        "excitation.kind=csv",
        "--set",
        f"excitation.file={json.dumps(str(path))}",
        "--set",
        f"excitation.disp_unit={unit}",
        "--set",
        f"excitation.acc_unit={acc_unit}",
    ]
    code, _out, err = run_cli(args)
    assert_contract(code, err, text[:300])
    if code == 0:  # accepted: every motion array finite, time strictly increasing from 0
        motion = support_motion(load_scene("saiidi-4span", args[4::2]))
        assert motion.t[0] == 0.0 and np.all(np.diff(motion.t) > 0)
        for arrays in (motion.disp, motion.vel):
            assert set(arrays) == set(channels)
            assert all(np.all(np.isfinite(x)) for x in arrays.values())


# -- (c) PEER AT2 records ------------------------------------------------------------------


def _at2_lines(n: int = 200, dt: float = 0.01) -> list[str]:
    t = np.arange(n) * dt
    acc = 0.3 * np.sin(2 * np.pi * 2.0 * t) * np.exp(-(((t - 1.0) / 0.5) ** 2))
    body = ["  ".join(f"{v: .7E}" for v in acc[i : i + 5]) for i in range(0, n, 5)]
    return AT2_HEADER + [f"NPTS=   {n}, DT=   {dt:.4f} SEC"] + body


dt_tokens = st.one_of(
    st.sampled_from(
        [
            "-0.01",
            "0",
            "0.0",
            ".",
            "-",
            "e",
            "1e",
            "1.2.3",
            "+-1",
            "1e400",
            "1e-400",
            "..01",
            "0.01",
            "1e-30",
            "E5",
            "--",
        ]
    ),
    st.text(alphabet="0123456789.eE+-", min_size=1, max_size=8),
)


def _at2_mutation(data: st.DataObject, lines: list[str]) -> list[str]:
    kind = data.draw(
        st.sampled_from(
            [
                "line4",
                "line4",
                "npts",
                "dt",
                "old_format",
                "token",
                "token",
                "delete",
                "append",
                "unicode",
                "drop_header",
                "extra_values",
                "unit_line",
            ]
        )
    )
    lines = list(lines)
    n = 200
    if kind == "line4":
        lines[3] = data.draw(st.text(max_size=40))
    elif kind == "npts":
        lines[3] = f"NPTS=   {data.draw(st.integers(0, 10**6))}, DT=   .0100 SEC"
    elif kind == "dt":
        lines[3] = f"NPTS=   {n}, DT=   {data.draw(dt_tokens)} SEC"
    elif kind == "old_format":
        lines[3] = f"{data.draw(st.integers(0, 400))} {data.draw(dt_tokens)} NPTS, DT"
    elif kind == "token" and len(lines) > 4:
        i = data.draw(st.integers(4, len(lines) - 1))
        toks = lines[i].split() or ["0"]
        j = data.draw(st.integers(0, len(toks) - 1))
        toks[j] = data.draw(
            st.one_of(
                st.sampled_from(
                    ["nan", "inf", "-inf", "1e400", "abc", "1,0", "0x1", "1.2.3", "", "1e308"]
                ),
                st.text(max_size=5),
            )
        )
        lines[i] = "  ".join(toks)
    elif kind == "delete" and len(lines) > 4:
        del lines[data.draw(st.integers(0, len(lines) - 1))]
    elif kind == "append":
        lines.append(data.draw(st.text(max_size=30)))
    elif kind == "unicode":
        i = data.draw(st.integers(0, len(lines)))
        lines.insert(
            i,
            data.draw(
                st.text(
                    alphabet=st.characters(min_codepoint=0x80, exclude_categories=("Cs",)),
                    max_size=20,
                )
            ),
        )
    elif kind == "drop_header":
        lines = lines[data.draw(st.integers(1, 4)) :]
    elif kind == "extra_values":  # downloads hold a value or more beyond NPTS
        lines.append("  ".join(["1.0E-03"] * data.draw(st.integers(1, 15))))
    elif kind == "unit_line":
        lines[2] = data.draw(
            st.sampled_from(
                [
                    "VELOCITY TIME SERIES IN UNITS OF CM/S",
                    "ACCELERATION IN UNITS OF CM/S/S",
                    "DISPLACEMENT IN UNITS OF CM",
                    "UNITS OF G",
                ]
            )
        )
    return lines


@FUZZ
@given(data=st.data())
def test_malformed_at2_record(workdir, data):
    lines = _at2_lines()
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        lines = _at2_mutation(data, lines)
    raw = ("\n".join(lines) + "\n").encode("utf-8", "surrogateescape")
    special = data.draw(st.sampled_from(["none"] * 7 + ["empty", "junk", "truncate"]))
    if special == "empty":
        raw = b""
    elif special == "junk":
        raw = data.draw(st.binary(max_size=300))
    elif special == "truncate":
        raw = raw[: data.draw(st.integers(0, len(raw)))]
    path = workdir / "bad.at2"
    path.write_bytes(raw)
    partner = workdir / "partner.at2"  # the other component: as long or a few samples shorter
    partner.write_text(
        "\n".join(
            _at2_lines(200 - data.draw(st.sampled_from([0, 0, 1, 4]), label="partner shorter by"))
        )
        + "\n"
    )
    x_is_bad = data.draw(st.booleans(), label="bad file is x")
    fx, fy = (path, partner) if x_is_bad else (partner, path)
    pair = [f"excitation.file_x={json.dumps(str(fx))}", f"excitation.file_y={json.dumps(str(fy))}"]
    if data.draw(st.integers(0, 4), label="one direction only") == 0:
        pair = pair[:1] if x_is_bad else pair[1:]
    args = ["scene", "validate", "saiidi-4span", "--set", "excitation.kind=at2"]
    for item in pair + data.draw(
        st.sampled_from(
            [
                [],
                ["excitation.scaling=none"],
                ["excitation.processing=baseline"],
                ["excitation.time_scale=0.5"],
            ]
        )
    ):
        args += ["--set", item]
    code, _out, err = run_cli(args)
    assert_contract(code, err, raw[:300])
    if code == 0:
        motion = support_motion(load_scene("saiidi-4span", args[4::2]))
        for arrays in (motion.disp, motion.vel):
            assert all(np.all(np.isfinite(x)) for x in arrays.values())


# -- (c2) two-column text records -----------------------------------------------------------


def _text_lines(n: int = 120, dt: float = 0.01) -> list[str]:
    t = np.arange(n) * dt
    acc = 0.3 * np.sin(2 * np.pi * 2.0 * t) * np.exp(-(((t - 0.6) / 0.3) ** 2))
    return ["# station, event", "time acc"] + [f"{t[k]!r} {acc[k]!r}" for k in range(n)]


def _text_mutation(data: st.DataObject, lines: list[str]) -> list[str]:
    kind = data.draw(
        st.sampled_from(
            [
                "token",
                "token",
                "third",
                "drop",
                "jitter",
                "dup_time",
                "separator",
                "comment",
                "delete",
                "unicode",
                "blank",
                "titles",
            ]
        )
    )
    lines = list(lines)
    i = data.draw(st.integers(2, len(lines) - 1)) if len(lines) > 2 else 0
    if kind == "token" and len(lines) > 2:
        toks = lines[i].split() or ["0"]
        toks[data.draw(st.integers(0, len(toks) - 1))] = data.draw(
            st.one_of(
                st.sampled_from(["nan", "inf", "1e400", "abc", "1,0", "1.2.3", "", "1e308", "-0"]),
                st.text(max_size=5),
            )
        )
        lines[i] = " ".join(toks)
    elif kind == "third" and len(lines) > 2:
        lines[i] += " 0.5"
    elif kind == "drop" and len(lines) > 2:
        lines[i] = lines[i].split(" ")[0]
    elif kind in ("jitter", "dup_time") and len(lines) > 3:
        toks = lines[i].split()
        prev = lines[i - 1].split()
        if toks and prev:
            toks[0] = (
                prev[0]
                if kind == "dup_time"
                else repr(float(data.draw(st.floats(-1.0, 3.0, allow_nan=False))))
            )
            lines[i] = " ".join(toks)
    elif kind == "separator":
        sep = data.draw(st.sampled_from([",", ";", "\t", " , ", ",,"]))
        lines = [line.replace(" ", sep) for line in lines]
    elif kind == "comment":
        lines.insert(
            i, data.draw(st.sampled_from(["#", "%", "!"])) + data.draw(st.text(max_size=20))
        )
    elif kind == "delete" and lines:
        del lines[i]
    elif kind == "unicode":
        lines.insert(
            i,
            data.draw(
                st.text(
                    alphabet=st.characters(min_codepoint=0x80, exclude_categories=("Cs",)),
                    max_size=20,
                )
            ),
        )
    elif kind == "blank":
        lines.insert(i, "")
    elif kind == "titles":
        lines.insert(2, data.draw(st.text(alphabet="abcxyz _", max_size=12)))
    return lines


@FUZZ
@given(data=st.data())
def test_malformed_text_record(workdir, data):
    lines = _text_lines()
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        lines = _text_mutation(data, lines)
    raw = ("\n".join(lines) + "\n").encode("utf-8", "surrogateescape")
    special = data.draw(st.sampled_from(["none"] * 7 + ["empty", "junk", "truncate"]))
    if special == "empty":
        raw = b""
    elif special == "junk":
        raw = data.draw(st.binary(max_size=300))
    elif special == "truncate":
        raw = raw[: data.draw(st.integers(0, len(raw)))]
    path = workdir / "bad.txt"
    path.write_bytes(raw)
    unit = data.draw(st.sampled_from(["g", "m/s^2", "cm/s^2"]))
    args = [
        "scene",
        "validate",
        "saiidi-4span",
        "--set",
        "excitation.kind=text",
        "--set",
        f"excitation.file_y={json.dumps(str(path))}",
        "--set",
        f"excitation.acc_unit={unit}",
    ]
    code, _out, err = run_cli(args)
    assert_contract(code, err, raw[:300])
    if code == 0:
        motion = support_motion(load_scene("saiidi-4span", args[4::2]))
        assert motion.t[0] == 0.0 and np.all(np.diff(motion.t) > 0)
        for arrays in (motion.disp, motion.vel):
            assert all(np.all(np.isfinite(x)) for x in arrays.values())
        assert motion.provenance["applied_pga"]["y"] == pytest.approx(0.5, rel=1e-12)

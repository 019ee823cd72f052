"""The ``input`` family of the CLI fuzz corpus (:mod:`tests._fuzz_corpus`, issue 28 item 4).

unit slips       a gap or deck size in mm, a deck mass in kg: refused (exit 2) by validate and
                 run, and accepted with ``allow_extreme = true`` (validate only)
absurd values    a dimension of 1e30, μ = 100, a mass beyond any bridge: refused
control chars    ``--set`` overrides with a newline, carriage return, escape, tab, C1 control or
                 line separator in the key or the value: refused before anything is parsed
inconsistent     a CSV record whose velocity column is 1000 m/s next to its displacement
velocities       column: refused naming the column (exit 2)
"""

from __future__ import annotations

import numpy as np
from _fuzz_corpus import OUT, SHORT, Case

from deckpound.models.plan import support_channels
from deckpound.models.scene_io import load_scene

SLIPS = (
    "seats[0].gap=12.7",
    "seats[1].gap=25",
    "deck.mass=140500",
    "deck.width=2400",
    "deck.length=33500",
)
ABSURD = (
    "deck.width=1e30",
    "deck.length=1e30",
    "contact.friction=100",
    "deck.mass=2e7",
    "bents[0].x.ultimate_displacement=1e5",
)
CONTROL = (
    "deck.length=33.5\nfoo=1",
    "deck.length=33.5\r",
    'description="a\x1b[2Jb"',
    "deck.len\tgth=33.5",
    "name=x\x85",
    "deck.mass=140.5\u2028",
    "\x1b[31mdeck.mass=140.5",
)


def _csv_bytes(fast: bool) -> bytes:
    """A 0.3 s displacement record of the benchmark's supports (d = 1e-3 sin(k t), v its
    derivative); ``fast``: bent1_x_vel replaced by 1000 m/s."""
    t = np.arange(61) * 0.005
    cols = {"t": t}
    for k, c in enumerate(support_channels(load_scene("saiidi-4span")), start=1):
        cols[f"{c}_disp"] = 1e-3 * np.sin(k * t)
        cols[f"{c}_vel"] = 1e-3 * k * np.cos(k * t)
    if fast:
        cols["bent1_x_vel"] = np.full(len(t), 1000.0)
    rows = [",".join(cols)]
    rows += [",".join(repr(float(v[i])) for v in cols.values()) for i in range(len(t))]
    return ("\n".join(rows) + "\n").encode()


def _validate(cid: str, *sets: str, expect=(2,), nonsense=True, files=()) -> Case:
    argv = ("scene", "validate", "saiidi-4span", *SHORT)
    return Case(
        cid,
        "input",
        argv + tuple(a for s in sets for a in ("--set", s)),
        files=files,
        nonsense=nonsense,
        expect=expect,
    )


def _run(cid: str, *sets: str, files=()) -> Case:
    argv = ("run", "saiidi-4span", *SHORT, "--engine", "nonsmooth", "-o", OUT)
    return Case(
        cid,
        "input",
        argv + tuple(a for s in sets for a in ("--set", s)),
        files=files,
        target=OUT,
        target_kind="dir",
        nonsense=True,
        expect=(2,),
        weight=3,
    )


def input_family() -> list[Case]:
    cases = []
    for s in SLIPS + ABSURD:
        cases.append(_validate(f"input:validate:{s}", s))
        cases.append(_run(f"input:run:{s}", s))
    for s in SLIPS:  # forced: a warning, and the scene is valid
        cases.append(
            _validate(f"input:forced:{s}", s, "allow_extreme=true", expect=(0,), nonsense=False)
        )
    for s in CONTROL:
        cases.append(_validate(f"input:control:{s!r}", s))
        cases.append(_run(f"input:run-control:{s!r}", s))
    record = ("excitation.kind=csv", 'excitation.file="{tmp}/rec.csv"', "excitation.scaling=none")
    cases.append(
        _validate("input:csv-velocity-1000", *record, files=(("rec.csv", _csv_bytes(True)),))
    )
    cases.append(
        _run("input:run-csv-velocity-1000", *record, files=(("rec.csv", _csv_bytes(True)),))
    )
    cases.append(
        _validate(
            "input:csv-velocity-consistent",
            *record,
            files=(("rec.csv", _csv_bytes(False)),),
            expect=(0,),
            nonsense=False,
        )
    )
    return cases

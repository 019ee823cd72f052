"""The generated CLI fuzz corpus of issue 16: deterministic cases, no randomness at run time.

:func:`generate` returns every case (> 3,000), grouped in families:

============  ===============================================================================
set           ``scene validate`` with one ``--set PATH=VALUE`` per leaf field of the benchmark
              and per hostile value (NaN, ±inf, 2^63, 1e308, a 401-digit integer, wrong types)
file          ``scene validate`` of mutated TOML files: deep nesting (arrays, inline tables,
              headers, dotted keys), unknown keys in every table, tables replaced by scalars,
              tables and keys deleted, truncation, junk bytes, encodings
override      malformed ``--set`` paths and values
path          every output command against hostile ``-o`` targets: below a file, a file in
              place of a folder, symbolic links (to folders, files, nowhere), ``/proc``,
              ``/sys``, ``/dev/full``, existing folders (:mod:`tests._fuzz_outputs`)
fault         faults injected into a command: full disk at the k-th write or fsync, a failing
              rename, a read-only folder, ``EACCES``, out of memory, Ctrl-C, stdout full
              (:mod:`tests._fuzz_outputs`)
engine        steps and output rates against the analysis length (30 s step on a short record,
              output step longer than the run, record shorter than one step)
              (:mod:`tests._fuzz_run_families`, as the three below)
vtk           ``export-vtk`` of damaged result folders
name          hostile scene names (TeX, control characters) through every figure
option        bad option values (--workers, --every, --timeout, --scheduler, --engines)
script        ``export`` to hostile file names (braces, ``[exec ...]``, ``$``, quotes, newlines,
              ``~``, control and bidi characters) and hostile scene names validated and
              exported (:mod:`tests._fuzz_scripts`)
input         unit slips (a gap or deck size in mm, a deck mass in kg), absurd magnitudes,
              --set overrides with control characters, a CSV velocity column that is not
              its displacement's derivative: exit 2 (:mod:`tests._fuzz_magnitudes`)
stream        closed stdout and stderr: exit 3 only for output that cannot reach stdout
              (:mod:`tests._fuzz_run_families`)
============  ===============================================================================

Each :class:`Case` states its command line (``{tmp}`` is the case's own folder), the files,
folders and links to create first, an injected fault, the output it must leave whole or
absent, whether success would be silent nonsense, and (where the contract fixes it) the exit
statuses allowed. :mod:`tests._fuzz_run` runs and classifies them. Engine runs are tiny
(0.3 s records).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field

import tomli_w

from deckpound.models.fields import to_mapping
from deckpound.models.scene_io import load_scene, scene_to_toml

SHORT = ("--set", "excitation.duration=0.3")
ENGINE_NAMES = ("opensees", "compliance", "nonsmooth")
OUT = "{tmp}/out"


@dataclass(frozen=True)
class Case:
    """One fuzz case (see the module docstring)."""

    id: str
    family: str
    argv: tuple[str, ...]
    files: tuple[tuple[str, bytes], ...] = ()
    dirs: tuple[str, ...] = ()
    links: tuple[tuple[str, str], ...] = ()
    setup: tuple[str, ...] = ()  # named steps: "result" copies a tiny run into {tmp}/res
    fault: str = ""  # see tests._fuzz_outputs.FAULTS
    target: str = ""  # output path checked for partial output
    target_kind: str = ""  # "dir" | "file"
    nonsense: bool = False  # exit status 0 would be silent nonsense
    expect: tuple[int, ...] = ()  # allowed exit statuses (empty: any clean one)
    weight: int = field(default=1, compare=False)  # rough cost, for the quick subset


def _leaves(obj, prefix=""):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _leaves(v, f"{prefix}.{k}" if prefix else k)
    elif isinstance(obj, list) and obj and isinstance(obj[0], dict):
        for i, v in enumerate(obj):
            yield from _leaves(v, f"{prefix}[{i}]")
    else:
        yield prefix, obj


BENCH = to_mapping(load_scene("saiidi-4span", ["excitation.duration=0.3"]))
LEAVES = [(p, v) for p, v in _leaves(BENCH) if not p.startswith("notes")]
BENCH_TOML = scene_to_toml(load_scene("saiidi-4span", ["excitation.duration=0.3"]))

# (TOML text, kind): kind "nonfinite" and "type:<t>" make success nonsense for numeric leaves
VALUES = [
    ("nan", "nonfinite"),
    ("inf", "nonfinite"),
    ("-inf", "nonfinite"),
    ("-1", "number"),
    ("0", "number"),
    ("-0.0", "number"),
    ("1e308", "huge"),
    ("1e-320", "tiny"),
    ("9223372036854775808", "number"),
    ("1" + "0" * 400, "huge"),
    ("3.5", "number"),
    ("1e30", "number"),
    ('"x"', "str"),
    ("true", "bool"),
    ("[]", "list"),
    ("[[1, 2]]", "list"),
    ("{a = 1}", "table"),
    ('"$\\\\frac{$"', "str"),
]


def _type_of(value) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, (int, float)):
        return "number"
    if isinstance(value, str):
        return "str"
    return "list"


def _set_family() -> list[Case]:
    cases = []
    for path, value in LEAVES:
        leaf = _type_of(value)
        for text, kind in VALUES:
            nonsense = leaf == "number" and kind in (
                "nonfinite",
                "huge",
                "str",
                "bool",
                "list",
                "table",
            )
            nonsense |= leaf in ("str", "bool") and kind not in (leaf,)
            nonsense &= not (leaf == "str" and kind == "str")
            cases.append(
                Case(
                    f"set:{path}={text[:24]}",
                    "set",
                    ("scene", "validate", "saiidi-4span", *SHORT, "--set", f"{path}={text}"),
                    nonsense=nonsense,
                    expect=(0, 2),
                )
            )
    return cases


def _nested(kind: str, depth: int) -> str:
    if kind == "array":
        return 'name = "x"\nv = ' + "[" * depth + "1" + "]" * depth + "\n"
    if kind == "inline":
        return "v = " + "{a = " * depth + "1" + "}" * depth + "\n"
    if kind == "header":
        return "[" + ".".join(["a"] * depth) + "]\nb = 1\n"
    return ".".join(["a"] * depth) + " = 1\n"


def _file_case(cid: str, text: str | bytes, nonsense: bool = False) -> Case:
    data = text.encode("utf-8", "surrogateescape") if isinstance(text, str) else text
    return Case(
        cid,
        "file",
        ("scene", "validate", "{tmp}/scene.toml"),
        files=(("scene.toml", data),),
        nonsense=nonsense,
        expect=(0, 2),
    )


def _file_family() -> list[Case]:
    cases = []
    for kind in ("array", "inline", "header", "dotted"):
        for depth in (8, 31, 33, 64, 500, 5000, 100_000):
            cases.append(
                _file_case(
                    f"file:nest-{kind}-{depth}", BENCH_TOML + _nested(kind, depth), nonsense=True
                )
            )
            cases.append(
                _file_case(f"file:nest-only-{kind}-{depth}", _nested(kind, depth), nonsense=True)
            )
    headers = [ln for ln in BENCH_TOML.splitlines() if ln.startswith("[")]
    for h in sorted(set(headers)):
        for key in ("colour", "Mass", '"mass "', '"x-y"', "ünïcode", "0"):
            text = BENCH_TOML.replace(h + "\n", f"{h}\n{key} = 1\n", 1)
            cases.append(_file_case(f"file:unknown-key-{h}-{key}", text, nonsense=True))
    for top in BENCH:
        for value in (1, "x", [], [1, 2], {}, True, 1.5, {"a": {"b": 1}}, [{"a": 1}]):
            data = dict(BENCH)
            data[top] = value
            same_type = type(value) is type(BENCH[top])
            cases.append(
                _file_case(
                    f"file:swap-{top}-{value!r}"[:80],
                    tomli_w.dumps(data),
                    nonsense=not same_type and top != "notes",
                )
            )
        data = dict(BENCH)
        del data[top]
        cases.append(_file_case(f"file:drop-{top}", tomli_w.dumps(data)))
    for path, _ in LEAVES:
        data = tomllib.loads(BENCH_TOML)
        node, parts = data, path.replace("]", "").split(".")
        for part in parts[:-1]:
            name, _, idx = part.partition("[")
            node = node[name][int(idx)] if idx else node[name]
        name, _, idx = parts[-1].partition("[")
        del node[name]
        cases.append(_file_case(f"file:delete-{path}", tomli_w.dumps(data)))
    raw = BENCH_TOML.encode()
    for i in range(24):
        cut = (i * 7919) % len(raw)
        cases.append(_file_case(f"file:truncate-{cut}", raw[:cut]))
        junk = bytes((i * 37 + j * 11) % 256 for j in range(1 + i % 7))
        cases.append(_file_case(f"file:junk-{i}", raw[:cut] + junk + raw[cut:]))
    for cid, data in (
        ("empty", b""),
        ("spaces", b"   \n\t\n"),
        ("bom", b"\xef\xbb\xbf" + raw),
        ("crlf", raw.replace(b"\n", b"\r\n")),
        ("utf16", BENCH_TOML.encode("utf-16")),
        ("latin1", BENCH_TOML.replace("bridge", "brücke").encode("latin-1")),
        ("nul", raw.replace(b"\n", b"\x00\n", 3)),
        (
            "long-description",
            BENCH_TOML.replace('description = "', 'description = "' + "x" * 2_000_000, 1).encode(),
        ),
        ("dup-table", raw + b"\n[deck]\nlength = 1.0\n"),
        ("dup-key", raw.replace(b"mass = 140.5", b"mass = 140.5\nmass = 1.0")),
    ):
        cases.append(_file_case(f"file:{cid}", data))
    for n in (0, 1, 2, 40):
        data = dict(BENCH)
        data["bents"] = [BENCH["bents"][0]] * n
        cases.append(_file_case(f"file:bents-{n}-copies", tomli_w.dumps(data)))
        data = dict(BENCH)
        data["seats"] = [BENCH["seats"][0]] * n
        cases.append(_file_case(f"file:seats-{n}", tomli_w.dumps(data)))
    return cases


BAD_PATHS = [
    "",
    ".",
    "..",
    "a..b",
    "[0]",
    "bents[x].station",
    "bents[-1].station",
    "bents[0][0]",
    "deck[0]",
    "seats[99999999999999999999].gap",
    "notes",
    "notes.deck.mass",
    "notes.x",
    "bents",
    "seats",
    "deck",
    "0deck",
    "déck.mass",
    "deck .mass",
    " deck.mass",
    "deck.mass.x",
    "deck.mass[0]",
    "excitation.file",
    "name",
    "a" * 1000,
    "bents[0].x.stiffness.y",
    "sequence.pgas[0]",
    "sequence.pgas[10]",
    "damping.modes[1]",
    "damping.modes[9]",
    "run",
    "run.duration.x",
    "opensees.mode",
    "contact.law",
    "bents[3].name",
    "bents[0].name",
    "seats[2].gap",
    "excitation.kind",
    "excitation.file_x",
    "notes.deck",
]
BAD_OVERRIDE_VALUES = ["1", "nan", "[" * 50 + "]" * 50, "", '"unterminated', "csv", "{}"]


def _override_family() -> list[Case]:
    cases = []
    for path in BAD_PATHS:
        for value in BAD_OVERRIDE_VALUES:
            cases.append(
                Case(
                    f"override:{path[:30]}={value[:12]}",
                    "override",
                    ("scene", "validate", "saiidi-4span", *SHORT, "--set", f"{path}={value}"),
                    expect=(0, 2),
                )
            )
        cases.append(
            Case(
                f"override:{path[:30]}-no-equals",
                "override",
                ("scene", "validate", "saiidi-4span", *SHORT, "--set", path),
                expect=(2,),
            )
        )
    return cases


def families() -> dict:
    """Family name -> case builder (the output families live in tests._fuzz_outputs, the
    run-side ones in tests._fuzz_run_families)."""
    from _fuzz_magnitudes import input_family
    from _fuzz_outputs import fault_family, path_family
    from _fuzz_run_families import (
        engine_family,
        name_family,
        option_family,
        stream_family,
        vtk_family,
    )
    from _fuzz_scripts import script_family

    return {
        "set": _set_family,
        "file": _file_family,
        "override": _override_family,
        "path": path_family,
        "fault": fault_family,
        "engine": engine_family,
        "vtk": vtk_family,
        "name": name_family,
        "option": option_family,
        "script": script_family,
        "input": input_family,
        "stream": stream_family,
    }


def generate() -> list[Case]:
    """Every case of the corpus, in a fixed order; ids are unique."""
    cases = [c for make in families().values() for c in make()]
    seen, out = set(), []
    for c in cases:
        cid, n = c.id, 1
        while cid in seen:
            n += 1
            cid = f"{c.id}#{n}"
        seen.add(cid)
        out.append(c if cid == c.id else Case(**{**c.__dict__, "id": cid}))
    return out


def quick_subset(cases: list[Case], budget: int = 230) -> list[Case]:
    """A deterministic, stratified sample of about ``budget`` cases (every family, costly
    families thinned by their weight)."""
    by_family: dict[str, list[Case]] = {}
    for c in cases:
        by_family.setdefault(c.family, []).append(c)
    share = {
        "set": 45,
        "file": 30,
        "override": 15,
        "path": 30,
        "fault": 35,
        "engine": 15,
        "vtk": 12,
        "name": 6,
        "option": 12,
        "script": 12,
        "input": 10,
        "stream": 10,
    }
    out = []
    for fam, members in by_family.items():
        cheap = [c for c in members if c.weight <= 2]
        pool = cheap if fam not in ("name",) else [c for c in members if c.weight <= 8][:4]
        k = min(share.get(fam, 10), len(pool))
        step = max(1, len(pool) // max(k, 1))
        out += pool[::step][:k]
    return out[:budget]

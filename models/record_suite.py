"""A folder of ground-motion records read as horizontal pairs, one pair per station.

Files: ``*.at2`` (PEER AT2) and ``*.txt`` / ``*.dat`` (two-column text records). They pair by
these rules, in this order:

1. **manifest** — a ``manifest.csv`` in the folder with the columns ``pair, file_x, file_y``
   (files relative to the folder) names its pairs explicitly; the files it lists are paired
   only there. It is for names that do not pair by rule 2 or 3.
2. **x/y names** — ``NAME_x.*`` and ``NAME_y.*`` form the pair ``NAME`` (x = longitudinal,
   y = transverse, as named).
3. **PEER names** — ``RSN753_LOMAP_CLS000.AT2`` and ``RSN753_LOMAP_CLS090.AT2`` form the pair
   ``RSN753_LOMAP_CLS``: the stem minus its component suffix, which is a three-digit azimuth
   (``000``, ``090``, ``228``), ``H1``/``H2``, a channel code ``HNE``/``HNN``/``HN1``/``HN2``
   (and ``HH``/``HL``/``HG`` ones), ``FN``/``FP``, or a single ``N``/``E``/``L``/``T`` after a
   ``-`` or ``_``. Vertical components (suffix ``UP``, ``DWN``, ``DN``, ``V`` or ``Z`` after a
   ``-``/``_``, channel codes ``HNZ`` …) are ignored, each stated in a note. Of a station's
   two horizontal components, x gets the first in this order: the smaller azimuth, ``H1``
   before ``H2``, ``1`` before ``2``, ``E`` before ``N``, ``FN`` before ``FP``, ``L`` before
   ``T`` (the other assignment is the pair rotated, ``rotate = True``).

A horizontal component without its partner, a station with more than two, a file no rule
pairs, a pair of files of different formats, and every inconsistency of the manifest are
refused (:class:`~deckpound.models.errors.SceneError` naming the file and what is missing),
never applied to both directions as if it were a pair.

With ``rotate`` every pair is also listed with its components swapped (x ↔ y: the pair
turned by 90°, up to the sign of one component, which a record's azimuth convention does not
fix), so that a suite covers both orientations of each station on the bridge.
"""

from __future__ import annotations

import csv
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from .errors import SceneError

RECORD_SUFFIXES = {".at2": "at2", ".txt": "text", ".dat": "text"}
MANIFEST = "manifest.csv"
MANIFEST_COLUMNS = ("pair", "file_x", "file_y")
MAX_MANIFEST_BYTES = 1 << 20  # a manifest of 10,000 pairs is below 1 MB

_XY = re.compile(r"^(?P<key>.+)_(?P<axis>[xy])$", re.IGNORECASE)
_COMPONENT = re.compile(
    r"^(?P<key>.*?)(?P<comp>\d{3}|H[12]|H[HNLG][ENZ12]|FN|FP|UP|DWN|DN|(?<=[-_])[NEVZLT])$",
    re.IGNORECASE,
)
_VERTICAL = re.compile(r"^(UP|DWN|DN|V|Z|H[HNLG]Z)$", re.IGNORECASE)
_ORDER = {"H1": 0, "H2": 1, "E": 0, "N": 1, "FN": 0, "FP": 1, "L": 0, "T": 1}


@dataclass(frozen=True)
class RecordPair:
    """One station's two horizontal components: ``file_x`` (longitudinal) and ``file_y``
    (transverse), both of format ``kind`` (at2 | text); ``rule`` says how they were paired
    (manifest | xy | peer); ``rotated``: the components swapped (the pair turned by 90°)."""

    name: str
    kind: str
    file_x: Path
    file_y: Path
    rule: str
    rotated: bool = False

    @property
    def label(self) -> str:
        return f"{self.name} (rotated 90°)" if self.rotated else self.name

    def swapped(self) -> RecordPair:
        return RecordPair(
            self.name, self.kind, self.file_y, self.file_x, self.rule, not self.rotated
        )

    def overrides(self) -> list[str]:
        """``path=value`` overrides that apply this pair to a scene."""

        return [
            f"excitation.kind={self.kind}",
            f"excitation.file_x={json.dumps(str(self.file_x))}",
            f"excitation.file_y={json.dumps(str(self.file_y))}",
        ]


@dataclass
class RecordSuite:
    """The pairs of a folder (sorted by name; a rotated pair follows its original) and the
    notes on what was left out (vertical components)."""

    folder: Path
    pairs: list[RecordPair]
    notes: list[str] = field(default_factory=list)


def component_of(stem: str) -> tuple[str, str] | None:
    """(station key, component) of a PEER-style file stem, or None when no component suffix
    is recognised: ``RSN753_LOMAP_CLS000`` → (``RSN753_LOMAP_CLS``, ``000``)."""
    m = _COMPONENT.match(stem)
    if not m or not m.group("key"):
        return None
    return m.group("key").rstrip("-_."), m.group("comp").upper()


def is_vertical(component: str) -> bool:
    return bool(_VERTICAL.match(component))


def _rank(component: str) -> tuple[int, str]:
    if component.isdigit():
        return int(component), component
    if component in _ORDER:
        return _ORDER[component], component
    return (0 if component[-1] in "E1" else 1), component  # channel codes HNE/HNN, HN1/HN2


def _kind(path: Path) -> str:
    return RECORD_SUFFIXES[path.suffix.lower()]


def _pair(name: str, fx: Path, fy: Path, rule: str, where: str) -> RecordPair:
    if _kind(fx) != _kind(fy):
        raise SceneError(
            where,
            f"pair {name!r}: {fx.name} and {fy.name} are records of different formats "
            f"({_kind(fx)}, {_kind(fy)}); a pair's two components share one format",
        )
    return RecordPair(name, _kind(fx), fx.resolve(), fy.resolve(), rule)


def read_manifest(root: Path, field_name: str) -> list[RecordPair]:
    """The pairs ``manifest.csv`` names (columns pair, file_x, file_y; files relative to the
    folder); refuses a missing column, an empty cell, a duplicate pair name or file, and a
    file that is not a record of the folder."""
    path = root / MANIFEST
    where = f"{field_name} ({path})"
    if path.stat().st_size > MAX_MANIFEST_BYTES:
        raise SceneError(where, f"holds more than {MAX_MANIFEST_BYTES} bytes; is it a manifest?")
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            rows = list(csv.DictReader(handle))
            columns = [c.strip() for c in (rows[0].keys() if rows else [])]
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise SceneError(where, f"cannot be read as CSV ({type(err).__name__})") from None
    missing = [c for c in MANIFEST_COLUMNS if c not in columns]
    if not rows or missing:
        raise SceneError(
            where,
            f"needs the columns {', '.join(MANIFEST_COLUMNS)} and one row per pair"
            + (f"; missing {', '.join(missing)}" if rows else "; it has no row"),
        )
    pairs, names, used = [], set(), set()
    for i, raw in enumerate(rows, start=2):
        row = {(k or "").strip(): (v or "").strip() for k, v in raw.items()}
        for col in MANIFEST_COLUMNS:
            if not row[col]:
                raise SceneError(where, f"row {i}: column {col!r} is empty")
        if row["pair"] in names:
            raise SceneError(where, f"row {i}: pair {row['pair']!r} is named twice")
        names.add(row["pair"])
        files = {}
        for col in ("file_x", "file_y"):
            f = (root / row[col]).resolve()
            if not f.is_file() or f.parent != root.resolve():
                raise SceneError(
                    where, f"row {i}: {col} = {row[col]!r} is not a file of the folder"
                )
            if f.suffix.lower() not in RECORD_SUFFIXES:
                raise SceneError(
                    where,
                    f"row {i}: {col} = {row[col]!r} is no record (*.at2, *.txt, *.dat)",
                )
            if f in used:
                raise SceneError(where, f"row {i}: {row[col]!r} is used twice")
            used.add(f)
            files[col] = f
        pairs.append(_pair(row["pair"], files["file_x"], files["file_y"], "manifest", where))
    return pairs


def read_suite(folder: str | Path, *, rotate: bool = False, field_name: str = "--records"):
    """The record pairs of ``folder`` (see the module docstring): a :class:`RecordSuite`."""
    root = Path(folder)
    if not root.is_dir():
        raise SceneError(field_name, f"{str(root)!r} is not a folder")
    files = sorted(p for p in root.iterdir() if p.is_file() and p.suffix.lower() in RECORD_SUFFIXES)
    manifest = read_manifest(root, field_name) if (root / MANIFEST).is_file() else []
    if not files:
        raise SceneError(field_name, f"{str(root)!r} holds no record (*.at2, *.txt, *.dat)")
    listed = {p for pair in manifest for p in (pair.file_x, pair.file_y)}
    pairs = list(manifest)
    notes: list[str] = []
    xy: dict[tuple[str, str], dict[str, Path]] = {}
    stations: dict[tuple[str, str], list[tuple[str, Path]]] = {}
    for p in files:
        if p.resolve() in listed:
            continue
        m = _XY.match(p.stem)
        if m:
            xy.setdefault((m.group("key"), _kind(p)), {})[m.group("axis").lower()] = p
            continue
        found = component_of(p.stem)
        if found is None:
            raise SceneError(
                field_name,
                f"{p.name}: no component in its name pairs it with another file (PEER names "
                f"like NAME_CLS000 / NAME_CLS090, H1 / H2, or NAME_x / NAME_y); rename it or "
                f"pair it in {MANIFEST} (columns {', '.join(MANIFEST_COLUMNS)})",
            )
        key, comp = found
        if is_vertical(comp):
            notes.append(
                f"{p.name}: vertical component ({comp}), not applied (the plan model has "
                "no vertical motion)"
            )
            continue
        stations.setdefault((key, _kind(p)), []).append((comp, p))
    for (key, _), parts in sorted(xy.items()):
        for axis, other in (("x", "y"), ("y", "x")):
            if axis in parts and other not in parts:
                raise SceneError(
                    field_name,
                    f"{parts[axis].name}: the {axis} component of {key!r} has no partner "
                    f"({key}_{other}{parts[axis].suffix} is missing); a lone component is "
                    f"not a pair: add it or pair it in {MANIFEST}",
                )
        pairs.append(_pair(key, parts["x"], parts["y"], "xy", field_name))
    for (key, _), comps in sorted(stations.items()):
        comps.sort(key=lambda c: _rank(c[0]))
        names = ", ".join(p.name for _, p in comps)
        if len(comps) == 1:
            raise SceneError(
                field_name,
                f"{comps[0][1].name}: horizontal component {comps[0][0]} of station {key!r} "
                f"has no partner (the second horizontal component, e.g. an azimuth 90° "
                f"apart, is missing from the folder); a lone component is not a pair: add "
                f"it or pair it in {MANIFEST}",
            )
        if len(comps) > 2:
            raise SceneError(
                field_name,
                f"station {key!r} has {len(comps)} horizontal components ({names}); "
                f"name its pair in {MANIFEST}",
            )
        pairs.append(_pair(key, comps[0][1], comps[1][1], "peer", field_name))
    pairs.sort(key=lambda pair: pair.name)
    names_seen: dict[str, RecordPair] = {}
    for pair in pairs:
        if pair.name in names_seen:
            raise SceneError(
                field_name,
                f"two pairs are named {pair.name!r} ({pair.file_x.name}, "
                f"{names_seen[pair.name].file_x.name}); rename one or use {MANIFEST}",
            )
        names_seen[pair.name] = pair
    if rotate:
        pairs = [q for pair in pairs for q in (pair, pair.swapped())]
    return RecordSuite(folder=root.resolve(), pairs=pairs, notes=notes)

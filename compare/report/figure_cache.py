"""Reuse of figures whose inputs are unchanged: a report re-run into the same folder redraws
only what changed (issue 32, item 7).

A figure function decorated with :func:`reusable` draws as it always does unless a manifest is
open (:func:`reuse_figures`; ``deckpound paper`` opens ``DIR/figure_inputs.json``). With one
open, the call's fingerprint is looked up under the figure's path: a SHA-256 of

- the function (module and qualified name) and the code that draws it: the source of its
  module and of every deckpound module that one imports (the style, the helpers the figures
  compute with), the engines' declared line styles, deckpound's and matplotlib's versions;
- every argument but the path: arrays by dtype, shape and bytes; tables by their columns, index,
  dtypes and values, but for the columns that say how a run was made (:data:`NOT_DRAWN`); a :class:`~deckpound.models.result.Result` by its engine and columns (its
  metadata holds timings, which no figure draws); a scene by its name and
  :func:`~deckpound.models.result.physics_hash` (engine settings, the sequence and the notes
  reach a figure only through the results it draws); a sequence run by its index, PGA, start state,
  scene and result (not by whether the result came from the cache).

If the manifest holds the same fingerprint and every file that call wrote (the PNG and any other
format) is there with the SHA-256 recorded when it was written, those files are the figure: it
is not drawn, and the files are not touched. Otherwise (a changed input, another version, a
missing or damaged file, an argument the fingerprint cannot read) the figure is drawn, and its
entry written as soon as its files are. Outside :func:`reuse_figures` nothing is looked up or
recorded.
"""

from __future__ import annotations

import ast
import contextvars
import dataclasses
import functools
import hashlib
import importlib.metadata
import inspect
import json
import math
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from deckpound.compare.engines import engine_names, engine_style
from deckpound.compare.studies.sequence_run import SequenceRun
from deckpound.models.file_io import atomic_write_text, file_digest
from deckpound.models.result import Result, physics_hash
from deckpound.models.scene import Scene
from deckpound.models.version import VERSION

#: the manifest's name in a report folder
MANIFEST_NAME = "figure_inputs.json"
#: format of the manifest file (another format is read as empty: every figure is redrawn)
MANIFEST_FORMAT = 1


#: table columns that record how a result was made (run and compile times, whether it came
#: from the cache), not what it gave: the fingerprint skips them, so a cached or recomputed
#: result draws the same figure. A :func:`reusable` figure must not draw them.
NOT_DRAWN = frozenset({"wall_time", "compile_time", "loop_time", "cached"})


class UnreadableInput(TypeError):
    """An argument of a figure the fingerprint cannot read: the figure is drawn, not reused."""


class FigureManifest:
    """The fingerprints and files of the figures drawn into one folder (a JSON file).

    ``drawn`` and ``reused`` list the figure paths of this run, in call order; with ``reuse``
    false every figure is drawn (and recorded)."""

    def __init__(self, path: str | Path, reuse: bool = True):
        self.path = Path(path)
        self.reuse = reuse
        self.entries: dict[str, dict[str, Any]] = self._load()
        self.drawn: list[Path] = []
        self.reused: list[Path] = []

    def _load(self) -> dict[str, dict[str, Any]]:
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {}
        if not isinstance(data, dict) or data.get("format") != MANIFEST_FORMAT:
            return {}
        figures = data.get("figures")
        return figures if isinstance(figures, dict) else {}

    def _name(self, path: Path) -> str:
        """A figure file as the manifest names it: relative to the manifest's folder when it is
        inside it (the folder may move), absolute otherwise."""
        path = Path(path).absolute()
        try:
            return path.relative_to(self.path.parent.absolute()).as_posix()
        except ValueError:
            return str(path)

    def _file(self, name: str) -> Path:
        path = Path(name)
        return path if path.is_absolute() else self.path.parent / path

    def lookup(self, path: Path, fingerprint: str) -> list[Path] | None:
        """The files of the figure at ``path`` if its entry has ``fingerprint`` and every one
        of its files is intact (same SHA-256 as when written); else None."""
        if not self.reuse:
            return None
        entry = self.entries.get(self._name(path))
        if not isinstance(entry, dict) or entry.get("fingerprint") != fingerprint:
            return None
        files = entry.get("files")
        if not isinstance(files, dict) or not files:
            return None
        found = []
        for name, digest in files.items():
            file = self._file(name)
            try:
                if file_digest(file) != digest:
                    return None
            except OSError:
                return None
            found.append(file)
        return found

    def record(self, path: Path, fingerprint: str | None, written: list[Path]) -> None:
        """Enter the figure at ``path`` as drawn with ``fingerprint`` into ``written`` (no
        fingerprint: forget any earlier entry) and write the manifest."""
        name = self._name(path)
        if fingerprint is None:
            self.entries.pop(name, None)
        else:
            self.entries[name] = {
                "fingerprint": fingerprint,
                "files": {self._name(p): file_digest(Path(p)) for p in written},
            }
        payload = {"format": MANIFEST_FORMAT, "figures": self.entries}
        atomic_write_text(self.path, json.dumps(payload, indent=1, sort_keys=True) + "\n")


_OPEN: contextvars.ContextVar[FigureManifest | None] = contextvars.ContextVar(
    "deckpound_figure_manifest", default=None
)


@contextmanager
def reuse_figures(manifest: str | Path, reuse: bool = True) -> Iterator[FigureManifest]:
    """Within the block, :func:`reusable` figures reuse the files of an unchanged figure
    (``reuse`` false: draw every one) and record what they draw in the manifest at
    ``manifest``. Yields the manifest (its ``drawn`` and ``reused`` lists)."""
    opened = FigureManifest(manifest, reuse)
    token = _OPEN.set(opened)
    try:
        yield opened
    finally:
        _OPEN.reset(token)


def _imported_modules(module_name: str) -> list[str]:
    """The module and the deckpound modules it imports (relative or absolute, at module level
    or inside a function), by name: the code a figure function draws with."""
    module = sys.modules[module_name]
    tree = ast.parse(Path(module.__file__).read_text(encoding="utf-8"))
    package = module_name.rpartition(".")[0]
    names = {module_name}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                source = f"{base}.{node.module}" if node.module else base
            else:
                source = node.module or ""
            candidates = [source] + [f"{source}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            candidates = [alias.name for alias in node.names]
        else:
            continue
        names.update(c for c in candidates if c.startswith("deckpound.") and c in sys.modules)
    return sorted(n for n in names if getattr(sys.modules[n], "__file__", None))


@functools.cache
def code_fingerprint(module_name: str) -> str:
    """SHA-256 of what draws a figure of the module ``module_name`` besides its arguments: the
    source of the module and of every deckpound module it imports (the style, the helpers the
    figures compute with), the engines' line styles, deckpound's and matplotlib's versions
    (read once per process and module)."""
    h = hashlib.sha256()
    for name in _imported_modules(module_name):
        h.update(f"{name}\0".encode())
        h.update(hashlib.sha256(Path(sys.modules[name].__file__).read_bytes()).digest())
    feed(h, [(e, engine_style(e)) for e in engine_names()])
    feed(h, (VERSION, importlib.metadata.version("matplotlib")))
    return h.hexdigest()


def _tag(h, tag: str, text: str = "") -> None:
    data = text.encode("utf-8", "surrogatepass")
    h.update(f"{tag}{len(data)}:".encode())
    h.update(data)


def _feed_array(h, arr: np.ndarray) -> None:
    if arr.dtype.kind not in "biufcmM":
        _tag(h, "objects", str(arr.shape))
        feed(h, arr.ravel().tolist())
        return
    _tag(h, "array", f"{arr.dtype.str}{arr.shape}")
    h.update(np.ascontiguousarray(arr).tobytes())


def _feed_series(h, s: pd.Series | pd.Index) -> None:
    _tag(h, "series", f"{s.dtype}")
    feed(h, s.name)
    values = s.to_numpy()
    if values.dtype.kind in "biufcmM":
        _feed_array(h, values)
    else:
        feed(h, values.tolist())


def feed(h, obj: Any) -> None:
    """Update the hash ``h`` with ``obj``, type and structure included (see the module
    docstring for what is read of which type); :class:`UnreadableInput` for another type."""
    if obj is None or isinstance(obj, (bool, np.bool_)):
        _tag(h, "const", repr(None if obj is None else bool(obj)))
    elif isinstance(obj, (int, np.integer)):
        _tag(h, "int", str(int(obj)))
    elif isinstance(obj, (float, np.floating)):
        value = float(obj)
        _tag(h, "float", "nan" if math.isnan(value) else value.hex())
    elif isinstance(obj, str):
        _tag(h, "str", obj)
    elif isinstance(obj, bytes):
        _tag(h, "bytes", str(len(obj)))
        h.update(obj)
    elif isinstance(obj, Path):
        _tag(h, "path", str(obj))
    elif isinstance(obj, Enum):
        _tag(h, "enum", f"{type(obj).__qualname__}.{obj.name}")
    elif isinstance(obj, np.ndarray):
        _feed_array(h, obj)
    elif isinstance(obj, pd.DataFrame):
        _tag(h, "frame", str(len(obj)))
        _feed_series(h, obj.index)
        for column in obj.columns:
            if column in NOT_DRAWN:
                continue
            feed(h, column)
            _feed_series(h, obj[column])
    elif isinstance(obj, (pd.Series, pd.Index)):
        _feed_series(h, obj)
    elif isinstance(obj, Result):
        _tag(h, "result", obj.engine)
        feed(h, obj.columns)
    elif isinstance(obj, Scene):
        _tag(h, "scene", obj.name)
        _tag(h, "physics", physics_hash(obj))
    elif isinstance(obj, SequenceRun):
        _tag(h, "sequence run")
        feed(h, (obj.index, obj.pga, obj.state, obj.scene, obj.result))
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        _tag(h, "dataclass", type(obj).__qualname__)
        for f in dataclasses.fields(obj):
            feed(h, f.name)
            feed(h, getattr(obj, f.name))
    elif isinstance(obj, (list, tuple)):
        _tag(h, type(obj).__name__, str(len(obj)))
        for item in obj:
            feed(h, item)
    elif isinstance(obj, dict):
        _tag(h, "dict", str(len(obj)))
        for key, value in obj.items():
            feed(h, key)
            feed(h, value)
    elif callable(obj) and hasattr(obj, "__qualname__"):
        _tag(h, "callable", f"{getattr(obj, '__module__', '')}.{obj.__qualname__}")
    else:
        raise UnreadableInput(f"a figure input of type {type(obj).__qualname__}")


def fingerprint(function: Callable, inputs: dict[str, Any]) -> str | None:
    """The fingerprint of drawing ``function`` with ``inputs`` (argument name → value), or
    None if an input cannot be read (the figure is then always drawn)."""
    h = hashlib.sha256()
    _tag(h, "code", code_fingerprint(function.__module__))
    _tag(h, "function", f"{function.__module__}.{function.__qualname__}")
    try:
        feed(h, inputs)
    except UnreadableInput:
        return None
    return h.hexdigest()


def reusable(function: Callable[..., list[Path]]) -> Callable[..., list[Path]]:
    """Decorate a figure function that takes its output file as ``path`` and returns the files
    it wrote: within :func:`reuse_figures`, an unchanged figure is not drawn again (its files
    are returned as they are). The function must draw nothing but its arguments (of a table,
    not the :data:`NOT_DRAWN` columns) and the code :func:`code_fingerprint` reads."""
    signature = inspect.signature(function)

    @functools.wraps(function)
    def draw_or_reuse(*args, **kwargs) -> list[Path]:
        manifest = _OPEN.get()
        if manifest is None:
            return function(*args, **kwargs)
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        path = Path(bound.arguments["path"])
        key = fingerprint(function, {k: v for k, v in bound.arguments.items() if k != "path"})
        if key is not None:
            files = manifest.lookup(path, key)
            if files is not None:
                manifest.reused.append(path)
                return files
        written = function(*args, **kwargs)
        manifest.drawn.append(path)
        manifest.record(path, key, written)
        return written

    return draw_or_reuse

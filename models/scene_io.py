"""Scene files: TOML in and out (exact round trip), built-in scenes, ``--set`` overrides, schema."""

from __future__ import annotations

import copy
import importlib.resources
import json
import tomllib
import unicodedata
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import tomli_w

from .errors import SceneError
from .fields import from_mapping, json_schema, set_path, split_path, to_mapping
from .records import resolve_path
from .scene import Scene

_BUILTIN_PACKAGE = "deckpound.models"
_BUILTIN_DIR = "scenes"


def builtin_scene_names() -> list[str]:
    """Names of the scenes shipped with the package."""
    folder = importlib.resources.files(_BUILTIN_PACKAGE) / _BUILTIN_DIR
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def builtin_scene_text(name: str) -> str:
    """The TOML text of a built-in scene (refuses unknown names, listing the valid ones)."""
    names = builtin_scene_names()
    if name not in names:
        raise SceneError("scene", f"unknown scene {name!r}; built-in scenes: {', '.join(names)}")
    return (importlib.resources.files(_BUILTIN_PACKAGE) / _BUILTIN_DIR / f"{name}.toml").read_text()


def scene_from_mapping(data: dict[str, Any]) -> Scene:
    """Build and validate a scene from a nested mapping.

    Unknown keys are refused first, then every value against its field's type and range
    (NaN and inf are refused there, so the message names the field's type and unit).
    """
    return from_mapping(Scene, data)


#: deepest nesting of tables and arrays a scene may use (the benchmark needs 4)
MAX_NESTING = 32
#: largest scene file read (the benchmark is 7 kB; records are separate files)
MAX_SCENE_BYTES = 16 * 1024 * 1024


def _nesting(value: Any, limit: int) -> int:
    """Depth of nested tables/arrays in ``value``, counted iteratively up to ``limit + 1``."""
    deepest, stack = 0, [(value, 0)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, (dict, list)):
            deepest = max(deepest, depth + 1)
            if deepest > limit:
                return deepest
            stack.extend(
                (v, depth + 1) for v in (node.values() if isinstance(node, dict) else node)
            )
    return deepest


def _check_dotted_depth(text: str, source: str) -> None:
    """Refuse dotted keys and table headers nested beyond MAX_NESTING before parsing: tomllib
    takes time and memory quadratic in their depth (a 200 kB key ``a.a.a...`` exhausts 8 GB)."""
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.lstrip()
        if stripped.startswith("["):
            key = stripped.split("]", 1)[0]
        elif "=" in stripped:
            key = stripped.split("=", 1)[0]
        else:
            continue
        if key.count(".") >= MAX_NESTING:
            raise SceneError(
                source,
                f"line {number}: a key or table header nested "
                f"{key.count('.') + 1} levels deep; at most {MAX_NESTING} levels "
                "are allowed",
            )


def parse_toml(text: str, source: str = "scene") -> dict[str, Any]:
    """Parse TOML text, turning syntax errors and absurd nesting into a one-line SceneError."""
    _check_dotted_depth(text, source)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SceneError(source, f"is not valid TOML: {err}") from None
    except RecursionError:
        raise SceneError(
            source,
            f"nests arrays or tables too deeply to parse; at most {MAX_NESTING} levels are allowed",
        ) from None
    if _nesting(data, MAX_NESTING) > MAX_NESTING:
        raise SceneError(source, f"nests arrays or tables more than {MAX_NESTING} levels deep")
    return data


def load_scene_data(ref: str | Path) -> tuple[dict[str, Any], Path | None]:
    """Raw mapping of a scene given by built-in name or file path, and its folder."""
    path = Path(ref)
    if path.suffix == ".toml" or path.exists():
        if not path.is_file():
            raise SceneError("scene", f"file {str(path)!r} does not exist")
        try:
            size = path.stat().st_size
            if size > MAX_SCENE_BYTES:
                raise SceneError(
                    "scene",
                    f"file {str(path)!r} holds {size} bytes; a scene file "
                    f"may hold at most {MAX_SCENE_BYTES} (records go in their own "
                    "files)",
                )
            text = path.read_text()
        except (OSError, UnicodeDecodeError) as err:
            raise SceneError("scene", f"cannot read {str(path)!r}: {err}") from None
        return parse_toml(text, str(path)), path.resolve().parent
    return parse_toml(builtin_scene_text(str(ref)), str(ref)), None


class RecordPathWarning(UserWarning):
    """A record path given relative to the scene file reaches outside the scene's folder."""


def resolve_record_paths(data: dict[str, Any], folder: Path) -> list[str]:
    """Resolve relative record paths (``excitation.file``, ``file_x``, ``file_y``) in place
    against the scene's folder, symbolic links followed; returns a notice for each one that
    ends outside that folder (``../other/x.at2``): the scene then reads a file it does not
    ship with, which a reader of the scene should be told."""
    notices = []
    exc = data.get("excitation")
    if not isinstance(exc, dict):
        return notices
    for key in ("file", "file_x", "file_y"):
        given = exc.get(key)
        if not isinstance(given, str) or not given:
            continue
        resolved = resolve_path(given, f"excitation.{key}", folder)
        if given.startswith("~") or Path(given).is_absolute():
            continue  # absolute: read as given (resolved when read)
        exc[key] = str(resolved)
        if not resolved.is_relative_to(folder.resolve()):
            notices.append(
                f"excitation.{key}: the relative path {given!r} reaches outside the "
                f"scene's folder {str(folder)!r}; it is read from {str(resolved)!r}"
            )
    return notices


def load_scene(ref: str | Path, overrides: Iterable[str] = ()) -> Scene:
    """Load a scene by built-in name or TOML path and apply ``path=value`` overrides.

    Relative record paths in the excitation are resolved against the scene file's folder
    (symbolic links followed, so every message shows the file actually read); a relative path
    reaching outside that folder is accepted with a :class:`RecordPathWarning`, issued once the
    scene is valid.
    """
    data, folder = load_scene_data(ref)
    data = apply_overrides(data, overrides)
    notices = resolve_record_paths(data, folder) if folder is not None else []
    scene = scene_from_mapping(data)
    for text in notices:
        warnings.warn(text, RecordPathWarning, stacklevel=1)  # one location: printed once
    return scene


def scene_to_toml(scene: Scene) -> str:
    """TOML text of a scene; ``scene_from_toml(scene_to_toml(s)) == s`` exactly."""
    return tomli_w.dumps(to_mapping(scene))


def scene_from_toml(text: str) -> Scene:
    """Scene from TOML text."""
    return scene_from_mapping(parse_toml(text))


def scene_schema() -> dict[str, Any]:
    """JSON Schema of the scene file."""
    schema = json_schema(Scene)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "deckpound scene"
    return schema


def scene_schema_json() -> str:
    return json.dumps(scene_schema(), indent=2)


def _parse_value(text: str) -> Any:
    """A TOML value (number, bool, string, array), or the bare text as a string."""
    _check_dotted_depth(f"v = {text}", "--set")
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text
    except RecursionError:
        raise SceneError(
            "--set",
            f"value nests arrays or tables too deeply; at most {MAX_NESTING} levels are allowed",
        ) from None
    if _nesting(value, MAX_NESTING) > MAX_NESTING:
        raise SceneError(
            "--set", f"value nests arrays or tables more than {MAX_NESTING} levels deep"
        )
    return value


_CONTROL_NAMES = {
    "\t": "CHARACTER TABULATION",
    "\n": "LINE FEED",
    "\r": "CARRIAGE RETURN",
    "\x1b": "ESCAPE",
    "\x00": "NULL",
    "\x7f": "DELETE",
}


def _control_character(text: str) -> int | None:
    """Index of the first control character in ``text`` (Unicode categories Cc — C0 and C1
    controls, DEL, tab, newline, carriage return, escape — and Zl, Zp: line and paragraph
    separators), or None."""
    for i, c in enumerate(text):
        if unicodedata.category(c) in ("Cc", "Zl", "Zp"):
            return i
    return None


def check_override_text(item: str) -> None:
    """Refuse a ``--set`` override holding a control character, naming it (escaped).

    An override is one line of printable text. A newline inside it would otherwise be read as
    TOML's line break, so ``deck.length=33.5\\nfoo=1`` set deck.length and silently dropped
    ``foo=1``; an escape or carriage return would reach the terminal in messages.
    """
    i = _control_character(item)
    if i is None:
        return
    c = item[i]
    name = unicodedata.name(c, "") or _CONTROL_NAMES.get(c, "control character")
    shown = item if len(item) <= 80 else item[:77] + "..."
    where = "key" if "=" not in item or i < item.index("=") else "value"
    raise SceneError(
        "--set",
        f"override {shown!a} holds a control character in its {where} "
        f"(U+{ord(c):04X} {name.lower()}, character {i + 1}); an override is one line of "
        "printable text: give each field its own --set",
    )


def apply_overrides(data: dict[str, Any], overrides: Iterable[str]) -> dict[str, Any]:
    """Apply ``dotted.path[index]=value`` overrides to a raw scene mapping (a copy).

    Values are parsed as TOML (``2e6``, ``true``, ``[1, 3]``, ``"text"``); a bare word is a
    string. Unknown paths are refused when the scene is validated; an override holding a
    control character (a newline, a tab, an escape, ...) is refused before it is parsed
    (:func:`check_override_text`).
    """
    data = copy.deepcopy(data)
    overrides = list(overrides)
    for item in overrides:
        check_override_text(item)
    for item in overrides:
        if "=" not in item:
            raise SceneError("--set", f"expects PATH=VALUE, got {item!r}")
        path, raw = item.split("=", 1)
        path = path.strip()
        split_path(path)  # a malformed path is refused before its value is parsed
        set_path(data, path, _parse_value(raw.strip()))
    return data


def modified(scene: Scene, *overrides: str) -> Scene:
    """A copy of the scene with ``path=value`` overrides applied and validated."""
    return scene_from_mapping(apply_overrides(to_mapping(scene), overrides))

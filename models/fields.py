"""Typed, self-validating, frozen description records.

A description class is a frozen dataclass whose fields are declared with :func:`spec`: the
field carries its unit, a one-line doc and its allowed range or choices. From that single
declaration this module derives

* validation at construction (``__post_init__`` calls :func:`validate`),
* construction from nested mappings (TOML, JSON, ``--set`` overrides) with unknown keys refused,
* the inverse mapping (exact TOML round trip: floats are written with ``repr``),
* a JSON Schema.

Errors are :class:`~deckpound.models.errors.SceneError` with the dotted path of the field.
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import math
import re
import types
import typing
from typing import Any

from .errors import SceneError

# Floats beyond these magnitudes are no physical value in SI units with tonnes, and they
# overflow or underflow (to inf, NaN or subnormals) in the engines' arithmetic.
MIN_MAGNITUDE = 1e-30
MAX_MAGNITUDE = 1e30
# Integers beyond this magnitude (2**53) lose exactness as floats and overflow the int64 loop
# counters of the compiled engines; no count, seed or index of a scene comes near it. Fields
# with a physical limit declare a tighter ``le`` (e.g. Newton iterations).
MAX_INT = 2**53


def spec(
    default: Any = dataclasses.MISSING,
    *,
    unit: str = "",
    doc: str = "",
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    choices: tuple[str, ...] | None = None,
    default_factory: Any = dataclasses.MISSING,
) -> Any:
    """Declare a description field with its unit, doc string and allowed values."""
    meta = {"unit": unit, "doc": doc, "gt": gt, "ge": ge, "lt": lt, "le": le, "choices": choices}
    if default_factory is not dataclasses.MISSING:
        return dataclasses.field(default_factory=default_factory, metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    """The resolved type hints of a description class (read-only; resolved once per class, as
    every scene built or modified reads them for each of its records)."""
    return typing.get_type_hints(cls)


def _unit(meta: typing.Mapping[str, Any]) -> str:
    return f" {meta['unit']}" if meta.get("unit") not in ("", "-", None) else ""


def _in_unit(meta: typing.Mapping[str, Any]) -> str:
    u = _unit(meta)
    return f" in{u}" if u else ""


def _fmt(value: Any) -> str:
    return repr(value) if isinstance(value, str) else f"{value}"


def _check_number(name: str, value: float, meta: typing.Mapping[str, Any]) -> None:
    if isinstance(value, float) and not math.isfinite(value):
        raise SceneError(name, f"must be a finite number{_in_unit(meta)}, got {value}")
    u = _unit(meta)
    if meta.get("gt") is not None and not value > meta["gt"]:
        raise SceneError(name, f"must be > {meta['gt']}{u}, got {_fmt(value)}")
    if meta.get("ge") is not None and not value >= meta["ge"]:
        raise SceneError(name, f"must be >= {meta['ge']}{u}, got {_fmt(value)}")
    if meta.get("lt") is not None and not value < meta["lt"]:
        raise SceneError(name, f"must be < {meta['lt']}{u}, got {_fmt(value)}")
    if meta.get("le") is not None and not value <= meta["le"]:
        raise SceneError(name, f"must be <= {meta['le']}{u}, got {_fmt(value)}")
    if (
        isinstance(value, float)
        and value != 0.0
        and not MIN_MAGNITUDE <= abs(value) <= MAX_MAGNITUDE
    ):
        raise SceneError(
            name,
            f"is beyond any physical value: magnitudes from {MIN_MAGNITUDE:g} "
            f"to {MAX_MAGNITUDE:g}{u} are allowed, got {_fmt(value)}",
        )


def _coerce(name: str, tp: Any, value: Any, meta: typing.Mapping[str, Any]) -> Any:
    """Convert a plain (TOML/JSON) value to the declared type, or raise SceneError."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if value is None:
            return None
        return _coerce(name, args[0], value, meta)
    if dataclasses.is_dataclass(tp):
        if dataclasses.is_dataclass(value) and isinstance(value, tp):
            return value
        return from_mapping(tp, value, name)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(name, f"must be a number{_in_unit(meta)}, got {_fmt(value)}")
        try:
            value = float(value)
        except OverflowError:
            raise SceneError(
                name,
                f"must be a finite number{_in_unit(meta)}, got an integer too large for a float",
            ) from None
        _check_number(name, value, meta)
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            if not (isinstance(value, float) and value.is_integer()):
                raise SceneError(name, f"must be an integer{_in_unit(meta)}, got {_fmt(value)}")
        if abs(value) > MAX_INT:
            hi = meta["le"] if meta.get("le") is not None else MAX_INT
            got = (
                f"{value:g}"
                if isinstance(value, float)
                else (
                    f"{value}"
                    if len(str(value)) <= 30
                    else f"an integer of {len(str(value))} digits"
                )
            )
            raise SceneError(
                name,
                f"must be an integer <= {hi}{_unit(meta)}, got {got}"
                if value > 0
                else f"must be an integer >= {-MAX_INT}{_unit(meta)}, got {got}",
            )
        value = int(value)
        _check_number(name, value, meta)
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise SceneError(name, f"must be true or false, got {_fmt(value)}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise SceneError(name, f"must be a string, got {_fmt(value)}")
        if meta.get("choices") and value not in meta["choices"]:
            allowed = ", ".join(meta["choices"])
            raise SceneError(name, f"unknown value {value!r}; allowed: {allowed}")
        return value
    if origin is tuple:
        item_tp = typing.get_args(tp)[0]
        if not isinstance(value, (list, tuple)):
            raise SceneError(name, f"must be a list, got {_fmt(value)}")
        return tuple(_coerce(f"{name}[{i}]", item_tp, v, meta) for i, v in enumerate(value))
    if origin is dict:
        if not isinstance(value, dict):
            raise SceneError(name, f"must be a table of strings, got {_fmt(value)}")
        out = {}
        for k, v in value.items():
            if not isinstance(v, str):
                raise SceneError(f"{name}.{k}", f"must be a string, got {_fmt(v)}")
            out[str(k)] = v
        return out
    raise TypeError(f"unsupported field type {tp!r} for {name}")  # a programming error


def validate(obj: Any) -> None:
    """Check every field of a description record against its declared type and range.

    Called from ``__post_init__``; values are coerced in place (ints to floats, lists to
    tuples) through ``object.__setattr__`` because the records are frozen.
    """
    hints = _hints(type(obj))
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        coerced = _coerce(f.name, hints[f.name], value, f.metadata)
        if coerced is not value:
            object.__setattr__(obj, f.name, coerced)


def from_mapping(cls: type, data: Any, path: str = "") -> Any:
    """Build description ``cls`` from a nested mapping, refusing unknown keys."""
    if not isinstance(data, dict):
        raise SceneError(path, f"must be a table, got {_fmt(data)}")
    names = [f.name for f in dataclasses.fields(cls)]
    for key in data:
        if key not in names:
            near = difflib.get_close_matches(str(key), names, n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            where = f"{path}.{key}" if path else str(key)
            raise SceneError(where, f"unknown key{hint}; allowed: {', '.join(names)}")
    hints = _hints(cls)
    kwargs = {}
    for f in dataclasses.fields(cls):
        if f.name not in data:
            continue
        sub = f"{path}.{f.name}" if path else f.name
        try:
            kwargs[f.name] = _coerce("", hints[f.name], data[f.name], f.metadata)
        except SceneError as err:
            raise err.prefixed(sub) from None
    try:
        return cls(**kwargs)
    except SceneError as err:
        raise err.prefixed(path) from None
    except TypeError as err:  # missing required field
        missing = [
            f.name
            for f in dataclasses.fields(cls)
            if f.default is dataclasses.MISSING
            and f.default_factory is dataclasses.MISSING
            and f.name not in kwargs
        ]
        if missing:
            where = f"{path}.{missing[0]}" if path else missing[0]
            raise SceneError(where, "is required but missing") from None
        raise SceneError(path, str(err)) from None


def to_mapping(obj: Any) -> Any:
    """Inverse of :func:`from_mapping`: plain dicts, lists, floats and strings (None dropped)."""
    if dataclasses.is_dataclass(obj):
        out = {}
        for f in dataclasses.fields(obj):
            v = getattr(obj, f.name)
            if v is None:
                continue
            out[f.name] = to_mapping(v)
        return out
    if isinstance(obj, tuple):
        return [to_mapping(v) for v in obj]
    if isinstance(obj, dict):
        return {k: to_mapping(v) for k, v in obj.items()}
    return obj


def json_schema(cls: type) -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of description ``cls``, with units in the descriptions."""
    hints = _hints(cls)
    props: dict[str, Any] = {}
    required = []
    for f in dataclasses.fields(cls):
        props[f.name] = _type_schema(hints[f.name], f.metadata)
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            required.append(f.name)
        elif f.default is not dataclasses.MISSING and not dataclasses.is_dataclass(f.default):
            if f.default is not None:
                props[f.name]["default"] = to_mapping(f.default)
    schema = {
        "type": "object",
        "title": cls.__name__,
        "properties": props,
        "additionalProperties": False,
    }
    doc = (cls.__doc__ or "").strip().splitlines()
    if doc:
        schema["description"] = doc[0]
    if required:
        schema["required"] = required
    return schema


def _type_schema(tp: Any, meta: typing.Mapping[str, Any]) -> dict[str, Any]:
    origin = typing.get_origin(tp)
    text = meta.get("doc", "")
    if meta.get("unit"):
        text = f"{text} [{meta['unit']}]".strip()
    out: dict[str, Any]
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        out = _type_schema(args[0], meta)
        return out
    if dataclasses.is_dataclass(tp):
        return json_schema(tp)
    if tp is float or tp is int:
        out = {"type": "number" if tp is float else "integer"}
        for key, js in (
            ("gt", "exclusiveMinimum"),
            ("ge", "minimum"),
            ("lt", "exclusiveMaximum"),
            ("le", "maximum"),
        ):
            if meta.get(key) is not None:
                out[js] = meta[key]
    elif tp is bool:
        out = {"type": "boolean"}
    elif tp is str:
        out = {"type": "string"}
        if meta.get("choices"):
            out["enum"] = list(meta["choices"])
    elif origin is tuple:
        out = {"type": "array", "items": _type_schema(typing.get_args(tp)[0], meta)}
        text = meta.get("doc", "")
    elif origin is dict:
        out = {"type": "object", "additionalProperties": {"type": "string"}}
    else:  # pragma: no cover - programming error
        raise TypeError(tp)
    if text:
        out["description"] = text
    return out


#: one segment of a dotted field path: a name, then any number of ``[index]``
_SEGMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")


def split_path(path: str, source: str = "--set") -> list[tuple[str, list[int]]]:
    """``"bents[1].y.beta"`` → ``[("bents", [1]), ("y", []), ("beta", [])]``; a malformed
    path is refused (SceneError naming ``source``, the option or call that gave it)."""
    out = []
    for part in path.split("."):
        m = _SEGMENT.match(part)
        if not m:
            raise SceneError(source, f"malformed path {path!r}")
        out.append((m.group(1), [int(i) for i in re.findall(r"\[(\d+)\]", m.group(2))]))
    return out


def set_path(data: dict[str, Any], path: str, value: Any, source: str = "--set") -> None:
    """Set the field at dotted ``path`` (``contact.stiffness``, ``bents[1].y.beta``) of a
    nested mapping (as :func:`to_mapping` gives) to ``value``, in place: the one path syntax
    of ``--set`` overrides and :meth:`Scene.replace`. Missing tables are created (an unknown
    name is refused when the mapping is validated, :func:`from_mapping`); an index past the
    end of a list, or a path through a value that is not a table, is refused naming the path.
    """
    parts = split_path(path, source)
    node: Any = data
    for depth, (key, idx) in enumerate(parts):
        last = depth == len(parts) - 1
        if not isinstance(node, dict):
            raise SceneError(path, "names no field of the scene")
        if last and not idx:
            node[key] = value
            return
        if key not in node:
            node[key] = {} if not idx else []
        node = node[key]
        for j, i in enumerate(idx):
            if not isinstance(node, list) or i >= len(node):
                raise SceneError(path, f"index {i} is out of range")
            if last and j == len(idx) - 1:
                node[i] = value
            else:
                node = node[i]

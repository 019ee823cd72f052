"""The arguments and checks the CLI's commands share: whole numbers in a range, seconds, the
scene and ``--set`` arguments, engine lists, and the output folder check that locks it."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from deckpound.compare.engines import ENGINES
from deckpound.models.errors import SceneError
from deckpound.models.file_io import check_parent, claim_folder


def int_in(lo: int, hi: int):
    """An argparse type: a whole number in [lo, hi] (a negative count never runs silently)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"must be in [{lo}, {hi}], got {value}")
        return value

    parse.__name__ = "whole number"
    return parse


def add_scene_args(p: argparse.ArgumentParser) -> None:
    """SCENE positional and repeatable --set PATH=VALUE."""
    p.add_argument("scene", metavar="SCENE", help="built-in scene name or TOML file")
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="PATH=VALUE",
        help="override a scene field, e.g. --set contact.stiffness=2e6 (repeatable)",
    )


def seconds(text: str) -> float:
    """A positive, finite number of seconds (refuses nan, inf, 0 and negatives)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number of seconds, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds > 0, got {text!r}")
    return value


def benchmark_scene_args(p: argparse.ArgumentParser, out_default: str, quick_help: str) -> None:
    """--scene (default: the benchmark), --set, -o and --quick of the whole-study commands."""
    p.add_argument("--scene", default="saiidi-4span", help="scene (default: the benchmark)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE")
    p.add_argument("-o", "--output", default=out_default, metavar="DIR")
    p.add_argument("--quick", action="store_true", help=quick_help)


def engine_list(text: str | None) -> list[str]:
    """The engines of ``--engines NAME,...`` (every registered engine when not given);
    an unknown name is refused with the valid ones."""
    if text is None:
        return list(ENGINES)
    names = [e.strip() for e in text.split(",") if e.strip()]
    for e in names:
        if e not in ENGINES:
            raise SceneError(
                "--engines", f"unknown engine {e!r}; valid engines: {', '.join(ENGINES)}"
            )
    if not names:
        raise SceneError("--engines", "names no engine")
    return names


def check_output_folder(path: str) -> Path:
    """Refuse, before any work, an output folder that can never be written: a symbolic link,
    a file in its place, a file among its parents, or one in use by another running command
    (exit status 2); lock it for the rest of the command (:func:`deckpound.models.file_io.claim_folder`)."""
    out = Path(path)
    if out.is_symlink():
        raise SceneError(
            "--output",
            f"{str(out)!r} is a symbolic link; deckpound never writes "
            "through links: give the real folder",
        )
    if out.exists() and not out.is_dir():
        raise SceneError("--output", f"{str(out)!r} exists and is not a folder")
    check_parent(out)
    claim_folder(out)
    return out

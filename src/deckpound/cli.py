"""The ``deckpound`` command line.

Every user error (bad scene, record, option) ends in one line on stderr and exit status 2;
an engine that fails ends with its status message and exit status 1. Subcommands live in
small modules (``_cli_*``) that each register themselves on the parser.
"""

from __future__ import annotations

import argparse
import sys
import warnings

from deckpound import __version__
from deckpound.models.errors import EngineFailure, SceneError


class UsageError(Exception):
    """Bad command-line usage (argparse's own errors are routed here)."""


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line and exit status 2, never a usage dump."""

    def error(self, message: str):  # noqa: D401 - argparse API
        raise UsageError(f"{self.prog}: {message}")


def build_parser() -> argparse.ArgumentParser:
    from . import _cli_engines, _cli_scene, _cli_study

    parser = _Parser(prog="deckpound", description="Deck-abutment pounding of bridges, three "
                     "ways from one scene: OpenSees, compliance and nonsmooth engines.")
    parser.add_argument("--version", action="version", version=f"deckpound {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for module in (_cli_scene, _cli_engines, _cli_study):
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status."""
    warnings.simplefilter("default")
    warnings.formatwarning = lambda msg, cat, *a, **k: f"deckpound: warning: {msg}\n"
    try:
        parser = build_parser()
        try:
            args = parser.parse_args(argv)
        except SystemExit as done:  # --help / --version have printed their text
            return done.code if isinstance(done.code, int) else 0
        return int(args.func(args) or 0)
    except (SceneError, UsageError) as err:
        print(f"deckpound: error: {err}", file=sys.stderr)
        return 2
    except EngineFailure as err:
        print(f"deckpound: engine failure: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("deckpound: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0


def add_scene_args(p: argparse.ArgumentParser) -> None:
    """SCENE positional and repeatable --set PATH=VALUE."""
    p.add_argument("scene", metavar="SCENE", help="built-in scene name or TOML file")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                   help="override a scene field, e.g. --set contact.stiffness=2e6 (repeatable)")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

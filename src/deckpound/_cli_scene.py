"""CLI: ``scene list|show|validate|schema`` and ``excitation plot``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from deckpound.models.errors import SceneError

from ._cli_args import add_scene_args
from ._terminal import terminal_text, terminal_toml


def register(sub: argparse._SubParsersAction) -> None:
    scene = sub.add_parser("scene", help="list, show, validate scenes; print the schema")
    ssub = scene.add_subparsers(dest="scene_command", metavar="ACTION")
    ssub.required = True
    p = ssub.add_parser("list", help="built-in scenes")
    p.set_defaults(func=_list)
    p = ssub.add_parser("show", help="print a scene as TOML (edit it and run it)")
    add_scene_args(p)
    p.set_defaults(func=_show)
    p = ssub.add_parser("validate", help="check a scene and its records; exit 2 if bad")
    add_scene_args(p)
    p.set_defaults(func=_validate)
    p = ssub.add_parser("schema", help="JSON Schema of the scene file")
    p.set_defaults(func=_schema)

    exc = sub.add_parser("excitation", help="support motion of a scene")
    esub = exc.add_subparsers(dest="excitation_command", metavar="ACTION")
    esub.required = True
    p = esub.add_parser("plot", help="plot every support's displacement, velocity, acceleration")
    add_scene_args(p)
    p.add_argument("-o", "--output", required=True, metavar="FILE.png")
    p.set_defaults(func=_plot)


def _list(args) -> int:
    from deckpound.models.scene_io import builtin_scene_names, load_scene

    for name in builtin_scene_names():
        print(f"{name}\t{load_scene(name).description}")
    return 0


def _show(args) -> int:
    from deckpound.models.scene_io import load_scene, scene_to_toml

    # control and bidi characters of a name or note as TOML escapes: the same scene, shown safely
    text = terminal_toml(scene_to_toml(load_scene(args.scene, args.overrides)))
    sys.stdout.write(text)  # a full or closed stdout: OSError, exit status 3 (cli.main)
    return 0


def _validate(args) -> int:
    from deckpound.compare.engines import engine_names, get_engine
    from deckpound.models import plausibility
    from deckpound.models.damping import rayleigh_coefficients
    from deckpound.models.excitation import support_motion
    from deckpound.models.scene_io import load_scene

    scene = load_scene(args.scene, args.overrides)
    motion = support_motion(scene)
    every_engine = [get_engine(name) for name in engine_names()]
    report = plausibility.enforce(
        scene, motion, engines=every_engine
    )  # steps vs record, periods, contact, output
    rayleigh_coefficients(scene)  # refuses damping.modes beyond the number of modes
    # a free deck (bents = []) has three rigid-body modes (infinite periods): name them
    finite = [T for T in report.periods if float("inf") != T]
    rigid = len(report.periods) - len(finite)
    segments = (
        f"{len(scene.segments)} deck segments, joint gaps "
        + "/".join(f"{j.gap:g}" for j in scene.joints)
        + " m, "
        if scene.segments is not None
        else ""
    )
    print(
        f"{terminal_text(scene.name)}: valid; {segments}{len(scene.bents)} bents, gaps "
        f"{scene.seats[0].gap:g}/{scene.seats[1].gap:g} m, record {motion.duration:g} s "
        f"({len(motion.channels)} supports), analysis {report.duration:g} s, "
        + (f"{rigid} rigid-body modes, " if rigid else "")
        + f"periods {', '.join(f'{T:.3f}' for T in finite[:3])} s"
        + "".join(
            f"; {name} {given:g} s runs as {h:.4g} s (contact-step rule, "
            f"run.steps_per_contact_period = {scene.run.steps_per_contact_period:g})"
            for name, given, h in report.shortened
        )
    )
    return 0


def _schema(args) -> int:
    from deckpound.models.scene_io import scene_schema_json

    print(scene_schema_json())
    return 0


def _plot(args) -> int:
    from deckpound.models.excitation import support_motion
    from deckpound.models.file_io import check_parent, check_target
    from deckpound.models.scene_io import load_scene

    out = Path(args.output)
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise SceneError("--output", f"must end in .png, .pdf or .svg, got {str(out)!r}")
    check_target(out)  # a folder or a symbolic link in its place: refused before any work
    check_parent(out)  # below a regular file: can never be written
    scene = load_scene(args.scene, args.overrides)
    motion = support_motion(scene)
    from deckpound.compare.report.plotting import plot_excitation

    plot_excitation(scene, motion, out)  # atomic (compare.style.save); OSError: exit status 3
    print(f"wrote {terminal_text(out)}")
    return 0

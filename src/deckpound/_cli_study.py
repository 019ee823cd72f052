"""CLI: ``compare``, ``study``, ``paper`` and ``export-vtk``."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from deckpound.compare.engines import engine_names, get_engine
from deckpound.models.errors import SceneError

from ._cli_args import (
    add_scene_args,
    benchmark_scene_args,
    check_output_folder,
    engine_list,
    int_in,
)
from ._terminal import terminal_text


def _scheduler(text: str) -> str:
    from deckpound.compare.cases import check_scheduler_address

    try:
        return check_scheduler_address(text)
    except SceneError as err:
        raise argparse.ArgumentTypeError(err.reason) from None


def _parallel_args(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--workers",
        type=int_in(1, 1024),
        default=None,
        help="local worker processes (default: one per core)",
    )
    p.add_argument(
        "--scheduler",
        type=_scheduler,
        default=None,
        metavar="ADDRESS",
        help="run cases on a Dask distributed cluster, e.g. tcp://127.0.0.1:8786",
    )
    p.add_argument(
        "--cache",
        default=None,
        metavar="DIR",
        help="result cache (default: OUT/cache); finished cases are never recomputed",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("compare", help="run engines on one scene, align, compare, plot")
    add_scene_args(p)
    p.add_argument(
        "--engines",
        default=None,
        help="comma-separated engine names (default: every registered engine)",
    )
    p.add_argument(
        "--reference",
        default=None,
        metavar="ENGINE",
        help="engine the others are compared with (default: opensees if run, else the first)",
    )
    p.add_argument(
        "--measured",
        default=None,
        metavar="CSV",
        help="measured data (t + result column names) to compare against",
    )
    p.add_argument("-o", "--output", required=True, metavar="DIR")
    _parallel_args(p)
    p.set_defaults(func=_compare)

    p = sub.add_parser("study", help="a sensitivity study: table + figure")
    p.add_argument(
        "name",
        metavar="NAME",
        help="stiffness, friction, sticking, law, geometry, "
        "opensees-mode, skew, damping, joint, sequence or variability",
    )
    add_scene_args(p)
    p.add_argument(
        "-o", "--output", default=None, metavar="DIR", help="output folder (default: study-NAME)"
    )
    p.add_argument("--quick", action="store_true", help="fewer cases")
    p.add_argument(
        "--state",
        default="virgin",
        metavar="STATE",
        help="start state: virgin (the scene as given, default), runK (the gap and "
        "bent stiffness the sequence carries into run K, at run K's PGA) or strongest",
    )
    p.add_argument(
        "--state-engine",
        default=None,
        metavar="ENGINE",
        help="engine whose sequence carries the state (default: the reference, opensees)",
    )
    p.add_argument("--pdf", action="store_true", help="figures also as PDF")
    _parallel_args(p)
    _variability_args(p)
    p.set_defaults(func=_study)

    p = sub.add_parser("paper", help="the main job: sequence x 3 engines + studies + report")
    benchmark_scene_args(p, "deckpound-report", "fewer study cases")
    p.add_argument(
        "--studies", default=None, help="comma-separated subset of studies (default: all)"
    )
    p.add_argument(
        "--full-histories",
        action="store_true",
        help="also write every run's aligned histories (Parquet and CSV, ~120 MB on the benchmark)",
    )
    p.add_argument("--pdf", action="store_true", help="figures also as PDF")
    p.add_argument(
        "--redraw",
        action="store_true",
        help="draw every figure (default: reuse those whose inputs are unchanged)",
    )
    _parallel_args(p)
    p.set_defaults(func=_paper)

    for name, levels_opt, what in (
        ("ida", "--levels", "incremental dynamic analysis: each record pair scaled to every level"),
        ("msa", "--stripes", "multiple-stripe analysis: the record pairs at each stripe"),
    ):
        p = sub.add_parser(name, help=f"{what}, with fragility curves (unseating, rotation)")
        add_scene_args(p)
        p.add_argument("--records", required=True, metavar="DIR", help="record pairs (AT2)")
        p.add_argument(
            "--im",
            default="sa-t1",
            choices=("sa-t1", "pga", "pgv", "rotd50"),
            help="intensity measure of the pair (one factor per pair): geometric-mean "
            "Sa(T1, 5 %%) [g] (default), PGA [g], PGV [m/s] or RotD50(T1) [g]",
        )
        p.add_argument(
            levels_opt,
            dest="levels",
            required=True,
            metavar="LEVELS",
            help="start:stop:step (stop included) or a,b,c, in the IM's unit",
        )
        p.add_argument(
            "--engines",
            default="compliance",
            metavar="NAMES",
            help="comma-separated engines, each running the whole sweep (default: compliance)",
        )
        p.add_argument(
            "--theta-limit",
            type=float,
            default=None,
            metavar="RAD",
            help="also fit the limit state peak deck rotation > RAD",
        )
        p.add_argument("--rotate90", action="store_true", help="also each pair turned by 90°")
        p.add_argument(
            "--vary",
            default=None,
            metavar="PATH=V1,V2,...",
            help="run the whole sweep once per value of a scene field (at most 10 values), "
            "e.g. contact.friction=0,0.2,0.4 or seats[0].gap=0.0127,0.025; gap=... sets both "
            "seats' gap",
        )
        p.add_argument("-o", "--output", default=None, metavar="DIR")
        _parallel_args(p)
        p.set_defaults(func=_ida, sweep=name)

    p = sub.add_parser("export-vtk", help="deck and seat outlines over time for ParaView")
    p.add_argument("result_dir", metavar="RESULT_DIR")
    p.add_argument("-o", "--output", required=True, metavar="DIR")
    p.add_argument(
        "--every", type=int_in(1, 10**9), default=1, help="write every N-th output sample"
    )
    p.add_argument(
        "--format",
        dest="fmt",
        choices=("xdmf", "pvd"),
        default="xdmf",
        help="xdmf: one time-series file per engine (default); pvd: a .pvd "
        "collection with one .vtu file per output time",
    )
    p.set_defaults(func=_export_vtk)


def _checked_scene(args, engines) -> object:
    """The scene of a whole-study command, with the plausibility checks of its engines."""
    from deckpound.models import plausibility
    from deckpound.models.excitation import support_motion
    from deckpound.models.scene_io import load_scene

    scene = load_scene(args.scene, args.overrides)
    checked = [get_engine(name) for name in engines]
    plausibility.enforce(scene, support_motion(scene), engines=checked)
    return scene


def _compare(args) -> int:
    from deckpound.compare.compare_run import run_compare
    from deckpound.models.file_io import output_folder

    engines = engine_list(args.engines)
    if args.reference is not None:
        engine_list(args.reference)  # an unknown name is refused with the valid ones
    check_output_folder(args.output)
    scene = _checked_scene(args, engines)
    measured = None
    if args.measured:
        from deckpound.compare.metrics import measured_result

        measured = measured_result(args.measured)
    with output_folder(args.output, "compare") as out:
        summary = run_compare(
            scene,
            engines,
            out,
            measured=measured,
            workers=args.workers,
            scheduler=args.scheduler,
            cache_dir=args.cache,
            progress=not args.no_progress,
            reference=args.reference,
        )
    print(terminal_text(summary, keep_newlines=True))
    return 0


def _study(args) -> int:
    from deckpound.compare.result_cache import ResultCache
    from deckpound.compare.studies.sensitivity import STUDY_NAMES, run_study, study_units
    from deckpound.models.file_io import output_folder, write_csv

    if args.name == "variability":
        return _variability(args)
    if args.name not in STUDY_NAMES:
        raise SceneError(
            "study", f"unknown study {args.name!r}; valid studies: {', '.join(STUDY_NAMES)}"
        )
    out = check_output_folder(args.output or f"study-{args.name}")
    scene = _checked_scene(args, engine_names())
    formats = ("pdf",) if args.pdf else ()
    with output_folder(out, f"study {args.name}") as out:
        cache_dir = Path(args.cache) if args.cache else out / "cache"
        if args.name == "sequence":
            from deckpound.compare.report import figures
            from deckpound.compare.report.outputs import write_csv
            from deckpound.compare.report.paper import sequence_table, sequence_units
            from deckpound.compare.studies.sequence_run import run_sequences

            if args.state != "virgin":
                raise SceneError(
                    "--state",
                    "applies to the sensitivity studies; the sequence "
                    "starts from the scene as given",
                )
            seqs = run_sequences(
                scene,
                list(engine_names()),
                cache_dir,
                args.workers,
                args.scheduler,
                not args.no_progress,
            )
            table = sequence_table(seqs)
            write_csv(table, out / "sequence.csv", sequence_units(table))
            figures.peak_vs_pga(table, scene, out / "sequence.png", formats=formats)
        else:
            table, _ = run_study(
                args.name,
                scene,
                out,
                quick=args.quick,
                cache=ResultCache(cache_dir),
                workers=args.workers,
                scheduler=args.scheduler,
                progress=not args.no_progress,
                state=args.state,
                state_engine=args.state_engine,
                formats=formats,
            )
    cols = [
        c
        for c in (
            "label",
            "engine",
            "state",
            "run",
            "pga",
            "peak_theta",
            "peak_y_rel",
            "peak_fn_joint",
            "joint_closures",
            "joint_margin_min",
            "gap_closures",
            "wall_time",
            "status",
        )
        if c in table
    ]
    from deckpound.compare.report.outputs import unit_header
    from deckpound.compare.report.paper import sequence_units

    units = study_units(args.name, table) if args.name != "sequence" else sequence_units(table)
    print(unit_header(table[cols], units).to_string(index=False))
    print(f"wrote {terminal_text(out)}")
    return 0


def _paper(args) -> int:
    from deckpound.compare.report.paper import run_paper
    from deckpound.compare.studies.sensitivity import STUDIES
    from deckpound.models.file_io import output_folder

    studies = None
    if args.studies:
        studies = tuple(s.strip() for s in args.studies.split(",") if s.strip())
        for s in studies:
            if s not in STUDIES:
                raise SceneError("--studies", f"unknown study {s!r}; valid: {', '.join(STUDIES)}")
    check_output_folder(args.output)
    scene = _checked_scene(args, engine_names())
    # the folder is marked INCOMPLETE until the report is written; a re-run resumes from the
    # cache (default DIR/cache) and removes the marker
    with output_folder(args.output, "paper") as out:
        report = run_paper(
            scene,
            out,
            quick=args.quick,
            workers=args.workers,
            scheduler=args.scheduler,
            cache_dir=args.cache,
            studies=studies,
            progress=not args.no_progress,
            full_histories=args.full_histories,
            formats=("pdf",) if args.pdf else (),
            redraw=args.redraw,
        )
    print(f"wrote {terminal_text(report)} and {terminal_text(report.with_suffix('.html'))}")
    return 0


def _export_vtk(args) -> int:
    from deckpound.compare.report.vtk import check_result_folder, export_vtk
    from deckpound.models.file_io import output_folder

    check_output_folder(args.output)
    results = check_result_folder(args.result_dir, args.every)  # damaged input: exit 2
    with output_folder(args.output, "export-vtk") as out:
        written = export_vtk(args.result_dir, out, args.every, fmt=args.fmt, results=results)
    for p in written:
        print(f"wrote {terminal_text(p)}")
    return 0


# -- the record-to-record variability study (issue 14: speed owner) ---------------------------


def _variability_args(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("variability study")
    g.add_argument(
        "--cases",
        type=int_in(1, 1_000_000),
        default=None,
        help="variability: N seeds of the synthetic record (default 1000)",
    )
    g.add_argument(
        "--records",
        default=None,
        metavar="DIR",
        help="variability: every record pair in DIR instead of seeds (PEER component "
        "names, NAME_x/NAME_y, or DIR/manifest.csv with pair,file_x,file_y)",
    )
    g.add_argument(
        "--rotate90",
        action="store_true",
        help="variability: also run each pair of --records with its components swapped",
    )
    g.add_argument(
        "--engine",
        default="compliance",
        metavar="NAME",
        help="variability: the engine (default: compliance)",
    )


def _variability(args) -> int:
    from deckpound.compare.engines import get_engine
    from deckpound.compare.studies.variability import QUANTITIES, run_variability
    from deckpound.models.file_io import output_folder

    get_engine(args.engine)  # an unknown name is refused before any work
    if args.cases is not None and args.records is not None:
        raise SceneError("--cases", "give either --cases N or --records DIR, not both")
    cases = args.cases if args.records is None else None
    if cases is None and args.records is None:
        cases = 20 if args.quick else 1000
    out = check_output_folder(args.output or "study-variability")
    scene = _checked_scene(args, (args.engine,))
    with output_folder(out, "study variability") as out:
        table, summary = run_variability(
            scene,
            out,
            engine=args.engine,
            cases=cases,
            records=args.records,
            rotate=args.rotate90,
            cache_dir=args.cache,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=not args.no_progress,
        )
    view = summary.set_index("quantity").loc[list(QUANTITIES)]
    print(view[["unit", "n", "median", "p16", "p84"]].to_string(float_format=lambda v: f"{v:.4g}"))
    failed = summary.attrs.get("failed", 0)
    doubtful = summary.attrs.get("doubtful", 0)
    unseated = summary.attrs.get("unseated", 0)
    print(
        f"{len(table)} cases ({failed} not finished, {doubtful} doubtful: energy created at a "
        f"contact, {unseated} unseated; all left out of the statistics) in "
        f"{summary.attrs['wall']:.1f} s; "
        f"wrote {terminal_text(out)}"
    )
    return 0 if not failed and (not doubtful or scene.run.accept_doubtful) else 1


# -- IDA and multiple-stripe analysis (issue 30) -------------------------------------------------


def _ida(args) -> int:
    """``deckpound ida|msa``: the sweep's rows, the fragility table, one line per limit state."""
    from deckpound.compare.studies.ida import IMS, parse_levels, parse_vary, run_ida
    from deckpound.models.file_io import output_folder

    engines = engine_list(args.engines)  # an unknown name is refused before any work
    option = "--levels" if args.sweep == "ida" else "--stripes"
    levels = parse_levels(args.levels, option)
    if args.theta_limit is not None and not (
        math.isfinite(args.theta_limit) and args.theta_limit > 0
    ):
        raise SceneError("--theta-limit", f"must be a finite angle > 0 rad, got {args.theta_limit}")
    out = check_output_folder(args.output or args.sweep)
    scene = _checked_scene(args, engines)
    variants = parse_vary(args.vary, scene) if args.vary is not None else None
    with output_folder(out, args.sweep) as out:
        table, frag = run_ida(
            scene,
            out,
            records=args.records,
            im=args.im,
            levels=levels,
            engines=tuple(engines),
            theta_limit=args.theta_limit,
            rotate=args.rotate90,
            cache_dir=args.cache,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=not args.no_progress,
            title=args.sweep,
            variants=variants,
        )
    unit = IMS[args.im][2]
    method = args.sweep
    for _, r in frag[frag["method"] == method].iterrows():
        fit = (
            f"median {r['median']:.4g} {unit}, beta {r['beta']:.3g}" if not r["note"] else r["note"]
        )
        who = f"{r['engine']} ({r['variant']})" if r["variant"] else r["engine"]
        print(
            f"{who}, {r['limit_state']}: {fit} ({r['cases']} cases fitted, "
            f"{r['left_out']} left out)"
        )
    counts = table["status"].value_counts().to_dict()
    print(
        f"{len(table)} cases ({', '.join(f'{v} {k}' for k, v in sorted(counts.items()))}); "
        f"wrote {terminal_text(out)}"
    )
    return 0

"""CLI: the measurement commands ``bench`` (work–precision, skips, speed table) and ``stress``."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._cli_args import benchmark_scene_args, check_output_folder, engine_list, int_in, seconds
from ._terminal import terminal_text


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="work-precision benchmark: wall time vs error, every engine")
    benchmark_scene_args(p, "deckpound-bench", "fewer configurations, shorter records")
    p.add_argument(
        "--repeats", type=int_in(1, 1000), default=None, help="runs per configuration (median)"
    )
    p.add_argument(
        "--skips",
        action="store_true",
        help="instead: time the compliance engine's work-saving skips on and off "
        "(identical results checked) and the adaptive step sizes in/out of contact",
    )
    _speed_args(p)
    p.set_defaults(func=_bench)

    p = sub.add_parser("stress", help="stability stress test over hard settings, every engine")
    benchmark_scene_args(p, "deckpound-stress", "a small subset of the grid")
    p.add_argument(
        "--engines",
        default=None,
        help="comma-separated engine names (default: every registered engine)",
    )
    p.add_argument("--timeout", type=seconds, default=300.0, help="seconds per cell")
    p.set_defaults(func=_stress)


def _bench(args) -> int:
    from deckpound.models.file_io import output_folder
    from deckpound.models.scene_io import load_scene

    scene = load_scene(args.scene, args.overrides)
    with output_folder(check_output_folder(args.output), "bench"):
        return _bench_body(args, scene)


def _bench_body(args, scene) -> int:
    from deckpound.compare.bench.skips import skip_failures
    from deckpound.compare.bench.work_precision import run_bench

    if args.skips:
        from deckpound.compare.bench.skips import run_skips

        table, steps = run_skips(scene, args.output, quick=args.quick, repeats=args.repeats)
        cols = [
            "scene",
            "skip",
            "time_with",
            "time_without",
            "speedup",
            "us_per_step_with",
            "us_per_step_without",
            "max_abs_diff",
        ]
        print(table[cols].to_string(index=False, float_format=lambda v: f"{v:.3g}"))
        print(
            steps[
                ["scene", "commit_cap", "where", "steps", "median", "min", "max", "time"]
            ].to_string(index=False, float_format=lambda v: f"{v:.3g}")
        )
        bad = skip_failures(table)
        print(
            f"wrote {args.output}; "
            + (
                "every skip gives identical results"
                if not len(bad)
                else f"{len(bad)} skip(s) changed a result"
            )
        )
        return 0 if not len(bad) else 1
    if not args.speed_only:
        table = run_bench(scene, args.output, quick=args.quick, repeats=args.repeats)
        cols = [
            c
            for c in (
                "scene",
                "config",
                "status",
                "wall",
                "compile_time",
                "us_per_step",
                "err_primary",
                "err_peak_theta",
                "err_peak_y",
                "nrmse_theta",
                "speedup_bound",
                "speedup_vs_opensees_equal_error",
            )
            if c in table
        ]
        print(table[cols].to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    _speed_table(args)
    print(f"wrote {terminal_text(args.output)}")
    return 0


def _stress(args) -> int:
    from deckpound.compare.bench.stress import run_stress
    from deckpound.models.file_io import output_folder
    from deckpound.models.scene_io import load_scene

    engines = tuple(engine_list(args.engines))
    out = check_output_folder(args.output)
    scene = load_scene(args.scene, args.overrides)
    with output_folder(out, "stress"):
        table = run_stress(scene, out, quick=args.quick, engines=engines, timeout=args.timeout)
    bad = table[(table["status"] != "success") | (~table["finite"])]
    print(table.groupby(["engine", "status"]).size().to_string())
    print(
        f"{len(table)} cells, {len(bad)} not finished with finite output; "
        f"wrote {terminal_text(args.output)}"
    )
    return 0


# -- the speed table (whole commands, every engine) -------------------------------------------


def _speed_args(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("speed table")
    g.add_argument(
        "--speed-only",
        action="store_true",
        help="only the speed table (processes and in-process runs of every engine)",
    )


def _speed_table(args) -> None:
    import sys

    from deckpound.compare.bench import speed
    from deckpound.models.file_io import atomic_write_text

    repeats = args.repeats if args.repeats is not None else 3
    rows, context = speed.measure(
        args.scene,
        args.overrides,
        repeats=repeats,
        progress=lambda t: print(f"deckpound bench: {t}", file=sys.stderr, flush=True),
    )
    block = speed.markdown(rows, context)
    print(block)
    atomic_write_text(Path(args.output) / "speed.md", block + "\n")

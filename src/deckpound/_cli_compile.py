"""CLI: ``compile`` — compile (or load) every kernel once, with a progress line per item."""

from __future__ import annotations

import argparse
import sys
import time

from ._terminal import terminal_text


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "compile",
        help="compile every numba kernel a run can use, once (set-up "
        "step: ./run.sh does it after installing; pip users run it once)",
    )
    p.add_argument(
        "--engines",
        default=None,
        help="comma-separated engine names (default: every analytic engine)",
    )
    p.add_argument(
        "--stamp",
        default=None,
        metavar="FILE",
        help="after success, write KEY and the cache folder into FILE (run.sh)",
    )
    p.add_argument("--key", default="", help="the first line of the stamp file")
    p.set_defaults(func=_compile)


def _compile(args) -> int:
    from deckpound.compare import warmup
    from deckpound.compare.engines import engine_names
    from deckpound.models.errors import SceneError

    engines = None
    if args.engines:
        engines = [e.strip() for e in args.engines.split(",") if e.strip()]
        for e in engines:
            if e not in engine_names():
                raise SceneError(
                    "--engines", f"unknown engine {e!r}; valid engines: {', '.join(engine_names())}"
                )
    try:
        modules = warmup.byte_compile()
        print(f"deckpound compile: Python bytecode of {modules} modules written", flush=True)
    except OSError as err:  # e.g. a read-only site-packages: the kernels matter more
        print(
            f"deckpound: warning: {terminal_text(err)}: where PYTHONDONTWRITEBYTECODE is set, "
            "every process compiles deckpound's modules from source",
            file=sys.stderr,
        )
    where = terminal_text(warmup.cache_location())
    print(f"deckpound compile: kernels are cached in {where}", flush=True)
    t0 = time.perf_counter()

    def report(start: str, end: str) -> None:
        print(start + end, end="\n" if end else "", flush=True)

    results = warmup.warm(engines=engines, report=report)
    total = time.perf_counter() - t0
    compiled = sum(r.compiled for r in results)
    for note in sorted({n for r in results for n in r.notes}):
        print(
            f"deckpound: warning: {note} (the kernel will compile in every process)",
            file=sys.stderr,
        )
    failed = [r for r in results if r.status != "success"]
    print(
        f"deckpound compile: {len(results)} items in {total:.1f} s, {compiled} kernels "
        f"compiled ({'all loaded from the cache' if not compiled else 'now cached'}); "
        f"runs now load them from {where}",
        flush=True,
    )
    if failed:
        for r in failed:
            print(
                f"deckpound: warning: warm-up run {r.item.engine}: {r.item.label} ended {r.status}",
                file=sys.stderr,
            )
        return 1
    if args.stamp:
        from deckpound.models.file_io import atomic_write_text

        atomic_write_text(args.stamp, f"{args.key}\n{where}\n")
    return 0

"""The run-side families of the CLI fuzz corpus (:mod:`tests._fuzz_corpus`).

engine   steps and output rates against the analysis length (30 s step on a short record,
         output step longer than the run, record shorter than one step)
vtk      ``export-vtk`` of damaged result folders
name     hostile scene names (TeX, control characters) through every figure
option   bad option values (--workers, --every, --timeout, --scheduler, --engines)
stream   closed stdout and stderr (``>&-``, ``2>&-``): exit 3 only for output that cannot
         be written to stdout, otherwise the status of open streams
"""

from __future__ import annotations

from _fuzz_corpus import ENGINE_NAMES, OUT, SHORT, Case


def engine_family() -> list[Case]:
    cases = []
    failing = (
        "opensees.tolerance=1e-30",
        "opensees.max_iterations=1",
        "opensees.fallback=none",
        "compliance.tolerance=1e-30",
        "compliance.max_iterations=1",
        "nonsmooth.tolerance=1e-30",
        "nonsmooth.max_iterations=1",
        "excitation.pga=2",
        "seats[0].gap=0",
    )
    sets = tuple(a for f in failing for a in ("--set", f))
    for engine in ENGINE_NAMES:  # the engine cannot converge: exit 1, the failed run written
        for substeps in ("2", "10"):
            cases.append(
                Case(
                    f"engine:fails:{engine}:{substeps}",
                    "engine",
                    (
                        "run",
                        "saiidi-4span",
                        *SHORT,
                        *sets,
                        "--set",
                        f"opensees.substeps={substeps}",
                        "--engine",
                        engine,
                        "-o",
                        OUT,
                    ),
                    target=OUT,
                    target_kind="dir",
                    expect=(1,),
                )
            )
    # (setting, kind): "field" is refused by field validation whatever the engine, "plaus" by
    # the plausibility checks of the engines that use it, "ok" runs
    grid = [
        ("opensees.dt=30", "plaus"),
        ("opensees.dt=0.3", "plaus"),
        ("opensees.dt=0.31", "plaus"),
        ("opensees.dt=0.2", "plaus"),
        ("nonsmooth.h=30", "plaus"),
        ("nonsmooth.h=0.5", "plaus"),
        ("compliance.dt=30", "plaus"),
        ("compliance.dt=0.29", "plaus"),
        ("run.duration=1e-4", "plaus"),
        ("run.duration=0.0005", "plaus"),
        ("run.output_dt=1e25", "plaus"),
        ("run.output_dt=100", "plaus"),
        ("run.output_dt=0.31", "plaus"),
        ("excitation.duration=0.0004", "field"),
        ("opensees.max_iterations=9223372036854775808", "field"),
        ("opensees.max_iterations=1e308", "field"),
        ("compliance.max_iterations=1e308", "field"),
        ("nonsmooth.max_iterations=18446744073709551616", "field"),
        ("opensees.substeps=1e9", "field"),
        ("damping.modes=[1, 9223372036854775807]", "field"),
        ("run.output_dt=0.001", "ok"),
        ("run.duration=0.2", "ok"),
        ("contact.stiffness=1e14", "ok"),
        ("opensees.dt=0.01", "ok"),
    ]
    for engine in ("opensees", "compliance", "nonsmooth"):
        for setting, kind in grid:
            for cmd in ("validate", "run"):
                argv = (
                    ("scene", "validate", "saiidi-4span", *SHORT, "--set", setting)
                    if cmd == "validate"
                    else (
                        "run",
                        "saiidi-4span",
                        *SHORT,
                        "--set",
                        setting,
                        "--engine",
                        engine,
                        "-o",
                        OUT,
                    )
                )
                if cmd == "validate" and engine != "opensees":
                    continue
                owner = setting.split(".")[0]
                # a run checks its own engine's settings (and the shared ones) only
                bad = kind == "field" or (
                    kind == "plaus"
                    and (cmd == "validate" or owner not in ENGINE_NAMES or owner == engine)
                )
                cases.append(
                    Case(
                        f"engine:{cmd}:{engine}:{setting}",
                        "engine",
                        argv,
                        target=OUT if cmd == "run" else "",
                        target_kind="dir" if cmd == "run" else "",
                        nonsense=bad,
                        expect=(2,) if bad else (0, 1),
                    )
                )
    return cases


def vtk_family() -> list[Case]:
    damaged = [
        ("json-truncated", "opensees.json", b'{"engine": "opensees", "sce'),
        ("json-empty", "opensees.json", b""),
        ("json-list", "opensees.json", b"[1, 2]"),
        ("json-nested", "opensees.json", b"[" * 100_000 + b"]" * 100_000),
        ("json-binary", "opensees.json", bytes(range(256))),
        ("json-no-scene", "opensees.json", b'{"engine": "opensees"}'),
        ("json-bad-scene", "opensees.json", b'{"scene": {"deck": 1}}'),
        ("json-scene-nan", "opensees.json", b'{"scene": NaN}'),
        ("csv-empty", "opensees.csv", b""),
        ("csv-header-only", "opensees.csv", b"t,deck_x\n"),
        ("csv-binary", "opensees.csv", bytes(range(256)) * 4),
        ("csv-nan", "opensees.csv", None),
        ("csv-text", "opensees.csv", b"t,deck_x\na,b\n"),
        ("csv-ragged", "opensees.csv", b"t,deck_x\n0,1,2,3\n0.1\n"),
        ("csv-decreasing", "opensees.csv", None),
        ("csv-missing-col", "opensees.csv", None),
    ]
    cases = []
    for cid, name, data in damaged:
        for every in ("1", "7"):
            files = () if data is None else ((f"res/{name}", data),)
            cases.append(
                Case(
                    f"vtk:{cid}:every{every}",
                    "vtk",
                    ("export-vtk", "{tmp}/res", "--every", every, "-o", OUT),
                    setup=("result", f"damage:{cid}") if data is None else ("result",),
                    files=files,
                    target=OUT,
                    target_kind="dir",
                    nonsense=True,
                    expect=(2,),
                    weight=2,
                )
            )
    for every in ("0", "-3", "1000000000000", "x"):
        cases.append(
            Case(
                f"vtk:every={every}",
                "vtk",
                ("export-vtk", "{tmp}/res", "--every", every, "-o", OUT),
                setup=("result",),
                target=OUT,
                target_kind="dir",
                expect=(0, 2),
            )
        )
    cases.append(
        Case(
            "vtk:not-a-folder",
            "vtk",
            ("export-vtk", "{tmp}/nothing", "-o", OUT),
            target=OUT,
            target_kind="dir",
            expect=(2,),
        )
    )
    return cases


NAMES = [
    "$\\\\frac{$",
    "$",
    "$$",
    "$x^$",
    "\\\\$",
    "$\\\\undefined{x}$",
    "a\\nb",
    "\\u0000",
    "nul\\u0000in",
    "\\u001b[31mred",
    "😀 émoji",
    "\\u202eRTL",
    "x" * 3000,
    "%s %d {0}",
    "<b>&amp;</b>",
    "_^{}",
    "\\\\",
    "'; exec rm -rf /",
    "\\t\\r",
]


def name_family() -> list[Case]:
    cases = []
    for i, name in enumerate(NAMES):
        cases.append(
            Case(
                f"name:{i}:plot",
                "name",
                (
                    "excitation",
                    "plot",
                    "saiidi-4span",
                    *SHORT,
                    "--set",
                    f'name="{name}"',
                    "-o",
                    "{tmp}/out/exc.png",
                ),
                target="{tmp}/out/exc.png",
                target_kind="file",
                expect=(0,),
                weight=8,
            )
        )
        cases.append(
            Case(
                f"name:{i}:validate",
                "name",
                ("scene", "validate", "saiidi-4span", *SHORT, "--set", f'name="{name}"'),
                expect=(0, 2),
            )
        )
    for i in (0, 1, 7, 12):  # every figure of compare, with the worst names
        cases.append(
            Case(
                f"name:{i}:compare",
                "name",
                (
                    "compare",
                    "saiidi-4span",
                    *SHORT,
                    "--set",
                    f'name="{NAMES[i]}"',
                    "--engines",
                    "compliance,nonsmooth",
                    "--workers",
                    "1",
                    "--no-progress",
                    "-o",
                    OUT,
                ),
                target=OUT,
                target_kind="dir",
                expect=(0,),
                weight=25,
            )
        )
    return cases


def option_family() -> list[Case]:
    cases = []
    base = ("compare", "saiidi-4span", *SHORT, "--engines", "nonsmooth", "--no-progress", "-o", OUT)
    for opt, values in (
        ("--workers", ["0", "-1", "abc", "1e9", "99999", "2.5", ""]),
        (
            "--scheduler",
            [
                "foo",
                "tcp://",
                "tcp://host",
                "tcp://h:0",
                "tcp://h:99999",
                "http://x:1",
                "tcp://a b:1",
                "",
                "tcp://127.0.0.1:1",
            ],
        ),
        ("--engines", ["", ",,", "x", "opensees,,x", "OpenSees"]),
    ):
        for v in values:
            argv = (
                tuple(a for a in base if a not in ("--engines", "nonsmooth"))
                if opt == "--engines"
                else base
            )
            fault = "connect-timeout" if v == "tcp://127.0.0.1:1" else ""
            cases.append(
                Case(
                    f"option:{opt}={v[:20]}",
                    "option",
                    (*argv, opt, v),
                    fault=fault,
                    target=OUT,
                    target_kind="dir",
                    expect=(3,) if fault else (0, 2),
                    weight=3 if fault else 1,
                )
            )
    # bad numbers for the measurement commands' options: refused (exit 2)
    for label, argv, values in (
        (
            "stress-timeout",
            ("stress", "--quick", "--timeout"),
            ("nan", "inf", "-1", "0", "abc", "-inf", "1e400"),
        ),
        ("bench-repeats", ("bench", "--quick", "--repeats"), ("0", "-5", "abc", "100000")),
    ):
        for v in values:
            cases.append(
                Case(
                    f"option:{label}={v}",
                    "option",
                    (*argv, v, "-o", OUT),
                    target=OUT,
                    target_kind="dir",
                    expect=(2,),
                )
            )
    for opt, v in (
        ("--states", "-5"),
        ("--states", "0"),
        ("--states", "10000000000000"),
        ("--seed", "-1"),
        ("--seed", "1e3"),
        ("--states", "nan"),
    ):
        cases.append(
            Case(
                f"option:verify-takeda{opt}={v}",
                "option",
                ("verify", "takeda", opt, v),
                nonsense=True,
                expect=(2,),
            )
        )
    return cases


#: how the stream cases close stdout and stderr (:mod:`tests._fuzz_run` sets ``sys.stdout`` /
#: ``sys.stderr`` to None for them, what Python does when ``>&-`` / ``2>&-`` closed them)
STREAM_FAULTS = ("stdout-closed", "stderr-closed", "streams-closed")


def stream_family() -> list[Case]:
    """Closed stdout and stderr: a command whose output cannot be written to stdout is an I/O
    failure (3); everything else ends as it would with both open (stderr never matters)."""
    cases = []
    prints = (  # (id, argv, exit status with stdout open): each prints to stdout
        ("list", ("scene", "list"), 0),
        ("show", ("scene", "show", "saiidi-4span"), 0),
        ("validate", ("scene", "validate", "saiidi-4span", *SHORT), 0),
        ("help", ("--help",), 0),
        ("version", ("--version",), 0),
    )
    silent = (  # (id, argv, exit status, output folder): they print nothing before they end
        ("missing-scene", ("scene", "validate", "{tmp}/nosuch.toml"), 2, ""),
        ("bad-value", ("scene", "validate", "saiidi-4span", "--set", "deck.mass=-1"), 2, ""),
        ("bad-option", ("scene", "list", "--no-such-option"), 2, ""),
        ("unknown-engine", ("run", "saiidi-4span", "--engine", "x", "-o", OUT), 2, OUT),
        (
            "engine-fails",
            ("run", "saiidi-4span", *SHORT, "--set", "nonsmooth.max_iterations=1")
            + ("--set", "nonsmooth.tolerance=1e-30", "--engine", "nonsmooth", "-o", OUT),
            1,
            OUT,
        ),
    )
    for fault in STREAM_FAULTS:
        for cid, argv, code in prints:
            closed_stdout = fault != "stderr-closed"
            cases.append(
                Case(
                    f"stream:{fault}:{cid}",
                    "stream",
                    argv,
                    fault=fault,
                    expect=(3,) if closed_stdout else (code,),
                )
            )
        for cid, argv, code, out in silent:
            if cid == "engine-fails" and fault != "stderr-closed":
                continue  # its summary line comes first: stdout's failure is met first
            cases.append(
                Case(
                    f"stream:{fault}:{cid}",
                    "stream",
                    argv,
                    fault=fault,
                    target=out,
                    target_kind="dir" if out else "",
                    expect=(code,),
                )
            )
    cases.append(  # with stderr closed a run succeeds and writes its result whole
        Case(
            "stream:stderr-closed:run",
            "stream",
            ("run", "saiidi-4span", *SHORT, "--engine", "nonsmooth", "-o", OUT),
            fault="stderr-closed",
            target=OUT,
            target_kind="dir",
            expect=(0,),
        )
    )
    return cases

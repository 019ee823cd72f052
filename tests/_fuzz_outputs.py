"""Fuzz cases of the output paths and the injected faults (part of :mod:`tests._fuzz_corpus`).

Every output-writing command (run with each engine, export tcl/py, excitation plot,
export-vtk, compare) against hostile ``-o`` targets, with the exit status the contract fixes
for each, and against faults injected while it writes (see :data:`FAULTS`;
:mod:`tests._fuzz_run` installs them).
"""

from __future__ import annotations

from _fuzz_corpus import OUT, SHORT, Case


def _commands(target: str) -> list[tuple[str, tuple[str, ...], str, tuple[str, ...], int]]:
    """(name, argv, target kind, setup, weight) of every output-writing command."""
    tiny = (*SHORT, "--set", "run.output_dt=0.01")
    return [
        (
            "run-opensees",
            ("run", "saiidi-4span", *tiny, "--engine", "opensees", "-o", target),
            "dir",
            (),
            1,
        ),
        (
            "run-compliance",
            ("run", "saiidi-4span", *tiny, "--engine", "compliance", "-o", target),
            "dir",
            (),
            1,
        ),
        (
            "run-nonsmooth",
            ("run", "saiidi-4span", *tiny, "--engine", "nonsmooth", "-o", target),
            "dir",
            (),
            1,
        ),
        (
            "export-tcl",
            (
                "export",
                "saiidi-4span",
                *tiny,
                "--format",
                "tcl",
                "-o",
                target + "/m.tcl" if not target.endswith((".tcl", "full")) else target,
            ),
            "file",
            (),
            1,
        ),
        (
            "export-py",
            ("export", "saiidi-4span", *tiny, "--format", "py", "-o", target),
            "file",
            (),
            1,
        ),
        (
            "plot",
            ("excitation", "plot", "saiidi-4span", *tiny, "-o", target + ".png"),
            "file",
            (),
            8,
        ),
        ("vtk", ("export-vtk", "{tmp}/res", "--every", "10", "-o", target), "dir", ("result",), 2),
        (
            "compare",
            (
                "compare",
                "saiidi-4span",
                *tiny,
                "--engines",
                "compliance,nonsmooth",
                "--workers",
                "1",
                "--no-progress",
                "-o",
                target,
            ),
            "dir",
            (),
            25,
        ),
    ]


TARGETS = [  # (id, -o path, dirs, links, files)
    ("fresh", OUT, (), (), ()),
    ("nested", "{tmp}/a/b/c/out", (), (), ()),
    ("existing-empty", OUT, ("out",), (), ()),
    ("existing-full", OUT, ("out",), (), (("out/keep.txt", b"user data\n"),)),
    ("below-file", "{tmp}/afile/out", (), (), (("afile", b"x"),)),
    ("file-in-place", OUT, (), (), (("out", b"precious\n"),)),
    ("link-to-dir", OUT, ("real",), (("out", "{tmp}/real"),), ()),
    ("link-to-file", OUT, (), (("out", "{tmp}/victim"),), (("victim", b"victim\n"),)),
    ("dangling-link", OUT, (), (("out", "{tmp}/nowhere"),), ()),
    ("proc", "/proc/deckpound-fuzz/out", (), (), ()),
    ("sys", "/sys/deckpound-fuzz/out", (), (), ()),
    ("dev-full", "/dev/full", (), (), ()),
]

# exit status of each command family for each target (the contract: 2 = refused before any
# work, 3 = the system refused); "dir" commands write a folder -o, "tcl" writes -o/m.tcl,
# "py" writes the file -o, "png" writes -o.png
_EXPECT = {
    "dir": {
        "fresh": 0,
        "nested": 0,
        "existing-empty": 0,
        "existing-full": 0,
        "below-file": 2,
        "file-in-place": 2,
        "link-to-dir": 2,
        "link-to-file": 2,
        "dangling-link": 2,
        "proc": 3,
        "sys": 3,
    },
    "tcl": {
        "fresh": 0,
        "nested": 0,
        "existing-empty": 0,
        "existing-full": 0,
        "below-file": 2,
        "file-in-place": 2,
        "link-to-dir": 0,
        "link-to-file": 2,
        "dangling-link": 2,
        "proc": 3,
        "sys": 3,
        "dev-full": 3,
    },
    "py": {
        "fresh": 0,
        "nested": 0,
        "existing-empty": 2,
        "existing-full": 2,
        "below-file": 2,
        "file-in-place": 0,
        "link-to-dir": 2,
        "link-to-file": 2,
        "dangling-link": 2,
        "proc": 3,
        "sys": 3,
        "dev-full": 2,  # a device: the export's data folder would land beside it in /dev
    },
    "png": {
        "fresh": 0,
        "nested": 0,
        "existing-empty": 0,
        "existing-full": 0,
        "below-file": 2,
        "file-in-place": 0,
        "link-to-dir": 0,
        "link-to-file": 0,
        "dangling-link": 0,
        "proc": 3,
        "sys": 3,
        "dev-full": 2,
    },
}


def _shape(name: str) -> str:
    return {"export-tcl": "tcl", "export-py": "py", "plot": "png"}.get(name, "dir")


def path_family() -> list[Case]:
    cases = []
    for tid, target, dirs, links, files in TARGETS:
        for name, argv, kind, setup, weight in _commands(target):
            shape = _shape(name)
            if tid not in _EXPECT[shape]:
                continue  # /dev/full as an output folder: the same as file-in-place
            if tid == "dev-full" and name == "plot":
                argv = tuple("/dev/full" if a == "/dev/full.png" else a for a in argv)
            out_path = argv[argv.index("-o") + 1]
            cases.append(
                Case(
                    f"path:{tid}:{name}",
                    "path",
                    argv,
                    files=files,
                    dirs=dirs,
                    links=links,
                    setup=setup,
                    target=out_path,
                    target_kind=kind,
                    expect=(_EXPECT[shape][tid],),
                    weight=weight,
                )
            )
    cases.append(
        Case(
            "path:show-stdout-full",
            "path",
            ("scene", "show", "saiidi-4span"),
            fault="stdout-full",
            expect=(3,),
        )
    )
    cases.append(
        Case("path:list-stdout-full", "path", ("scene", "list"), fault="stdout-full", expect=(3,))
    )
    cases.append(
        Case(
            "path:validate-stdout-full",
            "path",
            ("scene", "validate", "saiidi-4span", *SHORT),
            fault="stdout-full",
            expect=(3,),
        )
    )
    cases.append(
        Case(
            "path:run-into-existing-tmp",
            "path",
            ("run", "saiidi-4span", *SHORT, "--engine", "nonsmooth", "-o", "{tmp}"),
            target="{tmp}",
            target_kind="dir",
            expect=(0,),
        )
    )
    return cases


#: (fault, exit status when it strikes, whether the command may finish before it strikes)
FAULTS = [
    ("enospc-write:1", 3, False),
    ("enospc-write:2", 3, True),
    ("enospc-write:3", 3, True),
    ("enospc-write:5", 3, True),
    ("enospc-write:9", 3, True),
    ("enospc-fsync:1", 3, False),
    ("enospc-fsync:2", 3, True),
    ("enospc-fsync:4", 3, True),
    ("eio-replace:1", 3, False),
    ("eio-replace:2", 3, True),
    ("eio-replace:4", 3, True),
    ("readonly:EROFS", 3, False),
    ("readonly:EACCES", 3, False),
    ("interrupt-write:1", 130, False),
    ("interrupt-write:2", 130, True),
    ("interrupt-write:4", 130, True),
    ("memory-write:2", 3, True),
    ("savefig-enospc", 3, False),
    ("memory-engine", 3, False),
    ("interrupt-engine", 130, False),
    ("recursion-engine", 3, False),
]
_COMPARE_FAULTS = (
    "enospc-write:2",
    "enospc-fsync:4",
    "savefig-enospc",
    "interrupt-write:2",
    "memory-engine",
)


def fault_family() -> list[Case]:
    cases = []
    for name, argv, kind, setup, weight in _commands(OUT):
        for fault, code, may_finish in FAULTS:
            if fault.endswith("-engine") and not name.startswith(("run", "compare")):
                continue
            if fault == "savefig-enospc" and name not in ("plot", "compare"):
                continue
            if name == "compare" and fault not in _COMPARE_FAULTS:
                continue
            if name == "plot" and fault.split(":")[0] in (
                "enospc-write",
                "interrupt-write",
                "memory-write",
            ):
                may_finish = True  # matplotlib writes the figure itself: no write of ours
            expect = (code, 0) if may_finish else (code,)
            target = argv[argv.index("-o") + 1]
            cases.append(
                Case(
                    f"fault:{name}:{fault}",
                    "fault",
                    argv,
                    setup=setup,
                    fault=fault,
                    target=target,
                    target_kind=kind,
                    expect=expect,
                    weight=weight,
                )
            )
            if (
                kind == "dir"
                and name != "compare"
                and fault
                in ("enospc-write:2", "eio-replace:2", "interrupt-write:2", "readonly:EROFS")
            ):
                cases.append(
                    Case(
                        f"fault:{name}:{fault}:existing-full",
                        "fault",
                        argv,
                        setup=setup,
                        dirs=("out",),
                        files=(("out/keep.txt", b"user data\n"),),
                        fault=fault,
                        target=target,
                        target_kind=kind,
                        expect=expect,
                        weight=weight,
                    )
                )
    return cases

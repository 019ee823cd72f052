"""Export the OpenSees model of a scene as a runnable Tcl or Python script, and the golden log.

``export_script(scene, "py", path)`` writes ``path`` and, beside it, one text file per support
record (``<stem>.<channel>_disp.txt``, ``..._vel.txt``; 17 significant digits, so OpenSees reads
back the very doubles used in process). The Python script executes the same commands as the
in-process run and then the engine's own step loop (its source is copied verbatim from
:mod:`.engine`), and writes the result columns to ``<stem>.csv`` (or the path given as its first
argument) plus the run statistics to ``<stem>.stats.json``. The Tcl script holds the same
commands in Tcl syntax and an equivalent step loop writing ``<stem>.csv``.

Golden command log: :func:`regen_golden` (or ``python -m deckpound.opensees_build.export
--regen-golden``) rewrites ``data/golden/saiidi-4span.opensees.log``; floats are printed with
12 significant digits and support records abbreviated to their length and a SHA-256.
"""

from __future__ import annotations

import argparse
import inspect
import json
from pathlib import Path

from deckpound import __version__

from . import engine
from .ops import ArrayArg, Command, render_commands

GOLDEN_DIR = Path(__file__).resolve().parents[1] / "data" / "golden"
GOLDEN_SCENE = "saiidi-4span"

_RUNTIME = (engine.define_analysis, engine.corner_gaps, engine.contact_forces,
            engine.sample_row, engine.run_steps)


def golden_path(name: str = GOLDEN_SCENE) -> Path:
    return GOLDEN_DIR / f"{name}.opensees.log"


def golden_text(scene, motion=None) -> str:
    """The golden rendering of the scene's command log."""
    log = engine.command_log(scene, motion)
    return render_commands(log, "log", golden=True)


def regen_golden(name: str = GOLDEN_SCENE) -> Path:
    """Rewrite the golden command log of built-in scene ``name``."""
    from deckpound.models.scene_io import load_scene
    path = golden_path(name)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(golden_text(load_scene(name)))
    return path


def _arrays(log: list[Command]) -> list[ArrayArg]:
    return [a for c in log for a in c.args if isinstance(a, ArrayArg)]


def script_and_files(scene, fmt: str, stem: str, motion=None) -> tuple[str, dict[str, str], list]:
    """(script text, {file name: text} of the records, the command log)."""
    if fmt not in ("tcl", "py"):
        raise ValueError(f"fmt must be 'tcl' or 'py', got {fmt!r}")
    from .ops import OpsSession
    with OpsSession() as ops:
        info, plan = engine.build(ops, scene, motion)
        log = list(ops.log)
    arrays = _arrays(log)
    file_of = {a.name: f"{stem}.{a.name}.txt" for a in arrays}
    files = {file_of[a.name]: a.file_text() for a in arrays}
    body = render_commands(log, fmt, file_of=file_of)
    text = _py_script(scene, stem, body, plan) if fmt == "py" else _tcl_script(scene, stem, body, plan)
    return text, files, log


def export_script(scene, fmt: str, path, motion=None) -> Path:
    """Write a complete, runnable ``fmt`` ("tcl" | "py") script for the scene to ``path``,
    with the support records as files beside it. Returns the script path."""
    from deckpound._io import atomic_write_files

    path = Path(path)
    text, files, _ = script_and_files(scene, fmt, path.stem, motion)
    # all files or none: a full disk leaves no record cut short and no script without records
    atomic_write_files({**{path.parent / n: c for n, c in files.items()}, path: text})
    return path


def _py_script(scene, stem: str, body: str, plan: dict) -> str:
    runtime = "\n\n".join(inspect.getsource(f) for f in _RUNTIME)
    return f'''#!/usr/bin/env python3
"""OpenSees model of scene {scene.name!r}, exported by deckpound {__version__}.

Mode {scene.opensees.mode}, dt = {scene.opensees.dt} s. Run:  python {stem}.py [output.csv]
Writes the result columns (deckpound standard columns) to {stem}.csv and the run statistics
to {stem}.stats.json. The support records are read from the {stem}.*.txt files beside it.
"""
import csv
import json
import math
import os
import sys

import openseespy.opensees as ops

HERE = os.path.dirname(os.path.abspath(__file__))


def _here(name):
    return os.path.join(HERE, name)


# --- model and analysis ---
{body}# --- end model ---

PLAN = json.loads({json.dumps(json.dumps(plan))})


{runtime}


if __name__ == "__main__":
    out_csv = sys.argv[1] if len(sys.argv) > 1 else _here({stem + ".csv"!r})
    out = run_steps(ops, PLAN, log=lambda m: print(m, file=sys.stderr))
    with open(out_csv, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(PLAN["columns"])
        for row in out["rows"]:
            w.writerow([repr(float(v)) for v in row])
    with open(os.path.splitext(out_csv)[0] + ".stats.json", "w") as fh:
        json.dump(out["stats"], fh, indent=2)
    ops.wipe()
    print(out["stats"]["status"], out["stats"]["message"])
    sys.exit(0 if out["stats"]["status"] == "success" else 1)
'''


def _tcl_list(values) -> str:
    return "{" + " ".join(repr(v) if isinstance(v, float) else str(v) for v in values) + "}"


def _tcl_script(scene, stem: str, body: str, plan: dict) -> str:
    analysis = "\n    ".join(" ".join(str(a) if not isinstance(a, float) else repr(a) for a in c)
                              for c in plan["analysis"])
    gap_eles = plan["gap_elements"] or [0, 0, 0, 0]
    return f'''# OpenSees model of scene {scene.name}, exported by deckpound {__version__}.
# Mode {scene.opensees.mode}, dt = {scene.opensees.dt} s. Run:  OpenSees {stem}.tcl
# Writes the result columns (deckpound standard columns) to {stem}.csv; the support records
# are read from the {stem}.*.txt files beside this script.
set here [file dirname [file normalize [info script]]]

# --- model and analysis ---
{body}# --- end model ---

set dt {plan["dt"]!r}
set nSteps {plan["n_steps"]}
set stride {plan["stride"]}
set fallback {plan["fallback"]}
set nSub {plan["substeps"]}
set deck {plan["deck"]}
set seats {_tcl_list(plan["seats"])}
set deckCorners {_tcl_list(plan["deck_corners"])}
set seatCorners {_tcl_list(plan["seat_corners"])}
set gapEles {_tcl_list(gap_eles)}
set hasGaps {1 if plan["gap_elements"] else 0}
set g0 {_tcl_list(plan["g0"])}
set sides {_tcl_list(plan["sides"])}
set bentEles {_tcl_list(plan["bent_elements"])}
set friction {1 if plan["friction"] else 0}

proc defineAnalysis {{}} {{
    {analysis}
}}

proc cornerGaps {{}} {{
    global deckCorners seatCorners g0 sides
    set out {{}}
    for {{set c 0}} {{$c < 4}} {{incr c}} {{
        set ud [nodeDisp [lindex $deckCorners $c] 1]
        set us [nodeDisp [lindex $seatCorners $c] 1]
        lappend out [expr {{[lindex $g0 $c] + [lindex $sides $c] * ($ud - $us)}}]
    }}
    return $out
}}

proc sampleRow {{t}} {{
    global deck seats gapEles hasGaps friction sides bentEles
    set dk [nodeDisp $deck]
    set s1 [nodeDisp [lindex $seats 0]]
    set s2 [nodeDisp [lindex $seats 1]]
    set row [list $t [lindex $dk 0] [lindex $dk 1] [lindex $dk 2] [lindex $s1 0] [lindex $s1 2] \\
             [lindex $s2 0] [lindex $s2 2]]
    set row [concat $row [cornerGaps]]
    set fn {{}}
    set ft {{}}
    for {{set c 0}} {{$c < 4}} {{incr c}} {{
        set e [lindex $gapEles $c]
        if {{!$hasGaps}} {{
            lappend fn 0.0; lappend ft 0.0
        }} elseif {{$friction}} {{
            set f [eleResponse $e force]
            lappend fn [expr {{-[lindex $sides $c] * [lindex $f 3]}}]
            lappend ft [expr {{-[lindex $f 4]}}]
        }} else {{
            lappend fn [expr {{-[lindex [eleResponse $e basicForce] 0]}}]
            lappend ft 0.0
        }}
    }}
    set row [concat $row $fn $ft]
    foreach e $bentEles {{
        set f [eleResponse $e basicForce]
        lappend row [lindex $f 0] [lindex $f 1]
    }}
    return $row
}}

set fh [open [file join $here {stem}.csv] w]
puts $fh [join {{{" ".join(plan["columns"])}}} ","]
puts $fh [join [sampleRow 0.0] ","]
set failures 0
set status success
for {{set n 1}} {{$n <= $nSteps}} {{incr n}} {{
    set ok [analyze 1 $dt]
    if {{$ok != 0}} {{
        incr failures
        if {{$fallback == "substep"}} {{
            wipeAnalysis
            defineAnalysis
            set h [expr {{$dt / $nSub}}]
            for {{set k 0}} {{$k < $nSub}} {{incr k}} {{
                set ok [analyze 1 $h]
                if {{$ok != 0}} {{ break }}
            }}
            wipeAnalysis
            defineAnalysis
        }}
    }}
    if {{$ok != 0}} {{
        set status failed
        puts "step $n (t = [expr {{$n * $dt}}] s) did not converge"
        break
    }}
    if {{$n % $stride == 0}} {{
        puts $fh [join [sampleRow [expr {{$n * $dt}}]] ","]
    }}
}}
close $fh
wipe
puts "$status, failures: $failures"
'''


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m deckpound.opensees_build.export",
                                description=__doc__.splitlines()[0])
    p.add_argument("--regen-golden", action="store_true", help="rewrite the golden command log")
    p.add_argument("--scene", default=GOLDEN_SCENE, help="built-in scene name or TOML file")
    p.add_argument("--format", choices=("tcl", "py"), default="py")
    p.add_argument("--out", help="script path to write")
    a = p.parse_args(argv)
    if a.regen_golden:
        print(regen_golden())
        return 0
    if not a.out:
        p.error("--out is required unless --regen-golden")
    from deckpound.models.scene_io import load_scene
    print(export_script(load_scene(a.scene), a.format, a.out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The exported OpenSeesPy script: header, ``build()``, recorders and the engine's step loop.

Layout (scene text appears only in the header comments, from line 3 on):

1. the audit header (:func:`.export_header.header_lines`) as ``#`` comments;
2. imports and the ``HERE`` / ``DATA`` / ``OUT`` folders;
3. ``build()`` — the model and analysis commands deckpound ran in process, one per logged
   command, support records read with ``-filePath`` from the data folder (importing the script
   and calling ``build()`` gives the model alone, e.g. for opsvis);
4. ``PLAN`` (tags and constants of the step loop), ``REC_DT`` and ``add_recorders(out_dir)``;
5. the runtime functions of :mod:`.engine` (``define_analysis``, ``run_steps``, ...) copied
   verbatim, so the script steps exactly as the in-process run does;
6. ``main()``: build, recorders, ``record`` at t = 0, run, optional CSV, statistics.
"""

from __future__ import annotations

import inspect
import textwrap

from . import engine
from .export_header import ExportParts, header_lines
from .ops import render_commands
from .quoting import comment_text, py_str
from .recorders import PRECISION, render_recorders

#: the engine's runtime functions, copied into the script (the same code steps both runs)
RUNTIME = (
    engine.define_analysis,
    engine.corner_gaps,
    engine.contact_forces,
    engine.sample_row,
    engine.new_tracker,
    engine.track_step,
    engine.run_steps,
)


def py_literal(v, indent: int = 0) -> str:
    """``v`` (dict / list / str / number / bool / None) as Python source: ASCII strings,
    floats by ``repr`` (read back exactly), one top-level key per line."""
    if isinstance(v, dict):
        pad = " " * (indent + 4)
        items = ",\n".join(f"{pad}{py_str(k)}: {py_literal(x, indent + 4)}" for k, x in v.items())
        return "{\n" + items + ",\n" + " " * indent + "}"
    if isinstance(v, (list, tuple)):
        items = [py_literal(x, indent + 4) for x in v]
        flat = "[" + ", ".join(items) + "]"
        if indent + len(flat) <= 88:
            return flat
        pad = " " * (indent + 4)
        if any(isinstance(x, (list, tuple, dict)) for x in v):
            rows = items
        else:  # fill lines with whole items
            rows, cur = [], ""
            for it in items:
                if cur and len(pad) + len(cur) + len(it) + 2 > 96:
                    rows.append(cur.rstrip(", "))
                    cur = ""
                cur += it + ", "
            rows.append(cur.rstrip(", "))
        return "[\n" + ",\n".join(pad + r for r in rows) + ",\n" + " " * indent + "]"
    if isinstance(v, str):
        return py_str(v)
    if isinstance(v, bool) or v is None:
        return repr(v)
    if isinstance(v, float):
        return repr(float(v))
    if isinstance(v, int):
        return str(int(v))
    raise TypeError(f"cannot write {type(v).__name__} into the script")


def py_script(p: ExportParts) -> str:
    """The complete Python script of ``p``."""
    head = "\n".join(f"# {comment_text(x, 'py')}".rstrip() for x in header_lines(p))
    body = textwrap.indent(render_commands(p.log, "py", file_of=p.file_of), "    ")
    recorders = textwrap.indent("\n".join(render_recorders(p.recorders, "py")), "    ")
    runtime = "\n\n".join(inspect.getsource(f) for f in RUNTIME)
    margin = "0.5 / PLAN['substeps']" if p.plan["fallback"] == "substep" else "0.5"
    return f'''#!/usr/bin/env python3
# OpenSeesPy script written by deckpound; scene text appears only in comments below.
{head}

import argparse
import csv
import json
import math
import os
import sys

import openseespy.opensees as ops

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, {py_str(p.data_dir)})
OUT = os.path.join(HERE, {py_str(p.out_dir)})


def _data(name):
    return os.path.join(DATA, name)


def build():
    """Model, damping, support motion and analysis: the commands deckpound ran in process."""
    # --- model and analysis ---
{body}    # --- end model ---


# step plan (tags from the legend above)
PLAN = {py_literal(p.plan)}

# -dT of the recorders = (stride - half a sub-step) * dt: one row per output step, none from
# the sub-steps of the fallback
REC_DT = (PLAN['stride'] - {margin}) * PLAN['dt']


def _out(out_dir, name):
    return os.path.join(out_dir, name)


def add_recorders(out_dir):
    """One file per deckpound column in out_dir (maps in the header)."""
    opts = ['-time', '-precision', {PRECISION}, '-dT', REC_DT]
{recorders}


{runtime}

def main(argv=None):
    p = argparse.ArgumentParser(description="Run the exported OpenSees model (see the header).")
    p.add_argument("--out", default=OUT, help="folder of the recorder files")
    p.add_argument("--csv", action="store_true",
                   help="also write deckpound's CSV (opensees.csv) into the output folder")
    a = p.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    build()
    add_recorders(a.out)
    ops.record()  # the row at t = 0
    out = run_steps(ops, PLAN, log=lambda m: print(m, file=sys.stderr))
    ops.wipe()  # closes the recorder files
    if a.csv:
        with open(os.path.join(a.out, "opensees.csv"), "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(PLAN["columns"])
            for row in out["rows"]:
                w.writerow([repr(float(v)) for v in row])
    with open(os.path.join(a.out, "opensees.stats.json"), "w") as fh:
        json.dump(out["stats"], fh, indent=2)
    st = out["stats"]
    print(st["status"], st["message"], "gap_closures:", st["gap_closures"])
    return 0 if out["stats"]["status"] == "success" else 1


if __name__ == "__main__":
    sys.exit(main())
'''

"""The exported OpenSeesPy script: header, ``build()``, recorders and the engine's step loop.

Layout (scene text appears only in the header comments, from line 3 on):

1. the audit header (:func:`.export_header.header_lines`) as ``#`` comments;
2. imports and the ``HERE`` / ``DATA`` / ``OUT`` folders;
3. ``build()`` — the model and analysis commands deckpound ran in process, one per logged
   command, support records read with ``-filePath`` from the data folder (importing the script
   and calling ``build()`` gives the model alone, e.g. for opsvis);
4. ``PLAN`` (tags and constants of the step loop), ``REC_DT`` and ``add_recorders(out_dir)``;
5. the runtime functions of :mod:`.engine` (``define_analysis``, ``run_steps``, ...) copied
   verbatim, so the script steps exactly as the in-process run does — unseating included: the
   loop stops after the first step at which a corner's seat margin is negative, status
   ``"unseated"``;
6. ``main()``: build, recorders, ``record`` at t = 0, run, optional CSV, statistics.

The statistics (``opensees.stats.json``, and the status and seat-margin lines on stdout) add
to the loop's own the seat margins of :func:`seat_margin_minima`, the engine's equation
(:func:`deckpound.models.engine_contract.seat_margins`). A run stopped by unseating ends its
recorder files with the last row deckpound stores (:func:`keep_stored_rows`: OpenSees recorded
the unseating step's commit when it was an output step; the engine keeps no row of that step).

The optional CSV (``--csv``) holds every column of the in-process result, in its order: the
engine's sampled columns plus the displacements relative to the supports and the bent
deformations, derived in the script from the support displacement records of the data folder
(:func:`csv_plan`, :func:`interp_record`, :func:`result_rows`) by the arithmetic of
:func:`deckpound.models.engine_contract.finish` (linear interpolation of the records as ``np.interp``,
mean of the shake tables, d = B u − S u_g).
"""

from __future__ import annotations

import inspect
import textwrap

from deckpound.models.columns import column_names, column_unit
from deckpound.models.file_io import unit_label
from deckpound.models.plan import plan_of

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


def csv_plan(p: ExportParts) -> dict:
    """What the script needs to derive the result's relative columns (JSON-able).

    ``records``: the displacement record file of each support channel (``Plan.channels``
    order), sampled at ``dt`` [s] from t = 0; ``means``: (engine column of an absolute deck
    (segment) displacement, the channels it is taken relative to the mean of: its segment's
    tables, :meth:`~deckpound.models.plan.Plan.segment_table_channels`); ``seats``: (engine
    column of a seat's absolute displacement, its actuator's channel); ``springs``: per bent
    spring row of d = B u − S u_g, the (engine column, B coefficient) and (channel, S
    coefficient) terms; ``columns``: the CSV's columns (the in-process result's), ``header``:
    their header cells with units (``deck_theta [rad]``, the result file's header), ``order``:
    their positions in an engine row followed by the derived values.
    """
    plan = plan_of(p.scene)
    engine_cols = list(p.plan["columns"])
    # the model imposes one ground motion per support channel, in Plan.channels order
    # (opensees_build.model.build_model); its tag name ends with the channel's name
    disp = [r for r in p.records if r["quantity"] == "displacement"]
    if len(disp) != len(plan.channels) or not all(
        r["channel"].endswith(ch) for r, ch in zip(disp, plan.channels)
    ):
        raise AssertionError(
            f"the displacement records {[r['channel'] for r in disp]} are not the support "
            f"channels {list(plan.channels)}"
        )
    steps = {r["dt"] for r in disp}
    if len(steps) != 1:
        raise AssertionError(f"support records with different steps {sorted(steps)}")
    column_of_dof = {dof: engine_cols.index(name) for name, dof in plan.dof_columns}
    B, S = plan.spring_matrices
    springs = [
        [
            [[column_of_dof[k], float(B[i, k])] for k in range(B.shape[1]) if B[i, k] != 0.0],
            [[k, float(S[i, k])] for k in range(S.shape[1]) if S[i, k] != 0.0],
        ]
        for i in range(plan.n_bent_springs)
    ]
    derived = list(plan.relative_columns)
    derived += [f"{b}_d{axis}" for b in plan.bent_names for axis in ("x", "y")]
    extended = engine_cols + derived
    columns = column_names(plan)
    if sorted(columns) != sorted(extended):
        raise AssertionError("the script's CSV columns differ from the result's")
    return {
        "records": [r["file"] for r in disp],
        "dt": steps.pop(),
        "means": [
            [engine_cols.index(f"{seg.name}_{axis}_abs"), plan.segment_table_channels(k, axis)]
            for k, seg in enumerate(plan.segments)
            for axis in ("x", "y")
        ],
        "seats": [
            [engine_cols.index(f"seat{j}_x_abs"), plan.channels.index(f"seat{j}_x")] for j in (1, 2)
        ],
        "springs": springs,
        "columns": columns,
        # the CSV's header: each column with its unit, as deckpound writes its own result
        "header": [unit_label(c, column_unit(c)) for c in columns],
        "order": [extended.index(c) for c in columns],
    }


# -- copied into the script (plain Python: the script needs no numpy) ---------------------------


def interp_record(values, dt, t):
    """A support record sampled at j*dt (j = 0, 1, ...) at time t [s], linear between samples
    and held outside the record: the arithmetic of np.interp, as the in-process result."""
    last = len(values) - 1
    if t >= last * dt:
        return values[last]
    if t <= 0.0:
        return values[0]
    j = int(t / dt)
    while j > 0 and j * dt > t:
        j -= 1
    while (j + 1) * dt <= t:
        j += 1
    if j * dt == t:
        return values[j]
    slope = (values[j + 1] - values[j]) / ((j + 1) * dt - j * dt)
    return slope * (t - j * dt) + values[j]


def _total(terms):
    """The sum of terms from the first one on (numpy's order for a short row); 0.0 if none."""
    if not terms:
        return 0.0
    out = terms[0]
    for x in terms[1:]:
        out += x
    return out


def result_rows(rows, rel, read_record):
    """Rows of the engine columns (t first) to rows of the result's columns (rel["columns"]):
    each deck segment relative to the mean of its tables' displacement, each seat relative to its
    actuator and each bent spring's deformation d = B u - S u_g, the support displacements
    u_g read by read_record(file) and interpolated at each row's t (interp_record).
    """
    records = [read_record(name) for name in rel["records"]]
    out = []
    for row in rows:
        ug = [interp_record(values, rel["dt"], row[0]) for values in records]
        extra = []
        for col, chans in rel["means"]:
            extra.append(row[col] - (_total([ug[k] for k in chans]) / len(chans) if chans else 0.0))
        for col, ch in rel["seats"]:
            extra.append(row[col] - ug[ch])
        for dofs, chans in rel["springs"]:
            extra.append(
                _total([row[c] * b for c, b in dofs]) - _total([ug[k] * s for k, s in chans])
            )
        full = list(row) + extra
        out.append([full[i] for i in rel["order"]])
    return out


#: the engine contract's words for seats without a support length (``seat_margin_basis``)
UNCHECKED_SEATS = "not checked (no seats[i].support_length or joints[i].support_length)"


def seat_margin_minima(plan, stats, unchecked):
    """The seat margins of a finished step loop, the equation of deckpound's epilogue
    (deckpound.models.engine_contract.seat_margins): for each corner c (plan['corners']) whose
    seat has a support length N = plan['support_lengths'][c] [m], the smallest seat margin
    m = N - (g_max - g(0)) [m] and its time [s], from the largest opening over every converged
    step and sub-step (stats['gap_openings'] of run_steps). Returns 'seat_margin_min'
    ({corner: [margin m, time s]}) and 'seat_margin_basis' ('every step', or ``unchecked``
    when no corner's seat has a support length)."""
    margins = {}
    for name, length in zip(plan["corners"], plan["support_lengths"]):
        if length is not None:
            opening, when = stats["gap_openings"][name]
            margins[name] = [float(length) - opening, when]
    return {
        "seat_margin_min": margins,
        "seat_margin_basis": "every step" if margins else unchecked,
    }


def seat_margin_line(stats):
    """The seat margins as one line of text: corner, margin [m], time [s] of each checked
    corner (floats as repr: read back exactly), or the basis when none is checked."""
    margins = stats["seat_margin_min"]
    if not margins:
        return "seat_margin_min: " + stats["seat_margin_basis"]
    cells = [f"{c} {m!r} {t!r}" for c, (m, t) in margins.items()]
    return "seat_margin_min (margin m, time s): " + ", ".join(cells)


def keep_stored_rows(paths, n_rows):
    """Cut each recorder file to its first n_rows lines, the rows deckpound stores: a run
    stopped by unseating keeps no row of its last step, which OpenSees recorded at its commit
    when it was an output step."""
    for path in paths:
        with open(path, newline="") as fh:
            lines = fh.readlines()
        if len(lines) > n_rows:
            with open(path, "w", newline="") as fh:
                fh.writelines(lines[:n_rows])


#: the functions of this module the script carries (its CSV's derived columns, the seat
#: margins and the recorder rows of an unseated run)
SCRIPT_RUNTIME = (
    interp_record,
    _total,
    result_rows,
    seat_margin_minima,
    seat_margin_line,
    keep_stored_rows,
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
    runtime = "\n\n".join(inspect.getsource(f) for f in RUNTIME + SCRIPT_RUNTIME)
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

# the CSV's columns: the engine's and those derived from the support displacement records
CSV = {py_literal(csv_plan(p))}

# -dT of the recorders = (stride - half a sub-step) * dt: one row per output step, none from
# the sub-steps of the fallback
REC_DT = (PLAN['stride'] - {margin}) * PLAN['dt']

# the recorder files (add_recorders), cut to deckpound's rows after an unseating
RECORDER_FILES = {py_literal([r.file for r in p.recorders])}


def _out(out_dir, name):
    return os.path.join(out_dir, name)


def _read_record(name):
    with open(_data(name)) as fh:
        return [float(line) for line in fh if line.strip()]


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
    out["stats"].update(seat_margin_minima(PLAN, out["stats"], {py_str(UNCHECKED_SEATS)}))
    if out["stats"]["status"] == "unseated":
        keep_stored_rows([_out(a.out, name) for name in RECORDER_FILES], len(out["rows"]))
    if a.csv:
        with open(os.path.join(a.out, "opensees.csv"), "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(CSV["header"])
            for row in result_rows(out["rows"], CSV, _read_record):
                w.writerow([repr(float(v)) for v in row])
    with open(os.path.join(a.out, "opensees.stats.json"), "w") as fh:
        json.dump(out["stats"], fh, indent=2)
    st = out["stats"]
    print(st["status"], st["message"], "gap_closures:", st["gap_closures"])
    print(seat_margin_line(st))
    return 0 if out["stats"]["status"] in ("success", "unseated") else 1


if __name__ == "__main__":
    sys.exit(main())
'''

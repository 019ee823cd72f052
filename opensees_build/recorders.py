"""Standard OpenSees recorders of the exported scripts, and the map from their files to
deckpound's result columns (:func:`deckpound.models.engine_contract.engine_columns`).

One recorder file per result column the engine writes, named after it (``deck_x_abs.out``,
``deck_vx_abs.out``, ``gap_c1.out``, ``bent1_fx.out``, ...; a deck of segments
``frame1_x_abs.out``, ``gap_j1_c1.out``, ...; the columns deckpound derives from
these and the support motion — displacements relative to the supports, bent deformations — are
not recorded). Every file
starts with the time column (``-time``) and holds raw OpenSees quantities at 17 significant
digits; :class:`ColumnMap` states how a deckpound column follows from them:

* node displacements are the columns themselves (absolute, as in deckpound);
* ``gap_<corner>`` — straight deck without friction: the gap element's ``deformation``
  e = u_j − u_i, and g = g₀ + e (the nodes are ordered so that e = side·(u_deck − u_seat),
  closing negative); straight deck with friction (zeroLengthContact2D): the x displacements
  of the deck corner and the seat point (at a joint: the facing point on the other segment),
  g = g₀ + side·(u_deck − u_seat); skewed face (either
  element): their x and y displacements (``-dof 1 2``), g = g₀ + n·(u_deck − u_seat) with the
  corner's gap-opening normal n — the engine's own arithmetic;
* ``fn_<corner>`` — without friction the material stress (``basicForce``, ≤ 0 in compression),
  fn = −stress; with friction the element's resisting forces [Fx_i, Fy_i, M_i, Fx_j, Fy_j, M_j]
  (j = deck corner), fn = −n·(Fx_j, Fy_j) and ``ft_<corner>`` = −t·(Fx_j, Fy_j) (force on the deck
  along the face tangent t; −side·Fx_j and −Fy_j for a straight deck);
* ``<bent>_fx/_fy`` — stress of the bent's Hysteretic material 1 (x) and 2 (y).

Alignment with deckpound's rows: the engine stores a row at t = 0 and after every ``stride``-th
step, while OpenSees records at every commit — including the commits of the sub-steps of the
fallback. The recorders therefore get ``-dT = (stride − m)·dt`` with a margin m of half a
sub-step (half a step without the fallback), and the script calls ``record`` once at t = 0: a
recorder writes at the first commit at or after ``previous record + dT``, which is the output
step itself (the sub-step before it is ``m`` too early), whether or not the OpenSees build
applies its relative tolerance (1e-5·dT) to that comparison — as long as that tolerance stays
below the margin, which :func:`recorder_step` checks.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from deckpound.models.errors import SceneError

from .quoting import comment_text, py_str, safe_file_name, tcl_word

#: significant digits of the recorder files (17: reading back gives the very doubles)
PRECISION = 17
#: relative tolerance that newer OpenSees builds apply to ``-dT`` (``relDeltaTTol``, 1e-5);
#: :func:`recorder_step` keeps it below a tenth of the margin
OPENSEES_DT_RTOL = 1.0e-5


@dataclass(frozen=True)
class Recorder:
    """One ``recorder Node|Element`` command writing ``file`` (time, then ``columns``)."""

    file: str
    kind: str
    tags: tuple[int, ...]
    response: tuple
    columns: tuple[str, ...]
    meaning: str
    dofs: tuple[int, ...] = ()

    def args(self) -> list:
        """The arguments after ``-file PATH -time -precision P -dT DT``."""
        out: list = ["-node" if self.kind == "Node" else "-ele", *self.tags]
        if self.kind == "Node":
            out += ["-dof", *self.dofs]
        return out + list(self.response)


@dataclass(frozen=True)
class ColumnMap:
    """deckpound column = offset + scale·(x[a] − x[b]) (or offset + scale·x[a] when ``b`` is
    None) with x one row of recorder file ``file`` (x[0] is the time), plus, when ``a2`` is
    given, a second term scale2·(x[a2] − x[b2]) (or scale2·x[a2]) — a skewed deck's gap and
    forces project x and y components on the face normal; ``file`` None: the constant
    ``offset``. Evaluated in this order, so the arithmetic is the engine's own."""

    column: str
    file: str | None
    a: int = 1
    b: int | None = None
    offset: float = 0.0
    scale: float = 1.0
    a2: int | None = None
    b2: int | None = None
    scale2: float = 0.0

    @staticmethod
    def _term(file: str, a: int, b: int | None, scale: float) -> str:
        x = f"{file}[{a}]" if b is None else f"({file}[{a}] - {file}[{b}])"
        return x if scale == 1.0 else f"-{x}" if scale == -1.0 else f"{scale!r}*{x}"

    def formula(self) -> str:
        """The map as one line of text for the script header (``file[k]``: column k of the
        file, 0 = time)."""
        if self.file is None:
            return f"{self.column} = {self.offset!r} (no recorder)"
        if self.a == 0:
            return f"{self.column} = {self.file}[0]"
        lin = self._term(self.file, self.a, self.b, self.scale)
        if self.offset == 0.0:
            rhs = lin
        else:
            rhs = (
                f"{self.offset!r} - {lin[1:]}"
                if lin.startswith("-")
                else f"{self.offset!r} + {lin}"
            )
        if self.a2 is not None:
            two = self._term(self.file, self.a2, self.b2, self.scale2)
            rhs += f" - {two[1:]}" if two.startswith("-") else f" + {two}"
        return f"{self.column} = {rhs}"

    def apply(self, table: np.ndarray, n_rows: int) -> np.ndarray:
        if self.file is None:
            return np.full(n_rows, self.offset)
        if self.a == 0:
            return table[:, 0].copy()
        x = table[:, self.a] if self.b is None else table[:, self.a] - table[:, self.b]
        out = self.offset + self.scale * x
        if self.a2 is not None:
            x2 = table[:, self.a2] if self.b2 is None else table[:, self.a2] - table[:, self.b2]
            out = out + self.scale2 * x2
        return out


def recorder_step(plan: dict) -> float:
    """``-dT`` of the recorders [s]: (stride − m)·dt, m = 1/(2·substeps) with the sub-step
    fallback, 1/2 without (see the module docstring)."""
    margin = 0.5 / plan["substeps"] if plan["fallback"] == "substep" else 0.5
    if OPENSEES_DT_RTOL * plan["stride"] > 0.1 * margin:
        raise SceneError(
            "run.output_dt",
            f"an output every {plan['stride']} steps with "
            f"{plan['substeps']} sub-steps cannot be separated by OpenSees "
            "recorders (-dT tolerance 1e-5 of the output step exceeds a tenth of "
            "half a sub-step); lower run.output_dt or opensees.substeps so that "
            f"stride x substeps <= {int(0.05 / OPENSEES_DT_RTOL)}",
        )
    return (plan["stride"] - margin) * plan["dt"]


def standard_recorders(plan: dict, bent_names) -> tuple[list[Recorder], list[ColumnMap]]:
    """The recorders and column maps for the model described by the step plan ``plan``
    (:func:`deckpound.opensees_build.engine.step_plan`): the nodes' displacements and
    velocities, each corner's gap and contact forces, the bents' spring forces; the maps in
    the order of the result columns."""
    recs: list[Recorder] = []
    maps: list[ColumnMap] = [ColumnMap("t", f"{plan['columns'][1]}.out", a=0)]
    node_recorders(plan, recs, maps)
    for c, name in enumerate(plan["corners"]):
        if plan["gap_elements"]:
            gap_recorder(plan, c, recs, maps)
            force_recorders(plan, c, recs, maps)
        else:
            maps += [
                ColumnMap(f"gap_{name}", None, offset=plan["g0"][c]),
                ColumnMap(f"fn_{name}", None),
                ColumnMap(f"ft_{name}", None),
            ]
    bent_recorders(plan, bent_names, recs, maps)
    for r in recs:
        if safe_file_name(r.file) != r.file:  # bent names are validated words; keep it so
            raise SceneError("bents", f"recorder file name {r.file!r} is not a plain file name")
    order = {c: k for k, c in enumerate(plan["columns"])}
    if sorted(order) != sorted(m.column for m in maps):
        raise AssertionError("recorder maps do not cover the result columns")
    maps.sort(key=lambda m: order[m.column])
    return recs, maps


def node_recorders(plan: dict, recs: list[Recorder], maps: list[ColumnMap]) -> None:
    """Append the displacement and velocity recorders of the deck centre (x, y, θ; each
    segment's centre for a deck of segments) and the seats (x, θ) and their maps."""

    def node(col: str, vcol: str, tag: int, dof: int, what: str, unit: str) -> None:
        for c, response, kind in ((col, "disp", ""), (vcol, "vel", "/s")):
            quantity = "displacement" if response == "disp" else "velocity"
            recs.append(
                Recorder(
                    f"{c}.out",
                    "Node",
                    (tag,),
                    (response,),
                    (c,),
                    f"{what}, absolute {quantity} [{unit}{kind}]",
                    dofs=(dof,),
                )
            )
            maps.append(ColumnMap(c, f"{c}.out"))

    # the engine columns in DOF order: each segment's x, y, θ, then seat x, θ per seat, and
    # the velocities in the same order (deckpound.models.engine_contract.engine_columns)
    bodies = plan["bodies"]
    n = 3 * len(bodies) + 4
    cols = plan["columns"]
    names = list(zip(cols[1 : 1 + n], cols[1 + n : 1 + 2 * n]))
    for s, body in enumerate(bodies):
        what = "deck centre" if len(bodies) == 1 else f"segment {cols[1 + 3 * s][:-6]} centre"
        for dof, (col, vcol) in enumerate(names[3 * s : 3 * s + 3], start=1):
            unit = "rad" if dof == 3 else "m"
            node(col, vcol, body, dof, f"{what} node {body} dof {dof}", unit)
    seats = names[3 * len(bodies) :]
    for j, seat in enumerate(plan["seats"], start=1):
        for dof, (col, vcol) in zip((1, 3), seats[2 * j - 2 : 2 * j]):
            unit = "rad" if dof == 3 else "m"
            node(col, vcol, seat, dof, f"seat {j} node {seat} dof {dof}", unit)


def gap_recorder(plan: dict, c: int, recs: list[Recorder], maps: list[ColumnMap]) -> None:
    """Append corner ``c``'s gap recorder and map: a skewed face (any element) records the
    corner nodes' x and y displacements and projects them on n; a straight face with
    friction their x displacements (n = (side, 0)); else the gap element's deformation."""
    k = plan["corners"][c]
    side, g0 = plan["sides"][c], plan["g0"][c]
    e = plan["gap_elements"][c]
    dn, sn = plan["deck_corners"][c], plan["seat_corners"][c]
    nx, ny = plan["normals"][c]
    if ny != 0.0:
        # skewed deck, any element: the gap is the engine's own projection of the node
        # displacements on n (the zeroLength's deformation a.(u_j - u_i) is the same gap
        # but in other arithmetic: its last bits would differ from the engine's column)
        recs.append(
            Recorder(
                f"gap_{k}.out",
                "Node",
                (dn, sn),
                ("disp",),
                ("ux_deck corner", "uy_deck corner", "ux_seat point", "uy_seat point"),
                f"x and y displacements of deck corner node {dn} and seat point node {sn} [m]",
                dofs=(1, 2),
            )
        )
        maps.append(
            ColumnMap(
                f"gap_{k}", f"gap_{k}.out", a=1, b=3, offset=g0, scale=nx, a2=2, b2=4, scale2=ny
            )
        )
    elif plan["corner_friction"][c]:  # straight face: x displacements only, n = (side, 0)
        recs.append(
            Recorder(
                f"gap_{k}.out",
                "Node",
                (dn, sn),
                ("disp",),
                ("u_deck corner", "u_seat corner"),
                f"x displacement of deck corner node {dn} and seat corner node {sn} [m]",
                dofs=(1,),
            )
        )
        maps.append(ColumnMap(f"gap_{k}", f"gap_{k}.out", a=1, b=2, offset=g0, scale=side))
    else:
        recs.append(
            Recorder(
                f"gap_{k}.out",
                "Element",
                (e,),
                ("deformation",),
                ("deformation",),
                f"deformation u_j - u_i of gap element {e} [m]",
            )
        )
        maps.append(ColumnMap(f"gap_{k}", f"gap_{k}.out", offset=g0))


def force_recorders(plan: dict, c: int, recs: list[Recorder], maps: list[ColumnMap]) -> None:
    """Append corner ``c``'s contact force recorders and the fn, ft maps: with friction the
    element's resisting forces projected on −n and −t, else the gap material's stress."""
    k = plan["corners"][c]
    e = plan["gap_elements"][c]
    if plan["corner_friction"][c]:
        side = plan["sides"][c]
        (nx, ny), (tx, ty) = plan["normals"][c], plan["tangents"][c]
        # fn = -n.(Fx_j, Fy_j), ft = -t.(Fx_j, Fy_j) (j = deck corner); straight: -side*Fx_j,
        # -Fy_j
        terms = (
            ((f"fn_{k}", 4, -side, None, 0.0), (f"ft_{k}", 5, -1.0, None, 0.0))
            if ny == 0.0
            else ((f"fn_{k}", 4, -nx, 5, -ny), (f"ft_{k}", 4, -tx, 5, -ty))
        )
        for col, a, scale, a2, scale2 in terms:
            recs.append(
                Recorder(
                    f"{col}.out",
                    "Element",
                    (e,),
                    ("force",),
                    ("Fx_i", "Fy_i", "M_i", "Fx_j", "Fy_j", "M_j"),
                    f"resisting forces of contact element {e} (i = seat, "
                    "j = deck corner) [kN, kN*m]",
                )
            )
            maps.append(ColumnMap(col, f"{col}.out", a=a, scale=scale, a2=a2, scale2=scale2))
    else:
        recs.append(
            Recorder(
                f"fn_{k}.out",
                "Element",
                (e,),
                ("basicForce",),
                ("stress",),
                f"material stress of gap element {e}, <= 0 in compression [kN]",
            )
        )
        maps.append(ColumnMap(f"fn_{k}", f"fn_{k}.out", scale=-1.0))
        maps.append(ColumnMap(f"ft_{k}", None))


def bent_recorders(plan: dict, bent_names, recs: list[Recorder], maps: list[ColumnMap]) -> None:
    """Append the stress recorders of each bent's Hysteretic materials (x, y) and maps."""
    for name, e in zip(bent_names, plan["bent_elements"]):
        for mat, d in ((1, "x"), (2, "y")):
            col = f"{name}_f{d}"
            recs.append(
                Recorder(
                    f"{col}.out",
                    "Element",
                    (e,),
                    ("material", mat, "stress"),
                    ("stress",),
                    f"bent {name} element {e}, Hysteretic stress in "
                    f"{d} (deck - table deformation) [kN]",
                )
            )
            maps.append(ColumnMap(col, f"{col}.out"))


def render_recorders(recs: list[Recorder], lang: str) -> list[str]:
    """The recorder commands as lines of ``lang``: Tcl uses ``$outDir`` and ``$recDT``, Python
    ``_out(out_dir, name)`` and ``opts`` (-time -precision 17 -dT REC_DT; the script defines
    them)."""
    lines = []
    for r in recs:
        lines.append(f"# {comment_text(f'{r.file}: {r.meaning}', lang)}")
        if lang == "tcl":
            rest = " ".join(tcl_word(a) if isinstance(a, str) else str(a) for a in r.args())
            lines.append(
                f"recorder {r.kind} -file [file join $outDir {tcl_word(r.file)}] -time "
                f"-precision {PRECISION} -dT $recDT {rest}"
            )
        else:
            rest = ", ".join(py_str(a) if isinstance(a, str) else str(a) for a in r.args())
            lines.append(
                f"ops.recorder({py_str(r.kind)}, '-file', _out(out_dir, {py_str(r.file)}), "
                f"*opts, {rest})"
            )
    return lines


def manifest_entries(recs: list[Recorder], maps: list[ColumnMap]) -> dict:
    """JSON-able description of the recorder files and the column maps."""
    return {
        "files": [{**asdict(r), "columns": ["time", *r.columns]} for r in recs],
        "columns": [{**asdict(m), "formula": m.formula()} for m in maps],
    }


def read_columns(folder: str | Path, maps: list[ColumnMap] | list[dict]) -> dict[str, np.ndarray]:
    """deckpound's result columns from the recorder files in ``folder`` (maps as objects or
    as the dicts of a manifest)."""
    folder = Path(folder)
    maps = [
        m
        if isinstance(m, ColumnMap)
        else ColumnMap(**{k: v for k, v in m.items() if k != "formula"})
        for m in maps
    ]
    tables = {m.file: np.loadtxt(folder / m.file, ndmin=2) for m in maps if m.file}
    n_rows = {len(t) for t in tables.values()}
    if len(n_rows) != 1:
        raise ValueError(f"recorder files in {folder} differ in length: {sorted(n_rows)} rows")
    n = n_rows.pop()
    return {m.column: m.apply(tables.get(m.file), n) for m in maps}

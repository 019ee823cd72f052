"""The audit header of the exported scripts: what an engineer needs to check the model.

:func:`header_lines` returns plain text lines (not yet comments): title, scene name and hash,
how to run, units and axes, sign conventions of the gap and bent elements, damping assignment,
analysis and fallback, support records, recorder files and their map to deckpound's columns,
a legend of every tag (from the :class:`~.ops.OpsSession` tag registry) and the scene's notes.
Everything that is not a number is read from the command log, the tag registry and the step
plan, so the header describes the commands below it and not a separate description. The script
writers turn each line into a comment with :func:`~.quoting.comment_text`, which is where scene
text is made harmless.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from deckpound.models.version import VERSION

from .ops import ArrayArg, Command
from .quoting import wrap_comment
from .recorders import PRECISION, ColumnMap, Recorder

UNITS = (
    "Units: force kN, length m, mass t (tonne), time s, angle rad (1 kN = 1 t*m/s^2); "
    "stiffness kN/m or kN*m/rad, damping kN*s/m or kN*m*s/rad, stress of a zeroLength "
    "material = force [kN]."
)
AXES = (
    "Axes: x longitudinal (bridge axis), y transverse, theta rotation about the vertical, "
    "counter-clockwise positive; model basic -ndm 2 -ndf 3: dof 1 = x, 2 = y, 3 = theta."
)

#: width of the header lines (before the comment sign and escapes)
WIDTH = 96
#: (regular expression on a registry name, meaning) per kind; {0}, {1} are the groups
_MEANING = {
    "node": [
        (r"deck", "deck centre: all the deck mass and polar inertia"),
        (r"segment (\w+)", "centre of deck segment {0}: its mass and polar inertia"),
        (r"deck (c\d)", "deck corner {0}"),
        (r"deck (j\d+)_(c\d)", "joint {0} corner {1}: the striking segment's left-end corner"),
        (r"facing (j\d+)_(c\d)", "joint {0}: facing segment's end-face point met by corner {1}"),
        (r"deck ref (.+)", "reference node of the relative mass damping ({0})"),
        (r"deck (\w+)", "deck point above bent {0}"),
        (r"stick (\d+)", "node of the deck stick axis"),
        (r"stick (\w+) (\d+)", "node of the stick axis of segment {0}"),
        (r"seat(\d)", "seat {0}: contact-face mid-point, seat mass and inertia"),
        (r"seat(\d) (c\d)", "seat {0} point facing deck corner {1} (rigidLink to the seat)"),
        (r"actuator(\d)", "actuator {0}: imposed x motion; y and theta fixed"),
        (r"table (\w+)", "shake table of bent {0}: imposed x and y motion; theta fixed"),
    ],
    "element": [
        (r"bent (\w+)", "bent {0} springs, table -> deck point (x, y)"),
        (r"seat(\d) spring", "seat {0} springs kx, ktheta, actuator -> seat"),
        (r"seat(\d) dashpot", "seat {0} dashpots cx, ctheta, actuator -> seat"),
        (r"seat(\d) guide", "seat {0} y guide (stiff spring, the seat has no y mass)"),
        (r"gap (c\d)", "contact (gap) element of corner {0}"),
        (r"gap (j\d+_c\d)", "contact (gap) element of joint corner {0}"),
        (r"stick (c\d)", "transverse deck stick to corner {0}"),
        (r"stick (j\d+_c\d)", "transverse stick of the striking segment to corner {0}"),
        (r"stick facing (j\d+_c\d)", "transverse stick of the facing segment, met by {0}"),
        (r"stick (\d+)", "deck stick along the axis"),
        (r"stick (\w+) (\d+)", "stick along the axis of segment {0}"),
    ],
    "material": [
        (r"(\w+) ([xy])", "bent {0}, {1}: Hysteretic (Takeda stand-in)"),
        (r"seat(\d) (kx|ktheta)", "seat {0} spring {1}"),
        (r"seat(\d) (cx|ctheta)", "seat {0} dashpot {1}"),
        (r"seat guide", "seat y guide spring"),
        (r"gap (c\d)", "gap law of corner {0}"),
        (r"gap (j\d+_c\d)", "gap law of joint corner {0}"),
    ],
    "timeSeries": [
        (r"(\w+) disp", "displacement of support channel {0} [m]"),
        (r"(\w+) vel", "velocity of support channel {0} [m/s]"),
    ],
    "groundMotion": [(r"(\w+)", "support channel {0} (-disp and -vel series)")],
    "pattern": [(r"supports", "MultipleSupport pattern of all imposed motions")],
    "transf": [(r"deck", "Linear transformation of the deck sticks")],
    "region": [(r"sticks", "the deck sticks (excluded from Rayleigh damping)")],
}


@dataclass
class ExportParts:
    """Everything an exported script is made of (built by :func:`.export.export_parts`)."""

    scene: object
    fmt: str
    stem: str
    log: list[Command]
    tags: dict[str, dict[str, int]]
    plan: dict
    records: list[dict]
    file_of: dict[str, str]
    recorders: list[Recorder]
    maps: list[ColumnMap]
    rec_dt: float
    scene_hash: str
    data_dir: str
    out_dir: str
    names: dict[str, dict[int, str]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.names = {k: {t: n for n, t in v.items()} for k, v in self.tags.items()}

    def name(self, kind: str, tag) -> str:
        return self.names.get(kind, {}).get(int(tag), "?")


def meaning(kind: str, name: str) -> str:
    for pattern, text in _MEANING.get(kind, []):
        m = re.fullmatch(pattern, name)
        if m:
            return text.format(*m.groups())
    return name


def _fmt(v) -> str:
    if isinstance(v, ArrayArg):
        return f"<{len(v.values)} values>"
    if isinstance(v, float):
        return f"{v:.12g}"
    return str(v)


def _first(log: list[Command], name: str, pos: int | None = None, value=None) -> Command | None:
    """The first command ``name`` (whose argument ``pos`` equals ``value``, if given)."""
    for c in log:
        if c.name == name and (pos is None or (len(c.args) > pos and c.args[pos] == value)):
            return c
    return None


def tag_legend(p: ExportParts) -> list[str]:
    """One line per tag of every kind, with the facts the log gives about it."""
    out = ["Tags (from deckpound's tag registry; name: meaning):"]
    for kind in (
        "node",
        "element",
        "material",
        "transf",
        "region",
        "timeSeries",
        "groundMotion",
        "pattern",
    ):
        for name, tag in sorted(p.tags.get(kind, {}).items(), key=lambda kv: kv[1]):
            fact = ""
            if kind == "node":
                c = _first(p.log, "node", 0, tag)
                m = _first(p.log, "mass", 0, tag)
                fact = f" at ({_fmt(c.args[1])}, {_fmt(c.args[2])})" if c else ""
                fact += f", mass {' '.join(_fmt(a) for a in m.args[1:])}" if m else ""
            elif kind == "element":
                c = _first(p.log, "element", 1, tag)
                if c:
                    fact = (
                        f" [{c.args[0]} {p.name('node', c.args[2])} -> {p.name('node', c.args[3])}]"
                    )
            elif kind == "material":
                c = _first(p.log, "uniaxialMaterial", 1, tag)
                fact = f" [{c.args[0]}]" if c else ""
            out.append(f"  {kind} {tag} '{name}': {meaning(kind, name)}{fact}")
    return out


def sign_lines(p: ExportParts) -> list[str]:
    """Gap and bent sign conventions, per corner from the element and material commands."""
    normals = p.plan.get("normals") or [[s, 0.0] for s in p.plan["sides"]]
    skewed = any(n[1] != 0.0 for n in normals)
    names = p.plan["corners"]
    # the first corner facing seat 2 (c3): after the joints' corners in a deck of segments
    right = names.index("c3")
    out = [
        "Sign conventions (gap g, contact force fn, as deckpound reports them):",
        "  side = +1 for corners c1, c2 (seat 1, left), -1 for c3, c4 (seat 2, right);",
    ]
    if len(names) > 4:
        out.append(
            "  joints: corners j<k>_c1, j<k>_c2 are the left-end corners of segment k + 1 "
            "striking the right end face of segment k, side = +1; their 'seat point' is the "
            "node 'facing j<k>_c<m>' on segment k's face (g0 from the corner along -n), "
            "rigidLinked to segment k's centre (stick mode: a stick from its axis end);"
        )
    if skewed:
        out += [
            (
                "  skewed deck: n = gap-opening normal of each corner's end face (c1, c2: "
                f"{_fmt(normals[0][0])}, {_fmt(normals[0][1])}; c3, c4: "
                f"{_fmt(normals[right][0])}, "
                f"{_fmt(normals[right][1])}), t = face tangent {_fmt(p.plan['tangents'][0][0])}, "
                f"{_fmt(p.plan['tangents'][0][1])};"
            ),
            (
                "  physical gap g = g0 + n.(u_deck corner - u_seat point): open > 0, "
                "penetration < 0 (g0 measured along n);"
            ),
            "  fn >= 0 is compression; ft is the tangential force ON the deck corner along t.",
        ]
    else:
        out += [
            "  physical gap g = g0 + side*(u_deck,x - u_seat,x): open > 0, penetration < 0;",
            (
                "  fn >= 0 is compression; ft is the tangential (y) force ON the deck corner, "
                "+ = +y."
            ),
        ]
    for c, e in enumerate(p.plan["gap_elements"]):
        cmd = _first(p.log, "element", 1, e)
        i, j = p.name("node", cmd.args[2]), p.name("node", cmd.args[3])
        side, g0 = p.plan["sides"][c], p.plan["g0"][c]
        if p.plan["corner_friction"][c]:
            k = cmd.args.index("-normal")
            nx, ny = cmd.args[k + 1], cmd.args[k + 2]
            if skewed:
                out.append(
                    f"  {names[c]}: zeroLengthContact2D {e}, i = {i}, j = {j}, normal "
                    f"({_fmt(nx)}, {_fmt(ny)}) = -n, from the deck to the seat; g0 = "
                    f"{g0!r} m (the nodes sit g0 apart along n); fn = -n.(Fx_j, Fy_j), "
                    "ft = -t.(Fx_j, Fy_j)"
                )
            else:
                out.append(
                    f"  {names[c]}: zeroLengthContact2D {e}, i = {i}, j = {j}, normal "
                    f"({_fmt(nx)}, 0) from the deck to the seat; g0 = {g0!r} m (the nodes "
                    f"sit g0 apart); fn = -side*Fx_j = {_fmt(-side)}*Fx_j, ft = -Fy_j"
                )
        else:
            mat = _first(p.log, "uniaxialMaterial", 1, cmd.args[5])
            args = " ".join(_fmt(a) for a in mat.args[2:])
            if "-orient" in cmd.args:
                k = cmd.args.index("-orient")
                along = (
                    f"along its local x axis a = ({_fmt(cmd.args[k + 1])}, "
                    f"{_fmt(cmd.args[k + 2])}) (-orient)"
                )
                strain = f"a.(u_j - u_i) = {'+' if side > 0 else '-'}a.(u_deck - u_seat)"
            else:
                along = "along x"
                strain = f"u_j - u_i = {'+' if side > 0 else '-'}(u_deck - u_seat)"
            out.append(
                f"  {names[c]}: zeroLength {e} {along}, i = {i}, j = {j}: deformation "
                f"e = {strain} = g - g0, "
                f"closing negative; material {mat.args[1]} {mat.args[0]} {args} (negative "
                f"gap and yield: compression only); g = {g0!r} + e, fn = -stress"
            )
    if not p.plan["gap_elements"]:
        out.append("  this model has no gap elements (contact-free)")
    out.append(
        "  bents: zeroLength i = table, j = deck point; deformation u_deck - u_table; "
        "Hysteretic stress > 0 when the deck is displaced +x (+y) from its table"
    )
    return out


def damping_lines(p: ExportParts) -> list[str]:
    """Which elements and nodes take Rayleigh damping, read from the commands."""
    out = []
    ray = _first(p.log, "rayleigh")
    if ray is None:
        return ["Damping: no rayleigh command (only the element dashpots)."]
    am, bk, bk0, bkc = (float(a) for a in ray.args)
    out.append(
        f"Damping: rayleigh alphaM = {am:.12g}, betaK (current tangent) = {bk:.12g}, "
        f"betaKinit (initial stiffness) = {bk0:.12g}, betaKcomm (last committed) = "
        f"{bkc:.12g}."
    )
    masses = [f"{c.args[0]} {p.name('node', c.args[0])}" for c in p.log if c.name == "mass"]
    if am != 0.0:
        out.append(
            f"  alphaM*M acts on the nodes with mass ({', '.join(masses)}) and, under "
            "MultipleSupport, on their ABSOLUTE velocities."
        )
    else:
        out.append(
            "  alphaM = 0: no mass-proportional Rayleigh term (a mass part on velocities "
            "relative to the supports, if any, is in the 'mass damper' Viscous elements)."
        )
    with_r, without, beams = [], [], []
    for c in p.log:
        if c.name != "element":
            continue
        label = f"{c.args[1]} {p.name('element', c.args[1])}"
        if c.args[0] == "zeroLength":
            k = list(c.args).index("-doRayleigh") if "-doRayleigh" in c.args else -1
            (with_r if k >= 0 and int(c.args[k + 1]) == 1 else without).append(label)
        elif c.args[0] == "zeroLengthContact2D":
            without.append(label)
        else:
            beams.append(label)
    out.append(
        "  stiffness part on the elements with -doRayleigh 1: " + (", ".join(with_r) or "none")
    )
    out.append(
        "  no Rayleigh (zeroLength without -doRayleigh, zeroLengthContact2D): "
        + (", ".join(without) or "none")
    )
    excluded = set()
    for c in p.log:
        if c.name == "region":
            a = list(c.args)
            eles = a[a.index("-eleOnly") + 1 : a.index("-rayleigh")] if "-eleOnly" in a else []
            fac = (
                " ".join(_fmt(x) for x in a[a.index("-rayleigh") + 1 :]) if "-rayleigh" in a else ""
            )
            excluded |= {int(x) for x in eles}
            out.append(
                f"  region {a[0]} '{p.name('region', a[0])}': elements {len(eles)} "
                f"({_fmt(eles[0]) if eles else ''}..{_fmt(eles[-1]) if eles else ''}), "
                f"rayleigh {fac}"
            )
    rest = [b for b in beams if int(b.split()[0]) not in excluded]
    if beams:
        out.append(
            "  beam elements take the global factors unless in a region: "
            + (", ".join(rest) or "none (all in regions)")
        )
    return out


def analysis_lines(p: ExportParts) -> list[str]:
    pl = p.plan
    cmds = "; ".join(" ".join(_fmt(a) for a in c) for c in pl["analysis"])
    out = [
        f"Analysis: {cmds}.",
        (
            f"  dt = {pl['dt']!r} s, {pl['n_steps']} steps of analyze 1 $dt "
            f"({pl['n_steps'] * pl['dt']:.6g} s); deckpound stores a row at t = 0 and every "
            f"{pl['stride']} steps ({pl['stride'] * pl['dt']:.6g} s)."
        ),
        (
            "  Every analyze return code is checked. On a failed step OpenSees has reverted to "
            "the last commit; the step loop below counts it as a failure and"
        ),
    ]
    if pl["fallback"] == "substep":
        out.append(
            f"  (fallback 'substep') rebuilds the analysis (wipeAnalysis + the commands "
            "above: the Transformation handler keeps a stale increment on constrained "
            f"nodes otherwise), retries with {pl['substeps']} sub-steps of "
            f"dt/{pl['substeps']}, each checked, and rebuilds the analysis again; a step "
            "that still fails stops the run with status 'failed'."
        )
    else:
        out.append("  (fallback 'none') stops the run with status 'failed'.")
    return out + seat_lines(p)


def seat_lines(p: ExportParts) -> list[str]:
    """The unseating check of the step loop, with each corner's support length."""
    lengths = p.plan["support_lengths"]
    per_corner = ", ".join(
        f"{name} {'none (not checked)' if n is None else f'{_fmt(n)} m'}"
        for name, n in zip(p.plan["corners"], lengths)
    )
    where = "" if p.fmt == "tcl" else " and written to opensees.stats.json"
    return [
        (
            "  Unseating, as deckpound checks it: at every converged step and sub-step, corner c "
            "is unseated when its gap has opened by more than the support length N of the seat "
            "it faces since t = 0 (seat margin N - (g - g(0)) < 0); the loop stops after that "
            "step with status 'unseated' (exit 0), stores no row of it and cuts the recorder "
            "files to the rows stored; the smallest margin of each corner and its time are "
            f"printed{where}. N: {per_corner}."
        )
    ]


def record_lines(p: ExportParts) -> list[str]:
    out = [
        (
            "Support motion: MultipleSupport, each channel imposes displacement AND velocity "
            "(groundMotion Plain -disp -vel) read by timeSeries Path -dt -filePath from "
            f"'{p.data_dir}/' (one value a line, 17 digits; manifest.json there lists node, dof, "
            "dt, units, count, sha256). Path series interpolate linearly and return 0 after "
            "their last value, so every record ends with its last value repeated."
        )
    ]
    for r in p.records:
        if r["quantity"] != "displacement":
            continue
        vel = next(
            (v for v in p.records if v["channel"] == r["channel"] and v["quantity"] == "velocity"),
            None,
        )
        out.append(
            f"  {r['channel']}: node {r['node']} ({r['node_name']}) dof {r['dof']}; "
            f"disp {r['file']} [m], vel {vel['file'] if vel else '-'} [m/s]; "
            f"dt {r['dt']!r} s, {r['count']} values"
        )
    return out


def recorder_lines(p: ExportParts) -> list[str]:
    out = [
        (
            f"Recorders: files in the output folder (default '{p.out_dir}/'), each line 'time "
            f"value...' at {PRECISION} significant digits; written at t = 0 (record) and at "
            f"every output step: -dT = (stride - m)*dt = {p.rec_dt!r} s with m = half a "
            "sub-step, so the sub-steps of the fallback never add rows. deckpound's columns "
            "follow from them as (file[k] = column k of the file, 0 = time):"
        )
    ]
    out += [f"  {m.formula()}" for m in p.maps]
    vel = [r.file for r in p.recorders if r.file.endswith("_vel.out")]
    out.append(f"  also: {', '.join(vel)} (absolute velocities [m/s, rad/s])")
    out.append(
        "  deckpound.opensees_build.recorders.read_columns(folder, "
        "manifest['recorders']['columns']) applies these maps."
    )
    return out


def header_lines(p: ExportParts) -> list[str]:
    """The header as plain text lines (the writers make them comments)."""
    sc = p.scene
    lang = "Tcl" if p.fmt == "tcl" else "OpenSeesPy"
    friction = f", friction {sc.contact.friction_mode}" if sc.contact.has_friction else ""
    joints = "".join(
        f"; {where}: law {jc.law}" + (f", friction {jc.friction_mode}" if jc.has_friction else "")
        for where, jc in sc.contact_tables()[1:]
    )
    segments = "" if sc.segments is None else f" of {len(sc.segments)} segments"
    out = [
        f"deckpound {VERSION} export ({lang}) of scene '{sc.name}'",
        f"scene sha256: {p.scene_hash}",
        (
            f"model: {sc.opensees.mode} deck{segments}, {len(sc.bents)} bents, contact law "
            f"{sc.contact.law}{friction}{joints}; dt {sc.opensees.dt!r} s; "
            f"{p.plan['n_steps']} steps"
        ),
        UNITS,
        AXES,
    ]
    if p.fmt == "tcl":
        out.append(
            f"Run: OpenSees {p.stem}.tcl  (set outDir, writeCsv before 'source' to "
            "override the output folder / also write deckpound's CSV)"
        )
    else:
        out.append(
            f"Run: python {p.stem}.py [--out DIR] [--csv]  (--csv also writes "
            "deckpound's CSV, opensees.csv)"
        )
    if sc.description:
        out += ["Description:"] + [f"  {x}" for x in wrap_comment(sc.description)]
    out += [""] + sign_lines(p) + [""] + damping_lines(p) + [""] + analysis_lines(p)
    out += [""] + record_lines(p) + [""] + recorder_lines(p) + [""] + tag_legend(p)
    seats = [f"seat{j + 1} = '{s.name}'" for j, s in enumerate(sc.seats)]
    out.append(f"  (scene labels: {', '.join(seats)})")
    if sc.notes:
        out += ["", "Scene notes (sources and assumptions):"]
        for key, text in sc.notes.items():
            lines = wrap_comment(f"{key}: {text}", width=88)
            out += [f"  {lines[0]}"] + [f"    {x}" for x in lines[1:]]
    return [w for line in out for w in _wrap(line)]


def _wrap(line: str, width: int = WIDTH) -> list[str]:
    """A long line split on spaces, continuation lines indented two more than the first."""
    if len(line) <= width:
        return [line]
    body = line.lstrip(" ")
    lead = line[: len(line) - len(body)]
    words = body.split(" ")
    out, cur = [], lead + words[0]
    for w in words[1:]:
        if len(cur) + 1 + len(w) > width and cur.strip():
            out.append(cur)
            cur = lead + "  " + w
        else:
            cur = f"{cur} {w}"
    out.append(cur)
    return out

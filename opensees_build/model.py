"""Scene → OpenSees model commands (plan view: ndm 2, ndf 3; kN, m, t, s).

Nodes (tags by name through :meth:`OpsSession.tag`):

* ``deck`` — deck centre (0, 0) carrying all the deck mass (M_d, M_d, I_d);
* ``deck c1..c4`` — deck corners at (±L/2 + y_c tan φ, y_c), y_c = ±W/2 (c1 (−,−), c2 (−,+),
  c3 (+,−), c4 (+,+)), the plan model's corner table (φ = ``deck.skew``, 0 for a straight deck);
* the deck node above each bent at (x_b, 0) (the centre node itself when x_b = 0);
* ``seat1``/``seat2`` — the seats' pivots (contact-face mid-points) (∓L/2, 0) with mass
  (m_s, 0, I_s); with friction they sit at the physical pivot F₀ = (∓L/2, 0) − g₀ n (n the
  face's gap-opening normal; ∓(L/2 + g₀) for a straight deck) so that zeroLengthContact2D,
  whose gap includes the node coordinates, sees the clear gap g₀ along n;
* ``seat1 c1``, ... — seat points facing the deck corners, at pivot + lever r = (y_c tan φ, y_c)
  (the plan's ``Corner.lever``), rigidLinked (beam) to their seat node — or fixed, for a
  ``seats[i].fixed`` rigid abutment (its actuator is then at rest);
* ``actuator1``/``actuator2`` — at the seat nodes, imposed x motion, y and θ fixed;
* ``table <bent>`` — at (x_b, 0), imposed x and y motion, θ fixed.

Mode ``rigid``: rigidLink beams from the centre to the corners and bent nodes (exactly the 7
DOF of the analytic engines, plus massless seat-y DOFs held by a guide spring). Mode
``stick``: elasticBeamColumn sticks along the axis (``stick_elements`` equal elements per half,
plus nodes at the bent stations), transverse sticks from the deck ends to the corners;
E = ``deck.stick_modulus``, section of a deck W wide and W/8 deep (A = W²/8, I = W⁴/96 about
the vertical axis) — with E = 3e9 kN/m² (100× concrete) the sticks are near-rigid; the sticks
are massless and excluded from Rayleigh damping (``region -eleOnly ... -rayleigh 0 0 0 0``).

Seat guide: a rigidLink retained node must not be ``fix``ed (it breaks the Transformation
handler in 3.7), so each seat's y DOF is held by a stiff zeroLength spring (:data:`GUIDE_STIFFNESS`)
from its actuator, without Rayleigh damping; the seat has no y mass.

Springs: bents — zeroLength table → deck bent node, Hysteretic (Takeda stand-in) in x and y;
seats — zeroLength actuator → seat, Elastic k in x and θ, and a second zeroLength with
Viscous(c, α = 1) dashpots (no Rayleigh on it: see the comment in :func:`build_model`).
Damping (:mod:`deckpound.models.damping`, the scene's ``[damping]``): ``rayleigh αM βK βKinit
βKc`` (:func:`.damping.rayleigh_factors`: a1 on the stiffness the scene names), ``-doRayleigh 1`` on the
members the scene names (:func:`.damping.rayleigh_members`: the bents by default, the seat springs too
with ``bents+seats``); αM = a0 on the absolute velocities of the deck and seat nodes, or, with
``mass = relative``, Viscous dashpots from support reference nodes (:func:`.damping.mass_dampers`). Gap
elements, guides and sticks take no Rayleigh damping.

Gaps: see :func:`.gaps.gap_mapping` — the ONE place where the positive physical gap g₀ and the
closing direction are mapped to OpenSees' node order, element orientation and negative
(compression) parameters. Skewed decks (φ ≠ 0): the gap elements act along the face normal
(zeroLength ``-orient``, zeroLengthContact2D ``-normal``), the seats still slide along x; the
seat guide spring then carries the normal force's y component n_y·f_N, so its stiffness is
:data:`SKEW_GUIDE_STIFFNESS` (see there).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from deckpound.models.contact_laws_table import contact_law
from deckpound.models.damping import damping_model
from deckpound.models.errors import SceneError
from deckpound.models.plan import plan_of, takeda_hysteretic_args
from deckpound.models.scene import Scene

from .damping import mass_dampers, rayleigh_factors, rayleigh_members
from .gaps import SIDES, contact_normal, gap_mapping
from .geometry import seat_pivot, stick_section, stick_stations
from .ops import ArrayArg, OpsSession

#: stiffness of the seat y guide springs [kN/m] (seat y stays ~ F_t / k ≈ 0)
GUIDE_STIFFNESS = 1.0e10
#: guide stiffness of a skewed deck's seats [kN/m]. The plan model's seats cannot move in y;
#: OpenSees cannot ``fix`` them (a retained node of a rigidLink, see the module docstring), so
#: a guide spring holds them. With skew the normal force has a y component n_y f_N = sin φ f_N
#: on the seat (zero for a straight deck), and a 1e10 guide would put a series compliance
#: n_y²/k_guide ≈ 2.5e-11 m/kN (φ = 30°) behind each 1e6 kN/m contact: a 2.5e-5 relative
#: difference from the plan model. 1e16 makes it 2.5e-11, below the round-off the clone
#: comparison resolves (1e-9 of each column's peak), and the massless y DOF it restrains is
#: only coupled through the contacts (LU pivots on it harmlessly; checked by the skew
#: clone-vs-OpenSees test). Kept separate so a straight deck's command log is unchanged.
SKEW_GUIDE_STIFFNESS = 1.0e16
#: samples of the last value appended to every support record (a Path series returns 0 at and
#: after its last sample; time advances by repeated addition of dt and may overshoot)
RECORD_PAD = 16
CORNER_NAMES = ("c1", "c2", "c3", "c4")


@dataclass
class ModelInfo:
    """Tags and constants the runner needs to read the model's state.

    ``normals``/``tangents``: per corner the gap-opening normal n and the face tangent t of the
    plan's corner table (gap g = g₀ + n·(u_deck corner − u_seat point); ft along t on the deck).
    """

    mode: str
    deck: int
    seats: tuple[int, int]
    deck_corners: tuple[int, ...]
    seat_corners: tuple[int, ...]
    gap_elements: tuple[int, ...]
    g0: tuple[float, ...]
    sides: tuple[float, ...]
    bent_names: tuple[str, ...]
    bent_elements: tuple[int, ...]
    friction: bool
    normals: tuple[tuple[float, float], ...] = ()
    tangents: tuple[tuple[float, float], ...] = ()
    stick_elements: tuple[int, ...] = ()
    notes: list[str] = field(default_factory=list)


# -- checks -------------------------------------------------------------------------------


def refuse_scene(scene: Scene) -> None:
    """Refuse (SceneError) what the OpenSees model cannot express, naming the alternatives.

    The "option does nothing" warnings are derived by the engine contract from
    :meth:`deckpound.opensees_build.engine.OpenSeesEngine.reads`.
    """
    from deckpound.models.contact_laws_table import (
        BILINEAR_MIN_SUBSTEPS,
        BILINEAR_OPENSEES_REASON,
        friction_model,
    )

    c = scene.contact
    law = contact_law(c.law)
    if law.opensees is None:
        raise SceneError("contact.law", law.opensees_refusal)
    o = scene.opensees
    if c.law == "bilinear" and (o.substeps < BILINEAR_MIN_SUBSTEPS or o.fallback != "substep"):
        raise SceneError(
            "opensees.substeps",
            BILINEAR_OPENSEES_REASON.format(
                min=BILINEAR_MIN_SUBSTEPS,
                got=o.substeps
                if o.fallback == "substep"
                else f"{o.substeps} with fallback = {o.fallback!r}",
            ),
        )
    if c.has_friction:
        model = friction_model(c.friction_mode)
        if model.opensees is None:
            raise SceneError("contact.friction_mode", model.opensees_refusal)
        if c.law not in model.opensees_laws:
            raise SceneError(
                "contact.law",
                f"OpenSees cannot combine the {c.law!r} law with "
                "friction: zeroLengthContact2D is a linear penalty contact; use "
                "law = 'linear' with friction",
            )


def padded(values: np.ndarray) -> np.ndarray:
    return np.concatenate([values, np.full(RECORD_PAD, values[-1])])


# -- the model ----------------------------------------------------------------------------


def build_model(
    ops: OpsSession, scene: Scene, motion=None, *, gaps: bool = True, supports: str = "motion"
) -> ModelInfo:
    """Define nodes, masses, constraints, materials, elements, damping and (optionally) the
    multiple-support excitation.

    Parameters
    ----------
    motion : resampled :class:`SupportMotion` on the analysis step (needed for
        ``supports = "motion"``).
    gaps : False leaves the gap elements out (contact-free model, e.g. for eigen).
    supports : ``"motion"`` — MultipleSupport imposed motion; ``"fixed"`` — supports fixed.
    """
    refuse_scene(scene)
    s = scene.opensees
    d = scene.deck
    plan = plan_of(scene)
    friction = gaps and scene.contact.has_friction
    damping = damping_model(scene, plan)
    ray_bents, ray_seats = rayleigh_members(scene)
    T = ops.tag
    ops.model("basic", "-ndm", 2, "-ndf", 3)

    # --- deck ------------------------------------------------------------------------------
    ops.comment("deck: centre node with all the deck mass")
    deck = T("node", "deck")
    ops.node(deck, 0.0, 0.0)
    ops.mass(deck, d.mass, d.mass, d.inertia)
    dcorners = []
    for name, corner in zip(CORNER_NAMES, plan.corners):
        n = T("node", f"deck {name}")
        ops.node(n, corner.x, corner.y)
        dcorners.append(n)
    tol = 1e-9 * d.length
    bent_nodes: list[int] = []
    sticks: list[int] = []
    if s.mode == "rigid":
        for b, xb in zip(scene.bents, plan.bent_x):
            if abs(xb) <= tol:
                bent_nodes.append(deck)
            else:
                n = T("node", f"deck {b.name}")
                ops.node(n, xb, 0.0)
                bent_nodes.append(n)
        ops.comment("rigid deck: rigidLink beams from the centre")
        for n in dcorners + [n for n in bent_nodes if n != deck]:
            ops.rigidLink("beam", deck, n)
    else:
        area, inertia = stick_section(scene)
        ops.comment(
            f"stick deck: E = {d.stick_modulus:g} kN/m2, A = W^2/8, I = W^4/96 (near-rigid)"
        )
        transf = T("transf", "deck")
        ops.geomTransf("Linear", transf)
        xs = stick_stations(scene)
        axis = []
        for k, x in enumerate(xs):
            if x == 0.0:
                axis.append(deck)
                continue
            n = T("node", f"stick {k}")
            ops.node(n, x, 0.0)
            axis.append(n)
        for k in range(len(axis) - 1):
            e = T("element", f"stick {k}")
            ops.element(
                "elasticBeamColumn", e, axis[k], axis[k + 1], area, d.stick_modulus, inertia, transf
            )
            sticks.append(e)
        for c, n in enumerate(dcorners):
            end = axis[0] if c < 2 else axis[-1]
            e = T("element", f"stick {CORNER_NAMES[c]}")
            ops.element("elasticBeamColumn", e, end, n, area, d.stick_modulus, inertia, transf)
            sticks.append(e)
        for xb in plan.bent_x:
            k = min(range(len(xs)), key=lambda k: abs(xs[k] - xb))
            bent_nodes.append(axis[k])

    # --- seats ----------------------------------------------------------------------------
    seats, scorners, acts = [], [], []
    for j, seat in enumerate(scene.seats):
        xf, yf = seat_pivot(plan, j, friction)
        ops.comment(f"seat {j + 1}: contact-face mid-point, guided in y by a stiff spring")
        n = T("node", f"seat{j + 1}")
        ops.node(n, xf, yf)
        ops.mass(n, seat.mass, 0.0, seat.inertia)
        seats.append(n)
        a = T("node", f"actuator{j + 1}")
        ops.node(a, xf, yf)
        ops.fix(a, 1 if supports == "fixed" else 0, 1, 1)
        acts.append(a)
        for c in (0, 1) if j == 0 else (2, 3):
            sc = T("node", f"seat{j + 1} {CORNER_NAMES[c]}")
            rx, ry = plan.corners[c].lever
            ops.node(sc, xf + rx, yf + ry)
            if seat.fixed:
                # rigid abutment (actuator at rest, checked by the scene): the seat point is
                # fixed, not linked to the seat node, so the contact force never reaches the
                # seat — the plan model's zero seat columns of W_N, W_T, exactly
                ops.fix(sc, 1, 1, 1)
            else:
                ops.rigidLink("beam", n, sc)
            scorners.append(sc)

    # --- materials and springs ----------------------------------------------------------------
    bent_eles = []
    tables = []
    for b, xb, dn in zip(scene.bents, plan.bent_x, bent_nodes):
        tn = T("node", f"table {b.name}")
        ops.node(tn, xb, 0.0)
        ops.fix(tn, *((1, 1, 1) if supports == "fixed" else (0, 0, 1)))
        tables.append(tn)
        mats = []
        for dirn, spring in (("x", b.x), ("y", b.y)):
            m = T("material", f"{b.name} {dirn}")
            ops.uniaxialMaterial("Hysteretic", m, *takeda_hysteretic_args(spring))
            mats.append(m)
        e = T("element", f"bent {b.name}")
        ops.element(
            "zeroLength",
            e,
            tn,
            dn,
            "-mat",
            *mats,
            "-dir",
            1,
            2,
            *(("-doRayleigh", 1) if ray_bents else ()),
        )
        bent_eles.append(e)
        # explicit bent dashpots (bents[i].cx, cy), in their own element like the seats'
        dash = [(dirn, c) for dirn, c in ((1, b.cx), (2, b.cy)) if c > 0.0]
        if dash:
            dmats = []
            for dirn, c in dash:
                m = T("material", f"{b.name} c{'xy'[dirn - 1]}")
                ops.uniaxialMaterial("Viscous", m, c, 1.0)
                dmats.append(m)
            ops.element(
                "zeroLength",
                T("element", f"bent {b.name} dashpot"),
                tn,
                dn,
                "-mat",
                *dmats,
                "-dir",
                *(dirn for dirn, _ in dash),
            )
    for j, seat in enumerate(scene.seats):
        mx = T("material", f"seat{j + 1} kx")
        ops.uniaxialMaterial("Elastic", mx, seat.kx)
        mt = T("material", f"seat{j + 1} ktheta")
        ops.uniaxialMaterial("Elastic", mt, seat.ktheta)
        e = T("element", f"seat{j + 1} spring")
        ops.element(
            "zeroLength",
            e,
            acts[j],
            seats[j],
            "-mat",
            mx,
            mt,
            "-dir",
            1,
            3,
            *(("-doRayleigh", 1) if ray_seats else ()),
        )
        # dashpots in their own element: with -doRayleigh 1 a zeroLength (3.7) drops its
        # materials' damping tangent from the damping matrix (Newton then converges linearly)
        cx = T("material", f"seat{j + 1} cx")
        ops.uniaxialMaterial("Viscous", cx, seat.cx, 1.0)
        ct = T("material", f"seat{j + 1} ctheta")
        ops.uniaxialMaterial("Viscous", ct, seat.ctheta, 1.0)
        e = T("element", f"seat{j + 1} dashpot")
        ops.element("zeroLength", e, acts[j], seats[j], "-mat", cx, ct, "-dir", 1, 3)
    mg = T("material", "seat guide")
    # with friction the guide also carries the tangential force: 1e10 would add a series
    # compliance 1/k_guide behind the 1e6 stick spring (a 1e-4 relative difference from the
    # plan model, whose seats do not move in y); the skew guide makes it round-off
    stiff_guide = d.skew != 0.0 or friction
    ops.uniaxialMaterial("Elastic", mg, SKEW_GUIDE_STIFFNESS if stiff_guide else GUIDE_STIFFNESS)
    for j in range(2):
        e = T("element", f"seat{j + 1} guide")
        ops.element("zeroLength", e, acts[j], seats[j], "-mat", mg, "-dir", 2)

    # --- gaps -----------------------------------------------------------------------------
    gap_eles = []
    g0 = tuple(scene.seats[0].gap if c < 2 else scene.seats[1].gap for c in range(4))
    if gaps:
        ops.comment(
            f"contact at the corners: law {scene.contact.law}"
            + (", zeroLengthContact2D with friction" if friction else "")
        )
        for c in range(4):
            e = T("element", f"gap {CORNER_NAMES[c]}")
            if friction:
                # i = seat point, j = deck corner; zeroLengthContact2D (3.7) measures the gap
                # as n_c·(x_i + u_i − x_j − u_j) (verified), so n_c = −n points from the deck to
                # the seat: −x at seat 1, +x at seat 2 for a straight deck. Its nodes are g₀
                # apart along n (it warns that L > tolerance: harmless, the gap is the
                # geometric one).
                nx, ny = contact_normal(plan.corners[c])
                ct = scene.contact
                ops.element(
                    "zeroLengthContact2D",
                    e,
                    scorners[c],
                    dcorners[c],
                    ct.stiffness,
                    ct.tangential_stiffness,
                    ct.friction,
                    "-normal",
                    nx,
                    ny,
                )
            else:
                spec = gap_mapping(
                    scene, c, dcorners[c], scorners[c], T("material", f"gap {CORNER_NAMES[c]}")
                )
                ops.uniaxialMaterial(spec.material, *spec.args)
                orient = ("-orient", *spec.orient) if spec.orient is not None else ()
                ops.element(
                    "zeroLength",
                    e,
                    spec.i_node,
                    spec.j_node,
                    "-mat",
                    spec.args[0],
                    "-dir",
                    1,
                    *orient,
                )
            gap_eles.append(e)

    # --- damping --------------------------------------------------------------------------
    _a1, (wi, wj) = damping.a1, damping.omega
    dsc = scene.damping
    members = {
        "bents": "bent springs",
        "bents+seats": "bent and seat springs",
        "none": "no springs",
    }[dsc.members]
    factors = rayleigh_factors(scene, damping)
    ops.comment(
        f"Rayleigh: a0 M ({dsc.mass} velocities) + a1 K ({dsc.stiffness} stiffness of "
        f"the {members}, -doRayleigh 1); "
        + (
            f"matched at {wi:.6g} and {wj:.6g} rad/s"
            if dsc.method != "none"
            else "method none: no Rayleigh damping"
        )
    )
    ops.rayleigh(*factors)
    ref_nodes = mass_dampers(ops, scene, damping, deck, seats, acts, supports)
    if sticks:
        ops.region(T("region", "sticks"), "-eleOnly", *sticks, "-rayleigh", 0.0, 0.0, 0.0, 0.0)

    # --- excitation -----------------------------------------------------------------------
    if supports == "motion":
        if motion is None:
            raise ValueError("build_model needs the resampled motion for supports='motion'")
        dt = float(motion.t[1] - motion.t[0])
        ops.comment("multiple-support excitation: imposed displacement and velocity")
        pat = T("pattern", "supports")
        ops.pattern("MultipleSupport", pat)
        channels = plan.channels
        D, V = motion.matrices(channels)
        where = []
        for tn in tables:
            where += [(tn, 1), (tn, 2)]
        where += [(acts[0], 1), (acts[1], 1)]
        # reference nodes of the relative mass damping follow their table's motion
        also: dict[int, list[tuple[int, int]]] = {}
        for k, rn in enumerate(ref_nodes):
            also.setdefault(2 * k, []).append((rn, 1))
            also.setdefault(2 * k + 1, []).append((rn, 2))
        for k, (ch, (node, dof)) in enumerate(zip(channels, where)):
            ts_d = T("timeSeries", f"{ch} disp")
            ops.timeSeries("Path", ts_d, "-dt", dt, ArrayArg(f"{ch}_disp", padded(D[:, k])))
            ts_v = T("timeSeries", f"{ch} vel")
            ops.timeSeries("Path", ts_v, "-dt", dt, ArrayArg(f"{ch}_vel", padded(V[:, k])))
            gm = T("groundMotion", ch)
            ops.groundMotion(gm, "Plain", "-disp", ts_d, "-vel", ts_v)
            ops.imposedMotion(node, dof, gm)
            for rn, rdof in also.get(k, ()):
                ops.imposedMotion(rn, rdof, gm)

    return ModelInfo(
        mode=s.mode,
        deck=deck,
        seats=tuple(seats),
        deck_corners=tuple(dcorners),
        seat_corners=tuple(scorners),
        gap_elements=tuple(gap_eles),
        g0=g0,
        sides=SIDES,
        bent_names=tuple(b.name for b in scene.bents),
        bent_elements=tuple(bent_eles),
        friction=friction,
        normals=tuple(c.normal for c in plan.corners),
        tangents=tuple(c.tangent for c in plan.corners),
        stick_elements=tuple(sticks),
    )


def analysis_commands(scene: Scene) -> list[tuple]:
    """The analysis definition as (command, *args) tuples (re-issued by the substep fallback)."""
    s = scene.opensees
    return [
        ("constraints", "Transformation"),
        ("numberer", "RCM"),
        ("system", s.system),
        ("test", s.test, s.tolerance, s.max_iterations),
        ("algorithm", s.algorithm),
        ("integrator", "Newmark", s.gamma, s.beta),
        ("analysis", "Transient"),
    ]

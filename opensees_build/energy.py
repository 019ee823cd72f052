"""The work–energy balance of the OpenSees model, accumulated over every step.

:class:`EnergyBalance` is the ``on_step`` observer of
:func:`deckpound.opensees_build.engine.run_steps`: called after every converged ``analyze`` (a
step, or each sub-step of a rescued step), it reads the model's own state — zeroLength basic
deformations and forces (``deformationsANDforces``), their Rayleigh forces (``rayleighForces``),
node displacements, velocities and masses — and adds each element's work over the (sub)step by
the trapezoidal rule, W += ½(f_n + f_{n+1})·(d_{n+1} − d_n). At every output step it writes the
energy columns :data:`deckpound.models.columns.ENERGY_COLUMNS` [kJ] with the meanings the
compliance engine gives them (:mod:`deckpound.analytic.compliance.engine`):

* ``energy_input`` — the initial mechanical energy plus the work of the supports,
  −Σ ½(f_n + f_{n+1})·Δu_i over the elements whose node i is a support (bent tables, seat
  actuators, the reference nodes of the relative mass damping): f the element's force on that
  node, material force plus Rayleigh force (u_i = the imposed motion);
* ``energy_kinetic`` — ½ Σ m v² over the nodes with mass (deck centre, seats);
* ``energy_strain`` — recoverable energy of the bents (Hysteretic: f²/(2 k_u), k_u = E_u /
  max(1, μ^β) the Takeda unloading stiffness at the largest committed excursion μ, as
  :func:`deckpound.analytic.kernels.system.spring_stored_energy`), the seat springs (½ f d), the seat
  guides and the deck sticks of stick mode (½ q·v: linear elements, whose trapezoidal work is
  exactly this, so they are read at output steps only);
* ``energy_viscous`` — Rayleigh damping (the elements' α_M M + β K forces as OpenSees computes
  them, and α_M M u̇ on the nodes with mass) and the Viscous dashpots;
* ``energy_hysteretic`` — the bent springs' work minus their recoverable energy;
* ``energy_contact_stored`` — the gap law's potential while closed (ElasticPPGap and
  ViscoelasticGap ½ k g², Hertzdamp k δ^{n+1}/(n+1), ImpactMaterial's unloading path) plus the
  friction stick springs ½ f_t²/k_t;
* ``energy_contact_dissipated`` — contact work − contact stored (stick springs excluded); a
  negative value is energy the contact created;
* ``energy_friction`` — tangential work − stick-spring energy;
* ``energy_error`` — input − all the others.

With Newmark's average acceleration (γ = ½, β = ¼, the default) the trapezoidal work closes
the balance exactly up to the Newton residual: at every step ½(ü_n + ü_{n+1})·M Δu =
Δ(½ u̇ᵀ M u̇) and the equilibrium M ü + f = 0 holds at both ends. The balance is exact for the
linear gap too, also at the steps where it closes or opens: the trapezoidal work there differs
from ½ k g² by the energy the discrete scheme creates or removes, which is what
``energy_contact_dissipated`` then shows.

Three readings of the model need care:

* Committed-tangent Rayleigh (``rayleigh 0 0 0 βKc``): the damping force in the equilibrium at
  the end of a step uses the tangent committed at the previous step, while ``rayleighForces``
  read after the commit uses the new one; the force is then βKc k_c ḋ, with k_c the basic
  stiffness read at the previous commit and ḋ from the node velocities.
* The start (t = 0): elements update their materials only inside ``analyze``
  (``setNodeDisp``/``setNodeVel`` do not), so before the first step deformations come from
  the node displacements and forces from the elastic start the engine allows (k_init d + c ḋ:
  the forces the initial acceleration balances, :mod:`.initial_state`).
* zeroLengthContact2D: after a commit that slid the element reports zero tangential force (it
  moves its stick point to the current slip), while μ p acted during the step. The balance
  keeps the stick point in the deck's frame (s_p = s + f_t/k_t while sticking, s_p := s at a
  sliding commit); a step slid when the reported force is below half the trial force
  −k_t (s − s_p) (sticking, the element reports the trial force itself), and then
  μ p sign(−k_t (s − s_p)) acted.
"""

from __future__ import annotations

import math

import numpy as np

from deckpound.models.columns import ENERGY_COLUMNS
from deckpound.models.contact_params import corner_contacts
from deckpound.models.plan import Plan
from deckpound.models.scene import Scene

from .damping import rayleigh_factors, rayleigh_members
from .gaps import corner_orientation, gap_mapping

__all__ = [
    "EnergyBalance",
    "contact_stored_energy",
    "energy_closure",
    "takeda_constants",
    "takeda_unloading_stiffness",
]

# running work totals W [kJ]
_INPUT, _SPRINGS, _VISCOUS, _CONTACT, _FRICTION = range(5)


def takeda_constants(args) -> tuple[float, float, float, float, float]:
    """(e1p, e1n, E_up, E_un, β) of ``uniaxialMaterial Hysteretic`` from its 13 numbers after the
    tag (2-point backbone, :func:`deckpound.models.plan.takeda_hysteretic_args`): E_u is the
    largest backbone slope, computed as OpenSees does (the 2-point constructor inserts the
    mid-point, ``setEnvelope`` takes the slopes)."""
    s1p, e1p, s3p, e3p, s1n, e1n, s3n, e3n = (float(a) for a in args[:8])
    s2p, e2p = 0.5 * (s1p + s3p), 0.5 * (e1p + e3p)
    s2n, e2n = 0.5 * (s1n + s3n), 0.5 * (e1n + e3n)
    eup = max(s1p / e1p, (s2p - s1p) / (e2p - e1p), (s3p - s2p) / (e3p - e2p))
    eun = max(s1n / e1n, (s2n - s1n) / (e2n - e1n), (s3n - s2n) / (e3n - e2n))
    return e1p, e1n, eup, eun, float(args[12])


def takeda_unloading_stiffness(constants, rot_max: float, rot_min: float, stress: float) -> float:
    """Unloading stiffness E_u / max(1, μ^β) [kN/m] of a Takeda (Hysteretic, damage 0) spring
    with committed excursions rot_max ≥ 0 ≥ rot_min [m] at the committed force ``stress`` [kN]:
    μ = rot_max/e1p when stress ≥ 0, else rot_min/e1n."""
    e1p, e1n, eup, eun, beta = constants
    if stress >= 0.0:
        ratio, e = rot_max / e1p, eup
    else:
        ratio, e = rot_min / e1n, eun
    k = ratio**beta if ratio > 1.0 else 1.0
    return e / max(k, 1.0)


def contact_stored_energy(material: str, args, g: float, lam: float) -> float:
    """Recoverable energy [kJ] of one gap material at gap g [m] (< 0 closed) and normal force
    lam ≥ 0 [kN]; ``material``/``args`` as :func:`.gaps.gap_mapping` gives them (the tag first).
    The same potentials as :func:`deckpound.analytic.kernels.contact_laws.contact_stored_energy`."""
    if not (lam > 0.0 and g < 0.0):
        return 0.0
    k = float(args[1])
    if material in ("ElasticPPGap", "ViscoelasticGap"):
        return 0.5 * k * g * g
    if material == "Hertzdamp":
        n = float(args[4])
        return k * (-g) ** (n + 1.0) / (n + 1.0)
    if material == "ImpactMaterial":
        # unload along K1 from (g, -lam) to the K2 line through the origin, then along it
        k2 = float(args[2])
        gs = min((k * g + lam) / (k - k2), 0.0) if k > k2 else g
        lam_s = -k2 * gs
        return 0.5 * (lam + lam_s) * (gs - g) + 0.5 * k2 * gs * gs
    raise ValueError(f"no stored energy for the gap material {material!r}")


class _Link:
    """A zeroLength element from a support node i (table, actuator, reference node) to a node
    j of the structure, whose work is added every step: its directions' global DOFs (0 x, 1 y,
    2 θ; the model's zeroLength elements other than the gaps keep the default orientation, so
    the basic deformation of direction k is u_j[k] − u_i[k] and the basic force is the global
    force on node j), viscous coefficients c (Viscous materials; 0 for springs), Takeda
    constants per direction (bents), and the state at the last (sub)step: deformations d,
    material forces q, Rayleigh forces r, committed tangents k_c (committed-tangent Rayleigh),
    committed excursions rot_max ≥ 0 ≥ rot_min (Takeda)."""

    __slots__ = (
        "c",
        "d",
        "dashpot",
        "dofs",
        "i",
        "j",
        "k_c",
        "q",
        "r",
        "rayleigh",
        "rot_max",
        "rot_min",
        "tag",
        "takeda",
    )

    def __init__(self, tag, dofs, *, dashpot=False, c=None, rayleigh=False, takeda=None):
        self.tag = tag
        self.dofs = tuple(dofs)
        self.dashpot = dashpot
        self.c = tuple(c) if c is not None else (0.0,) * len(self.dofs)
        self.rayleigh = rayleigh
        self.takeda = takeda
        self.rot_max = [0.0] * len(self.dofs)
        self.rot_min = [0.0] * len(self.dofs)


class EnergyBalance:
    """Work–energy balance of the OpenSees model over every step (module docstring).

    Build it in the open session after the model, the analysis and the initial state
    (``ops``: openseespy or anything with its functions; ``plan``: the plan model it was
    built on; ``info``: the model's :class:`.model.ModelInfo`, with its damping model;
    ``steps``: the step plan of :func:`.engine.step_plan`;
    ``elements``: the session's element name → tag registry,
    :meth:`deckpound.opensees_build.ops.OpsSession.tags`), then pass it as ``on_step`` to
    :func:`.engine.run_steps`; :meth:`columns` gives the energy columns of the output rows
    (steps 0, stride, 2·stride, ...).

    Per step it calls ``nodeDisp`` once per node it needs (deformations are node
    differences), ``eleForce`` once per element (the material forces) and, for an element
    with Rayleigh damping, ``eleDynamicalForce`` (material + Rayleigh forces): the cheapest
    queries openseespy has (``eleResponse`` builds a response object per call).
    """

    def __init__(self, ops, scene: Scene, plan: Plan, info, steps: dict, elements: dict):
        self.stride = int(steps["stride"])
        dm = info.damping
        alpha_m, beta_k, beta_k0, beta_kc = rayleigh_factors(dm)
        ray_bents, ray_seats = rayleigh_members(plan, dm)
        self.alpha_m = alpha_m
        self.beta_kc = beta_kc
        has_beta = beta_k != 0.0 or beta_k0 != 0.0 or beta_kc != 0.0
        self.links = self._spring_links(plan, info, elements, ray_bents, ray_seats, has_beta)
        self.links += [_Link(m.element, m.dofs, dashpot=True, c=m.c) for m in info.mass_dampers]
        links = self.links
        # linear elements read at output steps only: (tag, basic stiffnesses, or None for a
        # beam, whose stored energy is ½ q·v)
        self.linear = [
            (elements[f"seat{j + 1} guide"], _diag(ops, elements[f"seat{j + 1} guide"]))
            for j in range(2)
        ] + [(tag, None) for tag in info.stick_elements]
        mass_nodes = []
        for tag in ops.getNodeTags():
            m = [float(x) for x in ops.nodeMass(tag)]
            if any(m):
                mass_nodes.append((tag, m))
        # contact
        # per corner: zeroLengthContact2D (its contact table has friction), else a gap material
        self.friction = list(info.corner_friction)
        self.gaps = list(info.gap_elements)
        self.g0 = [float(c.gap) for c in plan.corners]
        self.normals = [tuple(c.normal) for c in plan.corners]
        self.tangents = [tuple(c.tangent) for c in plan.corners]
        # each corner's contact table (a joint's own, else the scene's)
        tables = corner_contacts(scene, plan)
        self.kn = [ct.stiffness for ct in tables]
        self.kt = [ct.tangential_stiffness for ct in tables]
        self.mu = [ct.friction for ct in tables]
        self.gap_laws = []
        if self.gaps:
            for corner in plan.corners:
                if self.friction[corner.index]:
                    self.gap_laws.append(None)
                    continue
                orient = corner_orientation(corner)
                axis = (1.0, 0.0) if orient is None else (orient[0], orient[1])
                spec = gap_mapping(scene, corner, 0, 0, 0)
                # (material, its arguments, local x axis, the node order of the element)
                self.gap_laws.append((spec.material, spec.args, axis))
        # every node read per step, once: link ends, nodes with mass, the corners' nodes
        nodes: list[int] = []

        def index(tag: int) -> int:
            if tag not in nodes:
                nodes.append(tag)
            return nodes.index(tag)

        for L in links:
            L.i, L.j = (index(t) for t in ops.eleNodes(L.tag))
        self.mass_nodes = [(index(tag), m) for tag, m in mass_nodes]
        self.corner_nodes = []
        if self.gaps:
            for c, tag in enumerate(self.gaps):
                if self.friction[c]:
                    # zeroLengthContact2D: i = seat point, j = deck corner
                    dk, st = info.deck_corners[c], info.seat_corners[c]
                    self.corner_nodes.append((index(st), index(dk)))
                else:
                    self.corner_nodes.append(tuple(index(t) for t in ops.eleNodes(tag)))
        # the deck sticks of stick mode take the global Rayleigh factors: openseespy 3.7.1
        # ignores ``region -eleOnly ... -rayleigh 0 0 0 0`` for elasticBeamColumn (checked:
        # eleDynamicalForce − eleForce is β K u̇ after that command), so their damping work
        # is added every step; [tag, i, j, Rayleigh forces on both nodes at the last step]
        self.beams = (
            [[tag, *(index(t) for t in ops.eleNodes(tag)), None] for tag in info.stick_elements]
            if has_beta
            else []
        )
        self.nodes = nodes
        self.W = [0.0] * 5
        self.rows: list[list[float]] = []
        self.row_steps: list[int] = []
        self._start(ops)

    @staticmethod
    def _spring_links(plan: Plan, info, elements: dict, ray_bents, ray_seats, has_beta: bool):
        """The bents' and seats' spring and dashpot elements (:func:`.model.define_bents`,
        :func:`.model.define_seat_springs`), from the plan's springs."""
        links: list[_Link] = []
        for k, name in enumerate(plan.bent_names):
            springs = plan.springs[2 * k : 2 * k + 2]  # (x, y)
            takeda = tuple(takeda_constants(s.takeda) for s in springs)
            rayleigh = ray_bents[k] and has_beta
            links.append(_Link(info.bent_elements[k], (0, 1), rayleigh=rayleigh, takeda=takeda))
            dash = [(dof, s.dashpot) for dof, s in enumerate(springs) if s.dashpot > 0.0]
            if dash:
                tag = elements[f"bent {name} dashpot"]
                dofs, c = [d for d, _ in dash], [c for _, c in dash]
                links.append(_Link(tag, dofs, dashpot=True, c=c))
        n_bent = plan.n_bent_springs
        for j in range(2):
            kx, kt = plan.springs[n_bent + 2 * j : n_bent + 2 * j + 2]  # (x, θ)
            rayleigh = ray_seats[j] and has_beta
            links.append(_Link(elements[f"seat{j + 1} spring"], (0, 2), rayleigh=rayleigh))
            c = (kx.dashpot, kt.dashpot)
            links.append(_Link(elements[f"seat{j + 1} dashpot"], (0, 2), dashpot=True, c=c))
        return links

    # -- the state ---------------------------------------------------------------------------

    def _start(self, ops) -> None:
        """State at t = 0 (module docstring: deformations from the nodes, elastic forces)."""
        disp = [ops.nodeDisp(t) for t in self.nodes]
        vel = [ops.nodeVel(t) for t in self.nodes]
        for L in self.links:
            ui, uj, vi, vj = disp[L.i], disp[L.j], vel[L.i], vel[L.j]
            k_init = _diag(ops, L.tag)
            L.k_c = k_init
            L.d = [uj[dof] - ui[dof] for dof in L.dofs]
            rate = [vj[dof] - vi[dof] for dof in L.dofs]
            L.q = [k * x + c * v for k, x, c, v in zip(k_init, L.d, L.c, rate)]
            L.r = self._rayleigh(ops, L, vi, vj) if L.rayleigh else [0.0] * len(L.dofs)
        self.disp = disp
        self.vel_mass = [vel[k] for k, _ in self.mass_nodes]
        for beam in self.beams:
            beam[3] = _beam_rayleigh(ops, beam[0])
        nc = len(self.g0)
        self.stick = [0.0] * nc  # contact2d stick points s_p [m]
        self.ft_acting = [0.0] * nc  # the tangential forces that acted at the last (sub)step
        if self.gaps:
            # zeroLengthContact2D: (g, s, fn, ft), computed from the nodes when asked; a gap
            # material: (strain, stress), open at the start (the engine refuses an initial
            # state that closes a gap), so the force is zero
            self.contact_state = [
                self._contact2d(ops, c, disp)
                if self.friction[c]
                else (self._gap_strain(c, disp), 0.0)
                for c in range(nc)
            ]
        ke, es, e_lin, ec, _ = self._stored(ops)
        W = self.W
        W[_INPUT] = ke + es + ec
        W[_SPRINGS] = es - e_lin
        W[_CONTACT] = ec
        self._snapshot(ops, 0)

    def _gap_strain(self, c: int, disp) -> float:
        """Strain a·(u_j − u_i) of corner c's gap material (a its local x) [m]."""
        i, j = self.corner_nodes[c]
        ax, ay = self.gap_laws[c][2]
        ui, uj = disp[i], disp[j]
        return ax * (uj[0] - ui[0]) + ay * (uj[1] - ui[1])

    def _contact2d(self, ops, c: int, disp):
        """(g, s, fn, ft) of a zeroLengthContact2D corner: gap and tangential slip of the deck
        corner relative to the seat point along the plan's n and t [m], normal force
        (compression > 0) and tangential force on the deck along t as the element reports
        them [kN] (as :func:`.engine.contact_forces`)."""
        i, j = self.corner_nodes[c]
        ud, us = disp[j], disp[i]
        rx, ry = ud[0] - us[0], ud[1] - us[1]
        nx, ny = self.normals[c]
        tx, ty = self.tangents[c]
        f = ops.eleForce(self.gaps[c])
        return (
            self.g0[c] + nx * rx + ny * ry,
            tx * rx + ty * ry,
            -(nx * f[3] + ny * f[4]),
            -(tx * f[3] + ty * f[4]),
        )

    def _rayleigh(self, ops, L: _Link, vi, vj) -> list[float]:
        """Rayleigh force of each direction in the equilibrium of the current state [kN]."""
        if self.beta_kc != 0.0:
            return [self.beta_kc * k * (vj[dof] - vi[dof]) for k, dof in zip(L.k_c, L.dofs)]
        rf = ops.eleResponse(L.tag, "rayleighForces")
        return [rf[3 + dof] for dof in L.dofs]

    # -- the step ----------------------------------------------------------------------------

    def __call__(self, ops, n: int) -> None:
        """Add the work of the (sub)step just converged (a sub-step of step n, or step n).

        Written for speed (it runs at every step of the Python loop): sums of f_n + f_{n+1},
        halved once."""
        W = self.W
        disp = [ops.nodeDisp(t) for t in self.nodes]
        old = self.disp
        kc_mode = self.beta_kc != 0.0
        if kc_mode:
            vel = [ops.nodeVel(t) for t in self.nodes]
        w_springs = w_visc = w_in = 0.0
        for L in self.links:
            ui, uj, oi = disp[L.i], disp[L.j], old[L.i]
            dofs = L.dofs
            d = [uj[k] - ui[k] for k in dofs]
            work = inp = 0.0
            if L.rayleigh:
                if kc_mode:
                    p = ops.eleForce(L.tag)
                    r = self._rayleigh(ops, L, vel[L.i], vel[L.j])
                    L.k_c = _diag(ops, L.tag)
                else:
                    p = ops.eleForce(L.tag)
                    t = ops.eleDynamicalForce(L.tag)
                    r = [t[3 + k] - p[3 + k] for k in dofs]
                q = [p[3 + k] for k in dofs]
                for dof, x0, x1, f0, f1, g0, g1 in zip(dofs, L.d, d, L.q, q, L.r, r):
                    dx = x1 - x0
                    f = f0 + f1
                    fr = g0 + g1
                    work += f * dx
                    w_visc += fr * dx
                    inp += (f + fr) * (ui[dof] - oi[dof])
                L.r = r
            else:
                p = ops.eleForce(L.tag)
                q = [p[3 + k] for k in dofs]
                for dof, x0, x1, f0, f1 in zip(dofs, L.d, d, L.q, q):
                    f = f0 + f1
                    work += f * (x1 - x0)
                    inp += f * (ui[dof] - oi[dof])
            if L.dashpot:
                w_visc += work
            else:
                w_springs += work
            w_in -= inp
            if L.takeda is not None:
                L.rot_max = [a if a >= x else x for a, x in zip(L.rot_max, d)]
                L.rot_min = [a if a <= x else x for a, x in zip(L.rot_min, d)]
            L.d, L.q = d, q
        if self.alpha_m != 0.0:
            work = 0.0
            vel_mass = []
            for (k, mass), v0 in zip(self.mass_nodes, self.vel_mass):
                v1 = ops.nodeVel(self.nodes[k])
                for mk, a0, a1, b0, b1 in zip(mass, old[k], disp[k], v0, v1):
                    work += mk * (b0 + b1) * (a1 - a0)
                vel_mass.append(v1)
            w_visc += self.alpha_m * work
            self.vel_mass = vel_mass
        for beam in self.beams:
            tag, i, j, r0 = beam
            r1 = beam[3] = _beam_rayleigh(ops, tag)
            du = [a - b for a, b in zip(disp[i], old[i])] + [a - b for a, b in zip(disp[j], old[j])]
            w_visc += sum((a + b) * x for a, b, x in zip(r0, r1, du))
        W[_INPUT] += 0.5 * w_in
        W[_SPRINGS] += 0.5 * w_springs
        W[_VISCOUS] += 0.5 * w_visc
        if self.gaps:
            self._contact2d_step(ops, disp)
        if self.gaps and not all(self.friction):
            work = 0.0
            state = self.contact_state
            for c, tag in enumerate(self.gaps):
                if self.friction[c]:
                    continue
                e0, s0 = state[c]
                e1 = self._gap_strain(c, disp)
                p = ops.eleForce(tag)
                ax, ay = self.gap_laws[c][2]
                s1 = ax * p[3] + ay * p[4]
                work += (s0 + s1) * (e1 - e0)
                state[c] = (e1, s1)
            W[_CONTACT] += 0.5 * work
        self.disp = disp
        if n % self.stride == 0:
            self._snapshot(ops, n)

    def _contact2d_step(self, ops, disp) -> None:
        W = self.W
        for c in range(len(self.gaps)):
            if not self.friction[c]:
                continue
            g0, s0, fn0, _ = self.contact_state[c]
            g1, s1, fn1, ft_rep = self.contact_state[c] = self._contact2d(ops, c, disp)
            if fn1 > 0.0:
                trial = -self.kt[c] * (s1 - self.stick[c])
                if 2.0 * abs(ft_rep) < abs(trial):
                    # slid: the element moved its stick point to s and reports 0 (up to the
                    # round-off of projecting its force on t), while μ p acted in the step
                    ft = math.copysign(self.mu[c] * fn1, trial)
                    self.stick[c] = s1
                else:  # stuck: the element reports the force that acted, −k_t (s − s_p)
                    ft = ft_rep
                    self.stick[c] = s1 + ft_rep / self.kt[c]
            else:
                ft = 0.0
            W[_CONTACT] -= 0.5 * (fn0 + fn1) * (g1 - g0)
            W[_FRICTION] -= 0.5 * (self.ft_acting[c] + ft) * (s1 - s0)
            self.ft_acting[c] = ft

    # -- output ------------------------------------------------------------------------------

    def _stored(self, ops):
        """(kinetic, recoverable of springs and linear elements, of the linear elements alone,
        contact stored, stick-spring part of it) [kJ] at the current state."""
        ke = 0.0
        for k, mass in self.mass_nodes:
            v = ops.nodeVel(self.nodes[k])
            ke += 0.5 * (mass[0] * v[0] * v[0] + mass[1] * v[1] * v[1] + mass[2] * v[2] * v[2])
        es = 0.0
        for L in self.links:
            if L.dashpot:
                continue
            for k, (s, x) in enumerate(zip(L.q, L.d)):
                if L.takeda is not None:
                    ku = takeda_unloading_stiffness(L.takeda[k], L.rot_max[k], L.rot_min[k], s)
                    es += 0.5 * s * s / ku
                else:
                    es += 0.5 * s * x
        e_lin = 0.0
        for tag, stiffness in self.linear:
            v = ops.eleResponse(tag, "basicDeformation")
            if stiffness is not None:
                e_lin += 0.5 * sum(k * x * x for k, x in zip(stiffness, v))
            else:
                q = ops.eleResponse(tag, "basicForce")
                e_lin += 0.5 * sum(a * b for a, b in zip(q, v))
        es += e_lin
        ec = 0.0
        efs = 0.0
        for c, state in enumerate(self.contact_state if self.gaps else ()):
            if self.friction[c]:
                g, _, fn, ft_rep = state
                if fn > 0.0 and g < 0.0:
                    ec += 0.5 * self.kn[c] * g * g
                if ft_rep != 0.0:
                    efs += 0.5 * ft_rep * ft_rep / self.kt[c]
            else:
                strain, stress = state
                material, args, _ = self.gap_laws[c]
                ec += contact_stored_energy(material, args, self.g0[c] + strain, -stress)
        ec += efs
        return ke, es, e_lin, ec, efs

    def _snapshot(self, ops, n: int) -> None:
        ke, es, e_lin, ec, efs = self._stored(ops)
        w_in, w_springs, w_visc, w_contact, w_fric = self.W
        springs = w_springs + e_lin
        row = [
            w_in,
            ke,
            es,
            w_visc,
            springs - es,
            ec,
            w_contact - (ec - efs),
            w_fric - efs,
            w_in - (ke + springs + w_visc + w_contact + w_fric),
        ]
        if self.row_steps and self.row_steps[-1] == n:  # a later sub-step of the same step
            self.rows[-1] = row
        else:
            self.rows.append(row)
            self.row_steps.append(n)

    def columns(self, n_rows: int) -> dict[str, np.ndarray]:
        """The energy columns [kJ] of the first ``n_rows`` output rows (those the run kept)."""
        arr = np.array(self.rows[:n_rows], dtype=float).reshape(-1, len(ENERGY_COLUMNS))
        return {name: arr[:, k].copy() for k, name in enumerate(ENERGY_COLUMNS)}


def _beam_rayleigh(ops, tag) -> list[float]:
    """Rayleigh forces of a beam on its two nodes (global, 6 values) [kN, kN·m]: its dynamic
    force minus its resisting force (the sticks are massless)."""
    return [a - b for a, b in zip(ops.eleDynamicalForce(tag), ops.eleForce(tag))]


def _diag(ops, tag) -> list[float]:
    """The diagonal of a zeroLength element's basic stiffness (one entry per direction)."""
    m = ops.eleResponse(tag, "basicStiffness")
    n = math.isqrt(len(m))
    return [float(m[k * n + k]) for k in range(n)]


def energy_closure(columns: dict) -> float:
    """max |energy_error| / max |energy_input| of a result's columns (0 without input), as the
    compliance engine's ``meta["energy_closure"]``."""
    err, ein = columns.get("energy_error"), columns.get("energy_input")
    if err is None or ein is None or not len(ein):
        return 0.0
    ref = float(np.max(np.abs(ein)))
    return float(np.max(np.abs(err))) / ref if ref > 0.0 else 0.0

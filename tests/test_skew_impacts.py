r"""Skewed-deck impacts against closed forms (issue 15, item 3), posed from scene overrides.

Setting (every case): the benchmark deck (L = 33.5 m, W = 2.4 m, m = 140.5 t, I = 13,090 t·m²)
with skew φ, in free flight — bents of 1e-9 kN/m (never yielding), ``damping.ratio = 0`` — and
seats of mass and inertia 1e12 (t, t·m²) without dashpots: fixed abutments to 1e-12. Linear
(small-rotation) kinematics, so the contact rows are the rest ones. The deck starts at rest
position with ``initial.deck_velocity = (v_x, v_y, ω)`` towards seat 1 (the left face).

Impulse–momentum equations (the derivation the tests evaluate)
--------------------------------------------------------------
DOFs u = [x₁, θ₁, x₂, θ₂, x_d, y_d, θ_d], M = diag(m_s, I_s, m_s, I_s, m, m, I). A left corner
at ρ = (x_c, y_c) = (−L/2 + y_c tan φ, y_c) with gap-opening normal n = (cos φ, −sin φ) and face
tangent t = (sin φ, cos φ) meets the seat point at lever r = (y_c tan φ, y_c) from the seat's
pivot. The corner moves with (v_x − y_c ω, v_y + x_c ω), the seat point with
(ẋ₁ − r_y θ̇₁, r_x θ̇₁), so the normal and tangential relative velocities are U_N = w_N·u̇,
U_T = w_T·u̇ with

    w_N = [−n_x, n_x r_y − n_y r_x, 0, 0, n_x, n_y, a],      a = −n_x y_c + n_y x_c,
    w_T = [−t_x, 0,                 0, 0, t_x, t_y, b],      b = −t_x y_c + t_y x_c

(t·(−r_y, r_x) = 0: r lies along the face). An impact transmits the impulses P_N (normal,
compression > 0) and P_T (along t, on the deck): M Δu̇ = w_Nᵀ P_N + w_Tᵀ P_T, hence
U⁺ = U⁻ + G P with the Delassus matrix G = W M⁻¹ Wᵀ, W = [w_N; w_T]. The seat entries of G are
~1e-12 of the deck's (G → the free-parallelogram values 1/m + a²/I … as m_s, I_s → ∞).

Single-corner oblique impact (Newton's law on U_N, Coulomb on P_T, stick candidate first):

* stick: U_N⁺ = −e U_N⁻ and U_T⁺ = 0, i.e. G [P_N, P_T]ᵀ = [−(1+e) U_N⁻, −U_T⁻]ᵀ; accepted
  when |P_T| ≤ μ P_N;
* slide otherwise: P_T = s μ P_N with s = sign of the stick candidate's P_T, and
  U_N⁺ = −e U_N⁻ gives P_N = −(1+e) U_N⁻ / (G_NN + s μ G_NT); the slip then opposes the
  friction impulse, s U_T⁺ ≤ 0 (checked).

Face impact of a translating deck (u̇ = (−V, 0, 0) on the deck): both corners of the face close
together (the faces are parallel). Frictionless, the normal impulses solve the two-contact
LCP 0 ≤ P ⊥ G P + (1+e) U⁻ ≥ 0 (enumerated here). For the deck alone G = 11ᵀ/m + a aᵀ/I
with the levers a₁ = (W/2)/cos φ + (L/2) sin φ (acute corner c1) and
a₂ = −(W/2)/cos φ + (L/2) sin φ (obtuse corner c2): the face's normal line misses the deck
centre by (L/2) sin φ. When a₂ > 0 (sin φ cos φ > W/L, φ > 4.1° here) every
impulse on the face turns the deck counter-clockwise, the zero-rotation rebound is impossible
and the LCP puts the whole impulse on the obtuse corner c2:
P₂ = (1+e) V cos φ / (1/m + a₂²/I), ω⁺ = a₂ P₂ / I > 0. Below that skew both corners carry
impulse and the deck rebounds without rotating.

The penalty engines see a different idealisation of the same simultaneous impact: two equal
linear springs. Their answer does not depend on k (time scales as 1/√k and nothing else acts on
the free deck) and is the piecewise-linear solution :func:`compliant_face_impact` (both springs,
then c2 alone once c1 unloads). It differs from Newton's corner law by a few per cent — the
known non-uniqueness of multiple impacts — and has the same sign.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import eigh
from scipy.optimize import brentq

from deckpound.compare.engines import run_engine
from deckpound.models.scene_io import load_scene

L, W, M_D, I_D = 33.5, 2.4, 140.5, 13090.0
M_S = I_S = 1e12
MASS = np.diag([M_S, I_S, M_S, I_S, M_D, M_D, I_D])


def free_deck(
    phi,
    velocity,
    *,
    e,
    mu=0.0,
    gap=0.05,
    k=1e7,
    law="linear",
    duration=0.05,
    output_dt=1e-3,
    step=None,
    engine="nonsmooth",
):
    """The free-flight scene of the module docstring, from ``--set`` style overrides."""
    ov = [
        f"deck.skew={phi!r}",
        "damping.ratio=0.0",
        f"contact.friction={mu!r}",
        f"contact.friction_mode={'stick' if mu > 0 else 'none'}",
        f"initial.deck_velocity=[{velocity[0]!r}, {velocity[1]!r}, {velocity[2]!r}]",
        f"run.duration={duration!r}",
        f"run.output_dt={output_dt!r}",
        "excitation.kind=pulse",
        "excitation.pga=1e-9",
    ]
    for i in range(3):
        for d in ("x", "y"):
            ov += [f"bents[{i}].{d}.stiffness=1e-9", f"bents[{i}].{d}.ultimate_displacement=1e12"]
    for j in range(2):
        ov += [
            f"seats[{j}].mass={M_S!r}",
            f"seats[{j}].inertia={I_S!r}",
            f"seats[{j}].cx=0.0",
            f"seats[{j}].ctheta=0.0",
            f"seats[{j}].gap={gap!r}",
        ]
    # each engine gets the options it reads (an unused one warns): Newton's e, or the penalty law
    if engine == "nonsmooth" or law != "linear":
        ov.append(f"contact.restitution={e!r}")
    if engine != "nonsmooth":
        ov += [f"contact.law={law}", f"contact.stiffness={k!r}"]
    if step is not None:
        ov.append(
            {
                "nonsmooth": f"nonsmooth.h={step!r}",
                "compliance": f"compliance.dt={step!r}",
                "opensees": f"opensees.dt={step!r}",
            }[engine]
        )
    return load_scene("saiidi-4span", ov)


def left_rows(phi: float, yc: float) -> tuple[np.ndarray, np.ndarray]:
    """(w_N, w_T) of the left corner at y_c (module docstring), independent of the plan."""
    n = (math.cos(phi), -math.sin(phi))
    t = (math.sin(phi), math.cos(phi))
    xc = -L / 2 + yc * math.tan(phi)
    rx, ry = yc * math.tan(phi), yc
    wn = np.array([-n[0], n[0] * ry - n[1] * rx, 0, 0, n[0], n[1], -n[0] * yc + n[1] * xc])
    wt = np.array([-t[0], 0, 0, 0, t[0], t[1], -t[0] * yc + t[1] * xc])
    return wn, wt


def deck_velocity(v) -> np.ndarray:
    u = np.zeros(7)
    u[4:] = v
    return u


def single_corner_impact(phi, v, e, mu):
    """Closed form of the module docstring for corner c1: (mode, P_N, P_T, deck v⁺)."""
    wn, wt = left_rows(phi, -W / 2)
    Wm = np.array([wn, wt])
    G = Wm @ np.linalg.solve(MASS, Wm.T)
    u = deck_velocity(v)
    un, ut = wn @ u, wt @ u
    pn, pt = np.linalg.solve(G, [-(1 + e) * un, -ut])
    mode = "stick"
    if abs(pt) > mu * pn:
        s = math.copysign(1.0, pt)
        pn = -(1 + e) * un / (G[0, 0] + s * mu * G[0, 1])
        pt = s * mu * pn
        mode = "slide"
        assert s * (ut + G[1, 0] * pn + G[1, 1] * pt) <= 0.0  # slip opposes friction
    up = u + np.linalg.solve(MASS, wn * pn + wt * pt)
    return mode, pn, pt, up[4:]


def face_impact_newton(phi, V, e):
    """Frictionless two-corner LCP by enumeration: (P₁, P₂, deck v⁺)."""
    rows = np.array([left_rows(phi, -W / 2)[0], left_rows(phi, W / 2)[0]])
    G = rows @ np.linalg.solve(MASS, rows.T)
    u = deck_velocity((-V, 0.0, 0.0))
    q = (1 + e) * (rows @ u)
    found = []
    for active in ((0, 1), (0,), (1,), ()):
        P = np.zeros(2)
        if active:
            idx = list(active)
            P[idx] = np.linalg.solve(G[np.ix_(idx, idx)], -q[idx])
        w = G @ P + q
        if np.all(P >= -1e-12) and np.all(w >= -1e-12):
            found.append(P)
    assert len(found) == 1, found
    P = found[0]
    return P[0], P[1], (u + np.linalg.solve(MASS, rows.T @ P))[4:]


def compliant_face_impact(phi, V):
    """Two equal linear springs at c1, c2 on the free deck (fixed abutment): the deck's
    velocity after the springs release, by phases of the piecewise-linear system
    M q̈ + k Σ_active w_c w_cᵀ q = 0 (modal solution; switch when an active spring unloads).
    k drops out (it only scales time), so k = 1 here."""
    m3 = np.diag([M_D, M_D, I_D])
    rows = np.array([left_rows(phi, -W / 2)[0][4:], left_rows(phi, W / 2)[0][4:]])
    q, v = np.zeros(3), np.array([-V, 0.0, 0.0])
    active = [0, 1]
    while active:
        K = sum(np.outer(rows[c], rows[c]) for c in active)
        lam, phis = eigh(K, m3)
        a, b = phis.T @ m3 @ q, phis.T @ m3 @ v
        osc = lam > 1e-9 * lam.max()  # the rest are free (rigid) modes
        w = np.where(osc, np.sqrt(np.abs(lam)), 0.0)

        def state(t, a=a, b=b, w=w, phis=phis, osc=osc):
            c = np.where(osc, np.cos(w * t), 1.0)
            s = np.where(osc, np.sin(w * t) / np.where(osc, w, 1.0), t)
            sd = np.where(osc, np.cos(w * t), 1.0)
            cd = np.where(osc, -w * np.sin(w * t), 0.0)
            return phis @ (a * c + b * s), phis @ (a * cd + b * sd)

        period = 2 * math.pi / w[osc].min()
        ts = np.linspace(0.0, period, 40001)[1:]
        gaps = np.array([[rows[c] @ state(t)[0] for c in active] for t in ts])
        ends = [
            (np.argmax(gaps[:, i] > 0), i) for i in range(len(active)) if np.any(gaps[:, i] > 0)
        ]
        j, i = min(ends)
        assert j > 0  # compressed at the first sample: the spring unloads later
        t1 = brentq(lambda t, c=active[i]: rows[c] @ state(t)[0], ts[j - 1], ts[j], xtol=1e-16)
        q, v = state(t1)
        active.pop(i)
    assert np.all(rows @ v >= 0.0)  # both corners separate: no second contact
    return v


# -- nonsmooth engine: closed forms to round-off ------------------------------------------------

SINGLE = {
    "stick": ((-0.5, 0.0, -0.02), 0.6, 0.9),
    "slide": ((-0.5, 0.3, -0.02), 0.6, 0.2),
    "slide back": ((-0.5, -0.3, -0.02), 0.3, 0.2),
}


def _first_impact_row(r, corner):
    hit = np.flatnonzero(r[f"pn_c{corner}"] > 0.0)
    assert len(hit), "no impact"
    return int(hit[0])


@pytest.mark.filterwarnings("ignore:.*set-valued Coulomb friction")  # the engine's own note
@pytest.mark.parametrize("phi_deg", [30.0, 45.0])
@pytest.mark.parametrize("case", sorted(SINGLE))
def test_nonsmooth_single_corner_oblique_impact(case, phi_deg):
    v, e, mu = SINGLE[case]
    phi = math.radians(phi_deg)
    mode, pn, pt, vp = single_corner_impact(phi, v, e, mu)
    assert mode == case.split()[0]
    h, gap = 1e-4, 0.05
    t_hit = float(gap / -(left_rows(phi, -W / 2)[0] @ deck_velocity(v)))
    sc = free_deck(phi_deg, v, e=e, mu=mu, gap=gap, duration=t_hit + 0.005, output_dt=h, step=h)
    r = run_engine("nonsmooth", sc)
    assert r.ok, r.meta["message"]
    k = _first_impact_row(r, 1)
    # c1 alone strikes; nothing else touches for a few steps after (the others stay open)
    end = min(k + 20, len(r.t) - 1)
    for c in (2, 3, 4):
        assert np.all(r[f"pn_c{c}"][: end + 1] == 0.0)
    assert np.all(r["pn_c1"][k + 1 : end + 1] == 0.0)
    got = np.array([r["deck_vx_abs"][k], r["deck_vy_abs"][k], r["deck_omega"][k]])
    err = np.max(np.abs(got - vp)) / np.max(np.abs(v))
    state = int(r["state_c1"][k])
    print(
        f"{case} phi = {phi_deg}: P_N = {pn:.6f} kN s, P_T = {pt:.6f} kN s, v+ = {vp}, "
        f"relative error {err:.2e}, state {state}"
    )
    assert err <= 1e-10
    assert r["pn_c1"][k] == pytest.approx(pn, rel=1e-10)
    assert r["pt_c1"][k] == pytest.approx(pt, rel=1e-10)
    assert state == (1 if mode == "stick" else 2)


@pytest.mark.parametrize("phi_deg", [3.0, 30.0, 45.0])
def test_nonsmooth_translating_deck_face_impact_rotation(phi_deg):
    V, e = 0.5, 0.6
    phi = math.radians(phi_deg)
    p1, p2, vp = face_impact_newton(phi, V, e)
    a2 = -(W / 2) / math.cos(phi) + (L / 2) * math.sin(phi)
    h = 1e-4
    t_hit = 0.05 / (V * math.cos(phi))
    r = run_engine(
        "nonsmooth",
        free_deck(phi_deg, (-V, 0.0, 0.0), e=e, duration=t_hit + 0.005, output_dt=h, step=h),
    )
    assert r.ok, r.meta["message"]
    k = _first_impact_row(r, 2)
    got = np.array([r["deck_vx_abs"][k], r["deck_vy_abs"][k], r["deck_omega"][k]])
    print(
        f"phi = {phi_deg}: P1 = {p1:.6g}, P2 = {p2:.6g} kN s, omega+ = {vp[2]:.12g} rad/s, "
        f"engine {got[2]:.12g}"
    )
    assert np.max(np.abs(got - vp)) <= 1e-10 * V
    if a2 > 0:  # rotation: the obtuse corner c2 takes the whole impulse, ω⁺ = a₂ P₂ / I > 0
        assert p1 == 0.0 and r["pn_c1"][k] == 0.0
        assert vp[2] == pytest.approx(a2 * p2 / I_D, rel=1e-9) and vp[2] > 0.0
        assert r["deck_omega"][-1] > 0.0
    else:  # below the critical skew: both corners, no rotation (the 1e12 seats' own
        # compliance leaves ~1e-10 rad/s, against ~0.04 rad/s at 30°)
        assert p1 > 0 and p2 > 0 and abs(vp[2]) <= 1e-9
        assert r["pn_c1"][k] > 0.0


# -- penalty engines: sign and size, and the trend in k --------------------------------------

PENALTY = ("compliance", "opensees")


@pytest.mark.parametrize("phi_deg", [30.0, 45.0])
@pytest.mark.parametrize("engine", PENALTY)
def test_penalty_face_impact_rotation_and_stiffness_trend(engine, phi_deg):
    """ω⁺ for k = 1e6, 1e7, 1e8 kN/m (step = contact period / 400): the same value for every
    k — the compliant two-spring closed form — with the sign of Newton's corner law and a size
    within a few per cent of it (the two idealisations of a simultaneous face impact)."""
    V = 0.5
    phi = math.radians(phi_deg)
    newton = face_impact_newton(phi, V, 1.0)[2][2]
    compliant = compliant_face_impact(phi, V)[2]
    rows = []
    gap = 0.02
    a2 = (L / 2) * math.sin(phi) - (W / 2) / math.cos(phi)
    m_eff = 1.0 / (1.0 / M_D + a2**2 / I_D)  # what c2 alone sees
    t0 = gap / (V * math.cos(phi))  # contact starts
    for k in (1e6, 1e7, 1e8):
        tc = math.pi * math.sqrt(m_eff / k)  # half period of one corner's spring
        dt = tc / 400
        sc = free_deck(
            phi_deg,
            (-V, 0.0, 0.0),
            e=1.0,
            k=k,
            gap=gap,
            duration=t0 + 4 * tc + 0.01,
            output_dt=10 * dt,
            step=dt,
            engine=engine,
        )
        r = run_engine(engine, sc)
        assert r.ok, r.meta["message"]
        # the first output row after both corners have released (before any seat-2 contact)
        f = r["fn_c1"] + r["fn_c2"]
        hit = np.flatnonzero(f > 0.0)
        after = np.flatnonzero((np.arange(len(f)) > hit[0]) & (f == 0.0))
        assert len(hit) and len(after) and np.all(r["fn_c3"][: after[0] + 1] == 0.0)
        rows.append((k, r["deck_omega"][after[0]]))
    print(
        f"\n{engine} phi = {phi_deg}: Newton corner law {newton:.6f}, compliant limit "
        f"{compliant:.6f} rad/s ({compliant / newton - 1:+.2%})"
    )
    for k, om in rows:
        print(
            f"  k = {k:.0e}: omega+ = {om:.6f} ({om / compliant - 1:+.2e} vs compliant, "
            f"{om / newton - 1:+.2%} vs Newton)"
        )
    for _, om in rows:
        assert om > 0.0 and newton > 0.0  # the sign
        assert om == pytest.approx(compliant, rel=2e-3)  # the compliant closed form
        assert om == pytest.approx(newton, rel=0.05)  # and Newton's within 5 %


def test_compliant_closed_form_matches_a_direct_integration():
    """The piecewise modal solution against DOP853 on the same two unilateral springs."""
    from scipy.integrate import solve_ivp

    phi = math.radians(30.0)
    rows = np.array([left_rows(phi, -W / 2)[0][4:], left_rows(phi, W / 2)[0][4:]])
    m3 = np.array([M_D, M_D, I_D])

    def f(t, y):
        g = rows @ y[:3]
        force = rows.T @ np.where(g < 0, -1e6 * g, 0.0)
        return np.concatenate([y[3:], force / m3])

    sol = solve_ivp(
        f, (0, 0.3), [0, 0, 0, -0.5, 0, 0], method="DOP853", rtol=1e-12, atol=1e-15, max_step=1e-4
    )
    assert sol.y[5, -1] == pytest.approx(compliant_face_impact(phi, 0.5)[2], rel=1e-8)


# -- energy ------------------------------------------------------------------------------------


@pytest.mark.parametrize("engine", ("nonsmooth", "compliance", "opensees"))
def test_frictionless_elastic_skew_impact_gains_no_energy(engine):
    """φ = 30°, e = 1, pure −x velocity: the kinetic energy after the impact does not exceed
    the energy before (tolerances of ``tests/test_engine_contract.py``: θ = ½ with Newton's law
    conserves it exactly, a penalty contact switches on inside a step, O(dt) of either sign)."""
    V = 0.5
    dt = 1e-4 if engine == "nonsmooth" else 1e-5
    r = run_engine(
        engine,
        free_deck(
            30.0,
            (-V, 0.0, 0.0),
            e=1.0,
            k=1e7,
            gap=0.01,
            duration=0.1,
            output_dt=1e-3,
            step=dt,
            engine=engine,
        ),
    )
    assert r.ok, r.meta["message"]
    assert np.max(r["fn_c2"]) > 0.0
    ke0 = 0.5 * M_D * V**2
    ke = (
        0.5 * M_D * (r["deck_vx_abs"] ** 2 + r["deck_vy_abs"] ** 2)
        + 0.5 * I_D * r["deck_omega"] ** 2
    )
    open_rows = np.all(np.column_stack([r[f"gap_c{c}"] for c in range(1, 5)]) > 0.0, axis=1)
    ke1 = ke[open_rows & (r.t > 0.03)]
    print(f"{engine}: kinetic energy after/before {ke1.max() / ke0:.12f}")
    assert len(ke1) and ke1.max() <= ke0 * (1 + (1e-9 if engine == "nonsmooth" else 1e-5))
    assert ke1.min() >= ke0 * (1 - 1e-3)

"""One test body over the engine registry (issue 11): every registered engine, the same checks.

* the contract: standard columns in order with units, statistics with one meaning, t = 0 first;
* a contact-free oracle: elastic bridge under smooth analytic support motion against an
  independent DOP853 solution of the same ODE; the observed order of convergence from two
  step sizes is 2 (Newmark average acceleration; Moreau–Jean θ = ½ is the trapezoidal rule);
* a frictionless symmetric impact of the deck face on a (near-)rigid seat rebounds at −e·v and
  starts no rotation: Newton's law with e = 0.6 for the nonsmooth engine, the elastic gap
  (e = 1) for the penalty engines — a Kelvin–Voigt dashpot is calibrated to e for the mass one
  corner sees alone (the benchmark's 138 t), while in a face impact each corner carries half
  the deck, so its restitution there is lower (0.48 for e = 0.6: a property of the law's
  calibration, checked on single-corner impacts in ``test_compliance_contact.py``);
* an elastic impact gains no energy beyond the discretisation error of the contact switch.

A fourth engine (``tests/_extra_engine.py``, plain numpy) is registered with one line and
passes the contract and the contact-free oracle unchanged: a new engine needs its module and a
registry entry, nothing else.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from _compliance_helpers import (
    base_scene,
    motion_from,
    with_bents,
    with_contact,
    with_run,
    with_seats,
)
from scipy.integrate import solve_ivp

from deckpound.compare.engines import engine_names, get_engine, register, run_engine, unregister
from deckpound.models.columns import standard_columns
from deckpound.models.damping import damping_model
from deckpound.models.engine_contract import OptionIgnored
from deckpound.models.errors import SceneError
from deckpound.models.plan import plan_of

BUILT_IN = engine_names()
EXTRA = "linear-newmark"


@pytest.fixture(scope="module", autouse=True)
def extra_engine():
    register(EXTRA, "_extra_engine:LinearNewmarkEngine")  # the one registry line
    yield
    unregister(EXTRA)


def with_step(engine: str, scene, dt: float):
    """The engine's settings with its time step set to dt (read from the engine's declaration)."""
    e = get_engine(engine)
    s = e.settings_of(scene)
    return dataclasses.replace(s, **{e.step_field: dt})


# -- the contract ---------------------------------------------------------------------------


@pytest.mark.parametrize("engine", BUILT_IN + (EXTRA,))
def test_contract(engine):
    sc = with_run(base_scene(), duration=0.3)
    r = run_engine(engine, sc)
    std = standard_columns([b.name for b in sc.bents])
    assert list(r.columns)[: len(std)] == std
    assert r.t[0] == 0.0 and np.allclose(np.diff(r.t), sc.run.output_dt)
    assert r.meta["status"] == "success" and r.meta["failure"] is None
    for key in (
        "steps",
        "newton_iterations",
        "contact_solves",
        "gap_closures",
        "wall_time",
        "compile_time",
        "scene_hash",
        "physics_hash",
        "settings_hash",
        "settings",
        "version",
        "warnings",
        "units",
    ):
        assert key in r.meta, key
    assert r.meta["units"]["deck_theta"] == "rad" and r.meta["units"]["deck_vx_abs"] == "m/s"
    assert r.meta["units"]["bent1_dx"] == "m" and r.meta["units"]["fn_c1"] == "kN"
    for v in r.columns.values():
        assert np.all(np.isfinite(v))
    with pytest.raises(ValueError):
        r.columns["t"][0] = 1.0  # frozen
    frame = r.to_frame()
    assert frame.index.name == "t" and frame.attrs["units"]["deck_x_abs"] == "m"
    ds = r.to_xarray()
    assert ds["gap"].dims == ("time", "corner") and ds["bent_force"].dims == (
        "time",
        "bent",
        "direction",
    )


def test_unknown_engine_lists_the_valid_ones():
    with pytest.raises(SceneError, match="valid engines: opensees, compliance, nonsmooth"):
        get_engine("abaqus")


def test_ignored_options_are_derived_from_reads():
    sc = with_run(with_contact(base_scene(), law="hertz", exponent=1.4), duration=0.05)
    with pytest.warns(
        OptionIgnored, match=f"contact.exponent = 1.4 does nothing in the {EXTRA} engine"
    ):
        run_engine(EXTRA, sc)
    with pytest.warns(
        OptionIgnored, match="contact.law = 'hertz' does nothing in the nonsmooth engine"
    ):
        run_engine("nonsmooth", sc)


# -- contact-free oracle with observed order ------------------------------------------------

A, W1, W2, T_END = 0.02, 2 * np.pi * 1.5, 2 * np.pi * 2.3, 1.0


@pytest.fixture(scope="module")
def smooth():
    """Elastic bents, gaps that never close, smooth support motion; DOP853 reference."""
    sc = with_seats(with_bents(base_scene(), elastic=True), gap=10.0)
    sc = with_run(sc, duration=T_END, output_dt=0.02)
    plan = plan_of(sc)
    damp = damping_model(sc, plan)
    t = np.arange(0, int(round(T_END / 1e-4)) + 1) * 1e-4
    ax, ay = A * (1 - np.cos(W1 * t)), A * (1 - np.cos(W2 * t))
    vx, vy = A * W1 * np.sin(W1 * t), A * W2 * np.sin(W2 * t)
    disp = {ch: (ay if ch.endswith("_y") else ax) for ch in plan.channels}
    vel = {ch: (vy if ch.endswith("_y") else vx) for ch in plan.channels}
    motion = motion_from(sc, t, disp, vel)
    B, S = plan.spring_matrices
    k0, crate, M = plan.k0, damp.rate_coefficients(plan), plan.mass
    sel_y = np.array([ch.endswith("_y") for ch in plan.channels])

    def f(tt, y):
        u, v = y[:7], y[7:]
        ug = np.where(sel_y, A * (1 - np.cos(W2 * tt)), A * (1 - np.cos(W1 * tt)))
        vg = np.where(sel_y, A * W2 * np.sin(W2 * tt), A * W1 * np.sin(W1 * tt))
        F = B.T @ (k0 * (B @ u - S @ ug) + crate * (B @ v - S @ vg)) + damp.a0 * M * v
        return np.concatenate([v, -F / M])

    tt = np.arange(0, int(round(T_END / 0.02)) + 1) * 0.02
    sol = solve_ivp(f, (0, T_END), np.zeros(14), method="DOP853", rtol=1e-12, atol=1e-14, t_eval=tt)
    ref = {"deck_x_abs": sol.y[4], "deck_y_abs": sol.y[5], "deck_theta": sol.y[6]}
    return sc, motion, ref


@pytest.mark.parametrize("engine", BUILT_IN + (EXTRA,))
def test_contact_free_oracle_and_order(engine, smooth):
    sc, motion, ref = smooth
    sc = sc.replace(
        run=dataclasses.replace(sc.run, steps_per_contact_period=0.0)
    )  # the given steps
    errs = []
    for dt in (2e-3, 1e-3):
        r = run_engine(engine, sc, motion, settings=with_step(engine, sc, dt))
        assert r.ok, r.meta["message"]
        errs.append(max(np.max(np.abs(r[k] - ref[k])) / np.max(np.abs(ref[k])) for k in ref))
    order = np.log2(errs[0] / errs[1])
    print(f"{engine}: errors {errs[0]:.3e}, {errs[1]:.3e}; observed order {order:.3f}")
    assert errs[1] < 1e-3
    assert 1.8 < order < 2.2


# -- impacts ----------------------------------------------------------------------------------

GAP, V0 = 0.01, 0.5
CONTACT_ENGINES = BUILT_IN


def impact_scene(engine: str, e: float):
    """The benchmark deck in free flight (bents 1e-9 kN/m, no damping) at −V0 towards seat 1,
    whose mass and inertia are 1e12: a symmetric impact on corners c1 and c2."""
    sc = base_scene("damping.ratio=0.0")
    sc = with_bents(sc, kx=1e-9, ky=1e-9)
    sc = with_seats(sc, mass=1e12, inertia=1e12, cx=0.0, ctheta=0.0, gap=GAP)
    law = "linear" if e == 1.0 else "kelvin-voigt"
    sc = (
        with_contact(sc, law=law, restitution=e, stiffness=1e7)
        if engine != "nonsmooth"
        else with_contact(sc, restitution=e)
    )
    sc = sc.replace(initial=dataclasses.replace(sc.initial, deck_velocity=(-V0, 0.0, 0.0)))
    return with_run(sc, duration=0.06, output_dt=1e-3)


def _run_impact(engine, e):
    sc = impact_scene(engine, e)
    dt = 1e-4 if engine == "nonsmooth" else 1e-5
    r = run_engine(
        engine,
        sc,
        motion_from(sc, np.array([0.0, 1.0]), {}, {}),
        settings=with_step(engine, sc, dt),
    )
    assert r.ok, r.meta["message"]
    return sc, r


@pytest.mark.parametrize("engine", CONTACT_ENGINES)
def test_symmetric_impact_rebounds_at_minus_e_v(engine):
    e = 0.6 if engine == "nonsmooth" else 1.0
    _sc, r = _run_impact(engine, e)
    v_out = r["deck_vx_abs"][-1]
    tol = 1e-9 if engine == "nonsmooth" else 2e-3
    print(f"{engine}: rebound {v_out / V0:.6f} (e = {e})")
    assert v_out == pytest.approx(e * V0, rel=tol)
    assert np.max(np.abs(r["deck_theta"])) <= 1e-12
    assert r.meta["gap_closures_per_corner"]["c1"] == 1 == r.meta["gap_closures_per_corner"]["c2"]
    assert r.meta["gap_closures_per_corner"]["c3"] == 0


@pytest.mark.parametrize("engine", CONTACT_ENGINES)
def test_elastic_impact_gains_no_energy(engine):
    sc, r = _run_impact(engine, 1.0)
    m = sc.deck.mass
    ke0 = 0.5 * m * V0**2
    ke1 = (
        0.5 * m * (r["deck_vx_abs"][-1] ** 2 + r["deck_vy_abs"][-1] ** 2)
        + 0.5 * sc.deck.inertia * r["deck_omega"][-1] ** 2
    )
    print(f"{engine}: kinetic energy after/before {ke1 / ke0:.12f}")
    # θ = ½ with Newton's law conserves it exactly; a penalty contact switches on inside a
    # step, an O(dt) error of either sign (3e-6 at dt = 1e-5 s here)
    assert ke1 <= ke0 * (1 + (1e-9 if engine == "nonsmooth" else 1e-5))
    assert ke1 >= ke0 * (1 - 1e-3)  # and an elastic impact keeps it


@pytest.mark.parametrize("engine", BUILT_IN)
def test_velocity_columns_are_the_rates_of_the_displacements(engine):
    """Issue 12: every engine's result carries the deck and seat velocities (absolute), and
    they are the time derivatives of its displacement columns: on the smooth contact-free
    problem the central difference of the output displacements matches the velocity columns
    to O(Δt_out²)."""
    sc = with_seats(with_bents(base_scene(), elastic=True), gap=10.0)
    sc = with_run(sc, duration=1.0, output_dt=2e-3)
    t = np.linspace(0.0, 1.0, 2001)
    w = 2 * np.pi * 1.5
    a = 0.02 * (1 - np.cos(w * t))
    plan = plan_of(sc)
    motion = motion_from(
        sc,
        t,
        dict.fromkeys(plan.channels, a),
        {ch: 0.02 * w * np.sin(w * t) for ch in plan.channels},
    )
    r = run_engine(engine, sc, motion, settings=with_step(engine, sc, 2e-4))
    assert r.ok
    for disp, vel in (
        ("deck_x_abs", "deck_vx_abs"),
        ("deck_y_abs", "deck_vy_abs"),
        ("deck_theta", "deck_omega"),
        ("seat1_x_abs", "seat1_vx_abs"),
        ("seat1_theta", "seat1_omega"),
        ("seat2_x_abs", "seat2_vx_abs"),
        ("seat2_theta", "seat2_omega"),
    ):
        assert r.meta["units"][vel] == ("rad/s" if vel.endswith("omega") else "m/s")
        fd = np.gradient(r[disp], r.t)[1:-1]
        v = r[vel][1:-1]
        scale = max(np.max(np.abs(v)), 1e-12)
        if np.max(np.abs(v)) < 1e-12:  # e.g. no rotation under uniform x/y motion
            assert np.max(np.abs(fd)) < 1e-9
            continue
        assert np.max(np.abs(fd - v)) <= 2e-3 * scale, (engine, vel)


def test_penetration_quality_warning():
    """Issue 16: a run that penetrates beyond PENETRATION_WARN_FRACTION of the smallest gap
    (per-step maximum) says so in meta['warnings'] and as a QualityWarning; the benchmark at
    the engines' default settings does not."""
    import warnings

    from deckpound.models.engine_contract import PENETRATION_WARN_FRACTION, QualityWarning
    from deckpound.models.scene_io import load_scene

    quiet = [("nonsmooth", []), ("compliance", [])]
    loud = [("nonsmooth", ["nonsmooth.h=0.05"]), ("compliance", ["contact.stiffness=1e4"])]
    for (engine, ov), warn in [(c, False) for c in quiet] + [(c, True) for c in loud]:
        sc = load_scene("saiidi-4span", ["run.duration=6.0", *ov])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            r = run_engine(engine, sc)
        q = [w for w in caught if issubclass(w.category, QualityWarning)]
        limit = PENETRATION_WARN_FRACTION[engine != "nonsmooth"] * sc.seats[0].gap
        print(engine, ov, r.meta["max_penetration"], limit)
        assert (r.meta["max_penetration"] > limit) == warn
        assert bool(q) == warn == bool(r.meta.get("quality_warnings"))
        if warn:
            assert r.meta["quality_warnings"][0] in r.meta["warnings"]

"""Compliance engine: penalty (compliant) contact on the 7-DOF plan model.

Entry point :func:`run_compliance` (the engine contract of :mod:`deckpound.engines`).

Equation of motion (absolute coordinates, the model of the OpenSees engine)::

    M ü + a0 M u̇ + Bᵀ[f_s(d) + (a1 k0 + c_dash) ḋ] = W_Nᵀ λ_N + W_Tᵀ λ_T

smooth part from :mod:`deckpound.analytic.system`, contact laws from
:mod:`deckpound.analytic.contact_laws`, kinematics from :mod:`deckpound.analytic.kinematics`.

Integrators (``scene.compliance.integrator``)
---------------------------------------------
``newmark`` — the OpenSees transient algorithm step for step (Newmark γ = ½, β = ¼, full
Newton, NormDispIncr test): the kernel is :mod:`deckpound.analytic.newmark`, where the
algorithm is written out.

``adaptive`` — :mod:`deckpound.analytic.adaptive` (error-controlled Dormand–Prince 5(4) with
event location; see there).

Result columns: the standard ones (``fn_c*`` = λ_N, compression > 0, OpenSees-identical
Kelvin–Voigt may give small tension at the end of an impact; ``ft_c*`` = λ_T, the tangential
force on the deck along +t = +y for linear kinematics; ``<bent>_fx/_fy`` the Takeda material
force for deformation deck − table) plus energies [kJ]: ``energy_input`` (work of the support
reactions: −∫ f_springᵀ S du_g, plus the initial mechanical energy — zero from rest),
``energy_kinetic``, ``energy_strain`` (recoverable energy of
bent and seat springs), ``energy_viscous`` (Rayleigh + seat dashpots), ``energy_hysteretic``
(Takeda), ``energy_contact_stored`` (contact + stick springs), ``energy_contact_dissipated``,
``energy_friction`` (dissipated by slip) and ``energy_error`` = input − all the others. Work
terms are trapezoidal over each step, which closes the balance of the Newmark average
acceleration scheme exactly up to the Newton residual.
"""

from __future__ import annotations

import time as _time
import warnings

import numpy as np

from deckpound.analytic import contact_laws as cl
from deckpound.analytic.kinematics import pack_geometry
from deckpound.analytic.newmark import BETA, ENERGY_COLUMNS, F_CONTACT_SKIP, F_ENERGY, \
    F_FACTOR_REUSE, GAMMA, N_FLAGS, newmark_run, newmark_workspace
from deckpound.analytic.support_motion import support_record
from deckpound.analytic.system import initial_dofs, pack_system
from deckpound.engines import output_stride
from deckpound.models.excitation import SupportMotion, analysis_duration, support_motion
from deckpound.models.result import Result, scene_hash, \
    set_status, standard_columns
from deckpound.models.scene import Scene

__all__ = ["run_compliance", "ENERGY_COLUMNS", "output_columns"]

SUBSTEPS = 10   # sub-steps of the fallback for a failed step (OpenSees engine default)
#: The skips :func:`run_compliance` can turn off for measurement (``_skips={name: False}``);
#: results are identical with and without each (``compare/skips.py`` measures and checks):
#:
#: * ``contact`` — contact laws, contact tangent and refactorisation skipped while every
#:   corner's gap is open (g > 0: every law gives zero force); off: all four corners'
#:   laws are evaluated at every Newton iteration (linear kinematics; the nonlinear
#:   kinematics already evaluates the gaps every iteration).
#: * ``friction`` — no friction law when μ = 0 (or friction_mode = none); off: the
#:   regularised slip law runs with μ = 0 at every closed corner (forces exactly 0).
#: * ``factor_reuse`` — the Takeda elastic short-circuit at the system level: while every
#:   bent spring's tangent is its initial one (and no corner is closed) the effective tangent
#:   is bitwise the elastic one and its factors are reused; off: assembled and factorised
#:   every iteration. (The material kernel's own short-circuit, ``pow`` skipped while the
#:   ductility is ≤ 1, is measured separately, see
#:   :data:`deckpound.analytic._hysteretic_kernel.ELASTIC_SHORTCUT`.)
#: * ``decimate`` — output stored every output step only; off: every step is stored and the
#:   result decimated afterwards.
SKIPS = ("contact", "friction", "factor_reuse", "decimate")


def output_columns(scene: Scene) -> list[str]:
    """Column names of the compliance result (standard columns, then the energies)."""
    return standard_columns([b.name for b in scene.bents]) + list(ENERGY_COLUMNS)


# ----------------------------------------------------------------------------- engine
_STATUS_TEXT = {1: "Newton did not converge (NormDispIncr)", 2: "singular tangent",
                3: "non-finite state"}


def _warn_ignored(scene: Scene) -> None:
    ct = scene.contact
    if ct.friction > 0.0 and ct.friction_mode == "none":
        warnings.warn("contact.friction > 0 is ignored because contact.friction_mode = 'none'",
                      stacklevel=3)
    if ct.friction_mode != "none" and ct.friction == 0.0:
        warnings.warn(f"contact.friction_mode = {ct.friction_mode!r} has no effect with "
                      "contact.friction = 0", stacklevel=3)


def pack_run(scene: Scene, motion: SupportMotion | None, *, kv_clip: bool = False):
    """Like :func:`prepare` but with the support record at its own samples (tb, D, V) instead
    of resampled arrays: memory independent of the number of steps."""
    if motion is None:
        motion = support_motion(scene)
    duration = analysis_duration(scene, motion)
    ps = pack_system(scene)
    tb, D, V = support_record(motion, ps.channels)
    cp = cl.pack_contact(scene, kv_clip=kv_clip)
    geom = pack_geometry(scene)
    cs = cl.new_contact_state(geom[8:12])
    return ps, (tb, D, V), cp, cs, geom, duration


def prepare(scene: Scene, motion: SupportMotion | None, dt: float, *, kv_clip: bool = False):
    """Pack everything a run needs (shared by the integrators and the verification)."""
    if motion is None:
        motion = support_motion(scene)
    duration = analysis_duration(scene, motion)
    ps = pack_system(scene)
    res = motion.resample(dt, duration)
    UG, VG = res.matrices(ps.channels)
    cp = cl.pack_contact(scene, kv_clip=kv_clip)
    geom = pack_geometry(scene)
    cs = cl.new_contact_state(geom[8:12])
    return ps, UG, VG, cp, cs, geom, duration


def run_compliance(scene: Scene, motion: SupportMotion | None = None, *,
                   raise_on_failure: bool = False, kv_clip: bool = False,
                   initial_state=None, substeps: int = SUBSTEPS, channels=None,
                   _skips: dict | None = None) -> Result:
    """Run the compliance engine on ``scene`` (engine contract of :mod:`deckpound.engines`).

    Extra keywords (not scene options): ``kv_clip`` clips the Kelvin–Voigt force at zero
    instead of the OpenSees ViscoelasticGap behaviour (tension allowed until the gap reopens);
    ``initial_state = (u0, v0)`` starts from the given DOF displacements and velocities
    (default rest, as OpenSees); ``substeps``: sub-steps of the fallback for a failed step
    (like the OpenSees engine's ``fallback = "substep"``; 1 disables it); ``channels``: store
    only these result columns (``t`` is always stored; energy work is not accumulated unless
    an energy column is requested) — the default stores every column (engine contract).
    ``_skips`` (private, for measurement): ``{name: False}`` turns off a work-saving skip of
    :data:`SKIPS` (Newmark integrator only; results are identical).
    """
    _warn_ignored(scene)
    if scene.compliance.integrator == "adaptive":
        from deckpound.analytic.adaptive import run_adaptive
        return run_adaptive(scene, motion, raise_on_failure=raise_on_failure, kv_clip=kv_clip,
                            initial_state=initial_state)
    t0 = _time.perf_counter()
    skips = {k: True for k in SKIPS}
    for k, v in (_skips or {}).items():
        if k not in skips:
            raise ValueError(f"unknown skip {k!r}; valid: {', '.join(SKIPS)}")
        skips[k] = bool(v)
    cset = scene.compliance
    dt = cset.dt
    ps, (tb, DG, VGR), cp, cs, geom, duration = pack_run(scene, motion, kv_clip=kv_clip)
    if not skips["friction"]:
        # the slip law with μ = 0 wherever friction was switched off: same (zero) forces
        off = cp[:, cl.P_FMODE] == 0
        cp[off, cl.P_FMODE] = cl.FRICTION_CODES["slip"]
        cp[off, cl.P_MU] = 0.0
    stride = output_stride(dt, scene.run.output_dt)
    kstride = stride if skips["decimate"] else 1
    nsteps = int(round(duration / dt))
    nbs = ps.n_bent_springs
    all_cols = output_columns(scene)
    if channels is None:
        cols = all_cols
    else:
        unknown = [c for c in channels if c not in all_cols]
        if unknown:
            raise ValueError(f"unknown result column {unknown[0]!r}; valid: {', '.join(all_cols)}")
        cols = ["t"] + [c for c in all_cols if c in set(channels) and c != "t"]
    colsel = np.array([all_cols.index(c) for c in cols], dtype=np.int64)
    want_energy = any(c in ENERGY_COLUMNS for c in cols)
    flags = np.ones(N_FLAGS, dtype=np.int64)
    flags[F_CONTACT_SKIP] = skips["contact"]
    flags[F_FACTOR_REUSE] = skips["factor_reuse"]
    flags[F_ENERGY] = want_energy
    out = np.zeros((nsteps // kstride + 1, len(cols)))
    info = np.zeros(8, dtype=np.int64)
    hstate = ps.new_state()
    u0, v0 = initial_dofs(initial_state)
    work = newmark_workspace(ps.n_springs, DG.shape[1], nbs)
    t1 = _time.perf_counter()
    newmark_run(ps.arrays, ps.C, hstate, cp, cs, geom, scene.contact.geometry == "nonlinear",
                tb, DG, VGR, nsteps, dt, cset.tolerance, cset.max_iterations, kstride, nbs, out,
                info, u0, v0, substeps, flags, colsel, work)
    t2 = _time.perf_counter()
    status_code, rows = int(info[0]), int(info[1])
    if kstride != stride:
        out = out[:rows:stride]
        rows = out.shape[0]
    meta = {
        "engine": "compliance",
        "integrator": "newmark",
        "settings": {"dt": dt, "tolerance": cset.tolerance,
                     "max_iterations": cset.max_iterations, "gamma": GAMMA, "beta": BETA,
                     "kv_clip": kv_clip, "skips": skips},
        "scene_hash": scene_hash(scene),
        "wall_time": t2 - t0,
        "loop_time": t2 - t1,
        "us_per_step": 1e6 * (t2 - t1) / max(nsteps, 1),
        "steps": nsteps if status_code == 0 else int(info[2]) - 1,
        "iterations": int(info[3]),
        "max_step_iterations": int(info[6]),
        "elastic_factor_reuses": int(info[5]),
        "contact_events": int(info[4]),
        "failures": int(info[7]) + (0 if status_code == 0 else 1),
        "rescued_by_substeps": int(info[7]),
        "duration": duration,
        "rayleigh": {"a0": ps.a0, "a1": ps.a1, "omega": list(ps.omega)},
        "energy_note": "energy_error = input - (kinetic + strain + viscous + hysteretic + "
                       "contact_stored + contact_dissipated + friction) [kJ]",
    }
    columns = {k: out[:rows, i].copy() for i, k in enumerate(cols)}
    if "energy_input" in columns and "energy_error" in columns:
        ein = np.max(np.abs(columns["energy_input"])) if rows else 0.0
        meta["energy_closure"] = float(np.max(np.abs(columns["energy_error"])) / ein) \
            if ein > 0 else 0.0
    ok = status_code == 0
    set_status(meta, engine="compliance", ok=ok, step=int(info[2]), dt=dt,
               message=f"{nsteps} steps, {int(info[3])} Newton iterations" if ok
               else _STATUS_TEXT.get(status_code, "failure"), raise_on_failure=raise_on_failure)
    return Result(engine="compliance", columns=columns, meta=meta)

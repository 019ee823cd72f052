"""Compliance engine: penalty (compliant) contact on the 7-DOF plan model.

Engine :class:`ComplianceEngine` (registry name ``compliance``; the contract of
:mod:`deckpound.models.engine_contract`); :func:`run_compliance` is the same as a function.

Equation of motion (absolute coordinates, the model of the OpenSees engine)::

    M ü + a0 M u̇ + Bᵀ[f_s(d) + (a1 k0 + c_dash) ḋ] = W_Nᵀ λ_N + W_Tᵀ λ_T

smooth part from :mod:`deckpound.analytic.kernels.system`, contact laws from
:mod:`deckpound.analytic.kernels.contact_laws`, kinematics from :mod:`deckpound.analytic.kernels.kinematics`.

Integrators (``scene.compliance.integrator``)
---------------------------------------------
``newmark`` — the OpenSees transient algorithm step for step (Newmark γ = ½, β = ¼, full
Newton, NormDispIncr test): the kernel is :mod:`deckpound.analytic.compliance.newmark`, where the
algorithm is written out.

``adaptive`` — :mod:`deckpound.analytic.compliance.adaptive` (error-controlled Dormand–Prince 5(4) with
event location; see there).

Result columns: the standard ones (``fn_c*`` = λ_N, compression > 0, OpenSees-identical
Kelvin–Voigt may give small tension at the end of an impact; ``ft_c*`` = λ_T, the tangential
force on the deck along the face tangent t (+y for a straight deck and linear kinematics);
``<bent>_fx/_fy`` the Takeda material force for deformation deck − table) plus energies [kJ]: ``energy_input`` (work of the support
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
from typing import ClassVar

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic import interruptible
from deckpound.analytic._jit import ensure_compiled
from deckpound.analytic.compliance.adaptive import run_adaptive
from deckpound.analytic.compliance.newmark import BETA, GAMMA, newmark_run
from deckpound.analytic.compliance.newmark_work import NewmarkOptions, newmark_workspace
from deckpound.analytic.compliance.pack import pack_run
from deckpound.analytic.fp_mode import flush_note
from deckpound.analytic.kernels import contact_laws as cl
from deckpound.analytic.kernels.peaks import run_output_fields, run_peaks
from deckpound.analytic.kernels.system import initial_dofs
from deckpound.models.columns import ENERGY_COLUMNS, column_names  # energies [kJ]
from deckpound.models.contact_laws_table import contact_law, friction_model
from deckpound.models.contact_params import contact_resolving_step
from deckpound.models.damping import refuse_tangent_damping
from deckpound.models.engine_contract import (
    Engine,
    RunOutput,
    Status,
    engine_columns,
    output_stride,
)
from deckpound.models.errors import SceneError
from deckpound.models.motion import SupportMotion, analysis_duration
from deckpound.models.plan import Plan, plan_of
from deckpound.models.scene import Scene
from deckpound.models.scene_settings import ComplianceSettings

__all__ = [
    "SKIPS",
    "ComplianceEngine",
    "output_columns",
    "run_compliance",
]

SUBSTEPS = 10  # sub-steps of the fallback for a failed step (OpenSees engine default)
#: The skips the engine can turn off for measurement (``_skips={name: False}``);
#: results are identical with and without each (``compare/bench/skips.py`` measures and checks):
#:
#: * ``contact`` — contact laws, contact tangent and refactorisation skipped while every
#:   corner's gap is open (g > 0: every law gives zero force); off: all four corners'
#:   laws are evaluated at every Newton iteration (linear kinematics; the nonlinear
#:   kinematics already evaluates the gaps every iteration).
#: * ``friction`` — no friction law when μ = 0 (or friction_mode = none); off: the
#:   regularised slip law runs with μ = 0 at every closed corner (forces exactly 0).
#: * ``factor_reuse`` — the effective tangent's factors reused while the matrix is bitwise
#:   the one factorised: the elastic one while every bent spring's tangent is its initial one
#:   and no corner is closed (the Takeda elastic short-circuit at the system level), or the
#:   last one while the step, the spring tangents and, with linear contact kinematics, the
#:   closed corners and their law derivatives stay (in contact too; meta ``factorisations``,
#:   ``contact_factor_reuses``); off: assembled and factorised every iteration. (The material kernel's own short-circuit, ``pow`` skipped while the
#:   ductility is ≤ 1, is measured separately, see
#:   :data:`deckpound.analytic.kernels.hysteretic_kernel.ELASTIC_SHORTCUT`.)
#: * ``unmoved_iterate`` — no force evaluation at a converged Newton iterate whose last
#:   increment left every displacement bitwise unchanged (the round-off correction of a step
#:   that stayed on its material branches with every gap open, most steps): the Takeda trial
#:   states, spring forces and gaps are functions of u alone, so they are those of the last
#:   evaluation, and only the spring and gap rates are recomputed at the new u̇; off: the
#:   forces are evaluated at every iterate, as OpenSees does.
#: * ``decimate`` — output stored every output step only; off: every step is stored and the
#:   result decimated afterwards.
SKIPS = ("contact", "friction", "factor_reuse", "unmoved_iterate", "decimate")


def output_columns(scene: Scene, plan: Plan | None = None) -> list[str]:
    """Column names of the compliance result (the standard columns of the scene's plan, then
    the energies)."""
    return column_names(plan_of(scene) if plan is None else plan) + list(ENERGY_COLUMNS)


class ComplianceEngine(Engine):
    """The compliance clone of the OpenSees model (module docstring)."""

    name = "compliance"
    title = "compliance clone (penalty contact, numba)"
    Settings = ComplianceSettings
    settings_field = "compliance"
    step_field = "dt"
    summary_rows = True  # engine contract, point 12 (the Newmark loop; adaptive: all rows)
    style: ClassVar[dict] = {
        "color": "#1f5fa8",
        "linestyle": "--",
        "linewidth": 1.2,
        "label": "compliance clone",
    }

    def fixed_step(self, scene: Scene, settings) -> float | None:
        return super().fixed_step(scene, settings) if settings.integrator == "newmark" else None

    def reads(self, scene: Scene, settings) -> set[str]:
        """The law's and the friction model's parameters, from their rows of
        :mod:`deckpound.models.contact_laws_table`."""
        ct = scene.contact
        read = {"contact.law", "contact.stiffness", "contact.geometry"}
        if settings.integrator == "newmark":
            read.add("run.steps_per_contact_period")
        read |= set(contact_law(ct.law).params)
        if ct.friction_mode != "none":
            read.add("contact.friction")
        if ct.friction > 0.0:
            read.add("contact.friction_mode")
            read |= set(friction_model(ct.friction_mode).params)
        return read

    def notes(self, scene: Scene, settings) -> list[str]:
        return flush_note("compliance.subnormals", settings.subnormals)

    def refuse(self, scene: Scene, settings) -> None:
        """contact2d is OpenSees's discrete, step-by-step algorithm (its stick point moves at
        every sliding commit, so the answer depends on where the steps fall) on the element's
        fixed normal and tangent: it needs the fixed-step ``newmark`` integrator and the linear
        contact kinematics."""
        if settings.integrator != "newmark":
            refuse_tangent_damping(
                scene,
                "compliance engine's adaptive",
                "its explicit "
                "Dormand–Prince stages and energy work use the constant "
                "damping matrix",
            )
        ct = scene.contact
        if ct.has_friction and ct.friction_mode == "contact2d":
            if settings.integrator != "newmark":
                raise SceneError(
                    "compliance.integrator",
                    "friction_mode = 'contact2d' "
                    "(OpenSees zeroLengthContact2D's step-by-step algorithm) needs "
                    "integrator = 'newmark'; use friction_mode = 'stick' or "
                    "'slip' with the adaptive integrator",
                )
            if ct.geometry != "linear":
                raise SceneError(
                    "contact.geometry",
                    "friction_mode = 'contact2d' "
                    "(zeroLengthContact2D: fixed normal and tangent) needs "
                    "geometry = 'linear'; use friction_mode = 'stick' or 'slip' "
                    "with the nonlinear geometry",
                )

    def _run(
        self,
        plan: Plan,
        scene: Scene,
        settings,
        motion,
        *,
        kv_clip: bool = False,
        initial_state=None,
        substeps: int = SUBSTEPS,
        channels=None,
        summary_rows: bool = False,
        on_interrupt: str = "raise",
        _skips: dict | None = None,
    ) -> RunOutput:
        """Extra keywords (not scene options): ``kv_clip`` clips the Kelvin–Voigt force at zero
        instead of the OpenSees ViscoelasticGap behaviour (tension allowed until the gap
        reopens); ``initial_state = (u0, v0)`` starts from the given DOF displacements and
        velocities (default: the scene's ``initial`` table); ``substeps``: sub-steps of the fallback for a
        failed step (1 disables it); ``channels``: store only these columns besides the engine
        columns (energy work is not accumulated unless an energy column is requested);
        ``summary_rows``: store only ``t`` and the energy columns (engine contract, point 12;
        the Newmark integrator, the adaptive one stores every column); ``on_interrupt``: what
        Ctrl-C during the step loop does (it stops the loop within one Newton iteration, see
        :mod:`deckpound.analytic.interruptible`): ``"raise"`` (default)
        re-raises KeyboardInterrupt, ``"return"`` returns ``Status.INTERRUPTED`` with the rows
        computed so far; ``_skips`` (private, for measurement): ``{name: False}`` turns off a
        work-saving skip of :data:`SKIPS` (``newmark`` only; results are identical)."""
        if on_interrupt not in ("raise", "return"):
            raise ValueError(f"on_interrupt must be 'raise' or 'return', got {on_interrupt!r}")
        if initial_state is None:
            initial_state = plan.initial_state(scene.initial)
        if settings.integrator == "adaptive":
            return run_adaptive(
                plan,
                scene,
                settings,
                motion,
                kv_clip=kv_clip,
                initial_state=initial_state,
                on_interrupt=on_interrupt,
            )
        return _run_newmark(
            plan,
            scene,
            settings,
            motion,
            kv_clip=kv_clip,
            initial_state=initial_state,
            substeps=substeps,
            channels=channels,
            summary_rows=summary_rows,
            skips=_skips,
            on_interrupt=on_interrupt,
        )


def _skip_switches(skips: dict | None) -> dict[str, bool]:
    """Every skip of :data:`SKIPS` on, except those ``skips`` turns off (``{name: False}``)."""
    on = dict.fromkeys(SKIPS, True)
    for k, v in (skips or {}).items():
        if k not in on:
            raise ValueError(f"unknown skip {k!r}; valid: {', '.join(SKIPS)}")
        on[k] = bool(v)
    return on


def _stored_columns(
    plan: Plan, scene: Scene, channels, summary_rows: bool = False
) -> tuple[list[str], np.ndarray]:
    """The columns a Newmark run stores (the engine columns and the energies, or the engine
    columns plus ``channels``, or for summary rows ``t`` and the energies) and their indices
    into the loop's full row."""
    all_cols = output_columns(scene, plan)
    engine_cols = engine_columns(plan)
    if summary_rows:
        cols = ["t"] + [c for c in all_cols if c in ENERGY_COLUMNS]
    elif channels is None:
        cols = [c for c in all_cols if c in engine_cols or c in ENERGY_COLUMNS]
    else:
        unknown = [c for c in channels if c not in all_cols]
        if unknown:
            raise ValueError(f"unknown result column {unknown[0]!r}; valid: {', '.join(all_cols)}")
        want = set(channels) | set(engine_cols)
        cols = [c for c in all_cols if c in want and (c in engine_cols or c in ENERGY_COLUMNS)]
    full = engine_cols + list(ENERGY_COLUMNS)
    return cols, np.array([full.index(c) for c in cols], dtype=np.int64)


def _set_newton_contact(settings, cp: np.ndarray, friction_skip: bool) -> None:
    """Newton's contact-tangent switch into ``cp``; with the friction skip off, the slip law
    with μ = 0 where friction is off."""
    # Newton's contact tangent: the laws' derivatives, or what OpenSees's materials report
    cp[:, cl.P_OTAN] = 1.0 if settings.contact_tangent == "opensees" else 0.0
    if not friction_skip:
        # the slip law with μ = 0 wherever friction was switched off: same (zero) forces
        off = cp[:, cl.P_FMODE] == cl.FRICTION_NONE
        cp[off, cl.P_FMODE] = cl.FRICTION_CODES["slip"]
        cp[off, cl.P_MU] = 0.0


def _run_newmark(
    plan,
    scene,
    settings,
    motion,
    *,
    kv_clip,
    initial_state,
    substeps,
    channels,
    summary_rows,
    skips,
    on_interrupt,
) -> RunOutput:
    """The Newmark integrator of :meth:`ComplianceEngine._run` (same keywords)."""
    on = _skip_switches(skips)
    dt = contact_resolving_step(scene, settings.dt, plan)
    duration = analysis_duration(scene, motion)
    ps, record, cp, cs, corners = pack_run(plan, scene, motion, kv_clip=kv_clip)
    _set_newton_contact(settings, cp, on["friction"])
    stride = output_stride(dt, scene.run.output_dt)
    kstride = stride if on["decimate"] else 1
    nsteps = round(duration / dt)
    cols, colsel = _stored_columns(plan, scene, channels, summary_rows)
    rows_max = nsteps // kstride + 1
    opts = NewmarkOptions(
        nsteps=nsteps,
        dt=float(dt),
        tol=float(settings.tolerance),
        maxit=int(settings.max_iterations),
        stride=int(kstride),
        substeps=int(substeps),
        skip_contact=on["contact"],
        reuse_factors=on["factor_reuse"],
        skip_unmoved=on["unmoved_iterate"],
        want_energy=any(c in ENERGY_COLUMNS for c in cols),
        flush_subnormals=settings.subnormals == "flush",
    )
    peaks = run_peaks(plan, ps)
    n_full = len(engine_columns(plan)) + len(ENERGY_COLUMNS)
    output = bd.Output(bd.output_table(rows_max, len(cols)), colsel, np.zeros(n_full), peaks)
    u0, v0 = initial_dofs(initial_state, ps.arrays.mass.shape[0])
    work = newmark_workspace(u0, v0, ps.new_state(), cs, ps.n_springs, len(ps.channels))
    contact = bd.Contact(corners, cp, scene.contact.geometry == "nonlinear")
    stats = bd.new_stats()
    args = (ps.arrays, contact, bd.record(*record), opts, output, work, stats)
    compile_time = ensure_compiled(newmark_run, *args)
    t1 = _time.perf_counter()
    interrupted = interruptible.run_loop(newmark_run, args, stats)
    loop = _time.perf_counter() - t1
    if interrupted and on_interrupt == "raise":
        raise KeyboardInterrupt
    st = bd.stats_dict(stats)
    status = bd.status_of(st["status"])
    out, rows = output.table, st["rows"]
    if kstride != stride:
        out = out[:rows:stride]
        rows = out.shape[0]
    columns = bd.result_columns(out, rows, cols)
    ok = status == Status.SUCCESS
    finished = ok or status == Status.UNSEATED  # unseating is an answer, not a failure
    extra = {
        "integrator": "newmark",
        "dt": float(dt),
        "gamma": GAMMA,
        "beta": BETA,
        "kv_clip": kv_clip,
        "skips": on,
        "contact_tangent": settings.contact_tangent,
        "max_step_iterations": st["max_step_iterations"],
        "elastic_factor_reuses": st["factor_reuses"],
        "factorisations": st["factorisations"],
        "contact_factor_reuses": st["contact_factor_reuses"],
        "unmoved_iterates": st["unmoved_iterates"],
        "rayleigh": {"a0": ps.a0, "a1": ps.a1, "omega": list(ps.omega)},
        "energy_note": "energy_error = input - (kinetic + strain + viscous + hysteretic + "
        "contact_stored + contact_dissipated + friction) [kJ]",
    }
    if "energy_input" in columns and "energy_error" in columns:
        ein = np.max(np.abs(columns["energy_input"])) if rows else 0.0
        extra["energy_closure"] = (
            float(np.max(np.abs(columns["energy_error"])) / ein) if ein > 0 else 0.0
        )
    failed_step = st["failed_step"]
    return RunOutput(
        columns=columns,
        status=status,
        message=(
            f"{nsteps} steps, {st['newton_iterations']} Newton iterations"
            if ok
            else _failure_text(status)
        ),
        failed_step=None if finished else failed_step,
        failed_time=None if finished else failed_step * dt,
        steps=st["steps"],
        newton_iterations=st["newton_iterations"],
        failed_steps=st["rescued_steps"] + (0 if finished else 1),
        rescued_steps=st["rescued_steps"],
        compile_time=compile_time,
        loop_time=loop,
        max_penetration=st["max_penetration"],
        **run_output_fields(peaks, plan),
        summary_rows=summary_rows,
        extra=extra,
    )


def _failure_text(status: Status) -> str:
    """The status text (:attr:`Status.text`), with the test that failed for the Newton loop."""
    if status == Status.NOT_CONVERGED:
        return f"{status.text} (Newton, NormDispIncr test)"
    return status.text


def run_compliance(
    scene: Scene, motion: SupportMotion | None = None, *, raise_on_failure: bool = False, **options
):
    """Run the compliance engine on ``scene`` (keywords of :meth:`ComplianceEngine._run`)."""
    return ComplianceEngine().run(scene, None, motion, raise_on_failure=raise_on_failure, **options)

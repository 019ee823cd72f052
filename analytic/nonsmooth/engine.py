r"""Nonsmooth engine: Moreau–Jean time stepping with rigid, frictional, impacting contact.

Engine :class:`NonsmoothEngine` (registry name ``nonsmooth``; the contract of
:mod:`deckpound.models.engine_contract`); :func:`run_nonsmooth` is the same as a function.

Model
-----
The 7-DOF plan model of the other engines (DOFs u = [x₁, θ₁, x₂, θ₂, x_d, y_d, θ_d]) with the
deck–seat contacts made rigid: the measure differential equation

    M du̇ = −F(u, u̇, t) dt + W_Nᵀ dΛ_N + W_Tᵀ dΛ_T,
    F(u, u̇, t) = Bᵀ[f_s(d) + crate·ḋ] + a0·M u̇,   d = B u − S u_g(t),  ḋ = B u̇ − S u̇_g(t)

(smooth part: the shared kernels of :mod:`deckpound.analytic.kernels.system` — Takeda bent springs,
linear seat springs, seat dashpots, Rayleigh damping, multi-support excitation; W_N, W_T rows
from :func:`deckpound.analytic.kernels.kinematics.contact_kinematics`, geometrically linear or
nonlinear). Per corner: Newton's impact law 0 ≤ U_N⁺ + e·U_N⁻ ⊥ P_N ≥ 0 and set-valued planar
Coulomb friction −U_T⁺ ∈ μ·P_N·∂|P_T| (μ = ``contact.friction`` when
``contact.friction_mode`` ≠ none; the slip/stick distinction and the contact stiffness / law
options of the compliance engines do not apply). U_N = W_N u̇ and U_T = W_T u̇ contain the seat
DOFs, so the moving seats enter the relative velocities exactly as the kinematics define them.

Time discretisation: the Moreau–Jean θ-scheme (Jean 1999, Acary & Brogliato 2008 Ch. 10),
implicit in the smooth forces, with Newton impact and set-valued Coulomb friction solved
exactly per step; written out with its kernel in :mod:`deckpound.analytic.nonsmooth.moreau_jean`.

Output (every :func:`deckpound.compare.engines.output_stride` steps)
-------------------------------------------------------------
Standard columns (gaps at q_{k+1}; ``fn_c*``/``ft_c*`` = impulse over the output interval
divided by its length — impulse-conserving averages; ``ft`` along +t, +y for linear
kinematics, force on the deck; ``<bent>_fx/_fy`` the Takeda force), plus ``pn_c*``, ``pt_c*``
(impulse accumulated over the output interval [kN·s]; two corners of one face share one
tangent, so the per-corner split of ``pt`` is not unique — the solver returns the split in
proportion to μ·P_N; face totals are unique), ``state_c*`` (0 open, 1 stick, 2 slip, from the
last step of the interval) and energies [kJ], exact for the discrete scheme (closing to round-
off and the Newton tolerance; derivation: multiply the step equation by
v_m = (1−θ)v_k + θv_{k+1}, note Δq = h v_m and v_mᵀMΔv = ΔT + (θ−½)ΔvᵀMΔv):

* ``energy_input``: initial mechanical energy − Σ (SΔu_g)ᵀ(f_s + crate·ḋ)_θ, the work of the
  support reactions;
* ``energy_kinetic``; ``energy_strain`` (recoverable spring energy, as the compliance engine);
* ``energy_viscous``: Σ Δdᵀ crate ḋ_θ + a0 Δqᵀ M v_m; ``energy_hysteretic``: Σ Δdᵀ f_s,θ − strain;
* ``energy_impact`` = −Σ P_N (W_N v_m), ``energy_friction`` = −Σ P_T (W_T v_m) (for θ = ½:
  −½ P (U⁻ + U⁺), the impulses' work on the mean velocity);
* ``energy_numerical`` = Σ (θ − ½) Δvᵀ M Δv ≥ 0, the algorithmic dissipation of θ > ½;
* ``energy_error`` = input − all the others.

(x)_θ = θ x_{k+1} + (1−θ) x_k. Metadata: the contract's fields (``contact_solves``: contact
problems solved, Newton re-solves included; ``newton_iterations``: Newton iterations of the
Takeda springs) plus ``contact_steps``, ``max_complementarity`` and ``max_cone_residual``
(largest verified residuals of :func:`~deckpound.analytic.nonsmooth.frictional_contact.
solve_contact_impulses_into`, m/s; also ``max_complementarity_residual``), ``max_penetration``
(at every step, m, through the shared epilogue), ``impact_law`` and
``energy_error`` (largest |energy_error|, kJ), ``final_u``/``final_v`` (DOF displacements and
velocities at the last accepted step, DOF order of :mod:`deckpound.models.mechanics`).
"""

from __future__ import annotations

import time as _time
from typing import ClassVar

import numpy as np

from deckpound.analytic import bundles as bd
from deckpound.analytic import interruptible
from deckpound.analytic._jit import ensure_compiled
from deckpound.analytic.fp_mode import flush_note
from deckpound.analytic.kernels.contact_laws import pack_contact
from deckpound.analytic.kernels.hysteretic_layout import P_S1P
from deckpound.analytic.kernels.kinematics import pack_corners
from deckpound.analytic.kernels.peaks import run_output_fields, run_peaks
from deckpound.analytic.kernels.support_motion import support_record
from deckpound.analytic.kernels.system import initial_dofs, pack_system
from deckpound.analytic.nonsmooth.frictional_contact import MODE_AUTO, MODE_ENUM
from deckpound.analytic.nonsmooth.moreau_jean import moreau_jean_run
from deckpound.analytic.nonsmooth.moreau_jean_work import (
    ENERGY_COLUMNS,
    FINAL_U,
    FINAL_V,
    MoreauJeanOptions,
    impulse_columns,
    moreau_jean_workspace,
)
from deckpound.models.columns import column_names
from deckpound.models.contact_laws_table import RIGID_CONTACT, contact_law, friction_model
from deckpound.models.contact_params import corner_contacts
from deckpound.models.damping import damping_model, refuse_tangent_damping
from deckpound.models.engine_contract import (
    Engine,
    RunOutput,
    Status,
    engine_columns,
    output_stride,
)
from deckpound.models.motion import SupportMotion, analysis_duration
from deckpound.models.plan import Plan, plan_of
from deckpound.models.scene import Scene
from deckpound.models.scene_settings import NonsmoothSettings

__all__ = ["NonsmoothEngine", "output_columns", "run_nonsmooth", "separating_restitution"]


def output_columns(scene: Scene) -> list[str]:
    """Column names of the nonsmooth result (standard, impulses and contact states of the
    scene's plan's corners, energies)."""
    plan = plan_of(scene)
    return (
        column_names(plan)
        + list(impulse_columns(c.name for c in plan.corners))
        + list(ENERGY_COLUMNS)
    )


def separating_restitution(e: float, theta: float, impact_law: str = "energy-safe") -> float:
    """Restitution used at an active corner that is already separating (U_N⁻ > 0).

    ``impact_law = "newton"``: e, Newton's law at every active corner (Siconos'
    MoreauJeanOSI with NewtonImpactNSL). ``"energy-safe"``: max(e, (1 − θ)/θ) (= 1 for θ = ½),
    which makes the normal impulse's work on v_m = (1−θ)v_k + θv_{k+1} non-positive, so a
    frictionless step never gains energy (:mod:`deckpound.analytic.nonsmooth.moreau_jean`).
    """
    if impact_law == "newton":
        return float(e)
    if impact_law != "energy-safe":
        raise ValueError(f"impact_law must be 'newton' or 'energy-safe', got {impact_law!r}")
    return max(float(e), (1.0 - theta) / theta)


def _force_tolerance(ps, tol: float) -> float:
    """Newton acceptance of the spring-force linearisation mismatch [kN]."""
    hyst = ps.arrays.kind == 1
    scale = float(np.max(np.abs(ps.arrays.hparams[hyst, P_S1P]))) if np.any(hyst) else 1.0
    return tol * max(scale, 1.0)


class NonsmoothEngine(Engine):
    """Rigid unilateral frictional contact, Moreau–Jean time stepping (module docstring)."""

    name = "nonsmooth"
    title = "nonsmooth Moreau–Jean (Newton impact, set-valued Coulomb friction)"
    Settings = NonsmoothSettings
    settings_field = "nonsmooth"
    step_field = "h"
    compliant_contact = False
    summary_rows = True  # engine contract, point 12
    style: ClassVar[dict] = {
        "color": "#c0392b",
        "linestyle": ":",
        "linewidth": 1.6,
        "label": "nonsmooth",
    }

    def refuse(self, scene: Scene, settings) -> None:
        """Damping on the committed or current tangent is not implemented in the Moreau–Jean
        smooth-force step (its θ-linearisation uses the constant damping matrix)."""
        refuse_tangent_damping(
            scene,
            "nonsmooth",
            "its θ-method step linearises the smooth forces with the constant damping matrix",
        )

    def reads(self, scene: Scene, settings) -> set[str]:
        """Restitution, geometry and the friction coefficient; the contact law and its
        parameters only where the law's row of :mod:`deckpound.models.contact_laws_table` says
        the engine expresses it (``ContactLaw.nonsmooth``; no compliant law: rigid contact
        replaces them, so a non-default law is warned about)."""
        ct = scene.contact
        read = {"contact.restitution", "contact.geometry"}
        law = contact_law(ct.law)
        if law.nonsmooth:
            read |= {"contact.law", *law.params}
        if ct.friction_mode != "none":
            read.add("contact.friction")
        if ct.friction > 0.0:
            read.add("contact.friction_mode")
        return read

    def notes(self, scene: Scene, settings) -> list[str]:
        ct = scene.contact
        how = friction_model(ct.friction_mode).nonsmooth
        notes = flush_note("nonsmooth.subnormals", settings.subnormals)
        if ct.has_friction and how:
            notes.append(
                f"contact.friction_mode = {ct.friction_mode!r} means {how} "
                f"(mu = {ct.friction:g}): {RIGID_CONTACT}"
            )
        return notes

    def _run(
        self,
        plan: Plan,
        scene: Scene,
        settings,
        motion,
        *,
        initial_state=None,
        summary_rows: bool = False,
        on_interrupt: str = "raise",
    ) -> RunOutput:
        """Extra keywords (not scene options): ``initial_state = (u0, v0)`` starts from the
        given DOF displacements and velocities (default: the scene's ``initial`` table);
        ``summary_rows``: store only ``t`` and the energy columns (engine contract, point 12);
        ``on_interrupt``: Ctrl-C during the step loop stops it within one Newton iteration
        (:mod:`deckpound.analytic.interruptible`) and then re-raises KeyboardInterrupt (``"raise"``,
        default) or returns ``Status.INTERRUPTED`` with the rows so far (``"return"``)."""
        text_of = {
            bd.RUN_NOT_CONVERGED: "Newton iteration of the Takeda springs did not converge",
            bd.RUN_CONTACT_UNSOLVED: "contact problem not solved (no verified solution)",
            bd.RUN_NONFINITE: "non-finite state",
            bd.RUN_SINGULAR: "singular iteration matrix",
            bd.RUN_INTERRUPTED: "interrupted",
        }
        if on_interrupt not in ("raise", "return"):
            raise ValueError(f"on_interrupt must be 'raise' or 'return', got {on_interrupt!r}")
        if initial_state is None:
            initial_state = plan.initial_state(scene.initial)
        ns_set = settings
        h, theta = ns_set.h, ns_set.theta
        duration = analysis_duration(scene, motion)
        ps = pack_system(plan, damping_model(scene, plan))
        record = bd.record(*support_record(motion, ps.channels))
        ct = scene.contact
        mu = float(ct.friction) if ct.has_friction else 0.0
        tables = corner_contacts(scene, plan)
        stride = output_stride(h, scene.run.output_dt)
        nsteps = round(duration / h)
        corner_names = [c.name for c in plan.corners]
        full = engine_columns(plan) + list(impulse_columns(corner_names)) + list(ENERGY_COLUMNS)
        cols = ["t", *ENERGY_COLUMNS] if summary_rows else full
        peaks = run_peaks(plan, ps)
        output = bd.Output(
            bd.output_table(nsteps // stride + 1, len(cols)),
            np.array([full.index(c) for c in cols], dtype=np.int64),
            np.zeros(len(full)),
            peaks,
        )
        u0, v0 = initial_dofs(initial_state, ps.arrays.mass.shape[0])
        contact = bd.Contact(
            pack_corners(plan), pack_contact(scene, plan=plan), ct.geometry == "nonlinear"
        )
        work = moreau_jean_workspace(
            u0, v0, ps.new_state(), ps.n_springs, len(ps.channels), contact.corners.shape[0]
        )
        opts = MoreauJeanOptions(
            nsteps=nsteps,
            h=float(h),
            theta=float(theta),
            ecoef=np.array([float(c.restitution) for c in tables]),
            esep=np.array(
                [separating_restitution(c.restitution, theta, ns_set.impact_law) for c in tables]
            ),
            mu=np.array([float(c.friction) if c.has_friction else 0.0 for c in tables]),
            mode=MODE_ENUM if ns_set.solver == "enumeration" else MODE_AUTO,
            rtol=float(ns_set.tolerance),
            ftol=_force_tolerance(ps, ns_set.tolerance),
            maxit=int(ns_set.max_iterations),
            stride=int(stride),
            flush_subnormals=ns_set.subnormals == "flush",
        )
        stats = bd.new_stats()
        args = (ps.arrays, contact, record, opts, output, work, stats)
        compile_time = ensure_compiled(moreau_jean_run, *args)
        t1 = _time.perf_counter()
        interrupted = interruptible.run_loop(moreau_jean_run, args, stats)
        loop = _time.perf_counter() - t1
        if interrupted and on_interrupt == "raise":
            raise KeyboardInterrupt
        st = bd.stats_dict(stats)
        status = bd.status_of(st["status"])
        ok = status == Status.SUCCESS
        finished = ok or status == Status.UNSEATED  # unseating is an answer, not a failure
        rows = st["rows"]
        columns = bd.result_columns(output.table, rows, cols)
        ein = float(np.max(np.abs(columns["energy_input"]))) if rows else 0.0
        eerr = float(np.max(np.abs(columns["energy_error"]))) if rows else 0.0
        extra = {
            "restitution": float(ct.restitution),
            "friction": mu,
            "contact_steps": st["contact_steps"],
            "max_step_iterations": st["max_step_iterations"],
            "factorisations": st["factorisations"],
            "max_complementarity": st["max_complementarity"],
            "max_cone_residual": st["max_cone_residual"],
            "impact_law": ns_set.impact_law,
            "energy_error": eerr,
            "energy_closure": eerr / ein if ein > 0 else 0.0,
            "final_u": work.final[FINAL_U].tolist(),
            "final_v": work.final[FINAL_V].tolist(),
            "rayleigh": {"a0": ps.a0, "a1": ps.a1, "omega": list(ps.omega)},
            "energy_note": "energy_error = input - (kinetic + strain + viscous + hysteretic + "
            "impact + friction + numerical) [kJ]",
        }
        return RunOutput(
            columns=columns,
            status=status,
            message=(
                f"{nsteps} steps, {st['contact_steps']} with contact, "
                f"{st['contact_solves']} contact solves"
            )
            if ok
            else text_of.get(st["status"], status.text),
            failed_step=None if finished else st["failed_step"],
            failed_time=None if finished else st["failed_step"] * h,
            steps=st["steps"],
            newton_iterations=st["newton_iterations"],
            contact_solves=st["contact_solves"],
            failed_steps=0 if finished else 1,
            compile_time=compile_time,
            loop_time=loop,
            max_penetration=st["max_penetration"],
            max_complementarity_residual=st["max_complementarity"],
            **run_output_fields(peaks, plan),
            summary_rows=summary_rows,
            extra=extra,
        )


def run_nonsmooth(
    scene: Scene, motion: SupportMotion | None = None, *, raise_on_failure: bool = False, **options
):
    """Run the nonsmooth engine on ``scene`` (keywords of :meth:`NonsmoothEngine._run`)."""
    return NonsmoothEngine().run(scene, None, motion, raise_on_failure=raise_on_failure, **options)

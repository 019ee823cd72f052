"""The one table of contact laws and friction models: every dispatch on a law reads it.

Each normal contact law (``scene.contact.law``) and friction model (``scene.contact.
friction_mode``) is one row: its name, the integer code the compiled kernels dispatch on, the
scene parameters it uses, its OpenSees counterpart or why OpenSees refuses it, how the
nonsmooth engine treats it, and its force equation as plain Python (the executable statement
of the law, against which a test runs the compiled kernel branch). Readers:

* the scene's allowed values (:data:`deckpound.models.scene.CONTACT_LAWS`, ``FRICTION_MODES``);
* the compiled kernels (:mod:`deckpound.analytic.kernels.contact_laws`: named code constants, one
  branch per law, a final branch that fails: non-finite force, never a fall-through);
* the compliance and nonsmooth engines' ``reads()`` (the "option does nothing" warnings) and
  notes;
* the OpenSees refusals (:func:`deckpound.opensees_build.model.refuse_scene`);
* the contact-law study (:func:`deckpound.compare.studies.sensitivity.law_cases`).

Adding a law: a row here (code = the next integer), its branch in
:func:`deckpound.analytic.kernels.contact_laws.normal_law` (and its recoverable energy in
``contact_stored_energy``), tests. ``tests/test_contact_law_table.py`` runs every row through
the kernel against ``force``. Importable without numba.

Units: forces kN, gaps and penetrations δ = −g ≥ 0 m, rates δ̇ = −ġ m/s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

__all__ = [
    "BILINEAR_MIN_SUBSTEPS",
    "BILINEAR_OPENSEES_REASON",
    "CONTACT_LAW_TABLE",
    "DEFAULT_FRICTION",
    "FRICTION_CODES",
    "FRICTION_MODEL_TABLE",
    "LAW_CODES",
    "RIGID_CONTACT",
    "ContactLaw",
    "FrictionModel",
    "contact_law",
    "friction_model",
]


@dataclass(frozen=True)
class ContactLaw:
    """One normal contact law.

    Attributes
    ----------
    name, code : scene value and kernel code (``contact_laws.LAW_*``).
    params : scene fields the compliance engine's force depends on.
    equation : the force law in one line (docs, messages).
    force : λ_N(δ, δ̇, p) [kN] on first loading from the open state (virgin corner; δ > 0
        closed), p the packed parameters by name (:func:`deckpound.analytic.kernels.contact_law_checks.
        law_parameters`); the executable form of ``equation`` the kernel is tested against.
    opensees : OpenSees uniaxial material expressing it, or None; opensees_refusal : the
        refusal message when None.
    rate_event : the force switches branch with the sign of ġ while closed (loading /
        unloading): the adaptive integrator locates ġ = 0 as an event.
    nonsmooth : the nonsmooth engine expresses the law (it then reads ``contact.law`` and
        ``params``); False for every compliant law: rigid contact with Newton's impact law
        replaces it there (:data:`RIGID_CONTACT`) and a non-default law is warned as ignored.
    hysteresis : d(e), the factor of δ̇/v⁻ in a Hunt–Crossley-type law
        λ = k δ^n (1 + d(e) δ̇/v⁻) (packed for the kernel), or None.
    refuse : a scene check of the law's parameters: the refusal (field, message) or None;
        :class:`deckpound.models.scene.Contact` runs it at validation.
    """

    name: str
    code: int
    params: tuple[str, ...]
    equation: str
    force: Callable[[float, float, dict], float]
    opensees: str | None = None
    opensees_refusal: str | None = None
    rate_event: bool = False
    nonsmooth: bool = False
    hysteresis: Callable[[float], float] | None = None
    refuse: Callable[[object], tuple[str, str] | None] | None = None


@dataclass(frozen=True)
class FrictionModel:
    """One tangential (friction) model; ``params`` are read only when contact.friction > 0.

    force : λ_T(λ_N, Δs, U_T, p) [kN] from an unloaded tangential state (force on the deck
    along +t). opensees / opensees_refusal / opensees_laws: the OpenSees counterpart, why it is
    refused, and the normal laws it combines with. nonsmooth : how the nonsmooth engine treats
    the model (None: it does nothing there), said in the engine's notes with
    :data:`RIGID_CONTACT`.
    """

    name: str
    code: int
    params: tuple[str, ...]
    equation: str
    force: Callable[[float, float, float, dict], float]
    opensees: str | None = None
    opensees_refusal: str | None = None
    opensees_laws: tuple[str, ...] = ()
    nonsmooth: str | None = None


def _hertz_damp(d: float, r: float, p: dict) -> float:
    return max(p["k"] * d ** p["n"] * (1.0 + p["hc"] * r / max(p["v_impact"], p["v_min"])), 0.0)


def _lankarani_nikravesh(e: float) -> float:
    # Lankarani & Nikravesh (1990), J. Mech. Des. 112: d = 3(1 − e²)/4, valid for e near 1
    return 0.75 * (1.0 - e * e)


def _flores(e: float) -> float:
    # Flores, Machado, Silva & Martins (2011), Multibody Syst. Dyn. 25: d = 8(1 − e)/(5e),
    # derived for the whole range 0 < e ≤ 1 (energy lost over the whole impact, not e → 1)
    return 8.0 * (1.0 - e) / (5.0 * e)


def _needs_positive_restitution(contact) -> tuple[str, str] | None:
    if contact.restitution <= 0.0:
        return (
            "contact.restitution",
            "the flores law needs e > 0 (its damping factor "
            "8(1 − e)/(5e) is infinite at e = 0); use hertz-damp for a fully plastic impact",
        )
    return None


def _hertzdamp(d: float, r: float, p: dict) -> float:
    # OpenSees Hertzdamp on a virgin corner: ξ = ξ_n k / δ̇ at the first closed trial when
    # approaching (δ̇ > 0), so ξ δ̇ = ξ_n k there; ξ = 0 otherwise
    return p["k"] * d ** p["n"] * (1.0 + p["hc"]) if r > 0.0 else p["k"] * d ** p["n"]


def _bilinear(d: float, r: float, p: dict) -> float:
    # first loading from the closure point: K1 up to the yield line K1 δy + K2 (δ − δy)
    return min(p["k"] * d, p["k"] * p["dy"] + p["k2"] * (d - p["dy"]))


_OPENSEES_LAWS = "use linear, kelvin-voigt, hertz, hertzdamp or bilinear"
_HERTZ_DAMP_REFUSAL = (
    "OpenSees cannot express the 'hertz-damp' law (λ = k δ^n (1 + 3(1−e²)/4 δ̇/v⁻), v⁻ the "
    "committed approach velocity before the impact, floored at 1 mm/s, λ clipped at 0): its "
    "Hertzdamp material takes v⁻ from the strain rate of the first closed Newton trial, does "
    "not clip the tensile force near separation and has no floor (SRC/material/uniaxial/"
    "Hertzdamp.cpp); law = 'hertzdamp' is that material exactly, in every engine; " + _OPENSEES_LAWS
)
_FLORES_REFUSAL = (
    "OpenSees cannot express the 'flores' law (λ = k δ^n (1 + 8(1−e)/(5e) δ̇/v⁻)): no "
    "material has it (Hertzdamp's damping is the Lankarani–Nikravesh form); " + _OPENSEES_LAWS
)
#: Fewest OpenSees sub-steps per failed step that run the 'bilinear' law (ImpactMaterial)
BILINEAR_MIN_SUBSTEPS = 1000
BILINEAR_OPENSEES_REASON = (
    "OpenSees runs the 'bilinear' law (ImpactMaterial) only with opensees.substeps >= {min} "
    "(and fallback = 'substep'): ImpactMaterial measures the strain increment of the step in "
    "which the gap closes from the last committed (open) strain, not from the gap "
    "(SRC/material/uniaxial/ImpactMaterial.cpp, setTrialStrain), so its force jumps by "
    "K1·(committed strain − gap) at closure and Newton finds no equilibrium in most closing "
    "steps; on the benchmark it fails at t = 0.84 s with 10 sub-steps and at 11.58 s with 100, "
    "while with 1000 the 20 s record completes (116 closing steps rescued); its motion is then "
    "the clone's continuous bilinear law's to ~2e-4 (peak deck x), but the jump of the "
    "closing sub-step spikes the gap force (+34 % on the first impact); got "
    "opensees.substeps = {got}"
)

#: The normal contact laws, in code order.
CONTACT_LAW_TABLE: tuple[ContactLaw, ...] = (
    # ElasticPPGap(k, Fy → ∞, −g₀): the same force and tangent (clone ≡ OpenSees to
    # round-off, `deckpound verify clone`)
    ContactLaw(
        "linear",
        0,
        ("contact.stiffness",),
        "λ = k δ for δ ≥ 0",
        lambda d, r, p: p["k"] * d,
        opensees="ElasticPPGap",
    ),
    # ViscoelasticGap(k, c, −g₀): the same force (tension allowed); its tangent is k only (no
    # damping tangent), which compliance.contact_tangent = "opensees" reproduces
    ContactLaw(
        "kelvin-voigt",
        1,
        ("contact.stiffness", "contact.restitution"),
        "λ = k δ + c δ̇ for δ > 0, c = 2ζ(e)√(k m_eff) (tension allowed unless kv_clip)",
        lambda d, r, p: p["k"] * d + p["c"] * r,
        opensees="ViscoelasticGap",
    ),
    # Hertzdamp(k, 0, −g₀, n): with ξ_n = 0 its force is k δ^n exactly; its tangent has the
    # opposite sign (contact_tangent = "opensees" reproduces it)
    ContactLaw(
        "hertz",
        2,
        ("contact.stiffness", "contact.exponent"),
        "λ = k δ^n for δ > 0",
        lambda d, r, p: p["k"] * d ** p["n"],
        opensees="Hertzdamp",
    ),
    ContactLaw(
        "hertz-damp",
        3,
        ("contact.stiffness", "contact.exponent", "contact.restitution"),
        "λ = k δ^n (1 + 3(1 − e²)/4 · δ̇/v⁻) ≥ 0, v⁻ the approach velocity",
        _hertz_damp,
        opensees_refusal=_HERTZ_DAMP_REFUSAL,
        hysteresis=_lankarani_nikravesh,
    ),
    # ImpactMaterial: only with >= BILINEAR_MIN_SUBSTEPS sub-steps (see BILINEAR_OPENSEES_REASON);
    # the clone keeps the continuous law (difference measured there)
    ContactLaw(
        "bilinear",
        4,
        ("contact.stiffness", "contact.bilinear_ratio", "contact.bilinear_yield"),
        "Muthukumar: loading K1 capped by K1 δy + K2 (δ − δy), unloading K1 floored by K2 δ",
        _bilinear,
        opensees="ImpactMaterial",
        rate_event=True,
    ),
    ContactLaw(
        "flores",
        5,
        ("contact.stiffness", "contact.exponent", "contact.restitution"),
        "λ = k δ^n (1 + 8(1 − e)/(5e) · δ̇/v⁻) ≥ 0, v⁻ the approach velocity (Flores 2011)",
        _hertz_damp,
        opensees_refusal=_FLORES_REFUSAL,
        hysteresis=_flores,
        refuse=_needs_positive_restitution,
    ),
    # Hertzdamp(k, 3(1−e²)/4, −g₀, n): the material's arithmetic in every engine
    # (deckpound.analytic.kernels.contact_laws, hertzdamp)
    ContactLaw(
        "hertzdamp",
        6,
        ("contact.stiffness", "contact.exponent", "contact.restitution"),
        "OpenSees Hertzdamp: λ = (k + ξ δ̇) δ^n, ξ = 3(1 − e²)/4 · k / v_i, v_i = δ̇ of the "
        "first closed trial of an impact (no clipping)",
        _hertzdamp,
        opensees="Hertzdamp",
        hysteresis=_lankarani_nikravesh,
    ),
)


def _slip(lam_n: float, ds: float, ut: float, p: dict) -> float:
    return -p["mu"] * lam_n * math.tanh(ut / p["v0"])


def _stick(lam_n: float, ds: float, ut: float, p: dict) -> float:
    trial = -p["kt"] * ds
    lim = p["mu"] * lam_n
    return trial if abs(trial) <= lim else math.copysign(lim, trial)


#: Why the nonsmooth engine reads no compliant law nor the slip/stick distinction.
RIGID_CONTACT = (
    "contact is rigid, so the slip/stick distinction of the compliance laws does not apply"
)
_NONSMOOTH_COULOMB = "set-valued Coulomb friction"


def _contact2d(lam_n: float, ds: float, ut: float, p: dict) -> float:
    # from the virgin element (stick point 0): ds is the total tangential displacement s
    trial = -p["kt"] * ds
    lim = p["mu"] * lam_n
    return trial if abs(trial) - lim <= 0.0 else math.copysign(lim, trial)


_STICK_REFUSAL = (
    "OpenSees cannot express 'stick' (the project's return-mapping stick law: "
    "after sliding its stick spring keeps |λ_T| = μ λ_N and it is released when "
    "the corner opens); zeroLengthContact2D resets its stick point at every "
    "sliding commit and keeps it while the corner is open: use "
    "friction_mode = 'contact2d' (that element's algorithm, also in the "
    "compliance engine)"
)

#: The friction models, in code order.
FRICTION_MODEL_TABLE: tuple[FrictionModel, ...] = (
    FrictionModel(
        "none", 0, (), "λ_T = 0", lambda lam_n, ds, ut, p: 0.0, opensees="(no tangential element)"
    ),
    FrictionModel(
        "slip",
        1,
        ("contact.slip_velocity",),
        "λ_T = −μ λ_N tanh(U_T / v₀)",
        _slip,
        opensees_refusal="OpenSees cannot express 'slip' (regularised friction without "
        "sticking); zeroLengthContact2D always has a stick spring: use "
        "friction_mode = 'contact2d'",
        nonsmooth=_NONSMOOTH_COULOMB,
    ),
    FrictionModel(
        "stick",
        2,
        ("contact.tangential_stiffness",),
        "λ_T = λ_T,n − k_t Δs, returned to |λ_T| ≤ μ λ_N; λ_T = 0 when open",
        _stick,
        opensees_refusal=_STICK_REFUSAL,
        nonsmooth=_NONSMOOTH_COULOMB,
    ),
    FrictionModel(
        "contact2d",
        3,
        ("contact.tangential_stiffness",),
        "OpenSees zeroLengthContact2D: λ_T = −k_t (s − s_p) if |k_t (s − s_p)| ≤ "
        "μ λ_N (stick) else μ λ_N sign(−(s − s_p)) (slide); s_p := s at a sliding "
        "commit, kept while open",
        _contact2d,
        opensees="zeroLengthContact2D",
        opensees_laws=("linear",),
        nonsmooth=_NONSMOOTH_COULOMB,
    ),
)

#: The friction model the package switches on when it turns friction on (paper job, friction,
#: sticking and skew studies, stress grid, ``verify clone``): OpenSees's own element, so that
#: every "with friction" comparison between the engines is the same algorithm in OpenSees and
#: in the clone (the nonsmooth engine uses set-valued Coulomb friction for every model).
DEFAULT_FRICTION = "contact2d"

#: name → kernel code
LAW_CODES = {law.name: law.code for law in CONTACT_LAW_TABLE}
FRICTION_CODES = {m.name: m.code for m in FRICTION_MODEL_TABLE}


def contact_law(name: str) -> ContactLaw:
    """The row of law ``name`` (KeyError naming the valid laws otherwise)."""
    for law in CONTACT_LAW_TABLE:
        if law.name == name:
            return law
    raise KeyError(f"unknown contact law {name!r}; valid: {', '.join(LAW_CODES)}")


def friction_model(name: str) -> FrictionModel:
    """The row of friction model ``name`` (KeyError naming the valid models otherwise)."""
    for m in FRICTION_MODEL_TABLE:
        if m.name == name:
            return m
    raise KeyError(f"unknown friction model {name!r}; valid: {', '.join(FRICTION_CODES)}")


def _check_codes() -> None:
    for table in (CONTACT_LAW_TABLE, FRICTION_MODEL_TABLE):
        codes = [row.code for row in table]
        if codes != list(range(len(table))):
            raise RuntimeError(f"codes of {[r.name for r in table]} must be 0, 1, ... in order")


_check_codes()

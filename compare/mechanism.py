"""How friction acts on the deck's rotation: numbers per run, read from a result's columns.

For one result (corner positions, normals and tangents from the plan model):

* **peak excursion**: the peak |θ_d| and its time (``peak_theta``, ``t_peak``: over every step,
  :meth:`deckpound.models.result.Result.peak`) and the excursion that reaches it on the output
  rows, from the last change of sign of θ_d before the row of the largest |θ_d| to that row
  (``t_start`` …; the impulses below are integrals over the rows);
* **angular impulses about the deck centre over that excursion**, signed so that positive means
  *towards* the peak rotation: friction, J_T = sgn θ_p ∫ Σ_c (r_c × ft_c t_c) dt, and normal
  contact, J_N = sgn θ_p ∫ Σ_c (r_c × fn_c n_c) dt [kN·m·s] (r_c the corner at rest; the
  geometrically linear lever arms). J_T > 0: the friction forces drive the deck into its peak
  rotation; J_T < 0: they resist it. Given the frictionless result of the same case
  (``reference``), also J_T over *its* peak excursion, signed towards *its* peak
  (``friction_impulse_ref``): negative when friction resists the rotation that was the peak
  without friction;
* **where contact happens**: contact time per seat face (corners c1, c2 face seat 1; c3, c4
  seat 2) [s], the corners in contact at the peak and their face, and per corner its *first
  contact row* [s]: the time of the first output row at which it is in contact
  (:func:`deckpound.models.result.closure_times` on the rows). That is not the engines' gap
  closure, which they detect and count at every step (``meta["gap_closures"]``): a row-based
  time can lag it by up to one output step, hence its own name;
* **stick and slip**: the share of each corner's contact time spent sticking [-], from the
  nonsmooth engine's ``state_c*`` columns (1 stick, 2 slip) where a result has them, otherwise
  from the Coulomb limit: a contact row slips when |ft| ≥ (1 − 10⁻³) μ·fn.

Both the friction impulse and the Coulomb classification read the reported tangential force,
so they are used only where that output is usable (:func:`tangential_output`): with μ > 0, ft
stays within the Coulomb cone and is not exactly zero in more than ``ZERO_FT_SHARE`` of the
rows that carry a normal force (a frictional contact that transmits no tangential force in most
of its rows is not what the engine computed: OpenSees's zeroLengthContact2D reports ft = 0 in
about three quarters of them on the benchmark while its motion equals the compliance clone's).
Otherwise they are NaN and ``stick_source`` / ``ft_source`` say ``n/a``.
"""

from __future__ import annotations

import numpy as np

from deckpound.models.plan import plan_of
from deckpound.models.result import Result, closure_times, in_contact
from deckpound.models.scene import Scene

CONE_TOL = 1e-3
ZERO_FT_SHARE = 0.1

#: units of the columns of :func:`mechanism_row`
MECHANISM_UNITS = {
    "peak_theta": "rad",
    "t_peak": "s",
    "t_start": "s",
    "friction_impulse": "kN*m*s",
    "normal_impulse": "kN*m*s",
    "t_start_ref": "s",
    "t_peak_ref": "s",
    "friction_impulse_ref": "kN*m*s",
    "contact_seat1": "s",
    "contact_seat2": "s",
    "mu": "-",
    "ft_zero_share": "-",
    **{f"first_contact_row_c{c}": "s" for c in range(1, 5)},
    **{f"stick_share_c{c}": "-" for c in range(1, 5)},
}


def _face(corners: list) -> str:
    seats = sorted({c.seat for c in corners})
    if not seats:
        return "none"
    return "both faces" if len(seats) == 2 else f"seat {seats[0] + 1}"


def contact_moments(result: Result, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Moments about the deck centre of the tangential and of the normal contact forces on the
    deck, Σ_c r_c × f_c, at each output row [kN·m] (counter-clockwise positive)."""
    mt = np.zeros(len(result.t))
    mn = np.zeros(len(result.t))
    for c in plan_of(scene).corners:
        ft, fn = result[f"ft_{c.name}"], result[f"fn_{c.name}"]
        mt += ft * (c.x * c.tangent[1] - c.y * c.tangent[0])
        mn += fn * (c.x * c.normal[1] - c.y * c.normal[0])
    return mt, mn


NAMES = ("c1", "c2", "c3", "c4")


def tangential_output(result: Result, mu: float) -> tuple[bool, float]:
    """Whether the reported tangential forces are usable (see the module docstring), and the
    share of the rows with a normal force whose ft is exactly zero [-]."""
    fn = np.column_stack([result[f"fn_{n}"] for n in NAMES])
    ft = np.column_stack([np.abs(result[f"ft_{n}"]) for n in NAMES])
    loaded = fn > 0
    if not loaded.any():
        return True, 0.0
    zero = float(np.mean(ft[loaded] == 0.0))
    if not mu > 0:
        return True, zero
    inside = bool(np.all(ft[loaded] <= (1.0 + CONE_TOL) * mu * fn[loaded]))
    return inside and zero <= ZERO_FT_SHARE, zero


def stick_states(result: Result, mu: float) -> tuple[np.ndarray | None, str]:
    """(n, 4) contact states (0 open, 1 stick, 2 slip) and their source (``state``,
    ``coulomb`` or ``n/a``); None when they cannot be told from the result."""
    if all(f"state_{n}" in result.columns for n in NAMES):
        return np.column_stack([result[f"state_{n}"] for n in NAMES]).round(), "state"
    if not mu > 0 or not tangential_output(result, mu)[0]:
        return None, "n/a"
    closed = np.column_stack([in_contact(result.columns, n) for n in NAMES])
    fn = np.column_stack([result[f"fn_{n}"] for n in NAMES])
    ft = np.column_stack([np.abs(result[f"ft_{n}"]) for n in NAMES])
    slip = closed & (fn > 0) & (ft >= (1.0 - CONE_TOL) * mu * fn)
    return np.where(slip, 2.0, np.where(closed, 1.0, 0.0)), "coulomb"


def _integral(t: np.ndarray, x: np.ndarray) -> float:
    return float(np.sum(0.5 * (x[1:] + x[:-1]) * np.diff(t))) if len(t) > 1 else 0.0


def peak_excursion(t: np.ndarray, theta: np.ndarray) -> tuple[int, int, float]:
    """(start row, peak row, sign) of the excursion of θ that reaches its peak |θ|: from the
    last row before the peak where θ had the other sign (or zero) to the peak."""
    i = int(np.argmax(np.abs(theta))) if len(theta) else 0
    sign = 1.0 if theta[i] >= 0 else -1.0
    before = np.nonzero(sign * theta[:i] <= 0.0)[0]
    return (int(before[-1]) if len(before) else 0), i, sign


def _window(t: np.ndarray, x: np.ndarray, t0: float, t1: float) -> float:
    keep = (t >= t0 - 1e-12) & (t <= t1 + 1e-12)
    return _integral(t[keep], x[keep])


def mechanism_row(
    result: Result, scene: Scene, mu: float | None = None, reference: Result | None = None
) -> dict:
    """The numbers of the module docstring for one result (``mu`` defaults to the scene's;
    ``reference``: the frictionless result of the same case)."""
    mu = scene.contact.friction if mu is None else mu
    t, th = result.t, result["deck_theta"]
    corners = plan_of(scene).corners
    row: dict = {"mu": mu}
    i0, i, sign = peak_excursion(t, th)
    mt, mn = contact_moments(result, scene)
    usable, zero = tangential_output(result, mu)
    nan = float("nan")
    row.update(
        peak_theta=result.peak("deck_theta"),
        t_peak=result.peak_time("deck_theta"),
        t_start=float(t[i0]),
        friction_impulse=sign * _integral(t[i0 : i + 1], mt[i0 : i + 1]) if usable else nan,
        normal_impulse=sign * _integral(t[i0 : i + 1], mn[i0 : i + 1]),
        ft_source="reported" if usable else "n/a",
        ft_zero_share=zero,
        t_start_ref=nan,
        t_peak_ref=nan,
        friction_impulse_ref=nan,
    )
    if reference is not None and len(reference.t):
        j0, j, sign0 = peak_excursion(reference.t, reference["deck_theta"])
        t0, t1 = float(reference.t[j0]), float(reference.t[j])
        row.update(
            t_start_ref=t0,
            t_peak_ref=t1,
            friction_impulse_ref=sign0 * _window(t, mt, t0, t1) if usable else nan,
        )
    closed = {c.name: in_contact(result.columns, c.name) for c in corners}
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    for seat in (0, 1):
        rows = np.zeros(len(t), dtype=bool)
        for c in corners:
            if c.seat == seat:
                rows |= closed[c.name]
        row[f"contact_seat{seat + 1}"] = dt * int(rows.sum())
    window = slice(max(i - 1, 0), i + 1)
    at_peak = [c for c in corners if closed[c.name][window].any()]
    row["corners_at_peak"] = "+".join(c.name for c in at_peak) or "none"
    row["face_at_peak"] = _face(at_peak)
    for c in corners:
        times = closure_times(t, result[f"gap_{c.name}"], result[f"fn_{c.name}"])
        row[f"first_contact_row_{c.name}"] = float(times[0]) if len(times) else float("nan")
    states, source = stick_states(result, mu)
    row["stick_source"] = source
    for k, c in enumerate(corners):
        share = float("nan")
        if states is not None and mu > 0:
            touching = states[:, k] > 0
            if touching.any():
                share = float(np.mean(states[touching, k] == 1))
        row[f"stick_share_{c.name}"] = share
    return row

"""Skewed decks (issue 15): the skew study and the clone-vs-OpenSees check with skew.

Study ``skew`` (``deckpound study skew SCENE``; registered in :data:`.studies.STUDIES`): the
scene at skew φ = 0, 15, 30, 45, 60° (``quick``: 0, 30, 60°), without friction and with
μ = :data:`FRICTION` (the sticking law ``stick`` for the compliance engines — OpenSees
``zeroLengthContact2D`` and the clone's elastic-plastic stick spring — and set-valued Coulomb
friction for the nonsmooth engine), for every registered engine that can express the case
(an engine that refuses it at validation is left out, its reason in the log). The penalty
engines share one time step, the compliance engine's contact-resolving step
(:func:`.studies.contact_step`), so that OpenSees and its clone run the same discrete model.

Table (:func:`skew_row`, one row per case), besides the common headline numbers
(:func:`.studies.case_row`: ``peak_theta`` [rad], ``peak_y_rel`` = peak |deck_y_rel| [m], ...):

* ``first_corner`` — the corner that strikes first (first output row in contact, see
  :func:`deckpound.models.result.in_contact`), with ``first_time`` [s];
* ``share_acute`` — the share of the total normal impulse ∫f_N dt carried by corners c1 and c4,
  the acute corners of a deck skewed by φ > 0 (x = ±L/2 + y tan φ puts them furthest out);
  c2 and c3 are the obtuse ones. For φ = 0 the same corners (no longer acute);
* ``stick_share``, ``slip_share`` — of the output rows with a corner in contact (summed over
  corners), the share sticking and slipping: the nonsmooth engine's ``state_c*`` (1 stick,
  2 slip); for the penalty engines a contact row slips when |f_T| ≥ (1 − 1e-6) μ f_N, else it
  sticks (NaN without friction). ``stick_source`` says which. An engine whose sampled f_T is
  exactly 0 on more than 1 % of its loaded rows does not report the step's friction force
  (OpenSees' zeroLengthContact2D moves its stick point to the current slip at the commit of a
  sliding step, so the force read after the step is 0): its shares are NaN and
  ``stick_source`` says why — an elastic-plastic stick law under load is never exactly 0
  otherwise.

Figure (:func:`skew_figure`): peak deck rotation and peak transverse displacement relative to
the tables against φ, one line per engine × friction.

:func:`verify_skew` runs :func:`deckpound.compare.verify.clone.verify_clone` at φ = 30° and 45° on a
scene (the straight deck's tolerances: 1e-8 of each displacement/force column's peak,
velocities 1e-8) and returns one row per angle, ready to join a ``verify clone`` matrix.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd

from deckpound.compare.cases import Case, engine_expresses
from deckpound.compare.engines import engine_names, engine_style, get_engine
from deckpound.compare.studies.case_rows import case_row, contact_step
from deckpound.compare.verify.clone import verify_clone
from deckpound.models.contact_laws_table import DEFAULT_FRICTION
from deckpound.models.plan import CORNER_NAMES
from deckpound.models.result import Result, in_contact
from deckpound.models.scene import Scene
from deckpound.models.scene_io import modified

__all__ = [
    "FRICTION",
    "SKEWS",
    "SKEWS_QUICK",
    "SKEW_VERIFY_ANGLES",
    "skew_cases",
    "skew_figure",
    "skew_headlines",
    "skew_row",
    "verify_skew",
]


#: skew angles of the study [degrees]
SKEWS = (0.0, 15.0, 30.0, 45.0, 60.0)
SKEWS_QUICK = (0.0, 30.0, 60.0)
#: friction coefficient of the "with friction" cases (the paper's friction study value)
FRICTION = 0.2
#: the corners that are acute when φ > 0 (c1 at (−L/2 − W/2 tan φ, −W/2), c4 mirrored)
ACUTE = ("c1", "c4")
#: skew angles of the clone-vs-OpenSees check [degrees]
SKEW_VERIFY_ANGLES = (30.0, 45.0)
#: tolerances of the check: the straight deck's (``tests/test_clone_vs_opensees.py``). 1e-8
#: since issue 12: with the seats damped by their dashpots only (damping.members = bents) the
#: light seats ring more and the contact forces carry ~2e-9 of round-off (4e-10 before)
VERIFY_TOLERANCE = 1e-8
VERIFY_VELOCITY_TOLERANCE = 1e-8


# -- cases --------------------------------------------------------------------------------------


def skew_cases(scene: Scene, quick: bool = False) -> list[Case]:
    """φ × friction × engine (module docstring)."""

    cases = []
    for phi in SKEWS_QUICK if quick else SKEWS:
        for mu in (0.0, FRICTION):
            mode = DEFAULT_FRICTION if mu > 0 else "none"
            base = modified(
                scene,
                f"deck.skew={phi!r}",
                f"contact.friction={mu!r}",
                f"contact.friction_mode={mode}",
            )
            dt = contact_step(base)
            penalty = modified(base, f"compliance.dt={dt!r}", f"opensees.dt={dt!r}")
            for engine in engine_names():
                rigid = not get_engine(engine).compliant_contact  # no contact step to resolve
                sc = base if rigid else penalty
                if not engine_expresses(engine, sc, "skew"):
                    continue
                friction = "none" if mu == 0 else "Coulomb" if rigid else DEFAULT_FRICTION
                cases.append(
                    Case(
                        f"{engine} skew={phi:g} mu={mu:g}",
                        engine,
                        sc,
                        {"skew": phi, "mu": mu, "friction": friction},
                    )
                )
    return cases


# -- table --------------------------------------------------------------------------------------


def _impulses(result: Result) -> dict[str, float]:
    """∫ f_N dt per corner over the output rows [kN·s] (trapezoidal)."""
    dt = np.diff(result.t)
    out = {}
    for c in CORNER_NAMES:
        f = np.clip(result[f"fn_{c}"], 0.0, None)
        out[c] = float(np.sum(0.5 * (f[1:] + f[:-1]) * dt))
    return out


def first_strike(result: Result) -> tuple[str, float]:
    """(corner, time [s]) of the first output row with a corner in contact; ("none", NaN)."""
    best = ("none", float("nan"))
    for c in CORNER_NAMES:
        closed = in_contact(result.columns, c)
        if closed is not None and closed.any():
            k = int(np.argmax(closed))
            if best[0] == "none" or result.t[k] < best[1]:
                best = (c, float(result.t[k]))
    return best


def stick_slip_shares(result: Result, mu: float) -> tuple[float, float, str]:
    """(stick share, slip share, source) of the contact rows (module docstring); NaN without
    friction or contact, or when the engine's f_T is not the step's friction force."""
    nan = float("nan")
    if mu <= 0.0:
        return nan, nan, "no friction"
    stick = slip = zero = 0
    states = all(f"state_{c}" in result.columns for c in CORNER_NAMES)
    for c in CORNER_NAMES:
        if states:
            s = result[f"state_{c}"]
            stick += int(np.count_nonzero(s == 1))
            slip += int(np.count_nonzero(s == 2))
            continue
        fn, ft = result[f"fn_{c}"], result[f"ft_{c}"]
        on = fn > 0.0
        sliding = np.abs(ft) >= (1.0 - 1e-6) * mu * fn
        stick += int(np.count_nonzero(on & ~sliding))
        slip += int(np.count_nonzero(on & sliding))
        zero += int(np.count_nonzero(on & (ft == 0.0)))
    total = stick + slip
    if total == 0:
        return nan, nan, "no contact"
    if states:
        return stick / total, slip / total, "state_c*"
    if zero > 0.01 * total:
        return (
            nan,
            nan,
            (
                f"n/a: f_T = 0 on {100 * zero / total:.0f} % of loaded rows "
                "(reset at a sliding commit)"
            ),
        )
    return stick / total, slip / total, "|f_T| vs mu f_N"


def skew_row(case: Case, result: Result) -> dict:
    """One table row: the common headline numbers plus the mechanism (module docstring)."""

    row = case_row(case, result)
    corner, when = first_strike(result)
    imp = _impulses(result)
    total = sum(imp.values())
    stick, slip, source = stick_slip_shares(result, case.params["mu"])
    row.update(
        first_corner=corner,
        first_time=when,
        share_acute=sum(imp[c] for c in ACUTE) / total if total > 0 else float("nan"),
        stick_share=stick,
        slip_share=slip,
        stick_source=source,
    )
    return row


# -- figure -------------------------------------------------------------------------------------


#: the table column of the peak transverse deck displacement relative to the tables
Y_PEAK = "peak_y_rel"


def skew_figure(
    study,
    scene: Scene,
    cases,
    results,
    table: pd.DataFrame,
    path: str | Path,
    formats: tuple[str, ...] = (),
    subtitle: str = "",
) -> list[Path]:
    """Peak deck rotation (left) and peak transverse deck displacement relative to the tables
    (right) against the skew angle; one line per engine × friction (an engine's case with
    friction: hollow markers and another line style,
    :func:`~deckpound.compare.report.style.series_styles`)."""
    from deckpound.compare.report.style import new_figure, outside_legend, save, series_styles

    fig, axes = new_figure(1, 2, width=10.0, height=3.4)
    groups = [
        (engine, mu, g.sort_values("skew"))
        for (engine, mu), g in table.groupby(["engine", "mu"], sort=False)
    ]
    labels = [
        f"{engine_style(engine).get('label', engine)}, "
        + ("no friction" if mu == 0 else f"μ = {mu:g} ({g['friction'].iloc[0]})")
        for engine, mu, g in groups
    ]
    engines = [engine if engine in engine_names() else None for engine, _, _ in groups]
    for (_, _, g), st in zip(groups, series_styles(labels, engines)):
        for ax, q in zip(axes[0], ("peak_theta", Y_PEAK)):
            ax.plot(g["skew"], 1e3 * g[q], **st)
    axes[0, 0].set_ylabel("peak deck rotation θ_d [mrad]")
    axes[0, 1].set_ylabel("peak transverse y_d rel. tables [mm]")
    for ax in axes[0]:
        ax.set_xlabel("skew angle φ [°]")
        ax.set_xticks(sorted(table["skew"].unique()))
    axes[0, 0].set_title(study.title if study is not None else "skew")
    if subtitle:
        axes[0, 1].set_title(subtitle, fontsize=7)
    outside_legend(axes[0, 1])
    return save(fig, path, scene.name, formats)


# -- words --------------------------------------------------------------------------------------


def skew_headlines(table: pd.DataFrame) -> list[str]:
    """The mechanism in words, from the table's numbers (one sentence per engine × friction
    and one on the first strike)."""
    out = []
    for (engine, mu), g in table.groupby(["engine", "mu"], sort=False):
        g = g.sort_values("skew").set_index("skew")
        first, last = g.index[0], g.index[-1]
        peak_at = g["peak_theta"].idxmax()
        text = (
            f"{engine}, {'no friction' if mu == 0 else f'μ = {mu:g}'}: peak rotation "
            f"{1e3 * g.loc[first, 'peak_theta']:.3g} mrad at φ = {first:g}° → "
            f"{1e3 * g.loc[last, 'peak_theta']:.3g} mrad at {last:g}° (largest "
            f"{1e3 * g['peak_theta'].max():.3g} mrad at {peak_at:g}°); peak y rel. tables "
            f"{1e3 * g.loc[first, Y_PEAK]:.3g} → {1e3 * g.loc[last, Y_PEAK]:.3g} mm; "
            f"acute corners c1+c4 carry "
            + ", ".join(f"{100 * s:.0f} %" for s in g["share_acute"])
            + " of the impulse"
        )
        if mu > 0 and g["stick_share"].notna().any():
            text += " (stick share " + ", ".join(f"{100 * s:.0f} %" for s in g["stick_share"]) + ")"
        elif mu > 0:
            text += f" (stick share {g['stick_source'].iloc[0]})"
        out.append(text + " over φ = " + ", ".join(f"{p:g}" for p in g.index) + "°.")
    firsts = table.groupby("skew")["first_corner"].agg(lambda s: "/".join(sorted(set(s))))
    out.append(
        "First corner to strike, per φ: "
        + "; ".join(f"{p:g}°: {c}" for p, c in firsts.items())
        + "."
    )
    return out


# -- clone vs OpenSees ------------------------------------------------------------------------


def verify_skew(
    scene: Scene, angles=SKEW_VERIFY_ANGLES, *, duration: float | None = 5.0, motion=None
) -> list[dict]:
    """:func:`~deckpound.compare.verify.clone.verify_clone` of ``scene`` at each skew angle.

    Returns one dict per angle: ``skew`` [°], ``worst`` (column, deviation / column peak),
    ``worst_velocity``, ``iterations`` and ``speed_ratio`` of verify_clone, and ``ok`` (both
    engines succeeded and the deviations are within :data:`VERIFY_TOLERANCE` /
    :data:`VERIFY_VELOCITY_TOLERANCE`).
    """

    rows = []
    for phi in angles:
        sc = modified(scene, f"deck.skew={phi!r}")
        if duration is not None:
            sc = sc.replace(run=dataclasses.replace(sc.run, duration=duration))
        rep = verify_clone(sc, motion)
        ok = (
            set(rep["status"].values()) == {"success"}
            and rep["worst"][1] <= VERIFY_TOLERANCE
            and rep["worst_velocity"][1] <= VERIFY_VELOCITY_TOLERANCE
        )
        rows.append(
            {
                "skew": phi,
                "worst": rep["worst"],
                "worst_velocity": rep["worst_velocity"],
                "iterations": rep["iterations"],
                "speed_ratio": rep["speed_ratio"],
                "us_per_step": rep["us_per_step"],
                "ok": ok,
            }
        )
    return rows

"""The report's friction and mechanism sentences, generated from its tables.

The friction effect along the sequence and in a study (peak rotation with μ against μ = 0,
read against :data:`deckpound.compare.report_text.TOL`), and the mechanism behind a peak
(excursion, friction impulse, gap closures) — the same rules as :mod:`.report_text`: every
number and direction comes from a table (``tests/test_report_text.py``).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .report_text import (
    TOL,
    at_mu,
    direction,
    effect_clauses,
    engine_label,
    friction_model_text,
    in_runs,
    join,
    num,
    runs_text,
    short,
)

# -- friction along the sequence -----------------------------------------------------------


def friction_effect(seq: pd.DataFrame) -> pd.DataFrame:
    """Per engine and run: peak rotation without (μ = 0) and with friction, their ratio and the
    direction of the change. ``seq`` is the sequence table (columns run, pga, engine, mu,
    friction_mode, peak_theta, status)."""
    rows = []
    for (engine, run), g in seq.groupby(["engine", "run"], sort=False):
        base = g[g["mu"] == 0]
        for _, r in g[g["mu"] > 0].iterrows():
            t0 = float(base["peak_theta"].iloc[0]) if len(base) else float("nan")
            ok = (r["status"] == "success") and len(base) and base["status"].iloc[0] == "success"
            ratio = r["peak_theta"] / t0 if ok and t0 > 0 else float("nan")
            rows.append(
                {
                    "engine": engine,
                    "run": int(run),
                    "pga": r["pga"],
                    "mu": r["mu"],
                    "friction_mode": r["friction_mode"],
                    "peak_theta_0": t0,
                    "peak_theta_mu": r["peak_theta"],
                    "ratio": ratio,
                    "direction": direction(ratio),
                }
            )
    return pd.DataFrame(rows)


def sequence_friction_sentences(effect: pd.DataFrame) -> list[str]:
    """One sentence per engine: where along the sequence friction raises or lowers the peak
    rotation and by how much."""
    out = []
    for engine, g in effect.groupby("engine", sort=False):
        for (mu, mode), h in g.groupby(["mu", "friction_mode"], sort=False):
            items = list(zip(h["run"], h["ratio"]))
            out.append(
                f"{engine_label(engine)}: friction ({friction_model_text(mu, mode)}) "
                f"{effect_clauses(items, in_runs)}."
            )
    return out


# -- friction in a study (one start state) ----------------------------------------------------


def study_friction_effect(table: pd.DataFrame) -> pd.DataFrame:
    """Per engine and μ > 0 of a friction-study table: ratio to the same engine's μ = 0 case."""
    rows = []
    for engine, g in table.groupby("engine", sort=False):
        base = g[g["mu"] == 0]
        t0 = float(base["peak_theta"].iloc[0]) if len(base) else float("nan")
        for _, r in g[g["mu"] > 0].iterrows():
            ok = r["status"] == "success" and len(base) and base["status"].iloc[0] == "success"
            ratio = r["peak_theta"] / t0 if ok and t0 > 0 else float("nan")
            rows.append(
                {
                    "engine": engine,
                    "mu": r["mu"],
                    "state": r.get("state", ""),
                    "peak_theta_0": t0,
                    "peak_theta_mu": r["peak_theta"],
                    "ratio": ratio,
                    "direction": direction(ratio),
                }
            )
    return pd.DataFrame(rows)


def study_friction_sentences(effect: pd.DataFrame) -> list[str]:
    """One sentence per engine: the friction study's direction and size per μ."""
    out = []
    for engine, g in effect.groupby("engine", sort=False):
        g = g.sort_values("mu")
        items = list(zip(g["mu"], g["ratio"]))
        base = g["peak_theta_0"].iloc[0]
        out.append(
            f"{engine_label(engine)} (μ = 0: {num(1e3 * base)} mrad): friction "
            f"{effect_clauses(items, at_mu)}."
        )
    return out


# -- the mechanism ------------------------------------------------------------------------------


def _corner_face(corner: str) -> str:
    return "seat 1" if corner in ("c1", "c2") else "seat 2"


def mechanism_sentence(row: pd.Series, where: str) -> str:
    """What one frictional result shows: the peak excursion, the friction and normal angular
    impulses over it, the corners in contact at the peak, stick shares and first closures."""
    label = engine_label(row["engine"])
    s = (
        f"{label}, {where} (μ = {short(row['mu'])}): the peak rotation "
        f"{num(1e3 * row['peak_theta'])} mrad at t = {row['t_peak']:.2f} s ends an excursion "
        f"that began at t = {row['t_start']:.2f} s"
    )
    jt, jn = row["friction_impulse"], row["normal_impulse"]
    if np.isfinite(jt):
        s += (
            f"; over it the friction forces' angular impulse about the deck centre is "
            f"{jt:+.3g} kN·m·s ({'towards' if jt > 0 else 'against'} the peak rotation), "
            f"the normal forces' {jn:+.3g} kN·m·s"
        )
        jr = row.get("friction_impulse_ref", float("nan"))
        if np.isfinite(jr):
            s += (
                f"; over the excursion that is the peak without friction (t = "
                f"{row['t_start_ref']:.2f}–{row['t_peak_ref']:.2f} s) the friction impulse is "
                f"{jr:+.3g} kN·m·s ({'with' if jr > 0 else 'against'} that rotation)"
            )
    else:
        s += (
            f"; its reported tangential forces are zero in {100 * row['ft_zero_share']:.0f} % "
            "of the rows with a normal force, so no friction impulse is read from them"
        )
    corners = row["corners_at_peak"]
    if corners == "none":
        s += ". No corner is in contact at the peak"
    else:
        s += f". At the peak {corners.replace('+', ' and ')} ({row['face_at_peak']}) in contact"
    shares = {c: row[f"stick_share_{c}"] for c in ("c1", "c2", "c3", "c4")}
    known = {c: v for c, v in shares.items() if np.isfinite(v)}
    if known:
        src = "state_c*" if row["stick_source"] == "state" else "|ft| against μ·fn"
        s += (
            "; share of contact time sticking ("
            + src
            + "): "
            + ", ".join(f"{c} {100 * v:.0f} %" for c, v in known.items())
        )
    firsts = {c: row[f"first_closure_{c}"] for c in ("c1", "c2", "c3", "c4")}
    closed = {c: t for c, t in firsts.items() if np.isfinite(t)}
    if closed:
        t1 = min(closed.values())
        first = [c for c, t in closed.items() if t <= t1 + 1e-9]
        faces = join(sorted({_corner_face(c) for c in first}))
        s += f"; the gaps close first at {join(first)} ({faces}) at t = {t1:.2f} s"
    c1, c2 = row["contact_seat1"], row["contact_seat2"]
    if c1 + c2 > 0:
        s += (
            f"; {100 * c1 / (c1 + c2):.0f} % of the face contact time is at seat 1 "
            f"({c1:.2f} s against {c2:.2f} s at seat 2)"
        )
    return s + "."


def impulse_agreement_sentences(effect: pd.DataFrame, mech: pd.DataFrame) -> list[str]:
    """Per engine: do the friction impulses explain the directions of the friction effect
    along the sequence? Where friction raises the peak, the test is the impulse over the new
    peak's excursion (> 0: friction drives it); where it lowers the peak, the impulse over the
    excursion that was the peak without friction (< 0: friction resists it). ``mech`` holds
    the sequence's rows (run, engine, mu, friction_impulse, friction_impulse_ref)."""
    out = []
    for engine, g in effect.groupby("engine", sort=False):
        m = mech[(mech["engine"] == engine) & (mech["mu"] > 0)].set_index("run")
        changed = g[g["direction"].isin(["raises", "lowers"])]
        agree, disagree, unknown = [], [], []
        for _, r in changed.iterrows():
            raises = r["direction"] == "raises"
            col = "friction_impulse" if raises else "friction_impulse_ref"
            j = m[col].get(r["run"], float("nan")) if col in m else float("nan")
            if not np.isfinite(j):
                unknown.append(r["run"])
            elif (j > 0) == raises:
                agree.append(r["run"])
            else:
                disagree.append(r["run"])
        if not len(changed):
            continue
        label = engine_label(engine)
        if unknown and not agree and not disagree:
            out.append(f"{label}: the friction impulse cannot be read from its output.")
            continue
        n = len(agree) + len(disagree)
        s = (
            f"{label}: of the {n} run(s) where friction changes the peak rotation by more than "
            f"{short(100 * TOL)} %, the friction impulse explains the change in {len(agree)}: "
            "it drives the new peak where friction raises it and resists the frictionless "
            "peak's excursion where friction lowers it"
        )
        s += f" ({runs_text(agree)})" if agree else ""
        s += f"; it does not {in_runs(disagree)}" if disagree else ""
        s += f"; {runs_text(unknown)} cannot be read" if unknown else ""
        out.append(s + ".")
    return out

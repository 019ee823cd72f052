"""The report's sentences, generated from its tables: no number or direction is typed in.

The sequence and the studies, the friction effect (peak rotation with μ against μ = 0) and the
mechanism behind a peak (excursion, friction impulse) alike; forces, their moments and impulses
in the report's units (:data:`~.render.CONTACT_FORCE`).

Every function here takes tables (pandas frames of the report's own CSV tables) and returns
sentences; changing a table changes the sentences (``tests/test_report_text.py``). The
direction of an effect is the ratio of two peak rotations read against ``TOL``: above 1 + TOL
"raises", below 1 − TOL "lowers", in between "changes it by less than TOL".
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from deckpound.compare.engines import engine_names, engine_style
from deckpound.compare.report.render import CONTACT_FORCE

TOL = 0.02


def engine_label(engine: str) -> str:
    """An engine's name in prose (its registry label; the name itself if unregistered)."""

    return engine_style(engine)["label"] if engine in engine_names() else engine


def num(x: float, digits: int = 3) -> str:
    """A number with ``digits`` significant digits (no exponent for ordinary magnitudes)."""
    if x is None or not np.isfinite(x):
        return "n/a"
    if x == 0:
        return "0"
    mag = math.floor(math.log10(abs(x)))
    decimals = max(digits - 1 - mag, 0)
    return f"{x:.{decimals}f}"


def ratio_text(lo: float, hi: float | None = None) -> str:
    """``×2.56`` or the range ``×0.757–0.955``."""
    if hi is None or num(lo) == num(hi):
        return f"×{num(lo)}"
    return f"×{num(lo)}–{num(hi)}"


def direction(ratio: float, tol: float = TOL) -> str:
    if not np.isfinite(ratio):
        return "undetermined"
    if ratio > 1.0 + tol:
        return "raises"
    if ratio < 1.0 - tol:
        return "lowers"
    return "unchanged"


def runs_text(runs: list[int]) -> str:
    """``run 5``, ``runs 6–7``, ``runs 1–2 and 4``: consecutive runs joined by a dash."""
    runs = sorted(int(r) for r in runs)
    groups: list[list[int]] = []
    for r in runs:
        if groups and r == groups[-1][-1] + 1:
            groups[-1].append(r)
        else:
            groups.append([r])
    parts = [f"{g[0]}" if len(g) == 1 else f"{g[0]}–{g[-1]}" for g in groups]
    word = "run" if len(runs) == 1 else "runs"
    return f"{word} {join(parts)}"


def join(parts: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    if len(parts) <= 1:
        return "".join(parts)
    return ", ".join(parts[:-1]) + " and " + parts[-1]


def short(x: float) -> str:
    """A parameter value as given (``0.2``, ``1e+06``)."""
    return f"{x:g}"


def in_runs(runs: list[int]) -> str:
    return f"in {runs_text(runs)}"


def at_mu(mus: list[float]) -> str:
    return "at μ = " + join([short(m) for m in mus])


def effect_clauses(items: list[tuple[object, float]], keys_text, tol: float = TOL) -> str:
    """Clauses "raises the peak rotation in <keys> (×…), lowers it in <keys> (×…) and changes
    it by less than 2 % in <keys>" for (key, ratio) pairs; ``keys_text`` renders a list of keys
    with its preposition (:func:`in_runs`, :func:`at_mu`)."""
    by: dict[str, list[tuple[object, float]]] = {
        "raises": [],
        "lowers": [],
        "unchanged": [],
        "undetermined": [],
    }
    for key, ratio in items:
        by[direction(ratio, tol)].append((key, ratio))
    clauses = []
    for word in ("raises", "lowers"):
        if by[word]:
            ratios = [r for _, r in by[word]]
            obj = "the peak rotation" if not clauses else "it"
            clauses.append(
                f"{word} {obj} {keys_text([k for k, _ in by[word]])} "
                f"({ratio_text(min(ratios), max(ratios))})"
            )
    if by["unchanged"]:
        obj = "the peak rotation" if not clauses else "it"
        clauses.append(
            f"changes {obj} by less than {short(100 * tol)} % "
            f"{keys_text([k for k, _ in by['unchanged']])}"
        )
    if by["undetermined"]:
        clauses.append(
            f"cannot be judged {keys_text([k for k, _ in by['undetermined']])} (a case failed)"
        )
    return join(clauses)


def friction_model_text(mu: float, mode: str) -> str:
    how = {
        "stick": "with sticking",
        "contact2d": "with sticking, OpenSees's zeroLengthContact2D algorithm",
        "slip": "sliding only, no sticking",
    }.get(mode, mode)
    return f"μ = {short(mu)}, {how}"


# -- start states, studies -------------------------------------------------------------------


def state_name(label: str) -> str:
    """``the virgin state`` or ``the state carried into run 7``."""
    if label.startswith("run") and label[3:].isdigit():
        return f"the state carried into run {label[3:]}"
    return f"the {label} state"


def state_sentence(state) -> str:
    """The start state of a study in words (a :class:`~.studies.StartState`)."""
    sc = state.scene
    gaps = (
        f"gaps {1e3 * sc.seats[0].gap:.2f} mm at seat 1 and {1e3 * sc.seats[1].gap:.2f} mm "
        "at seat 2"
    )
    pga = f"excitation at {short(sc.excitation.pga)} g transverse"
    if not state.carried:
        return (
            f"Starts from the virgin state: the scene as given ({gaps}, bent stiffness as "
            f"given, {pga})."
        )
    ratios = state.stiffness_ratios()
    prior = "no earlier run" if state.run == 1 else runs_text(list(range(1, state.run)))
    return (
        f"Starts from the state carried into run {state.run} by the {state.engine} "
        f"sequence (after {prior}): {gaps}, bent stiffness {100 * min(ratios):.0f}–"
        f"{100 * max(ratios):.0f} % of the scene's, {pga}."
    )


def study_spread_sentence(table: pd.DataFrame) -> str:
    """Lowest and highest peak rotation over a study's cases, and their spread."""
    ok = table[table["status"] == "success"]
    if not len(ok):
        return "No case of this study finished."
    lo, hi = ok.loc[ok["peak_theta"].idxmin()], ok.loc[ok["peak_theta"].idxmax()]
    spread = (hi["peak_theta"] / lo["peak_theta"] - 1.0) if lo["peak_theta"] > 0 else np.nan
    s = (
        f"Peak rotation from {num(1e3 * lo['peak_theta'])} mrad ({lo['label']}) to "
        f"{num(1e3 * hi['peak_theta'])} mrad ({hi['label']}), a spread of "
        f"{num(100 * spread, 2)} % of the lowest"
    )
    return s + left_out_clause(table) + "."


def left_out_clause(table: pd.DataFrame) -> str:
    """ "; 2 case(s) doubtful (…), 1 failed: left out" for the cases a headline does not use:
    a doubtful case finished but failed a quality check (energy created at a contact), so its
    peaks are not quoted; the study table still lists it with its status."""
    status = table["status"] if "status" in table else pd.Series([], dtype=object)
    doubtful = int((status == "doubtful").sum())
    unseated = int((status == "unseated").sum())
    failed = int((~status.isin(["success", "doubtful", "unseated"])).sum())
    parts = []
    if doubtful:
        parts.append(f"{doubtful} case(s) doubtful (energy created at a contact)")
    if unseated:
        parts.append(f"{unseated} unseated (a corner lost its seat; the run stops there)")
    if failed:
        parts.append(f"{failed} failed")
    return "; " + ", ".join(parts) + ": left out" if parts else ""


def state_comparison_sentence(carried: pd.DataFrame, virgin: pd.DataFrame, run: int) -> str:
    """Peak rotations from the carried state against the virgin state's, case by case."""
    both = carried.merge(virgin, on="label", suffixes=("_c", "_v"))
    both = both[(both["status_c"] == "success") & (both["status_v"] == "success")]
    if not len(both):
        return ""
    r = both["peak_theta_c"] / both["peak_theta_v"]
    return (
        f"From the state carried into run {run}, the peak rotations are "
        f"{ratio_text(r.min(), r.max())} of the virgin state's for the same cases."
    )


# -- headline ----------------------------------------------------------------------------------


def _by_engine_clauses(items: list[tuple[str, float]]) -> str:
    return effect_clauses(items, lambda ks: "in " + join([engine_label(k) for k in ks]))


def headline_sentences(
    seq: pd.DataFrame,
    effect: pd.DataFrame,
    strongest: int,
    reference: str,
    metrics: pd.DataFrame | None = None,
    virgin: pd.DataFrame | None = None,
) -> list[str]:
    """The paper's comparison in words: the strongest run's peak rotations per engine with and
    without friction, the direction of friction's effect there and (``virgin``: the friction
    study's effect table from the virgin state) from the scene as given, the engines' agreement
    with the reference (``metrics``), and the first run in which the gaps close."""
    out = []
    last = seq[seq["run"] == strongest]
    if not len(last):
        return [f"The sequence did not reach its strongest run (run {strongest})."]
    ref = last[(last["engine"] == reference) & (last["mu"] == 0)]
    ref_theta = float(ref["peak_theta"].iloc[0]) if len(ref) else float("nan")
    for with_friction in (False, True):
        rows = last[(last["mu"] > 0) == with_friction]
        if not len(rows):
            continue
        parts = []
        for _, r in rows.iterrows():
            p = f"{engine_label(r['engine'])} {num(1e3 * r['peak_theta'])} mrad"
            if not with_friction and r["engine"] != reference and np.isfinite(ref_theta):
                p += f" ({ratio_text(r['peak_theta'] / ref_theta)} of {engine_label(reference)})"
            parts.append(p)
        what = (
            "without friction"
            if not with_friction
            else "with friction ("
            + friction_model_text(rows["mu"].iloc[0], rows["friction_mode"].iloc[0])
            + ")"
        )
        lead = (
            f"Strongest run (run {strongest}, {short(rows['pga'].iloc[0])} g transverse "
            "label): peak deck rotation "
            if not out
            else "With "
        )
        if with_friction and out:
            what = what.replace("with friction", "friction", 1)
        out.append(lead + f"{what}: " + "; ".join(parts) + ".")
    strong = effect[effect["run"] == strongest] if len(effect) else effect
    if len(strong):
        items = list(zip(strong["engine"], strong["ratio"]))
        out.append(f"In that run friction {_by_engine_clauses(items)}.")
    if virgin is not None and len(virgin):
        mu = strong["mu"].iloc[0] if len(strong) else virgin["mu"].min()
        v = virgin[np.isclose(virgin["mu"], mu)]
        if len(v):
            s = (
                f"From the virgin state (the scene as given, friction study at μ = {short(mu)}) "
                f"friction {_by_engine_clauses(list(zip(v['engine'], v['ratio'])))}"
            )
            if (
                len(strong)
                and set(v["direction"]) & {"raises", "lowers"}
                and not set(v["direction"]) & set(strong["direction"])
            ):
                s += ": the opposite of the carried state"
            out.append(s + ".")
    if metrics is not None and len(metrics):
        m = metrics[(metrics["run"] == strongest) & (metrics["quantity"] == "deck_theta")]
        if len(m):
            out.append(
                f"Against {engine_label(reference)} in run {strongest} (no friction): "
                + "; ".join(
                    f"{engine_label(r['engine'])} peak θ "
                    f"{ratio_text(r['peak_ratio'])}, NRMSE {r['nrmse']:.2g}"
                    for _, r in m.iterrows()
                )
                + "."
            )
    closes = seq[seq["gap_closures"] > 0].groupby("case", sort=False)["run"].min()
    never = sorted(set(seq["case"]) - set(closes.index))
    if len(closes):
        if closes.nunique() == 1 and not never:
            out.append(
                f"The gaps first close in run {int(closes.iloc[0])} for every engine and "
                "friction assumption."
            )
        else:
            out.append(
                "First run in which a gap closes: "
                + ", ".join(f"{c} run {int(r)}" for c, r in closes.items())
                + "."
            )
    if never:
        out.append(f"No gap closes in any run for: {', '.join(never)}.")
    return out


def state_contrast_sentence(engine: str, mu: float, parts: list[tuple]) -> str:
    """One engine's friction study at one μ from each start state, side by side: ``parts`` is
    a list of (StartState, mechanism row, ratio to μ = 0)."""
    clauses = []
    for state, row, ratio in parts:
        sc = state.scene
        word = direction(ratio)
        effect = (
            f"changes the peak rotation by less than {short(100 * TOL)} %"
            if word == "unchanged"
            else f"{word} the peak rotation {ratio_text(ratio)}"
        )
        if word == "lowers":  # what friction does to the rotation that was the peak without it
            jt, what = row["friction_impulse_ref"], "the frictionless peak's excursion"
        else:
            jt, what = row["friction_impulse"], "the peak excursion"
        drive = (
            f", its impulse {'driving' if jt > 0 else 'resisting'} {what} "
            f"({CONTACT_FORCE.scale * jt:+.3g} {CONTACT_FORCE.impulse()})"
            if np.isfinite(jt)
            else ""
        )
        c1, c2 = row["contact_seat1"], row["contact_seat2"]
        share = (
            f", seat 1 taking {100 * c1 / (c1 + c2):.0f} % of the face contact time"
            if c1 + c2 > 0
            else ""
        )
        clauses.append(
            f"from {state_name(state.label)} (gaps {1e3 * sc.seats[0].gap:.2f} and "
            f"{1e3 * sc.seats[1].gap:.2f} mm) friction {effect}{drive}{share}"
        )
    return f"{engine_label(engine)} at μ = {short(mu)}: " + "; ".join(clauses) + "."


def mode_pair_sentence(table: pd.DataFrame) -> str:
    """For a table with ``friction_mode`` stick and slip cases at equal μ (the sticking
    study): how sticking changes the peak rotation against sliding only, per μ."""
    if not {"friction_mode", "mu"} <= set(table.columns):
        return ""
    ok = table[table["status"] == "success"]
    slip = ok[ok["friction_mode"] == "slip"].set_index("mu")["peak_theta"]
    out = []
    for mode, what in (
        ("stick", "the project's stick law"),
        ("contact2d", "OpenSees's zeroLengthContact2D algorithm"),
    ):
        stick = ok[ok["friction_mode"] == mode].set_index("mu")["peak_theta"]
        items = [(mu, stick[mu] / slip[mu]) for mu in stick.index if mu in slip.index]
        if items:
            out.append(f"Against sliding only, {what} {effect_clauses(items, at_mu)}.")
    return " ".join(out)


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


def impulse_explains(direction_: str, jt: float, jt_ref: float) -> bool | None:
    """Does the friction impulse explain friction's effect on the peak rotation? Where friction
    raises the peak, the impulse over the new peak's excursion ``jt`` must drive it (> 0);
    where it lowers the peak, the impulse over the excursion that was the peak without
    friction ``jt_ref`` must resist that rotation (< 0). None: no change to explain
    (``unchanged``, ``undetermined``) or no impulse read (NaN)."""
    if direction_ not in ("raises", "lowers"):
        return None
    raises = direction_ == "raises"
    j = jt if raises else jt_ref
    if j is None or not np.isfinite(j):
        return None
    return (j > 0) == raises


def mechanism_table(mech: pd.DataFrame, effect: pd.DataFrame, run: int) -> pd.DataFrame:
    """The friction mechanism of one run of the sequence, one row per engine's frictional
    case (``mech``: the mechanism rows, :func:`deckpound.compare.mechanism.mechanism_row`;
    ``effect``: :func:`friction_effect`): peak rotation with friction and its ratio to μ = 0,
    the friction impulses J_T over the peak excursion and over the frictionless peak's
    excursion in the report's contact-force unit (:data:`~.render.CONTACT_FORCE`), whether
    they explain the change (:func:`impulse_explains`), the corners in contact at the peak
    and the share of contact time sticking (mean over the corners that touched)."""
    rows = mech[(mech["source"] == "sequence") & (mech["run"] == run) & (mech["mu"] > 0)]
    eff = effect[effect["run"] == run].set_index("engine") if len(effect) else None
    impulse = CONTACT_FORCE.impulse()
    out = []
    for _, r in rows.iterrows():
        ratio, word = float("nan"), "undetermined"
        if eff is not None and r["engine"] in eff.index:
            ratio, word = float(eff.loc[r["engine"], "ratio"]), eff.loc[r["engine"], "direction"]
        explains = impulse_explains(word, r["friction_impulse"], r["friction_impulse_ref"])
        shares = [r[f"stick_share_c{c}"] for c in range(1, 5)]
        shares = [v for v in shares if np.isfinite(v)]
        corners = r["corners_at_peak"]
        out.append(
            {
                "engine": engine_label(r["engine"]),
                "μ [-]": r["mu"],
                "peak θ_d [mrad]": 1e3 * r["peak_theta"],
                "with / without friction [-]": ratio,
                f"J_T, peak excursion [{impulse}]": CONTACT_FORCE.scale * r["friction_impulse"],
                f"J_T, μ = 0 peak excursion [{impulse}]": CONTACT_FORCE.scale
                * r["friction_impulse_ref"],
                "J_T explains the change": "—"
                if explains is None
                else ("yes" if explains else "no"),
                "in contact at peak": "none"
                if corners == "none"
                else f"{corners.replace('+', ', ')} ({r['face_at_peak']})",
                "sticking [% of contact time]": 100 * float(np.mean(shares))
                if shares
                else float("nan"),
            }
        )
    return pd.DataFrame(out)


def unread_impulse_sentence(mech: pd.DataFrame) -> str:
    """Which engines' tangential contact forces are not read for the friction impulse, and
    why (their share of exactly zero ft among the rows with a normal force); empty when every
    engine's are read."""
    unread = mech[mech["ft_source"] == "n/a"] if len(mech) else mech
    if not len(unread):
        return ""
    parts = [
        f"{engine_label(e)} (ft = 0 in {100 * g['ft_zero_share'].max():.0f} % of the rows "
        "with a normal force)"
        for e, g in unread.groupby("engine", sort=False)
    ]
    return (
        "No friction impulse (—) is read from the reported tangential forces of "
        + join(parts)
        + ": a frictional contact that transmits no tangential force in most of its rows is "
        "not what the engine computed."
    )


def closure_definition_sentence(output_dt: float) -> str:
    """The report's one gap-closure count and the name of the output-row time it also shows."""
    return (
        "Gap closures (the study tables, the headline, tables/sequence.csv with closures per "
        "corner) are the engines' own count, the one definition of every engine and of the "
        "exported OpenSees scripts: the steps at "
        "which a corner goes from out of contact to in contact (gap ≤ 0 or a normal force), "
        "counted at every step, a corner in contact at the start counting one; the report "
        "never recounts them from the output rows. The first contact row (first_contact_row "
        "in tables/sequence.csv and tables/friction_mechanism.csv) is another, clearly "
        "different number: the time of the first output row at which a corner is in contact "
        f"(the same test on the rows, every {short(output_dt)} s), which can lag the engines' "
        "first closure by up to one output step."
    )


def impulse_agreement_sentences(effect: pd.DataFrame, mech: pd.DataFrame) -> list[str]:
    """Per engine: do the friction impulses explain the directions of the friction effect
    along the sequence? Where friction raises the peak, the test is the impulse over the new
    peak's excursion (> 0: friction drives it); where it lowers the peak, the impulse over the
    excursion that was the peak without friction (< 0: friction resists it). ``mech`` holds
    the sequence's rows (run, engine, mu, friction_impulse, friction_impulse_ref)."""
    out = []
    nan = float("nan")
    for engine, g in effect.groupby("engine", sort=False):
        m = mech[(mech["engine"] == engine) & (mech["mu"] > 0)].set_index("run")
        changed = g[g["direction"].isin(["raises", "lowers"])]
        agree, disagree, unknown = [], [], []
        for _, r in changed.iterrows():
            jt, jr = (
                m[col].get(r["run"], nan) if col in m else nan
                for col in ("friction_impulse", "friction_impulse_ref")
            )
            explains = impulse_explains(r["direction"], jt, jr)
            if explains is None:
                unknown.append(r["run"])
            elif explains:
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

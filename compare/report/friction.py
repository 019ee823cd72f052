"""The report's friction section: friction's effect along the sequence and in the friction
studies, and its mechanism (:mod:`.report_sections` assembles the report).

Every number comes from the job's tables (``friction_effect_sequence.csv``,
``friction_mechanism.csv``, the friction studies) through :mod:`.report_text`.
"""

from __future__ import annotations

import numpy as np

from deckpound.compare.report import text as text
from deckpound.compare.report.render import MRAD, Bullets, Figure, Table, view

__all__ = ["MECHANISM_COLUMNS", "friction"]

MECHANISM_COLUMNS = (
    [
        ("source", "source", 1),
        ("state", "state", 1),
        ("engine", "engine", 1),
        ("mu", "μ [-]", 1),
        ("peak_theta", "peak θ_d [mrad]", MRAD),
        ("t_start", "excursion from [s]", 1),
        ("t_peak", "peak at [s]", 1),
        ("friction_impulse", "J_T [kN·m·s]", 1),
        ("normal_impulse", "J_N [kN·m·s]", 1),
        ("friction_impulse_ref", "J_T over the μ = 0 peak excursion [kN·m·s]", 1),
        ("corners_at_peak", "in contact at peak", 1),
        ("face_at_peak", "face", 1),
    ]
    + [(f"stick_share_c{c}", f"stick c{c} [%]", 100) for c in range(1, 5)]
    + [(f"first_closure_c{c}", f"first closure c{c} [s]", 1) for c in range(1, 5)]
    + [("contact_seat1", "contact seat 1 [s]", 1), ("contact_seat2", "contact seat 2 [s]", 1)]
)


def friction(d) -> list:
    eff = d.effect
    items = [
        (
            f"Each run of the sequence is computed with and without friction; the ratio of the "
            f"two peak rotations says where friction raises (> {1 + text.TOL:g}) and where it "
            f"lowers (< {1 - text.TOL:g}) the rotation. Each case carries its own state from "
            "its own previous runs."
        )
    ]
    items.append(Bullets(tuple(text.sequence_friction_sentences(eff))))
    if len(eff):
        items.append(
            Figure(
                "figures/friction_ratio_vs_run.png",
                "Peak |θ_d| with friction / "
                f"without, per run and engine [-]; grey band: ±{100 * text.TOL:g} %.",
            )
        )
        items.append(
            Table(
                view(
                    eff,
                    [
                        ("engine", "engine", 1),
                        ("run", "run", 1),
                        ("pga", "PGA label [g]", 1),
                        ("mu", "μ [-]", 1),
                        ("peak_theta_0", "peak θ_d, μ = 0 [mrad]", MRAD),
                        ("peak_theta_mu", "peak θ_d, with μ [mrad]", MRAD),
                        ("ratio", "ratio [-]", 1),
                        ("direction", "friction", 1),
                    ],
                ),
                "Friction's effect on the peak rotation along the sequence "
                "(tables/friction_effect_sequence.csv).",
            )
        )
    for r in d.studies:
        if r.name == "friction":
            items.append(
                f"**Friction study from {text.state_name(r.state.label)}.** "
                + text.state_sentence(r.state)
            )
            items.append(
                Bullets(tuple(text.study_friction_sentences(text.study_friction_effect(r.table))))
            )
    items.append(
        "**Mechanism.** The numbers below come from tables/friction_mechanism.csv: the "
        "excursion of θ_d that reaches the peak (from its last change of sign), the "
        "angular impulse about the deck centre of the friction forces and of the normal "
        "forces over it (positive: towards the peak rotation), the corners in contact "
        "at the peak, stick shares and first closures."
    )
    items.append(Bullets(tuple(_mechanism_sentences(d))))
    contrast = _state_contrasts(d)
    if contrast:
        items.append("**The two start states side by side** (friction study):")
        items.append(Bullets(tuple(contrast)))
    seq_mech = d.mech[d.mech["source"] == "sequence"] if len(d.mech) else d.mech
    if len(seq_mech):
        items.append(Bullets(tuple(text.impulse_agreement_sentences(eff, seq_mech))))
        shown = d.mech[
            (d.mech["mu"] > 0) & ((d.mech["source"] != "sequence") | (d.mech["run"] == d.strongest))
        ]
        items.append(
            Table(
                view(shown, MECHANISM_COLUMNS),
                "Friction mechanism of the frictional "
                f"cases of run {d.strongest} and of the friction studies "
                "(every run and case: tables/friction_mechanism.csv). J_T, J_N: angular "
                "impulse of the friction / normal contact forces about the deck centre "
                "over the peak excursion, positive towards the peak rotation.",
            )
        )
        items.append(
            Figure(
                "figures/friction_mechanism_strongest.png",
                f"Run {d.strongest}: deck rotation θ_d [mrad] without (dotted) and "
                "with "
                "friction (solid), and the moment of the tangential contact forces "
                "about the deck centre [MN·m].",
            )
        )
    return items


def _mechanism_sentences(d) -> list[str]:
    out = []
    m = d.mech
    if not len(m):
        return out
    strong = m[(m["source"] == "sequence") & (m["run"] == d.strongest) & (m["mu"] > 0)]
    for _, row in strong.iterrows():
        out.append(text.mechanism_sentence(row, f"run {d.strongest} of the sequence"))
    mu = strong["mu"].iloc[0] if len(strong) else None
    for r in d.studies:
        if r.name != "friction":
            continue
        rows = m[(m["source"] == "friction study") & (m["state"] == r.state.label) & (m["mu"] > 0)]
        if mu is not None:
            rows = rows[np.isclose(rows["mu"], mu)]
        for _, row in rows.iterrows():
            out.append(
                text.mechanism_sentence(
                    row, f"friction study from {text.state_name(r.state.label)}"
                )
            )
    return out


def _state_contrasts(d) -> list[str]:
    """Per engine, the friction study at the sequence's μ from every state it was run from."""
    runs = [r for r in d.studies if r.name == "friction"]
    if len(runs) < 2 or not len(d.mech):
        return []
    mus = d.seq.loc[d.seq["mu"] > 0, "mu"]
    mu = float(mus.iloc[0]) if len(mus) else 0.2
    out = []
    for engine in runs[0].table["engine"].unique():
        parts = []
        for r in runs:
            eff = text.study_friction_effect(r.table)
            e = eff[(eff["engine"] == engine) & np.isclose(eff["mu"], mu)]
            m = d.mech[
                (d.mech["source"] == "friction study")
                & (d.mech["state"] == r.state.label)
                & (d.mech["engine"] == engine)
                & np.isclose(d.mech["mu"], mu)
            ]
            if len(e) and len(m):
                parts.append((r.state, m.iloc[0], float(e["ratio"].iloc[0])))
        if len(parts) == len(runs):
            out.append(text.state_contrast_sentence(engine, mu, parts))
    return out

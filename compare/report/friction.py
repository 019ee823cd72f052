"""The report's friction section: friction's effect along the sequence and in the friction
studies, and its mechanism as a short table and one figure (:mod:`.sections` assembles the
report).

Every number comes from the job's tables (``friction_effect_sequence.csv``,
``friction_mechanism.csv``, the friction studies) through :mod:`.text`.
"""

from __future__ import annotations

import numpy as np

from deckpound.compare.report import text as text
from deckpound.compare.report.render import CONTACT_FORCE, MRAD, Bullets, Figure, Table, view

__all__ = ["friction"]


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
    contrast = _state_contrasts(d)
    if contrast:
        items.append("**The two start states side by side** (friction study):")
        items.append(Bullets(tuple(contrast)))
    items += _mechanism(d)
    return items


def _mechanism(d) -> list:
    """How friction acts on the rotation: a short table of the strongest run (one row per
    engine), whether the friction impulse explains friction's effect along the whole sequence
    (one sentence per engine), and the figure of the strongest run."""
    seq_mech = d.mech[d.mech["source"] == "sequence"] if len(d.mech) else d.mech
    if not len(seq_mech):
        return []
    items = [
        (
            f"**Mechanism** (run {d.strongest}). J_T: the angular impulse of the friction forces "
            "about the deck centre over the excursion of θ_d that reaches the peak (from its "
            "last change of sign), positive towards the peak; J_T over the μ = 0 peak "
            "excursion: the same over the excursion that was the peak without friction. J_T > 0 "
            "explains a raised peak; a negative impulse over the frictionless peak's excursion "
            "explains a lowered one."
        ),
        Table(
            text.mechanism_table(d.mech, d.effect, d.strongest),
            f"Friction mechanism of run {d.strongest}, one row per engine with friction. Every "
            "run and study case, with the normal forces' impulse, the contact time per seat "
            "face, the stick share per corner and the first contact rows: "
            "tables/friction_mechanism.csv.",
        ),
    ]
    unread = text.unread_impulse_sentence(seq_mech[seq_mech["run"] == d.strongest])
    if unread:
        items.append(unread)
    items.append(Bullets(tuple(text.impulse_agreement_sentences(d.effect, seq_mech))))
    items.append(
        Figure(
            "figures/friction_mechanism_strongest.png",
            f"Run {d.strongest}: deck rotation θ_d [mrad] per engine without and with "
            "friction, and the moment of the tangential contact forces about the deck "
            f"centre [{CONTACT_FORCE.moment()}]; shaded, the excursion that reaches the "
            "frictional peak.",
        )
    )
    return items


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

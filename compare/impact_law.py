"""The nonsmooth engine's impact law, measured: ``newton`` against ``energy-safe`` (issue 12).

At an active corner that already separates (U_N⁻ > 0; the step after an impact, or persistent
contact with the seat springs pushing) the two laws differ (:func:`deckpound.analytic.
nonsmooth.separating_restitution`): ``newton`` keeps 0 ≤ U_N⁺ + e·U_N⁻ ⊥ P_N ≥ 0 (Siconos'
Moreau–Jean), ``energy-safe`` uses max(e, (1 − θ)/θ) (= 1 for θ = ½) so that no normal impulse
does positive work. :func:`impact_law_table` runs the nonsmooth engine both ways on a scene,
without and with friction, and measures per case:

* ``energy_closure`` — largest |energy_error| / largest |energy_input| of the discrete energy
  balance (:mod:`deckpound.analytic.nonsmooth`; 0 up to round-off for an exact balance);
* ``max_penetration`` [m] — over every step (not the output rows);
* ``impact_gain`` — energy returned by the normal impulses (decreases of the cumulative
  ``energy_impact`` between output rows) over the total impact dissipation: what the
  energy-safe law rules out;
* ``peak_theta`` [rad] and its ratio to the compliance clone's peak deck rotation (the clone
  gives OpenSees's results to round-off: ``deckpound verify clone``), ``nrmse_theta`` — RMS of
  the rotation difference over the clone's peak.

``deckpound verify impact-law SCENE`` prints the table; the README quotes it and
``tests/test_impact_law.py`` re-derives the README's numbers from it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["FRICTION_CASE", "format_table", "impact_law_table"]

#: The frictional case of the measurement: μ = 0.2 with sticking (the report's headline case).
FRICTION_CASE = {"contact.friction": 0.2, "contact.friction_mode": "stick"}


def _with(scene, changes: dict):
    """``scene`` with ``contact.<name>`` fields replaced (validated again)."""
    contact = dataclasses.replace(
        scene.contact, **{k.split(".", 1)[1]: v for k, v in changes.items()}
    )
    return scene.replace(contact=contact)


def _impact_gain(e_impact: np.ndarray) -> float:
    """Energy the normal impulses gave back [kJ]: the sum of the decreases of the cumulative
    impact dissipation between output rows (0 when no row interval gains energy), over the
    total dissipation at the end."""
    gain = float(np.sum(np.maximum(0.0, -np.diff(e_impact))))
    total = float(e_impact[-1]) if len(e_impact) else 0.0
    return gain / total if total > 0 else 0.0


def impact_law_table(scene) -> list[dict]:
    """One row per (friction off/on, impact law) on ``scene`` (see the module docstring)."""
    from deckpound.engines import run_engine

    rows = []
    for label, changes in (
        ("none", {"contact.friction": 0.0, "contact.friction_mode": "none"}),
        ("mu=0.2 stick", FRICTION_CASE),
    ):
        sc = _with(scene, changes)
        ref = run_engine("compliance", sc)
        th_ref = np.asarray(ref["deck_theta"])
        peak_ref = float(np.max(np.abs(th_ref)))
        for law in ("newton", "energy-safe"):
            settings = dataclasses.replace(sc.nonsmooth, impact_law=law)
            r = run_engine("nonsmooth", sc, settings=settings)
            th = np.asarray(r["deck_theta"])
            n = min(len(th), len(th_ref))
            peak = float(np.max(np.abs(th)))
            rows.append(
                {
                    "friction": label,
                    "impact_law": law,
                    "peak_theta": peak,
                    "peak_ratio": peak / peak_ref if peak_ref > 0 else float("nan"),
                    "nrmse_theta": float(np.sqrt(np.mean((th[:n] - th_ref[:n]) ** 2)) / peak_ref)
                    if peak_ref > 0
                    else float("nan"),
                    "max_penetration": float(r.meta["max_penetration"]),
                    "max_penetration_rows": float(r.meta["max_penetration_rows"]),
                    "energy_closure": float(r.meta["energy_closure"]),
                    "impact_gain": _impact_gain(np.asarray(r["energy_impact"])),
                    "status": r.meta["status"],
                }
            )
    return rows


def _tiny(x: float, floor: float) -> str:
    """x to 2 significant digits, or "≤ floor" at round-off level (machine-dependent digits)."""
    return f"≤ {floor:.0e}" if abs(x) <= floor else f"{x:.2g}"


def format_table(rows: list[dict]) -> str:
    """The rows as the Markdown table the README quotes (3 significant digits)."""
    head = (
        "| friction | impact law | peak θ [mrad] | ÷ clone peak | NRMSE θ vs clone "
        "| max penetration, every step [mm] | on output rows [mm] | energy closure "
        "| impulse energy gain ÷ dissipation |"
    )
    lines = [head, "|" + "---|" * 9]
    for r in rows:
        lines.append(
            f"| {r['friction']} | {r['impact_law']} | {1e3 * r['peak_theta']:.3g} | "
            f"{r['peak_ratio']:.3g} | {r['nrmse_theta']:.3g} | "
            f"{1e3 * r['max_penetration']:.3g} | {1e3 * r['max_penetration_rows']:.3g} | "
            f"{_tiny(r['energy_closure'], 1e-13)} | {_tiny(r['impact_gain'], 1e-12)} |"
        )
    return "\n".join(lines)

"""Magnitudes a bridge can have: unit slips and absurd values, found before any engine runs.

Field validation (:mod:`._fields`) accepts any finite value in a field's range (up to 1e30);
these checks compare each value with what bridges and their models have, so that the usual
unit slips and absurd inputs are named instead of run. Part of
:func:`deckpound.models.plausibility.check`. Units inside are m, t, kN, s.

=====================  ==================  ================  ===================================
value                  warning above       refused above     the usual slip
=====================  ==================  ================  ===================================
seats[i].gap           0.5 m               2 m               mm for m (12.7 for 0.0127)
deck.width             100 m               200 m             mm for m
deck.length            2 km                10 km             mm for m
deck.mass per plan     10 t/m²             100 t/m²          kg for t (140500 for 140.5)
  area L·W
any mass               —                   1e7 t             —
any other length       —                   10 km             — (a dimension of 1e30)
contact.friction μ     1                   2                 —
contact.stiffness,     1e11 kN/m           never             N/m for kN/m
  tangential_stiffness
deck.inertia           M · r_max² (all     never             kg·m² for t·m²
                       mass at the
                       farthest corner)
bent springs           300× the softest    never             N/m for kN/m (one bent)
deck's fundamental     above 10 s, or      never             MN/m for kN/m or kg for t (T ×
  period (with bents)  below 0.05 s                          31.6), N/m for kN/m (T / 31.6)
=====================  ==================  ================  ===================================

A refused value is a finding of level ``"error"`` naming the field, the value, the bound and,
where the value divided by 1000 is a plausible one, the value probably meant ("it looks like
mm, did you mean 0.0127 m?"). The scene option ``allow_extreme = true`` turns the refusals into
warnings (numerical experiments with extreme values); warnings stay warnings. The reasons for
each bound are at its constant.
"""

from __future__ import annotations

import math

import numpy as np

from deckpound.models.mechanics import natural_modes

from .plan import plan_of
from .scene import Scene

#: warning above [m]: deck-abutment gaps (expansion joints, seismic gaps) are 5-300 mm; a
#: gap of 0.5-2 m is odd but is also how a run is kept free of contact
GAP_WARN = 0.5
#: refused above [m]: the largest modular expansion joints open about 2 m in all; a gap in mm
#: read as m (12.7 for 0.0127) is 5-300 m
GAP_MAX = 2.0
#: warning above [m]: the widest bridge decks (twin decks, many lanes) are 60-80 m wide
DECK_WIDTH_WARN = 100.0
#: refused above [m]: no deck is 200 m wide; a 2.4 m deck in mm reads 2400 m
DECK_WIDTH_MAX = 200.0
#: warning above [m]: continuous decks between two expansion joints reach 1-2 km
DECK_LENGTH_WARN = 2_000.0
#: refused above [m], for every length of the scene: no structure modelled as one rigid deck,
#: and no displacement of one, reaches 10 km (a 33.5 m deck in mm reads 33.5 km)
MAX_LENGTH = 10_000.0
#: warning above [t/m²] of deck plan: concrete decks weigh 0.5-2.5 t/m² (a solid slab 1 m
#: thick is 2.5 t/m²), steel decks less, scale models with added mass up to a few t/m² (the
#: 1/4-scale benchmark 1.75 t/m²)
AREAL_MASS_WARN = 10.0
#: refused above [t/m²]: a solid concrete block 40 m thick; a mass in kg read as t is 1000×
#: a deck's (the benchmark in kg: 1,750 t/m²)
AREAL_MASS_MAX = 100.0
#: refused above [t], every mass: ten times the heaviest bridges (about 1e6 t)
MAX_MASS = 1.0e7
#: warning above [-]: dry concrete on concrete 0.5-0.8, rubber on concrete up to about 1
FRICTION_WARN = 1.0
#: refused above [-]: no pair of dry surfaces reaches a Coulomb coefficient of 2
FRICTION_MAX = 2.0
#: warning above [kN/m] (never refused): 1000× the stiffest value of the built-in
#: contact-stiffness study (1e8 kN/m), the factor of a stiffness given in N/m; stiffer
#: contacts are legitimate limits (the nonsmooth engine is the rigid one)
STIFFNESS_WARN = 1.0e11
#: warning above [s]: fundamental periods of bridges, isolated ones included, stay below
#: about 5 s; a deck mass in kg lengthens the deck's periods up to 31.6× (√1000; the
#: benchmark's 0.61 s to 16 s)
PERIOD_WARN_LONG = 10.0
#: warning below [s]: no bridge or shake-table bridge model vibrates above 20 Hz in its
#: fundamental mode; bent stiffnesses in N/m shorten periods 31.6× (the benchmark to 0.019 s)
PERIOD_WARN_SHORT = 0.05
#: warning above [-]: the stiffest bent spring over the softest; bents of one bridge differ
#: by a factor of tens (column heights 1:4 give 1:64 by 1/h³), a bent in N/m by 1000s
BENT_RATIO_WARN = 300.0
#: the factor of the slips named (mm for m, kg for t, N/m for kN/m)
SLIP = 1000.0


def _hint(value: float, unit: str, slip_unit: str, plausible_max: float) -> str:
    """``: it looks like mm, did you mean 0.0127 m?`` when value / 1000 is plausible."""
    meant = value / SLIP
    if meant > plausible_max:
        return ""
    return f": it looks like {slip_unit}, did you mean {meant:.6g} {unit}?"


def _lengths(scene: Scene) -> list[tuple[str, float]]:
    """Every length of the scene [m] (field path, value) that only the 10 km bound limits."""
    out = [
        ("contact.bilinear_yield", scene.contact.bilinear_yield),
        *(
            (f"joints[{k}].contact.bilinear_yield", j.contact.bilinear_yield)
            for k, j in enumerate(scene.joints or ())
            if j.contact is not None and j.contact.bilinear_yield is not None
        ),
        ("initial.deck[0]", abs(scene.initial.deck[0])),
        ("initial.deck[1]", abs(scene.initial.deck[1])),
    ]
    for i, b in enumerate(scene.bents):
        for axis in ("x", "y"):
            spring = getattr(b, axis)
            out.append((f"bents[{i}].{axis}.ultimate_displacement", spring.ultimate_displacement))
    return out


def _findings(scene: Scene) -> list[tuple[str, str, str]]:
    """(level, field, message) of every value out of a bridge's range (levels before
    ``allow_extreme`` is applied)."""
    found: list[tuple[str, str, str]] = []
    deck = scene.deck

    def add(level: str, field: str, message: str) -> None:
        found.append((level, field, message))

    for i, seat in enumerate(scene.seats):
        g = seat.gap
        if g > GAP_MAX:
            add(
                "error",
                f"seats[{i}].gap",
                f"{g:g} m is wider than any deck-abutment gap (at most {GAP_MAX:g} m; "
                "expansion joints and seismic gaps are 5-300 mm)" + _hint(g, "m", "mm", GAP_WARN),
            )
        elif g > GAP_WARN:
            add(
                "warning",
                f"seats[{i}].gap",
                f"{g:g} m is wider than usual deck-abutment gaps (5-300 mm): is it in mm? "
                "(a wide gap also keeps a run free of contact)",
            )
    for name, value, warn, limit in (
        ("width", deck.width, DECK_WIDTH_WARN, DECK_WIDTH_MAX),
        ("length", deck.length, DECK_LENGTH_WARN, MAX_LENGTH),
    ):
        if value > limit:
            add(
                "error",
                f"deck.{name}",
                f"{value:g} m is beyond any bridge deck (at most {limit:g} m)"
                + _hint(value, "m", "mm", warn),
            )
        elif value > warn:
            add(
                "warning",
                f"deck.{name}",
                f"{value:g} m is more than any bridge deck's {name} (about {warn:g} m): "
                "is it in mm?",
            )
    for field, value in _lengths(scene):
        if value > MAX_LENGTH:
            add("error", field, f"{value:g} m is beyond any structure (at most {MAX_LENGTH:g} m)")

    masses = [("deck.mass", deck.mass)]
    masses += [(f"seats[{i}].mass", s.mass) for i, s in enumerate(scene.seats)]
    for field, m in masses:
        if m > MAX_MASS:
            hint = _hint(m, "t", "kg", MAX_MASS) if field == "deck.mass" else ""
            add(
                "error",
                field,
                f"{m:g} t is beyond any bridge (at most {MAX_MASS:g} t; the heaviest weigh "
                "about 1e6 t)" + hint,
            )
    area = deck.length * deck.width
    areal = deck.mass / area
    what = f"{deck.mass:g} t on a deck of {deck.length:g} m × {deck.width:g} m is {areal:.4g} t"
    if deck.mass > MAX_MASS:
        pass  # refused above
    elif areal > AREAL_MASS_MAX:
        add(
            "error",
            "deck.mass",
            f"{what} per m² of deck, more than {AREAL_MASS_MAX:g} t/m² (a solid concrete "
            "block 40 m thick; decks weigh 0.5-2.5 t/m²)"
            + _hint(deck.mass, "t", "kg", AREAL_MASS_WARN * area),
        )
    elif areal > AREAL_MASS_WARN:
        add(
            "warning",
            "deck.mass",
            f"{what} per m² of deck, more than {AREAL_MASS_WARN:g} t/m² (decks weigh "
            "0.5-2.5 t/m², scale models with added mass a few t/m²): is it in kg?",
        )

    _contact_magnitudes("contact", scene.contact, add)
    for k, joint in enumerate(scene.joints or ()):
        if joint.contact is not None:
            _contact_magnitudes(f"joints[{k}].contact", joint.contact, add)
    return found


def _contact_magnitudes(where: str, ct, add) -> None:
    """Friction and contact stiffnesses of one contact table (``where``: its field path; a
    joint's table checks the fields it gives, none is not given)."""
    mu = 0.0 if ct.friction is None else ct.friction
    if mu > FRICTION_MAX:
        add(
            "error",
            f"{where}.friction",
            f"μ = {mu:g} is beyond any pair of dry surfaces (at most {FRICTION_MAX:g}; "
            "concrete on concrete 0.5-0.8)",
        )
    elif mu > FRICTION_WARN:
        add(
            "warning",
            f"{where}.friction",
            f"μ = {mu:g} is more than dry concrete (0.5-0.8) or rubber (about 1) give",
        )
    for name in ("stiffness", "tangential_stiffness"):
        k = getattr(ct, name)
        if k is not None and k > STIFFNESS_WARN:
            add(
                "warning",
                f"{where}.{name}",
                f"{k:g} kN/m is 1000× the stiffest contact of the stiffness study (1e8 kN/m): "
                f"is it in N/m? (kN/m meant: {k / SLIP:g})",
            )


def _bent_springs(scene: Scene) -> list[tuple[str, str, str]]:
    """A warning when one bent spring is BENT_RATIO_WARN times stiffer than the softest."""
    springs = [
        (f"bents[{i}].{axis}.stiffness", getattr(b, axis).stiffness)
        for i, b in enumerate(scene.bents)
        for axis in ("x", "y")
    ]
    if len(springs) < 2:
        return []
    stiff, soft = max(springs, key=lambda s: s[1]), min(springs, key=lambda s: s[1])
    ratio = stiff[1] / soft[1]
    if ratio <= BENT_RATIO_WARN:
        return []
    return [
        (
            "warning",
            stiff[0],
            f"{stiff[1]:g} kN/m is {ratio:.3g}× the softest bent spring ({soft[0]} = "
            f"{soft[1]:g} kN/m; bents of one bridge differ by less than {BENT_RATIO_WARN:g}×): "
            f"is it in N/m? (kN/m meant: {stiff[1] / SLIP:g})",
        )
    ]


def _inertia_and_periods(scene: Scene, flagged: set[str]) -> list[tuple[str, str, str]]:
    """Warnings on the deck's polar inertia and the fundamental period (sound values only;
    ``flagged``: the fields already warned about)."""

    found = _bent_springs(scene)
    deck = scene.deck
    plan = plan_of(scene)
    # corners from the deck centre (a segment's corners are in its own frame; one segment: 0)
    centres = [seg.centre for seg in plan.segments]
    r2 = max((c.x + centres[c.body]) * (c.x + centres[c.body]) + c.y * c.y for c in plan.corners)
    if deck.inertia > deck.mass * r2:
        found.append(
            (
                "warning",
                "deck.inertia",
                f"{deck.inertia:g} t·m² is more than the {deck.mass * r2:.4g} t·m² of the whole "
                f"deck mass {deck.mass:g} t at its farthest corner: is it in kg·m²? (a very "
                "large inertia also holds a deck's rotation)",
            )
        )
    if not scene.bents:
        return found  # a free deck: no fundamental period of the bridge
    modes = natural_modes(scene, plan)
    periods = modes.periods
    if not np.all(np.isfinite(periods)):
        return found  # refused by the period checks of plausibility.check
    # the deck's modes (most of their kinetic energy in a deck segment's x, y or θ): the seats'
    # own modes are set by the seat springs, whatever the bridge
    energy = np.diag(plan.mass_matrix)[:, None] * modes.shapes**2
    dominant = np.argmax(energy, axis=0)
    names = plan.dof_names
    deck_modes = [k for k in range(len(periods)) if not names[dominant[k]].startswith("seat")]
    if not deck_modes:
        return found
    first = max(deck_modes, key=lambda k: periods[k])
    t1, dof = float(periods[first]), names[dominant[first]]
    # a deck mass or inertia already named as too heavy explains a long period by itself
    heavy = {"deck.mass", "deck.inertia"} & ({f for _, f, _ in found} | flagged)
    if t1 > PERIOD_WARN_LONG and not heavy:
        found.append(
            (
                "warning",
                "bents",
                f"the deck's fundamental period in the contact-free model is {t1:.3g} s "
                f"({dof}), beyond any bridge (below about 5 s): bent stiffnesses in MN/m, or "
                f"a deck mass in kg? (periods × {math.sqrt(SLIP):.3g})",
            )
        )
    elif t1 < PERIOD_WARN_SHORT:
        found.append(
            (
                "warning",
                "bents",
                f"the deck's fundamental period in the contact-free model is {t1:.3g} s "
                f"({dof}), shorter than any bridge's or bridge model's ({PERIOD_WARN_SHORT:g} "
                f"s): bent stiffnesses in N/m (periods / {math.sqrt(SLIP):.3g})?",
            )
        )
    return found


def magnitude_findings(scene: Scene) -> list[tuple[str, str, str]]:
    """(level, field, message) of every magnitude out of a bridge's range (module table).

    With ``scene.allow_extreme`` the refusals become warnings that say so. The inertia and
    period warnings are looked at only when no value was refused (they assume sound values).
    """
    found = _findings(scene)
    if not any(level == "error" for level, _, _ in found):
        found += _inertia_and_periods(scene, {field for _, field, _ in found})
    if scene.allow_extreme:
        suffix, refused = " (run anyway: allow_extreme = true)", "warning"
    else:
        suffix, refused = " (allow_extreme = true runs it anyway)", "error"
    return [
        (refused, field, message + suffix) if level == "error" else (level, field, message)
        for level, field, message in found
    ]

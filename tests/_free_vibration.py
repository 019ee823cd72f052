"""The undamped free-vibration case of issue 28, shared by the energy tests: no excitation,
no damping anywhere (seat dashpots included), bents that never yield; the deck launched with
``initial.deck_velocity`` bounces between its seats."""

from __future__ import annotations

from deckpound.models.scene_io import load_scene

#: bents that never yield
ELASTIC = [
    f"bents[{b}].{d}.{f}={v}"
    for b in range(3)
    for d in "xy"
    for f, v in (("yield_force", 1e6), ("ultimate_displacement", 1e3))
]


def undamped(duration: float) -> list[str]:
    """Overrides: no excitation for ``duration`` [s], no damping anywhere, elastic bents."""
    return [
        "excitation.kind=none",
        f"excitation.duration={duration:g}",
        "damping.ratio=0",
        *(f"seats[{i}].{f}=0" for i in (0, 1) for f in ("cx", "ctheta")),
        *ELASTIC,
    ]


#: the issue's case: 10 s, the deck launched at (0.25 m/s, 0.05 m/s, 0.002 rad/s)
LAUNCH = "initial.deck_velocity=[0.25,0.05,0.002]"
FREE_VIBRATION = [*undamped(10), LAUNCH]


def free_vibration(*overrides: str):
    """The benchmark in the issue's free vibration, with ``overrides`` after."""
    return load_scene("saiidi-4span", [*FREE_VIBRATION, *overrides])

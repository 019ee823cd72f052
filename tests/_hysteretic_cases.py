"""Parameter sets of the Hysteretic clone tests (``tests/test_hysteretic.py``).

Each is the 12 backbone numbers of OpenSees ``uniaxialMaterial Hysteretic`` after the tag
(s1p, e1p, s2p, e2p, s1n, e1n, s2n, e2n, pinchX, pinchY, damage1, damage2), with the Takeda
β where given: two-point Takeda backbones like the bents', three-point ones, and general
pinched and damaged materials.
"""

TAKEDA_2PT = {  # (s1p, e1p, s2p, e2p, s1n, e1n, s2n, e2n, px, py, d1, d2)
    f"takeda2_b{b}": (
        350.0,
        0.012,
        420.0,
        0.12,
        -350.0,
        -0.012,
        -420.0,
        -0.12,
        1.0,
        1.0,
        0.0,
        0.0,
        b,
    )
    for b in (0.0, 0.3, 0.5, 0.8)
}
TAKEDA_3PT = {
    f"takeda3_b{b}": (
        1.2e3,
        3.1e-3,
        1.5e3,
        0.021,
        1.55e3,
        0.07,
        -1.1e3,
        -2.9e-3,
        -1.45e3,
        -0.019,
        -1.5e3,
        -0.065,
        1.0,
        1.0,
        0.0,
        0.0,
        b,
    )
    for b in (0.0, 0.3, 0.5, 0.8)
}
GENERAL = {
    # pinched + damaged, 2-point, asymmetric
    "general2": (100.0, 0.01, 150.0, 0.05, -80.0, -0.008, -130.0, -0.06, 0.8, 0.2, 0.01, 0.02, 0.4),
    # pinched + damaged, 3-point with softening last branch (rotlim paths)
    "general3_soft": (
        100.0,
        0.01,
        140.0,
        0.03,
        60.0,
        0.08,
        -100.0,
        -0.01,
        -140.0,
        -0.03,
        -60.0,
        -0.08,
        0.5,
        0.3,
        0.02,
        0.05,
        0.3,
    ),
    # strong softening to zero/negative force (posEnvlpRotlim finite)
    "general3_collapse": (
        100.0,
        0.01,
        120.0,
        0.02,
        10.0,
        0.06,
        -100.0,
        -0.01,
        -120.0,
        -0.02,
        -10.0,
        -0.06,
        0.3,
        0.5,
        0.0,
        0.1,
        0.0,
    ),
    # 2-point with damage2 where the 2- and 3-segment energyA differ
    "general2_odd": (
        113.7,
        0.0117,
        171.3,
        0.0631,
        -97.1,
        -0.0093,
        -149.9,
        -0.0577,
        0.8,
        0.2,
        0.01,
        0.03,
        0.4,
    ),
    # 2-point, damage only, no beta (beta omitted -> 12 args)
    "general2_nobeta": (50.0, 0.002, 75.0, 0.03, -50.0, -0.002, -75.0, -0.03, 0.6, 0.4, 0.05, 0.0),
    # 3-point with E2 > E1 (Eup != E1p) and pinching
    "general3_stiffening": (
        10.0,
        0.01,
        40.0,
        0.02,
        50.0,
        0.05,
        -10.0,
        -0.01,
        -40.0,
        -0.02,
        -50.0,
        -0.05,
        0.7,
        0.6,
        0.0,
        0.0,
        0.5,
    ),
}
ALL_PARAMS = {**TAKEDA_2PT, **TAKEDA_3PT, **GENERAL}

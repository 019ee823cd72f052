"""Cross-verification of the Hysteretic (Takeda) clone against OpenSees itself.

``verify_takeda`` drives openseespy's ``uniaxialMaterial Hysteretic`` through
``testUniaxialMaterial``/``setStrain`` (which commits in 3.7) and the clone
(:class:`deckpound.analytic.kernels.hysteretic.HystereticMaterial`, ``element_copy=False`` to match
the material object that ``testUniaxialMaterial`` uses) along the same seeded random strain
histories — Takeda parameter sets (pinch 1, damage 0) and general ones — and reports the
largest relative deviation of stress and tangent.
"""

from __future__ import annotations

import numpy as np

from deckpound.analytic.kernels.hysteretic import HystereticMaterial
from deckpound.opensees_build.ops import OpsSession

#: (backbone and Hysteretic arguments after the tag) used by the check
PARAMETER_SETS = (
    (160.0, 0.0229, 170.5, 0.3, -160.0, -0.0229, -170.5, -0.3, 1.0, 1.0, 0.0, 0.0, 0.5),
    (120.0, 0.04, 133.0, 0.3, -120.0, -0.04, -133.0, -0.3, 1.0, 1.0, 0.0, 0.0, 0.0),
    (200.0, 0.0167, 227.0, 0.3, -200.0, -0.0167, -227.0, -0.3, 1.0, 1.0, 0.0, 0.0, 0.8),
    (
        100.0,
        0.01,
        140.0,
        0.05,
        150.0,
        0.2,
        -90.0,
        -0.01,
        -120.0,
        -0.06,
        -130.0,
        -0.2,
        0.8,
        0.3,
        0.02,
        0.01,
        0.4,
    ),
)


def random_history(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    """Random walk with occasional large excursions and repeated values (quirk coverage)."""
    steps = rng.normal(0.0, 0.15 * scale, n) * np.where(rng.random(n) < 0.1, 6.0, 1.0)
    x = np.cumsum(steps)
    x = np.clip(x, -4 * scale, 4 * scale)
    repeat = rng.random(n) < 0.03
    x[1:][repeat[1:]] = x[:-1][repeat[1:]]
    return x


def verify_takeda(n_states: int = 20000, seed: int = 0) -> dict:
    """Compare the clone with OpenSees on ``n_states`` strain states; returns a report dict."""
    rng = np.random.default_rng(seed)
    per_set = max(1, n_states // len(PARAMETER_SETS))
    total = exact = 0
    dev_s = dev_t = 0.0
    with OpsSession() as session:
        ops = session.raw
        ops.model("basic", "-ndm", 1, "-ndf", 1)
        for k, args in enumerate(PARAMETER_SETS):
            tag = k + 1
            ops.uniaxialMaterial("Hysteretic", tag, *args)
            clone = HystereticMaterial(*args, element_copy=False)
            ops.testUniaxialMaterial(tag)
            strains = random_history(rng, per_set, abs(args[1]))
            for e in strains:
                ops.setStrain(float(e))
                s_ref, t_ref = ops.getStress(), ops.getTangent()
                clone.set_trial_strain(float(e))
                clone.commit()
                s, t = clone.stress, clone.tangent
                total += 1
                exact += int(s == s_ref and t == t_ref)
                dev_s = max(dev_s, abs(s - s_ref) / max(abs(s_ref), 1e-300) if s != s_ref else 0.0)
                dev_t = max(dev_t, abs(t - t_ref) / max(abs(t_ref), 1e-300) if t != t_ref else 0.0)
    return {"n_states": total, "n_exact": exact, "max_rel_stress": dev_s, "max_rel_tangent": dev_t}

"""deckpound.analytic: the pure-Python (numba) engines of the 7-DOF plan model.

* :func:`run_compliance` — the compliance clone of the OpenSees model (gap elements, several
  contact laws, Coulomb friction with or without sticking, linear or exact geometry);
* :func:`run_nonsmooth` — rigid unilateral contact, Moreau–Jean time-stepping;
* :class:`HystereticMaterial` — OpenSees's Hysteretic material (the Takeda stand-in), cloned
  bit for bit.

Smooth forces, kinematics and the Takeda kernel are shared by both engines
(:mod:`.system`, :mod:`.kinematics`, :mod:`.hysteretic_kernel`).
"""

from deckpound.analytic._jit import use_source_keyed_cache

use_source_keyed_cache()

from deckpound.analytic.kernels.hysteretic import HystereticMaterial  # noqa: E402 (after the cache is keyed)

__all__ = ["HystereticMaterial", "run_compliance", "run_nonsmooth"]


def __getattr__(name):
    # the engines are imported on first use: importing the package stays cheap
    if name == "run_compliance":
        from deckpound.analytic.compliance.engine import run_compliance

        return run_compliance
    if name == "run_nonsmooth":
        from deckpound.analytic.nonsmooth.engine import run_nonsmooth

        return run_nonsmooth
    raise AttributeError(name)

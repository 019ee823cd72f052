r"""Exact clone of OpenSees 3.7.1 ``uniaxialMaterial Hysteretic``.

deckpound uses this material as the Takeda-type (Clough/Takeda peak-oriented)
force-deformation law of the bent springs.  The arithmetic lives in one place,
the numba kernels of :mod:`deckpound.analytic.kernels.hysteretic_kernel`;
:class:`HystereticMaterial` is a thin object-oriented wrapper for scripting
and testing, and the kernels are what a per-time-step loop should call.

Model
-----
Backbone: piecewise linear through ``(e1, s1), (e2, s2), (e3, s3)`` on each
side (zero-stress origin), flat at ``s3`` beyond ``e3`` unless the last slope
is positive (then extrapolated).  With only two points per side OpenSees
inserts the midpoint ``(e2, s2) = ((e1+e3)/2, (s1+s3)/2)``.

Unloading from a committed excursion uses the degraded stiffness

.. math::

    k_u = E_u \, \mu^{-\beta}, \qquad
    \mu = \max\!\left(1, \frac{\varepsilon_{\max}}{e_{1p}}\right)
    \text{ (positive side; } \varepsilon_{\min}/e_{1n} \text{ on the negative side)}

where :math:`E_u = \max(E_1, E_2, E_3)` is the largest backbone slope of that
side (normally :math:`k_0 = E_1 = s_1/e_1`) and
:math:`\varepsilon_{\max}` is the largest committed deformation.  After
crossing zero stress at :math:`\varepsilon_0` (e.g. ``rotNu``), reloading is
*peak oriented* (Clough/Takeda): the branch aims at the opposite-side peak
:math:`(\varepsilon_{\max}, \sigma_{env}(\varepsilon_{\max}))` with stiffness

.. math::

    k_r = \frac{\sigma_{env}(\varepsilon_{\max})}{\varepsilon_{\max} - \varepsilon_0},

capped by the unloading line :math:`\sigma_c + k_u\,\Delta\varepsilon`.
With pinching (``pinchX``, ``pinchY`` < 1) the reloading branch is bilinear
through the pinch point and with damage the target peak moves outwards:
:math:`\varepsilon_{\max} \leftarrow \varepsilon_{\max}(1 + D)`,
:math:`D = d_1(\mu_{opp} - 1) + d_2 E/E_A`, with ``E`` the dissipated energy
and ``E_A`` the area under both backbones.

**Takeda stand-in:** ``pinchX = pinchY = 1`` and ``damage1 = damage2 = 0``
leave only the peak-oriented reloading and the :math:`\mu^{-\beta}` unloading
degradation, i.e. the modified Takeda model (``beta`` = 0.5 is the classical
Takeda/Otani value; ``beta = 0`` gives Clough).

Units
-----
Unit-agnostic: ``e*`` are deformations (strain, m or rad) and ``s*`` the
matching stress/force/moment (Pa, kN, kN·m); tangents are ``s/e``.
"""

from __future__ import annotations

import math
from numbers import Real

import numpy as np

from deckpound.analytic.kernels.hysteretic_kernel import (
    hyst_commit,
    hyst_init_state,
    hyst_revert,
    hyst_revert_to_start,
    hyst_set_trial,
)
from deckpound.analytic.kernels.hysteretic_layout import (
    P_E1P_SLOPE,
    T_STRAIN,
    T_STRESS,
    T_TANGENT,
    pack_hysteretic_params,
)

__all__ = ["HystereticMaterial", "pack_hysteretic"]

_NAMES_3PT = (
    "s1p",
    "e1p",
    "s2p",
    "e2p",
    "s3p",
    "e3p",
    "s1n",
    "e1n",
    "s2n",
    "e2n",
    "s3n",
    "e3n",
    "pinchX",
    "pinchY",
    "damage1",
    "damage2",
    "beta",
)
_NAMES_2PT = (
    "s1p",
    "e1p",
    "s2p",
    "e2p",
    "s1n",
    "e1n",
    "s2n",
    "e2n",
    "pinchX",
    "pinchY",
    "damage1",
    "damage2",
    "beta",
)


def _parse(args, beta, element_copy):
    """Validate the OpenSees argument list; return the 3-point parameters."""
    n = len(args)
    if n not in (12, 13, 16, 17):
        raise ValueError(
            f"Hysteretic expects 12 or 13 numbers (2-point backbone) or 16 or "
            f"17 numbers (3-point backbone) after the tag, got {n} positional "
            f"arguments"
        )
    names = _NAMES_2PT if n in (12, 13) else _NAMES_3PT
    vals = list(args)
    if n in (13, 17):
        if beta is not None:
            raise ValueError(
                f"beta was given both positionally ({args[-1]!r}) and as a keyword ({beta!r})"
            )
    else:
        vals.append(0.0 if beta is None else beta)
    out = {}
    for name, v in zip(names, vals):
        if isinstance(v, bool) or not isinstance(v, (Real, np.floating, np.integer)):
            raise ValueError(f"Hysteretic argument {name} must be a real number, got {v!r}")
        fv = float(v)
        if not math.isfinite(fv):
            raise ValueError(f"Hysteretic argument {name} must be finite, got {fv!r}")
        out[name] = fv

    two_point = n in (12, 13)
    if two_point:
        # OpenSees: the 2nd given point becomes point 3; point 2 = midpoint.
        s1p, e1p, s3p, e3p = out["s1p"], out["e1p"], out["s2p"], out["e2p"]
        s1n, e1n, s3n, e3n = out["s1n"], out["e1n"], out["s2n"], out["e2n"]
        n3p, n3n = "e2p", "e2n"
    else:
        s1p, e1p, s3p, e3p = out["s1p"], out["e1p"], out["s3p"], out["e3p"]
        s1n, e1n, s3n, e3n = out["s1n"], out["e1n"], out["s3n"], out["e3n"]
        n3p, n3n = "e3p", "e3n"

    # --- backbone checks (OpenSees: "input backbone is not unique") -------
    if not e1p > 0.0:
        raise ValueError(
            f"Hysteretic argument e1p must be > 0 (first positive "
            f"backbone deformation), got {e1p!r}"
        )
    if not out["s1p"] > 0.0:
        raise ValueError(
            f"Hysteretic argument s1p must be > 0 (positive "
            f"initial stiffness s1p/e1p), got {out['s1p']!r}"
        )
    if not e1n < 0.0:
        raise ValueError(
            f"Hysteretic argument e1n must be < 0 (first negative "
            f"backbone deformation), got {e1n!r}"
        )
    if not out["s1n"] < 0.0:
        raise ValueError(
            f"Hysteretic argument s1n must be < 0 (positive "
            f"initial stiffness s1n/e1n), got {out['s1n']!r}"
        )
    if not two_point:
        if not out["e2p"] > e1p:
            raise ValueError(f"Hysteretic argument e2p must be > e1p = {e1p!r}, got {out['e2p']!r}")
        if not e3p > out["e2p"]:
            raise ValueError(f"Hysteretic argument e3p must be > e2p = {out['e2p']!r}, got {e3p!r}")
        if not out["e2n"] < e1n:
            raise ValueError(f"Hysteretic argument e2n must be < e1n = {e1n!r}, got {out['e2n']!r}")
        if not e3n < out["e2n"]:
            raise ValueError(f"Hysteretic argument e3n must be < e2n = {out['e2n']!r}, got {e3n!r}")
    else:
        if not e3p > e1p:
            raise ValueError(f"Hysteretic argument {n3p} must be > e1p = {e1p!r}, got {e3p!r}")
        if not e3n < e1n:
            raise ValueError(f"Hysteretic argument {n3n} must be < e1n = {e1n!r}, got {e3n!r}")
    for name in ("pinchX", "pinchY"):
        if not 0.0 <= out[name] <= 1.0:
            raise ValueError(f"Hysteretic argument {name} must lie in [0, 1], got {out[name]!r}")
    for name in ("damage1", "damage2", "beta"):
        if out[name] < 0.0:
            raise ValueError(f"Hysteretic argument {name} must be >= 0, got {out[name]!r}")

    if two_point:
        # Same expression order as the OpenSees 2-point constructor.
        energy_2pt = 0.5 * (
            e1p * s1p + (e3p - e1p) * (s3p + s1p) + e1n * s1n + (e3n - e1n) * (s3n + s1n)
        )
        s2p = 0.5 * (s1p + s3p)
        s2n = 0.5 * (s1n + s3n)
        e2p = 0.5 * (e1p + e3p)
        e2n = 0.5 * (e1n + e3n)
    else:
        s2p, e2p, s2n, e2n = out["s2p"], out["e2p"], out["s2n"], out["e2n"]
    energy_3pt = 0.5 * (
        e1p * s1p
        + (e2p - e1p) * (s2p + s1p)
        + (e3p - e2p) * (s3p + s2p)
        + e1n * s1n
        + (e2n - e1n) * (s2n + s1n)
        + (e3n - e2n) * (s3n + s2n)
    )
    energy_a = energy_3pt if (element_copy or not two_point) else energy_2pt
    if not energy_a != 0.0:
        raise ValueError(
            "Hysteretic backbone encloses zero energy (energyA = "
            "0); damage2 normalisation would divide by zero"
        )
    return (
        s1p,
        e1p,
        s2p,
        e2p,
        s3p,
        e3p,
        s1n,
        e1n,
        s2n,
        e2n,
        s3n,
        e3n,
        out["pinchX"],
        out["pinchY"],
        out["damage1"],
        out["damage2"],
        out["beta"],
        energy_a,
    )


def pack_hysteretic(*args, beta=None, element_copy=True):
    """Validate OpenSees ``Hysteretic`` arguments and build the params array.

    Parameters
    ----------
    *args : float
        Exactly the numbers that follow the tag in
        ``uniaxialMaterial('Hysteretic', tag, *args)``: either the 2-point form
        ``s1p, e1p, s2p, e2p, s1n, e1n, s2n, e2n, pinchX, pinchY, damage1,
        damage2[, beta]`` or the 3-point form ``s1p, e1p, s2p, e2p, s3p, e3p,
        s1n, e1n, s2n, e2n, s3n, e3n, pinchX, pinchY, damage1, damage2[,
        beta]``.  ``s*`` in force/stress units, ``e*`` in deformation units.
    beta : float, optional
        Unloading-stiffness exponent (keyword alternative to the last
        positional argument; default 0).
    element_copy : bool, default True
        Only matters for the 2-point form with ``damage2 != 0``.  OpenSees
        elements use ``getCopy()`` of the material, which re-runs the 3-point
        constructor on the midpoint-completed backbone and so computes the
        reference energy ``energyA`` with the 3-segment formula (it differs
        from the 2-segment value in the last bits).  ``True`` clones the
        material inside an element; ``False`` clones the original object as
        driven by ``testUniaxialMaterial``.

    Returns
    -------
    numpy.ndarray
        float64 params array (layout: :mod:`deckpound.analytic.kernels.hysteretic_kernel`).

    Raises
    ------
    ValueError
        Wrong argument count, non-numeric or non-finite value, non-monotonic
        or wrongly signed backbone deformations (OpenSees: "input backbone is
        not unique"), non-positive initial stiffness, pinch factors outside
        [0, 1], or negative damage factors / beta.
    """
    return pack_hysteretic_params(*_parse(args, beta, element_copy))


class HystereticMaterial:
    """OpenSees 3.7.1 ``uniaxialMaterial Hysteretic``, bit-for-bit.

    Construct with the same numbers as
    ``uniaxialMaterial('Hysteretic', tag, ...)`` after the tag (see
    :func:`pack_hysteretic` for the argument list, units and checks).  For the
    Takeda stand-in use ``pinchX = pinchY = 1``, ``damage1 = damage2 = 0``
    and ``beta`` in ``[0, 1)`` (unloading stiffness
    ``k0 * mu**-beta``, ``mu = max committed deformation / e1``).

    The object follows the OpenSees material protocol: :meth:`set_trial_strain`
    computes a trial state, :meth:`commit` accepts it,
    :meth:`revert_to_last_commit` discards it.  OpenSees 3.7.1 quirks are kept
    on purpose:

    * a trial strain within ``2.2e-16`` (absolute) of the committed strain is
      ignored: the previous *trial* stress and tangent stay (OpenSees #1817);
    * :meth:`revert_to_last_commit` does not restore the tangent (there is no
      committed tangent in 3.7.1);
    * a virgin material given ``strain == 0.0`` is left completely untouched.

    Attributes
    ----------
    params : numpy.ndarray
        Kernel parameter array (read-only by convention).
    state : numpy.ndarray
        Kernel state array, mutated in place.
    """

    __slots__ = ("params", "state")

    def __init__(self, *args, beta=None, element_copy=True):
        self.params = pack_hysteretic(*args, beta=beta, element_copy=element_copy)
        self.state = hyst_init_state(self.params)

    # ------------------------------------------------------------- protocol
    def set_trial_strain(self, strain):
        """Set the trial deformation (same units as ``e*``); returns self."""
        strain = float(strain)
        if not math.isfinite(strain):
            raise ValueError(f"trial strain must be finite, got {strain!r}")
        hyst_set_trial(self.params, self.state, strain)
        return self

    def commit(self):
        """Accept the trial state (OpenSees ``commitState``)."""
        hyst_commit(self.state)

    def revert_to_last_commit(self):
        """Discard the trial state (tangent is *not* restored, as in 3.7.1)."""
        hyst_revert(self.state)

    def revert_to_start(self):
        """Back to the virgin committed state (OpenSees ``revertToStart``)."""
        hyst_revert_to_start(self.params, self.state)

    # ----------------------------------------------------------- responses
    @property
    def strain(self):
        """Trial deformation."""
        return float(self.state[T_STRAIN])

    @property
    def stress(self):
        """Trial stress/force for the last trial strain."""
        return float(self.state[T_STRESS])

    @property
    def tangent(self):
        """Trial tangent stiffness (stress/strain units)."""
        return float(self.state[T_TANGENT])

    @property
    def initial_tangent(self):
        """Initial stiffness ``k0 = E1p = s1p / e1p``."""
        return float(self.params[P_E1P_SLOPE])

    def copy(self):
        """Independent copy with identical params and state."""
        new = object.__new__(type(self))
        new.params = self.params.copy()
        new.state = self.state.copy()
        return new

    def __repr__(self):
        p = self.params
        return (
            f"HystereticMaterial(s1p={p[0]!r}, e1p={p[1]!r}, s2p={p[2]!r}, "
            f"e2p={p[3]!r}, s3p={p[4]!r}, e3p={p[5]!r}, s1n={p[6]!r}, "
            f"e1n={p[7]!r}, s2n={p[8]!r}, e2n={p[9]!r}, s3n={p[10]!r}, "
            f"e3n={p[11]!r}, pinchX={p[12]!r}, pinchY={p[13]!r}, "
            f"damage1={p[14]!r}, damage2={p[15]!r}, beta={p[16]!r})"
        )

"""Numba kernels for the OpenSees ``Hysteretic`` uniaxial material.

This module holds the *only* implementation of the material arithmetic in
deckpound; :class:`deckpound.analytic.kernels.hysteretic.HystereticMaterial` is a thin
Python wrapper around it.  The kernels reproduce OpenSees 3.7.1
``HystereticMaterial.cpp`` operation by operation (same branch order, same
floating-point expression order), so that stresses and tangents agree bit for
bit with ``openseespy`` 3.7.1.

Units
-----
The material is unit-agnostic: "strain" is whatever deformation measure the
backbone rotations/strains ``e*`` are given in (e.g. m for a bent spring in
force-displacement form, rad for a moment-rotation hinge) and "stress" is the
matching force measure ``s*`` (kN, kN·m, ...).  Tangents are stress/strain.

Array layouts
-------------
The parameter and state arrays, their indices and :func:`pack_hysteretic_params` are in
:mod:`deckpound.analytic.kernels.hysteretic_layout` (re-exported here).
"""

from __future__ import annotations

import os

import numpy as np
from numba import njit

from deckpound.analytic._jit import kernel
from deckpound.analytic.kernels.hysteretic_layout import (
    C_ENERGYD,
    C_LOADIND,
    C_ROTMAX,
    C_ROTMIN,
    C_ROTNU,
    C_ROTPU,
    C_STRAIN,
    C_STRESS,
    DBL_EPSILON,
    K_KN,
    K_KN_ROT,
    K_KP,
    K_KP_ROT,
    N_STATE,
    NEG_INF_STRAIN,
    P_BETA,
    P_DAMAGE1,
    P_DAMAGE2,
    P_E1N,
    P_E1N_SLOPE,
    P_E1P,
    P_E1P_SLOPE,
    P_E2N,
    P_E2N_SLOPE,
    P_E2P,
    P_E2P_SLOPE,
    P_E3N,
    P_E3N_SLOPE,
    P_E3P,
    P_E3P_SLOPE,
    P_ENERGYA,
    P_EUN,
    P_EUP,
    P_PINCHX,
    P_PINCHY,
    P_S1N,
    P_S1P,
    P_S2N,
    P_S2P,
    P_S3N,
    P_S3P,
    POS_INF_STRAIN,
    R_CH,
    R_K_PINCH,
    R_K_RELOAD,
    R_MOM,
    R_NEG,
    R_POS,
    R_REL,
    R_ROT,
    R_ROT0,
    R_VALID,
    T_ENERGYD,
    T_LOADIND,
    T_ROTMAX,
    T_ROTMIN,
    T_ROTNU,
    T_ROTPU,
    T_STRAIN,
    T_STRESS,
    T_TANGENT,
)

__all__ = [
    "ELASTIC_SHORTCUT",
    "hyst_commit",
    "hyst_init_state",
    "hyst_revert",
    "hyst_revert_to_start",
    "hyst_set_trial",
]

#: The elastic short-circuit of :func:`_degradation` (``pow`` skipped while the ductility is
#: ≤ 1; bit-identical results). ``DECKPOUND_TAKEDA_SHORTCUT=0`` in the environment turns it
#: off, for measurement only (``compare/bench/skips.py``). numba freezes the value at compile time;
#: the package keys its kernel cache by it (:func:`deckpound.analytic._jit.use_source_keyed_cache`).
ELASTIC_SHORTCUT = os.environ.get("DECKPOUND_TAKEDA_SHORTCUT", "1") != "0"


# ------------------------------------------------------------ envelope helpers
@njit(cache=True, inline="always")
def _pos_env_stress(p, strain):
    if strain <= 0.0:
        return 0.0
    elif strain <= p[P_E1P]:
        return p[P_E1P_SLOPE] * strain
    elif strain <= p[P_E2P]:
        return p[P_S1P] + p[P_E2P_SLOPE] * (strain - p[P_E1P])
    elif strain <= p[P_E3P] or p[P_E3P_SLOPE] > 0.0:
        return p[P_S2P] + p[P_E3P_SLOPE] * (strain - p[P_E2P])
    else:
        return p[P_S3P]


@njit(cache=True, inline="always")
def _neg_env_stress(p, strain):
    if strain >= 0.0:
        return 0.0
    elif strain >= p[P_E1N]:
        return p[P_E1N_SLOPE] * strain
    elif strain >= p[P_E2N]:
        return p[P_S1N] + p[P_E2N_SLOPE] * (strain - p[P_E1N])
    elif strain >= p[P_E3N] or p[P_E3N_SLOPE] > 0.0:
        return p[P_S2N] + p[P_E3N_SLOPE] * (strain - p[P_E2N])
    else:
        return p[P_S3N]


@njit(cache=True, inline="always")
def _pos_env_tangent(p, strain):
    if strain < 0.0:
        return p[P_E1P_SLOPE] * 1.0e-9
    elif strain <= p[P_E1P]:
        return p[P_E1P_SLOPE]
    elif strain <= p[P_E2P]:
        return p[P_E2P_SLOPE]
    elif strain <= p[P_E3P] or p[P_E3P_SLOPE] > 0.0:
        return p[P_E3P_SLOPE]
    else:
        return p[P_E1P_SLOPE] * 1.0e-9


@njit(cache=True, inline="always")
def _neg_env_tangent(p, strain):
    if strain > 0.0:
        return p[P_E1N_SLOPE] * 1.0e-9
    elif strain >= p[P_E1N]:
        return p[P_E1N_SLOPE]
    elif strain >= p[P_E2N]:
        return p[P_E2N_SLOPE]
    elif strain >= p[P_E3N] or p[P_E3N_SLOPE] > 0.0:
        return p[P_E3N_SLOPE]
    else:
        return p[P_E1N_SLOPE] * 1.0e-9


@njit(cache=True, inline="always")
def _pos_env_rotlim(p, strain):
    """Strain where the softening positive backbone reaches zero stress."""
    limit = POS_INF_STRAIN
    if strain <= p[P_E1P]:
        return POS_INF_STRAIN
    if strain > p[P_E1P] and strain <= p[P_E2P] and p[P_E2P_SLOPE] < 0.0:
        limit = p[P_E1P] - p[P_S1P] / p[P_E2P_SLOPE]
    if strain > p[P_E2P] and p[P_E3P_SLOPE] < 0.0:
        limit = p[P_E2P] - p[P_S2P] / p[P_E3P_SLOPE]
    if limit == POS_INF_STRAIN or _pos_env_stress(p, limit) > 0.0:
        return POS_INF_STRAIN
    else:
        return limit


@njit(cache=True, inline="always")
def _neg_env_rotlim(p, strain):
    """Strain where the softening negative backbone reaches zero stress."""
    limit = NEG_INF_STRAIN
    if strain >= p[P_E1N]:
        return NEG_INF_STRAIN
    if strain < p[P_E1N] and strain >= p[P_E2N] and p[P_E2N_SLOPE] < 0.0:
        limit = p[P_E1N] - p[P_S1N] / p[P_E2N_SLOPE]
    if strain < p[P_E2N] and p[P_E3N_SLOPE] < 0.0:
        limit = p[P_E2N] - p[P_S2N] / p[P_E3N_SLOPE]
    if limit == NEG_INF_STRAIN or _neg_env_stress(p, limit) < 0.0:
        return NEG_INF_STRAIN
    else:
        return limit


@njit(cache=True, inline="always")
def _degradation(ratio, beta):
    """Unloading-stiffness factor ``k = 1 / max(1, ratio**beta)``.

    ``ratio`` is the committed ductility ``mu = rot_extreme / rot_1``.
    Short-circuit: for ``0 <= ratio <= 1`` and ``beta >= 0`` (enforced by the
    argument checks) IEEE ``pow`` returns a value in ``[0, 1]`` (the exact
    result is <= 1 and 1.0 is representable, so no correctly or faithfully
    rounded ``pow`` can exceed it); OpenSees then yields exactly ``1.0``
    either through ``k < 1 -> 1`` or ``1/1``.  Skipping ``pow`` therefore
    gives the identical double, and keeps the kernel cheap before yielding.
    """
    if ELASTIC_SHORTCUT and ratio <= 1.0 and ratio >= 0.0:
        return 1.0
    k = ratio**beta
    if k < 1.0:
        return 1.0
    return 1.0 / k


@njit(cache=True, inline="always")
def _cached_degradation(p, s, rot, rot1, ik, irot):
    """:func:`_degradation` of the committed excursion ``rot`` (ratio rot/rot1), from the
    state's cache slots ``ik`` (factor) and ``irot`` (the excursion it belongs to)."""
    if s[ik] == 0.0 or s[irot] != rot:
        s[ik] = _degradation(rot / rot1, p[P_BETA])
        s[irot] = rot
    return s[ik]


# ------------------------------------------------------------------- kernels
def hyst_init_state(params):
    """Return a fresh state array (OpenSees constructor: revertToStart +
    revertToLastCommit).  ``params`` as built by ``pack_hysteretic``.

    Plain Python (called once per spring and run, before the loop): a compiled version cost
    a fresh process ~70 ms to load from numba's cache, against microseconds to run."""
    s = np.zeros(N_STATE, dtype=np.float64)
    s[T_TANGENT] = params[P_E1P_SLOPE]
    return s


@kernel
def hyst_revert_to_start(params, state):
    """OpenSees ``revertToStart``: zero committed history and trial
    stress/strain, trial tangent = E1p.  Like OpenSees 3.7.1, the *trial*
    history variables (indices 8-13) are left untouched."""
    state[C_ROTMAX] = 0.0
    state[C_ROTMIN] = 0.0
    state[C_ROTPU] = 0.0
    state[C_ROTNU] = 0.0
    state[C_ENERGYD] = 0.0
    state[C_LOADIND] = 0.0
    state[C_STRESS] = 0.0
    state[C_STRAIN] = 0.0
    state[T_STRAIN] = 0.0
    state[T_STRESS] = 0.0
    state[T_TANGENT] = params[P_E1P_SLOPE]
    state[R_POS + R_VALID] = 0.0
    state[R_NEG + R_VALID] = 0.0


@kernel
def hyst_commit(state):
    """OpenSees ``commitState``: copy trial history/stress/strain to
    committed (there is no committed tangent).

    A reversal cache stays valid while its inputs do not change: the positive one while the
    material keeps loading positively (committed load indicator 1 before and after: no
    reversal, whose point depends on the committed strain and stress) and the excursions and
    the zero-stress strain it read (CrotMax, CrotMin, CrotNu) are unchanged; the negative one
    likewise (indicator 2; CrotMax, CrotMin, CrotPu)."""
    s = state
    same_rot = s[T_ROTMAX] == s[C_ROTMAX] and s[T_ROTMIN] == s[C_ROTMIN]
    if not (s[C_LOADIND] == 1.0 and s[T_LOADIND] == 1.0 and same_rot and s[T_ROTNU] == s[C_ROTNU]):
        s[R_POS + R_VALID] = 0.0
    if not (s[C_LOADIND] == 2.0 and s[T_LOADIND] == 2.0 and same_rot and s[T_ROTPU] == s[C_ROTPU]):
        s[R_NEG + R_VALID] = 0.0
    s[C_ROTMAX] = s[T_ROTMAX]
    s[C_ROTMIN] = s[T_ROTMIN]
    s[C_ROTPU] = s[T_ROTPU]
    s[C_ROTNU] = s[T_ROTNU]
    s[C_ENERGYD] = s[T_ENERGYD]
    s[C_LOADIND] = s[T_LOADIND]
    s[C_STRESS] = s[T_STRESS]
    s[C_STRAIN] = s[T_STRAIN]


@kernel
def hyst_revert(state):
    """OpenSees 3.7.1 ``revertToLastCommit``: trial := committed for history,
    stress and strain; the trial *tangent is not restored* (3.7.1 quirk)."""
    state[T_ROTMAX] = state[C_ROTMAX]
    state[T_ROTMIN] = state[C_ROTMIN]
    state[T_ROTPU] = state[C_ROTPU]
    state[T_ROTNU] = state[C_ROTNU]
    state[T_ENERGYD] = state[C_ENERGYD]
    state[T_LOADIND] = state[C_LOADIND]
    state[T_STRESS] = state[C_STRESS]
    state[T_STRAIN] = state[C_STRAIN]


@njit(cache=True, inline="always")
def _kept_slope(s, slot, a, b, den):
    """The branch slope a·b / den (OpenSees's expression, in its order) of a reversal cache:
    computed at the branch's first call since the cache was filled (the slot holds NaN), then
    read from ``s[slot]``."""
    slope = s[slot]
    if np.isnan(slope):
        slope = a * b / den
        s[slot] = slope
    return slope


@njit(cache=True, inline="always")
def _fill_reversal(s, r, rot, rot0, mom, rel, ch):
    """Fill the reversal cache at ``r`` (R_POS or R_NEG): the trial excursion ``rot``, the
    zero-stress strain ``rot0``, the backbone force ``mom`` there, the release strain ``rel``
    and the pinching strain ``ch``; the two branch slopes marked not computed (NaN)."""
    s[r + R_ROT] = rot
    s[r + R_ROT0] = rot0
    s[r + R_MOM] = mom
    s[r + R_REL] = rel
    s[r + R_CH] = ch
    s[r + R_K_PINCH] = np.nan
    s[r + R_K_RELOAD] = np.nan
    s[r + R_VALID] = 1.0


@njit(cache=True, inline="always")
def _reversal(s, r):
    """The reversal cache at ``r`` as :func:`_fill_reversal` filled it: (excursion,
    zero-stress strain, backbone force, release strain, pinching strain)."""
    return s[r + R_ROT], s[r + R_ROT0], s[r + R_MOM], s[r + R_REL], s[r + R_CH]


@njit(cache=True, inline="always")
def _positive_reversal(p, s, kn, kp):
    """OpenSees ``positiveIncrement`` up to the trial strain: the trial excursion and
    zero-stress strain from the committed state (a reversal from a negative increment moves
    them), the backbone force there, the release and pinching strains; kept in the state's
    positive reversal cache (R_POS), the slopes marked not computed."""
    c_rot_max = s[C_ROTMAX]
    c_rot_min = s[C_ROTMIN]
    c_stress = s[C_STRESS]
    e_up = p[P_EUP]
    e_un = p[P_EUN]
    rot1p = p[P_E1P]
    rot1n = p[P_E1N]
    t_rot_max = c_rot_max
    t_rot_nu = s[C_ROTNU]
    if s[T_LOADIND] == 2.0:
        if c_stress <= 0.0:
            t_rot_nu = s[C_STRAIN] - c_stress / (e_un * kn)
            energy = s[C_ENERGYD] - 0.5 * c_stress / (e_un * kn) * c_stress
            damfc = 0.0
            if c_rot_min < rot1n:
                damfc = p[P_DAMAGE2] * energy / p[P_ENERGYA]
                damfc += p[P_DAMAGE1] * (c_rot_min - rot1n) / rot1n
            t_rot_max = c_rot_max * (1.0 + damfc)
    t_rot_max = min(t_rot_max, POS_INF_STRAIN)
    t_rot_max = max(rot1p, t_rot_max)
    pinch_y = p[P_PINCHY]
    maxmom = _pos_env_stress(p, t_rot_max)
    rotlim = _neg_env_rotlim(p, c_rot_min)
    rotrel = max(t_rot_nu, rotlim)
    rotmp2 = t_rot_max - (1.0 - pinch_y) * maxmom / (e_up * kp)
    rotch = rotrel + (rotmp2 - rotrel) * p[P_PINCHX]
    _fill_reversal(s, R_POS, t_rot_max, t_rot_nu, maxmom, rotrel, rotch)


@njit(cache=True, inline="always")
def _positive_increment(p, s, d_strain):
    c_stress = s[C_STRESS]
    e_up = p[P_EUP]
    e_un = p[P_EUN]
    kn = _cached_degradation(p, s, s[C_ROTMIN], p[P_E1N], K_KN, K_KN_ROT)
    kp = _cached_degradation(p, s, s[C_ROTMAX], p[P_E1P], K_KP, K_KP_ROT)
    r = R_POS
    if s[r + R_VALID] == 0.0:
        _positive_reversal(p, s, kn, kp)
    t_rot_max, t_rot_nu, maxmom, rotrel, rotch = _reversal(s, r)
    s[T_ROTMAX] = t_rot_max
    s[T_ROTNU] = t_rot_nu
    s[T_LOADIND] = 1.0
    pinch_y = p[P_PINCHY]

    t_strain = s[T_STRAIN]
    if t_strain < t_rot_nu:
        tangent = e_un * kn
        stress = c_stress + tangent * d_strain
        if stress >= 0.0:
            stress = 0.0
            tangent = e_un * 1.0e-9
    elif t_strain >= t_rot_nu and t_strain < rotch:
        if t_strain <= rotrel:
            stress = 0.0
            tangent = e_up * 1.0e-9
        else:
            tangent = _kept_slope(s, r + R_K_PINCH, maxmom, pinch_y, rotch - rotrel)
            tmpmo1 = c_stress + e_up * kp * d_strain
            tmpmo2 = (t_strain - rotrel) * tangent
            if tmpmo1 < tmpmo2:
                stress = tmpmo1
                tangent = e_up * kp
            else:
                stress = tmpmo2
    else:
        tangent = _kept_slope(s, r + R_K_RELOAD, 1.0 - pinch_y, maxmom, t_rot_max - rotch)
        tmpmo1 = c_stress + e_up * kp * d_strain
        tmpmo2 = pinch_y * maxmom + (t_strain - rotch) * tangent
        if tmpmo1 < tmpmo2:
            stress = tmpmo1
            tangent = e_up * kp
        else:
            stress = tmpmo2
    s[T_STRESS] = stress
    s[T_TANGENT] = tangent


@njit(cache=True, inline="always")
def _negative_reversal(p, s, kn, kp):
    """OpenSees ``negativeIncrement`` up to the trial strain, as :func:`_positive_reversal`
    (the negative reversal cache, R_NEG)."""
    c_rot_max = s[C_ROTMAX]
    c_rot_min = s[C_ROTMIN]
    c_stress = s[C_STRESS]
    e_up = p[P_EUP]
    e_un = p[P_EUN]
    rot1p = p[P_E1P]
    rot1n = p[P_E1N]
    t_rot_min = c_rot_min
    t_rot_pu = s[C_ROTPU]
    if s[T_LOADIND] == 1.0:
        if c_stress >= 0.0:
            t_rot_pu = s[C_STRAIN] - c_stress / (e_up * kp)
            energy = s[C_ENERGYD] - 0.5 * c_stress / (e_up * kp) * c_stress
            damfc = 0.0
            if c_rot_max > rot1p:
                damfc = p[P_DAMAGE2] * energy / p[P_ENERGYA]
                damfc += p[P_DAMAGE1] * (c_rot_max - rot1p) / rot1p
            t_rot_min = c_rot_min * (1.0 + damfc)
    t_rot_min = max(t_rot_min, NEG_INF_STRAIN)
    t_rot_min = min(rot1n, t_rot_min)
    pinch_y = p[P_PINCHY]
    minmom = _neg_env_stress(p, t_rot_min)
    rotlim = _pos_env_rotlim(p, c_rot_max)
    rotrel = min(t_rot_pu, rotlim)
    rotmp2 = t_rot_min - (1.0 - pinch_y) * minmom / (e_un * kn)
    rotch = rotrel + (rotmp2 - rotrel) * p[P_PINCHX]
    _fill_reversal(s, R_NEG, t_rot_min, t_rot_pu, minmom, rotrel, rotch)


@njit(cache=True, inline="always")
def _negative_increment(p, s, d_strain):
    c_stress = s[C_STRESS]
    e_up = p[P_EUP]
    e_un = p[P_EUN]
    kn = _cached_degradation(p, s, s[C_ROTMIN], p[P_E1N], K_KN, K_KN_ROT)
    kp = _cached_degradation(p, s, s[C_ROTMAX], p[P_E1P], K_KP, K_KP_ROT)
    r = R_NEG
    if s[r + R_VALID] == 0.0:
        _negative_reversal(p, s, kn, kp)
    t_rot_min, t_rot_pu, minmom, rotrel, rotch = _reversal(s, r)
    s[T_ROTMIN] = t_rot_min
    s[T_ROTPU] = t_rot_pu
    s[T_LOADIND] = 2.0
    pinch_y = p[P_PINCHY]

    t_strain = s[T_STRAIN]
    if t_strain > t_rot_pu:
        tangent = e_up * kp
        stress = c_stress + tangent * d_strain
        if stress <= 0.0:
            stress = 0.0
            tangent = e_up * 1.0e-9
    elif t_strain <= t_rot_pu and t_strain > rotch:
        if t_strain >= rotrel:
            stress = 0.0
            tangent = e_un * 1.0e-9
        else:
            tangent = _kept_slope(s, r + R_K_PINCH, minmom, pinch_y, rotch - rotrel)
            tmpmo1 = c_stress + e_un * kn * d_strain
            tmpmo2 = (t_strain - rotrel) * tangent
            if tmpmo1 > tmpmo2:
                stress = tmpmo1
                tangent = e_un * kn
            else:
                stress = tmpmo2
    else:
        tangent = _kept_slope(s, r + R_K_RELOAD, 1.0 - pinch_y, minmom, t_rot_min - rotch)
        tmpmo1 = c_stress + e_un * kn * d_strain
        tmpmo2 = pinch_y * minmom + (t_strain - rotch) * tangent
        if tmpmo1 > tmpmo2:
            stress = tmpmo1
            tangent = e_un * kn
        else:
            stress = tmpmo2
    s[T_STRESS] = stress
    s[T_TANGENT] = tangent


@kernel(inline="always")
def hyst_set_trial(params, state, strain):
    """OpenSees 3.7.1 ``HystereticMaterial::setTrialStrain``.

    Updates ``state`` in place; read ``state[T_STRESS]`` (index 14) and
    ``state[T_TANGENT]`` (index 16) afterwards.  Reproduces two 3.7.1 quirks:

    * virgin material (trial load indicator 0) and ``strain == 0.0``: nothing
      at all is changed (not even the trial strain);
    * ``|strain - committed strain| < DBL_EPSILON`` (2.22e-16, absolute): the
      trial strain is stored and the trial history reset to the committed one,
      but the previous *trial* stress, tangent and load indicator are kept
      (OpenSees issue #1817).

    Cost: no ``pow`` while ``e1n <= CrotMin`` and ``CrotMax <= e1p`` (see
    ``_degradation``); after yielding, one ``pow`` per committed excursion
    that grew since the last call (the state's degradation cache), where
    OpenSees calls ``pow`` twice per call. Inside the hysteresis loop the
    reversal point, pinching strains and branch slopes come from the state's
    reversal caches while the committed values they depend on stay the same
    (:mod:`.hysteretic_layout`), where OpenSees computes them at every call.
    """
    p = params
    s = state
    if s[T_LOADIND] == 0.0 and strain == 0.0:
        return
    s[T_ROTMAX] = s[C_ROTMAX]
    s[T_ROTMIN] = s[C_ROTMIN]
    s[T_ENERGYD] = s[C_ENERGYD]
    s[T_ROTPU] = s[C_ROTPU]
    s[T_ROTNU] = s[C_ROTNU]

    s[T_STRAIN] = strain
    d_strain = strain - s[C_STRAIN]
    if abs(d_strain) < DBL_EPSILON:
        return

    load = s[C_LOADIND]
    if load == 0.0:
        load = 2.0 if d_strain < 0.0 else 1.0
    s[T_LOADIND] = load

    if strain >= s[C_ROTMAX]:
        s[T_ROTMAX] = strain
        s[T_TANGENT] = _pos_env_tangent(p, strain)
        s[T_STRESS] = _pos_env_stress(p, strain)
        s[T_LOADIND] = 1.0
    elif strain <= s[C_ROTMIN]:
        s[T_ROTMIN] = strain
        s[T_TANGENT] = _neg_env_tangent(p, strain)
        s[T_STRESS] = _neg_env_stress(p, strain)
        s[T_LOADIND] = 2.0
    else:
        if d_strain < 0.0:
            _negative_increment(p, s, d_strain)
        elif d_strain > 0.0:
            _positive_increment(p, s, d_strain)

    s[T_ENERGYD] = s[C_ENERGYD] + 0.5 * (s[C_STRESS] + s[T_STRESS]) * d_strain

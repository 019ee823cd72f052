"""Parameter and state arrays of the OpenSees ``Hysteretic`` material clone.

The data format of :mod:`deckpound.analytic.kernels.hysteretic_kernel` (which re-exports all of
this): index constants, the OpenSees strain clamp and ``DBL_EPSILON``, and
:func:`pack_hysteretic_params`.

Array layouts
-------------
Parameters (``params``, float64, length :data:`N_PARAMS`, read-only to the
kernels; build with :func:`pack_hysteretic`):

====  ===========  =====================================================
idx   name         meaning
====  ===========  =====================================================
0-5   s1p..e3p     positive backbone (s1p, e1p, s2p, e2p, s3p, e3p)
6-11  s1n..e3n     negative backbone (s1n, e1n, s2n, e2n, s3n, e3n)
12    pinchX       deformation pinching factor
13    pinchY       force pinching factor
14    damage1      ductility damage factor
15    damage2      energy damage factor
16    beta         unloading-stiffness degradation exponent
17-19 E1p,E2p,E3p  positive backbone slopes
20-22 E1n,E2n,E3n  negative backbone slopes
23    Eup          max(E1p, E2p, E3p): elastic reloading stiffness (+)
24    Eun          max(E1n, E2n, E3n): elastic reloading stiffness (-)
25    energyA      reference energy of the backbone (damage2 normaliser)
====  ===========  =====================================================

State (``state``, float64, length :data:`N_STATE`, mutated in place; build
with :func:`hyst_init_state`).  Load indicators are stored as 0.0/1.0/2.0
(0 = virgin, 1 = last increment positive, 2 = last increment negative):

====  ==============  ==============================================
idx   name            meaning
====  ==============  ==============================================
0     CrotMax         committed max strain (positive excursion)
1     CrotMin         committed min strain (negative excursion)
2     CrotPu          committed zero-stress strain after + unloading
3     CrotNu          committed zero-stress strain after - unloading
4     CenergyD        committed dissipated energy
5     CloadIndicator  committed load indicator
6     Cstress         committed stress
7     Cstrain         committed strain
8     TrotMax         trial counterpart of 0
9     TrotMin         trial counterpart of 1
10    TrotPu          trial counterpart of 2
11    TrotNu          trial counterpart of 3
12    TenergyD        trial counterpart of 4
13    TloadIndicator  trial counterpart of 5
14    Tstress         trial stress         (read this after set_trial)
15    Tstrain         trial strain
16    Ttangent        trial tangent        (read this after set_trial)
17    kn              cache: unloading-stiffness factor of CrotMin
18    knRot           cache: the CrotMin that kn was computed for
19    kp              cache: unloading-stiffness factor of CrotMax
20    kpRot           cache: the CrotMax that kp was computed for
21-28 reversal (+)    cache: the positive increment's reversal point
29-36 reversal (-)    cache: the negative increment's reversal point
====  ==============  ==============================================

The cache (17-20) is not OpenSees state: ``kn``/``kp`` are the pure
functions :func:`_degradation` of the committed excursions, which OpenSees
recomputes (two ``pow`` calls) at every trial strain once the material has
yielded.  They change only when a committed excursion grows, so they are kept
with the excursion they belong to and recomputed when it differs (or when
``kn``/``kp`` is 0.0, i.e. never computed: a zero-filled state is valid).
The same ``pow`` on the same arguments gives the same double, so results are
bit-identical; it removes ~20 % of the Newmark loop's time after yielding.

The reversal caches (21-36) hold what an increment inside the hysteresis loop computes
before it looks at the trial strain, the same for every trial strain of a step: OpenSees's
``positiveIncrement`` (``negativeIncrement``) sets the trial excursion and zero-stress strain
from the committed state, then the backbone force at the excursion, the release and
pinching strains, and divides by the reloading slopes. All of these are functions of the
committed state and the direction of the increment; Newton asks for several trial strains
per step, and the cache gives the later ones the numbers of the first: per direction, a
valid flag, the trial excursion and zero-stress strain, the backbone force, the release and
pinching strains, and the two slopes of the pinched and the reloading branch, each
computed when its branch is first taken (NaN until then). :func:`hyst_commit` and
``revertToStart`` clear a flag when the committed values that cache read change (while the
material keeps loading in one direction inside the loop, they do not, and the cache serves
step after step); ``revertToLastCommit`` leaves the committed state, and the flags, as they
are. The same expressions on the same doubles: results are bit-identical.

There is deliberately no committed tangent: OpenSees 3.7.1 does not keep one,
so ``revertToLastCommit`` leaves the trial tangent untouched.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "C_ENERGYD",
    "C_LOADIND",
    "C_ROTMAX",
    "C_ROTMIN",
    "C_ROTNU",
    "C_ROTPU",
    "C_STRAIN",
    "C_STRESS",
    "DBL_EPSILON",
    "K_KN",
    "K_KN_ROT",
    "K_KP",
    "K_KP_ROT",
    "NEG_INF_STRAIN",
    "N_PARAMS",
    "N_STATE",
    "POS_INF_STRAIN",
    "P_BETA",
    "P_DAMAGE1",
    "P_DAMAGE2",
    "P_E1N",
    "P_E1N_SLOPE",
    "P_E1P",
    "P_E1P_SLOPE",
    "P_E2N",
    "P_E2N_SLOPE",
    "P_E2P",
    "P_E2P_SLOPE",
    "P_E3N",
    "P_E3N_SLOPE",
    "P_E3P",
    "P_E3P_SLOPE",
    "P_ENERGYA",
    "P_EUN",
    "P_EUP",
    "P_PINCHX",
    "P_PINCHY",
    "P_S1N",
    "P_S1P",
    "P_S2N",
    "P_S2P",
    "P_S3N",
    "P_S3P",
    "R_CH",
    "R_K_PINCH",
    "R_K_RELOAD",
    "R_MOM",
    "R_NEG",
    "R_POS",
    "R_REL",
    "R_ROT",
    "R_ROT0",
    "R_VALID",
    "T_ENERGYD",
    "T_LOADIND",
    "T_ROTMAX",
    "T_ROTMIN",
    "T_ROTNU",
    "T_ROTPU",
    "T_STRAIN",
    "T_STRESS",
    "T_TANGENT",
    "pack_hysteretic_params",
]

#: Strain clamp used by OpenSees (``UniaxialMaterial.h``).
POS_INF_STRAIN = 1.0e16
NEG_INF_STRAIN = -1.0e16
#: ``DBL_EPSILON``: trial-strain increments smaller than this are ignored.
DBL_EPSILON = 2.0**-52  # 2.220446049250313e-16

# ---------------------------------------------------------------- parameters
P_S1P, P_E1P, P_S2P, P_E2P, P_S3P, P_E3P = 0, 1, 2, 3, 4, 5
P_S1N, P_E1N, P_S2N, P_E2N, P_S3N, P_E3N = 6, 7, 8, 9, 10, 11
P_PINCHX, P_PINCHY, P_DAMAGE1, P_DAMAGE2, P_BETA = 12, 13, 14, 15, 16
P_E1P_SLOPE, P_E2P_SLOPE, P_E3P_SLOPE = 17, 18, 19
P_E1N_SLOPE, P_E2N_SLOPE, P_E3N_SLOPE = 20, 21, 22
P_EUP, P_EUN, P_ENERGYA = 23, 24, 25
N_PARAMS = 26

# --------------------------------------------------------------------- state
C_ROTMAX, C_ROTMIN, C_ROTPU, C_ROTNU, C_ENERGYD, C_LOADIND = 0, 1, 2, 3, 4, 5
C_STRESS, C_STRAIN = 6, 7
T_ROTMAX, T_ROTMIN, T_ROTPU, T_ROTNU, T_ENERGYD, T_LOADIND = 8, 9, 10, 11, 12, 13
T_STRESS, T_STRAIN, T_TANGENT = 14, 15, 16
K_KN, K_KN_ROT, K_KP, K_KP_ROT = 17, 18, 19, 20  # degradation cache
# reversal caches, the positive increment's then the negative one's (8 slots each):
# valid flag, trial excursion, trial zero-stress strain, backbone force at the excursion,
# release strain, pinching strain, slope of the pinched branch, slope of the reloading branch
R_POS, R_NEG = 21, 29
R_VALID, R_ROT, R_ROT0, R_MOM, R_REL, R_CH, R_K_PINCH, R_K_RELOAD = 0, 1, 2, 3, 4, 5, 6, 7
N_STATE = 37


def pack_hysteretic_params(
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
    pinch_x,
    pinch_y,
    damage1,
    damage2,
    beta,
    energy_a,
):
    """Assemble a params array from an (already validated) 3-point backbone.

    No validation happens here; use
    :func:`deckpound.analytic.kernels.hysteretic.pack_hysteretic`, which parses the
    OpenSees argument list, checks it and computes ``energy_a``.

    Returns
    -------
    numpy.ndarray
        float64 array of length :data:`N_PARAMS` (layout in module docstring).
    """
    p = np.empty(N_PARAMS, dtype=np.float64)
    p[P_S1P], p[P_E1P], p[P_S2P], p[P_E2P], p[P_S3P], p[P_E3P] = (s1p, e1p, s2p, e2p, s3p, e3p)
    p[P_S1N], p[P_E1N], p[P_S2N], p[P_E2N], p[P_S3N], p[P_E3N] = (s1n, e1n, s2n, e2n, s3n, e3n)
    p[P_PINCHX], p[P_PINCHY] = pinch_x, pinch_y
    p[P_DAMAGE1], p[P_DAMAGE2], p[P_BETA] = damage1, damage2, beta
    # Envelope slopes (OpenSees setEnvelope); Python float arithmetic is
    # IEEE binary64, identical to the C++ expressions.
    e1p_s = s1p / e1p
    e2p_s = (s2p - s1p) / (e2p - e1p)
    e3p_s = (s3p - s2p) / (e3p - e2p)
    e1n_s = s1n / e1n
    e2n_s = (s2n - s1n) / (e2n - e1n)
    e3n_s = (s3n - s2n) / (e3n - e2n)
    eup = e1p_s
    eup = max(eup, e2p_s)
    eup = max(eup, e3p_s)
    eun = e1n_s
    eun = max(eun, e2n_s)
    eun = max(eun, e3n_s)
    p[P_E1P_SLOPE], p[P_E2P_SLOPE], p[P_E3P_SLOPE] = e1p_s, e2p_s, e3p_s
    p[P_E1N_SLOPE], p[P_E2N_SLOPE], p[P_E3N_SLOPE] = e1n_s, e2n_s, e3n_s
    p[P_EUP], p[P_EUN], p[P_ENERGYA] = eup, eun, energy_a
    return p

"""The reference loop's algorithm written in numba: what numba makes of the lean loop.

``reference.c`` is the yardstick of issue 33; this module is the same loop, statement for
statement, as one numba function over flat arrays, run on the same input file. It separates two
questions the comparison with the C loop mixes: how far numba's code is from gcc's on the same
lean algorithm, and how much deckpound's loop does or pays beyond that algorithm (its extras,
its bundles of arrays). Its answer matches the C loop's (status, Newton iterations,
factorisations, peaks) bit for bit; ``tests/test_reference_loop.py`` checks that.

As in the C file, the DOF count is a compile-time constant of the loop (a closure variable,
which numba freezes), so the DOF loops have constant bounds. Repository tooling, not part of
the package.

Usage::

    model = load_inputs(path)          # the input file run.py writes (reference.c's layout)
    loop = lean_loop(model.ndof)       # compiles on its first call (not timed by run_lean)
    report = run_lean(model, repeats=3)
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from deckpound.analytic.fp_mode import flush_enter, flush_leave

__all__ = ["LeanModel", "lean_loop", "load_inputs", "run_lean"]

REF_FORMAT = 33001.0
N_HARGS = 13
# material parameters (reference.c's enum)
(P_S1P, P_E1P, P_S2P, P_E2P, P_S3P, P_E3P, P_S1N, P_E1N, P_S2N, P_E2N, P_S3N, P_E3N,
 P_PINCHX, P_PINCHY, P_DAMAGE1, P_DAMAGE2, P_BETA, P_E1P_SLOPE, P_E2P_SLOPE, P_E3P_SLOPE,
 P_E1N_SLOPE, P_E2N_SLOPE, P_E3N_SLOPE, P_EUP, P_EUN, P_ENERGYA, N_P) = range(27)  # fmt: skip
# material state (reference.c's HystState): committed, trial, unloading factors
(CROT_MAX, CROT_MIN, CROT_PU, CROT_NU, CENERGY, CLOAD, CSTRESS, CSTRAIN,
 TROT_MAX, TROT_MIN, TROT_PU, TROT_NU, TENERGY, TLOAD, TSTRESS, TSTRAIN, TTANGENT,
 KP, KN, KP_ROT, KN_ROT, N_S) = range(22)  # fmt: skip
POS_INF_STRAIN = 1.0e16
NEG_INF_STRAIN = -1.0e16
DBL_EPS = 2.220446049250313e-16
ST_OK, ST_NOT_CONVERGED, ST_SINGULAR, ST_NONFINITE = range(4)
STATUS_NAMES = ("ok", "not converged", "singular", "non-finite")


@dataclass(frozen=True)
class LeanModel:
    """The problem of an input file (reference.c's Model): counts, scalars and arrays."""

    ndof: int
    nsteps: int
    maxit: int
    dt: float
    tol: float
    gamma: float
    beta: float
    flush: bool
    mass: np.ndarray  # (ndof,)
    K: np.ndarray  # (ndof, ndof)
    Kg: np.ndarray  # (ndof, nchan)
    C: np.ndarray  # (ndof, ndof)
    Cg: np.ndarray  # (ndof, nchan)
    hdof: np.ndarray  # (nhyst, 2) int64
    hcoef: np.ndarray  # (nhyst, 2)
    hnnz: np.ndarray  # (nhyst,) int64
    hchan: np.ndarray  # (nhyst,) int64, −1: none
    hchan_coef: np.ndarray  # (nhyst,)
    hparams: np.ndarray  # (nhyst, N_P)
    g0: np.ndarray  # (ncorner,)
    kc: np.ndarray  # (ncorner,)
    w: np.ndarray  # (ncorner, ndof)
    u0: np.ndarray
    v0: np.ndarray
    ug: np.ndarray  # (nsteps + 1, nchan)
    vg: np.ndarray


def _params(a: np.ndarray) -> np.ndarray:
    """reference.c's hyst_params: the 2-point form completed to the 3-point backbone."""
    s1p, e1p, s3p, e3p, s1n, e1n, s3n, e3n = (float(x) for x in a[:8])
    s2p, s2n = 0.5 * (s1p + s3p), 0.5 * (s1n + s3n)
    e2p, e2n = 0.5 * (e1p + e3p), 0.5 * (e1n + e3n)
    p = np.zeros(N_P)
    p[:12] = (s1p, e1p, s2p, e2p, s3p, e3p, s1n, e1n, s2n, e2n, s3n, e3n)
    p[P_PINCHX : P_BETA + 1] = a[8:13]
    p[P_E1P_SLOPE] = s1p / e1p
    p[P_E2P_SLOPE] = (s2p - s1p) / (e2p - e1p)
    p[P_E3P_SLOPE] = (s3p - s2p) / (e3p - e2p)
    p[P_E1N_SLOPE] = s1n / e1n
    p[P_E2N_SLOPE] = (s2n - s1n) / (e2n - e1n)
    p[P_E3N_SLOPE] = (s3n - s2n) / (e3n - e2n)
    p[P_EUP] = _max2(_max2(p[P_E1P_SLOPE], p[P_E2P_SLOPE]), p[P_E3P_SLOPE])
    p[P_EUN] = _max2(_max2(p[P_E1N_SLOPE], p[P_E2N_SLOPE]), p[P_E3N_SLOPE])
    p[P_ENERGYA] = 0.5 * (
        e1p * s1p + (e2p - e1p) * (s2p + s1p) + (e3p - e2p) * (s3p + s2p)
        + e1n * s1n + (e2n - e1n) * (s2n + s1n) + (e3n - e2n) * (s3n + s2n)
    )  # fmt: skip
    return p


def load_inputs(path: Path) -> LeanModel:
    """Read an input file of reference.c's layout (its header comment)."""
    x = np.fromfile(path, dtype="<f8")
    pos = 0

    def take(n: int | None = None):
        nonlocal pos
        if n is None:
            pos += 1
            return float(x[pos - 1])
        pos += n
        return x[pos - n : pos].copy()

    if take() != REF_FORMAT:
        raise ValueError(f"{path}: not an input file of format {REF_FORMAT}")
    nd, nh, nch, nc, nsteps, maxit = (int(take()) for _ in range(6))
    dt, tol, gamma, beta = (take() for _ in range(4))
    flush = bool(take())
    mass = take(nd)
    K = take(nd * nd).reshape(nd, nd)
    Kg = take(nd * nch).reshape(nd, nch)
    C = take(nd * nd).reshape(nd, nd)
    Cg = take(nd * nch).reshape(nd, nch)
    hdof, hcoef = np.zeros((nh, 2), np.int64), np.zeros((nh, 2))
    hnnz, hchan = np.zeros(nh, np.int64), np.zeros(nh, np.int64)
    hchan_coef, hparams = np.zeros(nh), np.zeros((nh, N_P))
    for h in range(nh):
        hnnz[h] = int(take())
        hdof[h] = (int(take()), int(take()))
        hcoef[h] = (take(), take())
        hchan[h] = int(take())
        hchan_coef[h] = take()
        hparams[h] = _params(take(N_HARGS))
    g0, kc, w = np.zeros(nc), np.zeros(nc), np.zeros((nc, nd))
    for c in range(nc):
        g0[c], kc[c] = take(), take()
        w[c] = take(nd)
    u0, v0 = take(nd), take(nd)
    ug = take((nsteps + 1) * nch).reshape(nsteps + 1, nch)
    vg = take((nsteps + 1) * nch).reshape(nsteps + 1, nch)
    if pos != x.size:
        raise ValueError(f"{path}: longer than its counts say")
    return LeanModel(nd, nsteps, maxit, dt, tol, gamma, beta, flush, mass, K, Kg, C, Cg,
                     hdof, hcoef, hnnz, hchan, hchan_coef, hparams, g0, kc, w, u0, v0, ug,
                     vg)  # fmt: skip


# ------------------------------------------------------------ OpenSees Hysteretic 3.7.1
# IEEE division without numba's zero-divisor test, as in C and in the engines' kernels
jit = numba.njit(_nrt=False, inline="always", error_model="numpy")


@jit
def _max2(a, b):
    return b if b > a else a


@jit
def _min2(a, b):
    return b if b < a else a


@jit
def _pos_env_stress(P, h, e):
    if e <= 0.0:
        return 0.0
    if e <= P[h, P_E1P]:
        return P[h, P_E1P_SLOPE] * e
    if e <= P[h, P_E2P]:
        return P[h, P_S1P] + P[h, P_E2P_SLOPE] * (e - P[h, P_E1P])
    if e <= P[h, P_E3P] or P[h, P_E3P_SLOPE] > 0.0:
        return P[h, P_S2P] + P[h, P_E3P_SLOPE] * (e - P[h, P_E2P])
    return P[h, P_S3P]


@jit
def _neg_env_stress(P, h, e):
    if e >= 0.0:
        return 0.0
    if e >= P[h, P_E1N]:
        return P[h, P_E1N_SLOPE] * e
    if e >= P[h, P_E2N]:
        return P[h, P_S1N] + P[h, P_E2N_SLOPE] * (e - P[h, P_E1N])
    if e >= P[h, P_E3N] or P[h, P_E3N_SLOPE] > 0.0:
        return P[h, P_S2N] + P[h, P_E3N_SLOPE] * (e - P[h, P_E2N])
    return P[h, P_S3N]


@jit
def _pos_env_tangent(P, h, e):
    if e < 0.0:
        return P[h, P_E1P_SLOPE] * 1.0e-9
    if e <= P[h, P_E1P]:
        return P[h, P_E1P_SLOPE]
    if e <= P[h, P_E2P]:
        return P[h, P_E2P_SLOPE]
    if e <= P[h, P_E3P] or P[h, P_E3P_SLOPE] > 0.0:
        return P[h, P_E3P_SLOPE]
    return P[h, P_E1P_SLOPE] * 1.0e-9


@jit
def _neg_env_tangent(P, h, e):
    if e > 0.0:
        return P[h, P_E1N_SLOPE] * 1.0e-9
    if e >= P[h, P_E1N]:
        return P[h, P_E1N_SLOPE]
    if e >= P[h, P_E2N]:
        return P[h, P_E2N_SLOPE]
    if e >= P[h, P_E3N] or P[h, P_E3N_SLOPE] > 0.0:
        return P[h, P_E3N_SLOPE]
    return P[h, P_E1N_SLOPE] * 1.0e-9


@jit
def _pos_env_rotlim(P, h, e):
    limit = POS_INF_STRAIN
    if e <= P[h, P_E1P]:
        return POS_INF_STRAIN
    if e > P[h, P_E1P] and e <= P[h, P_E2P] and P[h, P_E2P_SLOPE] < 0.0:
        limit = P[h, P_E1P] - P[h, P_S1P] / P[h, P_E2P_SLOPE]
    if e > P[h, P_E2P] and P[h, P_E3P_SLOPE] < 0.0:
        limit = P[h, P_E2P] - P[h, P_S2P] / P[h, P_E3P_SLOPE]
    if limit == POS_INF_STRAIN or _pos_env_stress(P, h, limit) > 0.0:
        return POS_INF_STRAIN
    return limit


@jit
def _neg_env_rotlim(P, h, e):
    limit = NEG_INF_STRAIN
    if e >= P[h, P_E1N]:
        return NEG_INF_STRAIN
    if e < P[h, P_E1N] and e >= P[h, P_E2N] and P[h, P_E2N_SLOPE] < 0.0:
        limit = P[h, P_E1N] - P[h, P_S1N] / P[h, P_E2N_SLOPE]
    if e < P[h, P_E2N] and P[h, P_E3N_SLOPE] < 0.0:
        limit = P[h, P_E2N] - P[h, P_S2N] / P[h, P_E3N_SLOPE]
    if limit == NEG_INF_STRAIN or _neg_env_stress(P, h, limit) < 0.0:
        return NEG_INF_STRAIN
    return limit


@jit
def _degradation(ratio, beta):
    if ratio <= 1.0 and ratio >= 0.0:
        return 1.0
    k = ratio**beta
    if k < 1.0:
        return 1.0
    return 1.0 / k


@jit
def _positive_increment(P, S, h, d_strain):
    c_rot_max, c_rot_min, c_stress = S[h, CROT_MAX], S[h, CROT_MIN], S[h, CSTRESS]
    e_up, e_un, rot1p, rot1n = P[h, P_EUP], P[h, P_EUN], P[h, P_E1P], P[h, P_E1N]
    kn, kp = S[h, KN], S[h, KP]
    if S[h, TLOAD] == 2.0:
        if c_stress <= 0.0:
            S[h, TROT_NU] = S[h, CSTRAIN] - c_stress / (e_un * kn)
            energy = S[h, CENERGY] - 0.5 * c_stress / (e_un * kn) * c_stress
            damfc = 0.0
            if c_rot_min < rot1n:
                damfc = P[h, P_DAMAGE2] * energy / P[h, P_ENERGYA]
                damfc += P[h, P_DAMAGE1] * (c_rot_min - rot1n) / rot1n
            S[h, TROT_MAX] = c_rot_max * (1.0 + damfc)
    S[h, TLOAD] = 1.0
    t_rot_max = _max2(rot1p, _min2(S[h, TROT_MAX], POS_INF_STRAIN))
    S[h, TROT_MAX] = t_rot_max
    t_rot_nu, pinch_y = S[h, TROT_NU], P[h, P_PINCHY]
    maxmom = _pos_env_stress(P, h, t_rot_max)
    rotrel = _max2(t_rot_nu, _neg_env_rotlim(P, h, c_rot_min))
    rotmp2 = t_rot_max - (1.0 - pinch_y) * maxmom / (e_up * kp)
    rotch = rotrel + (rotmp2 - rotrel) * P[h, P_PINCHX]
    t_strain = S[h, TSTRAIN]
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
            tangent = maxmom * pinch_y / (rotch - rotrel)
            tmpmo1 = c_stress + e_up * kp * d_strain
            tmpmo2 = (t_strain - rotrel) * tangent
            if tmpmo1 < tmpmo2:
                stress = tmpmo1
                tangent = e_up * kp
            else:
                stress = tmpmo2
    else:
        tangent = (1.0 - pinch_y) * maxmom / (t_rot_max - rotch)
        tmpmo1 = c_stress + e_up * kp * d_strain
        tmpmo2 = pinch_y * maxmom + (t_strain - rotch) * tangent
        if tmpmo1 < tmpmo2:
            stress = tmpmo1
            tangent = e_up * kp
        else:
            stress = tmpmo2
    S[h, TSTRESS] = stress
    S[h, TTANGENT] = tangent


@jit
def _negative_increment(P, S, h, d_strain):
    c_rot_max, c_rot_min, c_stress = S[h, CROT_MAX], S[h, CROT_MIN], S[h, CSTRESS]
    e_up, e_un, rot1p, rot1n = P[h, P_EUP], P[h, P_EUN], P[h, P_E1P], P[h, P_E1N]
    kn, kp = S[h, KN], S[h, KP]
    if S[h, TLOAD] == 1.0:
        if c_stress >= 0.0:
            S[h, TROT_PU] = S[h, CSTRAIN] - c_stress / (e_up * kp)
            energy = S[h, CENERGY] - 0.5 * c_stress / (e_up * kp) * c_stress
            damfc = 0.0
            if c_rot_max > rot1p:
                damfc = P[h, P_DAMAGE2] * energy / P[h, P_ENERGYA]
                damfc += P[h, P_DAMAGE1] * (c_rot_max - rot1p) / rot1p
            S[h, TROT_MIN] = c_rot_min * (1.0 + damfc)
    S[h, TLOAD] = 2.0
    t_rot_min = _min2(rot1n, _max2(S[h, TROT_MIN], NEG_INF_STRAIN))
    S[h, TROT_MIN] = t_rot_min
    t_rot_pu, pinch_y = S[h, TROT_PU], P[h, P_PINCHY]
    minmom = _neg_env_stress(P, h, t_rot_min)
    rotrel = _min2(t_rot_pu, _pos_env_rotlim(P, h, c_rot_max))
    rotmp2 = t_rot_min - (1.0 - pinch_y) * minmom / (e_un * kn)
    rotch = rotrel + (rotmp2 - rotrel) * P[h, P_PINCHX]
    t_strain = S[h, TSTRAIN]
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
            tangent = minmom * pinch_y / (rotch - rotrel)
            tmpmo1 = c_stress + e_un * kn * d_strain
            tmpmo2 = (t_strain - rotrel) * tangent
            if tmpmo1 > tmpmo2:
                stress = tmpmo1
                tangent = e_un * kn
            else:
                stress = tmpmo2
    else:
        tangent = (1.0 - pinch_y) * minmom / (t_rot_min - rotch)
        tmpmo1 = c_stress + e_un * kn * d_strain
        tmpmo2 = pinch_y * minmom + (t_strain - rotch) * tangent
        if tmpmo1 > tmpmo2:
            stress = tmpmo1
            tangent = e_un * kn
        else:
            stress = tmpmo2
    S[h, TSTRESS] = stress
    S[h, TTANGENT] = tangent


@jit
def _hyst_set_trial(P, S, h, strain):
    """HystereticMaterial::setTrialStrain (3.7.1), as reference.c's hyst_set_trial (inlined
    into the loop, as every helper of the material here)."""
    if S[h, TLOAD] == 0.0 and strain == 0.0:
        return
    S[h, TROT_MAX] = S[h, CROT_MAX]
    S[h, TROT_MIN] = S[h, CROT_MIN]
    S[h, TENERGY] = S[h, CENERGY]
    S[h, TROT_PU] = S[h, CROT_PU]
    S[h, TROT_NU] = S[h, CROT_NU]
    S[h, TSTRAIN] = strain
    d_strain = strain - S[h, CSTRAIN]
    if abs(d_strain) < DBL_EPS:
        return
    load = S[h, CLOAD]
    if load == 0.0:
        load = 2.0 if d_strain < 0.0 else 1.0
    S[h, TLOAD] = load
    if strain >= S[h, CROT_MAX]:
        S[h, TROT_MAX] = strain
        S[h, TTANGENT] = _pos_env_tangent(P, h, strain)
        S[h, TSTRESS] = _pos_env_stress(P, h, strain)
        S[h, TLOAD] = 1.0
    elif strain <= S[h, CROT_MIN]:
        S[h, TROT_MIN] = strain
        S[h, TTANGENT] = _neg_env_tangent(P, h, strain)
        S[h, TSTRESS] = _neg_env_stress(P, h, strain)
        S[h, TLOAD] = 2.0
    elif d_strain < 0.0:
        _negative_increment(P, S, h, d_strain)
    elif d_strain > 0.0:
        _positive_increment(P, S, h, d_strain)
    S[h, TENERGY] = S[h, CENERGY] + 0.5 * (S[h, CSTRESS] + S[h, TSTRESS]) * d_strain


@jit
def _hyst_commit(P, S, h):
    S[h, CROT_MAX] = S[h, TROT_MAX]
    S[h, CROT_MIN] = S[h, TROT_MIN]
    S[h, CROT_PU] = S[h, TROT_PU]
    S[h, CROT_NU] = S[h, TROT_NU]
    S[h, CENERGY] = S[h, TENERGY]
    S[h, CLOAD] = S[h, TLOAD]
    S[h, CSTRESS] = S[h, TSTRESS]
    S[h, CSTRAIN] = S[h, TSTRAIN]
    if S[h, CROT_MAX] != S[h, KP_ROT]:
        S[h, KP] = _degradation(S[h, CROT_MAX] / P[h, P_E1P], P[h, P_BETA])
        S[h, KP_ROT] = S[h, CROT_MAX]
    if S[h, CROT_MIN] != S[h, KN_ROT]:
        S[h, KN] = _degradation(S[h, CROT_MIN] / P[h, P_E1N], P[h, P_BETA])
        S[h, KN_ROT] = S[h, CROT_MIN]


def _initial_states(hparams: np.ndarray) -> np.ndarray:
    """reference.c's hyst_init for every spring."""
    s = np.zeros((hparams.shape[0], N_S))
    s[:, TTANGENT] = hparams[:, P_E1P_SLOPE]
    s[:, KP] = 1.0
    s[:, KN] = 1.0
    return s


# --------------------------------------------------------------------- the step loop
@functools.cache
def lean_loop(NDOF: int):  # NDOF: reference.c's name of the compile-time DOF count
    """The step loop for NDOF DOF (a compile-time constant of it: numba freezes the closure
    variable), reference.c's ``residual`` and ``run``; compiled on its first call, one
    compiled function per DOF count."""

    @numba.njit(_nrt=False, inline="always", error_model="numpy")
    def residual(m, hs, ugn, u, v, a, R, pg, kt, closed, f):
        """R = F_c − F − M ü at the trial (u, u̇) with the step's support forces pg; the
        springs' tangents kt and the closed corners (the factorisation key). f: scratch."""
        (K, C, mass, hdof, hcoef, hnnz, hchan, hchan_coef, hparams, g0, kc, wc) = m
        for i in range(NDOF):
            s = -pg[i]
            for j in range(NDOF):
                s += K[i, j] * u[j] + C[i, j] * v[j]
            f[i] = s
        for h in range(hs.shape[0]):
            d = 0.0
            for q in range(hnnz[h]):
                d += hcoef[h, q] * u[hdof[h, q]]
            if hchan[h] >= 0:
                d -= hchan_coef[h] * ugn[hchan[h]]
            _hyst_set_trial(hparams, hs, h, d)
            fs = hs[h, TSTRESS]
            kt[h] = hs[h, TTANGENT]
            for q in range(hnnz[h]):
                f[hdof[h, q]] += hcoef[h, q] * fs
        for c in range(g0.shape[0]):
            g = g0[c]
            for j in range(NDOF):
                g += wc[c, j] * u[j]
            closed[c] = g <= 0.0
            if g <= 0.0:
                lam = -kc[c] * g
                for j in range(NDOF):
                    f[j] -= wc[c, j] * lam
        for i in range(NDOF):
            R[i] = -f[i] - mass[i] * a[i]

    @numba.njit(_nrt=False, nogil=True, error_model="numpy")
    def run(model, work, hs, ug, vg, Kg, Cg, nsteps, maxit, dt, tol, gamma, beta, u0, v0,
            flush, peak, peak_time):  # fmt: skip
        """reference.c's ``run``: the whole record from the initial state; fills peak and
        peak_time (|u_j| over every step) and returns (status, failed step, Newton
        iterations, factorisations, most iterations of a step)."""
        (K, C, mass, hdof, hcoef, hnnz, hchan, hchan_coef, hparams, g0, kc, wc) = model
        (u, v, a, R, du, pg, f, x, inv_diag, kt, kt_fact, closed, closed_fact, LU, Kbase,
         perm) = work  # fmt: skip
        saved = flush_enter(flush)
        nh, nc, nch = hs.shape[0], g0.shape[0], ug.shape[1]
        have_factors = False
        c2, c3 = gamma / (beta * dt), 1.0 / (beta * dt * dt)
        tol2 = tol * tol
        a1p, a2p = 1.0 - gamma / beta, dt * (1.0 - 0.5 * gamma / beta)
        a3p, a4p = -1.0 / (beta * dt), 1.0 - 0.5 / beta
        for i in range(NDOF):
            for j in range(NDOF):
                Kbase[i, j] = K[i, j] + c2 * C[i, j]
        for i in range(NDOF):
            Kbase[i, i] += c3 * mass[i]
        status, failed, newton, facts, max_it = ST_OK, 0, 0, 0, 0
        for j in range(NDOF):
            u[j] = u0[j]
            v[j] = v0[j]
            a[j] = 0.0
        for i in range(NDOF):
            s = 0.0
            for k in range(nch):
                s += Kg[i, k] * ug[0, k] + Cg[i, k] * vg[0, k]
            pg[i] = s
        residual(model, hs, ug[0], u, v, a, R, pg, kt, closed, f)
        for i in range(NDOF):
            a[i] = R[i] / mass[i]
        for h in range(nh):
            _hyst_commit(hparams, hs, h)
        for j in range(NDOF):
            peak[j] = abs(u[j])
            peak_time[j] = 0.0
        for n in range(nsteps):
            ugn, vgn = ug[n + 1], vg[n + 1]
            for i in range(NDOF):
                s = 0.0
                for k in range(nch):
                    s += Kg[i, k] * ugn[k] + Cg[i, k] * vgn[k]
                pg[i] = s
            for j in range(NDOF):
                vn, an = v[j], a[j]
                v[j] = a1p * vn + a2p * an
                a[j] = a4p * an + a3p * vn
            residual(model, hs, ugn, u, v, a, R, pg, kt, closed, f)
            it = 0
            while True:
                reuse = have_factors
                if reuse:
                    for h in range(nh):
                        if kt[h] != kt_fact[h]:
                            reuse = False
                    for c in range(nc):
                        if closed[c] != closed_fact[c]:
                            reuse = False
                if not reuse:
                    facts += 1
                    for i in range(NDOF):
                        for j in range(NDOF):
                            LU[i, j] = Kbase[i, j]
                    for h in range(nh):
                        for q in range(hnnz[h]):
                            bq = hcoef[h, q] * kt[h]
                            for r in range(hnnz[h]):
                                LU[hdof[h, q], hdof[h, r]] += bq * hcoef[h, r]
                        kt_fact[h] = kt[h]
                    for c in range(nc):
                        closed_fact[c] = closed[c]
                        if closed[c]:
                            for i in range(NDOF):
                                for j in range(NDOF):
                                    LU[i, j] += kc[c] * wc[c, i] * wc[c, j]
                    for i in range(NDOF):
                        perm[i] = i
                    singular = False
                    for k in range(NDOF):
                        p = k
                        best = abs(LU[k, k])
                        for i in range(k + 1, NDOF):
                            if abs(LU[i, k]) > best:
                                best = abs(LU[i, k])
                                p = i
                        if best == 0.0:
                            singular = True
                            break
                        if p != k:
                            t = perm[k]
                            perm[k] = perm[p]
                            perm[p] = t
                            for j in range(NDOF):
                                t2 = LU[k, j]
                                LU[k, j] = LU[p, j]
                                LU[p, j] = t2
                        inv = 1.0 / LU[k, k]
                        inv_diag[k] = inv
                        for i in range(k + 1, NDOF):
                            lk = LU[i, k] * inv
                            LU[i, k] = lk
                            for j in range(k + 1, NDOF):
                                LU[i, j] -= lk * LU[k, j]
                    if singular:
                        status, failed = ST_SINGULAR, n + 1
                        break
                    have_factors = True
                for i in range(NDOF):
                    x[i] = R[perm[i]]
                for k in range(NDOF):
                    for i in range(k + 1, NDOF):
                        x[i] -= LU[i, k] * x[k]
                for k in range(NDOF - 1, -1, -1):
                    s = x[k]
                    for j in range(k + 1, NDOF):
                        s -= LU[k, j] * x[j]
                    x[k] = s * inv_diag[k]
                nrm2 = 0.0
                moved = False
                for j in range(NDOF):
                    du[j] = x[j]
                    uj = u[j] + du[j]
                    moved = moved or uj != u[j]
                    u[j] = uj
                    v[j] += c2 * du[j]
                    a[j] += c3 * du[j]
                    nrm2 += du[j] * du[j]
                it += 1
                if not math.isfinite(nrm2):
                    status, failed = ST_NONFINITE, n + 1
                    break
                if nrm2 <= tol2:
                    if moved:
                        for h in range(nh):
                            d = 0.0
                            for q in range(hnnz[h]):
                                d += hcoef[h, q] * u[hdof[h, q]]
                            if hchan[h] >= 0:
                                d -= hchan_coef[h] * ugn[hchan[h]]
                            _hyst_set_trial(hparams, hs, h, d)
                    break
                if it >= maxit:
                    status, failed = ST_NOT_CONVERGED, n + 1
                    break
                residual(model, hs, ugn, u, v, a, R, pg, kt, closed, f)
            newton += it
            if status != ST_OK:
                break
            max_it = max(max_it, it)
            for h in range(nh):
                _hyst_commit(hparams, hs, h)
            t = (n + 1) * dt
            for j in range(NDOF):
                xj = abs(u[j])
                if xj > peak[j]:
                    peak[j] = xj
                    peak_time[j] = t
        flush_leave(saved)
        return status, failed, newton, facts, max_it

    return run


def run_lean(model: LeanModel, repeats: int = 1) -> dict:
    """Run the whole record ``repeats`` times from the initial state (after one untimed run
    that compiles the loop); reference.c's report: status, counts, peaks, each repeat's loop
    time [s] (time.perf_counter around the compiled call only)."""
    loop = lean_loop(model.ndof)
    m = (model.K, model.C, model.mass, model.hdof, model.hcoef, model.hnnz, model.hchan,
         model.hchan_coef, model.hparams, model.g0, model.kc, model.w)  # fmt: skip
    nd, nh, nc = model.ndof, model.hparams.shape[0], model.g0.shape[0]
    peak, peak_time = np.zeros(nd), np.zeros(nd)
    work = tuple(np.zeros(nd) for _ in range(9)) + (
        np.zeros(nh), np.zeros(nh), np.zeros(nc, np.bool_), np.zeros(nc, np.bool_),
        np.zeros((nd, nd)), np.zeros((nd, nd)), np.zeros(nd, np.int64),
    )  # fmt: skip
    times = []
    for r in range(repeats + 1):
        hs = _initial_states(model.hparams)
        t0 = time.perf_counter()
        status, failed, newton, facts, max_it = loop(
            m, work, hs, model.ug, model.vg, model.Kg, model.Cg, model.nsteps, model.maxit,
            model.dt, model.tol, model.gamma, model.beta, model.u0, model.v0, model.flush,
            peak, peak_time,
        )  # fmt: skip
        if r:  # the first run compiles the loop (once per process) and touches the pages
            times.append(time.perf_counter() - t0)
    return {
        "status": STATUS_NAMES[status],
        "failed_step": int(failed),
        "steps": model.nsteps if status == ST_OK else int(failed) - 1,
        "newton_iterations": int(newton),
        "factorisations": int(facts),
        "max_step_iterations": int(max_it),
        "peak": peak.tolist(),
        "peak_time": peak_time.tolist(),
        "loop_seconds": times,
    }

/*
 * reference.c: a lean, hand-written Newmark–Newton step loop of the plan model, the yardstick
 * for the step loops of deckpound's compliance engine (issue 33); not part of the package:
 * run.py writes the input file, compiles this file and runs it (README.md).
 *
 * The problem (every number comes from the input file; the C code knows no model):
 *
 *     M ü + C u̇ + K u + Σ_h b_h f_h(d_h) = Σ_c w_cᵀ λ_c + K_g u_g(t) + C_g u̇_g(t)
 *
 *   M diagonal mass; K the stiffness of the linear springs, C the constant damping matrix
 *   (Rayleigh + dashpots, on the linear and the hysteretic springs alike), K_g and C_g the
 *   matrices that give the linear springs' and the dashpots' support forces; h the hysteretic
 *   springs, d_h = b_h·u − s_h u_g[ch_h] with at most 2 non-zeros in b_h, f_h the OpenSees
 *   3.7.1 ``Hysteretic`` material (its setTrialStrain / commitState, branch for branch, with
 *   its quirks); c the contact corners with linear gaps g_c = g0_c + w_c·u and the linear law
 *   λ_c = −k_c g_c for g_c ≤ 0, else 0 (OpenSees ElasticPPGap with F_y → ∞).
 *
 * The algorithm (the OpenSees transient analysis the compliance engine clones):
 *   Newmark γ, β (displacement form, constant-displacement predictor), supports at t_{n+1},
 *   full Newton on K_eff = K + Σ_h k_t,h b_h b_hᵀ + γ/(βΔt) C + 1/(βΔt²) M + Σ_closed k_c w_c w_cᵀ,
 *   NormDispIncr test ‖Δu‖₂ ≤ tol with at most maxit solves; materials committed after
 *   convergence; ü₀ from M ü₀ = F_c − F at t = 0.
 *
 * What makes it lean (and what it leaves out, README.md):
 *   - K_eff is factorised only when its key changes: the tangents of the hysteretic springs
 *     (bitwise) and the set of closed corners. The same key means the same matrix bit for bit,
 *     so the factors are those a refactorisation would give.
 *   - The support forces K_g u_g + C_g u̇_g are formed once per step, not per iteration.
 *   - At a converged iterate only the materials' trial strains are set (what the commit
 *     needs); the residual is not formed there (the next step forms its own). When the last
 *     increment left u bitwise unchanged not even that.
 *   - The triangular solves apply the row exchanges at once and multiply by the inverse pivots;
 *     the convergence test compares ‖Δu‖₂² with tol² (no square root).
 *   - The unloading-stiffness factors μ^−β of the material are recomputed at a commit when a
 *     committed excursion grew (they are functions of it), not at every trial.
 *   - Per step it keeps only the peak |u_j| of every DOF and its time; no output rows, no energy
 *     work, no sub-stepping fallback (a step that does not converge ends the run, status 1).
 *
 * Compile: gcc -O3 -march=native -std=c11 -DNDOF=<n> reference.c -o reference -lm
 *   (NDOF must equal the file's DOF count: the DOF loops then have compile-time bounds; ISO C
 *   so that gcc does not fuse a·b + c, as numba does not).
 * Run:     reference INPUT [REPEATS]
 *   runs the whole record REPEATS times (default 1) from the initial state; prints one JSON
 *   object: status, counts, peaks and the wall time of each repeat's step loop (clock_gettime
 *   CLOCK_MONOTONIC around the loop only; reading the file is outside).
 *
 * Two switches emulate what deckpound's loop does in addition, to measure what it costs:
 *   -DREF_REFACTOR_CONTACT  factorise at every iteration while a corner is closed
 *   -DREF_FULL_RESIDUAL     form the whole residual (springs and contacts) at the converged
 *                           iterate too, as OpenSees and deckpound do
 *
 * Input file: little-endian float64 values, in this order (counts stored as exact doubles):
 *   FORMAT (= REF_FORMAT below), ndof, nhyst, nchan, ncorner, nsteps, maxit, dt, tol, gamma, beta,
 *   flush (1: subnormal numbers flushed to zero while the loop runs, x86 FTZ/DAZ, as the
 *   compliance engine's ``subnormals = "flush"``; 0: IEEE gradual underflow),
 *   mass[ndof], K[ndof·ndof], Kg[ndof·nchan], C[ndof·ndof], Cg[ndof·nchan] (row-major),
 *   per hysteretic spring: nnz, dof0, dof1, coef0, coef1, channel (−1: none), channel_coef,
 *     the 13 numbers after the tag of OpenSees `uniaxialMaterial Hysteretic` (2-point form),
 *   per corner: g0, k, w[ndof],
 *   u0[ndof], v0[ndof],
 *   ug[(nsteps+1)·nchan], vg[(nsteps+1)·nchan]: the support motion at t_n = n·dt.
 * Units: those of the file (deckpound: kN, m, t, s, rad).
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#ifndef NDOF
#error "compile with -DNDOF=<number of DOF> (run.py passes the input file's DOF count)"
#endif

#define REF_FORMAT 33001.0
#define N_HARGS 13

/* ------------------------------------------------------------ OpenSees Hysteretic 3.7.1 */
/* parameters (3-point backbone after the 2-point constructor's mid-point completion) */
enum {
    P_S1P, P_E1P, P_S2P, P_E2P, P_S3P, P_E3P,
    P_S1N, P_E1N, P_S2N, P_E2N, P_S3N, P_E3N,
    P_PINCHX, P_PINCHY, P_DAMAGE1, P_DAMAGE2, P_BETA,
    P_E1P_SLOPE, P_E2P_SLOPE, P_E3P_SLOPE, P_E1N_SLOPE, P_E2N_SLOPE, P_E3N_SLOPE,
    P_EUP, P_EUN, P_ENERGYA, N_P
};
#define POS_INF_STRAIN 1.0e16
#define NEG_INF_STRAIN -1.0e16
#define DBL_EPS 2.220446049250313e-16

/* Python's max(a, b) and min(a, b) (a unless b is larger / smaller), as the clone computes
   them; inline comparisons, where fmax/fmin are library calls under ISO C */
static inline double max2(double a, double b) { return b > a ? b : a; }
static inline double min2(double a, double b) { return b < a ? b : a; }

typedef struct {
    /* committed */
    double crot_max, crot_min, crot_pu, crot_nu, cenergy, cload, cstress, cstrain;
    /* trial */
    double trot_max, trot_min, trot_pu, trot_nu, tenergy, tload, tstress, tstrain, ttangent;
    /* unloading factors of the committed excursions and the excursions they belong to */
    double kp, kn, kp_rot, kn_rot;
} HystState;

typedef struct {
    double p[N_P];
    int nnz, dof[2], chan;
    double coef[2], chan_coef;
    HystState s;
} Hyst;

static void hyst_params(const double *a, double *p)
{
    /* the 2-point form: the given 2nd point becomes point 3, point 2 is the mid-point */
    double s1p = a[0], e1p = a[1], s3p = a[2], e3p = a[3];
    double s1n = a[4], e1n = a[5], s3n = a[6], e3n = a[7];
    double s2p = 0.5 * (s1p + s3p), s2n = 0.5 * (s1n + s3n);
    double e2p = 0.5 * (e1p + e3p), e2n = 0.5 * (e1n + e3n);
    p[P_S1P] = s1p; p[P_E1P] = e1p; p[P_S2P] = s2p; p[P_E2P] = e2p; p[P_S3P] = s3p; p[P_E3P] = e3p;
    p[P_S1N] = s1n; p[P_E1N] = e1n; p[P_S2N] = s2n; p[P_E2N] = e2n; p[P_S3N] = s3n; p[P_E3N] = e3n;
    p[P_PINCHX] = a[8]; p[P_PINCHY] = a[9]; p[P_DAMAGE1] = a[10]; p[P_DAMAGE2] = a[11];
    p[P_BETA] = a[12];
    p[P_E1P_SLOPE] = s1p / e1p;
    p[P_E2P_SLOPE] = (s2p - s1p) / (e2p - e1p);
    p[P_E3P_SLOPE] = (s3p - s2p) / (e3p - e2p);
    p[P_E1N_SLOPE] = s1n / e1n;
    p[P_E2N_SLOPE] = (s2n - s1n) / (e2n - e1n);
    p[P_E3N_SLOPE] = (s3n - s2n) / (e3n - e2n);
    p[P_EUP] = max2(max2(p[P_E1P_SLOPE], p[P_E2P_SLOPE]), p[P_E3P_SLOPE]);
    p[P_EUN] = max2(max2(p[P_E1N_SLOPE], p[P_E2N_SLOPE]), p[P_E3N_SLOPE]);
    p[P_ENERGYA] = 0.5 * (e1p * s1p + (e2p - e1p) * (s2p + s1p) + (e3p - e2p) * (s3p + s2p)
                          + e1n * s1n + (e2n - e1n) * (s2n + s1n) + (e3n - e2n) * (s3n + s2n));
}

static double pos_env_stress(const double *p, double e)
{
    if (e <= 0.0) return 0.0;
    if (e <= p[P_E1P]) return p[P_E1P_SLOPE] * e;
    if (e <= p[P_E2P]) return p[P_S1P] + p[P_E2P_SLOPE] * (e - p[P_E1P]);
    if (e <= p[P_E3P] || p[P_E3P_SLOPE] > 0.0) return p[P_S2P] + p[P_E3P_SLOPE] * (e - p[P_E2P]);
    return p[P_S3P];
}

static double neg_env_stress(const double *p, double e)
{
    if (e >= 0.0) return 0.0;
    if (e >= p[P_E1N]) return p[P_E1N_SLOPE] * e;
    if (e >= p[P_E2N]) return p[P_S1N] + p[P_E2N_SLOPE] * (e - p[P_E1N]);
    if (e >= p[P_E3N] || p[P_E3N_SLOPE] > 0.0) return p[P_S2N] + p[P_E3N_SLOPE] * (e - p[P_E2N]);
    return p[P_S3N];
}

static double pos_env_tangent(const double *p, double e)
{
    if (e < 0.0) return p[P_E1P_SLOPE] * 1.0e-9;
    if (e <= p[P_E1P]) return p[P_E1P_SLOPE];
    if (e <= p[P_E2P]) return p[P_E2P_SLOPE];
    if (e <= p[P_E3P] || p[P_E3P_SLOPE] > 0.0) return p[P_E3P_SLOPE];
    return p[P_E1P_SLOPE] * 1.0e-9;
}

static double neg_env_tangent(const double *p, double e)
{
    if (e > 0.0) return p[P_E1N_SLOPE] * 1.0e-9;
    if (e >= p[P_E1N]) return p[P_E1N_SLOPE];
    if (e >= p[P_E2N]) return p[P_E2N_SLOPE];
    if (e >= p[P_E3N] || p[P_E3N_SLOPE] > 0.0) return p[P_E3N_SLOPE];
    return p[P_E1N_SLOPE] * 1.0e-9;
}

static double pos_env_rotlim(const double *p, double e)
{
    double limit = POS_INF_STRAIN;
    if (e <= p[P_E1P]) return POS_INF_STRAIN;
    if (e > p[P_E1P] && e <= p[P_E2P] && p[P_E2P_SLOPE] < 0.0)
        limit = p[P_E1P] - p[P_S1P] / p[P_E2P_SLOPE];
    if (e > p[P_E2P] && p[P_E3P_SLOPE] < 0.0) limit = p[P_E2P] - p[P_S2P] / p[P_E3P_SLOPE];
    if (limit == POS_INF_STRAIN || pos_env_stress(p, limit) > 0.0) return POS_INF_STRAIN;
    return limit;
}

static double neg_env_rotlim(const double *p, double e)
{
    double limit = NEG_INF_STRAIN;
    if (e >= p[P_E1N]) return NEG_INF_STRAIN;
    if (e < p[P_E1N] && e >= p[P_E2N] && p[P_E2N_SLOPE] < 0.0)
        limit = p[P_E1N] - p[P_S1N] / p[P_E2N_SLOPE];
    if (e < p[P_E2N] && p[P_E3N_SLOPE] < 0.0) limit = p[P_E2N] - p[P_S2N] / p[P_E3N_SLOPE];
    if (limit == NEG_INF_STRAIN || neg_env_stress(p, limit) < 0.0) return NEG_INF_STRAIN;
    return limit;
}

/* unloading-stiffness factor 1 / max(1, μ^β) of a committed ductility μ (pow skipped for
   0 ≤ μ ≤ 1, where it would give ≤ 1 and so the factor exactly 1) */
static double degradation(double ratio, double beta)
{
    if (ratio <= 1.0 && ratio >= 0.0) return 1.0;
    double k = pow(ratio, beta);
    if (k < 1.0) return 1.0;
    return 1.0 / k;
}

static void positive_increment(const double *p, HystState *s, double d_strain)
{
    double c_rot_max = s->crot_max, c_rot_min = s->crot_min, c_stress = s->cstress;
    double e_up = p[P_EUP], e_un = p[P_EUN], rot1p = p[P_E1P], rot1n = p[P_E1N];
    double kn = s->kn, kp = s->kp;
    if (s->tload == 2.0) {
        if (c_stress <= 0.0) {
            s->trot_nu = s->cstrain - c_stress / (e_un * kn);
            double energy = s->cenergy - 0.5 * c_stress / (e_un * kn) * c_stress;
            double damfc = 0.0;
            if (c_rot_min < rot1n) {
                damfc = p[P_DAMAGE2] * energy / p[P_ENERGYA];
                damfc += p[P_DAMAGE1] * (c_rot_min - rot1n) / rot1n;
            }
            s->trot_max = c_rot_max * (1.0 + damfc);
        }
    }
    s->tload = 1.0;
    double t_rot_max = s->trot_max;
    t_rot_max = min2(t_rot_max, POS_INF_STRAIN);
    t_rot_max = max2(rot1p, t_rot_max);
    s->trot_max = t_rot_max;
    double t_rot_nu = s->trot_nu, pinch_y = p[P_PINCHY];
    double maxmom = pos_env_stress(p, t_rot_max);
    double rotlim = neg_env_rotlim(p, c_rot_min);
    double rotrel = max2(t_rot_nu, rotlim);
    double rotmp2 = t_rot_max - (1.0 - pinch_y) * maxmom / (e_up * kp);
    double rotch = rotrel + (rotmp2 - rotrel) * p[P_PINCHX];
    double t_strain = s->tstrain, stress, tangent;
    if (t_strain < t_rot_nu) {
        tangent = e_un * kn;
        stress = c_stress + tangent * d_strain;
        if (stress >= 0.0) {
            stress = 0.0;
            tangent = e_un * 1.0e-9;
        }
    } else if (t_strain >= t_rot_nu && t_strain < rotch) {
        if (t_strain <= rotrel) {
            stress = 0.0;
            tangent = e_up * 1.0e-9;
        } else {
            tangent = maxmom * pinch_y / (rotch - rotrel);
            double tmpmo1 = c_stress + e_up * kp * d_strain;
            double tmpmo2 = (t_strain - rotrel) * tangent;
            if (tmpmo1 < tmpmo2) {
                stress = tmpmo1;
                tangent = e_up * kp;
            } else {
                stress = tmpmo2;
            }
        }
    } else {
        tangent = (1.0 - pinch_y) * maxmom / (t_rot_max - rotch);
        double tmpmo1 = c_stress + e_up * kp * d_strain;
        double tmpmo2 = pinch_y * maxmom + (t_strain - rotch) * tangent;
        if (tmpmo1 < tmpmo2) {
            stress = tmpmo1;
            tangent = e_up * kp;
        } else {
            stress = tmpmo2;
        }
    }
    s->tstress = stress;
    s->ttangent = tangent;
}

static void negative_increment(const double *p, HystState *s, double d_strain)
{
    double c_rot_max = s->crot_max, c_rot_min = s->crot_min, c_stress = s->cstress;
    double e_up = p[P_EUP], e_un = p[P_EUN], rot1p = p[P_E1P], rot1n = p[P_E1N];
    double kn = s->kn, kp = s->kp;
    if (s->tload == 1.0) {
        if (c_stress >= 0.0) {
            s->trot_pu = s->cstrain - c_stress / (e_up * kp);
            double energy = s->cenergy - 0.5 * c_stress / (e_up * kp) * c_stress;
            double damfc = 0.0;
            if (c_rot_max > rot1p) {
                damfc = p[P_DAMAGE2] * energy / p[P_ENERGYA];
                damfc += p[P_DAMAGE1] * (c_rot_max - rot1p) / rot1p;
            }
            s->trot_min = c_rot_min * (1.0 + damfc);
        }
    }
    s->tload = 2.0;
    double t_rot_min = s->trot_min;
    t_rot_min = max2(t_rot_min, NEG_INF_STRAIN);
    t_rot_min = min2(rot1n, t_rot_min);
    s->trot_min = t_rot_min;
    double t_rot_pu = s->trot_pu, pinch_y = p[P_PINCHY];
    double minmom = neg_env_stress(p, t_rot_min);
    double rotlim = pos_env_rotlim(p, c_rot_max);
    double rotrel = min2(t_rot_pu, rotlim);
    double rotmp2 = t_rot_min - (1.0 - pinch_y) * minmom / (e_un * kn);
    double rotch = rotrel + (rotmp2 - rotrel) * p[P_PINCHX];
    double t_strain = s->tstrain, stress, tangent;
    if (t_strain > t_rot_pu) {
        tangent = e_up * kp;
        stress = c_stress + tangent * d_strain;
        if (stress <= 0.0) {
            stress = 0.0;
            tangent = e_up * 1.0e-9;
        }
    } else if (t_strain <= t_rot_pu && t_strain > rotch) {
        if (t_strain >= rotrel) {
            stress = 0.0;
            tangent = e_un * 1.0e-9;
        } else {
            tangent = minmom * pinch_y / (rotch - rotrel);
            double tmpmo1 = c_stress + e_un * kn * d_strain;
            double tmpmo2 = (t_strain - rotrel) * tangent;
            if (tmpmo1 > tmpmo2) {
                stress = tmpmo1;
                tangent = e_un * kn;
            } else {
                stress = tmpmo2;
            }
        }
    } else {
        tangent = (1.0 - pinch_y) * minmom / (t_rot_min - rotch);
        double tmpmo1 = c_stress + e_un * kn * d_strain;
        double tmpmo2 = pinch_y * minmom + (t_strain - rotch) * tangent;
        if (tmpmo1 > tmpmo2) {
            stress = tmpmo1;
            tangent = e_un * kn;
        } else {
            stress = tmpmo2;
        }
    }
    s->tstress = stress;
    s->ttangent = tangent;
}

/* HystereticMaterial::setTrialStrain (3.7.1): a virgin material given 0 is left untouched; an
   increment below DBL_EPSILON keeps the previous trial stress, tangent and load indicator */
static void hyst_set_trial(const double *p, HystState *s, double strain)
{
    if (s->tload == 0.0 && strain == 0.0) return;
    s->trot_max = s->crot_max;
    s->trot_min = s->crot_min;
    s->tenergy = s->cenergy;
    s->trot_pu = s->crot_pu;
    s->trot_nu = s->crot_nu;
    s->tstrain = strain;
    double d_strain = strain - s->cstrain;
    if (fabs(d_strain) < DBL_EPS) return;
    double load = s->cload;
    if (load == 0.0) load = d_strain < 0.0 ? 2.0 : 1.0;
    s->tload = load;
    if (strain >= s->crot_max) {
        s->trot_max = strain;
        s->ttangent = pos_env_tangent(p, strain);
        s->tstress = pos_env_stress(p, strain);
        s->tload = 1.0;
    } else if (strain <= s->crot_min) {
        s->trot_min = strain;
        s->ttangent = neg_env_tangent(p, strain);
        s->tstress = neg_env_stress(p, strain);
        s->tload = 2.0;
    } else if (d_strain < 0.0) {
        negative_increment(p, s, d_strain);
    } else if (d_strain > 0.0) {
        positive_increment(p, s, d_strain);
    }
    s->tenergy = s->cenergy + 0.5 * (s->cstress + s->tstress) * d_strain;
}

static void hyst_commit(const double *p, HystState *s)
{
    s->crot_max = s->trot_max;
    s->crot_min = s->trot_min;
    s->crot_pu = s->trot_pu;
    s->crot_nu = s->trot_nu;
    s->cenergy = s->tenergy;
    s->cload = s->tload;
    s->cstress = s->tstress;
    s->cstrain = s->tstrain;
    /* the factors change only when a committed excursion grows */
    if (s->crot_max != s->kp_rot) {
        s->kp = degradation(s->crot_max / p[P_E1P], p[P_BETA]);
        s->kp_rot = s->crot_max;
    }
    if (s->crot_min != s->kn_rot) {
        s->kn = degradation(s->crot_min / p[P_E1N], p[P_BETA]);
        s->kn_rot = s->crot_min;
    }
}

static void hyst_init(const double *p, HystState *s)
{
    memset(s, 0, sizeof *s);
    s->ttangent = p[P_E1P_SLOPE];
    s->kp = 1.0;
    s->kn = 1.0;
}

/* ------------------------------------------------------------------------- the model */
typedef struct {
    int nhyst, nchan, ncorner, nsteps, maxit;
    double dt, tol, gamma, beta;
    int flush;
    double mass[NDOF], K[NDOF][NDOF], C[NDOF][NDOF];
    double *Kg, *Cg;      /* NDOF × nchan */
    Hyst *hyst;           /* nhyst */
    double *g0, *kc, *w;  /* ncorner, ncorner, ncorner × NDOF */
    double u0[NDOF], v0[NDOF];
    double *ug, *vg;      /* (nsteps + 1) × nchan */
} Model;

typedef struct {
    int status, failed_step;
    long newton, factorisations, max_iterations;
    double peak[NDOF], peak_time[NDOF];
} Outcome;

static void fail(const char *what)
{
    fprintf(stderr, "reference: %s\n", what);
    exit(2);
}

static double take(const double **cur, const double *end)
{
    if (*cur >= end) fail("input file too short");
    return *(*cur)++;
}

static int take_count(const double **cur, const double *end, const char *name, int lo)
{
    double x = take(cur, end);
    if (!(x >= lo) || x != floor(x) || x > 1e9) {
        fprintf(stderr, "reference: %s = %g is not a count >= %d\n", name, x, lo);
        exit(2);
    }
    return (int)x;
}

static double *take_array(const double **cur, const double *end, long n)
{
    if (end - *cur < n) fail("input file too short");
    double *out = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    if (!out) fail("out of memory");
    memcpy(out, *cur, sizeof(double) * (size_t)n);
    *cur += n;
    return out;
}

static void read_model(const char *path, Model *m)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail("cannot open the input file");
    fseek(f, 0, SEEK_END);
    long bytes = ftell(f);
    fseek(f, 0, SEEK_SET);
    if (bytes <= 0 || bytes % 8) fail("the input file is not a whole number of float64");
    double *buf = malloc((size_t)bytes);
    if (!buf || fread(buf, 1, (size_t)bytes, f) != (size_t)bytes) fail("cannot read the input");
    fclose(f);
    const double *cur = buf, *end = buf + bytes / 8;
    if (take(&cur, end) != REF_FORMAT) fail("not an input file of this format (REF_FORMAT)");
    int ndof = take_count(&cur, end, "ndof", 1);
    if (ndof != NDOF) {
        fprintf(stderr, "reference: the file has %d DOF, compiled for NDOF = %d\n", ndof, NDOF);
        exit(2);
    }
    m->nhyst = take_count(&cur, end, "nhyst", 0);
    m->nchan = take_count(&cur, end, "nchan", 0);
    m->ncorner = take_count(&cur, end, "ncorner", 0);
    m->nsteps = take_count(&cur, end, "nsteps", 1);
    m->maxit = take_count(&cur, end, "maxit", 1);
    m->dt = take(&cur, end);
    m->tol = take(&cur, end);
    m->gamma = take(&cur, end);
    m->beta = take(&cur, end);
    m->flush = take_count(&cur, end, "flush", 0);
    for (int i = 0; i < NDOF; i++) m->mass[i] = take(&cur, end);
    for (int i = 0; i < NDOF; i++)
        for (int j = 0; j < NDOF; j++) m->K[i][j] = take(&cur, end);
    m->Kg = take_array(&cur, end, (long)NDOF * m->nchan);
    for (int i = 0; i < NDOF; i++)
        for (int j = 0; j < NDOF; j++) m->C[i][j] = take(&cur, end);
    m->Cg = take_array(&cur, end, (long)NDOF * m->nchan);
    m->hyst = calloc((size_t)(m->nhyst > 0 ? m->nhyst : 1), sizeof(Hyst));
    if (!m->hyst) fail("out of memory");
    for (int h = 0; h < m->nhyst; h++) {
        Hyst *s = &m->hyst[h];
        s->nnz = take_count(&cur, end, "spring nnz", 0);
        if (s->nnz > 2) fail("a hysteretic spring with more than 2 DOF in its deformation");
        s->dof[0] = take_count(&cur, end, "spring dof", 0);
        s->dof[1] = take_count(&cur, end, "spring dof", 0);
        s->coef[0] = take(&cur, end);
        s->coef[1] = take(&cur, end);
        s->chan = (int)take(&cur, end);
        s->chan_coef = take(&cur, end);
        if (s->dof[0] >= NDOF || s->dof[1] >= NDOF || s->chan >= m->nchan)
            fail("a hysteretic spring's DOF or channel is out of range");
        double args[N_HARGS];
        for (int k = 0; k < N_HARGS; k++) args[k] = take(&cur, end);
        hyst_params(args, s->p);
    }
    m->g0 = malloc(sizeof(double) * (size_t)(m->ncorner + 1));
    m->kc = malloc(sizeof(double) * (size_t)(m->ncorner + 1));
    m->w = malloc(sizeof(double) * (size_t)(m->ncorner + 1) * NDOF);
    if (!m->g0 || !m->kc || !m->w) fail("out of memory");
    for (int c = 0; c < m->ncorner; c++) {
        m->g0[c] = take(&cur, end);
        m->kc[c] = take(&cur, end);
        for (int j = 0; j < NDOF; j++) m->w[c * NDOF + j] = take(&cur, end);
    }
    for (int i = 0; i < NDOF; i++) m->u0[i] = take(&cur, end);
    for (int i = 0; i < NDOF; i++) m->v0[i] = take(&cur, end);
    long nrec = (long)(m->nsteps + 1) * m->nchan;
    m->ug = take_array(&cur, end, nrec);
    m->vg = take_array(&cur, end, nrec);
    if (cur != end) fail("input file longer than its counts say");
    free(buf);
}

/* --------------------------------------------------------------------- the step loop */
typedef struct {
    double u[NDOF], v[NDOF], a[NDOF], R[NDOF], du[NDOF];
    double pg[NDOF];          /* support forces Kg ug + Cg vg of the current step */
    double kt[64], kt_fact[64];
    int closed[64], closed_fact[64];
    double LU[NDOF][NDOF], Kbase[NDOF][NDOF];
    double inv_diag[NDOF];    /* 1 / U_kk: the back substitution multiplies (no division) */
    int perm[NDOF];           /* row k of the factors is row perm[k] of K_eff */
    int have_factors;
} Work;

static void support_forces(const Model *m, const double *ugn, const double *vgn, double *pg)
{
    for (int i = 0; i < NDOF; i++) {
        double s = 0.0;
        for (int k = 0; k < m->nchan; k++)
            s += m->Kg[i * m->nchan + k] * ugn[k] + m->Cg[i * m->nchan + k] * vgn[k];
        pg[i] = s;
    }
}

#ifndef REF_FULL_RESIDUAL
/* the materials' trial state at u (supports ugn) */
static void set_materials(Model *m, Work *w, const double *ugn)
{
    for (int h = 0; h < m->nhyst; h++) {
        Hyst *s = &m->hyst[h];
        double d = 0.0;
        for (int q = 0; q < s->nnz; q++) d += s->coef[q] * w->u[s->dof[q]];
        if (s->chan >= 0) d -= s->chan_coef * ugn[s->chan];
        hyst_set_trial(s->p, &s->s, d);
    }
}
#endif

/* residual R = F_c − F − M ü at the trial state; the springs' tangents and the closed
   corners (the factorisation key) */
static void residual(Model *m, Work *w, const double *ugn)
{
    double f[NDOF];
    for (int i = 0; i < NDOF; i++) {
        double s = -w->pg[i];
        for (int j = 0; j < NDOF; j++) s += m->K[i][j] * w->u[j] + m->C[i][j] * w->v[j];
        f[i] = s;
    }
    for (int h = 0; h < m->nhyst; h++) {
        Hyst *s = &m->hyst[h];
        double d = 0.0;
        for (int q = 0; q < s->nnz; q++) d += s->coef[q] * w->u[s->dof[q]];
        if (s->chan >= 0) d -= s->chan_coef * ugn[s->chan];
        hyst_set_trial(s->p, &s->s, d);
        double fs = s->s.tstress;
        w->kt[h] = s->s.ttangent;
        for (int q = 0; q < s->nnz; q++) f[s->dof[q]] += s->coef[q] * fs;
    }
    for (int c = 0; c < m->ncorner; c++) {
        const double *wc = &m->w[c * NDOF];
        double g = m->g0[c];
        for (int j = 0; j < NDOF; j++) g += wc[j] * w->u[j];
        w->closed[c] = g <= 0.0;
        if (g <= 0.0) {
            double lam = -m->kc[c] * g;
            for (int j = 0; j < NDOF; j++) f[j] -= wc[j] * lam;
        }
    }
    for (int i = 0; i < NDOF; i++) w->R[i] = -f[i] - m->mass[i] * w->a[i];
}

static int same_key(const Model *m, const Work *w)
{
    if (!w->have_factors) return 0;
    for (int h = 0; h < m->nhyst; h++)
        if (w->kt[h] != w->kt_fact[h]) return 0;
    for (int c = 0; c < m->ncorner; c++)
        if (w->closed[c] != w->closed_fact[c]) return 0;
    return 1;
}

/* K_eff at the key (tangents, closed corners), LU with partial pivoting; 0 if singular */
static int factorise(const Model *m, Work *w)
{
    double (*A)[NDOF] = w->LU;
    memcpy(A, w->Kbase, sizeof w->Kbase);
    for (int h = 0; h < m->nhyst; h++) {
        const Hyst *s = &m->hyst[h];
        for (int q = 0; q < s->nnz; q++) {
            double bq = s->coef[q] * w->kt[h];
            for (int r = 0; r < s->nnz; r++) A[s->dof[q]][s->dof[r]] += bq * s->coef[r];
        }
        w->kt_fact[h] = w->kt[h];
    }
    for (int c = 0; c < m->ncorner; c++) {
        w->closed_fact[c] = w->closed[c];
        if (!w->closed[c]) continue;
        const double *wc = &m->w[c * NDOF];
        for (int i = 0; i < NDOF; i++)
            for (int j = 0; j < NDOF; j++) A[i][j] += m->kc[c] * wc[i] * wc[j];
    }
    for (int i = 0; i < NDOF; i++) w->perm[i] = i;
    for (int k = 0; k < NDOF; k++) {
        int p = k;
        double best = fabs(A[k][k]);
        for (int i = k + 1; i < NDOF; i++)
            if (fabs(A[i][k]) > best) {
                best = fabs(A[i][k]);
                p = i;
            }
        if (best == 0.0) return 0;
        if (p != k) {
            int t = w->perm[k];
            w->perm[k] = w->perm[p];
            w->perm[p] = t;
        }
        if (p != k)
            for (int j = 0; j < NDOF; j++) {
                double t = A[k][j];
                A[k][j] = A[p][j];
                A[p][j] = t;
            }
        double inv = 1.0 / A[k][k];
        w->inv_diag[k] = inv;
        for (int i = k + 1; i < NDOF; i++) {
            double l = A[i][k] * inv;
            A[i][k] = l;
            for (int j = k + 1; j < NDOF; j++) A[i][j] -= l * A[k][j];
        }
    }
    w->have_factors = 1;
    return 1;
}

/* du = K_eff⁻¹ R: the row exchanges of the factorisation applied at once (perm), then the two
   triangular solves, unrolled at the compile-time size so x stays in registers */
static void solve(Work *w)
{
    double x[NDOF];
    for (int i = 0; i < NDOF; i++) x[i] = w->R[w->perm[i]];
#pragma GCC unroll 32
    for (int k = 0; k < NDOF; k++)
#pragma GCC unroll 32
        for (int i = k + 1; i < NDOF; i++) x[i] -= w->LU[i][k] * x[k];
#pragma GCC unroll 32
    for (int k = NDOF - 1; k >= 0; k--) {
        double s = x[k];
#pragma GCC unroll 32
        for (int j = k + 1; j < NDOF; j++) s -= w->LU[k][j] * x[j];
        x[k] = s * w->inv_diag[k];
    }
    for (int i = 0; i < NDOF; i++) w->du[i] = x[i];
}

enum { ST_OK = 0, ST_NOT_CONVERGED = 1, ST_SINGULAR = 2, ST_NONFINITE = 3 };

/* x86 MXCSR: flush-to-zero (bit 15) and denormals-are-zero (bit 6); returns the old state */
static unsigned flush_enter(int on)
{
#if defined(__SSE__)
    unsigned saved = _mm_getcsr();
    if (on) _mm_setcsr(saved | 0x8040u);
    return saved;
#else
    if (on) fail("flush = 1 needs an x86 processor (MXCSR)");
    return 0u;
#endif
}

static void flush_leave(unsigned saved)
{
#if defined(__SSE__)
    _mm_setcsr(saved);
#else
    (void)saved;
#endif
}

static void run(Model *m, Outcome *out)
{
    Work w;
    memset(&w, 0, sizeof w);
    memset(out, 0, sizeof *out);
    const double dt = m->dt, gam = m->gamma, bet = m->beta;
    const double c2 = gam / (bet * dt), c3 = 1.0 / (bet * dt * dt), tol2 = m->tol * m->tol;
    const double a1p = 1.0 - gam / bet, a2p = dt * (1.0 - 0.5 * gam / bet);
    const double a3p = -1.0 / (bet * dt), a4p = 1.0 - 0.5 / bet;
    for (int i = 0; i < NDOF; i++)
        for (int j = 0; j < NDOF; j++) w.Kbase[i][j] = m->K[i][j] + c2 * m->C[i][j];
    for (int i = 0; i < NDOF; i++) w.Kbase[i][i] += c3 * m->mass[i];
    for (int h = 0; h < m->nhyst; h++) hyst_init(m->hyst[h].p, &m->hyst[h].s);
    const int nch = m->nchan;

    /* t = 0: ü₀ = (F_c − F) / m, materials committed */
    memcpy(w.u, m->u0, sizeof w.u);
    memcpy(w.v, m->v0, sizeof w.v);
    support_forces(m, m->ug, m->vg, w.pg);
    residual(m, &w, m->ug);
    for (int i = 0; i < NDOF; i++) w.a[i] = w.R[i] / m->mass[i];
    for (int h = 0; h < m->nhyst; h++) hyst_commit(m->hyst[h].p, &m->hyst[h].s);
    for (int j = 0; j < NDOF; j++) out->peak[j] = fabs(w.u[j]);

    for (int n = 0; n < m->nsteps; n++) {
        const double *ugn = m->ug + (long)(n + 1) * nch, *vgn = m->vg + (long)(n + 1) * nch;
        support_forces(m, ugn, vgn, w.pg);
        for (int j = 0; j < NDOF; j++) {
            double vn = w.v[j], an = w.a[j];
            w.v[j] = a1p * vn + a2p * an;
            w.a[j] = a4p * an + a3p * vn;
        }
        residual(m, &w, ugn);
        int it = 0;
        for (;;) {
            int reuse = same_key(m, &w);
#ifdef REF_REFACTOR_CONTACT
            for (int c = 0; c < m->ncorner; c++)
                if (w.closed[c]) reuse = 0;
#endif
            if (!reuse) {
                out->factorisations++;
                if (!factorise(m, &w)) {
                    out->status = ST_SINGULAR;
                    out->failed_step = n + 1;
                    return;
                }
            }
            solve(&w);
            double nrm2 = 0.0;
            int moved = 0;
            for (int j = 0; j < NDOF; j++) {
                double uj = w.u[j] + w.du[j];
                moved |= uj != w.u[j];
                w.u[j] = uj;
                w.v[j] += c2 * w.du[j];
                w.a[j] += c3 * w.du[j];
                nrm2 += w.du[j] * w.du[j];
            }
            it++;
            if (!isfinite(nrm2)) {
                out->status = ST_NONFINITE;
                out->failed_step = n + 1;
                return;
            }
            if (nrm2 <= tol2) { /* ‖Δu‖₂ ≤ tol without the square root */
#ifdef REF_FULL_RESIDUAL
                residual(m, &w, ugn);
#else
                if (moved) set_materials(m, &w, ugn);
#endif
                break;
            }
            if (it >= m->maxit) {
                out->status = ST_NOT_CONVERGED;
                out->failed_step = n + 1;
                out->newton += it;
                return;
            }
            residual(m, &w, ugn);
        }
        out->newton += it;
        if (it > out->max_iterations) out->max_iterations = it;
        for (int h = 0; h < m->nhyst; h++) hyst_commit(m->hyst[h].p, &m->hyst[h].s);
        const double t = (n + 1) * dt;
        for (int j = 0; j < NDOF; j++) {
            double x = fabs(w.u[j]);
            if (x > out->peak[j]) {
                out->peak[j] = x;
                out->peak_time[j] = t;
            }
        }
    }
}

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: %s INPUT [REPEATS]\n", argv[0]);
        return 2;
    }
    int repeats = argc == 3 ? atoi(argv[2]) : 1;
    if (repeats < 1) fail("REPEATS must be a whole number >= 1");
    Model m;
    memset(&m, 0, sizeof m);
    read_model(argv[1], &m);
    if (m.nhyst > 64 || m.ncorner > 64) fail("more than 64 hysteretic springs or corners");
    Outcome out;
    double *times = malloc(sizeof(double) * (size_t)repeats);
    if (!times) fail("out of memory");
    for (int r = 0; r < repeats; r++) {
        double t0 = seconds();
        unsigned saved = flush_enter(m.flush);
        run(&m, &out);
        flush_leave(saved);
        times[r] = seconds() - t0;
    }
    static const char *names[] = {"ok", "not converged", "singular", "non-finite"};
    printf("{\"status\": \"%s\", \"failed_step\": %d, \"steps\": %d, \"newton_iterations\": %ld, "
           "\"factorisations\": %ld, \"max_step_iterations\": %ld, \"peak\": [",
           names[out.status], out.failed_step, out.status == ST_OK ? m.nsteps : out.failed_step - 1,
           out.newton, out.factorisations, out.max_iterations);
    for (int j = 0; j < NDOF; j++) printf("%s%.17g", j ? ", " : "", out.peak[j]);
    printf("], \"peak_time\": [");
    for (int j = 0; j < NDOF; j++) printf("%s%.17g", j ? ", " : "", out.peak_time[j]);
    printf("], \"loop_seconds\": [");
    for (int r = 0; r < repeats; r++) printf("%s%.9g", r ? ", " : "", times[r]);
    printf("]}\n");
    return out.status == ST_OK ? 0 : 1;
}

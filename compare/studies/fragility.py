"""Lognormal fragility functions fitted by maximum likelihood, from stripes or from IDA.

A fragility function gives the probability that a limit state is exceeded at an intensity
measure (IM) level ``x`` (any positive IM, in its own unit: m/s², g, s...)::

    P(exceed | x) = Φ(ln(x / θ) / β)

with median ``θ`` (same unit as the IM) and logarithmic dispersion ``β`` (dimensionless).

* **Stripes** (multiple-stripe analysis, Baker 2015, "Efficient analytical fragility function
  fitting using dynamic structural analysis", Earthquake Spectra 31(1):579–599): at each IM level
  ``x_j``, ``n_j`` records were run and ``z_j`` exceeded the limit state. :func:`fit_stripes`
  maximises the binomial log-likelihood (Baker's Eq. 11, without the binomial coefficients,
  which do not depend on θ, β)::

      ℓ(θ, β) = Σ_j [ z_j ln p_j + (n_j − z_j) ln(1 − p_j) ],   p_j = Φ(ln(x_j / θ) / β)

  over (ln θ, ln β). ``ln p`` and ``ln(1 − p)`` are evaluated as ``log Φ(u)`` and ``log Φ(−u)``
  (:func:`scipy.special.log_ndtr`), which is finite for every finite ``u`` and exact where a
  clipped ``p`` would not be, so no clipping is needed. The maximum exists and is unique
  exactly when the data show an increasing trend and are not separated (below): in the probit
  form ``α + s ln x`` the log-likelihood is concave, and (ln θ, ln β) = (−α/s, −ln s) maps
  its half-plane ``s > 0`` one to one.
* **IDA** (incremental dynamic analysis): each record's capacity is the IM at which it first
  exceeds the limit state; a record that never does is right-censored at the largest IM it was
  run at. :func:`fit_ida` is the maximum-likelihood lognormal fit with censoring; with nothing
  censored it is the closed form ``ln θ = mean(ln c)``, ``β = std(ln c)`` with ``ddof = 0``
  (the MLE, not the unbiased ``ddof = 1``).

Data that no lognormal fragility fits are refused with :class:`FragilityDataError` (a
:class:`~deckpound.models.errors.SceneError`: the CLI exits with status 2), naming the reason.
Curves (:func:`fragility_curve`) are monotone by construction; bands come from bootstrap
resampling of records (:func:`bootstrap_stripes`, :func:`bootstrap_ida`) or, from stripe counts
alone, of the binomial counts (:func:`parametric_bootstrap_stripes`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import optimize, special, stats

from deckpound.models.errors import SceneError

#: gradient tolerance of the optimiser (the log-likelihood's gradient in (ln θ, ln β))
_GTOL = 1e-10


class FragilityDataError(SceneError):
    """Data or options from which no lognormal fragility can be fitted (bad input)."""


@dataclass(frozen=True)
class FragilityFit:
    """A fitted lognormal fragility ``P(x) = Φ(ln(x / median) / beta)``.

    Attributes
    ----------
    median:
        θ, the IM at which the probability of exceedance is 1/2 (unit of the IM).
    beta:
        β, the standard deviation of the log capacity (dimensionless).
    loglik:
        The maximised log-likelihood (stripes: the binomial kernel above, without the binomial
        coefficients; IDA: of the log capacities, with the censored records' survival terms).
    n_levels:
        Stripes: distinct IM levels; IDA: records.
    n_runs:
        Stripes: records run over all stripes (Σ n_j); IDA: records.
    se_ln_median, se_beta:
        Standard errors of ln θ and of β from the expected Fisher information at the estimate
        (stripes) or the observed information (IDA).
    method:
        ``"stripes"`` or ``"ida"``.
    """

    median: float
    beta: float
    loglik: float
    n_levels: int
    n_runs: int
    se_ln_median: float
    se_beta: float
    method: str

    def probability(self, im) -> np.ndarray:
        """P(exceed | im) on the given IM values (see :func:`fragility_curve`)."""
        return fragility_curve(im, self.median, self.beta)


def fragility_curve(im, median: float, beta: float) -> np.ndarray:
    """P(exceed | x) = Φ(ln(x / median) / beta) on the IM values ``im`` (> 0, IM unit).

    Monotone non-decreasing in ``x`` by construction (Φ and ln are increasing and β > 0); an IM
    of 0 gives 0. Refuses a non-positive median or beta and negative or non-finite IM values.
    """
    if not (math.isfinite(median) and median > 0):
        raise FragilityDataError("median", f"must be a finite number > 0, got {median!r}")
    if not (math.isfinite(beta) and beta > 0):
        raise FragilityDataError("beta", f"must be a finite number > 0, got {beta!r}")
    x = np.asarray(im, dtype=float)
    bad = ~np.isfinite(x) | (x < 0)
    if bad.any():
        raise FragilityDataError(
            "im", f"IM values must be finite and >= 0, got {x[bad].ravel()[0]!r}"
        )
    with np.errstate(divide="ignore"):
        return special.ndtr((np.log(x) - math.log(median)) / beta)


# ---------------------------------------------------------------------------------------------
# stripes


@dataclass(frozen=True)
class Stripes:
    """Multiple-stripe data: IM level ``im`` (> 0), records run ``n`` and exceedances ``exceed``
    per level, one entry per distinct level, sorted by IM (see :func:`stripes`)."""

    im: np.ndarray
    n: np.ndarray
    exceed: np.ndarray


def stripes(im, n, exceed) -> Stripes:
    """Checked stripe data, rows of equal IM merged (their counts add), sorted by IM.

    Refuses (with :class:`FragilityDataError`) arrays of different lengths, non-finite or
    non-positive IM, counts that are not whole numbers >= 0, ``exceed > n``, fewer than two
    distinct IM levels with records, no exceedance anywhere and exceedance of every record at
    every level.
    """
    x = np.asarray(im, dtype=float).ravel()
    n_arr = np.asarray(n, dtype=float).ravel()
    z_arr = np.asarray(exceed, dtype=float).ravel()
    if not (len(x) == len(n_arr) == len(z_arr)):
        raise FragilityDataError(
            "stripes",
            f"im, n and exceed must have one entry per stripe, got {len(x)}, {len(n_arr)} "
            f"and {len(z_arr)}",
        )
    for j in range(len(x)):
        if not (math.isfinite(x[j]) and x[j] > 0):
            raise FragilityDataError(f"im[{j}]", f"must be a finite IM > 0, got {float(x[j])!r}")
        for name, arr in (("n", n_arr), ("exceed", z_arr)):
            v = arr[j]
            if not (math.isfinite(v) and v >= 0 and v == round(v)):
                raise FragilityDataError(
                    f"{name}[{j}]",
                    f"must be a whole number >= 0 (a count of records), got {float(v)!r}",
                )
        if z_arr[j] > n_arr[j]:
            raise FragilityDataError(
                f"exceed[{j}]",
                f"must be <= n = {int(n_arr[j])}, the records run at im {x[j]:g}, "
                f"got {int(z_arr[j])}",
            )
    levels, where = np.unique(x, return_inverse=True)
    n_lev = np.bincount(where, weights=n_arr, minlength=len(levels))
    z_lev = np.bincount(where, weights=z_arr, minlength=len(levels))
    run = n_lev > 0
    levels, n_lev, z_lev = levels[run], n_lev[run], z_lev[run]
    if len(levels) < 2:
        raise FragilityDataError(
            "stripes",
            f"need at least two distinct IM levels with records run, got {len(levels)}: one "
            "level cannot separate the median from the dispersion",
        )
    if z_lev.sum() == 0:
        raise FragilityDataError(
            "exceed",
            "no record exceeds the limit state at any IM level: the median lies above every "
            "level run (run stronger stripes)",
        )
    if (z_lev == n_lev).all():
        raise FragilityDataError(
            "exceed",
            "every record exceeds the limit state at every IM level: the median lies below "
            "every level run (run weaker stripes)",
        )
    return Stripes(levels, n_lev.astype(int), z_lev.astype(int))


def stripes_loglik(data: Stripes, median: float, beta: float) -> float:
    """Σ_j [z_j ln p_j + (n_j − z_j) ln(1 − p_j)], p_j = Φ(ln(x_j/θ)/β) (no binomial
    coefficients), with ln p and ln(1 − p) as log Φ(±u)."""
    u = (np.log(data.im) - math.log(median)) / beta
    return float(
        np.sum(data.exceed * special.log_ndtr(u) + (data.n - data.exceed) * special.log_ndtr(-u))
    )


def _refuse_degenerate(data: Stripes) -> None:
    """Refuse stripes without a finite maximum-likelihood estimate with 0 < β < ∞.

    In probit form u = α + s ln x the log-likelihood is concave. (1) Its maximum over s >= 0 lies
    on s = 0 (β = ∞, no trend) exactly when the score in s at the best constant probability
    p̄ = Σz/Σn is <= 0, i.e. when Σ_j ln x_j (z_j − n_j p̄) <= 0. (2) It runs to s = ∞ (β → 0)
    exactly when the levels are separated: some level k has no exceedance at every level below
    it and exceedance of every record at every level above it.
    """
    p_bar = data.exceed.sum() / data.n.sum()
    ln_x = np.log(data.im)
    trend = float(np.sum((ln_x - ln_x.mean()) * (data.exceed - data.n * p_bar)))
    if trend <= 0:
        raise FragilityDataError(
            "exceed",
            "the fraction of records exceeding the limit state does not increase with the IM "
            "(no lognormal fragility fits: the likelihood is largest for β → ∞)",
        )
    none_, all_ = data.exceed == 0, data.exceed == data.n
    for k in range(len(data.im)):
        if not (none_[:k].all() and all_[k + 1 :].all()):
            continue
        if none_[k] or all_[k]:  # complete separation: between the last 0 and the first n
            last_none = int(np.flatnonzero(none_)[-1])
            below, above = data.im[last_none], data.im[last_none + 1]
            where = (
                f"no record exceeds at im <= {below:g} and every record exceeds at im >= "
                f"{above:g}, so β → 0 and the median lies anywhere between"
            )
        else:
            where = (
                f"no record exceeds below im {data.im[k]:g} and every record exceeds above it "
                f"({data.exceed[k]} of {data.n[k]} at it), so β → 0"
            )
        raise FragilityDataError(
            "exceed",
            f"the stripes separate perfectly: {where} (no finite fit; run stripes in between "
            "or more records)",
        )


def _probit_start(data: Stripes) -> tuple[float, float]:
    """A start (ln θ, ln β): the least-squares line, weighted by n, through the empirical
    probits Φ⁻¹((z + 1/2)/(n + 1)) against ln x (probit = (ln x − ln θ)/β); where that line does
    not rise, the n-weighted mean and the spread of ln x."""
    ln_x = np.log(data.im)
    probit = special.ndtri((data.exceed + 0.5) / (data.n + 1.0))
    w = data.n.astype(float)
    xm = np.average(ln_x, weights=w)
    ym = np.average(probit, weights=w)
    slope = np.sum(w * (ln_x - xm) * (probit - ym)) / np.sum(w * (ln_x - xm) ** 2)
    if slope > 0:
        return xm - ym / slope, -math.log(slope)
    spread = float(np.std(ln_x)) or 1.0
    return float(xm), math.log(spread)


def _negloglik_stripes(params: np.ndarray, ln_x, n, z) -> tuple[float, np.ndarray]:
    """−ℓ and its gradient in (ln θ, ln β)."""
    ln_theta, ln_beta = params
    beta = math.exp(ln_beta)
    u = (ln_x - ln_theta) / beta
    log_p, log_q = special.log_ndtr(u), special.log_ndtr(-u)
    value = -float(np.sum(z * log_p + (n - z) * log_q))
    log_phi = -0.5 * u * u - 0.5 * math.log(2 * math.pi)
    # dℓ/du = z φ/Φ(u) − (n − z) φ/Φ(−u), the ratios via logs so that far tails stay finite
    dl_du = z * np.exp(log_phi - log_p) - (n - z) * np.exp(log_phi - log_q)
    # du/d ln θ = −1/β, du/d ln β = −u
    grad = np.array([np.sum(dl_du) / beta, np.sum(dl_du * u)])
    return value, grad


def stripes_fisher_information(im, n, median: float, beta: float) -> np.ndarray:
    """Expected Fisher information of (ln θ, β) from stripes (2 × 2)::

        I = Σ_j n_j φ(u_j)² / (Φ(u_j) (1 − Φ(u_j))) g_j g_jᵀ,  g_j = (−1/β, −u_j/β)

    with u_j = ln(x_j/θ)/β; its inverse is the asymptotic covariance of the estimates.
    """
    u = (np.log(np.asarray(im, dtype=float)) - math.log(median)) / beta
    n = np.asarray(n, dtype=float)
    weight = n * np.exp(2 * stats.norm.logpdf(u) - special.log_ndtr(u) - special.log_ndtr(-u))
    g = np.stack([-np.ones_like(u) / beta, -u / beta])
    return (g * weight) @ g.T


def fit_stripes(im, n, exceed) -> FragilityFit:
    """Maximum-likelihood lognormal fragility from stripes (module docstring; Baker 2015).

    ``im``: IM level per stripe (> 0); ``n``: records run at it; ``exceed``: records exceeding
    the limit state there. Rows of equal IM are merged. Raises :class:`FragilityDataError` for
    data without a fit (see :func:`stripes` and the trend and separation checks).
    """
    data = stripes(im, n, exceed)
    _refuse_degenerate(data)
    ln_x = np.log(data.im)
    n_f, z_f = data.n.astype(float), data.exceed.astype(float)
    best = _maximise(_negloglik_stripes, np.array(_probit_start(data)), (ln_x, n_f, z_f))
    if best is None:
        raise FragilityDataError(
            "stripes", "the likelihood maximisation did not converge for these stripes"
        )
    median, beta = math.exp(best.x[0]), math.exp(best.x[1])
    cov = _inverse(stripes_fisher_information(data.im, data.n, median, beta))
    return FragilityFit(
        median=median,
        beta=beta,
        loglik=-float(best.fun),
        n_levels=len(data.im),
        n_runs=int(data.n.sum()),
        se_ln_median=math.sqrt(cov[0, 0]),
        se_beta=math.sqrt(cov[1, 1]),
        method="stripes",
    )


def _maximise(negloglik, start: np.ndarray, args: tuple):
    """Minimise ``negloglik`` (value and gradient) by BFGS from ``start``, then once more from
    where it stopped (its line search ends on a relative decrease, coarse near a flat optimum;
    the second pass polishes the last digits). None unless the end point is finite with a
    gradient below 1e-6 per unit of −ℓ (at least 1e-6)."""
    best = None
    for _ in range(2):
        res = optimize.minimize(
            negloglik,
            start if best is None else best.x,
            args=args,
            jac=True,
            method="BFGS",
            options={"gtol": _GTOL, "maxiter": 1000},
        )
        if not (np.all(np.isfinite(res.x)) and np.isfinite(res.fun)):
            return None
        best = res
    if np.max(np.abs(best.jac)) > 1e-6 * max(1.0, abs(best.fun)):
        return None
    return best


def _inverse(info: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.inv(info)
    except np.linalg.LinAlgError:
        return np.full_like(info, np.nan)


# ---------------------------------------------------------------------------------------------
# IDA


def _negloglik_ida(params, ln_c, censored) -> tuple[float, np.ndarray]:
    """−ℓ and gradient in (μ = ln θ, ln β) of log capacities, the censored ones entering as
    log Φ(−(ln c − μ)/β) (their capacity exceeds the IM reached)."""
    mu, ln_beta = params
    beta = math.exp(ln_beta)
    u = (ln_c - mu) / beta
    obs = ~censored
    value = -(
        np.sum(-0.5 * u[obs] ** 2 - 0.5 * math.log(2 * math.pi) - ln_beta)
        + np.sum(special.log_ndtr(-u[censored]))
    )
    # censored: d log Φ(−u)/du = −φ(u)/Φ(−u)
    hazard = np.exp(stats.norm.logpdf(u[censored]) - special.log_ndtr(-u[censored]))
    d_mu = np.sum(u[obs]) / beta + np.sum(hazard) / beta
    d_lnb = np.sum(u[obs] ** 2 - 1.0) + np.sum(hazard * u[censored])
    return float(value), -np.array([d_mu, d_lnb])


def fit_ida(capacity, censored=None) -> FragilityFit:
    """Maximum-likelihood lognormal fragility from IDA capacities (module docstring).

    ``capacity``: per record, the IM (> 0) at which it first exceeds the limit state, or for a
    censored record the largest IM it was run at; ``censored``: True for records that never
    exceeded it (default: none). With nothing censored: ln θ = mean(ln c), β = std(ln c) with
    ddof = 0 (the MLE). Refuses non-positive capacities, fewer than two distinct uncensored
    capacities (β → 0 otherwise).
    """
    c = np.asarray(capacity, dtype=float).ravel()
    cens = (
        np.zeros(len(c), dtype=bool)
        if censored is None
        else np.asarray(censored, dtype=bool).ravel()
    )
    if len(cens) != len(c):
        raise FragilityDataError(
            "censored", f"must have one flag per record ({len(c)}), got {len(cens)}"
        )
    for i, v in enumerate(c):
        if not (math.isfinite(v) and v > 0):
            raise FragilityDataError(f"capacity[{i}]", f"must be a finite IM > 0, got {float(v)!r}")
    observed = np.unique(c[~cens])
    if len(observed) < 2:
        raise FragilityDataError(
            "capacity",
            f"need at least two distinct capacities of records that exceed the limit state, "
            f"got {len(observed)} ({int(cens.sum())} of {len(c)} records censored): "
            "the dispersion cannot be estimated",
        )
    ln_c = np.log(c)
    if not cens.any():
        mu, beta = float(np.mean(ln_c)), float(np.std(ln_c, ddof=0))
    else:
        start = np.array([np.mean(ln_c), math.log(np.std(ln_c[~cens], ddof=0))])
        res = _maximise(_negloglik_ida, start, (ln_c, cens))
        if res is None:
            raise FragilityDataError(
                "capacity", "the censored likelihood maximisation did not converge"
            )
        mu, beta = float(res.x[0]), math.exp(res.x[1])
    loglik = -_negloglik_ida(np.array([mu, math.log(beta)]), ln_c, cens)[0]
    cov = _inverse(_ida_observed_information(ln_c, cens, mu, beta))
    return FragilityFit(
        median=math.exp(mu),
        beta=beta,
        loglik=float(loglik),
        n_levels=len(c),
        n_runs=len(c),
        se_ln_median=math.sqrt(cov[0, 0]),
        se_beta=math.sqrt(cov[1, 1]),
        method="ida",
    )


def _ida_observed_information(ln_c, censored, mu: float, beta: float) -> np.ndarray:
    """Observed information of (μ, β) by central differences of the analytic score."""

    def score(p):
        # the score in (μ, ln β) converted to (μ, β): d/dβ = (1/β) d/d ln β
        _, g = _negloglik_ida(np.array([p[0], math.log(p[1])]), ln_c, censored)
        return -np.array([g[0], g[1] / p[1]])

    h = 1e-6 * np.array([max(1.0, abs(mu)), beta])
    info = np.empty((2, 2))
    for k in range(2):
        e = np.zeros(2)
        e[k] = h[k]
        info[:, k] = -(score(np.array([mu, beta]) + e) - score(np.array([mu, beta]) - e)) / (
            2 * h[k]
        )
    return 0.5 * (info + info.T)


# ---------------------------------------------------------------------------------------------
# limit states on a summary table


#: the words a flag column read from text may hold
_FLAG_WORDS = {"true": 1.0, "false": 0.0}


@dataclass(frozen=True)
class LimitState:
    """A limit state read from a summary table: exceeded where ``column > threshold``, or, with
    ``threshold`` None, where the boolean flag ``column`` is true (bool, or numbers 0/1)."""

    column: str
    threshold: float | None = None

    def exceeded(self, table: pd.DataFrame) -> np.ndarray:
        """True per row of ``table`` where the limit state is exceeded."""
        if self.column not in table.columns:
            raise FragilityDataError(
                self.column,
                f"no such column in the summary table; columns: {', '.join(map(str, table.columns))}",
            )
        values = table[self.column]
        if self.threshold is None:
            if values.dtype == bool:
                return values.to_numpy()
            # a table read from CSV text holds the words: "true"/"false" in any case
            words = values.map(
                lambda v: _FLAG_WORDS.get(v.strip().lower(), v) if isinstance(v, str) else v
            )
            numbers = pd.to_numeric(words, errors="coerce").to_numpy(dtype=float)
            bad = ~np.isin(numbers, (0.0, 1.0))
            if bad.any():
                i = int(np.argmax(bad))
                raise FragilityDataError(
                    f"{self.column}[{i}]",
                    f"a flag column must hold true/false or 0/1, got {values.iloc[i]!r}",
                )
            return numbers == 1.0
        if not math.isfinite(self.threshold):
            raise FragilityDataError(
                "threshold", f"must be a finite number, got {self.threshold!r}"
            )
        numbers = pd.to_numeric(values, errors="coerce").to_numpy(dtype=float)
        bad = ~np.isfinite(numbers)
        if bad.any():
            i = int(np.argmax(bad))
            raise FragilityDataError(
                f"{self.column}[{i}]",
                f"must be a finite number to compare with the threshold {self.threshold:g}, "
                f"got {values.iloc[i]!r}",
            )
        return numbers > self.threshold


def _checked_im(table: pd.DataFrame, im_column: str) -> np.ndarray:
    if im_column not in table.columns:
        raise FragilityDataError(im_column, "no such column in the summary table")
    im = pd.to_numeric(table[im_column], errors="coerce").to_numpy(dtype=float)
    bad = ~(np.isfinite(im) & (im > 0))
    if bad.any():
        i = int(np.argmax(bad))
        raise FragilityDataError(
            f"{im_column}[{i}]", f"must be a finite IM > 0, got {table[im_column].iloc[i]!r}"
        )
    return im


def count_exceedances(
    table: pd.DataFrame, limit_state: LimitState, im_column: str = "im"
) -> pd.DataFrame:
    """Stripe counts from a summary table with one row per case (record × IM level).

    Returns a DataFrame with columns ``im``, ``n`` (cases at that IM) and ``exceed`` (cases
    exceeding ``limit_state``), one row per distinct IM, sorted — the input of
    :func:`fit_stripes` and of ``deckpound fragility fit``.
    """
    im = _checked_im(table, im_column)
    hit = limit_state.exceeded(table)
    levels, where = np.unique(im, return_inverse=True)
    return pd.DataFrame(
        {
            "im": levels,
            "n": np.bincount(where, minlength=len(levels)),
            "exceed": np.bincount(where, weights=hit, minlength=len(levels)).astype(int),
        }
    )


def ida_capacities(
    table: pd.DataFrame,
    limit_state: LimitState,
    im_column: str = "im",
    record_column: str = "record",
) -> pd.DataFrame:
    """Per record, the IM at which it first exceeds ``limit_state`` (its capacity), or, for a
    record that never does, the largest IM it was run at, censored.

    Returns a DataFrame indexed by record with columns ``capacity`` and ``censored`` — the input
    of :func:`fit_ida`.
    """
    if record_column not in table.columns:
        raise FragilityDataError(record_column, "no such column in the summary table")
    im = _checked_im(table, im_column)
    hit = limit_state.exceeded(table)
    missing = table[record_column].isna().to_numpy()
    if missing.any():
        i = int(np.argmax(missing))
        raise FragilityDataError(f"{record_column}[{i}]", "a case must name its record, got none")
    frame = pd.DataFrame({"record": table[record_column].to_numpy(), "im": im, "hit": hit})
    rows = {}
    for record, group in frame.sort_values("im", kind="stable").groupby("record", sort=True):
        first = group.loc[group["hit"], "im"]
        if len(first):
            rows[record] = (float(first.iloc[0]), False)
        else:
            rows[record] = (float(group["im"].max()), True)
    out = pd.DataFrame.from_dict(rows, orient="index", columns=["capacity", "censored"])
    out.index.name = "record"
    return out


# ---------------------------------------------------------------------------------------------
# bootstrap bands


@dataclass(frozen=True)
class BootstrapBands:
    """Percentile bands of P(x) on ``im`` from bootstrap refits.

    ``lower``/``upper``: the (1 − level)/2 and (1 + level)/2 percentiles of the refitted curves
    at each IM; ``curve``: the fit to the data themselves; ``medians``/``betas``: the refits;
    ``skipped``: resamples that could not be fitted (no exceedance, separated...), left out.
    """

    im: np.ndarray
    curve: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    level: float
    medians: np.ndarray
    betas: np.ndarray
    skipped: int

    def median_interval(self) -> tuple[float, float]:
        """The ``level`` percentile interval of the refitted medians (IM unit)."""
        lo, hi = np.quantile(self.medians, [(1 - self.level) / 2, (1 + self.level) / 2])
        return float(lo), float(hi)

    def beta_interval(self) -> tuple[float, float]:
        """The ``level`` percentile interval of the refitted dispersions."""
        lo, hi = np.quantile(self.betas, [(1 - self.level) / 2, (1 + self.level) / 2])
        return float(lo), float(hi)


def _bands(
    fit: FragilityFit,
    refit: Callable[[np.random.Generator], FragilityFit],
    im_grid,
    n_resamples: int,
    seed: int,
    level: float,
) -> BootstrapBands:
    if not (isinstance(n_resamples, int | np.integer) and n_resamples >= 1):
        raise FragilityDataError("n_resamples", f"must be a whole number >= 1, got {n_resamples!r}")
    if not 0 < level < 1:
        raise FragilityDataError("level", f"must be in (0, 1), got {level!r}")
    grid = np.asarray(im_grid, dtype=float)
    curve = fit.probability(grid)
    rng = np.random.default_rng(seed)
    medians, betas, skipped = [], [], 0
    for _ in range(n_resamples):
        try:
            f = refit(rng)
        except FragilityDataError:
            skipped += 1
            continue
        medians.append(f.median)
        betas.append(f.beta)
    if not medians:
        raise FragilityDataError(
            "bootstrap", f"none of the {n_resamples} resamples could be fitted"
        )
    curves = np.array([fragility_curve(grid, m, b) for m, b in zip(medians, betas)])
    lo, hi = np.quantile(curves, [(1 - level) / 2, (1 + level) / 2], axis=0)
    return BootstrapBands(
        im=grid,
        curve=curve,
        lower=lo,
        upper=hi,
        level=level,
        medians=np.array(medians),
        betas=np.array(betas),
        skipped=skipped,
    )


def bootstrap_stripes(
    table: pd.DataFrame,
    limit_state: LimitState,
    im_grid,
    n_resamples: int = 1000,
    seed: int = 0,
    level: float = 0.90,
    im_column: str = "im",
    record_column: str = "record",
) -> BootstrapBands:
    """Bands of a stripes fit by resampling records with replacement.

    Each resample draws as many records as the table has, with replacement; a drawn record
    brings all its cases (its rows at every stripe), so the stripes keep the correlation of a
    record's results across IM levels. Resamples that cannot be fitted are skipped and counted.
    """
    if record_column not in table.columns:
        raise FragilityDataError(record_column, "no such column in the summary table")
    im = _checked_im(table, im_column)
    hit = limit_state.exceeded(table).astype(float)
    fit = fit_stripes(*_counts(im, np.ones_like(im), hit))
    codes, _ = pd.factorize(table[record_column])
    if (codes < 0).any():
        i = int(np.argmax(codes < 0))
        raise FragilityDataError(f"{record_column}[{i}]", "a case must name its record, got none")
    rows_of = [np.flatnonzero(codes == k) for k in range(codes.max() + 1)]

    def refit(rng: np.random.Generator) -> FragilityFit:
        drawn = rng.integers(0, len(rows_of), size=len(rows_of))
        rows = np.concatenate([rows_of[k] for k in drawn])
        return fit_stripes(*_counts(im[rows], np.ones(len(rows)), hit[rows]))

    return _bands(fit, refit, im_grid, n_resamples, seed, level)


def _counts(im, n, z):
    levels, where = np.unique(im, return_inverse=True)
    return (
        levels,
        np.bincount(where, weights=n, minlength=len(levels)),
        np.bincount(where, weights=z, minlength=len(levels)),
    )


def bootstrap_ida(
    capacity,
    censored=None,
    im_grid=None,
    n_resamples: int = 1000,
    seed: int = 0,
    level: float = 0.90,
) -> BootstrapBands:
    """Bands of an IDA fit by resampling records (capacity, censored flag) with replacement;
    resamples that cannot be fitted are skipped and counted."""
    fit = fit_ida(capacity, censored)
    c = np.asarray(capacity, dtype=float).ravel()
    cens = np.zeros(len(c), bool) if censored is None else np.asarray(censored, bool).ravel()
    if im_grid is None:
        im_grid = np.geomspace(c.min() / 2, c.max() * 2, 50)

    def refit(rng: np.random.Generator) -> FragilityFit:
        drawn = rng.integers(0, len(c), size=len(c))
        return fit_ida(c[drawn], cens[drawn])

    return _bands(fit, refit, im_grid, n_resamples, seed, level)


def parametric_bootstrap_stripes(
    im, n, exceed, im_grid=None, n_resamples: int = 1000, seed: int = 0, level: float = 0.90
) -> BootstrapBands:
    """Bands of a stripes fit when records are not identified (counts only): parametric
    bootstrap, each resample drawing z*_j ~ Binomial(n_j, P̂(x_j)) from the fitted curve and
    refitting. Resamples that cannot be fitted are skipped and counted."""
    fit = fit_stripes(im, n, exceed)
    data = stripes(im, n, exceed)
    p_hat = fit.probability(data.im)
    if im_grid is None:
        im_grid = np.geomspace(data.im.min() / 2, data.im.max() * 2, 50)

    def refit(rng: np.random.Generator) -> FragilityFit:
        return fit_stripes(data.im, data.n, rng.binomial(data.n, p_hat))

    return _bands(fit, refit, im_grid, n_resamples, seed, level)

"""Lognormal fragility fitting (:mod:`deckpound.compare.studies.fragility`) and ``deckpound fragility fit``.

Recovery of known (θ, β) from seeded synthetic stripes and IDA capacities, with the spread of
the estimates checked against the Fisher information; agreement with an independent fitter,
pyFragility 0.2.0 (Dahal, Burton & Onyambu 2022: ``fit_msa`` is the same binomial-probit
likelihood in (θ, β), fitted as a GLM; ``fit_ida`` the same censored lognormal likelihood),
to 1e-6; monotone curves and bands; the refusals; the limit-state counting; the CLI.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from scipy import special

from deckpound.cli import main
from deckpound.compare.studies import fragility as fr

THETA, BETA = 0.5, 0.4  # the known fragility of the synthetic data (IM unit: g, say)
LEVELS = np.geomspace(0.15, 1.6, 10)  # 10 stripes
RECORDS = 40  # records per stripe


def draw_stripes(rng: np.random.Generator, n=RECORDS, levels=LEVELS):
    counts = np.full(len(levels), n)
    return levels, counts, rng.binomial(counts, fr.fragility_curve(levels, THETA, BETA))


# --------------------------------------------------------------------------------- stripes


def test_stripes_recover_known_parameters_within_fisher_standard_errors():
    """Over 300 seeded data sets of 10 stripes × 40 records: the estimates' mean lies within
    0.25 standard errors of the truth (4× the standard error of a 300-mean) and their spread
    matches the inverse expected Fisher information to 15 % (about 4× the sampling error of a
    standard deviation of 300); every single fit lies within 4.5 standard errors."""
    rng = np.random.default_rng(20261128)
    cov = np.linalg.inv(fr.stripes_fisher_information(LEVELS, np.full(10, RECORDS), THETA, BETA))
    se = np.sqrt(np.diag(cov))  # of (ln θ, β)
    estimates = []
    for _ in range(300):
        fit = fr.fit_stripes(*draw_stripes(rng))
        estimates.append((math.log(fit.median), fit.beta))
    est = np.array(estimates)
    error = (est - [math.log(THETA), BETA]) / se
    assert np.all(np.abs(error.mean(axis=0)) < 0.25), error.mean(axis=0)
    assert np.all(np.abs(est.std(axis=0) / se - 1) < 0.15), est.std(axis=0) / se
    assert np.abs(error).max() < 4.5


def test_stripes_fit_is_the_likelihood_maximum():
    """The fitted point beats every neighbour on a fine grid of (ln θ, ln β), with the
    log-likelihood written here independently (binomial pmf logs, coefficients removed)."""
    x, n, z = draw_stripes(np.random.default_rng(3))
    fit = fr.fit_stripes(x, n, z)

    def loglik(theta, beta):
        p = special.ndtr(np.log(x / theta) / beta)
        with np.errstate(divide="ignore"):
            terms = np.where(z > 0, z * np.log(p), 0) + np.where(n > z, (n - z) * np.log1p(-p), 0)
        return terms.sum()

    best = loglik(fit.median, fit.beta)
    assert best == pytest.approx(fit.loglik, rel=1e-12)
    for dt in np.linspace(-0.01, 0.01, 9):
        for db in np.linspace(-0.01, 0.01, 9):
            if dt or db:
                assert loglik(fit.median * math.exp(dt), fit.beta * math.exp(db)) < best


def test_stripes_agree_with_pyfragility():
    """fit_msa of pyFragility (same binomial-probit likelihood, maximised by statsmodels' GLM)
    on its own wood-frame data set and on synthetic stripes: θ and β to 1e-6. Its
    log-likelihood includes the binomial coefficients ln C(n, z), ours does not."""
    import pyFragility as pf  # test-only dependency (pyproject [test])

    ds = pf.datasets.load_msa_wood_frame()
    cases = [
        (np.asarray(ds.im, float), np.full(len(ds.im), ds.num_gm), np.asarray(ds.counts[k]))
        for k in ds.counts
    ]
    cases += [draw_stripes(np.random.default_rng(seed)) for seed in range(3)]
    for x, n, z in cases:
        ours = fr.fit_stripes(x, n, z)
        theirs = pf.fit_msa(x, z, n)
        theta, beta = theirs.params
        assert ours.median == pytest.approx(theta, rel=1e-6)
        assert ours.beta == pytest.approx(beta, rel=1e-6)
        coefficients = np.sum(
            special.gammaln(n + 1) - special.gammaln(z + 1) - special.gammaln(n - z + 1)
        )
        assert ours.loglik + coefficients == pytest.approx(theirs.loglik, rel=1e-9)
        # standard errors: theirs of θ from the observed information, ours of ln θ from the
        # expected (Fisher) information, so they agree only to the sampling difference
        assert ours.se_ln_median * ours.median == pytest.approx(
            theirs.std_errors("mle")[0], rel=0.02
        )
        assert ours.se_beta == pytest.approx(theirs.std_errors("mle")[1], rel=0.02)


def test_equal_im_rows_are_merged():
    x, n, z = draw_stripes(np.random.default_rng(5))
    whole = fr.fit_stripes(x, n, z)
    half = n // 2
    split = fr.fit_stripes(np.r_[x, x], np.r_[half, n - half], np.r_[z // 2, z - z // 2])
    assert split.median == pytest.approx(whole.median, rel=1e-9)
    assert split.beta == pytest.approx(whole.beta, rel=1e-9)
    assert split.n_levels == 10 and split.n_runs == 400


@pytest.mark.parametrize(
    "im, n, exceed, field, text",
    [
        ([0.1, 0.2, 0.4], [10, 10, 10], [0, 0, 0], "exceed", "no record exceeds"),
        ([0.1, 0.2, 0.4], [10, 10, 10], [10, 10, 10], "exceed", "every record exceeds"),
        ([0.3, 0.3], [10, 10], [2, 5], "stripes", "two distinct IM levels"),
        ([0.1, 0.2], [10, 10], [3, 11], "exceed[1]", "must be <= n = 10"),
        ([0.1, 0.2], [10, -1], [3, 0], "n[1]", "whole number >= 0"),
        ([0.1, 0.2], [10, 10], [-3, 5], "exceed[0]", "whole number >= 0"),
        ([0.1, 0.2], [10, 10.5], [3, 5], "n[1]", "whole number >= 0"),
        ([0.0, 0.2], [10, 10], [3, 5], "im[0]", "finite IM > 0"),
        ([-0.1, 0.2], [10, 10], [3, 5], "im[0]", "finite IM > 0"),
        ([math.nan, 0.2], [10, 10], [3, 5], "im[0]", "finite IM > 0"),
        ([0.1, 0.2], [10, 10], [3], "stripes", "one entry per stripe"),
        ([0.1, 0.2, 0.4], [10, 10, 10], [9, 5, 1], "exceed", "does not increase"),
        ([0.1, 0.2, 0.4], [10, 10, 10], [0, 0, 10], "exceed", "separate perfectly"),
        ([0.1, 0.2, 0.4], [10, 10, 10], [0, 4, 10], "exceed", "separate perfectly"),
    ],
)
def test_unfittable_stripes_are_refused(im, n, exceed, field, text):
    with pytest.raises(fr.FragilityDataError, match=text) as err:
        fr.fit_stripes(im, n, exceed)
    assert err.value.field == field
    assert isinstance(err.value, ValueError)


def test_separation_check_is_exact():
    """One mixed stripe between no-exceedance and all-exceedance stripes is still separated
    (β → 0); one record less at the top stripe makes a finite fit."""
    with pytest.raises(fr.FragilityDataError, match="separate"):
        fr.fit_stripes([0.1, 0.2, 0.4, 0.8], [10] * 4, [0, 0, 4, 10])
    fit = fr.fit_stripes([0.1, 0.2, 0.4, 0.8], [10] * 4, [0, 0, 4, 9])
    assert 0.2 < fit.median < 0.8 and 0 < fit.beta < 2


# --------------------------------------------------------------------------------- IDA


def test_ida_without_censoring_is_the_closed_form():
    """ln θ = mean ln c, β = std ln c with ddof = 0 (the MLE)."""
    c = np.exp(np.random.default_rng(1).normal(math.log(0.8), 0.3, 25))
    fit = fr.fit_ida(c)
    assert fit.median == pytest.approx(math.exp(np.mean(np.log(c))), rel=1e-14)
    assert fit.beta == pytest.approx(np.std(np.log(c), ddof=0), rel=1e-14)
    assert fit.beta != pytest.approx(np.std(np.log(c), ddof=1), rel=1e-3)


def test_censored_ida_recovers_known_parameters():
    """2000 records with capacity lognormal(0.8, 0.35), analysed up to IM 0.9 (37 % of the
    records never fail and are censored there): the censored fit lies within 4 standard errors
    of the truth, while treating the censoring IM as a capacity is off by more than 10."""
    rng = np.random.default_rng(11)
    capacity = np.exp(rng.normal(math.log(0.8), 0.35, 2000))
    top = 0.9
    censored = capacity > top
    observed = np.minimum(capacity, top)
    fit = fr.fit_ida(observed, censored)
    assert abs(math.log(fit.median / 0.8)) < 4 * fit.se_ln_median
    assert abs(fit.beta - 0.35) < 4 * fit.se_beta
    naive = fr.fit_ida(observed)
    assert abs(naive.beta - 0.35) > 10 * fit.se_beta
    assert censored.mean() == pytest.approx(0.37, abs=0.03)


def test_censored_ida_agrees_with_pyfragility():
    import pyFragility as pf  # test-only dependency (pyproject [test])

    rng = np.random.default_rng(2)
    for top in (0.7, 1.0, 1.5):
        capacity = np.exp(rng.normal(math.log(0.8), 0.3, 40))
        censored = capacity > top
        ours = fr.fit_ida(np.minimum(capacity, top), censored)
        theirs = pf.fit_ida(np.minimum(capacity, top), censored)
        assert ours.median == pytest.approx(theirs.params[0], rel=1e-6)
        assert ours.beta == pytest.approx(theirs.params[1], rel=1e-6)


@pytest.mark.parametrize(
    "capacity, censored, field",
    [
        ([0.5, 0.5, 0.9], [False, False, True], "capacity"),  # one distinct failure IM
        ([0.5, 0.6, 0.9], [True, True, True], "capacity"),  # all censored
        ([0.5, -0.6, 0.9], None, "capacity[1]"),
        ([0.5, 0.6], [False], "censored"),
    ],
)
def test_unfittable_ida_is_refused(capacity, censored, field):
    with pytest.raises(fr.FragilityDataError) as err:
        fr.fit_ida(capacity, censored)
    assert err.value.field == field


# --------------------------------------------------------------------------------- curves


def test_curves_are_monotone_and_pass_the_median():
    grid = np.r_[0.0, np.geomspace(1e-4, 1e4, 2001)]
    for theta, beta in [(0.5, 0.4), (2.0, 0.05), (0.01, 3.0)]:
        p = fr.fragility_curve(grid, theta, beta)
        assert p[0] == 0 and np.all(np.diff(p) >= 0) and p[-1] <= 1
        assert fr.fragility_curve([theta], theta, beta)[0] == pytest.approx(0.5)
    with pytest.raises(fr.FragilityDataError, match="beta"):
        fr.fragility_curve(grid, 0.5, 0.0)


# --------------------------------------------------------------------------------- tables


def summary_table(seed=4, records=30):
    """One row per (record, IM): a drift-like column and an 'unseated' flag, both exceeding at
    IM >= the record's capacity (lognormal THETA, BETA)."""
    rng = np.random.default_rng(seed)
    capacity = np.exp(rng.normal(math.log(THETA), BETA, records))
    rows = [
        {
            "record": f"rec{i:02d}",
            "im": x,
            "peak_theta": 0.01 * x / capacity[i],
            "unseated": bool(x >= capacity[i]),
        }
        for i in range(records)
        for x in LEVELS
    ]
    return pd.DataFrame(rows), capacity


def test_count_exceedances_by_threshold_and_flag():
    table, capacity = summary_table()
    flag = fr.count_exceedances(table, fr.LimitState("unseated"))
    drift = fr.count_exceedances(table, fr.LimitState("peak_theta", 0.01))
    assert list(flag.columns) == ["im", "n", "exceed"]
    assert np.array_equal(flag["im"], LEVELS) and (flag["n"] == 30).all()
    expected = [(capacity < x).sum() for x in LEVELS]
    assert flag["exceed"].tolist() == expected == drift["exceed"].tolist()
    as_numbers = table.assign(unseated=table["unseated"].astype(int))
    assert fr.count_exceedances(as_numbers, fr.LimitState("unseated")).equals(flag)
    as_words = table.assign(unseated=table["unseated"].map({True: "True", False: "false"}))
    assert fr.count_exceedances(as_words, fr.LimitState("unseated")).equals(flag)


def test_ida_capacities_first_exceedance_and_censoring():
    table, capacity = summary_table()
    ida = fr.ida_capacities(table.sample(frac=1, random_state=1), fr.LimitState("unseated"))
    for i, c in enumerate(capacity):
        row = ida.loc[f"rec{i:02d}"]
        if c > LEVELS[-1]:
            assert row["censored"] and row["capacity"] == LEVELS[-1]
        else:
            assert not row["censored"] and row["capacity"] == LEVELS[c <= LEVELS][0]


@pytest.mark.parametrize(
    "change, limit_state, field, text",
    [
        ({}, fr.LimitState("collapse"), "collapse", "no such column"),
        ({"peak_theta": "x"}, fr.LimitState("peak_theta", 0.01), "peak_theta[0]", "finite"),
        ({"unseated": 2}, fr.LimitState("unseated"), "unseated[0]", "true/false or 0/1"),
        ({"im": -1.0}, fr.LimitState("unseated"), "im[0]", "IM > 0"),
        ({"unseated": "yes"}, fr.LimitState("unseated"), "unseated[0]", "true/false or 0/1"),
        ({"unseated": None}, fr.LimitState("unseated"), "unseated[0]", "true/false or 0/1"),
    ],
)
def test_bad_summary_tables_are_refused(change, limit_state, field, text):
    table, _ = summary_table()
    for column, value in change.items():
        table[column] = table[column].astype(object)
        table.loc[0, column] = value
    with pytest.raises(fr.FragilityDataError, match=text) as err:
        fr.count_exceedances(table, limit_state)
    assert err.value.field == field


# --------------------------------------------------------------------------------- bootstrap


def test_record_bootstrap_bands_are_seeded_monotone_and_cover_the_fit():
    table, _ = summary_table(records=30)
    grid = np.geomspace(0.1, 2.0, 40)
    bands = fr.bootstrap_stripes(table, fr.LimitState("unseated"), grid, n_resamples=200, seed=9)
    again = fr.bootstrap_stripes(table, fr.LimitState("unseated"), grid, n_resamples=200, seed=9)
    assert np.array_equal(bands.lower, again.lower) and np.array_equal(bands.upper, again.upper)
    assert len(bands.medians) + bands.skipped == 200
    assert np.all(np.diff(bands.lower) >= 0) and np.all(np.diff(bands.upper) >= 0)
    assert np.all(bands.lower <= bands.curve + 1e-12) and np.all(bands.curve <= bands.upper + 1e-12)
    lo, hi = bands.median_interval()
    assert lo < THETA < hi


def test_bootstrap_skips_and_counts_unfittable_resamples():
    """Four records, two of which never fail: a resample with fewer than two distinct failure
    IMs cannot be fitted (probability 1 − P(two distinct failures) ≈ 0.6 per resample)."""
    bands = fr.bootstrap_ida(
        [0.4, 0.6, 1.0, 1.0], [False, False, True, True], [0.5, 1.0], n_resamples=300, seed=1
    )
    assert 0 < bands.skipped < 300 and len(bands.medians) + bands.skipped == 300
    with pytest.raises(fr.FragilityDataError, match="none of the 5 resamples"):
        fr.bootstrap_ida([0.4, 0.6, 1.0], [False, False, True], [0.5], n_resamples=5, seed=0)


def test_parametric_bootstrap_spread_matches_fisher():
    """Redrawing binomial counts from the fit: the spread of the refitted ln θ matches the
    inverse Fisher information to 15 % (400 resamples)."""
    x, n, z = draw_stripes(np.random.default_rng(6))
    fit = fr.fit_stripes(x, n, z)
    bands = fr.parametric_bootstrap_stripes(x, n, z, n_resamples=400, seed=2)
    assert np.std(np.log(bands.medians)) == pytest.approx(fit.se_ln_median, rel=0.15)
    assert np.std(bands.betas) == pytest.approx(fit.se_beta, rel=0.15)


# --------------------------------------------------------------------------------- CLI


def write_stripes(tmp_path, x, n, z, name="stripes.csv"):
    path = tmp_path / name
    lines = ["im,n,exceed,comment"] + [f"{float(a)!r},{b},{c},stripe" for a, b, c in zip(x, n, z)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_cli_table_and_json(tmp_path, capsys):
    x, n, z = draw_stripes(np.random.default_rng(8))
    fit = fr.fit_stripes(x, n, z)
    path = write_stripes(tmp_path, x, n, z)
    assert main(["fragility", "fit", str(path)]) == 0
    out, err = capsys.readouterr()
    assert not err
    assert f"median          {fit.median:.6g}" in out and f"beta            {fit.beta:.6g}" in out
    assert f"log-likelihood  {fit.loglik:.6f}" in out and "10 IM levels" in out
    assert main(["fragility", "fit", str(path), "--json"]) == 0
    out, err = capsys.readouterr()
    assert not err
    data = json.loads(out)
    assert data == {"median": fit.median, "beta": fit.beta}


def test_cli_parametric_bootstrap_is_seeded(tmp_path, capsys):
    path = write_stripes(tmp_path, *draw_stripes(np.random.default_rng(8)))
    outs = []
    for _ in range(2):
        assert main(["fragility", "fit", str(path), "--bootstrap", "50", "--seed", "4"]) == 0
        outs.append(capsys.readouterr().out)
    assert outs[0] == outs[1] and "50 of 50 resamples fitted" in outs[0]
    assert main(["fragility", "fit", str(path), "--bootstrap", "5", "--json"]) == 2


@pytest.mark.parametrize(
    "text, where, what",
    [
        ("im,n\n0.1,3\n", "", "no column 'exceed'"),
        ("im,n,exceed\n0.1,3,x\n", " line 2, column exceed", "must be a number, got 'x'"),
        ("im,n,exceed\n0.1,3,1\n\n0.2,3,5\n", " line 4, column exceed", "must be <= n = 3"),
        ("im,n,exceed\n0.1,3,1\n0.2,-3,1\n", " line 3, column n", "whole number >= 0"),
        ("im,n,exceed\n0.1,3,0\n0.2,3,0\n", " (column exceed)", "no record exceeds"),
        ("im,n,exceed\n", "", "no stripe rows"),
        ("", "", "is empty"),
    ],
)
def test_cli_bad_files_exit_2_with_one_line(tmp_path, capsys, text, where, what):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    assert main(["fragility", "fit", str(path)]) == 2
    out, err = capsys.readouterr()
    assert not out and len(err.splitlines()) == 1
    assert err.startswith(f"deckpound: error: {path}{where}") and what in err, err


def test_cli_unreadable_file_exits_3(tmp_path, capsys):
    assert main(["fragility", "fit", str(tmp_path / "missing.csv")]) == 3
    out, err = capsys.readouterr()
    assert not out and len(err.splitlines()) == 1 and "missing.csv" in err


def test_cases_without_a_record_are_refused():
    table, _ = summary_table()
    table.loc[3, "record"] = None
    for call in (
        lambda: fr.ida_capacities(table, fr.LimitState("unseated")),
        lambda: fr.bootstrap_stripes(table, fr.LimitState("unseated"), [0.5], n_resamples=2),
    ):
        with pytest.raises(fr.FragilityDataError, match="name its record") as err:
            call()
        assert err.value.field == "record[3]"


def test_cli_reads_a_spreadsheet_csv_with_bom(tmp_path, capsys):
    path = tmp_path / "excel.csv"
    path.write_bytes(b"\xef\xbb\xbfim,n,exceed\r\n0.2,10,1\r\n0.4,10,5\r\n0.8,10,9\r\n")
    assert main(["fragility", "fit", str(path), "--json"]) == 0
    fit = fr.fit_stripes([0.2, 0.4, 0.8], [10] * 3, [1, 5, 9])
    assert json.loads(capsys.readouterr().out) == {"median": fit.median, "beta": fit.beta}

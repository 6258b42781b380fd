"""Coverage of a new record by a baseline's fitting records (tsfdi.coverage, Baselines.covers; issue 31 part 2)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pandas as pd
import pytest
from _synthetic_fdi import FS, dataset, record
from conftest import as_kind
from scipy import stats

import tsfdi
from tsfdi.coverage import (ALL, LEVEL_SUM, MIN_RECORDS, Coverage, check_coverage, coverage, record_coverage,
                            warn_if_not_covered)
from tsfdi.exceptions import CoverageWarning, TsfdiWarning

A1 = np.array([[0.5, 0.1, 0.0], [0.0, 0.4, 0.1], [0.1, 0.0, 0.3]])
A2 = -0.2 * np.eye(3)
MU = np.array([1.0, -0.5, 0.2])
SPREAD = 0.15


def fleet(rng: np.random.Generator, count: int, n: int = 2000, noise: float = 1.0, shift: float = 0.0,
          law: str = "normal") -> list:
    """``count`` records of ``count`` aircraft of a fleet: VAR(2) y[t] = B1 y[t-1] + B2 y[t-2] + e[t] + mu whose
    coefficients, channel noise scales and means each vary by +-15 % between aircraft (``law="normal"``: factors
    1 + N(0, 0.075^2), 95 % of them within +-15 %; ``"uniform"``: uniform on 1 +- 0.15); ``noise`` scales every
    aircraft's noise, ``shift`` offsets its means (another fleet)."""
    def u(*shape):
        if law == "uniform":
            return 1.0 + SPREAD * rng.uniform(-1.0, 1.0, (count, *shape))
        return 1.0 + SPREAD / 2 * rng.standard_normal((count, *shape))

    b1, b2, s, mu = A1 * u(3, 3), A2 * u(3, 3), noise * u(3), MU * u(3) + shift
    e = rng.standard_normal((count, n + 200, 3)) * s[:, None, :]
    y = np.zeros_like(e)
    for t in range(2, n + 200):
        y[:, t] = np.einsum("rij,rj->ri", b1, y[:, t - 1]) + np.einsum("rij,rj->ri", b2, y[:, t - 2]) + e[:, t]
    return list(y[:, 200:] + mu[:, None, :])


def band(n: int, alpha: float, level: float = 0.99) -> tuple:
    """Two-sided binomial band of the number of warnings among ``n`` independent records."""
    return tuple(stats.binom.ppf([(1 - level) / 2, (1 + level) / 2], n, alpha))


@pytest.fixture(scope="module")
def baseline():
    rng = np.random.default_rng(31)
    return tsfdi.VAR(fleet(rng, 10), 2, trend="c").fit(), rng


@pytest.mark.slow
def test_false_warning_rate_and_power_on_a_simulated_fleet():
    """Monte Carlo, fixed seed: 150 baselines of 10 aircraft each judge 10 new aircraft of the same fleet (1,500
    records): the warnings lie in the 99 % binomial band of alpha = 0.01; records of another fleet (noise x1.5, or
    means offset by 0.5) are warned of in >= 90 %."""
    rng = np.random.default_rng(2031)
    same, noisy, shifted = [], [], []
    for _ in range(150):
        b = tsfdi.VAR(fleet(rng, 10), 2, trend="c").fit()
        held = b.model.held_out_residuals()
        same += [coverage(b, y, held_out=held).covered for y in fleet(rng, 10)]
        noisy += [coverage(b, y, held_out=held).covered for y in fleet(rng, 1, noise=1.5)]
        shifted += [coverage(b, y, held_out=held).covered for y in fleet(rng, 1, shift=0.5)]
    lo, hi = band(len(same), 0.01)
    warned = len(same) - sum(same)
    assert lo <= warned <= hi, (warned, (lo, hi))
    assert np.mean(np.logical_not(noisy)) >= 0.9, np.mean(np.logical_not(noisy))
    assert np.mean(np.logical_not(shifted)) >= 0.9, np.mean(np.logical_not(shifted))


def test_predictive_t_statistics_by_hand(baseline):
    """Every row of the table is the predictive t of the summary against the fitting records' summaries (computed
    here from the held-out residuals by hand), with the Sidak share of alpha over the summaries."""
    b, rng = baseline
    y = fleet(rng, 1)[0]
    cov = coverage(b, y, alpha=0.05, lags=1)
    held = b.model.held_out_residuals()
    e = np.asarray(b.residuals(y))
    feats = []
    for x, r in [(rec.values, np.asarray(h)) for rec, h in zip(b.model.records, held)] + [(y, e)]:
        ls = 0.5 * np.log((r ** 2).mean(axis=0))
        rc = r - r.mean(axis=0)
        acf = np.arctanh((rc[1:] * rc[:-1]).sum(axis=0) / (rc ** 2).sum(axis=0))
        feats.append(np.r_[x.mean(axis=0), ls, ls.mean(), acf])
    F, f = np.array(feats[:-1]), feats[-1]
    n, m = F.shape
    t = (f - F.mean(0)) / (F.std(0, ddof=1) * np.sqrt(1 + 1 / n))
    np.testing.assert_allclose(cov.table["t"].to_numpy(), t, rtol=1e-10)
    np.testing.assert_allclose(cov.table["pvalue"].to_numpy(), 2 * stats.t.sf(abs(t), n - 1), rtol=1e-10)
    crit = stats.t.ppf(1 - (1 - 0.95 ** (1 / m)) / 2, n - 1)
    np.testing.assert_allclose(cov.table["upper"] - cov.table["lower"],
                               2 * crit * F.std(0, ddof=1) * np.sqrt(1 + 1 / n), rtol=1e-10)
    assert cov.pvalue == pytest.approx(1 - (1 - cov.table["pvalue"].min()) ** m)
    assert cov.covered == (cov.pvalue > 0.05) == (abs(t) <= crit).all()
    assert cov.records == 10 and cov.nobs == 2000 and m == 10
    assert list(cov.table.index[:7]) == [("mean", "y0"), ("mean", "y1"), ("mean", "y2"), ("log_scale", "y0"),
                                         ("log_scale", "y1"), ("log_scale", "y2"), ("log_scale", ALL)]


def test_out_of_fleet_record_names_the_summaries_and_warns(baseline):
    b, rng = baseline
    y = fleet(rng, 1)[0]
    y[:, 1] += 3.0                                        # a new trim of channel 1
    cov = coverage(b, y)
    assert not cov.covered and cov.pvalue < 0.01
    assert cov.out.index[0] == ("mean", "y1") and cov.out["excess"].iloc[0] > 1
    assert "mean[y1]" in cov.warning_message() and "outside" in cov.warning_message()
    assert "mean[y1]" in repr(cov)
    with pytest.warns(CoverageWarning, match=r"detect: the record lies outside .*mean\[y1\]"):
        warn_if_not_covered(cov, "detect")
    assert issubclass(CoverageWarning, TsfdiWarning) and issubclass(CoverageWarning, UserWarning)
    with pytest.raises(dataclasses.FrozenInstanceError):
        cov.covered = True


def test_given_held_out_residuals_are_read_on_every_call(baseline):
    """The fitting records' summaries are kept between calls only for the model's own held-out residuals: residuals
    the caller gives are read each time, so a series changed in place between two calls changes the check."""
    b, rng = baseline
    y = fleet(rng, 1)[0]
    held = [np.array(h, dtype=np.float64) for h in b.model.held_out_residuals()]
    own = coverage(b, y, held_out=held)
    for h in held:
        h *= 3.0                                                           # louder fitting records, in place
    louder = coverage(b, y, held_out=held)
    assert not np.allclose(louder.table["fit_mean"], own.table["fit_mean"])
    pd.testing.assert_frame_equal(coverage(b, y).table, own.table)         # the model's own residuals: as given first
    pd.testing.assert_frame_equal(coverage(b, y).table, own.table)         # (and kept)


def test_covered_record_does_not_warn(baseline):
    b, rng = baseline
    cov = coverage(b, b.model.records[0].values)           # a fitting record itself lies within the spread
    assert cov.covered and "within" in cov.warning_message() and cov.out.empty
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warn_if_not_covered(cov, "detect")
    with pytest.raises(TypeError, match="coverage must be a Coverage"):
        warn_if_not_covered(cov.table, "detect")


def test_data_kinds_and_channel_names(kind):
    """numpy, pandas and xarray records and signals give the same coverage; named channels are matched by name."""
    rng = np.random.default_rng(7)
    recs = fleet(rng, 4, n=600)
    y = fleet(rng, 1, n=600)[0]
    names = ["roll", "pitch", "yaw"]
    b = tsfdi.VAR([as_kind(r, kind, names) for r in recs], 2).fit()
    ref = coverage(tsfdi.VAR(recs, 2).fit(), y)
    cov = coverage(b, as_kind(y, kind, names))
    np.testing.assert_allclose(cov.table["t"].to_numpy(), ref.table["t"].to_numpy(), rtol=1e-9)
    assert cov.covered == ref.covered
    if kind != "numpy":
        assert list(cov.table.loc["mean"].index) == names
        swapped = as_kind(y[:, ::-1], kind, names[::-1])       # same data, columns in another order
        np.testing.assert_allclose(coverage(b, swapped).table["t"], cov.table["t"], rtol=1e-12)
        with pytest.raises(ValueError, match="yaw"):
            coverage(b, as_kind(y[:, :2], kind, names[:2]), name="flight")


def test_bad_input(baseline):
    b, rng = baseline
    y = fleet(rng, 1, n=300)[0]
    two = tsfdi.VAR(fleet(rng, 2, n=300), 2).fit()
    with pytest.raises(ValueError, match=f"at least {MIN_RECORDS} fitting records.*fitted on 2"):
        coverage(two, y)
    with pytest.raises(ValueError, match="held_out must hold one residual series per fitting record"):
        coverage(b, y, held_out=b.model.held_out_residuals()[:3])
    with pytest.raises(ValueError, match=r"held_out\[0\]"):
        coverage(b, y, held_out=[h[:, :2] for h in b.model.held_out_residuals()])
    with pytest.raises(ValueError, match="alpha"):
        coverage(b, y, alpha=1.5)
    with pytest.raises(TypeError, match="lags"):
        coverage(b, y, lags=1.5)
    with pytest.raises(ValueError, match="flight"):
        coverage(b, y[:3], name="flight")
    with pytest.raises(ValueError, match="flight"):
        coverage(b, np.where(np.arange(300)[:, None] == 5, np.nan, y), name="flight")
    with pytest.raises(ValueError, match="channel"):
        coverage(b, y[:, :2])
    with pytest.raises(TypeError, match="results"):
        coverage(y, y)
    u = [rng.standard_normal(300) for _ in range(3)]
    arx = tsfdi.ARX([r[:, 0] for r in fleet(rng, 3, n=300)], u, na=1, nb=1).fit()
    with pytest.raises(TypeError, match="ARX"):
        coverage(arx, y[:, 0])


def test_scalar_ar_results():
    rng = np.random.default_rng(3)
    recs = [r[:, 0] for r in fleet(rng, 5, n=800)]
    b = tsfdi.AR(recs, 2).fit()
    cov = coverage(b, pd.Series(recs[0] + 0.0))
    assert cov.covered and list(cov.table.index.get_level_values("summary")) == ["mean", "log_scale", "acf1", "acf2"]
    assert not coverage(b, 3.0 * recs[0]).covered        # three times the noise level


def test_baselines_covers(synthetic):
    """Baselines.covers is coverage() of the state's model with the baseline's held-out residuals (kept by
    calibrate=True, computed otherwise); too few fitting records are refused with how many are needed."""
    recs, states, ft = synthetic
    kw = dict(states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, max_lags=6, var_max_lags=6)
    b = tsfdi.fit_baselines(recs, fit_records=4, calibrate=True, **kw)
    lazy = tsfdi.fit_baselines(recs, fit_records=4, **kw)
    rng = np.random.default_rng(11)
    new = record("healthy", 3000, rng)
    cov = b.covers(new)
    assert isinstance(cov, Coverage) and cov.records == 4
    ref = coverage(b.models["var"]["healthy"], new, held_out=b.heldout[("var", "healthy")])
    pd.testing.assert_frame_equal(cov.table, ref.table)
    pd.testing.assert_frame_equal(lazy.covers(new).table, cov.table)
    assert not b.covers(new + np.array([0.0, 2.0])).covered
    one = b.covers(new[:, 1], model="y1", state="f1", lags=1)
    assert not one.covered and one.out.index[0][0] == "log_scale"     # f1's noise is twice the healthy one
    with pytest.raises(ValueError, match="state must be one of"):
        b.covers(new, state="f9")
    with pytest.raises(ValueError, match="model must be one of"):
        b.covers(new, model="z")
    first = tsfdi.fit_baselines(recs, **kw)                # one fitting record per state
    with pytest.raises(ValueError, match="at least 3 fitting records of state 'healthy', the baseline has 1"):
        first.covers(new)


def combined(alpha: float = 0.01) -> tsfdi.AnyOf:
    return tsfdi.AnyOf([tsfdi.LjungBox(lags=20, alpha=alpha, threshold="calibrated"),
                        tsfdi.FTest(alpha=alpha, threshold="calibrated"),
                        tsfdi.MeanTest(alpha=alpha, threshold="calibrated")])


@pytest.fixture(scope="module")
def calibrated(baseline):
    b, _ = baseline
    return b, combined().calibrate(b.model.held_out_residuals(), window=200)


def test_record_coverage_table_is_the_record_law_of_every_part_and_channel(calibrated):
    """One row per part and channel: the new record's level and its p-value under the part's predictive record
    law (ScaledChi2Threshold.record_pvalue on the windows the calibration used: every window here, step 1), the
    fitting records' levels, the one-sided bound at the Sidak share of alpha over the 10 rows (these 9 and the
    levels' sum, test_record_coverage_level_sum_row_by_hand); a record of a higher noise level is out on the F
    test, one of a lower noise level is not warned of (its false alarms are fewer)."""
    b, test = calibrated
    rng = np.random.default_rng(12)
    y = fleet(rng, 1)[0]
    e = b.residuals(y)
    cov = record_coverage(test, e)
    assert cov.records == 10 and cov.nobs == e.shape[0] and len(cov.table) == 10
    assert list(cov.table.index.get_level_values("summary").unique()) == ["LjungBox", "FTest", "MeanTest",
                                                                          LEVEL_SUM]
    share = 1 - 0.99 ** (1 / 10)
    for part in test.tests:
        stat = part.window_statistic(np.asarray(e), 198, 1)
        for c, th in enumerate(part.thresholds_):
            row = cov.table.loc[(type(part).__name__, f"y{c}")]
            level, _, p = th.record_pvalue(stat[:, c], e.shape[0] // 198)
            assert row["value"] == pytest.approx(level) and row["pvalue"] == pytest.approx(p)
            assert row["fit_mean"] == pytest.approx(th.levels_.mean())
            assert row["upper"] == pytest.approx(th.record_bound(share, e.shape[0] // 198))
            assert row["lower"] == -np.inf and row["out"] == (p < share) == (level > row["upper"])
    assert cov.covered
    loud = record_coverage(test, b.residuals(fleet(rng, 1, noise=1.6)[0]))
    assert not loud.covered and loud.table.loc["FTest", "out"].any() and "FTest[" in loud.warning_message()
    quiet = record_coverage(test, b.residuals(fleet(rng, 1, noise=0.6)[0]))
    assert quiet.covered and (quiet.table.loc["FTest", "t"] < -3).all()


def test_record_coverage_level_sum_row_by_hand(calibrated):
    """The row of the whole decision: the new record's levels summed over the parts and channels against each
    fitting record's sum (the record laws' levels_), the one-sided Student t pivot (D - mean) / (s sqrt(1 + 1/J))
    with J - 1 degrees of freedom, its bound at the Sidak share of the 10 rows; a record half as long has its
    variance scaled by the fitting records' windows over its own (noisier levels). A record whose means moved a
    little on every channel lies within every part's row and outside the sum (it was covered before)."""
    b, test = calibrated
    rng = np.random.default_rng(18)
    e = np.asarray(b.residuals(fleet(rng, 1)[0]))
    fit = np.sum([th.levels_ for part in test.tests for th in part.thresholds_], axis=0)
    share = 1 - 0.99 ** (1 / 10)
    for x, ratio in ((e, 1.0), (e[:999], 10 / 5)):                   # 10 windows of 198 per fitting record; 5
        cov = record_coverage(test, x)
        row = cov.table.loc[(LEVEL_SUM, ALL)]
        d = cov.table["value"].iloc[:9].sum()
        scale = fit.std(ddof=1) * np.sqrt(1 / 10 + ratio)
        t = (d - fit.mean()) / scale
        assert row["value"] == pytest.approx(d) and row["fit_mean"] == pytest.approx(fit.mean())
        assert row["fit_std"] == pytest.approx(fit.std(ddof=1)) and row["fit_max"] == pytest.approx(fit.max())
        assert row["t"] == pytest.approx(t) and row["pvalue"] == pytest.approx(stats.t.sf(t, 9))
        assert row["upper"] == pytest.approx(fit.mean() + stats.t.isf(share, 9) * scale)
        assert row["out"] == (row["pvalue"] < share) and row["lower"] == -np.inf
    moved = record_coverage(test, b.residuals(fleet(rng, 1, shift=0.15)[0]))
    assert not moved.covered and list(moved.out.index) == [(LEVEL_SUM, ALL)], moved.table
    one = tsfdi.FTest(alpha=0.01, threshold="calibrated").calibrate(
        [r[:, :1] for r in b.model.held_out_residuals()], window=200)
    assert LEVEL_SUM not in record_coverage(one, e[:, :1]).table.index.get_level_values("summary")  # one row


def test_record_coverage_bad_input(calibrated):
    b, test = calibrated
    rng = np.random.default_rng(13)
    e = b.residuals(fleet(rng, 1)[0])
    with pytest.raises(ValueError, match="flight holds 500 samples, at least 3 disjoint windows"):
        record_coverage(test, e[:500], name="flight")
    with pytest.raises(ValueError, match="2 channel"):
        record_coverage(test, e[:, :2])
    with pytest.raises(ValueError, match="alpha"):
        record_coverage(test, e, alpha=0.0)
    with pytest.raises(TypeError, match="calibrated windowed test"):
        record_coverage(b, e)
    boot = tsfdi.FTest(alpha=0.01, threshold=tsfdi.ScaledChi2Threshold(0.01, record_effect="bootstrap"))
    with pytest.raises(ValueError, match="FTest is not calibrated with the predictive record law"):
        record_coverage(boot.calibrate(b.model.held_out_residuals(), window=200), e)
    with pytest.raises(ValueError, match="not calibrated with the predictive record law"):
        record_coverage(tsfdi.FTest(alpha=0.01), e)


@pytest.mark.slow
def test_record_coverage_false_warnings_and_the_records_the_test_flags():
    """Monte Carlo, fixed seed: 40 baselines of 10 aircraft, LB+F+M calibrated on their held-out residuals, judge 10
    new aircraft of the same fleet each (400 records: warnings in the 99 % binomial band of alpha = 0.01) and one of
    a noisier fleet (noise x1.5) each: warned of whenever the test flags its disjoint windows beyond their 99.9 %
    band, and on >= 90 % of them."""
    rng = np.random.default_rng(2032)
    same, flagged, loud = [], [], []
    for _ in range(40):
        b = tsfdi.VAR(fleet(rng, 10), 2, trend="c").fit()
        test = combined().calibrate(b.model.held_out_residuals(), window=200)
        same += [not record_coverage(test, b.residuals(y)).covered for y in fleet(rng, 10)]
        e = np.asarray(b.residuals(fleet(rng, 1, noise=1.5)[0]))
        w = np.zeros(e.shape[0] // 198, dtype=bool)
        for part in test.tests:
            w |= (part.window_statistic(e, 198, 198) > part.threshold_).any(axis=1)
        warned = not record_coverage(test, e).covered
        loud.append(warned)
        if w.sum() > stats.binom.ppf(0.9995, w.size, 0.01):
            flagged.append(warned)
    lo, hi = band(len(same), 0.01)
    assert lo <= sum(same) <= hi, (sum(same), (lo, hi))
    assert len(flagged) >= 30 and all(flagged), flagged
    assert np.mean(loud) >= 0.9, np.mean(loud)


@pytest.mark.slow
def test_record_pvalues_of_every_part_hold_their_rate_on_the_fleet():
    """Monte Carlo, fixed seed: 80 baselines of 10 aircraft, LB+F+M calibrated on their held-out residuals, 10 new
    aircraft of the same fleet each: per part, the 2,400 record p-values (3 channels) below 0.01 lie in the
    two-sided 99.9 % binomial band. (Comparing a record's own anchor -- the log of its alpha quantile, with its own
    Ljung-Box shape from 10 windows -- gave twice the rate for Ljung-Box; netting the levels' sampling variance
    out of their spread and adding the new record's back made it a quarter.)"""
    rng = np.random.default_rng([99, 10])
    p = {"LjungBox": [], "FTest": [], "MeanTest": []}
    for _ in range(80):
        b = tsfdi.VAR(fleet(rng, 10), 2, trend="c").fit()
        test = combined().calibrate(b.model.held_out_residuals(), window=200)
        for y in fleet(rng, 10):
            tab = record_coverage(test, b.residuals(y)).table
            for part in p:
                p[part] += list(tab.loc[part, "pvalue"])
    lo, hi = stats.binom.ppf([0.0005, 0.9995], 2400, 0.01)
    for part, v in p.items():
        assert len(v) == 2400 and lo <= np.sum(np.array(v) < 0.01) <= hi, (part, np.sum(np.array(v) < 0.01), lo, hi)


def test_detect_warns_and_keeps_the_coverage_of_an_uncovered_record(baseline, kind):
    """detect (issue 31): a baseline fitted on 3 or more records judges whole records by the spread of its fitting
    records' summaries; an out-of-fleet record warns naming detect, the summaries and what to do, and the decision
    keeps the Coverage in details["coverage"] (that of coverage() itself); a covered record does not warn."""
    b, _ = baseline
    rng = np.random.default_rng(14)
    names = ["roll", "pitch", "yaw"]
    named = tsfdi.VAR([pd.DataFrame(r.values, columns=names) for r in b.model.records], 2, trend="c").fit() \
        if kind != "numpy" else b
    y = fleet(rng, 1, shift=0.8)[0]
    with pytest.warns(CoverageWarning, match=r"detect: the record lies outside .*mean\[.*fit the baseline on flights"):
        d = tsfdi.detect(as_kind(y, kind, names), named)
    cov = d.details["coverage"]
    pd.testing.assert_frame_equal(cov.table, coverage(named, as_kind(y, kind, names)).table)
    assert not cov.covered and d.statistic.shape == (3,)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CoverageWarning)
        ok = tsfdi.detect(as_kind(named.model.records[0].values, kind, names), named)
    assert ok.details["coverage"].covered


def test_detect_says_nothing_when_coverage_cannot_be_checked(baseline):
    """One or two fitting records, or a signal shorter than every fitting record (a window): no check, no warning,
    no "coverage" in details; the decision is that of the test."""
    b, _ = baseline
    rng = np.random.default_rng(15)
    loud = fleet(rng, 1, noise=3.0)[0]
    two = tsfdi.VAR(b.model.records[:2], 2, trend="c").fit()
    with warnings.catch_warnings():
        warnings.simplefilter("error", CoverageWarning)
        for res, y in ((two, loud), (b, loud[:1999])):
            d = tsfdi.detect(y, res)
            assert "coverage" not in d.details
            np.testing.assert_array_equal(d.statistic, tsfdi.LjungBox().test(res.residuals(y)).statistic)


def test_check_coverage_prefers_the_record_law_of_a_calibrated_test(calibrated):
    """check_coverage: the record law of a test calibrated on 3 or more records when the record holds 3 of its
    windows (the residuals computed when not given, named by the model's channels), else the summaries (a record
    as long as the fitting records), else None (a shorter record; an uncalibrated test on a 2-record baseline)."""
    b, test = calibrated
    rng = np.random.default_rng(17)
    y = fleet(rng, 1, noise=1.6)[0]
    got = check_coverage(test, b, y)
    ref = record_coverage(test, b.residuals(y))
    np.testing.assert_allclose(got.table["pvalue"], ref.table["pvalue"], rtol=1e-12)
    assert not got.covered and got.table.loc["FTest", "out"].any()
    pd.testing.assert_frame_equal(check_coverage(tsfdi.LjungBox(), b, y).table, coverage(b, y).table)
    assert check_coverage(test, b, y[:590]) is None                  # 2 windows, shorter than the records
    assert not check_coverage(test, b, y[:600]).covered             # 3 windows of 198 residuals: the record law
    two = tsfdi.VAR(b.model.records[:2], 2, trend="c").fit()
    assert check_coverage(tsfdi.LjungBox(), two, y) is None


@pytest.mark.slow
def test_record_coverage_with_five_records_holds_its_rate_and_warns_of_moved_means():
    """Monte Carlo, fixed seed: 60 baselines of 5 aircraft, LB+F+M calibrated on their held-out residuals, judge 4
    new aircraft of the same fleet each (240 records: warnings in the 99 % binomial band of alpha = 0.01; 7, the
    band's top, all 7 by the rows per part and channel, as before the level-sum row: with 5 records a baseline's
    rate varies, 2 baselines give 4 of them) and one aircraft whose means moved by 0.3 (a trim the fitting records
    did not show): warned of in >= 60 % (41 of 60), where the rows per part and channel alone at the same alpha
    (the check before the level-sum row) warn of 28."""
    rng = np.random.default_rng([3705, 5])
    same, moved, parts_only = [], [], []
    for _ in range(60):
        b = tsfdi.VAR(fleet(rng, 5), 2, trend="c").fit()
        test = combined().calibrate(b.model.held_out_residuals(), window=200)
        same += [not record_coverage(test, b.residuals(y)).covered for y in fleet(rng, 4)]
        cov = record_coverage(test, b.residuals(fleet(rng, 1, shift=0.3)[0]))
        moved.append(not cov.covered)
        rows = cov.table.drop(index=LEVEL_SUM, level="summary")["pvalue"]
        parts_only.append(1 - (1 - rows.min()) ** len(rows) < 0.01)
    lo, hi = band(len(same), 0.01)
    assert lo <= sum(same) <= hi, (sum(same), (lo, hi))
    assert np.mean(moved) >= 0.6 > np.mean(parts_only), (np.mean(moved), np.mean(parts_only))

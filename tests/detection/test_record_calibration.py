"""Record-level (predictive) calibration holds on the next aircraft of a fleet (issue 31).

The simulated fleet of benchmarks/fleet_calibration.py: VAR(2) records whose coefficients and noise scale
(log-normal +-15 % per record and channel) vary from aircraft to aircraft. A baseline is fitted on 5, 10 or 20
records, the F and Ljung-Box tests (Sidak over the channels: alpha is the decision's rate) are calibrated on its
held-out residuals, and 60 new records (600 disjoint windows of 200 samples) are judged: the realised rate of the
decision must lie in the two-sided 99.9 % binomial band. The per-record mixture with a bootstrap bound (the previous
default, ``record_effect="bootstrap"``) treats the windows of a record as independent evidence and does not
extrapolate the record-to-record spread: its F test flags 5-15 % of new windows at alpha 0.01.
"""

from __future__ import annotations


import numpy as np
import pytest
from scipy import stats

import tsfdi
from tsfdi.detection.threshold import ScaledChi2Threshold, records_needed
from _scripts import load_script


def _bench():
    return load_script("benchmarks/fleet_calibration.py")


FC = _bench()
NEW = 60                                  # new records of the one-fleet checks: 600 disjoint windows


@pytest.fixture(scope="module")
def fleet():
    rng = np.random.default_rng(2031)
    return FC.fleet_records(rng, 20)[0], FC.fleet_records(rng, NEW)[0]


def band(n: int, alpha: float) -> tuple:
    lo, hi = stats.binom.ppf([0.0005, 0.9995], n, alpha)
    return lo / n, hi / n


@pytest.mark.parametrize("records", [5, 10, 20])
def test_new_records_of_the_fleet_in_band(fleet, records):
    fit, new = fleet
    spec = tsfdi.VAR(fit[:records], 2)
    base = spec.fit()
    held = spec.held_out_residuals()
    resid = [np.asarray(base.residuals(x)) for x in new]
    windows = len(new) * ((FC.N - 2) // (FC.WINDOW - 2))
    old_f = []
    for alpha in (1e-2, 1e-3):
        lo, hi = band(windows, alpha)
        for fam in ("F", "LB"):
            test = FC.make_test(fam, alpha, "predictive").calibrate(held, window=FC.WINDOW)
            rate = FC.decision_rate(test, resid)
            assert lo <= rate <= hi, (records, alpha, fam, rate, (lo, hi))
            law = test.thresholds_[0]
            assert law.records_ == records and law.record_law_["df"] == records - 1
            # windows of one record are not independent evidence of a new record's law (the F test's noise levels
            # differ between records; the Ljung-Box anchors' between-record spread may be estimated as none)
            assert law.effective_windows_ <= law.independent_
            assert fam == "LB" or law.effective_windows_ < law.independent_
        old_f.append(FC.decision_rate(FC.make_test("F", alpha, "bootstrap").calibrate(held, window=FC.WINDOW), resid)
                     > hi)
    assert any(old_f)                       # the previous calibration leaves the band on this fleet


def test_thresholds_widen_as_records_get_fewer(fleet):
    fit, _ = fleet
    thr = {}
    for records in (5, 10, 20):
        held = tsfdi.VAR(fit[:records], 2).held_out_residuals()
        test = tsfdi.FTest(alpha=1e-2, correction="sidak").calibrate(held, window=FC.WINDOW)
        thr[records] = test.threshold_
        assert test.threshold_.min() > 1.0
    assert np.all(thr[5] > thr[10]) and np.all(thr[10] > thr[20]), thr


def test_too_few_records_are_refused_with_what_is_needed(fleet):
    fit, _ = fleet
    assert [records_needed(a) for a in (1e-2, 1e-3, 1e-4)] == [3, 4, 5]
    held = tsfdi.VAR(fit[:3], 2).held_out_residuals()
    with pytest.raises(ValueError, match=r"channel 'y0': statistic comes from 3 records, at least 4 are needed for "
                                         r"false_alarm=0\.001.*more healthy records.*min_records"):
        tsfdi.LjungBox(lags=20, alpha=1e-3, correction="none").calibrate(held, window=FC.WINDOW)
    ok = tsfdi.LjungBox(lags=20, alpha=1e-3, correction="none",
                        threshold=ScaledChi2Threshold(1e-3, min_records=3))
    assert ok.calibrate(held, window=FC.WINDOW).thresholds_[0].records_ == 3
    with pytest.raises(ValueError, match="record_effect must be one of 'predictive', 'bootstrap'"):
        ScaledChi2Threshold(1e-3, record_effect="plugin")


def test_f_law_pools_the_shape_ljung_box_keeps_each_records(fleet):
    # a variance ratio's records differ by their noise level only (a change of scale): one shape for all; the
    # Ljung-Box Q of mismatched dynamics differs in shape too (pooled, its fleet rate was 1.6-1.8 alpha at 0.01)
    fit, _ = fleet
    held = tsfdi.VAR(fit[:10], 2).held_out_residuals()
    f = tsfdi.FTest(alpha=1e-2).calibrate(held, window=FC.WINDOW).thresholds_
    assert all(t.shape == "pooled" and np.ptp(t.df_) == 0 for t in f)
    lb = tsfdi.LjungBox(lags=20, alpha=1e-2).calibrate(held, window=FC.WINDOW).thresholds_
    assert all(t.shape == "record" and np.ptp(t.df_) > 0 for t in lb)
    own = tsfdi.FTest(alpha=1e-2, correction="none", threshold=ScaledChi2Threshold(1e-2, shape="record"))
    assert np.ptp(own.calibrate(held, window=FC.WINDOW).thresholds_[0].df_) > 0      # an explicit choice is kept
    with pytest.raises(ValueError, match="shape must be one of 'record', 'pooled', got 'scale'"):
        ScaledChi2Threshold(1e-2, shape="scale")


def test_pvalue_agrees_with_the_threshold(fleet):
    fit, _ = fleet
    held = tsfdi.VAR(fit[:10], 2).held_out_residuals()
    test = tsfdi.LjungBox(lags=20, alpha=1e-2, correction="none").calibrate(held, window=FC.WINDOW)
    thr = test.threshold_
    _, pv = test.threshold_pvalue(np.vstack([thr * 0.999, thr, thr * 1.001, thr * 100]), 198)
    assert np.all(pv[0] > 1e-2) and np.allclose(pv[1], 1e-2) and np.all(pv[2] < 1e-2)
    assert np.all(pv[3] < 1e-6) and np.all(np.diff(pv, axis=0) <= 0)
    d = tsfdi.detect(fit[0][:200], tsfdi.VAR(fit[:10], 2).fit(), test)
    assert d.details["calibration_records"] == 10 and len(d.details["record_law"]) == 3


def test_overlapping_windows_give_the_spread_of_disjoint_ones():
    # white noise: the Ljung-Box Q of every sliding window (overlapping) of 100 records of 10 windows each; the
    # variance of a record's overlapping windows about their own mean misses the variance of that mean (a mean of 10
    # independent windows), so the fitted law was ~7 % too light (df too large, a liberal threshold on new records)
    rng = np.random.default_rng(31)
    n, recs = 198, [rng.standard_normal((10 * 198, 1)) for _ in range(100)]
    lb = tsfdi.LjungBox(lags=20, alpha=1e-2)
    stat = np.concatenate([lb.window_statistic(r, n, 1)[:, 0] for r in recs])
    groups = np.repeat(np.arange(len(recs)), 10 * n - n + 1)
    law = ScaledChi2Threshold(1e-2).calibrate(stat, independent=[10] * len(recs), groups=groups)
    disjoint = np.concatenate([lb.window_statistic(r, n, n)[:, 0] for r in recs])
    cv2 = disjoint.var(ddof=1) / disjoint.mean() ** 2          # 2 / nu of the disjoint windows, the truth
    assert abs(np.mean(2.0 / law.df_) / cv2 - 1.0) < 0.03, (np.mean(2.0 / law.df_), cv2)


def fleet_rates(seed: int, fleets: int, records: int, alpha: float, family: str, new: int = 20) -> np.ndarray:
    """The decision's rate on ``new`` new records of each of ``fleets`` small simulated fleets (seeds ``seed``,
    ``seed + 1``, ...), the baseline fitted on ``records`` records of the fleet."""
    rates = []
    for f in range(fleets):
        rng = np.random.default_rng(seed + f)
        (fit, _), (fresh, _) = FC.fleet_records(rng, records), FC.fleet_records(rng, new)
        spec = tsfdi.VAR(fit, 2)
        base = spec.fit()
        test = FC.make_test(family, alpha, "predictive").calibrate(spec.held_out_residuals(), window=FC.WINDOW)
        rates.append(FC.decision_rate(test, [np.asarray(base.residuals(x)) for x in fresh]))
    return np.array(rates)


@pytest.mark.slow
@pytest.mark.parametrize("family", ["LB", "F"])
def test_rate_averaged_over_many_small_fleets(family):
    # 60 fleets (seeds 8000-8059, used for nothing else), 10 fitting records, 20 new records each (200 windows):
    # the rate of one fleet varies from fleet to fleet far beyond the binomial (its calibration records are a sample
    # of the fleet), so alpha must lie in the 99.9 % interval of the mean rate over the independent fleets
    rates = fleet_rates(8000, 60, 10, 1e-2, family)
    half = stats.t.isf(5e-4, rates.size - 1) * rates.std(ddof=1) / np.sqrt(rates.size)
    assert abs(rates.mean() - 1e-2) <= half, (rates.mean(), half)
    lo, hi = band(200 * rates.size, 1e-2)
    assert rates.mean() <= 2 * hi, (rates.mean(), hi)     # and never far above the pooled binomial band


def ideal_expected_rate(records: int, false_alarm: float, fleets: int, seed: int, tau: float = 0.3) -> tuple:
    """The ideal case where the answer is known: white-noise records (10 disjoint windows of 198 samples each) whose
    log variance is ``N(0, tau^2)`` from record to record, the F variance ratio against the true reference variance 1.
    The expected rate of the predictive threshold on a new record, over ``fleets`` fleets of ``records`` records:
    each fleet's rate exact (Gauss-Hermite over the new record's variance), its mean taken with the exact Student t
    pivot on the fleet's true log variances (expected rate exactly ``false_alarm``) as control variate. Returns the
    mean rate / ``false_alarm`` and its standard error."""
    from scipy import special

    n, w = 198, 10
    xh, wh = np.polynomial.hermite_e.hermegauss(80)
    wh = wh / wh.sum()
    q = stats.t.isf(false_alarm, records - 1) * np.sqrt(1 + 1 / records)
    rng = np.random.default_rng(seed)
    y, c = [], []
    for _ in range(fleets):
        x = tau * rng.standard_normal(records)
        e = rng.standard_normal((records, w, n)) * np.exp(x / 2)[:, None, None]
        s = np.mean(e * e, axis=2).ravel()
        law = ScaledChi2Threshold(false_alarm, shape="pooled").calibrate(s, independent=[w] * records,
                                                                        groups=np.repeat(np.arange(records), w))
        y.append(float(special.chdtrc(n, law.threshold_ * n / np.exp(tau * xh)) @ wh) / false_alarm)
        c.append(stats.norm.sf((x.mean() + q * x.std(ddof=1)) / tau) / false_alarm)
    y, c = np.array(y), np.array(c)
    adj = y - np.cov(y, c)[0, 1] / c.var(ddof=1) * (c - 1.0)
    return adj.mean(), adj.std(ddof=1) / np.sqrt(fleets)


def test_predictive_f_law_holds_its_rate_where_the_answer_is_known():
    # each record's own degrees of freedom from its ~10 windows made the anchors spread and the tails mix too wide:
    # 0.87 false_alarm at 20 records (the simulated fleet's calibrated F test was conservative for that reason);
    # one shape pooled over the records (the record effect is a scale) gives the exact rate
    pf = 1 - (1 - 1e-2) ** (1 / 3)
    rate, se = ideal_expected_rate(20, pf, 300, seed=3107)
    assert abs(rate - 1.0) < 0.08, (rate, se)


def test_record_pvalue_is_the_t_pivot_of_the_record_levels():
    """A new record with as many windows as a fitting record: its level (log mean statistic) has, under the
    predictive record law, the p-value of the Student t pivot of the fitting records' levels,
    (l - mean) / (s sqrt(1 + 1/J)) ~ t(J - 1), upper tail, computed here by hand (the between-record spread far
    above the levels' sampling noise, where the posterior average is the t law); the bound at a level is the record
    level whose p-value it is."""
    rng = np.random.default_rng(5)
    j, per, nu = 8, 40, 150.0
    level = np.exp(0.5 * rng.standard_normal(j + 1))
    stat = [lev * rng.chisquare(nu, per) / nu for lev in level]
    th = ScaledChi2Threshold(0.01, shape="pooled").calibrate(np.concatenate(stat[:j]), independent=[per] * j,
                                                             groups=np.repeat(np.arange(j), per))
    levels = np.log([s.mean() for s in stat[:j]])
    np.testing.assert_allclose(th.levels_, levels, rtol=1e-12)
    new = stat[j]
    a = np.log(new.mean())
    t = (a - levels.mean()) / (levels.std(ddof=1) * np.sqrt(1 + 1 / j))
    lev, z, p = th.record_pvalue(new)
    assert lev == pytest.approx(a, rel=1e-12)
    assert p == pytest.approx(stats.t.sf(t, j - 1), rel=1e-3)
    assert th.record_bound(p, per) == pytest.approx(a, rel=1e-3, abs=1e-4)
    # a record far above the law: p below any usual level; far below: p near 1 (one-sided)
    assert th.record_pvalue(new * np.exp(3.0))[2] < 1e-4
    assert th.record_pvalue(new * np.exp(-3.0))[2] > 1 - 1e-3


def test_record_pvalue_refuses_what_it_cannot_judge():
    rng = np.random.default_rng(6)
    stat = rng.chisquare(20, 120)
    boot = ScaledChi2Threshold(0.01, record_effect="bootstrap").calibrate(stat, independent=[40] * 3,
                                                                          groups=np.repeat([0, 1, 2], 40))
    with pytest.raises(ValueError, match="record law"):
        boot.record_pvalue(stat[:10])
    with pytest.raises(ValueError, match="record law"):
        boot.record_bound(0.01, 10)
    th = ScaledChi2Threshold(0.01).calibrate(stat, independent=[40] * 3, groups=np.repeat([0, 1, 2], 40))
    with pytest.raises(ValueError, match="at least 3"):
        th.record_pvalue(stat[:2])
    with pytest.raises(ValueError, match="at least 3"):
        th.record_pvalue(stat[:10], independent=2)
    with pytest.raises(ValueError, match="non-negative"):
        th.record_pvalue(-stat[:10])
    with pytest.raises(ValueError, match="not calibrated"):
        ScaledChi2Threshold(0.01).record_pvalue(stat)


def test_ljung_box_with_five_records_holds_its_rate_on_white_noise():
    """The Ljung-Box test (20 lags, one channel, alpha 0.01) calibrated with the predictive record law on 5 records of
    plain white noise (10 disjoint windows of 198 samples each; no record effect at all), 300 calibrations: the mean
    of their exact rates on new white noise (each threshold's tail in 400,000 windows of white noise) must lie in
    the 99.9 % binomial band of 15,000 windows (a tolerance wider than the Monte Carlo noise, narrower than the bias
    it catches). It was ~0.6 alpha: the anchors' spread (a record's shape from ~10 windows) was read as a
    between-record spread from 4 degrees of freedom, and the scaled chi-square's tail is too light for the
    portmanteau statistic (which hid that at 20 records)."""
    rng = np.random.default_rng(3131)
    n, alpha = 198, 1e-2
    lb = tsfdi.LjungBox(lags=20, alpha=alpha, correction="none")
    null = np.sort(np.concatenate([np.asarray(lb.window_statistic(rng.standard_normal((n * 20_000, 1)), n, n))[:, 0]
                                   for _ in range(20)]))
    rates = []
    for _ in range(300):
        fit = [rng.standard_normal((10 * n, 1)) for _ in range(5)]
        thr = lb.calibrate(fit, window=n).threshold_[0]
        rates.append(1.0 - np.searchsorted(null, thr, side="right") / null.size)
    lo, hi = band(15_000, alpha)
    assert lo <= np.mean(rates) <= hi, (np.mean(rates) / alpha, (lo, hi))


def short_fleet_rate(family: str, seed: int, fleets: int = 300, records: int = 4, alpha: float = 1e-2) -> tuple:
    """Records too short for a law of their own (2.3 windows of 190 samples each, so 2 independent windows: a
    CrazyPAD flight's segment at 2 s windows), ``records`` of them per fleet, the statistic on every overlapping
    window (step 1) calibrated with the predictive law; the rate on the disjoint windows of 4 new records of the
    same fleet (10 windows each), pooled over ``fleets`` fleets. ``"LB"``: Ljung-Box (20 lags) of AR(1) records
    whose coefficient varies between records (N(0, 0.1^2): mismatched dynamics); ``"F"``: the mean square of white
    noise whose log variance varies between records (N(0, 0.3^2)). Returns (flagged, windows)."""
    from scipy import signal

    n, rng = 190, np.random.default_rng(seed)
    lb = tsfdi.LjungBox(lags=20, alpha=alpha)
    spread = 0.1 if family == "LB" else 0.3

    def record(m, effect):
        e = rng.standard_normal(m + 50)
        return signal.lfilter([1.0], [1.0, -effect], e)[50:, None] if family == "LB" else \
            e[50:, None] * np.exp(effect / 2)

    def windows(x, step):
        if family == "LB":
            return np.asarray(lb.window_statistic(x, n, step))[:, 0]
        c = np.cumsum(np.r_[0.0, x[:, 0] ** 2])
        return ((c[n:] - c[:-n]) / n)[::step]

    flagged = total = 0
    for _ in range(fleets):
        fit = [windows(record(int(2.3 * n), a), 1) for a in spread * rng.standard_normal(records)]
        law = ScaledChi2Threshold(alpha, min_windows=5, min_records=2).calibrate(
            np.concatenate(fit), independent=[2] * records, groups=np.repeat(np.arange(records), [p.size for p in fit]))
        assert law.pooled_ and law.record_law_ is None
        new = np.concatenate([windows(record(10 * n, a), n) for a in spread * rng.standard_normal(4)])
        flagged += int((new > law.threshold_).sum())
        total += new.size
    return flagged, total


@pytest.mark.parametrize("family", ["LB", "F"])
def test_records_too_short_for_their_own_law_hold_their_rate(family):
    """Records of 2 independent windows (fewer than MIN_RECORD_WINDOWS) cannot show their own spread. They were pooled
    into one scaled chi-square fitted by its moments to the 8 windows of 4 records (plug-in: a shape from 8 windows,
    the overlap of the windows uncorrected) with a bootstrap bound over the records: on new records 2.9 (LB) and 5.7
    (F) alpha on development seeds, 2.5 / 5.6 alpha here. The predictive law of a new record's window (the log
    statistic a one-way random effect, a Student t with the Satterthwaite degrees of freedom) keeps the rate in the
    99.9 % binomial band of the 12,000 new windows or below it: 0.58 (LB) and 1.17 (F) alpha here, 0.78 +- 0.14 and
    0.99 +- 0.18 on development seeds (the log of a Ljung-Box Q is a little left-skewed: its normal law's tail, with
    the law known, is 0.76 alpha; and 8 windows leave the t few degrees of freedom). Not above: the honest side."""
    flagged, total = short_fleet_rate(family, 3601)
    lo, hi = band(total, 1e-2)
    assert 0.25 * 1e-2 <= flagged / total <= hi, (family, flagged / total / 1e-2, (lo / 1e-2, hi / 1e-2))


def test_short_records_law_is_what_the_test_calibrates_and_its_pvalue_agrees():
    """LjungBox.calibrate on segments of 2 windows (step 1) takes the short-record law: its threshold is the Student t
    quantile of the log statistic, the p-value is alpha there and falls with the statistic; too few records for
    the alpha are refused as for the record law."""
    rng = np.random.default_rng(3602)
    recs = [rng.standard_normal((440, 2)) for _ in range(6)]
    test = tsfdi.LjungBox(lags=20, alpha=1e-2, correction="none",
                          threshold=ScaledChi2Threshold(1e-2, min_windows=5)).calibrate(recs, window=200, step=1)
    th = test.thresholds_[0]
    assert th.pooled_ and th.record_law_ is None and th.records_ == 6 and th.independent_ == 12
    stat = [np.log(np.asarray(test.window_statistic(r, 200, 1))[:, 0]) for r in recs]
    lev = np.array([s.mean() for s in stat])
    var = (1 + 1 / 6) * lev.var(ddof=1) + np.mean([np.square(s - m).mean() for s, m in zip(stat, lev)])
    assert th.point_threshold_ < th.threshold_
    assert np.log(th.threshold_) == pytest.approx(lev.mean() + stats.t.isf(1e-2, th.effective_windows_ - 1)
                                                  * np.sqrt(var), rel=1e-10)
    thr = test.threshold_
    _, pv = test.threshold_pvalue(np.vstack([thr * 0.999, thr, thr * 1.001, thr * 100, np.full(2, np.inf)]), 200)
    assert np.all(pv[0] > 1e-2) and np.allclose(pv[1], 1e-2) and np.all(pv[2] < 1e-2) and np.all(pv[4] == 0)
    assert np.all(np.diff(pv, axis=0) <= 0)
    with pytest.raises(ValueError, match=r"channel 'y0': statistic comes from 3 records, at least 4 are needed"):
        tsfdi.LjungBox(lags=20, alpha=1e-3, correction="none", threshold=ScaledChi2Threshold(1e-3, min_windows=5)
                       ).calibrate(recs[:3], window=200, step=1)

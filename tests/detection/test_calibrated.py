"""Data-driven thresholds of the residual tests (LjungBox / FTest ``threshold="empirical"``, paper 002 Fig. 2)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy import signal as sps
from scipy import special, stats

import tsfdi
from tsfdi.detection import EmpiricalThreshold, FTest, LjungBox, ljungbox_windows


def ar2(n: int, rng: np.random.Generator) -> np.ndarray:
    """AR(2) y[t] - 1.2 y[t-1] + 0.5 y[t-2] = e[t]."""
    return sps.lfilter([1.0], [1.0, -1.2, 0.5], rng.standard_normal(n + 200))[200:]


@pytest.fixture(scope="module")
def misspecified():
    """An AR(1) baseline fitted on 300 samples of an AR(2) process: the residuals of new data are correlated, so
    the chi-square threshold of the Ljung-Box test is badly wrong."""
    rng = np.random.default_rng(11)
    res = tsfdi.AR(ar2(300, rng), 1).fit()
    calib = np.asarray(res.residuals(ar2(4000 * 200, rng)))
    fresh = np.asarray(res.residuals(ar2(4000 * 200, rng)))
    return res, calib, fresh


def test_ljungbox_false_alarm_monte_carlo(misspecified):
    _, calib, fresh = misspecified
    alpha, lags, window = 0.05, 10, 199
    chi2 = LjungBox(lags, alpha)
    emp = LjungBox(lags, alpha, threshold="empirical").calibrate(calib, window=window, step=window)
    n = calib.shape[0] // window                                      # 4020 independent windows
    assert emp.calibration_[0].size == n and emp.thresholds_[0].method_ == "empirical"
    q = ljungbox_windows(fresh, lags, window, window)[:, 0]
    fa_chi2 = np.mean(q > chi2.test(fresh[:window]).threshold[0])
    fa_emp = np.mean(q > emp.threshold_[0])
    assert fa_chi2 > 0.5                                              # chi-square(10) threshold badly wrong
    # binomial tolerance: fresh-sample and calibration-quantile errors, each sd sqrt(a(1-a)/4000) = 0.0034
    assert abs(fa_emp - alpha) < 4 * np.sqrt(2 * alpha * (1 - alpha) / n)
    # per-window decisions agree with the vectorised statistic
    d = emp.test(fresh[:window])
    assert d.statistic[0] == pytest.approx(q[0], rel=1e-9)
    assert d.reject == (q[0] > emp.threshold_[0])


def test_ftest_false_alarm_monte_carlo():
    """Heavy-tailed innovations (Student t, 5 df): the window variance spreads more than the F law of eq. 9
    assumes; the calibrated threshold keeps the false-alarm rate at alpha."""
    rng = np.random.default_rng(12)

    def heavy(n):
        return sps.lfilter([1.0], [1.0, -1.2, 0.5], rng.standard_t(5, n + 200))[200:]

    res = tsfdi.AR(heavy(2000), 2).fit()
    alpha, window, n = 0.05, 198, 4000
    calib = np.asarray(res.residuals(heavy(n * window + 2)))
    fresh = np.asarray(res.residuals(heavy(n * window + 2)))
    ref = FTest(alpha).reference(res)
    f = FTest(alpha, threshold="empirical").calibrate(calib, window=window, step=window, **ref)
    stat = f.window_statistic(fresh, window, window, **ref)[:, 0]
    fa_f = np.mean(stat > FTest(alpha).test(fresh[:window], **ref).threshold[0])
    fa_emp = np.mean(stat > f.threshold_[0])
    assert fa_f > 2 * alpha                                           # F(N_u, N_0 - d) law does not hold
    assert abs(fa_emp - alpha) < 4 * np.sqrt(2 * alpha * (1 - alpha) / n)
    d = f.test(fresh[:window], **ref)
    assert d.statistic[0] == pytest.approx(stat[0], rel=1e-9)


def test_small_baseline_correct_model_monte_carlo():
    """A correctly specified AR(2) baseline fitted on only 100 samples: E[Q] ~ r + p N_u / N_0 inflates the
    chi-square false-alarm rate; the calibrated threshold restores alpha."""
    rng = np.random.default_rng(3)
    res = tsfdi.AR(ar2(100, rng), 2).fit()
    alpha, lags, window = 0.05, 10, 400
    calib = np.asarray(res.residuals(ar2(3000 * window, rng)))
    fresh = np.asarray(res.residuals(ar2(3000 * window, rng)))
    emp = LjungBox(lags, alpha, threshold="empirical").calibrate(calib, window=window, step=window)
    q = ljungbox_windows(fresh, lags, window, window)[:, 0]
    fa_chi2 = np.mean(q > special.chdtri(lags, alpha))
    fa_emp = np.mean(q > emp.threshold_[0])
    assert fa_chi2 > 2 * alpha
    assert abs(fa_emp - alpha) < 4 * np.sqrt(2 * alpha * (1 - alpha) / 3000)


def test_decision_reports_empirical_threshold_and_pvalue():
    rng = np.random.default_rng(0)
    stat = rng.chisquare(5, size=(3000, 2))
    lb = LjungBox(5, 0.01, correction="none", threshold="empirical").calibrate(statistic=stat)
    np.testing.assert_allclose(lb.threshold_, np.quantile(stat, 0.99, axis=0))
    x = rng.standard_normal((300, 2))
    d = lb.test(x)
    np.testing.assert_array_equal(d.threshold, lb.threshold_)
    ref_p = [(1 + np.sum(stat[:, c] >= d.statistic[c])) / (3000 + 1) for c in range(2)]
    np.testing.assert_allclose(d.pvalue, ref_p)
    assert d.details["threshold_method"] == "empirical" and d.details["calibration_size"] == 3000
    np.testing.assert_array_equal(d.channel_reject, d.statistic > lb.threshold_)
    # the p-value of a statistic above every calibration value is 1 / (n + 1)
    assert lb.calibrated_pvalue(np.array([1e9, 1e9]))[0] == pytest.approx(1 / 3001)
    # distributional (chi-square, F) thresholds say so too, under one name
    assert LjungBox(5, 0.01).test(x).details["threshold_method"] == "theoretical"
    assert FTest(0.01).test(x, reference_variance=1.0, reference_df=100).details["threshold_method"] == "theoretical"
    assert FTest(0.01, alternative="two-sided").test(x, reference_variance=1.0,
                                                     reference_df=100).details["threshold_method"] == "theoretical"
    # Bonferroni: each channel calibrated at alpha / k
    lbb = LjungBox(5, 0.02, threshold="empirical", correction="bonferroni").calibrate(statistic=stat)
    np.testing.assert_allclose(lbb.threshold_, np.quantile(stat, 0.99, axis=0))
    # an EmpiricalThreshold sets the tail options: GPD tail below min_exceedances / alpha samples
    gpd = LjungBox(5, 0.001, threshold=EmpiricalThreshold(0.001)).calibrate(statistic=stat)
    assert [t.method_ for t in gpd.thresholds_] == ["gpd", "gpd"]
    assert "calibrated on 3000" in repr(gpd)


def test_multivariate_calibrated():
    rng = np.random.default_rng(1)
    recs = [rng.standard_normal((600, 2)) for _ in range(4)]
    lb = LjungBox(3, 0.05, multivariate="hosking", threshold="empirical").calibrate(recs, window=100, step=5)
    ref = LjungBox(3, 0.05, multivariate="hosking")
    assert lb.calibration_[0].size == 4 * 101
    assert lb.calibration_[0][0] == pytest.approx(min(ref.test(r[a:a + 100]).statistic[0] for r in recs
                                                       for a in range(0, 501, 5)))
    d = lb.test(recs[0][:100])
    assert d.channels == ("joint",) and d.threshold[0] == lb.threshold_[0]


@pytest.mark.parametrize("kind", ["numpy", "pandas", "xarray"])
def test_data_kinds(kind):
    rng = np.random.default_rng(2)
    recs = [rng.standard_normal((500, 2)) for _ in range(5)]
    wrap = {"numpy": lambda a: a, "pandas": lambda a: pd.DataFrame(a, columns=["p", "q"]),
            "xarray": lambda a: xr.DataArray(a, dims=("time", "channel"))}[kind]
    lb = LjungBox(4, 0.05, correction="none", threshold="empirical").calibrate([wrap(r) for r in recs], window=50,
                                                                            step=2)
    ref = LjungBox(4, 0.05, correction="none", threshold="empirical").calibrate(recs, window=50, step=2)
    np.testing.assert_allclose(lb.threshold_, ref.threshold_)
    d = lb.test(wrap(recs[0][:50]))
    np.testing.assert_allclose(d.statistic, ref.test(recs[0][:50]).statistic)
    f = FTest(0.05, correction="none", threshold="empirical").calibrate([wrap(r) for r in recs], window=50, step=2,
                                                     reference_variance=[1.0, 1.0])
    fr = FTest(0.05, correction="none", threshold="empirical").calibrate(recs, window=50, step=2,
                                                                         reference_variance=1.0)
    np.testing.assert_allclose(f.threshold_, fr.threshold_)
    # calibrating from precomputed statistics of any kind
    st = ljungbox_windows(recs[0], 4, 50, 1)
    a = LjungBox(4, 0.05, correction="none", threshold="empirical").calibrate(statistic=wrap(st)).threshold_
    np.testing.assert_allclose(a, np.quantile(st, 0.95, axis=0))


def test_public_rules_per_model_tests():
    """The public rules an engine applies to all windows at once (window_statistic + threshold_pvalue) equal the
    per-window decisions of each model's calibrated test."""
    rng = np.random.default_rng(4)
    y = ar2(3000, rng)
    models = {"a": tsfdi.AR(y[:1500], 2).fit(), "b": tsfdi.AR(y[1500:], 3).fit()}
    x = ar2(1000, rng)
    for name, res in models.items():
        n = 200 - res.lags
        test = LjungBox(6, 0.05, threshold="empirical").calibrate(np.asarray(res.residuals(ar2(20000, rng))),
                                                                  window=n, step=3)
        e = np.asarray(res.residuals(x)).reshape(-1, 1)
        stat = test.window_statistic(e, n, 50)
        thr, pv = test.threshold_pvalue(stat, n)
        np.testing.assert_array_equal(thr, test.threshold_)
        for w in range(stat.shape[0]):
            d = test.test(e[50 * w:50 * w + n])
            assert stat[w, 0] == pytest.approx(d.statistic[0], rel=1e-8)
            assert pv[w, 0] == pytest.approx(d.pvalue[0])
            assert (stat[w] > thr).any() == d.reject
            d2 = test.decision(d.statistic, n, d.channels)
            np.testing.assert_array_equal(d2.pvalue, d.pvalue)
            assert d2.details == d.details and d2.reject == d.reject


@pytest.mark.parametrize("demean", [False, True])
def test_ftest_public_rules_equal_test(demean):
    """FTest.threshold_pvalue / null_threshold / decision on a window's F give exactly what test() gives."""
    rng = np.random.default_rng(6)
    x = rng.standard_normal((400, 2)) * [1.0, 1.3]
    ref = {"reference_variance": np.array([1.0, 1.1]), "reference_df": np.array([500.0, 480.0])}
    for corr in ("none", "bonferroni"):
        ft = FTest(0.05, demean=demean, correction=corr)
        d = ft.test(x[100:300], **ref)
        stat = ft.window_statistic(x, 200, 100, **ref)
        np.testing.assert_allclose(stat[1], d.statistic, rtol=1e-10)
        thr, pv = ft.threshold_pvalue(stat, 200, **ref)
        np.testing.assert_array_equal(thr, d.threshold)
        np.testing.assert_allclose(pv[1], d.pvalue, rtol=1e-8)
        thr1, pv1 = ft.threshold_pvalue(d.statistic, 200, **ref)
        np.testing.assert_array_equal(thr1, d.threshold)
        np.testing.assert_array_equal(pv1, d.pvalue)
        np.testing.assert_array_equal(ft.null_threshold(2, 200, **ref), d.threshold)
        nu = 199 if demean else 200
        a = d.details["channel_alpha"]
        np.testing.assert_allclose(d.threshold, special.fdtri(nu, ref["reference_df"], 1 - a))
        d2 = ft.decision(d.statistic, 200, d.channels, details={"variance": d.details["variance"]}, **ref)
        for f in ("statistic", "threshold", "pvalue", "df", "channel_reject"):
            np.testing.assert_array_equal(getattr(d2, f), getattr(d, f))
        assert list(d2.details) == list(d.details) and d2.test == "FTest" and d2.reject == d.reject
        # two-sided: decision carries the lower limit as test() does
        f2 = FTest(0.05, demean=demean, correction=corr, alternative="two-sided")
        dt = f2.test(x[100:300], **ref)
        dt2 = f2.decision(dt.statistic, 200, dt.channels, details={"variance": dt.details["variance"]}, **ref)
        np.testing.assert_array_equal(dt2.pvalue, dt.pvalue)
        np.testing.assert_array_equal(dt2.details["lower_threshold"], dt.details["lower_threshold"])
        assert list(dt2.details) == list(dt.details)
    # empirical: the calibrated threshold and the empirical p-value, nobs and reference_df not needed
    fe = FTest(0.05, threshold="empirical").calibrate(rng.standard_normal((20000, 2)), window=200, step=10,
                                                      reference_variance=1.0)
    de = fe.test(x[:200], **ref)
    thr, pv = fe.threshold_pvalue(de.statistic)
    np.testing.assert_array_equal(thr, de.threshold)
    np.testing.assert_array_equal(pv, de.pvalue)
    with pytest.raises(TypeError, match="nobs"):
        FTest(0.05).threshold_pvalue(de.statistic, reference_df=100)
    with pytest.raises(TypeError, match="reference_df"):
        FTest(0.05).null_threshold(2, 200)


def test_bad_input():
    rng = np.random.default_rng(5)
    with pytest.raises(ValueError, match="at least 2000 are needed"):
        LjungBox(5, 1e-3, threshold="empirical").calibrate(statistic=rng.chisquare(5, 500))
    with pytest.raises(ValueError, match="not calibrated"):
        LjungBox(5, 0.05, threshold="empirical").test(rng.standard_normal(100))
    # calibrating a theoretical test fits the scaled chi-square law: chi2(5) data give back about chi2(5)
    lb = LjungBox(5, 0.05).calibrate(statistic=rng.chisquare(5, 5000))
    assert lb.threshold == "calibrated" and lb.threshold_[0] == pytest.approx(stats.chi2.ppf(0.95, 5), rel=0.03)
    with pytest.raises(ValueError, match="at least 30 are needed"):
        LjungBox(5, 0.05).calibrate(statistic=rng.chisquare(5, 29))
    with pytest.raises(ValueError, match="false_alarm"):
        LjungBox(5, 0.05, threshold=EmpiricalThreshold(0.01))
    with pytest.raises(TypeError, match="threshold"):
        LjungBox(5, 0.05, threshold=3.0)
    with pytest.raises(ValueError, match="threshold"):
        FTest(0.05, threshold="chi2")
    for old in ("chi2", "f", "analytical"):       # one name for the distributional threshold: "theoretical"
        with pytest.raises(ValueError, match="threshold must be one of 'theoretical', 'calibrated', 'empirical'"):
            LjungBox(5, 0.05, threshold=old)
        with pytest.raises(ValueError, match="threshold must be one of 'theoretical', 'calibrated', 'empirical'"):
            FTest(0.05, threshold=old)
    assert LjungBox(5, 0.05, threshold="theoretical").threshold == "theoretical"
    assert FTest(0.05, threshold="THEORETICAL").threshold == "theoretical"
    with pytest.raises(ValueError, match="alternative='greater'"):
        FTest(0.05, alternative="two-sided", threshold="empirical")
    lb = LjungBox(5, 0.05, threshold="empirical").calibrate(statistic=rng.chisquare(5, (5000, 2)))
    with pytest.raises(ValueError, match="calibrated on 2"):
        lb.test(rng.standard_normal((100, 3)))
    with pytest.raises(TypeError, match="window"):
        LjungBox(5, 0.05, threshold="empirical").calibrate(rng.standard_normal(500))
    with pytest.raises(TypeError, match="needs resid"):
        LjungBox(5, 0.05, threshold="empirical").calibrate()
    # without a baseline variance the F test divides by the pooled mean square of its calibration residuals
    e = 2.0 * rng.standard_normal(2000)
    f = FTest(0.05).calibrate(e, window=50)
    assert f.reference_variance_[0] == pytest.approx(np.mean(e * e)) and f.threshold == "calibrated"
    with pytest.raises(ValueError, match="alternative='greater'"):
        FTest(0.05, alternative="two-sided").calibrate(e, window=50)
    with pytest.raises(ValueError, match="window"):
        LjungBox(5, 0.05, threshold="empirical").calibrate(rng.standard_normal(500), window=4)


def test_calibrated_threshold_refuses_another_window_length():
    """Issue 29: a test calibrated with window=100 on held-out residuals, applied by detect to a 5,000-sample record,
    returned a decision silently; its threshold holds for 100-sample windows only, so it refuses and says what to
    do (identify_windows / Monitor with that window, or calibrate at the tested length)."""
    rng = np.random.default_rng(29)
    recs = [ar2(2000, rng) for _ in range(6)]
    spec = tsfdi.AR(recs, 2)
    base = spec.fit()
    for test in (LjungBox(10, 0.01), FTest(0.01), tsfdi.MeanTest(0.01)):
        test.calibrate(spec.held_out_residuals(), window=100)
        assert test.calibration_window_ == (98, 2)
        assert tsfdi.detect(ar2(100, rng), base, test).details["threshold_method"] == "calibrated"
        with pytest.raises(ValueError, match=r"calibrated on windows of 98 residual samples.*window=100.*"
                                             r"identify_windows.*Monitor.*window=5000"):
            tsfdi.detect(ar2(5000, rng), base, test)
        # the windowed engine applies it to windows of the calibrated length, and refuses another length
        assert len(tsfdi.identify_windows(ar2(1000, rng), {"h": base}, test, window=100, step=50)) == 19
        with pytest.raises(ValueError, match="calibrated on windows of 98"):
            tsfdi.identify_windows(ar2(1000, rng), {"h": base}, test, window=200)
    # a null sample given as statistics: the window is known only when given
    q = ljungbox_windows(ar2(20000, rng), 10, 50, 50)
    free = LjungBox(10, 0.01).calibrate(statistic=q)
    assert free.calibration_window_ is None and free.test(ar2(300, rng)).statistic.size == 1
    bound = LjungBox(10, 0.01).calibrate(statistic=q, window=50)
    assert bound.test(ar2(50, rng)).statistic.size == 1
    with pytest.raises(ValueError, match="calibrated on windows of 50 residual samples"):
        bound.test(ar2(300, rng))


def test_every_calibrated_test_refuses_a_frozen_stretch_in_healthy_records():
    """Issue 29: FTest / MeanTest.calibrate accepted healthy records with a frozen stretch (LjungBox refused): one
    rule for all, naming the record, the channel and where the stretch is; a stretch shorter than a window passes."""
    rng = np.random.default_rng(31)
    recs = [pd.DataFrame(rng.standard_normal((1000, 2)), columns=["roll", "pitch"]) for _ in range(4)]
    recs[2].iloc[300:400, 1] = 0.25
    for test in (LjungBox(5, 0.01), FTest(0.01), tsfdi.MeanTest(0.01)):
        with pytest.raises(ValueError, match=r"resid\[2\] holds a constant stretch \(a frozen sensor\) of 100 "
                                             r"samples in channel 'pitch' at samples \[300, 400\).*window \(100"):
            test.calibrate(recs, window=100)
        with pytest.raises(ValueError, match=r"^resid holds a constant stretch"):
            test.calibrate(recs[2], window=50)
        assert test.calibrate(recs, window=101).calibrated              # 100 samples: shorter than a window


def test_calibration_errors_name_the_channel_and_the_fix():
    """Issue 29: the calibration error named internal words ("statistic", "channel 0") and not min_windows; it names
    the records, the bound and how to lower it (ScaledChi2Threshold(min_windows=...), the CLI's --min-windows), and
    a per-channel failure names the channel."""
    rng = np.random.default_rng(32)
    recs = [pd.DataFrame(rng.standard_normal((1000, 2)), columns=["roll", "pitch"]) for _ in range(3)]
    with pytest.raises(ValueError, match=r"^resid \(the healthy records, windows of 101 residual samples\) holds 27 "
                                         r"independent .* at least 30 are needed \(min_windows\).*"
                                         r"ScaledChi2Threshold\(alpha, min_windows=\.\.\.\).*--min-windows") as err:
        LjungBox(5, 1e-3).calibrate(recs, window=101)
    assert "channel 0" not in str(err.value)
    with pytest.raises(ValueError, match=r"^LjungBox.calibrate, channel 'roll': statistic comes from 3 records, at "
                                         r"least 4 are needed for false_alarm=0.001"):
        LjungBox(5, 1e-3, correction="none", threshold=tsfdi.ScaledChi2Threshold(1e-3, min_windows=20)).calibrate(
            recs, window=101)
    assert LjungBox(5, 1e-3, threshold=tsfdi.ScaledChi2Threshold(1e-3, min_windows=20, min_records=3)).calibrate(
        recs, window=101).calibrated
    with pytest.raises(ValueError, match=r"^LjungBox.calibrate, channel 'roll': statistic is too small to calibrate"):
        LjungBox(5, 1e-5, threshold="empirical").calibrate(recs, window=101)

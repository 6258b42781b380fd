"""Data-driven thresholds of the residual tests (LjungBox / FTest ``threshold="empirical"``, paper 002 Fig. 2)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy import signal as sps
from scipy import special

import tsfdi
from tsfdi.detection import EmpiricalThreshold, FTest, LjungBox, ljungbox_windows
from tsfdi.monitoring import window_statistics


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
    lb = LjungBox(5, 0.01, threshold="empirical").calibrate(statistic=stat)
    np.testing.assert_allclose(lb.threshold_, np.quantile(stat, 0.99, axis=0))
    x = rng.standard_normal((300, 2))
    d = lb.test(x)
    np.testing.assert_array_equal(d.threshold, lb.threshold_)
    ref_p = [(1 + np.sum(stat[:, c] >= d.statistic[c])) / (3000 + 1) for c in range(2)]
    np.testing.assert_allclose(d.pvalue, ref_p)
    assert d.details["threshold_method"] == "empirical" and d.details["calibration_size"] == 3000
    np.testing.assert_array_equal(d.channel_reject, d.statistic > lb.threshold_)
    # the p-value of a statistic above every calibration value is 1 / (n + 1)
    assert lb.empirical_pvalue(np.array([1e9, 1e9]))[0] == pytest.approx(1 / 3001)
    # chi-square tests say so too
    assert LjungBox(5, 0.01).test(x).details["threshold_method"] == "chi2"
    assert FTest(0.01).test(x, reference_variance=1.0, reference_df=100).details["threshold_method"] == "f"
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
    lb = LjungBox(4, 0.05, threshold="empirical").calibrate([wrap(r) for r in recs], window=50, step=2)
    ref = LjungBox(4, 0.05, threshold="empirical").calibrate(recs, window=50, step=2)
    np.testing.assert_allclose(lb.threshold_, ref.threshold_)
    d = lb.test(wrap(recs[0][:50]))
    np.testing.assert_allclose(d.statistic, ref.test(recs[0][:50]).statistic)
    f = FTest(0.05, threshold="empirical").calibrate([wrap(r) for r in recs], window=50, step=2,
                                                     reference_variance=[1.0, 1.0])
    fr = FTest(0.05, threshold="empirical").calibrate(recs, window=50, step=2, reference_variance=1.0)
    np.testing.assert_allclose(f.threshold_, fr.threshold_)
    # calibrating from precomputed statistics of any kind
    st = ljungbox_windows(recs[0], 4, 50, 1)
    a = LjungBox(4, 0.05, threshold="empirical").calibrate(statistic=wrap(st)).threshold_
    np.testing.assert_allclose(a, np.quantile(st, 0.95, axis=0))


def test_window_statistics_per_model_tests():
    """window_statistics with one calibrated test per model equals the per-window decisions of each test."""
    rng = np.random.default_rng(4)
    y = ar2(3000, rng)
    models = {"a": tsfdi.AR(y[:1500], 2).fit(), "b": tsfdi.AR(y[1500:], 3).fit()}
    tests = {}
    for name, res in models.items():
        e = np.asarray(res.residuals(ar2(20000, rng)))
        tests[name] = LjungBox(6, 0.05, threshold="empirical").calibrate(e, window=200 - res.lags, step=3)
    x = ar2(1000, rng)
    ws = window_statistics(x, models, tests, window=200, step=50)
    for name, res in models.items():
        e = np.asarray(res.residuals(x)).reshape(-1, 1)
        p = res.lags
        for w, s in enumerate(ws["starts"]):
            d = tests[name].test(e[s:s + 200 - p])
            assert ws["decisions"][name]["statistic"][w, 0] == pytest.approx(d.statistic[0], rel=1e-8)
            assert ws["decisions"][name]["pvalue"][w, 0] == pytest.approx(d.pvalue[0])
            assert ws["decisions"][name]["reject"][w] == d.reject
            assert ws["decisions"][name]["threshold"][w, 0] == tests[name].threshold_[0]
    with pytest.raises(ValueError, match="no test for the model"):
        window_statistics(x, models, {"a": tests["a"]}, window=200, step=50)


def test_bad_input():
    rng = np.random.default_rng(5)
    with pytest.raises(ValueError, match="at least 2000 are needed"):
        LjungBox(5, 1e-3, threshold="empirical").calibrate(statistic=rng.chisquare(5, 500))
    with pytest.raises(ValueError, match="not calibrated"):
        LjungBox(5, 0.05, threshold="empirical").test(rng.standard_normal(100))
    with pytest.raises(ValueError, match="threshold='empirical'"):
        LjungBox(5, 0.05).calibrate(statistic=rng.chisquare(5, 5000))
    with pytest.raises(ValueError, match="false_alarm"):
        LjungBox(5, 0.05, threshold=EmpiricalThreshold(0.01))
    with pytest.raises(TypeError, match="threshold"):
        LjungBox(5, 0.05, threshold=3.0)
    with pytest.raises(ValueError, match="threshold"):
        FTest(0.05, threshold="chi2")
    with pytest.raises(ValueError, match="alternative='greater'"):
        FTest(0.05, alternative="two-sided", threshold="empirical")
    lb = LjungBox(5, 0.05, threshold="empirical").calibrate(statistic=rng.chisquare(5, (5000, 2)))
    with pytest.raises(ValueError, match="calibrated on 2"):
        lb.test(rng.standard_normal((100, 3)))
    with pytest.raises(TypeError, match="window"):
        LjungBox(5, 0.05, threshold="empirical").calibrate(rng.standard_normal(500))
    with pytest.raises(TypeError, match="needs resid"):
        LjungBox(5, 0.05, threshold="empirical").calibrate()
    with pytest.raises(TypeError, match="reference_variance"):
        FTest(0.05, threshold="empirical").calibrate(rng.standard_normal(500), window=50)
    with pytest.raises(ValueError, match="window"):
        LjungBox(5, 0.05, threshold="empirical").calibrate(rng.standard_normal(500), window=4)

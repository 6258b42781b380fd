"""MeanTest: the windowed mean-shift test (GLRT of a mean change with a known onset, paper 002 eq. 2)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

import tsfdi


def test_statistic_and_pvalue_match_the_two_sided_z_test():
    rng = np.random.default_rng(3)
    e = rng.normal(0.3, 2.0, size=(80, 2))
    ref = np.array([4.0, 4.0])
    d = tsfdi.MeanTest(alpha=0.05, correction="none").test(e, reference_variance=ref)
    z = e.sum(axis=0) / np.sqrt(80 * ref)
    np.testing.assert_allclose(d.statistic, z ** 2, rtol=1e-12)
    np.testing.assert_allclose(d.pvalue, 2 * stats.norm.sf(np.abs(z)), rtol=1e-10)
    np.testing.assert_allclose(d.threshold, stats.chi2.isf(0.05, 1), rtol=1e-12)
    np.testing.assert_allclose(d.details["mean"], e.mean(axis=0))
    assert d.channel_reject.tolist() == (d.pvalue < 0.05).tolist() and d.test == "MeanTest"


def test_window_statistic_equals_test_on_every_window():
    rng = np.random.default_rng(4)
    e = rng.standard_normal((300, 3))
    t = tsfdi.MeanTest(alpha=0.01, correction="sidak")
    w = t.window_statistic(e, 50, 7, reference_variance=1.5)
    starts = np.arange(0, 300 - 50 + 1, 7)
    direct = np.array([t.test(e[s:s + 50], reference_variance=1.5).statistic for s in starts])
    np.testing.assert_allclose(w, direct, rtol=1e-10)


@pytest.mark.parametrize("alpha", [0.05, 0.01])
def test_theoretical_size_on_iid_gaussian_residuals(alpha):
    """Monte Carlo (fixed seed): 20,000 disjoint windows of iid N(0, 1) inside the 99.9 % binomial band."""
    rng = np.random.default_rng(2026)
    n_win, n = 20000, 40
    e = rng.standard_normal((n_win * n, 1))
    flags = tsfdi.MeanTest(alpha=alpha).window_statistic(e, n, n, reference_variance=1.0)[:, 0] > stats.chi2.isf(
        alpha, 1)
    lo, hi = stats.binom.ppf([0.0005, 0.9995], n_win, alpha)
    assert lo <= flags.sum() <= hi


def test_detect_uses_the_baseline_variance_and_keeps_channel_names():
    rng = np.random.default_rng(5)
    y = pd.DataFrame(rng.standard_normal((2000, 2)), columns=["p", "q"])
    res = tsfdi.VAR(y, 2, trend="c").fit()
    shifted = y.iloc[:200] + [0.0, 1.0]
    d = tsfdi.detect(shifted, res, tsfdi.MeanTest(alpha=1e-3))
    assert d.channels == ("p", "q") and d.channel_reject.tolist() == [False, True]
    var = np.diag(np.asarray(res.sigma)) * res.nobs / res.df_resid
    np.testing.assert_allclose(d.details["reference_variance"], var)


def test_calibrated_on_held_out_residuals():
    rng = np.random.default_rng(6)
    recs = [rng.standard_normal((1500, 2)) + rng.normal(0, 0.05, 2) for _ in range(6)]
    spec = tsfdi.VAR(recs, 1, trend="c")
    t = tsfdi.MeanTest(alpha=0.01).calibrate(spec.held_out_residuals(), window=100)
    assert t.threshold == "calibrated" and t.threshold_.shape == (2,)
    law = t.thresholds_[0]                       # chi-square(1) per record, only its scale fitted: c_j = mean T
    np.testing.assert_array_equal(law.df_, np.ones(6))
    assert law.df == 1.0 and np.all(law.scale_ > 0)
    d = tsfdi.detect(recs[0][:100] + [0.0, 2.0], spec.fit(), t)
    assert d.details["threshold_method"] == "calibrated" and d.channel_reject[1]


def test_bad_reference_variance_is_named():
    t = tsfdi.MeanTest()
    with pytest.raises(TypeError, match="reference_variance"):
        t.test(np.zeros((10, 1)))
    with pytest.raises(TypeError, match="reference_variance"):
        t.test(np.ones((10, 1)), reference_variance="")
    with pytest.raises(ValueError, match="reference_variance"):
        t.test(np.ones((10, 2)), reference_variance=[1.0, -1.0])
    with pytest.raises(ValueError, match="alpha"):
        tsfdi.MeanTest(alpha=1.5)


def test_windowed_engine_agrees_with_detect_window_by_window():
    rng = np.random.default_rng(8)
    y = rng.standard_normal((1200, 2))
    res = tsfdi.VAR(y, 2, trend="c").fit()
    x = rng.standard_normal((400, 2)) + [0.0, 0.4]
    t = tsfdi.MeanTest(alpha=0.01)
    ws = tsfdi.ResidualWindows({"m": res}).fit(x).statistics(t, window=100, step=50)
    for i, s in enumerate(ws.starts):
        d = tsfdi.detect(x[s:s + 100], res, t)
        np.testing.assert_allclose(ws.statistic[i, 0], d.statistic, rtol=1e-10)
        assert ws.reject[i, 0] == d.reject

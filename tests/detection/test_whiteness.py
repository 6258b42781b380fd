"""LjungBox: equals statsmodels, multivariate portmanteau, windowed path, Monte Carlo size, power, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal as sps
from scipy import stats
from statsmodels.stats.diagnostic import acorr_ljungbox
from statsmodels.tsa.api import VAR as SMVAR

import tsfdi
from tsfdi.detection import autocovariance, ljungbox_windows
from tests.conftest import as_kind


def _sm_q(x, lags, model_df=0):
    r = acorr_ljungbox(x, lags=[lags], model_df=model_df)
    return r["lb_stat"].iloc[0], r["lb_pvalue"].iloc[0]


@pytest.mark.parametrize("n,lags", [(60, 5), (500, 20), (2000, 50), (3000, 100)])
def test_equals_statsmodels(n, lags):
    rng = np.random.default_rng(n)
    x = sps.lfilter([1], [1, -0.3], rng.standard_normal((n, 2)), axis=0) + 0.5
    d = tsfdi.LjungBox(lags, 0.05, correction="none").test(x)
    for c in range(2):
        q, p = _sm_q(x[:, c], lags)
        np.testing.assert_allclose(d.statistic[c], q, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(d.pvalue[c], p, rtol=1e-8, atol=1e-300)
    np.testing.assert_allclose(d.threshold, stats.chi2.ppf(0.95, lags), rtol=1e-10)
    # in-sample df correction
    d2 = tsfdi.LjungBox(lags, 0.05, model_df=2).test(x[:, 0])
    q, p = _sm_q(x[:, 0], lags, model_df=2)
    np.testing.assert_allclose(d2.pvalue[0], p, rtol=1e-8)
    assert d2.df[0] == lags - 2


def test_autocovariance_paths_agree():
    rng = np.random.default_rng(0)
    x = rng.standard_normal((5000, 2))
    x -= x.mean(axis=0)
    ref = np.array([[x[k:, c] @ x[:len(x) - k, c] / len(x) for c in range(2)] for k in range(41)])
    np.testing.assert_allclose(autocovariance(x, 40), ref, atol=1e-13)   # lag-product path
    ref200 = np.array([[x[k:, c] @ x[:len(x) - k, c] / len(x) for c in range(2)] for k in range(201)])
    np.testing.assert_allclose(autocovariance(x, 200), ref200, atol=1e-13)   # FFT path
    z = x[:300]
    ref_small = np.array([[z[k:, c] @ z[:300 - k, c] / 300 for c in range(2)] for k in range(6)])
    np.testing.assert_allclose(autocovariance(z, 5), ref_small, atol=1e-13)   # lag-product path


def test_multivariate_hosking_li_mcleod_against_statsmodels():
    rng = np.random.default_rng(1)
    y = rng.standard_normal((800, 3))
    y[:, 1] += 0.5 * y[:, 0]
    y = sps.lfilter([1], [1, -0.5], y, axis=0)
    smres = SMVAR(y).fit(2, trend="n")
    u = np.asarray(smres.resid)
    h = 10
    wt = smres.test_whiteness(nlags=h, adjusted=True)
    d = tsfdi.LjungBox(h, 0.05, model_df=9 * 2, multivariate="hosking").test(u)
    np.testing.assert_allclose(d.statistic[0], wt.test_statistic, rtol=1e-10)
    np.testing.assert_allclose(d.pvalue[0], wt.pvalue, rtol=1e-8)
    assert d.df[0] == wt.df and d.channels == ("joint",)
    wt0 = smres.test_whiteness(nlags=h, adjusted=False)
    d0 = tsfdi.LjungBox(h, 0.05, model_df=18, multivariate="li-mcleod").test(u)
    n = u.shape[0]
    np.testing.assert_allclose(d0.statistic[0], wt0.test_statistic + 9 * h * (h + 1) / (2 * n), rtol=1e-10)


@pytest.mark.parametrize("window,step,lags", [(1970, 100, 50), (300, 7, 10)])
def test_windows_equal_statsmodels(window, step, lags):
    rng = np.random.default_rng(2)
    x = sps.lfilter([1], [1, -0.2], rng.standard_normal((6000, 2)), axis=0) + 3.0
    q = ljungbox_windows(x, lags, window, step)
    starts = np.arange(0, 6000 - window + 1, step)
    assert q.shape == (starts.size, 2)
    for w in [0, 1, starts.size // 2, starts.size - 1]:
        for c in range(2):
            ref, _ = _sm_q(x[starts[w]:starts[w] + window, c], lags)
            np.testing.assert_allclose(q[w, c], ref, rtol=1e-9)
    np.testing.assert_array_equal(tsfdi.LjungBox(lags, 0.01).window_statistic(x, window, step), q)


def _ar2(rng, n, reps, a=(-0.6, 0.2)):
    return sps.lfilter([1], [1, *a], rng.standard_normal((reps, n + 200)), axis=1)[:, 200:]


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [0.05, 0.01])
def test_false_alarm_rate_h0(alpha):
    """H0: AR(2) baseline fitted on one long record (20,000 samples), tested on new records of 1,000.

    df = lags (the papers' use for new data) is accurate when the baseline record is much longer than the
    tested one; the baseline's estimation error adds about p * N_u / N_0 to E[Q] (0.1 here).
    """
    rng = np.random.default_rng(20 if alpha == 0.05 else 21)
    reps, lags = 2000, 20
    res = tsfdi.AR(_ar2(rng, 20000, 1)[0], 2).fit()
    new = _ar2(rng, 1000, reps)
    test = tsfdi.LjungBox(lags, alpha)
    rej = np.mean([tsfdi.detect(y, res, test).reject for y in new])
    lo, hi = stats.binom.interval(0.999, reps, alpha)
    assert lo / reps <= rej <= hi / reps, rej


@pytest.mark.slow
def test_false_alarm_rate_iid_vector_and_bonferroni():
    rng = np.random.default_rng(22)
    reps, alpha = 2000, 0.05
    e = rng.standard_normal((reps, 400, 3))
    per = np.array([tsfdi.LjungBox(10, alpha, correction="none").test(x).channel_reject for x in e])
    lo, hi = stats.binom.interval(0.999, reps * 3, alpha)
    assert lo / (reps * 3) <= per.mean() <= hi / (reps * 3)
    fam = np.mean([tsfdi.LjungBox(10, alpha, correction="bonferroni").test(x).reject for x in e])
    assert fam <= stats.binom.interval(0.999, reps, alpha)[1] / reps
    joint = np.mean([tsfdi.LjungBox(10, alpha, multivariate="li-mcleod").test(x).reject for x in e])
    lo, hi = stats.binom.interval(0.999, reps, alpha)
    assert lo / reps <= joint <= hi / reps, joint


@pytest.mark.slow
def test_chi2_tail_too_light_for_short_windows_and_simulated_null_fixes_it():
    """Documented in LjungBox: 480 iid Gaussian samples, 20 lags -- the chi2(20) test rejects more often than
    alpha in the far tail; a threshold calibrated on simulated white-noise statistics holds alpha on fresh noise."""
    rng = np.random.default_rng(25)
    n, lags, alpha, reps = 480, 20, 0.01, 40_000
    q = ljungbox_windows(rng.standard_normal((n * reps, 1)), lags, n, n)
    crit = stats.chi2.ppf(1.0 - alpha, lags)             # LjungBox's chi2 critical value (eq. 14)
    rej = np.mean(q[:, 0] > crit)
    lo, hi = stats.binom.interval(0.999, reps, alpha)
    assert rej > hi / reps, rej                        # chi2 test over-sized on white noise
    exact = tsfdi.LjungBox(lags, alpha, threshold="empirical").calibrate(statistic=q)
    fresh = ljungbox_windows(rng.standard_normal((n * reps, 1)), lags, n, n)
    rej = np.mean(fresh[:, 0] > exact.threshold_[0])
    assert lo / reps <= rej <= hi / reps, rej
    # longer windows: the chi2 law is close (size within the binomial band at 1980 samples)
    n = 1980
    q = ljungbox_windows(rng.standard_normal((n * 10_000, 1)), lags, n, n)
    lo, hi = stats.binom.interval(0.999, 10_000, alpha)
    assert lo / 10_000 <= np.mean(q[:, 0] > crit) <= hi / 10_000


def test_power_changed_dynamics():
    rng = np.random.default_rng(3)
    res = tsfdi.AR(_ar2(rng, 5000, 1)[0], 2).fit()
    faulty = _ar2(rng, 1000, 40, a=(-1.0, 0.4))
    assert np.mean([tsfdi.detect(y, res, tsfdi.LjungBox(20, 0.01)).reject for y in faulty]) >= 0.95


def test_data_kinds(kind):
    rng = np.random.default_rng(4)
    x = rng.standard_normal((300, 2))
    ref = tsfdi.LjungBox(10).test(x)
    d = tsfdi.LjungBox(10).test(as_kind(x, kind))
    np.testing.assert_allclose(d.statistic, ref.statistic)
    assert d.channels == ("y0", "y1")
    d1 = tsfdi.LjungBox(10).test(as_kind(x[:, 0], kind))
    np.testing.assert_allclose(d1.statistic, ref.statistic[:1])
    q = ljungbox_windows(as_kind(x, kind), 10, 100, 50)
    np.testing.assert_allclose(q[0], tsfdi.LjungBox(10).test(x[:100]).statistic)


@pytest.mark.parametrize("alpha", [0, 1, 2.0, -1e-3])
def test_bad_alpha(alpha):
    with pytest.raises(ValueError, match="alpha"):
        tsfdi.LjungBox(10, alpha)


def test_bad_input():
    x = np.random.default_rng(5).standard_normal(50)
    bad = x.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match="resid"):
        tsfdi.LjungBox(10).test(bad)
    bad[3] = -np.inf
    with pytest.raises(ValueError, match="resid"):
        tsfdi.LjungBox(10).test(bad)
    with pytest.raises(ValueError, match="resid is too short"):
        tsfdi.LjungBox(50).test(x)
    # a constant residual (a frozen sensor) is a documented outcome, not an error: Q = inf, p-value 0, reject
    d = tsfdi.LjungBox(5).test(np.ones(50))
    assert d.reject and d.statistic[0] == np.inf and d.pvalue[0] == 0 and d.details["constant"] == ("y0",)
    with pytest.raises(ValueError, match="lags"):
        tsfdi.LjungBox(0)
    with pytest.raises(TypeError, match="lags"):
        tsfdi.LjungBox(2.5)
    with pytest.raises(ValueError, match="model_df"):
        tsfdi.LjungBox(5, model_df=5)
    with pytest.raises(ValueError, match="multivariate"):
        tsfdi.LjungBox(5, multivariate="box")
    with pytest.raises(ValueError, match="window"):
        ljungbox_windows(x, 10, 10)
    with pytest.raises(ValueError, match="window"):
        ljungbox_windows(x, 10, 100)
    with pytest.raises(ValueError, match="resid"):
        ljungbox_windows(bad, 5, 20)
    y = np.random.default_rng(6).standard_normal((100, 2))
    y[:, 1] = 2 * y[:, 0]
    with pytest.raises(ValueError, match="singular"):
        tsfdi.LjungBox(5, multivariate="hosking").test(y)


@pytest.mark.slow
def test_baseline_estimation_error_inflates_q_by_p_nu_over_n0():
    """Documented in LjungBox: with a baseline fitted on N0 samples, E[Q] on new data is lags + p * Nu / N0.
    With N0 = Nu (the papers' 2,000 / 2,000) an AR(6) baseline raises E[Q] by about 6."""
    rng = np.random.default_rng(23)
    reps, lags, p = 1000, 20, 6
    base = _ar2(rng, 1000, reps)
    new = _ar2(rng, 1000, reps)
    q = np.array([tsfdi.detect(new[r], tsfdi.AR(base[r], p).fit(), tsfdi.LjungBox(lags)).statistic[0]
                  for r in range(reps)])
    se = q.std() / np.sqrt(reps)
    assert abs(q.mean() - lags - p) < 4 * se, (q.mean(), se)


def test_more_data_kinds(kind):
    rng = np.random.default_rng(24)
    x = rng.standard_normal((600, 2))
    q = tsfdi.LjungBox(10, 0.05).window_statistic(as_kind(x, kind), 200, 100)
    assert q.shape == (5, 2)
    np.testing.assert_allclose(q[2], tsfdi.LjungBox(10).test(x[200:400]).statistic)


def test_windowed_testing_is_not_duplicated():
    """Windowed testing has one engine (statistics + the public rules); LjungBox no longer has its own."""
    assert not hasattr(tsfdi.LjungBox, "test_windows")
    assert not hasattr(tsfdi.LjungBox, "_threshold_pvalue") and not hasattr(tsfdi.LjungBox, "_decision")


def test_public_rules_equal_test(kind):
    """threshold_pvalue / null_threshold / decision applied to a window's Q give exactly what test() gives."""
    rng = np.random.default_rng(25)
    x = sps.lfilter([1], [1, -0.15], rng.standard_normal((700, 3)), axis=0)
    for corr in ("none", "bonferroni"):
        lb = tsfdi.LjungBox(8, 0.05, model_df=1, correction=corr)
        d = lb.test(as_kind(x[100:400], kind))
        q = lb.window_statistic(as_kind(x, kind), 300, 100)          # window 1 is x[100:400]
        thr, pv = lb.threshold_pvalue(q)
        assert thr.shape == (3,) and pv.shape == q.shape
        np.testing.assert_array_equal(thr, d.threshold)
        np.testing.assert_allclose(q[1], d.statistic, rtol=1e-9)
        np.testing.assert_allclose(pv[1], d.pvalue, rtol=1e-8)
        thr1, pv1 = lb.threshold_pvalue(d.statistic, 300)                # on test()'s own statistic: identical
        np.testing.assert_array_equal(thr1, d.threshold)
        np.testing.assert_array_equal(pv1, d.pvalue)
        np.testing.assert_array_equal(lb.null_threshold(3), d.threshold)
        np.testing.assert_allclose(lb.null_threshold(3), stats.chi2.isf(d.details["channel_alpha"], 7), rtol=1e-10)
        d2 = lb.decision(d.statistic, d.nobs, d.channels)
        for f in ("statistic", "threshold", "pvalue", "df", "channel_reject"):
            np.testing.assert_array_equal(getattr(d2, f), getattr(d, f))
        assert (d2.reject, d2.nobs, d2.channels, d2.test, d2.alpha) == (d.reject, d.nobs, d.channels, "LjungBox",
                                                                        d.alpha)
        assert d2.details == d.details and d.details["threshold_method"] == "theoretical"
    assert tsfdi.LjungBox(8).decision([1.0, 50.0], 300).channels == ("y0", "y1")
    with pytest.raises(ValueError, match="statistic"):
        tsfdi.LjungBox(8).decision(np.ones((2, 2)), 300)


def _numpy_q(x, lags, demean=True):
    """Ljung-Box Q of one window in plain numpy: centred lag products summed window by window."""
    n = x.size
    xc = x - x.mean() if demean else x
    c0 = xc @ xc
    if c0 == 0 or (demean and np.all(x == x[0])):
        return np.inf
    rho = np.array([xc[lag:] @ xc[:-lag] for lag in range(1, lags + 1)]) / c0
    return n * (n + 2) * np.sum(rho ** 2 / (n - np.arange(1, lags + 1)))


@pytest.mark.parametrize("seed", range(6))
def test_windows_equal_numpy_reference(seed):
    # the lag-vectorised kernel against Q computed window by window, on records with an offset, a constant stretch
    # (a frozen sensor: inf) and a quiet stretch after a loud one (computed directly)
    rng = np.random.default_rng(seed)
    n, lags = int(rng.integers(1500, 3000)), int(rng.integers(1, 40))
    window, step, demean = int(rng.integers(lags + 1, min(n, 600))), int(rng.integers(1, 50)), bool(seed % 2)
    x = sps.lfilter([1], [1, -0.4], rng.standard_normal((n, 2)), axis=0) + [3.0, -1e4]
    x[n // 4:n // 4 + window + step, 0] = 2.5 if demean else 0.0
    x[n // 2:, 1] *= 1e-7
    q = ljungbox_windows(x, lags, window, step, demean=demean)
    starts = np.arange(0, n - window + 1, step)
    ref = np.array([[_numpy_q(x[s:s + window, c], lags, demean) for c in range(2)] for s in starts])
    assert np.array_equal(np.isinf(q), np.isinf(ref)) and np.isinf(q[:, 0]).any()
    np.testing.assert_allclose(q[np.isfinite(ref)], ref[np.isfinite(ref)], rtol=1e-9, atol=1e-9)


def test_lag_products_shared_across_window_lengths(monkeypatch):
    # one LjungBoxWindows gives every window length the statistics of ljungbox_windows exactly; a record whose lag
    # products are not kept (above the memory bound) gives the same to rounding
    from tsfdi.detection import LjungBoxWindows
    from tsfdi.detection import whiteness

    rng = np.random.default_rng(7)
    x = sps.lfilter([1], [1, -0.5], rng.standard_normal((5000, 3)), axis=0) + 2.0
    # the kept lag sums of one grid (the gcd of window and step) serve the windows on it and on coarser grids, a
    # finer grid replaces them: bit for bit the sums of the windows' own grid
    lbw = LjungBoxWindows(x, 20)
    for window, step in [(60, 40), (480, 100), (500, 100), (130, 15), (37, 3), (25, 1), (480, 100), (5000, 7),
                         (980, 100), (1980, 100)]:
        np.testing.assert_array_equal(lbw.statistic(window, step), ljungbox_windows(x, 20, window, step))
    lbw = LjungBoxWindows(x, 20)
    monkeypatch.setattr(whiteness, "_KEEP_LAGPROD", 3000)
    blocked = LjungBoxWindows(x, 20)
    for window, step in [(480, 100), (130, 1), (5000, 1), (60, 40)]:
        np.testing.assert_allclose(blocked.statistic(window, step), lbw.statistic(window, step), rtol=1e-12)
    assert blocked._grid is None                        # above the bound: nothing kept between calls
    with pytest.raises(ValueError, match="window"):
        lbw.statistic(20, 1)
    with pytest.raises(ValueError, match="window"):
        lbw.statistic(5001, 1)
    with pytest.raises(TypeError, match="demean"):
        LjungBoxWindows(x, 20, demean="yes")


def test_windowed_engine_on_shipped_data():
    # ResidualWindows (lag products shared across the window lengths) on the shipped hexacopter records equals
    # LjungBox.test on every window's residuals, with the same rejections
    from tsfdi.datasets import load_hexacopter
    from tsfdi.datasets.hexacopter import hexacopter_signals

    sig = hexacopter_signals(load_hexacopter())
    x = sig.isel(record=0).values[:3000]
    models = {"a": tsfdi.VAR(x[:1500], 4).fit(), "b": tsfdi.VAR(x[1500:], 8).fit()}
    test = tsfdi.LjungBox(20, 1e-3)
    rw = tsfdi.ResidualWindows(models).fit(x)
    for window in (500, 1000, 2000):
        ws = rw.statistics(test, window=window, step=100)
        for w, s in enumerate(ws.starts):
            for j, (name, m) in enumerate(models.items()):
                d = test.test(np.asarray(m.residuals(x))[s:s + window - m.lags])
                np.testing.assert_allclose(ws.statistic[w, j], d.statistic, rtol=1e-9)
                assert ws.channel_reject[w, j].tolist() == d.channel_reject.tolist()


def test_residual_windows_share_lag_products_across_lengths(monkeypatch):
    # ResidualWindows computes each model's lag products once per record and lags, whatever the window lengths
    import tsfdi.windows
    from tsfdi.detection import LjungBoxWindows

    made = []

    class Counting(LjungBoxWindows):
        def __init__(self, *args, **kwargs):
            made.append(args[1])
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(tsfdi.windows, "LjungBoxWindows", Counting)
    rng = np.random.default_rng(8)
    x = sps.lfilter([1], [1, -0.5], rng.standard_normal(3000))
    models = {"a": tsfdi.AR(x[:1500], 3).fit(), "b": tsfdi.AR(x[1500:], 5).fit()}
    rw = tsfdi.ResidualWindows(models).fit(x)
    for window in (300, 600, 1200):
        ws = rw.statistics(tsfdi.LjungBox(10, 1e-3), window=window, step=50)
        for j, (name, m) in enumerate(models.items()):
            np.testing.assert_array_equal(ws.statistic[:, j],
                                          ljungbox_windows(m.residuals(x), 10, window - m.lags, 50))
    rw.statistics(tsfdi.LjungBox(15, 1e-3), window=600, step=50)
    assert made == [10, 10, 15, 15]


@pytest.mark.parametrize("cls", [tsfdi.LjungBox, tsfdi.FTest, tsfdi.MeanTest])
def test_alpha_is_the_decisions_rate_by_default(cls):
    """Issue 31: alpha is the false-alarm rate of the multi-channel decision by default (Sidak over the channels);
    per-channel alpha is the explicit correction="none", and None (which reads as "the default") is refused."""
    t = cls(alpha=0.01)
    assert t.correction == "sidak" and t.channel_alpha(3) == pytest.approx(1 - 0.99 ** (1 / 3))
    assert t.family_alpha(t.channel_alpha(3), 3)[0] == pytest.approx(0.01)
    assert cls(alpha=0.01, correction="none").channel_alpha(3) == 0.01
    with pytest.raises(ValueError, match="correction must be 'sidak'.*'none'.*got None"):
        cls(alpha=0.01, correction=None)

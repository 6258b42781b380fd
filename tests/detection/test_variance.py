"""FTest: equals scipy.stats.f, Monte Carlo false-alarm rate under H0, power, data kinds, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal as sps
from scipy import stats

import tsfdi
from tests.conftest import as_kind


def binom_interval(p: float, n: int, conf: float = 0.999) -> tuple[float, float]:
    lo, hi = stats.binom.interval(conf, n, p)
    return lo / n, hi / n


def test_equals_scipy_f():
    rng = np.random.default_rng(0)
    e = rng.standard_normal((700, 2)) * [1.0, 1.3]
    ref_var, ref_df = np.array([1.05, 1.1]), np.array([950.0, 940.0])
    d = tsfdi.FTest(0.01, correction="none").test(e, reference_variance=ref_var, reference_df=ref_df)
    f = (e ** 2).mean(axis=0) / ref_var
    np.testing.assert_allclose(d.statistic, f, rtol=1e-14)
    for i in range(2):
        np.testing.assert_allclose(d.threshold[i], stats.f.ppf(0.99, 700, ref_df[i]), rtol=1e-10)
        np.testing.assert_allclose(d.pvalue[i], stats.f.sf(f[i], 700, ref_df[i]), rtol=1e-10)
    np.testing.assert_array_equal(d.df, [[700, 950], [700, 940]])
    assert d.channel_reject.tolist() == [False, True]
    assert d.reject is True and d.nobs == 700 and d.test == "FTest"
    # demeaned: N_u - 1 degrees of freedom and the variance about the mean
    d2 = tsfdi.FTest(0.01, demean=True).test(e[:, 0] + 3.0, reference_variance=1.0, reference_df=500)
    v = np.var(e[:, 0], ddof=1)
    np.testing.assert_allclose(d2.statistic[0], v, rtol=1e-12)
    np.testing.assert_allclose(d2.pvalue[0], stats.f.sf(v, 699, 500), rtol=1e-10)
    # two-sided
    d3 = tsfdi.FTest(0.05, alternative="two-sided").test(e[:, 0] * 0.5, reference_variance=1.0, reference_df=500)
    assert d3.reject and d3.statistic[0] < d3.details["lower_threshold"][0]
    np.testing.assert_allclose(d3.pvalue[0], 2 * stats.f.cdf(d3.statistic[0], 700, 500), rtol=1e-10)


def test_bonferroni():
    e = np.random.default_rng(1).standard_normal((400, 3))
    d = tsfdi.FTest(0.03, correction="bonferroni").test(e, reference_variance=1.0, reference_df=400)
    np.testing.assert_allclose(d.threshold, stats.f.ppf(1 - 0.01, 400, 400), rtol=1e-10)
    assert d.details["channel_alpha"] == pytest.approx(0.01)


def test_reference_from_model_unbiased():
    rng = np.random.default_rng(2)
    y = sps.lfilter([1], [1, -0.6, 0.2], rng.standard_normal(1500))
    res = tsfdi.AR(y, 2, trend="c").fit()
    ref = tsfdi.FTest().reference(res)
    rss = res.sigma2 * res.nobs
    np.testing.assert_allclose(ref["reference_variance"], rss / (res.nobs - 3))
    np.testing.assert_allclose(ref["reference_df"], res.nobs - 3)


def _ar2_records(rng, n, reps, a=(-0.6, 0.2)):
    e = rng.standard_normal((reps, n + 200))
    return sps.lfilter([1], [1, *a], e, axis=1)[:, 200:]


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [0.05, 0.01])
def test_false_alarm_rate_h0(alpha):
    """H0: each replication fits AR(2) on one record and tests a new record of the same process."""
    rng = np.random.default_rng(10 if alpha == 0.05 else 11)
    reps, n = 2000, 1000
    base = _ar2_records(rng, n, reps)
    new = _ar2_records(rng, n, reps)
    test = tsfdi.FTest(alpha)
    rej = 0
    for r in range(reps):
        res = tsfdi.AR(base[r], 2).fit()
        rej += tsfdi.detect(new[r], res, test).reject
    lo, hi = binom_interval(alpha, reps)
    assert lo <= rej / reps <= hi, (rej / reps, lo, hi)


def test_power_changed_dynamics():
    rng = np.random.default_rng(3)
    res = tsfdi.AR(_ar2_records(rng, 2000, 1)[0], 2).fit()
    faulty = _ar2_records(rng, 1000, 50, a=(-1.3, 0.6))
    rej = np.mean([tsfdi.detect(y, res, tsfdi.FTest(0.01)).reject for y in faulty])
    assert rej >= 0.95


def test_detect_data_kinds(kind):
    rng = np.random.default_rng(4)
    y0 = _ar2_records(rng, 1500, 1)[0]
    res = tsfdi.AR(y0, 2).fit()
    y = _ar2_records(rng, 800, 1)[0]
    ref = tsfdi.detect(y, res, tsfdi.FTest(0.05))
    d = tsfdi.detect(as_kind(y, kind), res, tsfdi.FTest(0.05))
    np.testing.assert_allclose(d.statistic, ref.statistic)
    e = res.residuals(y)
    d2 = tsfdi.FTest(0.05).test(as_kind(e, kind), **tsfdi.FTest().reference(res))
    np.testing.assert_allclose(d2.statistic, ref.statistic)


def test_vector_model_per_channel():
    rng = np.random.default_rng(5)
    y = np.column_stack([_ar2_records(rng, 1500, 1)[0], rng.standard_normal(1500)])
    res = tsfdi.VAR(y, 2).fit()
    ynew = np.column_stack([_ar2_records(rng, 1000, 1)[0], 2.0 * rng.standard_normal(1000)])
    d = tsfdi.detect(ynew, res, tsfdi.FTest(0.01))
    assert d.channel_reject.tolist() == [False, True] and d.reject
    var = np.diag(res.sigma) * res.nobs / res.df_resid
    e = np.asarray(res.residuals(ynew))
    np.testing.assert_allclose(d.statistic, (e ** 2).mean(axis=0) / var)
    np.testing.assert_allclose(d.df[:, 1], res.df_resid)


@pytest.mark.parametrize("alpha", [0, 1, -0.1, 1.5])
def test_bad_alpha(alpha):
    with pytest.raises(ValueError, match="alpha"):
        tsfdi.FTest(alpha)


def test_bad_input():
    e = np.random.default_rng(6).standard_normal(100)
    bad = e.copy()
    bad[5] = np.nan
    with pytest.raises(ValueError, match="resid"):
        tsfdi.FTest().test(bad, reference_variance=1.0, reference_df=100)
    bad[5] = np.inf
    with pytest.raises(ValueError, match="resid"):
        tsfdi.FTest().test(bad, reference_variance=1.0, reference_df=100)
    with pytest.raises(ValueError, match="reference_variance"):
        tsfdi.FTest().test(e, reference_variance=[1.0, 2.0], reference_df=100)
    with pytest.raises(ValueError, match="reference_variance"):
        tsfdi.FTest().test(e, reference_variance=-1.0, reference_df=100)
    with pytest.raises(ValueError, match="reference_df"):
        tsfdi.FTest().test(e, reference_variance=1.0, reference_df=0)
    with pytest.raises(TypeError, match="reference_variance"):
        tsfdi.FTest().test(e)
    with pytest.raises(ValueError, match="resid is too short"):
        tsfdi.FTest().test(e[:1], reference_variance=1.0, reference_df=10)
    with pytest.raises(ValueError, match="alternative"):
        tsfdi.FTest(alternative="less")
    with pytest.raises(ValueError, match="correction"):
        tsfdi.FTest(correction="holm")


@pytest.mark.parametrize("alpha", [0.05, 1e-12, 1e-300])
def test_huge_reference_df_gives_the_chi2_limit(alpha):
    """Issue 29: reference_df >= ~1e295 gave a NaN threshold (and above ~1e13 wrong digits): F(n, d) tends to
    chi2(n) / n as d grows, and the thresholds and p-values are that limit's, finite, for any reference_df."""
    from tsfdi.detection.variance import f_isf, f_sf

    y = np.random.default_rng(29).standard_normal(300)
    limit = stats.chi2.isf(alpha, 300) / 300
    lower_limit = stats.chi2.ppf(alpha / 2, 300) / 300
    for df in (1e11, 1e14, 1e200, 1e295, 1.7e308):
        d = tsfdi.FTest(alpha).test(y, reference_variance=1.0, reference_df=df)
        np.testing.assert_allclose(d.threshold, limit, rtol=1e-7)
        np.testing.assert_allclose(d.pvalue, stats.chi2.sf(300 * d.statistic, 300), rtol=1e-7)
        two = tsfdi.FTest(alpha, alternative="two-sided").test(y, reference_variance=1.0, reference_df=df)
        np.testing.assert_allclose(two.details["lower_threshold"], lower_limit, rtol=1e-7)
        assert np.isfinite(two.pvalue).all()
    # the limit takes over continuously from the exact law
    np.testing.assert_allclose(f_isf(300, 3e10, alpha), f_isf(300, 2.9e10, alpha), rtol=1e-7)
    np.testing.assert_allclose(f_sf(1e300, 40, 0.5), stats.chi2.cdf(40 / 0.5, 40), rtol=1e-10)


def test_min_resid_is_the_shortest_residual_series_each_test_accepts():
    """min_resid (what the command line adds to a model's order for the shortest window) is what test() accepts."""
    from tsfdi.detection import FTest, LjungBox, MeanTest

    rng = np.random.default_rng(5)
    ref = {"reference_variance": 1.0, "reference_df": 100}
    cases = ((LjungBox(lags=7), 8, {}), (FTest(), 2, ref), (FTest(demean=True), 3, ref),
             (MeanTest(), 1, {"reference_variance": 1.0}))
    for test, need, kwargs in cases:
        assert test.min_resid == need
        test.test(rng.standard_normal(need) + 1.0, **kwargs)
        if need > 1:
            with pytest.raises(ValueError, match="too short"):
                test.test(rng.standard_normal(need - 1) + 1.0, **kwargs)

"""Numerics of the residual tests under hostile input (issue 18, causes 1, 2, 3, 5 and 9).

1. a constant stretch (a frozen sensor) is a documented outcome, the same in ``test()`` and in the windowed path;
2. thresholds at tiny alpha come from the inverse of the upper tail (finite, and rejecting when p < alpha);
3. the statistics (Ljung-Box, Hosking / Li-McLeod, F, mean shift, GLRT, Z-score) do not depend on the scale of the
   residuals (1e-300 .. 1e300);
5. the GLRT window is bounded by the data, not by the option (memory, int64 overflow);
9. empty strings and other non-numbers for ``reference_variance`` / ``scale`` are refused naming the argument.
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from scipy import special

import tsfdi
from tsfdi.detection import GLRT, FTest, LjungBox, MeanTest, ZScore, glrt_direct, ljungbox_windows
from tsfdi.detection.variance import f_sf
from tsfdi.windows import ResidualWindows


def white(n: int, k: int | None = None, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).standard_normal(n if k is None else (n, k))


def frozen_record(seed: int = 1) -> np.ndarray:
    """White noise with a constant stretch (samples 100..199 frozen at 3.7)."""
    x = white(300, seed=seed)
    x[100:200] = 3.7
    return x


# ---------------------------------------------------------------------------------------------- cause 1
def test_ljungbox_windows_of_zeros_is_inf_not_zero_division():
    np.testing.assert_array_equal(ljungbox_windows(np.zeros(5), 3, 5), [[np.inf]])
    np.testing.assert_array_equal(ljungbox_windows(np.zeros((6, 2)), 3, 5), np.full((2, 2), np.inf))


@pytest.mark.parametrize("demean", [True, False])
def test_constant_window_agrees_in_test_and_windowed_path(demean):
    x = frozen_record()
    if not demean:
        x[100:200] = 0.0                                  # without demeaning only an all-zero window is degenerate
    lb = LjungBox(5, 1e-3, demean=demean)
    q = ljungbox_windows(x, 5, 50, 10, demean=demean)[:, 0]
    np.testing.assert_array_equal(lb.window_statistic(x, 50, 10)[:, 0], q)
    thr, pv = lb.threshold_pvalue(q[:, None], 50)
    for w, a in enumerate(range(0, 251, 10)):
        d = lb.test(x[a:a + 50])
        inside = 100 <= a and a + 50 <= 200
        if inside:
            assert q[w] == np.inf and d.statistic[0] == np.inf and d.pvalue[0] == 0 and pv[w, 0] == 0
            assert d.reject and d.channel_reject[0] and q[w] > thr[0] and d.details["constant"] == ("y0",)
        else:
            assert np.isfinite(q[w]) and d.details["constant"] == ()
            np.testing.assert_allclose(q[w], d.statistic[0], rtol=1e-9)
            assert (q[w] > thr[0]) == d.reject


def test_constant_window_whose_mean_does_not_round_exactly():
    # the mean of 50 times 0.1 is not exactly 0.1: the window is still constant, not "perfectly autocorrelated"
    for x in (np.full(50, 0.1), np.full(50, 3.7), np.full(50, -1e-300)):
        d = LjungBox(5).test(x)
        assert d.statistic[0] == np.inf and d.pvalue[0] == 0 and d.reject
        assert ljungbox_windows(x, 5, 20, 5)[0, 0] == np.inf


def test_demean_false_windows_equal_test():
    # the windowed path used to centre the record on its global mean even without demean
    x = white(300) + 5.0
    q = ljungbox_windows(x, 5, 100, 100, demean=False)[:, 0]
    expected = [LjungBox(5, demean=False).test(x[a:a + 100]).statistic[0] for a in (0, 100, 200)]
    np.testing.assert_allclose(q, expected, rtol=1e-10)


def test_quiet_stretch_after_a_loud_one_is_accurate():
    # prefix sums of a record whose first part is 1e6 times louder leave no digits for the quiet windows
    x = white(4000, seed=3)
    x[:2000] *= 1e6
    q = ljungbox_windows(x, 10, 200, 100)[:, 0]
    for w, a in enumerate(range(0, 3801, 100)):
        np.testing.assert_allclose(q[w], LjungBox(10).test(x[a:a + 200]).statistic[0], rtol=1e-8)
    f = FTest(demean=True).window_statistic(x, 200, 100, reference_variance=1.0)[:, 0]
    for w, a in enumerate(range(0, 3801, 100)):
        d = FTest(demean=True).test(x[a:a + 200], reference_variance=1.0, reference_df=100)
        np.testing.assert_allclose(f[w], d.statistic[0], rtol=1e-8)


@pytest.mark.parametrize("demean", [True, False])
def test_windows_of_a_record_wider_than_the_float_range(demean):
    # 1e200 and 1e-170 in one record: no common scale squares both, each window is computed at its own
    x = white(400, seed=12)
    x[:100] *= 1e200
    x[200:300] *= 1e-170
    q = ljungbox_windows(x, 5, 50, 25, demean=demean)[:, 0]
    expected = [LjungBox(5, demean=demean).test(x[a:a + 50]).statistic[0] for a in range(0, 351, 25)]
    np.testing.assert_allclose(q, expected, rtol=1e-10)


def test_ftest_constant_window_is_zero_variance():
    x = frozen_record()
    ref = {"reference_variance": 1.0, "reference_df": 200}
    greater = FTest(1e-3, demean=True)
    f = greater.window_statistic(x, 50, 10, **ref)[:, 0]
    two = FTest(1e-3, demean=True, alternative="two-sided")
    for w, a in enumerate(range(0, 251, 10)):
        d = greater.test(x[a:a + 50], **ref)
        if 100 <= a and a + 50 <= 200:
            assert f[w] == 0.0 and d.statistic[0] == 0.0 and d.details["variance"][0] == 0.0
            assert not d.reject and d.pvalue[0] == 1.0                     # the variance did not increase
            d2 = two.test(x[a:a + 50], **ref)
            assert d2.reject and d2.pvalue[0] == 0.0                       # it changed: a frozen sensor
        else:
            np.testing.assert_allclose(f[w], d.statistic[0], rtol=1e-9)


def test_multivariate_constant_channel():
    x = white(200, 2)
    x[:, 1] = 0.25
    d = LjungBox(3, multivariate="hosking").test(x)
    assert d.statistic[0] == np.inf and d.pvalue[0] == 0 and d.reject and d.details["constant"] == ("y1",)
    x[:100, 1] = white(100, seed=4)
    q = LjungBox(3, multivariate="li-mcleod").window_statistic(x, 50, 25)[:, 0]
    assert np.isfinite(q[:3]).all() and np.all(q[4:] == np.inf)


def test_windowed_engine_agrees_with_test_on_a_frozen_sensor():
    rng = np.random.default_rng(2)
    y = np.zeros(3000)
    e = rng.standard_normal(3000)
    for t in range(2, 3000):
        y[t] = 0.5 * y[t - 1] - 0.2 * y[t - 2] + e[t]
    model = tsfdi.AR(y[:2000], lags=2).fit()
    z = y.copy()
    z[2300:2600] = z[2300]
    rw = ResidualWindows({"h": model}).fit(z[:, None])
    resid = np.asarray(model.residuals(z))
    for test in (LjungBox(10, 1e-3), FTest(1e-3), FTest(1e-3, demean=True)):
        ws = rw.statistics(test, window=200, step=50)
        ref = test.reference(model)
        for w, s in enumerate(ws.starts):
            d = test.test(resid[s:s + 198], **ref)
            assert d.reject == ws.reject[w, 0]
            if np.isinf(d.statistic[0]):
                assert ws.statistic[w, 0, 0] == np.inf and ws.pvalue[w, 0, 0] == 0
            else:
                np.testing.assert_allclose(ws.statistic[w, 0, 0], d.statistic[0], rtol=1e-9)
    assert rw.statistics(LjungBox(10, 1e-3), window=200, step=50).reject.sum() >= 5


def test_calibrated_test_rejects_a_constant_window_and_refuses_constant_calibration_data():
    recs = [white(1000, seed=s) for s in range(3)]
    lb = LjungBox(5, 0.1, threshold="empirical").calibrate(recs, window=100, step=10)
    d = lb.test(np.full(100, 2.0))
    assert d.reject and d.pvalue[0] == 0 and d.details["constant"] == ("y0",)
    bad = [r.copy() for r in recs]
    bad[1][300:500] = 1.0
    with pytest.raises(ValueError, match=r"resid\[1\] holds a constant stretch .* at samples \[300, 500\)"):
        LjungBox(5, 0.01, threshold="calibrated").calibrate(bad, window=100, step=10)


def test_zscore_constant_history():
    x = np.r_[np.full(60, 2.0), 2.0, 2.5]
    d = ZScore(burn_in=50).test(x)
    z = np.asarray(d.details["z"])
    assert z[55] == 0 and z[61] == np.inf and d.reject and d.details["first_alarm"][0] == 61


# ---------------------------------------------------------------------------------------------- cause 2
@pytest.mark.parametrize("alpha", [0.05, 1e-3, 1e-12, 1e-17, 1e-50, 1e-300])
def test_ftest_threshold_at_tiny_alpha(alpha):
    # F(2, d): P(F > f) = (1 + 2 f / d)^(-d / 2), so f = d / 2 (alpha^(-2 / d) - 1) in closed form
    d0 = 30.0
    thr = FTest(alpha).null_threshold(1, 2, reference_df=d0)
    assert np.isfinite(thr).all()
    np.testing.assert_allclose(thr, d0 / 2 * np.expm1(-2 / d0 * np.log(alpha)), rtol=1e-9)
    for nu, df0 in ((400, 1000), (50, 100), (5, 7)):
        t = FTest(alpha).null_threshold(1, nu, reference_df=df0)[0]
        assert np.isfinite(t) and special.fdtrc(nu, df0, t) == pytest.approx(alpha, rel=1e-6)


def test_ftest_two_sided_limits_at_tiny_alpha():
    # scipy's fdtri / fdtr are off (or 0) in the far lower tail; the limits come from the upper tail of F(d2, d1)
    for alpha, nu, df0 in ((1.3e-270, 2504, 56), (7.3e-261, 1, 464), (0.05, 200, 500)):
        d = FTest(alpha, alternative="two-sided").decision([1.0], nu, reference_df=df0)
        lower = d.details["lower_threshold"][0]
        assert 0 <= lower < 1 < d.threshold[0] and not d.reject and 0 < d.pvalue[0] <= 1
        if lower > 0:
            np.testing.assert_allclose(f_sf(df0, nu, 1 / lower), alpha / 2, rtol=1e-6)


def test_ftest_rejects_when_pvalue_is_below_a_tiny_alpha():
    x = white(400, seed=9) * 3.0
    d = FTest(1e-20).test(x, reference_variance=1.0, reference_df=1000)
    assert d.pvalue[0] < 1e-20 and d.reject and np.isfinite(d.threshold[0])
    two = FTest(1e-20, alternative="two-sided").test(x, reference_variance=1.0, reference_df=1000)
    assert two.reject and np.isfinite(two.threshold[0])
    f = FTest(1e-20).window_statistic(x, 400, reference_variance=1.0)
    thr, pv = FTest(1e-20).threshold_pvalue(f, 400, reference_df=1000)
    assert (f > thr).all() and pv[0, 0] == pytest.approx(d.pvalue[0])


def test_thresholds_at_alpha_1e_300():
    assert np.isfinite(LjungBox(20, 1e-300).null_threshold(3)).all()
    assert special.chdtrc(20, LjungBox(20, 1e-300).null_threshold(1)[0]) == pytest.approx(1e-300, rel=1e-6)
    # GLRT: alpha / window below the smallest float still gives a finite threshold, continuous with chdtri
    g = GLRT(10 ** 12, alpha=1e-300).threshold_
    assert np.isfinite(g) and 2 * g > special.chdtri(1, 1e-300)
    below, above = GLRT(1, alpha=0.99e-300).threshold_, GLRT(1, alpha=1.01e-300).threshold_
    assert below == pytest.approx(above, rel=1e-4) and below > above


# ---------------------------------------------------------------------------------------------- cause 3
SCALES = [2.0 ** -1000, 1e-300, 1e-200, 1e-154, 1e154, 1e200, 1e300]


@pytest.mark.parametrize("c", SCALES)
def test_ljungbox_is_scale_invariant(c):
    x = white(400, 2, seed=5)
    x[200:260, 1] = 0.5
    q = LjungBox(8).test(x).statistic
    np.testing.assert_allclose(LjungBox(8).test(x * c).statistic, q, rtol=1e-12)
    np.testing.assert_allclose(ljungbox_windows(x * c, 8, 100, 20), ljungbox_windows(x, 8, 100, 20), rtol=1e-10)
    for method in ("hosking", "li-mcleod"):
        y = white(300, 2, seed=6) * [1.0, 1e-3]
        expected = LjungBox(4, multivariate=method).test(y).statistic
        np.testing.assert_allclose(LjungBox(4, multivariate=method).test(y * c).statistic, expected, rtol=1e-10)


@pytest.mark.parametrize("c", [1e-150, 1e-100, 1e100, 1e150])
def test_ftest_is_scale_invariant(c):
    x = white(400, seed=7)
    for demean in (False, True):
        ft = FTest(demean=demean)
        d = ft.test(x, reference_variance=1.3, reference_df=300)
        dc = ft.test(x * c, reference_variance=1.3 * c * c, reference_df=300)
        np.testing.assert_allclose(dc.statistic, d.statistic, rtol=1e-12)
        np.testing.assert_allclose(dc.pvalue, d.pvalue, rtol=1e-9)
        np.testing.assert_allclose(ft.window_statistic(x * c, 100, 30, reference_variance=1.3 * c * c),
                                   ft.window_statistic(x, 100, 30, reference_variance=1.3), rtol=1e-10)
    # a ratio beyond the float range is refused instead of turning into inf or NaN
    with pytest.raises(ValueError, match="reference_variance"):
        FTest().test(x * 1e200, reference_variance=1e-200, reference_df=300)
    with pytest.raises(ValueError, match="reference_variance"):
        FTest().window_statistic(x * 1e200, 50, reference_variance=1e-200)


@pytest.mark.parametrize("c", [1e-150, 1e-100, 1e100, 1e150])
def test_mean_test_is_scale_invariant(c):
    x = white(300, 2, seed=13) + 0.2
    mt = MeanTest()
    d = mt.test(x, reference_variance=[1.1, 0.9])
    dc = mt.test(x * c, reference_variance=[1.1 * c * c, 0.9 * c * c])
    np.testing.assert_allclose(dc.statistic, d.statistic, rtol=1e-12)
    np.testing.assert_allclose(dc.details["mean"] / c, d.details["mean"], rtol=1e-12)
    np.testing.assert_allclose(mt.window_statistic(x * c, 50, 25, reference_variance=c * c),
                               mt.window_statistic(x, 50, 25, reference_variance=1.0), rtol=1e-10)
    for bad in ("", True, object()):
        with pytest.raises(TypeError, match="reference_variance"):
            mt.test(x, reference_variance=bad)


@pytest.mark.parametrize("c", SCALES)
def test_glrt_and_zscore_are_scale_invariant(c):
    x = white(300, seed=8) + np.r_[np.zeros(200), np.full(100, 1.5)]
    g = GLRT(20).test(x)
    gc = GLRT(20).test(x * c)
    np.testing.assert_allclose(gc.statistic, g.statistic, rtol=1e-12)
    np.testing.assert_allclose(gc.details["jump"] / c, g.details["jump"], rtol=1e-12)
    assert gc.details["first_alarm"][0] == g.details["first_alarm"][0]
    np.testing.assert_allclose(GLRT(20, scale=0.9 * c).test(x * c).statistic, GLRT(20, scale=0.9).test(x).statistic,
                               rtol=1e-12)
    np.testing.assert_allclose(glrt_direct(x * c, 15, 0.9 * c), glrt_direct(x, 15, 0.9), rtol=1e-12)
    st = GLRT(20, scale=0.9 * c).stream()
    np.testing.assert_allclose(st.extend(x * c)[:, 0], np.asarray(GLRT(20, scale=0.9).statistic(x)), rtol=1e-12)
    z = ZScore().test(x * c)
    np.testing.assert_allclose(z.statistic, ZScore().test(x).statistic, rtol=1e-12)


def test_glrt_refuses_a_residual_far_beyond_its_scale():
    with pytest.raises(ValueError, match="times scale"):
        GLRT(10, scale=1e-300).test(white(50) * 1e100)


# ---------------------------------------------------------------------------------------------- cause 5
@pytest.mark.parametrize("window", [10 ** 9, 1e10, 2 ** 63, 10 ** 400])
def test_glrt_window_is_bounded_by_the_data(window):
    x = white(400, seed=10)
    tracemalloc.start()
    try:
        gl = GLRT(window)
        d = gl.test(x)
        g = np.asarray(gl.statistic(x))
        sc = gl.scan(x)
        st = gl.stream(scale=1.0)
        st.extend(x[:200])
        for v in x[200:]:
            st.update(v)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 20e6
    full = GLRT(400)                      # a window as long as the record: the same statistic
    np.testing.assert_array_equal(g, np.asarray(full.statistic(x)))
    np.testing.assert_array_equal(sc.g, full.scan(x).g)
    assert d.threshold[0] == full.threshold_          # the union bound over the record's 400 change instants
    assert st.g[0] == pytest.approx(np.asarray(GLRT(400, scale=1.0).statistic(x))[-1])
    assert st._buf.shape[1] <= 512
    np.testing.assert_array_equal(glrt_direct(x[:50], window, 1.0), glrt_direct(x[:50], 50, 1.0))


def test_glrt_stream_grows_its_buffer_with_the_data():
    x = white((700), 2, seed=11)
    gl = GLRT(300, scale=[1.0, 2.0])
    expected = np.asarray(gl.statistic(x))
    st = gl.stream(2)
    out = [st.update(x[i])[None] for i in range(100)] + [st.extend(x[100:450])]
    out += [st.update(x[i])[None] for i in range(450, 700)]
    np.testing.assert_allclose(np.concatenate(out), expected, rtol=1e-12, atol=1e-12)
    assert st._buf.shape[1] == 300


# ---------------------------------------------------------------------------------------------- cause 9
@pytest.mark.parametrize("bad", ["", "1.0", b"1", True, None, [[1.0]], object()])
def test_reference_variance_that_is_not_a_number_is_named(bad):
    x = white(50)
    if bad is None:
        with pytest.raises(TypeError, match="reference_variance"):
            FTest().test(x, reference_variance=bad, reference_df=30)
        return
    with pytest.raises((TypeError, ValueError), match="reference_variance"):
        FTest().test(x, reference_variance=bad, reference_df=30)
    with pytest.raises((TypeError, ValueError), match="reference_variance"):
        FTest().window_statistic(x, 10, reference_variance=bad)
    with pytest.raises((TypeError, ValueError), match="reference_df"):
        FTest().test(x, reference_variance=1.0, reference_df=bad)


@pytest.mark.parametrize("bad", ["", "1.0", True, [[1.0]], object(), -1.0, np.nan])
def test_glrt_scale_that_is_not_a_positive_number_is_named(bad):
    with pytest.raises((TypeError, ValueError), match="scale"):
        GLRT(10, scale=bad)
    with pytest.raises((TypeError, ValueError), match="scale"):
        GLRT(10).test(white(50), scale=bad)


def test_stream_and_decision_inputs_are_named():
    st = GLRT(10, scale=1.0).stream()
    for bad in (None, "", True, "x"):
        with pytest.raises(TypeError, match="x must be"):
            st.update(bad)
    with pytest.raises(TypeError, match="statistic"):
        LjungBox(5).decision("", 50)
    with pytest.raises(ValueError, match="statistic"):
        LjungBox(5).threshold_pvalue(np.array([[np.nan]]))
    with pytest.raises(TypeError, match="window"):
        LjungBox(5, threshold="calibrated").calibrate([white(500)], window="100")

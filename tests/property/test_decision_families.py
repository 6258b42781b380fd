"""Property-based tests of the decision families of issue 29: window against data length, extreme degrees of freedom
and thresholds, calibration inputs.

* **Window vs data length**: a test calibrated at one window applied to residuals of any length (``test``,
  :func:`tsfdi.detect`, the windowed engine); ``GLRT`` / ``ParameterGLRT`` windows from 1 to 10**12 on records of 2
  to 400 samples; ``Monitor`` windows against the signal length.
* **Extreme degrees of freedom / thresholds**: the F test with ``reference_df`` from 1 to 1.8e308, ``alpha`` from
  1e-300 to 0.5, one-sided and two-sided.
* **Calibration inputs**: healthy records with a frozen stretch of any length, place and channel, windows of any
  length, too few windows.

Each call gives a finite, correct result (the threshold of the clipped window, the chi-square limit of the F law, a
calibrated threshold of the calibrated window) or raises a ``ValueError`` / ``TypeError`` naming the argument.
"""

from __future__ import annotations

import math

import numpy as np
from _contract import named
from hypothesis import given
from hypothesis import strategies as st
from scipy import stats

import tsfdi
from tsfdi.detection import GLRT, FTest, LjungBox, MeanTest, ParameterGLRT

CALIBRATED = (lambda: LjungBox(5, 0.01), lambda: FTest(0.01), lambda: MeanTest(0.01))


def _noise(seed: int, n: int, k: int = 1) -> np.ndarray:
    return np.random.default_rng(seed).standard_normal((n, k))


# ------------------------------------------------------------------------------------------ window vs data length
@given(make=st.sampled_from(CALIBRATED), window=st.integers(10, 60), n=st.integers(8, 200),
       seed=st.integers(0, 2**16))
def test_calibrated_window_against_the_tested_length(make, window, n, seed):
    recs = [_noise(seed + i, 40 * window) for i in range(3)]    # 3 records: the fewest the predictive law takes
    test = make().calibrate(recs, window=window, step=window // 2)
    ref = {"reference_variance": 1.0} if not isinstance(test, LjungBox) else {}
    try:
        d = test.test(_noise(seed + 7, n), **ref)
    except (ValueError, TypeError) as err:
        named(err, ["window", "resid"])
        assert n != window or n <= getattr(test, "lags", 0)
        return
    assert n == window and np.isfinite(d.threshold).all() and np.array_equal(d.threshold, test.threshold_)
    assert ((0 <= d.pvalue) & (d.pvalue <= 1)).all()


@given(window=st.one_of(st.integers(1, 500), st.sampled_from([10**9, 10**12, 2**62])), n=st.integers(2, 400),
       alpha=st.floats(1e-300, 0.5), seed=st.integers(0, 2**16))
def test_glrt_threshold_is_that_of_the_window_clipped_to_the_record(window, n, alpha, seed):
    y = _noise(seed, n)[:, 0]
    d = GLRT(window, scale=1.0, alpha=alpha).test(y)
    m = min(window, n)
    assert np.isfinite(d.threshold).all() and d.details["window"] == m
    np.testing.assert_allclose(d.threshold, GLRT(m, scale=1.0, alpha=alpha).test(y).threshold, rtol=1e-14)
    if alpha / m > 1e-300:
        np.testing.assert_allclose(d.threshold, stats.chi2.isf(alpha / m, 1) / 2, rtol=1e-8)
    p = ParameterGLRT(window, scale=1.0, alpha=alpha).test(y, _noise(seed + 1, n, 2))
    assert p.details["window"] == m
    np.testing.assert_allclose(p.threshold, ParameterGLRT(m, scale=1.0, alpha=alpha).test(
        y, _noise(seed + 1, n, 2)).threshold, rtol=1e-14)


@given(window=st.integers(3, 800), n=st.integers(3, 600), seed=st.integers(0, 2**16))
def test_monitor_window_against_the_signal_length(window, n, seed):
    base = tsfdi.AR(_noise(seed, 400)[:, 0], 1).fit()
    mon = tsfdi.Monitor(base, window=window, step=50, steady_window=2, test=FTest(1e-3))
    try:
        res = mon.run(_noise(seed + 1, n)[:, 0])
    except ValueError as err:
        named(err, ["window"])
        assert window > n or window - 1 < 3
        return
    assert len(res.windows) == (n - window) // 50 + 1 > 0


# ------------------------------------------------------------------------------------------ extreme df / thresholds
@given(df=st.one_of(st.floats(1.0, 1.7e308), st.sampled_from([1e11, 1e14, 1e200, 1e295, 1.7976931348623157e308])),
       alpha=st.floats(1e-300, 0.5), n=st.integers(2, 500), two=st.booleans(), seed=st.integers(0, 2**16))
def test_ftest_with_any_reference_df_gives_a_finite_threshold(df, alpha, n, two, seed):
    y = _noise(seed, n)
    d = FTest(alpha, alternative="two-sided" if two else "greater").test(y, reference_variance=1.0, reference_df=df)
    assert (d.threshold > 0).all() and not np.isnan(d.threshold).any()
    if df >= 50:                # a quantile beyond the float range (inf, documented) needs a heavy tail: small df
        assert np.isfinite(d.threshold).all()
    assert ((0 <= d.pvalue) & (d.pvalue <= 1)).all()
    if two:
        lower = d.details["lower_threshold"]
        assert np.isfinite(lower).all() and (lower >= 0).all() and (lower < d.threshold).all()
    if df >= 1e8 * max(n, 100) and not two and alpha > 1e-290:      # the chi-square limit of F(n, df)
        np.testing.assert_allclose(d.threshold, stats.chi2.isf(alpha, n) / n, rtol=1e-6)


# ------------------------------------------------------------------------------------------ calibration inputs
@given(make=st.sampled_from(CALIBRATED), window=st.integers(8, 60), length=st.integers(2, 120),
       where=st.floats(0.0, 1.0), channel=st.integers(0, 1), seed=st.integers(0, 2**16))
def test_calibration_refuses_a_frozen_stretch_as_long_as_a_window(make, window, length, where, channel, seed):
    recs = [_noise(seed + i, 40 * window, 2) for i in range(3)]
    start = int(where * (recs[1].shape[0] - length))
    recs[1][start:start + length, channel] = 0.5
    try:
        test = make().calibrate(recs, window=window, step=window // 2)
    except ValueError as err:
        named(err, ["resid[1]"])
        assert length >= window and f"[{start}, {start + length})" in str(err)
        return
    assert length < window and np.isfinite(test.threshold_).all() and test.calibration_window_ == (window, 0)


@given(make=st.sampled_from(CALIBRATED), records=st.integers(1, 4), per=st.integers(1, 40),
       min_windows=st.integers(5, 60), seed=st.integers(0, 2**16))
def test_too_few_calibration_windows_name_min_windows(make, records, per, min_windows, seed):
    window = 20
    recs = [_noise(seed + i, per * window, 1) for i in range(records)]
    test = make()
    # the per-record mixture: its only refusal is min_windows (the predictive law also refuses too few records)
    test.threshold = tsfdi.ScaledChi2Threshold(test.alpha, min_windows=min_windows, record_effect="bootstrap")
    try:
        test.calibrate(recs, window=window)
    except ValueError as err:
        named(err, ["min_windows"])
        assert records * per < min_windows and "--min-windows" in str(err)
        return
    assert records * per >= min_windows and math.isfinite(float(test.threshold_[0]))

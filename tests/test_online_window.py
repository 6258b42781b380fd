"""OnlineDetector(statistic="zmean"): the standardised moving-window sum of the prediction errors (the causal
matched filter of a bias lasting ``window`` samples; paper 002's GLRT with a fixed window), issue 34."""

import numpy as np
import pytest
from scipy import stats
from test_online import FS, PAPER001, assert_streams_like_a_block, episodes_and_hours, healthy_runs, two_pairs

from tsfdi.detection.glrt import GLRT
from tsfdi.models.recursive import RecursiveARX
from tsfdi.online import OnlineDetector


def zmean_detector(**kw):
    """The window sum on the synthetic pairs, whose output follows the input at the same sample."""
    return OnlineDetector(["a", "b"], **{**PAPER001, "na": 1, "nb": 1, "statistic": "zmean", "window": 25, **kw})


def direct_window_sum(y, u, window, **det_options):
    """The statistic computed directly: the pair's RLS errors (the detector's model options), the Welford mean and
    standard deviation at the first sample whose error variance is stable and positive, armed from the next sample,
    and the window sums of the standardised errors divided by sqrt(window) once the window lies after arming."""
    m = RecursiveARX(1, 1, 0, PAPER001["forgetting_factor"], threshold=1e300, freeze_on_alarm=False,
                     eps=PAPER001["eps"], gate="relative")
    r = m.run(y, u)
    var, vs = np.asarray(r.variance), np.asarray(r.variance_stable)
    k0 = int(np.flatnonzero(vs & np.isfinite(var) & (var > 0))[0])
    armed = k0 + 1
    w = (np.asarray(r.resid) - np.asarray(r.mean)[k0]) / np.sqrt(var[k0])
    out = np.full(len(y), np.nan)
    for k in range(armed + window - 1, len(y)):
        out[k] = w[k - window + 1:k + 1].sum() / np.sqrt(window)
    return out, armed


def test_zmean_equals_a_direct_window_sum_of_the_standardised_errors():
    y, u = two_pairs(bias=0.3)
    out = zmean_detector(freeze_on_alarm=False, direction="up").run(y, u)
    for c, name in enumerate(["a", "b"]):
        ref, armed = direct_window_sum(y[:, c], u[:, c], 25)
        assert out.first_alarms.loc[name, "armed_at"] == armed
        s = np.asarray(out.statistic)[:, c]
        assert np.isnan(s[:armed + 24]).all() and np.isfinite(s[armed + 24:]).all()
        np.testing.assert_allclose(s, ref, rtol=1e-9, atol=1e-9)
    # the sides: "down" the negated sum, "both" its absolute value
    down = np.asarray(zmean_detector(freeze_on_alarm=False, direction="down").run(y, u).statistic)
    both = np.asarray(zmean_detector(freeze_on_alarm=False, direction="both").run(y, u).statistic)
    np.testing.assert_allclose(down, -np.asarray(out.statistic))
    np.testing.assert_allclose(both, np.abs(np.asarray(out.statistic)))
    # a bias of 3 error standard deviations from sample 3000 in pair b: up 3 sqrt(25) / ... found within the window
    fa = zmean_detector(direction="up").run(y, u).first_alarms
    assert fa.loc["a", "position"] == -1 and 3000 <= fa.loc["b", "position"] <= 3025
    assert fa.loc["b", "source"] == "zmean"


def test_zmean_is_standard_normal_under_white_errors():
    """Monte Carlo (fixed seed): 40 streams of white prediction errors (y = 0.8 u + e, the model y on u); the window
    sums over disjoint windows after arming pooled: mean 0 and standard deviation 1 within their sampling error plus
    that of the scale estimated at arming, and a normal shape (Kolmogorov-Smirnov)."""
    rng = np.random.default_rng(20261129)
    values = []
    for _ in range(40):
        u = rng.standard_normal(4000)
        y = 0.8 * u + 0.1 * rng.standard_normal(4000)
        det = OnlineDetector(1, **{**PAPER001, "na": 0, "nb": 1, "statistic": "zmean", "window": 25,
                                   "direction": "up", "freeze_on_alarm": False})
        s = np.asarray(det.run(y, u).statistic)[:, 0]
        start = int(np.flatnonzero(np.isfinite(s))[0]) + 500        # past the model's settling after arming
        values.append(s[start::25])
    v = np.concatenate(values)
    assert v.size > 5000
    assert abs(v.mean()) < 0.1 and 0.9 < v.std() < 1.1, (v.mean(), v.std())
    assert stats.kstest((v - v.mean()) / v.std(), "norm").pvalue > 0.01


def test_zmean_streaming_equals_block():
    y, u = two_pairs(n=3400, bias=0.3)
    assert assert_streams_like_a_block(zmean_detector, y, u).first_alarm is not None
    assert_streams_like_a_block(lambda: zmean_detector(scale_forgetting=0.999, settle=100), y, u)


def test_calibrated_zmean_keeps_its_rate_on_new_healthy_runs():
    """Calibrated on 20 healthy 10-minute runs for 2 episodes per hour; on 20 new runs its alarm episodes lie in the
    two-sided 99 % binomial band of the stated rate (per sample: rate / samples per hour)."""
    ys, us = healthy_runs(20, seed=0)
    det = OnlineDetector(1, **{**PAPER001, "na": 1, "nb": 1, "statistic": "zmean", "window": 10,
                               "freeze_on_alarm": False})
    det.calibrate(ys, us, false_alarms_per_hour=2.0, fs=FS)
    cal = det.calibration_
    assert cal.estimator == "empirical" and cal.source_rates == {"zmean": 2.0} and cal.glrt_threshold is None
    assert det.threshold == cal.threshold and 2.0 < det.threshold < 6.0     # standard deviations of the sum
    total, hours = episodes_and_hours(det, *healthy_runs(20, seed=1))
    samples = round(hours * 3600 * FS)
    lo, hi = stats.binom.ppf([0.005, 0.995], samples, 2.0 / (3600 * FS))
    assert lo <= total <= hi, (total, lo, hi)


def test_zmean_options_are_checked_by_name():
    with pytest.raises(ValueError, match="glrt must be None with statistic='zmean'"):
        zmean_detector(glrt=GLRT(window=20, alpha=1e-6))
    with pytest.raises(ValueError, match="window"):
        zmean_detector(window=0)
    with pytest.raises(TypeError, match="window"):
        zmean_detector(window=2.5)
    with pytest.raises(ValueError, match="direction"):
        zmean_detector(direction="left")
    with pytest.raises(ValueError, match="settle=5 needs statistic='sprt' or 'zmean'"):
        zmean_detector(statistic="mean", settle=5)
    with pytest.raises(ValueError, match="scale_forgetting=0.99 needs statistic='sprt' or 'zmean'"):
        zmean_detector(statistic="mean", scale_forgetting=0.99)
    with pytest.raises(ValueError, match="statistic"):
        zmean_detector(statistic="zsum")
    assert zmean_detector().glrt is None and zmean_detector().sprt is None and zmean_detector().threshold == 4.5

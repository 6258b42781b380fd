"""Thresholds calibrated on held-out residuals hold their size on new records of a fleet (issue 17).

Monte Carlo with a fixed seed: every record of a simulated "fleet" is a VAR(2) whose coefficients are drawn around a
common mean (paper 002: aircraft of one type with small differences). A baseline is fitted on 10 records; the tests
are calibrated on its held-out residuals (each record through the fit on the other 9); 300 new records of the fleet
then give 3,000 disjoint windows per channel. The realised false-alarm counts must lie in the two-sided 99.9 %
binomial band of alpha, per channel and family-wise, and the chi-square / F thresholds must lie above it.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import tsfdi

A1 = np.array([[0.5, 0.1, 0.0], [0.0, 0.4, 0.1], [0.1, 0.0, 0.3]])
A2 = -0.2 * np.eye(3)
N, WINDOW, SPREAD = 2000, 200, 0.04


def fleet_record(rng: np.random.Generator, n: int = N) -> np.ndarray:
    """One record of the fleet: VAR(2) with coefficients A + SPREAD * N(0, 1), unit innovations."""
    b1 = A1 + SPREAD * rng.standard_normal((3, 3))
    b2 = A2 + SPREAD * rng.standard_normal((3, 3))
    e = rng.standard_normal((n + 200, 3))
    y = np.zeros_like(e)
    for t in range(2, n + 200):
        y[t] = b1 @ y[t - 1] + b2 @ y[t - 2] + e[t]
    return y[200:]


@pytest.fixture(scope="module")
def fleet():
    rng = np.random.default_rng(2026)
    spec = tsfdi.VAR([fleet_record(rng) for _ in range(10)], 2)
    baseline = spec.fit()
    new = [np.asarray(baseline.residuals(fleet_record(rng))) for _ in range(300)]
    return spec, baseline, spec.held_out_residuals(), new


def band(n: int, alpha: float) -> tuple[float, float]:
    """Two-sided 99.9 % binomial band of the number of false alarms in ``n`` independent windows."""
    return tuple(stats.binom.ppf([0.0005, 0.9995], n, alpha))


def old(alpha: float) -> tsfdi.ScaledChi2Threshold:
    """The per-record mixture with a bootstrap bound (issue 17; the predictive record-level law of issue 31 is in
    test_record_calibration.py)."""
    return tsfdi.ScaledChi2Threshold(alpha, record_effect="bootstrap")


def alarms(test, new, reference=None) -> np.ndarray:
    """Flags of every disjoint window of the new records' residuals, shape (windows, channels)."""
    n = WINDOW - 2
    flags = []
    for e in new:
        q = test.window_statistic(e, n, n, **(reference or {}))
        thr, _ = test.threshold_pvalue(q, n, **(reference or {}))
        flags.append(q > thr)
    return np.concatenate(flags)


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [1e-2, 1e-3])
def test_calibrated_size_on_new_records_of_a_fleet(fleet, alpha):
    spec, baseline, held, new = fleet
    lo, hi = band(3000, alpha)
    # per channel: calibrated inside the band, chi-square above it
    cal = alarms(tsfdi.LjungBox(lags=20, alpha=alpha, correction="none", threshold=old(alpha)).calibrate(
        held, window=WINDOW), new)
    chi = alarms(tsfdi.LjungBox(lags=20, alpha=alpha, correction="none"), new)
    assert cal.shape == (3000, 3)
    for c in range(3):
        assert lo <= cal[:, c].sum() <= hi, (c, cal.sum(axis=0), (lo, hi))
        assert chi[:, c].sum() > hi, (c, chi.sum(axis=0), (lo, hi))
    # family-wise: Sidak per-channel alpha, "any channel rejects" at alpha
    fam = alarms(tsfdi.LjungBox(lags=20, alpha=alpha, correction="sidak", threshold=old(alpha)).calibrate(held, window=WINDOW), new)
    assert lo <= fam.any(axis=1).sum() <= hi, (fam.any(axis=1).sum(), (lo, hi))
    # the joint (multivariate) portmanteau: its finite-window law has a lighter upper tail than the fitted scaled
    # chi-square, so the calibrated joint test is conservative: never above the band, where chi2(s^2 r) is
    mv = tsfdi.LjungBox(lags=20, alpha=alpha, multivariate="hosking")
    joint = alarms(tsfdi.LjungBox(lags=20, alpha=alpha, multivariate="hosking",
                                  threshold=old(alpha)).calibrate(held, window=WINDOW), new)
    assert joint.sum() <= hi, (joint.sum(), (lo, hi))
    q = np.concatenate([mv.window_statistic(e, WINDOW - 2, WINDOW - 2) for e in new])[:, 0]
    assert (q > stats.chi2.isf(alpha, 9 * 20)).sum() > hi                 # chi2(s^2 r) of the joint statistic
    # the F test, calibrated against the pooled held-out variance: at most the band (conservative on some
    # channels; in this fleet the residual variance hardly varies, so the F law of eq. 9 is no worse)
    fcal = alarms(tsfdi.FTest(alpha=alpha, correction="none", threshold=old(alpha)).calibrate(
        held, window=WINDOW), new)
    assert fcal.sum(axis=0).max() <= hi and fcal.sum() >= lo, (fcal.sum(axis=0), (lo, hi))
    # the mean-shift test, its law's degrees of freedom fixed at 1: at most the band per channel (conservative
    # on some), the Sidak family-wise decision inside it
    mcal = alarms(tsfdi.MeanTest(alpha=alpha, correction="none", threshold=old(alpha)).calibrate(
        held, window=WINDOW), new)
    assert mcal.sum(axis=0).max() <= hi, (mcal.sum(axis=0), (lo, hi))
    mfam = alarms(tsfdi.MeanTest(alpha=alpha, correction="sidak", threshold=old(alpha)).calibrate(held, window=WINDOW), new)
    assert lo <= mfam.any(axis=1).sum() <= hi, (mfam.any(axis=1).sum(), (lo, hi))


def test_the_documented_pattern_runs(fleet):
    """The pattern of issue 17: fit on several flights, calibrate on held-out residuals, detect on a new flight."""
    spec, baseline, held, new = fleet
    rng = np.random.default_rng(7)
    new_flight = fleet_record(rng, 1000)
    for test in (tsfdi.LjungBox(lags=20, alpha=0.01), tsfdi.FTest(alpha=0.01),
                 tsfdi.LjungBox(lags=20, alpha=0.01, multivariate="hosking")):
        test.calibrate(spec.held_out_residuals(), window=200)
        d = tsfdi.detect(new_flight[:200], baseline, test)      # window counts signal samples, as in detection
        assert isinstance(d.reject, bool) and d.nobs == 198
        assert d.details["threshold_method"] == "calibrated" and test.threshold == "calibrated"
        assert d.details["calibration_records"] == 10
        np.testing.assert_array_equal(d.threshold, test.threshold_)
        # p-value and threshold agree: the p-value is below alpha exactly where the statistic exceeds it
        thr, pv = test.threshold_pvalue(np.vstack([test.threshold_ * 0.999, test.threshold_ * 1.001]), 198)
        a = test.channel_alpha(test.threshold_.shape[0])            # alpha 0.01 shared by the channels (Sidak)
        assert np.all(pv[0] > a) and np.all(pv[1] < a)
    assert held.lags == 2 and len(held) == 10


def test_calibration_needs_enough_independent_windows(fleet):
    spec, baseline, held, new = fleet
    with pytest.raises(ValueError, match="independent .* windows, at least 30 are needed"):
        tsfdi.LjungBox(lags=20, alpha=0.01).calibrate(held[:2], window=200)      # 2 x 9 disjoint windows
    with pytest.raises(ValueError, match="window"):
        tsfdi.LjungBox(lags=20, alpha=0.01).calibrate(held, window=2)


@pytest.mark.slow
def test_short_records_are_pooled(monkeypatch):
    """Records holding fewer than MIN_RECORD_WINDOWS independent windows cannot show their own spread (their
    windows overlap), so the records are pooled into one law. Over 40 calibrations on 8 one-window records of white
    noise, the median realised rate on 3,000 new windows is alpha and the mean rate is half that of laws fitted per
    record from nearly coinciding windows (whose tail is too light)."""
    import tsfdi.detection.threshold as threshold

    window, alpha, lags = 100, 1e-2, 10
    rng = np.random.default_rng(7)
    q = np.array([tsfdi.LjungBox(lags=lags).test(x).statistic[0] for x in rng.standard_normal((3000, window))])
    rates = {}
    for pooled in (True, False):
        monkeypatch.setattr(threshold, "MIN_RECORD_WINDOWS", 3 if pooled else 0)
        draw = np.random.default_rng(1)
        rates[pooled] = []
        for _ in range(40):
            short = [draw.standard_normal((window + 10, 1)) for _ in range(8)]
            test = tsfdi.LjungBox(lags=lags, alpha=alpha, threshold=tsfdi.ScaledChi2Threshold(
                alpha, min_windows=5, record_effect="bootstrap"))
            test.calibrate(short, window=window)
            assert bool(test.thresholds_[0].pooled_) is pooled
            rates[pooled].append((q > test.threshold_[0]).mean())
    assert 0.5 * alpha <= np.median(rates[True]) <= 2 * alpha, np.median(rates[True])
    assert np.mean(rates[True]) < 0.6 * np.mean(rates[False]), (np.mean(rates[True]), np.mean(rates[False]))

"""The predictive record-level threshold of ScaledChi2Threshold solves its own equation (issue 31).

The threshold ``t`` of the predictive law solves ``P(exp(X) c_j chi2(nu_j) > t) = false_alarm``, ``X`` the new
record's anchor (a normal random effect averaged over the posterior of the records' spread: Student t tails with
``J - 1`` degrees of freedom). Here that tail is recomputed at the calibrated threshold by a brute-force quadrature
that shares nothing with the library's (midpoint bins on the log tail probability of both laws, 400 posterior and
6,000 chi-square bins). Gauss-Legendre on 40 quantiles of ``X`` missed the step of the chi-square tail where ``X``'s
Student t tail is wide: with 4-5 records at 3.3e-4 (the Sidak share of 0.001 over three channels) the threshold's
true tail was 1.15-1.30 times ``false_alarm`` (a liberal threshold).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import special, stats

from tsfdi.detection.threshold import ScaledChi2Threshold


def brute_tail(scale, df, sa2: float, samp: float, j: int, t: float) -> float:
    """``P(exp(X) c_k chi2(nu_k) > t)``, equal mixture over the records ``k``; ``X`` normal with variance
    ``max(s2 - samp, 0) + s2 / j`` over ``s2 = sa2 (j - 1) / chi2(j - 1)``."""
    lu = np.linspace(np.log(1e-30), 0.0, 401)
    u = np.exp(lu)
    s2 = sa2 * (j - 1) / stats.chi2.ppf(np.exp(0.5 * (lu[1:] + lu[:-1])), j - 1)
    sd = np.sqrt(np.maximum(s2 - samp, 0.0) + s2 / j)
    wu = np.diff(u) / (u[-1] - u[0])
    lw = np.linspace(np.log(1e-30), np.log(0.5), 3001)
    mid, mass = np.exp(0.5 * (lw[1:] + lw[:-1])), np.diff(np.exp(lw))
    total = 0.0
    for c, nu in zip(scale, df):
        q = 2 * np.concatenate([special.gammainccinv(nu / 2, mid), special.gammaincinv(nu / 2, mid)])
        w = np.concatenate([mass, mass])
        y = np.log(c * q)
        total += float(special.ndtr(-(np.log(t) - y[None, :]) / sd[:, None]) @ (w / w.sum()) @ wu)
    return total / len(scale)


def lognormal_tail(windows: np.ndarray, pf: float, t: float) -> float:
    """The record-shape law's tail at ``t``, recomputed from the windows (records x disjoint windows): each record
    log-normal with its two moments, moved to the records' mean anchor (log ``1 - pf`` quantile); the new anchor
    normal with variance ``tau2 + s2 / J``, ``tau2`` the covariance over the records of the anchors of their first
    and last 4 windows (the 2 between left out), ``s2`` the anchors' variance: a log-normal mixture in closed
    form."""
    def anchors(w):
        m, v = w.mean(axis=1), w.var(axis=1, ddof=1)
        sg2 = np.log1p(v / m ** 2)
        return np.log(m) - sg2 / 2 + stats.norm.isf(pf) * np.sqrt(sg2), np.sqrt(sg2)

    a, sg = anchors(windows)
    tau2 = max(np.cov(anchors(windows[:, :4])[0], anchors(windows[:, 6:])[0])[0, 1], 0.0)
    sd = np.sqrt(sg ** 2 + tau2 + a.var(ddof=1) / a.size)
    return float(np.mean(stats.norm.sf((np.log(t) - a.mean() + stats.norm.isf(pf) * sg) / sd)))


@pytest.mark.parametrize("records", [4, 5, 10, 20])
@pytest.mark.parametrize("shape,tau", [("pooled", 0.3), ("record", 0.03), ("pooled", 0.0)])
def test_predictive_threshold_has_the_stated_tail(records, shape, tau):
    # white-noise records, 10 disjoint windows of 198 samples each, log variance N(0, tau^2) from record to record;
    # the F variance ratio of each window (tau 0.3: the fleet's noise spread; 0.03: a spread hidden in the windows'
    # sampling noise, Ljung-Box-like, each record its own log-normal shape, checked in closed form; 0: no spread, the
    # anchor law far narrower than a window's)
    rng = np.random.default_rng(31_000 + records)
    for pf in (1 - (1 - 1e-3) ** (1 / 3), 1e-5):
        x = tau * rng.standard_normal(records)
        e = rng.standard_normal((records, 10, 198)) * np.exp(x / 2)[:, None, None]
        s = np.mean(e * e, axis=2).ravel()
        law = ScaledChi2Threshold(pf, shape=shape, min_records=3).calibrate(
            s, independent=[10] * records, groups=np.repeat(np.arange(records), 10))
        if shape == "record":
            tail = lognormal_tail(s.reshape(records, 10), pf, law.threshold_)
        else:
            anchor = np.log(law.scale_ * special.chdtri(law.df_, pf))
            scale = law.scale_ * np.exp(anchor.mean() - anchor)
            tail = brute_tail(scale, law.df_, anchor.var(ddof=1), float(np.mean(2 / law.df_ / 10)), records,
                              law.threshold_)
        assert abs(tail / pf - 1) < 0.02, (records, shape, pf, tail / pf)
        assert law.pvalue(law.threshold_) == pytest.approx(pf, rel=1e-6)


def test_predictive_pvalue_is_zero_at_infinity_and_decreasing():
    """The predictive law's p-value: ~1 at 0, decreasing, and 0 at an infinite statistic (the interpolation grid
    ends near the float range; beyond it the grid's last p-value was returned)."""
    rng = np.random.default_rng(7)
    thr = ScaledChi2Threshold(0.01)
    stat = np.concatenate([rng.chisquare(5, size=20) * np.exp(0.1 * rng.standard_normal()) for _ in range(5)])
    thr.calibrate(stat[:, None], groups=np.repeat(np.arange(5), 20))
    p = thr.pvalue(np.array([0.0, 1.0, 10.0, 100.0, 1e6, 1e300, np.inf]))
    assert p[0] > 1 - 1e-9 and np.all(np.diff(p) < 0) and p[-1] == 0.0
    assert abs(float(thr.pvalue(thr.threshold_)) - 0.01) < 1e-9

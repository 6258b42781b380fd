"""Z-score test of a residual stream against its running (Welford) mean and variance (Keipour et al.)."""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
from scipy import special

from tsfdi._validation import float_like, int_like
from tsfdi.detection.base import ResidualTest, rescale_exponent
from tsfdi.detection.decision import Decision

__all__ = ["ZScore"]


@numba.njit(cache=True, nogil=True)
def _welford_z(x, burn_in, freeze):  # pragma: no cover - compiled
    """Z-score of x[t] against the mean / sample std of x[0..t-1] (Welford, eq. 8); NaN before ``burn_in``.

    With ``freeze`` the statistics stop at the first sample whose |z| exceeds ``freeze`` (> 0).
    """
    n = x.shape[0]
    z = np.full(n, np.nan)
    var = np.full(n, np.nan)
    mean = 0.0
    m2 = 0.0
    cnt = 0
    frozen = False
    for t in range(n):
        if cnt >= burn_in and cnt >= 2:
            sd = np.sqrt(m2 / (cnt - 1))
            z[t] = (x[t] - mean) / sd if sd > 0 else (np.inf if x[t] != mean else 0.0)
            if freeze > 0 and abs(z[t]) > freeze:
                frozen = True
        if not frozen:
            cnt += 1
            d = x[t] - mean
            mean += d / cnt
            m2 += d * (x[t] - mean)
        if cnt >= 2:
            var[t] = m2 / (cnt - 1)
    return z, var


class ZScore(ResidualTest):
    r"""Alarm when a residual sample lies more than ``threshold`` running standard deviations from the mean.

    Parameters
    ----------
    threshold : float, default 4.5
        Alarm bound on :math:`|z|`; 4.5 is the value of Keipour et al. (two-sided Gaussian tail
        :math:`2\,(1 - \Phi(4.5)) = 6.8 \cdot 10^{-6}` per sample, their "99.99931 %" interval).
    burn_in : int, default 50
        Samples used to start the running statistics before any Z-score is computed.
    freeze_on_alarm : bool, default True
        Stop updating mean and variance at the first alarm, so that the fault does not inflate them.

    Notes
    -----
    Running mean and variance by Welford's recursion (Keipour et al., eq. 8)

    .. math:: \bar x_n = \bar x_{n-1} + \frac{x_n - \bar x_{n-1}}{n}, \quad
              M_{2,n} = M_{2,n-1} + (x_n - \bar x_{n-1})(x_n - \bar x_n), \quad s_n^2 = \frac{M_{2,n}}{n-1},

    and :math:`z_t = (x_t - \bar x_{t-1}) / s_{t-1}`, i.e. each sample is scored against the statistics of the
    samples before it. ``alpha`` of the decision is the nominal per-sample two-sided Gaussian rate: alpha is the
    false-alarm probability per sample, not per window. Over ``N`` samples the false-alarm probability of the
    record is about ``N * alpha`` for iid Gaussian residuals.
    For a multi-channel decision (it rejects when any channel alarms) ``alpha`` is per channel and per sample: this
    test has no ``correction=``, so ``k`` channels give up to ``1 - (1 - alpha)^k`` per sample; give it ``alpha /
    k`` for a decision at ``alpha``.

    The Z-score does not depend on the scale of the residual: each channel is divided by a power of two before the
    recursion (exact), so values near 1e300 or 1e-300 give the scores of values near 1 (the running variance of
    ``details["variance"]`` is ``inf`` where it is itself beyond the float range, ``|resid|`` above about 1e154).
    A constant history (e.g. a frozen sensor during the burn-in) has a running standard deviation of 0: a sample
    equal to its mean scores 0, any other sample scores ``inf`` and alarms.
    The recursive model :class:`tsfdi.RecursiveARX` runs the same test online, armed by its stability gates.

    References
    ----------
    A. Keipour, M. Mousaei, S. Scherer, "Automatic real-time anomaly detection for autonomous aerial
    vehicles", ICRA 2019, eq. 8 and section V.B. B. P. Welford, Technometrics 4(3), 1962.
    """

    name = "Z-score"
    null_hypothesis = "every residual sample is drawn from the distribution of the earlier ones (healthy)"
    alternative_hypothesis = "some residual sample lies beyond threshold running standard deviations (fault)"

    def __init__(self, threshold: float = 4.5, *, burn_in: int = 50, freeze_on_alarm: bool = True) -> None:
        self.threshold = float_like(threshold, "threshold", minimum=0.0, strict_min=True)
        self.burn_in = int_like(burn_in, "burn_in", minimum=2)
        if not isinstance(freeze_on_alarm, (bool, np.bool_)):
            raise TypeError(f"freeze_on_alarm must be a bool, got {freeze_on_alarm!r}")
        self.freeze_on_alarm = bool(freeze_on_alarm)

    def __repr__(self) -> str:
        return f"ZScore(threshold={self.threshold:g}, burn_in={self.burn_in}, freeze_on_alarm={self.freeze_on_alarm})"

    @property
    def alpha(self) -> float:
        """Nominal two-sided Gaussian false-alarm rate of ``threshold`` :math:`t`, :math:`2(1 - \\Phi(t))`.

        alpha is the false-alarm probability per sample, not per window (nor per record).
        """
        return float(special.erfc(self.threshold / np.sqrt(2.0)))

    def zscores(self, resid: Any) -> Any:
        """Z-score series in the caller's data kind (NaN during the burn-in)."""
        sig = self._resid(resid, self.burn_in + 1, " (burn_in + 1)")
        return sig.wrap(self._scores(sig.values)[0], 0)

    def _scores(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Z-scores and running variances of every channel of ``x`` (rescaled by a power of two, see Notes)."""
        e = rescale_exponent(x)
        xu = np.ldexp(x, -e) if e.any() else x
        zs = np.empty(x.shape)
        vs = np.empty(x.shape)
        for c in range(x.shape[1]):
            zs[:, c], vs[:, c] = _welford_z(np.ascontiguousarray(xu[:, c]), self.burn_in,
                                            self.threshold if self.freeze_on_alarm else 0.0)
        if e.any():
            with np.errstate(over="ignore"):
                vs = np.ldexp(vs, 2 * e)                # inf where the variance is beyond the float range
        return zs, vs

    def test(self, resid: Any) -> Decision:
        """Score every sample of ``resid`` (per channel) and decide.

        Returns
        -------
        Decision
            ``statistic``: the largest :math:`|z|` per channel; ``threshold``; ``pvalue`` nan (the maximum over
            a record has no simple null distribution); ``alpha``: the per-sample rate. ``details``: ``"z"`` (the
            series, caller's kind), ``"alarms"`` (positions per channel), ``"first_alarm"`` (position per
            channel, -1 if none), ``"first_alarm_label"`` (index label or position), ``"variance"`` (running
            variance, caller's kind), ``"burn_in"``.
        """
        sig = self._resid(resid, self.burn_in + 1, " (burn_in + 1)")
        k = sig.nchan
        zs, vs = self._scores(sig.values)
        absz = np.abs(zs)
        alarm = np.nan_to_num(absz, nan=0.0) > self.threshold
        first = np.array([int(np.flatnonzero(alarm[:, c])[0]) if alarm[:, c].any() else -1 for c in range(k)])
        labels = [None if f < 0 else (sig.index[f] if sig.index is not None else int(f)) for f in first]
        details = {"z": sig.wrap(zs, 0), "variance": sig.wrap(vs, 0),
                   "alarms": [np.flatnonzero(alarm[:, c]) for c in range(k)],
                   "first_alarm": first, "first_alarm_label": labels, "burn_in": self.burn_in}
        return Decision(statistic=np.nanmax(absz, axis=0), threshold=np.full(k, self.threshold),
                        pvalue=np.full(k, np.nan), alpha=self.alpha, reject=bool(alarm.any()),
                        df=np.full(k, np.nan), nobs=sig.nobs, null_hypothesis=self.null_hypothesis,
                        alternative_hypothesis=self.alternative_hypothesis, details=details,
                        channel_reject=alarm.any(axis=0), channels=tuple(sig.channels), test="ZScore")

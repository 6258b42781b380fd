"""The windowed mean-shift test: has the residual mean moved away from zero over the window?"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import special

from tsfdi._validation import int_like
from tsfdi.detection.base import (ReferenceVarianceTest, baseline_variance, per_channel, rescale_exponent,
                                  scaled_ratio)
from tsfdi.detection.decision import Decision

__all__ = ["MeanTest"]


class MeanTest(ReferenceVarianceTest):
    r"""Test of a shift of the residual mean over a window (the GLRT of a mean change with a known onset).

    Parameters
    ----------
    alpha : float
        Type I risk per tested window, in (0, 1).
        For a multi-channel decision (it rejects when any channel rejects) ``alpha`` is the decision's false-alarm
        rate unless ``correction="none"``: by default (``"sidak"``) each of ``k`` channels is tested at
        ``1 - (1 - alpha)^(1/k)``; ``correction="none"`` tests each at ``alpha`` (paper 003), up to
        ``1 - (1 - alpha)^k`` for the decision.
    correction : {"sidak", "bonferroni", "none"}
        For vector residuals, test each of the ``k`` channels at :math:`1 - (1 - \alpha)^{1/k}` (``"sidak"``,
        default) or ``alpha / k`` (``"bonferroni"``), so that "some channel rejects" has size at most ``alpha``;
        ``"none"``: ``alpha`` per channel.
    threshold : {"theoretical", "calibrated", "empirical"} or an estimator
        ``"theoretical"``: the :math:`\chi^2(1)` quantile below (iid Gaussian residuals, exact baseline
        variance). ``"calibrated"`` / ``"empirical"``: set by :meth:`calibrate` from held-out residuals of
        healthy records (:meth:`~tsfdi.detection.base.CalibratedTest.calibrate`), which absorbs the residuals'
        autocorrelation and the record-to-record spread of the mean.

    Notes
    -----
    A fault that a closed loop compensates often leaves the residual *variance* and *whiteness* unchanged and
    moves its *level*: an attitude controller's integrator takes up the moment of a damaged propeller, so the
    commands settle on a new trim. With the baseline's residual variance :math:`\sigma_0^2` per channel, the
    window :math:`e_1 \dots e_n` gives

    .. math:: T = \frac{\left(\sum_{i=1}^{n} e_i\right)^2}{n\,\sigma_0^2} = 2 S_1^n ,

    twice the log-likelihood ratio :math:`S_j^k` of Hansen et al. (paper 002, eq. 2) for a jump :math:`A` of
    the mean at the window start, maximised over :math:`A` (:math:`\hat A = \bar e`). Under H0 (iid
    :math:`N(0, \sigma_0^2)` residuals) :math:`T \sim \chi^2(1)`: reject when
    :math:`T > \chi^2_{1-\alpha}(1)`, p-value :math:`P(\chi^2(1) > T)`. The scan over unknown change instants
    is :class:`~tsfdi.GLRT` (per sample); this test fixes the window, as the F and Ljung-Box tests do, so that
    all three share the windowed engine, the calibration and the identification rules.

    :math:`T` does not depend on the common scale of the residuals and ``reference_variance``: the residuals are
    rescaled by a power of two before the sum is squared (exact), and a :math:`T` beyond the float range is refused
    (``ValueError``: the reference variance cannot be the residual's). A constant window (a frozen sensor) is tested
    like any other: frozen away from zero its mean has moved (and it rejects when :math:`T` is large enough), frozen
    at zero :math:`T = 0`.

    References
    ----------
    Hansen, Blanke, Adrian (paper 002), eqs. 1-2. Kay, S. M., *Fundamentals of Statistical Signal
    Processing, Vol. II: Detection Theory*, section 6.4 (known variance, unknown level).
    """

    name = "mean-shift test"
    null_df = 1.0
    null_hypothesis = "residual mean is zero over the window (healthy / model fits)"
    alternative_hypothesis = "residual mean is not zero over the window (fault / model does not fit)"

    def __init__(self, alpha: float = 0.05, *, correction: str = "sidak", threshold: Any = "theoretical") -> None:
        self.alpha = self._check_alpha(alpha)
        self.correction = self._check_correction(correction)
        self.threshold = self._threshold_option(threshold)

    def __repr__(self) -> str:
        thr = "" if self.threshold == "theoretical" else f", threshold={self._threshold_name()!r}" + (
            f" (calibrated on {self.calibration_[0].size} windows)" if self.calibrated else " (not calibrated)")
        return f"MeanTest(alpha={self.alpha:g}, correction={self.correction!r}{thr})"

    # ------------------------------------------------------------------ reference variance
    def reference(self, results: Any) -> dict:
        """``reference_variance``: the baseline's unbiased residual variance ``RSS / (N0 - d)`` per channel."""
        var, _ = baseline_variance(results)
        return {"reference_variance": var}

    def _variance(self, reference_variance: Any, k: int) -> np.ndarray:
        # a calibrated test carries the variance it was calibrated with
        ref = getattr(self, "reference_variance_", reference_variance)
        if ref is None:
            raise TypeError("MeanTest needs reference_variance (the baseline's unbiased residual variance); "
                            "tsfdi.detect/identify take it from the model")
        return per_channel(ref, "reference_variance", k)

    # ------------------------------------------------------------------ statistic and rules
    def window_statistic(self, resid: Any, window: int, step: int = 1, reference_variance: Any = None,
                         **_: Any) -> np.ndarray:
        """:math:`T` of every sliding window (``window`` residual samples, ``step`` apart), shape
        (n_windows, k), from prefix sums."""
        sig = self._resid(resid, 1)
        ref = self._variance(reference_variance, sig.nchan)
        window = int_like(window, "window", minimum=1, maximum=sig.nobs)
        step = int_like(step, "step", minimum=1)
        starts = np.arange(0, sig.nobs - window + 1, step)
        scale = rescale_exponent(sig.values)
        e = np.ldexp(sig.values, -scale) if scale.any() else sig.values      # exact rescaling, see Notes
        c1 = np.concatenate([np.zeros((1, sig.nchan)), np.cumsum(e, axis=0)])
        s1 = c1[starts + window] - c1[starts]
        return scaled_ratio(s1 * s1 / window, ref, scale)

    def null_threshold(self, k: int, nobs: int | None = None, **reference: Any) -> np.ndarray:
        r""":math:`\chi^2_{1-\alpha}(1)` per channel (``alpha`` per channel after ``correction``)."""
        return np.full(k, special.chdtri(1.0, self._channel_alpha(self.alpha, k, self.correction)))

    def _null_pvalue(self, statistic: np.ndarray, nobs: int | None = None, **reference: Any) -> np.ndarray:
        return special.chdtrc(1.0, statistic)

    def _df(self, k: int, nobs: int, **reference: Any) -> np.ndarray:
        return np.ones(k)

    def _decision_details(self, k: int, reference_variance: Any = None, **reference: Any) -> dict:
        details: dict = {"channel_alpha": self._channel_alpha(self.alpha, k, self.correction),
                         "correction": self.correction}
        if reference_variance is not None:
            details["reference_variance"] = self._variance(reference_variance, k)
        return details

    def test(self, resid: Any, reference_variance: Any = None) -> Decision:
        """Test whether the mean of ``resid`` differs from zero.

        Parameters
        ----------
        resid : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, k)
            Current residuals (a signal driven through the fixed baseline model).
        reference_variance : float or array_like, shape (k,)
            Unbiased baseline residual variance per channel (:meth:`reference`).

        Returns
        -------
        Decision
            :meth:`~tsfdi.detection.base.CalibratedTest.decision` of :math:`T` per channel;
            ``details["mean"]`` holds the window mean per channel.
        """
        sig = self._resid(resid, 1)
        ref = self._variance(reference_variance, sig.nchan)
        scale = rescale_exponent(sig.values)
        e = np.ldexp(sig.values, -scale) if scale.any() else sig.values      # exact rescaling, see Notes
        total = e.sum(axis=0)
        stat = scaled_ratio(total * total / sig.nobs, ref, scale)
        return self.decision(stat, sig.nobs, tuple(sig.channels), details={"mean": np.ldexp(total / sig.nobs, scale)},
                             reference_variance=ref)

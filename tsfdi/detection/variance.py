"""Residual variance method: the F test of Dutta et al. (eqs. 8-11)."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import special

from tsfdi._validation import int_like, option
from tsfdi.detection.base import CalibratedTest, baseline_variance
from tsfdi.detection.decision import Decision

__all__ = ["FTest"]


class FTest(CalibratedTest):
    r"""Residual variance F test (Dutta et al., eqs. 8-11).

    Parameters
    ----------
    alpha : float
        Type I (false alarm) risk, in (0, 1), per channel.
    alternative : {"greater", "two-sided"}
        ``"greater"`` (the paper): H1 is a variance *increase*, reject when
        :math:`F > f_{1-\alpha}(N_u, N_0 - d)`. ``"two-sided"``: reject when
        :math:`F > f_{1-\alpha/2}` or :math:`F < f_{\alpha/2}`.
    demean : bool
        Subtract the mean of the current residual before estimating its variance; :math:`N_u` then becomes
        :math:`N_u - 1` (the paper's adjustment). The baseline's mean is accounted for by its ``d``
        (a fitted constant is one of the model's parameters), so its degrees of freedom are unchanged.
    correction : {None, "bonferroni"}
        For vector residuals, test each of the ``k`` channels at ``alpha / k`` so that the signal-level
        false-alarm rate is at most ``alpha``. ``None`` (the paper) uses ``alpha`` per channel.
    threshold : {"f", "empirical"} or EmpiricalThreshold
        ``"f"`` (the paper): the F quantile of eq. 10. ``"empirical"`` (``alternative="greater"`` only): the
        :math:`1-\alpha` quantile of the variance ratio on healthy (in-state) residual windows, estimated by
        :meth:`calibrate` (Hansen et al., paper 002, Fig. 2); decisions then report it and the empirical p-value.

    Attributes
    ----------
    threshold_ : ndarray, shape (k,)
        Calibrated threshold per channel (after :meth:`calibrate`, empirical threshold only).

    Notes
    -----
    Under H0 the current residuals :math:`e_{0u}` are iid :math:`N(0, \sigma_{00}^2)`, so
    :math:`N_u \hat\sigma_{0u}^2 / \sigma_{00}^2 \sim \chi^2(N_u)` and
    :math:`(N_0 - d) \hat\sigma_{00}^2 / \sigma_{00}^2 \sim \chi^2(N_0 - d)`, hence (eq. 9)

    .. math:: F = \hat\sigma_{0u}^2 / \hat\sigma_{00}^2 \sim F(N_u, N_0 - d)

    with :math:`\hat\sigma_{0u}^2 = \sum e_{0u}^2 / N_u` and :math:`\hat\sigma_{00}^2 = \mathrm{RSS}_0 / (N_0 - d)`.
    Fitted results store the maximum-likelihood variance ``RSS / nobs``; :func:`tsfdi.detect` converts it to
    ``RSS / df_resid`` (``df_resid = N_0 - d``) before calling :meth:`test`. Decision (eq. 10): accept H0
    when :math:`F \le f_{1-\alpha}(N_u, N_0 - d)`. Identification (eq. 11) uses the same test against each
    fault model's own baseline variance. For a VAR each channel is tested against the corresponding
    diagonal element of the residual covariance with ``d`` the number of parameters per equation.

    References
    ----------
    Dutta, McKay, Kopsaftopoulos, Gandhi, *Statistical Time Series Methods for Multicopter Fault Detection
    and Identification*, eqs. 8-11. Hansen, Blanke, Adrian (paper 002), Fig. 2 (empirical threshold).
    """

    name = "F test (residual variance)"
    _analytic = "f"

    def __init__(self, alpha: float = 0.05, *, alternative: str = "greater", demean: bool = False,
                 correction: str | None = None, threshold: Any = "f") -> None:
        self.alpha = self._check_alpha(alpha)
        self.alternative = option(alternative, "alternative", ("greater", "two-sided"))
        if not isinstance(demean, (bool, np.bool_)):
            raise TypeError(f"demean must be a bool, got {demean!r}")
        self.demean = bool(demean)
        self.correction = self._check_correction(correction)
        self.threshold = self._threshold_option(threshold)
        if self.empirical and self.alternative != "greater":
            raise ValueError("threshold='empirical' needs alternative='greater' (one upper quantile)")

    def __repr__(self) -> str:
        thr = "" if self.threshold == "f" else ", threshold='empirical'" + (
            f" (calibrated on {self.calibration_[0].size})" if self.calibrated else " (not calibrated)")
        return (f"FTest(alpha={self.alpha:g}, alternative={self.alternative!r}, demean={self.demean}, "
                f"correction={self.correction!r}{thr})")

    def window_statistic(self, resid: Any, window: int, step: int = 1, reference_variance: Any = None,
                         **_: Any) -> np.ndarray:
        """Variance ratio ``F`` of every sliding window (``window`` residual samples, ``step`` apart) against
        ``reference_variance``, shape (n_windows, k), from prefix sums."""
        sig = self._resid(resid, 3 if self.demean else 2)
        if reference_variance is None:
            raise TypeError("FTest.window_statistic needs reference_variance (the baseline's unbiased variance)")
        e = sig.values
        k = sig.nchan
        ref = _per_channel(reference_variance, "reference_variance", k)
        window = int_like(window, "window", minimum=3 if self.demean else 2, maximum=sig.nobs)
        step = int_like(step, "step", minimum=1)
        starts = np.arange(0, sig.nobs - window + 1, step)
        zero = np.zeros((1, k))
        c2 = np.concatenate([zero, np.cumsum(e * e, axis=0)])
        ss = c2[starts + window] - c2[starts]
        if self.demean:
            c1 = np.concatenate([zero, np.cumsum(e, axis=0)])
            s1 = c1[starts + window] - c1[starts]
            var_u = (ss - s1 * s1 / window) / (window - 1)
        else:
            var_u = ss / window
        return var_u / ref

    def _null_threshold(self, k: int, nobs: int, reference_df: Any = None, **_: Any) -> np.ndarray:
        """Upper critical value :math:`f_{1-\\alpha}(N_u, N_0 - d)` of eq. 10 per channel for ``nobs`` current
        residual samples (:math:`N_u = ` ``nobs - 1`` with ``demean``), shape (k,)."""
        if reference_df is None:
            raise TypeError("FTest needs reference_df (the baseline's N0 - d); tsfdi.detect/identify take it from "
                            "the model")
        df0 = _per_channel(reference_df, "reference_df", k)
        nu = float(nobs - 1 if self.demean else nobs)
        return special.fdtri(nu, df0, 1.0 - self._channel_alpha(self.alpha, k, self.correction))

    def _threshold_pvalue(self, f: np.ndarray, nobs: int, reference_df: Any = None,
                          **_: Any) -> tuple[np.ndarray, np.ndarray]:
        """Threshold (k,) and p-values (shape of ``f``, channels on the last axis) of the one-sided test of
        ``nobs``-sample variance ratios: calibrated threshold and empirical p-value, or the F ones (eq. 10)."""
        f = np.asarray(f, dtype=np.float64)
        k = f.shape[-1]
        if self.empirical:
            self._check_calibrated(k)
            return self.threshold_, self.empirical_pvalue(f)
        df0 = _per_channel(reference_df, "reference_df", k)
        nu = float(nobs - 1 if self.demean else nobs)
        return self._null_threshold(k, nobs, df0), special.fdtrc(nu, df0, f)

    @property
    def null_hypothesis(self) -> str:  # type: ignore[override]
        if self.alternative == "greater":
            return "residual variance <= baseline variance (healthy / model fits)"
        return "residual variance = baseline variance (healthy / model fits)"

    @property
    def alternative_hypothesis(self) -> str:  # type: ignore[override]
        if self.alternative == "greater":
            return "residual variance > baseline variance (fault / model does not fit)"
        return "residual variance != baseline variance (fault / model does not fit)"

    def reference(self, results: Any) -> dict:
        """``reference_variance`` (unbiased, ``RSS / (N0 - d)``) and ``reference_df`` (``N0 - d``)."""
        var, df = baseline_variance(results)
        return {"reference_variance": var, "reference_df": df}

    def test(self, resid: Any, reference_variance: Any = None, reference_df: Any = None) -> Decision:
        """Test whether the variance of ``resid`` exceeds the baseline's.

        Parameters
        ----------
        resid : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, k)
            Current residuals :math:`e_{Vu}` (a signal driven through the fixed baseline model).
        reference_variance : float or array_like, shape (k,)
            Unbiased baseline residual variance :math:`\\hat\\sigma_{VV}^2 = RSS/(N_0 - d)` per channel.
        reference_df : int or array_like, shape (k,)
            Its degrees of freedom :math:`N_0 - d`.

        Returns
        -------
        Decision
        """
        sig = self._resid(resid, 3 if self.demean else 2)
        e = sig.values
        k = sig.nchan
        if reference_variance is None or reference_df is None:
            raise TypeError("FTest.test needs reference_variance and reference_df (the baseline's unbiased "
                            "residual variance and N0 - d); tsfdi.detect/identify take them from the model")
        ref = _per_channel(reference_variance, "reference_variance", k)
        df0 = _per_channel(reference_df, "reference_df", k)
        n = e.shape[0]
        if self.demean:
            nu = n - 1
            var_u = np.sum((e - e.mean(axis=0)) ** 2, axis=0) / nu
        else:
            nu = n
            var_u = np.einsum("ij,ij->j", e, e) / nu
        f = var_u / ref
        a = self._channel_alpha(self.alpha, k, self.correction)
        dfn = np.full(k, float(nu))
        details: dict = {"variance": var_u, "reference_variance": ref, "alternative": self.alternative,
                         "demean": self.demean, "channel_alpha": a, "correction": self.correction,
                         "threshold_method": "f"}
        if self.empirical or self.alternative == "greater":
            thr, pv = self._threshold_pvalue(f, n, reference_df=df0)
            rej = f > thr
            if self.empirical:
                details.update(self._empirical_details())
        else:
            thr = special.fdtri(dfn, df0, 1.0 - a / 2)
            lower = special.fdtri(dfn, df0, a / 2)
            pv = np.minimum(1.0, 2 * np.minimum(special.fdtr(dfn, df0, f), special.fdtrc(dfn, df0, f)))
            rej = (f > thr) | (f < lower)
            details["lower_threshold"] = lower
        return Decision(statistic=f, threshold=thr, pvalue=pv, alpha=self.alpha, reject=bool(rej.any()),
                        df=np.column_stack([dfn, df0]), nobs=n, null_hypothesis=self.null_hypothesis,
                        alternative_hypothesis=self.alternative_hypothesis, details=details,
                        channel_reject=rej, channels=tuple(sig.channels), test="FTest")


def _per_channel(value: Any, name: str, k: int) -> np.ndarray:
    """A positive finite scalar or one value per channel, as a ``(k,)`` float array."""
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(k, float(arr))
    if arr.shape != (k,):
        raise ValueError(f"{name} must be a scalar or have one value per channel ({k}), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(f"{name} must be finite and > 0, got {arr}")
    return arr

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
        Type I (false alarm) risk, in (0, 1): the type I risk per tested window (per channel). Over many
        windows of a healthy record about ``alpha`` of them reject in each channel.
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
    threshold : {"theoretical", "empirical"} or EmpiricalThreshold
        ``"theoretical"`` (the paper): the F quantile of eq. 10. ``"empirical"`` (``alternative="greater"`` only): the
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

    def __init__(self, alpha: float = 0.05, *, alternative: str = "greater", demean: bool = False,
                 correction: str | None = None, threshold: Any = "theoretical") -> None:
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
        thr = "" if self.threshold == "theoretical" else f", threshold={self._threshold_name()!r}" + (
            f" (calibrated on {self.calibration_[0].size} windows)" if self.calibrated else " (not calibrated)")
        return (f"FTest(alpha={self.alpha:g}, alternative={self.alternative!r}, demean={self.demean}, "
                f"correction={self.correction!r}{thr})")

    def window_statistic(self, resid: Any, window: int, step: int = 1, reference_variance: Any = None,
                         **_: Any) -> np.ndarray:
        """Variance ratio ``F`` of every sliding window (``window`` residual samples, ``step`` apart) against
        ``reference_variance``, shape (n_windows, k), from prefix sums."""
        sig = self._resid(resid, 3 if self.demean else 2)
        # a calibrated test carries the variance it was calibrated with
        reference_variance = getattr(self, "reference_variance_", reference_variance)
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

    def null_threshold(self, k: int, nobs: int | None = None, reference_df: Any = None,
                       **reference: Any) -> np.ndarray:
        r"""Upper critical value of the F test under H0 (Dutta et al., paper 003, eqs. 9-10).

        Parameters
        ----------
        k : int
            Number of channels (with ``correction="bonferroni"`` each is tested at ``alpha / k``).
        nobs : int
            Current residual samples per window; :math:`N_u` = ``nobs`` (``nobs - 1`` with ``demean``).
        reference_df : int or array_like, shape (k,)
            Degrees of freedom :math:`N_0 - d` of the baseline variance (from :meth:`reference`).
        **reference :
            Other entries of :meth:`reference` (``reference_variance``), ignored.

        Returns
        -------
        ndarray, shape (k,)
            :math:`f_{1-\alpha}(N_u, N_0 - d)`, the :math:`1 - \alpha` quantile of the F law of the variance
            ratio (eq. 9); ``alpha`` is the type I risk per tested window (per channel). H0 is accepted when
            :math:`F \le f_{1-\alpha}(N_u, N_0 - d)` (eq. 10). One-sided (``alternative="greater"``); the
            two-sided limits are in :meth:`decision`.
        """
        if reference_df is None:
            raise TypeError("FTest needs reference_df (the baseline's N0 - d); tsfdi.detect/identify take it from "
                            "the model")
        if nobs is None:
            raise TypeError("FTest needs nobs (the number of current residual samples per window) for its "
                            "theoretical threshold")
        df0 = _per_channel(reference_df, "reference_df", k)
        return special.fdtri(self._nu(nobs), df0, 1.0 - self._channel_alpha(self.alpha, k, self.correction))

    def _nu(self, nobs: int) -> float:
        """:math:`N_u`: the current residual's degrees of freedom (``nobs - 1`` with ``demean``)."""
        return float(nobs - 1 if self.demean else nobs)

    def _null_pvalue(self, statistic: np.ndarray, nobs: int | None = None, reference_df: Any = None,
                     **reference: Any) -> np.ndarray:
        r""":math:`P(\mathcal F(N_u, N_0 - d) > F)` (eq. 9), same shape as ``statistic``."""
        df0 = _per_channel(reference_df, "reference_df", statistic.shape[-1])
        return special.fdtrc(self._nu(nobs), df0, statistic)

    def _df(self, k: int, nobs: int, reference_df: Any = None, **reference: Any) -> np.ndarray:
        df0 = np.full(k, np.nan) if reference_df is None else _per_channel(reference_df, "reference_df", k)
        return np.column_stack([np.full(k, self._nu(nobs)), df0])

    def _decision_details(self, k: int, reference_variance: Any = None, **reference: Any) -> dict:
        details: dict = {} if reference_variance is None else {
            "reference_variance": _per_channel(reference_variance, "reference_variance", k)}
        details.update({"alternative": self.alternative, "demean": self.demean,
                        "channel_alpha": self._channel_alpha(self.alpha, k, self.correction),
                        "correction": self.correction})
        return details

    def decision(self, statistic: Any, nobs: int, channels: Any = None, *, details: dict | None = None,
                 **reference: Any) -> Decision:
        r"""The :class:`~tsfdi.Decision` of one variance ratio per channel (what :meth:`test` returns).

        Parameters
        ----------
        statistic : array_like, shape (k,)
            Variance ratios :math:`F = \hat\sigma_{0u}^2 / \hat\sigma_{00}^2` of one window, per channel.
        nobs : int
            Number of current residual samples in the window (:math:`N_u`, ``nobs - 1`` with ``demean``).
        channels : sequence of str, optional
            Channel names (default ``y0, y1, ...``).
        details : dict, optional
            Extra entries placed first in ``Decision.details`` (:meth:`test` passes the window variances).
        **reference :
            ``reference_df`` (:math:`N_0 - d`, needed by the theoretical threshold) and optionally
            ``reference_variance`` (reported in the details), as given by :meth:`reference`.

        Returns
        -------
        Decision
            ``df`` holds :math:`(N_u, N_0 - d)` per channel. ``"greater"``: channel ``c`` rejects when
            :math:`F_c > f_{1-\alpha}(N_u, N_0 - d)` (eq. 10), or the calibrated threshold
            (:meth:`threshold_pvalue`). ``"two-sided"``: it rejects when :math:`F_c > f_{1-\alpha/2}` or
            :math:`F_c < f_{\alpha/2}` (``details["lower_threshold"]``), with p-value
            :math:`\min(1, 2 \min(P(\mathcal F \le F), P(\mathcal F > F)))`.

        Notes
        -----
        Dutta et al. (paper 003), eqs. 8-11: the same rule serves detection (eq. 10, against the healthy
        baseline) and identification (eq. 11, against each fault model's own baseline variance).
        """
        if self.empirical or self.alternative == "greater":
            return super().decision(statistic, nobs, channels, details=details, **reference)
        f = np.array(statistic, dtype=np.float64, ndmin=1)
        if f.ndim != 1:
            raise ValueError(f"statistic must hold one value per channel, got shape {f.shape}")
        k = f.shape[0]
        reference_df = reference.get("reference_df")
        if reference_df is None:
            raise TypeError("FTest needs reference_df (the baseline's N0 - d); tsfdi.detect/identify take it from "
                            "the model")
        df0 = _per_channel(reference_df, "reference_df", k)
        a = self._channel_alpha(self.alpha, k, self.correction)
        dfn = np.full(k, self._nu(nobs))
        info = dict(details) if details else {}
        info.update(self._decision_details(k, **reference))
        info["threshold_method"] = self._theoretical
        thr = special.fdtri(dfn, df0, 1.0 - a / 2)
        lower = special.fdtri(dfn, df0, a / 2)
        pv = np.minimum(1.0, 2 * np.minimum(special.fdtr(dfn, df0, f), special.fdtrc(dfn, df0, f)))
        rej = (f > thr) | (f < lower)
        info["lower_threshold"] = lower
        return Decision(statistic=f, threshold=thr, pvalue=pv, alpha=self.alpha, reject=bool(rej.any()),
                        df=np.column_stack([dfn, df0]), nobs=nobs, null_hypothesis=self.null_hypothesis,
                        alternative_hypothesis=self.alternative_hypothesis, details=info,
                        channel_reject=rej, channels=tuple(channels) if channels is not None else (),
                        test=type(self).__name__)

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
            :meth:`decision` of the variance ratio :math:`F` of ``resid`` (eq. 9); ``details["variance"]`` holds
            :math:`\\hat\\sigma_{Vu}^2` per channel.
        """
        sig = self._resid(resid, 3 if self.demean else 2)
        e = sig.values
        k = sig.nchan
        # a calibrated test carries the variance it was calibrated with
        reference_variance = getattr(self, "reference_variance_", reference_variance)
        if reference_variance is None or (reference_df is None and not self.empirical):
            raise TypeError("FTest.test needs reference_variance and reference_df (the baseline's unbiased "
                            "residual variance and N0 - d); tsfdi.detect/identify take them from the model")
        ref = _per_channel(reference_variance, "reference_variance", k)
        extra = {} if reference_df is None else {"reference_df": _per_channel(reference_df, "reference_df", k)}
        n = e.shape[0]
        if self.demean:
            nu = n - 1
            var_u = np.sum((e - e.mean(axis=0)) ** 2, axis=0) / nu
        else:
            nu = n
            var_u = np.einsum("ij,ij->j", e, e) / nu
        f = var_u / ref
        return self.decision(f, n, tuple(sig.channels), details={"variance": var_u}, reference_variance=ref,
                             **extra)

    def _calibration_reference(self, recs: list, reference: dict) -> dict:
        """The variance the calibrated test divides by, kept as ``reference_variance_``: the given
        ``reference_variance`` (a baseline's), else the pooled mean square of the calibration residuals per
        channel (held-out residuals need no baseline variance: the calibrated law absorbs the scale)."""
        ref = reference.get("reference_variance")
        sigs = [self._resid(r, 2) for r in recs]
        if ref is None:
            ss = sum(np.einsum("ij,ij->j", s.values, s.values) for s in sigs)
            ref = ss / sum(s.nobs for s in sigs)
        self.reference_variance_ = _per_channel(ref, "reference_variance", sigs[0].nchan)
        return {**reference, "reference_variance": self.reference_variance_}


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

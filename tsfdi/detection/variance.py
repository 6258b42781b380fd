"""Residual variance method: the F test of Dutta et al. (eqs. 8-11)."""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
from scipy import special

from tsfdi._validation import int_like, option
from tsfdi.detection.base import (ReferenceVarianceTest, baseline_variance, per_channel, rescale_exponent, scaled_ratio,
                                  statistic_array)
from tsfdi.detection.decision import Decision

__all__ = ["FTest"]


class FTest(ReferenceVarianceTest):
    r"""Residual variance F test (Dutta et al., eqs. 8-11).

    Parameters
    ----------
    alpha : float
        Type I (false alarm) risk, in (0, 1), per tested window. Over many windows of a healthy record about
        ``alpha`` of them reject.
        For a multi-channel decision (it rejects when any channel rejects) ``alpha`` is the decision's false-alarm
        rate unless ``correction="none"``: by default (``"sidak"``) each of ``k`` channels is tested at
        ``1 - (1 - alpha)^(1/k)``; ``correction="none"`` tests each at ``alpha`` (paper 003), up to
        ``1 - (1 - alpha)^k`` for the decision.
    alternative : {"greater", "two-sided"}
        ``"greater"`` (the paper): H1 is a variance *increase*, reject when
        :math:`F > f_{1-\alpha}(N_u, N_0 - d)`. ``"two-sided"``: reject when
        :math:`F > f_{1-\alpha/2}` or :math:`F < f_{\alpha/2}`.
    demean : bool
        Subtract the mean of the current residual before estimating its variance; :math:`N_u` then becomes
        :math:`N_u - 1` (the paper's adjustment). The baseline's mean is accounted for by its ``d``
        (a fitted constant is one of the model's parameters), so its degrees of freedom are unchanged.
    correction : {"sidak", "bonferroni", "none"}
        For vector residuals, test each of the ``k`` channels at :math:`1 - (1 - \alpha)^{1/k}` (``"sidak"``,
        default) or ``alpha / k`` (``"bonferroni"``) so that the signal-level false-alarm rate is at most
        ``alpha``; ``"none"`` (the paper) uses ``alpha`` per channel.
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

    Numerics: the residuals are rescaled by a power of two before they are squared and the reference variance by
    its square (exact), so that :math:`F` does not depend on the common scale of ``resid`` and
    ``reference_variance`` (values near 1e300 or 1e-300 give the :math:`F` of values near 1); a ratio beyond the
    float range (above about 1.8e308: the reference variance cannot be the residual's) is refused
    (``ValueError``). Thresholds are inverses of the upper tail of the F law (:func:`f_isf`; the lower limit of
    ``"two-sided"`` that of :math:`\mathcal F(N_0 - d, N_u)` at :math:`1 / F`), so that they hold down to
    ``alpha = 1e-300`` (inverting the lower tail at ``1 - alpha`` loses every digit of ``alpha`` below about
    1e-16), and p-values below 1e-250 are computed in log space (:func:`f_sf`).

    **A constant window** (a frozen sensor) has :math:`\hat\sigma_{0u}^2 = 0` with ``demean=True`` (exactly, in
    :meth:`test` and in :meth:`window_statistic` alike), so :math:`F = 0`: ``"greater"`` does not reject it (the
    variance did not increase) and ``"two-sided"`` rejects it with p-value 0. Without ``demean`` a constant
    window is tested by its mean square like any other. The Ljung-Box test rejects constant windows
    (:class:`~tsfdi.LjungBox`).

    References
    ----------
    Dutta, McKay, Kopsaftopoulos, Gandhi, *Statistical Time Series Methods for Multicopter Fault Detection
    and Identification*, eqs. 8-11. Hansen, Blanke, Adrian (paper 002), Fig. 2 (empirical threshold).
    """

    name = "F test (residual variance)"
    #: records differ by their noise level: a change of scale of the variance ratio (one shape for every record)
    null_shape = "pooled"

    def __init__(self, alpha: float = 0.05, *, alternative: str = "greater", demean: bool = False,
                 correction: str = "sidak", threshold: Any = "theoretical") -> None:
        self.alpha = self._check_alpha(alpha)
        self.alternative = option(alternative, "alternative", ("greater", "two-sided"))
        if not isinstance(demean, (bool, np.bool_)):
            raise TypeError(f"demean must be a bool, got {demean!r}")
        self.demean = bool(demean)
        self.correction = self._check_correction(correction)
        self.threshold = self._threshold_option(threshold)
        if self.empirical and self.alternative != "greater":
            raise ValueError("threshold='empirical' needs alternative='greater' (one upper quantile)")

    @property
    def min_resid(self) -> int:
        """Fewest residual samples :meth:`test` accepts: 3 with ``demean`` (two degrees of freedom), else 2."""
        return 3 if self.demean else 2

    def __repr__(self) -> str:
        thr = "" if self.threshold == "theoretical" else f", threshold={self._threshold_name()!r}" + (
            f" (calibrated on {self.calibration_[0].size} windows)" if self.calibrated else " (not calibrated)")
        return (f"FTest(alpha={self.alpha:g}, alternative={self.alternative!r}, demean={self.demean}, "
                f"correction={self.correction!r}{thr})")

    def window_statistic(self, resid: Any, window: int, step: int = 1, reference_variance: Any = None,
                         **_: Any) -> np.ndarray:
        """Variance ratio ``F`` of every sliding window (``window`` residual samples, ``step`` apart) against
        ``reference_variance``, shape (n_windows, k), from prefix sums."""
        sig = self._resid(resid, self.min_resid)
        # a calibrated test carries the variance it was calibrated with
        reference_variance = getattr(self, "reference_variance_", reference_variance)
        if reference_variance is None:
            raise TypeError("FTest.window_statistic needs reference_variance (the baseline's unbiased variance)")
        k = sig.nchan
        ref = per_channel(reference_variance, "reference_variance", k)
        window = int_like(window, "window", minimum=3 if self.demean else 2, maximum=sig.nobs)
        step = int_like(step, "step", minimum=1)
        e = sig.values
        scale = np.zeros(k, dtype=np.int32)
        zero = np.zeros((1, k))
        with np.errstate(over="ignore", under="ignore"):
            c2 = np.concatenate([zero, np.cumsum(e * e, axis=0)])
        total = c2[-1]
        if not ((total > 2.0 ** -512) & (total < np.inf)).all() and not all(
                2.0 ** -512 < t < np.inf or not e[:, c].any() for c, t in enumerate(total)):
            # squares beyond the float range, or so small that they lose digits: rescale (exact), see Notes
            scale = rescale_exponent(e)
            e = np.ldexp(e, -scale)
            c2 = np.concatenate([zero, np.cumsum(e * e, axis=0)])
        starts = np.arange(0, sig.nobs - window + 1, step)
        ends = starts + window
        ss = c2[ends] - c2[starts]
        if self.demean:
            c1 = np.concatenate([zero, np.cumsum(e, axis=0)])
            s1 = c1[ends] - c1[starts]
            ss = ss - s1 * s1 / window
        # a difference of prefix sums keeps only the digits the sums before the window leave: windows whose sum of
        # squares is below 1e-6 of the prefix sum at their end (a quiet or constant stretch) are summed directly
        if not ss.min() > 1e-6 * c2[-1].max():         # else no window can be (c2 only grows)
            direct = ss <= 1e-6 * c2[ends]
            for c in np.flatnonzero(direct.any(axis=0)):
                rows = np.flatnonzero(direct[:, c])
                ss[rows, c] = _sum_squares(e[:, c], starts[rows], window, self.demean)
        return scaled_ratio(ss / (window - 1 if self.demean else window), ref, scale)

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
            ratio (eq. 9); :math:`\alpha` is each channel's risk per tested window (``alpha`` shared by the
            ``k`` channels by ``correction``). H0 is accepted when
            :math:`F \le f_{1-\alpha}(N_u, N_0 - d)` (eq. 10). One-sided (``alternative="greater"``); the
            two-sided limits are in :meth:`decision`.
        """
        if reference_df is None:
            raise TypeError("FTest needs reference_df (the baseline's N0 - d); tsfdi.detect/identify take it from "
                            "the model")
        if nobs is None:
            raise TypeError("FTest needs nobs (the number of current residual samples per window) for its "
                            "theoretical threshold")
        df0 = per_channel(reference_df, "reference_df", k)
        nu, a = self._nu(nobs), self._channel_alpha(self.alpha, k, self.correction)
        key = (nu, tuple(df0), a)
        cache = self.__dict__.setdefault("_thr_cache", {})    # the same windows again: cache the critical values
        if key not in cache:
            if len(cache) >= 64:
                cache.clear()
            cache[key] = f_isf(nu, df0, a)
        return cache[key].copy()

    def _nu(self, nobs: int) -> float:
        """:math:`N_u`: the current residual's degrees of freedom (``nobs - 1`` with ``demean``)."""
        return float(nobs - 1 if self.demean else nobs)

    def _null_pvalue(self, statistic: np.ndarray, nobs: int | None = None, reference_df: Any = None,
                     **reference: Any) -> np.ndarray:
        r""":math:`P(\mathcal F(N_u, N_0 - d) > F)` (eq. 9), same shape as ``statistic``."""
        df0 = per_channel(reference_df, "reference_df", statistic.shape[-1])
        return f_sf(self._nu(nobs), df0, statistic)

    def _df(self, k: int, nobs: int, reference_df: Any = None, **reference: Any) -> np.ndarray:
        df0 = np.full(k, np.nan) if reference_df is None else per_channel(reference_df, "reference_df", k)
        return np.column_stack([np.full(k, self._nu(nobs)), df0])

    def _decision_details(self, k: int, reference_variance: Any = None, **reference: Any) -> dict:
        details: dict = {} if reference_variance is None else {
            "reference_variance": per_channel(reference_variance, "reference_variance", k)}
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
        f = np.atleast_1d(statistic_array(statistic))
        if f.ndim != 1 or np.isnan(f).any():
            raise ValueError(f"statistic must hold one number (not NaN) per channel, got {f}")
        k = f.shape[0]
        reference_df = reference.get("reference_df")
        if reference_df is None:
            raise TypeError("FTest needs reference_df (the baseline's N0 - d); tsfdi.detect/identify take it from "
                            "the model")
        df0 = per_channel(reference_df, "reference_df", k)
        a = self._channel_alpha(self.alpha, k, self.correction)
        dfn = np.full(k, self._nu(nobs))
        info = dict(details) if details else {}
        info.update(self._decision_details(k, **reference))
        info["threshold_method"] = self._theoretical
        # the lower tail of F(N_u, N_0 - d) is the upper tail of F(N_0 - d, N_u) at 1 / F
        thr = f_isf(dfn, df0, a / 2)
        with np.errstate(divide="ignore", over="ignore"):     # 1 / 0 = inf, 1 / subnormal = inf: tails of 0
            lower = 1.0 / f_isf(df0, dfn, a / 2)
            pv = np.minimum(1.0, 2 * np.minimum(f_sf(df0, dfn, 1.0 / f), f_sf(dfn, df0, f)))
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
            :math:`\\hat\\sigma_{Vu}^2` per channel (``inf`` if it is beyond the float range, ``|resid|`` above
            about 1e154, while :math:`F` is not).
        """
        sig = self._resid(resid, self.min_resid)
        e = sig.values
        k = sig.nchan
        # a calibrated test carries the variance it was calibrated with
        reference_variance = getattr(self, "reference_variance_", reference_variance)
        if reference_variance is None or (reference_df is None and not self.empirical):
            raise TypeError("FTest.test needs reference_variance and reference_df (the baseline's unbiased "
                            "residual variance and N0 - d); tsfdi.detect/identify take them from the model")
        ref = per_channel(reference_variance, "reference_variance", k)
        extra = {} if reference_df is None else {"reference_df": per_channel(reference_df, "reference_df", k)}
        n = e.shape[0]
        scale = rescale_exponent(e)
        if scale.any():
            e = np.ldexp(e, -scale)                     # exact rescaling: squares neither overflow nor underflow
        if self.demean:
            nu = n - 1
            var_u = np.sum((e - e.mean(axis=0)) ** 2, axis=0) / nu
            var_u[e.max(axis=0) == e.min(axis=0)] = 0.0   # a constant window, whatever the rounding of its mean
        else:
            nu = n
            var_u = np.einsum("ij,ij->j", e, e) / nu
        f = scaled_ratio(var_u, ref, scale)
        if scale.any():
            with np.errstate(over="ignore"):
                var_u = np.ldexp(var_u, 2 * scale)        # inf when the variance itself is beyond the float range
        return self.decision(f, n, tuple(sig.channels), details={"variance": var_u}, reference_variance=ref,
                             **extra)



#: Below this probability scipy's incomplete beta function (``fdtrc``, ``betaincinv``) loses its digits (it may be
#: off by a factor of 2 near 1e-300, or return NaN); the tail is then computed in log space (:func:`_log_beta_tail`).
_LOG_SPACE_BELOW = 1e-250


def _log_beta_tail(a: np.ndarray, b: np.ndarray, log_y: np.ndarray) -> np.ndarray:
    r""":math:`\ln I_y(a, b)` (the lower tail of :math:`B(a, b)` at :math:`y = e^{\text{log\_y}}`) for
    :math:`y < (a + 1) / (a + b + 2)`: the prefactor :math:`y^a (1-y)^b / (a B(a, b))` in log space times the
    continued fraction of the incomplete beta function (:func:`_beta_fraction`)."""
    y = np.exp(log_y)
    flat = [np.ascontiguousarray(v, dtype=np.float64).ravel() for v in np.broadcast_arrays(a, b, y)]
    h = _beta_fraction(*flat).reshape(np.shape(y))
    return a * log_y + b * np.log1p(-y) - special.betaln(a, b) - np.log(a) + np.log(h)


@numba.njit(cache=True, nogil=True)
def _beta_fraction(a: np.ndarray, b: np.ndarray, y: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """The continued fraction of the incomplete beta function :math:`I_y(a, b)` (Numerical Recipes' ``betacf``,
    modified Lentz), element by element until its last factor is within 1e-15 of 1 (at most 4,999 terms);
    compiled: the far tails of a fleet's F tests call it for thousands of windows."""
    tiny = 1e-300
    out = np.empty(y.size)
    for i in range(y.size):
        ai, bi, yi = a[i], b[i], y[i]
        qab, qap, qam = ai + bi, ai + 1.0, ai - 1.0
        c = 1.0
        d = 1.0 - qab * yi / qap
        d = 1.0 / (tiny if abs(d) < tiny else d)
        h = d
        for m in range(1, 5000):
            for even in (True, False):
                if even:
                    an = m * (bi - m) * yi / ((qam + 2 * m) * (ai + 2 * m))
                else:
                    an = -(ai + m) * (qab + m) * yi / ((ai + 2 * m) * (qap + 2 * m))
                d = 1.0 + an * d
                d = 1.0 / (tiny if abs(d) < tiny else d)
                c = 1.0 + an / c
                c = tiny if abs(c) < tiny else c
                h = h * d * c
            if abs(d * c - 1.0) < 1e-15:
                break
        out[i] = h
    return out


#: Ratio of the degrees of freedom from which the F law is its chi-square limit, :math:`\mathcal F(n, d) \to
#: \chi^2(n) / n` as :math:`d \to \infty` (``d >= _CHI2_LIMIT_FROM * max(n, 100)``; relative error of the quantiles
#: below about 1e-7 down to alpha = 1e-300): scipy's incomplete beta function loses digits beyond about 1e11 degrees
#: of freedom (1e-4 at 1e14) and gives NaN beyond 1e200.
_CHI2_LIMIT_FROM = 1e8


def _large(df: np.ndarray, other: np.ndarray) -> np.ndarray:
    """Where ``df`` is so much larger than ``other`` that the F law is its chi-square limit in ``df``."""
    return df / _CHI2_LIMIT_FROM >= np.maximum(other, 100.0)


def _f_limit(dfn: np.ndarray, dfd: np.ndarray, v: np.ndarray, quantile: bool, exact: Any) -> np.ndarray:
    r""":func:`f_isf` (``quantile``: ``v`` is alpha) or :func:`f_sf` (``v`` is the statistic) where one degree of
    freedom is far larger than the other (:func:`_large`): the chi-square limits :math:`\mathcal F(n, \infty) =
    \chi^2(n) / n` and :math:`\mathcal F(\infty, d) = d / \chi^2(d)` (the inverse incomplete gamma functions keep
    the digits of alpha down to 1e-300); ``exact`` elsewhere."""
    out = np.empty(dfn.shape)
    big_d, big_n = _large(dfd, dfn), _large(dfn, dfd)
    rest = ~(big_d | big_n)
    if rest.any():
        out[rest] = exact(dfn[rest], dfd[rest], v[rest])
    upper, lower = ((special.gammainccinv, special.gammaincinv) if quantile else
                    (special.gammaincc, special.gammainc))
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        m = big_d & ~big_n                              # chi2(n) / n
        if quantile:
            out[m] = 2.0 * upper(dfn[m] / 2, v[m]) / dfn[m]
        else:
            out[m] = upper(dfn[m] / 2, dfn[m] * v[m] / 2)
        m = big_n & ~big_d                              # d / chi2(d): upper tail of F is the lower tail of chi2(d)
        if quantile:
            out[m] = dfd[m] / (2.0 * lower(dfd[m] / 2, v[m]))
        else:
            out[m] = lower(dfd[m] / 2, dfd[m] / (2.0 * v[m]))
    return out


#: smallest alpha for which ``scipy.special.fdtri(dfn, dfd, 1 - alpha)`` is used as it is: ``1 - alpha`` keeps at
#: least six significant digits of alpha
_FDTRI_FROM = 1e-10


def f_isf(dfn: Any, dfd: Any, alpha: Any) -> np.ndarray:
    r"""Upper ``alpha`` quantile of the F law :math:`\mathcal F(\text{dfn}, \text{dfd})`, accurate down to
    ``alpha = 1e-300``.

    ``1 - X`` of :math:`X = \text{dfn} F / (\text{dfn} F + \text{dfd}) \sim B(\text{dfn}/2, \text{dfd}/2)` is
    :math:`Y \sim B(a, b)`, :math:`a = \text{dfd}/2`, :math:`b = \text{dfn}/2`, whose lower ``alpha`` quantile
    :math:`y` gives :math:`F = \text{dfd} (1 - y) / (\text{dfn}\, y)` (``inf`` beyond the float range):
    ``scipy.special.betaincinv`` where its result checks out, else (below ``alpha = 1e-250``, or where the
    inverse is NaN or wrong) Newton's method on :math:`\ln I_y(a, b) = \ln \alpha` in :math:`\ln y`
    (:func:`_log_beta_tail`). (``scipy.special.fdtri(dfn, dfd, 1 - alpha)`` loses the digits of ``alpha`` in
    ``1 - alpha``: it is ``inf`` below ``alpha`` of about 1e-16.) Where one degree of freedom is more than 1e8
    times the other (and 1e10) -- a baseline's ``reference_df`` up to 1.8e308 -- the chi-square limit
    :math:`\mathcal F(n, \infty) = \chi^2(n) / n` (:func:`_f_limit`), where the beta function gives wrong or NaN
    quantiles.
    """
    dfn, dfd, alpha = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (dfn, dfd, alpha)))
    if np.any(_large(dfd, dfn) | _large(dfn, dfd)):
        return _f_limit(dfn, dfd, alpha, True, f_isf)
    if np.all(alpha >= _FDTRI_FROM):            # 1 - alpha keeps alpha's digits: scipy's quantile (the fast path)
        return special.fdtri(dfn, dfd, 1.0 - alpha)
    shape = dfn.shape
    dfn, dfd, alpha = (v.ravel() for v in (dfn, dfd, alpha))
    a, b = dfd / 2, dfn / 2
    y = special.betaincinv(a, b, alpha)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore", under="ignore"):
        f = dfd * (1.0 - y) / (dfn * y)
        # scipy's inverse may be NaN, or a wrong power of two where y is tiny: checked by the forward function
        far = (alpha < _LOG_SPACE_BELOW) | ~(np.abs(special.betainc(a, b, y) / alpha - 1.0) < 1e-8)
        if np.any(far):
            a, b, log_alpha = a[far], b[far], np.log(alpha[far])
            log_y = (log_alpha + np.log(a) + special.betaln(a, b)) / a       # leading term of the tail as start
            top = np.log((a + 1) / (a + b + 2))
            for _ in range(100):
                log_y = np.minimum(log_y, top)
                log_i = _log_beta_tail(a, b, log_y)
                slope = np.exp(a * log_y + (b - 1) * np.log1p(-np.exp(log_y)) - special.betaln(a, b) - log_i)
                move = np.clip((log_i - log_alpha) / slope, -5.0, 5.0)
                log_y = log_y - move
                if np.all(np.abs(move) < 1e-13):
                    break
            f[far] = np.exp(np.log(dfd[far] / dfn[far]) + np.log1p(-np.exp(log_y)) - log_y)
    return f.reshape(shape)


def f_sf(dfn: Any, dfd: Any, f: Any) -> np.ndarray:
    r""":math:`P(\mathcal F(\text{dfn}, \text{dfd}) > f)`: ``scipy.special.fdtrc``, and in log space below
    1e-250 (:func:`_log_beta_tail`), where scipy's value may be off by a factor of 2 or be 0 for 1e-300; the
    chi-square limit where one degree of freedom is far larger than the other (as :func:`f_isf`)."""
    dfn, dfd, f = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (dfn, dfd, f)))
    if np.any(_large(dfd, dfn) | _large(dfn, dfd)):
        return _f_limit(dfn, dfd, f, False, f_sf)
    p = special.fdtrc(dfn, dfd, f)
    if not np.any(p < _LOG_SPACE_BELOW):
        return p
    dfn, dfd, f, p = (np.array(v, dtype=np.float64) for v in np.broadcast_arrays(dfn, dfd, f, p))
    far = (p < _LOG_SPACE_BELOW) & np.isfinite(f)
    a, b = dfd[far] / 2, dfn[far] / 2
    with np.errstate(divide="ignore", over="ignore", invalid="ignore", under="ignore"):
        log_y = np.log(a) - np.log(a + b * f[far])
        p[far] = np.exp(_log_beta_tail(a, b, log_y))
    return p


def _sum_squares(x: np.ndarray, starts: np.ndarray, window: int, demean: bool) -> np.ndarray:
    """Sum of squares of the windows ``x[s:s + window]`` (about their own mean with ``demean``; exactly 0 for a
    constant window), summed directly, a few million samples at a time."""
    view = np.lib.stride_tricks.sliding_window_view(x, window)
    out = np.empty(starts.size)
    chunk = max(1, 2 ** 21 // window)
    for i in range(0, starts.size, chunk):
        seg = view[starts[i:i + chunk]]
        if demean:
            dev = seg - seg.mean(axis=1)[:, None]
            out[i:i + chunk] = np.where(seg.max(axis=1) == seg.min(axis=1), 0.0, np.einsum("ij,ij->i", dev, dev))
        else:
            out[i:i + chunk] = np.einsum("ij,ij->i", seg, seg)
    return out

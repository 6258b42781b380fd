"""Residual uncorrelatedness method: Ljung-Box and multivariate portmanteau tests (Dutta et al., eqs. 12-14)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy import special

import numba

from tsfdi._data import as_signal
from tsfdi._validation import int_like, option
from tsfdi.detection.base import CalibratedTest, rescale_exponent, statistic_array
from tsfdi.detection.decision import Decision

__all__ = ["LjungBox", "LjungBoxWindows", "autocovariance", "ljungbox_windows"]

_FFT_MIN_LAGS = 96  # above this many lags (and a long record) the FFT path is used


@numba.njit(cache=True, nogil=True, fastmath=True)
def _acov_lagprod(xt, lags):  # pragma: no cover - compiled
    """Lag products sum_t x[t] x[t-lag] of each row, lag = 0..lags: O(N * lags), SIMD reductions."""
    k, n = xt.shape
    out = np.empty((k, lags + 1))
    for c in range(k):
        x = xt[c]
        for lag in range(lags + 1):
            a = x[lag:]
            b = x[:n - lag]
            s = 0.0
            for t in range(n - lag):
                s += a[t] * b[t]
            out[c, lag] = s
    return out


def autocovariance(x: np.ndarray, lags: int) -> np.ndarray:
    """Biased autocovariances ``c_k = sum_{t=k}^{N-1} x_t x_{t-k} / N``, ``k = 0..lags``, of each column.

    ``x`` is a float64 ``(N, k)`` array already centred by the caller. Cost O(N * lags) (compiled lag
    products) or O(N log N) (FFT, used above 96 lags) -- never the O(N^2) of a
    full correlation (statsmodels issue 4135).

    Returns
    -------
    ndarray, shape (lags + 1, k)
    """
    return _acov_t(np.ascontiguousarray(np.asarray(x, dtype=np.float64).T), lags).T


def _acov_t(xt: np.ndarray, lags: int) -> np.ndarray:
    """Autocovariances of the rows of a C-contiguous ``(k, N)`` array: returns ``(k, lags + 1)``."""
    k, n = xt.shape
    if lags > _FFT_MIN_LAGS and n > 4 * lags:
        from scipy import fft as sfft

        nfft = sfft.next_fast_len(n + lags, real=True)
        f = sfft.rfft(xt, n=nfft, axis=-1)
        acov = sfft.irfft(f.real ** 2 + f.imag ** 2, n=nfft, axis=-1)[:, : lags + 1]
    else:
        acov = _acov_lagprod(xt, lags)
    return acov / n


def _ljungbox_q(acov_t: np.ndarray, n: int) -> np.ndarray:
    """Q per row of ``(k, lags + 1)`` autocovariances (eq. 13)."""
    lags = acov_t.shape[1] - 1
    rho = acov_t[:, 1:] / acov_t[:, :1]
    w = 1.0 / (n - np.arange(1, lags + 1))
    return n * (n + 2) * ((rho * rho) @ w)


def _degenerate(xt: np.ndarray, demean: bool) -> np.ndarray:
    """Channels of C-contiguous ``(k, n)`` residuals whose autocorrelations are undefined (zero variance): constant
    ones (``demean``) or all-zero ones."""
    return xt.max(axis=1) == xt.min(axis=1) if demean else ~np.any(xt, axis=1)


class LjungBox(CalibratedTest):
    r"""Ljung-Box residual uncorrelatedness test (Dutta et al., eqs. 12-14).

    Parameters
    ----------
    lags : int
        Maximum lag :math:`r` of the normalised autocorrelations tested.
    alpha : float
        Type I (false alarm) risk in (0, 1), per tested window. Over many windows of a healthy record about
        ``alpha`` of them reject.
        For a multi-channel decision (it rejects when any channel rejects) ``alpha`` is the decision's false-alarm
        rate unless ``correction="none"``: by default (``"sidak"``) each of ``k`` channels is tested at
        ``1 - (1 - alpha)^(1/k)``; ``correction="none"`` tests each at ``alpha`` (paper 003), up to
        ``1 - (1 - alpha)^k`` for the decision.
    model_df : int
        Degrees of freedom subtracted from ``lags`` (scalar) or ``s**2 * lags`` (multivariate). Use 0 (the
        default, the papers' use) for residuals of a baseline model driven by *new* data; use the number of
        estimated AR coefficients (``p``, or ``s**2 * p`` for a VAR) for an in-sample check of a model's own
        residuals.
    multivariate : {None, "hosking", "li-mcleod"}
        ``None`` (the paper): one Ljung-Box test per channel. ``"hosking"`` / ``"li-mcleod"``: one joint
        multivariate portmanteau statistic over all auto- and cross-correlations (component ``"joint"``).
    demean : bool
        Subtract the sample mean before computing autocorrelations (as statsmodels ``acf`` does).
    correction : {"sidak", "bonferroni", "none"}
        How ``alpha`` is shared by the ``k`` channels of vector residuals (per-channel tests): ``"sidak"``
        (default) :math:`1 - (1 - \alpha)^{1/k}` each, ``"bonferroni"`` ``alpha / k`` each, so that the
        signal-level risk is at most ``alpha``; ``"none"``: ``alpha`` per channel (paper 003).
    threshold : {"theoretical", "empirical"} or EmpiricalThreshold
        ``"theoretical"`` (the paper): the chi-square critical value
        :math:`\chi^2_{1-\alpha}(r - \text{model\_df})` and its p-value. ``"empirical"`` (or an
        :class:`~tsfdi.EmpiricalThreshold` whose ``false_alarm`` is ``alpha``, to set its tail options): the
        :math:`1-\alpha` quantile of the statistic on healthy (in-state) residual windows, estimated by
        :meth:`calibrate` (Hansen et al., paper 002, Fig. 2); decisions then report that threshold and the
        empirical p-value.

    Attributes
    ----------
    threshold_ : ndarray, shape (k,)
        Calibrated threshold per channel (after :meth:`calibrate`, empirical threshold only).

    Notes
    -----
    Eq. 13: under H0 (iid residuals)

    .. math:: Q = N (N + 2) \sum_{\tau=1}^{r} \frac{\hat\rho[\tau]^2}{N - \tau} \sim \chi^2(r - \text{model\_df})

    and H0 is accepted when :math:`Q \le \chi^2_{1-\alpha}(r - \text{model\_df})` (eq. 14 has
    ``model_df = 0``). With ``model_df = 0`` the statistic and p-value equal statsmodels ``acorr_ljungbox``.
    The autocovariances cost O(N r) (lag products) or O(N log N) (FFT), never O(N^2).

    Multivariate (``s`` channels, :math:`C_k = N^{-1}\sum_t e_t e_{t-k}^T`):
    Hosking (1980) :math:`Q = N^2 \sum_{k=1}^{r} (N-k)^{-1} \mathrm{tr}(C_k^T C_0^{-1} C_k C_0^{-1})`;
    Li and McLeod (1981) :math:`Q = N \sum_{k=1}^{r} \mathrm{tr}(C_k^T C_0^{-1} C_k C_0^{-1}) + s^2 r (r+1)/(2N)`;
    both :math:`\sim \chi^2(s^2 r - \text{model\_df})`.

    Residuals of a baseline fitted on :math:`N_0` samples and driven by :math:`N_u` new samples carry the
    baseline's estimation error: :math:`E[Q] \approx r + p N_u / N_0` for an AR(p) baseline (checked by Monte
    Carlo in ``tests/detection/test_whiteness.py``). With :math:`N_0 = N_u` (the papers' 2,000 / 2,000) the
    false-alarm rate is therefore above ``alpha``; the chi-square(r) level is accurate when the baseline record
    is much longer than the tested one (or use a smaller ``alpha``, as the papers do). A threshold calibrated on
    out-of-sample residual windows (``threshold="empirical"``) absorbs that estimation error and mild
    misspecification: its false-alarm rate is ``alpha`` whatever the statistic's distribution, provided the
    calibration residuals come from the same process as the tested ones.

    **A constant window** (a frozen sensor; with ``demean=False`` an all-zero one) has no autocorrelation: its
    :math:`Q` is ``inf``, with p-value 0, and the channel rejects; ``Decision.details["constant"]`` names such
    channels (empty otherwise). The windowed path (:func:`ljungbox_windows`, :meth:`window_statistic`, and so
    ``tsfdi.identify_windows`` and ``Monitor``) gives the same ``inf`` for the same windows. With ``multivariate``
    a constant channel makes the joint statistic ``inf``. :math:`Q` does not depend on the scale of the residuals:
    they are rescaled by a power of two before any square (exact), so that values near 1e300 or 1e-300 give the
    :math:`Q` of values near 1.

    The chi-square law is asymptotic, and for short windows with many lags its upper tail is too light even for
    iid Gaussian residuals: with 480 samples and 20 lags the test rejects white noise more often than ``alpha``,
    increasingly so for small ``alpha``; at 1980 samples the excess is small (within Monte Carlo error at
    ``alpha = 0.01``: ``tests/detection/test_whiteness.py``; ``docs/results.md`` tabulates the size at the study's
    window lengths and three alphas). The exact null of a given window length is obtained by calibrating on simulated white noise:
    ``LjungBox(lags, alpha, threshold="empirical").calibrate(statistic=ljungbox_windows(z, lags, n, n))`` for
    ``z`` a long standard normal record.

    References
    ----------
    Dutta et al., eqs. 12-14. Ljung, G. M. and Box, G. E. P. (1978), Biometrika 65, 297-303.
    Hosking, J. R. M. (1980), JASA 75, 602-608. Li, W. K. and McLeod, A. I. (1981), JRSS B 43, 231-239.
    Hansen, Blanke, Adrian (paper 002), Fig. 2: threshold from the statistic's distribution in normal operation.
    """

    name = "Ljung-Box (residual uncorrelatedness)"
    null_hypothesis = "residuals are uncorrelated up to the tested lag (healthy / model fits)"
    alternative_hypothesis = "residuals are autocorrelated (fault / model does not fit)"

    def __init__(self, lags: int = 20, alpha: float = 0.05, model_df: int = 0, *, multivariate: str | None = None,
                 demean: bool = True, correction: str = "sidak", threshold: Any = "theoretical") -> None:
        self.lags = int_like(lags, "lags", minimum=1)
        self.alpha = self._check_alpha(alpha)
        self.model_df = int_like(model_df, "model_df", minimum=0)
        self.multivariate = None if multivariate is None else option(multivariate, "multivariate",
                                                                      ("hosking", "li-mcleod"))
        if self.multivariate is None and self.model_df >= self.lags:
            raise ValueError(f"model_df must be < lags ({self.lags}) so that df = lags - model_df >= 1, "
                             f"got {self.model_df}")
        if not isinstance(demean, (bool, np.bool_)):
            raise TypeError(f"demean must be a bool, got {demean!r}")
        self.demean = bool(demean)
        self.correction = self._check_correction(correction)
        self.threshold = self._threshold_option(threshold)

    def __repr__(self) -> str:
        thr = "" if self.threshold == "theoretical" else f", threshold={self._threshold_name()!r}" + (
            f" (calibrated on {self.calibration_[0].size} windows)" if self.calibrated else " (not calibrated)")
        return (f"LjungBox(lags={self.lags}, alpha={self.alpha:g}, model_df={self.model_df}, "
                f"multivariate={self.multivariate!r}, correction={self.correction!r}{thr})")

    def window_statistic(self, resid: Any, window: int, step: int = 1, **_: Any) -> np.ndarray:
        """``Q`` of every sliding window (``window`` residual samples, ``step`` apart), shape (n_windows, k):
        :func:`ljungbox_windows` per channel, or the joint statistic (one column) with ``multivariate``."""
        if self.multivariate is None:
            return ljungbox_windows(resid, self.lags, window, step, demean=self.demean)
        sig = self._prepare(resid)
        window = int_like(window, "window", minimum=self.lags + 1, maximum=sig.nobs)
        step = int_like(step, "step", minimum=1)
        x = sig.values
        out = []
        for a in range(0, sig.nobs - window + 1, step):
            w = x[a:a + window]
            if _degenerate(np.ascontiguousarray(w.T), self.demean).any():
                out.append(np.inf)
                continue
            e = rescale_exponent(w)
            xt = (np.ldexp(w, -e) if e.any() else w).T
            if self.demean:
                xt = xt - xt.mean(axis=1)[:, None]
            out.append(self._joint_q(np.ascontiguousarray(xt.T), window, sig.nchan))
        return np.array(out)[:, None]

    @property
    def min_resid(self) -> int:
        """Fewest residual samples :meth:`test` accepts: ``lags + 1``."""
        return self.lags + 1

    def _prepare(self, resid: Any):
        sig = as_signal(resid, "resid", min_nobs=1, allow_constant=True)
        if sig.nobs < self.min_resid:
            raise ValueError(f"resid is too short: {sig.nobs} samples, more than lags = {self.lags} are needed")
        return sig

    def test(self, resid: Any, **_: Any) -> Decision:
        """Test the residuals for autocorrelation up to ``lags``.

        Parameters
        ----------
        resid : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, k)

        Returns
        -------
        Decision
            One component per channel, or one named ``"joint"`` with ``multivariate`` set.
            ``details["constant"]``: the channels that are constant (a frozen sensor), whose statistic is ``inf``
            (p-value 0, reject).
        """
        sig = self._prepare(resid)
        xt = np.ascontiguousarray(sig.values.T)
        const = _degenerate(xt, self.demean)
        e = rescale_exponent(xt, axis=1)
        if e.any():
            xt = np.ldexp(xt, -e[:, None])                # exact rescaling, see Notes
        n = xt.shape[1]
        if self.demean:
            xt = xt - xt.mean(axis=1)[:, None]
        if self.multivariate is None:
            acov = _acov_t(xt, self.lags)
            with np.errstate(divide="ignore", invalid="ignore"):
                q = _ljungbox_q(acov, n)
            q[const] = np.inf
            return self.decision(q, n, tuple(sig.channels))
        q = np.inf if const.any() else self._joint_q(np.ascontiguousarray(xt.T), n, sig.nchan)
        return self._multivariate(q, n, sig.nchan, {"constant": tuple(np.asarray(sig.channels)[const].tolist())})

    def decision(self, statistic: Any, nobs: int, channels: Any = None, *, details: dict | None = None,
                 **reference: Any) -> Decision:
        """As :meth:`CalibratedTest.decision <tsfdi.detection.base.CalibratedTest.decision>`, with
        ``details["constant"]``: the channels whose statistic is ``inf`` (a constant window, see Notes)."""
        stat = np.atleast_1d(statistic_array(statistic))
        names = tuple(channels) if channels is not None else tuple(f"y{i}" for i in range(stat.shape[-1]))
        const = {"constant": tuple(c for c, q in zip(names, stat) if q == np.inf)} if stat.ndim == 1 else {}
        return super().decision(stat, nobs, channels, details={**const, **(details or {})}, **reference)

    def null_threshold(self, k: int, nobs: int | None = None, **reference: Any) -> np.ndarray:
        r"""Critical value of the per-channel Ljung-Box test under H0 (Dutta et al., paper 003, eq. 14).

        Parameters
        ----------
        k : int
            Number of channels (with ``correction="bonferroni"`` each is tested at ``alpha / k``).
        nobs : int, optional
            Residual samples per window; not used (the chi-square law does not depend on it).
        **reference :
            Ignored (the test needs nothing from the baseline model).

        Returns
        -------
        ndarray, shape (k,)
            :math:`\chi^2_{1-\alpha}(r - \text{model\_df})`, the :math:`1 - \alpha` quantile of the
            chi-square law of :math:`Q` (eq. 13) with :math:`r` = ``lags``; :math:`\alpha` is each channel's risk
            per tested window (``alpha`` shared by the ``k`` channels by ``correction``).

        Notes
        -----
        The per-channel test (``multivariate=None``); the joint portmanteau statistic has
        :math:`s^2 r - \text{model\_df}` degrees of freedom (see :meth:`test`).
        """
        df = float(self.lags - self.model_df)
        a = self._channel_alpha(self.alpha, k, self.correction)
        key = (df, a)
        if getattr(self, "_thr_key", None) != key:      # options are fixed; cache the critical value
            self._thr_key, self._thr = key, float(special.chdtri(df, a))
        return np.full(k, self._thr)

    def _null_pvalue(self, statistic: np.ndarray, nobs: int | None = None, **reference: Any) -> np.ndarray:
        r""":math:`P(\chi^2(r - \text{model\_df}) > Q)` (eq. 13), same shape as ``statistic``."""
        return special.chdtrc(float(self.lags - self.model_df), statistic)

    def _df(self, k: int, nobs: int, **reference: Any) -> np.ndarray:
        return np.full(k, float(self.lags - self.model_df))

    def _decision_details(self, k: int, **reference: Any) -> dict:
        return {"lags": self.lags, "model_df": self.model_df,
                "channel_alpha": self._channel_alpha(self.alpha, k, self.correction), "correction": self.correction}

    def _joint_q(self, x: np.ndarray, n: int, s: int) -> float:
        h = self.lags
        c0 = x.T @ x / n
        try:
            chol = np.linalg.cholesky(c0)
        except np.linalg.LinAlgError:
            raise ValueError("resid has a singular covariance matrix: the multivariate portmanteau test needs "
                             "linearly independent channels") from None
        # Whitening: tr(C_k' C0^-1 C_k C0^-1) = ||L^-1 C_k L^-T||_F^2 = ||R_k||_F^2 of z = x L^-T.
        z = np.linalg.solve(chol, x.T).T
        terms = np.empty(h)
        for lag in range(1, h + 1):
            r = z[lag:].T @ z[:-lag] / n
            terms[lag - 1] = np.einsum("ij,ij->", r, r)
        if self.multivariate == "hosking":
            q = n * n * np.sum(terms / (n - np.arange(1, h + 1)))
        else:
            q = n * np.sum(terms) + s * s * h * (h + 1) / (2.0 * n)
        return float(q)

    def _multivariate(self, q: float, n: int, s: int, details: dict) -> Decision:
        h = self.lags
        df = float(s * s * h - self.model_df)
        if df < 1:
            raise ValueError(f"model_df must be < s**2 * lags = {s * s * h} for the multivariate test, "
                             f"got {self.model_df}")
        details = {**details, "lags": h, "model_df": self.model_df, "method": self.multivariate, "nchan": s}
        if self.empirical:
            self._check_calibrated(1, n)
            thr = float(self.threshold_[0])
            pv = float(self.calibrated_pvalue(np.array([[q]]))[0, 0])
            details.update(self._calibration_details())
        else:
            thr = special.chdtri(df, self.alpha)
            pv = special.chdtrc(df, q)
            details["threshold_method"] = self._theoretical
        return Decision(statistic=np.array([q]), threshold=np.array([thr]), pvalue=np.array([pv]),
                        alpha=self.alpha, reject=bool(q > thr), df=np.array([df]), nobs=n,
                        null_hypothesis="residual auto- and cross-correlations are zero up to the tested lag",
                        alternative_hypothesis="some residual auto- or cross-correlation is non-zero",
                        details=details,
                        channel_reject=np.array([q > thr]), channels=("joint",), test="LjungBox")


def ljungbox_windows(resid: Any, lags: int, window: int, step: int = 1, *, demean: bool = True) -> np.ndarray:
    r"""Ljung-Box statistics of every sliding window of a residual record, all at once.

    Parameters
    ----------
    resid : array_like, Series, DataFrame or DataArray, shape (N,) or (N, k)
        Residual record (e.g. a whole flight driven once through a fixed model: because the model is
        fixed, the residuals of a window of the signal are a slice of the record's residuals).
    lags : int
        Maximum lag.
    window : int
        Window length in residual samples (a signal window of ``W`` samples through an AR(p) model gives
        ``W - p`` residuals).
    step : int
        Samples between window starts.
    demean : bool
        Subtract each window's own mean (as statsmodels ``acf``).

    Returns
    -------
    ndarray, shape (n_windows, k)
        ``Q`` of window ``w`` (samples ``[w * step, w * step + window)``) per channel, equal to
        statsmodels ``acorr_ljungbox`` on that window and to :meth:`LjungBox.test`; ``inf`` for a constant
        window (a frozen sensor; with ``demean=False`` an all-zero one), as :meth:`LjungBox.test` says.

    See Also
    --------
    LjungBoxWindows : the same for several window lengths of one record, sharing the lag products.

    Notes
    -----
    With prefix sums :math:`S`, :math:`S^{(2)}` of :math:`x` and :math:`x^2` and :math:`P_l` of the lag products
    :math:`x_t x_{t-l}`, the centred lag-:math:`l` sum of a window of length :math:`n` and mean :math:`m` is
    :math:`P_l - m (\sum_{t \ge l} x_t + \sum_{t < n - l} x_t) + (n - l) m^2`, so every window costs O(lags)
    after one O(N * lags) pass (compiled with the lags as the inner, packed loop). The prefix sums are of the record
    rescaled by a power of two (exact: :math:`Q` does not change, squares do not overflow) and, with ``demean``,
    centred on its mean. A difference of prefix sums loses the digits that the sums before the window carry: a
    window whose centred energy is below ``1e-6`` of :math:`S^{(2)}` at its end (a quiet stretch after a loud one)
    is computed directly from its own samples in O(window * lags); constant windows are found exactly (no sample
    differs from the one before it).
    """
    return LjungBoxWindows(resid, lags, demean=demean).statistic(window, step)


class LjungBoxWindows:
    r"""The lag products of a residual record, computed once, and the Ljung-Box statistic of every sliding window
    of any length and step from them (:func:`ljungbox_windows`, shared across window lengths).

    Parameters
    ----------
    resid : array_like, Series, DataFrame or DataArray, shape (N,) or (N, k)
        Residual record.
    lags : int
        Maximum lag.
    demean : bool
        Subtract each window's own mean (as statsmodels ``acf``).

    Notes
    -----
    The lag products are summed in one pass per grid of samples on which the windows start and end (the greatest
    common divisor of ``window`` and ``step``; below 5 samples, every sample), and only the sums at the grid's
    samples are kept (``2 * lags`` values per channel and grid sample, ``lags`` on the grid of every sample): the
    record's grid is kept when those sums number at most ``2**20`` over all channels (8 MB), and serves every later
    call whose windows lie on it (5 / 10 / 20 s windows 1 s apart share one); above, :meth:`statistic` recomputes
    them for each call, a block of windows at a time, in bounded memory.
    The statistics are those of :func:`ljungbox_windows` (see its Notes).

    Examples
    --------
    >>> lbw = LjungBoxWindows(e, lags=20)                                    # doctest: +SKIP
    >>> q5, q10 = lbw.statistic(500, 100), lbw.statistic(1000, 100)           # doctest: +SKIP
    """

    def __init__(self, resid: Any, lags: int, *, demean: bool = True) -> None:
        sig = as_signal(resid, "resid", allow_constant=True)
        self.lags = int_like(lags, "lags", minimum=1)
        if not isinstance(demean, (bool, np.bool_)):
            raise TypeError(f"demean must be a bool, got {demean!r}")
        self.demean = bool(demean)
        x = sig.values
        e = rescale_exponent(x)
        if np.any(np.abs(e) > 1000):                   # 2**-e would not be a float: rescale here
            x, e = np.ldexp(x, -e), np.zeros_like(e)
        self.nobs = x.shape[0]
        # channels on axis 0: the record, its rescaled and centred copy with its prefix sums, the last change
        self._x = np.ascontiguousarray(x.T)
        self._sums = _record_sums(self._x, np.ldexp(1.0, -e), self.demean)
        self._grid = None                     # (g, lag sums at every g-th sample) of the whole record, once kept

    def statistic(self, window: int, step: int = 1) -> np.ndarray:
        """``Q`` of every window of ``window`` samples, ``step`` apart: shape (n_windows, k), as
        :func:`ljungbox_windows`."""
        window = int_like(window, "window", minimum=2)
        step = int_like(step, "step", minimum=1)
        if window > self.nobs:
            raise ValueError(f"window must be <= the record length {self.nobs}, got {window}")
        if window <= self.lags:
            raise ValueError(f"window must be > lags ({self.lags}), got {window}")
        starts = np.arange(0, self.nobs - window + 1, step, dtype=np.int64)
        k, lags = self._x.shape[0], self.lags
        g = math.gcd(window, step)            # every window starts and ends on this grid of samples
        if g < _GRID_MIN:                     # a fine grid costs more bookkeeping than it saves: every sample's sums
            g = 1
        if self._grid is not None and g % self._grid[0] == 0:      # a finer grid kept by an earlier call serves
            return _windows_q(self._x, *self._sums, *self._grid[1:], _rows(starts, 0, window, self._grid[0]), lags,
                              window, starts, self.demean)
        kept = (1 + (g > 1)) * k * lags           # sums kept per grid sample (pa, and pb for g > 1)
        if kept * (self.nobs // g + 1) <= _KEEP_LAGPROD:
            self._grid = (g, *_lag_sums(self._sums[0], 0, self.nobs, lags, g))
            return _windows_q(self._x, *self._sums, *self._grid[1:], _rows(starts, 0, window, g), lags, window,
                              starts, self.demean)
        # a block of windows at a time: the lag sums of the samples they cover, from the block's first one
        per = max(1, (_KEEP_LAGPROD // kept * g - window) // step)
        q = np.empty((starts.size, k))
        for w0 in range(0, starts.size, per):
            st = starts[w0:w0 + per]
            r0, r1 = int(st[0]), int(st[-1]) + window
            grid = _lag_sums(self._sums[0], r0, r1, lags, g)
            q[w0:w0 + per] = _windows_q(self._x, *self._sums, *grid, _rows(st, r0, window, g), lags, window, st,
                                        self.demean)
        return q


def _rows(starts: np.ndarray, r0: int, window: int, g: int) -> np.ndarray:
    """The grid rows of the window starts from sample ``r0``, then the window's length in rows (:func:`_windows_q`)."""
    return np.append((starts - r0) // g, window // g)


def _lag_sums(v: np.ndarray, r0: int, r1: int, lags: int, g: int) -> tuple:
    """``pa``, ``pb`` of :func:`_lag_grid` over samples ``[r0, r1)`` on a grid of ``g`` (:func:`_lag_prefix` for
    ``g = 1``)."""
    k, rows = v.shape[0], (r1 - r0) // g + 1
    pa = np.empty((k, rows, lags))
    if g == 1:
        return _lag_prefix(v, r0, r1, lags, pa), np.empty((k, 0, lags))
    return _lag_grid(v, r0, r1, lags, g, pa, np.empty((k, rows, lags)))


#: Most lag sums (over all channels) a LjungBoxWindows keeps; above, they are recomputed per call in blocks.
_KEEP_LAGPROD = 2 ** 20
#: Finest grid whose lag sums LjungBoxWindows keeps alone (a window length and step with a smaller common divisor
#: use every sample's sums, on a grid of 1)
_GRID_MIN = 5


#: A window whose centred energy is below this fraction of the prefix sum of squares at its end is computed directly.
_DIRECT_BELOW = 1e-6


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _direct_q(x, a, window, lags, demean):  # pragma: no cover - compiled
    """Q of the window ``x[a:a + window]`` from its own samples (centred on its own mean with ``demean``), divided by
    their largest deviation first so that a window far quieter than the record does not underflow."""
    n = float(window)
    m = 0.0
    if demean:
        for t in range(a, a + window):
            m += x[t]
        m /= n
    top = 0.0
    for t in range(a, a + window):
        top = max(top, abs(x[t] - m))
    c0 = 0.0
    for t in range(a, a + window):
        c0 += ((x[t] - m) / top) ** 2
    q = 0.0
    for lag in range(1, lags + 1):
        c = 0.0
        for t in range(a + lag, a + window):
            c += ((x[t] - m) / top) * ((x[t - lag] - m) / top)
        r = c / c0
        q += r * r / (n - lag)
    return q * n * (n + 2)




@numba.njit(cache=True, nogil=True)
def _record_sums(x, factor, demean):  # pragma: no cover - compiled
    """Per channel (row of ``x``): the record rescaled by ``factor`` (a power of two) and, with ``demean``, centred
    on its mean (global centring limits cancellation in the prefix sums), its prefix sums of values and squares, and
    for every sample the last one up to it that differs from its predecessor (0 if none)."""
    k, n = x.shape
    v = np.empty((k, n))
    s1 = np.empty((k, n + 1))
    s2 = np.empty((k, n + 1))
    last = np.empty((k, n), dtype=np.int64)
    for c in range(k):
        f = factor[c]
        centre = 0.0
        if demean:
            for t in range(n):
                centre += x[c, t] * f
            centre /= n
        s1[c, 0] = 0.0
        s2[c, 0] = 0.0
        prev = 0
        for t in range(n):
            vt = x[c, t] * f - centre
            v[c, t] = vt
            s1[c, t + 1] = s1[c, t] + vt
            s2[c, t + 1] = s2[c, t] + vt * vt
            if t > 0 and x[c, t] != x[c, t - 1]:
                prev = t
            last[c, t] = prev
    return v, s1, s2, last


@numba.njit(cache=True, nogil=True)
def _lag_grid(v, r0, r1, lags, g, pa, pb):  # pragma: no cover - compiled
    """The sums of the lag products of ``v[:, r0:r1]`` that windows starting and ending on a grid of ``g > 1``
    samples need, with ``P[i, l - 1] = sum_{r0 <= t < r0 + i} v[t + l] v[t]``, into ``pa`` and ``pb`` (channels,
    ``(r1 - r0) // g + 1`` rows, ``lags`` columns): ``pa[c, j] = P[j g]`` and ``pb[c, j, l - 1] = P[j g - l, l - 1]``
    (where ``j g >= l``; other entries are not written). The lag-``l`` sum of the window ``[r0 + ja g, r0 + jb g)``
    is ``pb[c, jb, l - 1] - pa[c, ja, l - 1]``. Returns ``pa, pb``.

    One pass, with the lags as the inner loop: the ``lags`` running sums are independent, so the loop compiles to
    packed adds instead of one serial (latency-bound) recursion per lag, each sum adds the same products in the same
    order as :func:`_lag_prefix`, and only the grid's rows are written: a few kB instead of the ``8 N lags`` bytes
    per channel of every sample's sums, which evicted the rest of the work from the cache.
    """
    m = r1 - r0
    rows = pb.shape[1]
    full = max(0, m - lags)              # samples whose every lag stays inside [r0, r1)
    acc = np.empty(lags)                 # the running sums P[i]
    for c in range(v.shape[0]):
        x = v[c]
        acc[:] = 0.0
        j, phase = 0, 0                  # row i = j g + phase (no division in the loop)
        for i in range(m + 1):           # acc = P[i]: keep what the grid needs, then add the products of r0 + i
            if phase == 0:
                pa[c, j, :] = acc
            lag, n = g - phase, j + 1    # the lags l with i + l on the grid, (j + 1 + n') g: l = g - phase + n' g
            while lag <= lags and n < rows:
                pb[c, n, lag - 1] = acc[lag - 1]
                lag += g
                n += 1
            if i == m:
                break
            t = r0 + i
            vt = x[t]
            if i < full:
                seg = x[t + 1:t + 1 + lags]
                for lag in range(lags):
                    acc[lag] += seg[lag] * vt
            else:
                for lag in range(min(lags, r1 - 1 - t)):      # lags with t + l < r1
                    acc[lag] += x[t + 1 + lag] * vt
            phase += 1
            if phase == g:
                j, phase = j + 1, 0
    return pa, pb


@numba.njit(cache=True, nogil=True)
def _lag_prefix(v, r0, r1, lags, p):  # pragma: no cover - compiled
    """Prefix sums of the lag products of ``v[:, r0:r1]`` into ``p`` (channels, ``r1 - r0 + 1`` rows, ``lags``
    columns): row ``i``, column ``l - 1`` holds ``sum_{r0 <= t < r0 + i} v[t + l] v[t]`` (for ``r0 + i + l <= r1``;
    the rows beyond are not used): :func:`_lag_grid` for ``g = 1``, with the rows written as they are summed, which
    the compiled loop does at half the cost of the grid's bookkeeping. Returns ``p``.

    The lags are the inner loop: the ``lags`` running sums are independent, so the loop compiles to packed adds
    instead of one serial (latency-bound) recursion per lag, and each sum adds the same products in the same order.
    """
    m = r1 - r0
    full = max(0, m - lags)              # rows whose every lag stays inside [r0, r1)
    acc = np.empty(lags)                 # the running sums of row i
    for c in range(v.shape[0]):
        x = v[c]
        pc = p[c]
        acc[:] = 0.0
        pc[0, :] = 0.0
        for i in range(full):
            t = r0 + i
            vt = x[t]
            seg = x[t + 1:t + 1 + lags]
            row = pc[i + 1]
            for j in range(lags):
                acc[j] += seg[j] * vt
                row[j] = acc[j]
        for i in range(full, m):
            t = r0 + i
            vt = x[t]
            for j in range(min(lags, r1 - 1 - t)):      # lags with t + l < r1
                acc[j] += x[t + 1 + j] * vt
            pc[i + 1, :] = acc
    return p


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _windows_q(x, v, s1, s2, last, pa, pb, grid, lags, window, starts, demean):  # pragma: no cover - compiled
    """Q of every window (rows) and channel (columns) from prefix sums of ``v = x * factor - centre`` (``x``
    rescaled by a power of two, and centred on the record's mean with ``demean``; channels on axis 0 of every
    array): ``s1``, ``s2`` of values and squares (from sample 0) and ``pa``, ``pb`` of the lag products on the grid of
    ``g`` samples from sample ``r0`` (:func:`_lag_grid`; every window starts and ends on it; ``grid`` holds each
    start's row ``(start - r0) / g`` and the window's rows ``window / g``, divided by numpy). ``x`` itself (a
    rescaled record could underflow in a window far quieter than the rest) serves the exact test for constant
    windows (``last``: the last sample up to each one that differs from its predecessor) and the direct evaluation of
    windows the prefix sums cannot resolve."""
    nw = starts.shape[0]
    k = x.shape[0]
    n = float(window)
    q = np.empty((nw, k))
    for c in range(k):
        c1, c2, ca = s1[c], s2[c], pa[c]
        ends, back = (pa[c], 1) if pb.shape[1] == 0 else (pb[c], 0)   # P[b - l, l - 1]: ends[jb - back l, l - 1]
        for w in range(nw):
            a = starts[w]
            b = a + window
            m = (c1[b] - c1[a]) / n if demean else 0.0
            gamma0 = c2[b] - c2[a] - n * m * m
            if last[c, b - 1] <= a and (demean or x[c, a] == 0.0):
                q[w, c] = np.inf                # a constant window (a frozen sensor), see LjungBox
                continue
            if not gamma0 > _DIRECT_BELOW * c2[b]:
                q[w, c] = _direct_q(x[c], a, window, lags, demean)
                continue
            acc = 0.0
            ja = grid[w]
            jb = ja + grid[nw]
            for lag in range(1, lags + 1):
                lagsum = ends[jb - back * lag, lag - 1] - ca[ja, lag - 1]
                head = c1[b] - c1[a + lag]
                tail = c1[b - lag] - c1[a]
                cov = lagsum - m * (head + tail) + (n - lag) * m * m
                r = cov / gamma0
                acc += r * r * (1.0 / (n - lag))
            q[w, c] = acc * (n * (n + 2))
    return q

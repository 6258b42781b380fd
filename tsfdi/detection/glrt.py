"""GLRT for a change in mean of a Gaussian residual (Hansen, Blanke, Adrian, eqs. 1-3) and its thresholds."""

from __future__ import annotations

import copy
import math
from typing import Any

import numba
import numpy as np
from scipy import special

from tsfdi._data import as_signal
from tsfdi._validation import float_like, int_like, option, probability
from tsfdi.detection.base import ResidualTest, baseline_variance
from tsfdi.detection.decision import Decision

__all__ = ["GLRT", "EmpiricalThreshold", "GLRTStream", "GLRTScan", "glrt_direct"]


# ---------------------------------------------------------------------------------------------- kernels
@numba.njit(cache=True, nogil=True)
def _scan(x, first, window, scale):  # pragma: no cover - compiled
    """g(k), best post-change length and ML jump for k in [first, len(x)), windows may reach before first.

    For each k the post-change sum S_n = sum_{i=k-n+1}^{k} x_i is accumulated backwards, n = 1..window,
    so every g(k) costs O(window) and no cumulative-sum cancellation occurs.
    """
    n_out = x.shape[0] - first
    g = np.empty(n_out)
    best = np.empty(n_out, dtype=np.int64)
    jump = np.empty(n_out)
    for k in range(first, x.shape[0]):
        m = window if window < k + 1 else k + 1
        s = 0.0
        gmax = -1.0
        nbest = 1
        sbest = 0.0
        for n in range(1, m + 1):
            s += x[k - n + 1]
            v = s * s / n
            if v > gmax:
                gmax = v
                nbest = n
                sbest = s
        g[k - first] = gmax * scale
        best[k - first] = nbest
        jump[k - first] = sbest / nbest
    return g, best, jump


@numba.njit(cache=True, nogil=True, fastmath=True)
def _scan_g(x, first, window, scale):  # pragma: no cover - compiled
    """g(k) only, for k in [first, len(x)): O(window) per sample, SIMD-vectorisable.

    Window sums are differences of a cumulative sum restarted every block of 4096 outputs (so its
    magnitude stays bounded on long records); the max over the M lengths has no loop-carried dependency.
    """
    n_all = x.shape[0]
    n_out = n_all - first
    g = np.empty(n_out)
    inv = np.empty(window + 1)
    inv[0] = 0.0
    for n in range(1, window + 1):
        inv[n] = scale / n
    block = 4096
    c = np.empty(block + window + 1)
    for b0 in range(first, n_all, block):
        b1 = min(b0 + block, n_all)
        lo = max(b0 - window, 0)
        c[0] = 0.0
        for i in range(lo, b1):
            c[i - lo + 1] = c[i - lo] + x[i]
        for k in range(b0, b1):
            m = window if window < k + 1 else k + 1
            ck = c[k - lo + 1]
            base = k - lo + 1
            gmax = 0.0
            for n in range(1, m + 1):
                d = ck - c[base - n]
                v = d * d * inv[n]
                gmax = v if v > gmax else gmax
            g[k - first] = gmax
    return g

@numba.njit(cache=True, nogil=True)
def _direct(x, window, scale):  # pragma: no cover - compiled
    """Reference O(N * window^2) evaluation: every window sum recomputed from scratch (for benchmarks/tests)."""
    g = np.empty(x.shape[0])
    for k in range(x.shape[0]):
        m = window if window < k + 1 else k + 1
        gmax = -1.0
        for n in range(1, m + 1):
            s = 0.0
            for i in range(k - n + 1, k + 1):
                s += x[i]
            v = s * s / n
            if v > gmax:
                gmax = v
        g[k] = gmax * scale
    return g


@numba.njit(cache=True, nogil=True)
def _ring_update(buf, head, count, value, window, scale):  # pragma: no cover - compiled
    """Push one sample into a ring buffer and return (g, best n, jump, new head, new count)."""
    head = (head + 1) % window
    buf[head] = value
    if count < window:
        count += 1
    s = 0.0
    gmax = -1.0
    nbest = 1
    sbest = 0.0
    idx = head
    for n in range(1, count + 1):
        s += buf[idx]
        v = s * s / n
        if v > gmax:
            gmax = v
            nbest = n
            sbest = s
        idx -= 1
        if idx < 0:
            idx = window - 1
    return gmax * scale, nbest, sbest / nbest, head, count


def glrt_direct(resid: Any, window: int, sigma: float) -> np.ndarray:
    """Direct O(N * window^2) evaluation of g(k) for a scalar residual (reference for tests and benchmarks)."""
    x = as_signal(resid, "resid", vector=False, allow_constant=True).values[:, 0]
    window = int_like(window, "window", minimum=1)
    sigma = float_like(sigma, "sigma", minimum=0.0, strict_min=True)
    return _direct(x, window, 0.5 / sigma ** 2)


# ---------------------------------------------------------------------------------------------- threshold
def _ceil(v: float) -> int:
    """Ceiling that ignores floating-point noise (20 / 1e-4 is 200000, not 200001)."""
    return math.ceil(v * (1 - 1e-12))


class EmpiricalThreshold:
    r"""Threshold of a detection statistic from its distribution on healthy data (Hansen et al., Fig. 2).

    Parameters
    ----------
    false_alarm : float
        Required false-alarm probability :math:`P_F` per sample, in (0, 1).
    min_exceedances : int
        The empirical :math:`1 - P_F` quantile is used when the healthy sample holds at least this many
        expected exceedances (``n * P_F >= min_exceedances``).
    tail_fraction : float
        Below that, a generalised Pareto distribution is fitted to the excesses over the
        ``1 - tail_fraction`` quantile :math:`u` and the threshold is extrapolated:
        :math:`\gamma = u + \frac{\sigma}{\xi}\left[(P_F / \zeta)^{-\xi} - 1\right]`, :math:`\zeta` the
        fraction of samples above :math:`u` (:math:`\xi = 0`: :math:`u - \sigma \ln(P_F / \zeta)`).
    min_tail : int
        Minimum number of excesses for the tail fit.
    max_extrapolation : float
        The tail fit may reach :math:`P_F` down to ``min_exceedances / (n * max_extrapolation)``; a smaller
        sample raises an error stating how many samples are needed.
    tail_shape : float or None
        Shape :math:`\xi` of the generalised Pareto tail. ``0`` (default): exponential excesses, the Gumbel
        domain of attraction of a maximum of chi-square variables such as the GLRT statistic; its scale is the
        mean excess. ``None``: :math:`\xi` fitted by maximum likelihood too (for other statistics; with
        strongly dependent samples the fitted :math:`\xi` tends to be negative and the threshold too low).

    Attributes
    ----------
    threshold_ : float
        The calibrated threshold (after :meth:`calibrate`).
    method_ : str
        ``"empirical"`` or ``"gpd"``.
    sample_ : ndarray
        The calibration statistic (sorted), kept for :meth:`plot`.

    Notes
    -----
    The statistic of correlated residuals has no closed-form distribution; Hansen et al. estimate the
    threshold from the empirical distribution of g(k) in normal flight. Consecutive values of a windowed
    statistic are strongly dependent, so the effective sample is smaller than its length: calibrate on long
    healthy records.
    """

    def __init__(self, false_alarm: float = 1e-3, *, min_exceedances: int = 20, tail_fraction: float = 0.05,
                 min_tail: int = 100, max_extrapolation: float = 100.0, tail_shape: float | None = 0.0) -> None:
        self.false_alarm = probability(false_alarm, "false_alarm")
        self.min_exceedances = int_like(min_exceedances, "min_exceedances", minimum=1)
        self.tail_fraction = float_like(tail_fraction, "tail_fraction", minimum=0.0, maximum=0.5, strict_min=True)
        self.min_tail = int_like(min_tail, "min_tail", minimum=10)
        self.max_extrapolation = float_like(max_extrapolation, "max_extrapolation", minimum=1.0)
        self.tail_shape = float_like(tail_shape, "tail_shape", minimum=-1.0, maximum=1.0, optional=True)

    def __repr__(self) -> str:
        fitted = f", threshold_={self.threshold_:.5g} ({self.method_})" if hasattr(self, "threshold_") else ""
        return f"EmpiricalThreshold(false_alarm={self.false_alarm:g}{fitted})"

    def samples_needed(self) -> int:
        """Smallest calibration sample that supports ``false_alarm`` (empirical or tail fit)."""
        emp = _ceil(self.min_exceedances / self.false_alarm)
        gpd = max(_ceil(self.min_tail / self.tail_fraction),
                  _ceil(self.min_exceedances / (self.false_alarm * self.max_extrapolation)))
        return min(emp, gpd)

    def calibrate(self, statistic: Any) -> EmpiricalThreshold:
        """Estimate the threshold from healthy values of the statistic; returns ``self``.

        Parameters
        ----------
        statistic : array_like, Series or DataArray
            Values of the detection statistic under normal operation (all channels pooled).

        Raises
        ------
        ValueError
            If the sample is too small for ``false_alarm`` (the message says how many samples are needed).
        """
        sig = as_signal(statistic, "statistic", allow_constant=True)
        g = np.sort(sig.values.ravel())
        n = g.size
        pf = self.false_alarm
        if n * pf >= self.min_exceedances:
            self.method_ = "empirical"
            self.threshold_ = float(np.quantile(g, 1.0 - pf))
            self.gpd_ = None
        else:
            needed = self.samples_needed()
            if n < needed:
                raise ValueError(
                    f"statistic is too small to calibrate false_alarm={pf:g}: {n} samples, at least {needed} "
                    f"are needed (empirical quantile: {_ceil(self.min_exceedances / pf)}; generalised Pareto "
                    f"tail: {needed})")
            from scipy import stats

            u = float(np.quantile(g, 1.0 - self.tail_fraction))
            exc = g[g > u] - u
            zeta = exc.size / n
            if exc.size < self.min_tail or np.ptp(exc) == 0:
                raise ValueError(f"statistic has only {exc.size} distinct excesses over its "
                                 f"{1 - self.tail_fraction:g} quantile; a longer healthy sample is needed")
            if self.tail_shape is None:
                xi, _, scale = stats.genpareto.fit(exc, floc=0.0)
            elif self.tail_shape == 0.0:
                xi, scale = 0.0, float(exc.mean())           # ML scale of exponential excesses
            else:
                xi = self.tail_shape
                _, _, scale = stats.genpareto.fit(exc, f0=xi, floc=0.0)
            if abs(xi) < 1e-9:
                thr = u - scale * math.log(pf / zeta)
            else:
                thr = u + scale / xi * ((pf / zeta) ** (-xi) - 1.0)
            self.method_ = "gpd"
            self.threshold_ = float(thr)
            self.gpd_ = {"shape": float(xi), "scale": float(scale), "location": u, "zeta": zeta}
        self.sample_ = g
        self.nobs_ = n
        return self

    def exceedance(self, value: Any) -> np.ndarray:
        """Estimated probability that the healthy statistic exceeds ``value`` (empirical, or the tail fit
        above its location)."""
        self._check_fitted()
        v = np.asarray(value, dtype=np.float64)
        g = self.sample_
        p = 1.0 - np.searchsorted(g, v, side="right") / g.size
        if self.gpd_ is not None:
            u, xi, sc, z = (self.gpd_[k] for k in ("location", "shape", "scale", "zeta"))
            above = v > u
            t = np.maximum(v - u, 0.0)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                tail = z * (np.exp(-t / sc) if abs(xi) < 1e-9 else np.maximum(1 + xi * t / sc, 0) ** (-1 / xi))
            p = np.where(above, tail, p)
        return p

    def _check_fitted(self) -> None:
        if not hasattr(self, "threshold_"):
            raise ValueError("EmpiricalThreshold is not calibrated: call calibrate(healthy statistic) first")

    def plot(self, ax: Any = None, **kwargs: Any) -> Any:
        """Probability plot of the healthy statistic with the chosen threshold (Hansen et al., Fig. 2)."""
        self._check_fitted()
        from tsfdi.plotting.decision import plot_threshold

        return plot_threshold(self, ax=ax, **kwargs)


# ---------------------------------------------------------------------------------------------- results
class GLRTScan:
    """The GLRT statistic series and the ML estimates behind it (from :meth:`GLRT.scan`).

    Attributes
    ----------
    g : ndarray, shape (nobs, k)
        :math:`g(k)` per channel.
    change_index : ndarray of int, shape (nobs, k)
        Estimated change instant :math:`\\hat j` (sample position) maximising the likelihood ratio at each k.
    jump : ndarray, shape (nobs, k)
        Maximum-likelihood jump :math:`\\hat A` (mean of the residual since :math:`\\hat j`).
    """

    def __init__(self, g: np.ndarray, change_index: np.ndarray, jump: np.ndarray) -> None:
        self.g, self.change_index, self.jump = g, change_index, jump

    def __repr__(self) -> str:
        return f"GLRTScan(nobs={self.g.shape[0]}, channels={self.g.shape[1]}, max g={self.g.max():.4g})"


# ---------------------------------------------------------------------------------------------- GLRT
class GLRT(ResidualTest):
    r"""Generalised likelihood ratio test for a change in mean of a Gaussian residual (Hansen et al., eqs. 1-3).

    Parameters
    ----------
    window : int
        :math:`M`: the change instant :math:`j` ranges over the last ``window`` samples (post-change segment
        lengths ``1..window``).
    sigma : float or array_like, optional
        Standard deviation of the healthy residual (per channel). ``None``: taken from the baseline model by
        :func:`tsfdi.detect`, else estimated by :meth:`calibrate`, else from the tested residual itself
        (which lowers power against large jumps).
    threshold : "analytical", float or EmpiricalThreshold
        ``"analytical"``: :math:`\gamma = \chi^2_{1 - \alpha / M}(1) / 2` (below); a float: a fixed
        :math:`\gamma`; an :class:`EmpiricalThreshold`: calibrated on healthy residuals by :meth:`calibrate`.
    alpha : float
        Per-sample false-alarm probability for the analytical threshold.

        The false-alarm probability of the GLRT (``alpha`` here, ``false_alarm`` of an
        :class:`EmpiricalThreshold`) is per sample, as in Hansen et al. (Fig. 2): on a healthy record of
        ``N`` samples about ``N * alpha`` samples alarm, so :meth:`test` (which rejects when any sample alarms)
        rejects a long healthy record with high probability unless ``alpha << 1 / N``. The alarm rate of a
        record is in ``details["alarm_rate"]``.

    Notes
    -----
    H0: :math:`x_i = w_i`, H1: :math:`x_i = A + w_i` for :math:`i \ge j` (eq. 1), :math:`w` iid
    :math:`N(0, \sigma^2)`. The log-likelihood ratio of the samples :math:`j..k` (eq. 2) maximised over the
    jump, :math:`\hat A = \frac{1}{n}\sum_{i=j}^{k} x_i`, is :math:`S_j^k = (\sum_{i=j}^k x_i)^2 / (2 \sigma^2 n)`,
    :math:`n = k - j + 1`, and (eq. 3)

    .. math:: g(k) = \max_{k - M < j \le k} \frac{1}{2\sigma^2 n}\Big(\sum_{i=j}^{k} x_i\Big)^2 .

    Each :math:`g(k)` is accumulated backwards in O(M), O(N M) in all (compiled), instead of the
    O(N M^2) of recomputing every window sum (:func:`glrt_direct`).

    Analytical threshold: for a fixed :math:`j`, :math:`2 S_j^k \sim \chi^2(1)` when the residuals are iid
    Gaussian; the union bound over the :math:`M` change instants gives
    :math:`P(g(k) > \gamma) \le M \, P(\chi^2(1) > 2\gamma)`, so :math:`\gamma = \chi^2_{1-\alpha/M}(1)/2`
    has a per-sample false-alarm rate of at most :math:`\alpha` -- **valid only for iid residuals**. For
    correlated residuals (the usual case in flight, Hansen et al.) the rate is far higher; use
    :class:`EmpiricalThreshold`.

    References
    ----------
    Hansen, Blanke, Adrian, *A Framework for Rapid Diagnosis of Critical Faults in UAVs*, eqs. 1-3, Fig. 2.
    Kay, S. M., *Fundamentals of Statistical Signal Processing, Vol. II: Detection Theory*, ch. 12.
    """

    name = "GLRT (change in mean)"
    null_hypothesis = "residual mean is zero over the window (healthy)"
    alternative_hypothesis = "residual mean jumped to A != 0 at some instant in the window (fault)"

    def __init__(self, window: int = 100, sigma: Any = None, threshold: Any = "analytical", *,
                 alpha: float = 1e-3) -> None:
        self.window = int_like(window, "window", minimum=1)
        self.sigma = self._check_sigma(sigma)
        self.alpha = self._check_alpha(alpha)
        if isinstance(threshold, str):
            self.threshold = option(threshold, "threshold", ("analytical",))
        elif isinstance(threshold, EmpiricalThreshold):
            self.threshold = threshold
        else:
            self.threshold = float_like(threshold, "threshold", minimum=0.0, strict_min=True)

    def __repr__(self) -> str:
        return f"GLRT(window={self.window}, sigma={self.sigma}, threshold={self.threshold!r}, alpha={self.alpha:g})"

    @staticmethod
    def _check_sigma(sigma: Any) -> np.ndarray | None:
        if sigma is None:
            return None
        s = np.atleast_1d(np.asarray(sigma, dtype=np.float64))
        if s.ndim != 1 or not np.all(np.isfinite(s)) or np.any(s <= 0):
            raise ValueError(f"sigma must be a positive finite number or one per channel, got {sigma!r}")
        return s

    # ------------------------------------------------------------------ threshold
    @property
    def threshold_(self) -> float:
        """The threshold :math:`\\gamma` in use."""
        if isinstance(self.threshold, EmpiricalThreshold):
            self.threshold._check_fitted()
            return self.threshold.threshold_
        if self.threshold == "analytical":
            return float(special.chdtri(1.0, self.alpha / self.window) / 2.0)
        return float(self.threshold)

    @property
    def false_alarm(self) -> float:
        """Per-sample false-alarm probability targeted by the threshold."""
        if isinstance(self.threshold, EmpiricalThreshold):
            return self.threshold.false_alarm
        return self.alpha

    def calibrate(self, healthy: Any) -> GLRT:
        """Calibrate on healthy residuals: ``sigma_`` (if ``sigma`` is None) and an empirical threshold.

        The statistic of every channel of ``healthy`` is pooled into one sample for the
        :class:`EmpiricalThreshold` (a copy is stored, so one threshold object can serve several tests).
        Returns ``self``.
        """
        sig = as_signal(healthy, "healthy", min_nobs=2)
        if self.sigma is None:
            self.sigma_ = sig.values.std(axis=0, ddof=1)
        g = self._g_values(sig.values, self._sigma_for(sig.nchan, sig.values))
        if isinstance(self.threshold, EmpiricalThreshold):
            self.threshold = copy.copy(self.threshold).calibrate(g.ravel())
        self.healthy_statistic_ = g
        return self

    def reference(self, results: Any) -> dict:
        """``sigma`` from a fitted baseline (square root of its unbiased residual variance)."""
        if self.sigma is not None or hasattr(self, "sigma_"):
            return {}
        var, _ = baseline_variance(results)
        return {"sigma": np.sqrt(var)}

    def _sigma_for(self, k: int, values: np.ndarray | None, sigma: Any = None) -> np.ndarray:
        s = self._check_sigma(sigma) if sigma is not None else (
            self.sigma if self.sigma is not None else getattr(self, "sigma_", None))
        if s is None:
            s = values.std(axis=0, ddof=1)
            if np.any(s <= 0):
                raise ValueError("resid is constant: sigma cannot be estimated from it; pass sigma")
        if s.shape[0] == 1 and k > 1:
            s = np.repeat(s, k)
        if s.shape[0] != k:
            raise ValueError(f"sigma has {s.shape[0]} values for {k} channels")
        return s

    # ------------------------------------------------------------------ batch
    def _g_values(self, x: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        g = np.empty(x.shape)
        for c in range(x.shape[1]):
            g[:, c] = _scan_g(np.ascontiguousarray(x[:, c]), 0, self.window, 0.5 / sigma[c] ** 2)
        return g

    def _scan_values(self, x: np.ndarray, sigma: np.ndarray) -> GLRTScan:
        n, k = x.shape
        g = np.empty((n, k))
        ci = np.empty((n, k), dtype=np.int64)
        jump = np.empty((n, k))
        pos = np.arange(n)
        for c in range(k):
            gc, best, jc = _scan(np.ascontiguousarray(x[:, c]), 0, self.window, 0.5 / sigma[c] ** 2)
            g[:, c], ci[:, c], jump[:, c] = gc, pos - best + 1, jc
        return GLRTScan(g, ci, jump)

    def scan(self, resid: Any, sigma: Any = None) -> GLRTScan:
        """g(k), the estimated change instant and the ML jump at every sample (arrays, time on axis 0)."""
        sig = as_signal(resid, "resid", allow_constant=True)
        return self._scan_values(sig.values, self._sigma_for(sig.nchan, sig.values, sigma))

    def statistic(self, resid: Any, sigma: Any = None) -> Any:
        """The statistic series g(k) (eq. 3) in the caller's data kind, same index as ``resid``."""
        sig = as_signal(resid, "resid", allow_constant=True)
        g = self._g_values(sig.values, self._sigma_for(sig.nchan, sig.values, sigma))
        return sig.wrap(g, 0)

    def test(self, resid: Any, sigma: Any = None) -> Decision:
        """Run the GLRT over a residual record.

        Returns
        -------
        Decision
            ``statistic`` is the largest g(k) per channel, ``threshold`` :math:`\\gamma`; ``reject`` when any
            sample of any channel alarms. ``details``: ``"g"`` (the series, caller's kind), ``"alarms"``
            (positions of alarm samples per channel), ``"first_alarm"``, ``"change_index"`` and ``"jump"``
            (ML change instant and jump at the first alarm, per channel; -1 / nan without alarm),
            ``"first_alarm_label"`` / ``"change_label"`` (index labels for pandas/xarray input).
        """
        sig = as_signal(resid, "resid", allow_constant=True)
        s = self._sigma_for(sig.nchan, sig.values, sigma)
        gvals = self._g_values(sig.values, s)
        gamma = self.threshold_
        alarm = gvals > gamma
        k = sig.nchan
        first = np.full(k, -1, dtype=np.int64)
        change = np.full(k, -1, dtype=np.int64)
        jump = np.full(k, np.nan)
        alarms = []
        for c in range(k):
            idx = np.flatnonzero(alarm[:, c])
            alarms.append(idx)
            if idx.size:
                i0 = int(idx[0])
                lo = max(0, i0 - self.window + 1)
                _, best, jc = _scan(np.ascontiguousarray(sig.values[lo:i0 + 1, c]), i0 - lo, self.window,
                                    0.5 / s[c] ** 2)
                first[c] = i0
                change[c] = i0 - best[0] + 1
                jump[c] = jc[0]
        labels = sig.index if sig.index is not None else None

        def _label(i: int) -> Any:
            if i < 0:
                return None
            return labels[i] if labels is not None else int(i)

        analytical = self.threshold == "analytical"
        details = {"g": sig.wrap(gvals, 0), "alarms": alarms, "first_alarm": first, "change_index": change,
                   "jump": jump, "first_alarm_label": [_label(i) for i in first],
                   "change_label": [_label(i) for i in change], "window": self.window, "sigma": s,
                   "threshold_method": ("analytical" if analytical else
                                        self.threshold.method_ if isinstance(self.threshold, EmpiricalThreshold)
                                        else "fixed"),
                   "alarm_rate": alarm.mean(axis=0)}
        stat = gvals.max(axis=0)
        return Decision(statistic=stat, threshold=np.full(k, gamma), pvalue=np.full(k, np.nan),
                        alpha=self.false_alarm, reject=bool(alarm.any()),
                        df=np.full(k, 1.0 if analytical else np.nan), nobs=sig.nobs,
                        null_hypothesis=self.null_hypothesis, alternative_hypothesis=self.alternative_hypothesis,
                        details=details, channel_reject=alarm.any(axis=0), channels=tuple(sig.channels),
                        test="GLRT")

    # ------------------------------------------------------------------ streaming
    def stream(self, nchan: int = 1, sigma: Any = None) -> GLRTStream:
        """A stateful sample-by-sample GLRT with this test's window, sigma and threshold."""
        nchan = int_like(nchan, "nchan", minimum=1)
        s = self._sigma_for(nchan, None, sigma) if (sigma is not None or self.sigma is not None
                                                    or hasattr(self, "sigma_")) else None
        if s is None:
            raise ValueError("sigma is needed for a stream: pass sigma, set it on the GLRT, or calibrate() first")
        return GLRTStream(self.window, s, self.threshold_)


class GLRTStream:
    """Incremental GLRT: feed residual samples one at a time (:meth:`update`) or in blocks (:meth:`extend`).

    The values equal :meth:`GLRT.statistic` on the concatenated samples. Each update costs O(window).

    Attributes
    ----------
    k : int
        Number of samples seen.
    g : float or ndarray
        Last statistic (float for one channel).
    alarm : bool
        Whether the last sample alarmed (any channel).
    first_alarm : int or None
        Sample number (0-based) of the first alarm.
    change_index, jump : ndarray
        ML change instant (sample number) and jump of the last sample, per channel.
    """

    def __init__(self, window: int, sigma: np.ndarray, threshold: float) -> None:
        self.window = int(window)
        self.sigma = np.asarray(sigma, dtype=np.float64)
        self.nchan = self.sigma.shape[0]
        self.threshold = float(threshold)
        self._scale = 0.5 / self.sigma ** 2
        self.reset()

    def reset(self) -> None:
        """Forget all samples."""
        self._buf = np.zeros((self.nchan, self.window))
        self._head = np.full(self.nchan, self.window - 1, dtype=np.int64)
        self._count = np.zeros(self.nchan, dtype=np.int64)
        self.k = 0
        self.g = 0.0 if self.nchan == 1 else np.zeros(self.nchan)
        self.alarm = False
        self.first_alarm: int | None = None
        self.change_index = np.full(self.nchan, -1, dtype=np.int64)
        self.jump = np.full(self.nchan, np.nan)

    def update(self, x: Any) -> Any:
        """Add one sample (a float, or one value per channel) and return g (float for one channel)."""
        v = np.atleast_1d(np.asarray(x, dtype=np.float64))
        if v.shape != (self.nchan,):
            raise ValueError(f"x must hold {self.nchan} value(s), got shape {np.shape(x)}")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"x contains NaN/inf at sample {self.k}")
        g = np.empty(self.nchan)
        for c in range(self.nchan):
            gc, nb, jc, h, cnt = _ring_update(self._buf[c], self._head[c], self._count[c], v[c], self.window,
                                              self._scale[c])
            self._head[c], self._count[c] = h, cnt
            g[c] = gc
            self.change_index[c] = self.k - nb + 1
            self.jump[c] = jc
        self._finish(g)
        return self.g

    def _finish(self, g: np.ndarray) -> None:
        self.alarm = bool(np.any(g > self.threshold))
        if self.alarm and self.first_alarm is None:
            self.first_alarm = self.k
        self.k += 1
        self.g = float(g[0]) if self.nchan == 1 else g

    def extend(self, xs: Any) -> np.ndarray:
        """Add a block of samples ``(n,)`` or ``(n, nchan)``; returns g for the block, shape (n,) or (n, nchan)."""
        arr = np.asarray(xs, dtype=np.float64)
        arr2 = arr[:, None] if arr.ndim == 1 else arr
        if arr2.ndim != 2 or arr2.shape[1] != self.nchan:
            raise ValueError(f"xs must have shape (n,) or (n, {self.nchan}), got {arr.shape}")
        if not np.all(np.isfinite(arr2)):
            raise ValueError("xs contains NaN/inf")
        n = arr2.shape[0]
        if n == 0:
            return arr2.reshape(0) if arr.ndim == 1 else arr2
        out = np.empty((n, self.nchan))
        for c in range(self.nchan):
            cnt = int(self._count[c])
            hist = np.roll(self._buf[c], -(int(self._head[c]) + 1))[self.window - cnt:] if cnt else np.zeros(0)
            full = np.concatenate([hist, arr2[:, c]])
            g, best, jc = _scan(full, cnt, self.window, self._scale[c])
            out[:, c] = g
            tail = full[-self.window:]
            newcnt = min(self.window, full.size)
            buf = np.zeros(self.window)
            buf[:newcnt] = tail[-newcnt:]
            self._buf[c] = buf
            self._head[c] = newcnt - 1
            self._count[c] = newcnt
            self.change_index[c] = self.k + n - 1 - best[-1] + 1
            self.jump[c] = jc[-1]
        alarm_rows = np.flatnonzero(np.any(out > self.threshold, axis=1))
        if alarm_rows.size and self.first_alarm is None:
            self.first_alarm = self.k + int(alarm_rows[0])
        self.k += n - 1
        self._finish(out[-1])
        return out[:, 0] if arr.ndim == 1 else out

"""GLRT for a change in mean of a Gaussian residual (Hansen, Blanke, Adrian, eqs. 1-3).

The data-driven threshold (:class:`~tsfdi.detection.threshold.EmpiricalThreshold`) lives in
:mod:`tsfdi.detection.threshold`. ``scale`` is the standard deviation of the healthy residual throughout (the
compiled kernels receive the coefficient ``coef = 1 / (2 scale^2)`` of eq. 3). The kernels see the residual and
the scale both divided by the power of two nearest the scale (:func:`_unit`, exact), so that :math:`g` does not
depend on their common scale, and a window never longer than the record (the statistic is the same, the memory
bounded by the data).
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numba
import numpy as np
import pandas as pd
from scipy import special

from tsfdi._data import as_signal, is_xarray
from tsfdi._validation import float_like, int_like, option, sample_vector
from tsfdi.detection.base import ResidualTest, baseline_variance, max_abs, rescale_exponent
from tsfdi.detection.decision import Decision
from tsfdi.detection.threshold import EmpiricalThreshold

__all__ = ["GLRT", "GLRTStream", "GLRTScan", "ParameterGLRT", "glrt_direct"]


# ---------------------------------------------------------------------------------------------- kernels
@numba.njit(cache=True, nogil=True)
def _scan(x, first, window, coef):  # pragma: no cover - compiled
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
        g[k - first] = gmax * coef
        best[k - first] = nbest
        jump[k - first] = sbest / nbest
    return g, best, jump


@numba.njit(cache=True, nogil=True, fastmath=True)
def _scan_g(x, first, window, coef):  # pragma: no cover - compiled
    """g(k) only, for k in [first, len(x)): O(window) per sample.

    Window sums are differences of a cumulative sum ``c`` restarted every block of 2048 outputs (so its magnitude
    stays bounded on long records). Within a block the loop runs over the post-change length ``n`` outside and the
    outputs ``k`` inside: ``g[k] = max(g[k], (c[k] - c[k - n])^2 coef / n)`` reads ``c`` at unit-stride offsets
    and has no loop-carried dependency, so LLVM compiles it to packed subtract / multiply / compare instructions
    (4 doubles each with AVX2; ``tests/detection/test_glrt.py`` checks the assembly for packed instructions). The
    other order (max over ``n`` inside, a floating-point max reduction) compiles to scalar code. Where every output
    of the block has at least ``n + 3`` samples, one pass takes four lengths ``n .. n + 3``: ``c[k]`` and ``g[k]``
    are loaded and ``g[k]`` stored once for four products instead of four times (1.9x faster at N = 60,000,
    M = 500 on the benchmark's machine: the single-length pass is bound by its loads and stores). Each ``g[k]`` is
    the max of the same products in any order (equal to about 1e-16 relative: ``fastmath`` may round a product
    differently).
    """
    n_all = x.shape[0]
    n_out = n_all - first
    g = np.zeros(n_out)
    block = 2048                        # g and c of a block stay in the L1 / L2 cache
    c = np.empty(block + window + 1)
    for b0 in range(first, n_all, block):
        b1 = min(b0 + block, n_all)
        lo = max(b0 - window, 0)
        c[0] = 0.0
        for i in range(lo, b1):
            c[i - lo + 1] = c[i - lo] + x[i]
        gb = g[b0 - first:b1 - first]
        n = 1
        while n <= window:
            k0 = max(b0, n - 1)                 # outputs with at least n samples: k + 1 >= n
            if k0 >= b1:
                break
            if n + 3 <= window and b0 >= n + 2:
                # every output of the block has n + 3 samples: lengths n .. n + 3 in one pass (slices, so the
                # indices are non-negative and the loop vectorises)
                w0, w1, w2, w3 = coef / n, coef / (n + 1), coef / (n + 2), coef / (n + 3)
                at, size = b0 - lo + 1, b1 - b0     # c at k + 1 (sum up to x[k]) for k = b0
                hi = c[at:at + size]
                l0 = c[at - n:at - n + size]
                l1 = c[at - n - 1:at - n - 1 + size]
                l2 = c[at - n - 2:at - n - 2 + size]
                l3 = c[at - n - 3:at - n - 3 + size]
                for j in range(size):
                    h = hi[j]
                    d0, d1, d2, d3 = h - l0[j], h - l1[j], h - l2[j], h - l3[j]
                    v0, v1, v2, v3 = d0 * d0 * w0, d1 * d1 * w1, d2 * d2 * w2, d3 * d3 * w3
                    v0 = v0 if v0 > v1 else v1
                    v2 = v2 if v2 > v3 else v3
                    v0 = v0 if v0 > v2 else v2
                    gb[j] = v0 if v0 > gb[j] else gb[j]
                n += 4
                continue
            w = coef / n
            hi = c[k0 - lo + 1:b1 - lo + 1]     # c at k + 1 (sum up to x[k])
            low = c[k0 - lo + 1 - n:b1 - lo + 1 - n]
            gk = gb[k0 - b0:]
            for j in range(b1 - k0):
                d = hi[j] - low[j]
                v = d * d * w
                gk[j] = v if v > gk[j] else gk[j]
            n += 1
    return g


@numba.njit(cache=True, nogil=True)
def _direct(x, window, coef):  # pragma: no cover - compiled
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
        g[k] = gmax * coef
    return g


@numba.njit(cache=True, nogil=True)
def _ring_update(buf, head, count, value, coef):  # pragma: no cover - compiled
    """Push one sample into a ring buffer (the last ``len(buf)`` samples) and return (g, best n, jump, new head,
    new count)."""
    head = (head + 1) % buf.shape[0]
    buf[head] = value
    if count < buf.shape[0]:
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
            idx = buf.shape[0] - 1
    return gmax * coef, nbest, sbest / nbest, head, count


#: Largest |residual| / scale the kernels accept (2**400, about 2.6e120): g of a window stays far below 1e308.
_MAX_RATIO_EXP = 400


def _unit(x: np.ndarray, scale: np.ndarray, name: str = "resid", *,
          always: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``x`` and ``scale`` (per column) divided by the power of two nearest ``scale``, and its exponents (unchanged,
    exponents 0, when both are within 2**-256 .. 2**256, unless ``always``).

    The division is exact, so g (a function of ``x / scale``) is bit for bit unchanged, while ``x ** 2`` and
    ``scale ** 2`` no longer overflow or underflow. A residual more than 2**400 scales from zero is refused (its g
    would be beyond the float range: the scale is wrong).
    """
    e = np.frexp(scale)[1]
    top = max_abs(x.reshape(x.shape[0], -1)) if x.size else np.zeros(1)
    with np.errstate(over="ignore"):
        limit = np.ldexp(1.0, e + _MAX_RATIO_EXP)
    if np.any(top > limit):
        ratio = float(np.max(np.log10(top) - np.log10(scale)))
        raise ValueError(f"{name} is up to 1e{ratio:.0f} times scale ({scale}): the GLRT statistic would be beyond "
                         "the float range; scale must be the residual's standard deviation")
    if not always and not np.any(np.abs(e) > 256) and not np.any(top > 2.0 ** 256):
        return x, scale, np.zeros_like(e)               # squares of sums and 1 / scale**2 are floats: nothing to do
    return np.ldexp(x, -e), np.ldexp(scale, -e), e


def _std(x: np.ndarray) -> np.ndarray:
    """Sample standard deviation per column, computed on ``x`` rescaled by a power of two (exact, no overflow)."""
    e = rescale_exponent(x)
    if not e.any():
        return x.std(axis=0, ddof=1)
    return np.ldexp(np.ldexp(x, -e).std(axis=0, ddof=1), e)


def _chi2_1_isf(log_p: float) -> float:
    """Upper quantile of the chi-square(1) law at probability ``exp(log_p)``, also below the float range (log
    domain): ``chdtri`` down to 1e-300, then :math:`t = \\Phi^{-1}(p / 2)^2` by ``ndtri_exp`` of the log."""
    if log_p >= math.log(1e-300):
        return float(special.chdtri(1.0, np.exp(log_p)))
    return float(special.ndtri_exp(log_p - np.log(2.0)) ** 2)


def _chi2_isf(log_p: float, df: float) -> float:
    r"""Upper quantile of the chi-square(``df``) law at probability ``exp(log_p)``, also below the float range:
    ``chdtri`` down to 1e-300, then Newton's method on the asymptotic series of the log upper tail,
    :math:`\ln Q(a, z) \approx (a - 1)\ln z - z - \ln\Gamma(a) + \ln(1 + (a-1)/z + (a-1)(a-2)/z^2)`,
    :math:`a = df / 2`, :math:`z = x / 2` (:math:`z > 690` there: the series' next term is below 1e-4)."""
    if df == 1.0:
        return _chi2_1_isf(log_p)
    if log_p >= math.log(1e-300):
        return float(special.chdtri(df, math.exp(log_p)))
    a = df / 2.0
    z = -log_p
    for _ in range(100):
        f = ((a - 1) * math.log(z) - z - math.lgamma(a) + math.log1p((a - 1) / z + (a - 1) * (a - 2) / z ** 2)
             - log_p)
        step = f / ((a - 1) / z - 1.0)
        z -= step
        if abs(step) <= 1e-14 * z:
            break
    return 2.0 * z


def _is_record_list(value: Any) -> bool:
    """A non-empty list / tuple of arrays, pandas or xarray objects (several records), not of numbers."""
    return (isinstance(value, (list, tuple)) and len(value) > 0
            and all(isinstance(v, (np.ndarray, pd.Series, pd.DataFrame)) or is_xarray(v) for v in value))


def glrt_direct(resid: Any, window: int, scale: float) -> np.ndarray:
    """Direct O(N * window^2) evaluation of g(k) for a scalar residual (reference for tests and benchmarks).

    ``scale`` is the standard deviation :math:`\\sigma` of the healthy residual (eq. 3).
    """
    x = as_signal(resid, "resid", vector=False, allow_constant=True).values[:, 0]
    window = int_like(window, "window", minimum=1)
    scale = float_like(scale, "scale", minimum=0.0, strict_min=True)
    xu, su, _ = _unit(x, np.float64(scale))
    return _direct(xu, min(window, x.shape[0]), 0.5 / su ** 2)


# ---------------------------------------------------------------------------------------------- results

def _threshold_option(threshold: Any) -> Any:
    """A GLRT's ``threshold``: ``"theoretical"``, an :class:`EmpiricalThreshold` or a positive number."""
    if isinstance(threshold, str):
        return option(threshold, "threshold", ("theoretical",))
    if isinstance(threshold, EmpiricalThreshold):
        return threshold
    return float_like(threshold, "threshold", minimum=0.0, strict_min=True)

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
    scale : float or array_like, optional
        Standard deviation :math:`\sigma` of the healthy residual (per channel). ``None``: taken from the
        baseline model by :func:`tsfdi.detect`, else estimated by :meth:`calibrate`, else from the tested
        residual itself (which lowers power against large jumps).
    threshold : "theoretical", float or EmpiricalThreshold
        ``"theoretical"``: :math:`\gamma = \chi^2_{1 - \alpha / M}(1) / 2` (below); a float: a fixed
        :math:`\gamma`; an :class:`~tsfdi.EmpiricalThreshold`: calibrated on healthy residuals by
        :meth:`calibrate`.
    alpha : float
        False-alarm probability of the theoretical threshold: alpha is the false-alarm probability per sample,
        not per window.
        For a multi-channel decision (it rejects when any channel alarms) ``alpha`` is per channel and per sample:
        this test has no ``correction=``, so ``k`` channels give up to ``1 - (1 - alpha)^k`` per sample; give it
        ``alpha / k`` for a decision at ``alpha``.

        The false-alarm probability of the GLRT (``alpha`` here, ``false_alarm`` of an
        :class:`~tsfdi.EmpiricalThreshold`) is per sample, as in Hansen et al. (Fig. 2): on a healthy record
        of ``N`` samples about ``N * alpha`` samples alarm, so :meth:`test` (which rejects when any sample
        alarms) rejects a long healthy record with high probability unless ``alpha << 1 / N``. The alarm rate
        of a record is in ``details["alarm_rate"]``.

    Attributes
    ----------
    scale_ : ndarray, shape (k,)
        Standard deviation estimated by :meth:`calibrate` (when ``scale`` is None).

    Notes
    -----
    H0: :math:`x_i = w_i`, H1: :math:`x_i = A + w_i` for :math:`i \ge j` (eq. 1), :math:`w` iid
    :math:`N(0, \sigma^2)`, :math:`\sigma` = ``scale``. The log-likelihood ratio of the samples :math:`j..k`
    (eq. 2) maximised over the jump, :math:`\hat A = \frac{1}{n}\sum_{i=j}^{k} x_i`, is
    :math:`S_j^k = (\sum_{i=j}^k x_i)^2 / (2 \sigma^2 n)`, :math:`n = k - j + 1`, and (eq. 3)

    .. math:: g(k) = \max_{k - M < j \le k} \frac{1}{2\sigma^2 n}\Big(\sum_{i=j}^{k} x_i\Big)^2 .

    :meth:`statistic` and :meth:`test` take the window sums as differences of a cumulative sum, O(N M) in all in
    compiled packed (SIMD) code; :meth:`scan` (which also returns the change instant and jump) accumulates each
    :math:`g(k)` backwards in O(M), O(N M) in all (scalar compiled code). Both avoid the O(N M^2) of recomputing
    every window sum (:func:`glrt_direct`).

    Theoretical threshold: for a fixed :math:`j`, :math:`2 S_j^k \sim \chi^2(1)` when the residuals are iid
    Gaussian; the union bound over the :math:`M` change instants gives
    :math:`P(g(k) > \gamma) \le M \, P(\chi^2(1) > 2\gamma)`, so :math:`\gamma = \chi^2_{1-\alpha/M}(1)/2`
    has a per-sample false-alarm rate of at most :math:`\alpha` -- **valid only for iid residuals**. For
    correlated residuals (the usual case in flight, Hansen et al.) the rate is far higher; use
    :class:`~tsfdi.EmpiricalThreshold`. The quantile is computed from the logarithm of :math:`\alpha / M`, so it
    is finite for any ``alpha`` and ``window`` (about 710 at :math:`\alpha / M = 10^{-310}`).

    Numerics and resources: :math:`g` depends on the residual only through ``resid / scale``; both are divided by
    the power of two nearest ``scale`` before anything is squared (exact), so residuals and scales near 1e300 or
    1e-300 give the :math:`g` of values near 1, and a residual more than about 1e120 scales from zero is refused
    (``ValueError``: the scale is wrong). A window longer than the record is the record (:math:`j` cannot precede
    the first sample): memory and time grow with the data, never with ``window``, and a :meth:`stream` keeps at
    most ``window`` past samples, allocated as they arrive. A constant residual is tested like any other: with a
    known ``scale`` a constant level :math:`A` gives :math:`g = n A^2 / (2\sigma^2)` (a frozen sensor away from
    the healthy mean alarms; a residual frozen at exactly 0 does not); without ``scale`` it cannot give its own
    scale (``ValueError``).

    References
    ----------
    Hansen, Blanke, Adrian, *A Framework for Rapid Diagnosis of Critical Faults in UAVs*, eqs. 1-3, Fig. 2.
    Kay, S. M., *Fundamentals of Statistical Signal Processing, Vol. II: Detection Theory*, ch. 12.
    """

    name = "GLRT (change in mean)"
    null_hypothesis = "residual mean is zero over the window (healthy)"
    alternative_hypothesis = "residual mean jumped to A != 0 at some instant in the window (fault)"

    def __init__(self, window: int = 100, scale: Any = None, threshold: Any = "theoretical", *,
                 alpha: float = 1e-3) -> None:
        self.window = int_like(window, "window", minimum=1)
        self.scale = self._check_scale(scale)
        self.alpha = self._check_alpha(alpha)
        self.threshold = _threshold_option(threshold)

    def __repr__(self) -> str:
        return f"GLRT(window={self.window}, scale={self.scale}, threshold={self.threshold!r}, alpha={self.alpha:g})"

    @staticmethod
    def _check_scale(scale: Any) -> np.ndarray | None:
        if scale is None:
            return None
        if isinstance(scale, (str, bytes, bool, np.bool_)):
            raise TypeError(f"scale must be a positive finite number or one per channel, got {scale!r}")
        try:
            s = np.atleast_1d(np.asarray(scale, dtype=np.float64))
        except (TypeError, ValueError):
            raise TypeError(f"scale must be a positive finite number or one per channel, got {scale!r}") from None
        if s.ndim != 1 or not np.all(np.isfinite(s)) or np.any(s <= 0):
            raise ValueError(f"scale must be a positive finite number or one per channel, got {scale!r}")
        return s

    # ------------------------------------------------------------------ threshold
    @property
    def threshold_(self) -> float:
        """The threshold :math:`\\gamma` in use (the theoretical one for the full ``window``; :meth:`test` clips
        the window to the record, :meth:`critical_value`)."""
        return self.critical_value()

    def critical_value(self, nobs: int | None = None) -> float:
        """The threshold :math:`\\gamma` for a record of ``nobs`` samples: the theoretical one takes the union
        bound over the :math:`\\min(M, \\text{nobs})` change instants such a record has (``None``: :math:`M`);
        a calibrated or fixed threshold does not depend on it."""
        if isinstance(self.threshold, EmpiricalThreshold):
            self.threshold.check_fitted()
            return self.threshold.threshold_
        if self.threshold == "theoretical":
            m = self.window if nobs is None else min(self.window, int_like(nobs, "nobs", minimum=1))
            return _chi2_1_isf(math.log(self.alpha) - math.log(m)) / 2.0
        return float(self.threshold)

    @property
    def false_alarm(self) -> float:
        """Per-sample false-alarm probability targeted by the threshold (per sample, not per window)."""
        if isinstance(self.threshold, EmpiricalThreshold):
            return self.threshold.false_alarm
        return self.alpha

    def calibrate(self, healthy: Any) -> GLRT:
        """Calibrate on healthy residuals: ``scale_`` (if ``scale`` is None) and an empirical threshold.

        ``healthy`` is one residual record or a list / tuple of records (numpy arrays, pandas or xarray objects;
        same channels; a list of numbers is one record): the scale is the
        standard deviation of all their samples, and the statistic is computed record by record (no window
        straddles two records). The statistic of every channel of every record is pooled into one sample for the
        :class:`~tsfdi.EmpiricalThreshold` (a copy is stored, so one threshold object can serve several
        tests). Returns ``self``.
        """
        recs = list(healthy) if _is_record_list(healthy) else [healthy]
        sigs = [as_signal(r, "healthy" if len(recs) == 1 else f"healthy[{i}]", min_nobs=2)
                for i, r in enumerate(recs)]
        if len({s.nchan for s in sigs}) > 1:
            raise ValueError(f"healthy: every record must have the same channels, got {[s.nchan for s in sigs]}")
        pooled = np.concatenate([s.values for s in sigs])
        if self.scale is None:
            self.scale_ = _std(pooled)
        s = self._scale_for(sigs[0].nchan, pooled)
        g = np.concatenate([self._g_values(sg.values, s) for sg in sigs])     # no window straddles two records
        if isinstance(self.threshold, EmpiricalThreshold):
            self.threshold = copy.copy(self.threshold).calibrate(g.ravel())
        self.healthy_statistic_ = g
        return self

    def reference(self, results: Any) -> dict:
        """``scale`` from a fitted baseline (square root of its unbiased residual variance), as
        ``{"scale": ndarray}``; empty when the test already has a ``scale`` (given or calibrated)."""
        if self.scale is not None or hasattr(self, "scale_"):
            return {}
        var, _ = baseline_variance(results)
        return {"scale": np.sqrt(var)}

    def _scale_for(self, k: int, values: np.ndarray | None, scale: Any = None) -> np.ndarray:
        s = self._check_scale(scale) if scale is not None else (
            self.scale if self.scale is not None else getattr(self, "scale_", None))
        if s is None:
            if values.shape[0] < 2:
                raise ValueError("resid is too short to estimate scale from it: 1 sample, at least 2 are needed; "
                                 "pass scale")
            s = _std(values)
            if np.any(s <= 0):
                raise ValueError("resid is constant: scale cannot be estimated from it; pass scale")
        if s.shape[0] == 1 and k > 1:
            s = np.repeat(s, k)
        if s.shape[0] != k:
            raise ValueError(f"scale has {s.shape[0]} values for {k} channels")
        return s

    # ------------------------------------------------------------------ batch
    def _g_values(self, x: np.ndarray, scale: np.ndarray) -> np.ndarray:
        xu, su, _ = _unit(x, scale)
        window = min(self.window, x.shape[0])
        g = np.empty(x.shape)
        for c in range(x.shape[1]):
            g[:, c] = _scan_g(np.ascontiguousarray(xu[:, c]), 0, window, 0.5 / su[c] ** 2)
        return g

    def _scan_values(self, x: np.ndarray, scale: np.ndarray) -> GLRTScan:
        n, k = x.shape
        xu, su, e = _unit(x, scale)
        window = min(self.window, n)
        g = np.empty((n, k))
        ci = np.empty((n, k), dtype=np.int64)
        jump = np.empty((n, k))
        pos = np.arange(n)
        for c in range(k):
            gc, best, jc = _scan(np.ascontiguousarray(xu[:, c]), 0, window, 0.5 / su[c] ** 2)
            g[:, c], ci[:, c], jump[:, c] = gc, pos - best + 1, np.ldexp(jc, e[c])
        return GLRTScan(g, ci, jump)

    def scan(self, resid: Any, scale: Any = None) -> GLRTScan:
        """g(k), the estimated change instant and the ML jump at every sample (arrays, time on axis 0)."""
        sig = as_signal(resid, "resid", allow_constant=True)
        return self._scan_values(sig.values, self._scale_for(sig.nchan, sig.values, scale))

    def statistic(self, resid: Any, scale: Any = None) -> Any:
        """The statistic series g(k) (eq. 3) in the caller's data kind, same index as ``resid``."""
        sig = as_signal(resid, "resid", allow_constant=True)
        g = self._g_values(sig.values, self._scale_for(sig.nchan, sig.values, scale))
        return sig.wrap(g, 0)

    def test(self, resid: Any, scale: Any = None) -> Decision:
        """Run the GLRT over a residual record.

        Parameters
        ----------
        resid : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, k)
        scale : float or array_like, shape (k,), optional
            Standard deviation of the healthy residual per channel (overrides the test's ``scale``).

        Returns
        -------
        Decision
            ``statistic`` is the largest g(k) per channel, ``threshold`` :math:`\\gamma`; ``reject`` when any
            sample of any channel alarms; ``alpha`` is the per-sample false-alarm probability (not per
            window). ``details``: ``"g"`` (the series, caller's kind), ``"alarms"`` (positions of alarm samples
            per channel), ``"first_alarm"``, ``"change_index"`` and ``"jump"`` (ML change instant and jump at
            the first alarm, per channel; -1 / nan without alarm), ``"first_alarm_label"`` /
            ``"change_label"`` (index labels for pandas/xarray input), ``"scale"`` (standard deviation used),
            ``"threshold_method"`` (``"theoretical"``, ``"empirical"``, ``"gpd"`` or ``"fixed"``).
        """
        sig = as_signal(resid, "resid", allow_constant=True)
        s = self._scale_for(sig.nchan, sig.values, scale)
        gvals = self._g_values(sig.values, s)
        gamma = self.critical_value(sig.nobs)       # a record shorter than the window has fewer change instants
        alarm = gvals > gamma
        k = sig.nchan
        first = np.full(k, -1, dtype=np.int64)
        change = np.full(k, -1, dtype=np.int64)
        jump = np.full(k, np.nan)
        alarms = []
        xu, su, e = _unit(sig.values, s)
        window = min(self.window, sig.nobs)
        for c in range(k):
            idx = np.flatnonzero(alarm[:, c])
            alarms.append(idx)
            if idx.size:
                i0 = int(idx[0])
                lo = max(0, i0 - window + 1)
                _, best, jc = _scan(np.ascontiguousarray(xu[lo:i0 + 1, c]), i0 - lo, window, 0.5 / su[c] ** 2)
                first[c] = i0
                change[c] = i0 - best[0] + 1
                jump[c] = np.ldexp(jc[0], e[c])
        labels = sig.index if sig.index is not None else None

        def _label(i: int) -> Any:
            if i < 0:
                return None
            return labels[i] if labels is not None else int(i)

        theoretical = self.threshold == "theoretical"
        details = {"g": sig.wrap(gvals, 0), "alarms": alarms, "first_alarm": first, "change_index": change,
                   "jump": jump, "first_alarm_label": [_label(i) for i in first],
                   "change_label": [_label(i) for i in change], "window": window, "scale": s,
                   "threshold_method": ("theoretical" if theoretical else
                                        self.threshold.method_ if isinstance(self.threshold, EmpiricalThreshold)
                                        else "fixed"),
                   "alarm_rate": alarm.mean(axis=0)}
        stat = gvals.max(axis=0)
        return Decision(statistic=stat, threshold=np.full(k, gamma), pvalue=np.full(k, np.nan),
                        alpha=self.false_alarm, reject=bool(alarm.any()),
                        df=np.full(k, 1.0 if theoretical else np.nan), nobs=sig.nobs,
                        null_hypothesis=self.null_hypothesis, alternative_hypothesis=self.alternative_hypothesis,
                        details=details, channel_reject=alarm.any(axis=0), channels=tuple(sig.channels),
                        test="GLRT")

    # ------------------------------------------------------------------ streaming
    def stream(self, nchan: int = 1, scale: Any = None) -> GLRTStream:
        """A stateful sample-by-sample GLRT with this test's window, scale and threshold.

        ``scale`` (standard deviation per channel) overrides the test's ``scale`` / ``scale_``; one of them is
        needed.
        """
        nchan = int_like(nchan, "nchan", minimum=1)
        s = self._scale_for(nchan, None, scale) if (scale is not None or self.scale is not None
                                                    or hasattr(self, "scale_")) else None
        if s is None:
            raise ValueError("scale is needed for a stream: pass scale, set it on the GLRT, or calibrate() first")
        return GLRTStream(self.window, s, self.threshold_)


class GLRTStream:
    """Incremental GLRT: feed residual samples one at a time (:meth:`update`) or in blocks (:meth:`extend`).

    The values equal :meth:`GLRT.statistic` on the concatenated samples. Each update costs O(window). The
    returned statistics always carry a channel axis, whatever the number of channels: :meth:`update` returns
    shape ``(nchan,)``, :meth:`extend` shape ``(n, nchan)``.

    Parameters
    ----------
    window : int
        :math:`M`, as for :class:`GLRT`.
    scale : array_like, shape (nchan,)
        Standard deviation of the healthy residual per channel.
    threshold : float
        :math:`\\gamma`; a sample alarms when g exceeds it in any channel.

    Attributes
    ----------
    k : int
        Number of samples seen.
    g : ndarray, shape (nchan,)
        Last statistic per channel.
    alarm : bool
        Whether the last sample alarmed (any channel).
    first_alarm : int or None
        Sample number (0-based) of the first alarm.
    change_index, jump : ndarray, shape (nchan,)
        ML change instant (sample number) and jump of the last sample, per channel.
    """

    def __init__(self, window: int, scale: Any, threshold: float) -> None:
        self.window = int_like(window, "window", minimum=1)
        self.scale = GLRT._check_scale(scale)
        if self.scale is None:
            raise TypeError("scale is needed for a stream: the standard deviation of the healthy residual per channel")
        self.nchan = self.scale.shape[0]
        self.threshold = float_like(threshold, "threshold")
        self._exp = np.frexp(self.scale)[1]               # samples are kept divided by 2**_exp (exact), see _unit
        self._coef = 0.5 / np.ldexp(self.scale, -self._exp) ** 2
        self.reset()

    def __repr__(self) -> str:
        return (f"GLRTStream(window={self.window}, scale={self.scale}, threshold={self.threshold:.5g}, "
                f"k={self.k})")

    def reset(self) -> None:
        """Forget all samples."""
        # the ring buffer grows with the samples seen up to ``window``: memory is bounded by the data, not the option
        self._buf = np.zeros((self.nchan, min(self.window, 64)))
        self._head = np.full(self.nchan, self._buf.shape[1] - 1, dtype=np.int64)
        self._count = np.zeros(self.nchan, dtype=np.int64)
        self.k = 0
        self.g = np.zeros(self.nchan)
        self.alarm = False
        self.first_alarm: int | None = None
        self.change_index = np.full(self.nchan, -1, dtype=np.int64)
        self.jump = np.full(self.nchan, np.nan)

    def _history(self, c: int) -> np.ndarray:
        """The samples of channel ``c`` in the buffer, oldest first (rescaled)."""
        cnt = int(self._count[c])
        return np.roll(self._buf[c], -(int(self._head[c]) + 1))[self._buf.shape[1] - cnt:] if cnt else np.zeros(0)

    def _keep(self, rows: list, spare: int = 0) -> None:
        """Refill the buffer with the last ``window`` samples of every channel's ``rows`` (oldest first), growing it
        (doubling, up to ``window``) when they and ``spare`` more samples do not fit."""
        cnt = min(self.window, len(rows[0]))
        cap = self._buf.shape[1]
        if cnt + spare > cap:
            cap = min(self.window, max(cnt + spare, 2 * cap))
        buf = np.zeros((self.nchan, cap))
        for c, r in enumerate(rows):
            buf[c, :cnt] = r[len(r) - cnt:]
        self._buf = buf
        self._head[:] = (cnt - 1) % cap
        self._count[:] = cnt

    def _unit_sample(self, v: np.ndarray, name: str) -> np.ndarray:
        return _unit(v.reshape(-1, self.nchan), self.scale, name, always=True)[0]

    def update(self, x: Any) -> np.ndarray:
        """Add one sample (a float, or one value per channel).

        Returns
        -------
        ndarray, shape (nchan,)
            g of the sample per channel (shape ``(1,)`` for one channel).
        """
        v = sample_vector(x, self.nchan)
        if not np.all(np.isfinite(v)):
            raise ValueError(f"x contains NaN/inf at sample {self.k}")
        vu = self._unit_sample(v, "x")[0]
        if self._count[0] == self._buf.shape[1] < self.window:     # full but shorter than the window: grow
            self._keep([self._history(c) for c in range(self.nchan)], spare=1)
        g = np.empty(self.nchan)
        for c in range(self.nchan):
            gc, nb, jc, h, cnt = _ring_update(self._buf[c], self._head[c], self._count[c], vu[c], self._coef[c])
            self._head[c], self._count[c] = h, cnt
            g[c] = gc
            self.change_index[c] = self.k - nb + 1
            self.jump[c] = np.ldexp(jc, self._exp[c])
        self._finish(g)
        return g.copy()

    def _finish(self, g: np.ndarray) -> None:
        self.alarm = bool(np.any(g > self.threshold))
        if self.alarm and self.first_alarm is None:
            self.first_alarm = self.k
        self.k += 1
        self.g = g.copy()

    def extend(self, xs: Any) -> np.ndarray:
        """Add a block of samples, shape ``(n,)`` (one channel) or ``(n, nchan)``.

        Returns
        -------
        ndarray, shape (n, nchan)
            g of every sample of the block per channel (also for ``(n,)`` input).
        """
        try:
            arr = np.asarray(xs, dtype=np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"xs must be an array of numbers, got {type(xs).__name__}") from None
        arr2 = arr[:, None] if arr.ndim == 1 else arr
        if arr2.ndim != 2 or arr2.shape[1] != self.nchan:
            raise ValueError(f"xs must have shape (n,) or (n, {self.nchan}), got {arr.shape}")
        if not np.all(np.isfinite(arr2)):
            raise ValueError("xs contains NaN/inf")
        n = arr2.shape[0]
        if n == 0:
            return np.empty((0, self.nchan))
        xu = self._unit_sample(arr2, "xs")
        out = np.empty((n, self.nchan))
        rows = []
        for c in range(self.nchan):
            cnt = int(self._count[c])
            full = np.concatenate([self._history(c), xu[:, c]])
            g, best, jc = _scan(full, cnt, min(self.window, full.size), self._coef[c])
            out[:, c] = g
            rows.append(full[-min(self.window, full.size):])
            self.change_index[c] = self.k + n - 1 - best[-1] + 1
            self.jump[c] = np.ldexp(jc[-1], self._exp[c])
        self._keep(rows)
        alarm_rows = np.flatnonzero(np.any(out > self.threshold, axis=1))
        if alarm_rows.size and self.first_alarm is None:
            self.first_alarm = self.k + int(alarm_rows[0])
        self.k += n - 1
        self._finish(out[-1])
        return out


# ---------------------------------------------------------------------------------------------- parameter changes
#: relative pivot below which a regressor direction counts as not excited in a window (see ParameterGLRT, Notes)
_PIVOT_TOL = 1e-9


@numba.njit(cache=True, nogil=True)
def _quadratic(A, b, L, z, tol):  # pragma: no cover - compiled
    """``b' A^+ b`` over the excited directions of the symmetric ``A`` (lower triangle used): a Cholesky
    factorisation that skips every column whose pivot is below ``tol`` times its diagonal (collinear with the
    earlier columns, or zero)."""
    d = A.shape[0]
    q = 0.0
    for p in range(d):
        s = A[p, p]
        for r in range(p):
            s -= L[p, r] * L[p, r]
        if A[p, p] <= 0.0 or s <= tol * A[p, p]:
            for r in range(p, d):
                L[r, p] = 0.0
            z[p] = 0.0
            continue
        piv = np.sqrt(s)
        L[p, p] = piv
        for r in range(p + 1, d):
            t = A[r, p]
            for c in range(p):
                t -= L[r, c] * L[p, c]
            L[r, p] = t / piv
        t = b[p]
        for c in range(p):
            t -= L[p, c] * z[c]
        z[p] = t / piv
        q += z[p] * z[p]
    return q


@numba.njit(cache=True, nogil=True)
def _param_scan(y, phi, ref, window, coef, tol):  # pragma: no cover - compiled
    """g(k) and the best post-change length n for every k: the max over n = 1..window of
    ``coef * b' A^+ b`` with ``A = sum phi_i phi_i'``, ``b = sum phi_i (y_i - phi_i' ref[j])`` over i = j..k,
    j = k - n + 1, both accumulated backwards from k (O(window d^3) per sample)."""
    n_all, d = phi.shape
    g = np.empty(n_all)
    best = np.empty(n_all, dtype=np.int64)
    A = np.zeros((d, d))
    c = np.zeros(d)
    b = np.zeros(d)
    L = np.zeros((d, d))
    z = np.zeros(d)
    for k in range(n_all):
        A[:, :] = 0.0
        c[:] = 0.0
        m = window if window < k + 1 else k + 1
        gmax = -1.0
        nbest = 1
        for n in range(1, m + 1):
            i = k - n + 1
            for p in range(d):
                c[p] += phi[i, p] * y[i]
                for r in range(p + 1):
                    A[p, r] += phi[i, p] * phi[i, r]
            for p in range(d):
                t = c[p]
                for r in range(d):
                    t -= (A[p, r] if r <= p else A[r, p]) * ref[i, r]
                b[p] = t
            v = _quadratic(A, b, L, z, tol)
            if v > gmax:
                gmax = v
                nbest = n
        g[k] = gmax * coef
        best[k] = nbest
    return g, best


class ParameterGLRT(ResidualTest):
    r"""GLRT for a change in the parameters of a linear regression / ARX model (Hansen et al., section 3).

    Paper 002 monitors the parameters of its RLS-adapted residual generators (eqs. 14-16) with a GLRT beside the
    residual, and combines the two through their joint distribution. This is that test: under H0 the output
    follows the reference parameters, :math:`y_i = \varphi_i^\top\theta_{ref} + w_i`; under H1 the parameters
    jumped by an unknown :math:`\nu` at an unknown instant :math:`j` in the last ``window`` samples.

    Parameters
    ----------
    window : int
        :math:`M`: the change instant ranges over the last ``window`` samples.
    scale : float, optional
        Standard deviation :math:`\sigma` of the healthy residual :math:`w`. ``None``: estimated by
        :meth:`calibrate`, else from the tested record's residual.
    threshold : "theoretical", float or EmpiricalThreshold
        ``"theoretical"``: :math:`\gamma = \chi^2_{1-\alpha/M}(d)/2` (below); a float: a fixed :math:`\gamma`;
        an :class:`~tsfdi.EmpiricalThreshold`: calibrated on healthy records by :meth:`calibrate` (Hansen et
        al., Fig. 2; needed with an adapting reference, see Notes).
    alpha : float
        Per-sample false-alarm probability of the theoretical threshold.
    joint : bool, default False
        Test the joint residual-parameter alternative: a change of the residual mean *and* of the parameters
        (a constant regressor, reference 0, is put before the given ones). Its statistic is the residual's
        mean-change GLRT (:class:`GLRT`, eq. 3) plus the parameter-change statistic of the part of the
        regressors orthogonal to the constant (see Notes).

    Attributes
    ----------
    scale_ : float
        :math:`\sigma` estimated by :meth:`calibrate` (when ``scale`` is None).
    healthy_statistic_ : ndarray
        :math:`g` of the calibration records, pooled (after :meth:`calibrate`).

    Notes
    -----
    With the residual :math:`r_i = y_i - \varphi_i^\top\theta_{ref}` the log-likelihood ratio of a change
    :math:`\nu` at :math:`j`, maximised over :math:`\nu` (its ML value :math:`\hat\nu = A^{-1} b`, the least
    squares fit of the residuals on the regressors after :math:`j`), is (the form of eq. 2)

    .. math:: S_j^k = \frac{b^\top A^{-1} b}{2\sigma^2}, \quad A = \sum_{i=j}^{k}\varphi_i\varphi_i^\top, \quad
              b = \sum_{i=j}^{k}\varphi_i r_i, \qquad g(k) = \max_{k - M < j \le k} S_j^k \quad \text{(eq. 3)}.

    With one constant regressor it is the mean-change GLRT of :class:`GLRT`. Given the regressors and a known
    reference, :math:`2 S_j^k \sim \chi^2(d)` under H0 for a fixed :math:`j` (:math:`d` regressors, or the rank
    of :math:`A`), and the union bound over the :math:`M` change instants makes
    :math:`\gamma = \chi^2_{1-\alpha/M}(d)/2` a per-sample false-alarm rate of at most :math:`\alpha` (iid
    Gaussian :math:`w`). With ``joint=True``, :math:`d + 1` degrees of freedom; the statistic splits into the
    mean-change statistic of the residual (:math:`\chi^2(1)/2`) and the parameter-change statistic of the
    regressors made orthogonal to the constant on the window (:math:`\chi^2(d)/2`), independent under H0 for a
    fixed :math:`j`: the joint distribution of the two detectors of paper 002.

    *The RLS parameter change*: ``params`` may be the parameter history of :class:`tsfdi.RecursiveARX`
    (``results.params``, row :math:`t` the estimate after sample :math:`t`); the reference of a change at
    :math:`j` is then :math:`\hat\theta_{j-1}`, the estimate just before it. For RLS without forgetting,
    :math:`\hat\theta_k - \hat\theta_{j-1} = P_k b` exactly, so :math:`S_j^k` is the change of the recursive
    estimate over the window weighed by the information of the window's data. The reference's own estimation
    error inflates the statistic by about :math:`n / (j-1)` (relative) without forgetting and by about
    :math:`n (1 - \lambda)` with forgetting factor :math:`\lambda`, so with an adapting reference calibrate the
    threshold (``threshold=EmpiricalThreshold(...)``) on healthy records, as paper 002 does; a reference fixed
    from a long healthy fit keeps the chi-square law. Hold the adaptation on an alarm
    (:meth:`tsfdi.RecursiveARX.freeze`), else the estimate learns the fault and masks it (paper 002).

    A regressor direction that a window does not excite (a constant input, collinear regressors, the first
    samples of a window shorter than :math:`d`) is left out of that window's statistic (a Cholesky
    factorisation skipping pivots below ``1e-9`` of their diagonal): its law is then :math:`\chi^2` with fewer
    degrees of freedom and the theoretical threshold stays conservative. :math:`g` does not depend on the
    scale of ``y``, ``scale`` or any regressor column (all are rescaled by powers of two, exactly). Cost
    O(N M d^3), compiled.

    References
    ----------
    Hansen, Blanke, Adrian, *A Framework for Rapid Diagnosis of Critical Faults in UAVs*, section 3, eqs. 1-3,
    14-16, Fig. 9. Blanke and Hansen (2013), *Towards self-tuning residual generators for UAV control surface
    fault diagnosis*. Willsky and Jones (1976), *A generalized likelihood ratio approach to the detection and
    estimation of jumps in linear systems*, IEEE TAC 21(1).
    """

    name = "GLRT (parameter change)"
    null_hypothesis = "the model parameters equal the reference over the window (healthy)"
    alternative_hypothesis = "the model parameters jumped at some instant in the window (fault)"

    def __init__(self, window: int = 100, scale: float | None = None, threshold: Any = "theoretical", *,
                 alpha: float = 1e-3, joint: bool = False) -> None:
        self.window = int_like(window, "window", minimum=1)
        self.scale = float_like(scale, "scale", minimum=0.0, strict_min=True, optional=True)
        self.alpha = self._check_alpha(alpha)
        self.threshold = _threshold_option(threshold)
        if not isinstance(joint, (bool, np.bool_)):
            raise TypeError(f"joint must be True or False, got {joint!r}")
        self.joint = bool(joint)

    def __repr__(self) -> str:
        return (f"ParameterGLRT(window={self.window}, scale={self.scale}, threshold={self.threshold!r}, "
                f"alpha={self.alpha:g}, joint={self.joint})")

    def critical_value(self, df: int, nobs: int | None = None) -> float:
        """The threshold :math:`\\gamma` for ``df`` tested parameters (the regressors, plus one with ``joint``) on a
        record of ``nobs`` samples (the theoretical one: :math:`\\min(M, \\text{nobs})` change instants; ``None``:
        :math:`M`)."""
        df = int_like(df, "df", minimum=1)
        if isinstance(self.threshold, EmpiricalThreshold):
            self.threshold.check_fitted()
            return self.threshold.threshold_
        if self.threshold == "theoretical":
            m = self.window if nobs is None else min(self.window, int_like(nobs, "nobs", minimum=1))
            return _chi2_isf(math.log(self.alpha) - math.log(m), float(df)) / 2.0
        return float(self.threshold)

    # ------------------------------------------------------------------ inputs
    def _inputs(self, y: Any, regressors: Any, params: Any, name: str = "y") -> tuple:
        """Validated ``y`` (Signal), regressors (n, d), the reference of every change instant (n, d) and the
        regressor names (with the constant of ``joint`` first)."""
        sy = as_signal(y, name, vector=False, allow_constant=True)
        n = sy.nobs
        sx = as_signal(regressors, "regressors", allow_constant=True)
        if sx.nobs != n:
            raise ValueError(f"regressors must have one row per sample of {name} ({n}), got {sx.nobs}")
        phi, names = sx.values, list(sx.channels)
        d = phi.shape[1]
        if params is None:
            ref = np.zeros((n, d))
        else:
            sp = as_signal(params, "params", allow_constant=True)
            shape = sp.values.shape if sp.vector else (sp.nobs,)
            if shape == (n, d) and sp.vector:
                ref = np.concatenate([sp.values[:1], sp.values[:-1]])   # a change at j: from the estimate before j
            elif shape == (d,):
                ref = np.broadcast_to(sp.values[:, 0], (n, d))
            else:
                raise ValueError(f"params must be a reference vector ({d},) or a parameter history ({n}, {d}) "
                                 f"(one row per sample), got shape {shape}")
        if self.joint:
            phi = np.concatenate([np.ones((n, 1)), phi], axis=1)
            ref = np.concatenate([np.zeros((n, 1)), ref], axis=1)
            names = ["mean", *names]
        return sy, np.ascontiguousarray(phi), np.ascontiguousarray(ref), names

    @staticmethod
    def _residual(y: np.ndarray, phi: np.ndarray, ref: np.ndarray) -> np.ndarray:
        """:math:`r_i = y_i - \\varphi_i^\\top \\theta_{ref}` (the reference of a change at ``i``)."""
        with np.errstate(over="ignore", invalid="ignore"):
            r = y - np.einsum("ij,ij->i", phi, ref)
        if not np.all(np.isfinite(r)):
            first = int(np.flatnonzero(~np.isfinite(r))[0])
            raise ValueError(f"y - regressors @ params is beyond the float range (first at sample {first}): "
                             "rescale the regressors or params")
        return r

    def _scale_value(self, r: np.ndarray, scale: Any) -> float:
        if scale is not None:
            return float_like(scale, "scale", minimum=0.0, strict_min=True)
        if self.scale is not None:
            return self.scale
        if hasattr(self, "scale_"):
            return self.scale_
        s = float(_std(r[:, None])[0]) if r.shape[0] >= 2 else 0.0
        if not s > 0:
            raise ValueError("y: the residual is constant or has one sample, its scale cannot be estimated; pass "
                             "scale")
        return s

    def _g(self, y: np.ndarray, phi: np.ndarray, ref: np.ndarray, sigma: float) -> tuple[np.ndarray, np.ndarray]:
        """g and the best post-change length, on data rescaled by powers of two (exact, see Notes)."""
        r = self._residual(y, phi, ref)
        _unit(r[:, None], np.array([sigma]), "y")          # refuses a residual beyond 2**400 scales
        es = int(np.frexp(sigma)[1])
        ec = np.frexp(max_abs(phi))[1] if phi.size else np.zeros(0, dtype=np.int64)
        phi_u = np.ldexp(phi, -ec)
        ref_u = np.ldexp(ref, ec - es)
        y_u = np.ldexp(y, -es)
        coef = 0.5 / np.ldexp(sigma, -es) ** 2
        window = min(self.window, y.shape[0])
        return _param_scan(y_u, phi_u, ref_u, window, coef, _PIVOT_TOL)

    # ------------------------------------------------------------------ public
    def statistic(self, y: Any, regressors: Any, params: Any = None, scale: Any = None) -> Any:
        """The statistic series :math:`g(k)` in the kind of ``y`` (same index).

        Parameters
        ----------
        y : array_like, Series or DataArray, shape (nobs,)
            The model's output; with ``params=None`` the residual of the reference model itself.
        regressors : array_like, DataFrame or DataArray, shape (nobs, d)
            The regressor :math:`\\varphi_i` of every sample (for an ARX model: the lagged outputs and inputs in
            the order of the parameters; start-up rows without a complete regressor left out).
        params : array_like, shape (d,) or (nobs, d), optional
            The reference: a fixed parameter vector, or a parameter history (``RecursiveARX(...).run(...).params``;
            a change at sample ``j`` is measured from row ``j - 1``). ``None``: zero (``y`` is a residual).
        scale : float, optional
            :math:`\\sigma` (overrides the test's ``scale`` / ``scale_``).
        """
        sy, phi, ref, _ = self._inputs(y, regressors, params)
        y0 = sy.values[:, 0]
        g, _ = self._g(y0, phi, ref, self._scale_value(self._residual(y0, phi, ref), scale))
        return sy.wrap(g[:, None], 0)

    def calibrate(self, y: Any, regressors: Any, params: Any = None) -> ParameterGLRT:
        """``scale_`` (if ``scale`` is None: the standard deviation of the healthy residual) and the empirical
        threshold from healthy records; returns ``self``.

        ``y``, ``regressors`` and ``params`` are one record each, or lists of records of equal length (``params``
        may be one vector for all). The statistic is computed record by record and pooled.
        """
        many = _is_record_list(y)
        ys = list(y) if many else [y]
        xs = list(regressors) if many else [regressors]
        if len(xs) != len(ys):
            raise ValueError(f"regressors must hold one record per record of y ({len(ys)}), got {len(xs)}")
        ps = list(params) if many and _is_record_list(params) else [params] * len(ys)
        if len(ps) != len(ys):
            raise ValueError(f"params must hold one record per record of y ({len(ys)}), got {len(ps)}")
        parts = [self._inputs(yi, xi, pi, f"y[{i}]" if many else "y") for i, (yi, xi, pi) in enumerate(zip(ys, xs, ps))]
        resid = [self._residual(sy.values[:, 0], phi, ref) for sy, phi, ref, _ in parts]
        if self.scale is None:
            pooled = np.concatenate(resid)
            if pooled.shape[0] < 2 or not _std(pooled[:, None])[0] > 0:
                raise ValueError("y: the healthy residual is constant or has one sample, its scale cannot be "
                                 "estimated")
            self.scale_ = float(_std(pooled[:, None])[0])
        sigma = self.scale if self.scale is not None else self.scale_
        g = np.concatenate([self._g(sy.values[:, 0], phi, ref, sigma)[0] for sy, phi, ref, _ in parts])
        if isinstance(self.threshold, EmpiricalThreshold):
            self.threshold = copy.copy(self.threshold).calibrate(g)
        self.healthy_statistic_ = g
        return self

    def test(self, y: Any, regressors: Any, params: Any = None, scale: Any = None) -> Decision:
        """Run the test over a record (arguments as in :meth:`statistic`).

        Returns
        -------
        Decision
            ``statistic``: the largest :math:`g(k)`; ``threshold``: :math:`\\gamma`; ``df``: the number of tested
            parameters (:math:`d`, or :math:`d + 1` with ``joint``); ``pvalue`` nan (a maximum over the record);
            ``reject`` when any sample alarms; ``alpha`` the per-sample false-alarm probability. ``details``:
            ``"g"`` (the series, kind of ``y``), ``"alarms"`` (positions), ``"first_alarm"`` (position, -1 if
            none), ``"first_alarm_label"``, ``"change_index"`` (ML change instant at the first alarm, -1 if none),
            ``"change"`` (ML parameter change :math:`\\hat\\nu` at the first alarm, a ``pandas.Series`` named by
            the regressors, with ``"mean"`` first for ``joint``; NaN without alarm), ``"scale"``, ``"window"``,
            ``"threshold_method"``, ``"alarm_rate"``.
        """
        sy, phi, ref, names = self._inputs(y, regressors, params)
        y0 = sy.values[:, 0]
        r = self._residual(y0, phi, ref)
        sigma = self._scale_value(r, scale)
        g, best = self._g(y0, phi, ref, sigma)
        d = phi.shape[1]
        gamma = self.critical_value(d, y0.shape[0])
        alarms = np.flatnonzero(g > gamma)
        change = pd.Series(np.nan, index=pd.Index(names, name="parameter"), name="change")
        first = change_at = -1
        if alarms.size:
            first = int(alarms[0])
            change_at = first - int(best[first]) + 1
            seg = slice(change_at, first + 1)
            rs = y0[seg] - phi[seg] @ ref[change_at]
            change[:] = np.linalg.lstsq(phi[seg], rs, rcond=None)[0]
        method = ("theoretical" if isinstance(self.threshold, str) else
                  self.threshold.method_ if isinstance(self.threshold, EmpiricalThreshold) else "fixed")
        label = None if first < 0 else (sy.index[first] if sy.index is not None else first)
        details = {"g": sy.wrap(g[:, None], 0), "alarms": alarms, "first_alarm": first, "first_alarm_label": label,
                   "change_index": change_at, "change": change, "scale": sigma,
                   "window": min(self.window, y0.shape[0]),
                   "threshold_method": method, "alarm_rate": float(alarms.size / max(g.size, 1))}
        return Decision(statistic=np.array([g.max()]), threshold=np.array([gamma]), pvalue=np.array([np.nan]),
                        alpha=self.false_alarm, reject=bool(alarms.size), df=np.array([float(d)]), nobs=sy.nobs,
                        null_hypothesis=self.null_hypothesis, alternative_hypothesis=self.alternative_hypothesis,
                        details=details, channel_reject=np.array([bool(alarms.size)]),
                        channels=tuple(sy.channels), test="ParameterGLRT")

    @property
    def false_alarm(self) -> float:
        """Per-sample false-alarm probability targeted by the threshold."""
        if isinstance(self.threshold, EmpiricalThreshold):
            return self.threshold.false_alarm
        return self.alpha

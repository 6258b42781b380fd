"""Online detection on signal streams (Keipour et al., paper 001; Hansen et al., paper 002).

:class:`OnlineDetector` runs several (output, input) signal pairs at once, each through a recursive ARX model
with the stability gate, Welford running variance and Z-score alarms of paper 001 and a streaming GLRT on the
same prediction errors (paper 002), and reports the first alarm of every pair and of the whole system with time
stamps; ``statistic="sprt"`` runs Wald's restarted SPRT (:class:`tsfdi.SPRT`) on them instead, ``statistic="zmean"``
the standardised moving-window sum (paper 002's GLRT with a fixed window).
:meth:`OnlineDetector.calibrate` sets the thresholds from healthy runs for a required number of false alarms per
flight hour (paper 002's rule: the threshold from the statistic's distribution in normal operation; for the SPRT
from the restart cycles of a few short healthy logs, averaged over the spread between logs and its uncertainty).
"""

from __future__ import annotations

import copy
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy import optimize, special, stats
from scipy.signal import lfilter

from tsfdi._data import as_signal, check_paired, refuse_masked, sampling_frequency
from tsfdi._validation import boolean, float_like, int_like, option
from tsfdi.detection.glrt import GLRT
from tsfdi.detection.sequential import SPRT, renewal_walk
from tsfdi.exceptions import ConvergenceWarning, TsfdiWarning
from tsfdi.models.lstsq import check_size
from tsfdi.models.recursive import RecursiveARX

__all__ = ["OnlineDetector", "OnlineDetection", "OnlineCalibration"]

_SECONDS_PER_HOUR = 3600.0
_HUGE = 1e300            # a threshold no statistic reaches (calibration runs never alarm, so never freeze)
_MIN_EMPIRICAL = 5.0     # expected episodes at the target rate needed for the empirical estimate
_MIN_EXTRAPOLATED = 1.0  # ... and for the exponential tail fit
_MIN_SPRT_RECORDS = 3    # armed (run, pair) records the SPRT calibration needs (the spread between logs is estimated)
_SPRT_BLOCK = 32         # samples per batch of the long-run variance in the SPRT scale of one record
_MIN_EXPONENT_SAMPLES = 10 * _SPRT_BLOCK   # armed samples a record needs for its own Wald exponent
_DRIFT_SE = 2.0          # standard errors of its mean by which a record's SPRT log-likelihood ratio must grow to refuse
_SPRT_BAND = (0.05, 0.5, 0.95)  # quantiles of a new log's false-alarm rate reported as ``rate_band``
_SPRT_NODES = 400        # quantile nodes of the predictive law of a new log's Wald exponent
_MIN_SPRT_CYCLES = 50    # restart cycles of the SPRT walk the calibration needs
_TAIL_EPISODES = 20      # episodes above the base level of the tail fit
_MIN_TAIL_EPISODES = 10  # fewest episodes above the base level the tail fit accepts
#: the statistics on the errors standardised by the scale fixed at arming (the SPRT's arming, settle, running scale)
_ARMED_SCALE = ("sprt", "zmean")
_STEADY_RATIO = 4.0      # statistic="sprt": largest ratio of the error variances of the two halves of the errors
                         # that set the scale at arming (a steady regime)
#: the RecursiveARX options OnlineDetector passes on (it sets the others: gate, threshold, freeze_on_alarm, ...)
_RLS_OPTIONS = ("P0", "trend", "theta0", "stable_samples", "variance_tol", "min_variance_samples")
#: the RecursiveARX options that may differ between pairs (a mapping from pair names)
_PER_PAIR_OPTIONS = ("theta0", "P0")


@dataclass(frozen=True, eq=False)
class OnlineDetection:
    """Outcome of :meth:`OnlineDetector.run` over one block of samples.

    Attributes
    ----------
    pairs : tuple of str
        Pair names.
    zscore, glrt, resid : ndarray, DataFrame or DataArray, shape (nobs, n_pairs)
        Z-scores, GLRT statistics ``g(k)`` (NaN until the pair is armed) and prediction errors, in the kind of
        ``y`` (index kept).
    alarm : ndarray of bool, shape (nobs, n_pairs)
        Per-sample alarm of each pair (detection statistic or GLRT).
    first_alarms : pandas.DataFrame
        One row per pair: ``position`` (sample number since the detector started, -1 if none), ``time``
        (index label, None if none), ``source`` ("zscore", "mean", "sprt", "zmean", "glrt", or two joined by "+"),
        ``armed_at`` (position where the GLRT was armed / the variance became stable, -1 if not yet).
    first_alarm : int or None
        Earliest alarm position over all pairs (since the detector started).
    first_alarm_time : object or None
        Its index label (position for numpy input).
    first_alarm_pair : str or None
        The pair that raised it first (ties: the first pair in order).
    statistic : ndarray, DataFrame or DataArray, shape (nobs, n_pairs)
        The detection statistic compared with ``threshold``: the Z-score (``statistic="zscore"``; the alarm is
        on its absolute value), the direction-signed moving average of the prediction errors
        (``statistic="mean"``), the SPRT walk :math:`S_k` before its restart (``statistic="sprt"``) or the
        direction-signed standardised window sum :math:`T_k` (``statistic="zmean"``), NaN where undefined.
    alarm_start : ndarray of bool, shape (nobs, n_pairs)
        First sample of every alarm *episode* (a maximal stretch of consecutive alarmed samples of a pair, one
        alarm to the operator); an episode continuing from the previous block of the stream is not restarted.
    fs : float or None
        Sampling frequency in Hz read from the time index of ``y`` (None for numpy input or an index without
        time), used by :meth:`false_alarms_per_hour`.
    """

    pairs: tuple
    zscore: Any
    glrt: Any
    resid: Any
    alarm: np.ndarray
    first_alarms: pd.DataFrame
    first_alarm: int | None
    first_alarm_time: Any
    first_alarm_pair: str | None
    statistic: Any = None
    alarm_start: np.ndarray | None = None
    fs: float | None = None

    def false_alarms_per_hour(self, fs: float | None = None) -> pd.DataFrame:
        """Alarm episodes per hour of this block, per pair and in all: the false-alarm rate of a healthy run.

        On a healthy run every alarm episode is a false alarm; consecutive alarmed samples are one episode
        (counted at its first sample, :attr:`alarm_start`). The duration is that of the block,
        ``nobs / fs`` -- the flight time, baseline and arming phases included, as in
        :meth:`OnlineDetector.calibrate`.

        Parameters
        ----------
        fs : float, optional
            Sampling frequency in Hz; by default :attr:`fs` (from the time index of ``y``).

        Returns
        -------
        pandas.DataFrame
            One row per pair and a row ``"all"`` (the sum over pairs, the rate
            :meth:`OnlineDetector.calibrate` targets), columns ``episodes`` (int), ``hours`` (duration of the
            block) and ``per_hour`` (``episodes / hours``).

        Raises
        ------
        ValueError
            If ``fs`` is not positive, or not given for data without a time index.
        """
        if fs is not None:
            fs = float_like(fs, "fs", minimum=0.0, strict_min=True)
        elif self.fs is not None:
            fs = self.fs
        else:
            raise ValueError("fs (sampling frequency in Hz) is needed: the data of this run carry no time index")
        starts = self.alarm_start if self.alarm_start is not None else _episode_starts(self.alarm, None)
        hours = self.alarm.shape[0] / fs / _SECONDS_PER_HOUR
        episodes = np.append(starts.sum(axis=0), starts.sum()).astype(np.int64)
        return pd.DataFrame({"episodes": episodes, "hours": hours, "per_hour": episodes / hours},
                            index=pd.Index([*self.pairs, "all"], name="pair"))


@dataclass(frozen=True, eq=False)
class OnlineCalibration:
    """Record of :meth:`OnlineDetector.calibrate`.

    Attributes
    ----------
    false_alarms_per_hour : float
        The required rate of alarm episodes per flight hour (all pairs together).
    healthy_hours : float
        Total duration of the healthy runs, :math:`H`.
    runs : int
        Number of healthy runs.
    threshold : float
        The calibrated threshold of the detection statistic.
    glrt_threshold : float or None
        The calibrated GLRT threshold (None without GLRT).
    estimator : str
        ``"empirical"`` (counted episodes; with a GLRT, those of the combined alarm), ``"exponential tail"``
        (extrapolated from the episode peaks, each source on its own) or ``"sprt cycle maxima"``
        (``statistic="sprt"``, see :meth:`OnlineDetector.calibrate`).
    source_rates : dict
        Rate per hour at which each source ("zscore" / "mean", "glrt") is set on its own (one common rate).
    expected_episodes : float
        :math:`K = \\rho H`, the episodes the target rate means on the healthy runs.
    healthy_episodes : int
        Alarm episodes the calibrated detector would raise on the healthy runs (without freezing; for
        ``statistic="sprt"`` the restart cycles reaching the threshold).
    tail : dict
        Per source fitted with the exponential tail: base level ``u``, episodes above it ``n_u`` and mean
        excess ``beta`` (``statistic="sprt"``: of the restart cycles' maxima of all records, and
        ``log_exponent_sd``, the spread over records of the log of each record's Wald exponent, a censored
        maximum-likelihood estimate when records' log-likelihood ratios grow on average, see
        :meth:`OnlineDetector.calibrate`).
    rate_band : tuple of float or None
        ``statistic="sprt"``: false alarms per flight hour of a new healthy log at the calibrated threshold, 5 %,
        50 % and 95 % quantiles of its predictive law (between-log spread and its estimation from few logs; the
        stated rate is its mean). None for the other statistics.
    sprt_scale : float or None
        ``statistic="sprt"``: Wald's exponent of the pooled healthy walk, set as the SPRT's ``scale_``.
    """

    false_alarms_per_hour: float
    healthy_hours: float
    runs: int
    threshold: float
    glrt_threshold: float | None
    estimator: str
    source_rates: dict
    expected_episodes: float
    healthy_episodes: int
    tail: dict
    rate_band: tuple | None = None
    sprt_scale: float | None = None


def _episode_starts(alarm: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    """First samples of the runs of True in every column of ``alarm`` (``previous``: the row before)."""
    before = np.zeros((1, alarm.shape[1]), dtype=bool) if previous is None else previous.reshape(1, -1)
    return alarm & ~np.concatenate([before, alarm[:-1]], axis=0)


class _TooShort(Exception):
    """The healthy runs cannot support a rate (raised by :class:`_Upcrossings`, reworded by the caller)."""


class _Upcrossings:
    """Alarm episodes of a statistic against a threshold, over healthy series joined by NaN separators.

    A sample ``k`` starts an episode at level ``t`` when ``x(k) > t`` and not ``x(k-1) > t`` (NaN: not live), so
    the count is ``N(t) = #{k: lo(k) <= t < x(k)}`` with ``lo(k) = x(k-1)`` (``-inf`` after a NaN): evaluated at
    every observed level by two sorted arrays.
    """

    def __init__(self, x: np.ndarray, hours: float) -> None:
        self.x = x
        self.hours = hours
        prev = np.concatenate([[np.nan], x[:-1]])
        live = np.isfinite(x)
        hi = x[live]
        lo = np.where(np.isfinite(prev), prev, -np.inf)[live]
        a = np.sort(hi)
        b = np.sort(np.minimum(lo, hi))
        self.levels = np.unique(a)
        self.counts = np.searchsorted(b, self.levels, "right") - np.searchsorted(a, self.levels, "right")
        # monotone envelope from above: Ñ(t) = max over t' >= t of N(t')
        self.envelope = np.maximum.accumulate(self.counts[::-1])[::-1] if self.levels.size else self.counts

    def empirical(self, k: float) -> float:
        """Level with ``k >= 1`` episodes: between the ceil(k)-th and floor(k)-th highest episode peaks."""
        env, lev = self.envelope, self.levels
        if lev.size == 0 or env[0] < np.ceil(k):
            raise _TooShort("rate")
        # drop(m): the level where the envelope falls below m, i.e. the m-th highest episode peak
        m0, m1 = int(np.ceil(k)), int(np.floor(k))
        d0, d1 = (float(lev[np.searchsorted(-env, -(m - 1), "left")]) for m in (m0, m1))
        frac = (np.log(m0) - np.log(k)) / (np.log(m0) - np.log(m1)) if m0 > m1 else 0.0
        return float(d0 + frac * (d1 - d0))

    def level(self, rate: float) -> tuple[float, str, dict]:
        """Threshold with ``rate`` episodes per hour: (threshold, estimator, tail fit)."""
        k = rate * self.hours
        env, lev = self.envelope, self.levels
        if lev.size == 0 or env[0] < np.ceil(k):
            raise _TooShort("rate")
        if k >= _MIN_EMPIRICAL:
            return self.empirical(k), "empirical", {}
        if k < _MIN_EXTRAPOLATED:
            raise _TooShort("hours")
        j = int(np.argmax(env <= _TAIL_EPISODES)) if env[0] > _TAIL_EPISODES else 0
        u = float(lev[j])
        above = np.nan_to_num(self.x, nan=-np.inf) > u
        start = np.flatnonzero(above & ~np.concatenate([[False], above[:-1]]))
        stop = np.flatnonzero(above & ~np.concatenate([above[1:], [False]])) + 1
        if start.size < _MIN_TAIL_EPISODES:
            raise _TooShort("episodes")
        peaks = np.array([self.x[i:e].max() for i, e in zip(start, stop)])
        beta = float(np.mean(peaks - u))
        n_u = int(start.size)
        # mean-unbiased under the model: E[episodes above u + c beta_hat] = (n_u + 1) (1 + c / n_u)^-n_u = k
        c = n_u * ((n_u + 1.0) / k) ** (1.0 / n_u) - n_u
        return u + beta * c, "exponential tail", {"u": u, "n_u": n_u, "beta": beta}


def _moving_average(x: np.ndarray, window: int) -> np.ndarray:
    """Mean of ``x[t-window+1..t]`` for t >= window-1 (NaN where the window holds a NaN or is incomplete)."""
    n = x.shape[0]
    out = np.full(n, np.nan)
    if n < window:
        return out
    bad = ~np.isfinite(x)
    c = np.concatenate([[0.0], np.cumsum(np.where(bad, 0.0, x))])
    cb = np.concatenate([[0], np.cumsum(bad)])
    s = c[window:] - c[:-window]
    nb = cb[window:] - cb[:-window]
    out[window - 1:] = np.where(nb == 0, s / window, np.nan)
    return out


def _cycle_maxima(z: np.ndarray, lower: float) -> np.ndarray:
    """Maxima of the complete cycles of the walk of ``z`` restarted at ``lower`` (no upper bound)."""
    path = renewal_walk(z, lower, _HUGE)[0]
    ends = np.flatnonzero(path <= lower)
    if not ends.size:
        return np.empty(0)
    return np.maximum.reduceat(path[: ends[-1] + 1], np.concatenate([[0], ends[:-1] + 1]))


def _wald_exponent(z: np.ndarray, where: str) -> float:
    r"""Wald's exponent :math:`h > 0` of a walk of increments ``z`` drifting down: the root of
    :math:`\hat K(h) + \tfrac{h^2}{2}(\hat v_{lr} - \hat v) = 0` (empirical cumulant generating function of one
    increment, plus the excess of the long-run variance over batches of ``_SPRT_BLOCK`` samples: the
    autocorrelation to second order); :math:`E[e^{h S_n}] \approx 1`."""
    if z.size < _MIN_EXPONENT_SAMPLES:
        raise ValueError(f"{where}: {z.size} armed samples, at least {_MIN_EXPONENT_SAMPLES} are needed to estimate "
                         "the SPRT's scale on it: give longer healthy runs")
    m = float(z.mean())
    if not m < 0:
        raise ValueError(f"{where}: the SPRT's log-likelihood ratio grows on average ({m:.4g} per sample) on a "
                         "healthy run: the prediction errors are not the healthy law it assumes")
    extra = 0.5 * (_long_run_variance(z) - float(z.var()))
    log_n = np.log(z.size)

    def f(h: float) -> float:
        return float(special.logsumexp(h * z) - log_n + h * h * extra)

    # the smallest positive root: f(0) = 0 and f'(0) = mean < 0, so f starts negative; it is scanned upwards in steps
    # of 9 % from h = 2**-10, because with negatively autocorrelated increments (``extra`` < 0) f can be positive on
    # a short interval only (e.g. 1.30 to 1.76), which a search doubling h steps over
    lo = 0.0
    for hi in _EXPONENT_GRID:
        if f(hi) > 0:
            if lo == 0.0:                       # positive at the grid's first point already: halve below it
                lo = hi / 2.0
                while f(lo) >= 0:
                    lo /= 2.0
                    if lo < 1e-12:
                        raise ValueError(f"{where}: no positive root of the SPRT walk's cumulant equation")
            return float(optimize.brentq(f, lo, hi, rtol=1e-10))
        lo = hi
    ratio = 2.0 * extra / float(z.var()) + 1.0
    raise ValueError(f"{where}: the SPRT's log-likelihood ratio never rises on the healthy runs (no positive root of "
                     f"its walk's cumulant equation up to h = {_EXPONENT_GRID[-1]:.0e}; the long-run variance of its "
                     f"increments is {ratio:.2f} times their variance): give longer healthy runs, or prediction errors "
                     "closer to white")


#: where :func:`_wald_exponent` looks for the first sign change: 2**-10 to 2**20 in steps of 2**(1/8)
_EXPONENT_GRID = 2.0 ** (np.arange(-80, 161) / 8.0)


def _long_run_variance(z: np.ndarray) -> float:
    """Long-run variance per sample of ``z``: the variance of its sums over batches of ``_SPRT_BLOCK`` samples (about
    its mean) per sample (at least two batches)."""
    n = z.size // _SPRT_BLOCK
    sums = z[: n * _SPRT_BLOCK].reshape(n, _SPRT_BLOCK).sum(axis=1)
    return float(((sums - float(z.mean()) * _SPRT_BLOCK) ** 2).sum() / (n - 1) / _SPRT_BLOCK)


def _mean_se(z: np.ndarray) -> tuple:
    """Mean of ``z`` and its standard error from the long-run variance (:func:`_long_run_variance`)."""
    return float(z.mean()), float(np.sqrt(_long_run_variance(z) / z.size))


def _censored_sd(x: np.ndarray, c: np.ndarray) -> float:
    """Standard deviation of a normal law from values ``x`` and values known only to lie below ``c`` (left-censored):
    the maximum-likelihood estimate times :math:`\\sqrt{J/(J-1)}`, ``J`` all values (the sample standard deviation
    of ``x`` when nothing is censored)."""
    if not c.size:
        return float(x.std(ddof=1))

    def nll(p: np.ndarray) -> float:
        return -float(stats.norm.logpdf(x, p[0], np.exp(p[1])).sum() + stats.norm.logcdf(c, p[0], np.exp(p[1])).sum())

    fit = optimize.minimize(nll, [x.mean(), np.log(x.std(ddof=1))], method="Nelder-Mead",
                            options={"xatol": 1e-8, "fatol": 1e-10, "maxiter": 4000})
    j = x.size + c.size
    return float(np.exp(fit.x[1]) * np.sqrt(j / (j - 1.0)))


def _running_standardise(e: np.ndarray, m: float, v: float, pending: np.ndarray, lam: float,
                         lag: int) -> tuple:
    r"""Errors ``e`` standardised by the running mean and variance lagged by ``lag`` finite errors.

    ``(m, v)`` are the estimates after the errors entered so far, ``pending`` the last errors seen but not yet
    entered (at most ``lag``). The finite error :math:`e_k` is standardised by the estimates after
    :math:`e_{k-\text{lag}-1}` (the arming values before), and then enters as
    :math:`m_k = \lambda m_{k-1} + (1-\lambda) e_k`,
    :math:`v_k = \lambda v_{k-1} + \lambda(1-\lambda)(e_k - m_{k-1})^2`. NaN errors stay NaN and do not enter.
    Returns ``(w, m, v, pending)``."""
    ok = np.isfinite(e)
    x = e[ok]
    seq = np.concatenate([pending, x])
    n_in = max(seq.size - lag, 0)
    entries = seq[:n_in]
    M, V = np.array([m]), np.array([v])
    if n_in:
        ms = lfilter([1.0 - lam], [1.0, -lam], entries, zi=[lam * m])[0]
        d = entries - np.concatenate([M, ms[:-1]])
        vs = lfilter([lam * (1.0 - lam)], [1.0, -lam], d * d, zi=[lam * v])[0]
        M, V = np.concatenate([M, ms]), np.concatenate([V, vs])
    c = np.maximum(pending.size + np.arange(x.size) - lag, 0)   # errors entered before each of x
    w = np.full(e.shape, np.nan)
    w[ok] = (x - M[c]) / np.sqrt(V[c])
    return w, float(M[-1]), float(V[-1]), seq[n_in:]


class OnlineDetector:
    r"""Online anomaly detection on several commanded / measured (input / output) signal pairs at once.

    Every pair gets its own :class:`tsfdi.RecursiveARX` (same orders and options for all pairs). Its a-priori
    prediction errors feed one of four detection statistics:

    - ``statistic="zscore"`` (paper 001): the model's own Z-score against the Welford mean and variance, armed
      once the model and the error variance are stable; ``threshold`` is in standard deviations (4.5);
    - ``statistic="mean"``: the moving average of the last ``window`` prediction errors, compared with
      ``threshold`` in the units of ``y`` (a finite-moving-average change detector). ``direction`` makes it
      one-sided: "down" alarms when the average falls below ``-threshold`` (e.g. a loss of thrust in the
      longitudinal specific force), "up" above ``+threshold``, "both" on the absolute value;
    - ``statistic="sprt"``: Wald's SPRT (:class:`tsfdi.SPRT`, the ``sprt`` test, restarted as a CUSUM) of the
      errors standardised by the Welford mean and standard deviation at arming (or, with ``scale_forgetting``, by
      a lagged running mean and standard deviation, see Notes): the walk
      :math:`S_k = S_{k-1} + z_k` (:math:`z_k` the test's per-sample log-likelihood ratio times its ``scale_``)
      restarts at 0 at its lower bound and after every alarm; an alarm where :math:`S_k \ge` ``threshold`` (by
      default the test's upper bound :math:`\ln((1-\beta)/\alpha)`). The default, for autopilot logs (see the
      guide): :meth:`calibrate` sets it from a few short healthy logs;
    - ``statistic="zmean"``: the standardised moving-window sum of the last ``window`` errors (a causal matched
      filter of a bias of known length, paper 002's GLRT with a fixed window, see Notes),

      .. math:: T_k = \frac{1}{\hat\sigma\sqrt{w}} \sum_{i=k-w+1}^{k} (e_i - \hat\mu),

      with :math:`w` = ``window`` and :math:`\hat\mu, \hat\sigma` the mean and scale fixed at arming exactly as
      for ``"sprt"`` (``settle`` and ``scale_forgetting`` apply the same way); standard normal in normal operation
      for white errors, so one ``threshold`` in standard deviations serves logs whose error spread differs.
      ``direction`` as for ``"mean"``: "up" alarms when :math:`T_k >` ``threshold``, "down" when
      :math:`T_k <` ``-threshold``, "both" on :math:`|T_k|`.

    Optionally a streaming :class:`tsfdi.detection.GLRT` runs on the same errors once the variance is stable
    and positive (its ``scale`` is the Welford standard deviation at arming, its input the error minus the
    Welford mean at arming). No alarm of any source is raised among the first ``arm_after`` samples (baseline phase).

    A pair is *armed* (its Z-score and GLRT can alarm) once its model is stable by the scale-free gate of the Notes
    (:class:`tsfdi.RecursiveARX` with ``gate="relative"``) and then its error variance is stable. :meth:`run` warns
    (:class:`~tsfdi.exceptions.ConvergenceWarning`, once per pair and stream) when it returns with a pair that has
    not armed, naming the pair and the time of the last sample: no alarm could be raised for it.

    :meth:`calibrate` sets ``threshold`` (and the GLRT's) from healthy runs for a required number of false
    alarms per flight hour; :meth:`OnlineDetection.false_alarms_per_hour` reports the rate of a run.

    Parameters
    ----------
    pairs : int or sequence of str
        Number of pairs or their names.
    na, nb, nk : int
        ARX orders (see :class:`tsfdi.RecursiveARX`), defaults 1, 2, 1 (see Defaults in the Notes; paper 001:
        2, 2, 0).
    forgetting_factor : float, default 0.999
        Paper 001: 0.995.
    threshold : float, optional
        Alarm threshold of ``statistic``: standard deviations for "zscore" and "zmean" (default 4.5), units of ``y``
        for "mean" (default 4.5), the SPRT walk's level for "sprt" (default the upper bound of ``sprt``).
    glrt : GLRT or None, default ``GLRT(window=20, alpha=1e-6)`` for "zscore", None otherwise
        The GLRT whose window and threshold are used for every pair (its ``scale`` is replaced per pair);
        ``None`` disables the GLRT.
    freeze_on_alarm : bool, default True
        Freeze a pair's model from its first alarm of ``statistic`` on (paper 002), so the model does not learn
        the fault; the alarmed sample itself does not enter the model.
    nonfinite : {"skip", "raise"}, default "skip"
        Policy for NaN / inf samples (see :class:`tsfdi.RecursiveARX`); skipped samples are not fed to the GLRT
        and make the moving average undefined while they are in its window.
    n_inputs : int, default 1
        Inputs per pair; ``u`` then has ``n_pairs * n_inputs`` columns, pair by pair (the inputs of pair 0
        first).
    statistic : {"sprt", "zscore", "mean", "zmean"}, default "sprt"
        Paper 001: "zscore".
    window : int, default 20
        Length in samples of the moving average (``statistic="mean"``) or window sum (``"zmean"``); the errors it
        holds, ``n_pairs * (window - 1)`` values, are checked against the 2 GiB limit (2**28 values) before
        anything is allocated.
    direction : {"both", "down", "up"}, default "both"
        Side of the moving-average (``"mean"``) or window-sum (``"zmean"``) test.
    arm_after : int, default 0
        Length of the baseline phase in samples (counted from the first sample given to the detector).
    eps : float, default 0.03
        Model-stability bound of the arming gate: the largest parameter step relative to the largest parameter,
        both weighted by the scale of their regressor (see Notes); a fraction, so the same for any units of ``y``
        and ``u``. Paper 001's reproduction: 1e-2.
    sprt : SPRT, default ``SPRT("variance", ratio=4, alpha=1e-9, beta=0.01, restart=True)``
        The sequential test of ``statistic="sprt"`` (ignored otherwise): ``alternative`` "variance" (the error
        variance grows by ``ratio``: any change that makes the errors larger, either sign) or "mean" (a shift of
        ``shift`` standard deviations, one-sided), with ``restart=True``. With it ``glrt`` must be None.
    settle : int, default 0
        ``statistic="sprt"`` or ``"zmean"``: samples after arming during which a crossing of ``threshold`` re-arms
        the pair instead of alarming, with its scale taken from a steady regime (see Notes); for a log that starts
        on the ground and takes off. 0: the scale is the Welford standard deviation at arming and every crossing
        alarms.
    scale_forgetting : float in (0, 1), optional
        ``statistic="sprt"`` or ``"zmean"``: standardise the errors by a running mean and standard deviation with
        this exponential forgetting :math:`\lambda` (memory about :math:`1/(1-\lambda)` errors), lagged by
        ``scale_lag`` errors, instead of the values fixed at arming (None, the default); for logs whose healthy
        error spread varies along the flight (see Notes).
    scale_lag : int, default 50
        With ``scale_forgetting``: finite errors between an error and its entry into the running scale (a fault's
        errors meet the scale from before the fault for this many samples). The default is about twice the samples
        the default SPRT needs, on average, to reach its upper bound (20.7) on a fault of its alternative (error
        variance times 4: 0.81 per sample, 26 samples).
    **rls_options
        Further :class:`tsfdi.RecursiveARX` options: ``P0``, ``trend``, ``theta0``, ``stable_samples``
        (consecutive samples the model and the variance gates must hold), ``variance_tol``,
        ``min_variance_samples``. ``theta0`` and ``P0`` are one value for every pair or a mapping from pair names
        to each pair's own, e.g. ``theta0={"roll": arx_results, ...}`` (the ``ARXResults`` of a fit of that pair's
        ARX on other healthy logs: a prior, see Notes); a pair not named starts from RecursiveARX's defaults (zeros
        and ``1e4``), a name that is no pair raises ``ValueError``, and a value RecursiveARX refuses raises its
        error with the pair named. The others are set by the detector (``gate="relative"``, see Notes) or are its
        own parameters above; passing one raises ``TypeError``.

    Attributes
    ----------
    calibration_ : OnlineCalibration or None
        Record of the last :meth:`calibrate` (None before).

    Notes
    -----
    Feeding a stream in blocks (:meth:`run`) or sample by sample (:meth:`update`) gives the same alarms.

    **Defaults.** The defaults are the recipe for autopilot logs of the guide: each pair is a body rate against
    the actuator control of its axis one sample later (``na=1, nb=2, nk=1``), memory about 20 s at 50 Hz
    (``forgetting_factor=0.999``), ``eps=0.03`` and the restarted SPRT at the upper bound of ``alpha=1e-9``
    (about 20.7). Uncalibrated, on the twelve healthy and twelve failure development logs of
    ``benchmarks/streaming.py`` (90 s, 50 Hz, rotor losses of 10-100 %): every pair arms within 9.7 s, no healthy
    log alarms and all 12 failures are found within 0.5 s, where paper 001's settings (``na=2, nb=2, nk=0,
    forgetting_factor=0.995, eps=1e-2, statistic="zscore"`` with the GLRT) alarm on all twelve healthy logs and
    before 11 of the 12 failures, and ``alpha=1e-4`` (upper bound 9.2) alarms on 4 of the 12 healthy logs (the
    largest healthy statistic was 11.4, the smallest within 0.5 s of a failure 68). Paper 001's reproduction
    takes those arguments explicitly. For a stated false-alarm rate use :meth:`calibrate`.

    **Settle (take-off).** With ``statistic="sprt"`` (or ``"zmean"``) the errors are standardised by a scale fixed
    at arming.
    A pair that arms while the vehicle stands still takes the scale of the ground and alarms at take-off. With
    ``settle`` :math:`= S > 0` the pair arms on a *steady regime*: once the error variance is stable, the next
    :math:`W = \max(S, \text{min\_variance\_samples})` finite errors give the mean and scale if the variances
    of their two halves agree within a factor 4 (else the window slides by half); and a walk that reaches
    ``threshold`` within :math:`S` samples of arming is taken for a regime still changing, not a fault: no alarm,
    the pair re-arms from the next :math:`W` errors. A fault within :math:`S` samples of arming is therefore
    absorbed into the scale, and a vehicle standing armed on the ground for more than :math:`W + S` samples
    before take-off has a steady ground regime and still alarms at take-off (start the stream at take-off or
    set ``arm_after``). :meth:`calibrate` runs its healthy logs with the same rule at the detector's threshold
    before calibration.

    **Running scale.** With ``scale_forgetting`` :math:`= \lambda` and ``scale_lag`` :math:`= L`, the finite
    errors :math:`e_1, e_2, \dots` after arming enter a running mean and variance,

    .. math:: m_j = \lambda m_{j-1} + (1-\lambda)\, e_j, \qquad
              v_j = \lambda v_{j-1} + \lambda(1-\lambda)\,(e_j - m_{j-1})^2,

    from :math:`m_0, v_0` the mean and variance at arming, and the SPRT sees
    :math:`w_k = (e_k - m_{k-L-1}) / \sqrt{v_{k-L-1}}` (index below 0: the arming values). A change of the spread
    along a healthy flight (manoeuvres, wind, another flight phase) is followed within about
    :math:`1/(1-\lambda)` errors, so the walk's law varies less between and within logs. A fault's own errors
    enter the scale only :math:`L` samples after the walk has seen them against the scale from before the fault,
    and then with weight :math:`1-\lambda` each: :math:`n` errors later the variance has moved by the fraction
    :math:`1-\lambda^{n}` towards the fault's. A variance-increase test against a tracking scale adapts a fault
    away: a fault not found within :math:`L` samples plus a fraction of :math:`1/(1-\lambda)` is found late or not
    at all, as a slow drift is by design. :meth:`calibrate` standardises its healthy logs by the same rule. The
    scale is not frozen while the walk is above zero: that would make it depend on the walk's ``scale_`` and
    ``threshold``, which :meth:`calibrate` sets (its healthy runs would not see the scale of the calibrated
    detector), and would keep out of the scale the large healthy errors that lift the walk.

    **Prior per pair.** Each pair's RLS minimises, after :math:`N` samples,
    :math:`\sum_t \lambda^{N-t} e_t^2 + \lambda^N (\theta - \theta_0)' P_0^{-1} (\theta - \theta_0)` (the
    recursion of :class:`tsfdi.RecursiveARX` from :math:`\theta_0`, :math:`P_0`; with its anti-windup rule for
    :math:`\lambda < 1`). Least squares of the pair's ARX on :math:`M` samples of other healthy logs gives
    :math:`\hat\theta` and :math:`(\sum \varphi\varphi')^{-1}`, the RLS state after those samples: with
    ``theta0`` :math:`= \hat\theta` and ``P0`` :math:`= k (\sum \varphi\varphi')^{-1}` the pair starts as if it
    had seen :math:`M / k` samples of that fleet: it predicts from its first sample, and its steps, small against
    :math:`\hat\theta`, pass the model gate sooner than from zero. A prior helps only as far as the new vehicle is
    like the fleet: for a small :math:`k` the anti-windup rule keeps each variance at most its :math:`P_0` value, so
    the pair cannot move far from :math:`\hat\theta`. On the streaming benchmark's development logs (aircraft drawn
    around a nominal one) no prior did better than none (``benchmarks/streaming.py``, ``--prior``).

    **Arming gate.** Paper 001 (section IV-B) considers the model stable for fault detection when the parameter
    step :math:`\|L(k)\hat e(k)\|_\infty < \epsilon` "for some time", with :math:`\epsilon` "a small positive number"
    and no unit. An absolute bound depends on the units of ``y`` and ``u`` (a gain from a command in rad/s to a
    rate in deg/s is 57 times that to a rate in rad/s) and arms at once while the estimate is still at its
    start ``theta = 0`` on quiet data. The pairs' models therefore use the relative gate of
    :class:`tsfdi.RecursiveARX` (``gate="relative"``, see its Notes): sample :math:`k` passes when

    .. math:: \|D(k)\,\Delta\theta(k)\|_\infty < \epsilon\, \|D(k)\,\theta(k-1)\|_\infty ,

    with :math:`\Delta\theta(k) = \theta(k) - \theta(k-1)` (0 while the model is frozen) and :math:`D(k)` the
    diagonal of regressor scales (1 for the constant, :math:`\max_{t \le k}|y(t)|` for every :math:`a_i`,
    :math:`\max_{t \le k}|u_j(t)|` for every :math:`b_{ji}`): no term of the prediction
    :math:`\phi(k)'\theta` moves by more than the fraction :math:`\epsilon` of the largest term. Both sides are in
    the units of ``y``: the gate is unchanged when ``y`` and each input are rescaled, together or separately. The
    model is stable once ``stable_samples`` consecutive regression samples pass (paper 001's "for some time");
    from then on the error variance is tracked as in :class:`tsfdi.RecursiveARX`. A model that never moves from
    ``theta = 0`` (an output that does not depend on its regressors) never passes: paper 001 notes that
    uncorrelated pairs are "very unlikely to allow for the model estimation to stabilize".

    The moving average of the a-priori errors over ``w`` samples, ``m(k) = (1/w) sum_{i=k-w+1}^{k} e(i)``, is
    the finite-moving-average detector of a change in mean; for independent Gaussian errors it is the GLRT of
    a jump of known length ``w`` (paper 002, eq. 3 with ``n = w``). Its threshold is in physical units, which
    makes it usable on real records whose error distribution is heavy-tailed and non-stationary, where a
    single-sample Z-score against a running variance raises false alarms.

    **Standardised window sum** (``statistic="zmean"``). For independent Gaussian errors of variance
    :math:`\sigma^2` and a jump of the mean by :math:`A` over the last :math:`w` samples, paper 002's GLRT
    (eqs. 1-3) with the change instant fixed at :math:`j = k - w + 1` is
    :math:`\max_A S_j^k = (\sum_{i=j}^{k} e_i)^2 / (2\sigma^2 w) = T_k^2 / 2`: :math:`T_k` is its signed root, the
    matched filter of a bias lasting :math:`w` samples, :math:`N(0, 1)` under the null and shifted by
    :math:`A\sqrt{w}/\sigma` under the jump. Against ``"mean"`` it divides by the scale of each pair fixed at
    arming, so that its threshold is in standard deviations of the window sum and holds across pairs and logs
    whose error spread differs; against the SPRT of a mean shift it does not accumulate past :math:`w` samples,
    so a bias that decays (a loss the rate loop compensates within 1-2 s) is not offset by the negative drift of
    the walk. Autocorrelated errors make its null variance differ from 1 (the sum of the autocorrelations over the
    window): :meth:`calibrate` reads the threshold from the healthy runs, as for ``"mean"``.

    References
    ----------
    Keipour, Mousaei, Scherer, ICRA 2019 (paper 001), sections IV-V; Hansen, Blanke, Adrian (paper 002),
    eqs. 1-3 and 14-16; M. Basseville, I. Nikiforov, *Detection of Abrupt Changes*, 1993, section 2.1.
    """

    def __init__(self, pairs: Any, *, na: int = 1, nb: int = 2, nk: int = 1, forgetting_factor: float = 0.999,
                 threshold: float | None = None, glrt: Any = "default", freeze_on_alarm: bool = True,
                 nonfinite: str = "skip", n_inputs: int = 1, statistic: str = "sprt", window: int = 20,
                 direction: str = "both", arm_after: int = 0, eps: float = 0.03, sprt: Any = "default",
                 settle: int = 0, scale_forgetting: float | None = None, scale_lag: int = 50,
                 **rls_options: Any) -> None:
        if isinstance(pairs, (int, np.integer)) and not isinstance(pairs, bool):
            n = int_like(pairs, "pairs", minimum=1)
            names = tuple(f"pair{i}" for i in range(n))
        elif isinstance(pairs, (list, tuple)) and pairs and all(isinstance(p, str) for p in pairs):
            names = tuple(pairs)
            if len(set(names)) != len(names):
                raise ValueError(f"pairs must have distinct names, got {names}")
        else:
            raise TypeError(f"pairs must be a positive int or a non-empty sequence of names, got {pairs!r}")
        for key in rls_options:
            if key not in _RLS_OPTIONS:
                why = ("is set by OnlineDetector: its pairs use the scale-free gate='relative' (its Notes)"
                       if key == "gate" else "is not an option of OnlineDetector")
                raise TypeError(f"{key} {why}; the RecursiveARX options it passes on are {', '.join(_RLS_OPTIONS)}")
        # theta0 / P0 per pair: a mapping from pair names (a pair not named starts from RecursiveARX's default)
        per_pair: dict = {}
        for key in _PER_PAIR_OPTIONS:
            if isinstance(rls_options.get(key), Mapping):
                given = dict(rls_options[key])
                unknown = [k for k in given if k not in names]
                if unknown:
                    raise ValueError(f"{key} names no pair {unknown[0]!r}: a mapping of {key} is keyed by the pair "
                                     f"names {list(names)}")
                per_pair[key] = given
                rls_options[key] = given
        self.pairs = names
        self.nonfinite = option(nonfinite, "nonfinite", ("skip", "raise"))
        self.statistic = option(statistic, "statistic", ("zscore", "mean", "sprt", "zmean"))
        if isinstance(sprt, str) and sprt == "default":
            sprt = SPRT("variance", ratio=4.0, alpha=1e-9, beta=0.01, restart=True)
        if self.statistic != "sprt":
            sprt = None
        elif not isinstance(sprt, SPRT):
            raise TypeError(f"sprt must be a tsfdi.SPRT (statistic='sprt'), got {type(sprt).__name__}")
        elif sprt.alternative == "model" or not sprt.restart:
            raise ValueError(f"sprt must be a monitoring SPRT of the prediction errors: alternative 'variance' or "
                             f"'mean' with restart=True, got {sprt!r}")
        self.sprt = sprt
        if threshold is None:
            threshold = sprt.upper if sprt is not None else 4.5
        self.threshold = float_like(threshold, "threshold", minimum=0.0, strict_min=True)
        self.window = int_like(window, "window", minimum=1)
        check_size(len(names) * (self.window - 1), f"window={self.window} for {len(names)} pair(s): the errors "
                   f"in the moving window ({len(names):,} x {self.window - 1:,})")
        self.direction = option(direction, "direction", ("both", "down", "up"))
        self.arm_after = int_like(arm_after, "arm_after", minimum=0)
        self.n_inputs = int_like(n_inputs, "n_inputs", minimum=1)
        self.eps = float_like(eps, "eps", minimum=0.0, strict_min=True)
        self.settle = int_like(settle, "settle", minimum=0)
        if self.settle and self.statistic not in _ARMED_SCALE:
            raise ValueError(f"settle={self.settle} needs statistic='sprt' or 'zmean' (the scale it sets is theirs), "
                             f"got statistic={self.statistic!r}")
        self.scale_forgetting = float_like(scale_forgetting, "scale_forgetting", minimum=0.0, maximum=1.0,
                                           strict_min=True, strict_max=True, optional=True)
        if self.scale_forgetting is not None and self.statistic not in _ARMED_SCALE:
            raise ValueError(f"scale_forgetting={self.scale_forgetting:g} needs statistic='sprt' or 'zmean' (the "
                             f"scale is theirs), got statistic={self.statistic!r}")
        self.scale_lag = int_like(scale_lag, "scale_lag", minimum=0)
        self._settle_level: float | None = None   # the alarm-free copies of calibrate: the level settle watches
        self.freeze_on_alarm = boolean(freeze_on_alarm, "freeze_on_alarm")
        if isinstance(glrt, str) and glrt == "default":
            glrt = GLRT(window=20, alpha=1e-6) if self.statistic == "zscore" else None
        if glrt is not None and not isinstance(glrt, GLRT):
            raise TypeError(f"glrt must be a tsfdi.detection.GLRT or None, got {type(glrt).__name__}")
        if glrt is not None and self.statistic in _ARMED_SCALE:
            raise ValueError(f"glrt must be None with statistic={self.statistic!r}: it is the test of the prediction "
                             "errors (a GLRT beside it would double the false alarms calibrate sets)")
        self.glrt = glrt
        # the constructor's options, for the alarm-free copies run by calibrate()
        self._options = dict(na=na, nb=nb, nk=nk, forgetting_factor=forgetting_factor, threshold=self.threshold,
                             glrt=glrt, freeze_on_alarm=self.freeze_on_alarm, nonfinite=self.nonfinite,
                             n_inputs=self.n_inputs, statistic=self.statistic, window=self.window,
                             direction=self.direction, arm_after=self.arm_after, eps=self.eps, sprt=sprt,
                             settle=self.settle, scale_forgetting=self.scale_forgetting,
                             scale_lag=self.scale_lag, **rls_options)
        self.calibration_: OnlineCalibration | None = None
        zs = self.statistic == "zscore"
        # in "mean" mode the model's own Z-score never alarms (threshold 1e300) and halting is done here
        self._models = []
        for name in names:
            own = {k: v for k, v in rls_options.items() if k not in per_pair}
            own.update({key: given[name] for key, given in per_pair.items() if name in given})
            try:
                model = RecursiveARX(na, nb, nk, forgetting_factor, n_inputs=self.n_inputs,
                                     threshold=self.threshold if zs else 1e300,
                                     freeze_on_alarm=self.freeze_on_alarm and zs, nonfinite=self.nonfinite,
                                     arm_after=self.arm_after if zs else 0, eps=self.eps, gate="relative", **own)
            except (ValueError, TypeError) as err:
                if not any(name in given for given in per_pair.values()):
                    raise
                raise type(err)(f"pair {name!r}: {err}") from err
            self._models.append(model)
        self.reset()

    def reset(self) -> None:
        """Forget everything: models, GLRT streams and alarms."""
        for m in self._models:
            m.reset()
        k = len(self.pairs)
        self._streams: list = [None] * k
        self._armed_at = np.full(k, -1, dtype=np.int64)
        self._first = np.full(k, -1, dtype=np.int64)
        self._source = [""] * k
        self._time: list = [None] * k
        self._tail = np.full((k, max(self.window - 1, 0)), np.nan)
        self._walks: list = [None] * k   # statistic="sprt": the walk of every armed pair (see _sprt_walk)
        self._stat_alarmed = np.zeros(k, dtype=bool)
        self._last_alarm = np.zeros(k, dtype=bool)
        self._nobs = 0
        self._warned = np.zeros(k, dtype=bool)
        self._last_time: Any = None      # index label of the last sample (None for numpy input)

    @property
    def models(self) -> tuple:
        """The per-pair :class:`tsfdi.RecursiveARX` estimators (``gate="relative"``; read their state, do not feed
        them)."""
        return tuple(self._models)

    @property
    def nobs(self) -> int:
        """Samples processed so far."""
        return self._nobs

    def _signals(self, y: Any, u: Any):
        k = len(self.pairs)
        sy = as_signal(y, "y", vector=None, min_nobs=1, allow_constant=True, finite=False)
        su = as_signal(u, "u", vector=None, min_nobs=1, allow_constant=True, finite=False)
        if sy.nchan != k:
            raise ValueError(f"y must have one column per pair ({k}), got {sy.nchan}")
        if su.nchan != k * self.n_inputs:
            raise ValueError(f"u must have n_inputs={self.n_inputs} column(s) per pair ({k * self.n_inputs} in "
                             f"all), got {su.nchan}")
        if sy.nobs != su.nobs:
            raise ValueError(f"u and y must have the same length, got len(u)={su.nobs} and len(y)={sy.nobs}")
        check_paired(sy, su)
        return sy, su

    def _mean_statistic(self, c: int, e: np.ndarray) -> np.ndarray:
        """Direction-signed moving average of the errors of pair ``c`` continuing its tail (not updated)."""
        return self._signed(_moving_average(np.concatenate([self._tail[c], e]), self.window)[self.window - 1:])

    def _signed(self, m: np.ndarray) -> np.ndarray:
        """``m`` on the side of ``direction``: negated for "down", absolute for "both"."""
        if self.direction == "down":
            return -m
        if self.direction == "both":
            return np.abs(m)
        return m

    def _window_sum(self, w: np.ndarray, tail: np.ndarray) -> tuple:
        """Direction-signed standardised window sum ``T_k`` of the standardised errors ``w`` continuing ``tail`` (the
        last ``window - 1`` of them before; NaN in the window: NaN), and the new tail."""
        x = np.concatenate([tail, w])
        t = self._signed(_moving_average(x, self.window)[self.window - 1:] * np.sqrt(self.window))
        return t, x[x.size - tail.size:]

    @staticmethod
    def _join(parts: list) -> tuple:
        """Errors, Z-scores, Z-score alarms, variance-stable flags, variances and means of result parts."""
        def cat(name):
            return np.concatenate([np.asarray(getattr(p, name), dtype=float) for p in parts])

        flags = [np.concatenate([getattr(p, name) for p in parts]) for name in ("alarm", "variance_stable")]
        return cat("resid"), cat("zscore"), flags[0], flags[1], cat("variance"), cat("mean")

    def _run_mean(self, c: int, m: RecursiveARX, yc: np.ndarray, uc: np.ndarray, start: int):
        """Run pair ``c`` in "mean" mode, freezing its model at the first alarm (exactly as sample by sample)."""
        snap = m.get_state() if self.freeze_on_alarm and not self._stat_alarmed[c] else None
        parts = [m.run(yc, uc)]
        e = self._join(parts)[0]
        stat = self._mean_statistic(c, e)
        pos = start + np.arange(yc.shape[0])
        hit = np.flatnonzero((np.nan_to_num(stat, nan=-np.inf) > self.threshold) & (pos >= self.arm_after))
        if snap is not None and hit.size:
            i = int(hit[0])
            m.set_state(snap)
            parts = [m.run(yc[:i], uc[:i])] if i > 0 else []
            m.freeze()
            parts.append(m.run(yc[i:], uc[i:]))
            e = self._join(parts)[0]
            stat = self._mean_statistic(c, e)
        if hit.size:
            self._stat_alarmed[c] = True
        w1 = self.window - 1
        if w1:
            self._tail[c] = np.concatenate([self._tail[c], e])[-w1:]
        alarm = (np.nan_to_num(stat, nan=-np.inf) > self.threshold) & (pos >= self.arm_after)
        _, z, _, vstable, var, mean = self._join(parts)
        return e, z, stat, alarm, vstable, var, mean

    def _sprt_walk(self, c: int, e: np.ndarray, vstable: np.ndarray, var: np.ndarray, mean: np.ndarray,
                   start: int, commit: bool) -> tuple:
        """Restarted SPRT of the errors ``e`` of pair ``c`` continuing its walk (the state kept when ``commit``).

        ``settle=0``: armed from the sample after the error variance became stable and positive, on the errors
        minus the Welford mean at arming, scaled by the Welford standard deviation at arming. ``settle > 0`` (see
        the class Notes): from then on the next ``max(settle, min_variance_samples)`` finite errors whose two
        halves' variances agree give the mean and scale, and a crossing of the alarm level within ``settle``
        samples of arming re-arms the pair instead of alarming. Returns the walk (NaN where not armed) and the
        alarms."""
        n = e.shape[0]
        path = np.full(n, np.nan)
        alarm = np.zeros(n, dtype=bool)
        # [sd, mean at arming, walk value, end of the settle period, errors collected, running state or None]
        walk = self._walks[c]
        armed_at = int(self._armed_at[c])
        lo = 0
        if walk is None:
            vs = np.flatnonzero(vstable & np.isfinite(var) & (var > 0))
            if not vs.size:
                return path, alarm
            lo = int(vs[0]) + 1
            if self.settle:
                walk = [np.nan, np.nan, 0.0, 0, [], None]
            else:
                armed_at = start + lo
                walk = self._armed_walk(float(np.sqrt(var[vs[0]])), float(mean[vs[0]]), armed_at)
        walk = list(walk)
        level = self.threshold if self._settle_level is None else self._settle_level
        while lo < n:
            if walk[4] is not None:                         # arming: collect the errors of the scale
                need = max(self.settle, self._models[c].min_variance_samples) - len(walk[4])
                fin = lo + np.flatnonzero(np.isfinite(e[lo:]))
                if fin.size < need:
                    walk[4] = walk[4] + e[fin].tolist()
                    break
                j = int(fin[need - 1])
                x = np.array(walk[4] + e[fin[:need]].tolist())
                sd = float(x.std(ddof=1))
                lo = j + 1
                half = x.size // 2
                v = (float(x[:half].var()), float(x[half:].var()))
                if not (sd > 0 and max(v) <= _STEADY_RATIO * min(v)):
                    walk[4] = x[half:].tolist()             # not a steady regime: slide by half the errors
                    continue
                armed_at = start + lo
                walk = self._armed_walk(sd, float(x.mean()), armed_at + self.settle)
                continue
            w, running = self._standardise(e[lo:], walk)
            if self.statistic == "zmean":
                p, state = self._window_sum(w, walk[2])
                a = p > self.threshold                      # NaN (window not yet full): no alarm
            else:
                z = np.full(n - lo, np.nan)
                ok = np.isfinite(w)
                if ok.any():
                    z[ok] = self.sprt.loglik_ratio(w[ok], 1.0)
                p, a, _, _, state, _ = renewal_walk(z, self.sprt.lower, self.threshold, state=walk[2])
            settling = start + lo + np.arange(n - lo) < walk[3]
            if settling.any():
                if level == self.threshold:
                    hit = a
                elif self.statistic == "zmean":
                    hit = p > level
                else:
                    hit = renewal_walk(z, self.sprt.lower, level, state=walk[2])[1]
                hits = np.flatnonzero(hit & settling)
                if hits.size:                               # not a steady regime yet: re-arm
                    j = int(hits[0])
                    path[lo:lo + j + 1] = p[:j + 1]
                    lo += j + 1
                    walk[4] = []
                    continue
            path[lo:] = p
            alarm[lo:] = a
            walk[2] = state if self.statistic == "zmean" else float(state)
            walk[5] = running
            lo = n
        alarm &= (start + np.arange(n)) >= self.arm_after
        if commit:
            self._armed_at[c] = armed_at
            self._walks[c] = walk
        return path, alarm

    def _armed_walk(self, sd: float, mean: float, settle_end: int) -> list:
        """The walk state of a pair armed with the scale ``sd`` and mean ``mean`` (see :meth:`_sprt_walk`)."""
        running = None if self.scale_forgetting is None else (mean, sd ** 2, np.empty(0))
        # the statistic's state: the SPRT walk's value, or the last window - 1 standardised errors of "zmean"
        state = np.full(self.window - 1, np.nan) if self.statistic == "zmean" else 0.0
        return [sd, mean, state, settle_end, None, running]

    def _standardise(self, e: np.ndarray, walk: list) -> tuple:
        """Errors ``e`` of a pair armed with ``walk`` standardised: by the scale at arming (``scale_forgetting``
        None) or by the lagged running scale from the walk's running state (class Notes); returns them and the
        new running state."""
        if walk[5] is None:
            return (e - walk[1]) / walk[0], None
        w, m, v, pending = _running_standardise(e, *walk[5], self.scale_forgetting, self.scale_lag)
        return w, (m, v, pending)

    def _run_sprt(self, c: int, m: RecursiveARX, yc: np.ndarray, uc: np.ndarray, start: int):
        """Run pair ``c`` with the restarted SPRT, freezing its model at the first alarm (as sample by sample)."""
        snap = m.get_state() if self.freeze_on_alarm and not self._stat_alarmed[c] else None
        parts = [m.run(yc, uc)]
        e, _, _, vstable, var, mean = self._join(parts)
        _, alarm = self._sprt_walk(c, e, vstable, var, mean, start, commit=False)
        if snap is not None and alarm.any():
            i = int(np.flatnonzero(alarm)[0])
            m.set_state(snap)
            parts = [m.run(yc[:i], uc[:i])] if i > 0 else []
            m.freeze()
            parts.append(m.run(yc[i:], uc[i:]))
        e, z, _, vstable, var, mean = self._join(parts)
        stat, alarm = self._sprt_walk(c, e, vstable, var, mean, start, commit=True)
        if alarm.any():
            self._stat_alarmed[c] = True
        return e, z, stat, alarm, vstable, var, mean

    def run(self, y: Any, u: Any) -> OnlineDetection:
        """Process a block of samples of every pair (continuing from the current state).

        Parameters
        ----------
        y : array_like, DataFrame or DataArray, shape (nobs, n_pairs)
            Outputs, one column per pair (a 1-D array for a single pair).
        u : array_like, DataFrame or DataArray, shape (nobs, n_pairs * n_inputs)
            Inputs, ``n_inputs`` columns per pair, pair by pair.

        Returns
        -------
        OnlineDetection

        Warns
        -----
        ConvergenceWarning
            Once per pair and stream (until :meth:`reset`), when the block ends with a pair not armed while its
            Z-score or GLRT would need it, naming the pair, the time of the last sample (index label, and seconds
            since the first sample when the index gives ``fs``) and the gate that is still shut.
        """
        out = self._process(y, u)
        idle = self.statistic == "mean" and self.glrt is None       # nothing waits for arming
        for c in np.flatnonzero((self._armed_at < 0) & ~self._warned & ~idle):
            self._warned[c] = True
            m = self._models[c]
            last = self._nobs - 1
            when = f"sample {last}"
            if self._last_time is not None:
                seconds = "" if out.fs is None else f", {last / out.fs:.6g} s after the first sample"
                when = f"time {self._last_time} ({when}{seconds})"
            run = f"for stable_samples={m.stable_samples} samples in a row"
            gate = (f"its model is stable but its error variance has not settled (relative change per sample below "
                    f"variance_tol={m.variance_tol:g} {run}, after at least min_variance_samples="
                    f"{m.min_variance_samples} errors): give more data or raise variance_tol" if m.model_stable else
                    f"its parameter step never stayed below eps={self.eps:g} of the parameters {run}: check that y "
                    "follows u (on an autopilot log: the body rate of an axis against the actuator control of that "
                    "axis, nk=1), give more data or raise eps")
            source = {"zscore": "Z-score", "sprt": "SPRT", "zmean": "window-sum"}.get(self.statistic, "GLRT")
            warnings.warn(f"OnlineDetector pair {self.pairs[c]!r} has not armed by the end of the data at {when}, so "
                          f"it could raise no {source} alarm: {gate}",
                          ConvergenceWarning, stacklevel=2)
        return out

    def _process(self, y: Any, u: Any) -> OnlineDetection:
        """:meth:`run` without the warning (:meth:`update` feeds one sample at a time)."""
        sy, su = self._signals(y, u)
        n, k = sy.nobs, len(self.pairs)
        start = self._nobs
        Z = np.full((n, k), np.nan)
        G = np.full((n, k), np.nan)
        E = np.full((n, k), np.nan)
        S = np.full((n, k), np.nan)
        A = np.zeros((n, k), dtype=bool)
        labels = sy.index
        pos = start + np.arange(n)
        ni = self.n_inputs
        for c, m in enumerate(self._models):
            yc = np.ascontiguousarray(sy.values[:, c])
            uc = np.ascontiguousarray(su.values[:, c * ni:(c + 1) * ni])
            if self.statistic == "zscore":
                e, z, zal, vstable, var, mean = self._join([m.run(yc, uc)])
                stat = z
            elif self.statistic in _ARMED_SCALE:
                e, z, stat, zal, vstable, var, mean = self._run_sprt(c, m, yc, uc, start)
            else:
                e, z, stat, zal, vstable, var, mean = self._run_mean(c, m, yc, uc, start)
            Z[:, c] = z
            E[:, c] = e
            S[:, c] = stat
            gal = np.zeros(n, dtype=bool)
            if self.glrt is not None:
                # the GLRT is armed from the sample after the variance became stable (and positive: a stream of
                # exactly predicted samples has no scale to measure a change against)
                if self._streams[c] is None:
                    vs = np.flatnonzero(vstable & np.isfinite(var) & (var > 0))
                    if vs.size:
                        arm = int(vs[0]) + 1
                        self._streams[c] = (self.glrt.stream(1, scale=np.sqrt(var[vs[0]])), float(mean[vs[0]]))
                        self._armed_at[c] = start + arm
                        lo = arm
                    else:
                        lo = n
                else:
                    lo = 0
                if self._streams[c] is not None and lo < n:
                    stream, mu = self._streams[c]
                    seg = e[lo:] - mu
                    ok = np.isfinite(seg)
                    if ok.any():
                        g = stream.extend(seg[ok])[:, 0]
                        idx = np.flatnonzero(ok) + lo
                        G[idx, c] = g
                        gal[idx] = g > stream.threshold
                gal &= pos >= self.arm_after
            elif self._armed_at[c] < 0 and self.statistic not in _ARMED_SCALE:
                vs = np.flatnonzero(vstable)
                if vs.size:
                    self._armed_at[c] = start + int(vs[0]) + 1
            alarm = zal | gal
            A[:, c] = alarm
            if self._first[c] < 0 and alarm.any():
                i = int(np.flatnonzero(alarm)[0])
                self._first[c] = start + i
                self._source[c] = "+".join(s for s, a in ((self.statistic, zal[i]), ("glrt", gal[i])) if a)
                self._time[c] = labels[i] if labels is not None else start + i
        self._nobs += n
        if n:
            self._last_time = labels[-1] if labels is not None else None
        starts = _episode_starts(A, self._last_alarm)
        self._last_alarm = A[-1].copy()
        return self._result(sy, Z, G, E, A, S, starts)

    def update(self, y: Any, u: Any) -> np.ndarray:
        """Process one sample of every pair; returns the per-pair alarm flags (bool array).

        Parameters
        ----------
        y : float or array_like, shape (n_pairs,)
            The output of every pair at this sample (a number for a single pair); NaN / inf follow
            ``nonfinite``.
        u : float or array_like, shape (n_pairs * n_inputs,)
            The inputs of every pair, pair by pair.

        Raises
        ------
        TypeError
            ``y`` or ``u`` is None, a string, a boolean or otherwise not numbers.
        ValueError
            ``y`` or ``u`` has more than one dimension, the wrong number of values, or masked values.
        """
        return self._process(self._sample(y, "y"), self._sample(u, "u")).alarm[0]

    @staticmethod
    def _sample(value: Any, name: str) -> np.ndarray:
        """One sample of every pair, a number or a 1-D sequence, as a (1, k) float array."""
        if value is None or isinstance(value, (str, bytes)):
            raise TypeError(f"{name} must be a number or a 1-D sequence of numbers (this sample of every pair), "
                            f"got {value!r}")
        refuse_masked(value, name)
        if np.ndim(value) > 1:
            raise ValueError(f"{name} must be a number or a 1-D sequence (this sample of every pair), got shape "
                             f"{np.shape(value)}")
        values = as_signal(np.atleast_1d(value), name, min_nobs=1, allow_constant=True, finite=False).values
        return values.reshape(1, -1)

    # ------------------------------------------------------------------ thresholds from healthy runs
    def _alarm_free_copy(self) -> OnlineDetector:
        """A fresh detector with the same options whose thresholds are never reached (so it never freezes)."""
        glrt = None
        if self.glrt is not None:
            glrt = copy.copy(self.glrt)
            glrt.threshold = _HUGE
        free = OnlineDetector(self.pairs, **{**self._options, "threshold": _HUGE, "glrt": glrt})
        free._settle_level = self.threshold
        return free

    @staticmethod
    def _runs(runs: Any, name: str) -> list:
        if not isinstance(runs, (list, tuple)):
            raise TypeError(f"{name} must be a list of runs (one array, DataFrame or DataArray per healthy run), "
                            f"got {type(runs).__name__}")
        if not runs:
            raise ValueError(f"{name} must hold at least one healthy run")
        return list(runs)

    def calibrate(self, y_runs: Any, u_runs: Any, *, false_alarms_per_hour: float,
                  fs: float | None = None) -> OnlineDetector:
        r"""Set the thresholds for a required number of false alarms per flight hour, from healthy runs.

        Paper 002's rule (Hansen et al., section 3, Fig. 2): the threshold is read from the distribution of the
        detection statistic in normal operation for a required false-alarm probability. Here the requirement is
        a rate of alarm *episodes* per flight hour -- consecutive alarmed samples are one alarm to the operator
        -- which is what a crew or an operator counts, whatever the sampling rate and the correlation of the
        statistic.

        Every healthy run goes through a fresh copy of the detector (same options) whose thresholds are never
        reached, so its models never freeze; the copy's statistic is kept from the sample it can alarm at
        (after arming and the baseline phase ``arm_after``): :math:`|Z|` for ``statistic="zscore"``, the
        direction-signed moving average for ``"mean"``, the direction-signed standardised window sum for ``"zmean"``
        (its episodes counted as for the others), and the GLRT's :math:`g(k)` when the GLRT is on. The
        thresholds are then set, :meth:`reset` is called and ``calibration_`` records the estimate.

        Parameters
        ----------
        y_runs, u_runs : list of array_like, DataFrame or DataArray
            The healthy runs, one entry per run, each as :meth:`run` takes ``y`` and ``u``; runs are independent
            (every one starts a fresh detector), so each should be a whole flight or a stretch long enough to
            arm.
        false_alarms_per_hour : float
            Required alarm episodes per flight hour of healthy operation, all pairs together (the ``"all"`` row
            of :meth:`OnlineDetection.false_alarms_per_hour`).
        fs : float, optional
            Sampling frequency in Hz; by default read from each run's time index.

        Returns
        -------
        OnlineDetector
            ``self``, with ``threshold`` (and ``glrt``'s threshold) set and ``calibration_``
            (:class:`OnlineCalibration`).

        Raises
        ------
        ValueError
            For a non-positive rate or ``fs``, unequal numbers of runs, a run :meth:`run` refuses (the message
            names the run), no ``fs`` for data without a time index, or healthy runs too short for the rate
            (the message states how many healthy hours are needed).
        TypeError
            If ``y_runs`` / ``u_runs`` is not a list of runs.

        Notes
        -----
        Let :math:`x_r(k)` be the statistic of run :math:`r` (undefined before it can alarm) and
        :math:`H = \sum_r n_r / (3600 f_s)` the healthy flight hours (whole runs, arming phases included; with
        several pairs, :math:`x` runs over every pair of every run and the rate is that of all pairs
        together). A sample starts an episode at level :math:`t` when :math:`x_r(k) > t` and not
        :math:`x_r(k-1) > t`; :math:`N(t)` counts them and :math:`\tilde N(t) = \max_{t' \ge t} N(t')` is its
        non-increasing envelope. The target is :math:`K = \rho H` episodes, :math:`\rho` =
        ``false_alarms_per_hour``.

        - **Empirical** (:math:`K \ge 5`): with :math:`D_m = \min\{t: \tilde N(t) < m\}`, the :math:`m`-th
          highest episode peak (for Poisson episodes, :math:`m` are expected at or above it),

          .. math:: t = D_{\lceil K\rceil} + \frac{\ln\lceil K\rceil - \ln K}{\ln\lceil K\rceil - \ln\lfloor K\rfloor}
                    \,\big(D_{\lfloor K\rfloor} - D_{\lceil K\rceil}\big)

          (:math:`t = D_K` for an integer :math:`K`): the episode count interpolated log-linearly.
        - **Exponential tail** (:math:`1 \le K < 5`: too few episodes to count): peaks over a threshold,
          one peak per episode. :math:`u = D_{21}` is the lowest observed level with
          :math:`\tilde N(u) \le 20`, :math:`n_u` (at least 10) the episodes above it and :math:`p_i` their
          peaks (the largest :math:`x` of each). With exponential excesses of scale :math:`\beta` (a
          generalised Pareto tail of shape 0) the episode rate above :math:`t > u` is
          :math:`\rho(t) = \rho(u)\, e^{-(t - u)/\beta}`; the maximum-likelihood scale is the mean excess
          :math:`\hat\beta = \frac{1}{n_u}\sum_i (p_i - u)` (:math:`n_u\hat\beta/\beta \sim \Gamma(n_u)`), and
          :math:`u` being the :math:`(n_u+1)`-th peak, :math:`n_u + 1` episodes lie above it on average.
          :math:`t = u + c\,\hat\beta` with the expected number of episodes above :math:`t`,
          :math:`(n_u + 1)(1 + c/n_u)^{-n_u}`, equal to :math:`K`:

          .. math:: t = u + \hat\beta\, n_u\Big[\Big(\frac{n_u + 1}{K}\Big)^{1/n_u} - 1\Big]
                    \;\approx\; u + \hat\beta \ln\frac{n_u + 1}{K}.

          The exponential tail suits the GLRT's :math:`g(k)` (a maximum of scaled :math:`\chi^2(1)`
          variables). A lighter tail (log-survival concave, e.g. Gaussian errors) makes the threshold err
          high (fewer false alarms than required), a heavier one (e.g. runs whose error scale differs) low.
        - :math:`K < 1` (fewer than :math:`1/\rho` healthy hours): ``ValueError``.

        **statistic="sprt"**: a few short logs suffice (the restart cycles of the walk are many even where alarms
        are rare). The standardised errors of every armed (run, pair) record are one record (with
        ``scale_forgetting``, standardised by the lagged running scale as the walk saw them); at least three are
        needed. (1) The per-sample log-likelihood ratios :math:`z` of all records give Wald's exponent
        :math:`h > 0` of the pooled walk, the root of :math:`\hat K(h) + \tfrac{h^2}{2}(\hat v_{lr} - \hat v) = 0`
        (empirical cumulant generating function of :math:`z`, long-run variance over batches of 32 samples, as in
        :meth:`tsfdi.SPRT.calibrate`); ``sprt.scale_ = h``, so that the scaled walk satisfies
        :math:`E[e^{S_n}] \approx 1`. (2) The scaled walk is run restarted at its lower bound only; each complete
        cycle has a maximum :math:`M_i`, and an alarm at level :math:`a` is a cycle with :math:`M_i \ge a`. The
        tail of the maxima is fitted as in the exponential tail above: :math:`u` the 21st highest maximum of all
        records, the :math:`n_u = 20` above it, mean excess :math:`\hat\beta` (:math:`\hat\beta = 1` for Wald's
        identity without overshoot; bursts of a non-stationary error give more). (3) The between-log effect: logs
        differ (each standardises its errors by its own variance at arming), so the records' walks have their own
        exponents; :math:`\hat h_j` (step 1 on record :math:`j` alone, relative to the pooled walk) gives
        :math:`\ln \hat h_j`, taken as normal over logs with mean and spread :math:`s` estimated from the
        :math:`J` records (at least three; a record with fewer than 320 armed samples, too few for its own exponent,
        is left out of this step only, named in a ``TsfdiWarning``: it is left out by its length, not its values,
        and its samples stay in steps 1-2 with its hours; a record whose :math:`z` grows on average is refused when
        by at least two standard errors of its mean (long-run variance), and otherwise, its small exponent not
        estimable, enters as a value known only to lie below the exponent of its :math:`z` lowered by two standard
        errors -- left-censored, :math:`s` then the normal maximum-likelihood estimate times
        :math:`\sqrt{J/(J-1)}` -- named in a ``TsfdiWarning``), and a new log's relative exponent
        :math:`r = e^{s\sqrt{1 + 1/J}\, T}`, :math:`T \sim t_{J-1}` (the predictive law: the spread and its
        estimation from few logs). A new log with exponent :math:`r` raises, above :math:`u + x`, on average
        :math:`\rho(x, r) = \frac{n_u + 1}{H}\big(1 + \frac{x r}{n_u\hat\beta}\big)^{-n_u}` alarms per flight hour
        (:math:`H` the healthy flight hours, all pairs; the Gamma law of :math:`\hat\beta` averaged over as in the
        exponential tail). The threshold :math:`a = u + x` solves :math:`E_r[\rho(x, r)] = \rho` (400 quantile
        nodes of :math:`T`; a threshold below :math:`u`, for a rate above the healthy logs' top 21 cycles, takes
        :math:`r = 1`): the expected false-alarm rate of a new healthy log like the healthy ones equals
        ``false_alarms_per_hour`` -- a predictive mean, not a bound, so over many logs the count falls on both
        sides of it. ``calibration_.rate_band`` gives the 5 %, 50 % and 95 % quantiles of :math:`\rho(x, r)`
        over :math:`r` (how far a single new log's rate may lie from the stated mean; right-skewed, the median
        below it). The rate is per flight hour, arming phases included, as for the other statistics. What it
        counts are the cycles of the walk restarted at its lower bound only (as calibrate runs it) that reach the
        threshold; a log's first alarm is the first of them. A detector that does not freeze restarts its walk at 0
        after every alarm and may alarm again within the same burst of large errors, before the walk would have
        returned to its lower bound: :meth:`OnlineDetection.false_alarms_per_hour` counts those alarms too, so its
        episodes exceed the stated rate (by 1-7 % in the Monte Carlo of ``tests/test_online_sprt.py`` at 60 per
        hour). That Monte Carlo (the defaults on two ARX pairs at 50 Hz): calibrated 100 times on three 30 s logs
        for 60 per hour, 1,000 new 30 s logs had 62.6 restart cycles per hour reach the threshold (two-sided 99 %
        binomial band 53-67) and raised 63.0 alarm episodes per hour without freezing.

        With the GLRT on, an alarm of either source is an alarm of the pair. Both sources are set at the level
        of one common rate of their own, :math:`\rho_s \in [\rho/2, \rho]` (at :math:`\rho/2` the union bound
        caps the combined rate at :math:`\rho`). For :math:`K \ge 5` the episodes of the combined alarm are
        counted: with each source at its empirical level for :math:`\rho_s` (the interpolation above, defined
        down to one episode), :math:`R_m` is the largest :math:`\rho_s` whose combined alarm has fewer than
        :math:`m` episodes on the healthy runs (bisection), and :math:`\rho_s` interpolates
        :math:`R_{\lceil K\rceil}` and :math:`R_{\lfloor K\rfloor}` log-linearly as :math:`D_m` above. For
        :math:`K < 5`, :math:`\rho_s = \rho/2` and each source is extrapolated by its own tail fit (which needs
        :math:`K/2 \ge 1`).

        The rate is that of the detector without freezing, the statistic's distribution in normal operation
        (for ``statistic="sprt"``: of its restart cycles, above). With ``freeze_on_alarm=True`` (the default) the
        first alarm of a healthy run comes at that rate (nothing is frozen before it): a run of :math:`T` hours
        alarms with probability about :math:`1 - e^{-\rho T}`. The later episodes of that pair are not: its model
        stays frozen where a false alarm caught it, often with its parameters off, and may keep alarming (with
        ``"mean"`` often many times), as after a fault. With one threshold for all pairs, pairs whose statistics
        differ in scale (``"mean"`` in the units of each ``y``) share the rate unevenly.

        References
        ----------
        Hansen, Blanke, Adrian, *A Framework for Rapid Diagnosis of Critical Faults in UAVs* (paper 002),
        section 3 and Fig. 2; S. Coles, *An Introduction to Statistical Modeling of Extreme Values*, Springer
        2001, chapters 4 (threshold excesses) and 5 (dependent sequences, declustering).
        """
        rate = float_like(false_alarms_per_hour, "false_alarms_per_hour", minimum=0.0, strict_min=True)
        fs = float_like(fs, "fs", minimum=0.0, strict_min=True, optional=True)
        ys, us = self._runs(y_runs, "y_runs"), self._runs(u_runs, "u_runs")
        if len(ys) != len(us):
            raise ValueError(f"y_runs and u_runs must hold the same number of runs, got {len(ys)} and {len(us)}")
        if self.statistic == "sprt":
            return self._calibrate_sprt(ys, us, rate, fs)
        sep = np.array([np.nan])
        s_parts: list = []
        g_parts: list = []
        hours = 0.0
        for i, _, out, n, f in self._healthy_runs(ys, us, fs, stacklevel=3):
            hours += n / f / _SECONDS_PER_HOUR
            live = (np.arange(n) >= self.arm_after)[:, None]
            stat = np.asarray(out.statistic, dtype=float).reshape(n, -1)
            if self.statistic == "zscore":
                stat = np.abs(stat)
            stat = np.where(live, stat, np.nan)
            g = np.where(live, np.asarray(out.glrt, dtype=float).reshape(n, -1), np.nan)
            for c in range(len(self.pairs)):
                s_parts += [stat[:, c], sep]
                g_parts += [g[:, c], sep]
        k_target = rate * hours
        sources = {self.statistic: _Upcrossings(np.concatenate(s_parts), hours)}
        if self.glrt is not None:
            sources["glrt"] = _Upcrossings(np.concatenate(g_parts), hours)

        def explain(source: str, reason: str, rho: float) -> ValueError:
            where = f"{hours:.3g} healthy hours ({len(ys)} run(s))"
            if reason == "rate":
                return ValueError(f"false_alarms_per_hour={rate:g} is more than the {source} statistic raises on the "
                                  f"{where} at any threshold: require fewer false alarms")
            if reason == "hours":
                return ValueError(f"false_alarms_per_hour={rate:g} cannot be supported by {where}: at least "
                                  f"{_MIN_EXTRAPOLATED / rho:.3g} healthy hours are needed (exponential tail fit; "
                                  f"{_MIN_EMPIRICAL / rate:.3g} for an empirical estimate)")
            return ValueError(f"false_alarms_per_hour={rate:g}: the {source} statistic has fewer than "
                              f"{_MIN_TAIL_EPISODES} alarm episodes above any level on the {where}, too few for a "
                              f"tail fit; at least {_MIN_EMPIRICAL / rate:.3g} healthy hours are needed for an "
                              f"empirical estimate")

        def level(source: str, rho: float) -> tuple[float, str, dict]:
            try:
                return sources[source].level(rho)
            except _TooShort as err:
                raise explain(source, err.args[0], rho) from None

        xs = {name: np.nan_to_num(up.x, nan=-np.inf) for name, up in sources.items()}

        def episodes(thresholds: dict) -> int:
            above = np.zeros(next(iter(xs.values())).shape, dtype=bool)
            for name, t in thresholds.items():
                above |= xs[name] > t
            return int(np.count_nonzero(above[1:] & ~above[:-1]) + above[0])

        def at(rho: float) -> dict:
            return {name: level(name, rho) for name in sources}

        if len(sources) == 1:
            rho, fitted = rate, at(rate)
        elif k_target < _MIN_EMPIRICAL:
            rho = rate / 2.0                               # union bound, each source from its own tail fit
            fitted = at(rho)
        else:
            # the combined alarm's episodes counted: both sources at their empirical level of a common rate
            # r in [rate / 2, rate]; R_m = the largest r with fewer than m episodes, interpolated as D_m
            def empirical(r: float) -> dict:
                out = {}
                for name, up in sources.items():
                    try:
                        out[name] = up.empirical(r * hours)
                    except _TooShort as err:
                        raise explain(name, err.args[0], r) from None
                return out

            def boundary(m: int) -> float:
                lo, hi = rate / 2.0, rate
                if episodes(empirical(hi)) < m:
                    return hi
                if episodes(empirical(lo)) >= m:
                    return lo
                for _ in range(30):
                    mid = np.sqrt(lo * hi)
                    lo, hi = (mid, hi) if episodes(empirical(mid)) < m else (lo, mid)
                return lo

            m0, m1 = int(np.ceil(k_target)), int(np.floor(k_target))
            r0, r1 = boundary(m0), boundary(m1)
            frac = (np.log(m0) - np.log(k_target)) / (np.log(m0) - np.log(m1)) if m0 > m1 else 0.0
            rho = float(np.exp(np.log(r0) + frac * (np.log(r1) - np.log(r0))))
            fitted = {name: (t, "empirical", {}) for name, t in empirical(rho).items()}
        thresholds = {name: v[0] for name, v in fitted.items()}
        for name, t in thresholds.items():
            if not t > 0:
                raise ValueError(f"false_alarms_per_hour={rate:g} needs a {name} threshold of {t:.4g}, not positive: "
                                 f"require fewer false alarms")
        t = thresholds[self.statistic]
        self.threshold = t
        self._options["threshold"] = t
        if self.statistic == "zscore":
            for m in self._models:
                m.threshold = t
        gamma = thresholds.get("glrt")
        if gamma is not None:
            glrt = copy.copy(self.glrt)
            glrt.threshold = gamma
            self.glrt = glrt
            self._options["glrt"] = glrt
        self.calibration_ = OnlineCalibration(
            false_alarms_per_hour=rate, healthy_hours=hours, runs=len(ys), threshold=t, glrt_threshold=gamma,
            estimator=next(iter(fitted.values()))[1], source_rates={name: rho for name in sources},
            expected_episodes=k_target, healthy_episodes=episodes(thresholds),
            tail={name: v[2] for name, v in fitted.items() if v[2]})
        self.reset()
        return self

    def _healthy_runs(self, ys: list, us: list, fs: float | None, *, stacklevel: int):
        """Each healthy run through a copy of the detector that never freezes: ``(i, copy, detection, samples,
        sampling frequency)``; its errors and warnings name the run (warnings at ``stacklevel`` from here: the user's
        call), and a run without a time index needs ``fs``."""
        for i, (y, u) in enumerate(zip(ys, us)):
            free = self._alarm_free_copy()
            try:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always", ConvergenceWarning)
                    out = free.run(y, u)
            except (ValueError, TypeError) as err:
                raise type(err)(f"healthy run {i}: {err}") from err
            for w in caught:
                warnings.warn(f"healthy run {i}: {w.message}", w.category, stacklevel=stacklevel)
            f = fs if fs is not None else out.fs
            if f is None:
                raise ValueError(f"fs (sampling frequency in Hz) is needed: healthy run {i} carries no time index")
            n = out.alarm.shape[0]
            yield i, free, out, n, f

    def _calibrate_sprt(self, ys: list, us: list, rate: float, fs: float | None) -> OnlineDetector:
        """:meth:`calibrate` of ``statistic="sprt"`` (see its Notes)."""
        records, hours = [], 0.0
        for i, free, out, n, f in self._healthy_runs(ys, us, fs, stacklevel=4):
            hours += n / f / _SECONDS_PER_HOUR
            resid = np.asarray(out.resid, dtype=float).reshape(n, -1)
            for c, walk in enumerate(free._walks):
                armed = int(free._armed_at[c])
                if armed < 0:
                    continue
                # the errors standardised as the walk saw them, from its arming on (its state at arming)
                w = free._standardise(resid[armed:, c], free._armed_walk(walk[0], walk[1], 0))[0]
                w = w[max(self.arm_after - armed, 0):]
                w = w[np.isfinite(w)]
                records.append((i, self.pairs[c], w, f))
        if len(records) < _MIN_SPRT_RECORDS:
            raise ValueError(f"statistic='sprt' is calibrated from at least {_MIN_SPRT_RECORDS} armed (run, pair) "
                             f"records, the healthy runs give {len(records)}: give more healthy runs (or longer ones, "
                             f"so that the pairs arm)")
        base = copy.copy(self.sprt)
        base.scale_ = 1.0
        # (a pair armed at or after its run's end has no sample: left out of the spread below, by name)
        zs = [base.loglik_ratio(w, 1.0) if w.size else np.empty(0) for _, _, w, _ in records]
        rates = [f for *_, f in records]
        h = _wald_exponent(np.concatenate(zs), "the healthy runs")
        sprt = copy.copy(base)
        sprt.scale_ = h                              # the scaled walk has Wald's exponent 1
        lower = sprt.lower
        walks = [(_cycle_maxima(h * z, lower), z.size / f_rec / _SECONDS_PER_HOUR) for z, f_rec in zip(zs, rates)]
        cycles = sum(m.size for m, _ in walks)
        if cycles < _MIN_SPRT_CYCLES:
            raise ValueError(f"the SPRT walk returned to its lower bound {cycles} times on the healthy runs, at "
                             f"least {_MIN_SPRT_CYCLES} are needed: give longer healthy runs (or check that they are "
                             "healthy)")

        # the tail of the cycle maxima of all records: base level u (the 21st highest), mean excess beta
        m = np.sort(np.concatenate([mx for mx, _ in walks]))
        n_u = _TAIL_EPISODES
        u = float(m[-n_u - 1])
        beta = float(np.mean(m[-n_u:] - u))
        # the between-log effect: each record's own Wald exponent relative to the pooled one (1 after scaling);
        # its log over records is normal, a new log's is predicted by Student's t (mean and spread estimated). A
        # record too short for its own exponent is left out of the spread only (by its length, not its values: no
        # selection), named in a warning; its samples stay in the pooled walk and the tail above, with its hours. A
        # record whose ratio grows on average, not significantly, is kept as a left-censored exponent (warned)
        exps, below, short = [], [], []
        for (i, pair, _, _), z in zip(records, zs):
            where = f"healthy run {i}, pair {pair!r}"
            if z.size < _MIN_EXPONENT_SAMPLES:
                short.append(f"{where} ({z.size})")
                continue
            drift, se = _mean_se(h * z)
            if drift >= 0:
                if drift >= _DRIFT_SE * se:
                    raise ValueError(f"{where}: the SPRT's log-likelihood ratio grows on average ({drift:.4g} per "
                                     f"sample, {drift / se:.3g} standard errors) on a healthy run: the prediction "
                                     "errors are not the healthy law it assumes")
                # not significantly: its exponent is small, known only to lie below that of its mean at -2 se
                below.append((where, drift / se, _wald_exponent(h * z - _DRIFT_SE * se, where)))
                continue
            try:
                exps.append(_wald_exponent(h * z, where))
            except ValueError as err:
                raise ValueError(f"{err} (statistic='sprt' estimates the spread of the healthy logs from every "
                                 "armed record long enough for its own exponent)") from None
        if short:
            what = (f"armed (run, pair) record(s) with fewer than {_MIN_EXPONENT_SAMPLES} armed samples, too few for "
                    f"their own Wald exponent: {', '.join(short)}")
            if len(exps) < _MIN_SPRT_RECORDS:
                raise ValueError(f"statistic='sprt' estimates the spread between healthy logs from at least "
                                 f"{_MIN_SPRT_RECORDS} records of at least {_MIN_EXPONENT_SAMPLES} armed samples, "
                                 f"the healthy runs give {len(exps)} (the other {what}): give longer healthy runs")
            warnings.warn(f"{len(short)} {what} -- left out of the spread between logs, which {len(exps) + len(below)} "
                          f"of the {len(records)} records give (their samples still count in the pooled walk and its "
                          "tail)", TsfdiWarning, stacklevel=3)
        if below:
            if len(exps) < _MIN_SPRT_RECORDS:
                raise ValueError(f"statistic='sprt' needs at least {_MIN_SPRT_RECORDS} records whose log-likelihood "
                                 f"ratio falls on average, the healthy runs give {len(exps)}: give longer healthy runs")
            warnings.warn(f"{len(below)} armed (run, pair) record(s) whose SPRT log-likelihood ratio grows on average, "
                          f"though by less than {_DRIFT_SE:g} standard errors: "
                          + ", ".join(f"{w} ({t:.2g} standard errors)" for w, t, _ in below)
                          + " -- each taken in the spread between logs as an exponent known only to lie below that of "
                          f"its mean at -{_DRIFT_SE:g} standard errors (censored), which raises the threshold",
                          TsfdiWarning, stacklevel=3)
        log_h = np.log(exps)
        n_rec = log_h.size + len(below)
        sd = _censored_sd(log_h, np.log([c for *_, c in below]))
        spread = sd * np.sqrt(1.0 + 1.0 / n_rec)
        rel = np.exp(spread * stats.t.ppf((np.arange(_SPRT_NODES) + 0.5) / _SPRT_NODES, n_rec - 1))

        def per_hour(x: float, r: np.ndarray) -> np.ndarray:
            """Alarms per flight hour at ``u + x`` of a new log with relative exponent ``r``, averaged over the
            estimate of the mean excess (Gamma): n_u + 1 cycles above u on the healthy hours on average (below u,
            x < 0, the pooled tail alone: the spread between logs is that of the tail beyond u)."""
            return (n_u + 1.0) / hours * (1.0 + x * (r if x >= 0 else 1.0) / (n_u * beta)) ** -n_u * np.ones_like(r)

        x_min = -n_u * beta * (1.0 - 1e-12)
        x = optimize.brentq(lambda v: np.log(per_hour(v, rel).mean()) - np.log(rate), x_min,
                            1e3 * (abs(u) + n_u * beta), rtol=1e-12)
        a = u + float(x)
        if not a > 0:
            raise ValueError(f"false_alarms_per_hour={rate:g} needs an SPRT threshold of {a:.4g}, not positive: "
                             "require fewer false alarms")
        band = np.quantile(per_hour(x, rel), _SPRT_BAND)
        self.threshold = a
        self._options["threshold"] = a
        self.sprt = sprt
        self._options["sprt"] = sprt
        self.calibration_ = OnlineCalibration(
            false_alarms_per_hour=rate, healthy_hours=hours, runs=len(ys), threshold=a, glrt_threshold=None,
            estimator="sprt cycle maxima", source_rates={"sprt": rate}, expected_episodes=rate * hours,
            healthy_episodes=int(sum((m >= a).sum() for m, _ in walks)),
            tail={"sprt": {"u": u, "n_u": n_u, "beta": beta, "log_exponent_sd": sd}},
            rate_band=tuple(float(b) for b in band), sprt_scale=h)
        self.reset()
        return self

    @property
    def first_alarms(self) -> pd.DataFrame:
        """First alarm of every pair so far (see :class:`OnlineDetection`)."""
        return pd.DataFrame({"position": self._first.copy(), "time": pd.Series(list(self._time), dtype=object),
                             "source": [s or None for s in self._source], "armed_at": self._armed_at.copy()},
                            ).set_axis(pd.Index(self.pairs, name="pair"))

    def _result(self, sy: Any, Z, G, E, A, S, starts) -> OnlineDetection:
        fa = self.first_alarms
        hit = fa[fa["position"] >= 0]
        if len(hit):
            j = int(np.argmin(hit["position"].to_numpy()))
            first, first_time, pair = int(hit["position"].iloc[j]), hit["time"].iloc[j], hit.index[j]
        else:
            first, first_time, pair = None, None, None
        names = list(self.pairs)
        return OnlineDetection(pairs=self.pairs,
                               zscore=sy.wrap(Z, 0, channels=names, vector=True),
                               glrt=sy.wrap(G, 0, channels=names, vector=True),
                               resid=sy.wrap(E, 0, channels=names, vector=True),
                               alarm=A, first_alarms=fa, first_alarm=first, first_alarm_time=first_time,
                               first_alarm_pair=pair,
                               statistic=sy.wrap(S, 0, channels=names, vector=True), alarm_start=starts,
                               fs=sampling_frequency(sy))

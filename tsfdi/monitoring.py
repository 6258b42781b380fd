"""Online monitoring of signal streams.

:class:`OnlineDetector` runs several (output, input) signal pairs at once, each through a recursive ARX model
with the stability gate, Welford running variance and Z-score alarms of Keipour et al. (paper 001) and a
streaming GLRT on the same prediction errors (Hansen et al., paper 002), and reports the first alarm of every
pair and of the whole system with time stamps.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import as_signal
from tsfdi._validation import float_like, int_like, option
from tsfdi.detection.glrt import GLRT
from tsfdi.models.recursive import RecursiveARX

__all__ = ["OnlineDetector", "OnlineDetection", "Monitor", "MonitorResult", "MonitorEvent", "window_statistics",
           "rolling_variance", "RULES"]


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
        (index label, None if none), ``source`` ("zscore", "mean", "glrt", or two joined by "+"), ``armed_at``
        (position where the GLRT was armed / the variance became stable, -1 if not yet).
    first_alarm : int or None
        Earliest alarm position over all pairs (since the detector started).
    first_alarm_time : object or None
        Its index label (position for numpy input).
    first_alarm_pair : str or None
        The pair that raised it first (ties: the first pair in order).
    statistic : ndarray, DataFrame or DataArray, shape (nobs, n_pairs)
        The detection statistic compared with ``threshold``: the Z-score (``statistic="zscore"``; the alarm is
        on its absolute value) or the direction-signed moving average of the prediction errors
        (``statistic="mean"``), NaN where undefined.
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


class OnlineDetector:
    """Online anomaly detection on several commanded / measured (input / output) signal pairs at once.

    Every pair gets its own :class:`tsfdi.RecursiveARX` (same orders and options for all pairs). Its a-priori
    prediction errors feed one of two detection statistics:

    - ``statistic="zscore"`` (paper 001): the model's own Z-score against the Welford mean and variance, armed
      once the model and the error variance are stable; ``threshold`` is in standard deviations (4.5);
    - ``statistic="mean"``: the moving average of the last ``window`` prediction errors, compared with
      ``threshold`` in the units of ``y`` (a finite-moving-average change detector). ``direction`` makes it
      one-sided: "down" alarms when the average falls below ``-threshold`` (e.g. a loss of thrust in the
      longitudinal specific force), "up" above ``+threshold``, "both" on the absolute value.

    Optionally a streaming :class:`tsfdi.detection.GLRT` runs on the same errors once the variance is stable
    (its ``sigma`` is the Welford standard deviation at arming, its input the error minus the Welford mean at
    arming). No alarm of any source is raised among the first ``arm_after`` samples (baseline phase).

    Parameters
    ----------
    pairs : int or sequence of str
        Number of pairs or their names.
    na, nb, nk : int
        ARX orders (see :class:`tsfdi.RecursiveARX`), defaults 2, 2, 0.
    forgetting_factor : float, default 0.995
    threshold : float, default 4.5
        Alarm threshold of ``statistic`` (standard deviations for "zscore", units of ``y`` for "mean").
    glrt : GLRT or None, default ``GLRT(window=20, alpha=1e-6)`` for "zscore", None for "mean"
        The GLRT whose window and threshold are used for every pair (its ``sigma`` is replaced per pair);
        ``None`` disables the GLRT.
    halt_on_alarm : bool, default True
        Freeze a pair's model from its first alarm of ``statistic`` on (paper 002), so the model does not learn
        the fault; the alarmed sample itself does not enter the model.
    nonfinite : {"skip", "raise"}, default "skip"
        Policy for NaN / inf samples (see :class:`tsfdi.RecursiveARX`); skipped samples are not fed to the GLRT
        and make the moving average undefined while they are in its window.
    n_inputs : int, default 1
        Inputs per pair; ``u`` then has ``n_pairs * n_inputs`` columns, pair by pair (the inputs of pair 0
        first).
    statistic : {"zscore", "mean"}, default "zscore"
    window : int, default 20
        Length of the moving average (``statistic="mean"``).
    direction : {"both", "down", "up"}, default "both"
        Side of the moving-average test.
    arm_after : int, default 0
        Length of the baseline phase in samples (counted from the first sample given to the detector).
    **rls_options
        Further :class:`tsfdi.RecursiveARX` options: ``P0``, ``trend``, ``eps``, ``stable_samples``,
        ``variance_tol``, ``min_variance_samples``.

    Notes
    -----
    Feeding a stream in blocks (:meth:`run`) or sample by sample (:meth:`update`) gives the same alarms.

    The moving average of the a-priori errors over ``w`` samples, ``m(k) = (1/w) sum_{i=k-w+1}^{k} e(i)``, is
    the finite-moving-average detector of a change in mean; for independent Gaussian errors it is the GLRT of
    a jump of known length ``w`` (paper 002, eq. 3 with ``n = w``). Its threshold is in physical units, which
    makes it usable on real records whose error distribution is heavy-tailed and non-stationary, where a
    single-sample Z-score against a running variance raises false alarms.

    References
    ----------
    Keipour, Mousaei, Scherer, ICRA 2019 (paper 001), sections IV-V; Hansen, Blanke, Adrian (paper 002),
    eqs. 1-3 and 14-16; M. Basseville, I. Nikiforov, *Detection of Abrupt Changes*, 1993, section 2.1.
    """

    def __init__(self, pairs: Any, *, na: int = 2, nb: int = 2, nk: int = 0, forgetting_factor: float = 0.995,
                 threshold: float = 4.5, glrt: Any = "default", halt_on_alarm: bool = True,
                 nonfinite: str = "skip", n_inputs: int = 1, statistic: str = "zscore", window: int = 20,
                 direction: str = "both", arm_after: int = 0, **rls_options: Any) -> None:
        if isinstance(pairs, (int, np.integer)) and not isinstance(pairs, bool):
            n = int_like(pairs, "pairs", minimum=1)
            names = tuple(f"pair{i}" for i in range(n))
        elif isinstance(pairs, (list, tuple)) and pairs and all(isinstance(p, str) for p in pairs):
            names = tuple(pairs)
            if len(set(names)) != len(names):
                raise ValueError(f"pairs must have distinct names, got {names}")
        else:
            raise TypeError(f"pairs must be a positive int or a non-empty sequence of names, got {pairs!r}")
        self.pairs = names
        self.threshold = float_like(threshold, "threshold", minimum=0.0, strict_min=True)
        self.nonfinite = option(nonfinite, "nonfinite", ("skip", "raise"))
        self.statistic = option(statistic, "statistic", ("zscore", "mean"))
        self.window = int_like(window, "window", minimum=1)
        self.direction = option(direction, "direction", ("both", "down", "up"))
        self.arm_after = int_like(arm_after, "arm_after", minimum=0)
        self.n_inputs = int_like(n_inputs, "n_inputs", minimum=1)
        if not isinstance(halt_on_alarm, (bool, np.bool_)):
            raise TypeError(f"halt_on_alarm must be a bool, got {halt_on_alarm!r}")
        self.halt_on_alarm = bool(halt_on_alarm)
        if isinstance(glrt, str) and glrt == "default":
            glrt = GLRT(window=20, alpha=1e-6) if self.statistic == "zscore" else None
        if glrt is not None and not isinstance(glrt, GLRT):
            raise TypeError(f"glrt must be a tsfdi.detection.GLRT or None, got {type(glrt).__name__}")
        self.glrt = glrt
        zs = self.statistic == "zscore"
        # in "mean" mode the model's own Z-score never alarms (threshold 1e300) and halting is done here
        self._models = [RecursiveARX(na, nb, nk, forgetting_factor, n_inputs=self.n_inputs,
                                     threshold=self.threshold if zs else 1e300,
                                     halt_on_alarm=self.halt_on_alarm and zs, nonfinite=self.nonfinite,
                                     arm_after=self.arm_after if zs else 0, **rls_options)
                        for _ in names]
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
        self._stat_alarmed = np.zeros(k, dtype=bool)
        self._nobs = 0

    @property
    def models(self) -> tuple:
        """The per-pair :class:`tsfdi.RecursiveARX` estimators (read their state, do not feed them)."""
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
        return sy, su

    def _mean_statistic(self, c: int, e: np.ndarray) -> np.ndarray:
        """Direction-signed moving average of the errors of pair ``c`` continuing its tail (not updated)."""
        w1 = self.window - 1
        m = _moving_average(np.concatenate([self._tail[c], e]), self.window)[w1:]
        if self.direction == "down":
            return -m
        if self.direction == "both":
            return np.abs(m)
        return m

    def _run_mean(self, c: int, m: RecursiveARX, yc: np.ndarray, uc: np.ndarray, start: int):
        """Run pair ``c`` in "mean" mode, freezing its model at the first alarm (exactly as sample by sample)."""
        n = yc.shape[0]
        snap = None
        if self.halt_on_alarm and not self._stat_alarmed[c]:
            snap = (m.theta_.copy(), m.P_.copy(), m._ybuf.copy(), m._ubuf.copy(), m._ist.copy(), m._fst.copy())
        res = m.run(yc, uc)
        e = np.asarray(res.resid, dtype=float)
        stat = self._mean_statistic(c, e)
        pos = start + np.arange(n)
        hit = np.flatnonzero((np.nan_to_num(stat, nan=-np.inf) > self.threshold) & (pos >= self.arm_after))
        results = [res]
        if snap is not None and hit.size:
            i = int(hit[0])
            m.theta_[:], m.P_[:], m._ybuf[:], m._ubuf[:], m._ist[:], m._fst[:] = snap
            parts = [m.run(yc[:i], uc[:i])] if i > 0 else []
            m.freeze()
            parts.append(m.run(yc[i:], uc[i:]))
            e = np.concatenate([np.asarray(p.resid, dtype=float) for p in parts])
            stat = self._mean_statistic(c, e)
            results = parts
        if hit.size:
            self._stat_alarmed[c] = True
        w1 = self.window - 1
        if w1:
            self._tail[c] = np.concatenate([self._tail[c], e])[-w1:]
        alarm = (np.nan_to_num(stat, nan=-np.inf) > self.threshold) & (pos >= self.arm_after)
        z = np.concatenate([np.asarray(p.zscore, dtype=float) for p in results])
        vstable = np.concatenate([p.variance_stable for p in results])
        var = np.concatenate([np.asarray(p.variance, dtype=float) for p in results])
        mean = np.concatenate([np.asarray(p.mean, dtype=float) for p in results])
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
        """
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
                res = m.run(yc, uc[:, 0] if ni == 1 else uc)
                e = np.asarray(res.resid, dtype=float)
                z = np.asarray(res.zscore, dtype=float)
                stat, zal = z, res.alarm.copy()
                vstable = res.variance_stable
                var = np.asarray(res.variance, dtype=float)
                mean = np.asarray(res.mean, dtype=float)
            else:
                e, z, stat, zal, vstable, var, mean = self._run_mean(c, m, yc, uc, start)
            Z[:, c] = z
            E[:, c] = e
            S[:, c] = stat
            gal = np.zeros(n, dtype=bool)
            if self.glrt is not None:
                # the GLRT is armed from the sample after the variance became stable
                if self._streams[c] is None:
                    vs = np.flatnonzero(vstable)
                    if vs.size:
                        arm = int(vs[0]) + 1
                        self._streams[c] = (self.glrt.stream(1, sigma=np.sqrt(var[vs[0]])), float(mean[vs[0]]))
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
                        g = stream.extend(seg[ok])
                        idx = np.flatnonzero(ok) + lo
                        G[idx, c] = g
                        gal[idx] = g > stream.threshold
                gal &= pos >= self.arm_after
            elif self._armed_at[c] < 0:
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
        return self._result(sy, Z, G, E, A, S)

    def update(self, y: Any, u: Any) -> np.ndarray:
        """Process one sample of every pair; returns the per-pair alarm flags (bool array)."""
        yv = np.atleast_1d(np.asarray(y, dtype=np.float64)).reshape(1, -1)
        uv = np.atleast_1d(np.asarray(u, dtype=np.float64)).reshape(1, -1)
        return self.run(yv, uv).alarm[0]

    @property
    def first_alarms(self) -> pd.DataFrame:
        """First alarm of every pair so far (see :class:`OnlineDetection`)."""
        return pd.DataFrame({"position": self._first.copy(), "time": pd.Series(list(self._time), dtype=object),
                             "source": [s or None for s in self._source], "armed_at": self._armed_at.copy()},
                            ).set_axis(pd.Index(self.pairs, name="pair"))

    def _result(self, sy: Any, Z, G, E, A, S) -> OnlineDetection:
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
                               statistic=sy.wrap(S, 0, channels=names, vector=True))


# =====================================================================================================================
# Monitor: sliding windows -> detection with the healthy model -> steady-state check -> identification
# (Dutta et al., paper 003, Fig. 3 and the Fig. 7 discussion).
# =====================================================================================================================

#: Decision rules of :class:`Monitor` and :func:`tsfdi.evaluate`. ``"paper"``: a model is accepted when its residual
#: test does not reject; one accepted model is an identification, several are ambiguous, none is no decision
#: (Dutta et al.). ``"likelihood"``: among the accepted models (all models when none is accepted) take the one whose
#: residuals have the largest Gaussian log-likelihood on the window (smallest log-determinant of the window's residual
#: covariance, on samples common to every model). ``"pvalue"``: the same with the largest signal-level p-value
#: (the smallest channel p-value of each model).
RULES = ("paper", "likelihood", "pvalue")


def _seconds_to_samples(value: Any, name: str, fs: float, minimum: int = 1) -> int:
    v = float_like(value, name, minimum=0.0, strict_min=True)
    n = int(round(v * fs))
    if n < minimum:
        raise ValueError(f"{name} = {v} s is {n} sample(s) at fs = {fs} Hz; at least {minimum} are needed")
    return n


def rolling_variance(signal: Any, window: int, step: int = 1) -> np.ndarray:
    """Variance of every channel over sliding windows (Dutta et al., Fig. 7).

    Parameters
    ----------
    signal : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, k)
    window : int
        Window length in samples.
    step : int
        Samples between window starts.

    Returns
    -------
    ndarray, shape (n_windows, k)
        Variance (``ddof=0``) of window ``w`` = samples ``[w * step, w * step + window)``, from prefix sums of the
        globally centred signal.
    """
    sig = as_signal(signal, "signal", allow_constant=True)
    window = int_like(window, "window", minimum=2)
    step = int_like(step, "step", minimum=1)
    return _rolling_variance(sig.values, window, step)


def _rolling_variance(x: np.ndarray, window: int, step: int) -> np.ndarray:
    n_all = x.shape[0]
    if window > n_all:
        raise ValueError(f"window must be <= the signal length {n_all}, got {window}")
    x = x - x.mean(axis=0)
    zero = np.zeros((1, x.shape[1]))
    s1 = np.concatenate([zero, np.cumsum(x, axis=0)])
    s2 = np.concatenate([zero, np.cumsum(x * x, axis=0)])
    starts = np.arange(0, n_all - window + 1, step)
    m = (s1[starts + window] - s1[starts]) / window
    return np.maximum((s2[starts + window] - s2[starts]) / window - m * m, 0.0)


def _model_channels(res: Any, values: np.ndarray) -> np.ndarray:
    neqs = int(getattr(res, "neqs", 1))
    if neqs != values.shape[1]:
        raise ValueError(f"signal has {values.shape[1]} channel(s) but a model was fitted on {neqs}")
    e = res.residuals(values if neqs > 1 else values[:, 0])
    return np.asarray(e, dtype=np.float64).reshape(-1, neqs)


def _window_statistic(test: Any, e: np.ndarray, n: int, step: int, name: str, p: int,
                      reference: dict) -> np.ndarray | None:
    """Statistic of every window (``n`` residual samples, ``step`` apart) from prefix sums, or None when the test
    has no windowed form (then it is applied window by window)."""
    from tsfdi.detection.variance import FTest
    from tsfdi.detection.whiteness import LjungBox

    if isinstance(test, LjungBox) and test.multivariate is None:
        if n <= test.lags:
            raise ValueError(f"window must exceed lags + the model order ({test.lags} + {p}) for model "
                             f"{name!r}, got {n + p}")
    elif not (isinstance(test, FTest) and test.alternative == "greater"):
        return None
    return test.window_statistic(e, n, step, **reference)


def _members(what: str, res: Any) -> tuple:
    """The fitted models standing for one state (``what`` names the argument in errors): one result, or the
    members of a bank (a list or tuple)."""
    if isinstance(res, (list, tuple)):
        if not res:
            raise ValueError(f"{what} is an empty bank: give at least one fitted model")
        for r in res:
            if not hasattr(r, "residuals"):
                raise TypeError(f"{what} must hold fitted results, got {type(r).__name__}")
        if len({int(r.lags) for r in res}) > 1:
            raise ValueError(f"the members of the bank {what} must share one order, got lags "
                             f"{sorted({int(r.lags) for r in res})}")
        return tuple(res)
    if not hasattr(res, "residuals"):
        raise TypeError(f"{what} must be fitted results or a list of them (a bank), got "
                        f"{type(res).__name__}")
    return (res,)


def window_statistics(signal: Any, models: Mapping, test: Any, *, window: int, step: int = 1,
                      common: int | None = None) -> dict:
    r"""Residual test of every model on every sliding window of one record, all windows at once.

    The record is filtered once through each (fixed) model; the residuals of a signal window are a slice of the
    record's residuals (samples ``[s + p, s + W)`` of window ``[s, s + W)`` for an order-``p`` model), so every
    window's statistic comes from prefix sums: :func:`~tsfdi.detection.ljungbox_windows` for
    :class:`~tsfdi.LjungBox` (per channel), windowed sums of squares for :class:`~tsfdi.FTest`.

    Parameters
    ----------
    signal : array_like, DataFrame or DataArray, shape (nobs, k) or (nobs,)
    models : mapping
        Name -> fitted AR / VAR results with ``k`` channels, or a list of them of one order: a *bank* standing
        for one state by several models (e.g. one per fitting record, :meth:`tsfdi.Baselines.bank`). A bank
        accepts a window when any member accepts it; its decision on a window is that of its best member
        there (accepting before rejecting, then the largest smallest-channel p-value, then the smallest
        largest statistic-to-threshold ratio), and its likelihood score the largest of its members'.
    test : LjungBox, FTest or mapping
        Per-channel test (``LjungBox(multivariate=None)`` or ``FTest(alternative="greater")``); other tests
        are applied window by window through their ``test`` method. A mapping name -> test gives each model its
        own test (e.g. thresholds calibrated on that model's healthy residuals, ``threshold="empirical"``:
        the calibrated threshold and empirical p-values are used); the members of a bank share its test.
    window, step : int
        Window length and step in samples.
    common : int, optional
        Largest model order over which the likelihood score is aligned (default: the largest order in
        ``models``); the score of every model uses signal samples ``[s + common, s + W)``.

    Returns
    -------
    dict
        ``starts`` (n_windows,) window starts; and per model name arrays ``statistic``, ``pvalue``,
        ``channel_reject``, ``threshold`` (n_windows, k), ``reject`` and ``member`` (n_windows,: the bank
        member whose decision is reported, 0 for a single model) under ``"decisions"``;
        ``loglik`` (n_models, n_windows) Gaussian log-likelihood per sample of each model's residuals on the
        common samples with the window's own ML covariance, :math:`-\tfrac12(\ln\det\hat S + k\ln 2\pi + k)`.
    """
    sig = as_signal(signal, "signal", allow_constant=True)
    banks = _banks(models)
    return _window_statistics(sig.nobs, tuple(sig.channels), banks, _bank_residuals(banks, sig.values), test,
                              window=window, step=step, common=common)


def _banks(models: Mapping) -> dict:
    """Name -> tuple of fitted members (one for a single model), validated as :func:`window_statistics` needs."""
    if not isinstance(models, Mapping) or not models:
        raise TypeError("models must be a non-empty mapping name -> fitted results")
    return {name: _members(f"models[{name!r}]", res) for name, res in models.items()}


def _bank_residuals(banks: dict, x: np.ndarray) -> dict:
    """Residuals of the whole record ``x`` through every member with their prefix sums, name -> tuple of
    ``(e, c1, c2)``: ``e`` (nobs - p, k), ``c1`` and ``c2`` the cumulative sums of ``e`` and of its lag-0 products
    ``e_i e_j`` (leading zero row). Computed once per record, then shared by every window length and test of
    :func:`_window_statistics`."""
    out = {}
    for name, members in banks.items():
        out[name] = []
        for res in members:
            e = _model_channels(res, x)
            k = e.shape[1]
            c1 = np.concatenate([np.zeros((1, k)), np.cumsum(e, axis=0)])
            c2 = np.concatenate([np.zeros((1, k * k)), np.cumsum((e[:, :, None] * e[:, None, :]).reshape(-1, k * k),
                                                                 axis=0)])
            out[name].append((e, c1, c2))
    return out


def _window_statistics(nobs: int, channels: tuple, banks: dict, resid: dict, test: Any, *, window: int,
                       step: int = 1, common: int | None = None) -> dict:
    """:func:`window_statistics` of a record of ``nobs`` samples from validated ``banks`` and their residuals on
    it (:func:`_bank_residuals`)."""
    window = int_like(window, "window", minimum=2)
    step = int_like(step, "step", minimum=1)
    if window > nobs:
        raise ValueError(f"window must be <= the signal length {nobs}, got {window}")
    orders = {name: int(ms[0].lags) for name, ms in banks.items()}
    pmax = max(orders.values()) if common is None else int_like(common, "common", minimum=0)
    if window - pmax < 3:
        raise ValueError(f"window ({window}) must exceed the largest model order ({pmax}) by at least 3 samples")
    starts = np.arange(0, nobs - window + 1, step)
    nwin = starts.size
    decisions: dict = {}
    loglik = np.empty((len(banks), nwin))
    if isinstance(test, Mapping):
        missing = [name for name in banks if name not in test]
        if missing:
            raise ValueError(f"test is a mapping but has no test for the model(s) {missing}")
    for j, (name, members) in enumerate(banks.items()):
        p = orders[name]
        n = window - p
        test_j = test[name] if isinstance(test, Mapping) else test
        per = [_member_statistics(res, r, test_j, starts, n, step, name, p, pmax, window)
               for res, r in zip(members, resid[name])]
        stat, pv, thr, rej_c, ll = (np.stack([m[i] for m in per]) for i in range(5))
        acc = ~rej_c.any(axis=2)                                         # (members, n_windows)
        ratio = np.max(stat / np.where(thr > 0, thr, np.inf), axis=2)
        best = np.lexsort((-ratio, np.nan_to_num(pv.min(axis=2), nan=-1.0), acc), axis=0)[-1]
        w = np.arange(nwin)
        decisions[name] = {"statistic": stat[best, w], "pvalue": pv[best, w], "threshold": thr[best, w],
                           "channel_reject": rej_c[best, w], "reject": ~acc.any(axis=0), "member": best,
                           "nobs": n}
        loglik[j] = ll.max(axis=0)
    return {"starts": starts, "decisions": decisions, "loglik": loglik, "names": tuple(banks), "channels": channels}


def _member_statistics(res: Any, resid: tuple, test: Any, starts: np.ndarray, n: int, step: int, name: str,
                       p: int, pmax: int, window: int) -> tuple:
    """One fitted model with its record residuals and their prefix sums (:func:`_bank_residuals`) on every
    window: statistic, p-value, threshold, channel rejection (n_windows, k) and the likelihood score
    (n_windows,) of :func:`window_statistics`."""
    e, c1, c2 = resid
    nwin, k = starts.size, e.shape[1]
    ref = test.reference(res)
    stat = _window_statistic(test, e, n, step, name, p, ref)
    if stat is None:
        ds = [test.test(e[s:s + n], **ref) for s in starts]
        stat = np.array([d.statistic for d in ds]).reshape(nwin, k)
        pv = np.array([d.pvalue for d in ds]).reshape(nwin, k)
        thr = np.array([d.threshold for d in ds], dtype=float).reshape(nwin, -1)
        rej_c = np.array([d.channel_reject for d in ds]).reshape(nwin, -1)
    else:
        thr, pv = test._threshold_pvalue(stat, n, **ref)
        rej_c = stat > thr
    thr = np.broadcast_to(np.asarray(thr, dtype=float), rej_c.shape)
    # likelihood score on the common samples [s + pmax, s + W): residual rows [s + pmax - p, s + W - p)
    off = pmax - p
    m = window - pmax
    lo, hi = starts + off, starts + off + m
    mu = (c1[hi] - c1[lo]) / m
    cov = ((c2[hi] - c2[lo]) / m).reshape(nwin, k, k) - mu[:, :, None] * mu[:, None, :]
    sign, logdet = np.linalg.slogdet(cov)
    logdet = np.where(sign > 0, logdet, np.inf)
    return stat, pv, thr, rej_c, -0.5 * (logdet + k * np.log(2 * np.pi) + k)


def apply_rule(reject: np.ndarray, loglik: np.ndarray, pvalue: np.ndarray, rule: str = "paper") -> np.ndarray:
    """Label index per window from the per-model decisions (see :data:`RULES`).

    Parameters
    ----------
    reject : ndarray of bool, shape (n_models, n_windows)
        Whether each model's residual test rejects on each window.
    loglik : ndarray, shape (n_models, n_windows)
        Residual log-likelihood per sample of each model on each window (:func:`window_statistics`).
    pvalue : ndarray, shape (n_models, n_windows)
        Signal-level p-value of each model on each window (smallest channel p-value).
    rule : {"paper", "likelihood", "pvalue"}

    Returns
    -------
    ndarray of int, shape (n_windows,)
        Index of the identified model; ``-1`` no decision, ``-2`` ambiguous (``"paper"`` only).
    """
    rule = option(rule, "rule", RULES)
    reject = np.asarray(reject, dtype=bool)
    acc = ~reject
    nacc = acc.sum(axis=0)
    if rule == "paper":
        out = np.where(nacc == 1, np.argmax(acc, axis=0), np.where(nacc == 0, -1, -2))
        return out.astype(int)
    score = np.asarray(loglik if rule == "likelihood" else pvalue, dtype=float)
    score = np.where(np.isnan(score), -np.inf, score)
    masked = np.where(acc | (nacc == 0)[None, :], score, -np.inf)
    out = np.argmax(masked, axis=0).astype(int)
    out[~np.isfinite(masked.max(axis=0))] = -1
    return out


@dataclass(frozen=True)
class MonitorEvent:
    """One event of a :class:`Monitor`.

    Attributes
    ----------
    time : float
        Time in seconds from the start of the stream (the end of the window that produced the event).
    kind : {"detection", "steady", "identification"}
        Fault detected by the healthy model; post-failure steady state reached (rolling variances below the
        baseline thresholds); a window identified.
    label : str or None
        The identified model (identification events; ``None`` for an ambiguous or empty decision).
    status : str
        ``"fault"``, ``"steady"`` or the identification status ``"identified"``, ``"ambiguous"``, ``"none"``.
    accepted : tuple of str
        Models accepted by the residual test (identification events).
    window : tuple of float
        ``(start, end)`` time of the window in seconds.
    """

    time: float
    kind: str
    label: str | None = None
    status: str = ""
    accepted: tuple = ()
    window: tuple = ()


@dataclass(frozen=True, eq=False)
class MonitorResult:
    """Outcome of :meth:`Monitor.run`.

    Attributes
    ----------
    events : list of MonitorEvent
    windows : pandas.DataFrame
        One row per window: ``start``, ``end`` (s), ``detect_statistic`` (largest channel statistic/threshold
        ratio of the healthy model), ``detect_pvalue``, ``fault`` (healthy model rejects), ``phase`` ("healthy",
        "transient", "steady"), ``status``, ``label``, ``accepted``, and the rolling variance of every channel.
    detection_time, steady_time : float or None
        Time of the first detection / steady-state event.
    label : str or None
        Most frequent label over the identified windows (``None`` if none).
    """

    events: list
    windows: pd.DataFrame
    detection_time: float | None
    steady_time: float | None
    label: str | None

    def to_frame(self) -> pd.DataFrame:
        """The events as a ``DataFrame`` (one row per event)."""
        return pd.DataFrame([{"time": e.time, "kind": e.kind, "label": e.label, "status": e.status,
                              "accepted": ",".join(e.accepted), "window_start": e.window[0] if e.window else np.nan,
                              "window_end": e.window[1] if e.window else np.nan} for e in self.events],
                            columns=["time", "kind", "label", "status", "accepted", "window_start", "window_end"])

    def plot(self, ax: Any = None) -> Any:
        """Rolling variances against time with the steady-state thresholds and events (Dutta et al., Fig. 7)."""
        from tsfdi.plotting.monitoring import plot_monitor

        return plot_monitor(self, ax=ax)

    def __repr__(self) -> str:
        return (f"MonitorResult(windows={len(self.windows)}, events={len(self.events)}, detection_time="
                f"{self.detection_time}, steady_time={self.steady_time}, label={self.label!r})")


class Monitor:
    r"""Sliding-window fault detection and identification (Dutta et al., Fig. 3).

    Every window of ``window`` seconds, ``step`` seconds apart, goes through three phases:

    1. *healthy*: the window's residuals through the healthy ``baseline`` model are tested with
       ``detection_test``; the first rejection is a ``"detection"`` event at the window's end.
    2. *transient*: the rolling variance of every channel over ``steady_window`` seconds is compared with
       ``steady_thresholds`` (estimated in the baseline phase as the largest steady-state variances of the
       fault records, Fig. 7 discussion); the first variance window lying wholly after the detection with every
       channel below its threshold is a ``"steady"`` event.
    3. *steady*: every window starting at or after the start of that variance window is identified: its
       residuals through each fault model in ``models`` are tested with ``test``, and ``rule`` turns the
       decisions into a label (``"identification"`` event per window).

    Parameters
    ----------
    baseline : fitted results or list of them
        Healthy model :math:`M_0` (AR or VAR results), or a bank of healthy models (e.g. one per healthy
        fitting record, :meth:`tsfdi.Baselines.bank`): the window is healthy when any member accepts it
        (:func:`window_statistics`).
    models : mapping
        Name -> fitted fault models :math:`M_1, M_2, \dots` (or banks), with the baseline's channels.
    window : float
        Window length in seconds (samples when ``fs = 1``).
    step : float
        Seconds between window starts (default: 1 s as in the paper, at least one sample).
    fs : float
        Sampling frequency in Hz.
    test : ResidualTest or mapping, optional
        Identification test, :class:`~tsfdi.LjungBox` (default ``LjungBox(lags=25, alpha=1e-3)``) or
        :class:`~tsfdi.FTest`; or a mapping model name -> test (each fault model with its own calibrated
        thresholds, ``threshold="empirical"``; then ``detection_test`` is required).
    detection_test : ResidualTest, optional
        Detection test on the healthy model's residuals (default: ``test``).
    steady_thresholds : array_like, shape (k,), optional
        Rolling-variance thresholds per channel; ``None`` skips the steady-state check (identification starts
        with the first window after the detection).
    steady_window : float
        Length of the rolling-variance window in seconds (default 10 s, the paper's).
    rule : {"paper", "likelihood", "pvalue"}
        Decision rule (see :data:`RULES`).

    Notes
    -----
    :meth:`run` filters the record once through each model and computes every window's statistic from prefix
    sums (:func:`window_statistics`); :meth:`update` feeds a stream chunk by chunk and gives the same events as
    :meth:`run` on the concatenated stream.

    References
    ----------
    Dutta, McKay, Kopsaftopoulos, Gandhi, *Statistical Time Series Methods for Multicopter Fault Detection and
    Identification* (paper 003), Fig. 3, Fig. 7 and eqs. 8-14.
    """

    def __init__(self, baseline: Any, models: Mapping, *, window: float, step: float | None = None,
                 fs: float = 1.0, test: Any = None, detection_test: Any = None, steady_thresholds: Any = None,
                 steady_window: float | None = None, rule: str = "paper") -> None:
        from tsfdi.detection.base import ResidualTest
        from tsfdi.detection.whiteness import LjungBox

        self.fs = float_like(fs, "fs", minimum=0.0, strict_min=True)
        self.nchan = int(getattr(_members("baseline", baseline)[0], "neqs", 1))
        if not isinstance(models, Mapping) or not models:
            raise TypeError("models must be a non-empty mapping name -> fitted fault models")
        for name, res in models.items():
            for r in _members(f"models[{name!r}]", res):
                if int(getattr(r, "neqs", 1)) != self.nchan:
                    raise ValueError(f"models[{name!r}] has {getattr(r, 'neqs', 1)} channel(s) but baseline has "
                                     f"{self.nchan}")
        self.baseline = baseline
        self.models = dict(models)
        self.window_n = _seconds_to_samples(window, "window", self.fs, minimum=3)
        self.step_n = max(1, int(round(self.fs))) if step is None else _seconds_to_samples(step, "step", self.fs)
        self.window = self.window_n / self.fs
        self.step = self.step_n / self.fs
        test = LjungBox(lags=25, alpha=1e-3) if test is None else test
        if isinstance(test, Mapping):
            test = dict(test)
            missing = [n for n in self.models if n not in test]
            if missing or not all(isinstance(t, ResidualTest) for t in test.values()):
                raise ValueError(f"test as a mapping must hold a residual test for every model {list(self.models)}")
            if detection_test is None:
                raise TypeError("detection_test is required when test is a mapping (one test per fault model)")
        elif not isinstance(test, ResidualTest):
            raise TypeError(f"test must be a residual test (LjungBox, FTest), got {type(test).__name__}")
        detection_test = test if detection_test is None else detection_test
        if not isinstance(detection_test, ResidualTest):
            raise TypeError(f"detection_test must be a residual test, got {type(detection_test).__name__}")
        self.test, self.detection_test = test, detection_test
        self.rule = option(rule, "rule", RULES)
        sw = 10.0 if steady_window is None else steady_window
        self.steady_window_n = _seconds_to_samples(sw, "steady_window", self.fs, minimum=2)
        if steady_thresholds is None:
            self.steady_thresholds = None
        else:
            thr = np.asarray(steady_thresholds, dtype=np.float64).ravel()
            if thr.shape != (self.nchan,) or not np.all(np.isfinite(thr)) or np.any(thr <= 0):
                raise ValueError(f"steady_thresholds must hold {self.nchan} finite positive variance(s), got "
                                 f"{steady_thresholds!r}")
            self.steady_thresholds = thr
        self.reset()

    def __repr__(self) -> str:
        return (f"Monitor(models={list(self.models)}, window={self.window:g} s, step={self.step:g} s, fs={self.fs:g}, "
                f"rule={self.rule!r})")

    def reset(self) -> None:
        """Forget the stream: back to the healthy phase at time 0."""
        self._buffer = np.empty((0, self.nchan))
        self._offset = 0           # stream position of _buffer[0]
        self._next = 0             # stream position of the next window start
        self._phase = "healthy"
        self._detect_pos: int | None = None
        self._steady_pos: int | None = None
        self._rows: list = []
        self._events: list = []

    # ------------------------------------------------------------------------------------------------------------
    def _values(self, signal: Any) -> np.ndarray:
        sig = as_signal(signal, "signal", allow_constant=True)
        if sig.nchan != self.nchan:
            raise ValueError(f"signal has {sig.nchan} channel(s) but the models have {self.nchan}")
        return sig.values

    def _t(self, pos: int) -> float:
        return round(pos / self.fs, 9)

    def _process(self, x: np.ndarray, pos0: int, hist: int) -> list:
        """Windows starting at ``x[hist]``, ``x[hist + step]``, ...; ``x[0]`` is stream position ``pos0``.

        The ``hist`` samples before the first window only feed the rolling variance."""
        W, S, V = self.window_n, self.step_n, self.steady_window_n
        body = x[hist:]
        if body.shape[0] < W:
            return []
        det = window_statistics(body, {"healthy": self.baseline}, self.detection_test, window=W, step=S)
        d0 = det["decisions"]["healthy"]
        ident = window_statistics(body, self.models, self.test, window=W, step=S)
        names = ident["names"]
        rej = np.array([ident["decisions"][n]["reject"] for n in names])
        pmin = np.array([ident["decisions"][n]["pvalue"].min(axis=1) for n in names])
        labels = apply_rule(rej, ident["loglik"], pmin, self.rule)
        paper = apply_rule(rej, ident["loglik"], pmin, "paper")
        new_events = []
        for w, s in enumerate(det["starts"]):
            i0 = hist + int(s)                      # window start in x
            start = pos0 + i0
            end = start + W
            lo = i0 + W - V                         # rolling-variance window [lo, i0 + W) in x
            var = x[lo:i0 + W].var(axis=0) if lo >= 0 else np.full(self.nchan, np.nan)
            fault = bool(d0["reject"][w])
            row = {"start": self._t(start), "end": self._t(end),
                   "detect_statistic": float(np.max(d0["statistic"][w] / d0["threshold"][w])),
                   "detect_pvalue": float(np.min(d0["pvalue"][w])), "fault": fault}
            for c in range(self.nchan):
                row[f"variance_{c}"] = float(var[c])
            if self._phase == "healthy" and fault:
                self._phase = "transient"
                self._detect_pos = end
                new_events.append(MonitorEvent(self._t(end), "detection", None, "fault",
                                               window=(self._t(start), self._t(end))))
                if self.steady_thresholds is None:
                    self._phase, self._steady_pos = "steady", start
                    new_events.append(MonitorEvent(self._t(end), "steady", None, "steady",
                                                   window=(self._t(start), self._t(end))))
            if self._phase == "transient":
                var_start = pos0 + lo
                if lo >= 0 and var_start >= self._detect_pos and np.all(var <= self.steady_thresholds):
                    self._phase, self._steady_pos = "steady", var_start
                    new_events.append(MonitorEvent(self._t(end), "steady", None, "steady",
                                                   window=(self._t(var_start), self._t(end))))
            row["phase"] = self._phase
            status, label, acc = "", None, ()
            if self._phase == "steady" and start >= self._steady_pos:
                acc = tuple(n for j, n in enumerate(names) if not rej[j, w])
                status = "identified" if paper[w] >= 0 else ("none" if paper[w] == -1 else "ambiguous")
                label = names[labels[w]] if labels[w] >= 0 else None
                new_events.append(MonitorEvent(self._t(end), "identification", label, status, acc,
                                               (self._t(start), self._t(end))))
            row.update({"status": status, "label": label, "accepted": ",".join(acc)})
            self._rows.append(row)
        self._events.extend(new_events)
        return new_events

    def update(self, samples: Any) -> list:
        """Feed the next samples of a stream; returns the events of the windows they complete.

        Parameters
        ----------
        samples : array_like, DataFrame or DataArray, shape (n, k)
            New samples (time on axis 0), continuing the stream.

        Returns
        -------
        list of MonitorEvent
        """
        x = self._values(samples)
        self._buffer = np.concatenate([self._buffer, x])
        end = self._offset + self._buffer.shape[0]
        W, S = self.window_n, self.step_n
        if end - self._next < W:
            return []
        nwin = (end - self._next - W) // S + 1
        hist = self._next - self._offset
        seg = self._buffer[:hist + (nwin - 1) * S + W]
        events = self._process(seg, self._offset, hist)
        self._next += nwin * S
        keep = max(self._offset, self._next - max(self.steady_window_n - W, 0))
        self._buffer = self._buffer[keep - self._offset:]
        self._offset = keep
        return events

    def run(self, signal: Any) -> MonitorResult:
        """Monitor a whole record from time 0 (resets the monitor first).

        Parameters
        ----------
        signal : array_like, DataFrame or DataArray, shape (nobs, k)

        Returns
        -------
        MonitorResult
        """
        self.reset()
        self.update(signal)
        return self.result()

    def result(self) -> MonitorResult:
        """Events and per-window table of everything fed so far."""
        cols = ["start", "end", "detect_statistic", "detect_pvalue", "fault"] + \
            [f"variance_{c}" for c in range(self.nchan)] + ["phase", "status", "label", "accepted"]
        frame = pd.DataFrame(self._rows, columns=cols)
        ident = frame["label"][frame["status"] != ""].dropna()
        label = ident.value_counts().idxmax() if len(ident) else None
        det = next((e.time for e in self._events if e.kind == "detection"), None)
        st = next((e.time for e in self._events if e.kind == "steady"), None)
        return MonitorResult(events=list(self._events), windows=frame, detection_time=det, steady_time=st,
                             label=label)

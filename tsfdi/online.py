"""Online detection on signal streams (Keipour et al., paper 001; Hansen et al., paper 002).

:class:`OnlineDetector` runs several (output, input) signal pairs at once, each through a recursive ARX model
with the stability gate, Welford running variance and Z-score alarms of paper 001 and a streaming GLRT on the
same prediction errors (paper 002), and reports the first alarm of every pair and of the whole system with time
stamps.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import as_signal
from tsfdi._validation import float_like, int_like, option
from tsfdi.detection.glrt import GLRT
from tsfdi.models.recursive import RecursiveARX

__all__ = ["OnlineDetector", "OnlineDetection"]

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
    (its ``scale`` is the Welford standard deviation at arming, its input the error minus the Welford mean at
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
                 threshold: float = 4.5, glrt: Any = "default", freeze_on_alarm: bool = True,
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
        if not isinstance(freeze_on_alarm, (bool, np.bool_)):
            raise TypeError(f"freeze_on_alarm must be a bool, got {freeze_on_alarm!r}")
        self.freeze_on_alarm = bool(freeze_on_alarm)
        if isinstance(glrt, str) and glrt == "default":
            glrt = GLRT(window=20, alpha=1e-6) if self.statistic == "zscore" else None
        if glrt is not None and not isinstance(glrt, GLRT):
            raise TypeError(f"glrt must be a tsfdi.detection.GLRT or None, got {type(glrt).__name__}")
        self.glrt = glrt
        zs = self.statistic == "zscore"
        # in "mean" mode the model's own Z-score never alarms (threshold 1e300) and halting is done here
        self._models = [RecursiveARX(na, nb, nk, forgetting_factor, n_inputs=self.n_inputs,
                                     threshold=self.threshold if zs else 1e300,
                                     freeze_on_alarm=self.freeze_on_alarm and zs, nonfinite=self.nonfinite,
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
        if self.freeze_on_alarm and not self._stat_alarmed[c]:
            snap = m.get_state()
        res = m.run(yc, uc)
        e = np.asarray(res.resid, dtype=float)
        stat = self._mean_statistic(c, e)
        pos = start + np.arange(n)
        hit = np.flatnonzero((np.nan_to_num(stat, nan=-np.inf) > self.threshold) & (pos >= self.arm_after))
        results = [res]
        if snap is not None and hit.size:
            i = int(hit[0])
            m.set_state(snap)
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

"""Online monitoring of signal streams.

:class:`OnlineDetector` runs several (output, input) signal pairs at once, each through a recursive ARX model
with the stability gate, Welford running variance and Z-score alarms of Keipour et al. (paper 001) and a
streaming GLRT on the same prediction errors (Hansen et al., paper 002), and reports the first alarm of every
pair and of the whole system with time stamps.
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
        Per-sample alarm of each pair (Z-score or GLRT).
    first_alarms : pandas.DataFrame
        One row per pair: ``position`` (sample number since the detector started, -1 if none), ``time``
        (index label, None if none), ``source`` ("zscore", "glrt" or "zscore+glrt"), ``armed_at`` (position
        where the Z-score and GLRT were armed, -1 if not yet).
    first_alarm : int or None
        Earliest alarm position over all pairs (since the detector started).
    first_alarm_time : object or None
        Its index label (position for numpy input).
    first_alarm_pair : str or None
        The pair that raised it first (ties: the first pair in order).
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


class OnlineDetector:
    """Online anomaly detection on several commanded / measured (input / output) signal pairs at once.

    Every pair gets its own :class:`tsfdi.RecursiveARX` (same orders and options for all pairs); its a-priori
    prediction errors go to the model's Z-score test and, once the model and the error variance are stable
    (the pair is *armed*), to a streaming :class:`tsfdi.detection.GLRT` whose ``sigma`` is the Welford standard
    deviation at arming and whose input is the error minus the Welford mean at arming.

    Parameters
    ----------
    pairs : int or sequence of str
        Number of pairs or their names.
    na, nb, nk : int
        ARX orders (see :class:`tsfdi.RecursiveARX`), defaults 2, 2, 0.
    forgetting_factor : float, default 0.995
    threshold : float, default 4.5
        Z-score alarm threshold (paper 001).
    glrt : GLRT or None, default ``GLRT(window=20, alpha=1e-6)``
        The GLRT whose window and threshold are used for every pair (its ``sigma`` is replaced per pair);
        ``None`` disables the GLRT.
    halt_on_alarm : bool, default True
        Freeze a pair's model from its first Z-score alarm on (paper 002).
    nonfinite : {"skip", "raise"}, default "skip"
        Policy for NaN / inf samples (see :class:`tsfdi.RecursiveARX`); skipped samples are not fed to the GLRT.
    **rls_options
        Further :class:`tsfdi.RecursiveARX` options: ``P0``, ``trend``, ``eps``, ``stable_samples``,
        ``variance_tol``, ``min_variance_samples``.

    Notes
    -----
    Feeding a stream in blocks (:meth:`run`) or sample by sample (:meth:`update`) gives the same alarms.

    References
    ----------
    Keipour, Mousaei, Scherer, ICRA 2019 (paper 001), sections IV-V; Hansen, Blanke, Adrian (paper 002),
    eqs. 1-3 and 14-16.
    """

    def __init__(self, pairs: Any, *, na: int = 2, nb: int = 2, nk: int = 0, forgetting_factor: float = 0.995,
                 threshold: float = 4.5, glrt: Any = "default", halt_on_alarm: bool = True,
                 nonfinite: str = "skip", **rls_options: Any) -> None:
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
        if isinstance(glrt, str) and glrt == "default":
            glrt = GLRT(window=20, alpha=1e-6)
        if glrt is not None and not isinstance(glrt, GLRT):
            raise TypeError(f"glrt must be a tsfdi.detection.GLRT or None, got {type(glrt).__name__}")
        self.glrt = glrt
        self._models = [RecursiveARX(na, nb, nk, forgetting_factor, n_inputs=1, threshold=self.threshold,
                                     halt_on_alarm=halt_on_alarm, nonfinite=self.nonfinite, **rls_options)
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
        if su.nchan != k:
            raise ValueError(f"u must have one column per pair ({k}), got {su.nchan}")
        if sy.nobs != su.nobs:
            raise ValueError(f"u and y must have the same length, got len(u)={su.nobs} and len(y)={sy.nobs}")
        return sy, su

    def run(self, y: Any, u: Any) -> OnlineDetection:
        """Process a block of samples of every pair (continuing from the current state).

        Parameters
        ----------
        y, u : array_like, DataFrame or DataArray, shape (nobs, n_pairs)
            Outputs and inputs, one column per pair (a 1-D array for a single pair).

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
        A = np.zeros((n, k), dtype=bool)
        labels = sy.index
        for c, m in enumerate(self._models):
            res = m.run(np.ascontiguousarray(sy.values[:, c]), np.ascontiguousarray(su.values[:, c]))
            e = np.asarray(res.resid, dtype=float)
            Z[:, c] = np.asarray(res.zscore, dtype=float)
            E[:, c] = e
            zal = res.alarm.copy()
            gal = np.zeros(n, dtype=bool)
            if self.glrt is not None:
                # the GLRT is armed from the sample after the variance became stable
                if self._streams[c] is None:
                    vs = np.flatnonzero(res.variance_stable)
                    if vs.size:
                        arm = int(vs[0]) + 1
                        var = float(np.asarray(res.variance, dtype=float)[vs[0]])
                        mu = float(np.asarray(res.mean, dtype=float)[vs[0]])
                        self._streams[c] = (self.glrt.stream(1, sigma=np.sqrt(var)), mu)
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
            elif self._armed_at[c] < 0:
                vs = np.flatnonzero(res.variance_stable)
                if vs.size:
                    self._armed_at[c] = start + int(vs[0]) + 1
            alarm = zal | gal
            A[:, c] = alarm
            if self._first[c] < 0 and alarm.any():
                i = int(np.flatnonzero(alarm)[0])
                self._first[c] = start + i
                self._source[c] = "zscore+glrt" if (zal[i] and gal[i]) else ("zscore" if zal[i] else "glrt")
                self._time[c] = labels[i] if labels is not None else start + i
        self._nobs += n
        return self._result(sy, Z, G, E, A)

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

    def _result(self, sy: Any, Z, G, E, A) -> OnlineDetection:
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
                               first_alarm_pair=pair)

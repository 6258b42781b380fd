"""Moving average of squared prediction errors with residual padding (Samy, Postlethwaite, Gu, paper 004, eq. 6).

The residual evaluation of paper 004's sensor-validation scheme: the squared errors of an online model of the
sensor (an :class:`~tsfdi.EMRAN` network, a :class:`~tsfdi.RecursiveARX` model, or any other) are averaged over a
moving window, optionally after *padding* the window with copies of its smallest value, and compared with a
threshold.
"""

from __future__ import annotations

import copy
from typing import Any

import numba
import numpy as np

from tsfdi._data import Signal, as_signal, sampling_frequency, window_samples
from tsfdi._validation import float_like, int_like, sample_vector
from tsfdi.detection.base import ResidualTest
from tsfdi.detection.decision import Decision
from tsfdi.detection.threshold import EmpiricalThreshold

__all__ = ["MovingSquaredError", "MovingSquaredErrorStream"]


@numba.njit(cache=True, nogil=True)
def _padded_means(x, window, padding, weight):  # pragma: no cover - compiled
    """``weight * (sum(S) + padding * min(S)) / (window + padding)`` of every window ``S`` of squared values of
    ``x`` ending at ``t >= window - 1``; NaN before and for a window holding a NaN. O(window) per sample, exact sums
    (no running-sum cancellation)."""
    n = x.shape[0]
    out = np.full(n, np.nan)
    for t in range(window - 1, n):
        s = 0.0
        mn = np.inf
        for i in range(t - window + 1, t + 1):
            v = x[i] * x[i]
            s += v
            if v < mn:
                mn = v
        if np.isnan(s):
            continue
        out[t] = weight * (s + padding * mn) / (window + padding)
    return out


class MovingSquaredError(ResidualTest):
    r"""Paper 004's residual: weighted moving average of squared prediction errors, with residual padding.

    Parameters
    ----------
    window : int or str, default 20
        :math:`M` of eq. 6 (paper 004's :math:`D`, the points of one residual set): an int counts samples, a time
        span such as ``"1s"`` uses the residual's time index or ``fs``.
    threshold : float or EmpiricalThreshold, optional
        A sample alarms when :math:`r_i` exceeds it (in squared residual units times ``weight``). An
        :class:`~tsfdi.EmpiricalThreshold` is set by :meth:`calibrate` on healthy errors (per-sample false-alarm
        probability). Needed by :meth:`test` and :meth:`stream`, not by :meth:`statistic`.
    padding : int, default 0
        :math:`D_{pad} - D`: artificial points added to each window, each equal to the window's smallest squared
        error (paper 004, section IV.B). 0 gives eq. 6 alone; paper 004 settles on as many points as the window
        holds (``padding = window``, section VIII).
    weight : float, default 1.0
        :math:`w` of eq. 6 (paper 004: "deduced from experiments"); padding is what makes a large :math:`w`
        (residual amplification) possible without false alarms.
    fs : float, optional
        Sampling frequency (Hz) for a time-span ``window`` when the residual has no time index.

    Notes
    -----
    Eq. 6 of paper 004 with padding applied first: with :math:`S_i = \{e_j^2,\ i - M < j \le i\}` the last
    :math:`M` squared prediction errors and :math:`P` = ``padding``,

    .. math:: r_i = w \, \frac{\sum_{j=i-M+1}^{i} e_j^2 + P \min S_i}{M + P} .

    Without padding (:math:`P = 0`) this is eq. 6. A short burst of large errors (residual noise: a gust, a
    manoeuvre the model has not learnt) is damped by the factor :math:`M / (M + P)`, while a fault that raises
    every error of the window raises :math:`\min S_i` too and is not damped: paper 004's example, threshold 5,
    sets :math:`\{6, 6, 6, 6\}` (fault, mean 6 with or without padding) and :math:`\{24, 0, 0, 0\}` (noise spike:
    mean 6 without, 4 with two padding points). The price is a slower rise after a fault (paper 004: +55 % mean
    detection time).

    The first ``window - 1`` samples have no complete window: :math:`r` is NaN there and does not alarm. NaN
    errors (a model's start-up, a skipped sample) make every window that holds them NaN (no alarm); inf is
    refused. :math:`r` is in squared residual units (times :math:`w`): it is ``inf`` (an alarm) for errors beyond
    about 1e154 and underflows for errors below about 1e-162, so give the errors in units near their size.

    References
    ----------
    I. Samy, I. Postlethwaite, D. Gu, "Neural network based sensor validation scheme demonstrated on an unmanned
    air vehicle (UAV) model" (paper 004), eq. 6, sections IV-B and VIII, Tables 2-3.
    """

    name = "moving squared error"
    null_hypothesis = "the moving average of squared prediction errors stays below the threshold (healthy sensor)"
    alternative_hypothesis = "the moving average of squared prediction errors exceeds the threshold (sensor fault)"

    def __init__(self, window: Any = 20, threshold: Any = None, *, padding: int = 0, weight: float = 1.0,
                 fs: float | None = None) -> None:
        self.fs = float_like(fs, "fs", minimum=0.0, strict_min=True, optional=True)
        # type and value check now; a time span is turned into samples with the residual's fs at use
        window_samples(window, "window", self.fs if self.fs is not None else 1e9)
        self.window = window
        self.padding = int_like(padding, "padding", minimum=0)
        self.weight = float_like(weight, "weight", minimum=0.0, strict_min=True)
        if threshold is None or isinstance(threshold, EmpiricalThreshold):
            self.threshold = threshold
        else:
            self.threshold = float_like(threshold, "threshold", minimum=0.0)

    def __repr__(self) -> str:
        return (f"MovingSquaredError(window={self.window!r}, threshold={self.threshold!r}, padding={self.padding}, "
                f"weight={self.weight:g})")

    # ------------------------------------------------------------------ threshold
    @property
    def threshold_(self) -> float:
        """The threshold in use (a calibrated :class:`~tsfdi.EmpiricalThreshold`'s value, or the float given)."""
        if self.threshold is None:
            raise ValueError("threshold is None: give MovingSquaredError a threshold, or an EmpiricalThreshold and "
                             "calibrate() it on healthy prediction errors")
        if isinstance(self.threshold, EmpiricalThreshold):
            self.threshold.check_fitted()
            return self.threshold.threshold_
        return float(self.threshold)

    def calibrate(self, healthy: Any) -> MovingSquaredError:
        """Set an :class:`~tsfdi.EmpiricalThreshold` from the statistic of healthy prediction errors.

        The statistic of every channel of ``healthy`` (NaN values left out) is pooled into one sample; a copy of the
        threshold object is stored, so one object can serve several tests. Returns ``self``.

        Raises
        ------
        TypeError
            ``threshold`` is not an :class:`~tsfdi.EmpiricalThreshold`.
        ValueError
            Too few healthy samples for its ``false_alarm`` (the message says how many are needed).
        """
        if not isinstance(self.threshold, EmpiricalThreshold):
            raise TypeError(f"calibrate needs threshold=EmpiricalThreshold(...), got {self.threshold!r}")
        sig = self._resid_signal(healthy, "healthy")
        r = self._values(sig)
        self.threshold = copy.copy(self.threshold).calibrate(r[np.isfinite(r)])
        return self

    # ------------------------------------------------------------------ statistic
    def _resid_signal(self, resid: Any, name: str = "resid") -> Signal:
        sig = as_signal(resid, name, allow_constant=True, finite=False)
        inf = np.isinf(sig.values)
        if inf.any():
            raise ValueError(f"{name} contains {int(inf.sum())} inf value(s) (first at sample "
                             f"{int(np.argwhere(inf)[0, 0])}); NaN marks a missing error, inf is refused")
        m = self._window(sig, name)
        if sig.nobs < m:
            raise ValueError(f"{name} is too short: {sig.nobs} samples, at least window={m} are needed")
        return sig

    def _window(self, sig: Signal | None, name: str = "resid") -> int:
        fs = self.fs if self.fs is not None or sig is None else sampling_frequency(sig, None, name)
        return window_samples(self.window, "window", fs)

    def _values(self, sig: Signal) -> np.ndarray:
        m = self._window(sig)
        x = sig.values
        out = np.empty(x.shape)
        for c in range(x.shape[1]):
            out[:, c] = _padded_means(np.ascontiguousarray(x[:, c]), m, self.padding, self.weight)
        return out

    def statistic(self, resid: Any) -> Any:
        """The residual :math:`r_i` (eq. 6 after padding) in the caller's data kind, same index as ``resid``
        (NaN for the first ``window - 1`` samples and for windows holding a NaN error)."""
        sig = self._resid_signal(resid)
        return sig.wrap(self._values(sig), 0)

    def test(self, resid: Any) -> Decision:
        """Evaluate every sample of ``resid`` (per channel) against the threshold.

        Returns
        -------
        Decision
            ``statistic``: the largest :math:`r_i` per channel (NaN if no window is complete and finite);
            ``threshold``; ``pvalue`` NaN; ``alpha``: the calibrated per-sample false-alarm probability, NaN for a
            fixed threshold; ``reject`` when any sample alarms. ``details``: ``"r"`` (the series, caller's kind),
            ``"alarm"`` (per-sample alarm flags, caller's kind), ``"alarms"`` (positions per channel),
            ``"first_alarm"`` (position per channel, -1 if none), ``"first_alarm_label"`` (index label or position),
            ``"alarm_rate"`` (fraction of the evaluated samples that alarm, per channel), ``"window"`` (samples),
            ``"padding"``, ``"weight"``.
        """
        sig = self._resid_signal(resid)
        gamma = self.threshold_
        r = self._values(sig)
        k = sig.nchan
        alarm = np.nan_to_num(r, nan=-np.inf) > gamma
        first = np.array([int(np.flatnonzero(alarm[:, c])[0]) if alarm[:, c].any() else -1 for c in range(k)])
        labels = [None if f < 0 else (sig.index[f] if sig.index is not None else int(f)) for f in first]
        evaluated = np.isfinite(r).sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            rate = np.where(evaluated > 0, alarm.sum(axis=0) / np.maximum(evaluated, 1), np.nan)
        details = {"r": sig.wrap(r, 0), "alarm": sig.wrap(alarm, 0),
                   "alarms": [np.flatnonzero(alarm[:, c]) for c in range(k)], "first_alarm": first,
                   "first_alarm_label": labels, "alarm_rate": rate, "window": self._window(sig),
                   "padding": self.padding, "weight": self.weight}
        alpha = self.threshold.false_alarm if isinstance(self.threshold, EmpiricalThreshold) else np.nan
        return Decision(statistic=np.fmax.reduce(r, axis=0), threshold=np.full(k, gamma),
                        pvalue=np.full(k, np.nan), alpha=alpha, reject=bool(alarm.any()), df=np.full(k, np.nan),
                        nobs=sig.nobs, null_hypothesis=self.null_hypothesis,
                        alternative_hypothesis=self.alternative_hypothesis, details=details,
                        channel_reject=alarm.any(axis=0), channels=tuple(sig.channels), test="MovingSquaredError")

    def stream(self, nchan: int = 1) -> MovingSquaredErrorStream:
        """A stateful sample-by-sample evaluation with this test's window, padding, weight and threshold (a time-span
        window needs ``fs``)."""
        nchan = int_like(nchan, "nchan", minimum=1)
        if self.fs is None and not isinstance(self.window, (int, np.integer)):
            raise ValueError(f"window = {self.window!r} is a time span: give MovingSquaredError fs to stream")
        return MovingSquaredErrorStream(self._window(None), self.threshold_, nchan=nchan, padding=self.padding,
                                        weight=self.weight)


class MovingSquaredErrorStream:
    """Incremental :class:`MovingSquaredError`: feed prediction errors one sample at a time.

    The values equal :meth:`MovingSquaredError.statistic` on the concatenated samples. Each update costs
    O(window).

    Parameters
    ----------
    window : int
        :math:`M` in samples.
    threshold : float
        Alarm threshold on :math:`r_i`.
    nchan : int, default 1
    padding : int, default 0
    weight : float, default 1.0

    Attributes
    ----------
    k : int
        Samples seen.
    r : ndarray, shape (nchan,)
        Last statistic per channel (NaN until ``window`` samples are seen, and while the window holds a NaN).
    alarm : bool
        Whether the last sample alarmed (any channel).
    first_alarm : int or None
        Sample number (0-based) of the first alarm.
    """

    def __init__(self, window: int, threshold: float, *, nchan: int = 1, padding: int = 0, weight: float = 1.0):
        self.window = int_like(window, "window", minimum=1)
        self.threshold = float_like(threshold, "threshold", minimum=0.0)
        self.nchan = int_like(nchan, "nchan", minimum=1)
        self.padding = int_like(padding, "padding", minimum=0)
        self.weight = float_like(weight, "weight", minimum=0.0, strict_min=True)
        self.reset()

    def __repr__(self) -> str:
        return (f"MovingSquaredErrorStream(window={self.window}, threshold={self.threshold:.5g}, "
                f"padding={self.padding}, k={self.k})")

    def reset(self) -> None:
        """Forget all samples."""
        self._buf = np.zeros((self.window, self.nchan))
        self.k = 0
        self.r = np.full(self.nchan, np.nan)
        self.alarm = False
        self.first_alarm: int | None = None

    def update(self, x: Any) -> np.ndarray:
        """Add one prediction error (a float, or one per channel; NaN allowed, inf refused).

        Returns
        -------
        ndarray, shape (nchan,)
            :math:`r` of the sample per channel.
        """
        v = sample_vector(x, self.nchan)
        if np.isinf(v).any():
            raise ValueError(f"x contains inf at sample {self.k}")
        self._buf[self.k % self.window] = v * v
        self.k += 1
        if self.k >= self.window:
            # the window's samples in time order, so that the sum is the batch statistic's (same rounding)
            w = np.roll(self._buf, -(self.k % self.window), axis=0)
            s = np.zeros(self.nchan)
            for row in w:
                s = s + row
            self.r = self.weight * (s + self.padding * w.min(axis=0)) / (self.window + self.padding)
        self.alarm = bool(np.any(np.nan_to_num(self.r, nan=-np.inf) > self.threshold))
        if self.alarm and self.first_alarm is None:
            self.first_alarm = self.k - 1
        return self.r.copy()

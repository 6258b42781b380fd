"""Sensor-fault injection: the fault classes of paper 004 (Samy, Postlethwaite, Gu) and the usual others.

:func:`inject_fault` adds one fault to one channel of a fault-free signal and returns the faulty signal with the
ground truth, so that a detector can be scored on real data with a known fault (paper 004, Tables 2-3).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tsfdi._data import as_signal, sampling_frequency, window_samples
from tsfdi._validation import check_rng, float_like, option

__all__ = ["FAULT_KINDS", "inject_fault"]

#: the fault kinds of :func:`inject_fault`
FAULT_KINDS = ("bias", "hard", "soft", "drift", "stuck", "noise")
#: duration of the ramp of paper 004's hard and soft additive faults (section V, after An 1998)
_DEFAULT_RAMP = {"hard": "1s", "soft": "4s"}


def inject_fault(signal: Any, kind: str, magnitude: float, start: Any, *, duration: Any = None, ramp: Any = None,
                 rng: Any = None, channel: Any = None, sensor_range: float | None = None,
                 fs: float | None = None) -> tuple[Any, Any]:
    r"""Add a sensor fault to a fault-free signal; return the faulty signal and the per-sample ground truth.

    Parameters
    ----------
    signal : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, k)
        The fault-free signal (finite values).
    kind : {"bias", "hard", "soft", "drift", "stuck", "noise"}
        The fault, with :math:`A` = ``magnitude * range`` and :math:`k = 0, 1, \dots` the samples since ``start``:

        - ``"bias"``: constant bias, :math:`y + A` (paper 004's constant-bias fault; a step);
        - ``"hard"`` / ``"soft"``: additive ramp faults of paper 004, section V,
          :math:`y + A \min((k + 1) / n_R, 1)`, the ramp lasting :math:`n_R` samples (``ramp``: 1 s for a hard,
          4 s for a soft fault by default, paper 004 after An 1998);
        - ``"drift"``: unbounded linear drift :math:`y + A (k + 1) / n_R` (``ramp`` default: the fault's length,
          so that the drift reaches :math:`A` at its last sample);
        - ``"stuck"``: the sensor holds the last fault-free value (``y[start - 1]``; ``y[0]`` when ``start`` is
          0) plus :math:`A` (``magnitude=0``: frozen);
        - ``"noise"``: noise increase, :math:`y + A\,\varepsilon_k`, :math:`\varepsilon_k` iid standard normal
          from ``rng``.
    magnitude : float
        :math:`A` as a fraction of the sensor range (paper 004: 0.05 and 0.2); negative for a negative bias.
    start : int or time span
        First faulty sample: an int counts samples, a time span such as ``"60s"`` the time since the first sample
        (with the signal's time index or ``fs``).
    duration : int or time span, optional
        Length of the fault (default: to the end of the signal); the samples after it are fault-free again.
    ramp : int or time span, optional
        :math:`n_R` of the ``"hard"``, ``"soft"`` and ``"drift"`` faults (at least one sample; one sample makes a
        step). Not used by the other kinds.
    rng : None, int or numpy.random.Generator
        Randomness of the ``"noise"`` fault (the same seed gives the same fault).
    channel : int or str, optional
        The faulty channel of a 2-D signal (position, or name for a DataFrame / DataArray). Required when the
        signal has more than one channel.
    sensor_range : float, optional
        The sensor range that ``magnitude`` refers to (paper 004: 30 deg/s). Default: the range (max - min) of the
        channel over the given signal.
    fs : float, optional
        Sampling frequency (Hz) for time spans when the signal has no time index.

    Returns
    -------
    faulty : same kind as ``signal``
        A copy of ``signal`` with the fault added to the channel (index and channel names kept).
    labels : ndarray of bool, Series or DataArray, shape (nobs,)
        Ground truth: True on the faulty samples (``start`` up to ``start + duration``), named ``"fault"``.

    Raises
    ------
    ValueError
        An unknown ``kind``; ``start`` / ``duration`` / ``ramp`` out of the signal or not a number of samples or a
        time span (a time span without a time index or ``fs``); a missing or unknown ``channel``; a constant channel
        without ``sensor_range``; NaN / inf in the signal; duplicate channel names; a fault that leaves the
        floating-point range (``magnitude`` times the range beyond about 1e308).
    TypeError
        Non-numeric ``signal``, ``magnitude`` or ``sensor_range``.

    Notes
    -----
    The fault is exact by construction: ``faulty - signal`` is the term above to rounding (the stuck fault
    replaces the values), and is zero outside the labelled samples.

    References
    ----------
    I. Samy, I. Postlethwaite, D. Gu, "Neural network based sensor validation scheme demonstrated on an unmanned
    air vehicle (UAV) model" (paper 004), section V and Tables 2-3. Y. An, "A design of fault tolerant flight
    control systems for sensor and actuator failures using on-line learning neural networks", PhD thesis, West
    Virginia University, 1998.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.linspace(0.0, 1.0, 11)               # range 1
    >>> faulty, labels = inject_fault(y, "hard", 0.2, 5, ramp=4)
    >>> np.round(faulty - y, 3).tolist()
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.05, 0.1, 0.15, 0.2, 0.2, 0.2]
    >>> labels.nonzero()[0].tolist()
    [5, 6, 7, 8, 9, 10]
    """
    kind = option(kind, "kind", FAULT_KINDS)
    sig = as_signal(signal, "signal", allow_constant=True)
    dup = sorted({c for c in sig.channels if sig.channels.count(c) > 1}) if sig.named else []
    if dup:
        raise ValueError(f"signal has duplicate channel names {dup}: a fault is added to one channel; rename them "
                         "first")
    magnitude = float_like(magnitude, "magnitude")
    rate = sampling_frequency(sig, fs, "signal")
    n = sig.nobs
    c = _channel(sig, channel)
    y = sig.values[:, c]
    first = window_samples(start, "start", rate, minimum=0)
    if first >= n:
        raise ValueError(f"start must fall inside the signal (< {n} samples), got {start!r} = sample {first}")
    length = n - first if duration is None else window_samples(duration, "duration", rate)
    stop = min(n, first + length)
    if sensor_range is None:
        with np.errstate(over="ignore"):
            span = float(y.max() - y.min())
        if span == 0.0:
            raise ValueError("signal is constant in the faulty channel: its range is 0; give sensor_range")
        if not np.isfinite(span):
            raise ValueError("signal's range in the faulty channel overflows float64; give sensor_range")
    else:
        span = float_like(sensor_range, "sensor_range", minimum=0.0, strict_min=True)
    amp = magnitude * span
    k = np.arange(stop - first, dtype=np.float64)
    out = sig.values.copy()
    with np.errstate(over="ignore", invalid="ignore"):     # an overflow is refused below
        if kind == "bias":
            out[first:stop, c] += amp
        elif kind in ("hard", "soft", "drift"):
            if ramp is None:
                n_ramp = stop - first if kind == "drift" else window_samples(_DEFAULT_RAMP[kind], "ramp", rate)
            else:
                n_ramp = window_samples(ramp, "ramp", rate)
            shape = (k + 1.0) / n_ramp
            out[first:stop, c] += amp * (shape if kind == "drift" else np.minimum(shape, 1.0))
        elif kind == "stuck":
            out[first:stop, c] = y[max(first - 1, 0)] + amp
        else:
            out[first:stop, c] += amp * check_rng(rng).standard_normal(stop - first)
    if not np.isfinite(out[first:stop, c]).all():
        raise ValueError(f"magnitude = {magnitude:g} times the sensor range {span:g} gives a {kind} fault that leaves "
                         "the floating-point range (inf): give a smaller magnitude or sensor_range")
    labels = np.zeros(n, dtype=bool)
    labels[first:stop] = True
    return sig.wrap(out, 0), sig.wrap(labels, 0, vector=False, name="fault")


def _channel(sig: Any, channel: Any) -> int:
    """Position of the faulty channel."""
    if channel is None:
        if sig.nchan > 1:
            raise ValueError(f"channel is required for a signal with {sig.nchan} channels {sig.channels}")
        return 0
    if isinstance(channel, (bool, np.bool_)):
        raise TypeError(f"channel must be a position or a channel name, got {channel!r}")
    if isinstance(channel, (int, np.integer)):
        if not -sig.nchan <= int(channel) < sig.nchan:
            raise ValueError(f"channel must be a position in [0, {sig.nchan}), got {channel}")
        return int(channel) % sig.nchan
    names = [str(ch) for ch in sig.channels]
    if str(channel) not in names:
        raise ValueError(f"channel {channel!r} is not one of the signal's channels {names}")
    return names.index(str(channel))

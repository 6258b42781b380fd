"""Put multi-rate, irregularly stamped signals (flight-log topics) on one uniform time grid.

:func:`align` is the step between a log reader (:func:`tsfdi.datasets.read_ulog`, a CSV with a time column) and
the models, which need uniformly sampled records. It never fills: a gap or a NaN either ends a record
(``gaps="split"``, ``nan_policy="omit"``) or raises (``"raise"``).
"""

from __future__ import annotations

import datetime
import numbers
import warnings
from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from tsfdi._data import is_xarray, runs, window_samples
from tsfdi._validation import MAX_VALUES, option
from tsfdi.exceptions import TsfdiWarning

__all__ = ["align", "MAX_GAP_FACTOR"]

#: default largest gap of a topic, in multiples of its median sample period (and at least one grid period)
MAX_GAP_FACTOR = 3
_SPAN = (str, pd.Timedelta, datetime.timedelta, np.timedelta64)
_NS = 1_000_000_000


def _nanoseconds(value: Any, name: str) -> int:
    if not isinstance(value, _SPAN):
        raise TypeError(f"{name} must be a time span such as '20ms', got {value!r} ({type(value).__name__})")
    try:
        span = pd.Timedelta(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a time span such as '20ms', got {value!r}") from None
    if span is pd.NaT or span <= pd.Timedelta(0):
        raise ValueError(f"{name} must be a positive time span, got {value!r}")
    return int(span / pd.Timedelta(1, "ns"))


def _period(fs: Any) -> int:
    """The grid period in nanoseconds from ``fs`` in Hz or a time span."""
    if isinstance(fs, _SPAN):
        period = _nanoseconds(fs, "fs")
    elif isinstance(fs, (bool, np.bool_)) or not isinstance(fs, (numbers.Real, np.number)):
        raise TypeError(f"fs must be a frequency in Hz or a time span such as '20ms', got {fs!r}")
    elif not np.isfinite(fs) or fs <= 0:
        raise ValueError(f"fs must be a positive, finite frequency in Hz, got {fs!r}")
    else:
        period = _NS / float(fs)        # inf for a tiny fs: refused below, before rounding
        period = round(period) if np.isfinite(period) else period
    if not 1 <= period <= 2**62:
        raise ValueError(f"fs = {fs!r} gives a grid period of {period} ns: it must lie between 1 ns and 146 years")
    return period


def _as_frame(obj: Any, name: str) -> pd.DataFrame:
    """A topic as a DataFrame; an unnamed Series / DataArray is one column named ``None``."""
    if isinstance(obj, pd.DataFrame):
        return obj
    if isinstance(obj, pd.Series):
        return obj.to_frame(obj.name)
    if is_xarray(obj) or type(obj).__module__.startswith("xarray"):
        dims = tuple(obj.dims)
        time = "time" if "time" in dims else (dims[0] if dims else None)
        if hasattr(obj, "data_vars"):      # a Dataset: one column per variable along time
            if any(tuple(v.dims) != (time,) for v in obj.data_vars.values()):
                raise ValueError(f"{name} is an xarray.Dataset whose variables are not all 1-D along {time!r}")
            return obj.to_dataframe()
        if len(dims) not in (1, 2):
            raise ValueError(f"{name} must have 1 or 2 dimensions (time[, channel]), got dims {dims}")
        data = obj.transpose(time, ...)
        if data.ndim == 1:
            return data.to_series().to_frame(obj.name)
        return data.to_pandas()
    raise TypeError(f"{name} must be a pandas DataFrame / Series or an xarray DataArray / Dataset, got "
                    f"{type(obj).__name__}")


def _stamps(index: pd.Index, name: str) -> tuple[np.ndarray, Any]:
    """Time stamps in int64 nanoseconds and the time zone (``"relative"`` for elapsed time)."""
    if isinstance(index, (pd.DatetimeIndex, pd.TimedeltaIndex)):
        tz = index.tz if isinstance(index, pd.DatetimeIndex) else "relative"
        try:
            ns = index.as_unit("ns").asi8    # UTC for a time zone; NaT refused below
        except (OverflowError, ValueError):
            raise ValueError(f"{name} has time stamps beyond the nanosecond range (years 1677-2262)") from None
    elif (pd.api.types.is_numeric_dtype(index.dtype) and not pd.api.types.is_bool_dtype(index.dtype)
          and not isinstance(index, pd.RangeIndex)):
        tz = "relative"
        seconds = np.asarray(index, dtype=np.float64)
        if not np.isfinite(seconds).all() or np.abs(seconds).max() > 9e9:
            raise ValueError(f"{name} has a time index (seconds) with NaN, inf or values beyond 9e9 s")
        ns = np.round(seconds * _NS).astype(np.int64)
    else:
        raise TypeError(f"{name} needs a time index (DatetimeIndex, TimedeltaIndex or numbers in seconds), got "
                        f"{type(index).__name__}: set the time column as the index, e.g. frame.set_index('time')")
    if index.hasnans:
        raise ValueError(f"{name} has a missing time stamp (NaT) at sample {int(np.argmax(index.isna()))}")
    back = np.flatnonzero(np.diff(ns) < 0)
    if back.size:
        i = int(back[0])
        raise ValueError(f"{name}: time goes back at sample {i + 1} ({_time(ns[i + 1], tz)} after "
                         f"{_time(ns[i], tz)}); sort it first (sort_index) if the order is an artefact")
    return ns, tz


def _time(ns: int, tz: Any) -> str:
    if tz == "relative":
        return f"{ns / _NS:.6f} s"
    return pd.Timestamp(int(ns), tz="UTC").tz_convert(tz).isoformat() if tz is not None else \
        pd.Timestamp(int(ns)).isoformat()


class _Topic(NamedTuple):
    label: str              # for messages: frames['name']
    fields: list            # the topic's own column names
    columns: list[str]      # the output's column names
    ns: np.ndarray          # time stamps, int64 nanoseconds
    values: np.ndarray      # float64 (nobs, len(fields))
    tz: Any                 # "relative" (elapsed time) or the time zone of date-times (None: naive)


def _topics(frames: Any) -> list[_Topic]:
    if isinstance(frames, Mapping) and not hasattr(frames, "data_vars"):     # an xarray.Dataset is one frame
        if not frames:
            raise ValueError("frames is empty: give at least one topic")
        items = [(f"frames[{k!r}]", str(k), _as_frame(v, str(k))) for k, v in frames.items()]
    else:
        items = [("frames", None, _as_frame(frames, "frames"))]
    topics = []
    for label, prefix, frame in items:
        if frame.shape[0] == 0 or frame.shape[1] == 0:
            raise ValueError(f"{label} is empty ({frame.shape[0]} samples, {frame.shape[1]} columns)")
        for col, dtype in frame.dtypes.items():
            if not (pd.api.types.is_numeric_dtype(dtype) or pd.api.types.is_bool_dtype(dtype)) or \
                    pd.api.types.is_complex_dtype(dtype):
                raise TypeError(f"{label} column {str(col)!r} must hold real numbers, got dtype {dtype}")
        ns, tz = _stamps(frame.index, label)
        cols = [(prefix or "y0") if c is None else str(c) if prefix is None else f"{prefix}.{c}"
                for c in frame.columns]
        topics.append(_Topic(label, list(frame.columns), cols, ns, frame.to_numpy(dtype=np.float64), tz))
    zones = {str(t.tz) for t in topics}
    if len(zones) > 1:
        raise ValueError(f"frames mix time kinds (elapsed time and date-times, or time zones: {sorted(zones)}): "
                         "give every topic the same kind of time index")
    names = [c for t in topics for c in t.columns]
    dup = sorted({c for c in names if names.count(c) > 1})
    if dup:
        raise ValueError(f"frames give duplicate column names {dup}: rename them first")
    return topics


def align(frames: Any, fs: Any, *, method: str = "zoh", gaps: str = "split", max_gap: Any = None,
          nan_policy: str = "raise", min_length: Any = 10) -> list[pd.DataFrame]:
    """Put one or several time-stamped topics on one uniform time grid.

    Parameters
    ----------
    frames : mapping of str to DataFrame / Series, or one DataFrame
        The topics (e.g. the output of :func:`tsfdi.datasets.read_ulog`), each indexed by its time stamps: a
        ``TimedeltaIndex``, a ``DatetimeIndex`` or numbers in seconds; stamps may repeat but never go back. An
        ``xarray.DataArray`` / ``Dataset`` with a time coordinate is accepted in place of a frame.
    fs : float or time span
        Grid rate in Hz (``50``), or the grid period (``"20ms"``). The period is rounded to a whole nanosecond.
    method : {"zoh", "linear"}
        ``"zoh"`` (zero-order hold, causal): the value at grid time ``t`` is the last sample stamped at or before
        ``t`` (the last one logged when several share its stamp). ``"linear"``: linear interpolation between that
        sample and the next one. **Linear interpolation is not causal**: the value at ``t`` uses the first sample
        after ``t``, up to one source period in the future, so residuals computed on it see that much ahead.
    gaps : {"split", "raise"}
        What to do with a grid time that falls strictly inside a gap of a topic (two consecutive samples further
        apart than ``max_gap``): ``"split"`` ends the record before it and starts the next one after the gap;
        ``"raise"`` raises a ``ValueError`` naming the topic, the time and the length of the gap.
    max_gap : time span, optional
        The longest step between two samples of a topic that is not a gap. Default, per topic:
        :data:`MAX_GAP_FACTOR` (3) times the topic's median step, and at least one grid period.
    nan_policy : {"raise", "omit"}
        What to do with a non-finite (NaN or inf) sample used by a grid time: one held or interpolated, or any
        sample logged since the previous grid time (a sub-sampled NaN is not hidden). ``"raise"``: a
        ``ValueError`` naming the topic, the column and the time of the first one; ``"omit"``: those grid times
        are left out and the record is split there.
    min_length : int or time span
        Records shorter than this (samples, or a time span at ``fs``; default 10 samples) are left out with a
        ``TsfdiWarning`` giving their number and times.

    Returns
    -------
    list of pandas.DataFrame
        The records, in time order; always a list, of one record when there is no gap and no NaN. Each has a
        uniform index named ``"time"`` (a ``TimedeltaIndex`` for elapsed time or seconds, a ``DatetimeIndex`` in
        the input's time zone for date-times) and float64 columns (booleans as 0 / 1): a single frame's own
        column names; for a
        mapping, ``"<topic>.<column>"`` (``"vehicle_attitude.q[0]"``; an unnamed Series is named by its key).
        A single DataFrame's ``attrs`` are copied to every record.
        The list can be passed to the models as several records of one process (``tsfdi.VAR(records, ...)``).

    Notes
    -----
    The grid is ``t_k = t_0 + k / fs`` with ``t_0`` the first multiple of the period (counted from time 0, or
    the Unix epoch for date-times) at which every topic has a sample, up to the last time at which every topic
    still has one. With ``method="zoh"`` every value is a logged sample, bit for bit (as float64).

    Raises
    ------
    ValueError
        An empty topic, a time index that goes back in time or has NaT, topics without a common time span, a gap
        (``gaps="raise"``) or a NaN (``nan_policy="raise"``), duplicate column names, time kinds mixed across
        topics, no record of ``min_length`` samples, or a grid larger than 2**28 values.
    TypeError
        ``frames`` of the wrong kind, a topic without a time index, non-numeric columns.
    """
    method = option(method, "method", ("zoh", "linear"))
    gaps = option(gaps, "gaps", ("split", "raise"))
    nan_policy = option(nan_policy, "nan_policy", ("raise", "omit"))
    period = _period(fs)
    user_gap = None if max_gap is None else _nanoseconds(max_gap, "max_gap")
    min_length = window_samples(min_length, "min_length", _NS / period, minimum=1)
    topics = _topics(frames)
    first = max(topics, key=lambda t: t.ns[0])
    last = min(topics, key=lambda t: t.ns[-1])
    tz = first.tz
    start = -(-int(first.ns[0]) // period) * period
    if start > last.ns[-1]:
        raise ValueError(f"frames have no common time span at {_NS / period:g} Hz: {first.label} starts at "
                         f"{_time(first.ns[0], tz)} but {last.label} ends at {_time(last.ns[-1], tz)}")
    n = (int(last.ns[-1]) - start) // period + 1
    ncol = sum(len(t.columns) for t in topics)
    if n * ncol > MAX_VALUES:
        raise ValueError(f"fs = {_NS / period:g} Hz over {(n - 1) * period / _NS:g} s gives {n} x {ncol} values, "
                         f"more than {MAX_VALUES}: lower fs")
    grid = start + period * np.arange(n, dtype=np.int64)
    columns, blocks = [], []
    valid = np.ones(n, dtype=bool)
    for label, fields, cols, ns, values, _ in topics:
        prev = np.searchsorted(ns, grid, side="right") - 1          # >= 0: the grid starts after every first stamp
        nxt = np.minimum(prev + 1, len(ns) - 1)
        exact = ns[prev] == grid
        step = ns[nxt] - ns[prev]
        steps = np.diff(ns)
        limit = user_gap if user_gap is not None else max(MAX_GAP_FACTOR * int(np.median(steps)) if steps.size
                                                          else 0, period)
        in_gap = ~exact & (step > limit)
        if in_gap.any():
            k = int(np.argmax(in_gap))
            if gaps == "raise":
                raise ValueError(f"{label} has a gap of {step[k] / _NS:g} s after {_time(ns[prev[k]], tz)} (longer "
                                 f"than max_gap = {limit / _NS:g} s); gaps='split' cuts the records there")
            valid &= ~in_gap
        if method == "zoh":
            block = values[prev]
        else:
            w = np.where(exact, 0.0, (grid - ns[prev]) / np.where(step > 0, step, 1))[:, None]
            with np.errstate(invalid="ignore"):
                block = np.where(w > 0, values[prev] + w * (values[nxt] - values[prev]), values[prev])
        # non-finite samples: held / interpolated ones, and any logged since the previous grid time
        bad = ~np.isfinite(values).all(axis=1)
        count = np.concatenate([[0], np.cumsum(bad)])
        since = np.searchsorted(ns, grid - period, side="right")
        used = (count[prev + 1] > count[since]) | ~np.isfinite(block).all(axis=1)
        if used.any():
            k = int(np.argmax(used))
            lo, hi = min(int(since[k]), int(prev[k])), int(nxt[k] if method == "linear" else prev[k])
            i = lo + int(np.argmax(bad[lo:hi + 1]))
            if nan_policy == "raise":
                col = fields[int(np.argmax(~np.isfinite(values[i])))]
                raise ValueError(f"{label} column {str(col)!r} is {values[i][~np.isfinite(values[i])][0]} at "
                                 f"{_time(ns[i], tz)} (sample {i}); nan_policy='omit' leaves such times out and "
                                 "splits the records there")
            valid &= ~used
        columns += cols
        blocks.append(block)
    values = np.concatenate(blocks, axis=1)
    if tz == "relative":
        index = pd.TimedeltaIndex(grid.astype("timedelta64[ns]"), name="time")
    else:
        index = pd.DatetimeIndex(grid.astype("datetime64[ns]"), name="time")
        index = index.tz_localize("UTC").tz_convert(tz) if tz is not None else index
    pieces = runs(valid)
    short = [(a, b) for a, b in pieces if b - a < min_length]
    if short:
        spans = ", ".join(f"{_time(grid[a], tz)} ({b - a})" for a, b in short[:5])
        warnings.warn(f"align: {len(short)} record(s) shorter than min_length = {min_length} samples left out: "
                      f"{spans}{', ...' if len(short) > 5 else ''}", TsfdiWarning, stacklevel=2)
    records = [pd.DataFrame(values[a:b], index=index[a:b], columns=columns) for a, b in pieces if b - a >= min_length]
    if not records:
        raise ValueError(f"align: no record of at least min_length = {min_length} samples at {_NS / period:g} Hz "
                         f"({len(pieces)} shorter one(s) between gaps / NaNs)")
    for r in records if isinstance(frames, pd.DataFrame) else ():
        r.attrs = dict(frames.attrs)
    return records

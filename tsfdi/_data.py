"""The one place where numpy / pandas / xarray input becomes an array and results go back.

Convention (decided once for the whole package): **time is axis 0**. A scalar signal is 1-D ``(nobs,)``;
a vector signal is 2-D ``(nobs, nchan)``. For an xarray ``DataArray`` the time dimension is the one named
``"time"`` if present, otherwise the first dimension; the other dimension (if any) holds the channels.

Results are wrapped back in the caller's kind: a numpy array for numpy input, a ``Series`` /
``DataFrame`` with the sliced original index for pandas input, and a ``DataArray`` with the sliced time
coordinate for xarray input. Residuals of a model with ``lags`` lags lose the first ``lags`` samples, so
their index starts at the original index's position ``lags``.

Time index (decided here for every entry point: model fitting, residuals, detection, monitoring). A time index is
a ``DatetimeIndex`` / ``TimedeltaIndex`` or a numeric index named ``"time"`` (seconds) of a pandas object, or the
time coordinate of an xarray object (date-times, time spans or numbers in seconds). :func:`as_signal` checks it
with :func:`time_step`: it must be strictly increasing and uniformly sampled, every step within :data:`JITTER`
(10 %) of the median step. A non-increasing stamp, a duplicated stamp, a jitter or a gap (one missing sample is
already a step of twice the median) raises a ``ValueError`` naming the argument (the record of a list), the time
and the size of the step, and the fix: resample with :func:`tsfdi.align` or split the signal there. A
``RangeIndex``, any other numeric index and a numpy array carry positions, not stamps, and are accepted as they
are. :func:`sampling_frequency` reads ``fs`` from the time index, and refuses a given ``fs`` that disagrees with it
by more than :data:`FS_TOLERANCE` (1 %). Two signals paired sample by sample (``y`` and ``u``) must have the same
index when both carry one (:func:`check_paired`): nothing is aligned silently.
"""

from __future__ import annotations

import datetime
import lzma
import math
import numbers
import tarfile
import zipfile
import zlib
from dataclasses import dataclass, field
from typing import Any

import numba
import numpy as np
import pandas as pd

from tsfdi._validation import float_like, int_like

__all__ = ["FS_TOLERANCE", "JITTER", "Signal", "as_signal", "channel_extremes", "check_paired", "is_xarray", "read_csv",
           "refuse_masked", "rolling_variance", "runs", "sampling_frequency", "time_step", "window_samples"]

#: a time index is uniformly sampled when every step lies within this fraction of its median step
JITTER = 0.1
#: largest relative disagreement between a given ``fs`` and the rate of the signal's time index
FS_TOLERANCE = 0.01


def is_xarray(obj: Any) -> bool:
    """True for an ``xarray.DataArray`` without importing xarray when it is not loaded."""
    return type(obj).__module__.startswith("xarray") and hasattr(obj, "dims") and hasattr(obj, "values")


@dataclass(frozen=True)
class Signal:
    """A validated signal as a float64 ``(nobs, nchan)`` array plus what is needed to wrap results.

    Attributes
    ----------
    values : ndarray, shape (nobs, nchan)
        The data, float64, finite, C-contiguous.
    kind : {"numpy", "pandas", "xarray"}
        Kind of the caller's object.
    vector : bool
        Whether the caller passed a vector (2-D) signal; scalar results are returned 1-D.
    index : pandas.Index or None
        Time index (pandas) or time coordinate values (xarray); ``None`` for numpy.
    channels : list of str
        Channel names (column names, channel coordinate values, or ``"y0", "y1", ...``).
    name : str or None
        Series / DataArray name.
    time_dim, channel_dim : str
        xarray dimension names used when wrapping.
    """

    values: np.ndarray
    kind: str
    vector: bool
    index: pd.Index | None = None
    channels: list = field(default_factory=list)
    name: Any = None
    time_dim: str = "time"
    channel_dim: str = "channel"

    @property
    def nobs(self) -> int:
        return self.values.shape[0]

    @property
    def nchan(self) -> int:
        return self.values.shape[1]

    @property
    def named(self) -> bool:
        """Whether the channels carry the caller's names (a DataFrame's columns, a DataArray's channel
        coordinate) rather than positions (numpy, a Series, a DataArray without channel coordinate: the
        placeholder names ``y0, y1, ...`` count as positions)."""
        return (self.kind != "numpy" and self.vector
                and list(self.channels) != [f"y{i}" for i in range(self.nchan)])

    def match_channels(self, channels: Any, name: str, *, named: bool = True,
                       reference: str = "the model was fitted on") -> "Signal":
        """This signal with its channels in the order of ``channels``.

        A named signal matched against named ``channels`` (``named=True``: the model was fitted on named data)
        is reordered by name; a missing or an extra channel raises a ``ValueError`` naming it. Otherwise the
        channels are matched by position and only their number is checked. ``reference`` says where ``channels``
        come from in the message (``"{reference} channels [...]"``).
        """
        channels = [str(c) for c in channels]
        if not (named and self.named):
            if self.nchan != len(channels):
                raise ValueError(f"{name} has {self.nchan} channel(s) but {reference} {len(channels)} "
                                 f"({channels})")
            return self
        have = [str(c) for c in self.channels]
        if len(set(have)) != len(have):
            raise ValueError(f"{name} has duplicate channel names: {have}")
        missing = [c for c in channels if c not in have]
        extra = [c for c in have if c not in channels]
        if missing or extra:
            what = "; ".join(p for p in (f"missing channel(s) {missing}" if missing else "",
                                         f"extra channel(s) {extra}" if extra else "") if p)
            raise ValueError(f"{name}: {what}; {reference} channels {channels}")
        if have == channels:
            return self
        order = [have.index(c) for c in channels]
        return Signal(values=np.ascontiguousarray(self.values[:, order]), kind=self.kind, vector=self.vector,
                      index=self.index, channels=channels, name=self.name, time_dim=self.time_dim,
                      channel_dim=self.channel_dim)

    def channel(self, j: int) -> "Signal":
        """Channel ``j`` alone as a scalar signal named after it (what a ``Series`` of that channel gives), with
        its extremes (:func:`channel_extremes`) when this signal has them already."""
        name = self.channels[j]
        out = Signal(values=np.ascontiguousarray(self.values[:, j:j + 1]), kind=self.kind, vector=False,
                     index=self.index, channels=[name], name=name, time_dim=self.time_dim,
                     channel_dim=self.channel_dim)
        kept = self.__dict__.get("_extremes")
        if kept is not None:
            object.__setattr__(out, "_extremes", (kept[0][j:j + 1], kept[1][j:j + 1]))
        return out

    def wrap(self, values: np.ndarray, start: int = 0, *, channels: list | None = None,
             name: Any = None, vector: bool | None = None) -> Any:
        """Wrap an array whose rows are the samples ``start, start + 1, ...`` of this signal.

        Parameters
        ----------
        values : ndarray, shape (m,) or (m, k)
            Rows aligned with samples ``start .. start + m - 1`` of the input.
        start : int
            Position of the first row in the original time index.
        channels : list, optional
            Column names for ``k`` columns (defaults to this signal's channels).
        name : optional
            Name of a scalar result (defaults to the signal's name).
        vector : bool, optional
            Force a 2-D (True) or 1-D (False) result; defaults to the input's shape.
        """
        values = np.asarray(values)
        if values.ndim == 1:
            values = values[:, None]
        m = values.shape[0]
        vector = self.vector if vector is None else vector
        if channels is None:
            channels = self.channels if values.shape[1] == self.nchan else [f"y{i}" for i in range(values.shape[1])]
        name = self.name if name is None else name
        if not vector:
            values = values[:, 0]
        if self.kind == "numpy":
            return values
        index = self.index[start:start + m]
        if len(index) != m:
            raise ValueError(f"cannot wrap {m} rows starting at {start} on an index of length {len(self.index)}")
        if self.kind == "pandas":
            if vector:
                return pd.DataFrame(values, index=index, columns=list(channels))
            return pd.Series(values, index=index, name=name)
        import xarray as xr

        if vector:
            return xr.DataArray(values, dims=(self.time_dim, self.channel_dim),
                                coords={self.time_dim: np.asarray(index), self.channel_dim: list(channels)},
                                name=name)
        return xr.DataArray(values, dims=(self.time_dim,), coords={self.time_dim: np.asarray(index)}, name=name)


def _numeric(arr: np.ndarray, name: str) -> np.ndarray:
    """``arr`` as float64: integers and floats as they are, an object array of numbers converted; booleans,
    complex numbers, strings, datetimes and timedeltas refused."""
    if arr.dtype.kind == "O":
        text = next((v for v in arr.flat if isinstance(v, (str, bytes))), None)
        if text is not None:     # as a string dtype is: numbers written as text are not parsed silently
            raise TypeError(f"{name} must contain real numbers, got text ({text!r}) in an object array: convert "
                            "it first, e.g. with pandas.to_numeric")
        try:
            arr = arr.astype(np.float64)
        except OverflowError:
            raise ValueError(f"{name} holds a number too large for float64") from None
        except (TypeError, ValueError):
            raise TypeError(f"{name} must contain real numbers, got non-numeric values") from None
    elif arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must contain real numbers, got dtype {arr.dtype}")
    return np.ascontiguousarray(arr, dtype=np.float64)


def refuse_masked(value: Any, name: str) -> None:
    """Raise a ``ValueError`` naming ``name`` if ``value`` is a numpy masked array with masked entries.

    tsfdi has no notion of a masked sample: a masked value is never used as data. A masked array whose mask is
    empty is plain data.
    """
    if isinstance(value, np.ma.MaskedArray) and np.ma.is_masked(value):
        mask = np.ma.getmaskarray(value)
        first = int(np.argwhere(mask)[0, 0]) if mask.ndim else 0
        raise ValueError(f"{name} is a masked array with {int(mask.sum())} masked value(s) (first at sample "
                         f"{first}): fill or drop the masked values first")


def as_signal(data: Any, name: str = "y", *, vector: bool | None = None, min_nobs: int = 1,
              allow_constant: bool = False, finite: bool = True) -> Signal:
    """Validate ``data`` and return a :class:`Signal`.

    Parameters
    ----------
    data : array_like, pandas.Series, pandas.DataFrame or xarray.DataArray
        Time on axis 0 (numpy / pandas) or along the ``"time"`` (else first) dimension (xarray).
    name : str
        Argument name used in error messages.
    vector : bool, optional
        ``False``: a scalar signal is required (1-D, or 2-D with one column). ``True``: a 2-D signal is
        required. ``None``: either.
    min_nobs : int
        Minimum number of samples; the message states it.
    allow_constant : bool
        Reject channels with zero variance unless True.
    finite : bool
        Reject NaN / inf unless False.

    Raises
    ------
    TypeError
        Non-numeric data or an unsupported container.
    ValueError
        Wrong number of dimensions, too few samples, non-finite or constant values.
    """
    if isinstance(data, Signal):    # already validated (finite, numeric); re-check what depends on the caller
        if vector is False and data.nchan != 1:
            raise ValueError(f"{name} must be a scalar signal (1-D or one column), got {data.nchan} channels")
        if data.nobs < min_nobs:
            raise ValueError(f"{name} is too short: {data.nobs} samples, at least {min_nobs} are needed")
        return data
    kind, index, channels, sname, time_dim, channel_dim = "numpy", None, None, None, "time", "channel"
    if type(data) is np.ndarray:    # the common case first (a plain array: not masked, no container checks)
        arr = data
    elif isinstance(data, pd.Series):
        kind, index, sname = "pandas", data.index, data.name
        arr = data.to_numpy()
    elif isinstance(data, pd.DataFrame):
        kind, index, channels = "pandas", data.index, [str(c) for c in data.columns]
        try:
            arr = data.to_numpy(dtype=np.float64) if all(
                pd.api.types.is_numeric_dtype(t) and not pd.api.types.is_bool_dtype(t) for t in data.dtypes
            ) else data.to_numpy()
        except (TypeError, ValueError):
            raise TypeError(f"{name} must contain real numbers") from None
    elif is_xarray(data):
        kind, sname = "xarray", data.name
        dims = list(data.dims)
        if len(dims) not in (1, 2):
            raise ValueError(f"{name} must have 1 or 2 dimensions (time[, channel]), got dims {tuple(dims)}")
        time_dim = "time" if "time" in dims else dims[0]
        if len(dims) == 2:
            channel_dim = dims[1] if dims[0] == time_dim else dims[0]
            data = data.transpose(time_dim, channel_dim)
            channels = ([str(c) for c in data[channel_dim].values] if channel_dim in data.coords
                        else [f"y{i}" for i in range(data.sizes[channel_dim])])
        index = pd.Index(data[time_dim].values) if time_dim in data.coords else pd.RangeIndex(data.sizes[time_dim])
        arr = data.values
    elif isinstance(data, (np.ndarray, list, tuple)) or np.isscalar(data):
        refuse_masked(data, name)
        if isinstance(data, (list, tuple)):
            for i, item in enumerate(data):
                refuse_masked(item, f"{name}[{i}]")
        try:
            arr = np.asarray(data)
        except (TypeError, ValueError) as exc:     # ragged nested sequences
            raise ValueError(f"{name} must be a rectangular (nobs,) or (nobs, nchan) array of numbers: {exc}") from None
    else:
        raise TypeError(f"{name} must be a numpy array, pandas Series/DataFrame or xarray DataArray, "
                        f"got {type(data).__name__}")
    arr = _numeric(np.asarray(arr), name)
    if arr.ndim not in (1, 2):
        raise ValueError(f"{name} must be 1-D (nobs,) or 2-D (nobs, nchan), got {arr.ndim}-D with shape {arr.shape}")
    was_vector = arr.ndim == 2
    if vector is False and was_vector and arr.shape[1] != 1:
        raise ValueError(f"{name} must be a scalar signal (1-D or one column), got shape {arr.shape}")
    if vector is True and not was_vector:
        raise ValueError(f"{name} must be a 2-D (nobs, nchan) vector signal, got shape {arr.shape}")
    if vector is False:
        was_vector = False
    if arr.ndim == 1:
        arr = arr[:, None]
    if channels is None:
        channels = [str(sname)] if (not was_vector and sname is not None) else [f"y{i}" for i in range(arr.shape[1])]
    if arr.shape[1] == 0:
        raise ValueError(f"{name} has no channels")
    if arr.shape[0] < min_nobs:
        raise ValueError(f"{name} is too short: {arr.shape[0]} samples, at least {min_nobs} are needed")
    extremes, spreads, passed = None, None, False
    if not allow_constant and arr.shape[0] > 1:     # each channel's extremes, kept for channel_extremes
        cols = np.ascontiguousarray(arr.T)        # reductions along contiguous rows: ~30x faster than axis 0
        extremes = (np.maximum.reduce(cols, axis=1), np.minimum.reduce(cols, axis=1))
        # every spread positive and finite: finite values, none constant (a few channels: Python's arithmetic costs
        # less than numpy's calls, and an overflow or inf - inf gives inf / nan without a RuntimeWarning); otherwise
        # the checks below say which
        spreads = [hi - lo for hi, lo in zip(extremes[0].tolist(), extremes[1].tolist())]
        passed = all(0.0 < d < math.inf for d in spreads)
    # finite extremes with a finite spread mean finite values (a NaN propagates to both extremes, an inf shows in
    # one); a spread that is not finite (or an overflow of it) leaves the decision to the scan of every value
    if not passed and finite and (spreads is None or not all(math.isfinite(d) for d in spreads)) \
            and not np.isfinite(arr).all():
        bad = int((~np.isfinite(arr)).sum())
        first = int(np.argwhere(~np.isfinite(arr))[0, 0])
        raise ValueError(f"{name} contains {bad} NaN/inf value(s) (first at sample {first}); "
                         "remove or interpolate them first")
    if not passed and extremes is not None:
        const = extremes[0] == extremes[1]
        if const.any():
            which = [channels[i] for i in np.flatnonzero(const)]
            raise ValueError(f"{name} is constant in channel(s) {which}: a model cannot be identified from it")
    if index is not None:
        time_step(index, name, numeric=_numeric_time(kind, index))
    # arr is contiguous (_numeric's copy, or a column added to it) and channels a list made here
    sig = Signal(values=arr, kind=kind, vector=was_vector, index=index, channels=channels, name=sname,
                 time_dim=time_dim, channel_dim=channel_dim)
    if extremes is not None:    # not a field: a Signal made from this one (dataclasses.replace, ...) computes its own
        object.__setattr__(sig, "_extremes", extremes)
    return sig


def channel_extremes(signal: Signal) -> tuple[np.ndarray, np.ndarray]:
    """Largest and smallest value of every channel of ``signal`` (two arrays of shape ``(nchan,)``, not to be
    modified): the ones :func:`as_signal` computed for its checks when it made this very object, else computed
    here once and kept with it (a signal's values are not changed after it is made)."""
    kept = signal.__dict__.get("_extremes")
    if kept is None:
        cols = np.ascontiguousarray(signal.values.T)
        kept = (cols.max(axis=1), cols.min(axis=1))
        object.__setattr__(signal, "_extremes", kept)
    return kept


def _numeric_time(kind: str, index: pd.Index | None) -> bool:
    """Whether a numeric ``index`` holds time stamps in seconds: an xarray time coordinate, or a pandas index
    named ``"time"``."""
    return index is not None and (kind == "xarray" or index.name == "time")


def check_paired(a: Signal, b: Signal, names: tuple[str, str] = ("y", "u")) -> None:
    """Raise a ``ValueError`` naming both when two signals paired sample by sample carry different indexes.

    Signals of the same length are paired by position; when both carry an index (pandas, xarray) it must be the
    same, so that sample ``t`` of one is sample ``t`` of the other. Nothing is aligned silently.
    """
    ia, ib = a.index, b.index
    if ia is None or ib is None or len(ia) != len(ib) or ia.equals(ib):
        return
    try:
        diff = np.flatnonzero(~np.asarray(ia == ib, dtype=bool))
    except (TypeError, ValueError):      # indexes of different kinds (time zones, date-times and numbers)
        diff = np.zeros(1, dtype=np.int64)
    i = int(diff[0]) if diff.size else 0
    a_i, b_i = (v.item() if isinstance(v, np.generic) else v for v in (ia[i], ib[i]))
    raise ValueError(f"{names[0]} and {names[1]} have different indexes (first at sample {i}: {a_i!r} in "
                     f"{names[0]}, {b_i!r} in {names[1]}): they are paired sample by sample; give them the same "
                     f"index (e.g. {names[1]}.reindex({names[0]}.index) after checking that nothing is missing) or "
                     "pass arrays to pair them by position")


def model_input(u: Any, sig: Signal, inputs: tuple | None) -> Signal | None:
    """The input ``u`` of the samples ``sig`` for models fitted with ``inputs`` (``(channels, named)``: their input
    channels and whether they are named; ``None`` for models without input), in the models' input order.

    ``u`` is required for input-output (ARX) models and refused for the others (``TypeError``); it must be as long as
    ``sig``, carry the same index when both carry one (:func:`check_paired`) and hold the models' inputs (by name
    when both are named, else by position).
    """
    if inputs is None:
        if u is not None:
            raise TypeError("u is only for input-output (ARX) models: these models have no exogenous input; leave "
                            "u out")
        return None
    if u is None:
        raise TypeError("u is required: the models are ARX (input-output) models; pass the samples' input as u=")
    usig = as_signal(u, "u", allow_constant=True)
    if usig.nobs != sig.nobs:
        raise ValueError(f"u has {usig.nobs} samples but signal has {sig.nobs}: they must match")
    check_paired(sig, usig, ("signal", "u"))
    channels, named = inputs
    return usig.match_channels(channels, "u", named=named, reference="the models were fitted with")


def _format_time(value: Any) -> str:
    """A time stamp for a message: ISO format for a date-time, seconds otherwise."""
    if isinstance(value, (pd.Timestamp, np.datetime64)):
        return pd.Timestamp(value).isoformat()
    if isinstance(value, (pd.Timedelta, np.timedelta64)):
        return f"{pd.Timedelta(value).total_seconds():g} s"
    return f"{float(value):g} s"


#: the fix the even-sampling messages name, in Python (the command line names its flags instead)
RESAMPLE_FIX = "put it on a uniform grid with tsfdi.align(..., gaps='split'), or split the signal at the gap"


def time_step(index: pd.Index | None, name: str, *, numeric: bool = False, row: Any = None,
              fix: str = RESAMPLE_FIX) -> float | None:
    """Median step in seconds of a uniformly sampled time index; ``None`` when the index carries no time.

    A ``DatetimeIndex`` / ``TimedeltaIndex`` is a time index; a numeric index is one (in seconds) when ``numeric``
    is true. The index must be strictly increasing and every step ``d_i`` must satisfy
    ``|d_i - median(d)| <= JITTER * median(d)`` (:data:`JITTER` = 10 %). This is the one even-sampling rule of
    the package (Python and command line); its messages speak of the time index and its fix only.

    Parameters
    ----------
    index : pandas.Index or None
        The time stamps.
    name : str
        What the index belongs to, for messages (an argument, a record, a file).
    numeric : bool
        Whether a numeric index is read as seconds (else it carries positions and is not checked).
    row : callable, optional
        ``row(i)`` names sample ``i`` in messages (e.g. ``"line 252"`` of a CSV file); default ``"sample i"``.
    fix : str
        The fix the messages name (:data:`RESAMPLE_FIX`; :func:`tsfdi.read_records` names its own keywords).

    Raises
    ------
    ValueError
        Naming ``name``, the position and the time of the first missing (NaT / NaN), non-increasing or
        non-uniform step with its size, and the fix: resample with :func:`tsfdi.align`, or split.
    """
    if index is None or len(index) < 2 or isinstance(index, pd.RangeIndex):
        return None
    stamps = isinstance(index, (pd.DatetimeIndex, pd.TimedeltaIndex))
    if not (stamps or (numeric and pd.api.types.is_numeric_dtype(index.dtype)
                       and not pd.api.types.is_bool_dtype(index.dtype))):
        return None
    row = row or (lambda i: f"sample {i}")
    if index.hasnans:
        raise ValueError(f"{name} has a missing time stamp (NaT / NaN) at {row(int(np.argmax(index.isna())))} "
                         "of its time index")
    if stamps:      # integers in the index's own unit (UTC for a time zone)
        steps = np.diff(index.asi8) / {"s": 1.0, "ms": 1e3, "us": 1e6, "ns": 1e9}[index.unit]
    else:
        steps = np.diff(np.asarray(index, dtype=np.float64))
    bad = np.flatnonzero(~(steps > 0))
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"{name} has a time index that is not strictly increasing: {row(i + 1)} at "
                         f"{_format_time(index[i + 1])} follows {_format_time(index[i])}; sort it, or {fix}")
    dt = float(np.median(steps))
    bad = np.flatnonzero(np.abs(steps - dt) > JITTER * dt)
    if bad.size:
        i = int(bad[0])
        what = "gap" if steps[i] > dt else "short step"
        raise ValueError(f"{name} is not uniformly sampled: a {what} of {steps[i]:g} s after {row(i)} at "
                         f"{_format_time(index[i])} (median step {dt:g} s; every step must be within "
                         f"{JITTER:.0%} of it); {fix}")
    return dt


def sampling_frequency(signal: Signal, fs: Any = None, name: str = "signal") -> float | None:
    """Sampling frequency in Hz: ``fs`` when given, else read from the signal's time index, else ``None``.

    A ``DatetimeIndex`` / ``TimedeltaIndex`` gives ``1 / median(step)`` in seconds; a numeric index named
    ``"time"`` (pandas) or a numeric xarray time coordinate is taken to be in seconds. The index must be uniformly
    sampled (:func:`time_step`): a gap or a jitter beyond :data:`JITTER` raises a ``ValueError`` naming ``name``.
    A ``RangeIndex`` or a numpy array carries no time. A given ``fs`` that disagrees with the time index's rate by
    more than :data:`FS_TOLERANCE` (1 %) raises a ``ValueError`` naming both.
    """
    rate = None if fs is None else float_like(fs, "fs", minimum=0.0, strict_min=True)
    idx = signal.index
    dt = time_step(idx, name, numeric=_numeric_time(signal.kind, idx))
    if dt is None or rate is None:
        return rate if dt is None else 1.0 / dt
    if not abs(rate * dt - 1.0) <= FS_TOLERANCE:
        unit = "" if isinstance(idx, (pd.DatetimeIndex, pd.TimedeltaIndex)) else " (a numeric time index is in seconds)"
        raise ValueError(f"fs = {rate:g} Hz disagrees with the time index of {name}{unit}, sampled at {1.0 / dt:g} Hz "
                         f"(median step {dt:g} s), by more than {FS_TOLERANCE:.0%}: leave fs out to use the index, "
                         "or resample with tsfdi.align")
    return rate


def window_samples(value: Any, name: str, fs: float | None, *, minimum: int = 1) -> int:
    """A window length or step in samples, following pandas' ``rolling`` convention.

    An ``int`` counts samples; a time span (``"2s"``, ``pandas.Timedelta``, ``datetime.timedelta``,
    ``numpy.timedelta64``) is converted with the sampling frequency ``fs`` (Hz) and rounded to the nearest
    sample. Floats are refused: say ``"2.5s"`` for a time span.
    """
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be an int (samples) or a time span such as '2s', got {value!r}")
    # numpy counts timedelta64 as an integer type: time spans are recognised first
    if not isinstance(value, (str, pd.Timedelta, datetime.timedelta, np.timedelta64)) and isinstance(
            value, (numbers.Integral, np.integer)):
        n = int(value)
    elif isinstance(value, (str, pd.Timedelta, datetime.timedelta, np.timedelta64)):
        try:
            span = pd.Timedelta(value)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be an int (samples) or a time span such as '2s', got {value!r}") from None
        if span is pd.NaT:
            raise ValueError(f"{name} must be a time span such as '2s', got {value!r}")
        if fs is None:
            raise ValueError(f"{name} = {value!r} is a time span but the sampling frequency is unknown: give fs "
                             "or a signal with a time index, or count samples with an int")
        samples = span.total_seconds() * fs
        if not np.isfinite(samples):
            raise ValueError(f"{name} = {value!r} at fs = {fs:g} Hz is too many samples")
        n = int(round(samples))
        if n < minimum:
            raise ValueError(f"{name} = {value!r} is {n} sample(s) at fs = {fs:g} Hz; at least {minimum} are "
                             "needed")
    else:
        raise TypeError(f"{name} must be an int (samples) or a time span such as '2s', got {value!r} "
                        f"({type(value).__name__})")
    if n < minimum:
        raise ValueError(f"{name} must be >= {minimum} samples, got {n}")
    return n


def runs(mask: Any) -> list[tuple[int, int]]:
    """``(start, stop)`` of every run of True in a 1-D boolean ``mask``, in order (``mask[start:stop]`` all True)."""
    edges = np.flatnonzero(np.diff(np.r_[0, np.asarray(mask, dtype=np.int8), 0]))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


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
    # the channels as contiguous rows: numpy reduces axis 0 of an (n, k) array slowly for small k
    xt = np.ascontiguousarray(np.asarray(x, dtype=np.float64).T)
    starts = np.arange(0, n_all - window + 1, min(step, n_all))
    out = np.empty((starts.size, xt.shape[0]))
    _window_variances(xt, xt.mean(axis=1), starts, window, out)
    return out


@numba.njit(cache=True)
def _window_variances(xt, centre, starts, window, out):  # pragma: no cover - compiled
    """``out[w, c]``: variance of ``xt[c, starts[w]:starts[w] + window]`` from the running sums of ``x`` and ``x**2``
    of the signal less its mean ``centre`` (each sample less ``centre[c]`` as it is read: no centred copy), the prefix
    sums of ``numpy.cumsum``, in its order, read only at the window edges, clipped at 0. The sums run from one
    window edge to the next in a branch-free loop (no test of every sample against the edges)."""
    k, n = xt.shape
    m = starts.size
    s1 = np.zeros(k)
    s2 = np.zeros(k)
    a1 = np.empty((m, k))
    a2 = np.empty((m, k))
    w_lo = 0                    # next window whose start edge is due
    w_hi = 0                    # next window whose end edge is due
    t = 0
    while True:
        while w_lo < m and starts[w_lo] == t:
            for c in range(k):
                a1[w_lo, c] = s1[c]
                a2[w_lo, c] = s2[c]
            w_lo += 1
        while w_hi < m and starts[w_hi] + window == t:
            for c in range(k):
                mean = (s1[c] - a1[w_hi, c]) / window
                v = (s2[c] - a2[w_hi, c]) / window - mean * mean
                out[w_hi, c] = 0.0 if v < 0.0 else v     # (NaN kept, as numpy.maximum)
            w_hi += 1
        if w_hi == m:
            break
        nxt = starts[w_hi] + window             # the next edge: a window's end, or an earlier start
        if w_lo < m and starts[w_lo] < nxt:
            nxt = starts[w_lo]
        for c in range(k):
            acc1, acc2 = s1[c], s2[c]
            row, mc = xt[c], centre[c]
            for u in range(t, nxt):
                v = row[u] - mc
                acc1 += v
                acc2 += v * v
            s1[c], s2[c] = acc1, acc2
        t = nxt


def read_csv(path: Any, name: str = "path", **kwargs: Any) -> pd.DataFrame:
    """``pandas.read_csv(path, **kwargs)`` whose failures name the file.

    A missing file raises ``FileNotFoundError``; an empty file, text that does not parse, a file that is not
    what its compression suffix says (``.gz``, ``.zip``, ...), a truncated or undecodable file, or columns
    asked for in ``usecols`` that are not there raise a ``ValueError`` starting with ``name`` and the path.
    """
    try:
        return pd.read_csv(path, **kwargs)
    except FileNotFoundError:
        raise FileNotFoundError(f"{name}: {path} does not exist") from None
    except pd.errors.EmptyDataError:
        raise ValueError(f"{name}: {path} is empty (no header line)") from None
    except (ValueError, OSError, EOFError, ImportError, zlib.error, zipfile.BadZipFile, lzma.LZMAError,
            tarfile.TarError) as exc:
        raise ValueError(f"{name}: {path} cannot be read as a CSV file ({type(exc).__name__}: {exc})") from None

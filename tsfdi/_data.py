"""The one place where numpy / pandas / xarray input becomes an array and results go back.

Convention (decided once for the whole package): **time is axis 0**. A scalar signal is 1-D ``(nobs,)``;
a vector signal is 2-D ``(nobs, nchan)``. For an xarray ``DataArray`` the time dimension is the one named
``"time"`` if present, otherwise the first dimension; the other dimension (if any) holds the channels.

Results are wrapped back in the caller's kind: a numpy array for numpy input, a ``Series`` /
``DataFrame`` with the sliced original index for pandas input, and a ``DataArray`` with the sliced time
coordinate for xarray input. Residuals of a model with ``lags`` lags lose the first ``lags`` samples, so
their index starts at the original index's position ``lags``.
"""

from __future__ import annotations

import datetime
import lzma
import numbers
import tarfile
import zipfile
import zlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._validation import float_like, int_like

__all__ = ["Signal", "as_signal", "is_xarray", "read_csv", "refuse_masked", "rolling_variance", "sampling_frequency",
           "window_samples"]


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
        coordinate) rather than positions (numpy, a Series)."""
        return self.kind != "numpy" and self.vector

    def match_channels(self, channels: Any, name: str, *, named: bool = True) -> "Signal":
        """This signal with its channels in the order of ``channels``.

        A named signal matched against named ``channels`` (``named=True``: the model was fitted on named data)
        is reordered by name; a missing or an extra channel raises a ``ValueError`` naming it. Otherwise the
        channels are matched by position and only their number is checked.
        """
        channels = [str(c) for c in channels]
        if not (named and self.named):
            if self.nchan != len(channels):
                raise ValueError(f"{name} has {self.nchan} channel(s) but the model was fitted on {len(channels)} "
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
            raise ValueError(f"{name}: {what}; the model was fitted on channels {channels}")
        if have == channels:
            return self
        order = [have.index(c) for c in channels]
        return Signal(values=np.ascontiguousarray(self.values[:, order]), kind=self.kind, vector=self.vector,
                      index=self.index, channels=channels, name=self.name, time_dim=self.time_dim,
                      channel_dim=self.channel_dim)

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
    if isinstance(data, pd.Series):
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
    if finite and not np.isfinite(arr).all():
        bad = int((~np.isfinite(arr)).sum())
        first = int(np.argwhere(~np.isfinite(arr))[0, 0])
        raise ValueError(f"{name} contains {bad} NaN/inf value(s) (first at sample {first}); "
                         "remove or interpolate them first")
    if not allow_constant and arr.shape[0] > 1:
        cols = np.ascontiguousarray(arr.T)        # reductions along contiguous rows: ~30x faster than axis 0
        const = cols.max(axis=1) == cols.min(axis=1)
        if const.any():
            which = [channels[i] for i in np.flatnonzero(const)]
            raise ValueError(f"{name} is constant in channel(s) {which}: a model cannot be identified from it")
    return Signal(values=np.ascontiguousarray(arr), kind=kind, vector=was_vector, index=index,
                  channels=list(channels), name=sname, time_dim=time_dim, channel_dim=channel_dim)


def sampling_frequency(signal: Signal, fs: Any = None) -> float | None:
    """Sampling frequency in Hz: ``fs`` when given, else read from the signal's time index, else ``None``.

    A ``DatetimeIndex`` / ``TimedeltaIndex`` gives ``1 / median(spacing)`` in seconds; a numeric index named
    ``"time"`` (pandas) or a numeric xarray time coordinate is taken to be in seconds. A ``RangeIndex`` or a
    numpy array carries no time.
    """
    if fs is not None:
        return float_like(fs, "fs", minimum=0.0, strict_min=True)
    idx = signal.index
    if idx is None or len(idx) < 2 or isinstance(idx, pd.RangeIndex):
        return None
    if isinstance(idx, (pd.DatetimeIndex, pd.TimedeltaIndex)):
        dt = float(np.median(np.asarray((idx[1:] - idx[:-1]).total_seconds())))
    elif pd.api.types.is_numeric_dtype(idx.dtype) and (signal.kind == "xarray" or idx.name == "time"):
        dt = float(np.median(np.diff(np.asarray(idx, dtype=np.float64))))
    else:
        return None
    return 1.0 / dt if dt > 0 else None


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
    starts = np.arange(0, n_all - window + 1, min(step, n_all))
    m = (s1[starts + window] - s1[starts]) / window
    return np.maximum((s2[starts + window] - s2[starts]) / window - m * m, 0.0)


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

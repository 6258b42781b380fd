"""Baseline phase of paper 003: models of every state fitted on many records (Dutta et al., Table 2, Fig. 7).

:func:`fit_baselines` fits, for every aircraft state, a scalar AR model on each channel and a VAR model on all
channels with the order chosen by BIC (:func:`tsfdi.select_order`), and estimates the steady-state rolling-variance
thresholds; :attr:`Baselines.table` is the analogue of the paper's Table 2. :class:`Records` normalises many records
of the same channels (an xarray object or a sequence of signals).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import (Signal, as_signal, channel_extremes, is_xarray, refuse_masked, rolling_variance,
                         sampling_frequency, window_samples)
from tsfdi._validation import boolean, float_like, int_like, option, probability
from tsfdi.coverage import MIN_RECORDS, Coverage, coverage
from tsfdi.detection.base import ResidualTest
from tsfdi.detection.sequential import msprt_scale
from tsfdi.detection.whiteness import LjungBox, ljungbox_windows
from tsfdi.models import FPResults, select_fp_order
from tsfdi.monitoring import Monitor, operating_names, operating_points
from tsfdi.selection import select_order
from tsfdi.windows import RULES, SEQUENTIAL_RULES, ResidualWindows, status

__all__ = ["Baselines", "Records", "fit_baselines", "insample_q"]


@dataclass(frozen=True, eq=False)
class Records:
    """Many records of the same channels, normalised from an xarray object or a sequence of signals.

    Attributes
    ----------
    values : list of ndarray, each (nobs, k)
    state, turbulence : ndarray of str
    failure_time : ndarray of float (NaN for healthy records)
    ids : ndarray
        Record identifiers.
    valid : ndarray of bool
        False for records that cannot be used (lost control: NaN after the loss).
    channels : tuple of str
    fs : float
    source : xarray.Dataset or xarray.DataArray or None
        Records backed by dask, chunked along ``record`` (:func:`tsfdi.fleet.is_chunked`): the data itself, read
        where it is used (:meth:`read`, chunk by chunk by :func:`tsfdi.fleet.map_records`). ``values`` is then empty
        and ``valid`` reflects ``lost_control`` only: non-finite values are found when a record is read. ``None``
        for records in memory.
    length : int or None
        Samples of every record of ``source``.
    times : list of ndarray or None
        Per record, its time stamps in seconds (float64, ``(nobs,)``) on the clock of the file it was read from
        (:func:`tsfdi.read_records`); ``None`` when the records carry no time stamps.
    files : ndarray of str or None
        Per record, the file it was read from (:func:`tsfdi.read_records`); ``None`` for records not read from
        files. :attr:`ids` then names each record within its file: ``""`` for the single record of a CSV file, the
        ``record`` coordinate of a netCDF file, ``"0"``, ``"1"``, ... for the pieces a file is split into, and
        ``"2.0"``, ``"2.1"`` for the pieces of record 2.
    k : ndarray or None
        Per record, its operating point (float64, ``(records, d)``, columns :attr:`k_names`) read from the record
        coordinates named by ``k=`` (:meth:`from_data`): what a functionally pooled baseline is evaluated at
        (``res.at(k)``); ``None`` when no ``k`` was asked for.
    k_names : tuple of str
        The record coordinates :attr:`k` holds (empty without ``k``).
    """

    values: list
    state: np.ndarray
    turbulence: np.ndarray
    failure_time: np.ndarray
    ids: np.ndarray
    valid: np.ndarray
    channels: tuple
    fs: float
    source: Any = None
    length: int | None = None
    times: list | None = None
    files: np.ndarray | None = None
    k: np.ndarray | None = None
    k_names: tuple = ()

    @classmethod
    def from_data(cls, data: Any, *, states: Any = None, failure_times: Any = None, turbulence: Any = None,
                  fs: float | None = None, name: str = "data", check_finite: bool = True, k: Any = None) -> Records:
        """Build from a hexacopter ``Dataset``, a ``(record, time, channel)`` DataArray or a sequence of
        signals (numpy / pandas / xarray, each ``(nobs, k)``) with ``states`` (and optional ``failure_times``,
        ``turbulence``) given per record.

        ``check_finite=False`` leaves the records of a ``Dataset`` or ``DataArray`` in memory unread: :attr:`valid`
        then reflects ``lost_control`` only, and the caller checks the values of the records it uses (one pass over
        all the data otherwise; :func:`fit_baselines` reads only its fitting records). A sequence of signals is
        always checked (each signal is validated).

        Named records (``DataFrame``, ``DataArray`` with a channel coordinate) are put in the channel order of the
        first by name; a missing or an extra channel raises a ``ValueError`` naming the record and the channel.
        Without ``fs`` the sampling frequency comes from the time coordinate, or from the time index of the first
        record, else 1 Hz.

        A ``Dataset`` or ``DataArray`` backed by dask and chunked along ``record`` (:func:`tsfdi.fleet.is_chunked`)
        is not read: the labels, the channels and ``fs`` come from its coordinates, and the data stays in
        :attr:`source`.

        ``k`` (a name or a sequence of names) names the record coordinates holding each record's operating point
        (:attr:`k`, e.g. ``"speed"`` of a hexacopter fleet): numbers, finite for every record; a missing coordinate
        raises a ``ValueError`` naming ``k`` and the coordinate. A sequence of signals carries no coordinates: give
        such records as a ``(record, time, channel)`` DataArray with the coordinates."""
        check_finite = boolean(check_finite, "check_finite")
        k_names = operating_names(k)
        if isinstance(data, Records):
            if k is not None and k_names != data.k_names:
                raise ValueError(f"k names the coordinates {list(k_names)} but {name} is Records read with "
                                 f"k={list(data.k_names)}")
            return data
        import xarray as xr

        if k_names and not is_xarray(data):
            raise ValueError(f"k names record coordinates {list(k_names)}, but {name} is a sequence of signals, which "
                             "has none: give the records as a (record, time, channel) DataArray (or a hexacopter "
                             "Dataset) with those coordinates")

        from tsfdi.fleet import is_chunked

        if is_chunked(data):
            if isinstance(data, xr.Dataset):        # (lazily: the chunks will hold the signal variables only)
                from tsfdi.datasets.hexacopter import hexacopter_signals

                data = hexacopter_signals(data)
            if not (isinstance(data, xr.DataArray) and data.ndim == 3 and "time" in data.dims):
                raise TypeError(f"{name} backed by dask must be a hexacopter xarray.Dataset or a (record, time, "
                                f"channel) DataArray, got {type(data).__name__} with dims {data.dims}")
            st, tb, ft, ids, lost = _labels(data, states, failure_times, turbulence, name)
            # channels, fs and length from the coordinates: no record is read here (each chunk is read where used)
            third = next(d for d in data.dims if d not in ("record", "time"))
            fs_ = _time_rate(_coordinate(data, "time"), name) if fs is None else float_like(fs, "fs", minimum=0.0,
                                                                                            strict_min=True)
            return cls([], st, tb, ft, ids, ~lost, tuple(str(c) for c in _coordinate(data, third)), fs_,
                       source=data, length=int(data.sizes["time"]), k=operating_points(data, k_names, ids, name),
                       k_names=k_names)
        if isinstance(data, xr.Dataset):
            from tsfdi.datasets.hexacopter import hexacopter_signals

            data = hexacopter_signals(data)
        if isinstance(data, xr.DataArray) and data.ndim == 3 and "record" in data.dims:
            # (xarray's transpose costs ~0.2 ms even when the dimensions are in order already)
            da = data if data.dims[:2] == ("record", "time") else data.transpose("record", "time", ...)
            fs_ = _time_rate(_coordinate(da, "time"), name) if fs is None else float_like(fs, "fs", minimum=0.0,
                                                                                            strict_min=True)
            st, tb, ft, ids, lost = _labels(da, states, failure_times, turbulence, name)
            arr = np.asarray(da.values, dtype=np.float64)
            valid = ~lost
            if check_finite:
                # one pass over all records: a record's sum is finite when its values are (a finite sum that
                # overflows is rechecked value by value)
                with np.errstate(over="ignore", invalid="ignore"):
                    finite = np.isfinite(arr.sum(axis=(1, 2)))
                finite[~finite] = [np.isfinite(arr[i]).all() for i in np.flatnonzero(~finite)]
                valid &= finite
            vals = list(arr)
            chans = tuple(str(c) for c in _coordinate(da, da.dims[2]))
            return cls(vals, st, tb, ft, ids, valid, chans, fs_, k=operating_points(da, k_names, ids, name),
                       k_names=k_names)
        if isinstance(data, (str, bytes)) or not isinstance(data, Sequence) or len(data) == 0:
            raise TypeError(f"{name} must be a hexacopter xarray.Dataset, a (record, time, channel) DataArray or a "
                            f"non-empty sequence of signals, got {type(data).__name__}")
        if states is None:
            raise ValueError(f"states is required when {name} is a sequence of signals (one state per record)")
        sigs = [as_signal(d, f"{name}[{i}]", vector=True) for i, d in enumerate(data)]
        k = {s.nchan for s in sigs}
        if len(k) != 1:
            raise ValueError(f"every record of {name} must have the same number of channels, got {sorted(k)}")
        # named records (DataFrames, DataArrays with a channel coordinate) in the channel order of the first
        sigs = [sigs[0]] + [s.match_channels(sigs[0].channels, f"{name}[{i}]", named=sigs[0].named,
                                                 reference=f"{name}[0] has")
                            for i, s in enumerate(sigs[1:], start=1)]
        n = len(sigs)
        refuse_masked(states, "states")
        st = np.asarray(states).astype(str)
        if st.shape != (n,):
            raise ValueError(f"states must have one entry per record ({n}), got shape {st.shape}")
        ft = np.full(n, np.nan) if failure_times is None else _failure_times(failure_times, n)
        refuse_masked(turbulence, "turbulence")
        tb = np.full(n, "") if turbulence is None else np.asarray(turbulence).astype(str)
        if tb.shape != (n,):
            raise ValueError(f"turbulence must have one entry per record ({n}), got shape {tb.shape}")
        fs_ = sampling_frequency(sigs[0], fs, f"{name}[0]") or 1.0
        return cls([s.values for s in sigs], st, tb, ft, np.arange(n), np.ones(n, bool), tuple(sigs[0].channels),
                   fs_)

    def read(self, where: Any, chunk: Any = None) -> Records:
        """The records at positions ``where`` (a slice or an array of positions), in memory.

        Parameters
        ----------
        where : slice or array_like of int
        chunk : xarray.Dataset or xarray.DataArray, optional
            Those records of :attr:`source` already read (the chunk :func:`tsfdi.fleet.map_records` hands a
            worker); default: read them from :attr:`source` on the current dask scheduler.

        Returns
        -------
        Records
            With the labels and identifiers of those records (``source`` None).
        """
        if self.source is None and chunk is None:
            pos = np.arange(len(self.values))[where]
            return dataclasses.replace(self, values=[self.values[i] for i in pos], state=self.state[pos],
                                       turbulence=self.turbulence[pos], failure_time=self.failure_time[pos],
                                       ids=self.ids[pos], valid=self.valid[pos],
                                       times=None if self.times is None else [self.times[i] for i in pos],
                                       files=None if self.files is None else self.files[pos],
                                       k=None if self.k is None else self.k[pos])
        if chunk is None:
            chunk = self.source.isel(record=where).compute()
        out = Records.from_data(chunk, states=self.state[where], failure_times=self.failure_time[where],
                                turbulence=self.turbulence[where], fs=self.fs)
        # the operating points travel with the labels (read from the coordinates on the driver)
        return dataclasses.replace(out, ids=self.ids[where], k=None if self.k is None else self.k[where],
                                   k_names=self.k_names)

    def origin(self, i: int) -> str:
        """Where record ``i`` comes from, as messages name it: its file, with the record's :attr:`ids` entry when it
        has one (``"flight.csv"``, ``"sim.nc record 3"``); ``"record 3"`` for records not read from files."""
        rid = str(self.ids[i])
        if self.files is None:
            return f"record {rid}"
        return f"{self.files[i]} record {rid}" if rid else str(self.files[i])

    def names(self) -> list[str]:
        """A short name per record that tells it from the others, for the ``record`` column of a table.

        The :attr:`ids` of records read from one file (``""`` for a CSV file's single record) or from none; for
        records of several files (:func:`tsfdi.read_records` on a list), each file by the shortest tail of its path
        that tells it from the other files, with the record's id after a colon when it has one
        (``"normal_flight/E8_log00.csv.gz"``, ``"run2/sim.nc:3"``).
        """
        if self.files is None or len(set(self.files)) < 2:
            return [str(i) for i in self.ids]
        tails = _shortest_tails(list(dict.fromkeys(self.files)))
        return [f"{tails[f]}:{rid}" if str(rid) else tails[f] for f, rid in zip(self.files, self.ids)]

    def frames(self) -> list[pd.DataFrame]:
        """The records in memory as ``DataFrame``s: columns :attr:`channels`, index ``time`` in seconds (from
        :attr:`times`; a ``RangeIndex`` without them), ready for the models (``tsfdi.VAR(records.frames(), 4)``)."""
        if self.source is not None:
            raise ValueError("records backed by dask are not in memory: read them first with Records.read")
        return [pd.DataFrame(v, columns=list(self.channels),
                             index=None if self.times is None else pd.Index(self.times[i], name="time"))
                for i, v in enumerate(self.values)]


def _shortest_tails(files: list) -> dict:
    """File -> the shortest tail of its path that tells it from the other files (``normal_flight/E8_log00.csv.gz``)."""
    parts = {f: Path(f).parts or (f,) for f in files}
    for k in range(1, max(len(p) for p in parts.values()) + 1):
        tails = {f: "/".join(p[-k:]) for f, p in parts.items()}
        if len(set(tails.values())) == len(files):
            return tails
    return {f: str(f) for f in files}


def _labels(data: Any, states: Any, failure_times: Any, turbulence: Any, name: str) -> tuple:
    """State, turbulence, failure time, identifier and lost-control flag of every record of an xarray object with a
    ``record`` dimension, from its coordinates (and a ``lost_control`` variable) or the given labels."""
    import xarray as xr

    n = data.sizes["record"]
    keys = [k for k in ("state", "turbulence", "failure_time", "record") if k in data.coords]
    if "lost_control" in data.coords or (isinstance(data, xr.Dataset) and "lost_control" in data):
        keys.append("lost_control")
    # (the variables themselves: data[k] builds a DataArray with its coordinates for each, ~30x the cost)
    variables = data.variables if isinstance(data, xr.Dataset) else data.coords.variables
    found = {k: variables[k].values for k in keys}

    def coord(key, given, default):
        if given is not None:
            return np.asarray(given)
        return np.asarray(found[key]) if key in found else np.full(n, default)

    st = coord("state", states, None)
    if st[0] is None:
        raise ValueError(f"{name} needs a 'state' coordinate (or pass states=)")
    ids = np.asarray(found["record"]) if "record" in found else np.arange(n)
    return (st.astype(str), coord("turbulence", turbulence, "").astype(str),
            _failure_times(coord("failure_time", failure_times, np.nan), n), ids,
            coord("lost_control", None, False).astype(bool))


def _coordinate(da: Any, dim: str) -> np.ndarray:
    """The values of ``da[dim]``: from its index when it has one (the coordinate variable's values pass through
    xarray's indexing adapter, ~7 us), else from the coordinate variable (``da[dim]`` builds a DataArray with its
    coordinates first; without a coordinate it is the positions ``0, 1, ...``)."""
    if dim in da.xindexes:
        return np.asarray(da.get_index(dim))
    variable = da.coords.variables.get(dim)
    return da[dim].values if variable is None else variable.values


def _time_rate(time: np.ndarray, name: str) -> float:
    """Sampling frequency in Hz from a time coordinate in seconds (numbers), datetimes or timedeltas."""
    time = np.asarray(time)
    idx = None if time.dtype.kind in "iuf" else pd.Index(time)     # (numbers: seconds, no index needed)
    if idx is None:
        dt = np.diff(time.astype(float))
    elif isinstance(idx, (pd.DatetimeIndex, pd.TimedeltaIndex)):
        dt = np.asarray((idx[1:] - idx[:-1]).total_seconds())
    elif pd.api.types.is_numeric_dtype(idx.dtype) and not pd.api.types.is_bool_dtype(idx.dtype):
        dt = np.diff(np.asarray(idx, dtype=float))
    else:
        raise TypeError(f"{name}'s time coordinate must hold seconds, datetimes or timedeltas (or pass fs=), got "
                        f"dtype {idx.dtype}")
    step = float(np.median(dt)) if dt.size else float("nan")
    if not (np.isfinite(step) and step > 0 and np.isfinite(1.0 / step)):
        raise ValueError(f"{name}'s time coordinate gives no sampling frequency (median step {step} s): it must "
                         "increase, or pass fs=")
    return 1.0 / step


def _failure_times(value: Any, n: int) -> np.ndarray:
    """Failure time per record (s, >= 0; NaN for a record without failure) as a float array."""
    refuse_masked(value, "failure_times")
    try:
        ft = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"failure_times must hold numbers (s; NaN for a record without failure), got {value!r}") \
            from None
    if ft.shape != (n,):
        raise ValueError(f"failure_times must have one entry per record ({n}), got shape {ft.shape}")
    bad = np.flatnonzero(np.isinf(ft) | (ft < 0))
    if bad.size:
        raise ValueError(f"failure_times must be >= 0 s or NaN (no failure), got {ft[bad[0]]} for record {bad[0]}")
    return ft


def _finite(rec: Records) -> Any:
    """``finite(i)``: whether record ``i`` holds only finite values. Records in memory are checked when asked about
    (they may come from ``Records.from_data(..., check_finite=False)``); records backed by dask are read a chunk at
    a time when first asked about."""
    if rec.source is None:
        return lambda i: bool(np.isfinite(rec.values[i]).all())
    from tsfdi.fleet import record_chunks

    chunks = record_chunks(rec.source)
    starts = np.array([c.start for c in chunks])
    flags: dict = {}

    def finite(i: int) -> bool:
        c = int(np.searchsorted(starts, i, side="right")) - 1
        if c not in flags:
            flags[c] = rec.read(chunks[c]).valid
        return bool(flags[c][i - chunks[c].start])

    return finite


def _segment(rec: Records, i: int, settle: float, duration: float | None) -> np.ndarray:
    """Samples of record ``i`` from ``settle`` s after its failure (after 0 without failure), ``duration`` s long
    (``None``: to the end of the record, empty when it ends before)."""
    ft = rec.failure_time[i]
    t0 = (ft if np.isfinite(ft) else 0.0) + settle
    n = rec.values[i].shape[0]
    start = t0 * rec.fs
    a = int(round(start)) if start < n else n                   # (bounds first: no int() of a huge float)
    if duration is None:
        return rec.values[i][a:]
    length = duration * rec.fs
    b = a + (int(round(length)) if length <= n else n + 1)
    seg = rec.values[i][a:b]
    if seg.shape[0] < b - a:
        raise ValueError(f"record {rec.ids[i]} is too short for a {duration} s segment starting at {t0} s")
    if seg.shape[0] == 0:
        raise ValueError(f"duration: {duration} s is less than one sample at fs = {rec.fs:g} Hz")
    return seg


# ---------------------------------------------------------------------------------------------------- baselines
@dataclass(frozen=True, eq=False)
class Baselines:
    """Baseline models of every state (outcome of :func:`fit_baselines`).

    Attributes
    ----------
    models : dict
        Model name (a channel name for a scalar AR, ``"var"`` for the VAR) -> {state -> fitted results}
        (:class:`~tsfdi.FPResults` of functionally pooled models from ``fit_baselines(..., k=...)``).
    selections : dict
        ``(model name, state)`` -> :class:`~tsfdi.OrderSelection` (:class:`~tsfdi.models.FPOrderSelection`).
    channels : tuple of str
        Channel names of the records.
    healthy : str
        Name of the healthy state.
    faults : tuple of str
        Names of the fault states (the identification candidates).
    steady_thresholds : ndarray, shape (k,)
        Rolling-variance threshold of each channel below which a post-failure signal is steady.
    steady_window : int
        Rolling-variance window in samples.
    fit_records : tuple
        Identifiers of the records used for fitting (excluded from :func:`evaluate`).
    fs : float
        Sampling frequency in Hz.
    heldout : dict
        ``(model name, state)`` -> list of out-of-sample residual records, one per fitting record of that state:
        the residuals of the record through the model refitted (same order) on the state's *other* fitting
        records (leave one record out; filled by ``fit_baselines(..., calibrate=True)``, else empty). They
        calibrate data-driven test thresholds (:meth:`calibrated_tests`).
    """

    models: dict
    selections: dict
    channels: tuple
    healthy: str
    faults: tuple
    steady_thresholds: np.ndarray
    steady_window: int
    fit_records: tuple
    fs: float
    segments: dict = field(default_factory=dict, repr=False)
    heldout: dict = field(default_factory=dict, repr=False)
    _calibrated: dict = field(default_factory=dict, repr=False)

    def model_channels(self, model: str) -> list[int]:
        """Channel positions a model uses (all for ``"var"``)."""
        if model == "var":
            return list(range(len(self.channels)))
        if model not in self.channels:
            raise ValueError(f"model must be 'var' or one of the channels {self.channels}, got {model!r}")
        return [self.channels.index(model)]

    @property
    def table(self) -> pd.DataFrame:
        """Table 2 analogue: one row per (state, model) with the order, parameters, SPP, RSS/SSS and BIC.

        SPP is the paper's samples per parameter: estimation samples x channels / estimated AR parameters.
        ``records`` is the number of pooled fitting records; ``q_insample`` the median Ljung-Box ``Q`` (20 lags)
        of the in-sample residuals over 20 s blocks (``20 * fs`` samples; the whole record when shorter) and
        channels, to compare with the median of chi2(20), about 19.3.

        A functionally pooled model (``fit_baselines(..., k=...)``) is ``FP-VAR(lags) degree d`` (``FP-AR``): its
        parameters are the FP coefficients of every basis function, ``rss_sss`` is NaN (not defined for it) and
        ``stable`` holds at the operating point of every fitting record.
        """
        rows = []
        for state in (self.healthy,) + self.faults:
            for name, per_state in self.models.items():
                res = per_state[state]
                vec = name == "var"
                kind = "VAR" if vec else "AR"
                if isinstance(res, FPResults):
                    fp, lags = res.model, res.model.na
                    order = f"FP-{kind}({lags}) degree {','.join(map(str, fp.degree))}"
                    spp = res.nobs * res.neqs / res.df_model
                    rss_sss = np.nan
                    stable = all(res.at(kk).is_stable for kk in np.unique(fp.k, axis=0))
                else:
                    lags, order, spp, rss_sss, stable = res.lags, f"{kind}({res.lags})", res.spp, res.rss_sss, \
                        res.is_stable
                rows.append({"state": state, "model": kind,
                             "signals": ",".join(self.channels) if vec else name,
                             "order": order, "lags": int(lags),
                             "parameters": int(res.df_model), "records": len(_resid_list(res)),
                             "nobs": int(res.nobs), "spp": float(spp), "rss_sss": float(rss_sss),
                             "bic": float(res.bic), "q_insample": insample_q(res, int(round(20 * self.fs))),
                             "stable": bool(stable)})
        return pd.DataFrame(rows)

    def monitor(self, model: str = "var", *, window: Any = None, step: Any = "1s", test: ResidualTest | None = None,
                rule: str = "paper", k: Mapping | None = None, sprt_alpha: float = 0.01) -> Monitor:
        """A :class:`~tsfdi.Monitor` with this baseline's healthy and fault models and steady-state thresholds.

        ``test`` (default ``LjungBox(lags=20, alpha=1e-3)``) on ``window`` (default ``"20s"``) detects with the
        healthy model and identifies with the fault models; with ``threshold="empirical"`` each model gets its own
        copy calibrated by :meth:`calibrated_tests`. ``rule="sprt"``: the sequential monitor (no window, no test:
        giving either raises a ``ValueError``) at ``sprt_alpha``, its log-likelihoods scaled by :meth:`sprt_scale`
        (1 without held-out residuals, ``calibrate=False``). ``k``: the operating point of the flights it will watch
        (parameter name -> value): functionally pooled baselines (``fit_baselines(..., k=...)``) give their models at
        it (:meth:`state_models`), calibrated on the FP null. Without ``k`` the monitor of functionally pooled baselines holds the FP models and
        filters every flight at its own logged operating point (``run(signal, k={...})``, ``screen(records,
        k="speed")``).
        """
        chans = self.model_channels(model)
        states = self.state_models(model, k)
        if option(rule, "rule", RULES + SEQUENTIAL_RULES) in SEQUENTIAL_RULES:
            for name, value in (("window", window), ("test", test)):
                if value is not None:
                    raise ValueError(f"{name}: the sequential rule ({rule!r}) decides sample by sample with no window "
                                     f"and no residual test; leave {name} out")
            return Monitor(states[self.healthy], {f: states[f] for f in self.faults}, step=step, fs=self.fs,
                           rule=rule, sprt_alpha=sprt_alpha, sprt_scale=self.sprt_scale(model) if self.heldout else 1.0,
                           steady_thresholds=self.steady_thresholds[chans], steady_window=self.steady_window)
        window = "20s" if window is None else window
        test = _check_test(test)
        if test.empirical:
            tests = self.calibrated_tests(model, test, window)
            ident: Any = {f: tests[f] for f in self.faults}
            det = tests[self.healthy]
        else:
            ident = det = test
        return Monitor(states[self.healthy], {f: states[f] for f in self.faults},
                       window=window, step=step, fs=self.fs, test=ident, detection_test=det,
                       steady_thresholds=self.steady_thresholds[chans], steady_window=self.steady_window, rule=rule)

    def state_models(self, model: str, k: Mapping | None = None) -> dict:
        """State -> the fitted model ``model`` of that state (pooled over its fitting records).

        ``k``: an operating point, a mapping parameter name -> value (``{"speed": 4.2}``): the functionally pooled
        models (:class:`~tsfdi.FPResults`) are then given at that point, ``res.at(k)``, the point models as they are.
        A parameter of an FP model missing from ``k`` raises a ``ValueError`` naming it."""
        if not isinstance(model, str) or model not in self.models:
            raise ValueError(f"model must be one of the fitted models {list(self.models)}, got {model!r}")
        out = {s: self.models[model][s] for s in (self.healthy,) + self.faults}
        if k is None:
            return out
        if not isinstance(k, Mapping):
            raise TypeError(f"k must be a mapping operating parameter -> value (e.g. {{'speed': 4.2}}), got {k!r}")
        for s, res in out.items():
            if isinstance(res, FPResults):
                missing = [n for n in res.model.k_names if n not in k]
                if missing:
                    raise ValueError(f"k lacks the operating parameter(s) {missing} of the functionally pooled model "
                                     f"{model!r} of state {s!r} (its parameters: {list(res.model.k_names)})")
                out[s] = res.at([k[n] for n in res.model.k_names])
        return out

    def sprt_scale(self, model: str = "var") -> float:
        """Scale correction of the sequential rule (``rule="sprt"`` of :func:`tsfdi.evaluate` and :meth:`monitor`)
        for model ``model``: :func:`~tsfdi.detection.sequential.msprt_scale` of the per-sample log-likelihoods of every
        fault state's fitting records through every fault model, the record's own state's model refitted without it
        (:attr:`heldout`, ``fit_baselines(..., calibrate=True)``), the others fitted on other states' records: out of
        sample, as on a new record. Computed once per baselines and model.

        Functionally pooled models: the smallest of the scales at every operating point of the fitting records, each
        from the records logged there. A record's walk drifts at the rate of its own operating point (the models tell
        the states apart more easily at some points than at others); walks of several points joined into one would
        count their different drifts as autocorrelation (the long-run variance of the batch means about the pooled
        mean), a spread no record's walk has, and give a smaller scale than that of any point (0.03 against 0.09 /
        0.17 / 0.83 on the three speeds of tests/test_monitoring_fp.py): decisions slower than the bound needs.

        Raises
        ------
        ValueError
            Baselines without held-out residuals, or records too short for the scale (at an operating point, named).
        """
        if not isinstance(model, str) or model not in self.models:
            raise ValueError(f"model must be one of the fitted models {list(self.models)}, got {model!r}")
        if not self.heldout:
            raise ValueError("the sequential rule's scale comes from held-out residuals: fit the baselines with "
                             "calibrate=True")
        key = ("sprt_scale", model)
        if key not in self._calibrated:
            items = self._heldout_logliks(model)
            scales = []
            for point in dict.fromkeys(p for _, _, p in items):
                group = [(ll, j) for ll, j, p in items if p == point]
                try:
                    scales.append(msprt_scale([ll for ll, _ in group], [j for _, j in group]))
                except ValueError as err:
                    where = "" if point is None else f" at {', '.join(f'{n} = {v:g}' for n, v in point)}"
                    raise ValueError(f"the sequential rule cannot be scale-corrected for model {model!r} on the "
                                     f"baselines' held-out residuals{where}: {err}") from None
            self._calibrated[key] = min(scales)
        return self._calibrated[key]

    def _heldout_logliks(self, model: str) -> list:
        """``(loglik, state index, operating point)`` of every fitting record of every fault state (:meth:`sprt_scale`):
        the per-sample log-likelihoods of the record through every fault model (:meth:`ResidualWindows.loglik`). The
        operating point is the record's logged ``k`` for functionally pooled models, a tuple of ``(name, value)``
        pairs; ``None`` for point models."""
        chans = self.model_channels(model)
        out = []
        for j, state in enumerate(self.faults):
            own = self.models[model][state]
            for i, seg in enumerate(self.segments[state]):
                # functionally pooled models at the record's own operating point
                point = tuple(zip(own.model.k_names, own.model.k[i].tolist())) if isinstance(own, FPResults) else None
                models = {f: r for f, r in self.state_models(model, None if point is None else dict(point)).items()
                          if f in self.faults}
                x = seg[:, chans]
                if x.shape[0] <= max(int(r.lags) for r in models.values()) + 1:
                    continue
                given = {f: self.heldout[(model, state)][i] if f == state else np.asarray(res.residuals(x)).reshape(
                    x.shape[0] - int(res.lags), -1) for f, res in models.items()}
                out.append((ResidualWindows(models).fit_residuals(given, x.shape[0]).loglik(), j, point))
        return out

    def calibrated_tests(self, model: str, test: ResidualTest, window: Any, *, step: Any = 1) -> dict:
        r"""Per state, a copy of ``test`` for windows of ``window`` with its threshold calibrated on that state's
        leave-one-record-out residuals (:attr:`heldout`).

        Parameters
        ----------
        model : str
            A fitted model name (a channel for a scalar AR, ``"var"``).
        test : LjungBox or FTest
            Built with ``threshold="empirical"`` (or an :class:`~tsfdi.EmpiricalThreshold`); it is not modified.
        window, step : int or time span
            Window length and step between calibration windows (an int counts samples; ``"20s"`` a time span).

        Returns
        -------
        dict
            State -> calibrated copy of ``test``.

        Notes
        -----
        Hansen et al. (paper 002, Fig. 2) set the threshold at the :math:`1-\alpha` quantile of the statistic in
        normal operation. Here "normal" is each model's own state, and the statistics are computed out of sample
        (a record the model was not fitted on), as on the evaluation records: every fitting record in turn is
        left out, the model (same order) is refitted on the others and the left-out record's residual windows
        give statistics. The evaluation records are never used.

        A functionally pooled model (``fit_baselines(..., k=...)``) is calibrated on its own null: each fitting
        record at its own operating point through the FP model fitted without it (:attr:`heldout`), whatever the
        operating point of the record it then tests. A reference variance (:class:`~tsfdi.FTest`,
        :class:`~tsfdi.MeanTest`) is the pooled one, the same at every ``k``; an FP model fitted with
        ``weights="point"`` (a variance that changes with ``k``) is refused for such tests.
        """
        import copy

        test = _check_test(test)
        if not test.empirical:
            raise ValueError("test must be built with threshold='empirical' (or an EmpiricalThreshold) to be "
                             "calibrated")
        if model not in self.models:
            raise ValueError(f"model must be one of the fitted models {list(self.models)}, got {model!r}")
        W = window_samples(window, "window", self.fs, minimum=2)
        step = window_samples(step, "step", self.fs)
        key = (model, _options(test), W, step)
        if key in self._calibrated:
            return self._calibrated[key]
        if not self.heldout:
            raise ValueError("baselines have no held-out residuals: fit them with fit_baselines(..., calibrate=True) "
                             "to calibrate thresholds")
        out = {}
        for state in (self.healthy,) + self.faults:
            res = _reference_results(self.models[model][state], test, model, state)
            t = copy.deepcopy(test)
            n = W - int(res.lags)
            recs = self.heldout[(model, state)]
            try:
                t.calibrate([e for e in recs if e.shape[0] >= n], window=n, step=step, **t.reference(res))
            except ValueError as err:
                raise ValueError(f"cannot calibrate {type(test).__name__} of model {model!r}, state {state!r}, "
                                 f"{W}-sample windows: {err}") from None
            out[state] = t
        self._calibrated[key] = out
        return out

    def covers(self, signal: Any, *, model: str = "var", state: str | None = None, alpha: float = 0.01,
               lags: int = 2, k: Mapping | None = None) -> Coverage:
        """Whether this baseline's fitting records of ``state`` cover a new record (:func:`tsfdi.coverage.coverage`).

        The record's summaries (per channel: mean, log residual scale, residual autocorrelation at lags
        ``1..lags``) through the model ``model`` of ``state`` are compared with those of the state's fitting
        segments, each through the model refitted without it (:attr:`heldout` when ``fit_baselines(...,
        calibrate=True)`` kept it, else computed).

        Parameters
        ----------
        signal : array_like, pandas or xarray signal
            The new record, with the baseline's channels (all of them for ``"var"``, the model's channel for a
            scalar AR model).
        model : str
            A fitted model name (``"var"`` or a channel).
        state : str, optional
            The state whose fitting records are compared (default the healthy state).
        alpha : float
            False-warning rate of the check on a record like the fitting records.
        lags : int
            Residual autocorrelation lags summarised.
        k : mapping, optional
            The record's operating point (parameter name -> value), required for a functionally pooled model
            (``fit_baselines(..., k=...)``): the record is filtered at it, the fitting records at their own.

        Returns
        -------
        Coverage
        """
        state = self.healthy if state is None else state
        models = self.state_models(model, k)
        if state not in models:
            raise ValueError(f"state must be one of {list(models)}, got {state!r}")
        if isinstance(models[state], FPResults):
            raise TypeError(f"model {model!r} of state {state!r} is functionally pooled: give the record's operating "
                            f"point, k={{{', '.join(repr(n) + ': ...' for n in models[state].model.k_names)}}}")
        n = len(self.segments.get(state, ()))
        if n < MIN_RECORDS:
            raise ValueError(f"covers needs at least {MIN_RECORDS} fitting records of state {state!r}, the baseline "
                             f"has {n}: fit it with fit_baselines(..., fit_records='all') or fit_records={MIN_RECORDS}"
                             " or more")
        return coverage(models[state], signal, held_out=self.heldout.get((model, state)), alpha=alpha, lags=lags)

    def select_alpha(self, model: str = "var", test: ResidualTest | None = None, window: Any = "20s",
                     alphas: Sequence[float] = (1e-3, 1e-4, 1e-5, 1e-6), *, step: Any = "1s") -> pd.DataFrame:
        """Choose the identification alpha on the fitting records, leaving each record out (paper's rule).

        Every fitting record of every fault state is cut into windows of ``window``, ``step`` apart, and driven
        through each fault model: through its own state's model refitted without it (:attr:`heldout`) and through
        the other states' models, which never saw it. Each window is then identified by the paper's rule (a model
        is accepted when every channel's test accepts at ``alpha``) for every candidate alpha. The evaluation
        records are not used, so the choice can be evaluated on them honestly.

        Parameters
        ----------
        model : str
            A fitted model name.
        test : LjungBox or FTest, optional
            The test whose alpha is chosen (default ``LjungBox(lags=20)``); its own alpha is not used.
        window, step : int or time span
            Window length and step (an int counts samples; ``"20s"`` a time span).
        alphas : sequence of float
            Candidate per-channel alphas, each in (0, 1).

        Returns
        -------
        pandas.DataFrame
            Indexed by alpha: percent of held-out windows identified uniquely and correctly (``correct``),
            uniquely but wrongly (``wrong``), ambiguous (``ambiguous``), with no model accepted (``none``), and
            the number of windows. ``attrs["selected"]`` is the alpha with the highest ``correct`` rate (the
            largest such alpha on ties: the least conservative test that identifies best).

        Notes
        -----
        Dutta et al. (paper 003, Table 3) set each method's alpha (1e-3 to 1e-12) so as to minimise the
        confusion between failures. Out-of-sample residuals carry the baseline's estimation error, so at the
        nominal alpha the matching model is rejected more often than alpha (notes of :class:`~tsfdi.LjungBox`);
        this choice measures that on held-out records instead of assuming it away. A model accepts a window at
        ``alpha`` when its smallest channel p-value exceeds ``alpha``.
        """
        test = _check_test(test)
        if model not in self.models:
            raise ValueError(f"model must be one of the fitted models {list(self.models)}, got {model!r}")
        if test.empirical:
            raise ValueError("select_alpha chooses the alpha of a test with the theoretical threshold; got a test "
                             "with threshold='empirical'")
        if not self.heldout:
            raise ValueError("baselines have no held-out residuals: fit them with fit_baselines(..., calibrate=True) "
                             "to select alpha")
        W = window_samples(window, "window", self.fs, minimum=2)
        step = window_samples(step, "step", self.fs)
        alphas = np.array([probability(a, "alphas") for a in np.atleast_1d(alphas)], dtype=float)
        if alphas.size == 0:
            raise ValueError("alphas must hold at least one value")
        chan = None if model == "var" else self.channels.index(model)
        accepted, truth = [], []
        for state in self.faults:
            own = self.models[model][state]
            for j, seg in enumerate(self.segments[state]):
                x = seg if chan is None else seg[:, chan]
                if seg.shape[0] < W:                    # record shorter than one window: skipped
                    continue
                # functionally pooled models at the record's own operating point
                at = dict(zip(own.model.k_names, own.model.k[j])) if isinstance(own, FPResults) else None
                models = {f: r for f, r in self.state_models(model, at).items() if f in self.faults}
                given = {f: self.heldout[(model, state)][j] if f == state else res.residuals(x)
                         for f, res in models.items()}
                ws = ResidualWindows(models).fit_residuals(given, seg.shape[0]).statistics(
                    test, window=W, step=step, loglik=False)
                # accepted at alpha when every channel's p-value exceeds it: (windows, alphas, faults)
                accepted.append(ws.min_pvalue[:, None, :] > alphas[None, :, None])
                truth.append(np.full(len(ws), self.faults.index(state)))
        if not accepted:
            raise ValueError(f"no fitting record is longer than a {W}-sample window")
        acc = np.concatenate(accepted)          # (windows, alphas, faults)
        true = np.concatenate(truth)
        st = status(acc.sum(axis=-1))                                       # (windows, alphas)
        unique = st == "identified"
        right = acc[np.arange(acc.shape[0]), :, true]
        table = pd.DataFrame({"correct": 100.0 * (unique & right).mean(axis=0),
                              "wrong": 100.0 * (unique & ~right).mean(axis=0),
                              "ambiguous": 100.0 * (st == "ambiguous").mean(axis=0),
                              "none": 100.0 * (st == "none").mean(axis=0),
                              "windows": acc.shape[0]}, index=pd.Index(alphas, name="alpha"))
        best = table["correct"].max()
        table.attrs["selected"] = float(alphas[table["correct"].to_numpy() >= best].max())
        return table

    def __repr__(self) -> str:
        return (f"Baselines(models={list(self.models)}, healthy={self.healthy!r}, faults={self.faults}, "
                f"fit_records={len(self.fit_records)})")


def _names(value: Any, name: str) -> list:
    """A name or a sequence of names as a list (a str is one name)."""
    if isinstance(value, str):
        return [value]
    if not isinstance(value, Iterable):
        raise TypeError(f"{name} must be a name or a sequence of names, got {value!r}")
    return list(value)


def _check_test(test: Any) -> ResidualTest:
    if test is None:
        return LjungBox(lags=20, alpha=1e-3)
    if not isinstance(test, ResidualTest):
        raise TypeError(f"test must be a residual test (LjungBox, FTest, ...), got {type(test).__name__}")
    return test


def _options(value: Any) -> Any:
    """A hashable key of a test's options, by value: its type and its options, recursively (the parts of a combined
    test, a threshold estimator), not its fitted state (names ending in ``_``), private memos nor object addresses."""
    if isinstance(value, (list, tuple)):
        return tuple(_options(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((str(k), _options(v)) for k, v in value.items()))
    if isinstance(value, np.ndarray):
        return (value.dtype.str, value.shape, value.tobytes())
    if hasattr(value, "__dict__"):
        return (type(value).__qualname__, tuple(sorted((k, _options(v)) for k, v in vars(value).items()
                                                       if not (k.endswith("_") or k.startswith("_")))))
    return repr(value)


def _reference_results(res: Any, test: ResidualTest, model: str, state: str) -> Any:
    """The point results whose order and reference (:meth:`ResidualTest.reference`) a test calibrated for ``res`` is
    given: ``res`` itself, or an FP model at the operating point of its first fitting record (its reference is the
    same at every point with pooled weights; with point weights a test that carries a reference is refused)."""
    if not isinstance(res, FPResults):
        return res
    at = res.at(res.model.k[0])
    if res.weights is not None and _flat_reference(test.reference(at)):
        raise ValueError(f"{type(test).__name__} carries the reference variance of the model it is calibrated for, "
                         f"but the functionally pooled model {model!r} of state {state!r} has weights='point' (a "
                         "variance that changes with k): refit it with weights='pooled', or use LjungBox")
    return at


def _flat_reference(reference: dict) -> list:
    """The values of a test's reference keywords, those of a combined test's parts flattened."""
    out = []
    for key, value in reference.items():
        out += [v for part in value for v in _flat_reference(part)] if key == "references" else [value]
    return out


def _resid_list(res: Any) -> list:
    e = res.resid
    return [np.asarray(r, dtype=np.float64) for r in e] if isinstance(e, list) else [np.asarray(e, np.float64)]


def _fp_setup(rec: Records, idx: list, state: str, max_degree: int | None) -> tuple:
    """The operating points of a state's fitting records ``idx`` (a DataFrame, columns :attr:`Records.k_names`) and
    the largest basis degree searched, checked: several operating points, enough for an explicit ``max_degree``."""
    pts = rec.k[idx]
    distinct = [np.unique(pts[:, j]).size for j in range(pts.shape[1])]
    low = int(np.argmin(distinct))
    if distinct[low] < 2:
        raise ValueError(f"k: the fitting records of state {state!r} ({rec.ids[idx].tolist()}) all have "
                         f"{rec.k_names[low]} = {pts[0, low]:g}; a functionally pooled baseline needs fitting records "
                         "at several operating points of every parameter: give fit_records='all', an int or record "
                         "identifiers that span them")
    if max_degree is None:
        return pd.DataFrame(pts, columns=list(rec.k_names)), min(2, distinct[low] - 1)
    if max_degree >= distinct[low]:
        raise ValueError(f"max_degree={max_degree} needs at least {max_degree + 1} distinct values of each operating "
                         f"parameter; the fitting records of state {state!r} hold {distinct[low]} of "
                         f"{rec.k_names[low]!r}: give a smaller max_degree or fitting records at more operating points")
    return pd.DataFrame(pts, columns=list(rec.k_names)), max_degree


def _fp_order(sel: Any, lags: int) -> tuple:
    """``(lags, degree)``: the given order with the basis degree of the smallest BIC at it (an FP order selection)."""
    bic = sel.table["bic"].xs(lags, level="lags")
    return lags, int(bic.idxmin())


def insample_q(res: Any, block: int, lags: int = 20) -> float:
    """Median Ljung-Box Q of the in-sample residuals over non-overlapping blocks and channels."""

    qs = []
    for e in _resid_list(res):
        e = e.reshape(e.shape[0], -1)
        n = min(block, e.shape[0])
        if n <= lags + 1:
            continue
        qs.append(ljungbox_windows(e, lags, n, n).ravel())
    return float(np.median(np.concatenate(qs))) if qs else float("nan")


def fit_baselines(data: Any, *, states: Any = None, failure_times: Any = None, turbulence: Any = None,
                  fs: float | None = None, healthy: str = "healthy", fit_records: Any = "first",
                  fit_turbulence: Any = None, settle: float = 10.0, duration: float | None = 20.0,
                  models: Sequence[str] | None = None, max_lags: int = 20, var_max_lags: int = 20,
                  order: Any = "bic", steady_window: Any = "10s", steady_factor: float = 1.0,
                  calibrate: bool = False, k: Any = None, max_degree: int | None = None) -> Baselines:
    r"""Baseline phase: fit a scalar AR model per channel and a VAR on all channels for every state.

    With ``k`` the models are functionally pooled (FP-AR / FP-VAR, :mod:`tsfdi.models.fp`): one global model per
    state over the operating envelope of its fitting records, each record at its logged operating point.

    Parameters
    ----------
    data : xarray.Dataset, xarray.DataArray or mapping or sequence of signals
        A hexacopter dataset (:func:`tsfdi.datasets.load_hexacopter`; converted by :func:`hexacopter_signals`),
        a ``(record, time, channel)`` DataArray with ``state`` (and ``failure_time``, ``turbulence``)
        coordinates, a sequence of ``(nobs, k)`` signals with ``states=`` (numpy, pandas or xarray each), or a
        mapping state -> signal (one steady-state segment per state, used whole). Either xarray kind may be backed
        by dask, chunked along ``record`` (a fleet opened with ``xarray.open_zarr``; :mod:`tsfdi.fleet`): then only
        the fitting records are read (on the current dask scheduler), and the baselines are those of the same data
        in memory.
    states, failure_times, turbulence : array_like, optional
        Per-record labels for a sequence of signals.
    fs : float, optional
        Sampling frequency in Hz (default: from the time coordinate for xarray input, from the time index of the
        first record for a sequence of signals, else 1).
    healthy : str
        Name of the healthy state; every other state is a fault state.
    fit_records : "first", "all", int or sequence
        Records used for fitting: the first valid record of each (state, turbulence) cell (default), every
        valid record, the first ``n`` valid records of each cell (an int), or explicit record identifiers. They
        are listed in :attr:`Baselines.fit_records` and excluded by :func:`evaluate`. The records of one state
        are pooled: their regressions are stacked (each record holds back its own first samples, no junction
        between records), which shrinks the estimation error of the parameters.
    fit_turbulence : str or sequence, optional
        Restrict fitting records to these turbulence levels (the paper fits on "severe" only); several levels
        give models pooled across them.
    settle : float
        Seconds after the failure (after 0 for records without failure) where the fitting segment starts:
        the post-failure transient is excluded.
    duration : float or None
        Length of the fitting segment in seconds (the paper's 20 s); ``None`` uses the rest of the record.
    models : sequence of str, optional
        Which models to fit: channel names (scalar AR) and/or ``"var"``; default all channels and ``"var"``.
    max_lags, var_max_lags : int
        Largest AR / VAR order searched (on a common sample of the pooled records).
    order : {"bic", "rss_sss"} or int
        ``"bic"``: the BIC minimum (paper eq. 5); ``"rss_sss"``: the order where the RSS/SSS curve (eq. 6)
        stabilises (:attr:`tsfdi.OrderSelection.stabilized`, the paper's Fig. 8 reading); an int: that order
        for every model (at most the search bound).
    steady_window : int or time span
        Rolling-variance window of the steady-state check (an int counts samples; default ``"10s"``).
    steady_factor : float
        Thresholds are ``steady_factor`` times the largest rolling variance of each channel over the steady
        parts (from ``settle`` after the failure) of the fault-state fitting records (the paper's rule with
        factor 1).
    calibrate : bool
        Also compute, for every model and state with at least two fitting records, the leave-one-record-out
        residuals (:attr:`Baselines.heldout`) that calibrate data-driven thresholds (:meth:`Baselines.calibrated_tests`,
        a test with ``threshold="empirical"`` in :func:`~tsfdi.evaluate`): each fitting record in turn through the
        model refitted on the state's other fitting records (with ``k``: the FP model refitted without it, at the
        record's own operating point, :meth:`tsfdi.FPVAR.held_out_residuals`).
    k : str or sequence of str, optional
        Record coordinates (of a Dataset / DataArray) holding each record's operating parameters, e.g. ``"speed"``.
        Every model of every state is then functionally pooled over its fitting records at their logged ``k``
        (:class:`tsfdi.FPAR` per channel, :class:`tsfdi.FPVAR` for ``"var"``, pooled least squares, Legendre
        basis), with the order and the basis degree chosen together by BIC on a common sample
        (:func:`tsfdi.models.select_fp_order`; ``order=<int>`` fixes the order and BIC chooses the degree;
        ``"rss_sss"`` is for point models only). The fitting records of every state must lie at several operating
        points (give ``fit_records="all"``, an int or identifiers spanning them). :attr:`Baselines.models` then
        holds :class:`tsfdi.FPResults`, evaluated at each record's logged ``k`` by
        ``evaluate(..., k=...)``.
    max_degree : int, optional
        Largest polynomial degree of the basis searched (with ``k`` only). Default: 2, or fewer where a state's
        fitting records hold fewer than 3 distinct values of a parameter (degree ``d`` needs ``d + 1``).

    Returns
    -------
    Baselines

    Notes
    -----
    The segments of the fitting records of one state are passed to the model as a list of records: the
    least-squares regressions are stacked (no junction between records) and the Gram matrices of the order
    selection add up. Order selection follows the paper: BIC (eq. 5) or the RSS/SSS stabilisation (eq. 6)
    over orders ``1..max_lags``; :attr:`Baselines.table` also reports the median Ljung-Box ``Q`` (20 lags) of
    the in-sample residuals over 20 s blocks, a check of their whiteness.

    With ``k`` every parameter of a state's model is a function of the operating point,

    .. math::  \theta(k) = \sum_{j=1}^{p} \theta_j\, G_j(k),

    ``G_j`` Legendre polynomials (tensor products for several parameters) of ``k`` mapped onto ``[-1, 1]`` over the
    range of the state's fitting records, and the coefficients ``theta_j`` are estimated from all of them at once by
    pooled least squares (Kopsaftopoulos and Fassois 2010, 2013; the functionally pooled models paper 003 names as
    its next step): one global model set serves every operating point between the fitting ones.

    References
    ----------
    Dutta et al. (paper 003), section "Parametric Model Identification", Table 2 and the Fig. 7 discussion.
    Kopsaftopoulos and Fassois (2010, 2013): the functionally pooled models of ``k=`` (:mod:`tsfdi.models.fp`).
    """
    settle = float_like(settle, "settle", minimum=0.0)
    duration = None if duration is None else float_like(duration, "duration", minimum=0.0, strict_min=True)
    max_lags = int_like(max_lags, "max_lags", minimum=1)
    var_max_lags = int_like(var_max_lags, "var_max_lags", minimum=1)
    steady_factor = float_like(steady_factor, "steady_factor", minimum=0.0, strict_min=True)
    if isinstance(order, str):
        order = option(order, "order", ("bic", "rss_sss"))
    else:
        order = int_like(order, "order", minimum=1, maximum=max(max_lags, var_max_lags))
    calibrate = boolean(calibrate, "calibrate")
    if k is None and max_degree is not None:
        raise ValueError("max_degree is the largest basis degree of functionally pooled baselines: give k= (the "
                         "record coordinates of the operating parameters) with it")
    if k is not None:
        if order == "rss_sss":
            raise ValueError("order='rss_sss' reads the RSS/SSS curve of a point model; with k the order and the basis "
                             "degree are chosen together by BIC: give order='bic' or an int")
        max_degree = None if max_degree is None else int_like(max_degree, "max_degree", minimum=0)
    if isinstance(data, Mapping) and not is_xarray(data):
        if not data:
            raise ValueError("data is an empty mapping: give one signal per state")
        names = list(data)
        data = [data[s] for s in names]
        states, failure_times, turbulence = names, None, None
        fit_records, settle, duration = "all", 0.0, None
    # the values of the records considered for fitting are checked as they are considered (finite), not all
    rec = Records.from_data(data, states=states, failure_times=failure_times, turbulence=turbulence, fs=fs,
                            check_finite=False, k=k)
    V = window_samples(steady_window, "steady_window", rec.fs, minimum=2)
    uniq = list(dict.fromkeys(rec.state.tolist()))
    if healthy not in uniq:
        raise ValueError(f"healthy state {healthy!r} not found among the states {uniq}")
    faults = tuple(s for s in uniq if s != healthy)
    if not faults:
        raise ValueError("data has no fault state: at least one state other than the healthy one is needed")
    # which records fit (records backed by dask: checked for non-finite values as they are considered)
    finite = _finite(rec)
    ok = rec.valid.copy()
    if fit_turbulence is not None:
        ok &= np.isin(rec.turbulence, _names(fit_turbulence, "fit_turbulence"))
    per_cell = None
    if isinstance(fit_records, str):
        fit_records = option(fit_records, "fit_records", ("first", "all"))
        per_cell = 1 if fit_records == "first" else None
        if fit_records == "all":
            chosen = np.array([i for i in np.flatnonzero(ok) if finite(i)], dtype=int)
    elif isinstance(fit_records, (bool, np.bool_)) or not isinstance(fit_records, (Iterable, int, float, np.number)):
        raise TypeError(f"fit_records must be 'first', 'all', a positive int or a sequence of record identifiers, "
                        f"got {fit_records!r}")
    elif not isinstance(fit_records, Iterable):
        per_cell = int_like(fit_records, "fit_records", minimum=1)
    if per_cell is not None:
        seen: dict = {}
        chosen = []
        labels = list(zip(rec.state.tolist(), rec.turbulence.tolist()))     # (numpy scalar indexing costs more)
        for i in np.flatnonzero(ok).tolist():
            key = labels[i]
            if seen.get(key, 0) < per_cell and finite(i):
                seen[key] = seen.get(key, 0) + 1
                chosen.append(i)
        chosen = np.array(chosen, dtype=int)
    elif not isinstance(fit_records, str):
        wanted = list(fit_records)
        pos = {v: i for i, v in enumerate(rec.ids.tolist())}
        bad = [w for w in wanted if w not in pos]
        if bad:
            raise ValueError(f"fit_records {bad} are not record identifiers of data")
        chosen = np.array([pos[w] for w in wanted], dtype=int)
        if not (np.all(rec.valid[chosen]) and all(finite(i) for i in chosen)):
            raise ValueError("fit_records contains records that lost control or hold NaN")
    if rec.source is not None:          # only the fitting records are read
        rec, chosen = rec.read(chosen), np.arange(len(chosen))
    names = list(rec.channels) + ["var"] if models is None else _names(models, "models")
    if not names:
        raise ValueError("models must name at least one model (a channel or 'var')")
    for m in names:
        if m != "var" and m not in rec.channels:
            raise ValueError(f"models must hold channel names {rec.channels} or 'var', got {m!r}")
    out: dict = {m: {} for m in names}
    sels: dict = {}
    segments: dict = {}
    chosen_states = list(zip(chosen.tolist(), rec.state[chosen].tolist()))     # (numpy scalar indexing costs)
    ranges: dict = {}                   # segment length -> its RangeIndex
    for state in (healthy,) + faults:
        idx = [i for i, st in chosen_states if st == state]
        if not idx:
            raise ValueError(f"no valid fitting record for state {state!r}")
        segs = [_segment(rec, i, settle, duration) for i in idx]
        empty = rec.ids[[i for i, g in zip(idx, segs) if g.shape[0] == 0]].tolist()
        if empty:
            raise ValueError(f"record(s) {empty} of state {state!r} end before the fitting segment starts ({settle} s "
                             "after the failure): give a smaller settle")
        segments[state] = segs
        # the segments as the signals DataFrames / Series of them would give (pandas kind, RangeIndex, channel
        # names), validated once as arrays: building and reading the pandas objects cost more than the order search
        # (finite=False: the choice above checked every fitting record for non-finite values already), made as
        # Signals directly (dataclasses.replace reads every field's definition each call), one index per length
        ranges.update((g.shape[0], pd.RangeIndex(g.shape[0])) for g in segs if g.shape[0] not in ranges)
        sigs = [Signal(values=as_signal(g, f"record {rec.ids[i]}", vector=True, allow_constant=True,
                                        finite=False).values,
                       kind="pandas", vector=True, index=ranges[g.shape[0]], channels=list(rec.channels))
                for i, g in zip(idx, segs)]
        # each segment's extremes, kept with its signal for the models' units (channel_extremes)
        flat = [[c for c, hi, lo in zip(rec.channels, *channel_extremes(g)) if hi == lo] for g in sigs]
        operating = None if rec.k is None else _fp_setup(rec, idx, state, max_degree)
        for m in names:
            for i, f in zip(idx, flat):
                const = f if m == "var" else [c for c in f if c == m]
                if const:
                    raise ValueError(f"record {rec.ids[i]} of state {state!r} is constant in channel(s) {const} over "
                                     "its fitting segment: a model cannot be identified from it")
            y = sigs if m == "var" else [g.channel(rec.channels.index(m)) for g in sigs]
            top = var_max_lags if m == "var" else max_lags
            if operating is not None:
                sel = select_fp_order(y, operating[0], top, operating[1], "var" if m == "var" else "ar")
                sels[(m, state)] = sel
                out[m][state] = sel.fit() if order == "bic" else sel.fit(*_fp_order(sel, min(order, top)))
                continue
            sel = select_order(y, top, "var" if m == "var" else "ar")
            sels[(m, state)] = sel
            p = sel.selected if order == "bic" else sel.stabilized if order == "rss_sss" else \
                min(order, sel.max_lags)
            out[m][state] = sel.fit(p)
    heldout: dict = {}
    if calibrate:
        for state, segs in segments.items():
            if len(segs) < 2:
                raise ValueError(f"calibrate=True needs at least two fitting records per state; state {state!r} "
                                 f"has {len(segs)}")
            for m in names:
                # each fitting record through the model (same order, trend, hold-back) fitted on the others (an FP
                # model: at the record's own operating point)
                try:
                    held = out[m][state].model.held_out_residuals()
                except ValueError as err:
                    raise ValueError(f"calibrate=True: the held-out residuals of model {m!r}, state {state!r}: {err}") \
                        from None
                heldout[(m, state)] = [np.asarray(e, dtype=np.float64).reshape(np.shape(e)[0], -1) for e in held]
    # steady-state thresholds: largest rolling variance over the post-settle parts of the fault fitting records
    step = max(1, int(round(0.1 * rec.fs)))
    variances = []
    for i, st in chosen_states:
        if st != healthy:
            post = _segment(rec, i, settle, None)
            if post.shape[0] >= V:
                variances.append(rolling_variance(post, V, step))
    # (one maximum over the windows of all records: numpy reduces axis 0 of a few channels slowly, per call)
    thr = (steady_factor * np.concatenate(variances).max(axis=0) if variances
           else np.full(len(rec.channels), np.inf))
    if variances and not np.all(np.isfinite(thr)):
        raise ValueError(f"steady_factor={steady_factor:g} makes the steady-state thresholds overflow: give a smaller "
                         "factor")
    return Baselines(models=out, selections=sels, channels=rec.channels, healthy=healthy, faults=faults,
                     steady_thresholds=thr, steady_window=V,
                     fit_records=tuple(rec.ids[chosen].tolist()), fs=rec.fs, segments=segments, heldout=heldout)

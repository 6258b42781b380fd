"""Read data files into records: :func:`read_records`.

CSV files with a time column, netCDF files such as ``tsfdi simulate`` writes, PX4 flight logs (ULog) and folders
of per-topic CSV files become the project's :class:`tsfdi.Records`: one array per record with the chosen columns
as named channels, its time stamps in seconds, the file it comes from and its name within that file. The
``tsfdi`` command line reads its data files with this function, its flags named after the keywords
(``rows_where`` is ``--rows-where``).
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import FS_TOLERANCE, read_csv, runs, time_step
from tsfdi.baselines import Records
from tsfdi.exceptions import TsfdiWarning

__all__ = ["read_records", "TIME_COLUMNS", "TIME_UNITS"]

#: names of a CSV column taken as the time index when ``time`` is not given (case-insensitive), in this order
TIME_COLUMNS = ("time", "t", "timestamp", "%time")
#: units of a numeric CSV time column (``time_unit``), in seconds
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}

_NETCDF = (".nc", ".nc4", ".netcdf", ".cdf", ".h5")
#: comparisons of ``rows_where``, longest first (so that '>=' is not read as '>')
_COMPARISONS = {">=": np.greater_equal, "<=": np.less_equal, "==": np.equal, "!=": np.not_equal, ">": np.greater,
                "<": np.less}


@dataclass
class _Options:
    columns: list | None
    time: str | None
    time_unit: str | None
    fs: float | None
    start: int | float | None
    stop: int | float | None
    rows_where: list
    margin: float
    resample: bool
    nan_policy: str
    records: list | None
    where: list
    topics: list | None
    require_choice: bool = False


@dataclass
class _Part:
    """The records of one file."""

    frames: list            # DataFrames, index time in seconds
    ids: list               # names within the file
    fs: float
    labels: dict            # "state" / "turbulence" / "failure_time" -> one value per frame (netCDF coordinates)


# ------------------------------------------------------------------------------------------ checking keywords
def _names(value: Any, name: str) -> list[str] | None:
    """None, a name, comma-separated names or a sequence of names."""
    if value is None:
        return None
    items = value.split(",") if isinstance(value, str) else value
    if not isinstance(items, Sequence) or isinstance(items, bytes) or not all(isinstance(c, str) for c in items):
        raise TypeError(f"{name} must be a name, comma-separated names or a list of names, got {value!r}")
    out = [c.strip() for c in items if c.strip()]
    if not out:
        raise ValueError(f"{name} is empty: give at least one name (or None)")
    return out


def _seconds_of(value: Any, name: str, *, rows: bool) -> int | float | None:
    """A position (``rows``: an int counts rows) or a time span (a number of seconds, '110s', a Timedelta)."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be a number or a time span such as '2s', got {value!r}")
    if isinstance(value, (int, np.integer)) and rows:
        if value < 0:
            raise ValueError(f"{name}: a row number must be >= 0, got {value}")
        return int(value)
    if isinstance(value, (int, float, np.integer, np.floating)):
        seconds = float(value)
    else:
        try:
            span = pd.Timedelta(value)
        except (ValueError, TypeError, OverflowError):
            span = None
        if span is None or span is pd.NaT or isinstance(value, (bytes, bytearray)):
            raise TypeError(f"{name} must be {'a row number (int), ' if rows else ''}a number of seconds or a time "
                            f"span such as '110s', got {value!r}")
        seconds = span.total_seconds()
    if not np.isfinite(seconds):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return seconds


def _conditions(value: Any) -> list[tuple[str, str, float]]:
    """``rows_where``: 'COLUMN OP NUMBER' or a list of them."""
    if value is None:
        return []
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, Sequence) or not items:
        raise TypeError(f"rows_where must be a condition such as 'controller.cmd_thrust>0' or a list of them, got "
                        f"{value!r}")
    out = []
    for text in items:
        m = re.fullmatch(r"\s*(.+?)\s*(>=|<=|==|!=|>|<)\s*(\S+)\s*", text) if isinstance(text, str) else None
        try:
            number = float(m.group(3)) if m else None
        except ValueError:
            number = None
        if number is None or not np.isfinite(number):
            raise ValueError(f"rows_where {text!r}: must be COLUMN OP NUMBER with OP one of "
                             f"{', '.join(_COMPARISONS)}, such as 'controller.cmd_thrust>0'")
        out.append((m.group(1), m.group(2), number))
    return out


def _options(columns, time, time_unit, fs, start, stop, rows_where, margin, resample, nan_policy, records, where,
             topics, require_choice) -> _Options:
    if time is not None and not isinstance(time, str):
        raise TypeError(f"time must be the name of a CSV column, got {time!r}")
    if time_unit is not None and time_unit not in TIME_UNITS:
        raise ValueError(f"time_unit must be one of {', '.join(TIME_UNITS)}, got {time_unit!r}")
    if fs is not None:
        if isinstance(fs, (bool, np.bool_)) or not isinstance(fs, (int, float, np.integer, np.floating)):
            raise TypeError(f"fs must be a number (Hz), got {fs!r}")
        if not (np.isfinite(fs) and fs > 0):
            raise ValueError(f"fs must be a finite number > 0 (Hz), got {fs!r}")
        fs = float(fs)
    start, stop = _seconds_of(start, "start", rows=True), _seconds_of(stop, "stop", rows=True)
    if isinstance(start, float) and isinstance(stop, float) and stop <= start:
        raise ValueError(f"stop must come after start, got {stop:g} s <= {start:g} s")
    conditions = _conditions(rows_where)
    margin = _seconds_of(margin, "margin", rows=False) or 0.0
    if margin < 0:
        raise ValueError(f"margin must be >= 0 s, got {margin:g} s")
    if margin and not conditions:
        raise ValueError("margin trims the runs of rows_where: give rows_where too")
    if not isinstance(resample, (bool, np.bool_)):
        raise TypeError(f"resample must be True or False, got {resample!r}")
    if not isinstance(require_choice, (bool, np.bool_)):
        raise TypeError(f"require_choice must be True or False, got {require_choice!r}")
    if nan_policy not in ("raise", "omit"):
        raise ValueError(f"nan_policy must be 'raise' or 'omit', got {nan_policy!r}")
    if records is not None:
        items = [records] if isinstance(records, (int, np.integer)) else records
        if not isinstance(items, Sequence) or isinstance(items, str) or not items or \
                not all(isinstance(r, (int, np.integer)) and not isinstance(r, bool) for r in items):
            raise TypeError(f"records must be a record number or a non-empty list of them, got {records!r}")
        records = [int(r) for r in items]
    pairs = []
    if where is not None:
        items = list(where.items()) if isinstance(where, Mapping) else where
        if not isinstance(items, Sequence) or not all(isinstance(p, tuple) and len(p) == 2 for p in items):
            raise TypeError(f"where must be a mapping of coordinate names to values, got {where!r}")
        for key, values in items:
            values = list(values) if isinstance(values, (list, tuple, np.ndarray)) else [values]
            if not values:
                raise ValueError(f"where {key}: give at least one value")
            pairs.append((str(key), [str(v) for v in values]))
    return _Options(_names(columns, "columns"), time, time_unit, fs, start, stop, conditions, float(margin),
                    bool(resample), nan_policy, records, pairs, _names(topics, "topics"), bool(require_choice))


# ----------------------------------------------------------------------------------------------------- times
def _where_row(what: str, i: int) -> str:
    """How to point at data row ``i``: a CSV line (header is line 1) or a position."""
    return f"line {i + 2}" if what.startswith("column") else f"position {i}"


def _seconds(values: Any, what: str, source: str) -> np.ndarray:
    """Times as float seconds: numbers (seconds), timedeltas or elapsed times ('00:01:06.816502'), or dates and
    times -- datetime64 or text such as '2018-09-11 18:46:35.350' -- as seconds since the first."""
    v = np.asarray(values)
    if v.dtype.kind == "M":
        valid = np.flatnonzero(~np.isnat(v))
        v = v - v[valid[0]] if valid.size else v - v
    if v.dtype.kind == "m":
        return v / np.timedelta64(1, "s")
    if v.dtype.kind in "iuf":
        return v.astype(np.float64)
    text = pd.Series(v)
    t = pd.to_numeric(text, errors="coerce").to_numpy(dtype=np.float64)
    given = text.notna().to_numpy()
    bad = np.flatnonzero(np.isnan(t) & given)
    if bad.size:
        spans = pd.to_timedelta(text, errors="coerce")
        if not (spans.isna().to_numpy() & given).any():
            return _seconds(spans.to_numpy(), what, source)
        stamps = pd.to_datetime(text, errors="coerce", format="ISO8601")
        if not (stamps.isna().to_numpy() & given).any():
            return _seconds(stamps.to_numpy(), what, source)
        raise ValueError(f"{source}: {what} must hold times (numbers, elapsed times such as '00:01:06.816502', or "
                         f"dates and times such as '2018-09-11 18:46:35.350'); {_where_row(what, bad[0])} holds "
                         f"{v[bad[0]]!r}")
    return t


def _rate_guess(t: np.ndarray) -> float | None:
    """1 / the median of the positive finite steps of ``t`` (None without one)."""
    step = np.diff(t)
    step = step[np.isfinite(step) & (step > 0)]
    return 1.0 / float(np.median(step)) if step.size else None


def _check_time(t: np.ndarray, what: str, source: str, fs: float | None, first: int, csv: bool) -> float:
    """The sampling frequency of the time stamps ``t`` (s): finite, and uniform by the library's one rule
    (:func:`tsfdi._data.time_step`); ``t`` starts at row ``first`` of the file."""
    desc = f"{source}: {what}"
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise ValueError(f"{desc} holds {bad.size} empty or non-finite time(s), the first at "
                         f"{_where_row(what, first + bad[0])}")
    if t.size < 2:
        if fs is None:
            raise ValueError(f"{desc} holds a single time: give fs")
        return fs
    fix = ("resample=True with fs=RATE puts the rows on a uniform grid; " if csv else "") + \
        "start / stop or rows_where cut the gap off"
    dt = time_step(pd.Index(t), desc, numeric=True, row=lambda i: _where_row(what, first + i), fix=fix)
    rate = 1.0 / dt
    if fs is not None and abs(fs / rate - 1) > FS_TOLERANCE:
        raise ValueError(f"fs={fs:g}: the {what} of {source} gives {rate:.6g} Hz (median step {dt:.6g} s); leave "
                         "out fs or fix the time stamps")
    return rate


def _position(x: int | float | None, t: np.ndarray, fs: float | None) -> int | None:
    """``start`` / ``stop`` as a row position: a row number as it is, a time (s) on the clock ``t`` (half a sample
    early, at ``fs``)."""
    return x if x is None or isinstance(x, int) else int(np.searchsorted(t, x - (0.5 / fs if fs else 0.0)))


# --------------------------------------------------------------------------------------------------- columns
def _pick_columns(available: list[str], wanted: list[str] | None, source: str, kind: str) -> list[str]:
    """The data columns: those of ``columns``, else every available one."""
    if wanted:
        missing = [c for c in wanted if c not in available]
        if missing:
            raise ValueError(f"columns: {source} has no {kind} {', '.join(repr(c) for c in missing)}; its "
                             f"{kind}s are {available}")
        if len(set(wanted)) != len(wanted):
            raise ValueError(f"columns: a {kind} is named twice in {wanted}")
        return list(wanted)
    if not available:
        raise ValueError(f"{source} has no numeric {kind} over time")
    return available


def _row_mask(opt: _Options, available: list[str], path: str, kind: str, values: Any) -> Any:
    """The rows that meet every ``rows_where`` condition (None without one); ``values(name)`` gives a column,
    rows on the last axis. A NaN compares false: its row is left out."""
    if not opt.rows_where:
        return None
    mask = True
    for col, op, value in opt.rows_where:
        if col not in available:
            raise ValueError(f"rows_where {col}{op}{value:g}: {path} has no numeric {kind} {col!r}; its numeric "
                             f"{kind}s are {available}")
        with np.errstate(invalid="ignore"):
            mask = mask & _COMPARISONS[op](np.asarray(values(col), dtype=np.float64), value)
    return mask


def _piece(rid: str, k: int) -> str:
    return f"{rid}.{k}" if rid else str(k)


# ----------------------------------------------------------------------------------------------------- CSV
def _time_column(columns: list[str], opt: _Options, path: str) -> str | None:
    if opt.time is not None:
        if opt.time not in columns:
            raise ValueError(f"time: {path} has no column {opt.time!r}; its columns are {columns}")
        return opt.time
    lower = {c.strip().lower(): c for c in columns}
    return next((lower[n] for n in TIME_COLUMNS if n in lower), None)


def _time_of(df: pd.DataFrame, tcol: str, opt: _Options, path: str) -> np.ndarray:
    """The time column ``tcol`` in seconds."""
    if opt.time_unit is not None and not pd.api.types.is_numeric_dtype(df[tcol]):
        raise ValueError(f"time_unit: the time column {tcol!r} of {path} does not hold numbers (its first value is "
                         f"{df[tcol].iloc[0]!r}); dates and times need no unit")
    return _seconds(df[tcol].to_numpy(), f"column {tcol!r}", path) * TIME_UNITS[opt.time_unit or "s"]


def _numbers(df: pd.DataFrame, cols: list[str], path: str) -> None:
    """The columns ``cols`` of ``df`` as numbers, in place; text that is not a number is refused by line."""
    for c in cols:
        col = df[c]
        if pd.api.types.is_bool_dtype(col):
            raise ValueError(f"{path}: column {c!r} is not numeric (it holds True / False)")
        values = pd.to_numeric(col, errors="coerce")
        bad = np.flatnonzero(values.isna().to_numpy() & col.notna().to_numpy())
        if bad.size:
            raise ValueError(f"{path}: column {c!r} is not numeric (line {bad[0] + 2} holds {col.iloc[bad[0]]!r}); "
                             "leave it out with columns")
        df[c] = values


def _read_csv(path: str, opt: _Options) -> tuple[list, list, float | None, str | None, list]:
    df = read_csv(path, "paths")
    if len(df) == 0:
        raise ValueError(f"paths: {path} has a header but no rows")
    df.columns = [str(c) for c in df.columns]
    tcol = _time_column(list(df.columns), opt, path)
    if tcol is None and opt.time_unit is not None:
        raise ValueError(f"time_unit: {path} has no time column ({' / '.join(TIME_COLUMNS)}); name it with time")
    if tcol is None and opt.fs is None:
        raise ValueError(f"{path} has no time column ({' / '.join(TIME_COLUMNS)}): name it with time, or give fs to "
                         "count the rows as samples at that rate")
    data_cols = [c for c in df.columns if c != tcol]
    numeric = [c for c in data_cols if pd.api.types.is_numeric_dtype(df[c]) and not pd.api.types.is_bool_dtype(df[c])]
    cols = _pick_columns(numeric if opt.columns is None and numeric else data_cols, opt.columns, path, "column")
    skipped = [c for c in data_cols if c not in numeric]
    if opt.columns is None and skipped and cols == numeric:
        warnings.warn(f"left out the non-numeric column(s) {skipped} of {path}", TsfdiWarning, stacklevel=3)
    flags = [c for c in data_cols if pd.api.types.is_bool_dtype(df[c])]         # True / False compare as 1 / 0
    mask = _row_mask(opt, numeric + flags, path, "column", lambda c: df[c].to_numpy())
    if opt.resample and (tcol is None or opt.fs is None):
        raise ValueError(f"resample: {path} needs a time column and fs, the rate of the grid the rows are put on")
    _numbers(df, cols, path)
    if tcol is None:
        t, fs, clock = np.arange(len(df)) / opt.fs, opt.fs, None
    else:
        t = _time_of(df, tcol, opt, path)
        fs, clock = None, f"column {tcol!r}"
        guess = _rate_guess(t)
        if opt.time is None and opt.time_unit is None and guess is not None and guess < 1.0:
            warnings.warn(f"read the time column {tcol!r} of {path} in seconds, which gives {guess:.6g} Hz; if it "
                          "counts milliseconds (or us, ns), give time_unit='ms'", TsfdiWarning, stacklevel=3)
    frame = pd.DataFrame(df[cols].to_numpy(dtype=np.float64), columns=cols, index=pd.Index(t, name="time"))
    if not opt.resample:
        return [frame], [""], fs, clock, [mask]
    from tsfdi.datasets import align

    extra = [c for c, _, _ in opt.rows_where if c not in frame.columns]
    source = frame.assign(**{c: df[c].to_numpy(dtype=np.float64) for c in dict.fromkeys(extra)})
    source.index = pd.to_timedelta(frame.index.to_numpy(), unit="s")
    try:
        records = align(source, opt.fs, nan_policy=opt.nan_policy)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"resample: {path}: {exc}") from None
    return _on_grid(records, list(frame.columns), numeric + flags, opt, path)


def _on_grid(records: list, cols: list[str], comparable: list[str], opt: _Options,
             path: str) -> tuple[list, list, float, None, list]:
    """The records of :func:`tsfdi.datasets.align` (at ``fs``): their ``cols``, time in seconds, numbered when
    several, and the ``rows_where`` mask of each."""
    frames = [pd.DataFrame(r[cols].to_numpy(), columns=cols,
                           index=pd.Index(r.index.total_seconds().to_numpy(), name="time")) for r in records]
    masks = [_row_mask(opt, comparable, path, "column", lambda c, r=r: r[c].to_numpy()) for r in records]
    return frames, [str(k) for k in range(len(frames))] if len(frames) > 1 else [""], opt.fs, None, masks


# -------------------------------------------------------------------------------------------------- netCDF
def _select_records(ds: Any, opt: _Options, path: str) -> list[int]:
    """Positions along ``record`` chosen by ``records`` and ``where``."""
    n = ds.sizes["record"]
    labels = np.asarray(ds["record"].values) if "record" in ds.coords else np.arange(n)
    per_record = [k for k in ds.variables if ds[k].dims == ("record",) and k != "record"]
    pick = list(range(n))
    if opt.records:
        pick = []
        for r in opt.records:
            hits = np.flatnonzero(labels == r)
            if not hits.size:
                raise ValueError(f"records={r}: {path} has no record {r}; its records are "
                                 f"{labels.min()}..{labels.max()} ({n})")
            pick.append(int(hits[0]))
    for key, values in opt.where:
        if key not in per_record:
            raise ValueError(f"where {key}=...: {path} has no per-record coordinate {key!r}; they are {per_record}")
        v = np.asarray(ds[key].values)
        match = np.zeros(n, dtype=bool)
        for text in values:
            if v.dtype.kind == "b":
                if text.lower() not in ("true", "false", "1", "0"):
                    raise ValueError(f"where {key}={text}: {key} holds True / False")
                match |= v == (text.lower() in ("true", "1"))
            elif v.dtype.kind in "iuf":
                try:
                    match |= v == float(text)
                except ValueError:
                    raise ValueError(f"where {key}={text}: {key} holds numbers") from None
            else:
                match |= v.astype(str) == text
        if not match[pick].any():
            raise ValueError(f"where {key}={','.join(values)}: no selected record of {path} matches; {key} holds "
                             f"{sorted(set(v.astype(str).tolist()))}")
        pick = [i for i in pick if match[i]]
    return pick


def _choice_needed(ds: Any, path: str) -> str:
    """``require_choice``: the message of a netCDF file of several records read without ``records`` or ``where``,
    listing the values of its per-record coordinates (the text ones and ``state``)."""
    n = ds.sizes["record"]
    hints = "; ".join(f"{k}: {', '.join(sorted(set(np.asarray(ds[k].values).astype(str).tolist())))}"
                      for k in ds.variables if ds[k].dims == ("record",) and k != "record"
                      and (ds[k].dtype.kind in "OUSb" or k == "state"))
    return (f"{path} holds {n} records: choose the ones to use with records=N[,N...] or where KEY=VALUE "
            f"({hints or 'records 0..' + str(n - 1)})")


def _read_netcdf(path: str, opt: _Options) -> tuple[list, list, float | None, str | None, list, dict]:
    import xarray as xr

    for flag in ("time", "time_unit", "resample"):
        if getattr(opt, flag) not in (None, False):
            raise ValueError(f"{flag} is for CSV files; {path} is netCDF (its time is the 'time' coordinate)")
    try:
        with xr.open_dataset(path, engine="h5netcdf") as ds:
            ds = ds.load()
    except (OSError, ValueError, TypeError, KeyError) as exc:
        raise ValueError(f"paths: {path} cannot be read as a netCDF file ({type(exc).__name__}: {exc})") from None
    has_records = "record" in ds.dims
    if not has_records and (opt.records or opt.where):
        raise ValueError(f"{'records' if opt.records else 'where'}: {path} has no 'record' dimension (one record)")
    if has_records and opt.require_choice and not (opt.records or opt.where) and ds.sizes["record"] > 1:
        raise ValueError(_choice_needed(ds, path))
    dims = {("time",), ("record", "time")} if has_records else {("time",)}
    available = [str(k) for k, v in ds.data_vars.items() if v.dims in dims and v.dtype.kind in "iuf"]
    for c in opt.columns or []:
        if c in ds.data_vars and c not in available:
            raise ValueError(f"columns: variable {c!r} of {path} is not a numeric series over time (dims "
                             f"{ds[c].dims}, dtype {ds[c].dtype})")
    cols = _pick_columns(available, opt.columns, path, "variable")
    if "time" in ds.coords:
        t, fs, clock = _seconds(ds["time"].values, "coordinate 'time'", path), None, "coordinate 'time'"
    elif opt.fs is not None:
        t, fs, clock = np.arange(ds.sizes["time"]) / opt.fs, opt.fs, None
    else:
        raise ValueError(f"{path} has no 'time' coordinate: give fs")
    index = pd.Index(t, name="time")
    mask = _row_mask(opt, available, path, "variable", lambda c: ds[c].values)
    if not has_records:
        return ([pd.DataFrame({c: ds[c].values.astype(np.float64) for c in cols}, index=index)], [""], fs, clock,
                [mask], {})
    pick = _select_records(ds, opt, path)
    labels = np.asarray(ds["record"].values) if "record" in ds.coords else np.arange(ds.sizes["record"])
    frames = [pd.DataFrame({c: (ds[c].values[i] if ds[c].dims[0] == "record" else ds[c].values).astype(np.float64)
                            for c in cols}, index=index) for i in pick]
    masks = [None if mask is None else np.broadcast_to(mask, (ds.sizes["record"], len(t)))[i] for i in pick]
    coords = {k: np.asarray(ds[k].values)[pick] for k in ("state", "turbulence", "failure_time")
              if k in ds.variables and ds[k].dims == ("record",)}
    return frames, [str(labels[i]) for i in pick], fs, clock, masks, coords


# ------------------------------------------------------------------------------------- ULog and topic folders
def _aligned(topics: dict, path: str, opt: _Options) -> tuple[list, list, float, None, list]:
    from tsfdi.datasets import align

    try:
        records = align(topics, opt.fs, nan_policy=opt.nan_policy)
    except (ValueError, TypeError) as exc:
        raise ValueError(re.sub(r"^(?=frames\[)", "topics: ", f"{exc}")) from None
    available = [str(c) for c in records[0].columns]
    return _on_grid(records, _pick_columns(available, opt.columns, path, "column"), available, opt, path)


def _needs_topics(path: str, opt: _Options, kind: str, example: str) -> None:
    for flag in ("time", "time_unit", "resample", "records", "where") if kind == "ULog" else \
            ("resample", "records", "where"):
        if getattr(opt, flag):
            raise ValueError(f"{flag} is not for {kind}; {path} is one")
    if not opt.topics or opt.fs is None:
        raise ValueError(f"{'topics' if not opt.topics else 'fs'}: {path} is {kind}; name the topics to read with "
                         f"topics (e.g. {example}) and the rate of the grid they are aligned on with fs")


def _read_ulog(path: str, opt: _Options) -> tuple[list, list, float, None, list]:
    """The ``topics`` of a PX4 log on one grid at ``fs`` (zero-order hold; split at gaps)."""
    from tsfdi.datasets import read_ulog

    _needs_topics(path, opt, "a PX4 flight log", "['vehicle_attitude', 'sensor_combined']")
    try:
        topics = read_ulog(path, opt.topics)
    except ImportError:
        raise ImportError("reading a PX4 flight log (.ulg) needs the pyulog package: pip install tsfdi[px4]") \
            from None
    except (ValueError, TypeError) as exc:
        raise ValueError(re.sub(r"^path: ", "paths: ", f"{exc}")) from None
    return _aligned(topics, path, opt)


def _topic_files(folder: Path) -> dict[str, Path]:
    """Topic name -> CSV file of a folder: the file name less its extension and the prefix common to every file
    (cut at a '-', '_' or '.')."""
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.name.lower().endswith((".csv", ".csv.gz")))
    stems = [re.sub(r"\.csv(\.gz)?$", "", p.name, flags=re.I) for p in files]
    prefix = os.path.commonprefix(stems) if len(stems) > 1 else ""
    cut = max(prefix.rfind(c) for c in "-_.") + 1
    return {s[cut:]: p for s, p in zip(stems, files)}


def _read_folder(path: str, opt: _Options) -> tuple[list, list, float, None, list]:
    """The ``topics`` of a folder of per-topic CSV files (each with a time column) on one grid at ``fs``."""
    files = _topic_files(Path(path))
    if not files:
        raise ValueError(f"paths: {path} is a folder without CSV files (.csv, .csv.gz)")
    _needs_topics(path, opt, "a folder of per-topic CSV files", repr(list(files)[:2]))
    missing = [t for t in opt.topics if t not in files]
    if missing:
        raise ValueError(f"topics: {path} has no topic {', '.join(map(repr, missing))}; its topics are {list(files)}")
    stamps, frames = {}, {}
    for name in opt.topics:
        file = str(files[name])
        df = read_csv(file, "paths")
        df.columns = [str(c) for c in df.columns]
        tcol = _time_column(list(df.columns), opt, file)
        if tcol is None:
            raise ValueError(f"time: {file} has no time column ({' / '.join(TIME_COLUMNS)}); name it with time")
        numeric = [c for c in df.columns if c != tcol and (pd.api.types.is_numeric_dtype(df[c]))]
        if not numeric or not len(df):
            raise ValueError(f"topics: {file} holds no numeric column with rows")
        dates = not pd.api.types.is_numeric_dtype(df[tcol]) and opt.time_unit is None and \
            pd.to_timedelta(df[tcol], errors="coerce").isna().all()
        if dates:       # dates and times: nanoseconds, put on one clock below
            stamps[name] = pd.to_datetime(df[tcol], errors="coerce", format="ISO8601")
            if stamps[name].isna().any():
                _seconds(df[tcol].to_numpy(), f"column {tcol!r}", file)         # names the bad line
        else:
            stamps[name] = _time_of(df, tcol, opt, file)
        frames[name] = df[numeric]
    if len({isinstance(s, pd.Series) for s in stamps.values()}) > 1:
        raise ValueError(f"time: the topics of {path} mix dates and times with numbers")
    origin = min(s.min() for s in stamps.values()) if all(isinstance(s, pd.Series) for s in stamps.values()) \
        else None
    topics = {}
    for name, frame in frames.items():
        t = stamps[name]
        seconds = (t - origin).dt.total_seconds().to_numpy() if origin is not None else t
        try:
            topics[name] = frame.set_axis(pd.to_timedelta(seconds, unit="s"), axis=0)
        except (OverflowError, ValueError):
            raise ValueError(f"time_unit: the times of topic {name!r} of {path} are out of range in "
                             f"{opt.time_unit or 's'} (up to {np.nanmax(np.abs(seconds)):.6g} s); give their unit, "
                             "e.g. time_unit='ns'") from None
    return _aligned(topics, path, opt)


# ---------------------------------------------------------------------------------------------------- files
def _read_file(path: str, opt: _Options) -> _Part:
    """The records of one data file."""
    p = Path(path)
    if not p.exists():
        raise ValueError(f"paths: {path} does not exist")
    kind = "folder" if p.is_dir() else {**dict.fromkeys(_NETCDF, "netcdf"), ".ulg": "ulog"}.get(p.suffix.lower(),
                                                                                                  "csv")
    if kind in ("netcdf", "csv") and opt.topics:
        raise ValueError(f"topics is for PX4 flight logs (.ulg) and folders of per-topic CSV files; {path} is not "
                         "one")
    coords: dict = {}
    if kind == "netcdf":
        frames, ids, fs, clock, masks, coords = _read_netcdf(path, opt)
    elif kind == "ulog":
        frames, ids, fs, clock, masks = _read_ulog(path, opt)
    elif kind == "folder":
        frames, ids, fs, clock, masks = _read_folder(path, opt)
    else:
        if opt.records or opt.where:
            raise ValueError(f"{'records' if opt.records else 'where'} selects records of a netCDF file; {path} is "
                             "read as CSV")
        frames, ids, fs, clock, masks = _read_csv(path, opt)
    keep = list(range(len(frames)))
    first = [0] * len(frames)           # row of the file / record where each frame starts
    if opt.start is not None or opt.stop is not None:
        rate = fs if fs is not None else _rate_guess(frames[0].index.to_numpy())
        cut = [[_position(x, f.index.to_numpy(), rate) for x in (opt.start, opt.stop)] for f in frames]
        keep = [i for i, (f, (a, b)) in enumerate(zip(frames, cut)) if len(f.iloc[a:b])]
        if not keep:
            spans = ", ".join(f"{f.index[0]:g} s to {f.index[-1]:g} s ({len(f)} rows)" for f in frames[:5])
            raise ValueError(f"start / stop select no row of {path} (times {spans})")
        first = [len(frames[i].iloc[:cut[i][0]]) for i in keep]
        frames, ids = [frames[i].iloc[slice(*cut[i])] for i in keep], [ids[i] for i in keep]
        masks = [None if masks[i] is None else masks[i][slice(*cut[i])] for i in keep]
    origin = keep                       # per frame, the position of the record it comes from (for coords)
    if opt.rows_where:
        frames, ids, first, origin = _runs_where(frames, ids, first, masks, origin, opt, path)
    if fs is None:      # the file's clock, checked on the rows used only
        rates = [_check_time(f.index.to_numpy(), clock, path, opt.fs, row0, kind == "csv")
                 for f, row0 in zip(frames, first)]
        fs = rates[0]
        other = next((k for k, r in enumerate(rates) if abs(r / fs - 1) > 0.01), None)
        if other is not None:
            raise ValueError(f"{path}: the {clock} gives {fs:.6g} Hz in record {ids[0]} but {rates[other]:.6g} Hz in "
                             f"record {ids[other]}: the records must have one rate (within 1 %)")
    out_frames, out_ids, out_origin = [], [], []
    for f, rid, row0, o in zip(frames, ids, first, origin):
        bad = ~np.isfinite(f.to_numpy())
        if not bad.any():
            out_frames.append(f)
            out_ids.append(rid)
            out_origin.append(o)
            continue
        if opt.nan_policy == "omit":
            parts = [f.iloc[a:b] for a, b in runs(~bad.any(axis=1))]
            out_frames += parts
            out_ids += [_piece(rid, k) for k in range(len(parts))]
            out_origin += [o] * len(parts)
            continue
        j = int(np.flatnonzero(bad.any(axis=0))[0])
        i = int(np.flatnonzero(bad[:, j])[0])
        where = f"record {rid} of {path}" if rid else path
        at = f"line {row0 + i + 2}, " if kind == "csv" else ""
        what = "variable" if kind == "netcdf" else "column"
        raise ValueError(f"{where}: {what} {f.columns[j]!r} holds {int(bad[:, j].sum())} empty, NaN or infinite "
                         f"value(s), the first at {at}time {f.index[i]:.6g} s; leave it out with columns, cut it off "
                         "with start / stop, or give nan_policy='omit' to split the record there")
    if not out_frames:
        raise ValueError(f"nan_policy='omit': every row of {path} holds an empty or NaN value")
    labels = {k: [v[o] for o in out_origin] for k, v in coords.items()}
    return _Part(out_frames, out_ids, float(fs), labels)


def _runs_where(frames: list, ids: list, first: list, masks: list, origin: list, opt: _Options,
                path: str) -> tuple[list, list, list, list]:
    """The runs of rows that meet ``rows_where`` (``masks``), less ``margin`` at both ends: one record each,
    named ``"<record>.<k>"``, with the file row where each starts."""
    out_frames, out_ids, out_first, out_origin = [], [], [], []
    for f, rid, row0, mask, o in zip(frames, ids, first, masks, origin):
        t = f.index.to_numpy()
        for k, (a, b) in enumerate(runs(mask)):
            a, b = (int(np.searchsorted(t[a:b], t[a] + opt.margin) + a),
                    int(np.searchsorted(t[a:b], t[b - 1] - opt.margin, side="right") + a))
            if b > a:
                out_frames.append(f.iloc[a:b])
                out_ids.append(_piece(rid, k))
                out_first.append(row0 + a)
                out_origin.append(o)
    if not out_frames:
        conds = " and ".join(f"{c}{op}{v:g}" for c, op, v in opt.rows_where)
        raise ValueError(f"rows_where: no row of {path} meets {conds}"
                         + (f" for more than margin={opt.margin:g} s at both ends" if opt.margin else ""))
    return out_frames, out_ids, out_first, out_origin


def read_records(paths: str | os.PathLike | Sequence[str | os.PathLike], *, columns: Any = None,
                 time: str | None = None, time_unit: str | None = None, fs: float | None = None, start: Any = None,
                 stop: Any = None, rows_where: Any = None, margin: Any = 0.0, resample: bool = False,
                 nan_policy: str = "raise", records: Any = None, where: Any = None, topics: Any = None,
                 require_choice: bool = False) -> Records:
    """Read data files into records of named channels on a uniform time grid.

    Parameters
    ----------
    paths : str or path-like, or a list of them
        One or more data files, each read with the same options; several are pooled, in the order given, and must
        give the same columns and sampling frequency (within 1 %). The kind follows the name:

        - a CSV file (``.csv``, ``.csv.gz``, any other suffix): one column holds the time (see ``time``);
        - a netCDF file (``.nc``, ``.nc4``, ``.netcdf``, ``.cdf``, ``.h5``) such as ``tsfdi simulate`` writes:
          variables over ``time``, or over ``record`` and ``time``, with per-record coordinates;
        - a PX4 flight log (``.ulg``, needs ``pyulog``: ``pip install tsfdi[px4]``): the ``topics`` put on one grid
          at ``fs`` by zero-order hold (:func:`tsfdi.align`) and split into records at logging gaps; columns
          ``"topic.field"``, e.g. ``"sensor_combined.gyro_rad[0]"``;
        - a folder of per-topic CSV files (as ALFA's official ``<flight>-<topic>.csv``), each with a time column:
          the ``topics`` (the file names less their extension and the prefix common to every file of the folder)
          put on one grid as a flight log's.
    columns : str or list of str, optional
        The data channels, in this order (comma-separated names, or a list). Default: every numeric column (CSV,
        topics) or every numeric variable over time (netCDF).
    time : str, optional
        The CSV column holding the time (default: the first column named ``time``, ``t``, ``timestamp`` or
        ``%time``, in any case). Numbers (in ``time_unit``), elapsed times (``"00:01:06.816502"``) or dates and
        times (``"2018-09-11 18:46:35.350"``, counted in seconds from the first row). It is the index, never a
        channel; without one ``fs`` counts the rows as samples.
    time_unit : {"s", "ms", "us", "ns"}, optional
        Unit of the numbers of the time column (default seconds; CrazyPAD's ``timestamp`` is in ms).
    fs : float, optional
        Sampling frequency in Hz: required without a time column or coordinate, with ``resample`` and for flight
        logs and topic folders (the rate of the grid); beside a time column it must agree with it within 1 %.
    start, stop : int, float or time span, optional
        The part of every record used (``stop`` excluded): an ``int`` is a row number (from 0), a float a time in
        seconds and a time span (``"110s"``, ``pd.Timedelta``) a time, on the record's clock.
    rows_where : str or list of str, optional
        Conditions ``"COLUMN OP NUMBER"`` (OP one of ``>=, <=, ==, !=, >, <``), e.g. ``"controller.cmd_thrust>0"``
        for the airborne part of a flight: the rows where every one holds are kept (after ``start`` / ``stop``),
        each run of them becoming a record. The column may be a channel or not; ``True`` / ``False`` compare as
        1 / 0; a NaN compares false.
    margin : float or time span
        Time left out at both ends of every run of ``rows_where`` (seconds, or ``"1s"``).
    resample : bool
        A CSV file with uneven time stamps: put its rows on a uniform grid at ``fs`` by zero-order hold
        (:func:`tsfdi.align`), split into records at logging gaps.
    nan_policy : {"raise", "omit"}
        An empty, NaN or infinite value in a used column: ``"raise"`` refuses it (naming the file, the column, the
        line and the time); ``"omit"`` splits the record there into records.
    records : int or list of int, optional
        netCDF records to use, by the ``record`` coordinate (default every record).
    where : mapping of str to value or list of values, optional
        netCDF records whose per-record coordinate holds one of the values, e.g. ``{"state": "healthy"}``; every
        condition holds.
    topics : str or list of str, optional
        Flight logs and topic folders (required there): the topics to read.
    require_choice : bool
        For a caller that pools the records into one model: a netCDF file of several records then needs
        ``records`` or ``where`` (not to pool healthy and failed records by accident), else a ``ValueError``
        lists the values of the file's per-record coordinates (``state: healthy, rotor1; turbulence: ...``).

    Returns
    -------
    Records
        ``values`` (one float64 ``(nobs, k)`` array per record), ``channels`` (the column names), ``fs``,
        ``times`` (per record its time stamps in seconds: the file's clock, a flight log's time since the start
        of logging), ``files`` (per record the file, as given) and ``ids`` (the record's name within the file:
        ``""`` for a CSV file's single record, the netCDF ``record`` coordinate, ``"0"``, ``"1"``, ... for the
        pieces of a split file or ``"3.0"``, ``"3.1"`` for those of record 3); ``state``, ``turbulence`` and
        ``failure_time`` from a netCDF file's coordinates of those names (else ``""`` / NaN).
        :meth:`Records.frames` gives them as ``DataFrame``\\ s for the models.

    Raises
    ------
    ValueError
        Naming the keyword, the file and the column: a missing file, column, topic or record; a non-numeric
        column; a NaN (``nan_policy="raise"``); a time column that is not evenly sampled in the rows used (the
        library's one rule, :func:`tsfdi.align` or ``resample=True`` being the fix) or disagrees with ``fs``; a
        ``rows_where`` that no row meets; files that disagree; a netCDF file of several records without
        ``records`` or ``where`` when ``require_choice``.
    TypeError
        A keyword of the wrong type.
    ImportError
        A flight log without ``pyulog`` (``pip install tsfdi[px4]``).

    Examples
    --------
    A CrazyPAD log (CSV, ``timestamp`` in ms): the two airborne runs, less 1 s at both ends, as two records

    >>> rec = tsfdi.read_records("data/crazypad/controller/normal_flight/E8_log00.csv.gz", time_unit="ms",
    ...                          columns="controller.r_roll,controller.r_pitch",
    ...                          rows_where="controller.cmd_thrust>0", margin="1s")   # doctest: +SKIP

    An ALFA flight with uneven time stamps, on a 20 Hz grid

    >>> rec = tsfdi.read_records("data/alfa/engine_commanded_measured/carbonZ_2018-07-18-15-53-31_1_engine_failure"
    ...                          ".csv.gz", columns=["roll_measured", "roll_commanded"], resample=True,
    ...                          fs=20)                                                # doctest: +SKIP

    The healthy records of a netCDF file, the gyroscope of a PX4 log at 50 Hz, two topics of a folder

    >>> rec = tsfdi.read_records("data/hexacopter.nc", where={"state": "healthy"},
    ...                          columns=["roll", "pitch"])                            # doctest: +SKIP
    >>> rec = tsfdi.read_records("data/px4/sample.ulg", topics="sensor_combined", fs=50,
    ...                          start="12s")                                          # doctest: +SKIP
    >>> rec = tsfdi.read_records("flight/", topics=["mavros-imu-data", "mavros-nav_info-roll"], time_unit="ns",
    ...                          fs=20)                                                # doctest: +SKIP
    >>> model = tsfdi.VAR(rec.frames(), 4).fit()                                       # doctest: +SKIP
    """
    opt = _options(columns, time, time_unit, fs, start, stop, rows_where, margin, resample, nan_policy, records,
                   where, topics, require_choice)
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    if not isinstance(paths, Sequence) or not paths or not all(isinstance(p, (str, os.PathLike)) for p in paths):
        raise TypeError(f"paths must be a file name (str or path-like) or a non-empty list of them, got {paths!r}")
    names = [os.fspath(p) for p in paths]
    twice = next((p for p in names if names.count(p) > 1), None)
    if twice is not None:
        raise ValueError(f"paths: {twice} is given twice")
    parts = [_read_file(p, opt) for p in names]
    first = parts[0]
    cols = list(first.frames[0].columns)
    for p, part in zip(names[1:], parts[1:]):
        if list(part.frames[0].columns) != cols:
            raise ValueError(f"paths: {p} gives the column(s) {list(part.frames[0].columns)} but {names[0]} gives "
                             f"{cols}: every file must give the same ones (choose them with columns)")
        if abs(part.fs / first.fs - 1) > 0.01:
            raise ValueError(f"paths: {p} is sampled at {part.fs:.6g} Hz but {names[0]} at {first.fs:.6g} Hz: every "
                             "file must have the same rate (within 1 %)")
    frames = [f for part in parts for f in part.frames]
    n = len(frames)

    def label(key: str, default: Any) -> np.ndarray:
        return np.array([v for part in parts for v in part.labels.get(key, [default] * len(part.frames))])

    failure = label("failure_time", np.nan).astype(np.float64)
    return Records([np.ascontiguousarray(f.to_numpy(dtype=np.float64)) for f in frames], label("state", "").astype(str),
                   label("turbulence", "").astype(str), failure, np.array([i for part in parts for i in part.ids],
                                                                          dtype=object),
                   np.ones(n, dtype=bool), tuple(cols), first.fs,
                   times=[f.index.to_numpy(dtype=np.float64) for f in frames],
                   files=np.array([p for p, part in zip(names, parts) for _ in part.frames], dtype=object))

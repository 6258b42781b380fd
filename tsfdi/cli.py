"""The ``tsfdi`` command line: ``tsfdi <command> [options]`` (also ``python -m tsfdi``).

Sub-commands register themselves in :data:`COMMANDS` through :func:`command`: a function that adds its
options to an ``argparse`` parser and a function that runs it. Adding a sub-command is one decorated pair.

Data files (CSV, netCDF such as ``tsfdi simulate`` writes, PX4 flight logs) are read by :func:`_read_records` into
records: one ``DataFrame`` per record with the chosen columns as named channels and a ``time`` index in seconds,
so the models match channels by name. Window lengths and steps follow pandas ``rolling``: a bare integer counts
samples, a time span (``"2s"``, ``"500ms"``) is converted with the sampling frequency.

Errors never end in a traceback: :func:`main` prints the sub-command's usage and ``tsfdi <command>: error: ...``
naming the flag, file and column the user typed, and returns 2, as ``argparse`` does for a bad flag value.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi import __version__

__all__ = ["main", "command", "COMMANDS"]

#: name -> (help, add_arguments(parser), run(args) -> int)
COMMANDS: dict[str, tuple[str, Callable, Callable]] = {}

#: names of a CSV column taken as the time index when ``--time-column`` is not given (case-insensitive)
TIME_COLUMNS = ("time", "t", "timestamp", "%time")
#: units of a numeric CSV time column (``--time-unit``), in seconds
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}

#: a sampling step further than this fraction from the median step is a gap (or jitter) the command refuses
JITTER = 0.5


def command(name: str, help: str, add_arguments: Callable[[argparse.ArgumentParser], None]):
    """Register ``run(args) -> int`` as the sub-command ``name``."""
    def deco(run):
        COMMANDS[name] = (help, add_arguments, run)
        return run
    return deco


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """``--help`` shows every default except an absent one (``None``) and an off switch (``False``)."""

    def _get_help_string(self, action: argparse.Action) -> str:
        if action.default is None or action.default is False:
            return action.help or ""
        return super()._get_help_string(action)


# ------------------------------------------------------------------------------ flag values (argparse types)
def _finite(text: str) -> float:
    """A finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return value


def _positive(text: str) -> float:
    """A finite number > 0."""
    value = _finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return value


def _probability(text: str) -> float:
    """A number strictly between 0 and 1."""
    value = _finite(text)
    if not 0 < value < 1:
        raise argparse.ArgumentTypeError(f"must be strictly between 0 and 1, got {text!r}")
    return value


def _integer(text: str, minimum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {text!r}")
    return value


def _count(text: str) -> int:
    """An integer >= 1."""
    return _integer(text, 1)


def _seed(text: str) -> int:
    """An integer >= 0."""
    return _integer(text, 0)


def _two_or_more(text: str) -> int:
    """An integer >= 2."""
    return _integer(text, 2)


def _timedelta(text: str) -> pd.Timedelta | None:
    """``text`` as a time span with a unit (``"2s"``, ``"500ms"``), or ``None`` if it is not one."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # pandas' deprecation of upper-case units
        try:
            span = pd.Timedelta(text)
        except (ValueError, TypeError, OverflowError):
            return None
    return None if span is pd.NaT else span


def _bare_number(text: str) -> bool:
    """A finite number written without a unit."""
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def _span(text: str) -> int | str:
    """A window length or step as in pandas ``rolling``: an integer >= 1 counts samples; a time span > 0 such as
    '2s' or '500ms' is kept as text (converted with the sampling frequency once it is known)."""
    text = text.strip()
    try:
        n = int(text)
    except ValueError:
        pass
    else:
        if n < 1:
            raise argparse.ArgumentTypeError(f"must be >= 1 sample or a time span such as '2s', got {text!r}")
        return n
    if _bare_number(text):
        raise argparse.ArgumentTypeError(f"a bare number counts samples and must be an integer >= 1; write a time "
                                         f"with its unit, e.g. '{text}s' or '{text}ms', got {text!r}")
    span = _timedelta(text)
    if span is None:
        raise argparse.ArgumentTypeError(f"must be a number of samples (an integer such as 200) or a time span "
                                         f"such as '2s' or '500ms', got {text!r}")
    if span <= pd.Timedelta(0):
        raise argparse.ArgumentTypeError(f"must be a time span > 0, got {text!r}")
    return text


def _spans(text: str) -> list[int | str]:
    """Comma-separated window lengths (each as :func:`_span`)."""
    parts = _csv_list(text)
    if not parts:
        raise argparse.ArgumentTypeError(f"must hold at least one window length such as '10s', got {text!r}")
    return [_span(p) for p in parts]


def _instant(text: str) -> int | float:
    """A position in a record: an integer counts rows from the first (>= 0); a time span such as '110s' is a time
    on the record's clock, returned in seconds (float)."""
    text = text.strip()
    try:
        n = int(text)
    except ValueError:
        pass
    else:
        if n < 0:
            raise argparse.ArgumentTypeError(f"a row number must be >= 0, got {text!r}")
        return n
    if _bare_number(text):
        raise argparse.ArgumentTypeError(f"a bare number is a row number and must be an integer; write a time on "
                                         f"the record's clock with its unit, e.g. '{text}s', got {text!r}")
    span = _timedelta(text)
    if span is None:
        raise argparse.ArgumentTypeError(f"must be a row number or a time such as '110s' or '2min', got {text!r}")
    return span.total_seconds()


def _duration(text: str, minimum: float = 0.0, strict: bool = True) -> float:
    """A time span with its unit (``"60s"``, ``"1ms"``) in seconds; a bare number is refused."""
    text = text.strip()
    span = _timedelta(text)
    if span is None or _bare_number(text):
        hint = f", e.g. '{text}s'" if _bare_number(text) else " such as '60s' or '1ms'"
        raise argparse.ArgumentTypeError(f"must be a time span with its unit{hint}, got {text!r}")
    seconds = span.total_seconds()
    if seconds < minimum or (strict and seconds <= minimum):
        raise argparse.ArgumentTypeError(f"must be {'>' if strict else '>='} {minimum:g} s, got {text!r}")
    return seconds


def _time_from_start(text: str) -> float:
    """A time span >= 0 with its unit, in seconds."""
    return _duration(text, strict=False)


def _csv_list(text: str | None) -> list[str] | None:
    return None if text is None else [t.strip() for t in text.split(",") if t.strip()]


def _records_arg(text: str) -> list[int]:
    """Comma-separated record numbers."""
    return [_seed(t) for t in _csv_list(text) or [""]]


def _where(text: str) -> tuple[str, list[str]]:
    """``KEY=VALUE[,VALUE...]``."""
    key, sep, value = text.partition("=")
    values = _csv_list(value)
    if not sep or not key.strip() or not values:
        raise argparse.ArgumentTypeError(f"must be KEY=VALUE such as 'state=healthy', got {text!r}")
    return key.strip(), values


#: comparisons of ``--rows-where``, longest first (so that '>=' is not read as '>')
_COMPARISONS = {">=": np.greater_equal, "<=": np.less_equal, "==": np.equal, "!=": np.not_equal, ">": np.greater,
                "<": np.less}


def _row_condition(text: str) -> tuple[str, str, float]:
    """``COLUMN OP NUMBER`` with OP one of >=, <=, ==, !=, >, <."""
    m = re.fullmatch(r"\s*(.+?)\s*(>=|<=|==|!=|>|<)\s*(\S+)\s*", text)
    try:
        value = float(m.group(3)) if m else None
    except ValueError:
        value = None
    if value is None or not np.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be COLUMN OP NUMBER with OP one of {', '.join(_COMPARISONS)}, such as "
                                         f"'controller.cmd_thrust>0', got {text!r}")
    return m.group(1), m.group(2), value


def _order(text: str) -> int | str:
    """A model order >= 1, 'bic' or 'rss_sss'."""
    word = text.strip().lower()
    if word in ("bic", "rss_sss"):
        return word
    try:
        return _count(word)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, 'bic' or 'rss_sss', got {text!r}") from None


# ------------------------------------------------------------------------------------------------ reading data
@dataclass
class _Records:
    """The records a command works on.

    Attributes
    ----------
    files : list of str
        Per record, the data file it comes from, as the user typed it.
    frames : list of pandas.DataFrame
        One per record: float64 columns named as in the file, index ``time`` in seconds (uniform at ``fs``).
    ids : list of str
        Record names within their file (``""`` for the single record of a CSV file).
    fs : float
        Sampling frequency in Hz.
    split : bool
        Whether the records are pieces of longer ones: split at NaN (``--nan-policy omit``), into the runs of
        ``--rows-where``, or at the gaps of a flight log or a ``--resample``-d CSV file. A piece too short for the
        command is then dropped with a note instead of refused.
    rows : str
        ``"--start 10 / --stop 35"`` when the part used was selected by row numbers (bare integers), else ``""``.
    """

    files: list
    frames: list
    ids: list
    fs: float
    split: bool = False
    rows: str = ""

    @property
    def path(self) -> str:
        """The data file(s), for messages about all the records."""
        return ", ".join(dict.fromkeys(self.files))

    def label(self, i: int) -> str:
        """``"data.csv"`` or ``"sim.nc record 3"``: record ``i`` as named in messages."""
        return f"{self.files[i]} record {self.ids[i]}" if self.ids[i] else self.files[i]

    def names(self) -> list[str]:
        """The ``record`` column of the tables: the record names within the file, or the labels when the records
        come from several files (all ``""``: a single record, no column)."""
        return [self.label(i) for i in range(len(self.frames))] if len(set(self.files)) > 1 else list(self.ids)

    def about(self, i: int) -> str:
        """:meth:`label` for an error about record ``i``'s data, with the row numbers that cut it: a user who
        typed ``--start 10`` meaning seconds sees why the record is short."""
        if not self.rows:
            return self.label(i)
        first = self.rows.split()[1]
        return (f"{self.label(i)} ({self.rows}: a bare integer is a row number, not a time; write e.g. '{first}s' "
                "for seconds)")

    @property
    def columns(self) -> list[str]:
        return [str(c) for c in self.frames[0].columns]

    def span(self, n: int) -> str:
        """``"200 samples = 2 s"`` at this sampling frequency."""
        return f"{n} sample{'s' if n != 1 else ''} = {n / self.fs:.6g} s"


def _add_data_args(p: argparse.ArgumentParser, *, columns_help: str = "comma-separated columns to use "
                   "(default all numeric columns)", records_help: str = "default every record") -> None:
    p.add_argument("data", nargs="+",
                   help="one or more data files, read with the same options (the records of several files are "
                        "pooled by fit / select-order and each tested by detect / identify / monitor): CSV file (a "
                        "time column, see --time-column and --time-unit), netCDF file such as 'tsfdi simulate' "
                        "writes (variables over time, or over record and time), or PX4 flight log (.ulg, see "
                        "--topics)")
    p.add_argument("--columns", default=None, help=columns_help)
    p.add_argument("--time-column", default=None,
                   help="CSV column holding the time (numbers, see --time-unit, or dates and times): the index, "
                        "never a data channel (default: a column named "
                        f"{' / '.join(TIME_COLUMNS).replace('%', '%%')}; without one --fs is required)")
    p.add_argument("--time-unit", choices=tuple(TIME_UNITS), default=None,
                   help="unit of the CSV time column's numbers: s (default), ms, us or ns (e.g. a 'timestamp' in ms "
                        "since boot); --start / --stop times stay in seconds")
    p.add_argument("--fs", type=_positive, default=None,
                   help="sampling frequency in Hz: needed without a time column (CSV) or coordinate (netCDF), and "
                        "for a flight log (the rate of its grid); beside a time column it must agree with it "
                        "within 1%%")
    p.add_argument("--record", type=_records_arg, action="append", default=None, metavar="N[,N...]",
                   help=f"netCDF records to use, by the 'record' coordinate (repeatable; {records_help})")
    p.add_argument("--where", type=_where, action="append", default=None, metavar="KEY=VALUE[,VALUE...]",
                   help="netCDF records whose per-record coordinate KEY holds one of the VALUEs, e.g. "
                        "'state=healthy' (repeatable: every condition holds)")
    p.add_argument("--topics", default=None,
                   help="PX4 flight log (.ulg): comma-separated topics to read, put on one grid at --fs (required) "
                        "by zero-order hold and split into records at logging gaps; their columns are "
                        "'topic.field', e.g. 'vehicle_attitude.q[0]'")
    p.add_argument("--start", type=_instant, default=None,
                   help="first sample used: a time on the record's clock such as '110s', or a row number (an "
                        "integer, from 0)")
    p.add_argument("--stop", type=_instant, default=None,
                   help="end of the part used (excluded): a time such as '130s' or a row number")
    p.add_argument("--resample", action="store_true",
                   help="CSV file with uneven time stamps: put the rows on a uniform grid at --fs by zero-order hold "
                        "(as a flight log), split into records at logging gaps")
    p.add_argument("--rows-where", type=_row_condition, action="append", default=None, metavar="COLUMN>VALUE",
                   help="keep the rows where a column (used or not) compares so with a number, e.g. "
                        "'controller.cmd_thrust>0' for the airborne part of a flight (repeatable: every condition "
                        "holds); each run of kept rows becomes a record (runs too short for the command are "
                        "dropped), after --start / --stop")
    p.add_argument("--margin", type=lambda t: _duration(t, strict=False), default=0.0,
                   help="time left out at both ends of every run of --rows-where, e.g. '1s' after take-off and "
                        "before landing (default 0s)")
    p.add_argument("--nan-policy", choices=("raise", "omit"), default="raise",
                   help="empty, NaN or infinite values in a used column: 'raise' refuses them, 'omit' splits each "
                        "record at those rows into records (pieces too short for the command are dropped)")


def _check_out(flag: str, path: str | None) -> None:
    """Refuse an output file whose folder does not exist (before any work is done)."""
    if path is None:
        return
    folder = Path(path).expanduser().parent
    if not folder.is_dir():
        raise ValueError(f"{flag} {path}: the folder {str(folder)!r} does not exist")


def _seconds(values: Any, what: str, source: str) -> np.ndarray:
    """Times as float seconds: numbers (seconds), timedeltas, or dates and times -- datetime64 or text such as
    '2018-09-11 18:46:35.350' -- as seconds since the first."""
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
    bad = np.flatnonzero(np.isnan(t) & text.notna().to_numpy())
    if bad.size:
        stamps = pd.to_datetime(text, errors="coerce", format="ISO8601")
        if not (stamps.isna() & text.notna()).any():
            return _seconds(stamps.to_numpy(), what, source)
        raise ValueError(f"{source}: {what} must hold times (numbers, or dates and times such as "
                         f"'2018-09-11 18:46:35.350'); {_where_row(what, bad[0])} holds {v[bad[0]]!r}")
    return t


def _where_row(what: str, i: int) -> str:
    """How to point at data row ``i``: a CSV line (header is line 1) or a netCDF position."""
    return f"line {i + 2}" if what.startswith("column") else f"position {i}"


def _check_time(t: np.ndarray, what: str, source: str, fs: float | None, first: int = 0) -> float:
    """The sampling frequency of the time stamps ``t`` (s), which must be finite, increasing and uniform; ``t``
    starts at row ``first`` of the file (for the line numbers of the messages)."""
    desc = f"{source}: {what}"
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise ValueError(f"{desc} holds {bad.size} empty or non-finite time(s), the first at "
                         f"{_where_row(what, first + bad[0])}")
    if t.size < 2:
        if fs is None:
            raise ValueError(f"{desc} holds a single time: give --fs")
        return fs
    step = np.diff(t)
    dt = float(np.median(step))
    if not dt > 0:
        raise ValueError(f"{desc} does not increase (median step {dt:g} s)")
    off = np.flatnonzero(np.abs(step - dt) > JITTER * dt)
    if off.size:
        i = int(off[0])
        raise ValueError(f"{desc} steps by {step[i]:.6g} s at {_where_row(what, first + i + 1)} "
                         f"(time {t[i + 1]:.6g} s) "
                         f"where the median step is {dt:.6g} s: the rows must be evenly sampled (within "
                         f"{JITTER:.0%}); cut around it with --start / --stop or --rows-where"
                         + (", or put the rows on a grid with --resample --fs RATE" if what.startswith("column")
                            else ""))
    rate = 1.0 / dt
    if fs is not None and abs(fs / rate - 1) > 0.01:
        raise ValueError(f"--fs {fs:g}: the {what} of {source} gives {rate:.6g} Hz (median step {dt:.6g} s); "
                         "leave out --fs or fix the time stamps")
    return rate


def _pick_columns(available: list[str], flag_value: str | None, default: list[str] | None, source: str,
                  kind: str) -> list[str]:
    """The data columns: those of ``--columns``, else ``default`` when the file has them all, else all."""
    wanted = _csv_list(flag_value)
    if wanted:
        missing = [c for c in wanted if c not in available]
        if missing:
            raise ValueError(f"--columns: {source} has no {kind} {', '.join(repr(c) for c in missing)}; its "
                             f"{kind}s are {available}")
        if len(set(wanted)) != len(wanted):
            raise ValueError(f"--columns {flag_value}: a {kind} is named twice")
        return wanted
    if default and all(c in available for c in default):
        return list(default)
    if not available:
        raise ValueError(f"{source} has no numeric {kind} over time")
    return available


def _row_mask(args: argparse.Namespace, available: list[str], path: str, kind: str, values: Any) -> Any:
    """The rows that meet every ``--rows-where`` condition (None without one); ``values(name)`` gives a column of
    the file, rows on the last axis. A NaN compares false: its row is left out."""
    if not args.rows_where:
        return None
    mask = True
    for col, op, value in args.rows_where:
        if col not in available:
            raise ValueError(f"--rows-where {col}{op}{value:g}: {path} has no numeric {kind} {col!r}; its numeric "
                             f"{kind}s are {available}")
        with np.errstate(invalid="ignore"):
            mask = mask & _COMPARISONS[op](np.asarray(values(col), dtype=np.float64), value)
    return mask


def _read_csv(args: argparse.Namespace, default: list[str] | None) -> tuple[list, list, float | None, str | None,
                                                                           list]:
    from tsfdi._data import read_csv

    path = args.data
    df = read_csv(path, "data")
    if len(df) == 0:
        raise ValueError(f"data: {path} has a header but no rows")
    df.columns = [str(c) for c in df.columns]
    tcol = args.time_column
    if tcol is not None and tcol not in df.columns:
        raise ValueError(f"--time-column: {path} has no column {tcol!r}; its columns are {list(df.columns)}")
    if tcol is None:
        lower = {c.strip().lower(): c for c in df.columns}
        tcol = next((lower[n] for n in TIME_COLUMNS if n in lower), None)
    if tcol is None and args.time_unit is not None:
        raise ValueError(f"--time-unit: {path} has no time column ({' / '.join(TIME_COLUMNS)}); name it with "
                         "--time-column")
    if tcol is None and args.fs is None:
        raise ValueError(f"{path} has no time column ({' / '.join(TIME_COLUMNS)}): name it with --time-column, or "
                         "give --fs to count the rows as samples at that rate")
    data_cols = [c for c in df.columns if c != tcol]
    numeric = [c for c in data_cols if pd.api.types.is_numeric_dtype(df[c]) and not pd.api.types.is_bool_dtype(df[c])]
    cols = _pick_columns(numeric if args.columns is None and numeric else data_cols, args.columns, default, path,
                         "column")
    skipped = [c for c in data_cols if c not in numeric]
    if args.columns is None and skipped and cols == numeric:
        print(f"note: left out the non-numeric column(s) {skipped} of {path}", file=sys.stderr)
    flags = [c for c in data_cols if pd.api.types.is_bool_dtype(df[c])]         # True / False compare as 1 / 0
    mask = _row_mask(args, numeric + flags, path, "column", lambda c: df[c].to_numpy())
    if args.resample and (tcol is None or args.fs is None):
        raise ValueError(f"--resample: {path} needs a time column and --fs, the rate of the grid the rows are put on")
    for c in cols:
        col = df[c]
        if pd.api.types.is_bool_dtype(col):
            raise ValueError(f"{path}: column {c!r} is not numeric (it holds True / False)")
        values = pd.to_numeric(col, errors="coerce")
        bad = np.flatnonzero(values.isna().to_numpy() & col.notna().to_numpy())
        if bad.size:
            raise ValueError(f"{path}: column {c!r} is not numeric (line {bad[0] + 2} holds {col.iloc[bad[0]]!r}); "
                             "leave it out with --columns")
        df[c] = values
    if tcol is None:
        t, fs, clock = np.arange(len(df)) / args.fs, args.fs, None
    else:
        if args.time_unit is not None and not pd.api.types.is_numeric_dtype(df[tcol]):
            raise ValueError(f"--time-unit: the time column {tcol!r} of {path} does not hold numbers (its first "
                             f"value is {df[tcol].iloc[0]!r}); dates and times need no unit")
        t = _seconds(df[tcol].to_numpy(), f"column {tcol!r}", path) * TIME_UNITS[args.time_unit or "s"]
        fs, clock = None, f"column {tcol!r}"
        guess = _rate_guess(t)
        if args.time_column is None and args.time_unit is None and guess is not None and guess < 1.0:
            print(f"note: read the time column {tcol!r} of {path} in seconds, which gives {guess:.6g} Hz; if it "
                  "counts milliseconds (or us, ns), give --time-unit ms", file=sys.stderr)
    frame = pd.DataFrame(df[cols].to_numpy(dtype=np.float64), columns=cols, index=pd.Index(t, name="time"))
    if args.resample:
        return _resampled(frame, df, args, path, numeric + flags)
    return [frame], [""], fs, clock, [mask]


def _resampled(frame: pd.DataFrame, df: pd.DataFrame, args: argparse.Namespace, path: str,
               comparable: list[str]) -> tuple[list, list, float, None, list]:
    """``--resample``: the rows of a CSV file put on a uniform grid at ``--fs`` by zero-order hold
    (:func:`tsfdi.datasets.align`, split at logging gaps and, with ``--nan-policy omit``, at NaN), with the
    ``--rows-where`` columns held alike."""
    from tsfdi.datasets import align

    extra = [c for c, _, _ in args.rows_where or [] if c not in frame.columns]
    source = frame.assign(**{c: df[c].to_numpy(dtype=np.float64) for c in dict.fromkeys(extra)})
    source.index = pd.to_timedelta(frame.index.to_numpy(), unit="s")
    try:
        records = align(source, args.fs, nan_policy=args.nan_policy)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"--resample: {path}: {exc}") from None
    return _on_grid(records, list(frame.columns), comparable, args, path)


def _on_grid(records: list, cols: list[str], comparable: list[str], args: argparse.Namespace,
             path: str) -> tuple[list, list, float, None, list]:
    """The records of :func:`tsfdi.datasets.align` (at ``--fs``) as the readers return them: their ``cols``,
    time in seconds, numbered when several, and the ``--rows-where`` mask of each."""
    frames = [pd.DataFrame(r[cols].to_numpy(), columns=cols,
                           index=pd.Index(r.index.total_seconds().to_numpy(), name="time")) for r in records]
    masks = [_row_mask(args, comparable, path, "column", lambda c, r=r: r[c].to_numpy()) for r in records]
    return frames, [str(k) for k in range(len(frames))] if len(frames) > 1 else [""], args.fs, None, masks


def _select_records(ds: Any, args: argparse.Namespace, required: bool) -> list[int]:
    """Positions along ``record`` chosen by ``--record`` and ``--where``."""
    path, n = args.data, ds.sizes["record"]
    labels = np.asarray(ds["record"].values) if "record" in ds.coords else np.arange(n)
    per_record = [k for k in ds.variables if ds[k].dims == ("record",) and k != "record"]
    pick = list(range(n))
    if args.record:
        pick = []
        for r in (r for group in args.record for r in group):
            hits = np.flatnonzero(labels == r)
            if not hits.size:
                raise ValueError(f"--record {r}: {path} has no record {r}; its records are "
                                 f"{labels.min()}..{labels.max()} ({n})")
            pick.append(int(hits[0]))
    for key, values in args.where or []:
        if key not in per_record:
            raise ValueError(f"--where {key}=...: {path} has no per-record coordinate {key!r}; they are {per_record}")
        v = np.asarray(ds[key].values)
        match = np.zeros(n, dtype=bool)
        for text in values:
            if v.dtype.kind == "b":
                if text.lower() not in ("true", "false", "1", "0"):
                    raise ValueError(f"--where {key}={text}: {key} holds True / False")
                match |= v == (text.lower() in ("true", "1"))
            elif v.dtype.kind in "iuf":
                try:
                    match |= v == float(text)
                except ValueError:
                    raise ValueError(f"--where {key}={text}: {key} holds numbers") from None
            else:
                match |= v.astype(str) == text
        if not match[pick].any():
            raise ValueError(f"--where {key}={','.join(values)}: no selected record of {path} matches; {key} holds "
                             f"{sorted(set(v.astype(str).tolist()))}")
        pick = [i for i in pick if match[i]]
    if required and not args.record and not args.where and n > 1:
        hints = "; ".join(f"{k}: {', '.join(sorted(set(np.asarray(ds[k].values).astype(str).tolist())))}"
                          for k in per_record if ds[k].dtype.kind in "OUSb" or k == "state")
        raise ValueError(f"{path} holds {n} records: choose the ones to use with --record N[,N...] or --where "
                         f"KEY=VALUE ({hints or 'records ' + str(labels.tolist())})")
    return pick


def _read_netcdf(args: argparse.Namespace, default: list[str] | None,
                 required: bool) -> tuple[list, list, float | None, str | None, list]:
    import xarray as xr

    path = args.data
    for flag in ("time_column", "time_unit", "resample"):
        if getattr(args, flag) not in (None, False):
            raise ValueError(f"--{flag.replace('_', '-')} is for CSV files; {path} is netCDF (its time is the 'time' "
                             "coordinate)")
    try:
        with xr.open_dataset(path, engine="h5netcdf") as ds:
            ds = ds.load()
    except (OSError, ValueError, TypeError, KeyError) as exc:
        raise ValueError(f"data: {path} cannot be read as a netCDF file ({type(exc).__name__}: {exc})") from None
    records = "record" in ds.dims
    if not records and (args.record or args.where):
        raise ValueError(f"--{'record' if args.record else 'where'}: {path} has no 'record' dimension (one record)")
    dims = {("time",), ("record", "time")} if records else {("time",)}
    available = [str(k) for k, v in ds.data_vars.items() if v.dims in dims and v.dtype.kind in "iuf"]
    others = [str(k) for k, v in ds.data_vars.items() if str(k) not in available]
    if args.columns is not None:
        for c in _csv_list(args.columns) or []:
            if c in others:
                raise ValueError(f"--columns: variable {c!r} of {path} is not a numeric series over time (dims "
                                 f"{ds[c].dims}, dtype {ds[c].dtype})")
    cols = _pick_columns(available, args.columns, default, path, "variable")
    if "time" in ds.coords:
        t, fs, clock = _seconds(ds["time"].values, "coordinate 'time'", path), None, "coordinate 'time'"
    elif args.fs is not None:
        t, fs, clock = np.arange(ds.sizes["time"]) / args.fs, args.fs, None
    else:
        raise ValueError(f"{path} has no 'time' coordinate: give --fs")
    index = pd.Index(t, name="time")
    mask = _row_mask(args, available, path, "variable", lambda c: ds[c].values)
    if not records:
        return [pd.DataFrame({c: ds[c].values.astype(np.float64) for c in cols}, index=index)], [""], fs, clock, [mask]
    pick = _select_records(ds, args, required)
    labels = np.asarray(ds["record"].values) if "record" in ds.coords else np.arange(ds.sizes["record"])
    frames = [pd.DataFrame({c: (ds[c].values[i] if ds[c].dims[0] == "record" else ds[c].values).astype(np.float64)
                            for c in cols}, index=index) for i in pick]
    masks = [None if mask is None else np.broadcast_to(mask, (ds.sizes["record"], len(t)))[i] for i in pick]
    return frames, [str(labels[i]) for i in pick], fs, clock, masks


def _read_ulog(args: argparse.Namespace, default: list[str] | None) -> tuple[list, list, float, None, list]:
    """The topics ``--topics`` of a PX4 log on one grid at ``--fs`` (zero-order hold; split at gaps)."""
    from tsfdi.datasets import align, read_ulog

    path = args.data
    for flag in ("time_column", "time_unit", "resample", "record", "where"):
        if getattr(args, flag):
            raise ValueError(f"--{flag.replace('_', '-')} is not for ULog files; {path} is one")
    topics = _csv_list(args.topics)
    if not topics or args.fs is None:
        raise ValueError(f"--{'topics' if not topics else 'fs'}: {path} is a PX4 flight log; name the topics to "
                         "read with --topics (e.g. vehicle_attitude,sensor_combined) and the rate of the grid "
                         "they are aligned on with --fs")
    try:
        records = align(read_ulog(path, topics), args.fs, nan_policy=args.nan_policy)
    except (ValueError, TypeError) as exc:
        msg = re.sub(r"^path: ", "data: ", str(exc))
        raise ValueError(re.sub(r"^(topics: |(?=frames\[))", "--topics: ", msg)) from None
    available = [str(c) for c in records[0].columns]
    return _on_grid(records, _pick_columns(available, args.columns, default, path, "column"), available, args, path)


def _position(x: int | float | None, t: np.ndarray, fs: float | None) -> int | None:
    """``--start`` / ``--stop`` as a row position: a row number as it is, a time (s) on the clock ``t`` (half a
    sample early, at ``fs``)."""
    return x if x is None or isinstance(x, int) else int(np.searchsorted(t, x - (0.5 / fs if fs else 0.0)))


def _rate_guess(t: np.ndarray) -> float | None:
    """1 / the median of the positive finite steps of ``t`` (None without one): the rate of a clock not yet
    checked, for rounding --start / --stop and for hints."""
    step = np.diff(t)
    step = step[np.isfinite(step) & (step > 0)]
    return 1.0 / float(np.median(step)) if step.size else None


def _runs_where(frames: list, ids: list, first: list, masks: list, args: argparse.Namespace,
                path: str) -> tuple[list, list, list]:
    """The runs of rows that meet ``--rows-where`` (``masks``), less ``--margin`` at both ends: one record each,
    named ``"<record>.<k>"``, with the file row where each starts."""
    out_frames, out_ids, out_first = [], [], []
    for f, rid, row0, mask in zip(frames, ids, first, masks):
        t = f.index.to_numpy()
        for k, (a, b) in enumerate(_runs(mask)):
            a, b = (int(np.searchsorted(t[a:b], t[a] + args.margin) + a),
                    int(np.searchsorted(t[a:b], t[b - 1] - args.margin, side="right") + a))
            if b > a:
                out_frames.append(f.iloc[a:b])
                out_ids.append(f"{rid}.{k}" if rid else str(k))
                out_first.append(row0 + a)
    if not out_frames:
        conds = " and ".join(f"{c}{op}{v:g}" for c, op, v in args.rows_where)
        raise ValueError(f"--rows-where: no row of {path} meets {conds}"
                         + (f" for more than --margin {args.margin:g} s at both ends" if args.margin else ""))
    return out_frames, out_ids, out_first


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of every run of True in ``mask``."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def _split_at_nan(frame: pd.DataFrame) -> list[pd.DataFrame]:
    """The runs of rows without NaN."""
    return [frame.iloc[a:b] for a, b in _runs(np.isfinite(frame.to_numpy()).all(axis=1))]


def _read_records(args: argparse.Namespace, *, default_columns: list[str] | None = None,
                  required: bool = False) -> _Records:
    """The records of the data files ``args.data`` (one or more), each read by :func:`_read_file` with the same
    flags, in the order given: every file must give the same columns and sampling frequency (within 1 %)."""
    paths = args.data if isinstance(args.data, list) else [args.data]
    if len(set(paths)) < len(paths):
        twice = next(p for p in paths if paths.count(p) > 1)
        raise ValueError(f"data: {twice} is given twice")
    parts = [_read_file(argparse.Namespace(**{**vars(args), "data": p}), default_columns=default_columns,
                        required=required) for p in paths]
    first = parts[0]
    for part in parts[1:]:
        if part.columns != first.columns:
            raise ValueError(f"data: {part.path} gives the column(s) {part.columns} but {first.path} gives "
                             f"{first.columns}: every file must give the same ones (choose them with --columns)")
        if abs(part.fs / first.fs - 1) > 0.01:
            raise ValueError(f"data: {part.path} is sampled at {part.fs:.6g} Hz but {first.path} at {first.fs:.6g} "
                             "Hz: every file must have the same rate (within 1 %)")
    if len(parts) == 1:
        return first
    return _Records([f for p in parts for f in p.files], [f for p in parts for f in p.frames],
                    [i for p in parts for i in p.ids], first.fs, any(p.split for p in parts), first.rows)


def _read_file(args: argparse.Namespace, *, default_columns: list[str] | None = None,
               required: bool = False) -> _Records:
    """The records of the data file ``args.data`` selected by the data flags of :func:`_add_data_args`.

    Parameters
    ----------
    args : argparse.Namespace
        ``data`` (one path), ``columns``, ``time_column``, ``time_unit``, ``fs``, ``record``, ``where``,
        ``topics``, ``start``, ``stop``, ``rows_where``, ``margin``, ``nan_policy``.
    default_columns : list of str, optional
        Columns used without ``--columns`` when the file has them all (the channels of a model).
    required : bool
        Refuse a netCDF file of several records without ``--record`` / ``--where``.

    Raises
    ------
    ValueError
        Naming the flag, the file and the column: a missing file, column or record, a non-numeric column, NaN
        (with ``nan_policy="raise"``), a time column that is not evenly sampled (in the rows used) or disagrees with
        ``--fs``, a ``--rows-where`` that no row meets.
    """
    path = args.data
    if args.margin and not args.rows_where:
        raise ValueError("--margin trims the runs of --rows-where: give --rows-where too")
    p = Path(path)
    if not p.exists():
        raise ValueError(f"data: {path} does not exist")
    if p.is_dir():
        raise ValueError(f"data: {path} is a folder, not a data file")
    kind = {".nc": "netcdf", ".nc4": "netcdf", ".netcdf": "netcdf", ".cdf": "netcdf", ".h5": "netcdf",
            ".ulg": "ulog"}.get(p.suffix.lower(), "csv")
    if kind != "ulog" and args.topics:
        raise ValueError(f"--topics is for PX4 flight logs (.ulg); {path} is not one")
    if kind == "netcdf":
        frames, ids, fs, clock, masks = _read_netcdf(args, default_columns, required)
    elif kind == "ulog":
        frames, ids, fs, clock, masks = _read_ulog(args, default_columns)
    else:
        if args.record or args.where:
            raise ValueError(f"--{'record' if args.record else 'where'} selects records of a netCDF file; {path} "
                             "is read as CSV")
        frames, ids, fs, clock, masks = _read_csv(args, default_columns)
    if isinstance(args.start, float) and isinstance(args.stop, float) and args.stop <= args.start:
        raise ValueError(f"--stop must come after --start, got {args.stop:g} s <= {args.start:g} s")
    first = [0] * len(frames)           # row of the file / record where each frame starts
    rows = " / ".join(f"--{f} {getattr(args, f)}" for f in ("start", "stop") if isinstance(getattr(args, f), int))
    if args.start is not None or args.stop is not None:
        rate = fs if fs is not None else _rate_guess(frames[0].index.to_numpy())
        cut = [[_position(x, f.index.to_numpy(), rate) for x in (args.start, args.stop)] for f in frames]
        keep = [i for i, (f, (a, b)) in enumerate(zip(frames, cut)) if len(f.iloc[a:b])]
        if not keep:
            spans = ", ".join(f"{f.index[0]:g} s to {f.index[-1]:g} s ({len(f)} rows)" for f in frames[:5])
            raise ValueError(f"--start / --stop select no row of {path} (times {spans})")
        first = [len(frames[i].iloc[:cut[i][0]]) for i in keep]
        frames, ids = [frames[i].iloc[slice(*cut[i])] for i in keep], [ids[i] for i in keep]
        masks = [None if masks[i] is None else masks[i][slice(*cut[i])] for i in keep]
    if args.rows_where:
        frames, ids, first = _runs_where(frames, ids, first, masks, args, path)
    if fs is None:      # the file's clock, checked on the rows used only
        rates = [_check_time(f.index.to_numpy(), clock, path, args.fs, row0) for f, row0 in zip(frames, first)]
        fs = rates[0]
        other = next((k for k, r in enumerate(rates) if abs(r / fs - 1) > 0.01), None)
        if other is not None:
            raise ValueError(f"{path}: the {clock} gives {fs:.6g} Hz in record {ids[0]} but {rates[other]:.6g} Hz in "
                             f"record {ids[other]}: the records must have one rate (within 1 %)")
    out_frames, out_ids = [], []
    for f, rid, row0 in zip(frames, ids, first):
        bad = ~np.isfinite(f.to_numpy())
        if not bad.any():
            out_frames.append(f)
            out_ids.append(rid)
            continue
        if args.nan_policy == "omit":
            parts = _split_at_nan(f)
            out_frames += parts
            out_ids += [f"{rid}.{k}" if rid else str(k) for k in range(len(parts))]
            continue
        j = int(np.flatnonzero(bad.any(axis=0))[0])
        i = int(np.flatnonzero(bad[:, j])[0])
        where = f"record {rid} of {path}" if rid else path
        at = f"line {row0 + i + 2}, " if kind == "csv" else ""
        what = "variable" if kind == "netcdf" else "column"
        raise ValueError(f"{where}: {what} {f.columns[j]!r} holds {int(bad[:, j].sum())} empty, NaN or infinite "
                         f"value(s), the first at {at}time {f.index[i]:.6g} s; leave it out with --columns, cut it "
                         "off with --start / --stop, or give --nan-policy omit to split the record there")
    if not out_frames:
        raise ValueError(f"--nan-policy omit: every row of {path} holds an empty or NaN value")
    split = kind == "ulog" or args.resample or bool(args.rows_where) or len(out_frames) > len(frames)
    return _Records([path] * len(out_frames), out_frames, out_ids, float(fs), split, rows)


def _drop_short(data: _Records, need: int, why: str) -> _Records:
    """The records of at least ``need`` samples: shorter pieces of a split record are dropped with a note, a short
    record of the file is refused."""
    short = [i for i, f in enumerate(data.frames) if len(f) < need]
    if not short:
        return data
    if not data.split or len(short) == len(data.frames):
        i = short[0]
        raise ValueError(f"{data.about(i)} is too short: {data.span(len(data.frames[i]))} at {data.fs:g} Hz, "
                         f"{why} needs at least {need}")
    print(f"note: dropped {len(short)} piece(s) of split records shorter than {need} samples ({why})",
          file=sys.stderr)
    keep = [i for i in range(len(data.frames)) if i not in set(short)]
    return _Records([data.files[i] for i in keep], [data.frames[i] for i in keep], [data.ids[i] for i in keep],
                    data.fs, True, data.rows)


def _reword(exc: Exception, data: _Records, subs: tuple = ()) -> ValueError:
    """A library error about ``y`` / ``signal`` (``y[i]`` for record ``i``) told about the user's file."""
    msg = str(exc)
    m = re.match(r"(y|signal)(?:\[(\d+)\])?(:? )", msg)
    if m:
        i = int(m.group(2)) if m.group(2) else 0
        msg = data.about(i if i < len(data.frames) else 0) + m.group(3) + msg[m.end():]
    for old, new in subs:
        msg = msg.replace(old, new)
    return ValueError(msg)


# ---------------------------------------------------------------------------------------------------- models
def _load(flag: str, spec: str, path: str) -> Any:
    from tsfdi.models import ARXResults, load

    try:
        res = load(path)
    except (OSError, ValueError, TypeError) as exc:
        raise ValueError(f"{flag} {spec}: {exc}") from None
    if isinstance(res, ARXResults):
        raise ValueError(f"{flag} {spec}: an ARX (input-output) model; the command line tests AR / VAR models")
    return res


def _load_models(flag: str, specs: list[str]) -> dict:
    """``NAME=PATH`` or ``PATH`` (name = the file's stem) -> loaded models; a name given twice is refused."""
    models, given = {}, {}
    for spec in specs:
        name, sep, path = spec.partition("=")
        if not sep:
            name, path = Path(spec).stem, spec
        if not name or not path:
            raise ValueError(f"{flag} {spec}: expected NAME=PATH or PATH")
        if name in given:
            raise ValueError(f"{flag}: the name {name!r} is given twice ({given[name]} and {spec}); name each model "
                             "as NAME=PATH")
        given[name] = spec
        models[name] = _load(flag, spec, path)
    return models


def _channels(res: Any) -> list[str]:
    return [str(c) for c in res.model.data.channels]


def _check_channels(data: _Records, models: dict) -> None:
    """Every model (keyed by how the user gave it, ``"--baseline m.npz"``) has as many channels as the data has
    columns."""
    k = len(data.columns)
    bad = {n: _channels(m) for n, m in models.items() if len(_channels(m)) != k}
    if bad:
        name, ch = next(iter(bad.items()))
        raise ValueError(f"--columns: {data.path} gives {k} column(s) {data.columns} but {name} was fitted on "
                         f"{len(ch)} channel(s) {ch}; choose them with --columns")


def _test(args: argparse.Namespace, threshold: Any = "theoretical") -> Any:
    from tsfdi.detection import FTest, LjungBox, MeanTest

    if args.method == "whiteness":
        return LjungBox(lags=args.lags, alpha=args.alpha, threshold=threshold)
    test = FTest if args.method == "variance" else MeanTest
    return test(alpha=args.alpha, threshold=threshold)


def _tests(args: argparse.Namespace, models: dict, window: int | None) -> Any:
    """The test of ``args``: one with the theoretical threshold for every model, or (``--threshold calibrated``)
    one per model, calibrated for windows of ``window`` signal samples on the held-out residuals of the records
    the model was fitted on (stored in its file): each record through the model fitted on the others, a single
    record cut into blocks (:meth:`tsfdi.VAR.held_out_residuals`). ``models`` maps a name (the key the engine
    uses) to ``(flag text, results)``."""
    from tsfdi.detection import ScaledChi2Threshold

    if args.threshold == "theoretical":
        if args.min_windows is not None:
            raise ValueError("--min-windows is for --threshold calibrated")
        return _test(args)
    min_windows = 30 if args.min_windows is None else args.min_windows
    if min_windows < 5:
        raise ValueError(f"--min-windows must be at least 5, got {min_windows}")
    if window is None:
        raise ValueError("--threshold calibrated needs --window: the threshold is calibrated for windows of one "
                         "length")
    out = {}
    for name, (flag, res) in models.items():
        try:
            estimator = ScaledChi2Threshold(args.alpha, min_windows=min_windows)
            out[name] = _test(args, estimator).calibrate(res.model.held_out_residuals(), window=window)
        except ValueError as exc:
            recs = res.model.records
            cut = (f"; a single record is cut into 10 blocks of about {recs[0].nobs // 10} samples, each held out in "
                   "turn" if len(recs) == 1 else "")
            raise ValueError(f"--threshold calibrated, {flag}: {exc} (the null sample: held-out residuals of the "
                             f"{len(recs)} record(s), {sum(r.nobs for r in recs)} samples, the model was fitted "
                             f"on{cut}); fit the model on more or longer healthy records (several flights), or "
                             "test shorter windows") from None
    return out


def _test_args(p: argparse.ArgumentParser, lags: int = 20) -> None:
    p.add_argument("--method", choices=("whiteness", "variance", "mean"), default="whiteness",
                   help="residual test: Ljung-Box whiteness test, F test of the residual variance, or test of a "
                        "shift of the residual mean (a new trim: what a closed loop leaves of a compensated "
                        "fault; use it with --threshold calibrated)")
    p.add_argument("--alpha", type=_probability, default=1e-3, help="type I risk per channel and tested window")
    p.add_argument("--lags", type=_count, default=lags, help="Ljung-Box lags")
    p.add_argument("--threshold", choices=("theoretical", "calibrated"), default="theoretical",
                   help="theoretical: the test's chi-square / F law, exact only for the data the model was fitted "
                        "on; calibrated: the law of the statistic fitted to the model's held-out residuals (each "
                        "record it was fitted on, through the model fitted on the others; one record is cut into "
                        "blocks), so that --alpha holds on new records (needs --window)")
    p.add_argument("--min-windows", type=_count, default=None,
                   help="--threshold calibrated: fewest non-overlapping windows of held-out residuals the threshold "
                        "may rest on (default 30, at least 5); with few, its bound over the records is wider")


def _window_args(p: argparse.ArgumentParser, window_help: str, *, required: bool = False) -> None:
    samples = ("a bare integer counts samples (as pandas rolling), a time span such as '2s' or '500ms' is "
               "converted with the sampling frequency")
    p.add_argument("--window", type=_span, default=None, required=required, help=f"{window_help}: {samples}")
    p.add_argument("--step", type=_span, default="1s", help=f"distance between window starts: {samples}")


def _min_samples(args: argparse.Namespace, models: dict) -> tuple[int, str]:
    """Fewest samples a tested window needs, and why: the largest model order plus the Ljung-Box lags and one,
    plus three for the F test, plus one for the mean test."""
    order = max(int(m.lags) for m in models.values())
    if args.method == "whiteness":
        return order + args.lags + 1, f"the models' largest order ({order}) with --lags {args.lags}"
    if args.method == "variance":
        return order + 3, f"the models' largest order ({order}) with the F test"
    return order + 1, f"the models' largest order ({order}) with the mean test"


def _windows_in_samples(args: argparse.Namespace, data: _Records, models: dict) -> tuple[int, int]:
    """``--window`` and ``--step`` in samples, checked against the records and the models' orders."""
    from tsfdi._data import window_samples

    W = window_samples(args.window, "--window", data.fs, minimum=2)
    S = window_samples(args.step, "--step", data.fs, minimum=1)
    need, why = _min_samples(args, models)
    if W < need:
        raise ValueError(f"--window {args.window}: {data.span(W)} at {data.fs:g} Hz is too short; {why} needs "
                         f"at least {need} samples")
    shortest = min(range(len(data.frames)), key=lambda i: len(data.frames[i]))
    if W > len(data.frames[shortest]) and not data.split:
        raise ValueError(f"--window {args.window}: {data.span(W)} is longer than {data.about(shortest)} "
                         f"({data.span(len(data.frames[shortest]))} at {data.fs:g} Hz)")
    print(f"window {data.span(W)}, step {data.span(S)}, at {data.fs:g} Hz")
    return W, S


def _table(rows: list[pd.DataFrame], data: _Records) -> pd.DataFrame:
    """Per-record tables stacked, with a leading ``record`` column when the data holds records."""
    names = data.names()
    if any(names):
        rows = [r.assign(record=rid)[["record", *r.columns]] for r, rid in zip(rows, names)]
    return pd.concat(rows, ignore_index=True)


def _show(table: pd.DataFrame) -> None:
    print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}") if len(table) else "(no rows)")


def _write(flag: str, table: pd.DataFrame, path: str | None) -> None:
    if path:
        try:
            table.to_csv(path, index=False)
        except OSError as exc:
            raise ValueError(f"{flag} {path}: cannot write the file ({exc.strerror or exc})") from None
        print(f"wrote {path}")


# ---------------------------------------------------------------------------------------------------- simulate
def _simulate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", required=True, help="output file: netCDF, or a zarr store (format 2) for a name ending in "
                                                ".zarr; either is chunked by record")
    p.add_argument("--records-per-case", type=_count, default=20, help="records per state and turbulence level")
    p.add_argument("--seed", type=_seed, default=2024, help="base seed (record k uses SeedSequence([seed, k]))")
    p.add_argument("--duration", type=_duration, default="60s", help="record length, a time span such as '60s'")
    p.add_argument("--failure-time", type=_time_from_start, default="10s",
                   help="failure instant from the record's start, a time span such as '10s'")
    p.add_argument("--speed", type=_finite, default=5.0, help="forward speed in m/s")
    p.add_argument("--states", default="healthy,rotor1,rotor2,rotor6",
                   help="comma-separated states: healthy, rotor1 .. rotor6")
    p.add_argument("--turbulence", default="light,moderate,severe",
                   help="comma-separated Dryden levels: none, light, moderate, severe")
    p.add_argument("--dt", type=_duration, default="1ms", help="integration step, a time span such as '1ms'")
    p.add_argument("--fs", type=_positive, default=100.0, help="output sampling frequency in Hz")
    p.add_argument("--fleet", default=None, metavar="SPEC",
                   help="a fleet of aircraft of one type (Hansen et al.): each record's mass, centre-of-gravity "
                        "offset, motor constants and inertia drawn from its seed, uniformly around the nominal "
                        "aircraft, and written as the record coordinates mass (kg), cg_x, cg_y (m), "
                        "motor_constant, inertia (factors). SPEC is 'default' (mass=0.05, cg_offset=0.01, "
                        "motor_constant=0.03, inertia=0.05) or comma-separated NAME=VALUE overriding some of "
                        "them, e.g. 'mass=0.1,cg_offset=0.02' (relative spreads except cg_offset in m; see "
                        "tsfdi.datasets.hexacopter.FleetSpread). Default: one aircraft, no fleet")
    p.add_argument("--shipped", action="store_true",
                   help="write only the shipped variables packed as int32 counts (see data/README.md); "
                        "default: every channel as float64")
    p.add_argument("--chunk", type=_count, default=20,
                   help="records per chunk: the chunks are simulated in parallel on the dask scheduler and written "
                        "as they come, so memory holds a few chunks (each chunk x duration x fs x 19 x 8 bytes, and "
                        "the 1 kHz integration of 16 records at a time), whatever the number of records")
    p.add_argument("--scheduler", default="threads",
                   help="dask scheduler of the chunks: threads, processes, synchronous, or the address of a running "
                        "dask.distributed scheduler (e.g. tcp://10.0.0.1:8786) to simulate on its cluster")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _dask_scheduler(value: str) -> Any:
    """A context in which ``dask.compute`` runs on the scheduler ``--scheduler`` names."""
    import dask

    if "://" in value:
        from distributed import Client

        try:
            return Client(value, timeout="10s")
        except (OSError, ValueError) as exc:
            raise ValueError(f"--scheduler {value}: cannot connect to the dask scheduler ({exc})") from None
    if value in ("threads", "processes", "synchronous"):
        return dask.config.set(scheduler=value)
    raise ValueError(f"--scheduler must be threads, processes, synchronous or the address of a dask.distributed "
                     f"scheduler such as tcp://10.0.0.1:8786, got {value!r}")


def _write_chunks(ds: Any, enc: dict, args: argparse.Namespace, zarr: bool) -> int:
    """Write a fleet backed by dask chunk by chunk on the ``--scheduler``; the number of records that lost control."""
    import xarray as xr

    from tsfdi.fleet import compute

    if zarr:        # zarr's own compressor; the record coordinates chunked like the data
        enc = {v: {k: e[k] for k in ("dtype", "scale_factor", "_FillValue") if k in e} for v, e in enc.items()}
        enc.update({c: {"chunks": (args.chunk,)} for c, v in ds.coords.items() if v.dims == ("record",)
                    and c != "record"})
    elif args.scheduler == "processes":
        raise ValueError("--scheduler processes cannot write a netCDF file (the processes of dask's local scheduler "
                         "share no lock on it): write a .zarr store, or use threads or a dask.distributed scheduler")
    with _dask_scheduler(args.scheduler):
        store = ds.to_zarr(args.out, mode="w", encoding=enc, compute=False, zarr_format=2) if zarr else \
            ds.to_netcdf(args.out, engine="h5netcdf", encoding=enc, compute=False)
        compute(store, progress=not args.no_progress)
    with xr.open_zarr(args.out) if zarr else xr.open_dataset(args.out, engine="h5netcdf") as written:
        return int(written["lost_control"].values.sum())


@command("simulate", "simulate hexacopter records (Dryden turbulence, rotor failures) to a netCDF file or zarr store "
         "chunked by record, the chunks in parallel on dask", _simulate_args)
def _simulate(args: argparse.Namespace) -> int:
    import importlib.util

    from tsfdi.datasets.hexacopter import FleetSpread, encode_for_file, make_hexacopter_dataset

    _check_out("--out", args.out)
    zarr = Path(args.out).suffix.lower() == ".zarr"
    if importlib.util.find_spec("dask") is None:      # without the fleet extra: netCDF, simulated in memory
        if zarr or args.scheduler != "threads":
            raise ValueError(f"{'--out ' + args.out if zarr else '--scheduler'}: needs dask and zarr (pip install "
                             "'tsfdi[fleet]')")
        args.chunk = None
    t0 = time.perf_counter()
    fleet = None if args.fleet is None else FleetSpread.from_spec(args.fleet)
    # backed by dask: nothing is simulated until the chunks are written
    ds = make_hexacopter_dataset(args.records_per_case, seed=args.seed, duration=args.duration,
                                 failure_time=args.failure_time, speed=args.speed,
                                 states=tuple(s.strip() for s in args.states.split(",")),
                                 turbulence=tuple(s.strip() for s in args.turbulence.split(",")),
                                 dt=args.dt, fs=args.fs, fleet=fleet, chunks=args.chunk)
    if args.shipped:
        ds, enc = encode_for_file(ds)
    else:
        enc = {v: {"zlib": True, "shuffle": True} for v in ds.data_vars}
    try:
        if args.chunk is None:
            ds.to_netcdf(args.out, engine="h5netcdf", encoding=enc)
            nlost = int(ds["lost_control"].sum())
        else:
            nlost = _write_chunks(ds, enc, args, zarr)
    except OSError as exc:
        raise ValueError(f"--out {args.out}: cannot write the file ({exc.strerror or exc})") from None
    print(f"wrote {ds.sizes['record']} records to {args.out} in {time.perf_counter() - t0:.1f} s; "
          f"lost control in {nlost} record(s)")
    return 0


# ----------------------------------------------------------------------------------------------------- demo
def _demo_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="tsfdi-demo", help="output folder for the figures and tables")
    p.add_argument("--data", default=None, help="hexacopter netCDF file (default: the shipped data/hexacopter.nc)")
    p.add_argument("--records-per-case", type=_two_or_more, default=None,
                   help="use only the first N records of each state and turbulence level (N >= 2; default all)")
    p.add_argument("--fit-records", type=_count, default=10,
                   help="baseline records per state and turbulence level, pooled (excluded from the evaluation)")
    p.add_argument("--pool", choices=("level", "all"), default="level",
                   help="baseline models per turbulence level, or one set across levels")
    p.add_argument("--order", type=_order, default="20", help="model order: an integer, 'bic' or 'rss_sss'")
    p.add_argument("--windows", type=_spans, default="5s,10s,20s",
                   help="comma-separated window lengths: time spans such as '10s', or integers counting samples")
    p.add_argument("--models", default=None, help="comma-separated models: roll, pitch, yaw_rate, var (default all)")
    p.add_argument("--methods", default="whiteness,variance", help="comma-separated: whiteness, variance")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.add_argument("--no-figures", action="store_true", help="do not write figures")


@command("demo", "run the whole Dutta et al. study on the shipped hexacopter data: baselines (Table 2), "
                 "identification (Table 4), detection rates and figures", _demo_args)
def _demo(args: argparse.Namespace) -> int:
    from tsfdi.datasets import load_hexacopter
    from tsfdi.datasets.hexacopter import SIGNAL_CHANNELS
    from tsfdi.study import demo_report, hexacopter_study, paper_tests, write_report

    _check_out("--out", args.out)
    t0 = time.perf_counter()
    try:
        data = load_hexacopter(args.data)
    except (OSError, ValueError) as exc:
        if isinstance(exc, FileNotFoundError):
            raise ValueError(f"--data {args.data}: the file does not exist") from None
        raise ValueError(f"--data {args.data}: cannot be read as a hexacopter netCDF file ({exc})") from None
    models = _csv_list(args.models)
    tests = paper_tests(models or [*SIGNAL_CHANNELS, "var"], _csv_list(args.methods))
    bases, ev = hexacopter_study(data, records_per_case=args.records_per_case, models=models, tests=tests,
                                 windows=args.windows, fit_records=args.fit_records, pool=args.pool,
                                 order=args.order, progress=not args.no_progress)
    print(demo_report(bases, ev))
    written = write_report(bases, ev, data, args.out, figures=not args.no_figures)
    print(f"wrote {written[0]} and {len(written) - 2} figure(s) under {written[0].parent / 'figures'} in "
          f"{time.perf_counter() - t0:.1f} s")
    return 0


# ------------------------------------------------------------------------------------------- fit / select-order
def _order_args(p: argparse.ArgumentParser) -> None:
    _add_data_args(p, records_help="required when the file holds several records; several are pooled into one "
                                   "model")
    p.add_argument("--model", choices=("ar", "var"), default=None,
                   help="ar (one column) or var (several); default from the number of columns")
    p.add_argument("--max-lags", type=_count, default=20, help="largest order searched")
    p.add_argument("--trend", choices=("n", "c"), default="n",
                   help="n: no intercept (signals about zero, as the papers' models); c: an intercept, for signals "
                        "with a non-zero level such as commands holding a trim (then --method mean tests a change "
                        "of that level)")
    p.add_argument("--criterion", choices=("logdet", "trace"), default="logdet",
                   help="BIC of a VAR from the log-determinant or the trace of the residual covariance")


def _order_selection(args: argparse.Namespace) -> tuple[Any, _Records, str]:
    """``select_order`` on the records of ``args`` (pooled when several)."""
    from tsfdi.selection import select_order

    data = _read_records(args, required=True)
    data = _drop_short(data, args.max_lags + 2, f"--max-lags {args.max_lags}")
    k = len(data.columns)
    model = args.model or ("ar" if k == 1 else "var")
    if model == "ar" and k != 1:
        raise ValueError(f"--model ar needs one column, got {k} {data.columns}: pick one with --columns")
    if model == "var" and k < 2:
        raise ValueError(f"--model var needs at least two columns, got {data.columns}: add some with --columns")
    ys = [f.iloc[:, 0] if model == "ar" else f for f in data.frames]
    try:
        sel = select_order(ys if len(ys) > 1 else ys[0], args.max_lags, model, trend=args.trend,
                           criterion=args.criterion)
    except (ValueError, TypeError) as exc:
        raise _reword(exc, data, (("lags=", "--max-lags "),)) from None
    return sel, data, model


def _fit_args(p: argparse.ArgumentParser) -> None:
    _order_args(p)
    p.add_argument("--out", required=True, help="output .npz file for the fitted model")
    p.add_argument("--lags", type=_count, default=None, help="fixed order (default: the order of smallest BIC)")


@command("fit", "fit an AR / VAR baseline model (order by BIC) on records of a CSV, netCDF or flight-log file and "
                "save it (.npz)", _fit_args)
def _fit(args: argparse.Namespace) -> int:
    _check_out("--out", args.out)
    if args.lags is not None and args.lags > args.max_lags:
        raise ValueError(f"--lags {args.lags} exceeds --max-lags {args.max_lags}")
    sel, data, model = _order_selection(args)
    res = sel.fit(args.lags)
    try:
        written = res.save(args.out)
    except OSError as exc:
        raise ValueError(f"--out {args.out}: cannot write the file ({exc.strerror or exc})") from None
    print(f"{model.upper()}({res.lags}) on {data.columns} from {len(data.frames)} record(s) at {data.fs:g} Hz "
          f"({res.nobs} samples): BIC {res.bic:.6g}, RSS/SSS {res.rss_sss:.4g} %, SPP {res.spp:.2f}")
    print(str(res.summary()))
    print(f"saved to {written}")
    return 0


def _select_order_args(p: argparse.ArgumentParser) -> None:
    _order_args(p)
    p.add_argument("--out", default=None, help="write the table to this CSV file")


@command("select-order", "tabulate BIC, AIC, RSS/SSS and SPP of the orders 1 .. --max-lags on a common sample",
         _select_order_args)
def _select_order(args: argparse.Namespace) -> int:
    _check_out("--out", args.out)
    sel, data, model = _order_selection(args)
    print(f"{model.upper()} on {data.columns} from {len(data.frames)} record(s) at {data.fs:g} Hz")
    print(str(sel.summary()))
    _write("--out", sel.table.reset_index(), args.out)
    return 0


# --------------------------------------------------------------------------------------------------- detect
def _detect_args(p: argparse.ArgumentParser) -> None:
    _add_data_args(p, columns_help="comma-separated columns, matched to the baseline's channels by name (default: "
                                   "the baseline's channels when the file has them, else all numeric columns)")
    p.add_argument("--baseline", required=True, help="healthy model (.npz from 'tsfdi fit')")
    _window_args(p, "window length (default: each whole record)")
    _test_args(p)
    p.add_argument("--out", default=None, help="write the table to this CSV file")


@command("detect", "test a signal against a healthy baseline model: the decision per record, or per window",
         _detect_args)
def _detect(args: argparse.Namespace) -> int:
    from tsfdi.identification import detect
    from tsfdi.windows import ResidualWindows

    _check_out("--out", args.out)
    baseline = _load("--baseline", args.baseline, args.baseline)
    data = _read_records(args, default_columns=_channels(baseline))
    _check_channels(data, {f"--baseline {args.baseline}": baseline})
    rows = []
    if args.window is None:
        test = _tests(args, {}, None)
        data = _drop_short(data, *_min_samples(args, {"baseline": baseline}))
        for i, frame in enumerate(data.frames):
            try:
                d = detect(frame, baseline, test)
            except (ValueError, TypeError) as exc:
                raise _reword(exc, data) from None
            print(f"{data.label(i)} ({data.span(len(frame))} at {data.fs:g} Hz, {frame.index[0]:g} s to "
                  f"{frame.index[-1]:g} s):\n{str(d.summary())}\n")
            per_channel = [np.atleast_1d(np.asarray(a))[None, :] for a in (d.statistic, d.threshold, d.pvalue,
                                                                            d.reject)]
            rows.append(_detect_rows(data, frame, [0], len(frame), d.channels, *per_channel))
    else:
        W, S = _windows_in_samples(args, data, {"baseline": baseline})
        data = _drop_short(data, W, f"--window {args.window}")
        test = _tests(args, {"baseline": (f"--baseline {args.baseline}", baseline)}, W)
        for i, frame in enumerate(data.frames):
            try:
                ws = ResidualWindows({"baseline": baseline}).fit(frame).statistics(test, window=W, step=S,
                                                                                   loglik=False)
            except (ValueError, TypeError) as exc:
                raise _reword(exc, data) from None
            rows.append(_detect_rows(data, frame, ws.starts, W, ws.channels, ws.statistic[:, 0], ws.threshold[:, 0],
                                     ws.pvalue[:, 0], ws.channel_reject[:, 0]))
    table = _table(rows, data)
    if args.window is not None:
        _show(table)
    n = int(table["fault"].sum())
    print(f"fault in {n} of {len(table)} {'window' if args.window is not None else 'record'}(s)")
    _write("--out", table, args.out)
    return 0


def _detect_rows(data: _Records, frame: pd.DataFrame, starts: Any, W: int, channels: Any, stat: Any, thr: Any,
                 pv: Any, rej: Any) -> pd.DataFrame:
    """One row per window: times on the record's clock, per channel statistic / threshold / p-value, fault."""
    start = frame.index.to_numpy()[np.asarray(starts, dtype=int)]
    out = {"start": start, "end": np.round(start + W / data.fs, 9)}
    for j, c in enumerate(channels):
        out[f"statistic_{c}"] = np.asarray(stat)[:, j]
        out[f"threshold_{c}"] = np.asarray(thr)[:, j]
        out[f"pvalue_{c}"] = np.asarray(pv)[:, j]
    out["fault"] = np.asarray(rej, dtype=bool).any(axis=1)
    return pd.DataFrame(out)


# ------------------------------------------------------------------------------------------------- identify
def _identify_args(p: argparse.ArgumentParser) -> None:
    _add_data_args(p, columns_help="comma-separated columns, matched to the models' channels by name (default: the "
                                   "models' channels when the file has them, else all numeric columns)")
    p.add_argument("--models", required=True, nargs="+", metavar="NAME=PATH",
                   help="saved models (.npz from 'tsfdi fit'), as NAME=PATH or PATH (name = file stem); each "
                        "name once")
    _window_args(p, "window length (default: each whole record)")
    _test_args(p)
    p.add_argument("--rule", choices=("paper", "likelihood", "pvalue"), default="paper",
                   help="decision rule turning the models' acceptances into a label")
    p.add_argument("--out", default=None, help="write the table to this CSV file")


@command("identify", "identify which saved model fits a signal, per record or window by window", _identify_args)
def _identify(args: argparse.Namespace) -> int:
    from tsfdi.identification import identify_windows

    _check_out("--out", args.out)
    models = _load_models("--models", args.models)
    data = _read_records(args, default_columns=_channels(next(iter(models.values()))))
    _check_channels(data, {f"--models {n}": m for n, m in models.items()})
    if args.window is None:
        data = _drop_short(data, *_min_samples(args, models))
    else:
        W, S = _windows_in_samples(args, data, models)
        data = _drop_short(data, W, f"--window {args.window}")
    test = _tests(args, {n: (f"--models {n}", m) for n, m in models.items()}, None if args.window is None else W)
    rows = []
    for i, frame in enumerate(data.frames):
        n = len(frame)
        w, s = (n, n) if args.window is None else (W, S)
        try:
            wins = identify_windows(frame, models, test, window=w, step=s)
        except (ValueError, TypeError) as exc:
            raise _reword(exc, data) from None
        start = frame.index.to_numpy()[wins.starts]
        table = pd.DataFrame({"start": start, "end": np.round(start + w / data.fs, 9)})
        for j, name in enumerate(wins.models):
            table[f"pvalue_{name}"] = wins.windows.min_pvalue[:, j]
            table[f"accept_{name}"] = wins.accepted[:, j]
        # the status is that of the paper rule (how many models accept), whichever rule picks the label
        table["status"] = wins.status
        table["label"] = [lab or "" for lab in wins.decide(args.rule)]
        rows.append(table)
    table = _table(rows, data)
    _show(table)
    _write("--out", table, args.out)
    return 0


# -------------------------------------------------------------------------------------------------- monitor
def _monitor_args(p: argparse.ArgumentParser) -> None:
    _add_data_args(p, columns_help="comma-separated columns, matched to the baseline's channels by name (default: "
                                   "the baseline's channels when the file has them, else all numeric columns)")
    p.add_argument("--baseline", required=True, help="healthy model (.npz from 'tsfdi fit')")
    p.add_argument("--models", nargs="+", default=None, metavar="NAME=PATH",
                   help="fault models identifying the windows after a detection, as NAME=PATH or PATH (name = "
                        "file stem); default none: detection only")
    _window_args(p, "window length", required=True)
    p.add_argument("--steady-window", type=_span, default="10s",
                   help="rolling-variance window of the steady-state check: an integer counts samples, a time "
                        "span such as '10s' is converted with the sampling frequency")
    _test_args(p, lags=25)
    p.add_argument("--rule", choices=("paper", "likelihood", "pvalue"), default="paper",
                   help="decision rule turning the fault models' acceptances into a label")
    p.add_argument("--out", default=None, help="write the events to this CSV file")


@command("monitor", "slide windows over a signal: detection with a healthy baseline, then identification with "
                    "fault models; prints and writes the events", _monitor_args)
def _monitor(args: argparse.Namespace) -> int:
    from tsfdi._data import window_samples
    from tsfdi.monitoring import Monitor

    _check_out("--out", args.out)
    baseline = _load("--baseline", args.baseline, args.baseline)
    models = _load_models("--models", args.models) if args.models else {}
    data = _read_records(args, default_columns=_channels(baseline))
    given = {f"--baseline {args.baseline}": baseline, **{f"--models {n}": m for n, m in models.items()}}
    _check_channels(data, given)
    W, S = _windows_in_samples(args, data, {"baseline": baseline, **models})
    data = _drop_short(data, W, f"--window {args.window}")
    V = window_samples(args.steady_window, "--steady-window", data.fs, minimum=2)
    tests = _tests(args, {"": (f"--baseline {args.baseline}", baseline),
                          **{n: (f"--models {n}", m) for n, m in models.items()}}, W)
    if isinstance(tests, dict):         # calibrated: the baseline's own test detects, each model's identifies
        detection_test = tests.pop("")
        test = tests or None
    else:
        test, detection_test = tests, None
    try:
        monitor = Monitor(baseline, models or None, window=W, step=S, fs=data.fs, test=test,
                          detection_test=detection_test, steady_window=V, rule=args.rule)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"--baseline / --models: {exc}") from None
    rows = []
    for i, frame in enumerate(data.frames):
        try:
            result = monitor.run(frame)
        except (ValueError, TypeError) as exc:
            raise _reword(exc, data) from None
        events = result.to_frame()
        t0 = float(frame.index[0])
        for c in ("time", "window_start", "window_end"):       # times on the record's clock
            events[c] = t0 + events[c]
        print(f"{data.label(i)}: detection at "
              f"{'-' if result.detection_time is None else f'{t0 + result.detection_time:g} s'}, label "
              f"{result.label or '-'}")
        rows.append(events)
    table = _table(rows, data)
    _show(table)
    _write("--out", table, args.out)
    return 0


# ----------------------------------------------------------------------------------------------------- main
def _parser() -> tuple[argparse.ArgumentParser, dict]:
    parser = argparse.ArgumentParser(prog="tsfdi", description="Statistical time-series fault detection and "
                                                               "identification")
    parser.add_argument("--version", action="version", version=f"tsfdi {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="<command>")
    subs = {}
    for name, (help_, add, _) in COMMANDS.items():
        subs[name] = sub.add_parser(name, help=help_, description=help_, formatter_class=_HelpFormatter)
        add(subs[name])
    return parser, subs


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``tsfdi`` command.

    Returns 0 on success and 2 on any error (a bad flag value, an unreadable or unwritable file, data the
    library refuses), after printing a message that names the flag, file and column; ``--help`` and
    ``--version`` exit with status 0. Warnings are printed as one line each, ``tsfdi <command>: warning: ...``.
    """
    parser, subs = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:     # argparse has printed the usage and the flag's error
        if exc.code in (0, None):
            raise
        return 2
    if args.command is None:
        parser.print_help()
        return 2
    with warnings.catch_warnings():
        warnings.simplefilter("default")
        warnings.showwarning = lambda message, *a, **k: print(f"tsfdi {args.command}: warning: {message}",
                                                              file=sys.stderr)
        try:
            return COMMANDS[args.command][2](args)
        except BrokenPipeError:              # the reader of stdout has gone (``tsfdi ... | head``): stop quietly
            sys.stdout = open(os.devnull, "w")
            return 1
        except (ValueError, TypeError, OSError) as exc:
            subs[args.command].print_usage(sys.stderr)
            print(f"tsfdi {args.command}: error: {exc}", file=sys.stderr)
            return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())

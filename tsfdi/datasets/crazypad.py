"""Loader of the CrazyPAD dataset: real Crazyflie 2.1 flights with propeller defects.

CrazyPAD (Crazyflie Propeller Anomaly Data; Masalimov, Muslimov, Kozlov, Munasypov, Ufa University of Science
and Technology) holds flights of two Crazyflie 2.1 nano-quadcopters (``E8``, ``E9``) flying the same short
programme with and without structural defects: shortened propellers, adhesive tape (debris) on propellers,
small weights taped near motors, a weight hanging on a thread. It is **not** shipped with tsfdi. Download it
(MIT licence) from the GitHub repository https://github.com/AerialRoboticsUUST/CrazyPAD and cite

- K. Masalimov, T. Muslimov, E. Kozlov, R. Munasypov, "CrazyPAD: A Dataset for Assessing the Impact of
  Structural Defects on Nano-Quadcopter Performance", Data 9(6), 79, 2024, https://doi.org/10.3390/data9060079.

Every log is one CSV file (``.csv`` or ``.csv.gz``) of the drone's on-board logging, about 100 Hz, in one of two
logging configurations ("kinds"), which were recorded separately (their log numbers do not pair):

- ``controller``: ``timestamp`` (ms), ``stateEstimate.{x,y,z}``, ``controller.cmd_{roll,pitch,yaw,thrust}``,
  ``controller.r_{roll,pitch,yaw}`` (gyroscope body rates, rad/s), ``controller.accelz``, set points, ...;
- ``motor``: ``timestamp`` (ms), ``motor.m1..m4`` (motor commands), ``pwm.m1_pwm..m4_pwm``, ``pm.vbatMV``,
  ``stateEstimate.*``.

Two folder layouts are read: ``<root>/<kind>/<condition>/<drone>_<log>.csv[.gz]`` and the repository's own
``<root>/data/<kind>_data/<condition>/<drone>_<log>.csv`` (``<root>`` may also be the ``data`` folder). The
condition is the name of the folder holding the log, the drone the part of the file name before ``_``.

The logs include time on the ground. In the logs inspected every log holds **two** airborne segments (take-off,
programme, landing; about 5 s on the ground; take-off again, the log ending in the second descent), so
``airborne=True`` returns one record per airborne segment, each trimmed by ``margin`` at both ends. Samples are
returned as logged: never resampled, never filled; logging gaps are listed in ``attrs["gaps"]``.
"""

from __future__ import annotations

import datetime
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import read_csv
from tsfdi._validation import boolean, option

__all__ = ["list_crazypad", "load_crazypad", "read_crazypad_log", "CRAZYPAD_URL", "CRAZYPAD_DOI"]

CRAZYPAD_URL = "https://github.com/AerialRoboticsUUST/CrazyPAD"
CRAZYPAD_DOI = "10.3390/data9060079"

_KINDS = ("controller", "motor")
_THRUST = {"controller": ("controller.cmd_thrust",), "motor": ("motor.m1", "motor.m2", "motor.m3", "motor.m4")}
_NORMAL = "normal_flight"
_GAP_FACTOR = 2.5
_CITATION = ("Masalimov, Muslimov, Kozlov, Munasypov, CrazyPAD: A Dataset for Assessing the Impact of Structural "
             "Defects on Nano-Quadcopter Performance, Data 2024, 9, 79, doi:" + CRAZYPAD_DOI)
_HINT = f"download CrazyPAD from {CRAZYPAD_URL} (MIT licence) and pass its folder"
_MAX_SPAN_MS = 9.2e12   # a TimedeltaIndex holds int64 nanoseconds: about 292 years (in ms)


def _strip_ext(name: str) -> str:
    for ext in (".csv.gz", ".csv"):
        if name.endswith(ext):
            return name[: -len(ext)]
    return name


def _as_path(path: Any) -> Path:
    if path is None:
        raise ValueError(f"path: no CrazyPAD folder given (there is no default location); {_HINT}, e.g. "
                         "list_crazypad('path/to/CrazyPAD')")
    if not isinstance(path, (str, Path)):
        raise TypeError(f"path must be a str or pathlib.Path, got {type(path).__name__}")
    return Path(path)


def _margin(value: Any) -> tuple[pd.Timedelta, pd.Timedelta]:
    """(cut after take-off, cut before landing) from one time span or a pair."""
    if isinstance(value, (tuple, list)):
        if len(value) != 2:
            raise ValueError(f"margin must be one time span or a pair (after take-off, before landing), got "
                             f"{value!r}")
        return _span(value[0]), _span(value[1])
    span = _span(value)
    return span, span


def _span(value: Any) -> pd.Timedelta:
    spans = (str, pd.Timedelta, datetime.timedelta, np.timedelta64)
    if not isinstance(value, spans):
        raise TypeError(f"margin must be a time span such as '1s' or pandas.Timedelta, got {value!r} "
                        f"({type(value).__name__})")
    try:
        span = pd.Timedelta(value)
    except (TypeError, ValueError):
        raise ValueError(f"margin must be a time span such as '1s', got {value!r}") from None
    if span is pd.NaT or span < pd.Timedelta(0):
        raise ValueError(f"margin must be a time span >= 0, got {value!r}")
    return span


def _columns(columns: Any) -> list[str] | None:
    if columns is None:
        return None
    if isinstance(columns, str):
        return [columns]
    cols = list(columns) if isinstance(columns, Iterable) else None
    if cols is None or not all(isinstance(c, str) for c in cols):
        raise TypeError(f"columns must be None, a column name or a list of column names, got {columns!r}")
    return cols


def _kind_dirs(root: Path) -> dict[str, Path]:
    """The folder of each log kind under ``root`` (both layouts)."""
    found: dict[str, Path] = {}
    for kind in _KINDS:
        for cand in (root / kind, root / f"{kind}_data", root / "data" / kind, root / "data" / f"{kind}_data"):
            if cand.is_dir():
                found[kind] = cand
                break
    return found


def _log_files(root: Path) -> list[tuple[str, str, str, str, Path]]:
    """(kind, condition, drone, log, file) of every log under ``root``, sorted; duplicates (.csv and .csv.gz of
    one log) keep the first."""
    if not root.exists():
        raise FileNotFoundError(f"path: {root} does not exist; {_HINT}")
    if not root.is_dir():
        raise ValueError(f"path: {root} is a file, not the CrazyPAD folder; read one log with read_crazypad_log")
    dirs = _kind_dirs(root)
    if not dirs:
        raise ValueError(f"path: {root} holds no 'controller/' or 'motor/' folder (nor 'data/controller_data/', "
                         f"'data/motor_data/'): not a CrazyPAD folder; {_HINT}")
    out: list[tuple[str, str, str, str, Path]] = []
    seen: set[tuple[str, str, str]] = set()
    for kind, kdir in dirs.items():
        for cdir in sorted(p for p in kdir.iterdir() if p.is_dir()):
            for f in sorted(p for p in cdir.iterdir() if p.is_file() and p.name.endswith((".csv", ".csv.gz"))):
                log = _strip_ext(f.name)
                key = (kind, cdir.name, log)
                if key in seen:
                    continue
                seen.add(key)
                out.append((kind, cdir.name, log.split("_")[0] if "_" in log else log, log, f))
    return out


def _read_csv(file: Path, usecols: Any = None) -> pd.DataFrame:
    return read_csv(file, "file", usecols=usecols)


def _timestamps_ms(df: pd.DataFrame, file: Path) -> np.ndarray:
    if "timestamp" not in df.columns:
        raise ValueError(f"file: {file} has no column 'timestamp' (ms); columns: {list(df.columns)}")
    try:
        ts = df["timestamp"].to_numpy(dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"file: {file}: column 'timestamp' is not numeric") from None
    if not np.all(np.isfinite(ts)):
        raise ValueError(f"file: {file}: column 'timestamp' holds NaN or infinite values at rows "
                         f"{np.flatnonzero(~np.isfinite(ts))[:5].tolist()}")
    return ts


def list_crazypad(path: str | Path | None = None, *, kind: str | None = None) -> pd.DataFrame:
    """Table of the CrazyPAD logs found in a folder.

    Parameters
    ----------
    path : str or Path
        The CrazyPAD folder (``<path>/controller/<condition>/<drone>_<log>.csv[.gz]`` and ``<path>/motor/...``,
        or the repository's ``data/controller_data/...`` layout). There is no default: download the dataset
        from :data:`CRAZYPAD_URL` and pass its folder.
    kind : {"controller", "motor"}, optional
        List only the logs of one logging configuration; by default both.

    Returns
    -------
    pandas.DataFrame
        One row per log, sorted by ``kind``, ``condition``, ``log``: ``kind``, ``condition``, ``drone``, ``log``
        (e.g. ``"E8_log00"``), ``rows`` (samples), ``duration_s`` (last minus first time stamp, s) and ``file``
        (the path, a str). Controller and motor logs with the same number are different flights.
    """
    root = _as_path(path)
    if kind is not None:
        kind = option(kind, "kind", _KINDS)
    rows = []
    for k, cond, drone, log, f in _log_files(root):
        if kind is not None and k != kind:
            continue
        ts = _timestamps_ms(_read_csv(f, usecols=lambda c: c == "timestamp"), f)
        rows.append({"kind": k, "condition": cond, "drone": drone, "log": log, "rows": int(ts.size),
                     "duration_s": float(ts[-1] - ts[0]) / 1000.0 if ts.size else 0.0, "file": str(f)})
    cols = ["kind", "condition", "drone", "log", "rows", "duration_s", "file"]
    return pd.DataFrame(rows, columns=cols)


def _infer_kind(file: Path, names: Sequence[str]) -> str:
    for parent in (file.parent.parent.name, file.parent.name):
        for k in _KINDS:
            if parent in (k, f"{k}_data"):
                return k
    if _THRUST["controller"][0] in names:
        return "controller"
    if all(c in names for c in _THRUST["motor"]):
        return "motor"
    raise ValueError(f"file: {file} has neither the column '{_THRUST['controller'][0]}' (controller log) nor "
                     f"the columns {list(_THRUST['motor'])} (motor log); columns: {list(names)}")


def _segments(on: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) row of every maximal run of True."""
    edges = np.diff(np.concatenate(([0], on.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1).tolist(), (np.flatnonzero(edges == -1) - 1).tolist()))


def _gaps(index: pd.TimedeltaIndex) -> tuple[float, list[tuple[pd.Timedelta, pd.Timedelta]]]:
    """(fs, gaps) of the returned samples: 1 / median spacing and the spacings above 2.5 x the median."""
    if len(index) < 2:
        return float("nan"), []
    dt = np.diff(index.asi8)
    med = float(np.median(dt))
    big = np.flatnonzero(dt > _GAP_FACTOR * med)
    return 1e9 / med, [(index[i], pd.Timedelta(int(dt[i]), unit="ns")) for i in big]


def read_crazypad_log(file: str | Path, *, airborne: bool = True, margin: Any = "1s",
                      columns: Sequence[str] | str | None = None, kind: str | None = None) -> list[pd.DataFrame]:
    """Read one CrazyPAD log: its airborne segments (default) or the whole log.

    Parameters
    ----------
    file : str or Path
        One log, ``<kind>/<condition>/<drone>_<log>.csv[.gz]``.
    airborne : bool
        True: one DataFrame per airborne segment (a maximal run of samples with ``controller.cmd_thrust > 0``,
        for motor logs with any of ``motor.m1..m4 > 0``), from its first sample + ``margin`` to its last
        sample - ``margin`` (both ends included); segments left with fewer than 2 samples are dropped.
        False: the whole log, ground time included, as a one-element list.
    margin : str or pandas.Timedelta, or a pair of them
        Time cut at both ends of every airborne segment (take-off and landing transients), or a pair
        (after take-off, before landing). Ignored when ``airborne=False``. The climb to the hover height takes
        about 2 s after the thrust comes on: ``margin=("2.5s", "1s")`` leaves it out.
    columns : list of str, optional
        Columns to return, in this order; by default every column but ``timestamp`` (which becomes the index).
    kind : {"controller", "motor"}, optional
        The log's kind; by default from the folder name (``controller``/``motor``, ``*_data``), else from the
        columns.

    Returns
    -------
    list of pandas.DataFrame
        Each with a ``TimedeltaIndex`` named ``time`` (time since the log's first sample), the logged values as
        float64 and ``attrs``: ``condition``, ``drone``, ``log``, ``kind``, ``file``, ``segment`` (0, 1, ...
        among the log's airborne segments; None for the whole log), ``thrust_on`` ((first, last) time of the
        segment's positive thrust before the margin cut; None for the whole log), ``margin`` ((after take-off,
        before landing) Timedeltas; None for the whole log), ``fs`` (Hz, 1 / median spacing of the returned
        samples), ``gaps`` (list of (start, duration) Timedeltas of the spacings larger than 2.5 x the median,
        start = the sample before the gap), ``onset`` (None: a defect is present for the whole flight),
        ``faulty`` (condition is not ``normal_flight``), ``citation``.

    Raises
    ------
    FileNotFoundError
        ``file`` does not exist.
    ValueError
        The file is not a CSV log, lacks ``timestamp``, the thrust column(s) or a requested column, or its time
        stamps are not strictly increasing (the message names the file and the column).
    """
    if not isinstance(file, (str, Path)):
        raise TypeError(f"file must be a str or pathlib.Path, got {type(file).__name__}")
    f = Path(file)
    if not f.exists():
        raise FileNotFoundError(f"file: {f} does not exist; {_HINT}")
    if f.is_dir():
        raise ValueError(f"file: {f} is a folder; read a folder with load_crazypad")
    airborne = boolean(airborne, "airborne")
    span = _margin(margin)
    wanted = _columns(columns)
    if kind is not None:
        kind = option(kind, "kind", _KINDS)
    raw = _read_csv(f)
    ts = _timestamps_ms(raw, f)
    names = [c for c in raw.columns if c != "timestamp"]
    kind = kind or _infer_kind(f, names)
    for c in _THRUST[kind]:
        if c not in raw.columns:
            raise ValueError(f"file: {f} has no column '{c}' needed to find the airborne part of a {kind} log; "
                             f"columns: {list(raw.columns)}")
    if wanted is not None:
        missing = [c for c in wanted if c not in names]
        if missing:
            raise ValueError(f"columns: {missing} not in {f}; available: {names}")
        names = wanted
    if ts.size == 0:
        raise ValueError(f"file: {f} holds no samples")
    if ts[-1] - ts[0] > _MAX_SPAN_MS:
        raise ValueError(f"file: {f}: column 'timestamp' spans {ts[-1] - ts[0]:.3g} ms, more than a time index "
                         "can hold; not a CrazyPAD log (time stamps in ms)")
    bad = np.flatnonzero(np.diff(ts) <= 0)
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"file: {f}: column 'timestamp' is not strictly increasing ({bad.size} time(s); first at "
                         f"row {i + 1}: {ts[i]} ms then {ts[i + 1]} ms)")
    values = {}
    for c in dict.fromkeys([*names, *_THRUST[kind]]):
        try:
            values[c] = raw[c].to_numpy(dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"file: {f}: column '{c}' is not numeric") from None
    ns = np.rint((ts - ts[0]) * 1e6).astype(np.int64)
    index = pd.TimedeltaIndex(ns.astype("timedelta64[ns]"), name="time")
    table = pd.DataFrame({c: values[c] for c in names}, index=index)

    log = _strip_ext(f.name)
    condition = f.parent.name
    base = {"condition": condition, "drone": log.split("_")[0] if "_" in log else log, "log": log,
            "kind": kind, "file": str(f)}
    if not airborne:
        parts = [(table, None, None)]
    else:
        thrust = np.column_stack([values[c] for c in _THRUST[kind]])
        on = np.any(np.nan_to_num(thrust, nan=0.0) > 0, axis=1)
        parts = []
        for seg, (a, b) in enumerate(_segments(on)):
            lo, hi = index[a] + span[0], index[b] - span[1]
            keep = (index >= lo) & (index <= hi)
            if keep.sum() >= 2:
                parts.append((table.loc[keep].copy(), seg, (index[a], index[b])))
    out = []
    for df, seg, thrust_on in parts:
        fs, gaps = _gaps(df.index)
        df.attrs.update({**base, "segment": seg, "thrust_on": thrust_on,
                         "margin": span if airborne else None, "fs": fs, "gaps": gaps, "onset": None,
                         "faulty": condition != _NORMAL, "citation": _CITATION})
        out.append(df)
    return out


def _selection(value: Any, name: str, available: list[str], kind: str) -> list[str] | None:
    if value is None:
        return None
    chosen = [value] if isinstance(value, str) else (list(value) if isinstance(value, Iterable) else None)
    if chosen is None or not all(isinstance(v, str) for v in chosen):
        raise TypeError(f"{name} must be None, a str or a list of str, got {value!r}")
    unknown = [v for v in chosen if v not in available]
    if unknown:
        raise ValueError(f"{name}: {unknown} not among the {kind} logs; available: {available}")
    return chosen


def load_crazypad(path: str | Path | None = None, *, condition: str | Sequence[str] | None = None,
                  drone: str | Sequence[str] | None = None, kind: str = "controller", airborne: bool = True,
                  margin: Any = "1s", columns: Sequence[str] | str | None = None) -> list[pd.DataFrame]:
    """Read the CrazyPAD logs of a folder, optionally of some conditions and drones.

    Parameters
    ----------
    path : str or Path
        The CrazyPAD folder (see :func:`list_crazypad`); no default. One file: :func:`read_crazypad_log`.
    condition, drone : str or list of str, optional
        Keep these conditions (folder names, e.g. ``"normal_flight"``) / drones (``"E8"``, ``"E9"``).
    kind : {"controller", "motor"}
        Logging configuration.
    airborne, margin, columns
        As in :func:`read_crazypad_log`.

    Returns
    -------
    list of pandas.DataFrame
        The records of :func:`read_crazypad_log` of every selected log, sorted by condition and log: one per
        airborne segment with ``airborne=True`` (two per log in the shared copy), one per log otherwise.

    Raises
    ------
    ValueError
        An unknown condition or drone (the message lists the available ones), or no log of the selected
        condition and drone.
    """
    root = _as_path(path)
    kind = option(kind, "kind", _KINDS)
    airborne = boolean(airborne, "airborne")
    span = _margin(margin)
    wanted = _columns(columns)
    logs = [r for r in _log_files(root) if r[0] == kind]
    if not logs:
        raise ValueError(f"path: {root} holds no {kind} log")
    conds = _selection(condition, "condition", sorted({r[1] for r in logs}), kind)
    drones = _selection(drone, "drone", sorted({r[2] for r in logs}), kind)
    chosen = [r for r in logs if (conds is None or r[1] in conds) and (drones is None or r[2] in drones)]
    if not chosen:
        pairs = sorted({(r[1], r[2]) for r in logs if (conds is None or r[1] in conds)})
        raise ValueError(f"drone: no {kind} log of condition {conds} and drone {drones}; "
                         f"available (condition, drone): {pairs}")
    out: list[pd.DataFrame] = []
    for _, _, _, _, f in chosen:
        out += read_crazypad_log(f, airborne=airborne, margin=span, columns=wanted, kind=kind)
    return out

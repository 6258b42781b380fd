"""Loader of the ALFA fixed-wing UAV failure dataset (Keipour, Mousaei, Scherer; CMU AIR Lab).

The AIR Lab Failure and Anomaly (ALFA) dataset holds autonomous flights of a Carbon Z T-28 fixed-wing UAV
with mid-flight failures imposed in software: engine full power loss, left / right / both ailerons stuck,
elevator stuck, rudder stuck left / right, rudder and aileron stuck. It is **not** shipped with tsfdi.
Download it (CC BY 4.0) from the AIR Lab page http://theairlab.org/alfa-dataset, which links the public
Kilthub (Carnegie Mellon University figshare) record "ALFA: A Dataset for UAV Fault and Anomaly Detection",
https://doi.org/10.1184/R1/12707963. Unpack ``processed.zip``: every flight is a folder of CSV files, one per
ROS topic, named ``<flight>-<topic>.csv`` (``%time`` in nanoseconds). Credit the authors:

- A. Keipour, M. Mousaei, S. Scherer, "ALFA: A dataset for UAV fault and anomaly detection", The International
  Journal of Robotics Research 40(2-3), 2021, https://doi.org/10.1177/0278364920966642.
- A. Keipour, M. Mousaei, S. Scherer, "Automatic real-time anomaly detection for autonomous aerial
  vehicles", ICRA 2019, https://doi.org/10.1109/ICRA.2019.8794286.

:func:`load_alfa` reads one flight from either

- the official "processed" layout (a folder of per-topic CSV files, optionally gzip-compressed); the topics
  are aligned on the ``mavros-nav_info-roll`` timestamps (about 20 Hz) by taking, for every topic, the last
  message at or before each time stamp (no look-ahead);
- the merged 20 Hz copies (``merged_20hz/<fault>/<flight>.csv.gz``) or the engine commanded / measured
  copies (``engine_commanded_measured/<flight>.csv.gz``) kept for the tests in ``../shared/data/alfa``.

Ground truth never appears as an ordinary column: it is the boolean column ``ground_truth`` (True from the
onset on) and the attributes ``fault``, ``failure_code``, ``onset_time`` and ``onset_s``. The attribute
``leaking_columns`` lists columns that reveal the failure directly (the ground truth, the throttle that drops
to exactly 0 at an engine failure, the rc-out channels that freeze for a stuck surface); a detector must not
use them as inputs.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import read_csv
from tsfdi._validation import option

__all__ = ["load_alfa", "list_alfa", "ALFA_DOI", "ALFA_URL"]

ALFA_URL = "http://theairlab.org/alfa-dataset"
ALFA_DOI = "10.1184/R1/12707963"

_TOPIC_GRID = "mavros-nav_info-roll"
_SKIP_FIELDS = re.compile(r"^field\.header\.|covariance|^field\.coordinate_frame$")


def _fault_from_name(name: str) -> tuple[str, str]:
    """(fault, detail) from a flight name; fault uses the folder names of the shared copy."""
    low = name.lower()
    if "no_failure" in low:
        return "none", "none"
    if "rudder" in low:
        return "rudder", "rudder+aileron" if "aileron" in low else "rudder"
    if "aileron" in low:
        return "ailerons", "ailerons"
    if "elevator" in low:
        return "elevator", "elevator"
    if "engine" in low:
        return "engine", "engine"
    raise ValueError(f"path: cannot tell the failure type from the flight name {name!r}")


def _strip_ext(name: str) -> str:
    for ext in (".csv.gz", ".csv"):
        if name.endswith(ext):
            return name[: -len(ext)]
    return name


def _datetimes(values: pd.Series, path: Path, column: str) -> pd.DatetimeIndex:
    """The time stamps of ``column`` (date-time strings, or integers in ns), strictly increasing."""
    if pd.api.types.is_numeric_dtype(values.dtype):
        index = pd.DatetimeIndex(pd.to_datetime(_nanoseconds(values, path, column), unit="ns"))
    else:
        try:
            index = pd.DatetimeIndex(pd.to_datetime(values))
        except (TypeError, ValueError, OverflowError) as exc:
            raise ValueError(f"path: {path}: column {column!r} must hold time stamps ({exc})") from None
    _check_increasing(index.asi8, index.hasnans, path, column)
    return index


def _nanoseconds(values: pd.Series, path: Path, column: str) -> np.ndarray:
    """The integer time stamps (ns) of ``column``."""
    if pd.api.types.is_bool_dtype(values.dtype) or not pd.api.types.is_integer_dtype(values.dtype):
        raise ValueError(f"path: {path}: column {column!r} must hold integer time stamps in ns, got dtype "
                         f"{values.dtype}")
    return values.to_numpy(dtype=np.int64)


def _check_increasing(ns: np.ndarray, missing: bool, path: Path, column: str) -> None:
    if missing:
        raise ValueError(f"path: {path}: column {column!r} has missing or unreadable time stamps")
    back = np.flatnonzero(np.diff(ns) <= 0)
    if back.size:
        raise ValueError(f"path: {path}: column {column!r} is not strictly increasing (row {int(back[0]) + 1})")


def _read_table(path: Path, columns: tuple[str, ...], **kwargs: Any) -> pd.DataFrame:
    """One CSV file with at least one row and the given columns; errors name the file."""
    df = read_csv(path, "path", **kwargs)
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise ValueError(f"path: {path} has no column(s) {missing}; columns: {list(df.columns)}")
    if len(df) == 0:
        raise ValueError(f"path: {path} has a header but no rows")
    return df


def _number(value: Any, path: Path, column: str) -> float:
    """A finite number read from ``column``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = float("nan")
    if not np.isfinite(x):
        raise ValueError(f"path: {path}: column {column!r} must hold finite numbers, got {value!r}")
    return x


def _finish(df: pd.DataFrame, flight: str, onset: pd.Timestamp | None, code: int, layout: str, source: Path,
            leaking: list[str], kind: str) -> Any:
    fault, detail = _fault_from_name(flight)
    if len(df) < 2:
        raise ValueError(f"path: {source} holds {len(df)} time stamp(s); a flight needs at least 2")
    df.index.name = "time"
    gt = np.zeros(len(df), dtype=bool) if onset is None else np.asarray(df.index >= onset)
    df["ground_truth"] = gt
    t0 = df.index[0]
    dt = np.diff(df.index.values).astype("timedelta64[ns]").astype(np.int64) / 1e9
    attrs = {
        "flight": flight,
        "fault": fault,
        "fault_detail": detail,
        "failure_code": int(code),
        "onset_time": onset,
        "onset_s": None if onset is None else float((onset - t0).total_seconds()),
        "fs": float(1.0 / np.median(dt)),
        "layout": layout,
        "source": str(source),
        "leaking_columns": ["ground_truth", *leaking],
        "citation": "Keipour, Mousaei, Scherer, ALFA: A dataset for UAV fault and anomaly detection, "
                    "IJRR 2021, doi:10.1177/0278364920966642; data doi:" + ALFA_DOI,
    }
    df.attrs.update(attrs)
    if kind == "xarray":
        import xarray as xr

        ds = xr.Dataset.from_dataframe(df)
        ds.attrs.update({k: (v if not isinstance(v, (list, pd.Timestamp)) and v is not None else str(v))
                         for k, v in attrs.items()})
        return ds
    return df


def _read_merged(path: Path, kind: str) -> Any:
    df = _read_table(path, ())
    flight = _strip_ext(path.name)
    if "%time" in df.columns:  # merged_20hz
        df.index = _datetimes(df.pop("%time"), path, "%time")
        onset, code = None, 0
        if "field.data" in df.columns:
            try:
                data = df.pop("field.data").to_numpy(dtype=float)
            except (TypeError, ValueError):
                raise ValueError(f"path: {path}: column 'field.data' (failure code) must hold numbers") from None
            hit = np.flatnonzero(np.nan_to_num(data) != 0)
            if hit.size:
                onset, code = df.index[hit[0]], int(_number(data[hit[0]], path, "field.data"))
        return _finish(df, flight, onset, code, "merged_20hz", path, [], kind)
    if "time" in df.columns and "label" in df.columns:  # engine_commanded_measured
        df.index = _datetimes(df.pop("time"), path, "time")
        label = df.pop("label").astype(str).str.lower().eq("true").to_numpy()
        hit = np.flatnonzero(label)
        onset = df.index[hit[0]] if hit.size else None
        leaking = [c for c in ("throttle",) if c in df.columns]
        return _finish(df, flight, onset, 1 if hit.size else 0, "engine_commanded_measured", path, leaking, kind)
    raise ValueError(f"path: {path} is neither a merged 20 Hz ALFA file (%time, field.*) nor an engine "
                     "commanded/measured file (time, label, ...)")


def _read_official(folder: Path, flight: str | None, kind: str) -> Any:
    files = sorted(p for p in folder.iterdir() if p.name.endswith((".csv", ".csv.gz")))
    grid_files = [p for p in files if _strip_ext(p.name).endswith("-" + _TOPIC_GRID)]
    flights = sorted(_strip_ext(p.name)[: -len(_TOPIC_GRID) - 1] for p in grid_files)
    if not flights:
        raise ValueError(f"path: no '<flight>-{_TOPIC_GRID}.csv[.gz]' file in {folder}; not an official "
                         "ALFA processed folder")
    if flight is None:
        if len(flights) > 1:
            raise ValueError(f"flight: {folder} holds {len(flights)} flights, choose one of {flights}")
        flight = flights[0]
    elif flight not in flights:
        raise ValueError(f"flight: {flight!r} not found in {folder}; available: {flights}")
    prefix = flight + "-"
    topics = {_strip_ext(p.name)[len(prefix):]: p for p in files if p.name.startswith(prefix)}
    grid_file = topics[_TOPIC_GRID]
    grid = np.sort(_nanoseconds(_read_table(grid_file, ("%time",))["%time"], grid_file, "%time"))
    _check_increasing(grid, False, grid_file, "%time")
    out = pd.DataFrame(index=pd.to_datetime(grid, unit="ns"))
    onset_ns, code = None, 0
    leaking: list[str] = []
    for topic, p in sorted(topics.items()):
        if topic.startswith("failure_status"):
            fs = read_csv(p, "path")
            if len(fs):
                if "%time" not in fs.columns:
                    raise ValueError(f"path: {p} has no column '%time'; columns: {list(fs.columns)}")
                times = _nanoseconds(fs["%time"], p, "%time")
                first = int(times.min())
                if onset_ns is None or first < onset_ns:
                    onset_ns = first
                    code = int(_number(fs["field.data"].iloc[int(np.argmin(times))], p, "field.data")) \
                        if "field.data" in fs else 1
            continue
        tab = read_csv(p, "path")
        keep = [c for c in tab.columns if c.startswith("field.") and not _SKIP_FIELDS.search(c)
                and pd.api.types.is_numeric_dtype(tab[c]) and not pd.api.types.is_bool_dtype(tab[c])]
        if not keep or not len(tab):
            continue
        if "%time" not in tab.columns:
            raise ValueError(f"path: {p} has no column '%time'; columns: {list(tab.columns)}")
        times = _nanoseconds(tab["%time"], p, "%time")
        order = np.argsort(times, kind="stable")
        tab = tab[keep].iloc[order]
        short = topic[len("mavros-"):] if topic.startswith("mavros-") else topic
        names = {c: f"{short}.{c[len('field.'):]}" for c in keep}
        tab = tab.rename(columns=names)
        pos = np.searchsorted(times[order], grid, side="right") - 1
        vals = tab[list(names.values())].to_numpy(dtype=np.float64)
        block = np.full((grid.size, vals.shape[1]), np.nan)
        ok = pos >= 0
        block[ok] = vals[pos[ok]]
        for j, name in enumerate(names.values()):
            out[name] = block[:, j]
        if short == "rc-out":
            leaking += list(names.values())
        if short == "vfr_hud":
            leaking += [n for n in names.values() if n.endswith(".throttle")]
    onset = None if onset_ns is None else pd.Timestamp(onset_ns, unit="ns")
    return _finish(out, flight, onset, code, "official", folder, leaking, kind)


def load_alfa(path: str | Path, *, flight: str | None = None, kind: str = "pandas") -> Any:
    """Read one ALFA flight with its fault type and onset.

    Parameters
    ----------
    path : str or Path
        A folder in the official ALFA "processed" layout (one ``<flight>-<topic>.csv[.gz]`` per ROS topic),
        or one file of the shared processed copies (``merged_20hz/<fault>/<flight>.csv.gz`` or
        ``engine_commanded_measured/<flight>.csv.gz``).
    flight : str, optional
        Flight name, needed only when an official folder holds several flights.
    kind : {"pandas", "xarray"}
        Return a ``DataFrame`` (attributes in ``.attrs``) or an ``xarray.Dataset``.

    Returns
    -------
    pandas.DataFrame or xarray.Dataset
        Rows on the flight's time stamps (``DatetimeIndex`` named ``time``); the boolean column
        ``ground_truth``; attributes ``flight``, ``fault`` (engine | ailerons | rudder | elevator | none),
        ``fault_detail``, ``failure_code``, ``onset_time`` (Timestamp or None), ``onset_s`` (seconds from the
        first row), ``fs`` (Hz, from the median step), ``layout``, ``source``, ``leaking_columns``,
        ``citation``.

    Notes
    -----
    Official layout columns are ``<topic>.<field>`` with the ``mavros-`` prefix and ``field.`` removed, e.g.
    ``nav_info-roll.commanded``, ``nav_info-roll.measured``, ``imu-data.angular_velocity.x``; header and
    covariance fields are dropped; the failure onset is the first message of the ``failure_status-*`` topics.
    In the merged 20 Hz copies the ground-truth column ``field.data`` becomes ``ground_truth`` and
    ``failure_code``; in the engine copies ``label`` becomes ``ground_truth``.
    See :data:`ALFA_URL` / :data:`ALFA_DOI` for the download.
    """
    kind = option(kind, "kind", ("pandas", "xarray"))
    if not isinstance(path, (str, Path)):
        raise TypeError(f"path must be a str or pathlib.Path, got {type(path).__name__}")
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"path: {p} does not exist; download ALFA from {ALFA_URL} (doi:{ALFA_DOI})")
    if p.is_dir():
        return _read_official(p, flight, kind)
    return _read_merged(p, kind)


def list_alfa(root: str | Path) -> pd.DataFrame:
    """Table of the flights of a shared ALFA copy (``flights.csv`` plus the file of each flight).

    Parameters
    ----------
    root : str or Path
        Folder with ``flights.csv``, ``merged_20hz/`` and optionally ``engine_commanded_measured/``.

    Returns
    -------
    pandas.DataFrame
        One row per flight: ``flight``, ``fault``, ``failure_code``, ``onset_s``, ``merged_path`` and
        ``engine_path`` (the commanded / measured file or None).
    """
    if not isinstance(root, (str, Path)):
        raise TypeError(f"root must be a str or pathlib.Path, got {type(root).__name__}")
    root = Path(root)
    table = root / "flights.csv"
    if not table.is_file():
        raise FileNotFoundError(f"root: {table} not found; download ALFA from {ALFA_URL} (doi:{ALFA_DOI})")
    df = read_csv(table, "root")
    missing = [c for c in ("folder", "flight") if c not in df.columns]
    if missing:
        raise ValueError(f"root: {table} has no column(s) {missing}; not an ALFA flight table")
    df["merged_path"] = [str(root / "merged_20hz" / f / f"{n}.csv.gz") for f, n in zip(df["folder"], df["flight"])]
    eng = root / "engine_commanded_measured"
    df["engine_path"] = [str(eng / f"{n}.csv.gz") if (eng / f"{n}.csv.gz").is_file() else None
                         for n in df["flight"]]
    return df

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


def _finish(df: pd.DataFrame, flight: str, onset: pd.Timestamp | None, code: int, layout: str, source: Path,
            leaking: list[str], kind: str) -> Any:
    fault, detail = _fault_from_name(flight)
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
        "fs": float(1.0 / np.median(dt)) if dt.size else float("nan"),
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
    df = pd.read_csv(path)
    flight = _strip_ext(path.name)
    if "%time" in df.columns:  # merged_20hz
        df.index = pd.to_datetime(df.pop("%time"))
        onset, code = None, 0
        if "field.data" in df.columns:
            data = df.pop("field.data").to_numpy(dtype=float)
            hit = np.flatnonzero(np.nan_to_num(data) != 0)
            if hit.size:
                onset, code = df.index[hit[0]], int(data[hit[0]])
        return _finish(df, flight, onset, code, "merged_20hz", path, [], kind)
    if "time" in df.columns and "label" in df.columns:  # engine_commanded_measured
        df.index = pd.to_datetime(df.pop("time"))
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
    grid = pd.read_csv(topics[_TOPIC_GRID], usecols=["%time"])["%time"].to_numpy(dtype=np.int64)
    grid = np.sort(grid)
    out = pd.DataFrame(index=pd.to_datetime(grid, unit="ns"))
    onset_ns, code = None, 0
    leaking: list[str] = []
    for topic, p in sorted(topics.items()):
        if topic.startswith("failure_status"):
            fs = pd.read_csv(p)
            if len(fs):
                first = int(fs["%time"].min())
                if onset_ns is None or first < onset_ns:
                    onset_ns = first
                    code = int(fs.loc[fs["%time"].idxmin(), "field.data"]) if "field.data" in fs else 1
            continue
        tab = pd.read_csv(p)
        keep = [c for c in tab.columns if c.startswith("field.") and not _SKIP_FIELDS.search(c)
                and pd.api.types.is_numeric_dtype(tab[c])]
        if not keep:
            continue
        tab = tab[["%time", *keep]].sort_values("%time")
        short = topic[len("mavros-"):] if topic.startswith("mavros-") else topic
        names = {c: f"{short}.{c[len('field.'):]}" for c in keep}
        tab = tab.rename(columns=names)
        pos = np.searchsorted(tab["%time"].to_numpy(dtype=np.int64), grid, side="right") - 1
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
    root = Path(root)
    table = root / "flights.csv"
    if not table.is_file():
        raise FileNotFoundError(f"root: {table} not found; download ALFA from {ALFA_URL} (doi:{ALFA_DOI})")
    df = pd.read_csv(table)
    df["merged_path"] = [str(root / "merged_20hz" / f / f"{n}.csv.gz") for f, n in zip(df["folder"], df["flight"])]
    eng = root / "engine_commanded_measured"
    df["engine_path"] = [str(eng / f"{n}.csv.gz") if (eng / f"{n}.csv.gz").is_file() else None
                         for n in df["flight"]]
    return df

"""Reader of PX4 flight logs in the ULog format.

A ULog file (PX4 autopilot, https://docs.px4.io/main/en/dev_log/ulog_file_format.html) holds one stream of samples
per uORB topic, each logged at its own rate (1 to 250 Hz) with a ``timestamp`` field in microseconds since the
autopilot's boot. :func:`read_ulog` parses it with the ``pyulog`` package (``pip install pyulog``) and returns one
``DataFrame`` per topic, samples exactly as logged: nothing resampled, filled, sorted or dropped. Put the topics on
one uniform time grid with :func:`tsfdi.align`.
"""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["read_ulog"]


def _requested(topics: Any) -> list[str] | None:
    if topics is None:
        return None
    names = [topics] if isinstance(topics, str) else topics
    if not isinstance(names, Sequence) or isinstance(names, bytes) or not all(isinstance(t, str) for t in names):
        raise TypeError(f"topics must be None, a topic name or a list of topic names, got {topics!r}")
    if not names:
        raise ValueError("topics is empty: give None (every topic) or at least one topic name")
    return list(dict.fromkeys(names))


def _parse(path: Path, names: list[str] | None) -> Any:
    """``pyulog.ULog`` of ``path`` (topics ``names`` only), its failures as ``ValueError`` naming the file."""
    try:
        from pyulog import ULog
    except ImportError:
        raise ImportError("read_ulog needs the pyulog package: pip install pyulog (or tsfdi[px4])") from None
    printed = io.StringIO()     # pyulog prints its warnings about corrupt data; they go into the error message
    try:
        with contextlib.redirect_stdout(printed):
            ulog = ULog(str(path), names)
    except Exception as exc:    # noqa: BLE001 - pyulog raises ULogException, struct / Unicode / OS errors
        raise ValueError(f"path: {path} is not a readable ULog file ({type(exc).__name__}: {exc})") from None
    if ulog.file_corruption:
        said = printed.getvalue().strip().splitlines()
        raise ValueError(f"path: {path} is a damaged ULog file: pyulog found corrupt data"
                         + (f" ({said[0]})" if said else "") + "; its samples cannot be trusted")
    return ulog


def _key(name: str, instance: int) -> str:
    return name if instance == 0 else f"{name}/{instance}"


def read_ulog(path: str | os.PathLike, topics: str | Sequence[str] | None = None) -> dict[str, pd.DataFrame]:
    """Read the topics of a PX4 ULog flight log.

    Parameters
    ----------
    path : str or path-like
        The ``.ulg`` file.
    topics : str or list of str, optional
        Topics to read (default: every topic with data). A plain name (``"sensor_accel"``) selects every instance
        of a multi-instance topic; ``"sensor_accel/1"`` selects instance 1 only.

    Returns
    -------
    dict of str to pandas.DataFrame
        One frame per topic instance, keyed by the topic name for instance 0 and ``"name/1"``, ``"name/2"``, ...
        for further instances (PX4 publishes one instance per redundant sensor), in alphabetical order. Each frame
        has

        - index: a ``TimedeltaIndex`` named ``"time"``, the sample's ``timestamp`` minus the log's start time
          stamp (the file header's, in microseconds since boot), so 0 is the start of logging;
        - columns: the topic's fields as ``pyulog`` names them (``"gyro_rad[0]"``, ``"q[3]"``), with their logged
          dtypes (boolean fields are integers); the raw ``"timestamp"`` field is the index and is not a column;
        - ``attrs``: ``"file"``, ``"topic"``, ``"instance"``, ``"start_timestamp"`` (µs since boot),
          ``"dropouts"`` (list of ``(time, duration)`` Timedelta pairs: the logger's own record of lost data, for
          the whole file), ``"duplicate_stamps"`` and ``"backward_stamps"`` (how many samples repeat the previous
          time stamp or go back in time).

    Notes
    -----
    Samples are kept exactly as logged, in the order of the file. A sample stamped before the start of logging
    (queued before the logger started, or from a publisher that never sets its stamp, which then reads 0) has a
    negative time. Repeated and backward stamps are kept and counted in ``attrs``; :func:`tsfdi.align` holds the
    last sample logged at a repeated stamp and refuses a backward one, naming the topic and the time.

    A file that is truncated at its end (power lost while logging) is read up to the last complete message, as
    ``pyulog`` does. A file in which ``pyulog`` detects corrupt data is refused.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        ``path`` is not a readable ULog file, is damaged or holds no logged data; a requested topic is not in the
        file (the message lists the topics it holds).
    TypeError
        ``path`` or ``topics`` of the wrong type.
    ImportError
        ``pyulog`` is not installed.

    Examples
    --------
    >>> logs = tsfdi.datasets.read_ulog("flight.ulg", ["vehicle_attitude", "sensor_combined"])  # doctest: +SKIP
    >>> records = tsfdi.align(logs, fs=50)                                                        # doctest: +SKIP
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or path-like, got {type(path).__name__}")
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"path: {path} does not exist")
    if not path.is_file():
        raise ValueError(f"path: {path} is not a file")
    wanted = _requested(topics)
    ulog = _parse(path, None if wanted is None else sorted({w.split("/")[0] for w in wanted}))
    datasets = {_key(d.name, d.multi_id): d for d in ulog.data_list}
    if wanted is None:
        if not datasets:
            raise ValueError(f"path: {path} holds no logged data (an empty or truncated log)")
        keys = list(datasets)
    else:
        keys = []
        for w in wanted:
            found = [k for k in datasets if k == w or k.split("/")[0] == w or (w.endswith("/0") and k == w[:-2])]
            if not found:
                have = sorted(_key(d.name, d.multi_id) for d in _parse(path, None).data_list)
                raise ValueError(f"topics: {w!r} is not in {path}; it holds {have}")
            keys += [k for k in found if k not in keys]
    start = int(ulog.start_timestamp)
    dropouts = [(pd.Timedelta(int(d.timestamp) - start, unit="us"), pd.Timedelta(int(d.duration), unit="ms"))
                for d in ulog.dropouts]
    out = {}
    for key in keys:
        d = datasets[key]
        stamps = np.asarray(d.data["timestamp"])
        if stamps.max() >= 2**62:
            raise ValueError(f"path: {path} is damaged: topic {key!r} has a time stamp of {int(stamps.max())} µs")
        micros = stamps.astype(np.int64) - start
        steps = np.diff(micros)
        index = pd.TimedeltaIndex(micros.astype("timedelta64[us]"), name="time")
        frame = pd.DataFrame({f: np.asarray(v) for f, v in d.data.items() if f != "timestamp"}, index=index)
        frame.attrs = {"file": str(path), "topic": d.name, "instance": int(d.multi_id), "start_timestamp": start,
                       "dropouts": list(dropouts), "duplicate_stamps": int((steps == 0).sum()),
                       "backward_stamps": int((steps < 0).sum())}
        out[key] = frame
    return out

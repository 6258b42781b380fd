"""Saving and loading fitted models (``Results.save(path)`` / :func:`tsfdi.load`).

A results object is fully defined by its model spec (data and options) and its parameter matrix, so a
``.npz`` archive holding the data, the index, the options and the parameters restores it exactly: the
loaded object's parameters are the stored bytes and every derived quantity is recomputed from them by the
same code. No pickle is used; the archive can be read with ``numpy.load`` alone.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import Signal

__all__ = ["save", "load"]

FORMAT = "tsfdi-results"
VERSION = 1


def _signal_arrays(sig: Signal, prefix: str) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    arrays = {f"{prefix}values": sig.values}
    meta: dict[str, Any] = {"kind": sig.kind, "vector": sig.vector, "channels": list(sig.channels),
                            "name": sig.name if sig.name is None or isinstance(sig.name, (str, int, float)) else str(sig.name),
                            "time_dim": sig.time_dim, "channel_dim": sig.channel_dim, "index": None}
    idx = sig.index
    if idx is not None:
        if isinstance(idx, pd.RangeIndex):
            meta["index"] = {"type": "range", "start": idx.start, "stop": idx.stop, "step": idx.step, "name": idx.name}
        else:
            info: dict[str, Any] = {"type": "values", "name": idx.name if idx.name is None else str(idx.name)}
            values = idx
            if isinstance(idx, pd.DatetimeIndex):
                info["tz"] = None if idx.tz is None else str(idx.tz)
                info["freq"] = idx.freqstr
                values = idx.tz_convert("UTC").tz_localize(None) if idx.tz is not None else idx
                info["unit"] = str(values.dtype)
            arr = np.asarray(values)
            if arr.dtype == object:
                arr = arr.astype(str)
                info["dtype"] = "str"
            arrays[f"{prefix}index"] = arr
            meta["index"] = info
    return arrays, meta


def _signal_from(arrays: Any, meta: dict[str, Any], prefix: str) -> Signal:
    info = meta["index"]
    index = None
    if info is not None:
        if info["type"] == "range":
            index = pd.RangeIndex(info["start"], info["stop"], info["step"], name=info["name"])
        else:
            arr = arrays[f"{prefix}index"]
            if "tz" in info:
                index = pd.DatetimeIndex(arr.astype(info["unit"]), name=info["name"])
                if info["tz"] is not None:
                    index = index.tz_localize("UTC").tz_convert(info["tz"])
                if info["freq"] is not None:
                    index = pd.DatetimeIndex(index, freq=info["freq"])
            else:
                index = pd.Index(arr.astype(object) if info.get("dtype") == "str" else arr, name=info["name"])
    return Signal(values=np.ascontiguousarray(arrays[f"{prefix}values"]), kind=meta["kind"], vector=meta["vector"],
                  index=index, channels=meta["channels"], name=meta["name"], time_dim=meta["time_dim"],
                  channel_dim=meta["channel_dim"])


def save(results: Any, path: Any) -> None:
    """Write ``results`` (AR, VAR or ARX) to ``path`` as a ``.npz`` archive (the suffix is added if missing)."""
    model = results.model
    arrays: dict[str, np.ndarray] = {}
    ymeta, umeta = [], None
    for i, rec in enumerate(model.records):
        a, m = _signal_arrays(rec, f"y{i}_")
        arrays.update(a)
        ymeta.append(m)
    if model.u_records is not None:
        umeta = []
        for i, rec in enumerate(model.u_records):
            a, m = _signal_arrays(rec, f"u{i}_")
            arrays.update(a)
            umeta.append(m)
    meta: dict[str, Any] = {"format": FORMAT, "version": VERSION, "family": type(model).__name__,
                            "options": {"na": model.na, "nb": model.nb, "nk": model.nk, "trend": model.trend,
                                        "hold_back": model.hold_back, "criterion": model.criterion},
                            "multi": model.multi, "y": ymeta, "u": umeta}
    arrays["params"] = results._params2d
    arrays["meta"] = np.array(json.dumps(meta))
    with open(Path(path), "wb") as fh:
        np.savez_compressed(fh, **arrays)


def load(path: Any) -> Any:
    """Load a results object written by ``Results.save``; the round trip is exact."""
    from tsfdi import models

    with np.load(Path(path), allow_pickle=False) as f:
        arrays = {k: f[k] for k in f.files}
    if "meta" not in arrays:
        raise ValueError(f"path {str(path)!r} is not a tsfdi results archive (no metadata)")
    meta = json.loads(str(arrays["meta"]))
    if meta.get("format") != FORMAT:
        raise ValueError(f"path {str(path)!r} is not a tsfdi results archive")
    if meta["version"] > VERSION:
        raise ValueError(f"path {str(path)!r} was written by a newer tsfdi (format version {meta['version']})")
    ys = [_signal_from(arrays, m, f"y{i}_") for i, m in enumerate(meta["y"])]
    us = None if meta["u"] is None else [_signal_from(arrays, m, f"u{i}_") for i, m in enumerate(meta["u"])]
    y = ys if meta["multi"] else ys[0]
    u = us if (us is None or meta["multi"]) else us[0]
    o = meta["options"]
    family = meta["family"]
    if family == "AR":
        model = models.AR(y, o["na"], o["trend"], hold_back=o["hold_back"])
    elif family == "VAR":
        model = models.VAR(y, o["na"], o["trend"], hold_back=o["hold_back"], criterion=o["criterion"])
    elif family == "ARX":
        model = models.ARX(y, u, o["na"], o["nb"], o["nk"], o["trend"], hold_back=o["hold_back"])
    else:
        raise ValueError(f"path {str(path)!r} holds an unknown model family {family!r}")
    return model._results_class(model, arrays["params"])

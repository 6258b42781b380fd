"""The archive format of fitted models: ``Results.save(path)`` and :func:`load`.

A results object is fully defined by its model spec (data and options) and its parameter matrix, so a
``.npz`` archive holding the data, the index, the options and the parameters restores it exactly: the
loaded object's parameters are the stored bytes and every derived quantity is recomputed from them by the
same code. No pickle is used; the archive can be read with ``numpy.load`` alone.

This module imports no model family: the families that can be archived (AR, VAR, ARX) register their
class here with :func:`register` when their module is imported, so the results' ``save`` method (in the
common base module) and :func:`load` share one format module without an import circle.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import Signal

__all__ = ["FORMAT", "VERSION", "register", "save", "load"]

#: value of the ``format`` field of the metadata
FORMAT = "tsfdi-results"
#: current format version; archives of a newer version are refused
VERSION = 1

# model classes by family name (the class name stored in the archive), filled by :func:`register`
_families: dict[str, type] = {}

# how each family's model spec is rebuilt from the stored data and options
_BUILDERS = {
    "AR": lambda cls, y, u, o: cls(y, o["na"], o["trend"], hold_back=o["hold_back"]),
    "VAR": lambda cls, y, u, o: cls(y, o["na"], o["trend"], hold_back=o["hold_back"], criterion=o["criterion"]),
    "ARX": lambda cls, y, u, o: cls(y, u, o["na"], o["nb"], o["nk"], o["trend"], hold_back=o["hold_back"]),
}


def register(model_class: type) -> type:
    """Class decorator: make the model family ``model_class`` loadable by :func:`load`.

    The family is stored in an archive by class name; only the families known to this module (AR, VAR,
    ARX) can be registered.
    """
    name = model_class.__name__
    if name not in _BUILDERS:
        raise ValueError(f"the archive format has no layout for a model family named {name!r}")
    _families[name] = model_class
    return model_class


def _signal_arrays(sig: Signal, prefix: str) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    arrays = {f"{prefix}values": sig.values}
    name = sig.name if sig.name is None or isinstance(sig.name, (str, int, float)) else str(sig.name)
    meta: dict[str, Any] = {"kind": sig.kind, "vector": sig.vector, "channels": list(sig.channels), "name": name,
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
    """Write ``results`` (AR, VAR or ARX) to ``path`` as a compressed ``.npz`` archive.

    The file is written to exactly ``path``: no ``.npz`` suffix is added.
    """
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
    arrays["params"] = results.params2d
    arrays["meta"] = np.array(json.dumps(meta))
    with open(Path(path), "wb") as fh:
        np.savez_compressed(fh, **arrays)


def load(path: Any) -> Any:
    """Load a results object written by ``Results.save``; the round trip is exact.

    Parameters
    ----------
    path : str or path-like
        A ``.npz`` archive written by ``save``.

    Returns
    -------
    ARResults, VARResults or ARXResults
        The results of the stored model with the stored parameters (not re-estimated).
    """
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
    family = meta["family"]
    if family not in _families:
        raise ValueError(f"path {str(path)!r} holds an unknown model family {family!r}")
    cls = _families[family]
    model = _BUILDERS[family](cls, y, u, meta["options"])
    return model.results_class(model, arrays["params"])

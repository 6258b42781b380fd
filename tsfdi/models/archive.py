"""The archive format of fitted models: ``Results.save(path)`` and :func:`load`.

A results object is fully defined by its model spec (data and options) and its parameter matrix, so an
archive holding the data, the index, the options and the parameters restores it exactly: the loaded object's
parameters are the stored bytes and every derived quantity is recomputed from them by the same code. No pickle
is used; the archive is a ``.npz`` file that ``numpy.load(path, allow_pickle=False)`` reads alone.

Layout (format version 2): a zip archive of ``.npy`` members, the *fields*

``meta``
    0-d string array holding JSON: ``format`` (``"tsfdi-results"``), ``version``, ``family`` (``"AR"``,
    ``"VAR"``, ``"ARX"``, ``"VARX"``), ``options`` (``na``, ``nb``, ``nk``, ``trend``, ``hold_back``, ``criterion``),
    ``multi`` (a list of records) and, for every output record in ``y`` and input record in ``u``, its kind,
    channels, name and the description of its time index.
``params``
    the parameter matrix, float64 ``(df_eq, neqs)``.
``y0_values``, ``y1_values``, ..., ``u0_values``, ...
    the data of every record, float64 ``(nobs, nchan)``.
``y0_index``, ``y0_index_categories``, ``y0_index_level0``, ``y0_index_codes0``, ...
    the arrays of a record's time index (a ``RangeIndex`` needs none). Numeric values are stored as arrays,
    datetimes, timedeltas and periods as their int64 values, object and string elements as JSON; the
    description in ``meta`` gives the kind, dtype, unit, time zone, frequency and names.
``checksums``
    0-d string array holding JSON ``{"sha256": {field: digest}}``: the SHA-256 digest of the ``.npy`` bytes of
    every other field.

Every pandas index kind round-trips exactly (class, dtype, values, names and ``freq``): ``RangeIndex``,
``Index`` of numbers, booleans, strings or mixed objects, ``DatetimeIndex`` (time zone and ``freq``),
``TimedeltaIndex``, ``PeriodIndex``, ``CategoricalIndex``, ``IntervalIndex`` and ``MultiIndex``. Names and
object elements may be ``None``, ``str``, ``int``, ``float``, ``bool``, ``pandas.NA`` or tuples of these. What
cannot be stored exactly (another element or name type, a time zone without a name pandas reads back) is refused
by :func:`save` with a ``ValueError``; the save-time check decodes the description and compares it with the index.

:func:`load` validates every field and names the file and the field in its ``ValueError``: a file that is not
a zip archive, a member that cannot be read, a checksum that does not match, a malformed ``.npy`` header or
``meta`` entry, NaN / inf data or parameters, data too short for the stored order, parameters of the wrong
shape. Archives of format version 1 (written by tsfdi before the checksums) are read with the same checks,
without the checksums; archives of a newer version are refused, not misread.

This module imports no model family: the families that can be archived (AR, VAR, ARX, VARX) register their
class here with :func:`register` when their module is imported (the functionally pooled FPAR, FPVAR, FPARX add the
fields ``k`` (the operating point of every record), ``k_range``, and ``weights`` for a weighted fit, and the
options ``degree``, ``basis``, ``weights``, ``k_names``; the functionally pooled mean of windows FPMean stores the
fields ``k`` and ``k_range`` and the options ``window``, ``grid``, ``degree``, ``basis``, ``k_names`` instead of an
order), so the results' ``save`` method (in the
common base module) and :func:`load` share one format module without an import circle.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import uuid
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import Signal

__all__ = ["FORMAT", "VERSION", "register", "save", "load"]

#: value of the ``format`` field of the metadata
FORMAT = "tsfdi-results"
#: current format version; archives of a newer version are refused, version 1 (no checksums) is still read
VERSION = 2

# model classes by family name (the class name stored in the archive), filled by :func:`register`
_families: dict[str, type] = {}

# how each family's model spec is rebuilt from the stored data and options
_BUILDERS = {
    "AR": lambda cls, y, u, o: cls(y, o["na"], o["trend"], hold_back=o["hold_back"]),
    "VAR": lambda cls, y, u, o: cls(y, o["na"], o["trend"], hold_back=o["hold_back"], criterion=o["criterion"]),
    "ARX": lambda cls, y, u, o: cls(y, u, o["na"], o["nb"], o["nk"], o["trend"], hold_back=o["hold_back"]),
    "VARX": lambda cls, y, u, o: cls(y, u, o["na"], o["nb"], o["nk"], o["trend"], hold_back=o["hold_back"],
                                     criterion=o["criterion"]),
    # functionally pooled families (tsfdi.models.fp): the operating points and the basis ride along
    "FPAR": lambda cls, y, u, o: cls(y, o["k"], o["na"], o["degree"], o["trend"], basis=o["basis"],
                                     weights=o["weights"], hold_back=o["hold_back"], k_range=o["k_range"]),
    "FPVAR": lambda cls, y, u, o: cls(y, o["k"], o["na"], o["degree"], o["trend"], basis=o["basis"],
                                      weights=o["weights"], hold_back=o["hold_back"], k_range=o["k_range"]),
    "FPARX": lambda cls, y, u, o: cls(y, u, o["k"], o["na"], o["nb"], o["nk"], o["degree"], o["trend"],
                                      basis=o["basis"], weights=o["weights"], hold_back=o["hold_back"],
                                      k_range=o["k_range"]),
    # the functionally pooled mean of windows (tsfdi.models.fp.FPMean): no order, a window and a search grid
    "FPMean": lambda cls, y, u, o: cls(y, o["k"], o["window"], o["degree"], basis=o["basis"], k_range=o["k_range"],
                                       grid=o["grid"]),
}
#: the families whose archives hold operating points (fields ``k``, ``k_range``, optionally ``weights``)
_FP_FAMILIES = ("FPAR", "FPVAR", "FPARX", "FPMean")

# what reading a damaged zip archive or member raises (zipfile, zlib, truncated reads, a bad compression type
# or encryption flag, a member name that is not valid UTF-8)
_ZIP_ERRORS = (zipfile.BadZipFile, zlib.error, EOFError, OSError, ValueError, NotImplementedError, RuntimeError,
               OverflowError)
# what pandas raises when a stored index description is inconsistent (unknown time zone: a KeyError subclass;
# a string storage whose library is missing: ImportError)
_REBUILD_ERRORS = (ValueError, TypeError, KeyError, OverflowError, NotImplementedError, ImportError, IndexError)
# index descriptions nest (categories of a level of a MultiIndex, bounds of an IntervalIndex): at most this deep
_MAX_DEPTH = 4
# array dtype kinds that may appear in an archive (no object, structured or void arrays)
_KINDS = {"f": "floats", "i": "integers", "M": "datetimes", "biufc": "numbers", "U": "a string",
          "biufcUMm": "numbers, strings or datetimes"}


def register(model_class: type) -> type:
    """Class decorator: make the model family ``model_class`` loadable by :func:`load`.

    The family is stored in an archive by class name; only the families known to this module (AR, VAR,
    ARX, VARX) can be registered.
    """
    name = model_class.__name__
    if name not in _BUILDERS:
        raise ValueError(f"the archive format has no layout for a model family named {name!r}")
    _families[name] = model_class
    return model_class


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


# ------------------------------------------------------------------------------------- names and elements
def _encode_value(value: Any) -> Any:
    """JSON form of an index name or an object-index element that decodes to an equal value of the same type:
    None, bool, str, int, float, ``pandas.NA`` (``{"NA": null}``) or a tuple of these (``{"tuple": [...]}``);
    ``TypeError`` for anything else."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, tuple):
        return {"tuple": [_encode_value(v) for v in value]}
    if value is pd.NA:
        return {"NA": None}
    raise TypeError(f"{_short(value)} of type {type(value).__name__} (only None, str, int, float, bool, "
                    "pandas.NA and tuples of them are stored)")


def _decode_value(value: Any) -> Any:
    """Inverse of :func:`_encode_value`; ``ValueError`` for a JSON value it never writes."""
    if isinstance(value, dict):
        if value == {"NA": None}:
            return pd.NA
        if list(value) != ["tuple"] or not isinstance(value["tuple"], list):
            raise ValueError(f"{_short(value)} is not an encoded name or element")
        return tuple(_decode_value(v) for v in value["tuple"])
    if isinstance(value, list):
        raise ValueError(f"{_short(value)} is not an encoded name or element")
    return value


def _encode_names(names: Any) -> list:
    return [_encode_value(n) for n in names]


# --------------------------------------------------------------------------------------- index encoding
def _index_fields(idx: pd.Index, field: str) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The arrays (by field name) and the JSON description of ``idx``; ``TypeError`` naming what cannot be
    stored. The description names the fields it uses, so nested indexes (categories, interval bounds,
    MultiIndex levels) get fields of their own: ``<field>_categories``, ``<field>_left``, ``<field>_level0``."""
    if isinstance(idx, pd.MultiIndex):
        arrays: dict[str, np.ndarray] = {}
        levels, codes = [], []
        for i, (level, code) in enumerate(zip(idx.levels, idx.codes)):
            level_arrays, info = _index_fields(level, f"{field}_level{i}")
            arrays.update(level_arrays)
            levels.append(info)
            arrays[f"{field}_codes{i}"] = np.asarray(code)
            codes.append(f"{field}_codes{i}")
        return arrays, {"kind": "multi", "levels": levels, "codes": codes, "names": _encode_names(idx.names)}
    info: dict[str, Any] = {"name": _encode_value(idx.name)}
    if isinstance(idx, pd.RangeIndex):
        return {}, {**info, "kind": "range", "start": idx.start, "stop": idx.stop, "step": idx.step}
    if isinstance(idx, pd.CategoricalIndex):
        arrays, categories = _index_fields(idx.categories, f"{field}_categories")
        arrays[field] = np.asarray(idx.codes)
        return arrays, {**info, "kind": "categorical", "field": field, "categories": categories,
                        "ordered": bool(idx.ordered)}
    if isinstance(idx, pd.IntervalIndex):
        left, left_info = _index_fields(idx.left, f"{field}_left")
        right, right_info = _index_fields(idx.right, f"{field}_right")
        return {**left, **right}, {**info, "kind": "interval", "left": left_info, "right": right_info,
                                   "closed": idx.closed}
    if isinstance(idx, pd.DatetimeIndex):
        return {field: idx.asi8}, {**info, "kind": "datetime", "field": field, "unit": idx.unit,
                                   "tz": None if idx.tz is None else str(idx.tz), "freq": idx.freqstr}
    if isinstance(idx, pd.TimedeltaIndex):
        return {field: idx.asi8}, {**info, "kind": "timedelta", "field": field, "unit": idx.unit,
                                   "freq": idx.freqstr}
    if isinstance(idx, pd.PeriodIndex):
        return {field: idx.asi8}, {**info, "kind": "period", "field": field, "freq": idx.freqstr}
    if type(idx) is not pd.Index:
        raise TypeError(f"an index of class {type(idx).__name__} is not stored")
    dtype = idx.dtype
    if isinstance(dtype, np.dtype) and dtype.kind in "biufc":
        return {field: idx.to_numpy()}, {**info, "kind": "numeric", "field": field}
    if dtype == object:
        spec: Any = "object"
    elif isinstance(dtype, pd.StringDtype):
        spec = {"string": dtype.storage, "na": "NA" if dtype.na_value is pd.NA else "nan"}
    elif isinstance(dtype, pd.api.extensions.ExtensionDtype):
        spec = str(dtype)
    else:
        raise TypeError(f"an index of dtype {dtype} is not stored")
    elements = json.dumps([_encode_value(v) for v in idx.astype(object)])
    return {field: np.array(elements)}, {**info, "kind": "elements", "field": field, "dtype": spec}


def _same_index(a: pd.Index, b: pd.Index) -> bool:
    """``a`` and ``b`` are the same index: class, dtype, values, names, freq, and the same for their parts."""
    if (type(a) is not type(b) or a.dtype != b.dtype or len(a) != len(b) or not a.equals(b)
            or json.dumps(_encode_names(a.names)) != json.dumps(_encode_names(b.names))):
        return False
    if isinstance(a, pd.MultiIndex):
        return (all(_same_index(x, y) for x, y in zip(a.levels, b.levels))
                and all(np.array_equal(x, y) for x, y in zip(a.codes, b.codes)))
    if isinstance(a, pd.CategoricalIndex):
        return _same_index(a.categories, b.categories) and np.array_equal(a.codes, b.codes)
    if isinstance(a, pd.IntervalIndex):
        return _same_index(a.left, b.left) and _same_index(a.right, b.right)
    return getattr(a, "freq", None) == getattr(b, "freq", None)


# ------------------------------------------------------------------------------------------ .npy members
def _npy_bytes(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.asarray(arr), allow_pickle=False)
    return buf.getvalue()


def _parse_npy(raw: bytes) -> np.ndarray:
    """The array of one ``.npy`` member, parsed without pickle and without trusting the size its header
    announces: ``ValueError`` unless the header is valid and the data are exactly the bytes it announces."""
    fp = io.BytesIO(raw)
    try:
        version = np.lib.format.read_magic(fp)
        if version == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(fp)
        elif version == (2, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(fp)
        else:
            raise ValueError(f".npy version {version} is not written by tsfdi")
    except (ValueError, TypeError, SyntaxError, RecursionError, MemoryError, OverflowError) as exc:
        raise ValueError(f"bad .npy header: {exc}") from None
    if dtype.hasobject or dtype.itemsize == 0 or dtype.kind not in "biufcUMm":
        raise ValueError(f"dtype {dtype} is not written by tsfdi")
    if any(n < 0 for n in shape):
        raise ValueError(f"negative shape {shape}")
    size = math.prod(shape) * dtype.itemsize
    data = memoryview(raw)[fp.tell():]
    if len(data) != size:
        raise ValueError(f"its header announces shape {shape} of {dtype} ({size} bytes) but it holds {len(data)}")
    arr = np.frombuffer(data, dtype=dtype).reshape(shape, order="F" if fortran else "C")
    return np.array(arr, dtype=dtype.newbyteorder("="), order="C")    # native byte order, writable


# ---------------------------------------------------------------------------------------------- reading
class _Archive:
    """The fields of one model file: typed access that names the file and the field in every error.

    ``raw`` holds the ``.npy`` bytes of the members read from a file; ``arrays`` holds arrays already parsed
    (what :func:`save` checks an index description against).
    """

    def __init__(self, path: Path, raw: dict[str, bytes] | None = None,
                 arrays: dict[str, np.ndarray] | None = None, prefix: str | None = None) -> None:
        self.path = path
        self.prefix = f"model file {str(path)!r} is damaged: " if prefix is None else prefix
        self.raw = {} if raw is None else raw
        self.arrays = {} if arrays is None else dict(arrays)
        self.used: set[str] = set()

    def damaged(self, what: str) -> ValueError:
        return ValueError(f"{self.prefix}{what}")

    def array(self, field: str, kinds: str, ndim: int) -> np.ndarray:
        """Field ``field``, an ``ndim``-D array whose dtype kind is one of ``kinds``."""
        self.used.add(field)
        if field not in self.arrays:
            if field not in self.raw:
                raise self.damaged(f"field {field!r} is missing")
            try:
                self.arrays[field] = _parse_npy(self.raw[field])
            except ValueError as exc:
                raise self.damaged(f"field {field!r} is not a valid .npy array ({exc})") from None
        arr = self.arrays[field]
        if arr.dtype.kind not in kinds or arr.ndim != ndim:
            raise self.damaged(f"field {field!r} holds a {arr.ndim}-D array of dtype {arr.dtype}, expected a "
                               f"{ndim}-D array of {_KINDS[kinds]}")
        return arr

    def float_array(self, field: str, ncols: int | None = None) -> np.ndarray:
        """Field ``field``: a finite float64 2-D array (with ``ncols`` columns)."""
        arr = self.array(field, "f", 2)
        if arr.dtype != np.float64:
            raise self.damaged(f"field {field!r} has dtype {arr.dtype}, expected float64")
        if ncols is not None and arr.shape[1] != ncols:
            raise self.damaged(f"field {field!r} has {arr.shape[1]} column(s), its metadata lists {ncols} channel(s)")
        if not np.isfinite(arr).all():
            raise self.damaged(f"field {field!r} contains {int((~np.isfinite(arr)).sum())} NaN/inf value(s)")
        return arr

    def json(self, field: str) -> Any:
        """Field ``field``: a 0-d string array holding JSON."""
        text = str(self.array(field, "U", 0)[()])
        try:
            return json.loads(text)
        except (ValueError, RecursionError) as exc:
            raise self.damaged(f"field {field!r} is not valid JSON ({exc})") from None

    def entry(self, obj: Any, where: str, key: str, *types: type, field: str = "meta") -> Any:
        """``obj[key]`` of the JSON of ``field`` (``where`` locates ``obj``), an instance of one of ``types``."""
        if not isinstance(obj, dict) or key not in obj:
            raise self.damaged(f"field {field!r} has no entry '{where}{key}'")
        value = obj[key]
        if not isinstance(value, types) or (isinstance(value, bool) and int in types and bool not in types):
            expected = " or ".join("null" if t is type(None) else t.__name__ for t in types)
            raise self.damaged(f"field {field!r}: entry '{where}{key}' must be {expected}, got {_short(value)}")
        return value

    def value(self, obj: Any, where: str, key: str) -> Any:
        """Entry ``key`` of ``obj``: a name stored by :func:`_encode_value`."""
        return self.decoded(self.entry(obj, where, key, object), f"{where}{key}")

    def decoded(self, raw: Any, where: str) -> Any:
        try:
            return _decode_value(raw)
        except (ValueError, RecursionError) as exc:
            raise self.damaged(f"field 'meta': entry '{where}' is not a valid name ({exc})") from None

    def choice(self, obj: Any, where: str, key: str, options: tuple[str, ...]) -> str:
        """Entry ``key`` of ``obj``: one of the strings ``options``."""
        value = self.entry(obj, where, key, str)
        if value not in options:
            raise self.damaged(f"field 'meta': entry '{where}{key}' must be one of {options}, got {_short(value)}")
        return value

    def verify_checksums(self) -> None:
        """Every field has the SHA-256 digest listed in field ``checksums``, and no field is missing or extra."""
        if "checksums" not in self.raw:
            raise self.damaged("field 'checksums' is missing")
        sums = self.entry(self.json("checksums"), "", "sha256", dict, field="checksums")
        for field in self.raw:
            if field != "checksums" and field not in sums:
                raise self.damaged(f"field {field!r} has no checksum in field 'checksums'")
        for field, digest in sums.items():
            if field not in self.raw:
                raise self.damaged(f"field {field!r} is missing")
            if not isinstance(digest, str) or hashlib.sha256(self.raw[field]).hexdigest() != digest:
                raise self.damaged(f"checksum of field {field!r} does not match")

    # --- indexes
    def index(self, info: Any, where: str, depth: int = 0) -> pd.Index:
        """The index described by ``info`` (format version 2), at ``where`` in the metadata."""
        kind = self.choice(info, where, "kind", ("range", "numeric", "elements", "datetime", "timedelta", "period",
                                                 "categorical", "interval", "multi"))
        if depth >= _MAX_DEPTH:
            raise self.damaged(f"field 'meta': the index description '{where[:-1]}' is nested too deeply")
        if kind == "multi":
            levels = self.entry(info, where, "levels", list)
            codes = self.entry(info, where, "codes", list)
            names = self.entry(info, where, "names", list)
            if not levels or len(codes) != len(levels) or len(names) != len(levels):
                raise self.damaged(f"field 'meta': entry '{where}' needs as many levels, codes and names, "
                                   f"got {len(levels)}, {len(codes)}, {len(names)}")
            parts = [self.index(level, f"{where}levels[{i}].", depth + 1) for i, level in enumerate(levels)]
            code_arrays = [self.array(self._field_name(c, f"{where}codes[{i}]"), "i", 1) for i, c in enumerate(codes)]
            labels = [self.decoded(n, f"{where}names[{i}]") for i, n in enumerate(names)]
            return self._build(where, lambda: pd.MultiIndex(levels=parts, codes=code_arrays, names=labels))
        name = self.value(info, where, "name")
        if kind == "range":
            start, stop, step = (self.entry(info, where, k, int) for k in ("start", "stop", "step"))
            return self._build(where, lambda: pd.RangeIndex(start, stop, step, name=name))
        if kind == "interval":
            closed = self.choice(info, where, "closed", ("left", "right", "both", "neither"))
            left = self.index(self.entry(info, where, "left", dict), f"{where}left.", depth + 1)
            right = self.index(self.entry(info, where, "right", dict), f"{where}right.", depth + 1)
            return self._build(where, lambda: pd.IntervalIndex.from_arrays(left, right, closed=closed, name=name))
        if kind == "categorical":
            ordered = self.entry(info, where, "ordered", bool)
            categories = self.index(self.entry(info, where, "categories", dict), f"{where}categories.", depth + 1)
            codes = self.array(self._field_name(info.get("field"), f"{where}field"), "i", 1)
            return self._build(where, lambda: pd.CategoricalIndex(pd.Categorical.from_codes(
                codes, dtype=pd.CategoricalDtype(categories, ordered=ordered)), name=name))
        field = self._field_name(info.get("field"), f"{where}field")
        if kind == "numeric":
            arr = self.array(field, "biufc", 1)
            return self._build(where, lambda: pd.Index(arr, dtype=arr.dtype, name=name))
        if kind == "elements":
            spec = self.entry(info, where, "dtype", str, dict)
            elements = self.json(field)
            if not isinstance(elements, list):
                raise self.damaged(f"field {field!r} must hold a JSON list, got {type(elements).__name__}")
            try:
                values = [_decode_value(v) for v in elements]
            except (ValueError, RecursionError) as exc:
                raise self.damaged(f"field {field!r} holds an element that is not stored by tsfdi ({exc})") from None
            return self._build(where, lambda: pd.Index(values, dtype=self._dtype(spec), name=name,
                                                       tupleize_cols=False))
        arr = self.array(field, "i", 1)
        if arr.dtype != np.int64:
            raise self.damaged(f"field {field!r} has dtype {arr.dtype}, expected int64")
        freq = self.entry(info, where, "freq", str, type(None))
        if kind == "period":
            return self._build(where, lambda: pd.PeriodIndex.from_ordinals(arr, freq=freq, name=name))
        unit = self.choice(info, where, "unit", ("s", "ms", "us", "ns"))
        if kind == "timedelta":
            return self._build(where, lambda: pd.TimedeltaIndex(arr.view(f"m8[{unit}]"), freq=freq, name=name))
        tz = self.entry(info, where, "tz", str, type(None))

        def datetimes() -> pd.DatetimeIndex:
            index = pd.DatetimeIndex(arr.view(f"M8[{unit}]"), name=name)
            if tz is not None:
                index = index.tz_localize("UTC").tz_convert(tz)
            return index if freq is None else pd.DatetimeIndex(index, freq=freq, name=name)

        return self._build(where, datetimes)

    def _field_name(self, value: Any, where: str) -> str:
        if not isinstance(value, str):
            raise self.damaged(f"field 'meta': entry '{where}' must name a field, got {_short(value)}")
        return value

    def _dtype(self, spec: Any) -> Any:
        if spec == "object":
            return object
        if isinstance(spec, dict):
            return pd.StringDtype(spec.get("string"), na_value=pd.NA if spec.get("na") == "NA" else np.nan)
        return pd.api.types.pandas_dtype(spec)

    def _build(self, where: str, make: Any) -> pd.Index:
        try:
            return make()
        except _REBUILD_ERRORS as exc:
            raise self.damaged(f"the index described by entry '{where[:-1]}' of field 'meta' cannot be rebuilt "
                               f"({_error(exc)})") from None

    def index_v1(self, info: Any, field: str, where: str) -> pd.Index:
        """The index described by ``info`` in a format version 1 archive."""
        kind = self.choice(info, where, "type", ("range", "values"))
        name = self.value(info, where, "name")
        if kind == "range":
            start, stop, step = (self.entry(info, where, k, int) for k in ("start", "stop", "step"))
            return self._build(where, lambda: pd.RangeIndex(start, stop, step, name=name))
        if "tz" not in info:
            arr = self.array(field, "biufcUMm", 1)
            return self._build(where, lambda: pd.Index(
                arr.astype(object) if info.get("dtype") == "str" else arr, name=name))
        arr = self.array(field, "M", 1)
        unit = self.entry(info, where, "unit", str)
        tz = self.entry(info, where, "tz", str, type(None))
        freq = self.entry(info, where, "freq", str, type(None))

        def datetimes() -> pd.DatetimeIndex:
            index = pd.DatetimeIndex(arr.astype(unit), name=name)
            if tz is not None:
                index = index.tz_localize("UTC").tz_convert(tz)
            return index if freq is None else pd.DatetimeIndex(index, freq=freq, name=name)

        return self._build(where, datetimes)

    # --- records
    def signal(self, meta: Any, prefix: str, label: str, version: int) -> Signal:
        """Record ``label`` (``y[0]``, ``u[1]``, ...) from its metadata and fields ``<prefix>values`` / index."""
        where = f"{label}."
        kind = self.choice(meta, where, "kind", ("numpy", "pandas", "xarray"))
        vector = self.entry(meta, where, "vector", bool)
        channels = self.entry(meta, where, "channels", list)
        if not channels or not all(isinstance(c, str) for c in channels):
            raise self.damaged(f"field 'meta': entry '{where}channels' must be a non-empty list of strings")
        values = self.float_array(f"{prefix}values", len(channels))
        nobs, nchan = values.shape
        if nobs < 1 or (not vector and nchan != 1):
            raise self.damaged(f"field '{prefix}values' has shape {values.shape}, which does not fit a "
                               f"{'vector' if vector else 'scalar'} signal")
        if nobs > 1 and (np.ptp(values, axis=0) == 0).any():
            raise self.damaged(f"field '{prefix}values' has a constant channel, which no fitted model was built on")
        info = self.entry(meta, where, "index", dict, type(None))
        if (info is None) != (kind == "numpy"):
            raise self.damaged(f"field 'meta': entry '{where}index' does not fit the {kind} record kind")
        index = None
        if info is not None:
            index = (self.index(info, f"{where}index.") if version >= 2
                     else self.index_v1(info, f"{prefix}index", f"{where}index."))
            if len(index) != nobs:
                raise self.damaged(f"the index of {label} (entry '{where}index' of field 'meta') has {len(index)} "
                                   f"entries but its data (field '{prefix}values') has {nobs} samples")
        return Signal(values=values, kind=kind, vector=vector, index=index, channels=channels,
                      name=self.value(meta, where, "name"), time_dim=self.value(meta, where, "time_dim"),
                      channel_dim=self.value(meta, where, "channel_dim"))


def _error(exc: BaseException) -> str:
    kind = type(exc)
    return f"{'' if kind.__module__ == 'builtins' else kind.__module__ + '.'}{kind.__name__}: {exc}"


def _read_member(path: Path, zf: zipfile.ZipFile, info: zipfile.ZipInfo) -> bytes:
    try:
        return zf.read(info)
    except _ZIP_ERRORS as exc:
        raise ValueError(f"model file {str(path)!r} is damaged: field {info.filename[:-4]!r} cannot be read "
                         f"({_error(exc)})") from None


def _npz_path(path: Any) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or path-like, got {type(path).__name__}")
    p = Path(path)
    if not p.name:
        raise ValueError(f"path must name a file, got {str(path)!r}")
    return p


def _read(p: Path) -> tuple[_Archive, dict, int, str]:
    """The fields of model file ``p`` (checksums verified), its metadata, format version and model family."""
    foreign = f"model file {str(p)!r} is not a tsfdi results archive"
    with open(p, "rb") as fh:
        if os.fstat(fh.fileno()).st_size == 0:
            raise ValueError(f"{foreign}: the file is empty")
        try:
            zf = zipfile.ZipFile(fh)
        except _ZIP_ERRORS as exc:
            raise ValueError(f"{foreign}: it is not a zip (.npz) archive, or a damaged one "
                             f"({_error(exc)})") from None
        with zf:
            members: dict[str, zipfile.ZipInfo] = {}
            for info in zf.infolist():
                if info.filename in members:
                    raise ValueError(f"model file {str(p)!r} is damaged: member {info.filename!r} appears twice")
                members[info.filename] = info
            if "meta.npy" not in members:
                raise ValueError(f"{foreign} (it has no field 'meta')")
            # the metadata first: a foreign or newer archive is refused before the rest is read
            archive = _Archive(p, {"meta": _read_member(p, zf, members.pop("meta.npy"))})
            meta = archive.json("meta")
            if not isinstance(meta, dict) or meta.get("format") != FORMAT:
                raise ValueError(f"{foreign} (field 'meta' does not name the format {FORMAT!r})")
            version = archive.entry(meta, "", "version", int)
            if version > VERSION:
                raise ValueError(f"model file {str(p)!r} was written by a newer tsfdi (format version {version}; "
                                 f"this tsfdi reads versions 1 to {VERSION})")
            if version < 1:
                raise archive.damaged(f"field 'meta': entry 'version' must be >= 1, got {version}")
            family = archive.entry(meta, "", "family", str)
            if family not in _families:
                raise ValueError(f"model file {str(p)!r} holds an unknown model family {family!r}")
            for name, info in members.items():
                if not name.endswith(".npy"):
                    raise archive.damaged(f"member {name!r} is not a field of a model file (a .npy array)")
                archive.raw[name[:-4]] = _read_member(p, zf, info)
    if version >= 2:
        archive.verify_checksums()
        archive.used.add("checksums")
    return archive, meta, version, family


# ------------------------------------------------------------------------------------------- public API
def save(results: Any, path: Any) -> Path:
    """Write ``results`` (AR, VAR, ARX, VARX, or a functionally pooled FPAR, FPVAR, FPARX, FPMean) to ``path`` as a
    compressed ``.npz`` archive (format version 2).

    ``.npz`` is appended to a file name that does not end with it, as :func:`numpy.savez` does. The file is
    written next to its final name and renamed into place, so an interrupted save leaves no partial archive.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ValueError
        A record's time index or name that cannot be stored exactly (see the module documentation), parameters
        that are not finite, or an FP model's point at k (``FPResults.at``: save the FP results instead).
    FileNotFoundError
        The directory of ``path`` does not exist.
    """
    path = _npz_path(path)
    if not path.name.lower().endswith(".npz"):
        path = path.with_name(path.name + ".npz")
    model = results.model
    if "held_out_residuals" in vars(model):
        raise ValueError("results is a functionally pooled model's point at k (FPResults.at): its held-out "
                         "residuals are the FP model's, which a saved point model cannot keep (loaded, it would "
                         "calibrate on another model's null); save the FP results and call .at(k) after loading")
    params = np.asarray(results.params2d, dtype=np.float64)
    if not np.isfinite(params).all():
        raise ValueError("the parameters contain NaN/inf: these results cannot be saved")
    arrays: dict[str, np.ndarray] = {"params": params}

    def record(sig: Signal, prefix: str, label: str) -> dict[str, Any]:
        arrays[f"{prefix}values"] = sig.values
        try:
            meta = {"kind": sig.kind, "vector": sig.vector, "channels": [str(c) for c in sig.channels],
                    "name": _encode_value(sig.name), "time_dim": _encode_value(sig.time_dim),
                    "channel_dim": _encode_value(sig.channel_dim), "index": None}
        except TypeError as exc:
            raise ValueError(f"the name of {label} cannot be stored in a model file: {exc}") from None
        idx = sig.index
        if idx is not None:
            what = f"{type(idx).__name__} of dtype {idx.dtype}"
            try:
                idx_arrays, info = _index_fields(idx, f"{prefix}index")
            except TypeError as exc:
                raise ValueError(f"the time index of {label} ({what}) cannot be stored in a model file: "
                                 f"{exc}") from None
            info = json.loads(json.dumps(info))
            try:
                back = _Archive(path, arrays=idx_arrays, prefix="").index(info, "index.")
            except ValueError as exc:
                raise ValueError(f"the time index of {label} ({what}) cannot be stored in a model file: it does "
                                 f"not read back ({exc})") from None
            if not _same_index(back, idx):
                raise ValueError(f"the time index of {label} ({what}) cannot be stored in a model file: it reads "
                                 f"back as {type(back).__name__} of dtype {back.dtype}, not the same index")
            arrays.update(idx_arrays)
            meta["index"] = info
        return meta

    def records(signals: tuple[Signal, ...], letter: str) -> list[dict[str, Any]]:
        return [record(r, f"{letter}{i}_", f"{letter}[{i}]" if model.multi else letter)
                for i, r in enumerate(signals)]

    ymeta = records(model.records, "y")
    umeta = None if model.u_records is None else records(model.u_records, "u")
    family = type(model).__name__
    if family == "FPMean":
        options: dict[str, Any] = {"window": model.window, "grid": model.grid}
    else:
        options = {"na": model.na, "nb": model.nb, "nk": model.nk, "trend": model.trend,
                   "hold_back": model.hold_back, "criterion": model.criterion}
    if family in _FP_FAMILIES:
        arrays["k"] = np.asarray(model.k, dtype=np.float64)
        arrays["k_range"] = np.asarray(model.k_range, dtype=np.float64)
        if getattr(results, "weights", None) is not None:
            arrays["weights"] = np.asarray(results.weights, dtype=np.float64)
        options.update(degree=list(model.degree), basis=model.basis, k_names=list(model.k_names))
        if family != "FPMean":
            options["weights"] = model.weights
    meta: dict[str, Any] = {"format": FORMAT, "version": VERSION, "family": type(model).__name__,
                            "options": options, "multi": model.multi, "y": ymeta, "u": umeta}
    payload = {"meta": _npy_bytes(np.array(json.dumps(meta)))}
    payload.update((field, _npy_bytes(arr)) for field, arr in arrays.items())
    digests = {field: hashlib.sha256(data).hexdigest() for field, data in payload.items()}
    payload["checksums"] = _npy_bytes(np.array(json.dumps({"sha256": digests})))

    if not path.parent.is_dir():
        raise FileNotFoundError(f"the directory {str(path.parent)!r} of model file {str(path)!r} does not exist")
    if path.is_dir():
        raise ValueError(f"path {str(path)!r} is a directory, not a model file")
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        with open(tmp, "xb") as fh, zipfile.ZipFile(fh, "w") as zf:
            for field, data in payload.items():
                info = zipfile.ZipInfo(f"{field}.npy", date_time=(1980, 1, 1, 0, 0, 0))
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                zf.writestr(info, data)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def load(path: Any) -> Any:
    """Load a results object written by ``Results.save``; the round trip is exact.

    Parameters
    ----------
    path : str or path-like
        A ``.npz`` archive written by ``save``. When ``path`` does not exist and does not end with ``.npz``,
        ``path + ".npz"`` is read (the name ``save`` wrote).

    Returns
    -------
    ARResults, VARResults, ARXResults, FPResults or FPMeanResults
        The results of the stored model with the stored parameters (not re-estimated).

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        The file is not a tsfdi model archive, was written by a newer tsfdi, or is damaged; the message names
        the file and the field (``model file 'm.npz' is damaged: checksum of field 'params' does not match``).
    """
    p = _npz_path(path)
    if not p.exists() and not p.name.lower().endswith(".npz") and p.with_name(p.name + ".npz").exists():
        p = p.with_name(p.name + ".npz")
    if not p.exists():
        raise FileNotFoundError(f"model file {str(p)!r} does not exist")
    if not p.is_file():
        raise ValueError(f"model file {str(p)!r} is not a file")
    archive, meta, version, family = _read(p)

    options = archive.entry(meta, "", "options", dict)
    if family == "FPMean":
        opts: dict[str, Any] = {k: archive.entry(options, "options.", k, int) for k in ("window", "grid")}
    else:
        opts = {k: archive.entry(options, "options.", k, int) for k in ("na", "nb", "nk", "hold_back")}
        opts["trend"] = archive.choice(options, "options.", "trend", ("n", "c"))
        opts["criterion"] = archive.choice(options, "options.", "criterion", ("logdet", "trace"))
    fp = family in _FP_FAMILIES
    if fp:
        degree = archive.entry(options, "options.", "degree", list)
        k_names = archive.entry(options, "options.", "k_names", list)
        k_values = archive.float_array("k", len(k_names))
        opts["k"] = pd.DataFrame(k_values, columns=[str(n) for n in k_names])
        opts["k_range"] = archive.float_array("k_range", 2)
        opts["degree"] = [archive.entry({"degree": g}, "options.", "degree", int) for g in degree]
        opts["basis"] = archive.choice(options, "options.", "basis", ("legendre", "chebyshev"))
        if family != "FPMean":
            opts["weights"] = archive.choice(options, "options.", "weights", ("pooled", "point"))
    multi = archive.entry(meta, "", "multi", bool)
    ymeta = archive.entry(meta, "", "y", list)
    umeta = archive.entry(meta, "", "u", list, type(None))
    if not ymeta or (not multi and len(ymeta) != 1) or (umeta is not None and len(umeta) != len(ymeta)):
        raise archive.damaged(f"field 'meta': {len(ymeta)} output and {'no' if umeta is None else len(umeta)} "
                              f"input record(s) do not fit multi = {multi}")
    ys = [archive.signal(m, f"y{i}_", f"y[{i}]", version) for i, m in enumerate(ymeta)]
    us = None if umeta is None else [archive.signal(m, f"u{i}_", f"u[{i}]", version) for i, m in enumerate(umeta)]
    try:
        model = _BUILDERS[family](_families[family], ys if multi else ys[0],
                                  us if (us is None or multi) else us[0], opts)
    except (ValueError, TypeError) as exc:
        fields = ", ".join(repr(f) for f in sorted(archive.used) if f.endswith("_values"))
        raise archive.damaged(f"the data (fields {fields}) do not fit the {family} options in field 'meta' "
                              f"({exc})") from None
    params = archive.float_array("params")
    shape = (model.n_basis, model.neqs) if family == "FPMean" else (model.df_eq, model.neqs)
    if params.shape != shape:
        raise archive.damaged(f"field 'params' has shape {params.shape}, the stored {family} model needs {shape}")
    weights = None
    if fp and opts.get("weights") == "point":
        weights = archive.float_array("weights", model.neqs)
        if weights.shape[0] != len(model.records) or not (weights > 0).all():
            raise archive.damaged(f"field 'weights' must hold one positive weight per record and channel, shape "
                                  f"{(len(model.records), model.neqs)}, got shape {weights.shape}")
    extra = sorted(set(archive.raw) - archive.used)
    if extra:
        raise archive.damaged(f"field(s) {', '.join(repr(f) for f in extra)} are not part of a model file")
    if family == "FPMean":
        try:
            return model.results_class(model, params)
        except ValueError as exc:
            raise archive.damaged(f"the stored FPMean model cannot be rebuilt ({exc})") from None
    return model.results_class(model, params) if not fp else model.results_class(model, params, weights)

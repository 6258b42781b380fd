"""The model file format (issue 18, causes 6 and 7): damaged files fail loudly, every index kind round-trips
exactly or is refused when saving, the ``.npz`` suffix, format version 1 files."""

from __future__ import annotations

import datetime
import hashlib
import io
import json
import zipfile

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import tsfdi
from tsfdi.models import archive, load

RNG = np.random.default_rng(18)
Y1 = RNG.standard_normal(80)
Y2 = RNG.standard_normal((80, 2))
U1 = RNG.standard_normal((80, 1))


def members(path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as zf:
        return {info.filename[:-4]: zf.read(info) for info in zf.infolist()}


def npy(arr) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.asarray(arr), allow_pickle=True)   # object arrays: damaged cases
    return buf.getvalue()


def write(path, fields: dict[str, bytes], *, checksums: bool = False) -> None:
    """Write ``fields`` (``.npy`` bytes) as a zip archive; with ``checksums`` the ``checksums`` field is recomputed
    so that only the field validation can find what was changed."""
    fields = dict(fields)
    if checksums:
        fields.pop("checksums", None)
        digests = {k: hashlib.sha256(v).hexdigest() for k, v in fields.items()}
        fields["checksums"] = npy(np.array(json.dumps({"sha256": digests})))
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in fields.items():
            zf.writestr(f"{name}.npy", data)


def meta_of(fields) -> dict:
    return json.loads(str(np.load(io.BytesIO(fields["meta"]))))


def save_v1(res, path) -> None:
    """A format version 1 file, written as tsfdi wrote it before the checksums (the old ``archive.save``)."""
    model = res.model

    def record(sig, prefix):
        arrays = {f"{prefix}values": sig.values}
        meta = {"kind": sig.kind, "vector": sig.vector, "channels": list(sig.channels), "name": sig.name,
                "time_dim": sig.time_dim, "channel_dim": sig.channel_dim, "index": None}
        idx = sig.index
        if isinstance(idx, pd.RangeIndex):
            meta["index"] = {"type": "range", "start": idx.start, "stop": idx.stop, "step": idx.step, "name": idx.name}
        elif idx is not None:
            info = {"type": "values", "name": idx.name if idx.name is None else str(idx.name)}
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

    arrays, ymeta, umeta = {}, [], None
    for i, rec in enumerate(model.records):
        a, m = record(rec, f"y{i}_")
        arrays.update(a)
        ymeta.append(m)
    if model.u_records is not None:
        umeta = []
        for i, rec in enumerate(model.u_records):
            a, m = record(rec, f"u{i}_")
            arrays.update(a)
            umeta.append(m)
    meta = {"format": "tsfdi-results", "version": 1, "family": type(model).__name__,
            "options": {"na": model.na, "nb": model.nb, "nk": model.nk, "trend": model.trend,
                        "hold_back": model.hold_back, "criterion": model.criterion},
            "multi": model.multi, "y": ymeta, "u": umeta}
    arrays["params"] = res.params2d
    arrays["meta"] = np.array(json.dumps(meta))
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)


def assert_same(back, res) -> None:
    np.testing.assert_array_equal(back.params2d, res.params2d)
    assert back.llf == res.llf and back.bic == res.bic
    for a, b in zip(back.model.records, res.model.records):
        assert a.kind == b.kind and a.channels == b.channels and a.name == b.name
        np.testing.assert_array_equal(a.values, b.values)
        if b.index is not None:
            pd.testing.assert_index_equal(a.index, b.index, exact=True, check_exact=True)
            assert getattr(a.index, "freq", None) == getattr(b.index, "freq", None)


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """An AR(2) on a Series with a tz-aware DatetimeIndex, saved; its results and the archive's fields."""
    d = tmp_path_factory.mktemp("archive")
    s = pd.Series(Y1, index=pd.date_range("2024-01-01", periods=Y1.size, freq="10ms", tz="UTC", name="time"))
    res = tsfdi.AR(s, 2, "c").fit()
    path = res.save(d / "m.npz")
    return res, path, members(path)


# ------------------------------------------------------------------------------------------ file names
def test_save_appends_npz_suffix_and_load_finds_it(tmp_path):
    res = tsfdi.AR(Y1, 2).fit()
    for name, written in (("m", "m.npz"), ("m.v2", "m.v2.npz"), ("m.npz", "m.npz"), ("M.NPZ", "M.NPZ")):
        path = res.save(tmp_path / name)
        assert path == tmp_path / written and path.is_file()
        assert_same(load(tmp_path / name), res)       # the name given to save also loads
        assert_same(load(str(path)), res)
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]     # no temporary file left behind


def test_save_is_deterministic_and_readable_by_numpy(tmp_path):
    res = tsfdi.VAR(Y2, 2, "c").fit()
    a, b = res.save(tmp_path / "a"), res.save(tmp_path / "b")
    assert a.read_bytes() == b.read_bytes()
    with np.load(a, allow_pickle=False) as f:
        assert sorted(f.files) == ["checksums", "meta", "params", "y0_values"]
        np.testing.assert_array_equal(f["params"], res.params2d)
        assert json.loads(str(f["meta"]))["version"] == archive.VERSION == 2


def test_paths(tmp_path):
    res = tsfdi.AR(Y1, 2).fit()
    with pytest.raises(FileNotFoundError, match=r"model file '.*nothing.npz' does not exist"):
        load(tmp_path / "nothing.npz")
    with pytest.raises(FileNotFoundError, match="model file '.*nothing' does not exist"):
        load(tmp_path / "nothing")
    with pytest.raises(ValueError, match="is not a file"):
        load(tmp_path)
    with pytest.raises(TypeError, match="path must be a str or path-like, got int"):
        load(3)
    with pytest.raises(TypeError, match="path must be a str or path-like"):
        res.save(None)
    with pytest.raises(FileNotFoundError, match="directory .*missing.* does not exist"):
        res.save(tmp_path / "missing" / "m.npz")


# ------------------------------------------------------------------------- cause 6: damaged model files
def damage_cases(saved_fields):
    """(label, fields or raw bytes, expected message) for a checksummed file rewritten with one change."""
    fields = saved_fields
    meta = meta_of(fields)
    values = np.load(io.BytesIO(fields["y0_values"]))
    return [
        ("missing params", {k: v for k, v in fields.items() if k != "params"}, "field 'params' is missing"),
        ("missing checksums", {k: v for k, v in fields.items() if k != "checksums"}, "field 'checksums' is missing"),
        ("bad meta JSON", {**fields, "meta": npy(np.array('{"format": "tsfdi-results", "version": 2,'))},
         "field 'meta' is not valid JSON"),
        ("NaN params", {**fields, "params": npy(np.array([[np.nan], [0.5], [0.1]]))},
         "checksum of field 'params' does not match"),
        ("truncated data", {**fields, "y0_values": npy(values[:3])}, "checksum of field 'y0_values' does not match"),
        ("wrong parameter shape", {**fields, "params": npy(np.zeros((5, 1)))},
         "checksum of field 'params' does not match"),
        ("options changed", {**fields, "meta": npy(np.array(json.dumps({**meta, "options": {**meta["options"],
                                                                                           "na": 1}})))},
         "checksum of field 'meta' does not match"),
        ("extra field", {**fields, "extra": npy(np.zeros(2))}, "field 'extra' has no checksum"),
    ]


def test_damaged_files(tmp_path, saved):
    res, path, fields = saved
    data = path.read_bytes()
    raw_cases = [("empty", b"", "is not a tsfdi results archive: the file is empty"),
                 ("not a zip", b"time,y\n0,1\n1,2\n", "is not a tsfdi results archive: it is not a zip"),
                 ("a .npy file", npy(np.zeros(3)), "is not a tsfdi results archive: it is not a zip"),
                 ("truncated to half", data[:len(data) // 2], "not a zip"),
                 ("truncated by one byte", data[:-1], "not a zip"),
                 ("foreign npz", None, r"is not a tsfdi results archive \(it has no field 'meta'\)")]
    for label, blob, match in raw_cases:
        bad = tmp_path / f"{label.replace(' ', '_')}.npz"
        if blob is None:
            np.savez(bad, a=np.zeros(3))
        else:
            bad.write_bytes(blob)
        with pytest.raises(ValueError, match=match) as info:
            load(bad)
        assert str(bad) in str(info.value), label
    # a flipped byte in the compressed data of every field: the zip's CRC or the deflate stream catches it
    with zipfile.ZipFile(path) as zf:
        offsets = {i.filename[:-4]: i.header_offset + 30 + len(i.filename) + len(i.extra) for i in zf.infolist()}
    for field, offset in offsets.items():
        blob = bytearray(data)
        blob[offset + 2] ^= 0x10
        (tmp_path / "flip.npz").write_bytes(bytes(blob))
        with pytest.raises(ValueError, match=f"model file '.*flip.npz' is damaged: field '{field}' cannot be read"):
            load(tmp_path / "flip.npz")
    for label, changed, match in damage_cases(fields):
        write(tmp_path / "bad.npz", changed)
        with pytest.raises(ValueError, match=f"model file '.*bad.npz' is damaged: {match}"):
            load(tmp_path / "bad.npz")


def test_damaged_fields_are_validated(tmp_path, saved):
    """With consistent checksums (or none, format version 1) every field is still checked on its own."""
    res, path, fields = saved
    meta = meta_of(fields)
    values = np.load(io.BytesIO(fields["y0_values"]))

    def with_meta(**changes):
        return npy(np.array(json.dumps({**meta, **changes})))

    rec = meta["y"][0]
    cases = [
        ({"params": npy(np.array([[np.nan], [0.5], [0.1]]))}, r"field 'params' contains 1 NaN/inf value\(s\)"),
        ({"params": npy(np.zeros((5, 1)))}, r"field 'params' has shape \(5, 1\), the stored AR model needs \(3, 1\)"),
        ({"params": npy(np.zeros((3, 1), dtype=np.float32))}, "field 'params' has dtype float32, expected float64"),
        ({"params": npy(np.array(["a"]))}, "field 'params' holds a 1-D array of dtype <U1"),
        ({"params": npy(np.array([{}], dtype=object))}, "field 'params' is not a valid .npy array"),
        ({"params": fields["params"][:-8]}, "field 'params' is not a valid .npy array .*header announces"),
        ({"params": b"\x93NUMPY\x01\x00\xff\xff" + b"{" * 200}, "field 'params' is not a valid .npy array"),
        ({"y0_values": npy(values[:3]), "y0_index": npy(np.arange(3, dtype=np.int64)),
          "meta": with_meta(y=[{**rec, "index": {**rec["index"], "freq": None}}])},
         r"the data \(fields 'y0_values'\) do not fit the AR options in field 'meta' \(y is too short for lags=2"),
        ({"y0_values": npy(values[:3])}, r"the index of y\[0\] .* has 80 entries but its data .* has 3 samples"),
        ({"y0_values": npy(np.where(np.arange(80)[:, None] == 7, np.inf, values))}, "field 'y0_values' contains 1"),
        ({"y0_values": npy(np.ones((80, 1)))}, "field 'y0_values' has a constant channel"),
        ({"y0_values": npy(values[:, 0])}, "field 'y0_values' holds a 1-D array"),
        ({"meta": with_meta(options={**meta["options"], "na": 2.5})},
         r"field 'meta': entry 'options.na' must be int, got 2.5"),
        ({"meta": with_meta(options={**meta["options"], "trend": "ct"})},
         "field 'meta': entry 'options.trend' must be one of"),
        ({"meta": with_meta(options={k: v for k, v in meta["options"].items() if k != "na"})},
         "field 'meta' has no entry 'options.na'"),
        ({"meta": with_meta(y=[])}, "field 'meta': 0 output and no input record"),
        ({"meta": with_meta(y=[{**rec, "channels": ["a", "b"]}])}, "field 'y0_values' has 1 column"),
        ({"meta": with_meta(y=[{**rec, "kind": "numpy"}])},
         r"field 'meta': entry 'y\[0\].index' does not fit the numpy"),
        ({"meta": with_meta(y=[{**rec, "index": {**rec["index"], "tz": "Mars/Olympus"}}])},
         r"the index described by entry 'y\[0\].index' of field 'meta' cannot be rebuilt"),
        ({"meta": with_meta(y=[{**rec, "index": {**rec["index"], "freq": "7s"}}])},
         ".* cannot be rebuilt .*does not conform"),
        ({"meta": with_meta(y=[{**rec, "index": {**rec["index"], "kind": "spiral"}}])},
         r"field 'meta': entry 'y\[0\].index.kind' must be one of"),
        ({"meta": with_meta(y=[{**rec, "name": [1, 2]}])}, r"field 'meta': entry 'y\[0\].name' is not a valid name"),
        ({"meta": with_meta(version=0)}, "field 'meta': entry 'version' must be >= 1"),
        ({"meta": with_meta(version="2")}, "field 'meta': entry 'version' must be int"),
        ({"meta": npy(np.array([1.0]))}, "field 'meta' holds a 1-D array of dtype float64"),
        ({"y0_index": npy(np.arange(80.0))}, "field 'y0_index' holds a 1-D array of dtype float64"),
        ({"extra": npy(np.zeros(2))}, "field\\(s\\) 'extra' are not part of a model file"),
    ]
    for changes, match in cases:
        write(tmp_path / "bad.npz", {**fields, **changes}, checksums=True)
        with pytest.raises(ValueError, match=f"model file '.*bad.npz' is damaged: {match}"):
            load(tmp_path / "bad.npz")
    write(tmp_path / "bad.npz", {**fields, "meta": with_meta(format="other")}, checksums=True)
    with pytest.raises(ValueError, match="is not a tsfdi results archive"):
        load(tmp_path / "bad.npz")
    with zipfile.ZipFile(tmp_path / "bad.npz", "w") as zf:     # members that are not .npy arrays, or twice
        zf.writestr("meta.npy", fields["meta"])
        zf.writestr("notes.txt", b"hello")
    with pytest.raises(ValueError, match="member 'notes.txt' is not a field"):
        load(tmp_path / "bad.npz")
    with pytest.warns(UserWarning, match="Duplicate name"), zipfile.ZipFile(tmp_path / "bad.npz", "w") as zf:
        for name, data in [*fields.items(), ("params", fields["params"])]:
            zf.writestr(f"{name}.npy", data)
    with pytest.raises(ValueError, match="damaged: member 'params.npy' appears twice"):
        load(tmp_path / "bad.npz")


def test_save_refuses_non_finite_parameters(tmp_path):
    res = tsfdi.AR(Y1, 2).fit()
    bad = tsfdi.ARResults(res.model, np.array([np.nan, 0.1]))
    with pytest.raises(ValueError, match="parameters contain NaN/inf"):
        bad.save(tmp_path / "m.npz")
    assert not list(tmp_path.iterdir())


# ------------------------------------------------------------------------------- format version 1 files
@pytest.mark.parametrize("case", ["numpy", "range", "datetime_tz", "strings", "arx_records"])
def test_version_1_files_still_load(tmp_path, case):
    if case == "numpy":
        res = tsfdi.VAR(Y2, 2, "c").fit()
    elif case == "range":
        res = tsfdi.AR(pd.Series(Y1, index=pd.RangeIndex(10, 90), name="y"), 2).fit()
    elif case == "datetime_tz":
        idx = pd.date_range("2024-03-30", periods=80, freq="h", tz="Europe/Paris", name="time")
        res = tsfdi.AR(pd.Series(Y1, index=idx), 3, "c").fit()
    elif case == "strings":
        res = tsfdi.AR(pd.Series(Y1, index=pd.Index([f"t{i}" for i in range(80)], dtype=object)), 2).fit()
    else:
        res = tsfdi.ARX([Y1[:40], Y1[40:]], [U1[:40], U1[40:]], 2, 1, 1).fit()
    save_v1(res, tmp_path / "old.npz")
    back = load(tmp_path / "old.npz")
    np.testing.assert_array_equal(back.params2d, res.params2d)
    assert back.llf == res.llf
    if case in ("range", "datetime_tz"):     # what version 1 stored exactly comes back exactly
        assert_same(back, res)
    # a damaged version 1 file (no checksums) is caught by the field validation
    fields = members(tmp_path / "old.npz")
    write(tmp_path / "bad.npz", {**fields, "params": npy(np.full_like(res.params2d, np.nan))})
    with pytest.raises(ValueError, match="model file '.*bad.npz' is damaged: field 'params' contains"):
        load(tmp_path / "bad.npz")


def test_version_1_tuple_range_name_is_refused_clearly(tmp_path):
    # version 1 wrote a RangeIndex's tuple name as a JSON list, which it could not load (issue 18, cause 7)
    res = tsfdi.AR(pd.Series(Y1, index=pd.RangeIndex(80, name=("a", 1))), 2).fit()
    save_v1(res, tmp_path / "old.npz")
    with pytest.raises(ValueError, match=r"damaged: field 'meta': entry 'y\[0\].index.name' is not a valid name"):
        load(tmp_path / "old.npz")


# ------------------------------------------------------------------------------ cause 7: index round trip
INDEXES = {
    "range_tuple_name": lambda n: pd.RangeIndex(5, 5 + 2 * n, 2, name=("a", 1)),
    "int": lambda n: pd.Index(np.arange(n) * 3, name="t"),
    "int32": lambda n: pd.Index(np.arange(n, dtype=np.int32), name=7),
    "uint64": lambda n: pd.Index(np.arange(n, dtype=np.uint64)),
    "float": lambda n: pd.Index(np.linspace(0.0, 1.0, n), name=1.5),
    "bool_like_float_name": lambda n: pd.Index(np.linspace(-1.0, 1.0, n), name=True),
    "str": lambda n: pd.Index([f"s{i}" for i in range(n)]),
    "str_with_missing": lambda n: pd.Index([f"s{i}" for i in range(n - 1)] + [None]),
    "string_dtype_with_NA": lambda n: pd.Index([f"s{i}" for i in range(n - 1)] + [pd.NA], dtype="string"),
    "mixed_int_str": lambda n: pd.Index([i if i % 2 else str(i) for i in range(n)], dtype=object, name=("x", None)),
    "mixed_objects": lambda n: pd.Index([None, True, 1, 1.0, "1", (1, "a"), -0.0, float("inf")]
                                        + list(range(n - 8)), dtype=object, tupleize_cols=False),
    "tuples": lambda n: pd.Index([(i, "a") for i in range(n)], dtype=object, tupleize_cols=False),
    "nullable_int": lambda n: pd.Index(np.arange(n), dtype="Int64"),
    "datetime_tz_freq": lambda n: pd.date_range("2020-03-28", periods=n, freq="h", tz="Europe/Paris", name="time"),
    "datetime_fixed_offset": lambda n: pd.date_range(
        "2020", periods=n, freq="s", tz=datetime.timezone(datetime.timedelta(hours=-3, minutes=-30))),
    "datetime_no_freq": lambda n: pd.DatetimeIndex(pd.date_range("2020", periods=n, freq="D").values),
    "timedelta_freq": lambda n: pd.timedelta_range(0, periods=n, freq="250ms", name="dt"),
    "period": lambda n: pd.period_range("2000-01", periods=n, freq="M", name="p"),
    "period_quarter": lambda n: pd.period_range("2000Q1", periods=n, freq="Q-MAR"),
    "categorical": lambda n: pd.CategoricalIndex([f"c{i % 5}" for i in range(n)], categories=[
        f"c{i}" for i in (4, 2, 0, 1, 3, 9)], ordered=True, name="c"),
    "categorical_of_intervals": lambda n: pd.CategoricalIndex(pd.cut(np.arange(n), 5)),
    "interval": lambda n: pd.interval_range(0, n, name="iv", closed="left"),
    "interval_float_missing": lambda n: pd.IntervalIndex(list(pd.interval_range(0.0, n - 1.0)) + [np.nan]),
    "interval_datetime": lambda n: pd.interval_range(pd.Timestamp("2020", tz="UTC"), periods=n, freq="h"),
    "multi": lambda n: pd.MultiIndex.from_product([pd.date_range("2020", periods=n // 2, freq="D"), ["a", "b"]],
                                                  names=["t", ("x", 1)]),
    "multi_categorical_level": lambda n: pd.MultiIndex.from_arrays(
        [pd.CategoricalIndex(np.arange(n) % 3), np.arange(n) * 0.5], names=[None, "f"]),
}


@pytest.mark.parametrize("kind", list(INDEXES))
def test_every_index_kind_round_trips_exactly(tmp_path, kind):
    idx = INDEXES[kind](Y1.size)
    y = pd.Series(Y1, index=idx, name=("y", 2))
    u = pd.DataFrame(U1, index=idx, columns=["u"])
    for res in (tsfdi.AR(y, 2, "c").fit(), tsfdi.ARX(y, u, 2, 1, 1).fit()):
        back = load(res.save(tmp_path / "m"))
        assert_same(back, res)
        pd.testing.assert_series_equal(back.resid, res.resid)
        assert back.model.u_data is None or back.model.u_data.index.equals(idx)


def test_a_time_index_with_nat_is_refused_at_fit():
    """A missing time stamp cannot be fitted (issue 19: time indexes are checked), so it is never saved."""
    idx = pd.DatetimeIndex(list(pd.date_range("2020", periods=Y1.size - 1, freq="10ms", unit="ns")) + [pd.NaT])
    with pytest.raises(ValueError, match="missing time stamp"):
        tsfdi.AR(pd.Series(Y1, index=idx), 2, "c").fit()


def test_frame_records_with_different_indexes(tmp_path):
    a = pd.DataFrame(Y2[:40], columns=["p", "q"], index=pd.period_range("2001-01", periods=40, freq="D"))
    b = pd.DataFrame(Y2[40:], columns=["p", "q"], index=pd.timedelta_range("1s", periods=40, freq="1s"))
    res = tsfdi.VAR([a, b], 2).fit()
    back = load(res.save(tmp_path / "r"))
    assert_same(back, res)
    for x, z in zip(back.resid, res.resid):
        pd.testing.assert_frame_equal(x, z)


def test_xarray_coordinates_round_trip(tmp_path):
    time = pd.date_range("2024-01-01", periods=80, freq="10ms")
    da = xr.DataArray(Y2, dims=("t", "sensor"), coords={"t": time, "sensor": ["gx", "gy"]}, name=("gyro", 0))
    res = tsfdi.VAR(da, 2).fit()
    back = load(res.save(tmp_path / "x"))
    assert_same(back, res)
    assert back.resid.identical(res.resid) and back.resid.dims == ("t", "sensor")
    np.testing.assert_array_equal(back.resid["t"].values, time.values[2:])


@pytest.mark.parametrize("idx, match", [
    (pd.Index([pd.Timestamp("2020")] + list(range(79)), dtype=object),
     r"time index of y \(Index of dtype object\) cannot be stored in a model file: Timestamp"),
    (pd.Index([b"x"] * 80, dtype=object), "b'x' of type bytes"),
    (pd.RangeIndex(80, name=pd.Timestamp("2020")), "RangeIndex of dtype int64.*of type Timestamp"),
])
def test_index_that_cannot_be_stored_is_refused_at_save(tmp_path, idx, match):
    res = tsfdi.AR(pd.Series(Y1, index=idx), 2).fit()
    with pytest.raises(ValueError, match=match):
        res.save(tmp_path / "m.npz")
    assert not list(tmp_path.iterdir())


def test_unstorable_series_name_is_refused(tmp_path):
    res = tsfdi.AR(pd.Series(Y1, name=frozenset({1})), 2).fit()
    with pytest.raises(ValueError, match="the name of y cannot be stored in a model file: frozenset"):
        res.save(tmp_path / "m.npz")


def test_time_zone_without_a_readable_name_is_refused(tmp_path):
    tz = pytest.importorskip("dateutil.tz").gettz("Europe/Paris")
    if tz is None:
        pytest.skip("no time zone database")
    res = tsfdi.AR(pd.Series(Y1, index=pd.date_range("2020", periods=80, freq="h", tz=tz)), 2).fit()
    with pytest.raises(ValueError, match=r"time index of y \(DatetimeIndex of dtype datetime64\[us, tzfile.*"
                                         "it does not read back"):
        res.save(tmp_path / "m.npz")

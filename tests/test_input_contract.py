"""The input contract of the high-level entry points (issue 18, causes 8, 9 and 10).

Every entry point returns a correct result or raises a ``ValueError`` / ``TypeError`` (``FileNotFoundError`` for a
missing path) whose message names the argument, the file or the flag: detect / identify / identify_windows,
ResidualWindows, Monitor, OnlineDetector, fit_baselines / Baselines, evaluate, the ALFA and CrazyPAD loaders and
the command line.
"""

from __future__ import annotations

import gzip
import re

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import tsfdi
from tsfdi.cli import main
from tsfdi.datasets import list_alfa, list_crazypad, load_alfa, read_crazypad_log
from tsfdi.evaluation import first_alarm, score_records
from tsfdi.identification import identify_windows
from tsfdi.windows import ResidualWindows

rng = np.random.default_rng(18)
Y = rng.standard_normal(400)
U = rng.standard_normal(400)
Y2 = rng.standard_normal((400, 2))


@pytest.fixture(scope="module")
def fits():
    return {"ar": tsfdi.AR(Y, 2).fit(), "ar3": tsfdi.AR(rng.standard_normal(400), 3).fit(),
            "var": tsfdi.VAR(Y2, 1).fit(), "arx": tsfdi.ARX(Y, U, 2, 2).fit()}


def masked(x, at=3):
    mask = np.zeros(np.shape(x), dtype=bool)
    mask[at] = True
    return np.ma.array(x, mask=mask)


# ------------------------------------------------------------------------------------- cause 9: arguments
def test_detect_u_on_a_model_without_input_is_refused(fits):
    with pytest.raises(TypeError, match=r"u is only for input-output \(ARX\) models: baseline \(ARResults\)"):
        tsfdi.detect(Y, fits["ar"], u=U)
    with pytest.raises(TypeError, match=r"u is only for input-output \(ARX\) models: models\['h'\]"):
        tsfdi.identify(Y, {"h": fits["ar"]}, u=U)


def test_arx_needs_u_and_gets_it(fits):
    with pytest.raises(TypeError, match=r"u is required: baseline is an ARX"):
        tsfdi.detect(Y, fits["arx"])
    with pytest.raises(TypeError, match=r"u is required: models\['h'\] is an ARX"):
        tsfdi.identify(Y, {"h": fits["arx"]})
    d = tsfdi.detect(Y, fits["arx"], u=U)
    direct = tsfdi.LjungBox().test(fits["arx"].residuals(Y, U))
    np.testing.assert_array_equal(d.statistic, direct.statistic)
    assert tsfdi.identify(Y, {"h": fits["arx"]}, u=U).decisions["h"].reject == d.reject


def test_windowed_engine_and_monitor_need_the_input_of_arx(fits):
    """ARX models go through the windowed engine with ``u`` (issue 32): without it, or mixed with AR, refused."""
    with pytest.raises(TypeError, match="u is required"):
        identify_windows(Y, {"h": fits["arx"]}, window=100)
    with pytest.raises(TypeError, match="u is required"):
        ResidualWindows({"h": fits["arx"]}).fit(Y)
    with pytest.raises(TypeError, match="baseline and models mix input-output"):
        tsfdi.Monitor(fits["arx"], {"f": fits["ar"]}, window=100, step=10, steady_window=50)


@pytest.mark.parametrize("y, u, exc, name", [
    (None, 1.0, TypeError, "y"), (1.0, None, TypeError, "u"), ("a", 1.0, TypeError, "y"),
    (True, 1.0, TypeError, "y"), (1.0, np.bool_(False), TypeError, "u"), (1 + 2j, 1.0, TypeError, "y"),
    (object(), 1.0, TypeError, "y"), ([[1.0]], 1.0, ValueError, "y"), ([1.0, 2.0], 1.0, ValueError, "y"),
    (1.0, [1.0, 2.0], ValueError, "u"), (np.ma.array([1.0], mask=[True]), 1.0, ValueError, "y"),
])
def test_online_update_refuses_bad_samples(y, u, exc, name):
    det = tsfdi.OnlineDetector(1)
    with pytest.raises(exc, match=rf"^{name} "):
        det.update(y, u)
    assert det.nobs == 0


def test_online_update_equals_run_on_valid_samples():
    y, u = Y[:300], U[:300]
    a = tsfdi.OnlineDetector(1, na=1, nb=1)
    alarms = np.array([a.update(float(yi), [ui])[0] for yi, ui in zip(y, u)])
    b = tsfdi.OnlineDetector(1, na=1, nb=1).run(y, u)
    np.testing.assert_array_equal(alarms, b.alarm[:, 0])
    c = tsfdi.OnlineDetector(1, na=1, nb=1)
    c.update(np.float32(y[0]), np.array([u[0]]))
    c.update(int(3), 2)          # integers are numbers
    assert c.nobs == 2


def test_residual_windows_validate_their_input(fits):
    rw = ResidualWindows({"h": fits["ar"]})
    with pytest.raises(TypeError, match="^signal must contain real numbers"):
        rw.fit(np.array(["a"] * 50))
    with pytest.raises(ValueError, match="^signal is too short"):
        rw.fit(np.array([]))
    with pytest.raises(ValueError, match="^signal must be 1-D"):
        rw.fit(np.zeros((10, 2, 2)))
    with pytest.raises(ValueError, match="^signal contains 1 NaN"):
        rw.fit(np.r_[np.nan, Y])
    with pytest.raises(TypeError, match="^residuals must be a mapping"):
        rw.fit_residuals([Y], 400)
    with pytest.raises(TypeError, match=r"^residuals\['h'\] must contain real numbers"):
        rw.fit_residuals({"h": np.array(["x"] * 398)}, 400)
    with pytest.raises(ValueError, match="^nobs"):
        rw.fit_residuals({"h": Y}, 2)
    with pytest.raises(TypeError, match="^loglik"):
        rw.fit(Y).statistics(tsfdi.LjungBox(lags=5), window=50, loglik="no")
    # a Series keeps its name as the channel name; results equal those of the plain array
    ws = rw.fit(pd.Series(Y, name="roll")).statistics(tsfdi.LjungBox(lags=5), window=50, step=25)
    assert ws.channels == ("roll",)
    np.testing.assert_array_equal(ws.statistic, ResidualWindows({"h": fits["ar"]}).fit(Y).statistics(
        tsfdi.LjungBox(lags=5), window=50, step=25).statistic)


def test_signal_conversion_names_the_argument(fits):
    ar = fits["ar"]
    with pytest.raises(ValueError, match="^signal must be a rectangular"):
        tsfdi.detect([[1.0, 2.0], [3.0]], ar)
    with pytest.raises(ValueError, match="^signal holds a number too large for float64"):
        tsfdi.detect(np.array([10 ** 400] * 50, dtype=object), ar)
    with pytest.raises(TypeError, match="^signal must contain real numbers, got dtype timedelta64"):
        tsfdi.detect(np.arange(50).astype("timedelta64[s]"), ar)
    with pytest.raises(TypeError, match="^signal must contain real numbers, got dtype datetime64"):
        tsfdi.detect(np.arange(50).astype("datetime64[s]"), ar)
    # a time span that is more samples than a float holds
    with pytest.raises(ValueError, match="^window = '2s' at fs = 1e\\+308 Hz is too many samples"):
        identify_windows(Y, {"h": ar}, window="2s", fs=1e308)
    with pytest.raises(ValueError, match="^window = '2s'"):
        tsfdi.Monitor(ar, {"f": ar}, window="2s", fs=1e308)


def test_monitor_steady_thresholds_named(fits):
    ar = fits["ar"]
    with pytest.raises(TypeError, match="^steady_thresholds must be 1 number"):
        tsfdi.Monitor(ar, {"f": ar}, window=100, step=10, steady_window=50, steady_thresholds="abc")


# ------------------------------------------------------------------------------------ cause 10: masked arrays
def test_masked_arrays_are_refused_everywhere(fits):
    ar = fits["ar"]
    msg = r"is a masked array with 1 masked value\(s\) \(first at sample 3\): fill or drop"
    with pytest.raises(ValueError, match="^y " + msg):
        tsfdi.AR(masked(Y), 2)
    with pytest.raises(ValueError, match="^signal " + msg):
        tsfdi.detect(masked(Y), ar)
    with pytest.raises(ValueError, match="^signal " + msg):
        tsfdi.identify(masked(Y), {"h": ar})
    with pytest.raises(ValueError, match="^signal " + msg):
        identify_windows(masked(Y), {"h": ar}, window=100)
    with pytest.raises(ValueError, match="^signal " + msg):
        ResidualWindows({"h": ar}).fit(masked(Y))
    with pytest.raises(ValueError, match="^signal " + msg):
        tsfdi.Monitor(ar, {"f": ar}, window=100, step=10, steady_window=50).run(masked(Y))
    with pytest.raises(ValueError, match=r"^signal\[1\] " + msg):
        tsfdi.detect([Y, masked(Y)], ar)
    det = tsfdi.OnlineDetector(1)
    with pytest.raises(ValueError, match="^y " + msg):
        det.run(masked(Y), U)
    with pytest.raises(ValueError, match="^u " + msg):
        det.run(Y, masked(U))
    with pytest.raises(ValueError, match="^healthy run 0: y " + msg):
        det.calibrate([masked(Y)], [U], false_alarms_per_hour=1.0, fs=100.0)
    with pytest.raises(ValueError, match="^steady_thresholds is a masked array"):
        tsfdi.Monitor(ar, {"f": ar}, window=100, step=10, steady_window=50,
                      steady_thresholds=np.ma.array([1.0], mask=[True]))
    with pytest.raises(ValueError, match="^alarm is a masked array"):
        first_alarm(np.ma.array([False, True], mask=[False, True]))
    with pytest.raises(ValueError, match="^time is a masked array"):
        first_alarm([False, True], time=np.ma.array([0.0, 1.0], mask=[False, True]))
    with pytest.raises(ValueError, match="^onset is a masked array"):
        score_records(np.ma.array([1.0, 2.0], mask=[True, False]), [1.0, 2.0])


def test_masked_array_without_masked_values_is_plain_data(fits):
    plain = tsfdi.detect(Y, fits["ar"])
    same = tsfdi.detect(np.ma.array(Y), fits["ar"])
    np.testing.assert_array_equal(plain.statistic, same.statistic)
    np.testing.assert_array_equal(tsfdi.AR(np.ma.array(Y, mask=False), 2).fit().params, fits["ar"].params)


def test_masked_records_and_failure_times_refused():
    recs = [rng.standard_normal((300, 2)) for _ in range(4)]
    states = ["healthy", "healthy", "f", "f"]
    with pytest.raises(ValueError, match=r"^data\[2\] is a masked array"):
        tsfdi.fit_baselines([*recs[:2], masked(recs[2]), recs[3]], states=states, fs=10.0)
    with pytest.raises(ValueError, match="^failure_times is a masked array"):
        tsfdi.fit_baselines(recs, states=states, fs=10.0, failure_times=np.ma.array([0, 0, 1, 1.0], mask=[1, 1, 0, 0]))


# ---------------------------------------------------------------------------- baselines and evaluate options
@pytest.fixture(scope="module")
def records():
    from _synthetic_fdi import FS, dataset

    recs, states, ft = dataset(2, 1500, 500, np.random.default_rng(4))
    return recs, states, ft, FS


@pytest.mark.parametrize("option, value, exc, pattern", [
    ("fit_records", True, TypeError, "^fit_records must be 'first', 'all', a positive int"),
    ("fit_records", None, TypeError, "^fit_records must be"),
    ("fit_records", 2.5, TypeError, "^fit_records must be an integer"),
    ("fit_turbulence", 3, TypeError, "^fit_turbulence must be a name"),
    ("models", 3, TypeError, "^models must be a name"),
    ("models", [], ValueError, "^models must name at least one model"),
    ("failure_times", ["a"] * 6, TypeError, "^failure_times must hold numbers"),
    ("failure_times", [np.nan, np.nan, 1.0, 1.0, np.inf, 1.0], ValueError, "^failure_times must be >= 0 s or NaN"),
    ("failure_times", [np.nan, np.nan, -1.0, 1.0, 1.0, 1.0], ValueError, "^failure_times must be >= 0 s or NaN"),
    ("failure_times", [1.0] * 5, ValueError, "^failure_times must have one entry per record"),
    ("calibrate", "yes", TypeError, "^calibrate must be True or False"),
    ("settle", 1e300, ValueError, r"^record\(s\) \[0\] of state 'healthy' end before the fitting segment"),
    ("duration", 1e-300, ValueError, "^duration: 1e-300 s is less than one sample"),
])
def test_fit_baselines_options_named(records, option, value, exc, pattern):
    recs, states, ft, fs = records
    kw = dict(states=states, failure_times=ft, fs=fs, settle=1.0, duration=None, max_lags=3, var_max_lags=3,
              steady_window="2s")
    kw[option] = value
    with pytest.raises(exc, match=pattern):
        tsfdi.fit_baselines(recs, **kw)


def test_fit_baselines_time_coordinate(records):
    recs, states, _, fs = records
    coords = {"state": ("record", states)}
    for time, exc, pattern in [(np.zeros(1500), ValueError, "time coordinate gives no sampling frequency"),
                               ([f"t{i}" for i in range(1500)], TypeError, "time coordinate must hold seconds")]:
        da = xr.DataArray(np.stack(recs), dims=("record", "time", "channel"), coords={**coords, "time": time})
        with pytest.raises(exc, match="^data's " + pattern):
            tsfdi.fit_baselines(da, max_lags=3, var_max_lags=3)
    # datetimes give the sampling frequency in seconds
    t = pd.date_range("2024-01-01", periods=1500, freq="10ms")
    da = xr.DataArray(np.stack(recs), dims=("record", "time", "channel"), coords={**coords, "time": t})
    b = tsfdi.fit_baselines(da, failure_times=[np.nan] * 2 + [5.0] * 4, settle=1.0, duration=None, max_lags=3,
                            var_max_lags=3, steady_window="2s")
    assert b.fs == pytest.approx(fs)
    # one model name as a string is that model (not its letters)
    assert list(tsfdi.fit_baselines(da, failure_times=[np.nan] * 2 + [5.0] * 4, settle=1.0, duration=None,
                                    max_lags=3, var_max_lags=3, steady_window="2s", models="var").models) == ["var"]


@pytest.fixture(scope="module")
def baselines(records):
    recs, states, ft, fs = records
    return tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=fs, settle=1.0, duration=None,
                               max_lags=3, var_max_lags=3, steady_window="2s")


@pytest.mark.parametrize("option, value, exc, pattern", [
    ("models", 3, TypeError, "^models must be a model name"),
    ("turbulence", 3, TypeError, "^turbulence must be a level name"),
    ("detection", "no", TypeError, "^detection must be True or False"),
    ("progress", "no", TypeError, "^progress must be True or False"),
    ("windows", [10 ** 9], ValueError,
     r"^windows: a 1000000000-sample window is longer than the record\(s\) \[1, 3, 5\]"),
    ("windows", ["abc"], ValueError, "^windows must be an int"),
    ("step", 0, ValueError, "^step must be >= 1"),
])
def test_evaluate_options_named(records, baselines, option, value, exc, pattern):
    recs, states, ft, fs = records
    kw = dict(states=states, failure_times=ft, fs=fs, windows=[200], step=100, progress=False)
    kw[option] = value
    with pytest.raises(exc, match=pattern):
        tsfdi.evaluate(recs, baselines, **kw)


def test_baselines_state_models_named(baselines):
    with pytest.raises(ValueError, match="^model must be one of the fitted models"):
        baselines.state_models("nope")


# ------------------------------------------------------------------------------------------ cause 8: ALFA
def _write(path, text, *, gz=False):
    path.parent.mkdir(parents=True, exist_ok=True)
    data = text.encode() if isinstance(text, str) else text
    path.write_bytes(gzip.compress(data) if gz else data)
    return path


MERGED = "%time,field.data,field.x\n2018-09-11 18:55:44.750,0,1\n2018-09-11 18:55:44.800,1,2\n"


@pytest.mark.filterwarnings("ignore:Could not infer format")
@pytest.mark.parametrize("name, content, pattern", [
    ("engine_failure.csv", "%time,field.data,field.x\n", "has a header but no rows"),
    ("engine_failure.csv", "time,label,throttle\n", "has a header but no rows"),
    ("engine_failure.csv.gz", MERGED, r"cannot be read as a CSV file \(BadGzipFile"),
    ("engine_failure.csv.gz", gzip.compress(MERGED.encode() * 50)[:40], r"cannot be read as a CSV file \(EOFError"),
    ("engine_failure.csv", "", r"is empty \(no header line\)"),
    ("engine_failure.csv", b"\x00\xff\xfe\n\x02,\"", "cannot be read as a CSV file"),
    ("engine_failure.csv", "%time,field.data\nabc,0\n", "column '%time' must hold time stamps"),
    ("engine_failure.csv", "%time,field.data\n1e30,0\n2e30,0\n", "column '%time' must hold integer time stamps"),
    ("engine_failure.csv", "%time,field.data\n2000,0\n1000,0\n", r"column '%time' is not strictly increasing"),
    ("engine_failure.csv", "%time,field.data,field.x\n1000,abc,1\n2000,0,1\n", "column 'field.data'"),
    ("engine_failure.csv", "%time,field.data\n1000,0\n", "holds 1 time stamp"),
    ("engine_failure.csv", "time,label\nxyz,True\nzzz,False\n", "column 'time' must hold time stamps"),
])
def test_load_alfa_damaged_files(tmp_path, name, content, pattern):
    path = _write(tmp_path / name, content)
    with pytest.raises(ValueError, match="^path: " + re.escape(str(path)) + r"\S* *:? *.*" + pattern):
        load_alfa(path)


def test_load_alfa_damaged_official_folder(tmp_path):
    grid = "f_engine_failure-mavros-nav_info-roll"
    cases = [
        ({f"{grid}.csv": "%time,field.commanded\n"}, grid, "has a header but no rows"),
        ({f"{grid}.csv.gz": "not gzip"}, grid, "BadGzipFile"),
        ({f"{grid}.csv": "x,y\n1,2\n"}, grid, r"has no column\(s\) \['%time'\]"),
        ({f"{grid}.csv": "%time,field.commanded\nabc,1\n"}, grid, "integer time stamps in ns"),
        ({f"{grid}.csv": "%time,field.c\n1,1\n2,2\n", "f_engine_failure-mavros-imu.csv": "field.x\n1\n"},
         "mavros-imu", "has no column '%time'"),
        ({f"{grid}.csv": "%time,field.c\n1,1\n2,2\n", "f_engine_failure-failure_status-engines.csv": "%time\nx\n"},
         "failure_status", "integer time stamps in ns"),
        ({f"{grid}.csv": "%time,field.c\n1,1\n2,2\n",
          "f_engine_failure-failure_status-engines.csv": "%time,field.data\n1,x\n"}, "failure_status", "field.data"),
    ]
    for k, (files, culprit, pattern) in enumerate(cases):
        folder = tmp_path / f"flight{k}"
        for name, text in files.items():
            _write(folder / name, text)
        with pytest.raises(ValueError, match=rf"^path: .*{culprit}.*{pattern}"):
            load_alfa(folder)


def test_load_alfa_still_reads_a_small_valid_file(tmp_path):
    df = load_alfa(_write(tmp_path / "engine_failure_1.csv", MERGED))
    assert df.attrs["fault"] == "engine" and df.attrs["onset_s"] == pytest.approx(0.05)
    assert df.attrs["fs"] == pytest.approx(20.0) and df["ground_truth"].tolist() == [False, True]


def test_list_alfa_damaged_table(tmp_path):
    _write(tmp_path / "a" / "flights.csv", "x,y\n1,2\n")
    with pytest.raises(ValueError, match=r"^root: .*flights\.csv has no column\(s\) \['folder', 'flight'\]"):
        list_alfa(tmp_path / "a")
    _write(tmp_path / "b" / "flights.csv", "")
    with pytest.raises(ValueError, match=r"^root: .*flights\.csv is empty"):
        list_alfa(tmp_path / "b")
    with pytest.raises(TypeError, match="^root must be a str"):
        list_alfa(3)


def test_crazypad_error_paths(tmp_path):
    log = tmp_path / "controller" / "normal_flight"
    big = _write(log / "E8_log00.csv", "timestamp,controller.cmd_thrust\n1,1\n1e300,1\n")
    with pytest.raises(ValueError, match=r"^file: .*E8_log00\.csv: column 'timestamp' spans"):
        read_crazypad_log(big)
    ok = _write(log / "E8_log00.csv", "timestamp,controller.cmd_thrust\n0,1\n10,1\n20,1\n")
    with pytest.raises(TypeError, match="^airborne must be True or False"):
        read_crazypad_log(ok, airborne="no")
    with pytest.raises(TypeError, match="^airborne must be True or False"):
        tsfdi.datasets.load_crazypad(tmp_path, airborne=1)
    _write(log / "E8_log01.csv.gz", "timestamp\n1\n")
    with pytest.raises(ValueError, match=r"^file: .*E8_log01\.csv\.gz cannot be read as a CSV file \(BadGzipFile"):
        list_crazypad(tmp_path)


# -------------------------------------------------------------------------------------------- command line
@pytest.fixture(scope="module")
def cli_files(tmp_path_factory):
    """Data and model files of every kind the command line refuses, beside valid ones."""
    from _synthetic_fdi import FS, record

    d = tmp_path_factory.mktemp("cli")
    x = record("healthy", 500, np.random.default_rng(1))
    ok = pd.DataFrame({"time": np.arange(500) / FS, "a": x[:, 0], "b": x[:, 1]})
    ok.to_csv(d / "ok.csv", index=False)
    assert main(["fit", str(d / "ok.csv"), "--columns", "a", "--out", str(d / "m.npz"), "--max-lags", "3"]) == 0
    assert main(["fit", str(d / "ok.csv"), "--out", str(d / "m2.npz"), "--max-lags", "3"]) == 0
    (d / "sub").mkdir()
    (d / "sub" / "m.npz").write_bytes((d / "m.npz").read_bytes())
    (d / "truncated.npz").write_bytes((d / "m.npz").read_bytes()[:300])
    np.savez(d / "foreign.npz", weights=np.arange(3.0))
    np.savez(d / "pickled.npz", weights=np.array([{"w": 1}], dtype=object))
    ok.assign(label="x").to_csv(d / "text_column.csv", index=False)
    ok.assign(b=ok["b"].where(ok.index != 37)).to_csv(d / "nan.csv", index=False)
    ok.iloc[:10].to_csv(d / "short.csv", index=False)
    ok.assign(time=np.r_[ok["time"][:250], ok["time"][250:] + 1.0]).to_csv(d / "gap.csv", index=False)
    ok.drop(columns="time").to_csv(d / "no_time.csv", index=False)
    values = np.stack([x, x[::-1], x + 1.0])
    values[1, 40, 1] = np.nan
    xr.Dataset({"a": (("record", "time"), values[..., 0]), "b": (("record", "time"), values[..., 1])},
               coords={"time": np.arange(500) / FS, "state": ("record", ["healthy", "healthy", "f1"])}).to_netcdf(
        d / "records.nc", engine="h5netcdf")
    files = {"empty.csv": "", "header.csv": "time,a\n", "text.csv": "time,a\n0,x\n0.01,y\n",
             "same_time.csv": "time,a\n0,1\n0,2\n0,3\n", "fake.nc": "not netcdf", "fake.csv.gz": "not gzip",
             "time_text.csv": "time,a\nt0,1\nt1,2\n", "bad.npz": "junk", "notes.txt": "a text file"}
    for name, text in files.items():
        (d / name).write_text(text)
    return d


FIT = ["fit", "--out", "{d}/x.npz", "--max-lags", "3"]
DETECT = ["detect", "{d}/ok.csv", "--baseline", "{d}/m2.npz"]


@pytest.mark.parametrize("argv, named", [
    # missing files
    (["fit", "{d}/missing.csv", "--out", "{d}/x.npz"], ["missing.csv", "does not exist"]),
    (["detect", "{d}/ok.csv", "--baseline", "{d}/nope.npz"], ["--baseline", "nope.npz", "does not exist"]),
    (["identify", "{d}/ok.csv", "--models", "{d}/m.npz", "{d}/gone.npz"], ["--models", "gone.npz"]),
    (["demo", "--data", "{d}/gone.nc", "--no-figures", "--no-progress"], ["--data", "gone.nc", "does not exist"]),
    (["fit", "{d}", "--out", "{d}/x.npz"], ["is a folder"]),
    # missing / wrong columns
    ([*FIT, "{d}/ok.csv", "--columns", "accel_z"], ["--columns", "ok.csv", "'accel_z'", "['a', 'b']"]),
    ([*FIT, "{d}/ok.csv", "--columns", "a,a"], ["--columns", "named twice", "['a', 'a']"]),
    ([*FIT, "{d}/records.nc", "--record", "0", "--columns", "c"], ["--columns", "records.nc", "'c'", "['a', 'b']"]),
    ([*DETECT, "--columns", "a"], ["--columns", "ok.csv", "['a']", "--baseline", "m2.npz", "2 channel(s)"]),
    ([*FIT, "{d}/ok.csv", "--time-column", "clock"], ["--time-column", "ok.csv", "'clock'"]),
    ([*FIT, "{d}/ok.csv", "--model", "ar"], ["--model ar", "one column", "--columns"]),
    # no time, a time column with a gap, disagreeing --fs
    ([*FIT, "{d}/no_time.csv"], ["no_time.csv", "--time-column", "--fs"]),
    ([*FIT, "{d}/gap.csv"], ["gap.csv", "column 'time'", "gap of 1.01 s after line 251", "--resample", "--start / --stop"]),
    ([*FIT, "{d}/ok.csv", "--fs", "50"], ["--fs 50", "ok.csv", "100 Hz"]),
    ([*FIT, "{d}/same_time.csv"], ["same_time.csv", "column 'time'", "not strictly increasing", "line 3"]),
    ([*FIT, "{d}/time_text.csv"], ["time_text.csv", "column 'time'", "line 2", "'t0'"]),
    # NaN: the file, the column, where, and what to do
    ([*FIT, "{d}/nan.csv"], ["nan.csv", "column 'b'", "line 39", "time 0.37 s", "--nan-policy omit", "--columns"]),
    ([*FIT, "{d}/records.nc", "--record", "1"], ["record 1 of", "records.nc", "variable 'b'", "time 0.4 s"]),
    # too short
    ([*FIT, "{d}/short.csv", "--max-lags", "20"], ["short.csv", "too short", "10 samples", "--max-lags 20"]),
    ([*FIT, "{d}/ok.csv", "--start", "495"], ["ok.csv", "too short", "--max-lags 3"]),
    ([*FIT, "{d}/ok.csv", "--start", "3s", "--stop", "1s"], ["--stop", "--start"]),
    ([*FIT, "{d}/ok.csv", "--start", "10s"], ["--start / --stop", "ok.csv", "no row"]),
    ([*DETECT, "--window", "4"], ["--window 4", "4 samples = 0.04 s", "order"]),
    # non-numeric
    ([*FIT, "{d}/text.csv"], ["text.csv", "column 'a'", "not numeric", "line 2", "'x'"]),
    ([*FIT, "{d}/text_column.csv", "--columns", "a,label"], ["text_column.csv", "column 'label'", "not numeric"]),
    # bad --window / --step
    ([*DETECT, "--window", "0"], ["--window"]), ([*DETECT, "--window", "abc"], ["--window", "'abc'"]),
    ([*DETECT, "--window", "2.5"], ["--window", "'2.5s'", "samples"]), ([*DETECT, "--window", "inf"], ["--window"]),
    ([*DETECT, "--window", "1e300"], ["--window"]), ([*DETECT, "--window=-2s"], ["--window", "> 0"]),
    ([*DETECT, "--window", "100s"], ["--window 100s", "10000 samples = 100 s", "longer than", "ok.csv"]),
    ([*DETECT, "--window", "2s", "--step", "-1"], ["--step"]),
    ([*DETECT, "--window", "2s", "--step", "0.1ms"], ["--step", "0.1ms", "0 sample"]),
    (["monitor", "{d}/ok.csv", "--baseline", "{d}/m2.npz"], ["--window"]),
    (["monitor", "{d}/ok.csv", "--baseline", "{d}/m2.npz", "--window", "1s", "--steady-window", "1ms"],
     ["--steady-window"]),
    # output folder that does not exist: refused before any work
    ([*FIT, "{d}/ok.csv", "--out", "{d}/no/such/dir/x.npz"], ["--out", "no/such/dir"]),
    ([*DETECT, "--out", "{d}/no/dir/t.csv"], ["--out", "no/dir"]),
    (["identify", "{d}/ok.csv", "--models", "{d}/m2.npz", "--out", "{d}/no/dir/t.csv"], ["--out", "no/dir"]),
    (["select-order", "{d}/ok.csv", "--out", "{d}/no/dir/t.csv"], ["--out", "no/dir"]),
    (["monitor", "{d}/ok.csv", "--baseline", "{d}/m2.npz", "--window", "1s", "--out", "{d}/no/dir/e.csv"],
     ["--out", "no/dir"]),
    (["simulate", "--out", "{d}/no/dir/s.nc", "--records-per-case", "1", "--duration", "0.5s"], ["--out", "no/dir"]),
    # foreign or corrupt model files
    ([*DETECT[:2], "--baseline", "{d}/foreign.npz"], ["--baseline", "foreign.npz", "not a tsfdi"]),
    ([*DETECT[:2], "--baseline", "{d}/pickled.npz"], ["--baseline", "pickled.npz", "not a tsfdi"]),
    ([*DETECT[:2], "--baseline", "{d}/notes.txt"], ["--baseline", "notes.txt", "not a tsfdi"]),
    ([*DETECT[:2], "--baseline", "{d}/truncated.npz"], ["--baseline", "truncated.npz"]),
    ([*DETECT[:2], "--baseline", "{d}/ok.csv"], ["--baseline", "ok.csv", "not a tsfdi"]),
    (["identify", "{d}/ok.csv", "--models", "{d}/bad.npz"], ["--models", "bad.npz"]),
    (["monitor", "{d}/ok.csv", "--baseline", "{d}/m2.npz", "--models", "f={d}/notes.txt", "--window", "1s"],
     ["--models f=", "notes.txt"]),
    # duplicate model names
    (["identify", "{d}/ok.csv", "--models", "h={d}/m.npz", "h={d}/sub/m.npz"], ["--models", "'h'", "twice"]),
    (["identify", "{d}/ok.csv", "--models", "{d}/m.npz", "{d}/sub/m.npz"], ["--models", "'m'", "twice", "NAME=PATH"]),
    (["monitor", "{d}/ok.csv", "--baseline", "{d}/m2.npz", "--models", "f={d}/m2.npz", "f={d}/m2.npz", "--window",
      "1s"], ["--models", "'f'", "twice"]),
    # netCDF records
    ([*FIT, "{d}/records.nc"], ["records.nc", "3 records", "--record", "--where", "state: f1, healthy"]),
    ([*DETECT, "--record", "0"], ["--record", "ok.csv"]),
    (["detect", "{d}/records.nc", "--baseline", "{d}/m2.npz", "--record", "7"], ["--record 7", "records.nc", "0..2"]),
    (["detect", "{d}/records.nc", "--baseline", "{d}/m2.npz", "--record", "x"], ["--record", "'x'"]),
    (["detect", "{d}/records.nc", "--baseline", "{d}/m2.npz", "--where", "state=f9"],
     ["--where state=f9", "records.nc", "['f1', 'healthy']"]),
    (["detect", "{d}/records.nc", "--baseline", "{d}/m2.npz", "--where", "colour=red"], ["--where colour", "'state'"]),
    (["detect", "{d}/records.nc", "--baseline", "{d}/m2.npz", "--where", "state"], ["--where", "KEY=VALUE"]),
    # flag values
    ([*FIT, "{d}/ok.csv", "--max-lags", "0"], ["--max-lags"]),
    ([*FIT, "{d}/ok.csv", "--max-lags", "abc"], ["--max-lags"]),
    ([*FIT, "{d}/ok.csv", "--lags", "0"], ["--lags"]), ([*FIT, "{d}/ok.csv", "--lags", "30"], ["--lags 30"]),
    ([*FIT, "{d}/ok.csv", "--fs", "0"], ["--fs"]), ([*FIT, "{d}/ok.csv", "--fs", "nan"], ["--fs"]),
    ([*FIT, "{d}/ok.csv", "--start", "inf"], ["--start"]),
    ([*FIT, "{d}/ok.csv", "--start", "1.5"], ["--start", "'1.5s'"]),
    ([*DETECT, "--alpha", "1"], ["--alpha"]),
    # unreadable data files
    ([*FIT, "{d}/empty.csv"], ["empty.csv"]), ([*FIT, "{d}/header.csv"], ["header.csv"]),
    ([*FIT, "{d}/fake.nc"], ["fake.nc", "netCDF"]), ([*FIT, "{d}/fake.csv.gz"], ["fake.csv.gz"]),
    # simulate and demo
    (["simulate", "--out", "{d}/s.nc", "--records-per-case", "0"], ["--records-per-case"]),
    (["simulate", "--out", "{d}/s.nc", "--duration", "nan"], ["--duration"]),
    (["simulate", "--out", "{d}/s.nc", "--duration", "60"], ["--duration", "'60s'"]),
    (["simulate", "--out", "{d}/s.nc", "--seed", "-1"], ["--seed"]),
    (["demo", "--windows", "abc"], ["--windows"]), (["demo", "--order", "xyz"], ["--order"]),
    (["demo", "--data", "{d}/fake.nc", "--no-figures", "--no-progress"], ["--data", "fake.nc"]),
])
def test_cli_errors_exit_2_naming_what_the_user_typed(cli_files, capsys, argv, named):
    rc = main([a.format(d=cli_files) for a in argv])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("usage: tsfdi ") and f"tsfdi {argv[0]}: error: " in err, err
    for word in named:
        assert word.format(d=cli_files) in err, (word, err)
    assert "Traceback" not in err


def test_a_negative_seed_is_refused_naming_rng(fits):
    """Issue 29, item 11: simulate(rng=-1) passed numpy's 'expected non-negative integer' through."""
    from tsfdi.datasets import DrydenTurbulence, dryden_turbulence
    from tsfdi.datasets.faults import inject_fault

    calls = [lambda: fits["ar"].simulate(50, rng=-1), lambda: fits["var"].simulate(50, rng=-1),
             lambda: fits["arx"].simulate(U, rng=-1), lambda: DrydenTurbulence().simulate(50, 0.01, rng=-1),
             lambda: dryden_turbulence(1.0, 100.0, rng=-1), lambda: inject_fault(Y, "noise", 0.1, 10, rng=-1),
             lambda: tsfdi.datasets.simulate_hexacopter(1, duration=1.0, seed=-1)]
    for call in calls:
        with pytest.raises(ValueError, match=r"^(rng must be None, a non-negative int seed or a numpy.random.Generator, "
                                             r"got -1|seed must be >= 0, got -1)$"):
            call()
    assert fits["ar"].simulate(5, rng=np.int64(0)).shape == (5,)


def test_a_stream_sample_of_numbers_written_as_text_is_refused():
    """Issue 29, item 4, for the streaming path: ``update(["1.5", "2"])`` parsed the text as numbers."""
    from tsfdi._validation import sample_vector

    for value in (["1.5", "2"], np.array(["1.5", "2"]), np.array(["1.5", 2.0], dtype=object), [b"1", b"2"]):
        with pytest.raises(TypeError, match=r"x must be a number or one number per channel, got"):
            sample_vector(value, 2)
    assert sample_vector(np.array([1, 2.5], dtype=object), 2).tolist() == [1.0, 2.5]

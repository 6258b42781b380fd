"""tsfdi.read_records: every format the command line reads gives the same records in Python and through the CLI,
and read_records' own behaviour and errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import tsfdi
from tsfdi._data import RESAMPLE_FIX, time_step
from tsfdi.cli import main

DATA = Path(__file__).resolve().parents[1] / "data"
CRAZYPAD = DATA / "crazypad" / "controller" / "normal_flight" / "E8_log00.csv.gz"
ALFA = DATA / "alfa" / "engine_commanded_measured" / "carbonZ_2018-07-18-15-53-31_1_engine_failure.csv.gz"
ULOG = DATA / "px4" / "sample.ulg"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """One two-channel record at 50 Hz from 100 s written with each time form, a netCDF file of three records, a
    folder of two per-topic CSV files (20 Hz and 50 Hz, in ns), and a CSV with a NaN and a 'thrust' column."""
    d = tmp_path_factory.mktemp("io")
    rng = np.random.default_rng(11)
    n = 1000
    x = rng.standard_normal((n, 2)).cumsum(axis=0) * 0.1
    t = 100.0 + np.arange(n) / 50
    df = pd.DataFrame({"timestamp": t, "a": x[:, 0], "b": x[:, 1]})
    df.to_csv(d / "seconds.csv", index=False)
    df.assign(timestamp=np.round(t * 1000, 6)).to_csv(d / "ms.csv", index=False)
    stamps = pd.Timestamp("2018-09-11 18:46:35.350") + pd.to_timedelta(t - 100.0, unit="s")
    df.assign(timestamp=stamps.strftime("%Y-%m-%d %H:%M:%S.%f")).rename(columns={"timestamp": "%time"}).to_csv(
        d / "dated.csv", index=False)
    elapsed = pd.to_timedelta(t - 40.0, unit="s")          # 00:01:00 onwards
    df.assign(timestamp=[f"{str(e).split(' days ')[-1]}" for e in elapsed]).rename(
        columns={"timestamp": "time"}).to_csv(d / "elapsed.csv", index=False)
    thrust = np.zeros(n)
    thrust[100:450], thrust[600:900] = 1.0, 2.0
    gappy = df.assign(thrust=thrust)
    gappy.loc[300, "b"] = np.nan
    gappy.to_csv(d / "flight.csv", index=False)
    ds = xr.Dataset({"roll": (("record", "time"), rng.standard_normal((3, 400))),
                     "pitch": (("record", "time"), rng.standard_normal((3, 400)))},
                    coords={"time": np.arange(400) / 100, "record": [0, 1, 2],
                            "state": ("record", ["healthy", "healthy", "rotor1"]),
                            "turbulence": ("record", ["light", "severe", "light"])})
    ds.to_netcdf(d / "sim.nc", engine="h5netcdf")
    topics = d / "flight_topics"
    topics.mkdir()
    ns = (1_531_943_810 * 10**9 + np.arange(0, 30 * 10**9, 50_000_000)).astype(np.int64)    # 30 s at 20 Hz
    pd.DataFrame({"%time": ns, "field.roll": np.sin(np.arange(ns.size) / 7), "field.frame": "base"}).to_csv(
        topics / "flight-mavros-nav_info-roll.csv", index=False)
    ns2 = (ns[0] + 3_000_000 + np.arange(0, 30 * 10**9, 20_000_000)).astype(np.int64)        # 50 Hz
    pd.DataFrame({"%time": ns2, "field.x": np.cos(np.arange(ns2.size) / 11)}).to_csv(
        topics / "flight-mavros-imu-data.csv", index=False)
    return d, df


def fitted_records(tmp_path, argv):
    """The records `tsfdi fit` fits on (stored in the model file): values and time index of each."""
    out = tmp_path / "m.npz"
    assert main(["fit", *map(str, argv), "--lags", "1", "--max-lags", "1", "--quiet", "--out", str(out)]) == 0
    return [(r.values, np.asarray(r.index, dtype=np.float64)) for r in tsfdi.load(out).model.records]


def assert_same(cli, rec):
    assert len(cli) == len(rec.values) > 0
    for (values, index), v, t in zip(cli, rec.values, rec.times):
        np.testing.assert_array_equal(values, v)
        np.testing.assert_array_equal(index, t)


# ------------------------------------------------------------------------------------- CLI and Python agree
@pytest.mark.parametrize("name, argv, kwargs", [
    ("seconds.csv", [], {}),
    ("ms.csv", ["--time-unit", "ms", "--start", "110s"], {"time_unit": "ms", "start": "110s"}),
    ("dated.csv", ["--stop", "500"], {"stop": 500}),
    ("elapsed.csv", ["--columns", "b,a"], {"columns": ["b", "a"]}),
    ("flight.csv", ["--columns", "a,b", "--rows-where", "thrust>0", "--margin", "1s", "--nan-policy", "omit"],
     {"columns": "a,b", "rows_where": "thrust>0", "margin": 1.0, "nan_policy": "omit"}),
])
def test_cli_and_python_give_the_same_csv_records(files, tmp_path, name, argv, kwargs):
    d, df = files
    assert_same(fitted_records(tmp_path, [d / name, *argv]), tsfdi.read_records(d / name, **kwargs))


def test_cli_and_python_give_the_same_netcdf_records(files, tmp_path):
    d, _ = files
    rec = tsfdi.read_records(d / "sim.nc", where={"state": "healthy"}, columns=["roll", "pitch"])
    assert_same(fitted_records(tmp_path, [d / "sim.nc", "--where", "state=healthy", "--columns", "roll,pitch"]), rec)
    assert rec.ids.tolist() == ["0", "1"] and rec.state.tolist() == ["healthy"] * 2
    assert rec.turbulence.tolist() == ["light", "severe"] and rec.fs == pytest.approx(100.0)
    assert_same(fitted_records(tmp_path, [d / "sim.nc", "--record", "2", "--start", "1s"]),
                tsfdi.read_records(d / "sim.nc", records=[2], start=1.0))


def test_cli_and_python_give_the_same_topic_folder_records(files, tmp_path):
    d, _ = files
    kwargs = dict(topics=["nav_info-roll", "imu-data"], time_unit="ns", fs=20)
    rec = tsfdi.read_records(d / "flight_topics", **kwargs)
    assert rec.channels == ("nav_info-roll.field.roll", "imu-data.field.x") and rec.fs == 20.0
    assert rec.files.tolist() == [str(d / "flight_topics")] and rec.ids.tolist() == [""]
    assert_same(fitted_records(tmp_path, [d / "flight_topics", "--topics", "nav_info-roll,imu-data",
                                          "--time-unit", "ns", "--fs", "20"]), rec)


def test_cli_and_python_give_the_same_records_on_shipped_samples(tmp_path):
    """The CrazyPAD log (ms, airborne runs), the ALFA flight put on a 20 Hz grid, and the PX4 log."""
    cols = "controller.r_roll,controller.r_pitch"
    rec = tsfdi.read_records(CRAZYPAD, time_unit="ms", columns=cols, rows_where="controller.cmd_thrust>0",
                             margin="1s")
    assert [v.shape for v in rec.values] == [(665, 2), (730, 2)] and rec.ids.tolist() == ["0", "1"]
    assert_same(fitted_records(tmp_path, [CRAZYPAD, "--time-unit", "ms", "--columns", cols, "--rows-where",
                                          "controller.cmd_thrust>0", "--margin", "1s"]), rec)
    rec = tsfdi.read_records(ALFA, columns=["roll_measured", "roll_commanded"], resample=True, fs=20)
    assert_same(fitted_records(tmp_path, [ALFA, "--columns", "roll_measured,roll_commanded", "--resample", "--fs",
                                          "20"]), rec)
    pytest.importorskip("pyulog")
    gyro = [f"sensor_combined.gyro_rad[{i}]" for i in range(3)]
    rec = tsfdi.read_records(ULOG, topics="sensor_combined", fs=50, columns=gyro, start="12s", stop="26s")
    assert rec.channels == tuple(gyro) and rec.fs == 50.0
    assert_same(fitted_records(tmp_path, [ULOG, "--topics", "sensor_combined", "--fs", "50", "--columns",
                                          ",".join(gyro), "--start", "12s", "--stop", "26s"]), rec)


# ------------------------------------------------------------------------------------ read_records itself
def test_records_carry_times_files_and_names(files):
    d, df = files
    rec = tsfdi.read_records([d / "seconds.csv", d / "dated.csv"])
    assert rec.channels == ("a", "b") and rec.fs == pytest.approx(50.0)
    assert rec.files.tolist() == [str(d / "seconds.csv"), str(d / "dated.csv")] and rec.ids.tolist() == ["", ""]
    np.testing.assert_array_equal(rec.times[0], df["timestamp"])
    np.testing.assert_allclose(rec.times[1], df["timestamp"] - 100.0, atol=1e-9)   # dates: seconds from row 1
    frames = rec.frames()
    assert frames[0].index.name == "time" and list(frames[0].columns) == ["a", "b"]
    np.testing.assert_array_equal(frames[0].to_numpy(), df[["a", "b"]].to_numpy())
    np.testing.assert_allclose(tsfdi.read_records(d / "elapsed.csv").times[0], df["timestamp"] - 40.0, atol=1e-9)
    # the pieces of --nan-policy omit and --rows-where are named by number
    rec = tsfdi.read_records(d / "flight.csv", columns="a,b", nan_policy="omit")
    assert rec.ids.tolist() == ["0", "1"] and [len(v) for v in rec.values] == [300, 699]
    sub = rec.read([1])
    assert sub.ids.tolist() == ["1"] and sub.times[0][0] == df["timestamp"][301]


def test_one_even_sampling_rule(files, tmp_path):
    """A jitter the CLI accepted (within 50 %) is refused with the words of tsfdi._data.time_step (10 %), and the
    fix (resample) works."""
    d, df = files
    t = df["timestamp"].to_numpy().copy()
    t[500] += 0.006                                        # a 30 % jitter at one row
    df.assign(timestamp=t).to_csv(tmp_path / "jitter.csv", index=False)
    with pytest.raises(ValueError) as exc:
        tsfdi.read_records(tmp_path / "jitter.csv")
    with pytest.raises(ValueError) as rule:
        time_step(pd.Index(t), f"{tmp_path / 'jitter.csv'}: column 'timestamp'", numeric=True)
    # the same words, with the CSV line (header = line 1) for the sample and read_records' own fix
    words = str(rule.value).replace("; " + RESAMPLE_FIX, "").replace("after sample 499", "after line 501")
    assert str(exc.value).startswith(words) and "within 10% of it" in words, (words, str(exc.value))
    assert "resample=True with fs=RATE" in str(exc.value) and "tsfdi.align" not in str(exc.value)
    assert len(tsfdi.read_records(tmp_path / "jitter.csv", resample=True, fs=50).values) >= 1
    assert main(["fit", str(tmp_path / "jitter.csv"), "--out", str(tmp_path / "m.npz")]) == 2


def test_errors_name_the_keyword_file_and_column(files, tmp_path):
    d, _ = files
    cases = [
        (dict(paths=d / "missing.csv"), ValueError, "missing.csv does not exist"),
        (dict(paths=d / "seconds.csv", columns="a,z"), ValueError, "columns: " + str(d / "seconds.csv")
         + " has no column 'z'"),
        (dict(paths=d / "seconds.csv", time="clock"), ValueError, "time: " + str(d / "seconds.csv")
         + " has no column 'clock'"),
        (dict(paths=d / "seconds.csv", time_unit="min"), ValueError, "time_unit must be one of"),
        (dict(paths=d / "dated.csv", time_unit="ms"), ValueError, "dates and times need no unit"),
        (dict(paths=d / "seconds.csv", fs=51), ValueError, "fs=51: the column 'timestamp'"),
        (dict(paths=d / "seconds.csv", fs=True), TypeError, "fs must be a number"),
        (dict(paths=d / "seconds.csv", margin="1s"), ValueError, "margin trims the runs of rows_where"),
        (dict(paths=d / "seconds.csv", rows_where="a~0"), ValueError, "must be COLUMN OP NUMBER"),
        (dict(paths=d / "seconds.csv", rows_where="lift>0"), ValueError, "has no numeric column 'lift'"),
        (dict(paths=d / "seconds.csv", start="110s", stop="105s"), ValueError, "stop must come after start"),
        (dict(paths=d / "seconds.csv", start=[1]), TypeError, "start must be a row number"),
        (dict(paths=d / "seconds.csv", records=[1]), ValueError, "records selects records of a netCDF file"),
        (dict(paths=d / "seconds.csv", topics="x"), ValueError, "topics is for PX4 flight logs"),
        (dict(paths=d / "flight.csv", columns="a,b"), ValueError, "column 'b' holds 1 empty, NaN or infinite value(s), "
         "the first at line 302"),
        (dict(paths=d / "sim.nc", where={"state": "rotor9"}), ValueError, "where state=rotor9: no selected record"),
        (dict(paths=d / "sim.nc", records=7), ValueError, "has no record 7"),
        (dict(paths=d / "sim.nc", time_unit="ms"), ValueError, "time_unit is for CSV files"),
        (dict(paths=d / "flight_topics", fs=20), ValueError, "topics: " + str(d / "flight_topics")),
        (dict(paths=d / "flight_topics", topics="gps", fs=20), ValueError, "has no topic 'gps'; its topics are "
         "['imu-data', 'nav_info-roll']"),
        (dict(paths=d / "flight_topics", topics="imu-data", fs=20), ValueError, "time_unit='ns'"),
        (dict(paths=[d / "seconds.csv", d / "seconds.csv"]), ValueError, "is given twice"),
        (dict(paths=[d / "seconds.csv", d / "sim.nc"], columns="a"), ValueError, "has no variable 'a'"),
        (dict(paths=42), TypeError, "paths must be a file name"),
    ]
    for kwargs, kind, words in cases:
        with pytest.raises(kind) as exc:
            tsfdi.read_records(**kwargs)
        assert words in str(exc.value), (kwargs, str(exc.value))


def test_a_missing_pyulog_says_how_to_install(monkeypatch, tmp_path, capsys):
    import sys

    monkeypatch.setitem(sys.modules, "pyulog", None)
    with pytest.raises(ImportError, match=r"pip install tsfdi\[px4\]"):
        tsfdi.read_records(ULOG, topics="sensor_combined", fs=50)
    # the CLI: one line, exit status 2 (it was a 25-line traceback)
    assert main(["fit", str(ULOG), "--topics", "sensor_combined", "--fs", "50", "--out", str(tmp_path / "m.npz")]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [f"tsfdi fit: error: reading a PX4 flight log (.ulg) needs the pyulog package: "
                                        "pip install tsfdi[px4]"]


def test_require_choice_lists_a_netcdf_files_records_in_python_and_in_the_cli(files, tmp_path, capsys):
    """A caller pooling records into one model (fit / select-order) must choose among a netCDF file's records; the
    message lists the per-record coordinates, in keywords for Python and in flags for the command line."""
    d, _ = files
    with pytest.raises(ValueError) as exc:
        tsfdi.read_records(d / "sim.nc", require_choice=True)
    assert str(exc.value) == (f"{d / 'sim.nc'} holds 3 records: choose the ones to use with records=N[,N...] or "
                              "where KEY=VALUE (state: healthy, rotor1; turbulence: light, severe)")
    assert len(tsfdi.read_records(d / "sim.nc").values) == 3                  # default: every record
    assert len(tsfdi.read_records(d / "sim.nc", records=[2], require_choice=True).values) == 1
    assert len(tsfdi.read_records(d / "sim.nc", where={"state": "healthy"}, require_choice=True).values) == 2
    assert len(tsfdi.read_records(d / "seconds.csv", require_choice=True).values) == 1
    with pytest.raises(TypeError, match="require_choice must be True or False"):
        tsfdi.read_records(d / "sim.nc", require_choice="yes")
    for cmd in ("fit", "select-order"):
        assert main([cmd, str(d / "sim.nc"), "--out", str(tmp_path / "m.npz")]) == 2
        assert (f"tsfdi {cmd}: error: {d / 'sim.nc'} holds 3 records: choose the ones to use with --record N[,N...] "
                "or --where KEY=VALUE (state: healthy, rotor1; turbulence: light, severe)") in capsys.readouterr().err

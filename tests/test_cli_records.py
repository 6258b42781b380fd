"""`tsfdi` on its own netCDF output and on CSV files with a time column: record selection, pooled fits,
select-order / detect / identify / monitor equal to the library calls, time spans, --help defaults, --version."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from _synthetic_fdi import record

import tsfdi
from tsfdi.cli import COMMANDS, main
from tsfdi.windows import ResidualWindows

COLUMNS = ["roll", "pitch"]


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    """A tiny `tsfdi simulate` file (records 0, 1 healthy; 2, 3 rotor 1 failing at 1 s; 4 s at 100 Hz), a healthy
    VAR fitted on records 0 and 1 and a rotor-1 VAR on the post-failure part of records 2 and 3."""
    d = tmp_path_factory.mktemp("sim")
    nc = d / "sim.nc"
    assert main(["simulate", "--out", str(nc), "--records-per-case", "2", "--duration", "4s", "--failure-time", "1s",
                 "--states", "healthy,rotor1", "--turbulence", "light", "--seed", "5"]) == 0
    assert main(["fit", str(nc), "--where", "state=healthy", "--columns", "roll,pitch", "--max-lags", "8", "--out",
                 str(d / "healthy.npz")]) == 0
    assert main(["fit", str(nc), "--where", "state=rotor1", "--start", "1500ms", "--columns", "roll,pitch",
                 "--max-lags", "8", "--out", str(d / "rotor1.npz")]) == 0
    with xr.open_dataset(nc, engine="h5netcdf") as ds:
        ds = ds.load()
    return d, nc, ds


def frame(ds, i: int, columns=COLUMNS) -> pd.DataFrame:
    """Record ``i`` of the simulated Dataset as the command line reads it."""
    return pd.DataFrame({c: ds[c].values[i] for c in columns}, index=pd.Index(ds["time"].values, name="time"))


def test_monitor_steady_window_changes_the_events(sim, capsys):
    """Regression: --steady-window 1s, 50 and 200 gave byte-identical output (the steady-state thresholds were never
    passed to Monitor); now identification waits for the rolling variance over that window."""
    d, nc, ds = sim
    printed = []
    for v in ("1s", "50", "200"):
        assert main(["monitor", str(nc), "--record", "3", "--baseline", str(d / "healthy.npz"), "--models",
                     f"rotor1={d / 'rotor1.npz'}", "--window", "1s", "--step", "20", "--steady-window", v]) == 0
        printed.append(capsys.readouterr().out)
    assert printed[0] != printed[1] != printed[2] and "steady" in printed[1]
    assert main(["monitor", str(nc), "--record", "3", "--baseline", str(d / "healthy.npz"), "--models",
                 f"rotor1={d / 'rotor1.npz'}", "--window", "1s", "--steady-window", "10s"]) == 2
    assert "--steady-window (1000 samples (10 s)) is longer than every record the fault model 'rotor1' was fitted on " \
           "(at most" in capsys.readouterr().err


def test_fit_pools_the_selected_records(sim, capsys):
    d, nc, ds = sim
    capsys.readouterr()
    assert main(["fit", str(nc), "--where", "state=healthy", "--columns", "roll,pitch", "--max-lags", "8", "--out",
                 str(d / "h2.npz")]) == 0
    out = capsys.readouterr().out
    assert "on ['roll', 'pitch'] from 2 record(s) at 100 Hz" in out and "VAR results" in out
    res = tsfdi.load(d / "h2.npz")
    ref = tsfdi.select_order([frame(ds, 0), frame(ds, 1)], 8, "var").fit()
    assert res.model.multi and res.lags == ref.lags and res.nobs == ref.nobs == 2 * (400 - 8)
    np.testing.assert_array_equal(np.asarray(res.params), np.asarray(ref.params))
    # the same records chosen by number, by a numeric coordinate, and by two conditions
    for sel in (["--record", "0,1"], ["--record", "0", "--record", "1"], ["--where", "failed_rotor=0"],
                ["--where", "state=healthy,rotor9", "--where", "turbulence=light"]):
        assert main(["fit", str(nc), *sel, "--columns", "roll,pitch", "--max-lags", "8", "--out",
                     str(d / "h3.npz")]) == 0
        np.testing.assert_array_equal(np.asarray(tsfdi.load(d / "h3.npz").params), np.asarray(ref.params))


def test_select_order_prints_the_table(sim, capsys):
    d, nc, ds = sim
    out = d / "order.csv"
    assert main(["select-order", str(nc), "--record", "0", "--columns", "roll", "--max-lags", "6", "--out",
                 str(out)]) == 0
    printed = capsys.readouterr().out
    sel = tsfdi.select_order(frame(ds, 0, ["roll"])["roll"], 6)
    assert str(sel.summary()) in printed and "AR on ['roll'] from 1 record(s) at 100 Hz" in printed
    table = pd.read_csv(out)
    assert list(table["order"]) == list(range(1, 7))
    np.testing.assert_allclose(table[["bic", "aic", "rss_sss", "spp"]], sel.table[["bic", "aic", "rss_sss", "spp"]],
                               rtol=1e-12)
    assert main(["select-order", str(nc), "--record", "0", "--columns", "roll,pitch", "--max-lags", "4",
                 "--criterion", "trace"]) == 0
    trace = tsfdi.select_order(frame(ds, 0), 4, "var", criterion="trace")
    assert str(trace.summary()) in capsys.readouterr().out


def test_detect_whole_records_and_windows(sim, capsys):
    d, nc, ds = sim
    healthy = tsfdi.load(d / "healthy.npz")
    out = d / "detect.csv"
    capsys.readouterr()
    assert main(["detect", str(nc), "--baseline", str(d / "healthy.npz"), "--record", "1,2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "sim.nc record 1 (400 samples = 4 s at 100 Hz" in printed and "LjungBox decision" in printed
    t = pd.read_csv(out)
    assert list(t["record"]) == [1, 2] and list(t["start"]) == [0.0, 0.0] and list(t["end"]) == [4.0, 4.0]
    for row, i in zip(t.itertuples(), (1, 2)):
        dec = tsfdi.detect(frame(ds, i), healthy, tsfdi.LjungBox(lags=20, alpha=1e-3))
        assert (row.statistic_roll, row.statistic_pitch) == pytest.approx(tuple(dec.statistic), rel=1e-12)
        assert row.fault == bool(np.any(dec.reject))
    assert list(t["fault"]) == [False, True]            # the healthy record passes, the rotor failure is found
    # per window: a bare integer counts samples, '1s' is the same window at 100 Hz
    for window, step in (("100", "50"), ("1s", "500ms")):
        assert main(["detect", str(nc), "--baseline", str(d / "healthy.npz"), "--record", "2", "--window", window,
                     "--step", step, "--method", "variance", "--out", str(out)]) == 0
        assert "window 100 samples = 1 s, step 50 samples = 0.5 s, at 100 Hz" in capsys.readouterr().out
        t = pd.read_csv(out)
        ws = ResidualWindows({"h": healthy}).fit(frame(ds, 2)).statistics(tsfdi.FTest(alpha=1e-3), window=100,
                                                                           step=50)
        assert len(t) == len(ws) == 7
        np.testing.assert_allclose(t["start"], ws.starts / 100)
        np.testing.assert_allclose(t["end"] - t["start"], 1.0)
        np.testing.assert_allclose(t[["statistic_roll", "statistic_pitch"]], ws.statistic[:, 0], rtol=1e-12)
        np.testing.assert_array_equal(t["fault"], ws.reject[:, 0])


def test_identify_records(sim, capsys):
    d, nc, ds = sim
    out = d / "identify.csv"
    assert main(["identify", str(nc), "--models", f"healthy={d / 'healthy.npz'}", str(d / "rotor1.npz"),
                 "--where", "state=rotor1", "--window", "1s", "--step", "1s", "--method", "variance", "--out",
                 str(out)]) == 0
    t = pd.read_csv(out, keep_default_na=False)
    assert list(t["record"]) == [2] * 4 + [3] * 4
    models = {"healthy": tsfdi.load(d / "healthy.npz"), "rotor1": tsfdi.load(d / "rotor1.npz")}
    for i in (2, 3):
        part = t[t["record"] == i]
        wins = tsfdi.identify_windows(frame(ds, i), models, tsfdi.FTest(alpha=1e-3), window="1s", step="1s")
        np.testing.assert_array_equal(part["pvalue_rotor1"], wins.windows.min_pvalue[:, 1])
        assert part["label"].tolist() == [lab or "" for lab in wins.decide("paper")]
    assert (t["label"][t["start"] >= 2.0] == "rotor1").all()      # a second after the failure: rotor 1
    assert not t["accept_healthy"][t["start"] >= 1.0].any()


def test_monitor_writes_events(sim, capsys):
    d, nc, ds = sim
    out = d / "events.csv"
    assert main(["monitor", str(nc), "--record", "3", "--baseline", str(d / "healthy.npz"), "--models",
                 f"rotor1={d / 'rotor1.npz'}", "--window", "1s", "--step", "20", "--steady-window", "50",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    rotor1 = tsfdi.load(d / "rotor1.npz")
    mon = tsfdi.Monitor(tsfdi.load(d / "healthy.npz"), {"rotor1": rotor1}, window=100, step=20, fs=100.0,
                        test=tsfdi.LjungBox(lags=25, alpha=1e-3), steady_window=50)
    ref = mon.run(frame(ds, 3))
    assert f"sim.nc record 3: detection at {ref.detection_time:g} s, label rotor1" in printed
    t = pd.read_csv(out)
    expected = ref.to_frame()
    assert len(t) == len(expected) > 0 and (t["record"] == 3).all()
    np.testing.assert_allclose(t["time"], expected["time"])
    assert t["kind"].tolist() == expected["kind"].tolist()
    assert t["kind"].iloc[0] == "detection" and 1.0 < ref.detection_time < 2.5
    # detection only: no fault models, the same detection; the healthy records raise nothing
    assert main(["monitor", str(nc), "--baseline", str(d / "healthy.npz"), "--window", "1s", "--step", "20",
                 "--steady-window", "50", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"sim.nc record 3: detection at {ref.detection_time:g} s, label -" in printed
    # the healthy records: what the Python Monitor says of them (on the blade-element aircraft's light turbulence
    # record 0 raises a false alarm, record 1 none)
    alone = tsfdi.Monitor(tsfdi.load(d / "healthy.npz"), {}, window=100, step=20, fs=100.0,
                          test=tsfdi.LjungBox(lags=25, alpha=1e-3), steady_window=50)
    alarmed = {3}
    for i in (0, 1):
        det = alone.run(frame(ds, i)).detection_time
        assert f"sim.nc record {i}: detection at {'-' if det is None else f'{det:g} s'}" in printed
        alarmed |= set() if det is None else {i}
    t = pd.read_csv(out)
    assert {2, 3} <= set(t["record"]) and "identification" not in set(t["kind"])
    assert set(t["record"]) - {2} == alarmed
    assert t["time"][(t["record"] == 3) & (t["kind"] == "detection")].tolist() == [ref.detection_time]


@pytest.fixture(scope="module")
def csv_files(tmp_path_factory):
    """The same two-channel record at 50 Hz with a 'timestamp' column from 100 s, a 'clock' column, no time."""
    d = tmp_path_factory.mktemp("csv")
    x = record("healthy", 1000, np.random.default_rng(7))
    df = pd.DataFrame({"timestamp": 100.0 + np.arange(1000) / 50, "a": x[:, 0], "b": x[:, 1]})
    df.to_csv(d / "stamped.csv", index=False)
    df.rename(columns={"timestamp": "clock"}).to_csv(d / "clock.csv", index=False)
    df.drop(columns="timestamp").to_csv(d / "plain.csv", index=False)
    return d, df


def test_csv_time_column_is_the_index(csv_files, capsys):
    d, df = csv_files
    assert main(["fit", str(d / "stamped.csv"), "--max-lags", "4", "--out", str(d / "s.npz")]) == 0
    assert "VAR(2) on ['a', 'b'] from 1 record(s) at 50 Hz" in capsys.readouterr().out   # not a 'timestamp' channel
    ref = tsfdi.load(d / "s.npz")
    np.testing.assert_allclose(np.asarray(ref.model.data.index), df["timestamp"])
    for argv in (["clock.csv", "--time-column", "clock"], ["plain.csv", "--fs", "50"],
                 ["stamped.csv", "--fs", "50.2"]):                     # --fs within 1 % of the time column
        assert main(["fit", str(d / argv[0]), *argv[1:], "--max-lags", "4", "--out", str(d / "o.npz")]) == 0
        assert "at 50" in capsys.readouterr().out
        np.testing.assert_array_equal(np.asarray(tsfdi.load(d / "o.npz").params), np.asarray(ref.params))
    # windows of 2 s are 100 samples at 50 Hz, and their times are on the file's clock
    assert main(["detect", str(d / "stamped.csv"), "--baseline", str(d / "s.npz"), "--window", "2s", "--step", "5s",
                 "--out", str(d / "t.csv")]) == 0
    assert "window 100 samples = 2 s, step 250 samples = 5 s, at 50 Hz" in capsys.readouterr().out
    t = pd.read_csv(d / "t.csv")
    assert "record" not in t and t["start"].tolist() == [100.0, 105.0, 110.0, 115.0]
    # --start / --stop as times on that clock, or as row numbers
    assert main(["fit", str(d / "stamped.csv"), "--start", "110s", "--stop", "2min", "--lags", "2", "--max-lags", "4",
                 "--out", str(d / "o.npz")]) == 0
    assert "(496 samples)" in capsys.readouterr().out                   # 500 rows less the hold-back of 4
    assert main(["fit", str(d / "stamped.csv"), "--start", "500", "--stop", "1000", "--lags", "2", "--max-lags", "4",
                 "--out", str(d / "o.npz")]) == 0
    assert "(496 samples)" in capsys.readouterr().out


def test_csv_time_unit(csv_files, sim, capsys):
    """A 'timestamp' counting milliseconds (CrazyPAD, many autopilots): read in seconds it gives 0.05 Hz, which the
    note points out; --time-unit ms gives the model of the same record in seconds, --start / --stop in seconds."""
    d, df = csv_files
    df.assign(timestamp=1000 * df["timestamp"]).to_csv(d / "ms.csv", index=False)
    assert main(["fit", str(d / "ms.csv"), "--lags", "2", "--out", str(d / "o.npz")]) == 0
    captured = capsys.readouterr()
    assert "at 0.05 Hz" in captured.out and "give --time-unit ms" in captured.err
    assert main(["fit", str(d / "ms.csv"), "--time-unit", "ms", "--max-lags", "4", "--start", "110s", "--stop", "2min",
                 "--out", str(d / "o.npz")]) == 0
    captured = capsys.readouterr()
    assert "at 50 Hz" in captured.out and captured.err == ""
    ref = tsfdi.load(d / "o.npz")
    np.testing.assert_allclose(np.asarray(ref.model.data.index), df["timestamp"].iloc[500:1000])
    assert main(["fit", str(d / "stamped.csv"), "--time-unit", "s", "--lags", "2", "--out", str(d / "o.npz")]) == 0
    assert "at 50 Hz" in capsys.readouterr().out
    assert main(["fit", str(d / "plain.csv"), "--fs", "50", "--time-unit", "ms", "--out", str(d / "o.npz")]) == 2
    assert "--time-unit: " in capsys.readouterr().err
    assert main(["fit", str(sim[1]), "--record", "0", "--time-unit", "ms", "--out", str(d / "o.npz")]) == 2
    assert "--time-unit is for CSV files" in capsys.readouterr().err


def test_csv_dates_and_times(csv_files, capsys):
    """A time column of dates and times (ALFA's merged CSV: '%time' = '2018-09-11 18:46:35.350') is the clock in
    seconds since its first row: the same model as the column in seconds."""
    d, df = csv_files
    stamps = pd.Timestamp("2018-09-11 18:46:35.350") + pd.to_timedelta(df["timestamp"] - 100.0, unit="s")
    df.drop(columns="timestamp").assign(**{"%time": stamps.dt.strftime("%Y-%m-%d %H:%M:%S.%f")})[
        ["%time", "a", "b"]].to_csv(d / "dated.csv", index=False)
    assert main(["fit", str(d / "dated.csv"), "--max-lags", "4", "--start", "10s", "--out", str(d / "o.npz")]) == 0
    assert "from 1 record(s) at 50 Hz (496 samples)" in capsys.readouterr().out
    ref = df.iloc[500:].set_index("timestamp").rename_axis("time")
    np.testing.assert_array_equal(np.asarray(tsfdi.load(d / "o.npz").params),
                                  np.asarray(tsfdi.select_order(ref, 4, "var").fit().params))
    assert main(["fit", str(d / "dated.csv"), "--time-unit", "ms", "--out", str(d / "o.npz")]) == 2
    assert "dates and times need no unit" in capsys.readouterr().err
    df.assign(timestamp=df["timestamp"].astype(str).where(df.index != 7, "soon")).to_csv(d / "bad_time.csv",
                                                                                        index=False)
    assert main(["fit", str(d / "bad_time.csv"), "--out", str(d / "o.npz")]) == 2
    err = capsys.readouterr().err
    assert "must hold times (numbers, elapsed times" in err and "line 9 holds 'soon'" in err


def test_resample_uneven_time_stamps(csv_files, sim, capsys):
    """--resample --fs: a CSV log with uneven stamps (ALFA's engine files) put on a grid by zero-order hold, the
    records of tsfdi.datasets.align; --rows-where compares the held values."""
    from tsfdi.datasets import align

    d, df = csv_files
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.005, 0.035, 1000))              # 5-35 ms steps, about 50 Hz
    t[600:] += 1.0                                              # a 1 s logging gap
    log = df.assign(timestamp=t, level=np.where(t > 5.0, 1.0, 0.0))
    log.to_csv(d / "uneven.csv", index=False)
    assert main(["fit", str(d / "uneven.csv"), "--columns", "a,b", "--lags", "2", "--max-lags", "4",
                 "--out", str(d / "o.npz")]) == 2
    assert "--resample with --fs RATE puts the rows on a uniform grid" in capsys.readouterr().err
    out = d / "o.npz"
    for extra in ([], ["--rows-where", "level>0"]):
        assert main(["fit", str(d / "uneven.csv"), "--columns", "a,b", "--resample", "--fs", "50", *extra,
                     "--lags", "2", "--max-lags", "4", "--out", str(out)]) == 0
        capsys.readouterr()
        frame = log.set_index(pd.to_timedelta(log["timestamp"], unit="s"))[["a", "b", "level"]]
        recs = align(frame, 50)
        assert len(recs) == 2                                   # split at the gap
        if extra:
            recs = [r[r["level"] > 0] for r in recs]
        ref = tsfdi.select_order([r[["a", "b"]].to_numpy() for r in recs], 4, "var").fit(2)
        np.testing.assert_allclose(np.asarray(tsfdi.load(out).params), np.asarray(ref.params), rtol=1e-12)
    assert main(["fit", str(d / "uneven.csv"), "--resample", "--out", str(out)]) == 2
    assert "--resample: " in capsys.readouterr().err
    assert main(["fit", str(sim[1]), "--record", "0", "--resample", "--fs", "50", "--out", str(out)]) == 2
    assert "--resample is for CSV files" in capsys.readouterr().err


def test_a_logging_gap_can_be_cut_off(csv_files, capsys):
    """The even sampling is checked on the rows used: a gap before --start (a log's time on the ground) does not
    refuse the file, as the message about the gap advises; a gap inside the selection names its file line."""
    d, df = csv_files
    gap = df.drop(index=range(50, 60))                   # 0.2 s missing after 101 s
    gap.to_csv(d / "gap.csv", index=False)
    assert main(["fit", str(d / "gap.csv"), "--lags", "2", "--out", str(d / "o.npz")]) == 2
    assert "a gap of 0.22 s after line 51 at 100.98 s" in capsys.readouterr().err
    assert main(["fit", str(d / "gap.csv"), "--start", "110s", "--stop", "2min", "--lags", "2", "--out",
                 str(d / "o.npz")]) == 0
    assert "at 50 Hz (480 samples)" in capsys.readouterr().out         # 500 rows less the hold-back of 20
    assert main(["fit", str(d / "gap.csv"), "--start", "100.5s", "--lags", "2", "--out", str(d / "o.npz")]) == 2
    err = capsys.readouterr().err              # the rows used start at file line 27; the gap is named by its file line
    assert "column 'timestamp' is not uniformly sampled: a gap of 0.22 s after line 51 at 100.98 s" in err


def test_several_data_files(csv_files, capsys):
    """Several files, read with the same options: fit pools their records (the model of the same records in
    memory), detect tests each and names it by its file; files that disagree are refused by name."""
    d, df = csv_files
    other = df.assign(a=df["a"].to_numpy()[::-1], b=df["b"].to_numpy()[::-1])
    other.to_csv(d / "other.csv", index=False)
    assert main(["fit", str(d / "stamped.csv"), str(d / "other.csv"), "--max-lags", "4", "--out",
                 str(d / "two.npz")]) == 0
    assert "from 2 record(s) at 50 Hz" in capsys.readouterr().out
    recs = [f.set_index("timestamp").rename_axis("time") for f in (df, other)]
    ref = tsfdi.select_order(recs, 4, "var").fit()
    np.testing.assert_array_equal(np.asarray(tsfdi.load(d / "two.npz").params), np.asarray(ref.params))
    assert main(["detect", str(d / "stamped.csv"), str(d / "other.csv"), "--baseline", str(d / "two.npz"),
                 "--window", "5s", "--step", "5s", "--out", str(d / "t.csv")]) == 0
    capsys.readouterr()
    t = pd.read_csv(d / "t.csv")
    assert t["record"].tolist() == ["stamped.csv"] * 4 + ["other.csv"] * 4      # the shortest unique names
    df[["timestamp", "a"]].to_csv(d / "one_column.csv", index=False)
    df.assign(timestamp=df["timestamp"] * 2).to_csv(d / "slow.csv", index=False)
    for files, message in (([d / "stamped.csv", d / "one_column.csv"], "gives the column(s) ['a'] but"),
                           ([d / "stamped.csv", d / "slow.csv"], "is sampled at 25 Hz but"),
                           ([d / "stamped.csv", d / "stamped.csv"], "is given twice")):
        assert main(["fit", *map(str, files), "--out", str(d / "o.npz")]) == 2
        assert message in capsys.readouterr().err


def test_rows_where_and_margin(csv_files, sim, capsys):
    """--rows-where keeps the runs where a column (not a channel) compares so, one record each, less --margin at
    both ends (the airborne parts of a flight log); --trend c fits an intercept."""
    d, df = csv_files
    thrust = np.zeros(1000)
    thrust[100:450] = 1.0                                # airborne 102-109 s and 112-118 s
    thrust[600:900] = 2.0
    df.assign(thrust=thrust).to_csv(d / "flight.csv", index=False)
    out = d / "o.npz"
    assert main(["fit", str(d / "flight.csv"), "--columns", "a,b", "--rows-where", "thrust>0", "--margin", "1s",
                 "--lags", "2", "--max-lags", "4", "--trend", "c", "--out", str(out)]) == 0
    assert "from 2 record(s) at 50 Hz" in capsys.readouterr().out
    runs = [df.iloc[a:b].set_index("timestamp").rename_axis("time")[["a", "b"]] for a, b in ((150, 400), (650, 850))]
    ref = tsfdi.select_order(runs, 4, "var", trend="c").fit(2)
    np.testing.assert_array_equal(np.asarray(tsfdi.load(out).params), np.asarray(ref.params))
    # two conditions, both hold; the runs are tested as records named by their number
    assert main(["detect", str(d / "flight.csv"), "--rows-where", "thrust>0", "--rows-where", "thrust<=1",
                 "--baseline", str(out), "--out", str(d / "t.csv")]) == 0
    capsys.readouterr()
    assert pd.read_csv(d / "t.csv")["start"].tolist() == [102.0]
    # runs at two rates are refused by name (the second run at 25 Hz)
    slow = df.assign(thrust=thrust).iloc[np.r_[0:500, 500:1000:2]]
    slow.assign(timestamp=np.r_[slow["timestamp"].to_numpy()[:500], 110 + np.arange(250) / 25]).to_csv(
        d / "two_rates.csv", index=False)
    assert main(["fit", str(d / "two_rates.csv"), "--columns", "a,b", "--rows-where", "thrust>0", "--out",
                 str(out)]) == 2
    assert "gives 50 Hz in record 0 but 25 Hz in record 1" in capsys.readouterr().err
    # a True / False column compares as 1 / 0
    df.assign(armed=thrust == 1.0).to_csv(d / "armed.csv", index=False)
    assert main(["detect", str(d / "armed.csv"), "--rows-where", "armed==1", "--baseline", str(out), "--out",
                 str(d / "t.csv")]) == 0
    capsys.readouterr()
    assert pd.read_csv(d / "t.csv")["start"].tolist() == [102.0]
    for argv, message in ((["--rows-where", "lift>0"], "--rows-where lift>0: "),
                          (["--rows-where", "thrust>5"], "--rows-where: no row of"),
                          (["--rows-where", "thrust>0", "--margin", "5s"], "for more than --margin 5 s"),
                          (["--margin", "1s"], "--margin trims the runs of --rows-where")):
        assert main(["fit", str(d / "flight.csv"), "--columns", "a,b", *argv, "--out", str(out)]) == 2
        assert message in capsys.readouterr().err
    assert main(["fit", str(d / "flight.csv"), "--rows-where", "thrust~0", "--out", str(out)]) == 2
    assert "must be COLUMN OP NUMBER" in capsys.readouterr().err
    # a netCDF variable over record and time
    assert main(["fit", str(sim[1]), "--record", "0,1", "--columns", "roll,pitch", "--rows-where", "roll>-10",
                 "--max-lags", "4", "--out", str(out)]) == 0
    assert "from 2 record(s)" in capsys.readouterr().out


def test_nan_policy_omit_splits_into_records(csv_files, capsys):
    d, df = csv_files
    gappy = df.copy()
    gappy.loc[[300, 301, 700], "b"] = np.nan
    gappy.loc[702:703, "a"] = np.nan                    # leaves a 1-row piece (row 701), dropped as too short
    gappy.to_csv(d / "gappy.csv", index=False)
    assert main(["fit", str(d / "gappy.csv"), "--max-lags", "4", "--nan-policy", "omit", "--out",
                 str(d / "g.npz")]) == 0
    captured = capsys.readouterr()
    assert "from 3 record(s)" in captured.out
    assert "dropped 1 piece(s) of split records shorter than 6 samples" in captured.err
    pieces = [df.iloc[a:b].set_index("timestamp").rename_axis("time") for a, b in ((0, 300), (302, 700), (704, 1000))]
    ref = tsfdi.select_order(pieces, 4, "var").fit()
    np.testing.assert_array_equal(np.asarray(tsfdi.load(d / "g.npz").params), np.asarray(ref.params))


def test_help_shows_the_defaults(capsys):
    expect = {"fit": ["--max-lags MAX_LAGS   largest order searched (default: 20)", "(default: raise)"],
              "select-order": ["(default: logdet)"],
              "detect": ["(default: 1s)", "a bare integer counts samples", "(default: 0.001)", "(default: 20)"],
              "identify": ["(default: paper)", "(default: whiteness)"],
              "monitor": ["(default: 10s)", "(default: 25)"],
              "simulate": ["(default: 60s)", "(default: 10s)", "(default: 1ms)", "(default: 100.0)"],
              "demo": ["(default: 5s,10s,20s)", "(default: tsfdi-demo)"]}
    assert set(expect) == set(COMMANDS)
    for name, words in expect.items():
        with pytest.raises(SystemExit) as exc:
            main([name, "--help"])
        assert exc.value.code == 0
        text = " ".join(capsys.readouterr().out.split())        # argparse wraps lines
        for w in words:
            assert " ".join(w.split()) in text, (name, w)
        assert "(default: None)" not in text and "(default: False)" not in text


def test_version_and_python_m_tsfdi(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out == f"tsfdi {tsfdi.__version__}\n"
    # python -m tsfdi: the real exit status and stderr of an error
    r = subprocess.run([sys.executable, "-m", "tsfdi", "fit", str(tmp_path / "flight.csv"), "--out",
                        str(tmp_path / "m.npz")], capture_output=True, text=True)
    assert r.returncode == 2 and r.stdout == "" and r.stderr.startswith("usage: tsfdi fit")
    assert r.stderr.splitlines()[-1] == f"tsfdi fit: error: data: {tmp_path / 'flight.csv'} does not exist"
    assert "Traceback" not in r.stderr


def test_warnings_are_one_line(tmp_path, capsys):
    x = np.random.default_rng(3).standard_normal((300, 2))
    pd.DataFrame({"time": np.arange(300) / 10, "a": x[:, 0], "b": x[:, 1], "note": "text"}).to_csv(
        tmp_path / "noted.csv", index=False)
    assert main(["fit", str(tmp_path / "noted.csv"), "--max-lags", "2", "--out", str(tmp_path / "m.npz")]) == 0
    err = capsys.readouterr().err
    assert err and all(line.startswith("tsfdi fit: warning: ") for line in err.strip().splitlines())
    assert "cli.py" not in err


def test_columns_are_matched_by_name(sim, capsys):
    """--columns pitch,roll against a model of roll, pitch: the same decisions (channels matched by name)."""
    d, nc, ds = sim
    tables = []
    for cols in ("roll,pitch", "pitch,roll"):
        out = d / f"by_name_{cols}.csv"
        assert main(["identify", str(nc), "--models", f"healthy={d / 'healthy.npz'}", str(d / "rotor1.npz"),
                     "--record", "2", "--columns", cols, "--window", "1s", "--out", str(out)]) == 0
        tables.append(pd.read_csv(out, keep_default_na=False))
        assert main(["detect", str(nc), "--baseline", str(d / "healthy.npz"), "--record", "2", "--columns", cols,
                     "--window", "1s", "--out", str(out)]) == 0
        tables.append(pd.read_csv(out)[["statistic_roll", "statistic_pitch", "fault"]])
    pd.testing.assert_frame_equal(tables[0], tables[2])
    pd.testing.assert_frame_equal(tables[1], tables[3])


def test_the_cli_page_runs_and_says_true(tmp_path, capsys, monkeypatch):
    """Every command of docs/guide/cli.md runs (in its order, in a fresh folder beside the repository's data/),
    and its claims hold."""
    import re
    import shlex
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    page = (root / "docs" / "guide" / "cli.md").read_text()
    commands = [line for block in re.findall(r"```bash\n(.*?)```", page, re.S) for line in block.splitlines()
                if line.startswith("tsfdi ")]
    assert len(commands) == 19
    pytest.importorskip("pyulog")
    (tmp_path / "data").symlink_to(root / "data")
    monkeypatch.chdir(tmp_path)
    printed = {}
    for line in commands:
        argv = shlex.split(line)
        assert main(argv[1:]) == 0, (line, capsys.readouterr().err)
        key = argv[1] + (" calibrated" if "--threshold calibrated" in line else "")
        key += f" {argv[2].split('/')[3]}" if argv[2].startswith("data/crazypad/") else ""      # its condition
        key += " 4 records" if "crazyflie4.npz" in line else ""
        key += " depth" if "depth.npz" in line else ""
        key += " arx" if "yaw.npz" in line else ""
        printed[key] = capsys.readouterr().out
    # select-order: the orders the page quotes
    assert re.search(r"Selected \(min BIC\) +7\n", printed["select-order"])
    assert re.search(r"RSS/SSS stable from +7\n", printed["select-order"])
    # detect: the windows ending by the failure at 3 s pass; those of the transient (ending 4-6 s) reject, every
    # later one of record 3 too, while record 2 passes some of its later ones (the page says so)
    t = pd.read_csv("detect.csv")
    assert set(t["record"]) == {2, 3} and not t["fault"][t["end"] <= 3.0].any()
    assert t["fault"][(t["end"] > 3.0) & (t["end"] <= 6.0)].all() and t["fault"][t["record"] == 3][t["end"] > 3.0].all()
    assert not t["fault"][(t["record"] == 2) & (t["end"] > 6.0)].all()
    # monitor: detected by the end of the first window after the failure; rotor1 once the transient has passed
    ev = pd.read_csv("events.csv")
    assert ev["time"][ev["kind"] == "detection"].tolist() == [3.0]
    late = ev[(ev["kind"] == "identification") & (ev["window_start"] >= 5.0)]
    assert len(late) and (late["label"] == "rotor1").all()
    # the PX4 log: the 5 s windows of the first 10 s (the vehicle moved by hand) are faults, later ones are not
    table = [row.split() for row in printed["detect"].splitlines() if re.match(r"\s+\d+\s+\d", row)]
    faults = [(float(r[1]), r[-1] == "True") for r in table]
    assert faults and all(f == (start < 10.0) for start, f in faults)
    # calibrated thresholds on the rest of the PX4 log: 0 of the 17 one-second windows flagged
    assert printed["detect calibrated"].strip().splitlines()[-1] == "fault in 0 of 17 window(s)"
    # CrazyPAD: a baseline from the 2 airborne records of a normal log predicts thresholds so wide (up to 7e+50) that
    # the 4 mm cut is flagged in none of its windows; one from both normal logs (4 records) flags it in all 6
    assert "from 2 record(s) at 101.153 Hz" in printed["fit normal_flight"]
    cut = printed["detect calibrated cut_propeller_M3_4mm_4mm_39mm"]
    assert cut.strip().splitlines()[-1] == "fault in 0 of 6 window(s)"
    assert "e+50" in cut
    assert "from 4 record(s)" in printed["fit normal_flight 4 records"]
    cut = printed["detect calibrated cut_propeller_M3_4mm_4mm_39mm 4 records"]
    assert cut.strip().splitlines()[-1] == "fault in 6 of 6 window(s)"
    # controller-aware: the ARX of the yaw rate given the commands, from both normal logs, flags the cut (the page)
    assert printed["fit normal_flight arx"].startswith("ARX(5, 5, nk=0) of ['controller.r_yaw'] given --u")
    assert printed["detect calibrated cut_propeller_M3_4mm_4mm_39mm arx"].strip().splitlines()[-1] == \
        "fault in 6 of 6 window(s)"
    # the FP-VAR over the depth cut from M3: the estimates the page prints, its windows flagged (5 of the normal
    # flights' 6, the cut log's 3) and the k_depth column
    assert re.search(r"FP-VAR\(\d+\), degree 1 \(BIC over lags 1..12, degree 0..1\) over depth in \[0, 8\]",
                     printed["fit normal_flight depth"])
    said = re.findall(r"^(\S+) record 0, --baseline depth.npz: estimated depth = (.*)$",
                      printed["detect normal_flight depth"], re.M)
    def numbers(text):
        return [float(v) for v in re.findall(r"[-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?", text)]

    for name, text in said:
        shown = re.search(re.escape(f"{name} record 0, --baseline depth.npz: estimated depth = ") + "(.*)$", page, re.M)
        assert shown, f"the page does not show {name}'s estimate"
        # the 6 printed digits: the last may differ between numpy / scipy builds
        np.testing.assert_allclose(numbers(text), numbers(shown.group(1)), rtol=1e-5)
    assert len(said) == 3
    table = [row.split() for row in printed["detect normal_flight depth"].splitlines() if ".csv.gz:0" in row]
    assert [(r[0].split("/")[0], r[-2]) for r in table].count(("normal_flight", "True")) == 5
    assert all(r[-2] == "True" for r in table if r[0].startswith("cut_")) and len(table) == 9
    # without --min-windows 5 the page's "6 non-overlapping windows, fewer than the default 30" is the message
    line = next(c for c in commands if "--baseline crazyflie.npz" in c)
    assert main(shlex.split(line.replace(" --min-windows 5", ""))[1:]) == 2
    assert "holds 6 independent (non-overlapping) windows, at least 30 are needed" in capsys.readouterr().err

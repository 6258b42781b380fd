"""align (tsfdi.datasets.alignment) on synthetic multi-rate topics, and the uniform-sampling check of the time
index (tsfdi._data.time_step / sampling_frequency / as_signal)."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import tsfdi
from tsfdi._data import JITTER, as_signal, sampling_frequency, time_step
from tsfdi.datasets import align
from tsfdi.exceptions import TsfdiWarning


def topic(stamps_s, values, columns=None) -> pd.DataFrame:
    values = np.asarray(values, dtype=float)
    values = values[:, None] if values.ndim == 1 else values
    index = pd.TimedeltaIndex(np.round(np.asarray(stamps_s) * 1e9).astype("timedelta64[ns]"), name="time")
    return pd.DataFrame(values, index=index, columns=columns or [f"c{i}" for i in range(values.shape[1])])


@pytest.fixture(scope="module")
def jittery():
    """Two topics at about 250 Hz and 30 Hz with random jitter (no gap)."""
    rng = np.random.default_rng(1)
    fast = np.cumsum(rng.uniform(0.003, 0.005, 2500))
    slow = 0.05 + np.cumsum(rng.uniform(0.025, 0.04, 300))
    return {"imu": topic(fast, rng.normal(size=(2500, 3)), ["x", "y", "z"]),
            "att": topic(slow, rng.normal(size=(300, 2)), ["q0", "q1"])}


def brute_hold(src: pd.DataFrame, t: pd.Timedelta) -> np.ndarray:
    """The last sample at or before t, by a plain scan."""
    last = None
    for i, s in enumerate(src.index):
        if s <= t:
            last = i
    return src.to_numpy()[last]


def test_zoh_is_the_last_sample_at_or_before_each_grid_time(jittery):
    (rec,) = align(jittery, 50)
    assert rec.columns.tolist() == ["imu.x", "imu.y", "imu.z", "att.q0", "att.q1"]
    assert isinstance(rec.index, pd.TimedeltaIndex) and rec.index.name == "time"
    assert (np.diff(rec.index) == pd.Timedelta("20ms")).all()
    start = max(f.index[0] for f in jittery.values())
    assert rec.index[0] == start.ceil("20ms") and rec.index[-1] <= min(f.index[-1] for f in jittery.values())
    assert rec.index[-1] + pd.Timedelta("20ms") > min(f.index[-1] for f in jittery.values())
    for t in rec.index[::37]:
        np.testing.assert_array_equal(rec.loc[t, ["imu.x", "imu.y", "imu.z"]].to_numpy(),
                                      brute_hold(jittery["imu"], t))
        np.testing.assert_array_equal(rec.loc[t, ["att.q0", "att.q1"]].to_numpy(), brute_hold(jittery["att"], t))
    assert sampling_frequency(as_signal(rec)) == pytest.approx(50.0)


def test_fs_as_a_time_span(jittery):
    pd.testing.assert_frame_equal(align(jittery, "20ms")[0], align(jittery, 50)[0])
    pd.testing.assert_frame_equal(align(jittery, pd.Timedelta("20ms"))[0], align(jittery, 50.0)[0])


def test_linear_interpolates_between_the_samples_around_each_grid_time(jittery):
    (rec,) = align(jittery, 50, method="linear")
    for name, src in jittery.items():
        x = src.index.to_numpy().astype(np.int64)
        for c in src.columns:
            expected = np.interp(rec.index.to_numpy().astype(np.int64), x, src[c].to_numpy())
            np.testing.assert_allclose(rec[f"{name}.{c}"].to_numpy(), expected, rtol=0, atol=1e-12)


def test_a_repeated_stamp_holds_the_last_sample_logged_there():
    a = topic([0.0, 0.01, 0.02, 0.02, 0.03, 0.04], [1, 2, 3, 4, 5, 6])
    (rec,) = align(a, 100, min_length=1)
    np.testing.assert_array_equal(rec["c0"].to_numpy(), [1, 2, 4, 5, 6])


def test_time_going_back_is_refused_naming_topic_and_time():
    a = topic([0.0, 0.01, 0.02, 0.015, 0.03], [1, 2, 3, 4, 5])
    with pytest.raises(ValueError, match=r"frames\['imu'\]: time goes back at sample 3 \(0.015000 s after "
                                         r"0.020000 s\); sort it first"):
        align({"imu": a}, 100)


def one_second_gap() -> pd.DataFrame:
    t = np.r_[np.arange(0, 300) * 0.01, 4.0 + np.arange(0, 200) * 0.01]
    return topic(t, np.sin(t))


def test_a_one_second_gap_is_split_or_refused():
    gap = one_second_gap()
    first, second = align({"imu": gap}, 100)
    assert (first.index[0], first.index[-1], len(first)) == (pd.Timedelta(0), pd.Timedelta("2.99s"), 300)
    assert (second.index[0], second.index[-1], len(second)) == (pd.Timedelta("4s"), pd.Timedelta("5.99s"), 200)
    with pytest.raises(ValueError, match=r"frames\['imu'\] has a gap of 1.01 s after 2.990000 s \(longer than "
                                         r"max_gap = 0.03 s\); gaps='split'"):
        align({"imu": gap}, 100, gaps="raise")
    (whole,) = align({"imu": gap}, 100, max_gap="2s")       # a longer max_gap: held over the gap
    assert len(whole) == 600 and (whole["imu.c0"]["3.5s"] == np.sin(2.99)).all()


def test_the_default_max_gap_is_three_median_steps_and_at_least_one_grid_step():
    t = np.r_[np.arange(0, 100) * 0.01, 1.03 + np.arange(0, 100) * 0.01]     # one step of 40 ms
    a = topic(t, np.cos(t))
    assert len(align(a, 100)) == 2                     # 40 ms > 3 x 10 ms: a gap
    assert len(align(a, 20)) == 1                      # 40 ms <= one 50 ms grid step: not a gap


def test_nan_raise_names_topic_column_and_time():
    a = topic(np.arange(500) * 0.01, np.c_[np.arange(500.0), np.ones(500)], ["p", "q"])
    a.iloc[123, 1] = np.nan
    with pytest.raises(ValueError, match=r"frames\['imu'\] column 'q' is nan at 1.230000 s \(sample 123\); "
                                         r"nan_policy='omit'"):
        align({"imu": a}, 100)
    a.iloc[123, 1] = np.inf
    with pytest.raises(ValueError, match=r"column 'q' is inf at 1.230000 s"):
        align(a, 100)


def test_nan_omit_splits_at_the_nan_stretch():
    a = topic(np.arange(500) * 0.01, np.arange(500.0))
    a.iloc[200:210, 0] = np.nan
    first, second = align({"imu": a}, 100, nan_policy="omit")
    assert (first.index[-1], second.index[0]) == (pd.Timedelta("1.99s"), pd.Timedelta("2.1s"))
    assert len(first) + len(second) == 490
    assert np.isfinite(first.to_numpy()).all() and np.isfinite(second.to_numpy()).all()


def test_a_nan_skipped_by_subsampling_is_not_hidden():
    a = topic(np.arange(500) * 0.004, np.arange(500.0))       # 250 Hz, grid at 50 Hz holds every 5th sample
    a.iloc[101, 0] = np.nan                                   # not held by any grid time
    with pytest.raises(ValueError, match=r"is nan at 0.404000 s \(sample 101\)"):
        align(a, 50)
    records = align(a, 50, nan_policy="omit")
    assert [len(r) for r in records] == [21, 78]            # the grid time 0.42 s is left out
    assert records[1].index[0] - records[0].index[-1] == pd.Timedelta("40ms")


def test_linear_nan_in_the_next_sample_counts():
    a = topic(np.arange(100) * 0.03, np.arange(100.0))
    a.iloc[50, 0] = np.nan                                    # at 1.5 s: used by the grid times in (1.47, 1.5)
    with pytest.raises(ValueError, match=r"is nan at 1.500000 s"):
        align(a, 100, method="linear")


def test_short_records_are_reported_and_left_out():
    t = np.r_[np.arange(0, 300) * 0.01, 4.0, 4.01, 4.02, 6.0 + np.arange(0, 100) * 0.01]
    a = topic(t, np.sin(t))
    with pytest.warns(TsfdiWarning, match=r"1 record\(s\) shorter than min_length = 10 samples left out: "
                                          r"4.000000 s \(3\)"):
        records = align(a, 100)
    assert [len(r) for r in records] == [300, 100]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert [len(r) for r in align(a, 100, min_length=1)] == [300, 3, 100]
    with pytest.warns(TsfdiWarning, match="min_length = 200 samples"):
        assert [len(r) for r in align(a, 100, min_length="2s")] == [300]
    with pytest.raises(ValueError, match="no record of at least min_length = 400 samples"), \
            pytest.warns(TsfdiWarning):
        align(a, 100, min_length=400)


def test_column_names_and_duplicates():
    a = topic(np.arange(50) * 0.01, np.arange(50.0), ["x"])
    b = topic(np.arange(50) * 0.01, np.arange(50.0) ** 2, ["x"])
    assert align({"a": a, "b": b}, 100)[0].columns.tolist() == ["a.x", "b.x"]
    assert align(a, 100)[0].columns.tolist() == ["x"]
    series = {"speed": a["x"].rename(None), "alt": b["x"].rename("h")}
    assert align(series, 100)[0].columns.tolist() == ["speed", "alt.h"]
    with pytest.raises(ValueError, match=r"duplicate column names \['a.x'\]"):
        align({"a": pd.concat([a, a], axis=1)}, 100)
    with pytest.raises(ValueError, match=r"duplicate column names \['a.b.c'\]"):
        align({"a": topic(np.arange(50) * 0.01, np.ones(50), ["b.c"]),
               "a.b": topic(np.arange(50) * 0.01, np.ones(50), ["c"])}, 100)


def test_time_index_kinds():
    t = np.arange(100) * 0.01
    values = np.sin(t)
    seconds = pd.DataFrame({"v": values}, index=pd.Index(t, name="t"))
    (rec,) = align(seconds, 100)
    assert isinstance(rec.index, pd.TimedeltaIndex) and len(rec) == 100
    np.testing.assert_array_equal(rec["v"].to_numpy(), values)
    dates = pd.DataFrame({"v": values}, index=pd.date_range("2024-05-01 12:00", periods=100, freq="10ms",
                                                            tz="Europe/Paris"))
    dates.attrs["flight"] = "f1"
    (rec,) = align(dates, "10ms")
    assert isinstance(rec.index, pd.DatetimeIndex) and str(rec.index.tz) == "Europe/Paris"
    assert rec.index.name == "time" and rec.index[0] == dates.index[0] and rec.attrs == {"flight": "f1"}
    with pytest.raises(ValueError, match="mix time kinds"):
        align({"a": seconds, "b": dates}, 100)
    with pytest.raises(TypeError, match=r"frames\['a'\] needs a time index .* got RangeIndex: set the time column"):
        align({"a": seconds.reset_index(drop=True)}, 100)


def test_xarray_input():
    t = np.arange(100) * 0.01
    da = xr.DataArray(np.c_[np.sin(t), np.cos(t)], dims=("time", "channel"),
                      coords={"time": t, "channel": ["s", "c"]})
    (rec,) = align({"trig": da}, 100)
    assert rec.columns.tolist() == ["trig.s", "trig.c"]
    np.testing.assert_array_equal(rec.to_numpy(), da.values)
    ds = xr.Dataset({"s": ("time", np.sin(t)), "c": ("time", np.cos(t))}, coords={"time": t})
    (rec,) = align(ds, 100)
    assert rec.columns.tolist() == ["s", "c"]
    (rec,) = align({"s": da.sel(channel="s", drop=True)}, 100)
    assert rec.columns.tolist() == ["s"]


def test_records_feed_the_models():
    rng = np.random.default_rng(3)
    e = rng.normal(size=2000)
    y = np.zeros(2000)
    for i in range(2, 2000):
        y[i] = 1.2 * y[i - 1] - 0.5 * y[i - 2] + e[i]
    t = np.arange(2000) * 0.01
    keep = (t < 8) | (t >= 9)                                   # a 1 s logging gap
    records = align({"y": topic(t[keep], y[keep], ["v"])}, 100)
    assert [len(r) for r in records] == [800, 1100]
    res = tsfdi.AR(records, lags=2).fit()
    assert res.nobs == 800 + 1100 - 2 * 2
    np.testing.assert_allclose(-np.asarray(res.ar_coefs), [1.2, -0.5], atol=0.05)
    with pytest.raises(ValueError, match="gap of 1.01 s after sample 799"):
        tsfdi.AR(topic(t[keep], y[keep], ["v"]), lags=2)


@pytest.mark.parametrize("kwargs, error, match", [
    ({"fs": 0}, ValueError, "fs must be a positive, finite frequency"),
    ({"fs": -5.0}, ValueError, "fs must be a positive"),
    ({"fs": True}, TypeError, "fs must be a frequency in Hz or a time span"),
    ({"fs": "soon"}, ValueError, "fs must be a time span such as '20ms'"),
    ({"fs": "-20ms"}, ValueError, "fs must be a positive time span"),
    ({"fs": 2e9}, ValueError, "fs = 2000000000.0 gives a grid period of 0 ns: it must lie between 1 ns"),
    ({"fs": 1e-12}, ValueError, "fs = 1e-12 gives a grid period of 1000000000000000000000 ns"),
    ({"fs": 1e8}, ValueError, "gives .* values, more than 268435456: lower fs"),
    ({"fs": 100, "method": "cubic"}, ValueError, "method must be one of 'zoh', 'linear'"),
    ({"fs": 100, "gaps": "fill"}, ValueError, "gaps must be one of 'split', 'raise'"),
    ({"fs": 100, "nan_policy": "propagate"}, ValueError, "nan_policy must be one of 'raise', 'omit'"),
    ({"fs": 100, "max_gap": 3}, TypeError, "max_gap must be a time span"),
    ({"fs": 100, "max_gap": "0s"}, ValueError, "max_gap must be a positive time span"),
    ({"fs": 100, "min_length": 0}, ValueError, "min_length must be >= 1"),
])
def test_bad_options_name_the_argument(kwargs, error, match):
    a = topic(np.arange(0, 300) * 0.01, np.ones(300))
    with pytest.raises(error, match=match):
        align(a, **kwargs)


def test_bad_frames_name_the_topic():
    a = topic(np.arange(50) * 0.01, np.arange(50.0))
    with pytest.raises(ValueError, match="frames is empty"):
        align({}, 100)
    with pytest.raises(TypeError, match="frames must be a pandas DataFrame / Series or an xarray"):
        align(np.ones((5, 2)), 100)
    with pytest.raises(ValueError, match=r"frames\['e'\] is empty \(0 samples"):
        align({"a": a, "e": a.iloc[:0]}, 100)
    with pytest.raises(TypeError, match=r"frames\['s'\] column 'name' must hold real numbers"):
        align({"s": a.assign(name="x")}, 100)
    with pytest.raises(TypeError, match=r"column 'z' must hold real numbers, got dtype complex128"):
        align({"s": a.assign(z=1j)}, 100)
    flag = align({"s": a.assign(armed=np.arange(50) >= 20)}, 100)[0]["s.armed"]       # booleans as 0 / 1
    np.testing.assert_array_equal(flag.to_numpy(), np.r_[np.zeros(20), np.ones(30)])
    late = topic(1.0 + np.arange(50) * 0.01, np.arange(50.0))
    with pytest.raises(ValueError, match=r"no common time span at 100 Hz: frames\['late'\] starts at 1.000000 s "
                                         r"but frames\['a'\] ends at 0.490000 s"):
        align({"a": a, "late": late}, 100)
    nat = a.copy()
    nat.index = pd.TimedeltaIndex(list(a.index[:-1]) + [pd.NaT])
    with pytest.raises(ValueError, match="missing time stamp \\(NaT\\) at sample 49"):
        align(nat, 100)


# --- the uniform-sampling check of a time index ------------------------------------------------------------------


def test_sampling_frequency_reads_fs_from_every_kind_of_time_index():
    n = 500
    values = np.sin(np.arange(n))
    kinds = [pd.Series(values, index=pd.date_range("2024", periods=n, freq="10ms")),
             pd.Series(values, index=pd.timedelta_range(0, periods=n, freq="10ms")),
             pd.Series(values, index=pd.Index(np.arange(n) * 0.01, name="time")),
             xr.DataArray(values, dims="time", coords={"time": np.arange(n) * 0.01})]
    for y in kinds:
        assert sampling_frequency(as_signal(y)) == pytest.approx(100.0)
    for y in (values, pd.Series(values), pd.Series(values, index=pd.Index(np.arange(n) * 0.01, name="t"))):
        assert sampling_frequency(as_signal(y)) is None


def test_jitter_within_the_stated_tolerance_is_uniform():
    rng = np.random.default_rng(0)
    steps = 0.01 * (1 + rng.uniform(-0.9 * JITTER, 0.9 * JITTER, 999))
    index = pd.to_timedelta(np.r_[0, np.cumsum(steps)], unit="s")
    assert time_step(index, "y") == pytest.approx(np.median(steps), rel=1e-6)
    steps[500] = 0.01 * (1 + 1.5 * JITTER)
    index = pd.to_timedelta(np.r_[0, np.cumsum(steps)], unit="s")
    with pytest.raises(ValueError, match="y is not uniformly sampled: a gap of 0.0115 s after sample 500"):
        time_step(index, "y")


def test_a_one_second_gap_in_a_time_index_is_refused_naming_it():
    t = pd.date_range("2024-05-01 12:00", periods=300, freq="10ms")
    t = t.append(t[-1] + pd.Timedelta("1s") + pd.timedelta_range(0, periods=100, freq="10ms"))
    y = pd.Series(np.sin(np.arange(400)), index=t)
    with pytest.raises(ValueError, match=r"y is not uniformly sampled: a gap of 1 s after sample 299 at "
                                         r"2024-05-01T12:00:02.990000 \(median step 0.01 s; every step must be "
                                         r"within 10% of it\); put it on a uniform grid with tsfdi.align\(\.\.\., "
                                         r"gaps='split'\)"):
        as_signal(y)
    da = xr.DataArray(y.to_numpy(), dims="time", coords={"time": t})
    with pytest.raises(ValueError, match="y is not uniformly sampled: a gap of 1 s after sample 299"):
        tsfdi.AR(da, lags=2).fit()
    seconds = xr.DataArray(y.to_numpy(), dims="time", coords={"time": (t - t[0]).total_seconds()})
    with pytest.raises(ValueError, match="y is not uniformly sampled: a gap of 1 s after sample 299 at 2.99 s"):
        as_signal(seconds)                    # a numeric time coordinate holds seconds: the same rule
    with pytest.raises(ValueError, match="y is not uniformly sampled: a gap of 1 s after sample 299 at 2.99 s"):
        tsfdi.AR(seconds.to_series().rename_axis("time"), lags=2).fit()


def test_a_time_index_must_increase():
    t = pd.timedelta_range(0, periods=100, freq="10ms")
    with pytest.raises(ValueError, match=r"y has a time index that is not strictly increasing: sample 1 at 0.98 s "
                                         r"follows 0.99 s; sort it"):
        as_signal(pd.Series(np.arange(100.0), index=t[::-1]))
    with pytest.raises(ValueError, match="not strictly increasing: sample 50 at 0.49 s follows 0.49 s"):
        as_signal(pd.Series(np.arange(101.0), index=t.insert(50, t[49])))
    with pytest.raises(ValueError, match="y has a missing time stamp \\(NaT / NaN\\) at sample 3"):
        as_signal(pd.Series(np.arange(100.0), index=t.delete(3).insert(3, pd.NaT)))


def test_positions_are_not_checked():
    y = np.sin(np.arange(100.0))
    for index in (pd.RangeIndex(100), pd.Index(np.r_[np.arange(50), 1000 + np.arange(50)]), pd.Index(y[::-1])):
        assert as_signal(pd.Series(y, index=index)).nobs == 100


def _gap_jitter_frame(descending: bool = False) -> pd.DataFrame:
    """A log read as docs/guide/logs.md does (``read_csv(...).set_index("time")``): 5-15 ms steps and a 0.5 s gap."""
    rng = np.random.default_rng(29)
    t = np.cumsum(rng.uniform(0.005, 0.015, 600))
    t[300:] += 0.5
    frame = pd.DataFrame(rng.standard_normal((600, 2)), columns=["p", "q"], index=pd.Index(t, name="time"))
    return frame.iloc[::-1] if descending else frame


def test_model_fitting_follows_the_even_sampling_rule_of_the_time_index():
    """Issue 29, item 1: the models fitted across a logging gap and a jitter of a numeric "time" index silently."""
    frame = _gap_jitter_frame()
    uniform = align(frame, 100)                  # the fix the message names gives records the models accept
    for fit in (lambda: tsfdi.VAR(frame, 2).fit(), lambda: tsfdi.AR(frame["p"], 2).fit(),
                lambda: tsfdi.ARX(frame["p"], frame["q"], 2, 1).fit(),
                lambda: tsfdi.AR(uniform[0]["p"], 2).fit().residuals(frame["p"])):
        with pytest.raises(ValueError, match=r"y is not uniformly sampled: a short step of [\d.]+ s after sample \d+ "
                                             r"at [\d.]+ s \(median step .*within 10% of it\); put it on a uniform "
                                             r"grid with tsfdi.align.*or split the signal at the gap"):
            fit()
    with pytest.raises(ValueError, match=r"y is not uniformly sampled: a gap of 0.51 s after sample 299 at 2.99 s"):
        tsfdi.VAR(frame.set_axis(pd.Index(np.r_[0:300, 350:650] * 0.01, name="time")), 1).fit()
    # a list of records: each checked, the message naming the record
    good = pd.DataFrame(frame.to_numpy(), columns=["p", "q"], index=pd.Index(np.arange(600) * 0.01, name="time"))
    with pytest.raises(ValueError, match=r"y\[1\] is not uniformly sampled"):
        tsfdi.VAR([good, frame], 1).fit()
    assert tsfdi.VAR(uniform, 2).fit().nobs > 0
    assert tsfdi.VAR(good, 2).fit().nobs == 598
    # an index not named "time" carries positions and is not checked
    assert tsfdi.VAR(frame.rename_axis("t"), 2).fit().nobs == 598


def test_a_descending_time_index_is_refused_by_the_models_and_detect():
    """Issue 29, item 2: AR / detect accepted a time index that goes back."""
    frame = _gap_jitter_frame().set_axis(pd.Index(np.arange(600) * 0.01, name="time")).iloc[::-1]
    with pytest.raises(ValueError, match=r"y has a time index that is not strictly increasing: sample 1 at 5.98 s "
                                         r"follows 5.99 s"):
        tsfdi.AR(frame["p"], 2).fit()
    res = tsfdi.AR(frame["p"].to_numpy(), 2).fit()
    with pytest.raises(ValueError, match="not strictly increasing: sample 1 at 5.98 s follows 5.99 s"):
        tsfdi.detect(frame["p"], res, tsfdi.LjungBox(lags=5))
    da = xr.DataArray(frame["p"].to_numpy(), dims="time", coords={"time": frame.index.to_numpy()})
    with pytest.raises(ValueError, match="y has a time index that is not strictly increasing"):
        tsfdi.AR(da, 2).fit()


def test_an_fs_contradicting_the_time_index_is_refused():
    """Issue 29, item 3: a given fs was used silently against a DatetimeIndex (the command line refuses > 1 %)."""
    n = 500
    kinds = [pd.Series(np.sin(np.arange(n)), index=pd.date_range("2024", periods=n, freq="10ms")),
             pd.Series(np.sin(np.arange(n)), index=pd.Index(np.arange(n) * 0.01, name="time")),
             xr.DataArray(np.sin(np.arange(n)), dims="time", coords={"time": np.arange(n) * 0.01})]
    for y in kinds:
        sig = as_signal(y)
        assert sampling_frequency(sig, 100.5) == 100.5            # within 1 %: the given fs
        with pytest.raises(ValueError, match=r"fs = 50 Hz disagrees with the time index of signal.*sampled at 100 Hz "
                                             r"\(median step 0.01 s\), by more than 1%"):
            sampling_frequency(sig, 50)
    assert sampling_frequency(as_signal(np.zeros(5) + np.arange(5)), 50) == 50.0     # no time index: fs as given
    with pytest.raises(ValueError, match="fs = 50 Hz disagrees with the time index"):
        tsfdi.identify_windows(kinds[0], {"m": tsfdi.AR(np.sin(np.arange(n)) + np.cos(np.arange(n) * 0.3), 2).fit()},
                               tsfdi.LjungBox(lags=5), window="1s", fs=50)


def test_object_arrays_of_numeric_text_are_refused_like_a_string_dtype():
    """Issue 29, item 4: an object array of numeric strings was parsed as numbers."""
    text = np.array(["1.5", "2", "3", "0.5"], dtype=object)
    for data in (text, pd.Series(text), pd.Series(["1.5", "2", "3", "0.5"], dtype="string"),
                 pd.DataFrame({"a": text, "b": [1.0, 2.0, 3.0, 4.0]}), np.array([1.0, "2"], dtype=object),
                 np.array([b"1", b"2"], dtype=object)):
        with pytest.raises(TypeError, match=r"y must contain real numbers, got text \(.*\) in an object array"):
            as_signal(data)
    with pytest.raises(TypeError, match=r"y must contain real numbers, got dtype <U3"):
        as_signal(np.array(["1.5", "2", "3"]))
    with pytest.raises(TypeError, match=r"y must contain real numbers, got text"):
        tsfdi.AR(np.r_[np.arange(50.0), 3.0].astype(str).astype(object), 1)
    assert as_signal(np.array([1, 2.5, np.float32(3)], dtype=object)).values.tolist() == [[1.0], [2.5], [3.0]]


def test_a_tiny_or_huge_fs_is_refused_naming_it_before_anything_is_allocated(jittery):
    """Issue 29, item 9: align(frame, 1e-300) raised a raw OverflowError."""
    frame = jittery["imu"]
    for fs in (1e-300, 5e-324, 1e-10):
        with pytest.raises(ValueError, match=r"fs = [\de.+-]+ gives a grid period of [\de.+inf]+ ns: it must lie between "
                                             r"1 ns and 146 years"):
            align(frame, fs)
    # a grid of 10**15 points is refused before it is allocated
    long = pd.DataFrame({"a": [0.0, 1.0]}, index=pd.to_timedelta([0.0, 1e6], unit="s"))
    with pytest.raises(ValueError, match=r"fs = 1e\+09 Hz over 1e\+06 s gives 1000000000000001 x 1 values, more "
                                         r"than 268435456: lower fs"):
        align(long, 1e9)

"""read_ulog on the two shared PX4 logs (skipped when ../shared/data/px4 is missing, see ``shared_px4`` in
conftest.py), align on them, and a baseline fitted on one aligned part and tested on others; read_ulog's refusals
of bad input need no data."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from pyulog import ULog

import tsfdi
from tsfdi._data import as_signal, sampling_frequency
from tsfdi.datasets import align, read_ulog

GYRO = [f"sensor_combined.gyro_rad[{i}]" for i in range(3)]


@pytest.fixture(scope="module")
def px4(shared_px4) -> Path:
    if not (shared_px4 / "sample.ulg").is_file() or not (shared_px4 / "sample_log_small.ulg").is_file():
        raise FileNotFoundError(f"shared PX4 logs missing at {shared_px4}: tests need ../shared/data/px4/*.ulg")
    return shared_px4


@pytest.fixture(scope="module")
def sample(px4) -> dict:
    return read_ulog(px4 / "sample.ulg")


@pytest.fixture(scope="module")
def aligned(sample) -> list:
    return align({k: sample[k] for k in ("vehicle_attitude", "sensor_combined")}, 50)


def test_every_topic_of_sample_as_pyulog_reads_it(px4, sample):
    ulog = ULog(str(px4 / "sample.ulg"))
    assert list(sample) == sorted(d.name for d in ulog.data_list)
    assert len(sample) == 15
    for d in ulog.data_list:
        frame = sample[d.name]
        assert isinstance(frame.index, pd.TimedeltaIndex) and frame.index.name == "time"
        micros = d.data["timestamp"].astype(np.int64) - ulog.start_timestamp
        np.testing.assert_array_equal(frame.index.to_numpy().astype("timedelta64[us]").astype(np.int64), micros)
        assert "timestamp" not in frame.columns
        assert frame.columns.tolist() == [f for f in d.data if f != "timestamp"]
        for f in frame.columns:
            np.testing.assert_array_equal(frame[f].to_numpy(), d.data[f])
        assert frame.attrs["topic"] == d.name and frame.attrs["instance"] == 0
        assert frame.attrs["start_timestamp"] == ulog.start_timestamp


def test_sample_rates_and_fields(sample):
    combined = sample["sensor_combined"]
    assert combined.columns[:3].tolist() == ["gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]"]
    assert len(combined) == 17070
    step = np.median(np.diff(combined.index.to_numpy()) / np.timedelta64(1, "s"))
    assert step == pytest.approx(0.004, abs=1e-6)                  # 250 Hz
    att = sample["vehicle_attitude"]
    assert att.index[0] == pd.Timedelta(74131, "us") and att.index[-1] == pd.Timedelta(68988530, "us")


def test_repeated_stamps_are_kept_and_counted(sample):
    # ekf2_innovations was never stamped by its publisher (all 0): every sample is kept, at -start
    ekf = sample["ekf2_innovations"]
    assert len(ekf) == 3271 and ekf.attrs["duplicate_stamps"] == 3270 and ekf.attrs["backward_stamps"] == 0
    assert (ekf.index == pd.Timedelta(-112500176, "us")).all()
    assert sample["sensor_combined"].attrs["duplicate_stamps"] == 0


def test_dropouts_are_reported(sample):
    drops = sample["vehicle_attitude"].attrs["dropouts"]
    assert len(drops) == 4
    assert drops[-1] == (pd.Timedelta(41354932, "us"), pd.Timedelta(62, "ms"))


def test_multi_instance_keys(px4):
    logs = read_ulog(px4 / "sample_log_small.ulg")
    assert len(logs) == 70
    assert {"sensor_accel", "sensor_accel/1", "sensor_accel/2", "actuator_outputs/1"} <= set(logs)
    assert [logs[k].attrs["instance"] for k in ("sensor_accel", "sensor_accel/1", "sensor_accel/2")] == [0, 1, 2]
    assert not logs["sensor_accel"].equals(logs["sensor_accel/1"])


def test_topic_selection(px4):
    path = px4 / "sample_log_small.ulg"
    assert list(read_ulog(path, "sensor_accel")) == ["sensor_accel", "sensor_accel/1", "sensor_accel/2"]
    assert list(read_ulog(str(path), ["vehicle_angular_velocity", "sensor_accel/1"])) == [
        "vehicle_angular_velocity", "sensor_accel/1"]
    assert list(read_ulog(path, "sensor_accel/0")) == ["sensor_accel"]
    gyro = read_ulog(path, "vehicle_angular_velocity")["vehicle_angular_velocity"]
    assert gyro.columns.tolist() == ["timestamp_sample", "xyz[0]", "xyz[1]", "xyz[2]"]


@pytest.mark.parametrize("topic", ["no_such_topic", "sensor_accel/7"])
def test_unknown_topic_names_it_and_lists_the_file(px4, topic):
    with pytest.raises(ValueError, match=r"topics: '" + topic + r"' is not in .*sample_log_small.ulg; it holds "
                                         r"\['actuator_armed', .*'sensor_accel/2'"):
        read_ulog(px4 / "sample_log_small.ulg", ["vehicle_attitude", topic])


def test_bad_files_name_the_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="missing.ulg does not exist"):
        read_ulog(tmp_path / "missing.ulg")
    with pytest.raises(ValueError, match="is not a file"):
        read_ulog(tmp_path)
    empty = tmp_path / "empty.ulg"
    empty.write_bytes(b"")
    with pytest.raises(ValueError, match=r"empty.ulg is not a readable ULog file \(ULogException"):
        read_ulog(empty)
    text = tmp_path / "text.ulg"
    text.write_text("time,x\n0,1\n1,2\n")
    with pytest.raises(ValueError, match="text.ulg is not a readable ULog file"):
        read_ulog(text)


def test_cut_and_damaged_copies_of_a_log_name_the_file(tmp_path, px4):
    data = (px4 / "sample.ulg").read_bytes()
    head = tmp_path / "head.ulg"
    head.write_bytes(data[:100])
    with pytest.raises(ValueError, match="head.ulg holds no logged data"):
        read_ulog(head)
    damaged = bytearray(data)
    rng = np.random.default_rng(0)
    for i in rng.integers(100_000, len(data), 200):
        damaged[i] ^= 0xFF
    bad = tmp_path / "damaged.ulg"
    bad.write_bytes(bytes(damaged))
    with pytest.raises(ValueError, match="damaged.ulg is a damaged ULog file: pyulog found corrupt data"):
        read_ulog(bad)


def test_a_log_cut_at_its_end_reads_its_complete_messages(tmp_path, px4):
    data = (px4 / "sample.ulg").read_bytes()
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[: len(data) // 2])
    whole = read_ulog(px4 / "sample.ulg", "sensor_combined")["sensor_combined"]
    part = read_ulog(cut, "sensor_combined")["sensor_combined"]
    assert 0 < len(part) < len(whole)
    pd.testing.assert_frame_equal(part, whole.iloc[: len(part)], check_freq=False)


def test_argument_types():
    with pytest.raises(TypeError, match="path must be a str or path-like"):
        read_ulog(5)
    with pytest.raises(TypeError, match="topics must be None, a topic name or a list"):
        read_ulog(__file__, topics=5)
    with pytest.raises(ValueError, match="topics is empty"):
        read_ulog(__file__, topics=[])


def test_missing_pyulog_says_how_to_install(tmp_path, monkeypatch):
    log = tmp_path / "flight.ulg"
    log.write_bytes(b"ULog\x01\x12\x35\x01")           # never parsed: pyulog cannot be imported
    monkeypatch.setitem(sys.modules, "pyulog", None)
    with pytest.raises(ImportError, match="pip install pyulog"):
        read_ulog(log)


# --- align on the real log ---------------------------------------------------------------------------------------


def test_aligned_grid_is_uniform_and_inside_every_topic(sample, aligned):
    att, comb = sample["vehicle_attitude"], sample["sensor_combined"]
    period = pd.Timedelta("20ms")
    for r in aligned:
        assert isinstance(r.index, pd.TimedeltaIndex) and r.index.name == "time"
        assert (np.diff(r.index) == period).all()
        assert (r.index % period == pd.Timedelta(0)).all()
        assert r.index[0] >= max(att.index[0], comb.index[0]) and r.index[-1] <= min(att.index[-1], comb.index[-1])
        assert sampling_frequency(as_signal(r, allow_constant=True)) == pytest.approx(50.0)
    assert aligned[0].columns.tolist() == ([f"vehicle_attitude.{c}" for c in att.columns]
                                           + [f"sensor_combined.{c}" for c in comb.columns])


def test_aligned_values_are_the_zero_order_hold_of_the_log(sample, aligned):
    for topic in ("vehicle_attitude", "sensor_combined"):
        src = sample[topic]
        for r in aligned:
            held = src.iloc[src.index.searchsorted(r.index, side="right") - 1]
            assert (held.index <= r.index).all()
            got = r[[f"{topic}.{c}" for c in src.columns]].to_numpy()
            np.testing.assert_array_equal(got, held.to_numpy(dtype=np.float64))


def test_records_are_cut_at_the_gaps_of_the_log(sample, aligned):
    # 6 records: the logger's 62 ms dropout at 41.35 s and five 25-33 ms holes of the 250 Hz sensor_combined
    # (more than 3 of its 4 ms steps and than one 20 ms grid step)
    assert [len(r) for r in aligned] == [2060, 214, 191, 476, 237, 253]
    assert aligned[0].index[0] == pd.Timedelta("160ms") and aligned[0].index[-1] == pd.Timedelta("41.34s")
    assert aligned[1].index[0] == pd.Timedelta("41.42s")
    with pytest.raises(ValueError, match=r"frames\['vehicle_attitude'\] has a gap of 0.076 s after 0.074131 s"):
        align({k: sample[k] for k in ("vehicle_attitude", "sensor_combined")}, 50, gaps="raise")
    wide = align({k: sample[k] for k in ("vehicle_attitude", "sensor_combined")}, 50, max_gap="100ms")
    assert len(wide) == 1 and len(wide[0]) == 3444


def test_a_synthetic_one_second_gap_in_the_log(sample):
    comb = sample["sensor_combined"]
    cut = comb[(comb.index < pd.Timedelta("20s")) | (comb.index >= pd.Timedelta("21s"))]
    frames = {"vehicle_attitude": sample["vehicle_attitude"], "sensor_combined": cut}
    records = align(frames, 50, max_gap="100ms")
    assert [(r.index[0], r.index[-1]) for r in records] == [
        (pd.Timedelta("120ms"), pd.Timedelta("19.98s")), (pd.Timedelta("21.02s"), pd.Timedelta("68.98s"))]
    with pytest.raises(ValueError, match=r"frames\['sensor_combined'\] has a gap of 1.00\d* s after 19.99\d* s"):
        align(frames, 50, max_gap="100ms", gaps="raise")


def test_nan_in_the_log(sample):
    comb = sample["sensor_combined"].copy()
    comb.iloc[5000, 1] = np.nan
    frames = {"vehicle_attitude": sample["vehicle_attitude"], "sensor_combined": comb}
    with pytest.raises(ValueError, match=r"frames\['sensor_combined'\] column 'gyro_rad\[1\]' is nan at "
                                         r"20.264531 s \(sample 5000\)"):
        align(frames, 50, max_gap="100ms")
    records = align(frames, 50, max_gap="100ms", nan_policy="omit")
    assert [(r.index[0], r.index[-1]) for r in records] == [
        (pd.Timedelta("120ms"), pd.Timedelta("20.26s")), (pd.Timedelta("20.3s"), pd.Timedelta("68.98s"))]
    assert all(np.isfinite(r.to_numpy()).all() for r in records)


def test_multi_instance_topics_align_side_by_side(px4):
    logs = read_ulog(px4 / "sample_log_small.ulg", ["vehicle_angular_velocity", "vehicle_attitude"])
    records = align(logs, 100)
    assert len(records) == 1 and len(records[0]) == 633
    accel = read_ulog(px4 / "sample_log_small.ulg", "sensor_accel")     # three accelerometers at 1 Hz
    rec = align(accel, 1, max_gap="2s", min_length=2)[0]
    assert {"sensor_accel.x", "sensor_accel/1.x", "sensor_accel/2.x"} <= set(rec.columns)


# --- end to end: a baseline on one part of the log, decisions on the others ----------------------------------------


def test_fit_on_one_aligned_part_and_detect_on_others(aligned):
    # sample.ulg: the vehicle is handled for about 10 s, then lies still on the ground
    gyro = aligned[0][GYRO]
    baseline = tsfdi.VAR(gyro["12s":"26s"], lags=4).fit()
    still = tsfdi.detect(gyro["27s":"41s"], baseline, tsfdi.FTest())
    handled = tsfdi.detect(gyro[:"10s"], baseline, tsfdi.FTest())
    assert not np.any(still.reject) and np.all(still.pvalue > 0.1)
    assert np.all(handled.reject) and np.all(handled.pvalue < 1e-12)


def test_a_model_fits_on_the_list_of_records(aligned):
    records = [r[GYRO] for r in aligned[1:]]
    res = tsfdi.VAR(records, lags=2).fit()
    assert res.nobs == sum(len(r) - 2 for r in records)
    assert not np.any(tsfdi.detect(aligned[0][GYRO]["27s":"41s"], res, tsfdi.FTest()).reject)

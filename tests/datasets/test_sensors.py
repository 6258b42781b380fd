"""sensor_log: rates and stamps, noise variance, biases within spec, the attitude filter, GPS, reproducibility,
the round trip through a folder of per-topic CSV files, inject_fault on a topic, and refusals."""

import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy import stats

import tsfdi
from tsfdi.datasets.faults import inject_fault
from tsfdi.datasets.sensors import SENSOR_TOPICS, SensorSuite, sensor_log, write_sensor_log

G = 9.80665
NEEDED = ("x", "y", "z", "roll", "pitch", "yaw", "u", "v", "w", "p", "q", "r", "ax", "ay", "az",
          *SENSOR_TOPICS["commands"], *SENSOR_TOPICS["motors"])


def truth(seconds=1.0, *, fs=1000.0, **channels):
    """A synthetic true trajectory over ``time`` at ``fs``: level hover at rest unless a channel is given (a
    number or a function of the time)."""
    t = np.arange(int(round(seconds * fs)) + 1) / fs
    values = {c: 0.0 for c in NEEDED}
    values.update(z=-5.0, az=-G, collective=500.0, **{f"motor_command{i}": 500.0 + i for i in range(1, 7)})
    values.update(channels)
    data = {c: ("time", np.broadcast_to(v(t) if callable(v) else v, t.shape).astype(float))
            for c, v in values.items()}
    return xr.Dataset(data, coords={"time": t})


def quantised_var(sigma, full_scale):
    """Variance of white noise sigma after rounding to a 16-bit resolution (Sheppard's correction)."""
    return sigma**2 + (full_scale / 2**15) ** 2 / 12


# ------------------------------------------------------------------------------------------- rates and stamps
def test_topics_columns_rates_and_stamps():
    suite = SensorSuite()
    log = sensor_log(truth(2.0), rng=0)
    assert list(log) == list(SENSOR_TOPICS)
    rates = {"gyro": suite.imu_rate, "accel": suite.imu_rate, "baro": suite.baro_rate, "gps": suite.gps_rate,
             "attitude": suite.attitude_rate, "commands": suite.control_rate, "motors": suite.control_rate}
    for topic, frame in log.items():
        assert list(frame.columns) == list(SENSOR_TOPICS[topic])
        assert frame.index.name == "time" and frame.index.dtype == np.float64
        assert frame.attrs["units"] == SENSOR_TOPICS[topic]
        np.testing.assert_allclose(np.diff(frame.index), 1.0 / rates[topic], rtol=1e-9)
        assert frame.index[-1] <= 2.0 + 1e-12 and frame.index[-1] > 2.0 - 1.0 / rates[topic]
        assert np.isfinite(frame.to_numpy()).all()
    # the first stamp is one period after the record's start; the GPS's the first multiple after its latency
    assert log["gyro"].index[0] == pytest.approx(0.002) and log["baro"].index[0] == pytest.approx(0.02)
    assert log["attitude"].index[0] == pytest.approx(0.004) and log["motors"].index[0] == pytest.approx(0.004)
    assert log["gps"].index[0] == pytest.approx(0.2)
    assert len(log["gyro"]) == 1000 and len(log["gps"]) == 19


def test_record_dim_of_one_and_time_offset_are_kept():
    rec = truth(1.0).assign_coords(time=lambda d: d.time + 3.0)
    one = sensor_log(rec.expand_dims(record=[7]), rng=1)
    bare = sensor_log(rec, rng=1)
    for topic in SENSOR_TOPICS:
        pd.testing.assert_frame_equal(one[topic], bare[topic])
    assert bare["gyro"].index[0] == pytest.approx(3.002)


def test_integrating_sensors_average_each_period_digital_signals_are_copied():
    # a ramp: the boxcar mean over (t - T, t] is the ramp's value at t - (T - dt) / 2
    slope = 0.5
    suite = SensorSuite(gyro_noise_density=0.0, gyro_bias=0.0, baro_noise=0.0)
    rec = truth(1.0, q=lambda t: slope * t, z=lambda t: -2.0 * t, roll_command=lambda t: 0.1 * t)
    log = sensor_log(rec, suite, rng=0)
    t = log["gyro"].index.to_numpy()
    lsb = suite.gyro_range / 2**15
    np.testing.assert_allclose(log["gyro"]["q"], slope * (t - 0.0005), atol=lsb / 2 + 1e-12)
    tb = log["baro"].index.to_numpy()
    np.testing.assert_allclose(log["baro"]["altitude"], 2.0 * (tb - 0.0095), rtol=1e-12)
    tc = log["commands"].index.to_numpy()
    np.testing.assert_allclose(log["commands"]["roll_command"], 0.1 * tc, rtol=1e-12)
    np.testing.assert_array_equal(log["motors"].to_numpy(), np.tile(500.0 + np.arange(1, 7), (len(tc), 1)))


# ---------------------------------------------------------------------------------------------------- noise
@pytest.mark.parametrize("topic, density, full_scale, channel, value", [
    ("gyro", "gyro_noise_density", "gyro_range", "q", 0.3),
    ("accel", "accel_noise_density", "accel_range", "ay", 1.7),
])
def test_white_noise_variance_is_density_times_half_the_rate(topic, density, full_scale, channel, value):
    """Monte Carlo: (K - 1) s^2 / sigma^2 is chi-square with K - 1 degrees of freedom, sigma^2 = N_D^2 f / 2 plus
    the rounding's LSB^2 / 12; at a fixed seed it lies inside the central 99.8 %."""
    suite = SensorSuite()
    log = sensor_log(truth(10.0, **{channel: value}), suite, rng=0)
    y = log[topic][channel].to_numpy()
    var = quantised_var(getattr(suite, density) * math.sqrt(suite.imu_rate / 2), getattr(suite, full_scale))
    stat = (len(y) - 1) * y.var(ddof=1) / var
    lo, hi = stats.chi2.ppf([0.001, 0.999], len(y) - 1)
    assert lo < stat < hi
    # twice the density gives four times the noise variance (the formula, not the rounding)
    loud = sensor_log(truth(10.0, **{channel: value}), SensorSuite(**{density: 10 * getattr(suite, density)}),
                      rng=0)[topic][channel].to_numpy()
    var10 = quantised_var(10 * getattr(suite, density) * math.sqrt(suite.imu_rate / 2), getattr(suite, full_scale))
    assert lo < (len(y) - 1) * loud.var(ddof=1) / var10 < hi


def test_baro_noise_is_its_rms():
    suite = SensorSuite()
    alt = sensor_log(truth(60.0), suite, rng=5)["baro"]["altitude"].to_numpy()
    stat = ((alt - 5.0) ** 2).sum() / suite.baro_noise**2          # mean known: chi-square with K dof
    assert stats.chi2.ppf(0.001, len(alt)) < stat < stats.chi2.ppf(0.999, len(alt))
    assert suite.baro_noise == pytest.approx(0.0999, abs=1e-4)      # 1.2 Pa at rho g = 12.01 Pa/m


# ----------------------------------------------------------------------------------------------------- bias
def test_turn_on_biases_are_constant_within_spec_and_spread_over_it():
    suite = SensorSuite()
    rec = truth(0.6, p=0.1, ax=0.5)
    gyro_off, accel_off = [], []
    for seed in range(60):
        log = sensor_log(rec, suite, rng=seed)
        gyro_off.append(log["gyro"]["p"].mean() - 0.1)
        accel_off.append(log["accel"]["ax"].mean() - 0.5)
    gyro_off, accel_off = np.array(gyro_off), np.array(accel_off)
    k = len(log["gyro"])
    tol_g = 4 * math.sqrt(quantised_var(suite.gyro_noise_density * math.sqrt(suite.imu_rate / 2),
                                        suite.gyro_range) / k)
    tol_a = 4 * math.sqrt(quantised_var(suite.accel_noise_density * math.sqrt(suite.imu_rate / 2),
                                        suite.accel_range) / k)
    assert np.abs(gyro_off).max() <= suite.gyro_bias + tol_g
    assert np.abs(accel_off).max() <= suite.accel_bias + tol_a
    # uniform within the spec: some near its edge, both signs
    assert np.abs(gyro_off).max() > 0.8 * suite.gyro_bias and gyro_off.min() < 0 < gyro_off.max()
    assert np.abs(accel_off).max() > 0.8 * suite.accel_bias and accel_off.min() < 0 < accel_off.max()


def test_zero_spec_gives_no_bias_and_the_bias_is_constant_in_a_record():
    suite = SensorSuite(gyro_noise_density=0.0, accel_noise_density=0.0)
    log = sensor_log(truth(1.0, p=0.1), suite, rng=3)
    assert log["gyro"]["p"].nunique() == 1                 # constant rate + constant bias, no noise
    assert abs(log["gyro"]["p"].iloc[0] - 0.1) <= suite.gyro_bias + suite.gyro_range / 2**16
    flat = sensor_log(truth(1.0, p=0.1), SensorSuite(gyro_noise_density=0.0, gyro_bias=0.0), rng=3)
    assert abs(flat["gyro"]["p"].iloc[0] - 0.1) <= suite.gyro_range / 2**16


def test_range_saturates_and_rounds_to_16_bits():
    suite = SensorSuite(gyro_noise_density=0.0, gyro_bias=0.0)
    log = sensor_log(truth(0.5, r=100.0, q=0.0123456), suite, rng=0)
    lsb = suite.gyro_range / 2**15
    assert (log["gyro"]["r"] == (2**15 - 1) * lsb).all()                 # beyond 2000 dps: clipped
    np.testing.assert_allclose(log["gyro"]["q"] / lsb, np.round(0.0123456 / lsb), rtol=1e-12)


# ------------------------------------------------------------------------------------------------- attitude
def test_attitude_tracks_a_constant_yaw_rate_and_a_level_hover():
    rate = 0.4
    rec = truth(10.0, r=rate, yaw=lambda t: rate * t)
    att = sensor_log(rec, rng=4)["attitude"]
    t = att.index.to_numpy()
    np.testing.assert_allclose(att["yaw"], rate * t, atol=0.02)          # unwrapped beyond pi
    assert att["yaw"].iloc[-1] > 3.5
    assert np.abs(att[["roll", "pitch"]].to_numpy()).max() < 0.01


def test_attitude_filter_corrects_with_the_accelerometer_at_its_documented_speed():
    """The filter starts at the truth's first sample: a first roll of 0.2 rad over a level hover is a wrong
    initial estimate, which the accelerometer correction (ATT_W_ACC = 0.2 /s, with the bias loop ATT_W_GYRO_BIAS)
    removes in tens of seconds, not at once: a filter, not the truth plus noise."""
    rec = truth(30.0, roll=lambda t: np.where(t == 0.0, 0.2, 0.0))
    att = sensor_log(rec, SensorSuite(gyro_bias=0.0, accel_bias=0.0), rng=6)["attitude"]["roll"]
    assert att.loc[1.0] > 0.15                                          # slow: about e^{-0.2 s}
    assert abs(att.loc[25.0:].mean()) < 0.02                            # corrected
    fast = sensor_log(rec, SensorSuite(gyro_bias=0.0, accel_bias=0.0, attitude_accel_weight=1.0),
                      rng=6)["attitude"]["roll"]
    assert fast.loc[3.0] < att.loc[3.0] / 2                             # the gain sets the speed


def test_attitude_starts_with_the_gyro_bias_learned_and_an_accelerometer_bias_tilts_it():
    # the estimator starts with the turn-on gyro bias learned: no drift in hover whatever that bias
    att = sensor_log(truth(20.0), SensorSuite(gyro_bias=0.04, accel_bias=0.0), rng=8)["attitude"]
    assert np.abs(att[["roll", "pitch"]].to_numpy()).max() < 0.002
    assert np.abs(att["yaw"].to_numpy()).max() < 0.01
    # an accelerometer bias b is a tilt of the measured gravity: the level estimate settles about b / g off
    suite = SensorSuite(gyro_bias=0.0)
    log = sensor_log(truth(40.0), suite, rng=8)
    bias = log["accel"].loc[:, ["ax", "ay"]].mean().to_numpy()
    settled = log["attitude"].loc[30.0:, ["roll", "pitch"]].mean().to_numpy()
    np.testing.assert_allclose(settled, [-bias[1] / G, bias[0] / G], atol=3e-4)     # f = g (sin theta, -sin phi)
    assert np.abs(settled).max() > 1e-3


# ------------------------------------------------------------------------------------------------------ GPS
def test_gps_velocity_is_rotated_into_ned_and_delayed():
    # heading east (yaw pi/2), flying forward at 5 m/s and climbing: vn 0, ve 5, vd -1
    suite = SensorSuite()
    rec = truth(5.0, yaw=np.pi / 2, u=5.0, w=-1.0, y=lambda t: 5.0 * t, z=lambda t: -5.0 - t)
    gps = sensor_log(rec, suite, rng=9)["gps"]
    v = gps[["vn", "ve", "vd"]].to_numpy()
    sd = suite.gps_velocity_std * np.array([1.0, 1.0, suite.gps_vertical_factor])
    np.testing.assert_allclose(v.mean(axis=0), [0.0, 5.0, -1.0], atol=4 * sd.max() / math.sqrt(len(v)))
    resid = (v - [0.0, 5.0, -1.0]) / sd
    stat = (resid**2).sum()
    assert stats.chi2.ppf(0.001, resid.size) < stat < stats.chi2.ppf(0.999, resid.size)
    # the position error is slow (Gauss-Markov, 60 s): east minus the truth 110 ms earlier barely moves
    t = gps.index.to_numpy()
    err = gps["east"].to_numpy() - 5.0 * (t - suite.gps_latency)
    assert np.abs(np.diff(err)).max() < 0.5 and np.abs(err).max() < 5 * suite.gps_position_std
    exact = sensor_log(rec, SensorSuite(gps_velocity_std=0.0, gps_position_std=0.0), rng=9)["gps"]
    np.testing.assert_allclose(exact["east"], 5.0 * (t - 0.11), atol=1e-9)
    np.testing.assert_allclose(exact["down"], -5.0 - (t - 0.11), atol=1e-9)
    np.testing.assert_allclose(exact[["vn", "ve", "vd"]], np.tile([0.0, 5.0, -1.0], (len(t), 1)), atol=1e-12)


# -------------------------------------------------------------------------------------------- reproducibility
def test_same_seed_same_log_other_seed_other_log():
    rec = truth(1.0, p=0.2)
    a, b, c = sensor_log(rec, rng=11), sensor_log(rec, rng=np.random.default_rng(11)), sensor_log(rec, rng=12)
    for topic in SENSOR_TOPICS:
        pd.testing.assert_frame_equal(a[topic], b[topic])
    assert not np.array_equal(a["gyro"].to_numpy(), c["gyro"].to_numpy())
    pd.testing.assert_frame_equal(a["motors"], c["motors"])                 # copied: no randomness


# ---------------------------------------------------------------------------------- read like a real log
def test_written_folder_reads_back_with_read_records(tmp_path):
    log = sensor_log(truth(3.0, q=0.1), rng=13)
    files = write_sensor_log(tmp_path / "flight", log)
    assert [f.name for f in files] == [f"{t}.csv" for t in SENSOR_TOPICS]
    back = pd.read_csv(files[0], index_col="time")
    pd.testing.assert_frame_equal(back, log["gyro"], check_exact=True, check_flags=False)
    rec = tsfdi.read_records(tmp_path / "flight", topics=["gyro", "baro", "gps"], fs=50)
    assert rec.channels == ("gyro.p", "gyro.q", "gyro.r", "baro.altitude", "gps.vn", "gps.ve", "gps.vd",
                            "gps.north", "gps.east", "gps.down")
    assert round(rec.fs) == 50 and len(rec.values) == 1
    frame = rec.frames()[0]
    # zero-order hold: each grid time holds the last sample stamped at or before it
    t = frame.index.to_numpy()[5]
    held = log["gyro"]["q"].loc[:t + 1e-9].iloc[-1]
    assert frame["gyro.q"].iloc[5] == pytest.approx(held, abs=1e-12)
    with pytest.raises(ValueError, match="already exists"):
        write_sensor_log(tmp_path / "flight", log)


def test_write_sensor_log_refuses_bad_logs(tmp_path):
    log = sensor_log(truth(0.5), rng=0)
    with pytest.raises(TypeError, match="log"):
        write_sensor_log(tmp_path, [log["gyro"]])
    with pytest.raises(ValueError, match="no topic"):
        write_sensor_log(tmp_path, {})
    with pytest.raises(ValueError, match="time"):
        write_sensor_log(tmp_path, {"gyro": log["gyro"].reset_index(drop=True)})
    with pytest.raises(ValueError, match="plain file name"):
        write_sensor_log(tmp_path, {"../gyro": log["gyro"]})
    assert not list(tmp_path.iterdir())                                 # nothing written on a refusal


def test_inject_fault_on_a_topic_column():
    gyro = sensor_log(truth(5.0, q=0.05), rng=14)["gyro"]
    rng30 = math.radians(30.0)                                           # paper 004's 30 deg/s
    faulty, labels = inject_fault(gyro, "hard", 0.05, "2s", channel="q", sensor_range=rng30)
    assert isinstance(faulty, pd.DataFrame) and faulty.index.equals(gyro.index)
    d = (faulty - gyro).to_numpy()
    np.testing.assert_array_equal(d[:, [0, 2]], 0.0)
    first = int(np.argmax(labels.to_numpy()))
    assert gyro.index[first] == pytest.approx(2.0 + gyro.index[0])       # "2s" from the first sample
    n_ramp = int(round(1.0 * 500))                                       # hard fault: 1 s ramp at 500 Hz
    np.testing.assert_allclose(d[first + n_ramp - 1:, 1], 0.05 * rng30, rtol=1e-9)
    assert (d[:first, 1] == 0).all() and labels.name == "fault"


# ------------------------------------------------------------------------------------------------- refusals
def test_refuses_a_record_not_at_1khz():
    with pytest.raises(ValueError, match=r"record is sampled at 100 Hz.*fs=1000"):
        sensor_log(truth(2.0, fs=100.0))


def test_refuses_a_missing_channel_naming_it():
    with pytest.raises(ValueError, match=r"record has no channel 'az'"):
        sensor_log(truth(1.0).drop_vars("az"))
    with pytest.raises(ValueError, match=r"'motor_command3'"):
        sensor_log(truth(1.0).drop_vars("motor_command3"))


def test_refuses_other_records():
    with pytest.raises(TypeError, match="record"):
        sensor_log(truth(1.0).to_dataframe())
    with pytest.raises(ValueError, match=r"record must be one record: it has 2"):
        sensor_log(xr.concat([truth(1.0), truth(1.0)], dim="record"))
    with pytest.raises(ValueError, match=r"'q' is NaN or infinite from t = 0.5 s"):
        sensor_log(truth(1.0, q=lambda t: np.where(t >= 0.5, np.nan, 0.0)))
    with pytest.raises(ValueError, match="record is too short"):
        sensor_log(truth(0.1))
    with pytest.raises(TypeError, match="suite"):
        sensor_log(truth(1.0), {"imu_rate": 500})
    with pytest.raises(TypeError, match="rng"):
        sensor_log(truth(1.0), rng="seed")


@pytest.mark.parametrize("field, value, error, match", [
    ("imu_rate", 300.0, ValueError, "imu_rate must divide"),
    ("imu_rate", 0.0, ValueError, "imu_rate must be a finite positive"),
    ("attitude_rate", 300.0, ValueError, "attitude_rate must divide imu_rate"),
    ("gps_rate", 3.0, ValueError, "gps_rate must divide"),
    ("gyro_noise_density", -1e-3, ValueError, "gyro_noise_density must be a finite non-negative"),
    ("accel_range", 0.0, ValueError, "accel_range must be a finite positive"),
    ("baro_noise", float("nan"), ValueError, "baro_noise must be a finite"),
    ("gps_latency", 0.0005, ValueError, "gps_latency must be a whole number of milliseconds"),
    ("gyro_bias", "0.1", TypeError, "gyro_bias must be a real number"),
    ("heading_noise", True, TypeError, "heading_noise must be a real number"),
])
def test_suite_refuses_bad_fields(field, value, error, match):
    with pytest.raises(error, match=match):
        SensorSuite(**{field: value})


def test_suite_is_frozen_and_its_defaults_are_the_cited_values():
    suite = SensorSuite()
    with pytest.raises(AttributeError):
        suite.imu_rate = 1000.0
    assert math.degrees(suite.gyro_noise_density) == pytest.approx(2.8e-3)   # ICM-42688-P, mdps/sqrt(Hz)
    assert suite.accel_noise_density / G == pytest.approx(70e-6)             # ICM-42688-P, g/sqrt(Hz)
    assert math.degrees(suite.gyro_range) == pytest.approx(2000.0) and suite.accel_range / G == pytest.approx(16)
    assert suite.gps_velocity_std * 0.6745 == pytest.approx(0.05)            # NEO-M8N, 50 %
    assert suite.gps_position_std * 1.1774 == pytest.approx(2.5)             # NEO-M8N, CEP
    assert suite.imu_rate >= 250


# ------------------------------------------------------------------------------- on the simulated hexacopter
@pytest.fixture(scope="module")
def hover():
    """Two 5 s records of the simulator at 1 kHz hovering: calm and in severe turbulence."""
    from tsfdi.datasets import simulate_hexacopter

    return simulate_hexacopter(duration=5.0, fs=1000, turbulence=["none", "severe"], speed=0.0, seed=[1, 2])


def boxcar(series, n, index):
    """The mean of the 1 kHz truth over the n samples ending at each stamp of ``index``."""
    return series.rolling(n).mean().loc[index].to_numpy()


@pytest.mark.parametrize("i", [0, 1])
def test_on_a_simulated_record_the_sensors_read_the_truth(hover, i):
    suite = SensorSuite()
    rec = hover.isel(record=[i])                                     # a record dim of length 1 is accepted
    truth_ = rec.isel(record=0).to_dataframe()
    log = sensor_log(rec, suite, rng=21)
    k = len(log["gyro"])
    sd_g = math.sqrt(quantised_var(suite.gyro_noise_density * math.sqrt(suite.imu_rate / 2), suite.gyro_range))
    sd_a = math.sqrt(quantised_var(suite.accel_noise_density * math.sqrt(suite.imu_rate / 2), suite.accel_range))
    # the gyroscope's mean is the true rates' mean within its turn-on bias and noise
    off = log["gyro"].mean().to_numpy() - truth_[["p", "q", "r"]].mean().to_numpy()
    assert np.abs(off).max() <= suite.gyro_bias + 4 * sd_g / math.sqrt(k)
    # the accelerometer reads the true specific force, and about (0, 0, -g) in hover (NED body axes)
    acc = log["accel"].mean().to_numpy()
    off = acc - truth_[["ax", "ay", "az"]].mean().to_numpy()
    assert np.abs(off).max() <= suite.accel_bias + 4 * sd_a / math.sqrt(k)
    if i == 0:  # in calm hover; in severe gusts the rotor drag moves the mean specific force by ~1 m/s^2 in 5 s
        np.testing.assert_allclose(acc, [0.0, 0.0, -G], atol=suite.accel_bias + 0.02)
    # barometric altitude = -z within its RMS noise (chi-square, mean known)
    baro = log["baro"]
    err = baro["altitude"].to_numpy() + boxcar(truth_["z"], 20, baro.index)
    stat = (err**2).sum() / suite.baro_noise**2
    assert stats.chi2.ppf(0.001, len(err)) < stat < stats.chi2.ppf(0.999, len(err))


def test_on_a_simulated_record_the_attitude_filter_tracks_roll_and_pitch(hover):
    """Calibrated sensors (no turn-on biases): in calm hover the estimate is the truth within 1 mrad; in severe
    turbulence the accelerometer correction is pulled by the gust accelerations (PX4 compensates them with GPS,
    not modelled): within 0.03 rad and its error RMS below half the true attitude's standard deviation."""
    suite = SensorSuite(gyro_bias=0.0, accel_bias=0.0)
    for i, (worst, share) in enumerate([(1e-3, None), (0.03, 0.5)]):
        rec = hover.isel(record=i)
        log = sensor_log(rec, suite, rng=22)
        att = log["attitude"]
        true = rec[["roll", "pitch", "yaw"]].to_dataframe().loc[att.index, ["roll", "pitch", "yaw"]]
        err = att.to_numpy() - true.to_numpy()
        assert np.abs(err).max() < worst
        if share is not None:
            rms = np.sqrt((err[:, :2] ** 2).mean(axis=0))
            assert (rms < share * true[["roll", "pitch"]].std().to_numpy()).all()
            assert np.corrcoef(att["pitch"], true["pitch"])[0, 1] > 0.9

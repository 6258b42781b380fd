"""Paper 004's residual evaluation: eq. 6 and residual padding against hand computations and the paper's own
example, alarms, calibration, streaming, the errors of online models, data kinds and bad input."""

import numpy as np
import pandas as pd
import pytest

import tsfdi
from tsfdi import EmpiricalThreshold, RecursiveARX
from tsfdi.detection.moving import MovingSquaredError, MovingSquaredErrorStream
from tsfdi.models.emran import EMRAN
from conftest import as_kind, assert_kind
from _scripts import load_script


def test_exported():
    assert tsfdi.detection.MovingSquaredError is MovingSquaredError
    assert tsfdi.detection.MovingSquaredErrorStream is MovingSquaredErrorStream


def test_eq6_by_hand():
    # r_i = w * sum_{j=i-M+1}^{i} e_j^2 / M with M = 2, w = 2
    r = MovingSquaredError(2, weight=2.0).statistic(np.array([1.0, 2.0, 3.0, -4.0]))
    np.testing.assert_array_equal(r, [np.nan, 2 * (1 + 4) / 2, 2 * (4 + 9) / 2, 2 * (9 + 16) / 2])


def test_padding_by_hand():
    # squared errors [4, 1, 9] in a window of 3, padded with 3 copies of their minimum 1: (14 + 3) / 6
    r = MovingSquaredError(3, padding=3).statistic(np.array([2.0, -1.0, 3.0]))
    assert r[2] == 17.0 / 6.0
    # padding with P points: w (sum + P min) / (M + P), every window
    rng = np.random.default_rng(0)
    e = rng.standard_normal(50)
    r = MovingSquaredError(5, padding=2, weight=3.0).statistic(e)
    for i in range(4, 50):
        s = e[i - 4:i + 1] ** 2
        assert r[i] == pytest.approx(3.0 * (s.sum() + 2 * s.min()) / 7.0, rel=1e-14)


def test_paper_004_padding_example():
    """Section IV.B: threshold 5, two padding points; noise spike {24 0 0 0}: mean 6 without padding (false alarm),
    4 with; fault {6 6 6 6}: 6 either way (detected)."""
    spike = np.sqrt([24.0, 0.0, 0.0, 0.0])
    fault = np.sqrt([6.0, 6.0, 6.0, 6.0])
    plain = MovingSquaredError(4, threshold=5.0)
    padded = MovingSquaredError(4, threshold=5.0, padding=2)
    assert plain.statistic(spike)[-1] == pytest.approx(6.0) and padded.statistic(spike)[-1] == pytest.approx(4.0)
    assert plain.statistic(fault)[-1] == pytest.approx(6.0) and padded.statistic(fault)[-1] == pytest.approx(6.0)
    assert plain.test(spike).reject and not padded.test(spike).reject
    assert plain.test(fault).reject and padded.test(fault).reject


def test_decision_and_alarms():
    e = np.r_[np.zeros(10), np.full(5, 3.0), np.zeros(10)]
    d = MovingSquaredError(2, threshold=4.0).test(e)
    # r = 4.5 when one of the two squared errors is 9, 9 when both: alarms at 10..15
    np.testing.assert_array_equal(d.details["alarms"][0], np.arange(10, 16))
    assert d.reject and d.details["first_alarm"].tolist() == [10]
    assert d.statistic[0] == 9.0 and d.threshold[0] == 4.0 and np.isnan(d.pvalue[0]) and np.isnan(d.alpha)
    assert d.details["alarm_rate"][0] == pytest.approx(6 / 24)        # 24 evaluated samples (the first is NaN)
    np.testing.assert_array_equal(d.details["alarm"], np.isin(np.arange(25), np.arange(10, 16)))
    assert d.test == "MovingSquaredError" and d.details["window"] == 2


def test_vector_residual_per_channel():
    e = np.column_stack([np.zeros(20), np.r_[np.zeros(15), np.ones(5) * 2]])
    d = MovingSquaredError(3, threshold=1.0, padding=3).test(e)
    # window [0, 4, 4] padded with three 0: 8 / 6 > 1 at sample 16
    assert d.channel_reject.tolist() == [False, True] and d.details["first_alarm"].tolist() == [-1, 16]


def test_nan_errors_give_nan_windows_and_no_alarm():
    e = np.array([np.nan, np.nan, 1.0, 1.0, 1.0, np.nan, 1.0, 1.0, 1.0])
    d = MovingSquaredError(3, threshold=0.5).test(e)
    r = np.asarray(d.details["r"])
    np.testing.assert_array_equal(np.isnan(r), [True, True, True, True, False, True, True, True, False])
    np.testing.assert_array_equal(d.details["alarms"][0], [4, 8])


def test_works_on_the_errors_of_online_models():
    rng = np.random.default_rng(1)
    n = 3000
    u = rng.standard_normal(n)
    y = 0.8 * u + 0.05 * rng.standard_normal(n)
    y[2000:] += 0.5                                       # a bias fault at 2000
    det = MovingSquaredError(20, threshold=0.15, padding=20)
    rarx = RecursiveARX(0, 1, 0, 0.999).run(y, u)          # NaN-free here, a start-up NaN would be skipped
    net = EMRAN(1)
    trained = net.run(u[:1500], y[:1500]).resid
    net.freeze()                                          # trained online, then frozen (an online EMRAN learns a bias)
    emran = np.r_[trained, net.run(u[1500:], y[1500:]).resid]
    for resid in (rarx.resid, emran):
        alarm = np.asarray(det.test(resid).details["alarm"])
        assert not alarm[500:2000].any()                  # after the models' start-up, none before the fault
        assert 2000 <= 500 + np.argmax(alarm[500:]) < 2020
    with_nan = RecursiveARX(2, 1, 0).run(y, u).resid        # first two errors NaN (incomplete regressor)
    assert np.isnan(np.asarray(det.statistic(with_nan))[:21]).all()


def test_calibrate_with_empirical_threshold():
    rng = np.random.default_rng(2)
    healthy = rng.standard_normal(20000)
    det = MovingSquaredError(10, threshold=EmpiricalThreshold(1e-2)).calibrate(healthy)
    r = np.asarray(MovingSquaredError(10).statistic(healthy))
    assert det.threshold_ == pytest.approx(np.quantile(r[9:], 1 - 1e-2))      # the empirical quantile, NaN left out
    d = det.test(rng.standard_normal(20000))
    assert d.alpha == 1e-2 and 0.002 < d.details["alarm_rate"][0] < 0.03
    with pytest.raises(TypeError, match="calibrate needs threshold=EmpiricalThreshold"):
        MovingSquaredError(10, threshold=1.0).calibrate(healthy)


def test_stream_equals_batch():
    rng = np.random.default_rng(3)
    e = rng.standard_normal((200, 2))
    e[50, 0] = np.nan
    det = MovingSquaredError(7, threshold=1.5, padding=4, weight=2.0)
    batch = np.asarray(det.statistic(e))
    st = det.stream(nchan=2)
    out = np.array([st.update(row) for row in e])
    np.testing.assert_array_equal(out, batch)
    first = det.test(e).details["first_alarm"]
    assert st.first_alarm == min(f for f in first if f >= 0)
    assert isinstance(st, MovingSquaredErrorStream) and st.k == 200


def test_time_span_window_and_kinds(kind):
    e = np.r_[np.zeros(300), np.ones(100)]
    det = MovingSquaredError("0.5s", threshold=0.5, padding=10)
    if kind == "numpy":
        with pytest.raises(ValueError, match="sampling frequency is unknown"):
            det.statistic(e)
        det = MovingSquaredError("0.5s", threshold=0.5, padding=10, fs=100.0)
    r = det.statistic(as_kind(e, kind))
    assert_kind(r, kind, 1)
    r = np.asarray(r)
    assert np.isnan(r[:49]).all() and np.isfinite(r[49:]).all()          # 0.5 s at 100 Hz = 50 samples
    d = MovingSquaredError("0.5s", threshold=0.5, padding=10, fs=100.0).test(e)
    # k ones in the 50-sample window (minimum 0): k / 60 > 0.5 from k = 31
    assert d.details["window"] == 50 and d.details["first_alarm"][0] == 300 + 30


def test_pandas_alarm_series_keeps_the_index():
    idx = pd.date_range("2024-01-01", periods=30, freq="50ms")
    e = pd.Series(np.r_[np.zeros(20), np.ones(10)], index=idx)
    d = MovingSquaredError(4, threshold=0.5).test(e)
    assert isinstance(d.details["alarm"], pd.Series) and d.details["alarm"].index.equals(idx)
    assert d.details["first_alarm_label"][0] == idx[22]


@pytest.mark.parametrize("call, exc, match", [
    (lambda: MovingSquaredError(0), ValueError, "window must be >= 1"),
    (lambda: MovingSquaredError(2.5), TypeError, "window must be an int"),
    (lambda: MovingSquaredError(3, padding=-1), ValueError, "padding must be >= 0"),
    (lambda: MovingSquaredError(3, weight=0.0), ValueError, "weight must be > 0"),
    (lambda: MovingSquaredError(3, threshold="high"), TypeError, "threshold must be a real number"),
    (lambda: MovingSquaredError(3).test(np.zeros(10)), ValueError, "threshold is None"),
    (lambda: MovingSquaredError(30, threshold=1.0).test(np.zeros(10)), ValueError, "resid is too short: 10"),
    (lambda: MovingSquaredError(3, threshold=1.0).test(np.r_[0.0, np.inf, 0.0]), ValueError, "resid contains 1 inf"),
    (lambda: MovingSquaredError(3, threshold=1.0).test(["a", "b", "c"]), TypeError, "resid must contain real"),
    (lambda: MovingSquaredError("1s", threshold=1.0).stream(), ValueError, "give MovingSquaredError fs"),
    (lambda: MovingSquaredError(3, threshold=1.0).stream().update([1.0, 2.0]), ValueError, "x must hold 1"),
    (lambda: MovingSquaredError(3, threshold=1.0).stream().update(np.inf), ValueError, "x contains inf"),
    (lambda: MovingSquaredError(3, threshold=1.0).stream().update(True), TypeError, "x must be a number"),
])
def test_bad_input_names_the_argument(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


def test_alfa_benchmark_protocol(shared_alfa):
    """benchmarks/alfa_sensor_validation.py: fitting, calibration and held-out flights are disjoint (9 without
    failure, 18 + 18 pre-failure parts), the gyro's declared sensor noise is 0.02 deg/s, the added noise of a
    configuration is one draw per gyro update, and a record's statistic is the test's on its prediction errors."""
    bench = load_script("benchmarks/alfa_sensor_validation.py")
    root = shared_alfa
    fit, calibration, held, names = bench.setup(root)
    assert (len(fit), len(calibration), len(held)) == (9, 18, 18)
    assert not set(names["calibration"]) & set(names["held-out"]) and len(set(sum(names.values(), []))) == 45
    assert not any(f.isna().any().any() for f in fit + calibration + held)
    assert min(len(f) for f in calibration + held) > (bench.ARM_S + bench.LEAD_S + 20) * bench.FS
    assert abs(np.degrees(bench.sensor_noise(root)) - 0.02) < 1e-6
    q = held[0]["q"].to_numpy()
    noisy = bench.gyro(held[0], 10.0, 1e-3, 1)
    updates = np.r_[True, np.diff(q) != 0]
    assert np.all(np.diff(noisy - q)[~updates[1:]] == 0)          # held between the gyro's updates
    assert 0.5e-3 * np.sqrt(99) < np.std((noisy - q)[updates]) < 1.5e-3 * np.sqrt(99)

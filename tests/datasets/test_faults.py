"""inject_fault: every fault kind exact by construction, labels, reproducibility, data kinds and bad input."""

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from tsfdi.datasets.faults import FAULT_KINDS, inject_fault
from conftest import as_kind, assert_kind, to_numpy

FS = 20.0


@pytest.fixture
def y():
    t = np.arange(400) / FS
    return np.sin(t) + 0.3 * np.cos(3.1 * t)


def offset(y, kind, mag, start, **kw):
    faulty, labels = inject_fault(y, kind, mag, start, fs=FS, **kw)
    return faulty - y, labels


def test_bias_is_a_step_of_magnitude_times_range(y):
    d, lab = offset(y, "bias", 0.2, 100)
    a = 0.2 * (y.max() - y.min())
    np.testing.assert_array_equal(d[:100], 0.0)
    np.testing.assert_allclose(d[100:], a, rtol=1e-12)
    np.testing.assert_array_equal(lab, np.arange(400) >= 100)


@pytest.mark.parametrize("kind, seconds", [("hard", 1.0), ("soft", 4.0)])
def test_additive_ramps_of_paper_004(y, kind, seconds):
    d, lab = offset(y, kind, 0.05, 100, sensor_range=np.radians(30.0))      # paper 004: 5 % of 30 deg/s
    a = 0.05 * np.radians(30.0)
    n_ramp = int(seconds * FS)
    k = np.arange(300)
    np.testing.assert_allclose(d[100:], a * np.minimum((k + 1) / n_ramp, 1.0), rtol=1e-12, atol=1e-15)
    assert d[100 + n_ramp - 2] < a and d[100 + n_ramp - 1] == pytest.approx(a)
    np.testing.assert_array_equal(d[:100], 0.0)


def test_ramp_override_and_one_sample_ramp_is_a_step(y):
    d_step, _ = offset(y, "hard", 0.1, 50, ramp=1)
    d_bias, _ = offset(y, "bias", 0.1, 50)
    np.testing.assert_array_equal(d_step, d_bias)
    d, _ = offset(y, "soft", 0.1, 50, ramp="0.5s")                            # 10 samples
    np.testing.assert_allclose(d[50:61], 0.1 * np.ptp(y) * np.minimum(np.arange(1, 12) / 10, 1.0), rtol=1e-12)


def test_drift_reaches_the_magnitude_at_the_end_of_the_fault(y):
    d, lab = offset(y, "drift", -0.1, 200, duration=100)
    a = -0.1 * np.ptp(y)
    np.testing.assert_allclose(d[200:300], a * np.arange(1, 101) / 100, rtol=1e-12)
    np.testing.assert_array_equal(d[300:], 0.0)                                # fault-free again after it
    np.testing.assert_array_equal(lab, (np.arange(400) >= 200) & (np.arange(400) < 300))
    d2, _ = offset(y, "drift", -0.1, 200, ramp=50)                             # unbounded: 2 A at 100 samples
    assert d2[299] == pytest.approx(2 * a)


def test_stuck_holds_the_last_healthy_value(y):
    faulty, lab = inject_fault(y, "stuck", 0.0, 150)
    np.testing.assert_array_equal(faulty[150:], y[149])
    np.testing.assert_array_equal(faulty[:150], y[:150])
    faulty, _ = inject_fault(y, "stuck", 0.5, 0, sensor_range=2.0)
    np.testing.assert_array_equal(faulty, y[0] + 1.0)


def test_noise_is_reproducible_from_rng(y):
    d1, _ = offset(y, "noise", 0.1, 100, rng=7)
    d2, _ = offset(y, "noise", 0.1, 100, rng=np.random.default_rng(7))
    np.testing.assert_array_equal(d1, d2)
    np.testing.assert_allclose(d1[100:], 0.1 * np.ptp(y) * np.random.default_rng(7).standard_normal(300), rtol=1e-12)
    np.testing.assert_array_equal(d1[:100], 0.0)
    d3, _ = offset(y, "noise", 0.1, 100, rng=8)
    assert not np.array_equal(d1, d3)


def test_time_span_start_and_duration_from_the_index(kind):
    values = np.sin(np.arange(300) / 10.0)
    sig = as_kind(values, kind)                  # pandas: 10 ms DatetimeIndex; xarray: time in s (100 Hz)
    if kind == "numpy":
        with pytest.raises(ValueError, match="start = '1s' is a time span but the sampling frequency is unknown"):
            inject_fault(sig, "bias", 0.1, "1s")
        faulty, labels = inject_fault(sig, "bias", 0.1, "1s", duration="0.5s", fs=100.0)
    else:
        faulty, labels = inject_fault(sig, "bias", 0.1, "1s", duration="0.5s")
    assert_kind(faulty, kind, 1)
    assert_kind(labels, kind, 1)
    np.testing.assert_array_equal(to_numpy(labels), (np.arange(300) >= 100) & (np.arange(300) < 150))
    if kind == "pandas":
        assert faulty.index.equals(sig.index) and labels.name == "fault" and labels.dtype == bool


def test_one_channel_of_a_vector_signal():
    values = np.random.default_rng(0).standard_normal((50, 3))
    df = pd.DataFrame(values, columns=["p", "q", "r"])
    faulty, labels = inject_fault(df, "bias", 0.5, 10, channel="q", sensor_range=1.0)
    assert list(faulty.columns) == ["p", "q", "r"]
    diff = faulty.to_numpy() - values
    np.testing.assert_array_equal(diff[:, [0, 2]], 0.0)
    np.testing.assert_allclose(diff[10:, 1], 0.5)
    da = xr.DataArray(values, dims=("time", "channel"), coords={"channel": ["p", "q", "r"]})
    f2, _ = inject_fault(da, "bias", 0.5, 10, channel=-1, sensor_range=1.0)
    np.testing.assert_allclose(f2.values[10:, 2] - values[10:, 2], 0.5)
    assert list(f2["channel"].values) == ["p", "q", "r"]


def test_all_kinds_listed():
    assert FAULT_KINDS == ("bias", "hard", "soft", "drift", "stuck", "noise")


@pytest.mark.parametrize("call, exc, match", [
    (lambda y: inject_fault(y, "spike", 0.1, 10), ValueError, "kind must be one of"),
    (lambda y: inject_fault(y, "bias", 0.1, 400), ValueError, "start must fall inside the signal"),
    (lambda y: inject_fault(y, "bias", 0.1, -1), ValueError, "start must be >= 0"),
    (lambda y: inject_fault(y, "bias", 0.1, 10, duration=0), ValueError, "duration must be >= 1"),
    (lambda y: inject_fault(y, "hard", 0.1, 10, ramp=0), ValueError, "ramp must be >= 1"),
    (lambda y: inject_fault(y, "hard", 0.1, 10), ValueError, "ramp = '1s' is a time span"),
    (lambda y: inject_fault(y, "bias", "big", 10), TypeError, "magnitude must be a real number"),
    (lambda y: inject_fault(y, "bias", 0.1, 10, sensor_range=0.0), ValueError, "sensor_range must be > 0"),
    (lambda y: inject_fault(np.ones(10), "bias", 0.1, 2), ValueError, "constant in the faulty channel"),
    (lambda y: inject_fault(np.zeros((10, 2)), "bias", 0.1, 2), ValueError, "channel is required"),
    (lambda y: inject_fault(np.zeros((10, 2)), "bias", 0.1, 2, channel=2), ValueError, "channel must be a position"),
    (lambda y: inject_fault(np.zeros((10, 2)), "bias", 0.1, 2, channel="x"), ValueError, "channel 'x' is not"),
    (lambda y: inject_fault(np.r_[y, np.nan], "bias", 0.1, 2), ValueError, "signal contains 1 NaN"),
    (lambda y: inject_fault(y, "noise", 0.1, 2, rng="seed"), TypeError, "rng must be None"),
])
def test_bad_input_names_the_argument(y, call, exc, match):
    with pytest.raises(exc, match=match):
        call(y)


@pytest.mark.parametrize("kind", FAULT_KINDS)
def test_a_fault_that_overflows_is_refused(kind):
    """Issue 29, item 8: a fault beyond the float64 range was returned as inf."""
    y = np.sin(np.arange(100.0)) * 1e300
    with pytest.raises(ValueError, match=rf"magnitude = 1e\+10 times the sensor range [\d.e+]+ gives a {kind} fault "
                                         r"that leaves the floating-point range \(inf\)"):
        inject_fault(y, kind, 1e10, 10, ramp=5, rng=0)
    with pytest.raises(ValueError, match="gives a .* fault that leaves the floating-point range"):
        inject_fault(np.zeros(100), kind, 1e300, 10, ramp=5, sensor_range=1e300, rng=0)
    with pytest.raises(ValueError, match="signal's range in the faulty channel overflows float64; give sensor_range"):
        inject_fault(np.r_[-1e308, 1e308, np.zeros(98)], kind, 0.1, 10, ramp=5, rng=0)
    faulty, _ = inject_fault(y, kind, 0.5, 10, ramp=5, rng=0)          # a large signal with a fault in range is fine
    assert np.isfinite(faulty).all()


def test_duplicate_column_names_are_refused():
    """Issue 29, item 8: with duplicate column names only the first was faulted."""
    frame = pd.DataFrame(np.random.default_rng(0).standard_normal((50, 3)), columns=["p", "q", "p"])
    for channel in ("p", "q", 0):
        with pytest.raises(ValueError, match=r"signal has duplicate channel names \['p'\]: a fault is added to one "
                                             r"channel; rename them first"):
            inject_fault(frame, "bias", 0.1, 10, channel=channel)
    faulty, _ = inject_fault(frame.set_axis(["p", "q", "r"], axis=1), "bias", 0.1, 10, channel="r")
    assert (faulty["r"] != frame.iloc[:, 2]).sum() == 40

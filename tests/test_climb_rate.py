"""Climb-rate estimates for parity isolation on multirotors (issue 35, Benchmark 2): the barometer's causal slope
and the accelerometer's complementary integration against closed forms, on simulated sensors, and input checks."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tsfdi.isolation import climb_rate_from_accel, climb_rate_from_baro

FS = 50.0


def test_baro_slope_is_the_least_squares_slope_of_each_window():
    rng = np.random.default_rng(0)
    h = np.cumsum(rng.normal(0, 0.1, 200))
    out = climb_rate_from_baro(h, 10, fs=FS)
    assert out.shape == (191,)
    t = np.arange(10) / FS
    ref = [np.polyfit(t, h[k - 9:k + 1], 1)[0] for k in range(9, 200)]
    np.testing.assert_allclose(out, ref, rtol=1e-10, atol=1e-10)


def test_baro_exact_on_a_climb_and_index_kept():
    t = np.arange(500) / FS
    h = pd.Series(3.0 + 1.5 * t, index=pd.Index(t, name="time"))
    out = climb_rate_from_baro(h, "1s")
    assert isinstance(out, pd.Series) and out.index.equals(h.index[49:])
    np.testing.assert_allclose(out.to_numpy(), 1.5, rtol=1e-10)


def test_baro_noise_matches_the_stated_formula():
    rng = np.random.default_rng(1)
    n, sigma = 50, 0.1
    out = climb_rate_from_baro(rng.normal(0, sigma, 200_000), n, fs=FS)
    expected = sigma * FS * np.sqrt(12 / (n * (n * n - 1)))
    assert abs(np.std(out) / expected - 1) < 0.03


def _level(n, fz=-9.80665):
    accel = np.column_stack([np.zeros(n), np.zeros(n), np.full(n, fz)])
    return accel, np.zeros((n, 3))


def test_accel_zero_in_level_hover_and_follows_a_fast_climb():
    n = 5000                                          # 20 s at 250 Hz
    accel, att = _level(n)
    np.testing.assert_allclose(climb_rate_from_accel(accel, att, "5s", fs=250.0), 0.0, atol=1e-12)
    # a climb acceleration of 1 m/s^2 for 0.5 s: the climb rate reaches about 0.5 m/s (tau = 20 s >> 0.5 s)
    accel[1000:1125, 2] -= 1.0
    v = climb_rate_from_accel(accel, att, "20s", fs=250.0)
    assert abs(v[1124] - 0.5) < 0.02


def test_accel_bias_is_forgotten_and_peaks_at_tau_over_e():
    fs, tau, b = 250.0, 5.0, 0.3
    n = int(60 * fs)
    accel, att = _level(n, -9.80665 - b)              # a constant upward bias b (z down)
    v = climb_rate_from_accel(accel, att, "5s", fs=fs)
    # V(s) = s / (s + w)^2 * b / s: v(t) = b t exp(-t / tau), peak b tau / e at t = tau
    t = np.arange(1, n + 1) / fs
    np.testing.assert_allclose(v, b * t * np.exp(-t / tau), atol=2e-3)
    assert abs(v.max() - b * tau / np.e) < 2e-3 and abs(v[-1]) < 1e-3


def test_accel_rotation_uses_the_attitude():
    # tilted by a roll phi, hovering: the specific force in body axes is g (0, sin phi, -cos phi) rotated
    n, phi, g = 1000, 0.3, 9.80665
    accel = np.column_stack([np.zeros(n), np.full(n, -g * np.sin(phi)), np.full(n, -g * np.cos(phi))])
    att = np.column_stack([np.full(n, phi), np.zeros(n), np.zeros(n)])
    np.testing.assert_allclose(climb_rate_from_accel(accel, att, 100, fs=250.0), 0.0, atol=1e-9)
    # read as level, the tilt shows as a climb acceleration g (1 - cos phi), that the loop then forgets
    assert np.abs(climb_rate_from_accel(accel, np.zeros((n, 3)), 100, fs=250.0)).max() > 0.05


def test_accel_frame_in_series_out():
    n = 500
    idx = pd.Index(np.arange(n) / 250.0, name="time")
    accel, att = _level(n)
    out = climb_rate_from_accel(pd.DataFrame(accel, index=idx), pd.DataFrame(att, index=idx), "2s")
    assert isinstance(out, pd.Series) and out.name == "climb_rate" and out.index.equals(idx)


def test_inputs_are_checked():
    accel, att = _level(100)
    with pytest.raises(ValueError, match="fs"):
        climb_rate_from_baro(np.zeros(100), 10)
    with pytest.raises(ValueError, match="window"):
        climb_rate_from_baro(np.zeros(100), 200, fs=FS)
    with pytest.raises(ValueError, match="window"):
        climb_rate_from_baro(np.zeros(100), 1, fs=FS)
    with pytest.raises(ValueError, match="altitude"):
        climb_rate_from_baro(np.r_[np.zeros(99), np.nan], 10, fs=FS)
    with pytest.raises(ValueError, match="accel must have 3 columns"):
        climb_rate_from_accel(accel[:, :2], att, 10, fs=FS)
    with pytest.raises(ValueError, match="attitude must have one row per sample"):
        climb_rate_from_accel(accel, att[:50], 10, fs=FS)
    with pytest.raises(ValueError, match="fs"):
        climb_rate_from_accel(accel, att, 10)
    with pytest.raises(ValueError, match="gravity"):
        climb_rate_from_accel(accel, att, 10, fs=FS, gravity=-1.0)

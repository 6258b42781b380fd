"""benchmarks/sensor_validation_sim.py (issue 35, part 1): its data path on one short simulated flight.

The benchmark adds no library code; these checks pin what its numbers rest on: the 500 Hz sensor averaged onto the
100 Hz model grid as the sensor itself averages, the fault's first grid sample (MT is counted from it), the
configurations' noise, and lags that never look ahead.
"""

import copy

import numpy as np
import pytest

from tsfdi.datasets import simulate_hexacopter
from _scripts import load_script


def load_benchmark():
    return load_script("benchmarks/sensor_validation_sim.py")


@pytest.fixture(scope="module")
def bench():
    mod = load_benchmark()
    mod.DURATION, mod.FAULT_S = 4.0, 2.0
    record = simulate_hexacopter(duration=mod.DURATION, fs=1000, turbulence="light", seed=3).isel(record=0)
    return mod, mod.Flight(record, 3)


def test_grid_is_the_boxcar_of_the_500hz_samples(bench):
    mod, flight = bench
    raw = flight.log["gyro"]["q"].to_numpy()
    grid = flight.frame["gyro.q"].to_numpy()
    # grid sample j (t = (j + 1) / 100 s) averages the five 500 Hz samples stamped in (t - 0.01, t]
    np.testing.assert_allclose(grid[:len(raw) // 5], raw[:len(raw) // 5 * 5].reshape(-1, 5).mean(axis=1))
    held = flight.frame["gps.vn"].to_numpy()
    gps = flight.log["gps"]["vn"]
    j = 150                                       # t = 1.51 s: the last GPS sample stamped at or before it
    assert held[j] == gps[gps.index <= flight.t[j] + 1e-9].iloc[-1]


def test_fault_onset_on_the_grid(bench):
    mod, flight = bench
    clean = flight.sensor("gyro", "q")
    faulty = flight.sensor("gyro", "q", fault=("bias", 0.2), sensor_range=1.0)
    changed = np.flatnonzero(faulty != clean)
    assert changed[0] == flight.onset             # MT counts from the first grid sample that holds the fault
    assert flight.t[flight.onset] == pytest.approx(mod.FAULT_S + 0.01)
    np.testing.assert_allclose((faulty - clean)[flight.onset + 1:], 0.2)


def test_noise_configuration(bench):
    mod, flight = bench
    a = flight.sensor("gyro", "q", 10.0, 1e-3)
    b = flight.sensor("gyro", "q", 10.0, 1e-3)
    np.testing.assert_array_equal(a, b)          # seeded per flight and configuration
    added = a - flight.sensor("gyro", "q")
    # sqrt(k^2 - 1) sigma0 white noise at 500 Hz, averaged over 5 samples on the grid
    assert np.std(added) == pytest.approx(np.sqrt(99.0) * 1e-3 / np.sqrt(5.0), rel=0.1)


def test_lagged_never_looks_ahead():
    mod = load_benchmark()
    x = np.arange(6.0)[:, None]
    out = mod.lagged(x, (0, 2))
    np.testing.assert_array_equal(out[:, 0], x[:, 0])
    np.testing.assert_array_equal(out[:, 1], [0, 0, 0, 1, 2, 3])


def test_halted_run_keeps_a_slow_ramp_the_forgetting_model_learns():
    mod = load_benchmark()
    from tsfdi.models import RecursiveARX

    rng = np.random.default_rng(0)
    n, onset = 6000, 4500                         # 60 s at 100 Hz, a 4 s ramp of 5 noise deviations from 45 s
    x = rng.standard_normal((n, 1))
    ramp = 0.05 * np.clip((np.arange(n) - onset) / 400.0, 0.0, 1.0)
    y = 2.0 * x[:, 0] + 0.01 * rng.standard_normal(n) + ramp
    model = RecursiveARX(0, 1, 0, 0.999, P0=1e2, n_inputs=1, trend="c")
    model.run(2.0 * x[:3000, 0] + 0.01 * rng.standard_normal(3000), x[:3000])
    plain = np.asarray(copy.deepcopy(model).run(y, x).resid)
    halted = mod.halted_run(model, y, x, level=4e-4, window=25, padding=25)
    np.testing.assert_allclose(halted[:onset], plain[:onset])     # nothing crosses the level before the fault
    assert abs(plain[-100:].mean()) < 0.025                        # the forgetting model learns the offset
    assert halted[onset + 400:onset + 700].mean() > 0.04           # halted, the error holds the whole ramp
    assert not model.frozen and model.nobs == 3000                 # the model given is left as it was


def test_halted_run_releases_after_hold():
    mod = load_benchmark()
    from tsfdi.models import RecursiveARX

    rng = np.random.default_rng(1)
    n = 6000
    x = rng.standard_normal((n, 1))
    y = 2.0 * x[:, 0] + 0.01 * rng.standard_normal(n)
    y[2000:] += 0.05                              # a lasting change the frozen model alone would never follow
    model = RecursiveARX(0, 1, 0, 0.999, P0=1e2, n_inputs=1, trend="c")
    model.run(y[:1], x[:1])
    e = mod.halted_run(model, y, x, level=4e-4, window=25, padding=25)
    hold = int(mod.HOLD_S * mod.FS)
    assert abs(e[2000 + hold + 5]) > 0.04         # frozen for HOLD_S ...
    assert abs(e[-500:].mean()) < 0.01            # ... then it adapts (no halt for ever)


def test_inputs_filter_bank_is_causal_and_starts_at_rest(bench):
    mod, flight = bench
    cols = ["commands.pitch_control", "commands.pitch_command"]
    spec = ((0, 1), (0.1, 3.0))
    out = mod.inputs(flight, cols, spec)
    x = flight.frame[cols].to_numpy()
    assert out.shape == (len(x), 2 * 2 + 2 * 2)
    np.testing.assert_array_equal(out[:, :4], mod.lagged(x, (0, 1)))
    # started at rest on the first sample: a constant input passes unchanged
    frame = flight.frame
    flight.frame = frame.assign(**{c: 5.0 for c in cols})
    try:
        np.testing.assert_allclose(mod.inputs(flight, cols, spec)[:, 4:], 5.0)
        # causal: a step at sample 100 leaves every earlier filtered sample as it was, and a first-order low-pass
        # at 3 Hz has covered 1 - exp(-2 pi 3 t) of the step after t = 0.2 s (bilinear transform: within 2 %)
        flight.frame = frame.assign(**{c: np.where(np.arange(len(frame)) >= 100, 1.0, 0.0) for c in cols})
        step = mod.inputs(flight, cols, spec)
    finally:
        flight.frame = frame
    np.testing.assert_array_equal(step[:100, 4:], 0.0)
    assert step[100 + 20, 6] == pytest.approx(1.0 - np.exp(-2.0 * np.pi * 3.0 * 0.2), abs=0.02)


def test_widened_copy_starts_from_the_trained_estimate_and_adapts_faster():
    mod = load_benchmark()
    from tsfdi.models import RecursiveARX

    rng = np.random.default_rng(2)
    x = rng.standard_normal((6000, 1))
    model = RecursiveARX(0, 1, 0, 0.9999, P0=1e2, n_inputs=1, trend="c")
    model.run(2.0 * x[:, 0] + 0.01 * rng.standard_normal(6000), x)
    before = model.get_state()
    xs = rng.standard_normal((1000, 1))
    y = 2.0 * xs[:, 0] + 0.01 * rng.standard_normal(1000) + 0.05    # a new flight: another operating point
    plain = np.asarray(mod.widened(model, 1.0).run(y, xs).resid)
    np.testing.assert_array_equal(plain, np.asarray(copy.deepcopy(model).run(y, xs).resid))
    wide = np.asarray(mod.widened(model, 100.0).run(y, xs).resid)
    assert wide[0] == pytest.approx(plain[0], rel=1e-12)         # same estimate at the start
    assert abs(wide[500:].mean()) < 0.2 * abs(plain[500:].mean())  # the offset learnt within seconds
    np.testing.assert_array_equal(model.get_state().P, before.P)   # the trained model is left as it was
    assert model.nobs == 6000

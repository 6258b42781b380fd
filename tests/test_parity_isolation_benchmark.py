"""benchmarks/parity_isolation.py (issue 35, Benchmark 2): how a self-check flag joins the parity decision, the
flags' mapping onto the residual grid, and the stated self-check bound."""

from __future__ import annotations


import numpy as np
import pandas as pd
import pytest

from tsfdi.isolation import frozen_output
from _scripts import load_script


@pytest.fixture(scope="module")
def bench():
    return load_script("benchmarks/parity_isolation.py")


def test_a_self_check_flag_completes_its_sensors_column(bench):
    n = 6
    r = pd.DataFrame(np.zeros((n, 3)), columns=list(bench.PARITY.names))
    flags = np.zeros((n, 3), dtype=bool)
    flags[2:, bench.SENSORS.index("gps")] = True
    g = {("mean", "R3"): np.r_[0, 0, 0, 0, 1, 1.0]}           # R3 (gps - accel) alarms at rows 4, 5
    s = bench.series(g, {("mean", "R3"): 0.5}, r, flags)
    assert s.labels == [None, None, "gps", "gps", "gps", "gps"]  # R1 and R3 from the flag; R3's alarm agrees
    flags[:, :] = False
    flags[2:, bench.SENSORS.index("baro")] = True               # baro's column is R1, R2: R3's alarm breaks it
    s = bench.series(g, {("mean", "R3"): 0.5}, r, flags)
    assert s.labels == [None, None, "baro", "baro", None, None]
    assert list(s.status[4:]) == ["not isolable"] * 2


def test_flags_are_the_latest_sensor_sample_on_the_residual_grid(bench, monkeypatch):
    monkeypatch.setattr(bench, "DURATION", 40.0)                 # 10 s after the 30 s start-up
    log = bench.flights(7, 1)[0]
    stuck = bench.faulty(log, "gps", "stuck", 35.0)
    r, flags = bench.monitored(stuck)
    t = r.index.total_seconds().to_numpy()
    assert t[0] == pytest.approx(bench.WARM) and flags.shape == (len(r), 3)
    assert not flags[:, [0, 2]].any()                           # baro and accelerometer move
    gps = stuck["gps"]["vd"]
    raw = frozen_output(gps.to_numpy(), bench.SELF_CHECK["gps"][2])
    first = gps.index[np.flatnonzero(raw)[0]]                    # stamp of the first flagged fix
    hit = np.flatnonzero(flags[:, 1])
    assert hit.size and np.all(np.diff(hit) == 1) and hit[-1] == len(r) - 1
    assert t[hit[0]] >= first - 1e-9 and t[hit[0] - 1] < first   # from the first grid sample at or after it
    # the fault itself: the fix before the onset repeated, so the flag comes 9 fixes (0.9 s) after the onset
    assert first == pytest.approx(35.0 + gps.index[0] - 0.1 + 0.9, abs=1e-6)


def test_self_check_bound_is_frozen_outputs(bench):
    table = bench.self_check_bound()
    sigma, resolution, rate = bench.SELF_CHECK_NOISE["accel"]
    per_sample = (2 * resolution / (sigma * np.sqrt(2 * np.pi))) ** 49
    assert float(table.loc["accel", "P_F per sample"]) == pytest.approx(per_sample, rel=0.05)
    assert float(table.loc["accel", "P_F per flight-hour"]) == pytest.approx(per_sample * 3 * 500 * 3600, rel=0.05)

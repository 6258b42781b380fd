"""benchmarks/streaming.py (issue 34): its logs and its scoring, on a few short simulated logs."""


import numpy as np
import pytest
from _scripts import load_script


def _streaming_benchmark():
    return load_script("benchmarks/streaming.py")


@pytest.mark.slow
def test_rotor_failures_are_found_at_once_and_healthy_logs_stay_quiet():
    B = _streaming_benchmark()
    gen = np.random.default_rng(7)
    healthy = B.make_logs(gen, 4, failures=False, duration=40.0, fs=50.0)
    failures = B.make_logs(gen, 3, failures=True, duration=40.0, fs=50.0, loss=(0.5, 1.0))
    f, ft, rotor, turb, loss = failures[0]
    assert list(f.columns) == ["gyro.p", "gyro.q", "gyro.r", "commands.roll_control", "commands.pitch_control",
                               "commands.yaw_control", *(f"motors.motor_command{i}" for i in range(1, 7))]
    assert 15.0 <= ft <= 30.0 and 1 <= rotor <= 6 and turb in B.TURBULENCE and 0.5 <= loss <= 1.0
    y, u = B.split(f, "motors")
    assert list(y.columns) == ["gyro.p", "gyro.q", "gyro.r"] and u.shape[1] == 18     # six motors per pair
    # one pair per rotor: the rates in the direction its loss turns the aircraft (rotor 1 on the nose: pitch down,
    # rotor 2 at 60 degrees to the right: roll right and pitch down), against the six motor commands
    y, u = B.split(f, "rotors")
    assert list(y.columns) == [f"rotor{i}" for i in range(1, 7)] and u.shape[1] == 36
    p, q = f["gyro.p"].to_numpy(), f["gyro.q"].to_numpy()
    np.testing.assert_allclose(y["rotor1"], -q, atol=1e-12)
    np.testing.assert_allclose(y["rotor2"], np.sqrt(3) / 2 * p - q / 2, atol=1e-12)
    np.testing.assert_allclose(y["rotor4"], q, atol=1e-12)
    for pairs in B.PAIR_SETS:
        shift = B.SHIFTS[-1] if pairs == "rotors" else None
        det = B.calibrated(healthy[:3], pairs, 1, 2, 1.0, shift)
        assert det.calibration_.runs == 3 and det.statistic == "sprt" and det.models[0].nk == 1
        assert det.sprt.alternative == ("mean" if pairs == "rotors" else "variance")
        tab = B.score(det, B.unfrozen(det, pairs, 1, 2), healthy[3:] + failures, pairs)
        fail = tab[tab.kind == "failure"]
        assert (fail.outcome == "found").all() and (fail.delay_s <= B.DEADLINE).all(), (pairs, fail)
        assert tab.false_episodes.sum() == 0
        s = B.summary(tab).iloc[0]
        assert s["found"] == 3 and s["healthy h"] == pytest.approx(tab.healthy_hours.sum(), abs=1e-4)
    assert B.by_loss(tab)["logs"].sum() == 3

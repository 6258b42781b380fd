"""benchmarks/streaming.py (issue 34): its logs and its scoring, on a few short simulated logs."""


import numpy as np
import pandas as pd
import pytest
from _scripts import load_script


def _streaming_benchmark():
    return load_script("benchmarks/streaming.py")


@pytest.mark.slow
def test_rotor_failures_are_found_at_once_and_healthy_logs_stay_quiet():
    B = _streaming_benchmark()
    gen = np.random.default_rng(7)
    healthy = B.make_logs(gen, 4, failures=False, duration=40.0, fs=50.0, accel=True)
    failures = B.make_logs(gen, 3, failures=True, duration=40.0, fs=50.0, loss=(0.5, 1.0), accel=True)
    f, ft, rotor, turb, loss = failures[0]
    assert list(f.columns) == ["gyro.p", "gyro.q", "gyro.r", "commands.roll_control", "commands.pitch_control",
                               "commands.yaw_control", *(f"motors.motor_command{i}" for i in range(1, 7)),
                               "accel.ax", "accel.ay", "accel.az", "collective.collective"]
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
    # the same with the accelerometer's lateral specific forces after the six motor commands of every pair
    for pairs, k in (("motors+accel", 3), ("rotors+accel", 6)):
        y, u = B.split(f, pairs)
        assert y.shape[1] == k and u.shape[1] == 8 * k
        assert list(u.columns[6:8]) == ["accel.ax", "accel.ay"] and list(u.columns[-2:]) == ["accel.ax", "accel.ay"]
        np.testing.assert_array_equal(u.iloc[:, 8:14], f[B.MOTOR_COLS])
    for i, pairs in enumerate(B.PAIR_SETS):
        shift = B.SHIFTS[-1] if pairs.startswith("rotors") else None
        lam = B.FORGETTING[i % len(B.FORGETTING)]
        det = B.calibrated(healthy[:3], pairs, 1, 2, 1.0, shift, lam)
        assert det.calibration_.runs == 3 and det.statistic == "sprt" and det.models[0].nk == 1
        assert det.sprt.alternative == ("mean" if pairs.startswith("rotors") else "variance")
        free = B.unfrozen(det, pairs, 1, 2)          # the same detector but for freezing: its forgetting too
        assert [m.forgetting_factor for m in free.models] == [lam] * len(free.models) and not free.freeze_on_alarm
        assert free.threshold == det.threshold and free.n_inputs == det.n_inputs
        tab = B.score(det, free, healthy[3:] + failures, pairs)
        fail = tab[tab.kind == "failure"]
        assert (fail.outcome == "found").all() and (fail.delay_s <= B.DEADLINE).all(), (pairs, fail)
        assert tab.false_episodes.sum() == 0
        s = B.summary(tab).iloc[0]
        assert s["found"] == 3 and s["healthy h"] == pytest.approx(tab.healthy_hours.sum(), abs=1e-4)
    assert B.by_loss(tab)["logs"].sum() == 3


def test_detectability_bound_recovers_a_known_bias_on_synthetic_logs():
    B = _streaming_benchmark()
    gen = np.random.default_rng(3)
    # matched filter on white errors of covariance sigma: a bias b d over the window scores b sqrt(n d' sigma^-1 d)
    n, window, b = 20000, 25, 0.6
    sigma = np.array([[1.0, 0.8], [0.8, 4.0]])
    e = gen.multivariate_normal([0.0, 0.0], sigma, n)
    d = np.array([[0.6, -0.8], [-0.6, 0.8]])
    fit = np.arange(n) < n // 2
    expected = b * np.sqrt(window * d[0] @ np.linalg.solve(sigma, d[0]))      # 2.76 (unweighted by sigma: 2.05)
    z = B.matched(e + b * d[0] * ~fit[:, None], sigma, d, window, fit)
    assert np.isnan(z[n - window + 1:]).all() and np.isfinite(z[:n - window + 1]).all()
    np.testing.assert_allclose(z[:n // 2 - window + 1].mean(0), 0.0, atol=1e-9)          # healthy: standardised
    np.testing.assert_allclose(z[:n // 2 - window + 1].std(0, ddof=1), 1.0, atol=1e-9)
    np.testing.assert_allclose(z[n // 2:n - window + 1].mean(0), [expected, -expected], atol=0.3)
    # a bias on one window only, at five error sd along the direction: the first direction sees it, not the second
    e[15000:15000 + window] += 5 * d[0] / np.sqrt(d[0] @ np.linalg.solve(sigma, d[0]))
    z = B.matched(e, sigma, d, window, fit)
    assert abs(z[15000, 0] - 25) < 4 and z[15000, 1] < -20 and z[15000, 0] > max(z[14999, 0], z[15001, 0])
    assert np.nanmax(np.delete(z[:, 0], np.arange(15000 - window, 15000 + window))) < 5

    # the healthy level: the median of the largest of 100 logs' maxima, from a Gumbel fit to 4000 logs' maxima
    maxima = gen.gumbel(3.0, 1.0, 4000)
    largest = gen.gumbel(3.0, 1.0, (2000, 100)).max(1)
    assert abs(B.healthy_level(maxima, 0.01, 1.0) - np.median(largest)) < 0.2           # 7.97
    with pytest.raises(ValueError, match="maxima"):
        B.healthy_level(maxima[:2], 0.01, 1.0)

    # the whole bound on synthetic logs: two rates driven by six commands (one sample late) and white noise; a
    # failure adds a bias of known size in its rotor's direction from the failure on
    def log(ft, rotor, bias):
        t = np.arange(0, 60.0, 0.02)
        u = 500 + gen.normal(0, 5, (len(t), 6))
        y = np.zeros((len(t), 2))
        for k in range(1, len(t)):
            y[k] = 0.5 * y[k - 1] + 0.01 * (u[k - 1, :2] - u[k - 1, 3:5]) + gen.normal(0, 0.1, 2)
            if ft is not None and t[k] >= ft:
                y[k] += bias * np.array(B.SIGNATURES[rotor - 1])
        f = pd.DataFrame(np.column_stack([y, u]), index=pd.Index(t, name="time"),
                         columns=["gyro.p", "gyro.q", *(f"motors.{m}" for m in B.MOTORS)])
        return f, ft, rotor, "light", 0.15 if bias else 0.6
    healthy = [log(None, 0, 0.0) for _ in range(6)]
    failures = [log(40.0, 1 + k % 6, 0.2) for k in range(12)] + [log(30.0, 1, 0.0)]
    table, fails, levels = B.detectability(healthy, failures, ["gyro.p", "gyro.q"], B.MOTOR_COLS,
                                           directions=np.array(B.SIGNATURES), windows=(0.5, 1.0))
    # a bias of two error sd over 25 (50) samples: the matched filter 2 sqrt(25) = 10 (2 sqrt(50) = 14.1)
    got = fails.set_index("window_s")
    np.testing.assert_allclose(got.oracle[got.loss == 0.15].groupby(level=0).mean(), [10.0, 14.14], atol=1.0)
    assert abs(got.oracle[got.loss == 0.6]).max() < 3.5                                   # no bias: noise
    assert levels["healthy logs"].tolist() == [6, 6] and (levels["level for 2.4 h"] > levels["largest healthy"]).all()
    assert 3.0 < levels["level for 2.4 h"].min() and levels["level for 2.4 h"].max() < 6.0
    assert fails.found.tolist() == ([True] * 12 + [False]) * 2
    assert table.loc[pd.Interval(0.1, 0.2), ("found", 0.5)] == 12
    assert table.loc[pd.Interval(0.5, 1.0), ("found", 1.0)] == 0
    with pytest.raises(ValueError, match="directions"):
        B.detectability(healthy, failures, ["gyro.p", "gyro.q"], B.MOTOR_COLS, directions=np.eye(2))
    with pytest.raises(ValueError, match="healthy"):
        B.detectability(healthy[:2], failures, ["gyro.p", "gyro.q"], B.MOTOR_COLS)


def test_the_window_sum_detector_of_the_grid_and_its_unfrozen_copy():
    """The grid's standardised window sum (statistic="zmean", issue 34): one-sided on the rotor directions,
    two-sided on the rates; the unfrozen copy that counts false-alarm episodes keeps its statistic and window."""
    B = _streaming_benchmark()
    assert B.WINDOWS == (0.25, 0.5, 1.0)
    for pairs, side in (("rotors+accel", "up"), ("motors+accel", "both")):
        det = B.detector(pairs, 1, 2, window=25, forgetting_factor=0.9999, threshold=5.0)
        assert (det.statistic, det.window, det.direction, det.n_inputs) == ("zmean", 25, side, 8)
        free = B.unfrozen(det, pairs, 1, 2)
        assert (free.statistic, free.window, free.direction, free.threshold) == ("zmean", 25, side, 5.0)
        assert not free.freeze_on_alarm and free.models[0].forgetting_factor == 0.9999
    sprt = B.unfrozen(B.detector("rotors", 1, 2, shift=2.0, threshold=9.0), "rotors", 1, 2)
    assert sprt.statistic == "sprt" and sprt.sprt.shift == 2.0 and sprt.threshold == 9.0
    with pytest.raises(ValueError, match="give one"):
        B.detector("rotors+accel", 1, 2, shift=2.0, window=25)

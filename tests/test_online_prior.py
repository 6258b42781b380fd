"""OnlineDetector with a prior per pair: ``theta0`` and ``P0`` given as a mapping from pair names (issue 34: a fleet
prior, each pair's RLS started from a fit of other healthy logs)."""

import numpy as np
import pandas as pd
import pytest
from test_online import assert_streams_like_a_block, two_pairs

import tsfdi
from tsfdi.models.recursive import RecursiveARX
from tsfdi.online import OnlineDetector

ORDERS = dict(na=1, nb=1, nk=0)      # the orders of two_pairs: y = a y[-1] + b u + e


def fits(y, u, n=2000):
    """ARX fits of both pairs of ``two_pairs`` on their first ``n`` samples (a healthy log of the same process)."""
    return {name: tsfdi.ARX(y[:n, c], u[:n, c], **ORDERS).fit() for c, name in enumerate(("a", "b"))}


def test_each_pair_starts_from_its_own_prior():
    y, u = two_pairs(seed=1)
    prior = fits(y, u)
    p0 = np.array([[2e-4, 1e-5], [1e-5, 3e-4]])
    det = OnlineDetector(["a", "b"], **ORDERS, theta0=prior, P0={"a": 1e-3, "b": p0})
    a, b = det.models
    # ARX params (grouped by lag: a1, b1) in RecursiveARX's order (a1, b1) and the papers' sign: a1 = -0.7, -0.5
    np.testing.assert_allclose(a.theta_, prior["a"].params)
    np.testing.assert_allclose(b.theta_, prior["b"].params)
    np.testing.assert_allclose(a.theta_, [-0.7, 1.0], atol=0.02)
    np.testing.assert_allclose(b.theta_, [-0.5, 0.8], atol=0.02)
    np.testing.assert_array_equal(a.P_, 1e-3 * np.eye(2))
    np.testing.assert_array_equal(b.P_, p0)
    # reset (and calibrate, which resets) returns to the prior
    det.run(y[:500], u[:500])
    assert not np.allclose(a.theta_, prior["a"].params, rtol=0, atol=1e-12)
    det.reset()
    np.testing.assert_allclose(a.theta_, prior["a"].params)
    np.testing.assert_array_equal(b.P_, p0)


def test_a_pair_not_named_starts_from_the_default():
    y, u = two_pairs(seed=1)
    det = OnlineDetector(["a", "b"], **ORDERS, theta0={"b": fits(y, u)["b"]}, P0={"b": 1e-3})
    np.testing.assert_array_equal(det.models[0].theta_, [0.0, 0.0])
    np.testing.assert_array_equal(det.models[0].P_, 1e4 * np.eye(2))
    np.testing.assert_allclose(det.models[1].theta_, [-0.5, 0.8], atol=0.02)
    # one value for every pair, as before
    same = OnlineDetector(["a", "b"], **ORDERS, theta0=[-0.6, 0.9], P0=5.0)
    for m in same.models:
        np.testing.assert_array_equal(m.theta_, [-0.6, 0.9])
        np.testing.assert_array_equal(m.P_, 5.0 * np.eye(2))


@pytest.mark.filterwarnings("ignore::tsfdi.exceptions.ConvergenceWarning")     # 50 samples: not armed
def test_a_prior_predicts_from_the_first_samples():
    """From zero the first errors are the whole output; from a fit of another healthy log of the same process (its
    covariance about one log's worth) they are the noise (sd 0.1) from the first sample."""
    y, u = two_pairs(seed=1)
    y2, u2 = two_pairs(seed=2)                              # another healthy log of the same pairs
    prior = fits(y2, u2)
    p0 = {}
    for c, name in enumerate(("a", "b")):
        x = np.asarray(RecursiveARX(**ORDERS).regressors(y2[:2000, c], u2[:2000, c]))
        p0[name] = np.linalg.inv(x.T @ x)
    rms = {}
    for key, opts in (("plain", {}), ("primed", dict(theta0=prior, P0=p0))):
        e = np.asarray(OnlineDetector(["a", "b"], **ORDERS, **opts).run(y[:50], u[:50]).resid)
        rms[key] = np.sqrt(np.nanmean(e ** 2, axis=0))
    assert (rms["primed"] < 0.15).all() and (rms["plain"] > 0.2).all(), rms


def test_streaming_with_a_prior_equals_the_block():
    y, u = two_pairs(seed=3, bias=0.3)
    prior = fits(*two_pairs(seed=2))
    for statistic in ("sprt", "zscore"):
        extra = {} if statistic == "sprt" else {"glrt": None}
        ref = assert_streams_like_a_block(
            lambda: OnlineDetector(["a", "b"], **ORDERS, statistic=statistic, theta0=prior,
                                   P0={"a": 1e-3, "b": 1e-3}, **extra), y, u)
        assert ref.first_alarm is not None


def test_calibrate_runs_the_healthy_logs_from_the_prior():
    """calibrate's healthy runs use the pairs' priors (a copy of the detector): with an exact prior held nearly
    fixed (tiny P0) the threshold differs from the one without, and the calibrated detector starts from the prior."""
    rng = np.random.default_rng(5)
    logs = [two_pairs(n=1500, seed=int(s)) for s in rng.integers(0, 2**31, 4)]
    exact = {"a": [-0.7, 1.0], "b": [-0.5, 0.8]}
    ys, us = [y for y, _ in logs], [u for _, u in logs]
    primed = OnlineDetector(["a", "b"], **ORDERS, theta0=exact, P0={"a": 1e-9, "b": 1e-9})
    primed.calibrate(ys, us, false_alarms_per_hour=60, fs=50.0)
    plain = OnlineDetector(["a", "b"], **ORDERS).calibrate(ys, us, false_alarms_per_hour=60, fs=50.0)
    assert primed.threshold != plain.threshold
    np.testing.assert_array_equal(primed.models[1].theta_, exact["b"])


def test_per_pair_priors_are_checked_by_pair():
    y, u = two_pairs(seed=1)
    prior = fits(y, u)
    with pytest.raises(ValueError, match=r"^theta0 names no pair 'c': a mapping of theta0 is keyed by the pair "
                                         r"names \['a', 'b'\]"):
        OnlineDetector(["a", "b"], **ORDERS, theta0={"a": prior["a"], "c": prior["b"]})
    with pytest.raises(ValueError, match=r"^P0 names no pair 'x'"):
        OnlineDetector(["a", "b"], **ORDERS, P0={"x": 1.0})
    with pytest.raises(ValueError, match=r"^pair 'b': theta0 must hold 2 finite values, got shape \(3,\)"):
        OnlineDetector(["a", "b"], **ORDERS, theta0={"a": prior["a"], "b": [0.1, 0.2, 0.3]})
    with pytest.raises(ValueError, match=r"^pair 'a': theta0 is a ARX fit of other orders"):
        OnlineDetector(["a", "b"], na=2, nb=1, nk=0, theta0={"a": prior["a"]})
    with pytest.raises(TypeError, match=r"^pair 'a': theta0 must hold real numbers, got 'fast'"):
        OnlineDetector(["a", "b"], **ORDERS, theta0={"a": "fast"})
    with pytest.raises(ValueError, match=r"^pair 'b': P0 must be a positive scalar or a \(2, 2\) matrix"):
        OnlineDetector(["a", "b"], **ORDERS, P0={"a": 1.0, "b": np.eye(3)})
    with pytest.raises(ValueError, match=r"^pair 'a': P0 must be positive definite"):
        OnlineDetector(["a", "b"], **ORDERS, P0={"a": np.array([[1.0, 2.0], [2.0, 1.0]])})
    # one value for every pair keeps its message (no pair named)
    with pytest.raises(ValueError, match=r"^theta0 must hold 2 finite values"):
        OnlineDetector(["a", "b"], **ORDERS, theta0=[0.1, 0.2, 0.3])


def test_the_streaming_benchmarks_fleet_prior_is_the_pooled_least_squares():
    """benchmarks/streaming.py --prior: fleet_prior recovers the ARX of logs built from one (a rotor pair's output
    against the six motor commands, the accelerometer's inputs unused), in RecursiveARX's parameter order, with
    P = (X'X)^-1 of the pooled regressors; prior_options hands them to the detector per pair."""
    from _scripts import load_script
    from scipy.signal import lfilter

    B = load_script("benchmarks/streaming.py")
    rng = np.random.default_rng(7)
    bp, bq = rng.normal(0.0, 0.5, 6), rng.normal(0.0, 0.5, 6)
    logs = []
    for _ in range(3):
        n = 3000
        m = rng.standard_normal((n, 6))
        cols = {f"motors.{c}": m[:, j] for j, c in enumerate(B.MOTORS)}
        # p, q = 0.8 p[-1] + b . m[-1] + e: every rotor direction s p - c q has a1 = -0.8 (papers' sign)
        for name, b in (("p", bp), ("q", bq)):
            drive = np.r_[0.0, m[:-1] @ b] + 0.01 * rng.standard_normal(n)
            cols[f"gyro.{name}"] = lfilter([1.0], [1.0, -0.8], drive)
        cols["gyro.r"] = rng.standard_normal(n)
        cols["accel.ax"], cols["accel.ay"] = rng.standard_normal(n), rng.standard_normal(n)
        f = pd.DataFrame(cols, index=pd.to_timedelta(np.arange(n) / 50.0, unit="s"))
        logs.append((f, None, 0, "light", 1.0))
    prior = B.fleet_prior(logs, "rotors+accel", 1, 2)
    assert list(prior) == [f"rotor{i}" for i in range(1, 7)]
    sp, sq = B.SIGNATURES[1]              # rotor 2: y = sp p + sq q
    theta, p, between = prior["rotor2"]
    # theta: a1, then b0_1, b0_2 (motor 1 at lags 1 and 2), ..., b7_1, b7_2 (accel.ay)
    expected = np.r_[-0.8, np.column_stack([sp * bp + sq * bq, np.zeros(6)]).ravel(), np.zeros(4)]
    np.testing.assert_allclose(theta, expected, atol=2e-3)

    def regressors(f):                    # rotor 2's pair: its output and its 8 inputs
        y, u = B.split(f, "rotors+accel")
        return np.asarray(tsfdi.RecursiveARX(1, 2, 1, n_inputs=8).regressors(y.iloc[:, 1].to_numpy(),
                                                                           u.iloc[:, 8:16].to_numpy()))

    pooled = np.vstack([regressors(f) for f, *_ in logs])
    np.testing.assert_allclose(p, np.linalg.inv(pooled.T @ pooled), rtol=1e-8)
    assert between.shape == (17, 17)
    opts = B.prior_options(prior, 36.0)
    det = B.detector("rotors+accel", 1, 2, shift=2.0, **opts)
    np.testing.assert_allclose(det.models[1].theta_, theta)
    np.testing.assert_allclose(det.models[1].P_, 36.0 * p)
    # "between": the spread of the per-log fits (three logs here: singular, so only handed on)
    assert B.prior_options(prior, "between")["P0"]["rotor6"] is prior["rotor6"][2]

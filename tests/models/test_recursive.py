"""RecursiveARX: agreement with batch and exponentially weighted least squares, long-run stability,
online detection, streaming equivalence, state snapshots, data kinds and bad input."""

import dataclasses

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import tsfdi
from tsfdi.models.recursive import RecursiveARX


def simulate_arx(n, rng, a=(-1.2, 0.5), b=(0.8, 0.3), nk=1, sigma=0.1, change_at=None, db=0.5):
    """y[t] + a1 y[t-1] + a2 y[t-2] = b1 u[t-nk] + b2 u[t-nk-1] + e[t]; b1 += db from ``change_at`` on."""
    rng = np.random.default_rng(rng)
    u = rng.standard_normal(n)
    e = sigma * rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(n):
        acc = e[t]
        for i, ai in enumerate(a, start=1):
            if t - i >= 0:
                acc -= ai * y[t - i]
        for k, bk in enumerate(b):
            if t - nk - k >= 0:
                bb = bk + (db if (k == 0 and change_at is not None and t >= change_at) else 0.0)
                acc += bb * u[t - nk - k]
        y[t] = acc
    return y, u


def regressor(y, u, na, nb, nk, trend=False):
    """Rows t = t0..n-1 of phi[t] = [1?, -y[t-1..t-na], u[t-nk..t-nk-nb+1] per input]."""
    u = np.asarray(u).reshape(len(y), -1)
    t0 = max(na, nk + nb - 1)
    cols = [np.ones(len(y) - t0)] if trend else []
    cols += [-y[t0 - i:len(y) - i] for i in range(1, na + 1)]
    for j in range(u.shape[1]):
        cols += [u[t0 - nk - k:len(y) - nk - k, j] for k in range(nb)]
    return np.column_stack(cols), y[t0:], t0


def test_converges_to_batch_least_squares():
    y, u = simulate_arx(5000, 1)
    m = RecursiveARX(2, 2, 1, forgetting_factor=1.0, P0=1e10)
    res = m.run(y, u)
    X, Y, t0 = regressor(y, u, 2, 2, 1)
    # after the transient, theta(t) equals the least-squares fit on samples up to t
    for t in (200, 1000, 4999):
        ls = np.linalg.lstsq(X[:t - t0 + 1], Y[:t - t0 + 1], rcond=None)[0]
        np.testing.assert_allclose(res.params[t], ls, rtol=0, atol=1e-6)
    np.testing.assert_allclose(m.theta_, [-1.2, 0.5, 0.8, 0.3], atol=0.01)
    # and the batch ARX model of tsfdi (compared through a and b, which do not depend on the params order)
    batch = tsfdi.ARX(y, u, 2, 2, 1).fit()
    np.testing.assert_allclose(m.theta_[:2], batch.a, rtol=0, atol=1e-6)
    np.testing.assert_allclose(m.theta_[2:], np.ravel(batch.b), rtol=0, atol=1e-6)


def test_trend_and_two_inputs_match_least_squares():
    rng = np.random.default_rng(2)
    n = 3000
    u = rng.standard_normal((n, 2))
    y = np.zeros(n)
    for t in range(2, n):
        y[t] = 0.3 + 0.6 * y[t - 1] + 0.5 * u[t, 0] - 0.2 * u[t - 1, 0] + 0.7 * u[t, 1] + 0.1 * u[t - 1, 1] \
            + 0.05 * rng.standard_normal()
    m = RecursiveARX(1, 2, 0, P0=1e10, n_inputs=2, trend="c")
    assert m.param_names == ("const", "a1", "b0_1", "b0_2", "b1_1", "b1_2")
    m.run(y, u)
    X, Y, _ = regressor(y, u, 1, 2, 0, trend=True)
    np.testing.assert_allclose(m.theta_, np.linalg.lstsq(X, Y, rcond=None)[0], rtol=0, atol=1e-6)
    np.testing.assert_allclose(m.theta_, [0.3, -0.6, 0.5, -0.2, 0.7, 0.1], atol=0.02)
    batch = tsfdi.ARX(y, u, 1, 2, 0, trend="c").fit()
    np.testing.assert_allclose(m.theta_[0], batch.intercept, rtol=0, atol=1e-6)
    np.testing.assert_allclose(m.theta_[1:2], batch.a, rtol=0, atol=1e-6)
    np.testing.assert_allclose(m.theta_[2:], np.ravel(batch.b), rtol=0, atol=1e-6)


@pytest.mark.parametrize("na, nb, trend", [(1, 0, "n"), (1, 1, "n"), (2, 1, "n"), (2, 2, "c"), (3, 4, "n")])
def test_odd_and_even_dimensions_match_least_squares(na, nb, trend):
    # the kernel forms P phi two rows at a time, the last row alone when d = 1, 3, 5, 7 is odd
    y, u = simulate_arx(3000, 5)
    m = RecursiveARX(na, nb, 1, P0=1e10, trend=trend)
    m.run(y, u)
    X, Y, _ = regressor(y, u, na, nb, 1, trend=trend == "c")
    np.testing.assert_allclose(m.theta_, np.linalg.lstsq(X, Y, rcond=None)[0], rtol=0, atol=1e-6)


def test_forgetting_equals_exponentially_weighted_least_squares():
    y, u = simulate_arx(100_000, 3)
    lam = 0.99
    m = RecursiveARX(2, 2, 1, forgetting_factor=lam, P0=1e4)
    m.run(y, u)
    X, Y, _ = regressor(y, u, 2, 2, 1)
    w = np.sqrt(lam ** np.arange(len(Y))[::-1])
    exact = np.linalg.lstsq(X * w[:, None], Y * w, rcond=None)[0]
    np.testing.assert_allclose(m.theta_, exact, rtol=0, atol=1e-8)
    np.testing.assert_array_equal(m.P_, m.P_.T)  # symmetric form keeps P exactly symmetric
    # P is the inverse of the weighted information matrix (the prior weight lambda^N / P0 is ~ 0)
    np.testing.assert_allclose(m.P_, np.linalg.inv((X * w[:, None]).T @ (X * w[:, None])), rtol=1e-6)


def test_million_samples_stay_finite_and_positive_definite():
    rng = np.random.default_rng(4)
    n = 1_000_000
    u = rng.standard_normal(n)
    y = np.empty(n)
    y[0] = 0.0
    e = 0.1 * rng.standard_normal(n)
    # vectorised simulation of y[t] = 0.7 y[t-1] + u[t-1] + e[t] via scipy.signal.lfilter
    from scipy.signal import lfilter
    x = np.concatenate([[0.0], u[:-1]]) + e
    y = lfilter([1.0], [1.0, -0.7], x)
    m = RecursiveARX(1, 1, 1, forgetting_factor=0.99, P0=1e4)
    res = m.run(y, u)
    assert np.isfinite(res.params).all()
    assert np.isfinite(m.P_).all()
    np.testing.assert_array_equal(m.P_, m.P_.T)
    assert np.linalg.eigvalsh(m.P_).min() > 0
    np.linalg.cholesky(m.P_)
    np.testing.assert_allclose(m.theta_, [-0.7, 1.0], atol=0.05)


def test_abrupt_change_detected_with_bounded_delay_and_no_false_alarm():
    change = 3000
    y, u = simulate_arx(4000, 0, change_at=change)
    res = RecursiveARX(2, 2, 1, forgetting_factor=0.995, freeze_on_alarm=True).run(y, u)
    assert res.model_stable[:200].any() and res.variance_stable[change - 1]
    assert not res.alarm[:change].any()
    assert change <= res.first_alarm <= change + 10


@pytest.mark.slow
def test_abrupt_change_monte_carlo():
    # 40 fault-free stretches of 3000 samples: a Z-score test at 4.5 has a nominal two-sided per-sample rate
    # of 6.8e-6 (0.02 alarms per stretch); the a-priori errors of a forgetting estimator are somewhat
    # heavier-tailed (measured about 5 % of stretches). Allow 6 of 40 (P(X > 6 | p = 0.05) = 0.014),
    # and require every detected change within 10 samples.
    change, false_alarms, delays = 3000, 0, []
    for seed in range(40):
        y, u = simulate_arx(4000, 100 + seed, change_at=change)
        res = RecursiveARX(2, 2, 1, forgetting_factor=0.995, freeze_on_alarm=True).run(y, u)
        assert res.first_alarm is not None
        if res.first_alarm < change:
            false_alarms += 1
        else:
            delays.append(res.first_alarm - change)
    assert false_alarms <= 6
    assert max(delays) <= 10


def test_freeze_on_alarm_freezes_adaptation():
    change = 8000
    y, u = simulate_arx(10_000, 7, change_at=change, db=1.0)
    m = RecursiveARX(2, 2, 1, forgetting_factor=0.99, freeze_on_alarm=True)
    res = m.run(y, u)
    k = res.first_alarm
    assert k is not None and k >= change
    params = np.asarray(res.params)
    # the parameters stop at theta(k-1): the alarmed sample and later ones do not update them
    np.testing.assert_array_equal(params[k:], np.broadcast_to(params[k - 1], params[k:].shape))
    var = np.asarray(res.variance)
    assert np.all(var[k:] == var[k - 1])
    # without freezing the model adapts to the fault and the error variance grows
    m2 = RecursiveARX(2, 2, 1, forgetting_factor=0.99, freeze_on_alarm=False)
    res2 = m2.run(y, u)
    assert np.abs(np.asarray(res2.params)[-1, 2] - 1.8) < 0.05
    assert np.asarray(res2.variance)[-1] > var[-1]


def test_welford_variance_and_zscore_match_direct_computation():
    y, u = simulate_arx(4000, 5)
    m = RecursiveARX(2, 2, 1, forgetting_factor=0.995)
    res = m.run(y, u)
    first = int(np.argmax(res.model_stable))
    e = np.asarray(res.resid)[first:]
    var = np.asarray(res.variance)
    np.testing.assert_allclose(var[first + 10], np.var(e[:11], ddof=1), rtol=1e-12)
    np.testing.assert_allclose(var[-1], np.var(e, ddof=1), rtol=1e-10)
    np.testing.assert_allclose(m.error_mean, e.mean(), rtol=1e-10, atol=1e-15)
    armed = int(np.argmax(res.variance_stable))
    k = armed + 5
    expected = (e[k - first] - e[:k - first].mean()) / e[:k - first].std(ddof=1)
    np.testing.assert_allclose(np.asarray(res.zscore)[k], expected, rtol=1e-10)
    assert np.isnan(np.asarray(res.zscore)[:armed + 1]).all()


def test_update_and_chunked_run_equal_one_run():
    y, u = simulate_arx(1500, 6, change_at=1200)
    whole = RecursiveARX(2, 2, 1, forgetting_factor=0.98)
    rw = whole.run(y, u)
    step = RecursiveARX(2, 2, 1, forgetting_factor=0.98)
    errs = np.array([step.update(y[t], u[t]) for t in range(len(y))])
    np.testing.assert_array_equal(errs, rw.resid)
    np.testing.assert_array_equal(step.theta_, whole.theta_)
    chunk = RecursiveARX(2, 2, 1, forgetting_factor=0.98)
    r1 = chunk.run(y[:700], u[:700])
    r2 = chunk.run(y[700:], u[700:])
    np.testing.assert_array_equal(np.concatenate([r1.resid, r2.resid]), rw.resid)
    np.testing.assert_array_equal(np.vstack([r1.params, r2.params]), rw.params)
    assert r2.start == 700 and chunk.first_alarm == whole.first_alarm
    assert np.isnan(rw.resid[:2]).all() and np.isfinite(rw.resid[2:]).all()  # start-up: t0 = 2
    chunk.reset()
    assert chunk.nobs == 0 and not chunk.alarmed and np.all(chunk.theta_ == 0)


@pytest.mark.parametrize("kind", ["numpy", "pandas", "xarray"])
def test_data_kinds(kind):
    y, u = simulate_arx(3000, 8, change_at=2500, db=1.0)
    index = pd.date_range("2020-01-01", periods=len(y), freq="50ms")
    if kind == "pandas":
        yy, uu = pd.Series(y, index=index, name="roll"), pd.Series(u, index=index)
    elif kind == "xarray":
        yy = xr.DataArray(y, dims="time", coords={"time": index})
        uu = xr.DataArray(u, dims="time", coords={"time": index})
    else:
        yy, uu = y, u
    res = RecursiveARX(2, 2, 1, forgetting_factor=0.99, freeze_on_alarm=True).run(yy, uu)
    ref = RecursiveARX(2, 2, 1, forgetting_factor=0.99, freeze_on_alarm=True).run(y, u)
    np.testing.assert_array_equal(np.asarray(res.params), ref.params)
    np.testing.assert_array_equal(np.asarray(res.zscore), ref.zscore)
    assert res.first_alarm == ref.first_alarm and res.first_alarm >= 2500
    if kind == "pandas":
        assert isinstance(res.params, pd.DataFrame) and list(res.params.columns) == ["a1", "a2", "b1", "b2"]
        assert isinstance(res.resid, pd.Series) and res.resid.index.equals(index)
        assert res.first_alarm_time == index[res.first_alarm]
    elif kind == "xarray":
        assert isinstance(res.params, xr.DataArray) and res.params.dims == ("time", "channel")
        assert isinstance(res.zscore, xr.DataArray)
        assert res.first_alarm_time == index[res.first_alarm]
    else:
        assert isinstance(res.params, np.ndarray) and res.params.shape == (3000, 4)
        assert res.first_alarm_time == res.first_alarm


def test_nonfinite_policy():
    y, u = simulate_arx(600, 9)
    bad = y.copy()
    bad[300] = np.nan
    with pytest.raises(ValueError, match="y contains NaN/inf.*sample 300"):
        RecursiveARX(2, 2, 1).run(bad, u)
    ubad = u.copy()
    ubad[10] = np.inf
    with pytest.raises(ValueError, match="u contains NaN/inf"):
        RecursiveARX(2, 2, 1).run(y, ubad)
    with pytest.raises(ValueError, match="NaN"):
        RecursiveARX(2, 2, 1).update(np.nan, 0.0)
    m = RecursiveARX(2, 2, 1, nonfinite="skip")
    res = m.run(bad, u)
    assert res.n_skipped == 1 and m.n_skipped == 1 and res.skipped[300] and res.skipped.sum() == 1
    resid = np.asarray(res.resid)
    # the skipped sample and the two that need it as a lagged output have no prediction error
    assert np.isnan(resid[300:303]).all() and np.isfinite(resid[303:]).all()
    assert np.isfinite(m.theta_).all()
    # parameters are not touched by the gap
    np.testing.assert_array_equal(np.asarray(res.params)[302], np.asarray(res.params)[299])


def test_bad_arguments():
    with pytest.raises(ValueError, match="forgetting_factor"):
        RecursiveARX(2, 2, forgetting_factor=0.0)
    with pytest.raises(ValueError, match="forgetting_factor"):
        RecursiveARX(2, 2, forgetting_factor=1.01)
    with pytest.raises(ValueError, match="na"):
        RecursiveARX(-1, 2)
    with pytest.raises(ValueError, match="nb"):
        RecursiveARX(2, -1)
    with pytest.raises(ValueError, match="nk"):
        RecursiveARX(2, 2, nk=-1)
    with pytest.raises(TypeError, match="na"):
        RecursiveARX(1.5, 2)
    with pytest.raises(ValueError, match="without parameters"):
        RecursiveARX(0, 0)
    with pytest.raises(ValueError, match="P0"):
        RecursiveARX(1, 1, P0=-1.0)
    with pytest.raises(ValueError, match="P0"):
        RecursiveARX(1, 1, P0=np.array([[1.0, 2.0], [2.0, 1.0]]))
    with pytest.raises(ValueError, match="P0"):
        RecursiveARX(1, 1, P0=np.eye(3))
    with pytest.raises(ValueError, match="theta0"):
        RecursiveARX(1, 1, theta0=[1.0])
    with pytest.raises(ValueError, match="nonfinite"):
        RecursiveARX(1, 1, nonfinite="ignore")
    with pytest.raises(TypeError, match="freeze_on_alarm"):
        RecursiveARX(1, 1, freeze_on_alarm="yes")
    with pytest.raises(ValueError, match="gate"):
        RecursiveARX(1, 1, gate="scale-free")
    m = RecursiveARX(1, 1)
    with pytest.raises(ValueError, match="same length"):
        m.run(np.ones(10), np.ones(9))
    with pytest.raises(ValueError, match="u is required"):
        m.run(np.ones(10))
    with pytest.raises(ValueError, match="n_inputs"):
        m.run(np.ones(10), np.ones((10, 2)))
    with pytest.raises(ValueError, match="n_inputs"):
        m.update(1.0, [1.0, 2.0])
    with pytest.raises(TypeError, match="y"):
        m.update("a", 1.0)
    # an AR model needs no input
    ar = RecursiveARX(1, 0, P0=1e8)
    rng = np.random.default_rng(0)
    from scipy.signal import lfilter
    y = lfilter([1.0], [1.0, -0.5], rng.standard_normal(2000))
    ar.run(y)
    np.testing.assert_allclose(ar.theta_, [-0.5], atol=0.05)


def test_arm_after_and_freeze():
    change = 3000
    y, u = simulate_arx(4000, 0, change_at=change)
    # a baseline phase longer than the change hides its alarm; the statistics still learn during it
    late = RecursiveARX(2, 2, 1, forgetting_factor=0.995, arm_after=3500).run(y, u)
    free = RecursiveARX(2, 2, 1, forgetting_factor=0.995).run(y, u)
    assert not late.alarm[:3500].any()
    np.testing.assert_array_equal(np.asarray(late.zscore), np.asarray(free.zscore))
    np.testing.assert_array_equal(late.alarm[3500:], free.alarm[3500:])
    early = RecursiveARX(2, 2, 1, forgetting_factor=0.995, arm_after=2000).run(y, u)
    assert change <= early.first_alarm <= change + 10
    # freeze(): parameters, P and error statistics stop; errors and Z-scores are still computed
    m = RecursiveARX(2, 2, 1, forgetting_factor=0.995)
    m.run(y[:2000], u[:2000])
    theta, P, var = m.theta_.copy(), m.P_.copy(), m.error_variance
    assert not m.frozen
    m.freeze()
    res = m.run(y[2000:], u[2000:])
    assert m.frozen and np.isfinite(np.asarray(res.resid)).all()
    np.testing.assert_array_equal(m.theta_, theta)
    np.testing.assert_array_equal(m.P_, P)
    assert m.error_variance == var
    # the frozen model still predicts: its errors equal y - phi' theta with the frozen theta
    phi = np.column_stack([-y[1999:-1], -y[1998:-2], u[1999:-1], u[1998:-2]])
    np.testing.assert_allclose(np.asarray(res.resid), y[2000:] - phi @ theta, rtol=1e-10, atol=1e-12)
    # unfreeze(): adaptation resumes from the held parameters: the first error uses them, then they move
    m = RecursiveARX(2, 2, 1, forgetting_factor=0.995)
    m.run(y[:2000], u[:2000])
    m.freeze()
    m.run(y[2000:2500], u[2000:2500])
    m.unfreeze()
    assert not m.frozen
    resumed = m.run(y[2500:2600], u[2500:2600])
    assert np.asarray(resumed.resid)[0] == pytest.approx(y[2500] - phi[500] @ theta, rel=1e-10)
    np.testing.assert_array_equal(np.asarray(resumed.params)[0] != theta, True)
    m.reset()
    assert not m.frozen
    with pytest.raises(ValueError, match="arm_after"):
        RecursiveARX(2, 2, arm_after=-1)


def _assert_same_run(r1, r2):
    for name in ("params", "resid", "variance", "mean", "zscore", "model_stable", "variance_stable", "alarm",
                 "skipped"):
        np.testing.assert_array_equal(np.asarray(getattr(r1, name)), np.asarray(getattr(r2, name)), err_msg=name)
    assert (r1.first_alarm, r1.first_alarm_time, r1.n_skipped, r1.start) == \
        (r2.first_alarm, r2.first_alarm_time, r2.n_skipped, r2.start)


@pytest.mark.parametrize("freeze", [False, True])
def test_get_state_set_state_resumes_exactly(freeze):
    y, u = simulate_arx(4000, 0, change_at=3000)
    y[2700] = np.nan   # a skipped sample in the second part: counters and buffers must be restored too
    m = RecursiveARX(2, 2, 1, forgetting_factor=0.995, trend="c", freeze_on_alarm=True, nonfinite="skip")
    m.run(y[:2500], u[:2500])
    assert m.model_stable and m.variance_stable and not m.alarmed   # Welford state and gates are live
    if freeze:
        m.freeze()
    s = m.get_state()
    theta_id = id(m.theta_)
    first = m.run(y[2500:], u[2500:])
    assert first.n_skipped == 1 and (freeze or first.first_alarm is not None)
    end = m.get_state()
    m.set_state(s)
    assert id(m.theta_) == theta_id and m.nobs == 2500 and m.n_skipped == 0 and not m.alarmed
    assert m.frozen == freeze
    again = m.run(y[2500:], u[2500:])
    _assert_same_run(first, again)
    for name in ("theta", "P", "y_history", "u_history", "counters", "error_stats", "P_bound", "regressor_scales"):
        np.testing.assert_array_equal(getattr(m.get_state(), name), getattr(end, name), err_msg=name)
    # the snapshot is a read-only copy, reusable, and restores into another estimator with the same options
    assert not s.theta.flags.writeable and not s.counters.flags.writeable
    other = RecursiveARX(2, 2, 1, forgetting_factor=0.995, trend="c", freeze_on_alarm=True, nonfinite="skip")
    other.set_state(s)
    _assert_same_run(first, other.run(y[2500:], u[2500:]))


def test_set_state_rejects_foreign_states():
    m = RecursiveARX(2, 2, 1)
    with pytest.raises(TypeError, match="get_state"):
        m.set_state({"theta": np.zeros(4)})
    with pytest.raises(ValueError, match="theta"):
        m.set_state(RecursiveARX(3, 2, 1).get_state())
    # a failed restore leaves the estimator untouched (all shapes are checked before anything is copied)
    bad = dataclasses.replace(m.get_state(), theta=np.ones(4), u_history=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="u_history"):
        m.set_state(bad)
    np.testing.assert_array_equal(m.theta_, np.zeros(4))


# ------------------------------------------------------------------------------------------- relative gate
def two_input_arx(n=3000, seed=4):
    """y = 0.3 + 0.6 y[-1] + 0.5 u0 - 0.2 u0[-1] + 0.7 u1 + 0.1 u1[-1] + e (sd 0.2), with a few NaN samples."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 2))
    y = np.zeros(n)
    for t in range(1, n):
        y[t] = 0.3 + 0.6 * y[t - 1] + 0.5 * u[t, 0] - 0.2 * u[t - 1, 0] + 0.7 * u[t, 1] + 0.1 * u[t - 1, 1] \
            + 0.2 * rng.standard_normal()
    y[[30, 31, 80]] = np.nan       # skipped samples: no prediction error, they neither count nor break a run
    u[55, 1] = np.nan
    return y, u


def two_input_model(scales=(1.0, 1.0, 1.0), gate="relative"):
    """The two-input model of ``two_input_arx`` with a ``P0`` that makes its estimate equivariant when y, u0, u1
    are scaled by ``scales`` (``P0 ~ 1 / regressor**2``; the constant's regressor is 1)."""
    cy, c0, c1 = scales
    p0 = 1e4 / np.array([1.0, cy, c0, c0, c1, c1]) ** 2
    return RecursiveARX(1, 2, 0, 0.995, P0=np.diag(p0), n_inputs=2, trend="c", nonfinite="skip", gate=gate)


def first_stable(res):
    return int(np.argmax(res.model_stable)) if res.model_stable.any() else -1


def test_relative_gate_is_the_equation_of_the_notes():
    """The first stable sample is where ||D dtheta|| < eps ||D theta(k-1)|| held for stable_samples samples with a
    prediction error in a row, computed here from the parameter history (which the gate does not change)."""
    y, u = two_input_arx()
    res = two_input_model().run(y, u)
    theta = np.vstack([np.zeros((1, 6)), np.asarray(res.params)])
    ymax = np.fmax.accumulate(np.abs(y))
    umax = np.fmax.accumulate(np.abs(u), axis=0)
    scale = np.column_stack([np.ones_like(y), ymax, umax[:, 0], umax[:, 0], umax[:, 1], umax[:, 1]])
    step = (np.abs(np.diff(theta, axis=0)) * scale).max(axis=1)
    size = (np.abs(theta[:-1]) * scale).max(axis=1)
    run, expected = 0, -1
    for k in np.flatnonzero(np.isfinite(np.asarray(res.resid))):
        run = run + 1 if step[k] < 1e-2 * size[k] else 0
        if run == 25:
            expected = k
            break
    assert expected == 134
    assert first_stable(res) == expected
    np.testing.assert_array_equal(res.model_stable, np.arange(len(y)) >= expected)
    # the gate does not touch the estimate: the same parameters as under the absolute gate
    absolute = two_input_model(gate="absolute").run(y, u)
    np.testing.assert_array_equal(np.asarray(absolute.params), np.asarray(res.params))


@pytest.mark.parametrize("scales", [(1e-3, 1e-3, 1e-3), (1e3, 1e3, 1e3), (1e3, 1.0, 1.0), (1.0, 1e-3, 1e3),
                                    (1e-3, 1e3, 1.0)])
def test_relative_gate_arms_at_the_same_sample_in_any_units(scales):
    y, u = two_input_arx()
    ref = first_stable(two_input_model().run(y, u))
    cy, c0, c1 = scales
    got = two_input_model(scales).run(y * cy, u * [c0, c1])
    assert first_stable(got) == ref
    assert ref > 0


def test_absolute_gate_depends_on_the_units():
    """What gate="relative" is for: the absolute bound arms the same equivariant estimate elsewhere, or never."""
    y, u = two_input_arx()

    def stable_at(cy):
        return first_stable(two_input_model((cy, 1.0, 1.0), gate="absolute").run(y * cy, u))

    at = [stable_at(c) for c in (1e-3, 1.0, 1e3)]
    assert len(set(at)) == 3 and -1 in at, at


def test_relative_gate_state_round_trip():
    y, u = two_input_arx()
    k = first_stable(two_input_model().run(y, u))
    m = two_input_model()
    m.run(y[:k - 10], u[:k - 10])                  # inside the arming run: its counter and the scales are live
    state = m.get_state()
    assert not m.model_stable and state.counters[1] > 0
    np.testing.assert_array_equal(state.regressor_scales,
                                  [np.nanmax(np.abs(y[:k - 10])), *np.nanmax(np.abs(u[:k - 10]), axis=0)])
    assert not state.regressor_scales.flags.writeable
    first = m.run(y[k - 10:], u[k - 10:])
    assert first_stable(first) == 10
    # restored into the same or a fresh estimator: the rest of the stream again, identical, sample by sample too
    m.set_state(state)
    _assert_same_run(first, m.run(y[k - 10:], u[k - 10:]))
    other = two_input_model()
    other.set_state(state)
    _assert_same_run(first, other.run(y[k - 10:], u[k - 10:]))
    other.set_state(state)
    for t in range(k - 10, k):
        other.update(y[t], u[t])
    assert not other.model_stable
    other.update(y[k], u[k])
    assert other.model_stable
    # scales that do not fit the inputs are refused before anything is copied; reset() clears them
    before = other.get_state()
    with pytest.raises(ValueError, match="regressor_scales"):
        other.set_state(dataclasses.replace(state, regressor_scales=np.zeros(2)))
    np.testing.assert_array_equal(other.get_state().regressor_scales, before.regressor_scales)
    other.reset()
    np.testing.assert_array_equal(other.get_state().regressor_scales, np.zeros(3))


def test_relative_gate_counts_a_frozen_step_as_zero():
    """While adaptation is halted the step taken is 0: a frozen model away from theta = 0 passes the gate."""
    y, u = two_input_arx()
    m = two_input_model()
    m.run(y[:100], u[:100])
    assert not m.model_stable
    carried = int(m.get_state().counters[1])       # passing samples in a row so far
    m.freeze()
    res = m.run(y[100:200], u[100:200])             # no NaN here: every sample has a prediction error
    assert np.all(np.asarray(res.params) == m.theta_)
    assert first_stable(res) == 24 - carried < 34   # adapting, the model arms at sample 134


# --- joint bound of P0 and the sample magnitude (Notes, Scale) ----------------------------------------------
def test_large_p0_with_large_samples_is_refused_not_collapsed():
    # P0 = 1e50 with samples of 1e140: the compiled loop's products phi_i (P0 phi)_i overflow, P collapsed to 0
    # and theta stayed at 0 without a word; the pair is now refused before anything is processed
    y, u = simulate_arx(300, 31)
    c = 1e140 / max(np.abs(y).max(), np.abs(u).max())
    m = RecursiveARX(2, 2, 1, P0=1e50)
    with pytest.raises(ValueError, match=r"[yu] has a sample of magnitude .*: P0 \(largest absolute row sum "
                                         r"1e\+50\) allows samples within \+-1e\+129 only"):
        m.run(c * y, c * u)
    with pytest.raises(ValueError, match=r"y has a sample of magnitude 1e\+140 .* lower P0"):
        m.update(1e140, 1.0)
    assert m.nobs == 0 and not m.theta_.any() and m.P_[0, 0] == 1e50      # nothing was processed
    # a matrix P0 counts by its largest absolute row sum; below 1e4 the bound is the plain 1e152
    with pytest.raises(ValueError, match=r"P0 \(largest absolute row sum 3e\+50\)"):
        RecursiveARX(1, 1, P0=np.array([[1e50, 1e50], [1e50, 2e50]])).update(1e130, 0.0)
    RecursiveARX(1, 1, P0=1e4).update(1e152, -1e152)


@pytest.mark.parametrize("lam, shape", [(1.0, "scalar"), (0.99, "scalar"), (1.0, "matrix")])
def test_estimate_is_least_squares_wherever_p0_and_scale_are_accepted(lam, shape):
    """Sweep P0 x the largest sample: every pair accepted gives the (weighted) batch least-squares estimate, every
    pair refused has P0 * sample**2 above 1e308 (fresh compile in CI: the failure came from fastmath codegen)."""
    y, u = simulate_arx(1500, 32, nk=0)
    top = max(np.abs(y).max(), np.abs(u).max())
    y, u = y / top, u / top
    X, Y, _ = regressor(y, u, 2, 2, 0)
    w = np.sqrt(lam ** np.arange(len(Y))[::-1])
    ref = np.linalg.lstsq(X * w[:, None], Y * w, rcond=None)[0]
    shape_P0 = np.eye(4) if shape == "scalar" else 0.5 * np.eye(4) + 0.125 * np.ones((4, 4))   # row sums 1
    refused = []
    for p0 in (1e-4, 1.0, 1e4, 1e20, 1e50, 1e80, 1e100):
        for mag in (1e-100, 1.0, 1e100, 1e103, 1e120, 1e128, 1e130, 1e140, 1e150, 1e152):
            m = RecursiveARX(2, 2, 0, lam, P0=p0 * shape_P0 if shape == "matrix" else p0)
            try:
                m.run(mag * y, mag * u)
            except ValueError as exc:
                assert "P0" in str(exc)
                refused.append((p0, mag))
                continue
            if p0 * mag**2 >= 1e8:      # the prior (precision 1 / P0 against data of size mag**2) weighs nothing
                np.testing.assert_allclose(m.theta_, ref, atol=1e-3, err_msg=f"P0={p0:g}, samples up to {mag:g}")
            assert p0 * mag**2 <= 1e308
    assert refused == [(p0, mag) for p0 in (1e-4, 1.0, 1e4, 1e20, 1e50, 1e80, 1e100)
                       for mag in (1e-100, 1.0, 1e100, 1e103, 1e120, 1e128, 1e130, 1e140, 1e150, 1e152)
                       if p0 * mag**2 > 1e308]
    assert (1e50, 1e140) in refused and (1e4, 1e152) not in refused


@pytest.mark.parametrize("na, nb, nk, n_inputs, trend", [(2, 2, 1, 1, "c"), (0, 3, 0, 2, "n"), (3, 0, 0, 1, "c"),
                                                         (1, 1, 2, 2, "n"), (0, 0, 0, 1, "c")])
def test_regressors_give_the_a_priori_errors_of_run(na, nb, nk, n_inputs, trend):
    """e(t) = y(t) - phi(t)' theta(t-1) with run's own parameter history: the regressor of the kernel, exactly."""
    rng = np.random.default_rng(31)
    y, u = simulate_arx(400, rng)
    u = np.column_stack([u] + [rng.standard_normal(400) for _ in range(n_inputs - 1)]) if n_inputs > 1 else u
    u = u if nb else None
    kw = dict(n_inputs=n_inputs, trend=trend, forgetting_factor=0.99)
    res = RecursiveARX(na, nb, nk, **kw).run(y, u)
    model = RecursiveARX(na, nb, nk, **kw)
    phi = model.regressors(y, u)
    lag = model.max_lag
    assert lag == max(na, nk + nb - 1 if nb else 0) and phi.shape == (400 - lag, model.n_params)
    theta_before = np.vstack([np.zeros((1, model.n_params)), res.params[:-1]])
    e = y[lag:] - np.einsum("ij,ij->i", phi, theta_before[lag:])
    np.testing.assert_allclose(e, res.resid[lag:], rtol=1e-12, atol=1e-12)
    assert np.isnan(res.resid[:lag]).all() and np.isfinite(res.resid[lag:]).all()
    assert model.nobs == 0                                  # the estimator's state is not touched


def test_regressors_keep_the_kind_index_and_names():
    rng = np.random.default_rng(32)
    y, u = simulate_arx(50, rng)
    idx = pd.date_range("2024-01-01", periods=50, freq="10ms")
    model = RecursiveARX(2, 2, 1, trend="c")
    phi = model.regressors(pd.Series(y, index=idx), pd.Series(u, index=idx))
    assert isinstance(phi, pd.DataFrame) and list(phi.columns) == ["const", "a1", "a2", "b1", "b2"]
    assert phi.index.equals(idx[2:])
    np.testing.assert_array_equal(phi["a1"], -y[1:-1])
    np.testing.assert_array_equal(phi["b2"], u[:-2])
    assert not np.signbit(RecursiveARX(1, 0).regressors(np.zeros(3))).any()    # -y of 0 is 0.0, not -0.0
    da = model.regressors(xr.DataArray(y, dims="time", coords={"time": np.arange(50) / 100}), u)
    assert isinstance(da, xr.DataArray) and da.shape == (48, 5)
    np.testing.assert_array_equal(da["time"].values, np.arange(2, 50) / 100)


def test_regressors_refuse_bad_records_by_name():
    model = RecursiveARX(2, 2, 1)
    with pytest.raises(ValueError, match="y"):
        model.regressors(np.ones(2), np.ones(2))
    with pytest.raises(ValueError, match="u contains NaN/inf \\(first at sample 3\\)"):
        model.regressors(np.ones(10), np.r_[np.ones(3), np.nan, np.ones(6)])
    with pytest.raises(ValueError, match="same length"):
        model.regressors(np.ones(10), np.ones(9))
    with pytest.raises(ValueError, match="u is required"):
        model.regressors(np.ones(10))
    with pytest.raises(ValueError, match="y"):
        model.regressors(np.r_[np.ones(5), np.inf, np.ones(4)], np.ones(10))


def test_regressors_refuse_an_unbounded_allocation(monkeypatch):
    import tsfdi.models.lstsq as lstsq

    monkeypatch.setattr(lstsq, "MAX_VALUES", 1000)
    model = RecursiveARX(2, 2, 1)
    assert model.regressors(np.ones(250), np.ones(250)).shape == (248, 4)
    with pytest.raises(ValueError, match="y with 251 samples: the regressors \\(251 x 4\\)"):
        model.regressors(np.ones(251), np.ones(251))


@pytest.mark.parametrize("trend", ["n", "c"])
def test_theta0_from_a_batch_arx_fit_seeds_its_coefficients(trend):
    """Issue 29, item 7: ``RecursiveARX(theta0=ARX(...).fit().params)`` seeded the wrong coefficients (ARX groups its
    params by lag, RecursiveARX by kind). The ARXResults (or its labelled params) is mapped: with a tiny P0 the
    estimate stays at theta0 and the a-priori errors are the batch model's residuals."""
    rng = np.random.default_rng(29)
    n = 600
    u = rng.standard_normal((n, 2))
    y = np.zeros(n)
    for t in range(3, n):
        y[t] = (0.5 * y[t - 1] - 0.2 * y[t - 2] + 0.8 * u[t - 1, 0] + 0.3 * u[t - 2, 0] - 0.4 * u[t - 1, 1]
                + 0.2 * u[t - 3, 1] + (1.0 if trend == "c" else 0.0) + 0.1 * rng.standard_normal())
    batch = tsfdi.ARX(y, u, 2, 3, nk=1, trend=trend).fit()
    labelled = tsfdi.ARX(pd.Series(y), pd.DataFrame(u, columns=["p", "q"]), 2, 3, nk=1, trend=trend).fit()
    for theta0 in (batch, labelled, labelled.params):
        m = RecursiveARX(2, 3, nk=1, n_inputs=2, trend=trend, theta0=theta0, P0=1e-12)
        np.testing.assert_array_equal(m.theta_[m.trend == "c":][:2], batch.a)
        np.testing.assert_array_equal(m.theta_[-6:], batch.b.ravel())
        e = np.asarray(m.run(y, u).resid)[batch.model.max_lag:]
        np.testing.assert_allclose(e, batch.residuals(y, u), rtol=0, atol=1e-8)
    fresh = RecursiveARX(2, 3, nk=1, n_inputs=2, trend=trend, theta0=batch)
    own = pd.Series(fresh.theta_, index=fresh.param_names)      # labelled in its own order: taken as it is
    np.testing.assert_array_equal(RecursiveARX(2, 3, nk=1, n_inputs=2, trend=trend, theta0=own).theta_, own)
    with pytest.raises(ValueError, match=r"theta0 is a ARX fit of other orders: \(na, nb, nk, n_inputs, trend\) = "
                                         rf"\(2, 3, 1, 2, '{trend}'\), this estimator has \(2, 3, 0, 2, '{trend}'\)"):
        RecursiveARX(2, 3, nk=0, n_inputs=2, trend=trend, theta0=batch)
    foreign = labelled.params.set_axis([f"x{i}" for i in range(len(labelled.params))])
    with pytest.raises(ValueError, match=r"theta0 is labelled \['x0', .*: neither this estimator's parameters"):
        RecursiveARX(2, 3, nk=1, n_inputs=2, trend=trend, theta0=foreign)
    ar = tsfdi.AR(y, 2, trend=trend).fit()          # an AR fit seeds an estimator without input
    np.testing.assert_array_equal(RecursiveARX(2, 0, trend=trend, theta0=ar).theta_, np.asarray(ar.params))

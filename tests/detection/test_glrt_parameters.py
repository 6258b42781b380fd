"""GLRT on parameter changes (paper 002, section 3): the likelihood ratio by brute force, the mean-change GLRT as a
special case, the joint residual-parameter statistic, chi-square sizes by Monte Carlo, RLS references, inputs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import tsfdi
from tsfdi.detection.glrt import ParameterGLRT
from tests.conftest import as_kind, assert_kind, to_numpy


def _llr(y, phi, ref, j, k, sigma):
    """Eq. 2 maximised over the change nu, literally: (RSS under H0 - RSS under H1) / (2 sigma^2), by lstsq."""
    r = y[j:k + 1] - phi[j:k + 1] @ ref[j]
    nu = np.linalg.lstsq(phi[j:k + 1], r, rcond=None)[0]
    return (r @ r - np.sum((r - phi[j:k + 1] @ nu) ** 2)) / (2 * sigma ** 2)


def _brute(y, phi, ref, window, sigma):
    return np.array([max(_llr(y, phi, ref, j, k, sigma) for j in range(max(0, k - window + 1), k + 1))
                     for k in range(len(y))])


def _arx(rng, n, theta=(0.6, 1.0, -0.4)):
    """y[t] = -a y[t-1] + b0 u[t] + b1 u[t-1] + e[t] and its regressor rows [-y[t-1], u[t], u[t-1]]."""
    u = rng.standard_normal(n + 1)
    e = rng.standard_normal(n + 1)
    y = np.zeros(n + 1)
    for t in range(1, n + 1):
        y[t] = -theta[0] * y[t - 1] + theta[1] * u[t] + theta[2] * u[t - 1] + e[t]
    phi = np.column_stack([-y[:-1], u[1:], u[:-1]])
    return y[1:], phi, np.array(theta)


def test_equals_the_likelihood_ratio_fixed_reference():
    rng = np.random.default_rng(0)
    y, phi, theta = _arx(rng, 120)
    y[80:] += phi[80:] @ np.array([0.0, 0.8, 0.0])            # the input gain jumps at sample 80
    g = ParameterGLRT(15, scale=1.0).statistic(y, phi, theta)
    np.testing.assert_allclose(g, _brute(y, phi, np.broadcast_to(theta, phi.shape), 15, 1.0), rtol=1e-9, atol=1e-10)


def test_equals_the_likelihood_ratio_parameter_history():
    """With a history the reference of a change at j is row j - 1 (row 0 for j = 0)."""
    rng = np.random.default_rng(1)
    y, phi, theta = _arx(rng, 90)
    hist = theta + 0.05 * np.cumsum(rng.standard_normal((90, 3)), axis=0)
    ref = np.concatenate([hist[:1], hist[:-1]])
    g = ParameterGLRT(12, scale=0.7).statistic(y, phi, hist)
    np.testing.assert_allclose(g, _brute(y, phi, ref, 12, 0.7), rtol=1e-9, atol=1e-10)


def test_one_constant_regressor_is_the_mean_change_glrt():
    x = np.random.default_rng(2).standard_normal(3000) * 2.0
    x[2000:] += 1.0
    np.testing.assert_allclose(ParameterGLRT(50, scale=2.0).statistic(x, np.ones(3000)),
                               tsfdi.GLRT(50, scale=2.0).statistic(x), rtol=1e-12, atol=1e-12)


def test_joint_statistic_is_mean_plus_orthogonal_parameters():
    """joint S = residual mean-change S + parameter-change S of the regressors demeaned on the window (paper 002's
    two detectors), and the joint GLRT is the max over j of that sum."""
    rng = np.random.default_rng(3)
    y, phi, theta = _arx(rng, 60)
    r = y - phi @ theta
    ones = np.ones((60, 1))
    for j, k in ((10, 40), (0, 59), (35, 36)):
        seg = r[j:k + 1]
        mean_part = seg.sum() ** 2 / (2 * seg.size)                       # eq. 3's S for a fixed j
        rc, xc = seg - seg.mean(), phi[j:k + 1] - phi[j:k + 1].mean(axis=0)
        fit = xc @ np.linalg.lstsq(xc, rc, rcond=None)[0]
        param_part = (rc @ rc - np.sum((rc - fit) ** 2)) / 2                # parameters, orthogonal to the mean
        joint = _llr(r, np.hstack([ones, phi]), np.zeros((60, 4)), j, k, 1.0)
        assert joint == pytest.approx(mean_part + param_part, rel=1e-9)
    g = ParameterGLRT(20, scale=1.0, joint=True).statistic(y, phi, theta)
    np.testing.assert_allclose(g, _brute(r, np.hstack([ones, phi]), np.zeros((60, 4)), 20, 1.0), rtol=1e-9)


def _size(test, rng, reps, n, d, joint_ref=None):
    """Alarm frequency of the last sample of ``reps`` independent records (independent Bernoulli trials)."""
    hits = 0
    for _ in range(reps):
        phi = rng.standard_normal((n, d))
        theta = np.arange(1.0, d + 1)
        y = phi @ theta + rng.standard_normal(n)
        hits += bool(test.statistic(y, phi, theta)[-1] > test.critical_value(d + test.joint))
    return hits / reps


def _band(p, reps, z=4.0):
    return z * np.sqrt(p * (1 - p) / reps)


def test_size_window_one_is_exactly_chi2_one():
    """A window of one sample has rank one: 2 g ~ chi2(1) whatever d, so the rate at chi2_{1-a}(1) / 2 is a."""
    alpha, reps = 0.05, 4000
    test = ParameterGLRT(1, scale=1.0, threshold=stats.chi2.isf(alpha, 1) / 2)
    p = _size(test, np.random.default_rng(4), reps, 3, 3)
    assert abs(p - alpha) < _band(alpha, reps)


@pytest.mark.parametrize("joint", [False, True])
def test_size_theoretical_threshold_monte_carlo(joint):
    """Per-sample false-alarm probability with gamma = chi2_{1 - a/M}(d) / 2: at most a (union bound over the M
    change instants), at least a / M (the full-window statistic alone is chi2(d) with that tail)."""
    alpha, window, reps = 0.05, 10, 3000
    test = ParameterGLRT(window, scale=1.0, alpha=alpha, joint=joint)
    p = _size(test, np.random.default_rng(5 + joint), reps, window, 2)
    assert alpha / window - _band(alpha / window, reps) <= p <= alpha + _band(alpha, reps)
    assert test.critical_value(2 + joint) == pytest.approx(stats.chi2.isf(alpha / window, 2 + joint) / 2)


def test_size_with_a_recursive_least_squares_reference():
    """Reference = the RLS estimate before the window (lambda = 1, after 400 samples): the reference's own
    estimation error inflates the statistic by about n / j only, so the rate stays below alpha."""
    rng = np.random.default_rng(7)
    alpha, window, reps, n = 0.05, 10, 600, 420
    test = ParameterGLRT(window, scale=1.0, alpha=alpha)
    hits = 0
    for _ in range(reps):
        y, phi, _ = _arx(rng, n)
        params = tsfdi.RecursiveARX(0, 1, n_inputs=3, P0=1e6).run(y, phi).params
        hits += bool(test.statistic(y[1:], phi[1:], params[1:])[-1] > test.critical_value(3))
    assert hits / reps <= alpha + _band(alpha, reps)


def test_detects_a_parameter_jump_and_estimates_it():
    rng = np.random.default_rng(18)
    y, phi, theta = _arx(rng, 1500)
    nu = np.array([0.0, 1.0, 0.0])
    y[1000:] += phi[1000:] @ nu
    d = ParameterGLRT(80, scale=1.0, alpha=1e-4).test(y, phi, theta)
    assert d.reject and d.test == "ParameterGLRT" and d.df.tolist() == [3.0]
    assert 1000 <= d.details["first_alarm"] <= 1060
    assert abs(d.details["change_index"] - 1000) <= 15
    np.testing.assert_allclose(d.details["change"].to_numpy(), nu, atol=0.35)
    healthy = ParameterGLRT(80, scale=1.0, alpha=1e-4).test(y[:1000], phi[:1000], theta)
    assert not healthy.reject and healthy.details["first_alarm"] == -1
    assert np.isnan(healthy.details["change"]).all()


def test_kinds_and_names(kind):
    rng = np.random.default_rng(9)
    y, phi, theta = _arx(rng, 200)
    yk = as_kind(y, kind)
    xk = as_kind(phi, kind, channels=["a1", "b0", "b1"])
    g = ParameterGLRT(20).statistic(yk, xk, theta)
    assert_kind(g, kind, 1)
    np.testing.assert_allclose(to_numpy(g), ParameterGLRT(20).statistic(y, phi, theta))
    d = ParameterGLRT(20, alpha=0.5).test(yk, xk, theta)
    assert_kind(d.details["g"], kind, 1)
    names = ["a1", "b0", "b1"] if kind != "numpy" else ["y0", "y1", "y2"]
    assert d.details["change"].index.tolist() == names
    assert ParameterGLRT(20, joint=True, alpha=0.5).test(yk, xk, theta).details["change"].index[0] == "mean"


def test_scale_invariance_and_unexcited_directions():
    rng = np.random.default_rng(10)
    y, phi, theta = _arx(rng, 300)
    g = ParameterGLRT(30, scale=1.0).statistic(y, phi, theta)
    big = phi * np.array([1e120, 1e-90, 3.0])
    np.testing.assert_allclose(ParameterGLRT(30, scale=1e200).statistic(y * 1e200, big, theta / [1e120, 1e-90, 3.0]
                                                                          * 1e200), g, rtol=1e-8)
    # a zero column and a duplicated column carry no information: the statistic of the other columns
    wide = np.column_stack([phi, np.zeros(300), phi[:, 1]])
    np.testing.assert_allclose(ParameterGLRT(30, scale=1.0).statistic(y, wide, np.r_[theta, 0.0, 0.0]), g,
                               rtol=1e-7)


def test_calibrate_records_and_empirical_threshold():
    rng = np.random.default_rng(11)
    recs = [_arx(rng, 3000) for _ in range(3)]
    test = ParameterGLRT(30, threshold=tsfdi.EmpiricalThreshold(1e-3)).calibrate(
        [r[0] for r in recs], [r[1] for r in recs], recs[0][2])
    assert test.scale_ == pytest.approx(1.0, rel=0.05)
    assert test.healthy_statistic_.shape == (9000,)
    assert test.critical_value(3) == test.threshold.threshold_
    assert test.test(*recs[0]).details["threshold_method"] in ("empirical", "gpd")
    with pytest.raises(ValueError, match="not calibrated"):
        ParameterGLRT(30, threshold=tsfdi.EmpiricalThreshold(1e-3)).test(*recs[0])


def test_critical_value_is_continuous_below_the_float_range():
    test = ParameterGLRT(10, alpha=0.1)
    lo, hi = ParameterGLRT(10, alpha=1e-299 * (1 - 1e-9)), ParameterGLRT(10, alpha=1e-299 * (1 + 1e-9))
    for df in (2, 3, 7):
        assert np.isfinite(ParameterGLRT(10, alpha=1e-320).critical_value(df))
        assert lo.critical_value(df) == pytest.approx(hi.critical_value(df), rel=1e-6)
        assert test.critical_value(df) < lo.critical_value(df) < ParameterGLRT(10, alpha=1e-320).critical_value(df)


@pytest.mark.parametrize("args, kwargs, exc, match", [
    ((np.zeros(5), np.ones((4, 2))), {}, ValueError, "regressors must have one row per sample"),
    ((np.zeros(5), np.ones((5, 2)), [1.0, 2.0, 3.0]), {}, ValueError, "params must be a reference vector"),
    ((np.zeros(5), np.ones((5, 2)), np.ones((4, 2))), {}, ValueError, "params must be a reference vector"),
    ((np.zeros(5), np.ones((5, 2))), {}, ValueError, "scale cannot be estimated"),
    ((np.r_[0.0, np.nan, 1, 2, 3], np.ones((5, 1))), {}, ValueError, "y contains 1 NaN"),
    ((np.zeros(5), "abc"), {}, TypeError, "regressors"),
])
def test_input_errors(args, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        ParameterGLRT(3).test(*args, **kwargs)


def test_option_errors():
    with pytest.raises(ValueError, match="window must be >= 1"):
        ParameterGLRT(0)
    with pytest.raises(TypeError, match="joint must be True or False"):
        ParameterGLRT(5, joint=1)
    with pytest.raises(ValueError, match="threshold must be one of"):
        ParameterGLRT(5, threshold="empirical")
    with pytest.raises(ValueError, match="scale must be > 0"):
        ParameterGLRT(5, scale=-1.0)


def test_glrt_calibrate_accepts_records():
    """GLRT.calibrate on a list of records: one scale for all, windows never straddle two records."""
    rng = np.random.default_rng(12)
    a, b = rng.standard_normal(4000), rng.standard_normal(3000) + 5.0
    gl = tsfdi.GLRT(20, threshold=tsfdi.EmpiricalThreshold(1e-2)).calibrate([a, b])
    pooled = np.concatenate([a, b])
    assert gl.scale_[0] == pytest.approx(pooled.std(ddof=1))
    expected = np.concatenate([tsfdi.GLRT(20, scale=gl.scale_).statistic(x) for x in (a, b)])
    np.testing.assert_allclose(gl.healthy_statistic_[:, 0], expected)
    one = tsfdi.GLRT(20, threshold=tsfdi.EmpiricalThreshold(1e-2)).calibrate(list(pooled[:3000]))  # numbers: a record
    assert one.healthy_statistic_.shape == (3000, 1)


def test_rls_reference_with_the_model_regressors():
    """Paper 002's use: the GLRT on the RLS parameter history, regressors from ``RecursiveARX.regressors``
    (after the estimator's start-up, ``SETTLE`` samples); calibrated on healthy records, it stays quiet on the
    healthy part of a record whose b0 jumps and alarms soon after the jump."""
    settle = 300
    rng = np.random.default_rng(21)
    theta = (0.6, 1.0, -0.4)

    def record(n, jump_at=None):
        u, e = rng.standard_normal(n), 0.5 * rng.standard_normal(n)
        y = np.zeros(n)
        for t in range(1, n):
            b0 = theta[1] + (1.0 if jump_at is not None and t >= jump_at else 0.0)
            y[t] = -theta[0] * y[t - 1] + b0 * u[t] + theta[2] * u[t - 1] + e[t]
        return y, u

    def inputs(y, u):
        model = tsfdi.RecursiveARX(1, 2, 0, forgetting_factor=0.995)
        params = model.run(y, u).params
        keep = slice(settle - model.max_lag, None)       # regressor rows start at sample max_lag
        return y[settle:], model.regressors(y, u)[keep], params[settle:]

    test = ParameterGLRT(50, threshold=tsfdi.EmpiricalThreshold(1e-3))
    healthy = [inputs(*record(3000)) for _ in range(3)]
    test.calibrate([h[0] for h in healthy], [h[1] for h in healthy], [h[2] for h in healthy])
    d = test.test(*inputs(*record(3000, jump_at=2000)))
    assert d.reject and 2000 <= settle + d.details["first_alarm"] <= 2100

"""Issue 18, models: numerics that survive scale, exact fits, option ranges, memory bounds, argument types.

Cause 3 (scale, exact fits, leaked LinAlgError), cause 4 (RecursiveARX options that produced NaN), cause 5
(orders and lengths checked against the data and a memory limit before allocating) and cause 9
(``RecursiveARX.update`` with bools, a VAR ``sigma`` given as an empty string).
"""

import warnings

import numpy as np
import pandas as pd
import pytest
from scipy import linalg
from scipy import signal as sps

import tsfdi
from tsfdi.exceptions import IllConditionedWarning
from tsfdi.models import AR, ARX, VAR, RecursiveARX
from tsfdi.models import lstsq as lstsq_module


def ar2(n, rng):
    y = sps.lfilter([1.0], [1.0, -0.5, 0.2], np.random.default_rng(rng).standard_normal(n))
    return y / np.abs(y).max()


def var2(n, rng):
    rng = np.random.default_rng(rng)
    y = ar2(n, rng)
    return np.column_stack([y, 0.5 * np.roll(y, 2) + 0.3 * rng.standard_normal(n)])


def arx_data(n, rng):
    rng = np.random.default_rng(rng)
    u = rng.standard_normal(n)
    y = sps.lfilter([0.0, 0.5, 0.3], [1.0, -0.6, 0.1], u) + 0.05 * rng.standard_normal(n)
    return y, u


SCALES = [1e-150, 2.0**-400, 1e-40, 1e40, 2.0**400, 1e150]


# --- cause 3: scale ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("c", SCALES)
def test_ar_results_are_scale_equivariant(c):
    y = ar2(400, 0)
    base = AR(y, 3, "c").fit()
    res = AR(c * y, 3, "c").fit()
    np.testing.assert_allclose(res.ar_coefs, base.ar_coefs, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(res.intercept, c * base.intercept, rtol=1e-10)
    np.testing.assert_allclose(res.sigma2, c * c * base.sigma2, rtol=1e-12)
    np.testing.assert_allclose(res.llf, base.llf - res.nobs * np.log(c), rtol=1e-13)
    np.testing.assert_allclose(res.bic, base.bic + 2 * res.nobs * np.log(c), rtol=1e-13)
    np.testing.assert_allclose(res.rss_sss, base.rss_sss, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(res.resid), c * np.asarray(base.resid), rtol=1e-9, atol=1e-12 * c)
    assert all(np.isfinite([res.sigma2, res.llf, res.aic, res.bic]))


@pytest.mark.parametrize("c", SCALES)
def test_var_and_arx_results_are_scale_equivariant(c):
    Y = var2(400, 1)
    base = VAR(Y, 2, "c").fit()
    res = VAR(c * Y, 2, "c").fit()
    np.testing.assert_allclose(res.coefs, base.coefs, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(res.sigma, c * c * base.sigma, rtol=1e-12)
    np.testing.assert_allclose(res.llf, base.llf - 2 * res.nobs * np.log(c), rtol=1e-12)
    y, u = arx_data(400, 2)
    bx = ARX(y, u, 2, 2, 1, "c").fit()
    rx = ARX(c * y, c * u, 2, 2, 1, "c").fit()
    np.testing.assert_allclose(rx.a, bx.a, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(rx.b, bx.b, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(rx.llf, bx.llf - rx.nobs * np.log(c), rtol=1e-12)


def test_power_of_two_scale_is_exact_for_the_lags():
    y = ar2(300, 3)
    base = AR(y, 4).fit()
    for k in (-490, -200, 200, 490):
        res = AR(np.ldexp(y, k), 4).fit()
        np.testing.assert_array_equal(res.ar_coefs, base.ar_coefs)
        assert res.sigma2 == np.ldexp(base.sigma2, 2 * k)


@pytest.mark.parametrize("c", SCALES)
def test_select_order_and_held_out_do_not_depend_on_scale(c):
    y = ar2(2000, 4)
    sel = tsfdi.select_order(c * y, 10, trend="c")
    ref = tsfdi.select_order(y, 10, trend="c")
    assert sel.selected == ref.selected == 2
    np.testing.assert_allclose(sel.table["bic"], ref.table["bic"] + 2 * sel.spec.nobs_records[0] * np.log(c),
                               rtol=1e-12)
    np.testing.assert_allclose(sel.table.loc[3, "bic"], sel.fit(3).bic, rtol=1e-9)
    Y = var2(1000, 5)
    assert tsfdi.select_order(c * Y, 6, "var").selected == tsfdi.select_order(Y, 6, "var").selected
    yx, u = arx_data(1000, 6)
    assert (tsfdi.select_order(c * yx, 5, "arx", u=c * u, nk=1).selected
            == tsfdi.select_order(yx, 5, "arx", u=u, nk=1).selected)
    held = AR(c * y, 2).held_out_residuals(blocks=4)
    ref_held = AR(y, 2).held_out_residuals(blocks=4)
    for a, b in zip(held, ref_held):
        np.testing.assert_allclose(a, c * b, rtol=1e-9, atol=1e-12 * c)
    recs = [c * ar2(300, s) for s in range(3)]
    assert all(np.isfinite(r).all() for r in VAR([np.column_stack([r, np.roll(r, 1) + 0.1 * c]) for r in recs],
                                                  1).held_out_residuals())


def test_channels_in_very_different_units():
    # 9 samples, VAR(2): 7 regression rows for 6 + 3 columns of [X | Y]; the channels' units differ by 1e130,
    # so the Gram matrix fails and the QR fallback factors a wide matrix (was a broadcast error)
    x = np.random.default_rng(2).standard_normal((9, 3)) * np.array([1e15, 1e77, 1e146])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sel = tsfdi.select_order(x, 2, "var")
    assert np.isfinite(sel.table.to_numpy()).all()
    Y = var2(300, 22) * np.array([1e-100, 1e100])
    res = VAR(Y, 2).fit()
    ref = VAR(var2(300, 22), 2).fit()
    np.testing.assert_allclose(res.coefs[:, 0, 0], ref.coefs[:, 0, 0], rtol=1e-10)
    np.testing.assert_allclose(res.coefs[:, 0, 1], ref.coefs[:, 0, 1] * 1e-200, rtol=1e-10)
    np.testing.assert_allclose(res.sigma[1, 1], ref.sigma[1, 1] * 1e200, rtol=1e-10)


def test_data_outside_the_range_is_refused_naming_it():
    y = ar2(200, 7)
    for c in (1e-160, 1e160, 1e300):
        with pytest.raises(ValueError, match=r"y peaks at .* within \[1e-152, 1e\+152\]"):
            AR(c * y, 2)
        with pytest.raises(ValueError, match="y peaks at"):
            tsfdi.select_order(c * y, 4)
    yx, u = arx_data(200, 8)
    with pytest.raises(ValueError, match="u peaks at"):
        ARX(yx, 1e200 * u, 1, 1)
    with pytest.raises(ValueError, match=r"y peaks at .* channel 'y1'"):
        VAR(np.column_stack([y, 1e-200 * np.roll(y, 1)]), 1)


def test_residuals_that_overflow_raise():
    res = AR(ar2(200, 9), 2).fit()
    with pytest.raises(ValueError, match="y: the residuals"):
        res.residuals(np.r_[ar2(50, 10), 1.7e308, -1.7e308])


def test_solver_failure_is_a_value_error(monkeypatch):
    def no_convergence(*args, **kwargs):
        raise linalg.LinAlgError("SVD did not converge")

    monkeypatch.setattr(lstsq_module.linalg, "lstsq", no_convergence)
    # a sinusoid obeys a 2nd-order recursion: three lag columns are collinear, so the fit leaves the normal
    # equations for the SVD solver, whose failure must surface as a ValueError
    with pytest.raises(ValueError, match="y: the least-squares solver did not converge"):
        AR(np.sin(0.3 * np.arange(100.0)), 3).fit()


# --- cause 3: exact and degenerate fits -------------------------------------------------------------------
@pytest.mark.filterwarnings("ignore::tsfdi.exceptions.UnstableModelWarning")   # a ramp has a unit root
def test_exact_fit_warns_and_gives_finite_criteria():
    ramp = np.arange(60.0)                 # y[t] = 2 y[t-1] - y[t-2] exactly: zero residuals
    with pytest.warns(IllConditionedWarning, match="fits y exactly"):
        res = AR(ramp, 2).fit()
        llf = res.llf
    assert res.sigma2 < 1e-26 and np.isfinite(llf) and np.isfinite(res.bic) and res.rss_sss < 1e-26
    np.testing.assert_allclose(res.ar_coefs, [-2.0, 1.0], rtol=1e-12)
    # the floor is (1e-12 * peak)^2: llf = -n/2 (ln 2 pi + ln floor + 1)
    floor = (1e-12 * 59.0) ** 2
    np.testing.assert_allclose(llf, -res.nobs / 2 * (np.log(2 * np.pi) + np.log(floor) + 1), rtol=1e-12)
    # scale-equivariant like any fit
    with pytest.warns(IllConditionedWarning):
        np.testing.assert_allclose(AR(1e100 * ramp, 2).fit().llf, llf - res.nobs * np.log(1e100), rtol=1e-12)


@pytest.mark.filterwarnings("ignore::tsfdi.exceptions.UnstableModelWarning")   # a sinusoid is marginally stable
def test_select_order_picks_the_smallest_exact_order():
    t = np.arange(500)
    y = np.sin(0.3 * t)                   # an exact AR(2) recursion: lags 3+ are collinear too
    with pytest.warns(IllConditionedWarning) as record:
        sel = tsfdi.select_order(y, 6)
    assert any("orders [2, 3, 4, 5, 6] fit the data exactly" in str(w.message) for w in record)
    assert sel.selected == 2
    assert np.isfinite(sel.table.to_numpy()).all()
    assert sel.stabilized == 2


def test_var_with_collinear_channels_has_a_finite_likelihood():
    y = ar2(300, 12)
    Y = np.column_stack([y, 3.0 * y])      # singular residual covariance
    with pytest.warns(IllConditionedWarning):
        res = VAR(Y, 2).fit()
        assert np.isfinite([res.llf, res.aic, res.bic]).all()


# --- cause 3 and 4: RecursiveARX --------------------------------------------------------------------------
@pytest.mark.parametrize("c", [1e-200, 1e-150, 1e7, 7e15, 1e20, 1e150])
def test_recursive_arx_survives_scale(c):
    y, u = arx_data(3000, 13)
    base = RecursiveARX(2, 2, 1, 0.99).run(y, u)
    m = RecursiveARX(2, 2, 1, 0.99)
    res = m.run(c * y, c * u)
    params = np.asarray(res.params)
    assert np.isfinite(params).all() and np.isfinite(m.P_).all()
    assert np.linalg.eigvalsh(m.P_ / np.abs(m.P_).max()).min() >= -1e-12
    # the error statistics are kept in the errors' own unit: no inf Z-score, no alarm on clean data
    assert not np.isinf(np.asarray(res.zscore)).any() and res.alarm.sum() == base.alarm.sum() == 0
    if c >= 1:   # the data carry the estimate: the same parameters (P0 = 1e4 weighs little either way)
        np.testing.assert_allclose(params[-1], np.asarray(base.params)[-1], rtol=1e-4)
        # with P0 scaled by 1 / c^2 the recursion is the same one in other units
        scaled = RecursiveARX(2, 2, 1, 0.99, P0=1e4 / c**2).run(c * y, c * u)
        np.testing.assert_allclose(np.asarray(scaled.params), np.asarray(base.params), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(np.asarray(scaled.zscore), np.asarray(base.zscore), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(np.asarray(scaled.variance), c * c * np.asarray(base.variance), rtol=1e-9)


def test_recursive_arx_refuses_samples_beyond_range():
    m = RecursiveARX(2, 2, 1)
    y, u = arx_data(100, 14)
    with pytest.raises(ValueError, match=r"y has a sample of magnitude 2e\+200 \(first at sample 5"):
        m.run(np.r_[y[:5], 2e200, y[6:]], u)
    with pytest.raises(ValueError, match="u has a sample of magnitude"):
        m.run(y, 1e160 * u)
    with pytest.raises(ValueError, match="y has a sample of magnitude"):
        m.update(1e200, 1.0)
    assert m.nobs == 0      # nothing was processed


def test_recursive_arx_covariance_does_not_wind_up():
    # a frozen sensor and an input at rest for 20,000 samples with lambda = 0.95: P would grow as 0.95^-t
    # (overflow after ~14,000 samples, then NaN); it stays at most P0 and the estimate recovers afterwards
    y, u = arx_data(24000, 15)
    y[2000:22000], u[2000:22000] = y[1999], 0.0
    m = RecursiveARX(2, 2, 1, 0.95, P0=1e4)
    res = m.run(y, u)
    assert np.isfinite(np.asarray(res.params)).all() and np.isfinite(m.P_).all()
    assert np.diag(m.P_).max() <= 1e4
    fresh = RecursiveARX(2, 2, 1, 0.95, P0=1e4)
    fresh.run(y[22000:], u[22000:])
    np.testing.assert_allclose(m.theta_, fresh.theta_, atol=1e-6)


def test_recursive_arx_option_ranges():
    with pytest.raises(ValueError, match="forgetting_factor must be >= 0.5"):
        RecursiveARX(2, 2, forgetting_factor=1e-300)
    with pytest.raises(ValueError, match=r"P0 must be <= 1e\+100"):
        RecursiveARX(2, 2, P0=1e300)
    with pytest.raises(ValueError, match=r"P0 must have a diagonal of at most 1e\+100"):
        RecursiveARX(1, 1, P0=np.diag([1.0, 1e200]))
    with pytest.raises(TypeError, match="P0"):
        RecursiveARX(1, 1, P0=[["a", "b"], ["c", "d"]])
    # the extremes of the ranges run without NaN
    y, u = arx_data(2000, 16)
    for lam, p0 in ((0.5, 1e100), (0.5, 1e-300), (1.0, 1e100)):
        m = RecursiveARX(2, 2, 1, lam, P0=p0)
        res = m.run(y, u)
        assert np.isfinite(np.asarray(res.params)).all() and np.isfinite(m.P_).all()


# --- cause 5: memory bounds -------------------------------------------------------------------------------
def test_orders_are_checked_against_a_memory_limit():
    with pytest.raises(ValueError, match=r"na=1000000, nb=0, n_inputs=1: the covariance P .*\(2 GiB\)"):
        RecursiveARX(10**6, 0)
    with pytest.raises(ValueError, match=r"nk=1000000000000, nb=1, n_inputs=1: the input history"):
        RecursiveARX(1, 1, nk=10**12)
    m = RecursiveARX(1500, 0, P0=1.0)
    with pytest.raises(ValueError, match=r"y with 180,000 samples: the parameter history"):
        m.run(np.zeros(180_000))
    y = np.random.default_rng(17).standard_normal(300_000)
    with pytest.raises(ValueError, match=r"lags=1000 on 299,000 regression rows: the regressor"):
        AR(y, 1000)
    with pytest.raises(ValueError, match=r"lags=1000 on 299,000 regression rows"):
        tsfdi.select_order(y, 1000)
    with pytest.raises(ValueError, match="y is too short for lags=1000000000000"):
        AR(y[:50], 10**12)
    with pytest.raises(ValueError, match="y is too short for na=1"):
        ARX(y[:50], y[1:51], 1, 1, nk=10**12)
    res = AR(y[:1000], 2).fit()
    with pytest.raises(ValueError, match=r"nobs=1000000000000 \(\+ burn=120\): the simulated signal"):
        res.simulate(10**12)


def test_simulation_overflow_raises():
    y = 1.05 ** np.arange(200) + 0.01 * np.random.default_rng(18).standard_normal(200)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = AR(y, 1).fit()
    assert not res.is_stable
    with pytest.raises(ValueError, match="nobs=100000: the simulation leaves the floating-point range"):
        res.simulate(100_000, rng=0)


# --- cause 9: argument types ------------------------------------------------------------------------------
def test_recursive_update_refuses_bools_and_strings():
    m = RecursiveARX(1, 1)
    with pytest.raises(TypeError, match="y must be a real number, got True"):
        m.update(True, 1.0)
    with pytest.raises(TypeError, match="y must be a real number"):
        m.update("1.5", 1.0)
    with pytest.raises(TypeError, match="u must be real number"):
        m.update(1.0, True)
    assert m.nobs == 0
    m.update(np.float32(1.0), 2)
    m.update(3, np.int64(1))
    assert m.nobs == 2


def test_var_simulate_sigma_is_validated_by_name():
    res = VAR(var2(300, 19), 1).fit()
    with pytest.raises(TypeError, match="sigma must be a real"):
        res.simulate(10, sigma="")
    with pytest.raises(ValueError, match=r"sigma must be a \(2, 2\) covariance"):
        res.simulate(10, sigma=np.eye(3))
    with pytest.raises(ValueError, match="sigma must be positive semi-definite"):
        res.simulate(10, sigma=np.array([[1.0, 2.0], [2.0, 1.0]]))
    with pytest.raises(ValueError, match="sigma must be a finite symmetric"):
        res.simulate(10, sigma=np.array([[1.0, np.nan], [np.nan, 1.0]]))
    # a singular covariance is valid: zero noise gives the deterministic response
    assert np.array_equal(res.simulate(10, sigma=np.zeros((2, 2)), burn=0), np.zeros((10, 2)))
    ar = AR(ar2(300, 20), 1).fit()
    with pytest.raises(TypeError, match="sigma2 must be a real number"):
        ar.simulate(10, sigma2="")
    with pytest.raises(ValueError, match="sigma2 must be >= 0"):
        ar.simulate(10, sigma2=-1.0)


def test_an_exact_fit_names_the_proportional_channels():
    """The warning of an exact fit (VAR.fit, select_order) names the channels behind it, as 'tsfdi fit' does."""
    y = ar2(300, 12)
    Y = pd.DataFrame({"a": y, "b": ar2(300, 13), "c": -3.0 * y})
    assert VAR(Y, 2).collinear_channels() == ["'c' is proportional to 'a'"]
    with pytest.warns(IllConditionedWarning, match="or collinear channels; 'c' is proportional to 'a'\\)"):
        VAR(Y, 2).fit().llf
    with pytest.warns(IllConditionedWarning, match="'c' is proportional to 'a'\\)"):
        tsfdi.select_order([Y, Y * 2], 3, "var")
    assert VAR(np.column_stack([y, ar2(300, 13)]), 2).collinear_channels() == []


def _criteria_reference(sse, sss, nobs, df_model, s, criterion, scale, peak):
    """information_criteria as numpy formulas (the implementation before the compiled kernel)."""
    from tsfdi.models.criteria import COLLINEAR_RTOL, EXACT_FIT_RTOL

    own = scale is None
    peak = (np.ones(s) if own else scale) if peak is None else peak
    floor = (EXACT_FIT_RTOL * peak) ** 2 if own else (EXACT_FIT_RTOL * (peak / scale)) ** 2
    sigma = sse / nobs
    var = sigma.diagonal(axis1=-2, axis2=-1)
    if s == 1:
        exact = var[:, 0] < floor[0]
        logdet = np.log(np.maximum(var[:, 0], floor[0]))
    else:
        tr = var.sum(axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            sign, logdet = np.linalg.slogdet(sigma)
            exact = ~((sign > 0) & (logdet - (s - 1) * np.log(tr) > np.log(floor.max()))
                      & (logdet - s * np.log(tr) > np.log(COLLINEAR_RTOL)))
        if exact.any():
            root = np.sqrt(floor)
            lam = np.linalg.eigvalsh(sigma[exact] / root[:, None] / root[None, :])
            low = np.maximum(1.0, COLLINEAR_RTOL * lam.max(axis=-1, keepdims=True))
            logdet[exact] = np.log(np.maximum(lam, low)).sum(axis=-1) + np.log(floor).sum()
            exact[exact] = (lam < low).any(axis=-1)
    top = 1.0 if own else scale.max()
    w = np.ones(s) if own else (scale / top) ** 2
    if not own:
        logdet = logdet + 2 * np.log(scale).sum()
    resid_ss = np.sum(var * w, axis=-1)
    trace = np.sum(np.maximum(var, floor) * w, axis=-1) if exact.any() else resid_ss
    m2llf = nobs * (logdet + s * np.log(2 * np.pi) + s)
    k = df_model + s * (s + 1) / 2
    fit = m2llf if criterion == "logdet" else nobs * (np.log(2 * np.pi * trace) + 2 * np.log(top) + 1)
    sss_w = np.sum(sss * w)
    return {"llf": -m2llf / 2, "aic": m2llf + 2 * k, "bic": fit + k * np.log(nobs),
            "hqic": m2llf + 2 * k * np.log(np.log(nobs)), "rss_sss": 100 * nobs * resid_ss / sss_w,
            "spp": nobs * s / df_model, "sigma2": resid_ss * top ** 2 / s, "exact": exact}


@pytest.mark.parametrize("s", [1, 2, 3])
@pytest.mark.parametrize("criterion", ["logdet", "trace"])
@pytest.mark.parametrize("units", ["own", "scaled"])
def test_information_criteria_equal_the_numpy_formulas(s, criterion, units):
    """The compiled criteria (a vector model's ln det by Cholesky) against the numpy formulas (slogdet), with
    ordinary, exact (below the floor) and collinear fits among the rows."""
    from tsfdi.models.criteria import information_criteria

    rng = np.random.default_rng(s)
    nobs, q = 500, 9
    E = rng.standard_normal((q, nobs, s)) * np.linspace(2.0, 0.1, q)[:, None, None]
    E[3] *= 1e-14                                           # an exact fit (residual RMS below the floor)
    if s > 1:
        E[5, :, 1] = 2.0 * E[5, :, 0] + 1e-8 * E[5, :, 1]    # collinear (above the floor, below COLLINEAR_RTOL)
    sse = np.einsum("qta,qtb->qab", E, E)
    sss = np.full(s, 40.0 * nobs)
    df_model = (1 + np.arange(1, q + 1) * s) * s
    scale, peak = (None, None) if units == "own" else (2.0 ** np.arange(-2, s - 2), 3.0 * np.arange(1, s + 1))
    got = information_criteria(sse, sss, nobs, df_model, s, criterion, scale=scale, peak=peak)
    ref = _criteria_reference(sse, sss, nobs, df_model, s, criterion, scale, peak)
    np.testing.assert_array_equal(got["exact"], ref["exact"])
    assert got["exact"][3] and (s == 1 or got["exact"][5])
    for key in ("llf", "aic", "bic", "hqic", "rss_sss", "spp", "sigma2"):
        np.testing.assert_allclose(got[key], ref[key], rtol=1e-12, err_msg=key)

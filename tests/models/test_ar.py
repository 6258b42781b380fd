"""Scalar AR: agreement with statsmodels AutoReg, data kinds, simulation, persistence."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm
from scipy import signal as sps
from statsmodels.tsa.ar_model import AutoReg

import tsfdi
from tsfdi.models import load
from tests.conftest import as_kind, assert_kind, to_numpy

TRUE_A6 = np.poly(np.r_[0.9 * np.exp(1j * np.array([0.3, -0.3, 1.2, -1.2])), 0.7, -0.5]).real[1:]


def simulate_ar(a, n, rng, c=0.0):
    e = rng.standard_normal(n + 500) + c
    return sps.lfilter([1.0], np.r_[1.0, a], e)[500:]


def signals():
    rng = np.random.default_rng(11)
    sun = sm.datasets.sunspots.load_pandas().data["SUNACTIVITY"].to_numpy()
    return {
        "ar2": simulate_ar([-1.3, 0.6], 1500, rng),
        "ar6": simulate_ar(TRUE_A6, 3000, rng, c=0.4),
        "sunspots": sun,     # a real signal shipped with statsmodels
    }


@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("name", ["ar2", "ar6", "sunspots"])
@pytest.mark.parametrize("lags", [1, 3, 9])
def test_ar_matches_autoreg(name, trend, lags):
    y = signals()[name]
    res = tsfdi.AR(y, lags, trend).fit()
    ref = AutoReg(y, lags, trend=trend).fit()
    sign = np.r_[np.ones(int(trend == "c")), -np.ones(lags)]     # phi_i = -a_i, the intercept is shared
    np.testing.assert_allclose(res.params, sign * ref.params, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(res.ar_coefs, -ref.params[-lags:], rtol=1e-8)
    np.testing.assert_allclose(res.sigma2, ref.sigma2, rtol=1e-8)
    np.testing.assert_allclose(res.resid, ref.resid, rtol=1e-8, atol=1e-10 * np.std(y))
    np.testing.assert_allclose(res.residuals(y), ref.resid, rtol=1e-8, atol=1e-10 * np.std(y))
    for ic in ("bic", "aic", "llf"):
        np.testing.assert_allclose(getattr(res, ic), getattr(ref, ic), rtol=1e-8)
    assert res.nobs == ref.nobs and res.df_model == ref.df_model
    np.testing.assert_allclose(np.sort_complex(res.roots), np.sort_complex(ref.roots), rtol=1e-8)


def test_residuals_of_new_signal_match_autoreg_apply():
    rng = np.random.default_rng(3)
    y, y_new = simulate_ar([-1.3, 0.6], 800, rng), simulate_ar([-1.3, 0.6], 500, rng)
    res = tsfdi.AR(y, 4, "c").fit()
    ref = AutoReg(y, 4, trend="c").fit().apply(y_new)
    np.testing.assert_allclose(res.residuals(y_new), ref.resid, rtol=1e-9, atol=1e-12)


def test_fit_criteria_closed_forms():
    y = signals()["ar2"]
    res = tsfdi.AR(y, 2).fit()
    e = to_numpy(res.resid)
    n = e.size
    assert res.nobs == y.size - 2
    np.testing.assert_allclose(res.sigma2, e @ e / n)
    np.testing.assert_allclose(res.rss_sss, 100 * (e @ e) / (y[2:] @ y[2:]))          # paper 003 eq. 6
    np.testing.assert_allclose(res.spp, n / 2)
    # BIC / N is paper 003 eq. 5 up to the order-independent constant ln(2 pi) + 1 (noise variance counted)
    eq5 = np.log(e @ e / n) + (res.df_model + 1) * np.log(n) / n
    np.testing.assert_allclose(res.bic / n, eq5 + np.log(2 * np.pi) + 1, rtol=1e-12)
    assert res.is_stable and res.df_resid == n - 2


def test_kinds_round_trip(kind):
    y = signals()["ar2"]
    obj = as_kind(y, kind)
    res = tsfdi.AR(obj, 3).fit()
    ref = tsfdi.AR(y, 3).fit()
    np.testing.assert_array_equal(res.params, ref.params)
    for out in (res.resid, res.residuals(obj)):
        assert_kind(out, kind, 1)
        np.testing.assert_allclose(to_numpy(out), to_numpy(ref.resid), atol=1e-12)
    if kind == "pandas":
        assert res.resid.index.equals(obj.index[3:])
        assert res.resid.name == "y"
    if kind == "xarray":
        np.testing.assert_array_equal(res.resid["time"].values, obj["time"].values[3:])


def test_one_column_dataframe_is_a_scalar_signal():
    y = signals()["ar2"]
    df = pd.DataFrame({"pitch": y})
    res = tsfdi.AR(df, 2).fit()
    assert isinstance(res.resid, pd.Series)
    np.testing.assert_allclose(res.params, tsfdi.AR(y, 2).fit().params)


def test_simulate_is_reproducible_and_recovers_the_model():
    y = simulate_ar([-1.3, 0.6], 4000, np.random.default_rng(5))
    res = tsfdi.AR(y, 2, "c").fit()
    a = res.simulate(20000, rng=42)
    np.testing.assert_array_equal(a, res.simulate(20000, rng=np.random.default_rng(42)))
    refit = tsfdi.AR(a, 2, "c").fit()
    np.testing.assert_allclose(refit.ar_coefs, res.ar_coefs, atol=0.02)
    np.testing.assert_allclose(refit.sigma2, res.sigma2, rtol=0.03)
    # the stationary mean of y + sum a_i y[t-i] = c + e is c / (1 + sum a_i)
    np.testing.assert_allclose(a.mean(), res.intercept / (1 + res.ar_coefs.sum()), atol=0.05)


def test_results_are_immutable():
    res = tsfdi.AR(signals()["ar2"], 2).fit()
    with pytest.raises(AttributeError):
        res.sigma2 = 1.0
    with pytest.raises(ValueError):
        res.params[0] = 1.0


def test_summary_and_repr():
    res = tsfdi.AR(signals()["ar2"], 2).fit()
    text = str(res.summary())
    assert "BIC" in text and "RSS/SSS" in text and "a2" in text and f"{res.bic:.6g}" in text
    assert "ARResults" in repr(res)


@pytest.mark.parametrize("trend", ["n", "c"])
def test_save_load_exact(tmp_path, kind, trend):
    obj = as_kind(signals()["ar6"], kind)
    res = tsfdi.AR(obj, 6, trend).fit()
    res.save(tmp_path / "m.npz")
    back = load(tmp_path / "m.npz")
    assert isinstance(back, tsfdi.ARResults)
    np.testing.assert_array_equal(back.params, res.params)
    assert back.sigma2 == res.sigma2 and back.bic == res.bic and back.trend == trend
    if kind == "numpy":
        np.testing.assert_array_equal(back.resid, res.resid)
    elif kind == "pandas":
        pd.testing.assert_series_equal(back.resid, res.resid)
        assert back.resid.index.freq == res.resid.index.freq
    else:
        assert back.resid.identical(res.resid)


def test_unstable_fit_warns():
    y = np.cumsum(np.cumsum(np.random.default_rng(0).standard_normal(400)))
    with pytest.warns(tsfdi.exceptions.UnstableModelWarning):
        tsfdi.AR(y, 1).fit()

"""VAR against statsmodels VAR and ARX against an explicit least-squares solve."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm
from statsmodels.tsa.api import VAR as smVAR

import tsfdi
from tsfdi.models import load
from tsfdi.models.var import simulate_var
from tests.conftest import as_kind, assert_kind, to_numpy


def var_system(seed=0, n=3000):
    rng = np.random.default_rng(seed)
    A1 = np.array([[-0.5, 0.1, 0.0], [0.2, -0.4, 0.1], [0.0, 0.3, -0.6]])
    A2 = np.array([[0.2, 0.0, 0.05], [0.0, 0.15, 0.0], [0.1, 0.0, 0.1]])
    coefs = np.stack([A1, A2])
    cov = np.array([[1.0, 0.3, 0.1], [0.3, 0.8, 0.0], [0.1, 0.0, 0.5]])
    e = rng.multivariate_normal(np.zeros(3), cov, size=n + 300)
    return simulate_var(coefs, e)[300:], coefs, cov


def macro():
    data = sm.datasets.macrodata.load_pandas().data
    return np.log(data[["realgdp", "realcons", "realinv"]]).diff().dropna().to_numpy()


@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("which", ["sim", "macro"])
@pytest.mark.parametrize("lags", [1, 2, 4])
def test_var_matches_statsmodels(which, trend, lags):
    y = var_system()[0] if which == "sim" else macro()
    res = tsfdi.VAR(y, lags, trend).fit()
    ref = smVAR(y).fit(lags, trend=trend)
    np.testing.assert_allclose(res.coefs, -ref.coefs, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(res.sigma, ref.sigma_u_mle, rtol=1e-8)
    np.testing.assert_allclose(to_numpy(res.resid), ref.resid, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(to_numpy(res.residuals(y)), ref.resid, rtol=1e-8, atol=1e-12)
    if trend == "c":
        np.testing.assert_allclose(res.intercept, ref.params[0], rtol=1e-8, atol=1e-12)
    # statsmodels' VAR bic is per observation, without the covariance parameters and the constant
    s, n = 3, res.nobs
    sm_equiv = (res.bic - n * s * (1 + np.log(2 * np.pi)) - np.log(n) * s * (s + 1) / 2) / n
    np.testing.assert_allclose(sm_equiv, ref.bic, rtol=1e-8)
    np.testing.assert_allclose(np.sort_complex(res.roots), np.sort_complex(ref.roots), rtol=1e-8)
    assert res.is_stable == ref.is_stable()


def test_var_trace_criterion_and_closed_forms():
    y = var_system()[0]
    res = tsfdi.VAR(y, 2, criterion="trace").fit()
    e = to_numpy(res.resid)
    n, s = e.shape
    k = res.df_model + s * (s + 1) / 2
    # paper 003: the trace of the residual covariance replaces sigma^2 in eq. 5
    np.testing.assert_allclose(res.bic, n * (np.log(2 * np.pi * np.trace(e.T @ e / n)) + 1) + k * np.log(n))
    assert res.df_model == 2 * 9 and res.df_eq == 6 and res.df_resid == n - 6
    np.testing.assert_allclose(res.spp, n * 3 / 18)
    np.testing.assert_allclose(res.rss_sss, 100 * np.sum(e * e) / np.sum(y[2:] ** 2))
    logdet = tsfdi.VAR(y, 2).fit()
    assert logdet.bic != res.bic and logdet.llf == res.llf


def test_var_kinds(kind):
    y = var_system()[0][:600]
    obj = as_kind(y, kind, channels=["roll", "pitch", "yaw"])
    res = tsfdi.VAR(obj, 3).fit()
    np.testing.assert_allclose(res.coefs, tsfdi.VAR(y, 3).fit().coefs)
    for out in (res.resid, res.residuals(obj)):
        assert_kind(out, kind, 2)
        assert to_numpy(out).shape == (597, 3)
    if kind == "pandas":
        assert list(res.resid.columns) == ["roll", "pitch", "yaw"]
        assert res.resid.index.equals(obj.index[3:])
    if kind == "xarray":
        assert list(res.resid["channel"].values) == ["roll", "pitch", "yaw"]
        np.testing.assert_array_equal(res.resid["time"].values, obj["time"].values[3:])


def test_xarray_channel_first_is_transposed():
    y = var_system()[0][:400]
    da = as_kind(y, "xarray").transpose("channel", "time")
    np.testing.assert_allclose(tsfdi.VAR(da, 2).fit().coefs, tsfdi.VAR(y, 2).fit().coefs)


def test_var_simulate_recovers_coefs():
    y, coefs, cov = var_system(1, 20000)
    res = tsfdi.VAR(y, 2).fit()
    np.testing.assert_allclose(res.coefs, coefs, atol=0.03)
    np.testing.assert_allclose(res.sigma, cov, atol=0.05)
    sim = res.simulate(20000, rng=7)
    np.testing.assert_array_equal(sim, res.simulate(20000, rng=7))
    np.testing.assert_allclose(tsfdi.VAR(sim, 2).fit().coefs, res.coefs, atol=0.03)


@pytest.mark.parametrize("trend", ["n", "c"])
def test_var_save_load(tmp_path, kind, trend):
    obj = as_kind(var_system()[0][:500], kind)
    res = tsfdi.VAR(obj, 2, trend, criterion="trace").fit()
    res.save(tmp_path / "v.npz")
    back = load(tmp_path / "v.npz")
    np.testing.assert_array_equal(back.params, res.params)
    np.testing.assert_array_equal(back.sigma, res.sigma)
    assert back.bic == res.bic and back.model.criterion == "trace"
    if kind == "pandas":
        pd.testing.assert_frame_equal(back.resid, res.resid)
    elif kind == "xarray":
        assert back.resid.identical(res.resid)


# ---------------------------------------------------------------------------------------------------- ARX
def arx_data(seed=0, n=2000, inputs=2):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, inputs))
    y = np.zeros(n)
    e = 0.1 * rng.standard_normal(n)
    for t in range(3, n):
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.8 * u[t - 1, 0] + 0.3 * u[t - 2, 0] + e[t] + 0.2
        if inputs > 1:
            y[t] += -0.4 * u[t - 1, 1]
    return y, u


@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("na,nb,nk", [(2, 2, 1), (3, 1, 0), (0, 3, 2), (2, 0, 0)])
def test_arx_matches_explicit_lstsq(na, nb, nk, trend):
    y, u = arx_data()
    res = tsfdi.ARX(y, u, na, nb, nk, trend).fit()
    start = max(na, nk + nb - 1)
    cols = [np.ones(y.size - start)] if trend == "c" else []
    for i in range(1, na + 1):
        cols.append(-y[start - i:y.size - i])
    for m in range(2):
        for j in range(nb):
            d = nk + j
            cols.append(u[start - d:y.size - d, m])
    X = np.column_stack(cols)
    beta = np.linalg.lstsq(X, y[start:], rcond=None)[0]
    k = int(trend == "c")
    np.testing.assert_allclose(res.a, beta[k:k + na], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res.b, beta[k + na:].reshape(2, nb), rtol=1e-9, atol=1e-12)
    e = y[start:] - X @ beta
    np.testing.assert_allclose(res.resid, e, atol=1e-10)
    np.testing.assert_allclose(res.residuals(y, u), e, atol=1e-10)
    np.testing.assert_allclose(res.sigma2, e @ e / e.size)


def test_arx_recovers_true_system():
    y, u = arx_data(n=20000)
    res = tsfdi.ARX(y, u, 2, 2, 1, "c").fit()
    np.testing.assert_allclose(res.a, [-1.2, 0.5], atol=0.01)
    np.testing.assert_allclose(res.b, [[0.8, 0.3], [-0.4, 0.0]], atol=0.01)
    np.testing.assert_allclose(res.intercept, 0.2, atol=0.01)


def test_arx_kinds_and_save(tmp_path, kind):
    y, u = arx_data(n=600)
    yo, uo = as_kind(y, kind), as_kind(u, kind, name="u")
    res = tsfdi.ARX(yo, uo, 2, 2, 1).fit()
    assert_kind(res.resid, kind, 1)
    assert_kind(res.residuals(yo, uo), kind, 1)
    np.testing.assert_allclose(res.params, tsfdi.ARX(y, u, 2, 2, 1).fit().params)
    res.save(tmp_path / "a.npz")
    back = load(tmp_path / "a.npz")
    np.testing.assert_array_equal(back.params, res.params)
    np.testing.assert_array_equal(to_numpy(back.resid), to_numpy(res.resid))
    assert "ARX" in repr(res.model) and "b1" in str(res.summary())


def test_arx_simulate(kind):
    y, u = arx_data(n=20000)
    res = tsfdi.ARX(y, u, 2, 2, 1, "c").fit()
    uo = as_kind(u, kind, name="u")
    clean = res.simulate(uo, sigma2=0.0)
    assert_kind(clean, kind, 1)
    # the noise-free response satisfies the model exactly: its one-step prediction errors are zero
    np.testing.assert_allclose(to_numpy(res.residuals(to_numpy(clean), u)), 0.0, atol=1e-10)
    sim = res.simulate(u, rng=5)
    np.testing.assert_array_equal(sim, res.simulate(u, rng=5))
    refit = tsfdi.ARX(sim, u, 2, 2, 1, "c").fit()
    np.testing.assert_allclose(refit.a, res.a, atol=0.01)
    np.testing.assert_allclose(refit.b, res.b, atol=0.01)
    np.testing.assert_allclose(refit.sigma2, res.sigma2, rtol=0.05)
    with pytest.raises(ValueError, match=r"u has 1 input\(s\) but the model was fitted with 2"):
        res.simulate(u[:, 0])
    with pytest.raises(ValueError, match="sigma2 must be >= 0"):
        res.simulate(u, sigma2=-1.0)


@pytest.mark.parametrize("trend", ["n", "c"])
def test_ar_blocks_are_the_lag_rows_of_params(trend):
    """The AR coefficient matrices (read by one reshape of the parameter rows when the model has no input) are the
    lag blocks of params2d, transposed, in lag order, for AR, VAR and ARX (row lists)."""
    rng = np.random.default_rng(3)
    y, u = rng.standard_normal((400, 3)), rng.standard_normal(400)
    c = int(trend == "c")
    for res in (tsfdi.VAR(y, 4, trend=trend).fit(), tsfdi.AR(y[:, 0], 3, trend=trend).fit()):
        s = res.neqs
        ref = np.stack([res.params2d[c + i * s:c + (i + 1) * s].T for i in range(res.lags)])
        A = res._ar_matrices()
        assert A.shape == (res.lags, s, s) and np.array_equal(A, ref) and A.flags.writeable
    arx = tsfdi.ARX(y[:, 0], u, na=2, nb=2, trend=trend).fit()
    np.testing.assert_array_equal(arx._ar_matrices()[:, 0, 0], arx.params2d[[c, c + 2], 0])

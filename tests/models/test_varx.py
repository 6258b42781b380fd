"""VARX (several outputs given several inputs, issue 32) against statsmodels' VAR with lagged exogenous columns,
against ARX at one output, and the family's contract (names, records, archive, forecasts, simulation, bad input)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from statsmodels.tsa.api import VAR as smVAR

import tsfdi
from tsfdi.models import VARX, load
from tests.conftest import as_kind, assert_kind, to_numpy

A1 = np.array([[-0.5, 0.1], [0.2, -0.4]])
A2 = np.array([[0.15, 0.0], [0.05, 0.1]])
B1 = np.array([[0.8, 0.0, 0.3], [0.1, 0.5, 0.0]])
B2 = np.array([[0.2, -0.1, 0.0], [0.0, 0.3, 0.4]])
COV = np.array([[0.04, 0.01], [0.01, 0.09]])


def varx_system(n=2000, seed=0, nk=1, c=(0.3, -0.2)):
    """``y[t] + A1 y[t-1] + A2 y[t-2] = c + B1 u[t-nk] + B2 u[t-nk-1] + e[t]`` with two outputs, three inputs."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 3))
    e = rng.multivariate_normal(np.zeros(2), COV, size=n)
    y = np.zeros((n, 2))
    for t in range(n):
        y[t] = np.asarray(c) + e[t]
        for i, A in enumerate((A1, A2), start=1):
            if t - i >= 0:
                y[t] -= A @ y[t - i]
        for j, B in enumerate((B1, B2)):
            if t - nk - j >= 0:
                y[t] += B @ u[t - nk - j]
    return y, u


def lagged_inputs(u, nb, nk):
    """statsmodels' exogenous columns ``[u[t-nk], u[t-nk-1], ...]`` (zeros before the first sample)."""
    n, m = u.shape
    out = np.zeros((n, nb * m))
    for j in range(nb):
        d = nk + j
        out[d:, j * m:(j + 1) * m] = u[:n - d]
    return out


@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("lags, nb, nk", [(2, 2, 1), (2, 3, 0), (1, 2, 2), (3, 1, 0)])
def test_varx_matches_statsmodels_var_with_lagged_inputs(trend, lags, nb, nk):
    """``statsmodels.tsa.api.VAR(y, exog=<u lagged nk .. nk + nb - 1>)`` is the same regression: the same
    coefficients, covariance, standard errors, residuals and log-likelihood to 1e-8 (the samples before the largest
    lag dropped from both)."""
    y, u = varx_system(1500, seed=lags + 10 * nb + 100 * nk)
    res = VARX(y, u, lags, nb=nb, nk=nk, trend=trend).fit()
    p = res.model.max_lag
    off = p - lags                       # statsmodels holds back `lags` samples: start its endog that much later
    ref = smVAR(y[off:], exog=lagged_inputs(u, nb, nk)[off:]).fit(lags, trend=trend)
    s, m, k = 2, 3, int(trend == "c")
    assert res.nobs == ref.nobs == len(y) - p
    # our rows [const, (A_g | B_g) for g = 1..], statsmodels' [const, B_1..B_nb, L1..Llags] (lags in its sign)
    rows, sign = list(range(k)), [1.0] * k
    for g in range(1, max(lags, nb) + 1):
        if g <= lags:
            rows += list(range(k + nb * m + (g - 1) * s, k + nb * m + g * s))
            sign += [-1.0] * s
        if g <= nb:
            rows += list(range(k + (g - 1) * m, k + g * m))
            sign += [1.0] * m
    sign = np.array(sign)[:, None]
    np.testing.assert_allclose(res.params, sign * ref.params[rows], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(res.bse, ref.stderr[rows], rtol=1e-8)
    np.testing.assert_allclose(res.tvalues, sign * ref.tvalues[rows], rtol=1e-8)
    np.testing.assert_allclose(res.pvalues, ref.pvalues[rows], rtol=1e-6, atol=1e-300)
    np.testing.assert_allclose(res.sigma, ref.sigma_u_mle, rtol=1e-8)
    np.testing.assert_allclose(res.llf, ref.llf, rtol=1e-10)
    np.testing.assert_allclose(res.coefs, -ref.coefs, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(to_numpy(res.resid), ref.resid, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(res.residuals(y, u), ref.resid, rtol=1e-8, atol=1e-12)
    assert res.b.shape == (nb, s, m) and res.coefs.shape == (lags, s, s)
    np.testing.assert_allclose(np.sort_complex(res.roots), np.sort_complex(ref.roots), rtol=1e-8)


def test_recovers_the_system():
    """A long record: the estimates lie within four standard errors of the true matrices and sigma is near COV."""
    y, u = varx_system(20000, seed=3)
    res = VARX(y, u, 2, nb=2, nk=1, trend="c").fit()
    true = np.vstack([[0.3, -0.2], A1.T, B1.T, A2.T, B2.T])
    assert np.all(np.abs(res.params - true) < 4 * res.bse)
    np.testing.assert_allclose(res.sigma, COV, rtol=0.05, atol=2e-3)


@pytest.mark.parametrize("trend", ["n", "c"])
def test_one_output_is_arx(trend):
    """``s = 1``: VARX(lags) is ARX(na = lags): the same coefficients, residuals, variance and criteria."""
    y, u = varx_system(1200, seed=5)
    v = VARX(y[:, :1], u, 2, nb=3, nk=1, trend=trend).fit()
    a = tsfdi.ARX(y[:, 0], u, 2, 3, nk=1, trend=trend).fit()
    np.testing.assert_allclose(v.params[:, 0], a.params, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(v.residuals(y[:, :1], u)[:, 0], a.residuals(y[:, 0], u), rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(v.sigma[0, 0], a.sigma2, rtol=1e-10)
    for crit in ("llf", "aic", "bic", "hqic"):
        np.testing.assert_allclose(getattr(v, crit), getattr(a, crit), rtol=1e-10)
    # the standard errors differ by each family's statsmodels convention only: RSS / (nobs - df_eq) vs RSS / nobs
    np.testing.assert_allclose(v.bse[:, 0], a.bse * np.sqrt(a.nobs / (a.nobs - a.df_eq)), rtol=1e-8)


def test_names_kept_and_checked():
    y, u = varx_system(1000, seed=7)
    t = pd.Index(np.arange(1000) / 100.0, name="time")
    Y = pd.DataFrame(y, columns=["p", "q"], index=t)
    U = pd.DataFrame(u, columns=["c1", "c2", "c3"], index=t)
    res = VARX(Y, U, 1, nb=2, nk=1, trend="c").fit()
    assert list(res.params.index) == ["const", "A1.p", "A1.q", "b1.c1", "b1.c2", "b1.c3", "b2.c1", "b2.c2", "b2.c3"]
    assert list(res.params.columns) == ["p", "q"]
    e = res.residuals(Y, U)
    assert isinstance(e, pd.DataFrame) and list(e.columns) == ["p", "q"] and e.index[0] == t[2]
    # outputs and inputs given in another column order are matched by name
    pd.testing.assert_frame_equal(res.residuals(Y[["q", "p"]], U[["c3", "c1", "c2"]]), e)
    np.testing.assert_allclose(e.to_numpy(), VARX(y, u, 1, nb=2, nk=1, trend="c").fit().residuals(y, u),
                               rtol=1e-12)
    with pytest.raises(ValueError, match=r"u: missing channel\(s\) \['c2'\]"):
        res.residuals(Y, U.rename(columns={"c2": "cx"}))
    with pytest.raises(ValueError, match="y and u have different indexes"):
        res.residuals(Y, U.set_axis(t + 0.005))
    with pytest.raises(ValueError, match="u has 999 samples but y has 1000"):
        res.residuals(Y, U.iloc[1:])
    text = str(res.summary())
    assert "VARX" in text and "c1, c2, c3" in text and "Equation q" in text and "sum_j B_j u[t-nk-j+1]" in text


@pytest.mark.parametrize("kind", ["numpy", "pandas", "xarray"])
def test_kinds_in_kinds_out(kind):
    """numpy / pandas / xarray in, the same kind out (residuals, forecasts, simulations), the same numbers."""
    y, u = varx_system(600, seed=17)
    Y, U = as_kind(y, kind, ["p", "q"], "y"), as_kind(u, kind, ["c1", "c2", "c3"], "u")
    res = VARX(Y, U, 2, nb=2, nk=1).fit()
    ref = VARX(y, u, 2, nb=2, nk=1).fit()
    np.testing.assert_allclose(to_numpy(res.params), ref.params, rtol=1e-12)
    e = res.residuals(Y, U)
    assert_kind(e, kind, 2)
    np.testing.assert_allclose(to_numpy(e), ref.residuals(y, u), rtol=1e-12)
    for out in (res.forecast(3, U[:3] if kind == "numpy" else U.iloc[:3] if kind == "pandas" else U[:3]),
                res.simulate(U, rng=0)):
        assert_kind(out, kind, 2)


def test_no_output_lags_is_a_regression_on_the_inputs():
    """``lags = 0``: ``y[t] = c + B_1 u[t] + B_2 u[t-1] + e[t]``, the least-squares solve of that regression."""
    y, u = varx_system(500, seed=19)
    res = VARX(y, u, 0, nb=2, trend="c").fit()
    X = np.column_stack([np.ones(499), u[1:], u[:-1]])
    np.testing.assert_allclose(res.params, np.linalg.lstsq(X, y[1:], rcond=None)[0], rtol=1e-9, atol=1e-12)
    assert res.coefs.shape == (0, 2, 2) and res.is_stable
    sim = res.simulate(u[:20], sigma=np.zeros((2, 2)))
    np.testing.assert_allclose(sim[1:], res.intercept + u[1:20] @ res.b[0].T + u[:19] @ res.b[1].T, rtol=1e-12)


def test_records_are_stacked_regressions():
    """A list of records: each holds back its own first samples and the regressions add up (the explicit solve of
    the stacked design)."""
    recs = [varx_system(600, seed=s) for s in (1, 2, 3)]
    res = VARX([r[0] for r in recs], [r[1] for r in recs], 2, nb=2, nk=1, trend="c").fit()
    X, Y = [], []
    for y, u in recs:
        rows = range(2, len(y))
        X.append([np.r_[1.0, -y[t - 1], u[t - 1], -y[t - 2], u[t - 2]] for t in rows])
        Y.append(y[2:])
    want = np.linalg.lstsq(np.vstack(X), np.vstack(Y), rcond=None)[0]
    np.testing.assert_allclose(res.params, want, rtol=1e-9, atol=1e-12)
    assert res.nobs == 3 * 598 and len(res.resid) == 3
    # a record held out is the fit on the others
    spec = VARX([r[0] for r in recs], [r[1] for r in recs], 2, nb=2, nk=1, trend="c")
    held = spec.held_out_residuals()
    other = VARX([r[0] for r in recs[1:]], [r[1] for r in recs[1:]], 2, nb=2, nk=1, trend="c").fit()
    np.testing.assert_allclose(held[0], other.residuals(*recs[0]), rtol=1e-9, atol=1e-12)


def test_save_load_round_trip(tmp_path):
    y, u = varx_system(800, seed=9)
    Y = pd.DataFrame(y, columns=["p", "q"])
    U = pd.DataFrame(u, columns=["c1", "c2", "c3"])
    res = VARX(Y, U, 2, nb=1, nk=0, trend="c", criterion="trace").fit()
    back = load(res.save(tmp_path / "varx"))
    assert type(back) is tsfdi.models.VARXResults and back.model.criterion == "trace"
    np.testing.assert_array_equal(back.params2d, res.params2d)
    pd.testing.assert_frame_equal(back.params, res.params)
    pd.testing.assert_frame_equal(back.residuals(Y, U), res.residuals(Y, U))
    assert back.bic == res.bic and (back.model.nb, back.model.nk) == (1, 0)


def test_forecast_matches_statsmodels_and_simulate_is_the_recursion():
    y, u = varx_system(1000, seed=11)
    res = VARX(y, u, 2, nb=2, nk=0, trend="c").fit()
    future = np.random.default_rng(1).standard_normal((5, 3))
    # statsmodels' exog of the forecast steps: [u[t], u[t-1]], the last fitted input before the first future one
    ref = smVAR(y, exog=lagged_inputs(u, 2, 0)).fit(2, trend="c")
    exog = lagged_inputs(np.vstack([u[-1:], future]), 2, 0)[1:]
    np.testing.assert_allclose(res.forecast(5, future), ref.forecast(y[-2:], 5, exog_future=exog), rtol=1e-9)
    # noise-free simulation: y[t] = c - A1 y[t-1] - A2 y[t-2] + B1 u[t] + B2 u[t-1] from zero initial conditions
    sim = res.simulate(u[:50], sigma=np.zeros((2, 2)))
    want = np.zeros((50, 2))
    A, B = res.coefs, res.b
    for t in range(50):
        want[t] = res.intercept + B[0] @ u[t] + (B[1] @ u[t - 1] if t >= 1 else 0)
        want[t] -= sum(A[i] @ want[t - i - 1] for i in range(2) if t - i - 1 >= 0)
    np.testing.assert_allclose(sim, want, rtol=1e-12, atol=1e-14)
    # noisy: reproducible, in the kind of u with the output names
    U = pd.DataFrame(u[:50], columns=["c1", "c2", "c3"])
    a, b = res.simulate(U, rng=3), res.simulate(U, rng=3)
    pd.testing.assert_frame_equal(a, b)
    assert list(a.columns) == ["y0", "y1"] and not np.allclose(a.to_numpy(), sim)


def test_bad_input_is_named():
    y, u = varx_system(300, seed=13)
    with pytest.raises(ValueError, match="u is required"):
        VARX(y, None, 2)
    with pytest.raises(ValueError, match="u has 299 samples but y has 300"):
        VARX(y, u[1:], 2)
    with pytest.raises(ValueError, match="lags must be"):
        VARX(y, u, -1)
    with pytest.raises(TypeError, match="lags"):
        VARX(y, u, 1.5)
    with pytest.raises(ValueError, match="nb"):
        VARX(y, u, 1, nb=-1)
    with pytest.raises(ValueError, match=r"y must be a 2-D \(nobs, nchan\)"):
        VARX(y[:, 0], u, 1)
    with pytest.raises(ValueError, match="lags \\+ nb must be >= 1"):
        VARX(y, u, 0, nb=0)
    with pytest.raises(ValueError, match=r"u contains 3 NaN/inf value\(s\) \(first at sample 4\)"):
        VARX(y, np.where(np.arange(300)[:, None] == 4, np.nan, u), 1)
    with pytest.raises(ValueError, match="y is too short"):
        VARX(y[:10], u[:10], 2, nb=2)
    with pytest.raises(ValueError, match="u must be a list of as many records as y"):
        VARX([y, y], u, 1)
    res = VARX(y, u, 1, nb=1).fit()
    with pytest.raises(ValueError, match=r"u has 2 input\(s\) but the model was fitted with 3"):
        res.residuals(y, u[:, :2])
    with pytest.raises(ValueError, match=r"sigma must be a \(2, 2\) covariance matrix"):
        res.simulate(u, sigma=np.eye(3))
    with pytest.raises(ValueError, match="steps"):
        res.forecast(0, u[:1])

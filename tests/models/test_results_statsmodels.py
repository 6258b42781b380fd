"""Results as statsmodels users expect them (issue 19): bse, tvalues, pvalues, conf_int, fittedvalues, hqic and
forecast against statsmodels ``AutoReg`` / ``VAR`` / ``OLS`` on the same sample, labelled parameters for named
data; and channel safety: a named signal is matched to a model fitted on named data by name."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm
import xarray as xr
from scipy import signal as sps
from scipy import stats
from statsmodels.tsa.ar_model import AutoReg
from statsmodels.tsa.api import VAR as smVAR

import tsfdi
from tsfdi.models import load
from tsfdi.models.var import simulate_var
from tests.conftest import as_kind, to_numpy

RTOL = 1e-8


def ar_signal(n=800, seed=3, c=0.4):
    """y[t] = 1.2 y[t-1] - 0.5 y[t-2] + c + e[t]."""
    rng = np.random.default_rng(seed)
    e = rng.standard_normal(n + 200)
    y = np.zeros(n + 200)
    for t in range(2, n + 200):
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + c + e[t]
    return y[200:]


def var_signal(n=1200, seed=4):
    rng = np.random.default_rng(seed)
    A1 = np.array([[-0.5, 0.1, 0.0], [0.2, -0.4, 0.1], [0.0, 0.3, -0.6]])
    A2 = np.array([[0.2, 0.0, 0.05], [0.0, 0.15, 0.0], [0.1, 0.0, 0.1]])
    cov = np.array([[1.0, 0.3, 0.1], [0.3, 0.8, 0.0], [0.1, 0.0, 0.5]])
    e = rng.multivariate_normal(np.zeros(3), cov, size=n + 300) + np.array([0.3, -0.2, 0.1])
    return simulate_var(np.stack([A1, A2]), e)[300:]


def arx_signal(n=900, seed=5):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 2))
    y = np.zeros(n)
    e = 0.1 * rng.standard_normal(n)
    for t in range(3, n):
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.8 * u[t - 1, 0] + 0.3 * u[t - 2, 0] - 0.4 * u[t - 1, 1] + e[t] + 0.2
    return y, u


def close(a, b, rtol=RTOL, atol=1e-12):
    np.testing.assert_allclose(to_numpy(a), to_numpy(b), rtol=rtol, atol=atol)


def ar_sign(trend, lags):
    """tsfdi's a_i are statsmodels' -phi_i; the intercept is the same."""
    return np.r_[np.ones(int(trend == "c")), -np.ones(lags)]


# --- AR against statsmodels AutoReg -----------------------------------------------------------------------------
@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("lags", [1, 2, 5])
def test_ar_inference_matches_autoreg(kind, trend, lags):
    y = ar_signal()
    res = tsfdi.AR(as_kind(y, kind), lags, trend).fit()
    ref = AutoReg(y, lags, trend=trend).fit()
    sign = ar_sign(trend, lags)
    close(res.params, sign * ref.params)
    close(res.bse, ref.bse)
    close(res.tvalues, sign * ref.tvalues)
    close(res.pvalues, ref.pvalues)
    ci, ref_ci = to_numpy(res.conf_int(0.1)), ref.conf_int(0.1)
    # a lag coefficient's interval is statsmodels' mirrored: [-upper, -lower]
    close(ci, np.where(sign[:, None] > 0, ref_ci, -ref_ci[:, ::-1]))
    close(res.fittedvalues, ref.fittedvalues)
    close(res.hqic, ref.hqic)
    close(res.aic, ref.aic)
    close(res.bic, ref.bic)
    close(res.forecast(25), ref.forecast(25))


def test_ar_named_input_matches_autoreg_and_keeps_the_index():
    """A pandas Series with a frequency: statsmodels continues the index; so does tsfdi."""
    y = pd.Series(ar_signal(), index=pd.date_range("2024-01-01", periods=800, freq="10ms"), name="roll")
    res = tsfdi.AR(y, 3, "c").fit()
    ref = AutoReg(y, 3, trend="c").fit()
    assert isinstance(res.params, pd.Series) and list(res.params.index) == ["const", "a1", "a2", "a3"]
    assert res.params.name == "roll" and list(res.bse.index) == list(res.params.index)
    close(res.bse, ref.bse.to_numpy())
    ci = res.conf_int()
    assert list(ci.columns) == ["lower", "upper"] and list(ci.index) == list(res.params.index)
    pd.testing.assert_index_equal(res.fittedvalues.index, ref.fittedvalues.index)
    close(res.fittedvalues, ref.fittedvalues)
    f, ref_f = res.forecast(7), ref.forecast(7)
    assert isinstance(f, pd.Series) and f.name == "roll"
    pd.testing.assert_index_equal(f.index, ref_f.index, check_names=False)
    close(f, ref_f)


def test_ar_params_kind_follows_the_data(kind):
    res = tsfdi.AR(as_kind(ar_signal(), kind), 2).fit()
    for values in (res.params, res.bse, res.tvalues, res.pvalues):
        if kind == "numpy":
            assert type(values) is np.ndarray and values.shape == (2,)
        else:
            assert isinstance(values, pd.Series) and list(values.index) == ["a1", "a2"]
    assert type(res.conf_int()) is (np.ndarray if kind == "numpy" else pd.DataFrame)
    assert np.shape(res.conf_int()) == (2, 2)


def test_ar_results_are_in_the_data_units():
    """A signal far outside 2**-20..2**20 is fitted in power-of-two units; every result is in the data's."""
    y = ar_signal() * 3e9
    res = tsfdi.AR(y, 2, "c").fit()
    assert res.model._rescaled
    ref = AutoReg(y, 2, trend="c").fit()
    close(res.bse, ref.bse)
    close(res.pvalues, ref.pvalues)
    close(res.fittedvalues, ref.fittedvalues, atol=0)
    close(res.forecast(5), ref.forecast(5), atol=0)
    close(res.hqic, ref.hqic)


# --- VAR against statsmodels VAR --------------------------------------------------------------------------------
@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("lags", [1, 2, 4])
def test_var_inference_matches_statsmodels(trend, lags):
    y = var_signal()
    res = tsfdi.VAR(y, lags, trend).fit()
    ref = smVAR(y).fit(lags, trend=trend)
    sign = ar_sign(trend, lags * 3)[:, None]
    close(res.params, sign * ref.params)
    close(res.bse, ref.bse)                  # df-adjusted sigma_u = E'E / (nobs - df_eq), per equation
    close(res.tvalues, sign * ref.tvalues)
    close(res.pvalues, ref.pvalues)           # normal, as statsmodels' VAR
    q = stats.norm.isf(0.025)
    ci = res.conf_int()
    assert ci.shape == (res.df_eq, 3, 2)
    close(ci[..., 0], sign * ref.params - q * ref.bse)
    close(ci[..., 1], sign * ref.params + q * ref.bse)
    close(res.fittedvalues, ref.fittedvalues)
    close(res.forecast(12), ref.forecast(y[-lags:], 12))
    # statsmodels' VAR hqic is per sample, without the likelihood constants and the covariance parameters
    n, s = res.nobs, 3
    close((res.hqic - n * s * (1 + np.log(2 * np.pi)) - 2 * np.log(np.log(n)) * s * (s + 1) / 2) / n, ref.hqic)


def test_var_named_input_is_labelled_and_matches_statsmodels():
    df = pd.DataFrame(var_signal(), columns=["roll", "pitch", "yaw"],
                      index=pd.date_range("2024-01-01", periods=1200, freq="4ms"))
    res = tsfdi.VAR(df, 2, "c").fit()
    ref = smVAR(df).fit(2, trend="c")
    names = ["const"] + [f"A{g}.{c}" for g in (1, 2) for c in ("roll", "pitch", "yaw")]
    for values in (res.params, res.bse, res.tvalues, res.pvalues):
        assert isinstance(values, pd.DataFrame)
        assert list(values.index) == names and list(values.columns) == ["roll", "pitch", "yaw"]
    close(res.bse, ref.bse.to_numpy())
    close(res.pvalues, ref.pvalues.to_numpy())
    ci = res.conf_int(0.01)
    assert list(ci.columns) == [(c, b) for c in ("roll", "pitch", "yaw") for b in ("lower", "upper")]
    close(ci[("pitch", "upper")], res.params["pitch"] + stats.norm.isf(0.005) * res.bse["pitch"])
    pd.testing.assert_frame_equal(res.fittedvalues, ref.fittedvalues, check_freq=False, rtol=RTOL)
    f = res.forecast(4)
    assert isinstance(f, pd.DataFrame) and list(f.columns) == ["roll", "pitch", "yaw"]
    pd.testing.assert_index_equal(f.index, pd.date_range(df.index[-1], periods=5, freq="4ms")[1:])
    close(f, ref.forecast(df.to_numpy()[-2:], 4))


def test_var_xarray_is_labelled_and_forecasts_continue_the_time_coordinate():
    y = var_signal(400)
    da = as_kind(y, "xarray", channels=["a", "b", "c"])
    res = tsfdi.VAR(da, 2).fit()
    assert isinstance(res.params, pd.DataFrame) and list(res.params.columns) == ["a", "b", "c"]
    f = res.forecast(3)
    assert isinstance(f, xr.DataArray) and list(f["channel"].values) == ["a", "b", "c"]
    np.testing.assert_allclose(f["time"].values, (400 + np.arange(3)) / 100.0, rtol=1e-12)
    close(f, smVAR(y).fit(2, trend="n").forecast(y[-2:], 3))


def test_forecast_of_an_irregular_index_counts_samples():
    y = pd.Series(ar_signal(50), index=np.r_[np.arange(25), np.arange(25) + 100.5])
    f = tsfdi.AR(y, 2).fit().forecast(3)
    assert list(f.index) == [50, 51, 52]


def test_var_results_are_in_the_data_units():
    """Channels of very different scales (fitted in power-of-two units): each coefficient's standard error
    scales like the coefficient itself, A_g[i, j] and its bse by c_i / c_j, the intercept by c_i."""
    y = var_signal()
    c = np.array([1e9, 1.0, 1e-9])
    base = tsfdi.VAR(y, 2, "c").fit()
    scaled = tsfdi.VAR(y * c, 2, "c").fit()
    assert scaled.model._rescaled
    factor = np.r_[np.ones(1), np.tile(1 / c, 2)][:, None] * c[None, :]
    close(scaled.params, base.params * factor, atol=0)
    close(scaled.bse, base.bse * factor, atol=0)
    close(scaled.tvalues, base.tvalues, atol=1e-9)
    close(scaled.forecast(5), base.forecast(5) * c, atol=0)
    close(scaled.fittedvalues, base.fittedvalues * c, atol=0)


# --- ARX against OLS on the same regressor ----------------------------------------------------------------------
@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("orders", [(2, 2, 1), (1, 3, 0), (0, 2, 1)])
def test_arx_inference_matches_ols_on_the_same_design(trend, orders):
    y, u = arx_signal()
    na, nb, nk = orders
    res = tsfdi.ARX(y, u, na, nb, nk, trend).fit()
    X, Y = res.model.design_all()
    ols = sm.OLS(Y[:, 0], X).fit()
    n, k = X.shape
    adjust = np.sqrt((n - k) / n)      # statsmodels AutoReg: sigma2 = RSS / nobs, normal distribution
    close(res.params, ols.params)
    close(res.bse, ols.bse * adjust)
    close(res.tvalues, ols.tvalues / adjust)
    close(res.pvalues, 2 * stats.norm.sf(np.abs(ols.tvalues / adjust)))
    close(res.conf_int(), ols.params[:, None] + np.outer(ols.bse * adjust, [-1, 1]) * stats.norm.isf(0.025))
    close(res.fittedvalues, ols.fittedvalues)
    close(res.sigma2, ols.ssr / n)


def test_arx_forecast_matches_autoreg_with_lagged_inputs():
    """AutoReg(y, na, exog=[u[t-nk], ..., u[t-nk-nb+1]]) is the same regression; its forecast with the future
    rows of that exog is tsfdi's forecast with the future inputs."""
    y, u_all = arx_signal(960)
    y, u, u_future = y[:900], u_all[:900], u_all[900:]
    na, nb, nk = 2, 2, 1
    res = tsfdi.ARX(y, u, na, nb, nk, "c").fit()

    def lagged(v, start, stop):
        return np.hstack([v[start - nk - j:stop - nk - j] for j in range(nb)])

    p = res.model.max_lag
    exog = np.vstack([np.zeros((p, 2 * nb)), lagged(u_all, p, 900)])
    ref = AutoReg(y, na, trend="c", exog=exog, hold_back=p).fit()
    close(res.bse[[0, 1, 4]], ref.bse[:3])              # const, a1, a2 (the rest in another order)
    close(res.hqic, ref.hqic)
    close(res.forecast(60, u_future), ref.forecast(60, exog=lagged(u_all, 900, 960)))


def test_arx_forecast_takes_the_kind_of_u_and_checks_it():
    y, u = arx_signal()
    index = pd.date_range("2024-01-01", periods=900, freq="10ms")
    ys, ud = pd.Series(y, index=index, name="pitch"), pd.DataFrame(u, index=index, columns=["elev", "thr"])
    res = tsfdi.ARX(ys, ud, 2, 2, 1).fit()
    future = pd.DataFrame(np.ones((5, 2)), index=pd.date_range(index[-1], periods=6, freq="10ms")[1:],
                          columns=["thr", "elev"])
    f = res.forecast(5, future)
    assert isinstance(f, pd.Series) and f.name == "pitch" and f.index.equals(future.index)
    close(f, res.forecast(5, future[["elev", "thr"]].to_numpy()))       # matched by name
    assert list(res.params.index) == ["a1", "b1.elev", "b1.thr", "a2", "b2.elev", "b2.thr"]
    with pytest.raises(ValueError, match="u has 4 samples but steps is 5"):
        res.forecast(5, future.iloc[:4])
    with pytest.raises(ValueError, match=r"missing channel\(s\) \['thr'\]"):
        res.forecast(5, future[["elev"]].assign(rud=1.0))


def test_forecast_rejects_bad_steps():
    res = tsfdi.AR(ar_signal(), 2).fit()
    for bad in (0, -1):
        with pytest.raises(ValueError, match="steps"):
            res.forecast(bad)
    with pytest.raises(TypeError, match="steps"):
        res.forecast(2.5)
    with pytest.raises(ValueError, match="alpha"):
        res.conf_int(1.5)


# --- several records: the statistics of the stacked regression --------------------------------------------------
def test_multi_record_ar_uses_the_stacked_regression():
    """nobs counts the regression rows of every record; bse is that of OLS on the stacked regressor with
    AutoReg's variance RSS / nobs; hqic uses that nobs; fittedvalues come per record."""
    records = [ar_signal(300, seed=s) for s in (1, 2, 3)]
    res = tsfdi.AR(records, 2, "c").fit()
    assert res.nobs == 3 * (300 - 2)
    X, Y = res.model.design_all()
    ols = sm.OLS(Y[:, 0], X).fit()
    n, k = X.shape
    close(res.bse, ols.bse * np.sqrt((n - k) / n))
    close(res.hqic, -2 * res.llf + 2 * (k + 1) * np.log(np.log(n)))
    fitted = res.fittedvalues
    assert isinstance(fitted, list) and [len(f) for f in fitted] == [298] * 3
    close(np.concatenate(fitted), ols.fittedvalues)
    # the forecast continues the last record: statsmodels' prediction past its end with tsfdi's parameters
    sm_params = res.params * ar_sign("c", 2)
    close(res.forecast(4), AutoReg(records[-1], 2, trend="c").predict(sm_params, start=300, end=303))


def test_multi_record_var_uses_the_stacked_regression():
    records = [var_signal(400, seed=s) for s in (7, 8)]
    res = tsfdi.VAR(records, 2, "c").fit()
    X, Y = res.model.design_all()
    assert res.nobs == X.shape[0] == 2 * 398
    for j in range(3):   # statsmodels' VAR is OLS per equation with sigma_u = RSS / (nobs - df_eq): OLS's bse
        ols = sm.OLS(Y[:, j], X).fit()
        close(res.bse[:, j], ols.bse)
        close(res.pvalues[:, j], 2 * stats.norm.sf(np.abs(ols.tvalues)))


# --- channel safety -----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def named_var():
    y = var_signal(1500)
    df = pd.DataFrame(y, columns=["roll", "pitch", "yaw"], index=pd.date_range("2024", periods=1500, freq="10ms"))
    return df, tsfdi.VAR(df.iloc[:1000], 2, "c").fit()


def test_a_reordered_named_signal_gives_identical_residuals(named_var):
    df, res = named_var
    new = df.iloc[1000:]
    expected = res.residuals(new)
    pd.testing.assert_frame_equal(res.residuals(new[["yaw", "roll", "pitch"]]), expected)
    np.testing.assert_array_equal(res.residuals(new.to_numpy()), expected.to_numpy())   # numpy: by position
    da = xr.DataArray(new.to_numpy(), dims=("time", "channel"),
                      coords={"time": np.arange(500) / 100.0, "channel": ["roll", "pitch", "yaw"]})
    np.testing.assert_array_equal(res.residuals(da.sel(channel=["pitch", "yaw", "roll"])).values,
                                  expected.to_numpy())


def pitch_fault(df):
    """A fault in one channel: pitch through an extra pole, 1 / (1 - 0.7 q^-1)."""
    out = df.copy()
    out["pitch"] = sps.lfilter([1.0], [1.0, -0.7], out["pitch"].to_numpy())
    return out


def test_reordered_channels_give_identical_decisions(named_var):
    df, res = named_var
    new = pitch_fault(df.iloc[1000:])
    shuffled = new[["pitch", "yaw", "roll"]]
    for test in (tsfdi.LjungBox(10, 0.01), tsfdi.FTest(alpha=0.01)):
        a, b = tsfdi.detect(new, res, test), tsfdi.detect(shuffled, res, test)
        assert a.channels == b.channels == ("roll", "pitch", "yaw")
        np.testing.assert_array_equal(a.statistic, b.statistic)
        np.testing.assert_array_equal(a.channel_reject, b.channel_reject)
        assert a.reject and b.reject and a.channel_reject[1]      # pitch rejects
    models = {"healthy": res, "fault": tsfdi.VAR(pitch_fault(df.iloc[:1000]), 2, "c").fit()}
    ia, ib = tsfdi.identify(new, models), tsfdi.identify(shuffled, models)
    assert ia.label == ib.label == "fault"
    for name in models:
        np.testing.assert_array_equal(ia.decisions[name].statistic, ib.decisions[name].statistic)
    # by position the shuffled signal is another signal: the healthy model's pitch column then holds yaw
    assert not np.array_equal(tsfdi.detect(shuffled.to_numpy(), res).statistic, tsfdi.detect(new, res).statistic)


def test_a_missing_or_extra_channel_is_named(named_var):
    df, res = named_var
    new = df.iloc[1000:]
    with pytest.raises(ValueError, match=r"y: missing channel\(s\) \['yaw'\]"):
        res.residuals(new[["roll", "pitch"]])
    with pytest.raises(ValueError, match=r"y: extra channel\(s\) \['airspeed'\]"):
        res.residuals(new.assign(airspeed=1.0))
    with pytest.raises(ValueError, match=r"missing channel\(s\) \['yaw'\]; extra channel\(s\) \['heading'\]"):
        res.residuals(new.rename(columns={"yaw": "heading"}))
    with pytest.raises(ValueError, match=r"missing channel\(s\) \['yaw'\].*extra channel\(s\) \['heading'\]"):
        tsfdi.detect(new.rename(columns={"yaw": "heading"}), res)
    with pytest.raises(ValueError, match=r"missing channel\(s\) \['yaw'\]"):
        tsfdi.detect(new[["roll", "pitch"]], res)
    with pytest.raises(ValueError, match=r"extra channel\(s\) \['airspeed'\]"):
        tsfdi.identify(new.assign(airspeed=np.arange(500.0)), {"healthy": res})
    with pytest.raises(ValueError, match=r"y has 2 channel\(s\) but the model was fitted on 3"):
        res.residuals(new.to_numpy()[:, :2])


def test_a_loaded_model_still_matches_by_name(named_var, tmp_path):
    df, res = named_var
    back = load(res.save(tmp_path / "m"))
    new = df.iloc[1000:]
    pd.testing.assert_frame_equal(back.residuals(new[["pitch", "roll", "yaw"]]), res.residuals(new))
    with pytest.raises(ValueError, match=r"missing channel\(s\) \['roll'\]"):
        back.residuals(new[["pitch", "yaw"]])


def test_records_are_matched_by_name_when_fitting(named_var):
    df, _ = named_var
    a, b = df.iloc[:700], df.iloc[700:]
    ref = tsfdi.VAR([a, b], 2).fit()
    res = tsfdi.VAR([a, b[["yaw", "pitch", "roll"]]], 2).fit()
    pd.testing.assert_frame_equal(res.params, ref.params)
    with pytest.raises(ValueError, match=r"y\[1\]: missing channel\(s\) \['yaw'\]"):
        tsfdi.VAR([a, b[["roll", "pitch"]].assign(alt=np.arange(800.0))], 2)


def test_arx_inputs_are_matched_by_name():
    y, u = arx_signal()
    ud = pd.DataFrame(u, columns=["elev", "thr"])
    ys = pd.Series(y, name="pitch")
    res = tsfdi.ARX(ys, ud, 2, 2, 1).fit()
    pd.testing.assert_series_equal(res.residuals(ys, ud[["thr", "elev"]]), res.residuals(ys, ud))
    with pytest.raises(ValueError, match=r"u: missing channel\(s\) \['thr'\]"):
        res.residuals(ys, ud[["elev"]])
    np.testing.assert_array_equal(res.residuals(y, u), res.residuals(ys, ud).to_numpy())

"""Functionally pooled models (issue 32): FP-AR / FP-VAR / FP-ARX against the explicit pooled regression
``phi[t] (x) G(k_i)`` solved by statsmodels' OLS / WLS, theta(k) and its delta-method errors, residuals at k, the
three data kinds, save / load, operating-point estimation, order selection and bad input."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm
from conftest import KINDS, as_kind, to_numpy
from scipy import signal as sps

from tsfdi.models import AR, ARX, VAR, FPAR, FPARX, FPVAR, FPResults, OperatingPointEstimate, fp_basis, load
from tsfdi.models import select_fp_order

KS = np.array([0.0, 0.2, 0.45, 0.7, 1.0, 0.45])


def ar2(k: float) -> np.ndarray:
    """True AR(2) coefficients (papers' sign) at k: a polynomial surface of degree 2."""
    return np.array([-1.0 + 0.3 * k - 0.6 * k * k, 0.5 + 0.2 * k])


def simulate_ar(k: float, n: int, rng, scale: float = 1.0) -> np.ndarray:
    e = rng.standard_normal(n + 200) * scale
    return sps.lfilter([1.0], np.r_[1.0, ar2(k)], e)[200:]


def records(n: int = 300, seed: int = 0, ks=KS) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [simulate_ar(k, n, rng) for k in ks]


def explicit(ys, us, ks, degree, lags, trend="n", nb=0, nk=0, kmin=None, kmax=None):
    """The FP regressor phi[t] (x) G(k_i) and target of all records, built from the point family's design."""
    lo = np.min(ks) if kmin is None else kmin
    hi = np.max(ks) if kmax is None else kmax
    G = fp_basis(np.asarray(ks, float), degree, [[lo, hi]])
    X, Y = [], []
    for i, y in enumerate(ys):
        if us is None:
            spec = (AR if np.ndim(y) == 1 else VAR)(y, lags, trend)
        else:
            spec = ARX(y, us[i], lags, nb, nk, trend)
        Xi, Yi = spec.design_all()
        X.append((Xi[:, :, None] * G[i][None, None, :]).reshape(Xi.shape[0], -1))
        Y.append(Yi)
    return np.vstack(X), np.vstack(Y), G


def test_fpar_is_the_pooled_regression_of_statsmodels():
    ys = records()
    res = FPAR(ys, KS, 2, degree=2, trend="c").fit()
    X, Y, _ = explicit(ys, None, KS, 2, 2, "c")
    ols = sm.OLS(Y[:, 0], X).fit()
    np.testing.assert_allclose(res.params, ols.params, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res.bse, ols.bse, rtol=1e-9)
    assert res.nobs == X.shape[0] and res.df_model == X.shape[1]
    np.testing.assert_allclose(res.sigma_pooled[0, 0], ols.ssr / ols.nobs, rtol=1e-10)
    assert res.llf == pytest.approx(ols.llf, rel=1e-10)      # Gaussian, sigma2 = RSS / nobs: statsmodels' llf


def test_fpar_weighted_is_statsmodels_wls_with_the_first_stage_variances():
    rng = np.random.default_rng(3)
    ys = [simulate_ar(k, 300, rng, scale=1 + 2 * k) for k in KS]
    res = FPAR(ys, KS, 2, degree=1, weights="point").fit()
    X, Y, G = explicit(ys, None, KS, 1, 2)
    first = sm.OLS(Y[:, 0], X).fit()
    n = [len(y) - 2 for y in ys]
    edges = np.r_[0, np.cumsum(n)]
    s2 = np.array([np.mean(first.resid[a:b] ** 2) for a, b in zip(edges[:-1], edges[1:])])
    w = np.repeat(1 / s2, n)
    wls = sm.WLS(Y[:, 0], X, weights=w).fit()
    np.testing.assert_allclose(res.params, wls.params, rtol=1e-9)
    np.testing.assert_allclose(res.bse, wls.bse, rtol=1e-8)
    np.testing.assert_allclose(res.weights[:, 0], 1 / s2, rtol=1e-9)
    # the noise level grows with k: sigma(k) follows it, positive, between the records' own
    assert res.sigma(0.0)[0, 0] < res.sigma(0.5)[0, 0] < res.sigma(1.0)[0, 0]
    assert res.sigma(1.0)[0, 0] == pytest.approx(9.0, rel=0.35)    # log-variance linear in k: (1 + 2k)^2 roughly


def test_fpvar_and_fparx_equal_the_explicit_regression():
    rng = np.random.default_rng(4)
    ys, us = [], []
    for k in KS:
        u = rng.standard_normal((400, 1))
        e = rng.standard_normal((400, 2))
        y = np.zeros((400, 2))
        for t in range(1, 400):
            y[t] = ((0.5 - 0.3 * k) * y[t - 1] + np.array([0.4 * k, 0.0]) * y[t - 1, ::-1] + e[t]
                    + np.array([1.0, 0.5 * k]) * u[t - 1, 0])
        ys.append(y)
        us.append(u)
    res = FPVAR(ys, KS, 2, degree=1, trend="c").fit()
    X, Y, _ = explicit(ys, None, KS, 1, 2, "c")
    for j in range(2):
        ols = sm.OLS(Y[:, j], X).fit()
        np.testing.assert_allclose(res.params[:, j], ols.params, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(res.bse[:, j], ols.bse, rtol=1e-8)
    yx = [y[:, 0] for y in ys]
    resx = FPARX(yx, us, KS, 2, 2, 1, degree=2).fit()
    X, Y, _ = explicit(yx, us, KS, 2, 2, nb=2, nk=1)
    ols = sm.OLS(Y[:, 0], X).fit()
    np.testing.assert_allclose(resx.params, ols.params, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(resx.bse, ols.bse, rtol=1e-8)


def test_theta_residuals_and_delta_method():
    ys = records(seed=5)
    res = FPAR(ys, KS, 2, degree=2).fit()
    g = fp_basis([0.3], 2, [[0, 1]])[0]
    P = res.params.reshape(2, 3)
    np.testing.assert_allclose(res.theta(0.3), P @ g, rtol=1e-12)
    # delta method against the explicit covariance of statsmodels
    X, Y, _ = explicit(ys, None, KS, 2, 2)
    cov = sm.OLS(Y[:, 0], X).fit().cov_params()
    L = np.kron(np.eye(2), g[None, :])
    np.testing.assert_allclose(res.theta_bse(0.3), np.sqrt(np.diag(L @ cov @ L.T)), rtol=1e-8)
    # residuals at k are the point AR's with theta(k)
    # in-sample residuals: record i through theta(k_i)
    np.testing.assert_allclose(res.resid[1], res.residuals(ys[1], KS[1]), rtol=1e-10, atol=1e-12)
    y = simulate_ar(0.3, 100, np.random.default_rng(1))
    e = res.residuals(y, 0.3)
    ref = np.convolve(y, np.r_[1.0, res.theta(0.3)], "valid")
    np.testing.assert_allclose(e, ref, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_data_kinds_and_channel_names_are_kept(kind):
    rng = np.random.default_rng(6)
    raw = [np.column_stack([simulate_ar(k, 200, rng), rng.standard_normal(200)]) for k in KS]
    ys = [as_kind(r, kind, channels=["roll", "pitch"]) for r in raw]
    k = pd.Series(KS, name="depth") if kind != "numpy" else KS
    res = FPVAR(ys, k, 1, degree=1).fit()
    new = as_kind(raw[0][:, ::-1], kind, channels=["pitch", "roll"]) if kind != "numpy" else raw[0]
    e = res.residuals(new, 0.0)
    if kind == "numpy":
        assert isinstance(res.params, np.ndarray) and res.params.shape == (2 * 2, 2)
        assert isinstance(e, np.ndarray) and e.shape == (199, 2)
    else:
        assert list(res.params.columns) == ["roll", "pitch"]
        assert list(res.params.index) == ["A1.roll:P0", "A1.roll:P1", "A1.pitch:P0", "A1.pitch:P1"]
        assert list(res.theta(0.5).index) == ["A1.roll", "A1.pitch"]
        assert list(to_numpy(e.coords["channel"]) if kind == "xarray" else e.columns) == ["roll", "pitch"]
        # the reordered channels are matched by name: same residuals as the numpy record
        np.testing.assert_allclose(to_numpy(e), FPVAR(raw, KS, 1, degree=1).fit().residuals(raw[0], 0.0),
                                   rtol=1e-12, atol=1e-12)
        assert res.model.k_names == (["depth"])
    assert "FPVAR results" in str(res.summary())


@pytest.mark.parametrize("family", ["ar", "var", "arx", "weighted"])
def test_save_load_round_trip(tmp_path, family):
    rng = np.random.default_rng(7)
    ys = records(120, seed=7)
    idx = pd.date_range("2024", periods=120, freq="10ms")
    if family == "ar":
        res = FPAR([pd.Series(y, index=idx, name="gyro") for y in ys], pd.DataFrame({"depth": KS}), 2, 2).fit()
    elif family == "weighted":
        res = FPAR(ys, KS, 2, 1, "c", weights="point", basis="chebyshev").fit()
    elif family == "var":
        res = FPVAR([np.column_stack([y, rng.standard_normal(120)]) for y in ys], KS, 1, 1).fit()
    else:
        res = FPARX(ys, [rng.standard_normal(120) for _ in ys], KS, 2, 1, 0, 1).fit()
    back = load(res.save(tmp_path / "m"))
    assert isinstance(back, FPResults) and type(back.model) is type(res.model)
    np.testing.assert_array_equal(back.params2d, res.params2d)
    np.testing.assert_allclose(back.bse, res.bse, rtol=1e-12)
    assert back.model.k_names == res.model.k_names and back.model.basis == res.model.basis
    np.testing.assert_array_equal(back.model.k, res.model.k)
    assert back.bic == pytest.approx(res.bic, rel=1e-12)
    if family == "weighted":
        np.testing.assert_array_equal(back.weights, res.weights)


def test_fpvar_weighted_is_statsmodels_wls_per_equation():
    rng = np.random.default_rng(11)
    ys = [np.column_stack([simulate_ar(k, 300, rng, scale=1 + k), rng.standard_normal(300) * (2 - k)]) for k in KS]
    res = FPVAR(ys, KS, 1, degree=1, weights="point").fit()
    X, Y, _ = explicit(ys, None, KS, 1, 1)
    n = [len(y) - 1 for y in ys]
    edges = np.r_[0, np.cumsum(n)]
    for j in range(2):
        first = sm.OLS(Y[:, j], X).fit()
        s2 = np.array([np.mean(first.resid[a:b] ** 2) for a, b in zip(edges[:-1], edges[1:])])
        wls = sm.WLS(Y[:, j], X, weights=np.repeat(1 / s2, n)).fit()
        np.testing.assert_allclose(res.params[:, j], wls.params, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(res.bse[:, j], wls.bse, rtol=1e-8)
    sig = res.sigma(0.5)
    assert sig.shape == (2, 2) and np.all(np.linalg.eigvalsh(sig) > 0)
    assert res.sigma(1.0)[0, 0] > res.sigma(0.0)[0, 0] and res.sigma(1.0)[1, 1] < res.sigma(0.0)[1, 1]


def test_parameter_surface_plot():
    from tsfdi.plotting.fp import plot_fp_surface

    res = FPAR([pd.Series(y, name="gyro") for y in records()], KS, 2, 2).fit()
    fig = plot_fp_surface(res)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["a1", "a2"]
    np.testing.assert_allclose(ax.lines[0].get_ydata()[0], res.theta(0.0)["a1"])


def test_units_far_from_one_are_fitted_exactly_rescaled():
    """Data of magnitude 1e8 are fitted in power-of-two units (as the point models): lag coefficients and their
    errors unchanged, the intercept and sigma scaled, the same operating-point estimate."""
    ys = records(300, seed=13)
    c = 2.0 ** 27
    a = FPVAR([np.column_stack([y, y[::-1]]) for y in ys], KS, 2, 1, "c").fit()
    b = FPVAR([np.column_stack([y, y[::-1]]) * c for y in ys], KS, 2, 1, "c").fit()
    np.testing.assert_allclose(b.params[2:], a.params[2:], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(b.params[:2], a.params[:2] * c, rtol=1e-9, atol=1e-12 * c)
    np.testing.assert_allclose(b.bse[2:], a.bse[2:], rtol=1e-9)
    np.testing.assert_allclose(b.sigma(0.5), a.sigma(0.5) * c * c, rtol=1e-9)
    y = np.column_stack([ys[2], ys[2][::-1]])
    assert b.estimate_k(y * c).k_hat[0] == pytest.approx(a.estimate_k(y).k_hat[0], abs=1e-6)


def test_collinear_regressors_fall_back_to_the_svd_with_a_warning():
    """Exactly collinear channels: the Cholesky factor is refused and the explicit FP regressor goes to the SVD
    solver of the point models (:func:`tsfdi.models.lstsq.lstsq`), which warns that the estimates are not
    reliable; the coefficients stay finite."""
    from tsfdi.exceptions import IllConditionedWarning

    ys = [np.column_stack([y, 2 * y]) for y in records(200, seed=14)]      # exactly collinear channels
    with pytest.warns(IllConditionedWarning, match="ill-conditioned"):
        res = FPVAR(ys, KS, 1, 1).fit()
    assert np.isfinite(res.params2d).all()


def test_immutable():
    res = FPAR(records(), KS, 2, 1).fit()
    with pytest.raises(AttributeError):
        res.weights = None


def test_estimate_k_finds_the_operating_point_and_plots():
    rng = np.random.default_rng(8)
    ks = np.linspace(0, 1, 7)
    res = FPAR([simulate_ar(k, 1500, rng) for k in ks], ks, 2, 2).fit()
    est = res.estimate_k(simulate_ar(0.62, 2000, rng))
    assert isinstance(est, OperatingPointEstimate)
    assert abs(est.k_hat[0] - 0.62) < 4 * est.bse[0] and est.bse[0] < 0.1
    assert est.conf_int[0, 0] < est.k_hat[0] < est.conf_int[0, 1]
    assert est.grid.shape == est.loglik.shape == (1, 201)
    assert est.llf - 0.01 < est.loglik.max() <= est.llf + 1e-9      # the curve peaks at k_hat (between grid points)
    with pytest.raises(ValueError):
        est.k_hat[0] = 0.0
    fig = est.plot()
    assert fig.axes and "k0" in fig.axes[0].get_xlabel()
    assert "Operating-point estimate" in str(est.summary())


def test_estimate_k_two_parameters():
    rng = np.random.default_rng(9)
    pts = np.array([(a, b) for a in (0, 0.5, 1) for b in (0, 0.5, 1)])

    def coefs(a, b):
        return np.array([-1.0 + 0.3 * a, 0.5 + 0.25 * b])

    ys = [sps.lfilter([1.0], np.r_[1.0, coefs(*p)], rng.standard_normal(1200))[200:] for p in pts]
    res = FPAR(ys, pts, 2, 1).fit()
    assert res.model.n_basis == 4 and res.model.basis_names() == ["P0,0", "P0,1", "P1,0", "P1,1"]
    y = sps.lfilter([1.0], np.r_[1.0, coefs(0.3, 0.7)], rng.standard_normal(3200))[200:]
    est = res.estimate_k(y)
    assert np.all(np.abs(est.k_hat - [0.3, 0.7]) < 4 * est.bse)
    assert est.grid.shape == (2, 201)
    # profiles: the other parameter maximised at every grid value, so each curve peaks at the maximum
    assert np.all(est.loglik.max(axis=1) <= est.llf + 1e-6) and np.all(est.loglik.max(axis=1) > est.llf - 0.05)
    i = int(np.argmin(np.abs(est.grid[0] - 0.9)))
    k = np.array([est.grid[0, i], est.k_hat[1]])
    e = res.residuals(y, k)                  # the profiled Gaussian log-likelihood at k, from the residuals
    slice_value = -0.5 * e.size * (np.log(2 * np.pi) + np.log(np.mean(e ** 2)) + 1)
    assert est.loglik[0, i] >= slice_value - 1e-6
    e = res.residuals(y, est.k_hat)
    assert est.llf == pytest.approx(-0.5 * e.size * (np.log(2 * np.pi) + np.log(np.mean(e ** 2)) + 1), abs=1e-6)
    assert len(est.plot().axes) == 2


def test_select_fp_order_finds_the_true_order_and_degree():
    ys = records(800, seed=10, ks=np.linspace(0, 1, 7))
    sel = select_fp_order(ys, np.linspace(0, 1, 7), 4, 3)
    assert sel.selected == (2, 2)
    assert sel.table.shape[0] == 4 * 4
    res = sel.fit()
    assert res.model.na == 2 and res.model.degree == (2,) and res.model.hold_back == 4
    # the selection's BIC is the fit's on the same common sample
    assert res.bic == pytest.approx(sel.table.loc[(2, 2), "bic"], rel=1e-9)


def test_select_fp_order_var_and_arx_refit_their_choice():
    rng = np.random.default_rng(12)
    ks = np.linspace(0, 1, 5)
    ys = [np.column_stack([simulate_ar(k, 300, rng), rng.standard_normal(300)]) for k in ks]
    sel = select_fp_order(ys, ks, 3, 2, "var")
    res = sel.fit()
    assert isinstance(res.model, FPVAR)
    assert res.bic == pytest.approx(sel.table.loc[sel.selected, "bic"], rel=1e-9)
    us = [rng.standard_normal(300) for _ in ks]
    yx = [sps.lfilter([0, 1.0], [1, -0.5 + 0.3 * k], u) + 0.1 * rng.standard_normal(300) for k, u in zip(ks, us)]
    selx = select_fp_order(yx, ks, 3, 2, "arx", u=us)
    resx = selx.fit()
    assert isinstance(resx.model, FPARX) and resx.model.nb == resx.model.na == selx.selected[0]
    assert resx.bic == pytest.approx(selx.table.loc[selx.selected, "bic"], rel=1e-9)
    assert selx.selected[1] >= 1


def test_damaged_fp_archive_is_refused(tmp_path):
    import hashlib
    import io
    import json
    import zipfile

    res = FPAR(records(100), KS, 2, 1).fit()
    path = res.save(tmp_path / "m.npz")
    with zipfile.ZipFile(path) as zf:
        fields = {i.filename: zf.read(i) for i in zf.infolist()}
    def npy(arr) -> bytes:
        buf = io.BytesIO()
        np.lib.format.write_array(buf, np.asarray(arr))
        return buf.getvalue()

    fields["k.npy"] = npy(np.zeros((3, 1)))          # operating points of 3 records for 6, checksums recomputed
    sums = {name[:-4]: hashlib.sha256(data).hexdigest() for name, data in fields.items() if name != "checksums.npy"}
    fields["checksums.npy"] = npy(np.array(json.dumps({"sha256": sums})))
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in fields.items():
            zf.writestr(name, data)
    with pytest.raises(ValueError, match="damaged: the data .* do not fit the FPAR options .*one operating point"):
        load(path)


def test_bad_input_names_the_argument():
    ys = records(100)
    with pytest.raises(ValueError, match="list of records"):
        FPAR(ys[0], [0.0], 2)
    with pytest.raises(ValueError, match="one operating point per record"):
        FPAR(ys, KS[:-1], 2)
    with pytest.raises(ValueError, match="k contains NaN"):
        FPAR(ys, np.r_[KS[:-1], np.nan], 2)
    with pytest.raises(TypeError, match="k must be real"):
        FPAR(ys, ["a"] * len(ys), 2)
    with pytest.raises(ValueError, match="distinct operating points"):
        FPAR(ys, KS, 2, degree=5)
    with pytest.raises(ValueError, match="takes one value only"):
        FPAR(ys, np.zeros(len(ys)), 2, degree=0)
    with pytest.raises(ValueError, match="k_range"):
        FPAR(ys, KS, 2, k_range=[0.1, 1.0])
    with pytest.raises(ValueError, match="basis"):
        FPAR(ys, KS, 2, basis="fourier")
    with pytest.raises(ValueError, match="weights"):
        FPAR(ys, KS, 2, weights="gls")
    with pytest.raises(ValueError, match=r"y\[2\]"):
        FPAR(ys[:2] + [np.r_[ys[2][:-1], np.nan]] + ys[3:], KS, 2)
    res = FPAR(ys, KS, 2, 1).fit()
    with pytest.raises(ValueError, match="k must be one operating point"):
        res.theta([0.1, 0.2])
    with pytest.raises(ValueError, match="k must be finite"):
        res.residuals(ys[0], np.nan)
    with pytest.raises(ValueError, match="bounds"):
        res.estimate_k(ys[0], bounds=[1.0, 0.0])
    with pytest.raises(ValueError, match="u is given"):
        res.estimate_k(ys[0], u=ys[1])
    with pytest.raises(ValueError, match="alpha"):
        res.estimate_k(ys[0], alpha=1.5)
    with pytest.raises(ValueError, match="model"):
        select_fp_order(ys, KS, 2, 1, model="arma")
    with pytest.raises(ValueError, match="k_range"):
        fp_basis([0.5], 1, [[1.0, 1.0]])
    with pytest.raises(ValueError, match="NaN"):
        fp_basis([np.nan], 1, [[0.0, 1.0]])
    rng = np.random.default_rng(0)
    vres = FPVAR([pd.DataFrame(rng.standard_normal((50, 2)), columns=["p", "q"]) for _ in KS], KS, 1, 1).fit()
    with pytest.raises(ValueError, match="missing channel"):
        vres.estimate_k(pd.DataFrame(rng.standard_normal((50, 2)), columns=["p", "r"]))
    with pytest.raises(ValueError, match="y"):
        vres.estimate_k(pd.DataFrame(np.full((50, 2), np.nan), columns=["p", "q"]))
    xres = FPARX(ys, [rng.standard_normal(100) for _ in ys], KS, 1, 1, 0, 1).fit()
    with pytest.raises(ValueError, match="u is required"):
        xres.residuals(ys[0], 0.5)
    with pytest.raises(ValueError, match="u is required"):
        xres.estimate_k(ys[0])


def test_at_is_the_point_results_at_k():
    """at(k) is the point family's results with theta(k) and sigma(k): its residuals are residuals(y, k) for AR,
    VAR and ARX, its sigma / sigma2 is sigma(k) (pooled and point-weighted), nobs is the FP model's."""
    from tsfdi.models import ARResults, ARXResults, VARResults

    rng = np.random.default_rng(9)
    ys = [simulate_ar(k, 300, rng, scale=1 + 2 * k) for k in KS]
    y = simulate_ar(0.3, 200, np.random.default_rng(2))
    for weights in ("pooled", "point"):
        res = FPAR(ys, KS, 2, degree=2, weights=weights).fit()
        pt = res.at(0.3)
        assert isinstance(pt, ARResults)
        np.testing.assert_array_equal(pt.params, res.theta(0.3))
        np.testing.assert_array_equal(pt.residuals(y), res.residuals(y, 0.3))
        assert pt.sigma2 == pytest.approx(res.sigma(0.3)[0, 0], rel=1e-12)
        assert pt.nobs == res.nobs
    assert res.at(1.0).sigma2 > 2 * res.at(0.0).sigma2          # the point-weighted sigma(k) follows k
    vs = [np.column_stack([y_, np.roll(y_, 1) + rng.standard_normal(300)]) for y_ in ys]
    rv = FPVAR(vs, KS, 2, degree=1, weights="point").fit()
    pv = rv.at(0.6)
    assert isinstance(pv, VARResults)
    np.testing.assert_allclose(pv.sigma, rv.sigma(0.6), rtol=1e-12)
    np.testing.assert_array_equal(pv.residuals(vs[0]), rv.residuals(vs[0], 0.6))
    us = [rng.standard_normal(300) for _ in KS]
    rx = FPARX(ys, us, KS, 2, 2, 1, degree=1).fit()
    px = rx.at(0.2)
    assert isinstance(px, ARXResults)
    np.testing.assert_array_equal(px.residuals(ys[0], us[0]), rx.residuals(ys[0], 0.2, us[0]))
    with pytest.raises(ValueError, match="k"):
        res.at([0.1, 0.2])


def test_identify_and_detect_take_fp_models_at_k():
    """One FP model per class (healthy, fault) serves every operating point: identify / identify_windows / detect
    with at(k) pick the record's class at operating points between the fitted ones, with the F test's reference
    variance sigma(k)."""
    import tsfdi

    def fault(k):
        return np.array([-0.4 + 0.3 * k, 0.3])

    rng = np.random.default_rng(11)
    h = [simulate_ar(k, 2000, rng) for k in KS]
    f = [sps.lfilter([1.0], np.r_[1.0, fault(k)], rng.standard_normal(2200))[200:] for k in KS]
    healthy = FPAR(h, KS, 2, degree=2).fit()
    faulty = FPAR(f, KS, 2, degree=2).fit()
    test = tsfdi.FTest(alpha=0.01)
    for k in (0.1, 0.6, 0.85):
        yh = simulate_ar(k, 2000, rng)
        yf = sps.lfilter([1.0], np.r_[1.0, fault(k)], rng.standard_normal(2200))[200:]
        models = {"healthy": healthy.at(k), "fault": faulty.at(k)}
        assert tsfdi.identify(yh, models, test).label == "healthy"
        assert tsfdi.identify(yf, models, test).label == "fault"
        assert not tsfdi.detect(yh, healthy.at(k), test).reject
        assert tsfdi.detect(yf, healthy.at(k), test).reject
        win = tsfdi.identify_windows(yf, models, tsfdi.LjungBox(lags=10, alpha=0.01), window=500, step=500)
        assert (np.asarray(win.labels) == "fault").mean() >= 0.75


def test_results_take_residual_products_and_check_them():
    """LinearTimeSeriesResults(model, params, residual_products=E'E): sigma reads it (what FPResults.at passes)
    instead of the model's own residuals; a wrong shape or a non-finite entry is refused by name."""
    y = np.random.default_rng(4).standard_normal((500, 2))
    res = VAR(y, 1).fit()
    other = type(res)(res.model, res.params, residual_products=4.0 * res.nobs * np.eye(2))
    np.testing.assert_allclose(other.sigma, 4.0 * np.eye(2))             # sigma = E'E / nobs (ML)
    for bad in (np.eye(3), np.full((2, 2), np.nan)):
        with pytest.raises(ValueError, match=r"residual_products must be a finite \(2, 2\) matrix"):
            type(res)(res.model, res.params, residual_products=bad)

"""fit() through the Gram matrix (issue 36): the same results as the SVD of the regressor, which is kept only for the
ill-conditioned regressors that the conditioning check sends to it."""

import warnings

import numpy as np
import pytest
from scipy import linalg
from scipy import signal as sps

import tsfdi.models._base as base_module
from tsfdi import AR, ARX, VAR
from tsfdi.exceptions import IllConditionedWarning, UnstableModelWarning


def smooth(n, s, seed, cutoff=0.02, noise=1e-6):
    """Low-pass filtered noise sampled far above its bandwidth: a regressor with condition number ~1e6, where
    plain normal equations lose ~1e-5 relative in the coefficients."""
    rng = np.random.default_rng(seed)
    b, a = sps.butter(4, cutoff)
    mix = np.triu(np.full((s, s), 0.4)) + 0.6 * np.eye(s)
    return sps.lfilter(b, a, rng.standard_normal((n, s)) @ mix, axis=0) + noise * rng.standard_normal((n, s))


def svd_results(model):
    """The results of the SVD path: LAPACK gelsd on the explicit regressor (data within the models' own units)."""
    X, Y = model.design_all()
    return model.results_class(model, linalg.lstsq(X, Y, lapack_driver="gelsd")[0])


def assert_same(res, ref, rtol=1e-8):
    def close(a, b):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * np.abs(b).max())

    close(res.params2d, ref.params2d)
    close(res.bse, ref.bse)
    for name in ("llf", "aic", "bic", "hqic", "rss_sss"):
        close(getattr(res, name), getattr(ref, name))
    close(res.sigma if res.model.neqs > 1 else res.sigma2, ref.sigma if ref.model.neqs > 1 else ref.sigma2)
    r, q = res.resid, ref.resid
    for a, b in zip(r if isinstance(r, list) else [r], q if isinstance(q, list) else [q]):
        close(a, b)


def count_svd_calls(monkeypatch):
    calls = []
    real = base_module.lstsq

    def spy(X, Y):
        calls.append(X.shape)
        return real(X, Y)

    monkeypatch.setattr(base_module, "lstsq", spy)
    return calls


CASES = {
    "AR one record": lambda tr: AR(smooth(4000, 1, 1)[:, 0], 16, trend=tr),
    "AR records": lambda tr: AR([smooth(1500, 1, i)[:, 0] for i in range(3)], 16, trend=tr),
    "VAR one record": lambda tr: VAR(smooth(3000, 3, 4), 16, trend=tr),
    "VAR records": lambda tr: VAR([smooth(3000, 3, i) for i in range(3)], 16, trend=tr),
    "VAR records, hold_back": lambda tr: VAR([smooth(2000, 2, i) for i in range(3)], 8, trend=tr, hold_back=20),
    "ARX records": lambda tr: ARX([smooth(2000, 1, i)[:, 0] for i in range(3)],
                                  [smooth(2000, 2, 10 + i) for i in range(3)], na=8, nb=6, nk=1, trend=tr),
}


@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("case", list(CASES))
def test_fit_through_the_gram_matrix_equals_the_svd_path(case, trend, monkeypatch):
    model = CASES[case](trend)
    ref = svd_results(model)
    calls = count_svd_calls(monkeypatch)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnstableModelWarning)
        res = model.fit()
    assert calls == []                          # the well-conditioned regressor never reaches the SVD
    assert_same(res, ref)


def test_gram_starts_at_hold_back():
    """gram() of an AR / VAR with hold_back > lags covers the rows of design_all (it started at lags before)."""
    for model in (VAR([smooth(300, 2, i) for i in range(2)], 3, trend="c", hold_back=10),
                  AR(smooth(300, 1, 7)[:, 0], 2, hold_back=9)):
        Z = np.hstack(model.design_all(scaled=True))
        np.testing.assert_allclose(model.gram(), Z.T @ Z, rtol=1e-10, atol=1e-12 * np.abs(Z.T @ Z).max())


@pytest.mark.parametrize("make", [
    lambda: AR(np.sin(0.3 * np.arange(400.0)) + 1e-7 * np.random.default_rng(0).standard_normal(400), 6),
    lambda: VAR(np.column_stack([np.sin(0.2 * np.arange(500.0)), np.cos(0.2 * np.arange(500.0))])
                + 1e-7 * np.random.default_rng(1).standard_normal((500, 2)), 4, trend="c"),
])
def test_ill_conditioned_fit_takes_the_svd_fallback(make, monkeypatch):
    """A regressor whose columns keep less than GRAM_RELATIVE_FLOOR of their energy is solved by the SVD of the
    regressor, exactly the SVD answer."""
    model = make()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", (IllConditionedWarning, UnstableModelWarning))
        ref = svd_results(model)
        calls = count_svd_calls(monkeypatch)
        res = model.fit()
        assert calls == [(sum(model.nobs_records), model.df_eq)]
        np.testing.assert_array_equal(res.params2d, ref.params2d)
        assert_same(res, ref, rtol=1e-12)


@pytest.mark.parametrize("lags", [1, 2, 5, 13])
@pytest.mark.parametrize("const", [False, True])
def test_lag_kernels_equal_explicit_products(lags, const):
    """The compiled lag kernels give the explicit Gram matrix and X'(Y - X B) of records end to end."""
    from tsfdi.models import lstsq

    rng = np.random.default_rng(lags)
    for s, lengths in [(1, [40]), (1, [30, lags + 2, 50]), (3, [57, 23, 41]), (2, [lags + 2, 64])]:
        records = [rng.standard_normal((n, s)) + 0.3 for n in lengths]
        parts = [lstsq.lagged_design(r, lags, lags, const=const) for r in records]
        X, Y = np.vstack([p[0] for p in parts]), np.vstack([p[1] for p in parts])
        Z = np.hstack([X, Y])
        np.testing.assert_allclose(lstsq.lag_gram(records, lags, const=const), Z.T @ Z, rtol=1e-12, atol=1e-11)
        coef = rng.standard_normal((X.shape[1], s))
        np.testing.assert_allclose(lstsq.lag_residual_products(records, coef, const=const), X.T @ (Y - X @ coef),
                                   rtol=1e-12, atol=1e-10)


@pytest.mark.parametrize("where", ["diag", "offdiag", "nan", "nan_diag"])
def test_gram_factor_refuses_non_finite_gram(where):
    """No factor of a Gram matrix with an inf / NaN entry (the Cholesky check has no separate finiteness scan:
    potrf's pivots and the energy test refuse every such case)."""
    from tsfdi.models.lstsq import gram_factor

    rng = np.random.default_rng(0)
    X = rng.standard_normal((50, 6))
    G = X.T @ X
    G[3, 3] = np.inf if where == "diag" else np.nan if where == "nan_diag" else G[3, 3]
    if where in ("offdiag", "nan"):
        G[1, 4] = G[4, 1] = np.inf if where == "offdiag" else np.nan
    assert gram_factor(G, 6) is None
    assert gram_factor(X.T @ X, 6) is not None

"""Order selection: common sample, agreement with fitted models, the papers' BIC, the fast Gram path."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from scipy import signal as sps
from statsmodels.tsa.api import VAR as smVAR
from statsmodels.tsa.ar_model import ar_select_order

import tsfdi
from tsfdi.models import lstsq
from tests.conftest import as_kind
from tests.models.test_ar import TRUE_A6, simulate_ar
from tests.models.test_var_arx import arx_data


def var4(seed, n=2000):
    rng = np.random.default_rng(seed)
    A = [np.diag([-0.5, -0.3, -0.4]) + 0.05, np.diag([0.3, 0.2, 0.25]), np.diag([-0.15, 0.1, -0.1]),
         np.array([[0.3, 0.1, 0.0], [0.0, -0.3, 0.1], [0.1, 0.0, 0.35]])]
    from tsfdi.models.var import simulate_var

    return simulate_var(np.stack(A), rng.standard_normal((n + 500, 3)))[500:]


@pytest.mark.parametrize("trend", ["n", "c"])
def test_table_equals_fitted_models_on_the_common_sample(trend):
    y = simulate_ar(TRUE_A6, 2000, np.random.default_rng(1))
    sel = tsfdi.select_order(y, 15, trend=trend)
    assert list(sel.table.index) == list(range(1, 16))
    for p in (1, 6, 11, 15):
        res = sel.fit(p)
        assert res.nobs == 2000 - 15
        for col in ("bic", "aic", "llf", "rss_sss", "spp", "sigma2"):
            np.testing.assert_allclose(sel.table.loc[p, col], getattr(res, col), rtol=1e-9)


def test_var_table_equals_fitted_models():
    y = var4(0)
    for criterion in ("logdet", "trace"):
        sel = tsfdi.select_order(y, 10, "var", trend="c", criterion=criterion)
        for p in (1, 4, 10):
            res = sel.fit(p)
            assert res.model.criterion == criterion
            np.testing.assert_allclose(sel.table.loc[p, "bic"], res.bic, rtol=1e-9)
            np.testing.assert_allclose(sel.table.loc[p, "sigma2"], np.trace(res.sigma) / 3, rtol=1e-9)


def test_arx_selection_equals_fits():
    y, u = arx_data(n=1500)
    sel = tsfdi.select_order(y, 6, "arx", u=u, nk=1, trend="c")
    assert sel.selected == 2
    for p in (1, 2, 6):
        res = sel.fit(p)
        assert res.model.na == res.model.nb == p
        np.testing.assert_allclose(sel.table.loc[p, "bic"], res.bic, rtol=1e-9)


def test_at_order_equals_the_spec_of_that_order():
    """spec.at_order(p) (what OrderSelection.fit fits; the Gram matrix read from the larger spec's) is the spec its
    constructor gives with the same hold_back: same options, Gram matrix, fit (1e-10) and the order checked."""
    y, u = arx_data(n=800)
    rng = np.random.default_rng(3)
    big = [rng.standard_normal((300, 2)) * 1e9, rng.standard_normal((250, 2)) * 1e9]   # fitted in rescaled units
    cases = [(tsfdi.AR(y, 12, trend="c"), lambda p: tsfdi.AR(y, p, trend="c", hold_back=12)),
             (tsfdi.VAR(big, 7, trend="c", criterion="trace"),
              lambda p: tsfdi.VAR(big, p, trend="c", hold_back=7, criterion="trace")),
             (tsfdi.ARX(y, u, na=5, nb=4, nk=2, hold_back=9),
              lambda p: tsfdi.ARX(y, u, na=p, nb=p, nk=2, hold_back=9))]
    for spec, make in cases:
        top = min(spec.na, spec.nb) if spec.nb else spec.na
        for p in (1, 3, top):
            sub, ref = spec.at_order(p), make(p)
            for name in ("na", "nb", "nk", "max_lag", "hold_back", "trend", "criterion", "df_eq"):
                assert getattr(sub, name) == getattr(ref, name), name
            np.testing.assert_allclose(sub.gram(), ref.gram(), rtol=1e-12, atol=1e-12 * np.abs(ref.gram()).max())
            a, b = sub.fit(), ref.fit()
            np.testing.assert_allclose(a.params2d, b.params2d, rtol=1e-10, atol=1e-10 * np.abs(b.params2d).max())
            np.testing.assert_allclose(a.bic, b.bic, rtol=1e-12)
        with pytest.raises(ValueError, match="order"):
            spec.at_order(top + 1)
    with pytest.raises(ValueError, match="read-only"):
        spec.gram()[0, 0] = 1.0


@pytest.mark.parametrize("seed", range(5))
def test_papers_bic_selects_the_true_ar6_order(seed):
    y = simulate_ar(TRUE_A6, 2000, np.random.default_rng(seed))
    sel = tsfdi.select_order(y, 30)
    assert sel.selected == 6
    # paper 003 eq. 5 (ln sigma^2 + d ln N / N) picks the same order as the likelihood BIC
    n = 2000 - 30
    eq5 = np.log(sel.table["sigma2"]) + sel.table.index * np.log(n) / n
    assert int(eq5.idxmin()) == 6
    assert sel.stabilized <= 6


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("criterion", ["logdet", "trace"])
def test_papers_bic_selects_the_true_var4_order(seed, criterion):
    sel = tsfdi.select_order(var4(seed), 12, "var", criterion=criterion)
    assert sel.selected == 4


def test_same_orders_as_statsmodels():
    y = simulate_ar(TRUE_A6, 2000, np.random.default_rng(7))
    ref = ar_select_order(y, 20, ic="bic", trend="c")
    assert tsfdi.select_order(y, 20, trend="c").selected == max(ref.ar_lags)
    Y = var4(3)
    assert tsfdi.select_order(Y, 10, "var", trend="c").selected == smVAR(Y).select_order(10).selected_orders["bic"]


def test_gram_matches_explicit_cross_products():
    rng = np.random.default_rng(2)
    for s, const in [(1, False), (1, True), (3, True), (2, False)]:
        y = rng.standard_normal((300, s)).cumsum(0) * 0.1 + rng.standard_normal((300, s))
        X, Y = lstsq.lagged_design(y, 9, 9, const=const)
        Z = np.hstack([X, Y])
        np.testing.assert_allclose(lstsq.lag_gram(y, 9, const=const), Z.T @ Z, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("const", [False, True])
def test_cholesky_nested_fits_equal_the_lapack_path(const):
    """The compiled route (own Cholesky factor and nested fits) against LAPACK's factor (triangular_factor) +
    nested_fits, on the benchmark's shapes, several records, and ARX-like widths (groups wider than the targets)."""
    rng = np.random.default_rng(7)
    y6 = simulate_ar(TRUE_A6, 2000, rng)[:, None]
    Y = var4(3)
    cases = [(y6, 50, 1), (Y, 20, 3), ([y6[:600], y6[600:1300], y6[1300:]], 13, 1), ([Y[:500], Y[500:]], 7, 3),
             (rng.standard_normal((40, 2)), 5, 2), (y6[:30], 1, 1), (Y, 6, 1), (Y[:, :1], 12, 3)]
    for y, p, group in cases:
        s = (y[0] if isinstance(y, list) else y).shape[1]
        gram = lstsq.lag_gram(y, p, const=const)
        widths = int(const) + np.arange(1, (gram.shape[0] - s - int(const)) // group + 1) * group
        sse = lstsq.cholesky_nested_fits(gram, s, widths)
        ref = lstsq.nested_fits(lstsq.triangular_factor(gram, None, s), s, widths)
        assert sse.shape == ref.shape == (widths.size, s, s)
        np.testing.assert_allclose(sse, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())


def test_cholesky_kernel_matches_potrf_and_refuses_what_it_refuses():
    """The compiled Cholesky factor (panels of 4 rows) equals LAPACK's at every size around the panel edges, and
    refuses the matrices that _cholesky refuses: not positive definite, a column keeping no more than
    GRAM_RELATIVE_FLOOR of its energy, an inf / NaN entry."""
    from scipy.linalg import lapack

    rng = np.random.default_rng(11)
    for n in range(1, 14):
        X = rng.standard_normal((3 * n + 5, n))
        G = X.T @ X
        R = np.empty_like(G)
        assert lstsq._cholesky_upper(G, lstsq.GRAM_RELATIVE_FLOOR, R)
        np.testing.assert_allclose(np.triu(R), lapack.dpotrf(G, lower=0, clean=1)[0], rtol=1e-12, atol=1e-12)
    X = rng.standard_normal((50, 6))
    bad = []
    G = X.T @ X
    G[2, 2] = -1.0
    bad.append(G)
    Xc = X.copy()
    Xc[:, 4] = Xc[:, 1] - 2 * Xc[:, 3] + 1e-6 * rng.standard_normal(50)    # keeps ~1e-13 of its energy
    bad.append(Xc.T @ Xc)
    for v in (np.inf, np.nan):
        for ij in ((3, 3), (1, 4)):
            G = X.T @ X
            G[ij] = G[ij[::-1]] = v
            bad.append(G)
    for G in bad:
        assert lstsq._cholesky(G) is None
        assert not lstsq._cholesky_upper(G, lstsq.GRAM_RELATIVE_FLOOR, np.empty_like(G))


@pytest.mark.filterwarnings("ignore::tsfdi.exceptions.UnstableModelWarning")  # a sinusoid is marginally stable
def test_qr_fallback_for_ill_conditioned_regressors():
    # a nearly noise-free sinusoid: lagged copies are almost collinear (cond ~ 2e7), so the Gram matrix
    # (cond ~ 5e14) loses the digits and R must come from a QR of the regressor
    t = np.arange(3000)
    y = np.sin(0.05 * t) + 1e-7 * np.random.default_rng(0).standard_normal(t.size)
    gram = lstsq.lag_gram(y[:, None], 10, const=False)
    called = []

    def design():
        called.append(True)
        return np.hstack(lstsq.lagged_design(y[:, None], 10, 10, const=False))

    R = lstsq.triangular_factor(gram, design)
    assert called, "the QR fallback was not used"
    assert lstsq.cholesky_nested_fits(gram, 1, np.arange(1, 11)) is None     # select_order's route declines too
    Rq = np.linalg.qr(design(), mode="r")
    np.testing.assert_allclose(np.abs(np.diag(R)), np.abs(np.diag(Rq)), rtol=1e-8)
    sel = tsfdi.select_order(y, 10)
    for p in (2, 5, 10):
        np.testing.assert_allclose(sel.table.loc[p, "sigma2"], sel.fit(p).sigma2, rtol=1e-6)


@pytest.mark.filterwarnings("ignore::tsfdi.exceptions.UnstableModelWarning")
def test_rank_deficient_regressor_warns():
    y = np.sin(0.05 * np.arange(3000))    # satisfies an exact AR(2) recursion: lags 3+ are collinear
    with pytest.warns(tsfdi.exceptions.IllConditionedWarning):
        tsfdi.select_order(y, 10)
    with pytest.warns(tsfdi.exceptions.IllConditionedWarning):
        tsfdi.AR(y, 10).fit()


def test_stabilized_rule():
    y = simulate_ar(TRUE_A6, 2000, np.random.default_rng(4))
    sel = tsfdi.select_order(y, 20, tol=0.01)
    r = sel.table["rss_sss"].to_numpy()
    p = sel.stabilized
    gains = (r[:-1] - r[1:]) / r[:-1]
    assert np.all(gains[p - 1:] <= 0.01) and gains[p - 2] > 0.01


def test_kinds_and_plot(kind):
    y = simulate_ar(TRUE_A6, 800, np.random.default_rng(5))
    sel = tsfdi.select_order(as_kind(y, kind), 10)
    assert sel.selected == tsfdi.select_order(y, 10).selected
    fig = sel.plot()
    assert len(fig.axes) == 2
    Y = var4(1, 600)
    assert tsfdi.select_order(as_kind(Y, kind), 6, "var").selected == tsfdi.select_order(Y, 6, "var").selected
    assert "OrderSelection" in repr(sel)


def test_bad_options():
    y = simulate_ar(TRUE_A6, 300, np.random.default_rng(5))
    with pytest.raises(ValueError, match="model"):
        tsfdi.select_order(y, 5, "arma")
    with pytest.raises(ValueError, match="max_lags"):
        tsfdi.select_order(y, 0)
    with pytest.raises(ValueError, match="u is required"):
        tsfdi.select_order(y, 5, "arx")
    with pytest.raises(ValueError, match="u is only used"):
        tsfdi.select_order(y, 5, "ar", u=y)
    with pytest.raises(ValueError, match="order"):
        tsfdi.select_order(y, 5).fit(6)
    with pytest.raises(ValueError, match="y is too short"):
        tsfdi.select_order(y[:40], 30)


def test_bic_minimum_at_the_search_bound_is_flagged():
    """Issue 29: a BIC minimum at max_lags was not flagged: it warns (ConvergenceWarning, a TsfdiWarning) and the
    summary says so; an interior minimum does not."""
    from tsfdi.exceptions import ConvergenceWarning, TsfdiWarning

    rng = np.random.default_rng(29)
    y = sps.lfilter([1.0], [1.0, -0.5, 0.4, -0.3, 0.3, -0.3, 0.3], rng.standard_normal(4000))   # AR(6)
    with pytest.warns(ConvergenceWarning, match=r"BIC minimum is at the search bound max_lags = 3.*max_lags=6"):
        sel = tsfdi.select_order(y, 3)
    assert issubclass(ConvergenceWarning, TsfdiWarning) and sel.at_bound and sel.selected == 3
    text = str(sel.summary())
    assert "3 (at the search bound)" in text and "min BIC (at the search bound)" in text and "search further" in text
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        wide = tsfdi.select_order(y, 12)
    assert not wide.at_bound and "search bound" not in str(wide.summary())


def test_vector_data_with_model_ar_suggests_var():
    """Issue 29: select_order(DataFrame with 3 columns, 10) did not suggest model='var'."""
    df = pd.DataFrame(np.random.default_rng(30).standard_normal((500, 3)), columns=["roll", "pitch", "yaw"])
    for data in (df, [df, df]):
        with pytest.raises(ValueError, match=r"data has 3 channels .*model='var'.*select_order\(data, 10, "
                                             r"model='var'\)"):
            tsfdi.select_order(data, 10)

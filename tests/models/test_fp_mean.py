"""FPMean, the functionally pooled mean of windows (the trim model of issue 32): Monte Carlo recovery of a known
surface and of its standard errors, BIC's choice of the degree, the window log-likelihood against a direct
computation, the record covariance, archive, kinds and bad input."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import optimize, stats

import tsfdi
from tsfdi.models import FPMean, FPMeanResults, fp_basis, load

K_RANGE = np.array([[2.0, 10.0], [0.0, 0.3]])


def surface(k: np.ndarray, degree: int) -> np.ndarray:
    """The true trim (3 channels) at points ``k`` (m, 2): linear, plus quadratic terms for degree 2."""
    s, p = k[:, 0], k[:, 1]
    out = np.column_stack([10.0 + 2.0 * s, -30.0 + 40.0 * p, 5.0 - s])
    if degree >= 2:
        out = out + np.column_stack([0.3 * s * s, -300.0 * p * p, 0.5 * s * s - 20 * s * p])
    return out


def records(rng, n_rec: int, *, degree: int = 1, offset_sd: float = 1.0, noise_sd: float = 5.0, n: int = 4000):
    """Records whose three channels are the surface at the record's k, plus a per-record offset (an unlogged
    airframe), plus white noise."""
    k = np.column_stack([rng.uniform(*K_RANGE[0], n_rec), rng.uniform(*K_RANGE[1], n_rec)])
    level = surface(k, degree) + rng.normal(0, offset_sd, (n_rec, 3))
    return [lv + rng.normal(0, noise_sd, (n, 3)) for lv in level], k


def true_coef(degree: int) -> np.ndarray:
    """The Legendre coefficients of the true surface (exact: the basis of ``degree`` holds it)."""
    g = np.array(np.meshgrid(np.linspace(*K_RANGE[0], 9), np.linspace(*K_RANGE[1], 9))).reshape(2, -1).T
    return np.linalg.lstsq(fp_basis(g, degree, K_RANGE), surface(g, degree), rcond=None)[0]


@pytest.mark.slow
def test_monte_carlo_recovers_the_surface_and_its_standard_errors():
    rng = np.random.default_rng(20261129)
    truth = true_coef(2)
    est, z = [], []
    for _ in range(150):
        y, k = records(rng, 40, degree=2, offset_sd=2.0, noise_sd=20.0, n=2000)
        res = FPMean(y, k, 500, 2, k_range=K_RANGE).fit()
        est.append(res.params)
        z.append((res.params - truth) / res.bse)
    est, z = np.array(est), np.array(z)
    # unbiased: the mean estimate within 4 Monte Carlo standard errors of the truth, every coefficient
    mc_se = est.std(axis=0, ddof=1) / np.sqrt(len(est))
    assert (np.abs(est.mean(axis=0) - truth) < 4 * mc_se).all()
    # the standard errors have the estimates' spread: 95 % normal intervals cover at 95 % over all coefficients
    cover = (np.abs(z) < stats.norm.isf(0.025)).mean()
    assert 0.93 <= cover <= 0.97
    assert 0.85 < z.std() < 1.15


def test_bic_picks_the_true_degree():
    rng = np.random.default_rng(7)
    for true in (1, 2):
        picks = []
        for _ in range(30):
            y, k = records(rng, 40, degree=true, offset_sd=1.0, noise_sd=10.0, n=2000)
            bic = [FPMean(y, k, 500, d, k_range=K_RANGE).fit().bic for d in range(4)]
            picks.append(int(np.argmin(bic)))
        assert np.mean(np.array(picks) == true) >= 0.9, (true, picks)


def test_loglike_and_statistic_equal_a_direct_computation():
    rng = np.random.default_rng(1)
    y, k = records(rng, 30, degree=2, offset_sd=1.0, noise_sd=5.0)
    res = FPMean(y, k, 500, 2, k_range=K_RANGE).fit()
    new, k_new = records(rng, 1, degree=2)
    sig = new[0]
    ll, q, kh = res.loglike(sig), res.statistic(sig), res.estimate_k(sig)
    assert ll.shape == q.shape == (8,) and kh.shape == (8, 2)

    def direct(m, kk):
        mean = fp_basis(np.atleast_2d(kk), 2, K_RANGE)[0] @ res.params2d
        return stats.multivariate_normal(mean, res.S).logpdf(m)

    for w in range(8):
        m = sig[500 * w:500 * (w + 1)].mean(axis=0)
        # the window's likelihood at the returned k, exactly
        assert ll[w] == pytest.approx(direct(m, kh[w]), rel=1e-10, abs=1e-10)
        d = m - fp_basis(kh[w][None], 2, K_RANGE)[0] @ res.params2d
        assert q[w] == pytest.approx(d @ np.linalg.solve(res.S, d), rel=1e-10, abs=1e-12)
        # and that k is the maximum over k_range: no bounded search from many starts finds a larger one
        best = max(-optimize.minimize(lambda x: -direct(m, x), x0, bounds=K_RANGE.tolist(), method="L-BFGS-B").fun
                   for x0 in np.column_stack([np.linspace(2.5, 9.5, 5), np.linspace(0.02, 0.28, 5)]))
        assert ll[w] >= best - 1e-6 * abs(best)
    # a step of the window gives the consecutive windows; another step, the windows every step samples
    np.testing.assert_array_equal(res.loglike(sig, 500), ll)
    ll250 = res.loglike(sig, 250)
    assert ll250.shape == (15,)
    np.testing.assert_allclose(ll250[::2], ll, rtol=1e-12)


def test_statistic_and_loglike_at_a_logged_k():
    """With the record's operating point known, the statistic and the log-likelihood at it (no search): equal to a
    direct computation from predict(k), never below the profiled minimum; chi-square with s degrees of freedom on
    new records at their own k (Monte Carlo, windows of independent records); k checked naming it."""
    rng = np.random.default_rng(7)
    y, k = records(rng, 40, degree=1, offset_sd=1.0, noise_sd=5.0)
    res = FPMean(y, k, 500, 1, k_range=K_RANGE).fit()
    new, k_new = records(rng, 1, degree=1)
    sig, kk = new[0], k_new[0]
    mean = res.predict(kk)
    np.testing.assert_allclose(mean, fp_basis(kk[None], 1, K_RANGE)[0] @ res.params2d, rtol=1e-14)
    q, ll = res.statistic(sig, k=kk), res.loglike(sig, k=kk)
    for w in range(8):
        d = sig[500 * w:500 * (w + 1)].mean(axis=0) - mean
        assert q[w] == pytest.approx(d @ np.linalg.solve(res.S, d), rel=1e-10)
        assert ll[w] == pytest.approx(stats.multivariate_normal(mean, res.S).logpdf(d + mean), rel=1e-10)
    assert (q >= res.statistic(sig) - 1e-9).all()
    # under the model (new records' offsets and noise as the fitting ones'), one window per record, the model
    # fitted on many records (S estimated closely: with few records the statistic is Hotelling's, wider): chi2(3)
    many = FPMean(*records(rng, 600, degree=1, n=2000), 500, 1, k_range=K_RANGE).fit()
    stat = [many.statistic(r[:500], k=kr)[0] for r, kr in zip(*records(rng, 400, degree=1, n=500))]
    assert stats.kstest(stat, stats.chi2(3).cdf).pvalue > 0.001
    with pytest.raises(ValueError, match=r"k must be one operating point with 2 value\(s\)"):
        res.statistic(sig, k=[3.0])
    with pytest.raises(ValueError, match="k must be finite"):
        res.predict([np.nan, 0.1])
    named = FPMean([pd.DataFrame(r, columns=["a", "b", "c"]) for r in y], k, 500, 1, k_range=K_RANGE).fit()
    assert list(named.predict(kk).index) == ["a", "b", "c"]


def test_refinement_moves_k_off_the_grid_and_never_lowers_the_likelihood():
    # a window generated at an operating point between grid points: the refined k is closer to it than the grid's
    rng = np.random.default_rng(5)
    y, k = records(rng, 30, degree=1, offset_sd=0.0, noise_sd=1.0, n=8000)
    res = FPMean(y, k, 4000, 1, k_range=K_RANGE, grid=5).fit()
    k0 = np.array([[3.3, 0.11]])
    sig = surface(k0, 1) + rng.normal(0, 0.01, (4000, 3))
    kh = res.estimate_k(sig)[0]
    assert np.abs(kh - k0[0]).max() < 0.05 * np.abs(k0[0]).max()
    grid = np.array(np.meshgrid(np.linspace(2, 10, 5), np.linspace(0, 0.3, 5))).reshape(2, -1).T
    assert not any(np.allclose(kh, g) for g in grid)


def test_record_covariance_keeps_the_record_spread_with_few_records_per_basis_function():
    # 12 records, degree 2 (9 basis functions): a covariance of the window residuals over windows - basis
    # functions takes the record offsets the surface absorbs for noise it has seen and is about half the true
    # spread; over records - basis functions it is unbiased (moved from tests/models/test_fp_hexacopter.py)
    rng = np.random.default_rng(3)
    var = []
    for _ in range(40):
        y, k = records(rng, 12, offset_sd=5.0, noise_sd=20.0)
        var.append(np.diag(FPMean(y, k, 500, 2, k_range=K_RANGE).fit().S))
    assert np.mean(var) == pytest.approx(5.0 ** 2 + 20.0 ** 2 / 500, rel=0.15)


def test_degree_needs_more_records_than_basis_functions():
    y, k = records(np.random.default_rng(0), 11)
    with pytest.raises(ValueError, match="9 basis functions and 3 channel.s. need at least 12 records"):
        FPMean(y, k, 500, 2)
    FPMean(y + y[:1], np.vstack([k, k[:1] + 0.01]), 500, 2)


def test_save_load_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(2)
    y, k = records(rng, 12, n=1200)
    idx = pd.timedelta_range(0, periods=1200, freq="10ms")
    frames = [pd.DataFrame(v, index=idx, columns=["roll_c", "pitch_c", "yaw_c"]) for v in y]
    res = FPMean(frames, pd.DataFrame(k, columns=["speed", "payload"]), "4s", 1, grid=7).fit()
    back = load(res.save(tmp_path / "trim"))
    assert isinstance(back, FPMeanResults)
    assert back.model.window == 400 and back.model.grid == 7 and back.model.k_names == ["speed", "payload"]
    np.testing.assert_array_equal(back.params2d, res.params2d)
    np.testing.assert_array_equal(back.S, res.S)
    pd.testing.assert_series_equal(back.loglike(frames[3]), res.loglike(frames[3]))
    assert repr(back) == repr(res)


def test_kinds_in_kinds_out_names_kept():
    xr = pytest.importorskip("xarray")
    rng = np.random.default_rng(4)
    y, k = records(rng, 12, n=1000)
    idx = pd.timedelta_range(0, periods=1000, freq="10ms")
    names = ["a", "b", "c"]
    frames = [pd.DataFrame(v, index=idx, columns=names) for v in y]
    res = FPMean(frames, pd.DataFrame(k, columns=["speed", "payload"]), 250, 1).fit()
    plain = FPMean(y, k, 250, 1).fit()
    np.testing.assert_array_equal(res.params.to_numpy(), plain.params)
    assert list(res.params.columns) == names and list(res.bse.index) == ["P0,0", "P0,1", "P1,0", "P1,1"]
    # a named signal is matched by name, in any order
    sig = frames[0][["c", "a", "b"]]
    ll = res.loglike(sig)
    assert isinstance(ll, pd.Series) and list(ll.index) == list(idx[[0, 250, 500, 750]])
    np.testing.assert_array_equal(ll.to_numpy(), plain.loglike(y[0]))
    kh = res.estimate_k(sig, "1s")
    assert isinstance(kh, pd.DataFrame) and list(kh.columns) == ["speed", "payload"] and len(kh) == 8
    da = xr.DataArray(y[0], dims=("time", "channel"), coords={"time": np.arange(1000) / 100, "channel": names})
    q = res.statistic(da)
    assert isinstance(q, xr.DataArray) and q.dims == ("time",)
    np.testing.assert_array_equal(q.values, plain.statistic(y[0]))
    assert "Surface of a" in str(res.summary()) and "FPMeanResults(window=250" in repr(res)
    with pytest.raises(AttributeError, match="immutable"):
        res.S = 0


def test_bad_input_is_refused_naming_the_argument():
    rng = np.random.default_rng(6)
    y, k = records(rng, 7, n=1000)
    with pytest.raises(ValueError, match="y must be a list of records"):
        FPMean(y[0], k[:1], 250)
    with pytest.raises(ValueError, match="k must hold one operating point per record"):
        FPMean(y, k[:6], 250)
    with pytest.raises(ValueError, match=r"y\[2\] has 100 samples, fewer than window=250"):
        FPMean(y[:2] + [y[2][:100]] + y[3:], k, 250)
    with pytest.raises(ValueError, match=r"y\[1\] has 2 channel"):
        FPMean([y[0], y[1][:, :2]] + y[2:], k, 250)
    with pytest.raises(ValueError, match=r"y\[1\].*NaN"):
        FPMean([y[0], np.full((1000, 3), np.nan)] + y[2:], k, 250)
    with pytest.raises(ValueError, match="no record holds two windows"):
        FPMean(y, k, 600)
    with pytest.raises(TypeError, match="window must be an int"):
        FPMean(y, k, 2.5)
    with pytest.raises(ValueError, match="sampling frequency is unknown"):
        FPMean(y, k, "2s")
    idx100 = pd.timedelta_range(0, periods=1000, freq="10ms")
    frames = [pd.DataFrame(v, index=idx100) for v in y]
    frames[3] = pd.DataFrame(y[3], index=pd.timedelta_range(0, periods=1000, freq="20ms"))
    with pytest.raises(ValueError, match=r"y\[3\] is sampled at 50 Hz but y\[0\] at 100 Hz"):
        FPMean(frames, k, "2s")
    with pytest.raises(ValueError, match="grid must be >= 2"):
        FPMean(y, k, 250, grid=1)
    with pytest.raises(ValueError, match="basis"):
        FPMean(y, k, 250, basis="fourier")
    res = FPMean(y, k, 250, 1).fit()
    with pytest.raises(ValueError, match="signal has 100 samples, fewer than the model's window"):
        res.loglike(y[0][:100])
    with pytest.raises(ValueError, match="signal has 2 channel"):
        res.statistic(y[0][:, :2])
    with pytest.raises(ValueError, match="step must be >= 1"):
        res.estimate_k(y[0], 0)
    with pytest.raises(ValueError, match="signal contains .*NaN"):
        res.loglike(np.full((300, 3), np.nan))


def test_detect_and_identify_take_fp_mean_results():
    # the identification rule and the detector through the library's engines: identify ranks by the window's
    # log-likelihood, identify_windows' likelihood rule is its argmax, detect compares the statistic with a
    # calibrated EmpiricalThreshold (details in tests/test_identification_fp_mean.py)
    rng = np.random.default_rng(8)
    models = {c: FPMean(*records(rng, 20, offset_sd=0.5), 500, 1, k_range=K_RANGE).fit() for c in ("a", "b")}
    y, _ = records(rng, 1, offset_sd=0.5)
    ident = tsfdi.identify(y[0][:500], models)
    lls = {c: float(m.loglike(y[0][:500])[0]) for c, m in models.items()}
    assert ident.ranking == tuple(sorted(lls, key=lambda c: -lls[c]))


def test_a_signal_changed_in_place_is_searched_again():
    # the results keep the last signal's profile (statistic, loglike and estimate_k search k once): keyed by the
    # signal's values, so a signal changed in place between two calls is not answered from the previous search
    rng = np.random.default_rng(9)
    y, k = records(rng, 12, n=1000)
    res, fresh = FPMean(y, k, 250, 1).fit(), FPMean(y, k, 250, 1).fit()
    sig = y[0].copy()
    before = res.loglike(sig)
    sig[:, 0] += 30.0
    after = res.loglike(sig)
    assert not np.allclose(before, after)
    np.testing.assert_array_equal(after, fresh.loglike(sig))
    np.testing.assert_array_equal(res.estimate_k(sig), fresh.estimate_k(sig))
    assert res.loglike(sig, 125).shape == (7,)
    out = res.statistic(sig)
    out[:] = 0.0                               # the caller's array is a copy
    assert (res.statistic(sig) > 0).all()

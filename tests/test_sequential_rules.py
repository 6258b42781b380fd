"""Sequential decisions in the windowed engine, evaluate, Monitor and the command line (issue 33, part 2)."""

import numpy as np
import pytest
from scipy import stats

import tsfdi
from tsfdi.windows import ResidualWindows


def _models(rng):
    x = rng.standard_normal((600, 2))
    y = x.copy()
    y[1:] += 0.6 * y[:-1]
    return x, {"a": tsfdi.VAR(x, 2).fit(), "b": tsfdi.VAR(y, 3).fit()}


def test_engine_per_sample_loglik_is_the_gaussian_logpdf_and_the_windows_mean():
    rng = np.random.default_rng(3)
    x, models = _models(rng)
    rw = ResidualWindows(models).fit(x)
    ll = rw.loglik()
    assert ll.shape == (600 - 3, 2)
    for j, (name, res) in enumerate(models.items()):
        e = np.asarray(res.residuals(x))[3 - res.lags:]
        np.testing.assert_allclose(ll[:, j], stats.multivariate_normal(np.zeros(2), res.sigma).logpdf(e), rtol=1e-10)
    ws = rw.statistics(tsfdi.LjungBox(lags=5), window=100, step=40)
    for w, s in enumerate(ws.starts):
        np.testing.assert_allclose(ws.loglik[w], ll[s:s + 97].mean(axis=0), rtol=1e-12)
    np.testing.assert_array_equal(rw.loglik(common=10), ll[7:])


def test_engine_loglik_refuses_bad_common_and_an_unfitted_engine():
    rng = np.random.default_rng(4)
    x, models = _models(rng)
    with pytest.raises(ValueError, match="not fitted"):
        ResidualWindows(models).loglik()
    rw = ResidualWindows(models).fit(x)
    with pytest.raises(ValueError, match="common"):
        rw.loglik(common=2)           # below the largest order: model "b" has no residual there
    with pytest.raises(ValueError, match="common"):
        rw.loglik(common=600)

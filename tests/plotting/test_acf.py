"""plot_acf: values against statsmodels, the band, the vector grid, data kinds."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from statsmodels.tsa.stattools import acf, ccf

import tsfdi
from tsfdi.plotting.acf import correlations
from tests.conftest import as_kind


def test_correlations_match_statsmodels():
    x = np.random.default_rng(0).standard_normal((400, 3)).cumsum(0)
    r = correlations(x, 15)
    for i in range(3):
        np.testing.assert_allclose(r[:, i, i], acf(x[:, i], nlags=15), rtol=1e-10)
    np.testing.assert_allclose(r[:, 0, 2], ccf(x[:, 0], x[:, 2], adjusted=False)[:16], rtol=1e-10)


def test_scalar_plot_has_band(kind):
    e = np.random.default_rng(1).standard_normal(900)
    fig = tsfdi.plot_acf(as_kind(e, kind), lags=20, alpha=0.01)
    (ax,) = fig.axes
    band = ax.collections[-1].get_paths()[0].vertices[:, 1]
    np.testing.assert_allclose(band.max(), stats.norm.ppf(0.995) / 30, rtol=1e-12)


def test_vector_grid(kind):
    e = np.random.default_rng(2).standard_normal((500, 3))
    fig = tsfdi.plot_acf(as_kind(e, kind, channels=["roll", "pitch", "yaw"]), lags=10)
    assert len(fig.axes) == 9
    titles = [a.get_title() for a in fig.axes]
    a, b = ("roll", "pitch") if kind != "numpy" else ("y0", "y1")
    assert f"ACF {a}" in titles and f"CCF {a} vs {b}(t-k)" in titles


def test_bad_arguments():
    e = np.random.default_rng(2).standard_normal((500, 2))
    with pytest.raises(ValueError, match="alpha"):
        tsfdi.plot_acf(e, 10, alpha=1.5)
    with pytest.raises(ValueError, match="lags must be <= 499"):
        tsfdi.plot_acf(e, 500)
    import matplotlib.pyplot as plt

    _, ax = plt.subplots()
    with pytest.raises(ValueError, match=r"ax must be .* \(2, 2\) array"):
        tsfdi.plot_acf(e, 10, ax=ax)

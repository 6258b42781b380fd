"""The compiled rolling variance of tsfdi._data (issue 36: running sums read at the window edges instead of two
prefix-sum arrays along axis 0): every window's variance as numpy computes it, for any window, step and shape."""

import numpy as np
import pytest

from tsfdi._data import rolling_variance


@pytest.mark.parametrize("n, k, window, step", [(500, 3, 100, 10), (40, 1, 2, 1), (50, 2, 50, 7), (300, 4, 17, 3),
                                                (20, 1, 20, 100), (7, 2, 3, 5), (1000, 3, 333, 1)])
def test_rolling_variance_equals_numpy_per_window(n, k, window, step):
    rng = np.random.default_rng(n + k)
    x = rng.standard_normal((n, k)) * np.arange(1, k + 1) + 50.0
    x[n // 3: n // 3 + window // 2 + 1, 0] = 7.0          # a flat stretch: variance 0 in the windows inside it
    starts = range(0, n - window + 1, min(step, n))
    ref = np.array([x[a:a + window].var(axis=0) for a in starts])
    out = rolling_variance(x, window, step)
    assert out.shape == ref.shape and out.dtype == np.float64
    np.testing.assert_allclose(out, ref, rtol=1e-9, atol=1e-11 * ref.max())
    assert (out >= 0).all()
    np.testing.assert_allclose(rolling_variance(x[:, 0], window, step), ref[:, :1], rtol=1e-9,
                               atol=1e-11 * ref.max())


def test_rolling_variance_overflow_is_not_silent():
    """Squares that overflow (finite values near 1e200) give the NaN windows numpy's prefix sums gave, never a
    silent variance of 0."""
    x = np.array([1e200, -1e200, 1e200, 3.0, 1.0, 2.0])[:, None]
    with np.errstate(over="ignore", invalid="ignore"):
        c = x - x.mean(axis=0)
        s1, s2 = np.r_[[[0.0]], np.cumsum(c, axis=0)], np.r_[[[0.0]], np.cumsum(c * c, axis=0)]
        m = (s1[2:] - s1[:-2]) / 2
        ref = np.maximum((s2[2:] - s2[:-2]) / 2 - m * m, 0.0)
        out = rolling_variance(x, 2)
    assert np.isnan(ref[:3, 0]).all()
    np.testing.assert_array_equal(out, ref)

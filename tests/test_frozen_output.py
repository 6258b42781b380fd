"""frozen_output: the per-sensor self-check for a frozen output (issue 35, Benchmark 2): exact flags on a frozen
stretch, the stated false-alarm bound on quantised noise, kinds and input checks."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from tsfdi.datasets.faults import inject_fault
from tsfdi.isolation import frozen_output


def test_flags_from_the_nth_sample_of_the_repeated_value():
    rng = np.random.default_rng(0)
    y = rng.normal(0, 0.1, 300)
    stuck, _ = inject_fault(y, "stuck", 0.0, 200)              # holds y[199] from sample 200 on
    flag = frozen_output(stuck, 10)
    assert flag.dtype == bool and flag.shape == (300,)
    # y[199], y[200], ... repeat one value: the 10th of them is sample 208
    np.testing.assert_array_equal(np.flatnonzero(flag), np.arange(208, 300))
    assert not frozen_output(y, 2).any()


def test_tolerance_is_the_spread_of_the_window():
    y = np.r_[0.0, 1.0, 1.25, 1.0, 1.125, 5.0]            # exact binary fractions: spreads 0.25, 0.25, 0.25
    np.testing.assert_array_equal(frozen_output(y, 3, tolerance=0.25), [0, 0, 0, 1, 1, 0])
    np.testing.assert_array_equal(frozen_output(y, 3, tolerance=0.2), [0, 0, 0, 0, 0, 0])
    np.testing.assert_array_equal(frozen_output(y, 4, tolerance=0.25), [0, 0, 0, 0, 1, 0])


def test_quantised_noise_stays_below_the_stated_bound():
    # Gaussian noise sigma on a moving signal, rounded to a resolution of sigma: bound (2 Delta / (sigma
    # sqrt(2 pi)))^(n - 1) = 0.798^(n - 1) per sample
    rng = np.random.default_rng(1)
    m, sigma, delta = 400_000, 1.0, 1.0
    y = np.round((np.sin(np.arange(m) / 50.0) + rng.normal(0, sigma, m)) / delta) * delta
    for n in (2, 3, 5):
        rate = frozen_output(y, n)[n - 1:].mean()
        bound = (2 * delta / (sigma * np.sqrt(2 * np.pi))) ** (n - 1)
        assert 0 < rate < bound
    # an unquantised noisy output never repeats
    assert not frozen_output(rng.normal(0, 1e-6, 10_000), 2).any()


@pytest.mark.parametrize("kind", ["numpy", "series", "dataarray"])
def test_kinds_and_time_span(kind):
    t = np.arange(100) / 50.0
    y = np.r_[np.arange(60) * 0.1, np.full(40, 6.0)]
    if kind == "numpy":
        out = frozen_output(y, "0.2s", fs=50.0)
    elif kind == "series":
        out = frozen_output(pd.Series(y, index=pd.Index(t, name="time"), name="alt"), "0.2s")
        assert isinstance(out, pd.Series) and out.index.equals(pd.Index(t, name="time")) and out.name == "alt"
    else:
        out = frozen_output(xr.DataArray(y, dims="time", coords={"time": t}), "0.2s")
        assert isinstance(out, xr.DataArray) and np.array_equal(out["time"], t)
    # the repeated value 6.0 starts at sample 60; the 10th sample of it (0.2 s at 50 Hz) is sample 69
    np.testing.assert_array_equal(np.flatnonzero(np.asarray(out)), np.arange(69, 100))


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"window": 1}, ValueError, "window"),
    ({"window": 101}, ValueError, "window must be <= the length of signal"),
    ({"window": 2.5}, TypeError, "window"),
    ({"window": "1s"}, ValueError, "sampling frequency"),
    ({"window": 5, "tolerance": -0.1}, ValueError, "tolerance"),
])
def test_bad_input_names_the_argument(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        frozen_output(np.arange(100.0), **kwargs)


def test_non_finite_and_vector_signals_are_refused():
    with pytest.raises(ValueError, match="signal"):
        frozen_output(np.r_[np.arange(10.0), np.nan], 3)
    with pytest.raises(ValueError, match="signal"):
        frozen_output(np.zeros((10, 2)), 3)

"""Shared test helpers: the three data kinds, the location of ../shared/data, the synthetic 4-state data set."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
import pytest
import xarray as xr
from _synthetic_fdi import FS, dataset
from hypothesis import HealthCheck, settings

import tsfdi

matplotlib.use("Agg")

# property-based tests (tests/property): a fixed, derandomised profile for CI and the default run, and a longer
# random one for local runs: ``HYPOTHESIS_PROFILE=long pytest tests/property``
settings.register_profile("ci", derandomize=True, max_examples=60, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile("long", max_examples=2000, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

#: ../shared next to the repository (CI has it there too); tests that need it fail loudly if it is missing
SHARED = Path(__file__).resolve().parents[1].parent / "shared"

KINDS = ("numpy", "pandas", "xarray")


def as_kind(values: np.ndarray, kind: str, channels: list[str] | None = None, name: str = "y"):
    """Wrap a (n,) or (n, s) array as numpy, pandas (DatetimeIndex at 100 Hz) or xarray (time in s)."""
    values = np.asarray(values)
    n = values.shape[0]
    if kind == "numpy":
        return values
    if values.ndim == 2 and channels is None:
        channels = [f"{name}{i}" for i in range(values.shape[1])]
    if kind == "pandas":
        index = pd.date_range("2024-01-01", periods=n, freq="10ms", name="time")
        if values.ndim == 1:
            return pd.Series(values, index=index, name=name)
        return pd.DataFrame(values, index=index, columns=channels)
    time = np.arange(n) / 100.0
    if values.ndim == 1:
        return xr.DataArray(values, dims=("time",), coords={"time": time}, name=name)
    return xr.DataArray(values, dims=("time", "channel"), coords={"time": time, "channel": channels}, name=name)


def to_numpy(obj) -> np.ndarray:
    return np.asarray(obj.values if hasattr(obj, "values") else obj)


def assert_kind(obj, kind: str, ndim: int) -> None:
    """The result has the caller's kind and dimensionality."""
    expected = {"numpy": np.ndarray, "pandas": pd.Series if ndim == 1 else pd.DataFrame, "xarray": xr.DataArray}
    assert isinstance(obj, expected[kind]), type(obj)
    assert np.ndim(to_numpy(obj)) == ndim


@pytest.fixture(params=KINDS)
def kind(request) -> str:
    return request.param


@pytest.fixture(scope="session")
def shared_data() -> Path:
    path = SHARED / "data"
    if not path.is_dir():
        raise FileNotFoundError(f"shared data folder missing: {path} (tests need ../shared/data next to the repo)")
    return path


# the synthetic 4-state data set of test_baselines.py and test_evaluation.py, fitted once per module
@pytest.fixture(scope="module")
def synthetic():
    """5 records per state, 40 s at 100 Hz, failure at 10 s."""
    return dataset(5, 4000, 1000, np.random.default_rng(5))


@pytest.fixture(scope="module")
def fitted(synthetic):
    recs, states, ft = synthetic
    b = tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, max_lags=6,
                            var_max_lags=6, steady_window="5s")
    return b

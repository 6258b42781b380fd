"""Shared test helpers: the three data kinds, ../shared/data (skipped when missing), the synthetic 4-state data set."""

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

#: ../shared next to the repository: the fuller real data copies (not part of a clone; CI has them). A test that
#: needs them takes the ``shared_data`` fixture (or ``shared_alfa`` / ``shared_crazypad`` / ``shared_px4``): it is
#: skipped, with the missing folder in the reason, on a clone without them, and fails when REQUIRE_SHARED is "1"
SHARED = Path(__file__).resolve().parents[1].parent / "shared"
REQUIRE_SHARED = "TSFDI_REQUIRE_SHARED"

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


def _shared(*parts: str) -> Path:
    """``../shared/data/<parts>``; skip the test when that folder is missing (fail it when
    ``TSFDI_REQUIRE_SHARED=1``), the folder named in the reason."""
    path = SHARED.joinpath("data", *parts)
    if path.is_dir():
        return path
    name = "/".join(("../shared/data", *parts))
    reason = f"needs the shared data folder {name} next to the repository ({path} is missing)"
    if os.environ.get(REQUIRE_SHARED) == "1":
        pytest.fail(f"{reason}; {REQUIRE_SHARED}=1 requires it", pytrace=False)
    pytest.skip(reason)


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The folder ``../shared/data`` (tests that need one of its sub-folders take the fixture of that one)."""
    return _shared()


@pytest.fixture(scope="session")
def shared_alfa() -> Path:
    """``../shared/data/alfa``: the processed ALFA copy."""
    return _shared("alfa")


@pytest.fixture(scope="session")
def shared_crazypad() -> Path:
    """``../shared/data/crazypad``: the CrazyPAD copy (``flights.csv``, ``controller/``, ``motor/``)."""
    return _shared("crazypad")


@pytest.fixture(scope="session")
def shared_px4() -> Path:
    """``../shared/data/px4``: the PX4 ULog files."""
    return _shared("px4")


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

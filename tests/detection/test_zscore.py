"""ZScore: Welford running statistics, alarms, nominal false-alarm rate, data kinds, bad input."""

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy import stats

from tsfdi.detection.decision import Decision
from tsfdi.detection.zscore import ZScore


def test_zscores_match_direct_computation():
    rng = np.random.default_rng(0)
    x = rng.standard_normal(300) * 2.0 + 1.0
    z = ZScore(burn_in=20, freeze_on_alarm=False).zscores(x)
    assert np.isnan(z[:20]).all()
    for t in (20, 57, 299):
        expected = (x[t] - x[:t].mean()) / x[:t].std(ddof=1)
        np.testing.assert_allclose(z[t], expected, rtol=1e-11)


def test_alpha_is_gaussian_two_sided_tail():
    np.testing.assert_allclose(ZScore().alpha, 2 * stats.norm.sf(4.5), rtol=1e-12)
    np.testing.assert_allclose(ZScore(3.0).alpha, 2 * stats.norm.sf(3.0), rtol=1e-12)


def test_detects_a_spike_and_freezes():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(1000)
    x[700:] += 8.0
    d = ZScore().test(x)
    assert isinstance(d, Decision) and d.reject
    assert d.details["first_alarm"][0] == 700
    # frozen statistics: every shifted sample keeps alarming
    assert np.all(np.abs(d.details["z"][700:]) > 4.5)
    free = ZScore(freeze_on_alarm=False).test(x)
    assert free.details["first_alarm"][0] == 700
    assert len(free.details["alarms"][0]) < len(d.details["alarms"][0])


def test_false_alarm_rate_monte_carlo():
    # threshold 3: per-sample rate 2.7e-3; 200 records x 2000 samples after burn-in
    rng = np.random.default_rng(2)
    x = rng.standard_normal((2050, 200))
    test = ZScore(3.0, freeze_on_alarm=False)
    d = test.test(x)
    n = 2000 * 200
    count = sum(len(a) for a in d.details["alarms"])
    p = test.alpha
    # estimated-variance Z is t-like: allow the binomial 4-sigma band around n p, plus 15 % for the t tails
    assert abs(count - n * p) < 4 * np.sqrt(n * p) + 0.15 * n * p
    assert d.statistic.shape == (200,) and d.reject


@pytest.mark.parametrize("kind", ["numpy", "pandas", "xarray"])
def test_data_kinds(kind):
    rng = np.random.default_rng(3)
    x = rng.standard_normal(500)
    x[400] = 10.0
    index = pd.date_range("2021-01-01", periods=500, freq="50ms")
    data = {"numpy": x, "pandas": pd.Series(x, index=index, name="r"),
            "xarray": xr.DataArray(x, dims="time", coords={"time": index})}[kind]
    d = ZScore().test(data)
    assert d.reject and d.details["first_alarm"][0] == 400
    z = d.details["z"]
    if kind == "pandas":
        assert isinstance(z, pd.Series) and d.details["first_alarm_label"][0] == index[400]
    elif kind == "xarray":
        assert isinstance(z, xr.DataArray) and d.details["first_alarm_label"][0] == index[400]
    else:
        assert isinstance(z, np.ndarray) and d.details["first_alarm_label"][0] == 400
    np.testing.assert_allclose(np.asarray(z), ZScore().zscores(x), equal_nan=True)


def test_bad_input():
    with pytest.raises(ValueError, match="threshold"):
        ZScore(0.0)
    with pytest.raises(TypeError, match="threshold"):
        ZScore("4")
    with pytest.raises(ValueError, match="burn_in"):
        ZScore(burn_in=1)
    with pytest.raises(TypeError, match="freeze_on_alarm"):
        ZScore(freeze_on_alarm=1)
    with pytest.raises(ValueError, match="resid is too short"):
        ZScore(burn_in=50).test(np.ones(30))
    x = np.random.default_rng(0).standard_normal(100)
    x[5] = np.nan
    with pytest.raises(ValueError, match="resid"):
        ZScore().test(x)

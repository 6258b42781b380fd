"""OnlineDetector: several pairs at once, first alarms with time stamps, streaming GLRT, data kinds."""

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy.signal import lfilter

from tsfdi.detection.glrt import GLRT
from tsfdi.models.recursive import RecursiveARX
from tsfdi.monitoring import OnlineDetector


def two_pairs(n=4000, change=3000, seed=0, bias=0.0, gain=0.0):
    """Pair A: y = 0.7 y[-1] + u + e; pair B: y = 0.5 y[-1] + 0.8 u + e with a fault in B from ``change``."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 2))
    e = 0.1 * rng.standard_normal((n, 2))
    ya = lfilter([1.0], [1.0, -0.7], u[:, 0] + e[:, 0])
    xb = 0.8 * u[:, 1] + e[:, 1]
    xb[change:] += bias + gain * u[change:, 1]
    yb = lfilter([1.0], [1.0, -0.5], xb)
    return np.column_stack([ya, yb]), u


def test_first_alarm_per_pair_and_overall():
    y, u = two_pairs(gain=1.0)
    det = OnlineDetector(["a", "b"], na=1, nb=1)
    out = det.run(y, u)
    fa = out.first_alarms
    assert list(fa.index) == ["a", "b"]
    assert fa.loc["a", "position"] == -1 and fa.loc["a", "time"] is None
    assert 3000 <= fa.loc["b", "position"] <= 3010
    assert out.first_alarm == fa.loc["b", "position"] and out.first_alarm_pair == "b"
    assert out.first_alarm_time == out.first_alarm  # numpy input: positions
    assert (fa["armed_at"] > 0).all() and (fa["armed_at"] < 1000).all()
    assert not out.alarm[:3000].any()


def test_glrt_catches_a_small_bias_the_zscore_misses():
    # a bias of 1.5 sigma: single samples rarely pass 4.5 sigma, the windowed GLRT accumulates evidence
    y, u = two_pairs(bias=0.15, seed=3)
    z_only = OnlineDetector(["a", "b"], na=1, nb=1, glrt=None).run(y, u)
    both = OnlineDetector(["a", "b"], na=1, nb=1, glrt=GLRT(window=20, alpha=1e-6)).run(y, u)
    fb = both.first_alarms.loc["b"]
    assert fb["source"] == "glrt" and 3000 <= fb["position"] <= 3040
    zpos = z_only.first_alarms.loc["b", "position"]
    assert zpos == -1 or zpos > fb["position"]
    # the GLRT values equal a batch GLRT on the armed, mean-corrected prediction errors
    m = RecursiveARX(1, 1, forgetting_factor=0.995, halt_on_alarm=True, nonfinite="skip")
    res = m.run(y[:, 1], u[:, 1])
    arm = int(np.argmax(res.variance_stable))
    sigma = np.sqrt(res.variance[arm])
    ref = GLRT(window=20, sigma=sigma).statistic(res.resid[arm + 1:] - res.mean[arm])
    np.testing.assert_allclose(np.asarray(both.glrt)[arm + 1:, 1], ref, rtol=1e-10)
    assert both.first_alarms.loc["b", "armed_at"] == arm + 1


def test_streaming_blocks_and_samples_agree():
    y, u = two_pairs(n=1500, change=1200, gain=1.0, seed=5)
    whole = OnlineDetector(2, na=1, nb=1).run(y, u)
    det = OnlineDetector(2, na=1, nb=1)
    det.run(y[:500], u[:500])
    det.run(y[500:900], u[500:900])
    last = det.run(y[900:], u[900:])
    pd.testing.assert_frame_equal(last.first_alarms, whole.first_alarms)
    step = OnlineDetector(2, na=1, nb=1)
    flags = np.array([step.update(y[t], u[t]) for t in range(len(y))])
    np.testing.assert_array_equal(flags, whole.alarm)
    pd.testing.assert_frame_equal(step.first_alarms, whole.first_alarms)
    assert step.nobs == 1500
    step.reset()
    assert step.nobs == 0 and (step.first_alarms["position"] == -1).all()


@pytest.mark.parametrize("kind", ["numpy", "pandas", "xarray"])
def test_data_kinds_and_timestamps(kind):
    y, u = two_pairs(n=3500, change=3000, gain=1.0, seed=7)
    index = pd.date_range("2018-07-18 19:56:50", periods=len(y), freq="50ms")
    if kind == "pandas":
        yy, uu = pd.DataFrame(y, index=index, columns=["a", "b"]), pd.DataFrame(u, index=index)
    elif kind == "xarray":
        yy = xr.DataArray(y, dims=("time", "pair"), coords={"time": index})
        uu = xr.DataArray(u, dims=("time", "pair"), coords={"time": index})
    else:
        yy, uu = y, u
    out = OnlineDetector(["a", "b"], na=1, nb=1).run(yy, uu)
    ref = OnlineDetector(["a", "b"], na=1, nb=1).run(y, u)
    assert out.first_alarm == ref.first_alarm and out.first_alarm_pair == ref.first_alarm_pair
    assert out.first_alarm == out.first_alarms["position"][out.first_alarms["position"] >= 0].min()
    assert 3000 <= out.first_alarms.loc["b", "position"] <= 3010
    np.testing.assert_array_equal(np.asarray(out.zscore), np.asarray(ref.zscore))
    if kind == "numpy":
        assert isinstance(out.zscore, np.ndarray)
    else:
        assert out.first_alarm_time == index[out.first_alarm]
        assert isinstance(out.glrt, pd.DataFrame if kind == "pandas" else xr.DataArray)


def test_nonfinite_and_bad_input():
    y, u = two_pairs(n=1000, change=900, gain=1.0)
    y[100, 0] = np.nan
    out = OnlineDetector(2, na=1, nb=1).run(y, u)
    assert out.first_alarms["position"].iloc[1] >= 900
    assert OnlineDetector(2, na=1, nb=1).models[0].nonfinite == "skip"
    det = OnlineDetector(2, na=1, nb=1)
    det.run(y, u)
    assert det.models[0].n_skipped == 1
    with pytest.raises(ValueError, match="NaN"):
        OnlineDetector(2, na=1, nb=1, nonfinite="raise").run(y, u)
    with pytest.raises(ValueError, match="one column per pair"):
        OnlineDetector(3).run(y, u)
    with pytest.raises(ValueError, match="same length"):
        OnlineDetector(2).run(y, u[:-1])
    with pytest.raises(TypeError, match="pairs"):
        OnlineDetector(1.5)
    with pytest.raises(ValueError, match="distinct"):
        OnlineDetector(["a", "a"])
    with pytest.raises(TypeError, match="glrt"):
        OnlineDetector(2, glrt="yes")
    with pytest.raises(ValueError, match="forgetting_factor"):
        OnlineDetector(2, forgetting_factor=1.5)
    with pytest.raises(ValueError, match="na"):
        OnlineDetector(2, na=-1)

"""The windowed engine matches a named signal to the models' channels by name (issue 19)."""

import numpy as np
import pandas as pd
import pytest

import tsfdi


@pytest.fixture(scope="module")
def named():
    rng = np.random.default_rng(0)
    y = pd.DataFrame(rng.standard_normal((2000, 3)), columns=["roll", "pitch", "yaw"])
    x = y.iloc[:600].copy()
    x["pitch"] *= 3.0
    return {"a": tsfdi.VAR(y, 2).fit(), "b": tsfdi.VAR(1.1 * y, 2).fit()}, y, x


def test_reordered_signal_gives_identical_statistics(named):
    models, _, x = named
    for test in (tsfdi.FTest(), tsfdi.LjungBox(lags=5), tsfdi.MeanTest()):
        ws = tsfdi.ResidualWindows(models).fit(x).statistics(test, window=200, step=100)
        ws2 = tsfdi.ResidualWindows(models).fit(x[["yaw", "pitch", "roll"]]).statistics(test, window=200, step=100)
        assert ws.channels == ws2.channels == ("roll", "pitch", "yaw")
        np.testing.assert_array_equal(ws.statistic, ws2.statistic)
        np.testing.assert_array_equal(ws.reject, ws2.reject)
        np.testing.assert_array_equal(ws.loglik, ws2.loglik)
    ws = tsfdi.ResidualWindows(models).fit(x[["yaw", "pitch", "roll"]]).statistics(tsfdi.FTest(), window=200, step=100)
    assert ws.channel_reject[:, :, 1].all() and not ws.channel_reject[:, :, 0].any()   # the fault stays on pitch


def test_missing_extra_channel_and_mixed_orders_are_refused(named):
    models, y, x = named
    with pytest.raises(ValueError, match=r"missing channel\(s\) \['yaw'\]"):
        tsfdi.ResidualWindows(models).fit(x[["roll", "pitch"]].assign(speed=1.0))
    with pytest.raises(ValueError, match="share one channel order"):
        tsfdi.ResidualWindows({"a": models["a"], "c": tsfdi.VAR(y[["yaw", "roll", "pitch"]], 2).fit()})
    # positional arrays still work, in the models' order
    ws = tsfdi.ResidualWindows(models).fit(x.to_numpy()).statistics(tsfdi.FTest(), window=200, step=100)
    assert ws.channel_reject[:, :, 1].all()


def test_per_channel_and_joint_tests_of_one_engine_are_refused_by_name(named):
    # a mapping that tests one model per channel (3 statistics per window) and the other jointly (1) cannot share
    # the arrays of WindowStatistics: a ValueError naming the model, not numpy's stacking error
    models, _, x = named
    tests = {"a": tsfdi.LjungBox(lags=5), "b": tsfdi.LjungBox(lags=5, multivariate="hosking")}
    with pytest.raises(ValueError, match="3 and 1 statistics per window \\(model 'b'\\)"):
        tsfdi.ResidualWindows(models).fit(x).statistics(tests, window=200, step=100)

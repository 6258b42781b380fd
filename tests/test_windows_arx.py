"""Input-output (ARX, VARX, FP-ARX point) models in the windowed engine: ResidualWindows and identify_windows
with ``u``."""

import numpy as np
import pandas as pd
import pytest
import scipy.signal as sps
import xarray as xr

import tsfdi
from tsfdi.models import VARX
from tsfdi.windows import ResidualWindows


def simulate(gain, n, rng):
    """Output of two inputs through a plant whose first input's gain is ``gain`` (a loss of effectiveness)."""
    u = rng.standard_normal((n, 2))
    y = (sps.lfilter([0, 0.8 * gain, 0.3], [1, -0.5], u[:, 0]) + sps.lfilter([0, 0, 0.5], [1, -0.5], u[:, 1])
         + 0.1 * rng.standard_normal(n))
    return y, u


@pytest.fixture(scope="module")
def arx():
    rng = np.random.default_rng(2032)
    # nb = 3, nk = 1: the input lags reach 3 samples back, beyond na = 1 (the first residual is at max_lag = 3)
    return {name: tsfdi.ARX(*simulate(g, 3000, rng), 1, 3, nk=1).fit() for name, g in (("healthy", 1.0),
                                                                                       ("loss", 0.5))}


@pytest.fixture(scope="module")
def record():
    rng = np.random.default_rng(7)
    y0, u0 = simulate(1.0, 1200, rng)
    y1, u1 = simulate(0.5, 1200, rng)
    return np.r_[y0, y1], np.r_[u0, u1]


def check_windows_equal_identify(y, u, models, test):
    """identify_windows of an input-output model set equals identify on each window (400 samples, step 200)."""
    wi = tsfdi.identify_windows(y, models, test, window=400, step=200, u=u)
    if isinstance(test, tsfdi.FTest):        # the loss of gain changes the residual variance (not its whiteness)
        assert wi.labels[0] == "healthy" and wi.labels[-1] == "loss"
    for w, (s, e) in enumerate(zip(wi.starts, wi.stops)):
        one = tsfdi.identify(y[s:e], models, test, u=u[s:e])
        assert wi[w].label == one.label
        for name in models:
            np.testing.assert_allclose(wi[w].decisions[name].statistic, one.decisions[name].statistic, rtol=1e-9)


@pytest.mark.parametrize("test", [tsfdi.FTest(1e-3), tsfdi.LjungBox(10, 1e-3), tsfdi.GLRT(alpha=1e-3)])
def test_windows_equal_identify_on_each_window(arx, record, test):
    check_windows_equal_identify(*record, arx, test)


def test_residuals_are_the_record_residuals_windowed(arx, record):
    """The engine's residuals are ``results.residuals(y, u)`` of the record, window by window (no re-filtering)."""
    y, u = record
    ws = ResidualWindows(arx).fit(y, u=u).statistics(tsfdi.FTest(1e-3), window=300, step=150)
    for j, (name, res) in enumerate(arx.items()):
        e = res.residuals(y, u)
        p = res.model.max_lag
        assert ws.nobs[j] == 300 - p == 297
        for w, s in enumerate(ws.starts):
            want = tsfdi.FTest(1e-3).test(e[s:s + 300 - p], **tsfdi.FTest().reference(res)).statistic
            np.testing.assert_allclose(ws.statistic[w, j], want, rtol=1e-12)
    # the per-sample log-likelihood is that of those residuals under sigma2
    ll = ResidualWindows(arx).fit(y, u=u).loglik()
    e = arx["loss"].residuals(y, u)
    s2 = arx["loss"].sigma2
    np.testing.assert_allclose(ll[:, 1], -0.5 * (np.log(s2) + e ** 2 / s2 + np.log(2 * np.pi)))


def test_pandas_and_xarray_inputs_matched_by_name(record):
    rng = np.random.default_rng(3)
    yt, ut = simulate(1.0, 3000, rng)
    idx = pd.RangeIndex(3000, name="time") / 100.0
    fit_u = pd.DataFrame(ut, columns=["cmd_a", "cmd_b"], index=idx)
    res = tsfdi.ARX(pd.Series(yt, index=idx, name="gyro"), fit_u, 1, 3, nk=1).fit()
    y, u = record
    t = pd.Index(np.arange(len(y)) / 100.0, name="time")
    ys = pd.Series(y, index=t, name="gyro")
    us = pd.DataFrame(u[:, ::-1], columns=["cmd_b", "cmd_a"], index=t)          # columns in another order
    want = tsfdi.identify_windows(y, {"h": res}, tsfdi.FTest(1e-3), window=400, step=200, u=u)
    got = tsfdi.identify_windows(ys, {"h": res}, tsfdi.FTest(1e-3), window="4s", step="2s", u=us)
    np.testing.assert_allclose(got.statistic, want.statistic, rtol=1e-12)
    assert got.to_frame()["start"].iloc[1] == 2.0
    ux = xr.DataArray(u[:, ::-1], dims=("time", "channel"), coords={"time": t.values, "channel": ["cmd_b", "cmd_a"]})
    yx = xr.DataArray(y, dims=("time",), coords={"time": t.values}, name="gyro")
    got = tsfdi.identify_windows(yx, {"h": res}, tsfdi.FTest(1e-3), window=400, step=200, u=ux)
    np.testing.assert_allclose(got.statistic, want.statistic, rtol=1e-12)
    with pytest.raises(ValueError, match=r"u: missing channel\(s\) \['cmd_a'\]"):
        tsfdi.identify_windows(ys, {"h": res}, window=400, u=us.rename(columns={"cmd_a": "cmd_c"}))
    with pytest.raises(ValueError, match="signal and u have different indexes"):
        tsfdi.identify_windows(ys, {"h": res}, window=400, u=us.set_axis(t + 0.005))


def test_named_inputs_in_each_models_own_order(record):
    """Models fitted on the same named inputs in different column orders: each takes ``u`` by name."""
    rng = np.random.default_rng(5)
    fits = [simulate(g, 3000, rng) for g in (1.0, 0.5)]
    ab = tsfdi.ARX(fits[0][0], pd.DataFrame(fits[0][1], columns=["a", "b"]), 1, 3, nk=1).fit()
    ba = tsfdi.ARX(fits[1][0], pd.DataFrame(fits[1][1][:, ::-1], columns=["b", "a"]), 1, 3, nk=1).fit()
    y, u = record
    un = pd.DataFrame(u, columns=["a", "b"])
    ws = ResidualWindows({"ab": ab, "ba": ba}).fit(y, u=un).statistics(tsfdi.FTest(1e-3), window=400, step=400)
    for j, res in enumerate((ab, ba)):
        e = res.residuals(y, un)
        want = [tsfdi.FTest(1e-3).test(e[s:s + 397], **tsfdi.FTest().reference(res)).statistic for s in ws.starts]
        np.testing.assert_allclose(ws.statistic[:, j, 0], np.ravel(want), rtol=1e-12)
    assert ws.labels()[0] == 0 and ws.labels()[-1] == 1


def test_fp_arx_point_accepted(record):
    rng = np.random.default_rng(11)
    gains = [0.25, 0.5, 0.75, 1.0]
    recs = [simulate(g, 2000, rng) for g in gains]
    fp = tsfdi.models.FPARX([r[0] for r in recs], [r[1] for r in recs], pd.DataFrame({"gain": gains}), 1, 3,
                            nk=1).fit()
    models = {"healthy": fp.at(1.0), "half": fp.at(0.5)}
    y, u = record
    wi = tsfdi.identify_windows(y, models, tsfdi.FTest(1e-3), window=400, step=200, u=u)
    assert wi.labels[0] == "healthy" and wi.labels[-1] == "half"
    np.testing.assert_allclose(wi[2].decisions["half"].statistic,
                               tsfdi.identify(y[400:800], models, tsfdi.FTest(1e-3),
                                              u=u[400:800]).decisions["half"].statistic)


def test_input_refused_or_required(arx, record):
    y, u = record
    ar = {"healthy": tsfdi.AR(y[:1200], 3).fit()}
    with pytest.raises(TypeError, match="u is required"):
        tsfdi.identify_windows(y, arx, window=400)
    with pytest.raises(TypeError, match="u is required"):
        ResidualWindows(arx).fit(y)
    with pytest.raises(TypeError, match="u is only for input-output"):
        tsfdi.identify_windows(y, ar, window=400, u=u)
    with pytest.raises(TypeError, match="models mixes ARX"):
        tsfdi.identify_windows(y, {**arx, **ar}, window=400, u=u)
    with pytest.raises(ValueError, match="u has 2399 samples but signal has 2400"):
        tsfdi.identify_windows(y, arx, window=400, u=u[1:])
    with pytest.raises(ValueError, match=r"u has 1 channel\(s\) but the models were fitted with 2"):
        tsfdi.identify_windows(y, arx, window=400, u=u[:, 0])
    with pytest.raises(ValueError, match="u .*NaN"):
        tsfdi.identify_windows(y, arx, window=400, u=np.where(np.arange(len(y))[:, None] == 5, np.nan, u))
    one = tsfdi.ARX(y[:1200], u[:, :1][:1200], 1, 2).fit()
    with pytest.raises(ValueError, match="ARX models must share one set of inputs"):
        ResidualWindows({**arx, "one": one})


def simulate_two(gain, n, rng):
    """Two rates driven by two commands through a coupled plant; the first command's gain is ``gain``."""
    y, u = simulate(gain, n, rng)
    y2 = sps.lfilter([0, 0.4, 0.2], [1, -0.3], u[:, 1]) + 0.3 * np.r_[0, y[:-1]] + 0.1 * rng.standard_normal(n)
    return np.column_stack([y, y2]), u


@pytest.fixture(scope="module")
def varx():
    rng = np.random.default_rng(2033)
    # nb = 3, nk = 1: the input lags reach beyond lags = 1, as for the ARX models above
    return {name: VARX(*simulate_two(g, 3000, rng), 1, nb=3, nk=1).fit() for name, g in (("healthy", 1.0),
                                                                                              ("loss", 0.5))}


@pytest.mark.parametrize("test", [tsfdi.FTest(1e-3), tsfdi.LjungBox(10, 1e-3), tsfdi.MeanTest(1e-3)])
def test_varx_windows_equal_identify_on_each_window(varx, test):
    """VARX results (several outputs given the inputs) run through the windowed engine and identify exactly as ARX
    results: the windows equal ``identify`` on each window and the residuals are ``residuals(y, u)`` windowed."""
    rng = np.random.default_rng(8)
    parts = [simulate_two(g, 1200, rng) for g in (1.0, 0.5)]
    y, u = np.vstack([p[0] for p in parts]), np.vstack([p[1] for p in parts])
    check_windows_equal_identify(y, u, varx, test)
    ws = ResidualWindows(varx).fit(y, u=u).statistics(test, window=400, step=200)
    for j, (name, res) in enumerate(varx.items()):
        e = res.residuals(y, u)
        assert ws.nobs[j] == 400 - res.model.max_lag == 397
        for w, s in enumerate(ws.starts):
            want = test.test(e[s:s + 397], **test.reference(res)).statistic
            np.testing.assert_allclose(ws.statistic[w, j], want, rtol=1e-9)
    d = tsfdi.detect(y[:1200], varx["healthy"], tsfdi.FTest(1e-3), u=u[:1200])
    np.testing.assert_allclose(d.statistic, tsfdi.identify(y[:1200], {"h": varx["healthy"]}, tsfdi.FTest(1e-3),
                                                           u=u[:1200]).decisions["h"].statistic)
    with pytest.raises(TypeError, match="u is required: models\\['healthy'\\] is a VARX"):
        tsfdi.identify(y, varx, test)
    with pytest.raises(TypeError, match="models mixes ARX / VARX"):
        ResidualWindows({**varx, "var": tsfdi.VAR(y, 2).fit()})


def test_crazypad_rates_given_the_commands(shared_crazypad):
    """Real flights (CrazyPAD, drone E8): each gyro rate given the three commands (one ARX per axis, each axis at the
    Sidak share of alpha = 0.01), fitted on four normal logs. The windows of a time-indexed flight equal ``identify``
    on each window; the mean test flags most 2 s windows of a large M3 cut (which the attitude loop compensates; 11
    of 18 measured) and none of the normal log left out of the fit (``benchmarks/crazypad_controller.py`` measures
    this in full)."""
    from tsfdi.datasets import load_crazypad

    gyro = ["controller.r_roll", "controller.r_pitch", "controller.r_yaw"]
    cmd = ["controller.cmd_roll", "controller.cmd_pitch", "controller.cmd_yaw"]
    normal = load_crazypad(shared_crazypad, condition="normal_flight", drone="E8", columns=gyro + cmd)
    fit = [s for s in normal if s.attrs["log"] != "E8_log04"]
    held = [s for s in normal if s.attrs["log"] == "E8_log04"]
    cut = load_crazypad(shared_crazypad, condition="cut_propeller_M3_3.5mm_3mm_40.5mm", drone="E8",
                        columns=gyro + cmd)
    groups = [s.attrs["log"] for s in fit]
    W = int(round(2 * fit[0].attrs["fs"]))
    alpha = 1 - (1 - 0.01) ** (1 / 3)
    flagged = [False] * (len(held) + len(cut))
    for g in gyro:
        spec = tsfdi.ARX([s[g] for s in fit], [s[cmd] for s in fit], 8, 8, trend="c")
        res = spec.fit()
        test = tsfdi.MeanTest(alpha=alpha, threshold=tsfdi.ScaledChi2Threshold(alpha, min_windows=5, min_records=2))
        test.calibrate(spec.held_out_residuals(groups=groups), window=W, step=1)
        for i, s in enumerate(held + cut):
            rej = ~tsfdi.identify_windows(s[g], {"h": res}, test, window="2s", step="2s", u=s[cmd]).accepted[:, 0]
            flagged[i] = rej | flagged[i]
        seg = cut[0]
        wi = tsfdi.identify_windows(seg[g], {"h": res}, test, window=W, step=50, u=seg[cmd[::-1]])
        for w in (0, len(wi) - 1):
            a, b = wi.starts[w], wi.stops[w]
            one = tsfdi.identify(seg[g].iloc[a:b], {"h": res}, test, u=seg[cmd].iloc[a:b])
            np.testing.assert_allclose(wi[w].decisions["h"].statistic, one.decisions["h"].statistic, rtol=1e-9)
    assert not np.concatenate(flagged[:len(held)]).any()             # the held-out normal log: no alarm
    assert np.concatenate(flagged[len(held):]).mean() > 0.5          # the cut flights: most windows (11 of 18)


def test_monitor_takes_varx_models(varx):
    """Monitor with VARX baseline and fault models (it raised a raw KeyError 'baseline'): detects and identifies the
    loss, streamed equals batch, u required, input-output and AR / VAR models not mixed."""
    models = varx
    rng = np.random.default_rng(2034)
    parts = [simulate_two(g, 1500, rng) for g in (1.0, 0.5)]       # the loss from 15 s at 100 Hz
    y, u = np.vstack([p[0] for p in parts]), np.vstack([p[1] for p in parts])
    make = lambda: tsfdi.Monitor(models["healthy"], {"loss": models["loss"]}, window="5s", fs=100.0,  # noqa: E731
                                 test=tsfdi.FTest(alpha=1e-3), steady_window="5s",
                                 steady_thresholds=[3 * y[1500:, 0].var(), 3 * y[1500:, 1].var()])
    batch = make().run(y, u=u)
    assert 15.0 < batch.detection_time <= 20.0 and batch.label == "loss"
    mon = make()
    for a in range(0, len(y), 250):                                 # streamed block by block: the same events
        mon.update(y[a:a + 250], u=u[a:a + 250])
    assert mon.result().to_frame().equals(batch.to_frame())
    with pytest.raises(TypeError, match="u is required"):
        make().run(y)
    with pytest.raises(TypeError, match="mix input-output"):
        tsfdi.Monitor(models["healthy"], {"var": tsfdi.VAR(y, 2).fit()})

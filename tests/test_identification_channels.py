"""Channel safety (issue 19): a named signal is matched to the models by name in detect, identify, identify_windows,
Monitor and fit_baselines -- reordered channels give identical decisions, a missing or an extra channel raises
naming it, positional arrays still work."""

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from _synthetic_fdi import FS, record

import tsfdi
from tsfdi import VAR, LjungBox

CHANNELS = ["roll", "pitch", "yaw"]


def three(state, n, rng, failure=None):
    """The two-channel synthetic system plus an AR(1) third channel, as a DataFrame at 100 Hz."""
    x = record(state, n, rng, failure)
    e = rng.standard_normal(n + 100)
    yaw = np.zeros(n + 100)
    for t in range(1, n + 100):
        yaw[t] = 0.6 * yaw[t - 1] + e[t]
    index = pd.timedelta_range(0, periods=n, freq="10ms", name="time")
    return pd.DataFrame(np.column_stack([x, yaw[100:]]), index=index, columns=CHANNELS)


@pytest.fixture(scope="module")
def models():
    rng = np.random.default_rng(21)
    return {s: VAR(three(s, 6000, rng), 2).fit() for s in ("healthy", "f1", "f2")}


@pytest.fixture(scope="module")
def failure_record():
    return three("f1", 3000, np.random.default_rng(22), failure=1000)


def as_xarray(frame):
    return xr.DataArray(frame.to_numpy(), dims=("time", "channel"),
                        coords={"time": frame.index.total_seconds(), "channel": list(frame.columns)})


def same_decision(a, b):
    assert a.channels == b.channels == tuple(CHANNELS)
    for field in ("statistic", "threshold", "pvalue", "channel_reject"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert a.reject == b.reject and a.nobs == b.nobs


@pytest.mark.parametrize("kind", ["pandas", "xarray"])
@pytest.mark.parametrize("order", [["yaw", "roll", "pitch"], ["pitch", "yaw", "roll"]])
def test_reordered_channels_give_identical_decisions(models, failure_record, kind, order):
    wrap = (lambda f: f) if kind == "pandas" else as_xarray
    x, shuffled = wrap(failure_record), wrap(failure_record[order])
    test = LjungBox(lags=20, alpha=1e-3)
    same_decision(tsfdi.detect(x, models["healthy"], test), tsfdi.detect(shuffled, models["healthy"], test))
    a, b = tsfdi.identify(x[:1500], models, test), tsfdi.identify(shuffled[:1500], models, test)
    assert (a.accepted, a.label, a.status) == (b.accepted, b.label, b.status)
    for name in models:
        same_decision(a.decisions[name], b.decisions[name])
    a = tsfdi.identify_windows(x, models, test, window="5s", step="1s")
    b = tsfdi.identify_windows(shuffled, models, test, window="5s", step="1s")
    assert a.channels == b.channels == tuple(CHANNELS) and a.labels == b.labels and a.status == b.status
    np.testing.assert_array_equal(a.statistic, b.statistic)
    assert "f1" in a.labels[-10:]
    mon = tsfdi.Monitor(models["healthy"], {"f1": models["f1"], "f2": models["f2"]}, window="5s", test=test)
    a, b = mon.run(x), mon.run(shuffled)
    assert a.events == b.events and a.label == "f1" and a.detection_time is not None
    pd.testing.assert_frame_equal(a.windows, b.windows)
    assert [c for c in a.windows if c.startswith("variance_")] == [f"variance_{c}" for c in CHANNELS]


def test_positional_signals_still_work(models, failure_record):
    test = LjungBox(lags=20, alpha=1e-3)
    x = failure_record.to_numpy()
    ref, got = tsfdi.detect(failure_record, models["healthy"], test), tsfdi.detect(x, models["healthy"], test)
    np.testing.assert_array_equal(ref.statistic, got.statistic)
    # an array is taken in the models' order: reordering it changes the answer (nothing to match by)
    swapped = tsfdi.detect(x[:, [2, 0, 1]], models["healthy"], test)
    assert not np.array_equal(ref.statistic, swapped.statistic)
    mon = tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window=500, step=100, steady_window=500, test=test)
    a, b = mon.run(failure_record), mon.run(x)
    assert [(e.kind, e.label) for e in a.events] == [(e.kind, e.label) for e in b.events]
    # an array is taken in the model's order, so its variance columns carry the model's channel names
    assert list(b.windows.columns) == list(a.windows.columns)
    np.testing.assert_array_equal(b.windows["variance_yaw"], a.windows["variance_yaw"])


@pytest.mark.parametrize("kind", ["pandas", "xarray"])
def test_a_missing_or_extra_channel_is_named(models, failure_record, kind):
    wrap = (lambda f: f) if kind == "pandas" else as_xarray
    cases = {"missing channel\\(s\\) \\['pitch'\\]": failure_record[["yaw", "roll"]],
             "extra channel\\(s\\) \\['thrust'\\]": failure_record.assign(thrust=1.0),
             "missing channel\\(s\\) \\['yaw'\\]; extra channel\\(s\\) \\['r'\\]": failure_record.rename(
                 columns={"yaw": "r"})}
    mon = tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window="5s")
    detect_only = tsfdi.Monitor(models["healthy"], window="5s")
    calls = {"detect": lambda s: tsfdi.detect(s, models["healthy"]),
             "identify": lambda s: tsfdi.identify(s, models),
             "identify_windows": lambda s: tsfdi.identify_windows(s, models, window="5s"),
             "Monitor.run": mon.run, "Monitor.run (detection only)": detect_only.run}
    for what, bad in cases.items():
        for call in calls.values():
            with pytest.raises(ValueError, match=f"^signal: {what}; .*{CHANNELS}"):
                call(wrap(bad))


def test_a_stream_keeps_the_channels_of_its_first_block(models, failure_record):
    mon = tsfdi.Monitor(models["healthy"], {"f1": models["f1"], "f2": models["f2"]}, window="5s")
    ref = mon.run(failure_record)
    mon.reset()
    events = []
    orders = [CHANNELS, ["yaw", "pitch", "roll"], ["pitch", "roll", "yaw"]]
    for i, k in enumerate(range(0, 3000, 250)):
        events += mon.update(failure_record[orders[i % 3]].iloc[k:k + 250])
    assert events == ref.events
    pd.testing.assert_frame_equal(mon.result().windows, ref.windows)
    with pytest.raises(ValueError, match=r"signal: missing channel\(s\) \['roll'\]"):
        mon.update(failure_record[["yaw", "pitch"]].iloc[:10])


def test_fault_models_are_matched_by_their_own_names(models, failure_record):
    """A fault model fitted on another column order than the baseline still gets its own channels."""
    rng = np.random.default_rng(21)
    f1 = VAR(three("f1", 6000, rng)[["yaw", "pitch", "roll"]], 2).fit()
    test = LjungBox(lags=20, alpha=1e-3)
    a = tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window="5s", test=test).run(failure_record)
    b = tsfdi.Monitor(models["healthy"], {"f1": f1}, window="5s", test=test).run(failure_record)
    assert a.label == b.label == "f1"
    ident = tsfdi.identify(failure_record[2000:], {"f1": f1}, test)
    assert ident.accepted == ("f1",) and ident.decisions["f1"].channels == ("yaw", "pitch", "roll")


def test_baseline_records_are_matched_by_name():
    rng = np.random.default_rng(3)
    recs = {s: three(s, 3000, rng) for s in ("healthy", "f1", "f2")}
    ref = tsfdi.fit_baselines(recs, models=["var"], var_max_lags=4)
    shuffled = {s: (r if s == "healthy" else r[["yaw", "roll", "pitch"]]) for s, r in recs.items()}
    got = tsfdi.fit_baselines(shuffled, models=["var"], var_max_lags=4)
    assert got.channels == tuple(CHANNELS) and got.fs == FS
    for s in recs:
        np.testing.assert_array_equal(got.models["var"][s].params, ref.models["var"][s].params)
    bad = {**recs, "f2": recs["f2"].rename(columns={"yaw": "psi"})}
    with pytest.raises(ValueError, match=r"data\[2\]: missing channel\(s\) \['yaw'\]; extra channel\(s\) \['psi'\]"):
        tsfdi.fit_baselines(bad, models=["var"], var_max_lags=4)

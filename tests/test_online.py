"""OnlineDetector: several pairs at once, first alarms with time stamps, streaming GLRT, data kinds."""

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy.signal import lfilter

import tsfdi
from tsfdi.detection.glrt import GLRT
from tsfdi.models.recursive import RecursiveARX
from tsfdi.online import OnlineDetector


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


def test_module_and_exports():
    import tsfdi
    import tsfdi.monitoring
    from tsfdi.online import OnlineDetection

    assert tsfdi.OnlineDetector is OnlineDetector and tsfdi.OnlineDetection is OnlineDetection
    assert not hasattr(tsfdi.monitoring, "OnlineDetector")
    det = OnlineDetector(2, na=1, nb=1)
    assert det.freeze_on_alarm and all(m.freeze_on_alarm for m in det.models)
    # "mean" mode freezes the models itself (at the first alarm of the moving average), not through the model
    assert mean_detector().freeze_on_alarm and not any(m.freeze_on_alarm for m in mean_detector().models)
    assert not OnlineDetector(2, freeze_on_alarm=False).models[0].freeze_on_alarm


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
    m = RecursiveARX(1, 1, forgetting_factor=0.995, freeze_on_alarm=True, nonfinite="skip")
    res = m.run(y[:, 1], u[:, 1])
    arm = int(np.argmax(res.variance_stable))
    sigma = np.sqrt(res.variance[arm])
    ref = GLRT(window=20, scale=sigma).statistic(res.resid[arm + 1:] - res.mean[arm])
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


# ------------------------------------------------------------------ moving-average statistic, baseline phase
def thrust_like(n=3000, change=2000, drop=1.0, seed=11):
    """y = 0.5 + 0.8 u1 - 0.3 u2 + noise (sd 0.3) with a level drop ``drop`` from ``change`` (loss of thrust)."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 2))
    y = 0.5 + 0.8 * u[:, 0] - 0.3 * u[:, 1] + 0.3 * rng.standard_normal(n)
    y[change:] -= drop
    return y, u


def mean_detector(**kw):
    opts = dict(na=0, nb=1, trend="c", forgetting_factor=0.999, P0=1e2, n_inputs=2, statistic="mean", window=10,
                direction="down", threshold=0.6, arm_after=300)
    opts.update(kw)
    return OnlineDetector(["thrust"], **opts)


def test_mean_statistic_detects_a_level_drop_within_the_window_and_not_before():
    y, u = thrust_like()
    out = mean_detector().run(y, u)
    fa = out.first_alarms.loc["thrust"]
    assert fa["source"] == "mean"
    # a drop of 1.0 against a threshold of 0.6: the 10-sample average passes it after 6-10 post-change samples
    assert 2000 + 4 <= fa["position"] <= 2000 + 12
    assert not out.alarm[:2000].any()
    # the statistic is the direction-signed 10-sample average of the prediction errors
    e = np.asarray(out.resid)[:, 0]
    ref = -pd.Series(e).rolling(10).mean().to_numpy()
    np.testing.assert_allclose(np.asarray(out.statistic)[:, 0], ref, rtol=1e-10, atol=1e-12, equal_nan=True)
    # one-sided: a rise of the same size is no fault for direction="down", it is for "up" and "both"
    y_up, _ = thrust_like(drop=-1.0)
    assert mean_detector().run(y_up, u).first_alarm is None
    for d in ("up", "both"):
        pos = mean_detector(direction=d).run(y_up, u).first_alarm
        assert 2004 <= pos <= 2012


def test_mean_statistic_freezes_the_model_at_the_first_alarm():
    y, u = thrust_like()
    det = mean_detector()
    out = det.run(y, u)
    first = out.first_alarm
    m = det.models[0]
    assert m.frozen
    # the frozen parameters are those after the sample before the alarm: equal to a model run up to it
    ref = RecursiveARX(0, 1, 0, 0.999, P0=1e2, n_inputs=2, trend="c", threshold=1e300, nonfinite="skip")
    ref.run(y[:first], u[:first])
    np.testing.assert_allclose(m.theta_, ref.theta_, rtol=1e-12)
    # the fault is not learnt: the errors stay near -1 (the drop) to the end; without freezing they fade
    assert np.asarray(out.resid)[-200:, 0].mean() < -0.8
    free = mean_detector(freeze_on_alarm=False).run(y, u)
    assert np.asarray(free.resid)[-200:, 0].mean() > -0.5


def test_mean_statistic_streaming_equals_block():
    y, u = thrust_like(n=2500, change=1500, seed=4)
    whole = mean_detector().run(y, u)
    det = mean_detector()
    parts = [det.run(y[a:b], u[a:b]) for a, b in ((0, 700), (700, 1505), (1505, 2500))]
    pd.testing.assert_frame_equal(det.first_alarms, whole.first_alarms)
    np.testing.assert_allclose(np.concatenate([np.asarray(p.statistic) for p in parts]),
                               np.asarray(whole.statistic), rtol=1e-12, equal_nan=True)
    np.testing.assert_allclose(np.concatenate([np.asarray(p.resid) for p in parts]), np.asarray(whole.resid),
                               rtol=1e-12, equal_nan=True)
    step = mean_detector()
    flags = np.array([step.update(y[t], u[t])[0] for t in range(len(y))])
    np.testing.assert_array_equal(flags, whole.alarm[:, 0])


def test_arm_after_suppresses_alarms_in_the_baseline_phase():
    # a change at 400 inside a 600-sample baseline phase is not reported; with a shorter phase it is
    y, u = thrust_like(n=1500, change=400)
    assert mean_detector(arm_after=600).run(y, u).first_alarm is None or \
        mean_detector(arm_after=600).run(y, u).first_alarm >= 600
    assert 404 <= mean_detector(arm_after=300).run(y, u).first_alarm <= 412
    # Z-score mode: the recursive model's alarms and the GLRT obey the same phase
    yy, uu = two_pairs(gain=1.0)
    out = OnlineDetector(["a", "b"], na=1, nb=1, arm_after=3500).run(yy, uu)
    assert (out.first_alarms["position"] == -1).all() or out.first_alarms["position"].max() >= 3500
    assert not out.alarm[:3500].any()


@pytest.mark.parametrize("kind", ["numpy", "pandas", "xarray"])
def test_mean_statistic_data_kinds(kind):
    y, u = thrust_like(n=2500, change=1500)
    index = pd.date_range("2018-07-18 19:56:50", periods=len(y), freq="50ms")
    if kind == "pandas":
        yy, uu = pd.Series(y, index=index, name="ax"), pd.DataFrame(u, index=index, columns=["aspd", "alt"])
    elif kind == "xarray":
        yy = xr.DataArray(y, dims=("time",), coords={"time": index})
        uu = xr.DataArray(u, dims=("time", "input"), coords={"time": index})
    else:
        yy, uu = y, u
    out = mean_detector().run(yy, uu)
    ref = mean_detector().run(y, u)
    assert out.first_alarm == ref.first_alarm
    np.testing.assert_array_equal(np.asarray(out.statistic), np.asarray(ref.statistic))
    if kind == "pandas":
        assert isinstance(out.statistic, pd.DataFrame) and out.first_alarm_time == index[out.first_alarm]
    elif kind == "xarray":
        assert isinstance(out.statistic, xr.DataArray) and out.first_alarm_time == index[out.first_alarm]


def test_mean_statistic_bad_input():
    y, u = thrust_like(n=500)
    with pytest.raises(ValueError, match="n_inputs"):
        mean_detector().run(y, u[:, :1])
    with pytest.raises(ValueError, match="statistic"):
        OnlineDetector(1, statistic="median")
    with pytest.raises(ValueError, match="direction"):
        OnlineDetector(1, direction="sideways")
    with pytest.raises(ValueError, match="window"):
        OnlineDetector(1, window=0)
    with pytest.raises(ValueError, match="arm_after"):
        OnlineDetector(1, arm_after=-1)
    with pytest.raises(TypeError, match="freeze_on_alarm"):
        OnlineDetector(1, freeze_on_alarm="yes")
    with pytest.raises(TypeError, match="halt_on_alarm"):           # the former name is not an option any more
        OnlineDetector(1, halt_on_alarm=True)
    assert mean_detector().glrt is None and OnlineDetector(1).glrt is not None


# ------------------------------------------------------------------ real flights with the shipped settings
def _alfa_benchmark():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / "alfa_detection.py"
    spec = importlib.util.spec_from_file_location("alfa_detection_bench", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    if not (mod.ROOT / "flights.csv").is_file():
        raise FileNotFoundError(f"shared ALFA data missing at {mod.ROOT}: tests need ../shared/data/alfa")
    return mod


def test_real_alfa_flights_with_the_shipped_settings():
    """Rudder, engine and no-failure flights: alarms shortly after the onset, none on the healthy flight."""
    B = _alfa_benchmark()
    from tsfdi.datasets.alfa import list_alfa, load_alfa

    tab = list_alfa(B.ROOT).set_index("flight")
    cases = {"carbonZ_2018-09-11-15-06-34_1_rudder_right_failure": ("sideslip", 1.5),
             "carbonZ_2018-07-30-16-39-00_1_engine_failure": ("thrust", 2.0),
             "carbonZ_2018-10-05-14-37-22_1_no_failure": (None, None)}
    for flight, (channel, max_delay) in cases.items():
        df = B.prepare(load_alfa(tab.loc[flight, "merged_path"]))
        assert not set(df.columns) & B.LEAKING
        alarms = {c: B.first_alarm_s(df, B.run_channel(df, c, t)) for c, t in B.ALFA_SETTINGS.items()}
        first = min((a for a in alarms.values() if np.isfinite(a)), default=np.nan)
        if channel is None:
            assert np.isnan(first), alarms
        else:
            onset = df.attrs["onset_s"]
            assert onset <= alarms[channel] <= onset + max_delay, (alarms, onset)
            assert onset <= first <= onset + max_delay


def test_alfa_lofo_chooses_the_channel_set_inside_the_folds():
    """A channel that alarms before the onset is switched off in every fold; held-out alarms and metrics exact."""
    B = _alfa_benchmark()
    onset = np.array([10.0, 10.0, np.nan, np.nan])
    times = {"good": np.array([[11.0], [12.0], [np.nan], [np.nan]]),
             "bad": np.array([[5.0], [11.0], [3.0], [np.nan]])}
    grids = {"good": np.array([1.0]), "bad": np.array([2.0])}
    alarm, chosen, alarm_fit, label_fit, idx_fit = B.lofo(onset, times, grids)
    np.testing.assert_array_equal(alarm, [11.0, 12.0, np.nan, np.nan])
    assert chosen == ["good 1, bad off"] * 4 and label_fit == "good 1, bad off"
    assert idx_fit == {"good": 0, "bad": 1}
    m = tsfdi.detection_metrics(tsfdi.score_records(onset, alarm), max_delay=5.0).loc["all"]
    assert (m["TP"], m["FP"], m["FN"], m["TN"], m["TP_within"]) == (2, 0, 0, 2, 2)
    assert m["mean_delay"] == 1.5 and m["mean_delay_within"] == 1.5 and m["accuracy"] == 1.0
    m = tsfdi.detection_metrics(tsfdi.score_records([0.0, 0.0], [1.0, 7.0]), max_delay=5.0).loc["all"]
    assert m["mean_delay"] == 4.0 and m["mean_delay_within"] == 1.0 and m["TP_within"] == 1


def test_real_alfa_roll_gain_channel_with_the_shipped_threshold():
    """Configuration C's roll-effectiveness GLRT: an aileron failure alarms within 10 s, a healthy flight never."""
    B = _alfa_benchmark()
    from tsfdi.datasets.alfa import list_alfa, load_alfa

    tab = list_alfa(B.ROOT).set_index("flight")
    thr = [B.ALFA_GAIN_THRESHOLD]
    for flight, max_delay in {"carbonZ_2018-09-11-17-27-13_2_both_ailerons_failure": 10.0,
                              "carbonZ_2018-10-05-14-37-22_2_right_aileron_failure": 10.0,
                              "carbonZ_2018-10-05-14-37-22_1_no_failure": None}.items():
        df = B.prepare(load_alfa(tab.loc[flight, "merged_path"]))
        t, s = B.roll_gain_statistic(df)
        assert t.size == len(df) // B.GAIN["block"] and np.all(np.diff(t) > 0)
        alarm = B.gain_crossing_times(df, thr)[0]
        if max_delay is None:
            assert np.isnan(alarm)
        else:
            onset = df.attrs["onset_s"]
            assert onset <= alarm <= onset + max_delay, (alarm, onset)
            # the statistic stays below the threshold over the whole healthy part after the baseline phase
            pre = (t >= B.ARM_AFTER_S) & (t < onset)
            assert np.nanmax(s[pre]) < thr[0]


def test_keipour_subset_has_table_i_counts_and_rejects_others():
    """The inferred 22 test flights of paper 001 match Table I per failure type; a changed table is an error."""
    B = _alfa_benchmark()
    from tsfdi.datasets.alfa import list_alfa

    tab = list_alfa(B.ROOT)
    mask, kind = B.keipour_flights(tab)
    assert mask.sum() == 22 and kind.shape == (len(tab),)
    assert (kind == "rudder+ailerons").sum() == 1
    engine = tab.flight[mask & (tab.fault == "engine").to_numpy()]
    assert set(engine) == set(tab.flight[tab.engine_path.notna()])  # the 7 commanded / measured flights
    with pytest.raises(RuntimeError, match="Table I"):
        B.keipour_flights(tab.drop(index=tab.index[mask][0]))


def test_departure_is_the_first_exceedance_of_the_pre_onset_range():
    B = _alfa_benchmark()
    t = np.arange(0.0, 40.0, 0.5)
    v = np.where(t < 30.0, np.sin(t), 0.0)
    v[t == 34.0] = -1.5                              # |v| exceeds the pre-onset max (<= 1) 4 s after onset
    df = pd.DataFrame({"x": v}, index=pd.to_datetime(t, unit="s"))
    assert B.departure_s(df, "x", 30.0) == 4.0
    assert np.isnan(B.departure_s(df.assign(x=np.where(t < 30.0, v, 0.5)), "x", 30.0))

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
from _scripts import load_script


#: paper 001's settings, the constructor's defaults before issue 34 made the autopilot-log recipe the default: the
#: tests of the Z-score, GLRT and moving-average paths pass them explicitly (the reproduction stays reachable)
PAPER001 = dict(na=2, nb=2, nk=0, forgetting_factor=0.995, eps=1e-2, statistic="zscore")


def paper001(pairs, **options):
    """An OnlineDetector with paper 001's settings, ``options`` overriding them."""
    return OnlineDetector(pairs, **{**PAPER001, **options})


def assert_streams_like_a_block(make, y, u, sizes=(777,)):
    """The detector ``make()`` fed the stream sample by sample (``update``) and in chunks of each of ``sizes``
    (``run``) gives the alarms, first alarms and statistic of one ``run`` over the whole stream; returns that run."""
    ref = make().run(y, u)
    det = make()
    alarms = np.array([det.update(y[i], u[i]) for i in range(len(y))])
    np.testing.assert_array_equal(alarms, ref.alarm)
    pd.testing.assert_frame_equal(det.first_alarms, ref.first_alarms)
    for size in sizes:
        det = make()
        parts = [det.run(y[i:i + size], u[i:i + size]) for i in range(0, len(y), size)]
        np.testing.assert_array_equal(np.vstack([p.alarm for p in parts]), ref.alarm)
        np.testing.assert_allclose(np.vstack([np.asarray(p.statistic) for p in parts]), np.asarray(ref.statistic),
                                   equal_nan=True)
    return ref


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
    det = paper001(2, na=1, nb=1)
    assert det.freeze_on_alarm and all(m.freeze_on_alarm for m in det.models)
    # "mean" mode freezes the models itself (at the first alarm of the moving average), not through the model
    assert mean_detector().freeze_on_alarm and not any(m.freeze_on_alarm for m in mean_detector().models)
    assert not paper001(2, freeze_on_alarm=False).models[0].freeze_on_alarm


def test_the_defaults_are_the_autopilot_log_recipe():
    """Issue 34: the simplest call gets the recipe of the guide (body rate against the actuator control one sample
    later, SPRT), not paper 001's settings, which alarmed on every healthy simulated autopilot log."""
    det = OnlineDetector(["roll", "pitch", "yaw"])
    m = det.models[0]
    assert (m.na, m.nb, m.nk, m.forgetting_factor, m.eps) == (1, 2, 1, 0.999, 0.03)
    assert det.statistic == "sprt" and det.glrt is None and det.sprt.alternative == "variance"
    assert det.threshold == pytest.approx(np.log(0.99 / 1e-9)) and det.freeze_on_alarm and det.nonfinite == "skip"
    ref = paper001(["roll", "pitch", "yaw"])
    assert (ref.models[0].na, ref.models[0].nk, ref.statistic, ref.threshold) == (2, 0, "zscore", 4.5)
    assert ref.glrt is not None


def test_first_alarm_per_pair_and_overall():
    y, u = two_pairs(gain=1.0)
    det = paper001(["a", "b"], na=1, nb=1)
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
    z_only = paper001(["a", "b"], na=1, nb=1, glrt=None).run(y, u)
    both = paper001(["a", "b"], na=1, nb=1, glrt=GLRT(window=20, alpha=1e-6)).run(y, u)
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
    whole = paper001(2, na=1, nb=1).run(y, u)
    det = paper001(2, na=1, nb=1)
    det.run(y[:500], u[:500])
    det.run(y[500:900], u[500:900])
    last = det.run(y[900:], u[900:])
    pd.testing.assert_frame_equal(last.first_alarms, whole.first_alarms)
    step = paper001(2, na=1, nb=1)
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
    out = paper001(["a", "b"], na=1, nb=1).run(yy, uu)
    ref = paper001(["a", "b"], na=1, nb=1).run(y, u)
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
    out = paper001(2, na=1, nb=1).run(y, u)
    assert out.first_alarms["position"].iloc[1] >= 900
    assert paper001(2, na=1, nb=1).models[0].nonfinite == "skip"
    det = paper001(2, na=1, nb=1)
    det.run(y, u)
    assert det.models[0].n_skipped == 1
    with pytest.raises(ValueError, match="NaN"):
        paper001(2, na=1, nb=1, nonfinite="raise").run(y, u)
    with pytest.raises(ValueError, match="one column per pair"):
        paper001(3).run(y, u)
    with pytest.raises(ValueError, match="same length"):
        paper001(2).run(y, u[:-1])
    with pytest.raises(TypeError, match="pairs"):
        paper001(1.5)
    with pytest.raises(ValueError, match="distinct"):
        paper001(["a", "a"])
    with pytest.raises(TypeError, match="glrt"):
        paper001(2, glrt="yes")
    with pytest.raises(ValueError, match="forgetting_factor"):
        paper001(2, forgetting_factor=1.5)
    with pytest.raises(ValueError, match="na"):
        paper001(2, na=-1)


def test_rls_options_are_passed_on_or_refused_by_name():
    # gate is the detector's own choice: it was a duplicate keyword of RecursiveARX (a TypeError from Python)
    with pytest.raises(TypeError, match=r"^gate is set by OnlineDetector: .*gate='relative'.* P0, trend, theta0"):
        paper001(2, gate="absolute")
    with pytest.raises(TypeError, match=r"^gate is set by OnlineDetector"):
        paper001(2, gate="relative")
    with pytest.raises(TypeError, match=r"^gates is not an option of OnlineDetector"):
        paper001(2, gates="absolute")
    # every option reaches every pair's model: its own parameters under their name, the others as given
    det = paper001(["a", "b"], na=1, nb=2, nk=1, forgetting_factor=0.99, threshold=3.0, freeze_on_alarm=False,
                         nonfinite="raise", n_inputs=2, arm_after=5, eps=0.05, P0=10.0, trend="c",
                         theta0=[0.1, 0.2, 0.3, 0.4, 0.5, 0.6], stable_samples=7, variance_tol=0.02,
                         min_variance_samples=9)
    for m in det.models:
        assert (m.na, m.nb, m.nk, m.n_inputs, m.trend) == (1, 2, 1, 2, "c")
        assert (m.forgetting_factor, m.threshold, m.freeze_on_alarm, m.nonfinite) == (0.99, 3.0, False, "raise")
        assert (m.arm_after, m.eps, m.gate) == (5, 0.05, "relative")
        assert (m.stable_samples, m.variance_tol, m.min_variance_samples) == (7, 0.02, 9)
        np.testing.assert_array_equal(m.P_, 10.0 * np.eye(6))
        np.testing.assert_array_equal(m.theta_, [0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    # ... and the alarm-free copies of calibrate()
    assert det._alarm_free_copy().models[1].stable_samples == 7


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
    return paper001(["thrust"], **opts)


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
    out = paper001(["a", "b"], na=1, nb=1, arm_after=3500).run(yy, uu)
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
        paper001(1, statistic="median")
    with pytest.raises(ValueError, match="direction"):
        paper001(1, direction="sideways")
    with pytest.raises(ValueError, match="window"):
        paper001(1, window=0)
    with pytest.raises(ValueError, match="arm_after"):
        paper001(1, arm_after=-1)
    with pytest.raises(TypeError, match="freeze_on_alarm"):
        paper001(1, freeze_on_alarm="yes")
    with pytest.raises(TypeError, match="halt_on_alarm"):           # the former name is not an option any more
        paper001(1, halt_on_alarm=True)
    assert mean_detector().glrt is None and paper001(1).glrt is not None


# ------------------------------------------------------------------ real flights with the shipped settings
def _alfa_benchmark(alfa=None):
    """benchmarks/alfa_detection.py, reading the ALFA copy ``alfa`` (the ``shared_alfa`` fixture; its functions on
    arrays need none)."""
    mod = load_script("benchmarks/alfa_detection.py")
    if alfa is not None:
        mod.ROOT = alfa
    return mod


def test_real_alfa_flights_with_the_shipped_settings(shared_alfa):
    """Rudder, engine and no-failure flights: alarms shortly after the onset, none on the healthy flight."""
    B = _alfa_benchmark(shared_alfa)
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
    alarm, chosen, alarm_fit, label_fit, idx_fit, _ = B.lofo(onset, times, grids)
    np.testing.assert_array_equal(alarm, [11.0, 12.0, np.nan, np.nan])
    assert chosen == ["good 1, bad off"] * 4 and label_fit == "good 1, bad off"
    assert idx_fit == {"good": 0, "bad": 1}
    m = tsfdi.detection_metrics(tsfdi.score_records(onset, alarm), max_delay=5.0).loc["all"]
    assert (m["TP"], m["FP"], m["FN"], m["TN"], m["TP_within"]) == (2, 0, 0, 2, 2)
    assert m["mean_delay"] == 1.5 and m["mean_delay_within"] == 1.5 and m["accuracy"] == 1.0
    m = tsfdi.detection_metrics(tsfdi.score_records([0.0, 0.0], [1.0, 7.0]), max_delay=5.0).loc["all"]
    assert m["mean_delay"] == 4.0 and m["mean_delay_within"] == 1.0 and m["TP_within"] == 1


def test_alfa_pf_thresholds_come_from_the_other_flights_healthy_parts_only():
    """C-PF: a fold's thresholds are EmpiricalThreshold(P_F / channels) of the other flights' healthy-part maxima;
    the held-out flight and every sample after an onset stay out; the held-out alarm is the first crossing."""
    B = _alfa_benchmark()
    rng = np.random.default_rng(1)
    n, pf = 40, 0.2
    t = np.arange(0.0, 60.0, 0.5)
    onset = np.where(np.arange(n) % 4 == 0, np.nan, 40.0)            # 10 flights without failure
    stats = {"a": [], "b": []}
    for i in range(n):
        for c in stats:
            s = np.where(t >= 20.0, rng.gumbel(size=t.size), -np.inf)  # armed after 20 s
            if c == "a" and np.isfinite(onset[i]):
                s = np.where(t >= onset[i], s + 100.0, s)              # the failure: far above any healthy value
            stats[c].append((t, s))
    alarm, thr, maxima = B.pf_folds(stats, onset, pf)
    assert thr.shape == maxima.shape == (n, 2) and maxima.to_numpy().max() < 50.0  # no post-onset sample
    for i in (0, 1):
        for c in stats:
            est = tsfdi.EmpiricalThreshold(pf / 2, **B.PF_ESTIMATOR).calibrate(maxima[c].drop(index=i))
            assert est.method_ == "gpd" and thr.at[i, c] == est.threshold_
    for i in range(n):                                                 # first crossing of any channel
        firsts = [t[s > thr.at[i, c]][0] for c in stats for tt, s in [stats[c][i]] if (s > thr.at[i, c]).any()]
        assert alarm[i] == min(firsts) if firsts else np.isnan(alarm[i])
    sc = tsfdi.score_records(onset, alarm)
    assert (sc["outcome"] == "FP").sum() == (maxima.to_numpy() > thr.to_numpy()).any(axis=1).sum()
    assert set(sc["outcome"][np.isfinite(onset)]) <= {"TP", "FP"}     # every failure is caught (+100)
    # a held-out flight with huge healthy values does not move its own thresholds, only the other folds'
    stats["b"][1] = (t, np.where(t >= 20.0, 1e6, -np.inf))
    alarm2, thr2, _ = B.pf_folds(stats, onset, pf)
    pd.testing.assert_series_equal(thr2.loc[1], thr.loc[1])
    assert (thr2["b"].drop(index=1) > thr["b"].drop(index=1)).all() and alarm2[1] == 20.0


def test_real_alfa_roll_gain_channel_with_the_shipped_threshold(shared_alfa):
    """Configuration C's roll-effectiveness GLRT: an aileron failure alarms within 10 s, a healthy flight never."""
    B = _alfa_benchmark(shared_alfa)
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


def test_keipour_subset_has_table_i_counts_and_rejects_others(shared_alfa):
    """The inferred 22 test flights of paper 001 match Table I per failure type; a changed table is an error."""
    B = _alfa_benchmark(shared_alfa)
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


# ------------------------------------------------------------------ thresholds for false alarms per flight hour
FS = 20.0


def healthy_runs(n_runs, seed, minutes=10.0):
    """ARX runs y = 0.7 y[-1] + u + e (e: sd 0.1) sampled at FS Hz, one generator per run."""
    n = int(minutes * 60 * FS)
    ys, us = [], []
    for r in range(n_runs):
        rng = np.random.default_rng([seed, r])
        u = rng.standard_normal(n)
        ys.append(lfilter([1.0], [1.0, -0.7], u + 0.1 * rng.standard_normal(n)))
        us.append(u)
    return ys, us


def episodes_and_hours(det, ys, us, fs=FS):
    total, hours = 0, 0.0
    for y, u in zip(ys, us):
        det.reset()
        rate = det.run(y, u).false_alarms_per_hour(fs)
        total += int(rate.loc["all", "episodes"])
        hours += rate.loc["all", "hours"]
    return total, hours


@pytest.mark.parametrize("opts", [{}, {"statistic": "mean", "window": 10}], ids=["zscore+glrt", "mean"])
def test_calibrated_rate_holds_on_new_healthy_runs(opts):
    from scipy import stats

    ys, us = healthy_runs(20, seed=0)
    det = paper001(1, na=1, nb=1, freeze_on_alarm=False, **opts)
    assert det.calibration_ is None
    assert det.calibrate(ys, us, false_alarms_per_hour=2.0, fs=FS) is det
    cal = det.calibration_
    assert cal.runs == 20 and cal.healthy_hours == pytest.approx(20 / 6)
    assert cal.expected_episodes == pytest.approx(2.0 * 20 / 6) and cal.false_alarms_per_hour == 2.0
    assert cal.threshold == det.threshold and abs(cal.healthy_episodes - cal.expected_episodes) <= 2
    if det.glrt is not None:
        assert cal.glrt_threshold == det.glrt.threshold_ and det.models[0].threshold == det.threshold
        assert set(cal.source_rates) == {"zscore", "glrt"}
        assert all(1.0 <= r <= 2.0 for r in cal.source_rates.values())
    else:
        assert cal.glrt_threshold is None and cal.estimator == "empirical" and cal.source_rates == {"mean": 2.0}
    # 20 new healthy runs: the alarm episodes lie in the two-sided 99 % Poisson band of the target
    total, hours = episodes_and_hours(det, *healthy_runs(20, seed=1))
    lo, hi = stats.poisson.ppf([0.005, 0.995], 2.0 * hours)
    assert lo <= total <= hi, (total, lo, hi)


def test_calibrated_default_detector_first_alarms_and_a_fault():
    """With freeze_on_alarm the first alarm of a healthy run comes at the calibrated rate; a fault still alarms."""
    from scipy import stats

    ys, us = healthy_runs(20, seed=0)
    det = paper001(["ax"], na=1, nb=1).calibrate(ys, us, false_alarms_per_hour=2.0, fs=FS)
    assert det.freeze_on_alarm and det.threshold < 4.5     # 2 per hour at 20 Hz is looser than 4.5 sigma
    new_y, new_u = healthy_runs(20, seed=1)
    alarmed = 0
    for y, u in zip(new_y, new_u):
        det.reset()
        alarmed += det.run(y, u).first_alarm is not None
    p = 1.0 - np.exp(-2.0 * 600 / 3600)                   # P(a 10-minute run alarms) for Poisson episodes
    lo, hi = stats.binom.ppf([0.005, 0.995], 20, p)
    assert lo <= alarmed <= hi, (alarmed, lo, hi)
    # a sensor bias of 5 error standard deviations in the output from sample 6000
    y, u = new_y[0].copy(), new_u[0]
    y[6000:] += 0.5
    det.reset()
    out = det.run(y, u)
    assert out.alarm[6000:6040, 0].any()


def test_calibration_extrapolates_short_healthy_data_with_an_exponential_tail():
    ys, us = healthy_runs(20, seed=0)
    two = paper001(1, na=1, nb=1, glrt=None).calibrate(ys, us, false_alarms_per_hour=2.0, fs=FS)
    half = paper001(1, na=1, nb=1, glrt=None).calibrate(ys, us, false_alarms_per_hour=0.5, fs=FS)
    cal = half.calibration_
    assert two.calibration_.estimator == "empirical" and cal.estimator == "exponential tail"
    fit = cal.tail["zscore"]
    assert 10 <= fit["n_u"] <= 20 and fit["beta"] > 0
    # t = u + beta n_u (((n_u + 1) / K)^(1 / n_u) - 1), K = 0.5 * 20 / 6 expected episodes
    k, n_u = 0.5 * 20 / 6, fit["n_u"]
    assert half.threshold == pytest.approx(fit["u"] + fit["beta"] * n_u * (((n_u + 1) / k) ** (1 / n_u) - 1))
    assert half.threshold > two.threshold
    # with the GLRT, below 5 expected episodes each source gets half the rate (union bound)
    both = paper001(1, na=1, nb=1).calibrate(ys, us, false_alarms_per_hour=1.0, fs=FS)
    assert both.calibration_.source_rates == {"zscore": 0.5, "glrt": 0.5}
    assert both.calibration_.estimator == "exponential tail" and set(both.calibration_.tail) == {"zscore", "glrt"}
    assert both.glrt.threshold_ == both.calibration_.glrt_threshold


def test_false_alarms_per_hour_report():
    y, u = thrust_like(n=4000, change=4000)                # healthy
    index = pd.date_range("2018-07-18 19:56:50", periods=len(y), freq="50ms")
    det = mean_detector(threshold=0.15, direction="both", freeze_on_alarm=False)
    out = det.run(pd.Series(y, index=index), pd.DataFrame(u, index=index))
    a = out.alarm[:, 0]
    starts = int(a[0]) + int(np.count_nonzero(a[1:] & ~a[:-1]))
    assert starts >= 3 and out.alarm_start.sum() == starts and out.fs == pytest.approx(20.0)
    rep = out.false_alarms_per_hour()                      # fs from the time index
    assert list(rep.index) == ["thrust", "all"] and list(rep.columns) == ["episodes", "hours", "per_hour"]
    hours = 4000 / 20.0 / 3600
    assert rep.loc["thrust", "episodes"] == starts and rep.loc["all", "hours"] == pytest.approx(hours)
    assert rep.loc["all", "per_hour"] == pytest.approx(starts / hours)
    pd.testing.assert_frame_equal(out.false_alarms_per_hour(20.0), rep)
    # numpy input has no time: fs is needed
    det.reset()
    out = det.run(y, u)
    with pytest.raises(ValueError, match="fs"):
        out.false_alarms_per_hour()
    with pytest.raises(ValueError, match="fs"):
        out.false_alarms_per_hour(0.0)
    # an episode running across two blocks of a stream is counted once
    cut = int(np.flatnonzero(a & np.r_[a[1:], False] & ~np.r_[False, a[:-1]])[0]) + 1   # inside an episode
    det.reset()
    parts = [det.run(y[:cut], u[:cut]), det.run(y[cut:], u[cut:])]
    assert sum(int(p.false_alarms_per_hour(20.0).loc["all", "episodes"]) for p in parts) == starts
    # several pairs: "all" is the sum over the pairs
    yy, uu = two_pairs(gain=1.0)
    rep = paper001(["a", "b"], na=1, nb=1, freeze_on_alarm=False).run(yy, uu).false_alarms_per_hour(50.0)
    assert rep.loc["all", "episodes"] == rep.loc["a", "episodes"] + rep.loc["b", "episodes"] > 0


def test_calibration_reads_fs_from_the_time_index_and_resets():
    ys, us = healthy_runs(5, seed=2)
    ref = paper001(1, na=1, nb=1).calibrate(ys, us, false_alarms_per_hour=20.0, fs=FS)
    index = pd.date_range("2020-01-01", periods=len(ys[0]), freq="50ms")
    det = paper001(1, na=1, nb=1)
    det.run(ys[0][:100], us[0][:100])
    det.calibrate([pd.Series(y, index=index) for y in ys], [pd.Series(u, index=index) for u in us],
                  false_alarms_per_hour=20.0)
    assert det.nobs == 0 and det.threshold == ref.threshold and det.glrt.threshold_ == ref.glrt.threshold_
    assert det.calibration_.healthy_hours == pytest.approx(5 / 6)


def test_calibration_bad_input():
    ys, us = healthy_runs(3, seed=0, minutes=2.0)
    det = paper001(1, na=1, nb=1)
    with pytest.raises(ValueError, match="false_alarms_per_hour"):
        det.calibrate(ys, us, false_alarms_per_hour=0.0, fs=FS)
    with pytest.raises(TypeError, match="false_alarms_per_hour"):
        det.calibrate(ys, us, false_alarms_per_hour="2/h", fs=FS)
    with pytest.raises(ValueError, match="fs"):
        det.calibrate(ys, us, false_alarms_per_hour=2.0, fs=-20.0)
    with pytest.raises(ValueError, match="fs"):
        det.calibrate(ys, us, false_alarms_per_hour=2.0)         # numpy runs carry no time
    with pytest.raises(TypeError, match="y_runs"):
        det.calibrate(ys[0], us, false_alarms_per_hour=2.0, fs=FS)
    with pytest.raises(ValueError, match="u_runs"):
        det.calibrate(ys, [], false_alarms_per_hour=2.0, fs=FS)
    with pytest.raises(ValueError, match="same number of runs"):
        det.calibrate(ys, us[:2], false_alarms_per_hour=2.0, fs=FS)
    with pytest.raises(ValueError, match="healthy run 1: u and y must have the same length"):
        det.calibrate(ys, [us[0], us[1][:-1], us[2]], false_alarms_per_hour=2.0, fs=FS)
    # 0.1 h of healthy flight: 1 per hour needs 2 h for the tail fit of each source (half the rate each)
    with pytest.raises(ValueError, match=r"at least 2 healthy hours are needed .* 5 for an empirical"):
        det.calibrate(ys, us, false_alarms_per_hour=1.0, fs=FS)
    with pytest.raises(ValueError, match="require fewer false alarms"):
        det.calibrate(ys, us, false_alarms_per_hour=1e7, fs=FS)
    assert det.calibration_ is None and det.threshold == 4.5   # nothing changed by the failed calls

"""fit_baselines (Table 2 analogue), Baselines.monitor / calibrated_tests / select_alpha (tsfdi.baselines)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from _synthetic_fdi import FS, dataset, record
from conftest import as_kind
from scipy import stats

import tsfdi
from tsfdi import FTest, LjungBox
from tsfdi.baselines import Baselines, Records, fit_baselines, insample_q
from tsfdi.windows import ResidualWindows


def test_module_exports():
    assert tsfdi.fit_baselines is fit_baselines and tsfdi.Baselines is Baselines and tsfdi.Records is Records


def test_baselines_table_and_exclusion(synthetic, fitted):
    b = fitted
    assert b.healthy == "healthy" and b.faults == ("f1", "f2")
    assert b.fit_records == (0, 5, 10)          # first record of each state
    assert b.steady_window == 500               # samples
    t = b.table
    assert list(t.columns[:6]) == ["state", "model", "signals", "order", "lags", "parameters"]
    assert len(t) == 3 * 3                      # 3 states x (2 scalar AR + VAR)
    var = t[t["model"] == "VAR"].set_index("state")
    # the systems are VAR(2): BIC finds order 2; parameters s^2 p; SPP = nobs s / parameters
    assert (var["lags"] == 2).all() and (var["parameters"] == 8).all()
    np.testing.assert_allclose(var["spp"], var["nobs"] * 2 / 8)
    # the table's order equals tsfdi.select_order on the same segment
    seg = b.segments["f1"][0]
    assert b.models["y0"]["f1"].lags == tsfdi.select_order(seg[:, 0], 6, "ar").selected
    assert (t["records"] == 1).all() and np.isfinite(t["q_insample"]).all()
    # q_insample: median Ljung-Box Q (20 lags) over 20 s blocks of the in-sample residuals
    res = b.models["var"]["f1"]
    assert var.loc["f1", "q_insample"] == insample_q(res, 2000)
    (e,) = res.resid                            # one fitting record: one residual array
    q = [tsfdi.LjungBox(lags=20).test(e[a:a + 2000]).statistic for a in range(0, e.shape[0] - 1999, 2000)]
    assert len(q) == 1 and insample_q(res, 2000) == pytest.approx(np.median(q), rel=1e-10)
    # a block longer than the record: the whole record
    assert insample_q(res, 10**6) == pytest.approx(np.median(tsfdi.LjungBox(lags=20).test(e).statistic), rel=1e-10)
    # steady threshold: max 5 s rolling variance (0.1 s step) of the post-settle fault fitting records
    recs, _, _ = synthetic
    post = [recs[i][1500:] for i in (5, 10)]
    ref = np.max([tsfdi.monitoring.rolling_variance(p, 500, 10).max(axis=0) for p in post], axis=0)
    np.testing.assert_allclose(b.steady_thresholds, ref, rtol=1e-10)


def test_steady_window_as_samples_or_time_span(synthetic, fitted):
    recs, states, ft = synthetic
    kw = dict(states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, max_lags=6, var_max_lags=6,
              models=["var"])
    b = tsfdi.fit_baselines(recs, steady_window=500, **kw)
    assert b.steady_window == 500
    np.testing.assert_array_equal(b.steady_thresholds, fitted.steady_thresholds)
    with pytest.raises(TypeError, match="steady_window"):
        tsfdi.fit_baselines(recs, steady_window=5.0, **kw)
    with pytest.raises(ValueError, match="steady_window"):
        tsfdi.fit_baselines(recs, steady_window="1ms", **kw)


def test_fit_baselines_data_kinds(kind):
    rng = np.random.default_rng(7)
    segs = {s: as_kind(record(s, 3000, rng), kind) for s in ("healthy", "f1", "f2")}
    b = tsfdi.fit_baselines(segs, max_lags=4, var_max_lags=4, models=["var"])
    assert b.faults == ("f1", "f2")
    assert all(b.models["var"][s].lags == 2 for s in segs)
    # without fs the rate comes from the records' time index (100 Hz: "10s" is 1000 samples); arrays carry no time
    # and are taken at 1 Hz ("10s" is 10 samples)
    mon = b.monitor("var", window="10s", test=LjungBox(lags=10, alpha=1e-3))
    assert b.fs == (1.0 if kind == "numpy" else pytest.approx(100.0, rel=1e-12))
    assert mon.nchan == 2 and (mon.window, mon.step, mon.steady_window) == ((10, 1, 10) if kind == "numpy" else
                                                                            (1000, 100, 1000))


def test_monitor_from_baselines(synthetic, fitted):
    """Baselines.monitor: the healthy and fault models, the steady-state thresholds and the test given."""
    recs, _, _ = synthetic
    b = fitted
    mon = b.monitor("var")
    assert (mon.window, mon.step, mon.steady_window, mon.fs) == (2000, 100, 500, FS)
    assert repr(mon.test) == repr(LjungBox(lags=20, alpha=1e-3)) and mon.detection_test is mon.test
    assert mon.baseline is b.models["var"]["healthy"] and mon.models["f1"] is b.models["var"]["f1"]
    np.testing.assert_array_equal(mon.steady_thresholds, b.steady_thresholds)
    test = FTest(alpha=1e-4)
    m5 = b.monitor("var", window="5s", step=50, test=test, rule="likelihood")
    assert (m5.window, m5.step, m5.rule) == (500, 50, "likelihood") and m5.test is test
    ref = tsfdi.Monitor(b.models["var"]["healthy"], {f: b.models["var"][f] for f in b.faults}, window=500, step=50,
                        fs=FS, test=test, steady_thresholds=b.steady_thresholds, steady_window=500, rule="likelihood")
    assert m5.run(recs[5]).events == ref.run(recs[5]).events
    y0 = b.monitor("y0", window=500)
    assert y0.nchan == 1 and y0.steady_thresholds.tolist() == [b.steady_thresholds[0]]
    with pytest.raises(TypeError, match="test"):
        b.monitor("var", test="whiteness")
    with pytest.raises(TypeError, match="window"):
        b.monitor("var", window=20.0)
    with pytest.raises(ValueError, match="model"):
        b.monitor("roll")


def test_bad_input(synthetic):
    recs, states, ft = synthetic
    with pytest.raises(ValueError, match="states"):
        tsfdi.fit_baselines(recs, fs=FS)
    with pytest.raises(ValueError, match="healthy"):
        tsfdi.fit_baselines(recs, states=states, healthy="nominal", fs=FS)
    with pytest.raises(ValueError, match="models"):
        tsfdi.fit_baselines(recs, states=states, fs=FS, models=["altitude"])


def test_fit_baselines_pooled_records(synthetic):
    """fit_records=n pools the first n records of each state without junctions (= the list fit of the models);
    order options; in-sample whiteness column."""
    recs, states, ft = synthetic
    b = tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, max_lags=6,
                            var_max_lags=6, fit_records=3, models=["var"])
    assert b.fit_records == (0, 1, 2, 5, 6, 7, 10, 11, 12)
    segs = [recs[i][1500:] for i in (5, 6, 7)]
    ref = tsfdi.select_order(segs, 6, "var")
    np.testing.assert_allclose(b.models["var"]["f1"].params, ref.fit().params, rtol=1e-10)
    t = b.table.set_index("state")
    assert (t["records"] == 3).all() and (t["lags"] == 2).all()
    # in-sample residuals of the true order are white: median Q over 20 s blocks near the chi2(20) median
    q = t["q_insample"].to_numpy()
    assert np.all(np.abs(q - stats.chi2.median(20)) < 4.0), q
    fixed = tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=FS, settle=5.0, duration=None,
                                max_lags=6, var_max_lags=6, fit_records=3, models=["var"], order=4)
    assert fixed.models["var"]["f1"].lags == 4
    np.testing.assert_allclose(fixed.models["var"]["f1"].params, ref.fit(4).params, rtol=1e-10)
    stab = tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=FS, settle=5.0, duration=None,
                               max_lags=6, var_max_lags=6, fit_records=3, models=["var"], order="rss_sss")
    assert stab.models["var"]["f1"].lags == ref.stabilized
    with pytest.raises(ValueError, match="order"):
        tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=FS, order="aic")
    with pytest.raises(ValueError, match="fit_records"):
        tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=FS, fit_records=0)


def test_select_alpha_leave_one_out(synthetic):
    """Baselines.select_alpha: the paper's rule on held-out fitting windows for each candidate alpha; the
    acceptances are those of the chi-square Ljung-Box test on the same residual windows."""
    recs, states, ft = synthetic
    kw = dict(states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, order=2, max_lags=4,
              var_max_lags=4, steady_window="5s", fit_records=3, models=["var"])
    b = tsfdi.fit_baselines(recs, calibrate=True, **kw)
    alphas = (1e-2, 1e-4, 1e-300)
    tab = b.select_alpha("var", LjungBox(lags=20), "5s", alphas, step="1s")
    assert list(tab.index) == list(alphas)
    np.testing.assert_allclose(tab[["correct", "wrong", "ambiguous", "none"]].sum(axis=1), 100.0)
    # windows: every fault fitting record cut into 5 s windows 1 s apart, over 2 faults x 3 records
    n = [(e.shape[0] - (500 - 2)) // 100 + 1 for f in b.faults for e in b.heldout[("var", f)]]
    assert (tab["windows"] == sum(n)).all()
    # at alpha ~ 0 no test rejects: every window accepts every model
    assert tab.loc[1e-300, "ambiguous"] == 100.0
    # the same windows in samples; the test's own alpha does not matter, LjungBox(lags=20) is the default
    for same in (b.select_alpha("var", LjungBox(lags=20, alpha=0.3), 500, alphas, step=100),
                 b.select_alpha("var", None, "5s", alphas)):
        pd.testing.assert_frame_equal(same, tab, check_exact=True)
        assert same.attrs == tab.attrs
    # the first window of every fault fitting record, recomputed with LjungBox: through its own state's model
    # refitted without it (held out) and through the other state's model (never fitted on it)
    for a in alphas[:2]:
        test = tsfdi.LjungBox(lags=20, alpha=a)
        count = dict.fromkeys(("correct", "wrong", "ambiguous", "none"), 0)
        for f in b.faults:
            for j, seg in enumerate(b.segments[f]):
                acc = {g: not test.test((b.heldout[("var", f)][j] if g == f else
                                         np.asarray(b.models["var"][g].residuals(seg)))[:500 - 2]).reject
                       for g in b.faults}
                hit = [g for g, ok in acc.items() if ok]
                count["none" if not hit else "ambiguous" if len(hit) > 1 else
                      "correct" if hit[0] == f else "wrong"] += 1
        one = b.select_alpha("var", LjungBox(lags=20), "5s", [a], step="1000s")   # one window per record
        assert one.loc[a, "windows"] == 6
        for k, v in count.items():
            assert one.loc[a, k] == pytest.approx(100.0 * v / 6)
    best = tab["correct"].max()
    assert tab.attrs["selected"] == max(a for a in alphas if tab.loc[a, "correct"] >= best)
    with pytest.raises(ValueError, match="alphas"):
        b.select_alpha("var", LjungBox(lags=20), "5s", [0.0])
    with pytest.raises(ValueError, match="model"):
        b.select_alpha("nope", LjungBox(lags=20), "5s")
    with pytest.raises(TypeError, match="test"):
        b.select_alpha("var", "whiteness", "5s")
    with pytest.raises(ValueError, match="empirical"):
        b.select_alpha("var", LjungBox(lags=20, threshold="empirical"), "5s")
    with pytest.raises(TypeError, match="window"):
        b.select_alpha("var", LjungBox(lags=20), 5.0)
    with pytest.raises(TypeError, match="step"):
        b.select_alpha("var", LjungBox(lags=20), "5s", step=1.0)
    with pytest.raises(ValueError, match="calibrate=True"):
        tsfdi.fit_baselines(recs, **kw).select_alpha("var", LjungBox(lags=20), "5s")


def test_empirical_thresholds_leave_one_out(synthetic):
    """fit_baselines(calibrate=True): leave-one-record-out residuals; evaluate with tests built with
    threshold="empirical" uses each model's thresholds calibrated on them (never on evaluation records)."""
    recs, states, ft = synthetic
    kw = dict(states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, order=2, max_lags=4,
              var_max_lags=4, steady_window="5s", fit_records=3, models=["var", "y0"])
    b = tsfdi.fit_baselines(recs, calibrate=True, **kw)
    assert set(b.heldout) == {(m, s) for m in ("var", "y0") for s in ("healthy", "f1", "f2")}
    # record 1 of f1 left out: VAR(2) refitted on the other two f1 fitting records
    segs = b.segments["f1"]
    ref = tsfdi.VAR([segs[0], segs[2]], 2, hold_back=4).fit().residuals(segs[1])
    np.testing.assert_allclose(b.heldout[("var", "f1")][1], np.asarray(ref), rtol=1e-10)
    y0 = tsfdi.AR([segs[1][:, 0], segs[2][:, 0]], 2, hold_back=4).fit().residuals(segs[0][:, 0])
    np.testing.assert_allclose(b.heldout[("y0", "f1")][0][:, 0], np.asarray(y0), rtol=1e-10)
    lb = LjungBox(lags=20, alpha=0.01, correction="none", threshold="empirical")
    cal = b.calibrated_tests("var", lb, "5s")
    assert set(cal) == {"healthy", "f1", "f2"} and all(t.empirical for t in cal.values())
    assert not lb.calibrated and all(t is not lb for t in cal.values())          # the given test is not modified
    st = np.concatenate([tsfdi.detection.ljungbox_windows(e, 20, 500 - 2, 1) for e in b.heldout[("var", "f2")]])
    np.testing.assert_allclose(cal["f2"].threshold_, np.quantile(st, 0.99, axis=0))
    # cached: the same test (an equal one too), window and step, whether the window is a time span or samples
    assert b.calibrated_tests("var", lb, "5s") is cal
    equal = LjungBox(lags=20, alpha=0.01, correction="none", threshold="empirical")
    assert b.calibrated_tests("var", equal, 500) is cal
    assert b.calibrated_tests("var", lb, "5s", step=2) is not cal
    # a test with other options is calibrated anew, even where its repr does not show them
    other = b.calibrated_tests("var", LjungBox(lags=20, alpha=0.01, correction="none", threshold="empirical",
                                               demean=False), "5s")
    assert other is not cal and not other[b.healthy].demean
    ev = tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=FS, models=("var",),
                        tests={"whiteness": lb,
                               "variance": FTest(alpha=0.01, correction="none", threshold="empirical")},
                        windows=("5s",), settle=5.0, progress=False)
    assert ev.thresholds == "empirical"
    assert not set(ev.records.loc[ev.records["evaluated"], "record"]) & set(b.fit_records)
    c = ev.calibration.set_index(["method", "state", "channel"]).sort_index()
    np.testing.assert_allclose(c.loc[("whiteness", "f2"), "empirical"], cal["f2"].threshold_)
    np.testing.assert_allclose(c.loc[("whiteness", "f2"), "distribution"], stats.chi2.ppf(0.99, 20))
    # detection decisions are those of the calibrated healthy test on each window (500 samples, 498 residuals of
    # VAR(2), 1 s apart) of the healthy evaluated records
    alarms = 0
    for i in np.flatnonzero(ev.records["evaluated"] & (ev.records["state"] == "healthy")):
        e = np.asarray(b.models["var"]["healthy"].residuals(recs[i]))
        alarms += sum(bool(cal["healthy"].test(e[s:s + 500 - 2]).reject) for s in range(0, len(recs[i]) - 499, 100))
    d = ev.detection_counts.query("model == 'var' and method == 'whiteness' and state == 'healthy'")
    assert 0 < alarms == d.loc[d["alarm"], "windows"].sum()
    # the theoretical threshold on the same baselines gives the distributional thresholds
    ev2 = tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=FS, models=("var",), windows=("5s",),
                         tests={"whiteness": LjungBox(lags=20, alpha=0.01)}, settle=5.0, progress=False)
    assert ev2.thresholds == "theoretical" and "empirical" not in ev2.calibration
    mon = b.monitor("var", window="5s", test=lb)
    assert mon.test["f1"] is cal["f1"] and mon.detection_test is cal["healthy"]
    out = mon.run(recs[5])
    assert out.detection_time is not None
    fitted_plain = tsfdi.fit_baselines(recs, **kw)
    with pytest.raises(ValueError, match="calibrate=True"):
        tsfdi.evaluate(recs, fitted_plain, states=states, failure_times=ft, fs=FS, windows=("5s",), settle=5.0,
                       progress=False, tests=lb)
    with pytest.raises(ValueError, match="calibrate=True"):
        fitted_plain.monitor("var", window="5s", test=lb)
    with pytest.raises(ValueError, match="threshold"):
        tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=FS, windows=("5s",), progress=False,
                       tests=LjungBox(lags=20, threshold="gpd"))
    with pytest.raises(ValueError, match="at least 200000 are needed"):
        b.calibrated_tests("var", LjungBox(lags=20, alpha=1e-6, correction="none", threshold="empirical"), "5s")
    with pytest.raises(ValueError, match="empirical"):
        b.calibrated_tests("var", LjungBox(lags=20, alpha=0.01), "5s")
    with pytest.raises(TypeError, match="calibrate"):
        tsfdi.fit_baselines(recs, calibrate="yes", **kw)


def test_records_names_and_origin(tmp_path):
    """Records.names() tells records apart by the shortest tail of their files' paths (the record column of the
    command line's tables), Records.origin(i) names a record's file and id as messages do."""
    t = np.arange(200) / 100.0
    for folder in ("run1", "run2"):
        (tmp_path / folder).mkdir()
        pd.DataFrame({"time": t, "x": np.sin(t), "y": np.cos(t)}).to_csv(tmp_path / folder / "log.csv", index=False)
    one = tsfdi.read_records(tmp_path / "run1" / "log.csv")
    assert one.names() == [""] and one.origin(0) == str(tmp_path / "run1" / "log.csv")
    two = tsfdi.read_records([tmp_path / "run1" / "log.csv", tmp_path / "run2" / "log.csv"])
    assert two.names() == ["run1/log.csv", "run2/log.csv"]
    assert two.origin(1) == str(tmp_path / "run2" / "log.csv")
    # pieces of split files: the piece's id after the file's tail (and after the file's name in messages)
    pieces = tsfdi.read_records([tmp_path / "run1" / "log.csv", tmp_path / "run2" / "log.csv"],
                                rows_where="x<0.5")
    assert pieces.names()[0] == "run1/log.csv:0" and pieces.names()[-1].startswith("run2/log.csv:")
    assert pieces.origin(0) == f"{tmp_path / 'run1' / 'log.csv'} record 0"
    # records not read from files: their ids, record 0 included
    rec = Records.from_data([np.arange(5.0)[:, None], np.arange(5.0)[::-1, None]], states=["a", "b"])
    assert rec.names() == ["0", "1"] and rec.origin(0) == "record 0"


def test_constant_fitting_segment_named(synthetic):
    """A channel constant over a record's fitting segment is refused naming the record, its state and the channel
    (the models' own message named the segment's position in the pooled list, "y[0]", and for the VAR alone
    placeholder channels); a constant channel that no requested model reads is no error."""
    recs, states, ft = synthetic
    recs = [r.copy() for r in recs]
    recs[5][1500:, 1] = 0.25                    # record 5 (state f1): y1 stuck after the failure
    kw = dict(states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, max_lags=4, var_max_lags=4)
    for models in (["var"], ["y1"], None):
        with pytest.raises(ValueError, match=r"record 5 of state 'f1' is constant in channel\(s\) \['y1'\]"):
            tsfdi.fit_baselines(recs, models=models, **kw)
    assert tsfdi.fit_baselines(recs, models=["y0"], **kw).models["y0"]["f1"].lags >= 1


def test_records_validity_of_a_record_array():
    """Records.from_data of a (record, time, channel) array: a record holding NaN or an infinity is not valid, one
    whose values are finite but whose sum overflows is (the check sums each record once, then rechecks a record
    whose sum is not finite value by value)."""
    xr = pytest.importorskip("xarray")
    v = np.random.default_rng(0).standard_normal((5, 50, 2))
    v[1, 3, 0] = np.nan
    v[2, 7, 1] = np.inf
    v[3, 4, 0], v[3, 9, 1] = np.inf, -np.inf    # sum NaN
    v[4, :2, 0] = 1e308                         # finite values, sum overflows
    da = xr.DataArray(v, dims=("record", "time", "channel"),
                      coords={"time": np.arange(50) / 10, "channel": ["a", "b"], "state": ("record", ["h"] * 5)})
    rec = Records.from_data(da)
    assert rec.valid.tolist() == [True, False, False, False, True]
    np.testing.assert_array_equal(np.stack(rec.values), v)
    unread = Records.from_data(da, check_finite=False)         # the caller checks the records it uses
    assert unread.valid.all()
    np.testing.assert_array_equal(np.stack(unread.values), v)
    with pytest.raises(TypeError, match="check_finite"):
        Records.from_data(list(v), states=["h"] * 5, check_finite="no")


def test_records_rate_and_labels_from_the_coordinates():
    """Records.from_data reads fs, the channel names and the labels of a (record, time, channel) array from its
    coordinate variables: a time coordinate of any real dtype (float16 included, which a pandas index refuses), and
    positions (1 Hz) and channels 0, 1, ... when there is no coordinate."""
    xr = pytest.importorskip("xarray")
    v = np.random.default_rng(0).standard_normal((3, 40, 2))
    labels = {"state": ("record", ["h", "f", "f"]), "turbulence": ("record", ["light"] * 3)}
    for dtype in (np.float16, np.float32, np.int64):
        da = xr.DataArray(v, dims=("record", "time", "channel"),
                          coords={"time": (np.arange(40) * 2).astype(dtype), "channel": ["a", "b"], **labels})
        rec = Records.from_data(da)
        assert rec.fs == 0.5 and rec.channels == ("a", "b")
        assert rec.state.tolist() == ["h", "f", "f"] and rec.turbulence.tolist() == ["light"] * 3
    bare = Records.from_data(xr.DataArray(v, dims=("record", "time", "channel"), coords={"state": labels["state"]}))
    assert bare.fs == 1.0 and bare.channels == ("0", "1") and bare.ids.tolist() == [0, 1, 2]
    # a coordinate without an index (xarray's drop_indexes) is read from its variable, not the default positions
    loose = Records.from_data(da.drop_indexes(["time", "channel"]))
    assert loose.fs == 0.5 and loose.channels == ("a", "b")




def test_records_of_a_dask_array_read_no_record():
    """Records.from_data of a dask-backed (record, time, channel) array takes the channels, fs and length from its
    coordinates and reads no record (a fleet's chunks are read where they are used): a chunk that fails when read
    does not fail here; an array of other dims is refused naming the argument."""
    xr = pytest.importorskip("xarray")
    dask = pytest.importorskip("dask")
    da_ = pytest.importorskip("dask.array")

    def unreadable():
        raise AssertionError("a record was read")

    lazy = da_.from_delayed(dask.delayed(unreadable)(), (4, 30, 2), dtype=float)
    da = xr.DataArray(lazy, dims=("record", "time", "channel"),
                      coords={"time": np.arange(30) / 50, "channel": ["p", "q"], "state": ("record", ["h"] * 4)})
    rec = Records.from_data(da)
    assert rec.channels == ("p", "q") and rec.fs == pytest.approx(50.0) and rec.length == 30 and rec.source is da
    assert Records.from_data(da.transpose("time", "record", "channel"), fs=10).fs == 10.0
    with pytest.raises(TypeError, match=r"data backed by dask must be .*dims \('record', 'time'\)"):
        Records.from_data(da.isel(channel=0))


def test_fit_baselines_skips_non_finite_records_of_an_array(synthetic):
    """fit_baselines reads only the records it considers for fitting (Records.from_data(check_finite=False)): a
    record holding NaN is still skipped ("first" / an int per cell, "all") or refused (named fitting records), as
    when every record was checked first."""
    xr = pytest.importorskip("xarray")
    recs, states, ft = synthetic
    v = np.stack(recs)
    v[0, 50, 1] = np.nan                        # the first healthy record
    v[6, 3000, 0] = np.inf                      # the second record of f1
    da = xr.DataArray(v, dims=("record", "time", "channel"),
                      coords={"time": np.arange(v.shape[1]) / FS, "channel": ["y0", "y1"],
                              "state": ("record", states), "failure_time": ("record", ft)})
    kw = dict(settle=5.0, duration=None, max_lags=4, var_max_lags=4, models=["var"])
    assert tsfdi.fit_baselines(da, **kw).fit_records == (1, 5, 10)
    assert tsfdi.fit_baselines(da, fit_records=2, **kw).fit_records == (1, 2, 5, 7, 10, 11)
    assert 0 not in tsfdi.fit_baselines(da, fit_records="all", **kw).fit_records
    with pytest.raises(ValueError, match="lost control or hold NaN"):
        tsfdi.fit_baselines(da, fit_records=[0, 5, 10], **kw)


def test_combined_test_in_calibrated_tests_and_evaluate(synthetic):
    """AnyOf is calibrated per state by Baselines.calibrated_tests (cached by its options, its parts' included,
    even those its repr does not show) and evaluated with theoretical and calibrated thresholds: the calibration table
    holds the combined statistic and every part, and the expected false-alarm rate of Sidak-corrected parts is
    alpha (the decision's rate), not 1 - (1 - alpha)^k."""
    recs, states, ft = synthetic
    b = tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, order=2,
                            max_lags=4, var_max_lags=4, steady_window="5s", fit_records=3, models=["var"],
                            calibrate=True)

    def anyof(demean=True, correction="sidak"):
        return tsfdi.AnyOf([LjungBox(10, alpha=0.01, correction="sidak", demean=demean, threshold="empirical"),
                            FTest(alpha=0.01, correction="sidak", threshold="empirical")], correction=correction)

    cal = b.calibrated_tests("var", anyof(), "2s")
    assert set(cal) == {"healthy", "f1", "f2"} and all(t.calibrated for t in cal.values())
    assert b.calibrated_tests("var", anyof(), 200) is cal                      # an equal test: cached
    other = b.calibrated_tests("var", anyof(demean=False), "2s")                 # a part's option differs
    assert other is not cal and not other["f1"].tests[0].demean
    assert b.calibrated_tests("var", anyof(correction="minp"), "2s") is not cal
    kw = dict(states=states, failure_times=ft, fs=FS, models=("var",), windows=("2s",), settle=5.0, progress=False)
    ev = tsfdi.evaluate(recs, b, tests={"any": anyof(), "minp": anyof(correction="minp")}, **kw)
    c = ev.calibration.set_index(["method", "part", "state", "channel"]).sort_index()
    share = 1 - (1 - 0.01) ** (1 / 2)
    np.testing.assert_allclose(c.loc[("any", "0: LjungBox", "f2"), "empirical"], cal["f2"].tests[0].threshold_)
    np.testing.assert_allclose(c.loc[("any", "0: LjungBox", "f2"), "distribution"],
                               stats.chi2.isf(1 - (1 - share) ** (1 / 2), 10))
    np.testing.assert_allclose(c.loc[("any", "", "f2"), "distribution"], -2 * np.log(1 - (1 - 0.01) ** (1 / 4)))
    minp = b.calibrated_tests("var", anyof(correction="minp"), "2s")
    np.testing.assert_allclose(c.loc[("minp", "", "f1"), "empirical"], minp["f1"].threshold_)
    det = ev.detection_rates()
    assert det.loc[("var", "any", 2.0), "expected_false_alarm"] == pytest.approx(1.0)
    assert ev.alphas[("var", "any")] == pytest.approx(1 - 0.99 ** 0.5)
    ev_t = tsfdi.evaluate(recs, b, tests={"any": tsfdi.AnyOf([LjungBox(10, alpha=0.01, correction="none"),
                                                              FTest(alpha=0.01, correction="none")])}, **kw)
    assert ev_t.thresholds == "theoretical" and "empirical" not in ev_t.calibration
    # no correction over the channels: each channel at alpha, the decision at 1 - (1 - alpha)^2
    expected = ev_t.detection_rates().loc[("var", "any", 2.0), "expected_false_alarm"]
    assert expected == pytest.approx(100 * (1 - 0.99 ** 2))

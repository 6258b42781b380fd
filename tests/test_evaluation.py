"""fit_baselines (Table 2 analogue), evaluate (Table 4 analogue, rates, detection) and their helpers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from _synthetic_fdi import FS, dataset, record
from conftest import as_kind
from scipy import stats

import tsfdi
from tsfdi.evaluation import Evaluation, hexacopter_signals


@pytest.fixture(scope="module")
def synthetic():
    """5 records per state, 40 s at 100 Hz, failure at 10 s."""
    return dataset(5, 4000, 1000, np.random.default_rng(5))


@pytest.fixture(scope="module")
def fitted(synthetic):
    recs, states, ft = synthetic
    b = tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, max_lags=6,
                            var_max_lags=6, steady_window=5.0)
    return b


def test_baselines_table_and_exclusion(synthetic, fitted):
    b = fitted
    assert b.healthy == "healthy" and b.faults == ("f1", "f2")
    assert b.fit_records == (0, 5, 10)          # first record of each state
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
    # steady threshold: max 5 s rolling variance (0.1 s step) of the post-settle fault fitting records
    recs, _, _ = synthetic
    post = [recs[i][1500:] for i in (5, 10)]
    ref = np.max([tsfdi.monitoring.rolling_variance(p, 500, 10).max(axis=0) for p in post], axis=0)
    np.testing.assert_allclose(b.steady_thresholds, ref, rtol=1e-10)


def test_evaluate_synthetic(synthetic, fitted):
    recs, states, ft = synthetic
    ev = tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, models=("var", "y0"),
                        methods=("whiteness", "variance"), windows=(5.0, 20.0), settle=5.0,
                        alpha=1e-3, rules=("paper", "likelihood", "pvalue"), progress=False)
    # fitting records are excluded
    assert not set(ev.identification["record"]) & set(fitted.fit_records)
    assert set(ev.records.loc[~ev.records["evaluated"], "skipped"]) == {"fitting record"}
    # windows: starts >= failure + settle = 15 s, 1 s apart, up to 40 - W
    w20 = ev.identification.query("model == 'var' and method == 'whiteness' and window == 20.0")
    assert sorted(w20["start"].unique()) == list(np.arange(15.0, 21.0))
    assert len(w20) == 8 * 6
    rates = ev.rates()
    corr = rates.xs(("var", "whiteness", 20.0), level=("model", "method", "window"))["correct"]
    assert (corr.xs("paper", level="rule") >= 90).all()
    assert (corr.xs("likelihood", level="rule") == 100).all()
    t4 = ev.table4(20.0)
    assert t4.index.names == ["model", "method"] and list(t4.columns) == ["f1", "f2"]
    assert t4.loc[("var", "whiteness"), "f1"].count("/") == 1
    # detection: healthy-window false alarms within a binomial bound of 1 - (1 - alpha)^2 (windows overlap, so
    # the bound uses the number of disjoint 5 s windows)
    det = ev.detection_rates()
    row = det.loc[("var", "whiteness", 5.0)]
    p0 = 1 - (1 - 1e-3) ** 2
    n_disjoint = 4 * 8
    assert row["expected_false_alarm"] == pytest.approx(100 * p0)
    assert row["false_alarm"] / 100 <= stats.binom.ppf(0.999, n_disjoint, p0) / n_disjoint + 1e-12
    assert row["disjoint_windows"] == n_disjoint and row["false_alarm_pvalue"] > 1e-3
    assert row["missed_records"] == 0
    assert 0 < row["delay_median"] <= 5.0
    assert "Identification" in ev.summary()


def test_confusion_closed_form():
    """Hand-made windows: confusion, rates, Table 4 and detection rates from counts."""
    ident = pd.DataFrame({
        "record": [1, 1, 2, 2, 3, 3, 3, 3], "state": ["a"] * 4 + ["b"] * 4, "turbulence": "x", "model": "var",
        "method": "whiteness", "window": 5.0, "start": [0, 1, 0, 1, 0, 1, 2, 3],
        "acc_a": [True, True, True, False, False, True, False, False],
        "acc_b": [False, True, False, False, True, True, True, False],
        "label_paper": ["a", "ambiguous", "a", "none", "b", "ambiguous", "b", "none"],
        "label_likelihood": ["a", "a", "a", "b", "b", "a", "b", "b"]})
    det = pd.DataFrame({
        "record": [0, 0, 0, 0, 1, 1, 1, 1, 2, 2], "state": ["h"] * 4 + ["a"] * 6, "model": "var",
        "method": "whiteness", "window": 5.0, "start": [0, 1, 2, 3, 0, 5, 10, 0, 5, 10],
        "end": [5, 6, 7, 8, 5, 10, 15, 5, 10, 15], "failure_time": [np.nan] * 4 + [6.0] * 6,
        "fault_true": [False] * 4 + [False, False, True, False, False, True],
        "pre": [True] * 4 + [True, False, False, True, False, False],
        "alarm": [False, True, False, False, False, True, True, False, False, False]})
    recs = pd.DataFrame({"record": [0, 1, 2, 3]})
    recs.attrs["healthy"] = "h"
    ev = Evaluation(identification=ident, detection=det, faults=("a", "b"), rules=("paper", "likelihood"),
                    alphas={("var", "whiteness"): 0.01}, lags={5.0: 20}, records=recs, nchan={"var": 3})
    conf = ev.confusion("paper").xs(("var", "whiteness", 5.0), level=("model", "method", "window"))
    np.testing.assert_allclose(conf.loc["a"], [75.0, 25.0])
    np.testing.assert_allclose(conf.loc["b"], [25.0, 75.0])
    conf = ev.confusion("likelihood").xs(("var", "whiteness", 5.0), level=("model", "method", "window"))
    np.testing.assert_allclose(conf.loc["a"], [75.0, 25.0])
    np.testing.assert_allclose(conf.loc["b"], [25.0, 75.0])
    r = ev.rates().xs(("var", "whiteness", 5.0), level=("model", "method", "window"))
    np.testing.assert_allclose(r.loc[("a", "paper"), ["correct", "wrong", "ambiguous", "none"]], [50, 0, 25, 25])
    np.testing.assert_allclose(r.loc[("b", "paper"), ["correct", "wrong", "ambiguous", "none"]], [50, 0, 25, 25])
    np.testing.assert_allclose(r.loc[("b", "likelihood"), ["correct", "wrong", "ambiguous", "none"]], [75, 25, 0, 0])
    assert r.loc[("a", "paper"), "windows"] == 4
    assert ev.table4(5.0).loc[("var", "whiteness"), "a"] == "75.00/25.00"
    d = ev.detection_rates().loc[("var", "whiteness", 5.0)]
    assert d["false_alarm"] == pytest.approx(25.0)
    assert d["expected_false_alarm"] == pytest.approx(100 * (1 - 0.99 ** 3))
    assert d["missed_fault"] == pytest.approx(50.0)         # 2 post-failure windows, 1 alarm
    assert d["missed_records"] == 1                          # record 2: no alarm after the failure
    assert d["delay_median"] == pytest.approx(4.0)           # first alarm window ends at 10 s, failure at 6 s
    # only the window starting at 0 s of the healthy record does not overlap another: the alarm at 1 s is not
    # an independent trial
    assert (d["disjoint_windows"], d["disjoint_alarms"], d["false_alarm_pvalue"]) == (1, 0, 1.0)
    det2 = det.assign(start=[0, 5, 10, 15] + det["start"].tolist()[4:], alarm=[True, False, False, True]
                      + det["alarm"].tolist()[4:])
    d2 = Evaluation(identification=ident, detection=det2, faults=("a", "b"), rules=("paper", "likelihood"),
                    alphas={("var", "whiteness"): 0.01}, lags={5.0: 20}, records=recs,
                    nchan={"var": 3}).detection_rates().loc[("var", "whiteness", 5.0)]
    p0 = 1 - 0.99 ** 3
    assert (d2["disjoint_windows"], d2["disjoint_alarms"]) == (4, 2)
    assert d2["false_alarm_pvalue"] == pytest.approx(1 - (1 - p0) ** 4 - 4 * p0 * (1 - p0) ** 3)
    with pytest.raises(ValueError, match="window"):
        ev.table4(7.0)


def test_fit_baselines_data_kinds(kind):
    rng = np.random.default_rng(7)
    segs = {s: as_kind(record(s, 3000, rng), kind) for s in ("healthy", "f1", "f2")}
    b = tsfdi.fit_baselines(segs, max_lags=4, var_max_lags=4, models=["var"])
    assert b.faults == ("f1", "f2")
    assert all(b.models["var"][s].lags == 2 for s in segs)
    assert b.monitor("var", window=10.0, lags=10).nchan == 2


def test_hexacopter_signals():
    t = np.arange(6) / 100.0
    ds = xr.Dataset({v: (("record", "time"), np.arange(12.0).reshape(2, 6) * k)
                     for v, k in (("roll", 1.0), ("pitch", 2.0), ("yaw", 3.0))},
                    coords={"record": [0, 1], "time": t, "state": ("record", ["healthy", "rotor1"]),
                            "failure_time": ("record", [np.nan, 0.02])})
    da = hexacopter_signals(ds)
    assert da.dims == ("record", "time", "channel")
    assert list(da["channel"].values) == ["roll", "pitch", "yaw_rate"]
    np.testing.assert_allclose(da["time"].values, t[1:])
    np.testing.assert_allclose(da.values[0, :, 2], 3.0 * 100.0)           # diff(3 t) * fs
    np.testing.assert_allclose(da.values[1, :, 0], np.arange(7.0, 12.0))
    assert list(da["state"].values) == ["healthy", "rotor1"]
    with pytest.raises(TypeError, match="data"):
        hexacopter_signals(ds["roll"])
    with pytest.raises(ValueError, match="yaw"):
        hexacopter_signals(ds, yaw="heading")
    # a dataset with the body yaw rate r: the yaw_rate channel is r itself, every sample kept
    ds_r = ds.assign(r=(("record", "time"), np.arange(12.0).reshape(2, 6) * 5.0))
    da_r = hexacopter_signals(ds_r)
    np.testing.assert_allclose(da_r["time"].values, t)
    np.testing.assert_allclose(da_r.values[..., 2], ds_r["r"].values)
    np.testing.assert_allclose(da_r.values[..., 1], ds["pitch"].values)
    np.testing.assert_allclose(hexacopter_signals(ds_r, yaw="angle").values[..., 2], ds["yaw"].values)
    with pytest.raises(ValueError, match="r"):
        hexacopter_signals(ds_r.drop_vars("roll"))


def test_bad_input(synthetic, fitted):
    recs, states, ft = synthetic
    with pytest.raises(ValueError, match="states"):
        tsfdi.fit_baselines(recs, fs=FS)
    with pytest.raises(ValueError, match="healthy"):
        tsfdi.fit_baselines(recs, states=states, healthy="nominal", fs=FS)
    with pytest.raises(ValueError, match="models"):
        tsfdi.fit_baselines(recs, states=states, fs=FS, models=["altitude"])
    with pytest.raises(TypeError, match="baselines"):
        tsfdi.evaluate(recs, {"x": 1}, states=states, fs=FS)
    with pytest.raises(ValueError, match="models"):
        tsfdi.evaluate(recs, fitted, states=states, fs=FS, models=("roll",))
    with pytest.raises(ValueError, match="methods"):
        tsfdi.evaluate(recs, fitted, states=states, fs=FS, methods=("spectral",))
    with pytest.raises(ValueError, match="Hz"):
        tsfdi.evaluate(recs, fitted, states=states, fs=50.0)
    with pytest.raises(ValueError, match="channels"):
        tsfdi.evaluate([r[:, :1] for r in recs], fitted, states=states, fs=FS)
    with pytest.raises(TypeError, match="data"):
        tsfdi.evaluate("records.csv", fitted)
    with pytest.raises(ValueError, match="alpha"):
        tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, alpha=2.0, progress=False)


def test_fit_baselines_pooled_records(synthetic):
    """fit_records=n pools the first n records of each state without junctions (= the list fit of the models);
    order options; in-sample whiteness column."""
    from scipy import stats

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
              var_max_lags=4, steady_window=5.0, fit_records=3, models=["var"])
    b = tsfdi.fit_baselines(recs, calibrate=True, **kw)
    alphas = (1e-2, 1e-4, 1e-300)
    tab = b.select_alpha("var", "whiteness", 5.0, alphas, step=1.0)
    assert list(tab.index) == list(alphas)
    np.testing.assert_allclose(tab[["correct", "wrong", "ambiguous", "none"]].sum(axis=1), 100.0)
    # windows: every fault fitting record cut into 5 s windows 1 s apart, over 2 faults x 3 records
    n = [(e.shape[0] - (500 - 2)) // 100 + 1 for f in b.faults for e in b.heldout[("var", f)]]
    assert (tab["windows"] == sum(n)).all()
    # at alpha ~ 0 no test rejects: every window accepts every model
    assert tab.loc[1e-300, "ambiguous"] == 100.0
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
        one = b.select_alpha("var", "whiteness", 5.0, [a], step=1000.0)   # one window per record
        assert one.loc[a, "windows"] == 6
        for k, v in count.items():
            assert one.loc[a, k] == pytest.approx(100.0 * v / 6)
    best = tab["correct"].max()
    assert tab.attrs["selected"] == max(a for a in alphas if tab.loc[a, "correct"] >= best)
    with pytest.raises(ValueError, match="alphas"):
        b.select_alpha("var", "whiteness", 5.0, [0.0])
    with pytest.raises(ValueError, match="model"):
        b.select_alpha("nope", "whiteness", 5.0)
    with pytest.raises(ValueError, match="calibrate=True"):
        tsfdi.fit_baselines(recs, **kw).select_alpha("var", "whiteness", 5.0)


def test_empirical_thresholds_leave_one_out(synthetic):
    """fit_baselines(calibrate=True): leave-one-record-out residuals; evaluate(thresholds="empirical") uses each
    model's thresholds calibrated on them (never on evaluation records)."""
    recs, states, ft = synthetic
    kw = dict(states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, order=2, max_lags=4,
              var_max_lags=4, steady_window=5.0, fit_records=3, models=["var", "y0"])
    b = tsfdi.fit_baselines(recs, calibrate=True, **kw)
    assert set(b.heldout) == {(m, s) for m in ("var", "y0") for s in ("healthy", "f1", "f2")}
    # record 1 of f1 left out: VAR(2) refitted on the other two f1 fitting records
    segs = b.segments["f1"]
    ref = tsfdi.VAR([segs[0], segs[2]], 2, hold_back=4).fit().residuals(segs[1])
    np.testing.assert_allclose(b.heldout[("var", "f1")][1], np.asarray(ref), rtol=1e-10)
    y0 = tsfdi.AR([segs[1][:, 0], segs[2][:, 0]], 2, hold_back=4).fit().residuals(segs[0][:, 0])
    np.testing.assert_allclose(b.heldout[("y0", "f1")][0][:, 0], np.asarray(y0), rtol=1e-10)
    cal = b.calibrated_tests("var", "whiteness", 5.0, alpha=0.01)
    assert set(cal) == {"healthy", "f1", "f2"} and all(t.empirical for t in cal.values())
    st = np.concatenate([tsfdi.detection.ljungbox_windows(e, 20, 500 - 2, 1) for e in b.heldout[("var", "f2")]])
    np.testing.assert_allclose(cal["f2"].threshold_, np.quantile(st, 0.99, axis=0))
    assert b.calibrated_tests("var", "whiteness", 5.0, alpha=0.01) is cal         # cached
    ev = tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=FS, models=("var",),
                        methods=("whiteness", "variance"), windows=(5.0,), settle=5.0, alpha=0.01,
                        progress=False, thresholds="empirical")
    assert ev.thresholds == "empirical"
    assert not set(ev.identification["record"]) & set(b.fit_records)
    c = ev.calibration.set_index(["method", "state", "channel"]).sort_index()
    np.testing.assert_allclose(c.loc[("whiteness", "f2"), "empirical"], cal["f2"].threshold_)
    np.testing.assert_allclose(c.loc[("whiteness", "f2"), "distribution"], stats.chi2.ppf(0.99, 20))
    # detection decisions are those of the calibrated healthy test on each window
    rec5 = recs[4]                                                               # healthy, evaluated
    d = ev.detection[(ev.detection["record"] == 4) & (ev.detection["method"] == "whiteness")]
    e = np.asarray(b.models["var"]["healthy"].residuals(rec5))
    first = cal["healthy"].test(e[:500 - 2])
    assert bool(d["alarm"].iloc[0]) == first.reject
    # chi-square run on the same baselines gives the distributional thresholds
    ev2 = tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=FS, models=("var",), windows=(5.0,),
                         settle=5.0, alpha=0.01, progress=False)
    assert ev2.thresholds == "chi2" and "empirical" not in ev2.calibration
    mon = b.monitor("var", window=5.0, alpha=0.01, thresholds="empirical")
    assert mon.test["f1"] is cal["f1"] and mon.detection_test is cal["healthy"]
    out = mon.run(recs[5])
    assert out.detection_time is not None
    fitted_plain = tsfdi.fit_baselines(recs, **kw)
    with pytest.raises(ValueError, match="calibrate=True"):
        tsfdi.evaluate(recs, fitted_plain, states=states, failure_times=ft, fs=FS, windows=(5.0,), settle=5.0,
                       progress=False, thresholds="empirical")
    with pytest.raises(ValueError, match="thresholds"):
        tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=FS, windows=(5.0,), progress=False,
                       thresholds="gpd")
    with pytest.raises(ValueError, match="at least 200000 are needed"):
        b.calibrated_tests("var", "whiteness", 5.0, alpha=1e-6)
    with pytest.raises(TypeError, match="calibrate"):
        tsfdi.fit_baselines(recs, calibrate="yes", **kw)


def test_bank_per_record_models(synthetic):
    """Baselines.bank refits each state's model on each fitting record alone; evaluate / select_alpha / monitor
    with bank=True test every state by its bank (a window is accepted when any member accepts)."""
    from tsfdi.monitoring import window_statistics

    recs, states, ft = synthetic
    kw = dict(states=states, failure_times=ft, fs=FS, settle=5.0, duration=None, order=2, max_lags=4,
              var_max_lags=4, steady_window=5.0, fit_records=3, models=["var", "y0"])
    b = tsfdi.fit_baselines(recs, **kw)
    bank = b.bank("var", "f1")
    assert len(bank) == 3 and b.bank("var", "f1") is bank                         # cached
    for seg, res in zip(b.segments["f1"], bank):
        np.testing.assert_allclose(res.params, tsfdi.VAR(seg, 2, hold_back=4).fit().params, rtol=1e-10)
    np.testing.assert_allclose(b.bank("y0", "f2")[1].params,
                               tsfdi.AR(b.segments["f2"][1][:, 0], 2, hold_back=4).fit().params, rtol=1e-10)
    assert b.state_models("var")["f1"] is b.models["var"]["f1"]
    assert b.state_models("var", bank=True)["f1"] is bank
    ev = tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=FS, models=("var",), windows=(5.0,),
                        settle=5.0, alpha=0.01, progress=False, bank=True)
    assert ev.bank
    # detection alarms of a healthy evaluation record: every healthy member rejects
    ws = window_statistics(recs[4], {f"m{i}": m for i, m in enumerate(b.bank("var", "healthy"))},
                           tsfdi.LjungBox(lags=20, alpha=0.01), window=500, step=100)
    alarms = np.all([d["reject"] for d in ws["decisions"].values()], axis=0)
    det = ev.detection[ev.detection["record"] == 4]
    np.testing.assert_array_equal(det["alarm"].to_numpy(), alarms)
    # identification of a fault window: accepted by a state when one of its members accepts
    row = ev.identification[ev.identification["record"] == 8].iloc[0]
    s0 = int(round(row["start"] * FS))
    for f in b.faults:
        acc = any(not tsfdi.LjungBox(lags=20, alpha=0.01).test(np.asarray(m.residuals(recs[8][s0:s0 + 500]))).reject
                  for m in b.bank("var", f))
        assert row[f"acc_{f}"] == acc
    mon = b.monitor("var", window=5.0, alpha=0.01, bank=True)
    assert mon.baseline is b.bank("var", "healthy") and mon.models["f2"] is b.bank("var", "f2")
    # select_alpha with banks: the held-out record's own state is its bank without that record's member
    tab = b.select_alpha("var", "whiteness", 5.0, (1e-2, 1e-300), bank=True)
    np.testing.assert_allclose(tab[["correct", "wrong", "ambiguous", "none"]].sum(axis=1), 100.0)
    assert tab.loc[1e-300, "ambiguous"] == 100.0
    one = b.select_alpha("var", "whiteness", 5.0, [1e-2], step=1000.0, bank=True)    # one window per record
    test = tsfdi.LjungBox(lags=20, alpha=1e-2)
    count = dict.fromkeys(("correct", "wrong", "ambiguous", "none"), 0)
    for f in b.faults:
        for j, seg in enumerate(b.segments[f]):
            hit = [g for g in b.faults
                   if any(not test.test(np.asarray(m.residuals(seg))[:500 - 2]).reject
                          for i, m in enumerate(b.bank("var", g)) if g != f or i != j)]
            count["none" if not hit else "ambiguous" if len(hit) > 1 else
                  "correct" if hit[0] == f else "wrong"] += 1
    for k, v in count.items():
        assert one.loc[1e-2, k] == pytest.approx(100.0 * v / 6)
    with pytest.raises(ValueError, match="thresholds='chi2'"):
        tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=FS, windows=(5.0,), progress=False,
                       thresholds="empirical", bank=True)
    with pytest.raises(TypeError, match="bank"):
        b.monitor("var", window=5.0, bank="yes")
    with pytest.raises(ValueError, match="state"):
        b.bank("var", "f9")
    first = tsfdi.fit_baselines(recs, **{**kw, "fit_records": 1})
    with pytest.raises(ValueError, match="two fitting records"):
        first.select_alpha("var", "whiteness", 5.0, bank=True)

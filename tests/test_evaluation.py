"""evaluate (Table 4 analogue, rates, detection), Evaluation and hexacopter_signals; the baselines are tested in
test_baselines.py."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from _synthetic_fdi import FS
from _synthetic_fdi import record as _synthetic_record
from scipy import stats

import tsfdi
from tsfdi import FTest, LjungBox
from tsfdi.datasets.hexacopter import hexacopter_signals
from tsfdi.evaluation import Evaluation
from tsfdi.windows import ResidualWindows, decide


def test_evaluate_synthetic(synthetic, fitted):
    recs, states, ft = synthetic
    ev = tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, models=("var", "y0"),
                        tests={"whiteness": LjungBox(lags=20, alpha=1e-3, correction="none"),
                               "variance": FTest(alpha=1e-3, correction="none")},
                        windows=("5s", "20s"), settle=5.0, rules=("paper", "likelihood", "pvalue"), progress=False)
    assert ev.thresholds == "theoretical"
    assert ev.alphas == {(m, meth): 1e-3 for m in ("var", "y0") for meth in ("whiteness", "variance")}
    assert ev.lags == {5.0: 20, 20.0: 20} and ev.nchan == {"var": 2, "y0": 1}
    # fitting records are excluded
    assert not set(ev.records.loc[ev.records["evaluated"], "record"]) & set(fitted.fit_records)
    assert set(ev.records.loc[~ev.records["evaluated"], "skipped"]) == {"fitting record"}
    # windows: starts >= failure + settle = 15 s, 1 s apart, up to 40 - W: 6 per fault record, 8 of them
    w20 = ev.identification_counts.query("model == 'var' and method == 'whiteness' and window == 20.0")
    assert w20["windows"].sum() == 8 * 6
    # detection: every 20 s window of the 12 evaluated records (4 healthy, 8 faulty), (40 - 20) / 1 + 1 each
    d20 = ev.detection_counts.query("model == 'var' and method == 'whiteness' and window == 20.0")
    assert d20["windows"].sum() == 12 * 21
    # the counts are one row per distinct outcome
    assert not ev.identification_counts.drop(columns="windows").duplicated().any()
    assert not ev.detection_counts.drop(columns="windows").duplicated().any()
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
    summ = ev.summary()
    assert isinstance(summ, tsfdi.summary.Summary) and "Identification, 20 s windows" in str(summ)
    assert dict(summ.header)["Identification windows"] == int(ev.identification_counts["windows"].sum())
    assert summ.tables[-1][1].equals(det) and "<table>" in ev._repr_html_()


def _counted(windows: pd.DataFrame, count: str = "windows") -> pd.DataFrame:
    """Hand-made per-window (or per-record) rows collapsed to counts of their distinct rows, as evaluate keeps them."""
    return windows.groupby(list(windows.columns), sort=False, dropna=False).size().rename(count).reset_index()


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
    keys = ["turbulence", "model", "method", "window", "state"]

    def evaluation(det):
        flags = det.assign(turbulence="x", disjoint=det["start"] % det["window"] == 0)
        delays = pd.DataFrame({"turbulence": "x", "model": "var", "method": "whiteness", "window": 5.0, "state": "a",
                               "delay": [4.0, np.nan]})         # record 1: 10 s - 6 s; record 2: no alarm after 6 s
        return Evaluation(identification_counts=_counted(ident.drop(columns=["record", "start"])),
                          detection_counts=_counted(flags[keys + ["fault_true", "pre", "alarm", "disjoint"]]),
                          detection_delays=_counted(delays, "records"), faults=("a", "b"),
                          rules=("paper", "likelihood"), alphas={("var", "whiteness"): 0.01}, lags={5.0: 20},
                          records=recs, nchan={"var": 3})

    ev = evaluation(det)
    assert ev.identification_counts["windows"].tolist() == [2, 1, 1, 2, 1, 1]     # rows 0 / 2 and 4 / 6 alike
    assert ev.detection_counts["windows"].tolist() == [1, 1, 2, 2, 1, 1, 1, 1]
    # decisions per true state: the faults decided, then ambiguous and none; every row adds to 100
    conf = ev.confusion("paper").xs(("var", "whiteness", 5.0), level=("model", "method", "window"))
    assert list(conf.columns) == ["a", "b", "ambiguous", "none"]
    np.testing.assert_allclose(conf.loc["a"], [50.0, 0.0, 25.0, 25.0])
    np.testing.assert_allclose(conf.loc["b"], [0.0, 50.0, 25.0, 25.0])
    conf = ev.confusion("likelihood").xs(("var", "whiteness", 5.0), level=("model", "method", "window"))
    np.testing.assert_allclose(conf.loc["a"], [75.0, 25.0, 0.0, 0.0])
    np.testing.assert_allclose(conf.loc["b"], [25.0, 75.0, 0.0, 0.0])
    np.testing.assert_allclose(conf.sum(axis=1), 100.0)
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
    d2 = evaluation(det2).detection_rates().loc[("var", "whiteness", 5.0)]
    p0 = 1 - 0.99 ** 3
    assert (d2["disjoint_windows"], d2["disjoint_alarms"]) == (4, 2)
    # two-sided: twice the smaller tail, P(X >= 2) here
    assert d2["false_alarm_pvalue"] == pytest.approx(2 * (1 - (1 - p0) ** 4 - 4 * p0 * (1 - p0) ** 3))
    assert (d2["disjoint_band_low"], d2["disjoint_band_high"]) == tuple(stats.binom.ppf([0.005, 0.995], 4, p0))
    assert d2["false_alarm_in_band"] == (d2["disjoint_band_low"] <= 2 <= d2["disjoint_band_high"])
    with pytest.raises(ValueError, match="window"):
        ev.table4(7.0)


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
    with pytest.raises(TypeError, match="baselines"):
        tsfdi.evaluate(recs, {"x": 1}, states=states, fs=FS)
    with pytest.raises(ValueError, match="models"):
        tsfdi.evaluate(recs, fitted, states=states, fs=FS, models=("roll",))
    with pytest.raises(TypeError, match="tests"):
        tsfdi.evaluate(recs, fitted, states=states, fs=FS, tests=("spectral",))
    with pytest.raises(TypeError, match="tests"):
        tsfdi.evaluate(recs, fitted, states=states, fs=FS, tests={"spectral": "whiteness"})
    with pytest.raises(TypeError, match="tests"):
        tsfdi.evaluate(recs, fitted, states=states, fs=FS, models=("var", "y0"),
                       tests={"whiteness": {"var": LjungBox(lags=20)}})
    with pytest.raises(ValueError, match="Hz"):
        tsfdi.evaluate(recs, fitted, states=states, fs=50.0)
    with pytest.raises(ValueError, match="channels"):
        tsfdi.evaluate([r[:, :1] for r in recs], fitted, states=states, fs=FS)
    with pytest.raises(TypeError, match="data"):
        tsfdi.evaluate("records.csv", fitted)
    with pytest.raises(ValueError, match="alpha"):
        tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, tests=LjungBox(lags=20, alpha=2.0),
                       progress=False)
    # windows and step: ints count samples, time spans need the sampling frequency, floats are refused
    with pytest.raises(TypeError, match="windows"):
        tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, windows=(5.0,), progress=False)
    with pytest.raises(TypeError, match="step"):
        tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, windows=("5s",), step=1.0,
                       progress=False)
    with pytest.raises(ValueError, match="windows"):
        tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, windows=("1ms",), progress=False)


def test_absent_parts_are_left_out_or_refused_by_name(synthetic, fitted):
    """detection=False: empty detection tables, no detection part in the summary, detection_rates refused naming
    the option (it raised a raw KeyError, and so did summary()); no fault record evaluated: no Table 4."""
    recs, states, ft = synthetic
    kw = dict(states=states, failure_times=ft, fs=FS, windows=("5s",), settle=5.0, progress=False)
    full = tsfdi.evaluate(recs, fitted, **kw)
    ev = tsfdi.evaluate(recs, fitted, detection=False, **kw)
    assert ev.detection_counts.empty and ev.detection_delays.empty
    assert list(ev.detection_counts.columns) == list(full.detection_counts.columns)
    assert list(ev.detection_delays.columns) == list(full.detection_delays.columns)
    pd.testing.assert_series_equal(ev.detection_counts.dtypes, full.detection_counts.dtypes)
    pd.testing.assert_series_equal(ev.detection_delays.dtypes, full.detection_delays.dtypes)
    with pytest.raises(ValueError, match="no detection windows: evaluate was run with detection=False"):
        ev.detection_rates()
    # the summary of the run with detection, less its detection part; the identification tables are the same
    summ, ref = ev.summary(), full.summary()
    assert summ.header == [row for row in ref.header if row[0] != "Detection windows"]
    assert [title for title, _ in summ.tables] == [title for title, _ in ref.tables][:-1]
    assert ref.tables[-1][0] == "Detection with the healthy model" and "Detection" not in str(summ)
    for (_, mine), (_, theirs) in zip(summ.tables, ref.tables):
        pd.testing.assert_frame_equal(mine, theirs)
    assert "<table>" in ev._repr_html_() and "0 detection" in repr(ev)
    pd.testing.assert_frame_equal(ev.identification_counts, full.identification_counts)
    # healthy records only (record 0 is a fitting record): nothing to identify, detection as usual
    healthy = [i for i, s in enumerate(states) if s == "healthy"]
    ev = tsfdi.evaluate([recs[i] for i in healthy], fitted, **{**kw, "states": [states[i] for i in healthy],
                                                              "failure_times": ft[healthy]})
    assert ev.identification_counts.empty and ev.rates().empty
    pd.testing.assert_series_equal(ev.identification_counts.dtypes, full.identification_counts.dtypes)
    with pytest.raises(ValueError, match="no identification windows"):
        ev.table4()
    assert ev.detection_rates().loc[("var", "whiteness", 5.0), "healthy_windows"] == 4 * 36
    assert [title for title, _ in ev.summary().tables] == ["Rates (percent of windows)",
                                                           "Detection with the healthy model"]


def test_windows_as_time_spans_or_samples(synthetic, fitted):
    """windows / step follow pandas rolling: "5s" at 100 Hz and 500 samples give the same evaluation; a single test
    is labelled by its class name; tests may differ per model."""
    recs, states, ft = synthetic
    kw = dict(states=states, failure_times=ft, fs=FS, models=("var", "y0"), settle=5.0, progress=False)
    lb = LjungBox(lags=20, alpha=1e-3)
    ref = tsfdi.evaluate(recs, fitted, tests={"whiteness": lb}, windows=("5s",), step="1s", **kw)
    got = tsfdi.evaluate(recs, fitted, tests={"whiteness": lb}, windows=(500,), step=100, **kw)
    for name in ("identification_counts", "detection_counts", "detection_delays", "calibration"):
        pd.testing.assert_frame_equal(getattr(got, name), getattr(ref, name), check_exact=True, obj=name)
    assert sorted(ref.identification_counts["window"].unique()) == [5.0]
    one = tsfdi.evaluate(recs, fitted, tests=lb, windows=pd.Timedelta(seconds=5), **kw)
    assert set(one.identification_counts["method"]) == {"LjungBox"}
    pd.testing.assert_frame_equal(one.identification_counts.drop(columns="method"),
                                  ref.identification_counts.drop(columns="method"), check_exact=True)
    # per model tests: the y0 rows of {"var": lb, "y0": lb} are those of lb for every model
    per = tsfdi.evaluate(recs, fitted, tests={"whiteness": {"var": lb, "y0": LjungBox(lags=20, alpha=1e-3)}},
                         windows=("5s",), **kw)
    pd.testing.assert_frame_equal(per.identification_counts, ref.identification_counts, check_exact=True)
    # the default test is the paper's whiteness test at alpha = 1e-3
    dflt = tsfdi.evaluate(recs, fitted, windows=("5s",), **kw)
    pd.testing.assert_frame_equal(dflt.identification_counts, ref.identification_counts, check_exact=True)


def _sorted(frame: pd.DataFrame) -> pd.DataFrame:
    return frame.sort_values(list(frame.columns)).reset_index(drop=True)


def test_counts_are_the_engine_windows(synthetic, fitted):
    """The counts are those of the windowed engine run record by record, each window's outcome kept in a table and
    counted at the end (pandas ``groupby().size()``), the delays read off each record's windows."""
    recs, states, ft = synthetic
    lb = LjungBox(lags=20, alpha=1e-3)
    ev = tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, models=("var",), tests=lb,
                        windows=("5s",), settle=5.0, rules=("paper", "likelihood", "pvalue"), progress=False)
    names = np.array(list(fitted.faults) + ["ambiguous", "none"], dtype=object)
    healthy = ResidualWindows({"h": fitted.models["var"]["healthy"]})
    faults = ResidualWindows({f: fitted.models["var"][f] for f in fitted.faults})
    ident, det, delays = [], [], []
    for i in np.flatnonzero(ev.records["evaluated"]):
        key = {"turbulence": "", "model": "var", "method": "LjungBox", "window": 5.0, "state": states[i]}
        wh = healthy.fit(recs[i]).statistics(lb, window=500, step=100)
        start, end = wh.starts / FS, wh.starts / FS + 5.0
        fault = states[i] != "healthy"
        pre = (end <= ft[i]) | (not fault)
        alarm = wh.reject[:, 0]
        det.append(pd.DataFrame({**key, "fault_true": fault & (start >= ft[i]), "pre": pre, "alarm": alarm,
                                 "disjoint": wh.starts % 500 == 0}))
        if not fault:
            continue
        hit = alarm & ~pre
        delays.append({**key, "delay": end[hit][0] - ft[i] if hit.any() else np.nan})
        ws = faults.fit(recs[i]).statistics(lb, window=500, step=100)
        keep = ws.starts >= ft[i] * FS + 500
        rows = pd.DataFrame({**key, **{f"acc_{f}": ws.accepted[keep, j] for j, f in enumerate(fitted.faults)}})
        for rule in ("paper", "likelihood", "pvalue"):
            lab = decide(ws.accepted[keep], rule, loglik=ws.loglik[keep], pvalue=ws.min_pvalue[keep])
            rows[f"label_{rule}"] = names[np.where(lab >= 0, lab, lab + 4)]
        ident.append(rows)
    pd.testing.assert_frame_equal(_sorted(ev.identification_counts), _sorted(_counted(pd.concat(ident))),
                                  check_exact=True)
    pd.testing.assert_frame_equal(_sorted(ev.detection_counts), _sorted(_counted(pd.concat(det))), check_exact=True)
    pd.testing.assert_frame_equal(_sorted(ev.detection_delays), _sorted(_counted(pd.DataFrame(delays), "records")),
                                  check_exact=True)
    assert ev.detection_counts["disjoint"].any() and ev.detection_delays["delay"].notna().any()


def test_paper_tests_have_the_alphas_of_table_3():
    """study.paper_tests: method -> {model -> test} at the paper's Table 3 alphas, as evaluate takes them."""
    from tsfdi.study import PAPER_ALPHA, paper_tests

    models = ["roll", "pitch", "yaw_rate", "var", "altitude"]
    tests = paper_tests(models)
    assert list(tests) == ["whiteness", "variance"] and all(list(t) == models for t in tests.values())
    for m in models:
        key = "yaw" if m.startswith("yaw") else m
        lb, ft = tests["whiteness"][m], tests["variance"][m]
        assert isinstance(lb, LjungBox) and lb.lags == 20 and lb.threshold == "theoretical"
        assert isinstance(ft, FTest) and ft.threshold == "theoretical"
        assert lb.alpha == PAPER_ALPHA.get(("whiteness", key), 1e-3)
        assert ft.alpha == PAPER_ALPHA.get(("variance", key), 1e-8)
    assert tests["variance"]["pitch"].alpha == 1e-12 and tests["variance"]["var"].alpha == 1e-8
    emp = paper_tests(["var"], ("whiteness",), lags=10, threshold="empirical")
    assert list(emp) == ["whiteness"] and emp["whiteness"]["var"].lags == 10 and emp["whiteness"]["var"].empirical
    with pytest.raises(ValueError, match="methods"):
        paper_tests(["var"], ("spectral",))


def test_evaluate_with_paper_tests(synthetic, fitted):
    """Per-model tests (label -> {model -> test}): each model's rows use its own test and alpha."""
    from tsfdi.study import paper_tests

    recs, states, ft = synthetic
    tests = paper_tests(["var", "y0"])
    ev = tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, models=("var", "y0"), tests=tests,
                        windows=("5s",), settle=5.0, progress=False)
    assert ev.alphas == {("var", "whiteness"): 1e-3, ("y0", "whiteness"): 1e-3, ("var", "variance"): 1e-8,
                         ("y0", "variance"): 1e-8}
    for m in ("var", "y0"):
        one = tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, models=(m,),
                             tests={"variance": FTest(alpha=1e-8)}, windows=(500,), settle=5.0, progress=False)
        for name in ("identification_counts", "detection_counts", "detection_delays"):
            sub = getattr(ev, name).query("model == @m and method == 'variance'").reset_index(drop=True)
            pd.testing.assert_frame_equal(sub, getattr(one, name), check_exact=True, obj=name)


def test_evaluate_warns_of_records_the_baselines_do_not_cover(synthetic):
    """evaluate (issue 31): with 4 healthy fitting records the healthy part of every evaluated record (a healthy
    record from settle s on) is judged by the spread of their summaries; a louder healthy record warns once naming
    the record, model, method, window and the summaries out; Evaluation.coverage has a row per check, records its
    covered column (<NA> for the fault records, whose healthy part is shorter than the fitting segments). The same
    table, warning and counts from the records chunked on dask, where the check runs in the chunk's task; with the
    test calibrated per state (record law of 4 records), the record law judges."""
    import warnings

    from tsfdi.coverage import coverage
    from tsfdi.exceptions import CoverageWarning

    recs, states, ft = synthetic
    rng = np.random.default_rng(32)
    loud = 1.6 * _synthetic_record("healthy", 4000, rng)
    recs, states, ft = [*recs, loud], [*states, "healthy"], np.append(ft, np.nan)
    kw = dict(states=states, failure_times=ft, fs=FS)
    b = tsfdi.fit_baselines(recs, fit_records=4, settle=5.0, duration=None, max_lags=6, var_max_lags=6,
                            steady_window="5s", calibrate=True, **kw)
    opts = dict(models=("var",), tests={"whiteness": LjungBox(lags=20, alpha=1e-3)}, windows=("5s", "20s"),
                settle=5.0, progress=False)
    said = r"evaluate: record 15: model var, method whiteness, 5 s windows: the record lies outside .*log_scale"
    with pytest.warns(CoverageWarning, match=said + r"\[all\].*fit the baseline on flights") as w:
        ev = tsfdi.evaluate(recs, b, **kw, **opts)
    assert len([x for x in w if issubclass(x.category, CoverageWarning)]) == 1
    cov = ev.coverage
    assert list(cov.columns) == ["record", "model", "method", "window", "covered", "pvalue", "records", "outside"]
    assert cov["record"].tolist() == [4, 4, 15, 15] and cov["window"].tolist() == [5.0, 20.0, 5.0, 20.0]
    assert cov["covered"].tolist() == [True, True, False, False] and (cov["records"] == 4).all()
    ref = coverage(b.models["var"]["healthy"], loud[500:], held_out=b.heldout[("var", "healthy")])
    assert cov["pvalue"].iloc[2] == pytest.approx(ref.pvalue, rel=1e-12)
    covered = ev.records.set_index("record")["covered"]
    assert str(covered.dtype) == "boolean" and not covered[15]
    assert covered[4] and covered[[9, 14]].isna().all() and covered[list(b.fit_records)].isna().all()
    x = xr.DataArray(np.stack(recs), dims=("record", "time", "channel"),
                     coords={"state": ("record", states), "failure_time": ("record", ft),
                             "time": np.arange(4000) / FS, "channel": ["y0", "y1"]}).chunk(record=4)
    with pytest.warns(CoverageWarning, match=r"evaluate: record 15: "):
        lazy = tsfdi.evaluate(x, b, **opts)
    pd.testing.assert_frame_equal(lazy.coverage, cov)
    pd.testing.assert_frame_equal(lazy.records, ev.records)
    # a calibrated test: its record law judges (one row per window, each its own law)
    cal = {"variance": FTest(alpha=0.01, threshold="calibrated")}
    with pytest.warns(CoverageWarning, match=r"evaluate: record 15: .*FTest\[y0\]"):
        law = tsfdi.evaluate(recs, b, **kw, **{**opts, "tests": cal, "windows": ("1s", "2s")})
    # the fault records' healthy part (5 s before the failure) holds 5 windows of 1 s, 2 of 2 s: judged at 1 s only
    assert law.coverage[["record", "window"]].values.tolist() == [[4, 1], [4, 2], [9, 1], [14, 1], [15, 1], [15, 2]]
    assert law.coverage["covered"].tolist() == [True] * 4 + [False] * 2
    assert law.coverage["outside"].str.contains("FTest").tolist() == [False] * 4 + [True] * 2
    with warnings.catch_warnings():
        warnings.simplefilter("error", CoverageWarning)
        first = tsfdi.fit_baselines(recs, settle=5.0, duration=None, max_lags=6, var_max_lags=6,
                                    steady_window="5s", **kw)
        none = tsfdi.evaluate(recs, first, **kw, **opts)          # one fitting record per state: nothing checked
    assert none.coverage.empty and list(none.coverage.columns) == list(cov.columns)
    assert none.records["covered"].isna().all()


def test_arx_models_are_refused_naming_the_way_out(synthetic, fitted):
    """An ARX (input-output) model in the baselines is refused naming it and the engines that take an input, not
    with the windowed engine's 'u is required' (evaluate has no u)."""
    import dataclasses

    recs, states, ft = synthetic
    arx = tsfdi.ARX(recs[0][:, :1], recs[0][:, 1:], na=2, nb=2).fit()
    io = dataclasses.replace(fitted, models={**fitted.models, "var": {**fitted.models["var"], "healthy": arx}})
    with pytest.raises(TypeError, match=r"^baselines.models\['var'\]\['healthy'\] is an ARX \(input-output\) model: "
                                        r".*identify_windows\(y, models, test, u=\.\.\.\)"):
        tsfdi.evaluate(recs, io, states=states, failure_times=ft, fs=FS, windows=("5s",), settle=5.0,
                       progress=False)
    # a VARX (several outputs given inputs) alike, not the engine's error further on
    varx = tsfdi.models.VARX(recs[0], recs[1][:, :1], 2, 2).fit()
    io = dataclasses.replace(fitted, models={**fitted.models, "var": {**fitted.models["var"], "healthy": varx}})
    with pytest.raises(TypeError, match=r"^baselines.models\['var'\]\['healthy'\] is a VARX \(input-output\) "
                                        r"model: .*identify_windows\(y, models, test, u=\.\.\.\)"):
        tsfdi.evaluate(recs, io, states=states, failure_times=ft, fs=FS, windows=("5s",), settle=5.0,
                       progress=False)

def test_functionally_pooled_models_are_refused_naming_at_k(synthetic, fitted):
    """An FP model in the baselines is named with the way out (its point model .at(k)) instead of an AttributeError
    from the coverage check; its point model at one k is evaluated as any VAR."""
    import dataclasses

    recs, states, ft = synthetic
    healthy = [r[:1000] * (1 + 0.2 * k) for r, k in zip(recs[:3], (0.0, 0.5, 1.0))]
    fp = tsfdi.models.FPVAR(healthy, [0.0, 0.5, 1.0], 2, degree=1).fit()
    pooled = dataclasses.replace(fitted, models={**fitted.models, "var": {**fitted.models["var"], "healthy": fp}})
    with pytest.raises(TypeError, match=r"^baselines.models\['var'\]\['healthy'\] is a functionally pooled model "
                                        r".*\.at\(k\)"):
        tsfdi.evaluate(recs, pooled, states=states, failure_times=ft, fs=FS, windows=("5s",), settle=5.0,
                       progress=False)
    at = dataclasses.replace(pooled, models={**pooled.models, "var": {**pooled.models["var"], "healthy": fp.at(0.0)}})
    ev = tsfdi.evaluate(recs, at, states=states, failure_times=ft, fs=FS, windows=("5s",), settle=5.0, progress=False)
    assert len(ev.records)

"""Monitor: sliding-window detection, steady-state check and identification events (Dutta et al., Fig. 3)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from _synthetic_fdi import FS, record
from conftest import as_kind

import tsfdi
from tsfdi import VAR, FTest, LjungBox
from tsfdi.monitoring import MonitorEvent, apply_rule, rolling_variance, window_statistics


@pytest.fixture(scope="module")
def models():
    rng = np.random.default_rng(11)
    return {s: VAR(record(s, 6000, rng), 2).fit() for s in ("healthy", "f1", "f2")}


@pytest.fixture(scope="module")
def failure_record():
    """30 s at 100 Hz: healthy, then fault f1 from 10 s."""
    return record("f1", 3000, np.random.default_rng(12), failure=1000)


def _monitor(models, **kw):
    opts = dict(window=5.0, step=1.0, fs=FS, test=LjungBox(lags=20, alpha=1e-4), steady_window=5.0)
    opts.update(kw)
    return tsfdi.Monitor(models["healthy"], {"f1": models["f1"], "f2": models["f2"]}, **opts)


def test_events_and_times(models, failure_record):
    # thresholds: the fault's steady variance is larger than the healthy one; 3x its value is a generous ceiling
    thr = 3.0 * failure_record[1500:].var(axis=0)
    res = _monitor(models, steady_thresholds=thr).run(failure_record)
    kinds = [e.kind for e in res.events]
    assert kinds[0] == "detection" and kinds[1] == "steady"
    # detection: the first window holding post-failure samples that rejects; windows end on whole seconds
    assert 10.0 < res.detection_time <= 12.0
    assert res.detection_time == pytest.approx(round(res.detection_time))
    # steady: the first variance window lying wholly after the detection
    steady = res.events[1]
    assert steady.window[0] >= res.detection_time
    assert steady.time == pytest.approx(steady.window[0] + 5.0)
    ident = [e for e in res.events if e.kind == "identification"]
    assert len(ident) == 30 - 5 - int(steady.window[0]) + 1      # windows starting at steady start .. 25 s
    for e in ident:
        assert e.window[1] - e.window[0] == pytest.approx(5.0)
        assert e.time == pytest.approx(e.window[1])
        assert e.window[0] >= steady.window[0]
    labels = [e.label for e in ident]
    assert labels.count("f1") >= 0.9 * len(labels)
    assert res.label == "f1"
    # no window before the failure is flagged (alpha = 1e-4 per channel, 6 windows)
    w = res.windows
    assert not w.loc[w["end"] <= 10.0, "fault"].any()
    assert list(w["phase"].unique()) == ["healthy", "transient", "steady"]
    frame = res.to_frame()
    assert list(frame["kind"][:2]) == ["detection", "steady"]


def test_healthy_record_has_no_event(models):
    x = record("healthy", 3000, np.random.default_rng(13))
    res = _monitor(models).run(x)
    assert res.events == [] and res.detection_time is None and res.label is None


def test_without_thresholds_identifies_from_detection(models, failure_record):
    res = _monitor(models).run(failure_record)
    ident = [e for e in res.events if e.kind == "identification"]
    assert ident[0].window[1] == pytest.approx(res.detection_time)


def test_streaming_equals_batch(models, failure_record):
    thr = 3.0 * failure_record[1500:].var(axis=0)
    mon = _monitor(models, steady_thresholds=thr, steady_window=8.0, rule="likelihood")
    batch = mon.run(failure_record)
    mon.reset()
    streamed = []
    for k in range(0, failure_record.shape[0], 137):
        streamed += mon.update(failure_record[k:k + 137])
    assert streamed == batch.events
    pd.testing.assert_frame_equal(mon.result().windows, batch.windows)


def test_data_kinds_give_same_events(models, failure_record, kind):
    ref = _monitor(models).run(failure_record).events
    got = _monitor(models).run(as_kind(failure_record, kind)).events
    assert got == ref
    assert all(isinstance(e, MonitorEvent) for e in got)


def test_window_statistics_equal_tests_on_slices(models, failure_record):
    x = failure_record
    W, S = 400, 150
    lb = LjungBox(lags=15, alpha=1e-3)
    ft = FTest(alpha=1e-3)
    for test in (lb, ft):
        ws = window_statistics(x, models, test, window=W, step=S)
        assert ws["starts"].tolist() == list(range(0, x.shape[0] - W + 1, S))
        for name, res in models.items():
            d = ws["decisions"][name]
            for w in (0, 7, len(ws["starts"]) - 1):
                s = ws["starts"][w]
                ref = test.test(np.asarray(res.residuals(x[s:s + W])), **test.reference(res))
                np.testing.assert_allclose(d["statistic"][w], ref.statistic, rtol=1e-8)
                np.testing.assert_allclose(d["pvalue"][w], ref.pvalue, rtol=1e-6, atol=1e-300)
                assert bool(d["reject"][w]) == ref.reject
    # likelihood score on the common samples [s + pmax, s + W): -(log det S + k log 2 pi + k) / 2
    ws = window_statistics(x, models, lb, window=W, step=S)
    s = ws["starts"][3]
    e = np.asarray(models["f1"].residuals(x[s:s + W]))
    cov = np.cov(e.T, bias=True)
    expected = -0.5 * (np.linalg.slogdet(cov)[1] + 2 * np.log(2 * np.pi) + 2)
    assert ws["loglik"][1, 3] == pytest.approx(expected, rel=1e-9)


def test_window_statistics_bank(models, failure_record):
    """A bank (list of models of one order) accepts a window when any member accepts; its decision is its best
    member's there and its likelihood score the largest of its members'."""
    x = failure_record
    W, S = 400, 100
    lb = LjungBox(lags=15, alpha=1e-3)
    members = [models["healthy"], models["f2"], models["f1"]]
    one = window_statistics(x, {f"m{i}": m for i, m in enumerate(members)}, lb, window=W, step=S)
    ws = window_statistics(x, {"bank": members, "f1": models["f1"]}, lb, window=W, step=S)
    d = ws["decisions"]["bank"]
    rej = np.array([one["decisions"][f"m{i}"]["reject"] for i in range(3)])
    np.testing.assert_array_equal(d["reject"], rej.all(axis=0))
    assert d["reject"].any() and not d["reject"].all()          # the record switches from healthy to f1
    for w, m in enumerate(d["member"]):
        ref = one["decisions"][f"m{m}"]
        np.testing.assert_array_equal(d["statistic"][w], ref["statistic"][w])
        np.testing.assert_array_equal(d["threshold"][w], ref["threshold"][w])
        if not d["reject"][w]:                                   # an accepting member is reported
            assert not ref["reject"][w]
            pm = [one["decisions"][f"m{i}"]["pvalue"][w].min() for i in range(3) if not rej[i, w]]
            assert ref["pvalue"][w].min() == max(pm)
    np.testing.assert_allclose(ws["loglik"][0], one["loglik"].max(axis=0))
    np.testing.assert_allclose(ws["loglik"][1], one["loglik"][2])
    # a one-member bank is the model itself
    solo = window_statistics(x, {"h": [models["healthy"]]}, lb, window=W, step=S)["decisions"]["h"]
    for key in ("statistic", "pvalue", "reject", "threshold"):
        np.testing.assert_array_equal(solo[key], one["decisions"]["m0"][key])
    assert (solo["member"] == 0).all()
    # a Monitor with banks gives the events of the plain models when every bank has one member
    plain = _monitor(models).run(x)
    banked = _monitor({k: [m] for k, m in models.items()}).run(x)
    assert banked.events == plain.events
    with pytest.raises(ValueError, match="empty bank"):
        window_statistics(x, {"b": []}, lb, window=W)
    with pytest.raises(ValueError, match="share one order"):
        window_statistics(x, {"b": [models["f1"], VAR(x, 3).fit()]}, lb, window=W)
    with pytest.raises(TypeError, match=r"models\['b'\]"):
        window_statistics(x, {"b": [models["f1"], "f2"]}, lb, window=W)


@pytest.mark.slow
def test_bank_holds_alpha_where_the_pooled_model_does_not():
    """Records of one state that differ (AR(1) with coefficient 0.2, 0.5 or 0.8): the model pooled over them
    averages the dynamics and its residuals on a new record are correlated; a bank of one model per record
    rejects a new record's window at most at about alpha (binomial 99.9 % bound over independent records)."""
    from scipy import stats

    rng = np.random.default_rng(2026)
    phis = (0.2, 0.5, 0.8)

    def ar1(phi, n):
        e = rng.standard_normal(n + 200)
        y = np.zeros_like(e)
        for t in range(1, e.size):
            y[t] = phi * y[t - 1] + e[t]
        return y[200:]

    fitting = [ar1(phi, 5000) for phi in phis for _ in range(2)]
    pooled = tsfdi.AR(fitting, 1).fit()
    bank = [tsfdi.AR(y, 1).fit() for y in fitting]
    alpha, trials = 0.05, 300
    lb = LjungBox(lags=10, alpha=alpha)
    rejects = {"pooled": 0, "bank": 0}
    for _ in range(trials):
        y = ar1(phis[rng.integers(3)], 500)
        d = window_statistics(y, {"pooled": pooled, "bank": bank}, lb, window=500)["decisions"]
        for k in rejects:
            rejects[k] += int(d[k]["reject"][0])
    assert rejects["bank"] <= stats.binom.ppf(0.999, trials, alpha), rejects
    assert rejects["pooled"] >= 0.5 * trials, rejects


def test_rolling_variance(kind):
    x = np.random.default_rng(3).standard_normal((500, 2)) * [1.0, 3.0] + 5.0
    v = rolling_variance(as_kind(x, kind), 100, 30)
    ref = np.array([x[s:s + 100].var(axis=0) for s in range(0, 401, 30)])
    np.testing.assert_allclose(v, ref, rtol=1e-10)


def test_apply_rule_closed_form():
    reject = np.array([[False, False, True, True, False],
                       [True, False, True, False, False],
                       [True, True, True, True, False]])
    loglik = np.array([[0.0, 1.0, 5.0, 0.0, 3.0],
                       [9.0, 2.0, 1.0, 0.0, 9.0],
                       [9.0, 9.0, 0.0, 9.0, 1.0]])
    pval = np.array([[0.5, 0.1, 1e-9, 0.0, 0.2],
                     [0.0, 0.3, 1e-8, 0.4, 0.1],
                     [0.0, 0.0, 1e-3, 0.0, 0.3]])
    assert apply_rule(reject, loglik, pval, "paper").tolist() == [0, -2, -1, 1, -2]
    # likelihood: best among the accepted, or among all when none is accepted
    assert apply_rule(reject, loglik, pval, "likelihood").tolist() == [0, 1, 0, 1, 1]
    assert apply_rule(reject, loglik, pval, "pvalue").tolist() == [0, 1, 2, 1, 2]


def test_bad_input(models, failure_record):
    with pytest.raises(TypeError, match="baseline"):
        tsfdi.Monitor(object(), {"f1": models["f1"]}, window=5.0, fs=FS)
    with pytest.raises(TypeError, match="models"):
        tsfdi.Monitor(models["healthy"], [models["f1"]], window=5.0, fs=FS)
    with pytest.raises(ValueError, match="window"):
        tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window=0.01, fs=FS)
    with pytest.raises(ValueError, match="rule"):
        tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window=5.0, fs=FS, rule="vote")
    with pytest.raises(ValueError, match="steady_thresholds"):
        tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window=5.0, fs=FS, steady_thresholds=[1.0])
    with pytest.raises(TypeError, match="test"):
        tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window=5.0, fs=FS, test="whiteness")
    mon = _monitor(models)
    with pytest.raises(ValueError, match="channel"):
        mon.run(failure_record[:, :1])
    bad = failure_record.copy()
    bad[5, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        mon.run(bad)
    with pytest.raises(ValueError, match="window"):
        window_statistics(failure_record[:100], models, LjungBox(lags=10), window=200)


def test_plots(models, failure_record):
    import matplotlib.pyplot as plt

    from tsfdi.plotting.monitoring import plot_confusion, plot_variance_evolution

    thr = 3.0 * failure_record[1500:].var(axis=0)
    res = _monitor(models, steady_thresholds=thr).run(failure_record)
    fig = res.plot()
    assert len(fig.axes) == 3
    fig2 = plot_variance_evolution([failure_record], fs=FS, window=5.0, thresholds=thr, failure_time=10.0,
                                   labels=["f1"])
    line = fig2.axes[0].lines[0]
    np.testing.assert_allclose(line.get_ydata(), rolling_variance(failure_record, 500, 10)[:, 0])
    fig3 = plot_confusion(pd.DataFrame([[90.0, 10.0], [0.0, 100.0]], index=["a", "b"], columns=["a", "b"]))
    assert fig3.axes[0].images[0].get_array().max() == 100.0
    with pytest.raises(TypeError, match="DataFrame"):
        plot_confusion([[1, 2]])
    plt.close("all")

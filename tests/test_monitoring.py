"""Monitor: sliding-window detection, steady-state check and identification events (Dutta et al., Fig. 3)."""

from __future__ import annotations

import datetime

import numpy as np
import pandas as pd
import pytest
from _synthetic_fdi import FS, record
from conftest import as_kind

import tsfdi
from tsfdi import VAR, FTest, LjungBox
from tsfdi.monitoring import MonitorEvent, rolling_variance
from tsfdi.windows import AMBIGUOUS, NONE, ResidualWindows, WindowStatistics, decide, status


@pytest.fixture(scope="module")
def models():
    rng = np.random.default_rng(11)
    return {s: VAR(record(s, 6000, rng), 2).fit() for s in ("healthy", "f1", "f2")}


@pytest.fixture(scope="module")
def failure_record():
    """30 s at 100 Hz: healthy, then fault f1 from 10 s."""
    return record("f1", 3000, np.random.default_rng(12), failure=1000)


def _monitor(models, **kw):
    opts = dict(window="5s", step="1s", fs=FS, test=LjungBox(lags=20, alpha=1e-4), steady_window="5s")
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


def test_steady_state_is_paper_003s_check_at_the_time_it_is_established(models, failure_record):
    """Issue 29: "steady" was reported at the detection instant and the steady window changed nothing. Without
    steady_thresholds the thresholds are paper 003's -- the largest rolling variance of every channel over the fault
    models' (steady) fitting records -- and the steady event is the end of the first variance window wholly after
    the detection with every channel at or below them; identification starts there."""
    x = failure_record
    times = {}
    for V in ("2s", "5s", "8s"):
        mon = _monitor(models, steady_window=V)
        res = mon.run(x)
        n = mon.steady_window
        expect = np.max([np.max(rolling_variance(m.model.records[0].values, n, 1), axis=0)
                         for m in (models["f1"], models["f2"])], axis=0)
        np.testing.assert_allclose(mon.steady_thresholds, expect)
        kinds = [e.kind for e in res.events]
        assert kinds[:2] == ["detection", "steady"]
        steady = res.events[1]
        assert steady.window[0] >= res.detection_time and steady.time == pytest.approx(steady.window[0] + n / FS)
        assert steady.time > res.detection_time                      # not the detection instant
        end = int(round(steady.time * FS))
        assert np.all(x[end - n:end].var(axis=0) <= expect)          # the check itself, at that time
        for t in np.arange(res.detection_time + n / FS, steady.time - 1e-9, 1.0):   # and not one step earlier
            e = int(round(t * FS))
            assert not np.all(x[e - n:e].var(axis=0) <= expect)
        ident = [e for e in res.events if e.kind == "identification"]
        assert ident and ident[0].window[0] >= steady.window[0]
        times[V] = steady.time
    assert len(set(times.values())) > 1                              # the steady window changes the result
    # detection only: no fault records, no steady-state check unless thresholds are given
    only = tsfdi.Monitor(models["healthy"], window="5s", step="1s", fs=FS, test=LjungBox(lags=20, alpha=1e-4))
    assert only.steady_thresholds is None and "steady" not in [e.kind for e in only.run(x).events]


def test_streaming_equals_batch(models, failure_record):
    thr = 3.0 * failure_record[1500:].var(axis=0)
    mon = _monitor(models, steady_thresholds=thr, steady_window="8s", rule="likelihood")
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


def _stats(x, models, test, **kw):
    """Every model's test on every window of ``x`` (the windowed engine, filtered once)."""
    return ResidualWindows(models).fit(x).statistics(test, **kw)


def test_window_statistics_equal_tests_on_slices(models, failure_record):
    x = failure_record
    W, S = 400, 150
    lb = LjungBox(lags=15, alpha=1e-3)
    ft = FTest(alpha=1e-3)
    for test in (lb, ft):
        ws = _stats(x, models, test, window=W, step=S)
        assert isinstance(ws, WindowStatistics)
        assert ws.starts.tolist() == list(range(0, x.shape[0] - W + 1, S))
        assert (ws.window, ws.step, ws.models, len(ws)) == (W, S, tuple(models), len(ws.starts))
        assert ws.nobs == tuple(W - res.lags for res in models.values())
        k = x.shape[1]
        for arr in (ws.statistic, ws.threshold, ws.pvalue, ws.channel_reject):
            assert arr.shape == (len(ws), len(models), k)
        for arr in (ws.reject, ws.loglik):
            assert arr.shape == (len(ws), len(models))
        for j, (name, res) in enumerate(models.items()):
            for w in (0, 7, len(ws.starts) - 1):
                s = ws.starts[w]
                ref = test.test(np.asarray(res.residuals(x[s:s + W])), **test.reference(res))
                np.testing.assert_allclose(ws.statistic[w, j], ref.statistic, rtol=1e-8)
                np.testing.assert_allclose(ws.pvalue[w, j], ref.pvalue, rtol=1e-6, atol=1e-300)
                assert bool(ws.reject[w, j]) == ref.reject
                np.testing.assert_array_equal(ws.channel_reject[w, j], ref.channel_reject)
        np.testing.assert_array_equal(ws.accepted, ~ws.reject)
        np.testing.assert_array_equal(ws.min_pvalue, ws.pvalue.min(axis=2))
    # likelihood score on the common samples [s + pmax, s + W): mean Gaussian log-density under N(0, sigma)
    from scipy.stats import multivariate_normal

    ws = _stats(x, models, lb, window=W, step=S)
    s, pmax = ws.starts[3], max(res.lags for res in models.values())
    for j, res in enumerate(models.values()):
        e = np.asarray(res.residuals(x[s:s + W]))[-(W - pmax):]
        expected = multivariate_normal(np.zeros(2), res.sigma).logpdf(e).mean()
        assert ws.loglik[3, j] == pytest.approx(expected, rel=1e-9)
    assert np.isnan(_stats(x, models, lb, window=W, step=S, loglik=False).loglik).all()


def test_window_statistics_is_frozen(models, failure_record):
    ws = _stats(failure_record, models, LjungBox(lags=15, alpha=1e-3), window=400, step=150)
    with pytest.raises(AttributeError):
        ws.window = 10
    with pytest.raises(AttributeError):
        ws.reject = ~ws.reject
    assert ws.window == 400
    assert "WindowStatistics(" in repr(ws)


def test_window_statistics_labels_and_status(models, failure_record):
    """The labels of WindowStatistics are decide() on its acceptances and scores; its status the count rule."""
    ws = _stats(failure_record, models, LjungBox(lags=15, alpha=1e-3), window=400, step=100)
    for rule in ("paper", "likelihood", "pvalue"):
        np.testing.assert_array_equal(ws.labels(rule), decide(ws.accepted, rule, loglik=ws.loglik,
                                                              pvalue=ws.min_pvalue))
    np.testing.assert_array_equal(ws.status, status(ws.accepted.sum(axis=1)))
    paper = ws.labels("paper")
    np.testing.assert_array_equal(ws.status == "identified", paper >= 0)
    np.testing.assert_array_equal(ws.status == "ambiguous", paper == AMBIGUOUS)
    np.testing.assert_array_equal(ws.status == "none", paper == NONE)


def test_fit_residuals_equals_fit(models, failure_record):
    """Residuals computed elsewhere give the statistics of the engine's own filtering when they are the same."""
    x = failure_record
    for test in (LjungBox(lags=15, alpha=1e-3), FTest(alpha=1e-3)):
        ref = _stats(x, models, test, window=400, step=150)
        given = {name: np.asarray(res.residuals(x)) for name, res in models.items()}
        got = ResidualWindows(models).fit_residuals(given, x.shape[0]).statistics(test, window=400, step=150)
        for attr in ("starts", "statistic", "threshold", "pvalue", "channel_reject", "reject", "loglik"):
            np.testing.assert_array_equal(getattr(got, attr), getattr(ref, attr), err_msg=attr)
        assert (got.nobs, got.models, got.channels) == (ref.nobs, ref.models, ref.channels)
    with pytest.raises(ValueError, match="f2"):
        ResidualWindows(models).fit_residuals({"healthy": given["healthy"], "f1": given["f1"]}, x.shape[0])
    with pytest.raises(ValueError, match="shape"):
        ResidualWindows(models).fit_residuals({n: np.asarray(r.residuals(x))[1:] for n, r in models.items()},
                                              x.shape[0])
    with pytest.raises(ValueError, match="not fitted"):
        ResidualWindows(models).statistics(LjungBox(lags=15), window=400)


@pytest.mark.parametrize("method", ["hosking", "li-mcleod"])
def test_multivariate_ljungbox_through_the_engine(models, failure_record, method):
    """A joint portmanteau test (one "joint" component) is applied window by window: each window's decision is
    the test on that window's slice of the record's residuals."""
    x = failure_record
    W, S = 400, 250
    test = LjungBox(lags=10, alpha=1e-3, multivariate=method)
    ws = _stats(x, models, test, window=W, step=S)
    assert ws.statistic.shape == (len(ws), len(models), 1)
    assert ws.decisions is not None and len(ws.decisions) == len(ws)
    for j, (name, res) in enumerate(models.items()):
        e = np.asarray(res.residuals(x))
        for w, s in enumerate(ws.starts):
            ref = test.test(e[s:s + W - res.lags])
            # the same residuals as the window's own filtering
            np.testing.assert_allclose(e[s:s + W - res.lags], np.asarray(res.residuals(x[s:s + W])), rtol=1e-12)
            np.testing.assert_array_equal(ws.statistic[w, j], ref.statistic)
            np.testing.assert_array_equal(ws.pvalue[w, j], ref.pvalue)
            np.testing.assert_array_equal(ws.threshold[w, j], ref.threshold)
            assert bool(ws.reject[w, j]) == ref.reject
            assert ws.decisions[w][j].channels == ("joint",)
            np.testing.assert_array_equal(ws.decisions[w][j].statistic, ref.statistic)
    # the failure record switches from healthy to f1: the joint test sees it
    assert not ws.reject[0, 0] and ws.reject[-1, 0]


def test_rolling_variance(kind):
    x = np.random.default_rng(3).standard_normal((500, 2)) * [1.0, 3.0] + 5.0
    v = rolling_variance(as_kind(x, kind), 100, 30)
    ref = np.array([x[s:s + 100].var(axis=0) for s in range(0, 401, 30)])
    np.testing.assert_allclose(v, ref, rtol=1e-10)


def test_decide_closed_form():
    """The decision rules on hand-made acceptances and scores (the former apply_rule(reject, loglik, pvalue) with
    (n_models, n_windows) inputs is decide(~reject.T, rule, loglik=loglik.T, pvalue=pvalue.T))."""
    reject = np.array([[False, False, True, True, False],
                       [True, False, True, False, False],
                       [True, True, True, True, False]])
    loglik = np.array([[0.0, 1.0, 5.0, 0.0, 3.0],
                       [9.0, 2.0, 1.0, 0.0, 9.0],
                       [9.0, 9.0, 0.0, 9.0, 1.0]])
    pval = np.array([[0.5, 0.1, 1e-9, 0.0, 0.2],
                     [0.0, 0.3, 1e-8, 0.4, 0.1],
                     [0.0, 0.0, 1e-3, 0.0, 0.3]])
    acc = ~reject.T
    assert decide(acc, "paper", loglik=loglik.T, pvalue=pval.T).tolist() == [0, -2, -1, 1, -2]
    assert decide(acc).tolist() == [0, -2, -1, 1, -2]                 # "paper" is the default and needs no score
    assert (NONE, AMBIGUOUS) == (-1, -2)
    # likelihood: best among the accepted, or among all when none is accepted
    assert decide(acc, "likelihood", loglik=loglik.T, pvalue=pval.T).tolist() == [0, 1, 0, 1, 1]
    assert decide(acc, "pvalue", loglik=loglik.T, pvalue=pval.T).tolist() == [0, 1, 2, 1, 2]
    # the status counts the accepted models whatever the rule
    assert status(acc.sum(axis=1)).tolist() == ["identified", "ambiguous", "none", "identified", "ambiguous"]
    # one window as a 1-D input
    assert int(decide([False, True, False])) == 1 and int(decide([True, True])) == AMBIGUOUS
    assert int(decide([False, False], "likelihood", loglik=[1.0, 2.0])) == 1
    # a NaN score never wins; all-NaN is no decision
    assert int(decide([True, True], "likelihood", loglik=[np.nan, -5.0])) == 1
    assert int(decide([True, True], "pvalue", pvalue=[np.nan, np.nan])) == NONE
    with pytest.raises(ValueError, match="loglik"):
        decide(acc, "likelihood")
    with pytest.raises(ValueError, match="pvalue"):
        decide(acc, "pvalue")
    with pytest.raises(ValueError, match="shape"):
        decide(acc, "likelihood", loglik=loglik)
    with pytest.raises(ValueError, match="rule"):
        decide(acc, "vote")


def test_window_and_step_as_time_span_or_samples(models, failure_record):
    """window / step / steady_window follow pandas rolling: "5s" at 100 Hz is 500 samples, any spelling."""
    thr = 3.0 * failure_record[1500:].var(axis=0)
    span = _monitor(models, steady_thresholds=thr)
    assert (span.window, span.step, span.steady_window) == (500, 100, 500)
    ref = span.run(failure_record)
    for kw in (dict(window=500, step=100, steady_window=500),
               dict(window=pd.Timedelta(seconds=5), step=np.int64(100), steady_window="5000ms"),
               dict(window=datetime.timedelta(seconds=5), step="1s", steady_window=500)):
        mon = _monitor(models, steady_thresholds=thr, **kw)
        assert (mon.window, mon.step, mon.steady_window) == (500, 100, 500)
        got = mon.run(failure_record)
        assert got.events == ref.events
        pd.testing.assert_frame_equal(got.windows, ref.windows)
    # the defaults with fs: 1 s step, 10 s variance window
    mon = tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window="2s", fs=FS)
    assert (mon.window, mon.step, mon.steady_window) == (200, 100, 1000)
    # without fs, times are in samples: the events of the same windows, every time multiplied by fs
    samples = _monitor(models, steady_thresholds=thr, window=500, step=100, steady_window=500, fs=None)
    assert samples.fs is None
    got = samples.run(failure_record)
    assert [(e.kind, e.label, e.status, e.accepted) for e in got.events] == \
        [(e.kind, e.label, e.status, e.accepted) for e in ref.events]
    for a, b in zip(got.events, ref.events):
        assert a.time == pytest.approx(b.time * FS)
        np.testing.assert_allclose(a.window, np.multiply(b.window, FS))
    assert got.detection_time == pytest.approx(ref.detection_time * FS)


def test_numpy_timedelta64_is_a_time_span(models):
    h, f = models["healthy"], {"f1": models["f1"]}
    for span in (np.timedelta64(5, "s"), np.timedelta64(5_000_000_000, "ns")):
        mon = tsfdi.Monitor(h, f, window=span, fs=FS)
        assert mon.window == 500


def test_window_vocabulary_errors(models):
    h, f = models["healthy"], {"f1": models["f1"]}
    # a float is neither samples nor a time span: refused, naming the argument
    with pytest.raises(TypeError, match="window"):
        tsfdi.Monitor(h, f, window=5.0, fs=FS)
    with pytest.raises(TypeError, match="step"):
        tsfdi.Monitor(h, f, window=500, step=1.0, fs=FS)
    with pytest.raises(TypeError, match="steady_window"):
        tsfdi.Monitor(h, f, window=500, step=100, steady_window=5.0, fs=FS)
    with pytest.raises(TypeError, match="window"):
        tsfdi.Monitor(h, f, window=True, fs=FS)
    # a time span needs the sampling frequency: fs, or the time index of the data (read at the first samples)
    x = np.zeros((2000, 2))
    for kw, named in ((dict(window="5s", step=100, steady_window=500), r"window = '5s' is a time span"),
                      (dict(window=500, step="1s", steady_window=500), r"step = '1s' is a time span"),
                      (dict(window=500, step=100, steady_window="10s"), r"steady_window = '10s' is a time span"),
                      # the defaults are time spans too (1 s step, 10 s variance window)
                      (dict(window=500), r"step = '1s' \(the default\), steady_window = '10s' are time spans"),
                      (dict(window=500, step=100), r"steady_window = '10s' is a time span")):
        mon = tsfdi.Monitor(h, f, **kw)
        assert mon.fs is None
        with pytest.raises(ValueError, match=named + r", .*signal carries no time index"):
            mon.run(x)
        with pytest.raises(ValueError, match="at least two samples in the first block"):
            mon.run(as_kind(x, "pandas")[:1])
    # a typo or a non-positive span is refused at once, with or without fs
    for span in ("five seconds", "-2s", "0s"):
        for fs in (FS, None):
            with pytest.raises(ValueError, match="window"):
                tsfdi.Monitor(h, f, window=span, fs=fs)
    with pytest.raises(ValueError, match="window"):
        tsfdi.Monitor(h, f, window=2, step=1, steady_window=500)
    # a span too short at the rate read from the data names the rate and where it came from
    with pytest.raises(ValueError, match=r"window = '20ms' is 2 sample\(s\) at fs = 100 Hz.*read from the time index"):
        tsfdi.Monitor(h, f, window="20ms").run(as_kind(x, "pandas"))


def test_bad_baseline_is_named(models):
    with pytest.raises(TypeError, match="baseline"):
        tsfdi.Monitor(object(), {"f1": models["f1"]}, window="5s", fs=FS)


def test_bad_input(models, failure_record):
    with pytest.raises(TypeError, match="fitted results"):
        tsfdi.Monitor(object(), {"f1": models["f1"]}, window="5s", fs=FS)
    with pytest.raises(TypeError, match="fitted results"):
        tsfdi.Monitor(models["healthy"], {"f1": object()}, window="5s", fs=FS)
    with pytest.raises(TypeError, match="models"):
        tsfdi.Monitor(models["healthy"], [models["f1"]], window="5s", fs=FS)
    with pytest.raises(ValueError, match="window"):
        tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window="10ms", fs=FS)
    with pytest.raises(ValueError, match="rule"):
        tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window="5s", fs=FS, rule="vote")
    with pytest.raises(ValueError, match="steady_thresholds"):
        tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window="5s", fs=FS, steady_thresholds=[1.0])
    with pytest.raises(TypeError, match="test"):
        tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window="5s", fs=FS, test="whiteness")
    mon = _monitor(models)
    with pytest.raises(ValueError, match="channel"):
        mon.run(failure_record[:, :1])
    bad = failure_record.copy()
    bad[5, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        mon.run(bad)
    with pytest.raises(ValueError, match="window"):
        _stats(failure_record[:100], models, LjungBox(lags=10), window=200)
    with pytest.raises(ValueError, match="order"):
        _stats(failure_record, models, LjungBox(lags=10), window=4)
    with pytest.raises(ValueError, match="lags"):
        _stats(failure_record, models, LjungBox(lags=10), window=12)
    with pytest.raises(TypeError, match="test"):
        _stats(failure_record, models, "whiteness", window=200)
    with pytest.raises(ValueError, match="no test"):
        _stats(failure_record, models, {"f1": LjungBox(lags=10)}, window=200)
    with pytest.raises(ValueError, match="channel"):
        ResidualWindows(models).fit(failure_record[:, :1])
    with pytest.raises(TypeError, match="models"):
        ResidualWindows([models["f1"]])


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


def test_likelihood_score_sees_a_mean_shift():
    """Two AR(1) models that differ only in their intercept: the likelihood rule picks the one whose mean the
    window has (the former score, the window's own demeaned covariance, could not tell them apart)."""
    rng = np.random.default_rng(3)
    e = rng.standard_normal(4000)
    y0 = np.empty(4000)
    y0[0] = 0.0
    for t in range(1, 4000):
        y0[t] = 0.5 * y0[t - 1] + e[t]
    low, high = tsfdi.AR(y0, 1, trend="c").fit(), tsfdi.AR(y0 + 3.0, 1, trend="c").fit()
    models = {"low": low, "high": high}
    ws = tsfdi.ResidualWindows(models).fit(y0[:1000] + 3.0).statistics(LjungBox(lags=5), window=200, step=200)
    assert (ws.loglik[:, 1] > ws.loglik[:, 0]).all()
    assert (decide(np.ones_like(ws.accepted), "likelihood", loglik=ws.loglik) == 1).all()


# ------------------------------------------------------------------------------- detection only, fs from the data
def test_detection_only(models, failure_record):
    full = _monitor(models).run(failure_record)
    for none in (None, {}):
        mon = tsfdi.Monitor(models["healthy"], none, window="5s", step="1s", fs=FS,
                            test=LjungBox(lags=20, alpha=1e-4), steady_window="5s")
        assert repr(mon) == "Monitor(models=None (detection only), window=500, step=100, fs=100.0, rule='paper')"
        res = mon.run(failure_record)
        # the same healthy-model test of every window as with fault models, and nothing identified
        pd.testing.assert_frame_equal(res.windows.drop(columns=["phase", "status", "label", "accepted"]),
                                      full.windows.drop(columns=["phase", "status", "label", "accepted"]))
        assert [(e.kind, e.time) for e in res.events] == [("detection", full.detection_time)]
        assert res.label is None and res.steady_time is None and res.models == ()
        assert (res.windows["status"] == "").all() and res.windows["label"].isna().all()
        assert list(res.windows["phase"].unique()) == ["healthy", "transient"]
        assert repr(res).startswith("MonitorResult(detection only, windows=26, fault windows=")
    # with thresholds, the steady state is still reported
    thr = 3.0 * failure_record[1500:].var(axis=0)
    res = tsfdi.Monitor(models["healthy"], window="5s", fs=FS, test=LjungBox(lags=20, alpha=1e-4),
                        steady_window="5s", steady_thresholds=thr).run(failure_record)
    assert [e.kind for e in res.events] == ["detection", "steady"]
    assert res.plot() is not None
    # healthy data: no event
    assert tsfdi.Monitor(models["healthy"], window="5s", fs=FS, test=LjungBox(lags=20, alpha=1e-4)).run(
        record("healthy", 3000, np.random.default_rng(13))).events == []


@pytest.mark.parametrize("index", ["datetime", "timedelta", "seconds", "xarray"])
def test_fs_is_read_from_the_time_index(models, failure_record, index):
    """window / step / steady_window as time spans without fs: the rate of the data's time index (100 Hz)."""
    n = failure_record.shape[0]
    if index == "xarray":
        x = as_kind(failure_record, "xarray")
    else:
        idx = {"datetime": pd.date_range("2024-05-01", periods=n, freq="10ms"),
               "timedelta": pd.timedelta_range(0, periods=n, freq="10ms"),
               "seconds": pd.Index(np.arange(n) / FS, name="time")}[index]
        x = pd.DataFrame(failure_record, index=idx, columns=["y0", "y1"])
    thr = 3.0 * failure_record[1500:].var(axis=0)
    ref = _monitor(models, steady_thresholds=thr).run(failure_record)            # numpy with fs=100
    mon = _monitor(models, steady_thresholds=thr, fs=None)
    assert (mon.fs, mon.window, mon.step, mon.steady_window) == (None, None, None, None)
    assert "window='5s', step='1s', fs=None" in repr(mon)
    got = mon.run(x)
    assert mon.fs == pytest.approx(FS) and (mon.window, mon.step, mon.steady_window) == (500, 100, 500)
    assert [(e.kind, e.label, e.status) for e in got.events] == [(e.kind, e.label, e.status) for e in ref.events]
    np.testing.assert_allclose([e.time for e in got.events], [e.time for e in ref.events])
    assert got.detection_time == pytest.approx(ref.detection_time)
    # the defaults (1 s step, 10 s variance window) too
    mon2 = tsfdi.Monitor(models["healthy"], {"f1": models["f1"]}, window="2s")
    mon2.run(x)
    assert (mon2.window, mon2.step, mon2.steady_window) == (200, 100, 1000)
    # streamed in blocks: the rate of the first block
    mon.reset()
    assert mon.fs is None and mon.window is None
    streamed = []
    for k in range(0, n, 250):
        streamed += mon.update(x[k:k + 250])
    assert streamed == got.events


def test_an_fs_contradicting_the_time_index_is_refused(models, failure_record):
    """fs=50 given for a 100 Hz DatetimeIndex was used silently (windows of half the time span)."""
    x = as_kind(failure_record, "pandas")
    with pytest.raises(ValueError, match=r"fs = 50 Hz disagrees with the time index of signal.*100 Hz"):
        _monitor(models, fs=50.0).run(x)
    assert _monitor(models, fs=FS).run(x).detection_time == pytest.approx(_monitor(models, fs=None).run(x)
                                                                          .detection_time)


def test_sample_counts_with_a_time_index_give_times_in_seconds(models, failure_record):
    x = as_kind(failure_record, "pandas")
    counts = _monitor(models, window=500, step=100, steady_window=500, fs=None)
    assert counts.window == 500 and counts.fs is None
    res = counts.run(x)
    assert counts.fs == pytest.approx(FS) and 10.0 < res.detection_time <= 12.0
    assert counts.run(failure_record).detection_time == pytest.approx(res.detection_time * FS)   # numpy: samples


def test_window_longer_than_the_signal_is_refused(models, failure_record):
    """Issue 29: Monitor with a window longer than the signal returned 0 windows silently; it names window and the
    signal length, in samples and seconds (samples only without fs), and a stream's short first block still waits."""
    with pytest.raises(ValueError, match=r"window \(500 samples \(5 s\)\) is longer than the signal \(300 samples "
                                         r"\(3 s\)\)"):
        _monitor(models).run(failure_record[:300])
    with pytest.raises(ValueError, match=r"window \(500 samples\) is longer than the signal \(300 samples\):"):
        _monitor(models, window=500, step=100, steady_window=500, fs=None).run(failure_record[:300])
    with pytest.raises(ValueError, match=r"record 1: window \(500 samples"):
        _monitor(models).screen([failure_record, failure_record[:300]])
    mon = _monitor(models)
    assert mon.update(failure_record[:300]) == [] and len(mon.update(failure_record[300:600])) == 0
    assert len(mon.result().windows) == 2


def test_steady_window_longer_than_the_fault_records_is_refused(models, failure_record):
    """The default steady-state thresholds come from the fault models' records: a steady_window longer than all of
    them is refused, naming it in samples and seconds."""
    with pytest.raises(ValueError, match=r"steady_window \(7000 samples \(70 s\)\) is longer than every record the "
                                         r"fault model 'f1' was fitted on \(at most 6000 samples \(60 s\)\)"):
        _monitor(models, steady_window="70s")
    res = _monitor(models, steady_window="70s", steady_thresholds=[1.0, 1.0, 1.0][:failure_record.shape[1]])
    assert res.steady_window == 7000


@pytest.fixture(scope="module")
def fleet_baseline():
    """A healthy VAR(2) on 8 records (3000 samples each) and an F test calibrated on their held-out residuals with
    the predictive record law, for 200-sample windows."""
    rng = np.random.default_rng(41)
    spec = VAR([record("healthy", 3000, rng) for _ in range(8)], 2)
    return spec.fit(), FTest(alpha=0.01, threshold="calibrated").calibrate(spec.held_out_residuals(), window=200), rng


def test_run_and_screen_warn_of_a_record_the_baseline_does_not_cover(fleet_baseline):
    """Monitor.run (issue 31): a record louder than the fitting records warns naming Monitor.run and the summaries
    out, and MonitorResult.coverage holds the check: the detection test's record law when it carries one
    (check_coverage), else the fitting records' summaries; screen has covered / outside per record and warns
    naming the record; a record like the fitting ones is covered, without a warning."""
    import warnings

    from tsfdi.coverage import check_coverage, coverage
    from tsfdi.exceptions import CoverageWarning

    b, test, rng = fleet_baseline
    ok, loud = record("healthy", 3000, rng), 1.5 * record("healthy", 3000, rng)
    law = tsfdi.Monitor(b, window=200, step=100, fs=FS, detection_test=test)
    plain = tsfdi.Monitor(b, window=200, step=100, fs=FS)
    with pytest.warns(CoverageWarning, match=r"Monitor.run: the record lies outside .*FTest\[y0\]"):
        res = law.run(loud)
    pd.testing.assert_frame_equal(res.coverage.table, check_coverage(test, b, loud).table)
    with pytest.warns(CoverageWarning, match=r"Monitor.run: the record lies outside .*log_scale\[all\]"):
        res = plain.run(loud)
    pd.testing.assert_frame_equal(res.coverage.table, coverage(b, loud).table)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CoverageWarning)
        assert law.run(ok).coverage.covered and plain.run(ok).coverage.covered
    with pytest.warns(CoverageWarning, match=r"Monitor.screen: record 1: the record lies outside .*FTest\[y0\]") as w:
        table = law.screen([ok, loud])
    assert len([x for x in w if issubclass(x.category, CoverageWarning)]) == 1
    assert table["covered"].tolist() == [True, False] and str(table["covered"].dtype) == "boolean"
    assert table["outside"].iloc[0] == "" and "FTest[y0]" in table["outside"].iloc[1]
    # several uncovered records (a fleet screened at once): one warning with their number and the first of them,
    # not one per record; each record's summaries out stay in the table
    louder = [(1.5 + 0.1 * i) * record("healthy", 3000, rng) for i in range(7)]
    with pytest.warns(CoverageWarning, match=r"Monitor.screen: 7 of 8 records checked lie outside .*records 1, 2, 3, "
                                             r"4, 5, \.\.\.\); the summaries out of each are in the 'outside' column"
                      ) as w:
        table = law.screen([ok, *louder])
    assert len([x for x in w if issubclass(x.category, CoverageWarning)]) == 1
    assert table["covered"].tolist() == [True] + [False] * 7 and (table["outside"].iloc[1:] != "").all()


def test_monitor_says_nothing_when_coverage_cannot_be_checked(models, fleet_baseline):
    """A baseline fitted on one record with an uncalibrated test, or a stream fed by update: coverage None, no
    warning, screen's covered <NA>."""
    import warnings

    from tsfdi.exceptions import CoverageWarning

    _, _, rng = fleet_baseline
    loud = 3.0 * record("healthy", 3000, rng)
    mon = _monitor(models)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CoverageWarning)
        assert mon.run(loud).coverage is None
        table = mon.screen([loud])
    assert table["covered"].isna().all() and table["outside"].tolist() == [""]


def test_functionally_pooled_models_are_filtered_at_the_streams_k():
    """An FP model has no single parameter set: a Monitor of FP models (alone or beside point models) asks for the
    stream's operating point, k={name: value}, instead of failing with an AttributeError inside the windowed engine,
    and with it is the Monitor of the point models .at(k)."""
    rng = np.random.default_rng(5)
    recs = [record("healthy", 1500, rng) * (1 + 0.2 * k) for k in (0.0, 0.5, 1.0)]
    fp = tsfdi.models.FPVAR(recs, [0.0, 0.5, 1.0], 2, degree=1).fit()
    (name,) = fp.model.k_names
    monitor = tsfdi.Monitor(fp, window=200, fs=FS, test=FTest(alpha=0.01))
    with pytest.raises(TypeError, match=rf"^k is required: the monitor's models are functionally pooled over "
                                        rf"\['{name}'\]"):
        monitor.run(recs[1])
    point = VAR(recs[0], 2).fit()
    mixed = tsfdi.Monitor(point, {"f": fp}, window=200, fs=FS, test=FTest(alpha=0.01))
    with pytest.raises(TypeError, match=r"^k is required"):
        mixed.run(recs[1])
    at = tsfdi.Monitor(fp.at(0.5), window=200, fs=FS, test=FTest(alpha=0.01)).run(recs[1])
    got = monitor.run(recs[1], k={name: 0.5})
    assert got.windows.shape[0] > 0
    pd.testing.assert_frame_equal(got.windows, at.windows)
    ref = tsfdi.Monitor(point, {"f": fp.at(0.5)}, window=200, fs=FS, test=FTest(alpha=0.01)).run(recs[1])
    pd.testing.assert_frame_equal(mixed.run(recs[1], k={name: 0.5}).windows, ref.windows)


def _arx_record(gain, n, rng, failure=None):
    """Output of two commands through a plant whose first command's gain drops to ``gain`` from ``failure``
    (a compensated loss of effectiveness seen in the command-response relation)."""
    import scipy.signal as sps

    u = rng.standard_normal((n, 2))
    g = np.ones(n)
    g[(0 if failure is None else failure):] = gain
    y = (sps.lfilter([0, 0.8], [1, -0.5], g * u[:, 0]) + sps.lfilter([0, 0, 0.5], [1, -0.5], u[:, 1])
         + 0.1 * rng.standard_normal(n))
    return y, u


@pytest.fixture(scope="module")
def arx_models():
    rng = np.random.default_rng(32)
    return {name: tsfdi.ARX(*_arx_record(g, 4000, rng), 1, 3, nk=1).fit()
            for name, g in (("healthy", 1.0), ("f1", 0.5), ("f2", 0.0))}


@pytest.mark.parametrize("rule", ["paper", "sprt"])
def test_arx_models_with_their_input(arx_models, rule):
    """Monitor with ARX models: the input ``u`` beside the stream, the windows those of ``identify_windows(y, u=)``;
    streamed block by block it gives the events of the whole record."""
    y, u = _arx_record(0.5, 3000, np.random.default_rng(33), failure=1000)
    opts = dict(fs=FS, steady_window="5s", steady_thresholds=[3 * y[1500:].var()])
    opts.update(dict(test=FTest(alpha=1e-4), window="5s", step="1s") if rule == "paper" else dict(rule="sprt"))
    mon = tsfdi.Monitor(arx_models["healthy"], {"f1": arx_models["f1"], "f2": arx_models["f2"]}, **opts)
    res = mon.run(y, u=u)
    assert 10.0 < res.detection_time <= 12.0 and res.label == "f1"
    if rule == "paper":
        wi = tsfdi.identify_windows(y, {"healthy": arx_models["healthy"]}, FTest(alpha=1e-4), window=500,
                                    step=100, u=u)
        np.testing.assert_allclose(res.windows["detect_statistic"], wi.statistic[:, 0, 0] / wi.threshold[:, 0, 0])
    mon.reset()
    streamed = []
    for k in range(0, y.shape[0], 137):
        streamed += mon.update(y[k:k + 137], u=u[k:k + 137])
    assert streamed == res.events
    pd.testing.assert_frame_equal(mon.result().windows, res.windows)
    # named: u's columns in another order, matched to the models' inputs by name
    named = {n: tsfdi.ARX(pd.Series(r.model.data.values[:, 0], name="gyro"),
                          pd.DataFrame(r.model.u_data.values, columns=["cmd_a", "cmd_b"]), 1, 3, nk=1).fit()
             for n, r in arx_models.items()}
    mon = tsfdi.Monitor(named["healthy"], {"f1": named["f1"], "f2": named["f2"]}, **opts)
    got = mon.run(pd.Series(y, name="gyro"), u=pd.DataFrame(u[:, ::-1], columns=["cmd_b", "cmd_a"]))
    assert got.events == res.events


@pytest.mark.parametrize("rule", ["paper", "sprt"])
def test_arx_named_inputs_in_each_models_own_order(arx_models, rule):
    """A fault model fitted on the inputs in another column order than the baseline takes them by name: the events
    are those of the same model fitted in the baseline's order."""
    def fit(res, cols):
        u = pd.DataFrame(res.model.u_data.values, columns=["cmd_a", "cmd_b"])[cols]
        return tsfdi.ARX(pd.Series(res.model.data.values[:, 0], name="gyro"), u, 1, 3, nk=1).fit()

    y, u = _arx_record(0.5, 3000, np.random.default_rng(35), failure=1000)
    opts = dict(fs=FS, steady_window="5s", steady_thresholds=[3 * y[1500:].var()])
    opts.update(dict(test=FTest(alpha=1e-4), window="5s", step="1s") if rule == "paper" else dict(rule="sprt"))
    base = fit(arx_models["healthy"], ["cmd_a", "cmd_b"])
    got, want = ({"f1": fit(arx_models["f1"], order), "f2": fit(arx_models["f2"], order)}
                 for order in (["cmd_b", "cmd_a"], ["cmd_a", "cmd_b"]))
    u = pd.DataFrame(u, columns=["cmd_a", "cmd_b"])
    res = tsfdi.Monitor(base, got, **opts).run(pd.Series(y, name="gyro"), u=u)
    assert res.events == tsfdi.Monitor(base, want, **opts).run(pd.Series(y, name="gyro"), u=u).events
    assert res.label == "f1"


def test_arx_input_required_or_refused(arx_models, models, failure_record):
    y, u = _arx_record(1.0, 1000, np.random.default_rng(34))
    mon = tsfdi.Monitor(arx_models["healthy"], window="5s", fs=FS, test=FTest(alpha=1e-4))
    with pytest.raises(TypeError, match="u is required"):
        mon.run(y)
    with pytest.raises(ValueError, match="u has 999 samples but signal has 1000"):
        mon.run(y, u=u[1:])
    with pytest.raises(ValueError, match=r"u has 1 channel\(s\) but the models were fitted with 2"):
        mon.run(y, u=u[:, 0])
    with pytest.raises(ValueError, match="signal and u have different indexes"):
        mon.run(pd.Series(y), u=pd.DataFrame(u, index=np.arange(1, 1001)))
    with pytest.raises(TypeError, match="u is only for input-output"):
        _monitor(models).run(failure_record, u=failure_record)
    with pytest.raises(TypeError, match="baseline and models mix input-output"):
        tsfdi.Monitor(arx_models["healthy"], {"f": tsfdi.AR(y, 2).fit()}, window="5s", fs=FS)
    one = tsfdi.ARX(y, u[:, 0], 1, 2).fit()
    with pytest.raises(ValueError, match="ARX models must share one set of inputs"):
        tsfdi.Monitor(arx_models["healthy"], {"f": one}, window="5s", fs=FS)
    with pytest.raises(TypeError, match="records: screen runs the records without an input"):
        mon.screen([y, y])

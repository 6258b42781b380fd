"""Monitor(rule="sprt"): sequential detection (restarted SPRT) and identification (restarted MSPRT), their error
rates and delays against the restart-SPRT theory, streaming exactness and bounded memory (issue 33)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from _synthetic_fdi import FS, record
from scipy import stats
from scipy.signal import lfilter

import tsfdi
from tsfdi import AR, SPRT, VAR, LjungBox

AR_POLY = [1.0, -1.2, 0.5]          # y[t] = 1.2 y[t-1] - 0.5 y[t-2] + e[t]


def _ar(e):
    return lfilter([1.0], AR_POLY, e)


# ---------------------------------------------------------------------------------------------- the theory
def _chain(sprt, theta, k, n=801):
    """The restarted statistic as a Markov chain on ``n`` cells of (B, A) (Brook & Evans 1972): transitions
    between cells, the probability of leaving below B and above A from each cell, and the cell of 0. The variance
    alternative's z = c (a Q - b), Q ~ theta chi2(k), integrated exactly over each cell: the overshoot is kept."""
    B, A = sprt.lower, sprt.upper
    c = sprt.scale_
    a, b = 0.5 * (1.0 - 1.0 / sprt.ratio) * c, 0.5 * k * np.log(sprt.ratio) * c
    edges = np.linspace(B, A, n + 1)
    mid = 0.5 * (edges[:-1] + edges[1:])
    cdf = stats.chi2.cdf(np.maximum((edges[None, :] - mid[:, None] + b) / (a * theta), 0.0), k)
    return np.diff(cdf, axis=1), cdf[:, 0], 1.0 - cdf[:, -1], int(np.argmin(np.abs(mid)))


def _samples_to_alarm(sprt, theta, k):
    """Mean samples to the first alarm from every cell (restart at 0 after a lower crossing)."""
    P, low, _, zero = _chain(sprt, theta, k)
    P[:, zero] += low
    return np.linalg.solve(np.eye(P.shape[0]) - P, np.ones(P.shape[0])), zero


def restart_sprt_theory(sprt, k, ratio):
    """(mean samples between false alarms, mean delay after a change to ``ratio`` from the stationary healthy
    statistic, mean delay from 0) of the monitor's restarted SPRT."""
    L0, zero = _samples_to_alarm(sprt, 1.0, k)
    P, low, up, _ = _chain(sprt, 1.0, k)
    P[:, zero] += low + up                                   # every cycle restarts at 0
    w, v = np.linalg.eig(P.T)
    pi = np.real(v[:, np.argmin(np.abs(w - 1.0))])
    pi /= pi.sum()
    L1, _ = _samples_to_alarm(sprt, ratio, k)
    return float(L0[zero]), float(pi @ L1), float(L1[zero])


def test_chain_theory_is_converged_and_wald_overestimates_the_rate(monkeypatch):
    sp = SPRT("variance", ratio=2.0, alpha=0.01, beta=0.01, restart=True)
    coarse = restart_sprt_theory(sp, 1, 2.0)
    monkeypatch.setattr(_chain, "__defaults__", (1601,))
    assert restart_sprt_theory(sp, 1, 2.0) == pytest.approx(coarse, rel=0.01)
    # the overshoot of the chi-square LLR: fewer alarms than Wald's alpha per ASN_0 cycle, slower than ASN_1
    assert coarse[0] > sp.asn(1.0) / 0.01 and coarse[2] > sp.asn(2.0)


# ---------------------------------------------------------------------------------------------- Monte Carlo
@pytest.fixture(scope="module")
def ar_baseline():
    return AR(_ar(np.random.default_rng(1).standard_normal(200_000)), 2).fit()


@pytest.fixture(scope="module")
def var_baseline():
    return VAR(record("healthy", 100_000, np.random.default_rng(2)), 2).fit()


@pytest.mark.parametrize("alpha, hours", [(0.01, 2.0), (0.001, 20.0)])
def test_false_alarms_per_hour_match_the_restart_sprt_theory_ar(ar_baseline, alpha, hours):
    sp = SPRT("variance", ratio=2.0, alpha=alpha, beta=alpha, restart=True)
    y = _ar(np.random.default_rng(3).standard_normal(int(hours * 3600 * FS)))
    res = tsfdi.Monitor(ar_baseline, rule="sprt", fs=FS, detection_test=sp, step="10s").run(y)
    alarms = int(res.windows["fault"].sum())        # steps of 10 s: at most one alarm each at these rates
    arl0, _, _ = restart_sprt_theory(sp, 1, 2.0)
    expected = hours * 3600 * FS / arl0
    # alarms form a renewal process with near-exponential gaps: Poisson counts, a 4-sigma band
    assert abs(alarms - expected) <= 4 * np.sqrt(expected) + 1, (alarms, expected)
    # Wald's per-cycle bound p <= alpha / (1 - beta) with the cycle length ASN_0 overestimates the rate
    assert alarms / hours <= 3600 * FS * alpha / (1 - alpha) / sp.asn(1.0)


def test_false_alarms_per_hour_match_the_restart_sprt_theory_var(var_baseline):
    sp = SPRT("variance", ratio=2.0, alpha=0.01, beta=0.01, restart=True)
    hours = 1.0
    y = record("healthy", int(hours * 3600 * FS), np.random.default_rng(4))
    res = tsfdi.Monitor(var_baseline, rule="sprt", fs=FS, detection_test=sp, step="10s").run(y)
    alarms = int(res.windows["fault"].sum())
    arl0, _, _ = restart_sprt_theory(sp, 2, 2.0)
    expected = hours * 3600 * FS / arl0
    assert abs(alarms - expected) <= 4 * np.sqrt(expected) + 1, (alarms, expected)
    assert alarms / hours <= 3600 * FS * 0.01 / 0.99 / sp.asn(1.0, nchan=2)


def test_detection_delay_on_a_variance_change_matches_the_theory_and_wald_asn(ar_baseline):
    sp = SPRT("variance", ratio=2.0, alpha=0.001, beta=0.001, restart=True)
    mon = tsfdi.Monitor(ar_baseline, rule="sprt", fs=FS, detection_test=sp)
    _, stationary, fresh = restart_sprt_theory(sp, 1, 2.0)
    g = np.random.default_rng(5)
    delays, starts = [], []
    for _ in range(300):
        c = int(g.integers(1000, 3000))
        e = g.standard_normal(c + 3000)
        e[c:] *= np.sqrt(2.0)
        y = _ar(e)
        mon.reset()
        if mon.update(y[:c]):                 # a false alarm before the change: not a delay
            continue
        det = [ev for ev in mon.update(y[c:]) if ev.kind == "detection"]
        delays.append(det[0].time * FS - c + 1)       # samples of the faulty law accumulated
        # the record starting in the fault: the statistic starts at 0, Wald's E_1[N]
        res = mon.run(_ar(g.standard_normal(3000) * np.sqrt(2.0)))
        starts.append(res.detection_time * FS + 1 - 2)    # the first residual is sample 2 (the AR order)
    d, s = np.array(delays), np.array(starts)
    assert d.size > 250
    # the monitor against the Markov-chain theory (overshoot kept), a 4-sigma band of the mean
    assert abs(d.mean() - stationary) <= 4 * d.std() / np.sqrt(d.size)
    assert abs(s.mean() - fresh) <= 4 * s.std() / np.sqrt(s.size)
    # from 0, within 20 % of Wald's ASN (the acceptance); from the running statistic it starts lower: longer
    assert s.mean() == pytest.approx(sp.asn(2.0), rel=0.2)
    assert sp.asn(2.0) < d.mean() < 1.6 * sp.asn(2.0)


# ---------------------------------------------------------------------------------------------- the monitor
@pytest.fixture(scope="module")
def models():
    rng = np.random.default_rng(11)
    return {s: VAR(record(s, 6000, rng), 2).fit() for s in ("healthy", "f1", "f2")}


def _monitor(models, **kw):
    return tsfdi.Monitor(models["healthy"], {"f1": models["f1"], "f2": models["f2"]}, rule="sprt", fs=FS,
                         steady_window="5s", **kw)


@pytest.mark.parametrize("fault", ["f1", "f2"])
def test_detection_then_identification_with_decision_times(models, fault):
    x = record(fault, 3000, np.random.default_rng(12), failure=1000)
    res = _monitor(models).run(x)
    assert [e.kind for e in res.events] == ["detection", "steady", "identification"]
    det, steady, ident = res.events
    assert 10.0 <= res.detection_time < 11.0 and det.time == res.detection_time
    assert det.window[0] <= det.window[1] == det.time
    assert steady.window[0] >= det.time and steady.time == res.steady_time
    assert ident.label == res.label == fault and ident.status == "identified"
    assert res.identification_time == ident.time >= res.steady_time
    assert ident.window[0] == steady.window[0]           # accumulated from the start of the steady state
    w = res.windows
    assert len(w) == 30 and list(w["end"]) == [float(i) for i in range(1, 31)]
    assert not w["fault"][:10].any() and w["fault"][10]
    assert (w["detect_statistic"][w["fault"]] >= 1).all() and (w["detect_statistic"][~w["fault"]] < 1).all()
    assert w["detect_pvalue"].isna().all()
    assert list(w["status"]).count("identified") == 1 and w["phase"].iloc[-1] == "identified"


def test_healthy_record_raises_nothing(models):
    x = record("healthy", 3000, np.random.default_rng(13))
    res = _monitor(models, sprt_alpha=1e-4).run(x)
    assert res.events == [] and res.detection_time is None and res.label is None
    assert res.identification_time is None


def test_detection_only(models):
    x = record("f1", 3000, np.random.default_rng(12), failure=1000)
    res = tsfdi.Monitor(models["healthy"], rule="sprt", fs=FS).run(x)
    assert [e.kind for e in res.events] == ["detection"] and res.label is None
    assert 10.0 <= res.detection_time < 11.0


@pytest.mark.parametrize("chunk", [1, 7, 37, 100, 1001])
def test_streaming_equals_batch_and_memory_is_bounded(models, chunk):
    x = record("f2", 3000, np.random.default_rng(14), failure=1000)
    whole = _monitor(models).run(x)
    mon = _monitor(models)
    sizes = []
    for i in range(0, x.shape[0], chunk):
        mon.update(x[i:i + chunk])
        sizes.append(mon._buffer.shape[0])
    res = mon.result()
    assert res.events == whole.events                                  # exactly the same times and labels
    # the residuals of a VAR filtered block by block round in the last bit (matrix products of other shapes)
    pd.testing.assert_frame_equal(res.windows, whole.windows, check_exact=False, rtol=1e-12)
    # the state kept between blocks: steady_window + the models' order samples (and the block being processed)
    assert max(sizes) <= 500 + 2 + chunk
    assert mon._w.shape == (2, 2)


def test_an_alarm_at_a_block_boundary_is_the_same(ar_baseline):
    # a healthy hour cut into blocks of coprime sizes: every alarm (rows) and the detection as on the whole record
    sp = SPRT("variance", ratio=2.0, alpha=0.01, beta=0.01, restart=True)
    y = _ar(np.random.default_rng(6).standard_normal(360_000))
    whole = tsfdi.Monitor(ar_baseline, rule="sprt", fs=FS, detection_test=sp).run(y)
    mon = tsfdi.Monitor(ar_baseline, rule="sprt", fs=FS, detection_test=sp)
    g = np.random.default_rng(7)
    i = 0
    while i < y.size:
        n = int(g.integers(1, 3000))
        mon.update(y[i:i + n])
        i += n
    pd.testing.assert_frame_equal(mon.result().windows, whole.windows, check_exact=True)
    assert whole.windows["fault"].sum() > 20


def test_data_kinds_and_time_index(models):
    x = record("f1", 3000, np.random.default_rng(12), failure=1000)
    ref = _monitor(models).run(x)
    frame = pd.DataFrame(x, columns=["y0", "y1"], index=pd.Index(np.arange(3000) / FS, name="time"))
    res = tsfdi.Monitor(models["healthy"], {"f1": models["f1"], "f2": models["f2"]}, rule="sprt",
                        steady_window="5s").run(frame)                      # fs read from the index
    assert res.events == ref.events


def test_calibrated_detection_test_and_scale_are_used(models):
    x = record("f1", 3000, np.random.default_rng(12), failure=1000)
    sp = SPRT("variance", ratio=2.0, restart=True)
    sp.scale_ = 0.5                        # as SPRT.calibrate sets it: half the evidence per sample
    slow = _monitor(models, detection_test=sp).run(x)
    fast = _monitor(models).run(x)
    assert slow.detection_time > fast.detection_time
    # the deciding sample (the end of the identification's window) comes later with less evidence per sample
    assert _monitor(models, sprt_scale=0.05).run(x).events[-1].window[1] > fast.events[-1].window[1]


def test_screen_runs_the_sequential_monitor(models):
    recs = [record(f, 3000, np.random.default_rng(20 + i), failure=1000) for i, f in enumerate(("f1", "f2"))]
    # sprt_alpha = 1e-3: at the default 0.01 this VAR(2) baseline raises a false alarm about every 50 s at 100 Hz
    table = _monitor(models, sprt_alpha=1e-3).screen(recs)
    assert list(table["label"]) == ["f1", "f2"]
    assert (table["detection_time"] >= 10.0).all()


def test_sequential_input_errors(models):
    h, f = models["healthy"], {"f1": models["f1"], "f2": models["f2"]}
    with pytest.raises(ValueError, match="window does not apply to rule='sprt'"):
        tsfdi.Monitor(h, f, rule="sprt", window="5s")
    with pytest.raises(TypeError, match="window is required"):
        tsfdi.Monitor(h, f)
    with pytest.raises(ValueError, match="test does not apply"):
        tsfdi.Monitor(h, f, rule="sprt", test=LjungBox())
    with pytest.raises(TypeError, match="detection_test with rule='sprt'"):
        tsfdi.Monitor(h, f, rule="sprt", detection_test=LjungBox())
    with pytest.raises(TypeError, match="restart=True"):
        tsfdi.Monitor(h, f, rule="sprt", detection_test=SPRT("variance"))
    with pytest.raises(ValueError, match="at least two"):
        tsfdi.Monitor(h, {"f1": models["f1"]}, rule="sprt")
    with pytest.raises(ValueError, match="sprt_alpha"):
        tsfdi.Monitor(h, f, rule="sprt", sprt_alpha=1.5)
    with pytest.raises(ValueError, match="sprt_scale"):
        tsfdi.Monitor(h, f, rule="sprt", sprt_scale=0.0)
    with pytest.raises(ValueError, match="rule"):
        tsfdi.Monitor(h, f, window=100, rule="wald")
    with pytest.raises(ValueError, match="more than the models' largest order"):
        tsfdi.Monitor(h, f, rule="sprt", fs=FS).run(np.zeros((2, 2)) + [[1.0, 2.0]])
    assert "rule='sprt'" in repr(tsfdi.Monitor(h, f, rule="sprt", fs=FS))

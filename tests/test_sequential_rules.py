"""Sequential decisions in the windowed engine, evaluate, Monitor and the command line (issue 33, part 2)."""

import numpy as np
import pytest
from scipy import stats

import tsfdi
from tsfdi.windows import ResidualWindows


def _models(rng):
    x = rng.standard_normal((600, 2))
    y = x.copy()
    y[1:] += 0.6 * y[:-1]
    return x, {"a": tsfdi.VAR(x, 2).fit(), "b": tsfdi.VAR(y, 3).fit()}


def test_engine_per_sample_loglik_is_the_gaussian_logpdf_and_the_windows_mean():
    rng = np.random.default_rng(3)
    x, models = _models(rng)
    rw = ResidualWindows(models).fit(x)
    ll = rw.loglik()
    assert ll.shape == (600 - 3, 2)
    for j, (name, res) in enumerate(models.items()):
        e = np.asarray(res.residuals(x))[3 - res.lags:]
        np.testing.assert_allclose(ll[:, j], stats.multivariate_normal(np.zeros(2), res.sigma).logpdf(e), rtol=1e-10)
    ws = rw.statistics(tsfdi.LjungBox(lags=5), window=100, step=40)
    for w, s in enumerate(ws.starts):
        np.testing.assert_allclose(ws.loglik[w], ll[s:s + 97].mean(axis=0), rtol=1e-12)
    np.testing.assert_array_equal(rw.loglik(common=10), ll[7:])


def test_engine_loglik_refuses_bad_common_and_an_unfitted_engine():
    rng = np.random.default_rng(4)
    x, models = _models(rng)
    with pytest.raises(ValueError, match="not fitted"):
        ResidualWindows(models).loglik()
    rw = ResidualWindows(models).fit(x)
    with pytest.raises(ValueError, match="common"):
        rw.loglik(common=2)           # below the largest order: model "b" has no residual there
    with pytest.raises(ValueError, match="common"):
        rw.loglik(common=600)


# ------------------------------------------------------------------------------------------------ evaluate
def test_evaluate_sprt_rule_is_msprt_on_each_fault_record(synthetic, fitted):
    """Every fault record is decided once by msprt on the fault models' per-sample log-likelihoods from settle s
    after its failure; the counts, rates and times are those decisions."""
    from tsfdi.detection.sequential import msprt

    recs, states, ft = synthetic
    ev = tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=100.0, models=["var"], windows=["10s"],
                        settle=5.0, rules=("paper", "sprt"), progress=False, sprt_alpha=1e-3)
    assert ev.rules == ("paper",) and ev.sprt == {"alpha": 1e-3, "scale": {("", "var"): 1.0}}
    faults = fitted.faults
    models = {f: fitted.models["var"][f] for f in faults}
    expected = {}
    for i, x in enumerate(recs):
        if states[i] == fitted.healthy or i in fitted.fit_records:
            continue
        rw = ResidualWindows(models).fit(x)
        seq = msprt(rw.loglik(common=int(np.ceil((ft[i] + 5.0) * 100))), alpha=1e-3)
        key = (states[i], faults[seq.label] if seq.label >= 0 else "undecided",
               seq.decision_time / 100.0 if seq.label >= 0 else None)
        expected[key] = expected.get(key, 0) + 1
    got = {(r.state, r.label, None if np.isnan(r.time) else r.time): r.records
           for r in ev.sequential_counts.itertuples()}
    assert got.keys() == expected.keys()
    for k, n in expected.items():
        assert got[k] == n
    rates = ev.sequential_rates()
    np.testing.assert_allclose(rates[["correct", "wrong", "undecided"]].sum(axis=1), 100.0)
    assert rates["records"].sum() == sum(expected.values())
    for (_, true), row in rates.iterrows():
        t = np.concatenate([[k[2]] * n for k, n in expected.items() if k[0] == true and k[2] is not None])
        assert row["time_mean"] == pytest.approx(t.mean()) and row["time_q90"] == pytest.approx(np.quantile(t, 0.9))
    np.testing.assert_allclose(ev.sequential_confusion().sum(axis=1), 100.0)
    assert "Sequential" in str(ev.summary())


def test_evaluate_sprt_is_refused_by_name_when_absent_or_bad(synthetic, fitted):
    recs, states, ft = synthetic
    kw = dict(states=states, failure_times=ft, fs=100.0, models=["var"], windows=["10s"], settle=5.0, progress=False)
    ev = tsfdi.evaluate(recs, fitted, rules=("paper",), **kw)
    assert ev.sequential_counts.empty
    with pytest.raises(ValueError, match="sprt"):
        ev.sequential_rates()
    for bad in (0.0, 1.0, -1, float("nan")):
        with pytest.raises(ValueError, match="sprt_alpha"):
            tsfdi.evaluate(recs, fitted, rules=("sprt",), sprt_alpha=bad, **kw)
    with pytest.raises(ValueError, match="rules"):
        tsfdi.evaluate(recs, fitted, rules=("sprtt",), **kw)


def test_evaluate_sprt_scale_comes_from_the_held_out_fitting_records(synthetic):
    """With held-out residuals (calibrate=True) the scale is msprt_scale of every fault state's fitting records
    through every fault model, its own state's model refitted without it; never of an evaluation record."""
    from tsfdi.detection.sequential import msprt_scale

    recs, states, ft = synthetic
    b = tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=100.0, settle=5.0, duration=None, max_lags=6,
                            var_max_lags=6, steady_window="5s", calibrate=True, fit_records=2)
    ev = tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=100.0, models=["var"], windows=["10s"],
                        settle=5.0, rules=("sprt",), progress=False, detection=False)
    models = {f: b.models["var"][f] for f in b.faults}
    lls, labels = [], []
    for j, f in enumerate(b.faults):
        for i, seg in enumerate(b.segments[f]):
            given = {g: b.heldout[("var", f)][i] if g == f else models[g].residuals(seg) for g in b.faults}
            lls.append(ResidualWindows(models).fit_residuals(given, seg.shape[0]).loglik())
            labels.append(j)
    scale = ev.sprt["scale"][("", "var")]
    assert scale == msprt_scale(lls, labels) and scale != 1.0


def test_evaluate_sprt_needs_two_fault_models(synthetic):
    recs, states, ft = synthetic
    keep = [i for i, s in enumerate(states) if s in ("healthy", states[-1])]
    sub = [recs[i] for i in keep]
    st = [states[i] for i in keep]
    ftt = [ft[i] for i in keep]
    b = tsfdi.fit_baselines(sub, states=st, failure_times=ftt, fs=100.0, settle=5.0, duration=None, max_lags=6,
                            var_max_lags=6, steady_window="5s")
    with pytest.raises(ValueError, match="rules: 'sprt'.*two"):
        tsfdi.evaluate(sub, b, states=st, failure_times=ftt, fs=100.0, models=["var"], windows=["10s"], settle=5.0,
                       rules=("sprt",), progress=False)


def test_baselines_monitor_with_the_sequential_rule(synthetic):
    """Baselines.monitor(rule="sprt") gives the sequential Monitor with the baselines' scale (it passed a window
    and a test, which the sequential monitor refuses); on a fault record it identifies the record's state, the same
    events as the Monitor built by hand with that scale."""
    recs, states, ft = synthetic
    b = tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=100.0, settle=5.0, duration=None, max_lags=6,
                            var_max_lags=6, steady_window="5s", calibrate=True, fit_records=2)
    ev = tsfdi.evaluate(recs, b, states=states, failure_times=ft, fs=100.0, models=["var"], windows=["10s"],
                        settle=5.0, rules=("sprt",), progress=False, detection=False)
    assert b.sprt_scale("var") == ev.sprt["scale"][("", "var")] != 1.0
    mon = b.monitor("var", rule="sprt", sprt_alpha=1e-3)
    assert mon.sequential and mon.sprt_scale == b.sprt_scale("var") and mon.sprt_alpha == 1e-3
    i = next(i for i, s in enumerate(states) if s != "healthy" and i not in b.fit_records)
    res = mon.run(recs[i])
    hand = tsfdi.Monitor(b.models["var"]["healthy"], {f: b.models["var"][f] for f in b.faults}, fs=100.0,
                         rule="sprt", sprt_alpha=1e-3, sprt_scale=b.sprt_scale("var"),
                         steady_thresholds=b.steady_thresholds, steady_window=b.steady_window).run(recs[i])
    assert res.label == states[i] and res.to_frame().equals(hand.to_frame())
    with pytest.raises(ValueError, match="test"):
        b.monitor("var", rule="sprt", test=tsfdi.LjungBox(lags=10))
    with pytest.raises(ValueError, match="window"):
        b.monitor("var", rule="sprt", window="10s")
    plain = tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=100.0, settle=5.0, duration=None,
                                max_lags=6, var_max_lags=6, steady_window="5s", fit_records=2)
    assert plain.monitor("var", rule="sprt").sprt_scale == 1.0     # no held-out residuals: exact-model scale

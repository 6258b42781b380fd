"""Sequential tests (issue 33): Wald's bounds, the per-sample log-likelihood ratios against scipy, the decision
rule against a plain loop, OC / ASN closed forms, the MSPRT kernel, data kinds and input checks."""

from __future__ import annotations

import dataclasses

import matplotlib.figure
import numpy as np
import pandas as pd
import pytest
from conftest import as_kind
from scipy import integrate, stats

from tsfdi.detection import sequential
from tsfdi.detection.sequential import (SPRT, aligned_record_effect, SequentialDecision, SequentialIdentification, msprt, msprt_scale,
                                        record_effect, wald_bounds)


def loop_sprt(z, lower, upper, restart=False):
    """Reference: Wald's rule sample by sample."""
    s, restarts = 0.0, 0
    for t, v in enumerate(z):
        s += v
        if s >= upper:
            return t + 1, True, restarts
        if s <= lower:
            if not restart:
                return t + 1, False, restarts
            restarts += 1
            s = 0.0
    return -1, False, restarts


def loop_msprt(ll, bound, restart=False):
    m = ll.shape[1]
    s = np.zeros(m)
    w = np.zeros((m, m))
    for t in range(ll.shape[0]):
        if restart:
            w = np.maximum(0.0, w + ll[t][:, None] - ll[t][None, :])
            d = np.array([min(w[j, k] for k in range(m) if k != j) for j in range(m)])
        else:
            s += ll[t]
            d = np.array([s[j] - max(s[k] for k in range(m) if k != j) for j in range(m)])
        if d.max() >= bound:
            return int(np.argmax(d)), t + 1
    return -1, -1


def test_wald_bounds():
    lo, hi = wald_bounds(0.05, 0.1)
    assert hi == pytest.approx(np.log(0.9 / 0.05)) and lo == pytest.approx(np.log(0.1 / 0.95))
    with pytest.raises(ValueError, match="alpha"):
        wald_bounds(0.0, 0.1)
    with pytest.raises(ValueError, match="beta"):
        wald_bounds(0.1, 1.0)
    with pytest.raises(ValueError, match="alpha \\+ beta"):
        wald_bounds(0.6, 0.5)


def test_llr_against_scipy():
    rng = np.random.default_rng(0)
    e = rng.standard_normal((50, 2)) * [1.0, 2.0]
    var = np.array([1.0, 4.0])
    z = SPRT("variance", ratio=3.0).loglik_ratio(e, var)
    ref = (stats.norm.logpdf(e, scale=np.sqrt(3 * var)) - stats.norm.logpdf(e, scale=np.sqrt(var))).sum(axis=1)
    np.testing.assert_allclose(z, ref, rtol=1e-12)
    cov = np.array([[1.0, 0.6], [0.6, 4.0]])
    z = SPRT("variance", ratio=0.5).loglik_ratio(e, cov)
    ref = (stats.multivariate_normal(cov=0.5 * cov).logpdf(e) - stats.multivariate_normal(cov=cov).logpdf(e))
    np.testing.assert_allclose(z, ref, rtol=1e-10)
    z = SPRT("mean", shift=[0.5, -1.0]).loglik_ratio(e, cov)
    mu = np.array([0.5, -2.0])
    ref = stats.multivariate_normal(mu, cov).logpdf(e) - stats.multivariate_normal(cov=cov).logpdf(e)
    np.testing.assert_allclose(z, ref, rtol=1e-10)
    f = rng.standard_normal((50, 2))
    z = SPRT("model").loglik_ratio(e, cov, fault_residuals=f, fault_sigma=[2.0, 3.0])
    ref = (stats.multivariate_normal(cov=np.diag([2.0, 3.0])).logpdf(f) - stats.multivariate_normal(cov=cov).logpdf(e))
    np.testing.assert_allclose(z, ref, rtol=1e-10)


@pytest.mark.parametrize("restart", [False, True])
def test_decision_matches_loop(restart):
    rng = np.random.default_rng(1)
    test = SPRT("mean", shift=0.3, alpha=0.05, beta=0.1, restart=restart)
    for i in range(30):
        e = rng.standard_normal(400) + (0.3 if i % 2 else 0.0)
        d = test.test(e, sigma=1.0)
        n, rej, restarts = loop_sprt(test.loglik_ratio(e, 1.0), test.lower, test.upper, restart)
        assert (d.decision_time, d.reject, d.decided, d.restarts) == (n, rej, n > 0, restarts)
        if not restart and n > 0:
            np.testing.assert_allclose(d.statistic, np.cumsum(test.loglik_ratio(e, 1.0)))


def test_kinds_and_seconds(kind):
    e = np.random.default_rng(2).standard_normal((300, 2)) * 1.4
    d = SPRT("variance", ratio=2.0).test(as_kind(e, kind, ["p", "q"]), sigma=[1.0, 1.0])
    ref = SPRT("variance", ratio=2.0).test(e, sigma=[1.0, 1.0])
    np.testing.assert_array_equal(d.statistic, ref.statistic)
    assert d.decision_time == ref.decision_time > 0
    if kind == "numpy":
        assert np.isnan(d.decision_seconds) and d.time is None and d.channels == ("y0", "y1")
    else:
        assert d.decision_seconds == pytest.approx(d.decision_time * 0.01) and d.channels == ("p", "q")
    assert SPRT().test(e, sigma=1.0, fs=50.0).decision_seconds == pytest.approx(
        SPRT().test(e, sigma=1.0).decision_time / 50.0)


def test_decision_is_frozen_and_displays():
    d = SPRT("variance").test(np.random.default_rng(3).standard_normal(200) * 2, sigma=1.0)
    assert isinstance(d, SequentialDecision)
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.reject = False
    with pytest.raises(ValueError):
        d.statistic[0] = 1.0
    assert "reject" in repr(d) and "Decision time" in str(d.summary())
    assert isinstance(d.plot(), matplotlib.figure.Figure)


def test_oc_asn_closed_forms():
    for test, null, alt in ((SPRT("variance", ratio=1.8, alpha=0.03, beta=0.07), 1.0, 1.8),
                            (SPRT("mean", shift=0.4, alpha=0.03, beta=0.07), 0.0, 0.4)):
        A, B = test.upper, test.lower
        assert test.oc(null) == pytest.approx(0.97) and test.oc(alt) == pytest.approx(0.07)
        z0 = test.loglik_ratio(np.zeros(1), 1.0)[0]
        if test.alternative == "variance":
            e0 = 0.5 * ((1 - 1 / 1.8) - np.log(1.8))
            e1 = 0.5 * ((1 - 1 / 1.8) * 1.8 - np.log(1.8))
        else:
            e0, e1 = z0, z0 + 0.4 * 0.4
        assert test.asn(null) == pytest.approx((0.97 * B + 0.03 * A) / e0)
        assert test.asn(alt) == pytest.approx((0.07 * B + 0.93 * A) / e1)
        oc = test.oc(np.linspace(null - 0.3 if null else 0.5, alt + 0.5, 9))
        assert np.all(np.diff(oc) < 0)


def test_oc_h_solves_wald_equation():
    """h(theta) of the variance alternative: E_theta[exp(h z)] = 1, by quadrature over chi2(2)."""
    test = SPRT("variance", ratio=2.0)
    for theta in (0.7, 1.3, 1.6, 2.5):
        h, _, _ = test._h_moments(np.array(theta), 2)
        f = lambda q: np.exp(h * 0.5 * (0.5 * theta * q - 2 * np.log(2.0)) + stats.chi2.logpdf(q, 2))  # noqa: E731
        assert integrate.quad(f, 0, np.inf)[0] == pytest.approx(1.0, rel=1e-8)


def test_monte_carlo_agrees_with_theory():
    mc = SPRT("variance", ratio=1.5, alpha=0.05, beta=0.05).monte_carlo([1.0, 1.25, 1.5], n_rep=400, rng=4)
    assert list(mc.columns) == ["accept", "reject", "undecided", "mean_n", "std_n", "oc", "asn"]
    assert (mc["undecided"] == 0).all()
    assert np.all(np.abs(mc["accept"] - mc["oc"]) < 0.08)
    assert np.all(np.abs(mc["mean_n"] / mc["asn"] - 1) < 0.25)


def test_calibrate_white_residuals_keeps_scale_one():
    e = list(np.random.default_rng(5).standard_normal((20, 2000)))
    for test in (SPRT("variance", ratio=1.5), SPRT("mean", shift=0.3)):
        assert test.calibrate(e, 1.0).scale_ == pytest.approx(1.0, abs=0.1)
        assert "scale_" in repr(test)
    with pytest.raises(ValueError, match="blocks"):
        SPRT().calibrate(np.zeros(100), 1.0)


@pytest.mark.parametrize("restart", [False, True])
def test_msprt_matches_loop(restart):
    rng = np.random.default_rng(6)
    for i in range(20):
        ll = rng.standard_normal((300, 4))
        ll[:, i % 4] += 0.3
        out = msprt(ll, alpha=0.05, restart=restart)
        bound = np.log(3 / 0.05)
        assert out.bound == pytest.approx(bound)
        assert (out.label, out.decision_time) == loop_msprt(ll, bound, restart)
    out = msprt(ll, alpha=0.05, start=100, scale=0.5)
    assert out.statistic.shape == (200, 4)
    assert (out.label, out.decision_time) == loop_msprt(0.5 * ll[100:], bound)


def test_msprt_kinds_names_and_display(kind):
    ll = np.random.default_rng(7).standard_normal((200, 3))
    ll[:, 2] += 0.5
    out = msprt(as_kind(ll, kind, ["healthy", "rotor1", "rotor2"]))
    assert isinstance(out, SequentialIdentification)
    assert out.label == 2 and out.decided and out.status == "identified"
    if kind == "numpy":
        assert out.models == ("m0", "m1", "m2") and np.isnan(out.decision_seconds)
    else:
        assert out.name == "rotor2" and out.decision_seconds == pytest.approx(out.decision_time * 0.01)
    assert msprt(ll, models=["a", "b", "c"]).name == "c"
    assert "rotor2" in str(out.summary()) or kind == "numpy"
    assert isinstance(out.plot(), matplotlib.figure.Figure)
    undecided = msprt(np.zeros((10, 3)))
    assert (undecided.label, undecided.decision_time, undecided.name) == (-1, -1, None)


def test_plot_oc_asn():
    from tsfdi.plotting.sequential import plot_oc_asn

    test = SPRT("mean", shift=0.5, alpha=0.05, beta=0.05)
    fig = plot_oc_asn(test, np.linspace(-0.2, 0.8, 21), monte_carlo=test.monte_carlo([0.0, 0.5], n_rep=50, rng=0))
    assert isinstance(fig, matplotlib.figure.Figure) and len(fig.axes) == 2


@pytest.mark.parametrize("call, exc, match", [
    (lambda: SPRT("nope"), ValueError, "alternative"),
    (lambda: SPRT("variance", ratio=1.0), ValueError, "ratio"),
    (lambda: SPRT("variance", ratio=-2), ValueError, "ratio"),
    (lambda: SPRT("variance", shift=1.0), ValueError, "shift"),
    (lambda: SPRT("mean", shift=0.0), ValueError, "shift"),
    (lambda: SPRT("mean", shift="x"), TypeError, "shift"),
    (lambda: SPRT(alpha=1.5), ValueError, "alpha"),
    (lambda: SPRT(restart=1), TypeError, "restart"),
    (lambda: SPRT().test(np.ones(10)), TypeError, "sigma"),
    (lambda: SPRT().test(np.ones(10), sigma=-1.0), ValueError, "sigma"),
    (lambda: SPRT().test(np.ones((10, 2)), sigma=[1.0, 2.0, 3.0]), ValueError, "sigma"),
    (lambda: SPRT().test(np.ones((10, 2)), sigma=[[1.0, 2.0], [2.0, 1.0]]), ValueError, "sigma"),
    (lambda: SPRT().test(np.r_[1.0, np.nan], sigma=1.0), ValueError, "resid"),
    (lambda: SPRT("mean", shift=[1.0, 2.0]).test(np.ones((10, 3)), sigma=1.0), ValueError, "shift"),
    (lambda: SPRT("model").test(np.ones(10), sigma=1.0), TypeError, "fault_residuals"),
    (lambda: SPRT("model").test(np.ones(10), sigma=1.0, fault_residuals=np.ones(9), fault_sigma=1.0),
     ValueError, "fault_residuals"),
    (lambda: SPRT().test(np.ones(10), sigma=1.0, fault_residuals=np.ones(10)), ValueError, "fault_residuals"),
    (lambda: SPRT("model").oc(1.0), ValueError, "oc and asn"),
    (lambda: SPRT().oc(-1.0), ValueError, "theta"),
    (lambda: SPRT().asn("a"), TypeError, "theta"),
    (lambda: SPRT().monte_carlo(1.0, n_rep=0), ValueError, "n_rep"),
    (lambda: msprt(np.ones((10, 1))), ValueError, "loglik"),
    (lambda: msprt(np.ones((10, 2)), alpha=0), ValueError, "alpha"),
    (lambda: msprt(np.ones((10, 2)), start=10), ValueError, "start"),
    (lambda: msprt(np.ones((10, 2)), scale=0), ValueError, "scale"),
    (lambda: msprt(np.ones((10, 2)), models=["a"]), ValueError, "models"),
    (lambda: msprt(np.full((10, 2), np.inf)), ValueError, "loglik"),
    (lambda: msprt_scale([np.ones((700, 2))], [0, 1]), ValueError, "labels"),
    (lambda: msprt_scale([np.ones((700, 2))], [2]), ValueError, "labels"),
])
def test_input_checks(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


# ------------------------------------------------------------------ record effect
def record_law_data(seed=3, M=3, k=2, R=6, n=400):
    rng = np.random.default_rng(seed)
    held = {f"m{j}": [rng.normal(0.2 * j, 1.0 + 0.1 * j, (n, k)) + rng.normal(0, 0.1, k) for _ in range(R)]
            for j in range(M)}
    return rng, held


def test_record_effect_loglik_telescopes_to_the_summaries_predictive_density():
    rng, held = record_law_data()
    law = record_effect(held, block=20)
    resid = [rng.normal(0.1, 1.1, (300, 2)) for _ in range(3)]
    ll = law.loglik(resid)
    assert ll.shape == (300, 3)
    assert np.all(ll[: law.min_samples - 1] == 0.0) and np.all(ll[law.min_samples - 1] != 0.0)
    for j, e in enumerate(resid):
        for n in (law.min_samples, 150, 300):
            f = np.r_[e[:n].mean(axis=0), 0.5 * np.log(np.mean(e[:n] ** 2, axis=0))]
            ref = stats.multivariate_t(law.center[j], law.between[j] + law.within[j] / n, df=law.df[j]).logpdf(f)
            assert ll[:n, j].sum() == pytest.approx(ref, rel=1e-9, abs=1e-9)
    # the mapping form reads the residuals by model name
    assert np.array_equal(law.loglik(dict(zip(["m2", "m0", "m1"], [resid[2], resid[0], resid[1]]))), ll)


def test_record_effect_law_estimates():
    _, held = record_law_data()
    law = record_effect(held, block=20)
    f = {m: np.array([np.r_[e.mean(axis=0), 0.5 * np.log(np.mean(e ** 2, axis=0))] for e in recs])
         for m, recs in held.items()}
    dev = np.vstack([v - v.mean(axis=0) for v in f.values()])
    S = dev.T @ dev / (3 * 5)
    assert np.allclose(law.center, [v.mean(axis=0) for v in f.values()])
    # the scale of the t law: S (1 + 1/R) nu / (nu - q + 1), nu = 15, q = 4 (Hotelling's predictive law)
    assert np.allclose(law.between[0], S * (1 + 1 / 6) * 15 / 12)
    assert np.allclose(law.df, 15 - 4 + 1)
    assert law.records == (6, 6, 6) and law.models == ("m0", "m1", "m2")
    assert law.summaries == ("mean[y0]", "mean[y1]", "log_scale[y0]", "log_scale[y1]")
    # white residuals: the long-run covariance of the running mean is the residual covariance
    assert np.allclose(np.diag(law.within[0])[:2], 1.0, atol=0.25)
    assert "RecordEffect(models=3" in repr(law)


def test_record_effect_keeps_the_named_summaries_only():
    # raw signals as every model's "residuals": the trim of channel 1 and the scale of channel 0 carry the state,
    # the other summaries are left out (their degrees of freedom kept for the spread); the law and its loglik are
    # those of the kept summaries, in the order given
    rng, held = record_law_data()
    keep = ["mean[y1]", "log_scale[y0]"]
    law = record_effect(held, block=20, summaries=keep)
    ref = record_effect(held, block=20)
    idx = [ref.summaries.index(s) for s in keep]
    assert law.summaries == tuple(keep) and law.nchan == 2
    assert np.allclose(law.center, ref.center[:, idx])
    dev = np.vstack([np.array([np.r_[e.mean(axis=0), 0.5 * np.log(np.mean(e ** 2, axis=0))] for e in recs])[:, idx]
                     for recs in held.values()])
    dev = np.vstack([d - d.mean(axis=0) for d in np.split(dev, 3)])
    assert np.allclose(law.between[0], dev.T @ dev / 15 * (1 + 1 / 6) * 15 / 14)
    assert np.allclose(law.within, ref.within[:, idx][:, :, idx]) and np.allclose(law.df, 15 - 2 + 1)
    resid = [rng.normal(0.1, 1.1, (300, 2)) for _ in range(3)]
    ll = law.loglik(resid)
    for j, e in enumerate(resid):
        f = np.r_[e.mean(axis=0), 0.5 * np.log(np.mean(e ** 2, axis=0))][idx]
        d = stats.multivariate_t(law.center[j], law.between[j] + law.within[j] / 300, df=law.df[j]).logpdf(f)
        assert ll[:, j].sum() == pytest.approx(d, rel=1e-9)
    # one summary: still a (1, 1) covariance
    assert record_effect(held, block=20, summaries=["mean[y0]"]).within.shape == (3, 1, 1)
    with pytest.raises(ValueError, match=r"summaries: 'mean\[y2\]' is not one of the 4 summaries"):
        record_effect(held, block=20, summaries=["mean[y2]"])
    with pytest.raises(ValueError, match="a name given twice"):
        record_effect(held, block=20, summaries=["mean[y0]", "mean[y0]"])
    with pytest.raises(TypeError, match="summaries"):
        record_effect(held, block=20, summaries="mean[y0]")


def test_record_effect_model_with_one_record():
    # a model (e.g. a condition on one airframe) with a single held-out record: its centre is that record's
    # summaries, its predictive covariance twice the spread pooled over the other models, which alone give the
    # degrees of freedom
    _, held = record_law_data()
    one = {**held, "m3": held["m2"][:1]}
    law = record_effect(one, block=20)
    ref = record_effect(held, block=20)
    e = held["m2"][0]
    assert law.records == (6, 6, 6, 1) and law.models[-1] == "m3"
    assert np.allclose(law.center[3], np.r_[e.mean(axis=0), 0.5 * np.log(np.mean(e ** 2, axis=0))])
    S = ref.between[0] / (1 + 1 / 6)
    assert np.allclose(law.between[3], 2.0 * S) and np.allclose(law.between[0], ref.between[0])
    assert np.allclose(law.df, ref.df[0])
    assert np.isfinite(law.loglik([e] * 4)).all()


def test_record_effect_evidence_saturates_where_the_gaussian_grows():
    # a record of state 0 whose trim sits between two states' centres: the Gaussian log-likelihood ratio grows
    # with every sample, the record-effect one settles at the summaries' density ratio
    rng = np.random.default_rng(0)
    held = {"a": [rng.normal(u, 1.0, (500, 1)) for u in rng.normal(0.0, 0.3, 8)],
            "b": [rng.normal(u, 1.0, (500, 1)) for u in rng.normal(0.0, 0.3, 8)]}
    law = record_effect(held, block=25)
    e = rng.normal(0.4, 1.0, (20000, 1))
    s = np.cumsum(law.loglik([e, e - 0.3]), axis=0)
    d = s[:, 0] - s[:, 1]
    assert abs(d[-1] - d[len(d) // 2]) < 0.1 * abs(d[-1]) + 0.5
    g = -0.5 * np.cumsum(e[:, 0] ** 2 - (e[:, 0] - 0.3) ** 2)
    assert abs(g[-1]) > 1.8 * abs(g[len(g) // 2]) > 100


def test_record_effect_input_checks():
    _, held = record_law_data()
    with pytest.raises(TypeError, match="held_out"):
        record_effect([held["m0"], held["m1"]])
    with pytest.raises(TypeError, match="held_out"):
        record_effect({"m0": held["m0"]})
    with pytest.raises(TypeError, match=r"held_out\['m0'\]"):
        record_effect({"m0": held["m0"][0], "m1": held["m1"]})
    with pytest.raises(ValueError, match=r"held_out\['m1'\]\[0\] has 3 channel"):
        record_effect({"m0": held["m0"], "m1": [np.ones((400, 3))] + held["m1"][1:]})
    with pytest.raises(ValueError, match="blocks of 300 samples"):
        record_effect(held, block=300)
    with pytest.raises(ValueError, match="degrees of freedom"):
        record_effect({m: v[:2] for m, v in held.items()}, block=20)
    with pytest.raises(ValueError, match="not finite"):
        record_effect({"m0": held["m0"], "m1": [np.zeros((400, 2))] + held["m1"][1:]}, block=20)
    with pytest.raises(ValueError, match="lags"):
        record_effect(held, lags=-1)
    law = record_effect(held, block=20)
    e = np.ones((100, 2))
    with pytest.raises(ValueError, match="one residual array per model"):
        law.loglik([e, e])
    with pytest.raises(ValueError, match=r"no entry for the model 'm2'"):
        law.loglik({"m0": e, "m1": e})
    with pytest.raises(ValueError, match=r"resid\['m1'\] has 90 samples"):
        law.loglik([e, e[:90], e])
    with pytest.raises(ValueError, match=r"resid\['m2'\] has 1 channel"):
        law.loglik([e, e, e[:, :1]])
    with pytest.raises(ValueError, match=r"resid\['m0'\]"):
        law.loglik([np.full((100, 2), np.nan), e, e])
    with pytest.raises(ValueError, match=r"resid\['m0'\]: a channel's residuals are zero"):
        law.loglik([np.zeros((100, 2)), e, e])


def test_record_effect_singular_between_covariance_and_chunks(monkeypatch):
    # summaries that do not vary over the records: no between-record law (a ValueError, not a LinAlgError)
    rng = np.random.default_rng(1)
    same = rng.standard_normal((400, 1))
    with pytest.raises(ValueError, match="singular"):
        record_effect({"a": [same] * 4, "b": [same + 1] * 4}, block=20)
    # the covariances are made in bounded chunks: the same result with tiny chunks
    _, held = record_law_data()
    law = record_effect(held, block=20)
    resid = [rng.normal(0.0, 1.0, (300, 2)) for _ in range(3)]
    ref = law.loglik(resid)
    monkeypatch.setattr(sequential, "MAX_VALUES", 8 * 16 * 7)
    assert np.allclose(law.loglik(resid), ref, rtol=1e-12, atol=1e-12)


def test_msprt_state_continues_a_stream_in_chunks():
    """msprt(..., restart=True, state=previous.state) on the next chunk continues the pairwise CUSUMs: chunks give the
    whole record's statistics and decision (what the sequential Monitor relies on); the plain form's state is the
    pairwise differences of the cumulative sums; a bad state is refused by name."""
    rng = np.random.default_rng(12)
    ll = rng.standard_normal((900, 3)) * 0.3
    ll[400:, 2] += 0.2                                   # model 2 takes over after a change
    whole = msprt(ll, alpha=0.01, restart=True)
    assert whole.decided and whole.label == 2
    state, seen = None, 0
    for a, b in ((0, 137), (137, 390), (390, 900)):
        part = msprt(ll[a:b], alpha=0.01, restart=True, state=state)
        np.testing.assert_allclose(part.statistic, whole.statistic[a:b], rtol=0, atol=1e-12)
        if part.decided:
            assert seen + part.decision_time == whole.decision_time and part.label == whole.label
            break
        state, seen = part.state, b
    else:
        raise AssertionError("the chunks never decided")
    plain = msprt(ll, alpha=0.01)
    s = ll.sum(axis=0)
    np.testing.assert_allclose(plain.state, s[:, None] - s[None, :], atol=1e-9)
    with pytest.raises(ValueError, match="state is for restart=True"):
        msprt(ll, state=np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"state must be the finite non-negative \(3, 3\)"):
        msprt(ll, restart=True, state=-np.ones((3, 3)))


def test_renewal_walk_restarts_at_both_bounds_and_continues_in_chunks():
    """renewal_walk: the statistic restarts at 0 at each crossing of either bound, alarms where it reaches the upper
    one, skips non-finite samples, and a stream fed in chunks (state, start carried) walks as the whole record."""
    rng = np.random.default_rng(14)
    z = rng.normal(0.05, 1.0, 600)
    z[[17, 300]] = np.nan
    path, alarm, cycle, lowers, s, start = sequential.renewal_walk(z, -2.0, 3.0)
    ref_s, ref_start, ref_low, ref_alarm = 0.0, 0, 0, []
    for t, v in enumerate(z):                       # the rule, sample by sample
        assert cycle[t] == ref_start
        if not np.isfinite(v):
            assert np.isnan(path[t])
            continue
        ref_s += v
        assert path[t] == pytest.approx(ref_s)
        if ref_s >= 3.0:
            ref_alarm.append(t)
            ref_s, ref_start = 0.0, t + 1
        elif ref_s <= -2.0:
            ref_s, ref_start, ref_low = 0.0, t + 1, ref_low + 1
    assert list(np.flatnonzero(alarm)) == ref_alarm and ref_alarm and lowers == ref_low
    assert (s, start) == (pytest.approx(ref_s), ref_start)
    state, begin, got = 0.0, 0, []
    for a, b in ((0, 250), (250, 251), (251, 600)):
        p, al, cy, _, state, begin = sequential.renewal_walk(z[a:b], -2.0, 3.0, state=state, start=begin)
        got.append((p, al, cy + a))
        begin -= b - a
    np.testing.assert_array_equal(np.concatenate([g[0] for g in got]), path)
    np.testing.assert_array_equal(np.concatenate([g[1] for g in got]), alarm)
    np.testing.assert_array_equal(np.concatenate([g[2] for g in got]), cycle)


# ------------------------------------------------------------------ time-aligned record effect
def aligned_data(seed=5, M=3, k=2, R=5, n=200):
    rng = np.random.default_rng(seed)
    prog = np.sin(np.linspace(0, 3, n))[:, None]             # the programme every record follows
    held = {f"m{j}": [prog + rng.normal(0.3 * j, 1.0, (n, k)) + rng.normal(0, 0.2, k) for _ in range(R)]
            for j in range(M)}
    return rng, prog, held


def running(e, n):
    return np.r_[e[:n].mean(axis=0), 0.5 * np.log(np.mean(e[:n] ** 2, axis=0))]


def test_aligned_record_effect_loglik_is_the_predictive_density_at_each_sample():
    rng, prog, held = aligned_data()
    law = aligned_record_effect(held, min_samples=10, summaries=["mean[y0]", "mean[y1]", "log_scale[y1]"])
    assert law.center.shape == (3, 200, 3) and law.between.shape == (200, 3, 3)
    assert np.all(law.df[:, 9:] == 10.0) and np.all(law.scale[:, 9:] == 1.0) and np.isnan(law.scale[:, :9]).all()
    assert law.records == (5, 5, 5) and "AlignedRecordEffect(models=3" in repr(law)
    new = [prog[:150] + rng.normal(0.3, 1.0, (150, 2)) for _ in range(3)]      # a record so far: 150 of 200
    ll = law.loglik(new)
    assert ll.shape == (150, 3) and np.all(ll[:9] == 0.0)
    idx = [0, 1, 3]
    for n in (10, 60, 150):
        f = {m: np.array([running(e, n)[idx] for e in recs]) for m, recs in held.items()}
        dev = np.vstack([v - v.mean(axis=0) for v in f.values()])
        S = dev.T @ dev / 12
        for j, m in enumerate(held):
            ref = stats.multivariate_t(f[m].mean(axis=0), S * (1 + 1 / 5) * 12 / 10, df=10).logpdf(
                running(new[j], n)[idx])
            assert ll[:n, j].sum() == pytest.approx(ref, rel=1e-9)
    assert np.array_equal(law.loglik({"m2": new[2], "m0": new[0], "m1": new[1]}), ll)
    with pytest.raises(ValueError):                          # the law's arrays are read-only
        law.center[0, 0, 0] = 1.0


def test_aligned_record_effect_input_checks():
    _, _, held = aligned_data()
    with pytest.raises(TypeError, match="held_out"):
        aligned_record_effect({"m0": held["m0"]})
    with pytest.raises(ValueError, match=r"held_out\['m1'\]\[2\] has 150 samples, the first record 200"):
        aligned_record_effect({**held, "m1": held["m1"][:2] + [held["m1"][2][:150]]})
    with pytest.raises(ValueError, match="degrees of freedom"):
        aligned_record_effect({m: v[:2] for m, v in held.items()})
    with pytest.raises(ValueError, match=r"summaries: 'acf1\[y0\]' is not one of"):
        aligned_record_effect(held, summaries=["acf1[y0]"])
    with pytest.raises(ValueError, match="min_samples"):
        aligned_record_effect(held, min_samples=1)
    with pytest.raises(ValueError, match="singular"):
        aligned_record_effect({"a": [np.ones((50, 1))] * 4, "b": [np.ones((50, 1))] * 4}, min_samples=5)
    with pytest.raises(TypeError, match=r"held_out\['m1'\] must be a non-empty list"):
        aligned_record_effect({**held, "m1": 3})
    with pytest.raises(ValueError, match=r"held_out\['m0'\]: a record has a channel that is zero"):
        aligned_record_effect({**held, "m0": [np.zeros((200, 2))] + held["m0"][1:]}, min_samples=5)
    with pytest.raises(ValueError, match="fewer than min_samples = 300"):
        aligned_record_effect(held, min_samples=300)
    law = aligned_record_effect(held)
    e = np.ones((100, 2))
    with pytest.raises(ValueError, match="one residual array per model"):
        law.loglik([e, e])
    with pytest.raises(ValueError, match=r"resid has 201 samples, the law covers the first 200"):
        law.loglik([np.ones((201, 2))] * 3)
    with pytest.raises(ValueError, match=r"resid\['m1'\] has 90 samples"):
        law.loglik([e, e[:90], e])
    with pytest.raises(ValueError, match=r"resid\['m0'\]: a channel is zero over the first"):
        law.loglik([np.zeros((100, 2)), e, e])


def test_aligned_record_effect_spread_groups_scale_the_pooled_spread_per_group():
    # the models of a group predict with the pooled scale matrix times the group's factor: its squared standardised
    # deviations s_g over q nu_g degrees of freedom, shrunk towards 1 by the prior weight nu0 = 4 + 2 / tau2 that
    # the groups' spread of factors gives; min(nu - q + 1, nu0 + q nu_g) degrees of freedom
    rng, prog, held = aligned_data(M=4, R=4)
    held["m3"] = [e + rng.normal(0, 1.5, 2) for e in held["m3"]]            # m3's records spread more
    idx, summ = [0, 1, 3], ["mean[y0]", "mean[y1]", "log_scale[y1]"]
    groups = {"m0": "a", "m1": "a", "m2": "b", "m3": "c"}
    law = aligned_record_effect(held, min_samples=10, summaries=summ, spread_groups=groups)
    new = [prog[:120] + rng.normal(0.3, 1.0, (120, 2)) for _ in range(4)]
    ll = law.loglik(new)
    for n in (10, 120):
        f = {m: np.array([running(e, n)[idx] for e in recs]) for m, recs in held.items()}
        dev = {m: v - v.mean(axis=0) for m, v in f.items()}
        D = np.vstack(list(dev.values()))
        S = D.T @ D / 12
        m2 = {m: np.einsum("ri,ij,rj->", d, np.linalg.inv(S), d) for m, d in dev.items()}
        ss = {"a": m2["m0"] + m2["m1"], "b": m2["m2"], "c": m2["m3"]}
        nu = {"a": 6, "b": 3, "c": 3}
        lam = {g: ss[g] / (3 * nu[g]) for g in ss}
        tau2 = max(np.mean([(v - 1) ** 2 for v in lam.values()]) - np.mean([2 / (3 * v) for v in nu.values()]), 0)
        assert tau2 > 0 and lam["c"] > 2 * lam["a"]
        nu0 = 4 + 2 / tau2
        for j, m in enumerate(held):
            g = groups[m]
            post, df = (nu0 + ss[g]) / (nu0 + 3 * nu[g]), min(12 - 3 + 1, nu0 + 3 * nu[g])
            assert law.scale[j, n - 1] == pytest.approx(post, rel=1e-9) and law.df[j, n - 1] == pytest.approx(df)
            ref = stats.multivariate_t(f[m].mean(axis=0), post * S * (1 + 1 / 4) * 12 / 10, df=df).logpdf(
                running(new[j], n)[idx])
            assert ll[:n, j].sum() == pytest.approx(ref, rel=1e-9)
    # one group: the law without groups
    plain = aligned_record_effect(held, min_samples=10, summaries=summ)
    one = aligned_record_effect(held, min_samples=10, summaries=summ, spread_groups=dict.fromkeys(held, "all"))
    assert np.allclose(one.scale[:, 9:], 1.0, rtol=1e-12) and np.array_equal(one.df, plain.df, equal_nan=True)
    assert np.allclose(one.loglik(new), plain.loglik(new), rtol=1e-10, atol=1e-12)
    # a group whose models have one record each keeps the pooled spread
    solo = aligned_record_effect({**held, "m4": held["m3"][:1]}, min_samples=10, summaries=summ,
                                 spread_groups={**groups, "m4": "d"})
    assert np.all(solo.scale[4, 9:] == 1.0) and np.isfinite(solo.loglik(new + new[:1])).all()


def test_aligned_record_effect_spread_groups_input_checks():
    _, _, held = aligned_data()
    with pytest.raises(TypeError, match="spread_groups must be a mapping"):
        aligned_record_effect(held, spread_groups=["a", "a", "b"])
    with pytest.raises(ValueError, match="spread_groups: the model 'm2' has no group"):
        aligned_record_effect(held, spread_groups={"m0": "a", "m1": "a"})
    with pytest.raises(ValueError, match="spread_groups: 'm9' is not a model of held_out"):
        aligned_record_effect(held, spread_groups={"m0": "a", "m1": "a", "m2": "b", "m9": "b"})
    with pytest.raises(TypeError, match=r"spread_groups\['m1'\] must be a group label"):
        aligned_record_effect(held, spread_groups={"m0": "a", "m1": ["a"], "m2": "b"})


def test_aligned_record_effect_allocation_is_bounded(monkeypatch):
    # the (n, q, q) spread and the (R, n, q) running summaries are refused beyond MAX_VALUES, naming held_out
    _, _, held = aligned_data()
    monkeypatch.setattr(sequential, "MAX_VALUES", 200 * 4 * 10)
    with pytest.raises(ValueError, match="held_out: 15 records of 200 samples and 4 summaries need more values"):
        aligned_record_effect(held)
    assert aligned_record_effect(held, summaries=["mean[y0]"]).between.shape == (200, 1, 1)

"""AnyOf: a combined residual test whose parts share alpha (issue 31)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tsfdi
from tsfdi import AnyOf, FTest, LjungBox, MeanTest


def parts(alpha=1e-2, correction="sidak"):
    return [LjungBox(10, alpha=alpha, correction=correction), FTest(alpha=alpha, correction=correction),
            MeanTest(alpha=alpha, correction=correction)]


@pytest.fixture(scope="module")
def fleet():
    rng = np.random.default_rng(3131)
    recs = [rng.standard_normal((1500, 2)) * np.exp(0.1 * rng.standard_normal(2)) for _ in range(6)]
    spec = tsfdi.VAR(recs, 1)
    return spec, spec.fit(), spec.held_out_residuals(), rng


def test_parts_share_alpha_and_decision_is_any_part(fleet):
    spec, res, held, rng = fleet
    test = AnyOf(parts()).calibrate(held, window=200)
    share = 1 - (1 - 1e-2) ** (1 / 3)
    assert all(math.isclose(t.alpha, share) for t in test.tests) and math.isclose(test.share, share)
    for scale in (1.0, 1.0, 3.0):
        e = np.asarray(res.residuals(scale * rng.standard_normal((200, 2))))
        d = test.test(e, **test.reference(res))
        ds = d.details["parts"]
        assert len(ds) == 3 and d.reject == any(p.reject for p in ds)
        assert np.array_equal(d.channel_reject, np.logical_or.reduce([p.channel_reject for p in ds]))
        pmin = np.minimum.reduce([p.pvalue for p in ds])
        np.testing.assert_allclose(d.pvalue, 1 - (1 - pmin) ** 3)
        # the adjusted p-value against the channel alpha is the rule of the parts
        assert np.array_equal(d.pvalue < -np.expm1(np.log1p(-1e-2) / 2), d.channel_reject)
    assert d.reject                                             # three times the noise: rejected
    b = AnyOf(parts(), correction="bonferroni")
    assert math.isclose(b.tests[0].alpha, 1e-2 / 3)
    # the caller's tests are not modified
    given = parts()
    AnyOf(given)
    assert given[0].alpha == 1e-2 and not given[0].calibrated


def test_accepted_wherever_a_test_is(fleet):
    spec, res, held, rng = fleet
    test = AnyOf(parts()).calibrate(held, window=200)
    x = 3.0 * rng.standard_normal((1000, 2))                   # the loud aircraft
    d = tsfdi.detect(x[:200], res, test)
    assert d.test == "AnyOf" and len(d.details["parts"]) == 3 and d.reject
    other = tsfdi.VAR([3.0 * r.values for r in spec.records], 1)
    models = {"nominal": res, "loud": other.fit()}
    tests = {"nominal": test, "loud": AnyOf(parts()).calibrate(other.held_out_residuals(), window=200)}
    assert tsfdi.identify(x[:200], models, tests).label == "loud"
    w = tsfdi.identify_windows(x, models, tests, window=200, step=100)
    # the windowed engine gives the decisions of test()
    for i, s in enumerate(range(0, 801, 100)):
        for j, (name, r) in enumerate(models.items()):
            e = np.asarray(r.residuals(x[s:s + 200]))
            assert w.windows.reject[i, j] == tests[name].test(e, **tests[name].reference(r)).reject
    mon = tsfdi.Monitor(res, models, window=200, step=100, fs=1.0, test=tests, detection_test=test)
    out = mon.run(x)
    assert out.detection_time == 200.0 and out.label == "loud"


def test_minp_calibrates_the_smallest_pvalue(fleet):
    spec, res, held, rng = fleet
    test = AnyOf(parts()[:2], correction="minp")
    with pytest.raises(ValueError, match="not calibrated"):
        test.test(rng.standard_normal((199, 2)))
    test.calibrate(held, window=200)
    assert test.threshold_.shape == (2,) and np.all(test.threshold_ > -2 * math.log(1e-2))
    d = tsfdi.detect(rng.standard_normal((200, 2)), res, test)
    assert np.array_equal(d.channel_reject, d.statistic > d.threshold)
    assert np.array_equal(d.pvalue < -np.expm1(np.log1p(-1e-2) / 2), d.channel_reject)


def test_bad_parts_are_refused(fleet):
    _, _, held, _ = fleet
    with pytest.raises(ValueError, match="at least two tests"):
        AnyOf([LjungBox(10)])
    with pytest.raises(ValueError, match="share one alpha"):
        AnyOf([LjungBox(10, alpha=0.01), FTest(alpha=0.05)])
    with pytest.raises(ValueError, match="same correction"):
        AnyOf([LjungBox(10, correction="none"), FTest()])
    with pytest.raises(TypeError, match=r"tests\[1\] must be a windowed residual test"):
        AnyOf([LjungBox(10), tsfdi.ZScore()])
    with pytest.raises(TypeError, match="tests must be a sequence"):
        AnyOf(LjungBox(10))
    with pytest.raises(ValueError, match="correction must be one of"):
        AnyOf(parts(), correction="holm")
    with pytest.raises(ValueError, match=r"tests\[0\] \(LjungBox\) is already calibrated"):
        AnyOf([LjungBox(10, alpha=0.01).calibrate(held, window=200), FTest(alpha=0.01)])
    with pytest.raises(ValueError, match="different channels"):
        AnyOf([LjungBox(10, multivariate="hosking"), MeanTest()]).test(np.random.default_rng(0).standard_normal((99, 2)),
                                                                    reference_variance=1.0)


@pytest.mark.parametrize("correction, calibrated", [("sidak", False), ("bonferroni", False), ("sidak", True),
                                                    ("minp", True)])
def test_windowed_engine_computes_anyof_from_prefix_sums(fleet, correction, calibrated):
    """The windowed engine computes every part from prefix sums (no per-window decisions), with the statistic,
    threshold, p-value and rejection of AnyOf.test on every window."""
    spec, res, held, rng = fleet
    test = AnyOf(parts(), correction=correction)
    if calibrated:
        test.calibrate(held, window=200)
    x = rng.standard_normal((1400, 2))
    x[700:] *= 1.8
    ws = tsfdi.ResidualWindows({"a": res}).fit(x).statistics(test, window=200, step=9)
    assert ws.decisions is None                                 # not the per-window .test fallback
    e = np.asarray(res.residuals(x))
    ds = [test.test(e[s:s + 199], **test.reference(res)) for s in ws.starts]
    np.testing.assert_allclose(ws.statistic[:, 0], [d.statistic for d in ds], rtol=1e-9)
    np.testing.assert_allclose(ws.pvalue[:, 0], [d.pvalue for d in ds], rtol=1e-9)
    np.testing.assert_allclose(ws.threshold[:, 0], [d.threshold for d in ds], rtol=1e-12)
    assert np.array_equal(ws.channel_reject[:, 0], [d.channel_reject for d in ds])
    assert 0 < ws.reject.mean() < 1

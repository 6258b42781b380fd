"""detect, identify and identify_windows with FPMean results (the trim models of issue 32): the ranking and the
likelihood rule by each class's window log-likelihood, the healthy statistic against a calibrated
EmpiricalThreshold, and what is refused."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import tsfdi
from tsfdi.models import FPMean

K_RANGE = np.array([[2.0, 10.0], [0.0, 0.3]])
OFFSETS = {"healthy": np.zeros(3), "rotor1": np.array([-25.0, 10.0, 15.0]), "rotor2": np.array([8.0, -12.0, 4.0])}


def records(rng, n_rec: int, offset: np.ndarray, n: int = 2000, noise_sd: float = 6.0):
    k = np.column_stack([rng.uniform(*K_RANGE[0], n_rec), rng.uniform(*K_RANGE[1], n_rec)])
    level = np.column_stack([10 + 2 * k[:, 0], -30 + 40 * k[:, 1], 5 - k[:, 0]]) + offset
    level = level + rng.normal(0, 1.0, level.shape)
    return [lv + rng.normal(0, noise_sd, (n, 3)) for lv in level], k


@pytest.fixture(scope="module")
def trim():
    rng = np.random.default_rng(11)
    models = {c: FPMean(*records(rng, 20, off), 250, 1, k_range=K_RANGE).fit() for c, off in OFFSETS.items()}
    cal, _ = records(rng, 40, OFFSETS["healthy"])
    stat = np.concatenate([models["healthy"].statistic(y, 50) for y in cal])
    return models, tsfdi.EmpiricalThreshold(0.05).calibrate(stat), rng


def test_identify_ranks_the_classes_by_the_window_loglike(trim):
    models, thr, rng = trim
    for c, off in OFFSETS.items():
        y = records(rng, 1, off)[0][0][:250]
        ident = tsfdi.identify(y, models)
        ll = {m: float(r.loglike(y)[0]) for m, r in models.items()}
        assert ident.ranking == tuple(sorted(ll, key=lambda m: -ll[m]))
        assert ident.ranking[0] == c
        for m, d in ident.decisions.items():
            assert d.details["loglik"] == ll[m]
            np.testing.assert_array_equal(d.details["k_hat"], models[m].estimate_k(y)[0])
            assert d.statistic[0] == models[m].statistic(y)[0] and not d.reject     # no threshold: accepted
        assert ident.status == "ambiguous" and ident.test == "none"


def test_identify_windows_likelihood_rule_is_the_argmax_of_the_loglikes(trim):
    models, thr, rng = trim
    y = np.vstack([records(rng, 1, OFFSETS["rotor1"])[0][0], records(rng, 1, OFFSETS["healthy"])[0][0]])
    res = tsfdi.identify_windows(y, models, window=250, step=125)
    ll = np.column_stack([r.loglike(y, 125) for r in models.values()])
    np.testing.assert_array_equal(res.windows.loglik, ll)
    names = list(models)
    assert res.decide("likelihood") == [names[i] for i in ll.argmax(axis=1)]
    assert res.decide("likelihood")[:10] == ["rotor1"] * 10 and res.decide("likelihood")[-10:] == ["healthy"] * 10
    # every window's Identification is the one of identify on the window
    w = 7
    one = tsfdi.identify(y[res.starts[w]:res.stops[w]], models)
    assert res[w].ranking == one.ranking
    assert res[w].decisions["rotor2"].details["loglik"] == one.decisions["rotor2"].details["loglik"]


def test_healthy_statistic_with_a_calibrated_threshold(trim):
    models, thr, rng = trim
    healthy, fault = records(rng, 1, OFFSETS["healthy"])[0][0], records(rng, 1, OFFSETS["rotor2"])[0][0]
    d = tsfdi.detect(fault[:250], models["healthy"], thr)
    q = models["healthy"].statistic(fault[:250])[0]
    assert d.reject == (q > thr.threshold_) and d.reject
    assert d.threshold[0] == thr.threshold_ and d.pvalue[0] == thr.pvalue(q) and d.alpha == 0.05
    # through identify_windows: the healthy model rejects where its statistic exceeds the threshold; the fault
    # models, without a threshold, accept every window
    y = np.vstack([healthy, fault])
    res = tsfdi.identify_windows(y, models, {"healthy": thr, "rotor1": None, "rotor2": None}, window=250, step=250)
    stat = models["healthy"].statistic(y)
    np.testing.assert_array_equal(res.windows.reject[:, 0], stat > thr.threshold_)
    assert res.windows.reject[8:, 0].all() and not res.windows.reject[:, 1:].any()
    assert res.labels[8:] == [None] * 8 and res.status[8:] == ["ambiguous"] * 8       # rotor1 and rotor2 accept
    assert res.decide("likelihood")[8:] == ["rotor2"] * 8


def test_refused(trim):
    models, thr, rng = trim
    y = records(rng, 1, OFFSETS["healthy"])[0][0]
    with pytest.raises(TypeError, match="an FPMean baseline needs a calibrated EmpiricalThreshold"):
        tsfdi.detect(y[:250], models["healthy"])
    with pytest.raises(TypeError, match="must be a calibrated EmpiricalThreshold"):
        tsfdi.detect(y[:250], models["healthy"], tsfdi.FTest())
    with pytest.raises(ValueError, match="calibrate"):
        tsfdi.detect(y[:250], models["healthy"], tsfdi.EmpiricalThreshold(0.05))
    with pytest.raises(ValueError, match="fitted on windows of 250 samples; the window is 300"):
        tsfdi.identify(y[:300], models)
    with pytest.raises(ValueError, match="fitted on windows of 250 samples; the window is 500"):
        tsfdi.identify_windows(y, models, window=500)
    with pytest.raises(TypeError, match="u is only for input-output"):
        tsfdi.identify(y[:250], models, u=y[:250, 0])
    with pytest.raises(ValueError, match="has no threshold for the model"):
        tsfdi.identify(y[:250], models, {"healthy": thr})
    var = tsfdi.VAR(y, 2).fit()
    with pytest.raises(TypeError, match="mixes FPMean results with residual models"):
        tsfdi.identify(y[:250], {**models, "var": var})
    with pytest.raises(ValueError, match="signal has 2 channel"):
        tsfdi.identify(y[:250, :2], models)


def test_named_signal_is_matched_by_channel_name():
    rng = np.random.default_rng(3)
    names = ["roll_control", "pitch_control", "yaw_control"]
    models = {}
    for c, off in OFFSETS.items():
        y, k = records(rng, 12, off, n=1000)
        models[c] = FPMean([pd.DataFrame(v, columns=names) for v in y], k, 250, 1, k_range=K_RANGE).fit()
    y = pd.DataFrame(records(rng, 1, OFFSETS["rotor1"], n=1000)[0][0], columns=names)
    ref = tsfdi.identify_windows(y, models, window=250, step=250)
    swapped = tsfdi.identify_windows(y[names[::-1]], models, window=250, step=250)
    np.testing.assert_array_equal(ref.windows.loglik, swapped.windows.loglik)
    with pytest.raises(ValueError, match="extra channel"):
        tsfdi.identify(y.assign(other=1.0).iloc[:250], models)

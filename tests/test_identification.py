"""detect / identify / Identification / Decision: four known VAR systems, statuses, frames, plots, bad input."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import signal as sps

import tsfdi
from tsfdi.identification import identify_windows
from tests.conftest import as_kind

# ----------------------------------------------------------------------------------- four VAR systems
# Each system is y = M z with z three independent AR processes (unit innovations) whose poles are damped
# oscillations; a VAR(p) with A_i = M diag(a_i) M^-1 and innovation covariance M M'. The fault systems share
# the healthy system's dominant modes, shifted in frequency by 10 % in some channels, plus extra modes.
_BASE_F = np.array([0.05, 0.08, 0.12])
_BASE_R = np.array([0.90, 0.85, 0.80])
_D = 0.10


def _pair(f, r):
    z = r * np.exp(2j * np.pi * f)
    return [z, np.conj(z)]


def _system(shift, drad, extra, real=None):
    polys = []
    for c in range(3):
        poles = _pair(_BASE_F[c] * (1 + shift[c]), _BASE_R[c] + drad[c])
        for f, r in extra:
            poles += _pair(f[c], r[c])
        if real is not None:
            poles.append(real[c])
        polys.append(np.real(np.poly(poles)))
    return polys


SYSTEMS = {
    "healthy": _system([0, 0, 0], [0, 0, 0], [], real=[0.5, 0.3, -0.2]),                        # VAR(3)
    "rotor1": _system([_D, 0, -_D], [0.02, 0, 0], [([0.2, 0.25, 0.3], [0.5, 0.5, 0.4])]),         # VAR(4)
    "rotor2": _system([0, _D, _D], [0, -0.02, 0], [([0.2, 0.25, 0.3], [0.5, 0.5, 0.4]),
                                                   ([0.3, 0.35, 0.4], [0.4, 0.3, 0.3])]),       # VAR(6)
    "rotor6": _system([-_D, -_D, 0], [0, 0, 0.03], [([0.18, 0.22, 0.26], [0.5, 0.5, 0.4]),
                                                    ([0.3, 0.33, 0.4], [0.4, 0.4, 0.3]),
                                                    ([0.38, 0.42, 0.45], [0.3, 0.3, 0.3])]),    # VAR(8)
}
ORDERS = {"healthy": 3, "rotor1": 4, "rotor2": 6, "rotor6": 8}
MIX = np.array([[1.0, 0.3, -0.2], [0.25, 1.0, 0.3], [-0.3, 0.2, 1.0]])


def simulate(name, n, rng, burn=500):
    z = np.column_stack([sps.lfilter([1.0], a, rng.standard_normal(n + burn))[burn:] for a in SYSTEMS[name]])
    return z @ MIX.T


@pytest.fixture(scope="module")
def models():
    rng = np.random.default_rng(100)
    return {name: tsfdi.VAR(simulate(name, 40_000, rng), ORDERS[name]).fit() for name in SYSTEMS}


def test_var_coefficients_recovered(models):
    """The simulator is the VAR it claims to be: fitted coefficients are close to M diag(a_i) M^-1."""
    minv = np.linalg.inv(MIX)
    for name, res in models.items():
        p = ORDERS[name]
        true = np.zeros((p, 3, 3))
        for c, a in enumerate(SYSTEMS[name]):
            true[:len(a) - 1, c, c] = a[1:]
        true = np.einsum("ij,pjk,kl->pil", MIX, true, minv)
        assert res.coefs.shape == (p, 3, 3)
        np.testing.assert_allclose(res.coefs, true, atol=0.05)


@pytest.mark.slow
def test_identify_four_var_systems(models):
    """Acceptance: >= 99 % of 2,000-sample windows correctly labelled with LjungBox (lags 50, alpha 1e-3,
    the paper's settings); every window without a unique label is reported as ambiguous or none."""
    rng = np.random.default_rng(101)
    test = tsfdi.LjungBox(50, 1e-3)
    n_win, correct, total, wrong = 100, 0, 0, 0
    closest = np.inf
    for name in SYSTEMS:
        y = simulate(name, 2000 * n_win, rng)
        for w in range(n_win):
            ident = tsfdi.identify(y[w * 2000:(w + 1) * 2000], models, test)
            total += 1
            correct += ident.label == name
            wrong += ident.label is not None and ident.label != name
            if ident.label is None:
                assert ident.status in ("ambiguous", "none")
                assert (ident.status == "ambiguous") == (len(ident.accepted) > 1)
            others = [ident.decisions[m].margin for m in SYSTEMS if m != name]
            closest = min(closest, min(others))
    assert correct / total >= 0.99, correct / total
    assert wrong == 0
    # not trivially distinct: the closest wrong model is within a factor 5 of the critical limit
    assert closest < 5.0


def test_statuses_and_ranking(models):
    rng = np.random.default_rng(102)
    y = simulate("rotor2", 2000, rng)
    ident = tsfdi.identify(y, models, tsfdi.LjungBox(50, 1e-3))
    assert ident.status == "identified" and ident.label == "rotor2" and ident.accepted == ("rotor2",)
    assert ident.ranking[0] == "rotor2"
    assert "rotor2" in repr(ident) and "identified" in str(ident.summary())
    assert "<table" in ident._repr_html_() and ident.summary().tables[0][1].equals(ident.to_frame())
    # ambiguous: the same model twice
    amb = tsfdi.identify(y, {"a": models["rotor2"], "b": models["rotor2"], "h": models["healthy"]},
                         tsfdi.LjungBox(50, 1e-3))
    assert amb.status == "ambiguous" and amb.label is None and amb.accepted == ("a", "b")
    # none: no model fits
    none = tsfdi.identify(y, {"h": models["healthy"], "r1": models["rotor1"]}, tsfdi.LjungBox(50, 1e-3))
    assert none.status == "none" and none.label is None and none.accepted == ()
    frame = ident.to_frame()
    assert list(frame.index.names) == ["model", "channel"] and frame.shape[0] == 12
    assert frame.loc[("rotor2", "y0"), "model_accepted"] and not frame.loc[("healthy", "y0"), "model_accepted"]
    np.testing.assert_allclose(frame["statistic"].to_numpy(),
                               np.concatenate([d.statistic for d in ident.decisions.values()]))
    assert "<table" in ident._repr_html_()


def test_identify_with_ftest_and_glrt(models):
    rng = np.random.default_rng(103)
    y = simulate("rotor1", 2000, rng)
    ft = tsfdi.identify(y, models, tsfdi.FTest(1e-8))
    assert "rotor1" in ft.accepted
    assert ft.decisions["rotor1"].df.shape == (3, 2)
    gl = tsfdi.identify(y, models, tsfdi.GLRT(50, alpha=1e-6))
    assert set(gl.decisions) == set(SYSTEMS) and np.isnan(gl.decisions["rotor1"].pvalue).all()
    assert gl.ranking  # by statistic / threshold when there are no p-values


def test_identify_windows_equals_identify(models):
    rng = np.random.default_rng(104)
    y = simulate("rotor6", 3000, rng)
    wins = identify_windows(y, models, tsfdi.LjungBox(50, 1e-3), window=2000, step=250)
    assert len(wins) == 5
    for w in (0, 4):
        s0 = w * 250
        ref = tsfdi.identify(y[s0:s0 + 2000], models, tsfdi.LjungBox(50, 1e-3))
        assert wins[w].span == (s0, s0 + 2000) and wins[w].label == ref.label == "rotor6"
        for m in models:
            np.testing.assert_allclose(wins[w].decisions[m].statistic, ref.decisions[m].statistic, rtol=1e-9)
    fw = identify_windows(y, models, tsfdi.FTest(1e-8), window=2000, step=1000)
    assert len(fw) == 2 and fw[1].span == (1000, 3000)
    assert fw.labels[1] == fw[1].label and fw.status[0] == fw[0].status
    np.testing.assert_allclose(fw.statistic[1, 3], tsfdi.identify(y[1000:], models, tsfdi.FTest(1e-8))
                               .decisions["rotor6"].statistic)
    assert wins.labels == ["rotor6"] * 5 and wins.status == ["identified"] * 5
    assert wins.statistic.shape == (5, 4, 3) and wins.accepted[:, 3].all()
    frame = wins.to_frame()
    assert frame["start"].tolist() == [0, 250, 500, 750, 1000] and "5" in repr(wins)
    assert [i.label for i in wins] == wins.labels and wins[-1].span == (1000, 3000)
    np.testing.assert_allclose(wins.pvalue[2, 1], wins[2].decisions["rotor1"].pvalue)


def test_identify_windows_time_spans_follow_pandas_rolling(models):
    """window / step: an int counts samples, a time span is converted with the time index or fs; floats refused."""
    import pandas as pd

    rng = np.random.default_rng(105)
    y = simulate("rotor1", 3000, rng)
    by_samples = identify_windows(y, models, tsfdi.LjungBox(30, 1e-3), window=2000, step=500)
    df = pd.DataFrame(y, index=pd.date_range("2026-01-01", periods=3000, freq="10ms"))
    by_index = identify_windows(df, models, tsfdi.LjungBox(30, 1e-3), window="20s", step=pd.Timedelta("5s"))
    by_fs = identify_windows(y, models, tsfdi.LjungBox(30, 1e-3), window="20s", step="5s", fs=100.0)
    for other in (by_index, by_fs):
        np.testing.assert_array_equal(other.starts, by_samples.starts)
        np.testing.assert_array_equal(other.statistic, by_samples.statistic)
        assert other.labels == by_samples.labels
    with pytest.raises(TypeError, match="window"):
        identify_windows(y, models, tsfdi.LjungBox(30), window=2000.0)
    with pytest.raises(ValueError, match="window.*sampling frequency"):
        identify_windows(y, models, tsfdi.LjungBox(30), window="20s")
    with pytest.raises(ValueError, match="step"):
        identify_windows(y, models, tsfdi.LjungBox(30), window=2000, step=0)


def test_identify_windows_decide_rules(models):
    """decide(rule) labels every window; the paper rule's labels are the single accepted model."""
    rng = np.random.default_rng(106)
    y = simulate("rotor2", 3000, rng)
    wins = identify_windows(y, models, tsfdi.LjungBox(30, 1e-3), window=1000, step=500)
    assert wins.decide("paper") == wins.labels
    lik = wins.decide("likelihood")
    assert all(lab in models for lab in lik)
    assert [lab for lab, st in zip(lik, wins.status) if st == "identified"] == \
        [lab for lab in wins.labels if lab is not None]
    with pytest.raises(dataclasses.FrozenInstanceError):
        wins.test = None


def test_identify_windows_empirical_threshold_arrays_match_windows():
    """The all-windows arrays of a calibrated LjungBox carry its empirical p-values and thresholds, as identify
    does on each window (they used to hold chi-square p-values)."""
    rng = np.random.default_rng(7)
    y = rng.standard_normal(1200)
    res = tsfdi.AR(y[:600], lags=2).fit()
    test = tsfdi.LjungBox(lags=5, alpha=0.05, threshold="empirical").calibrate(
        [res.residuals(rng.standard_normal(4000))], window=98)
    wins = identify_windows(y, {"h": res}, test, window=100, step=100)
    for w in range(len(wins)):
        ref = tsfdi.identify(y[w * 100:w * 100 + 100], {"h": res}, test).decisions["h"]
        np.testing.assert_allclose(wins.pvalue[w, 0], ref.pvalue, rtol=1e-12)
        np.testing.assert_allclose(wins.threshold[w, 0], ref.threshold, rtol=1e-12)
        assert wins.accepted[w, 0] == (not ref.reject)
    assert np.all(wins.pvalue >= 1.0 / (test.calibration_[0].size + 1))


def test_data_kinds(kind, models):
    rng = np.random.default_rng(105)
    y = simulate("healthy", 1500, rng)
    ref = tsfdi.identify(y, models, tsfdi.LjungBox(30, 1e-3))
    got = tsfdi.identify(as_kind(y, kind), models, tsfdi.LjungBox(30, 1e-3))
    for m in models:
        np.testing.assert_allclose(got.decisions[m].statistic, ref.decisions[m].statistic, rtol=1e-12)
    assert got.label == ref.label
    d = tsfdi.detect(as_kind(y, kind), models["healthy"], tsfdi.LjungBox(30, 1e-3))
    np.testing.assert_allclose(d.statistic, ref.decisions["healthy"].statistic)
    wins = identify_windows(as_kind(y, kind), models, tsfdi.LjungBox(30, 1e-3), window=1000, step=500)
    np.testing.assert_allclose(wins[0].decisions["rotor1"].statistic,
                               tsfdi.identify(y[:1000], models, tsfdi.LjungBox(30, 1e-3)).decisions["rotor1"].statistic,
                               rtol=1e-9)
    # scalar AR models on a scalar signal
    y0 = y[:, 0]
    ar = {"a": tsfdi.AR(simulate("healthy", 5000, rng)[:, 0], 6).fit()}
    ident = tsfdi.identify(as_kind(y0, kind), ar, tsfdi.LjungBox(20, 1e-3))
    assert ident.decisions["a"].channels.__len__() == 1


def test_decision_object():
    d = tsfdi.LjungBox(10, 0.05).test(np.random.default_rng(6).standard_normal((300, 2)))
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.reject = True
    with pytest.raises(ValueError):
        d.statistic[0] = 1.0
    for f in ("statistic", "threshold", "pvalue", "alpha", "reject", "df", "nobs", "null_hypothesis",
              "alternative_hypothesis", "details"):
        assert hasattr(d, f)
    assert isinstance(d.reject, bool) and d.statistic.shape == (2,) and d.df.shape == (2,)
    assert d.accept == (not d.reject)
    assert d.signal_pvalue == pytest.approx(1 - (1 - d.pvalue.min()) ** 2)     # Sidak over the 2 channels
    s = str(d.summary())
    assert "every channel accepts" in s and "y1" in s
    assert repr(d).startswith("Decision(test='LjungBox'")
    assert "<table>" in d._repr_html_()
    b = tsfdi.LjungBox(10, 0.05, correction="bonferroni").test(np.random.default_rng(6).standard_normal((300, 2)))
    assert b.signal_pvalue == pytest.approx(min(1.0, 2 * b.pvalue.min()))


def test_plots(models):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(7)
    y = simulate("rotor1", 2000, rng)
    ident = tsfdi.identify(y, models, tsfdi.LjungBox(50, 1e-3))
    fig = ident.plot()
    ax = fig.axes[0]
    assert len(ax.patches) == 12 and len(ax.collections) == 12   # 4 models x 3 channels bars and limits
    plt.close(fig)
    fig, ax = plt.subplots()
    out = ident.decisions["rotor1"].plot(ax=ax)
    assert out is fig and len(ax.patches) == 3
    plt.close(fig)
    gl = tsfdi.GLRT(20, threshold=tsfdi.EmpiricalThreshold(1e-2)).calibrate(rng.standard_normal(20_000))
    fig = gl.threshold.plot()
    assert any("threshold" in t.get_text() for t in fig.axes[0].get_legend().get_texts())
    plt.close(fig)
    fig = tsfdi.plotting.plot_threshold(gl)
    plt.close(fig)


def test_bad_input(models):
    rng = np.random.default_rng(8)
    y = simulate("healthy", 500, rng)
    with pytest.raises(ValueError, match="models is empty"):
        tsfdi.identify(y, {}, tsfdi.LjungBox(10))
    with pytest.raises(TypeError, match="models"):
        tsfdi.identify(y, [models["healthy"]], tsfdi.LjungBox(10))
    with pytest.raises(TypeError, match="models"):
        tsfdi.identify(y, {"x": np.zeros(3)}, tsfdi.LjungBox(10))
    with pytest.raises(ValueError, match="signal has 2 channel"):
        tsfdi.identify(y[:, :2], models, tsfdi.LjungBox(10))
    with pytest.raises(ValueError, match="signal has 3 channel.*baseline"):
        tsfdi.detect(y, tsfdi.AR(y[:, 0], 2).fit(), tsfdi.LjungBox(10))
    bad = y.copy()
    bad[10, 1] = np.nan
    with pytest.raises(ValueError, match="signal"):
        tsfdi.identify(bad, models, tsfdi.LjungBox(10))
    with pytest.raises(ValueError, match="signal"):
        tsfdi.detect(bad, models["healthy"])
    with pytest.raises(ValueError, match="resid is too short"):
        tsfdi.identify(y[:40], models, tsfdi.LjungBox(35))
    with pytest.raises(TypeError, match="test"):
        tsfdi.identify(y, models, "ljungbox")
    with pytest.raises(ValueError, match="window"):
        identify_windows(y, models, tsfdi.LjungBox(10), window=1000)


def test_detect_identify_arx_with_input():
    rng = np.random.default_rng(9)
    u = rng.standard_normal(3000)
    y = sps.lfilter([0, 0.8, 0.3], [1, -0.5], u) + sps.lfilter([1], [1, -0.5], 0.1 * rng.standard_normal(3000))
    res = tsfdi.ARX(y[:2000], u[:2000], 1, 2, nk=1).fit()
    d = tsfdi.detect(y[2000:], res, tsfdi.FTest(1e-3), u=u[2000:])
    np.testing.assert_allclose(d.statistic, tsfdi.FTest(1e-3).test(res.residuals(y[2000:], u[2000:]),
                                                                      **tsfdi.FTest().reference(res)).statistic)
    assert not d.reject
    yf = sps.lfilter([0, 0.4, 0.3], [1, -0.5], u) + 0.1 * rng.standard_normal(3000)
    ident = tsfdi.identify(yf[2000:], {"healthy": res}, tsfdi.FTest(1e-3), u=u[2000:])
    assert ident.status == "none"


def test_one_test_per_model(models):
    """identify / identify_windows with a mapping name -> test: each candidate with its own (calibrated) test."""
    rng = np.random.default_rng(107)
    y = simulate("rotor2", 3000, rng)
    # a calibrated threshold holds for the calibrated window: 1000 signal samples, 1000 - order residuals
    tests = {name: tsfdi.LjungBox(30, 1e-3).calibrate(
        [np.asarray(res.residuals(simulate(name, 4000, rng))) for _ in range(8)], window=1000 - res.lags)
        for name, res in models.items()}
    ident = tsfdi.identify(y[:1000], models, tests)
    for name, res in models.items():
        alone = tsfdi.identify(y[:1000], {name: res}, tests[name]).decisions[name]
        np.testing.assert_array_equal(ident.decisions[name].threshold, alone.threshold)
        assert ident.decisions[name].details["threshold_method"] == "calibrated"
    assert len({float(d.threshold[0]) for d in ident.decisions.values()}) == len(models)   # one null per model
    wins = identify_windows(y, models, tests, window=1000, step=500)
    assert wins[0].label == ident.label and wins.tests == tuple(tests.values())
    np.testing.assert_allclose(wins[0].decisions["rotor2"].statistic, ident.decisions["rotor2"].statistic)
    with pytest.raises(ValueError, match="no test for the model"):
        tsfdi.identify(y[:1000], models, {"rotor2": tests["rotor2"]})


def test_windowed_frame_gives_start_and_stop_in_the_inputs_time():
    """Issue 29: identify_windows(...).to_frame() gave start / stop in samples for a DatetimeIndex input; they are in
    the input's time (Timestamp, Timedelta, seconds of a numeric 'time' index), in samples without a time index, and
    the sample positions stay in starts / stops."""
    import pandas as pd

    rng = np.random.default_rng(29)
    y = rng.standard_normal(1000)
    models = {"h": tsfdi.AR(y, 2).fit()}
    t0 = pd.Timestamp("2024-05-01 12:00")
    for index, first, second in ((pd.date_range(t0, periods=1000, freq="10ms"), t0, t0 + pd.Timedelta("2.5s")),
                                 (pd.timedelta_range(0, periods=1000, freq="10ms"), pd.Timedelta(0),
                                  pd.Timedelta("2.5s")),
                                 (pd.Index(10.0 + np.arange(1000) / 100, name="time"), 10.0, 12.5)):
        wins = identify_windows(pd.Series(y, index=index), models, window="1s", step="2.5s")
        frame = wins.to_frame()
        assert frame["start"].iloc[0] == first and frame["start"].iloc[1] == second
        span = frame["stop"].iloc[1] - frame["start"].iloc[1]
        assert span == (pytest.approx(1.0) if first == 10.0 else pd.Timedelta("1s"))
        assert wins.starts[:2].tolist() == [0, 250] and wins.stops[:2].tolist() == [100, 350]
    frame = identify_windows(y, models, window=100, step=250).to_frame()
    assert frame["start"].tolist()[:2] == [0, 250] and frame["stop"].tolist()[:2] == [100, 350]

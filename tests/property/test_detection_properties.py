"""Property-based tests of the residual tests (issue 18: numerics and the input contract).

Generated residuals -- 1-D and 2-D (one to three channels), lengths 1 to 500, float64 / float32 / int / bool /
object dtypes, scales from 1e-300 to 1e300, constant stretches (a frozen sensor, also at exactly 0), whole constant
records, NaN and inf -- and generated options -- lags, windows and steps (valid, 0, negative, beyond the record,
10**12, 2**63, floats, strings), alpha (1e-300 .. 0.5 and out of range), reference variances / degrees of freedom
/ scales (valid, 0, negative, NaN, "", bools, wrong lengths) -- go through

* ``LjungBox`` (per channel, ``multivariate="hosking"`` / ``"li-mcleod"``): ``test``, ``window_statistic``,
  ``ljungbox_windows``, ``threshold_pvalue``;
* ``FTest`` (``"greater"`` / ``"two-sided"``, ``demean``): ``test``, ``window_statistic``, ``threshold_pvalue``;
* ``MeanTest``: ``test``, ``window_statistic``;
* ``GLRT``: ``test``, ``statistic``, ``scan``, ``stream`` (``update`` / ``extend``), ``glrt_direct``;
* ``ZScore``: ``test``, ``zscores``;
* ``calibrate`` of ``LjungBox`` and ``FTest`` (``"calibrated"`` and ``"empirical"`` thresholds) and a test after it.

Each call returns a well-formed result or raises a ``ValueError`` / ``TypeError`` naming the argument. A
well-formed result has one finite statistic per channel, except the documented ones -- ``inf`` for the Ljung-Box
statistic of a constant window (p-value 0, reject, ``details["constant"]``) and for the Z-score of a sample after
a constant history; a variance ratio beyond the float range is refused -- and p-values in [0, 1] (NaN
for the GLRT and the Z-score, which have none). The windowed statistics equal ``test()`` window by window (constant
windows included), and every statistic is unchanged when the residuals (and the reference variance or scale) are
multiplied by ``c`` in 1e-150 .. 1e150 (rtol 1e-6).

On the "ci" profile every test runs 60 examples: 8 tests, 480 generated cases (2,000 per test, 16,000 in all, with
``HYPOTHESIS_PROFILE=long``).
"""

from __future__ import annotations

import math

import numpy as np
from _contract import named
from hypothesis import assume, event, given
from hypothesis import strategies as st
from scipy import special

from tsfdi.detection import GLRT, FTest, LjungBox, MeanTest, ZScore, glrt_direct, ljungbox_windows

# ---------------------------------------------------------------------------------------------- strategies
def option(valid, hostile, odds: int = 12):
    """``valid`` values, and ``hostile`` ones once in ``odds`` (shrinking goes to the valid ones)."""
    return st.integers(0, odds - 1).flatmap(lambda i: hostile if i == odds - 1 else valid)


DTYPES = option(st.sampled_from(["float64", "float64", "float64", "float32", "int64", "object"]), st.just("bool"))
SPECIALS = option(st.sampled_from(["none", "none", "stretch", "zero_stretch", "constant"]),
                  st.sampled_from(["nan", "inf"]), odds=8)


def _values(n: int, k: int | None, seed: int, exponent: int, special: str, dtype: str) -> np.ndarray:
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((n,) if k is None else (n, k))
    if special == "constant":
        z[:] = 0.3
    elif special in ("stretch", "zero_stretch") and n > 2:
        a = int(rng.integers(0, n - 1))
        b = int(rng.integers(a + 2, n + 1))
        z[a:b] = 0.0 if special == "zero_stretch" else z[a]
    if dtype == "int64":
        return np.round(z * 10).astype(dtype)
    if dtype == "bool":
        return z > 0
    x = z * 10.0 ** exponent
    if special in ("nan", "inf"):
        x.flat[rng.integers(x.size)] = np.nan if special == "nan" else np.inf
    with np.errstate(over="ignore", under="ignore"):
        return x.astype(dtype)         # float32 beyond its range is inf: refused as such


@st.composite
def residuals(draw, max_len: int = 500, channels: tuple = (None, 1, 2, 3)):
    n = draw(option(st.integers(13, max_len), st.integers(1, 12), odds=6))
    dtype = draw(DTYPES)
    exponent = draw(st.integers(-300, 300) if dtype != "float32" else st.integers(-30, 30))
    return _values(n, draw(st.sampled_from(channels)), draw(st.integers(0, 2 ** 16)), exponent, draw(SPECIALS), dtype)


ALPHAS = option(st.sampled_from([0.05, 1e-3, 1e-17, 1e-50, 1e-300, 0.5]),
                st.sampled_from([0, 1, -1e-3, 1.5, np.nan, np.inf, "0.05", None, True]))
LAGS = option(st.integers(1, 30), st.sampled_from([0, -2, 10 ** 12, 2 ** 63, 2.5, "5", None, True]))
STEPS = option(st.integers(1, 60), st.sampled_from([0, -1, 1.5, "2", None]))
POSITIVE = option(st.sampled_from([1.0, 0.5, 3.0, 1e-20, 1e20, 1e-300, 1e300]),
                  st.sampled_from([0.0, -1.0, np.nan, np.inf, "", "1", True, [1.0, 2.0, 3.0, 4.0], [[1.0]]]))
DFS = option(st.sampled_from([100, 5, 1, 1e6]), st.sampled_from([0, -5, np.nan, "", True]))
HOSTILE_WINDOWS = st.sampled_from([-1, 0, 10 ** 12, 2 ** 63, 1e10, 20.5, "50", None])


def windows(n: int):
    """A window for a record of ``n`` samples: mostly fitting in it, sometimes not at all."""
    return option(st.integers(2, max(2, n)), st.one_of(st.integers(n + 1, n + 50), HOSTILE_WINDOWS))


def as_2d(x) -> np.ndarray:
    a = np.asarray(x, dtype=np.float64)
    return a[:, None] if a.ndim == 1 else a


def constant_columns(x: np.ndarray, demean: bool = True) -> np.ndarray:
    x = as_2d(x)
    return np.ptp(x, axis=0) == 0 if demean else ~np.any(x != 0, axis=0)


def check_decision(d, nchan: int, *, inf_ok: np.ndarray | None = None, pvalue: bool = True) -> None:
    """One statistic per channel, finite unless ``inf_ok`` says so (then p-value 0 and reject); p-values in [0, 1]
    (NaN where the test has none)."""
    stat, thr, pv = (np.asarray(v, dtype=float) for v in (d.statistic, d.threshold, d.pvalue))
    assert stat.shape == (nchan,) and not np.isnan(stat).any() and not np.isnan(thr).any() and np.all(thr >= 0)
    inf = np.isinf(stat)
    assert not inf.any() or (inf_ok is not None and np.all(inf_ok[inf])), (stat, inf_ok)
    assert np.all(stat[inf] > 0) and np.all(np.asarray(d.channel_reject)[inf])
    if pvalue:
        assert np.all((pv >= 0) & (pv <= 1)) and np.all(pv[inf] == 0)
    else:
        assert np.all(np.isnan(pv))
    np.testing.assert_array_equal(np.asarray(d.channel_reject), stat > thr) if d.test != "FTest" or \
        d.details.get("alternative") == "greater" else None
    assert d.reject == bool(np.asarray(d.channel_reject).any())


# ---------------------------------------------------------------------------------------------- Ljung-Box
@given(x=residuals(), lags=LAGS, alpha=ALPHAS, demean=option(st.booleans(), st.sampled_from([1, "yes"])),
       multivariate=option(st.sampled_from([None, None, "hosking", "li-mcleod"]), st.just("box")),
       step=STEPS, correction=st.sampled_from([None, "bonferroni", "sidak"]), data=st.data())
def test_ljungbox(x, lags, alpha, demean, multivariate, step, correction, data):
    window = data.draw(windows(x.shape[0]), "window")
    try:
        lb = LjungBox(lags, alpha, demean=demean, multivariate=multivariate, correction=correction)
    except (ValueError, TypeError) as exc:
        named(exc, ("lags", "alpha", "demean", "multivariate", "model_df"))
        return
    try:
        d = lb.test(x)
    except (ValueError, TypeError) as exc:
        named(exc, ("resid",))
    else:
        event("result: test")
        const = constant_columns(x, lb.demean)
        nchan = 1 if multivariate else as_2d(x).shape[1]
        check_decision(d, nchan, inf_ok=np.array([const.any()]) if multivariate else const)
        assert len(d.details["constant"]) == int(const.sum())
    try:
        q = lb.window_statistic(x, window, step)
    except (ValueError, TypeError) as exc:
        named(exc, ("resid", "window", "step", "lags"))
        return
    event("result: windows")
    arr = as_2d(x)
    window = int(window)
    starts = np.arange(0, arr.shape[0] - window + 1, int(step))
    assert q.shape == (starts.size, 1 if multivariate else arr.shape[1]) and not np.isnan(q).any()
    assert np.all(q >= 0)
    if multivariate is None:
        np.testing.assert_array_equal(q, ljungbox_windows(x, lags, window, step, demean=lb.demean))
    thr, pv = lb.threshold_pvalue(q, window)
    assert np.all((pv >= 0) & (pv <= 1)) and np.all(pv[np.isinf(q)] == 0)
    for w in np.unique(np.linspace(0, starts.size - 1, 4).astype(int)):       # the windowed path equals test()
        seg = arr[starts[w]:starts[w] + window]
        if multivariate is None and np.isfinite(seg).all():
            d = lb.test(seg)
            const = constant_columns(seg, lb.demean)
            assert np.all(np.isinf(q[w]) == const)
            np.testing.assert_allclose(q[w][~const], d.statistic[~const], rtol=1e-6)


# ---------------------------------------------------------------------------------------------- F test
@given(x=residuals(), alpha=ALPHAS, alternative=option(st.sampled_from(["greater", "two-sided"]), st.just("less")),
       demean=st.booleans(), ref=POSITIVE, df=DFS, step=STEPS, correction=st.sampled_from([None, "bonferroni"]),
       data=st.data())
def test_ftest(x, alpha, alternative, demean, ref, df, step, correction, data):
    window = data.draw(windows(x.shape[0]), "window")
    try:
        ft = FTest(alpha, alternative=alternative, demean=demean, correction=correction)
    except (ValueError, TypeError) as exc:
        named(exc, ("alpha", "alternative"))
        return
    names = ("resid", "reference_variance", "reference_df", "window", "step")
    try:
        d = ft.test(x, reference_variance=ref, reference_df=df)
    except (ValueError, TypeError) as exc:
        named(exc, names)
    else:
        event("result: test")
        nchan = as_2d(x).shape[1]
        check_decision(d, nchan)
        assert np.all(np.asarray(d.statistic) >= 0)
        const = constant_columns(x)
        if demean:
            assert np.all(np.asarray(d.statistic)[const] == 0)
    try:
        f = ft.window_statistic(x, window, step, reference_variance=ref)
        thr, pv = ft.threshold_pvalue(f, int(window), reference_df=df)
    except (ValueError, TypeError) as exc:
        named(exc, names)
        return
    event("result: windows")
    assert np.all(np.isfinite(f)) and np.all(f >= 0) and np.all((pv >= 0) & (pv <= 1))
    arr = as_2d(x)
    window = int(window)
    starts = np.arange(0, arr.shape[0] - window + 1, int(step))
    for w in np.unique(np.linspace(0, starts.size - 1, 4).astype(int)):
        d = ft.test(arr[starts[w]:starts[w] + window], reference_variance=ref, reference_df=df)
        np.testing.assert_allclose(f[w], d.statistic, rtol=1e-6, atol=1e-300)


# ---------------------------------------------------------------------------------------------- mean-shift test
@given(x=residuals(), alpha=ALPHAS, ref=POSITIVE, step=STEPS, data=st.data())
def test_mean_test(x, alpha, ref, step, data):
    window = data.draw(windows(x.shape[0]), "window")
    try:
        mt = MeanTest(alpha)
    except (ValueError, TypeError) as exc:
        named(exc, ("alpha",))
        return
    names = ("resid", "reference_variance", "window", "step")
    try:
        d = mt.test(x, reference_variance=ref)
    except (ValueError, TypeError) as exc:
        named(exc, names)
    else:
        event("result: test")
        check_decision(d, as_2d(x).shape[1])
    try:
        t = mt.window_statistic(x, window, step, reference_variance=ref)
    except (ValueError, TypeError) as exc:
        named(exc, names)
        return
    event("result: windows")
    arr = as_2d(x)
    starts = np.arange(0, arr.shape[0] - int(window) + 1, int(step))
    assert np.all(np.isfinite(t)) and np.all(t >= 0)
    for w in np.unique(np.linspace(0, starts.size - 1, 4).astype(int)):
        d = mt.test(arr[starts[w]:starts[w] + int(window)], reference_variance=ref)
        np.testing.assert_allclose(t[w], d.statistic, rtol=1e-6, atol=1e-12 * max(1.0, float(np.max(d.statistic))))


# ---------------------------------------------------------------------------------------------- GLRT
@given(x=residuals(max_len=300), scale=st.one_of(st.none(), POSITIVE), alpha=ALPHAS,
       threshold=option(st.just("theoretical"), st.sampled_from([3.0, 0.0, -1.0, "x", np.inf])),
       split=st.integers(0, 300), data=st.data())
def test_glrt(x, scale, alpha, threshold, split, data):
    window = data.draw(option(st.integers(1, 60), st.sampled_from([10 ** 9, 1e10, 2 ** 63, 0, -3, 2.5, "9"])),
                       "window")
    try:
        gl = GLRT(window, scale, threshold, alpha=alpha)
    except (ValueError, TypeError) as exc:
        named(exc, ("window", "scale", "threshold", "alpha"))
        return
    assert np.isfinite(gl.threshold_)
    try:
        d = gl.test(x)
        g = np.asarray(gl.statistic(x))
        sc = gl.scan(x)
    except (ValueError, TypeError) as exc:
        named(exc, ("resid", "scale"))
        return
    event("result: test")
    arr = as_2d(x)
    check_decision(d, arr.shape[1], pvalue=False)
    assert g.shape == x.shape and np.all(np.isfinite(g)) and np.all(g >= 0)
    np.testing.assert_allclose(as_2d(g), sc.g, rtol=1e-9, atol=1e-12)   # two kernels (prefix sums, direct sums)
    assert np.all(np.isfinite(sc.jump))
    s = np.asarray(d.details["scale"])
    st_ = gl.stream(arr.shape[1], scale=s)
    out = np.concatenate([st_.extend(arr[:split]), *[st_.update(v)[None] for v in arr[split:split + 20]],
                          st_.extend(arr[split + 20:])])
    np.testing.assert_allclose(out, sc.g, rtol=1e-9, atol=1e-12)
    assert st_._buf.shape[1] <= max(64, 2 * arr.shape[0])
    if arr.shape[1] == 1:
        np.testing.assert_allclose(glrt_direct(arr[:60, 0], window, s[0]), sc.g[:60, 0], rtol=1e-9, atol=1e-12)


# ---------------------------------------------------------------------------------------------- Z-score
@given(x=residuals(max_len=300), threshold=option(st.sampled_from([4.5, 1.0, 1e-3]), st.sampled_from([0, -1, "4"])),
       burn_in=option(st.integers(2, 60), st.sampled_from([1, 10 ** 12, 2.5])), freeze=st.booleans())
def test_zscore(x, threshold, burn_in, freeze):
    try:
        zs = ZScore(threshold, burn_in=burn_in, freeze_on_alarm=freeze)
        d = zs.test(x)
    except (ValueError, TypeError) as exc:
        named(exc, ("threshold", "burn_in", "resid"))
        return
    event("result")
    var = as_2d(d.details["variance"])
    z = as_2d(d.details["z"])
    # |z| = inf only for a sample scored against a constant history (running variance 0 just before it)
    zero_history = np.array([np.any(np.isinf(z[1:, c]) & (var[:-1, c] == 0)) for c in range(z.shape[1])])
    assert np.all(np.isinf(z[1:]) <= (var[:-1] == 0))
    check_decision(d, z.shape[1], inf_ok=zero_history, pvalue=False)
    np.testing.assert_array_equal(as_2d(zs.zscores(x)), z)


# ---------------------------------------------------------------------------------------------- calibrate
@st.composite
def records(draw):
    """One to three healthy records of two channels, 300 to 800 samples (sometimes short or hostile)."""
    out = []
    for _ in range(draw(st.integers(1, 3))):
        dtype = draw(DTYPES)
        exponent = draw(option(st.integers(-150, 150), st.integers(-300, 300)) if dtype != "float32" else
                        st.integers(-30, 30))
        out.append(_values(draw(option(st.integers(300, 800), st.integers(1, 60))), 2, draw(st.integers(0, 2 ** 16)),
                           exponent, draw(SPECIALS), dtype))
    return out


@given(recs=records(), alpha=option(st.sampled_from([0.1, 0.05, 1e-3, 1e-300]), ALPHAS),
       test=st.sampled_from(["lb", "f"]), threshold=st.sampled_from(["calibrated", "empirical"]),
       window=option(st.integers(8, 60), st.sampled_from([0, 1, 10 ** 12, "50", None])),
       step=option(st.integers(1, 8), STEPS), new=residuals(max_len=200, channels=(2,)))
def test_calibrate(recs, alpha, test, threshold, window, step, new):
    try:
        t = LjungBox(3, alpha, threshold=threshold) if test == "lb" else FTest(alpha, threshold=threshold)
        t.calibrate(recs, window=window, step=step)
    except (ValueError, TypeError) as exc:
        named(exc, ("alpha", "resid", "window", "step", "statistic", "reference_variance"))
        return
    event("result: calibrate")
    assert t.threshold_.shape == (2,) and np.all(np.isfinite(t.threshold_))
    try:
        d = t.test(new)
    except (ValueError, TypeError) as exc:
        named(exc, ("resid",))
        return
    event("result: test")
    check_decision(d, 2, inf_ok=constant_columns(new) if test == "lb" else None)


# ---------------------------------------------------------------------------------------------- scale invariance
@st.composite
def well_formed(draw):
    """Finite float residuals (one or two channels, maybe a constant stretch) at scale 10**s, and a factor 10**t,
    both results within 1e-150 .. 1e150."""
    n = draw(st.integers(30, 400))
    k = draw(st.sampled_from([None, 1, 2]))
    x = _values(n, k, draw(st.integers(0, 2 ** 16)), 0, draw(st.sampled_from(["none", "none", "stretch"])),
                "float64")
    t = draw(st.integers(-150, 150))
    s = draw(st.integers(max(-150, -150 - t), min(150, 150 - t)))
    return x * 10.0 ** s, 10.0 ** t


@given(case=well_formed(), lags=st.integers(1, 10), window_frac=st.floats(0.3, 1.0), step=st.integers(1, 40))
def test_scale_invariance(case, lags, window_frac, step):
    x, c = case
    n = x.shape[0]
    window = max(lags + 2, int(window_frac * n))
    assume(window <= n)

    def close(a, b):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        np.testing.assert_array_equal(np.isinf(a), np.isinf(b))
        np.testing.assert_allclose(a[np.isfinite(a)], b[np.isfinite(b)], rtol=1e-6, atol=1e-9)

    close(LjungBox(lags).test(x * c).statistic, LjungBox(lags).test(x).statistic)
    close(ljungbox_windows(x * c, lags, window, step), ljungbox_windows(x, lags, window, step))
    if x.ndim == 2 and x.shape[1] == 2 and not constant_columns(x).any():
        for method in ("hosking", "li-mcleod"):
            try:
                close(LjungBox(lags, multivariate=method).test(x * c).statistic,
                      LjungBox(lags, multivariate=method).test(x).statistic)
            except ValueError as exc:       # a (nearly) singular covariance: refused, at either scale
                named(exc, ("resid",))
    var = float(np.mean(x ** 2))
    for demean in (False, True):
        ft = FTest(demean=demean)
        close(ft.test(x * c, reference_variance=var * c * c, reference_df=200).statistic,
              ft.test(x, reference_variance=var, reference_df=200).statistic)
        close(ft.window_statistic(x * c, window, step, reference_variance=var * c * c),
              ft.window_statistic(x, window, step, reference_variance=var))
    close(MeanTest().test(x * c, reference_variance=var * c * c).statistic,
          MeanTest().test(x, reference_variance=var).statistic)
    close(MeanTest().window_statistic(x * c, window, step, reference_variance=var * c * c),
          MeanTest().window_statistic(x, window, step, reference_variance=var))
    if not constant_columns(x).any():
        close(GLRT(window).test(x * c).statistic, GLRT(window).test(x).statistic)
    sd = np.sqrt(var)
    close(GLRT(window, scale=sd * c).test(x * c).statistic, GLRT(window, scale=sd).test(x).statistic)
    if n > 50:
        close(ZScore().test(x * c).statistic, ZScore().test(x).statistic)


# ---------------------------------------------------------------------------------------------- thresholds
def log_f_tail(dfn: int, dfd: float, f: float) -> float:
    """Exact log P(F(dfn, dfd) > f) for even dfn: the incomplete beta function with an integer parameter is a finite
    sum (an independent check of scipy and of the log-space tail)."""
    a, b = dfd / 2, dfn // 2
    y = dfd / (dfd + dfn * f)
    terms = [math.lgamma(a + j) - math.lgamma(a) - math.lgamma(j + 1) + j * math.log1p(-y) for j in range(b)]
    top = max(terms)
    return a * math.log(y) + top + math.log(sum(math.exp(t - top) for t in terms))


@given(alpha=st.floats(1e-300, 0.5), nu=st.integers(2, 3000), df0=st.integers(1, 10 ** 6),
       lags=st.integers(1, 200), window=st.integers(1, 10 ** 6))
def test_thresholds_hold_alpha(alpha, nu, df0, lags, window):
    """The upper-tail probability of every theoretical threshold is alpha, down to 1e-300."""
    ft = FTest(alpha)
    f = ft.null_threshold(1, nu, reference_df=df0)[0]
    assert f > 0 and not np.isnan(f)
    if np.isfinite(f):
        p = ft.threshold_pvalue(np.array([[f]]), nu, reference_df=df0)[1][0, 0]
        np.testing.assert_allclose(p, alpha, rtol=1e-6)
        if nu % 2 == 0 and nu <= 600 and f < 1e300:
            np.testing.assert_allclose(log_f_tail(nu, df0, f), math.log(alpha), rtol=1e-9, atol=1e-7)
    q = LjungBox(lags, alpha).null_threshold(1)[0]
    np.testing.assert_allclose(special.chdtrc(lags, q), alpha, rtol=1e-5)
    g = GLRT(window, alpha=alpha).threshold_
    assert np.isfinite(g) and g > 0
    if alpha / window > 1e-300:
        np.testing.assert_allclose(special.chdtrc(1, 2 * g), alpha / window, rtol=1e-5)

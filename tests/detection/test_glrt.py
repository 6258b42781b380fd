"""GLRT: equals the direct O(N M^2) form, change estimates, streaming, thresholds, false-alarm rates."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal as sps
from scipy import stats

import tsfdi
from tsfdi.detection import GLRTStream, glrt_direct
from tests.conftest import as_kind, assert_kind, to_numpy


def _rec(rng, n, phi=0.0):
    e = rng.standard_normal(n + 500)
    return sps.lfilter([1], [1, -phi], e)[500:] if phi else e[500:]


def _brute(x, window, scale):
    """Eq. 3 literally: max over change instants of the LLR maximised over the jump A."""
    g = np.empty(len(x))
    for k in range(len(x)):
        best = -np.inf
        for j in range(max(0, k - window + 1), k + 1):
            seg = x[j:k + 1]
            a = seg.mean()  # ML jump
            llr = np.sum(stats.norm.logpdf(seg, a, scale) - stats.norm.logpdf(seg, 0, scale))
            best = max(best, llr)
        g[k] = best
    return g


def test_equals_likelihood_ratio_and_direct():
    rng = np.random.default_rng(0)
    x = rng.standard_normal(50) * 1.5
    x[35:] += 2.0
    gl = tsfdi.GLRT(12, scale=1.5)
    g = gl.statistic(x)
    np.testing.assert_allclose(g, _brute(x, 12, 1.5), rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(g, glrt_direct(x, 12, 1.5), rtol=1e-12, atol=1e-12)
    y = rng.standard_normal(20_000)
    np.testing.assert_allclose(tsfdi.GLRT(200, scale=1.0).statistic(y), glrt_direct(y, 200, 1.0), rtol=1e-9)


def test_change_instant_and_jump():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(3000) * 0.5
    x[2000:] += 1.0
    d = tsfdi.GLRT(100, scale=0.5, alpha=1e-4).test(x)
    assert d.reject and d.channel_reject.tolist() == [True]
    first = d.details["first_alarm"][0]
    assert 2000 <= first <= 2020
    assert abs(d.details["change_index"][0] - 2000) <= 10
    assert 0.5 < d.details["jump"][0] < 2.0
    scan = tsfdi.GLRT(100, scale=0.5).scan(x)
    k = 2099
    assert abs(scan.change_index[k, 0] - 2000) <= 5
    np.testing.assert_allclose(scan.jump[k, 0], x[scan.change_index[k, 0]:k + 1].mean())
    assert np.isnan(d.pvalue).all() and d.test == "GLRT"
    assert d.threshold[0] == pytest.approx(stats.chi2.isf(1e-4 / 100, 1) / 2)


def test_streaming_equals_batch():
    rng = np.random.default_rng(2)
    x = rng.standard_normal((700, 2))
    x[400:, 1] += 1.5
    gl = tsfdi.GLRT(60, scale=[1.0, 1.0], alpha=1e-3)
    g = np.asarray(gl.statistic(x))
    st = gl.stream(nchan=2)
    out = np.array([st.update(v) for v in x[:300]])
    out = np.vstack([out, st.extend(x[300:305]), st.extend(x[305:650]), np.array([st.update(x[650])]),
                     st.extend(x[651:])])
    np.testing.assert_allclose(out, g, rtol=1e-12, atol=1e-12)
    assert st.k == 700 and st.first_alarm == int(np.flatnonzero((g > gl.threshold_).any(axis=1))[0])
    s1 = tsfdi.GLRT(60, scale=1.0).stream()
    vals = np.array([s1.update(v) for v in x[:, 1]])
    assert vals.shape == (700, 1)
    np.testing.assert_allclose(vals[:, 0], g[:, 1], atol=1e-12)
    sc = tsfdi.GLRT(60, scale=1.0).scan(x[:, 1])
    assert s1.change_index[0] == sc.change_index[-1, 0] and s1.jump[0] == pytest.approx(sc.jump[-1, 0])
    s1.reset()
    assert s1.k == 0 and s1.first_alarm is None
    with pytest.raises(ValueError, match="x"):
        s1.update(np.nan)
    with pytest.raises(ValueError, match="x"):
        s1.update([1.0, 2.0])
    with pytest.raises(ValueError, match="scale"):
        tsfdi.GLRT(10).stream()
    assert isinstance(tsfdi.GLRT(10, scale=1.0).stream(), GLRTStream)


@pytest.mark.slow
@pytest.mark.parametrize("phi", [0.0, 0.8])
def test_empirical_threshold_false_alarm_within_factor_2(phi):
    """Calibrated on one healthy record, the rate on fresh healthy records is within 2x of P_F, for iid and
    for AR(1) residuals; the theoretical (iid) threshold holds its bound for iid and is far off for AR(1)."""
    pf, window = 1e-3, 50
    rng = np.random.default_rng(30)
    gl = tsfdi.GLRT(window, threshold=tsfdi.EmpiricalThreshold(pf)).calibrate(_rec(rng, 200_000, phi))
    assert gl.threshold.method_ == "empirical"
    fresh = [_rec(rng, 100_000, phi) for _ in range(10)]
    rate = np.mean([gl.test(x).details["alarm_rate"][0] for x in fresh])
    assert pf / 2 <= rate <= 2 * pf, rate
    theoretical = tsfdi.GLRT(window, scale=gl.scale_, alpha=pf)
    rate_an = np.mean([np.mean(np.asarray(theoretical.statistic(x)) > theoretical.threshold_) for x in fresh])
    if phi == 0.0:
        assert rate_an <= pf          # union bound: conservative for iid
    else:
        assert rate_an > 2 * pf       # wrong (by orders of magnitude) for correlated residuals
        assert rate_an > 50 * pf


@pytest.mark.slow
def test_gpd_tail_threshold():
    pf = 1e-4
    rng = np.random.default_rng(31)
    gl = tsfdi.GLRT(5, threshold=tsfdi.EmpiricalThreshold(pf)).calibrate(rng.standard_normal(50_000))
    assert gl.threshold.method_ == "gpd"
    g = np.asarray(gl.statistic(rng.standard_normal(2_000_000)))
    rate = np.mean(g > gl.threshold_)
    assert pf / 2 <= rate <= 2 * pf, rate
    # the tail model agrees with the empirical exceedance at the fit location and at the threshold
    et = gl.threshold
    assert et.exceedance(et.gpd_["location"] + 1e-9) == pytest.approx(et.gpd_["zeta"], rel=1e-6)
    assert et.exceedance(et.threshold_) == pytest.approx(pf, rel=1e-6)
    assert et.gpd_["shape"] == 0.0
    # shape fitted by maximum likelihood as well
    free = tsfdi.EmpiricalThreshold(pf, tail_shape=None).calibrate(gl.healthy_statistic_.ravel())
    assert free.method_ == "gpd" and free.gpd_["shape"] != 0.0
    assert free.exceedance(free.threshold_) == pytest.approx(pf, rel=1e-6)
    fixed = tsfdi.EmpiricalThreshold(pf, tail_shape=0.1).calibrate(gl.healthy_statistic_.ravel())
    assert fixed.gpd_["shape"] == 0.1 and fixed.exceedance(fixed.threshold_) == pytest.approx(pf, rel=1e-6)


def test_calibration_sample_too_small():
    et = tsfdi.EmpiricalThreshold(1e-6)
    with pytest.raises(ValueError, match=r"statistic is too small.*at least 200000 are needed"):
        et.calibrate(np.random.default_rng(3).standard_normal(5000) ** 2)
    assert et.samples_needed() == 200_000
    with pytest.raises(ValueError, match="needed"):
        tsfdi.GLRT(10, threshold=tsfdi.EmpiricalThreshold(1e-6)).calibrate(np.random.default_rng(4).standard_normal(3000))
    with pytest.raises(ValueError, match="not calibrated"):
        tsfdi.GLRT(10, scale=1.0, threshold=tsfdi.EmpiricalThreshold(1e-3)).test(np.zeros(100))


def test_empirical_quantile_value():
    s = np.random.default_rng(5).exponential(size=10_000)
    et = tsfdi.EmpiricalThreshold(0.01).calibrate(s)
    assert et.threshold_ == pytest.approx(np.quantile(s, 0.99))
    assert "empirical" in repr(et)


def test_data_kinds(kind):
    rng = np.random.default_rng(6)
    x = rng.standard_normal((400, 2))
    x[300:, 0] += 2
    gl = tsfdi.GLRT(40, scale=1.0, alpha=1e-3)
    g = gl.statistic(as_kind(x, kind))
    assert_kind(g, kind, 2)
    np.testing.assert_allclose(to_numpy(g), np.asarray(gl.statistic(x)))
    d = gl.test(as_kind(x[:, 0], kind, name="r"))
    assert d.reject
    assert_kind(d.details["g"], kind, 1)
    if kind == "pandas":
        assert d.details["first_alarm_label"][0] == as_kind(x[:, 0], kind).index[d.details["first_alarm"][0]]
    cal = tsfdi.GLRT(40, threshold=tsfdi.EmpiricalThreshold(0.01)).calibrate(as_kind(rng.standard_normal(5000), kind))
    assert cal.threshold.method_ == "empirical"


def test_detect_with_glrt_uses_baseline_scale():
    rng = np.random.default_rng(7)
    y0 = sps.lfilter([1], [1, -0.5], rng.standard_normal(3000)) * 0.2
    res = tsfdi.AR(y0, 1).fit()
    y = sps.lfilter([1], [1, -0.5], rng.standard_normal(2000)) * 0.2
    y[1500:] += 0.5
    d = tsfdi.detect(y, res, tsfdi.GLRT(50, alpha=1e-4))
    np.testing.assert_allclose(d.details["scale"], np.sqrt(res.sigma2 * res.nobs / res.df_resid))
    assert d.reject and 1450 <= d.details["change_index"][0] <= 1560


def test_bad_input():
    x = np.random.default_rng(8).standard_normal(100)
    bad = x.copy()
    bad[10] = np.nan
    with pytest.raises(ValueError, match="resid"):
        tsfdi.GLRT(10, scale=1.0).test(bad)
    with pytest.raises(ValueError, match="healthy"):
        tsfdi.GLRT(10, threshold=tsfdi.EmpiricalThreshold(0.1)).calibrate(bad)
    with pytest.raises(ValueError, match="window"):
        tsfdi.GLRT(0)
    with pytest.raises(ValueError, match="scale"):
        tsfdi.GLRT(10, scale=-1.0)
    with pytest.raises(ValueError, match="threshold"):
        tsfdi.GLRT(10, threshold="bonferroni")
    with pytest.raises(ValueError, match="threshold"):
        tsfdi.GLRT(10, threshold=-3.0)
    for a in (0, 1, 1.2):
        with pytest.raises(ValueError, match="alpha"):
            tsfdi.GLRT(10, alpha=a)
        with pytest.raises(ValueError, match="false_alarm"):
            tsfdi.EmpiricalThreshold(a)
    with pytest.raises(ValueError, match="scale"):
        tsfdi.GLRT(10, scale=[1.0, 2.0]).test(np.ones((50, 3)))


def test_scan_direct_and_threshold_kinds(kind):
    rng = np.random.default_rng(40)
    x = rng.standard_normal(500)
    gl = tsfdi.GLRT(30, scale=1.0)
    sc = gl.scan(as_kind(x, kind))
    np.testing.assert_allclose(sc.g[:, 0], glrt_direct(as_kind(x, kind), 30, 1.0))
    s = rng.exponential(size=5000)
    et = tsfdi.EmpiricalThreshold(0.01).calibrate(as_kind(s, kind))
    assert et.threshold_ == pytest.approx(np.quantile(s, 0.99))


@pytest.mark.parametrize("k", [1, 3])
def test_stream_update_always_returns_one_value_per_channel(k):
    """update returns shape (k,) and extend (n, k) for every number of channels, k = 1 included."""
    rng = np.random.default_rng(41)
    x = rng.standard_normal((120, k))
    x[80:] += 2.0
    gl = tsfdi.GLRT(15, scale=1.0, alpha=1e-3)
    ref = np.asarray(gl.statistic(x)).reshape(120, k)
    st = gl.stream(k)
    assert st.g.shape == (k,) and repr(st).startswith("GLRTStream(window=15, scale=")
    first = st.update(x[0] if k > 1 else float(x[0, 0]))           # a plain float is one sample of one channel
    assert isinstance(first, np.ndarray) and first.shape == (k,) and first.dtype == np.float64
    ups = [st.update(v) for v in x[1:60]]
    assert all(isinstance(u, np.ndarray) and u.shape == (k,) for u in ups)
    assert st.g.shape == (k,)
    last = ups[-1].copy()
    ups[-1][:] = -1.0                                                 # the returned array is the caller's own
    np.testing.assert_array_equal(st.g, last)
    ups[-1] = last
    block = st.extend(x[60:100, 0] if k == 1 else x[60:100])          # (n,) input for one channel, too
    assert block.shape == (40, k)
    assert st.extend(np.empty((0, k))).shape == (0, k)
    if k == 1:
        assert st.extend(np.empty(0)).shape == (0, 1)
    rest = st.extend(x[100:])
    out = np.vstack([first[None], np.array(ups), block, rest])
    np.testing.assert_allclose(out, ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(st.g, rest[-1])
    assert st.k == 120 and st.first_alarm is not None


def test_theoretical_threshold_vocabulary():
    """threshold="theoretical" is the one name of the distributional threshold; the old names are gone."""
    gl = tsfdi.GLRT(20, scale=1.0, alpha=1e-3)
    assert gl.threshold == "theoretical" and "threshold='theoretical'" in repr(gl) and "scale=[1.]" in repr(gl)
    d = gl.test(np.random.default_rng(42).standard_normal(200))
    assert d.details["threshold_method"] == "theoretical" and d.df[0] == 1.0
    assert tsfdi.GLRT(20, threshold=3.0, scale=1.0).test(np.zeros(50)).details["threshold_method"] == "fixed"
    for old in ("analytical", "chi2"):
        with pytest.raises(ValueError, match="threshold"):
            tsfdi.GLRT(20, threshold=old)
    with pytest.raises(TypeError):
        tsfdi.GLRT(20, sigma=1.0)  # the standard deviation is called scale


def test_reference_gives_scale():
    rng = np.random.default_rng(43)
    res = tsfdi.AR(rng.standard_normal(500), 1).fit()
    ref = tsfdi.GLRT(20).reference(res)
    assert list(ref) == ["scale"]
    np.testing.assert_allclose(ref["scale"], np.sqrt(res.sigma2 * res.nobs / res.df_resid))
    assert tsfdi.GLRT(20, scale=2.0).reference(res) == {}
    d = tsfdi.GLRT(20).test(rng.standard_normal(300), **ref)
    np.testing.assert_array_equal(d.details["scale"], ref["scale"])


def test_empirical_threshold_module():
    """EmpiricalThreshold lives in detection.threshold (no test imports), exported by tsfdi.detection and tsfdi."""
    from tsfdi.detection import threshold as threshold_module

    assert tsfdi.detection.EmpiricalThreshold is threshold_module.EmpiricalThreshold is tsfdi.EmpiricalThreshold
    et = tsfdi.EmpiricalThreshold(0.01)
    with pytest.raises(ValueError, match="not calibrated"):
        et.check_fitted()
    et.calibrate(np.random.default_rng(44).exponential(size=5000))
    et.check_fitted()


def test_theoretical_threshold_clips_the_window_to_the_record():
    """Issue 29: GLRT(10**9).test on 300 samples took the union bound over 10**9 change instants (threshold 25.4);
    a record of 300 samples has 300, so the threshold is that of GLRT(300) (10.8)."""
    y = np.random.default_rng(29).standard_normal(300)
    huge, clipped = tsfdi.GLRT(10**9, scale=1.0).test(y), tsfdi.GLRT(300, scale=1.0).test(y)
    np.testing.assert_allclose(huge.threshold, clipped.threshold, rtol=1e-14)
    np.testing.assert_allclose(huge.threshold, stats.chi2.isf(1e-3 / 300, 1) / 2, rtol=1e-10)
    assert huge.details["window"] == 300 and huge.reject == clipped.reject
    assert tsfdi.GLRT(10**9).threshold_ > huge.threshold[0]          # the full window: for a stream
    # the parameter GLRT: the same union bound
    from tsfdi.detection import ParameterGLRT

    x = np.random.default_rng(30).standard_normal((300, 2))
    a, b = ParameterGLRT(10**9, scale=1.0).test(y, x), ParameterGLRT(300, scale=1.0).test(y, x)
    np.testing.assert_allclose(a.threshold, b.threshold, rtol=1e-14)
    assert a.details["window"] == 300


def _numpy_scan(x, window, scale):
    """The O(N M) scan in plain numpy: one vector operation per post-change length."""
    c = np.concatenate([[0.0], np.cumsum(x)])
    g = np.zeros(x.size)
    for n in range(1, min(window, x.size) + 1):
        d = c[n:] - c[:-n]
        np.maximum(g[n - 1:], d * d / (2.0 * scale ** 2 * n), out=g[n - 1:])
    return g


@pytest.mark.parametrize("n, window", [(1, 1), (7, 3), (2047, 500), (4097, 4096), (12_000, 5000), (30_000, 500),
                                       (9000, 20_000), (5000, 7), (6000, 2050), (4500, 13)])
def test_statistic_equals_numpy_scan(n, window):
    # the length-outer kernel of GLRT.statistic on records spanning several 2048-sample blocks, windows longer than a
    # block or than the record, windows whose lengths do not split into the kernel's passes of four (7, 13, 2050),
    # with a mean far from zero (cumulative-sum cancellation)
    rng = np.random.default_rng(n + window)
    x = 3.0 * rng.standard_normal(n) + 40.0
    g = np.asarray(tsfdi.GLRT(window, scale=2.5).statistic(x))
    np.testing.assert_allclose(g, _numpy_scan(x, window, 2.5), rtol=1e-10)
    y = 0.7 * rng.standard_normal((n, 2))
    np.testing.assert_allclose(np.asarray(tsfdi.GLRT(window, scale=0.7).scan(y).g),
                               np.asarray(tsfdi.GLRT(window, scale=0.7).statistic(y)), rtol=1e-12, atol=1e-300)


@pytest.mark.skipif(__import__("platform").machine() not in ("x86_64", "AMD64"), reason="x86-64 assembly")
def test_scan_kernel_compiles_to_packed_instructions():
    # the kernel of GLRT.statistic must compile to packed (SIMD) double-precision arithmetic, not scalar code; the
    # cached dispatcher cannot be inspected, so the same Python function is compiled afresh
    import re

    import numba

    from tsfdi.detection import glrt as glrt_module

    kernel = numba.njit(nogil=True, fastmath=True)(glrt_module._scan_g.py_func)
    kernel(np.zeros(10), 0, 5, 0.5)
    asm = "\n".join(kernel.inspect_asm().values())
    packed = re.findall(r"\bv?(?:sub|mul)pd\b", asm)
    assert len(packed) >= 2, "GLRT scan kernel compiled to scalar code"

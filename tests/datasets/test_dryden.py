"""Dryden turbulence: specification values, exact discretisation, Monte Carlo sigmas and Welch PSDs."""

import numpy as np
import pytest
from scipy import linalg, signal

from tsfdi.datasets import DrydenTurbulence, dryden_turbulence

FT, KT = 0.3048, 0.514444


def test_spec_values_low_altitude():
    d = DrydenTurbulence(altitude=5.0, airspeed=5.0, span=0.6096, intensity="severe")
    h = 5.0 / FT
    lu, lv, lw = d.length_scales
    assert lw == pytest.approx(5.0)
    assert lu == pytest.approx(h / (0.177 + 0.000823 * h) ** 1.2 * FT)
    assert lv == lu
    su, sv, sw = d.linear_sigmas
    assert sw == pytest.approx(4.5 * KT)
    assert su == pytest.approx(sw / (0.177 + 0.000823 * h) ** 0.4)
    for level, w20 in [("light", 15), ("moderate", 30), ("severe", 45)]:
        assert DrydenTurbulence(intensity=level).linear_sigmas[2] == pytest.approx(0.1 * w20 * KT)


def test_state_space_variance_equals_spec_and_closed_form_p():
    d = DrydenTurbulence(altitude=5.0, airspeed=5.0, intensity="moderate")
    std = d.std()
    np.testing.assert_allclose(std[:3], d.linear_sigmas, rtol=1e-10)
    # sigma_p^2 = sigma_w^2 * 0.8 (pi/4b)^(1/3) / L_w^(2/3) * pi^2 / (8 b) (integral of the p filter)
    b, lw, sw = d.span, d.length_scales[2], d.linear_sigmas[2]
    sp2 = sw ** 2 * 0.8 * (np.pi / (4 * b)) ** (1 / 3) / lw ** (2 / 3) * np.pi ** 2 / (8 * b)
    assert std[3] == pytest.approx(np.sqrt(sp2), rel=1e-10)
    # the analytic PSD integrates to the variance
    f = np.logspace(-5, 4, 200001)
    np.testing.assert_allclose(np.trapezoid(d.psd(f), f, axis=1), std ** 2, rtol=2e-3)


def test_exact_discretisation_preserves_stationary_covariance():
    d = DrydenTurbulence(intensity="severe")
    P = d.stationary_covariance()
    for dt in (1e-3, 1e-2, 0.5):
        Ad, F = d.discretize(dt)
        A, _, _ = d.state_space()
        np.testing.assert_allclose(Ad, linalg.expm(A * dt), rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(Ad @ P @ Ad.T + F @ F.T, P, rtol=1e-8, atol=1e-10 * np.abs(P).max())


@pytest.mark.parametrize("intensity", ["light", "severe"])
def test_monte_carlo_sigmas_within_10_percent(intensity):
    d = DrydenTurbulence(altitude=5.0, airspeed=5.0, intensity=intensity)
    g = d.simulate(60000, 0.01, rng=1, records=20)  # 20 records x 600 s
    sd = g.reshape(-1, 6).std(axis=0)
    spec = np.r_[d.linear_sigmas, d.std()[3:]]
    np.testing.assert_allclose(sd, spec, rtol=0.10)


def test_welch_psd_matches_dryden_forms():
    """Band-averaged Welch PSD / analytic PSD in [0.75, 1.33] on 10 log bands from 0.02 to 5 Hz
    (fs = 100 Hz; below 0.02 Hz the 200 s segments do not resolve, above fs/20 aliasing grows)."""
    fs = 100.0
    d = DrydenTurbulence(altitude=5.0, airspeed=5.0, intensity="moderate")
    g = d.simulate(120000, 1 / fs, rng=7, records=8)
    f, pxx = signal.welch(g, fs=fs, nperseg=20000, axis=1)
    pxx = pxx.mean(axis=0)  # (nf, 6)
    model = d.psd(f).T
    edges = np.logspace(np.log10(0.02), np.log10(5.0), 11)
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (f >= lo) & (f < hi)
        ratio = pxx[sel].mean(axis=0) / model[sel].mean(axis=0)
        assert np.all((ratio > 0.75) & (ratio < 1.33)), (lo, hi, ratio)


def test_dryden_turbulence_dataarray_and_reproducible():
    a = dryden_turbulence(5.0, fs=100.0, intensity="light", rng=3)
    b = dryden_turbulence(5.0, fs=100.0, intensity="light", rng=3)
    assert a.dims == ("time", "component") and a.shape == (500, 6)
    assert list(a.component.values) == ["u", "v", "w", "p", "q", "r"]
    np.testing.assert_array_equal(a.values, b.values)
    c = dryden_turbulence(5.0, fs=100.0, sigmas=(1.0, 2.0, 0.5), rng=3)
    assert c.attrs["sigma_u_v_w"] == [1.0, 2.0, 0.5]


@pytest.mark.parametrize("kwargs, name", [
    ({"intensity": "extreme"}, "intensity"), ({"altitude": -1.0}, "altitude"), ({"airspeed": 0.0}, "airspeed"),
    ({"span": 0.0}, "span"), ({"sigmas": (1.0, -1.0, 1.0)}, "sigmas")])
def test_bad_model_input(kwargs, name):
    with pytest.raises(ValueError, match=name):
        DrydenTurbulence(**kwargs)


def test_bad_step():
    d = DrydenTurbulence()
    with pytest.raises(ValueError, match="dt"):
        d.simulate(10, 0.0)
    with pytest.raises(ValueError, match="dt"):
        d.discretize(-1e-3)
    with pytest.raises(ValueError, match="fs"):
        dryden_turbulence(1.0, fs=0.0)


def test_scale_length_sets_all_three_and_keeps_the_intensities():
    d = DrydenTurbulence(altitude=5.0, airspeed=5.0, intensity="severe", scale_length=0.6096)
    assert d.length_scales == (0.6096, 0.6096, 0.6096)
    assert d.linear_sigmas == DrydenTurbulence(altitude=5.0, airspeed=5.0, intensity="severe").linear_sigmas
    np.testing.assert_allclose(d.std()[:3], d.linear_sigmas, rtol=1e-10)
    g = dryden_turbulence(1.0, fs=100.0, scale_length=2.0, rng=0)
    assert g.attrs["L_u_v_w"] == [2.0, 2.0, 2.0]


@pytest.mark.parametrize("length", [0.6096, 3.0])
def test_scale_length_monte_carlo_variance(length):
    """Sample variance of each linear gust over 4 x 1000 s at 100 Hz equals sigma^2 within 5 standard errors of a
    variance estimate (chi-square: relative standard error sqrt(2 T_c / T) with the correlation time T_c = 2 L / V
    taken generously for the second-order v, w filters)."""
    V = 5.0
    d = DrydenTurbulence(altitude=5.0, airspeed=V, intensity="moderate", scale_length=length)
    g = d.simulate(100000, 0.01, rng=11, records=4)
    var = (g.reshape(-1, 6)[:, :3] ** 2).mean(axis=0)
    rse = np.sqrt(2.0 * (2.0 * length / V) / 4000.0)
    np.testing.assert_allclose(var, np.square(d.linear_sigmas), rtol=5 * rse)


def test_scale_length_psd_shape():
    """Welch PSD / analytic PSD in [0.75, 1.33] on log bands from 0.05 to 5 Hz with L = 0.6096 m (corner of the
    u filter at V / (2 pi L) = 1.3 Hz for V = 5 m/s, inside the bands), and the PSD differs from the
    MIL-F-8785C one (its u corner is at 0.08 Hz). Linear gusts only: the angular ones have corners near
    fs / 2 at this span and alias."""
    fs = 100.0
    d = DrydenTurbulence(altitude=5.0, airspeed=5.0, intensity="moderate", scale_length=0.6096)
    g = d.simulate(60000, 1 / fs, rng=3, records=8)
    f, pxx = signal.welch(g, fs=fs, nperseg=4000, axis=1)
    pxx = pxx.mean(axis=0)
    model = d.psd(f).T
    edges = np.logspace(np.log10(0.05), np.log10(5.0), 9)
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (f >= lo) & (f < hi)
        ratio = pxx[sel, :3].mean(axis=0) / model[sel, :3].mean(axis=0)
        assert np.all((ratio > 0.75) & (ratio < 1.33)), (lo, hi, ratio)
    default = DrydenTurbulence(altitude=5.0, airspeed=5.0, intensity="moderate").psd([1.3])[0, 0]
    assert d.psd([1.3])[0, 0] > 3 * default


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan")])
def test_bad_scale_length(value):
    with pytest.raises(ValueError, match="scale_length"):
        DrydenTurbulence(scale_length=value)

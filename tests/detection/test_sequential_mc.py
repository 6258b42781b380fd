"""Monte Carlo acceptance of the sequential tests (issue 33): Wald's bounds and ASN on ideal AR / VAR data, the
MSPRT bound on 4 AR models, and the LLR scale calibration on misspecified residuals.

Ideal data: a model is fitted on one long record of the true process; fresh records of the true process (H0) and of
the fault process (H1: innovations with ``ratio`` times the variance, or shifted by ``shift`` standard deviations)
are filtered by the fitted model and tested. Realised error rates must satisfy Wald's bounds
(alpha' <= alpha / (1 - beta), beta' <= beta / (1 - alpha)): the count must not lie above the two-sided 99.9 %
binomial band of the bound. Mean decision times must be within 20 % of Wald's ASN; the settings keep the per-sample
information small against the bounds (ratio 1.5, shift 0.25 std, alpha = beta = 0.02), where the overshoot that
Wald's ASN neglects is below about 10 % (a ratio of 3 or a shift of 1 std overshoots by 25-40 %).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal, stats

import tsfdi
from tsfdi.detection.sequential import SPRT, aligned_record_effect, msprt, msprt_scale, record_effect

pytestmark = pytest.mark.slow

ALPHA = BETA = 0.02
REPS = 1500


def band_high(count: int, n: int, p: float) -> bool:
    """Whether ``count`` of ``n`` lies above the two-sided 99.9 % binomial band of probability ``p``."""
    return count > stats.binom.ppf(1 - 0.0005, n, p)


def ar_records(a: np.ndarray, n_rec: int, n: int, rng: np.random.Generator, scale: float = 1.0,
               shift: float = 0.0) -> np.ndarray:
    """``n_rec`` records of ``y[t] + a_1 y[t-1] + ... = e[t]``, ``e ~ N(shift, scale)`` (paper sign convention)."""
    e = np.sqrt(scale) * rng.standard_normal((n_rec, n + 200)) + shift
    return signal.lfilter([1.0], np.r_[1.0, a], e, axis=1)[:, 200:]


def run(test: SPRT, records, sigma) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    d = [test.test(r, sigma=sigma) for r in records]
    return (np.array([x.reject for x in d]), np.array([x.decided for x in d]),
            np.array([x.decision_time for x in d]))


def check(test: SPRT, h0, h1, sigma, nchan: int) -> None:
    rej0, dec0, n0 = run(test, h0, sigma)
    rej1, dec1, n1 = run(test, h1, sigma)
    assert dec0.all() and dec1.all()
    a_bound, b_bound = test.alpha / (1 - test.beta), test.beta / (1 - test.alpha)
    assert not band_high(int(rej0.sum()), len(h0), a_bound), rej0.mean()
    assert not band_high(int((~rej1).sum()), len(h1), b_bound), (~rej1).mean()
    null, alt = (1.0, test.ratio) if test.alternative == "variance" else (0.0, test.shift)
    for n, theta in ((n0, null), (n1, alt)):
        asn = test.asn(theta, nchan=nchan)
        assert abs(n.mean() / asn - 1) < 0.2, (theta, n.mean(), asn)


@pytest.fixture(scope="module")
def ar_fit():
    a = np.array([-0.9, 0.4])
    rng = np.random.default_rng(330)
    y = ar_records(a, 1, 20000, rng)[0]
    return a, tsfdi.AR(y, 2).fit(), rng


@pytest.mark.parametrize("alternative", ["variance", "mean"])
def test_sprt_ar_error_rates_and_asn(ar_fit, alternative):
    a, res, rng = ar_fit
    if alternative == "variance":
        test = SPRT("variance", ratio=1.5, alpha=ALPHA, beta=BETA)
        fault = {"scale": 1.5}
    else:
        test = SPRT("mean", shift=0.25, alpha=ALPHA, beta=BETA)
        fault = {"shift": 0.25}
    h0 = [res.residuals(y) for y in ar_records(a, REPS, 1500, rng)]
    h1 = [res.residuals(y) for y in ar_records(a, REPS, 1500, rng, **fault)]
    check(test, h0, h1, res.sigma2, 1)


def test_sprt_var_error_rates_and_asn():
    """VAR(1) with correlated innovations: the variance alternative with the fitted covariance matrix (the law of
    e' Sigma0^-1 e is theta chi2(k) for any Sigma0, so the theory holds for the joint statistic)."""
    rng = np.random.default_rng(331)
    A = np.array([[0.5, 0.2], [-0.1, 0.3]])
    L = np.linalg.cholesky(np.array([[1.0, 0.5], [0.5, 2.0]]))

    def records(n_rec, n, scale=1.0):
        e = np.sqrt(scale) * rng.standard_normal((n_rec, n + 100, 2)) @ L.T
        y = np.zeros_like(e)
        for t in range(1, n + 100):
            y[:, t] = y[:, t - 1] @ A.T + e[:, t]
        return y[:, 100:]

    res = tsfdi.VAR(records(1, 20000)[0], 1).fit()
    test = SPRT("variance", ratio=1.5, alpha=ALPHA, beta=BETA)
    h0 = [res.residuals(y) for y in records(REPS, 800)]
    h1 = [res.residuals(y) for y in records(REPS, 800, 1.5)]
    check(test, h0, h1, res.sigma, 2)


def test_msprt_four_ar_models_error_rate():
    """4 AR(2) candidates fitted on one record each; fresh records of each true model: the rate of wrong
    decisions under each model lies within the band of alpha, and every record is decided."""
    rng = np.random.default_rng(332)
    coefs = [np.array([-0.9, 0.4]), np.array([-0.8, 0.4]), np.array([-0.9, 0.5]), np.array([-0.6, 0.2])]
    fits = [tsfdi.AR(ar_records(a, 1, 20000, rng)[0], 2).fit() for a in coefs]
    alpha, reps = 0.05, 400

    def loglik(y):
        cols = []
        for f in fits:
            e = f.residuals(y)
            cols.append(-0.5 * (np.log(2 * np.pi * f.sigma2) + e * e / f.sigma2))
        return np.column_stack(cols)

    for i, a in enumerate(coefs):
        out = [msprt(loglik(y), alpha=alpha) for y in ar_records(a, reps, 3000, rng)]
        labels = np.array([o.label for o in out])
        assert (labels < 0).mean() < 0.02
        wrong = int(((labels >= 0) & (labels != i)).sum())
        assert not band_high(wrong, reps, alpha), (i, wrong)


def ar1_residuals(n_rec: int, n: int, rng: np.random.Generator, phi: float = 0.6, scale: float = 1.0):
    """Misspecified residuals: AR(1) with marginal variance ``scale``, tested as white noise of variance 1."""
    e = rng.standard_normal((n_rec, n + 100)) * np.sqrt(scale * (1 - phi ** 2))
    return signal.lfilter([1.0], [1.0, -phi], e, axis=1)[:, 100:]


def test_sprt_calibrate_restores_the_bounds_on_autocorrelated_residuals():
    """AR(1) residuals (phi = 0.6) treated as white: the raw SPRT's error rates break Wald's bounds; the scale
    estimated on held-out records brings them back within them on fresh records."""
    rng = np.random.default_rng(333)
    alpha = beta = 0.05
    raw = SPRT("variance", ratio=1.5, alpha=alpha, beta=beta)
    h0, h1 = ar1_residuals(REPS, 3000, rng), ar1_residuals(REPS, 3000, rng, scale=1.5)
    a_bound, b_bound = alpha / (1 - beta), beta / (1 - alpha)
    rej0, _, _ = run(raw, h0, 1.0)
    rej1, _, _ = run(raw, h1, 1.0)
    assert band_high(int(rej0.sum()), REPS, a_bound) and band_high(int((~rej1).sum()), REPS, b_bound)

    cal = SPRT("variance", ratio=1.5, alpha=alpha, beta=beta).calibrate(list(ar1_residuals(20, 3000, rng)), 1.0)
    assert 0.3 < cal.scale_ < 0.6
    rej0, dec0, _ = run(cal, h0, 1.0)
    rej1, dec1, _ = run(cal, h1, 1.0)
    assert dec0.all() and dec1.all()
    assert not band_high(int(rej0.sum()), REPS, a_bound), rej0.mean()
    assert not band_high(int((~rej1).sum()), REPS, b_bound), (~rej1).mean()


def test_msprt_scale_restores_the_bound_on_autocorrelated_residuals():
    """Three white-noise variance models (1, 1.5, 2.25) on AR(1) residuals of those variances: the raw MSPRT errs
    more often than alpha; with msprt_scale estimated on held-out records it does not."""
    rng = np.random.default_rng(334)
    var = np.array([1.0, 1.5, 2.25])
    alpha, reps = 0.05, 400

    def loglik(e):
        return -0.5 * (np.log(2 * np.pi * var) + e[:, None] ** 2 / var)

    held = [(loglik(e), i) for i in range(3) for e in ar1_residuals(10, 3000, rng, scale=var[i])]
    c = msprt_scale([h for h, _ in held], [i for _, i in held])
    assert 0.2 < c < 0.5
    wrong_raw = wrong_cal = 0
    for i in range(3):
        for e in ar1_residuals(reps, 3000, rng, scale=var[i]):
            ll = loglik(e)
            wrong_raw += msprt(ll, alpha=alpha).label != i
            out = msprt(ll, alpha=alpha, scale=c)
            assert out.decided
            wrong_cal += out.label != i
    assert band_high(wrong_raw, 3 * reps, alpha)
    assert not band_high(wrong_cal, 3 * reps, alpha)


def hierarchical_records(rng: np.random.Generator, mu: np.ndarray, lam: np.ndarray, per_state: int, n: int,
                         b_mu: float = 0.3, b_lam: float = 0.15, phi: float = 0.5) -> list:
    """``per_state`` records of every state ``i``: the residuals of every model ``c`` on the record,
    ``(mu_i - mu_c + u) + exp(lam_i - lam_c + v) eps`` with a record effect ``u ~ N(0, b_mu^2)``,
    ``v ~ N(0, b_lam^2)`` per channel and unit-variance AR(1) noise ``eps`` (coefficient ``phi``)."""
    M, k = mu.shape
    out = []
    for i in range(M):
        for _ in range(per_state):
            u, v = b_mu * rng.standard_normal(k), b_lam * rng.standard_normal(k)
            eps = signal.lfilter([1.0], [1.0, -phi], rng.standard_normal((n + 100, k)), axis=0)[100:]
            eps *= np.sqrt(1 - phi ** 2)
            out.append((i, [(mu[i] - mu[c] + u) + np.exp(lam[i] - lam[c] + v) * eps for c in range(M)]))
    return out


def test_record_effect_keeps_the_msprt_bound_under_record_to_record_variation():
    # 4 states whose records differ from each other (trim, scale) more than their within-record noise says: the
    # Gaussian per-sample log-likelihoods (each model's variance from its own fitting records) decide early and
    # wrongly far more often than alpha; the record-effect likelihood fitted on 8 records per state keeps
    # P(wrong decision) <= alpha (count within the 99.9 % binomial band of alpha over all records)
    rng = np.random.default_rng(20261128)
    M, k, n, alpha, reps = 4, 2, 1000, 0.05, 250
    mu, lam = rng.normal(0.0, 1.0, (M, k)), rng.normal(0.0, 0.2, (M, k))
    fit = hierarchical_records(rng, mu, lam, 8, n)
    law = record_effect({f"s{c}": [r[c] for i, r in fit if i == c] for c in range(M)}, block=50)
    var = [np.mean([np.mean(r[c] ** 2, axis=0) for i, r in fit if i == c], axis=0) for c in range(M)]
    test = hierarchical_records(rng, mu, lam, reps, n)
    wrong_re = wrong_g = decided_re = 0
    for i, r in test:
        d = msprt(law.loglik(r), alpha=alpha)
        decided_re += d.decided
        wrong_re += d.decided and d.label != i
        gauss = np.column_stack([-0.5 * (np.log(var[c]).sum() + (r[c] ** 2 / var[c]).sum(axis=1)) for c in range(M)])
        g = msprt(gauss, alpha=alpha)
        wrong_g += g.decided and g.label != i
    total = M * reps
    assert wrong_g > 3 * alpha * total, wrong_g                      # the problem: the Gaussian rule errs
    assert decided_re > 0.3 * total, decided_re                      # the record-effect rule decides
    assert not band_high(wrong_re, total, alpha), (wrong_re, decided_re)


def test_aligned_record_effect_decides_records_that_follow_a_programme():
    # 3 states differing in trim; every record flies the same manoeuvre early on (a large common excursion of the
    # running mean) with its own trim and AR(1) noise. The aligned law has the manoeuvre in its centre at every
    # sample and decides about twice as many records as the one-centre record effect, within the bound
    rng = np.random.default_rng(20261128)
    M, n, alpha, reps = 3, 600, 0.05, 80
    t = np.arange(n)
    prog = np.where(t < 150, 2.0, 0.0) * np.sin(np.pi * t / 150)
    mu = np.array([0.0, 0.6, 1.2])

    def rec(j):
        eps = signal.lfilter([1.0], [1.0, -0.7], rng.standard_normal(n + 50))[50:] * np.sqrt(1 - 0.49)
        return (prog + mu[j] + 0.1 * rng.standard_normal() + eps)[:, None]

    fit = {f"s{j}": [rec(j) for _ in range(6)] for j in range(M)}
    aligned = aligned_record_effect(fit, min_samples=20)
    fixed = record_effect(fit, block=30, min_samples=20)
    wrong = decided = decided_fixed = 0
    for _ in range(reps):
        for j in range(M):
            x = rec(j)
            d = msprt(aligned.loglik([x] * M), alpha=alpha)
            decided += d.decided
            wrong += d.decided and d.label != j
            decided_fixed += msprt(fixed.loglik([x] * M), alpha=alpha).decided
    assert decided > 1.5 * decided_fixed, (decided, decided_fixed)
    assert not band_high(wrong, M * reps, alpha), (wrong, decided)


def test_aligned_record_effect_keeps_the_bound_when_its_assumptions_hold():
    # CrazyPAD's shape (7 candidates, 3 records each, 4 summaries) with the law's assumptions true: a Gaussian
    # record effect with one spread for every state, AR(0.9) noise. msprt looks at every sample, yet P(wrong) stays
    # within alpha (the bound is not guaranteed for a running predictive law; this checks it where it should hold)
    rng = np.random.default_rng(1)
    M, R, n, q, alpha = 7, 3, 1000, 4, 0.01
    mu = rng.normal(0.0, 1.0, (M, q))

    def rec(j):
        eps = signal.lfilter([1.0], [1.0, -0.9], rng.standard_normal((n + 50, q)), axis=0)[50:] * np.sqrt(1 - 0.81)
        return mu[j] + 0.3 * rng.standard_normal(q) + eps

    wrong = decided = total = 0
    for _ in range(60):
        law = aligned_record_effect({f"s{j}": [rec(j) for _ in range(R)] for j in range(M)}, min_samples=50,
                                    summaries=[f"mean[y{i}]" for i in range(q)])
        for j in range(M):
            x = rec(j)
            d = msprt(law.loglik([x] * M), alpha=alpha)
            total += 1
            decided += d.decided
            wrong += d.decided and d.label != j
    assert decided > 0.3 * total, decided
    assert not band_high(wrong, total, alpha), (wrong, decided, total)


def test_aligned_record_effect_spread_groups_keep_the_bound_when_the_spread_differs_by_group():
    # two airframes: A (10 states) whose records hardly differ, B (4 states) whose records spread widely, 3 records
    # per state, 4 summaries, AR(0.9) noise; B's records are decided among B's states. One spread pooled over both
    # says B's records are tighter than they are and msprt errs far beyond alpha on them; the spread per group
    # (spread_groups) keeps the bound
    rng = np.random.default_rng(2)
    R, n, q, alpha, reps = 3, 600, 4, 0.01, 80
    groups = {"A": (10, 0.02), "B": (4, 0.6)}            # states, record-effect standard deviation
    mu = {g: rng.normal(0.0, 0.6, (m, q)) for g, (m, _) in groups.items()}

    def rec(g, j):
        eps = signal.lfilter([1.0], [1.0, -0.9], rng.standard_normal((n + 50, q)), axis=0)[50:] * np.sqrt(1 - 0.81)
        return mu[g][j] + groups[g][1] * rng.standard_normal(q) + eps

    summaries = [f"mean[y{i}]" for i in range(q)]
    wrong = {"pooled": 0, "grouped": 0}
    decided = {"pooled": 0, "grouped": 0}
    total = 0
    for _ in range(reps):
        held = {f"{j}@{g}": [rec(g, j) for _ in range(R)] for g, (m, _) in groups.items() for j in range(m)}
        laws = {"pooled": aligned_record_effect(held, min_samples=50, summaries=summaries),
                "grouped": aligned_record_effect(held, min_samples=50, summaries=summaries,
                                                 spread_groups={m: m.split("@")[1] for m in held})}
        on_b = [i for i, m in enumerate(held) if m.endswith("@B")]
        for j in range(groups["B"][0]):
            x = rec("B", j)
            total += 1
            for name, law in laws.items():
                d = msprt(law.loglik([x] * len(held))[:, on_b], alpha=alpha)
                decided[name] += d.decided
                wrong[name] += d.decided and d.label != j
    assert band_high(wrong["pooled"], total, alpha), (wrong, decided, total)          # the problem
    assert not band_high(wrong["grouped"], total, alpha), (wrong, decided, total)
    assert decided["grouped"] > 0.05 * total, (wrong, decided, total)


def test_aligned_record_effect_predictive_law_covers_new_records():
    # 6 states, 3 records each, 6 summaries (nu = 12 degrees of freedom for the spread, 7 for the t law): a new
    # record's summaries fall outside the law's 99 % region (its Mahalanobis distance under the law's scale matrix
    # beyond q F(0.99; q, df)) on 1 % of records. The scale matrix must carry the uncertainty of the spread,
    # nu / (nu - q + 1) = 1.7 here: without it ~10 % fall outside
    rng = np.random.default_rng(7)
    M, R, n, q, reps = 6, 3, 60, 6, 1500
    summaries = [f"mean[y{i}]" for i in range(q)]
    outside = 0
    for _ in range(reps):
        mu = rng.normal(0.0, 1.0, (M, q))
        law = aligned_record_effect({f"s{j}": [mu[j] + rng.normal(0.0, 1.0, q) + 0.01 * rng.standard_normal((n, q))
                                               for _ in range(R)] for j in range(M)},
                                    min_samples=n, summaries=summaries)
        x = mu[0] + rng.normal(0.0, 1.0, q) + 0.01 * rng.standard_normal((n, q))
        d = x.mean(axis=0) - law.center[0, -1]
        psi = law.between[-1] * law.scale[0, -1] * (1 + 1 / R)
        outside += d @ np.linalg.solve(psi, d) / q > stats.f.ppf(0.99, q, law.df[0, -1])
    assert law.df[0, -1] == 12 - q + 1
    assert not band_high(outside, reps, 0.01) and outside > stats.binom.ppf(0.0005, reps, 0.01), outside

"""The fit-time stability check of scalar models (issue 36): the Schur-Cohn step-down recursion against the
eigenvalues of the companion matrix (:attr:`roots`), on random stable, unstable and near-unit polynomials."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tsfdi
from tsfdi.exceptions import UnstableModelWarning
from tsfdi.models._base import _scalar_stable


def _eig_stable(a):
    """All roots of 1 + a[0] z + ... + a[p-1] z^p outside the unit circle, by the companion eigenvalues, and the
    distance of the nearest root modulus to 1 (how far the case is from the rounding boundary)."""
    p = a.size
    comp = np.zeros((p, p))
    comp[0] = -a
    comp[np.arange(1, p), np.arange(p - 1)] = 1.0
    lam = np.abs(np.linalg.eigvals(comp))         # inverse roots: stable when all < 1
    return bool(np.all(lam < 1.0)), float(np.min(np.abs(lam - 1.0)))


@st.composite
def polynomials(draw):
    """Coefficients a[0..p-1] from roots drawn stable, unstable or near the circle (real and complex pairs),
    or drawn directly."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    p = draw(st.integers(1, 50))
    if draw(st.booleans()):
        return rng.uniform(-1.5, 1.5, p) / rng.uniform(1, p + 1)
    kind = draw(st.sampled_from(["stable", "unstable", "near"]))
    inv = []                                       # inverse roots (inside the circle: stable)
    while len(inv) < p:
        if kind == "near":
            rho = 1.0 + rng.choice([-1, 1]) * 10.0 ** rng.uniform(-6, -2)
        elif kind == "stable" or len(inv) > 0:
            rho = rng.uniform(0.0, 0.999)
        else:
            rho = rng.uniform(1.001, 1.5)
        if len(inv) < p - 1 and rng.random() < 0.6:
            w = rng.uniform(0, np.pi)
            inv += [rho * np.exp(1j * w), rho * np.exp(-1j * w)]
        else:
            inv.append(rho * rng.choice([-1.0, 1.0]))
    a = np.poly(inv).real[1:]                      # z^p + a[0] z^(p-1) + ... : the inverse roots
    return a


@settings(max_examples=400, deadline=None)
@given(polynomials())
def test_step_down_agrees_with_eigenvalues(a):
    stable, margin = _eig_stable(a)
    if margin < 1e-9:                              # within rounding of the circle: either answer is right
        return
    assert _scalar_stable(a) == stable


def test_step_down_edge_cases():
    assert _scalar_stable(np.array([0.0]))                     # 1: no finite root
    assert _scalar_stable(np.array([0.5, 0.0, 0.0]))           # trailing zero coefficients: roots at infinity
    assert not _scalar_stable(np.array([-1.0]))                # a root at z = 1
    assert not _scalar_stable(np.array([0.0, 1.0]))            # roots at +-i
    assert not _scalar_stable(np.array([np.nan, 0.1]))
    assert not _scalar_stable(np.array([0.1, np.inf]))


@pytest.mark.parametrize("a, warns", [([-0.5], False), ([-1.01], True), ([-1.8, 0.81], False),
                                      ([-1.9, 0.95], False), ([-2.0, 1.02], True)])
def test_fit_warns_iff_unstable(a, warns):
    """The fit's UnstableModelWarning follows the eigenvalues (roots), decided by the step-down recursion."""
    rng = np.random.default_rng(4)
    e = rng.standard_normal(3000)
    y = np.zeros(3000)
    for t in range(len(a), 3000):
        y[t] = e[t] - sum(ai * y[t - i - 1] for i, ai in enumerate(a))
    y /= np.abs(y).max()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = tsfdi.AR(y, len(a)).fit()
    said = any(issubclass(w.category, UnstableModelWarning) for w in caught)
    assert said == (not res.is_stable) == warns

"""Held-out residuals of functionally pooled models (issue 32): each record at its own operating point through the
FP model refitted without it (against brute-force refits), whole groups held out together, folds that cannot be
fitted refused, and ``at(k)`` carrying them so that calibration and coverage read the FP model's null."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from conftest import as_kind, to_numpy
from test_fp import KS, simulate_ar

import tsfdi
from tsfdi.models import AR, FPAR, FPARX, FPVAR, HeldOutResiduals
from tsfdi.coverage import coverage


def brute(family, ys, ks, drop, *args, us=None, **kw):
    """Residuals of records ``drop`` through ``family`` fitted on the other records, each at its own k."""
    keep = [i for i in range(len(ys)) if i not in drop]
    sub = [ys[i] for i in keep]
    if us is None:
        res = family(sub, np.asarray(ks)[keep], *args, **kw).fit()
        return [res.residuals(ys[i], ks[i]) for i in drop]
    res = family(sub, [us[i] for i in keep], np.asarray(ks)[keep], *args, **kw).fit()
    return [res.residuals(ys[i], ks[i], us[i]) for i in drop]


def test_held_out_residuals_equal_brute_force_refits():
    """FP-AR (pooled and point-weighted), FP-VAR and FP-ARX: every record through the FP fit on the others at its
    own k, equal to refitting the FP model without it (1e-10); groups hold out whole operating points."""
    rng = np.random.default_rng(3)
    ys = [simulate_ar(k, 300, rng, scale=1 + k) for k in KS]
    for weights in ("pooled", "point"):
        spec = FPAR(ys, KS, 2, degree=2, trend="c", weights=weights)
        held = spec.held_out_residuals()
        assert isinstance(held, HeldOutResiduals) and held.lags == 2 and len(held) == len(ys)
        for i in range(len(ys)):
            want = brute(FPAR, ys, KS, [i], 2, degree=2, trend="c", weights=weights)[0]
            np.testing.assert_allclose(held[i], want, rtol=0, atol=1e-10 * np.abs(want).max())
    # the two records at k = 0.45 held out together: the fit sees 4 distinct points, enough for degree 2
    groups = ["a", "b", "mid", "c", "d", "mid"]
    held = FPAR(ys, KS, 2, degree=2).held_out_residuals(groups=groups)
    for i, want in zip([2, 5], brute(FPAR, ys, KS, [2, 5], 2, degree=2)):
        np.testing.assert_allclose(held[i], want, rtol=0, atol=1e-10 * np.abs(want).max())
    vs = [np.column_stack([y, np.roll(y, 1) + rng.standard_normal(300)]) for y in ys]
    held = FPVAR(vs, KS, 2, degree=1, weights="point").held_out_residuals()
    for i in (0, 4):
        want = brute(FPVAR, vs, KS, [i], 2, degree=1, weights="point")[0]
        np.testing.assert_allclose(held[i], want, rtol=0, atol=1e-10 * np.abs(want).max())
    us = [rng.standard_normal(300) for _ in KS]
    held = FPARX(ys, us, KS, 2, 2, 1, degree=1).held_out_residuals()
    for i in (1, 4):
        want = brute(FPARX, ys, KS, [i], 2, 2, 1, us=us, degree=1)[0]
        np.testing.assert_allclose(held[i], want, rtol=0, atol=1e-10 * np.abs(want).max())


@pytest.mark.parametrize("kind", ["pandas", "xarray"])
def test_held_out_residuals_keep_the_data_kind(kind):
    rng = np.random.default_rng(4)
    ys = [as_kind(simulate_ar(k, 200, rng), kind) for k in KS]
    held = FPAR(ys, KS, 2, degree=1).held_out_residuals()
    res = FPAR(ys[1:], KS[1:], 2, degree=1).fit()
    want = res.residuals(ys[0], KS[0])
    assert type(held[0]) is type(want)
    np.testing.assert_allclose(to_numpy(held[0]), to_numpy(want), rtol=0, atol=1e-10)
    if kind == "pandas":
        pd.testing.assert_index_equal(held[0].index, want.index)


def test_held_out_folds_that_cannot_be_fitted_are_refused():
    """Holding out a whole operating point of three at degree 2 leaves two: refused, naming what is needed."""
    rng = np.random.default_rng(5)
    ks = np.array([0.0, 0.5, 1.0, 0.0, 0.5, 1.0])
    ys = [simulate_ar(k, 200, rng) for k in ks]
    spec = FPAR(ys, ks, 2, degree=2)
    assert len(spec.held_out_residuals()) == 6          # one record out: the other record at its k stays
    with pytest.raises(ValueError, match=r"group 0.0 \(y\[0, 3\]\) leaves 2 distinct operating point\(s\).*3 basis functions of degree 2 in k0"):
        spec.held_out_residuals(groups=ks)
    with pytest.raises(ValueError, match="blocks must be None"):
        spec.held_out_residuals(blocks=4)
    with pytest.raises(ValueError, match="one label per record"):
        spec.held_out_residuals(groups=[0, 1])
    with pytest.raises(ValueError, match="two distinct labels"):
        spec.held_out_residuals(groups=[1] * 6)
    with pytest.raises(ValueError, match="sequence of one label"):
        spec.held_out_residuals(groups="ab")


def test_at_k_calibrates_and_checks_coverage_on_the_fp_null():
    """calibrated_for and coverage of fp.at(k) read the FP model's held-out residuals, not those of the point model
    pooled over every operating point (before: silently the pooled AR's null)."""
    rng = np.random.default_rng(6)
    ys = [simulate_ar(k, 1000, rng) for k in KS]
    spec = FPAR(ys, KS, 2, degree=2)
    fp = spec.fit()
    null = spec.held_out_residuals()
    pooled = AR(ys, 2).held_out_residuals()
    pt = fp.at(0.45)
    for a, b in zip(pt.model.held_out_residuals(), null):
        np.testing.assert_array_equal(a, b)
    test = tsfdi.LjungBox(lags=5, alpha=0.01)
    got = test.calibrated_for({"b": pt}, window=100)["b"]
    want = tsfdi.LjungBox(lags=5, alpha=0.01).calibrate(null, window=100)
    wrong = tsfdi.LjungBox(lags=5, alpha=0.01).calibrate(pooled, window=100)
    np.testing.assert_array_equal(got.threshold_, want.threshold_)
    assert not np.array_equal(got.threshold_, wrong.threshold_)
    y = simulate_ar(0.45, 600, rng)
    c = coverage(pt, y)
    pd.testing.assert_frame_equal(c.table, coverage(pt, y, held_out=null).table)
    assert not c.table.equals(coverage(pt, y, held_out=pooled).table)


def test_a_point_at_k_is_not_saved_as_a_plain_point_model(tmp_path):
    """fp.at(k) saved and loaded would be a point model whose held-out residuals are the pooled point model's (the
    wrong null, silently): save refuses it, naming what to save instead; the FP results themselves save."""
    rng = np.random.default_rng(7)
    ys = [simulate_ar(k, 400, rng) for k in KS]
    fp = FPAR(ys, KS, 2, degree=1).fit()
    with pytest.raises(ValueError, match="save the FP results"):
        fp.at(0.45).save(tmp_path / "pt")
    assert not list(tmp_path.iterdir())
    fp.save(tmp_path / "fp")
    np.testing.assert_array_equal(tsfdi.load(tmp_path / "fp.npz").at(0.45).params, fp.at(0.45).params)

"""Held-out residuals (issue 17): each record / block through the model fitted on all the others."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

import tsfdi
from tsfdi.models import lstsq
from tests.conftest import as_kind, assert_kind, to_numpy
from tests.models.test_ar import simulate_ar
from tests.models.test_var_arx import arx_data, var_system


def ar_records(ns=(400, 600, 500), seed=0, c=0.0):
    rng = np.random.default_rng(seed)
    return [simulate_ar([-1.3, 0.6], n, rng, c=c) for n in ns]


def var_records(ns=(800, 900, 700), seed=1):
    y = var_system(seed, sum(ns))[0]
    edges = np.cumsum((0,) + tuple(ns))
    return [y[a:b] for a, b in zip(edges[:-1], edges[1:])]


def arx_records(ns=(700, 800, 600), seed=2):
    y, u = arx_data(seed, sum(ns))
    edges = np.cumsum((0,) + tuple(ns))
    return [y[a:b] for a, b in zip(edges[:-1], edges[1:])], [u[a:b] for a, b in zip(edges[:-1], edges[1:])]


def others(seq, j):
    return [r for i, r in enumerate(seq) if i != j]


# --- several records: agreement with refitting on the other records ------------------------------------
@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("hold_back", [None, 5])
def test_ar_records_equal_refits(trend, hold_back):
    records = ar_records(c=0.3)
    spec = tsfdi.AR(records, 3, trend, hold_back=hold_back)
    held = spec.held_out_residuals()
    assert isinstance(held, list) and len(held) == len(records)
    for j, r in enumerate(records):
        ref = tsfdi.AR(others(records, j), 3, trend, hold_back=hold_back).fit().residuals(r)
        assert held[j].shape == ref.shape == (r.size - 3,)
        np.testing.assert_allclose(held[j], ref, rtol=1e-8, atol=1e-12)


@pytest.mark.parametrize("trend", ["n", "c"])
def test_var_records_equal_refits(trend):
    records = var_records()
    held = tsfdi.VAR(records, 2, trend).held_out_residuals()
    for j, r in enumerate(records):
        ref = tsfdi.VAR(others(records, j), 2, trend).fit().residuals(r)
        np.testing.assert_allclose(held[j], ref, rtol=1e-8, atol=1e-12)
    # the held-out residuals are not the in-sample ones (the model has not seen the record) ...
    resid = tsfdi.VAR(records, 2, trend).fit().resid
    assert not np.allclose(held[0], resid[0], rtol=1e-6, atol=0)
    # ... and are larger on average: the in-sample fit absorbs part of the noise
    assert sum(float(np.sum(h ** 2)) for h in held) > sum(float(np.sum(e ** 2)) for e in resid)


@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("na,nb,nk", [(2, 2, 1), (0, 3, 2), (3, 1, 0)])
def test_arx_records_equal_refits(trend, na, nb, nk):
    ys, us = arx_records()
    held = tsfdi.ARX(ys, us, na, nb, nk, trend).held_out_residuals()
    for j, (y, u) in enumerate(zip(ys, us)):
        ref = tsfdi.ARX(others(ys, j), others(us, j), na, nb, nk, trend).fit().residuals(y, u)
        np.testing.assert_allclose(held[j], ref, rtol=1e-8, atol=1e-12)


def test_kinds_and_index(kind):
    records = var_records()
    wrapped = [as_kind(r, kind) for r in records]
    held = tsfdi.VAR(wrapped, 2, "c").held_out_residuals()
    for j, (r, h) in enumerate(zip(wrapped, held)):
        assert_kind(h, kind, 2)
        ref = tsfdi.VAR(others(wrapped, j), 2, "c").fit().residuals(r)
        np.testing.assert_allclose(to_numpy(h), to_numpy(ref), rtol=1e-8, atol=1e-12)
        if kind == "pandas":
            pd.testing.assert_index_equal(h.index, r.index[2:])
            assert list(h.columns) == list(r.columns)
            pd.testing.assert_frame_equal(h, ref, rtol=1e-8, atol=1e-12)
        if kind == "xarray":
            np.testing.assert_array_equal(h["time"].values, r["time"].values[2:])
    # a scalar record keeps its Series name and index
    ars = [as_kind(r, kind) for r in ar_records()]
    for r, h in zip(ars, tsfdi.AR(ars, 2).held_out_residuals()):
        assert_kind(h, kind, 1)
        if kind == "pandas":
            assert h.name == r.name and h.index.equals(r.index[2:])


def test_fit_unchanged():
    records = var_records()
    spec = tsfdi.VAR(records, 2, "c")
    before = spec.fit()
    params, sigma, resid = before.params.copy(), before.sigma.copy(), [e.copy() for e in before.resid]
    copies = [r.copy() for r in records]
    spec.held_out_residuals()
    spec.held_out_residuals(blocks=3)
    after = spec.fit()
    np.testing.assert_array_equal(after.params, params)
    np.testing.assert_array_equal(before.params, params)
    np.testing.assert_array_equal(after.sigma, sigma)
    for a, b in zip(after.resid, resid):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(records, copies):
        np.testing.assert_array_equal(a, b)


def test_ill_conditioned_gram_falls_back_to_svd(monkeypatch):
    """When the downdated Gram matrix is refused (forced here), the SVD fit on the other records gives the
    same residuals."""
    records = var_records()
    fast = tsfdi.VAR(records, 2, "c").held_out_residuals()
    monkeypatch.setattr(lstsq, "GRAM_RELATIVE_FLOOR", 1.0)
    slow = tsfdi.VAR(records, 2, "c").held_out_residuals()
    for a, b in zip(fast, slow):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)


# --- blocks ----------------------------------------------------------------------------------------------
def block_reference(X, Y, blocks):
    edges = np.r_[0, np.cumsum([len(c) for c in np.array_split(np.arange(X.shape[0]), blocks)])]
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        keep = np.r_[0:lo, hi:X.shape[0]]
        B = np.linalg.lstsq(X[keep], Y[keep], rcond=None)[0]
        out.append(Y[lo:hi] - X[lo:hi] @ B)
    return edges, out


@pytest.mark.parametrize("trend", ["n", "c"])
@pytest.mark.parametrize("model", ["ar", "var", "arx"])
def test_blocks_equal_explicit_lstsq(model, trend):
    if model == "ar":
        y = simulate_ar([-1.3, 0.6], 1200, np.random.default_rng(5), c=0.4)
        spec, p = tsfdi.AR(y, 3, trend, hold_back=4), 4
        X, Y = lstsq.lagged_design(y[:, None], 3, 4, const=trend == "c")
    elif model == "var":
        y = var_system(6, 1500)[0]
        spec, p = tsfdi.VAR(y, 2, trend), 2
        X, Y = lstsq.lagged_design(y, 2, 2, const=trend == "c")
    else:
        y, u = arx_data(7, 1500)
        spec, p = tsfdi.ARX(y, u, 2, 2, 1, trend), 2
        X, Y = lstsq.lagged_design(y[:, None], 2, 2, const=trend == "c", u=u, nb=2, nk=1)
    for blocks in (None, 4):
        held = spec.held_out_residuals(blocks)
        n = 10 if blocks is None else blocks
        edges, ref = block_reference(X, Y, n)
        assert len(held) == n
        for h, r in zip(held, ref):
            np.testing.assert_allclose(np.reshape(h, r.shape), r, rtol=1e-8, atol=1e-12)
        # the blocks tile the in-sample rows
        assert sum(len(h) for h in held) == X.shape[0] == spec.fit().nobs
        assert [len(h) for h in held] == np.diff(edges).tolist()
        assert p == spec.hold_back


def test_blocks_index_and_single_record_in_list():
    y = var_system(8, 1000)[0]
    frame = as_kind(y, "pandas")
    held = tsfdi.VAR(frame, 2, "c").held_out_residuals(blocks=5)
    assert len(held) == 5 and all(isinstance(h, pd.DataFrame) for h in held)
    start = 2
    for h in held:
        assert h.index.equals(frame.index[start:start + len(h)])
        start += len(h)
    assert start == len(frame)
    # a single record given as a list is a single record: default 10 blocks, flat list
    listed = tsfdi.VAR([y], 2, "c").held_out_residuals()
    alone = tsfdi.VAR(y, 2, "c").held_out_residuals()
    assert len(listed) == len(alone) == 10
    for a, b in zip(listed, alone):
        np.testing.assert_array_equal(a, b)


def test_blocks_with_several_records():
    records = var_records()
    spec = tsfdi.VAR(records, 2, "c")
    flat = spec.held_out_residuals(blocks=3)
    assert len(flat) == 9 and flat.lags == spec.max_lag            # one flat list, blocks in record order
    held = [flat[3 * i:3 * i + 3] for i in range(3)]
    X, Y = spec.design_all()
    bounds = np.r_[0, np.cumsum(spec.nobs_records)]
    for i, rec_blocks in enumerate(held):
        n = spec.nobs_records[i]
        edges = np.r_[0, np.cumsum([len(c) for c in np.array_split(np.arange(n), 3)])] + bounds[i]
        for h, lo, hi in zip(rec_blocks, edges[:-1], edges[1:]):
            keep = np.r_[0:lo, hi:X.shape[0]]
            B = np.linalg.lstsq(X[keep], Y[keep], rcond=None)[0]
            np.testing.assert_allclose(h, Y[lo:hi] - X[lo:hi] @ B, rtol=1e-8, atol=1e-12)


# --- errors ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("blocks", [1, 0, -3, 2.5, "3", True])
def test_bad_blocks(blocks):
    spec = tsfdi.AR(ar_records()[0], 2)
    with pytest.raises(ValueError, match="blocks"):
        spec.held_out_residuals(blocks)


def test_too_few_rows_per_block():
    y = simulate_ar([-1.3, 0.6], 35, np.random.default_rng(3))      # 33 regression rows, 4 coefficients
    with pytest.raises(ValueError, match=r"blocks=10 leaves 3 regression row\(s\) per block .*df_eq \+ 1 = 4"):
        tsfdi.AR(y, 2, "c").held_out_residuals()
    assert len(tsfdi.AR(y, 2, "c").held_out_residuals(5)) == 5     # 6 or 7 rows per block


def test_too_few_rows_per_block_var():
    y = var_system(9, 200)[0]
    with pytest.raises(ValueError, match=r"blocks=10 leaves 19 regression row\(s\) per block in y .*df_eq \+ 1 = 23"):
        tsfdi.VAR(y, 7, "c").held_out_residuals()
    with pytest.raises(ValueError, match=r"in y\[1\]"):
        tsfdi.VAR([y, y[:60]], 2).held_out_residuals(blocks=10)


def test_singular_removal_names_the_record():
    rng = np.random.default_rng(4)
    # removing y[0] leaves two regression rows for four coefficients
    with pytest.raises(ValueError, match=r"removing y\[0\] leaves a singular regression"):
        tsfdi.AR([simulate_ar([-1.3, 0.6], 300, rng), rng.standard_normal(5)], 3, "c").held_out_residuals()
    # removing y[1] leaves a ramp, whose lags and intercept are collinear
    with pytest.raises(ValueError, match=r"removing y\[1\]"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tsfdi.AR([np.arange(300.0), simulate_ar([-1.3, 0.6], 300, rng)], 2, "c").held_out_residuals()


def test_groups_hold_out_records_together():
    """groups: the records of one label are held out together (e.g. the two flights of one log)."""
    records = var_records()
    spec = tsfdi.VAR(records, 2, "c")
    held = spec.held_out_residuals(groups=["a", "a", "b"])
    assert len(held) == 3 and held.lags == spec.max_lag
    without_a = tsfdi.VAR([records[2]], 2, "c").fit()
    without_b = tsfdi.VAR(records[:2], 2, "c").fit()
    for h, ref in zip(held, (without_a.residuals(records[0]), without_a.residuals(records[1]),
                             without_b.residuals(records[2]))):
        np.testing.assert_allclose(np.asarray(h), np.asarray(ref), rtol=1e-8, atol=1e-12)
    # one label per record: the same as no groups
    for h, ref in zip(spec.held_out_residuals(groups=[0, 1, 2]), spec.held_out_residuals()):
        np.testing.assert_allclose(np.asarray(h), np.asarray(ref), rtol=1e-12)
    with pytest.raises(ValueError, match="one label per record"):
        spec.held_out_residuals(groups=["a", "b"])
    with pytest.raises(ValueError, match="two distinct labels"):
        spec.held_out_residuals(groups=["a", "a", "a"])
    with pytest.raises(ValueError, match="blocks"):
        spec.held_out_residuals(blocks=2, groups=["a", "a", "b"])

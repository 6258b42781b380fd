"""Models fitted on several records of one process: stacked regressions, no junction between records."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import tsfdi
from tsfdi.models import load, lstsq
from tests.conftest import as_kind, to_numpy
from tests.models.test_ar import simulate_ar
from tests.models.test_var_arx import arx_data, var_system


def stacked(records, p, const):
    parts = [lstsq.lagged_design(np.atleast_2d(r.T).T, p, p, const=const) for r in records]
    return np.vstack([a for a, _ in parts]), np.vstack([b for _, b in parts])


def test_ar_on_records_equals_stacked_least_squares():
    rng = np.random.default_rng(0)
    records = [simulate_ar([-1.3, 0.6], n, rng) for n in (300, 500, 400)]
    res = tsfdi.AR(records, 3, "c").fit()
    X, Y = stacked(records, 3, True)
    beta = np.linalg.lstsq(X, Y, rcond=None)[0][:, 0]
    np.testing.assert_allclose(res.params, beta, rtol=1e-10)
    assert res.nobs == 1200 - 9
    resid = res.resid
    assert isinstance(resid, list) and [len(r) for r in resid] == [297, 497, 397]
    np.testing.assert_allclose(np.concatenate(resid), Y[:, 0] - X @ beta, atol=1e-12)
    for r, e in zip(records, resid):      # in-sample residuals = residuals of each record through the model
        np.testing.assert_allclose(res.residuals(r), e, atol=1e-12)
    # a single record in a list is the same fit as the record alone
    np.testing.assert_allclose(tsfdi.AR([records[0]], 3).fit().params, tsfdi.AR(records[0], 3).fit().params)


def test_var_records_kinds_and_selection(kind):
    y = var_system(3, 3000)[0]
    records = [as_kind(y[:1200], kind), as_kind(y[1200:], kind)]
    res = tsfdi.VAR(records, 2).fit()
    X, Y = stacked([y[:1200], y[1200:]], 2, False)
    B = np.linalg.lstsq(X, Y, rcond=None)[0]
    np.testing.assert_allclose(res.params, B, rtol=1e-9, atol=1e-12)
    assert all(type(r) is type(records[0]) for r in res.resid)
    if kind == "pandas":
        assert res.resid[1].index.equals(records[1].index[2:])
    sel = tsfdi.select_order(records, 6, "var", trend="c")
    assert sel.spec.multi and sel.selected == 2
    for p in (1, 2, 6):
        np.testing.assert_allclose(sel.table.loc[p, "bic"], sel.fit(p).bic, rtol=1e-9)
    assert sel.fit(3).nobs == 3000 - 2 * 6


def test_arx_records():
    y, u = arx_data(n=1500)
    ys, us = [y[:700], y[700:]], [u[:700], u[700:]]
    res = tsfdi.ARX(ys, us, 2, 2, 1).fit()
    assert res.nobs == 1500 - 2 * 2
    sel = tsfdi.select_order(ys, 4, "arx", u=us, nk=1)
    np.testing.assert_allclose(sel.table.loc[2, "bic"], sel.fit(2).bic, rtol=1e-9)
    np.testing.assert_allclose(res.residuals(ys[1], us[1]), res.resid[1], atol=1e-12)


def test_save_load_records(tmp_path, kind):
    y = var_system(4, 1000)[0]
    res = tsfdi.VAR([as_kind(y[:500], kind), as_kind(y[500:], kind)], 2, "c").fit()
    res.save(tmp_path / "r.npz")
    back = load(tmp_path / "r.npz")
    assert back.model.multi and len(back.model.records) == 2
    np.testing.assert_array_equal(back.params, res.params)
    for a, b in zip(back.resid, res.resid):
        np.testing.assert_array_equal(to_numpy(a), to_numpy(b))
        if kind == "pandas":
            pd.testing.assert_frame_equal(a, b)


def test_list_of_numbers_is_one_signal():
    y = list(simulate_ar([-1.3, 0.6], 200, np.random.default_rng(2)))
    assert not tsfdi.AR(y, 2).multi


def test_bad_records():
    rng = np.random.default_rng(3)
    a, b = rng.standard_normal((300, 3)), rng.standard_normal((300, 2))
    with pytest.raises(ValueError, match=r"y\[1\] has 2 channel\(s\) but y\[0\] has 3"):
        tsfdi.VAR([a, b], 2)
    with pytest.raises(ValueError, match=r"y\[1\] is too short: 3 samples, at least 5"):
        tsfdi.VAR([a, a[:3]], 4)
    with pytest.raises(ValueError, match="y is too short: 0 samples"):
        tsfdi.AR([], 2)
    with pytest.raises(ValueError, match=r"y\[0\] contains 1 NaN"):
        bad = a[:, 0].copy()
        bad[4] = np.nan
        tsfdi.AR([bad, a[:, 1]], 2)
    with pytest.raises(ValueError, match="u must be a list of as many records as y"):
        tsfdi.ARX([a[:, 0], a[:, 1]], a[:, 2], 1, 1)
    with pytest.raises(ValueError, match=r"u\[1\] has 100 samples but y\[1\] has 300"):
        tsfdi.ARX([a[:, 0], a[:, 1]], [a[:, 2], a[:100, 2]], 1, 1)


def test_records_with_other_channel_names_are_named_against_the_first_record():
    rng = np.random.default_rng(4)
    a = pd.DataFrame(rng.standard_normal((300, 2)), columns=["p", "q"])
    b = a.rename(columns={"q": "r"})
    with pytest.raises(ValueError, match=r"y\[1\]: missing channel\(s\) \['q'\]; extra channel\(s\) \['r'\]; "
                                         r"y\[0\] has channels \['p', 'q'\]"):
        tsfdi.VAR([a, b], 2)
    with pytest.raises(ValueError, match=r"data\[1\]: .*; data\[0\] has channels"):
        tsfdi.fit_baselines([a, b], states=["healthy", "healthy"], fs=10.0)

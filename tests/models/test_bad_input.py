"""Every bad input of the models raises an error that names the argument."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import tsfdi
from tsfdi.models import load
from tsfdi.models.archive import register
from tests.conftest import as_kind

rng = np.random.default_rng(0)
Y1 = rng.standard_normal(200)
Y3 = rng.standard_normal((200, 3))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite(bad, kind):
    y = Y1.copy()
    y[17] = bad
    with pytest.raises(ValueError, match=r"y contains 1 NaN/inf value\(s\) \(first at sample 17\)"):
        tsfdi.AR(as_kind(y, kind), 2)
    Y = Y3.copy()
    Y[5, 1] = bad
    with pytest.raises(ValueError, match="y contains"):
        tsfdi.VAR(as_kind(Y, kind), 2)
    with pytest.raises(ValueError, match="u contains"):
        tsfdi.ARX(Y1, y, 1, 1)
    with pytest.raises(ValueError, match="y contains"):
        tsfdi.AR(Y1, 2).fit().residuals(y)


def test_too_short_says_the_minimum():
    with pytest.raises(ValueError, match=r"y is too short for lags=5: 8 samples, at least 11 are needed"):
        tsfdi.AR(Y1[:8], 5)
    with pytest.raises(ValueError, match=r"at least 12 are needed"):
        tsfdi.AR(Y1[:8], 5, "c")
    with pytest.raises(ValueError, match=r"y is too short for lags=4"):
        tsfdi.VAR(Y3[:15], 4)        # 4 + 12 + 1 = 17 needed
    with pytest.raises(ValueError, match=r"y is too short: 3 samples, at least 6"):
        tsfdi.AR(Y1, 5).fit().residuals(Y1[:3])


@pytest.mark.parametrize("lags", [0, -1])
def test_lags_below_one(lags):
    with pytest.raises(ValueError, match="lags must be >= 1"):
        tsfdi.AR(Y1, lags)
    with pytest.raises(ValueError, match="lags must be >= 1"):
        tsfdi.VAR(Y3, lags)


@pytest.mark.parametrize("lags", [1.5, "2", None, True])
def test_lags_not_integer(lags):
    with pytest.raises(TypeError, match="lags must be an integer"):
        tsfdi.AR(Y1, lags)


def test_arx_orders():
    with pytest.raises(ValueError, match="na must be >= 0"):
        tsfdi.ARX(Y1, Y1, -1, 1)
    with pytest.raises(ValueError, match="nb must be >= 0"):
        tsfdi.ARX(Y1, Y1, 1, -1)
    with pytest.raises(ValueError, match="nk must be >= 0"):
        tsfdi.ARX(Y1, Y1, 1, 1, -2)
    with pytest.raises(ValueError, match="na \\+ nb must be >= 1"):
        tsfdi.ARX(Y1, Y1, 0, 0)
    with pytest.raises(ValueError, match="u has 100 samples but y has 200"):
        tsfdi.ARX(Y1, Y1[:100], 1, 1)
    with pytest.raises(ValueError, match="u is required"):
        tsfdi.ARX(Y1, None, 1, 1)


def test_wrong_ndim():
    with pytest.raises(ValueError, match=r"y must be 1-D \(nobs,\) or 2-D"):
        tsfdi.AR(np.zeros((10, 2, 2)), 1)
    with pytest.raises(ValueError, match="y must be a scalar signal"):
        tsfdi.AR(Y3, 2)
    with pytest.raises(ValueError, match="y must be a 2-D"):
        tsfdi.VAR(Y1, 2)
    with pytest.raises(ValueError, match="y must have 1 or 2 dimensions"):
        import xarray as xr

        tsfdi.AR(xr.DataArray(np.zeros((4, 4, 4))), 1)


def test_constant_signal():
    with pytest.raises(ValueError, match=r"y is constant in channel\(s\) \['y1'\]"):
        Y = Y3.copy()
        Y[:, 1] = 3.0
        tsfdi.VAR(Y, 2)
    with pytest.raises(ValueError, match="y is constant"):
        tsfdi.AR(np.ones(100), 1)


def test_channel_mismatch_between_model_and_signal():
    res = tsfdi.VAR(Y3, 2).fit()
    with pytest.raises(ValueError, match=r"y has 2 channel\(s\) but the model was fitted on 3"):
        res.residuals(Y3[:, :2])
    arx = tsfdi.ARX(Y1, Y3[:, :2], 1, 1).fit()
    with pytest.raises(ValueError, match=r"u has 3 input\(s\) but the model was fitted with 2"):
        arx.residuals(Y1, Y3)


def test_non_numeric():
    with pytest.raises(TypeError, match="y must contain real numbers"):
        tsfdi.AR(np.array(["a"] * 50), 1)
    with pytest.raises(TypeError, match="y must contain real numbers"):
        tsfdi.VAR(pd.DataFrame({"a": Y1, "b": ["x"] * 200}), 1)
    with pytest.raises(TypeError, match="y must contain real numbers"):
        tsfdi.AR(Y1.astype(complex), 1)
    with pytest.raises(TypeError, match="y must be a numpy array"):
        tsfdi.AR({"a": 1}, 1)


def test_bad_options():
    with pytest.raises(ValueError, match="trend must be one of"):
        tsfdi.AR(Y1, 2, "ct")
    with pytest.raises(ValueError, match="criterion must be one of"):
        tsfdi.VAR(Y3, 2, criterion="aic")
    with pytest.raises(ValueError, match="hold_back must be >= the largest lag"):
        tsfdi.AR(Y1, 3, hold_back=2)
    with pytest.raises(TypeError, match="rng must be"):
        tsfdi.AR(Y1, 2).fit().simulate(10, rng="seed")
    with pytest.raises(ValueError, match="nobs must be >= 1"):
        tsfdi.AR(Y1, 2).fit().simulate(0)


def test_load_rejects_other_files(tmp_path):
    np.savez(tmp_path / "x.npz", a=np.zeros(3))
    with pytest.raises(ValueError, match="not a tsfdi results archive"):
        load(tmp_path / "x.npz")
    # a genuine archive whose family is unknown, or of a newer format version, is refused
    tsfdi.AR(Y1, 2).fit().save(tmp_path / "m.npz")
    with np.load(tmp_path / "m.npz") as f:
        arrays = {k: f[k] for k in f.files}
    meta = json.loads(str(arrays["meta"]))
    for key, value, match in (("family", "ARMA", "unknown model family 'ARMA'"), ("version", 99, "newer tsfdi")):
        arrays["meta"] = np.array(json.dumps({**meta, key: value}))
        np.savez(tmp_path / "bad.npz", **arrays)
        with pytest.raises(ValueError, match=match):
            load(tmp_path / "bad.npz")
    with pytest.raises(ValueError, match="no layout"):
        register(type("ARMA", (), {}))


def test_constant_new_signal_is_allowed_for_residuals():
    # a stuck sensor is a legitimate signal to test: the residuals are computed, not refused
    res = tsfdi.AR(Y1, 2).fit()
    e = res.residuals(np.full(50, 2.0))
    np.testing.assert_allclose(e, 2.0 * (1 + res.ar_coefs.sum()))


def test_arx_too_short_names_the_orders_that_set_the_lags():
    """Issue 29, item 6: ARX blamed ``na`` when ``nb`` or ``nk`` made the record too short."""
    y, u = Y1[:20], Y3[:20, 0]
    with pytest.raises(ValueError, match=r"y is too short for na=2, nb=30, nk=0: 20 samples, at least 62 are needed "
                                         r"\(hold back 29, the largest lag nk \+ nb - 1, \+ 32 parameters \+ 1\)"):
        tsfdi.ARX(y, u, 2, 30)
    with pytest.raises(ValueError, match=r"y is too short for na=2, nb=1, nk=30: 20 samples, at least 34 are needed "
                                         r"\(hold back 30, the largest lag nk \+ nb - 1,"):
        tsfdi.ARX(y, u, 2, 1, nk=30)
    with pytest.raises(ValueError, match=r"y is too short for na=19, nb=1, nk=0: 20 samples.*\(hold back 19, the "
                                         r"largest lag na,"):
        tsfdi.ARX(y, u, 19, 1)
    with pytest.raises(ValueError, match=r"y is too short for na=1, nb=1, nk=0: 20 samples.*\(hold back 25 \+"):
        tsfdi.ARX(y, u, 1, 1, hold_back=25)
    with pytest.raises(ValueError, match=r"y is too short for na=1, nb=12, nk=3: 12 usable samples in all records"):
        tsfdi.ARX([Y1[:20], Y1[20:40]], [Y3[:20, 0], Y3[20:40, 0]], 1, 12, nk=3)


def test_pandas_y_and_u_with_different_indexes_are_refused():
    """Issue 29, item 5: pandas y and u with different indexes were paired by position."""
    t = pd.date_range("2024", periods=200, freq="10ms")
    y = pd.Series(Y1, index=t)
    late = pd.DataFrame({"p": Y3[:, 0]}, index=t + pd.Timedelta("20ms"))
    with pytest.raises(ValueError, match=r"y and u have different indexes \(first at sample 0: "
                                         r"Timestamp\('2024-01-01 00:00:00'\) in y, Timestamp\('2024-01-01 "
                                         r"00:00:00.020000'\) in u\): they are paired sample by sample"):
        tsfdi.ARX(y, late, 2, 2)
    shuffled = pd.Series(Y3[:, 0], index=np.r_[0:100, 101, 100, 102:200])
    with pytest.raises(ValueError, match=r"y and u have different indexes \(first at sample 100: 100 in y, 101 in u\)"):
        tsfdi.ARX(pd.Series(Y1), shuffled, 2, 2)
    with pytest.raises(ValueError, match=r"y\[1\] and u\[1\] have different indexes"):
        tsfdi.ARX([pd.Series(Y1), pd.Series(Y1)], [pd.Series(Y3[:, 0]), shuffled], 2, 2)
    res = tsfdi.ARX(y, late.set_axis(t), 2, 2).fit()          # the same index: accepted
    with pytest.raises(ValueError, match=r"y and u have different indexes"):
        res.residuals(y, late)
    # arrays, or one array and one labelled signal, are paired by position
    assert tsfdi.ARX(y, Y3[:, 0], 2, 2).fit().nobs == 198
    assert tsfdi.ARX(Y1, late, 2, 2).fit().nobs == 198


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_non_finite_values_are_found_through_the_channel_extremes():
    """as_signal reads finiteness from each channel's extremes (which the models reuse for their peaks): a NaN, an
    inf of either sign in any channel is still refused with its count and first sample, and finite data whose
    spread overflows (1e308 and -1e308 in one channel) is still accepted, neither with a RuntimeWarning from the
    spread's arithmetic (numpy's overflow / inf - inf warnings leaked to the user before)."""
    import dataclasses

    from tsfdi._data import as_signal, channel_extremes

    Y = np.random.default_rng(0).standard_normal((200, 3))
    for (t, j), v in {(57, 1): np.nan, (10, 2): np.inf, (3, 0): -np.inf}.items():
        bad = Y.copy()
        bad[t, j] = v
        with pytest.raises(ValueError, match=rf"y contains 1 NaN/inf value\(s\) \(first at sample {t}\)"):
            as_signal(bad, "y")
        with pytest.raises(ValueError, match=rf"y contains 1 NaN/inf value\(s\) \(first at sample {t}\)"):
            tsfdi.VAR(bad, 2)
    wide = np.c_[Y[:, 0], np.r_[1e308, -1e308, Y[2:, 1]]]
    hi, lo = channel_extremes(as_signal(wide, "y"))
    np.testing.assert_array_equal(hi, wide.max(axis=0))
    np.testing.assert_array_equal(lo, wide.min(axis=0))
    # a Signal made from a checked one (another channel here) computes its own extremes
    sub = dataclasses.replace(as_signal(Y, "y"), values=np.ascontiguousarray(Y[:, [2]]))
    np.testing.assert_array_equal(channel_extremes(sub)[0], Y[:, [2]].max(axis=0))

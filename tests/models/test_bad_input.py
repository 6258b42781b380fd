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

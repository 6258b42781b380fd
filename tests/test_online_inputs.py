"""OnlineDetector and RecursiveARX on hostile input (issue 29): sizes checked up front, y and u paired by index."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import tsfdi
from tsfdi.models.recursive import RecursiveARX

rng = np.random.default_rng(29)
N = 300
U = rng.standard_normal(N)
Y = np.convolve(U, [0.0, 0.8, 0.3])[:N] + 0.05 * rng.standard_normal(N)


def test_a_window_too_large_to_allocate_is_refused_naming_it():
    """Issue 29, item 10: OnlineDetector(window=10**12) allocated 7 TiB (MemoryError)."""
    with pytest.raises(ValueError, match=r"window=1000000000000 for 1 pair\(s\): the errors in the moving window "
                                         r"\(1 x 999,999,999,999\) would hold 999,999,999,999 values \(7.45e\+03 GiB\), "
                                         r"more than the limit of 268,435,456 values \(2 GiB\)"):
        tsfdi.OnlineDetector(1, statistic="mean", window=10**12)
    with pytest.raises(ValueError, match=r"window=2000000 for 200 pair\(s\)"):
        tsfdi.OnlineDetector(200, window=2_000_000)
    assert tsfdi.OnlineDetector(2, statistic="mean", window=1000).window == 1000


def test_y_and_u_with_different_indexes_are_refused():
    """Issue 29, item 5: pandas y and u with different indexes were paired by position."""
    t = pd.date_range("2024", periods=N, freq="10ms")
    y = pd.Series(Y, index=t)
    u = pd.Series(U, index=t + pd.Timedelta("10ms"))
    with pytest.raises(ValueError, match=r"y and u have different indexes \(first at sample 0: Timestamp\('2024-01-01 "
                                         r"00:00:00'\) in y, Timestamp\('2024-01-01 00:00:00.010000'\) in u\)"):
        tsfdi.OnlineDetector(1, na=1, nb=2).run(y, u)
    det = tsfdi.OnlineDetector(1, na=1, nb=2)
    with pytest.raises(ValueError, match=r"y and u have different indexes"):
        det.run(y.to_frame("a"), u.to_frame("b"))
    assert det.nobs == 0                                    # nothing processed
    m = RecursiveARX(1, 2)
    with pytest.raises(ValueError, match=r"y and u have different indexes \(first at sample 0"):
        m.run(y, u)
    with pytest.raises(ValueError, match=r"y and u have different indexes"):
        m.regressors(y, u)
    assert m.nobs == 0
    # the same index, or arrays: paired sample by sample
    assert m.run(y, u.set_axis(t)).resid.index.equals(t)
    assert tsfdi.OnlineDetector(1, na=1, nb=2).run(y, U).resid.index.equals(t)


def test_a_time_index_with_a_gap_is_refused_by_the_online_detector():
    """Issue 29, item 1: the even-sampling rule holds for the online path too."""
    t = pd.Index(np.r_[0:150, 200:350] * 0.01, name="time")
    with pytest.raises(ValueError, match=r"y is not uniformly sampled: a gap of 0.51 s after sample 149 at 1.49 s"):
        tsfdi.OnlineDetector(1, na=1, nb=2).run(pd.Series(Y, index=t), pd.Series(U, index=t))
    with pytest.raises(ValueError, match=r"y is not uniformly sampled: a gap of 0.51 s"):
        RecursiveARX(1, 2).run(pd.Series(Y, index=t), pd.Series(U, index=t))

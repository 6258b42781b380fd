"""Property-based tests of the input families behind the causes of issue 29.

Each family is generated from its valid values and the hostile ones around them, and every entry point on its path
returns a valid result or raises a ``ValueError`` / ``TypeError`` naming the argument:

- **time indexes** (numeric seconds named ``"time"``, ``TimedeltaIndex``, ``DatetimeIndex``, xarray time
  coordinate) with jitter, gaps, repeated stamps and steps back: accepted exactly when every step is positive and
  within :data:`tsfdi._data.JITTER` of the median step (the one even-sampling rule), by the models, their
  residuals, ``detect``, the recursive estimator and the online detector alike;
- **y / u pairing**: pandas ``y`` and ``u`` are accepted exactly when their indexes are equal;
- **object and string dtypes**: numbers held as text are refused, numbers held as objects accepted;
- **overflow to inf**: faults and data near the float64 range give finite results or are refused;
- **huge sizes**: windows, grids and orders far beyond memory are refused before anything is allocated.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import xarray as xr
from _contract import named
from hypothesis import event, given
from hypothesis import strategies as st

import tsfdi
from tsfdi._data import JITTER, as_signal, sampling_frequency
from tsfdi.datasets import align
from tsfdi.datasets.faults import FAULT_KINDS, inject_fault
from tsfdi.models.recursive import RecursiveARX

N = 80
_rng = np.random.default_rng(29)
U = _rng.standard_normal(N)
Y = np.convolve(U, [0.0, 0.7, 0.2])[:N] + 0.3 * _rng.standard_normal(N)


@st.composite
def time_steps(draw) -> np.ndarray:
    """``N - 1`` steps in seconds around a base step: mostly uniform (jitter within the rule), else one hostile
    step (a gap, a short step, a repeat, a step back) or a jitter beyond the rule."""
    dt = draw(st.sampled_from([0.001, 0.01, 0.02, 0.1]))
    jitter = draw(st.sampled_from([0.0, 0.0, 0.3 * JITTER, 0.9 * JITTER, 1.5 * JITTER, 5 * JITTER]))
    rng = np.random.default_rng(draw(st.integers(0, 2**16)))
    steps = dt * (1 + rng.uniform(-jitter, jitter, N - 1)) if jitter else np.full(N - 1, dt)
    hostile = draw(st.sampled_from(["none", "none", "gap", "short", "repeat", "back", "descending"]))
    at = draw(st.integers(0, N - 2))
    if hostile == "gap":
        steps[at] = dt * draw(st.sampled_from([1.2, 2.0, 50.0]))
    elif hostile == "short":
        steps[at] = dt * 0.5
    elif hostile == "repeat":
        steps[at] = 0.0
    elif hostile == "back":
        steps[at] = -dt
    elif hostile == "descending":
        steps = -steps
    return steps


def uniform(steps: np.ndarray, stamps: np.ndarray) -> bool:
    """The rule, on the stamps as the index holds them (nanoseconds for pandas time stamps)."""
    d = np.diff(stamps)
    if not (d > 0).all():
        return False
    med = np.median(d)
    return bool((np.abs(d - med) <= JITTER * med).all())


def indexed(values: np.ndarray, steps: np.ndarray, kind: str):
    seconds = np.r_[0.0, np.cumsum(steps)] + 100.0
    if kind == "numeric":
        index = pd.Index(seconds, name="time")
        return pd.Series(values, index=index), index.to_numpy()
    if kind == "timedelta":
        index = pd.to_timedelta(seconds, unit="s")
        return pd.Series(values, index=index), index.asi8 / 1e9
    if kind == "datetime":
        index = pd.Timestamp("2024-05-01") + pd.to_timedelta(seconds, unit="s")
        return pd.Series(values, index=index), index.asi8 / 1e9
    return xr.DataArray(values, dims="time", coords={"time": seconds}), seconds


KINDS = st.sampled_from(["numeric", "timedelta", "datetime", "xarray"])


@given(time_steps(), KINDS)
def test_one_even_sampling_rule_for_every_entry_point(steps, kind):
    y, stamps = indexed(Y, steps, kind)
    u, _ = indexed(U, steps, kind)
    ok = uniform(steps, stamps)
    event(f"uniform={ok}")
    fitted = tsfdi.ARX(Y, U, 2, 2).fit()
    calls = {"AR": lambda: tsfdi.AR(y, 2).fit().params,
             "ARX": lambda: tsfdi.ARX(y, u, 2, 2).fit().params,
             "residuals": lambda: fitted.residuals(y, u),
             "detect": lambda: tsfdi.detect(y, tsfdi.AR(Y, 2).fit(), tsfdi.LjungBox(lags=5)).statistic,
             "sampling_frequency": lambda: sampling_frequency(as_signal(y)),
             "RecursiveARX": lambda: RecursiveARX(2, 2).run(y, u).resid}
    for name, call in calls.items():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out = call()
        except ValueError as exc:
            assert not ok, f"{name} refused a uniform index: {exc}"
            named(exc, ["y", "signal"])
            continue
        assert ok, f"{name} accepted a non-uniform index: steps {steps.min():g} .. {steps.max():g}"
        assert np.all(np.isfinite(np.asarray(out, dtype=float)) | np.isnan(np.asarray(out, dtype=float)))


@given(st.sampled_from(["same", "shifted", "swapped", "other_kind", "array"]), st.integers(0, N - 2))
def test_y_and_u_are_paired_only_with_the_same_index(how, at):
    t = pd.date_range("2024", periods=N, freq="10ms")
    y = pd.Series(Y, index=t)
    u_index = {"same": t, "shifted": t + pd.Timedelta("10ms"), "swapped": t[np.r_[0:at, at + 1, at, at + 2:N]],
               "other_kind": pd.RangeIndex(N), "array": None}[how]
    u = U if u_index is None else pd.Series(U, index=u_index)
    ok = how in ("same", "array")
    calls = {"ARX": lambda: tsfdi.ARX(y, u, 1, 2).fit().params,
             "RecursiveARX": lambda: RecursiveARX(1, 2).run(y, u).resid,
             "OnlineDetector": lambda: tsfdi.OnlineDetector(1, na=1, nb=2).run(y, u).resid}
    for name, call in calls.items():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                call()
        except ValueError as exc:
            assert not ok, f"{name}: {exc}"
            named(exc, ["u"])        # a swapped pair of time stamps breaks u's own time index first
            assert "y and u have different indexes" in str(exc) or how == "swapped", str(exc)
            continue
        assert ok, f"{name} paired y and u with different indexes ({how})"


ELEMENTS = st.one_of(st.floats(-1e3, 1e3), st.integers(-1000, 1000),
                     st.sampled_from(["1.5", "2", "nan", "", b"3", None, True]))


@given(st.lists(ELEMENTS, min_size=N, max_size=N), st.sampled_from(["object", "str", "series", "frame"]))
def test_numbers_held_as_text_are_refused(items, container):
    arr = np.array(items, dtype=object)
    text = any(isinstance(v, (str, bytes)) for v in items)
    data = {"object": arr, "str": arr.astype(str), "series": pd.Series(arr), "frame": pd.DataFrame({"a": arr})}[container]
    try:
        tsfdi.AR(data, 1).fit()
    except TypeError as exc:
        named(exc, ["y"])
        return
    except ValueError as exc:           # None / NaN (a missing value), True, constant data
        assert not text or container == "str", str(exc)
        named(exc, ["y"])
        return
    assert not text and container != "str", f"numbers held as text were parsed ({container})"


@given(st.sampled_from(FAULT_KINDS), st.floats(-1e308, 1e308), st.sampled_from([1.0, 1e150, 1e300, 1e307]),
       st.one_of(st.none(), st.floats(1e-300, 1e308)))
def test_a_fault_is_finite_or_refused(kind, magnitude, scale, sensor_range):
    y = np.sin(np.arange(N)) * scale
    try:
        faulty, labels = inject_fault(y, kind, magnitude, 10, ramp=5, sensor_range=sensor_range, rng=0)
    except ValueError as exc:
        named(exc, ["magnitude", "sensor_range"])
        return
    assert np.isfinite(faulty).all() and labels.sum() == N - 10


@given(st.one_of(st.integers(-5, 10**15), st.floats(1e-300, 1e15)), st.sampled_from(["window", "fs", "lags", "na",
                                                                                       "nb"]))
def test_huge_sizes_are_refused_before_allocating(size, what):
    frame = pd.DataFrame({"a": Y}, index=pd.to_timedelta(np.arange(N) * 0.01, unit="s"))
    calls = {"window": lambda: tsfdi.OnlineDetector(3, statistic="mean", window=size),
             "fs": lambda: align(frame, size, min_length=1),
             "lags": lambda: tsfdi.AR(Y, size),
             "na": lambda: RecursiveARX(size, 1),
             "nb": lambda: tsfdi.ARX(Y, U, 1, size)}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            calls[what]()
    except (ValueError, TypeError) as exc:
        named(exc, [what, "min_length", "y"])

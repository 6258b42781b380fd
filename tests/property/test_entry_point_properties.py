"""Property-based tests of the high-level entry points (issue 18: the input contract).

Generated signals -- numpy arrays, lists, pandas and xarray objects, masked arrays; lengths from 0 to 160; one to
three channels (the right number or not); float64 / float32 / float16 / int / bool / complex / object / string /
datetime / timedelta dtypes; scales from 1e-300 to 1e300; NaN, inf and constant stretches -- and generated option
values (windows and steps as ints, negative, 0, floats, time spans such as ``"2s"``, junk strings, wrong types;
sampling frequencies; alphas outside (0, 1)) go through ``detect``, ``identify``, ``identify_windows``,
``ResidualWindows``, ``Monitor`` (+ ``run``), ``OnlineDetector`` (+ ``run``, ``update``, ``calibrate``),
``fit_baselines`` / ``Baselines`` (``monitor``, ``select_alpha``), ``evaluate``, ``make_hexacopter_dataset``,
``load_alfa``, ``read_crazypad_log`` and the command line (``fit``, ``identify``). Each call returns a
well-formed result (the caller's kind and shape, no NaN statistic, p-values in [0, 1], rates in [0, 100]) or
raises a ``ValueError`` / ``TypeError`` whose message names the argument (the command line: returns 2 and names
the flag or file). Any other exception fails the test.

Every strategy draws a valid value most of the time and a hostile one otherwise, so that both the checks and the
computations behind them are exercised (``pytest --hypothesis-show-statistics`` lists how often each entry point
returned a result and which argument each refusal named). The models are fitted once per module
(:func:`fitted`), never per example.
"""

from __future__ import annotations

import contextlib
import functools
import gzip
import io
import re
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr
from _contract import named
from hypothesis import event, given
from hypothesis import strategies as st
from scipy.signal import lfilter

import tsfdi
from tsfdi.cli import main
from tsfdi.datasets import load_alfa, make_hexacopter_dataset, read_crazypad_log
from tsfdi.identification import identify_windows
from tsfdi.windows import RULES, STATUS, ResidualWindows

FS = 100.0


@functools.lru_cache(maxsize=None)
def fitted() -> dict:
    """Small AR and VAR models (healthy and fault), records of three states and their baselines, fitted once."""
    rng = np.random.default_rng(0)
    e = rng.standard_normal((2, 600, 2))
    y = lfilter([1.0], [1.0, -0.6, 0.2], e[0, :, 0])
    yf = lfilter([1.0], [1.0, 0.5], e[1, :, 0])
    Y = np.column_stack([y, lfilter([1.0], [1.0, -0.3], e[0, :, 1])])
    Yf = np.column_stack([yf, lfilter([1.0], [1.0, 0.4], e[1, :, 1])])
    recs, states, ft = [], [], []
    for s, a in (("healthy", [1.0, -0.6]), ("f1", [1.0, 0.5]), ("f2", [1.0, -0.2, 0.3])):
        for _ in range(3):
            recs.append(np.column_stack([lfilter([1.0], a, rng.standard_normal(500)) for _ in range(2)]))
            states.append(s)
            ft.append(np.nan if s == "healthy" else 1.0)
    u = rng.standard_normal((2, 2000))
    runs = [lfilter([1.0], [1.0, -0.7], u[i] + 0.1 * rng.standard_normal(2000)) for i in range(2)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = {"ar": tsfdi.AR(y, 2).fit(), "ar_f": tsfdi.AR(yf, 1).fit(), "var": tsfdi.VAR(Y, 1).fit(),
               "var_f": tsfdi.VAR(Yf, 2).fit(), "records": (recs, states, np.array(ft)), "runs": (runs, list(u)),
               "baselines": tsfdi.fit_baselines(recs, states=states, failure_times=ft, fs=FS, settle=0.5,
                                                duration=None, max_lags=3, var_max_lags=3, steady_window="1s",
                                                fit_records=2, calibrate=True)}
    return out


# ---------------------------------------------------------------------------------------------- strategies
def mostly(valid: st.SearchStrategy, hostile: st.SearchStrategy, weight: int = 6) -> st.SearchStrategy:
    """``valid`` about ``weight`` times in ``weight + 1``, else ``hostile``. (``one_of`` would not do:
    hypothesis draws its branches evenly, duplicates or not.)"""
    return st.sampled_from([False] * weight + [True]).flatmap(lambda bad: hostile if bad else valid)


GOOD_DTYPES = ["float64", "float32", "int64", "int8", "uint16", "object"]
BAD_DTYPES = ["float16", "bool", "complex128", "object_str", "datetime64[s]", "timedelta64[s]"]
SCALES = [1.0, 1e-300, 1e-150, 1e-8, 1e8, 1e150, 1e300]


def _values(n: int, k: int | None, seed: int, scale: float, special: str, dtype: str) -> np.ndarray:
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((n,) if k is None else (n, k))
    if special == "constant":
        z[:] = 0.7
    elif special == "constant_stretch" and n > 4:
        z[n // 4: n // 4 + max(n // 2, 3)] = -1.25
    if dtype in ("float64", "float32", "float16", "object"):
        x = (z * scale).astype("float64")
        if special in ("nan", "inf") and x.size:
            x.flat[rng.integers(x.size)] = np.nan if special == "nan" else -np.inf
        with np.errstate(over="ignore"):           # float32 / float16 overflow to inf: part of the test
            return x.astype(dtype)
    if dtype in ("int64", "int8"):
        return np.round(z * 10).astype(dtype)
    if dtype == "uint16":
        return np.round(np.abs(z) * 1000).astype(dtype)
    if dtype == "bool":
        return z > 0
    if dtype == "complex128":
        return z + 1j * z
    if dtype == "object_str":
        return np.array([str(v) for v in z.ravel()], dtype=object).reshape(z.shape)
    return np.arange(z.size).reshape(z.shape).astype(dtype)


def _wrap(x: np.ndarray, container: str, name: str = "y"):
    n = x.shape[0]
    if container == "list":
        return x.tolist()
    if container == "pandas":
        index = pd.date_range("2024-01-01", periods=n, freq="10ms", name="time")
        if x.ndim == 1:
            return pd.Series(x, index=index, name=name)
        return pd.DataFrame(x, index=index, columns=[f"{name}{i}" for i in range(x.shape[1])])
    if container == "xarray":
        time = np.arange(n) / FS
        if x.ndim == 1:
            return xr.DataArray(x, dims=("time",), coords={"time": time}, name=name)
        return xr.DataArray(x, dims=("time", "channel"), coords={"time": time}, name=name)
    if container == "masked":
        mask = np.zeros(x.shape, dtype=bool)
        if n:
            mask[n // 2] = True
        return np.ma.array(x, mask=mask)
    if container == "masked_none":
        return np.ma.array(x)
    return x


@st.composite
def signals(draw, channels: tuple = (None,), other_channels: tuple = (2, 3), max_len: int = 160):
    """A signal: mostly ``channels`` (None: 1-D), valid dtypes, no NaN, numpy / pandas / xarray; sometimes not."""
    n = draw(mostly(st.integers(40, max_len), st.integers(0, 8)))
    k = draw(mostly(st.sampled_from(channels), st.sampled_from(other_channels)))
    dtype = draw(mostly(st.sampled_from(GOOD_DTYPES), st.sampled_from(BAD_DTYPES)))
    special = draw(mostly(st.sampled_from(["none", "constant_stretch"]),
                          st.sampled_from(["nan", "inf", "constant"])))
    container = draw(mostly(st.sampled_from(["numpy", "pandas", "xarray", "list", "masked_none"]),
                            st.just("masked")))
    x = _values(n, k, draw(st.integers(0, 2 ** 16)), draw(st.sampled_from(SCALES)), special, dtype)
    return _wrap(x, container)


# window / step values as a user might pass them (in samples they suit records of 40-160 samples)
BAD_SPANS = st.one_of(st.integers(-3, 2), st.sampled_from([10 ** 12, 2 ** 63]), st.floats(-5, 200),
                      st.sampled_from(["-1s", "0s", "abc", "", "1 day", "1e300s"]), st.none(), st.booleans(),
                      st.just([5]))
WINDOWS = mostly(st.one_of(st.integers(15, 60), st.sampled_from(["0.3s", "400ms", pd.Timedelta("250ms"),
                                                                 np.timedelta64(300, "ms")])), BAD_SPANS)
STEPS = mostly(st.one_of(st.integers(1, 30), st.sampled_from(["0.1s", pd.Timedelta("50ms")])), BAD_SPANS)
RATES = mostly(st.sampled_from([None, 100.0, 100]),
               st.sampled_from([1.0, 0.0, -1.0, np.nan, np.inf, 1e-300, 1e300, "100"]))


def check_decision(d: tsfdi.Decision, nchan: int) -> None:
    stat, thr, pv = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (d.statistic, d.threshold, d.pvalue))
    assert stat.shape == (nchan,) and not np.isnan(stat).any()
    assert np.all(np.isfinite(thr)) and np.all(thr > 0)
    assert np.all(np.isnan(pv) | ((pv >= 0) & (pv <= 1)))
    np.testing.assert_array_equal(np.asarray(d.channel_reject), stat > thr)
    assert bool(d.reject) == bool(np.any(stat > thr))


@contextlib.contextmanager
def quiet():
    """Warnings (unstable fits, ill-conditioned regressors, ...) are not what these tests check."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


SIGNAL_NAMES = ("signal", "y", "u", "resid", "scale", "lags", "window", "order", "models", "baseline")


# ------------------------------------------------------------------------------------ detect and identify
@st.composite
def model_and_signal(draw):
    vector = draw(st.booleans())
    sig = draw(signals(channels=(2,), other_channels=(None, 1, 3)) if vector else
               signals(channels=(None, 1), other_channels=(2, 3)))
    return vector, sig


@given(case=model_and_signal(), test=st.sampled_from(["lb", "f", "glrt"]), use_u=mostly(st.just(False), st.just(True)))
def test_detect_and_identify(case, test, use_u):
    vector, sig = case
    m = fitted()
    base, fault = (m["var"], m["var_f"]) if vector else (m["ar"], m["ar_f"])
    t = {"lb": tsfdi.LjungBox(lags=5), "f": tsfdi.FTest(), "glrt": tsfdi.GLRT(window=4)}[test]
    u = np.ones(5) if use_u else None
    with quiet():
        try:
            d = tsfdi.detect(sig, base, t, u=u)
        except (ValueError, TypeError) as exc:
            named(exc, SIGNAL_NAMES)
        else:
            event("result: detect")
            assert u is None
            check_decision(d, base.neqs)
        try:
            ident = tsfdi.identify(sig, {"h": base, "f": fault}, t, u=u)
        except (ValueError, TypeError) as exc:
            named(exc, SIGNAL_NAMES)
        else:
            event("result: identify")
            assert ident.status in STATUS and set(ident.accepted) <= {"h", "f"}
            assert ident.label in (None, "h", "f") and sorted(ident.ranking) == ["f", "h"]
            for dec in ident.decisions.values():
                check_decision(dec, base.neqs)


@given(case=model_and_signal(), window=WINDOWS, step=STEPS, fs=RATES, lb=st.booleans())
def test_identify_windows(case, window, step, fs, lb):
    vector, sig = case
    m = fitted()
    models = {"h": m["var"], "f": m["var_f"]} if vector else {"h": m["ar"], "f": m["ar_f"]}
    test = tsfdi.LjungBox(lags=3) if lb else tsfdi.FTest()
    with quiet():
        try:
            res = identify_windows(sig, models, test, window=window, step=step, fs=fs)
        except (ValueError, TypeError) as exc:
            named(exc, SIGNAL_NAMES + ("step", "fs"))
            return
    event("result")
    nobs, nwin = len(sig), len(res)
    assert nwin >= 1 and res.statistic.shape == (nwin, 2, 2 if vector else 1)
    assert not np.isnan(res.statistic).any() and np.all(np.isfinite(res.threshold))
    assert np.all(np.isnan(res.pvalue) | ((res.pvalue >= 0) & (res.pvalue <= 1)))
    assert np.all((res.starts >= 0) & (res.stops <= nobs)) and np.all(res.stops - res.starts == res.windows.window)
    assert set(res.status) <= set(STATUS) and all(lab in (None, "h", "f") for lab in res.labels)
    first = res[0]
    assert first.span == (int(res.starts[0]), int(res.stops[0])) and first.status == res.status[0]


@given(sig=signals(channels=(None, 1)), window=WINDOWS, step=STEPS,
       common=mostly(st.none(), st.one_of(st.integers(-2, 200), st.just("a"))),
       loglik=mostly(st.booleans(), st.sampled_from([1, "no", None])))
def test_residual_windows(sig, window, step, common, loglik):
    m = fitted()
    with quiet():
        try:
            rw = ResidualWindows({"h": m["ar"], "f": m["ar_f"]}).fit(sig)
            ws = rw.statistics(tsfdi.LjungBox(lags=3), window=window, step=step, common=common, loglik=loglik)
        except (ValueError, TypeError) as exc:
            named(exc, SIGNAL_NAMES + ("step", "common", "loglik"))
            return
    event("result")
    assert ws.statistic.shape == (len(ws), 2, 1) and not np.isnan(ws.statistic).any()
    assert ws.loglik.shape == (len(ws), 2)
    for rule in RULES:
        labels = ws.labels(rule)
        assert labels.shape == (len(ws),) and np.all((labels >= -2) & (labels <= 1))


# --------------------------------------------------------------------------------------------------- Monitor
@given(sig=signals(channels=(None, 1)), window=WINDOWS, step=STEPS,
       steady=mostly(st.integers(5, 30), BAD_SPANS), fs=RATES, rule=mostly(st.sampled_from(RULES), st.just("vote")),
       thresholds=mostly(st.sampled_from([None, [1.0], [1e-300], [1e300]]),
                         st.sampled_from([[1.0, 2.0], [np.nan], [-1.0], "abc", np.ma.array([1.0], mask=[1])])))
def test_monitor(sig, window, step, steady, fs, rule, thresholds):
    m = fitted()
    with quiet():
        try:
            mon = tsfdi.Monitor(m["ar"], {"f1": m["ar_f"], "f2": m["ar"]}, window=window, step=step, fs=fs,
                                steady_window=steady, rule=rule, test=tsfdi.LjungBox(lags=3),
                                steady_thresholds=thresholds)
        except (ValueError, TypeError) as exc:
            named(exc, ("window", "step", "steady_window", "fs", "rule", "steady_thresholds"))
            return
        try:
            res = mon.run(sig)
        except (ValueError, TypeError) as exc:
            named(exc, SIGNAL_NAMES)
            return
    event("result" if len(res.windows) else "result: no window")
    frame = res.windows
    assert not frame["detect_statistic"].isna().any() and frame["detect_pvalue"].between(0, 1).all()
    assert np.all(np.isfinite(frame[["start", "end"]].to_numpy(dtype=float)))
    assert all(np.isfinite(e.time) for e in res.events)
    assert res.label in (None, "f1", "f2")


# -------------------------------------------------------------------------------------------- OnlineDetector
ONLINE_OPTIONS = st.fixed_dictionaries({}, optional={
    "threshold": mostly(st.sampled_from([4.5, 2.0, 1e300]), st.sampled_from([0.0, -1.0, np.nan, "4"])),
    "window": mostly(st.sampled_from([1, 5, 20]), st.sampled_from([0, -3, 2.5, "5"])),
    "arm_after": mostly(st.sampled_from([0, 10]), st.sampled_from([-1, 1.5])),
    "statistic": mostly(st.sampled_from(["zscore", "mean"]), st.just("median")),
    "direction": mostly(st.sampled_from(["both", "down", "up"]), st.just("left")),
    "nonfinite": mostly(st.sampled_from(["skip", "raise"]), st.just("ignore")),
    "na": mostly(st.sampled_from([1, 2]), st.sampled_from([0, -1])),
})
SAMPLES = mostly(st.floats(-10, 10), st.one_of(st.none(), st.floats(allow_nan=True, allow_infinity=True),
                                               st.booleans(), st.text(max_size=2), st.lists(st.floats(-10, 10),
                                                                                            max_size=3),
                                               st.just(np.ma.array([1.0], mask=[True]))))


@st.composite
def online_case(draw):
    pairs = draw(mostly(st.sampled_from([1, 2, ["a", "b"]]), st.sampled_from([0, ["a", "a"], "a", True, []])))
    k = len(pairs) if isinstance(pairs, list) else pairs if isinstance(pairs, int) and not isinstance(pairs, bool) \
        else 1
    chans = (None, 1) if k == 1 else (k,)
    y = draw(signals(channels=chans, max_len=120))
    u = draw(signals(channels=chans, max_len=120))
    if draw(st.integers(0, 3)):                     # mostly as many input samples as outputs
        u = _wrap(np.ones((len(y),) if k == 1 else (len(y), k)), "numpy")
    return pairs, y, u


@given(case=online_case(), options=ONLINE_OPTIONS, y1=SAMPLES, u1=SAMPLES)
def test_online_detector(case, options, y1, u1):
    pairs, y, u = case
    names = ("y", "u", "pairs", *options)
    with quiet():
        try:
            det = tsfdi.OnlineDetector(pairs, **options)
        except (ValueError, TypeError) as exc:
            named(exc, names)
            return
        k = len(det.pairs)
        try:
            out = det.run(y, u)
        except (ValueError, TypeError) as exc:
            named(exc, names)
        else:
            event("result: run")
            n = len(y)
            assert out.alarm.shape == (n, k) and out.alarm.dtype == bool
            for arr in (out.zscore, out.glrt, out.resid, out.statistic):
                assert np.shape(arr) == (n, k)
            assert out.first_alarm is None or 0 <= out.first_alarm < det.nobs
        before = det.nobs
        try:
            flags = det.update(y1 if k == 1 else [y1] * k, u1 if k == 1 else [u1] * k)
        except (ValueError, TypeError) as exc:
            named(exc, names)
            assert det.nobs == before
        else:
            event("result: update")
            assert flags.shape == (k,) and flags.dtype == bool and det.nobs == before + 1


@given(runs=mostly(st.just("healthy"), st.sampled_from(["generated", "tuple", "array", "empty", "unequal"])),
       y=signals(), rate=mostly(st.sampled_from([400.0, 800.0]), st.sampled_from([1e6, 0.0, -1.0, np.nan, "1"])),
       fs=mostly(st.just(FS), st.sampled_from([None, 0.0, np.inf])), statistic=st.sampled_from(["zscore", "mean"]))
def test_online_calibrate(runs, y, rate, fs, statistic):
    hy, hu = fitted()["runs"]
    u = np.ones(len(y))
    ys, us = {"healthy": (hy, hu), "generated": ([y], [u]), "tuple": ((y, y), (u, u)),
              "array": (np.asarray(hy), hu), "empty": ([], []), "unequal": (hy, hu[:1])}[runs]
    det = tsfdi.OnlineDetector(1, na=1, nb=1, statistic=statistic)
    with quiet():
        try:
            det.calibrate(ys, us, false_alarms_per_hour=rate, fs=fs)
        except (ValueError, TypeError) as exc:
            named(exc, ("y_runs", "u_runs", "y", "u", "false_alarms_per_hour", "fs"))
            return
    event("result")
    cal = det.calibration_
    assert np.isfinite(det.threshold) and det.threshold > 0 and cal.threshold == det.threshold
    assert cal.glrt_threshold is None or (np.isfinite(cal.glrt_threshold) and cal.glrt_threshold > 0)


# -------------------------------------------------------------------------------- fit_baselines / evaluate
@given(settle=mostly(st.sampled_from([0.5, 0.0]), st.sampled_from([-1.0, 1e300, np.nan, "1"])),
       duration=mostly(st.sampled_from([None, 3.0]), st.sampled_from([0.0, 1e-300, 1e300, np.inf])),
       max_lags=mostly(st.sampled_from([2, 3]), st.sampled_from([0, 10 ** 12, 2.5, None])),
       order=mostly(st.sampled_from(["bic", "rss_sss", 2]), st.sampled_from([0, 99, "x", 1.5])),
       steady_window=mostly(st.sampled_from(["1s", 50]), BAD_SPANS),
       fit_records=mostly(st.sampled_from(["first", "all", 1, [0, 3, 6]]), st.sampled_from([0, True, None, [99]])),
       models=mostly(st.sampled_from([None, "var", ["y0"]]), st.sampled_from([[], ["zz"], 3])),
       failure_times=mostly(st.just("given"), st.sampled_from(["none", "negative", "inf", "short", "text"])),
       kind=mostly(st.sampled_from(["numpy", "pandas", "xarray"]), st.just("masked")))
def test_fit_baselines(settle, duration, max_lags, order, steady_window, fit_records, models, failure_times, kind):
    recs, states, ft = fitted()["records"]
    ft = {"given": ft, "none": None, "negative": -ft, "inf": np.where(np.isnan(ft), ft, np.inf),
          "short": ft[:3], "text": ["a"] * len(ft)}[failure_times]
    data = [_wrap(r, "numpy" if kind == "masked" else kind) for r in recs]
    if kind == "masked":
        data[0] = _wrap(recs[0], "masked")
    with quiet():
        try:
            b = tsfdi.fit_baselines(data, states=states, failure_times=ft, fs=FS, settle=settle, duration=duration,
                                    max_lags=max_lags, var_max_lags=3, order=order, steady_window=steady_window,
                                    fit_records=fit_records, models=models)
        except (ValueError, TypeError) as exc:
            named(exc, ("settle", "duration", "max_lags", "var_max_lags", "order", "steady_window", "fit_records",
                        "models", "failure_times", "data", "y", "record", "record(s)", "fs", "lags"))
            return
    event("result")
    assert b.healthy == "healthy" and b.faults == ("f1", "f2")
    assert not np.isnan(b.steady_thresholds).any() and np.all(b.steady_thresholds > 0)   # inf: no steady part
    table = b.table
    assert np.all(np.isfinite(table["bic"])) and (table["lags"] >= 1).all()


@given(windows=mostly(st.sampled_from([[100], ["1s"], [50, "0.8s"], 60]), st.one_of(BAD_SPANS, st.just([]))),
       step=mostly(st.sampled_from([50, "0.5s"]), BAD_SPANS),
       settle=mostly(st.sampled_from([0.0, 0.5]), st.sampled_from([-1.0, 1e300, np.nan])),
       rules=mostly(st.sampled_from([("paper",), ("paper", "likelihood", "pvalue")]),
                    st.sampled_from([("vote",), "paper", ()])),
       models=mostly(st.sampled_from([("var",), "y0", ["y0", "var"]]), st.sampled_from([[], ["zz"], 3])),
       tests=mostly(st.sampled_from([None, "lb", "f", "empirical"]), st.sampled_from(["text", "empty"])),
       kind=mostly(st.just("numpy"), st.just("masked")))
def test_evaluate(windows, step, settle, rules, models, tests, kind):
    m = fitted()
    recs, states, ft = m["records"]
    data = list(recs)
    if kind == "masked":
        data[-1] = _wrap(recs[-1], "masked")
    tests = {None: None, "lb": tsfdi.LjungBox(lags=3), "f": {"variance": tsfdi.FTest()},
             "empirical": tsfdi.LjungBox(lags=3, threshold="empirical"), "text": "whiteness", "empty": {}}[tests]
    with quiet():
        try:
            ev = tsfdi.evaluate(data, m["baselines"], models=models, tests=tests, windows=windows, step=step,
                                settle=settle, rules=rules, states=states, failure_times=ft, fs=FS, progress=False)
        except (ValueError, TypeError) as exc:
            named(exc, ("windows", "window", "step", "settle", "rules", "models", "tests", "data", "data[8]",
                        "lags"))
            return
    event("result")
    det = ev.detection_rates()
    for col in ("false_alarm", "missed_fault"):             # NaN: no window of that kind (documented)
        assert (det[col].between(0, 100) | det[col].isna()).all()
    if ev.identification_counts["windows"].sum():
        assert ev.rates()[["correct", "wrong", "ambiguous", "none"]].sum(axis=1).round(6).eq(100).all()


@given(model=mostly(st.sampled_from(["var", "y0"]), st.sampled_from(["zz", 3])), window=WINDOWS, step=STEPS,
       alphas=mostly(st.sampled_from([(1e-3, 0.5), 0.01]), st.sampled_from([(0.0,), (1.0,), (np.nan,), ("a",), ()])))
def test_baselines_methods(model, window, step, alphas):
    b = fitted()["baselines"]
    with quiet():
        try:
            mon = b.monitor(model, window=window, step=step, test=tsfdi.LjungBox(lags=3))
        except (ValueError, TypeError) as exc:
            named(exc, ("model", "window", "step", "steady_thresholds"))
        else:
            event("result: monitor")
            assert isinstance(mon, tsfdi.Monitor)
        try:
            table = b.select_alpha(model, tsfdi.LjungBox(lags=3), window=window, step=step, alphas=alphas)
        except (ValueError, TypeError) as exc:
            named(exc, ("model", "window", "step", "alphas", "lags"))
        else:
            event("result: select_alpha")
            assert table[["correct", "wrong", "ambiguous", "none"]].sum(axis=1).round(6).eq(100).all()
            assert table.attrs["selected"] in table.index


# ------------------------------------------------------------------------------------------ hexacopter data
@given(rpc=mostly(st.just(1), st.sampled_from([0, -1, 1.5, "a", True])),
       duration=mostly(st.just(0.1), st.sampled_from([0.0, -1.0, np.nan, np.inf])),
       failure_time=mostly(st.sampled_from([0.05, 0.0]), st.sampled_from([0.5, -1.0, np.nan])),
       seed=mostly(st.sampled_from([0, 7]), st.sampled_from([-1, 2.5, "s"])),
       states=mostly(st.sampled_from([("healthy",), ("rotor2",)]), st.sampled_from([("rotor9",), ("nope",)])),
       turbulence=mostly(st.sampled_from([("none",), ("light",)]), st.sampled_from([("hurricane",), "none"])))
def test_make_hexacopter_dataset(rpc, duration, failure_time, seed, states, turbulence):
    with quiet():
        try:
            ds = make_hexacopter_dataset(rpc, duration=duration, failure_time=failure_time, seed=seed, states=states,
                                         turbulence=turbulence)
        except (ValueError, TypeError) as exc:
            named(exc, ("records_per_case", "duration", "failure_time", "seed", "states", "turbulence",
                        "failed_rotor", "records"))
            return
    event("result")
    assert ds.sizes["record"] == rpc * len(states) * len(turbulence)
    assert np.all(np.isfinite(ds["roll"].values) | ds["lost_control"].values[:, None])


# ----------------------------------------------------------------------------------------------- loaders
HEADERS = {"merged": "%time,field.data,field.x", "engine": "time,label,roll_measured",
           "crazypad": "timestamp,controller.cmd_thrust,stateEstimate.z"}


@st.composite
def csv_files(draw) -> tuple[str, bytes]:
    """A CSV log of one of the three layouts, often damaged: (suffix, bytes as stored)."""
    layout = draw(st.sampled_from(sorted(HEADERS)))
    n = draw(mostly(st.integers(2, 8), st.integers(0, 1)))
    t = np.cumsum(draw(st.lists(st.integers(1, 60), min_size=n, max_size=n))) if n else np.zeros(0, int)
    rows = []
    for i, ti in enumerate(t):
        value = draw(st.floats(-1e3, 1e3))
        if layout == "merged":
            rows.append(f"{pd.Timestamp('2018-07-18') + pd.Timedelta(int(ti), 'ms')},{int(i >= n // 2)},{value}")
        elif layout == "engine":
            rows.append(f"{pd.Timestamp('2018-07-18') + pd.Timedelta(int(ti), 'ms')},{i >= n // 2},{value}")
        else:
            rows.append(f"{ti},{int(i % 5 != 0)},{value}")
    damage = draw(mostly(st.just("none"), st.sampled_from(["junk_line", "swap", "text_value", "empty", "binary",
                                                           "no_header", "nan_time"])))
    if damage == "junk_line" and rows:
        rows.insert(draw(st.integers(0, len(rows))), draw(st.sampled_from(['"', ",,,,", "abc", "1e400,1"])))
    elif damage == "swap" and len(rows) > 1:
        rows[0], rows[1] = rows[1], rows[0]
    elif damage == "text_value" and rows:
        rows[-1] = rows[-1].rsplit(",", 1)[0] + ",x"
    elif damage == "nan_time" and rows:
        rows[-1] = "," + rows[-1].split(",", 1)[1]
    text = "\n".join(([] if damage == "no_header" else [HEADERS[layout]]) + rows) + "\n"
    data = b"" if damage == "empty" else draw(st.binary(min_size=1, max_size=30)) if damage == "binary" \
        else text.encode()
    suffix = draw(st.sampled_from([".csv", ".csv.gz"]))
    stored = draw(mostly(st.just("as named"), st.sampled_from(["plain", "gzip", "truncated"])))
    if stored == "as named":
        stored = "gzip" if suffix == ".csv.gz" else "plain"
    if stored != "plain":
        data = gzip.compress(data)
        if stored == "truncated":
            data = data[: len(data) // 2]
    return layout, suffix, data


@given(case=csv_files())
def test_loaders_on_generated_files(case):
    layout, suffix, data = case
    load = read_crazypad_log if layout == "crazypad" else load_alfa
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "controller" / "normal_flight" / f"E8_engine_failure{suffix}"
        path.parent.mkdir(parents=True)
        path.write_bytes(data)
        with quiet():
            try:
                out = load(path, airborne=False) if load is read_crazypad_log else load(path)
            except (ValueError, TypeError) as exc:
                event(f"refused: {layout}")
                assert re.match(r"^(path|file): " + re.escape(str(path)), str(exc)), str(exc)
                return
    event(f"result: {layout}")
    frames = [out] if isinstance(out, pd.DataFrame) else out
    assert len(frames) == 1
    df = frames[0]
    assert len(df) >= 1 and df.index.is_monotonic_increasing and df.index.is_unique
    assert np.isnan(df.attrs["fs"]) if len(df) < 2 else np.isfinite(df.attrs["fs"]) and df.attrs["fs"] > 0
    if layout != "crazypad":
        onset = df.attrs["onset_time"]
        assert df["ground_truth"].tolist() == ([False] * len(df) if onset is None else list(df.index >= onset))


# ------------------------------------------------------------------------------------------ command line
@functools.lru_cache(maxsize=None)
def cli_files() -> Path:
    d = Path(tempfile.mkdtemp(prefix="tsfdi-cli-"))
    rng = np.random.default_rng(3)
    x = lfilter([1.0], [1.0, -0.5], rng.standard_normal(300))
    pd.DataFrame({"time": np.arange(300) / FS, "a": x, "b": rng.standard_normal(300)}).to_csv(d / "ok.csv", index=False)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["fit", str(d / "ok.csv"), "--columns", "a", "--out", str(d / "m.npz"), "--max-lags", "3"]) == 0
    (d / "junk.csv").write_bytes(b"\x00\xff,\n\"")
    (d / "empty.csv").write_text("")
    return d


FLAGS = {"fit": {"--max-lags": ["3", "5"], "--lags": ["1", "2"], "--start": ["0.5s", "50"], "--stop": ["2s", "2.9s"],
                 "--fs": ["100", "50"]},
         "identify": {"--window": ["50", "0.5s"], "--step": ["20", "0.2s"], "--alpha": ["0.01", "1e-6"],
                      "--fs": ["100", "200"], "--lags": ["3", "5"]}}
BAD_FLAG_VALUES = ["0", "-1", "1e300", "nan", "inf", "abc", "", "0.001", "1000"]


@st.composite
def cli_calls(draw):
    command = draw(st.sampled_from(sorted(FLAGS)))
    chosen = draw(st.lists(st.sampled_from(sorted(FLAGS[command])), max_size=3, unique=True))
    flags = {f: draw(mostly(st.sampled_from(FLAGS[command][f]), st.sampled_from(BAD_FLAG_VALUES))) for f in chosen}
    data = draw(mostly(st.just("ok.csv"), st.sampled_from(["junk.csv", "empty.csv", "missing.csv"])))
    columns = draw(mostly(st.just("a"), st.sampled_from([None, "zz", "a,b"])))
    return command, flags, data, columns


@given(call=cli_calls())
def test_cli(call):
    command, flags, data, columns = call
    d = cli_files()
    argv = [command, str(d / data)]
    argv += ["--out", str(d / "out.npz")] if command == "fit" else ["--models", str(d / "m.npz")]
    if columns:
        argv += ["--columns", columns]
    for k, v in flags.items():
        argv += [f"{k}={v}"]
    err = io.StringIO()
    with quiet(), contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        rc = main(argv)
    text = err.getvalue()
    event(f"{command}: rc {rc}")
    assert rc in (0, 2) and "Traceback" not in text
    if rc == 2:
        words = [*flags, data, "--columns", "--models", "--window", "--out"]
        assert any(w in text for w in words) or re.search(r"error: (y|signal|window|lags)\b", text), text

"""Functionally pooled baselines (issue 32): fit_baselines(..., k=) fits one FP model per state over the fitting
records at their logged operating points, evaluate(..., k=) tests every record at its own (res.at(k_record)), on
records in memory and on a dask-backed fleet."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from _synthetic_fdi import FS, SIGMA, SYSTEMS

import tsfdi
from tsfdi import FTest, LjungBox
from tsfdi.exceptions import CoverageWarning
from tsfdi.models import FPResults, select_fp_order

#: the change of every state's A1 from the lowest operating point (speed 2) to the highest (speed 8): the VAR(2)
#: systems of _synthetic_fdi move with the speed, linearly (degree 1 in the speed)
SHIFT = {"healthy": np.array([[0.3, 0.0], [0.1, 0.2]]), "f1": np.array([[-0.2, 0.0], [0.1, 0.3]]),
         "f2": np.array([[0.3, 0.1], [0.0, -0.2]])}
LOW, HIGH = 2.0, 8.0


def _systems(state: str, speed: np.ndarray) -> tuple:
    """A1 (records, 2, 2) and A2 (2, 2) of ``state`` at every record's speed."""
    a1, a2 = SYSTEMS[state]
    x = (np.asarray(speed, dtype=float) - LOW) / (HIGH - LOW)
    return a1[None] + x[:, None, None] * SHIFT[state][None], a2


def records(states: list, speeds: list, n: int, failure: int | None, rng) -> xr.DataArray:
    """``(record, time, channel)`` records, one per (state, speed): healthy until sample ``failure`` then the state
    (healthy records all along), each at its speed; 200 burn-in samples dropped. Coordinates ``state``,
    ``failure_time`` (s), ``speed`` and ``record`` (0, 1, ...)."""
    speeds = np.asarray(speeds, dtype=float)
    states = list(states)
    burn = 200
    total = n + burn
    r = len(states)
    start = np.array([0 if s == "healthy" or failure is None else burn + failure for s in states])
    h1, h2 = _systems("healthy", speeds)
    f1 = np.empty_like(h1)
    f2 = np.empty((r, 2, 2))
    sig = np.empty(r)
    for name in SYSTEMS:
        pick = np.array([s == name for s in states])
        if pick.any():
            a1, a2 = _systems(name, speeds[pick])
            f1[pick], f2[pick], sig[pick] = a1, a2, SIGMA[name]
    e = rng.standard_normal((total, r, 2))
    y = np.zeros((total + 2, r, 2))
    for t in range(total):
        fault = t >= start
        a1 = np.where(fault[:, None, None], f1, h1)
        a2 = np.where(fault[:, None, None], f2, h2)
        scale = np.where(fault, sig, SIGMA["healthy"])
        y[t + 2] = e[t] * scale[:, None] - np.einsum("rij,rj->ri", a1, y[t + 1]) - np.einsum("rij,rj->ri", a2, y[t])
    y = y[2 + burn:].transpose(1, 0, 2)
    ft = np.array([np.nan if s == "healthy" or failure is None else failure / FS for s in states])
    return xr.DataArray(y, dims=("record", "time", "channel"),
                        coords={"record": np.arange(r), "time": np.arange(n) / FS, "channel": ["y0", "y1"],
                                "state": ("record", states), "failure_time": ("record", ft),
                                "speed": ("record", speeds)})


def _with_ids(da: xr.DataArray, first: int) -> xr.DataArray:
    return da.assign_coords(record=np.arange(first, first + da.sizes["record"]))


@pytest.fixture(scope="module")
def fleet():
    """Fitting records: 2 per state at each of the speeds 2, 5, 8 (40 s, failure at 10 s); evaluation records: 3
    healthy and 2 per fault state at speeds between the fitting ones."""
    rng = np.random.default_rng(3201)
    fit_states = [s for s in SYSTEMS for _ in range(6)]
    fit = records(fit_states, [LOW, 5.0, HIGH] * 6, 4000, 1000, rng)
    new_states = ["healthy"] * 3 + ["f1", "f1", "f2", "f2"]
    new = records(new_states, [3.1, 4.4, 6.9, 2.8, 7.3, 3.6, 6.2], 4000, 1000, rng)
    return xr.concat([fit, _with_ids(new, 18)], dim="record")


@pytest.fixture(scope="module")
def fp_baselines(fleet):
    return tsfdi.fit_baselines(fleet, k="speed", fit_records=list(range(18)), settle=5.0, duration=None,
                               max_lags=4, var_max_lags=4, steady_window="5s", calibrate=True)


def test_fit_baselines_with_k_fits_one_fp_model_per_state(fleet, fp_baselines):
    """Every model of every state is an FP model over its fitting records at their logged speeds, order and degree
    chosen by BIC as select_fp_order chooses them on the same segments; the held-out residuals are the FP ones
    (each record at its own speed through the FP fit without it); Baselines.table describes them."""
    b = fp_baselines
    assert b.fit_records == tuple(range(18))
    for m in ("var", "y0", "y1"):
        for state in ("healthy", "f1", "f2"):
            res = b.models[m][state]
            assert isinstance(res, FPResults) and res.model.k_names == ["speed"]
            np.testing.assert_array_equal(res.model.k[:, 0], [LOW, 5.0, HIGH] * 2)
            segs = b.segments[state]
            y = segs if m == "var" else [g[:, b.channels.index(m)] for g in segs]
            sel = select_fp_order(y, pd.DataFrame({"speed": res.model.k[:, 0]}), 4, 2, "var" if m == "var" else "ar")
            assert b.selections[(m, state)].selected == sel.selected
            assert (res.model.na, res.model.degree[0]) == sel.selected
            np.testing.assert_allclose(res.params2d, sel.fit().params2d, rtol=1e-10, atol=1e-12)
            held = res.model.held_out_residuals()
            for e, h in zip(b.heldout[(m, state)], held):
                np.testing.assert_allclose(e, np.asarray(h).reshape(e.shape), rtol=1e-10, atol=1e-12)
    # the simulated systems are VAR(2) linear in the speed: BIC finds order 2, degree 1
    assert b.selections[("var", "healthy")].selected == (2, 1)
    t = b.table.set_index(["state", "model", "signals"])
    row = t.loc[("healthy", "VAR", "y0,y1")]
    assert row["order"] == "FP-VAR(2) degree 1" and row["lags"] == 2 and row["records"] == 6
    assert row["spp"] == pytest.approx(row["nobs"] * 2 / row["parameters"]) and np.isnan(row["rss_sss"])
    assert bool(row["stable"])


def test_fp_baselines_at_one_k_equal_point_baselines_of_at_k(fleet, fp_baselines):
    """Records all at one speed: FP baselines evaluated at each record's logged speed give the tables of the point
    baselines made of every FP model .at(that speed) -- windows, delays, coverage and calibration -- with a
    theoretical and a calibrated test (both calibrated on the FP null, the same held-out residuals). The coverage
    check, on the FP null too, warns of the records relabelled away from the speed they were flown at."""
    k0 = 4.4
    at = fleet.isel(record=slice(18, None)).assign_coords(speed=("record", np.full(7, k0)))
    point = dataclasses.replace(fp_baselines, models={m: {s: r.at(k0) for s, r in per.items()}
                                                      for m, per in fp_baselines.models.items()}, _calibrated={})
    opts = dict(models=("var", "y0"), windows=("2s", "5s"), settle=5.0, progress=False,
                tests={"whiteness": LjungBox(lags=10, alpha=0.01), "variance": FTest(alpha=0.01),
                       "calibrated": LjungBox(lags=10, alpha=0.01, threshold="calibrated")})
    # the records flown at 3.1 and 6.9 m/s and filtered at 4.4 lie outside the fitting records' spread: both warn
    with pytest.warns(CoverageWarning, match=r"records 18, 20\)"):
        ev = tsfdi.evaluate(at, fp_baselines, k="speed", **opts)
    with pytest.warns(CoverageWarning, match=r"records 18, 20\)"):
        ref = tsfdi.evaluate(at, point, **opts)
    for name in ("identification_counts", "detection_counts", "detection_delays", "records"):
        pd.testing.assert_frame_equal(getattr(ev, name), getattr(ref, name), check_exact=True)
    pd.testing.assert_frame_equal(ev.calibration, ref.calibration, rtol=1e-10)
    pd.testing.assert_frame_equal(ev.coverage, ref.coverage, rtol=1e-10)
    assert ev.identification_counts["windows"].sum() > 0 and ev.detection_counts["windows"].sum() > 0


def test_evaluate_at_each_records_k_in_memory_and_on_dask(fleet, fp_baselines):
    """Records at their own speeds: in memory and chunked on dask (the speeds travel with each chunk's labels) the
    tables are equal, and so are the FP baselines fitted on the chunked fleet; the FP baselines identify the faults
    at speeds between the fitting ones."""
    opts = dict(models=("var",), windows=("5s",), settle=5.0, progress=False, k="speed",
                rules=("paper", "likelihood", "sprt"),
                tests={"whiteness": LjungBox(lags=10, alpha=0.01, threshold="calibrated")})
    ev = tsfdi.evaluate(fleet, fp_baselines, **opts)
    lazy = tsfdi.evaluate(fleet.chunk(record=4), fp_baselines, **opts)
    # the FP baselines of the fleet on dask (only the fitting records read, with their speeds) are the same
    fitted = tsfdi.fit_baselines(fleet.chunk(record=4), k="speed", fit_records=list(range(18)), settle=5.0,
                                 duration=None, max_lags=4, var_max_lags=4, steady_window="5s", models=("var",))
    for s, r in fitted.models["var"].items():
        np.testing.assert_array_equal(r.params2d, fp_baselines.models["var"][s].params2d)
        np.testing.assert_array_equal(r.model.k, fp_baselines.models["var"][s].model.k)
    for name in ("identification_counts", "detection_counts", "detection_delays", "records", "coverage",
                 "calibration", "sequential_counts"):
        pd.testing.assert_frame_equal(getattr(lazy, name), getattr(ev, name))
    assert lazy.sprt == ev.sprt and 0 < ev.sprt["scale"][("", "var")] <= 1.5
    assert ev.records["evaluated"].sum() == 7
    rates = ev.rates().xs(("var", "whiteness", 5.0), level=("model", "method", "window"))
    assert (rates.xs("likelihood", level="rule")["correct"] == 100).all()
    assert (ev.sequential_rates()["correct"] == 100).all()


def test_fp_baselines_without_k_and_bad_k_are_refused_by_name(fleet, fp_baselines, synthetic, fitted):
    """FP baselines without k=: a TypeError naming k= (and .at(k)); k naming a missing coordinate, a coordinate the
    FP models do not have, non-numeric or non-finite values, or given for point baselines / a sequence of signals:
    ValueError / TypeError naming k and the coordinate."""
    opts = dict(windows=("5s",), settle=5.0, progress=False)
    with pytest.raises(TypeError, match=r"^baselines.models\['var'\]\['healthy'\] is a functionally pooled model "
                                        r"\(FPResults\) over \['speed'\]: give k= .*\.at\(k\)"):
        tsfdi.evaluate(fleet, fp_baselines, **opts)
    with pytest.raises(ValueError, match=r"k: data has no record coordinate 'weight' \(its record coordinates: "
                                         r"\['state', 'failure_time', 'speed'\]\)"):
        tsfdi.evaluate(fleet, fp_baselines, k="weight", **opts)
    two = fleet.assign_coords(weight=("record", np.ones(fleet.sizes["record"])))
    with pytest.raises(ValueError, match=r"k names the record coordinates \['speed', 'weight'\], but "
                                         r"baselines.models\['var'\]\['healthy'\] .* over \['speed'\]: 'weight' is "
                                         r"not one of its operating parameters"):
        tsfdi.evaluate(two, fp_baselines, k=["speed", "weight"], **opts)
    with pytest.raises(ValueError, match=r"k names the record coordinates \['weight'\], .*: 'weight' is not one of "
                                         r"its operating parameters"):
        tsfdi.evaluate(two, fp_baselines, k="weight", **opts)
    with pytest.raises(TypeError, match=r"k: the coordinate 'state' of data must hold numbers"):
        tsfdi.evaluate(fleet, fp_baselines, k="state", **opts)
    gap = fleet.assign_coords(speed=("record", np.r_[fleet["speed"].values[:-1], np.nan]))
    with pytest.raises(ValueError, match=r"k: the coordinate 'speed' of data is not finite for record 24"):
        tsfdi.evaluate(gap, fp_baselines, k="speed", **opts)
    with pytest.raises(ValueError, match=r"k names a coordinate twice"):
        tsfdi.evaluate(fleet, fp_baselines, k=["speed", "speed"], **opts)
    with pytest.raises(TypeError, match=r"k must name record coordinates"):
        tsfdi.evaluate(fleet, fp_baselines, k=3.0, **opts)
    recs, states, ft = synthetic
    with pytest.raises(ValueError, match=r"k names record coordinates \['speed'\], but data is a sequence of "
                                         r"signals"):
        tsfdi.evaluate(recs, fitted, states=states, failure_times=ft, fs=FS, k="speed", **opts)
    point = fleet.assign_coords(speed=("record", np.full(fleet.sizes["record"], 5.0)))
    with pytest.raises(ValueError, match=r"k names operating parameters \['speed'\], but the baselines' models "
                                         r"\['var'\] are point models"):
        tsfdi.evaluate(point, dataclasses.replace(fp_baselines, models={
            m: {s: r.at(5.0) for s, r in per.items()} for m, per in fp_baselines.models.items()}), k="speed", **opts)


def test_fit_baselines_with_k_refuses_what_it_cannot_fit(fleet):
    """fit_records at one operating point, order='rss_sss', max_degree without k or beyond the points: refused
    naming what is needed."""
    kw = dict(settle=5.0, duration=None, max_lags=4, var_max_lags=4, steady_window="5s", models=("var",))
    with pytest.raises(ValueError, match=r"k: the fitting records of state 'healthy' \(\[0\]\) all have speed = 2; a "
                                         r"functionally pooled baseline needs fitting records at several operating "
                                         r"points .*fit_records='all'"):
        tsfdi.fit_baselines(fleet, k="speed", **kw)
    with pytest.raises(ValueError, match=r"order='rss_sss' .* with k .* give order='bic' or an int"):
        tsfdi.fit_baselines(fleet, k="speed", fit_records="all", order="rss_sss", **kw)
    with pytest.raises(ValueError, match=r"max_degree is the largest basis degree .* give k="):
        tsfdi.fit_baselines(fleet, fit_records="all", max_degree=1, **kw)
    two = list(range(0, 18, 3)) + list(range(1, 18, 3))         # speeds 2 and 5 only
    with pytest.raises(ValueError, match=r"max_degree=2 needs at least 3 distinct values .* state 'healthy' hold 2 "
                                         r"of 'speed'"):
        tsfdi.fit_baselines(fleet, k="speed", fit_records=two, max_degree=2, **kw)
    b = tsfdi.fit_baselines(fleet, k="speed", fit_records=two, order=3, **kw)       # default: degree up to 1
    assert all(r.model.na == 3 and r.model.degree[0] <= 1 for r in b.models["var"].values())


def test_false_alarms_at_logged_k_between_the_fitting_points_hold_alpha():
    """Monte Carlo (fixed seed): 120 healthy records at speeds drawn between the fitting points (2, 5, 8 m/s, 3
    records each), each tested by the FP baselines at its logged speed: the disjoint 5 s windows' false alarms of
    the Ljung-Box test lie in the two-sided 99 % binomial band of alpha (0.05 and 0.01); the test calibrated on the
    FP null is not liberal (with 9 healthy fitting records its record law is conservative, as the point models'
    with few records, issue 31). The same records tested at a wrong speed (mirrored in the envelope), or all at the
    centre's point model, are flagged above the band: the test can fail."""
    rng = np.random.default_rng(3202)
    fit_states = [s for s in SYSTEMS for _ in range(9)]
    fit = records(fit_states, [LOW, 5.0, HIGH] * 9, 4000, 1000, rng)
    speeds = rng.uniform(LOW, HIGH, 120)
    new = _with_ids(records(["healthy"] * 120, speeds, 4000, None, rng), 27)
    data = xr.concat([fit, new], dim="record")
    b = tsfdi.fit_baselines(data, k="speed", fit_records=list(range(27)), settle=5.0, duration=None, max_lags=4,
                            var_max_lags=4, steady_window="5s", calibrate=True, models=("var",))
    tests = {"a05": LjungBox(lags=10, alpha=0.05), "a01": LjungBox(lags=10, alpha=0.01),
             "calibrated": LjungBox(lags=10, alpha=0.05, threshold="calibrated")}
    opts = dict(models=("var",), windows=("5s",), settle=5.0, progress=False, tests=tests)
    rates = tsfdi.evaluate(data, b, k="speed", **opts).detection_rates().xs(("var", 5.0), level=("model", "window"))
    assert (rates["disjoint_windows"] == 120 * 8).all()
    assert rates.loc["a05", "false_alarm_in_band"] and rates.loc["a01", "false_alarm_in_band"], rates
    assert rates.loc["calibrated", "disjoint_alarms"] <= rates.loc["calibrated", "disjoint_band_high"]
    mirrored = np.where(data["record"] >= 27, HIGH + LOW - data["speed"], data["speed"])
    with pytest.warns(CoverageWarning):
        wrong = tsfdi.evaluate(data.assign_coords(speed=("record", mirrored)), b, k="speed", **opts)
    point = dataclasses.replace(b, models={"var": {s: r.at(5.0) for s, r in b.models["var"].items()}}, _calibrated={})
    with pytest.warns(CoverageWarning):
        centre = tsfdi.evaluate(data, point, **opts)
    for ev in (wrong, centre):
        row = ev.detection_rates().loc[("var", "a05", 5.0)]
        assert row["disjoint_alarms"] > row["disjoint_band_high"], row


def test_baselines_methods_take_the_operating_point(fleet, fp_baselines):
    """state_models / monitor / covers at an operating point (a mapping name -> value) give the FP models .at(k);
    without it covers names k; select_alpha filters every fitting record at its own logged speed (through the other
    states' FP models too): the held-out windows are identified as the evaluation records are."""
    b = fp_baselines
    at = b.state_models("var", k={"speed": 3.1})
    for s, r in at.items():
        np.testing.assert_array_equal(r.params, b.models["var"][s].at(3.1).params)
    with pytest.raises(ValueError, match=r"k lacks the operating parameter\(s\) \['speed'\] of the functionally "
                                         r"pooled model 'var' of state 'healthy'"):
        b.state_models("var", k={"weight": 1.0})
    new = fleet.isel(record=18).transpose("time", "channel").values         # healthy, flown at 3.1 m/s
    with pytest.raises(TypeError, match=r"model 'var' of state 'healthy' is functionally pooled: give the record's "
                                        r"operating point, k=\{'speed': \.\.\.\}"):
        b.covers(new)
    cov = b.covers(new, k={"speed": 3.1})
    ref = tsfdi.coverage.coverage(b.models["var"]["healthy"].at(3.1), new, held_out=b.heldout[("var", "healthy")])
    assert cov.covered and cov.pvalue == pytest.approx(ref.pvalue, rel=1e-12)
    fault = fleet.isel(record=22).transpose("time", "channel").values       # f1 from 10 s, flown at 7.3 m/s
    with pytest.warns(CoverageWarning, match=r"Monitor.run: the record lies outside"):      # its fault part
        out = b.monitor("var", window="5s", k={"speed": 7.3}).run(fault)
    assert out.label == "f1" and 10.0 < out.detection_time < 16.0
    table = b.select_alpha("var", window="5s", alphas=(1e-3, 1e-5))
    # 21 windows (5 s, 1 s apart) of the 25 s after settle in each of the 6 fitting records of the 2 fault states
    assert table["correct"].min() > 99 and (table["windows"] == 2 * 6 * 21).all()


def test_hexacopter_fleet_at_several_speeds_end_to_end():
    """evaluate(ds, fit_baselines(ds, k="speed", ...), k="speed") on a hexacopter Dataset simulated at three speeds
    (healthy and rotor 1 failing; two fitting records per state and speed) and tested at two speeds between them:
    the FP baselines are fitted, calibrated on their held-out null and every record is evaluated at its speed."""
    from tsfdi.datasets import simulate_hexacopter

    parts = [simulate_hexacopter(4, duration=30.0, speed=v, turbulence="light", failed_rotor=[0, 0, 1, 1],
                                 failure_time=10.0, seed=[10 * j + 1, 10 * j + 2, 10 * j + 3, 10 * j + 4], fs=50.0)
             for j, v in enumerate([2.0, 5.0, 8.0])]
    parts += [simulate_hexacopter(2, duration=30.0, speed=v, turbulence="light", failed_rotor=[0, 1],
                                  failure_time=10.0, seed=[100 + j, 110 + j], fs=50.0)
              for j, v in enumerate([3.5, 6.5])]
    ds = xr.concat(parts, dim="record")
    ds = ds.assign_coords(record=np.arange(ds.sizes["record"]))
    b = tsfdi.fit_baselines(ds, k="speed", fit_records=list(range(12)), models=("var",), settle=5.0, duration=None,
                            var_max_lags=6, calibrate=True)
    assert all(isinstance(r, FPResults) and r.model.k_names == ["speed"] for r in b.models["var"].values())
    ev = tsfdi.evaluate(ds, b, k="speed", windows=("5s",), settle=5.0, progress=False,
                        tests={"whiteness": LjungBox(lags=10, alpha=0.01, threshold="empirical")})
    assert ev.records["evaluated"].tolist() == [False] * 12 + [True] * 4
    assert ev.identification_counts["windows"].sum() > 0 and ev.detection_counts["windows"].sum() > 0
    assert ev.rates().xs("likelihood", level="rule")["correct"].min() == 100
    assert ev.detection_rates()["missed_records"].sum() == 0
    with pytest.raises(TypeError, match=r"give k= naming"):
        tsfdi.evaluate(ds, b, windows=("5s",), settle=5.0, progress=False)


def test_calibrating_a_reference_variance_on_point_weights_is_refused(fp_baselines):
    """An FP model fitted with weights='point' has a noise variance that changes with k: a calibrated test carrying
    one reference variance (FTest) is refused naming the model, state and the way out; Ljung-Box is calibrated."""
    b = fp_baselines
    res = b.models["var"]["healthy"]
    point = tsfdi.models.FPVAR(b.segments["healthy"], pd.DataFrame({"speed": res.model.k[:, 0]}), res.model.na,
                               res.model.degree, weights="point").fit()
    mixed = dataclasses.replace(b, models={**b.models, "var": {**b.models["var"], "healthy": point}}, _calibrated={})
    with pytest.raises(ValueError, match=r"FTest carries the reference variance .* model 'var' of state 'healthy' has "
                                         r"weights='point' .* refit it with weights='pooled', or use LjungBox"):
        mixed.calibrated_tests("var", FTest(alpha=0.01, threshold="empirical"), "5s")
    calibrated = mixed.calibrated_tests("var", LjungBox(lags=10, alpha=0.01, threshold="empirical"), "5s")
    assert calibrated["healthy"].calibrated

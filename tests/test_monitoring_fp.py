"""Monitor with functionally pooled baselines (issue 32): a Monitor of FP models filters each stream at its logged
operating point (run / update with k={...}), screen(records, k="speed") each record at its own, in memory and on
dask; the sequential rule's scale of FP baselines is that of the operating point where it is smallest."""

from __future__ import annotations

from contextlib import nullcontext

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy import stats
from test_evaluation_fp import HIGH, LOW, _with_ids, records

import tsfdi
from tsfdi import SPRT, LjungBox
from tsfdi.detection.sequential import msprt_scale
from tsfdi.exceptions import CoverageWarning
from tsfdi.windows import ResidualWindows

STATES = ["healthy", "f1", "f2"]


@pytest.fixture(scope="module")
def fleet():
    """Fitting records: 2 per state at each of the speeds 2, 5, 8 (40 s, failure at 10 s); new records: 3 healthy and
    2 per fault state at speeds between the fitting ones (those of tests/test_evaluation_fp.py)."""
    rng = np.random.default_rng(3201)
    fit = records([s for s in STATES for _ in range(6)], [LOW, 5.0, HIGH] * 6, 4000, 1000, rng)
    new = records(["healthy"] * 3 + ["f1", "f1", "f2", "f2"], [3.1, 4.4, 6.9, 2.8, 7.3, 3.6, 6.2], 4000, 1000, rng)
    return xr.concat([fit, _with_ids(new, 18)], dim="record")


@pytest.fixture(scope="module")
def fp_baselines(fleet):
    return tsfdi.fit_baselines(fleet, k="speed", fit_records=list(range(18)), settle=5.0, duration=None,
                               max_lags=4, var_max_lags=4, steady_window="5s", calibrate=True, models=("var",))


def _new(fleet):
    return fleet.isel(record=slice(18, None))


CALIBRATED = dict(window="5s", test=LjungBox(lags=10, alpha=0.01, threshold="calibrated"))


def test_fp_monitor_at_one_k_equals_the_point_monitor_of_at_k(fleet, fp_baselines):
    """Baselines.monitor() of FP baselines holds the FP models; run(record, k={...}) gives the events, windows and
    coverage of the point monitor of every model .at(k) (Baselines.monitor(k=...)), with a calibrated test (on the
    FP null) and with the sequential rule; update in blocks (k with the first) gives those of run."""
    b = fp_baselines
    fp = b.monitor("var", **CALIBRATED)
    assert isinstance(fp.baseline, tsfdi.FPResults) and fp.k_names == ("speed",)
    assert "functionally pooled over ['speed']" in repr(fp)
    for rec in (22, 23, 18):                                # f1 at 7.3, f2 at 3.6, healthy at 3.1 m/s
        x = fleet.isel(record=rec).transpose("time", "channel")
        v = float(fleet["speed"][rec])
        point = b.monitor("var", k={"speed": v}, **CALIBRATED)
        with pytest.warns(CoverageWarning) if rec != 18 else nullcontext():
            got = fp.run(x, k={"speed": v})
        with pytest.warns(CoverageWarning) if rec != 18 else nullcontext():
            ref = point.run(x)
        assert got.events == ref.events and len(got.events) > (1 if rec != 18 else -1)
        pd.testing.assert_frame_equal(got.windows, ref.windows)
        assert got.label == ref.label and got.coverage.warning_message() == ref.coverage.warning_message()
        pd.testing.assert_frame_equal(got.coverage.table, ref.coverage.table)
        fp.reset()
        events = fp.update(x.isel(time=slice(0, 1500)), k={"speed": v}) + fp.update(x.isel(time=slice(1500, None)))
        assert events == ref.events
    # the sequential rule: FP models at k against their point models at k
    models = b.state_models("var")
    v = 7.3
    x = fleet.isel(record=22).transpose("time", "channel")
    seq = tsfdi.Monitor(models["healthy"], {f: models[f] for f in b.faults}, rule="sprt", sprt_scale=0.5,
                        steady_window="5s", detection_test=SPRT("variance", ratio=2.0, alpha=0.01, restart=True))
    at = tsfdi.Monitor(models["healthy"].at(v), {f: models[f].at(v) for f in b.faults}, rule="sprt", sprt_scale=0.5,
                       steady_window="5s", detection_test=SPRT("variance", ratio=2.0, alpha=0.01, restart=True))
    got, ref = seq.run(x, k={"speed": v}), at.run(x)
    assert got.events == ref.events and got.identification_time is not None and got.label == "f1"
    pd.testing.assert_frame_equal(got.windows, ref.windows)


def test_screen_at_each_records_k_in_memory_and_on_dask(fleet, fp_baselines):
    """screen(records, k="speed") monitors every record at its logged speed: each row is run(record, k={speed}); the
    table of the chunked fleet (the speeds read on the driver, sent with each chunk) is the one in memory, and the
    faults are detected and identified at speeds between the fitting ones."""
    fp = fp_baselines.monitor("var", **CALIBRATED)
    new = _new(fleet)
    with pytest.warns(CoverageWarning, match=r"4 of 7 records"):           # the fault records' fault parts
        table = fp.screen(new, k="speed")
    with pytest.warns(CoverageWarning, match=r"4 of 7 records"):
        lazy = fp.screen(new.chunk(record=3), k="speed")
    pd.testing.assert_frame_equal(lazy, table)
    assert table["speed"].tolist() == new["speed"].values.tolist()
    for i, rec in enumerate(new["record"].values):
        x = new.sel(record=rec).transpose("time", "channel")
        with pytest.warns(CoverageWarning) if new["state"].values[i] != "healthy" else nullcontext():
            res = fp.run(x, k={"speed": float(new["speed"][i])})
        assert table.loc[rec, "fault_windows"] == res.windows["fault"].sum()
        assert table.loc[rec, "label"] == res.label
        np.testing.assert_equal(table.loc[rec, "detection_time"],
                                np.nan if res.detection_time is None else res.detection_time)
    faults = table[table["state"] != "healthy"]
    assert (faults["label"] == faults["state"]).all()
    assert ((faults["detection_time"] > 10.0) & (faults["detection_time"] < 16.0)).all()


def test_fp_monitor_refuses_bad_k_by_name(fleet, fp_baselines):
    """k missing for FP models or given for point models (TypeError naming k); an operating point without one of the
    parameters, with another, not finite, or changed within a stream; screen's k naming other coordinates than the
    models' parameters, a coordinate the records lack, non-numeric or non-finite values (naming the record), or
    given with a sequence of signals: ValueError / TypeError naming k; FP models over different parameters
    refused."""
    b = fp_baselines
    fp = b.monitor("var", **CALIBRATED)
    point = b.monitor("var", k={"speed": 5.0}, **CALIBRATED)
    x = fleet.isel(record=18).transpose("time", "channel")
    with pytest.raises(TypeError, match=r"k is required: the monitor's models are functionally pooled over "
                                        r"\['speed'\]; give the stream's operating point, k=\{'speed': \.\.\.\}"):
        fp.run(x)
    with pytest.raises(TypeError, match=r"k is the operating point of functionally pooled models .* leave k out"):
        point.run(x, k={"speed": 5.0})
    with pytest.raises(TypeError, match=r"k must be a mapping operating parameter -> value"):
        fp.run(x, k=5.0)
    with pytest.raises(ValueError, match=r"k must give exactly the models' operating parameters \['speed'\], got "
                                         r"\['weight'\] \(missing \['speed'\]\)"):
        fp.run(x, k={"weight": 1.0})
    with pytest.raises(ValueError, match=r"got \['speed', 'weight'\] \(\['weight'\] not among them\)"):
        fp.run(x, k={"speed": 5.0, "weight": 1.0})
    with pytest.raises(ValueError, match=r"k\['speed'\] must be finite"):
        fp.run(x, k={"speed": np.nan})
    with pytest.raises(TypeError, match=r"k\['speed'\] must be a real number"):
        fp.run(x, k={"speed": "fast"})
    fp.reset()
    fp.update(x.isel(time=slice(0, 600)), k={"speed": 3.1})
    fp.update(x.isel(time=slice(600, 900)), k={"speed": 3.1})
    with pytest.raises(ValueError, match=r"k: the stream is monitored at \{'speed': 3.1\}, got \{'speed': 4.0\}: a "
                                         r"stream has one operating point; reset\(\)"):
        fp.update(x.isel(time=slice(900, 1200)), k={"speed": 4.0})
    new = _new(fleet)
    with pytest.raises(TypeError, match=r"the monitor's models are functionally pooled over \['speed'\]: give k= "
                                        r"naming the record coordinate"):
        fp.screen(new)
    with pytest.raises(TypeError, match=r"k names operating parameters \['speed'\], but the monitor's models are "
                                        r"point models"):
        point.screen(new, k="speed")
    two = new.assign_coords(weight=("record", np.ones(7)))
    with pytest.raises(ValueError, match=r"k names the record coordinates \['speed', 'weight'\], but the monitor's "
                                         r"models are functionally pooled over \['speed'\]: 'weight' is not one of "
                                         r"their operating parameters"):
        fp.screen(two, k=["speed", "weight"])
    with pytest.raises(ValueError, match=r"k names the record coordinates \['weight'\], .*: 'weight' is not one of "
                                         r"their operating parameters"):
        fp.screen(two, k="weight")
    with pytest.raises(ValueError, match=r"k: records has no record coordinate 'speed' \(its record coordinates: "
                                         r"\['state', 'failure_time'\]\)"):
        fp.screen(new.drop_vars("speed"), k="speed")
    with pytest.raises(TypeError, match=r"k: the coordinate 'speed' of records must hold numbers"):
        fp.screen(new.assign_coords(speed=("record", ["a"] * 7)), k="speed")
    gap = new.assign_coords(speed=("record", np.r_[new["speed"].values[:-1], np.nan]))
    with pytest.raises(ValueError, match=r"k: the coordinate 'speed' of records is not finite for record 24"):
        fp.screen(gap, k="speed")
    with pytest.raises(ValueError, match=r"k: the coordinate 'speed' of records is not finite for record 24"):
        fp.screen(gap.chunk(record=3), k="speed")
    with pytest.raises(ValueError, match=r"k names record coordinates \['speed'\], but records is a sequence of "
                                         r"signals"):
        fp.screen([x.values], k="speed")
    with pytest.raises(TypeError, match=r"k must name record coordinates"):
        fp.screen(new, k=3.0)
    res = b.models["var"]["healthy"]
    other = tsfdi.models.FPVAR(b.segments["f1"], pd.DataFrame({"weight": res.model.k[:, 0]}), 2, degree=1).fit()
    with pytest.raises(ValueError, match=r"baseline is functionally pooled over \['speed'\] but models\['f1'\] over "
                                         r"\['weight'\]"):
        tsfdi.Monitor(res, {"f1": other, "f2": b.models["var"]["f2"]}, window="5s")


def test_sprt_scale_of_fp_baselines_is_the_smallest_over_the_operating_points(fleet, fp_baselines):
    """The sequential rule's scale of FP baselines: msprt_scale of the held-out fitting records of each operating
    point (every fault model at that point), the smallest over the points; not that of all the points' records
    joined, whose different drifts count as autocorrelation (0.033 here, against 0.085 / 0.165 / 0.83 at 2 / 5 / 8
    m/s)."""
    b = fp_baselines
    fp = b.models["var"]
    per: dict = {}
    for j, f in enumerate(b.faults):
        for i, seg in enumerate(b.segments[f]):
            v = float(fp[f].model.k[i, 0])
            at = {g: fp[g].at(v) for g in b.faults}
            given = {g: b.heldout[("var", f)][i] if g == f else at[g].residuals(seg) for g in b.faults}
            lls, labels = per.setdefault(v, ([], []))
            lls.append(ResidualWindows(at).fit_residuals(given, seg.shape[0]).loglik())
            labels.append(j)
    scales = {v: msprt_scale(*ll) for v, ll in per.items()}
    joined = msprt_scale([a for ll, _ in per.values() for a in ll], [j for _, lab in per.values() for j in lab])
    assert sorted(scales) == [LOW, 5.0, HIGH] and joined < 0.5 * min(scales.values())
    ev = tsfdi.evaluate(fleet, b, k="speed", windows=("5s",), settle=5.0, rules=("sprt",), detection=False,
                        progress=False)
    assert ev.sprt["scale"][("", "var")] == min(scales.values())
    assert (ev.sequential_rates()["correct"] == 100).all()


def test_screen_false_alarms_at_logged_k_between_the_fitting_points_hold_alpha():
    """Monte Carlo (fixed seed): an FP-VAR healthy baseline on 9 records at 2, 5, 8 m/s; 120 healthy records at
    speeds drawn between them, screened at their logged speeds with disjoint 5 s windows: the windows flagged by
    the Ljung-Box test (alpha 0.05, 0.01) lie in the two-sided 99 % binomial band of alpha. The same records
    screened at a wrong speed (mirrored in the envelope) are flagged above the band: the test can fail."""
    rng = np.random.default_rng(3203)
    fit = records(["healthy"] * 9, [LOW, 5.0, HIGH] * 3, 4000, None, rng)
    fp = tsfdi.models.FPVAR(list(fit.transpose("record", "time", "channel").values),
                            pd.DataFrame({"speed": fit["speed"].values}), 2, degree=1).fit()
    speeds = rng.uniform(LOW, HIGH, 120)
    new = records(["healthy"] * 120, speeds, 4000, None, rng)
    for alpha in (0.05, 0.01):
        monitor = tsfdi.Monitor(fp, window="5s", step="5s", test=LjungBox(lags=10, alpha=alpha))
        table = monitor.screen(new, k="speed")
        assert (table["windows"] == 8).all()
        lo, hi = stats.binom.interval(0.99, 960, alpha)
        assert lo <= table["fault_windows"].sum() <= hi, (alpha, table["fault_windows"].sum(), lo, hi)
    wrong = new.assign_coords(speed=("record", HIGH + LOW - speeds))
    with pytest.warns(CoverageWarning):
        flagged = monitor.screen(wrong, k="speed")["fault_windows"].sum()
    assert flagged > hi, flagged


def test_baselines_monitor_of_fp_baselines_keeps_the_fp_models(fp_baselines):
    """Baselines.monitor without k gives a monitor of the FP models (screen / run take k); with k the point models
    at it, as before."""
    b = fp_baselines
    fp = b.monitor("var", window="5s")
    assert fp.baseline is b.models["var"]["healthy"] and fp.models == {f: b.models["var"][f] for f in b.faults}
    point = b.monitor("var", window="5s", k={"speed": 4.0})
    assert point.k_names == () and not isinstance(point.baseline, tsfdi.FPResults)

"""``--threshold calibrated`` of ``tsfdi detect / identify / monitor``: every model's test calibrated on the held-out
residuals of the records stored in its file, exactly as the library does it."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from _synthetic_fdi import FS, record

import tsfdi
from tsfdi.cli import main
from tsfdi.identification import identify_windows

WINDOW = 200                 # samples: the "2s" of the commands below at FS = 100 Hz


def _csv(x: np.ndarray, path, t0: float = 0.0) -> None:
    pd.DataFrame({"time": t0 + np.arange(x.shape[0]) / FS, "a": x[:, 0], "b": x[:, 1]}).to_csv(path, index=False)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Models of the healthy, f1 and f2 states fitted by ``tsfdi fit`` on one 80 s record each, and a record that
    is healthy for 20 s, then f2."""
    d = tmp_path_factory.mktemp("calibrated")
    rng = np.random.default_rng(5)
    paths = {}
    for s in ("healthy", "f1", "f2"):
        _csv(record(s, 8000, rng), d / f"{s}.csv")
        paths[s] = d / f"{s}.npz"
        assert main(["fit", str(d / f"{s}.csv"), "--out", str(paths[s]), "--max-lags", "6"]) == 0
    x = record("f2", 4000, rng, failure=2000)
    _csv(x, d / "current.csv", t0=50.0)
    return d, paths, x


def _tests(paths, names, alpha=1e-2, **kw):
    return {n: tsfdi.LjungBox(lags=20, alpha=alpha).calibrate(tsfdi.load(paths[n]).model.held_out_residuals(),
                                                            window=WINDOW, **kw) for n in names}


def test_detect_calibrated_is_the_library_calibration(files, capsys):
    d, paths, x = files
    common = ["detect", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--window", "2s", "--step",
              "1s", "--alpha", "0.01"]
    assert main(common + ["--threshold", "calibrated", "--out", str(d / "cal.csv")]) == 0
    assert main(common + ["--out", str(d / "theo.csv")]) == 0
    capsys.readouterr()
    cal, theo = pd.read_csv(d / "cal.csv"), pd.read_csv(d / "theo.csv")
    test = _tests(paths, ["healthy"])["healthy"]
    for j, c in enumerate(("a", "b")):
        np.testing.assert_allclose(cal[f"threshold_{c}"], test.threshold_[j], rtol=1e-12)
        assert (theo[f"threshold_{c}"] != cal[f"threshold_{c}"]).all()
    ws = tsfdi.ResidualWindows({"baseline": tsfdi.load(paths["healthy"])}).fit(x).statistics(
        test, window=WINDOW, step=100)
    np.testing.assert_array_equal(cal["fault"], ws.reject[:, 0])
    np.testing.assert_allclose(cal["pvalue_a"], ws.pvalue[:, 0, 0], rtol=1e-9)
    # healthy for 20 s, f2 after: the windows inside the f2 part are flagged
    assert cal["fault"][cal["start"] >= 70.0].all()


@pytest.mark.parametrize("method, test", [("variance", tsfdi.FTest), ("mean", tsfdi.MeanTest)])
def test_detect_other_methods_calibrated(files, capsys, method, test):
    """--method variance / mean: the library's FTest / MeanTest, calibrated the same way."""
    d, paths, x = files
    out = d / f"{method}.csv"
    assert main(["detect", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--window", "2s", "--step",
                 "1s", "--alpha", "0.01", "--method", method, "--threshold", "calibrated", "--out", str(out)]) == 0
    capsys.readouterr()
    t = pd.read_csv(out)
    baseline = tsfdi.load(paths["healthy"])
    ref = test(alpha=0.01).calibrate(baseline.model.held_out_residuals(), window=WINDOW)
    ws = tsfdi.ResidualWindows({"baseline": baseline}).fit(x).statistics(ref, window=WINDOW, step=100)
    for j, c in enumerate(("a", "b")):
        np.testing.assert_allclose(t[f"threshold_{c}"], ref.threshold_[j], rtol=1e-12)
        np.testing.assert_allclose(t[f"statistic_{c}"], ws.statistic[:, 0, j], rtol=1e-9)
    np.testing.assert_array_equal(t["fault"], ws.reject[:, 0])


@pytest.mark.parametrize("threshold", ["theoretical", "calibrated"])
def test_detect_combined_method(files, capsys, threshold):
    """--method whiteness+variance+mean: the library's AnyOf of the three tests sharing --alpha by Sidak (each
    model's copy calibrated as AnyOf.calibrated_for does with --threshold calibrated)."""
    d, paths, x = files
    out = d / f"any_{threshold}.csv"
    assert main(["detect", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--window", "2s", "--step",
                 "1s", "--alpha", "0.01", "--method", "whiteness+variance+mean", "--threshold", threshold,
                 "--out", str(out)]) == 0
    capsys.readouterr()
    t = pd.read_csv(out)
    baseline = tsfdi.load(paths["healthy"])
    kw = {} if threshold == "theoretical" else {"threshold": "calibrated"}
    ref = tsfdi.AnyOf([tsfdi.LjungBox(20, alpha=0.01, **kw), tsfdi.FTest(alpha=0.01, **kw),
                       tsfdi.MeanTest(alpha=0.01, **kw)])
    if threshold == "calibrated":
        ref.calibrate(baseline.model.held_out_residuals(), window=WINDOW)
    ws = tsfdi.ResidualWindows({"baseline": baseline}).fit(x).statistics(ref, window=WINDOW, step=100)
    for j, c in enumerate(("a", "b")):
        np.testing.assert_allclose(t[f"statistic_{c}"], ws.statistic[:, 0, j], rtol=1e-9)
        np.testing.assert_allclose(t[f"pvalue_{c}"], ws.pvalue[:, 0, j], rtol=1e-9)
    np.testing.assert_array_equal(t["fault"], ws.reject[:, 0])
    assert t["fault"][t["start"] >= 70.0].all()
    for bad, message in (("whiteness+bogus", "'bogus' is none of them"), ("mean+mean", "each test once")):
        assert main(["detect", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--window", "2s",
                     "--method", bad]) == 2
        assert message in capsys.readouterr().err


def test_min_windows(files, tmp_path, capsys):
    """--min-windows lowers the support a calibration needs (the library's ScaledChi2Threshold(min_windows=))."""
    d, paths, x = files
    _csv(record("healthy", 4000, np.random.default_rng(2)), tmp_path / "short.csv")
    assert main(["fit", str(tmp_path / "short.csv"), "--out", str(tmp_path / "short.npz"), "--max-lags", "4"]) == 0
    capsys.readouterr()
    common = ["detect", str(d / "current.csv"), "--baseline", str(tmp_path / "short.npz"), "--window", "2s",
              "--alpha", "0.01", "--out", str(tmp_path / "t.csv")]
    assert main(common + ["--threshold", "calibrated"]) == 2          # 20 windows < 30
    assert main(common + ["--threshold", "calibrated", "--min-windows", "20"]) == 0
    capsys.readouterr()
    res = tsfdi.load(tmp_path / "short.npz")
    ref = tsfdi.LjungBox(lags=20, alpha=0.01, threshold=tsfdi.ScaledChi2Threshold(0.01, min_windows=20))
    ref.calibrate(res.model.held_out_residuals(), window=WINDOW)
    np.testing.assert_allclose(pd.read_csv(tmp_path / "t.csv")["threshold_a"], ref.threshold_[0], rtol=1e-12)
    for extra, message in ((["--threshold", "calibrated", "--min-windows", "4"], "--min-windows must be at least 5"),
                           (["--min-windows", "20"], "--min-windows is for --threshold calibrated")):
        assert main(common + extra) == 2
        assert message in capsys.readouterr().err


def test_identify_calibrated_per_model(files, capsys):
    d, paths, x = files
    out = d / "ident.csv"
    assert main(["identify", str(d / "current.csv"), "--models", f"f1={paths['f1']}", f"f2={paths['f2']}",
                 "--window", "2s", "--step", "1s", "--alpha", "0.01", "--threshold", "calibrated", "--rule", "pvalue",
                 "--out", str(out)]) == 0
    capsys.readouterr()
    t = pd.read_csv(out, keep_default_na=False)
    models = {n: tsfdi.load(paths[n]) for n in ("f1", "f2")}
    wins = identify_windows(x, models, _tests(paths, ["f1", "f2"]), window=WINDOW, step=100)
    for j, n in enumerate(("f1", "f2")):
        np.testing.assert_allclose(t[f"pvalue_{n}"], wins.windows.min_pvalue[:, j], rtol=1e-9)
        np.testing.assert_array_equal(t[f"accept_{n}"], wins.accepted[:, j])
    assert t["label"].tolist() == [lab or "" for lab in wins.decide("pvalue")]
    assert (t["label"][t["start"] >= 70.0] == "f2").all()


def test_monitor_calibrated(files, capsys):
    d, paths, x = files
    out = d / "events.csv"
    assert main(["monitor", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--models",
                 f"f1={paths['f1']}", f"f2={paths['f2']}", "--window", "2s", "--step", "1s", "--alpha", "0.001",
                 "--lags", "20", "--threshold", "calibrated", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    # alpha 0.001: at 0.01 per channel, two channels and 19 overlapping healthy windows (about 10 independent) give
    # a false alarm before the failure in about one run in five
    tests = _tests(paths, ["healthy", "f1", "f2"], alpha=1e-3)
    ref = tsfdi.Monitor(tsfdi.load(paths["healthy"]), {n: tsfdi.load(paths[n]) for n in ("f1", "f2")},
                        window=WINDOW, step=100, fs=FS, detection_test=tests.pop("healthy"), test=tests,
                        steady_window="10s").run(x)
    assert f"detection at {50.0 + ref.detection_time:g} s, label {ref.label}" in printed
    assert ref.label == "f2" and 70.0 <= 50.0 + ref.detection_time <= 73.0
    events = pd.read_csv(out)
    assert len(events) == len(ref.to_frame())


def test_calibrated_errors(files, tmp_path, capsys):
    d, paths, x = files
    assert main(["detect", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--threshold",
                 "calibrated"]) == 2
    assert "--threshold calibrated needs --window" in capsys.readouterr().err
    # a model fitted on one 40 s record: held out in 10 blocks of 4 s, 20 non-overlapping 2 s windows, too few
    _csv(record("healthy", 4000, np.random.default_rng(2)), tmp_path / "short.csv")
    assert main(["fit", str(tmp_path / "short.csv"), "--out", str(tmp_path / "short.npz"), "--max-lags", "4"]) == 0
    capsys.readouterr()
    assert main(["detect", str(d / "current.csv"), "--baseline", str(tmp_path / "short.npz"), "--window", "2s",
                 "--threshold", "calibrated"]) == 2
    err = capsys.readouterr().err
    assert f"--threshold calibrated, --baseline {tmp_path / 'short.npz'}: " in err
    assert "holds 20 independent" in err and "at least 30 are needed" in err
    assert "1 record(s), 4000 samples" in err
    # --min-records: only with --threshold calibrated, at least 2
    common = ["detect", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--window", "2s"]
    assert main(common + ["--min-records", "3"]) == 2
    assert "--min-records is for --threshold calibrated" in capsys.readouterr().err
    assert main(common + ["--threshold", "calibrated", "--min-records", "1"]) == 2
    assert "--min-records must be at least 2, got 1" in capsys.readouterr().err


def test_min_records_reaches_the_threshold(files, tmp_path, capsys):
    """--min-records is the calibrated threshold's min_records: a baseline of 2 records is refused at alpha 0.01
    (the predictive law needs 3) and accepted with --min-records 2, with the library's threshold."""
    d, paths, x = files
    rng = np.random.default_rng(11)
    for i in range(2):
        _csv(record("healthy", 4000, rng), tmp_path / f"two{i}.csv")
    assert main(["fit", str(tmp_path / "two0.csv"), str(tmp_path / "two1.csv"), "--out", str(tmp_path / "two.npz"),
                 "--max-lags", "4"]) == 0
    capsys.readouterr()
    common = ["detect", str(d / "current.csv"), "--baseline", str(tmp_path / "two.npz"), "--window", "2s",
              "--step", "1s", "--alpha", "0.01", "--threshold", "calibrated", "--min-windows", "5"]
    assert main(common) == 2
    assert "at least 3 are needed" in capsys.readouterr().err
    assert main(common + ["--min-records", "2", "--out", str(tmp_path / "two.csv")]) == 0
    res = tsfdi.load(tmp_path / "two.npz")
    test = tsfdi.LjungBox(lags=20, alpha=0.01, threshold=tsfdi.ScaledChi2Threshold(0.01, min_windows=5,
                                                                                   min_records=2))
    test = test.calibrated_for({"b": res}, window=WINDOW)["b"]
    out = pd.read_csv(tmp_path / "two.csv")
    np.testing.assert_allclose(out["threshold_a"], test.threshold_[0], rtol=1e-12)


def test_calibrated_for_is_one_calibration_per_model(files, tmp_path):
    """LjungBox(...).calibrated_for(models, window=...): per model, a copy of the test calibrated on that model's
    held-out residuals (what --threshold calibrated uses); the test itself stays uncalibrated."""
    d, paths, x = files
    models = {n: tsfdi.load(paths[n]) for n in ("f1", "f2")}
    test = tsfdi.LjungBox(lags=20, alpha=1e-2)
    tests = test.calibrated_for(models, window=WINDOW)
    ref = _tests(paths, ["f1", "f2"])
    assert list(tests) == ["f1", "f2"] and not test.calibrated
    for n in ("f1", "f2"):
        np.testing.assert_array_equal(tests[n].threshold_, ref[n].threshold_)
    wins = identify_windows(x, models, tests, window=WINDOW, step=100)
    np.testing.assert_array_equal(wins.accepted, identify_windows(x, models, ref, window=WINDOW, step=100).accepted)
    # too few held-out windows: the model is named with the size of its null sample and the fix
    _csv(record("healthy", 4000, np.random.default_rng(2)), tmp_path / "short.csv")
    short = tsfdi.VAR(pd.read_csv(tmp_path / "short.csv").set_index("time"), 4).fit()
    with pytest.raises(ValueError, match=r"models\['short'\]: .*at least 30 are needed.*1 record\(s\), 4000 samples"
                                         r".*cut into 10 blocks.*more or longer healthy records"):
        test.calibrated_for({"short": short}, window=WINDOW)
    with pytest.raises(TypeError, match=r"models\['x'\] must be fitted results"):
        test.calibrated_for({"x": x}, window=WINDOW)
    with pytest.raises(TypeError, match="models must be a mapping"):
        test.calibrated_for([models["f1"]], window=WINDOW)


def test_px4_healthy_continuation(shared_px4, tmp_path, capsys):
    """The example of docs/guide/cli.md: a gyroscope VAR fitted on 12-50 s of the PX4 sample log (lying still,
    three records between logging gaps); the rest of the log (50-68 s, still) tested on 1 s windows at alpha 0.03
    (the decision's rate, each channel at about 1 %): the chi-square thresholds flag 4 of 17 windows (the two-sided
    99 % binomial band of 17 windows at 3 % ends at 3), the calibrated ones none."""
    log = shared_px4 / "sample.ulg"
    data = [str(log), "--topics", "sensor_combined", "--fs", "50", "--columns",
            ",".join(f"sensor_combined.gyro_rad[{i}]" for i in range(3))]
    model = tmp_path / "gyro.npz"
    assert main(["fit", *data, "--start", "12s", "--stop", "50s", "--out", str(model)]) == 0
    found = {}
    for threshold in ("theoretical", "calibrated"):
        capsys.readouterr()
        assert main(["detect", *data, "--start", "50s", "--stop", "68s", "--baseline", str(model), "--window", "1s",
                     "--alpha", "0.03", "--threshold", threshold]) == 0
        found[threshold] = capsys.readouterr().out.strip().splitlines()[-1]
    assert found == {"theoretical": "fault in 4 of 17 window(s)", "calibrated": "fault in 0 of 17 window(s)"}


def test_px4_rows_where(shared_px4, tmp_path, capsys):
    """--rows-where on a flight log: a condition every row meets changes nothing; --margin trims each record (the
    log's pieces between logging gaps) at both ends; a column of the topics that is not a channel can be used."""
    log = shared_px4 / "sample.ulg"
    data = [str(log), "--topics", "sensor_combined", "--fs", "50", "--columns",
            ",".join(f"sensor_combined.gyro_rad[{i}]" for i in range(3)), "--lags", "2", "--max-lags", "2"]
    fitted = {}
    for name, extra in (("all", []), ("true", ["--rows-where", "sensor_combined.accelerometer_m_s2[2]>-1000"]),
                        ("margin", ["--rows-where", "sensor_combined.accelerometer_m_s2[2]>-1000", "--margin",
                                    "1s"])):
        assert main(["fit", *data, *extra, "--out", str(tmp_path / f"{name}.npz")]) == 0
        fitted[name] = capsys.readouterr().out.splitlines()[0]
    assert fitted["true"] == fitted["all"]
    records = int(fitted["all"].split(" record(s)")[0].split()[-1])
    rows = [int(fitted[k].split("(")[-1].split(" samples")[0]) for k in ("all", "margin")]
    assert rows[0] - rows[1] == records * 2 * 50               # 1 s at 50 Hz off both ends of every record


def test_detect_warns_when_the_baseline_does_not_cover_a_record(tmp_path, capsys):
    """A baseline fitted on several records (>= tsfdi.coverage.MIN_RECORDS): detect warns, naming the file and the
    baseline, about a record outside their spread (here three times the noise), and is silent about one like them;
    a baseline of one record cannot say and says nothing."""
    rng = np.random.default_rng(21)
    fits = []
    for i in range(5):
        _csv(record("healthy", 3000, rng), tmp_path / f"h{i}.csv")
        fits.append(str(tmp_path / f"h{i}.csv"))
    assert main(["fit", *fits, "--out", str(tmp_path / "base.npz"), "--max-lags", "4"]) == 0
    _csv(record("healthy", 3000, rng), tmp_path / "like.csv")
    _csv(3.0 * record("healthy", 3000, rng), tmp_path / "noisy.csv")
    capsys.readouterr()
    assert main(["detect", str(tmp_path / "like.csv"), str(tmp_path / "noisy.csv"), "--baseline",
                 str(tmp_path / "base.npz")]) == 0
    err = capsys.readouterr().err
    assert err.count("warning:") == 1 and "noisy.csv" in err and "like.csv" not in err
    assert f"against --baseline {tmp_path / 'base.npz'}" in err and "outside the spread" in err
    assert main(["fit", fits[0], "--out", str(tmp_path / "one.npz"), "--max-lags", "4"]) == 0
    capsys.readouterr()
    assert main(["detect", str(tmp_path / "noisy.csv"), "--baseline", str(tmp_path / "one.npz")]) == 0
    assert "outside the spread" not in capsys.readouterr().err
    # monitor (issue 31): Monitor.run's check, said once per record naming the file, not the library's "Monitor.run"
    assert main(["monitor", str(tmp_path / "like.csv"), str(tmp_path / "noisy.csv"), "--baseline",
                 str(tmp_path / "base.npz"), "--window", "2s"]) == 0
    err = capsys.readouterr().err
    assert err.count("warning:") == 1 and "noisy.csv" in err and "like.csv" not in err and "Monitor.run" not in err
    assert f"against --baseline {tmp_path / 'base.npz'}" in err and "outside the spread" in err

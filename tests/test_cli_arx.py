"""Controller-aware models on the command line (issue 32): ``--u COL[,COL...]`` fits an ARX of one output (a VARX of
several) given the input columns (``fit``) and gives ``detect`` / ``identify`` / ``monitor`` the input of ARX / VARX
models, exactly as the library does with ``u=``."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import scipy.signal as sps

import tsfdi
from tsfdi.cli import main
from tsfdi.windows import ResidualWindows

FS = 100.0


def _flight(gain: float, n: int, rng, failure: int | None = None) -> pd.DataFrame:
    """A rate ``gyro`` driven by two commands; the first command's effectiveness is ``gain`` (from ``failure``)."""
    u = rng.standard_normal((n, 2))
    g = np.ones(n)
    g[(0 if failure is None else failure):] = gain
    y = (sps.lfilter([0.6, 0.3], [1, -0.5], g * u[:, 0]) + sps.lfilter([0, 0.5], [1, -0.5], u[:, 1])
         + 0.1 * rng.standard_normal(n))
    other = rng.standard_normal(n)
    # a second rate, for the VARX (several outputs): coupled to the first, driven by cmd_b (no new draws: the
    # flights of the ARX tests are unchanged)
    rate2 = sps.lfilter([0, 0.5], [1, -0.3], u[:, 1]) + 0.3 * np.r_[0.0, y[:-1]] + 0.1 * other
    return pd.DataFrame({"time": np.arange(n) / FS, "gyro": y, "cmd_a": u[:, 0], "cmd_b": u[:, 1],
                         "other": other, "rate2": rate2})


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("arx")
    rng = np.random.default_rng(2032)
    out = {}
    for name, gain, failure in (("healthy", 1.0, None), ("loss", 0.5, None), ("new", 0.5, 1000)):
        out[name] = folder / f"{name}.csv"
        _flight(gain, 3000, rng, failure).to_csv(out[name], index=False)
    for name in ("healthy", "loss"):
        out[f"{name}.npz"] = folder / f"{name}.npz"
        assert main(["fit", str(out[name]), "--columns", "gyro", "--u", "cmd_a,cmd_b", "--lags", "2",
                     "--max-lags", "4", "--out", str(out[f"{name}.npz"]), "--quiet"]) == 0
    out["folder"] = folder
    return out


def _frame(path) -> pd.DataFrame:
    return pd.read_csv(path).set_index("time")


@pytest.mark.filterwarnings("ignore::tsfdi.exceptions.ConvergenceWarning")   # max_lags 4 at the BIC bound
def test_fit_is_the_library_arx(files, capsys):
    f = _frame(files["healthy"])
    res = tsfdi.load(files["healthy.npz"])
    ref = tsfdi.select_order(f["gyro"], 4, "arx", u=f[["cmd_a", "cmd_b"]]).fit(2)
    np.testing.assert_allclose(np.asarray(res.params), np.asarray(ref.params), rtol=1e-10)
    assert list(res.model.u_data.channels) == ["cmd_a", "cmd_b"] and res.model.nk == 0
    assert main(["fit", str(files["healthy"]), "--columns", "gyro", "--u", "cmd_a,cmd_b", "--nk", "1", "--lags", "2",
                 "--max-lags", "4", "--out", str(files["folder"] / "nk1.npz"), "--quiet"]) == 0
    assert "ARX(2, 2, nk=1) of ['gyro'] given --u ['cmd_a', 'cmd_b']" in capsys.readouterr().out
    nk1 = tsfdi.load(files["folder"] / "nk1.npz")
    ref = tsfdi.select_order(f["gyro"], 4, "arx", u=f[["cmd_a", "cmd_b"]], nk=1).fit(2)
    np.testing.assert_allclose(np.asarray(nk1.params), np.asarray(ref.params), rtol=1e-10)


def test_detect_and_identify_are_the_library_with_u(files, tmp_path):
    f = _frame(files["new"])
    y, u = f["gyro"], f[["cmd_a", "cmd_b"]]
    models = {n: tsfdi.load(files[f"{n}.npz"]) for n in ("healthy", "loss")}
    out = tmp_path / "detect.csv"
    # --u defaults to the inputs the model was fitted with
    assert main(["detect", str(files["new"]), "--baseline", str(files["healthy.npz"]), "--window", "2s", "--step",
                 "1s", "--method", "variance", "--out", str(out)]) == 0
    got = pd.read_csv(out)
    ws = ResidualWindows({"h": models["healthy"]}).fit(y, u=u).statistics(tsfdi.FTest(1e-3), window=200, step=100)
    np.testing.assert_allclose(got["statistic_gyro"], ws.statistic[:, 0, 0], rtol=1e-6)
    assert not got["fault"].iloc[:8].any() and got["fault"].iloc[10:].all()
    # identify: --u in another order, matched by name
    out = tmp_path / "identify.csv"
    assert main(["identify", str(files["new"]), "--models", f"healthy={files['healthy.npz']}",
                 f"loss={files['loss.npz']}", "--u", "cmd_b,cmd_a", "--window", "2s", "--step", "1s", "--method",
                 "variance", "--out", str(out)]) == 0
    got = pd.read_csv(out)
    wi = tsfdi.identify_windows(y, models, tsfdi.FTest(1e-3), window=200, step=100, u=u)
    assert got["label"].fillna("").tolist() == [lab or "" for lab in wi.labels]
    assert got["label"].iloc[0] == "healthy" and got["label"].iloc[-1] == "loss"
    # the whole record as one window: detect(y, baseline, u=)
    out = tmp_path / "whole.csv"
    assert main(["detect", str(files["new"]), "--baseline", str(files["healthy.npz"]), "--method", "variance",
                 "--out", str(out)]) == 0
    d = tsfdi.detect(y, models["healthy"], tsfdi.FTest(1e-3), u=u)
    np.testing.assert_allclose(pd.read_csv(out)["statistic_gyro"], d.statistic, rtol=1e-6)


@pytest.mark.filterwarnings("ignore::tsfdi.exceptions.ConvergenceWarning")   # max_lags 4 at the BIC bound
def test_select_order_and_sequential_identify(files, tmp_path):
    f = _frame(files["new"])
    out = tmp_path / "orders.csv"
    assert main(["select-order", str(files["healthy"]), "--columns", "gyro", "--u", "cmd_a,cmd_b", "--max-lags", "4",
                 "--out", str(out)]) == 0
    h = _frame(files["healthy"])
    ref = tsfdi.select_order(h["gyro"], 4, "arx", u=h[["cmd_a", "cmd_b"]])
    np.testing.assert_allclose(pd.read_csv(out)["bic"], np.asarray(ref.table["bic"]), rtol=1e-9)
    out = tmp_path / "sprt.csv"
    assert main(["identify", str(files["new"]), "--models", f"healthy={files['healthy.npz']}",
                 f"loss={files['loss.npz']}", "--rule", "sprt", "--out", str(out)]) == 0
    models = {n: tsfdi.load(files[f"{n}.npz"]) for n in ("healthy", "loss")}
    from tsfdi.detection.sequential import msprt

    seq = msprt(ResidualWindows(models).fit(f["gyro"], u=f[["cmd_a", "cmd_b"]]).loglik(), alpha=0.01,
                models=list(models))
    got = pd.read_csv(out)
    assert got["label"].iloc[0] == seq.name == "healthy"           # decided within the healthy first 10 s
    assert got["decision_time"].iloc[0] == pytest.approx(f.index[2 + seq.decision_time - 1])


@pytest.mark.parametrize("rule", ["paper", "sprt"])
def test_monitor_is_the_library_with_u(files, tmp_path, rule):
    f = _frame(files["new"])
    models = {n: tsfdi.load(files[f"{n}.npz"]) for n in ("healthy", "loss")}
    out = tmp_path / "monitor.csv"
    flags = ["--window", "5s", "--method", "variance"] if rule == "paper" else ["--rule", "sprt"]
    assert main(["monitor", str(files["new"]), "--baseline", str(files["healthy.npz"]), "--models",
                 f"loss={files['loss.npz']}", f"healthy={files['healthy.npz']}", "--steady-window", "5s",
                 *flags, "--out", str(out)]) == 0
    kw = dict(window=500, step=100, test=tsfdi.FTest(1e-3)) if rule == "paper" else dict(rule="sprt")
    lib = tsfdi.Monitor(models["healthy"], {"loss": models["loss"], "healthy": models["healthy"]}, fs=FS,
                        steady_window=500, **kw).run(f["gyro"], u=f[["cmd_a", "cmd_b"]])
    got = pd.read_csv(out)
    np.testing.assert_allclose(got["time"], lib.to_frame()["time"])
    assert got["kind"].tolist() == lib.to_frame()["kind"].tolist()
    assert 10.0 < lib.detection_time <= 13.0 and lib.label == "loss"


@pytest.mark.filterwarnings("ignore::tsfdi.exceptions.ConvergenceWarning")   # max_lags 4 at the BIC bound
def test_several_outputs_with_u_fit_a_varx(files, tmp_path, capsys):
    """``fit --columns gyro,rate2 --u cmd_a,cmd_b`` fits the library's VARX (order by BIC on the common sample of
    ``select_order(..., "varx")``), ``select-order`` tabulates it, and ``detect`` / ``identify`` test it with the
    input columns it was fitted with."""
    outs = ["gyro", "rate2"]
    paths = {}
    for name in ("healthy", "loss"):
        paths[name] = tmp_path / f"{name}_varx.npz"
        assert main(["fit", str(files[name]), "--columns", ",".join(outs), "--u", "cmd_a,cmd_b", "--max-lags", "4",
                     "--out", str(paths[name]), "--quiet"]) == 0
    assert "VARX(" in capsys.readouterr().out
    h = _frame(files["healthy"])
    sel = tsfdi.select_order(h[outs], 4, "varx", u=h[["cmd_a", "cmd_b"]])
    res = tsfdi.load(paths["healthy"])
    assert type(res) is tsfdi.models.VARXResults and res.lags == sel.selected
    np.testing.assert_allclose(np.asarray(res.params), np.asarray(sel.fit().params), rtol=1e-10)
    table = tmp_path / "orders.csv"
    assert main(["select-order", str(files["healthy"]), "--columns", ",".join(outs), "--u", "cmd_a,cmd_b",
                 "--max-lags", "4", "--out", str(table)]) == 0
    np.testing.assert_allclose(pd.read_csv(table)["bic"], np.asarray(sel.table["bic"]), rtol=1e-9)
    f = _frame(files["new"])
    y, u = f[outs], f[["cmd_a", "cmd_b"]]
    models = {n: tsfdi.load(paths[n]) for n in ("healthy", "loss")}
    out = tmp_path / "detect.csv"
    assert main(["detect", str(files["new"]), "--columns", ",".join(outs), "--baseline", str(paths["healthy"]),
                 "--window", "2s", "--step", "1s", "--method", "variance", "--out", str(out)]) == 0
    ws = ResidualWindows({"h": models["healthy"]}).fit(y, u=u).statistics(tsfdi.FTest(1e-3), window=200, step=100)
    got = pd.read_csv(out)
    np.testing.assert_allclose(got[["statistic_gyro", "statistic_rate2"]], ws.statistic[:, 0, :], rtol=1e-6)
    assert not got["fault"].iloc[:8].any() and got["fault"].iloc[10:].all()
    out = tmp_path / "identify.csv"
    assert main(["identify", str(files["new"]), "--columns", ",".join(outs), "--models",
                 f"healthy={paths['healthy']}", f"loss={paths['loss']}", "--window", "2s", "--step", "1s",
                 "--method", "variance", "--out", str(out)]) == 0
    wi = tsfdi.identify_windows(y, models, tsfdi.FTest(1e-3), window=200, step=100, u=u)
    got = pd.read_csv(out)
    assert got["label"].fillna("").tolist() == [lab or "" for lab in wi.labels]
    assert got["label"].iloc[0] == "healthy" and got["label"].iloc[-1] == "loss"


def test_errors_name_the_flag_file_and_column(files, capsys):
    new, healthy = str(files["new"]), str(files["healthy.npz"])
    ar = str(files["folder"] / "ar.npz")
    assert main(["fit", str(files["healthy"]), "--columns", "gyro", "--lags", "2", "--out", ar, "--quiet"]) == 0
    capsys.readouterr()
    cases = [
        (["detect", new, "--baseline", healthy, "--u", "cmd_a,cmd_x"],
         "--u cmd_a,cmd_x: --baseline " + healthy + " was fitted with the inputs ['cmd_a', 'cmd_b']; missing "
         "['cmd_b']; not an input: ['cmd_x']"),
        (["detect", new, "--baseline", ar, "--u", "cmd_a"],
         f"--u cmd_a: --baseline {ar} has no input (AR / VAR); leave --u out"),
        (["identify", new, "--models", f"a={ar}", f"b={healthy}"],
         "--models b is an ARX (input-output) model and --models a an AR / VAR model"),
        (["fit", new, "--columns", "gyro", "--u", "cmd_a,cmd_x", "--out", ar],
         f"--u: {new} has no column 'cmd_x'"),
        (["fit", new, "--u", "cmd_a,cmd_b", "--k", "g=1", "--out", ar],
         "--u with --k: a functionally pooled input-output model (FP-ARX) has one output, but the data gives 3 "
         "other column(s) ['gyro', 'other', 'rate2']"),
        (["fit", new, "--columns", "gyro,cmd_a", "--u", "cmd_a,cmd_b", "--out", ar],
         "--u cmd_a: the column is also an output (--columns gyro,cmd_a)"),
        (["fit", new, "--columns", "gyro", "--nk", "1", "--out", ar],
         "--nk 1 is the input delay of an ARX / VARX model: give its inputs with --u"),
        (["fit", new, "--columns", "gyro", "--u", "cmd_a,cmd_a", "--out", ar],
         "must name each column once, 'cmd_a' is given twice"),
        (["fit", new, "--columns", "gyro", "--u", "cmd_a", "--model", "ar", "--out", ar],
         "--model ar: with --u the model is an ARX"),
    ]
    for argv, said in cases:
        assert main(argv) == 2, argv
        err = " ".join(capsys.readouterr().err.split())
        assert " ".join(said.split()) in err, (argv, err)
    # a column missing from a file being tested (the model's input): the file and the column are named
    frame = pd.read_csv(files["new"]).drop(columns="cmd_b")
    bad = files["folder"] / "no_cmd_b.csv"
    frame.to_csv(bad, index=False)
    assert main(["detect", str(bad), "--baseline", healthy]) == 2
    assert f"--u: {bad} has no column 'cmd_b'" in capsys.readouterr().err


def test_fit_with_k_is_the_library_fparx(files, capsys):
    """``fit --k --u``: an FP-ARX over the files' operating points; detect tests a record at a logged ``--k`` and at
    its ``--k estimate`` (FPResults.estimate_k given the input)."""
    out = files["folder"] / "fparx.npz"
    fit = [str(files["healthy"]), str(files["loss"])]
    assert main(["fit", *fit, "--columns", "gyro", "--u", "cmd_a,cmd_b", "--k", "gain=1,0.5", "--lags", "2",
                 "--degree", "1", "--out", str(out), "--quiet"]) == 0
    assert "FP-ARX(2, 2, nk=0), degree 1 (given)" in capsys.readouterr().out
    frames = [_frame(p) for p in fit]
    ref = tsfdi.models.FPARX([f["gyro"] for f in frames], [f[["cmd_a", "cmd_b"]] for f in frames],
                             pd.DataFrame({"gain": [1.0, 0.5]}), 2, 2, 0, 1).fit()
    res = tsfdi.load(out)
    np.testing.assert_allclose(np.asarray(res.params), np.asarray(ref.params), rtol=1e-10)
    new = str(files["new"])
    table = files["folder"] / "fparx.csv"
    assert main(["detect", new, "--baseline", str(out), "--k", "gain=0.5", "--method", "variance", "--out",
                 str(table)]) == 0
    f = _frame(files["new"])
    d = tsfdi.detect(f["gyro"], ref.at(0.5), tsfdi.FTest(1e-3), u=f[["cmd_a", "cmd_b"]])
    np.testing.assert_allclose(pd.read_csv(table)["statistic_gyro"], d.statistic, rtol=1e-9)
    capsys.readouterr()
    assert main(["detect", new, "--baseline", str(out), "--k", "estimate", "--method", "variance"]) == 0
    est = ref.estimate_k(f["gyro"], f[["cmd_a", "cmd_b"]])
    assert f"estimated gain = {est.k_hat[0]:.6g}" in capsys.readouterr().out


def test_an_input_copying_the_output_is_refused(files, capsys):
    frame = pd.read_csv(files["healthy"]).assign(copy=lambda f: f["gyro"])
    path = files["folder"] / "copy.csv"
    frame.to_csv(path, index=False)
    assert main(["fit", str(path), "--columns", "gyro", "--u", "copy,cmd_b", "--max-lags", "3", "--out",
                 str(files["folder"] / "copy.npz")]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "exactly" in err and "Choose the channels with --columns and --u" in err

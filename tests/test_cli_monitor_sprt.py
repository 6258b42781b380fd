"""``tsfdi monitor --rule sprt``: the sequential monitor end to end, from CSV files and saved models (issue 33)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from _synthetic_fdi import FS, record

import tsfdi
from tsfdi import SPRT
from tsfdi.cli import main


def _csv(x, path, t0=0.0):
    t = t0 + np.arange(x.shape[0]) / FS
    pd.DataFrame({"time": t, "a": x[:, 0], "b": x[:, 1]}).to_csv(path, index=False)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("sprt")
    rng = np.random.default_rng(31)
    paths = {}
    for s in ("healthy", "f1", "f2"):
        _csv(record(s, 6000, rng), d / f"{s}.csv")
        paths[s] = d / f"{s}.npz"
        assert main(["fit", str(d / f"{s}.csv"), "--out", str(paths[s]), "--max-lags", "4"]) == 0
    x = record("f2", 3000, np.random.default_rng(12), failure=1000)      # the failure at 10 s of the record
    _csv(x, d / "current.csv", t0=50.0)
    return d, paths, x


def test_monitor_sprt_end_to_end(files, capsys):
    d, paths, x = files
    capsys.readouterr()
    out = d / "events.csv"
    assert main(["monitor", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--models",
                 f"f1={paths['f1']}", f"f2={paths['f2']}", "--rule", "sprt", "--sprt-alpha", "0.001",
                 "--steady-window", "5s", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    models = {n: tsfdi.load(paths[n]) for n in ("f1", "f2")}
    ref = tsfdi.Monitor(tsfdi.load(paths["healthy"]), models, rule="sprt", fs=FS, steady_window="5s",
                        detection_test=SPRT("variance", ratio=2.0, alpha=1e-3, beta=1e-3, restart=True),
                        sprt_alpha=1e-3).run(x)
    assert "sequential (SPRT, variance ratio 2, alpha 0.001), rows every 100 samples = 1 s, at 100 Hz" in printed
    assert ref.label == "f2" and 10.0 <= ref.detection_time < 12.0
    assert (f"detection at {50.0 + ref.detection_time:g} s, label f2 (decided at "
            f"{50.0 + ref.identification_time:g} s)") in printed
    events = pd.read_csv(out)
    assert list(events["kind"]) == ["detection", "steady", "identification"]
    np.testing.assert_allclose(events["time"], 50.0 + ref.to_frame()["time"])     # on the record's clock
    assert events["label"].iloc[-1] == "f2"


def test_monitor_sprt_detection_only_and_ratio(files, capsys):
    d, paths, x = files
    capsys.readouterr()
    for ratio in (1.5, 4.0):
        assert main(["monitor", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--rule", "sprt",
                     "--sprt-ratio", f"{ratio:g}", "--sprt-alpha", "0.001"]) == 0
        line = next(ln for ln in capsys.readouterr().out.splitlines() if "detection at" in ln)
        ref = tsfdi.Monitor(tsfdi.load(paths["healthy"]), rule="sprt", fs=FS, detection_test=SPRT(
            "variance", ratio=ratio, alpha=1e-3, beta=1e-3, restart=True)).run(x)
        assert f"detection at {50.0 + ref.detection_time:g} s, label -" in line
        assert 10.0 <= ref.detection_time < 12.0


@pytest.mark.parametrize("extra, message", [
    (["--window", "2s"], "--window does not apply to --rule sprt"),
    (["--threshold", "calibrated"], "--threshold calibrated does not apply to --rule sprt"),
    (["--sprt-ratio", "1"], "--sprt-ratio must differ from 1"),
    (["--sprt-alpha", "2"], "--sprt-alpha: must be strictly between 0 and 1"),
    (["--sprt-ratio", "-1"], "--sprt-ratio: must be > 0"),
])
def test_monitor_sprt_errors(files, capsys, extra, message):
    d, paths, _ = files
    capsys.readouterr()
    assert main(["monitor", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--rule", "sprt",
                 *extra]) == 2
    assert message in capsys.readouterr().err


def test_monitor_without_window_needs_sprt(files, capsys):
    d, paths, _ = files
    capsys.readouterr()
    assert main(["monitor", str(d / "current.csv"), "--baseline", str(paths["healthy"])]) == 2
    assert "--window is required (except with --rule sprt)" in capsys.readouterr().err
    assert main(["monitor", str(d / "current.csv"), "--baseline", str(paths["healthy"]), "--models",
                 f"f1={paths['f1']}", "--rule", "sprt"]) == 2
    assert "needs at least two" in capsys.readouterr().err

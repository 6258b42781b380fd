"""The ``tsfdi`` command: demo on a reduced subset of the shipped data, fit / identify round trips."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from _synthetic_fdi import FS, record

from tsfdi.cli import main


def test_demo_reduced(tmp_path, capsys):
    out = tmp_path / "demo"
    rc = main(["demo", "--out", str(out), "--records-per-case", "3", "--fit-records", "2", "--order", "bic",
               "--models", "var", "--windows", "20", "--methods", "whiteness", "--no-progress"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "Table 2 analogue" in text and "Table 4 analogue, 20 s windows, rule 'paper'" in text
    assert "Detection with the healthy model" in text
    report = (out / "report.md").read_text()
    assert "| turbulence | state | model |" in report
    assert "| 2 |" in report                     # two pooled fitting records per state and level
    figs = sorted(p.name for p in (out / "figures").glob("*.png"))
    assert "variance_evolution.png" in figs and "order_selection_var_healthy.png" in figs
    assert "confusion_var_whiteness_20s_paper.png" in figs
    assert any(f.startswith("identification_bars_var_") for f in figs)


def _write(x: np.ndarray, path, fmt: str):
    t = np.arange(x.shape[0]) / FS
    if fmt == "csv":
        pd.DataFrame({"time": t, "a": x[:, 0], "b": x[:, 1]}).to_csv(path, index=False)
    else:
        xr.Dataset({"a": ("time", x[:, 0]), "b": ("time", x[:, 1])}, coords={"time": t}).to_netcdf(
            path, engine="h5netcdf")


@pytest.mark.parametrize("fmt", ["csv", "nc"])
def test_fit_identify_round_trip(tmp_path, capsys, fmt):
    rng = np.random.default_rng(21)
    paths = {}
    for s in ("f1", "f2"):
        p = tmp_path / f"{s}.{fmt}"
        _write(record(s, 4000, rng), p, fmt)
        paths[s] = tmp_path / f"{s}.npz"
        assert main(["fit", str(p), "--out", str(paths[s]), "--max-lags", "6"]) == 0
        assert f"VAR(2) on ['a', 'b']" in capsys.readouterr().out
    # scalar fit of one column
    assert main(["fit", str(tmp_path / f"f1.{fmt}"), "--columns", "a", "--out", str(tmp_path / "a.npz"),
                 "--max-lags", "6"]) == 0
    assert "AR(" in capsys.readouterr().out
    cur = tmp_path / f"current.{fmt}"
    _write(record("f2", 3000, rng), cur, fmt)
    table = tmp_path / "ident.csv"
    rc = main(["identify", str(cur), "--models", f"f1={paths['f1']}", f"f2={paths['f2']}", "--window", "10",
               "--step", "2", "--out", str(table)])
    assert rc == 0
    t = pd.read_csv(table)
    assert len(t) == (30 - 10) // 2 + 1
    np.testing.assert_allclose(t["end"] - t["start"], 10.0)
    assert (t["label"] == "f2").mean() >= 0.9
    assert (~t["accept_f1"]).all()
    capsys.readouterr()


def test_cli_errors(tmp_path, capsys):
    assert main(["fit", str(tmp_path / "missing.csv"), "--out", str(tmp_path / "m.npz")]) == 2
    assert "does not exist" in capsys.readouterr().err
    p = tmp_path / "two.csv"
    _write(record("f1", 500, np.random.default_rng(1)), p, "csv")
    assert main(["fit", str(p), "--model", "ar", "--out", str(tmp_path / "m.npz")]) == 2
    assert "one column" in capsys.readouterr().err
    assert main(["fit", str(p), "--columns", "zz", "--out", str(tmp_path / "m.npz")]) == 2
    assert "lacks" in capsys.readouterr().err
    assert main(["identify", str(p), "--models", str(tmp_path / "nope.npz")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main([]) == 2
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "--help"])
    assert exc.value.code == 0


def test_fit_start_stop_are_times_on_the_record_clock(tmp_path, capsys):
    # a record whose clock starts at 100 s: --start 110 --stop 130 selects 20 s = 2000 samples, not an empty slice
    x = record("f1", 4000, np.random.default_rng(5))
    p = tmp_path / "late.csv"
    pd.DataFrame({"time": 100.0 + np.arange(x.shape[0]) / FS, "a": x[:, 0], "b": x[:, 1]}).to_csv(p, index=False)
    assert main(["fit", str(p), "--out", str(tmp_path / "m.npz"), "--lags", "2", "--start", "110",
                 "--stop", "130"]) == 0
    assert "(1980 samples)" in capsys.readouterr().out    # 2000 rows minus the max_lags=20 hold-back
    # a start before the first sample keeps the record from its beginning (no wrap to the end)
    assert main(["fit", str(p), "--out", str(tmp_path / "m.npz"), "--lags", "2", "--start", "0",
                 "--stop", "110"]) == 0
    assert "(980 samples)" in capsys.readouterr().out

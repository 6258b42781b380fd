"""The ``tsfdi`` command: demo on a reduced subset of the shipped data, fit / identify round trips."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from _synthetic_fdi import FS, record

import tsfdi
from tsfdi.cli import main
from tsfdi.identification import identify, identify_windows


def test_demo_reduced(tmp_path, capsys):
    out = tmp_path / "demo"
    rc = main(["demo", "--out", str(out), "--records-per-case", "3", "--fit-records", "2", "--order", "bic",
               "--models", "var", "--windows", "20s", "--methods", "whiteness", "--no-progress"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "Table 2 analogue" in text and "Table 4 analogue, 20 s windows, rule 'paper'" in text
    assert "Detection with the healthy model" in text
    report = (out / "report.md").read_text()
    assert "| turbulence | state | model |" in report
    assert "| 2 |" in report                     # two pooled fitting records per state and level
    # the numbers of the study on the shipped data (the blade-element aircraft of issue 30, seed 2024)
    assert "| light | rotor2 | VAR | roll,pitch,yaw_rate | VAR(8) | 72 | 2 | 7960 | 331.67 | 0.00402 | 21.94 | False |" \
        in report
    assert "| var | whiteness | 40.00/0.00/0.00 | 0.00/68.33/0.00 | 0.00/0.00/91.67 |" in report
    assert "| var | whiteness | 100.00/0.00/0.00 | 0.00/100.00/0.00 | 0.00/0.00/100.00 |" in report
    # the two-sided binomial p-value of 0 alarms in 9 disjoint windows at 0.3 %, its 99 % band 0-1, inside it
    assert "| var | whiteness | 20 | 11.382 | 0.3 | 123 | 9 | 0 | 1 | 0 | 1 | True | 7.778 | 0 | 10 | 10 |" in report
    ident = pd.read_csv(out / "identification_counts.csv.gz")
    assert ident["windows"].sum() == 180 and set(ident["window"]) == {20.0}
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
        assert "VAR(2) on ['a', 'b']" in capsys.readouterr().out
    # scalar fit of one column
    assert main(["fit", str(tmp_path / f"f1.{fmt}"), "--columns", "a", "--out", str(tmp_path / "a.npz"),
                 "--max-lags", "6"]) == 0
    assert "AR(" in capsys.readouterr().out
    cur = tmp_path / f"current.{fmt}"
    _write(record("f2", 3000, rng), cur, fmt)
    table = tmp_path / "ident.csv"
    rc = main(["identify", str(cur), "--models", f"f1={paths['f1']}", f"f2={paths['f2']}", "--window", "10s",
               "--step", "2s", "--out", str(table)])
    assert rc == 0
    t = pd.read_csv(table)
    assert len(t) == (30 - 10) // 2 + 1
    np.testing.assert_allclose(t["end"] - t["start"], 10.0)
    assert (t["label"] == "f2").mean() >= 0.9
    assert (~t["accept_f1"]).all()
    capsys.readouterr()


@pytest.fixture(scope="module")
def saved_models(tmp_path_factory):
    """Two VAR(2) models saved by ``tsfdi fit`` and a current f2 record (CSV with a time column from 100 s)."""
    d = tmp_path_factory.mktemp("identify")
    rng = np.random.default_rng(31)
    paths = {}
    for s in ("f1", "f2"):
        _write(record(s, 4000, rng), d / f"{s}.csv", "csv")
        paths[s] = d / f"{s}.npz"
        assert main(["fit", str(d / f"{s}.csv"), "--out", str(paths[s]), "--max-lags", "6"]) == 0
    x = record("f2", 3000, rng, failure=1000, healthy_state="f1")       # f1 for 10 s, then f2
    cur = d / "current.csv"
    pd.DataFrame({"time": 100.0 + np.arange(x.shape[0]) / FS, "a": x[:, 0], "b": x[:, 1]}).to_csv(cur, index=False)
    return d, paths, cur, x


@pytest.mark.parametrize("method", ["whiteness", "variance"])
@pytest.mark.parametrize("rule", ["paper", "likelihood", "pvalue"])
def test_identify_is_identify_windows(saved_models, capsys, method, rule):
    """`tsfdi identify` prints and writes identify_windows of the record: window times on the record's clock,
    smallest channel p-value and acceptance of every model, the paper's status and the rule's label."""
    d, paths, cur, x = saved_models
    out = d / f"ident_{method}_{rule}.csv"
    rc = main(["identify", str(cur), "--models", f"f1={paths['f1']}", str(paths["f2"]), "--window", "10s",
               "--step", "2s", "--method", method, "--rule", rule, "--alpha", "1e-3", "--lags", "15",
               "--out", str(out)])
    assert rc == 0
    printed = capsys.readouterr().out
    assert f"wrote {out}" in printed and "status" in printed
    t = pd.read_csv(out, keep_default_na=False)
    assert list(t.columns) == ["start", "end", "pvalue_f1", "accept_f1", "pvalue_f2", "accept_f2", "status", "label"]
    models = {"f1": tsfdi.load(paths["f1"]), "f2": tsfdi.load(paths["f2"])}   # name of a bare path: its stem
    test = tsfdi.LjungBox(lags=15, alpha=1e-3) if method == "whiteness" else tsfdi.FTest(alpha=1e-3)
    wins = identify_windows(x, models, test, window="10s", step="2s", fs=FS)
    assert len(t) == len(wins) == (30 - 10) // 2 + 1
    np.testing.assert_allclose(t["start"], 100.0 + wins.starts / FS, rtol=0, atol=1e-9)
    np.testing.assert_allclose(t["end"], 100.0 + wins.stops / FS, rtol=0, atol=1e-9)
    for j, n in enumerate(("f1", "f2")):
        np.testing.assert_array_equal(t[f"pvalue_{n}"], wins.windows.min_pvalue[:, j])     # CSV round trip exact
        np.testing.assert_array_equal(t[f"accept_{n}"], wins.accepted[:, j])
    assert t["status"].tolist() == wins.status
    assert t["label"].tolist() == [lab or "" for lab in wins.decide(rule)]
    # and identify_windows is identify on each window's slice of the record
    for w in (0, 5, len(wins) - 1):
        s0, s1 = int(wins.starts[w]), int(wins.stops[w])
        ref = identify(x[s0:s1], models, test)
        assert ref.status == t["status"][w]
        for n in ("f1", "f2"):
            assert bool(t[f"accept_{n}"][w]) == (n in ref.accepted)
            assert t[f"pvalue_{n}"][w] == pytest.approx(ref.decisions[n].pvalue.min(), rel=1e-6, abs=1e-300)
        if rule == "paper":
            assert t["label"][w] == (ref.label or "")
    if method == "whiteness":                   # f1 for 10 s then f2: the windows follow the record
        assert t["label"].iloc[0] in ("f1", "") and t["label"].iloc[-1] == "f2"


def test_identify_whole_record_by_default(saved_models, capsys):
    d, paths, cur, x = saved_models
    assert main(["identify", str(cur), "--models", f"f1={paths['f1']}", f"f2={paths['f2']}"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2 and lines[0].split()[:2] == ["start", "end"]          # header and one window
    models = {n: tsfdi.load(p) for n, p in paths.items()}
    ref = identify(x, models, tsfdi.LjungBox(lags=20, alpha=1e-3))
    assert lines[1].split()[:2] == ["100", "130"] and ref.status in lines[1]


def test_cli_errors(tmp_path, capsys):
    assert main(["fit", str(tmp_path / "missing.csv"), "--out", str(tmp_path / "m.npz")]) == 2
    assert "does not exist" in capsys.readouterr().err
    p = tmp_path / "two.csv"
    _write(record("f1", 500, np.random.default_rng(1)), p, "csv")
    assert main(["fit", str(p), "--model", "ar", "--out", str(tmp_path / "m.npz")]) == 2
    assert "one column" in capsys.readouterr().err
    assert main(["fit", str(p), "--columns", "zz", "--out", str(tmp_path / "m.npz")]) == 2
    assert "--columns: " + str(p) + " has no column 'zz'; its columns are ['a', 'b']" in capsys.readouterr().err
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
    assert main(["fit", str(p), "--out", str(tmp_path / "m.npz"), "--lags", "2", "--start", "110s",
                 "--stop", "130s"]) == 0
    assert "(1980 samples)" in capsys.readouterr().out    # 2000 rows minus the max_lags=20 hold-back
    # a start before the first sample keeps the record from its beginning (no wrap to the end)
    assert main(["fit", str(p), "--out", str(tmp_path / "m.npz"), "--lags", "2", "--start", "0s",
                 "--stop", "110s"]) == 0
    assert "(980 samples)" in capsys.readouterr().out


def test_short_selection_by_row_numbers_hints_at_seconds(tmp_path, capsys):
    """``--start 10 --stop 35`` are rows, not seconds: when the selection is then too short, the error says so."""
    _write(record("healthy", 4000, np.random.default_rng(3)), tmp_path / "f.csv", "csv")
    assert main(["fit", str(tmp_path / "f.csv"), "--start", "10", "--stop", "35", "--out", str(tmp_path / "m.npz")]) == 2
    err = capsys.readouterr().err
    assert "too short" in err
    assert "(--start 10 / --stop 35: a bare integer is a row number, not a time; write e.g. '10s' for seconds)" in err
    assert main(["fit", str(tmp_path / "f.csv"), "--start", "10s", "--stop", "35s", "--out", str(tmp_path / "m.npz"),
                 "--max-lags", "6"]) == 0


CRAZYPAD = "data/crazypad/controller/normal_flight/E8_log00.csv.gz"


def test_fit_refuses_an_exact_fit(tmp_path, capsys):
    """Regression: `tsfdi fit` on a CrazyPAD log with all 19 numeric columns (controller.ctr_yaw repeats
    controller.cmd_yaw) warned that every order fits exactly and saved the model with exit 0; it is refused now,
    naming the columns and the fix."""
    from pathlib import Path

    log = Path(__file__).resolve().parents[1] / CRAZYPAD
    out = tmp_path / "m.npz"
    assert main(["fit", str(log), "--time-unit", "ms", "--max-lags", "4", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "fits the 19 column(s)" in err and "exactly" in err and "not saved. Choose the channels with --columns" in err
    assert "'controller.ctr_yaw' is proportional to 'controller.cmd_yaw'" in err and not out.exists()
    x = np.random.default_rng(2).standard_normal((400, 2))
    pd.DataFrame({"time": np.arange(400) / 10, "a": x[:, 0], "b": 3 * x[:, 0]}).to_csv(tmp_path / "twins.csv",
                                                                                     index=False)
    assert main(["fit", str(tmp_path / "twins.csv"), "--max-lags", "2", "--out", str(out)]) == 2
    assert "'b' is proportional to 'a'" in capsys.readouterr().err


def test_fit_prints_a_compact_summary(tmp_path, capsys):
    """Regression: fit printed every coefficient (1,031 lines for a CrazyPAD VAR); the header only by default,
    --coefficients for the tables, --quiet for the result line."""
    x = np.random.default_rng(4).standard_normal((600, 3))
    pd.DataFrame({"time": np.arange(600) / 50, "a": x[:, 0], "b": x[:, 1], "c": x[:, 2]}).to_csv(
        tmp_path / "log.csv", index=False)
    out = str(tmp_path / "m.npz")
    printed = {}
    for flag in ("", "--coefficients", "--quiet"):
        assert main(["fit", str(tmp_path / "log.csv"), "--lags", "4", "--max-lags", "4", "--out", out,
                     *([flag] if flag else [])]) == 0
        printed[flag] = capsys.readouterr().out.splitlines()
    assert len(printed["--quiet"]) == 2 and printed["--quiet"][-1].startswith("saved to")
    assert len(printed[""]) < 25 < len(printed["--coefficients"])
    assert "Samples per parameter" in "\n".join(printed[""])


def test_help_says_why_the_defaults_differ_from_python(capsys):
    """Regression: --alpha 0.001 and --lags 25 (monitor) differ from LjungBox() / FTest() (0.05, 20) without a
    stated reason."""
    for name in ("detect", "monitor"):
        with pytest.raises(SystemExit):
            main([name, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "the test classes of tsfdi default to 0.05" in text
    assert "25 for monitor, as in paper 003" in text


def test_identify_rule_sprt_is_msprt_per_record(saved_models, capsys):
    """`tsfdi identify --rule sprt`: one row per record, msprt on the models' per-sample log-likelihoods from the
    first sample every model has a residual for, decision time on the record's clock."""
    from tsfdi.detection.sequential import msprt
    from tsfdi.windows import ResidualWindows

    d, paths, cur, x = saved_models
    out = d / "ident_sprt.csv"
    rc = main(["identify", str(cur), "--models", f"f1={paths['f1']}", f"f2={paths['f2']}", "--rule", "sprt",
               "--sprt-alpha", "1e-4", "--start", "115s", "--out", str(out)])
    assert rc == 0
    t = pd.read_csv(out, keep_default_na=False)
    assert list(t.columns) == ["start", "decision_time", "status", "label"] and len(t) == 1
    models = {n: tsfdi.load(p) for n, p in paths.items()}
    rw = ResidualWindows(models)
    p = max(rw.orders.values())
    seq = msprt(rw.fit(x[1500:]).loglik(), alpha=1e-4)
    assert seq.label == 1 and t["label"][0] == "f2" and t["status"][0] == "identified"
    assert t["start"][0] == pytest.approx(115.0 + p / FS)
    assert t["decision_time"][0] == pytest.approx(115.0 + (p + seq.decision_time - 1) / FS)
    capsys.readouterr()
    assert main(["identify", str(cur), "--models", str(paths["f1"]), str(paths["f2"]), "--rule", "sprt",
                 "--window", "10s"]) == 2
    assert "--window" in capsys.readouterr().err
    assert main(["identify", str(cur), "--models", str(paths["f1"]), str(paths["f2"]), "--rule", "sprt",
                 "--sprt-alpha", "1"]) == 2
    assert "--sprt-alpha" in capsys.readouterr().err
    assert main(["identify", str(cur), "--models", str(paths["f1"]), str(paths["f2"]), "--rule", "sprt",
                 "--threshold", "calibrated"]) == 2
    assert "--threshold" in capsys.readouterr().err

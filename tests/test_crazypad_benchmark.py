"""benchmarks/crazypad.py (issue 17) on a reduced path: one fold, one faulty condition, one held-out flight.

Needs ../shared/data/crazypad (the ``shared_data`` fixture and the benchmark's ``setup`` fail loudly without it).
"""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

CUT4 = "cut_propeller_M3_4mm_4mm_39mm"


@pytest.fixture(scope="module")
def bench(shared_data):
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "crazypad.py"
    spec = importlib.util.spec_from_file_location("crazypad_bench", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.setup(shared_data / "crazypad")          # raises FileNotFoundError if the CrazyPAD copy is missing
    return mod


@pytest.fixture(scope="module")
def fold0(bench):
    return bench.false_alarms(folds=[0], windows=(2.0,), alphas=(1e-2,))


def test_choices_are_made_on_the_fitting_normal_flights(bench, fold0):
    _, choices, ncal = fold0
    (ch,) = choices
    assert ch.logs == bench.normal_logs()[1:] and "E8_log00" not in ch.logs
    assert ch.margin == (2.5, 1.0)                   # the climb takes ~2.1 s, the descent ~0.5 s
    assert ch.channels == bench.BASE                 # accelz does not help predict on held-out logs
    assert 1 <= ch.order <= bench.MAX_LAGS
    assert 5 <= ncal[2.0][0] < 30                    # why min_windows is lowered: 2 s windows on 4 logs
    assert 98 < bench.FS < 104


def test_false_alarms_one_fold(bench, fold0):
    fa, choices, _ = fold0
    assert set(fa.fold) == {0} and set(fa.window_s) == {2.0} and set(fa.step_s) == {2.0, bench.SLIDE_S}
    tab = bench.fa_table(fa, len(choices[0].channels))
    assert ((tab.rate >= 0) & (tab.rate <= 1) & (tab.n > 0)).all()
    assert ((tab.lo <= tab.expected) & (tab.expected <= tab.hi + 1e-12)).all()
    indep = tab[(tab.step_s == 2.0) & (tab.channel == "any")]
    assert indep.n.between(2, 8).all()                # two segments of ~5-6 s: 2 windows of 2 s each
    sliding = tab[(tab.step_s == bench.SLIDE_S) & (tab.channel == "pooled")].set_index(["family", "mode"])
    for fam in ("LB", "F", "M"):                      # the held-out calibration removes most theoretical alarms
        assert sliding.loc[(fam, "calibrated"), "rate"] < sliding.loc[(fam, "theoretical"), "rate"]
        assert sliding.loc[(fam, "calibrated"), "rate"] < 0.15
    lines = bench.fa_verdicts(tab)
    assert len(lines) == 18 and all(line.split()[0] in ("PASS", "FAIL") for line in lines)


def test_detection_of_the_largest_cut(bench, fold0):
    choice = fold0[1][0]
    det, ncal = bench.detection(choice, conditions=(CUT4,), windows=(2.0,), alphas=(1e-2,))
    assert set(det.condition) == {CUT4} and set(det.family) == set(bench.DETECTORS)
    assert ncal[2.0] >= bench.MIN_WINDOWS
    rate = {fam: g.flagged.sum() / g.n.sum() for fam, g in det.groupby("family")}
    assert rate["LB+F"] > 0.25                        # far above the false-alarm level of the normal flights
    assert rate["M-S"] > 0.9                          # the trim of the commands moves: the integrator compensates
    assert all(line.split()[0] in ("PASS", "FAIL") for line in bench.detection_verdicts(det))


def test_identification_one_held_out_flight(bench, fold0, capsys):
    choice = fold0[1][0]
    conditions = (bench.NORMAL, CUT4, "tape_on_propeller_M1_M3")
    ident, ncal = bench.identification(choice, conditions=conditions, alphas=(1e-2,),
                                       held_out=[(CUT4, "E8_log00")])
    assert ncal >= bench.MIN_WINDOWS
    assert set(ident.condition) == {CUT4} and set(ident.log) == {"E8_log00"}
    assert set(ident.label) <= set(conditions) | {"ambiguous", "none"}
    lik = ident[ident.rule == "likelihood"]
    assert lik.label.isin(conditions).all()          # the likelihood rule always names a model
    assert ident[ident.rule == "pvalue"].label.isin(conditions).all()
    assert set(ident.rule) == {"paper", "likelihood", "pvalue"}
    per = ident.groupby(["family", "rule"]).size()
    assert per.nunique() == 1 and per.iloc[0] >= 10   # every family and rule labels the same windows
    summary = bench.ident_summary(ident)
    assert np.isfinite(summary.to_numpy()).all() and ((summary >= 0) & (summary <= 100)).all().all()
    bench.report_identification(ident, conditions)
    out = capsys.readouterr().out
    assert "confusion (likelihood rule" in out and "confusion (pvalue rule" in out and "cut4" in out


def test_missing_data_fails_loudly(bench, tmp_path):
    root = bench.ROOT
    try:
        with pytest.raises(FileNotFoundError, match="CrazyPAD data missing"):
            bench.setup(tmp_path)
    finally:
        bench.setup(root)

"""benchmarks/crazypad.py (issue 17) on a reduced path: one fold, one faulty condition, one held-out flight.

Needs ../shared/data/crazypad (skipped without it, see ``shared_crazypad`` in conftest.py). What the tests expect
of the copy is read from its ``flights.csv``.
"""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from _scripts import load_script

CUT4 = "cut_propeller_M3_4mm_4mm_39mm"


def load_benchmark():
    """A fresh import of benchmarks/crazypad.py, not yet pointed at a copy (its functions on names need none)."""
    return load_script("benchmarks/crazypad.py")


@pytest.fixture(scope="module")
def bench(shared_crazypad):
    mod = load_benchmark()
    mod.setup(shared_crazypad)                   # the default selection: the nine conditions of KNOWN
    return mod


@pytest.fixture(scope="module")
def flights(shared_crazypad) -> pd.DataFrame:
    return pd.read_csv(shared_crazypad / "flights.csv")


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
    assert "decided per held-out flight" in out


def test_flight_summary_counts_majorities_and_ties():
    bench = load_benchmark()
    def rows(cond, log, labels):
        return [{"alpha": 0.01, "family": "LB+F+M", "rule": "pvalue", "condition": cond, "log": log, "label": lb}
                for lb in labels]
    ident = pd.DataFrame(rows("a", "l0", "aab") + rows("a", "l1", "abb") + rows("b", "l2", "ab")
                         + rows("b", "l3", "bbba"))
    # a: l0 right, l1 wrong -> 50 %; b: l2 a tie (counted wrong), l3 right -> 50 %
    assert bench.flight_summary(ident).loc[(0.01, "LB+F+M"), "pvalue"] == pytest.approx(50.0)


def test_missing_data_fails_loudly(tmp_path):
    with pytest.raises(FileNotFoundError, match="CrazyPAD data missing"):
        load_benchmark().setup(tmp_path)


# ------------------------------------------------------------------ the data the benchmark finds in a copy
def fuller_copy(root: Path, shared: Path) -> Path:
    """A copy of the shared CrazyPAD folder (files linked) with one more condition (one log of
    tape_on_propeller_M3_M4 under a new name) and one E9 normal flight (an E8 normal log under another name)."""
    (root / "controller").mkdir(parents=True)
    for cond in (shared / "controller").iterdir():
        (root / "controller" / cond.name).symlink_to(cond)
    (root / "controller" / "normal_flight").unlink()
    (root / "controller" / "normal_flight").mkdir()
    for f in (shared / "controller" / "normal_flight").iterdir():
        (root / "controller" / "normal_flight" / f.name).symlink_to(f)
    (root / "controller" / "normal_flight" / "E9_log07.csv.gz").symlink_to(
        shared / "controller" / "normal_flight" / "E8_log01.csv.gz")
    (root / "controller" / "bent_propeller_M2").mkdir()
    (root / "controller" / "bent_propeller_M2" / "E8_log00.csv.gz").symlink_to(
        shared / "controller" / "tape_on_propeller_M3_M4" / "E8_log00.csv.gz")
    table = (shared / "flights.csv").read_text()
    (root / "flights.csv").write_text(table + "bent_propeller_M2,E8,E8_log00,2600,25.7\n"
                                      "normal_flight,E9,E9_log07,2600,25.7\n")
    return root


def test_conditions_and_labels_are_read_from_the_copy(bench, flights):
    assert set(bench.KNOWN) <= set(flights.condition)
    assert bench.CONDITIONS == tuple(bench.KNOWN) and bench.SHORT == bench.KNOWN   # by default the published nine
    root = bench.ROOT
    try:
        bench.setup(root, "*")                                                       # every condition of the copy
        everything = bench.CONDITIONS
        assert len(everything) == flights.condition.nunique() and set(everything) == set(flights.condition)
        assert everything[:len(bench.KNOWN)] == tuple(bench.KNOWN)
        assert list(everything[len(bench.KNOWN):]) == sorted(set(flights.condition) - set(bench.KNOWN))
        assert len(set(bench.SHORT.values())) == len(everything)
        bench.setup(root, "tape_on_propeller_*, cut_propeller_M3_1mm")              # patterns and names
        tape = sorted(c for c in set(flights.condition) if c.startswith("tape_on_propeller_"))
        assert len(tape) >= 2
        assert set(bench.CONDITIONS) == {"normal_flight", "cut_propeller_M3_1mm", *tape}
        assert bench.CONDITIONS[0] == "normal_flight"                                 # always there, first
    finally:
        bench.setup(root)
    assert bench.CONDITIONS == tuple(bench.KNOWN)


def test_condition_selection_order_and_labels():
    bench = load_benchmark()
    names = ["tape_x_M1", "weight_on_string_W2_near_M3", "tape_y_M2", "cut_propeller_M3_1mm", "normal_flight"]
    assert bench.select_conditions(names) == ("normal_flight", "cut_propeller_M3_1mm", "weight_on_string_W2_near_M3")
    assert bench.select_conditions(names, "tape_*,cut_propeller_M3_1mm") == (
        "normal_flight", "cut_propeller_M3_1mm", "tape_x_M1", "tape_y_M2")
    assert bench.select_conditions(names, "*") == bench.conditions_of(names)
    for bad in ("no_such_*", "tape_x_M1,,tape_y_M2", "Normal_flight", "tape_x"):
        with pytest.raises(ValueError, match=r"conditions: .* matches no condition.*available: cut_propeller_M3_1mm"):
            bench.select_conditions(names, bad)
    with pytest.raises(TypeError, match="conditions"):
        bench.select_conditions(names, ["normal_flight"])
    with pytest.raises(ValueError, match="normal_flight"):
        bench.select_conditions(names[:-1], "*")
    names = ["weight_on_string_W2_near_M3", "cut_propeller_M3_1mm", "normal_flight", "zz_new_M1", "bent_M2_3mm"]
    assert bench.conditions_of(names) == ("normal_flight", "cut_propeller_M3_1mm", "weight_on_string_W2_near_M3",
                                          "bent_M2_3mm", "zz_new_M1")
    with pytest.raises(ValueError, match="normal_flight"):
        bench.conditions_of(["cut_propeller_M3_1mm"])
    assert bench.short_label("bent_propeller_M2_3mm") == "bentM23mm"
    labels = bench.short_labels(("normal_flight", "cut_propeller_M3_1mm", "cut_M3_1mm", "tape_on_propeller_M1_M3",
                                 "tape_x_M1_M3"))
    assert labels["cut_propeller_M3_1mm"] == "cut1" and labels["cut_M3_1mm"] == "cutM31mm"
    assert labels["tape_x_M1_M3"] == "tape_x_M1_M3"              # "tapeM1M3" is taken: the name itself
    assert len(set(labels.values())) == len(labels)


def test_corrupt_log_rule_flags_the_flipped_log_only(bench, flights):
    conditions = sorted(set(flights.condition))                                    # every condition of the copy
    flagged = {c: bench.corrupt_logs(c) for c in conditions}
    assert {(c, log) for c, logs in flagged.items() for log in logs} == {("weight_on_string_W2_near_M3", "E8_log02")}
    assert min(flagged["weight_on_string_W2_near_M3"]["E8_log02"]) > 5.0          # both segments, seconds on end
    top = {c: max(s[bench.THRUST].max() for s in bench.load_segments(c, (0.0, 0.0))
                  if s.attrs["log"] not in flagged[c]) for c in conditions}
    assert max(top.values()) < bench.THRUST_FULL_SCALE                             # no other log touches full scale
    assert max(top[c] for c in bench.CONDITIONS) < 0.85 * bench.THRUST_FULL_SCALE  # the published nine: far from it
    logs = {f.log for f in bench.load_condition("weight_on_string_W2_near_M3", (0.0, 0.0))}
    assert "E8_log02" not in logs
    assert len(logs) == (flights.condition == "weight_on_string_W2_near_M3").sum() - 1


def test_a_fuller_copy_is_discovered(bench, flights, shared_crazypad, tmp_path, capsys):
    root = bench.ROOT
    fuller = fuller_copy(tmp_path / "crazypad", shared_crazypad)
    normal = flights[flights.condition == "normal_flight"]
    try:
        bench.setup(fuller)
        assert bench.CONDITIONS == tuple(bench.KNOWN)            # the default selection: a new condition is not in
        bench.setup(fuller, "*")
        others = sorted({*flights.condition, "bent_propeller_M2"} - set(bench.KNOWN))
        assert bench.CONDITIONS == (*bench.KNOWN, *others) and bench.SHORT["bent_propeller_M2"] == "bentM2"
        bench.setup(fuller, "bent_*")
        assert bench.CONDITIONS == ("normal_flight", "bent_propeller_M2")
        assert bench.normal_logs() == (*normal.log, "E9_log07")
        assert bench.identified_conditions((0.0, 0.0)) == ("normal_flight",)   # one log: cannot be held out
        bench.print_data()
        out = capsys.readouterr().out
        drones = pd.Series([*normal.drone, "E9"]).value_counts().sort_index()       # E9_log07 added
        assert (f"normal_flight                        {len(normal) + 1} logs ("
                + ", ".join(f"{d}: {n}" for d, n in drones.items()) + ")") in out
        assert "bentM2    bent_propeller_M2                    1 logs (E8: 1)" in out
    finally:
        bench.setup(root)
    assert bench.CONDITIONS == tuple(bench.KNOWN)

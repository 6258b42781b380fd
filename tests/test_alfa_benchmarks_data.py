"""The ALFA benchmarks find their flights in the copy they are given (benchmarks/alfa_isolation.py,
alfa_detection.py, alfa_sensor_validation.py): the shared copy's selection, and a fuller copy's without crashing.

Needs ../shared/data/alfa (skipped without it, see ``shared_alfa`` in conftest.py).
"""

import shutil
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from _scripts import load_script

from tsfdi.datasets.alfa import list_alfa
from tsfdi.evaluation import score_records
from tsfdi.exceptions import ConvergenceWarning

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def benchmark(name: str):
    return load_script(f"benchmarks/{name}.py")


def linked_copy(root: Path, shared: Path) -> Path:
    """The shared ALFA folder with its files linked one by one (so that files can be added or left out)."""
    for f in shared.rglob("*"):
        if f.is_file():
            (root / f.relative_to(shared)).parent.mkdir(parents=True, exist_ok=True)
            (root / f.relative_to(shared)).symlink_to(f)
    return root


def test_isolation_flights_are_the_engine_flights_with_a_pitot(shared_alfa, tmp_path):
    bench = benchmark("alfa_isolation")
    shared = shared_alfa
    names = bench.pitot_flights(shared)
    assert names == [f"carbonZ_{n}_engine_failure" for n in ("2018-07-18-15-53-31_1", "2018-07-18-15-53-31_2",
                                                             "2018-07-30-16-39-00_1", "2018-07-30-16-39-00_2")]
    root = linked_copy(tmp_path / "alfa", shared)
    new = "carbonZ_2019-01-01-10-00-00_engine_failure"       # a new flight with a pitot (a copy of one)
    for folder in ("engine_commanded_measured", "merged_20hz/engine"):
        (root / folder / f"{new}.csv.gz").symlink_to(shared / folder / f"{names[0]}.csv.gz")
    (root / "merged_20hz" / "engine" / f"{names[1]}.csv.gz").unlink()      # no ground velocity: left out
    assert bench.pitot_flights(root) == [names[0], *names[2:], new]
    with pytest.raises(FileNotFoundError, match="ALFA data not found"):
        bench.pitot_flights(tmp_path / "missing")


def test_keipour_subset_refuses_another_copy_with_its_counts(shared_alfa):
    """keipour_flights refuses a copy whose flights up to 2018-09-11 do not count as Table I (the benchmark prints
    its message and skips the comparison); its message gives the counts found."""
    bench = benchmark("alfa_detection")
    tab = list_alfa(shared_alfa)
    mask, _ = bench.keipour_flights(tab)
    assert mask.sum() == 22
    extra = tab[tab.flight.str.contains("rudder_right")].iloc[:1].assign(flight="carbonZ_2018-09-11-18-00-00_rudder")
    with pytest.raises(RuntimeError, match=r"'rudder': 4.*Table I"):
        bench.keipour_flights(pd.concat([tab, extra], ignore_index=True))


def test_sensor_validation_noise_from_any_official_imu_file(shared_alfa, tmp_path):
    bench = benchmark("alfa_sensor_validation")
    shared = shared_alfa
    sigma0 = bench.sensor_noise(shared)
    assert abs(np.degrees(sigma0) - 0.02) < 1e-6
    root = linked_copy(tmp_path / "alfa", shared)
    sample = root / "official_format_sample"
    (imu,) = sample.glob(f"*-{bench.IMU_TOPIC}.csv.gz")
    shutil.copy(imu, sample / imu.name.replace("2018-07-18-15-53-31_1", "2019-01-01-10-00-00"))
    assert bench.sensor_noise(root) == sigma0                 # another flight's messages: the same setting
    shutil.rmtree(sample)
    with pytest.raises(FileNotFoundError, match="mavros-imu-data.csv"):
        bench.sensor_noise(root)


def test_sprt_folds_calibrate_on_the_other_flights_healthy_parts_only(shared_alfa, monkeypatch):
    """Configuration S of alfa_detection.py: in fold i every detector is calibrated (OnlineDetector.calibrate, the
    defaults' code path) on the rows before the onset of the other flights only -- never on flight i, never on a
    row at or after an onset, never on a healthy part shorter than MIN_HEALTHY_S -- and a fold whose calibration is
    refused raises no alarm (it is not scored)."""
    bench = benchmark("alfa_detection")
    tab = list_alfa(shared_alfa)
    pick = [tab.index[tab.fault == f][0] for f in ("engine", "rudder", "none", "ailerons")]
    flights = [bench.prepare(bench.load_alfa(tab.merged_path[i])) for i in pick]
    onset = tab.onset_s.to_numpy(dtype=float)[pick]
    for df, o in zip(flights, onset):
        part = bench.healthy_part(df, o)
        t = (part.index - df.index[0]).total_seconds()
        assert part.index.equals(df.index[: len(part)]) and (t < o).all() if np.isfinite(o) else part is df
        assert np.isnan(o) or len(part) == int(((df.index - df.index[0]).total_seconds() < o).sum())

    seen = []

    class Spy(bench.OnlineDetector):
        def calibrate(self, y_runs, u_runs, **kwargs):
            seen.append((self.pairs, [y.index[[0, -1]] for y in y_runs]))
            raise ValueError("refused by the spy")

    monkeypatch.setattr(bench, "OnlineDetector", Spy)
    alarm, refusals = bench.sprt_folds(flights, onset)
    groups = bench.recipe_groups()
    assert np.isnan(alarm).all()
    assert {g: [i for i, _ in v] for g, v in refusals.items()} == {"+".join(g): list(range(4)) for g in groups}
    assert len(seen) == 4 * len(groups)
    # healthy parts shorter than MIN_HEALTHY_S are left out (their pairs arm too late for calibrate's records)
    long_enough = [len(bench.healthy_part(df, o)) >= bench.MIN_HEALTHY_S * bench.FS for df, o in zip(flights, onset)]
    assert 0 < sum(long_enough) < 4
    for k, (pairs, spans) in enumerate(seen):
        i = k // len(groups)
        assert list(pairs) == groups[k % len(groups)]
        others = [j for j in range(4) if j != i and long_enough[j]]
        for (first, last), j in zip(spans, others, strict=True):
            assert first == flights[j].index[0]
            end = flights[j].index[0] + pd.Timedelta(seconds=onset[j]) if np.isfinite(onset[j]) else None
            assert last == flights[j].index[-1] if end is None else last < end


def test_thrust_variants_base_is_the_thrust_channel_and_signs_split_the_input(shared_alfa):
    """Configuration T of alfa_detection.py: the base variant is B's thrust channel (the same statistic), and a
    ``+`` / ``-`` column is the positive / negative part of the input (not the input itself, not dropped)."""
    bench = benchmark("alfa_detection")
    tab = list_alfa(shared_alfa)
    df = bench.prepare(bench.load_alfa(tab.merged_path[tab.index[tab.fault == "engine"][0]]))
    t, s = bench.thrust_variant_statistic(df, "thrust (B, C)")
    t_b, s_b = bench.channel_statistic(df, "thrust")
    np.testing.assert_array_equal(t, t_b)
    np.testing.assert_array_equal(s, s_b)
    a = df["field.aspd_error"]
    split = df.assign(pos=a.clip(lower=0), neg=a.clip(upper=0))
    bench.THRUST_VARIANTS["check"] = (["pos", "neg", "field.alt_error"], {})
    try:
        _, expected = bench.thrust_variant_statistic(split, "check")
    finally:
        del bench.THRUST_VARIANTS["check"]
    _, got = bench.thrust_variant_statistic(df, "airspeed error split by sign")
    np.testing.assert_array_equal(got, expected)
    assert np.isfinite(got).sum() > 1000 and not np.array_equal(got, s)


def test_lofo_criterion_is_the_fold_choice_on_its_fitting_flights():
    """lofo's criterion (used by configuration CT to choose the thrust structure in each fold) is the number of
    correct outcomes and the mean detection time of the fold's choice on the other flights only."""
    bench = benchmark("alfa_detection")
    onset = np.array([10.0, np.nan, 20.0])
    times = {"a": np.array([[5.0, 12.0], [30.0, np.nan], [21.0, 25.0]])}
    alarm, labels, _, _, _, criterion = bench.lofo(onset, times, {"a": np.array([1.0, 2.0])})
    np.testing.assert_array_equal(criterion, [[2, 5.0], [2, 3.5], [2, 2.0]])
    np.testing.assert_array_equal(alarm, [12.0, np.nan, 25.0])
    assert labels == ["a 2"] * 3


def test_thrust_variant_chosen_in_each_fold_on_its_fitting_flights(monkeypatch):
    """Configuration CT picks, in each fold, the thrust variant whose choice scores best on the other flights
    (ties: the first variant), and applies that fold's thresholds to the held-out flight."""
    bench = benchmark("alfa_detection")
    onset = np.array([10.0, np.nan, 20.0])
    t = np.arange(0.0, 40.0, 0.5)

    def statistic(i, name):
        if name == "early":                                        # alarms at 5 s on every flight
            return t, np.where(t >= 5.0, 3.0, 0.0)
        return t, np.where(t >= onset[i] + 1.0, 3.0, 0.0) if np.isfinite(onset[i]) else np.zeros_like(t)

    monkeypatch.setattr(bench, "THRUST_VARIANTS", {"early": None, "at onset": None, "same": None})
    monkeypatch.setattr(bench, "thrust_variant_statistic", statistic)
    grids = {"thrust": np.array([1.0, 2.0])}
    alarm, labels = bench.lofo_thrust_variants([0, 1, 2], onset, {"thrust": None}, grids)
    np.testing.assert_array_equal(alarm, [11.0, np.nan, 21.0])
    assert labels == ["thrust variant 'at onset': thrust 1"] * 3


def test_configuration_a_is_paper_001s_zscore_detector(shared_alfa):
    """Configuration A (and A-K) is paper 001's Z-score detector with its gate, whatever OnlineDetector's defaults
    are: on the 45 flights 5 true positives, 30 false positives, 5 missed, 5 true negatives (the module docstring
    and the guide). With the recipe's defaults (SPRT, eps 0.03) in its place it alarmed before the onset on 44."""
    bench = benchmark("alfa_detection")
    tab = list_alfa(shared_alfa)
    ycols = [y for y, _ in bench.PAPER_PAIRS.values()]
    ucols = [u for _, u in bench.PAPER_PAIRS.values()]
    alarm = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)         # pairs that never arm on some flights
        for path in tab.merged_path:
            df = bench.prepare(bench.load_alfa(path))
            alarm.append(bench.first_alarm_s(df, bench.paper_detector().run(df[ycols], df[ucols])))
    det = bench.paper_detector()
    assert det.statistic == "zscore" and det.eps == 1e-2 and det.glrt is None
    outcome = score_records(tab.onset_s.to_numpy(dtype=float), alarm, records=tab.flight)["outcome"]
    assert outcome.value_counts().to_dict() == {"FP": 30, "TP": 5, "FN": 5, "TN": 5}


def test_pitch_error_level_finds_the_elevator_failure_c_misses(shared_alfa):
    """Configuration CP's pitch_err channel: on 2018-09-11-14-41-51 (elevator) it exceeds, within 3 s of the onset,
    its largest value over the healthy part of every flight (the module docstring's claim); it is a candidate of
    CP only, not of B5."""
    bench = benchmark("alfa_detection")
    tab = list_alfa(shared_alfa)
    onset = tab.onset_s.to_numpy(dtype=float)
    healthy, target = [], None
    for i, path in enumerate(tab.merged_path):
        t, s = bench.channel_statistic(bench.prepare(bench.load_alfa(path)), "pitch_err")
        end = onset[i] if np.isfinite(onset[i]) else np.inf
        healthy.append(s[t < end].max())
        if "14-41-51_elevator" in tab.flight[i]:
            target = s[(t >= end) & (t < end + 3.0)].max()
    assert target > max(healthy) > 25.0
    assert "pitch_err" not in bench.B5_CHANNELS and "pitch_err" not in bench.BASE_CHANNELS

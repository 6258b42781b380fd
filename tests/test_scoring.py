"""Per-record detection scoring (Keipour et al., paper 001, Table I): first alarm, outcomes, metrics."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tsfdi.evaluation import OUTCOMES, detection_metrics, first_alarm, score_records

NAN = np.nan


# ------------------------------------------------------------------------------------------------ score_records
@pytest.mark.parametrize("onset, alarm, outcome, delay", [
    (10.0, 12.5, "TP", 2.5),    # fault, alarm after the onset
    (10.0, 10.0, "TP", 0.0),    # fault, alarm exactly at the onset
    (10.0, 9.99, "FP", NAN),    # fault, alarm before the onset
    (10.0, NAN, "FN", NAN),     # fault, no alarm
    (NAN, 3.0, "FP", NAN),      # fault-free, alarm
    (NAN, NAN, "TN", NAN),      # fault-free, no alarm
    (-2.0, -1.0, "TP", 1.0),    # any consistent time origin
])
def test_every_outcome_case(onset, alarm, outcome, delay):
    s = score_records([onset], [alarm])
    assert list(s.columns) == ["onset", "first_alarm", "outcome", "delay"]
    assert s["outcome"].iloc[0] == outcome
    np.testing.assert_equal(s["delay"].iloc[0], delay)
    np.testing.assert_equal(s["onset"].iloc[0], onset)
    np.testing.assert_equal(s["first_alarm"].iloc[0], alarm)


def test_score_records_numpy_list_and_none():
    onset = np.array([10.0, 10.0, 10.0, NAN, NAN])
    alarm = [12.0, 4.0, None, 30.0, None]  # None: no alarm
    s = score_records(onset, alarm)
    assert s["outcome"].tolist() == ["TP", "FP", "FN", "FP", "TN"]
    np.testing.assert_array_equal(s["delay"].to_numpy(), [2.0, NAN, NAN, NAN, NAN])
    assert isinstance(s.index, pd.RangeIndex) and s.index.name == "record"
    assert s["onset"].dtype == np.float64 and s["first_alarm"].dtype == np.float64
    # integer input is fine
    assert score_records([1, 2], [3, 1])["outcome"].tolist() == ["TP", "FP"]


def test_score_records_pandas_index_records_and_kind():
    idx = pd.Index(["f1", "f2", "f3"], name="flight")
    onset = pd.Series([5.0, NAN, 7.0], index=idx)
    alarm = pd.Series([6.0, NAN, NAN], index=idx)
    s = score_records(onset, alarm, kind=pd.Series(["engine", "none", "rudder"], index=idx))
    assert s.index.equals(idx) and s.index.name == "flight"
    assert s.loc["f1", "outcome"] == "TP" and s.loc["f2", "outcome"] == "TN" and s.loc["f3", "outcome"] == "FN"
    assert s["kind"].tolist() == ["engine", "none", "rudder"]
    assert list(s.columns) == ["onset", "first_alarm", "outcome", "delay", "kind"]
    # only first_alarm is a Series: its index is kept
    s = score_records([5.0, NAN, 7.0], alarm)
    assert s.index.equals(idx)
    # explicit records win and the Series values are used in order
    s = score_records(onset, alarm, records=["a", "b", "c"])
    assert s.index.tolist() == ["a", "b", "c"] and s["outcome"].tolist() == ["TP", "TN", "FN"]
    s = score_records(onset.to_numpy(), alarm.to_numpy(), records=pd.Series(["x", "y", "z"], name="flight"))
    assert s.index.name == "flight" and s.index.tolist() == ["x", "y", "z"]
    # nullable float input with pd.NA
    s = score_records(pd.Series([5.0, None], dtype="Float64"), pd.Series([None, 1.0], dtype="Float64"))
    assert s["outcome"].tolist() == ["FN", "FP"]


def test_score_records_empty():
    s = score_records([], [])
    assert len(s) == 0 and list(s.columns) == ["onset", "first_alarm", "outcome", "delay"]
    m = detection_metrics(s, max_delay=1.0)
    assert m.loc["all", "records"] == 0 and np.isnan(m.loc["all", "accuracy"])


@pytest.mark.parametrize("kwargs, exc, match", [
    (dict(onset=[1.0, 2.0], first_alarm=[1.0]), ValueError, "first_alarm has 1 values but onset has 2"),
    (dict(onset=["a", "b"], first_alarm=[1.0, 2.0]), TypeError, "onset"),
    (dict(onset=[1.0, "b"], first_alarm=[1.0, 2.0]), TypeError, "onset"),
    (dict(onset=[True, False], first_alarm=[1.0, 2.0]), TypeError, "onset"),
    (dict(onset=[1.0, 2.0], first_alarm=[True, False]), TypeError, "first_alarm"),
    (dict(onset=[1.0, 2.0], first_alarm=["x", 2.0]), TypeError, "first_alarm"),
    (dict(onset=pd.to_datetime(["2020-01-01", "2020-01-02"]), first_alarm=[1.0, 2.0]), TypeError, "onset"),
    (dict(onset=[1.0, 2.0], first_alarm=pd.Series(pd.to_timedelta([1, 2], unit="s"))), TypeError, "first_alarm"),
    (dict(onset=[1.0, np.inf], first_alarm=[1.0, 2.0]), ValueError, "onset must be finite or NaN"),
    (dict(onset=[1.0, 2.0], first_alarm=[-np.inf, 2.0]), ValueError, "first_alarm must be finite or NaN"),
    (dict(onset=[[1.0, 2.0]], first_alarm=[[1.0, 2.0]]), ValueError, "onset must be 1-D"),
    (dict(onset=1.0, first_alarm=2.0), ValueError, "onset must be 1-D"),
    (dict(onset=pd.DataFrame({"a": [1.0]}), first_alarm=[1.0]), TypeError, "onset"),
    (dict(onset=[1.0, 2.0], first_alarm=[1.0, 2.0], records=["a"]), ValueError, "records has 1 labels"),
    (dict(onset=[1.0, 2.0], first_alarm=[1.0, 2.0], records="ab"), ValueError, "records"),
    (dict(onset=[1.0, 2.0], first_alarm=[1.0, 2.0], kind=["a", "b", "c"]), ValueError, "kind has 3 labels"),
    (dict(onset=[1.0, 2.0], first_alarm=[1.0, 2.0], kind="engine"), ValueError, "kind"),
    (dict(onset=pd.Series([1.0, 2.0], index=["a", "b"]), first_alarm=pd.Series([1.0, 2.0], index=["b", "a"])),
     ValueError, "first_alarm's index does not match onset's index"),
])
def test_score_records_bad_input_names_the_argument(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        score_records(kwargs.pop("onset"), kwargs.pop("first_alarm"), **kwargs)


# -------------------------------------------------------------------------------------------- detection_metrics
def _example():
    """Eight records by hand: engine TP 1 s, TP 6 s, FP (early), FN; rudder TP 0.5 s; none FP, TN, TN."""
    onset = [10.0, 20.0, 30.0, 40.0, 5.0, NAN, NAN, NAN]
    alarm = [11.0, 26.0, 29.0, NAN, 5.5, 8.0, NAN, NAN]
    kind = ["engine"] * 4 + ["rudder"] + ["none"] * 3
    return score_records(onset, alarm, kind=kind, records=[f"r{i}" for i in range(8)])


def test_metrics_by_hand():
    s = _example()
    assert s["outcome"].tolist() == ["TP", "TP", "FP", "FN", "TP", "FP", "TN", "TN"]
    m = detection_metrics(s)
    assert m.index.tolist() == ["all"]
    row = m.loc["all"]
    assert (row["records"], row["TP"], row["FP"], row["FN"], row["TN"]) == (8, 3, 2, 1, 2)
    assert row["precision"] == pytest.approx(3 / 5)
    assert row["recall"] == pytest.approx(3 / 4)
    assert row["accuracy"] == pytest.approx(5 / 8)
    assert row["mean_delay"] == pytest.approx((1.0 + 6.0 + 0.5) / 3)
    assert row["longest_delay"] == 6.0
    assert list(m.columns) == ["records", "TP", "FP", "FN", "TN", "precision", "recall", "accuracy", "mean_delay",
                               "longest_delay"]
    # raw numbers: integer counts, float rates, no strings
    assert all(m[c].dtype == np.int64 for c in ["records", "TP", "FP", "FN", "TN"])
    assert all(m[c].dtype == np.float64 for c in ["precision", "recall", "accuracy", "mean_delay", "longest_delay"])
    assert m.attrs["max_delay"] is None


def test_metrics_grouping_and_max_delay():
    s = _example()
    m = detection_metrics(s, by="kind", max_delay=5.0)
    assert m.index.tolist() == ["engine", "none", "rudder", "all"] and m.index.name == "kind"
    assert m.loc["engine", ["records", "TP", "FP", "FN", "TN"]].tolist() == [4, 2, 1, 1, 0]
    assert m.loc["engine", "precision"] == pytest.approx(2 / 3)
    assert m.loc["engine", "recall"] == pytest.approx(2 / 3)
    assert m.loc["engine", "accuracy"] == pytest.approx(2 / 4)
    assert m.loc["engine", "mean_delay"] == pytest.approx(3.5) and m.loc["engine", "longest_delay"] == 6.0
    # max_delay: the 6 s detection is a TP but not within 5 s
    assert m.loc["engine", "TP_within"] == 1 and m.loc["engine", "mean_delay_within"] == 1.0
    assert m.loc["all", "TP_within"] == 2 and m.loc["all", "mean_delay_within"] == pytest.approx(0.75)
    assert m["TP_within"].dtype == np.int64 and m.attrs["max_delay"] == 5.0
    # undefined rates are NaN, not 0 or strings
    none = m.loc["none"]
    assert (none["TP"], none["FP"], none["TN"]) == (0, 1, 2)
    assert none["precision"] == 0.0 and np.isnan(none["recall"]) and none["accuracy"] == pytest.approx(2 / 3)
    assert np.isnan(none["mean_delay"]) and np.isnan(none["longest_delay"]) and np.isnan(none["mean_delay_within"])
    assert none["TP_within"] == 0
    rudder = m.loc["rudder"]
    assert rudder["precision"] == 1.0 and rudder["recall"] == 1.0 and rudder["mean_delay_within"] == 0.5
    # the "all" row equals the ungrouped metrics
    pd.testing.assert_series_equal(m.loc["all"], detection_metrics(s, max_delay=5.0).loc["all"])
    # max_delay = 0 counts only alarms exactly at the onset
    assert detection_metrics(score_records([1.0, 1.0], [1.0, 1.5]), max_delay=0).loc["all", "TP_within"] == 1


def test_metrics_by_array_categorical_and_order():
    s = _example()
    labels = np.array(["b", "b", "b", "b", "a", "c", "c", "c"])
    m = detection_metrics(s, by=labels)
    assert m.index.tolist() == ["a", "b", "c", "all"] and m.index.name == "group"
    cat = pd.Categorical(s["kind"], categories=["rudder", "engine", "elevator", "none"])
    m = detection_metrics(s.assign(kind=cat), by="kind")
    assert m.index.tolist() == ["rudder", "engine", "none", "all"]  # category order, unobserved dropped
    by = pd.Series(s["kind"].to_numpy(), index=s.index, name="fault")
    m2 = detection_metrics(s, by=by)
    assert m2.index.name == "fault" and m2.loc["engine", "TP"] == 2
    # the same numbers however the groups are given
    pd.testing.assert_frame_equal(m2.rename_axis("kind"), detection_metrics(s, by="kind"))
    # integer group labels
    m = detection_metrics(s, by=[1, 1, 1, 1, 2, 3, 3, 3])
    assert m.index.tolist() == [1, 2, 3, "all"] and m.loc[2, "TP"] == 1


def test_metrics_on_a_subset_and_handmade_frame():
    s = _example()
    sub = s[s["kind"].to_numpy() != "none"]
    m = detection_metrics(sub, by="kind")
    assert m.loc["all", "records"] == 5 and "none" not in m.index
    # any frame with outcome and delay columns works
    frame = pd.DataFrame({"outcome": ["TP", "TN", "FN"], "delay": [0.2, NAN, NAN]})
    m = detection_metrics(frame)
    assert m.loc["all", "accuracy"] == pytest.approx(2 / 3) and m.loc["all", "mean_delay"] == 0.2


@pytest.mark.parametrize("scores, kwargs, exc, match", [
    ([["TP", 1.0]], {}, TypeError, "scores must be a pandas.DataFrame"),
    (pd.DataFrame({"outcome": ["TP"]}), {}, ValueError, r"scores lacks the column\(s\) \['delay'\]"),
    (pd.DataFrame({"outcome": ["TP", "XX"], "delay": [1.0, NAN]}), {}, ValueError, r"scores\['outcome'\]"),
    (pd.DataFrame({"outcome": ["TP", None], "delay": [1.0, NAN]}), {}, ValueError, r"scores\['outcome'\]"),
    (pd.DataFrame({"outcome": ["TP"], "delay": [NAN]}), {}, ValueError, r"scores\['delay'\]"),
    (pd.DataFrame({"outcome": ["TP"], "delay": [-1.0]}), {}, ValueError, r"scores\['delay'\]"),
    (pd.DataFrame({"outcome": ["TP"], "delay": ["1"]}), {}, TypeError, r"scores\['delay'\]"),
    (pd.DataFrame({"outcome": ["TP"], "delay": [1.0]}), dict(max_delay=-1.0), ValueError, "max_delay"),
    (pd.DataFrame({"outcome": ["TP"], "delay": [1.0]}), dict(max_delay="5"), TypeError, "max_delay"),
    (pd.DataFrame({"outcome": ["TP"], "delay": [1.0]}), dict(max_delay=np.nan), ValueError, "max_delay"),
    (pd.DataFrame({"outcome": ["TP"], "delay": [1.0]}), dict(by="kind"), ValueError, "no column 'kind'"),
    (pd.DataFrame({"outcome": ["TP"], "delay": [1.0]}), dict(by=["a", "b"]), ValueError, "by has 2 labels"),
    (pd.DataFrame({"outcome": ["TP", "TN"], "delay": [1.0, NAN]}), dict(by=["a", None]), ValueError,
     "by has missing labels"),
    (pd.DataFrame({"outcome": ["TP", "TN"], "delay": [1.0, NAN]}), dict(by=["a", "all"]), ValueError, "by has a group"),
    (pd.DataFrame({"outcome": ["TP", "TN"], "delay": [1.0, NAN]}), dict(by=pd.Series(["a", "b"], index=[5, 6])),
     ValueError, "by's index"),
    (pd.DataFrame({"outcome": ["TP", "TN"], "delay": [1.0, NAN]}), dict(by=[["a", "b"]]), ValueError, "by"),
])
def test_metrics_bad_input_names_the_argument(scores, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        detection_metrics(scores, **kwargs)


# -------------------------------------------------------------------------------------------------- first_alarm
def test_first_alarm_1d_positions_and_time():
    assert first_alarm([False, False, True, True]) == 2.0
    assert first_alarm(np.array([0, 1, 0])) == 1.0
    assert first_alarm(np.array([0.0, 0.0, 1.0])) == 2.0
    assert np.isnan(first_alarm([False, False]))
    assert np.isnan(first_alarm(np.zeros(0, dtype=bool)))
    assert first_alarm([False, True], time=[0.5, 0.75]) == 0.75
    assert first_alarm([False, True], time=np.array([10, 20])) == 20.0
    assert first_alarm([False, True], time=[0.5, 0.75], origin=0.5) == 0.25
    assert first_alarm([False, True], origin=1) == 0.0
    assert isinstance(first_alarm([True]), float)


def test_first_alarm_2d_any_column():
    a = np.zeros((6, 3), dtype=bool)
    a[4, 0] = a[2, 2] = a[5, 1] = True
    assert first_alarm(a) == 2.0
    assert first_alarm(a, time=np.arange(6) * 0.05) == pytest.approx(0.1)
    assert np.isnan(first_alarm(np.zeros((4, 2), dtype=bool)))
    assert np.isnan(first_alarm(np.zeros((4, 0), dtype=bool)))
    df = pd.DataFrame(a, columns=["roll", "pitch", "yaw"], index=np.arange(6) * 0.5)
    assert first_alarm(df) == 1.0  # the (numeric) index


def test_first_alarm_series_with_datetime_index():
    idx = pd.date_range("2018-07-30 16:39:00", periods=8, freq="50ms")
    s = pd.Series([False] * 5 + [True] * 3, index=idx)
    assert first_alarm(s) == pytest.approx(0.25)  # seconds since the first sample
    assert first_alarm(s, origin="2018-07-30 16:38:59") == pytest.approx(1.25)
    assert first_alarm(s, origin=idx[0] - pd.Timedelta("2s")) == pytest.approx(2.25)
    assert first_alarm(s.to_numpy(), time=idx) == pytest.approx(0.25)
    assert np.isnan(first_alarm(pd.Series(False, index=idx)))
    df = pd.DataFrame({"a": s.to_numpy(), "b": np.r_[False, False, True, [False] * 5]}, index=idx)
    assert first_alarm(df) == pytest.approx(0.1)
    # explicit time overrides the index
    assert first_alarm(s, time=np.arange(8)) == 5.0
    # timedelta index: seconds of the timedelta (origin zero)
    td = pd.Series([False, True], index=pd.to_timedelta([1.0, 1.5], unit="s"))
    assert first_alarm(td) == 1.5 and first_alarm(td, origin=pd.Timedelta("1s")) == 0.5
    # a default RangeIndex is the position
    assert first_alarm(pd.Series([False, True, True])) == 1.0
    # nullable boolean without missing values is fine
    assert first_alarm(pd.Series([False, True], dtype="boolean")) == 1.0


def test_first_alarm_feeds_score_records():
    """Seconds since the record start from a DatetimeIndex, scored against onsets in seconds."""
    idx = pd.date_range("2024-01-01", periods=100, freq="100ms")
    records = {"fault_late": (5.0, 62), "fault_early": (5.0, 20), "healthy": (NAN, None)}
    alarms, onsets = [], []
    for onset, k in records.values():
        a = np.zeros(100, dtype=bool)
        if k is not None:
            a[k:] = True
        alarms.append(first_alarm(pd.Series(a, index=idx)))
        onsets.append(onset)
    s = score_records(onsets, alarms, records=list(records))
    assert s["outcome"].tolist() == ["TP", "FP", "TN"]
    assert s.loc["fault_late", "delay"] == pytest.approx(1.2)


@pytest.mark.parametrize("alarm, kwargs, exc, match", [
    (np.array([0.0, np.nan, 1.0]), {}, ValueError, "alarm must be boolean, got NaN"),
    (pd.Series([False, None, True], dtype="boolean"), {}, ValueError, "alarm must be boolean, got a missing"),
    (pd.Series([False, np.nan, True]), {}, ValueError, "alarm must be boolean"),
    (np.array([0, 2, 1]), {}, ValueError, "alarm must be boolean"),
    (np.array(["no", "yes"]), {}, TypeError, "alarm must be boolean"),
    (np.array(["no", "yes"], dtype=object), {}, TypeError, "alarm must be boolean"),
    ("yes", {}, TypeError, "alarm must be boolean"),
    (True, {}, ValueError, "alarm must be 1-D"),
    (np.zeros((2, 2, 2), dtype=bool), {}, ValueError, "alarm must be 1-D"),
    ([False, True], dict(time=[0.0]), ValueError, "time has 1 entries but alarm has 2 rows"),
    ([False, True], dict(time=[0.0, np.nan]), ValueError, "time has missing values"),
    ([False, True], dict(time=["a", "b"]), TypeError, "time must hold numbers"),
    ([False, True], dict(time=[True, False]), TypeError, "time must hold numbers"),
    ([False, True], dict(time=1.0), ValueError, "time must be 1-D"),
    (pd.Series([False, True], index=["a", "b"]), {}, TypeError, "alarm's index"),
    ([False, True], dict(origin="x"), TypeError, "origin"),
    (pd.Series([False, True], index=pd.date_range("2024", periods=2)), dict(origin=1.5), TypeError, "origin"),
    (pd.Series([False, True], index=pd.date_range("2024", periods=2, tz="UTC")), dict(origin="2024-01-01"),
     TypeError, "origin"),
])
def test_first_alarm_bad_input(alarm, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        first_alarm(alarm, **kwargs)


def test_outcomes_constant():
    assert OUTCOMES == ("TP", "FP", "FN", "TN")

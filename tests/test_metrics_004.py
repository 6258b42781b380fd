"""Paper 004's metrics (MT, UD, FA) in tsfdi.evaluation, on hand-made alarms."""

import numpy as np
import pandas as pd
import pytest

from tsfdi.evaluation import detection_time, false_alarm_percentage, sensor_validation_metrics


def test_detection_time_by_hand():
    labels = np.arange(10) >= 4
    alarm = np.zeros(10, dtype=bool)
    alarm[[1, 6, 7]] = True                                  # a false alarm at 1, the detection at 6
    assert detection_time(alarm, labels) == 2.0             # in samples without a time axis
    assert detection_time(alarm, labels, time=np.arange(10) * 0.05) == 0.1
    assert detection_time(alarm.astype(int), labels.astype(float)) == 2.0


def test_detection_time_with_a_datetime_index_is_in_seconds():
    idx = pd.date_range("2024-01-01", periods=10, freq="50ms")
    alarm = pd.Series(np.arange(10) >= 7, index=idx)
    assert detection_time(alarm, np.arange(10) >= 4) == pytest.approx(0.15)


def test_undetected_and_alarms_after_the_fault_do_not_detect():
    labels = (np.arange(12) >= 4) & (np.arange(12) < 8)     # the fault lasts 4 samples
    late = np.arange(12) >= 9                               # alarms only after it ended
    assert np.isnan(detection_time(late, labels))
    assert np.isnan(detection_time(np.zeros(12, bool), labels))
    assert np.isnan(detection_time(np.ones(12, bool), np.zeros(12, bool)))   # no fault: nothing to detect
    assert detection_time(np.ones(12, bool), labels) == 0.0


def test_false_alarm_percentage_by_hand():
    labels = np.arange(10) >= 8                              # 8 fault-free samples before the onset
    alarm = np.zeros(10, bool)
    alarm[[2, 3, 8, 9]] = True                              # 2 of 8 before the onset, the rest during the fault
    assert false_alarm_percentage(alarm, labels) == 25.0
    assert false_alarm_percentage(alarm, np.zeros(10, bool)) == 40.0     # fault-free record: all of it
    assert np.isnan(false_alarm_percentage(alarm, np.ones(10, bool)))    # starts faulty


def test_sensor_validation_metrics_over_records():
    n = 20
    lab = np.arange(n) >= 10
    rec = []
    a1 = np.zeros(n, bool)
    a1[[12, 13]] = True                                     # detected after 2 samples, no false alarm
    a2 = np.zeros(n, bool)
    a2[[3, 15]] = True                                      # 1 of 10 fault-free samples, detected after 5
    a3 = np.zeros(n, bool)                                  # undetected
    a4 = np.zeros(n, bool)
    a4[[0, 1]] = True                                       # a fault-free record: counts for FA only
    rec = [a1, a2, a3, a4]
    labels = [lab, lab, lab, np.zeros(n, bool)]
    m = sensor_validation_metrics(rec, labels, times=[np.arange(n) * 0.1] * 4)
    assert m["MT"] == pytest.approx((0.2 + 0.5) / 2)
    assert m["UD"] == 1 and m["faults"] == 3
    assert m["FA"] == pytest.approx(100.0 * (0 + 1 + 0 + 2) / (10 + 10 + 10 + 20))
    assert m["longest"] == pytest.approx(0.5)
    none = sensor_validation_metrics([a3], [lab])
    assert np.isnan(none["MT"]) and none["UD"] == 1 and none["FA"] == 0.0


@pytest.mark.parametrize("call, exc, match", [
    (lambda: detection_time([0, 1], [0, 1, 1]), ValueError, "same length"),
    (lambda: detection_time([0, np.nan], [0, 1]), ValueError, "alarm must be boolean, got NaN"),
    (lambda: detection_time([0, 1], [0, 2]), ValueError, "labels must be boolean"),
    (lambda: detection_time(np.zeros((2, 2)), [0, 1]), ValueError, "alarm must be 1-D"),
    (lambda: detection_time("01", [0, 1]), TypeError, "alarm must be boolean"),
    (lambda: sensor_validation_metrics(np.zeros(4, bool), np.zeros(4, bool)), TypeError, "alarms must be a sequence"),
    (lambda: sensor_validation_metrics([[0, 1]], [[0, 1], [0, 1]]), ValueError, "same number of records"),
    (lambda: sensor_validation_metrics([[0, 1], [0]], [[0, 1], [0, 1]]), ValueError, "record 1: alarm and labels"),
    (lambda: sensor_validation_metrics([[0, 1]], [[0, 1]], times=[]), ValueError, "times must hold one time axis"),
])
def test_bad_input(call, exc, match):
    with pytest.raises(exc, match=match):
        call()

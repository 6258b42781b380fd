"""The guide's PX4 example (docs/guide/online.md, issue 34): body rates against the actuator controls of
``data/px4/sample.ulg`` with the autopilot-log recipe, the constructor's defaults -- every axis arms within 10 s of
the start and nothing alarms -- and the warning of a pair that never arms."""

import warnings
from pathlib import Path

import numpy as np
import pytest

import tsfdi
from tsfdi.exceptions import ConvergenceWarning
from tsfdi.online import OnlineDetector

pytest.importorskip("pyulog")
SAMPLE = Path(__file__).resolve().parents[1] / "data" / "px4" / "sample.ulg"


def rates_and_controls(fs=50):
    topics = tsfdi.datasets.read_ulog(SAMPLE, ["vehicle_attitude", "actuator_controls_0"])
    records = tsfdi.align({"rates": topics["vehicle_attitude"][["rollspeed", "pitchspeed", "yawspeed"]],
                           "controls": topics["actuator_controls_0"][["control[0]", "control[1]", "control[2]"]]},
                          fs=fs)
    return [(r.iloc[:, :3], r.iloc[:, 3:]) for r in records]


def test_the_guide_px4_example_arms_within_10_s_and_raises_no_alarm():
    records = rates_and_controls()
    assert [len(y) for y, _ in records] == [2060, 1378]        # align splits the log at a logging gap (41 s)
    y, u = records[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        out = OnlineDetector(["roll", "pitch", "yaw"]).run(y, u)
    armed = out.first_alarms["armed_at"].to_numpy() / out.fs
    assert np.all((armed > 0) & (armed < 10.0)), armed
    assert out.first_alarm is None and not out.alarm.any()


def test_a_pair_that_never_arms_is_named_with_what_to_change():
    y, u = rates_and_controls()[1]              # the vehicle lies still: the yaw rate is noise around a constant
    with pytest.warns(ConvergenceWarning, match="pair 'yaw' has not armed") as caught:
        OnlineDetector(["roll", "pitch", "yaw"]).run(y, u)
    assert "actuator control" in str(caught[0].message)

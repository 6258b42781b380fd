"""list_crazypad / load_crazypad / read_crazypad_log on the shared CrazyPAD copy (skipped when
../shared/data/crazypad is missing, see ``shared_crazypad`` in conftest.py; what they expect is read from its
``flights.csv`` and its files) and on small synthetic logs."""

import gzip
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tsfdi.datasets import list_crazypad, load_crazypad, read_crazypad_log

THRUST = "controller.cmd_thrust"
MOTORS = ["motor.m1", "motor.m2", "motor.m3", "motor.m4"]
RATES = ["controller.r_roll", "controller.r_pitch", "controller.r_yaw"]


@pytest.fixture(scope="module")
def root(shared_crazypad) -> Path:
    return shared_crazypad


@pytest.fixture(scope="module")
def flights(root) -> pd.DataFrame:
    """The copy's own table of its controller logs: what the tests on the copy expect."""
    return pd.read_csv(root / "flights.csv")


@pytest.fixture(scope="module")
def table(root) -> pd.DataFrame:
    return list_crazypad(root)


def motor_files(root: Path, condition: str = "*") -> list[Path]:
    """The motor logs on disk (flights.csv lists the controller logs only)."""
    return sorted(root.glob(f"motor/{condition}/*.csv.gz"))


def _write_log(path: Path, t_ms, thrust, *, extra=None) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    cols = {"timestamp": t_ms, "stateEstimate.z": np.linspace(0, 1, len(t_ms)), THRUST: thrust,
            "controller.r_roll": np.sin(np.arange(len(t_ms)) / 7.0)}
    cols.update(extra or {})
    pd.DataFrame(cols).to_csv(path, index=False)
    return path


def test_listing_matches_the_flight_table(root, flights, table):
    ctrl = table[table.kind == "controller"]
    assert list(table.columns) == ["kind", "condition", "drone", "log", "rows", "duration_s", "file"]
    assert ctrl.groupby("condition").size().to_dict() == flights.groupby("condition").size().to_dict()
    merged = ctrl.merge(flights, on=["condition", "drone", "log"], suffixes=("", "_ref"), validate="1:1")
    assert len(merged) == len(flights) == len(ctrl)
    assert (merged.rows == merged.rows_ref).all()
    np.testing.assert_allclose(merged.duration_s, merged.duration_s_ref, atol=0.006)
    assert all(Path(f).is_file() for f in table.file)
    # motor logs: a separate kind, numbered independently
    motor = list_crazypad(root, kind="motor")
    on_disk = motor_files(root)
    assert on_disk and sorted(Path(f) for f in motor.file) == on_disk
    assert (motor.kind == "motor").all() and len(motor) == (table.kind == "motor").sum() == len(on_disk)
    assert motor.groupby("condition").size()["normal_flight"] == len(motor_files(root, "normal_flight"))
    assert list_crazypad(str(root), kind="controller").equals(ctrl.reset_index(drop=True))


def test_airborne_segments_are_trimmed_by_the_margin(table):
    normal = table[(table.kind == "controller") & (table.condition == "normal_flight")]
    for r in normal.itertuples():
        whole = read_crazypad_log(r.file, airborne=False)[0]
        assert len(whole) == r.rows and whole.attrs["segment"] is None
        segs = read_crazypad_log(r.file)
        # the programme takes off twice: two airborne segments per log
        assert [s.attrs["segment"] for s in segs] == [0, 1]
        for seg in segs:
            a, b = seg.attrs["thrust_on"]
            assert seg.attrs["margin"] == (pd.Timedelta("1s"), pd.Timedelta("1s"))
            # exactly the logged samples inside [first thrust + 1 s, last thrust - 1 s]
            t = whole.index
            expected = whole[(t >= a + pd.Timedelta("1s")) & (t <= b - pd.Timedelta("1s"))]
            pd.testing.assert_frame_equal(seg, expected)
            assert (seg[THRUST] > 0).all()
            assert (whole.loc[a:b, THRUST] > 0).all()
            # the thrust is off right before and after the run (or the log ends)
            i, j = t.get_loc(a), t.get_loc(b)
            assert i == 0 or whole[THRUST].iloc[i - 1] <= 0
            assert j == len(t) - 1 or whole[THRUST].iloc[j + 1] <= 0
            assert 6.0 < (seg.index[-1] - seg.index[0]).total_seconds() < 7.5
    # an asymmetric margin (climb, landing) and no margin
    f = normal.file.iloc[0]
    seg0 = read_crazypad_log(f, margin=("2.5s", "0.5s"))[0]
    a, b = seg0.attrs["thrust_on"]
    assert seg0.index[0] >= a + pd.Timedelta("2.5s") and seg0.index[-1] <= b - pd.Timedelta("0.5s")
    assert seg0.index[0] - (a + pd.Timedelta("2.5s")) < pd.Timedelta("20ms")
    full = read_crazypad_log(f, margin="0s")[0]
    assert (full.index[0], full.index[-1]) == (a, b)


def test_motor_logs_use_the_motor_commands(table):
    r = table[(table.kind == "motor") & (table.condition == "normal_flight")].iloc[0]
    segs = read_crazypad_log(r.file, margin=pd.Timedelta("500ms"))
    assert len(segs) == 2
    for seg in segs:
        assert seg.attrs["kind"] == "motor" and (seg[MOTORS].max(axis=1) > 0).all()
        assert "pm.vbatMV" in seg and seg["pm.vbatMV"].dtype == np.float64


def test_index_fs_attrs_and_values(root, flights, table):
    recs = load_crazypad(root, condition="normal_flight")
    normal = flights[flights.condition == "normal_flight"]
    assert len(recs) == 2 * len(normal)  # 2 airborne segments per log
    assert [(d.attrs["drone"], d.attrs["log"]) for d in recs[::2]] == list(zip(normal.drone, normal.log))
    raw = pd.read_csv(table[(table.kind == "controller") & (table.condition == "normal_flight")].file.iloc[0])
    for df in recs:
        a = df.attrs
        assert isinstance(df.index, pd.TimedeltaIndex) and df.index.name == "time"
        assert df.index.is_monotonic_increasing and df.index.is_unique
        assert 99.0 < a["fs"] < 102.0 and a["gaps"] == []
        assert (df.dtypes == np.float64).all() and "timestamp" not in df.columns
        assert a["condition"] == "normal_flight" and a["kind"] == "controller"
        assert a["log"].startswith(a["drone"] + "_log") and Path(a["file"]).name == a["log"] + ".csv.gz"
        assert a["onset"] is None and a["faulty"] is False and "10.3390/data9060079" in a["citation"]
    first = recs[0]
    # times relative to the log's first sample; values as logged
    t = (raw.timestamp - raw.timestamp.iloc[0]).to_numpy()
    k = int(np.searchsorted(t, first.index[0].total_seconds() * 1000 - 1e-6))
    np.testing.assert_allclose(first.index.total_seconds().to_numpy() * 1000, t[k:k + len(first)], atol=1e-6)
    np.testing.assert_array_equal(first[RATES].to_numpy(), raw[RATES].to_numpy()[k:k + len(first)])
    # a faulty condition, selection by drone, a column subset
    e9 = load_crazypad(root, condition=["cut_propeller_M3_1mm"], drone="E9", columns=RATES)
    n_e9 = ((flights.condition == "cut_propeller_M3_1mm") & (flights.drone == "E9")).sum()
    assert n_e9 > 0 and len(e9) == 2 * n_e9 and all(d.attrs["drone"] == "E9" and d.attrs["faulty"] for d in e9)
    assert all(list(d.columns) == RATES for d in e9)
    whole = load_crazypad(root, condition="normal_flight", airborne=False, columns="controller.accelz")
    assert [len(d) for d in whole] == list(table[(table.kind == "controller")
                                                 & (table.condition == "normal_flight")].rows)
    assert all(d.attrs["margin"] is None for d in whole)
    motor = load_crazypad(root, kind="motor", condition="normal_flight")
    assert len(motor) == 2 * len(motor_files(root, "normal_flight")) and all(d.attrs["kind"] == "motor" for d in motor)


def test_gaps_on_a_synthetic_log(tmp_path):
    t = np.arange(800) * 10.0 + 5000.0  # ms since boot, 100 Hz
    t[300:] += 290.0  # a 300 ms spacing inside the flight
    t[50:] += 140.0   # a 150 ms spacing on the ground
    thrust = np.where((np.arange(800) >= 100) & (np.arange(800) < 700), 40000.0, 0.0)
    f = _write_log(tmp_path / "controller" / "my_condition" / "E1_log07.csv", t, thrust)
    (seg,) = read_crazypad_log(f)
    a = seg.attrs
    assert (a["condition"], a["drone"], a["log"], a["kind"]) == ("my_condition", "E1", "E1_log07", "controller")
    assert a["faulty"] is True
    np.testing.assert_allclose(a["fs"], 100.0)
    t0 = pd.to_timedelta(np.rint((t - t[0]) * 1e6).astype(np.int64), unit="ns")
    assert a["thrust_on"] == (t0[100], t0[699])
    assert a["gaps"] == [(t0[299], pd.Timedelta("300ms"))]
    # exactly the logged samples inside the trimmed span: none invented across the gap
    np.testing.assert_array_equal(seg.index, t0[(t0 >= t0[100] + pd.Timedelta("1s"))
                                                 & (t0 <= t0[699] - pd.Timedelta("1s"))])
    (whole,) = read_crazypad_log(f, airborne=False)
    assert [d for _, d in whole.attrs["gaps"]] == [pd.Timedelta("150ms"), pd.Timedelta("300ms")]
    # a short hop shrinks to nothing and is dropped; a thrust dropout splits the flight
    thrust2 = thrust.copy()
    thrust2[400] = 0.0
    thrust2[720:760] = 30000.0
    g = _write_log(tmp_path / "controller" / "my_condition" / "E1_log08.csv.gz", t, thrust2)
    segs = read_crazypad_log(g)
    assert [s.attrs["segment"] for s in segs] == [0, 1] and all((s[THRUST] > 0).all() for s in segs)
    assert load_crazypad(tmp_path, drone="E1")[0].attrs["log"] == "E1_log07"


def test_repository_layout(tmp_path, table):
    # the GitHub repository keeps plain CSV files under data/controller_data/<condition>/
    src = Path(table[(table.kind == "controller") & (table.condition == "normal_flight")].file.iloc[0])
    dst = tmp_path / "data" / "controller_data" / "normal_flight" / src.name.replace(".csv.gz", ".csv")
    dst.parent.mkdir(parents=True)
    with gzip.open(src, "rb") as fin, open(dst, "wb") as fout:
        shutil.copyfileobj(fin, fout)
    (dst.parent / "E8_log00").write_bytes(b"\x00\x01binary log")  # undecoded logs are ignored
    tab = list_crazypad(tmp_path)
    assert len(tab) == 1 and tab.kind[0] == "controller" and tab.log[0] == "E8_log00"
    for base in (tmp_path, tmp_path / "data"):
        recs = load_crazypad(base)
        assert len(recs) == 2
        pd.testing.assert_frame_equal(recs[0], read_crazypad_log(src)[0], check_like=False)


def test_missing_and_bad_paths(tmp_path):
    with pytest.raises(ValueError, match="AerialRoboticsUUST/CrazyPAD"):
        list_crazypad()
    with pytest.raises(ValueError, match="AerialRoboticsUUST/CrazyPAD"):
        load_crazypad(condition="normal_flight")
    with pytest.raises(TypeError, match="path"):
        list_crazypad(3)
    missing = tmp_path / "nowhere"
    with pytest.raises(FileNotFoundError, match="nowhere"):
        list_crazypad(missing)
    with pytest.raises(FileNotFoundError, match="nowhere"):
        load_crazypad(missing)
    with pytest.raises(FileNotFoundError, match="nope.csv"):
        read_crazypad_log(tmp_path / "nope.csv")
    with pytest.raises(ValueError, match="not a CrazyPAD folder"):
        list_crazypad(tmp_path)
    only = tmp_path / "only"
    f = _write_log(only / "controller" / "c" / "E1_log00.csv", np.arange(10.0), np.ones(10))
    with pytest.raises(ValueError, match="read_crazypad_log"):
        load_crazypad(f)
    with pytest.raises(ValueError, match="load_crazypad"):
        read_crazypad_log(only)
    with pytest.raises(ValueError, match="no motor log"):
        load_crazypad(only, kind="motor")


def test_bad_files(tmp_path):
    t = np.arange(300) * 10.0
    thrust = np.r_[np.zeros(50), np.full(200, 1.0), np.zeros(50)]
    d = tmp_path / "controller" / "c"
    no_time = _write_log(d / "E1_log00.csv", t, thrust)
    pd.read_csv(no_time).drop(columns="timestamp").to_csv(no_time, index=False)
    with pytest.raises(ValueError, match=r"E1_log00\.csv.*'timestamp'"):
        read_crazypad_log(no_time)
    with pytest.raises(ValueError, match=r"E1_log00\.csv.*'timestamp'"):
        list_crazypad(tmp_path)
    no_time.unlink()
    no_thrust = _write_log(d / "E1_log01.csv", t, thrust)
    pd.read_csv(no_thrust).drop(columns=THRUST).to_csv(no_thrust, index=False)
    with pytest.raises(ValueError, match=r"E1_log01\.csv.*'controller\.cmd_thrust'"):
        read_crazypad_log(no_thrust)
    with pytest.raises(ValueError, match=r"E1_log01\.csv.*'controller\.cmd_thrust'"):
        read_crazypad_log(no_thrust, airborne=False)
    motor = tmp_path / "motor" / "c" / "E1_log02.csv"
    motor.parent.mkdir(parents=True)
    pd.DataFrame({"timestamp": t, "motor.m1": thrust, "motor.m2": thrust, "motor.m4": thrust}).to_csv(motor,
                                                                                                     index=False)
    with pytest.raises(ValueError, match=r"E1_log02\.csv.*'motor\.m3'"):
        read_crazypad_log(motor)
    stray = tmp_path / "stray.csv"
    pd.DataFrame({"timestamp": t, "x": t}).to_csv(stray, index=False)
    with pytest.raises(ValueError, match=r"stray\.csv.*controller\.cmd_thrust"):
        read_crazypad_log(stray)
    back = t.copy()
    back[120] = back[118]
    shuffled = _write_log(d / "E1_log03.csv", back, thrust)
    with pytest.raises(ValueError, match=r"E1_log03\.csv.*not strictly increasing.*row 120"):
        read_crazypad_log(shuffled)
    nan_t = t.copy()
    nan_t[5] = np.nan
    with pytest.raises(ValueError, match=r"E1_log04\.csv.*NaN"):
        read_crazypad_log(_write_log(d / "E1_log04.csv", nan_t, thrust))
    for name, text, message in [
            ("E1_log05.csv", "timestamp,controller.cmd_thrust\nsoon,1\nlater,1\n", r".*'timestamp' is not numeric"),
            ("E1_log06.csv", "", r" is empty"),
            ("E1_log07.csv", "timestamp,controller.cmd_thrust\n", r" holds no samples"),
            ("E1_log08.csv", "timestamp,controller.cmd_thrust,x\n1,1,a\n2,1,b\n", r".*'x' is not numeric")]:
        (d / name).write_text(text)
        with pytest.raises(ValueError, match=re.escape(name) + message):
            read_crazypad_log(d / name)


def test_bad_options(root, flights, table):
    f = table.file.iloc[0]
    with pytest.raises(ValueError, match=r"condition.*'no_such'.*available.*normal_flight"):
        load_crazypad(root, condition="no_such")
    drones = sorted(set(flights.drone))
    assert "E7" not in drones
    with pytest.raises(ValueError, match=r"drone.*'E7'.*available: " + re.escape(str(drones))):
        load_crazypad(root, drone=[drones[0], "E7"])
    # a condition and a drone the copy holds, never flown together (e.g. E9 alone flew the cut_M2_* series)
    flown = set(zip(flights.condition, flights.drone))
    condition, drone = next((c, d) for c in sorted(set(flights.condition)) for d in drones if (c, d) not in flown)
    with pytest.raises(ValueError, match=rf"no controller log of condition \['{re.escape(condition)}'\] and drone "
                                         rf"\['{drone}'\]; available.*'{re.escape(condition)}'"):
        load_crazypad(root, condition=condition, drone=drone)
    with pytest.raises(TypeError, match="condition"):
        load_crazypad(root, condition=3)
    with pytest.raises(ValueError, match="kind"):
        load_crazypad(root, kind="imu")
    with pytest.raises(ValueError, match="kind"):
        list_crazypad(root, kind="imu")
    with pytest.raises(ValueError, match=r"columns.*'controller\.nope'.*available"):
        read_crazypad_log(f, columns=["controller.r_roll", "controller.nope"])
    with pytest.raises(ValueError, match="columns"):
        read_crazypad_log(f, columns=["timestamp"])
    with pytest.raises(TypeError, match="columns"):
        read_crazypad_log(f, columns=3)
    with pytest.raises(TypeError, match="margin"):
        read_crazypad_log(f, margin=1.0)
    with pytest.raises(ValueError, match="margin"):
        read_crazypad_log(f, margin="-1s")
    with pytest.raises(ValueError, match="margin"):
        read_crazypad_log(f, margin="soon")
    with pytest.raises(ValueError, match="margin"):
        load_crazypad(root, margin=("1s",))
    with pytest.raises(TypeError, match="file"):
        read_crazypad_log(None)

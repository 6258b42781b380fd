"""load_alfa / list_alfa on the shared ALFA copies (skipped when ../shared/data/alfa is missing, see
``shared_alfa`` in conftest.py), and their refusals of bad input (no data needed)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from tsfdi.datasets.alfa import list_alfa, load_alfa


@pytest.fixture(scope="module")
def root(shared_alfa) -> Path:
    return shared_alfa


def test_every_merged_flight_matches_the_flight_table(root):
    tab = list_alfa(root)
    assert len(tab) == 45 and (tab.fault != "none").sum() == 36
    for r in tab.itertuples():
        df = load_alfa(r.merged_path)
        a = df.attrs
        assert a["fault"] == r.fault and a["layout"] == "merged_20hz" and a["flight"] == r.flight
        assert "field.data" not in df.columns and df["ground_truth"].dtype == bool
        assert len(df) == r.rows
        np.testing.assert_allclose(a["fs"], 20.0, rtol=1e-6)
        if r.fault == "none":
            assert a["onset_s"] is None and not df["ground_truth"].any()
        else:
            np.testing.assert_allclose(a["onset_s"], r.onset_s, atol=1e-9)
            assert a["failure_code"] == r.failure_code
            first = int(np.argmax(df["ground_truth"].to_numpy()))
            assert df.index[first] == a["onset_time"] and df["ground_truth"].iloc[first:].all()


def test_engine_commanded_measured(root):
    tab = list_alfa(root)
    eng = tab.dropna(subset=["engine_path"])
    assert len(eng) == 7
    df = load_alfa(eng.engine_path.iloc[0])
    assert df.attrs["fault"] == "engine" and df.attrs["layout"] == "engine_commanded_measured"
    assert {"roll_commanded", "roll_measured", "pitch_commanded", "pitch_measured"} <= set(df.columns)
    assert "label" not in df.columns and "throttle" in df.attrs["leaking_columns"]
    # onset agrees with the merged copy's to within one sample of either grid
    np.testing.assert_allclose((df.attrs["onset_time"] - pd.Timestamp(df.index[0])).total_seconds(),
                               df.attrs["onset_s"])
    merged = load_alfa(eng.merged_path.iloc[0])
    assert abs((df.attrs["onset_time"] - merged.attrs["onset_time"]).total_seconds()) < 0.1


def test_official_layout_sample(root):
    folder = root / "official_format_sample"
    df = load_alfa(folder)
    a = df.attrs
    assert a["layout"] == "official" and a["fault"] == "engine" and a["failure_code"] == 1
    assert a["flight"] == "carbonZ_2018-07-18-15-53-31_1_engine_failure"
    # the onset is the first failure_status-engines message
    fs = pd.read_csv(folder / f"{a['flight']}-failure_status-engines.csv.gz")
    assert a["onset_time"] == pd.Timestamp(int(fs["%time"].min()), unit="ns")
    np.testing.assert_allclose(a["onset_s"], 116.26, atol=0.05)  # flights.csv: alfa_ground_truth 116.259
    assert 19.0 < a["fs"] < 21.0
    for col in ("nav_info-roll.commanded", "nav_info-roll.measured", "nav_info-pitch.commanded",
                "imu-data.angular_velocity.x", "nav_info-errors.aspd_error"):
        assert col in df.columns
    assert "rc-out.channels0" in a["leaking_columns"] and "vfr_hud.throttle" in a["leaking_columns"]
    # aligned without look-ahead: every value is the last message at or before the row's time stamp
    roll = pd.read_csv(folder / f"{a['flight']}-mavros-nav_info-pitch.csv.gz")
    t = pd.to_datetime(roll["%time"].to_numpy(), unit="ns")
    k = 1000
    pos = np.searchsorted(t.values, df.index.values[k], side="right") - 1
    assert df["nav_info-pitch.commanded"].iloc[k] == roll["field.commanded"].iloc[pos]
    # the same flight in the engine commanded/measured copy has the same commanded roll series
    eng = load_alfa(root / "engine_commanded_measured" / f"{a['flight']}.csv.gz")
    np.testing.assert_allclose(df["nav_info-roll.commanded"].to_numpy()[:5], eng["roll_commanded"].to_numpy()[:5])


def test_xarray_output(root):
    ds = load_alfa(root / "official_format_sample", kind="xarray")
    assert isinstance(ds, xr.Dataset) and ds.attrs["fault"] == "engine"
    assert "nav_info-roll.commanded" in ds and ds["ground_truth"].dtype == bool


def test_bad_options_on_the_copy(root):
    with pytest.raises(ValueError, match="kind"):
        load_alfa(root / "official_format_sample", kind="polars")
    with pytest.raises(ValueError, match="flight"):
        load_alfa(root / "official_format_sample", flight="nope")


def test_bad_input(tmp_path):
    with pytest.raises(FileNotFoundError, match="alfa-dataset"):
        load_alfa(tmp_path / "missing")
    with pytest.raises(ValueError, match="not an official"):
        load_alfa(tmp_path)
    with pytest.raises(TypeError, match="path"):
        load_alfa(3)
    bad = tmp_path / "x.csv"
    bad.write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="neither"):
        load_alfa(bad)
    with pytest.raises(FileNotFoundError, match="flights.csv"):
        list_alfa(tmp_path)

"""The small real samples shipped in ``data/`` (PX4, CrazyPAD, ALFA) load with the library's readers, hold what
``data/README.md`` says (rows, rates, labels) and are tracked by git, with no ``../shared`` needed."""

from __future__ import annotations

import hashlib
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tsfdi.datasets import list_alfa, list_crazypad, load_alfa, load_crazypad, read_crazypad_log, read_ulog

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data"
README = (DATA / "README.md").read_text()

ENGINE = "carbonZ_2018-07-18-15-53-31_1_engine_failure"
NO_FAILURE = "carbonZ_2018-07-18-16-37-39_1_no_failure"
#: every sample file (path under data/) with the licence file that must stay beside it
SAMPLES = {
    "px4/sample.ulg": "px4/LICENSE.md",
    "crazypad/flights.csv": "crazypad/LICENSE",
    "crazypad/controller/normal_flight/E8_log00.csv.gz": "crazypad/LICENSE",
    "crazypad/controller/normal_flight/E8_log01.csv.gz": "crazypad/LICENSE",
    "crazypad/controller/cut_propeller_M3_4mm_4mm_39mm/E8_log00.csv.gz": "crazypad/LICENSE",
    "alfa/flights.csv": None,   # CC BY 4.0 asks for credit and a link to the licence: in data/README.md
    f"alfa/merged_20hz/engine/{ENGINE}.csv.gz": None,
    f"alfa/merged_20hz/no_failure/{NO_FAILURE}.csv.gz": None,
    f"alfa/engine_commanded_measured/{ENGINE}.csv.gz": None,
}


def test_every_sample_is_listed_licensed_and_small():
    shipped = {p.relative_to(DATA).as_posix() for p in DATA.rglob("*") if p.is_file()}
    samples = {p for p in shipped if p.split("/")[0] in ("px4", "crazypad", "alfa")}
    licences = {v for v in SAMPLES.values() if v}
    assert samples == set(SAMPLES) | licences, sorted(samples ^ (set(SAMPLES) | licences))
    for name in SAMPLES:
        assert name.split("/")[-1] in README, f"data/README.md does not describe {name}"
    assert "BSD 3-Clause" in README and "MIT" in README and "creativecommons.org/licenses/by/4.0" in README
    assert "Redistributions of source code must retain" in (DATA / "px4" / "LICENSE.md").read_text()
    assert "Masalimov" in (DATA / "crazypad" / "LICENSE").read_text()
    size = sum((DATA / name).stat().st_size for name in samples)
    assert size < 6e6, f"the samples hold {size / 1e6:.1f} MB; keep them to a few MB"


def test_git_tracks_the_samples():
    """No ignore rule drops a sample (a fresh clone would lack it)."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    names = [f"data/{n}" for n in [*SAMPLES, *{v for v in SAMPLES.values() if v}]]
    ignored = subprocess.run(["git", "check-ignore", *names], cwd=ROOT, capture_output=True, text=True)
    assert ignored.returncode == 1 and not ignored.stdout, f"ignored by git: {ignored.stdout}"


def test_px4_log():
    pytest.importorskip("pyulog")
    logs = read_ulog(DATA / "px4" / "sample.ulg")
    assert len(logs) == 15
    gyro = logs["sensor_combined"]
    assert len(gyro) == 17_070
    steps = gyro.index.to_series().diff().dt.total_seconds()
    assert steps.median() == pytest.approx(1 / 250)
    assert 68.9 < gyro.index[-1].total_seconds() < 69.1
    for part in ("69 s", "15 topics", "17,070 samples at 250 Hz"):
        assert part in README


def test_crazypad_logs():
    root = DATA / "crazypad"
    table = list_crazypad(root)
    flights = pd.read_csv(root / "flights.csv")
    assert len(flights) == 3 and set(table["kind"]) == {"controller"}
    merged = table.merge(flights, on=["condition", "drone", "log"], suffixes=("", "_table"), validate="1:1")
    assert len(merged) == 3
    np.testing.assert_array_equal(merged["rows"], merged["rows_table"])
    np.testing.assert_allclose(merged["duration_s"], merged["duration_s_table"], atol=0.006)
    assert sorted(table["condition"]) == ["cut_propeller_M3_4mm_4mm_39mm", "normal_flight", "normal_flight"]
    for r in merged.itertuples():
        assert f"{r.rows:,}" in README and f"{r.duration_s_table:.2f} s" in README

    records = load_crazypad(root)
    assert [(r.attrs["condition"], r.attrs["log"], r.attrs["segment"]) for r in records] == [
        ("cut_propeller_M3_4mm_4mm_39mm", "E8_log00", 0), ("cut_propeller_M3_4mm_4mm_39mm", "E8_log00", 1),
        ("normal_flight", "E8_log00", 0), ("normal_flight", "E8_log00", 1),
        ("normal_flight", "E8_log01", 0), ("normal_flight", "E8_log01", 1)]
    assert [r.attrs["faulty"] for r in records] == [True, True, False, False, False, False]
    assert [len(r) for r in records] == [665, 731, 665, 730, 664, 731]
    assert "665 / 730 samples" in README
    for r in records:
        assert 100.5 < r.attrs["fs"] < 101.5 and r.attrs["gaps"] == []
        assert (r["controller.cmd_thrust"] > 0).all()
    # the damage shows in the trims the controller settles on: the cut log's mean roll command is far above
    normal = load_crazypad(root, condition="normal_flight", columns="controller.cmd_roll")
    (cut,) = read_crazypad_log(root / "controller" / "cut_propeller_M3_4mm_4mm_39mm" / "E8_log00.csv.gz",
                               airborne=False)
    assert len(cut) == 2606
    assert max(r["controller.cmd_roll"].mean() for r in normal) < 1000 < 9000 < records[0]["controller.cmd_roll"].mean()


def test_alfa_flights():
    table = list_alfa(DATA / "alfa")
    assert table["flight"].tolist() == [ENGINE, NO_FAILURE]
    assert table["engine_path"].notna().tolist() == [True, False]
    assert all(Path(p).is_file() for p in table["merged_path"])

    engine = load_alfa(table["merged_path"][0])
    assert (len(engine), engine.attrs["fs"], engine.attrs["fault"], engine.attrs["failure_code"]) == \
        (2646, 20.0, "engine", 1)
    assert engine.attrs["onset_s"] == pytest.approx(116.25)
    assert engine.attrs["onset_s"] == pytest.approx(table["onset_s"][0])
    assert not engine["ground_truth"].iloc[:2325].any() and engine["ground_truth"].iloc[2325:].all()
    assert (engine.index[-1] - engine.index[0]).total_seconds() == pytest.approx(132.25)

    none = load_alfa(table["merged_path"][1])
    assert (len(none), none.attrs["fs"], none.attrs["fault"], none.attrs["onset_s"]) == (607, 20.0, "none", None)
    assert not none["ground_truth"].any()
    assert (none.index[-1] - none.index[0]).total_seconds() == pytest.approx(30.3)

    pair = load_alfa(table["engine_path"][0])
    assert (len(pair), pair.attrs["fault"], round(pair.attrs["onset_s"], 2)) == (2531, "engine", 116.30)
    assert 20.1 < pair.attrs["fs"] < 20.25
    assert {"roll_commanded", "roll_measured", "throttle"} <= set(pair.columns)
    assert "throttle" in pair.attrs["leaking_columns"]
    for part in ("2,646 at 20 Hz (132.25 s)", "engine (code 1) at 116.25 s", "2,531 (raw stamps, median 20.2 Hz)",
                 "engine at 116.30 s", "607 at 20 Hz (30.3 s)"):
        assert part in README


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_samples_are_the_shared_files_unchanged(shared_data):
    """Provenance: each sample is byte for byte the file of the developers' fuller copy (rows of its table)."""
    for name in SAMPLES:
        if name.endswith("flights.csv"):
            full = pd.read_csv(shared_data / name, dtype=str, keep_default_na=False)
            sub = pd.read_csv(DATA / name, dtype=str, keep_default_na=False)
            key = ["flight"] if "flight" in sub else ["condition", "drone", "log"]
            pd.testing.assert_frame_equal(sub, full.merge(sub[key], on=key)[list(sub.columns)]
                                          .sort_values(key, ignore_index=True))
        else:
            assert _sha256(DATA / name) == _sha256(shared_data / name), name

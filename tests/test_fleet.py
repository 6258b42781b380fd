"""Fleets on dask (issue 21): records backed by dask, chunked along ``record``, through evaluate, fit_baselines,
Monitor.screen and ``tsfdi simulate`` on the current dask scheduler give the results of the same records in memory,
bit for bit, and the driver does not hold the records."""

from __future__ import annotations

import pickle
import re
import textwrap
import tracemalloc
from pathlib import Path

import dask
import dask.array as da
import numpy as np
import pandas as pd
import pytest
import xarray as xr
from _synthetic_fdi import FS, SYSTEMS, record
from distributed import Client, LocalCluster, get_task_stream

import tsfdi
from tsfdi import LjungBox
from tsfdi.cli import main
from tsfdi.datasets import make_hexacopter_dataset
from tsfdi.datasets.hexacopter import FleetSpread
from tsfdi.fleet import is_chunked, map_records, record_chunks

DESIGN = dict(duration=20.0, failure_time=2.0, turbulence=("light", "severe"))
TESTS = {"whiteness": LjungBox(lags=10, alpha=1e-3), "empirical": LjungBox(lags=10, alpha=0.05, correction="none",
                                                                                 threshold="empirical")}
OPTIONS = dict(models=("var", "roll"), tests=TESTS, windows=("5s", "10s"), settle=5.0,
               rules=("paper", "likelihood", "pvalue"), progress=False)


@pytest.fixture(scope="module")
def fleet():
    """24 hexacopter records in memory: 3 per state and turbulence level, 20 s, failure at 2 s."""
    return make_hexacopter_dataset(3, **DESIGN)


def _fit(data):
    return tsfdi.fit_baselines(data, settle=5.0, duration=None, models=("var", "roll"), max_lags=8, var_max_lags=8,
                               fit_records=1, calibrate=True, steady_window="5s")


@pytest.fixture(scope="module")
def baselines(fleet):
    return _fit(fleet)


@pytest.fixture(scope="module")
def serial(fleet, baselines):
    return tsfdi.evaluate(fleet, baselines, **OPTIONS)


def assert_same_evaluation(a, b):
    for name in ("identification_counts", "detection_counts", "detection_delays", "records", "calibration"):
        pd.testing.assert_frame_equal(getattr(a, name), getattr(b, name), check_exact=True, obj=name)
    assert (a.faults, a.rules, a.alphas, a.lags, a.nchan, a.thresholds) == \
        (b.faults, b.rules, b.alphas, b.lags, b.nchan, b.thresholds)
    assert str(a.summary()) == str(b.summary())


def assert_same_baselines(a, b):
    pd.testing.assert_frame_equal(a.table, b.table, check_exact=True)
    assert a.fit_records == b.fit_records and a.channels == b.channels and a.fs == b.fs
    np.testing.assert_array_equal(a.steady_thresholds, b.steady_thresholds)
    assert a.heldout.keys() == b.heldout.keys()
    for key in a.heldout:
        for x, y in zip(a.heldout[key], b.heldout[key], strict=True):
            np.testing.assert_array_equal(x, y)
    for m in a.models:
        for s in a.models[m]:
            np.testing.assert_array_equal(a.models[m][s].params, b.models[m][s].params)


def test_local_cluster_equals_serial(fleet, baselines, serial, tmp_path):
    """Two worker processes (processes=True: everything a worker gets is pickled) reading a zarr store."""
    fleet.chunk(record=5).to_zarr(tmp_path / "fleet.zarr", zarr_format=2)
    stored = xr.open_zarr(tmp_path / "fleet.zarr")
    assert is_chunked(stored) and len(record_chunks(stored)) == 5
    monitor = baselines.monitor("var", window="10s", test=LjungBox(lags=10, alpha=1e-3))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster):
        assert_same_evaluation(serial, tsfdi.evaluate(stored, baselines, **OPTIONS))
        with get_task_stream() as stream:
            assert_same_evaluation(serial, tsfdi.evaluate(stored, baselines, **OPTIONS))   # the baselines sent before
        lazy_baselines = _fit(stored)
        screened = monitor.screen(stored)
    # one task per chunk of records, which reads them (issue 36: the reads and the per-record labels were ~16 tasks
    # of the cluster's graph per chunk); the labels are read by the driver, the first record (channels, length) by
    # a few tasks
    tasks = [t["key"] if isinstance(t["key"], str) else t["key"][0] for t in stream.data]
    assert sum(k.startswith("_read_call-") for k in tasks) == 5 and len(tasks) <= 5 + 8, tasks
    assert_same_baselines(baselines, lazy_baselines)
    pd.testing.assert_frame_equal(baselines.select_alpha("var", window="10s"),
                                  lazy_baselines.select_alpha("var", window="10s"), check_exact=True)
    pd.testing.assert_frame_equal(screened, monitor.screen(stored.compute()), check_exact=True)
    pd.testing.assert_frame_equal(screened[monitor.screen(fleet).columns], monitor.screen(fleet), check_exact=True)
    assert list(screened.index) == list(range(24)) and screened["windows"].eq(11).all()
    # the screen table scores records as paper 001 does: onset = failure time, first alarm = detection time
    scores = tsfdi.score_records(screened["failure_time"], screened["detection_time"])
    assert len(scores) == 24


def test_one_worker_equals_serial(fleet, baselines, serial):
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster):
        assert_same_evaluation(serial, tsfdi.evaluate(fleet.chunk(record=8), baselines, **OPTIONS))


@pytest.mark.parametrize("scheduler", ["synchronous", "threads"])
def test_local_schedulers_equal_serial(fleet, baselines, serial, scheduler):
    """The same fleet simulated chunk by chunk as it is evaluated (make_hexacopter_dataset(chunks=...))."""
    lazy = make_hexacopter_dataset(3, chunks=7, **DESIGN)
    assert is_chunked(lazy) and [s.stop - s.start for s in record_chunks(lazy)] == [7, 7, 7, 3]
    with dask.config.set(scheduler=scheduler):
        assert_same_evaluation(serial, tsfdi.evaluate(lazy, baselines, **{**OPTIONS, "progress": True}))


def test_baselines_per_turbulence_level(fleet):
    """Condition-scheduled baselines (a mapping level -> Baselines) on chunked data."""
    by_level = {lvl: tsfdi.fit_baselines(fleet, settle=5.0, duration=10.0, models=("var",), var_max_lags=6,
                                         fit_records=1, fit_turbulence=lvl) for lvl in ("light", "severe")}
    opts = dict(models=("var",), windows=("5s",), settle=5.0, progress=False)
    with dask.config.set(scheduler="threads"):
        assert_same_evaluation(tsfdi.evaluate(fleet, by_level, **opts),
                               tsfdi.evaluate(fleet.chunk(record=4), by_level, **opts))


def test_lost_control_and_nan_records_are_skipped_alike(fleet, baselines):
    """A record holding NaN (found by the worker that reads it) and one flagged lost_control are skipped as in
    memory."""
    bad = fleet.copy(deep=True)
    bad["roll"][10, 100] = np.nan
    bad["lost_control"][17] = True
    opts = {**OPTIONS, "tests": LjungBox(lags=10, alpha=1e-3)}
    ev = tsfdi.evaluate(bad, baselines, **opts)
    assert set(ev.records.loc[ev.records["skipped"] == "lost control / non-finite", "record"]) == {10, 17}
    assert_same_evaluation(ev, tsfdi.evaluate(bad.chunk(record=5), baselines, **opts))


def test_chunked_simulation_is_bit_identical():
    for fleet_spread in (None, FleetSpread()):
        eager = make_hexacopter_dataset(1, duration=2.0, failure_time=1.0, fleet=fleet_spread, turbulence=("severe",))
        lazy = make_hexacopter_dataset(1, duration=2.0, failure_time=1.0, fleet=fleet_spread, turbulence=("severe",),
                                       chunks=3)
        assert lazy["roll"].chunks == ((3, 1), (200,))
        xr.testing.assert_identical(eager, lazy.compute())
    with pytest.raises(TypeError, match="chunks"):
        make_hexacopter_dataset(1, chunks="3")
    with pytest.raises(TypeError, match="unexpected keyword"):
        make_hexacopter_dataset(1, chunks=3, wind=2.0)


@pytest.mark.parametrize("suffix", [".zarr", ".nc"])
def test_simulate_writes_chunked_storage(tmp_path, capsys, suffix):
    out = tmp_path / f"fleet{suffix}"
    args = ["simulate", "--out", str(out), "--records-per-case", "3", "--duration", "2s", "--failure-time", "1s",
            "--states", "healthy,rotor2", "--turbulence", "light", "--seed", "3", "--chunk", "4"]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert "wrote 6 records" in captured.out and "100% Completed" in captured.err     # dask's progress bar
    ref = make_hexacopter_dataset(3, seed=3, duration=2.0, failure_time=1.0, states=("healthy", "rotor2"),
                                  turbulence=("light",))
    with (xr.open_zarr(out) if suffix == ".zarr" else xr.open_dataset(out, engine="h5netcdf", chunks={})) as ds:
        for name in ("roll", "r", "lost_control", "failure_time", "seed"):
            np.testing.assert_array_equal(ds[name].values, ref[name].values, err_msg=name)
        assert list(ds["state"].values) == list(ref["state"].values)
        if suffix == ".zarr":          # chunked by record on disk; each label in one chunk (one read, issue 36)
            assert ds["roll"].data.chunks[0] == (4, 2)
            for name in ("lost_control", "lost_control_time", "failure_time", "seed", "state"):
                assert ds[name].chunks == ((6,),), name
                assert name in (ds.data_vars if name.startswith("lost") else ds.coords), name
    # the packed variables, and a cluster-less processes scheduler (zarr only)
    assert main(args[:2] + [str(tmp_path / "s.zarr")] + args[3:] + ["--shipped", "--no-progress"]) == 0
    with xr.open_zarr(tmp_path / "s.zarr", mask_and_scale=False) as ds:
        assert ds["roll"].dtype == np.int32 and "p" not in ds


def test_simulate_errors_name_the_flag(tmp_path, capsys):
    base = ["simulate", "--out", str(tmp_path / "x.nc"), "--duration", "1s", "--failure-time", "0.5s"]
    assert main(base + ["--scheduler", "cluster"]) == 2
    assert "--scheduler must be threads, processes, synchronous" in capsys.readouterr().err
    assert main(base + ["--scheduler", "processes"]) == 2
    assert "--scheduler processes cannot write a netCDF file" in capsys.readouterr().err
    assert main(base + ["--chunk", "0"]) == 2 and "--chunk" in capsys.readouterr().err
    assert not (tmp_path / "x.nc").exists()


def test_write_hexacopter_dataset_in_python(tmp_path):
    """write_hexacopter_dataset: what `tsfdi simulate` writes, from Python; it returns the per-record table."""
    from tsfdi.datasets.hexacopter import write_hexacopter_dataset

    design = dict(seed=3, duration=2.0, failure_time=1.0, states=("healthy", "rotor2"), turbulence=("light",))
    ref = make_hexacopter_dataset(2, **design)
    written = write_hexacopter_dataset(tmp_path / "a.nc", 2, **design)
    assert written.sizes["record"] == 4 and "time" not in written.dims and "roll" not in written
    np.testing.assert_array_equal(written["lost_control"].values, ref["lost_control"].values)
    assert list(written["state"].values) == list(ref["state"].values)
    with xr.open_dataset(tmp_path / "a.nc", engine="h5netcdf") as ds:
        xr.testing.assert_identical(ds[["roll", "p"]].load(), ref[["roll", "p"]])
    # chunked on dask to a zarr store, the shipped packing: the same records within the packing step
    write_hexacopter_dataset(tmp_path / "b.zarr", 2, shipped=True, chunks=3, scheduler="synchronous", **design)
    with xr.open_zarr(tmp_path / "b.zarr") as ds:
        assert "p" not in ds and ds["roll"].encoding["dtype"] == np.int32
        np.testing.assert_allclose(ds["roll"].values, ref["roll"].values, atol=0.5e-6, rtol=0)
    with pytest.raises(ValueError, match="chunks: .*zarr store"):
        write_hexacopter_dataset(tmp_path / "c.zarr", 1, **design)
    with pytest.raises(TypeError, match="path must be"):
        write_hexacopter_dataset(3, 1, **design)
    with pytest.raises(TypeError, match="shipped must be True or False"):
        write_hexacopter_dataset(tmp_path / "d.nc", 1, shipped="yes", **design)
    assert not (tmp_path / "c.zarr").exists() and not (tmp_path / "d.nc").exists()


# ------------------------------------------------------------------------------------------------- map_records
def _square(chunk, where, offset):
    if offset == "fail":
        raise ValueError("bad offset")
    return where, float((chunk["v"] ** 2).sum()) + offset


def test_map_records_in_order_with_arguments():
    v = np.arange(30.0).reshape(10, 3)
    data = xr.Dataset({"v": (("record", "time"), v)}).chunk(record=(4, 4, 2))
    for scheduler in ("synchronous", "threads"):
        with dask.config.set(scheduler=scheduler):
            out = list(map_records(_square, data, 1.0))
        assert [w for w, _ in out] == [slice(0, 4), slice(4, 8), slice(8, 10)]
        assert [s for _, s in out] == [float((v[w] ** 2).sum()) + 1.0 for w, _ in out]
    with pytest.raises(ValueError, match="bad offset"):
        list(map_records(_square, data, "fail"))
    with pytest.raises(TypeError, match="callable"):
        list(map_records(3, data))
    with pytest.raises(TypeError, match="'record' dimension"):
        record_chunks(np.zeros((3, 2)))
    assert not is_chunked(data.compute()) and record_chunks(data.compute()) == [slice(0, 10)]
    assert not is_chunked(v) and not is_chunked(data.rename(record="flight"))


def test_map_records_reads_a_zarr_store_whose_coordinates_are_one_chunk(tmp_path):
    """xr.open_zarr gives the data in chunks of records and a record coordinate in one chunk: the chunks are the
    data's (xarray's chunksizes of the whole object raised 'inconsistent chunks')."""
    v = np.arange(30.0).reshape(10, 3)
    xr.Dataset({"v": (("record", "time"), v)}, coords={"state": ("record", list("abcdefghij"))}).chunk(
        record=4).to_zarr(tmp_path / "f.zarr", zarr_format=2)
    stored = xr.open_zarr(tmp_path / "f.zarr").assign_coords(state=lambda d: d.state.chunk(record=10))
    assert record_chunks(stored) == [slice(0, 4), slice(4, 8), slice(8, 10)]
    with dask.config.set(scheduler="synchronous"):
        out = list(map_records(_square, stored, 0.0))
    assert [s for _, s in out] == [float((v[w] ** 2).sum()) for w, _ in out]


def _churn(chunk, where, size):
    """Allocate and free 200 arrays of ``size`` bytes, as a chunk's temporaries: the page faults of this process
    meanwhile."""
    import resource

    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(200):
        np.ones(size // 8).sum()
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before


def _allocator(chunk, where):
    from tsfdi.fleet import worker_allocator

    return worker_allocator()


@pytest.mark.skipif(not __import__("sys").platform.startswith("linux"), reason="glibc's mallopt: Linux only")
def test_workers_keep_freed_memory_and_get_the_arguments_once(monkeypatch):
    """A worker started by dask's nanny (MALLOC_TRIM_THRESHOLD_=65536, which also fixes the mmap threshold at 128
    kB) maps and unmaps every 2 MB temporary: 200 of them cost about 100,000 page faults. map_records sets the
    worker's allocator first (worker_allocator): a few. The arguments go to the workers once: a second call with
    equal arguments refers to them, new ones are sent. The fleet, still lazy, goes to the workers once per call and
    each chunk's task only names its records (issue 36: a task carrying its chunk's graph cost the driver and the
    scheduler ~10 ms of CPU time per chunk, which two workers on two cores lack); records held in memory go in
    their chunks' tasks."""
    data = xr.Dataset({"v": (("record", "time"), np.zeros((4, 3)))}).chunk(record=1)
    assert not tsfdi.fleet.worker_allocator()           # the driver is not a dask worker: left as it is
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
        sent, tasks = [], []
        scatter, submit = client.scatter, client.submit
        monkeypatch.setattr(client, "scatter", lambda *a, **k: sent.append(a[0][0]) or scatter(*a, **k))
        monkeypatch.setattr(client, "submit", lambda *a, **k: tasks.append(a) or submit(*a, **k))
        faults = list(map_records(_churn, data, 2**21))
        assert max(faults[1:]) < 2_000, faults           # the first chunk: the heap grows once
        assert len(tasks) == 4 and not any(dask.is_dask_collection(x) for t in tasks for x in t), tasks
        assert list(map_records(_allocator, data)) == [True] * 4
        small = data.isel(record=slice(0, 2))
        for offset in (1.0, 1.0, 2.0, 1.0):
            assert [s for _, s in map_records(_square, small, offset)] == [offset, offset]
        assert list(map_records(_churn, data, 2**21)) != []
        # equal arguments sent once while among the last SCATTERED = 2 sets; older ones are released, sent again
        assert [a for a in sent if isinstance(a, tuple)] == [(2**21,), (), (1.0,), (2.0,), (2**21,)]
        assert [len(a.record) for a in sent if isinstance(a, xr.Dataset)] == [4, 4, 2, 2, 2, 2, 4]
        # records held in memory (80 kB per chunk, above HELD_PER_CHUNK): each chunk goes in its own task, with its
        # records only, instead of the whole fleet to every worker
        sent.clear()
        tasks.clear()
        held = xr.Dataset({"v": (("record", "time"), np.ones((3, 10_000)))}).chunk(record=1)
        assert [s for _, s in map_records(_square, held, 0.0)] == [10_000.0] * 3
        assert not any(isinstance(a, xr.Dataset) for a in sent)
        assert len(tasks) == 3 and all(80_000 < len(pickle.dumps(t[2])) < 160_000 for t in tasks)
        assert [s for _, s in map_records(_square, small.compute(), 1.0)] == [1.0]     # not backed by dask: one chunk


# ---------------------------------------------------------------------------------------- the driver's memory
def _synthetic_chunk(first: int, n: int, length: int) -> np.ndarray:
    states = list(SYSTEMS)
    return np.stack([record(states[i % 3], length, np.random.default_rng(i), None if i % 3 == 0 else length // 4)
                     for i in range(first, first + n)])


def _synthetic_fleet(records: int, length: int = 1500, chunk: int = 6) -> xr.DataArray:
    """Synthetic records simulated where their chunk is computed (nothing in the driver)."""
    parts = [da.from_delayed(dask.delayed(_synthetic_chunk)(a, min(chunk, records - a), length),
                             (min(chunk, records - a), length, 2), dtype=float) for a in range(0, records, chunk)]
    states = np.array([list(SYSTEMS)[i % 3] for i in range(records)])
    return xr.DataArray(da.concatenate(parts), dims=("record", "time", "channel"),
                        coords={"time": np.arange(length) / FS, "channel": ["y0", "y1"], "state": ("record", states),
                                "failure_time": ("record", np.where(states == "healthy", np.nan, length / 4 / FS))})


def _peak(data, b) -> tuple[int, int]:
    """Peak traced memory of the driver during evaluate (bytes) and the number of windows tested."""
    tracemalloc.start()
    try:
        ev = tsfdi.evaluate(data, b, windows=("5s",), step=10, settle=2.0, progress=False)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return peak, int(ev.detection_counts["windows"].sum() + ev.identification_counts["windows"].sum())


def test_driver_memory_does_not_grow_with_the_records():
    """With the synchronous scheduler the chunks are even computed in the driver process; still, its peak grows
    neither with the records (24 kB each here) nor with their windows (0.1 s apart: about 130 per record): a row
    per window, as evaluate kept before, costs 100 bytes or more. What does grow is a row per record in
    ``Evaluation.records`` and dask's bookkeeping per chunk."""
    small, large = _synthetic_fleet(12, chunk=12), _synthetic_fleet(60, chunk=12)
    b = tsfdi.fit_baselines(small, fit_records=1, settle=2.0, duration=None, max_lags=4, var_max_lags=4,
                            steady_window="5s")
    with dask.config.set(scheduler="synchronous"):
        _peak(small, b)                                  # (first-call imports and caches)
        (p_small, w_small), (p_large, w_large) = _peak(small, b), _peak(large, b)
    data_growth = 48 * 1500 * 2 * 8
    assert w_large - w_small > 5000
    assert p_large - p_small < min(0.15 * data_growth, 25 * (w_large - w_small)), (p_small, p_large)


# ---------------------------------------------------------------------------------------------- Monitor.screen
def test_screen_kinds_and_errors(fleet, baselines):
    monitor = baselines.monitor("var", window="10s", test=LjungBox(lags=10, alpha=1e-3))
    from tsfdi.datasets.hexacopter import hexacopter_signals

    signals = hexacopter_signals(fleet.isel(record=slice(0, 4)))
    table = monitor.screen(signals)
    frames = monitor.screen([signals.isel(record=i).to_pandas() for i in range(4)], progress=True)
    cols = ["windows", "fault_windows", "detection_time", "steady_time", "label"]
    pd.testing.assert_frame_equal(table[cols], frames[cols], check_exact=True)
    assert len(monitor.result().windows) == 0           # the monitor itself is left as it was
    single = monitor.run(signals.isel(record=2))
    assert table.loc[2, "detection_time"] == (np.nan if single.detection_time is None else single.detection_time)
    assert table.loc[2, "fault_windows"] == single.windows["fault"].sum()
    with pytest.raises(TypeError, match="records must be"):
        monitor.screen(np.zeros((3, 100, 3)))
    bad = signals.copy(deep=True)
    bad[1, 5, 0] = np.nan
    with pytest.raises(ValueError, match="records: record 1: .*NaN"):
        monitor.screen(bad)
    with pytest.raises(ValueError, match="records: record 1: .*NaN"):
        monitor.screen(bad.chunk(record=2))


# ------------------------------------------------------------------------------------------- the guide's examples
GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "cluster.md"


def test_cluster_guide_examples_run(tmp_path, monkeypatch, capsys, fleet, baselines):
    """docs/guide/cluster.md: the LocalCluster example (its workers in-process here, to start fast) and the
    map_records reduction."""
    blocks = re.findall(r"```python\n(.*?)```", GUIDE.read_text(), re.S)
    local = blocks[0].replace("LocalCluster(n_workers=2, threads_per_worker=1)",
                              "LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=':0')")
    assert local != blocks[0]
    monkeypatch.chdir(tmp_path)
    exec(compile(local, str(GUIDE), "exec"), {"__name__": "__main__"})
    out = capsys.readouterr().out
    assert "correct" in out and "rotor1" in out and (tmp_path / "fleet.zarr").is_dir()
    reduce = textwrap.dedent(blocks[-1])
    namespace = {"fleet": fleet.chunk(record=6), "baselines": baselines, "tsfdi": tsfdi}
    with dask.config.set(scheduler="threads"):
        exec(compile(reduce, str(GUIDE), "exec"), namespace)
    counts = namespace["counts"]
    assert len(counts) == 24 and all(0 <= flagged <= tested == 11 for flagged, tested in counts)


def test_simulate_without_dask_writes_netcdf_in_memory(tmp_path, capsys, monkeypatch):
    """Without the fleet extra (no dask): netCDF simulated in memory as before; zarr and --scheduler need it."""
    import importlib.util

    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "dask" else find_spec(name, *a))
    base = ["simulate", "--records-per-case", "1", "--duration", "2s", "--failure-time", "1s", "--states", "rotor1",
            "--turbulence", "light"]
    assert main(base + ["--out", str(tmp_path / "a.nc")]) == 0
    assert "wrote 1 records" in capsys.readouterr().out
    with xr.open_dataset(tmp_path / "a.nc", engine="h5netcdf") as ds:
        ref = make_hexacopter_dataset(1, duration=2.0, failure_time=1.0, states=("rotor1",), turbulence=("light",))
        np.testing.assert_array_equal(ds["roll"].values, ref["roll"].values)
    assert main(base + ["--out", str(tmp_path / "a.zarr")]) == 2
    assert "needs dask and zarr (pip install 'tsfdi[fleet]')" in capsys.readouterr().err

"""Fleet scale (issue 21): ``tsfdi.evaluate`` over 2,000 simulated records, serially and on 1 and 2 dask workers.

1. The fleet: 2,000 hexacopter records (4 states x moderate / severe turbulence x 250), 30 s each at 100 Hz, the rotor
   failing at 5 s, written once by ``tsfdi simulate --shipped --chunk 50`` to a zarr store under the cache folder
   (``~/.cache/tsfdi/fleet_scale``, or ``--cache``; delete it to regenerate). The generation time is printed (and
   remembered for later runs).
2. Baselines from the store (two fitting records per state and level, VAR by BIC): only those records are read.
3. ``evaluate`` (VAR, Ljung-Box 20 lags and F test at alpha 1e-3, 5 / 10 / 20 s windows 1 s apart, detection and
   identification) of every other record: serially on the records in memory, and on a ``dask.distributed``
   cluster of 1 and of 2 worker processes (one thread each, so the GIL is not the limit) reading the store. The
   clusters are ``SubprocessCluster``: a ``LocalCluster`` whose scheduler runs in a process of its own, as on a real
   cluster, so that the driver's process holds the client alone (its memory is measured below).
   The three are interleaved ``--repeat`` times (the machine may be shared) and the medians reported; the tables are
   checked equal to the serial ones. Speed-up = 1-worker time / 2-worker time (acceptance: >= 1.7 on 2 cores).
4. The driver's memory at 200 and 2,000 records -- ``evaluate`` and ``Monitor.screen`` on the 2 workers, and the
   serial ``evaluate``, which reads the records into the driver: the peak of Python's traced allocations
   (tracemalloc), what is still held when the call has returned (its result), and the rise of the resident set
   (RSS, sampled every 5 ms).
5. Throughput in record-hours per second, and a projection (an extrapolation, not a measurement) of the wall time of
   100,000 flight hours on 64 workers from the measured cost per record.

BLAS is pinned to one thread. Run: ``python benchmarks/fleet_scale.py [--records 2000] [--repeat 3] [--cache DIR]``.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import gc  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import threading  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import psutil  # noqa: E402
import xarray as xr  # noqa: E402
from distributed import Client  # noqa: E402
from distributed.deploy.subprocess import SubprocessCluster  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.exceptions import UnstableModelWarning  # noqa: E402

DURATION, FAILURE, CHUNK = 30.0, 5.0, 50
LEVELS = ("moderate", "severe")
TESTS = {"whiteness": tsfdi.LjungBox(lags=20, alpha=1e-3), "variance": tsfdi.FTest(alpha=1e-3)}
OPTIONS = dict(models=("var",), tests=TESTS, windows=("5s", "10s", "20s"), settle=5.0, progress=False)


def generate(cache: Path, records: int) -> tuple[Path, float, bool]:
    """The zarr store of ``records`` records (made by ``tsfdi simulate`` when missing) and its generation time."""
    per_case = records // (4 * len(LEVELS))
    store = cache / f"fleet_{per_case * 4 * len(LEVELS)}.zarr"
    info = cache / (store.name + ".json")
    if store.exists() and info.exists():
        return store, json.loads(info.read_text())["seconds"], True
    cache.mkdir(parents=True, exist_ok=True)
    env = {k: v for k, v in os.environ.items() if k != "OMP_NUM_THREADS"}     # numba simulates on every core
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "tsfdi", "simulate", "--out", str(store), "--records-per-case",
                    str(per_case), "--turbulence", ",".join(LEVELS), "--duration", f"{DURATION:g}s",
                    "--failure-time", f"{FAILURE:g}s", "--chunk", str(CHUNK), "--shipped", "--seed", "21"],
                   check=True, env=env)
    seconds = time.perf_counter() - t0
    info.write_text(json.dumps({"seconds": seconds}))
    return store, seconds, False


def balanced(ds: xr.Dataset, n: int) -> xr.Dataset:
    """The first ``n / 8`` records of each state and turbulence level, chunked by ``CHUNK`` records."""
    cells = np.char.add(np.asarray(ds["state"].values).astype(str), np.asarray(ds["turbulence"].values).astype(str))
    take = np.sort(np.concatenate([np.flatnonzero(cells == c)[: n // 8] for c in pd.unique(cells)]))
    return ds.isel(record=take).chunk(record=CHUNK)


def timed(fn) -> tuple[float, object]:
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def same(a, b) -> bool:
    return all(getattr(a, n).equals(getattr(b, n)) for n in ("identification", "detection", "records"))


def driver_memory(fn) -> tuple[float, float, float, object]:
    """Peak traced allocations, those still held when ``fn`` has returned (its result), and the rise of the RSS of
    this process while ``fn`` runs (MB)."""
    proc = psutil.Process()
    base = proc.memory_info().rss
    peak = [base]
    done = threading.Event()

    def sample():
        while not done.is_set():
            peak[0] = max(peak[0], proc.memory_info().rss)
            time.sleep(0.005)

    watcher = threading.Thread(target=sample, daemon=True)
    tracemalloc.start()
    watcher.start()
    try:
        out = fn()
        traced = tracemalloc.get_traced_memory()[1]
        gc.collect()                                # (what is still referenced, not what awaits the collector)
        held = tracemalloc.get_traced_memory()[0]
    finally:
        done.set()
        watcher.join()
        tracemalloc.stop()
    return traced / 2**20, held / 2**20, (peak[0] - base) / 2**20, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--records", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cache", type=Path, default=Path.home() / ".cache" / "tsfdi" / "fleet_scale")
    args = ap.parse_args()
    warnings.simplefilter("ignore", UnstableModelWarning)

    store, gen_s, cached = generate(args.cache, args.records)
    ds = xr.open_zarr(store)
    n = ds.sizes["record"]
    print(f"fleet: {n} records x {DURATION:g} s at 100 Hz ({n * DURATION / 3600:.1f} record-hours), {store}")
    print(f"generation (tsfdi simulate, {os.cpu_count()} cores, chunks of {CHUNK}): {gen_s:.1f} s"
          f"{' (measured when the cache was made)' if cached else ''}")

    t_fit, base = timed(lambda: tsfdi.fit_baselines(ds, fit_records=2, settle=5.0, duration=20.0, models=("var",)))
    order = int(base.models["var"]["healthy"].lags)
    n_eval = n - len(base.fit_records)
    hours = n_eval * DURATION / 3600
    print(f"baselines from the store (the {len(base.fit_records)} fitting records read): {t_fit:.1f} s, healthy "
          f"VAR({order}); {n_eval} records evaluated ({hours:.2f} record-hours)")
    t_load, memory = timed(lambda: ds[["roll", "pitch", "r", "lost_control"]].compute())
    print(f"serial path: the records read into memory first ({t_load:.1f} s, not timed below)")

    times: dict = {"serial": [], "1 worker": [], "2 workers": []}
    driver_cpu: dict = {}
    with SubprocessCluster(n_workers=1, threads_per_worker=1, dashboard_address=":0") as one, \
            SubprocessCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0") as two:
        for cluster in (one, two):                       # workers import tsfdi and load the store's metadata
            with Client(cluster):
                tsfdi.evaluate(balanced(ds, 200), base, **OPTIONS)
        reference = None
        for r in range(args.repeat):
            t, reference = timed(lambda: tsfdi.evaluate(memory, base, **OPTIONS))
            times["serial"].append(t)
            for name, cluster in (("1 worker", one), ("2 workers", two)):
                with Client(cluster):
                    cpu = time.process_time()
                    t, ev = timed(lambda: tsfdi.evaluate(ds, base, **OPTIONS))
                    cpu = time.process_time() - cpu
                times[name].append(t)
                driver_cpu.setdefault(name, []).append(cpu)
                if not same(ev, reference):
                    raise AssertionError(f"{name}: the tables differ from the serial ones")
            print(f"repeat {r + 1}: " + ", ".join(f"{k} {v[-1]:.1f} s" for k, v in times.items()))
        med = {k: statistics.median(v) for k, v in times.items()}
        print(f"\nevaluate, median of {args.repeat} (tables equal to the serial ones in every run):")
        for k, v in med.items():
            print(f"  {k:>9}: {v:6.1f} s  {n_eval / v:6.1f} records/s  {hours / v:6.3f} record-hours/s")
        speedup = med["1 worker"] / med["2 workers"]
        print(f"  speed-up at 2 workers: {speedup:.2f}x over 1 worker (target >= 1.7), "
              f"{med['serial'] / med['2 workers']:.2f}x over the serial path")
        print("  driver CPU time during the dask runs (median): " + ", ".join(
            f"{k} {statistics.median(v):.1f} s" for k, v in driver_cpu.items()))
        print(f"  rows: {len(reference.detection):,} detection + {len(reference.identification):,} identification "
              "windows")

        print("\ndriver memory (MB) at 200 and 2,000 records: the dask runs on the 2 workers, the serial one reading the "
              "records into the driver")
        print(f"  {'call':<22} {'records':>8} {'traced peak':>12} {'held after (result)':>20} {'RSS rise':>9}")
        monitor = base.monitor("var", window="10s", test=tsfdi.LjungBox(lags=20, alpha=1e-3))
        calls = {"evaluate (dask)": lambda d: tsfdi.evaluate(d, base, **OPTIONS),
                 "Monitor.screen (dask)": monitor.screen,
                 "evaluate (serial)": lambda d: tsfdi.evaluate(d[["roll", "pitch", "r", "lost_control"]].compute(),
                                                               base, **OPTIONS)}
        peaks: dict = {}
        for name, call in calls.items():
            for size in (200, n):
                sub = balanced(ds, size) if size < n else ds
                with Client(two):
                    traced, held, rss, out = driver_memory(lambda: call(sub))
                del out
                peaks.setdefault(name, []).append((traced, held))
                print(f"  {name:<22} {size:>8} {traced:>12.1f} {held:>20.1f} {rss:>9.1f}")
        print(f"  200 -> {n} records ({n * DURATION * 100 * 3 * 8 / 2**20:.0f} MB of float64 signals at {n}):")
        for name, ((p0, h0), (p1, h1)) in peaks.items():
            print(f"    {name:<22} peak {p1 - p0:+7.1f} MB, of which the result held {h1 - h0:+7.1f} MB and the rest "
                  f"{(p1 - h1) - (p0 - h0):+7.1f} MB")
        print("  (evaluate keeps one row per window in Evaluation, and joining the chunks' rows at the end holds them "
              "twice for a moment: both grow with the windows; the records never reach the driver)")

    per_hour = med["1 worker"] / hours                  # worker-seconds per record-hour
    print("\nprojection (extrapolated from the measured cost, not measured): 100,000 flight hours on 64 workers")
    print(f"  measured cost: {per_hour:.2f} worker-s per record-hour ({med['1 worker'] / n_eval * 1e3:.1f} ms per "
          f"{DURATION:g} s record on 1 worker)")
    print(f"  ideal scaling: {1e5 * per_hour / 64 / 3600:.2f} h; at the measured 2-worker efficiency "
          f"({speedup / 2:.0%}): {1e5 * per_hour / (64 * speedup / 2) / 3600:.2f} h")
    held = peaks["evaluate (dask)"][1][1]
    print(f"  the per-window tables of Evaluation would hold about {1e5 / hours * held / 1024:.0f} GB "
          "in the driver (measured size per record-hour): at that scale reduce them per chunk "
          "(tsfdi.fleet.map_records) rather than keep every window")


if __name__ == "__main__":
    main()

"""Fleet scale (issues 21, 36): ``tsfdi.evaluate`` over 2,000 simulated records, serially and on 1 and 2 dask workers.

1. The fleet: 2,000 hexacopter records (4 states x moderate / severe turbulence x 250), 30 s each at 100 Hz, the rotor
   failing at 5 s, written once by ``tsfdi simulate --shipped --chunk 50`` to a zarr store under the cache folder
   (``~/.cache/tsfdi/fleet_scale``, or ``--cache``; delete it to regenerate). The generation time is printed (and
   remembered for later runs).
2. Baselines from the store (two fitting records per state and level, VAR by BIC): only those records are read.
3. ``evaluate`` (VAR, Ljung-Box 20 lags and F test at alpha 1e-3, 5 / 10 / 20 s windows 1 s apart, detection and
   identification) of every other record, each path starting from the same zarr store and timed from it: serially
   (the records read into this process's memory with one thread, dask's synchronous scheduler, then evaluated in
   memory), and on a ``dask.distributed`` cluster of 1 and of 2 worker processes (one thread each, so the GIL is
   not the limit), each worker reading its chunks of the store. The clusters are ``SubprocessCluster``: a
   ``LocalCluster`` whose scheduler runs in a process of its own, as on a real cluster, so that the driver's process
   holds the client alone (its memory is measured below). Each is started for its run, warmed up by an untimed
   ``evaluate`` of 200 records (the workers import tsfdi and get the baselines, which the timed run then refers to,
   as a user's second call does), and closed after it: one cluster is alive at a time, as a user has. The clusters
   start with :data:`THROUGHPUT` (session 38): dask's monitoring -- the event-loop tick every 20 ms, the system
   monitor every 0.5 s, the workers' memory monitor every 0.1 s, their profiler's stack sample every 10 ms -- made
   less frequent or off, which the printed idle CPU of a 2-worker cluster with and without them shows is about a
   tenth of a core by default (the ratio of 2 workers to 1 was 1.79-1.88 in three runs of session 38 with the
   defaults); ``--dask-defaults`` starts them with dask's defaults, docs/guide/cluster.md says what the settings
   cost (dashboard detail).
   What changed in this yardstick in issue 36's session 32, and why: (a) the serial path read the records into
   memory before its timed runs, while the workers read their chunks within theirs (0.7-1 s of ~17 s): the ratio
   compared evaluate in memory with read + evaluate. Now both pay for their read; the serial read's time is
   printed. (b) Both clusters were alive during every run; an idle cluster's scheduler, nanny and worker processes
   use 7 % (1 worker) to 11 % (2 workers) of a core, which on 2 cores the running cluster shared.
   The three are interleaved ``--repeat`` times (the machine may be shared) and the medians reported; the count
   tables are checked equal to the serial ones. Each run also reports the CPU time (user and system) and the minor
   page faults of the process(es) doing the work -- this process for the serial run, the workers
   (``resource.getrusage`` on each, ``Client.run``) for the dask runs -- which other jobs on a shared machine disturb
   far less than wall time, and the CPU time that other processes of the machine used meanwhile (all busy CPU time
   minus that of this process and its children); a run during which they used under a tenth of a core is quiet, and
   with at least two quiet runs of each kind the ratios are judged on those (both medians are printed). Beside the
   wall-time ratios, the same ratios by CPU time, which other jobs disturb far less: the serial process's over the
   one worker's, and the one worker's over the busiest of the two workers' (the speed-up of two workers that each
   have a core to themselves and never wait); and the CPU time of the driver and of the scheduler, which on a
   2-core machine share the two workers' cores. Where the workers' wall time went, from the scheduler's task stream
   (which its dashboard records anyway; read after each run): computing, idle before their first task (the driver's
   start), between tasks, and after their last (the tail), with the spread of the workers' last task ends.
   Acceptance (issue 36): one worker >= 0.9x the serial speed; two workers >= 1.8x one worker.
4. The same dask runs with tsfdi of an earlier commit (``--against REF``, default :data:`PREVIOUS`, the commit before
   issue 36; ``--against ''`` skips it): this script again in a fresh interpreter with that tree first on
   ``PYTHONPATH`` (``previous_commit.previous_tree``; the workers inherit it), after the runs above.
5. The driver's memory at 200 and 2,000 records -- ``evaluate`` and ``Monitor.screen`` on the 2 workers, and the
   serial ``evaluate``, which reads the records into the driver: the peak of the driver process's traced allocations
   during the call (tracemalloc: every Python object and numpy buffer allocated by this process, the dask client
   included; the workers and the scheduler are other processes), what is still held when the call has returned (its
   result), and the rise of the resident set (RSS, sampled every 5 ms; the allocator keeps freed pages, so it is
   coarser). ``evaluate`` on dask is measured twice: as is, and with the client's log of its last messages to the
   scheduler (``distributed.admin.low-level-log-length``, 1,000 by default, bounded) turned off. Acceptance: the
   ``evaluate`` (dask) peak flat from 200 to 2,000 records, i.e. growing by less than 2 % of the records' signals.
6. Throughput in record-hours per second, and a projection (an extrapolation, not a measurement) of the wall time of
   100,000 flight hours on 64 workers from the measured cost per record.

BLAS is pinned to one thread (here and, inherited, on the workers). Run:
``python benchmarks/fleet_scale.py [--records 2000] [--repeat 3] [--cache DIR] [--against REF] [--dask-defaults]``.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import contextlib  # noqa: E402
import gc  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import threading  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import dask  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import psutil  # noqa: E402
import xarray as xr  # noqa: E402
from distributed import Client, get_task_stream  # noqa: E402
from distributed.deploy.subprocess import SubprocessCluster  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.exceptions import UnstableModelWarning  # noqa: E402

#: the smaller fleet of the memory section (and of the untimed warm-up): the driver at SMALL and --records
SMALL = 200
DURATION, FAILURE, CHUNK = 30.0, 5.0, 50
#: the commit before issue 36 (dask workers' allocator, baselines sent once)
PREVIOUS = "f9e25de"
#: the client keeps its last messages to the scheduler (each chunk's task) for debugging: this many (default 1000)
LOG = "distributed.admin.low-level-log-length"
LEVELS = ("moderate", "severe")
#: the dask runs: name -> worker processes (one thread each)
CLUSTERS = {"1 worker": 1, "2 workers": 2}
#: dask settings of the benchmark's clusters (issue 36, session 38): the monitoring a cluster's processes run beside the
#: tasks, less often -- the event-loop tick (20 ms), the system monitor (0.5 s), the workers' memory monitor (0.1 s)
#: and their statistical profiler (a stack sample every 10 ms). With dask's defaults an idle cluster of 2 workers uses
#: about a tenth of a core (its scheduler, 2 nannies and 2 workers), which on 2 cores the computing workers lack;
#: printed by :func:`idle_cpu`. ``--dask-defaults`` runs the clusters with dask's defaults instead.
THROUGHPUT = {"distributed.admin.tick.interval": "1s", "distributed.admin.system-monitor.interval": "2s",
              "distributed.worker.memory.monitor-interval": "1s", "distributed.worker.profile.enabled": False}
#: the settings the clusters of this run start with (THROUGHPUT, or {} with --dask-defaults)
SETTINGS: dict = dict(THROUGHPUT)
#: the variables the serial path reads into memory (what evaluate reads of each record)
SIGNALS = ("roll", "pitch", "r", "lost_control")


def per_channel(cls, **options):
    """``cls(**options)`` testing every channel at ``alpha``: ``correction="none"``, or, in a tree before issue 31
    (step 4's earlier commit), which has no such option, its default, which was per channel."""
    try:
        return cls(correction="none", **options)
    except ValueError:
        return cls(**options)


TESTS = {"whiteness": per_channel(tsfdi.LjungBox, lags=20, alpha=1e-3),
         "variance": per_channel(tsfdi.FTest, alpha=1e-3)}
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


def _own_cpu() -> float:
    """CPU seconds used so far by this process and its children (the clusters' scheduler and workers)."""
    me, total = psutil.Process(), 0.0
    for proc in (me, *me.children(recursive=True)):
        try:
            t = proc.cpu_times()
        except psutil.NoSuchProcess:
            continue
        total += t.user + t.system
    return total


def _busy_cpu() -> float:
    """CPU seconds the machine has been busy, every process of every user."""
    t = psutil.cpu_times()
    return t.user + t.nice + t.system + getattr(t, "irq", 0.0) + getattr(t, "softirq", 0.0)


def timed(fn) -> tuple[float, object, float]:
    """Wall time of ``fn()``, its result, and the CPU seconds that other processes of the machine used meanwhile."""
    busy, own = _busy_cpu(), _own_cpu()
    t0 = time.perf_counter()
    out = fn()
    wall = time.perf_counter() - t0
    return wall, out, max(0.0, (_busy_cpu() - busy) - (_own_cpu() - own))


def usage() -> np.ndarray:
    """User and system CPU seconds and minor page faults of this process so far."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return np.array([r.ru_utime, r.ru_stime, float(r.ru_minflt)])


def measure(fn, client=None) -> tuple[float, object, float, np.ndarray]:
    """:func:`timed`, and the user s, system s and page faults of the process(es) doing the work meanwhile: this one
    (``client`` None), else every worker of ``client`` added up; last, the CPU seconds (user + system) of the busiest
    of them."""
    def now():
        return {"": usage()} if client is None else client.run(usage)

    before = now()
    wall, out, other = timed(fn)
    after = now()
    each = [after[w] - before[w] for w in after]
    return wall, out, other, np.array([*np.sum(each, axis=0), max(u[0] + u[1] for u in each)])


def from_store(ds, base, reads: list):
    """The serial path from the store: the records read into this process's memory (one thread: dask's synchronous
    scheduler; its wall time appended to ``reads``), then ``evaluate`` on them."""
    t0 = time.perf_counter()
    memory = ds[list(SIGNALS)].compute(scheduler="synchronous")
    reads.append(time.perf_counter() - t0)
    return tsfdi.evaluate(memory, base, **OPTIONS)


@contextlib.contextmanager
def environment(settings: dict):
    """The dask ``settings`` as the environment variables that set them in the processes started meanwhile (the
    cluster's scheduler, nannies and workers read ``DASK_*`` when they import dask)."""
    env = {"DASK_" + k.upper().replace(".", "__").replace("-", "_"): str(v) for k, v in settings.items()}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k)
            else:
                os.environ[k] = v


@contextlib.contextmanager
def cluster(n: int, ds, base):
    """A ``SubprocessCluster`` of ``n`` single-threaded workers started with :data:`SETTINGS` and a Client of it,
    warmed up (the workers import tsfdi, load the store's metadata and get the baselines: ``evaluate`` of 200 records,
    not timed)."""
    with environment(SETTINGS), SubprocessCluster(n_workers=n, threads_per_worker=1, dashboard_address=":0") as cl, \
            Client(cl, set_as_default=False) as client:
        client.wait_for_workers(n)
        with client.as_current():
            tsfdi.evaluate(balanced(ds, SMALL), base, **OPTIONS)
        yield cl, client


def idle_cpu(settings: dict, seconds: float = 10.0) -> float:
    """Percent of a core that the processes of an idle 2-worker ``SubprocessCluster`` started with ``settings`` use
    over ``seconds`` (after 3 s to settle): what the workers' cores lose to the cluster itself."""
    with environment(settings), SubprocessCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0") as cl, \
            Client(cl, set_as_default=False) as client:
        client.wait_for_workers(2)
        time.sleep(3.0)
        before, t0 = _own_cpu(), time.perf_counter()
        time.sleep(seconds)
        return 100.0 * (_own_cpu() - before) / (time.perf_counter() - t0)


def workers_time(stream: list, start: float, stop: float) -> np.ndarray:
    """Where the workers' wall time of a call from ``start`` to ``stop`` (``time.time()``) went, from its task stream
    (``distributed.get_task_stream``), in seconds added up over the workers that ran a task: computing tasks, idle
    before their first task (the driver's start: reading the labels, sending the arguments), idle between tasks
    (waiting for the next one), idle after their last task (the tail: waiting for the other workers' last chunks,
    then the driver's end); last, the spread of the workers' last task ends (the tail's imbalance)."""
    spans: dict = {}
    for task in stream:
        for s in task["startstops"]:
            if s["action"] == "compute":
                spans.setdefault(task["worker"], []).append((s["start"], s["stop"]))
    out = np.zeros(5)
    ends = []
    for spans_w in spans.values():
        busy = sum(b - a for a, b in spans_w)
        first, last = min(a for a, _ in spans_w), max(b for _, b in spans_w)
        out += [busy, first - start, last - first - busy, stop - last, 0.0]
        ends.append(last)
    out[4] = max(ends) - min(ends) if ends else 0.0
    return out


def dask_runs(ds, base, repeat: int, runs: dict, driver_cpu: dict, reads: list | None = None,
              idle: dict | None = None) -> object:
    """``repeat`` times: the serial path from the store (:func:`from_store`, when ``reads`` is given), then
    ``evaluate`` of the store on each cluster of :data:`CLUSTERS` in turn, each started for its run and closed after
    it (:func:`cluster`: one cluster alive at a time, as a user has; an idle cluster's scheduler, nannies and workers
    use ~7-11 % of a core, which on 2 cores the running one would share); each run appended to ``runs[name]`` as
    (wall s, others' CPU s, user s, system s, page faults, CPU s of the busiest worker), and where the workers' wall
    time went (:func:`workers_time`) to ``idle[name]``. Returns the last tables (checked equal to the serial ones
    when there are)."""
    ev = reference = None
    for r in range(repeat):
        line = []
        if reads is not None:
            t, reference, other, u = measure(lambda: from_store(ds, base, reads))
            runs["serial"].append((t, other, *u))
            line.append(f"serial {t:.1f} s (read {reads[-1]:.1f} s; CPU {u[0] + u[1]:.1f} s, {u[2]:,.0f} faults)")
        for name, workers in CLUSTERS.items():
            with cluster(workers, ds, base) as (_, client), client.as_current():
                cpu, sched = time.process_time(), client.run_on_scheduler(usage)
                span: list = []

                def run():
                    span.append(time.time())
                    out = tsfdi.evaluate(ds, base, **OPTIONS)
                    span.append(time.time())
                    return out

                # (the task stream: the scheduler's record, which its dashboard keeps anyway; read after the run)
                with get_task_stream(client=client) as stream:
                    t, ev, other, u = measure(run, client)
                sched = client.run_on_scheduler(usage) - sched
                if idle is not None:
                    idle.setdefault(name, []).append(workers_time(stream.data, *span))
                driver_cpu.setdefault(name, []).append((time.process_time() - cpu, sched[0] + sched[1]))
            runs[name].append((t, other, *u))
            line.append(f"{name} {t:.1f} s (CPU {u[0] + u[1]:.1f} s, {u[2]:,.0f} faults)")
            if reads is not None and not same(ev, reference):
                raise AssertionError(f"{name}: the tables differ from the serial ones")
        print(f"repeat {r + 1}: " + ", ".join(line), flush=True)
    return reference if reads is not None else ev


def dask_only(store: Path, repeat: int, out: Path) -> None:
    """Step 4 in the interpreter of an earlier tree: the dask runs alone; their figures and tables to ``out``."""
    warnings.simplefilter("ignore", UnstableModelWarning)
    ds = xr.open_zarr(store)
    base = tsfdi.fit_baselines(ds, fit_records=2, settle=5.0, duration=20.0, models=("var",))
    runs: dict = {k: [] for k in CLUSTERS}
    ev = dask_runs(ds, base, repeat, runs, {})
    pd.to_pickle({"runs": runs, "tsfdi": tsfdi.__file__,
                  "tables": {n: getattr(ev, n) for n in ("identification_counts", "detection_counts",
                                                           "detection_delays", "records")}}, out)


def previous(ref: str, store: Path, repeat: int, runs: dict, reference) -> None:
    """Step 4: the dask runs with tsfdi of commit ``ref`` (a fresh interpreter, its workers too), against ``runs``."""
    from previous_commit import previous_tree

    tree = previous_tree(ref)
    out = tree / "runs.pkl"
    env = dict(os.environ, PYTHONPATH=str(tree))
    subprocess.run([sys.executable, str(Path(__file__).resolve()), "--repeat", str(repeat), "--dask-only",
                    str(store), str(out), *([] if SETTINGS else ["--dask-defaults"])], check=True, env=env,
                   cwd=str(tree))
    prev = pd.read_pickle(out)
    equal = all(prev["tables"][n].equals(getattr(reference, n)) for n in prev["tables"])
    print(f"\nthe same dask runs with tsfdi of commit {ref} ({prev['tsfdi']}), after the runs above, {repeat} "
          f"rounds, medians; its tables {'equal to' if equal else 'DIFFER from'} this tree's:")
    print(f"  {'':>9}  {'previous':>9} {'current':>8} {'prev/curr':>9}   {'CPU prev':>8} {'CPU curr':>8}   "
          f"{'sys prev':>8} {'sys curr':>8}   {'faults prev':>11} {'faults curr':>11}")
    for k in ("1 worker", "2 workers"):
        p, c = np.median(np.array(prev["runs"][k]), axis=0), np.median(np.array(runs[k]), axis=0)
        print(f"  {k:>9}: {p[0]:8.1f}s {c[0]:7.1f}s {p[0] / c[0]:8.2f}x   {p[2] + p[3]:7.1f}s {c[2] + c[3]:7.1f}s   "
              f"{p[3]:7.2f}s {c[3]:7.2f}s   {p[4]:11,.0f} {c[4]:11,.0f}")
    p1, p2 = (np.median(np.array(prev["runs"][k]), axis=0)[0] for k in ("1 worker", "2 workers"))
    print(f"  previous: 1 worker {statistics.median(r[0] for r in runs['serial']) / p1:.2f}x the serial speed "
          f"(this run's serial median), 2 workers {p1 / p2:.2f}x one worker")


def same(a, b) -> bool:
    return all(getattr(a, n).equals(getattr(b, n))
               for n in ("identification_counts", "detection_counts", "detection_delays", "records"))


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
    ap.add_argument("--against", default=PREVIOUS, help="earlier commit whose dask runs are timed too ('': none)")
    ap.add_argument("--dask-only", nargs=2, type=Path, metavar=("STORE", "OUT"), help=argparse.SUPPRESS)
    ap.add_argument("--dask-defaults", action="store_true",
                    help="start the clusters with dask's default settings instead of THROUGHPUT")
    args = ap.parse_args()
    if args.dask_defaults:
        SETTINGS.clear()
    if args.records <= SMALL:
        ap.error(f"--records must be above {SMALL}: the memory section compares the driver at {SMALL} records with "
                 f"--records (got {args.records})")
    if args.dask_only:
        return dask_only(args.dask_only[0], args.repeat, args.dask_only[1])
    warnings.simplefilter("ignore", UnstableModelWarning)

    store, gen_s, cached = generate(args.cache, args.records)
    ds = xr.open_zarr(store)
    n = ds.sizes["record"]
    print(f"fleet: {n} records x {DURATION:g} s at 100 Hz ({n * DURATION / 3600:.1f} record-hours), {store}")
    print(f"generation (tsfdi simulate, {os.cpu_count()} cores, chunks of {CHUNK}): {gen_s:.1f} s"
          f"{' (measured when the cache was made)' if cached else ''}")

    t_fit, base, _ = timed(lambda: tsfdi.fit_baselines(ds, fit_records=2, settle=5.0, duration=20.0, models=("var",)))
    order = int(base.models["var"]["healthy"].lags)
    n_eval = n - len(base.fit_records)
    hours = n_eval * DURATION / 3600
    print(f"baselines from the store (the {len(base.fit_records)} fitting records read): {t_fit:.1f} s, healthy "
          f"VAR({order}); {n_eval} records evaluated ({hours:.2f} record-hours)")

    runs: dict = {"serial": [], "1 worker": [], "2 workers": []}
    driver_cpu: dict = {}
    reads: list = []
    idle: dict = {}
    reference = dask_runs(ds, base, args.repeat, runs, driver_cpu, reads=reads, idle=idle)
    print(f"\nserial path: the records read from the store in {statistics.median(reads):.2f} s (median; timed "
          "within its runs, as the workers read their chunks within theirs)")
    # a run is quiet when the other processes of the (shared) machine used under a tenth of a core meanwhile
    quiet = {k: [r for r in v if r[1] < 0.1 * r[0]] for k, v in runs.items()}
    use_quiet = all(len(v) >= 2 for v in quiet.values())
    for label, chosen in (("all runs", runs), ("quiet runs", quiet)):
        if not all(chosen.values()):
            print(f"\nevaluate, {label}: none for " + ", ".join(k for k, v in chosen.items() if not v))
            continue
        m = {k: np.median(np.array(v), axis=0) for k, v in chosen.items()}
        print(f"\nevaluate, median of the {label} ({', '.join(f'{k} {len(v)}' for k, v in chosen.items())}; tables "
              "equal to the serial ones in every run); CPU time and page faults of the process(es) doing the "
              "work (this one, or the workers added up):")
        print(f"  {'':>9}  {'wall':>7} {'records/s':>10} {'rec-h/s':>8} {'user':>7} {'system':>7} "
              f"{'page faults':>12} {'busiest CPU':>12} {'others CPU':>11}")
        for k, (t, other, user, system, faults, busiest) in m.items():
            print(f"  {k:>9}: {t:6.1f}s {n_eval / t:10.1f} {hours / t:8.3f} {user:6.1f}s {system:6.2f}s "
                  f"{faults:12,.0f} {busiest:11.1f}s {other:10.1f}s")
        one_x, two_x = m["serial"][0] / m["1 worker"][0], m["1 worker"][0] / m["2 workers"][0]
        cpu_x, cpu_2x = m["serial"][5] / m["1 worker"][5], m["1 worker"][5] / m["2 workers"][5]
        print(f"  1 worker: {one_x:.2f}x the serial speed (acceptance >= 0.9: {'MET' if one_x >= 0.9 else 'NOT MET'}"
              f"); by CPU time (user + system) {cpu_x:.2f}x")
        print(f"  2 workers: {two_x:.2f}x one worker (acceptance >= 1.8: {'MET' if two_x >= 1.8 else 'NOT MET'}), "
              f"{m['serial'][0] / m['2 workers'][0]:.2f}x the serial path; the 2 workers' CPU time is "
              f"{(m['2 workers'][2] + m['2 workers'][3]) / (m['1 worker'][2] + m['1 worker'][3]):.2f}x one "
              f"worker's (1.00 = no work added by splitting); by CPU time, one worker's over the busiest of the "
              f"two's (what 2 workers give with a core each and no wait), {cpu_2x:.2f}x")
        if label == ("quiet runs" if use_quiet else "all runs"):
            med, speedup = {k: v[0] for k, v in m.items()}, two_x
    print(f"  (the ratios judged and projected below: {'quiet runs' if use_quiet else 'all runs'}; on a machine "
          "shared with other jobs the wall times of 2 workers on 2 cores are not a clean measurement)")
    print("  driver and scheduler CPU time during the dask runs (medians; on 2 cores they share the workers' "
          "cores): " + ", ".join(f"{k} {statistics.median(d for d, _ in v):.1f} s + "
                                 f"{statistics.median(c for _, c in v):.1f} s" for k, v in driver_cpu.items()))
    print("  where the workers' wall time went (task stream; medians over all runs, seconds added up over the "
          "workers; wall x workers = the sum of the first four):")
    print(f"  {'':>9}  {'computing':>9} {'before 1st':>10} {'between':>8} {'after last':>10} {'last ends spread':>16}")
    for k, v in idle.items():
        b, first, gaps, end, spread = np.median(np.array(v), axis=0)
        print(f"  {k:>9}: {b:8.2f}s {first:9.2f}s {gaps:7.2f}s {end:9.2f}s {spread:15.2f}s")
    print(f"  windows: {reference.detection_counts['windows'].sum():,} detection + "
          f"{reference.identification_counts['windows'].sum():,} identification, counted in "
          f"{len(reference.detection_counts)} + {len(reference.identification_counts)} rows (+ "
          f"{len(reference.detection_delays)} delay rows)")

    settings = ", ".join(f"{k} = {v}" for k, v in SETTINGS.items()) or "dask's defaults"
    print(f"\nthe clusters' dask settings: {settings}; an idle 2-worker cluster and its client use "
          f"{idle_cpu({}):.1f} % of a core with dask's defaults, {idle_cpu(THROUGHPUT):.1f} % with THROUGHPUT (10 s each)")
    with cluster(2, ds, base) as (two, _):
        print(f"\ndriver memory (MB) at {SMALL} and {n:,} records: the dask runs on the 2 workers, the serial one "
              "reading the records into the driver")
        print(f"  {'call':<26} {'records':>8} {'traced peak':>12} {'held after':>11} {'RSS rise':>9} "
              f"{'per-record table':>17}")
        monitor = base.monitor("var", window="10s", test=per_channel(tsfdi.LjungBox, lags=20, alpha=1e-3))

        def evaluate(d):
            return tsfdi.evaluate(d, base, **OPTIONS)

        calls = {"evaluate (dask)": (evaluate, {}), "evaluate (dask), no log": (evaluate, {LOG: 0}),
                 "Monitor.screen (dask)": (monitor.screen, {}),
                 "evaluate (serial)": (lambda d: evaluate(d[list(SIGNALS)].compute()), {})}
        peaks: dict = {}
        for name, (call, config) in calls.items():
            for size in (SMALL, n):
                sub = balanced(ds, size) if size < n else ds
                with dask.config.set(config), Client(two):
                    traced, held, rss, out = driver_memory(lambda: call(sub))
                table = (out if isinstance(out, pd.DataFrame) else out.records).memory_usage(deep=True).sum() / 2**20
                del out
                peaks.setdefault(name, []).append((traced, table))
                print(f"  {name:<26} {size:>8} {traced:>12.1f} {held:>11.1f} {rss:>9.1f} {table:>17.2f}")
        data = (n - SMALL) * DURATION * 100 * 3 * 8 / 2**20
        print(f"  {SMALL} -> {n} records: the records' float64 signals grow by {data:.0f} MB, their windows "
              f"{n / SMALL:g}-fold")
        for name, ((p0, _), (p1, t1)) in peaks.items():
            print(f"    {name:<26} peak {p1 - p0:+7.1f} MB ({100 * (p1 - p0) / data:5.1f} % of the signals' growth)")
        (p0, _), (p1, t1) = peaks["evaluate (dask)"]
        (q0, _), (q1, _) = peaks["evaluate (dask), no log"]
        print(f"  evaluate (dask): the driver's peak {p0:.1f} -> {p1:.1f} MB, "
              f"{'FLAT' if p1 - p0 < 0.02 * data else 'NOT FLAT'} (acceptance: it grows by less than 2 % of the "
              f"signals). Each chunk comes back as its windows counted per distinct outcome (a few kB). What grows: "
              f"the row per record of Evaluation.records ({t1 * 2**20 / n:.0f} bytes), and the client's log of its "
              f"last 1,000 messages to the scheduler (dask config {LOG}; each chunk's task is one; bounded) -- "
              f"without it the peak grows by {q1 - q0:+.1f} MB")

    if args.against:
        previous(args.against, store, args.repeat, runs, reference)

    per_hour = med["1 worker"] / hours                  # worker-seconds per record-hour
    print("\nprojection (extrapolated from the measured cost, not measured): 100,000 flight hours on 64 workers")
    print(f"  measured cost: {per_hour:.2f} worker-s per record-hour ({med['1 worker'] / n_eval * 1e3:.1f} ms per "
          f"{DURATION:g} s record on 1 worker)")
    print(f"  ideal scaling: {1e5 * per_hour / 64 / 3600:.2f} h; at the measured 2-worker efficiency "
          f"({speedup / 2:.0%}): {1e5 * per_hour / (64 * speedup / 2) / 3600:.2f} h")
    per_record = peaks["evaluate (dask)"][1][1] / n         # MB per record of Evaluation.records
    flights = 1e5 * 3600 / DURATION
    print(f"  driver memory: Evaluation.records, {per_record * 2**20:.0f} bytes per record, would hold about "
          f"{flights * per_record / 1024:.1f} GB for the {flights:,.0f} records of {DURATION:g} s; the counts stay "
          "a few kB whatever the number of records")


if __name__ == "__main__":
    main()

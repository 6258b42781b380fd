"""The same workloads timed on this tree and on an earlier commit of tsfdi, in one run.

Used by ``identify_speed.py`` and ``evaluate_speed.py`` (``--against REF``, default :data:`REFERENCE`, the last
commit before the windowed engine of issue 16; ``evaluate_speed.py`` also against the commit before issue 36),
``rls_throughput.py`` (default there: the commit before issue 18), ``glrt_speed.py`` and ``order_selection.py`` (the
commit before issue 36).
The earlier ``tsfdi`` package is exported with ``git archive`` into a temporary folder; each measurement is a fresh
interpreter (``python previous_commit.py WORKLOAD REPEAT CLOCK``) with that folder or this repository first on
``PYTHONPATH``, the two trees alternating so that a slow spell of the machine hits both. A worker builds its inputs,
runs the workload twice to compile (numba) and warm caches, then times ``repeat`` units of as many calls as take
about 0.1 s and prints the median time per call; the comparison reports the median over rounds of each tree and the
ratio previous / current (above 1: the current tree is faster). Time is wall-clock time, or with ``clock="cpu"``
the process's CPU time (user + system, page faults included), which other jobs on a shared machine disturb far less
for single-threaded work.

The workloads use only calls whose meaning did not change, spelled for each tree where the spelling did
(``evaluate(methods=...)`` before, ``evaluate(tests=...)`` after).
"""

from __future__ import annotations

import atexit
import json
import os
import shutil
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

os.environ["OPENBLAS_NUM_THREADS"] = "1"

ROOT = Path(__file__).resolve().parents[1]
#: The commit before the one-flow refactor (issue 16).
REFERENCE = "899984e"
#: The commit before the windowed kernels and GLRT scan of issue 36.
BEFORE_ISSUE_36 = "f9e25de"


CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}


def median_time(fn, repeat: int, number: int = 1, clock: str = "wall") -> float:
    """Median over ``repeat`` units of the time per call of ``fn``, each unit ``number`` calls, by ``clock``
    (a key of :data:`CLOCKS`)."""
    now = CLOCKS[clock]
    times = []
    for _ in range(repeat):
        t0 = now()
        for _ in range(number):
            fn()
        times.append((now() - t0) / number)
    return float(statistics.median(times))


def previous_tree(ref: str) -> Path:
    """``tsfdi`` of commit ``ref`` unpacked under a temporary folder (removed when the process exits)."""
    out = Path(tempfile.mkdtemp(prefix=f"tsfdi-{ref}-"))
    atexit.register(shutil.rmtree, out, True)
    archive = out / "tree.tar"
    subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", "-o", str(archive), ref, "tsfdi"], check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(out, filter="data")
    return out


def _run(tree: Path, workload: str, repeat: int, clock: str) -> float:
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(Path(__file__).resolve()), workload, str(repeat), clock], env=env,
                          capture_output=True, text=True, cwd=str(tree))
    if proc.returncode != 0:
        raise RuntimeError(f"workload {workload} failed on {tree}:\n{proc.stderr[-3000:]}")
    return float(json.loads(proc.stdout.strip().splitlines()[-1])["median_s"])


def compare(workloads: dict, against: str = REFERENCE, rounds: int = 3, clock: str = "wall") -> dict:
    """Time every ``workloads`` entry (name -> (description, repeat)) on this tree and on ``against`` by ``clock``
    ("wall" or "cpu", see the module docstring); print a table and return name -> (previous, current) medians in s.

    A workload counts as not slower when the current median is at most 5 % above the previous one (timing noise of
    this machine between interleaved runs)."""
    prev = previous_tree(against)
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip()
    what = "wall-clock" if clock == "wall" else "CPU"
    print(f"\nThis tree (HEAD {head} + working tree) against commit {against}, {rounds} interleaved rounds per tree, "
          f"each a fresh interpreter timing the median {what} time of its runs after a warm-up run:")
    print(f"  {'workload':<58} {'previous':>10} {'current':>10} {'prev/curr':>10}  verdict")
    out = {}
    for name, (what, repeat) in workloads.items():
        old, new = [], []
        for _ in range(rounds):
            old.append(_run(prev, name, repeat, clock))
            new.append(_run(ROOT, name, repeat, clock))
        mo, mn = statistics.median(old), statistics.median(new)
        verdict = "not slower" if mn <= 1.05 * mo else "SLOWER"
        digits = 3 if max(mo, mn) < 0.01 else 1                # sub-10-ms workloads to the microsecond
        print(f"  {what:<58} {mo * 1e3:8.{digits}f}ms {mn * 1e3:8.{digits}f}ms {mo / mn:9.2f}x  {verdict}")
        out[name] = (mo, mn)
    return out


# ------------------------------------------------------------------------------------------------- workloads
def _windows_inputs():
    import numpy as np
    from scipy import signal as sps

    import tsfdi

    rng = np.random.default_rng(0)
    fs = 100
    y_train = [sps.lfilter([1.0], [1.0, -0.6 - 0.05 * i, 0.2], rng.standard_normal(20_000)) for i in range(4)]
    record = sps.lfilter([1.0], [1.0, -0.7, 0.2], rng.standard_normal(60 * fs))
    models = {f"M{i}": tsfdi.AR(y, 30).fit() for i, y in enumerate(y_train)}
    return record, models, tsfdi.LjungBox(50, 1e-3), 20 * fs, fs


def identify_windows_workload():
    import tsfdi

    record, models, test, window, step = _windows_inputs()
    return lambda: tsfdi.identify_windows(record, models, test, window=window, step=step)


def identify_windows_ftest_workload():
    import tsfdi

    record, models, _, window, step = _windows_inputs()
    test = tsfdi.FTest(1e-8)
    return lambda: tsfdi.identify_windows(record, models, test, window=window, step=step)


def _hexacopter(fit_records=10):
    import warnings

    import tsfdi
    from tsfdi.datasets import load_hexacopter
    from tsfdi.exceptions import UnstableModelWarning

    warnings.simplefilter("ignore", UnstableModelWarning)
    try:
        from tsfdi.datasets.hexacopter import hexacopter_signals
    except ImportError:                                     # before issue 16
        from tsfdi.evaluation import hexacopter_signals
    sig = hexacopter_signals(load_hexacopter(ROOT / "data" / "hexacopter.nc"))   # this repository's copy
    bases = {lvl: tsfdi.fit_baselines(sig, fit_turbulence=lvl, duration=None, models=["var"],
                                      fit_records=fit_records, order=20) for lvl in ("light", "moderate", "severe")}
    new = hasattr(tsfdi, "ResidualWindows")
    kw = ({"tests": {"whiteness": tsfdi.LjungBox(lags=20, alpha=1e-3)}, "windows": ("5s", "10s", "20s")} if new
          else {"methods": ("whiteness",), "windows": (5.0, 10.0, 20.0)})
    return sig, bases, kw


def evaluate_workload(fit_records=10):
    import tsfdi

    sig, bases, kw = _hexacopter(fit_records)
    return lambda: tsfdi.evaluate(sig, bases, models=("var",), progress=False, **kw)


def monitor_workload():
    sig, bases, _ = _hexacopter()
    b = bases["severe"]
    try:
        mon = b.monitor("var", window="5s", rule="likelihood")
    except TypeError:                                       # before issue 16: seconds as floats
        mon = b.monitor("var", window=5.0, rule="likelihood")
    recs = [sig.isel(record=i).values for i in range(int(sig.sizes["record"]))
            if str(sig["turbulence"].values[i]) == "severe" and not bool(sig["lost_control"].values[i])][:20]
    return lambda: [mon.run(x) for x in recs]


def glrt_workload():
    """``GLRT(500, scale=1.0).statistic`` on 60,000 standard normal samples (benchmarks/glrt_speed.py)."""
    import numpy as np

    import tsfdi

    x = np.random.default_rng(0).standard_normal(60_000)
    gl = tsfdi.GLRT(500, scale=1.0)
    return lambda: gl.statistic(x)


def _rls_workload(d: int):
    """``RecursiveARX(d // 2, d - d // 2, 0, 0.99).run`` on white noise: 500,000 samples (100,000 at ``d >= 60``)."""
    import numpy as np

    from tsfdi import RecursiveARX

    rng = np.random.default_rng(0)
    n = 500_000 if d < 60 else 100_000
    u, y = rng.standard_normal(n), rng.standard_normal(n)
    return lambda: RecursiveARX(d // 2, d - d // 2, 0, 0.99).run(y, u)


def _var_fit_workload(trend: str):
    """VAR(20).fit() on roll, pitch, r of 10 shipped records (benchmarks/fit_speed.py)."""
    import numpy as np

    import tsfdi
    from tsfdi.datasets import load_hexacopter

    ds = load_hexacopter(ROOT / "data" / "hexacopter.nc")
    records = [np.column_stack([ds[c].isel(record=i).values for c in ("roll", "pitch", "r")]) for i in range(10)]
    return tsfdi.VAR(records, 20, trend=trend).fit


def _fit_baselines_workload(**kw):
    """fit_baselines on the shipped data (benchmarks/fit_speed.py)."""
    import tsfdi
    from tsfdi.datasets import load_hexacopter
    from tsfdi.datasets.hexacopter import hexacopter_signals

    sig = hexacopter_signals(load_hexacopter(ROOT / "data" / "hexacopter.nc"))
    return lambda: tsfdi.fit_baselines(sig, **kw)


def _select_workload(model: str, n: int):
    """``select_order`` of benchmarks/order_selection.py: AR, max lag 50, or VAR of 3 channels, max lag 20."""
    import numpy as np

    import tsfdi
    from order_selection import ar6, var4

    rng = np.random.default_rng(2026)
    if model == "ar":
        y = ar6(n, rng)
        return lambda: tsfdi.select_order(y, 50, trend="c").selected
    y = var4(n, rng)
    return lambda: tsfdi.select_order(y, 20, "var", trend="c").selected


WORKLOADS = {"identify_windows": identify_windows_workload, "identify_windows_ftest": identify_windows_ftest_workload,
             "evaluate": evaluate_workload, "evaluate_first": lambda: evaluate_workload("first"), "monitor": monitor_workload, "glrt": glrt_workload,
             "rls_d4": lambda: _rls_workload(4), "rls_d20": lambda: _rls_workload(20),
             "rls_d60": lambda: _rls_workload(60),
             "var_fit_c": lambda: _var_fit_workload("c"), "var_fit_n": lambda: _var_fit_workload("n"),
             "fit_baselines": _fit_baselines_workload,
             "select_ar_2000": lambda: _select_workload("ar", 2000),
             "select_ar_60000": lambda: _select_workload("ar", 60_000),
             "select_var_2000": lambda: _select_workload("var", 2000),
             "fit_baselines_var10": lambda: _fit_baselines_workload(fit_turbulence="severe", duration=None,
                                                                    models=["var"], fit_records=10, order=20)}


def _worker(name: str, repeat: int, clock: str) -> None:
    import warnings

    warnings.simplefilter("ignore")                         # a warning printed per call would be timed too
    fn = WORKLOADS[name]()
    t0 = time.perf_counter()
    fn()                                                    # compile and warm up
    fn()
    once = time.perf_counter() - t0
    number = max(1, int(0.1 / max(once / 2, 1e-9)))         # calls per timed unit: at least ~0.1 s of work
    print(json.dumps({"median_s": median_time(fn, repeat, number, clock)}))


if __name__ == "__main__":
    _worker(sys.argv[1], int(sys.argv[2]), sys.argv[3])

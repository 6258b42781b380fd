"""Speed of tsfdi.select_order against statsmodels, measured in one run.

Prints the median time (CPU time of the process by default, ``--clock wall`` for wall-clock time: the machine is
shared) of
  * select_order(y, max_lags=50)           vs statsmodels ar_select_order(y, 50)        for N = 2,000 and 60,000
  * select_order(Y, 20, model="var")       vs statsmodels VAR(Y).select_order(20)      3 channels, N = 2,000
and the ratio against the issue 36 acceptance targets, together with the orders both select (they must agree); then
the same tsfdi calls on this tree against the commit before issue 36 (``previous_commit.py``; ``--against REF`` picks
another commit), fresh interpreters, interleaved rounds. BLAS is pinned to one thread.

Run: python benchmarks/order_selection.py [--clock cpu|wall] [--against REF]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from scipy import signal as sps  # noqa: E402
from statsmodels.tsa.api import VAR as smVAR  # noqa: E402
from statsmodels.tsa.ar_model import ar_select_order  # noqa: E402

import tsfdi  # noqa: E402
from previous_commit import BEFORE_ISSUE_36, compare  # noqa: E402

#: issue 36 acceptance: ratio statsmodels / tsfdi
TARGETS = {"AR N=2000": 1000, "AR N=60000": 6000, "VAR N=2000": 400}
CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}
now = CLOCKS["cpu"]


def median_time(fn, repeat: int, budget: float = 20.0) -> float:
    times = []
    t_end = time.perf_counter() + budget
    for _ in range(repeat):
        t0 = now()
        fn()
        times.append(now() - t0)
        if time.perf_counter() > t_end and len(times) >= 3:
            break
    return float(np.median(times))


def ar6(n, rng):
    a = np.poly(np.r_[0.9 * np.exp(1j * np.array([0.3, -0.3, 1.2, -1.2])), 0.7, -0.5]).real
    return sps.lfilter([1.0], a, rng.standard_normal(n + 500))[500:]


def var4(n, rng):
    """A stable VAR(4) in the papers' sign, y[t] = e[t] - sum_i A_i y[t-i], after 500 samples of burn-in."""
    A = [np.diag([-0.5, -0.3, -0.4]) + 0.05, np.diag([0.3, 0.2, 0.25]), np.diag([-0.15, 0.1, -0.1]),
         np.array([[0.3, 0.1, 0.0], [0.0, -0.3, 0.1], [0.1, 0.0, 0.35]])]
    y = rng.standard_normal((n + 500, 3))
    for t in range(len(A), n + 500):
        y[t] -= sum(a @ y[t - i] for i, a in enumerate(A, start=1))
    return y[500:]


def main() -> None:
    global now
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clock", choices=("cpu", "wall"), default="cpu")
    parser.add_argument("--against", default=BEFORE_ISSUE_36,
                        help=f"earlier commit to compare with (default {BEFORE_ISSUE_36}, before issue 36)")
    args = parser.parse_args()
    now = CLOCKS[args.clock]
    rng = np.random.default_rng(2026)
    rows = []
    for n, rep_ref in ((2000, 7), (60000, 3)):
        y = ar6(n, rng)
        ours = median_time(lambda: tsfdi.select_order(y, 50, trend="c").selected, 200)
        ref = median_time(lambda: ar_select_order(y, 50, ic="bic", trend="c"), rep_ref, budget=60)
        p_ours = tsfdi.select_order(y, 50, trend="c").selected
        p_ref = max(ar_select_order(y, 50, ic="bic", trend="c").ar_lags)
        rows.append((f"AR N={n}", ours, ref, p_ours, p_ref))
    Y = var4(2000, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ours = median_time(lambda: tsfdi.select_order(Y, 20, "var", trend="c").selected, 200)
        ref = median_time(lambda: smVAR(Y).select_order(20, trend="c"), 7)
        p_ref = smVAR(Y).select_order(20, trend="c").selected_orders["bic"]
    rows.append(("VAR N=2000", ours, ref, tsfdi.select_order(Y, 20, "var", trend="c").selected, p_ref))

    print(f"{'case':<12} {'tsfdi (ms)':>11} {'statsmodels (ms)':>17} {'ratio':>9} {'target':>7}  "
          f"{'order tsfdi':>11} {'order sm':>8}")
    ok = True
    for name, ours, ref, p_ours, p_ref in rows:
        ratio = ref / ours
        ok &= ratio >= TARGETS[name] and p_ours == p_ref
        print(f"{name:<12} {1e3 * ours:>11.3f} {1e3 * ref:>17.1f} {ratio:>8.0f}x {TARGETS[name]:>6}x  "
              f"{p_ours:>11d} {p_ref:>8d}")
    print("all targets met and the same orders selected" if ok else "SOME TARGET MISSED OR ORDERS DIFFER")
    compare({"select_ar_2000": ("select_order(y, 50), AR, N = 2,000", 50),
             "select_ar_60000": ("select_order(y, 50), AR, N = 60,000", 15),
             "select_var_2000": ("select_order(Y, 20, 'var'), 3 channels, N = 2,000", 50)},
            args.against, rounds=3, clock=args.clock)


if __name__ == "__main__":
    main()

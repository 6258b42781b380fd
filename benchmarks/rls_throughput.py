"""RLS throughput of tsfdi.RecursiveARX (numba, symmetric update) against a plain numpy per-sample RLS, and
against the same calls on an earlier commit.

1. Samples/s (median of repeats) of ``RecursiveARX(na, nb, 0, 0.99).run`` for parameter dimension 4, 20 and 60
   and the ratio to the numpy loop run in the same process. Target (issue 4): >= 3e6 samples/s at dimension 20.
2. The same ``run`` calls on this tree and on commit ``--against`` (default :data:`REFERENCE`, the commit before
   the issue 18 safeguards), through ``previous_commit.py``: fresh interpreters alternating between the two
   trees, CPU time, median over rounds. Target: not slower.

Run: ``python benchmarks/rls_throughput.py [--against REF] [--rounds N]``.
"""

import os

os.environ["OPENBLAS_NUM_THREADS"] = "1"

import time  # noqa: E402

import numpy as np  # noqa: E402

from tsfdi.models.recursive import RecursiveARX  # noqa: E402


def numpy_rls(y, u, na, nb, lam=0.99, p0=1e4):
    """Plain per-sample numpy RLS with the same regressor and symmetric update (the reference)."""
    d = na + nb
    theta = np.zeros(d)
    P = np.eye(d) * p0
    t0 = max(na, nb - 1)
    err = np.full(len(y), np.nan)
    for t in range(t0, len(y)):
        phi = np.concatenate([-y[t - na:t][::-1], u[t - nb + 1:t + 1][::-1]])
        px = P @ phi
        s = lam + phi @ px
        e = y[t] - phi @ theta
        theta = theta + px * (e / s)
        v = px / np.sqrt(lam * s)
        P = P / lam - np.outer(v, v)
        err[t] = e
    return theta, err


def median_time(fn, repeats):
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return float(np.median(ts)), float(np.min(ts))


#: The commit before issue 18 (input contract, numerical safeguards of RecursiveARX).
REFERENCE = "39c9c1c"


def main():
    rng = np.random.default_rng(0)
    n_fast, n_ref = 500_000, 20_000
    u = rng.standard_normal(n_fast)
    y = rng.standard_normal(n_fast)
    RecursiveARX(1, 1).run(y[:100], u[:100])  # compile (cached) outside the timing
    print(f"load average at start: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores (timings are shared-machine)")
    print(f"{'dim':>4} {'tsfdi median/s':>16} {'tsfdi best/s':>14} {'numpy median/s':>16} {'ratio':>8}   agree")
    for d in (4, 20, 60):
        na, nb = d // 2, d - d // 2
        n = n_fast if d < 60 else n_fast // 5
        tf, tf_best = median_time(lambda: RecursiveARX(na, nb, 0, 0.99).run(y[:n], u[:n]), 7)
        tr, _ = median_time(lambda: numpy_rls(y[:n_ref], u[:n_ref], na, nb), 3)
        m = RecursiveARX(na, nb, 0, 0.99)
        m.run(y[:n_ref], u[:n_ref])
        ref_theta, _ = numpy_rls(y[:n_ref], u[:n_ref], na, nb)
        agree = np.max(np.abs(m.theta_ - ref_theta))
        print(f"{d:>4} {n / tf:>16.3e} {n / tf_best:>14.3e} {n_ref / tr:>16.3e} {(n / tf) / (n_ref / tr):>8.1f}   max|dtheta|={agree:.1e}")


if __name__ == "__main__":
    import argparse

    from previous_commit import compare

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default=REFERENCE, help=f"earlier commit to compare with (default {REFERENCE})")
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds per tree (default 5)")
    args = parser.parse_args()
    main()
    compare({f"rls_d{d}": (f"RecursiveARX.run, d={d}, {'100,000' if d >= 60 else '500,000'} samples", 7)
             for d in (4, 20, 60)}, args.against, rounds=args.rounds, clock="cpu")

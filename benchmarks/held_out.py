"""Cost of held-out residuals (issue 17) against one fit and against refitting without each record.

``spec.held_out_residuals()`` downdates the Gram matrices summed over the records (one small solve per
held-out record or block) instead of refitting. Measured in one run, BLAS pinned to one thread, medians over
repeats:

1. VAR(20), 3 channels, trend "c", 10 records of 2,000 samples: ``held_out_residuals()`` against one
   ``spec.fit()`` and against the naive path (10 refits on the other records + ``residuals(record_j)``).
   Target: held-out / one fit <= 3.
2. AR(20), trend "c", 10 records of 2,000 samples: same comparison.
3. VAR(20), 3 channels, one record of 20,000 samples in 10 blocks: against one fit and against 10 explicit
   least-squares fits on the other blocks' rows (SVD solver, as ``fit``) + the block's residuals.

Each case also checks that the held-out residuals equal the naive ones (max relative difference printed).

Run: ``python benchmarks/held_out.py``.
"""

import os

os.environ["OPENBLAS_NUM_THREADS"] = "1"
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from scipy import linalg  # noqa: E402
from scipy import signal as sps  # noqa: E402

import tsfdi  # noqa: E402

TARGET = 3.0


def median_time(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def resonant_record(rng, n, s):
    """``s`` channels, each a sum of damped resonances (poles of modulus 0.95 .. 0.7), mixed across channels."""
    z = []
    for c in range(s):
        poles = []
        for k, f in enumerate((0.04, 0.13, 0.22, 0.31)):
            r = 0.95 - 0.08 * k
            f = f + 0.01 * c
            poles += [r * np.exp(2j * np.pi * f), r * np.exp(-2j * np.pi * f)]
        z.append(sps.lfilter([1.0], np.real(np.poly(poles)), rng.standard_normal(n + 500))[500:])
    mix = np.eye(s) + 0.3 * rng.standard_normal((s, s))
    return np.column_stack(z) @ mix.T + 0.5


def max_rel(a, b):
    a, b = np.concatenate([np.asarray(x).ravel() for x in a]), np.concatenate([np.asarray(x).ravel() for x in b])
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def report(name, t_held, t_fit, t_naive, diff):
    ratio = t_held / t_fit
    print(f"{name}")
    print(f"  held_out_residuals(): {t_held * 1e3:8.2f} ms")
    print(f"  one fit():            {t_fit * 1e3:8.2f} ms   held-out / fit   = {ratio:5.2f}  "
          f"(target <= {TARGET:g}) {'PASS' if ratio <= TARGET else 'FAIL'}")
    print(f"  naive (10 refits):    {t_naive * 1e3:8.2f} ms   naive / held-out = {t_naive / t_held:5.1f}x")
    print(f"  max |held-out - naive| / max |naive| = {diff:.2e}")
    return ratio <= TARGET


def bench_records(kind, repeat):
    rng = np.random.default_rng(17)
    if kind == "var":
        records = [resonant_record(rng, 2000, 3) for _ in range(10)]
        cls, name = tsfdi.VAR, "VAR(20), 3 channels, trend 'c', 10 records x 2,000 samples"
    else:
        records = [resonant_record(rng, 2000, 1)[:, 0] for _ in range(10)]
        cls, name = tsfdi.AR, "AR(20), trend 'c', 10 records x 2,000 samples"
    spec = cls(records, 20, "c")

    def naive():
        out = []
        for j in range(len(records)):
            others = [r for i, r in enumerate(records) if i != j]
            out.append(cls(others, 20, "c").fit().residuals(records[j]))
        return out

    spec.held_out_residuals(), spec.fit(), naive()          # warm up (compiled kernels, caches)
    t_held = median_time(spec.held_out_residuals, repeat)
    t_fit = median_time(spec.fit, repeat)
    t_naive = median_time(naive, max(3, repeat // 3))
    return report(name, t_held, t_fit, t_naive, max_rel(spec.held_out_residuals(), naive()))


def bench_blocks(repeat):
    rng = np.random.default_rng(18)
    y = resonant_record(rng, 20000, 3)
    spec = tsfdi.VAR(y, 20, "c")

    def naive():
        X, Y = spec.design_all()
        edges = np.r_[0, np.cumsum([len(c) for c in np.array_split(np.arange(X.shape[0]), 10)])]
        out = []
        for lo, hi in zip(edges[:-1], edges[1:]):
            keep = np.r_[0:lo, hi:X.shape[0]]
            B = linalg.lstsq(X[keep], Y[keep], lapack_driver="gelsd", check_finite=False)[0]
            out.append(Y[lo:hi] - X[lo:hi] @ B)
        return out

    spec.held_out_residuals(), spec.fit(), naive()
    t_held = median_time(spec.held_out_residuals, repeat)
    t_fit = median_time(spec.fit, repeat)
    t_naive = median_time(naive, max(3, repeat // 3))
    return report("VAR(20), 3 channels, trend 'c', one record x 20,000 samples in 10 blocks",
                  t_held, t_fit, t_naive, max_rel(spec.held_out_residuals(), naive()))


def main():
    warnings.simplefilter("ignore", tsfdi.exceptions.UnstableModelWarning)
    print(f"BLAS threads pinned to 1 (OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}); medians\n")
    ok = [bench_records("var", 15), bench_records("ar", 15), bench_blocks(15)]
    print(f"\noverall: {'PASS' if all(ok) else 'FAIL'}")


if __name__ == "__main__":
    main()

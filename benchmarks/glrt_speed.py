"""Speed of the GLRT statistic (issue 36 acceptance: >= 5x a plain numpy O(N M) scan), N = 60,000, M = 500.

1. ``tsfdi.GLRT(500, scale=1.0).statistic`` on 60,000 standard normal samples against the O(N M) scan written in
   plain numpy (one vector operation per post-change length ``n``: the window sums as differences of a cumulative
   sum, an elementwise maximum), results checked equal (relative 1e-12). Medians of CPU time (``--clock wall`` for
   wall-clock time), BLAS on one thread.
2. The compiled kernel's assembly: packed (SIMD) double-precision instructions of the scan (the kernel before
   issue 36 compiled to scalar code).
3. The same ``statistic`` call on this tree against the commit before issue 36 (``previous_commit.py``; ``--against
   REF`` picks another commit), fresh interpreters, interleaved rounds.

Run: ``python benchmarks/glrt_speed.py [--against REF] [--clock cpu|wall]``.
"""

import os

os.environ["OPENBLAS_NUM_THREADS"] = "1"
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import collections  # noqa: E402
import platform  # noqa: E402
import re  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.detection import glrt as glrt_module  # noqa: E402
from previous_commit import BEFORE_ISSUE_36, median_time, compare  # noqa: E402

N, M = 60_000, 500


def numpy_scan(x: np.ndarray, window: int, scale: float) -> np.ndarray:
    """g(k) = max over n <= min(window, k + 1) of (sum of the last n samples)^2 / (2 scale^2 n): O(N M) in numpy."""
    c = np.concatenate([[0.0], np.cumsum(x)])
    g = np.zeros(x.size)
    for n in range(1, min(window, x.size) + 1):
        d = c[n:] - c[:-n]
        np.maximum(g[n - 1:], d * d * (1.0 / (2.0 * scale ** 2 * n)), out=g[n - 1:])
    return g


def packed_instructions() -> collections.Counter:
    """Packed double-precision instructions in the GLRT scan kernel, compiled afresh (a cached dispatcher cannot be
    inspected) with the kernel's own options."""
    kernel = numba.njit(nogil=True, fastmath=True)(glrt_module._scan_g.py_func)
    kernel(np.zeros(10), 0, 5, 0.5)
    asm = "\n".join(kernel.inspect_asm().values())
    return collections.Counter(re.findall(r"\b(v?(?:add|sub|mul|max|cmp\w*)pd)\b", asm))


def main(clock: str) -> None:
    x = np.random.default_rng(0).standard_normal(N)
    gl = tsfdi.GLRT(M, scale=1.0)
    g = np.asarray(gl.statistic(x))                      # compile
    ref = numpy_scan(x, M, 1.0)
    np.testing.assert_allclose(g, ref, rtol=1e-12)
    err = float(np.max(np.abs(g - ref) / ref))
    t_ours = median_time(lambda: gl.statistic(x), repeat=15, number=5, clock=clock)
    t_np = median_time(lambda: numpy_scan(x, M, 1.0), repeat=7, clock=clock)
    ratio = t_np / t_ours
    print(f"[GLRT] N = {N:,}, window M = {M}, medians of {clock} time, results equal (max relative "
          f"difference {err:.1e})")
    print(f"  tsfdi GLRT.statistic              {t_ours * 1e3:8.2f} ms")
    print(f"  plain numpy O(N M) scan           {t_np * 1e3:8.2f} ms   ratio {ratio:5.1f}x  "
          f"-> {'PASS' if ratio >= 5 else 'FAIL'} (>= 5x)")
    if platform.machine() in ("x86_64", "AMD64"):
        packed = packed_instructions()
        print(f"  compiled scan kernel: packed instructions {dict(packed) or 'none (scalar code)'}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default=BEFORE_ISSUE_36,
                        help=f"earlier commit to compare with (default {BEFORE_ISSUE_36}, before issue 36)")
    parser.add_argument("--clock", default="cpu", choices=("cpu", "wall"))
    args = parser.parse_args()
    main(args.clock)
    compare({"glrt": (f"GLRT(500).statistic, N = {N:,}", 15)}, args.against, rounds=5, clock=args.clock)

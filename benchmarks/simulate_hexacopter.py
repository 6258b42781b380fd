"""Wall time to generate the full shipped design (240 records x 60 s at 1 kHz, decimated to 100 Hz).

Prints the time of one full generation (after a short warm-up run that loads the cached numba code),
its ratio to the 5-minute target of issue 5, and the real-time factor (simulated seconds per wall second).
Run: ``python benchmarks/simulate_hexacopter.py [--repeat N]``.
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from tsfdi.datasets import make_hexacopter_dataset  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    t0 = time.perf_counter()
    make_hexacopter_dataset(1, duration=1.0, failure_time=0.5)
    print(f"warm-up (numba load/compile, 12 records x 1 s): {time.perf_counter() - t0:.2f} s")
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        ds = make_hexacopter_dataset(20, seed=2024)
        times.append(time.perf_counter() - t0)
    med = float(np.median(times))
    simulated = ds.sizes["record"] * 60.0
    print(f"cpu cores: {os.cpu_count()}")
    print(f"full design: {ds.sizes['record']} records x 60 s at 1000 Hz -> 100 Hz, "
          f"lost control in {int(ds['lost_control'].sum())} records")
    print(f"wall time (median of {args.repeat}): {med:.1f} s")
    print(f"ratio to the 300 s target: {med / 300.0:.3f}")
    print(f"real-time factor: {simulated / med:.0f}x ({simulated:.0f} simulated s)")


if __name__ == "__main__":
    main()

"""Wall time of the hexacopter simulator: the previous aircraft (``BIDIRECTIONAL_HEXACOPTER``, lumped rotors,
fixed gains) against the default (blade-element rotors with dynamic inflow, one-way rotors, scheduled gains).

Prints, in one run, for each aircraft: one 60 s record at 1 kHz (severe turbulence, rotor 2 failed at 10 s) on one
core (numba threads 1; median of ``--repeat``), and the full design (240 records x 60 s at 1 kHz, decimated to
100 Hz) on every core. Target of issue 30: <= 5 s per 60 s record on one core.
Run: ``python benchmarks/simulate_hexacopter.py [--repeat N] [--no-design]``.
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402

from tsfdi.datasets import BIDIRECTIONAL_HEXACOPTER, make_hexacopter_dataset, simulate_hexacopter  # noqa: E402

AIRCRAFT = {"bidirectional (previous, lumped rotors)": BIDIRECTIONAL_HEXACOPTER, "regular (default, BET)": None}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-design", action="store_true", help="skip the 240-record design")
    args = ap.parse_args()
    t0 = time.perf_counter()
    for params in AIRCRAFT.values():
        make_hexacopter_dataset(1, duration=1.0, failure_time=0.5, params=params)
    print(f"warm-up (numba load/compile, 2 x 12 records x 1 s): {time.perf_counter() - t0:.2f} s")
    cores = numba.get_num_threads()
    print(f"cpu cores: {os.cpu_count()}, numba threads: {cores}")
    for name, params in AIRCRAFT.items():
        numba.set_num_threads(1)
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            simulate_hexacopter(duration=60.0, turbulence="severe", failed_rotor=2, seed=1, params=params)
            times.append(time.perf_counter() - t0)
        numba.set_num_threads(cores)
        print(f"{name}: one 60 s record at 1 kHz on one core: {np.median(times):.2f} s (median of {args.repeat}; "
              f"target 5 s)")
    if args.no_design:
        return
    for name, params in AIRCRAFT.items():
        t0 = time.perf_counter()
        ds = make_hexacopter_dataset(20, seed=2024, params=params)
        wall = time.perf_counter() - t0
        simulated = ds.sizes["record"] * 60.0
        print(f"{name}: full design {ds.sizes['record']} records x 60 s at 1000 Hz -> 100 Hz on {cores} threads: "
              f"{wall:.1f} s, real-time factor {simulated / wall:.0f}x, lost control in "
              f"{int(ds['lost_control'].sum())} records")


if __name__ == "__main__":
    main()

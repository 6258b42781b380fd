"""Record-level calibration on the next aircraft of a fleet (issue 31).

1. A simulated fleet: VAR(2) records whose coefficients (``A + 0.04 N(0, 1)``) and innovation scale (log-normal
   +-15 % per record and channel) vary from aircraft to aircraft. A baseline VAR(2) is fitted on 5, 10 or 20
   records, the F and Ljung-Box tests (Sidak over the 3 channels, so alpha is the decision's rate) are calibrated on
   its held-out residuals (windows of 200 samples), and 60 new records of the same fleet (600 disjoint windows) are
   judged. Over ``--fleets`` fleets: the realised rate of the decision averaged over fleets, its spread, and how
   many fleets fall in the two-sided 99.9 % binomial band of one fleet's 600 windows; "old" is the per-record
   mixture with a 90 % bootstrap bound (``record_effect="bootstrap"``), "new" the predictive record-level law.
2. The realistic hexacopter (``tsfdi.datasets.simulate_hexacopter``) with a fleet spread (payload 30 %, airframe):
   healthy records only, a VAR fitted on some aircraft, calibrated on its held-out residuals, the others judged.

Run: ``python benchmarks/fleet_calibration.py [--fleets 40]``.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

import tsfdi  # noqa: E402

A1 = np.array([[0.5, 0.1, 0.0], [0.0, 0.4, 0.1], [0.1, 0.0, 0.3]])
A2 = -0.2 * np.eye(3)
N, WINDOW, SPREAD, NOISE = 2000, 200, 0.04, 0.15
RECORDS, NEW, ALPHAS = (5, 10, 20), 60, (1e-2, 1e-3)


def fleet_records(rng: np.random.Generator, count: int, n: int = N) -> list:
    """``count`` records of the fleet: VAR(2) with coefficients ``A + SPREAD N(0, 1)`` and innovations scaled by
    ``exp(NOISE N(0, 1))`` per record and channel (+-15 %, log-normal) (all records simulated at once)."""
    b1 = A1 + SPREAD * rng.standard_normal((count, 3, 3))
    b2 = A2 + SPREAD * rng.standard_normal((count, 3, 3))
    e = rng.standard_normal((n + 200, count, 3)) * np.exp(NOISE * rng.standard_normal((count, 3)))
    y = np.zeros_like(e)
    for t in range(2, n + 200):
        y[t] = np.einsum("rij,rj->ri", b1, y[t - 1]) + np.einsum("rij,rj->ri", b2, y[t - 2]) + e[t]
    return [y[200:, r] for r in range(count)]


def make_test(family: str, alpha: float, effect: str):
    thr = tsfdi.ScaledChi2Threshold(alpha, record_effect=effect)
    if family == "F":
        return tsfdi.FTest(alpha=alpha, correction="sidak", threshold=thr)
    return tsfdi.LjungBox(lags=20, alpha=alpha, correction="sidak", threshold=thr)


def decision_rate(test, new_resid: list) -> float:
    """Fraction of the disjoint windows of the new records' residuals whose decision (any channel) rejects."""
    n = WINDOW - 2
    flags = []
    for e in new_resid:
        s = test.window_statistic(e, n, n, **getattr(test, "_bench_ref", {}))
        thr, _ = test.threshold_pvalue(s, n)
        flags.append((s > thr).any(axis=1))
    return float(np.concatenate(flags).mean())


def one_fleet(seed: int, records=RECORDS, alphas=ALPHAS, effects=("bootstrap", "predictive"),
              families=("F", "LB")) -> list:
    """Rows (records, alpha, family, effect, rate, threshold of channel 0) of one simulated fleet: the baselines fit
    on the first 5 / 10 / 20 records of the fleet, all judged on the same 60 new records."""
    rng = np.random.default_rng(seed)
    fit = fleet_records(rng, max(records))
    new = fleet_records(rng, NEW)
    rows = []
    for j in records:
        spec = tsfdi.VAR(fit[:j], 2)
        base = spec.fit()
        held = spec.held_out_residuals()
        resid = [np.asarray(base.residuals(x)) for x in new]
        for a in alphas:
            for fam in families:
                for eff in effects:
                    test = make_test(fam, a, eff).calibrate(held, window=WINDOW)
                    rows.append((j, a, fam, eff, decision_rate(test, resid), float(test.threshold_[0])))
    return rows


def band(n: int, alpha: float) -> tuple:
    """Two-sided 99.9 % binomial band of the rate in ``n`` independent windows."""
    lo, hi = stats.binom.ppf([0.0005, 0.9995], n, alpha)
    return lo / n, hi / n


def fleet_table(fleets: int, seed: int = 2031) -> None:
    import pandas as pd

    t0 = time.perf_counter()
    rows = [(f, *r) for f in range(fleets) for r in one_fleet(seed + f)]
    df = pd.DataFrame(rows, columns=["fleet", "records", "alpha", "test", "calibration", "rate", "threshold"])
    windows = NEW * ((N - 2) // (WINDOW - 2))
    out = []
    for (j, a, fam, eff), g in df.groupby(["records", "alpha", "test", "calibration"], sort=False):
        lo, hi = band(windows, a)
        lo_all, hi_all = band(windows * fleets, a)
        out.append({"records": j, "alpha": a, "test": fam, "calibration": eff,
                    "mean rate %": 100 * g.rate.mean(), "band (all fleets) %": f"{100 * lo_all:.3g}-{100 * hi_all:.3g}",
                    "median %": 100 * g.rate.median(), "p10-p90 %": f"{100 * g.rate.quantile(.1):.2f}-"
                    f"{100 * g.rate.quantile(.9):.2f}", "fleets in band": f"{((g.rate >= lo) & (g.rate <= hi)).sum()}/"
                    f"{len(g)}", "one-fleet band %": f"{100 * lo:.3g}-{100 * hi:.3g}",
                    "threshold y0": g.threshold.median()})
    print(f"simulated fleet: {fleets} fleets, {NEW} new records x {(N - 2) // (WINDOW - 2)} windows each, "
          f"Sidak over 3 channels ({time.perf_counter() - t0:.0f} s)")
    print(pd.DataFrame(out).to_string(index=False, float_format=lambda v: f"{v:.3g}"))


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fleets", type=int, default=40)
    p.add_argument("--no-hexacopter", action="store_true")
    args = p.parse_args(argv)
    fleet_table(args.fleets)


if __name__ == "__main__":
    main()

"""Speed of ``fit()`` (issue 36: least squares through the Gram matrix), in one run, BLAS pinned to one thread.

Prints the medians of

* ``VAR(records, 20, trend).fit()`` on 10 records of the shipped data (roll, pitch, yaw rate; 6,000 samples each),
  ``trend="c"`` and ``"n"``, and ``fit_baselines`` on the shipped data (the defaults, and 10 fitting records per
  state with VAR(20) on whole records, where the fit dominates): this tree against an earlier commit (``--against``,
  default :data:`AGAINST`, the commit before the Gram-matrix fit: the issue's reference) and against the previous
  commit (``--previous``, default :data:`PREVIOUS`), each measurement a fresh interpreter with that commit's
  ``tsfdi`` or this one first on ``PYTHONPATH`` (the mechanism of ``previous_commit.py``), the two alternating;
* ``VAR(y, 20, trend).fit()`` against statsmodels ``VAR(y).fit(20, trend=...)`` on the same data (one record, and
  the 10 records end to end as one signal: statsmodels fits one record), in this process, with the coefficients
  and the residual covariance checked equal (relative 1e-8) and the standard errors to 1e-5 (statsmodels inverts
  ``Z'Z``, which squares the condition number, ~1.7e6 here: its standard errors carry ~4e-6 relative error).

Time is CPU time of the process by default (``--clock cpu``; ``wall`` for wall-clock time): the machine is shared.

Run: python benchmarks/fit_speed.py [--against REF] [--previous REF] [--rounds 3] [--clock cpu|wall]
"""

from __future__ import annotations

import os

os.environ["OPENBLAS_NUM_THREADS"] = "1"
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from previous_commit import CLOCKS, compare, median_time  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: the commit before fit() went through the Gram matrix (issue 36)
AGAINST = "cf49e9f"
#: the commit before session 34's fit_baselines changes (issue 36: residual products in one compiled kernel, the
#: segments' extremes computed once; session 31's changes start after 1aa5ada)
PREVIOUS = "e75e770"
CHANNELS = ("roll", "pitch", "r")
#: workloads of benchmarks/previous_commit.py timed here: name -> (description, timed units per run)
WORKLOADS = {
    "var_fit_c": ("VAR(20, trend='c').fit(), 10 records x 6000 x 3", 7),
    "var_fit_n": ("VAR(20, trend='n').fit(), 10 records x 6000 x 3", 7),
    "fit_baselines": ("fit_baselines(shipped data), defaults", 7),
    "fit_baselines_var10": ("fit_baselines(.., 10 records/state, VAR(20), whole)", 7),
}


def _records(n_records: int = 10):
    import numpy as np

    from tsfdi.datasets import load_hexacopter

    ds = load_hexacopter(ROOT / "data" / "hexacopter.nc")
    return [np.column_stack([ds[c].isel(record=i).values for c in CHANNELS]) for i in range(n_records)]


def against_statsmodels(clock: str) -> None:
    import numpy as np
    from statsmodels.tsa.api import VAR as smVAR

    import tsfdi
    from tsfdi.exceptions import UnstableModelWarning

    recs = _records()
    now = CLOCKS[clock]
    print(f"\ntsfdi against statsmodels VAR(y).fit(20, trend) on the same signal (this process, median {clock} time; "
          "coefficients and residual covariance checked equal to 1e-8 relative, standard errors to 1e-5):")
    print(f"  {'case':<40} {'tsfdi':>10} {'statsmodels':>12} {'ratio':>8}  equal")
    for label, y in (("one record, 6000 x 3", recs[0]), ("10 records end to end, 60000 x 3", np.concatenate(recs))):
        for trend in ("c", "n"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UnstableModelWarning)
                ours = lambda: tsfdi.VAR(y, 20, trend=trend).fit()   # noqa: E731
                ref = lambda: smVAR(y).fit(20, trend=trend)          # noqa: E731
                res, sm = ours(), ref()
                t_ours = median_time(ours, 7, max(1, int(0.1 / _once(ours, now))), clock)
                t_ref = median_time(ref, 5, 1, clock)

            def close(a, b, rtol=1e-8):
                return bool(np.allclose(a, b, rtol=rtol, atol=rtol * np.abs(b).max()))

            sign = np.r_[np.ones(res.model.k_const), -np.ones(res.params2d.shape[0] - res.model.k_const)][:, None]
            equal = (close(res.params2d, sign * sm.params) and close(res.bse, sm.stderr, 1e-5)
                     and close(res.sigma, sm.sigma_u_mle))
            print(f"  {label + ', trend=' + repr(trend):<40} {t_ours * 1e3:8.2f}ms {t_ref * 1e3:10.1f}ms "
                  f"{t_ref / t_ours:7.1f}x  {'yes' if equal else 'NO'}")


def _once(fn, now) -> float:
    t0 = now()
    fn()
    return max(now() - t0, 1e-6)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default=AGAINST, help="earlier commit to compare with (default %(default)s)")
    parser.add_argument("--previous", default=PREVIOUS, help="previous commit (default %(default)s)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--clock", choices=("cpu", "wall"), default="cpu")
    args = parser.parse_args()
    compare(WORKLOADS, against=args.previous, rounds=args.rounds, clock=args.clock)
    ratios = {name: prev / cur for name, (prev, cur) in
              compare(WORKLOADS, against=args.against, rounds=args.rounds, clock=args.clock).items()}
    against_statsmodels(args.clock)
    print(f"\nIssue 36 acceptance: VAR(20) fit on 10 records >= 30x: {min(ratios['var_fit_c'], ratios['var_fit_n']):.1f}x "
          f"(worse trend); fit_baselines >= 5x: {ratios['fit_baselines']:.1f}x (defaults), "
          f"{ratios['fit_baselines_var10']:.1f}x (10 records/state, VAR(20))")


if __name__ == "__main__":
    main()

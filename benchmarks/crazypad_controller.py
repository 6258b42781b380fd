"""Controller-aware against response-only models on CrazyPAD (issue 32): detection of the propeller-M3 cut flights.

Run: ``python benchmarks/crazypad_controller.py [--data PATH]`` (reads ``../shared/data/crazypad`` next to the
repository; BLAS pinned to one thread; prints its run time).

The question. A Crazyflie's attitude loop compensates a shortened propeller: the gyro rates it regulates stay
close to normal, the commands it sends take up the lost thrust. A model of the rates alone sees little; a model of
the rates *given the commands* (the command-response relation, VARX with the commands as inputs) should see that
the same rates now need other commands. Three baselines of the same flights, in one run:

- ``VAR gyro``: VAR of the gyro rates ``controller.r_{roll,pitch,yaw}`` (response only);
- ``VAR gyro+cmd``: VAR of the rates and the commands ``controller.cmd_{roll,pitch,yaw}`` as six channels (how
  the command line could use commands before ``--u``);
- ``VARX gyro|cmd``: one VARX of the three rates given the three commands (``tsfdi.VARX``, ``nk = 0``,
  ``nb = lags``), tested through the windowed engine with ``u`` (``tsfdi.ResidualWindows(...).fit(y, u=...)``).
  Until issue 32's VARX this row combined three scalar ARX models, one per axis (each axis its own order, its
  likelihood the sum of the three axes' as if their residuals were independent); the VARX couples the axes in one
  model and one residual covariance.

Data and settings, all fixed before looking at a faulty flight, or chosen on normal flights only:

- drone E8 (the airframe of the whole M3 cut series; the two airframes' trims differ, so they are not pooled):
  its 5 normal-flight logs, and every E8 log of the 17 ``cut_propeller_M3_*`` conditions; airborne segments of
  :func:`tsfdi.datasets.load_crazypad` with its default margin of 1 s after take-off and before landing (the data's
  README), two segments per log, held out together;
- trend ``"c"`` and the order of every model by BIC, ``select_order(max_lags=20)``, on the fitting normal logs of
  each fold;
- windows of 2 s (202 samples at 101 Hz), step 2 s (independent windows), ``alpha = 0.01`` for the decision of a
  window: a model flags a window when one channel (axis) rejects, each at the Sidak share of alpha over the
  channels (3, 6 or 3), so that every model's decision has size alpha;
- tests: ``F`` (variance, ``tsfdi.FTest``), ``M`` (mean shift, ``tsfdi.MeanTest``) and ``F+M``
  (``tsfdi.AnyOf`` of both at their Sidak shares), thresholds calibrated on the held-out residuals of the fitting
  logs (``ScaledChi2Threshold(alpha, min_windows=5, min_records=2)``, as ``benchmarks/crazypad.py``: the short
  flights hold fewer than 30 windows).

Sections: (1) false alarms, leave one normal log out (5 folds: fitted and calibrated on the other 4 logs, tested on
the held-out log), with the 99 % binomial band of alpha; (2) detection: fitted on the 5 normal logs, the percent of
the 2 s windows flagged on every M3 cut flight, per condition and over all of them; (3) identification among five
conditions of the cut depth series, chosen before any run (``IDENTIFY``: normal flight and the M3 cuts of 1, 2, 3
and 4 mm on both edges), leave one flight out: one model per condition and kind (the held-out flight's own
condition fitted on its other logs, every other condition on all its logs), each with the ``F+M`` test calibrated
on its own held-out residuals; every 2 s window, step 0.5 s, of the held-out flight is labelled by the paper rule
(the one accepted model) and the likelihood rule (the most likely accepted model, any model when none is accepted;
each model's Gaussian log-likelihood under its own residual covariance), percent of the windows correct.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.datasets import load_crazypad  # noqa: E402
from tsfdi.models import VARX  # noqa: E402

GYRO = ["controller.r_roll", "controller.r_pitch", "controller.r_yaw"]
CMD = ["controller.cmd_roll", "controller.cmd_pitch", "controller.cmd_yaw"]
DRONE = "E8"
WINDOW_S = 2.0
ALPHA = 0.01
MAX_LAGS = 20
FAMILIES = ("F", "M", "F+M")
MODELS = ("VAR gyro", "VAR gyro+cmd", "VARX gyro|cmd")
#: each model's outputs and inputs
COLUMNS = {"VAR gyro": (GYRO, None), "VAR gyro+cmd": (GYRO + CMD, None), "VARX gyro|cmd": (GYRO, CMD)}
IDENTIFY = ("normal_flight", "cut_propeller_M3_1mm_1mm_45mm", "cut_propeller_M3_2mm_2mm_43mm",
            "cut_propeller_M3_3mm_3mm_41mm", "cut_propeller_M3_4mm_4mm_39mm")
IDENTIFY_STEP_S = 0.5


def segments(root: Path, condition: str) -> list[pd.DataFrame]:
    return load_crazypad(root, condition=condition, drone=DRONE, columns=GYRO + CMD)


def logs_of(segs: list) -> dict:
    out: dict = {}
    for s in segs:
        out.setdefault(s.attrs["log"], []).append(s)
    return out


def make_test(family: str, alpha: float):
    thr = tsfdi.ScaledChi2Threshold(alpha, min_windows=5, min_records=2)
    if family == "F+M":      # each part at its Sidak share of alpha: "any part rejects" has size alpha
        return tsfdi.AnyOf([make_test("F", alpha), make_test("M", alpha)])
    cls = tsfdi.FTest if family == "F" else tsfdi.MeanTest
    return cls(alpha=alpha, correction="sidak", threshold=thr)


class Baseline:
    """One model kind fitted on normal segments: the results (a VAR, or a VARX given the commands), a test per
    family calibrated on its held-out residuals; ``flags(segment)`` the windows it flags."""

    def __init__(self, kind: str, segs: list, W: int) -> None:
        self.kind, self.W = kind, W
        self.cols, self.inputs = COLUMNS[kind]
        groups = [s.attrs["log"] for s in segs]
        recs = [s[self.cols] for s in segs]
        if self.inputs is None:
            p = int(tsfdi.select_order(recs, MAX_LAGS, "var", trend="c").selected)
            spec = tsfdi.VAR(recs, p, trend="c")
        else:
            us = [s[self.inputs] for s in segs]
            p = int(tsfdi.select_order(recs, MAX_LAGS, "varx", u=us, trend="c").selected)
            spec = VARX(recs, us, p, nk=0, trend="c")
        self.res = spec.fit()
        held = spec.held_out_residuals(groups=groups)
        self.tests = {f: make_test(f, ALPHA).calibrate(held, window=W, step=1) for f in FAMILIES}
        self.order = int(self.res.model.max_lag)

    def engine(self, seg: pd.DataFrame) -> tsfdi.ResidualWindows:
        u = None if self.inputs is None else seg[self.inputs]
        return tsfdi.ResidualWindows({"m": self.res}).fit(seg[self.cols], u=u)

    def windows(self, seg: pd.DataFrame, family: str, step: int, common: int) -> tuple:
        """Every window (``self.W``, ``step`` apart) of ``seg`` under ``family``: rejected and the log-likelihood
        score on the samples from ``common`` on."""
        ws = self.engine(seg).statistics(self.tests[family], window=self.W, step=step, common=common)
        return ws.reject[:, 0], ws.loglik[:, 0]

    def flags(self, seg: pd.DataFrame) -> dict:
        """Family -> bool per 2 s window (step = window) of ``seg``."""
        rw = self.engine(seg)
        return {f: rw.statistics(self.tests[f], window=self.W, step=self.W, loglik=False).reject[:, 0]
                for f in FAMILIES}


def identification(root: Path, W: int, step: int) -> pd.DataFrame:
    """Section 3: percent of the windows of the held-out flights labelled with their own condition."""
    flights = {c: logs_of(segments(root, c)) for c in IDENTIFY}
    rows = []
    for kind in MODELS:
        full = {c: Baseline(kind, [s for segs in fl.values() for s in segs], W) for c, fl in flights.items()}
        counts = {r: [0, 0] for r in ("paper", "likelihood")}
        status = np.zeros(3, dtype=int)         # paper rule: identified, ambiguous, none
        for c, fl in flights.items():
            for out, held in fl.items():
                models = {**full, c: Baseline(kind, [s for log, segs in fl.items() if log != out for s in segs], W)}
                common = max(b.order for b in models.values())
                truth = list(models).index(c)
                for seg in held:
                    got = [models[m].windows(seg, "F+M", step, common) for m in models]
                    acc = ~np.column_stack([g[0] for g in got])
                    ll = np.column_stack([g[1] for g in got])
                    for rule in counts:
                        lab = tsfdi.windows.decide(acc, rule, loglik=ll)
                        counts[rule][0] += int((lab == truth).sum())
                        counts[rule][1] += lab.size
                    n_acc = acc.sum(axis=1)
                    status += [int((n_acc == 1).sum()), int((n_acc > 1).sum()), int((n_acc == 0).sum())]
        n = status.sum()
        rows.append({"model": kind, **{f"{r} rule": f"{100 * k / n:.1f} %" for r, (k, n) in counts.items()},
                     "windows": n, **{f"paper: {w}": f"{100 * c / n:.1f} %"
                                      for w, c in zip(("identified", "ambiguous", "none"), status)}})
    return pd.DataFrame(rows)


def band(n: int, p: float) -> tuple:
    return stats.binom.ppf(0.005, n, p) / n, stats.binom.isf(0.005, n, p) / n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "crazypad"))
    args = ap.parse_args()
    root = Path(args.data)
    t0 = time.perf_counter()
    normal = logs_of(segments(root, "normal_flight"))
    fs = normal[next(iter(normal))][0].attrs["fs"]
    W = int(round(WINDOW_S * fs))
    cuts = sorted(c for c in tsfdi.datasets.list_crazypad(root)["condition"].unique()
                  if c.startswith("cut_propeller_M3_"))
    print(f"drone {DRONE}: {len(normal)} normal logs, {len(cuts)} M3 cut conditions; window {W} samples "
          f"({WINDOW_S:g} s at {fs:.4g} Hz), step = window, alpha {ALPHA}")

    # 1. false alarms, leave one normal log out
    fa = {(m, f): [0, 0] for m in MODELS for f in FAMILIES}
    for out in normal:
        fit = [s for log, segs in normal.items() if log != out for s in segs]
        for kind in MODELS:
            base = Baseline(kind, fit, W)
            for seg in normal[out]:
                for f, rej in base.flags(seg).items():
                    fa[kind, f][0] += int(rej.sum())
                    fa[kind, f][1] += rej.size
            print(f"  fold {out}: {kind} order {base.order}")
    # 2. detection of the M3 cut flights, baseline on every normal log
    full = {kind: Baseline(kind, [s for segs in normal.values() for s in segs], W) for kind in MODELS}
    print("orders on all normal logs: " + ", ".join(f"{k} {b.order}" for k, b in full.items()))
    det = {(m, f, c): [0, 0] for m in MODELS for f in FAMILIES for c in cuts}
    for c in cuts:
        for seg in segments(root, c):
            for kind, base in full.items():
                for f, rej in base.flags(seg).items():
                    det[kind, f, c][0] += int(rej.sum())
                    det[kind, f, c][1] += rej.size

    rows = []
    for kind in MODELS:
        for f in FAMILIES:
            k, n = fa[kind, f]
            lo, hi = band(n, ALPHA)
            d = np.array([det[kind, f, c] for c in cuts])
            big = [c for c in cuts if c.startswith(("cut_propeller_M3_3", "cut_propeller_M3_4"))]
            db = np.array([det[kind, f, c] for c in big])
            rows.append({"model": kind, "test": f, "false alarms": f"{k}/{n} ({100 * k / n:.1f} %)",
                         "99% band": f"{100 * lo:.1f}-{100 * hi:.1f} %",
                         "M3 cut windows flagged": f"{d[:, 0].sum()}/{d[:, 1].sum()} "
                                                   f"({100 * d[:, 0].sum() / d[:, 1].sum():.1f} %)",
                         "cuts >= 3 mm": f"{100 * db[:, 0].sum() / db[:, 1].sum():.1f} %"})
    print()
    print(pd.DataFrame(rows).to_string(index=False))
    print("\nper condition, percent of windows flagged (F+M):")
    per = pd.DataFrame({kind: [100 * det[kind, "F+M", c][0] / det[kind, "F+M", c][1] for c in cuts]
                        for kind in MODELS}, index=[c.removeprefix("cut_propeller_M3_") for c in cuts])
    print(per.round(1).to_string())
    print(f"\nidentification among {len(IDENTIFY)} conditions ({', '.join(IDENTIFY)}), leave one flight out, "
          f"windows of {WINDOW_S:g} s, step {IDENTIFY_STEP_S:g} s, F+M calibrated, percent of windows correct:")
    print(identification(root, W, int(round(IDENTIFY_STEP_S * fs))).to_string(index=False))
    print(f"\nrun time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()

"""Functionally pooled models (issue 32): fit and filtering cost against point models, and a first application,
the cut depth of CrazyPAD propeller M3 estimated from a flight (leave one depth out).

Run: ``python benchmarks/fp_models.py [--data PATH] [--lags N] [--degree D]`` (BLAS pinned to one thread; reads
``../shared/data/crazypad`` for sections 2-3, skipped with a message when it is missing; about 100 s on the 2-core
development machine (97 s in session 38), most of it the inner folds of section 2 and the nested folds of its
detection through models of the depth).

1. Cost, simulated FP-VAR data (6 channels, 16 operating points x 2 records x 2000 samples, lags 8, Legendre degree
   3): ``FPVAR.fit`` against the point models it replaces (one ``VAR`` per operating point) and one pooled ``VAR``
   on all records, best of 5 in one run; residual filtering of a 2000-sample record by ``FPResults.residuals(y, k)``
   against ``VARResults.residuals(y)``, and ``estimate_k`` on it.
2. CrazyPAD, propeller M3 cut series (the conditions ``cut_propeller_M3_<a>mm_<b>mm_<L>mm`` and
   ``cut_propeller_M3_0.5mm_46.5mm``: the blade length L in the name; the earlier series ``cut_propeller_M3_1mm``
   names no length and is left out). Operating parameter: the length removed, ``k = 47 - L`` mm (0.5 .. 8 mm, 16
   depths; per blade edge half of it). Margin, channels and corrupt-log rule are those of ``benchmarks/crazypad.py``
   (``crazypad.choose`` on all normal flights: take-off / landing margin from their altitude, gyro rates and
   attitude commands unless accelz earns its place; functions imported from it). Every airborne segment is one
   record. Leave one depth out: an FP-VAR (trend "c") fitted on the segments of the other 15 depths,
   ``estimate_k`` on each segment of the held-out depth, bounded to the fitted range (so the two end depths, outside
   the range of their fold, can at best reach the nearest fitted depth). Order and basis degree chosen once by
   ``select_fp_order`` (BIC, max lags ``crazypad.MAX_LAGS`` = 20, max degree 4) on all depths, the one choice that
   sees every depth (stated, not hidden): the BIC minimum over degrees >= 1, since degree 0 (a model that does not
   depend on the depth, which BIC prefers here: the depth's effect does not pay for a second copy of every
   coefficient) estimates nothing; ``--lags`` / ``--degree`` override it. Printed: per depth the estimates, and the
   RMSE of k_hat, the share of 95 % intervals that hold the true depth, per segment and per log (the mean of its
   segments' estimates), the coverage of the likelihood-ratio interval read off the profile curve, for pooled and
   for per-point weighted least squares, and with one FP-VAR per airframe (the airframe as a logged second k).
   The curvature interval holds the record's noise and the FP coefficients' error, not the flight-to-flight spread
   of the depth's effect (airframe, session, the cut itself), so it undercovers. With pooled LS the benchmark adds
   a between-flight variance component, chosen inside each fold on its fitting depths only: each fitting depth
   held out in turn from the fold's fitting depths (the model without both depths; ``estimate_k``'s first grid
   ``INNER_GRID`` points), ``tau^2 = max(0, mean(err^2 - se^2))`` over those estimates, per segment and per log
   (``spread``); the interval ``k_hat -+ 1.96 sqrt(se^2 + tau^2)``.
   Detection of the cut flights, every depth unseen: the healthy baselines of section 3 fitted on all normal
   flights (never a cut flight), ``LB+F+M`` at alpha 0.01 on disjoint 2 s windows; per depth the share of windows
   flagged and of flights detected (a flight is detected when its flagged windows lie above the two-sided 99 %
   binomial band of alpha for its windows), beside the normal flights' false-alarm rate of section 3.
   Detection through models of the depth (``depth_detection``): the normal flights (k = 0) and the cut flights fitted
   together, leave one depth out for the cut flights and one flight out for the normal ones (their false-alarm rate
   with its 99 % binomial band, 8 flights); one decision per flight (log) at alpha 0.01. (a) The FP-VAR over the
   depth (lags ``crazypad.choose``'s BIC order on the normal flights, degree 1 a priori: nothing chosen on a cut
   flight), ``estimate_k`` per segment bounded to the fitted range whose lower end is the normal flights' 0, the
   flight's statistic the sum over its segments of the likelihood ratio ``2 (llf(k_hat) - llf(0))``; nominally
   chi-bar-square (each segment's ratio half 0, half chi2_1: k = 0 is the boundary). (b) The controller's trim:
   ``tsfdi.FPMean`` of the three commands' 2 s window means over k = (depth, airframe) (airframe categorical,
   degree 1; depth degree 1-3 by BIC over the fold's fitting flights), one record per flight (its segments' whole
   windows), the flight's mean trim against the surface at its logged airframe with variance ``S_rec + S_within /
   windows``: ``q(0) - min q(k)`` over a depth grid, its minimum the depth estimate, the likelihood-ratio 95 %
   interval. (b0) The healthy trim: ``tsfdi.FPMean`` of the normal flights only over the airframe (no cut flight
   ever fitted), the flight's Mahalanobis distance from its airframe's trim, nominally chi2 with 3 degrees of
   freedom. (b1) The same with one record per segment over (airframe, segment position in the log): added after
   the first run of (a)-(b0) had been seen (so not a blind evaluation), from the structure of the normal flights
   alone: a log holds two short flights, and in every normal log the second's pitch command sits 2200-2800 above
   the first's, a systematic difference that (b0)'s spread of windows about the flight's mean counts as noise
   (within-flight pitch sd 1730 against 660 about each segment's own trim). Three rules per detector: nominal (the
   law above), calibrated (that point times the fold's scale, the mean statistic of its normal flights each left
   out in turn from the fold's fitting flights over its nominal mean: nested, the judged flight never fitted nor
   calibrated on) and window counting (each part, a segment for (a), a 2 s window for (b) / (b0) / (b1), against
   its nominal point, flagged parts above the flight's 99 % band). Depth RMSE and 95 % interval coverage per flight
   for (a) (curvature interval of the segments' mean) and (b).
3. CrazyPAD healthy flights of both airframes (E8, E9), leave one flight out over all normal flights, the choices
   of ``crazypad.choose`` on each fold's fitting flights, two baselines: pooled (one VAR of both airframes,
   ``crazypad.fit_model``, held-out residuals log by log) and FP (an FP-VAR whose k is the airframe, a category:
   the drones at evenly spaced points of [0, 1] with Legendre degree drones - 1, so one VAR per airframe estimated
   together; each flight filtered ``at`` its drone's k; held-out residuals: every fitting log through the FP-VAR
   refitted without it). What the data support as k: the controller logs carry no battery channel (the motor
   logs with ``pm.vbatMV`` cover nine conditions and do not pair with the controller logs), and a flight-level trim
   (the commands' mean, which moves between sessions of one drone) is not known before the flight: it would be
   estimated from the judged flight itself and absorb the new trim a compensated defect shows as. The drone is
   logged. Tests of ``crazypad.py`` (``LB-S``, ``F-S``, ``M-S`` and ``LB+F+M``, ``tsfdi.AnyOf`` of the three, each
   at its Sidak share so that alpha is the decision's rate), calibrated on the baseline's held-out residuals;
   false-alarm rate at alpha 0.01 on disjoint 2 s windows with its two-sided 99 % binomial band (8 flights, 32
   windows: the band is wide), and the rate of sliding 2 s windows (step 0.1 s, dependent: rate only).
4. Detectability limit of the M3 cut flights (``detectability``): per flight the summaries a detector can use
   (``flight_summaries``: the three attitude commands' and the thrust command's trims, each attitude command's log
   spread about its segment's mean, the healthy VAR's residual log generalised variance), each cut depth's shift in
   units of the normal flights' flight-to-flight sd (each airframe's mean, sd pooled over the airframes, 6 degrees of
   freedom) with its standard error over the depth's flights, and the power at that shift of the best test of that
   summary at a per-flight false-alarm rate of 0.01 with the null estimated from the 8 normal flights (predictive t;
   Hotelling for the three trims, (b0)'s summary, and the three spreads), beside (b0)'s calibrated detections; the
   scatter of the depths' mean shifts about a quadratic in the depth (every depth was flown in one session: a
   session's offset) against the normal flights' sd; then the predictive Hotelling test of the three command
   spreads, chosen after this analysis had been read (the cut flights were seen in earlier sessions, so this copy
   cannot test it blindly), its cut flights detected per depth and its normal flights alarmed (each left out).
"""

from __future__ import annotations

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import re  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import optimize, stats  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.models import FPVAR, fp_basis, select_fp_order  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import crazypad as cp  # noqa: E402

FULL_LENGTH_MM = 47.0
SERIES = re.compile(r"^cut_propeller_M3_(?:[0-9.]+mm_){1,2}([0-9.]+)mm$")


def best_of(fn, repeat: int = 5) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def simulate_fp_var(k: float, n: int, rng, s: int = 6, lags: int = 8) -> np.ndarray:
    """A stable VAR(lags) whose coefficients move smoothly with k in [0, 1]: a damped oscillation per channel
    (poles of modulus 0.6 + 0.2 k) and a weak coupling to the next channel growing with k; lags beyond 2 zero."""
    r, w = 0.6 + 0.2 * k, 0.4 + 0.6 * k
    A = np.zeros((lags, s, s))
    A[0] = -2 * r * np.cos(w) * np.eye(s) + 0.1 * k * np.roll(np.eye(s), 1, axis=1)
    A[1] = r * r * np.eye(s)
    e = rng.standard_normal((n + 200, s))
    y = np.zeros((n + 200, s))
    for t in range(2, n + 200):
        y[t] = e[t] - A[0] @ y[t - 1] - A[1] @ y[t - 2]
    return y[200:]


def cost() -> None:
    print("== 1. cost: FP-VAR against point VARs (6 channels, 16 points x 2 records x 2000 samples, lags 8, "
          "degree 3; best of 5)")
    rng = np.random.default_rng(32)
    ks = np.repeat(np.linspace(0, 1, 16), 2)
    recs = [simulate_fp_var(k, 2000, rng) for k in ks]
    spec = FPVAR(recs, ks, 8, 3, "c")
    t_fp = best_of(lambda: spec.fit())
    t_fp_spec = best_of(lambda: FPVAR(recs, ks, 8, 3, "c").fit())
    t_point = best_of(lambda: [tsfdi.VAR(recs[2 * i:2 * i + 2], 8, "c").fit() for i in range(16)])
    t_pooled = best_of(lambda: tsfdi.VAR(recs, 8, "c").fit())
    res = spec.fit()
    point = tsfdi.VAR(recs[:2], 8, "c").fit()
    y = simulate_fp_var(0.37, 2000, rng)
    t_res_fp = best_of(lambda: res.residuals(y, 0.37), 20)
    t_res_pt = best_of(lambda: point.residuals(y), 20)
    t_est = best_of(lambda: res.estimate_k(y), 3)
    est = res.estimate_k(y)
    print(f"  FPVAR fit (spec built once)          {t_fp * 1e3:8.1f} ms  ({res.model.df_eq} coefficients per "
          "equation)")
    print(f"  FPVAR spec + fit                     {t_fp_spec * 1e3:8.1f} ms")
    print(f"  16 point VAR fits (one per point)    {t_point * 1e3:8.1f} ms  -> FP / point = {t_fp_spec / t_point:.2f}")
    print(f"  one pooled VAR on all 32 records     {t_pooled * 1e3:8.1f} ms  -> FP / pooled = "
          f"{t_fp_spec / t_pooled:.2f}")
    print(f"  residuals of 2000 samples: FP at k {t_res_fp * 1e3:6.2f} ms, point VAR {t_res_pt * 1e3:6.2f} ms "
          f"-> ratio {t_res_fp / t_res_pt:.2f}")
    print(f"  estimate_k on 2000 samples           {t_est * 1e3:8.1f} ms  (true k 0.37: k_hat {est.k_hat[0]:.4f}, "
          f"95 % [{est.conf_int[0, 0]:.4f}, {est.conf_int[0, 1]:.4f}])")


def cut_series() -> list:
    """(depth k in mm, condition) of the M3 cut series of the copy, by depth."""
    names = pd.read_csv(cp.ROOT / "flights.csv").condition.unique()
    out = []
    for c in names:
        m = SERIES.match(c)
        if m:
            out.append((FULL_LENGTH_MM - float(m.group(1)), c))
    return sorted(out)


# ------------------------------------------------------------------ 2. CrazyPAD cut depth
ALPHA, WINDOW_S = 1e-2, 2.0              # the detection rows: alpha 0.01 on disjoint 2 s windows
HEALTHY_TESTS = ("LB-S", "F-S", "M-S", "LB+F+M")
DETECTOR = "LB+F+M"                      # tsfdi.AnyOf of the three, each at its Sidak share: size alpha
LEVEL = 0.5 * stats.chi2.isf(0.05, 1)   # the likelihood-ratio (profile) interval's drop
Z95 = stats.norm.isf(0.025)
INNER_GRID = 41                          # estimate_k's first grid in the inner folds (only the search's start)


@dataclass(frozen=True)
class Segment:
    """One airborne segment of the cut series."""

    depth: float
    condition: str
    drone: str
    log: str
    x: np.ndarray


def depth_data(ch) -> list:
    """Every airborne segment of the M3 cut series (``cut_series``) with the margin and channels of ``ch``."""
    return [Segment(depth, cond, f.drone, f.log, x) for depth, cond in cut_series()
            for f in cp.load_condition(cond, ch.margin) for x in f.arrays(ch.channels)]


def fit_depths(data: list, keep, lags: int, degree: int, weights: str = "pooled"):
    """The FP-VAR (trend "c") of the segments whose depth is in ``keep``."""
    idx = [i for i, s in enumerate(data) if s.depth in keep]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return FPVAR([data[i].x for i in idx], [data[i].depth for i in idx], lags, degree, "c",
                     weights=weights).fit()


def estimate(res, seg: Segment, grid: int = 201) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = res.estimate_k(seg.x, grid=grid)
    inside = est.grid[0][est.loglik[0] >= est.llf - LEVEL]
    return {"depth": seg.depth, "condition": seg.condition, "log": seg.log, "drone": seg.drone,
            "k_hat": est.k_hat[0], "se": est.bse[0], "covers": est.covers(seg.depth),
            "lr_covers": inside.min() <= seg.depth <= inside.max(), "at_bound": est.at_bound}


def per_log(t: pd.DataFrame) -> pd.DataFrame:
    """The per-log estimate (the mean of its segments' k_hat) with its standard error (segments taken as
    independent given the log: ``sqrt(mean(se^2) / m)``)."""
    g = t.groupby(["depth", "condition", "log"])
    return pd.DataFrame({"k_hat": g.k_hat.mean(), "se": np.sqrt(g.se.apply(lambda v: np.mean(v ** 2)) / g.size()),
                         "tau2": g.tau2.first(), "tau2_log": g.tau2_log.first()}).reset_index()


def spread(t: pd.DataFrame) -> tuple:
    """Between-flight variance components (mm^2) from held-out estimates ``t``: the moment estimate
    ``max(0, mean(err^2 - se^2))`` per segment and per log (the mean of its segments), over the estimates with a
    finite standard error (a curvature that failed gives none)."""
    t = t[np.isfinite(t.se)].assign(tau2=0.0, tau2_log=0.0)
    logs = per_log(t)
    return (max(0.0, float(np.mean((t.k_hat - t.depth) ** 2 - t.se ** 2))),
            max(0.0, float(np.mean((logs.k_hat - logs.depth) ** 2 - logs.se ** 2))))


def depth_folds(data: list, lags: int, degree: int, weights: str = "pooled", inner: bool = True,
                held=None) -> pd.DataFrame:
    """Leave one depth out: one row per segment of the held-out depth (``held``: those depths only, default
    every depth) with its estimate; with ``inner``, the fold's between-flight variance components ``tau2`` (per
    segment) and ``tau2_log`` (per log), chosen on the fitting depths only: every fitting depth held out in turn
    from the fold's fitting depths (estimates started from a grid of ``INNER_GRID``), ``spread`` of those
    estimates. A model on the depths without {a, b} serves two inner folds (held out a in b's fold, b in a's):
    fitted once."""
    depths = sorted({s.depth for s in data})
    fits: dict = {}

    def without(*gone):
        key = frozenset(gone)
        if key not in fits:
            fits[key] = fit_depths(data, [d for d in depths if d not in key], lags, degree, weights)
        return fits[key]

    rows = []
    for depth in depths if held is None else held:
        res = without(depth)
        tau2 = tau2_log = 0.0
        if inner:
            inner_rows = [estimate(without(depth, d), s, INNER_GRID) for d in depths if d != depth
                          for s in data if s.depth == d]
            tau2, tau2_log = spread(pd.DataFrame(inner_rows))
        rows += [{**estimate(res, s), "tau2": tau2, "tau2_log": tau2_log} for s in data if s.depth == depth]
    return pd.DataFrame(rows)


def report_depths(t: pd.DataFrame, all_depths: np.ndarray, inner: bool) -> None:
    err = t.k_hat - t.depth
    inner_d = t[(t.depth > all_depths.min()) & (t.depth < all_depths.max())]
    logs = per_log(t)
    print(f"  per segment: RMSE {np.sqrt(np.mean(err ** 2)):.2f} mm, mean error {err.mean():+.2f} mm, 95 % "
          f"interval coverage {t.covers.mean():.0%} ({int(t.covers.sum())}/{len(t)}), likelihood-ratio "
          f"interval {t.lr_covers.mean():.0%}, median se {t.se.median():.2f} mm")
    print(f"  interior depths only (the ends are outside the fitted range of their fold): RMSE "
          f"{np.sqrt(np.mean((inner_d.k_hat - inner_d.depth) ** 2)):.2f} mm, coverage {inner_d.covers.mean():.0%} "
          f"({int(inner_d.covers.sum())}/{len(inner_d)})")
    log_cov = (np.abs(logs.k_hat - logs.depth) <= Z95 * logs.se).mean()
    both = t[t.groupby("depth").drone.transform("nunique") == t.drone.nunique()]
    if t.drone.nunique() > 1:
        print(f"  per airframe, on the {both.depth.nunique()} depths every airframe flew: " + ", ".join(
            f"{drone} {len(g)} segments RMSE {np.sqrt(np.mean((g.k_hat - g.depth) ** 2)):.2f} mm, mean error "
            f"{(g.k_hat - g.depth).mean():+.2f} mm" for drone, g in both.groupby("drone")))
    print(f"  per log (mean of its segments): RMSE {np.sqrt(np.mean((logs.k_hat - logs.depth) ** 2)):.2f} mm "
          f"over {len(logs)} logs, 95 % interval coverage {log_cov:.0%}; predicting the mean depth: RMSE "
          f"{np.sqrt(np.mean((all_depths - all_depths.mean()) ** 2)):.2f} mm")
    if inner:
        seg = np.abs(err) <= Z95 * np.sqrt(t.se ** 2 + t.tau2)
        lg = np.abs(logs.k_hat - logs.depth) <= Z95 * np.sqrt(logs.se ** 2 + logs.tau2_log)
        print(f"  with the between-flight spread (tau chosen per fold on its fitting depths, leave one fitting "
              f"depth out; median tau {np.sqrt(t.tau2).median():.2f} mm per segment, "
              f"{np.sqrt(logs.tau2_log).median():.2f} mm per log): 95 % interval k_hat -+ 1.96 sqrt(se^2 + tau^2) "
              f"covers {seg.mean():.0%} of segments ({int(seg.sum())}/{len(t)}), {lg.mean():.0%} of logs "
              f"({int(lg.sum())}/{len(lg)}); median half-width {Z95 * np.sqrt(t.se ** 2 + t.tau2).median():.2f} mm "
              f"per segment, {Z95 * np.sqrt(logs.se ** 2 + logs.tau2_log).median():.2f} mm per log")


def choose_order(data: list) -> tuple:
    """(lags, degree): the BIC minimum of ``select_fp_order`` over degrees >= 1 on every depth (see the module
    docstring), and the line that reports it."""
    t0 = time.perf_counter()
    sel = select_fp_order([s.x for s in data], [s.depth for s in data], cp.MAX_LAGS, 4, "var", trend="c")
    bic = sel.table["bic"]
    usable = bic[bic.index.get_level_values("degree") >= 1]     # degree 0 does not depend on k
    choice = tuple(int(v) for v in usable.idxmin())
    line = (f"  select_fp_order (BIC, all depths, max lags {cp.MAX_LAGS}, max degree 4, "
            f"{time.perf_counter() - t0:.1f} s): minimum at lags {sel.selected[0]}, degree {sel.selected[1]}; "
            f"among degrees >= 1 (a model that depends on the depth) lags {choice[0]}, degree {choice[1]} "
            f"(BIC {bic[choice] - bic.min():+.0f} from the minimum)")
    return choice, line


# ------------------------------------------------------------------ healthy baselines (pooled, FP over airframes)
def airframe_k(drones) -> dict:
    """Drone -> its operating point for the FP baseline: the sorted drones evenly spaced on [0, 1]. With Legendre
    degree ``len(drones) - 1`` the expansion takes any value at each point: the airframe as a categorical k."""
    drones = sorted(set(drones))
    if len(drones) < 2:
        raise ValueError(f"an FP baseline over airframes needs normal flights of two drones or more, got {drones}")
    return dict(zip(drones, np.linspace(0.0, 1.0, len(drones)).tolist()))


def fp_fit(flights, ch, ks: dict):
    recs = cp.records(flights, ch.channels)
    k = [ks[f.drone] for f in flights for _ in f.segments]
    return FPVAR(recs, k, ch.order, len(ks) - 1, "c").fit()


def healthy_baseline(kind: str, flights, ch, ks: dict) -> dict:
    """Drone -> ``crazypad.Model`` of the healthy baseline fitted on the normal ``flights`` with the choices
    ``ch``: ``"pooled"`` one VAR of every flight (``crazypad.fit_model``, held-out residuals by log); ``"fp"`` an
    FP-VAR over the airframes (``airframe_k``), each drone's point results ``at`` its k, its held-out residuals
    those of every log through the FP-VAR refitted without it, at the log's k."""
    if kind == "pooled":
        model = cp.fit_model(flights, ch.channels, ch.order)
        return dict.fromkeys(ks, model)
    if kind != "fp":
        raise ValueError(f"kind must be 'pooled' or 'fp', got {kind!r}")
    short = [d for d in ks if sum(f.drone == d for f in flights) < 2]
    if short:
        raise ValueError(f"the FP baseline holds out each log in turn: it needs two or more normal flights of each "
                         f"drone, {', '.join(short)} has fewer")
    res = fp_fit(flights, ch, ks)
    held = []
    for f in flights:
        inner = fp_fit([g for g in flights if g is not f], ch, ks)
        held += [np.asarray(inner.residuals(x, ks[f.drone])) for x in f.arrays(ch.channels)]
    held = tsfdi.HeldOutResiduals(held, lags=ch.order)    # as VAR.held_out_residuals: windows in signal samples
    return {d: cp.Model(res.at(k), ch.order, held) for d, k in ks.items()}


def judge(models: dict, flights, ch, families=HEALTHY_TESTS, alpha: float = ALPHA, wsec: float = WINDOW_S,
          steps=(WINDOW_S,)) -> list:
    """Rows (condition, drone, log, step_s, test, flagged, n) of the ``wsec`` windows of ``flights`` every step of
    ``steps`` (s; ``wsec``: disjoint windows), each flight through its drone's model of ``models``; the tests
    calibrated on the held-out residuals (one calibration per distinct model: the FP baseline's drones share
    theirs)."""
    window = cp.samples(wsec)
    calibrated = {}
    rows = []
    for f in flights:
        model = models[f.drone]
        if id(model.held) not in calibrated:
            calibrated[id(model.held)] = cp.tests_for(model, families, alpha, window, True)
        tests = {fam: {"m": t} for fam, t in calibrated[id(model.held)].items()}
        for step_s in steps:
            flagged, n = dict.fromkeys(families, 0), dict.fromkeys(families, 0)
            for x in f.arrays(ch.channels):
                fl = cp.flags({"m": model}, tests, x, window, cp.samples(step_s))
                for fam in families:
                    flagged[fam] += int(fl[fam][1].sum())
                    n[fam] += int(fl[fam][1].shape[0])
            rows += [{"condition": f.condition, "drone": f.drone, "log": f.log, "step_s": step_s, "test": fam,
                      "flagged": flagged[fam], "n": n[fam]} for fam in families]
    return rows


def above_band(flagged: int, n: int, alpha: float = ALPHA) -> bool:
    """Whether a flight's flagged windows exceed the upper end of the two-sided 99 % binomial band of alpha for its
    windows: the flight is detected (a healthy flight is, at most 0.5 % of the time)."""
    return flagged / n > cp.binomial_band(n, alpha)[1]


def healthy_lofo(kind: str, folds=None) -> pd.DataFrame:
    """Leave one normal flight out over the normal flights of every drone: the choices (``crazypad.choose``) and the
    ``kind`` baseline on the other flights, the held-out flight judged (``judge``: disjoint windows and sliding ones,
    step ``crazypad.SLIDE_S``); ``folds``: the held-out logs' positions (default all)."""
    logs = cp.normal_logs()
    ks = airframe_k(f.drone for f in cp.load_condition(cp.NORMAL, (0.0, 0.0)))
    rows = []
    for i in range(len(logs)) if folds is None else folds:
        ch = cp.choose(tuple(log for j, log in enumerate(logs) if j != i))
        flights = cp.load_condition(cp.NORMAL, ch.margin)
        models = healthy_baseline(kind, [f for f in flights if f.log != logs[i]], ch, ks)
        held_out = [f for f in flights if f.log == logs[i]]
        rows += [{**r, "baseline": kind, "fold": i} for r in judge(models, held_out, ch, steps=(WINDOW_S, cp.SLIDE_S))]
    return pd.DataFrame(rows)


def rate_line(g: pd.DataFrame, alpha: float = ALPHA) -> str:
    n, x = int(g.n.sum()), int(g.flagged.sum())
    lo, hi = cp.binomial_band(n, alpha)
    inside = "in band" if lo <= x / n <= hi else ("ABOVE" if x / n > hi else "below")
    return f"{x:4d}/{n:<4d} = {100 * x / n:5.2f} %  99 % band [{100 * lo:.2f}, {100 * hi:.2f}] %  {inside}"


def report_healthy(fa: pd.DataFrame) -> None:
    for kind, d in fa.groupby("baseline", sort=False):
        slide = d[(d.step_s != WINDOW_S) & (d.test == DETECTOR)]
        d = d[d.step_s == WINDOW_S]
        print(f"  -- {kind} baseline: disjoint {WINDOW_S:g} s windows, alpha {ALPHA:g} (expected rate alpha)")
        for fam in HEALTHY_TESTS:
            print(f"    {fam:<7} {rate_line(d[d.test == fam])}")
        for drone, g in d[d.test == DETECTOR].groupby("drone"):
            print(f"    {DETECTOR} {drone} flights: {rate_line(g)}")
        for step_s, g in slide.groupby("step_s"):
            print(f"    {DETECTOR} sliding, step {step_s:g} s (dependent windows, rate only): "
                  f"{int(g.flagged.sum())}/{int(g.n.sum())} = {100 * g.flagged.sum() / g.n.sum():.2f} %")
        det = d[d.test == DETECTOR]
        up = [r.log for r in det.itertuples() if above_band(r.flagged, r.n)]
        print(f"    flights above their own 99 % band ({DETECTOR}): {len(up)}/{len(det)}"
              + (f" ({', '.join(up)})" if up else ""))


# ------------------------------------------------------------------ detection through depth models (every depth unseen)
TRIM_DEGREES = (1, 2, 3)                 # the trim surface's depth degree, chosen per fold by BIC over its records
DEPTH_STEPS = 321                        # the trim profile's depth grid (0.025 mm over 0-8 mm)


def chibar_isf(alpha: float, parts: int) -> float:
    """Upper ``alpha`` point of the sum of ``parts`` independent likelihood-ratio statistics of ``k = 0`` on the
    boundary of ``k >= 0``, each ``0.5 chi2_0 + 0.5 chi2_1`` (the chi-bar-square law): ``P(T > t) = sum_j
    C(parts, j) 2^-parts P(chi2_j > t)``."""
    w = stats.binom.pmf(np.arange(1, parts + 1), parts, 0.5)
    df = np.arange(1, parts + 1)
    if w.sum() <= alpha:
        return 0.0
    return float(optimize.brentq(lambda t: float(w @ stats.chi2.sf(t, df)) - alpha, 0.0, 1e4))


def chibar_mean(parts: int) -> float:
    """Mean of the chi-bar-square law of ``chibar_isf``: half a degree of freedom per part."""
    return 0.5 * parts


def cut_flights(ch) -> list:
    """(depth, flight) of every normal flight (depth 0) and every log of the M3 cut series."""
    return ([(0.0, f) for f in cp.load_condition(cp.NORMAL, ch.margin)]
            + [(depth, f) for depth, cond in cut_series() for f in cp.load_condition(cond, ch.margin)])


def var_model(ch):
    """Fitter of (a): the FP-VAR (trend "c") over the depth, lags ``ch.order`` (BIC on the normal flights), degree 1
    (a priori), of every segment of the given (depth, flight) items."""
    def fit(items):
        recs = [x for _, f in items for x in f.arrays(ch.channels)]
        k = [d for d, f in items for _ in f.segments]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return FPVAR(recs, k, ch.order, 1, "c").fit()
    return fit


def var_stat(ch):
    """Statistic of (a) for one flight: per segment ``estimate_k`` (bounded to the fitted range, whose lower end is
    the normal flights' 0) and the likelihood ratio ``2 (llf(k_hat) - llf(0))``; the flight's statistic their sum
    (one boundary chi-bar part per segment), its depth the mean of the segments' estimates."""
    def stat(res, flight):
        lr, k_hat, se = [], [], []
        for x in flight.arrays(ch.channels):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                est = res.estimate_k(x, grid=81)
            if est.grid[0][0] != 0.0:
                raise ValueError(f"the FP-VAR's depth range starts at {est.grid[0][0]:g}, not at the normal flights' 0")
            lr.append(max(0.0, 2 * (est.llf - est.loglik[0][0])))
            k_hat.append(est.k_hat[0])
            se.append(est.bse[0])
        half = Z95 * np.sqrt(np.mean(np.square(se)) / len(se))
        k = float(np.mean(k_hat))
        return {"lr": float(sum(lr)), "crit": chibar_isf(ALPHA, len(lr)), "mean0": chibar_mean(len(lr)),
                "lr_parts": tuple(lr), "crit_part": chibar_isf(ALPHA, 1), "k_hat": k, "lo": k - half, "hi": k + half}
    return stat


def trim_record(flight, window: int) -> np.ndarray:
    """The commands of a flight's segments, each cut to its whole ``window``-sample windows, end to end (no window
    spans two segments)."""
    return np.vstack([x[:len(x) - len(x) % window] for x in flight.arrays(cp.COMMANDS)])


def trim_model(airframes: dict, window: int):
    """Fitter of (b): ``tsfdi.FPMean`` of the commands' window means over k = (depth, airframe) (airframe: the
    categorical ``airframe_k``, degree 1), one record per flight, the depth degree among ``TRIM_DEGREES`` (those the
    fitting depths allow) of the smallest BIC (over records) of the fitting flights."""
    def fit(items):
        recs = [trim_record(f, window) for _, f in items]
        k = [[d, airframes[f.drone]] for d, f in items]
        depths = len({d for d, _ in items})             # degree d needs d + 1 depths
        fits = [tsfdi.FPMean(recs, k, window, (deg, 1)).fit() for deg in TRIM_DEGREES if deg < depths]
        return min(fits, key=lambda r: r.bic)
    return fit


def trim_profile(res, means: np.ndarray, airframe: float, V: np.ndarray) -> tuple:
    """(depth grid, q) of window means ``means`` ``(n, s)``: ``q(k) = (m - M(k, airframe))' V^-1 (m - M(...))``
    on ``DEPTH_STEPS`` depths of the model's range."""
    m = res.model
    grid = np.linspace(*m.k_range[0], DEPTH_STEPS)
    surf = fp_basis(np.column_stack([grid, np.full_like(grid, airframe)]), m.degree, m.k_range, m.basis) @ res.params2d
    dev = means[:, None, :] - surf[None]
    return grid, np.einsum("wka,ab,wkb->wk", dev, np.linalg.inv(V), dev)


def trim_stat(airframes: dict, window: int):
    """Statistic of (b) for one flight: its mean trim over all its windows against the surface at its logged
    airframe, variance ``S_rec + S_within / windows`` (a new flight's offset plus its windows' mean spread);
    ``T = q(0) - min_k q(k)`` over depth (one boundary chi-bar part), the depth of the minimum and the
    likelihood-ratio 95 % interval. Per window (c, window counting): the same with ``S`` and the window's mean."""
    def stat(res, flight):
        x = trim_record(flight, window)
        means = x.reshape(-1, window, x.shape[1]).mean(axis=1)
        a = airframes[flight.drone]
        grid, q = trim_profile(res, means.mean(axis=0, keepdims=True), a, res.S_rec + res.S_within / len(means))
        q = q[0]
        if grid[0] != 0.0:
            raise ValueError(f"the trim model's depth range starts at {grid[0]:g}, not at the normal flights' 0")
        j = int(np.argmin(q))
        inside = grid[q - q[j] <= stats.chi2.isf(0.05, 1)]
        _, qw = trim_profile(res, means, a, res.S)
        return {"lr": float(q[0] - q[j]), "crit": chibar_isf(ALPHA, 1), "mean0": chibar_mean(1),
                "lr_parts": tuple((qw[:, 0] - qw.min(axis=1)).tolist()), "crit_part": chibar_isf(ALPHA, 1),
                "k_hat": float(grid[j]), "lo": float(inside.min()), "hi": float(inside.max()),
                "degree": res.model.degree[0]}
    return stat


def healthy_trim_points(flight, airframes: dict, by_segment: bool) -> list:
    """The healthy trim model's operating point of each segment of a flight: its airframe, and with ``by_segment``
    the segment's position in the log (first or second short flight: a categorical second parameter)."""
    a = airframes[flight.drone]
    return [[a, float(i)] if by_segment else [a] for i in range(len(flight.segments))]


def healthy_trim_model(airframes: dict, window: int, by_segment: bool = False):
    """Fitter of (b0) / (b1): ``tsfdi.FPMean`` of the commands' window means of the normal flights only (the cut
    flights of the items are ignored: no depth is ever seen) over the airframe (categorical, degree 1), one record
    per flight (b0); with ``by_segment`` (b1) one record per segment over (airframe, segment position), so that a
    flight's windows spread about their own segment's trim, not about a flight mean that holds the two segments'
    systematic difference."""
    def fit(items):
        normal = [f for d, f in items if d == 0.0]
        if by_segment:
            recs = [x[:len(x) - len(x) % window] for f in normal for x in f.arrays(cp.COMMANDS)]
            k = [p for f in normal for p in healthy_trim_points(f, airframes, True)]
        else:
            recs = [trim_record(f, window) for f in normal]
            k = [airframes[f.drone] for f in normal]
        return tsfdi.FPMean(recs, k, window, 1).fit()
    return fit


def healthy_trim_stat(airframes: dict, window: int, by_segment: bool = False):
    """Statistic of (b0) / (b1) for one flight: the Mahalanobis distance of the mean of its windows' deviations from
    the healthy trim (of its airframe; with ``by_segment`` of its airframe and each window's segment position),
    variance ``S_rec + S_within / windows``, nominally chi-square with one degree of freedom per command; per window
    the same with ``S``. No depth estimate."""
    def stat(res, flight):
        dev = []
        for x, point in zip(flight.arrays(cp.COMMANDS), healthy_trim_points(flight, airframes, True)):
            x = x[:len(x) - len(x) % window]
            trim = res.predict(point if by_segment else point[:1])
            dev.append(x.reshape(-1, window, x.shape[1]).mean(axis=1) - trim)
        dev = np.vstack(dev)
        r = dev.mean(axis=0)
        crit = stats.chi2.isf(ALPHA, res.neqs)
        return {"lr": float(r @ np.linalg.solve(res.S_rec + res.S_within / len(dev), r)), "crit": crit,
                "mean0": float(res.neqs), "crit_part": crit,
                "lr_parts": tuple(np.einsum("wa,wa->w", dev, np.linalg.solve(res.S, dev.T).T).tolist()),
                "k_hat": np.nan, "lo": np.nan, "hi": np.nan}
    return stat


def detection_folds(items: list, fit, stat, depths=None, normals=None) -> pd.DataFrame:
    """Leave one depth out for the cut flights and one flight out for the normal ones (``items``: (depth, flight),
    normal flights at depth 0), each judged by ``stat`` through the model ``fit`` on the rest, with the scale of
    its fold: the mean of the statistics of the fold's normal flights, each left out in turn from the fold's
    fitting items (nested: the judged flights are never seen), over their nominal means. ``stat(model, flight)``
    gives a dict: ``lr`` (the flight's statistic), ``crit`` / ``mean0`` (its nominal upper ``ALPHA`` point and
    mean), ``lr_parts`` / ``crit_part`` (the statistics of its parts, segments or windows, and their nominal
    point), ``k_hat``, ``lo``, ``hi`` (its depth and 95 % interval, NaN without one). ``depths`` / ``normals``: the
    cut depths / normal flights' positions to judge (default all). One row per judged flight."""
    fits: dict = {}
    normal = [i for i, (d, _) in enumerate(items) if d == 0.0]

    def without(gone):
        key = frozenset(gone)
        if key not in fits:
            fits[key] = fit([it for i, it in enumerate(items) if i not in key])
        return fits[key]

    def scale(gone):
        cal = [stat(without(gone | {j}), items[j][1]) for j in normal if j not in gone]
        return sum(c["lr"] for c in cal) / sum(c["mean0"] for c in cal)

    folds = [frozenset(i for i, (d, _) in enumerate(items) if d == depth)
             for depth in sorted({d for d, _ in items if d > 0}) if depths is None or depth in depths]
    folds += [frozenset({j}) for pos, j in enumerate(normal) if normals is None or pos in normals]
    rows = []
    for gone in folds:
        res, c = without(gone), scale(gone)
        for i in sorted(gone):
            depth, f = items[i]
            rows.append({"depth": depth, "drone": f.drone, "log": f.log, "scale": c, **stat(res, f)})
    return pd.DataFrame(rows)


def decide(t: pd.DataFrame) -> pd.DataFrame:
    """Flight decisions at ``ALPHA``: ``nominal`` (``lr`` above its nominal point ``crit``), ``calibrated`` (above
    ``scale * crit``) and ``windows`` (the parts' statistics above the one-part point ``crit_part``, counted against
    the flight's 99 % binomial band, ``above_band``)."""
    return t.assign(nominal=t.lr > t.crit, calibrated=t.lr > t.scale * t.crit,
                    windows=[above_band(int(np.sum(np.array(r.lr_parts) > r.crit_part)), len(r.lr_parts))
                             for r in t.itertuples()])


def report_detection_folds(t: pd.DataFrame, name: str) -> None:
    t = decide(t)
    cut, normal = t[t.depth > 0], t[t.depth == 0]
    depth = cut.k_hat.notna().all()
    print(f"  -- {name}: flights detected per depth (nominal / calibrated / window counting)"
          + ("; depth of the flight: estimate and 95 % interval" if depth else ""))
    print("     depth  flights  nominal  calibrated  windows" + ("  mean k_hat  covered" if depth else ""))
    for d, g in cut.groupby("depth"):
        cov = ((g.lo <= d) & (d <= g.hi)).mean()
        print(f"     {d:5.1f}  {len(g):7d}  {int(g.nominal.sum()):7d}  {int(g.calibrated.sum()):10d}  "
              f"{int(g.windows.sum()):7d}" + (f"  {g.k_hat.mean():10.2f}  {cov:7.0%}" if depth else ""))
    lo, hi = cp.binomial_band(len(normal), ALPHA)
    for rule in ("nominal", "calibrated", "windows"):
        x = int(normal[rule].sum())
        band = "in band" if lo <= x / len(normal) <= hi else ("ABOVE" if x / len(normal) > hi else "below")
        print(f"     {rule:<10} cut flights {int(cut[rule].sum())}/{len(cut)}; normal flights (leave one out) "
              f"{x}/{len(normal)}, 99 % band [{100 * lo:.1f}, {100 * hi:.1f}] % {band}"
              + (f" ({', '.join(normal.log[normal[rule]])})" if x else ""))
    print("     calibrated, per airframe: " + ", ".join(
        f"{drone} cut flights {int(g.calibrated.sum())}/{len(g)}" for drone, g in cut.groupby("drone")))
    if not depth:
        print(f"     calibration scale median {t.scale.median():.2f} "
              f"[{t.scale.min():.2f}, {t.scale.max():.2f}]")
        return
    err = cut.k_hat - cut.depth
    cov = (cut.lo <= cut.depth) & (cut.depth <= cut.hi)
    print(f"     depth per flight (cut flights, every depth unseen): RMSE {np.sqrt(np.mean(err ** 2)):.2f} mm, mean "
          f"error {err.mean():+.2f} mm, 95 % interval coverage {cov.mean():.0%} ({int(cov.sum())}/{len(cut)}), median "
          f"half-width {((cut.hi - cut.lo) / 2).median():.2f} mm; normal flights: mean k_hat "
          f"{normal.k_hat.mean():.2f} mm; calibration scale median {t.scale.median():.2f} "
          f"[{t.scale.min():.2f}, {t.scale.max():.2f}]")
    if "degree" in t:
        print(f"     depth degree chosen (flights judged): {t.degree.value_counts().sort_index().to_dict()}")


def depth_detection(ch) -> dict:
    """The cut flights of every depth detected through models of the depth, the normal flights (depth 0) and the
    cut depths fitted together (see the module docstring, section 2): (a) the FP-VAR's likelihood ratio of k = 0
    against k_hat, (b) the controller's trim (``tsfdi.FPMean`` over depth and airframe), each per flight (pooled)
    and by counting its parts (segments / windows). Returns the decided tables (``decide``) by detector:
    ``"a"``, ``"b"``, ``"b0"``, ``"b1"``."""
    items = cut_flights(ch)
    airframes = airframe_k(f.drone for d, f in items if d == 0.0)
    window = cp.samples(WINDOW_S)
    print(f"\n  detection through models of the depth: normal flights (k = 0) and the cut depths fitted together, "
          f"leave one depth out (cut flights) / one flight out (normal flights), alpha {ALPHA:g}; a flight is a cut "
          "when its likelihood-ratio statistic exceeds its nominal point (chi-bar-square of k = 0 against k_hat, or "
          "chi-square), or that point times the fold's scale from its normal flights left out in turn (calibrated, "
          "nested)")
    tables = {}
    for key, name, fit, stat in (
            ("a", f"(a) FP-VAR over depth (lags {ch.order}: BIC on the normal flights; degree 1 a priori), per segment "
             "estimate_k", var_model(ch), var_stat(ch)),
            ("b", f"(b) trim: FPMean of the commands' {WINDOW_S:g} s window means over (depth, airframe "
             f"{', '.join(f'{d} {k:g}' for d, k in airframes.items())}), depth degree by BIC per fold among "
             f"{TRIM_DEGREES}, one record per flight", trim_model(airframes, window), trim_stat(airframes, window)),
            ("b0", "(b0) healthy trim: FPMean of the normal flights' commands only (no cut flight fitted) over the "
             "airframe; the flight's mean trim against its airframe's, nominally chi-square",
             healthy_trim_model(airframes, window), healthy_trim_stat(airframes, window)),
            ("b1", "(b1) healthy trim by segment: as (b0), one record per segment over (airframe, segment position in "
             "the log); added after the first run of (a)-(b0), see the module docstring",
             healthy_trim_model(airframes, window, True), healthy_trim_stat(airframes, window, True))):
        t0 = time.perf_counter()
        t = detection_folds(items, fit, stat)
        report_detection_folds(t, f"{name} ({time.perf_counter() - t0:.0f} s)")
        tables[key] = decide(t)
    return tables


# ------------------------------------------------------------------ 4. detectability limit of the cut flights
TRIMS = ("trim roll", "trim pitch", "trim yaw")            # what (b0) uses, per flight
SPREADS = ("spread roll", "spread pitch", "spread yaw")   # the detector tried after the analysis (section 4)
SUMMARIES = TRIMS + ("trim thrust",) + SPREADS + ("resid gyro", "resid all")
LACK_OF_FIT_DEGREE = 2                   # the depth curve about which a depth's session offset is measured


def flight_summaries(items: list, ch) -> pd.DataFrame:
    """One row per flight of ``items`` ((depth, flight), normal flights at depth 0): depth, drone, log and the
    flight-level ``SUMMARIES`` on each segment's whole ``WINDOW_S`` windows (the samples (b0) uses): ``trim`` the
    mean of the three attitude commands and of the thrust command; ``spread`` the log of each attitude command's
    standard deviation about its segment's own mean (pooled over the segments: the normal logs' two short flights
    hold different trims, a difference that is not command noise); ``resid`` the log generalised variance of the
    healthy VAR's residuals (lags ``ch.order``, trend "c", fitted on the normal flights; a normal flight through the
    VAR without it), of the gyro rates and of all of ``ch.channels``."""
    window = cp.samples(WINDOW_S)
    normal = [f for d, f in items if d == 0.0]

    def var(flights):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return tsfdi.VAR(cp.records(flights, ch.channels), ch.order, trend="c").fit()

    full = var(normal)
    gyro = [ch.channels.index(c) for c in cp.GYRO]
    rows = []
    for depth, f in items:
        res = var([g for g in normal if g is not f]) if depth == 0.0 else full
        e = np.vstack([np.asarray(res.residuals(x)) for x in f.arrays(ch.channels)])
        segs = [x[:len(x) - len(x) % window] for x in f.arrays(cp.COMMANDS + (cp.THRUST,))]
        x = np.vstack(segs)
        dev = np.vstack([s[:, :3] - s[:, :3].mean(axis=0) for s in segs])
        sd = np.sqrt((dev ** 2).sum(axis=0) / (len(dev) - len(segs)))
        rows.append({"depth": depth, "drone": f.drone, "log": f.log,
                     **dict(zip(TRIMS + ("trim thrust",), x.mean(axis=0))), **dict(zip(SPREADS, np.log(sd))),
                     "resid gyro": np.linalg.slogdet(np.cov(e[:, gyro].T))[1],
                     "resid all": np.linalg.slogdet(np.cov(e.T))[1]})
    return pd.DataFrame(rows)


def null_spread(t: pd.DataFrame, cols) -> tuple:
    """The normal flights' (depth 0) law of the summaries ``cols`` of ``t``: (mean per drone (DataFrame), the
    pooled within-airframe covariance (each flight about its own airframe's mean), its degrees of freedom (flights
    minus airframes), normal flights per drone (Series))."""
    n = t[t.depth == 0.0]
    mu = n.groupby("drone")[list(cols)].mean()
    dev = n[list(cols)].to_numpy() - mu.loc[n.drone].to_numpy()
    df = len(n) - len(mu)
    return mu, dev.T @ dev / df, df, n.groupby("drone").size()


def predictive_power(nc, p: int, df: int, alpha: float = ALPHA):
    """Power of the predictive test at size ``alpha`` of a new flight's ``p`` summaries against ``df`` degrees of
    freedom of the null covariance: ``T2 (df - p + 1) / (df p)`` is ``F(p, df - p + 1)`` under the null (Hotelling;
    ``p = 1``: the two-sided predictive t), noncentral with ``nc = delta' Sigma^-1 delta / (1 + 1 / n_a)`` under a
    shift ``delta`` (``n_a`` normal flights of the airframe). ``df = inf``: the null known (chi-square)."""
    nc = np.asarray(nc, dtype=float)
    if df < p:
        raise ValueError(f"df: {df} degrees of freedom cannot estimate the covariance of {p} summaries")
    if np.isinf(df):
        return stats.ncx2.sf(stats.chi2.isf(alpha, p), p, np.maximum(nc, 1e-12))
    crit = stats.f.isf(alpha, p, df - p + 1)
    return stats.ncf.sf(crit, p, df - p + 1, np.maximum(nc, 1e-12))


def detectable_effect(power: float, n_a: int, df, alpha: float = ALPHA) -> float:
    """The shift of one summary, in units of the normal flights' flight-to-flight sd, that the predictive t test
    (``df`` degrees of freedom, ``n_a`` normal flights of the airframe; ``inf``: the null known) detects with
    probability ``power``."""
    return float(optimize.brentq(lambda z: predictive_power(z * z / (1 + 1 / n_a), 1, df, alpha) - power, 0.0, 1e3))


def predictive_test(t: pd.DataFrame, cols, alpha: float = ALPHA) -> pd.DataFrame:
    """The predictive test of every flight of ``t`` on the summaries ``cols``: a cut flight (depth > 0) against
    all normal flights, a normal flight against the others (left out); ``T2 = d' S^-1 d / (1 + 1 / n_a)`` with
    ``d`` the flight's deviation from its airframe's normal mean (of ``n_a`` flights) and ``S`` the pooled
    within-airframe covariance (``null_spread``), its p-value from ``F(p, df - p + 1)``. Columns depth, drone,
    log, T2, df, pvalue, detected (``pvalue < alpha``)."""
    cols = list(cols)
    p = len(cols)
    law = {}
    rows = []
    for i, r in enumerate(t.itertuples(index=False)):
        key = i if r.depth == 0.0 else None
        if key not in law:
            law[key] = null_spread(t.drop(index=t.index[i]) if key is not None else t, cols)
        mu, S, df, n_a = law[key]
        if r.drone not in mu.index:
            raise ValueError(f"no normal flight of airframe {r.drone!r} to judge {r.log} against")
        d = t.iloc[i][cols].to_numpy(dtype=float) - mu.loc[r.drone].to_numpy()
        T2 = float(d @ np.linalg.solve(S, d)) / (1 + 1 / n_a[r.drone])
        pv = float(stats.f.sf(T2 * (df - p + 1) / (df * p), p, df - p + 1))
        rows.append({"depth": r.depth, "drone": r.drone, "log": r.log, "T2": T2, "df": df, "pvalue": pv,
                     "detected": pv < alpha})
    return pd.DataFrame(rows)


def depth_effects(t: pd.DataFrame, cols) -> pd.DataFrame:
    """Per (drone, depth) of the cut flights: flights, and for each summary of ``cols`` the mean shift from the
    airframe's normal mean in units of the normal flights' sd (``null_spread``; column ``z <summary>``), its
    standard error over the depth's flights (``se <summary>``), and the power of the predictive t test at that
    shift (``power <summary>``, ``predictive_power``)."""
    mu, S, df, n_a = null_spread(t, cols)
    sd = np.sqrt(np.diag(S))
    cut = t[t.depth > 0]
    d = cut[list(cols)].to_numpy() - mu.loc[cut.drone].to_numpy()
    rows = []
    for (drone, depth), idx in cut.groupby(["drone", "depth"]).indices.items():
        z = d[idx].mean(axis=0) / sd
        se = (d[idx].std(axis=0, ddof=1) / np.sqrt(len(idx)) / sd) if len(idx) > 1 else np.full(len(cols), np.nan)
        row = {"drone": drone, "depth": depth, "flights": len(idx)}
        for c, zc, sc in zip(cols, z, se):
            row |= {f"z {c}": zc, f"se {c}": sc, f"power {c}": float(predictive_power(zc * zc / (1 + 1 / n_a[drone]),
                                                                                       1, df))}
        rows.append(row)
    return pd.DataFrame(rows).sort_values(["drone", "depth"], ignore_index=True)


def joint_power(t: pd.DataFrame, cols) -> pd.Series:
    """Per (drone, depth) of the cut flights of ``t``: the power of the predictive Hotelling test of the summaries
    ``cols`` jointly (``predictive_power``) at the depth's mean shift from the airframe's normal mean, the null
    covariance that of ``null_spread``."""
    mu, S, df, n_a = null_spread(t, cols)
    cut = t[t.depth > 0]
    d = cut[list(cols)].to_numpy() - mu.loc[cut.drone].to_numpy()
    out = {}
    for (drone, depth), idx in cut.groupby(["drone", "depth"]).indices.items():
        m = d[idx].mean(axis=0)
        out[(drone, depth)] = float(predictive_power(m @ np.linalg.solve(S, m) / (1 + 1 / n_a[drone]), len(cols), df))
    return pd.Series(out).rename_axis(["drone", "depth"])


def session_spread(eff: pd.DataFrame, col: str, degree: int = LACK_OF_FIT_DEGREE) -> tuple:
    """(session sd, within-depth flight sd) of one summary for one airframe's depths (``eff``: ``depth_effects``
    rows of one drone), in units of the normal flights' sd. A depth's flights are one session, so the scatter of
    the depths' mean shifts about a smooth curve in the depth (polynomial of ``degree``, least squares) is the spread
    of a session's offset plus that of its flights' mean: ``tau^2 = max(0, RSS / (depths - degree - 1) -
    mean(se^2))``; the within-depth sd is ``sqrt(mean(flights se^2))`` (a session's flights about their mean)."""
    if len(eff) <= degree + 1:
        raise ValueError(f"{len(eff)} depths cannot measure the scatter about a degree-{degree} curve")
    z, se2 = eff[f"z {col}"].to_numpy(), eff[f"se {col}"].to_numpy() ** 2
    fit = np.polyval(np.polyfit(eff.depth, z, degree), eff.depth)
    rss = float(np.sum((z - fit) ** 2))
    return (float(np.sqrt(max(0.0, rss / (len(eff) - degree - 1) - np.nanmean(se2)))),
            float(np.sqrt(np.nanmean(se2 * eff.flights))))


def detectability(ch, b0: pd.DataFrame) -> None:
    """Section 4: how far the cut shifts each flight-level summary (``flight_summaries``) from the normal flights,
    in units of their flight-to-flight sd, what power a detector of that summary could reach at a per-flight
    false-alarm rate of ``ALPHA`` with the null estimated from the 8 normal flights, beside the flights (b0)
    detected (``b0``: its decided table of ``depth_detection``); the session scatter about a depth curve; and the
    predictive Hotelling test of the three command spreads (``SPREADS``)."""
    items = cut_flights(ch)
    t0 = time.perf_counter()
    t = flight_summaries(items, ch)
    mu, S, df, n_a = null_spread(t, SUMMARIES)
    sd = pd.Series(np.sqrt(np.diag(S)), SUMMARIES)
    print(f"\n== 4. detectability of the M3 cut flights ({len(t[t.depth > 0])} cut flights, {len(n_a)} airframes, "
          f"{int(n_a.sum())} normal flights: {', '.join(f'{d} {k}' for d, k in n_a.items())}; summaries in "
          f"{time.perf_counter() - t0:.0f} s)")
    print(f"  flight-level summaries (whole {WINDOW_S:g} s windows of each segment, as (b0)): trim = mean command; "
          "spread = log sd of an attitude command about its segment's mean; resid = log generalised variance of the "
          f"healthy VAR's residuals (lags {ch.order}, normal flights; a normal flight through the VAR without it), "
          "gyro rates / all channels. Null: each airframe's normal mean, the pooled within-airframe sd sigma "
          f"({df} degrees of freedom; its 95 % interval is sigma_hat x [{np.sqrt(df / stats.chi2.isf(0.025, df)):.2f}"
          f", {np.sqrt(df / stats.chi2.isf(0.975, df)):.2f}])")
    nc3 = optimize.brentq(lambda nc: float(predictive_power(nc, 3, df)) - 0.5, 0.0, 1e4)
    z50 = {d: detectable_effect(0.5, k, df) for d, k in n_a.items()}
    z90 = {d: detectable_effect(0.9, k, df) for d, k in n_a.items()}
    print(f"  detectability limit of one summary at a per-flight false-alarm rate {ALPHA:g} (two-sided predictive "
          f"t, {df} df): a shift of " + ", ".join(f"{d} {z50[d]:.2f} / {z90[d]:.2f}" for d in n_a.index)
          + f" sigma is detected with probability 0.5 / 0.9; with the null known "
          f"{detectable_effect(0.5, np.inf, np.inf):.2f} / {detectable_effect(0.9, np.inf, np.inf):.2f} sigma. "
          f"Three summaries jointly (Hotelling, F(3, {df - 2})): a Mahalanobis shift of "
          + ", ".join(f"{d} {np.sqrt(nc3 * (1 + 1 / k)):.2f}" for d, k in n_a.items()) + " for 0.5")
    eff = depth_effects(t, SUMMARIES)
    print("  per summary: normal sd sigma (per airframe: sd, df); session scatter / within-depth flight sd about a "
          f"degree-{LACK_OF_FIT_DEGREE} depth curve (sigma units, per airframe); cut flights beyond the predictive "
          f"{ALPHA:g} point; normal flights beyond it (each left out, {df - 1} df)")
    for c in SUMMARIES:
        own = t[t.depth == 0.0].groupby("drone")[c].agg(["std", "size"])
        sess = [f"{d} {'/'.join(f'{v:.1f}' for v in session_spread(g, c))}" for d, g in eff.groupby("drone")]
        if c == SUMMARIES[0]:
            print("      (session scatter over depths - " + f"{LACK_OF_FIT_DEGREE + 1} degrees of freedom: "
                  + ", ".join(f"{d} {len(g) - LACK_OF_FIT_DEGREE - 1}" for d, g in eff.groupby("drone")) + ")")
        pt = predictive_test(t, [c])
        cut, normal = pt[pt.depth > 0], pt[pt.depth == 0]
        per = ", ".join(f"{d} {sd_a:.4g}, {n - 1}" for d, sd_a, n in zip(own.index, own["std"], own["size"]))
        print(f"    {c:<12} sigma {sd[c]:9.4g} ({per}); session / within {', '.join(sess)}; cut " + ", ".join(
                  f"{d} {int(g.detected.sum())}/{len(g)}" for d, g in cut.groupby("drone"))
              + f"; normal {int(normal.detected.sum())}/{len(normal)}")
    b0 = b0[b0.depth > 0].groupby(["drone", "depth"]).calibrated.sum()
    print("  per depth: mean shift z (sigma units) +- its se over the depth's flights, and the power of the "
          "predictive t at z; (b0) calibrated flights detected; 'trims' / 'spreads': Hotelling power of the three "
          "trims ((b0)'s summary) / spreads jointly at the depth's mean shift")
    short = {"trim roll": "tr roll", "trim pitch": "tr pitch", "trim yaw": "tr yaw", "trim thrust": "thrust",
             "spread roll": "sp roll", "spread pitch": "sp pitch", "spread yaw": "sp yaw", "resid gyro": "res gyro",
             "resid all": "res all"}
    print("    drone depth n  b0  trims spreads " + "".join(f"{short[c]:>15}" for c in SUMMARIES))
    trims, spreads = joint_power(t, TRIMS), joint_power(t, SPREADS)
    for _, r in eff.iterrows():
        cells = "".join(f"{r[f'z {c}']:6.1f}+-{r[f'se {c}']:3.1f} {100 * r[f'power {c}']:3.0f}" for c in SUMMARIES)
        print(f"    {r.drone:<5} {r.depth:5.1f} {r.flights:1d} {int(b0.get((r.drone, r.depth), 0)):3d}  "
              f"{100 * trims[(r.drone, r.depth)]:4.0f}% {100 * spreads[(r.drone, r.depth)]:6.0f}% {cells}")
    pt = predictive_test(t, SPREADS)
    cut, normal = pt[pt.depth > 0], pt[pt.depth == 0]
    lo, hi = cp.binomial_band(len(normal), ALPHA)
    x = int(normal.detected.sum())
    print(f"  -- the command spreads' predictive test (Hotelling T2 of the three spreads, F(3, {df - 2}) for a cut "
          f"flight, F(3, {df - 3}) for a normal flight left out; chosen after this analysis had been read on flights "
          f"seen in earlier sessions: not a blind evaluation): cut flights {int(cut.detected.sum())}/{len(cut)} "
          f"(b0: {int(b0.sum())}); normal flights {x}/{len(normal)}, 99 % band [{100 * lo:.1f}, {100 * hi:.1f}] % "
          + ("in band" if lo <= x / len(normal) <= hi else "ABOVE" if x / len(normal) > hi else "below"))
    print("     depth  flights  spreads  (b0)")
    for depth, g in cut.groupby("depth"):
        found = int(b0.xs(depth, level="depth").sum())
        print(f"     {depth:5.1f}  {len(g):7d}  {int(g.detected.sum()):7d}  {found:4d}")
    print("     per airframe: " + ", ".join(f"{d} {int(g.detected.sum())}/{len(g)} (b0 {int(b0.xs(d).sum())})"
                                          for d, g in cut.groupby("drone")))


# ------------------------------------------------------------------ the CrazyPAD sections
def crazypad(lags=None, degree=None) -> None:
    print("\n== 2. CrazyPAD propeller M3 cut depth (k = 47 mm - blade length), leave one depth out")
    cp.setup(conditions="cut_propeller_M3_*")
    ch = cp.choose(cp.normal_logs())
    data = depth_data(ch)
    depths = np.array([s.depth for s in data])
    print(f"  choices of crazypad.py on all normal flights: {ch.line()}; "
          f"{len(set(depths))} depths, {len({(s.condition, s.log) for s in data})} logs, {len(data)} segments of "
          f"{min(len(s.x) for s in data)}-{max(len(s.x) for s in data)} samples at {cp.FS:g} Hz")
    if lags is None or degree is None:
        choice, line = choose_order(data)
        print(line)
        lags = choice[0] if lags is None else lags
        degree = choice[1] if degree is None else degree
    print(f"  FP-VAR(lags {lags}, Legendre degree {degree}, trend c)")
    for weights in ("pooled", "point"):
        t0 = time.perf_counter()
        t = depth_folds(data, lags, degree, weights, inner=weights == "pooled")
        print(f"  -- weights={weights!r}: {len(set(depths))} folds in {time.perf_counter() - t0:.1f} s")
        if weights == "pooled":
            print("  depth  segments  mean k_hat  median se  covered  at a bound")
            for depth, g in t.groupby("depth"):
                print(f"  {depth:5.1f}  {len(g):8d}  {g.k_hat.mean():10.2f}  {g.se.median():9.2f}  "
                      f"{g.covers.mean():7.0%}  {g.at_bound.mean():10.0%}")
        report_depths(t, depths, weights == "pooled")
    print("  -- the airframe as a second operating parameter (it is logged): one FP-VAR per airframe, the same as "
          "k = (depth, airframe) with tensor degree (degree, 1); pooled LS, leave one depth out within the airframe")
    for drone in sorted({s.drone for s in data}):
        own = [s for s in data if s.drone == drone]
        print(f"  {drone} ({len({s.depth for s in own})} depths):")
        report_depths(depth_folds(own, lags, degree, inner=False), np.array([s.depth for s in own]), False)

    print(f"\n  detection of the cut flights by a healthy baseline (normal flights of both airframes, never a cut "
          f"flight: every depth is unseen), {DETECTOR}, alpha {ALPHA:g}, disjoint {WINDOW_S:g} s windows; a flight "
          "is detected when its flagged windows are above its 99 % binomial band of alpha")
    flights = [f for _, cond in cut_series() for f in cp.load_condition(cond, ch.margin)]
    normal = cp.load_condition(cp.NORMAL, ch.margin)
    ks = airframe_k(f.drone for f in normal)
    depth_of = {cond: depth for depth, cond in cut_series()}
    fa = pd.concat([healthy_lofo(kind) for kind in ("pooled", "fp")])
    for kind in ("pooled", "fp"):
        det = pd.DataFrame(judge(healthy_baseline(kind, normal, ch, ks), flights, ch, (DETECTOR,)))
        det["depth"] = det.condition.map(depth_of)
        print(f"  -- {kind} baseline: depth  windows flagged    flights detected")
        for depth, g in det.groupby("depth"):
            x, n = int(g.flagged.sum()), int(g.n.sum())
            up = sum(above_band(r.flagged, r.n) for r in g.itertuples())
            print(f"     {depth:5.1f}  {x:3d}/{n:<3d} = {100 * x / n:5.1f} %  {up}/{len(g)}")
        x, n = int(det.flagged.sum()), int(det.n.sum())
        ref = fa[(fa.baseline == kind) & (fa.test == DETECTOR) & (fa.step_s == WINDOW_S)]
        print(f"     all    {x:3d}/{n:<3d} = {100 * x / n:5.1f} %  "
              f"{sum(above_band(r.flagged, r.n) for r in det.itertuples())}/{len(det)}; normal flights (leave one "
              f"flight out, section 3): {rate_line(ref)}, {sum(above_band(r.flagged, r.n) for r in ref.itertuples())}"
              f"/{len(ref)} flights above their band")

    tables = depth_detection(ch)

    print(f"\n== 3. CrazyPAD healthy flights of both airframes, leave one flight out ({len(cp.normal_logs())} folds): "
          f"a pooled baseline (one VAR of both airframes) and an FP baseline (FP-VAR, k = airframe "
          f"{', '.join(f'{d}: {k:g}' for d, k in ks.items())}, Legendre degree {len(ks) - 1}: the airframe is what "
          "the controller logs carry at flight level; no battery channel, trims move within a drone between "
          "sessions); margin, channels and order of crazypad.py chosen on each fold's fitting flights; tests "
          "calibrated on the baseline's held-out residuals (log by log)")
    report_healthy(fa)
    detectability(ch, tables["b0"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=None, help="CrazyPAD folder (default ../shared/data/crazypad)")
    ap.add_argument("--lags", type=int, default=None)
    ap.add_argument("--degree", type=int, default=None)
    args = ap.parse_args()
    t0 = time.perf_counter()
    cost()
    if args.data is not None:
        cp.ROOT = Path(args.data)
    if (cp.ROOT / "flights.csv").is_file():
        crazypad(args.lags, args.degree)
    else:
        print(f"\n== 2-3. skipped: CrazyPAD data missing at {cp.ROOT}")
    print(f"\nrun time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()

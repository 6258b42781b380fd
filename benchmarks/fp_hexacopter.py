"""Global FP models on the realistic hexacopter (issue 32): rotor identification across forward speeds, payloads and
the three turbulence levels, healthy false alarms, and the magnitude of a partial loss of rotor effectiveness.

Run: ``python benchmarks/fp_hexacopter.py [--quick] [--dev]`` (BLAS pinned to one thread; numba uses the cores).
``--dev`` evaluates on the development evaluation seed ``DEV_EVAL_SEED`` instead of a fresh one (the runs the
choices below were made on); ``--quick`` a quarter of the records.

Design (every choice below was made on development records, seeds ``DEV_SEED`` and ``DEV_EVAL_SEED``, never on the
evaluation ones):

* Aircraft: the default (blade-element, one-way rotors) hexacopter, ``FleetSpread(payload=0.3)`` (the default
  airframe spreads plus a payload of 0-30 % of the gross weight), forward speed drawn in ``SPEEDS`` (m/s) per record,
  the turbulence levels of the realistic-aircraft design (``LEVELS``: light, moderate, severe; equal numbers of
  records, the level not logged and not used by any model), 45 s records, rotor failure at 1 s, analysed from 5 s
  to 45 s (the transient left out): two 20 s windows or eight 5 s windows per record.
* Operating parameters ``k = (speed, payload)``. Held-out weight: development records are drawn only outside the
  payload band ``HELD_OUT``; the evaluation records inside it form the held-out-weight set, those outside it the
  interpolation set (speeds and payloads drawn afresh, so every evaluation point lies between fitting ones).
* Identification (controller-aware, functionally pooled trim): what the controller does about a failed rotor is to
  hold a large steady roll / pitch / yaw control (the compensation among the paper's eq. 2 outputs, about (-170, 72,
  105) for rotor 2 against (13, -32, -5) healthy), which the one-step prediction errors of an FP-VAR barely see (its
  lags carry the level). That is where the earlier rule's rotor 2 confusion came from: on the development records the
  FP-VAR likelihood sent the 5 s windows of rotor 2 records after the first 10 s to healthy, in light turbulence most
  (``test_trim_identifies_the_rotor2_windows_the_fp_var_likelihood_calls_healthy``). Per class, the trim model
  :class:`tsfdi.models.FPMean`: the window means of the three controller outputs regressed on the FP basis of ``k``
  (Legendre, degree ``TRIM_DEGREE``), pooled least squares over all fitting windows of all turbulence levels
  (healthy: the development fitting records and ``HEALTHY_POOL`` more per level, seed ``DEV_SEED + 100``; each rotor:
  its development fitting records); the residual covariance ``S`` of a window is the spread of the records' mean
  residuals (records - basis functions degrees of freedom: the unlogged airframe of a record moves its whole trim)
  plus the spread of the windows around their record's mean. A window goes to the class whose trim surface, at that
  class's maximum-likelihood ``k`` (a grid of ``K_GRID`` points per parameter over the fitted range, refined by
  bounded local grids), gives its mean the largest Gaussian log-likelihood with ``S`` (:func:`tsfdi.identify_windows`
  with the FPMean results, ``decide("likelihood")``): everything from the window itself (no logged ``k``, no
  turbulence level, no other window of the record).
* Healthy false alarms, alpha = 0.01 per window: the ``trim`` detector, the healthy trim statistic ``min_k (m - M(k))'
  S^-1 (m - M(k))`` against the empirical 0.99 quantile (:class:`tsfdi.EmpiricalThreshold`) of that statistic on
  windows every ``CAL_STEP`` samples of the development calibration records (healthy, all levels, outside
  ``HELD_OUT``; ``N_CAL`` per level, seed ``CAL_SEED``, none of them fitted). For comparison ``F``:
  :func:`tsfdi.detect` with the healthy FP-VAR (channels roll, pitch, yaw rate and the three controller outputs; order
  and degree by ``select_fp_order`` on the healthy development records, BIC over degree >= 1) at the logged ``k`` and
  the F test calibrated as the shipped pipeline does (``FTest.calibrate``, ``ScaledChi2Threshold(0.01,
  min_windows=5)``, records joined to hold three windows each). The 99 % binomial band of alpha for the number of
  windows (windows of one record are not independent: the band is narrower than the rate's real spread).
* The claim >= 99.6 % per class needs enough windows: the rule used is the one-sided 95 % Clopper-Pearson lower
  bound of the correct share over all evaluation windows of the class (interpolation and held-out weight
  together; 0 errors shows >= 99.6 % from 748 windows, the run has 756 20 s windows per class). Windows of one
  record share its aircraft, so they are not independent; the bound counts windows, as the issue's rates do.
* Chosen on the development evaluation records (``--dev``, seed ``DEV_EVAL_SEED``, full size): ``TRIM_DEGREE = 2``
  (the BIC over records prefers 1, which made 1 + 6 errors on the healthy 20 s / 5 s windows there, degree 2 and 3
  none; the ``--dev`` run prints every degree's errors); the trim detector (1.06 % / 1.32 % of 756 / 3024 healthy
  windows there, the F detector 0 %: below the band). Before that, the trim model's covariance over windows
  rather than records was found too small on a ``--quick --dev`` run (9 records per class, degree 2: every
  healthy window went to a fault).
* Healthy class, changed after the evaluation run on seed 866863658 (trim alarms 1.72 % / 2.02 % of the 20 s / 5 s
  healthy windows, 2.02 % above the 99 % band; 6 healthy 20 s windows sent to a fault), on development records only:
  the healthy trim model was fitted on 36 records (its record covariance on 27 degrees of freedom) and the threshold
  calibrated on 192 others. A second development evaluation seed, 20261130 (healthy records only, the design of the
  evaluation sets), reproduced the excess with that design (2.03 % / 1.98 % of the 5 s windows, interpolation /
  held-out weight). The statistic is a record-level quantity: the record spread of the trim (sd about 10 / 10 / 5 in
  roll / pitch / yaw control, the unlogged airframe: uniform centre-of-gravity offsets) is at least 10 times the
  spread of the windows around their record's mean in every turbulence level, the record means do not depend on the
  level, and the attitude means explain none of it (R^2 <= 0.02); profiling k takes up much of it
  (the healthy statistic's median is 0.45-1.1, between those of chi-square with one and two degrees of freedom). So
  the alarms come by record (an alarmed record has 1-8 of its eight 5 s windows above the threshold) and a threshold
  set on a few records in the tail is noisy. Tried on the development records (seeds 20261129 and 20261130, 378
  healthy records each; rates of the 5 s windows, interpolation / held-out weight): a predictive law on the record
  covariance (F(1, records - basis functions), the covariance inflated by the surface's leverage at each k: 0 % from
  36 fitting records, 0.84-1.19 % / 0.50-0.99 % from 228); a covariance of the window from its own sample covariance
  (the turbulence seen in the window: no change, 0.79-1.19 %); leave-one-record-out calibration on the fitting records
  (1.29-1.44 % / 1.19-1.29 % from 228, 0.64-1.84 % / 0.60-1.09 % from 528). Kept: the same statistic and model (no
  leverage term: it sent 1 + 5 healthy 20 s + 5 s windows to a fault there, without it 0 + 6), fitted on 228 healthy
  records (``HEALTHY_POOL``), the empirical threshold from 300 other healthy records (``CAL_SEED``): 0.79-0.99 % of
  the 20 s and 0.60-1.19 % of the 5 s windows on the four development sets, all in their bands; identification:
  healthy 0 of 1512 20 s and 6 of 6048 5 s windows wrong (the 36-record healthy model: 0 and 3), every rotor window
  correct on seed 20261129. Resampling the 756 development records' alarm counts (378 records a run, rate 1.03 %): a
  run lands in the 99 % band of its 3,024 5 s windows with probability 0.76 only (0.94 for the 756 20 s windows): the
  windows of a record are not independent, the band is narrower than the rate's spread.
* Library (issue 32): the trim model is :class:`tsfdi.models.FPMean`, identification :func:`tsfdi.identify_windows`,
  the trim detector :func:`tsfdi.detect` with the calibrated threshold (before: functions of this file). On the
  full development run (``--dev``) the library gives this file's former figures exactly with ``k`` from the grid
  alone. With its refinement of ``k`` beyond the grid (the maximum likelihood) the trim detector has 33 instead of
  32 alarms in the 3,024 healthy 5 s windows (held-out weight, severe turbulence: 3 instead of 2 of 336), and the
  ``--dev`` degree table 2 healthy 5 s windows wrong at degree 3 instead of 0; everything else, identification at
  ``TRIM_DEGREE`` included, is unchanged (``--dev --quick``: identical). The BIC by degree now holds the Gaussian
  constant and the covariance parameters (the same differences between degrees).
* Magnitude: rotors 1 and 2 at the nominal point, moderate turbulence, 25 s records, FP-VAR (controller-aware
  channels) over the loss level, fitted at ``LEVELS_FIT`` (0: healthy records), ``estimate_k`` on records at
  ``LEVELS_EVAL`` (not fitted); RMSE in percentage points and coverage of the 95 % intervals.
"""

from __future__ import annotations

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.datasets import simulate_hexacopter  # noqa: E402
from tsfdi.datasets.hexacopter import FleetSpread, HexacopterParameters  # noqa: E402
from tsfdi.models import FPVAR, FPMean, FPMeanResults, select_fp_order  # noqa: E402
from tsfdi.study import evaluation_seed  # noqa: E402

DEV_SEED = 20261128
DEV_EVAL_SEED = 20261129
CAL_SEED = 20261131                      # the healthy calibration records of the detectors (development)
HEALTHY_POOL = 64                        # more healthy fitting records per level (seed DEV_SEED + 100)
N_CAL = 100                              # healthy calibration records per level
FLEET = FleetSpread(payload=0.3)
SPEEDS = (2.0, 10.0)
HELD_OUT = (0.12, 0.18)
K_RANGE = np.array([SPEEDS, (0.0, FLEET.payload)])
K_GRID = 11
CLASSES = {"healthy": 0, "rotor1": 1, "rotor2": 2, "rotor6": 6}
LEVELS = ("light", "moderate", "severe")
CONTROL = ("roll", "pitch", "r", "roll_control", "pitch_control", "yaw_control")
TRIM = slice(3, 6)                       # the controller outputs among CONTROL
DURATION, FAIL_T, START, FS = 45.0, 1.0, 500, 100
WINDOWS = (2000, 500)
MAX_TRIM_DEGREE = 3
TRIM_DEGREE = 2
CAL_STEP = 25                            # samples between the calibration windows of the trim detector
LEVELS_FIT = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)
LEVELS_EVAL = (0.1, 0.3, 0.5, 0.7, 0.9)
ALPHA = 0.01


def seeds(base: int, count: int, band: str | None = None, start: int = 0) -> list[int]:
    """``count`` record seeds of ``base``; ``band`` "in" / "out": only those whose drawn payload is inside / outside
    ``HELD_OUT`` (the draw depends on the seed alone, so no record is simulated to choose it)."""
    out, i = [], start
    nominal = HexacopterParameters()
    while len(out) < count:
        sd = int(np.random.SeedSequence([base, i]).generate_state(1)[0] >> 1)
        i += 1
        if band is not None:
            pay = FLEET.draw(nominal, sd)[1]["payload"]
            inside = HELD_OUT[0] <= pay <= HELD_OUT[1]
            if inside != (band == "in"):
                continue
        out.append(sd)
    return out


def simulate(sds, rotor, turbulence, *, duration=DURATION, fleet=True, speed=SPEEDS, level=1.0):
    """The CONTROL channels of every record from ``START`` on, and ``k`` = (speed, payload) per record."""
    ds = simulate_hexacopter(duration=duration, turbulence=turbulence, failed_rotor=rotor, failure_time=FAIL_T,
                             failure_level=level, seed=sds, speed=speed, fleet=FLEET if fleet else None)
    assert not ds["lost_control"].any(), "a record lost control"
    recs = [np.column_stack([ds[c].values[i, START:] for c in CONTROL]) for i in range(ds.sizes["record"])]
    k = np.column_stack([ds["speed"].values, ds["payload"].values]) if fleet else None
    return recs, k


def simulate_levels(base: int, count: int, rotor: int, band: str | None, start: int = 0):
    """``count`` records per turbulence level (seeds of ``base`` in ``band``): records, k and level index."""
    sds = seeds(base, count * len(LEVELS), band, start)
    turb = [lv for lv in LEVELS for _ in range(count)]
    recs, k = simulate(sds, rotor, turb)
    return recs, k, np.repeat(np.arange(len(LEVELS)), count)


def join(*sets):
    """One set of records from several sets of :func:`simulate_levels` (records, k and level index in order)."""
    return sum((list(s[0]) for s in sets), []), np.vstack([s[1] for s in sets]), np.concatenate([s[2] for s in sets])


def fit_trim(recs, k, w: int, degree: int) -> FPMeanResults:
    """The trim model (:class:`tsfdi.models.FPMean`) of the controller outputs of the records on windows of ``w``
    samples."""
    return FPMean([y[:, TRIM] for y in recs], k, w, degree, k_range=K_RANGE, grid=K_GRID).fit()


def identify_trim(models: dict, y: np.ndarray, w: int) -> np.ndarray:
    """The class of every consecutive window of ``w`` samples of record ``y``: the largest log-likelihood of the trim
    models (:func:`tsfdi.identify_windows` without thresholds, ``decide("likelihood")``)."""
    return np.array(tsfdi.identify_windows(y[:, TRIM], models, window=w, step=w).decide("likelihood"))


def fp_choice(sel) -> tuple[int, int]:
    """The BIC minimum over degrees >= 1 (degree 0, one pooled VAR that does not depend on k, estimates nothing)."""
    t = sel.table[sel.table.index.get_level_values("degree") >= 1]
    lags, deg = t["bic"].idxmin()
    return int(lags), int(deg)


def band99(n: int, alpha: float = ALPHA) -> tuple[float, float]:
    return stats.binom.ppf(0.005, n, alpha) / n, stats.binom.isf(0.005, n, alpha) / n


def lower95(correct: int, n: int) -> float:
    """One-sided 95 % Clopper-Pearson lower bound of a share."""
    return 0.0 if correct == 0 else float(stats.beta.ppf(0.05, correct, n - correct + 1))


def windows(y, w):
    return [y[a:a + w] for a in range(0, len(y) - w + 1, w)]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="a quarter of the records (a smoke run)")
    ap.add_argument("--dev", action="store_true", help="evaluate on the development evaluation seed")
    args = ap.parse_args()
    q = 4 if args.quick else 1
    n_fit, n_int, n_held = max(12 // q, 4), 84 // q, 42 // q                   # records per class and level
    n_pool, n_cal = HEALTHY_POOL // q, N_CAL // q                                # healthy only, per level
    n_lfit, n_leval = max(4 // q, 2), max(3 // q, 1)
    ev = DEV_EVAL_SEED if args.dev else evaluation_seed()
    print(f"development seed {DEV_SEED}, evaluation seed {ev} "
          + ("(the development evaluation seed)" if args.dev else "(fresh, unstored)"))
    t0 = time.perf_counter()
    dev, ev_int, ev_held = {}, {}, {}
    for j, (c, rotor) in enumerate(CLASSES.items()):
        dev[c] = simulate_levels(DEV_SEED + j, n_fit, rotor, "out")
        ev_int[c] = simulate_levels(ev, n_int, rotor, "out", start=100000 * j)
        ev_held[c] = simulate_levels(ev, n_held, rotor, "in", start=100000 * j + 50000)
    # the healthy trim surface and covariance from the healthy fitting records and the pool; the detectors
    # calibrated on other records (CAL_SEED)
    trim_fit = dict(dev, healthy=join(dev["healthy"], simulate_levels(DEV_SEED + 100, n_pool, 0, "out")))
    cal = simulate_levels(CAL_SEED, n_cal, 0, "out")
    nrec = len(CLASSES) * len(LEVELS) * (n_fit + n_int + n_held) + len(LEVELS) * (n_pool + n_cal)
    print(f"simulated {nrec} records of {DURATION:g} s ({', '.join(LEVELS)} turbulence) in "
          f"{time.perf_counter() - t0:.0f} s")

    # --- trim models at the frozen degree (BIC on the development records, and with --dev every degree's
    # identification on the development evaluation records, printed below)
    degrees = [d for d in range(MAX_TRIM_DEGREE + 1) if (d + 1) ** 2 < len(dev["rotor1"][0])]
    bic = {d: sum(fit_trim(*trim_fit[c][:2], WINDOWS[-1], d).bic for c in CLASSES) for d in degrees}
    print(f"trim FP regression: degree {TRIM_DEGREE} (frozen); BIC over records of the development set by degree: "
          + ", ".join(f"{d}: {b:.0f}" for d, b in bic.items()))
    trim = {w: {c: fit_trim(*trim_fit[c][:2], w, TRIM_DEGREE) for c in CLASSES} for w in WINDOWS}
    if args.dev:
        for d in degrees:
            line = []
            for w in WINDOWS:
                tw = {c: fit_trim(*trim_fit[c][:2], w, d) for c in CLASSES}
                for c in CLASSES:
                    wrong = sum(int((identify_trim(tw, y, w) != c).sum()) for data in (ev_int, ev_held)
                                for y in data[c][0])
                    line.append(f"{c} {w // FS}s {wrong}")
            print(f"  degree {d}: wrong windows " + ", ".join(line))

    # --- the healthy FP-VAR of the F detector
    sel = select_fp_order(dev["healthy"][0], dev["healthy"][1], 10, 2, "var")
    lags, deg = fp_choice(sel)
    print(f"healthy FP-VAR: select_fp_order (BIC, lags <= 10, degree <= 2): minimum lags={sel.selected[0]}, "
          f"degree={sel.selected[1]}; over degree >= 1: lags={lags}, degree={deg}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", tsfdi.exceptions.IllConditionedWarning)
        fp = FPVAR(dev["healthy"][0], dev["healthy"][1], lags, degree=deg, k_range=K_RANGE).fit()

    # --- detectors calibrated on the development calibration records
    ftest, trim_thr = {}, {}
    for w in WINDOWS:
        group = -(-3 // (len(cal[0][0]) // w))         # records joined so that each holds >= 3 windows
        res = [np.asarray(fp.residuals(y, k)) for y, k in zip(cal[0], cal[1])]
        # each record's residuals hold whole windows of w - lags, so no window spans two records; consecutive
        # records joined in len(res) // group groups of at least ``group`` records (none left short)
        res = [np.concatenate([r[:(len(r) // (w - lags)) * (w - lags)] for r in res[i[0]:i[-1] + 1]])
               for i in np.array_split(np.arange(len(res)), len(res) // group)]
        t = tsfdi.FTest(alpha=ALPHA, correction="bonferroni", threshold=tsfdi.ScaledChi2Threshold(ALPHA, min_windows=5))
        ftest[w] = t.calibrate(res, window=w - lags, step=w - lags, **t.reference(fp.at(cal[1][0])))
        stat = np.concatenate([trim[w]["healthy"].statistic(y[:, TRIM], CAL_STEP) for y in cal[0]])
        trim_thr[w] = tsfdi.EmpiricalThreshold(ALPHA).calibrate(stat)

    t1 = time.perf_counter()
    # per record: correct windows, windows, and (healthy) the trim and F false alarms
    score = {}
    for w in WINDOWS:
        for setname, data in (("interp", ev_int), ("heldout", ev_held)):
            for c in CLASSES:
                recs, ks, lvl = data[c]
                for i, y in enumerate(recs):
                    labels = identify_trim(trim[w], y, w)
                    fa_t = fa_f = 0
                    if c == "healthy":
                        fa_t = sum(tsfdi.detect(seg, trim[w]["healthy"], trim_thr[w]).reject
                                   for seg in windows(y[:, TRIM], w))
                        at = fp.at(ks[i])
                        fa_f = sum(tsfdi.detect(seg, at, ftest[w]).reject for seg in windows(y, w))
                    score[w, setname, c, i] = (lvl[i], int((labels == c).sum()), len(labels), fa_t, fa_f)

    def total(w, sets, c, level=None):
        rows = [v for (w_, s_, c_, _), v in score.items() if w_ == w and s_ in sets and c_ == c
                and (level is None or v[0] == level)]
        return np.array(rows)[:, 1:].sum(axis=0)

    print()
    print("Identification (percent of windows correct per class: the class whose trim surface at its maximum-"
          "likelihood k gives the window's mean controller output the largest likelihood) and healthy false "
          f"alarms (alpha {ALPHA}) of the trim and F detectors")
    print(f"{'set':8s} {'turb':8s} {'win':>4s} " + " ".join(f"{c:>8s}" for c in CLASSES)
          + f" {'windows':>7s} {'FA trim %':>9s} {'FA F %':>7s} {'99% band':>13s}")
    for w in WINDOWS:
        for setname in ("interp", "heldout"):
            for li, lv in list(enumerate(LEVELS)) + [(None, "all")]:
                row = {c: total(w, (setname,), c, li) for c in CLASSES}
                _, nwin, fa_t, fa_f = row["healthy"]
                lo, hi = band99(nwin)
                print(f"{setname:8s} {lv:8s} {w // FS:3d}s " + " ".join(f"{100 * r[0] / r[1]:8.1f}" for r in row.values())
                      + f" {nwin:7d} {100 * fa_t / nwin:9.2f} {100 * fa_f / nwin:7.2f} [{100 * lo:4.2f}, {100 * hi:4.2f}]")
    print()
    print("Per class over both sets and all levels: correct / windows, percent, one-sided 95 % Clopper-Pearson lower "
          "bound (target: >= 99.6 % at 20 s, >= 97 % at 5 s)")
    for w in WINDOWS:
        tot = {c: total(w, ("interp", "heldout"), c) for c in CLASSES}
        print(f"{w // FS:3d}s " + "  ".join(f"{c}: {a}/{n} {100 * a / n:.2f} % (>= {100 * lower95(a, n):.2f} %)"
                                            for c, (a, n, _, _) in tot.items()))
        _, nwin, fa_t, fa_f = tot["healthy"]
        lo, hi = band99(nwin)
        print(f"     healthy false alarms: trim {fa_t}/{nwin} = {100 * fa_t / nwin:.2f} %, F {fa_f}/{nwin} = "
              f"{100 * fa_f / nwin:.2f} %; 99 % band of {ALPHA} for {nwin} windows [{100 * lo:.2f}, {100 * hi:.2f}] %")
    print(f"(identification and detection {time.perf_counter() - t1:.0f} s)", flush=True)

    # --- magnitude: loss of effectiveness at the nominal point
    print()
    print("Loss-of-effectiveness level by estimate_k (FP-VAR over the level, controller-aware channels, "
          f"fit levels {LEVELS_FIT}, evaluated at {LEVELS_EVAL})")
    for rotor in (1, 2):
        ys, ks = [], []
        for lv in LEVELS_FIT:
            r, _ = simulate(seeds(DEV_SEED + 300 + rotor, n_lfit, start=int(100 * lv) * 10), rotor if lv else 0,
                            "moderate", duration=25.0, fleet=False, speed=5.0, level=lv if lv else 1.0)
            ys += r
            ks += [lv] * len(r)
        sel = select_fp_order(ys, np.array(ks), lags, 3, "var")
        lf, df = fp_choice(sel)
        fpl = FPVAR(ys, np.array(ks), lf, degree=df).fit()
        err, cover = [], []
        for lv in LEVELS_EVAL:
            r, _ = simulate(seeds(ev, n_leval, start=900000 + 1000 * rotor + int(100 * lv)), rotor, "moderate",
                            duration=25.0, fleet=False, speed=5.0, level=lv)
            for y in r:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    est = fpl.estimate_k(y)
                err.append(est.k_hat[0] - lv)
                cover.append(est.conf_int[0, 0] <= lv <= est.conf_int[0, 1])
                print(f"  rotor{rotor} level {lv:.2f}: k_hat {est.k_hat[0]:.3f} "
                      f"[{est.conf_int[0, 0]:.3f}, {est.conf_int[0, 1]:.3f}]")
        print(f"rotor{rotor}: lags={lf}, degree={df} (BIC over degree >= 1 on the fitting levels); "
              f"RMSE {100 * np.sqrt(np.mean(np.square(err))):.2f} percentage points, 95 % interval coverage "
              f"{100 * np.mean(cover):.0f} % ({len(err)} records)", flush=True)
    print(f"total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()

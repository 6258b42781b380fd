"""Record-level calibration on the next aircraft of a fleet (issue 31).

1. A simulated fleet: VAR(2) records whose coefficients (``A + 0.04 N(0, 1)``) and innovation scale (log-normal
   +-15 % per record and channel) vary from aircraft to aircraft. A baseline VAR(2) is fitted on 5, 10 or 20
   records, the F and Ljung-Box tests (Sidak over the 3 channels, so alpha is the decision's rate) are calibrated on
   its held-out residuals (windows of 200 samples), and 60 new records of the same fleet (600 disjoint windows) are
   judged. Over ``--fleets`` fleets (``--seed``: the first): the realised rate of the decision averaged over fleets,
   its 99.9 % interval over the independent fleets, for the F test the same mean with the fitting records' noise
   levels as control variate (:func:`pivot_rate`), its spread, and how many fleets fall in the two-sided 99.9 %
   binomial band of one fleet's 600 windows, whether the mean over fleets lies in the all-fleets band ("mean in
   band") and how often an *exact* law would (``yardstick_reach``: 1,500 runs of as many ideal fleets with this
   layout and the measured row's between / within spread; the yardstick's own reach); "old" is the per-record
   mixture with a 90 % bootstrap bound (``record_effect="bootstrap"``), "new" the predictive record-level law.
2. CrazyPAD (``../shared/data/crazypad``, the functions of ``benchmarks/crazypad.py``: margin, channels and VAR
   order chosen on the fitting flights, each log's two airborne segments fitted and held out together), normal
   flights of both airframes (E8, E9). The tests, each Sidak-corrected over the channels so that alpha is the
   decision's rate, calibrated with the predictive record-level law (the default) on the baseline's held-out
   residuals (``min_windows=5`` as in crazypad.py): ``LB-S`` (Ljung-Box, 10 lags per s), ``F-S``, ``M-S`` and
   ``LB+F+M`` (``tsfdi.AnyOf`` of the three). Realised rate of the decision on the disjoint 1 s and 2 s windows of
   the judged flights, with the two-sided 99.9 % binomial band of alpha:
   a. leave one flight out over all normal flights (8 folds);
   b. leave one flight out within an airframe (same-airframe flights), and the two coverage checks on every judged
      segment, ``tsfdi.coverage.coverage`` (summaries) and ``tsfdi.coverage.record_coverage`` (the record law of
      ``LB+F+M`` calibrated at 1 s windows): their false-warning rates;
   c. fit on one airframe, judge the other: rates, and per judged flight whether ``LB+F+M`` (2 s and 1 s, alpha
      0.01) breaks the band of its own windows and whether each check fires on it;
   d. detection kept: ``LB+F+M`` on cut_propeller_M3_4mm_4mm_39mm, the VAR of all normal flights, 2 s windows
      (target >= 95 %).
3. The realistic hexacopter (``tsfdi.datasets.simulate_hexacopter``, 30 s in severe turbulence, the first 5 s
   dropped; channels roll, pitch, yaw rate) with a fleet spread: ``FleetSpread(payload=0.3)`` (payload 0-30 % of
   the gross weight) and the default airframe spreads (mass, centre of gravity, motor constant, inertia); healthy
   records only. A VAR (BIC order) fitted on 10 aircraft, the tests calibrated on its held-out residuals, 40 other
   aircraft judged (2 s windows, disjoint): in band?

Run: ``python benchmarks/fleet_calibration.py [--fleets 40] [--seed 2031] [--predictive-only] [--data PATH]
[--no-crazypad] [--no-hexacopter]``
(BLAS pinned to one thread; prints its run time).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ["OPENBLAS_NUM_THREADS"] = "1"
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.coverage import coverage, record_coverage  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import crazypad as cp  # noqa: E402

A1 = np.array([[0.5, 0.1, 0.0], [0.0, 0.4, 0.1], [0.1, 0.0, 0.3]])
A2 = -0.2 * np.eye(3)
N, WINDOW, SPREAD, NOISE = 2000, 200, 0.04, 0.15
RECORDS, NEW, ALPHAS = (5, 10, 20), 60, (1e-2, 1e-3)


def fleet(rng: np.random.Generator, count: int, n: int = N) -> tuple:
    """``count`` records of the fleet: VAR(2) with coefficients ``A + SPREAD N(0, 1)`` and innovations scaled by
    ``exp(NOISE z)``, ``z`` standard normal per record and channel (+-15 %, log-normal) (all records simulated at
    once); returns the records and ``z`` (count, 3)."""
    b1 = A1 + SPREAD * rng.standard_normal((count, 3, 3))
    b2 = A2 + SPREAD * rng.standard_normal((count, 3, 3))
    e = rng.standard_normal((n + 200, count, 3))
    z = rng.standard_normal((count, 3))
    e = e * np.exp(NOISE * z)
    y = np.zeros_like(e)
    for t in range(2, n + 200):
        y[t] = np.einsum("rij,rj->ri", b1, y[t - 1]) + np.einsum("rij,rj->ri", b2, y[t - 2]) + e[t]
    return [y[200:, r] for r in range(count)], z


def fleet_records(rng: np.random.Generator, count: int, n: int = N) -> list:
    """The records of :func:`fleet`."""
    return fleet(rng, count, n)[0]


def pivot_rate(z: np.ndarray, alpha: float) -> float:
    """Control variate of the F test's rate: per channel, the exact Student t prediction bound of a new record's log
    noise variance (``2 NOISE z``) from the fitting records' ``z`` (records, 3) at the Sidak share of ``alpha``, and
    the probability that a new record's variance exceeds it; the mean over channels divided by the share. Its
    expectation over fleets is exactly 1 (the t pivot), and it moves with the F test's rate, which the fitting
    records' noise levels drive."""
    j = z.shape[0]
    share = 1.0 - (1.0 - alpha) ** (1.0 / z.shape[1])
    bound = z.mean(axis=0) + stats.t.isf(share, j - 1) * z.std(axis=0, ddof=1) * np.sqrt(1.0 + 1.0 / j)
    return float(stats.norm.sf(bound).mean() / share)


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
    """Rows (records, alpha, family, effect, rate, threshold of channel 0, :func:`pivot_rate`) of one simulated
    fleet: the baselines fit on the first 5 / 10 / 20 records of the fleet, all judged on the same 60 new records."""
    rng = np.random.default_rng(seed)
    fit, z = fleet(rng, max(records))
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
                    laws = [t.record_law_ for t in test.thresholds_]
                    between = np.mean([law["between_sd"] for law in laws]) if laws[0] is not None else np.nan
                    within = np.sqrt(np.mean([np.mean(2.0 / t.df_) for t in test.thresholds_]))
                    rows.append((j, a, fam, eff, decision_rate(test, resid), float(test.threshold_[0]),
                                 pivot_rate(z[:j], a), between, within))
    return rows


def exact_factor(j: int, share: float, ratio: float) -> float:
    """``c`` of the exact law of :func:`yardstick_reach`: ``E_s[P(N(0, k^2 + ratio^2) > s k c)] = share`` with
    ``k^2 = 1 + 1/j`` and ``s^2 ~ chi2(j - 1) / (j - 1)`` (on 4,000 quantiles of that law), by bisection."""
    u = (np.arange(4000) + 0.5) / 4000
    s = np.sqrt(stats.chi2.ppf(u, j - 1) / (j - 1))
    k = np.sqrt(1.0 + 1.0 / j)
    tot = np.sqrt(k * k + ratio * ratio)
    lo, hi = 0.0, 1e4
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stats.norm.sf(s * k * mid / tot).mean() > share else (lo, mid)
    return 0.5 * (lo + hi)


def yardstick_reach(j: int, alpha: float, ratio: float, fleets: int, sets: int = 1500, seed: int = 0) -> tuple:
    """How often an *exact* law meets the yardstick "the mean rate over ``fleets`` fleets inside the all-fleets
    99.9 % binomial band" (the share of ``sets`` independent runs that do), and its mean rate over all runs.

    The ideal fleet has this benchmark's layout (``j`` fitting records, ``NEW`` new records of ``(N - 2) //
    (WINDOW - 2)`` windows, 3 independent channels, Sidak): a record's log statistic level is normal between
    records (sd 1), a window's log statistic that level plus normal noise of sd ``ratio`` (within over between, as
    the calibrations of the measured row estimate it); the fitting records' levels are known exactly. The law
    flags a window above ``mean + s sqrt(1 + 1/j) c`` of the fitting records' levels, ``c`` from
    :func:`exact_factor`: its rate over fleets is exactly the per-channel share (the new level minus the mean is
    independent of ``s``), so the decision's expected rate is exactly ``alpha``; what it cannot avoid is that a
    fleet's rate depends on its few fitting records."""
    rng = np.random.default_rng(seed)
    windows = (N - 2) // (WINDOW - 2)
    share = 1.0 - (1.0 - alpha) ** (1.0 / 3.0)
    c = exact_factor(j, share, ratio)
    x = rng.standard_normal((sets, fleets, 3, j))
    thr = x.mean(axis=-1) + x.std(axis=-1, ddof=1) * np.sqrt(1.0 + 1.0 / j) * c
    p = stats.norm.sf((thr[:, :, None, :] - rng.standard_normal((sets, fleets, NEW, 3))) / ratio)
    rate = rng.binomial(windows, 1.0 - np.prod(1.0 - p, axis=-1)).sum(axis=-1) / (NEW * windows)
    mean = rate.mean(axis=-1)
    lo, hi = band(NEW * windows * fleets, alpha)
    return float(np.mean((mean >= lo) & (mean <= hi))), float(mean.mean())


def band(n: int, alpha: float) -> tuple:
    """Two-sided 99.9 % binomial band of the rate in ``n`` independent windows."""
    lo, hi = stats.binom.ppf([0.0005, 0.9995], n, alpha)
    return lo / n, hi / n


def ratio(g: pd.DataFrame) -> float:
    """Within- over between-record spread of a row's calibrations (medians over its fleets; at most 30: a spread
    estimated as 0 leaves the windows' binomial noise only)."""
    return float(min(g.within.median() / max(g.between.median(), 1e-9), 30.0))


def fleet_table(fleets: int, seed: int = 2031, effects=("bootstrap", "predictive")) -> None:
    """The table of part 1. Besides the binomial bands (which treat every window of every fleet as independent), the
    mean rate's 99.9 % t interval over the independent fleets (a fleet's rate varies far beyond the binomial: its
    fitting records are a sample of the fleet), and for the F test the mean rate with :func:`pivot_rate` as control
    variate (``rate - beta (pivot - 1) alpha``, ``beta`` by least squares; unbiased, with its own 99.9 % interval;
    the Ljung-Box rate does not follow the noise levels)."""
    t0 = time.perf_counter()
    rows = [(f, *r) for f in range(fleets) for r in one_fleet(seed + f, effects=effects)]
    df = pd.DataFrame(rows, columns=["fleet", "records", "alpha", "test", "calibration", "rate", "threshold",
                                     "pivot_rate", "between", "within"])
    windows = NEW * ((N - 2) // (WINDOW - 2))
    q = stats.t.isf(5e-4, fleets - 1)
    out = []
    for (j, a, fam, eff), g in df.groupby(["records", "alpha", "test", "calibration"], sort=False):
        lo, hi = band(windows, a)
        lo_all, hi_all = band(windows * fleets, a)
        y, c = g["rate"].to_numpy(), g["pivot_rate"].to_numpy() * a
        beta = np.cov(y, c)[0, 1] / c.var(ddof=1) if fam == "F" and c.var() > 0 else 0.0
        adj = y - beta * (c - a)
        cv = f"{100 * adj.mean():.3g} +- {100 * q * adj.std(ddof=1) / np.sqrt(fleets):.2g}" if fam == "F" else "-"
        out.append({"records": j, "alpha": a, "test": fam, "calibration": eff,
                    "mean rate %": 100 * y.mean(), "band (all fleets) %": f"{100 * lo_all:.3g}-{100 * hi_all:.3g}",
                    "mean in band": "yes" if lo_all <= y.mean() <= hi_all else "no",
                    "exact law in band %": "-" if eff != "predictive" else
                    f"{100 * yardstick_reach(j, a, ratio(g), fleets)[0]:.0f}",
                    "99.9 % CI over fleets %": f"{100 * (y.mean() - q * y.std(ddof=1) / np.sqrt(fleets)):.3g}-"
                    f"{100 * (y.mean() + q * y.std(ddof=1) / np.sqrt(fleets)):.3g}",
                    "control-variate mean %": cv,
                    "median %": 100 * np.median(y), "p10-p90 %": f"{100 * g.rate.quantile(.1):.2f}-"
                    f"{100 * g.rate.quantile(.9):.2f}", "fleets in band": f"{((y >= lo) & (y <= hi)).sum()}/"
                    f"{len(g)}", "one-fleet band %": f"{100 * lo:.3g}-{100 * hi:.3g}",
                    "threshold y0": g.threshold.median()})
    print(f"simulated fleet: {fleets} fleets (seeds {seed}-{seed + fleets - 1}), {NEW} new records x "
          f"{(N - 2) // (WINDOW - 2)} windows each, Sidak over 3 channels ({time.perf_counter() - t0:.0f} s)")
    print(pd.DataFrame(out).to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    print("mean in band: the mean rate over the fleets inside the all-fleets band; exact law in band %: how often an "
          "exact law (expected rate alpha) meets that yardstick with this many fleets (yardstick_reach, 1,500 runs)")


# ------------------------------------------------------------------ 2. CrazyPAD, real flights
CP_ALPHAS, CP_WINDOWS_S = (1e-2, 1e-3), (1.0, 2.0)
CP_TESTS = ("LB-S", "F-S", "M-S", "LB+F+M")
CUT4 = "cut_propeller_M3_4mm_4mm_39mm"


def cp_model(fit_logs: tuple) -> tuple:
    """The choices (``cp.choose``) and the VAR of the normal flights ``fit_logs``, with its held-out residuals."""
    ch = cp.choose(fit_logs)
    flights = [f for f in cp.load_condition(cp.NORMAL, ch.margin) if f.log in fit_logs]
    return ch, cp.fit_model(flights, ch.channels, ch.order)


def cp_judge(ch, model, flights, key: dict, refused: dict) -> list:
    """Rows (``key``, flight, window, alpha, test, flagged, n) of the disjoint windows of ``flights`` through
    ``model`` with the tests of ``CP_TESTS`` calibrated on its held-out residuals; a calibration the library refuses
    (too few records for the alpha) is counted in ``refused`` (window, alpha -> the first line of its reason)."""
    rows = []
    for wsec in CP_WINDOWS_S:
        window = cp.samples(wsec)
        for alpha in CP_ALPHAS:
            try:
                tests = {fam: {"m": t} for fam, t in cp.tests_for(model, CP_TESTS, alpha, window, True).items()}
            except ValueError as err:
                refused.setdefault((wsec, alpha), str(err).split(": a new record")[0])
                continue
            for f in flights:
                n, flagged = dict.fromkeys(CP_TESTS, 0), dict.fromkeys(CP_TESTS, 0)
                for x in f.arrays(ch.channels):
                    fl = cp.flags({"m": model}, tests, x, window, window)
                    for fam in CP_TESTS:
                        flagged[fam] += int(fl[fam][1].sum())
                        n[fam] += int(fl[fam][1].shape[0])
                rows += [{**key, "flight": f.log, "drone": f.drone, "window_s": wsec, "alpha": alpha, "test": fam,
                          "flagged": flagged[fam], "n": n[fam]} for fam in CP_TESTS]
    return rows


def cp_warned(ch, model, flights) -> dict:
    """flight -> coverage warnings (alpha 0.01) of its segments against the model's fitting records."""
    return {f.log: [not coverage(model.results, x, held_out=model.held).covered for x in f.arrays(ch.channels)]
            for f in flights}


def cp_law_warned(ch, model, flights) -> dict:
    """flight -> record-law warnings (``record_coverage``, alpha 0.01) of its segments: LB+F+M at alpha 0.01
    calibrated at 1 s windows (a segment holds 4-5; at 2 s it holds 2, too few for a record's own law of LB and F)."""
    test = cp.tests_for(model, ("LB+F+M",), 1e-2, cp.samples(1.0), True)["LB+F+M"]
    return {f.log: [not record_coverage(test, model.results.residuals(x)).covered for x in f.arrays(ch.channels)]
            for f in flights}


def rate_table(df: pd.DataFrame, by: list) -> pd.DataFrame:
    """Flagged / windows per group, the rate and the two-sided 99.9 % band of alpha for that many windows."""
    out = []
    for key, g in df.groupby(by + ["window_s", "alpha", "test"], sort=False):
        n, x = int(g.n.sum()), int(g.flagged.sum())
        a = key[-2]
        lo, hi = band(n, a)
        out.append({**dict(zip(by + ["window_s", "alpha", "test"], key)), "flagged": f"{x}/{n}",
                    "rate %": 100 * x / n, "band %": f"{100 * lo:.3g}-{100 * hi:.3g}",
                    "in band": "yes" if lo <= x / n <= hi else ("ABOVE" if x / n > hi else "below")})
    return pd.DataFrame(out)


def show(tab: pd.DataFrame) -> None:
    print(tab.to_string(index=False, float_format=lambda v: f"{v:.3g}"))


def crazypad_rows(root=None) -> None:
    t0 = time.perf_counter()
    cp.setup(root)
    logs = cp.normal_logs()
    drones = sorted({log.split("_")[0] for log in logs})
    print(f"\nCrazyPAD ({cp.ROOT}), normal flights {', '.join(logs)}; tests {', '.join(CP_TESTS)} (Sidak over the "
          "channels; LB+F+M = AnyOf of the three, each at its Sidak share), predictive record-level calibration "
          f"(min_windows={cp.MIN_WINDOWS}); disjoint windows; band: two-sided 99.9 % binomial of alpha")
    # a. leave one flight out over both airframes
    rows, warn_a, refused = [], [], {}
    for k, out in enumerate(logs):
        ch, model = cp_model(tuple(log for log in logs if log != out))
        flight = [f for f in cp.load_condition(cp.NORMAL, ch.margin) if f.log == out]
        rows += cp_judge(ch, model, flight, {"fold": k}, refused)
        warn_a += cp_warned(ch, model, flight)[out]
    a = pd.DataFrame(rows)
    print(f"\na. leave one flight out, both airframes ({len(logs)} folds; every baseline holds both airframes)")
    show(rate_table(a, []))
    print("   per airframe of the held-out flight (2 s windows, LB+F+M):")
    show(rate_table(a[(a.window_s == 2.0) & (a.test == "LB+F+M")], ["drone"]))
    print(f"   coverage warnings on the held-out segments: {sum(warn_a)}/{len(warn_a)}")
    for (wsec, alpha), why in refused.items():
        print(f"   refused: {wsec:g} s, alpha {alpha:g}: {why}")
    # b. leave one flight out within an airframe
    rows, warn_b, law_b, refusals = [], {}, {}, set()
    for d in drones:
        own = tuple(log for log in logs if log.startswith(d))
        for out in own:
            ch, model = cp_model(tuple(log for log in own if log != out))
            flight = [f for f in cp.load_condition(cp.NORMAL, ch.margin) if f.log == out]
            refused = {}
            rows += cp_judge(ch, model, flight, {"baseline": f"{d} ({len(own) - 1} flights)"}, refused)
            for (wsec, alpha), why in refused.items():
                refusals.add(f"{d} ({len(own) - 1} flights), {wsec:g} s, alpha {alpha:g}: {why}")
            warn_b[out] = cp_warned(ch, model, flight)[out]
            law_b[out] = cp_law_warned(ch, model, flight)[out]
    print("\nb. leave one flight out within an airframe (same-airframe flights)")
    show(rate_table(pd.DataFrame(rows), ["baseline"]))
    for r in sorted(refusals):
        print(f"   refused (every fold): {r}")
    for what, wb in (("coverage (summaries)", warn_b), ("record_coverage (record law)", law_b)):
        segs = [w for v in wb.values() for w in v]
        print(f"   {what}, alpha 0.01, false warnings on same-airframe flights: {sum(segs)}/{len(segs)} segments, "
              f"{sum(any(v) for v in wb.values())}/{len(wb)} flights ("
              + ", ".join(f"{log}: {v}" for log, v in wb.items()) + ")")
    # c. fit on one airframe, judge the other
    print("\nc. fit on one airframe, judge the other")
    for d in drones:
        fit_logs = tuple(log for log in logs if log.startswith(d))
        ch, model = cp_model(fit_logs)
        others = [f for f in cp.load_condition(cp.NORMAL, ch.margin) if f.drone != d]
        refused = {}
        c = pd.DataFrame(cp_judge(ch, model, others, {"fit": d}, refused))
        print(f"   fit on {d} ({len(fit_logs)} flights, {len(model.held)} segments), judge the other airframe's "
              f"{len(others)} flights:")
        show(rate_table(c, ["fit"]))
        for (wsec, alpha), why in refused.items():
            print(f"   refused: {wsec:g} s, alpha {alpha:g}: {why}")
        warned, law = cp_warned(ch, model, others), cp_law_warned(ch, model, others)
        print("   per judged flight (LB+F+M, alpha 0.01): flagged/windows at 2 s and at 1 s, above the flight's 99.9 % "
              "band?, coverage (summaries) and record_coverage (record law) warned (per segment)")
        for log in dict.fromkeys(c.flight):
            verdicts = []
            for wsec in (2.0, 1.0):
                r = c[(c.window_s == wsec) & (c.alpha == 1e-2) & (c.test == "LB+F+M") & (c.flight == log)].iloc[0]
                up = r.flagged / r.n > band(r.n, 1e-2)[1]
                verdicts.append(f"{wsec:g} s {r.flagged}/{r.n} {'ABOVE' if up else 'in band'}")
            print(f"     {log}: {', '.join(verdicts)}  summaries {warned[log]}  record law {law[log]}")
    # d. detection kept
    ch = cp.choose(logs)
    det, ncal = cp.detection(ch, conditions=(CUT4,), windows=(2.0,))
    print(f"\nd. detection, VAR of all {len(logs)} normal flights ({ch.line()}), {CUT4}, 2 s windows "
          f"(independent calibration windows {ncal[2.0]}):")
    print("\n".join(v for v in cp.detection_verdicts(det) if "LB+F+M" in v))
    print(f"CrazyPAD rows: {time.perf_counter() - t0:.0f} s")


# ------------------------------------------------------------------ 3. hexacopter fleet
HEX_FIT, HEX_NEW, HEX_WINDOW = 10, 40, 200


def hexacopter_rows() -> None:
    from tsfdi.datasets import simulate_hexacopter
    from tsfdi.datasets.hexacopter import FleetSpread, hexacopter_signals

    t0 = time.perf_counter()
    seeds = list(range(3100, 3100 + HEX_FIT + HEX_NEW))
    ds = simulate_hexacopter(len(seeds), duration=30.0, failed_rotor=0, seed=seeds, fleet=FleetSpread(payload=0.3))
    if bool(np.any(ds["lost_control"].values)):
        raise RuntimeError("a hexacopter record lost control")
    sig = hexacopter_signals(ds).isel(time=slice(500, None))
    recs = [sig.isel(record=i).values for i in range(len(seeds))]
    fit, new = recs[:HEX_FIT], recs[HEX_FIT:]
    order = int(tsfdi.select_order(fit, 20, "var", trend="c").selected)
    spec = tsfdi.VAR(fit, order, trend="c")
    res, held = spec.fit(), spec.held_out_residuals()
    n = HEX_WINDOW - order
    rows = []
    for a in ALPHAS:
        lb = tsfdi.LjungBox(lags=20, alpha=a, correction="sidak", threshold="calibrated")
        f = tsfdi.FTest(alpha=a, correction="sidak", threshold="calibrated")
        m = tsfdi.MeanTest(alpha=a, correction="sidak", threshold="calibrated")
        tests = {"LB-S": lb, "F-S": f, "M-S": m, "LB+F+M": tsfdi.AnyOf([lb, f, m])}
        for name, t in tests.items():
            t.calibrate(held, window=HEX_WINDOW)
            ws = [tsfdi.ResidualWindows({"m": res}).fit(x).statistics(t, window=HEX_WINDOW, step=HEX_WINDOW,
                                                                      loglik=False) for x in new]
            rows.append({"test": name, "window_s": HEX_WINDOW / 100, "alpha": a,
                         "flagged": int(sum(w.reject.sum() for w in ws)), "n": int(sum(w.reject.shape[0] for w in ws))})
    payload = ds["payload"].values
    print(f"\nhexacopter fleet: FleetSpread(payload=0.3) and the default airframe spreads, severe turbulence, 30 s "
          f"(first 5 s dropped); VAR({order}) on {HEX_FIT} aircraft (payload {payload[:HEX_FIT].min():.2f}-"
          f"{payload[:HEX_FIT].max():.2f}), {HEX_NEW} others judged (payload {payload[HEX_FIT:].min():.2f}-"
          f"{payload[HEX_FIT:].max():.2f}), {n} residuals per window; predictive calibration; Sidak over "
          f"{sig.sizes['channel']} channels ({time.perf_counter() - t0:.0f} s)")
    show(rate_table(pd.DataFrame(rows), []))


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fleets", type=int, default=40)
    p.add_argument("--seed", type=int, default=2031, help="seed of the first simulated fleet")
    p.add_argument("--predictive-only", action="store_true", help="skip the bootstrap law in the fleet table")
    p.add_argument("--data", default=None, help="CrazyPAD folder (default ../shared/data/crazypad)")
    p.add_argument("--no-crazypad", action="store_true")
    p.add_argument("--no-hexacopter", action="store_true")
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    if args.fleets:
        fleet_table(args.fleets, args.seed, ("predictive",) if args.predictive_only else ("bootstrap", "predictive"))
    if not args.no_crazypad:
        crazypad_rows(args.data)
    if not args.no_hexacopter:
        hexacopter_rows()
    print(f"\nrun time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()

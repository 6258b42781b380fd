"""Coverage benchmark (issue 31, part 2): does a baseline cover a new flight? False-warning rate and power of
``tsfdi.coverage.coverage`` / ``Baselines.covers``. (Not named ``coverage.py``: run as a script, this folder comes
first on ``sys.path``, where that name would shadow the ``coverage`` package numba imports and break every
benchmark.)

Run: ``python benchmarks/baseline_coverage.py [--data PATH] [--reps N]`` (BLAS pinned to one thread; prints its
run time, about 40 min on the 2-core development machine). Two checks side by side, each warning at alpha = 0.01 (the
check's false-warning rate on a record like the fitting records, all summaries together): "summaries"
(``coverage``: trims, residual scales and autocorrelations, two-sided per-summary predictive t) and "record law"
(``record_coverage`` of LB+F+M -- ``tsfdi.AnyOf`` of Ljung-Box, F and mean tests, Sidak over parts and channels,
calibrated on the held-out residuals -- one-sided: the tests' own statistics above the predictive record law their
thresholds rest on; since session 37 with the row of their levels' sum, section 6); and, per section, of the
records whose disjoint windows LB+F+M flags beyond their two-sided 99.9 % binomial band of alpha (where its
calibration does not hold), how many each check warned of. Sections:

1. Simulated fleet (fixed seed): VAR(2) records whose coefficients, channel noise scales and means vary by +-15 %
   between aircraft (factors 1 + N(0, 0.075^2), or uniform on 1 +- 0.15); per repetition a baseline on 5, 10 or
   20 aircraft, judged on 10 new aircraft of the same fleet (false warnings, with the two-sided 99 % binomial band
   of alpha) and on one aircraft of each other fleet: noise x1.5, dynamics x1.4 (both coefficient matrices), means
   offset by 0.5 (power). Target: in band, and >= 90 % for at least one other fleet, at 10 records.
2. CrazyPAD (``../shared/data/crazypad``; the choices of ``benchmarks/crazypad.py``: margin, channels, VAR order,
   made on the normal flights; each log's two airborne segments are fitted and held out together): leave one
   normal flight out within an airframe (its segments judged against the drone's other normal flights:
   false-warning rate with its band); fit on one airframe's normal flights, judge the other's (fires?); the
   payload conditions (add_weight_*, weight_on_string_*) against the same drone's normal flights. The record law
   is LB+F+M calibrated at 1 s windows (a 5 s segment holds 4-5; at 2 s only 2, too few for a record's own law).
3. Hexacopter (``tsfdi.datasets.simulate_hexacopter``, default aircraft, 30 s in severe turbulence, the first 5 s
   dropped; channels roll, pitch, yaw_rate): a VAR on 10 light aircraft (``FleetSpread(payload=0.1)``: payload 0-10 %
   of the gross weight), judged on 60 more of the same spread (false warnings) and on aircraft with a payload of
   20-30 % (``FleetSpread(payload=0.3)``, those above 20 %).
4. The check as the library runs it (``tsfdi.coverage.check_coverage``, what ``detect``, ``Monitor.run`` and
   ``evaluate`` call: the record law of a test calibrated on 3 or more records when the record holds 3 of its
   windows, else the summaries): ``evaluate`` on the shipped hexacopter data (``data/hexacopter.nc``, a VAR on 10
   healthy records per turbulence level, ``calibrate=True``; LB+F+M calibrated per state at 2 s and 5 s windows, and
   Ljung-Box with its theoretical threshold, whose records get the summary check): the warnings on its healthy
   records (false warnings: the shipped healthy records are like the fitting ones); and, with ../shared, the
   CrazyPAD leave-one-flight-out of section 2 through ``check_coverage`` (the wired check per segment).

5. Both checks at once? (``--sections 5``, about 14 min.) Where both apply, would warning when either fires, each
   at its Sidak share ``1 - (1 - alpha)^(1/2)`` of alpha ("union"), warn of more of the records LB+F+M misjudges
   than ``check_coverage``'s rule (the record law alone when it applies)? The simulated fleet of section 1 (seed
   :data:`UNION_SEED`; per baseline 10 aircraft of the same fleet, in domain, and one each of six other fleets,
   out of domain: noise x1.2 and x1.5, dynamics x1.25 and x1.4, means +0.2 and +0.5), and the hexacopter of
   section 3 (baselines of 10 aircraft with payload 0-10 %, seeds from 5000; in domain 15 more of them, out of
   domain those of 60 aircraft with payload 0-30 % whose payload exceeds 20 %). Per rule: false warnings on the
   in-domain records (99 % band of alpha), the share warned of the out-of-domain records whose windows LB+F+M
   flags beyond their 99.9 % band (the records the test misjudges), and of every out-of-domain record.

6. The record law's level-sum row (``--sections 6 [--seed N]``; the seed drawn at run time unless given).
   ``record_coverage`` tests every part and channel (18 rows for LB+F+M on six channels) at its Sidak share against
   a Student t of ``J - 1`` degrees of freedom: with the 6 segments (3 flights) of a CrazyPAD airframe a row must lie
   ~6.7 predictive standard deviations out, so a record whose statistics all sit a few deviations high is not
   warned of. Since session 37 it has one more row, the record's levels summed over the parts and channels (a
   fixed linear combination of the levels the record law takes as normal, so its Student t pivot is exact for
   jointly normal levels). This section measures the check with that row and the rows alone (the check before it)
   on the simulated fleet of section 1 (normal spread; 5 / 10 / 20 records, 200 / 200 / 120 baselines at
   ``--reps 100``; 3 same-fleet records and one of each other fleet per baseline), with the same-fleet warnings'
   standard error over baselines beside the binomial one (records judged by one baseline share it).
   Development seed 9500 (scratch script of the same design): false warnings with the row 0.67 / 1.17 / 1.11 %
   (900 / 600 / 360 records; the rows alone 0.89 / 1.17 / 0.83 %), every row in its 99 % band; records LB+F+M
   flags beyond their band warned 493 / 497 / 342 of 545 / 515 / 352 (rows alone 496 / 499 / 342); means +0.2
   warned 28 / 70 / 89 % (rows alone 22 / 62 / 82 %).
   Measured before and not adopted (session 36): a row of the decision's own window p-values, the record's mean
   ``-ln`` of the test's smallest p-value over its windows against the fitting records' (each through the test
   calibrated without it), one-sided ``t(J - 1)``: 3.0 % false warnings with 5 records (seed 622370679; ABOVE the
   99 % band), 1.3 % with 10. Session 37's development seed 9200 (1,000 records with 5 fitting records): 3.0 %,
   on its log 2.0 %, as the mean normal score of the window's Sidak-adjusted p-value 1.9 %; with the new record
   judged by the same leave-one-out tests 2.1 / 1.7 / 1.5 % (standard error over baselines ~2x the binomial): a
   positive, right-skewed summary whose spread over 5 records is not a t law's. Development seed 9600, one new
   record per baseline (800 independent trials, 5 records; run after section 6's evaluation, information only):
   2.25 / 1.75 / 1.88 % judged by the full test (S / log S / normal score), 1.88 / 1.00 / 1.00 % judged by the
   leave-one-out tests; with 10 records (400 trials) 3.50 / 2.00 / 2.00 % and 3.25 / 1.50 / 2.00 % (in the wide
   band 0-2.5 % but S above it). So log S or the normal score judged that way is not shown liberal, nor shown to
   hold; it would need the fitting records' residuals and ``J`` calibrations per test, which ``record_coverage``
   does not have.

``--sections 4`` runs section 4 alone (about a minute).
"""

import os

os.environ["OPENBLAS_NUM_THREADS"] = "1"
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.coverage import check_coverage, coverage, record_coverage  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import crazypad as cp  # noqa: E402

ALPHA = 0.01
A1 = np.array([[0.5, 0.1, 0.0], [0.0, 0.4, 0.1], [0.1, 0.0, 0.3]])
A2 = -0.2 * np.eye(3)
MU = np.array([1.0, -0.5, 0.2])
SPREAD = 0.15


def fleet(rng, count, n=2000, noise=1.0, gain=1.0, shift=0.0, law="normal"):
    """``count`` aircraft of a fleet, one record each (as in tests/test_coverage.py, plus ``gain`` on the
    dynamics)."""
    def u(*shape):
        if law == "uniform":
            return 1.0 + SPREAD * rng.uniform(-1.0, 1.0, (count, *shape))
        return 1.0 + SPREAD / 2 * rng.standard_normal((count, *shape))

    b1, b2, s, mu = gain * A1 * u(3, 3), gain * A2 * u(3, 3), noise * u(3), MU * u(3) + shift
    e = rng.standard_normal((count, n + 200, 3)) * s[:, None, :]
    y = np.zeros_like(e)
    for t in range(2, n + 200):
        y[:, t] = np.einsum("rij,rj->ri", b1, y[:, t - 1]) + np.einsum("rij,rj->ri", b2, y[:, t - 2]) + e[:, t]
    return list(y[:, 200:] + mu[:, None, :])


def band(n, p=ALPHA):
    """Two-sided 99 % binomial band of the count of ``n`` Bernoulli(p) trials."""
    lo, hi = stats.binom.ppf([0.005, 0.995], n, p)
    return int(lo), int(hi)


def rate(flags, p=ALPHA):
    k, n = int(np.sum(flags)), len(flags)
    lo, hi = band(n, p)
    verdict = "in band" if lo <= k <= hi else ("BELOW band" if k < lo else "ABOVE band")
    return f"{k:4d}/{n:<5d} = {100 * k / n:5.2f} % (99 % band {lo}-{hi}: {verdict})"


def warned(res, held, recs):
    return [not coverage(res, y, held_out=held, alpha=ALPHA).covered for y in recs]


def combined(held, window):
    """LB+F+M (``tsfdi.AnyOf``, Sidak over the parts and the channels: alpha is the decision's rate) calibrated on
    held-out residuals with the predictive record law, for windows of ``window`` signal samples."""
    parts = [tsfdi.LjungBox(lags=20, alpha=ALPHA, threshold="calibrated"),
             tsfdi.FTest(alpha=ALPHA, threshold="calibrated"), tsfdi.MeanTest(alpha=ALPHA, threshold="calibrated")]
    return tsfdi.AnyOf(parts).calibrate(held, window=window)


def law_warned(test, res, recs):
    """The record-law check (``record_coverage`` of the calibrated test) on every record."""
    return [not record_coverage(test, res.residuals(y), alpha=ALPHA).covered for y in recs]


def above_band(test, res, y):
    """Whether the calibrated test flags the record's disjoint windows beyond the two-sided 99.9 % binomial band of
    alpha (the record its calibration does not hold on)."""
    e = np.asarray(res.residuals(y))
    n = test.tests[0].calibration_window_[0]
    flags = np.zeros(e.shape[0] // n, dtype=bool)
    for part in test.tests:
        flags |= (part.window_statistic(e, n, n) > part.threshold_).any(axis=1)
    return flags.sum() > stats.binom.ppf(0.9995, flags.size, ALPHA)


# ------------------------------------------------------------------ 1. simulated fleet
def simulated(reps):
    print(f"1. Simulated fleet, VAR(2) with +-15 % aircraft-to-aircraft spread, {reps} baselines per row, "
          f"alpha {ALPHA}; two checks: 'summaries' = coverage() (trims, residual scales and autocorrelations, "
          "two-sided), 'record law' = record_coverage() of LB+F+M calibrated on the held-out residuals (200-sample "
          "windows; one-sided: the tests' statistics above the predictive record law)")
    ok = True
    kinds = {"same fleet": {}, "noise x1.5": {"noise": 1.5}, "dynamics x1.4": {"gain": 1.4},
             "means +0.5": {"shift": 0.5}}
    for law in ("normal", "uniform"):
        for nfit in (5, 10, 20):
            rng = np.random.default_rng([31, nfit, law == "uniform"])
            out = {k: {"summaries": [], "record law": [], "above": []} for k in kinds}
            for _ in range(reps):
                res = tsfdi.VAR(fleet(rng, nfit, law=law), 2, trend="c").fit()
                held = res.model.held_out_residuals()
                test = combined(held, 200)
                for kind, kw in kinds.items():
                    recs = fleet(rng, 10 if kind == "same fleet" else 1, law=law, **kw)
                    out[kind]["summaries"] += warned(res, held, recs)
                    out[kind]["record law"] += law_warned(test, res, recs)
                    out[kind]["above"] += [above_band(test, res, y) for y in recs]
            print(f"   {law:7s} spread, {nfit:2d} records:")
            report(out, kinds, ("summaries", "record law"))
            if law == "normal" and nfit == 10:
                same = out["same fleet"]["summaries"]
                lo, hi = band(len(same))
                ok &= lo <= sum(same) <= hi and max(np.mean(out[k]["summaries"]) for k in kinds
                                                    if k != "same fleet") >= 0.9
    return ok


# ------------------------------------------------------------------ 2. CrazyPAD
CHECKS = ("summaries", "record law")


def judge(model, flights, channels):
    """Per check, per flight: one warning flag per airborne segment. The record law is that of LB+F+M (Sidak over
    the parts and channels, the choices of crazypad.py) calibrated at 1 s windows (a 5 s segment holds 4-5 of them;
    at 2 s it holds 2, too few for a record's own law of Ljung-Box and F, which are then pooled without one)."""
    test = cp.tests_for(model, ("LB+F+M",), ALPHA, cp.samples(1.0), True)["LB+F+M"]
    return {"summaries": {f.log: warned(model.results, model.held, f.arrays(channels)) for f in flights},
            "record law": {f.log: law_warned(test, model.results, f.arrays(channels)) for f in flights}}


def tally(flags):
    segs = [x for v in flags.values() for x in v]
    return f"warned on {sum(any(v) for v in flags.values())}/{len(flags)} flights, {sum(segs)}/{len(segs)} segments"


def crazypad(root):
    cp.setup(root)
    choice = cp.choose(cp.normal_logs())
    print(f"2. CrazyPAD ({cp.ROOT}); choices on the normal flights: {choice.line()}")
    normal = cp.load_condition(cp.NORMAL, choice.margin)
    drones = sorted({f.drone for f in normal})
    by_drone = {d: [f for f in normal if f.drone == d] for d in drones}
    seg_flags, flight_flags = {c: [] for c in CHECKS}, {c: [] for c in CHECKS}
    for d, fl in by_drone.items():
        for i, f in enumerate(fl):
            model = cp.fit_model([g for j, g in enumerate(fl) if j != i], choice.channels, choice.order)
            flags = judge(model, [f], choice.channels)
            for c in CHECKS:
                seg_flags[c] += flags[c][f.log]
                flight_flags[c].append(any(flags[c][f.log]))
            print(f"   {d} leave {f.log} out: baseline of {len(fl) - 1} flights ({len(model.held)} segments); "
                  "segments warned " + ", ".join(f"{c} {flags[c][f.log]}" for c in CHECKS))
    p2 = 1 - (1 - ALPHA) ** 2
    for c in CHECKS:
        print(f"   {c}: same airframe, leave one flight out: segments {rate(seg_flags[c])}; flights (either segment "
              f"warns, nominal {100 * p2:.2f} %): {rate(flight_flags[c], p2)}")
    print("   (few trials: a 99 % band this wide cannot tell a rate of 0 % from one of several per cent)")
    full = {d: cp.fit_model(fl, choice.channels, choice.order) for d, fl in by_drone.items()}
    for d in drones:
        for o in drones:
            if o == d:
                continue
            flags = judge(full[d], by_drone[o], choice.channels)
            print(f"   fit on {d} ({len(by_drone[d])} flights), judge {o}'s normal flights: "
                  + "; ".join(f"{c} {tally(flags[c])} {flags[c]}" for c in CHECKS))
    payload = [c for c in sorted(set(pd.read_csv(cp.ROOT / "flights.csv").condition))
               if c.startswith(("add_weight", "weight_on_string"))]
    for cond in payload:
        for d in drones:
            fl = [f for f in cp.load_condition(cond, choice.margin) if f.drone == d]
            if not fl:
                continue
            flags = judge(full[d], fl, choice.channels)
            print(f"   payload {cond} ({d}), against {d}'s normal flights: "
                  + "; ".join(f"{c} {tally(flags[c])}" for c in CHECKS))


# ------------------------------------------------------------------ 3. hexacopter
def hexacopter():
    from tsfdi.datasets import simulate_hexacopter
    from tsfdi.datasets.hexacopter import FleetSpread, hexacopter_signals

    def records(payload, seeds):
        ds = simulate_hexacopter(len(seeds), duration=30.0, failed_rotor=0, seed=list(seeds),
                                 fleet=FleetSpread(payload=payload))
        sig = hexacopter_signals(ds).isel(time=slice(500, None))
        return [sig.isel(record=i) for i in range(len(seeds))], ds["payload"].values

    light, p_light = records(0.1, range(1000, 1070))
    heavy, p_heavy = records(0.3, range(2000, 2060))
    heavy = [y for y, p in zip(heavy, p_heavy) if p > 0.2]
    fit, new = light[:10], light[10:]
    order = int(tsfdi.select_order(fit, 20, "var", trend="c").selected)
    spec = tsfdi.VAR(fit, order, trend="c")
    res, held = spec.fit(), spec.held_out_residuals()
    print(f"3. Hexacopter, VAR({order}) on 10 aircraft with payload 0-10 % (channels "
          f"{list(map(str, fit[0].channel.values))})")
    test = combined(held, 200)
    print(f"   same spread (payload {p_light[10:].min():.2f}-{p_light[10:].max():.2f}): summaries "
          f"{rate(warned(res, held, new))}; record law {rate(law_warned(test, res, new))}")
    w, lw = warned(res, held, heavy), law_warned(test, res, heavy)
    up = [above_band(test, res, y) for y in heavy]
    print(f"   heavier (payload 20-30 %): summaries warned {sum(w)}/{len(w)} = {100 * np.mean(w):.1f} %; record law "
          f"warned {sum(lw)}/{len(lw)} = {100 * np.mean(lw):.1f} %; LB+F+M (2 s windows) flags {sum(up)} of them "
          f"beyond their 99.9 % band, of which the summaries warned {sum(a and b for a, b in zip(up, w))} and the "
          f"record law {sum(a and b for a, b in zip(up, lw))}")
    tables = [coverage(res, y, held_out=held, alpha=ALPHA).table for y in heavy]
    t = sum(tab["t"] for tab in tables) / len(tables)
    crit = float((tables[0]["t"].abs() / tables[0]["excess"]).iloc[0])          # the interval's |t| limit
    top = t.abs().sort_values(ascending=False).index[:3]
    print("   heavier: mean predictive t of the summaries that move most: "
          + ", ".join(f"{s}[{c}] {t[(s, c)]:+.2f}" for s, c in top) + f" (a warning needs |t| > {crit:.2f})")


# ------------------------------------------------------------------ 4. the check as the library runs it
def shipped():
    """False warnings of evaluate's coverage check on the shipped healthy records."""
    import warnings

    from tsfdi.datasets import load_hexacopter
    from tsfdi.datasets.hexacopter import hexacopter_signals
    from tsfdi.exceptions import CoverageWarning, TsfdiWarning

    sig = hexacopter_signals(load_hexacopter(Path(__file__).resolve().parents[1] / "data" / "hexacopter.nc"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TsfdiWarning)
        bases = {lvl: tsfdi.fit_baselines(sig, fit_turbulence=lvl, duration=None, models=["var"], fit_records=10,
                                          order=20, calibrate=True) for lvl in ("light", "moderate", "severe")}
        lbfm = tsfdi.AnyOf([tsfdi.LjungBox(lags=20, alpha=ALPHA, threshold="calibrated"),
                            tsfdi.FTest(alpha=ALPHA, threshold="calibrated"),
                            tsfdi.MeanTest(alpha=ALPHA, threshold="calibrated")])
        tests = {"LB+F+M": lbfm, "LjungBox": tsfdi.LjungBox(lags=20, alpha=ALPHA)}
        warnings.simplefilter("ignore", CoverageWarning)
        ev = tsfdi.evaluate(sig, bases, models=("var",), tests=tests, windows=("2s", "5s"), progress=False)
    healthy = ev.records.loc[ev.records["evaluated"] & (ev.records["state"] == "healthy"), "record"]
    cov = ev.coverage[ev.coverage["record"].isin(healthy)]
    print(f"4. The wired check (check_coverage) in evaluate, shipped hexacopter data, VAR(20) on 10 healthy records "
          f"per turbulence level; {len(healthy)} healthy records evaluated (their whole record from settle = 10 s):")
    for (meth, w), part in cov.groupby(["method", "window"]):
        kind = "record law" if meth == "LB+F+M" else "summaries"
        print(f"   {meth:8s} {w:g} s windows ({kind}): false warnings {rate(~part['covered'].to_numpy(bool))}")
    per = ev.records.set_index("record").loc[healthy, "covered"]
    print(f"   records warned by any of the {cov.groupby('record').size().max()} checks: {int((~per).sum())}/"
          f"{len(per)}")


def wired_crazypad(root):
    """The CrazyPAD leave-one-flight-out of section 2 through check_coverage: LB+F+M calibrated at 1 s (record law)
    and Ljung-Box with its theoretical threshold (the summaries)."""
    cp.setup(root)
    choice = cp.choose(cp.normal_logs())
    normal = cp.load_condition(cp.NORMAL, choice.margin)
    flags = {"record law": [], "summaries": []}
    none = 0
    for d in sorted({f.drone for f in normal}):
        fl = [f for f in normal if f.drone == d]
        for i, f in enumerate(fl):
            model = cp.fit_model([g for j, g in enumerate(fl) if j != i], choice.channels, choice.order)
            law = cp.tests_for(model, ("LB+F+M",), ALPHA, cp.samples(1.0), True)["LB+F+M"]
            for name, test in (("record law", law), ("summaries", tsfdi.LjungBox(lags=20, alpha=ALPHA))):
                for y in f.arrays(choice.channels):
                    cov = check_coverage(test, model.results, y, held_out=model.held)
                    none += cov is None
                    flags[name].append(cov is not None and not cov.covered)
    print(f"   CrazyPAD same airframe, leave one flight out, per segment through check_coverage ({none} segments "
          "not checkable): " + "; ".join(f"{k} {rate(v)}" for k, v in flags.items()))


# ------------------------------------------------------------------ 5. both checks at once?
UNION_SEED = 3401
#: (fitting records, spread law, baselines) of the simulated-fleet rows
UNION_ROWS = ((5, "normal", 200), (10, "normal", 200), (20, "normal", 100), (5, "uniform", 100))
OTHER_FLEETS = {"noise x1.2": {"noise": 1.2}, "dynamics x1.25": {"gain": 1.25}, "means +0.2": {"shift": 0.2},
                "noise x1.5": {"noise": 1.5}, "dynamics x1.4": {"gain": 1.4}, "means +0.5": {"shift": 0.5}}
#: hexacopter baselines (each its own 25 light and 60 drawn aircraft)
HEX_BASELINES = 6


def pvalues(test, res, held, y, kind):
    """The family p-values of both checks on record ``y`` (a Coverage's ``pvalue`` does not depend on its
    ``alpha``), and whether LB+F+M flags its windows beyond their band."""
    return {"kind": kind, "summaries": coverage(res, y, held_out=held).pvalue,
            "record law": record_coverage(test, res.residuals(y)).pvalue, "above": above_band(test, res, y)}


def union_table(rows):
    d = pd.DataFrame(rows)
    share = 1 - (1 - ALPHA) ** 0.5
    rules = {"summaries": d["summaries"] < ALPHA, "record law (the rule)": d["record law"] < ALPHA,
             "union (Sidak halves)": np.minimum(d["summaries"], d["record law"]) < share}
    same, flagged = d["kind"] == "same", (d["kind"] != "same") & d["above"]
    for name, w in rules.items():
        kinds = ", ".join(f"{k} {int(w[flagged & (d['kind'] == k)].sum())}/{int((flagged & (d['kind'] == k)).sum())}"
                          for k in dict.fromkeys(d.loc[d["kind"] != "same", "kind"]))
        print(f"     {name:22s}: false warnings {rate(w[same])}; out of domain and flagged beyond band: warned "
              f"{int(w[flagged].sum())}/{int(flagged.sum())} = {100 * w[flagged].mean():.1f} % ({kinds}); every "
              f"out-of-domain record: warned {int(w[~same].sum())}/{int((~same).sum())}")


def union():
    print(f"5. Both checks at once (each at its Sidak share) or the record law alone? alpha {ALPHA}, seed "
          f"{UNION_SEED}; 'flagged': out-of-domain records whose disjoint 200-sample windows LB+F+M flags beyond "
          "their 99.9 % band")
    for nfit, law, reps in UNION_ROWS:
        rng = np.random.default_rng([UNION_SEED, nfit, law == "uniform"])
        rows = []
        for _ in range(reps):
            res = tsfdi.VAR(fleet(rng, nfit, law=law), 2, trend="c").fit()
            held = res.model.held_out_residuals()
            test = combined(held, 200)
            for kind, kw in {"same": {}, **OTHER_FLEETS}.items():
                rows += [pvalues(test, res, held, y, kind) for y in fleet(rng, 10 if kind == "same" else 1, law=law,
                                                                            **kw)]
        print(f"   simulated fleet, {law} spread, {nfit} records, {reps} baselines:")
        union_table(rows)
    from tsfdi.datasets import simulate_hexacopter
    from tsfdi.datasets.hexacopter import FleetSpread, hexacopter_signals

    def records(payload, seeds):
        ds = simulate_hexacopter(len(seeds), duration=30.0, failed_rotor=0, seed=list(seeds),
                                 fleet=FleetSpread(payload=payload))
        sig = hexacopter_signals(ds).isel(time=slice(500, None))
        return [sig.isel(record=i).values for i in range(len(seeds))], ds["payload"].values

    rows, order = [], None
    for b in range(HEX_BASELINES):
        first = 5000 + 1000 * b
        light, _ = records(0.1, range(first, first + 25))
        heavy, payload = records(0.3, range(first + 500, first + 560))
        if order is None:
            order = int(tsfdi.select_order(light[:10], 20, "var", trend="c").selected)
        spec = tsfdi.VAR(light[:10], order, trend="c")
        res, held = spec.fit(), spec.held_out_residuals()
        test = combined(held, 200)
        rows += [pvalues(test, res, held, y, "same") for y in light[10:]]
        rows += [pvalues(test, res, held, y, "payload 20-30 %") for y, p in zip(heavy, payload) if p > 0.2]
    print(f"   hexacopter, {HEX_BASELINES} baselines of VAR({order}) on 10 aircraft with payload 0-10 %:")
    union_table(rows)


# ------------------------------------------------------------------ 6. the level-sum row
LEVEL_ROWS = ((5, 200), (10, 200), (20, 120))        # (fitting records, baselines) at --reps 100 (scaled by --reps)


def level_rows(reps, seed=None):
    """False warnings and power of ``record_coverage`` with and without its level-sum row, 5 / 10 / 20 records."""
    from tsfdi.coverage import LEVEL_SUM
    from tsfdi.study import evaluation_seed

    drawn = seed is None
    seed = evaluation_seed() if drawn else seed
    print(f"6. The record law's level-sum row (record_coverage: the rows per part and channel and the sum of the "
          f"levels, each at its Sidak share), against the rows alone (the check before it); alpha {ALPHA}, simulated "
          f"fleet, normal spread; per baseline 3 records of the same fleet and one of each other fleet; seed {seed} "
          f"({'drawn at run time' if drawn else 'given'})")
    kinds = {"same fleet": {}, **OTHER_FLEETS}
    for nfit, base in LEVEL_ROWS:
        rng = np.random.default_rng([seed, nfit])
        out = {k: {"record law": [], "rows alone": [], "above": [], "baseline": []} for k in kinds}
        for b in range(max(1, round(base * reps / 100))):
            res = tsfdi.VAR(fleet(rng, nfit), 2, trend="c").fit()
            test = combined(res.model.held_out_residuals(), 200)
            for kind, kw in kinds.items():
                for y in fleet(rng, 3 if kind == "same fleet" else 1, **kw):
                    cov = record_coverage(test, res.residuals(y), alpha=ALPHA)
                    rows = cov.table.drop(index=LEVEL_SUM, level="summary")["pvalue"]
                    out[kind]["record law"].append(not cov.covered)
                    out[kind]["rows alone"].append(bool(-np.expm1(len(rows) * np.log1p(-rows.min())) < ALPHA))
                    out[kind]["above"].append(above_band(test, res, y))
                    out[kind]["baseline"].append(b)
        print(f"   {nfit} records, {b + 1} baselines:")
        report(out, kinds, ("record law", "rows alone"))
        same = out["same fleet"]
        for c in ("record law", "rows alone"):
            w = pd.Series(same[c], dtype=float).groupby(same["baseline"]).mean()
            n = len(same[c])
            print(f"     {c}: same-fleet warnings' standard error over baselines / binomial "
                  f"{w.std(ddof=1) / np.sqrt(w.size) / np.sqrt(ALPHA * (1 - ALPHA) / n):.2f}")


def report(out, kinds, checks):
    """Print, per check, its false-warning rate on the same fleet and how often it warned of other fleets' records,
    then how many records LB+F+M flags beyond their 99.9 % band and how many of those each check warned of."""
    for check in checks:
        power = ", ".join(f"{k} {100 * np.mean(out[k][check]):5.1f} %" for k in kinds if k != "same fleet")
        print(f"     {check:10s}: same fleet {rate(out['same fleet'][check])}; other fleets warned: {power}")
    flagged = {c: [w for k in kinds for w, a in zip(out[k][c], out[k]["above"]) if a] for c in checks}
    print(f"     records whose windows LB+F+M flags beyond their 99.9 % band: {len(flagged[checks[0]])}; warned: "
          + ", ".join(f"{c} {sum(v)}/{len(v)}" for c, v in flagged.items()))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=None, help="CrazyPAD folder (default ../shared/data/crazypad)")
    ap.add_argument("--reps", type=int, default=100, help="baselines per simulated-fleet row (default 100)")
    ap.add_argument("--sections", default="12345", help="the sections to run (default 12345; 6: the level-sum row)")
    ap.add_argument("--seed", type=int, default=None,
                    help="section 6's seed (default: drawn at run time, printed; give one for development runs)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    if "1" in args.sections:
        ok = simulated(args.reps)
        print(f"   target (normal spread, 10 records: in band, >= 90 % on another fleet): {'PASS' if ok else 'FAIL'}")
    if "2" in args.sections:
        crazypad(args.data)
    if "3" in args.sections:
        hexacopter()
    if "4" in args.sections:
        shipped()
        wired_crazypad(args.data)
    if "5" in args.sections:
        union()
    if "6" in args.sections:
        level_rows(args.reps, args.seed)
    print(f"run time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()

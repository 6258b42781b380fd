"""Generate docs/results.md and docs/figures/study/ from the shipped hexacopter data (issue 6).

Every number in docs/results.md is computed here; nothing is typed by hand. Run from the repository root:

    python docs/scripts/study.py

Steps: paper 003's protocol like for like beside its Table 4; tsfdi's calibrated method with one set of models for
all levels, on the shipped data and on a fleet generated on demand; then baselines per turbulence level (first 10
valid records of each state and level pooled, post-transient part, VAR(20) / AR(20): Table 2 analogue), then evaluation of every other record with 1 s sliding windows of 5 / 10 / 20 s for the
scalar AR models (roll, pitch, yaw rate) and the VAR, residual variance (F test) and whiteness (Ljung-Box) methods,
the paper's decision rule and two rules resolving ambiguous windows (Table 4 analogues, rates, detection), then the
Monitor end to end on every evaluated fault record; then the VAR / AR whiteness study again with thresholds
calibrated per model on leave-one-record-out residuals of its fitting records (paper 002 Fig. 2), side by side;
then the healthy-model detection at four per-channel alphas, and with the Ljung-Box test's exact finite-sample
null (simulated white noise) at three; then the VAR + whiteness study once more on the
design regenerated with each choice of the shipped aircraft undone (full speed, rotor drag, weathervane moment,
one-way rotors: the regular aircraft).
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.baselines import insample_q  # noqa: E402
from tsfdi.detection import EmpiricalThreshold  # noqa: E402
from tsfdi.datasets import (REGULAR_HEXACOPTER, FleetSpread, HexacopterParameters, load_hexacopter,  # noqa: E402
                            make_hexacopter_dataset)
from tsfdi.datasets.hexacopter import SHIPPED_VARIABLES, SIGNAL_CHANNELS, encode_for_file  # noqa: E402
from tsfdi.datasets._shipped import REGENERATE_COMMAND  # noqa: E402
from tsfdi.datasets.hexacopter import hexacopter_signals  # noqa: E402
from tsfdi.study import (PAPER_ALPHA, demo_report, hexacopter_study, markdown_figures, markdown_table,  # noqa: E402
                         paper_tests, write_figures)
from tsfdi.exceptions import UnstableModelWarning  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
#: the paper's whiteness test of the VAR (Ljung-Box, 20 lags, alpha 1e-3 per channel, Table 3)
WHITENESS = {"whiteness": tsfdi.LjungBox(lags=20, alpha=1e-3)}
FIGS = ROOT / "docs" / "figures" / "study"


def evaluated(sig, level, baselines):
    """(position, state) of the records of ``level`` that :func:`tsfdi.evaluate` evaluates with ``baselines``:
    valid and not fitting records."""
    for i in range(sig.sizes["record"]):
        if (str(sig["turbulence"].values[i]) == level and not bool(sig["lost_control"].values[i])
                and sig["record"].values[i] not in baselines.fit_records):
            yield i, str(sig["state"].values[i])


def monitor_table(bases, data) -> pd.DataFrame:
    """Monitor (VAR, whiteness, 5 s windows, likelihood rule) on every evaluated fault record."""
    sig = hexacopter_signals(data)
    rows = []
    for lvl, b in bases.items():
        mon = b.monitor("var", window="5s", rule="likelihood")
        for i, st in evaluated(sig, lvl, b):
            if st == b.healthy:
                continue
            res = mon.run(sig.isel(record=i).values)
            ident = res.windows[res.windows["status"] != ""]
            rows.append({"turbulence": lvl, "state": st,
                         "delay": np.nan if res.detection_time is None else res.detection_time - 10.0,
                         "steady_after_failure": np.nan if res.steady_time is None else res.steady_time - 10.0,
                         "identified_windows": len(ident),
                         "correct_windows": float((ident["label"] == st).mean() * 100) if len(ident) else np.nan,
                         "majority_correct": res.label == st})
    df = pd.DataFrame(rows)
    return df.groupby("state").agg(records=("delay", "size"), detection_delay_median_s=("delay", "median"),
                                   steady_after_failure_median_s=("steady_after_failure", "median"),
                                   correct_windows_pct=("correct_windows", "mean"),
                                   records_majority_correct_pct=("majority_correct", lambda s: 100 * s.mean()))


#: Paper 003's Table 4 as published: percent of the 20 s windows of each rotor failure accepted as rotor 1 / 2 / 6,
#: all turbulence levels, 20 datasets each (model, method) -> {true rotor: "r1/r2/r6"}
PAPER_TABLE4 = {
    ("roll", "variance"): {"rotor1": "97.54/100/99.36", "rotor2": "0/100/100", "rotor6": "0/100/100"},
    ("roll", "whiteness"): {"rotor1": "98.78/0.23/1.19", "rotor2": "0/97.06/99.20", "rotor6": "0/97.38/97.93"},
    ("pitch", "variance"): {"rotor1": "100/0/0", "rotor2": "100/100/100", "rotor6": "100/100/100"},
    ("pitch", "whiteness"): {"rotor1": "87.70/7.38/10.95", "rotor2": "56.90/98.25/98.96",
                             "rotor6": "86.18/98.57/98.89"},
    ("yaw_rate", "variance"): {"rotor1": "100/14.76/0.32", "rotor2": "100/94.52/59.04", "rotor6": "100/99.28/95.95"},
    ("yaw_rate", "whiteness"): {"rotor1": "77.77/46.02/42.85", "rotor2": "58.77/49.04/45.47",
                                "rotor6": "88.09/60.79/56.58"},
    ("var", "variance"): {"rotor1": "100/0/0", "rotor2": "0/21.75/0", "rotor6": "0/31.26/33.49"},
    ("var", "whiteness"): {"rotor1": "100/0/0", "rotor2": "0/99.62/0.02", "rotor6": "0/0/99.68"},
}


def paper_like_for_like(data) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """Paper 003's protocol on the shipped data: one 20 s severe-turbulence record per state fits the models
    (the first valid one, 10 s after the failure), order by BIC, Ljung-Box with 30 lags (scalar AR, the paper's
    pitch example) and 50 lags (VAR) at alpha = 1e-3, the F test at Table 3's alphas, 20 s windows 1 s apart on
    every other valid record of every level. Returns the Table 4 analogue beside the published Table 4, the
    detection rates of the healthy model, and the BIC orders."""
    sig = hexacopter_signals(data)
    names = [*SIGNAL_CHANNELS, "var"]
    b = tsfdi.fit_baselines(sig, fit_records="first", fit_turbulence="severe", duration=20.0, settle=10.0,
                            order="bic", models=names, max_lags=30, var_max_lags=30)
    tests = {"variance": {m: tsfdi.FTest(alpha=PAPER_ALPHA[("variance", "yaw" if m.startswith("yaw") else m)])
                          for m in names},
             "whiteness": {m: tsfdi.LjungBox(lags=50 if m == "var" else 30, alpha=1e-3) for m in names}}
    ev = tsfdi.evaluate(sig, b, models=names, tests=tests, windows=("20s",), rules=("paper",), progress=False)
    ours = ev.table4(20.0, "paper")
    rows = []
    for (model, method), row in ours.iterrows():
        for true, cell in row.items():
            rows.append({"model": model, "method": method, "true": true, "tsfdi (shipped data)": cell,
                         "paper Table 4": PAPER_TABLE4[(model, method)][true]})
    tab = pd.DataFrame(rows).set_index(["model", "method", "true"])
    orders = {m: sorted({int(r.lags) for r in per.values()}) for m, per in b.models.items()}
    return tab, ev.detection_rates(), orders


def calibrated_one_set(data) -> tuple[pd.DataFrame, list[str], dict]:
    """tsfdi's calibrated method: one set of models for all turbulence levels (the level is not known in
    flight), fitted on the first 10 valid records of each state and level pooled, VAR order by BIC on those
    records, Ljung-Box with 20 lags at alpha = 1e-3 per channel with thresholds calibrated per model on its
    held-out fitting records (leave one record out), beside the chi-square thresholds; 5 / 10 / 20 s windows on
    every other record. Returns the correct-unique rates, the detection lines and the VAR orders."""
    parts, lines, orders = [], [], {}
    for thr in ("theoretical", "calibrated"):
        bases, ev = hexacopter_study(data, models=["var"], pool="all", order="bic", rules=("paper", "likelihood"),
                                     tests={"whiteness": tsfdi.LjungBox(lags=20, alpha=1e-3, threshold=thr)},
                                     progress=False)
        r = ev.rates()["correct"].xs(("var", "whiteness"), level=("model", "method")).unstack("true")
        r.insert(0, "thresholds", thr)
        parts.append(r)
        one = next(iter(bases.values()))
        orders = {st: int(one.models["var"][st].lags) for st in (one.healthy,) + one.faults}
        d = ev.detection_rates()
        for w in sorted(d.index.get_level_values("window").unique()):
            lines.append(detection_line(f"one set of models, {thr} thresholds, {w:g} s",
                                        d.loc[("var", "whiteness", w)]))
    tab = pd.concat(parts).reset_index().set_index(["thresholds", "window", "rule"]).round(2)
    return tab, lines, orders


def pct(g: pd.DataFrame, mask: pd.Series) -> float:
    """Percent of the windows counted in ``g`` (rows of ``Evaluation.identification_counts`` / ``detection_counts``)
    for which ``mask`` holds."""
    return float(g.loc[mask, "windows"].sum() / g["windows"].sum() * 100.0)


def correct_pct(g: pd.DataFrame, state: str, rule: str = "paper") -> float:
    """Percent of the windows of true failure ``state`` in ``g`` labelled ``state`` by ``rule``."""
    g = g[g["state"] == state]
    return pct(g, g[f"label_{rule}"] == state)


def level_lines(ev) -> list[str]:
    """Per turbulence level: VAR + whiteness paper rule at 20 s and the best improved rule at 5 s."""
    df = ev.identification_counts
    df = df[df["model"] == "var"]
    lines = []
    for lvl in dict.fromkeys(df["turbulence"]):
        g = df[df["turbulence"] == lvl]

        def correct(meth, w, rule):
            h = g[(g["method"] == meth) & (g["window"] == w)]
            return {f: correct_pct(h, f, rule) for f in ev.faults}

        p20 = correct("whiteness", 20.0, "paper")
        best = max(((rule, meth, correct(meth, 5.0, rule)) for rule in ev.rules[1:] for meth in ("whiteness", "variance")),
                   key=lambda x: min(x[2].values()))
        lines.append(f"- **{lvl}**: VAR + whiteness, paper rule, 20 s: "
                     f"{', '.join(f'{k} {v:.2f}%' for k, v in p20.items())} "
                     f"(>= 99.6%: **{'met' if min(p20.values()) >= 99.6 else 'not met'}**); best improved rule "
                     f"at 5 s ({best[0]}, {best[1]}): {', '.join(f'{k} {v:.2f}%' for k, v in best[2].items())} "
                     f"(>= 95%: **{'met' if min(best[2].values()) >= 95 else 'not met'}**).")
    return lines


def variants(data) -> pd.DataFrame:
    """How the baseline choices change VAR identification (whiteness method): fitting records, pooling, order."""
    rows = []
    for n, pool, order in [(1, "level", "bic"), (5, "level", "bic"), (10, "level", "bic"), (10, "level", 20),
                           (10, "all", 20), (10, "level", "rss_sss")]:
        bases, ev = hexacopter_study(data, models=["var"], tests=WHITENESS, windows=("5s", "20s"),
                                     rules=("paper", "likelihood"), fit_records=n, pool=pool, order=order,
                                     progress=False)
        r = ev.rates()["correct"]
        orders = sorted({int(b.models["var"][s].lags) for b in bases.values() for s in (b.healthy,) + b.faults})
        row = {"fit_records": n, "pool": pool, "order": str(order),
               "var_orders": f"{orders[0]}-{orders[-1]}" if len(orders) > 1 else str(orders[0])}
        for lvl in ("light", "moderate", "severe"):
            sub = ev.identification_counts
            sub = sub[(sub["turbulence"] == lvl) & (sub["window"] == 20.0)]
            row[f"paper 20 s {lvl} (min over rotors)"] = min(correct_pct(sub, f) for f in ev.faults)
        row["likelihood 5 s all (min)"] = r.xs(("var", "whiteness", 5.0, "likelihood"),
                                               level=("model", "method", "window", "rule")).min()
        d = ev.detection_rates().loc[("var", "whiteness", 20.0)]
        row["false alarm 20 s"] = d["false_alarm"]
        rows.append(row)
    return pd.DataFrame(rows).round(2)


def alpha_table(bases, data) -> pd.DataFrame:
    """Detection (VAR + whiteness, healthy model) on the healthy evaluation records at several per-channel alphas:
    false-alarm rate of all windows and of the disjoint ones against the expectation ``1 - (1 - alpha)^3``."""
    sig = hexacopter_signals(data)
    rows = []
    for a in (1e-4, 1e-3, 1e-2, 5e-2):
        ev = tsfdi.evaluate(sig, bases, models=["var"], tests={"whiteness": tsfdi.LjungBox(lags=20, alpha=a)},
                            rules=["paper"], progress=False)
        for w, r in ev.detection_rates().loc[("var", "whiteness")].iterrows():
            n, x = int(r["disjoint_windows"]), int(r["disjoint_alarms"])
            rows.append({"alpha per channel": a, "window (s)": w,
                         "expected false alarms (%)": round(r["expected_false_alarm"], 3),
                         "expected disjoint": round(n * r["expected_false_alarm"] / 100.0, 2),
                         "false alarms, all windows (%)": round(r["false_alarm"], 2),
                         "disjoint windows flagged": f"{x} of {n}",
                         "in the 99 % band": bool(r["false_alarm_in_band"]),
                         "two-sided binomial p": float(f"{r['false_alarm_pvalue']:.2g}")})
    return pd.DataFrame(rows).set_index(["alpha per channel", "window (s)"])


def two_sided_p(x: int, n: int, p0: float) -> float:
    """Two-sided binomial p-value of ``x`` events in ``n`` independent trials at rate ``p0``."""
    return min(1.0, 2.0 * min(stats.binom.cdf(x, n, p0), stats.binom.sf(x - 1, n, p0)))


#: Simulated white-noise windows per window length for the Ljung-Box null (:func:`white_noise_null`)
NULL_DRAWS = 200_000


def white_noise_null(bases, data, alphas=(1e-3, 1e-2, 5e-2), draws=None, seed=2026) -> pd.DataFrame:
    """The healthy VAR's Ljung-Box detection against the test's exact finite-sample null.

    The null distribution of ``Q`` for ``n`` iid Gaussian residuals and 20 lags is simulated (``draws`` windows
    per window length, fixed seed). It gives the size of the chi-square test on white noise and the exact
    critical value; the healthy model then detects on the healthy evaluation records with that critical value
    (the threshold of a :class:`tsfdi.LjungBox` calibrated on the simulated statistics)."""
    from tsfdi.detection import LjungBox, ljungbox_windows

    draws = NULL_DRAWS if draws is None else draws
    sig = hexacopter_signals(data)
    rng = np.random.default_rng(seed)
    first = next(iter(bases.values()))
    fs, lags = first.fs, 20
    step = int(round(fs))
    rows = []
    for w in (5.0, 10.0, 20.0):
        W = int(round(w * fs))
        n = W - int(first.models["var"][first.healthy].lags)
        null = ljungbox_windows(rng.standard_normal((n * draws, 1)), lags, n, n).ravel()
        # the healthy model's Q on every healthy evaluation record, computed once for all alphas
        q = [tsfdi.ResidualWindows({"h": b.models["var"][b.healthy]}).fit(sig.isel(record=i).values).statistics(
                 LjungBox(lags), window=W, step=step, loglik=False).statistic[:, 0]
             for lvl, b in bases.items() for i, st in evaluated(sig, lvl, b) if st == b.healthy]
        for a in alphas:
            crit = float(stats.chi2.ppf(1.0 - a, lags))
            test = LjungBox(lags=lags, alpha=a, threshold="empirical").calibrate(
                statistic=np.repeat(null[:, None], len(first.channels), axis=1))
            alarms = [(s > test.threshold_).any(axis=1) for s in q]
            al = np.concatenate(alarms)
            dj = np.concatenate([d[::int(round(w))] for d in alarms])
            p0 = 1.0 - (1.0 - a) ** len(first.channels)
            rows.append({"alpha per channel": a, "window (s)": w,
                         "chi2 test on white noise: size / alpha": round(float(np.mean(null > crit)) / a, 2),
                         "critical value chi2": round(crit, 2),
                         "critical value exact": round(float(test.threshold_[0]), 2),
                         "expected false alarms (%)": round(100.0 * p0, 3),
                         "false alarms, exact null (%)": round(100.0 * al.mean(), 2),
                         "disjoint windows flagged": f"{int(dj.sum())} of {dj.size}",
                         "two-sided binomial p": float(f"{two_sided_p(int(dj.sum()), dj.size, p0):.2g}")})
    return pd.DataFrame(rows).set_index(["alpha per channel", "window (s)"])


#: Aircraft of "The shipped aircraft and its alternatives": the shipped design (same seeds and command line) with
#: one of its choices undone, then all of them (the regular aircraft); packed like the shipped file and studied
#: like the shipped data
WHAT_IF = {
    "full speed 900 rad/s": HexacopterParameters(omega_max=900.0),
    "with rotor drag": HexacopterParameters(k_rotor_drag=REGULAR_HEXACOPTER.k_rotor_drag),
    "with weathervane": HexacopterParameters(k_weathervane=REGULAR_HEXACOPTER.k_weathervane),
    "regular (one-way rotors)": REGULAR_HEXACOPTER,
}


def what_if_tables(bases, ev) -> tuple[dict, pd.DataFrame, dict]:
    """The shipped design regenerated as each :data:`WHAT_IF` aircraft and studied like the shipped data.

    Returns (1) per level and failure, VAR + whiteness at 20 s, paper rule: tables of correct unique
    identification, of how often the matching model is rejected and of how often another failure's model accepts
    the window (keys), one column per aircraft; (2) the severe-turbulence steady-state variance thresholds of
    roll, pitch and yaw rate (largest 10 s rolling variance from 10 s after the failure over the fault fitting
    records; the paper's Fig. 7 discussion gives 1e-3, 1e-4 and, for the heading, 3e-4 rad^2 for its aircraft);
    (3) lost records per aircraft."""
    evs, thr, lost = {"shipped": ev}, {"shipped": bases["severe"].steady_thresholds}, {}
    for name, params in WHAT_IF.items():
        ds = make_hexacopter_dataset(20, seed=2024, params=params)
        lost[name] = int(ds["lost_control"].sum())
        # the heading of the regular aircraft slips by whole turns, past the int32 range of the shipped yaw step;
        # the study uses the yaw rate r, so the heading is left out
        ds, enc = encode_for_file(ds, [v for v in SHIPPED_VARIABLES if v != "yaw"])
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "what_if.nc"
            ds.to_netcdf(path, engine="h5netcdf", encoding=enc)
            data = load_hexacopter(path)
        b, evs[name] = hexacopter_study(data, models=["var"], tests=WHITENESS, windows=("20s",),
                                        rules=("paper",), progress=False)
        thr[name] = b["severe"].steady_thresholds
    rows = []
    for name, e in evs.items():
        df = e.identification_counts
        df = df[(df["model"] == "var") & (df["method"] == "whiteness") & (df["window"] == 20.0)]
        for (lvl, st), g in df.groupby(["turbulence", "state"], sort=False):
            other = g[[f"acc_{f}" for f in e.faults if f != st]].any(axis=1)
            rows.append({"turbulence": lvl, "state": st, "aircraft": name,
                         "correct unique (%)": pct(g, g["label_paper"] == st),
                         "matching model rejected (%)": pct(g, ~g[f"acc_{st}"]),
                         "another failure accepted (%)": pct(g, other)})
    df = pd.DataFrame(rows)
    t = {v: df.pivot_table(index=["turbulence", "state"], columns="aircraft", values=v, sort=False)[list(evs)]
         .round(1) for v in ("correct unique (%)", "matching model rejected (%)", "another failure accepted (%)")}
    steady = pd.DataFrame({name: {"roll (rad^2)": v[0], "pitch (rad^2)": v[1], "yaw rate (rad^2/s^2)": v[2]}
                           for name, v in thr.items()}).T
    steady.index.name = "aircraft"
    return t, steady.apply(lambda c: c.map(lambda v: float(f"{v:.2g}"))), lost


#: candidate per-channel alphas for the leave-one-record-out choice: the range of the paper's Table 3
LOO_ALPHAS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-8, 1e-10, 1e-12)


def loo_alpha(bases_e, data) -> tuple[pd.DataFrame, list[str]]:
    """Per turbulence level, the VAR + whiteness alpha chosen on the fitting records (leave one record out,
    :meth:`tsfdi.Baselines.select_alpha`, 20 s windows) and the evaluation records identified and monitored at it.
    Returns the table and the target lines."""
    sig = hexacopter_signals(data)
    rows, idents, dets = [], [], []
    for lvl, b in bases_e.items():
        tab = b.select_alpha("var", tsfdi.LjungBox(lags=20), "20s", LOO_ALPHAS)
        a = tab.attrs["selected"]
        ev = tsfdi.evaluate(sig, bases_e, models=["var"], tests={"whiteness": tsfdi.LjungBox(lags=20, alpha=a)},
                            turbulence=lvl, rules=["paper"], progress=False)
        idents.append(ev.identification_counts)
        dets.append(ev.detection_counts)
        r = ev.rates()["correct"].xs(("var", "whiteness", "paper"), level=("model", "method", "rule"))
        d = ev.detection_rates().loc[("var", "whiteness")]
        for w in sorted(d.index):
            rows.append({"turbulence": lvl, "alpha per channel": a,
                         "held-out correct at 20 s, alpha 1e-3 (%)": round(float(tab.loc[1e-3, "correct"]), 2),
                         "held-out correct at 20 s (%)": round(float(tab.loc[a, "correct"]), 2),
                         "held-out windows": int(tab.loc[a, "windows"]), "window (s)": w,
                         **{f: round(float(r.loc[(w, f)]), 2) for f in ev.faults},
                         "false alarms (%)": round(float(d.loc[w, "false_alarm"]), 2),
                         "expected (%)": float(f"{d.loc[w, 'expected_false_alarm']:.2g}"),
                         "disjoint flagged": (f"{int(d.loc[w, 'disjoint_alarms'])} of "
                                              f"{int(d.loc[w, 'disjoint_windows'])}"),
                         "two-sided binomial p": float(f"{d.loc[w, 'false_alarm_pvalue']:.2g}"),
                         "missed faults (%)": round(float(d.loc[w, "missed_fault"]), 2),
                         "median delay (s)": float(d.loc[w, "delay_median"])})
    df = pd.concat(idents, ignore_index=True)
    df = df[df["window"] == 20.0]
    rates = {f: correct_pct(df, f) for f in sorted(set(df["state"]))}
    low = min(correct_pct(g, st) for (_, st), g in df.groupby(["turbulence", "state"]))
    ok = all(v >= 99.6 for v in rates.values())
    lines = ["- VAR + whiteness, paper rule, 20 s, alpha chosen per level on the fitting records: correct "
             "unique identification " + ", ".join(f"{f} {v:.2f}%" for f, v in rates.items())
             + f" (lowest level and rotor {low:.2f}%) -> target >= 99.6% per rotor "
             + ("**met**." if ok else "**not met**.")]
    # detection over all levels: alarms on healthy windows against the sum of the per-level expectations
    tab = pd.DataFrame(rows)
    det = pd.concat(dets, ignore_index=True)
    first = next(iter(bases_e.values()))
    chosen = dict(zip(tab["turbulence"], tab["alpha per channel"]))
    for w, g in det[det["state"] == first.healthy].groupby("window"):
        # independent trials: the non-overlapping windows of each record; expectation pooled over the levels
        dj = g[g["disjoint"]]
        n_dj = int(dj["windows"].sum())
        p0 = sum((1.0 - (1.0 - chosen[lvl]) ** len(first.channels)) * h["windows"].sum()
                 for lvl, h in dj.groupby("turbulence")) / n_dj
        lo, hi = stats.binom.ppf([0.005, 0.995], n_dj, p0)
        x = int(dj.loc[dj["alarm"], "windows"].sum())
        lines.append(f"- Detection (healthy model at the chosen alpha, {w:g} s): non-overlapping healthy "
                     f"windows flagged {x} of {n_dj}, two-sided 99 % band {lo:.0f}-{hi:.0f} at the expected "
                     f"{100 * p0:.3g}% (all {g['windows'].sum()} sliding windows: {pct(g, g['alarm']):.2f}%) -> "
                     + ("**met**." if lo <= x <= hi else "**not met**."))
    return tab.set_index(["turbulence", "alpha per channel", "held-out correct at 20 s, alpha 1e-3 (%)",
                          "held-out correct at 20 s (%)", "held-out windows", "window (s)"]), lines


def targets(ev) -> list[str]:
    r = ev.rates()["correct"]
    lines = []
    v20 = r.xs(("var", "whiteness", 20.0, "paper"), level=("model", "method", "window", "rule"))
    ok = (v20 >= 99.6).all()
    lines.append(f"- VAR + whiteness, paper rule, 20 s: correct unique identification "
                 f"{', '.join(f'{k} {v:.2f}%' for k, v in v20.items())} -> target >= 99.6% per rotor "
                 f"**{'met' if ok else 'not met'}**.")
    best = None
    for rule in ev.rules[1:]:
        for meth in ("whiteness", "variance"):
            v5 = r.xs(("var", meth, 5.0, rule), level=("model", "method", "window", "rule"))
            if best is None or v5.min() > best[2].min():
                best = (rule, meth, v5)
    rule, meth, v5 = best
    lines.append(f"- Improved rules at 5 s: best VAR combination is rule '{rule}' with the {meth} method: "
                 f"{', '.join(f'{k} {v:.2f}%' for k, v in v5.items())} -> target >= 95% per rotor "
                 f"**{'met' if (v5 >= 95).all() else 'not met'}**.")
    d = ev.detection_rates()
    for meth in ("whiteness", "variance"):
        for w in sorted(d.index.get_level_values("window").unique()):
            lines.append(detection_line(f"VAR, {meth}, {w:g} s", d.loc[("var", meth, w)]))
    return lines


def detection_line(label: str, row) -> str:
    """One detection target line: the non-overlapping windows' false-alarm count against the two-sided 99 %
    binomial band of its expectation (the verdict: too many and too few both miss it), the rate over all windows,
    missed faults."""
    return (f"- Detection ({label}): non-overlapping healthy windows flagged {int(row['disjoint_alarms'])} of "
            f"{int(row['disjoint_windows'])}, two-sided 99 % band {row['disjoint_band_low']:.0f}-"
            f"{row['disjoint_band_high']:.0f} at the expected {row['expected_false_alarm']:.4f}% -> "
            f"**{'met' if row['false_alarm_in_band'] else 'not met'}** (two-sided binomial p = "
            f"{row['false_alarm_pvalue']:.2g}; all {int(row['healthy_windows'])} sliding windows: "
            f"{row['false_alarm']:.2f}%); missed faults {row['missed_fault']:.2f}% of post-failure windows, median "
            f"delay {row['delay_median']:.1f} s.")


def side_by_side(ev, ev_e) -> pd.DataFrame:
    """VAR + whiteness, correct unique identification (percent of windows) per level, rotor, window and rule with the
    chi-square and the calibrated thresholds."""
    rows = []
    for name, e in (("chi2", ev), ("empirical", ev_e)):
        df = e.identification_counts
        df = df[(df["model"] == "var") & (df["method"] == "whiteness")]
        for (lvl, w, st), g in df.groupby(["turbulence", "window", "state"], sort=False):
            for rule in e.rules:
                rows.append({"turbulence": lvl, "window": w, "rule": rule, "true": st, "thresholds": name,
                             "correct": pct(g, g[f"label_{rule}"] == st)})
    t = pd.DataFrame(rows).pivot_table(index=["turbulence", "window", "rule", "true"], columns="thresholds",
                                       values="correct", sort=False)
    return t.round(2)


def calibrated_lines(ev_e) -> list[str]:
    """Target lines for the calibrated-threshold run (VAR + whiteness)."""
    r = ev_e.rates()["correct"]
    v20 = r.xs(("var", "whiteness", 20.0, "paper"), level=("model", "method", "window", "rule"))
    lines = [f"- VAR + whiteness, calibrated thresholds, paper rule, 20 s: correct unique identification "
             f"{', '.join(f'{k} {v:.2f}%' for k, v in v20.items())} -> target >= 99.6% per rotor "
             f"**{'met' if (v20 >= 99.6).all() else 'not met'}**."]
    df = ev_e.identification_counts
    df = df[(df["model"] == "var") & (df["window"] == 20.0)]
    for lvl in dict.fromkeys(df["turbulence"]):
        g = df[df["turbulence"] == lvl]
        c = {f: correct_pct(g, f) for f in ev_e.faults}
        lines.append(f"  - **{lvl}**: {', '.join(f'{k} {v:.2f}%' for k, v in c.items())} "
                     f"(>= 99.6%: **{'met' if min(c.values()) >= 99.6 else 'not met'}**).")
    d = ev_e.detection_rates()
    for w in sorted(d.index.get_level_values("window").unique()):
        lines.append(detection_line(f"VAR, whiteness, calibrated, {w:g} s", d.loc[("var", "whiteness", w)]))
    det = ev_e.detection_counts
    det = det[(det["model"] == "var") & (det["state"] == "healthy")]
    fa = det.assign(flagged=det["windows"].where(det["alarm"], 0)).groupby(["window", "turbulence"], sort=False)[
        ["flagged", "windows"]].sum()
    fa = (fa["flagged"] / fa["windows"]).unstack() * 100.0
    lines.append("- Detection false alarms per level (percent of healthy windows, calibrated): " + "; ".join(
        f"{w:g} s: " + ", ".join(f"{lvl} {v:.2f}%" for lvl, v in row.items()) for w, row in fa.iterrows()) + ".")
    return lines


def threshold_table(ev_e) -> pd.DataFrame:
    """Calibrated Ljung-Box thresholds of the VAR models at 20 s against chi2(20) (per channel)."""
    c = ev_e.calibration
    c = c[(c["model"] == "var") & (c["method"] == "whiteness") & (c["window"] == 20.0)]
    t = c.pivot_table(index=["turbulence", "state"], columns="channel", values="empirical", sort=False)
    t.columns = [f"Q threshold {ch}" for ch in t.columns]
    t["chi2(20) threshold"] = c.groupby(["turbulence", "state"], sort=False)["distribution"].first()
    t["calibration windows per channel"] = c.groupby(["turbulence", "state"], sort=False)["calibration_size"].first()
    return t.round(2)


def main() -> None:
    warnings.simplefilter("ignore", UnstableModelWarning)
    t0 = time.perf_counter()
    data = load_hexacopter()
    paper_tab, paper_det, paper_orders = paper_like_for_like(data)
    cal_tab, cal_lines, cal_orders = calibrated_one_set(data)
    fleet = make_hexacopter_dataset(20, seed=2024, fleet=FleetSpread())
    fleet_tab, fleet_lines, fleet_orders = calibrated_one_set(fleet)
    fleet_lost = int(fleet["lost_control"].sum())
    bases, ev = hexacopter_study(data, progress="--progress" in sys.argv)
    bases_e, ev_e = hexacopter_study(data, tests=paper_tests([*SIGNAL_CHANNELS, "var"], ["whiteness"],
                                                             threshold="empirical"),
                                     progress="--progress" in sys.argv)
    counts = sorted({sum(e.shape[0] // (2000 - 20) for e in b.heldout[("var", st)])
                     for b in bases_e.values() for st in (b.healthy,) + b.faults})
    indep = f"{counts[0]}-{counts[-1]}" if len(counts) > 1 else str(counts[0])
    report = demo_report(bases, ev, markdown=True)
    mon = monitor_table(bases, data)
    var_tab = variants(data)
    alpha_tab = alpha_table(bases, data)
    null_tab = white_noise_null(bases, data)
    size5 = null_tab.loc[(1e-3, 5.0), "chi2 test on white noise: size / alpha"]
    size20 = null_tab.loc[(1e-3, 20.0), "chi2 test on white noise: size / alpha"]
    big = null_tab.index.get_level_values(0) > 1e-3
    sig_big, n_big = int((null_tab.loc[big, "two-sided binomial p"] < 0.05).sum()), int(big.sum())
    sig_small, n_small = int((null_tab.loc[~big, "two-sided binomial p"] < 0.05).sum()), int((~big).sum())
    alt, alt_steady, alt_lost = what_if_tables(bases, ev)
    loo_tab, loo_lines = loo_alpha(bases_e, data)
    improved = [line for line in targets(ev) if line.startswith("- Improved rules at 5 s")]
    summary_line = ("Summary: the calibrated method with one set of models for all levels is the second section "
                    "above; with the per-level models of this section and chi-square thresholds, the improved rule "
                    f"at 5 s: {'met' if improved and improved[0].endswith('**met**.') else 'not met'}. (The banks of "
                    "per-record models of earlier versions had no false-alarm size of their own and were removed.)")
    pooled_in = alpha_tab["in the 99 % band"]
    pooled_cells = f"{int(pooled_in.sum())} of {pooled_in.size}"
    sel_rows = []
    for lvl, b in bases.items():
        for st in (b.healthy,) + b.faults:
            sel = b.selections[("var", st)]
            row = {"turbulence": lvl, "state": st, "bic_order": sel.selected, "rss_sss_order": sel.stabilized}
            for p in (sel.selected, 20):
                row[f"q_insample VAR({p if p == 20 else 'bic'})"] = insample_q(sel.fit(p), 2000)
            sel_rows.append(row)
    sel_tab = pd.DataFrame(sel_rows).set_index(["turbulence", "state"]).round(2)

    def span(col, digits=0):
        lo, hi = (f"{v:.{digits}f}" for v in (col.min(), col.max()))
        return lo if lo == hi else f"{lo}-{hi}"
    FIGS.mkdir(parents=True, exist_ok=True)
    for old in FIGS.glob("*.png"):
        old.unlink()
    figs = write_figures(bases, ev, data, FIGS)
    elapsed = time.perf_counter() - t0
    n_eval = int(ev.records["evaluated"].sum())
    skipped = ev.records.loc[~ev.records["evaluated"], "skipped"].value_counts().to_dict()
    head = f"""# Results: the Dutta et al. study on the shipped hexacopter data

*Generated by `python docs/scripts/study.py` (tsfdi {tsfdi.__version__}, {elapsed:.0f} s); do not edit by hand.*

Data: `data/hexacopter.nc` ({REGENERATE_COMMAND}): 240 records = 4 states (healthy, rotor 1 / 2 / 6
failure at 10 s) x 3 Dryden turbulence levels x 20 records x 60 s at 100 Hz. {n_eval} records are evaluated;
skipped: {', '.join(f'{v} {k}' for k, v in skipped.items())}.

## Paper 003's protocol, like for like

One 20 s severe-turbulence record per state fits the models (the first valid record of each state, from 10 s
after the failure), the order is chosen by BIC (roll AR({'/'.join(map(str, paper_orders['roll']))}), pitch
AR({'/'.join(map(str, paper_orders['pitch']))}), yaw rate AR({'/'.join(map(str, paper_orders['yaw_rate']))}),
VAR({'/'.join(map(str, paper_orders['var']))}) over the four states), the Ljung-Box test uses 30 lags for the
scalar AR models (the paper's pitch example) and 50 for the VAR at alpha = 1e-3, the F test Table 3's alphas; every
other valid record of **all** levels is identified on 20 s windows 1 s apart. Percent of the windows of each true
failure accepted as rotor 1 / 2 / 6, beside the paper's Table 4:

""" + markdown_table(paper_tab) + f"""

Detection with the healthy model under that protocol (VAR, whiteness, 20 s): {paper_det.loc[('var', 'whiteness',
20.0), 'false_alarm']:.1f}% of the healthy windows flagged against {paper_det.loc[('var', 'whiteness', 20.0),
'expected_false_alarm']:.2f}% expected. On the shipped data the paper's protocol does not reproduce its Table 4: a
model fitted on one 20 s record of one level rejects most windows of new records, healthy or of its own failure.
Everything below departs from it, and says how.

## tsfdi's calibrated method: one set of models for all levels

The turbulence level is not known in flight, so one set of models serves every level: the first 10 valid records
of each state and level, pooled (30 per state); the VAR order by BIC on those records
(VAR({'/'.join(sorted({str(v) for v in cal_orders.values()}))}), the search bound being 20); Ljung-Box with 20
lags at alpha = 1e-3 per channel. "calibrated": every model's thresholds are fitted to its own held-out fitting
records (each record through the model fitted on the other 29, `held_out_residuals`; a scaled chi-square law per
record, mixed, with a 90 % bootstrap bound over records: `tsfdi.ScaledChi2Threshold`); "theoretical": chi2(20).
What was chosen on what: alpha = 1e-3 is the paper's; 20 lags and the 10 fitting records per state and level are
the settings of the sections below, which were compared on the evaluation records when they were built (issue 17
points this out), so they are not evaluation-free; the order (BIC) and the thresholds are chosen on the fitting
records only; the evaluation records are used once, here. Correct unique identification (percent of windows):

""" + markdown_table(cal_tab) + """

""" + "\n".join(cal_lines) + f"""

### The same on a fleet (generated on demand, not shipped)

Paper 002's aircraft are "of the same type but with small differences in weight and handling due to payloads".
The shipped design with `make_hexacopter_dataset(20, seed=2024, fleet=FleetSpread())`: every record draws its
mass (+-5 %), centre-of-gravity offset (+-1 cm in x and y), motor constants (+-3 %) and inertia (+-5 %) uniformly
from its seed and is trimmed for its own aircraft ({fleet_lost} records lost control). The same method, VAR order
by BIC (VAR({'/'.join(sorted({str(v) for v in fleet_orders.values()}))})):

""" + markdown_table(fleet_tab) + """

""" + "\n".join(fleet_lines) + f"""

Set-up of the sections below (what differs from the paper, and why):

- **Aircraft**: the shipped hexacopter has bidirectional rotors, 1100 rad/s full speed and no rotor drag or
  weathervane moment, so that after a failure it holds heading and its dynamics stay close to linear, as the
  paper's do (its yaw steady-state variance of 3e-4 rad^2 needs a held heading). Each of these choices is undone
  in "The shipped aircraft and its alternatives" below, where the regular aircraft (one-way rotors) is studied too.
- **Channels**: roll, pitch and the **yaw rate** `r`. The heading is the integral of the yaw rate under a slow
  heading loop, close to a unit root at 100 Hz, and an AR/VAR of order 20 does not whiten it.
- **Baselines per turbulence level, pooled**: for each level the first 10 valid records of each state fit the
  models (post-transient part from 10 s after the failure to the end; healthy records from 10 s). The records are
  passed to `tsfdi.VAR` / `tsfdi.AR` / `tsfdi.select_order` as a list: the regressions are stacked with no
  junction between records. The other 10 records of each state and level are evaluated, each with the models of
  its own level. Pooling across levels (one set of models for all) is compared below and is worse.
- **Orders**: VAR(20) and AR(20). BIC on the pooled records picks VAR({span(sel_tab['bic_order'])}), with median
  in-sample Ljung-Box Q {span(sel_tab['q_insample VAR(bic)'], 1)} against the chi2(20) median of 19.3 (table below),
  and the RSS/SSS stabilisation (1% tolerance) picks VAR({span(sel_tab['rss_sss_order'])}); order 20 gives in-sample
  Q {span(sel_tab['q_insample VAR(20)'], 1)} and the best identification of the orders compared ("Baseline
  choices compared"). **Tests**: Ljung-Box with 20 lags
  per channel at alpha = 1e-3 (paper Table 3); F test at the paper's alphas (1e-6 roll, 1e-12 pitch / yaw, 1e-8
  VAR). A model is accepted when every channel accepts (paper). Identification windows start at least 10 s after
  the failure (post-failure steady state), 1 s apart.
- **Rules**: `paper` (accepted set; one = identified, several = ambiguous, none = no decision), `likelihood`
  (among the accepted models, or all models when none is accepted, the one whose window residuals have the
  largest Gaussian log-likelihood, i.e. the smallest log-determinant of their covariance on common samples) and
  `pvalue` (the same with the largest smallest-channel p-value).

## Targets of issue 6

""" + summary_line + """

### Chi-square thresholds (the paper's tests)

All levels together:

""" + "\n".join(targets(ev)) + """

Per turbulence level:

""" + "\n".join(level_lines(ev)) + """

### Alpha chosen on the fitting records (leave one record out)

The paper sets each method's alpha (Table 3: 1e-3 to 1e-12) to minimise the confusion between failures. Here it
is chosen per turbulence level from the fitting records alone (`Baselines.select_alpha`): every fault fitting
record is cut into 20 s windows 1 s apart and driven through its own state's VAR refitted without it and through
the other failures' VARs, which never saw it; the paper's rule identifies each window at every candidate alpha
(""" + ", ".join(f"{a:g}" for a in LOO_ALPHAS) + """), and the largest alpha with the highest held-out correct rate
is kept. The evaluation records are then identified at that alpha (all window lengths), and the healthy model
detects at it.

""" + "\n".join(loo_lines) + """

""" + markdown_table(loo_tab) + """

Reading: out-of-sample residuals carry the baselines' estimation error, so at the nominal 1e-3 the matching
model is rejected more often than 1e-3 -- on the held-out fitting windows as on the evaluation records; the
windows the paper's rule misses there are windows with no model accepted. A smaller alpha accepts the matching
model on those windows while the other failures' models, whose residuals are far from white, stay rejected. The
healthy model detecting at the chosen alpha: false alarms and missed faults in the table (the false-alarm rate
against the expectation is the subject of the detection sections).

### Calibrated thresholds (leave-one-record-out, paper 002 Fig. 2)

Every model (healthy and each rotor, per level) gets its own per-channel Ljung-Box threshold: the 1 - alpha
quantile (alpha = 1e-3 per channel, as above) of the statistic on windows of its *own* fitting records, each
computed out of sample: each of the 10 fitting records in turn is left out, the model (same order) is refitted on
the other 9 and the left-out record's residual windows (every sample a window start) give statistics
(`fit_baselines(..., calibrate=True)`, `evaluate` with `LjungBox(..., threshold="empirical")`). Evaluation records are never used.
p-values are empirical. The variance method is not calibrated: the paper's alphas (1e-6 to 1e-12) would need
far more healthy windows than 10 records hold (the library says how many).

""" + "\n".join(calibrated_lines(ev_e)) + """

Calibrated thresholds of the VAR models (20 s windows, 20 lags) against the chi-square critical value:

""" + markdown_table(threshold_table(ev_e)) + """

Table 4 analogue, VAR + whiteness, 20 s windows, paper rule, calibrated thresholds (percent of windows of each
true failure accepted as rotor1/rotor2/rotor6):

""" + markdown_table(ev_e.table4(20.0, "paper").loc[["var"]]) + """

Chi-square and calibrated thresholds side by side (VAR + whiteness, correct unique identification, percent of
windows):

""" + markdown_table(side_by_side(ev, ev_e)) + """

Reading: the calibration sample counts every window start, so consecutive windows overlap almost entirely. The
held-out records of one model hold only """ + indep + """ non-overlapping 20 s windows, while an empirical
1 - 1e-3 quantile needs """ + f"{20 / 1e-3:.0f}" + """ independent statistics (20 expected exceedances) and even the
generalised Pareto tail fit """ + f"{EmpiricalThreshold(1e-3).samples_needed()}" + """: the record-to-record
spread of the statistic dominates the estimated tail. The calibrated thresholds scatter around the chi2(20)
value (table above), and neither the identification nor the false-alarm rates on the evaluation records (lines
above) are better than with chi-square thresholds.

Reading: with 10 pooled baseline records per state and level and order 20, the matching model's residuals on new
records are close to white at every turbulence level and no window of one failure is accepted by another
failure's model (Table 4 analogues); the windows the paper's rule misses are windows where the matching model too
is rejected (no decision). The likelihood rule (pick the model whose window residuals have the smallest
covariance log-determinant) decides those as well. "The shipped aircraft and its alternatives" shows how each
design choice of the aircraft changes this.

## Monitor end to end (VAR, whiteness, 5 s windows, likelihood rule)

Detection with the healthy model, steady-state check with the baseline variance thresholds (10 s rolling
variance, Fig. 7), then identification of every window. Times relative to the failure.

""" + markdown_table(mon.round(2)) + "\n\n"
    tail = f"""

## Order choice on the pooled records (VAR)

Median Ljung-Box Q (20 lags) of the in-sample residuals over 20 s blocks and channels; chi2(20) median 19.3.

""" + markdown_table(sel_tab) + """

## Baseline choices compared (VAR, whiteness method)

Correct unique identification in percent of windows (minimum over the three rotors) for the paper rule at
20 s per level, the likelihood rule at 5 s over all levels, and the detection false-alarm rate at 20 s
(expectation 0.3%). Each row is a full re-run of the baselines and the evaluation.

""" + markdown_table(var_tab.set_index(["fit_records", "pool", "order"])) + """

## Detection false alarms against alpha (VAR, whiteness method)

The healthy model's Ljung-Box test (20 lags, every channel, paper rule) on the healthy evaluation records, at
several per-channel alphas; the expectation is ``1 - (1 - alpha)^3`` for the three channels, and the binomial
p-value counts the disjoint windows as independent trials:

""" + markdown_table(alpha_tab) + """

Reading: over all windows the pooled model's false-alarm rate is above its expectation at nearly every alpha and
window length; counted on the disjoint windows it is inside the two-sided 99 % band in """ + pooled_cells + """
cells: the excess at the paper's alpha (1e-3) and below is within binomial noise here, while at 1e-2 and
5e-2, where the tail is sampled best, it is significant in most cells: the statistic on new healthy
records is spread wider than chi2(20) (the baseline's estimation error and slight misfit; notes of
`tsfdi.LjungBox`), and thresholds calibrated on the fitting records do not fix that (calibrated section above).

### How much of the excess is the chi-square approximation

The chi-square(20) law of the Ljung-Box statistic is asymptotic. For the windows here (5, 10 and 20 s: the window's
samples less the VAR order, with 20 lags) its upper tail is too light even for residuals that are exactly iid Gaussian: the
null distribution of ``Q`` was simulated (""" + f"{NULL_DRAWS}" + """ windows of iid Gaussian noise per length, fixed seed), which
gives the chi-square test's size on white noise and the exact critical value. The healthy VAR then detects on
the healthy evaluation records with that exact critical value (a `tsfdi.LjungBox(threshold="empirical")`
calibrated on the simulated statistics):

""" + markdown_table(null_tab) + f"""

Reading: at alpha 1e-3 per channel the chi-square test itself rejects white noise {size5:g} times as often as
alpha on 5 s windows ({size20:g} times on 20 s windows), so a part of the false-alarm excess above is the test's
finite-sample law, not the model. With the exact critical values the remaining excess is the baselines' misfit
of new healthy records: on the disjoint windows it is significant (two-sided binomial p < 0.05) in {sig_big} of
{n_big} cells at alpha 1e-2 and 5e-2, where the tail is sampled well, and in {sig_small} of {n_small} at 1e-3.
""" + """

## The shipped aircraft and its alternatives

The same design (same seeds and command line) regenerated with one choice of the shipped aircraft undone at a
time -- full rotor speed 900 rad/s instead of 1100 (thrust-to-weight 3.2 instead of 4.8), rotor drag (H-force)
`k_rotor_drag = 1.2e-4`, weathervane moment `k_weathervane = 8e-4` -- and then the regular aircraft
(`tsfdi.datasets.REGULAR_HEXACOPTER`: all three, and one-way rotors with a 60 rad/s idle floor; the file shipped
before). Packed like the shipped file (lost records: """ + "; ".join(f"{k}: {v}" for k, v in alt_lost.items()) + """),
fitted and evaluated exactly as above. VAR + whiteness, 20 s windows, paper rule, correct unique identification (%):

""" + markdown_table(alt["correct unique (%)"]) + """

How often the matching model is rejected (%):

""" + markdown_table(alt["matching model rejected (%)"]) + """

How often another failure's model accepts the window (%):

""" + markdown_table(alt["another failure accepted (%)"]) + """

Steady-state variance thresholds in severe turbulence (largest 10 s rolling variance from 10 s after the failure
over the fault fitting records; the paper's aircraft: roll 1e-3, pitch 1e-4 rad^2):

""" + markdown_table(alt_steady) + """

Reading: each choice removes one cause of error of the paper's rule. At 900 rad/s the four rotors that carry the
aircraft after a failure reach full speed in strong gusts; the clipping is a non-linearity the VAR cannot follow,
and the matching model is rejected on many severe-turbulence windows. Rotor drag makes the post-failure dynamics
of rotors 2 and 6 (mirror images with the same spin direction) so alike that each one's model accepts the other's
windows. The weathervane moment, quadratic in the relative wind, raises the rejections of the matching model in
moderate and severe turbulence. On the regular aircraft the rotor opposite the failed one runs near its idle
floor and switches on and off it in gusts, and the heading slips by whole turns in severe turbulence: in severe
turbulence the matching model is rejected on many windows and other failures' models accept many of rotor 2's and
6's. The shipped choices make a benchmark on which the paper's assumption (linear, stationary post-failure
dynamics) holds; the regular aircraft shows what happens when it does not.

## What was investigated

On the regular aircraft shipped before (see above):

- Pooling records as a list (no junctions) instead of one record: see "Baseline choices compared"; one record
  per state leaves a large estimation error, which shows as correlated out-of-sample residuals.
- Pooling across turbulence levels (one model set): see the table; worse than per-level models.
- Fitting on severe turbulence only (paper), earlier data: healthy-model false alarms 46-100% on severe to light
  records.
- Decimating to 50 / 25 Hz before modelling: BIC then selects the largest order and residuals stay correlated.
- An intercept (`trend="c"`): no material change in the residual whiteness.
- Ljung-Box with 30 or 50 lags (the paper's identification uses 50) and VAR(30): the paper rule at 20 s moves by a
  few points per level either way; severe turbulence stays far below the target.
- Roll and pitch rates (differenced angles) instead of the angles, to remove slow trim changes during heading
  slips: no material change, so the non-whiteness is fast dynamics, not drift.
- A heteroskedasticity-robust portmanteau (each lag's autocovariance standardised by the sum of
  `e[t]^2 e[t-k]^2`): it rejects the matching model in severe turbulence almost as often as Ljung-Box.
- Earlier (one fitting record per state): a VAR fitted on one record and tested on another gave Ljung-Box Q
  of about 40-60 for 25 lags (expected 25); pooling removed most of that excess outside severe turbulence.

""" + markdown_figures(figs, ROOT / "docs")
    (ROOT / "docs" / "results.md").write_text(head + report + tail)
    print(f"wrote docs/results.md and {len(figs)} figures in {elapsed:.0f} s")


if __name__ == "__main__":
    main()

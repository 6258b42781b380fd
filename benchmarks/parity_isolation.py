"""Benchmark 2 of issue 35: parity isolation of three climb-rate estimates on sensors logged at real rates.

Three estimates of the climb rate of the default hexacopter (``simulate_hexacopter``, moderate turbulence, 2-8
m/s forward), each from its own sensor of ``sensor_log`` (gyro / accelerometer 500 Hz, barometer 50 Hz, GPS 10 Hz
with 110 ms latency, attitude estimate 250 Hz):

- ``baro``: the least-squares slope of the barometric altitude over 1 s (``climb_rate_from_baro``);
- ``gps``: minus the GPS down velocity, its mean over the last 1 s (10 fixes);
- ``accel``: the specific force rotated by the attitude estimate, gravity removed, integrated with a complementary
  correction of time constant 5 s towards zero climb (``climb_rate_from_accel``);

put on one 50 Hz grid (``tsfdi.align``, zero-order hold). Paper 002's parity relations (``ResidualSet.pairwise``):
R1 = baro - gps, R2 = baro - accel, R3 = gps - accel, each sensitive to two estimates. Each residual has a GLRT
on its mean (eq. 3: biases, drifts) and, if the development flights choose it, one on the log of its mean square
over the last ``var_window`` samples minus its healthy mean (a variance change). Beside them, every sensor checks
its own raw output for a frozen value (``frozen_output``: the same value repeated over 10 barometer samples, 10
GPS fixes or 50 samples of any accelerometer axis), fixed by that check's false-alarm bound, not tuned. A residual
fires when one of its GLRTs alarms or when the self-check of one of its two sensors flags: a self-check flag
thereby completes its sensor's column. The fired pattern is matched to the columns of the table; a fault is
isolated when one sensor stays isolated for ``hold`` consecutive samples (``IsolationSeries.confirmed``).

False-alarm budget per flight-hour, not per sample: the GLRTs share a budget B of expected alarmed samples per
flight-hour (all residuals and statistics together, a union bound; every false-alarm episode and every false
isolation has at least one alarmed sample), so each of the m GLRTs runs at P_F = B / (m x 50 Hz x 3600 s) per
sample, its threshold extrapolated by the generalised Pareto tail of ``EmpiricalThreshold`` from the pooled
healthy statistics of the training flights. The hold then asks a false pattern to persist.

Faults (``inject_fault`` on the sensor's own topic, at its own rate, from a random onset 50-90 s into a 120 s
flight; the first 30 s are the estimators' start-up and are not tested): bias, drift and stuck (frozen) of the
barometric altitude, the GPS down velocity and the body-z accelerometer axis. Sizes: baro bias 1.5 m, drift
0.1 m/s; GPS bias 0.5 m/s, drift 0.02 m/s per s; accelerometer bias 0.3 m/s^2 (31 mg), drift 0.02 m/s^2 per s.

Protocol: the GLRT window, the budget, the variance GLRT (with its window, or none) and the hold are chosen on
flights of the development seed only: 20 training flights calibrate the scales and thresholds, 20 other
development flights score 9 faults each and their fault-free 30 min count false isolations. The choice asks for
no false isolation on the development flights with a margin (the longest run of one isolated sensor on the
fault-free development flights at most half the hold), then the most correct isolations, then the simpler
detector (no variance GLRT), then the smaller budget, then the shortest median isolation delay
(``--development-only`` stops here). The evaluation then runs once, on flights
simulated from a seed drawn at run time (``tsfdi.study.evaluation_seed()``), printed and stored nowhere; nothing
is chosen after it. A scenario is correct when the first confirmed isolation of its flight comes after the onset,
within 30 s, and names the faulty sensor. False isolations: confirmed isolations on fault-free flights, and
before the onset of a faulty one (the same healthy stretch of that flight: the estimators are causal).

Slow degradations: the parameter GLRT (``ParameterGLRT``) on an RLS estimate (``RecursiveARX``, constant only,
forgetting factor 0.999, paper 002 eqs. 14-16) of each residual's offset, its threshold calibrated on the
training flights; its detection delay on the drift scenarios is printed beside the mean GLRT's.

The figure (``docs/figures/parity_isolation.png``, ``--figure PATH``) shows one development flight with a frozen
GPS: the residuals, every GLRT's alarms and self-check flags, and the isolation decision.

Run: ``python benchmarks/parity_isolation.py`` (about 5 min on one core).
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

import tsfdi
from tsfdi.datasets import simulate_hexacopter
from tsfdi.datasets.faults import inject_fault
from tsfdi.datasets.sensors import sensor_log
from tsfdi.detection.glrt import ParameterGLRT
from tsfdi.isolation import IsolationSeries, ResidualSet, climb_rate_from_accel, climb_rate_from_baro, frozen_output
from tsfdi.study import evaluation_seed

FS = 50                    # Hz, the grid of the estimates
WARM = 30.0                # s of start-up left out (the accelerometer estimate learns its bias)
DURATION = 120.0
ONSET = (50.0, 90.0)       # s, uniform
HORIZON = 30.0             # s after the onset within which the isolation must come
DEV_SEED = 2035
N_TRAIN, N_DEV, N_EVAL = 20, 20, 20
SENSORS = ("baro", "gps", "accel")
TOPIC = {"baro": ("baro", "altitude"), "gps": ("gps", "vd"), "accel": ("accel", "az")}
FAULTS = {("baro", "bias"): 1.5, ("baro", "drift"): 0.1, ("baro", "stuck"): 0.0,
          ("gps", "bias"): 0.5, ("gps", "drift"): 0.02, ("gps", "stuck"): 0.0,
          ("accel", "bias"): 0.3, ("accel", "drift"): 0.02, ("accel", "stuck"): 0.0}
# frozen-output self-check of each sensor's raw output: (topic, channels, window in samples at the topic's rate),
# tolerance 0 (a repeated value); fixed by the false-alarm bound of frozen_output, not tuned
SELF_CHECK = {"baro": ("baro", ("altitude",), 10), "gps": ("gps", ("vd",), 10),
              "accel": ("accel", ("ax", "ay", "az"), 50)}
# per-sample bound (2 f_max (tolerance + resolution))^(n - 1) with the suite's noise and an output resolution of
# 1 cm (baro), 1 cm/s (GPS; u-blox reports mm/s), 16 g / 2^15 (accelerometer): (sigma, resolution, rate)
SELF_CHECK_NOISE = {"baro": (0.10, 0.01, 50), "gps": (0.10, 0.01, 10), "accel": (0.0108, 156.9 / 2**15, 500)}
# settings chosen on the development flights
BUDGETS = (10.0, 1.0, 0.3)         # expected alarmed samples of all GLRTs per flight-hour (family-wise)
WINDOWS = (100, 200)               # GLRT window, samples
VAR_WINDOWS = (None, 50)           # variance GLRT on the log mean square of each residual (None: not used)
HOLDS = (10, 25, 50)               # samples one sensor must stay isolated
MAX_EXTRAPOLATION = 1000.0         # the GPD tail may reach P_F down to 20 / (1000 n) (EmpiricalThreshold)
PARITY = ResidualSet.pairwise(SENSORS)     # R1 = baro - gps, R2 = baro - accel, R3 = gps - accel
FIGURE = Path(__file__).resolve().parent.parent / "docs" / "figures" / "parity_isolation.png"


def flights(seed: int, n: int) -> list[dict]:
    """``n`` healthy flights of the seed's stream: 1 kHz truth -> sensor logs."""
    seeds = np.random.default_rng(seed).integers(0, 2**31, size=(n, 2))
    ds = simulate_hexacopter(records=n, duration=DURATION, fs=1000, turbulence="moderate", failed_rotor=0,
                             seed=seeds[:, 0].tolist(), speed=(2.0, 8.0))
    return [sensor_log(ds.isel(record=r), rng=int(seeds[r, 1])) for r in range(n)]


def estimates(log: dict) -> pd.DataFrame:
    imu = tsfdi.align({"accel": log["accel"], "attitude": log["attitude"]}, 250)[0]
    accel = climb_rate_from_accel(imu[["accel.ax", "accel.ay", "accel.az"]],
                                  imu[["attitude.roll", "attitude.pitch", "attitude.yaw"]], "5s")
    baro = climb_rate_from_baro(log["baro"]["altitude"], "1s")
    gps = -log["gps"]["vd"].rolling(10).mean().iloc[9:]
    est = tsfdi.align({"baro": baro.rename("baro"), "gps": gps.rename("gps"), "accel": accel.rename("accel")}, FS)[0]
    est.columns = list(SENSORS)
    return est


def faulty(log: dict, sensor: str, kind: str, onset: float) -> dict:
    topic, column = TOPIC[sensor]
    out = dict(log)
    ramp = {"ramp": "1s"} if kind == "drift" else {}          # drift: magnitude per second
    out[topic], _ = inject_fault(log[topic], kind, FAULTS[sensor, kind], f"{onset}s", channel=column,
                                 sensor_range=1.0, **ramp)
    return out


def monitored(log: dict) -> tuple[pd.DataFrame, np.ndarray]:
    """The three parity residuals from WARM s on, and the self-check flags of the three sensors on their samples
    (bool, one column per sensor: the flag of the sensor's latest sample at or before each residual sample)."""
    r = PARITY.residuals(estimates(log))
    r = r[r.index >= pd.Timedelta(seconds=WARM)]
    t = r.index.total_seconds().to_numpy()
    flags = np.zeros((len(r), len(SENSORS)), dtype=bool)
    for j, sensor in enumerate(SENSORS):
        topic, channels, n = SELF_CHECK[sensor]
        frame = log[topic]
        raw = np.any([frozen_output(frame[c].to_numpy(), n) for c in channels], axis=0)
        last = np.searchsorted(frame.index.to_numpy(), t + 1e-9, side="right") - 1
        flags[:, j] = raw[last]
    return r, flags


def log_power(r: pd.DataFrame, var_window: int) -> pd.DataFrame:
    """log of the residuals' mean square over the last var_window samples (first var_window - 1 left out)."""
    return np.log((r**2).rolling(var_window).mean()).iloc[var_window - 1:]


class Statistics:
    """GLRT statistics g(k) of every residual (mean change) and of its log mean square (variance change) for one
    GLRT window and variance window, the scales calibrated on the training flights; thresholds for a family-wise
    budget of alarmed samples per flight-hour from the pooled healthy statistics (EmpiricalThreshold)."""

    def __init__(self, window: int, var_window: int | None, train: list[pd.DataFrame]) -> None:
        self.window, self.var_window = window, var_window
        self.tests = {}
        for n in PARITY.names:
            self.tests["mean", n] = tsfdi.GLRT(window).calibrate([r[n].to_numpy() for r in train])
        if var_window is not None:
            powers = [log_power(r, var_window) for r in train]
            self.centre = pd.concat(powers).mean()
            for n in PARITY.names:
                self.tests["var", n] = tsfdi.GLRT(window).calibrate([(p[n] - self.centre[n]).to_numpy()
                                                                      for p in powers])

    def false_alarm(self, budget: float) -> float:
        """Per-sample P_F of each GLRT: the budget shared by the tests over a flight-hour of samples."""
        return budget / (len(self.tests) * FS * 3600.0)

    def thresholds(self, budget: float) -> dict:
        pf = self.false_alarm(budget)
        return {k: tsfdi.EmpiricalThreshold(pf, max_extrapolation=MAX_EXTRAPOLATION).calibrate(
            t.healthy_statistic_.ravel()).threshold_ for k, t in self.tests.items()}

    def g(self, r: pd.DataFrame) -> dict:
        out = {("mean", n): self.tests["mean", n].test(r[n].to_numpy()).details["g"] for n in PARITY.names}
        if self.var_window is not None:          # no variance alarm before the first complete mean square
            p = log_power(r, self.var_window) - self.centre
            pad = np.zeros(self.var_window - 1)
            out.update({("var", n): np.r_[pad, self.tests["var", n].test(p[n].to_numpy()).details["g"]]
                        for n in PARITY.names})
        return out


def series(g: dict, thresholds: dict, r: pd.DataFrame, flags: np.ndarray | None) -> IsolationSeries:
    """Per-sample isolation: a residual fires where its mean or variance GLRT alarms, or where the self-check of
    a sensor of its row flags a frozen output (the flag completes that sensor's column)."""
    fired = np.zeros((len(r), len(PARITY.names)), dtype=bool)
    for (what, n), gk in g.items():
        fired[:, PARITY.names.index(n)] |= gk > thresholds[what, n]
    if flags is not None:
        fired |= (flags.astype(int) @ PARITY.incidence.T.astype(int)) > 0
    pos = np.arange(len(r))
    return IsolationSeries(fired, PARITY.names, PARITY.sensors, PARITY.incidence, pos, pos + 1, r.index)


def scenarios(logs: list[dict], seed: int) -> list[tuple]:
    """(flight, sensor, kind, onset s, residuals, flags) for every flight and fault, onsets drawn from ``seed``."""
    rng = np.random.default_rng([seed, 35])
    out = []
    for i, log in enumerate(logs):
        for sensor, kind in FAULTS:
            onset = round(float(rng.uniform(*ONSET)), 2)
            out.append((i, sensor, kind, onset, *monitored(faulty(log, sensor, kind, onset))))
    return out


def wrong_run(s: IsolationSeries) -> int:
    """Longest run of rows isolating one sensor (the margin to the hold on a fault-free record)."""
    code = np.array([SENSORS.index(x) if x is not None else -1 for x in s.labels])
    longest, run, prev = 0, 0, -1
    for c in code:
        run = run + 1 if c >= 0 and c == prev else (1 if c >= 0 else 0)
        prev = c
        longest = max(longest, run)
    return longest


def score(all_series: list[IsolationSeries], faults: list[tuple], healthy: list[IsolationSeries], hold: int
          ) -> tuple[pd.DataFrame, int]:
    rows = []
    for s, (i, sensor, kind, onset, r, _) in zip(all_series, faults):
        t = (s.index - pd.Timedelta(seconds=onset)).total_seconds().to_numpy()
        c = s.confirmed(hold)
        first = s.first_detection
        after = np.flatnonzero(s.fired.any(axis=1) & (t >= 0))
        iso_t = None if c is None else t[c]
        rows.append({"flight": i, "sensor": sensor, "kind": kind, "onset": onset,
                     "label": None if c is None else s.labels[c],
                     "correct": c is not None and 0 <= iso_t <= HORIZON and s.labels[c] == sensor,
                     "false_before_onset": c is not None and iso_t < 0,
                     "alarm_before_onset": first is not None and t[first] < 0,
                     "detection_delay": t[after[0]] if after.size else np.nan,
                     "isolation_delay": iso_t if c is not None and 0 <= iso_t <= HORIZON else np.nan})
    false_healthy = sum(s.confirmed(hold) is not None for s in healthy)
    return pd.DataFrame(rows), false_healthy


def drift_glrt(train: list[pd.DataFrame], faults: list[tuple], window: int = 500, false_alarm: float = 1e-5):
    """Detection delay of the parameter GLRT on the RLS offset of each residual, drift scenarios."""
    def inputs(x: np.ndarray):
        rls = tsfdi.RecursiveARX(na=0, nb=0, trend="c", forgetting_factor=0.999)
        params = rls.run(x).params
        return x, np.ones((x.size, 1)), np.asarray(params).reshape(x.size, -1)

    tests = {}
    for n in PARITY.names:
        tests[n] = ParameterGLRT(window, threshold=tsfdi.EmpiricalThreshold(false_alarm))
        tests[n].calibrate(*map(list, zip(*[inputs(r[n].to_numpy()) for r in train])))
    rows = []
    for i, sensor, kind, onset, r, _ in faults:
        if kind != "drift":
            continue
        t = (r.index - pd.Timedelta(seconds=onset)).total_seconds().to_numpy()
        alarms = np.zeros(len(r), dtype=bool)
        for n in PARITY.names:
            if PARITY.table.loc[n, sensor]:
                d = tests[n].test(*inputs(r[n].to_numpy()))
                alarms[np.asarray(d.details["alarms"], dtype=np.int64)] = True
        after = np.flatnonzero(alarms & (t >= 0))
        rows.append({"sensor": sensor, "before_onset": bool((alarms & (t < 0)).any()),
                     "delay": t[after[0]] if after.size else np.nan})
    return pd.DataFrame(rows)


def table(res: pd.DataFrame) -> pd.DataFrame:
    g = res.groupby(["sensor", "kind"], sort=False)
    return pd.DataFrame({"correct": g["correct"].sum().astype(int).astype(str) + " / " + g.size().astype(str),
                         "median detection delay (s)": g["detection_delay"].median().round(2),
                         "median isolation delay (s, correct ones)": g["isolation_delay"].median().round(2),
                         "max isolation delay (s, correct ones)": g["isolation_delay"].max().round(2)})


def self_check_bound() -> pd.DataFrame:
    """frozen_output's false-alarm bound per sensor: per sample and per flight-hour (union over channels and
    samples)."""
    rows = {}
    for sensor, (sigma, resolution, rate) in SELF_CHECK_NOISE.items():
        _, channels, n = SELF_CHECK[sensor]
        per_sample = (2 * resolution / (sigma * np.sqrt(2 * np.pi))) ** (n - 1)
        rows[sensor] = {"window (samples)": n, "rate (Hz)": rate, "channels": len(channels),
                        "P_F per sample": f"{per_sample:.1e}",
                        "P_F per flight-hour": f"{per_sample * len(channels) * rate * 3600:.1e}"}
    return pd.DataFrame(rows).T


def plot(scenario: tuple, stats: Statistics, thresholds: dict, hold: int, path: Path) -> None:
    """Residuals, GLRT alarms, self-check flags and the isolation decision of one faulty flight."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    i, sensor, kind, onset, r, flags = scenario
    s = series(stats.g(r), thresholds, r, flags)
    t = r.index.total_seconds().to_numpy()
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True, gridspec_kw={"height_ratios": [3, 2, 1.2]})
    for n in PARITY.names:
        a, b = PARITY.table.columns[PARITY.table.loc[n].to_numpy() == 1]
        axes[0].plot(t, r[n], lw=0.7, label=f"{n} = {a} - {b}")
    axes[0].set_ylabel("parity residual (m/s)")
    axes[0].legend(loc="upper left", fontsize=8, ncol=3)
    g = stats.g(r)
    rows = [(f"{n} mean GLRT", g["mean", n] > thresholds["mean", n]) for n in PARITY.names]
    rows += [(f"{n} variance GLRT", g["var", n] > thresholds["var", n]) for n in PARITY.names if ("var", n) in g]
    rows += [(f"{x} frozen (self-check)", flags[:, j]) for j, x in enumerate(SENSORS)]
    for k, (name, on) in enumerate(rows):
        axes[1].fill_between(t, k - 0.4, k + 0.4, where=on, step="post", color=f"C{k % 10}", lw=0)
    axes[1].set_yticks(range(len(rows)), [x for x, _ in rows], fontsize=8)
    axes[1].set_ylim(-0.6, len(rows) - 0.4)
    code = np.array([SENSORS.index(x) if x is not None else -1 for x in s.labels], dtype=float)
    code[code < 0] = np.nan
    axes[2].plot(t, code, ".", ms=2, color="k")
    c = s.confirmed(hold)
    if c is not None:
        axes[2].axvline(t[c], color="C3", lw=1, label=f"confirmed: {s.labels[c]} ({t[c] - onset:.2f} s)")
        axes[2].legend(loc="upper left", fontsize=8)
    axes[2].set_yticks(range(len(SENSORS)), SENSORS, fontsize=8)
    axes[2].set_ylim(-0.5, len(SENSORS) - 0.5)
    axes[2].set_ylabel("isolated")
    axes[2].set_xlabel("time (s)")
    for ax in axes:
        ax.axvline(onset, color="0.4", ls="--", lw=0.8)
    axes[0].set_title(f"development flight {i}: {sensor} {kind} at {onset:g} s (dashed)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    print(f"figure: {path}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figure", type=Path, default=FIGURE, metavar="PATH", help="where to save the figure")
    parser.add_argument("--no-figure", action="store_true", help="do not draw the figure")
    parser.add_argument("--development-only", action="store_true",
                        help="stop after the choice on the development flights (no evaluation flights)")
    args = parser.parse_args(argv)
    t0 = time.time()
    dev = flights(DEV_SEED, N_TRAIN + N_DEV)
    train = [monitored(log)[0] for log in dev[:N_TRAIN]]
    dev_faults = scenarios(dev[N_TRAIN:], DEV_SEED)
    dev_healthy = [monitored(log) for log in dev[N_TRAIN:]]
    hours = N_DEV * (DURATION - WARM) / 3600
    print(f"development seed {DEV_SEED}: {N_TRAIN} training flights (scales, thresholds), {N_DEV} development "
          f"flights x {len(FAULTS)} faults and fault-free ({hours:.2f} flight-hours monitored fault-free) for the "
          f"settings; {time.time() - t0:.0f} s")
    print("\nself-check (frozen_output, tolerance 0), false-alarm bound (stated noise and resolution):")
    print(self_check_bound().to_string())
    print("\nsettings on the development flights (budget: expected alarmed samples of all GLRTs per flight-hour; "
          "wrong run: longest run of one isolated sensor on the fault-free flights):")
    best = None
    for window, vw in itertools.product(WINDOWS, VAR_WINDOWS):
        stats = Statistics(window, vw, train)
        gf = [stats.g(sc[4]) for sc in dev_faults]
        gh = [stats.g(r) for r, _ in dev_healthy]
        for budget in BUDGETS:
            try:
                thr = stats.thresholds(budget)
            except ValueError as exc:       # the tail fit cannot reach this P_F on the training sample
                print(f"  window {window}  var_window {vw}  budget {budget:g}/h: {exc}")
                continue
            sf = [series(g, thr, sc[4], sc[5]) for g, sc in zip(gf, dev_faults)]
            sh = [series(g, thr, r, f) for g, (r, f) in zip(gh, dev_healthy)]
            alarmed = sum(int(s.fired.any(axis=1).sum()) for s in
                          [series(g, thr, r, None) for g, (r, _) in zip(gh, dev_healthy)])
            run = max(wrong_run(s) for s in sh)
            for hold in HOLDS:
                res, false_healthy = score(sf, dev_faults, sh, hold)
                false = false_healthy + int(res["false_before_onset"].sum())
                key = (false == 0 and 2 * run <= hold, round(res["correct"].mean(), 3), vw is None, -budget,
                       -res["isolation_delay"].median())
                print(f"  window {window:3d}  var_window {str(vw):4s}  budget {budget:4g}/h (P_F "
                      f"{stats.false_alarm(budget):.1e})  hold {hold:2d}: correct {res['correct'].mean():6.1%}, "
                      f"false isolations {false}, alarmed samples {alarmed / hours:5.1f}/h, wrong run {run}, "
                      f"median isolation delay {res['isolation_delay'].median():.2f} s")
                if best is None or key > best[0]:
                    best = (key, window, vw, budget, hold)
    _, window, vw, budget, hold = best
    stats = Statistics(window, vw, train)
    thr = stats.thresholds(budget)
    print(f"chosen on the development flights: GLRT window {window}, var_window {vw}, budget {budget:g} alarmed "
          f"samples per flight-hour (P_F {stats.false_alarm(budget):.1e} per sample and test), hold {hold} samples "
          f"({hold / FS:g} s); {time.time() - t0:.0f} s")
    if not args.no_figure:
        pick = next(sc for sc in dev_faults if sc[1:3] == ("gps", "stuck"))
        plot(pick, stats, thr, hold, args.figure)
    if args.development_only:
        return

    seed = evaluation_seed()
    print(f"\nevaluation (run once, after every choice above): seed drawn now, stored nowhere: {seed}")
    logs = flights(seed, N_EVAL)
    eval_faults = scenarios(logs, seed)
    eval_healthy = [monitored(log) for log in logs]
    sf = [series(stats.g(sc[4]), thr, sc[4], sc[5]) for sc in eval_faults]
    sh = [series(stats.g(r), thr, r, f) for r, f in eval_healthy]
    res, false_healthy = score(sf, eval_faults, sh, hold)
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(table(res).to_string())
    n = len(res)
    before = res[res["false_before_onset"]]
    print(f"\ncorrect isolation: {int(res['correct'].sum())} / {n} ({res['correct'].mean():.1%}); "
          f"false isolation on {false_healthy} of {N_EVAL} fault-free flights ({N_EVAL * (DURATION - WARM) / 60:g} "
          f"min), before the onset in {len(before)} of {n} faulty flights ({res['onset'].sub(WARM).sum() / 3600:.2f} "
          f"h fault-free; on {before['flight'].nunique()} distinct flights); longest run of one isolated sensor on "
          f"the fault-free flights {max(wrong_run(s) for s in sh)} samples (hold {hold}); any alarm before the "
          f"onset in {int(res['alarm_before_onset'].sum())}")
    wrong = res[~res["correct"]]
    if len(wrong):
        print("not correctly isolated:\n" + wrong[["flight", "sensor", "kind", "onset", "label",
                                                      "detection_delay"]].to_string(index=False))

    drift = drift_glrt(train, eval_faults)
    mean_delay = res[res["kind"] == "drift"].groupby("sensor", sort=False)["detection_delay"].median()
    print("\ndrifts, parameter GLRT on the RLS offset (window 500, P_F 1e-5) vs the mean GLRT:")
    print(pd.DataFrame({"RLS parameter GLRT median delay (s)": drift.groupby("sensor", sort=False)["delay"].median(),
                        "detected": drift.groupby("sensor", sort=False)["delay"].count(),
                        "alarm before onset": drift.groupby("sensor", sort=False)["before_onset"].sum(),
                        "mean GLRT median delay (s)": mean_delay}).round(2).to_string())
    print(f"\ntotal {time.time() - t0:.0f} s")


if __name__ == "__main__":
    sys.exit(main())

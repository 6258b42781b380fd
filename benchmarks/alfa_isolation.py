"""Benchmark 2 of issue 20: isolation of airspeed-sensor faults on real ALFA flights (paper 002, Table 2).

Protocol
--------
Data: every flight of ``engine_commanded_measured`` (in ``../shared/data/alfa``, or the ALFA copy given by
``--data``) that carries a pitot airspeed (one not identically zero) and has its ``merged_20hz/engine`` counterpart,
sorted by name (:func:`pitot_flights`). In the shared copy these are four: carbonZ_2018-07-18-15-53-31_1 / _2 and
carbonZ_2018-07-30-16-39-00_1 / _2 (the three 2018-09-11 flights log an airspeed of exactly 0). The local-position
velocity of the same flights comes from ``merged_20hz/engine``; both are put on one 20 Hz grid by
:func:`tsfdi.datasets.align` (zero-order hold). Only the fault-free part is used: from ``SETTLE`` = 40 s after the
start of the log (the autopilot's wind estimate is still converging before) to the engine-failure onset: 76, 33, 77
and 52 s of flight in the shared copy.

Three airspeed estimates (paper 002, section 4.1):

- ``pitot``: the logged airspeed, into which the faults are injected;
- ``gps2air``: :func:`tsfdi.isolation.airspeed_from_gps` (eqs. 4-6) from the ground velocity and the autopilot's
  wind estimate (mavros reports the direction the wind comes from), with the climb rate added (eq. 4 is 2-D), the
  scale ``a`` (eq. 5) and the delay to the pitot reading fitted on the training flights;
- ``thrust``: ALFA logs no propeller speed, so the closest substitute for paper 002's thrust observer: a linear
  model of the airspeed in the low-passed throttle, pitch, climb rate and bank angle (time constants 1, 3, 10 s),
  fitted on the training flights.

Residuals and tests: R1 = pitot - gps2air, R2 = pitot - thrust, R3 = gps2air - thrust
(:func:`tsfdi.isolation.airspeed_parity`), each minus a self-tuned offset (exponential forgetting) whose adaptation
is halted while any residual alarms (paper 002: "setting adaptation on hold when a fault is detected"). One
:class:`tsfdi.GLRT` per residual with an :class:`tsfdi.EmpiricalThreshold` (paper 002, Fig. 2: the threshold is the
quantile of the healthy statistic for a required false-alarm probability), scale and threshold calibrated on the
training flights, armed ``ARM`` = 5 s after the monitoring starts. Validity domain: the parity relations assume
level flight (eq. 5's small angles); while the climb rate exceeds the *gate* (and 2 s after) the residuals carry no
evidence (0) and nothing adapts. A sensor counts as isolated when the fired residuals have matched its column of
Table 2 for *hold* samples (:meth:`tsfdi.isolation.IsolationSeries.confirmed`).

Settings fixed on training flights, results on held-out flights: leave-one-flight-out
-------------------------------------------------------------------------------------
Each flight is held out once; the others (three in the shared copy) are the training flights of that fold.

1. The *settings* -- GLRT window (50, 100, 200 samples), false-alarm probability per sample (1e-3, 5e-4 as in
   paper 002's Fig. 2, 2e-4), offset forgetting factor (0.995, 0.998, 0.999), level-flight gate (3 m/s, 5 m/s,
   none) and isolation hold (20, 40 samples), 162 combinations -- are chosen on the training flights: a monitor
   fitted and calibrated on them monitors each of them, fault-free and with every injected fault; the settings with
   the fewest false isolations (fault-free) plus wrong isolations (faults), then the most correct isolations, then
   the shortest median isolation delay, are kept.
2. The thrust model, the scale and delay of gps2air, the GLRT scales and thresholds are fitted on the training
   flights with those settings.
3. The held-out flight is monitored once, fault-free (false alarms, false isolations) and with every injected
   fault. Nothing of it is used before.

The choice in step 1 sees the training flights with thresholds calibrated on themselves: it favours sensitive
settings. A stricter protocol, printed second, chooses them by an inner leave-one-flight-out: each training flight
is monitored by a monitor fitted and calibrated on the two others. The thresholds fit an exponential tail to the
top 10 % of the healthy statistic (``TAIL``; default 5 %) and the false-alarm probabilities stop at 2e-4, so that
the two shortest flights (75 s together) suffice.

Fixed, not selected: the monitored segment (``SETTLE``), ``ARM``, the thrust model's inputs and time constants, the
fault scenarios. Faults (on the pitot reading, from ``start`` to the end of a 15 s evaluation horizon; a start every
5 s from 10 s into the monitored segment): ``bias+`` / ``bias-``: a step of +-5 m/s; ``drift``: -0.5 m/s per second
(:func:`tsfdi.datasets.faults.inject_fault`); ``clog``: a clogging pitot port, the dynamic pressure falling linearly
to zero in 20 s, ``v * sqrt(1 - t / 20 s)``. A fault is correctly isolated when the first confirmed isolation after
its start names the pitot within the horizon. A variant applies the same (selected) settings to smaller faults
(bias +-3 m/s, drift -0.3 m/s/s) on the held-out flights.

Caveats: the faults are injected after the flight, so the autopilot (which flew on the true pitot reading) does not
react to them, and the logged wind estimate, computed onboard from the true reading, does not absorb them. Four
flights from two days are few: the settings are chosen on three flights (two in the stricter protocol), and a
held-out flight shares its day (wind, trim) with one training flight.

Findings (this script's output): **issue 20's target (>= 95 % correct isolation, no false isolation on
fault-free flight) is not met.** With the settings chosen on the training flights, 108 of the 120 held-out faults
are isolated correctly (90.0 %), 12 are attributed to another sensor, and two of the four fault-free held-out
flights have a false isolation (one "pitot", one "thrust"); with the stricter inner choice, 28 of 120 (23.3 %):
fitted on two flights, the thrust model and the thresholds do not carry to the third. An earlier version of this
script, whose constants were chosen by looking at the leave-one-out results of all four flights, reported 116 of
120 without false isolation: that figure was not out of sample. Four flights are too few to choose the settings on
some and confirm them on another.

Run: ``python benchmarks/alfa_isolation.py [--data PATH]`` (about three minutes; ``--quick`` skips the stricter
protocol and the variant; ``--data``: an ALFA folder of the shared copy's layout, default ``../shared/data/alfa``).
"""

from __future__ import annotations

import argparse
import copy
import itertools
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import signal as sps

import tsfdi
from tsfdi.datasets import align, load_alfa
from tsfdi.datasets.faults import inject_fault
from tsfdi.isolation import IsolationSeries, airspeed_from_gps, airspeed_parity

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "alfa"
FS = 20.0
SETTLE = 40.0           # s from the start of the log: the wind estimate has converged
ARM = int(5.0 * FS)     # samples of offset adaptation before the tests are armed
HORIZON = int(15.0 * FS)  # samples of evaluation after a fault starts
STEP = int(5.0 * FS)    # samples between fault starts
TAUS = (1.0, 3.0, 10.0)  # s, low-pass time constants of the thrust model's inputs
KINDS = ("bias+", "bias-", "drift", "clog")
TAIL = 0.1              # tail fraction of the thresholds' exponential tail fit (see Monitor)
CHUNK = 400             # samples looked ahead at a time by the halted offset adaptation (any value gives the same)


@dataclass(frozen=True)
class Settings:
    """The constants chosen on training flights (see the module docstring)."""

    window: int             # GLRT window, samples
    false_alarm: float      # per sample and residual
    forgetting: float       # offset adaptation
    gate: float | None      # m/s: |climb rate| above which the parity relations are not evaluated
    hold: int               # samples an isolation must persist

    def __str__(self) -> str:
        gate = "none" if self.gate is None else f"{self.gate:g} m/s"
        return (f"window {self.window}, P_F {self.false_alarm:g}, forgetting {self.forgetting}, gate {gate}, "
                f"hold {self.hold}")


HOLDS = (20, 40)        # applied to the fired residuals after a run: every hold is scored from the same runs
GRID = [Settings(w, p, f, g, HOLDS[0]) for w, p, f, g in itertools.product(
    (50, 100, 200), (1e-3, 5e-4, 2e-4), (0.995, 0.998, 0.999), (3.0, 5.0, None))]


# ------------------------------------------------------------------------------------------------------ data
def pitot_flights(data: Path) -> list[str]:
    """The flights of ``data / "engine_commanded_measured"`` whose airspeed is not identically zero (a pitot
    reading) and that have a ``merged_20hz/engine`` counterpart (the ground velocity), sorted by name."""
    folder = data / "engine_commanded_measured"
    if not folder.is_dir():
        raise FileNotFoundError(f"ALFA data not found: {folder} (give the ALFA folder with --data; default "
                                "../shared/data/alfa)")
    out = []
    for path in sorted(folder.glob("*.csv.gz")):
        flight = path.name.removesuffix(".csv.gz")
        if (data / "merged_20hz" / "engine" / path.name).is_file() and load_alfa(path)["airspeed"].abs().max() > 0:
            out.append(flight)
    return out


def load(flight: str) -> pd.DataFrame:
    """The fault-free part of one flight on a 20 Hz grid."""
    ecm = load_alfa(DATA / "engine_commanded_measured" / f"{flight}.csv.gz")
    vel = load_alfa(DATA / "merged_20hz" / "engine" / f"{flight}.csv.gz")
    cols = ["airspeed", "wind_estimation_linear_x", "wind_estimation_linear_y", "throttle", "pitch_measured",
            "roll_measured", "climb"]
    grid = align({"e": ecm[cols], "v": vel[["field.twist.linear.x", "field.twist.linear.y"]].dropna()}, fs=FS,
                 max_gap="1s")
    if len(grid) != 1:
        raise ValueError(f"{flight}: the aligned record is split in {len(grid)} parts")
    a = grid[0].rename(columns=lambda c: c.split(".", 1)[1])
    t = (a.index - ecm.index[0]).total_seconds()
    return a[(t >= SETTLE) & (a.index < ecm.attrs["onset_time"])]


def lowpass(x: np.ndarray, tau: float) -> np.ndarray:
    """First-order low-pass filter (time constant ``tau`` s), started at the first value."""
    alpha = 1.0 / (tau * FS)
    y, _ = sps.lfilter([alpha], [1.0, alpha - 1.0], x, zi=[(1.0 - alpha) * x[0]])
    return y


def thrust_inputs(a: pd.DataFrame) -> np.ndarray:
    cols = [np.ones(len(a))]
    for tau in TAUS:
        cols += [lowpass(a[c].to_numpy(), tau) for c in ("throttle", "pitch_measured", "climb")]
        cols.append(lowpass(np.abs(a["roll_measured"].to_numpy()), tau))
    return np.column_stack(cols)


def gps_airspeed(a: pd.DataFrame, scale: float = 1.0) -> np.ndarray:
    ve, vn = a["field.twist.linear.x"].to_numpy(), a["field.twist.linear.y"].to_numpy()
    wx, wy = a["wind_estimation_linear_x"].to_numpy(), a["wind_estimation_linear_y"].to_numpy()
    horizontal = airspeed_from_gps(np.hypot(ve, vn), np.arctan2(vn, ve), np.hypot(wx, wy), np.arctan2(-wy, -wx),
                                   scale=scale)
    return np.hypot(horizontal, scale * a["climb"].to_numpy())


def delayed(x: np.ndarray, k: int) -> np.ndarray:
    return np.concatenate([np.full(k, x[0]), x[:len(x) - k]]) if k else x


def inject(pitot: np.ndarray, kind: str, start: int, magnitude: float) -> np.ndarray:
    if kind in ("bias+", "bias-"):
        return inject_fault(pitot, "bias", magnitude if kind == "bias+" else -magnitude, start, sensor_range=1.0)[0]
    if kind == "drift":             # -magnitude / 10 m/s per second
        return inject_fault(pitot, "drift", -magnitude, start, ramp=int(10 * FS), sensor_range=1.0)[0]
    t = np.maximum(np.arange(pitot.size) - start + 1, 0) / FS     # clogging: dynamic pressure to 0 in 20 s
    return pitot * np.sqrt(np.clip(1.0 - t / 20.0, 0.0, 1.0))


# ------------------------------------------------------------------------------------------------ monitoring
class Fit:
    """The estimators fitted on training flights: thrust model, scale and delay of gps2air."""

    def __init__(self, train: list[pd.DataFrame]) -> None:
        pitot = np.concatenate([a["airspeed"].to_numpy() for a in train])
        self.coef = np.linalg.lstsq(np.vstack([thrust_inputs(a) for a in train]), pitot, rcond=None)[0]
        gps = np.concatenate([gps_airspeed(a) for a in train])
        self.scale = float(gps @ pitot / (gps @ gps))

        def spread(lag: int) -> float:          # variance of pitot - delayed gps2air around a 20 s mean
            out = 0.0
            for a in train:
                r = a["airspeed"].to_numpy() - delayed(gps_airspeed(a, self.scale), lag)
                out += np.var(r - pd.Series(r).ewm(span=400).mean().to_numpy())
            return out

        self.lag = min(range(0, 41, 2), key=spread)
        self._cache: dict = {}
        self._parity = airspeed_parity()

    def residuals(self, a: pd.DataFrame, pitot: np.ndarray | None = None) -> np.ndarray:
        """Raw parity residuals R1, R2, R3 (before the offsets); the flight's own pitot reading by default."""
        key = id(a)
        if key not in self._cache:           # the estimates that do not depend on the pitot reading
            self._cache[key] = (delayed(gps_airspeed(a, self.scale), self.lag), thrust_inputs(a) @ self.coef)
        gps2air, thrust = self._cache[key]
        pitot = a["airspeed"].to_numpy() if pitot is None else pitot
        est = pd.DataFrame({"pitot": pitot, "gps2air": gps2air[:len(pitot)], "thrust": thrust[:len(pitot)]})
        return self._parity.residuals(est).to_numpy()


def level(a: pd.DataFrame, gate: float | None) -> np.ndarray:
    """Samples inside the level-flight domain (causal: the gate holds 2 s after the climb rate falls back)."""
    n = len(a)
    if gate is None:
        return np.ones(n, dtype=bool)
    steep = (np.abs(a["climb"].to_numpy()) > gate).astype(float)
    return np.convolve(steep, np.ones(int(2 * FS) + 1))[:n] == 0


def adapt(raw: np.ndarray, valid: np.ndarray, offset: np.ndarray, gain: float) -> np.ndarray:
    """Offsets before every sample of ``raw`` (and after the last, ``len(raw) + 1`` rows) of the recursion
    ``o <- o + gain (raw - o)`` on the valid samples (held on the others), in closed form per block:
    ``o[i] = P[i] (o[0] + sum_{j < i} b[j] / P[j + 1])``, ``P`` the running product of ``1 - gain * valid``."""
    out = [offset[None, :]]
    for s in range(0, len(raw), CHUNK):            # blocks keep 1 / P <= (1 - gain) ** -CHUNK
        v = valid[s:s + CHUNK, None]
        prod = np.cumprod(1.0 - gain * v, axis=0)
        o = prod * (out[-1][-1] + np.cumsum(gain * v * raw[s:s + CHUNK] / prod, axis=0))
        out.append(o)
    return np.concatenate(out)


class Run:
    """The state of one monitored record: offsets adapting except while a residual alarms (from ``ARM`` on).

    :meth:`advance` gives exactly the sample-by-sample loop (residual minus offset, one GLRT per residual, the
    offsets halted on an alarm) but evaluates the tests on blocks: it assumes that the alarm state of the last
    sample holds, computes the block's residuals and GLRT statistics (the statistic of a sample depends on the
    last ``window`` residuals only), and keeps the samples up to the first one whose alarm state differs; the
    offset after it follows that sample's true state.
    """

    def __init__(self, parity: tsfdi.isolation.ResidualSet, gain: float, raw: np.ndarray) -> None:
        self.gain = gain
        self.tests = [parity.tests[n] for n in parity.names]
        self.thresholds = np.array([t.threshold_ for t in self.tests])
        self.offset = raw[:int(2 * FS)].mean(axis=0)
        self.alarm = False
        self.k = 0
        self.recent = np.zeros((0, len(self.tests)))   # the last window - 1 residuals fed to the tests
        self.fired: list[np.ndarray] = []              # rows from ARM on

    def advance(self, raw: np.ndarray, valid: np.ndarray, stop: int) -> None:
        while self.k < stop:
            k = self.k
            end = min(stop, k + CHUNK) if k >= ARM else min(stop, ARM)
            if self.alarm:
                offsets = np.repeat(self.offset[None, :], end - k + 1, axis=0)
            else:
                offsets = adapt(raw[k:end], valid[k:end], self.offset, self.gain)
            out = np.where(valid[k:end, None], raw[k:end] - offsets[:-1], 0.0)
            if k < ARM:                                  # not armed: no alarm, the offsets adapt
                self.offset, self.k = offsets[-1], end
                continue
            x = np.concatenate([self.recent, out])
            g = np.column_stack([t.statistic(x[:, c]) for c, t in enumerate(self.tests)])[len(self.recent):]
            fired = g > self.thresholds
            alarm = fired.any(axis=1)
            flip = np.flatnonzero(alarm != self.alarm)
            n = int(flip[0]) + 1 if flip.size else end - k
            kept = np.concatenate([self.recent, out[:n]])
            self.recent = kept[max(0, len(kept) - self.tests[0].window + 1):]
            last = k + n - 1
            o = offsets[n - 1]
            self.alarm = bool(alarm[n - 1])
            self.offset = o + self.gain * (raw[last] - o) if valid[last] and not self.alarm else o
            self.fired.append(fired[:n])
            self.k += n

    def copy(self) -> Run:
        """An independent copy (the rows kept so far are shared: they are never modified)."""
        new = copy.copy(self)
        new.fired = list(self.fired)
        return new

    def series(self, parity: tsfdi.isolation.ResidualSet, start: int = 0) -> IsolationSeries:
        """Isolation at every sample from row ``start`` of the armed rows on."""
        fired = np.concatenate(self.fired)[start:]
        pos = np.arange(len(fired))
        return IsolationSeries(fired, parity.names, parity.sensors, parity.incidence, pos, pos + 1)


class Monitor:
    """Residual tests of one fold with given settings, calibrated on the training flights."""

    def __init__(self, fit: Fit, settings: Settings, train: list[pd.DataFrame]) -> None:
        self.fit, self.settings = fit, settings
        self.gain = 1.0 - settings.forgetting
        # a tail fraction of 10 % (default 5 %): the exponential tail is fitted from 1000 samples on, so that the
        # two shortest training flights of an inner fold (75 s) can be calibrated
        threshold = tsfdi.EmpiricalThreshold(settings.false_alarm, tail_fraction=TAIL)
        self.parity = airspeed_parity(tsfdi.GLRT(settings.window, threshold=threshold))
        healthy = []
        for a in train:                             # offsets adapting throughout (no test yet)
            raw, valid = fit.residuals(a), level(a, settings.gate)
            out = np.where(valid[:, None], raw - adapt(raw, valid, raw[:int(2 * FS)].mean(axis=0), self.gain)[:-1],
                           0.0)
            healthy.append(out[ARM:])
        self.parity.calibrate(healthy)

    def flight(self, a: pd.DataFrame, magnitude: float, holds: tuple = HOLDS) -> tuple[dict, list[dict]]:
        """Monitor one flight fault-free and with every injected fault (each from the fault-free state at its
        start); returns the fault-free summary and one row per fault, with the isolation for every hold."""
        raw, valid = self.fit.residuals(a), level(a, self.settings.gate)
        run = Run(self.parity, self.gain, raw)
        starts = range(ARM + STEP, len(a) - HORIZON + 1, STEP)
        snapshots = {}
        for k0 in starts:
            run.advance(raw, valid, k0)
            snapshots[k0] = run.copy()
        run.advance(raw, valid, len(a))
        ser = run.series(self.parity)
        any_ = ser.fired.any(axis=1).astype(int)
        healthy = {"minutes": len(ser) / FS / 60, "alarm episodes": int(np.sum(np.diff(any_, prepend=0) == 1))}
        for h in holds:
            iso = ser.confirmed(h)
            healthy[f"false isolation {h}"] = "-" if iso is None else ser.labels[iso]
        faulty = []
        pitot = a["airspeed"].to_numpy()
        for k0, kind in itertools.product(starts, KINDS):
            stop = k0 + HORIZON
            fault = self.fit.residuals(a, inject(pitot[:stop], kind, k0, magnitude))
            r = snapshots[k0].copy()
            r.advance(fault, valid, stop)
            tail = r.series(self.parity, k0 - ARM)
            det = tail.first_detection
            row = {"kind": kind, "start_s": k0 / FS, "delay_s": np.nan if det is None else det / FS}
            for h in holds:
                iso = tail.confirmed(h)
                row[f"isolated {h}"] = None if iso is None else tail.labels[iso]
                row[f"isolation delay {h}"] = np.nan if iso is None else iso / FS
            faulty.append(row)
        return healthy, faulty


# ------------------------------------------------------------------------------------------------ protocol
def score(healthy: list[dict], faulty: list[dict], hold: int) -> tuple:
    """Selection key (smaller is better): false + wrong isolations, -correct isolations, median delay."""
    false = sum(h[f"false isolation {hold}"] != "-" for h in healthy)
    labels = [f[f"isolated {hold}"] for f in faulty]
    correct = sum(lab == "pitot" for lab in labels)
    wrong = sum(lab is not None and lab != "pitot" for lab in labels)
    delays = [f[f"isolation delay {hold}"] for f in faulty if f[f"isolated {hold}"] == "pitot"]
    return false + wrong, -correct, float(np.median(delays)) if delays else np.inf


def select(train: list[pd.DataFrame], magnitude: float, nested: bool) -> tuple[Settings, tuple]:
    """The settings chosen on the training flights: each monitored by a monitor fitted on all of them (``nested``
    False) or on the others (``nested`` True, leave-one-flight-out); see the module docstring."""
    results = {(s, h): ([], []) for s in GRID for h in HOLDS}
    for i in range(len(train)) if nested else [None]:
        fitted = [a for j, a in enumerate(train) if j != i]
        fit = Fit(fitted)
        for s in GRID:
            monitor = Monitor(fit, s, fitted)
            for a in [train[i]] if nested else train:
                healthy, faulty = monitor.flight(a, magnitude)
                for h in HOLDS:
                    results[(s, h)][0].append(healthy)
                    results[(s, h)][1].extend(faulty)
    keys = {(s, h): score(*results[(s, h)], h) for s, h in results}
    s, h = min(keys, key=keys.get)
    return Settings(s.window, s.false_alarm, s.forgetting, s.gate, h), keys[(s, h)]


def report(title: str, healthy: pd.DataFrame, faulty: pd.DataFrame) -> None:
    faulty = faulty.assign(correct=faulty["isolated"] == "pitot",
                           wrong=faulty["isolated"].notna() & (faulty["isolated"] != "pitot"))
    table = faulty.groupby("kind", sort=False).agg(
        scenarios=("correct", "size"), correct_isolation=("correct", "mean"), wrong_isolation=("wrong", "sum"),
        not_isolated=("isolated", lambda s: int(s.isna().sum())), median_delay_s=("delay_s", "median"),
        median_isolation_delay_s=("isolation_delay_s", "median"), max_isolation_delay_s=("isolation_delay_s", "max"))
    print(f"\n== {title}")
    print(table.round(3).to_string())
    print(f"all faults: {faulty['correct'].sum()} / {len(faulty)} correctly isolated "
          f"({100 * faulty['correct'].mean():.1f} %), {int(faulty['wrong'].sum())} wrong isolations, "
          f"{int(faulty['isolated'].isna().sum())} not isolated within {HORIZON / FS:g} s")
    print("fault-free held-out flights:")
    print(healthy.round(2).to_string(index=False))
    print(f"false isolations on fault-free flight: {int((healthy['false isolation'] != '-').sum())} in "
          f"{healthy['minutes'].sum():.1f} min; alarm episodes (detection, not isolated): "
          f"{int(healthy['alarm episodes'].sum())}")


def main(argv: list[str] | None = None) -> int:
    global DATA                     # load() reads the folder given by --data
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the main protocol only, without the variants")
    parser.add_argument("--data", type=Path, default=DATA, metavar="PATH",
                        help="the ALFA folder (engine_commanded_measured/, merged_20hz/); default ../shared/data/alfa")
    args = parser.parse_args(argv)
    DATA = args.data
    t0 = time.perf_counter()
    names = pitot_flights(DATA)
    if len(names) < 3:
        raise ValueError(f"{DATA}: {len(names)} engine flight(s) with a pitot airspeed and a merged_20hz counterpart "
                         f"{names}; the protocol needs at least 3 (two to fit, one held out)")
    flights = [load(f) for f in names]
    print("flights: " + ", ".join(f"{f[8:30]} ({len(a) / FS:.0f} s)" for f, a in zip(names, flights)))
    print(f"settings grid: {len(GRID) * len(HOLDS)} combinations; each flight held out once, the settings chosen "
          "on the others")
    protocols = [("settings chosen on the training flights (fitted, calibrated and faulted on them)", False)]
    if not args.quick:
        protocols.append(("stricter: settings chosen by leave-one-flight-out inside the training flights", True))
    for title, nested in protocols:
        print(f"\n#### {title}")
        magnitudes = [5.0] if nested or args.quick else [5.0, 3.0]
        tables = {m: ([], []) for m in magnitudes}
        for h, name in enumerate(names):
            train = [a for i, a in enumerate(flights) if i != h]
            settings, key = select(train, 5.0, nested)
            print(f"fold {h + 1}, held out {name[8:30]}: {settings} (on the training flights: {-key[1]} correct, "
                  f"{key[0]} false or wrong isolations)")
            monitor = Monitor(Fit(train), settings, train)
            for magnitude in magnitudes:
                healthy, faulty = monitor.flight(flights[h], magnitude, (settings.hold,))
                tables[magnitude][0].append({"flight": name[8:30], "minutes": healthy["minutes"],
                                             "alarm episodes": healthy["alarm episodes"],
                                             "false isolation": healthy[f"false isolation {settings.hold}"]})
                tables[magnitude][1].extend(
                    {"flight": h, "kind": f["kind"], "start_s": f["start_s"], "delay_s": f["delay_s"],
                     "isolated": f[f"isolated {settings.hold}"],
                     "isolation_delay_s": f[f"isolation delay {settings.hold}"]} for f in faulty)
        for magnitude in magnitudes:
            healthy, faulty = (pd.DataFrame(t) for t in tables[magnitude])
            report("held-out flights, " + ("bias +-5 m/s, drift -0.5 m/s/s, clogging to 0 in 20 s" if magnitude == 5
                                           else "same settings, smaller faults: bias +-3 m/s, drift -0.3 m/s/s, "
                                           "clogging unchanged"), healthy, faulty)
            if magnitude == 5.0:
                rate = (faulty["isolated"] == "pitot").mean()
                false = int((healthy["false isolation"] != "-").sum())
                print(f"issue 20 target (>= 95 % correct isolation, no false isolation on fault-free flight): "
                      f"{100 * rate:.1f} %, {false} false isolation(s): "
                      f"{'met' if rate >= 0.95 and false == 0 else 'NOT met'}")
    print(f"\nrun time {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

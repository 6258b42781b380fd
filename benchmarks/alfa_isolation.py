"""Benchmark 2 of issue 20: isolation of airspeed-sensor faults on real ALFA flights (paper 002, Table 2).

Protocol
--------
Data: the four ALFA flights of ``../shared/data/alfa/engine_commanded_measured`` that carry a pitot airspeed
(carbonZ_2018-07-18-15-53-31_1 / _2 and carbonZ_2018-07-30-16-39-00_1 / _2; the three 2018-09-11 flights log an
airspeed of exactly 0), with the local-position velocity of the same flights from ``merged_20hz/engine``, put on one
20 Hz grid by :func:`tsfdi.datasets.align` (zero-order hold). Only the fault-free part is used: from 40 s after the
start of the log (the autopilot's wind estimate is still converging before: 7.9 -> 2.4 m/s over the first 40 s of
07-18 _1) to the engine-failure onset: 76, 33, 77 and 52 s of flight.

Three airspeed estimates (paper 002, section 4.1):

- ``pitot``: the logged airspeed, into which the faults are injected;
- ``gps2air``: :func:`tsfdi.isolation.airspeed_from_gps` (eqs. 4-6) from the ground velocity and the autopilot's
  wind estimate (mavros reports the direction the wind comes from), with the climb rate added (eq. 4 is 2-D), the
  scale ``a`` (eq. 5) and the delay to the pitot reading fitted on the training flights;
- ``thrust``: ALFA logs no propeller speed, so the closest substitute for paper 002's thrust observer: a linear
  model of the airspeed in the low-passed throttle, pitch, climb rate and bank angle (time constants 1, 3, 10 s),
  fitted on the training flights.

Residual generation and tests: R1 = pitot - gps2air, R2 = pitot - thrust, R3 = gps2air - thrust
(:func:`tsfdi.isolation.airspeed_parity`), each minus a self-tuned offset (exponential forgetting 0.998, a memory of
25 s) whose adaptation is halted while any residual alarms (paper 002: "setting adaptation on hold when a fault is
detected"). One :class:`tsfdi.GLRT` per residual (window 100 samples = 5 s) with an
:class:`tsfdi.EmpiricalThreshold` at a false-alarm probability of 1e-4 per sample, scale and threshold calibrated
on the training flights. Validity domain: the parity relations assume level flight (eq. 5's small angles); while the
climb rate exceeds 5 m/s (and 2 s after) the residuals carry no evidence (0) and nothing adapts. A sensor counts as
isolated when the fired residuals have matched its column of Table 2 for 2 s (40 samples,
:meth:`tsfdi.isolation.IsolationSeries.confirmed`).

Settings fixed on training flights, results on held-out flights: leave-one-flight-out. For each flight, the thrust
model, the scale and delay of gps2air, the GLRT scales and thresholds are fitted on the three other flights; the
held-out flight is then monitored fault-free (false alarms, false isolations) and with every injected fault.

Faults (on the pitot reading, from ``start`` to the end of a 15 s evaluation horizon; a start every 5 s from 10 s
into the monitored segment): ``bias+`` / ``bias-``: a step of +-5 m/s; ``drift``: -0.5 m/s per second
(:func:`tsfdi.datasets.faults.inject_fault`); ``clog``: a clogging pitot port, the dynamic pressure falling linearly to
zero in 20 s, ``v * sqrt(1 - t / 20 s)``. A fault is correctly isolated when the first confirmed isolation after its
start names the pitot within the horizon.

Caveats: the faults are injected after the flight, so the autopilot (which flew on the true pitot reading) does not
react to them, and the logged wind estimate, computed onboard from the true reading, does not absorb them. The design
constants (window, forgetting factor, false-alarm rate, gate, 2 s confirmation) were chosen by looking at the
leave-one-out results of all four flights: only the fitted quantities above are clean out-of-sample. The variants
printed after the main table show what the gate and the fault size do.

Run: ``python benchmarks/alfa_isolation.py`` (about a minute).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import signal as sps

import tsfdi
from tsfdi.datasets import align, load_alfa
from tsfdi.datasets.faults import inject_fault
from tsfdi.isolation import airspeed_from_gps, airspeed_parity

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "alfa"
FLIGHTS = ("carbonZ_2018-07-18-15-53-31_1_engine_failure", "carbonZ_2018-07-18-15-53-31_2_engine_failure",
           "carbonZ_2018-07-30-16-39-00_1_engine_failure", "carbonZ_2018-07-30-16-39-00_2_engine_failure")
FS = 20.0
SETTLE = 40.0           # s from the start of the log: the wind estimate has converged
ARM = 5.0               # s of offset adaptation before the tests are armed
HORIZON = 15.0          # s of evaluation after a fault starts
STEP = 5.0              # s between fault starts
WINDOW = 100            # GLRT window, samples (5 s)
FALSE_ALARM = 1e-4      # per sample and residual
FORGETTING = 0.998      # offset adaptation (memory 1 / (1 - lambda) = 500 samples = 25 s)
GATE = 5.0              # m/s: |climb rate| above which the parity relations are not evaluated
HOLD = 40               # samples an isolation must persist (2 s)
TAUS = (1.0, 3.0, 10.0)  # s, low-pass time constants of the thrust model's inputs
KINDS = ("bias+", "bias-", "drift", "clog")


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


class Monitor:
    """The residual generators and tests of one fold, fitted on the training flights."""

    def __init__(self, train: list[pd.DataFrame], gate: float | None) -> None:
        self.gate = gate
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
        self.parity = airspeed_parity(tsfdi.GLRT(WINDOW, threshold=tsfdi.EmpiricalThreshold(FALSE_ALARM)))
        arm = int(ARM * FS)
        self.parity.calibrate([self.errors(a, a["airspeed"].to_numpy())[arm:] for a in train])

    def errors(self, a: pd.DataFrame, pitot: np.ndarray, streams: list | None = None) -> pd.DataFrame:
        """Offset-corrected residuals; the offsets adapt except while a residual alarms (``streams``: the GLRT of
        every residual, fed from the arming time on) and outside the level-flight domain."""
        est = pd.DataFrame({"pitot": pitot, "gps2air": delayed(gps_airspeed(a, self.scale), self.lag),
                            "thrust": thrust_inputs(a) @ self.coef}, index=a.index)
        raw = self.parity.residuals(est).to_numpy()
        n = raw.shape[0]
        valid = np.ones(n, dtype=bool)
        if self.gate is not None:                 # causal: the gate holds 2 s after the climb rate falls back
            steep = (np.abs(a["climb"].to_numpy()) > self.gate).astype(float)
            valid = np.convolve(steep, np.ones(int(2 * FS) + 1))[:n] == 0
        offset = raw[:int(2 * FS)].mean(axis=0)
        gain = 1.0 - FORGETTING
        arm = int(ARM * FS)
        out = np.zeros_like(raw)
        for k in range(n):
            if valid[k]:
                out[k] = raw[k] - offset
            alarm = False
            if streams is not None and k >= arm:
                for c, stream in enumerate(streams):
                    stream.update(out[k, c])
                    alarm |= stream.alarm
            if valid[k] and not alarm:
                offset = offset + gain * (raw[k] - offset)
        return pd.DataFrame(out, index=a.index, columns=list(self.parity.names))

    def run(self, a: pd.DataFrame, pitot: np.ndarray) -> tsfdi.isolation.IsolationSeries:
        """Monitor one record; rows of the result start at the arming time."""
        streams = [self.parity.tests[n].stream() for n in self.parity.names]
        e = self.errors(a, pitot, streams)
        return self.parity.isolate_samples(e.iloc[int(ARM * FS):])


def inject(pitot: np.ndarray, kind: str, start: int, magnitude: float) -> np.ndarray:
    if kind in ("bias+", "bias-"):
        return inject_fault(pitot, "bias", magnitude if kind == "bias+" else -magnitude, start, sensor_range=1.0)[0]
    if kind == "drift":             # -magnitude / 10 m/s per second
        return inject_fault(pitot, "drift", -magnitude, start, ramp=int(10 * FS), sensor_range=1.0)[0]
    t = np.maximum(np.arange(pitot.size) - start + 1, 0) / FS     # clogging: dynamic pressure to 0 in 20 s
    return pitot * np.sqrt(np.clip(1.0 - t / 20.0, 0.0, 1.0))


def episodes(fired: np.ndarray) -> int:
    """Alarm episodes: maximal stretches of samples where some residual fired."""
    any_ = fired.any(axis=1).astype(int)
    return int(np.sum(np.diff(np.concatenate([[0], any_])) == 1))


def evaluate(flights: list[pd.DataFrame], magnitude: float, gate: float | None,
             held_out: list[int] | None = None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Leave-one-flight-out: the fault-free run and every fault scenario of each held-out flight (default all)."""
    arm = int(ARM * FS)
    healthy, faulty = [], []
    for h in range(len(flights)) if held_out is None else held_out:
        test = flights[h]
        mon = Monitor([a for i, a in enumerate(flights) if i != h], gate)
        ser = mon.run(test, test["airspeed"].to_numpy())
        iso = ser.confirmed(HOLD)
        healthy.append({"flight": FLIGHTS[h][8:30], "minutes": len(ser) / FS / 60,
                        "alarm episodes": episodes(ser.fired),
                        "false isolations": int(iso is not None),
                        "isolated": "-" if iso is None else ser.labels[iso]})
        starts = np.arange(int((ARM + STEP) * FS), len(test) - int(HORIZON * FS) + 1, int(STEP * FS))
        for k0 in starts:
            rec = test.iloc[:k0 + int(HORIZON * FS)]
            for kind in KINDS:
                ser = mon.run(rec, inject(rec["airspeed"].to_numpy(), kind, int(k0), magnitude))
                after = k0 - arm                           # the fault's first row in ser
                det = np.flatnonzero(ser.fired[after:].any(axis=1))
                tail = tsfdi.isolation.IsolationSeries(ser.fired[after:], ser.names, ser.sensors, ser.incidence,
                                                       ser.starts[after:], ser.stops[after:])
                iso = tail.confirmed(HOLD)
                before = ser.fired[:after].any()
                faulty.append({"flight": h, "kind": kind, "start_s": k0 / FS,
                               "delay_s": det[0] / FS if det.size else np.nan,
                               "isolation_delay_s": iso / FS if iso is not None else np.nan,
                               "isolated": None if iso is None else tail.labels[iso],
                               "alarm_before_fault": bool(before)})
    return pd.DataFrame(healthy), pd.DataFrame(faulty)


def report(title: str, healthy: pd.DataFrame, faulty: pd.DataFrame) -> None:
    faulty = faulty.assign(correct=faulty["isolated"] == "pitot",
                           wrong=faulty["isolated"].notna() & (faulty["isolated"] != "pitot"))
    table = faulty.groupby("kind", sort=False).agg(
        scenarios=("correct", "size"), correct_isolation=("correct", "mean"), wrong_isolation=("wrong", "sum"),
        not_isolated=("isolated", lambda s: int(s.isna().sum())), median_delay_s=("delay_s", "median"),
        median_isolation_delay_s=("isolation_delay_s", "median"), max_isolation_delay_s=("isolation_delay_s", "max"))
    total = faulty["correct"].mean()
    print(f"\n== {title}")
    print(table.round(3).to_string())
    print(f"all faults: {faulty['correct'].sum()} / {len(faulty)} correctly isolated ({100 * total:.1f} %), "
          f"{int(faulty['wrong'].sum())} wrong isolations, {int(faulty['isolated'].isna().sum())} not isolated "
          f"within {HORIZON:g} s")
    print("fault-free held-out flights:")
    print(healthy.round(2).to_string(index=False))
    print(f"false isolations on fault-free flight: {int(healthy['false isolations'].sum())} in "
          f"{healthy['minutes'].sum():.1f} min; alarm episodes (detection, not isolated): "
          f"{int(healthy['alarm episodes'].sum())}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the main configuration only, without the variants")
    args = parser.parse_args(argv)
    if not DATA.is_dir():
        raise FileNotFoundError(f"ALFA data not found: {DATA} (the benchmark needs ../shared/data/alfa)")
    t0 = time.perf_counter()
    flights = [load(f) for f in FLIGHTS]
    print("held-out flights (leave-one-out): " + ", ".join(
        f"{f[8:30]} ({len(a) / FS:.0f} s)" for f, a in zip(FLIGHTS, flights)))
    runs = [("main: bias +-5 m/s, drift -0.5 m/s/s, clogging to 0 in 20 s; level-flight gate", 5.0, GATE)]
    if not args.quick:
        runs += [("variant: without the level-flight gate", 5.0, None),
                 ("variant: smaller faults, bias +-3 m/s, drift -0.3 m/s/s (clogging unchanged)", 3.0, GATE)]
    for title, magnitude, gate in runs:
        healthy, faulty = evaluate(flights, magnitude, gate)
        report(title, healthy, faulty)
    print(f"\nrun time {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

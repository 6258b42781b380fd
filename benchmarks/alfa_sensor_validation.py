"""Paper 004's sensor-validation protocol on real ALFA flights: the pitch-rate gyro, injected faults, MT / UD / FA.

Run: ``python benchmarks/alfa_sensor_validation.py`` (reads ``../shared/data/alfa`` next to the repository; about a
minute). Samy, Postlethwaite, Gu (paper 004) validate the pitch gyro of a simulated UAV with an online EMRAN network
that predicts it from other signals, the moving average of squared prediction errors (eq. 6) with and without
residual padding, and six injected faults (constant bias, hard and soft additive at 5 % and 20 % of the sensor
range) under three sensor-noise configurations; Tables 2-3 give the mean detection time (MT), the undetected faults
(UD) and the false alarms (FA, % of the fault-free time above the threshold). This script runs the same protocol on
real flights, with three models side by side.

Signals (20 Hz ``merged_20hz`` copies)
--------------------------------------
* Validated sensor: the pitch-rate gyro ``field.angular_velocity.y`` (rad/s).
* Model inputs, the analogues of paper 004's eq. 1 (:math:`\\alpha, \\delta_e, V_t, a_z / V_t^2`): the normal
  specific force :math:`f_z` (``field.linear_acceleration.z``), the speed :math:`V` (norm of the local-position
  velocity ``field.twist.linear``; airspeed is not in this copy), :math:`f_z / V^2` (:math:`V` floored at 5 m/s),
  the pitch tracking error ``delta_pitch`` (commanded minus measured pitch: the autopilot turns it into the elevator
  demand, the stand-in for :math:`\\delta_e`; angle of attack is not logged), and the yaw-rate magnitude
  ``|field.angular_velocity.z|`` (in a coordinated turn the body pitch rate is :math:`\\dot\\psi \\sin\\phi`, so the
  turns that :math:`f_z` alone cannot tell from a pull-up show in the yaw gyro). Never used: the gyro itself or its
  copy ``field.twist.angular.y`` (paper 004 leaves the pitch rate out of the inputs "to avoid contaminating the NN
  structure when a fault is present", so every model here has no autoregressive term), and the attitude quaternion,
  which the autopilot's filter computes from the gyros (a real gyro fault would leak into it; in this copy it would
  carry the fault-free rate). Caveat: ``delta_pitch`` contains the measured pitch, which comes from that filter
  too, as paper 004's elevator demand comes from a controller that uses the pitch gyro; it is kept as the paper
  keeps :math:`\\delta_e`. All inputs and the gyro are standardised with the training flights' mean and standard
  deviation.

Flights (settings fixed on training flights, results on held-out flights)
-------------------------------------------------------------------------
* Training flights: the 9 flights without failure, in ``flights.csv`` order; the 1st, 3rd, 5th, 7th and 9th
  *train* the models (``TRAIN``), the 2nd, 4th, 6th and 8th *calibrate* (``CALIBRATION``): the thresholds and the
  choice among the online-learning variants below are made on them (with faults injected into them for the
  choice), never on a held-out flight.
* Held-out flights: the 36 flights with a real failure, only their part before the failure onset (fault-free), the
  first ``RECORD_S`` = 45 s of it (every onset is after 49 s). A fault is injected at ``FAULT_AT_S`` = 30 s and lasts
  to the end of the record (15 s); FA is counted over the samples before 30 s that have a complete window.
* Sensor range (the 5 % and 20 % refer to it): the range (max - min) of the gyro over the training flights,
  0.98 rad/s (56 deg/s; paper 004: 30 deg/s).

Faults (``tsfdi.datasets.inject_fault``): ``bias`` (constant bias, a step), ``hard`` (ramp over 1 s), ``soft`` (ramp
over 4 s), at 5 % and 20 % of the range, positive.

Noise configurations. Paper 004's configurations 2 and 3 have twice and ten times the sensor-noise standard
deviation of configuration 1. Here configuration 1 is the flights as measured; the gyro's measured noise
:math:`\\sigma_0` is estimated on the training flights as the median over flights of the robust (MAD) standard
deviation of the second differences of the gyro at its update instants, divided by :math:`\\sqrt 6` (0.042 rad/s:
it includes turbulence and manoeuvres, the gyro updates at about 2.6 Hz in this copy); configurations 2 and 3 add white Gaussian
noise of standard deviation :math:`\\sqrt{k^2 - 1}\\,\\sigma_0` (k = 2, 10) to every 20 Hz gyro sample of every
flight (training ones included: thresholds are recalibrated per configuration), seeded per flight.

Models (all predict the standardised gyro from the standardised inputs at the same instant)
-----------------------------------------------------------------------------------------
* ``EMRAN`` (``tsfdi.EMRAN``, EKF, library defaults except ``error_threshold=0.3, rms_threshold=0.15,
  distance_threshold=2.0, measurement_noise=1.0``: among 24 settings measured while writing this script --
  error_threshold 0.3 / 0.6, distance_threshold 0.5 / 1 / 2, measurement_noise 0.1 / 1, overlap 0.8 / 2 -- the
  smallest prediction error of the network frozen after training, on the calibration flights), trained online by
  ``EPOCHS`` = 3 passes over the training flights (paper 004 trains offline first), then continuing online on each
  flight.
* ``RecursiveARX``: ``na = 0``, one coefficient per input, a constant, ``P0 = 100``, trained online on the training
  flights, then continuing on each flight.
* ``ARX``: the same structure fitted by least squares on the training flights (stacked records), fixed.

Online learning during the tested flights is what lets a model absorb a fault before it is detected (paper 004,
section VIII: a high learning rate learns slow drifts). Each online model therefore has variants, and the one with
the fewest undetected faults (then the shortest MT) on the calibration flights (faults injected at 20 s, config 1,
no padding) is used on the held-out flights: EMRAN continuing its EKF, following paper 004's eq. 5 with learning
rate 1e-3 (the winner's and the bias's gradient step, no growth change), or frozen (paper 004 stops training at a
detection); RecursiveARX with forgetting 0.999, 0.9999 or 1.

Residual evaluation (``tsfdi.detection.moving.MovingSquaredError``): window ``WINDOW`` = 20 samples (1 s), weight 1,
without padding and with ``padding = window`` (paper 004, section VIII: "an artificial data set of size D"). The
threshold of each model, padding and configuration is the largest value of the statistic on the calibration flights
(no alarm on them by construction).

Output: per scenario (configuration x fault) and model, MT (s, mean over the detected faults of the 36 flights),
UD (out of 36) and FA (%, pooled over the 36 flights), with and without padding, beside paper 004's Table 3 (its
detection times with padding; one fault per scenario); then the per-configuration summary beside Table 2. The
acceptance targets of issue 20 (best model, with padding: FA 0 %, UD 0, MT <= 1.3 s) are checked and printed.

Findings (measured, run of this script; 5-15 s)
------------------------------------------------
* **The targets are not met by any model.** With padding, configuration 1: the 20 % faults are all detected by
  RecursiveARX and ARX (hard 1.53 / 1.41 s, soft 3.87 / 3.36 s, bias 0.80 / 0.75 s; UD 0 of 36 each) with FA
  0.29 % / 0.66 %; the 5 % faults are not (UD 30-32 of 36; the few "detections", at ~3.4 s, are alarms that fall
  inside the fault by chance). At 10 times the measured noise (configuration 3) no fault is detected reliably
  (UD 31-35 of 36 per scenario). Paper 004 (Table 2, with padding): UD 0, FA 0 %, MT 1.30-1.53 s.
* Why: the best fault-free prediction of this gyro from the other logged signals has an RMS error of about
  0.060 rad/s on the held-out flights (batch ARX; 0.064 for the frozen EMRAN), more than the 5 % fault (0.049
  rad/s); the errors decorrelate within one gyro update (0.4 s), so a 1 s window averages only about three
  independent errors. Paper 004's simulated network reaches 0.0075 rad/s (0.43 deg/s) against a 5 % fault of
  1.5 deg/s. Its thresholds are 0.001 / 0.006 rad^2/s^2 without / with padding; here 0.015-0.04 (0.23 at ten
  times the noise).
* Online learning absorbs faults: an EMRAN that keeps growing units and adapting by EKF while the fault is present
  learns it (UD 17 of 24 on the calibration flights, 157 of 216 held-out faults with padding in configuration 1);
  frozen, it predicts worse than the linear models (UD 21 of 24). RecursiveARX with forgetting 0.999 is the
  chosen variant (its single constant and five input gains cannot follow a step in 1 s). This is paper 004's own
  warning about learning rates (section VIII).
* Padding does what paper 004 says on the 20 % faults (RecursiveARX, configuration 1: hard 1.76 -> 1.53 s and
  UD 2 -> 0, soft UD 0, bias 0.93 -> 0.80 s with UD 1 -> 0), but it does not remove the false alarms on held-out
  flights: the thresholds, set to the largest value on the four calibration flights, are exceeded on other flights
  (FA 0.3-0.9 %).
"""

import os

os.environ["OPENBLAS_NUM_THREADS"] = "1"

import copy  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from tsfdi.datasets.alfa import list_alfa, load_alfa  # noqa: E402
from tsfdi.datasets.faults import inject_fault  # noqa: E402
from tsfdi.detection.moving import MovingSquaredError  # noqa: E402
from tsfdi.evaluation import sensor_validation_metrics  # noqa: E402
from tsfdi.models import ARX, EMRAN, RecursiveARX  # noqa: E402

ROOT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "alfa"
FS = 20.0
GYRO = "field.angular_velocity.y"
INPUTS = ["fz", "V", "fz_V2", "delta_pitch", "abs_r"]
RECORD_S, FAULT_AT_S = 45.0, 30.0
WINDOW = 20
EPOCHS = 3
EMRAN_OPTIONS = dict(error_threshold=0.3, rms_threshold=0.15, distance_threshold=2.0, measurement_noise=1.0)
FAULTS = [("hard", 0.20), ("hard", 0.05), ("soft", 0.20), ("soft", 0.05), ("bias", 0.20), ("bias", 0.05)]
CONFIGS = {1: 1.0, 2: 2.0, 3: 10.0}          # total gyro noise std in units of the measured noise
MODELS = ["EMRAN", "RecursiveARX", "ARX"]
EMRAN_VARIANTS = {"EKF": None, "eq. 5, rate 1e-3": 1e-3, "frozen": 0.0}
RARX_VARIANTS = {"forgetting 0.999": 0.999, "forgetting 0.9999": 0.9999, "forgetting 1": 1.0}
#: paper 004, Table 3 (with padding): detection time (s) per configuration and fault
PAPER_TABLE3 = {1: [1.17, 1.42, 1.52, 1.70, 1.00, 1.00], 2: [1.20, 1.42, 1.58, 1.71, 1.00, 1.00],
                3: [1.36, 1.58, 2.06, 2.18, 1.00, 1.00]}
#: paper 004, Table 2: (MT s, UD, FA %) without and with padding per configuration
PAPER_TABLE2 = {1: ((0.72, 2, 0.10), (1.30, 0, 0.0)), 2: ((0.77, 2, 0.09), (1.32, 0, 0.0)),
                3: ((0.79, 2, 0.14), (1.53, 0, 0.0))}


# ------------------------------------------------------------------------------------------------------ data
def flight_frame(path, onset_s=None):
    """Gyro and inputs of one flight (up to the failure onset), leading / trailing incomplete rows dropped."""
    df = load_alfa(path)
    speed = np.sqrt(sum(df[f"field.twist.linear.{c}"] ** 2 for c in "xyz")).clip(lower=5.0)
    fz = df["field.linear_acceleration.z"]
    out = pd.DataFrame({"q": df[GYRO], "fz": fz, "V": speed, "fz_V2": fz / speed ** 2,
                        "delta_pitch": df["delta_pitch"], "abs_r": df["field.angular_velocity.z"].abs()})
    if onset_s is not None and np.isfinite(onset_s):
        out = out.iloc[:int(round(onset_s * FS))]
    ok = out.notna().all(axis=1).to_numpy()
    return out.iloc[int(np.argmax(ok)):len(ok) - int(np.argmax(ok[::-1]))]


def setup(root=ROOT):
    """Training, calibration and held-out flights (raises FileNotFoundError without the ALFA copy)."""
    table = list_alfa(root)
    clean = table[table["fault"] == "none"].reset_index(drop=True)
    failed = table[table["fault"] != "none"].reset_index(drop=True)
    train = [flight_frame(p) for p in clean["merged_path"][0::2]]
    calibration = [flight_frame(p) for p in clean["merged_path"][1::2]]
    n = int(RECORD_S * FS)
    held = [flight_frame(p, o).iloc[:n] for p, o in zip(failed["merged_path"], failed["onset_s"])]
    if min(len(h) for h in held) < n:
        raise ValueError(f"a held-out flight has less than {RECORD_S} s before its failure onset")
    return train, calibration, held


def measured_noise(frames):
    """Median over flights of the robust std of the gyro's second differences at its update instants / sqrt(6)."""
    out = []
    for f in frames:
        q = f["q"].to_numpy()
        qu = q[np.r_[True, np.diff(q) != 0]]
        d2 = np.diff(qu, 2)
        out.append(1.4826 * np.median(np.abs(d2 - np.median(d2))) / np.sqrt(6.0))
    return float(np.median(out))


class Scaler:
    """Standardisation with the training flights' statistics."""

    def __init__(self, frames):
        allf = pd.concat(frames)
        self.mx, self.sx = allf[INPUTS].mean(), allf[INPUTS].std()
        self.my, self.sy = allf["q"].mean(), allf["q"].std()

    def x(self, frame):
        return ((frame[INPUTS] - self.mx) / self.sx).to_numpy()

    def y(self, q):
        return (np.asarray(q) - self.my) / self.sy


# ---------------------------------------------------------------------------------------------------- models
def train_models(train, sc):
    """The three models after training on the training flights (clean gyro)."""
    net = EMRAN(len(INPUTS), **EMRAN_OPTIONS)
    for _ in range(EPOCHS):
        for f in train:
            net.run(sc.x(f), sc.y(f["q"]))
    rarx = {name: RecursiveARX(0, 1, 0, lam, P0=1e2, n_inputs=len(INPUTS), trend="c")
            for name, lam in RARX_VARIANTS.items()}
    for m in rarx.values():
        for f in train:
            m.run(sc.y(f["q"]), sc.x(f))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arx = ARX([sc.y(f["q"]) for f in train], [sc.x(f) for f in train], 0, 1, 0, trend="c").fit()
    return net, rarx, arx


def errors(model, variant, frame, q, sc):
    """A-priori prediction errors (rad/s) of ``model`` on one flight with gyro ``q`` (a copy of an online model
    continues from its trained state)."""
    x, y = sc.x(frame), sc.y(q)
    if isinstance(model, EMRAN):
        net = copy.deepcopy(model)
        if variant == 0.0:
            net.freeze()
        elif variant is not None:
            net.learning_rate = variant         # paper 004's eq. 5 for the online phase
        e = net.run(x, y).resid
    elif isinstance(model, RecursiveARX):
        e = copy.deepcopy(model).run(y, x).resid
    else:
        e = model.residuals(y, x)
    return np.asarray(e) * sc.sy


def gyro(frame, k, sigma0, seed):
    """The gyro of a flight with the configuration's added white noise (total std k * sigma0)."""
    q = frame["q"].to_numpy()
    if k == 1.0:
        return q
    return q + np.sqrt(k * k - 1.0) * sigma0 * np.random.default_rng(seed).standard_normal(q.size)


def evaluate(model, variant, frames, seeds, k, sigma0, sc, padding, threshold, fault_at, sensor_range):
    """MT / UD / FA of one model over flights, per fault (with the statistic's threshold given)."""
    det = MovingSquaredError(WINDOW, threshold, padding=padding)
    rows = {}
    for kind, mag in FAULTS:
        alarms, labels = [], []
        for f, s in zip(frames, seeds):
            q, lab = inject_fault(gyro(f, k, sigma0, s), kind, mag, int(fault_at * FS), sensor_range=sensor_range,
                                  fs=FS)
            alarms.append(np.asarray(det.test(errors(model, variant, f, q, sc)).details["alarm"]))
            labels.append(lab)
        rows[(kind, mag)] = sensor_validation_metrics(alarms, labels, times=[np.arange(len(a)) / FS for a in alarms])
    return rows


def threshold(model, variant, frames, seeds, k, sigma0, sc, padding):
    """Largest statistic on fault-free flights."""
    det = MovingSquaredError(WINDOW, padding=padding)
    return max(float(np.nanmax(np.asarray(det.statistic(errors(model, variant, f, gyro(f, k, sigma0, s), sc)))))
               for f, s in zip(frames, seeds))


def choose(model, variants, calibration, cal_seeds, sigma0, sc, sensor_range):
    """The variant with the fewest undetected faults, then the shortest MT, on the calibration flights."""
    best = None
    for name, v in variants.items():
        m = model[name] if isinstance(model, dict) else model
        thr = threshold(m, v, calibration, cal_seeds, 1.0, sigma0, sc, 0)
        res = evaluate(m, v, calibration, cal_seeds, 1.0, sigma0, sc, 0, thr, 20.0, sensor_range)
        ud = sum(r["UD"] for r in res.values())
        mt = np.nanmean([r["MT"] for r in res.values()])
        print(f"    {name:<20} calibration: UD {ud:>2} / {6 * len(calibration)}, mean MT {mt:.2f} s")
        if best is None or (ud, mt) < best[:2]:
            best = (ud, mt, name, m, v)
    return best[2], best[3], best[4]


def fmt(m):
    mt = "  -  " if np.isnan(m["MT"]) else f"{m['MT']:5.2f}"
    return f"{mt} {m['UD']:>2} {m['FA']:5.2f}"


def main():
    t0 = time.perf_counter()
    train, calibration, held = setup()
    sc = Scaler(train)
    allq = pd.concat(train)["q"]
    sensor_range = float(allq.max() - allq.min())
    sigma0 = measured_noise(train)
    print(f"training flights {len(train)}, calibration flights {len(calibration)}, held-out flights {len(held)} "
          f"({RECORD_S:g} s each, fault at {FAULT_AT_S:g} s)")
    print(f"sensor range {sensor_range:.3f} rad/s ({np.degrees(sensor_range):.0f} deg/s): 5 % = "
          f"{0.05 * sensor_range:.3f}, 20 % = {0.2 * sensor_range:.3f} rad/s; measured gyro noise sigma0 = "
          f"{sigma0:.4f} rad/s")
    net, rarx, arx = train_models(train, sc)
    print(f"EMRAN after {EPOCHS} passes over the training flights: {net.n_units} units ({net.n_grown} added, "
          f"{net.n_pruned} pruned)")
    cal_seeds = [1000 + i for i in range(len(calibration))]
    held_seeds = [2000 + i for i in range(len(held))]
    print("online-learning variants, chosen on the calibration flights:")
    chosen = {"EMRAN": choose(net, EMRAN_VARIANTS, calibration, cal_seeds, sigma0, sc, sensor_range),
              "RecursiveARX": choose(rarx, RARX_VARIANTS, calibration, cal_seeds, sigma0, sc, sensor_range),
              "ARX": ("fixed", arx, None)}
    print("  chosen: " + ", ".join(f"{k} {v[0]}" for k, v in chosen.items()))

    results = {}        # (padding, config, model) -> {fault: metrics}
    thresholds = {}
    for padding in (0, WINDOW):
        for cfg, k in CONFIGS.items():
            for name in MODELS:
                _, m, v = chosen[name]
                thr = threshold(m, v, calibration, cal_seeds, k, sigma0, sc, padding)
                thresholds[(padding, cfg, name)] = thr
                results[(padding, cfg, name)] = evaluate(m, v, held, held_seeds, k, sigma0, sc, padding, thr,
                                                         FAULT_AT_S, sensor_range)

    for padding in (0, WINDOW):
        title = "with padding (padding = window)" if padding else "no padding (eq. 6)"
        print(f"\nHeld-out flights, {title}: MT (s) / UD (of {len(held)}) / FA (%) per scenario"
              + ("; paper 004 Table 3 MT beside" if padding else ""))
        print(f"{'cfg':>3} {'fault':<9}" + "".join(f" {n:^16}" for n in MODELS) + ("  paper MT" if padding else ""))
        for cfg in CONFIGS:
            for j, (kind, mag) in enumerate(FAULTS):
                line = f"{cfg:>3} {kind + f' {mag:.0%}':<9}"
                line += "".join(f" {fmt(results[(padding, cfg, n)][(kind, mag)]):>16}" for n in MODELS)
                if padding:
                    line += f"  {PAPER_TABLE3[cfg][j]:8.2f}"
                print(line)
        print("thresholds (rad^2/s^2): " + ", ".join(
            f"cfg {c} " + "/".join(f"{thresholds[(padding, c, n)]:.3g}" for n in MODELS) for c in CONFIGS)
            + "  (EMRAN/RecursiveARX/ARX)")

    print(f"\nSummary per configuration (Table 2 style: MT over detected faults, UD of {6 * len(held)} faults, FA %)")
    print(f"{'':<13} {'cfg':>3}  {'no padding':^18}  {'with padding':^18}   paper no pad / pad")
    summary = {}
    for name in MODELS:
        for cfg in CONFIGS:
            cells = []
            for padding in (0, WINDOW):
                rs = list(results[(padding, cfg, name)].values())
                mts = [r["MT"] for r in rs if np.isfinite(r["MT"])]
                cell = {"MT": float(np.mean(mts)) if mts else np.nan, "UD": sum(r["UD"] for r in rs),
                        "FA": float(np.mean([r["FA"] for r in rs]))}
                summary[(name, cfg, padding)] = cell
                cells.append(f"{cell['MT']:5.2f} {cell['UD']:>3} {cell['FA']:5.2f}")
            (pm0, pu0, pf0), (pm1, pu1, pf1) = PAPER_TABLE2[cfg]
            print(f"{name:<13} {cfg:>3}  {cells[0]:^18}  {cells[1]:^18}   {pm0:.2f} {pu0} {pf0:.2f} / "
                  f"{pm1:.2f} {pu1} {pf1:.2f}")

    print("\nIssue 20 targets (best model, with padding, all 18 scenarios): FA 0 %, UD 0, MT <= 1.3 s")
    for name in MODELS:
        rs = [r for cfg in CONFIGS for r in results[(WINDOW, cfg, name)].values()]
        fa = max(r["FA"] for r in rs)
        ud = sum(r["UD"] for r in rs)
        mts = [r["MT"] for r in rs if np.isfinite(r["MT"])]
        mt = float(np.mean(mts)) if mts else np.nan
        ok = fa == 0 and ud == 0 and mt <= 1.3
        print(f"  {name:<13} largest FA {fa:5.2f} %, UD {ud:>3} of {len(rs) * len(held)}, mean MT {mt:5.2f} s: "
              f"{'met' if ok else 'NOT met'}")
    print(f"\nrun time {time.perf_counter() - t0:.0f} s")
    return results, summary


if __name__ == "__main__":
    main()

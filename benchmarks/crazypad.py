"""CrazyPAD benchmark (issue 17): detection and identification of propeller defects on real Crazyflie flights.

Run: ``python benchmarks/crazypad.py [--data PATH] [--conditions NAMES] [--normal-drones DRONES]`` (reads ``../shared/data/crazypad`` next
to the repository, or the CrazyPAD folder ``PATH`` of the same layout; BLAS pinned to one thread; it prints its run
time: 2-3 min on the 2-core development machine with the nine conditions and E8's five normal flights, about 7 min
with the E9 normal flights the shared copy now adds, on a busy machine). Prints the choices, then three
sections, with PASS/FAIL against the targets.

Data. Controller logs of CrazyPAD (``tsfdi.datasets.load_crazypad``). Conditions: by default the nine of the
published runs (``KNOWN``: normal flight, cut M3 1 / 2.5 / 4 mm, tape M1M3 / M3M4, weight near M3 / M3M4, string
W2), those of them the copy's ``flights.csv`` holds, so that a grown copy (the shared one now holds 56) does not
change which faulty conditions are evaluated; the normal flights are every normal log of the copy (the E9 normal
logs the shared copy added changed the numbers of all three sections). ``--conditions`` chooses others:
comma-separated condition names or glob patterns, e.g. ``--conditions 'cut_propeller_M3_*'`` or ``--conditions '*'``
(every condition of the copy; a copy with conditions not in ``KNOWN``, such as the withheld-data check's, needs it
to evaluate them). Normal flight is always included. Section 3 fits one VAR per condition and holds out every
flight: its run time grows with the number of conditions (56 conditions take long). Order: normal flight first, then
those of ``KNOWN`` in its order, then any other sorted by name. Every log holds two airborne segments (two short
flights, ~5-6 s each once trimmed), so a *flight* below is one log, and its two segments always go together: fitted
together, held out together. A log is left out as corrupt when, in one of its airborne segments, the thrust command
stays at its full scale (65535, a uint16) for 0.5 s or more: the controller has lost authority and the flight is no
longer a stabilised one. In the shared copy this rule leaves out ``weight_on_string_W2_near_M3/E8_log02`` only, of
all its 56 conditions (the drone flipped: the body z specific force falls to -1 g, the thrust command sits at full
scale for 7.8 s and 9.2 s of its two segments; the largest thrust command of every other log is below 84 % of full
scale in the nine default conditions, below 87 % in all 56, and none reaches it). Normal flights: E8 5 logs and E9 3
logs in the shared copy (earlier copies: E8 only; ``--normal-drones E8`` uses those five, like for like with the
published runs); normal logs of several drones are pooled. Some conditions were
flown by E9 only or by both drones (printed), and the two airframes differ, so results are also given per drone.

Choices, all made on normal flights only (in section 1 on the fitting logs of each fold, 7 in the shared copy, in
sections 2-3 on all normal logs, 8), never on a faulty flight:

- margin (take-off, landing): from the altitude ``stateEstimate.z`` (not a tested channel): the time from
  thrust-on until z first enters +-10 % of the hover height (median z of the segment's central half), and from z
  last leaving that band to thrust-off; the largest over the fitting segments plus a 0.25 s guard, rounded up to
  0.5 s.
- channels: the gyro rates ``controller.r_{roll,pitch,yaw}`` and the attitude controller's outputs
  ``controller.cmd_{roll,pitch,yaw}`` (a defect the loop compensates shows as a new trim of the commands: the
  integrator takes up the moment); ``controller.accelz`` is added only if modelling it lowers the held-out (leave
  one fitting log out) generalised variance of the gyro residuals by at least 5 %.
- VAR order (trend "c"): BIC of ``select_order`` (max_lags 20) on the fitting flights of every model.
- Ljung-Box lags: fixed a priori at 10 per second of window (10 for 1 s, 20 for 2 s windows), not tuned.
- thresholds: ``test.calibrate(spec.held_out_residuals(), window=..., step=1)`` with the library's calibrated
  threshold (``ScaledChi2Threshold``, see its docstring). Its default of 30 non-overlapping calibration windows
  cannot be met with 2 s windows on these short flights (7 normal logs hold 28, a condition's 2-5 logs fewer), so
  ``min_windows=5`` is passed; the number of independent windows behind the calibrations is printed.
  ``held_out_residuals(groups=logs)`` holds out the two segments of one log together, as the folds do. The
  predictive record-level law (the default since issue 31) predicts a new flight's threshold from the spread of
  the held-out segments and refuses fewer than it needs for the per-channel alpha (5 at 1e-3 with Sidak over 6
  channels); the conditions of section 3 hold 2-5 logs (4-10 segments), so ``min_records=2`` is passed: the
  threshold widens for the few records instead of being refused (sections 1-2 have enough records: unchanged).
  At 2 s a segment holds 2 windows, too few for a law of its own: since session 36 those calibrations take the
  short-record law (a Student t of the log statistic over the segments, ``ScaledChi2Threshold`` Notes) instead of
  one plug-in law fitted to the pooled windows. This script before / after, same data (session 36): section 1 at
  2 s, LB+F+M 1/32 -> 0/32 disjoint and 14/556 -> 2/556 sliding windows, LB-S 1/32 both and 20/556 -> 36/556
  sliding (FAIL both), F-S 1/32 -> 0/32; section 2, cut4 at 2 s unchanged for LB+F+M (12/12 at 0.01, 11/12 at
  0.001); section 3, the p-value rule 74.2 / 75.5 -> 78.0 / 78.0 % at 0.01 / 0.001.

Tests: ``LB`` Ljung-Box per channel, ``LB-S`` the same with Sidak correction over the channels, ``LB-H``
multivariate Ljung-Box (Hosking), ``F`` / ``F-S`` the variance F test without / with Sidak correction, ``M`` /
``M-S`` the mean-shift test (``tsfdi.MeanTest``) without / with Sidak correction; the combined detectors ``LB+F``
(``LB-S`` and ``F-S``) and ``LB+F+M`` (``LB-S``, ``F-S`` and ``M-S``), ``tsfdi.AnyOf`` of the parts, flag a window
(reject a model) when a part rejects, each part at the Sidak share ``1 - (1 - alpha)^(1/parts)`` of alpha, so that
the detector's size is alpha.
The commands and the mean-shift test were added after the first runs of this benchmark had shown that the
variance and whiteness tests miss the largest cut (section 2): that choice was made looking at faulty flights,
which the conditions withheld from the shared copy check.

1. False alarms, leave one normal flight out (one fold per normal log, 8 in the shared copy): VAR fitted on the
   other logs (7, 14 segments), tests calibrated on its held-out residuals; windows of 1 s and 2 s, step = window
   (independent trials) and step 0.1 s (sliding rate, dependent windows), on the held-out flight; per channel and
   family-wise ("any"), calibrated and theoretical (chi-square / F) thresholds, with the two-sided 99 % binomial
   band of the count.
   Target: realised rate <= 2 alpha at alpha = 1e-2 with 2 s windows, calibrated, for the per-channel tests
   (LB, F, M pooled over channels) and the family-wise ones (LB-S, LB-H, F-S, M-S and the combined detectors).
2. Detection per condition: VAR on all normal flights (faulty flights are never fitted), tests calibrated on its
   held-out residuals; percent of the non-overlapping 1 s and 2 s windows flagged on every faulty flight, per
   condition and drone. Target: cut_propeller_M3_4mm_4mm_39mm >= 95 % of its 2 s windows.
3. Identification among the conditions (9 by default): one VAR per condition, leave one flight out within
   the condition (the held-out flight's own condition model is fitted on that condition's other logs, every other
   model on all its logs; normal included; a condition with fewer than 2 usable logs cannot be held out so: the
   script prints that it skips it, and it is not a candidate either), every model with its own tests calibrated on
   its own held-out residuals; every 2 s window (step 0.5 s) of the held-out flight is decided by the three rules of
   ``tsfdi.windows.decide``: the paper rule (the single accepted model, else ambiguous / none), the likelihood rule
   (the accepted model, or any model when none is accepted, with the most likely residuals) and the p-value rule
   (the same with the largest p-value; the tests are calibrated, so a p-value measures the window against the
   model's flight-to-flight spread; a combined detector's p-value is ``tsfdi.AnyOf``'s, the Sidak-adjusted smallest
   of its parts'). Per condition:
   percent correct unique / wrong / ambiguous / none, per drone, confusion tables; target: mean correct
   identification over conditions >= 85 % at 2 s (printed for every rule, test ``LB+F+M``). The p-value rule was
   added to this section after the likelihood rule had been seen to miss the target on these conditions.
"""

import os

os.environ["OPENBLAS_NUM_THREADS"] = "1"
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import fnmatch  # noqa: E402
import functools  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

import tsfdi  # noqa: E402
from tsfdi.datasets import load_crazypad  # noqa: E402
from tsfdi.windows import RULES, decide  # noqa: E402

ROOT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "crazypad"
FS = None                  # sampling rate (Hz), set by setup()

NORMAL = "normal_flight"
#: short labels of the conditions of the shared copy, in the order the benchmark reports them; the conditions of
#: the copy it reads (``flights.csv``) are set by ``setup()``: these first, the others sorted after them, with a
#: label made by ``short_label``
KNOWN = {NORMAL: "normal", "cut_propeller_M3_1mm": "cut1", "cut_propeller_M3_2.5mm_2.5mm_42mm": "cut2.5",
         "cut_propeller_M3_4mm_4mm_39mm": "cut4", "tape_on_propeller_M1_M3": "tapeM1M3",
         "tape_on_propeller_M3_M4": "tapeM3M4", "add_weight_W1_near_M3": "wM3", "add_weight_W1_near_M3_M4": "wM3M4",
         "weight_on_string_W2_near_M3": "string"}
CONDITIONS = tuple(KNOWN)  # the conditions of the copy, normal first (set by setup())
SHORT = dict(KNOWN)        # condition -> short label (set by setup())
MIN_LOGS = 2               # usable logs a condition needs in section 3: one held out, its model on the others
NORMAL_DRONES = None       # the drones whose normal flights are used (None: every drone; set by setup())

THRUST = "controller.cmd_thrust"
THRUST_FULL_SCALE = 65535  # the thrust command is a uint16
SATURATED_S = 0.5          # a log is left out when a segment's thrust command stays at full scale this long (s)

GYRO = ("controller.r_roll", "controller.r_pitch", "controller.r_yaw")
COMMANDS = ("controller.cmd_roll", "controller.cmd_pitch", "controller.cmd_yaw")
BASE = GYRO + COMMANDS
ACCELZ = "controller.accelz"
ALTITUDE = "stateEstimate.z"

ALPHAS = (1e-2, 1e-3)
WINDOWS_S = (1.0, 2.0)
SLIDE_S = 0.1
LB_LAGS_PER_S = 10
MAX_LAGS = 20
MIN_WINDOWS = 5
MIN_RECORDS = 2            # fewest held-out records (segments) the predictive record law may rest on (see docstring)
HOVER_BAND = 0.10          # +- fraction of the hover height
GUARD_S = 0.25
MARGIN_STEP_S = 0.5
ACCELZ_GAIN = 0.05         # required relative decrease of the held-out gyro residual generalised variance
IDENT_WINDOW_S, IDENT_STEP_S = 2.0, 0.5
TARGET_FA, TARGET_DETECT, TARGET_IDENT = 2.0, 0.95, 0.85

FAMILIES = ("LB", "LB-S", "LB-H", "F", "F-S", "M", "M-S")
COMBINED = {"LB+F": ("LB-S", "F-S"), "LB+F+M": ("LB-S", "F-S", "M-S")}
DETECTORS = ("LB-S", "F-S", "LB-H", "M-S", "LB+F", "LB+F+M")   # family-wise detectors of sections 2 and 3
PRIMARY = "LB+F+M"                                             # the identification test detailed in section 3


# ------------------------------------------------------------------ data
@dataclass(frozen=True)
class Flight:
    """One log: its airborne segments (DataFrames), of one condition and drone."""

    condition: str
    drone: str
    log: str
    segments: tuple

    def arrays(self, channels) -> list:
        return [s[list(channels)].to_numpy(dtype=np.float64) for s in self.segments]


def setup(root=None, conditions=None, normal_drones=None) -> None:
    """Point the benchmark at a CrazyPAD folder (default ``../shared/data/crazypad``), fail loudly if it is
    missing, choose its conditions (``CONDITIONS``, ``SHORT``; ``conditions`` as in ``select_conditions``) and the
    drones whose normal flights are used (``normal_drones``: a str of comma-separated drone names, None for every
    drone), and read the sampling rate."""
    global ROOT, FS, CONDITIONS, SHORT, NORMAL_DRONES
    ROOT = Path(root) if root is not None else ROOT
    NORMAL_DRONES = None if normal_drones is None else tuple(d.strip() for d in normal_drones.split(","))
    if NORMAL_DRONES is not None:
        flown = set(pd.read_csv(ROOT / "flights.csv").query("condition == @NORMAL").drone) if (
            ROOT / "flights.csv").is_file() else set()
        if flown and not set(NORMAL_DRONES) <= flown:
            raise ValueError(f"--normal-drones {normal_drones}: the normal flights of {ROOT} are by "
                             f"{', '.join(sorted(flown))}")
    if not (ROOT / "flights.csv").is_file():
        raise FileNotFoundError(f"CrazyPAD data missing at {ROOT}: the benchmark needs ../shared/data/crazypad")
    CONDITIONS = select_conditions(pd.read_csv(ROOT / "flights.csv").condition, conditions)
    SHORT = short_labels(CONDITIONS)
    load_segments.cache_clear()
    load_condition.cache_clear()
    FS = float(np.median([s.attrs["fs"] for f in load_condition(NORMAL, (0.0, 0.0)) for s in f.segments]))


def conditions_of(names) -> tuple:
    """The conditions among ``names`` (the ``condition`` column of ``flights.csv``), each once: normal flight
    first, then those of ``KNOWN`` in its order, then the others sorted. Raises ValueError without normal
    flights (every section needs them)."""
    names = set(names)
    if NORMAL not in names:
        raise ValueError(f"flights.csv of {ROOT} has no {NORMAL!r} log: the benchmark needs normal flights")
    return tuple(c for c in KNOWN if c in names) + tuple(sorted(names - set(KNOWN)))


def select_conditions(names, conditions=None) -> tuple:
    """The conditions the benchmark uses among ``names`` (the ``condition`` column of ``flights.csv``), in the
    order of ``conditions_of``; normal flight is always one of them.

    ``conditions``: None for the conditions of ``KNOWN`` that the copy holds (the nine of the published runs), or
    a str of comma-separated condition names or glob patterns (``fnmatch``, case-sensitive), e.g.
    ``"cut_propeller_M3_*,tape_on_propeller_M1_M3"`` or ``"*"`` for every condition of the copy. A name or pattern
    that matches no condition of the copy raises ValueError (with the available names)."""
    names = set(names)
    if conditions is None:
        return conditions_of(names & (set(KNOWN) | {NORMAL}))
    if not isinstance(conditions, str):
        raise TypeError(f"conditions must be None or a str of comma-separated names or patterns, got {conditions!r}")
    chosen = {NORMAL} & names
    for item in (part.strip() for part in conditions.split(",")):
        found = {c for c in names if fnmatch.fnmatchcase(c, item)} if item else set()
        if not found:
            raise ValueError(f"conditions: {item!r} (of {conditions!r}) matches no condition of {ROOT / 'flights.csv'}"
                             f"; available: {', '.join(sorted(names))}")
        chosen |= found
    return conditions_of(chosen)


def short_label(condition: str) -> str:
    """Short label of a condition not in ``KNOWN``: its first word and the words with a digit (motor, weight,
    size), e.g. ``"tape_on_propeller_M1_M3"`` -> ``"tapeM1M3"``."""
    words = condition.split("_")
    return words[0] + "".join(w for w in words[1:] if any(ch.isdigit() for ch in w))


def short_labels(conditions) -> dict:
    """Condition -> short label: ``KNOWN``'s, else ``short_label``'s, else (when that is taken) the name."""
    out = {c: KNOWN[c] for c in conditions if c in KNOWN}
    for c in conditions:
        if c not in out:
            label = short_label(c)
            out[c] = c if label in out.values() else label
    return out


def saturated_s(segment: pd.DataFrame) -> float:
    """Time (s) the thrust command of an airborne segment spends at full scale (``THRUST_FULL_SCALE``)."""
    return float((segment[THRUST] >= THRUST_FULL_SCALE).sum() / segment.attrs["fs"])


@functools.lru_cache(maxsize=None)
def load_segments(condition: str, margin: tuple) -> tuple:
    """The airborne segments of every log of one condition with the (take-off, landing) margin in s."""
    return tuple(load_crazypad(ROOT, condition=condition, kind="controller", airborne=True,
                               margin=tuple(pd.Timedelta(seconds=m) for m in margin)))


def corrupt_logs(condition: str) -> dict:
    """The logs of one condition that the benchmark leaves out, ``{log: seconds at full thrust per segment}``.

    Rule: a log is corrupt when, in one of its airborne segments (no margin), the thrust command stays at full
    scale for ``SATURATED_S`` or longer: the controller has lost authority (the drone flipped or crashed; see
    the module docstring), and a model of stabilised flight does not describe it."""
    out: dict = {}
    for s in load_segments(condition, (0.0, 0.0)):
        out.setdefault(s.attrs["log"], []).append(saturated_s(s))
    return {log: sat for log, sat in out.items() if max(sat) >= SATURATED_S}


@functools.lru_cache(maxsize=None)
def load_condition(condition: str, margin: tuple) -> tuple:
    """The flights (logs) of one condition with the (take-off, landing) margin in s; corrupt logs left out."""
    corrupt = corrupt_logs(condition)
    flights: dict = {}
    for s in load_segments(condition, margin):
        if s.attrs["log"] not in corrupt and (condition != NORMAL or NORMAL_DRONES is None
                                              or s.attrs["drone"] in NORMAL_DRONES):
            flights.setdefault((s.attrs["drone"], s.attrs["log"]), []).append(s)
    return tuple(Flight(condition, d, log, tuple(v)) for (d, log), v in sorted(flights.items()))


def records(flights, channels) -> list:
    return [x for f in flights for x in f.arrays(channels)]


def samples(seconds: float) -> int:
    if FS is None:
        raise RuntimeError("call setup() first")
    return int(round(seconds * FS))


# ------------------------------------------------------------------ models and tests
@dataclass(frozen=True)
class Model:
    """A VAR fitted on some records, with the held-out residuals its tests are calibrated on."""

    results: object
    order: int
    held: list


def select_order(recs) -> int:
    return int(tsfdi.select_order(recs, MAX_LAGS, "var", trend="c").selected)


def fit_model(flights, channels, order=None) -> Model:
    """VAR(order) with an intercept (order by BIC when None) on the flights' segments, and its held-out
    residuals: the two segments of one log are held out together (a log is one flight of the folds)."""
    recs = records(flights, channels)
    order = select_order(recs) if order is None else order
    spec = tsfdi.VAR(recs, order, trend="c")
    logs = [f.log for f in flights for _ in f.segments]
    groups = logs if len(set(logs)) > 1 else None      # one log: its two segments held out in turn
    return Model(spec.fit(), order, spec.held_out_residuals(groups=groups))


def make_test(family: str, alpha: float, lags: int, calibrated: bool):
    thr = tsfdi.ScaledChi2Threshold(alpha, min_windows=MIN_WINDOWS, min_records=MIN_RECORDS) if calibrated \
        else "theoretical"
    sidak = "sidak" if family.endswith("-S") else "none"
    if family.startswith("M"):
        return tsfdi.MeanTest(alpha=alpha, correction=sidak, threshold=thr)
    if family.startswith("LB"):
        return tsfdi.LjungBox(lags=lags, alpha=alpha, correction=sidak, threshold=thr,
                              multivariate="hosking" if family == "LB-H" else None)
    return tsfdi.FTest(alpha=alpha, correction=sidak, threshold=thr)


def calibration_window(held, window: int, order: int) -> int:
    """``calibrate``'s ``window``: signal samples for held-out residuals that carry the model order (``.lags``),
    residual samples (signal window minus the order) for a plain list."""
    return window if getattr(held, "lags", None) is not None else window - order


def tests_for(model: Model, families, alpha: float, window: int, calibrated: bool) -> dict:
    """One test per family for windows of ``window`` signal samples: calibrated on the model's held-out residuals,
    or with the theoretical threshold. A combined family (``COMBINED``) is a ``tsfdi.AnyOf`` of its parts, each at
    the Sidak share ``1 - (1 - alpha)^(1/parts)``, so that "any part rejects" has size alpha."""
    lags = LB_LAGS_PER_S * round(window / FS)
    out = {}
    for fam in families:
        parts = COMBINED.get(fam)
        test = tsfdi.AnyOf([make_test(p, alpha, lags, calibrated) for p in parts]) if parts else \
            make_test(fam, alpha, lags, calibrated)
        if calibrated:
            test.calibrate(model.held, window=calibration_window(model.held, window, model.order), step=1)
        out[fam] = test
    return out


def independent_windows(tests: dict) -> int:
    """Non-overlapping calibration windows behind calibrated tests (the smallest over them and their parts)."""
    return min(int(p.calibration_windows_[1]) for t in tests.values() for p in getattr(t, "tests", (t,)))


def flags(models: dict, tests: dict, x: np.ndarray, window: int, step: int, loglik: bool = False) -> dict:
    """Every window of ``x`` through every model, for every family of ``tests`` (``tests[family][model]``):
    family -> (channel rejections (n_windows, n_models, k), model rejections (n_windows, n_models));
    ``"p:<family>"`` -> smallest channel p-value (n_windows, n_models; a combined family's is ``AnyOf``'s, the
    Sidak-adjusted smallest p-value of its parts); ``"loglik"`` -> likelihood score (n_windows, n_models)."""
    rw = tsfdi.ResidualWindows({m: r.results for m, r in models.items()}).fit(x)
    out = {"loglik": None}
    for fam, test in tests.items():
        ws = rw.statistics(test, window=window, step=step, loglik=loglik and out["loglik"] is None)
        out["loglik"] = ws.loglik if out["loglik"] is None else out["loglik"]
        out[fam] = (ws.channel_reject, ws.reject)
        out[f"p:{fam}"] = ws.min_pvalue
    return out


# ------------------------------------------------------------------ choices (normal fitting flights only)
@dataclass(frozen=True)
class Choices:
    """What was chosen on a set of normal flights."""

    logs: tuple
    climb_s: float
    descent_s: float
    margin: tuple
    accelz_gain: float
    channels: tuple
    order: int

    def line(self) -> str:
        one_drone = len({log.split("_")[0] for log in self.logs}) == 1      # then the log number names a log
        logs = ",".join(log[-2:] if one_drone else log for log in self.logs)
        return (f"logs {logs:<14} climb {self.climb_s:4.2f} s, descent "
                f"{self.descent_s:4.2f} s -> margin ({self.margin[0]:g} s, {self.margin[1]:g} s); with accelz the "
                f"held-out gyro gen. variance changes by {-100 * self.accelz_gain:+4.1f} % (added if <= "
                f"{-100 * ACCELZ_GAIN:g} %) -> "
                f"{'gyro, commands + accelz' if ACCELZ in self.channels else 'gyro + commands'}; BIC order {self.order}")


def _round_up(t: float) -> float:
    return MARGIN_STEP_S * math.ceil((t + GUARD_S) / MARGIN_STEP_S - 1e-9)


def transient_times(flights) -> tuple:
    """Largest time from thrust-on to entering the hover band, and from leaving it to thrust-off (s)."""
    climb, descent = [], []
    for f in flights:
        for s in f.segments:
            t = (s.index - s.index[0]).total_seconds().to_numpy()
            z = s[ALTITUDE].to_numpy()
            hover = np.median(z[(t > 0.25 * t[-1]) & (t < 0.75 * t[-1])])
            inside = np.abs(z - hover) <= HOVER_BAND * hover
            climb.append(t[np.argmax(inside)])
            descent.append(t[-1] - t[len(z) - 1 - np.argmax(inside[::-1])])
    return max(climb), max(descent)


def accelz_gain(flights) -> float:
    """Mean relative decrease of the held-out gyro residual generalised variance when accelz is modelled too
    (leave one log out among ``flights``, BIC order per channel set)."""
    gains = []
    for i, out in enumerate(flights):
        fit = [f for j, f in enumerate(flights) if j != i]
        logdet = []
        for channels in (BASE, BASE + (ACCELZ,)):
            recs = records(fit, channels)
            res = tsfdi.VAR(recs, select_order(recs), trend="c").fit()
            e = np.vstack([np.asarray(res.residuals(x))[:, :len(GYRO)] for x in out.arrays(channels)])
            logdet.append(np.linalg.slogdet(np.cov(e.T))[1])
        gains.append(-np.expm1(logdet[1] - logdet[0]))
    return float(np.mean(gains))


def choose(logs: tuple) -> Choices:
    """Margin, channels and VAR order from the normal flights ``logs``."""
    raw = [f for f in load_condition(NORMAL, (0.0, 0.0)) if f.log in logs]
    climb, descent = transient_times(raw)
    margin = (_round_up(climb), _round_up(descent))
    flights = [f for f in load_condition(NORMAL, margin) if f.log in logs]
    gain = accelz_gain(flights)
    channels = BASE + (ACCELZ,) if gain >= ACCELZ_GAIN else BASE
    return Choices(tuple(logs), climb, descent, margin, gain, channels, select_order(records(flights, channels)))


def normal_logs() -> tuple:
    return tuple(f.log for f in load_condition(NORMAL, (0.0, 0.0)))


# ------------------------------------------------------------------ 1. false alarms (LOFO on normal flights)
def false_alarms(folds=None, windows=WINDOWS_S, alphas=ALPHAS) -> tuple:
    """Flagged windows of every held-out normal flight: a DataFrame with one row per (fold, window, step, alpha,
    mode, family, channel or "any"), the choices of every fold and the calibration windows per window length."""
    logs = normal_logs()
    rows, choices, ncal = [], [], {}
    for k in range(len(logs)) if folds is None else folds:
        fit_logs = tuple(log for i, log in enumerate(logs) if i != k)
        ch = choose(fit_logs)
        choices.append(ch)
        flights = load_condition(NORMAL, ch.margin)
        model = fit_model([f for f in flights if f.log in fit_logs], ch.channels, ch.order)
        held_out = next(f for f in flights if f.log == logs[k])
        for wsec in windows:
            window = samples(wsec)
            for alpha in alphas:
                for mode in ("calibrated", "theoretical"):
                    tests = tests_for(model, FAMILIES + tuple(COMBINED), alpha, window, mode == "calibrated")
                    if mode == "calibrated":
                        ncal.setdefault(wsec, []).append(independent_windows(tests))
                    tests = {fam: {"m": t} for fam, t in tests.items()}
                    for step_s in (wsec, SLIDE_S):
                        for x in held_out.arrays(ch.channels):
                            fl = flags({"m": model}, tests, x, window, samples(step_s))
                            key = dict(fold=k, window_s=wsec, step_s=step_s, alpha=alpha, mode=mode)
                            rows += _fa_rows(fl, ch.channels, key)
    return pd.DataFrame(rows), choices, ncal


def _fa_rows(fl: dict, channels, key: dict) -> list:
    rows = []
    for fam in FAMILIES + tuple(COMBINED):
        rej_c, rej = fl[fam]
        n = rej.shape[0]
        rows.append({**key, "family": fam, "channel": "any", "flagged": int(rej[:, 0].sum()), "n": n})
        if fam != "LB-H" and fam not in COMBINED:
            rows += [{**key, "family": fam, "channel": name.split(".")[-1], "flagged": int(rej_c[:, 0, c].sum()),
                      "n": n} for c, name in enumerate(channels)]
    return rows


def expected_rate(family: str, alpha: float, k: int, any_channel: bool) -> float:
    """Nominal false-alarm rate of one window: per channel alpha (Sidak: the per-channel share); any channel
    1 - (1 - alpha)^k without correction (independent channels), alpha with Sidak or the joint test."""
    if any_channel:
        return -math.expm1(k * math.log1p(-alpha)) if family in ("LB", "F", "M") else alpha
    return -math.expm1(math.log1p(-alpha) / k) if family.endswith("-S") else alpha


def binomial_band(n: int, p: float) -> tuple:
    """Two-sided 99 % band of the rate of ``n`` Bernoulli(p) trials."""
    return stats.binom.ppf(0.005, n, p) / n, stats.binom.ppf(0.995, n, p) / n


def fa_table(fa: pd.DataFrame, k: int) -> pd.DataFrame:
    """Counts and rates per (window, step, alpha, family, channel group, mode): each channel, the channels
    pooled (one trial per window and channel) and "any"; with the expected rate and its 99 % band."""
    out = []
    for key, g in fa.groupby(["window_s", "step_s", "alpha", "family", "mode"], sort=False):
        chans = [c for c in g.channel.unique() if c != "any"]
        groups = [(c, g[g.channel == c]) for c in chans]
        groups += [("pooled", g[g.channel != "any"])] if chans else []
        groups += [("any", g[g.channel == "any"])]
        for chan, rows in groups:
            n, x = int(rows.n.sum()), int(rows.flagged.sum())
            p = expected_rate(key[3], key[2], k, chan == "any")
            lo, hi = binomial_band(n, p)
            out.append(dict(zip(["window_s", "step_s", "alpha", "family", "mode"], key), channel=chan, flagged=x,
                            n=n, rate=x / n, expected=p, lo=lo, hi=hi))
    return pd.DataFrame(out)


def report_false_alarms(tab: pd.DataFrame) -> None:
    for (wsec, step_s), block in tab.groupby(["window_s", "step_s"]):
        indep = step_s == wsec
        kind = "non-overlapping: independent trials" if indep else "sliding: dependent windows, rate only"
        print(f"\nwindow {wsec:g} s, step {step_s:g} s ({kind})")
        cell = f"{'flagged/n':>10} {'rate':>6} {'99% band':>13} in"
        print(f"{'alpha':>6} {'test':<5} {'channel':<8} {'expected':>8} | {'calibrated':^37} | {'theoretical':^37}")
        print(f"{'':>6} {'':<5} {'':<8} {'':>8} | {cell} | {cell}")
        for (alpha, fam, chan), g in block.groupby(["alpha", "family", "channel"], sort=False):
            cells = []
            for mode in ("calibrated", "theoretical"):
                r = g[g["mode"] == mode].iloc[0]
                band = f"[{r.lo:.3f},{r.hi:.3f}]" if indep else "n/a"
                inside = ("yes" if r.lo <= r.rate <= r.hi else "NO ") if indep else "   "
                cells.append(f"{r.flagged:>4}/{r.n:<5} {r.rate:6.3f} {band:>13} {inside}")
            print(f"{alpha:>6g} {fam:<5} {chan:<8} {g.expected.iloc[0]:8.4f} | {cells[0]} | {cells[1]}")


def fa_verdicts(tab: pd.DataFrame) -> list:
    """PASS/FAIL: calibrated, alpha 1e-2, 2 s windows; per channel pooled (LB, F, M) and family-wise (LB-S, LB-H,
    F-S, M-S and the combined detectors)."""
    sel = tab[(tab["mode"] == "calibrated") & (tab.alpha == 1e-2) & (tab.window_s == 2.0)
              & (((tab.channel == "pooled") & tab.family.isin(["LB", "F", "M"]))
                 | ((tab.channel == "any") & tab.family.isin(["LB-S", "LB-H", "F-S", "M-S", *COMBINED])))]
    lines = []
    for r in sel.sort_values(["step_s", "family"], ascending=[False, True]).itertuples():
        what = "per channel (pooled)" if r.channel == "pooled" else "family-wise (any)"
        lines.append(f"  {'PASS' if r.rate <= TARGET_FA * r.alpha else 'FAIL'}  {r.family:<5} {what:<21} step "
                     f"{r.step_s:g} s: {r.flagged}/{r.n} = {r.rate:.4f} vs <= {TARGET_FA * r.alpha:g}")
    return lines


# ------------------------------------------------------------------ 2. detection per condition
def detection(choice: Choices, conditions=None, windows=WINDOWS_S, alphas=ALPHAS) -> tuple:
    """Flagged non-overlapping windows of every faulty flight against the VAR of all normal flights; and the
    calibration windows per window length. ``conditions``: the faulty conditions (default: every one of the
    copy)."""
    conditions = CONDITIONS[1:] if conditions is None else conditions
    model = fit_model(load_condition(NORMAL, choice.margin), choice.channels, choice.order)
    rows, ncal = [], {}
    for wsec in windows:
        window = samples(wsec)
        for alpha in alphas:
            tests = tests_for(model, DETECTORS, alpha, window, True)
            ncal[wsec] = independent_windows(tests)
            tests = {fam: {"m": t} for fam, t in tests.items()}
            for cond in conditions:
                for f in load_condition(cond, choice.margin):
                    for x in f.arrays(choice.channels):
                        fl = flags({"m": model}, tests, x, window, window)
                        rows += [{"condition": cond, "drone": f.drone, "log": f.log, "window_s": wsec,
                                  "alpha": alpha, "family": fam, "flagged": int(fl[fam][1].sum()),
                                  "n": int(fl[fam][1].shape[0])} for fam in DETECTORS]
    return pd.DataFrame(rows), ncal


def report_detection(det: pd.DataFrame) -> None:
    for alpha, d in det.groupby("alpha", sort=False):
        tab = d.groupby(["condition", "drone", "window_s", "family"], sort=False)[["flagged", "n"]].sum()
        pct = (100 * tab.flagged / tab.n).unstack(["window_s", "family"])
        n2 = tab.n.xs(max(d.window_s), level="window_s").groupby(level=[0, 1], sort=False).first()
        pct.index = [f"{SHORT[c]} {dr} ({n2.loc[(c, dr)]})" for c, dr in pct.index]
        pct.columns = [f"{fam} {w:g}s" for w, fam in pct.columns]
        print(f"\nalpha = {alpha:g}: percent of windows flagged (rows: condition, drone, number of "
              f"{max(d.window_s):g} s windows)")
        print(pct.round(1).to_string())


def detection_verdicts(det: pd.DataFrame) -> list:
    d = det[(det.condition == "cut_propeller_M3_4mm_4mm_39mm") & (det.window_s == 2.0)]
    lines = []
    for (alpha, fam), g in d.groupby(["alpha", "family"], sort=False):
        r = g.flagged.sum() / g.n.sum()
        lines.append(f"  {'PASS' if r >= TARGET_DETECT else 'FAIL'}  alpha {alpha:g} {fam:<5} cut4 2 s: "
                     f"{g.flagged.sum()}/{g.n.sum()} = {100 * r:.1f} % vs >= {100 * TARGET_DETECT:g} %")
    return lines


# ------------------------------------------------------------------ 3. identification
def identified_conditions(margin: tuple) -> tuple:
    """The conditions of section 3: those with at least ``MIN_LOGS`` usable logs."""
    return tuple(c for c in CONDITIONS if len(load_condition(c, margin)) >= MIN_LOGS)


def identification(choice: Choices, conditions=None, alphas=ALPHAS, held_out=None) -> tuple:
    """Label of every 2 s window of every held-out flight, per test family, alpha and rule (one row per window);
    and the fewest calibration windows behind a model's tests.

    ``conditions``: the candidate conditions, each with at least ``MIN_LOGS`` usable logs (default
    ``identified_conditions``); ``held_out``: optional (condition, log) pairs to hold out (default every flight
    of ``conditions``)."""
    conditions = identified_conditions(choice.margin) if conditions is None else conditions
    window, step = samples(IDENT_WINDOW_S), samples(IDENT_STEP_S)
    flights = {c: load_condition(c, choice.margin) for c in conditions}
    full = {c: fit_model(fl, choice.channels) for c, fl in flights.items()}
    full_tests = {(c, a): tests_for(m, DETECTORS, a, window, True) for c, m in full.items() for a in alphas}
    ncal = [independent_windows(t) for t in full_tests.values()]
    rows = []
    for cond in conditions:
        for f in flights[cond]:
            if held_out is not None and (cond, f.log) not in held_out:
                continue
            own = fit_model([g for g in flights[cond] if g.log != f.log], choice.channels)
            models = {**full, cond: own}
            for alpha in alphas:
                per_model = {c: full_tests[(c, alpha)] for c in conditions}
                per_model[cond] = tests_for(own, DETECTORS, alpha, window, True)
                ncal.append(independent_windows(per_model[cond]))
                tests = {key: {c: per_model[c][key] for c in conditions} for key in per_model[cond]}
                for seg, x in enumerate(f.arrays(choice.channels)):
                    fl = flags(models, tests, x, window, step, loglik=True)
                    for fam in DETECTORS:
                        for rule in RULES:
                            labels = decide(~fl[fam][1], rule, loglik=fl["loglik"], pvalue=fl[f"p:{fam}"])
                            rows += [{"condition": cond, "drone": f.drone, "log": f.log, "segment": seg,
                                      "alpha": alpha, "family": fam, "rule": rule, "order": own.order,
                                      "label": conditions[lb] if lb >= 0 else ("ambiguous" if lb == -2 else "none")}
                                     for lb in labels]
    return pd.DataFrame(rows), min(ncal)


def with_outcome(ident: pd.DataFrame) -> pd.DataFrame:
    out = np.where(ident.label == ident.condition, "correct",
                   np.where(ident.label.isin(["ambiguous", "none"]), ident.label, "wrong"))
    return ident.assign(outcome=out)


def ident_summary(ident: pd.DataFrame) -> pd.DataFrame:
    """Mean over conditions of the percent of correctly identified windows, per alpha, family and rule."""
    ident = with_outcome(ident)
    per_cond = ident.groupby(["alpha", "family", "rule", "condition"]).outcome.apply(lambda o: (o == "correct").mean())
    return 100 * per_cond.groupby(level=[0, 1, 2]).mean().unstack("rule")


def flight_summary(ident: pd.DataFrame) -> pd.DataFrame:
    """Mean over conditions of the percent of held-out flights whose most frequent window label is their condition
    (a tie counts as wrong), per alpha, family and rule: how far whole-flight decisions get."""
    def majority(labels: pd.Series) -> str:
        counts = labels.value_counts()
        top = counts.index[counts == counts.max()]
        return top[0] if len(top) == 1 else "tie"
    voted = ident.groupby(["alpha", "family", "rule", "condition", "log"]).label.agg(majority).reset_index()
    per_cond = (voted.label == voted.condition).groupby([voted.alpha, voted.family, voted.rule, voted.condition]).mean()
    return 100 * per_cond.groupby(level=[0, 1, 2]).mean().unstack("rule")


def report_identification(ident: pd.DataFrame, conditions=None) -> None:
    conditions = CONDITIONS if conditions is None else conditions
    ident = with_outcome(ident)
    order = [SHORT[c] for c in conditions if c in set(ident.condition)]
    print(f"\nmean over conditions of the percent of correct windows, {IDENT_WINDOW_S:g} s windows, step "
          f"{IDENT_STEP_S:g} s (paper: correct unique; likelihood, pvalue: correct label)")
    print(ident_summary(ident).round(1).to_string())
    print(f"\n{PRIMARY}, decided per held-out flight (the label most of its windows carry): mean over conditions of "
          "the percent of correct flights")
    print(flight_summary(ident).xs(PRIMARY, level="family").round(1).to_string())
    alpha = max(ident.alpha)
    for rule, d in ident[(ident.family == PRIMARY) & (ident.alpha == alpha)].groupby("rule", sort=False):
        print(f"\n{PRIMARY}, alpha {alpha:g}, {rule} rule: percent of the held-out condition's windows")
        tab = pd.crosstab(d.condition, d.outcome, normalize="index")
        tab = (100 * tab.reindex(columns=["correct", "wrong", "ambiguous", "none"]).fillna(0.0)).round(1)
        drones = d.groupby("condition").drone.agg(lambda s: "+".join(sorted(s.unique())))
        by_drone = d.groupby(["condition", "drone"]).outcome.apply(lambda o: 100 * (o == "correct").mean())
        tab["drones"] = drones
        tab["correct per drone"] = [" ".join(f"{dr}:{by_drone[(c, dr)]:.0f}" for dr in drones[c].split("+"))
                                    for c in tab.index]
        tab["windows"] = d.groupby("condition").size()
        tab.index = tab.index.map(SHORT)
        print(tab.reindex(order).to_string())
        conf = pd.crosstab(d.condition.map(SHORT), d.label.map(lambda v: SHORT.get(v, v)), normalize="index")
        cols = order + [c for c in ("ambiguous", "none") if c in conf.columns]
        print(f"confusion ({rule} rule, percent of the true condition's windows; rows true, columns decided):")
        print((100 * conf.reindex(index=order, columns=cols).fillna(0.0)).round(0).astype(int).to_string())


def ident_verdicts(ident: pd.DataFrame) -> list:
    summary = ident_summary(ident)
    return [f"  {'PASS' if v >= 100 * TARGET_IDENT else 'FAIL'}  alpha {alpha:g} {PRIMARY} {rule:<10} rule: "
            f"mean correct {v:.1f} % vs >= {100 * TARGET_IDENT:g} %"
            for alpha in sorted(set(ident.alpha), reverse=True) for rule, v in summary.loc[(alpha, PRIMARY)].items()]


# ------------------------------------------------------------------ main
def print_data() -> None:
    print(f"CrazyPAD benchmark (issue 17) on {ROOT}, controller logs, fs = {FS:.2f} Hz")
    for c in CONDITIONS:
        for log, sat in corrupt_logs(c).items():
            print(f"excluded: {c}/{log} (thrust command at full scale for {', '.join(f'{t:.1f} s' for t in sat)} of "
                  f"its airborne segments, >= {SATURATED_S:g} s: loss of control)")
    print("flights per condition (a flight = one log = 2 airborne segments):")
    for c in CONDITIONS:
        drones = pd.Series([f.drone for f in load_condition(c, (0.0, 0.0))]).value_counts().sort_index()
        print(f"  {SHORT[c]:<9} {c:<36} {drones.sum()} logs ({', '.join(f'{d}: {n}' for d, n in drones.items())})")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=ROOT, metavar="PATH",
                        help="the CrazyPAD folder (flights.csv, controller/); default ../shared/data/crazypad")
    parser.add_argument("--conditions", metavar="NAMES",
                        help="comma-separated conditions or glob patterns ('*': every condition of the copy); "
                             "normal_flight is always included; default the nine conditions of the published runs")
    parser.add_argument("--normal-drones", metavar="DRONES",
                        help="comma-separated drones whose normal flights are used (default every drone of the copy; "
                             "'E8' gives the normal flights of the published runs, like for like)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    try:
        setup(args.data, args.conditions, args.normal_drones)
    except (FileNotFoundError, ValueError) as err:
        parser.error(str(err))
    print_data()

    fa, fold_choices, ncal1 = false_alarms()
    n = len(normal_logs())
    choice = choose(normal_logs())
    det, ncal2 = detection(choice)
    identified = identified_conditions(choice.margin)
    ident, ncal3 = identification(choice, identified)
    print(f"\n== choices (made on normal flights only: per fold on its {n - 1} fitting logs; sections 2-3 on all {n}) "
          "==")
    for k, ch in enumerate(fold_choices):
        print(f"  fold {k} (held out {normal_logs()[k]}): {ch.line()}")
    print(f"  sections 2-3 (all normal): {choice.line()}")
    print(f"  Ljung-Box lags fixed a priori: {LB_LAGS_PER_S} per s of window (1 s: {LB_LAGS_PER_S}, 2 s: "
          f"{2 * LB_LAGS_PER_S}); thresholds: ScaledChi2Threshold(min_windows={MIN_WINDOWS}) calibrated on "
          "held_out_residuals(groups=logs) (both segments of a log held out together), step 1")
    print("  independent calibration windows: section 1 "
          + ", ".join(f"{w:g} s: {min(v)}-{max(v)}" for w, v in ncal1.items())
          + "; section 2 " + ", ".join(f"{w:g} s: {v}" for w, v in ncal2.items())
          + f"; section 3 (2 s, per condition model): >= {ncal3}")
    orders = ident.groupby("condition").order.agg(lambda s: sorted(set(s)))
    print("  section 3 BIC orders of the held-out flights' own-condition models: "
          + ", ".join(f"{SHORT[c]} {orders[c]}" for c in identified))
    print(f"  section 3 detailed test {PRIMARY} ({' + '.join(COMBINED[PRIMARY])}, each at the Sidak share of alpha)")

    print(f"\n== 1. false alarms on held-out normal flights (leave one log out, {n} folds) ==")
    tab = fa_table(fa, len(choice.channels))
    report_false_alarms(tab)
    print("\ntarget: realised FA <= 2 alpha at alpha = 1e-2, 2 s windows, calibrated:")
    print("\n".join(fa_verdicts(tab)))

    print("\n== 2. detection per condition (VAR on all normal flights, calibrated tests, non-overlapping windows) ==")
    report_detection(det)
    print("\ntarget: cut_propeller_M3_4mm_4mm_39mm >= 95 % of its 2 s windows:")
    print("\n".join(detection_verdicts(det)))

    print(f"\n== 3. identification among the {len(identified)} conditions (per-condition VARs, leave one flight out "
          "within the condition) ==")
    for c in CONDITIONS:
        if c not in identified:
            print(f"skipped {SHORT[c]} ({c}): {len(load_condition(c, choice.margin))} usable log(s), a condition "
                  f"needs >= {MIN_LOGS} (one held out, its model fitted on the others)")
    report_identification(ident)
    print(f"\ntarget: mean correct identification over conditions >= 85 % at 2 s ({PRIMARY}):")
    print("\n".join(ident_verdicts(ident)))
    print(f"\nrun time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()

"""Structured residuals and fault isolation (Hansen, Blanke, Adrian, paper 002, section 4.1 and Table 2).

A :class:`ResidualSet` is a set of residuals, each a function of the sensors, with its *incidence* (signature)
table: entry (residual, sensor) is 1 when a fault of that sensor shows in that residual. Each residual has its own
residual test (:class:`~tsfdi.GLRT`, :class:`~tsfdi.ZScore`, a calibrated test, ...). The residuals whose test
rejects form the *fired pattern*; the faulty sensor is the one whose column of the table equals it (column
matching). The outcome is an :class:`Isolation`:

- ``"isolated"``: exactly one column matches (``label`` is that sensor);
- ``"several"``: several columns match (identical columns: those sensors cannot be told apart);
- ``"not isolable"``: residuals fired but no column matches (a fault the table does not describe, several faulty
  sensors at once, a false alarm, or a fault seen so far by only part of its residuals);
- ``"none"``: no residual fired.

:meth:`ResidualSet.isolate` decides on a whole record, :meth:`ResidualSet.isolate_windows` on every sliding
window and :meth:`ResidualSet.isolate_samples` at every sample (tests with per-sample alarms), the last two as an
:class:`IsolationSeries`.

A sensor whose output freezes shows in its parity residuals only as far as the quantity moves; its own output
shows it directly: :func:`frozen_output` flags the samples where a sensor's output has stayed put over a window.

Paper 002's worked example (:func:`airspeed_parity`): three estimates of the airspeed -- the pitot tube, the GPS
ground speed corrected for the wind (:func:`airspeed_from_gps`, eqs. 4-6), and the airspeed expected from the
thrust -- give three residuals, each the difference of two estimates and sensitive to those two (Table 2).
"""

from __future__ import annotations

import copy
import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import as_signal, sampling_frequency, window_samples
from tsfdi._validation import float_like, int_like
from tsfdi.detection.base import ResidualTest
from tsfdi.detection.glrt import GLRT
from tsfdi.summary import Summary

__all__ = ["STATUS", "Isolation", "IsolationSeries", "ResidualSet", "airspeed_from_gps", "airspeed_parity",
           "climb_rate_from_accel", "climb_rate_from_baro", "frozen_output"]

#: The outcomes of an isolation, in this order of precedence.
STATUS = ("isolated", "several", "not isolable", "none")


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a)
    a.flags.writeable = False
    return a


def _match(fired: np.ndarray, incidence: np.ndarray) -> np.ndarray:
    """Columns of ``incidence`` (r, s) equal to every fired pattern (n, r): bool (n, s); a pattern where nothing
    fired matches no column (not even an all-zero one)."""
    return (fired[:, :, None] == incidence[None, :, :]).all(axis=1) & fired.any(axis=1)[:, None]


def _status(fired: np.ndarray, n_match: np.ndarray) -> np.ndarray:
    return np.where(~fired.any(axis=1), STATUS[3],
                    np.where(n_match == 1, STATUS[0], np.where(n_match > 1, STATUS[1], STATUS[2])))


@dataclass(frozen=True, eq=False)
class Isolation:
    """Outcome of an isolation: which residuals fired and which sensor's signature they match.

    Attributes
    ----------
    fired : tuple of str
        Residuals whose test rejects, in table order.
    names : tuple of str
        All residuals (rows of the incidence table).
    sensors : tuple of str
        All sensors (columns of the incidence table).
    incidence : ndarray of bool, shape (n_residuals, n_sensors)
        The signature table (read-only).
    decisions : dict
        Residual name -> its :class:`~tsfdi.Decision` (empty for :meth:`ResidualSet.match`).
    span : tuple or None
        ``(start, stop)`` sample positions of the tested stretch (windows and samples of an
        :class:`IsolationSeries`).
    """

    fired: tuple
    names: tuple
    sensors: tuple
    incidence: np.ndarray
    decisions: dict = field(default_factory=dict)
    span: tuple | None = None

    @property
    def signature(self) -> np.ndarray:
        """The fired pattern as a bool vector in table order."""
        return np.array([n in self.fired for n in self.names])

    @property
    def candidates(self) -> tuple:
        """Sensors whose column of the table equals the fired pattern (none when nothing fired)."""
        m = _match(self.signature[None, :], self.incidence)[0]
        return tuple(s for s, hit in zip(self.sensors, m) if hit)

    @property
    def label(self) -> str | None:
        """The isolated sensor, or ``None`` unless ``status == "isolated"``."""
        c = self.candidates
        return c[0] if len(c) == 1 else None

    @property
    def status(self) -> str:
        """``"isolated"``, ``"several"``, ``"not isolable"`` or ``"none"`` (see :data:`STATUS`)."""
        return str(_status(self.signature[None, :], np.array([len(self.candidates)]))[0])

    def to_frame(self) -> pd.DataFrame:
        """The incidence table with the fired pattern as a last column (and the test's statistic and threshold
        when there are decisions)."""
        table = pd.DataFrame(self.incidence.astype(int), index=pd.Index(self.names, name="residual"),
                             columns=list(self.sensors))
        table["fired"] = self.signature
        if self.decisions:
            table["statistic"] = [float(np.max(self.decisions[n].statistic)) for n in self.names]
            table["threshold"] = [float(np.max(self.decisions[n].threshold)) for n in self.names]
        return table

    def summary(self) -> Summary:
        header = [("Status", self.status), ("Isolated sensor", self.label or "-"),
                  ("Candidates", ", ".join(self.candidates) or "-"), ("Fired", ", ".join(self.fired) or "-")]
        if self.span is not None:
            header.append(("Samples", f"{self.span[0]}..{self.span[1] - 1}"))
        return Summary("Fault isolation", header, [("Signature table", self.to_frame())],
                       ["Rule: the sensor whose column equals the fired residuals (column matching)."])

    def __repr__(self) -> str:
        return (f"Isolation(status={self.status!r}, label={self.label!r}, fired={self.fired}, "
                f"candidates={self.candidates})")

    def _repr_html_(self) -> str:
        return self.summary().as_html()


@dataclass(frozen=True, eq=False)
class IsolationSeries:
    """Isolation at every sample or sliding window of a record (:meth:`ResidualSet.isolate_samples`,
    :meth:`ResidualSet.isolate_windows`).

    Attributes
    ----------
    fired : ndarray of bool, shape (n_rows, n_residuals)
        Residuals fired in each row (read-only).
    names, sensors, incidence :
        As in :class:`Isolation`.
    starts, stops : ndarray of int, shape (n_rows,)
        Row ``i`` covers the samples ``[starts[i], stops[i])`` (one sample per row for
        :meth:`~ResidualSet.isolate_samples`).
    index : pandas.Index or None
        The time label of the last sample of every row (pandas / xarray input), else ``None``.
    status : ndarray of str, shape (n_rows,)
        :data:`STATUS` of every row.
    labels : list
        The isolated sensor of every row, else ``None``.
    first_detection : int or None
        First row where any residual fired.
    first_isolation : int or None
        First row with status ``"isolated"``; :attr:`isolated` is its sensor. :meth:`confirmed` asks for the
        isolation to persist.

    ``series[i]`` is the :class:`Isolation` of row ``i`` (with its ``span``, without decisions).
    """

    fired: np.ndarray
    names: tuple
    sensors: tuple
    incidence: np.ndarray
    starts: np.ndarray
    stops: np.ndarray
    index: pd.Index | None = None

    @property
    def _matches(self) -> np.ndarray:
        return _match(self.fired, self.incidence)

    @property
    def status(self) -> np.ndarray:
        return _status(self.fired, self._matches.sum(axis=1))

    @property
    def _codes(self) -> np.ndarray:
        """Position of the isolated sensor of every row, -1 where none is isolated."""
        m = self._matches
        return np.where(m.sum(axis=1) == 1, m.argmax(axis=1), -1)

    @property
    def labels(self) -> list:
        return [self.sensors[c] if c >= 0 else None for c in self._codes.tolist()]

    @property
    def first_detection(self) -> int | None:
        hit = np.flatnonzero(self.fired.any(axis=1))
        return int(hit[0]) if hit.size else None

    @property
    def first_isolation(self) -> int | None:
        hit = np.flatnonzero(self.status == STATUS[0])
        return int(hit[0]) if hit.size else None

    @property
    def isolated(self) -> str | None:
        """The sensor isolated at :attr:`first_isolation` (None if no row isolates)."""
        i = self.first_isolation
        return None if i is None else self.labels[i]

    def confirmed(self, hold: int = 1) -> int | None:
        """The first row at which the same sensor has been isolated for ``hold`` consecutive rows (the decision
        time of an isolation that must persist, e.g. ``hold=40`` samples = 2 s at 20 Hz); ``None`` if none.
        ``labels[row]`` is the sensor. ``hold=1`` gives :attr:`first_isolation`."""
        hold = int_like(hold, "hold", minimum=1)
        code = self._codes
        rows = np.arange(code.size)
        # length of the run of equal codes ending at every row
        first = np.maximum.accumulate(np.where(np.diff(code, prepend=-2) != 0, rows, 0))
        hit = np.flatnonzero((code >= 0) & (rows - first + 1 >= hold))
        return int(hit[0]) if hit.size else None

    def __len__(self) -> int:
        return int(self.fired.shape[0])

    def __getitem__(self, i: int) -> Isolation:
        i = int(i)
        if i < 0:
            i += len(self)
        if not 0 <= i < len(self):
            raise IndexError(f"row index out of range (0..{len(self) - 1})")
        fired = tuple(n for n, f in zip(self.names, self.fired[i]) if f)
        return Isolation(fired, self.names, self.sensors, self.incidence,
                         span=(int(self.starts[i]), int(self.stops[i])))

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def to_frame(self) -> pd.DataFrame:
        """One row per sample / window: start, stop, one bool column per residual, status, label."""
        frame = pd.DataFrame(self.fired, columns=list(self.names), index=self.index)
        frame.insert(0, "stop", self.stops)
        frame.insert(0, "start", self.starts)
        frame["status"] = self.status
        frame["label"] = self.labels
        return frame

    def __repr__(self) -> str:
        counts = {s: int((self.status == s).sum()) for s in STATUS}
        return (f"IsolationSeries(rows={len(self)}, first_detection={self.first_detection}, "
                f"first_isolation={self.first_isolation}, isolated={self.isolated!r}, {counts})")


def _incidence(incidence: Any) -> tuple[tuple, tuple, np.ndarray]:
    """(residual names, sensor names, bool table) from a DataFrame of 0/1 or a mapping residual -> sensors."""
    if isinstance(incidence, pd.DataFrame):
        names = tuple(str(i) for i in incidence.index)
        sensors = tuple(str(c) for c in incidence.columns)
        values = incidence.to_numpy()
        if values.dtype.kind not in "biuf" or not np.isin(values, (0, 1)).all():
            raise ValueError("incidence must hold 0 / 1 (or booleans) only")
        table = values.astype(bool)
    elif isinstance(incidence, Mapping):
        names = tuple(str(k) for k in incidence)
        sensors: list = []
        for k, v in incidence.items():
            if isinstance(v, str) or not isinstance(v, (Sequence, set, frozenset)):
                raise TypeError(f"incidence[{k!r}] must be a sequence of sensor names, got {v!r}")
            sensors += [str(s) for s in v if str(s) not in sensors]
        sensors = tuple(sensors)
        table = np.array([[s in {str(x) for x in incidence[k]} for s in sensors] for k in incidence], dtype=bool)
    else:
        raise TypeError("incidence must be a DataFrame (residuals x sensors, 0 / 1) or a mapping residual -> "
                        f"sensor names, got {type(incidence).__name__}")
    if not names or not sensors:
        raise ValueError("incidence must have at least one residual and one sensor")
    for what, seq in (("residual", names), ("sensor", sensors)):
        dup = sorted({x for x in seq if seq.count(x) > 1})
        if dup:
            raise ValueError(f"incidence has duplicate {what} names: {dup}")
    if not table.any(axis=1).all():
        raise ValueError(f"incidence: residual(s) {[n for n, r in zip(names, table) if not r.any()]} depend on no "
                         "sensor")
    return names, sensors, table


class ResidualSet:
    """A structured residual set: residuals, their incidence (signature) table and one test per residual.

    Parameters
    ----------
    incidence : DataFrame or mapping
        The signature table: a ``DataFrame`` indexed by residual name with one 0 / 1 column per sensor, or a
        mapping residual name -> the sensors it depends on (e.g. ``{"R1": ("pitot", "gps2air"), ...}``).
    tests : ResidualTest or mapping, optional
        The test of every residual: one test (copied for each residual, so each gets its own calibration) or a
        mapping residual name -> test. Default ``GLRT(window=100)``.
    functions : mapping, optional
        Residual name -> a function of the signals (a ``DataFrame`` with one column per signal) returning the
        residual (one value per sample), used by :meth:`residuals`.

    Attributes
    ----------
    names, sensors : tuple of str
        Residuals (table rows) and sensors (table columns).
    incidence : ndarray of bool, shape (n_residuals, n_sensors)
        The table (read-only); :attr:`table` as a ``DataFrame``.
    tests : dict
        Residual name -> its test.

    Notes
    -----
    Column matching (the "voting scheme" of Hansen et al., Table 2): a fault of sensor :math:`s` changes the
    residuals of column :math:`s` and no other, so the fired pattern equals that column. A sensor whose column
    equals another's cannot be isolated from it (``"several"``); a sensor with an all-zero column cannot be
    detected at all. :attr:`isolable` lists the sensors with a non-zero column shared by no other. Isolation
    assumes one faulty sensor at a time (paper 002: "this scheme will however not work if faults involving more
    than one of the parameters occurs at the same time").

    The false-alarm rate of the set is that of "some residual fires", at most the sum of the per-residual rates;
    a false *isolation* needs a fired pattern equal to a column, i.e. several residuals firing together.

    References
    ----------
    Hansen, Blanke, Adrian, *A Framework for Rapid Diagnosis of Critical Faults in UAVs*, section 4.1, Table 2.
    Gertler, J., *Fault Detection and Diagnosis in Engineering Systems*, Marcel Dekker, 1998 (structured
    residuals).
    """

    def __init__(self, incidence: Any, tests: Any = None, *, functions: Mapping | None = None) -> None:
        self.names, self.sensors, table = _incidence(incidence)
        self.incidence = _readonly(table)
        if tests is None:
            tests = GLRT(window=100)
        if isinstance(tests, Mapping):
            missing = [n for n in self.names if n not in tests]
            if missing:
                raise ValueError(f"tests has no test for residual(s) {missing}")
            self.tests = {n: tests[n] for n in self.names}
        else:
            self.tests = {n: copy.deepcopy(tests) for n in self.names}
        for n, t in self.tests.items():
            if not isinstance(t, ResidualTest):
                raise TypeError(f"tests[{n!r}] must be a residual test (GLRT, ZScore, FTest, ...), got "
                                f"{type(t).__name__}")
        if functions is not None:
            if not isinstance(functions, Mapping):
                raise TypeError(f"functions must be a mapping residual name -> function, got "
                                f"{type(functions).__name__}")
            missing = [n for n in self.names if n not in functions]
            if missing:
                raise ValueError(f"functions has no function for residual(s) {missing}")
            bad = [n for n in self.names if not callable(functions[n])]
            if bad:
                raise TypeError(f"functions[{bad[0]!r}] must be callable")
            functions = {n: functions[n] for n in self.names}
        self.functions = functions

    @classmethod
    def pairwise(cls, estimates: Sequence[str], tests: Any = None) -> ResidualSet:
        """Parity relations between estimates of one quantity: every pair gives a residual, the difference of
        the two, sensitive to those two (Hansen et al., Table 2 for three airspeed estimates).

        Residual ``R{i}`` is ``estimates[a] - estimates[b]`` for the ``i``-th pair ``a < b`` in order, so three
        estimates give R1 = e0 - e1, R2 = e0 - e2, R3 = e1 - e2. With three or more estimates every estimate
        is isolable.
        """
        if isinstance(estimates, str) or not isinstance(estimates, Sequence):
            raise TypeError(f"estimates must be a sequence of names, got {estimates!r}")
        est = [str(e) for e in estimates]
        if len(est) < 2 or len(set(est)) != len(est):
            raise ValueError(f"estimates must hold at least two distinct names, got {est}")
        pairs = list(itertools.combinations(est, 2))
        incidence = {f"R{i + 1}": pair for i, pair in enumerate(pairs)}
        functions = {f"R{i + 1}": (lambda s, a=a, b=b: s[a] - s[b]) for i, (a, b) in enumerate(pairs)}
        return cls(incidence, tests, functions=functions)

    # ------------------------------------------------------------------ the table
    @property
    def table(self) -> pd.DataFrame:
        """The incidence table as a ``DataFrame`` of 0 / 1 (residuals x sensors)."""
        return pd.DataFrame(self.incidence.astype(int), index=pd.Index(self.names, name="residual"),
                            columns=list(self.sensors))

    @property
    def isolable(self) -> tuple:
        """Sensors with a non-zero column equal to no other column: a single fault of these can be isolated."""
        cols = [tuple(c) for c in self.incidence.T]
        return tuple(s for s, c in zip(self.sensors, cols) if any(c) and cols.count(c) == 1)

    def match(self, fired: Any) -> Isolation:
        """The isolation of a given fired pattern: residual names, or one bool per residual in table order."""
        if isinstance(fired, str):
            fired = [fired]
        if not isinstance(fired, (Sequence, np.ndarray, set, frozenset)):
            raise TypeError(f"fired must be residual names or one bool per residual, got {type(fired).__name__}")
        fired = list(fired)
        if all(isinstance(f, (bool, np.bool_)) for f in fired) and fired:
            if len(fired) != len(self.names):
                raise ValueError(f"fired must hold one bool per residual ({len(self.names)}), got {len(fired)}")
            return Isolation(tuple(n for n, f in zip(self.names, fired) if f), self.names, self.sensors,
                             self.incidence)
        unknown = [f for f in fired if f not in self.names]
        if unknown:
            raise ValueError(f"fired names unknown residual(s) {unknown}; residuals: {list(self.names)}")
        return Isolation(tuple(n for n in self.names if n in fired), self.names, self.sensors, self.incidence)

    # ------------------------------------------------------------------ residuals
    def residuals(self, signals: Any) -> Any:
        """Evaluate the residual functions on ``signals`` (one column per signal, named as the functions
        expect); the result has one column per residual, in the kind and with the index of ``signals``."""
        if self.functions is None:
            raise ValueError("this residual set has no residual functions: build it with functions= or "
                             "ResidualSet.pairwise, or compute the residuals yourself")
        sig = as_signal(signals, "signals", vector=True, allow_constant=True)
        frame = pd.DataFrame(sig.values, columns=sig.channels)
        cols = []
        for n in self.names:
            try:
                r = self.functions[n](frame)
            except KeyError as exc:
                raise ValueError(f"signals has no column {exc.args[0]!r} needed by residual {n!r}; columns: "
                                 f"{list(sig.channels)}") from None
            r = np.asarray(r, dtype=np.float64).reshape(-1)
            if r.shape[0] != sig.nobs:
                raise ValueError(f"the function of residual {n!r} returned {r.shape[0]} values for {sig.nobs} "
                                 "samples")
            cols.append(r)
        return sig.wrap(np.column_stack(cols), 0, channels=list(self.names), vector=True)

    def _signal(self, residuals: Any, name: str = "residuals") -> Any:
        sig = as_signal(residuals, name, vector=len(self.names) > 1 or None, allow_constant=True)
        return sig.match_channels(self.names, name, reference="the residual set is built on")

    def _column(self, sig: Any, i: int, start: int = 0, stop: int | None = None) -> Any:
        stop = sig.nobs if stop is None else stop
        return sig.wrap(sig.values[start:stop, i], start, name=self.names[i], vector=False)

    # ------------------------------------------------------------------ calibration and isolation
    def calibrate(self, healthy: Any, **kwargs: Any) -> ResidualSet:
        """Calibrate every residual's test on healthy residual records; returns ``self``.

        ``healthy`` is one record or a list of records with one column per residual; each test gets its
        residual's column of every record (``GLRT.calibrate`` a list of records, a calibrated test with
        ``kwargs`` such as ``window``). Tests without a ``calibrate`` method (``ZScore``) are left as they are.
        """
        recs = list(healthy) if isinstance(healthy, (list, tuple)) else [healthy]
        if not recs:
            raise ValueError("healthy is an empty sequence: give at least one healthy residual record")
        sigs = [self._signal(r, f"healthy[{k}]" if len(recs) > 1 else "healthy") for k, r in enumerate(recs)]
        for i, n in enumerate(self.names):
            test = self.tests[n]
            if hasattr(test, "calibrate"):
                test.calibrate([self._column(s, i) for s in sigs], **kwargs)
        return self

    def isolate(self, residuals: Any) -> Isolation:
        """Test every residual over the whole record and isolate (one decision per residual)."""
        sig = self._signal(residuals)
        decisions = {n: self.tests[n].test(self._column(sig, i)) for i, n in enumerate(self.names)}
        return Isolation(tuple(n for n in self.names if decisions[n].reject), self.names, self.sensors,
                         self.incidence, decisions, (0, sig.nobs))

    def isolate_samples(self, residuals: Any) -> IsolationSeries:
        """Isolation at every sample: a residual fires at the samples where its test alarms.

        Needs tests with per-sample alarms (``Decision.details["alarms"]``): :class:`~tsfdi.GLRT`,
        :class:`~tsfdi.ZScore`, :class:`~tsfdi.detection.glrt.ParameterGLRT`.
        """
        sig = self._signal(residuals)
        fired = np.zeros((sig.nobs, len(self.names)), dtype=bool)
        for i, n in enumerate(self.names):
            d = self.tests[n].test(self._column(sig, i))
            if "alarms" not in d.details:
                raise TypeError(f"tests[{n!r}] ({type(self.tests[n]).__name__}) decides per record, not per sample: "
                                "use isolate_windows, or a GLRT / ZScore test")
            alarms = d.details["alarms"]
            fired[np.asarray(alarms[0] if isinstance(alarms, list) else alarms, dtype=np.int64), i] = True
        pos = np.arange(sig.nobs)
        return IsolationSeries(_readonly(fired), self.names, self.sensors, self.incidence, pos, pos + 1, sig.index)

    def isolate_windows(self, residuals: Any, window: Any, step: Any = 1, *, fs: float | None = None
                        ) -> IsolationSeries:
        """Isolation on every sliding window ``[w * step, w * step + window)``: each residual's test decides on
        the window (:meth:`isolate` of the window).

        ``window`` and ``step`` as in pandas ``rolling``: an int counts samples, a time span (``"2s"``) uses the
        time index of ``residuals`` or ``fs``.
        """
        sig = self._signal(residuals)
        rate = sampling_frequency(sig, fs, "residuals")
        window = window_samples(window, "window", rate, minimum=1)
        step = window_samples(step, "step", rate, minimum=1)
        if window > sig.nobs:
            raise ValueError(f"window must be <= the length of residuals ({sig.nobs}), got {window}")
        starts = np.arange(0, sig.nobs - window + 1, step)
        fired = np.array([[self.tests[n].test(self._column(sig, i, s, s + window)).reject
                           for i, n in enumerate(self.names)] for s in starts], dtype=bool)
        stops = starts + window
        index = sig.index[stops - 1] if sig.index is not None else None
        return IsolationSeries(_readonly(fired.reshape(len(starts), len(self.names))), self.names, self.sensors,
                               self.incidence, starts, stops, index)

    def __repr__(self) -> str:
        return (f"ResidualSet(residuals={self.names}, sensors={self.sensors}, "
                f"tests={[type(t).__name__ for t in self.tests.values()]})")


# ---------------------------------------------------------------------------------------------- airspeed (paper 002)
def airspeed_from_gps(ground_speed: Any, course: Any, wind_speed: Any, wind_direction: Any, *,
                      scale: float = 1.0) -> Any:
    r"""Airspeed from the GPS ground speed and a wind estimate (Hansen et al., eqs. 4-6).

    Parameters
    ----------
    ground_speed, course : array_like, Series or DataArray, shape (nobs,)
        GPS ground speed :math:`v_g` and course :math:`\psi_g` (rad).
    wind_speed, wind_direction : array_like or float
        Wind speed :math:`v_w` and the direction :math:`\psi_w` it blows *towards* (rad; a wind reported as the
        direction it comes from is :math:`\psi_w + \pi`).
    scale : float, default 1
        :math:`a \simeq \cos\alpha\cos\beta`, the ratio of the pitot reading to the true airspeed (eq. 5;
        estimated with the wind by an EKF in paper 002).

    Returns
    -------
    The kind of ``ground_speed``
        :math:`a\sqrt{v_w^2 + v_g^2 - 2 v_g v_w \cos(\psi_w - \psi_g)}` (eqs. 4 and 6): the length of the ground
        velocity minus the wind velocity, scaled to the pitot reading.
    """
    sig = as_signal(ground_speed, "ground_speed", vector=False, allow_constant=True)
    scale = float_like(scale, "scale", minimum=0.0, strict_min=True)
    n = sig.nobs

    def values(v: Any, name: str) -> np.ndarray:
        if np.ndim(v) == 0:
            return np.full(n, float_like(v, name))
        s = as_signal(v, name, vector=False, allow_constant=True)
        if s.nobs != n:
            raise ValueError(f"{name} must have one value per sample of ground_speed ({n}), got {s.nobs}")
        return s.values[:, 0]

    vg = sig.values[:, 0]
    psi_g, vw, psi_w = (values(v, k) for v, k in ((course, "course"), (wind_speed, "wind_speed"),
                                                  (wind_direction, "wind_direction")))
    # the law of cosines written as the length of v_g - v_w (no cancellation when the two are nearly equal)
    rel = np.hypot(vg * np.cos(psi_g) - vw * np.cos(psi_w), vg * np.sin(psi_g) - vw * np.sin(psi_w))
    return sig.wrap(scale * rel, 0, vector=False)


def airspeed_parity(tests: Any = None) -> ResidualSet:
    """Paper 002's parity relations for the airspeed (Hansen et al., Table 2).

    Three estimates of the airspeed: ``"pitot"`` (the pitot-static measurement :math:`v_{pitot}`),
    ``"gps2air"`` (the GPS velocity compensated for the wind, :func:`airspeed_from_gps`) and ``"thrust"`` (the
    airspeed expected from the engine's thrust, an observer of the longitudinal dynamics, eqs. 7-9). The
    residuals R1 = pitot - gps2air, R2 = pitot - thrust, R3 = gps2air - thrust each depend on two of them::

               pitot  gps2air  thrust
        R1       1       1       0
        R2       1       0       1
        R3       0       1       1

    so a pitot fault fires R1 and R2 but not R3. :meth:`ResidualSet.residuals` takes a frame with the columns
    ``pitot``, ``gps2air`` and ``thrust``. ``tests`` as for :class:`ResidualSet` (default ``GLRT(window=100)``
    per residual; calibrate them on healthy flights).
    """
    return ResidualSet.pairwise(("pitot", "gps2air", "thrust"), tests)


# ------------------------------------------------------------------------------------- climb rate (multirotor)
def climb_rate_from_baro(altitude: Any, window: Any, *, fs: float | None = None) -> Any:
    r"""Climb rate from barometric altitude: the least-squares slope over the last ``window`` samples.

    Parameters
    ----------
    altitude : array_like, Series or DataArray, shape (nobs,)
        Barometric altitude (m, up positive).
    window : int or time span
        Samples of each causal slope fit (an int, at least 2), or a time span such as ``"1s"`` (with the time
        index of ``altitude`` or ``fs``). Over ``window = n`` samples of white noise :math:`\sigma_h` at ``fs``
        the slope's standard deviation is :math:`\sigma_h f_s \sqrt{12 / (n (n^2 - 1))}` and its delay
        :math:`(n - 1) / (2 f_s)`.
    fs : float, optional
        Sampling frequency (Hz) when ``altitude`` has no time index.

    Returns
    -------
    The kind of ``altitude``, ``nobs - window + 1`` samples
        The climb rate (m/s, up positive) at samples ``window - 1, ..., nobs - 1`` (index kept): the first
        ``window - 1`` samples have no complete window and are not in the result.

    Raises
    ------
    ValueError
        No sampling frequency (no time index, no ``fs``), a window shorter than 2 samples or longer than
        ``altitude``, non-finite values.
    """
    sig = as_signal(altitude, "altitude", vector=False, allow_constant=True)
    rate = sampling_frequency(sig, fs, "altitude")
    if rate is None:
        raise ValueError("altitude has no time index: pass fs (Hz)")
    n = window_samples(window, "window", rate, minimum=2)
    if n > sig.nobs:
        raise ValueError(f"window must be <= the length of altitude ({sig.nobs} samples), got {n}")
    t = np.arange(n) / rate
    kernel = (t - t.mean()) / np.sum((t - t.mean()) ** 2)           # slope weights, oldest sample first
    slope = np.convolve(sig.values[:, 0], kernel[::-1], mode="valid")
    return sig.wrap(slope, n - 1, vector=False)


def climb_rate_from_accel(accel: Any, attitude: Any, time_constant: Any, *, fs: float | None = None,
                          gravity: float = 9.80665) -> Any:
    r"""Climb rate from the accelerometer: the specific force rotated to the vertical, gravity removed,
    integrated with a slow complementary correction towards zero climb.

    Parameters
    ----------
    accel : array_like, DataFrame or DataArray, shape (nobs, 3)
        Specific force in body axes (m/s^2; x forward, y right, z down: about ``(0, 0, -g)`` in level hover).
    attitude : array_like, DataFrame or DataArray, shape (nobs, 3)
        Roll, pitch and yaw (rad, Z-Y-X Euler angles, body to NED) at the samples of ``accel`` (put them on one
        grid first, e.g. with :func:`tsfdi.align`).
    time_constant : int or time span
        :math:`\tau`, the time constant of the correction (samples, or a time span such as ``"5s"``).
    fs : float, optional
        Sampling frequency (Hz) when ``accel`` has no time index.
    gravity : float
        :math:`g` (m/s^2).

    Returns
    -------
    The kind of ``accel``, shape (nobs,)
        The climb rate (m/s, up positive), named ``"climb_rate"`` for pandas / xarray.

    Notes
    -----
    The climb acceleration is :math:`a = -(R_{31} f_x + R_{32} f_y + R_{33} f_z) - g` with
    :math:`(R_{31}, R_{32}, R_{33}) = (-\sin\theta, \sin\phi\cos\theta, \cos\phi\cos\theta)` the last row of the
    body-to-NED rotation. Integrated alone it drifts (an accelerometer bias :math:`b` gives :math:`b t`); the
    estimate is the integral corrected by a proportional-integral loop that pulls it towards zero,

    .. math:: V(s) = \frac{s}{(s + \omega)^2} A(s), \qquad \omega = 1 / \tau,

    discretised by the bilinear transform and started at rest. It follows the climb rate at frequencies well
    above :math:`\omega` and forgets a constant bias (the loop's integral learns it) after a few :math:`\tau`:
    a flight holding its altitude on average, climbs and descents shorter than :math:`\tau`. Its low-frequency
    content is the part the other estimates (barometer, GPS) measure better; a fault of the accelerometer
    shows as a transient of about :math:`\tau` seconds, a bias step :math:`\Delta b` peaking at
    :math:`\Delta b\,\tau / e`. Discard the first few :math:`\tau` (the turn-on bias being learned).
    """
    from scipy.signal import bilinear, lfilter

    sa = as_signal(accel, "accel", vector=True, allow_constant=True)
    so = as_signal(attitude, "attitude", vector=True, allow_constant=True)
    for what, s in (("accel", sa), ("attitude", so)):
        if s.values.shape[1] != 3:
            raise ValueError(f"{what} must have 3 columns, got {s.values.shape[1]}")
    if so.nobs != sa.nobs:
        raise ValueError(f"attitude must have one row per sample of accel ({sa.nobs}), got {so.nobs}")
    rate = sampling_frequency(sa, fs, "accel")
    if rate is None:
        raise ValueError("accel has no time index: pass fs (Hz)")
    tau = window_samples(time_constant, "time_constant", rate, minimum=1) / rate
    gravity = float_like(gravity, "gravity", minimum=0.0, strict_min=True)
    roll, pitch = so.values[:, 0], so.values[:, 1]
    f = sa.values
    down = -np.sin(pitch) * f[:, 0] + np.sin(roll) * np.cos(pitch) * f[:, 1] + np.cos(roll) * np.cos(pitch) * f[:, 2]
    omega = 1.0 / tau
    b, a = bilinear([1.0, 0.0], [1.0, 2.0 * omega, omega * omega], rate)
    return sa.wrap(lfilter(b, a, -(down + gravity)), 0, name="climb_rate", vector=False)


# ---------------------------------------------------------------------------------------------- frozen output
def frozen_output(signal: Any, window: Any, *, tolerance: float = 0.0, fs: float | None = None) -> Any:
    r"""Flag the samples where a sensor's output has not moved over the last ``window`` samples.

    A per-sensor self-check for a frozen (stuck) output: the raw samples of a healthy sensor move by at least
    their noise from one sample to the next, a frozen sensor repeats one value. The check looks at the sensor's
    own output only, so its alarm names the sensor directly, whatever its parity residuals do (a sensor frozen
    while the quantity it measures holds still reads nearly the truth, and only its noise vanishes).

    Parameters
    ----------
    signal : array_like, Series or DataArray, shape (nobs,)
        The raw output of one sensor channel at its own rate (before any filtering or resampling: a
        zero-order hold onto a faster grid repeats samples).
    window : int or time span
        :math:`n`, samples of the check (an int, at least 2), or a time span such as ``"0.2s"`` (with the time
        index of ``signal`` or ``fs``).
    tolerance : float, default 0
        Largest spread :math:`\max - \min` of the window's samples that counts as frozen, in the units of
        ``signal``. 0: the window holds one repeated value.
    fs : float, optional
        Sampling frequency (Hz) when ``window`` is a time span and ``signal`` has no time index.

    Returns
    -------
    The kind of ``signal``, bool, shape (nobs,)
        True at sample :math:`k` when the samples :math:`k - n + 1, \dots, k` all lie within ``tolerance`` of
        each other; False at the first :math:`n - 1` samples (no complete window yet). Index kept.

    Raises
    ------
    ValueError
        A window shorter than 2 samples or longer than ``signal``, a negative ``tolerance``, non-finite values,
        a time span without a sampling frequency.

    Notes
    -----
    False-alarm bound. Let the output be :math:`y_i = Q(s_i + e_i)` with :math:`s_i` any signal, :math:`e_i`
    independent noise whose density is at most :math:`f_{max}` (:math:`1 / (\sigma\sqrt{2\pi})` for Gaussian
    noise of standard deviation :math:`\sigma`) and :math:`Q` a rounding to a resolution :math:`\Delta`
    (:math:`\Delta = 0` for none). Given the first sample of a window, each of the :math:`n - 1` others must fall
    in an interval of width :math:`2(\text{tolerance} + \Delta)` about it, so a healthy sensor raises the flag
    at a given sample with probability at most

    .. math:: P_F \le \left(2 f_{max} (\text{tolerance} + \Delta)\right)^{n - 1}.

    For example an accelerometer with :math:`\sigma` = 0.011 m/s^2 and :math:`\Delta` = 0.0048 m/s^2
    (16 g over 16 bits): 0.35 per sample, :math:`10^{-22}` for :math:`n = 50`. A frozen output raises the flag at
    the :math:`n`-th sample of its repeated value (with ``tolerance`` 0).

    To join the parity decision of a :class:`ResidualSet` whose table has the sensor as a column, count the
    flag as an alarm of every residual of that column (``fired | np.outer(flag, table[sensor])`` on the samples
    of the residuals): its fired pattern is then the sensor's column, the frozen sensor is isolated.
    """
    sig = as_signal(signal, "signal", vector=False, allow_constant=True)
    rate = sampling_frequency(sig, fs, "signal")
    n = window_samples(window, "window", rate, minimum=2)
    if n > sig.nobs:
        raise ValueError(f"window must be <= the length of signal ({sig.nobs} samples), got {n}")
    tolerance = float_like(tolerance, "tolerance", minimum=0.0)
    rolling = pd.Series(sig.values[:, 0]).rolling(n)
    spread = (rolling.max() - rolling.min()).to_numpy()
    flag = np.zeros(sig.nobs, dtype=bool)
    flag[n - 1:] = spread[n - 1:] <= tolerance
    return sig.wrap(flag, 0, vector=False)

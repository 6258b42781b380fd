"""Sliding-window (Dutta et al., paper 003, Fig. 3) or sequential fault detection and identification of one stream.

:class:`Monitor` tests every window with the healthy model, waits for the post-failure steady state (rolling
variances, Fig. 7 discussion) and then identifies every window with the fault models (without fault models it
detects only); the windows are tested by the windowed engine (:class:`tsfdi.windows.ResidualWindows`) and labelled
by its decision rule (:func:`tsfdi.windows.decide`). With ``rule="sprt"`` it decides sample by sample instead: a
restarted SPRT of the healthy residuals detects and a restarted multi-hypothesis SPRT of the fault models identifies
(:mod:`tsfdi.detection.sequential`), each event at its deciding sample.
"""

from __future__ import annotations

import copy
import dataclasses
import datetime
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import (Signal, as_signal, model_input, refuse_masked, rolling_variance, sampling_frequency,
                         window_samples)
from tsfdi._validation import boolean, float_like, option, probability
from tsfdi.coverage import Coverage, check_coverage, warn_if_not_covered, warn_records_not_covered
from tsfdi.detection.base import ResidualTest
from tsfdi.detection.sequential import SPRT, msprt, renewal_walk
from tsfdi.detection.whiteness import LjungBox
from tsfdi.exceptions import CoverageWarning
from tsfdi.models import FPResults, InputOutputResults
from tsfdi.windows import RULES, SEQUENTIAL_RULES, ResidualWindows

__all__ = ["Monitor", "MonitorResult", "MonitorEvent", "rolling_variance"]

@dataclass(frozen=True)
class MonitorEvent:
    """One event of a :class:`Monitor`.

    Attributes
    ----------
    time : float
        Time from the start of the stream (the end of the window that produced the event): seconds when the
        monitor has ``fs``, samples without.
    kind : {"detection", "steady", "identification"}
        Fault detected by the healthy model; post-failure steady state reached (the rolling variance of every
        channel over a window wholly after the detection at or below its steady-state threshold, paper 003; at the
        end of that variance window); a window identified.
    label : str or None
        The identified model (identification events; ``None`` for an ambiguous or empty decision).
    status : str
        ``"fault"``, ``"steady"`` or the identification status ``"identified"``, ``"ambiguous"``, ``"none"``.
    accepted : tuple of str
        Models accepted by the residual test (identification events).
    window : tuple of float
        ``(start, end)`` time of the window (seconds with ``fs``, samples without).
    """

    time: float
    kind: str
    label: str | None = None
    status: str = ""
    accepted: tuple = ()
    window: tuple = ()


@dataclass(frozen=True, eq=False)
class MonitorResult:
    """Outcome of :meth:`Monitor.run`.

    Attributes
    ----------
    events : list of MonitorEvent
    windows : pandas.DataFrame
        One row per window: ``start``, ``end`` (seconds with ``fs``, else samples), ``detect_statistic`` (largest
        channel statistic/threshold ratio of the healthy model), ``detect_pvalue``, ``fault`` (healthy model
        rejects), ``phase`` ("healthy", "transient", "steady"), ``status``, ``label``, ``accepted`` (empty without
        fault models), and ``variance_<channel>``, the rolling variance of every channel.
    detection_time, steady_time : float or None
        Time of the first detection / steady-state event.
    label : str or None
        Most frequent label over the identified windows (``None`` if none, always ``None`` without fault models).
    models : tuple of str
        The fault models' names; empty for a detection-only monitor.
    fs : float or None
        Sampling frequency in Hz: times are in seconds with it, in samples without.
    steady_thresholds : ndarray, shape (k,), or None
        The steady-state variance thresholds the monitor used (``None``: no steady-state check).
    identification_time : float or None
        Time of the first ``"identification"`` event whose status is ``"identified"`` (with ``rule="sprt"``: the
        sequential decision, at its deciding sample).
    coverage : Coverage or None
        Of :meth:`Monitor.run`: whether the baseline covers the whole record (:func:`tsfdi.coverage.check_coverage`:
        the detection test's record law, else the spread of the baseline's fitting records); ``None`` when that
        cannot be said (one or two fitting records, a test without a record law, a short record) and for a stream
        fed by :meth:`Monitor.update`.
    """

    events: list
    windows: pd.DataFrame
    detection_time: float | None
    steady_time: float | None
    label: str | None
    models: tuple = ()
    fs: float | None = None
    steady_thresholds: np.ndarray | None = None
    identification_time: float | None = None
    coverage: Coverage | None = None

    def to_frame(self) -> pd.DataFrame:
        """The events as a ``DataFrame`` (one row per event)."""
        return pd.DataFrame([{"time": e.time, "kind": e.kind, "label": e.label, "status": e.status,
                              "accepted": ",".join(e.accepted), "window_start": e.window[0] if e.window else np.nan,
                              "window_end": e.window[1] if e.window else np.nan} for e in self.events],
                            columns=["time", "kind", "label", "status", "accepted", "window_start", "window_end"])

    def plot(self, ax: Any = None) -> Any:
        """Rolling variances against time with the steady-state thresholds and events (Dutta et al., Fig. 7)."""
        from tsfdi.plotting.monitoring import plot_monitor

        return plot_monitor(self, ax=ax)

    def __repr__(self) -> str:
        faults = int(self.windows["fault"].sum()) if len(self.windows) else 0
        what = "detection only" if not self.models else f"models={list(self.models)}"
        return (f"MonitorResult({what}, windows={len(self.windows)}, fault windows={faults}, events="
                f"{len(self.events)}, detection_time={self.detection_time}, steady_time={self.steady_time}, "
                f"label={self.label!r})")


def _is_span(value: Any) -> bool:
    """Whether ``value`` is a time span (``"2s"``, ``Timedelta``, ``timedelta``, ``timedelta64``), not a count."""
    return isinstance(value, (str, datetime.timedelta, np.timedelta64))


def _check_span(value: Any, name: str) -> None:
    """A time span given before ``fs`` is known: parsed now (a typo is an error at once), converted later."""
    try:
        span = pd.Timedelta(value)
    except (TypeError, ValueError, OverflowError):
        span = pd.NaT
    if span is pd.NaT or not span > pd.Timedelta(0):
        raise ValueError(f"{name} must be an int (samples) or a positive time span such as '2s', got {value!r}")


class Monitor:
    r"""Sliding-window fault detection and identification (Dutta et al., Fig. 3).

    Every window of ``window`` samples (or a time span), ``step`` apart, goes through three phases:

    1. *healthy*: the window's residuals through the healthy ``baseline`` model are tested with
       ``detection_test``; the first rejection is a ``"detection"`` event at the window's end.
    2. *transient*: the rolling variance of every channel over ``steady_window`` is compared with
       ``steady_thresholds`` (paper 003, Fig. 7 discussion: estimated in the baseline phase as the largest
       steady-state variances of the fault records -- by default those of the records the fault models were fitted
       on); the first variance window lying wholly after the detection with every channel at or below its threshold
       is a ``"steady"`` event at the end of that variance window, the time the steady state is established.
    3. *steady*: every window starting at or after the start of that variance window is identified: its
       residuals through each fault model in ``models`` are tested with ``test``, and ``rule`` turns the
       decisions into a label (``"identification"`` event per window).

    Without fault models (``models=None``) the monitor detects only: every window is tested with the healthy
    model (``fault`` in :attr:`MonitorResult.windows`), the first rejection is the ``"detection"`` event, a
    ``"steady"`` event follows only with ``steady_thresholds`` given, and no window is identified.

    Parameters
    ----------
    baseline : fitted results
        Healthy model :math:`M_0`: AR or VAR results, or ARX results (an input-output model, e.g. an FP-ARX's
        point ``.at(k)``, with the controller's commands as inputs: then every block of the stream comes with its
        input, ``run(signal, u=...)`` / ``update(samples, u=...)``); or functionally pooled results
        (:class:`~tsfdi.FPResults`, a global model over operating points ``k``): then every stream comes with its
        logged operating point, ``run(signal, k={"speed": 4.2})`` / ``update(samples, k=...)`` /
        ``screen(records, k="speed")``, and is filtered by every FP model at it, ``res.at(k)`` (the monitor of the
        point models ``.at(k)``, whose tests calibrated on the FP null hold at every ``k``).
    models : mapping or None
        Name -> fitted fault models :math:`M_1, M_2, \dots`, with the baseline's channels (and, for an ARX
        baseline, ARX models with its inputs: the kinds do not mix; functionally pooled models beside point models,
        all of them over the same operating parameters); ``None`` (or an empty mapping) for detection only.
    window : int or time span
        Window length, as in pandas ``rolling``: an int counts samples, a time span (``"20s"``,
        ``pandas.Timedelta``) is converted with ``fs``.
    step : int or time span, optional
        Distance between window starts (default ``"1s"`` as in the paper, at least one sample).
    fs : float, optional
        Sampling frequency in Hz. By default it is read from the time index of the first block of samples
        (:meth:`run`, :meth:`update`): a ``DatetimeIndex`` / ``TimedeltaIndex``, a numeric pandas index named
        ``"time"`` or an xarray time coordinate (seconds), at least two samples. Time spans need it; event and
        window times are in seconds with it, in samples without it.
    test : ResidualTest or mapping, optional
        Identification test, :class:`~tsfdi.LjungBox` (default ``LjungBox(lags=25, alpha=1e-3)``) or
        :class:`~tsfdi.FTest`; or a mapping model name -> test (each fault model with its own thresholds, e.g.
        ``test.calibrate(spec.held_out_residuals(), window=...)`` per model; then ``detection_test`` is required).
    detection_test : ResidualTest, optional
        Detection test on the healthy model's residuals (default: ``test``).
    steady_thresholds : array_like, shape (k,), optional
        Rolling-variance thresholds per channel. ``None`` (default): paper 003's rule on the fault models' own
        fitting records (steady post-failure records): the largest variance of every channel over every
        ``steady_window`` of every record (``ValueError`` when a model has no record that long); without fault
        models no steady-state check is made.
    steady_window : int or time span, optional
        Length of the rolling-variance window (default ``"10s"``, the paper's); it sets both the variance checked
        and, by default, the thresholds.
    rule : {"paper", "likelihood", "pvalue", "sprt"}
        Decision rule (see :data:`tsfdi.windows.RULES`), or ``"sprt"``: the sequential monitor (see Notes), with no
        window and no residual test (``window`` and ``test`` must be left out).
    sprt_alpha : float
        ``rule="sprt"``: the error probability of the identification's bound :math:`\ln((M - 1)/\alpha)`
        (:func:`~tsfdi.detection.sequential.msprt`) and of the default ``detection_test``
        (``SPRT("variance", ratio=2.0, alpha=sprt_alpha, beta=sprt_alpha, restart=True)``).
    sprt_scale : float
        ``rule="sprt"``: the scale of the fault models' log-likelihoods (1 for exact models;
        :func:`~tsfdi.detection.sequential.msprt_scale` on held-out records for estimated ones).

    Attributes
    ----------
    k_names : tuple of str
        The operating parameters of the functionally pooled models (empty for point models).
    window, step, steady_window : int or None
        The lengths in samples; ``None`` for a time span while ``fs`` is not known yet (before the first samples).
    steady_thresholds : ndarray, shape (k,), or None
        The thresholds in use (given, or from the fault models once ``steady_window`` is known in samples).

    Notes
    -----
    ``rule="sprt"`` (sequential monitoring, Kopsaftopoulos & Fassois 2015): every sample's healthy residual feeds
    ``detection_test``, an :class:`~tsfdi.SPRT` with ``restart=True`` (variance or mean alternative, scaled by its
    ``scale_`` when calibrated): its statistic starts a new cycle at 0 whenever it crosses the lower bound (H0
    accepted) or the upper bound (an alarm); the first alarm is the ``"detection"`` event, at the deciding sample,
    its ``window`` the cycle that raised it. The steady-state check runs at the end of every ``step`` as in the
    windowed monitor; from the start of the variance window that establishes the steady state, the fault models'
    per-sample Gaussian log-likelihoods (:meth:`~tsfdi.windows.ResidualWindows.loglik`) feed the restarted
    multi-hypothesis rule (the pairwise CUSUMs of :func:`~tsfdi.detection.sequential.msprt` with
    ``restart=True``); the first model to dominate every other by the bound is the one ``"identification"``
    event (status ``"identified"``, at its deciding sample, or at the steady event when the samples before it
    already decide), after which the phase is ``"identified"``. :attr:`MonitorResult.windows` has one row per
    complete ``step``: ``detect_statistic`` is the largest detection statistic over the step over the upper bound
    (``fault``: it reached the bound, an alarm, within the step; every alarm counts, before and after the
    detection), ``detect_pvalue`` is NaN. :meth:`update` continues both statistics exactly across blocks (the same
    events and rows as :meth:`run` on the concatenated stream) and keeps ``steady_window`` plus the models' order
    samples: its memory does not grow with the stream (only the rows and events do).

    False alarms of the sequential detection on healthy data (independent residuals of the assumed law): the
    alarms form a renewal process of cycles, so the long-run rate is :math:`p / E_0[N]` per sample, :math:`p` the
    probability that a cycle ends at the upper bound and :math:`E_0[N]` the mean cycle length. Wald's bound holds
    exactly, :math:`p \le e^{-A} = \alpha / (1 - \beta)`; neglecting the overshoot, :math:`p \approx \alpha` and
    :math:`E_0[N] \approx` :meth:`SPRT.asn(1.0) <tsfdi.SPRT.asn>`, hence about :math:`3600 f_s \alpha /
    \mathrm{ASN}_0` false alarms per hour, an overestimate (the overshoot of the chi-square log-likelihood ratio
    lowers :math:`p`: about half that rate for ``ratio=2``, see the guide). The detection delay after a change to
    the alternative is Wald's :math:`\mathrm{ASN}_1` plus the time to climb from where the statistic was at the
    change (about 1.45 ASN_1 for ``ratio=2``); both are computed with the overshoot by the Markov-chain
    approximation in the tests (``tests/test_monitoring_sprt.py``).

    :meth:`run` filters the record once through each model and computes every window's statistic from prefix
    sums (:class:`~tsfdi.windows.ResidualWindows`); :meth:`update` feeds a stream chunk by chunk and gives the same
    events as :meth:`run` on the concatenated stream.

    A named signal (a ``DataFrame``, a ``DataArray`` with a channel coordinate) is matched to the baseline's
    channels by name: its columns may come in any order, and a missing or an extra channel raises a
    ``ValueError`` naming it. Later blocks of a stream are matched to the first one the same way. Arrays and
    models fitted on arrays are matched by position.

    References
    ----------
    Dutta, McKay, Kopsaftopoulos, Gandhi, *Statistical Time Series Methods for Multicopter Fault Detection and
    Identification* (paper 003), Fig. 3, Fig. 7 and eqs. 8-14.
    """

    def __init__(self, baseline: Any, models: Mapping | None = None, *, window: Any = None, step: Any = None,
                 fs: float | None = None, test: Any = None, detection_test: Any = None, steady_thresholds: Any = None,
                 steady_window: Any = None, rule: str = "paper", sprt_alpha: float = 0.01,
                 sprt_scale: float = 1.0) -> None:
        self.rule = option(rule, "rule", RULES + SEQUENTIAL_RULES)
        self.sequential = self.rule in SEQUENTIAL_RULES
        self._fs = None if fs is None else float_like(fs, "fs", minimum=0.0, strict_min=True)
        models = {} if models is None else models
        if not isinstance(models, Mapping):
            raise TypeError(f"models must be a mapping name -> fitted fault models, or None to detect only, got "
                            f"{type(models).__name__}")
        if not hasattr(baseline, "residuals"):
            raise TypeError(f"baseline must be fitted results (AR, VAR or ARX), got {type(baseline).__name__}")
        self.baseline = baseline
        self.models = dict(models)
        # functionally pooled models: every one over the same operating parameters, filtered at the stream's k
        pooled = {n: m for n, m in {"baseline": baseline, **{f"models[{k!r}]": v for k, v in models.items()}}.items()
                  if isinstance(m, FPResults)}
        params = {n: list(m.model.k_names) for n, m in pooled.items()}
        first = next(iter(params.items()), (None, []))
        other = next((n for n, p in params.items() if set(p) != set(first[1])), None)
        if other is not None:
            raise ValueError(f"{first[0]} is functionally pooled over {first[1]} but {other} over {params[other]}: "
                             "the models of a monitor are filtered at one operating point; fit them over the same "
                             "operating parameters")
        self.k_names = tuple(first[1])
        self._set_point(None)                 # (the checks read each FP model at its first fitting point)
        baseline, models = self._base, self._faults
        if len({isinstance(m, InputOutputResults) for m in (baseline, *models.values())}) > 1:
            raise TypeError("baseline and models mix input-output (ARX, VARX) models with AR / VAR models: their "
                            "residuals are of the output given u, the others of the output alone; use one kind")
        engine = ResidualWindows({"baseline": baseline, **{f"models[{k!r}]": v for k, v in models.items()}}
                                 if isinstance(baseline, InputOutputResults) else {"healthy": baseline})
        self.nchan = engine.nchan
        #: whether the models take an input ``u`` (ARX models), the same for baseline and fault models (checked by
        #: ``engine``), and its channels in the models' order with whether they are named
        self.inputs = engine.inputs
        self._order = engine.orders["baseline" if self.inputs else "healthy"]
        self._fault_order = max(ResidualWindows(models).orders.values()) if models else 0
        u_data = baseline.model.u_data if self.inputs else None
        self._u_channels = None if u_data is None else ([str(c) for c in u_data.channels], u_data.named)
        if models:
            nf = ResidualWindows(models).nchan
            if nf != self.nchan:
                raise ValueError(f"models have {nf} channel(s) but baseline has {self.nchan}")
        data = getattr(getattr(baseline, "model", None), "data", None)     # the channels it was fitted on
        self._model_named = isinstance(data, Signal) and data.named
        self._model_channels = list(data.channels) if isinstance(data, Signal) else [
            f"y{i}" for i in range(self.nchan)]
        # lengths in samples now, or time spans kept until fs is read from the data
        if self.sequential and window is not None:
            raise ValueError(f"window does not apply to rule='sprt' (the statistic is sequential: sample by sample, "
                             f"no window), got window={window!r}; leave it out")
        if not self.sequential and window is None:
            raise TypeError("window is required (the length of the tested windows) unless rule='sprt'")
        self.window = None
        self._lengths = {"step": (step, 1), "steady_window": ("10s" if steady_window is None else steady_window, 2)}
        if not self.sequential:
            self._lengths = {"window": (window, 3), **self._lengths}
        for name, (value, minimum) in self._lengths.items():
            if value is None and name == "step":
                continue
            if self._fs is None and _is_span(value):
                _check_span(value, name)
            else:
                window_samples(value, name, self._fs, minimum=minimum)
        self.sprt_alpha = probability(sprt_alpha, "sprt_alpha")
        self.sprt_scale = float_like(sprt_scale, "sprt_scale", minimum=0.0, strict_min=True)
        if self.sequential:
            self._sequential_tests(test, detection_test)
        else:
            self._window_tests(test, detection_test)
        self._steady_given = steady_thresholds is not None
        self._steady_cache: dict = {}           # steady_window in samples -> the thresholds of the fault models
        if steady_thresholds is None:
            self.steady_thresholds = None          # from the fault models' records once steady_window is known
        else:
            refuse_masked(steady_thresholds, "steady_thresholds")
            try:
                thr = np.asarray(steady_thresholds, dtype=np.float64).ravel()
            except (TypeError, ValueError):
                raise TypeError(f"steady_thresholds must be {self.nchan} number(s), got {steady_thresholds!r}") \
                    from None
            if thr.shape != (self.nchan,) or not np.all(np.isfinite(thr)) or np.any(thr <= 0):
                raise ValueError(f"steady_thresholds must hold {self.nchan} finite positive variance(s), got "
                                 f"{steady_thresholds!r}")
            self.steady_thresholds = thr
        self.reset()

    def _window_tests(self, test: Any, detection_test: Any) -> None:
        """The residual tests of the windowed rules."""
        test = LjungBox(lags=25, alpha=1e-3) if test is None else test
        if isinstance(test, Mapping):
            test = dict(test)
            missing = [n for n in self.models if n not in test]
            if missing or not all(isinstance(t, ResidualTest) for t in test.values()):
                raise ValueError(f"test as a mapping must hold a residual test for every model {list(self.models)}")
            if detection_test is None:
                raise TypeError("detection_test is required when test is a mapping (one test per fault model)")
        elif not isinstance(test, ResidualTest):
            raise TypeError(f"test must be a residual test (LjungBox, FTest), got {type(test).__name__}")
        detection_test = test if detection_test is None else detection_test
        if not isinstance(detection_test, ResidualTest):
            raise TypeError(f"detection_test must be a residual test, got {type(detection_test).__name__}")
        self.test, self.detection_test = test, detection_test

    def _sequential_tests(self, test: Any, detection_test: Any) -> None:
        """The SPRT of the sequential rule (default: variance ratio 2, error rates ``sprt_alpha``)."""
        if test is not None:
            raise ValueError("test does not apply to rule='sprt' (the fault models are told apart by their "
                             "residuals' log-likelihoods, not by a residual test); leave it out")
        if len(self.models) == 1:
            raise ValueError("rule='sprt' chooses among the fault models and needs at least two (or none, to "
                             f"detect only), got {list(self.models)}")
        if detection_test is None:
            detection_test = SPRT("variance", ratio=2.0, alpha=self.sprt_alpha, beta=self.sprt_alpha, restart=True)
        if not isinstance(detection_test, SPRT) or detection_test.alternative == "model" or not detection_test.restart:
            raise TypeError("detection_test with rule='sprt' must be an SPRT of the healthy residuals with "
                            "alternative 'variance' or 'mean' and restart=True (the monitoring form), e.g. "
                            f"SPRT('variance', ratio=2.0, restart=True); got {detection_test!r}")
        self.test, self.detection_test = None, detection_test

    def _set_point(self, k: dict | None) -> None:
        """Filter the stream at operating point ``k`` (name -> value): the models the engine runs, ``_base`` and
        ``_faults``, are the functionally pooled ones ``.at(k)`` (``None``: each at its first fitting point, for
        the checks of the constructor), the point models as given."""
        def at(res):
            if not isinstance(res, FPResults):
                return res
            return res.at(res.model.k[0] if k is None else [k[n] for n in res.model.k_names])

        self._k = k
        self._base, self._faults = at(self.baseline), {n: at(m) for n, m in self.models.items()}
        if self.sequential:
            sigma = self._base.sigma if hasattr(self._base, "sigma") else self._base.sigma2
            self._sigma = np.atleast_2d(np.asarray(sigma, dtype=np.float64))

    def _stream_point(self, k: Any) -> None:
        """Check the operating point ``k`` given with a block of the stream (:meth:`update`) and, with the first
        block of a stream, filter it there."""
        if not self.k_names:
            if k is not None:
                raise TypeError(f"k is the operating point of functionally pooled models (FPResults), but the "
                                f"monitor's models are point models: leave k out (got k={k!r})")
            return
        if k is None:
            if self._k is None:
                raise TypeError(f"k is required: the monitor's models are functionally pooled over "
                                f"{list(self.k_names)}; give the stream's operating point, k={{"
                                f"{', '.join(repr(n) + ': ...' for n in self.k_names)}}}")
            return
        if not isinstance(k, Mapping):
            raise TypeError(f"k must be a mapping operating parameter -> value (e.g. {{{self.k_names[0]!r}: 4.2}}), "
                            f"got {k!r}")
        missing = [n for n in self.k_names if n not in k]
        extra = [n for n in k if n not in self.k_names]
        if missing or extra:
            raise ValueError(f"k must give exactly the models' operating parameters {list(self.k_names)}, got "
                             f"{list(k)}" + (f" (missing {missing})" if missing else f" ({extra} not among them)"))
        point = {n: float_like(k[n], f"k[{n!r}]") for n in self.k_names}
        if self._k is None:
            self._set_point(point)
        elif point != self._k:
            raise ValueError(f"k: the stream is monitored at {self._k}, got {point}: a stream has one operating point; "
                             "reset() (or run) to monitor another")

    def __repr__(self) -> str:
        what = f"models={list(self.models)}" if self.models else "models=None (detection only)"
        if self.k_names:
            what += f", functionally pooled over {list(self.k_names)}"

        def length(name):       # samples, or the time span while fs is unknown
            value = getattr(self, name)
            return value if value is not None else repr(self._lengths[name][0] or "1s")

        if self.sequential:
            return (f"Monitor({what}, rule='sprt', detection_test={self.detection_test!r}, sprt_alpha="
                    f"{self.sprt_alpha:g}, step={length('step')}, fs={self.fs})")
        return (f"Monitor({what}, window={length('window')}, step={length('step')}, fs={self.fs}, "
                f"rule={self.rule!r})")

    def _set_fs(self, fs: float | None, source: str = "") -> None:
        """Set ``fs`` and the lengths in samples (those given as time spans need it)."""
        self.fs = fs
        for name, (value, minimum) in self._lengths.items():
            if value is None:                       # the default step (checked above): 1 s, at least one sample
                size = None if fs is None else max(1, int(round(fs)))
            elif fs is None and _is_span(value):
                size = None
            else:
                try:
                    size = window_samples(value, name, fs, minimum=minimum)
                except ValueError as err:
                    raise ValueError(f"{err}{source}") from None
            setattr(self, name, size)
        if not self._steady_given:
            V = self.steady_window
            if self.models and V is not None and V not in self._steady_cache:
                self._steady_cache[V] = self._model_steady_thresholds(V)
            self.steady_thresholds = self._steady_cache.get(V) if self.models else None

    def _model_steady_thresholds(self, V: int) -> np.ndarray:
        """Paper 003's steady-state thresholds: per channel, the largest variance over every ``V``-sample window of
        the records the fault models were fitted on (steady post-failure records; records shorter than ``V`` give no
        window, a model without a record that long is refused)."""
        top = np.zeros(self.nchan)
        for name, res in self._faults.items():
            recs = list(getattr(getattr(res, "model", None), "records", None) or ())
            lengths = []
            for i, rec in enumerate(recs):
                if rec.named and self._model_named:
                    rec = rec.match_channels(self._model_channels, f"models[{name!r}] record {i}")
                lengths.append(rec.nobs)
                if rec.nobs >= V:
                    top = np.maximum(top, rolling_variance(rec.values, V, 1).max(axis=0))
            if not lengths:
                raise ValueError(f"steady_thresholds: the fault model {name!r} carries no records to take the "
                                 "steady-state variances from (paper 003: the largest variance of every channel "
                                 "over its steady post-failure records); give steady_thresholds")
            if max(lengths) < V:
                secs = (lambda n: f" ({n / self.fs:g} s)") if self.fs else (lambda n: "")
                raise ValueError(f"steady_window ({V} samples{secs(V)}) is longer than every record the fault model "
                                 f"{name!r} was fitted on (at most {max(lengths)} samples{secs(max(lengths))}): the "
                                 "steady-state thresholds are the largest variances over windows of steady_window "
                                 "in those records; give a shorter steady_window or steady_thresholds")
        return top

    def reset(self) -> None:
        """Forget the stream: back to the healthy phase at time 0 (with ``fs`` as given to the constructor; with
        functionally pooled models, the next stream gives its operating point ``k``)."""
        self._set_fs(self._fs)
        self._k = None
        self._channels: list | None = None     # channel names of the stream (its first block), in model order
        self._named = False
        self._buffer = np.empty((0, self.nchan))
        self._ubuffer = np.empty((0, len(self._u_channels[0]) if self.inputs else 0))   # the input beside it
        self._offset = 0           # stream position of _buffer[0]
        self._next = 0             # stream position of the next window start
        self._phase = "healthy"
        self._detect_pos: int | None = None
        self._steady_pos: int | None = None
        self._rows: list = []
        self._events: list = []
        # the sequential rule's state: O(k (V + p) + M^2), whatever the length of the stream
        self._s = 0.0              # detection SPRT statistic after the last processed sample
        self._cycle = 0            # stream position where its current cycle started (its last restart)
        self._w = np.zeros((len(self.models), len(self.models)))    # pairwise CUSUMs of the identification
        self._ident_pos: int | None = None      # next stream position the identification accumulates
        self._row_peak = -np.inf   # largest statistic over the current step (before restarts)
        self._row_alarm = False
        self._row_ident: tuple = ()             # (label, status) of an identification within the current step

    # ------------------------------------------------------------------------------------------------------------
    def _values(self, samples: Any, u: Any) -> tuple:
        """The samples in the stream's channel order and their input (in the models' order; ``None`` without
        inputs); the first block sets the channels (matched to the baseline's by name when both are named) and,
        without ``fs``, the sampling frequency from its time index."""
        sig = as_signal(samples, "signal", allow_constant=True)
        usig = model_input(u, sig, self._u_channels)
        return self._channel_values(sig), None if usig is None else usig.values

    def _channel_values(self, sig: Signal) -> np.ndarray:
        if self._channels is not None:
            return sig.match_channels(self._channels, "signal", named=self._named).values
        sig = sig.match_channels(self._model_channels, "signal", named=self._model_named)
        if self.fs is not None:          # a given fs must agree with the signal's time index, if it has one
            sampling_frequency(sig, self.fs, "signal")
        else:
            fs = sampling_frequency(sig, None, "signal")
            spans = [f"{name} = {value!r}" if value is not None else f"{name} = '1s' (the default)"
                     for name, (value, _) in self._lengths.items() if value is None or _is_span(value)]
            if fs is None and spans:
                raise ValueError(f"{', '.join(spans)} {'is a time span' if len(spans) == 1 else 'are time spans'}, "
                                 "but fs is not given and signal carries no time index to read it from (a "
                                 "DatetimeIndex / TimedeltaIndex, a numeric index named 'time' or an xarray time "
                                 "coordinate, with at least two samples in the first block): give fs=, such a "
                                 "signal, or count samples with ints")
            self._set_fs(fs, f" (fs = {fs:g} Hz read from the time index of signal)" if fs else "")
        # the names of a named signal, else those of the model (an array is taken in the model's order)
        self._channels, self._named = list(sig.channels if sig.named else self._model_channels), sig.named
        return sig.values

    def _residuals(self, res: Any, lo: int, hi: int | None = None) -> np.ndarray:
        """Residuals of the buffered stream positions ``[lo, hi)`` through ``res`` (given their input for ARX)."""
        a, b = lo - self._offset, None if hi is None else hi - self._offset
        e = (res.residuals(self._record(self._buffer[a:b])) if not self.inputs else
             res.residuals(self._record(self._buffer[a:b]), self._input(self._ubuffer[a:b])))
        return np.asarray(e, dtype=np.float64).reshape(-1, self.nchan)

    def _input(self, ux: np.ndarray | None) -> Any:
        """Buffered inputs as a signal every model takes by name (named inputs: each model in its own order)."""
        if ux is None or not self._u_channels[1]:
            return ux
        return pd.DataFrame(ux, columns=self._u_channels[0])

    def _append(self, x: np.ndarray, ux: np.ndarray | None) -> None:
        self._buffer = np.concatenate([self._buffer, x])
        if ux is not None:
            self._ubuffer = np.concatenate([self._ubuffer, ux])

    def _keep(self, keep: int) -> None:
        """Forget the buffered samples before stream position ``keep``."""
        self._buffer = self._buffer[keep - self._offset:]
        self._ubuffer = self._ubuffer[keep - self._offset:]
        self._offset = keep

    def _record(self, x: np.ndarray) -> Any:
        """Samples of the stream as a signal the models match by name (when the stream is named)."""
        if not self._named:
            return x
        return Signal(values=np.ascontiguousarray(x), kind="pandas", vector=True, index=pd.RangeIndex(x.shape[0]),
                      channels=self._channels)

    def _t(self, pos: int) -> float:
        return round(pos / (1.0 if self.fs is None else self.fs), 9)

    def _process(self, x: np.ndarray, pos0: int, hist: int, ux: np.ndarray | None = None) -> list:
        """Windows starting at ``x[hist]``, ``x[hist + step]``, ...; ``x[0]`` is stream position ``pos0``; ``ux``
        the input beside ``x`` (ARX models).

        The ``hist`` samples before the first window only feed the rolling variance."""
        W, S, V = self.window, self.step, self.steady_window
        body = x[hist:]
        if body.shape[0] < W:
            return []
        record = self._record(body)
        ubody = None if ux is None else self._input(ux[hist:])
        det = ResidualWindows({"healthy": self._base}).fit(record, u=ubody).statistics(self.detection_test,
                                                                                        window=W, step=S)
        if self.models:
            ident = ResidualWindows(self._faults).fit(record, u=ubody).statistics(self.test, window=W, step=S)
            names, rej, labels, state = ident.models, ident.reject.T, ident.labels(self.rule), ident.status
        d_stat, d_thr = det.statistic[:, 0], det.threshold[:, 0]
        d_pv, d_rej = det.pvalue[:, 0], det.reject[:, 0]
        new_events = []
        for w, s in enumerate(det.starts):
            i0 = hist + int(s)                      # window start in x
            start = pos0 + i0
            end = start + W
            lo = i0 + W - V                         # rolling-variance window [lo, i0 + W) in x
            var = x[lo:i0 + W].var(axis=0) if lo >= 0 else np.full(self.nchan, np.nan)
            fault = bool(d_rej[w])
            row = {"start": self._t(start), "end": self._t(end),
                   "detect_statistic": float(np.max(d_stat[w] / d_thr[w])),
                   "detect_pvalue": float(np.min(d_pv[w])), "fault": fault}
            for c, name in enumerate(self._channels):
                row[f"variance_{name}"] = float(var[c])
            if self._phase == "healthy" and fault:
                self._phase = "transient"
                self._detect_pos = end
                new_events.append(MonitorEvent(self._t(end), "detection", None, "fault",
                                               window=(self._t(start), self._t(end))))
            if self._phase == "transient" and self.steady_thresholds is not None:
                var_start = pos0 + lo
                if lo >= 0 and var_start >= self._detect_pos and np.all(var <= self.steady_thresholds):
                    self._phase, self._steady_pos = "steady", var_start
                    new_events.append(MonitorEvent(self._t(end), "steady", None, "steady",
                                                   window=(self._t(var_start), self._t(end))))
            row["phase"] = self._phase
            label, acc, st = None, (), ""
            if self.models and self._phase == "steady" and start >= self._steady_pos:
                acc = tuple(n for j, n in enumerate(names) if not rej[j, w])
                st = str(state[w])
                label = names[labels[w]] if labels[w] >= 0 else None
                new_events.append(MonitorEvent(self._t(end), "identification", label, st, acc,
                                               (self._t(start), self._t(end))))
            row.update({"status": st, "label": label, "accepted": ",".join(acc)})
            self._rows.append(row)
        self._events.extend(new_events)
        return new_events

    # ------------------------------------------------------------------------------------------------------------
    def _update_sequential(self, x: np.ndarray, ux: np.ndarray | None) -> list:
        """:meth:`update` of the sequential rule: every new sample through the detection SPRT, the rows of the
        completed steps (with the steady-state check at their ends) and, once steady, the identification MSPRT."""
        first = self._offset + self._buffer.shape[0]          # stream position of x[0]
        self._append(x, ux)
        end = self._offset + self._buffer.shape[0]
        n = end - first
        peak, alarm, cycle = np.full(n, -np.inf), np.zeros(n, dtype=bool), np.zeros(n, dtype=np.int64)
        a = max(first, self._order)                            # first new sample with a healthy residual
        if end > a:
            e = self._residuals(self._base, a - self._order)
            z = self.detection_test.loglik_ratio(e, self._sigma)
            test = self.detection_test
            p, al, cy, _, self._s, start = renewal_walk(z, test.lower, test.upper, state=self._s,
                                                        start=self._cycle - a)
            peak[a - first:], alarm[a - first:], cycle[a - first:] = p, al, cy + a
            self._cycle = int(start) + a
        events: list = []
        S, pos = self.step, first
        while pos < end:
            b = min((pos // S + 1) * S, end)
            i, j = pos - first, b - first
            self._row_peak = max(self._row_peak, float(peak[i:j].max()))
            if alarm[i:j].any():
                self._row_alarm = True
                if self._phase == "healthy":
                    t = first + i + int(np.argmax(alarm[i:j]))
                    self._phase, self._detect_pos = "transient", t + 1
                    events.append(MonitorEvent(self._t(t), "detection", None, "fault",
                                               window=(self._t(int(cycle[t - first])), self._t(t))))
            if self._phase == "steady" and self.models:
                self._identify(b, pos, events)
            if b % S == 0:
                self._sequential_row(b, events)
            pos = b
        self._keep(max(self._offset, end - self.steady_window - max(self._order, self._fault_order)))
        self._events.extend(events)
        return events

    def _identify(self, upto: int, known: int, events: list) -> None:
        """Accumulate the identification MSPRT over the stream positions up to ``upto`` (exclusive); a decision is
        an event at its deciding sample, or at ``known`` when it is told later (the samples before the steady
        event, accumulated when it is established)."""
        lo = self._ident_pos
        if upto <= lo:
            return
        pm = self._fault_order
        a, b = lo - pm - self._offset, upto - self._offset
        ll = ResidualWindows(self._faults).fit(self._record(self._buffer[a:b]),
                                              u=self._input(self._ubuffer[a:b] if self.inputs else None)
                                              ).loglik(common=pm)
        res = msprt(ll, alpha=self.sprt_alpha, restart=True, scale=self.sprt_scale, models=list(self.models),
                    state=self._w)
        self._w = res.state
        if not res.decided:
            self._ident_pos = upto
            return
        t, label = res.decision_time - 1, res.name
        self._phase, self._ident_pos = "identified", upto
        self._row_ident = (label, "identified")
        events.append(MonitorEvent(self._t(max(lo + int(t), known)), "identification", label, "identified",
                                   (label,), (self._t(self._steady_pos), self._t(lo + int(t)))))

    def _sequential_row(self, b: int, events: list) -> None:
        """Close the step ending at stream position ``b``: the steady-state check there, and its row."""
        lo = b - self.steady_window
        var = self._buffer[lo - self._offset: b - self._offset].var(axis=0) if lo >= 0 else np.full(self.nchan,
                                                                                                      np.nan)
        if self._phase == "transient" and self.steady_thresholds is not None and lo >= 0 and \
                lo >= self._detect_pos and np.all(var <= self.steady_thresholds):
            self._phase, self._steady_pos, self._ident_pos = "steady", lo, lo
            events.append(MonitorEvent(self._t(b), "steady", None, "steady", window=(self._t(lo), self._t(b))))
            if self.models:
                self._identify(b, b, events)
        label, st = self._row_ident or (None, "")
        peak = self._row_peak / self.detection_test.upper if np.isfinite(self._row_peak) else np.nan
        row = {"start": self._t(b - self.step), "end": self._t(b), "detect_statistic": peak,
               "detect_pvalue": np.nan, "fault": self._row_alarm}
        for c, name in enumerate(self._channels):
            row[f"variance_{name}"] = float(var[c])
        row.update({"phase": self._phase, "status": st, "label": label, "accepted": label or ""})
        self._rows.append(row)
        self._row_peak, self._row_alarm, self._row_ident = -np.inf, False, ()

    def update(self, samples: Any, *, u: Any = None, k: Mapping | None = None) -> list:
        """Feed the next samples of a stream; returns the events of the windows they complete.

        Parameters
        ----------
        samples : array_like, DataFrame or DataArray, shape (n, k)
            New samples (time on axis 0), continuing the stream.
        u : array_like, Series, DataFrame or DataArray, shape (n,) or (n, n_inputs)
            Their input, for ARX models only (required for them, refused otherwise): as many samples, the same
            index when both carry one, the channels matched to the models' inputs by name when both are named.
        k : mapping, optional
            The stream's operating point, parameter name -> value (``{"speed": 4.2}``), for functionally pooled
            models only (required with the first block of a stream, refused for point models): every model is
            filtered at it, ``res.at(k)``. A stream has one operating point: later blocks may leave it out or repeat
            it.

        Returns
        -------
        list of MonitorEvent

        Raises
        ------
        ValueError
            Samples that are not a finite signal, a missing / extra channel (named) or another number of channels;
            a time span (``window``, ``step``, ``steady_window``; the defaults are time spans) without ``fs`` when
            the first block carries no time index; ``u`` of another length, index or inputs; ``k`` without one of
            the models' operating parameters, with another, with a value that is not finite, or other than the
            stream's.
        TypeError
            ``u`` missing for ARX models or given for others; ``k`` missing for functionally pooled models, given
            for point models, or not a mapping of numbers.
        """
        self._stream_point(k)
        x, ux = self._values(samples, u)
        if self.sequential:
            return self._update_sequential(x, ux)
        self._append(x, ux)
        end = self._offset + self._buffer.shape[0]
        W, S = self.window, self.step
        if end - self._next < W:
            return []
        nwin = (end - self._next - W) // S + 1
        hist = self._next - self._offset
        n = hist + (nwin - 1) * S + W
        events = self._process(self._buffer[:n], self._offset, hist, self._ubuffer[:n] if self.inputs else None)
        self._next += nwin * S
        self._keep(max(self._offset, self._next - max(self.steady_window - W, 0)))
        return events

    def run(self, signal: Any, *, u: Any = None, k: Mapping | None = None) -> MonitorResult:
        """Monitor a whole record from time 0 (resets the monitor first).

        Parameters
        ----------
        signal : array_like, DataFrame or DataArray, shape (nobs, k)
        u : array_like, Series, DataFrame or DataArray, optional
            The record's input, for ARX models only (as in :meth:`update`).
        k : mapping, optional
            The record's operating point, parameter name -> value, for functionally pooled models only (required
            for them, as in :meth:`update`).

        Returns
        -------
        MonitorResult
            With :attr:`~MonitorResult.coverage`, whether the baseline covers the record.

        Warns
        -----
        CoverageWarning
            The record lies outside what the detection rests on (:func:`tsfdi.coverage.check_coverage`): the
            predictive record law of a ``detection_test`` calibrated on held-out residuals of at least three records
            (the record holding three of its windows), else the spread of the summaries of the baseline's fitting
            records (an AR / VAR fitted on at least three records, the record at least as long as the shortest of
            them). It names the summaries out: the record's decisions are not covered (a fault, or a flight unlike
            the fitting ones: fit the baseline on flights like it). Nothing is checked (nor said) otherwise.

        Raises
        ------
        ValueError
            As :meth:`update`; also for a ``window`` longer than the signal (no window to test).
        TypeError
            As :meth:`update`.
        """
        res, unchecked = self._run(signal, u, k)
        if unchecked:
            warnings.warn(f"Monitor.run: coverage not checked: {unchecked}", CoverageWarning, stacklevel=2)
        elif res.coverage is not None:
            warn_if_not_covered(res.coverage, "Monitor.run")
        return res

    def _run(self, signal: Any, u: Any = None, k: Mapping | None = None) -> tuple:
        """:meth:`run` without its warnings: the result, and why the coverage could not be checked ("" if it could
        or need not be)."""
        self.reset()
        self.update(signal, u=u, k=k)
        nobs = self._offset + self._buffer.shape[0]
        if self.sequential and nobs <= max(self._order, self._fault_order):
            raise ValueError(f"signal has {nobs} samples: the sequential rule needs more than the models' largest "
                             f"order ({max(self._order, self._fault_order)}) to have a residual to test")
        if not self.sequential and nobs < self.window:
            secs = (lambda n: f" ({n / self.fs:g} s)") if self.fs else (lambda n: "")
            raise ValueError(f"window ({self.window} samples{secs(self.window)}) is longer than the signal ({nobs} "
                             f"samples{secs(nobs)}): no window to test; give a shorter window or a longer signal")
        res = self.result()
        sig = as_signal(signal, "signal", allow_constant=True)
        resid = None
        if self.inputs:               # an ARX baseline's residuals need the input: given, named by its output
            e = np.asarray(self._base.residuals(sig, u), dtype=np.float64).reshape(-1, self.nchan)
            resid = pd.DataFrame(e, columns=[str(c) for c in self._base.model.data.channels])
        try:
            cov = check_coverage(self.detection_test, self._base, sig, resid=resid)
        except ValueError as err:
            return res, str(err)
        return (res, "") if cov is None else (dataclasses.replace(res, coverage=cov), "")

    def screen(self, records: Any, *, k: Any = None, progress: bool = False) -> pd.DataFrame:
        """Run the monitor over every record of many (offline, each from time 0 as :meth:`run`): one row per record.

        Parameters
        ----------
        records : sequence of signals, xarray.DataArray or xarray.Dataset
            A sequence of records, each what :meth:`run` takes (numpy, pandas or xarray); a ``(record, time,
            channel)`` DataArray; or a hexacopter Dataset (converted by
            :func:`~tsfdi.datasets.hexacopter.hexacopter_signals`). Either xarray kind may be backed by dask, chunked
            along ``record`` (a fleet opened with ``xarray.open_zarr``): the chunks then run on the current dask
            scheduler (threads, processes or a ``dask.distributed`` Client, :func:`tsfdi.fleet.map_records`) and only
            their rows come back, so the driver never holds the records; the table is the one of the same records in
            memory.
        k : str or sequence of str, optional
            For functionally pooled models (:class:`~tsfdi.FPResults`, e.g. ``Baselines.monitor()`` of
            ``fit_baselines(..., k=...)``; required for them, refused for point models): the record coordinates
            holding each record's operating point (``"speed"``), exactly the models' operating parameters. Every
            record is monitored with the models at its own logged point, ``res.at(k_record)``, as
            ``run(record, k={...})`` (the tests calibrated on the FP null hold at every point). The records must then
            be xarray with those coordinates (numbers, finite for every record); on dask they are read on the
            driver and travel with each chunk.
        progress : bool
            Show a tqdm progress bar over the records.

        Returns
        -------
        pandas.DataFrame
            Indexed by ``record`` (the ``record`` coordinate, else the position), with the other record coordinates of
            xarray input (``state``, ``turbulence``, ``failure_time``, ...), then ``windows`` (windows tested),
            ``fault_windows`` (windows the healthy model rejects), ``detection_time`` and ``steady_time`` (NaN without
            the event), ``label`` (:attr:`MonitorResult.label`, None without), ``covered`` (whether the baseline
            covers the record, :attr:`MonitorResult.coverage`; a nullable boolean, ``<NA>`` where that cannot be said)
            and ``outside`` (the summaries of the record out of the fitting records' spread, ``""`` when none).
            ``detection_time`` is the time of the first alarm (the end of the first rejected window), ready for
            :func:`tsfdi.score_records`.

        Warns
        -----
        CoverageWarning
            When the baseline does not cover some records: for one, naming it and its summaries out (as :meth:`run`);
            for several, one warning with their number and the first of them (the summaries out in ``outside``).

        Raises
        ------
        TypeError
            ``records`` of another kind, or ARX models (the records come without their input: :meth:`run` each
            record with ``u=``); ``k`` missing for functionally pooled models, given for point models, not names, or
            naming a coordinate that does not hold numbers.
        ValueError
            A record that :meth:`run` refuses (NaN after a loss of control, too short, other channels), named;
            ``k`` naming a coordinate the records lack, other than the models' operating parameters, a coordinate
            not finite for some record (named), or given with a sequence of signals (no coordinates).

        Notes
        -----
        The monitor's own state is left alone: every record runs on a copy (reset, as :meth:`run` does).
        """
        from tsfdi.fleet import is_chunked, map_records

        if self.inputs:
            raise TypeError("records: screen runs the records without an input, but the models are ARX (input-output) "
                            "models; run each record with its input, Monitor.run(signal, u=...)")
        import xarray as xr

        progress = boolean(progress, "progress")
        if isinstance(records, xr.Dataset):     # (lazily on dask: the chunks will hold the signal variables only)
            from tsfdi.datasets.hexacopter import hexacopter_signals

            records = hexacopter_signals(records)
        operating = self._record_points(records, k)
        if is_chunked(records):
            parts = map_records(_screen_rows, records, self, False, operating, progress=progress, desc="tsfdi screen")
            table = pd.concat(list(parts))
        else:
            table = _screen_rows(records, slice(0, None), self, progress, operating)
        # the check ran where the records are; its warnings are said here, on the driver
        warn_records_not_covered(table["outside"][table["outside"] != ""], "Monitor.screen",
                                 judged=int(table["covered"].notna().sum()), see="the 'outside' column")
        return table

    def _record_points(self, records: Any, k: Any) -> tuple | None:
        """``(names, points)``: the coordinates ``k`` names and every record's values of them (``(records, d)``),
        checked against the models' operating parameters (:meth:`screen`); ``None`` for point models."""
        import xarray as xr

        names = operating_names(k)
        if not self.k_names:
            if names:
                raise TypeError(f"k names operating parameters {list(names)}, but the monitor's models are point "
                                "models (no FPResults): leave k out, or monitor with functionally pooled models")
            return None
        if not names:
            raise TypeError(f"the monitor's models are functionally pooled over {list(self.k_names)}: give k= naming "
                            "the record coordinate(s) of those operating parameters (each record is monitored at its "
                            "own, res.at(k_record))")
        if set(names) != set(self.k_names):
            other = next(iter([c for c in names if c not in self.k_names] or
                              [c for c in self.k_names if c not in names]))
            raise ValueError(f"k names the record coordinates {list(names)}, but the monitor's models are functionally "
                             f"pooled over {list(self.k_names)}: {other!r} is "
                             f"{'not one of their operating parameters' if other in names else 'not named'}; name "
                             "exactly their parameters")
        if not isinstance(records, xr.DataArray):
            what = "a sequence of signals" if isinstance(records, Sequence) else f"a {type(records).__name__}"
            raise ValueError(f"k names record coordinates {list(names)}, but records is {what}, which has none: give "
                             "the records as a (record, time, channel) DataArray (or a hexacopter Dataset) with those "
                             "coordinates, or run each with Monitor.run(record, k={...})")
        n = records.sizes.get("record", 0)
        ids = records["record"].values if "record" in records.coords else np.arange(n)
        return names, operating_points(records, names, ids, "records")

    def result(self) -> MonitorResult:
        """Events and per-window table of everything fed so far."""
        channels = self._channels if self._channels is not None else self._model_channels
        cols = ["start", "end", "detect_statistic", "detect_pvalue", "fault"] + \
            [f"variance_{c}" for c in channels] + ["phase", "status", "label", "accepted"]
        frame = pd.DataFrame(self._rows, columns=cols)
        ident = frame["label"][frame["status"] != ""].dropna()
        label = ident.value_counts().idxmax() if len(ident) else None
        det = next((e.time for e in self._events if e.kind == "detection"), None)
        st = next((e.time for e in self._events if e.kind == "steady"), None)
        ident_t = next((e.time for e in self._events if e.kind == "identification" and e.status == "identified"),
                       None)
        return MonitorResult(events=list(self._events), windows=frame, detection_time=det, steady_time=st,
                             label=label, models=tuple(self.models), fs=self.fs,
                             steady_thresholds=self.steady_thresholds, identification_time=ident_t)


def operating_names(k: Any, name: str = "k") -> tuple:
    """The record coordinates ``k`` names (a name or a sequence of distinct names) as a tuple; ``()`` for None (the
    ``k=`` of :meth:`Monitor.screen`, :func:`tsfdi.fit_baselines` and :func:`tsfdi.evaluate`)."""
    if k is None:
        return ()
    names = [k] if isinstance(k, str) else k
    if not isinstance(names, Iterable) or isinstance(names, (bytes, Mapping)):
        raise TypeError(f"{name} must name record coordinates (a name or a sequence of names), got {k!r}")
    names = list(names)
    if not names or not all(isinstance(n, str) and n for n in names):
        raise TypeError(f"{name} must name record coordinates (non-empty strings), got {k!r}")
    if len(set(names)) < len(names):
        raise ValueError(f"{name} names a coordinate twice: {names}")
    return tuple(names)


def operating_points(data: Any, names: tuple, ids: np.ndarray, name: str) -> np.ndarray | None:
    """The operating point of every record, ``(records, len(names))`` float64, from the record coordinates
    ``names`` of ``data`` (None without names); missing, non-numeric or non-finite coordinates raise naming ``k``."""
    if not names:
        return None
    cols = []
    for c in names:
        variable = data.coords.variables.get(c)
        if variable is None or variable.dims != ("record",):
            have = [v for v, var in data.coords.variables.items() if var.dims == ("record",) and v != "record"]
            raise ValueError(f"k: {name} has no record coordinate {c!r} (its record coordinates: {have})")
        values = np.asarray(variable.values)
        if values.dtype.kind not in "iuf":
            raise TypeError(f"k: the coordinate {c!r} of {name} must hold numbers (operating parameters), got dtype "
                            f"{values.dtype}")
        values = values.astype(np.float64)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise ValueError(f"k: the coordinate {c!r} of {name} is not finite for record {ids[bad[0]]} "
                             f"({values[bad[0]]}); every record needs its operating point")
        cols.append(values)
    return np.column_stack(cols)


def _screen_rows(records: Any, where: slice, monitor: Monitor, progress: bool = False,
                 operating: tuple | None = None) -> pd.DataFrame:
    """:meth:`Monitor.screen` of records in memory; ``where.start`` is the position of the first (the index when the
    records have no ``record`` coordinate); ``operating``: the names of the operating parameters and the operating
    point of every record of the whole (:meth:`Monitor._record_points`), or None."""
    import xarray as xr

    if isinstance(records, xr.Dataset):
        from tsfdi.datasets.hexacopter import hexacopter_signals

        records = hexacopter_signals(records)
    coords: dict = {}
    if isinstance(records, xr.DataArray):
        if "record" not in records.dims or records.ndim not in (2, 3):
            raise TypeError(f"records as a DataArray must have dims (record, time[, channel]), got {records.dims}")
        records = records.transpose("record", ...)
        n = records.sizes["record"]
        index = records["record"].values if "record" in records.coords else np.arange(n) + where.start
        coords = {k: np.asarray(c.values) for k, c in records.coords.items() if c.dims == ("record",) and k != "record"}
        items: Sequence = [records.isel(record=i) for i in range(n)]
    elif isinstance(records, Sequence) and not isinstance(records, (str, bytes)) and len(records):
        items, index = records, np.arange(len(records)) + where.start
    else:
        raise TypeError(f"records must be a non-empty sequence of signals, a (record, time, channel) DataArray or a "
                        f"hexacopter Dataset, got {type(records).__name__}")
    if progress:
        from tqdm.auto import tqdm

        items = tqdm(items, desc="tsfdi screen", unit="record")
    m = copy.copy(monitor)
    rows = []
    for i, x in enumerate(items):
        try:
            res, unchecked = m._run(x, k=None if operating is None else
                                    dict(zip(operating[0], operating[1][where][i].tolist())))
        except (TypeError, ValueError) as err:
            raise type(err)(f"records: record {index[i]}: {err}") from None
        cov = res.coverage
        outside = f"coverage not checked: {unchecked}" if unchecked else (
            "" if cov is None or cov.covered else cov.warning_message())
        rows.append((len(res.windows), int(res.windows["fault"].sum()),
                     np.nan if res.detection_time is None else res.detection_time,
                     np.nan if res.steady_time is None else res.steady_time, res.label,
                     pd.NA if cov is None else cov.covered, outside))
    windows, faults, detection, steady, label, covered, outside = zip(*rows)
    index = pd.Index(index, name="record")
    table = {**coords, "windows": np.array(windows, dtype=np.int64), "fault_windows": np.array(faults, dtype=np.int64),
             "detection_time": np.array(detection, dtype=float), "steady_time": np.array(steady, dtype=float),
             "label": pd.Series(label, index=index, dtype=object),
             "covered": pd.array(covered, dtype="boolean"), "outside": np.array(outside, dtype=object)}
    return pd.DataFrame(table, index=index)

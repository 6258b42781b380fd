"""Fault detection and identification by residual hypothesis tests (Dutta et al., Figs. 3, 10-13).

``detect`` drives a signal through one baseline model and tests its residuals (healthy vs fault).
``identify`` drives it through every candidate model (healthy and fault models) and applies the same test to
each: the paper's multiple binary hypothesis tests. A model is *accepted* when its residuals pass the test
(for vector residuals: every channel passes). One accepted model is an identification, several are an
ambiguity ("confusion between those types of failures"), none means no decision. Functionally pooled means of
windows (:class:`tsfdi.models.FPMean`, the trim of a signal over operating parameters) can be the models instead
(all of them; they have no residuals): a window's mean is judged at each class's maximum-likelihood operating point,
the classes are ranked by that likelihood, and the detector's statistic is compared with a calibrated
:class:`~tsfdi.EmpiricalThreshold`.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import Signal, as_signal, sampling_frequency, window_samples
from tsfdi.coverage import check_coverage, warn_if_not_covered
from tsfdi.detection.base import ResidualTest
from tsfdi.detection.decision import Decision
from tsfdi.detection.whiteness import LjungBox
from tsfdi.exceptions import CoverageWarning
from tsfdi.detection.threshold import EmpiricalThreshold
from tsfdi.models import FPMeanResults, FPResults, InputOutputResults
from tsfdi.summary import Summary
from tsfdi.windows import STATUS, ResidualWindows, WindowStatistics, decide, status

__all__ = ["detect", "identify", "identify_windows", "Identification", "WindowedIdentification"]


def _check_test(test: Any) -> ResidualTest:
    if test is None:
        return LjungBox()
    if not isinstance(test, ResidualTest):
        raise TypeError(f"test must be a residual test object (FTest, LjungBox, GLRT, ...), got "
                        f"{type(test).__name__}")
    return test


def _model_tests(test: Any, models: Mapping) -> dict:
    """Name -> the test of each model: one test for all, or a mapping name -> test (one calibrated per model)."""
    if isinstance(test, Mapping):
        missing = [name for name in models if name not in test]
        if missing:
            raise ValueError(f"test is a mapping but has no test for the model(s) {missing}")
        return {name: _check_test(test[name]) for name in models}
    test = _check_test(test)
    return dict.fromkeys(models, test)


def _check_model(res: Any, name: str, sig: Signal, arg: str) -> None:
    """``res`` is fitted results whose channels ``sig`` has: by name when both are named (a missing or an extra
    channel raises naming it; the model's ``residuals`` reorders the signal), else by their number."""
    if not hasattr(res, "residuals"):
        raise TypeError(f"{arg} must hold fitted results (AR, VAR, ARX or VARX) with a residuals() method; "
                        f"{name!r} is a {type(res).__name__}")
    if isinstance(res, FPResults):
        raise TypeError(f"{arg if name == arg else f'{arg}[{name!r}]'} is a functionally pooled model (FPResults): "
                        "give its point model at the record's operating point, .at(k) (k logged, or "
                        ".estimate_k(signal).k_hat)")
    data = getattr(getattr(res, "model", None), "data", None)
    if isinstance(data, Signal) and data.named and sig.named:
        sig.match_channels(data.channels, "signal")
        return
    neqs = int(getattr(res, "neqs", 1))
    if neqs != sig.nchan:
        raise ValueError(f"signal has {sig.nchan} channel(s) but {arg} {name!r} was fitted on {neqs} channel(s)")


def _residuals(res: Any, signal: Any, u: Any, what: str) -> Any:
    """Residuals of ``signal`` through ``res``, with the input ``u`` for an input-output (ARX, VARX) model only."""
    if isinstance(res, InputOutputResults):
        if u is None:
            name = type(res.model).__name__
            raise TypeError(f"u is required: {what} is {'a' if name.startswith('V') else 'an'} {name} (input-output) "
                            "model; pass its input signal as u=")
        return res.residuals(signal, u)
    if u is not None:
        raise TypeError(f"u is only for input-output (ARX) models: {what} ({type(res).__name__}) has no exogenous "
                        "input; leave u out")
    return res.residuals(signal)


def _mean_models(models: Mapping, arg: str) -> bool:
    """Whether the models are window-mean models (:class:`~tsfdi.models.FPMeanResults`); a mixture with residual
    models is refused (their likelihoods are of different data)."""
    kinds = {isinstance(res, FPMeanResults) for res in models.values()}
    if len(kinds) > 1:
        raise TypeError(f"{arg} mixes FPMean results with residual models (AR, VAR, ARX): an FPMean model judges a "
                        "window's mean, the others its residuals; identify with one kind")
    return kinds == {True}


def _mean_thresholds(test: Any, models: Mapping, arg: str) -> dict:
    """Name -> the calibrated :class:`~tsfdi.EmpiricalThreshold` of the statistic of each FPMean model, or None (no
    threshold: the model accepts every window)."""
    def check(t: Any, what: str) -> EmpiricalThreshold | None:
        if t is None:
            return None
        if not isinstance(t, EmpiricalThreshold):
            raise TypeError(f"{what} must be a calibrated EmpiricalThreshold (or None) for FPMean models: their "
                            "statistic min_k (m - M(k))' S^-1 (m - M(k)) is not a residual test's; got "
                            f"{type(t).__name__}")
        t.check_fitted()
        return t

    if isinstance(test, Mapping):
        missing = [name for name in models if name not in test]
        if missing:
            raise ValueError(f"{arg} is a mapping but has no threshold for the model(s) {missing}")
        return {name: check(test[name], f"{arg}[{name!r}]") for name in models}
    return dict.fromkeys(models, check(test, arg))


def _mean_decision(res: FPMeanResults, q: float, ll: float, kh: np.ndarray, thr: EmpiricalThreshold | None
                   ) -> Decision:
    """The decision of an FPMean model on one window: statistic ``min_k q(k)`` against the threshold (none: accept),
    the window's log-likelihood and ``k`` in ``details``."""
    limit = np.inf if thr is None else thr.threshold_
    return Decision(statistic=q, threshold=limit, pvalue=np.nan if thr is None else float(thr.pvalue(q)),
                    alpha=np.nan if thr is None else thr.false_alarm, reject=bool(q > limit), df=np.nan,
                    nobs=res.model.window,
                    null_hypothesis="the window's mean lies on the model's surface at some k (the model fits)",
                    alternative_hypothesis="it does not (another class, or a fault)",
                    details={"loglik": float(ll), "k_hat": kh}, channels=("joint",),
                    test="FPMean" + ("" if thr is None else " + EmpiricalThreshold"))


def _mean_scores(res: FPMeanResults, sig: Signal, step: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Statistic, log-likelihood and ``k`` of every window of ``sig`` (numpy arrays; channels matched by name)."""
    data = res.model.data
    plain = dataclasses.replace(sig.match_channels(data.channels, "signal", named=data.named), kind="numpy",
                                index=None)
    return res.profile(plain, step)


def _mean_identify(sig: Signal, models: Mapping, test: Any, u: Any, arg: str) -> tuple[dict, dict]:
    """:func:`detect` / :func:`identify` with FPMean models on one window (``sig``): name -> decision, and name ->
    threshold."""
    if u is not None:
        raise TypeError("u is only for input-output (ARX) models: FPMean models have no input; leave u out")
    thresholds = _mean_thresholds(test, models, "test")
    for name, res in models.items():
        _mean_check(res, name, sig, sig.nobs, arg)
    decisions = {}
    for name, res in models.items():
        q, ll, kh = _mean_scores(res, sig, sig.nobs)
        decisions[name] = _mean_decision(res, q[0], ll[0], kh[0], thresholds[name])
    return decisions, thresholds


def _mean_check(res: Any, name: str, sig: Signal, window: int, arg: str) -> None:
    data = res.model.data
    sig.match_channels(data.channels, "signal", named=data.named)
    if window != res.model.window:
        raise ValueError(f"{arg} {name!r} was fitted on windows of {res.model.window} samples; the window is "
                         f"{window} (its covariance S holds for its own window length only)")


def detect(signal: Any, baseline: Any, test: ResidualTest | None = None, *, u: Any = None) -> Decision:
    """Healthy-vs-fault decision: drive ``signal`` through ``baseline`` and test the residuals.

    Parameters
    ----------
    signal : array_like, Series, DataFrame or DataArray
        Current signal :math:`Z_u` (scalar or vector, time on axis 0). A named signal (``DataFrame``,
        ``DataArray`` with a channel coordinate) is matched to a model fitted on named data by channel name, in
        any order; an array by position.
    baseline : fitted results
        The healthy model :math:`M_0` (``tsfdi.AR(...).fit()`` or ``tsfdi.VAR(...).fit()``), or a functionally
        pooled mean of windows (:class:`tsfdi.models.FPMean` results): then ``signal`` is one window of the model's
        ``window`` samples and the statistic is its :meth:`~tsfdi.models.FPMeanResults.statistic`.
    test : ResidualTest or EmpiricalThreshold, optional
        :class:`~tsfdi.FTest`, :class:`~tsfdi.LjungBox` (default, ``lags=20``) or :class:`~tsfdi.GLRT`.
        What the test needs from the baseline (reference variance and degrees of freedom for the F test,
        sigma for the GLRT) is taken from the fitted results. For an FPMean baseline: an
        :class:`~tsfdi.EmpiricalThreshold` calibrated on the statistic of healthy records the baseline was not fitted
        on (required: the statistic's null law has no closed form); the decision's p-value is the threshold's.
    u : array_like, optional
        Input signal for an input-output baseline (``tsfdi.ARX(...).fit()``, ``tsfdi.VARX(...).fit()``), passed to
        its ``residuals``; required for such a baseline, refused for AR / VAR baselines.

    Returns
    -------
    Decision
        ``reject`` True means fault (H1). ``details["coverage"]``: whether the baseline covers the record, a
        :class:`~tsfdi.Coverage` (see Warns), when that can be said.

    Warns
    -----
    CoverageWarning
        The record lies outside the spread of the baseline's fitting records (:func:`tsfdi.coverage.check_coverage`:
        an AR / VAR fitted on at least three records, ``signal`` at least as long as the shortest of them; a test
        calibrated with a record law judges single windows here, too few for its own record-level check, which
        :class:`~tsfdi.Monitor` and :func:`~tsfdi.evaluate` make). The warning names the summaries out: the
        decision is not covered by the baseline (a fault, or a flight unlike the fitting ones: fit the baseline on
        flights like it). Otherwise (fewer fitting records, a shorter signal) nothing is checked and ``details`` has
        no ``"coverage"``; a record that cannot be summarised (a constant channel) is said in a ``CoverageWarning``.

    Raises
    ------
    TypeError
        ``baseline`` is not fitted results or is a functionally pooled model itself (:class:`~tsfdi.FPResults`:
        give its point model ``.at(k)``), ``test`` is not a residual test (for an FPMean baseline: not a
        calibrated EmpiricalThreshold), ``u`` is missing for an ARX / VARX baseline or given for another, or
        ``signal`` is not numeric.
    ValueError
        ``signal`` is not 1-D / 2-D, holds NaN / inf or a masked value, is too short for the model and test, lacks
        a channel of the baseline or has one it does not know (named), or has a channel count other than the
        baseline's; for an FPMean baseline, ``signal`` is not one window of its length, or ``test`` is an
        uncalibrated threshold.
    """
    sig = as_signal(signal, "signal", allow_constant=True)
    if isinstance(baseline, FPMeanResults):
        if test is None:
            raise TypeError("test: an FPMean baseline needs a calibrated EmpiricalThreshold of its statistic "
                            "(EmpiricalThreshold(alpha).calibrate(baseline.statistic(healthy record)) on healthy "
                            "records it was not fitted on)")
        return _mean_identify(sig, {"baseline": baseline}, test, u, "baseline")[0]["baseline"]
    test = _check_test(test)
    _check_model(baseline, "baseline", sig, "baseline")
    resid = _residuals(baseline, sig, u, "baseline")
    decision = test.test(resid, **test.reference(baseline))
    try:
        cov = check_coverage(test, baseline, sig, resid=resid)
    except ValueError as err:
        warnings.warn(f"detect: coverage not checked: {err}", CoverageWarning, stacklevel=2)
        return decision
    if cov is None:
        return decision
    warn_if_not_covered(cov, "detect")
    return dataclasses.replace(decision, details={**decision.details, "coverage": cov})


@dataclass(frozen=True)
class Identification:
    """Outcome of :func:`identify`: one decision per candidate model.

    Attributes
    ----------
    decisions : dict
        Model name -> :class:`~tsfdi.detection.decision.Decision` of its residuals (insertion order kept).
    test : str
        Name of the test used.
    span : tuple or None
        ``(start, stop)`` sample positions of the signal window (set by :func:`identify_windows`).
    """

    decisions: dict
    test: str = ""
    span: tuple | None = None

    @property
    def accepted(self) -> tuple:
        """Names of the models whose residuals pass the test (every channel accepts), in model order."""
        return tuple(name for name, d in self.decisions.items() if not d.reject)

    @property
    def label(self) -> str | None:
        """The single accepted model, else ``None``."""
        i = int(decide([not d.reject for d in self.decisions.values()]))
        return list(self.decisions)[i] if i >= 0 else None

    @property
    def status(self) -> str:
        """``"identified"`` (one model accepted), ``"ambiguous"`` (several) or ``"none"`` (no decision)."""
        return str(status(len(self.accepted)))

    @property
    def ranking(self) -> tuple:
        """Model names from most to least plausible: by signal-level p-value (descending), ties and tests
        without p-values broken by the largest statistic/threshold ratio (ascending). For window-mean models
        (:class:`~tsfdi.models.FPMean`, whose decisions carry ``details["loglik"]``): by the window's
        log-likelihood (descending), the likelihood rule of :func:`identify_windows`."""
        if all("loglik" in d.details for d in self.decisions.values()):
            return tuple(sorted(self.decisions, key=lambda name: -self.decisions[name].details["loglik"]))

        def key(item):
            name, d = item
            p = d.signal_pvalue
            return (-(p if np.isfinite(p) else 0.0), d.margin)

        return tuple(name for name, _ in sorted(self.decisions.items(), key=key))

    def to_frame(self):
        """A ``DataFrame`` with one row per (model, channel): statistic, threshold, p-value, df, reject,
        and whether the model is accepted."""
        rows = []
        for name, d in self.decisions.items():
            for i, c in enumerate(d.channels):
                df = d.df[i]
                rows.append({"model": name, "channel": c, "statistic": d.statistic[i], "threshold": d.threshold[i],
                             "pvalue": d.pvalue[i], "df": df if np.ndim(df) == 0 else tuple(df),
                             "reject": bool(d.channel_reject[i]), "model_accepted": not d.reject})
        return pd.DataFrame(rows).set_index(["model", "channel"])

    def summary(self) -> Summary:
        """The outcome (test, status, label, accepted models, ranking) and the decision of every model and channel,
        as text (``str``) and HTML tables."""
        header = [("Test", self.test), ("Status", self.status), ("Label", self.label),
                  ("Accepted", ", ".join(self.accepted) or "-"), ("Ranking", ", ".join(self.ranking))]
        return Summary("Identification", header, [("Decision per model and channel", self.to_frame())])

    def __repr__(self) -> str:
        return (f"Identification(status={self.status!r}, label={self.label!r}, accepted={self.accepted}, "
                f"test={self.test!r})")

    def _repr_html_(self) -> str:
        return self.summary()._repr_html_()

    def plot(self, ax: Any = None, **kwargs: Any) -> Any:
        """Grouped bars of the statistic per model and channel against the critical limit
        (Dutta et al., Figs. 12-13). Returns the ``Figure``."""
        from tsfdi.plotting.decision import plot_identification

        return plot_identification(self, ax=ax, **kwargs)


def _check_models(models: Any) -> Mapping:
    if not isinstance(models, Mapping):
        raise TypeError(f"models must be a mapping name -> fitted results, got {type(models).__name__}")
    if len(models) == 0:
        raise ValueError("models is empty: give at least one fitted model (name -> results)")
    return models


def identify(signal: Any, models: Mapping, test: Any = None, *, u: Any = None) -> Identification:
    """Multi-class identification by one binary test per candidate model (Dutta et al., eq. 11 and the
    residual uncorrelatedness method).

    Parameters
    ----------
    signal : array_like, Series, DataFrame or DataArray
        Current signal (scalar for AR models, ``(nobs, s)`` for VAR models); a named signal is matched to each
        model's channels by name (see :func:`detect`).
    models : mapping
        Name -> fitted results (``tsfdi.AR(...).fit()`` / ``tsfdi.VAR(...).fit()``), e.g. the healthy
        model and one model per fault type. All must have the signal's number of channels. Or name ->
        functionally pooled means of windows (:class:`tsfdi.models.FPMean` results, all of them: the kinds do not
        mix): ``signal`` is then one window of the models' ``window`` samples, each model's decision carries the
        window's :meth:`~tsfdi.models.FPMeanResults.loglike` (``details["loglik"]``) and ``k``
        (``details["k_hat"]``), and :attr:`Identification.ranking` orders the models by it.
    test : ResidualTest or mapping, optional
        The test applied to each model's residuals (default ``LjungBox()``), or a mapping name -> test: each
        model with its own test, e.g. thresholds calibrated on that model's held-out residuals
        (``LjungBox(...).calibrate(spec.held_out_residuals(), window=...)`` for each fault model's spec), so that
        every candidate's accept / reject has a known size. For FPMean models: a calibrated
        :class:`~tsfdi.EmpiricalThreshold` of their statistic, a mapping name -> threshold, or ``None`` (default: no
        threshold, every model accepts and only the ranking decides).
    u : array_like, optional
        Input signal when the candidates are input-output models (``tsfdi.ARX``, ``tsfdi.VARX``): required for
        those, refused for AR / VAR models.

    Returns
    -------
    Identification

    Raises
    ------
    TypeError, ValueError
        As :func:`detect`, for every model; also for ``models`` that is not a non-empty mapping.
    """
    models = _check_models(models)
    sig = as_signal(signal, "signal", allow_constant=True)
    if _mean_models(models, "models"):
        decisions, thresholds = _mean_identify(sig, models, test, u, "models")
        return Identification(decisions=decisions, test=_test_name(thresholds))
    tests = _model_tests(test, models)
    for name, res in models.items():
        _check_model(res, name, sig, "models")
    decisions = {}
    for name, res in models.items():
        resid = _residuals(res, sig, u, f"models[{name!r}]")
        decisions[name] = tests[name].test(resid, **tests[name].reference(res))
    return Identification(decisions=decisions, test=_test_name(tests))


def _test_name(tests: dict) -> str:
    """The class name of the tests (one name when every model has a test of the same class; ``"none"`` for an
    FPMean model without a threshold)."""
    names = list(dict.fromkeys("none" if t is None else type(t).__name__ for t in tests.values()))
    return names[0] if len(names) == 1 else "+".join(names)


@dataclass(frozen=True, eq=False)
class WindowedIdentification:
    """:func:`identify` on every sliding window of a record, held as arrays; windows as objects on demand.

    A thin view of the windowed engine's :class:`~tsfdi.windows.WindowStatistics` (``windows``) under the
    paper's decision rule.

    Attributes
    ----------
    windows : WindowStatistics
        Statistics, thresholds, p-values and rejections, shape (n_windows, n_models, n_channels); its ``loglik`` is
        NaN (:meth:`decide` computes the scores when the ``"likelihood"`` rule is asked for).
    tests : tuple of ResidualTest
        The test of every model, in model order.
    references : tuple of dict
        What the test takes from each fitted model (:meth:`~tsfdi.ResidualTest.reference`), in model order.
    engine : ResidualWindows
        The fitted engine (:func:`identify_windows` computes the likelihood scores only when the
        ``"likelihood"`` rule is asked for).
    time : pandas.Index or None
        The time of every sample of the signal, when it has a time index (a ``DatetimeIndex`` /
        ``TimedeltaIndex``, a numeric index named ``"time"``, an xarray time coordinate); ``None`` otherwise.
    fs : float or None
        The sampling frequency in Hz (given or read from the time index).
    models, channels, starts, stops, statistic, threshold, pvalue, channel_reject :
        Those of ``windows``; window ``w`` covers signal samples ``[starts[w], stops[w])`` (sample positions,
        whatever the index).
    accepted : ndarray of bool, shape (n_windows, n_models)
        Model accepted in the window (every channel accepts).
    labels : list
        The single accepted model per window, else ``None``.
    status : list of str
        ``"identified" | "ambiguous" | "none"`` per window.

    Indexing (``result[w]``) or iterating gives :class:`Identification` objects, built when asked for.
    """

    windows: WindowStatistics
    tests: tuple
    references: tuple = ()
    engine: Any = field(default=None, repr=False, compare=False)
    time: Any = field(default=None, repr=False, compare=False)
    fs: float | None = None

    models = property(lambda self: self.windows.models)
    channels = property(lambda self: self.windows.channels)
    starts = property(lambda self: self.windows.starts)
    stops = property(lambda self: self.windows.starts + self.windows.window)
    statistic = property(lambda self: self.windows.statistic)
    threshold = property(lambda self: self.windows.threshold)
    pvalue = property(lambda self: self.windows.pvalue)
    channel_reject = property(lambda self: self.windows.channel_reject)
    accepted = property(lambda self: self.windows.accepted)

    @property
    def status(self) -> list:
        return self.windows.status.tolist()

    @property
    def labels(self) -> list:
        return self.decide("paper")

    def decide(self, rule: str = "paper") -> list:
        """The label of every window by ``rule`` (:data:`tsfdi.windows.RULES`): a model name or ``None``."""
        ws = self.windows
        if rule == "likelihood" and self.engine is not None and np.isnan(ws.loglik).all():
            ws = self.engine.statistics(dict(zip(self.models, self.tests)), window=ws.window, step=ws.step)
        return [self.models[i] if i >= 0 else None for i in ws.labels(rule)]

    def __len__(self) -> int:
        return len(self.windows)

    def __getitem__(self, w: int) -> Identification:
        w = int(w)
        if w < 0:
            w += len(self)
        if not 0 <= w < len(self):
            raise IndexError(f"window index out of range (0..{len(self) - 1})")
        ws = self.windows
        if ws.decisions is not None:
            dec = dict(zip(self.models, ws.decisions[w]))
        else:
            dec = {m: self.tests[i].decision(ws.statistic[w, i], ws.nobs[i], self.channels, **self.references[i])
                   for i, m in enumerate(self.models)}
        return Identification(decisions=dec, test=_test_name(dict(zip(self.models, self.tests))),
                              span=(int(self.starts[w]), int(self.stops[w])))

    def __iter__(self):
        return (self[w] for w in range(len(self)))

    def to_frame(self):
        """One row per window: ``start``, ``stop``, ``status``, ``label``.

        ``start`` / ``stop`` are in the signal's time when it has a time index (:attr:`time`: the time of the
        window's first sample and that time plus the window's span, the window ``[start, stop)`` as pandas
        ``Timestamp`` / ``Timedelta`` or seconds), in samples otherwise; the sample positions are always
        :attr:`starts` / :attr:`stops`."""
        start, stop = self.starts, self.stops
        if self.time is not None:
            t0 = self.time[start]
            span = self.windows.window / self.fs
            start = t0
            stop = t0 + (pd.Timedelta(seconds=span) if isinstance(self.time, (pd.DatetimeIndex, pd.TimedeltaIndex))
                         else span)
        return pd.DataFrame({"start": start, "stop": stop, "status": self.status, "label": self.labels})

    def __repr__(self) -> str:
        counts = {s: self.status.count(s) for s in STATUS}
        return f"WindowedIdentification(windows={len(self)}, models={self.models}, {counts})"


def identify_windows(signal: Any, models: Mapping, test: Any = None, *, window: Any,
                     step: Any = 1, fs: float | None = None, u: Any = None) -> WindowedIdentification:
    """:func:`identify` on every sliding window of one record.

    Window ``w`` covers signal samples ``[w * step, w * step + window)``. The record is filtered once through each
    model and every window's statistic comes from the windowed engine (:class:`tsfdi.windows.ResidualWindows`).

    Parameters
    ----------
    signal, models, test :
        As in :func:`identify`; the models are AR / VAR results, ARX / VARX results (input-output models, e.g. an
        FP-ARX's point ``.at(k)``; then ``u`` is required), or FPMean results
        (``window`` must be theirs; the result's ``windows.loglik`` is each window's
        :meth:`~tsfdi.models.FPMeanResults.loglike`, so ``decide("likelihood")`` gives the class of the largest
        likelihood among the accepted models, among all when no threshold is given). The kinds do not mix.
    window, step : int or time span
        As in pandas ``rolling``: an int counts samples, a time span (``"2s"``, ``pandas.Timedelta``) is converted
        with the signal's time index or ``fs``.
    fs : float, optional
        Sampling frequency in Hz (default: read from the signal's time index when a time span is given).
    u : array_like, Series, DataFrame or DataArray, optional
        The record's input for ARX / VARX models (required for them, refused for the others): as long as
        ``signal``, with its index when both carry one, its channels matched to the models' inputs by name when both
        are named. The residuals of every window are those of ``results.residuals(signal, u)`` on the window.

    Returns
    -------
    WindowedIdentification
        Arrays over windows, models and channels; ``result[w]`` is the :class:`Identification` of window ``w``
        (with ``span = (start, stop)``), equal to ``identify(signal[start:stop], models, test)`` (with
        ``u=u[start:stop]`` for ARX / VARX models).

    Raises
    ------
    TypeError, ValueError
        As :func:`identify`; also for a ``window`` / ``step`` that is not a positive int or time span, a time span
        without a known sampling frequency, a ``window`` longer than the signal or too short for a model's order
        and the test's lags.
    """
    models = _check_models(models)
    sig = as_signal(signal, "signal", allow_constant=True)
    rate = sampling_frequency(sig, fs)
    window = window_samples(window, "window", rate, minimum=2)
    step = window_samples(step, "step", rate, minimum=1)
    if window > sig.nobs:
        raise ValueError(f"window must be <= the signal length {sig.nobs}, got {window}")
    timed = sig.index is not None and sampling_frequency(sig, None) is not None      # a time index, not positions
    if _mean_models(models, "models"):
        if u is not None:
            raise TypeError("u is only for input-output (ARX) models: FPMean models have no input; leave u out")
        return _mean_windows(sig, models, test, window, step, pd.Index(sig.index) if timed else None, rate)
    tests = _model_tests(test, models)
    for name, res in models.items():
        _check_model(res, name, sig, "models")
    engine = ResidualWindows(models).fit(sig, u=u)
    ws = engine.statistics(tests, window=window, step=step, loglik=False)
    return WindowedIdentification(ws, tuple(tests.values()),
                                  tuple(tests[name].reference(res) for name, res in models.items()), engine,
                                  pd.Index(sig.index) if timed else None, rate)


def _mean_windows(sig: Signal, models: Mapping, test: Any, window: int, step: int, time: Any,
                  rate: float | None) -> WindowedIdentification:
    """:func:`identify_windows` with FPMean models: every window's statistic, threshold and log-likelihood."""
    thresholds = _mean_thresholds(test, models, "test")
    for name, res in models.items():
        _mean_check(res, name, sig, window, "models")
    scores = [_mean_scores(res, sig, step) for res in models.values()]
    starts = np.arange(0, sig.nobs - window + 1, step)
    q = np.stack([sc[0] for sc in scores], axis=1)
    thr = np.array([np.inf if t is None else t.threshold_ for t in thresholds.values()])
    pv = np.stack([np.full(len(starts), np.nan) if t is None else np.asarray(t.pvalue(sc[0]), dtype=float)
                   for t, sc in zip(thresholds.values(), scores)], axis=1)
    decisions = tuple(tuple(_mean_decision(res, sc[0][w], sc[1][w], sc[2][w], t)
                            for res, sc, t in zip(models.values(), scores, thresholds.values()))
                      for w in range(len(starts)))
    rej = (q > thr)[:, :, None]
    ws = WindowStatistics(models=tuple(models), channels=("joint",), starts=starts, window=window, step=step,
                          nobs=(window,) * len(models), statistic=q[:, :, None],
                          threshold=np.broadcast_to(thr, q.shape)[:, :, None].copy(), pvalue=pv[:, :, None],
                          channel_reject=rej, reject=rej[:, :, 0], loglik=np.stack([sc[1] for sc in scores], axis=1),
                          decisions=decisions)
    return WindowedIdentification(ws, tuple(thresholds.values()), ({},) * len(models), None, time, rate)

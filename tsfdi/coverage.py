r"""Does a baseline cover a new flight? Record-level summaries of a new record against the fitting records' spread.

A residual test calibrated on a baseline's fitting records holds its false-alarm rate on flights like those
records. A flight with another payload, trim or airframe is outside what the baseline has seen, and a decision on
it silently changes meaning. :func:`coverage` says when: it compares a few record-level summaries of the new record
(per channel: the mean of the signal, the log scale of its residuals, the autocorrelation of its residuals at lags
``1..lags``) with the spread of the same summaries over the fitting records, each fitting record's residuals taken
through a model *not* fitted on it (:meth:`~tsfdi.models.AR.held_out_residuals`), as the new record's are.
:meth:`tsfdi.Baselines.covers` is the same check for a baseline's state model. :func:`record_coverage` checks a
calibrated test's own statistics against the predictive record law its thresholds rest on (one-sided: the record
whose false-alarm rate the calibration no longer bounds). :func:`check_coverage` picks the one a decision's test and
baseline allow (``None`` when neither): what :func:`~tsfdi.detect`, :meth:`~tsfdi.Monitor.run` and
:func:`~tsfdi.evaluate` run on the records they judge. :func:`warn_if_not_covered` emits a
:class:`~tsfdi.exceptions.CoverageWarning`.
"""

from __future__ import annotations

import functools
import warnings
import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy import special

from tsfdi._data import Signal, as_signal
from tsfdi._validation import int_like, probability
from tsfdi.exceptions import CoverageWarning

__all__ = ["Coverage", "coverage", "record_coverage", "check_coverage", "warn_if_not_covered",
           "warn_records_not_covered",
           "MIN_RECORDS", "ALL", "LEVEL_SUM"]

#: fitting records needed: the predictive law of a new record's summary is a t law with ``records - 1`` degrees of
#: freedom, so two records give one degree of freedom (a Cauchy law whose intervals are too wide to warn of
#: anything) and one gives none
MIN_RECORDS = 3

#: the ``summary`` label of :func:`record_coverage`'s row of the whole decision: a record's levels (log mean
#: statistic) summed over the test's parts and channels (channel :data:`ALL`)
LEVEL_SUM = "level_sum"

#: the ``channel`` label of the summary over all channels: the mean of the channels' log scales (the noise level of
#: the whole aircraft, which moves every channel's scale together)
ALL = "all"


@dataclass(frozen=True, eq=False)
class Coverage:
    """Whether a baseline's fitting records cover a new record (outcome of :func:`coverage`).

    Attributes
    ----------
    covered : bool
        ``False`` when a summary of the new record lies outside its predictive interval (the warning fires).
    pvalue : float
        Sidak-adjusted smallest per-summary p-value, ``1 - (1 - min p)^m``: ``covered`` is ``pvalue > alpha``.
    alpha : float
        False-warning rate of the check on a record like the fitting records (all summaries together).
    table : pandas.DataFrame
        One row per summary, indexed by (``summary``, ``channel``) (of :func:`record_coverage`: see there, with
        the row of the whole decision :data:`LEVEL_SUM`); ``summary`` is ``"mean"`` (the signal's mean, the
        trim), ``"log_scale"`` (log root-mean-square residual) or
        ``"acf1"``, ``"acf2"``, ... (Fisher z, ``arctanh``, of the residual autocorrelation at that lag).
        Columns: ``value`` (the new record's), ``fit_mean``, ``fit_std``, ``fit_min``, ``fit_max`` (over the
        fitting records), ``lower``, ``upper`` (the predictive interval at the per-summary level), ``t``
        (predictive t statistic), ``pvalue`` (two-sided, per summary), ``out`` (outside the interval), ``excess``
        (``|t|`` over the interval's half-width in t units: above 1 when out).
    records : int
        Fitting records the spread comes from.
    nobs : int
        Samples of the new record.
    """

    covered: bool
    pvalue: float
    alpha: float
    table: pd.DataFrame
    records: int
    nobs: int

    @property
    def out(self) -> pd.DataFrame:
        """The rows of :attr:`table` outside their predictive interval, largest ``excess`` first."""
        return self.table[self.table["out"]].sort_values("excess", ascending=False)

    def warning_message(self) -> str:
        """One sentence: covered, or which summaries lie outside the fitting records' spread and by how much."""
        m = len(self.table)
        if self.covered:
            return (f"the record lies within the spread of the baseline's {self.records} fitting records ({m} "
                    f"summaries, alpha {self.alpha:g}, p = {self.pvalue:.3g})")
        parts = [f"{s}[{c}] = {r.value:.4g} (fitting records {r.fit_min:.4g} .. {r.fit_max:.4g}, predictive "
                 f"interval {r.lower:.4g} .. {r.upper:.4g}, t = {r.t:.3g})" for (s, c), r in self.out.iterrows()]
        return (f"the record lies outside the spread of the baseline's {self.records} fitting records (p = "
                f"{self.pvalue:.3g} < alpha {self.alpha:g}, {len(parts)} of {m} summaries out): " + "; ".join(parts)
                + ". Decisions on it are not covered by the baseline's calibration: fit the baseline on flights "
                  "like this one")

    def __repr__(self) -> str:
        return (f"Coverage(covered={self.covered}, pvalue={self.pvalue:.3g}, alpha={self.alpha:g}, "
                f"records={self.records}, out={[f'{s}[{c}]' for s, c in self.out.index]})")


def _summaries(y: np.ndarray, e: np.ndarray, lags: int) -> np.ndarray:
    """Record-level summaries of one record: per channel the mean of ``y``, the log RMS of the residuals ``e`` (and
    its mean over the channels when there are several) and the Fisher z of their autocorrelation at lags
    ``1..lags``; in :func:`_index`'s order (summary-major)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = 0.5 * np.log(np.mean(e * e, axis=0))
        out = [y.mean(axis=0), scale] + ([scale.mean(keepdims=True)] if scale.size > 1 else [])
        c = e - e.mean(axis=0)
        c0 = np.sum(c * c, axis=0)
        for j in range(1, lags + 1):
            out.append(np.arctanh(np.sum(c[j:] * c[:-j], axis=0) / c0))
    return np.concatenate(out)


#: model -> {lags: the fitting records' summaries on the model's own held-out residuals}: one entry per model
#: specification, shared by every results object of it (a functionally pooled model's point results ``.at(k)`` at
#: every ``k`` share one model, whose held-out residuals are the FP model's), so that judging many records against
#: one baseline summarises its fitting records once (only what the library computed is kept: a ``held_out`` the
#: caller gives may change between calls)
_FIT: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _index(channels: list, lags: int) -> pd.MultiIndex:
    return _summary_index(tuple(str(c) for c in channels), lags).copy()     # a copy: its names may be set


@functools.lru_cache(maxsize=64)
def _summary_index(chans: tuple, lags: int) -> pd.MultiIndex:
    """The summaries' index of :func:`_index` (kept: an index is immutable, and building one costs ~1 ms)."""
    rows = [(s, c) for s in ("mean", "log_scale") for c in chans] + ([("log_scale", ALL)] if len(chans) > 1 else [])
    rows += [(f"acf{j}", c) for j in range(1, lags + 1) for c in chans]
    return pd.MultiIndex.from_tuples(rows, names=["summary", "channel"])


def coverage(results: Any, signal: Any, *, held_out: Any = None, alpha: float = 0.01, lags: int = 2,
             name: str = "signal") -> Coverage:
    r"""Whether the records a model was fitted on cover a new record.

    Parameters
    ----------
    results : ARResults or VARResults
        A model fitted on several records (``tsfdi.VAR([r1, r2, ...], lags).fit()``): its records are the
        baseline's fitting records.
    signal : array_like, pandas.Series / DataFrame or xarray.DataArray
        The new record, with the model's channels (a named signal is matched by name, as
        :meth:`~tsfdi.VARResults.residuals` does).
    held_out : sequence of residual series, optional
        One residual series per fitting record, in record order, each through a model not fitted on it (default
        ``results.model.held_out_residuals()``; pass ``held_out_residuals(groups=...)`` to hold out related
        records together).
    alpha : float
        False-warning rate on a record like the fitting records, all summaries together (Sidak).
    lags : int
        Residual autocorrelation lags summarised (``0``: none).
    name : str
        Name of ``signal`` in error messages.

    Returns
    -------
    Coverage

    Raises
    ------
    ValueError
        Fewer than :data:`MIN_RECORDS` fitting records; ``held_out`` not one series per record with the model's
        channels; a record (or ``signal``) too short for ``lags``; non-finite summaries.
    TypeError
        ``results`` not an AR / VAR results object (an ARX needs its input: not supported).

    Notes
    -----
    For each summary :math:`f` (``m`` of them), with :math:`\bar f` and :math:`s` its mean and standard deviation
    over the ``n`` fitting records, a new record like them has

    .. math::  t = \frac{f_{new} - \bar f}{s \sqrt{1 + 1/n}} \sim t_{n-1}

    when the records' summaries are independent normal draws (the predictive law, which carries the uncertainty
    of estimating the spread from few records: with few records the interval widens). The record is covered when
    every :math:`|t|` is below the :math:`1 - \alpha_m / 2` quantile of :math:`t_{n-1}`, with the Sidak share
    :math:`\alpha_m = 1 - (1 - \alpha)^{1/m}`. Between-record differences (payload, trim, airframe, noise
    level) and the within-record estimation noise of the summaries both enter :math:`s`, so records of
    comparable length should be compared: a much shorter new record has noisier summaries and warns more often,
    a much longer one less often. Correlated summaries (the residual scales of all channels when the noise level
    of the whole aircraft changes) make the Sidak share conservative.
    """
    alpha = probability(alpha, "alpha")
    lags = int_like(lags, "lags", minimum=0)
    model = getattr(results, "model", None)
    if model is None or not hasattr(model, "records") or not callable(getattr(results, "residuals", None)):
        raise TypeError(f"results must be fitted AR or VAR results, got {type(results).__name__}")
    if getattr(model, "u_records", None) is not None:
        raise TypeError("results must be AR or VAR results: a model with an input (ARX) is not supported")
    records = model.records
    n = len(records)
    if n < MIN_RECORDS:
        raise ValueError(f"coverage needs at least {MIN_RECORDS} fitting records (the spread of their summaries is "
                         f"estimated from them), the model was fitted on {n}: fit it on a list of {MIN_RECORDS} or "
                         "more records")
    data = model.data
    k = data.nchan
    sig = as_signal(signal, name, min_nobs=model.max_lag + lags + 2, allow_constant=True)
    sig = sig.match_channels(data.channels, name, named=data.named)
    idx = _index(data.channels, lags)
    F = _fit_summaries(results, held_out, lags, idx)
    new = _summaries(sig.values, np.asarray(results.residuals(sig.values), np.float64).reshape(-1, k), lags)
    if not np.all(np.isfinite(new)):
        j = int(np.flatnonzero(~np.isfinite(new))[0])
        raise ValueError(f"{name}: summary {idx[j][0]}[{idx[j][1]}] is not finite (a constant or perfectly "
                         "predicted channel)")
    centre, sd = F.mean(axis=0), F.std(axis=0, ddof=1)
    scale = sd * np.sqrt(1.0 + 1.0 / n)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(scale > 0, (new - centre) / scale, np.where(new == centre, 0.0, np.inf * np.sign(new - centre)))
    p = 2.0 * special.stdtr(n - 1, -np.abs(t))                       # the t law's two tails (scipy.stats.t, faster)
    crit = float(-special.stdtrit(n - 1, _share(alpha, len(new)) / 2.0))
    return _verdict({"value": new, "fit_mean": centre, "fit_std": sd, "fit_min": F.min(axis=0),
                     "fit_max": F.max(axis=0), "lower": centre - crit * scale, "upper": centre + crit * scale,
                     "t": t, "pvalue": p, "excess": np.abs(t) / crit}, idx, alpha, n, sig.nobs)


def _fit_summaries(results: Any, held_out: Any, lags: int, idx: pd.MultiIndex) -> np.ndarray:
    """The summaries of the fitting records of ``results`` (one row each) on their held-out residuals (``held_out``,
    default ``results.model.held_out_residuals()``, whose summaries are kept for the next call with the same model
    and ``lags``)."""
    if held_out is None:
        known = _FIT.setdefault(results.model, {})
        if lags not in known:
            known[lags] = _fit_summaries(results, results.model.held_out_residuals(), lags, idx)
        return known[lags]
    model = results.model
    records, k = model.records, model.data.nchan
    n = len(records)
    if isinstance(held_out, (str, bytes)) or not hasattr(held_out, "__len__") or len(held_out) != n:
        raise ValueError(f"held_out must hold one residual series per fitting record ({n}), got "
                         f"{len(held_out) if hasattr(held_out, '__len__') else type(held_out).__name__}")
    fit = []
    for i, (rec, e) in enumerate(zip(records, held_out)):
        e = np.asarray(e, dtype=np.float64)
        e = e.reshape(e.shape[0], -1) if e.ndim else e
        if e.ndim != 2 or e.shape[1] != k or e.shape[0] < lags + 2:
            raise ValueError(f"held_out[{i}] must be a residual series of {k} channel(s) and at least {lags + 2} "
                             f"samples, got shape {np.shape(e)}")
        fit.append(_summaries(rec.values, e, lags))
    F = np.array(fit)
    bad = ~np.isfinite(F)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise ValueError(f"summary {idx[j][0]}[{idx[j][1]}] of fitting record {i} is not finite (a constant or "
                         "perfectly predicted channel)")
    return F


def _share(alpha: float, m: int) -> float:
    """Sidak share ``1 - (1 - alpha)^(1/m)`` of each of ``m`` summaries."""
    return float(-np.expm1(np.log1p(-alpha) / m))


def _verdict(columns: dict, index: pd.MultiIndex, alpha: float, records: int, nobs: int) -> Coverage:
    """The :class:`Coverage` of the summaries' ``columns`` (arrays, one value per summary of ``index``; ``pvalue``
    per summary): a summary is out when its p-value is below the Sidak share of ``alpha``; the family p-value is
    the Sidak-adjusted smallest one. The table is built once (pandas' overhead counts once per judged record)."""
    p = np.asarray(columns["pvalue"], dtype=np.float64)
    m = p.size
    out = p < _share(alpha, m)
    table = pd.DataFrame({**{c: columns[c] for c in ("value", "fit_mean", "fit_std", "fit_min", "fit_max", "lower",
                                                     "upper", "t", "pvalue")}, "out": out,
                          "excess": columns["excess"]}, index=index)
    pmin = float(p.min())
    family = float(-np.expm1(m * np.log1p(-pmin))) if pmin < 1 else 1.0
    return Coverage(covered=not bool(out.any()), pvalue=family, alpha=alpha, table=table, records=records, nobs=nobs)


def record_coverage(test: Any, resid: Any, *, alpha: float = 0.01, name: str = "resid") -> Coverage:
    r"""Whether a new record as a whole lies in the predictive record law of a calibrated test.

    A calibrated test (:class:`~tsfdi.LjungBox`, :class:`~tsfdi.FTest`, :class:`~tsfdi.MeanTest` or an
    :class:`~tsfdi.AnyOf` of them, calibrated with the predictive record-level law on held-out residuals of
    several records) predicts the law of its statistic on a *new* record from a record effect: each fitting
    record's level a normal draw (:class:`~tsfdi.ScaledChi2Threshold`). This check asks whether the new record's
    level -- the log mean of the very statistics that flag its windows, per part and channel -- is a draw of that
    predictive law (:meth:`~tsfdi.ScaledChi2Threshold.record_pvalue`): it warns when the record, not a window, is
    out of the law, which is when the calibrated false-alarm rate no longer applies to it. :func:`coverage`
    compares generic summaries (trims, residual scales and autocorrelations) two-sided; this check compares what
    the decision rests on, one-sided, so that with few fitting records it warns of more of the records whose
    windows the test flags beyond alpha (``benchmarks/baseline_coverage.py``).

    Parameters
    ----------
    test : calibrated test
        Calibrated with ``record_effect="predictive"`` (the default) on held-out residuals of at least
        :data:`MIN_RECORDS` records.
    resid : array_like, pandas or xarray
        The new record's residuals through the baseline model (what the test is given), ``(nobs, k)``: at least
        three windows of the calibrated length.
    alpha : float
        False-warning rate of the check on a record like the fitting records, all summaries together (Sidak).
    name : str
        Name of ``resid`` in error messages.

    Returns
    -------
    Coverage
        Its table has one row per (``summary`` = the part's class name, ``channel``): ``value`` the new record's
        level (log mean statistic), ``fit_mean`` / ``fit_std`` / ``fit_min`` / ``fit_max`` the fitting records'
        levels, ``upper`` the predictive bound at the Sidak share (``lower`` is ``-inf``: one-sided, see Notes),
        ``t`` the level's distance in predictive standard deviations, ``pvalue`` the law's upper tail, ``excess``
        the level's distance from the fitting records' mean over the bound's (above 1 when out); and, when there
        are two or more such rows, one row of the whole decision, (:data:`LEVEL_SUM`, :data:`ALL`): the same
        columns for the sum of the levels over the parts and channels (see Notes). The Sidak share is that of
        all the rows.

    Raises
    ------
    TypeError
        ``test`` not a calibrated windowed test.
    ValueError
        The test not calibrated, or calibrated without a record law (too few records, ``record_effect="bootstrap"``
        or a threshold other than :class:`~tsfdi.ScaledChi2Threshold`); ``resid`` with other channels or shorter
        than three windows.

    Notes
    -----
    The check is one-sided: a calibrated threshold promises a false-alarm rate of at most ``alpha`` on a new record,
    and the promise fails for a record whose statistics lie above the law; a record below it (a quieter aircraft)
    has fewer false alarms and is not warned of (its decisions are conservative, with less power). With as many
    windows as a fitting record the per-summary statistic is the Student t pivot of normal record
    levels, :math:`(l_{new} - \bar l) / (s \sqrt{1 + 1/J}) \sim t_{J-1}`; the level of a new record with fewer
    (more) windows is noisier (less noisy) and the law accounts for it. The new record's statistic is taken on
    windows of the calibrated length and step (the step read from the calibration's windows per independent window),
    as the fitting records' were.

    Each row has its share of ``alpha``: with the 6 segments of 3 flights of a CrazyPAD airframe (``J = 6``) and
    LB+F+M on six channels (18 rows), a row must lie about 6.7 predictive standard deviations out (6.8 with the
    row below), so that a record whose statistics all sit a few deviations high is not warned of. The row of the
    whole decision sums a record's levels over the parts and channels, :math:`D = \sum_r l_r`: the record law takes
    every level as a normal record effect, so a fixed linear combination of them is normal too (when they are
    jointly normal), and over the ``J`` fitting records' sums :math:`D_j`, with mean :math:`\bar D` and standard
    deviation :math:`s_D`,

    .. math:: t = \frac{D_{new} - \bar D}{s_D \sqrt{1/J + \max(1, \bar n / n_{new})}} \sim t_{J-1}

    (the Student t pivot; :math:`\bar n` the fitting records' independent windows per record, :math:`n_{new}` the
    new record's: a shorter record's levels are noisier, and scaling the whole variance by the ratio errs on the
    safe side). A summary of the decision's own window p-values (the record's mean :math:`-\ln \min p`, each
    fitting record through the test calibrated without it) was measured and not adopted: a positive, right-skewed
    statistic whose t pivot was liberal with 5 records (3.0 % false warnings at 0.01); its log or mean normal score
    came closer only with the new record judged by the same leave-one-out calibrations, and needs the fitting
    records' residuals and a calibration without each of them (``benchmarks/baseline_coverage.py``, section 6).
    """
    alpha = probability(alpha, "alpha")
    parts = tuple(getattr(test, "tests", (test,)))
    if not all(callable(getattr(p, "window_statistic", None)) for p in parts):
        raise TypeError(f"test must be a calibrated windowed test (LjungBox, FTest, MeanTest or an AnyOf of them), "
                        f"got {type(test).__name__}")
    rows, names, index = [], [type(p).__name__ for p in parts], []
    sig = None
    for i, part in enumerate(parts):
        ths = getattr(part, "thresholds_", None)
        label = names[i] if names.count(names[i]) == 1 else f"{names[i]}{i}"
        if not ths or not all(getattr(t, "record_law_", None) is not None for t in ths):
            raise ValueError(f"test part {label} is not calibrated with the predictive record law: calibrate it on "
                             f"held-out residuals of at least {MIN_RECORDS} records with threshold='calibrated' "
                             "(record_effect='predictive', the default)")
        window = part.calibration_window_[0] if getattr(part, "calibration_window_", None) else None
        if window is None:
            raise ValueError(f"test part {label} was calibrated on a statistic without its window: calibrate it on "
                             "residual records (calibrate(resid, window=...))")
        if sig is None:
            sig = as_signal(resid, name, allow_constant=True)
            if sig.nobs < 3 * window:
                raise ValueError(f"{name} holds {sig.nobs} samples, at least 3 disjoint windows of the calibrated "
                                 f"{window} residual samples ({3 * window}) are needed")
        if sig.nchan != len(ths):
            raise ValueError(f"{name} has {sig.nchan} channel(s) but the test was calibrated on {len(ths)}")
        # the fitting records' windows were taken `step` apart: the new record's are too (its law's estimate then
        # has the noise the record law's spread holds); the step from the windows per independent window
        step = max(1, min(window, round(window * ths[0].independent_ / ths[0].nobs_)))
        stat = np.asarray(part.window_statistic(sig.values, window, step), dtype=np.float64)
        for c, th in enumerate(ths):
            try:
                level, z, p = th.record_pvalue(stat[:, c], sig.nobs // window)
            except ValueError as err:
                raise ValueError(f"{name}, {label} channel {sig.channels[c]!r}: {err}") from None
            fit = th.levels_
            rows.append((level, z, p, fit, th, sig.nobs // window))
            index.append((label, str(sig.channels[c])))
    share = _share(alpha, len(rows) + (len(rows) > 1))         # the rows and the levels' sum (when there are two)
    levels = np.array([r[0] for r in rows])
    centre = np.array([r[3].mean() for r in rows])
    upper = np.array([th.record_bound(share, windows) for *_, th, windows in rows])
    cols = {"value": levels, "fit_mean": centre, "fit_std": np.array([r[3].std(ddof=1) for r in rows]),
            "fit_min": np.array([r[3].min() for r in rows]), "fit_max": np.array([r[3].max() for r in rows]),
            "lower": np.full(len(rows), -np.inf), "upper": upper, "t": np.array([r[1] for r in rows]),
            "pvalue": np.array([r[2] for r in rows]), "excess": (levels - centre) / (upper - centre)}
    if len(rows) > 1:
        th0 = rows[0][4]
        total = np.sum([r[3] for r in rows], axis=0)   # each fitting record's sum (the parts share the records)
        row = _level_sum(levels.sum(), total, th0.independent_ / th0.records_, rows[0][5], share)
        cols = {c: np.append(v, row[c]) for c, v in cols.items()}
        index.append((LEVEL_SUM, ALL))
    return _verdict(cols, pd.MultiIndex.from_tuples(index, names=["summary", "channel"]), alpha,
                    parts[0].thresholds_[0].records_, sig.nobs)


def _level_sum(value: float, fit: np.ndarray, fit_windows: float, windows: int, share: float) -> dict:
    """The :data:`LEVEL_SUM` row of :func:`record_coverage`: the new record's sum of levels ``value`` against the
    fitting records' sums ``fit``, one-sided Student t pivot of ``J - 1`` degrees of freedom, the variance of a new
    record of ``windows`` independent windows scaled by ``fit_windows / windows`` when it is shorter than the
    fitting records (``fit_windows`` per record on average); the bound at ``share``."""
    j = fit.size
    centre, sd = float(fit.mean()), float(fit.std(ddof=1))
    scale = sd * np.sqrt(1.0 / j + max(1.0, fit_windows / windows))
    d = value - centre
    t = d / scale if scale > 0 else (0.0 if d == 0 else np.inf * np.sign(d))
    upper = centre + float(special.stdtrit(j - 1, 1.0 - share)) * scale
    return {"value": value, "fit_mean": centre, "fit_std": sd, "fit_min": float(fit.min()),
            "fit_max": float(fit.max()), "lower": -np.inf, "upper": upper, "t": t,
            "pvalue": float(special.stdtr(j - 1, -t)), "excess": d / (upper - centre) if upper > centre else
            (0.0 if d == 0 else np.inf * np.sign(d))}


def check_coverage(test: Any, results: Any, signal: Any, *, resid: Any = None, held_out: Any = None,
                   alpha: float = 0.01) -> Coverage | None:
    """The coverage of a judged record by what its decision rests on, when that is enough to say; else ``None``.

    What :func:`~tsfdi.detect`, :meth:`~tsfdi.Monitor.run` and :func:`~tsfdi.evaluate` check:

    1. :func:`record_coverage` of ``test`` on the record's residuals when the test carries a predictive record law
       (calibrated on held-out residuals of at least :data:`MIN_RECORDS` records) and the residuals hold at least
       three windows of the calibrated length;
    2. else :func:`coverage` of ``signal`` by ``results`` when they are an AR / VAR fitted on at least
       :data:`MIN_RECORDS` records and ``signal`` is at least as long as the shortest of them (the summaries of a
       shorter record are noisier than the fitting records' and would warn more often than ``alpha``);
    3. else ``None``, at the cost of a few attribute look-ups (nothing is filtered).

    One check, not both: where both apply, warning when either fires (each at its Sidak share of ``alpha``) warned
    of fewer of the records the test misjudges than the record law alone, both with false-warning rates in the
    binomial band of ``alpha`` (simulated fleets and hexacopters, ``benchmarks/baseline_coverage.py --sections 5``).

    Parameters
    ----------
    test : ResidualTest
        The test of the decision.
    results : fitted results
        The baseline model.
    signal : array_like, pandas, xarray or Signal
        The record (time on axis 0).
    resid : array_like, optional
        The record's residuals through ``results`` when already computed (default: computed when the record law
        applies).
    held_out : sequence of residual series, optional
        The fitting records' held-out residuals (:func:`coverage`; default computed once per ``results``).
    alpha : float
        False-warning rate of the check on a record like the fitting records.

    Returns
    -------
    Coverage or None

    Raises
    ------
    ValueError
        The check applies but the record cannot be summarised (a constant channel: a non-finite summary).
    """
    nobs = signal.nobs if isinstance(signal, Signal) else len(signal)
    model = getattr(results, "model", None)
    window = _record_window(test)
    if window is not None and nobs - int(getattr(results, "lags", 0)) >= 3 * window:
        if resid is None:          # named by the model's channels (the warning names them)
            resid = np.asarray(results.residuals(signal), dtype=np.float64)
            resid = pd.DataFrame(resid.reshape(resid.shape[0], -1), columns=[str(c) for c in model.data.channels])
        if np.shape(resid)[0] >= 3 * window:
            return record_coverage(test, resid, alpha=alpha)
    records = getattr(model, "records", None)
    if (records is None or len(records) < MIN_RECORDS or getattr(model, "u_records", None) is not None
            or nobs < min(r.nobs for r in records)):
        return None
    return coverage(results, signal, held_out=held_out, alpha=alpha)


def _record_window(test: Any) -> int | None:
    """The calibrated window of ``test`` when every part carries a predictive record law (:func:`record_coverage`
    can judge a record with it), else ``None``."""
    parts = getattr(test, "tests", (test,))
    windows = {(getattr(p, "calibration_window_", None) or (None,))[0] for p in parts}
    if len(windows) != 1 or None in windows or not all(
            getattr(p, "thresholds_", None) and all(getattr(t, "record_law_", None) is not None
                                                    for t in p.thresholds_) for p in parts):
        return None
    return int(windows.pop())


#: record identifiers named in :func:`warn_records_not_covered`'s one warning for many records
NAMED_RECORDS = 5


def warn_records_not_covered(outside: Any, where: str, *, judged: int, see: str, stacklevel: int = 2) -> None:
    """One :class:`~tsfdi.exceptions.CoverageWarning` for the records of a call that the baseline does not cover:
    the record's own message when there is one, else how many of ``judged`` records lie outside, the first
    :data:`NAMED_RECORDS` of them, and where the summaries out of each are kept (``see``), so that a fleet screened
    at once does not print a warning per record. Nothing when ``outside`` is empty.

    Parameters
    ----------
    outside : mapping
        Record identifier -> the summaries out (the text of :meth:`Coverage.warning_message`), in record order.
    where : str
        The caller (``"Monitor.screen"``, ``"evaluate"``).
    judged : int
        Records whose coverage was checked.
    see : str
        Where the per-record result is, e.g. ``"the 'outside' column"``.
    stacklevel : int
        Counted from the caller of this function, as :func:`warnings.warn` does from its own caller.
    """
    items = list(dict(outside).items())
    if not items:
        return
    if len(items) == 1:
        (r, out), = items
        msg = f"{where}: record {r}: {out}"
    else:
        named = ", ".join(str(r) for r, _ in items[:NAMED_RECORDS]) + (", ..." if len(items) > NAMED_RECORDS else "")
        msg = (f"{where}: {len(items)} of {judged} records checked lie outside the spread of the baseline's fitting "
               f"records (records {named}); the summaries out of each are in {see}. Decisions on them are not "
               "covered by the baseline's calibration: fit the baseline on flights like these")
    warnings.warn(msg, CoverageWarning, stacklevel=stacklevel + 1)


def warn_if_not_covered(coverage: Coverage, where: str, *, stacklevel: int = 2) -> None:
    """Emit a :class:`~tsfdi.exceptions.CoverageWarning` naming ``where`` (``"detect"``, ``"Monitor"``, a file)
    when ``coverage`` is not covered; nothing otherwise.

    ``stacklevel`` counts from the caller of this function, as :func:`warnings.warn` does from its own caller.
    """
    if not isinstance(coverage, Coverage):
        raise TypeError(f"coverage must be a Coverage (tsfdi.coverage.coverage, Baselines.covers), got "
                        f"{type(coverage).__name__}")
    if not coverage.covered:
        warnings.warn(f"{where}: {coverage.warning_message()}", CoverageWarning, stacklevel=stacklevel + 1)

"""Evaluation of the whole method over many records (Dutta et al., paper 003, Table 4) and per-record scoring.

:func:`evaluate` runs detection with the healthy model and identification with the fault models on every sliding
window of every record that was *not* used for fitting, for the models x tests x window lengths x turbulence levels
asked for, and returns an :class:`Evaluation` holding the window outcomes counted (per distinct outcome, summed over
records and window positions, so that its size does not grow with the records), the Table 4 analogue (percent of
windows of each true failure accepted as each rotor), unique-correct, ambiguity and no-decision rates, detection
false-alarm and missed-fault rates and detection delays.

Per-record detection scoring (Keipour et al., paper 001, Table I) scores a detector once per record, from its
*first* alarm:

- a record with a fault (an onset time): an alarm before the onset is a false positive (FP), an alarm at or
  after it a true positive (TP) whose detection delay is ``first_alarm - onset``, no alarm a false negative (FN);
- a fault-free record (no onset): any alarm is a false positive (FP), no alarm a true negative (TN);
- precision = TP / (TP + FP), recall = TP / (TP + FN), accuracy = (TP + TN) / records, and the mean detection
  delay over the true positives.

:func:`first_alarm` reads the first alarm off a per-sample or per-window boolean alarm (for instance
``OnlineDetection.alarm`` or ``MonitorResult.windows["fault"]``), :func:`score_records` turns onsets and first
alarms into one outcome and delay per record and :func:`detection_metrics` counts them, per group (fault kind) and
over all records. Nothing there depends on a data set: times are plain numbers in one consistent unit (seconds in
the examples), NaN meaning "no fault" (onset) or "no alarm" (first alarm).
"""

from __future__ import annotations

import dataclasses
import numbers
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from tsfdi._data import as_signal, refuse_masked, window_samples
from tsfdi._validation import boolean, float_like, option
from tsfdi.baselines import Baselines, Records
from tsfdi.coverage import check_coverage, warn_records_not_covered
from tsfdi.detection.base import ResidualTest
from tsfdi.detection.combined import AnyOf
from tsfdi.detection.whiteness import LjungBox
from tsfdi.models import FPResults, InputOutputResults
from tsfdi.summary import Summary
from tsfdi.detection.sequential import msprt
from tsfdi.windows import AMBIGUOUS, RULES, SEQUENTIAL_RULES, ResidualWindows, decide

__all__ = ["OUTCOMES", "Evaluation", "detection_metrics", "evaluate", "first_alarm", "score_records"]


@dataclass(frozen=True, eq=False)
class Evaluation:
    """Outcome of :func:`evaluate`: the window outcomes counted, and the rates and delays read from the counts.

    Every table is a count of windows (or records) per distinct outcome, summed over the records and the window
    positions: its size does not grow with the number of records, and the tables of two sets of records add up
    (``pandas.concat`` then a ``groupby(...).sum()`` over every column but the count), which is how chunks of a fleet
    on dask are combined. The outcome of one window of one record is not kept; run :func:`tsfdi.identify_windows` or
    :class:`tsfdi.Monitor` on that record for it.

    Attributes
    ----------
    identification_counts : pandas.DataFrame
        Windows of the fault records starting at least ``settle`` s after the failure, tested with every fault
        model: one row per distinct combination of ``turbulence, model, method, window, state`` (the true
        failure), the bool columns ``acc_<fault>``, one per fault model (its test accepts), and ``label_<rule>``,
        one per rule (the identified fault, ``"ambiguous"`` or ``"none"``), with ``windows``, the number of such
        windows.
    detection_counts : pandas.DataFrame
        Windows of every evaluated record tested with the healthy model: one row per distinct combination of
        ``turbulence, model, method, window, state`` and the flags ``fault_true`` (the window starts at or after
        the failure), ``pre`` (it ends at or before the failure; every window of a healthy record), ``alarm`` (the
        test rejects) and ``disjoint`` (it starts at a multiple of the window length: the windows that do not
        overlap), with ``windows``.
    detection_delays : pandas.DataFrame
        Fault records with a window ending after the failure: one row per distinct combination of ``turbulence,
        model, method, window, state`` and ``delay`` (s, from the failure to the end of the first flagged window
        ending after it; NaN: no such window is flagged, a missed record), with ``records``, the number of such
        records.
    faults : tuple of str
    rules : tuple of str
    alphas : dict
        ``(model, method)`` -> the risk of each channel of the test's decision (per window; the test's ``alpha``, or
        its share with ``correction=``: :meth:`~tsfdi.ResidualTest.channel_alpha`).
    lags : dict
        window length (s) -> Ljung-Box lags.
    records : pandas.DataFrame
        The records evaluated (id, state, turbulence) and those skipped with the reason.
    nchan : dict
        model -> number of channels tested.
    thresholds : {"theoretical", "empirical"}
        How the test thresholds were set (``"empirical"`` when any test was calibrated).
    calibration : pandas.DataFrame
        Per turbulence level (baselines), model, method, ``part`` (``""``: the test's statistic; for an
        :class:`~tsfdi.AnyOf` also each part, ``"0: LjungBox"``, ...), window length, state and channel: the null
        distribution's critical value (``distribution``) and, for a test with ``threshold="empirical"``, the calibrated
        one (``empirical``), its calibration sample size and estimate (``"empirical"`` quantile or ``"gpd"``
        tail).
    sequential_counts : pandas.DataFrame
        The sequential rule (``rules=(..., "sprt")``; empty without it): one row per distinct combination of
        ``turbulence, model, state`` (the true failure), ``label`` (the fault identified, ``"undecided"`` when no
        model dominates by the end of the record) and ``time`` (s from the start, ``settle`` s after the failure,
        to the decision; NaN undecided), with ``records``, the number of fault records with that outcome.
    sprt : dict
        The sequential rule's settings: ``alpha`` (the bound's error probability) and ``scale``, ``(turbulence,
        model)`` -> the scale correction of the log-likelihood ratios (1.0 without held-out residuals).
    coverage : pandas.DataFrame
        Whether the baselines cover each evaluated record's healthy part (:func:`tsfdi.coverage.check_coverage` of
        the healthy model's detection test; see :func:`evaluate`): one row per ``record, model, method, window``
        checked, with ``covered``, ``pvalue`` (the check's, alpha 0.01), ``records`` (fitting records behind it) and
        ``outside`` (the warning: the summaries out, ``""`` when covered). Empty when nothing could be checked.
        :attr:`records` has the column ``covered`` (every check of the record covered; ``<NA>`` where none ran).

    Notes
    -----
    The rates are ratios of these counts: a percent of windows is ``100 * (windows with the outcome) / (windows)``,
    the mean of the per-window flags, and the delays' median and maximum come from the ``delay`` values repeated
    ``records`` times.
    """

    identification_counts: pd.DataFrame
    detection_counts: pd.DataFrame
    detection_delays: pd.DataFrame
    faults: tuple
    rules: tuple
    alphas: dict
    lags: dict
    records: pd.DataFrame
    nchan: dict = field(default_factory=dict)
    thresholds: str = "theoretical"
    calibration: pd.DataFrame = field(default_factory=pd.DataFrame)
    sequential_counts: pd.DataFrame = field(default_factory=pd.DataFrame)
    sprt: dict = field(default_factory=dict)
    coverage: pd.DataFrame = field(default_factory=pd.DataFrame)

    # -- identification
    def _percent(self, flags: dict, keys: Sequence[str] = ("model", "method", "window", "state")) -> pd.DataFrame:
        """Percent of the identification windows of each ``keys`` group for which each of ``flags`` (name -> bool
        Series over the rows of :attr:`identification_counts`) holds, indexed ``(model, method, window, true)``."""
        df = self.identification_counts
        n = df["windows"]
        by = [df[k] for k in keys]
        hits = pd.DataFrame({c: n.where(f, 0) for c, f in flags.items()}).groupby(by, sort=False).sum()
        tab = hits.div(n.groupby(by, sort=False).sum(), axis=0) * 100.0
        tab.index = tab.index.set_names(["model", "method", "window", "true"])
        return tab

    def confusion(self, rule: str = "paper") -> pd.DataFrame:
        """Percent of the windows of each true failure labelled as each fault, ``"ambiguous"`` or ``"none"`` by
        ``rule``, per model, method and window length: every row adds up to 100.

        With the ``"paper"`` rule a window is labelled by the fault model that alone accepts it, ``"ambiguous"``
        when several accept it and ``"none"`` when none does; the other rules label every window (their
        ``"ambiguous"`` and ``"none"`` columns are 0). The paper's Table 4 counts acceptances instead, which
        need not add up to 100 (:meth:`table4`).

        Returns
        -------
        DataFrame indexed by ``(model, method, window, true)`` with one column per fault, then ``ambiguous``
        and ``none`` (percent of the row's windows).
        """
        lab = self.identification_counts[f"label_{option(rule, 'rule', self.rules)}"]
        return self._percent({c: lab == c for c in [*self.faults, "ambiguous", "none"]})

    def _accepted(self, rule: str) -> pd.DataFrame:
        """Percent of the windows of each true failure accepted as each fault (``"paper"``: several may be
        accepted) or labelled as it (other rules), indexed like :meth:`confusion`: the numbers of Table 4."""
        rule = option(rule, "rule", self.rules)
        if rule != "paper":
            return self.confusion(rule)[list(self.faults)]
        return self._percent({f: self.identification_counts[f"acc_{f}"] for f in self.faults})

    def rates(self) -> pd.DataFrame:
        """Per model, method, window length, true failure and rule: percent of windows identified uniquely and
        correctly (``correct``), uniquely but wrongly (``wrong``), ambiguous (``ambiguous``) and with no
        decision (``none``), and the number of windows."""
        df = self.identification_counts
        parts = []
        for rule in self.rules:
            lab = df[f"label_{rule}"]
            known = lab.isin(self.faults)
            t = self._percent({"correct": known & (lab == df["state"]), "wrong": known & (lab != df["state"]),
                               "ambiguous": lab == "ambiguous", "none": lab == "none"})
            t["windows"] = df.groupby([df[k] for k in ("model", "method", "window", "state")],
                                      sort=False)["windows"].sum().to_numpy()
            t["rule"] = rule
            parts.append(t.reset_index())
        return pd.concat(parts, ignore_index=True).set_index(["model", "method", "window", "true", "rule"])

    def table4(self, window: float | None = None, rule: str = "paper") -> pd.DataFrame:
        """The paper's Table 4 layout: rows ``(model, method)``, one column per true failure holding
        ``"a/b/c"``, the percent of its windows accepted (or labelled) as each fault, for one window length."""
        conf = self._accepted(rule)
        wins = sorted(conf.index.get_level_values("window").unique())
        if not wins:
            raise ValueError("this evaluation has no identification windows (no fault record was evaluated): there "
                             "is no Table 4")
        window = wins[-1] if window is None else float(window)
        if window not in wins:
            raise ValueError(f"window must be one of the evaluated lengths {wins}, got {window}")
        sub = conf.xs(window, level="window")
        out = {}
        for (model, method, true), row in sub.iterrows():
            out.setdefault((model, method), {})[true] = "/".join(f"{v:.2f}" for v in row.values)
        frame = pd.DataFrame.from_dict(out, orient="index")
        frame.index = frame.index.set_names(["model", "method"])
        return frame[[f for f in self.faults if f in frame.columns]]

    # -- sequential identification
    def sequential_rates(self, quantiles: Sequence[float] = (0.1, 0.9)) -> pd.DataFrame:
        """The sequential rule (``"sprt"``) per model and true failure: percent of the fault records identified
        correctly (``correct``), wrongly (``wrong``) and not decided by the record's end (``undecided``), the number
        of records, and the decision time (s from the start, ``settle`` s after the failure) of the decided
        records: ``time_mean``, ``time_median`` and the ``quantiles`` (``time_q10``, ... NaN without a decided
        record).

        Raises
        ------
        ValueError
            The evaluation was run without the ``"sprt"`` rule."""
        if self.sequential_counts.empty:
            raise ValueError("this evaluation has no sequential decisions: run evaluate with rules=(..., 'sprt')")
        qs = [float_like(q, "quantiles", minimum=0.0, maximum=1.0) for q in quantiles]
        rows = []
        for (model, true), g in self.sequential_counts.groupby(["model", "state"], sort=False):
            n = g["records"].to_numpy()
            lab = g["label"].to_numpy(dtype=object)
            total = int(n.sum())
            decided = lab != "undecided"
            t = np.repeat(g["time"].to_numpy(dtype=float)[decided], n[decided])
            row = {"model": model, "true": true,
                   "correct": 100.0 * n[lab == true].sum() / total,
                   "wrong": 100.0 * n[decided & (lab != true)].sum() / total,
                   "undecided": 100.0 * n[~decided].sum() / total, "records": total,
                   "time_mean": float(t.mean()) if t.size else np.nan,
                   "time_median": float(np.median(t)) if t.size else np.nan}
            for q in qs:
                row[f"time_q{100 * q:g}"] = float(np.quantile(t, q)) if t.size else np.nan
            rows.append(row)
        return pd.DataFrame(rows).set_index(["model", "true"])

    def sequential_confusion(self) -> pd.DataFrame:
        """Percent of the fault records of each true failure identified as each fault by the sequential rule, or
        ``"undecided"``, per model: every row adds up to 100."""
        if self.sequential_counts.empty:
            raise ValueError("this evaluation has no sequential decisions: run evaluate with rules=(..., 'sprt')")
        df = self.sequential_counts
        tab = df.pivot_table(index=["model", "state"], columns="label", values="records", aggfunc="sum",
                             fill_value=0, sort=False)
        tab = tab.reindex(columns=[*self.faults, "undecided"], fill_value=0)
        tab = tab.div(tab.sum(axis=1), axis=0) * 100.0
        tab.index = tab.index.set_names(["model", "true"])
        tab.columns.name = None
        return tab

    # -- detection
    def detection_rates(self) -> pd.DataFrame:
        r"""Per model, method and window length: ``false_alarm`` (percent of healthy-record windows flagged),
        ``expected_false_alarm`` (percent, ``1 - (1 - alpha)^k`` for ``k`` channels tested at ``alpha``),
        ``disjoint_windows`` and ``disjoint_alarms`` (the healthy windows that do not overlap: those starting at a
        multiple of the window length, and how many of them are flagged),
        ``false_alarm_pvalue`` (two-sided binomial p-value of ``disjoint_alarms`` alarms in ``disjoint_windows``
        independent windows at the expected rate, :math:`\min(1, 2\min(P(X \le x), P(X \ge x)))`: sliding windows
        1 s apart share most of their samples, so one excursion flags a run of them and only the disjoint ones can
        be counted as independent trials; small values mean more -- or fewer -- false alarms than the expectation
        allows), ``disjoint_band_low`` / ``disjoint_band_high`` (the two-sided 99 % binomial band of that count)
        and ``false_alarm_in_band`` (the count lies inside it: the judgement of the false-alarm rate),
        ``missed_fault`` (percent of fault-record windows starting after the failure not flagged),
        ``missed_records`` (fault records with no alarm after the failure), ``delay_median`` and ``delay_max``
        (s, from the failure to the end of the first flagged window ending after it). A rate or delay over no
        window (no healthy record, no window after a failure, no detection) is NaN.

        Raises
        ------
        ValueError
            The evaluation has no detection windows: :func:`evaluate` was run with ``detection=False``."""
        if self.detection_counts.empty:
            raise ValueError("this evaluation has no detection windows: evaluate was run with detection=False; run it "
                             "with detection=True for the detection rates")
        keys = ["model", "method", "window"]
        delays = self.detection_delays
        rows = []
        for key, g in self.detection_counts.groupby(keys, sort=False):
            n = g["windows"]
            healthy = g["state"] == self._healthy
            n_h, x_h = int(n[healthy].sum()), int(n[healthy & g["alarm"]].sum())
            n_dis, x_dis = int(n[healthy & g["disjoint"]].sum()), int(n[healthy & g["disjoint"] & g["alarm"]].sum())
            fault = ~healthy & g["fault_true"]
            n_f, x_f = int(n[fault].sum()), int(n[fault & g["alarm"]].sum())
            d = delays[(delays["model"] == key[0]) & (delays["method"] == key[1]) & (delays["window"] == key[2])]
            hit = d["delay"].notna()
            missed = int(d.loc[~hit, "records"].sum())
            d = np.repeat(d["delay"][hit].to_numpy(), d["records"][hit].to_numpy())
            p0 = 1.0 - (1.0 - self.alphas[(key[0], key[1])]) ** self.nchan.get(key[0], 1)
            lo, hi = stats.binom.ppf([0.005, 0.995], n_dis, p0) if n_dis else (np.nan, np.nan)
            p_two = min(1.0, 2.0 * min(stats.binom.cdf(x_dis, n_dis, p0), stats.binom.sf(x_dis - 1, n_dis, p0))) \
                if n_dis else np.nan
            rows.append({"model": key[0], "method": key[1], "window": key[2],
                         "false_alarm": 100.0 * (x_h / n_h) if n_h else np.nan,
                         "expected_false_alarm": 100.0 * p0, "healthy_windows": n_h,
                         "disjoint_windows": n_dis, "disjoint_alarms": x_dis,
                         "false_alarm_pvalue": p_two, "disjoint_band_low": lo, "disjoint_band_high": hi,
                         "false_alarm_in_band": bool(lo <= x_dis <= hi) if n_dis else False,
                         "missed_fault": 100.0 * (1.0 - x_f / n_f) if n_f else np.nan,
                         "missed_records": missed,
                         "delay_median": float(np.median(d)) if d.size else np.nan,
                         "delay_max": float(np.max(d)) if d.size else np.nan})
        return pd.DataFrame(rows).set_index(keys)

    @property
    def _healthy(self) -> str:
        return str(self.records.attrs.get("healthy", "healthy"))

    def summary(self) -> Summary:
        """Table 4 (percent of the windows of each true failure accepted / labelled as each fault) per window
        length and rule, the rates of every rule and the detection rates, as text (``str``) and HTML tables.

        Without detection windows (``evaluate(..., detection=False)``) it has no detection part."""
        detected = not self.detection_counts.empty
        header = [("Faults", ", ".join(self.faults)), ("Rules", ", ".join(self.rules)),
                  ("Records evaluated", f"{int(self.records['evaluated'].sum())} of {len(self.records)}"),
                  ("Identification windows", int(self.identification_counts["windows"].sum())),
                  *([("Detection windows", int(self.detection_counts["windows"].sum()))] if detected else []),
                  ("Thresholds", self.thresholds),
                  *([("Sequential rule", f"sprt, alpha = {self.sprt['alpha']:g}, "
                      f"{int(self.sequential_counts['records'].sum())} fault records")]
                    if not self.sequential_counts.empty else [])]
        tables = [(f"Identification, {w:g} s windows, rule {rule!r} (percent of the windows of each true failure "
                   f"{'accepted' if rule == 'paper' else 'labelled'} as each fault)", self.table4(w, rule))
                  for w in sorted(self.identification_counts["window"].unique()) for rule in self.rules]
        tables.append(("Rates (percent of windows)", self.rates()))
        if not self.sequential_counts.empty:
            tables.append((f"Sequential identification (MSPRT, alpha = {self.sprt['alpha']:g}; percent of fault "
                           "records, decision time in s)", self.sequential_rates()))
        if detected:
            tables.append(("Detection with the healthy model", self.detection_rates()))
        return Summary("Evaluation", header, tables)

    def _repr_html_(self) -> str:
        return self.summary()._repr_html_()

    def __repr__(self) -> str:
        return (f"Evaluation(windows={self.identification_counts['windows'].sum()} identification, "
                f"{self.detection_counts['windows'].sum()} detection, faults={self.faults}, rules={self.rules})")


def _named_tests(tests: Any, models: list) -> dict:
    """``(model, label) -> ResidualTest`` from a test, or a mapping label -> test or label -> {model -> test}."""
    if tests is None:
        tests = {"whiteness": LjungBox(lags=20, alpha=1e-3, correction="none")}
    elif isinstance(tests, ResidualTest):
        tests = {type(tests).__name__: tests}
    if not isinstance(tests, Mapping) or not tests:
        raise TypeError("tests must be a residual test or a non-empty mapping label -> test (or label -> {model -> "
                        f"test}}), got {type(tests).__name__}")
    out = {}
    for m in models:
        for label, t in tests.items():
            tm = t.get(m) if isinstance(t, Mapping) else t
            if not isinstance(tm, ResidualTest):
                raise TypeError(f"tests[{label!r}] must be a residual test or a mapping model -> test holding one for "
                                f"every model; got {type(tm).__name__} for model {m!r}")
            out[(m, str(label))] = tm
    return out


def evaluate(data: Any, baselines: Baselines, *, models: Sequence[str] = ("var",), tests: Any = None,
             windows: Sequence[Any] = ("5s", "10s", "20s"), turbulence: Any = None, step: Any = "1s",
             settle: float = 10.0, rules: Sequence[str] = ("paper", "likelihood"), detection: bool = True,
             progress: bool = True, states: Any = None, failure_times: Any = None, fs: float | None = None,
             sprt_alpha: float = 0.01, k: Any = None) -> Evaluation:
    r"""Detection and identification over many records, per sliding window (Dutta et al., Table 4).

    Parameters
    ----------
    data : xarray.Dataset, xarray.DataArray or sequence of signals
        Records as accepted by :func:`~tsfdi.fit_baselines`; the records in ``baselines.fit_records`` and records
        that lost control (NaN) are skipped. Either xarray kind may be backed by dask, chunked along ``record``
        (a fleet opened with ``xarray.open_zarr``, :mod:`tsfdi.fleet`): its chunks are then evaluated on the
        current dask scheduler (threads, processes or a ``dask.distributed`` Client) and only their counts come
        back, added in record order, so the result is the one of the same records in memory.
    baselines : Baselines or mapping
        From :func:`~tsfdi.fit_baselines`, or a mapping turbulence level -> :class:`~tsfdi.Baselines`
        (condition-scheduled baselines: each record is tested with the models of its own turbulence level; levels
        not in the mapping are skipped).
    models : sequence of str
        Model names of ``baselines`` (channel names for scalar AR, ``"var"``).
    tests : ResidualTest or mapping, optional
        The residual tests, each applied to every model: one test, or a mapping label -> test, or label ->
        {model -> test} (e.g. the paper's Table 3 alphas per model, :func:`tsfdi.study.paper_tests`). The label
        is the ``method`` of the result tables (a single test is labelled by its class name). Default
        ``{"whiteness": LjungBox(lags=20, alpha=1e-3, correction="none")}`` (the paper's per-channel alpha). Each
        channel is tested at its share of the test's ``alpha`` (``correction``; ``"none"``: at ``alpha``, the type I
        risk per window and channel) and a model is accepted only if every channel accepts (paper's rule for
        vector residuals). A test built with ``threshold="empirical"`` is calibrated for every model (healthy and
        each fault) on that model's own leave-one-record-out fitting residuals
        (:meth:`Baselines.calibrated_tests`; needs ``fit_baselines(..., calibrate=True)``) and gives empirical
        p-values (paper 002, Fig. 2); evaluation records are never used for calibration.
    windows : sequence of int or time span
        Window lengths, as in pandas ``rolling``: an int counts samples, a time span (``"5s"``) is converted with
        the records' sampling frequency. The result tables give them in seconds.
    turbulence : str or sequence, optional
        Turbulence levels to evaluate (default all).
    step : int or time span
        Distance between window starts (the paper's ``"1s"``).
    settle : float
        Identification windows start at least ``settle`` seconds after the failure (post-failure steady state).
    rules : sequence of str
        Decision rules (:data:`tsfdi.windows.RULES`); ``"paper"`` is always included. ``"sprt"`` adds the
        sequential rule (:data:`tsfdi.windows.SEQUENTIAL_RULES`): every fault record is identified once, by the
        multi-hypothesis sequential test of the fault models (:func:`tsfdi.detection.sequential.msprt` on
        their per-sample log-likelihoods, :meth:`tsfdi.windows.ResidualWindows.loglik`)
        on its samples from ``settle`` s after the failure to its end (:attr:`Evaluation.sequential_counts`,
        :meth:`Evaluation.sequential_rates`); it uses neither ``tests`` nor ``windows``.
    detection : bool
        Also test every window of every record with the healthy model (false alarms, missed faults, delays).
        With ``False`` the detection tables of the result are empty, :meth:`Evaluation.detection_rates` raises
        ``ValueError`` and :meth:`Evaluation.summary` has no detection part.
    progress : bool
        Show a tqdm progress bar over records.
    states, failure_times, fs :
        Per-record labels and sampling frequency for a sequence of signals.
    sprt_alpha : float
        Error probability of the sequential rule's bound (in (0, 1)). With held-out residuals in the baselines
        (``fit_baselines(..., calibrate=True)``) the log-likelihood ratios are scale-corrected on them
        (:meth:`Baselines.sprt_scale`: the held-out records of each fault state through every fault model; for
        functionally pooled baselines the smallest of the scales at each operating point of the fitting records),
        so that the bound's error rate holds on records the models were not fitted on; evaluation records are never
        used for it.
    k : str or sequence of str, optional
        The record coordinates holding each record's operating parameters (e.g. ``"speed"`` of a hexacopter fleet),
        for baselines holding functionally pooled models (``fit_baselines(..., k=...)``, :class:`~tsfdi.FPResults`):
        every record is then tested with each FP model at its own logged operating point, ``res.at(k_record)``, the
        parameters :math:`\theta(k) = \sum_j \theta_j G_j(k)` (see Notes). The names must be those of the FP
        models' operating parameters. A calibrated test (``threshold="empirical"``) is calibrated on the FP null:
        the fitting records at their own operating points through the FP model fitted without each
        (:attr:`Baselines.heldout`), and so is the coverage check. Point models are evaluated as without ``k``.
        Records backed by dask carry their operating points with their labels (read from the coordinates on the
        driver).

    Returns
    -------
    Evaluation
        The windows counted per distinct outcome (:attr:`Evaluation.identification_counts`,
        :attr:`~Evaluation.detection_counts`, :attr:`~Evaluation.detection_delays`) and the rates read from them;
        whether the baselines cover each record (:attr:`Evaluation.coverage`, the ``covered`` column of
        :attr:`~Evaluation.records`).

    Warns
    -----
    CoverageWarning
        When the baselines do not cover the healthy part of evaluated records (all of a healthy record, a fault record's
        samples before the failure; from ``settle`` s on, as the fitting segments start): for one record, naming it, the
        model, method, window and the summaries out; for several, one warning with their number and the first of them
        (each one's summaries out in :attr:`Evaluation.coverage`). The check is :func:`tsfdi.coverage.check_coverage`:
        the record law of a detection test calibrated on held-out residuals of at least three healthy records, the part
        holding three of its windows; else the spread of the summaries of the healthy model's fitting records, at least
        three, the part at least as long as the shortest. Their decisions are not covered by the baselines: fit them on
        flights like these. Nothing is checked (nor said, nor spent) otherwise. The check runs where the records are (on
        the dask workers for a chunked fleet); the warnings are said by the caller's process.

    Notes
    -----
    Every record is filtered once through each model and all windows' statistics come from
    prefix sums (:class:`tsfdi.windows.ResidualWindows`). Each record's windows are counted as soon as they are
    tested: the number of distinct outcomes is bounded by the models, tests, window lengths, states and turbulence
    levels (and the distinct detection delays), not by the records, and counts add up exactly in any order.

    With data backed by dask, the driver reads the record coordinates and the first record only; each worker reads
    its chunk, checks it for non-finite values (skipped records, as in memory) and returns the counts of its windows
    (:func:`tsfdi.fleet.map_records`), which the driver adds. The driver then holds the counts and one row per record
    in :attr:`Evaluation.records`, whatever the number of windows.

    A functionally pooled baseline (Kopsaftopoulos and Fassois 2010, 2013; the "global" model of paper 003's
    conclusion) is one model per state over the operating envelope: each parameter is :math:`\theta(k) =
    \sum_{j=1}^{p} \theta_j G_j(k)` on a polynomial basis :math:`G_j` of the operating point
    (:mod:`tsfdi.models.fp`), so with ``k`` one model set serves records at every operating point between the fitting
    ones, each filtered at its logged ``k``.
    """
    if isinstance(baselines, Baselines):
        by_level = None
    elif isinstance(baselines, Mapping) and baselines and all(isinstance(b, Baselines) for b in baselines.values()):
        by_level = {str(lvl): b for lvl, b in baselines.items()}
    else:
        raise TypeError("baselines must be the result of tsfdi.fit_baselines or a mapping turbulence level -> "
                        f"Baselines, got {type(baselines).__name__}")
    first = baselines if by_level is None else next(iter(by_level.values()))
    rec = Records.from_data(data, states=states, failure_times=failure_times, fs=fs, k=k)
    for b in ([first] if by_level is None else by_level.values()):
        if rec.channels != b.channels:
            raise ValueError(f"data has channels {rec.channels} but the baselines were fitted on {b.channels}")
        if abs(rec.fs - b.fs) > 1e-9 * b.fs:
            raise ValueError(f"data is sampled at {rec.fs} Hz but the baselines at {b.fs} Hz")
        if (b.healthy, b.faults) != (first.healthy, first.faults):
            raise ValueError("every Baselines of the mapping must have the same healthy and fault states")
    if not isinstance(models, (str, Iterable)):
        raise TypeError(f"models must be a model name or a sequence of names, got {models!r}")
    models = [models] if isinstance(models, str) else list(models)
    for m in models:
        if not isinstance(m, str) or m not in first.models:
            raise ValueError(f"models must be among the fitted models {list(first.models)}, got {m!r}")
    # models evaluate cannot run: records carry no input; an FP model needs the records' operating points (k=)
    pooled = False
    for b in ([first] if by_level is None else by_level.values()):
        for m in models:
            for s, r in b.models[m].items():
                where = f"baselines.models[{m!r}][{s!r}]"
                if isinstance(r, InputOutputResults) or (isinstance(r, FPResults) and r.model.nb):
                    kind = "FP-ARX" if isinstance(r, FPResults) else type(r).__name__.removesuffix("Results")
                    raise TypeError(f"{where} is {'a' if kind == 'VARX' else 'an'} {kind} (input-output) model: "
                                    "evaluate's records carry no input u; "
                                    "test input-output models record by record with identify_windows(y, models, test, "
                                    "u=...) or Monitor(...).run(y, u=...)")
                if not isinstance(r, FPResults):
                    continue
                pooled = True
                params = list(r.model.k_names)
                if not rec.k_names:
                    raise TypeError(f"{where} is a functionally pooled model (FPResults) over {params}: give k= naming "
                                    "the record coordinate(s) of those operating parameters (each record is tested at "
                                    "its own, res.at(k_record)), or its point model at one operating point, .at(k) (a "
                                    "mapping turbulence level -> Baselines for one point per level)")
                if set(params) != set(rec.k_names):
                    other = next(iter([c for c in rec.k_names if c not in params] or
                                      [c for c in params if c not in rec.k_names]))
                    raise ValueError(f"k names the record coordinates {list(rec.k_names)}, but {where} is a "
                                     f"functionally pooled model over {params}: {other!r} is "
                                     f"{'not one of its operating parameters' if other in rec.k_names else 'not named'}"
                                     "; name exactly its parameters")
    if rec.k_names and not pooled:
        raise ValueError(f"k names operating parameters {list(rec.k_names)}, but the baselines' models {models} are "
                         "point models (no FPResults): fit them with fit_baselines(..., k=...) or leave k out")
    if not isinstance(windows, (list, tuple)):
        windows = [windows]
    wins = {window_samples(w, "windows", rec.fs, minimum=2): None for w in windows}
    if not models or not wins:
        raise ValueError("models and windows must each hold at least one entry")
    detection = boolean(detection, "detection")
    progress = boolean(progress, "progress")
    if turbulence is not None and not isinstance(turbulence, (str, Iterable)):
        raise TypeError(f"turbulence must be a level name or a sequence of names, got {turbulence!r}")
    tests = _named_tests(tests, models)
    methods = list(dict.fromkeys(meth for _, meth in tests))
    empirical = any(t.empirical for t in tests.values())
    if isinstance(rules, str):
        rules = [rules]
    rules = [option(r, "rules", RULES + SEQUENTIAL_RULES) for r in rules]
    sequential = "sprt" in rules
    rules = tuple(dict.fromkeys(["paper"] + [r for r in rules if r in RULES]))
    sprt_alpha = float_like(sprt_alpha, "sprt_alpha", minimum=0.0, maximum=1.0, strict_min=True, strict_max=True)
    if sequential and len(first.faults) < 2:
        raise ValueError(f"rules: 'sprt' chooses among the fault models and needs at least two, the baselines have "
                         f"{list(first.faults)}")
    step_n = window_samples(step, "step", rec.fs)
    settle = float_like(settle, "settle", minimum=0.0)
    healthy, faults = first.healthy, first.faults
    fit = set(first.fit_records) if by_level is None else {r for b in by_level.values() for r in b.fit_records}
    use = rec.valid & ~np.isin(rec.ids, list(fit)) & np.isin(rec.state, (healthy,) + faults)
    if by_level is not None:
        use &= np.isin(rec.turbulence, list(by_level))
    if turbulence is not None:
        use &= np.isin(rec.turbulence, [turbulence] if isinstance(turbulence, str) else list(turbulence))
    if not use.any():
        raise ValueError("no record left to evaluate (all are fitting records, invalid or not selected)")
    longest = max(wins)
    short = rec.ids[[i for i in np.flatnonzero(use)
                     if (rec.values[i].shape[0] if rec.source is None else rec.length) < longest]].tolist()
    if short:
        raise ValueError(f"windows: a {longest}-sample window is longer than the record(s) {short[:5]}"
                         f"{' ...' if len(short) > 5 else ''}; give shorter windows")

    alphas = {(m, meth): t.channel_alpha(len(first.model_channels(m))) for (m, meth), t in tests.items()}
    lag_of = {round(W / rec.fs, 9): p.lags for W in wins for t in tests.values()
              for p in (t.tests if isinstance(t, AnyOf) else (t,)) if isinstance(p, LjungBox)}
    # what every record needs, calibrated once here (an empirical test, per state) and sent once to the workers
    levels = {None: first} if by_level is None else by_level
    plan = {"models": {lvl: {m: (b.state_models(m), b.model_channels(m)) for m in models}
                       for lvl, b in levels.items()},
            "tests": {(lvl, m, meth, W): _state_tests(b, tests[(m, meth)], m, W)
                      for lvl, b in levels.items() for (m, meth) in tests for W in wins},
            "by_level": by_level is not None, "methods": methods, "windows": list(wins), "step": step_n,
            "fs": rec.fs, "settle": settle, "rules": rules, "healthy": healthy, "faults": faults,
            "detection": detection, "sprt": None, "k_names": rec.k_names}
    if sequential:
        plan["sprt"] = {"alpha": sprt_alpha, "scale": {(lvl, m): b.sprt_scale(m) if b.heldout else 1.0
                                                       for lvl, b in levels.items() for m in models}}
    counts = _new_counts()
    if rec.source is None:
        idx = np.flatnonzero(use)
        iterator = idx
        if progress:
            from tqdm.auto import tqdm

            iterator = tqdm(idx, desc="tsfdi evaluate", unit="record")
        for i in iterator:
            _evaluate_record(rec.values[i], rec.state[i], rec.turbulence[i], rec.failure_time[i], plan, counts, i,
                             None if rec.k is None else rec.k[i])
    else:
        # records backed by dask: every chunk runs on the current dask scheduler and comes back as its counts, added
        # in record order: integer counts, so the tables are those of the loop above
        from tsfdi.fleet import map_records, record_chunks

        valid = rec.valid.copy()
        chunks = map_records(_evaluate_chunk, rec.source, dataclasses.replace(rec, source=None), use, plan,
                             progress=progress, desc="tsfdi evaluate")
        for where, (ok, part) in zip(record_chunks(rec.source), chunks):
            valid[where] = ok
            for name, c in part.items():
                counts[name].update(c)
        rec = dataclasses.replace(rec, valid=valid)
        use &= valid
        if not use.any():
            raise ValueError("no record left to evaluate (all are fitting records, invalid or not selected)")
    reasons = np.where(np.isin(rec.ids, list(fit)), "fitting record",
                       np.where(~rec.valid, "lost control / non-finite",
                                np.where(use, "", "not selected")))
    # the coverage checks, in record order (each record's in method and window order); warned of here, on the driver
    rows = sorted(counts["coverage"], key=lambda row: row[0])
    covered: list = [None] * len(rec.ids)            # a record: False when a check says so, True when one ran
    said: dict = {}
    for i, m, meth, w, ok, _, _, out in rows:
        if ok is not None:
            covered[i] = bool(ok) and covered[i] is not False
        if out:
            said.setdefault(i, []).append(f"model {m}, method {meth}, {w:g} s windows: {out}")
    warn_records_not_covered({rec.ids[i]: "; ".join(parts) for i, parts in said.items()}, "evaluate",
                             judged=sum(c is not None for c in covered), see="Evaluation.coverage")
    cover = pd.DataFrame([(rec.ids[row[0]], *row[1:]) for row in rows],
                         columns=["record", "model", "method", "window", "covered", "pvalue", "records", "outside"])
    cover = cover.astype({"covered": "boolean", "window": np.float64, "pvalue": np.float64, "records": np.int64})
    covered = pd.array(covered, dtype="boolean")
    recs = pd.DataFrame({"record": rec.ids, "state": rec.state, "turbulence": rec.turbulence,
                         "evaluated": use, "skipped": reasons, "covered": covered})
    recs.attrs["healthy"] = healthy
    keys = ["turbulence", "model", "method", "window", "state"]
    ident = _count_table(counts["identification"], [*keys, *(f"acc_{f}" for f in faults),
                                                   *(f"label_{r}" for r in rules), "windows"])
    det = _count_table(counts["detection"], [*keys, "fault_true", "pre", "alarm", "disjoint", "windows"])
    delays = _count_table(counts["delays"], [*keys, "delay", "records"])
    seq = _count_table(counts["sequential"], ["turbulence", "model", "state", "label", "time", "records"]) \
        if sequential else pd.DataFrame()
    cal_rows = []
    for lvl, b in ([("", first)] if by_level is None else by_level.items()):
        for (m, meth), t in tests.items():
            chans = [b.channels[c] for c in b.model_channels(m)]
            for W in wins:
                cal = b.calibrated_tests(m, t, W) if t.empirical else {}
                for state in (healthy,) + faults:
                    res = b.models[m][state]
                    # (an FP model's null distribution: its point model's at any operating point, the same order,
                    # degrees of freedom and, with pooled weights, reference variance)
                    res = res.at(res.model.k[0]) if isinstance(res, FPResults) else res
                    # the test's own statistic, and that of each part of a combined test
                    units = [("", t, cal.get(state))]
                    if isinstance(t, AnyOf):
                        units += [(f"{i}: {type(p).__name__}", p, cal[state].tests[i] if state in cal else None)
                                  for i, p in enumerate(t.tests)]
                    for part, u, cu in units:
                        dist = u.null_threshold(len(chans), W - int(res.lags), **u.reference(res))
                        for c, ch in enumerate(chans):
                            row = {"turbulence": lvl, "model": m, "method": meth, "part": part,
                                   "window": round(W / rec.fs, 9), "state": state, "channel": ch,
                                   "distribution": float(dist[c])}
                            if cu is not None and hasattr(cu, "threshold_"):
                                row["empirical"] = float(cu.threshold_[c])
                                row["calibration_size"] = int(cu.thresholds_[c].nobs_)
                                row["estimate"] = cu.thresholds_[c].method_
                            cal_rows.append(row)
    return Evaluation(identification_counts=ident, detection_counts=det, detection_delays=delays, faults=faults,
                      rules=rules, alphas=alphas, lags=lag_of, records=recs,
                      nchan={m: len(first.model_channels(m)) for m in models},
                      thresholds="empirical" if empirical else "theoretical", calibration=pd.DataFrame(cal_rows),
                      sequential_counts=seq, coverage=cover,
                      sprt={} if not sequential else {"alpha": sprt_alpha, "scale": {
                          ("" if lvl is None else lvl, m): v for (lvl, m), v in plan["sprt"]["scale"].items()}})


def _state_tests(base: Baselines, test: ResidualTest, m: str, W: int) -> tuple:
    """The detection test and the fault models' tests of model ``m`` on ``W``-sample windows (calibrated per state
    on the baselines' held-out residuals for an empirical test)."""
    if not test.empirical:
        return test, test
    cal = base.calibrated_tests(m, test, W)
    return cal[base.healthy], {f: cal[f] for f in base.faults}


def _new_counts() -> dict:
    """Empty counts of :func:`evaluate`: identification and detection windows and delays per distinct outcome."""
    return {"identification": Counter(), "detection": Counter(), "delays": Counter(), "sequential": Counter(),
            "coverage": Counter()}


def _count(counter: Counter, key: tuple, flags: np.ndarray, codes: Sequence = (), names: Sequence = ()) -> None:
    """Add windows to ``counter``, one entry per distinct outcome: ``key``, then the window's ``flags`` (windows x
    k, bool) and the ``names`` its ``codes`` (arrays of one int per window) point to."""
    k, r = flags.shape[1], len(names)
    if k + len(codes) * max(r, 1).bit_length() > 62:     # too many columns for one integer per row
        rows, n = np.unique(np.column_stack([flags, *codes]), axis=0, return_counts=True)
        for row, c in zip(rows.tolist(), n.tolist()):
            counter[(*key, *(bool(v) for v in row[:k]), *(names[v] for v in row[k:]))] += c
        return
    # each distinct row as one mixed-radix integer (first column most significant), so that one 1-D unique gives
    # the rows in lexicographic order, as a unique of the rows would
    code = np.zeros(flags.shape[0], dtype=np.int64)
    for col in flags.T:
        code = code * 2 + col
    for col in codes:
        code = code * r + col
    size = 2 ** k * r ** len(codes)
    if size <= 4 * code.size + 64:                      # few possible rows: counted without sorting the windows
        n = np.bincount(code, minlength=size)
        values = np.flatnonzero(n)
        n = n[values]
    else:
        values, n = np.unique(code, return_counts=True)
    for v, c in zip(values.tolist(), n.tolist()):
        picks = []
        for _ in codes:
            v, i = divmod(v, r)
            picks.append(names[i])
        bits = [bool((v >> (k - 1 - i)) & 1) for i in range(k)]
        counter[(*key, *bits, *reversed(picks))] += c


_COUNT_TYPES = {"window": np.float64, "delay": np.float64, "time": np.float64, "fault_true": bool, "pre": bool, "alarm": bool,
                "disjoint": bool}


def _count_table(counter: Counter, columns: list) -> pd.DataFrame:
    """The counts as a table: one row per key, in order of first appearance, the count last (int64). Columns have
    the same dtypes whether there are rows or not (labels: pandas' string dtype)."""
    types = {c: bool if c.startswith("acc_") else _COUNT_TYPES.get(c, str) for c in columns[:-1]}
    return pd.DataFrame([(*key, n) for key, n in counter.items()], columns=columns).astype(
        {**types, columns[-1]: np.int64})


def _evaluate_record(x_all: np.ndarray, state: str, turb: str, ft: float, plan: dict, counts: dict,
                     position: int, k: np.ndarray | None = None) -> None:
    """Add the windows of one record (``evaluate``), every length, model and test, to ``counts``
    (:func:`_new_counts`); its coverage checks under its ``position`` in the records. ``k``: the record's
    operating point (``plan["k_names"]``), where its functionally pooled models are evaluated."""
    healthy, faults, fs, step_n = plan["healthy"], plan["faults"], plan["fs"], plan["step"]
    detection, rules = plan["detection"], plan["rules"]
    level = turb if plan["by_level"] else None
    is_fault = bool(state != healthy)
    names = [*faults, "ambiguous", "none"]
    # the record's healthy part from settle s on, as the fitting segments: what the coverage check judges
    part = slice(int(np.ceil(round(plan["settle"] * fs, 9))), int(np.floor(round(ft * fs, 9))) if is_fault else None)
    point = None if k is None else dict(zip(plan["k_names"], k.tolist()))
    for m, (fitted, chans) in plan["models"][level].items():
        per_state = fitted if point is None else {
            s: r.at([point[n] for n in r.model.k_names]) if isinstance(r, FPResults) else r for s, r in fitted.items()}
        sig = as_signal(x_all[:, chans], "signal", allow_constant=True)
        _check_coverage(sig.values[part], per_state[healthy], plan, (level, m), position, counts["coverage"])
        # each record is filtered once through every (member) model; the windows of every length and
        # test are slices of these residuals
        rw_h = ResidualWindows({healthy: per_state[healthy]})
        rw_f = ResidualWindows({f: per_state[f] for f in faults})
        if detection:
            rw_h.fit(sig)
        if is_fault:
            rw_f.fit(sig)
            if plan["sprt"] is not None:
                # one sequential decision per record and model, from the first sample settle s after the failure
                start = max(int(np.ceil(round((ft + plan["settle"]) * fs, 9))), max(rw_f.orders.values()))
                if start >= rw_f.nobs_:
                    raise ValueError(f"a fault record ends before settle = {plan['settle']:g} s after its failure: "
                                     "nothing left for the sequential rule; give a smaller settle")
                seq = msprt(rw_f.loglik(common=start), alpha=plan["sprt"]["alpha"],
                            scale=plan["sprt"]["scale"][(level, m)])
                label = faults[seq.label] if seq.label >= 0 else "undecided"
                counts["sequential"][(turb, m, state, label, None if seq.label < 0 else
                                      round(seq.decision_time / fs, 9))] += 1
        for meth in plan["methods"]:
            for W in plan["windows"]:
                key = (turb, m, meth, round(W / fs, 9), state)
                test_h, test_f = plan["tests"][(level, m, meth, W)]
                if detection:
                    wh = rw_h.statistics(test_h, window=W, step=step_n, loglik=False)
                    st, en = wh.starts / fs, (wh.starts + W) / fs
                    alarm, pre = wh.reject[:, 0], (en <= ft) | (not is_fault)
                    _count(counts["detection"], key,
                           np.column_stack([is_fault & (st >= ft), pre, alarm, wh.starts % W == 0]))
                    if not pre.all():                    # a fault record with windows ending after the failure
                        hit = np.flatnonzero(alarm & ~pre)
                        counts["delays"][(*key, float(en[hit[0]] - ft) if hit.size else None)] += 1
                if not is_fault:
                    continue
                ws = rw_f.statistics(test_f, window=W, step=step_n)
                keep = ws.starts / fs >= ft + plan["settle"]
                if not keep.any():
                    continue
                acc = ws.accepted[keep]
                codes = [decide(acc, rule, loglik=ws.loglik[keep], pvalue=ws.min_pvalue[keep]) for rule in rules]
                codes = [np.where(c >= 0, c, np.where(c == AMBIGUOUS, len(faults), len(faults) + 1)) for c in codes]
                _count(counts["identification"], key, acc, codes, names)


def _check_coverage(x: np.ndarray, res: Any, plan: dict, key: tuple, position: int, out: Counter) -> None:
    """The coverage checks of one record's healthy part ``x`` by the healthy model ``res`` of ``key`` (level,
    model), one per method and window, into ``out`` (a row each): the record law of each calibrated detection test,
    else the summary check (on the held-out residuals of ``res``'s model: for a functionally pooled model's point
    results ``.at(k)``, the FP model's, summarised once for every ``k``), made once for every test without a record
    law."""
    if x.shape[0] < 2:
        return
    level, m = key
    done: dict = {}
    for meth in plan["methods"]:
        for W in plan["windows"]:
            test = plan["tests"][(level, m, meth, W)][0]
            memo = id(test) if test.calibrated else None
            if memo not in done:
                try:
                    done[memo] = check_coverage(test, res, x)
                except ValueError as err:
                    done[memo] = f"coverage not checked: {err}"
            cov = done[memo]
            if cov is None:
                continue
            if isinstance(cov, str):
                out[(position, m, meth, round(W / plan["fs"], 9), None, np.nan, 0, cov)] += 1
            else:
                out[(position, m, meth, round(W / plan["fs"], 9), cov.covered, cov.pvalue, cov.records,
                     "" if cov.covered else cov.warning_message())] += 1


def _evaluate_chunk(chunk: Any, where: slice, labels: Records, use: np.ndarray, plan: dict) -> tuple:
    """One chunk of records backed by dask, on a worker (``evaluate``): which of its records are valid, and the
    counts of the windows of those evaluated (and their coverage checks)."""
    rec = labels.read(where, chunk)
    counts = _new_counts()
    for j in np.flatnonzero(use[where] & rec.valid):
        _evaluate_record(rec.values[j], rec.state[j], rec.turbulence[j], rec.failure_time[j], plan, counts,
                         where.start + j, None if rec.k is None else rec.k[j])
    return rec.valid, counts


# ------------------------------------------------------------------------------------ per-record scoring
#: Per-record outcomes of :func:`score_records` (Keipour et al., paper 001, Table I).
OUTCOMES = ("TP", "FP", "FN", "TN")


# ----------------------------------------------------------------------------------------------- input checks
def _is_missing(v: Any) -> bool:
    """``None``, ``pandas.NA``, ``NaT`` or a float NaN."""
    if v is None or v is pd.NA or v is pd.NaT:
        return True
    return isinstance(v, (float, np.floating)) and bool(np.isnan(v))


def _scoring_times(value: Any, name: str) -> np.ndarray:
    """One number per record as a float64 array (NaN allowed, inf not) or raise naming ``name``."""
    refuse_masked(value, name)
    if isinstance(value, pd.DataFrame):
        raise TypeError(f"{name} must be 1-D (one value per record), got a DataFrame")
    if isinstance(value, (pd.Series, pd.Index)):
        if pd.api.types.is_bool_dtype(value.dtype):
            raise TypeError(f"{name} must hold numbers (times), got booleans")
        if pd.api.types.is_numeric_dtype(value.dtype):
            arr = value.to_numpy(dtype=np.float64, na_value=np.nan)
        else:
            arr = value.to_numpy()  # datetime64 / timedelta64 kept (and refused below), else object
    else:
        try:
            arr = np.asarray(value)
        except (ValueError, TypeError) as exc:  # ragged nested sequences
            raise ValueError(f"{name} must be 1-D (one value per record): {exc}") from None
    kind = arr.dtype.kind
    if kind == "b":
        raise TypeError(f"{name} must hold numbers (times), got booleans")
    if kind in "mM":
        raise TypeError(f"{name} must hold numbers in one unit (e.g. seconds since the record start), got "
                        f"{arr.dtype} values; convert them first (first_alarm(..., time=...) returns seconds)")
    if kind in "iuf":
        arr = arr.astype(np.float64)
    elif kind == "O":
        out = np.empty(arr.shape, dtype=np.float64)
        for i, v in enumerate(arr.flat):
            if _is_missing(v):
                out.flat[i] = np.nan
            elif isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)):
                out.flat[i] = float(v)
            else:
                raise TypeError(f"{name} must hold numbers or NaN, got {v!r} ({type(v).__name__}) at position {i}")
        arr = out
    else:
        raise TypeError(f"{name} must hold numbers, got dtype {arr.dtype}")
    if arr.ndim != 1:
        raise ValueError(f"{name} must be 1-D (one value per record), got shape {arr.shape}")
    bad = np.flatnonzero(np.isinf(arr))
    if bad.size:
        raise ValueError(f"{name} must be finite or NaN, got {arr[bad[0]]} at position {int(bad[0])}")
    return arr


def _scoring_index(n: int, records: Any, pandas_inputs: dict) -> pd.Index:
    """The record index: ``records``, else the index shared by the pandas inputs, else ``0..n-1``."""
    idx, src = None, None
    for name, obj in pandas_inputs.items():
        if isinstance(obj, pd.Series):
            if idx is None:
                idx, src = obj.index, name
            elif not obj.index.equals(idx):
                raise ValueError(f"{name}'s index does not match {src}'s index; align them (e.g. "
                                 f"{name}.reindex({src}.index)) or pass plain arrays")
    if records is None:
        return idx if idx is not None else pd.RangeIndex(n, name="record")
    if isinstance(records, (str, bytes)) or np.ndim(records) != 1:
        raise ValueError(f"records must be 1-D (one label per record), got {records!r}")
    if isinstance(records, pd.Index):
        out = records
    elif isinstance(records, pd.Series):
        out = pd.Index(records.to_numpy(), name=records.name)
    else:
        out = pd.Index(list(records), name="record")
    if len(out) != n:
        raise ValueError(f"records has {len(out)} labels but onset has {n} values (one per record)")
    return out


# ------------------------------------------------------------------------------------------------ first alarm
def _alarm_flags(values: np.ndarray) -> np.ndarray:
    """Boolean alarm array from ``values`` (bool, 0/1 numbers); NaN / missing values raise."""
    kind = values.dtype.kind
    if kind == "b":
        return values
    if kind in "iuf":
        nan = np.flatnonzero(np.isnan(values).ravel()) if kind == "f" else np.empty(0, int)
        if nan.size:
            raise ValueError(f"alarm must be boolean, got NaN at flat position {int(nan[0])}; decide what a "
                             f"missing sample means (e.g. alarm.fillna(False)) before scoring")
        other = np.flatnonzero(~np.isin(values.ravel(), (0, 1)))
        if other.size:
            raise ValueError(f"alarm must be boolean (or 0 / 1), got {values.ravel()[other[0]]!r} at flat position "
                             f"{int(other[0])}")
        return values != 0
    if kind == "O":
        out = np.empty(values.shape, dtype=bool)
        for i, v in enumerate(values.flat):
            if _is_missing(v):
                raise ValueError(f"alarm must be boolean, got a missing value ({v!r}) at flat position {i}; decide "
                                 f"what a missing sample means (e.g. alarm.fillna(False)) before scoring")
            if isinstance(v, (bool, np.bool_)) or (isinstance(v, numbers.Real) and v in (0, 1)):
                out.flat[i] = bool(v)
            else:
                raise TypeError(f"alarm must be boolean, got {v!r} ({type(v).__name__}) at flat position {i}")
        return out
    raise TypeError(f"alarm must be boolean, got dtype {values.dtype}")


def first_alarm(alarm: Any, time: Any = None, *, origin: Any = None) -> float:
    """Time (or position) of the first alarm of one record.

    Parameters
    ----------
    alarm : array_like of bool, shape (nobs,) or (nobs, k), pandas.Series or pandas.DataFrame
        Per-sample or per-window alarm flags, for instance ``OnlineDetection.alarm`` (one column per pair) or
        ``MonitorResult.windows["fault"]``. A 2-D alarm raises the record's alarm at the first row where any
        column alarms. ``0`` / ``1`` numbers are accepted; NaN or missing values are an error (decide first what
        a missing sample means, e.g. ``alarm.fillna(False)``).
    time : array_like, optional
        Time of every row of ``alarm`` (same length): numbers, datetimes or timedeltas. Default: the index of a
        pandas ``alarm``, else the row position.
    origin : number, datetime or timedelta, optional
        Subtracted from the alarm's time. Default: the first entry of the time axis for datetimes (so the result
        is the time since the first sample), zero otherwise.

    Returns
    -------
    float
        ``time[k] - origin`` for the first alarming row ``k``: in seconds for a datetime / timedelta time axis,
        in the unit of ``time`` for numbers, the row position ``k`` when there is no time axis. NaN if no row
        alarms (including an empty record).

    Raises
    ------
    TypeError
        ``alarm`` is not boolean-like, ``time`` holds neither numbers, datetimes nor timedeltas (for example a
        string index; pass ``time``), or ``origin`` does not match ``time``'s kind.
    ValueError
        ``alarm`` has NaN / missing values, values other than 0 / 1 or more than 2 dimensions; ``time`` has a
        different length or missing values.

    See Also
    --------
    score_records : Outcome and delay per record from onsets and first alarms.

    Notes
    -----
    The first alarm is what Keipour et al. (paper 001, Table I) score per flight; pass it with the onset (in the
    same unit, e.g. seconds since the record start) to :func:`score_records`.

    Examples
    --------
    >>> import numpy as np, pandas as pd
    >>> first_alarm([False, False, True, True])
    2.0
    >>> first_alarm(np.array([[0, 0], [0, 0], [0, 1]]), time=[0.0, 0.05, 0.1])
    0.1
    >>> idx = pd.date_range("2018-07-30 16:39", periods=4, freq="500ms")
    >>> first_alarm(pd.Series([False, False, False, True], index=idx))
    1.5
    >>> first_alarm([False, False])
    nan
    """
    index = None
    if isinstance(alarm, (pd.Series, pd.DataFrame)):
        index = alarm.index
        values = alarm.to_numpy()
    elif isinstance(alarm, (str, bytes)):
        raise TypeError(f"alarm must be boolean, got a {type(alarm).__name__}")
    else:
        refuse_masked(alarm, "alarm")
        try:
            values = np.asarray(alarm)
        except (ValueError, TypeError) as exc:
            raise ValueError(f"alarm must be a 1-D or 2-D array: {exc}") from None
    if values.ndim not in (1, 2):
        raise ValueError(f"alarm must be 1-D (nobs,) or 2-D (nobs, k), got shape {values.shape}")
    flags = _alarm_flags(values)
    if flags.ndim == 2:
        flags = flags.any(axis=1)
    n = flags.shape[0]

    axis = None
    if time is not None:
        if isinstance(time, (str, bytes)) or np.ndim(time) != 1:
            raise ValueError(f"time must be 1-D (one entry per row of alarm), got {time!r}")
        refuse_masked(time, "time")
        axis, tname = pd.Index(time), "time"
        if len(axis) != n:
            raise ValueError(f"time has {len(axis)} entries but alarm has {n} rows")
    elif index is not None:
        axis, tname = index, "alarm's index (pass time= to override)"
    if axis is not None:
        if isinstance(axis, (pd.DatetimeIndex, pd.TimedeltaIndex)) or pd.api.types.is_numeric_dtype(axis.dtype):
            if pd.api.types.is_bool_dtype(axis.dtype):
                raise TypeError(f"{tname} must hold numbers, datetimes or timedeltas, got booleans")
            if axis.hasnans:
                raise ValueError(f"{tname} has missing values (NaN / NaT)")
        else:
            raise TypeError(f"{tname} must hold numbers, datetimes or timedeltas, got dtype {axis.dtype}")

    hit = np.flatnonzero(flags)
    if not hit.size:
        return float("nan")
    k = int(hit[0])
    if axis is None:
        return float(k) - (0.0 if origin is None else float_like(origin, "origin"))
    if isinstance(axis, (pd.DatetimeIndex, pd.TimedeltaIndex)) and isinstance(origin, numbers.Number):
        raise TypeError(f"origin must be a {'datetime' if isinstance(axis, pd.DatetimeIndex) else 'timedelta'} "
                        f"for {tname} ({axis.dtype}), got the number {origin!r}")
    if isinstance(axis, pd.DatetimeIndex):
        try:
            ref = axis[0] if origin is None else pd.Timestamp(origin)
            return float((axis[k] - ref).total_seconds())
        except (TypeError, ValueError) as exc:
            raise TypeError(f"origin must be a datetime comparable with {tname} ({axis.dtype}): {exc}") from None
    if isinstance(axis, pd.TimedeltaIndex):
        try:
            ref = pd.Timedelta(0) if origin is None else pd.Timedelta(origin)
        except (TypeError, ValueError) as exc:
            raise TypeError(f"origin must be a timedelta for a timedelta time axis: {exc}") from None
        return float((axis[k] - ref).total_seconds())
    return float(axis[k]) - (0.0 if origin is None else float_like(origin, "origin"))


# --------------------------------------------------------------------------------------------------- scoring
def score_records(onset: Any, first_alarm: Any, *, records: Any = None, kind: Any = None) -> pd.DataFrame:
    """Outcome (TP / FP / FN / TN) and detection delay of every record from its fault onset and first alarm.

    The per-flight definitions of Keipour et al. (paper 001, Table I):

    ========================  ===================================  =======  =======================
    record                    first alarm                          outcome  delay
    ========================  ===================================  =======  =======================
    fault (onset finite)      before the onset                     FP       NaN
    fault                     at or after the onset                TP       first_alarm - onset
    fault                     none (NaN)                           FN       NaN
    fault-free (onset NaN)    any                                  FP       NaN
    fault-free                none (NaN)                           TN       NaN
    ========================  ===================================  =======  =======================

    Parameters
    ----------
    onset : array_like of float, shape (n_records,)
        Fault onset time of every record; NaN (or ``None``) for a fault-free record. Numpy arrays, lists and
        pandas Series are accepted.
    first_alarm : array_like of float, shape (n_records,)
        Time of the detector's first alarm on every record (see :func:`first_alarm`); NaN (or ``None``) for no
        alarm. Same unit and same time origin as ``onset`` -- seconds since the record start in the examples,
        but any consistent unit works (the delays are then in that unit).
    records : array_like, optional
        Record labels (the returned index). Default: the index of ``onset`` / ``first_alarm`` when they are
        pandas Series (both Series must then have equal indexes), else ``0..n_records-1`` named ``"record"``.
    kind : array_like, optional
        A label per record (e.g. the fault type), stored as column ``kind`` for grouping in
        :func:`detection_metrics` (``by="kind"``).

    Returns
    -------
    pandas.DataFrame
        One row per record, in input order, with columns ``onset`` and ``first_alarm`` (float, NaN: no fault /
        no alarm), ``outcome`` (one of :data:`OUTCOMES`), ``delay`` (float, ``first_alarm - onset`` for a TP,
        NaN otherwise) and, if given, ``kind``.

    Raises
    ------
    TypeError
        ``onset`` or ``first_alarm`` holds non-numbers (strings, booleans, datetimes: convert to a number of
        seconds first).
    ValueError
        ``onset``, ``first_alarm``, ``records`` or ``kind`` is not 1-D, their lengths differ, a value is
        infinite, or pandas inputs have different indexes.

    See Also
    --------
    first_alarm : First alarm time of one record from a boolean alarm array.
    detection_metrics : TP / FP / FN / TN counts, precision, recall, accuracy and delays.

    References
    ----------
    A. Keipour, M. Mousaei, S. Scherer, "Automatic Real-time Anomaly Detection for Autonomous Aerial Vehicles",
    ICRA 2019 (paper 001), Table I.

    Examples
    --------
    >>> s = score_records([10.0, 10.0, 10.0, np.nan, np.nan], [12.5, 4.0, np.nan, 30.0, np.nan])
    >>> s["outcome"].tolist()
    ['TP', 'FP', 'FN', 'FP', 'TN']
    >>> s["delay"].tolist()
    [2.5, nan, nan, nan, nan]
    """
    on = _scoring_times(onset, "onset")
    fa = _scoring_times(first_alarm, "first_alarm")
    if fa.size != on.size:
        raise ValueError(f"first_alarm has {fa.size} values but onset has {on.size} (one per record)")
    n = on.size
    if kind is not None:
        if isinstance(kind, (str, bytes)) or np.ndim(kind) != 1:
            raise ValueError(f"kind must be 1-D (one label per record), got {kind!r}")
        if len(kind) != n:
            raise ValueError(f"kind has {len(kind)} labels but onset has {n} values (one per record)")
    index = _scoring_index(n, records, {"onset": onset, "first_alarm": first_alarm, "kind": kind})

    fault, alarmed = ~np.isnan(on), ~np.isnan(fa)
    tp = fault & alarmed & (fa >= on)
    fp = alarmed & ~tp  # an alarm on a fault-free record or before the onset
    fn = fault & ~alarmed
    outcome = np.select([tp, fp, fn], ["TP", "FP", "FN"], "TN")
    delay = np.where(tp, fa - on, np.nan)
    out = pd.DataFrame({"onset": on, "first_alarm": fa, "outcome": outcome, "delay": delay}, index=index)
    if kind is not None:
        out["kind"] = kind.to_numpy() if isinstance(kind, (pd.Series, pd.Index)) else list(kind)
    return out


def _detection_row(outcome: np.ndarray, delay: np.ndarray, max_delay: float | None) -> dict:
    """Counts, rates and delays of one group of records (paper 001, Table I)."""
    n = outcome.size
    tp, fp, fn, tn = (int(np.count_nonzero(outcome == k)) for k in OUTCOMES)
    d = delay[outcome == "TP"]
    nan = float("nan")
    row = dict(records=n, TP=tp, FP=fp, FN=fn, TN=tn,
               precision=tp / (tp + fp) if tp + fp else nan, recall=tp / (tp + fn) if tp + fn else nan,
               accuracy=(tp + tn) / n if n else nan,
               mean_delay=float(d.mean()) if d.size else nan, longest_delay=float(d.max()) if d.size else nan)
    if max_delay is not None:
        dw = d[d <= max_delay]
        row.update(TP_within=int(dw.size), mean_delay_within=float(dw.mean()) if dw.size else nan)
    return row


def detection_metrics(scores: pd.DataFrame, *, by: Any = None, max_delay: float | None = None) -> pd.DataFrame:
    """Counts, precision, recall, accuracy and detection delays of scored records, per group and overall.

    Parameters
    ----------
    scores : pandas.DataFrame
        As returned by :func:`score_records`: at least the columns ``outcome`` (one of :data:`OUTCOMES`) and
        ``delay`` (finite for every TP).
    by : str or array_like, optional
        Groups: the name of a column of ``scores`` (e.g. ``"kind"``) or one label per record (positional; a
        pandas Series must have ``scores``' index). One row per group -- in category order for a categorical,
        else in sorted order (first appearance if the labels do not sort) -- then the ``"all"`` row. Default:
        only the ``"all"`` row.
    max_delay : float, optional
        If given (>= 0, in the unit of the delays), also count the true positives detected within it
        (``delay <= max_delay``) and their mean delay: a late alarm still counts as a TP by the definitions of
        paper 001, but may be of little use.

    Returns
    -------
    pandas.DataFrame
        One row per group plus ``"all"`` (index named after ``by``'s column or Series, else ``"group"``), with
        columns

        - ``records``, ``TP``, ``FP``, ``FN``, ``TN`` (int): number of records and of each outcome;
        - ``precision`` = TP / (TP + FP), ``recall`` = TP / (TP + FN), ``accuracy`` = (TP + TN) / records
          (float, NaN where the denominator is zero);
        - ``mean_delay``, ``longest_delay`` (float): mean and largest detection delay of the true positives
          (NaN without true positives);
        - with ``max_delay``: ``TP_within`` (int) and ``mean_delay_within`` (float), the same restricted to
          ``delay <= max_delay``.

        Values are raw numbers (no rounding); ``attrs["max_delay"]`` holds ``max_delay``.

    Raises
    ------
    TypeError
        ``scores`` is not a DataFrame, ``delay`` holds non-numbers or ``max_delay`` is not a number.
    ValueError
        ``scores`` lacks ``outcome`` / ``delay``, has an unknown outcome or a TP without a finite, non-negative
        delay; ``by`` names no column, has the wrong length, missing labels or a label ``"all"``; ``max_delay``
        is negative or not finite.

    See Also
    --------
    score_records : The per-record outcomes and delays.

    References
    ----------
    A. Keipour, M. Mousaei, S. Scherer, "Automatic Real-time Anomaly Detection for Autonomous Aerial Vehicles",
    ICRA 2019 (paper 001), Table I (precision, recall, accuracy and mean detection time over 22 flights).

    Examples
    --------
    >>> s = score_records([10.0, 10.0, 10.0, np.nan, np.nan], [12.5, 4.0, np.nan, 30.0, np.nan],
    ...                   kind=["engine", "engine", "rudder", "none", "none"])
    >>> m = detection_metrics(s, by="kind", max_delay=2.0)
    >>> m[["records", "TP", "FP", "FN", "TN", "TP_within"]]  # doctest: +NORMALIZE_WHITESPACE
            records  TP  FP  FN  TN  TP_within
    kind
    engine        2   1   1   0   0          0
    none          2   0   1   0   1          0
    rudder        1   0   0   1   0          0
    all           5   1   2   1   1          0
    >>> m.loc["all", ["precision", "recall", "accuracy", "mean_delay"]].round(3).tolist()
    [0.333, 0.5, 0.4, 2.5]
    """
    if not isinstance(scores, pd.DataFrame):
        raise TypeError(f"scores must be a pandas.DataFrame as returned by score_records, got "
                        f"{type(scores).__name__}")
    missing = [c for c in ("outcome", "delay") if c not in scores.columns]
    if missing:
        raise ValueError(f"scores lacks the column(s) {missing} (use score_records)")
    outcome = scores["outcome"].to_numpy(dtype=object)
    unknown = sorted({repr(v) for v in outcome if not (isinstance(v, str) and v in OUTCOMES)})
    if unknown:
        raise ValueError(f"scores['outcome'] must hold only {', '.join(OUTCOMES)}, got {', '.join(unknown)}")
    outcome = outcome.astype(str)
    delay = _scoring_times(scores["delay"], "scores['delay']")
    d_tp = delay[outcome == "TP"]
    if np.isnan(d_tp).any() or (d_tp < 0).any():
        raise ValueError("scores['delay'] must be finite and >= 0 for every TP record")
    if max_delay is not None:
        max_delay = float_like(max_delay, "max_delay", minimum=0.0)

    n = len(scores)
    groups: list = []
    name = "group"
    masks: list = []
    if by is not None:
        if isinstance(by, (str, bytes)) or np.ndim(by) == 0:
            try:
                present = by in scores.columns
            except TypeError:
                present = False
            if not present:
                raise ValueError(f"by must be a column of scores or one label per record; no column {by!r} in "
                                 f"{list(scores.columns)}")
            labels, name = scores[by], by
        else:
            if np.ndim(by) != 1:
                raise ValueError(f"by must be 1-D (one label per record), got shape {np.shape(by)}")
            if len(by) != n:
                raise ValueError(f"by has {len(by)} labels but scores has {n} records")
            if isinstance(by, pd.Series) and not by.index.equals(scores.index):
                raise ValueError("by's index does not match scores' index; align it (by.reindex(scores.index)) or "
                                 "pass a plain array")
            labels = by if isinstance(by, (pd.Series, pd.Index)) else pd.Series(list(by), dtype=object)
            name = getattr(by, "name", None) or "group"
        labels = pd.Series(labels).reset_index(drop=True)
        miss = np.flatnonzero(labels.isna().to_numpy())
        if miss.size:
            raise ValueError(f"by has missing labels ({miss.size} records, first at position {int(miss[0])})")
        if isinstance(labels.dtype, pd.CategoricalDtype):
            seen = set(labels)
            groups = [c for c in labels.cat.categories if c in seen]
        else:
            groups = list(pd.unique(labels.to_numpy(dtype=object)))
            try:
                groups = sorted(groups)
            except TypeError:
                pass
        if any(isinstance(g, str) and g == "all" for g in groups):
            raise ValueError('by has a group labelled "all", which is the name of the overall row; rename it')
        lab = labels.to_numpy(dtype=object)
        masks = [lab == g for g in groups]

    rows = [_detection_row(outcome[m], delay[m], max_delay) for m in masks]
    rows.append(_detection_row(outcome, delay, max_delay))
    out = pd.DataFrame(rows, index=pd.Index([*groups, "all"], name=name))
    ints = ["records", *OUTCOMES] + (["TP_within"] if max_delay is not None else [])
    out = out.astype({c: np.int64 for c in ints})
    out.attrs["max_delay"] = max_delay
    return out


# ------------------------------------------------------------------------------- paper 004: MT / UD / FA
__all__ += ["detection_time", "false_alarm_percentage", "sensor_validation_metrics"]


def _alarm_and_labels(alarm: Any, labels: Any, time: Any) -> tuple[np.ndarray, np.ndarray, Any]:
    """Flags of one record's alarm and ground truth (1-D, same length) and its time axis (``time``, else the
    alarm's pandas index, else None)."""
    out = []
    for value, name in ((alarm, "alarm"), (labels, "labels")):
        if isinstance(value, (str, bytes)):
            raise TypeError(f"{name} must be boolean, got a {type(value).__name__}")
        refuse_masked(value, name)
        arr = value.to_numpy() if isinstance(value, (pd.Series, pd.DataFrame)) else np.asarray(
            value.values if hasattr(value, "dims") else value)
        if arr.ndim != 1:
            raise ValueError(f"{name} must be 1-D (one flag per sample), got shape {arr.shape}")
        try:
            out.append(_alarm_flags(arr))
        except (TypeError, ValueError) as exc:
            raise type(exc)(str(exc).replace("alarm", name, 1)) from None
    flags, truth = out
    if flags.shape != truth.shape:
        raise ValueError(f"alarm and labels must have the same length, got {flags.size} and {truth.size}")
    if time is None and isinstance(alarm, pd.Series):
        time = alarm.index
    return flags, truth, time


def detection_time(alarm: Any, labels: Any, time: Any = None) -> float:
    """Time from a fault's onset to its first alarm (paper 004's detection time), NaN if it is not detected.

    Parameters
    ----------
    alarm : array_like of bool, shape (nobs,), or pandas.Series
        Per-sample alarm flags of one record (e.g. ``Decision.details["alarm"]`` of
        :class:`~tsfdi.detection.moving.MovingSquaredError`); 0 / 1 numbers are accepted, NaN is an error.
    labels : array_like of bool, shape (nobs,)
        Ground truth: True on the faulty samples (e.g. from :func:`tsfdi.datasets.inject_fault`).
    time : array_like, optional
        Time of every sample (numbers, datetimes or timedeltas). Default: the index of a pandas ``alarm``, else the
        sample position (the result is then in samples).

    Returns
    -------
    float
        ``time[first alarm on a faulty sample] - time[first faulty sample]``, in seconds for datetimes / timedeltas;
        NaN when no faulty sample alarms (an undetected fault) or the record has no faulty sample. Alarms before the
        onset are false alarms (:func:`false_alarm_percentage`), alarms after the fault has ended do not detect it.

    Examples
    --------
    >>> detection_time([0, 1, 0, 0, 1, 1], [0, 0, 0, 1, 1, 1], time=[0.0, 0.02, 0.04, 0.06, 0.08, 0.1])
    0.02
    >>> detection_time([0, 0, 0, 0], [0, 0, 1, 1])
    nan
    """
    flags, truth, time = _alarm_and_labels(alarm, labels, time)
    if not (flags & truth).any():
        return float("nan")
    # rounded to 12 significant digits: the difference of two time stamps without its rounding noise
    return float(f"{first_alarm(flags & truth, time) - first_alarm(truth, time):.12g}")


def false_alarm_percentage(alarm: Any, labels: Any) -> float:
    """Paper 004's false-alarm figure FA: percentage of the time before the fault onset spent in alarm.

    Parameters
    ----------
    alarm, labels : array_like of bool, shape (nobs,)
        Per-sample alarm flags and ground truth of one record, as for :func:`detection_time`.

    Returns
    -------
    float
        ``100 * (alarming samples before the first faulty sample) / (samples before it)``; the whole record when no
        sample is faulty; NaN when the record starts faulty. Every sample counts for the same time (a uniformly
        sampled record).

    Examples
    --------
    >>> false_alarm_percentage([0, 1, 0, 0, 1, 1], [0, 0, 0, 0, 1, 1])
    25.0
    """
    flags, truth, _ = _alarm_and_labels(alarm, labels, None)
    onset = int(np.argmax(truth)) if truth.any() else truth.size
    return float(100.0 * flags[:onset].mean()) if onset else float("nan")


def sensor_validation_metrics(alarms: Sequence, labels: Sequence, *, times: Sequence | None = None) -> pd.Series:
    """Paper 004's figures of a sensor-validation scheme over several records: MT, UD and FA (Tables 2-3).

    Parameters
    ----------
    alarms : sequence of array_like of bool
        Per-sample alarm flags, one array (or pandas Series) per record -- typically one record per injected fault.
    labels : sequence of array_like of bool
        Ground truth of each record (True on the faulty samples); a record without faulty samples counts for FA
        only.
    times : sequence of array_like, optional
        Time axis of each record (default: each alarm's pandas index, else sample positions).

    Returns
    -------
    pandas.Series
        ``MT``: mean detection time of the detected faults (:func:`detection_time`; NaN if none is detected);
        ``UD``: number of undetected faults; ``FA``: percentage of the fault-free time before the onsets spent in
        alarm, pooled over the records (total alarming samples over total samples before the onsets); ``faults``:
        number of records with a fault; ``longest``: the largest detection time.

    Raises
    ------
    TypeError, ValueError
        A record that is not a 1-D boolean array, alarm and labels of different lengths, sequences of different
        lengths.

    References
    ----------
    I. Samy, I. Postlethwaite, D. Gu, "Neural network based sensor validation scheme demonstrated on an unmanned
    air vehicle (UAV) model" (paper 004), section VII and Tables 2-3.

    Examples
    --------
    >>> m = sensor_validation_metrics([[0, 0, 1, 1], [1, 0, 0, 0]], [[0, 0, 1, 1], [0, 0, 1, 1]])
    >>> m.to_dict()
    {'MT': 0.0, 'UD': 1, 'FA': 25.0, 'faults': 2, 'longest': 0.0}
    """
    for value, name in ((alarms, "alarms"), (labels, "labels")):
        if isinstance(value, (str, bytes)) or not isinstance(value, (Sequence, np.ndarray)) or (
                isinstance(value, np.ndarray) and value.ndim != 2):
            raise TypeError(f"{name} must be a sequence of per-record arrays (a list), got {type(value).__name__}")
    if len(alarms) != len(labels):
        raise ValueError(f"alarms and labels must hold the same number of records, got {len(alarms)} and "
                         f"{len(labels)}")
    if times is not None and len(times) != len(alarms):
        raise ValueError(f"times must hold one time axis per record, got {len(times)} for {len(alarms)} records")
    delays, undetected, faults, in_alarm, before = [], 0, 0, 0, 0
    for i, (a, lab) in enumerate(zip(alarms, labels)):
        try:
            flags, truth, _ = _alarm_and_labels(a, lab, None)
            d = detection_time(a, lab, None if times is None else times[i])
        except (TypeError, ValueError) as exc:
            raise type(exc)(f"record {i}: {exc}") from None
        onset = int(np.argmax(truth)) if truth.any() else truth.size
        in_alarm += int(flags[:onset].sum())
        before += onset
        if truth.any():
            faults += 1
            if np.isnan(d):
                undetected += 1
            else:
                delays.append(d)
    return pd.Series({"MT": float(np.mean(delays)) if delays else float("nan"), "UD": undetected,
                      "FA": 100.0 * in_alarm / before if before else float("nan"), "faults": faults,
                      "longest": float(np.max(delays)) if delays else float("nan")}, dtype=object)

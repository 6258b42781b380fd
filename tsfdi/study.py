"""The paper-003 study on a hexacopter dataset and its report (tables as text / markdown, figures).

Outside the core API: it drives :func:`tsfdi.fit_baselines` and :func:`tsfdi.evaluate` with the paper's protocol
(Dutta et al., Tables 2-4) and writes what ``tsfdi demo`` and ``docs/scripts/study.py`` print.
"""

from __future__ import annotations

import secrets
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._validation import int_like, option
from tsfdi.baselines import Baselines, fit_baselines
from tsfdi.datasets.hexacopter import hexacopter_signals
from tsfdi.detection.variance import FTest
from tsfdi.detection.whiteness import LjungBox
from tsfdi.evaluation import Evaluation, evaluate
from tsfdi.exceptions import UnstableModelWarning

__all__ = ["DEVELOPMENT_NOTE", "PAPER_ALPHA", "UNITS", "baselines_table", "demo_report", "evaluation_seed",
           "hexacopter_study", "markdown_figures", "markdown_table", "paper_tests", "write_figures", "write_report"]


#: Type I risk of each method and model family in the paper's Table 3 (scalar AR on roll / pitch / yaw, VAR).
PAPER_ALPHA = {("variance", "roll"): 1e-6, ("variance", "pitch"): 1e-12, ("variance", "yaw"): 1e-12,
               ("variance", "var"): 1e-8, ("whiteness", "roll"): 1e-3, ("whiteness", "pitch"): 1e-3,
               ("whiteness", "yaw"): 1e-3, ("whiteness", "var"): 1e-3}


def paper_tests(models: Sequence[str], methods: Sequence[str] = ("whiteness", "variance"), *, lags: int = 20,
                threshold: str = "theoretical") -> dict:
    """The paper's tests for :func:`tsfdi.evaluate`: method -> {model -> test} at the alphas of Table 3.

    ``"whiteness"``: :class:`~tsfdi.LjungBox` with ``lags`` lags; ``"variance"``: :class:`~tsfdi.FTest`; each
    channel at the alpha (``correction="none"``, the paper's per-channel use, like for like). A model
    named like a yaw channel (``"yaw"``, ``"yaw_rate"``) takes the yaw alpha; unknown models 1e-3 (whiteness) or
    1e-8 (variance). ``threshold="empirical"`` builds tests to be calibrated on held-out residuals.
    """
    out = {}
    for meth in methods:
        meth = option(meth, "methods", ("whiteness", "variance"))
        per = {}
        for m in models:
            key = "yaw" if m.startswith("yaw") else m
            a = PAPER_ALPHA.get((meth, key), 1e-3 if meth == "whiteness" else 1e-8)
            per[m] = (LjungBox(lags=lags, alpha=a, correction="none", threshold=threshold) if meth == "whiteness"
                      else FTest(alpha=a, correction="none", threshold=threshold))
        out[meth] = per
    return out


def evaluation_seed() -> int:
    """A fresh seed for evaluation records that no choice has seen: 31 random bits drawn from the operating
    system (:func:`secrets.randbits`) at every call.

    ``docs/scripts/study.py`` makes every choice on the shipped development records (``data/hexacopter.nc``,
    seed 2024), then simulates the evaluation records of the same design from this seed and prints it in its
    report. The seed is never a constant and is stored nowhere but in that report, so no choice can have been
    made on the records it generates.

    Returns
    -------
    int
        In ``[0, 2**31)``, a valid ``seed`` of :func:`tsfdi.datasets.make_hexacopter_dataset`.
    """
    return secrets.randbits(31)


def hexacopter_study(data: Any = None, *, records_per_case: int | None = None, models: Sequence[str] | None = None,
                     tests: Any = None, windows: Sequence[Any] = ("5s", "10s", "20s"),
                     rules: Sequence[str] = ("paper", "likelihood", "pvalue"), settle: float = 10.0,
                     fit_records: int = 10, pool: str = "level", order: Any = 20, max_lags: int = 20,
                     var_max_lags: int = 20, progress: bool = True) -> tuple[dict, Evaluation]:
    """The whole study of paper 003 on a hexacopter dataset: pooled baselines, then evaluation.

    The first ``fit_records`` valid records of each state and turbulence level fit the baselines (whole
    post-settle part of each record, pooled without junctions; see :func:`fit_baselines`); every other valid
    record is evaluated. With ``pool="level"`` each level has its own models and every record is tested with
    the models of its level (condition-scheduled baselines); with ``pool="all"`` one set of models is fitted on
    the fitting records of all levels.

    Parameters
    ----------
    data : xarray.Dataset, optional
        Default the shipped :func:`tsfdi.datasets.load_hexacopter`.
    records_per_case : int, optional
        Use only the first ``records_per_case`` records of each (state, turbulence) cell (more than
        ``fit_records``: those fit, the others are evaluated); default all.
    models, tests, windows, rules, settle, progress :
        As in :func:`~tsfdi.evaluate`; ``models`` defaults to every channel and ``"var"``, ``tests`` to
        :func:`paper_tests` (Ljung-Box with 20 lags and the F test at the alphas of Table 3). When a test has
        ``threshold="empirical"`` the baselines are fitted with ``calibrate=True`` (leave-one-record-out
        residuals of the fitting records).
    fit_records : int
        Fitting records per state and turbulence level (reduced to ``records_per_case - 1`` when fewer).
    pool : {"level", "all"}
        Models per turbulence level, or one set pooled across levels.
    order, max_lags, var_max_lags :
        Order choice and search bounds of :func:`fit_baselines`. Default order 20, chosen on the shipped
        development records against BIC and RSS/SSS (docs/results.md, "Order choice on the pooled records").

    Returns
    -------
    baselines : dict
        Turbulence level -> :class:`Baselines` (with ``pool="all"`` every level maps to the same object).
    evaluation : Evaluation
    """
    if data is None:
        from tsfdi.datasets import load_hexacopter

        data = load_hexacopter()
    import xarray as xr

    if not isinstance(data, xr.Dataset):
        raise TypeError(f"data must be a hexacopter xarray.Dataset, got {type(data).__name__}")
    fit_records = int_like(fit_records, "fit_records", minimum=1)
    pool = option(pool, "pool", ("level", "all"))
    if records_per_case is not None:
        n = int_like(records_per_case, "records_per_case", minimum=2)
        fit_records = min(fit_records, n - 1)
        st, tb = data["state"].values, data["turbulence"].values
        keep, count = [], {}
        for i in range(data.sizes["record"]):
            key = (st[i], tb[i])
            count[key] = count.get(key, 0) + 1
            if count[key] <= n:
                keep.append(i)
        data = data.isel(record=keep)
    levels = list(dict.fromkeys(np.asarray(data["turbulence"].values).astype(str).tolist()))
    sig = hexacopter_signals(data)
    names = list(sig["channel"].values) + ["var"] if models is None else list(models)
    tests = paper_tests(names) if tests is None else tests
    empirical = any(getattr(t, "empirical", False) for t in _flat(tests))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnstableModelWarning)
        kw = dict(duration=None, settle=settle, models=names, fit_records=fit_records, order=order,
                  max_lags=max_lags, var_max_lags=var_max_lags, calibrate=empirical)
        if pool == "level":
            bases = {lvl: fit_baselines(sig, fit_turbulence=lvl, **kw) for lvl in levels}
        else:
            one = fit_baselines(sig, **kw)
            bases = dict.fromkeys(levels, one)
    ev = evaluate(sig, bases, models=names, tests=tests, windows=windows, rules=rules, settle=settle,
                  progress=progress)
    return bases, ev


def _flat(tests: Any) -> list:
    """The test objects of a test, a mapping label -> test or label -> {model -> test}."""
    if isinstance(tests, Mapping):
        return [t for v in tests.values() for t in _flat(v)]
    return [tests]


def baselines_table(baselines: Any) -> pd.DataFrame:
    """Table 2 analogue of one :class:`Baselines` or of a mapping turbulence level -> Baselines (one
    ``turbulence`` column added)."""
    if isinstance(baselines, Baselines):
        return baselines.table
    if not isinstance(baselines, Mapping) or not all(isinstance(b, Baselines) for b in baselines.values()):
        raise TypeError("baselines must be a Baselines or a mapping turbulence level -> Baselines")
    frames, seen = [], {}
    for lvl, b in baselines.items():       # one Baselines shared by several levels (pooled) is listed once
        seen.setdefault(id(b), (b, []))[1].append(str(lvl))
    for b, lvls in seen.values():
        t = b.table
        t.insert(0, "turbulence", lvls[0] if len(lvls) == 1 else "+".join(lvls))
        frames.append(t)
    return pd.concat(frames, ignore_index=True)


def markdown_table(df) -> str:
    """A pipe table of a DataFrame (index levels as leading columns), without the optional tabulate package."""
    flat = df.reset_index()

    def cell(v):
        if isinstance(v, float):
            return f"{v:.6g}"
        return str(v)

    head = "| " + " | ".join(str(c) for c in flat.columns) + " |"
    rule = "|" + "|".join("---" for _ in flat.columns) + "|"
    rows = ["| " + " | ".join(cell(v) for v in row) + " |" for row in flat.itertuples(index=False)]
    return "\n".join([head, rule] + rows)


#: Units of the report's columns, written into their headers (counts of windows / records / parameters and the
#: dimensionless statistics keep their names)
UNITS = {"nobs": "nobs (samples)", "spp": "spp (samples per parameter)", "rss_sss": "rss_sss (%)",
         "window": "window (s)", "false_alarm": "false_alarm (%)", "expected_false_alarm": "expected_false_alarm (%)",
         "missed_fault": "missed_fault (%)", "delay_median": "delay_median (s)", "delay_max": "delay_max (s)"}


def _units(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` with the columns and index levels of :data:`UNITS` renamed to carry their unit."""
    df = df.rename(columns=UNITS)
    return df.rename_axis(index=[UNITS.get(n, n) for n in df.index.names])


#: First paragraph of :func:`demo_report`: which records its figures are on
DEVELOPMENT_NOTE = ("Evaluated records: those of the data set that fit no model. On the shipped data/hexacopter.nc "
                    "these are development records: the study's settings (model orders, fitting records, alphas, "
                    "decision rules) were chosen on them, so the figures below are not an evaluation. "
                    "docs/results.md gives the evaluation, on records simulated from a fresh seed after every "
                    "choice was frozen.\n")


def demo_report(bases: dict, ev: Evaluation, *, markdown: bool = False) -> str:
    """Text of the demo: which records it is on (:data:`DEVELOPMENT_NOTE`), Table 2 analogue, Table 4 analogues
    (paper and improved rules), rates, detection.

    Every table gives its units: in the column headers (``(%)``, ``(s)``, ``(samples)``) or, for the
    percentages of Table 4, in the caption and the headers."""
    def show(df: pd.DataFrame) -> str:
        df = _units(df)
        return markdown_table(df) if markdown else df.to_string()

    out = [DEVELOPMENT_NOTE]
    t2 = baselines_table(bases)[["turbulence", "state", "model", "signals", "order", "parameters", "records", "nobs",
                                 "spp", "rss_sss", "q_insample", "stable"]]
    out.append("## Table 2 analogue: baseline models\n\nPooled fitting records; order in lags (samples); parameters "
               "and records are counts; nobs in samples; spp: samples per parameter; rss_sss in percent; "
               "q_insample: median in-sample Ljung-Box Q (20 lags, 20 s blocks), dimensionless.\n")
    out.append(show(t2.set_index(["turbulence", "state", "model", "signals"]).round(
        {"spp": 2, "rss_sss": 5, "q_insample": 2})))
    for w in sorted(ev.identification_counts["window"].unique()):
        for rule in ev.rules:
            what = "accepted" if rule == "paper" else "labelled"
            out.append(f"\n## Table 4 analogue, {w:g} s windows, rule '{rule}'\n\nPercent of the windows of each true "
                       f"failure (columns) {what} as {' / '.join(ev.faults)} (%).\n")
            out.append(show(ev.table4(w, rule).rename(columns=lambda c: f"{c} (%)")))
    out.append("\n## Decisions of the paper's rule (percent of windows)\n\nPercent of the windows of each true failure "
               "identified as each fault, ambiguous (several models accept) or none (no model accepts); every row "
               "adds up to 100 %.\n")
    out.append(show(ev.confusion("paper").rename(columns=lambda c: f"{c} (%)").round(2)))
    r = ev.rates()["correct"].unstack("true").unstack("rule")
    r.columns = [f"{t} ({rule}, %)" for t, rule in r.columns]
    out.append("\n## Correct unique identification (percent of windows)\n")
    out.append(show(r.round(2)))
    out.append("\n## Detection with the healthy model\n\nRates in percent of windows, delays in s from the failure to "
               "the end of the first flagged window; counts of windows and records.\n")
    out.append(show(ev.detection_rates().round(3)))
    return "\n".join(out) + "\n"


def markdown_figures(paths: Sequence[Any], start: Any) -> str:
    """Markdown that embeds figures written by :func:`write_figures`, one ``![caption](path)`` per figure with
    its path relative to the folder ``start`` (where the markdown file is), under a ``## Figures`` heading."""
    import os
    from pathlib import Path

    lines = ["## Figures", ""]
    for p in map(Path, paths):
        rel = Path(os.path.relpath(p, start)).as_posix()
        lines += [f"![{_caption(p.stem)}]({rel})", ""]
    return "\n".join(lines)


def _caption(stem: str) -> str:
    """Caption of a figure of :func:`write_figures` from its file name."""
    parts = stem.split("_")
    if stem.startswith("order_selection_var"):
        return "Order selection of the healthy VAR: BIC and RSS/SSS against the order"
    if stem.startswith("order_selection_ar_"):
        return f"Order selection of the healthy AR model of {'_'.join(parts[3:-1])}: BIC and RSS/SSS against the order"
    if stem == "acf_var_healthy":
        return "Auto- and cross-correlations of the healthy VAR's residuals on a healthy test record"
    if stem == "variance_evolution":
        return "Rolling variance (10 s) of one test record per failure against the steady-state thresholds"
    if stem.startswith("identification_bars_"):
        return f"Ljung-Box statistic of each fault VAR on a {parts[-1]} test record against the critical limit"
    if stem.startswith("confusion_"):
        model, method, w, rule = parts[1], parts[2], parts[3], "_".join(parts[4:])
        return (f"Decisions in percent of the windows of each true failure ({model}, {method}, {w.rstrip('s')} s "
                f"windows, rule {rule})")
    return stem.replace("_", " ")


def write_report(bases: dict, ev: Evaluation, data: Any, out: Any, *, figures: bool = True) -> list:
    """Write ``report.md`` (:func:`demo_report` as markdown; with ``figures`` it embeds them, paths relative to
    ``out``), ``identification_counts.csv.gz`` (the identification windows counted per distinct outcome) and,
    with ``figures``, :func:`write_figures` under ``out/figures``. Returns the paths written, the report first."""
    from pathlib import Path

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "report.md", out / "identification_counts.csv.gz"]
    figs = write_figures(bases, ev, data, out / "figures") if figures else []
    text = demo_report(bases, ev, markdown=True)
    if figs:
        text += "\n" + markdown_figures(figs, out)
    paths[0].write_text(text)
    ev.identification_counts.to_csv(paths[1], index=False)
    return paths + figs


def write_figures(bases: dict, ev: Evaluation, data: Any, out: Any) -> list:
    """Figures of the study under ``out`` (Path): order selection, residual ACF, variance evolution, identification
    bars, confusion heatmaps. Returns the written paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from tsfdi.identification import identify
    from tsfdi.plotting.acf import plot_acf
    from tsfdi.plotting.monitoring import plot_confusion, plot_variance_evolution

    out.mkdir(parents=True, exist_ok=True)
    written = []

    def save(fig, name):
        p = out / name
        fig.savefig(p, dpi=90)
        plt.close(fig)
        written.append(p)

    level = "severe" if "severe" in bases else next(iter(bases))
    b = bases[level]
    if ("var", b.healthy) in b.selections:
        save(b.selections[("var", b.healthy)].plot(), "order_selection_var_healthy.png")
    ch = b.channels[1] if len(b.channels) > 1 else b.channels[0]
    if (ch, b.healthy) in b.selections:
        save(b.selections[(ch, b.healthy)].plot(), f"order_selection_ar_{ch}_healthy.png")
    sig = hexacopter_signals(data)
    st, tb = sig["state"].values, sig["turbulence"].values
    valid = ~sig["lost_control"].values if "lost_control" in sig.coords else np.ones(sig.sizes["record"], bool)
    fit = set(b.fit_records)
    test_rec = {s: next((i for i in range(sig.sizes["record"]) if st[i] == s and tb[i] == level and valid[i]
                         and sig["record"].values[i] not in fit), None) for s in (b.healthy,) + b.faults}
    def record(i, start=0, stop=None):
        """Record ``i`` as a DataFrame (time index in s, one column per named channel), samples start:stop."""
        return sig.isel(record=i, time=slice(start, stop)).to_pandas()

    if "var" in b.models and test_rec[b.healthy] is not None:
        x = record(test_rec[b.healthy], 2000, 4000)
        save(plot_acf(b.models["var"][b.healthy].residuals(x), lags=40), "acf_var_healthy.png")
    recs = [record(i) for s, i in test_rec.items() if i is not None and s != b.healthy]
    if recs:
        save(plot_variance_evolution(recs, fs=b.fs, thresholds=b.steady_thresholds, failure_time=10.0,
                                     labels=[s for s, i in test_rec.items() if i is not None and s != b.healthy],
                                     channels=list(b.channels)), "variance_evolution.png")
    if "var" in b.models:
        mon = b.monitor("var", window="20s")
        for f in b.faults:
            i = test_rec.get(f)
            if i is None:
                continue
            x = record(i, 3000, 5000)
            ident = identify(x, {g: b.models["var"][g] for g in b.faults}, mon.test)
            save(ident.plot(), f"identification_bars_var_{f}.png")
    confs = {rule: ev.confusion(rule).sort_index() for rule in ev.rules[:2]}
    for key in confs["paper"].index.droplevel("true").unique():
        model, method, w = key
        if model != "var":
            continue
        for rule, conf in confs.items():
            c = conf.loc[key]
            save(plot_confusion(c, title=f"{model}, {method}, {w:g} s, rule {rule}"),
                 f"confusion_{model}_{method}_{int(w)}s_{rule}.png")
    return written

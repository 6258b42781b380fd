"""Plots of decisions, identifications and GLRT thresholds. matplotlib is imported inside each function."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plot_decision", "plot_identification", "plot_threshold"]


def _axes(ax: Any, figsize=(6, 4)):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize)
    else:
        fig = ax.figure
    return fig, ax


def plot_decision(decision: Any, ax: Any = None, *, log: bool | None = None, title: str | None = None) -> Any:
    """Bars of the statistic per channel against the critical limit (Dutta et al., Figs. 10-11).

    Parameters
    ----------
    decision : Decision
    ax : matplotlib Axes, optional
    log : bool, optional
        Logarithmic y axis (default: when the statistics span more than two decades).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax)
    x = np.arange(len(decision.channels))
    colors = ["tab:red" if r else "tab:blue" for r in decision.channel_reject]
    ax.bar(x, decision.statistic, color=colors, width=0.6)
    for i, t in enumerate(decision.threshold):
        ax.hlines(t, i - 0.4, i + 0.4, colors="k", linestyles="--")
    ax.set_xticks(x, decision.channels)
    ax.set_ylabel("test statistic")
    vals = np.r_[decision.statistic, decision.threshold]
    vals = vals[np.isfinite(vals) & (vals > 0)]
    if log is None:
        log = vals.size > 0 and vals.max() / vals.min() > 100
    if log:
        ax.set_yscale("log")
    verdict = "reject H0" if decision.reject else "accept H0"
    ax.set_title(title or f"{decision.test}: {verdict} (alpha = {decision.alpha:g}; dashed: critical limit)")
    return fig


def plot_identification(identification: Any, ax: Any = None, *, log: bool | None = None,
                        title: str | None = None) -> Any:
    """Grouped bars per model and channel with each channel's critical limit (Dutta et al., Figs. 12-13).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(7, 4))
    names = list(identification.decisions)
    decs = [identification.decisions[n] for n in names]
    chans = list(decs[0].channels)
    k = len(chans)
    width = 0.8 / k
    cmap = __import__("matplotlib").colormaps["tab10"]
    for c in range(k):
        xs = np.arange(len(names)) + (c - (k - 1) / 2) * width
        stats = [d.statistic[c] if c < len(d.statistic) else np.nan for d in decs]
        ax.bar(xs, stats, width=width * 0.95, color=cmap(c % 10), label=str(chans[c]))
        for x, d in zip(xs, decs):
            if c < len(d.threshold):
                ax.hlines(d.threshold[c], x - width / 2, x + width / 2, colors="k", linestyles="--")
    ax.set_xticks(np.arange(len(names)),
                  [f"{n}\n({'accepted' if not identification.decisions[n].reject else 'rejected'})" for n in names])
    ax.set_ylabel("test statistic")
    vals = np.concatenate([np.r_[d.statistic, d.threshold] for d in decs])
    vals = vals[np.isfinite(vals) & (vals > 0)]
    if log is None:
        log = vals.size > 0 and vals.max() / vals.min() > 100
    if log:
        ax.set_yscale("log")
    ax.legend(title="channel", fontsize="small")
    ax.set_title(title or f"{identification.test}: {identification.status}"
                 + (f" -> {identification.label}" if identification.label else "") + " (dashed: critical limit)")
    return fig


def plot_threshold(threshold: Any, ax: Any = None, *, title: str | None = None) -> Any:
    """Probability plot of the healthy statistic with the chosen threshold (Hansen et al., Fig. 2).

    The y axis is the exceedance probability :math:`1 - F(g)` on a log scale, so the tail that sets the
    threshold is visible; the dashed lines mark :math:`P_F` and the threshold :math:`\\gamma`. A fitted
    generalised Pareto tail is drawn when it was used.

    Parameters
    ----------
    threshold : EmpiricalThreshold (calibrated) or GLRT calibrated with one
    """
    thr = getattr(threshold, "threshold", threshold)
    if not hasattr(thr, "sample_"):
        raise ValueError("threshold must be a calibrated EmpiricalThreshold (or a GLRT calibrated with one)")
    fig, ax = _axes(ax)
    g = thr.sample_
    n = g.size
    exceed = 1.0 - (np.arange(1, n + 1) - 0.5) / n
    idx = np.unique(np.linspace(0, n - 1, min(n, 5000)).astype(int))
    ax.semilogy(g[idx], exceed[idx], ".", ms=3, label="healthy statistic (empirical)")
    if thr.gpd_ is not None:
        grid = np.linspace(thr.gpd_["location"], max(thr.threshold_, g[-1]) * 1.05, 200)
        ax.semilogy(grid, thr.exceedance(grid), "-", label="generalised Pareto tail")
    ax.axvline(thr.threshold_, color="k", ls="--", label=f"threshold = {thr.threshold_:.4g}")
    ax.axhline(thr.false_alarm, color="grey", ls=":", label=f"P_F = {thr.false_alarm:g}")
    ax.set_xlabel("test statistic")
    ax.set_ylabel("exceedance probability 1 - F")
    ax.legend(fontsize="small")
    ax.set_title(title or f"Healthy statistic and threshold ({thr.method_}, n = {n})")
    return fig

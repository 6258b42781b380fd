"""Plots of sequential decisions: the statistic path with its bounds, OC and ASN curves. matplotlib is imported
inside each function."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plot_oc_asn", "plot_sequential_decision", "plot_sequential_identification"]


def _axes(ax: Any, figsize=(7, 4)):
    import matplotlib.pyplot as plt

    if ax is None:
        return plt.subplots(figsize=figsize)
    return ax.figure, ax


def _x(result: Any, n: int) -> tuple[np.ndarray, str, float]:
    """Sample axis (seconds when the result carries a time) and the factor from samples to it."""
    if result.time is not None and len(result.time) == n and n > 1:
        dt = float(result.time[1] - result.time[0])
        return np.asarray(result.time), "time since the first tested sample (s)", dt
    return np.arange(1, n + 1), "samples", 1.0


def plot_sequential_decision(decision: Any, ax: Any = None, *, title: str | None = None) -> Any:
    """Path of the cumulative log-likelihood ratio of an SPRT with Wald's bounds and the decision time.

    Parameters
    ----------
    decision : SequentialDecision
    ax : matplotlib Axes, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(7, 4))
    s = decision.statistic
    x, label, dt = _x(decision, s.size)
    ax.plot(x, s, color="tab:blue", lw=1, label="cumulative LLR S")
    lo, hi = decision.bounds
    ax.axhline(hi, color="tab:red", ls="--", label=f"A = {hi:.3g} (reject H0)")
    ax.axhline(lo, color="tab:green", ls="--", label=f"B = {lo:.3g} (accept H0)")
    if decision.decided:
        ax.axvline(x[decision.decision_time - 1], color="k", ls=":", label="decision")
    ax.set_xlabel(label)
    ax.set_ylabel("log-likelihood ratio")
    ax.legend(fontsize="small")
    verdict = ("reject H0" if decision.reject else "accept H0") if decision.decided else "undecided"
    when = f" after {decision.decision_time} samples" if decision.decided else ""
    ax.set_title(title or f"{decision.test}: {verdict}{when} (alpha = {decision.alpha:g}, beta = {decision.beta:g})")
    return fig


def plot_sequential_identification(identification: Any, ax: Any = None, *, title: str | None = None) -> Any:
    """Dominance path of every candidate model of an MSPRT with the bound and the decision time.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(7, 4))
    d = identification.statistic
    x, label, _ = _x(identification, d.shape[0])
    for j, name in enumerate(identification.models):
        ax.plot(x, d[:, j], lw=1, label=str(name))
    ax.axhline(identification.bound, color="k", ls="--", label=f"bound ln((M-1)/alpha) = {identification.bound:.3g}")
    if identification.decided:
        ax.axvline(x[identification.decision_time - 1], color="k", ls=":")
    ax.set_xlabel(label)
    ax.set_ylabel("dominance S_j - max_k S_k")
    lo = min(float(np.min(d)), -identification.bound) if d.size else -identification.bound
    ax.set_ylim(max(lo, -4 * identification.bound), None)
    ax.legend(fontsize="small", title="model")
    ax.set_title(title or f"MSPRT: {identification.status}"
                 + (f" -> {identification.name} after {identification.decision_time} samples"
                    if identification.decided else "") + f" (alpha = {identification.alpha:g})")
    return fig


def plot_oc_asn(test: Any, theta: Any, *, nchan: int = 1, monte_carlo: Any = None, axes: Any = None) -> Any:
    """Operating characteristic and average sample number of an SPRT: Wald's approximations as curves, Monte Carlo
    points (:meth:`SPRT.monte_carlo`) when given.

    Parameters
    ----------
    test : SPRT
    theta : array_like
        True variance ratios or mean shifts for the curves.
    nchan : int
        Residual channels.
    monte_carlo : DataFrame, optional
        The output of ``test.monte_carlo(...)``: its ``accept`` and ``mean_n`` are drawn as points.
    axes : sequence of two matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    if axes is None:
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    else:
        fig = axes[0].figure
    th = np.sort(np.asarray(theta, dtype=np.float64).ravel())
    ax_oc, ax_asn = axes
    ax_oc.plot(th, test.oc(th, nchan=nchan), label="Wald's approximation")
    ax_asn.plot(th, test.asn(th, nchan=nchan), label="Wald's approximation")
    if monte_carlo is not None:
        ax_oc.plot(monte_carlo.index, monte_carlo["accept"], "o", label="Monte Carlo")
        ax_asn.plot(monte_carlo.index, monte_carlo["mean_n"], "o", label="Monte Carlo")
    what = "true variance ratio" if test.alternative == "variance" else "true mean shift (std)"
    ax_oc.set_xlabel(what)
    ax_asn.set_xlabel(what)
    ax_oc.set_ylabel("P(accept H0)")
    ax_asn.set_ylabel("E[N] (samples)")
    ax_oc.set_title("Operating characteristic")
    ax_asn.set_title("Average sample number")
    for a in axes:
        a.legend(fontsize="small")
    return fig

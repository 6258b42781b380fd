"""Functionally pooled models: the likelihood curve of an operating-point estimate and the parameter surfaces."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plot_k_estimate", "plot_fp_surface"]


def plot_k_estimate(estimate: Any, ax: Any = None) -> Any:
    """The profile log-likelihood of each operating parameter, with ``k_hat``, its interval (from the curvature)
    and the level ``-chi2_1(1 - alpha) / 2`` below the maximum whose crossings bound the likelihood-ratio interval.

    Parameters
    ----------
    estimate : OperatingPointEstimate
        From :meth:`tsfdi.models.FPResults.estimate_k`.
    ax : matplotlib Axes or a sequence of one Axes per operating parameter, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from scipy import stats

    d = len(estimate.names)
    level = -0.5 * stats.chi2.ppf(1 - estimate.alpha, 1)
    if ax is None:
        fig, axes = plt.subplots(1, d, figsize=(5.5 * d, 3.6), squeeze=False)
        axes = list(axes[0])
    else:
        axes = list(np.ravel(np.asarray(ax, dtype=object)))
        if len(axes) != d:
            raise ValueError(f"ax must hold one Axes per operating parameter ({d}), got {len(axes)}")
        fig = axes[0].figure
    for a, name, grid, ll, k, (lo, hi) in zip(axes, estimate.names, estimate.grid, estimate.loglik,
                                              estimate.k_hat, estimate.conf_int):
        a.plot(grid, ll - estimate.llf, color="C0", lw=1.2, label="log-likelihood - max")
        a.axvline(k, color="C3", lw=1.2, label=f"k_hat = {k:.4g}")
        if np.isfinite(lo) and np.isfinite(hi):
            a.axvspan(max(lo, grid[0]), min(hi, grid[-1]), color="C3", alpha=0.15,
                      label=f"{1 - estimate.alpha:.0%} interval [{lo:.4g}, {hi:.4g}]")
        a.axhline(level, color="0.5", ls=":", lw=1,
                  label=f"profile-likelihood {1 - estimate.alpha:.0%} level ({level:.2f})")
        finite = ll[np.isfinite(ll)] - estimate.llf
        if finite.size:
            a.set_ylim(max(finite.min(), -50.0) - 1.0, 1.0)
        a.set_xlabel(f"operating parameter {name}")
        a.set_ylabel("log-likelihood - max")
        a.legend(loc="lower center", fontsize=8)
    axes[0].set_title("Operating-point estimate")
    fig.tight_layout()
    return fig


def plot_fp_surface(results: Any, k: Any = None, *, equation: int = 0, ax: Any = None, alpha: float = 0.05) -> Any:
    """The point parameters ``theta(k)`` of an FP model against one operating parameter, with pointwise
    ``1 - alpha`` bands (:meth:`~tsfdi.models.FPResults.theta_bse`, delta method); grey lines mark the fitted
    operating points.

    Parameters
    ----------
    results : FPResults
        A fitted FP model of one operating parameter (for several, pass ``k`` as a grid of points whose first
        column is the abscissa).
    k : array_like (m,) or (m, d), optional
        Where to evaluate (default: 101 points over the model's ``k_range``, one parameter).
    equation : int
        The equation (output channel) of an FP-VAR.
    ax : matplotlib Axes, optional
    alpha : float

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from scipy import stats

    m = results.model
    if k is None:
        if m.k_range.shape[0] != 1:
            raise ValueError("k is required for a model of several operating parameters (a grid of points)")
        k = np.linspace(m.k_range[0, 0], m.k_range[0, 1], 101)[:, None]
    k = np.asarray(k, dtype=float)
    k = k[:, None] if k.ndim == 1 else k
    names = results.point_names()
    theta = np.array([np.asarray(results.theta(p), dtype=float).reshape(m.df_point, -1)[:, equation] for p in k])
    bse = np.array([np.asarray(results.theta_bse(p), dtype=float).reshape(m.df_point, -1)[:, equation] for p in k])
    q = stats.norm.isf(alpha / 2)
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.5, 4.0))
    else:
        fig = ax.figure
    x = k[:, 0]
    for a in range(theta.shape[1]):
        line, = ax.plot(x, theta[:, a], lw=1.4, label=names[a])
        ax.fill_between(x, theta[:, a] - q * bse[:, a], theta[:, a] + q * bse[:, a], color=line.get_color(),
                        alpha=0.2)
    for kk in np.unique(m.k[:, 0]):
        ax.axvline(kk, color="0.8", lw=0.6, zorder=0)
    ax.set_xlabel(f"operating parameter {m.k_names[0]}")
    ax.set_ylabel("parameter value (papers' sign)")
    ax.set_title(f"{type(m).__name__} parameter surfaces ({1 - alpha:.0%} bands; grey: fitted operating points)")
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    return fig

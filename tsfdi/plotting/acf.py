"""Residual auto- and cross-correlation plots (paper 003 Fig. 9)."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import stats

from tsfdi._data import as_signal
from tsfdi._validation import int_like, probability

__all__ = ["plot_acf", "correlations"]


def correlations(x: np.ndarray, lags: int) -> np.ndarray:
    """Sample auto- and cross-correlations ``r_ij(k) = c_ij(k) / sqrt(c_ii(0) c_jj(0))``, ``k = 0..lags``.

    ``c_ij(k) = sum_{t=k}^{N-1} (x_i[t] - mean_i)(x_j[t-k] - mean_j) / N`` (biased, as statsmodels ``acf``).
    ``x`` has shape ``(N, s)``; the result has shape ``(lags + 1, s, s)``. Cost O(N lags s^2).
    """
    x = np.asarray(x, dtype=float)
    x = x - x.mean(axis=0)
    n = x.shape[0]
    c = np.empty((lags + 1, x.shape[1], x.shape[1]))
    c[0] = x.T @ x
    for k in range(1, lags + 1):
        c[k] = x[k:].T @ x[:-k]
    sd = np.sqrt(np.diag(c[0]))
    return c / n / (np.outer(sd, sd) / n)


def plot_acf(resid: Any, lags: int = 40, alpha: float = 0.05, ax: Any = None) -> Any:
    """Plot the residual autocorrelation with the white-noise confidence band.

    For a vector residual an ``s x s`` grid is drawn: autocorrelations on the diagonal, cross-correlations
    ``corr(e_i[t], e_j[t-k])`` off the diagonal (paper 003 Fig. 9).

    Parameters
    ----------
    resid : array_like, Series, DataFrame or DataArray
        Residual series (scalar or vector).
    lags : int
        Largest lag shown.
    alpha : float
        The band is ``+- z_{1-alpha/2} / sqrt(N)``, the limit of a sample correlation of white noise.
    ax : matplotlib Axes, or an ``(s, s)`` array of Axes for a vector residual, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    sig = as_signal(resid, "resid", min_nobs=3)
    lags = int_like(lags, "lags", minimum=1, maximum=sig.nobs - 1)
    alpha = probability(alpha, "alpha")
    r = correlations(sig.values, lags)
    band = stats.norm.ppf(1 - alpha / 2) / np.sqrt(sig.nobs)
    s = sig.nchan
    if ax is None:
        fig, axes = plt.subplots(s, s, figsize=(3.2 * s + 1.5, 2.4 * s + 0.8), squeeze=False, sharex=True)
    else:
        axes = np.atleast_2d(np.asarray(ax, dtype=object))
        if axes.shape != (s, s):
            raise ValueError(f"ax must be a single Axes for a scalar residual or an ({s}, {s}) array of Axes, "
                             f"got shape {axes.shape}")
        fig = axes[0, 0].figure
    k = np.arange(lags + 1)
    names = sig.channels
    for i in range(s):
        for j in range(s):
            a = axes[i, j]
            a.vlines(k, 0, r[:, i, j], color="C0" if i == j else "C1", lw=1.2)
            a.plot(k, r[:, i, j], "o", ms=2.5, color="C0" if i == j else "C1")
            a.axhline(0, color="k", lw=0.6)
            a.fill_between(k, -band, band, color="0.8", alpha=0.6, lw=0,
                           label=f"{100 * (1 - alpha):g}% band" if i == j == 0 else None)
            a.set_title(f"ACF {names[i]}" if i == j else f"CCF {names[i]} vs {names[j]}(t-k)", fontsize=9)
            if i == s - 1:
                a.set_xlabel("lag k")
    axes[0, 0].legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig

"""Order-selection curves (paper 003 Fig. 8)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plot_order_selection"]


def plot_order_selection(selection: Any, ax: Any = None) -> Any:
    """BIC (top panel) and RSS/SSS in percent (bottom panel, log scale) against the model order.

    The two criteria have their own axes so that neither hides the other. BIC is drawn as its distance to the
    minimum, on a scale linear below 10 and logarithmic above, so that the minimum stays visible beside the
    large drop of the first orders. The BIC minimum
    (:attr:`OrderSelection.selected`) and the RSS/SSS stabilisation order (:attr:`OrderSelection.stabilized`)
    are marked in both, and the order axis has integer ticks.

    Parameters
    ----------
    selection : OrderSelection
    ax : sequence of two matplotlib Axes, optional
        Axes of the BIC and of the RSS/SSS curve (default: a new figure with two panels sharing the order axis).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    t = selection.table
    if ax is None:
        fig, axes = plt.subplots(2, 1, figsize=(6.5, 5.0), sharex=True)
    else:
        axes = list(np.ravel(np.asarray(ax, dtype=object)))
        if len(axes) != 2:
            raise ValueError(f"ax must be a sequence of two Axes (BIC, RSS/SSS), got {len(axes)}")
        fig = axes[0].figure
    top, bottom = axes
    top.plot(t.index, t["bic"] - t["bic"].min(), "o-", color="C0", ms=3, label="BIC - min BIC")
    top.set_yscale("symlog", linthresh=10.0)
    bottom.semilogy(t.index, t["rss_sss"], "s-", color="C3", ms=3, label="RSS/SSS")
    for a in axes:
        a.axvline(selection.selected, color="C0", ls="--", lw=1, label=f"min BIC: order {selection.selected}")
        a.axvline(selection.stabilized, color="C3", ls=":", lw=1,
                  label=f"RSS/SSS stable: order {selection.stabilized}")
        a.xaxis.set_major_locator(MaxNLocator(integer=True))
        a.legend(loc="upper right", fontsize=8)
    top.set_ylabel("BIC - min BIC")
    bottom.set_ylabel("RSS/SSS (%)")
    bottom.set_xlabel("model order (lags)")
    top.set_title(f"Order selection, {type(selection.spec).__name__}")
    fig.tight_layout()
    return fig

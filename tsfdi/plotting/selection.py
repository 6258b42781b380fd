"""Order-selection curves (paper 003 Fig. 8)."""

from __future__ import annotations

from typing import Any

__all__ = ["plot_order_selection"]


def plot_order_selection(selection: Any, ax: Any = None) -> Any:
    """BIC (left axis) and RSS/SSS in percent (right axis, log scale) against the model order.

    The BIC minimum (:attr:`OrderSelection.selected`) and the RSS/SSS stabilisation order
    (:attr:`OrderSelection.stabilized`) are marked.

    Parameters
    ----------
    selection : OrderSelection
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    t = selection.table
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.5, 3.8))
    else:
        fig = ax.figure
    ax.plot(t.index, t["bic"], "o-", color="C0", ms=3, label="BIC")
    ax.axvline(selection.selected, color="C0", ls="--", lw=1, label=f"min BIC: {selection.selected}")
    ax.set_xlabel("model order")
    ax.set_ylabel("BIC", color="C0")
    ax2 = ax.twinx()
    ax2.semilogy(t.index, t["rss_sss"], "s-", color="C3", ms=3, label="RSS/SSS (%)")
    ax2.axvline(selection.stabilized, color="C3", ls=":", lw=1, label=f"RSS/SSS stable: {selection.stabilized}")
    ax2.set_ylabel("RSS/SSS (%)", color="C3")
    lines = ax.get_legend_handles_labels()
    lines2 = ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], loc="upper right", fontsize=8)
    ax.set_title(f"Order selection, {type(selection.spec).__name__}")
    fig.tight_layout()
    return fig

"""Plots of the monitoring and evaluation stage: variance evolution (Dutta et al., Fig. 7), monitor timelines and
confusion heatmaps (Table 4). matplotlib is imported inside each function."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plot_variance_evolution", "plot_monitor", "plot_confusion"]


def _axes(ax: Any, nrows: int = 1, figsize=(7, 5)):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, axes = plt.subplots(nrows, 1, figsize=figsize, sharex=True, squeeze=False)
        return fig, list(axes[:, 0])
    axes = list(np.atleast_1d(ax))
    if len(axes) != nrows:
        raise ValueError(f"ax must hold {nrows} axes, got {len(axes)}")
    return axes[0].figure, axes


def plot_variance_evolution(signals: Any, *, fs: float = 1.0, window: float = 10.0, step: float = 0.1,
                            thresholds: Any = None, failure_time: float | None = None, labels: Any = None,
                            channels: Any = None, ax: Any = None) -> Any:
    """Rolling variance of each channel against time for one or more records (Dutta et al., Fig. 7).

    Parameters
    ----------
    signals : array_like (nobs, k) or sequence of them (numpy, pandas or xarray)
        Records; each is drawn as one line per channel panel.
    fs : float
        Sampling frequency (Hz).
    window, step : float
        Rolling window and its update interval in seconds (the paper: 10 s, 0.1 s).
    thresholds : array_like, shape (k,), optional
        Steady-state variance thresholds, drawn dashed.
    failure_time : float, optional
        Failure instant (s), drawn as a vertical dashed line.
    labels : sequence of str, optional
        Legend labels of the records (default: no label; the legend then shows the threshold and failure lines
        only).
    channels : sequence of str, optional
        Channel names of the y-axis labels (default the signal's channel names).
    ax : sequence of k Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from tsfdi._data import as_signal, rolling_variance

    is_one = not isinstance(signals, (list, tuple))
    sigs = [as_signal(s, "signals", allow_constant=True) for s in ([signals] if is_one else signals)]
    if not sigs:
        raise ValueError("signals is empty")
    k = sigs[0].nchan
    W = max(2, int(round(window * fs)))
    S = max(1, int(round(step * fs)))
    fig, axes = _axes(ax, k, figsize=(7, 2.2 * k))
    names = list(channels) if channels is not None else list(sigs[0].channels)
    for r, sig in enumerate(sigs):
        v = rolling_variance(sig.values, W, S)
        t = (np.arange(v.shape[0]) * S + W) / fs
        for c in range(k):
            axes[c].plot(t, v[:, c], lw=1, label=None if labels is None else str(labels[r]))
    for c in range(k):
        axes[c].set_ylabel(f"var({names[c]})")
        axes[c].set_yscale("log")
        if thresholds is not None:
            axes[c].axhline(float(np.asarray(thresholds)[c]), color="k", ls="--", lw=1,
                            label="steady-state threshold")
        if failure_time is not None:
            axes[c].axvline(failure_time, color="k", ls=":", lw=1, label=f"failure at {failure_time:g} s")
    axes[-1].set_xlabel(f"time of the window end (s), window {window:g} s")
    if axes[0].get_legend_handles_labels()[0]:
        axes[0].legend(fontsize="small", ncol=min(5, len(sigs) + 2), loc="lower center", bbox_to_anchor=(0.5, 1.0),
                       frameon=False)
    fig.tight_layout()
    return fig


def plot_monitor(result: Any, ax: Any = None) -> Any:
    """Timeline of a :class:`~tsfdi.monitoring.MonitorResult`: rolling variances (with the steady-state thresholds),
    healthy-model detection statistic (ratio to its threshold) and, when windows were identified, their label.

    Parameters
    ----------
    result : MonitorResult
        Its ``windows`` table; each ``variance_<channel>`` column is one curve of the top panel, labelled by
        ``<channel>``. Times are in seconds when the monitor had ``fs``, in samples otherwise (the axis and the
        event labels say which).
    ax : sequence of matplotlib Axes, optional
        One per panel drawn: the variance panel when some window has a variance (windows shorter than the steady
        window have none), the detection panel, and the label panel when some window was identified.

    Returns
    -------
    matplotlib.figure.Figure
    """
    w = result.windows
    if len(w) == 0:
        raise ValueError("result has no window to plot")
    unit = "s" if getattr(result, "fs", None) else "samples"
    var_cols = [c for c in w.columns if c.startswith("variance_") and w[c].notna().any()]
    ident = (w["status"] != "").to_numpy()
    panels = (["variance"] if var_cols else []) + ["detection"] + (["label"] if ident.any() else [])
    fig, axes = _axes(ax, len(panels), figsize=(7, 2.2 * len(panels) + 0.4))
    panel = dict(zip(panels, axes))
    if var_cols:
        a = panel["variance"]
        thr = getattr(result, "steady_thresholds", None)
        for i, c in enumerate(var_cols):
            line, = a.plot(w["end"], w[c], lw=1, label=c.removeprefix("variance_"))
            if thr is not None:
                j = [x for x in w.columns if x.startswith("variance_")].index(c)
                a.axhline(float(thr[j]), color=line.get_color(), ls="--", lw=0.8)
        a.set_yscale("log")
        a.set_ylabel("rolling variance" + ("\n(dashed: steady-state\nthreshold)" if thr is not None else ""))
        a.legend(title="channel", fontsize="small")
    a = panel["detection"]
    a.plot(w["end"], w["detect_statistic"], lw=1, color="C3", label="healthy model")
    a.axhline(1.0, color="k", ls="--", lw=1, label="threshold")
    a.set_yscale("log")
    a.set_ylabel("healthy model\nstatistic / threshold")
    if ident.any():
        a = panel["label"]
        labs = sorted({str(x) for x in w["label"][ident].dropna()} | {"(none)"})
        y = [labs.index(str(x)) if x is not None and x == x else labs.index("(none)") for x in w["label"]]
        a.scatter(w["end"][ident], np.asarray(y)[ident], s=10)
        a.set_yticks(range(len(labs)), labs)
        a.set_ylabel("label")
    axes[-1].set_xlabel(f"time of the window end ({unit})")
    for e in result.events:
        if e.kind in ("detection", "steady"):
            for a in axes:
                a.axvline(e.time, color="k" if e.kind == "detection" else "g", ls=":", lw=1,
                          label=f"{e.kind} at {e.time:g} {unit}" if a is panel["detection"] else None)
    panel["detection"].legend(fontsize="small")
    fig.tight_layout()
    return fig


def plot_confusion(table: Any, ax: Any = None, *, title: str | None = None, cmap: str = "Blues") -> Any:
    """Heatmap of a confusion table: rows true failures, columns the decision, percent of the row's windows.

    Parameters
    ----------
    table : pandas.DataFrame
        Rows true classes, columns the decisions in percent, e.g. one ``(model, method, window)`` slice of
        :meth:`tsfdi.Evaluation.confusion`: one column per fault, then ``ambiguous`` (several models accept) and
        ``none`` (no model accepts), so that every row adds up to 100. Those two columns are set apart by a line.
    ax : matplotlib Axes, optional
    title : str, optional
    cmap : str
        Matplotlib colour map of the cells (0 to 100 %).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    import pandas as pd

    if not isinstance(table, pd.DataFrame) or table.empty:
        raise TypeError("table must be a non-empty pandas DataFrame (rows true class, columns decisions in %)")
    if ax is None:
        fig, ax = plt.subplots(figsize=(1.3 * table.shape[1] + 2, 1.0 * table.shape[0] + 1.5))
    else:
        fig = ax.figure
    vals = table.to_numpy(dtype=float)
    im = ax.imshow(vals, cmap=cmap, vmin=0, vmax=100)
    ax.set_xticks(range(table.shape[1]), [str(c) for c in table.columns])
    ax.set_yticks(range(table.shape[0]), [str(i) for i in table.index])
    ax.set_xlabel("decided as")
    ax.set_ylabel("true failure")
    undecided = [j for j, c in enumerate(table.columns) if str(c) in ("ambiguous", "none")]
    if undecided and undecided[0] > 0:
        ax.axvline(undecided[0] - 0.5, color="k", lw=1.5)
    for i in range(vals.shape[0]):
        for j in range(vals.shape[1]):
            ax.text(j, i, f"{vals[i, j]:.1f}", ha="center", va="center",
                    color="white" if vals[i, j] > 60 else "black", fontsize="small")
    fig.colorbar(im, ax=ax, label="% of the true failure's windows")
    if title:
        ax.set_title(title, fontsize="medium")
    fig.tight_layout()
    return fig

"""The :class:`Decision` object returned by every residual test.

A decision always has the same shape, whatever the test or the options: the per-channel quantities
(``statistic``, ``threshold``, ``pvalue``, ``df``, ``channel_reject``) are 1-D numpy arrays with one entry
per tested component (one for a scalar residual, one per channel for a vector residual, one named
``"joint"`` for a multivariate portmanteau test), and ``reject`` is a plain ``bool`` stating the decision
for the whole signal.

Combining channels (Dutta et al., Vector residual based FDI): the signal is accepted (healthy, or "this
model fits") only when **every** channel accepts; it is rejected when any channel rejects. With ``alpha`` used
per channel the family-wise false-alarm rate of ``k`` independent channels is ``1 - (1 - alpha)**k`` (at most
``k * alpha``). The windowed tests therefore share ``alpha`` by default (``correction="sidak"``: every channel at
``1 - (1 - alpha)**(1/k)``; ``"bonferroni"``: ``alpha / k``), so that the signal-level false-alarm rate is at most
``alpha``; ``correction="none"`` tests every channel at ``alpha``, the paper's use.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from tsfdi.summary import Summary

__all__ = ["Decision"]


def _fmt(v: Any) -> str:
    if isinstance(v, (float, np.floating)):
        if np.isnan(v):
            return "nan"
        return f"{v:.4g}"
    if isinstance(v, (np.ndarray, list, tuple)):
        return "(" + ", ".join(_fmt(x) for x in np.asarray(v).ravel()) + ")"
    return str(v)


@dataclass(frozen=True)
class Decision:
    """Outcome of a residual hypothesis test.

    Attributes
    ----------
    statistic : ndarray, shape (k,)
        Test statistic per tested component (channel).
    threshold : ndarray, shape (k,)
        Critical value per component; the component rejects when ``statistic > threshold``.
    pvalue : ndarray, shape (k,)
        p-value per component; ``nan`` where the test has none (e.g. an empirical GLRT threshold).
    alpha : float
        Type I (false alarm) risk requested; per component unless ``details["correction"]`` says otherwise.
    reject : bool
        Decision for the whole signal: True (H1, fault / model does not fit) when any component rejects.
    df : ndarray
        Degrees of freedom per component: shape (k,) for chi-square tests, shape (k, 2) for the F test
        (numerator, denominator); ``nan`` where none.
    nobs : int
        Number of residual samples tested.
    null_hypothesis, alternative_hypothesis : str
        The hypotheses in words.
    details : dict
        Test-specific extra results (e.g. alarm times of the GLRT, the multivariate method).
    channel_reject : ndarray of bool, shape (k,)
        Decision per component.
    channels : tuple of str
        Component names.
    test : str
        Name of the test that produced the decision.
    """

    statistic: np.ndarray
    threshold: np.ndarray
    pvalue: np.ndarray
    alpha: float
    reject: bool
    df: np.ndarray
    nobs: int
    null_hypothesis: str
    alternative_hypothesis: str
    details: dict = field(default_factory=dict)
    channel_reject: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    channels: tuple = ()
    test: str = ""

    def __post_init__(self) -> None:
        stat = np.array(self.statistic, dtype=np.float64, ndmin=1)
        k = stat.shape[0]

        def per_channel(v: Any, dtype: type) -> np.ndarray:
            a = np.array(v, dtype=dtype, ndmin=1)
            if a.shape[0] == k:
                return a
            if a.shape == (1,):
                return np.full(k, a[0], dtype=dtype)
            return np.broadcast_to(a, (k,) + a.shape).copy()

        thr = per_channel(self.threshold, np.float64)
        pv = per_channel(self.pvalue, np.float64)
        df = per_channel(self.df, np.float64)
        rej = self.channel_reject
        rej = stat > thr if rej is None or np.size(rej) == 0 else per_channel(rej, bool)
        channels = tuple(self.channels) if self.channels else tuple(f"y{i}" for i in range(k))
        if len(channels) != k:
            raise ValueError(f"channels has {len(channels)} names for {k} components")
        for arr in (stat, thr, pv, df, rej):
            arr.flags.writeable = False
        object.__setattr__(self, "statistic", stat)
        object.__setattr__(self, "threshold", thr)
        object.__setattr__(self, "pvalue", pv)
        object.__setattr__(self, "df", df)
        object.__setattr__(self, "channel_reject", rej)
        object.__setattr__(self, "channels", channels)
        object.__setattr__(self, "reject", bool(self.reject))
        object.__setattr__(self, "alpha", float(self.alpha))
        object.__setattr__(self, "nobs", int(self.nobs))

    # ------------------------------------------------------------------ derived
    @property
    def accept(self) -> bool:
        """``not reject``: the null hypothesis (healthy / model fits) is accepted for the whole signal."""
        return not self.reject

    @property
    def signal_pvalue(self) -> float:
        """p-value of the signal-level decision: the smallest channel p-value, adjusted by the test's correction over
        the ``k`` channels (Sidak ``1 - (1 - p)^k``, Bonferroni ``min(1, k * p)``), so that it is below ``alpha``
        when the signal rejects; ``nan`` if the test has none."""
        if np.all(np.isnan(self.pvalue)):
            return float("nan")
        p = float(np.nanmin(self.pvalue))
        k = len(self.channels) or self.pvalue.shape[0]
        if self.details.get("correction") == "bonferroni":
            p = min(1.0, p * k)
        elif self.details.get("correction") == "sidak":
            p = float(-np.expm1(k * np.log1p(-p))) if p < 1.0 else 1.0
        return p

    @property
    def margin(self) -> float:
        """Largest ``statistic / threshold`` over the channels (> 1 means reject)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return float(np.max(self.statistic / self.threshold))

    # ------------------------------------------------------------------ display
    def summary(self) -> Summary:
        """The decision per channel and for the signal: a :class:`tsfdi.summary.Summary` (text when printed,
        HTML tables in a notebook) with the hypotheses, ``alpha``, the signal's decision and p-value in its header
        and one row per channel (statistic, threshold, p-value, degrees of freedom, reject)."""
        header = [("Test", self.test or "Residual test"), ("H0", self.null_hypothesis),
                  ("H1", self.alternative_hypothesis), ("alpha", self.alpha), ("Observations", self.nobs)]
        corr = self.details.get("correction")
        if corr:
            header.append(("Per-channel correction", corr))
        header += [("Signal p-value", self.signal_pvalue),
                   ("Signal decision", "reject H0 (fault / model does not fit)" if self.reject else "accept H0")]
        df = self.df
        if df.ndim == 1:
            dfs = {"df": df}
        elif df.shape[1:] == (2,):      # the F test: numerator and denominator
            dfs = {"df num": df[:, 0], "df den": df[:, 1]}
        else:
            dfs = {"df": [_fmt(d) for d in df]}
        table = pd.DataFrame({"statistic": self.statistic, "threshold": self.threshold, "p-value": self.pvalue,
                              **dfs, "reject": self.channel_reject}, index=pd.Index(self.channels, name="channel"))
        return Summary(f"{self.test or 'Residual test'} decision", header, [("Per channel", table)],
                       ["Rule: the signal is accepted only if every channel accepts."])

    def __repr__(self) -> str:
        stats = ", ".join(f"{c}={s:.4g}{'>' if r else '<='}{t:.4g}" for c, s, t, r in
                          zip(self.channels, self.statistic, self.threshold, self.channel_reject))
        return (f"Decision(test={self.test!r}, reject={self.reject}, alpha={self.alpha:g}, nobs={self.nobs}, "
                f"{stats})")

    def _repr_html_(self) -> str:
        return self.summary().as_html()

    def plot(self, ax: Any = None, **kwargs: Any) -> Any:
        """Bars of the statistic per channel against the critical limit (Dutta et al., Figs. 10-13).

        Returns the matplotlib ``Figure``. See :func:`tsfdi.plotting.plot_decision`.
        """
        from tsfdi.plotting.decision import plot_decision

        return plot_decision(self, ax=ax, **kwargs)

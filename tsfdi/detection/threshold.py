"""Data-driven threshold of a detection statistic (Hansen, Blanke, Adrian, paper 002, Fig. 2).

:class:`EmpiricalThreshold` is shared by the GLRT and by the calibrated residual tests
(:class:`~tsfdi.detection.base.CalibratedTest`); it depends on no test, so every detection module may import it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tsfdi._data import as_signal
from tsfdi._validation import float_like, int_like, probability

__all__ = ["EmpiricalThreshold"]


def _ceil(v: float) -> int:
    """Ceiling that ignores floating-point noise (20 / 1e-4 is 200000, not 200001)."""
    return math.ceil(v * (1 - 1e-12))


class EmpiricalThreshold:
    r"""Threshold of a detection statistic from its distribution on healthy data (Hansen et al., Fig. 2).

    Parameters
    ----------
    false_alarm : float
        Required false-alarm probability :math:`P_F` of one value of the statistic, in (0, 1): per sample
        for a per-sample statistic such as the GLRT's :math:`g(k)`, per tested window (per channel) for a
        windowed statistic (Ljung-Box, F test).
    min_exceedances : int
        The empirical :math:`1 - P_F` quantile is used when the healthy sample holds at least this many
        expected exceedances (``n * P_F >= min_exceedances``).
    tail_fraction : float
        Below that, a generalised Pareto distribution is fitted to the excesses over the
        ``1 - tail_fraction`` quantile :math:`u` and the threshold is extrapolated:
        :math:`\gamma = u + \frac{\sigma}{\xi}\left[(P_F / \zeta)^{-\xi} - 1\right]`, :math:`\zeta` the
        fraction of samples above :math:`u` (:math:`\xi = 0`: :math:`u - \sigma \ln(P_F / \zeta)`).
    min_tail : int
        Minimum number of excesses for the tail fit.
    max_extrapolation : float
        The tail fit may reach :math:`P_F` down to ``min_exceedances / (n * max_extrapolation)``; a smaller
        sample raises an error stating how many samples are needed.
    tail_shape : float or None
        Shape :math:`\xi` of the generalised Pareto tail. ``0`` (default): exponential excesses, the Gumbel
        domain of attraction of a maximum of chi-square variables such as the GLRT statistic; its scale is the
        mean excess. ``None``: :math:`\xi` fitted by maximum likelihood too (for other statistics; with
        strongly dependent samples the fitted :math:`\xi` tends to be negative and the threshold too low).

    Attributes
    ----------
    threshold_ : float
        The calibrated threshold (after :meth:`calibrate`).
    method_ : str
        ``"empirical"`` or ``"gpd"``.
    sample_ : ndarray
        The calibration statistic (sorted), kept for :meth:`plot`.

    Notes
    -----
    The statistic of correlated residuals has no closed-form distribution; Hansen et al. estimate the
    threshold from the empirical distribution of g(k) in normal flight. Consecutive values of a windowed
    statistic are strongly dependent, so the effective sample is smaller than its length: calibrate on long
    healthy records.
    """

    def __init__(self, false_alarm: float = 1e-3, *, min_exceedances: int = 20, tail_fraction: float = 0.05,
                 min_tail: int = 100, max_extrapolation: float = 100.0, tail_shape: float | None = 0.0) -> None:
        self.false_alarm = probability(false_alarm, "false_alarm")
        self.min_exceedances = int_like(min_exceedances, "min_exceedances", minimum=1)
        self.tail_fraction = float_like(tail_fraction, "tail_fraction", minimum=0.0, maximum=0.5, strict_min=True)
        self.min_tail = int_like(min_tail, "min_tail", minimum=10)
        self.max_extrapolation = float_like(max_extrapolation, "max_extrapolation", minimum=1.0)
        self.tail_shape = float_like(tail_shape, "tail_shape", minimum=-1.0, maximum=1.0, optional=True)

    def __repr__(self) -> str:
        fitted = f", threshold_={self.threshold_:.5g} ({self.method_})" if hasattr(self, "threshold_") else ""
        return f"EmpiricalThreshold(false_alarm={self.false_alarm:g}{fitted})"

    def samples_needed(self) -> int:
        """Smallest calibration sample that supports ``false_alarm`` (empirical or tail fit)."""
        emp = _ceil(self.min_exceedances / self.false_alarm)
        gpd = max(_ceil(self.min_tail / self.tail_fraction),
                  _ceil(self.min_exceedances / (self.false_alarm * self.max_extrapolation)))
        return min(emp, gpd)

    def calibrate(self, statistic: Any) -> EmpiricalThreshold:
        """Estimate the threshold from healthy values of the statistic; returns ``self``.

        Parameters
        ----------
        statistic : array_like, Series or DataArray
            Values of the detection statistic under normal operation (all channels pooled).

        Raises
        ------
        ValueError
            If the sample is too small for ``false_alarm`` (the message says how many samples are needed).
        """
        sig = as_signal(statistic, "statistic", allow_constant=True)
        g = np.sort(sig.values.ravel())
        n = g.size
        pf = self.false_alarm
        if n * pf >= self.min_exceedances:
            self.method_ = "empirical"
            self.threshold_ = float(np.quantile(g, 1.0 - pf))
            self.gpd_ = None
        else:
            needed = self.samples_needed()
            if n < needed:
                raise ValueError(
                    f"statistic is too small to calibrate false_alarm={pf:g}: {n} samples, at least {needed} "
                    f"are needed (empirical quantile: {_ceil(self.min_exceedances / pf)}; generalised Pareto "
                    f"tail: {needed})")
            from scipy import stats

            u = float(np.quantile(g, 1.0 - self.tail_fraction))
            exc = g[g > u] - u
            zeta = exc.size / n
            if exc.size < self.min_tail or np.ptp(exc) == 0:
                raise ValueError(f"statistic has only {exc.size} distinct excesses over its "
                                 f"{1 - self.tail_fraction:g} quantile; a longer healthy sample is needed")
            if self.tail_shape is None:
                xi, _, scale = stats.genpareto.fit(exc, floc=0.0)
            elif self.tail_shape == 0.0:
                xi, scale = 0.0, float(exc.mean())           # ML scale of exponential excesses
            else:
                xi = self.tail_shape
                _, _, scale = stats.genpareto.fit(exc, f0=xi, floc=0.0)
            if abs(xi) < 1e-9:
                thr = u - scale * math.log(pf / zeta)
            else:
                thr = u + scale / xi * ((pf / zeta) ** (-xi) - 1.0)
            self.method_ = "gpd"
            self.threshold_ = float(thr)
            self.gpd_ = {"shape": float(xi), "scale": float(scale), "location": u, "zeta": zeta}
        self.sample_ = g
        self.nobs_ = n
        return self

    def exceedance(self, value: Any) -> np.ndarray:
        """Estimated probability that the healthy statistic exceeds ``value`` (empirical, or the tail fit
        above its location)."""
        self.check_fitted()
        v = np.asarray(value, dtype=np.float64)
        g = self.sample_
        p = 1.0 - np.searchsorted(g, v, side="right") / g.size
        if self.gpd_ is not None:
            u, xi, sc, z = (self.gpd_[k] for k in ("location", "shape", "scale", "zeta"))
            above = v > u
            t = np.maximum(v - u, 0.0)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                tail = z * (np.exp(-t / sc) if abs(xi) < 1e-9 else np.maximum(1 + xi * t / sc, 0) ** (-1 / xi))
            p = np.where(above, tail, p)
        return p

    def check_fitted(self) -> None:
        """Raise ``ValueError`` unless :meth:`calibrate` has been run (``threshold_`` is set)."""
        if not hasattr(self, "threshold_"):
            raise ValueError("EmpiricalThreshold is not calibrated: call calibrate(healthy statistic) first")

    def plot(self, ax: Any = None, **kwargs: Any) -> Any:
        """Probability plot of the healthy statistic with the chosen threshold (Hansen et al., Fig. 2)."""
        self.check_fitted()
        from tsfdi.plotting.decision import plot_threshold

        return plot_threshold(self, ax=ax, **kwargs)

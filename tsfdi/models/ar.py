"""Scalar autoregressive model AR(na) (paper 003 eq. 4)."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import signal as sps

from tsfdi._validation import check_rng, float_like, int_like
from tsfdi.models._base import LinearTimeSeriesModel, ScalarOutputResults
from tsfdi.models.archive import register
from tsfdi.models.lstsq import check_size

__all__ = ["AR", "ARResults"]


@register
class AR(LinearTimeSeriesModel):
    """Scalar autoregression estimated by least squares.

    .. math::  y[t] + \\sum_{i=1}^{n_a} a_i\\, y[t-i] = c + e[t], \\qquad e[t] \\sim \\mathrm{iid}\\ \\mathcal{N}(0, \\sigma_e^2)

    (paper 003, eq. 4; ``c = 0`` unless ``trend="c"``). The coefficients ``a_i`` are stored in this sign;
    statsmodels' ``AutoReg`` estimates ``phi_i = -a_i`` and the same intercept.

    Parameters
    ----------
    y : array_like, Series, DataFrame (one column) or DataArray, or a list of them
        Scalar signal, time on axis 0 (or the ``"time"`` dimension). A list of signals is a set of records
        of the same process (several flights): their regressions are stacked, each record holding back its
        own first samples, so no artificial jump joins them.
    lags : int
        Order ``na >= 1``.
    trend : {"n", "c"}
        No intercept (the papers' model) or an intercept.
    hold_back : int, optional
        Number of initial samples excluded from the estimation sample (default ``lags``); used to fit
        several orders on a common sample (see :func:`tsfdi.select_order`).

    Raises
    ------
    ValueError
        A channel whose largest magnitude is outside ``[1e-152, 1e152]`` (where variances leave the
        floating-point range), NaN / inf or constant data, too few samples for the order, or a regressor of
        more than 2 GiB (:data:`~tsfdi.models.lstsq.MAX_VALUES`), each named in the message.
    TypeError
        Non-numeric data or a non-integer order.

    Notes
    -----
    The fit runs in units near each channel's peak (:attr:`y_scale`: powers of two, exact), so the
    results at ``c * y`` are those at ``y`` rescaled: lag coefficients unchanged, ``sigma2`` times ``c**2``,
    ``llf`` minus ``nobs * log|c|`` per channel. An exact fit (zero residuals to rounding) warns and gets a
    finite ``llf`` (see :func:`~tsfdi.models.criteria.information_criteria`).
    """

    _vector = False

    def __init__(self, y: Any, lags: int, trend: str = "n", *, hold_back: int | None = None) -> None:
        int_like(lags, "lags", minimum=1)
        super().__init__(y, lags, trend=trend, hold_back=hold_back)


class ARResults(ScalarOutputResults):
    """Results of :meth:`AR.fit` (immutable).

    Attributes
    ----------
    ar_coefs : ndarray, shape (lags,)
        ``a_1..a_na`` in the papers' sign (``y[t] + sum a_i y[t-i] = c + e[t]``).
    params : ndarray or Series
        ``[c, a_1, ..., a_na]`` (``c`` only with ``trend="c"``); a Series indexed ``const, a1, a2, ...`` for
        pandas / xarray data.
    bse, tvalues, pvalues : ndarray or Series
        Standard errors ``sqrt(sigma2 diag((X'X)^-1))``, ``params / bse`` and their two-sided normal p-values, as
        statsmodels ``AutoReg(y, lags, trend).fit()`` (whose lag coefficients have the opposite sign).
    sigma2 : float
        Maximum-likelihood residual variance ``RSS / nobs`` (as statsmodels ``AutoReg``).
    fittedvalues : same kind as ``y``
        ``y[t] - e[t]`` over the estimation sample.
    """

    @property
    def ar_coefs(self) -> np.ndarray:
        return self._ar_matrices()[:, 0, 0]

    def residuals(self, y: Any) -> Any:
        """One-step prediction errors of a new signal through the fixed model.

        ``e[t] = y[t] + sum_i a_i y[t-i] - c`` for ``t = lags .. len(y) - 1`` (one convolution pass).

        Parameters
        ----------
        y : array_like, Series or DataArray
            New scalar signal (at least ``lags + 1`` samples).

        Returns
        -------
        Same kind as ``y``, ``len(y) - lags`` samples; its index starts at the original position ``lags``.
        """
        sig = self._new_signal(y)
        return sig.wrap(self._residuals_array(sig.values, None), self.lags)

    def forecast(self, steps: int = 1) -> Any:
        """Forecasts of the ``steps`` samples after the end of the fitted data (the last record of a model fitted
        on several), ``y[t] = c - sum_i a_i y[t-i]`` with the forecasts in place of the samples not yet seen
        (statsmodels' ``AutoRegResults.forecast(steps)``).

        Returns
        -------
        Same kind as ``y``, ``steps`` samples: a Series / DataArray's time index continued at its frequency (or
        constant spacing; the sample positions ``len(y), ...`` when it has none).

        Raises
        ------
        ValueError
            ``steps`` < 1, or forecasts that leave the floating-point range (an unstable model).
        """
        return self._forecast(steps)

    def simulate(self, nobs: int, rng: Any = None, *, burn: int | None = None, sigma2: float | None = None) -> np.ndarray:
        """Simulate ``nobs`` samples of the fitted process with Gaussian innovations.

        Parameters
        ----------
        nobs : int
            Number of samples returned.
        rng : None, int or numpy.random.Generator
            Source of randomness.
        burn : int, optional
            Samples discarded at the start (default ``10 * lags + 100``).
        sigma2 : float, optional
            Innovation variance ``>= 0`` (default :attr:`sigma2`).

        Raises
        ------
        ValueError
            ``nobs + burn`` samples larger than the memory limit (:data:`~tsfdi.models.lstsq.MAX_VALUES`); a
            simulation that leaves the floating-point range (an unstable model).
        """
        nobs = int_like(nobs, "nobs", minimum=1)
        burn = 10 * self.lags + 100 if burn is None else int_like(burn, "burn", minimum=0)
        var = self.sigma2 if sigma2 is None else float_like(sigma2, "sigma2", minimum=0.0)
        check_size(nobs + burn, f"nobs={nobs} (+ burn={burn}): the simulated signal")
        rng = check_rng(rng)
        e = rng.standard_normal(nobs + burn) * np.sqrt(var) + self.intercept
        with np.errstate(over="ignore", invalid="ignore"):
            y = sps.lfilter([1.0], np.r_[1.0, self.ar_coefs], e)[burn:]
        if not np.isfinite(y).all():
            raise ValueError(f"nobs={nobs}: the simulation leaves the floating-point range (the fitted AR is "
                             f"{'unstable' if not self.is_stable else 'driven by a huge sigma2'}); simulate fewer "
                             "samples")
        return y


AR.results_class = ARResults

"""Vector autoregressive model VAR(na) (paper 003 eq. 7)."""

from __future__ import annotations

from typing import Any

import numpy as np

from tsfdi._validation import check_rng, int_like
from tsfdi.models._base import (LinearTimeSeriesModel, VectorOutputResults, check_covariance, gaussian_innovations,
                               simulate_var)
from tsfdi.models.archive import register
from tsfdi.models.lstsq import check_size

__all__ = ["VAR", "VARResults"]


@register
class VAR(LinearTimeSeriesModel):
    """Vector autoregression estimated by ordinary least squares, equation by equation.

    .. math::  \\mathbf{y}[t] + \\sum_{i=1}^{n_a} \\mathbf{A}_i\\, \\mathbf{y}[t-i] = \\mathbf{c} + \\mathbf{e}[t],
               \\qquad \\mathbf{e}[t] \\sim \\mathrm{iid}\\ \\mathcal{N}(\\mathbf{0}, \\Sigma)

    (paper 003, eq. 7). ``A_i`` are stored in this sign; statsmodels' ``VAR`` estimates ``-A_i``.

    Parameters
    ----------
    y : array_like (nobs, s), DataFrame or DataArray (time, channel), or a list of them
        Vector signal, or a list of records of the same process (stacked regressions, as for :class:`AR`).
    lags : int
        Order ``na >= 1``.
    trend : {"n", "c"}
        No intercept (the papers' model) or an intercept per channel.
    hold_back : int, optional
        Initial samples excluded from estimation (default ``lags``).
    criterion : {"logdet", "trace"}
        BIC variant: the likelihood's log-determinant of ``Sigma`` (standard) or the log of its trace
        (paper 003, "Vector AR Identification Method"). See :func:`tsfdi.models.criteria.information_criteria`.

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

    _vector = True

    def __init__(self, y: Any, lags: int, trend: str = "n", *, hold_back: int | None = None,
                 criterion: str = "logdet") -> None:
        int_like(lags, "lags", minimum=1)
        super().__init__(y, lags, trend=trend, hold_back=hold_back, criterion=criterion)


class VARResults(VectorOutputResults):
    """Results of :meth:`VAR.fit` (immutable).

    Attributes
    ----------
    coefs : ndarray, shape (lags, s, s)
        ``A_1..A_na`` in the papers' sign; ``coefs[i][r, c]`` multiplies channel ``c`` at lag ``i + 1`` in
        the equation of channel ``r``.
    params : ndarray or DataFrame, shape (df_eq, s)
        Regression coefficients, one column per equation, rows ``[const, lag-1 block, lag-2 block, ...]``
        (``A{i}.{channel}``); a DataFrame (parameters x channels) for pandas / xarray data.
    bse, tvalues, pvalues : ndarray or DataFrame, shape (df_eq, s)
        Standard errors ``sqrt(diag((X'X)^-1) sigma_u[j, j])`` with statsmodels' degrees-of-freedom adjusted
        ``sigma_u = E'E / (nobs - df_eq)``, ``params / bse`` and their two-sided normal p-values, exactly as
        statsmodels ``VAR(y).fit(lags, trend)`` (``stderr``, ``tvalues``, ``pvalues``).
    sigma : ndarray, shape (s, s)
        Maximum-likelihood residual covariance ``E'E / nobs`` (statsmodels' ``sigma_u_mle``).
    fittedvalues : same kind as ``y``
        ``y[t] - e[t]`` over the estimation sample.
    """

    def residuals(self, y: Any) -> Any:
        """One-step prediction errors of a new vector signal through the fixed model.

        ``e[t] = y[t] + sum_i A_i y[t-i] - c`` for ``t = lags .. len(y) - 1``.

        Returns
        -------
        Same kind as ``y``, shape ``(len(y) - lags, s)``, index starting at position ``lags``.
        """
        sig = self._new_signal(y)
        return sig.wrap(self._residuals_array(sig.values, None), self.lags)

    def forecast(self, steps: int = 1) -> Any:
        """Forecasts of the ``steps`` samples after the end of the fitted data (the last record of a model fitted
        on several), ``y[t] = c - sum_i A_i y[t-i]`` with the forecasts in place of the samples not yet seen
        (statsmodels' ``VARResults.forecast(y[-lags:], steps)``, Lütkepohl 2005, sec. 2.2.2).

        Returns
        -------
        Same kind as ``y``, shape ``(steps, s)``: a DataFrame / DataArray's time index continued at its frequency
        (or constant spacing; the sample positions ``len(y), ...`` when it has none).

        Raises
        ------
        ValueError
            ``steps`` < 1, or forecasts that leave the floating-point range (an unstable model).
        """
        return self._forecast(steps)

    def simulate(self, nobs: int, rng: Any = None, *, burn: int | None = None,
                 sigma: np.ndarray | None = None) -> np.ndarray:
        """Simulate ``nobs`` samples ``(nobs, s)`` of the fitted process with Gaussian innovations.

        Parameters
        ----------
        nobs : int
        rng : None, int or numpy.random.Generator
        burn : int, optional
            Samples discarded at the start (default ``10 * lags + 100``).
        sigma : ndarray (s, s), optional
            Innovation covariance (default :attr:`sigma`): symmetric positive semi-definite (a singular one, e.g.
            zeros for the noise-free response, is drawn through its eigendecomposition).

        Raises
        ------
        ValueError
            ``nobs + burn`` samples larger than the memory limit
            (:data:`~tsfdi.models.lstsq.MAX_VALUES`); ``sigma`` not a finite symmetric positive semi-definite
            ``(s, s)`` matrix; a simulation that leaves the floating-point range (an unstable model).
        """
        nobs = int_like(nobs, "nobs", minimum=1)
        burn = 10 * self.lags + 100 if burn is None else int_like(burn, "burn", minimum=0)
        s = self.neqs
        check_size((nobs + burn) * s, f"nobs={nobs} (+ burn={burn}): the simulated signal")
        rng = check_rng(rng)
        cov = self.sigma if sigma is None else check_covariance(sigma, s)
        e = gaussian_innovations(rng, cov, nobs + burn)
        with np.errstate(over="ignore", invalid="ignore"):
            y = simulate_var(self.coefs, e + self.intercept)[burn:]
        if not np.isfinite(y).all():
            raise ValueError(f"nobs={nobs}: the simulation leaves the floating-point range (the fitted VAR is "
                             f"{'unstable' if not self.is_stable else 'driven by a huge sigma'}); simulate fewer "
                             "samples")
        return y


VAR.results_class = VARResults

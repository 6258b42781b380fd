"""Vector autoregressive model with exogenous inputs VARX(lags, nb, nk): several outputs given several inputs."""

from __future__ import annotations

from typing import Any

import numpy as np

from tsfdi._validation import check_rng, int_like
from tsfdi.models._base import (InputOutputResults, LinearTimeSeriesModel, VectorOutputResults, check_covariance,
                               gaussian_innovations, simulate_var)
from tsfdi.models.archive import register
from tsfdi.models.lstsq import check_size

__all__ = ["VARX", "VARXResults"]


@register
class VARX(LinearTimeSeriesModel):
    """Vector autoregression with exogenous inputs, estimated by least squares, equation by equation.

    .. math::  \\mathbf{y}[t] + \\sum_{i=1}^{p} \\mathbf{A}_i\\, \\mathbf{y}[t-i]
               = \\mathbf{c} + \\sum_{j=1}^{n_b} \\mathbf{B}_j\\, \\mathbf{u}[t - n_k - j + 1] + \\mathbf{e}[t],
               \\qquad \\mathbf{e}[t] \\sim \\mathrm{iid}\\ \\mathcal{N}(\\mathbf{0}, \\Sigma)

    with ``y`` the ``s`` outputs (e.g. the body rates), ``u`` the ``m`` inputs (e.g. the commands the controller
    sends), ``A_i`` ``(s, s)`` and ``B_j`` ``(s, m)``. Written as ``y[t] = c + sum_i A'_i y[t-i] + sum_j B_j
    u[t-nk-j+1] + e[t]`` (statsmodels' and Lütkepohl's sign) the lag matrices are ``A'_i = -A_i``; ``A_i`` are
    stored in the papers' sign, as :class:`VAR` stores them.

    This is MATLAB's ``arx`` for several outputs (``A(q) y = B(q) u + e`` with ``A(q) = I + A_1 q^-1 + ...`` and
    ``B(q) = q^-nk (B_1 + B_2 q^-1 + ...)``, the same ``na`` / ``nb`` / ``nk`` for every output-input pair) and the
    VARX model of Lütkepohl (2005, *New Introduction to Multiple Time Series Analysis*, ch. 10), estimated by
    ordinary least squares equation by equation (the same regressor for every equation, so this is also the
    Gaussian maximum-likelihood estimate given the first samples). With one output (``s = 1``) it is
    :class:`ARX` with ``na = lags``: the same coefficients, residuals and ``sigma2`` (only ``bse`` differs, by
    statsmodels' degrees-of-freedom convention of each family, see :class:`VARXResults`).

    Parameters
    ----------
    y : array_like (nobs, s), DataFrame or DataArray (time, channel), or a list of them
        Outputs, or a list of records of the same process (stacked regressions, as for :class:`VAR`).
    u : array_like (nobs,) or (nobs, m), Series, DataFrame or DataArray, or a list of them
        Inputs, same length (and index) as ``y``; one input record per output record.
    lags : int
        Output order ``p >= 0``.
    nb : int, optional
        Number of input coefficient matrices (default ``lags``); ``lags + nb >= 1``.
    nk : int
        Input delay in samples (``0`` lets ``u[t]`` act on ``y[t]``).
    trend : {"n", "c"}
        No intercept or an intercept per output channel.
    hold_back : int, optional
        Initial samples excluded from estimation (default: the largest lag ``max(lags, nk + nb - 1)``).
    criterion : {"logdet", "trace"}
        BIC variant, as for :class:`VAR`.

    Raises
    ------
    ValueError
        ``u`` missing or of another length or index than ``y``, a channel whose largest magnitude is outside
        ``[1e-152, 1e152]``, NaN / inf or constant data, too few samples for the order, or a regressor of more
        than 2 GiB (:data:`~tsfdi.models.lstsq.MAX_VALUES`), each named in the message.
    TypeError
        Non-numeric data or a non-integer order.

    Notes
    -----
    The fit is that of every family of :mod:`tsfdi.models`: the Gram matrix of the regressor solved by its
    Cholesky factor when every column keeps more than ``GRAM_RELATIVE_FLOOR`` of its energy, else the SVD of the
    regressor (see :meth:`fit`), in units near each channel's peak (:attr:`y_scale` / :attr:`u_scale`).

    Examples
    --------
    >>> res = tsfdi.VARX(gyro, commands, lags=4, nk=1, trend="c").fit()     # doctest: +SKIP
    >>> e = res.residuals(new_gyro, new_commands)                            # doctest: +SKIP
    """

    _vector = True

    def __init__(self, y: Any, u: Any, lags: int, nb: int | None = None, nk: int = 0, trend: str = "n", *,
                 hold_back: int | None = None, criterion: str = "logdet") -> None:
        if u is None:
            raise ValueError("u is required: a VARX model needs an input signal (a VAR has none)")
        lags = int_like(lags, "lags", minimum=0)
        super().__init__(y, lags, trend=trend, hold_back=hold_back, u=u, nb=lags if nb is None else nb, nk=nk,
                         criterion=criterion)

    def __repr__(self) -> str:
        return (f"VARX(nobs={sum(r.nobs for r in self.records)}, lags={self.na}, nb={self.nb}, nk={self.nk}, "
                f"neqs={self.neqs}, n_inputs={self.n_inputs}, trend={self.trend!r})")


class VARXResults(VectorOutputResults, InputOutputResults):
    """Results of :meth:`VARX.fit` (immutable).

    Attributes
    ----------
    coefs : ndarray, shape (lags, s, s)
        ``A_1..A_lags`` in the papers' sign (statsmodels' are ``-A_i``); ``coefs[i][r, c]`` multiplies output
        ``c`` at lag ``i + 1`` in the equation of output ``r``.
    b : ndarray, shape (nb, s, m)
        ``B_1..B_nb``; ``b[j][r, q]`` multiplies input ``q`` at ``t - nk - j`` in the equation of output ``r``.
    params : ndarray or DataFrame, shape (df_eq, s)
        Regression coefficients, one column per equation, rows grouped by lag ``[const, A1.<outputs>,
        b1.<inputs>, A2.<outputs>, b2.<inputs>, ...]``; a DataFrame (parameters x outputs) for pandas / xarray data.
    bse, tvalues, pvalues : ndarray or DataFrame, shape (df_eq, s)
        Standard errors ``sqrt(diag((X'X)^-1) sigma_u[j, j])`` with ``sigma_u = E'E / (nobs - df_eq)``, as
        statsmodels ``VAR(y, exog=<the lagged inputs>).fit(lags, trend)`` (``stderr``), ``params / bse`` and their
        two-sided normal p-values.
    sigma : ndarray, shape (s, s)
        Maximum-likelihood residual covariance ``E'E / nobs`` (statsmodels' ``sigma_u_mle``).
    llf, aic, bic, hqic : float
        As for :class:`VARResults` (``Sigma`` the maximum-likelihood covariance).
    """

    @property
    def b(self) -> np.ndarray:
        return self._input_matrices()

    def simulate(self, u: Any, rng: Any = None, *, sigma: Any = None) -> Any:
        """Simulate the outputs of the fitted model driven by the input ``u`` and Gaussian innovations.

        ``y[t] = c - sum_i A_i y[t-i] + sum_j B_j u[t-nk-j+1] + e[t]`` with zero initial conditions (outputs and
        inputs before the first sample), ``e ~ N(0, sigma)``.

        Parameters
        ----------
        u : array_like (nobs,) or (nobs, m), Series, DataFrame or DataArray
            Input signal (matched by name when the model and ``u`` are named).
        rng : None, int or numpy.random.Generator
        sigma : ndarray (s, s), optional
            Innovation covariance (default :attr:`sigma`): symmetric positive semi-definite (zeros give the
            noise-free response).

        Returns
        -------
        The simulated outputs, ``len(u)`` samples ``(nobs, s)`` in the kind of ``u`` (the model's output names).

        Raises
        ------
        ValueError
            ``u`` with other inputs; ``sigma`` not a finite symmetric positive semi-definite ``(s, s)`` matrix; a
            simulation larger than the memory limit or one that leaves the floating-point range (an unstable model).
        """
        usig = self._new_input(u)
        s, n = self.neqs, usig.nobs
        check_size(n * s, f"u ({n} samples): the simulated output")
        cov = self.sigma if sigma is None else check_covariance(sigma, s)
        y = gaussian_innovations(check_rng(rng), cov, n) + self.intercept
        with np.errstate(over="ignore", invalid="ignore"):
            for j, B in enumerate(self.b):
                d = self.model.nk + j
                if d < n:
                    y[d:] += usig.values[:n - d] @ B.T
            if self.lags:
                y = simulate_var(self.coefs, y)
        if not np.isfinite(y).all():
            raise ValueError("u: the simulated output leaves the floating-point range (the fitted VARX is "
                             f"{'unstable' if not self.is_stable else 'driven far beyond its data'}); use a shorter "
                             "or smaller u")
        return usig.wrap(y, 0, vector=True, channels=list(self.model.data.channels), name="y")


VARX.results_class = VARXResults

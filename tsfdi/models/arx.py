"""Autoregressive model with exogenous inputs ARX(na, nb, nk)."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import signal as sps

from tsfdi._validation import check_rng, float_like
from tsfdi.models._base import InputOutputResults, LinearTimeSeriesModel, ScalarOutputResults
from tsfdi.models.archive import register

__all__ = ["ARX", "ARXResults"]


@register
class ARX(LinearTimeSeriesModel):
    """Scalar-output ARX model with one or several inputs, estimated by least squares.

    .. math::  y[t] + \\sum_{i=1}^{n_a} a_i\\, y[t-i] = c + \\sum_{m} \\sum_{j=1}^{n_b} b_{m,j}\\, u_m[t - n_k - j + 1] + e[t]

    This is the convention of MATLAB's ``arx`` (``nb`` coefficients per input, dead time ``nk``; ``nk = 0``
    lets ``u[t]`` act on ``y[t]``) and of the ARX model of paper 001 (eqs. 2-3), whose recursive estimate is
    :class:`tsfdi.RecursiveARX`.

    Parameters
    ----------
    y : array_like, Series or DataArray, or a list of them
        Scalar output, or a list of records of the same process (stacked regressions, as for :class:`AR`).
    u : array_like (nobs,) or (nobs, n_inputs), Series, DataFrame or DataArray, or a list of them
        Inputs, same length as ``y`` (one input record per output record).
    na, nb : int
        Number of output and input coefficients (``na + nb >= 1``).
    nk : int
        Input delay in samples.
    trend : {"n", "c"}
    hold_back : int, optional
        Initial samples excluded (default: the largest lag ``max(na, nk + nb - 1)``).

    Raises
    ------
    ValueError
        ``u`` of another length than ``y``, a channel whose largest magnitude is outside ``[1e-152, 1e152]``
        (where variances leave the floating-point range), NaN / inf or constant data, too few samples for the
        order, or a regressor of more than 2 GiB (:data:`~tsfdi.models.lstsq.MAX_VALUES`), each named in the
        message.
    TypeError
        Non-numeric data or a non-integer order.

    Notes
    -----
    The fit runs in units near each channel's peak (:attr:`y_scale` / :attr:`u_scale`: powers of two, exact),
    so the results at ``c * y`` (and ``c * u``) are those at ``y`` rescaled: lag coefficients unchanged,
    ``sigma2`` times ``c**2``, ``llf`` minus ``nobs * log|c|`` per channel. An exact fit (zero residuals to
    rounding) warns and gets a finite ``llf`` (see :func:`~tsfdi.models.criteria.information_criteria`).
    """

    _vector = False

    def __init__(self, y: Any, u: Any, na: int, nb: int, nk: int = 0, trend: str = "n", *,
                 hold_back: int | None = None) -> None:
        if u is None:
            raise ValueError("u is required: an ARX model needs an input signal")
        super().__init__(y, na, trend=trend, hold_back=hold_back, u=u, nb=nb, nk=nk, lag_name="na")

    def __repr__(self) -> str:
        return (f"ARX(nobs={self.data.nobs}, na={self.na}, nb={self.nb}, nk={self.nk}, "
                f"n_inputs={self.n_inputs}, trend={self.trend!r})")


class ARXResults(ScalarOutputResults, InputOutputResults):
    """Results of :meth:`ARX.fit` (immutable).

    Attributes
    ----------
    a : ndarray, shape (na,)
        Output coefficients in the papers' sign.
    b : ndarray, shape (n_inputs, nb)
        Input coefficients; ``b[m, j]`` multiplies ``u_m[t - nk - j]``.
    params : ndarray or Series
        ``[c, (a_1, b_{., 1}), (a_2, b_{., 2}), ...]`` grouped by lag (the regressor order), named ``const, a1,
        b1.<input>, a2, ...`` in a Series for pandas / xarray data.
    bse, tvalues, pvalues : ndarray or Series
        Standard errors ``sqrt(sigma2 diag((X'X)^-1))``, ``params / bse`` and their two-sided normal p-values:
        statsmodels ``AutoReg``'s convention, i.e. ``OLS`` on the same regressor with its covariance scaled by
        ``(nobs - df_eq) / nobs``.
    sigma2 : float
        ``RSS / nobs``.
    fittedvalues : same kind as ``y``
        ``y[t] - e[t]`` over the estimation sample.
    """

    @property
    def a(self) -> np.ndarray:
        return self._ar_matrices()[:, 0, 0]

    @property
    def b(self) -> np.ndarray:
        return self._input_matrices()[:, 0, :].T.copy()

    def simulate(self, u: Any, rng: Any = None, *, sigma2: float | None = None) -> Any:
        """Simulate the output of the fitted model driven by the input ``u`` and Gaussian innovations.

        ``A(q) y[t] = c + sum_m B_m(q) u_m[t] + e[t]`` with zero initial conditions, ``e ~ N(0, sigma2)``.

        Parameters
        ----------
        u : array_like (nobs,) or (nobs, n_inputs), Series, DataFrame or DataArray
            Input signal.
        rng : None, int or numpy.random.Generator
        sigma2 : float, optional
            Innovation variance (default :attr:`sigma2`; ``0`` gives the noise-free response).

        Returns
        -------
        The simulated output, ``len(u)`` samples in the kind of ``u``.

        Raises
        ------
        ValueError
            ``sigma2`` negative, ``u`` with another number of inputs, or a simulated output that leaves the
            floating-point range (an unstable model), named in the message.
        """
        usig = self._new_input(u)
        var = self.sigma2 if sigma2 is None else float_like(sigma2, "sigma2", minimum=0.0)
        e = check_rng(rng).standard_normal(usig.nobs) * np.sqrt(var) + self.intercept
        a = np.r_[1.0, self.a]
        with np.errstate(over="ignore", invalid="ignore"):
            y = sps.lfilter([1.0], a, e)
            for m, b in enumerate(self.b):
                y += sps.lfilter(np.r_[np.zeros(self.model.nk), b], a, usig.values[:, m])
        if not np.isfinite(y).all():
            raise ValueError("u: the simulated output leaves the floating-point range (the fitted ARX is "
                             f"{'unstable' if not self.is_stable else 'driven far beyond its data'}); use a shorter "
                             "or smaller u")
        return usig.wrap(y, 0, vector=False, name="y")


ARX.results_class = ARXResults

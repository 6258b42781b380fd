"""Vector autoregressive model VAR(na) (paper 003 eq. 7)."""

from __future__ import annotations

from typing import Any

import numpy as np

from tsfdi._validation import check_rng, int_like
from tsfdi.models._base import LinearTimeSeriesModel, LinearTimeSeriesResults
from tsfdi.models.archive import register

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
    """

    _vector = True

    def __init__(self, y: Any, lags: int, trend: str = "n", *, hold_back: int | None = None,
                 criterion: str = "logdet") -> None:
        int_like(lags, "lags", minimum=1)
        super().__init__(y, lags, trend=trend, hold_back=hold_back, criterion=criterion)


class VARResults(LinearTimeSeriesResults):
    """Results of :meth:`VAR.fit` (immutable).

    Attributes
    ----------
    coefs : ndarray, shape (lags, s, s)
        ``A_1..A_na`` in the papers' sign; ``coefs[i][r, c]`` multiplies channel ``c`` at lag ``i + 1`` in
        the equation of channel ``r``.
    params : ndarray, shape (df_eq, s)
        Regression coefficients, one column per equation, rows ``[const, lag-1 block, lag-2 block, ...]``.
    sigma : ndarray, shape (s, s)
        Maximum-likelihood residual covariance ``E'E / nobs`` (statsmodels' ``sigma_u_mle``).
    """

    @property
    def params(self) -> np.ndarray:
        return self._params2d

    @property
    def coefs(self) -> np.ndarray:
        return self._ar_matrices()

    @property
    def intercept(self) -> np.ndarray:
        return self._params2d[0].copy() if self.model.k_const else np.zeros(self.neqs)

    @property
    def sigma(self) -> np.ndarray:
        return self._sse / self.nobs

    def residuals(self, y: Any) -> Any:
        """One-step prediction errors of a new vector signal through the fixed model.

        ``e[t] = y[t] + sum_i A_i y[t-i] - c`` for ``t = lags .. len(y) - 1``.

        Returns
        -------
        Same kind as ``y``, shape ``(len(y) - lags, s)``, index starting at position ``lags``.
        """
        sig = self._new_signal(y)
        return sig.wrap(self._residuals_array(sig.values, None), self.lags)

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
            Innovation covariance (default :attr:`sigma`).
        """
        nobs = int_like(nobs, "nobs", minimum=1)
        burn = 10 * self.lags + 100 if burn is None else int_like(burn, "burn", minimum=0)
        rng = check_rng(rng)
        s, p = self.neqs, self.lags
        cov = self.sigma if sigma is None else np.asarray(sigma, dtype=float)
        e = rng.multivariate_normal(np.zeros(s), cov, size=nobs + burn, method="cholesky") + self.intercept
        return _simulate_var(self.coefs, e)[burn:]


def _simulate_var(coefs: np.ndarray, e: np.ndarray) -> np.ndarray:
    """``y[t] = e[t] - sum_i A_i y[t-i]`` with zero initial conditions."""
    p, s, _ = coefs.shape
    n = e.shape[0]
    y = np.zeros((n + p, s))
    Aflat = np.concatenate(list(coefs[::-1]), axis=1)   # [A_p ... A_1], (s, p s)
    for t in range(n):
        y[t + p] = e[t] - Aflat @ y[t:t + p].ravel()
    return y[p:]


VAR.results_class = VARResults

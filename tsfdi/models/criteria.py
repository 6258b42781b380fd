"""Information criteria and fit measures of least-squares time-series fits (paper 003 eqs. 5-6).

One function, :func:`information_criteria`, evaluates them for one fit (the results objects of
:mod:`tsfdi.models`) or for many nested fits at once (:func:`tsfdi.select_order`), so both use the same
formulas.
"""

from __future__ import annotations

import numpy as np

__all__ = ["information_criteria"]


def information_criteria(sse: np.ndarray, sss: float, nobs: int, df_model: np.ndarray, neqs: int,
                         criterion: str = "logdet") -> dict[str, np.ndarray]:
    """Fit criteria of one or several fits of an ``s``-channel linear time-series model.

    Parameters
    ----------
    sse : ndarray, shape (q, s, s)
        Residual cross-product matrices ``E'E`` of ``q`` fits.
    sss : float
        Signal sum of squares ``sum_t y[t]' y[t]`` over the estimation sample.
    nobs : int
        Number of residuals ``N``.
    df_model : ndarray, shape (q,)
        Number of regression coefficients ``d`` of each fit (all equations).
    neqs : int
        Number of channels ``s``.
    criterion : {"logdet", "trace"}
        How a vector model's residual covariance enters the BIC: its log-determinant (the likelihood,
        statsmodels' ``VAR``) or the log of its trace (paper 003, "Vector AR Identification Method").
        Identical for ``s = 1``.

    Returns
    -------
    dict of ndarray
        ``llf``, ``aic``, ``bic``, ``rss_sss`` (percent), ``spp``, ``sigma2``.

    Notes
    -----
    With ``Sigma = E'E / N`` and ``k = d + s (s + 1) / 2`` free parameters (the noise covariance counted),

    .. math::

        \\ell = -\\tfrac{N}{2}\\,(s \\ln 2\\pi + \\ln\\det\\Sigma + s), \\quad
        \\mathrm{AIC} = -2\\ell + 2k, \\quad \\mathrm{BIC} = -2\\ell + k \\ln N .

    ``BIC / N = ln sigma_e^2 + k ln N / N + const`` is paper 003's eq. 5 (the constant ``ln 2 pi + 1`` does
    not depend on the order, so both select the same order). The trace variant uses
    ``N (ln(2 pi tr Sigma) + 1) + k ln N``. ``RSS/SSS = 100 sum e'e / sum y'y`` is eq. 6 in percent;
    ``SPP = N s / d`` (paper 003 Table 2 uses the signal length for ``N``). ``sigma2`` is ``tr Sigma / s``.
    """
    sse = np.asarray(sse, dtype=float)
    df_model = np.asarray(df_model, dtype=float)
    sigma = sse / nobs
    s = neqs
    _, logdet = np.linalg.slogdet(sigma)
    trace = np.trace(sigma, axis1=-2, axis2=-1)
    llf = -0.5 * nobs * (s * np.log(2 * np.pi) + logdet + s)
    k = df_model + s * (s + 1) / 2
    fit_term = -2 * llf if criterion == "logdet" else nobs * (np.log(2 * np.pi * trace) + 1)
    return {
        "llf": llf,
        "aic": -2 * llf + 2 * k,
        "bic": fit_term + k * np.log(nobs),
        "rss_sss": 100.0 * nobs * trace / sss,
        "spp": nobs * s / df_model,
        "sigma2": trace / s,
    }

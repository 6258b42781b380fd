"""Information criteria and fit measures of least-squares time-series fits (paper 003 eqs. 5-6).

One function, :func:`information_criteria`, evaluates them for one fit (the results objects of
:mod:`tsfdi.models`) or for many nested fits at once (:func:`tsfdi.select_order`), so both use the same
formulas.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["information_criteria", "EXACT_FIT_RTOL", "COLLINEAR_RTOL"]

#: residual RMS, relative to a channel's largest magnitude, below which a fit counts as exact (to rounding)
EXACT_FIT_RTOL = 1e-12
#: eigenvalue of a residual covariance, relative to its largest, below which the decomposition does not resolve
#: it (channels whose residuals are collinear to rounding)
COLLINEAR_RTOL = 1e-12


def information_criteria(sse: np.ndarray, sss: np.ndarray, nobs: int, df_model: np.ndarray, neqs: int,
                         criterion: str = "logdet", *, scale: np.ndarray | None = None,
                         peak: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Fit criteria of one or several fits of an ``s``-channel linear time-series model.

    Parameters
    ----------
    sse : ndarray, shape (q, s, s)
        Residual cross-product matrices ``E'E`` of ``q`` fits, in the units of the fit: channel ``j`` divided
        by ``scale[j]``.
    sss : float or ndarray, shape (s,)
        Signal sum of squares ``sum_t y_j[t]^2`` of each channel over the estimation sample (same units).
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
    scale : ndarray, shape (s,), optional
        The unit of each channel in ``sse`` and ``sss`` (a power of two; default: the data's own units): the
        criteria are those of the data in its own units, computed without forming ``scale**2 * sse`` (which
        may leave the floating-point range).
    peak : ndarray, shape (s,), optional
        Largest magnitude of each channel in the data's units (default ``scale``); sets the exact-fit floor.

    Returns
    -------
    dict of ndarray
        ``llf``, ``aic``, ``bic``, ``hqic``, ``rss_sss`` (percent), ``spp``, ``sigma2`` (data units) and ``exact``
        (bool: the fit's residual covariance reached the floor below).

    Notes
    -----
    With ``Sigma = E'E / N`` and ``k = d + s (s + 1) / 2`` free parameters (the noise covariance counted),

    .. math::

        \\ell = -\\tfrac{N}{2}\\,(s \\ln 2\\pi + \\ln\\det\\Sigma + s), \\quad
        \\mathrm{AIC} = -2\\ell + 2k, \\quad \\mathrm{BIC} = -2\\ell + k \\ln N, \\quad
        \\mathrm{HQIC} = -2\\ell + 2k \\ln \\ln N

    (HQIC: Hannan and Quinn, 1979, in the likelihood form of statsmodels ``AutoReg``, whose ``k`` also counts the
    noise variance; statsmodels ``VAR`` reports ``ln det Sigma + 2 d ln ln N / N``, the same criterion divided by
    ``N`` without the terms that do not depend on the order).

    ``BIC / N = ln sigma_e^2 + k ln N / N + const`` is paper 003's eq. 5 (the constant ``ln 2 pi + 1`` does
    not depend on the order, so both select the same order). The trace variant uses
    ``N (ln(2 pi tr Sigma) + 1) + k ln N``. ``RSS/SSS = 100 sum e'e / sum y'y`` is eq. 6 in percent (0 when
    the estimation sample is all zeros); ``SPP = N s / d`` (paper 003 Table 2 uses the signal length for
    ``N``). ``sigma2`` is ``tr Sigma / s``.

    **Exact fits.** When the residuals vanish to rounding (a deterministic signal: a ramp, a sinusoid, an
    exact recursion) or the channels are collinear, ``Sigma`` is singular and the likelihood is unbounded
    (``llf = +inf``). A residual RMS below ``EXACT_FIT_RTOL = 1e-12`` times a channel's peak carries no
    information beyond rounding, so ``Sigma``'s eigenvalues (each channel measured in units of
    ``1e-12 * peak``) are floored at 1, and at ``COLLINEAR_RTOL = 1e-12`` times the largest one (below it an
    eigenvalue is rounding), and ``tr Sigma``'s terms at the first floor: ``llf``, ``aic`` and ``bic`` stay
    finite and reproducible, every exact order gets the same fit term, and the BIC penalty picks the smallest
    exact order. ``exact`` flags those fits; the callers warn.
    """
    sse = np.asarray(sse, dtype=float)
    df_model = np.asarray(df_model, dtype=float)
    s = neqs
    own = scale is None                                     # the data's own units: no weights
    peak = (np.ones(s) if own else scale) if peak is None else peak
    floor = (EXACT_FIT_RTOL * peak) ** 2 if own else (EXACT_FIT_RTOL * (peak / scale)) ** 2   # units of the fit
    sss = np.asarray(sss, dtype=float)
    sigma = sse / nobs
    var = sigma.diagonal(axis1=-2, axis2=-1)               # (q, s)
    if s == 1:
        v0, f0 = var[:, 0], float(floor[0])
        exact = v0 < f0
        logdet = np.log(np.maximum(v0, f0))
    else:   # the smallest eigenvalue is >= det / tr^(s-1), and >= det / tr^s times the largest: only the fits
        # that fail these bounds (against the largest floor) are decomposed, in units of the floor
        tr = var.sum(axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):   # a singular Sigma: -inf, replaced below
            sign, logdet = np.linalg.slogdet(sigma)
            log_tr = np.log(tr)
            exact = ~((sign > 0) & (logdet - (s - 1) * log_tr > np.log(floor.max()))
                      & (logdet - s * log_tr > math.log(COLLINEAR_RTOL)))
        if exact.any():
            root = np.sqrt(floor)
            lam = np.linalg.eigvalsh(sigma[exact] / root[:, None] / root[None, :])
            low = np.maximum(1.0, COLLINEAR_RTOL * lam.max(axis=-1, keepdims=True))
            logdet[exact] = np.log(np.maximum(lam, low)).sum(axis=-1) + np.log(floor).sum()
            exact[exact] = (lam < low).any(axis=-1)
    any_exact = exact.any()
    if own:
        top = 1.0
        resid_ss = var[:, 0] if s == 1 else tr                  # tr Sigma
        sss_w = float(sss[0]) if sss.size == 1 else float(sss.sum())
        trace = np.maximum(var, floor).sum(axis=-1) if any_exact else resid_ss
    else:   # tr Sigma and tr Y'Y in data units, as top^2 * (sum of (scale / top)^2-weighted terms)
        logdet = logdet + 2 * np.log(scale).sum()
        top = scale.max()
        w = (scale / top) ** 2
        resid_ss = np.sum(var * w, axis=-1)
        sss_w = float(np.sum(sss * w))
        trace = np.sum(np.maximum(var, floor) * w, axis=-1) if any_exact else resid_ss
    # (scalar logarithms and factors by math / floats, one array operation per term: numpy's scalar calls and the
    # operations on these short arrays cost more than the arithmetic)
    m2llf = nobs * logdet + nobs * (s * math.log(2 * math.pi) + s)          # -2 llf
    k = df_model + s * (s + 1) / 2
    fit_term = m2llf if criterion == "logdet" else nobs * (np.log(2 * np.pi * trace) + 2 * math.log(top) + 1)
    return {
        "llf": -0.5 * m2llf,
        "aic": m2llf + 2 * k,
        "bic": fit_term + k * math.log(nobs),
        "hqic": m2llf + k * (2 * math.log(math.log(nobs))),
        "rss_sss": resid_ss * (100.0 * nobs / sss_w) if sss_w > 0 else np.zeros(len(sse)),
        "spp": (nobs * s) / df_model,
        "sigma2": resid_ss * (top * top / s),
        "exact": exact,
    }

"""Information criteria and fit measures of least-squares time-series fits (paper 003 eqs. 5-6).

One function, :func:`information_criteria`, evaluates them for one fit (the results objects of
:mod:`tsfdi.models`) or for many nested fits at once (:func:`tsfdi.select_order`), so both use the same
formulas.
"""

from __future__ import annotations

import math

import numba
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
    own = scale is None                                     # the data's own units: no weights
    peak = np.asarray((np.ones(neqs) if own else scale) if peak is None else peak, dtype=float)
    sse = np.asarray(sse, dtype=float)
    q = sse.shape[0]
    out = np.empty((7, q))
    exact = np.empty(q, dtype=np.bool_)
    # sss copied: a read-only or strided view (a Gram matrix's diagonal) would make numba build a second signature
    _criteria_kernel(sse, np.array(sss, dtype=float).reshape(-1), float(nobs),
                     np.array(df_model, dtype=float).reshape(-1), peak, peak if own else np.asarray(scale, dtype=float),
                     own, criterion == "logdet", out, exact)
    llf, aic, bic, hqic, rss_sss, spp, sigma2 = out
    return {"llf": llf, "aic": aic, "bic": bic, "hqic": hqic, "rss_sss": rss_sss, "spp": spp, "sigma2": sigma2,
            "exact": exact}


@numba.njit(cache=True, error_model="numpy")
def _criteria_kernel(sse, sss, nobs, df_model, peak, scale, own, logdet_bic, out, exact):  # pragma: no cover
    """:func:`information_criteria` in one compiled pass over the fits (numpy's small-array calls cost far more than
    the arithmetic): rows ``llf, aic, bic, hqic, rss_sss, spp, sigma2`` of ``out`` and ``exact`` (``scale`` is not read
    when ``own``).

    A vector model's ``ln det Sigma`` comes from its Cholesky factor; the fits whose factor fails or whose
    log-determinant fails the bounds ``det / tr^(s-1) > max(floor)`` and ``det / tr^s > COLLINEAR_RTOL`` (the
    smallest eigenvalue is at least ``det / tr^(s-1)``, and ``det / tr^s`` times the largest) are decomposed in units
    of the floor, as the docstring of :func:`information_criteria` says."""
    q, s = sse.shape[0], sse.shape[1]
    floor = np.empty(s)                     # the exact-fit floor of each channel's variance, in the units of the fit
    for a in range(s):
        f = EXACT_FIT_RTOL * peak[a] if own else EXACT_FIT_RTOL * (peak[a] / scale[a])
        floor[a] = f ** 2
    var = np.empty((q, s))
    logdet = np.empty(q)
    for r in range(q):
        for a in range(s):
            var[r, a] = sse[r, a, a] / nobs
    if s == 1:
        f0 = floor[0]
        for r in range(q):
            v0 = var[r, 0]
            exact[r] = v0 < f0
            logdet[r] = np.log(f0 if v0 < f0 else v0)
    else:
        log_floor_max = np.log(floor.max())
        log_floor_sum = np.log(floor).sum()
        root = np.sqrt(floor)
        L = np.empty((s, s))
        for r in range(q):
            sigma = sse[r] / nobs
            tr = var[r].sum()
            ok = True                       # Cholesky factor of sigma: ln det = 2 sum ln L[i, i]
            ld = 0.0
            for i in range(s):
                for j in range(i + 1):
                    acc = sigma[i, j]
                    for k in range(j):
                        acc -= L[i, k] * L[j, k]
                    if i == j:
                        if not acc > 0.0:
                            ok = False
                            break
                        L[i, i] = np.sqrt(acc)
                        ld += np.log(acc)
                    else:
                        L[i, j] = acc / L[j, j]
                if not ok:
                    break
            log_tr = np.log(tr)
            exact[r] = not (ok and ld - (s - 1) * log_tr > log_floor_max and ld - s * log_tr > math.log(COLLINEAR_RTOL))
            if exact[r]:
                scaled = np.empty((s, s))
                for i in range(s):
                    for j in range(s):
                        scaled[i, j] = sigma[i, j] / root[i] / root[j]
                with numba.objmode(lam="float64[:]"):      # rare: numpy's (a compiled eigvalsh costs seconds to build)
                    lam = np.linalg.eigvalsh(scaled)
                low = max(1.0, COLLINEAR_RTOL * lam.max())
                ld = log_floor_sum
                exact[r] = False
                for lv in lam:
                    ld += np.log(lv if lv > low else low)
                    exact[r] = exact[r] or lv < low
            logdet[r] = ld
    any_exact = exact.any()
    top = 1.0
    if not own:         # tr Sigma and tr Y'Y in data units, as top^2 * (sum of (scale / top)^2-weighted terms)
        log_scale = 2 * np.log(scale).sum()
        for r in range(q):
            logdet[r] += log_scale
        top = scale.max()
    w = (scale / top) ** 2
    sss_w = 0.0
    for a in range(s):
        sss_w += sss[a] if own else sss[a] * w[a]
    const = s * math.log(2 * math.pi) + s
    log_n = math.log(nobs)
    hq = 2 * math.log(log_n)
    for r in range(q):
        resid_ss = 0.0
        trace = 0.0
        for a in range(s):
            v = var[r, a]
            resid_ss += v if own else v * w[a]
            vf = v if v > floor[a] else floor[a]
            trace += vf if own else vf * w[a]
        if not any_exact:
            trace = resid_ss
        m2llf = nobs * logdet[r] + nobs * const                    # -2 llf
        k = df_model[r] + s * (s + 1) / 2
        fit_term = m2llf if logdet_bic else nobs * (np.log(2 * np.pi * trace) + 2 * math.log(top) + 1)
        out[0, r] = -0.5 * m2llf
        out[1, r] = m2llf + 2 * k
        out[2, r] = fit_term + k * log_n
        out[3, r] = m2llf + k * hq
        out[4, r] = resid_ss * (100.0 * nobs / sss_w) if sss_w > 0 else 0.0
        out[5, r] = (nobs * s) / df_model[r]
        out[6, r] = resid_ss * (top * top / s)

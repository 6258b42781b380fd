"""Shared kernels of the linear time-series models: regressors, least squares, nested fits.

All models of :mod:`tsfdi.models` are linear regressions of ``y[t]`` on lagged outputs and inputs:

.. math::

    y[t] = c - \\sum_{i=1}^{n_a} A_i\\, y[t-i] + \\sum_{j=1}^{n_b} B_j\\, u[t-n_k-j+1] + e[t],

so the regressor of lag ``i`` is ``-y[t-i]`` and the least-squares coefficients come out directly in the
papers' sign convention (``y[t] + sum a_i y[t-i] = e[t]``, paper 003 eqs. 4 and 7).

The regressor columns are grouped by lag (``[const, group 1, group 2, ...]``), so the fit of every lower
order uses a leading block of the same columns. One triangular factor ``R`` of ``[X | Y]`` therefore gives
the residual sums of squares of *all* orders at once (see :func:`nested_fits`).
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy import linalg

from tsfdi.exceptions import IllConditionedWarning

__all__ = ["lagged_design", "lstsq", "lag_gram", "triangular_factor", "nested_fits"]

#: condition number of the regressor above which a fit warns (digits left < ~6)
COND_WARN = 1e10
#: smallest fraction of a Gram column's energy left unexplained by the columns before it for which the
#: Cholesky route is trusted; below it the factor is recomputed by QR of the regressor itself.
GRAM_RELATIVE_FLOOR = 1e-9


def lagged_design(y: np.ndarray, lags: int, start: int, *, const: bool, u: np.ndarray | None = None,
                  nb: int = 0, nk: int = 0, max_group: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Regressor and target of a lag-grouped linear time-series regression.

    Parameters
    ----------
    y : ndarray, shape (n, s)
        Output signal.
    lags : int
        Number of output lags ``na``.
    start : int
        First sample used as a target (``>=`` the largest lag used).
    const : bool
        Include a column of ones first.
    u : ndarray, shape (n, m), optional
        Input signal; ``nb`` terms per input starting at delay ``nk``.
    max_group : int, optional
        Number of lag groups (defaults to ``max(lags, nb)``). Group ``g`` (1-based) holds ``-y[t-g]``
        (if ``g <= lags``) then ``u[t-nk-g+1]`` (if ``g <= nb``).

    Returns
    -------
    X : ndarray, shape (n - start, k)
    Y : ndarray, shape (n - start, s)
    """
    n = y.shape[0]
    rows = n - start
    groups = max(lags, nb) if max_group is None else max_group
    cols = [np.ones((rows, 1))] if const else []
    for g in range(1, groups + 1):
        if g <= lags:
            cols.append(-y[start - g:n - g])
        if u is not None and g <= nb:
            d = nk + g - 1
            cols.append(u[start - d:n - d])
    X = np.concatenate(cols, axis=1) if cols else np.empty((rows, 0))
    return X, y[start:]


def lstsq(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Least squares by LAPACK ``gelsd`` (SVD based, never the normal equations).

    Warns with :class:`~tsfdi.exceptions.IllConditionedWarning` when ``X`` is rank deficient or its
    condition number exceeds ``1e10``; the minimum-norm solution is returned in that case.
    """
    coef, _, rank, sv = linalg.lstsq(X, Y, lapack_driver="gelsd", check_finite=False)
    if X.shape[1]:
        cond = sv[0] / sv[-1] if sv[-1] > 0 else np.inf
        if rank < X.shape[1] or cond > COND_WARN:
            warnings.warn(f"the regressor is ill-conditioned (rank {rank} of {X.shape[1]}, condition number "
                          f"{cond:.3g}); the estimates are not reliable", IllConditionedWarning, stacklevel=3)
    return coef


def lag_gram(y: np.ndarray, lags: int, *, const: bool) -> np.ndarray:
    """Gram matrix of ``[const, -y[t-1], ..., -y[t-lags], y[t]]`` over ``t = lags .. n-1`` in O(n * lags).

    The lag-product blocks are Toeplitz up to end effects: with
    ``C_k = sum_{u=k}^{n-1} y[u] y[u-k]'`` the block of lags ``(i, j)``, ``i <= j``, ``k = j - i`` is

    .. math::  \\sum_{t=p}^{n-1} y[t-i]\\, y[t-j]' = C_k - H_k(p - i) - T_k(n - i),

    where ``H`` removes the products before the sample (``u < p - i``) and ``T`` those after it
    (``u >= n - i``). Both only involve the first and last ``p`` samples, so the cost is ``p + 1`` lag
    products over the signal plus ``O(p^2 s^2)`` corrections, instead of ``O(n p^2 s^2)`` for ``X'X``.

    Parameters
    ----------
    y : ndarray, shape (n, s)
    lags : int
        Largest lag ``p`` (``n > 2 p`` is required).
    const : bool
        Prepend the intercept column.

    Returns
    -------
    ndarray, shape (c + (p + 1) s, c + (p + 1) s)
        Column order ``[const, lag 1 block, ..., lag p block, y[t] block]``; lag blocks carry the minus
        sign of the regressor.
    """
    n, s = y.shape
    p = lags
    # full lag products C[k] = sum_{u=k}^{n-1} y[u] y[u-k]'
    C = np.empty((p + 1, s, s))
    for k in range(p + 1):
        C[k] = y[k:].T @ y[:n - k]
    # products y[u] y[u-k]' for u in the first p samples (head) and the last p samples (tail)
    k_idx = np.arange(p + 1)[:, None]
    u_head = np.arange(p)[None, :]
    valid = u_head >= k_idx
    head = y[u_head][..., :, None] * y[np.where(valid, u_head - k_idx, 0)][..., None, :]
    head[~valid] = 0.0
    u_tail = np.arange(n - p, n)[None, :]
    tail = y[u_tail][..., :, None] * y[u_tail - k_idx][..., None, :]
    zero = np.zeros((p + 1, 1, s, s))
    Hc = np.concatenate([zero, np.cumsum(head, axis=1)], axis=1)           # Hc[k, e] = sum_{u<e} (head)
    Tc = np.concatenate([np.cumsum(tail[:, ::-1], axis=1)[:, ::-1], zero], axis=1)  # Tc[k, b] = sum_{u>=n-p+b}
    I, J = np.triu_indices(p + 1)
    K = J - I
    blocks = C[K] - Hc[K, p - I] - Tc[K, p - I]
    G4 = np.empty((p + 1, p + 1, s, s))
    G4[I, J] = blocks
    G4[J, I] = np.swapaxes(blocks, -1, -2)
    # reorder lag index: 0 (y[t]) goes last; lag blocks i >= 1 take the regressor sign (-1)
    order = np.r_[1:p + 1, 0]
    sign = np.r_[-np.ones(p), 1.0]
    G4 = G4[order][:, order] * (sign[:, None] * sign[None, :])[:, :, None, None]
    G = G4.transpose(0, 2, 1, 3).reshape((p + 1) * s, (p + 1) * s)
    if not const:
        return G
    cs = np.concatenate([np.zeros((1, s)), np.cumsum(y, axis=0)])
    lag_sums = np.stack([cs[n - i] - cs[p - i] for i in order]) * sign[:, None]
    out = np.empty((G.shape[0] + 1, G.shape[0] + 1))
    out[0, 0] = n - p
    out[0, 1:] = out[1:, 0] = lag_sums.ravel()
    out[1:, 1:] = G
    return out


def triangular_factor(gram: np.ndarray | None, design: callable, n_targets: int = 1) -> np.ndarray:
    """Upper-triangular ``R`` with ``R'R = Z'Z`` from the Gram matrix, or by QR when that loses digits.

    The Cholesky factor of the Gram matrix squares the condition number. When a diagonal entry of ``R``
    shows that a column keeps less than ``GRAM_RELATIVE_FLOOR`` of its energy after projection on the
    columns before it (or the factorisation fails), ``R`` is recomputed from a QR decomposition of the
    explicit regressor ``design()``, which is backward stable, and a warning is given if that regressor
    (its first ``R.shape[0] - n_targets`` columns) is ill-conditioned.
    """
    if gram is not None:
        try:
            R = linalg.cholesky(gram, lower=False, check_finite=False)
            rel = np.diag(R) ** 2 / np.diag(gram)
            if np.all(np.isfinite(R)) and rel.min() > GRAM_RELATIVE_FLOOR:
                return R
        except linalg.LinAlgError:
            pass
    Z = design()
    R = linalg.qr(Z, mode="r", check_finite=False)[0][: Z.shape[1]]
    m = R.shape[0] - n_targets
    if m:
        cond = np.linalg.cond(R[:m, :m])
        if not cond < COND_WARN:
            warnings.warn(f"the regressor of the largest order is ill-conditioned (condition number {cond:.3g}); "
                          "criteria of the highest orders are not reliable", IllConditionedWarning, stacklevel=3)
    return R


def nested_fits(R: np.ndarray, n_targets: int, widths: np.ndarray) -> np.ndarray:
    """Residual cross-product matrices of the nested fits that use the first ``widths[q]`` columns.

    With ``Z = [X | Y] = Q R``, the residual of ``Y`` regressed on the first ``k`` columns of ``X`` has
    cross-product ``R[k:, m:]' R[k:, m:]`` where ``m`` is the number of regressor columns.

    Returns
    -------
    ndarray, shape (len(widths), s, s)
    """
    m = R.shape[0] - n_targets
    Rt = R[:, m:]
    # suffix sums of outer products of the rows of R[:, m:]
    outer = Rt[:, :, None] * Rt[:, None, :]
    suffix = np.cumsum(outer[::-1], axis=0)[::-1]
    return suffix[np.asarray(widths)]

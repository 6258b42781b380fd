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

import numba
import numpy as np
from scipy import linalg
from scipy.linalg import lapack

from tsfdi._validation import MAX_VALUES
from tsfdi.exceptions import IllConditionedWarning

__all__ = ["lagged_design", "lstsq", "lag_gram", "cholesky_nested_fits",
           "lag_residual_products", "triangular_factor", "nested_fits", "gram_factor",
           "gram_solve", "check_size", "MAX_VALUES"]

#: condition number of the regressor above which a fit warns (digits left < ~6)
COND_WARN = 1e10
#: smallest fraction of a Gram column's energy left unexplained by the columns before it for which the
#: Cholesky route is trusted; below it the factor is recomputed by QR of the regressor itself.
GRAM_RELATIVE_FLOOR = 1e-9


def check_size(n_values: int, what: str) -> None:
    """Raise ``ValueError`` when an array of ``n_values`` float64 values would exceed :data:`MAX_VALUES`.

    ``what`` names the arguments that set the size and the array, e.g. ``"lags=5000 on 10,000,000 samples:
    the regressor (9,995,000 x 5,000)"``; the message adds the size and the limit.
    """
    if n_values > MAX_VALUES:
        raise ValueError(f"{what} would hold {n_values:,} values ({n_values * 8 / 2**30:,.3g} GiB), more than the "
                         f"limit of {MAX_VALUES:,} values (2 GiB)")


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
    condition number exceeds ``1e10``; the minimum-norm solution is returned in that case. ``X`` and ``Y`` must
    be finite; a singular value decomposition that does not converge raises ``ValueError`` (naming ``y``).
    """
    try:
        coef, _, rank, sv = linalg.lstsq(X, Y, lapack_driver="gelsd", check_finite=False)
    except (linalg.LinAlgError, ValueError):
        raise ValueError(f"y: the least-squares solver did not converge on the {X.shape[0]} x {X.shape[1]} "
                         "regressor (a numerically degenerate signal)") from None
    if X.shape[1]:
        with np.errstate(over="ignore"):
            cond = sv[0] / sv[-1] if sv[-1] > 0 else np.inf
        if rank < X.shape[1] or cond > COND_WARN:
            warnings.warn(f"the regressor is ill-conditioned (rank {rank} of {X.shape[1]}, condition number "
                          f"{cond:.3g}); the estimates are not reliable", IllConditionedWarning, stacklevel=3)
    return coef


def lag_gram(y: np.ndarray | list[np.ndarray], lags: int, *, const: bool) -> np.ndarray:
    r"""Gram matrix of ``[const, -y[t-1], ..., -y[t-lags], y[t]]`` over ``t = lags .. n-1`` in O(n * lags).

    The lag-product blocks are Toeplitz up to end effects. With ``L[i, j] = sum_{t=p}^{n-1} y[t-i] y[t-j]'``
    (lag space, ``i, j = 0..p``), the first block row follows from the full lag products
    ``C_k = sum_{u=k}^{n-1} y[u] y[u-k]'`` less the ``u < p`` terms, and shifting
    the summation window by one sample gives

    .. math::  L[i+1, j+1] = L[i, j] + y[p-1-i]\, y[p-1-j]' - y[n-1-i]\, y[n-1-j]' .

    The cost is the ``p + 1`` lag products over the signal plus ``O(p^2 s^2)`` for the recursion (compiled
    kernels), instead of ``O(n p^2 s^2)`` for ``X'X``. For a list of records (the sum of their Gram
    matrices) the lag products come from the records end to end with ``p`` zero samples between two, and the
    end corrections are summed over the records. The lag products are dot products of contiguous channel rows
    summed in SIMD order (:func:`_direct_lag_products`).

    Parameters
    ----------
    y : ndarray, shape (n, s), or a list of them
        The signal, or records of it (each ``n > p`` samples).
    lags : int
        Largest lag ``p`` (``n > p``).
    const : bool
        Prepend the intercept column.

    Returns
    -------
    ndarray, shape (c + (p + 1) s, c + (p + 1) s)
        Column order ``[const, lag 1 block, ..., lag p block, y[t] block]``; lag blocks carry the minus
        sign of the regressor.
    """
    x, starts, ends = _channel_rows(y if isinstance(y, list) else [y], lags)
    out = np.empty((int(const) + (lags + 1) * x.shape[0],) * 2)
    _lag_gram_kernel(x, starts, ends, lags, bool(const), out)
    return out


def cholesky_nested_fits(gram: np.ndarray, n_targets: int, widths: np.ndarray) -> np.ndarray | None:
    """:func:`nested_fits` of the Cholesky factor of ``gram`` in compiled code, or ``None`` when that factor loses
    digits (the caller then factors the explicit regressor: :func:`triangular_factor` with no Gram matrix).

    The factor comes from :func:`_cholesky_upper` (equal to LAPACK's ``potrf`` to rounding, faster at the sizes of
    order selection), accepted only when every column keeps more than ``GRAM_RELATIVE_FLOOR`` of its energy after
    projection on the columns before it (the check of :func:`triangular_factor`).

    Parameters
    ----------
    gram : ndarray, shape (m + s, m + s)
        Gram matrix of ``[X | Y]`` (``s = n_targets``).
    n_targets : int
        Number of target columns ``s``.
    widths : ndarray of int, increasing
        The nested fits' numbers of regressor columns.

    Returns
    -------
    ndarray, shape (len(widths), s, s), or None
    """
    widths = np.asarray(widths, dtype=np.int64)
    sse = np.empty((widths.size, n_targets, n_targets))
    ok = _cholesky_fits(np.ascontiguousarray(gram, dtype=float), widths, GRAM_RELATIVE_FLOOR,
                        np.empty(gram.shape), sse)
    return sse if ok else None


@numba.njit(cache=True)
def _cholesky_fits(gram, widths, floor, R, sse):  # pragma: no cover - compiled
    """:func:`cholesky_nested_fits`: the upper Cholesky factor ``R`` of ``gram`` (:func:`_cholesky_upper`) and the
    suffix sums of the outer products of the rows of ``R[:, m:]`` (``m`` regressor columns) from row ``widths[q]``
    on into ``sse[q]``; ``False`` when the factor fails the energy check (``sse`` left undefined)."""
    n, s = gram.shape[0], sse.shape[1]
    m = n - s
    if not _cholesky_upper(gram, floor, R):
        return False
    acc = np.zeros((s, s))
    q = widths.shape[0] - 1
    for i in range(n - 1, -1, -1):          # rows of R from the last up, as numpy's cumsum of the reversed rows
        if q < 0:
            break
        for a in range(max(i - m, 0), s):    # R[i, m + a] is zero below the diagonal (m + a < i)
            for b in range(max(i - m, 0), s):
                acc[a, b] += R[i, m + a] * R[i, m + b]
        while q >= 0 and widths[q] == i:
            for a in range(s):
                for b in range(s):
                    sse[q, a, b] = acc[a, b]
            q -= 1
    return True


@numba.njit(cache=True, fastmath={"contract"})
def _cholesky_upper(G, floor, R):  # pragma: no cover - compiled
    """Upper Cholesky factor of ``G`` into the upper triangle of ``R`` (its strict lower triangle is left holding
    ``G``'s), and whether every pivot keeps more than ``floor`` of its column's energy (``R[i, i]**2 > floor *
    G[i, i]``; ``False`` at the first pivot that is not positive, NaN or fails the test: an infinite or NaN entry of
    ``G`` makes a pivot fail, as in :func:`_cholesky`).

    Right-looking in panels of 4 rows: each row of a panel scaled by its pivot and taken off the panel's later rows,
    then the rows below the panel updated by contiguous rank-4 axpys (no dot-product reductions, whose latency
    dominates at these sizes; a quarter of the passes over the trailing rows). Equal to LAPACK's ``potrf`` to
    rounding."""
    n = G.shape[0]
    for i in range(n):                      # (loops, not R[:] = G: a broadcast assignment costs seconds to compile)
        for j in range(n):
            R[i, j] = G[i, j]
    for i0 in range(0, n, 4):
        i1 = min(i0 + 4, n)
        for i in range(i0, i1):
            d = R[i, i]
            if not d > 0.0:
                return False
            r = np.sqrt(d)
            if not r * r > floor * G[i, i]:
                return False
            R[i, i] = r
            inv = 1.0 / r
            Ri = R[i]
            for j in range(i + 1, n):
                Ri[j] *= inv
            for k in range(i + 1, i1):
                f, Rk = Ri[k], R[k]
                for j in range(k, n):
                    Rk[j] -= f * Ri[j]
        if i1 < n:                          # a full panel: rank-4 update of the rows below
            R0, R1, R2, R3 = R[i0], R[i0 + 1], R[i0 + 2], R[i0 + 3]
            for k in range(i1, n):
                f0, f1, f2, f3, Rk = R0[k], R1[k], R2[k], R3[k], R[k]
                for j in range(k, n):
                    Rk[j] -= f0 * R0[j] + f1 * R1[j] + f2 * R2[j] + f3 * R3[j]
    return True


def _channel_rows(records: list[np.ndarray], lags: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The records' channels as contiguous rows, the records end to end with ``lags`` zero samples between two (no
    product of samples at most ``lags`` apart pairs two records), and where each record starts and ends: the layout
    of the compiled kernels of :func:`lag_gram` and :func:`lag_residual_products`. One record is a view when it
    can be (short inputs pay for every call here)."""
    r = records[0]
    s = r.shape[1]
    if len(records) == 1:
        x = r.reshape(1, -1) if s == 1 and r.flags.c_contiguous else np.ascontiguousarray(r.T)
        bounds = np.array([0, r.shape[0]], dtype=np.int64)
        return x, bounds[:1], bounds[1:]
    x = np.zeros((s, sum(r.shape[0] for r in records) + lags * (len(records) - 1)))
    starts, ends = np.empty(len(records), dtype=np.int64), np.empty(len(records), dtype=np.int64)
    pos = 0
    for i, r in enumerate(records):
        x[:, pos:pos + r.shape[0]] = r.T
        starts[i], ends[i] = pos, pos + r.shape[0]
        pos += r.shape[0] + lags
    return x, starts, ends


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def _lag_gram_kernel(x, starts, ends, p, const, out):  # pragma: no cover - compiled
    """:func:`lag_gram` of the records ``x[:, starts[r]:ends[r]]`` (channel rows, :func:`lag_gram`'s layout): the
    full lag products and sums (:func:`_direct_lag_products`), each record's first / last ``p`` samples latest
    first (``hr[r, i s + a] = x[a, starts[r] + p - 1 - i]``, ``tr`` the same at the end) and the assembly
    (:func:`_assemble_gram`), in one call."""
    s = x.shape[0]
    nrec = starts.shape[0]
    C = np.empty((p + 1, s, s))
    S0 = np.empty(s)
    _direct_lag_products(x, p, C, S0)
    hr = np.empty((nrec, p * s))
    tr = np.empty((nrec, p * s))
    rows = (ends - starts).sum() - nrec * p     # (not a loop from a literal 0: numba would compile twice)
    for r in range(nrec):
        for i in range(p):
            for a in range(s):
                hr[r, i * s + a] = x[a, starts[r] + p - 1 - i]
                tr[r, i * s + a] = x[a, ends[r] - 1 - i]
                S0[a] -= hr[r, i * s + a]      # sum_t y[t] over the regression rows: less each record's first p
    _assemble_gram(C, hr, tr, S0, rows, const, out)


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def _direct_lag_products(x, p, C, S):  # pragma: no cover - compiled
    """``C[k, a, b] = sum_u x[a, u] x[b, u - k]`` for ``k = 0..p`` and ``S[a] = sum_u x[a, u]`` of the channel rows
    ``x`` (shape (s, n), contiguous): dot products of contiguous rows, four lags and two lagged rows per pass
    (:func:`_lag_pass`: the products are load-bound, and each loaded sample serves up to eight of them), their sums
    reassociated so that they run in SIMD lanes (the operands are finite: the models check their data), ~1e-16
    relative from the sums in order."""
    s, n = x.shape
    for a in range(s):
        acc = 0.0
        for u in range(n):
            acc += x[a, u]
        S[a] = acc
    for a in range(s):
        for b in range(0, s, 2):
            c = min(b + 1, s - 1)           # the next row, or none (c == b) after the last pair
            _lag_pass(x[a], x[b], x[c], c > b, n, p, C[:, a, b], C[:, a, c])


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def _lag_pass(xa, xb, xc, two, n, p, cb, cc):  # pragma: no cover - compiled
    """``cb[k] = sum_u xa[u + k] xb[u]`` for ``k = 0..p`` and, when ``two``, ``cc[k]`` the same with ``xc``: four lags
    per pass over the samples all four have, then each lag's last samples."""
    k = 0
    while k + 3 <= p and n - k - 3 > 0:
        m = n - k - 3
        b0 = b1 = b2 = b3 = c0 = c1 = c2 = c3 = 0.0
        if two:
            for u in range(m):
                v, w = xb[u], xc[u]
                y0, y1, y2, y3 = xa[u + k], xa[u + k + 1], xa[u + k + 2], xa[u + k + 3]
                b0 += y0 * v
                b1 += y1 * v
                b2 += y2 * v
                b3 += y3 * v
                c0 += y0 * w
                c1 += y1 * w
                c2 += y2 * w
                c3 += y3 * w
        else:
            for u in range(m):
                v = xb[u]
                b0 += xa[u + k] * v
                b1 += xa[u + k + 1] * v
                b2 += xa[u + k + 2] * v
                b3 += xa[u + k + 3] * v
        for u in range(m, n - k):
            b0 += xa[u + k] * xb[u]
            c0 += xa[u + k] * xc[u]
        for u in range(m, n - k - 1):
            b1 += xa[u + k + 1] * xb[u]
            c1 += xa[u + k + 1] * xc[u]
        for u in range(m, n - k - 2):
            b2 += xa[u + k + 2] * xb[u]
            c2 += xa[u + k + 2] * xc[u]
        if two:
            cc[k], cc[k + 1], cc[k + 2], cc[k + 3] = c0, c1, c2, c3
        cb[k], cb[k + 1], cb[k + 2], cb[k + 3] = b0, b1, b2, b3
        k += 4
    while k <= p:
        acc = acc2 = 0.0
        for u in range(n - k):
            acc += xa[u + k] * xb[u]
            acc2 += xa[u + k] * xc[u]
        if two:
            cc[k] = acc2
        cb[k] = acc
        k += 1


@numba.njit(cache=True)
def _assemble_gram(C, hr, tr, S0, rows, const, out):  # pragma: no cover - compiled
    """Fill ``out`` from the full lag products ``C`` (summed over the records) and the first / last ``p`` samples of
    every record, latest first (``hr[r, i s + a] = heads[r, p - 1 - i, a]``, ``tr`` the same of the tails; shape
    (records, p s)); see :func:`lag_gram`.

    In lag space (lag 0 = ``y[t]``), flattened to ``G[i s + a, j s + b] = L[i, j][a, b]``, the first block row is
    ``L[0, k] = C[k] - sum_{u=k}^{p-1} y[u] y[u-k]'`` and ``L[i+1, j+1] = L[i, j] + y[p-1-i] y[p-1-j]' -
    y[n-1-i] y[n-1-j]'`` (shift the window by one sample), each correction summed over the records: the
    recursion is ``G[I + s, J + s] = G[I, J] + D[I, J]`` on flat indices, whole rows at a time from the first block
    row and its mirror (contiguous loops; no fast-math contraction, so ``G`` is exactly symmetric). Lag ``i >= 1``
    goes to block ``i - 1`` with a minus sign, lag 0 to the last block, row by row; the intercept row holds
    ``sum_t y[t-i]`` by the same recursion (``rows`` regression rows).
    """
    nrec, m = hr.shape
    s = S0.shape[0]
    p = m // s
    n = m + s
    c = 1 if const else 0
    G = np.empty((n, n))
    for a in range(s):                      # first block row: C[k] less the heads' own lag products, and its mirror
        for J in range(a, n):
            k, b = J // s, J % s
            acc = C[k, a, b]
            for r in range(nrec):
                for i in range(p - k):
                    acc -= hr[r, i * s + a] * hr[r, i * s + J]
            G[a, J] = acc
            G[J, a] = acc
    for I in range(m):
        GI, GN = G[I], G[I + s]
        for J in range(m):
            GN[J + s] = GI[J]
        for r in range(nrec):
            hI, tI, hrr, trr = hr[r, I], tr[r, I], hr[r], tr[r]
            for J in range(m):
                GN[J + s] += hI * hrr[J] - tI * trr[J]
    for I in range(n):                      # lag i >= 1 -> block i - 1 (minus sign), lag 0 -> the last block
        row = out[c + I - s] if I >= s else out[c + m + I]
        si = -1.0 if I >= s else 1.0
        GI = G[I]
        for J in range(s, n):
            row[c + J - s] = -si * GI[J]
        for b in range(s):
            row[c + m + b] = si * GI[b]
    if const:
        out[0, 0] = rows
        S = S0.copy()                       # S_i = sum_{t=p}^{n-1} y[t-i], summed over the records
        for i in range(p + 1):
            si = 1.0 if i == 0 else -1.0
            col = c + (p if i == 0 else i - 1) * s
            for a in range(s):
                v = si * S[a]
                out[0, col + a] = v
                out[col + a, 0] = v
            if i < p:
                for a in range(s):
                    for r in range(nrec):
                        S[a] += hr[r, i * s + a] - tr[r, i * s + a]


def lag_residual_products(y: np.ndarray | list[np.ndarray], coef: np.ndarray, *, const: bool) -> np.ndarray:
    """``X'(Y - X coef)`` of the lag regression ``[const, -y[t-1], ..., -y[t-p]]`` over ``t = p .. n-1``, summed
    over the records, without the regressor.

    The records end to end (``p`` zero samples between two, as :func:`lag_gram`) give the residuals of all in one
    compiled pass (those of each record's first ``p`` samples and of the gaps set to zero) and their lag products with
    the samples, ``D[k] = sum_t e[t] y[t-k]'``, as dot products of contiguous channel rows summed in SIMD order (as
    :func:`_direct_lag_products`). The block of lag ``k`` is ``-D[k]'``, the intercept row ``sum_t e[t]``. This is
    the right-hand side of a refinement step of the normal equations: accurate to rounding of ``|X| |e|``, where
    ``X'Y - X'X coef`` from the Gram matrix loses the digits of ``|X| |Y|``.
    """
    records = y if isinstance(y, list) else [y]
    s = records[0].shape[1]
    c = int(const)
    p = (coef.shape[0] - c) // s
    x, starts, ends = _channel_rows(records, p)
    out = np.empty((c + p * s, s))
    # (contiguous operands: one compiled signature whatever the layout of coef)
    _residual_products(x, starts, ends, np.ascontiguousarray(coef[c:].reshape(p, s, s)),
                       np.ascontiguousarray(coef[0]) if c else np.zeros(s), c, np.empty_like(x), out)
    return out


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def _residual_products(x, starts, ends, W, c0, c, e, out):  # pragma: no cover - compiled
    """:func:`lag_residual_products` of ``s`` channel rows ``x`` (records end to end, ``p`` zeros between two) with lag
    coefficients ``W[k - 1, a, j]`` (channel ``a`` at lag ``k`` in equation ``j``) and intercepts ``c0``: each
    equation's residuals ``e[j, t] = x[j, t] - c0[j] + sum_{k, a} W[k - 1, a, j] x[a, t - k]`` on each record's rows
    ``starts[r] + p .. ends[r] - 1`` (zero elsewhere) by contiguous passes of four lag terms each, then
    ``sum_t e[j, t]`` and ``-sum_t e[j, t] x[a, t - k]`` by :func:`_lag_pass` (two channels per pass)."""
    s, n = x.shape
    p = W.shape[0]
    m = n - p
    terms = p * s
    cb = np.empty(p + 1)
    cc = np.empty(p + 1)
    for j in range(s):
        ej, xj, cj = e[j], x[j], c0[j]
        for t in range(n):
            ej[t] = xj[t] - cj
        rest = ej[p:]                               # (slices: numba vectorizes the passes on views, not on t - k)
        q = 0
        while q < terms:
            # terms q .. q + 3 (lag q // s + 1, channel q % s); past the last term, zero weights (lags clamped to p)
            k0, k1, k2, k3 = q // s + 1, (q + 1) // s + 1, (q + 2) // s + 1, (q + 3) // s + 1
            a0, a1, a2, a3 = q % s, (q + 1) % s, (q + 2) % s, (q + 3) % s
            w0 = W[k0 - 1, a0, j]
            w1 = W[k1 - 1, a1, j] if q + 1 < terms else 0.0
            w2 = W[k2 - 1, a2, j] if q + 2 < terms else 0.0
            w3 = W[k3 - 1, a3, j] if q + 3 < terms else 0.0
            k1, k2, k3 = min(k1, p), min(k2, p), min(k3, p)
            l0, l1, l2, l3 = x[a0, p - k0:n - k0], x[a1, p - k1:n - k1], x[a2, p - k2:n - k2], x[a3, p - k3:n - k3]
            for i in range(m):
                rest[i] += w0 * l0[i] + w1 * l1[i] + w2 * l2[i] + w3 * l3[i]
            q += 4
        end = 0
        for r in range(starts.shape[0]):            # the gap before each record and its first p samples
            ej[end:starts[r] + p] = 0.0
            end = ends[r]
        if c:
            acc = 0.0
            for t in range(n):
                acc += ej[t]
            out[0, j] = acc
        for a in range(0, s, 2):
            b = min(a + 1, s - 1)                   # the next channel, or none (b == a) after the last pair
            _lag_pass(ej, x[a], x[b], b > a, n, p, cb, cc)
            for k in range(1, p + 1):
                out[c + (k - 1) * s + a, j] = -cb[k]
                if b > a:
                    out[c + (k - 1) * s + b, j] = -cc[k]


def triangular_factor(gram: np.ndarray | None, design: callable, n_targets: int = 1, *,
                      stacklevel: int = 3) -> np.ndarray:
    """Upper-triangular ``R`` with ``R'R = Z'Z`` from the Gram matrix, or by QR when that loses digits.

    The Cholesky factor of the Gram matrix squares the condition number. When a diagonal entry of ``R``
    shows that a column keeps less than ``GRAM_RELATIVE_FLOOR`` of its energy after projection on the
    columns before it (or the factorisation fails), ``R`` is recomputed from a QR decomposition of the
    explicit regressor ``design()``, which is backward stable, and a warning is given if that regressor
    (its first ``R.shape[0] - n_targets`` columns) is ill-conditioned (``stacklevel`` as ``warnings.warn``'s).
    """
    if gram is not None:
        R = _cholesky(gram)
        if R is not None:
            return R
    Z = design()
    R = np.zeros((Z.shape[1], Z.shape[1]))         # square even when Z has fewer rows than columns
    Rq = linalg.qr(Z, mode="r", check_finite=False)[0][: Z.shape[1]]
    R[: Rq.shape[0]] = Rq
    m = R.shape[0] - n_targets
    if m:
        cond = np.linalg.cond(R[:m, :m])
        if not cond < COND_WARN:
            warnings.warn(f"the regressor of the largest order is ill-conditioned (condition number {cond:.3g}); "
                          "criteria of the highest orders are not reliable", IllConditionedWarning,
                          stacklevel=stacklevel)
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


def gram_factor(gram: np.ndarray, k: int) -> np.ndarray | None:
    """Upper Cholesky factor ``R`` of the leading ``k x k`` block of ``gram`` (``R'R = X'X``), or ``None`` when
    the normal equations would lose digits.

    The factor is accepted only when it is finite and every column of ``X`` keeps more than
    ``GRAM_RELATIVE_FLOOR`` of its energy after projection on the columns before it (``R[i, i]**2 / G[i, i]``);
    otherwise (or when the factorisation fails) the caller solves on the explicit regressor instead.
    """
    return _cholesky(gram[:k, :k])


def _cholesky(gram: np.ndarray) -> np.ndarray | None:
    """Upper Cholesky factor of ``gram`` by LAPACK ``potrf`` (the routine of ``scipy.linalg.cholesky``, called
    directly: its wrapper costs more than the factorisation of a small matrix), or ``None`` when the factorisation
    fails, is not finite or a column keeps no more than ``GRAM_RELATIVE_FLOOR`` of its energy."""
    R, info = lapack.dpotrf(gram, lower=0, clean=1)
    if info != 0:
        return None
    d = R.diagonal()
    # R[i, i]**2 / G[i, i] > floor without the division (G[i, i] > 0 where potrf succeeds; NaN compares False).
    # No separate finiteness check: potrf stops at a NaN or non-positive pivot, an infinite off-diagonal entry of
    # G makes a later pivot -inf or NaN, an infinite diagonal entry fails this test (inf > inf is False), and
    # |R[i, j]| <= sqrt(G[j, j]) keeps every other entry finite
    if (d * d > GRAM_RELATIVE_FLOOR * gram.diagonal()).all():
        return R
    return None


def gram_solve(gram: np.ndarray, k: int, design: callable, *, what: str = "the regressor",
               stacklevel: int = 3) -> np.ndarray | None:
    """Least-squares coefficients of ``Y`` on ``X`` from the Gram matrix of ``Z = [X | Y]``.

    ``B = (X'X)^{-1} X'Y`` by a Cholesky factor of the leading ``k x k`` block of ``gram`` (the normal
    equations), accepted only when every column of ``X`` keeps more than ``GRAM_RELATIVE_FLOOR`` of its
    energy after projection on the columns before it (as :func:`triangular_factor`). Otherwise the
    coefficients are recomputed from the explicit regressor ``design() -> (X, Y)`` by :func:`lstsq`'s SVD
    solver, which warns (naming ``what``) when ``X`` is ill-conditioned.

    Returns
    -------
    ndarray, shape (k, s), or None
        ``None`` when ``X`` is rank deficient (fewer rows than columns, or singular values below
        ``eps * max(X.shape)`` times the largest, numpy's rank rule) or its SVD does not converge.
    """
    R = gram_factor(gram, k)
    if R is not None:
        return lapack.dpotrs(R, gram[:k, k:], lower=0)[0]      # scipy.linalg.cho_solve without its wrapper
    X, Y = design()
    if X.shape[0] < k:
        return None
    try:
        coef, _, rank, sv = linalg.lstsq(X, Y, cond=np.finfo(float).eps * max(X.shape), lapack_driver="gelsd",
                                         check_finite=False)
    except (linalg.LinAlgError, ValueError):   # an SVD that does not converge: no usable solution
        return None
    if rank < k:
        return None
    with np.errstate(over="ignore"):
        cond = sv[0] / sv[-1]
    if cond > COND_WARN:
        warnings.warn(f"{what} is ill-conditioned (condition number {cond:.3g}); the estimates are not reliable",
                      IllConditionedWarning, stacklevel=stacklevel)
    return coef

"""Functionally pooled models FP-AR, FP-VAR, FP-ARX and operating-parameter estimation.

A functionally pooled (FP) model is one AR / VAR / ARX whose parameters are smooth functions of one or more
operating parameters ``k`` (forward speed, gross weight, a fault magnitude such as a cut depth), expanded on a
functional basis (Kopsaftopoulos and Fassois 2010, 2013; Sakellariou and Fassois 2008, 2016):

.. math::

    \\theta(k) = \\sum_{j=1}^{p} \\theta_j\\, G_j(k), \\qquad
    y[t] + \\sum_{i=1}^{n_a} A_i(k)\\, y[t-i] = c(k) + \\sum_{m=1}^{n_b} B_m(k)\\, u[t-n_k-m+1] + e[t],

with ``G_j`` Legendre (default) or Chebyshev polynomials of ``k`` mapped onto ``[-1, 1]`` over the range of the
fitted operating points (tensor products for several parameters). All records, each at its own operating point
``k_i``, are estimated at once: the regressor of record ``i`` is ``phi[t] (x) G(k_i)``, so the pooled Gram matrix
is ``sum_i (Phi_i' Phi_i) (x) G(k_i) G(k_i)'`` and the per-record Gram matrices ``Phi_i' Phi_i`` come from the
lag products of :mod:`tsfdi.models.lstsq` (no FP regressor is built). The parameters keep the papers' sign
(``a_i`` as in :class:`tsfdi.AR`).

:meth:`FPResults.estimate_k` turns a fitted FP model around: the operating point that best explains a new record
(maximum likelihood over ``k``) with its confidence interval, i.e. fault-magnitude or operating-point estimation.

:class:`FPMean` is the same expansion for the level of a signal's windows (the trim a closed loop holds, where a
compensated fault shows): each class's window means as a surface over ``k``, the window's likelihood maximised over
``k`` for :func:`tsfdi.identify`, and its distance for a detector with a calibrated threshold.
"""

from __future__ import annotations

import copy
import dataclasses
import itertools
import warnings
from functools import cached_property
from typing import Any, ClassVar

import numpy as np
import pandas as pd
from numpy.polynomial import chebyshev, legendre
from scipy import optimize, stats
from scipy.linalg import lapack

from tsfdi._data import as_signal, sampling_frequency, window_samples
from tsfdi._validation import int_like, option, probability
from tsfdi.exceptions import IllConditionedWarning
from tsfdi.models._base import FrozenResults, HeldOutResiduals
from tsfdi.models.ar import AR
from tsfdi.models.archive import register
from tsfdi.models.archive import save as save_archive
from tsfdi.models.arx import ARX
from tsfdi.models.lstsq import check_size, gram_factor, lag_gram, lag_residual_products, lagged_design, lstsq
from tsfdi.models.var import VAR
from tsfdi.summary import Summary

__all__ = ["FPAR", "FPVAR", "FPARX", "FPResults", "FPMean", "FPMeanResults", "OperatingPointEstimate",
           "FPOrderSelection", "select_fp_order", "fp_basis"]

_VANDER = {"legendre": legendre.legvander, "chebyshev": chebyshev.chebvander}
_LETTER = {"legendre": "P", "chebyshev": "T"}


def _operating_points(k: Any, nrec: int) -> tuple[np.ndarray, list[str]]:
    """``k`` as a finite float ``(records, d)`` array and the parameter names (a DataFrame's columns, a Series'
    name, else ``k0, k1, ...``)."""
    names = None
    if isinstance(k, pd.DataFrame):
        names = [str(c) for c in k.columns]
    elif isinstance(k, pd.Series) and k.name is not None:
        names = [str(k.name)]
    try:
        arr = np.asarray(k, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"k must be real operating parameters, one row per record, got {type(k).__name__}") from None
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != nrec or arr.shape[1] < 1:
        raise ValueError(f"k must hold one operating point per record ({nrec} records): shape ({nrec},) or "
                         f"({nrec}, d), got shape {np.shape(k)}")
    if not np.isfinite(arr).all():
        raise ValueError("k contains NaN/inf")
    return np.ascontiguousarray(arr), names or [f"k{j}" for j in range(arr.shape[1])]


def fp_basis(k: Any, degree: Any, k_range: Any, basis: str = "legendre") -> np.ndarray:
    """The functional basis ``G(k)`` of an FP model at the operating points ``k``.

    Parameters
    ----------
    k : array_like, shape (m,) or (m, d)
        Operating points (one row each; a 1-D array is one parameter).
    degree : int or sequence of int
        Largest polynomial degree of each parameter (one int for all).
    k_range : array_like, shape (d, 2)
        The interval of each parameter mapped onto ``[-1, 1]``.
    basis : {"legendre", "chebyshev"}

    Returns
    -------
    ndarray, shape (m, p)
        ``p = prod(degree_j + 1)`` functions: the tensor products ``G_{j_1}(k_1) ... G_{j_d}(k_d)``, the index of the
        last parameter running fastest.
    """
    basis = option(basis, "basis", tuple(_VANDER))
    try:
        k = np.asarray(k, dtype=float)
        rng = np.asarray(k_range, dtype=float).reshape(-1, 2)
    except (TypeError, ValueError):
        raise TypeError("k and k_range must be real arrays (k_range of shape (d, 2))") from None
    k = k[:, None] if k.ndim == 1 else k
    d = rng.shape[0]
    deg = _degrees(degree, d)
    if k.ndim != 2 or k.shape[1] != d:
        raise ValueError(f"k must have {d} operating parameter(s) per point, got shape {k.shape}")
    if not np.isfinite(rng).all() or not (rng[:, 1] > rng[:, 0]).all():
        raise ValueError(f"k_range must hold finite intervals (low, high) with low < high, got {rng.tolist()}")
    if not np.isfinite(k).all():
        raise ValueError("k contains NaN/inf")
    x = 2.0 * (k - rng[:, 0]) / (rng[:, 1] - rng[:, 0]) - 1.0
    G = np.ones((k.shape[0], 1))
    for j in range(d):
        V = _VANDER[basis](x[:, j], deg[j])
        G = (G[:, :, None] * V[:, None, :]).reshape(k.shape[0], -1)
    return G


def _operating_setup(k: Any, nrec: int, degree: Any, k_range: Any
                     ) -> tuple[np.ndarray, list[str], tuple[int, ...], np.ndarray]:
    """The operating points, their names, the degree per parameter and the ``(d, 2)`` range of an FP model, checked:
    ``k_range`` holds every point, every parameter takes more distinct values than its degree."""
    k, names = _operating_points(k, nrec)
    d = k.shape[1]
    deg = _degrees(degree, d)
    if k_range is None:
        rng = np.stack([k.min(axis=0), k.max(axis=0)], axis=1)
    else:
        try:
            rng = np.asarray(k_range, dtype=float).reshape(d, 2)
        except (TypeError, ValueError):
            raise ValueError(f"k_range must be ({d}, 2) bounds (low, high) of the operating parameters, got "
                             f"{k_range!r}") from None
        if not np.isfinite(rng).all() or (k < rng[:, 0]).any() or (k > rng[:, 1]).any():
            raise ValueError("k_range must be finite and contain every operating point of k")
    if not (rng[:, 1] > rng[:, 0]).all():
        j = int(np.argmin(rng[:, 1] - rng[:, 0]))
        raise ValueError(f"k: operating parameter {names[j]!r} takes one value only; an FP model needs "
                         "records at several operating points")
    for j in range(d):
        distinct = np.unique(k[:, j]).size
        if distinct <= deg[j]:
            raise ValueError(f"degree={deg[j]} for {names[j]!r} needs at least {deg[j] + 1} distinct operating "
                             f"points, k has {distinct}")
    return k, names, deg, rng


def _degrees(degree: Any, d: int) -> tuple[int, ...]:
    if isinstance(degree, (list, tuple, np.ndarray)):
        deg = tuple(int_like(g, "degree", minimum=0) for g in degree)
        if len(deg) != d:
            raise ValueError(f"degree must give one degree per operating parameter ({d}), got {len(deg)}")
        return deg
    return (int_like(degree, "degree", minimum=0),) * d


class _FPModel:
    """Common machinery of FPAR, FPVAR and FPARX (see :class:`FPAR` for the parameters)."""

    _point_family: ClassVar[type]
    results_class: ClassVar[type]

    def __init__(self, y: Any, k: Any, *, lags: int, degree: Any, trend: str, basis: str, weights: str,
                 hold_back: int | None, k_range: Any, u: Any = None, nb: int = 0, nk: int = 0) -> None:
        if not isinstance(y, (list, tuple)) or len(y) < 2:
            raise ValueError("y must be a list of records (at least 2), one per operating point")
        self.basis = option(basis, "basis", tuple(_VANDER))
        self.weights = option(weights, "weights", ("pooled", "point"))
        self.k, self.k_names, self.degree, self.k_range = _operating_setup(k, len(y), degree, k_range)
        # the point family on all records validates the data (finite, channels matched by name, lengths, sizes)
        # and gives the records and their common units
        if u is None:
            self.point = self._point_family(list(y), lags, trend, hold_back=hold_back)
        else:
            self.point = self._point_family(list(y), list(u), lags, nb, nk, trend, hold_back=hold_back)
        pt = self.point
        self.G = fp_basis(self.k, self.degree, self.k_range, self.basis)
        p = self.G.shape[1]
        cols = pt.df_eq * p + pt.neqs
        check_size(cols * cols * len(y), f"lags={pt.na} with {p} basis functions: the Gram matrices")
        if sum(pt.nobs_records) < pt.df_eq * p + 1:
            raise ValueError(f"y is too short: {sum(pt.nobs_records)} regression rows in all records for "
                             f"{pt.df_eq * p} coefficients per equation")

    # --- dimensions, names
    @property
    def records(self) -> tuple:
        return self.point.records

    @property
    def u_records(self) -> tuple | None:
        return self.point.u_records

    @property
    def data(self):
        return self.point.data

    @property
    def multi(self) -> bool:
        return True

    na = property(lambda self: self.point.na)
    nb = property(lambda self: self.point.nb)
    nk = property(lambda self: self.point.nk)
    trend = property(lambda self: self.point.trend)
    hold_back = property(lambda self: self.point.hold_back)
    max_lag = property(lambda self: self.point.max_lag)
    neqs = property(lambda self: self.point.neqs)
    criterion = property(lambda self: "logdet")
    #: the point family's output kind: False scalar (FP-AR, FP-ARX), True vector (FP-VAR)
    _vector: ClassVar[bool]
    #: the name of the output order in messages and summaries
    _lag_name: ClassVar[str] = "lags"

    @property
    def n_basis(self) -> int:
        """Number of basis functions ``p``."""
        return self.G.shape[1]

    @property
    def df_point(self) -> int:
        """Coefficients per equation of the point model (AR / VAR / ARX) at one operating point."""
        return self.point.df_eq

    @property
    def df_eq(self) -> int:
        """FP coefficients per equation, ``df_point * n_basis``."""
        return self.point.df_eq * self.n_basis

    @property
    def nobs_records(self) -> list[int]:
        return self.point.nobs_records

    def basis_names(self) -> list[str]:
        """Names of the basis functions: ``P0, P1, ...`` (``T`` for Chebyshev), ``P1,2`` for a tensor product."""
        letter = _LETTER[self.basis]
        return [letter + ",".join(map(str, idx)) for idx in itertools.product(*[range(g + 1) for g in self.degree])]

    # --- per-record quantities in the units of the fit
    def _unit_columns(self) -> np.ndarray:
        """The fit's regressor column ``a`` is the data's times this (inputs and outputs in their fit units)."""
        pt = self.point
        col = [np.ones(pt.k_const)]
        uscale = pt.u_scale if pt.u_scale is not None else np.ones(0)
        for g in range(1, max(pt.na, pt.nb) + 1):
            col += ([1.0 / pt.y_scale] if g <= pt.na else []) + ([1.0 / uscale] if g <= pt.nb else [])
        return np.concatenate(col)

    def _scaled(self, i: int) -> tuple[np.ndarray, np.ndarray | None]:
        pt = self.point
        y = pt.records[i].values / pt.y_scale
        u = None if pt.u_records is None else pt.u_records[i].values / pt.u_scale
        return y, u

    def _design(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        y, u = self._scaled(i)
        pt = self.point
        return lagged_design(y, pt.na, pt.hold_back, const=bool(pt.k_const), u=u, nb=pt.nb, nk=pt.nk)

    def record_grams(self) -> np.ndarray:
        """Gram matrix of ``[Phi_i | Y_i]`` of every record (units of the fit), shape ``(records, df_point + s,
        df_point + s)``: from the lag products (:func:`~tsfdi.models.lstsq.lag_gram`) for an FP-AR / FP-VAR, from
        the explicit regressor for an FP-ARX."""
        pt = self.point
        out = []
        for i in range(len(pt.records)):
            if pt.nb == 0:
                y = self._scaled(i)[0][pt.hold_back - pt.na:]
                out.append(lag_gram(y, pt.na, const=bool(pt.k_const)))
            else:
                Z = np.hstack(self._design(i))
                out.append(Z.T @ Z)
        return np.stack(out)

    def _pooled_system(self, grams: np.ndarray, w: np.ndarray | None, G: np.ndarray, kp: int
                       ) -> tuple[np.ndarray, np.ndarray]:
        """``sum_i w_i (Phi_i'Phi_i) (x) G_i G_i'`` and ``sum_i w_i (Phi_i'Y_i) (x) G_i`` (``w``: one weight per record
        and equation, shape (records, s), or None), over the first ``kp`` point coefficients."""
        s = self.neqs
        q = G.shape[1]
        XX = grams[:, :kp, :kp]
        XY = grams[:, :kp, -s:]
        GG = G[:, :, None] * G[:, None, :]
        if w is None:
            A = np.einsum("iab,ijl->ajbl", XX, GG).reshape(kp * q, kp * q)
            b = np.einsum("iac,ij->ajc", XY, G).reshape(kp * q, s)
            return A[None], b
        A = np.einsum("ie,iab,ijl->eajbl", w, XX, GG).reshape(s, kp * q, kp * q)
        b = np.einsum("ic,iac,ij->ajc", w, XY, G).reshape(kp * q, s)
        return A, b

    def _solve(self, A: np.ndarray, b: np.ndarray, idx: np.ndarray, w: np.ndarray | None, refine: bool = True
               ) -> np.ndarray:
        """FP coefficients (fit units, ``(df_eq, s)``) of the records ``idx`` from the pooled normal equations (one
        system per equation when weighted), with one refinement step on the residual products (``refine``: a pass
        over the records' samples); the SVD of the explicit FP regressor when the Cholesky factor would lose
        digits."""
        out = np.empty(b.shape)
        for e in range(A.shape[0]):
            cols = slice(None) if A.shape[0] == 1 else slice(e, e + 1)
            R = gram_factor(A[e], A.shape[1])
            if R is None:
                X, Y = self._fp_design(idx, None if w is None else w[:, e])
                out[:, cols] = lstsq(X, Y[:, cols])
                continue
            coef = lapack.dpotrs(R, b[:, cols], lower=0)[0]
            if refine:
                coef = coef + lapack.dpotrs(R, self._residual_products(coef, idx, cols, w, e), lower=0)[0]
            out[:, cols] = coef
        return out

    def _fp_design(self, idx: np.ndarray, w: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """The explicit FP regressor ``phi[t] (x) G(k_i)`` and target of the records ``idx`` (rows weighted by
        ``sqrt(w)``, one weight per record of ``idx``)."""
        xs, ys = [], []
        for r, i in enumerate(idx):
            X, Y = self._design(i)
            sq = 1.0 if w is None else np.sqrt(w[r])
            xs.append((X[:, :, None] * self.G[i][None, None, :]).reshape(X.shape[0], -1) * sq)
            ys.append(Y * sq)
        return np.vstack(xs), np.vstack(ys)

    def _residual_products(self, coef: np.ndarray, idx: np.ndarray, cols: slice, w: np.ndarray | None,
                           e: int) -> np.ndarray:
        """``X_fp' W (Y - X_fp coef)`` = ``sum_i w_i (Phi_i' E_i) (x) G_i`` over the records ``idx``, with ``E_i`` the
        residuals of record ``i`` through ``theta(k_i)`` (:func:`~tsfdi.models.lstsq.lag_residual_products` for an
        FP-AR / FP-VAR)."""
        pt = self.point
        q = self.n_basis
        kp = coef.shape[0] // q
        full = np.zeros((coef.shape[0], self.neqs))
        full[:, cols] = coef
        total = np.zeros((kp, q, coef.shape[1]))
        for r, i in enumerate(idx):
            theta = np.einsum("ajc,j->ac", full.reshape(kp, q, -1), self.G[i])
            if pt.nb == 0:
                y = self._scaled(i)[0][pt.hold_back - pt.na:]
                res = lag_residual_products(y, theta, const=bool(pt.k_const))[:, cols]
            else:
                X, Y = self._design(i)
                res = X.T @ (Y - X @ theta)[:, cols]
            total += (1.0 if w is None else w[r, e]) * res[:, None, :] * self.G[i][None, :, None]
        return total.reshape(kp * q, -1)

    def fit(self) -> FPResults:
        """Estimate the FP coefficients by pooled least squares over all records.

        ``weights="pooled"``: ordinary least squares (one noise covariance for every operating point).
        ``weights="point"``: two-stage weighted least squares, each equation's rows of record ``i`` weighted by
        ``1 / Sigma_i[j, j]``, the residual variance of that record through the first-stage (pooled) fit: the
        estimator for a noise level that changes with the operating point (the off-diagonal terms of
        ``Sigma_i`` are not used: equation by equation, as the point VAR).

        The normal equations are solved by a Cholesky factor with one refinement step on the exact residual
        products; when the factor would lose digits the explicit FP regressor is solved by SVD
        (:func:`~tsfdi.models.lstsq.lstsq`, with an :class:`~tsfdi.exceptions.IllConditionedWarning` when
        ill-conditioned).
        """
        coef, w = self._fit_coef(np.arange(len(self.records)), self.record_grams())
        params = coef * np.repeat(self._unit_columns(), self.n_basis)[:, None] * self.point.y_scale[None, :]
        if not np.isfinite(params).all():
            raise ValueError("y: the FP coefficients leave the floating-point range; rescale y (and u)")
        return FPResults(self, params, w)

    def _fit_coef(self, idx: np.ndarray, grams: np.ndarray, refine: bool = True
                  ) -> tuple[np.ndarray, np.ndarray | None]:
        """The FP coefficients (fit units) fitted on the records ``idx`` alone (``grams``: :meth:`record_grams` of
        all records), and their weights (records of ``idx``, s) with ``weights="point"``; ``refine``: see
        :meth:`_solve`."""
        kp = self.df_point
        A, b = self._pooled_system(grams[idx], None, self.G[idx], kp)
        coef = self._solve(A, b, idx, None, refine)
        if self.weights == "pooled":
            return coef, None
        if refine:
            sse = self._record_sse(coef, idx).diagonal(axis1=1, axis2=2)
        else:       # diag(E_i'E_i) from the Gram matrices: YY - 2 theta'XY + theta'XX theta, no pass over the samples
            g = grams[idx]
            theta = np.einsum("ajc,ij->iac", coef.reshape(kp, self.n_basis, -1), self.G[idx])
            sse = (np.einsum("icc->ic", g[:, kp:, kp:]) - 2 * np.einsum("iac,iac->ic", theta, g[:, :kp, kp:])
                   + np.einsum("iac,iab,ibc->ic", theta, g[:, :kp, :kp], theta))
        s2 = sse / np.asarray(self.nobs_records, dtype=float)[idx, None]
        if not (s2 > 0).all():
            raise ValueError("weights='point': a record is fitted exactly (zero residual variance); use "
                             "weights='pooled'")
        w = 1.0 / s2
        A, b = self._pooled_system(grams[idx], w, self.G[idx], kp)
        return self._solve(A, b, idx, w, refine), w

    def _record_sse(self, coef: np.ndarray, idx: Any = None) -> np.ndarray:
        """Residual cross products ``E_i'E_i`` of the records ``idx`` (default all) through ``theta(k_i)`` (fit
        units), (records, s, s)."""
        return np.stack([e.T @ e for e in self._record_resid(coef, idx)])

    def _record_resid(self, coef: np.ndarray, idx: Any = None) -> list[np.ndarray]:
        q = self.n_basis
        kp = self.df_point
        out = []
        for i in range(len(self.records)) if idx is None else idx:
            theta = np.einsum("ajc,j->ac", coef.reshape(kp, q, -1), self.G[i])
            X, Y = self._design(i)
            out.append(Y - X @ theta)
        return out

    # --- held-out residuals
    def held_out_residuals(self, blocks: int | None = None, *, groups: Any = None) -> HeldOutResiduals:
        """Residuals of each record at its own operating point ``k_i`` through the FP model fitted on all the
        *other* records.

        The FP counterpart of :meth:`tsfdi.AR.held_out_residuals` (see there why a calibrated threshold needs
        them): the null sample of a global baseline, each record filtered as the baseline filters a new flight
        at its operating point. Every fold is the FP fit of this spec (same lags, degree, basis, trend, weights,
        ``hold_back``) on the remaining records, solved from their Gram matrices (:meth:`record_grams`, accumulated
        once; no refinement pass over the samples, so a fold costs a solve, as the point models' folds, unless the
        Gram matrix is too ill-conditioned and the SVD of the explicit FP regressor takes over), so it equals ``type(self)(other records, their k, ...).fit().residuals(record_i, k_i)`` without
        rebuilding the records (the polynomial space, hence the fit, does not depend on ``k_range``). They are
        also what :meth:`tsfdi.FPResults.at` carries, so that :meth:`tsfdi.LjungBox.calibrated_for` and the coverage
        checks (:func:`tsfdi.coverage.check_coverage`) of a model at ``k`` read the FP model's null, not that of
        a point model pooled over the operating points.

        Parameters
        ----------
        blocks : None
            Only ``None``: an FP model holds out whole records (a block of one record would leave its operating
            point in the fit). Kept so that the call reads as the point models'.
        groups : sequence, optional
            One label per record: the records sharing a label are held out together (e.g. all the records of one
            operating point, or the flights of one airframe).

        Returns
        -------
        HeldOutResiduals
            One residual series per record, in record order and the record's data kind, the residuals of
            :meth:`tsfdi.FPResults.residuals` (samples ``max_lag .. nobs - 1``, index from position ``max_lag``), with
            ``lags`` the model's ``max_lag``.

        Raises
        ------
        ValueError
            ``blocks`` given; ``groups`` not one label per record or a single label; a fold whose remaining
            records hold fewer distinct operating points than the basis needs (degree ``d`` in one parameter needs
            ``d + 1``), or too few regression rows, named in the message.
        """
        if blocks is not None:
            raise ValueError(f"blocks must be None for an FP model, got {blocks!r}: its records are held out whole "
                             "(a block of a record would leave its operating point in the fit); use groups")
        n = len(self.records)
        if groups is None:
            label = list(range(n))
        else:
            if isinstance(groups, (str, bytes)) or not hasattr(groups, "__len__"):
                raise ValueError(f"groups must be a sequence of one label per record, got {groups!r}")
            label = list(groups)
            if len(label) != n:
                raise ValueError(f"groups must hold one label per record ({n}), got {len(label)}")
            if len(set(label)) < 2:
                raise ValueError("groups must hold at least two distinct labels: holding out every record leaves "
                                 "nothing to fit")
        grams = self.record_grams()
        pt = self.point
        scale = np.repeat(self._unit_columns(), self.n_basis)[:, None] * pt.y_scale[None, :]
        nobs = np.asarray(self.nobs_records)
        out: list = [None] * n
        for g in dict.fromkeys(label):
            members = [i for i in range(n) if label[i] == g]
            keep = np.array([i for i in range(n) if label[i] != g])
            what = (f"y[{members[0]}]" if groups is None
                    else f"group {g.item() if isinstance(g, np.generic) else g!r} (y[{', '.join(map(str, members))}])")
            points = len(np.unique(self.k[keep], axis=0))
            degree = self.degree[0] if len(self.degree) == 1 else self.degree
            if np.linalg.matrix_rank(self.G[keep]) < self.n_basis:
                raise ValueError(
                    f"removing {what} leaves {points} distinct operating point(s), too few for the {self.n_basis} "
                    f"basis functions of degree {degree} in {', '.join(self.k_names)}: fit records at more "
                    "operating points, hold out fewer records together (groups) or lower the degree")
            if nobs[keep].sum() < self.df_eq + 1:
                raise ValueError(f"removing {what} leaves {nobs[keep].sum()} regression rows for {self.df_eq} "
                                 "coefficients per equation: fit more or longer records")
            params = self._fit_coef(keep, grams, refine=False)[0] * scale
            for i in members:
                theta = np.einsum("ajc,j->ac", params.reshape(self.df_point, self.n_basis, -1), self.G[i])
                rec = self.records[i]
                u = None if self.u_records is None else self.u_records[i].values
                e = pt.results_class(pt, theta)._residuals_array(rec.values, u)
                out[i] = rec.wrap(e, self.max_lag)
        return HeldOutResiduals(out, lags=self.max_lag)

    @cached_property
    def _point_at(self) -> Any:
        """The point spec of :meth:`FPResults.at`: the point family on all the records (a copy of :attr:`point`)
        whose ``held_out_residuals`` are this FP model's."""
        spec = copy.copy(self.point)
        spec.held_out_residuals = self.held_out_residuals
        return spec

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(records={len(self.records)}, {self._lag_name}={self.na}, "
                f"degree={self.degree}, basis={self.basis!r}, trend={self.trend!r}, weights={self.weights!r})")


@register
class FPAR(_FPModel):
    """Functionally pooled scalar autoregression FP-AR(na) over operating parameters ``k``.

    .. math::  y[t] + \\sum_{i=1}^{n_a} a_i(k)\\, y[t-i] = c(k) + e[t], \\qquad
               a_i(k) = \\sum_{j=1}^{p} a_{i,j}\\, G_j(k)

    (Kopsaftopoulos and Fassois 2010, 2013). The records are the point AR's (:class:`tsfdi.AR`) at several operating
    points, estimated at once by pooled least squares.

    Parameters
    ----------
    y : list of array_like, Series, DataFrame (one column) or DataArray
        One record per operating point (several records may share a point).
    k : array_like (records,) or (records, d), Series or DataFrame
        The operating point of every record (one or more parameters; a DataFrame's columns / a Series' name
        name them).
    lags : int
        Order ``na >= 1``.
    degree : int or sequence of int
        Largest polynomial degree of the basis in each operating parameter (``p = prod(degree + 1)`` functions,
        tensor products for several parameters).
    trend : {"n", "c"}
        No intercept or an intercept ``c(k)`` (expanded on the basis too).
    basis : {"legendre", "chebyshev"}
        Polynomial family on ``k`` mapped onto ``[-1, 1]`` over ``k_range``.
    weights : {"pooled", "point"}
        Ordinary pooled least squares, or two-stage weighted least squares with each record's residual variance
        (see :meth:`fit`).
    hold_back : int, optional
        Samples held back at the start of every record (default ``lags``; a common sample for
        :func:`select_fp_order`).
    k_range : array_like (d, 2), optional
        The interval of each parameter mapped onto ``[-1, 1]`` (default: the range of ``k``).

    Raises
    ------
    ValueError
        Fewer than 2 records, ``k`` not one finite point per record, a parameter with fewer distinct values than
        ``degree + 1``, and every check of :class:`tsfdi.AR` on the records (named ``y[i]``).
    TypeError
        Non-numeric data or ``k``, a non-integer order or degree.

    Notes
    -----
    The standard errors (:attr:`FPResults.bse`) are ordinary (weighted) least squares ones, ``s_j^2 (X'WX)^{-1}``
    with ``s_j^2 = RSS_j / (nobs - df_eq)`` (statsmodels ``WLS``), and those of ``theta(k)`` follow by the delta
    method (exact here: ``theta(k)`` is linear in the coefficients).
    """

    _point_family = AR
    _vector = False

    def __init__(self, y: Any, k: Any, lags: int, degree: Any = 1, trend: str = "n", *, basis: str = "legendre",
                 weights: str = "pooled", hold_back: int | None = None, k_range: Any = None) -> None:
        super().__init__(y, k, lags=lags, degree=degree, trend=trend, basis=basis, weights=weights,
                         hold_back=hold_back, k_range=k_range)


@register
class FPVAR(_FPModel):
    """Functionally pooled vector autoregression FP-VAR(na): :class:`FPAR` for a vector output,
    ``y[t] + sum_i A_i(k) y[t-i] = c(k) + e[t]``, ``A_i(k) = sum_j A_{i,j} G_j(k)``, equation by equation
    (Sakellariou and Fassois 2016). Parameters as :class:`FPAR`, records as :class:`tsfdi.VAR`'s (channels matched
    by name)."""

    _point_family = VAR
    _vector = True

    def __init__(self, y: Any, k: Any, lags: int, degree: Any = 1, trend: str = "n", *, basis: str = "legendre",
                 weights: str = "pooled", hold_back: int | None = None, k_range: Any = None) -> None:
        super().__init__(y, k, lags=lags, degree=degree, trend=trend, basis=basis, weights=weights,
                         hold_back=hold_back, k_range=k_range)


@register
class FPARX(_FPModel):
    """Functionally pooled ARX(na, nb, nk): :class:`FPAR` with inputs,
    ``y[t] + sum_i a_i(k) y[t-i] = c(k) + sum_m b_m(k)' u[t-nk-m+1] + e[t]`` (Sakellariou and Fassois 2008). ``u``:
    one input record per output record, as :class:`tsfdi.ARX`'s; other parameters as :class:`FPAR`."""

    _point_family = ARX
    _vector = False
    _lag_name = "na"

    def __init__(self, y: Any, u: Any, k: Any, na: int, nb: int, nk: int = 0, degree: Any = 1, trend: str = "n", *,
                 basis: str = "legendre", weights: str = "pooled", hold_back: int | None = None,
                 k_range: Any = None) -> None:
        if not isinstance(u, (list, tuple)):
            raise ValueError("u must be a list of input records, one per output record")
        super().__init__(y, k, lags=na, degree=degree, trend=trend, basis=basis, weights=weights,
                         hold_back=hold_back, k_range=k_range, u=u, nb=nb, nk=nk)


def _operating_point(k: Any, k_names: tuple, name: str = "k") -> np.ndarray:
    """One operating point ``k`` of a model over the parameters ``k_names`` as a finite ``(d,)`` array, or an error
    naming ``name``."""
    d = len(k_names)
    try:
        arr = np.asarray(k, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real operating point ({d} value(s)), got {k!r}") from None
    if arr.size != d:
        raise ValueError(f"{name} must be one operating point with {d} value(s) {tuple(k_names)}, got {arr.size}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    return arr


class FPResults(FrozenResults):
    """Results of :meth:`FPAR.fit` / :meth:`FPVAR.fit` / :meth:`FPARX.fit` (immutable).

    Attributes
    ----------
    params : ndarray or Series / DataFrame
        The FP coefficients ``theta_j`` of every point parameter and basis function, rows ``(point parameter,
        basis function)`` with the point parameter outer (``a1:P0, a1:P1, ..., a2:P0, ...``), one column per
        equation for an FP-VAR; 1-D for a scalar output with numpy data, labelled for pandas / xarray data.
    bse, tvalues, pvalues : same shape as params
        Standard errors ``sqrt(diag(s_j^2 (X'WX)^{-1}))`` (``W`` the record weights, identity when pooled,
        ``s_j^2 = RSS_j / (nobs - df_eq)`` in the weighted metric), ``params / bse`` and the two-sided normal
        p-values.
    resid : list
        In-sample residuals, one series per record (data kind of the records).
    sigma_points : ndarray, shape (records, s, s)
        Maximum-likelihood residual covariance of every record through ``theta(k_i)``.
    nobs, df_model, llf, aic, bic : int / float
        Regression rows of all records, coefficients of all equations, Gaussian log-likelihood (pooled ``Sigma``,
        or the records' own ``Sigma_i`` with ``weights="point"``) and its criteria
        (``-2 llf + 2 k`` / ``+ k ln nobs``, ``k`` counting the noise covariance parameters).
    """

    def __init__(self, model: _FPModel, params: np.ndarray, weights: np.ndarray | None = None) -> None:
        params = np.array(params, dtype=float).reshape(model.df_eq, model.neqs)
        params.setflags(write=False)
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "_params2d", params)
        if weights is not None:
            weights = np.array(weights, dtype=float).reshape(len(model.records), model.neqs)
            weights.setflags(write=False)
        object.__setattr__(self, "weights", weights)

    # --- parameters
    @property
    def params2d(self) -> np.ndarray:
        """FP coefficients (read-only), shape ``(df_eq, neqs)``, row ``a * n_basis + j`` for point parameter ``a``
        and basis function ``j``."""
        return self._params2d

    @property
    def neqs(self) -> int:
        return self.model.neqs

    def _fit_units(self) -> np.ndarray:
        m = self.model
        scale = np.repeat(m._unit_columns(), m.n_basis)[:, None] * m.point.y_scale[None, :]
        return self._params2d / scale

    def _param_names(self) -> list[str]:
        return [f"{a}:{g}" for a in self.point_names() for g in self.model.basis_names()]

    def point_names(self) -> list[str]:
        """The point model's parameter names (as its ``params``): ``const``, ``a1`` / ``A1.<channel>``,
        ``b1.<input>``."""
        m = self.model
        names = ["const"] if m.point.k_const else []
        u = m.point.u_data
        inputs = [] if u is None else ([str(c) for c in u.channels] if u.named or (not u.vector and u.name is not None)
                                       else [f"u{i}" for i in range(u.nchan)])
        for g in range(1, max(m.na, m.nb) + 1):
            if g <= m.na:
                names += [f"a{g}" if self.neqs == 1 else f"A{g}.{c}" for c in m.data.channels]
            if g <= m.nb:
                names += [f"b{g}.{c}" for c in inputs]
        return names

    def _labelled(self, values: np.ndarray, names: list[str]) -> Any:
        m = self.model
        out = values if m._vector else values[:, 0]
        if m.data.kind == "numpy":
            return out
        if not m._vector:
            return pd.Series(out.copy(), index=names, name=m.data.name)
        return pd.DataFrame(out.copy(), index=names, columns=list(m.data.channels))

    @property
    def params(self) -> Any:
        return self._labelled(self._params2d, self._param_names())

    @cached_property
    def _resid_fit(self) -> list[np.ndarray]:
        return self.model._record_resid(self._fit_units())

    @cached_property
    def _sse_points(self) -> np.ndarray:
        """``E_i'E_i`` per record in the data's units, (records, s, s)."""
        sc = self.model.point.y_scale
        return np.stack([e.T @ e for e in self._resid_fit]) * sc[None, :, None] * sc[None, None, :]

    @property
    def nobs(self) -> int:
        return int(sum(self.model.nobs_records))

    @property
    def df_model(self) -> int:
        return self.model.df_eq * self.neqs

    @property
    def df_resid(self) -> int:
        return self.nobs - self.model.df_eq

    @property
    def resid(self) -> list:
        """In-sample residuals of every record through ``theta(k_i)``, one series per record in the record's data
        kind (index from position ``hold_back``)."""
        m = self.model
        sc = m.point.y_scale
        return [rec.wrap(e * sc, m.hold_back) for rec, e in zip(m.records, self._resid_fit)]

    @property
    def sigma_points(self) -> np.ndarray:
        return self._sse_points / np.asarray(self.model.nobs_records, dtype=float)[:, None, None]

    @property
    def sigma_pooled(self) -> np.ndarray:
        """Maximum-likelihood residual covariance of all records pooled, ``sum_i E_i'E_i / nobs``, (s, s)."""
        return self._sse_points.sum(axis=0) / self.nobs

    @cached_property
    def _cov(self) -> np.ndarray:
        """Covariance of the FP coefficients of every equation, (s, df_eq, df_eq), in the data's units."""
        m = self.model
        grams = m.record_grams()
        A, _ = m._pooled_system(grams, self.weights, m.G, m.df_point)
        sse = np.stack([e.T @ e for e in self._resid_fit]).diagonal(axis1=1, axis2=2)   # (records, s), fit units
        rss = sse.sum(axis=0) if self.weights is None else (self.weights * sse).sum(axis=0)
        s2 = rss / self.df_resid
        scale = np.repeat(m._unit_columns(), m.n_basis)
        out = np.empty((self.neqs, m.df_eq, m.df_eq))
        for e in range(self.neqs):
            Ae = A[0] if A.shape[0] == 1 else A[e]
            inv = np.linalg.pinv(Ae, hermitian=True)
            ys = m.point.y_scale[e]
            out[e] = s2[e] * inv * np.outer(scale, scale) * ys * ys
        out.setflags(write=False)
        return out

    @cached_property
    def _bse2d(self) -> np.ndarray:
        b = np.sqrt(np.maximum(self._cov.diagonal(axis1=1, axis2=2), 0.0)).T
        b.setflags(write=False)
        return b

    @property
    def bse(self) -> Any:
        return self._labelled(self._bse2d, self._param_names())

    @property
    def tvalues(self) -> Any:
        with np.errstate(divide="ignore", invalid="ignore"):
            return self._labelled(self._params2d / self._bse2d, self._param_names())

    @property
    def pvalues(self) -> Any:
        with np.errstate(divide="ignore", invalid="ignore"):
            return self._labelled(2 * stats.norm.sf(np.abs(self._params2d / self._bse2d)), self._param_names())

    # --- evaluation at an operating point
    def _point(self, k: Any, name: str = "k") -> np.ndarray:
        return _operating_point(k, self.model.k_names, name)

    def _g(self, k: np.ndarray) -> np.ndarray:
        m = self.model
        return fp_basis(k[None, :], m.degree, m.k_range, m.basis)[0]

    def _theta2d(self, k: np.ndarray) -> np.ndarray:
        m = self.model
        return np.einsum("ajc,j->ac", self._params2d.reshape(m.df_point, m.n_basis, -1), self._g(k))

    def theta(self, k: Any) -> Any:
        """The point model's parameters at operating point ``k``: ``theta(k) = sum_j theta_j G_j(k)``, laid out as
        the point model's ``params`` (:class:`tsfdi.AR` / ``VAR`` / ``ARX``: ``[const, a1, a2, ...]``).

        Outside ``k_range`` the polynomials extrapolate (allowed, not advised)."""
        return self._labelled(self._theta2d(self._point(k)), self.point_names())

    def theta_bse(self, k: Any) -> Any:
        """Standard errors of :meth:`theta` at ``k`` (delta method: ``sqrt(g' Cov_a g)`` per point parameter ``a``,
        exact since ``theta(k)`` is linear in the coefficients), same layout."""
        m = self.model
        g = self._g(self._point(k))
        cov = self._cov.reshape(self.neqs, m.df_point, m.n_basis, m.df_point, m.n_basis)
        var = np.einsum("eajal,j,l->ae", cov, g, g)
        return self._labelled(np.sqrt(np.maximum(var, 0.0)), self.point_names())

    def sigma(self, k: Any) -> np.ndarray:
        """Residual covariance at operating point ``k``, (s, s).

        ``weights="pooled"``: the pooled covariance :attr:`sigma_pooled` at every ``k``. ``weights="point"``: the
        log-variance of every channel expanded on the model's basis (least squares over the records' ``Sigma_i``
        diagonals, weighted by their rows) with the pooled correlation, ``D(k) C D(k)``, so positive definite.
        """
        kk = self._point(k)
        if self.weights is None:
            return self.sigma_pooled.copy()
        return self._sigma_from_logvar(kk)

    @cached_property
    def _logvar_coef(self) -> np.ndarray:
        m = self.model
        lv = np.log(self.sigma_points.diagonal(axis1=1, axis2=2))
        sw = np.sqrt(np.asarray(m.nobs_records, dtype=float))[:, None]
        coef = np.linalg.lstsq(m.G * sw, lv * sw, rcond=None)[0]
        return coef

    def _sigma_from_logvar(self, k: np.ndarray) -> np.ndarray:
        pooled = self.sigma_pooled
        sd = np.sqrt(pooled.diagonal())
        corr = pooled / np.outer(sd, sd)
        dk = np.exp(0.5 * (self._g(k) @ self._logvar_coef))
        return corr * np.outer(dk, dk)

    # --- criteria
    @cached_property
    def llf(self) -> float:
        n = np.asarray(self.model.nobs_records, dtype=float)
        s = self.neqs
        if self.weights is None:
            ld = np.linalg.slogdet(self.sigma_pooled)[1]
            return float(-0.5 * self.nobs * (s * np.log(2 * np.pi) + ld + s))
        ld = np.linalg.slogdet(self.sigma_points)[1]
        return float(-0.5 * np.sum(n * (s * np.log(2 * np.pi) + ld + s)))

    @property
    def _n_free(self) -> int:
        s = self.neqs
        cov = s * (s + 1) // 2 * (1 if self.weights is None else len(self.model.records))
        return self.df_model + cov

    @property
    def aic(self) -> float:
        return -2 * self.llf + 2 * self._n_free

    @property
    def bic(self) -> float:
        return -2 * self.llf + self._n_free * np.log(self.nobs)

    # --- new data
    def at(self, k: Any) -> Any:
        """The point results at operating point ``k``: :class:`tsfdi.ARResults` / ``VARResults`` / ``ARXResults``
        with the parameters :meth:`theta` ``(k)`` and the residual covariance :meth:`sigma` ``(k)``.

        Every engine that takes point results takes it unchanged (:func:`tsfdi.detect`, :func:`tsfdi.identify`,
        :func:`tsfdi.identify_windows`, :class:`tsfdi.Monitor`, :func:`tsfdi.evaluate`): global detection and
        identification with ``k`` logged or estimated (:meth:`estimate_k`). Its ``residuals`` are
        :meth:`residuals` at ``k``; ``sigma`` (VAR) / ``sigma2`` (AR, ARX) is ``sigma(k)``, and ``nobs``,
        ``df_resid``, ``llf``, ``bse`` and the criteria follow from it with the FP model's regression rows ``nobs``
        (so a test's reference variance and its degrees of freedom are the FP model's). The model behind it is the
        point family on all the FP records whose ``held_out_residuals`` are the FP model's
        (:meth:`tsfdi.FPAR.held_out_residuals`: each record at its own ``k_i`` through the FP model fitted without it), so
        that :meth:`tsfdi.LjungBox.calibrated_for` and the coverage checks of :func:`tsfdi.detect`,
        :class:`tsfdi.Monitor` and :func:`tsfdi.evaluate` read the FP model's null. ``resid`` (the in-sample
        residuals of every record through ``theta(k)``) does not match ``sigma(k)`` away from the records at ``k``,
        and ``save`` stores those records with ``theta(k)``: a loaded copy is a point model, whose residual
        covariance and held-out residuals are recomputed from those records (not ``sigma(k)``, not the FP model's
        null): save the FP results and call ``at(k)`` after loading them.

        Parameters
        ----------
        k : float or array_like (d,)
            The operating point (inside ``k_range``; beyond it the polynomials extrapolate).

        Returns
        -------
        ARResults, VARResults or ARXResults
        """
        kk = self._point(k)
        pt = self.model.point
        sc = pt.y_scale
        sse = self.sigma(kk) * self.nobs / np.outer(sc, sc)          # the point results' E'E, in its fit units
        return pt.results_class(self.model._point_at, self._theta2d(kk), residual_products=sse)

    def residuals(self, y: Any, k: Any, u: Any = None) -> Any:
        """One-step prediction errors of a new signal through the model at operating point ``k``
        (``theta(k)``), as the point model's ``residuals``: same kind as ``y``, from sample ``max_lag`` on, channels
        matched by name.

        Parameters
        ----------
        y : array_like, Series, DataFrame or DataArray
        k : float or array_like (d,)
            The operating point (logged, or estimated by :meth:`estimate_k`).
        u : optional
            The inputs (FP-ARX only, required there).
        """
        res = self.at(k)
        if self.model.nb:
            if u is None:
                raise ValueError("u is required: an FP-ARX filters a new output with its input")
            return res.residuals(y, u)
        if u is not None:
            raise ValueError("u is given but the model has no input")
        return res.residuals(y)

    def estimate_k(self, y: Any, u: Any = None, *, alpha: float = 0.05, bounds: Any = None,
                   grid: int = 201) -> OperatingPointEstimate:
        """The operating point that best explains a new record: maximum likelihood over ``k``.

        The residuals ``e_t(k)`` of ``y`` through ``theta(k)`` are linear in the basis ``G(k)``
        (``e_t(k) = y_t - sum_j G_j(k) phi_t' theta_j``), so their cross products for any ``k`` follow from one
        ``((p + 1) s)^2`` matrix of the record. The noise covariance of the new record is unknown and profiled
        out: the log-likelihood is ``-n/2 (s ln 2 pi + ln det(E(k)'E(k) / n) + s)``. It is maximised over a grid
        of the bounds (``grid`` points per parameter, at most 41 per parameter for several), then refined by a
        bounded search, and the profile log-likelihood of every parameter is traced on ``grid`` points; the
        standard error is the inverse of the observed information (the curvature of the
        log-likelihood at ``k_hat``, central differences) plus the part carried by the FP coefficients' own
        estimation error (:attr:`OperatingPointEstimate.cov_fp`, delta method: ``B Cov(theta(k_hat)) B'`` with
        ``B = (D'ID)^{-1} D'I`` the sensitivity of ``k_hat`` to the point parameters, ``D = d theta / dk`` and ``I``
        the record's information ``Sigma^{-1} (x) X'X``), and the interval is ``k_hat -+ z_{1-alpha/2} se``. Without
        that second part a long record would hold the fitted model's error as a bias the interval ignores.

        Parameters
        ----------
        y, u : signal (and input for an FP-ARX)
            The new record (channels matched by name).
        alpha : float
            The interval has level ``1 - alpha``.
        bounds : array_like (d, 2), optional
            Search interval of every parameter (default: the model's ``k_range``; beyond it the polynomials
            extrapolate).
        grid : int
            Grid points of the first search per parameter (>= 5).

        Returns
        -------
        OperatingPointEstimate
        """
        alpha = probability(alpha)
        grid = int_like(grid, "grid", minimum=5)
        m = self.model
        d = len(m.k_names)
        if bounds is None:
            bnd = m.k_range.copy()
        else:
            try:
                bnd = np.asarray(bounds, dtype=float).reshape(d, 2)
            except (TypeError, ValueError):
                raise ValueError(f"bounds must be ({d}, 2) intervals (low, high), got {bounds!r}") from None
            if not np.isfinite(bnd).all() or not (bnd[:, 1] > bnd[:, 0]).all():
                raise ValueError(f"bounds must be finite intervals with low < high, got {bnd.tolist()}")
        W, n, XX = self._record_products(y, u)
        s = self.neqs

        def negllf(kv: np.ndarray) -> float:
            c = np.r_[1.0, self._g(np.asarray(kv, dtype=float))]
            S = np.tensordot(np.tensordot(c, W, axes=(0, 0)), c, axes=(1, 0)) / n     # sum_jl c_j c_l W[j, :, l, :]
            sign, ld = np.linalg.slogdet(S)
            if sign <= 0:
                return np.inf
            return 0.5 * n * (s * np.log(2 * np.pi) + ld + s)

        m1 = grid if d == 1 else min(grid, 41)
        axes = [np.linspace(lo, hi, m1) for lo, hi in bnd]
        pts = np.array(list(itertools.product(*axes)))
        vals = np.array([negllf(p) for p in pts])
        best = pts[int(np.argmin(vals))]
        step = (bnd[:, 1] - bnd[:, 0]) / (m1 - 1)
        lo = np.maximum(best - step, bnd[:, 0])
        hi = np.minimum(best + step, bnd[:, 1])
        if d == 1:
            r = optimize.minimize_scalar(lambda x: negllf(np.array([x])), bounds=(lo[0], hi[0]), method="bounded",
                                         options={"xatol": 1e-10 * (bnd[0, 1] - bnd[0, 0])})
            k_hat = np.array([r.x])
        else:
            r = optimize.minimize(negllf, best, method="L-BFGS-B", bounds=list(zip(lo, hi)))
            k_hat = np.asarray(r.x, dtype=float)
        if negllf(k_hat) > negllf(best):
            k_hat = best
        # observed information by central differences (one-sided at a bound)
        h = 1e-3 * (bnd[:, 1] - bnd[:, 0])
        H = np.empty((d, d))
        f0 = negllf(k_hat)
        for a in range(d):
            for b in range(a, d):
                ea, eb = np.eye(d)[a] * h[a], np.eye(d)[b] * h[b]
                if a == b:
                    H[a, a] = (negllf(k_hat + ea) - 2 * f0 + negllf(k_hat - ea)) / h[a] ** 2
                else:
                    H[a, b] = H[b, a] = (negllf(k_hat + ea + eb) - negllf(k_hat + ea - eb)
                                         - negllf(k_hat - ea + eb) + negllf(k_hat - ea - eb)) / (4 * h[a] * h[b])
        at_bound = bool(((k_hat - bnd[:, 0]) < 2 * h).any() or ((bnd[:, 1] - k_hat) < 2 * h).any())
        evals = np.linalg.eigvalsh(H) if np.isfinite(H).all() else np.array([-1.0])
        if (evals > 0).all():
            cov_fp = self._k_cov_from_fp(k_hat, W, n, XX, h)
            cov = np.linalg.inv(H) + cov_fp
            se = np.sqrt(np.diag(cov))
        else:
            cov = cov_fp = np.full((d, d), np.inf)
            se = np.full(d, np.inf)
            warnings.warn("estimate_k: the log-likelihood is not curved downwards at k_hat (flat, or the "
                          "maximum lies on a bound): no interval from the curvature", IllConditionedWarning,
                          stacklevel=2)
        q = stats.norm.isf(alpha / 2)
        ci = np.stack([k_hat - q * se, k_hat + q * se], axis=1)
        # the profile log-likelihood of each parameter: the others maximised (bounded) at every grid value,
        # each search started from the previous grid value's optimum
        curve_k = np.stack([np.linspace(lo_, hi_, grid) for lo_, hi_ in bnd])
        curve = np.empty_like(curve_k)
        for a in range(d):
            others = [b for b in range(d) if b != a]
            start = k_hat[others]
            for i, v in enumerate(curve_k[a]):
                kk = k_hat.copy()
                kk[a] = v
                if others:
                    def profile(x, kk=kk):
                        kk[others] = x
                        return negllf(kk)

                    r = optimize.minimize(profile, start, method="L-BFGS-B", bounds=[tuple(bnd[b]) for b in others])
                    start = np.asarray(r.x, dtype=float)
                    kk[others] = start
                curve[a, i] = -negllf(kk)
        for arr in (k_hat, se, ci, cov, cov_fp, curve_k, curve, bnd):
            arr.setflags(write=False)
        return OperatingPointEstimate(k_hat=k_hat, bse=se, conf_int=ci, cov=cov, cov_fp=cov_fp, alpha=alpha,
                                      llf=-f0, nobs=int(n),
                                      names=list(m.k_names), bounds=bnd, grid=curve_k, loglik=curve,
                                      at_bound=at_bound)

    def _record_products(self, y: Any, u: Any) -> tuple[np.ndarray, int, np.ndarray]:
        """``W[j, l] = Z_j' Z_l`` (shape (p+1, s, p+1, s)) of ``Z_0 = y[t]`` and ``Z_j = -phi_t' theta_j`` (the part
        of the prediction carried by basis function ``j``) of a new record in the data's units, its rows, and the
        Gram matrix ``X'X`` of its point regressor. The record is validated and its channels matched by name as
        the point model's ``residuals`` does."""
        m = self.model
        pt = m.point
        if pt.nb and u is None:
            raise ValueError("u is required: an FP-ARX estimates k from an output and its input")
        if not pt.nb and u is not None:
            raise ValueError("u is given but the model has no input")
        sig = as_signal(y, "y", vector=self._vector_output, min_nobs=pt.max_lag + 2, allow_constant=True)
        sig = sig.match_channels(pt.data.channels, "y", named=pt.data.named)
        uv = None
        if pt.nb:
            usig = as_signal(u, "u", min_nobs=pt.max_lag + 2, allow_constant=True)
            usig = usig.match_channels(pt.u_data.channels, "u", named=pt.u_data.named,
                                       reference="the model's inputs are")
            if usig.nobs != sig.nobs:
                raise ValueError(f"u has {usig.nobs} samples but y has {sig.nobs}: they must match")
            uv = usig.values
        X, Y = lagged_design(sig.values, pt.na, pt.max_lag, const=bool(pt.k_const), u=uv, nb=pt.nb, nk=pt.nk)
        P = self._params2d.reshape(m.df_point, m.n_basis, -1)
        with np.errstate(over="ignore", invalid="ignore"):
            Z = np.concatenate([Y[:, None, :], -np.einsum("ta,ajc->tjc", X, P)], axis=1)   # (n, p+1, s)
            n = Z.shape[0]
            Zf = Z.reshape(n, -1)
            W = (Zf.T @ Zf).reshape(m.n_basis + 1, self.neqs, m.n_basis + 1, self.neqs)
            XX = X.T @ X
        if not (np.isfinite(W).all() and np.isfinite(XX).all()):
            raise ValueError(f"y: the residuals through the {type(m).__name__} leave the floating-point range (y "
                             f"peaks at {np.abs(sig.values).max():.3g}); rescale y to the units of the model's data")
        return W, n, XX

    @property
    def _vector_output(self) -> bool:
        return self.model._vector

    def _k_cov_from_fp(self, k_hat: np.ndarray, W: np.ndarray, n: int, XX: np.ndarray, h: np.ndarray) -> np.ndarray:
        """Covariance of ``k_hat`` carried by the FP coefficients' estimation error (delta method, see
        :meth:`estimate_k`), (d, d)."""
        m = self.model
        d, s, df = k_hat.size, self.neqs, m.df_point
        g = self._g(k_hat)
        c = np.r_[1.0, g]
        S = np.tensordot(np.tensordot(c, W, axes=(0, 0)), c, axes=(1, 0)) / n
        # D: d theta / dk, (df * s, d) in vec (column-major: equation outer) order
        D = np.empty((df * s, d))
        for a in range(d):
            e = np.eye(d)[a] * h[a]
            D[:, a] = ((self._theta2d(k_hat + e) - self._theta2d(k_hat - e)) / (2 * h[a])).T.ravel()
        info = np.kron(np.linalg.inv(S), XX)
        DI = D.T @ info
        B = np.linalg.solve(DI @ D, DI)                                     # (d, df * s)
        # Cov(theta(k_hat)) across equations: per-equation blocks, cross blocks from the residual correlation
        L = np.kron(np.eye(df), g[None, :])                                 # theta(k) = L theta_fp
        blocks = L @ self._cov @ L.T                                        # (s, df, df)
        if self.weights is None and s > 1:
            sp = self.sigma_pooled
            sd = np.sqrt(np.diag(sp))
            corr = sp / np.outer(sd, sd)
        else:
            corr = np.eye(s)
        C = np.empty((s * df, s * df))
        for e in range(s):
            for f in range(s):
                base = np.sqrt(np.abs(blocks[e] * blocks[f])) * np.sign(blocks[e])
                C[e * df:(e + 1) * df, f * df:(f + 1) * df] = blocks[e] if e == f else corr[e, f] * base
        return B @ C @ B.T

    # --- output
    def summary(self, alpha: float = 0.05) -> Summary:
        """Fit statistics and one coefficient table per equation (coef, std err, z, P>|z|, interval)."""
        alpha = probability(alpha)
        m = self.model
        header = [("Model", type(m).__name__), ("Channels", ", ".join(map(str, m.data.channels))),
                  ("Order", f"{m._lag_name}={m.na}" + (f", nb={m.nb}, nk={m.nk}" if m.nb else "")),
                  ("Trend", m.trend), ("Operating parameters", ", ".join(
                      f"{n} in [{lo:g}, {hi:g}]" for n, (lo, hi) in zip(m.k_names, m.k_range))),
                  ("Basis", f"{m.basis}, degree {', '.join(map(str, m.degree))} ({m.n_basis} functions)"),
                  ("Weights", m.weights),
                  ("Records", len(m.records)), ("Operating points", len(np.unique(m.k, axis=0))),
                  ("Observations", self.nobs), ("Parameters", self.df_model), ("Log-likelihood", self.llf),
                  ("AIC", self.aic), ("BIC", self.bic)]
        q = stats.norm.isf(alpha / 2)
        names = self._param_names()
        tables = []
        for j, ch in enumerate(m.data.channels):
            coef, bse = self._params2d[:, j], self._bse2d[:, j]
            with np.errstate(divide="ignore", invalid="ignore"):
                z = coef / bse
            tables.append((f"Equation {ch}" if m._vector else f"Coefficients of {ch}", pd.DataFrame(
                {"coef": coef, "std err": bse, "z": z, "P>|z|": 2 * stats.norm.sf(np.abs(z)),
                 f"[{alpha / 2:g}": coef - q * bse, f"{1 - alpha / 2:g}]": coef + q * bse}, index=names)))
        notes = ["theta(k) = sum_j theta_j G_j(k); point parameters in the papers' sign "
                 "(y[t] + sum_i a_i(k) y[t-i] = c(k) + ... + e[t]).",
                 "std err from s_j^2 (X'WX)^-1, s_j^2 = RSS_j / (nobs - df_eq) (weighted least squares); z and "
                 "P>|z| from the normal distribution."]
        return Summary(f"{type(m).__name__} results", header, tables, notes)

    def save(self, path: Any) -> Any:
        """Save the model (records, operating points, options) and its coefficients for
        :func:`tsfdi.models.load`; see :mod:`tsfdi.models.archive`."""
        return save_archive(self, path)

    def __repr__(self) -> str:
        m = self.model
        return (f"FPResults({type(m).__name__}, {m._lag_name}={m.na}, degree={m.degree}, nobs={self.nobs}, "
                f"bic={self.bic:.6g})")


for _cls in (FPAR, FPVAR, FPARX):
    _cls.results_class = FPResults


@dataclasses.dataclass(frozen=True, eq=False)
class OperatingPointEstimate:
    """Maximum-likelihood operating point of a record (:meth:`FPResults.estimate_k`), frozen.

    Attributes
    ----------
    k_hat : ndarray (d,)
        The estimate.
    bse : ndarray (d,)
        Its standard error from the observed information (``inf`` when the log-likelihood is not curved downwards).
    conf_int : ndarray (d, 2)
        ``k_hat -+ z_{1-alpha/2} bse``.
    cov : ndarray (d, d)
        Covariance of ``k_hat``: the inverse observed information plus :attr:`cov_fp`.
    cov_fp : ndarray (d, d)
        The part of ``cov`` carried by the FP coefficients' estimation error (delta method).
    alpha : float
    llf : float
        Maximised (profiled) log-likelihood.
    nobs : int
        Residual samples of the record.
    names : list of str
        The operating parameters.
    bounds : ndarray (d, 2)
        Search interval.
    grid, loglik : ndarray (d, m)
        The profile log-likelihood of each parameter on a grid of its bounds (the others maximised within theirs;
        for one parameter, the likelihood curve).
    at_bound : bool
        ``k_hat`` within two difference steps of a bound (the interval is then one-sided in truth).
    """

    k_hat: np.ndarray
    bse: np.ndarray
    conf_int: np.ndarray
    cov: np.ndarray
    cov_fp: np.ndarray
    alpha: float
    llf: float
    nobs: int
    names: list
    bounds: np.ndarray
    grid: np.ndarray
    loglik: np.ndarray
    at_bound: bool

    def covers(self, k: Any) -> bool:
        """Whether the interval holds ``k`` in every parameter."""
        kk = np.asarray(k, dtype=float).reshape(-1)
        if kk.size != self.k_hat.size or not np.isfinite(kk).all():
            raise ValueError(f"k must be one finite operating point with {self.k_hat.size} value(s), got {k!r}")
        return bool(((self.conf_int[:, 0] <= kk) & (kk <= self.conf_int[:, 1])).all())

    def summary(self) -> Summary:
        table = pd.DataFrame({"k_hat": self.k_hat, "std err": self.bse,
                              f"[{self.alpha / 2:g}": self.conf_int[:, 0],
                              f"{1 - self.alpha / 2:g}]": self.conf_int[:, 1],
                              "low bound": self.bounds[:, 0], "high bound": self.bounds[:, 1]}, index=self.names)
        return Summary("Operating-point estimate", [("Observations", self.nobs), ("Log-likelihood", self.llf),
                                                    ("At a bound", self.at_bound)], [("Estimate", table)],
                       ["Maximum likelihood over the FP model (noise covariance profiled out); interval from the "
                        "observed information plus the FP coefficients' estimation error (delta method)."])

    def plot(self, ax: Any = None) -> Any:
        """The log-likelihood curve with ``k_hat`` and its interval (:func:`tsfdi.plotting.fp.plot_k_estimate`)."""
        from tsfdi.plotting.fp import plot_k_estimate

        return plot_k_estimate(self, ax=ax)

    def __repr__(self) -> str:
        parts = ", ".join(f"{n}={v:.6g} [{lo:.6g}, {hi:.6g}]" for n, v, (lo, hi)
                          in zip(self.names, self.k_hat, self.conf_int))
        return f"OperatingPointEstimate({parts}, level={1 - self.alpha:g})"


@dataclasses.dataclass(frozen=True, eq=False)
class FPOrderSelection:
    """Orders and basis degrees of an FP model compared on a common sample (:func:`select_fp_order`), frozen.

    Attributes
    ----------
    table : DataFrame
        ``llf``, ``aic``, ``bic`` and ``df_model`` per ``(lags, degree)`` (a MultiIndex).
    selected : tuple of int
        ``(lags, degree)`` of the smallest BIC.
    spec : dict
        The arguments that rebuild the FP model (for :meth:`fit`).
    """

    table: pd.DataFrame
    selected: tuple
    spec: dict

    def fit(self, lags: int | None = None, degree: int | None = None) -> FPResults:
        """Fit the selected (or the given) order and degree on the records, with the common ``hold_back``."""
        lg, dg = self.selected
        sp = dict(self.spec)
        family = sp.pop("family")
        lags = lg if lags is None else lags
        degree = dg if degree is None else degree
        if family is FPARX:
            sp.pop("nb")
            return FPARX(sp.pop("y"), sp.pop("u"), sp.pop("k"), lags, lags, sp.pop("nk"), degree, **sp).fit()
        sp.pop("u"), sp.pop("nb"), sp.pop("nk")
        return family(sp.pop("y"), sp.pop("k"), lags, degree, **sp).fit()

    def summary(self) -> Summary:
        return Summary("FP order selection", [("Selected (lags, degree)", str(self.selected))],
                       [("Criteria", self.table)], ["BIC on a common sample (hold back max_lags in every record)."])

    def __repr__(self) -> str:
        return f"FPOrderSelection(selected lags={self.selected[0]}, degree={self.selected[1]})"


def select_fp_order(y: Any, k: Any, max_lags: int, max_degree: int, model: str = "ar", *, u: Any = None,
                    nk: int = 0, trend: str = "n", basis: str = "legendre",
                    k_range: Any = None) -> FPOrderSelection:
    """Choose the order and the basis degree of an FP model by BIC on a common sample.

    Every ``lags = 1 .. max_lags`` and ``degree = 0 .. max_degree`` (the same degree for every operating parameter)
    is fitted by pooled least squares on the regression rows from ``max_lags`` on in every record (as
    :func:`tsfdi.select_order`), all from one Gram matrix per record (the largest order: the lower ones are its
    leading blocks) and the basis of the largest degree (the lower ones are its leading functions).

    Parameters
    ----------
    y, k : as :class:`FPAR` (a list of records and their operating points)
    max_lags, max_degree : int
    model : {"ar", "var", "arx"}
    u, nk : input records and delay of an FP-ARX (``model="arx"`` compares ``na = nb = lags``)
    trend, basis, k_range : as :class:`FPAR`

    Returns
    -------
    FPOrderSelection
    """
    model = option(model, "model", ("ar", "var", "arx"))
    max_lags = int_like(max_lags, "max_lags", minimum=1)
    max_degree = int_like(max_degree, "max_degree", minimum=0)
    family = {"ar": FPAR, "var": FPVAR, "arx": FPARX}[model]
    if model == "arx":
        if u is None:
            raise ValueError("model='arx' needs the input records u")
        nbs = max_lags
        big = FPARX(y, u, k, max_lags, nbs, nk, max_degree, trend, basis=basis, hold_back=max(max_lags, nk + nbs - 1),
                    k_range=k_range)
    else:
        if u is not None:
            raise ValueError(f"u is given but model={model!r} has no input; use model='arx'")
        nbs = 0
        big = family(y, k, max_lags, max_degree, trend, basis=basis, k_range=k_range)
    grams = big.record_grams()
    s = big.neqs
    c = big.point.k_const
    m_in = big.point.n_inputs
    N = sum(big.nobs_records)
    names = big.basis_names()
    letter_len = len(_LETTER[big.basis])
    idx = [tuple(int(v) for v in nm[letter_len:].split(",")) for nm in names]
    rows = []
    for lags in range(1, max_lags + 1):
        keep_point = np.arange(c + lags * (s + m_in))   # the lag groups (outputs and inputs) up to ``lags``
        sub = np.concatenate([keep_point, np.arange(grams.shape[1] - s, grams.shape[1])])
        g_lags = grams[:, sub][:, :, sub]
        kp = keep_point.size
        for deg in range(max_degree + 1):
            cols = [j for j, t in enumerate(idx) if max(t) <= deg]
            G = big.G[:, cols]
            A, b = big._pooled_system(g_lags, None, G, kp)
            R = gram_factor(A[0], A.shape[1])
            if R is None:
                rows.append((lags, deg, np.nan, np.nan, np.nan, kp * len(cols) * s))
                continue
            coef = lapack.dpotrs(R, b, lower=0)[0]
            YY = g_lags[:, kp:, kp:].sum(axis=0)
            sse = YY - b.T @ coef
            sigma = sse / N * np.outer(big.point.y_scale, big.point.y_scale)
            sign, ld = np.linalg.slogdet(sigma)
            llf = -0.5 * N * (s * np.log(2 * np.pi) + ld + s) if sign > 0 else np.nan
            nfree = kp * len(cols) * s + s * (s + 1) // 2
            rows.append((lags, deg, llf, -2 * llf + 2 * nfree, -2 * llf + nfree * np.log(N), kp * len(cols) * s))
    table = pd.DataFrame(rows, columns=["lags", "degree", "llf", "aic", "bic", "df_model"]).set_index(
        ["lags", "degree"])
    if not np.isfinite(table["bic"]).any():
        raise ValueError("select_fp_order: no order and degree gives a well-conditioned fit")
    selected = tuple(int(v) for v in table["bic"].idxmin())
    spec = {"family": family, "y": list(y), "u": None if u is None else list(u), "k": k, "nb": nbs, "nk": nk,
            "trend": trend, "basis": basis, "k_range": big.k_range, "hold_back": big.hold_back}
    return FPOrderSelection(table=table, selected=selected, spec=spec)


# --------------------------------------------------------------------------------------------------------------
# the functionally pooled mean of windows (the trim model)
# the local refinement of k (FPMeanResults._profile): at most _REFINE rounds, until the local grid spans less than
# _REFINE_TOL of the range
_REFINE = 50
_REFINE_TOL = 1e-7

def _window_means(values: np.ndarray, window: int, starts: np.ndarray) -> np.ndarray:
    """Means of ``values`` (nobs, s) over ``[a, a + window)`` for every start ``a``, (windows, s), computed in chunks
    of at most ~4M samples (the mean of consecutive windows is that of the reshaped record)."""
    out = np.empty((starts.size, values.shape[1]))
    chunk = max(1, (1 << 22) // (window * values.shape[1]))
    offs = np.arange(window)
    for c in range(0, starts.size, chunk):
        a = starts[c:c + chunk]
        out[c:c + a.size] = values[a[:, None] + offs].mean(axis=1)
    return out


@register
class FPMean:
    r"""Functionally pooled mean of windows: the level (trim) of a signal's windows as a surface over operating
    parameters ``k``.

    A closed loop that compensates a fault holds its commands on a new steady level: the window mean of the
    controller outputs moves, while their one-step prediction errors barely change (paper 003 names the
    controller's fault compensation as the next step; an FP-VAR's lags carry the level). This model regresses the
    mean :math:`m_{i,w}` of window ``w`` of record ``i`` on the functional basis of the record's operating point
    :math:`k_i` (Kopsaftopoulos and Fassois 2010, 2013: the FP expansion of :class:`FPAR` with the point model
    reduced to a mean),

    .. math::

        m_{i,w} = M(k_i) + \varepsilon_i + \eta_{i,w}, \qquad M(k) = \sum_{j=1}^{p} \beta_j\, G_j(k),

    by pooled least squares over all windows of all records. :math:`\varepsilon_i` is the record's own offset (an
    unlogged airframe: its centre of gravity moves the whole trim of the record) and :math:`\eta_{i,w}` the window's
    spread about its record's mean. The covariance of a window's residual is

    .. math::

        S = \frac{1}{N - p} \sum_i \bar e_i \bar e_i' + \frac{1}{\sum_i n_i - N} \sum_{i,w} (m_{i,w} - \bar m_i)
            (m_{i,w} - \bar m_i)',

    with :math:`\bar e_i = \bar m_i - M(k_i)` the mean residual of record ``i`` (``N`` records, ``n_i`` windows
    each): the records, not the windows, are the independent units of the first term (its degrees of freedom are
    records minus basis functions; counted over windows it takes the record offsets the surface absorbs for noise
    and is too small when there are few records per basis function).

    A new window's mean ``m`` is judged at the ``k`` that explains it best: the Gaussian log-likelihood
    :math:`\ell(k) = -\tfrac12 (s \ln 2\pi + \ln\det S + q(k))`, :math:`q(k) = (m - M(k))' S^{-1} (m - M(k))`,
    maximised over ``k`` in ``k_range`` (:meth:`FPMeanResults.estimate_k`). Its largest value
    (:meth:`FPMeanResults.loglike`) ranks the classes of :func:`tsfdi.identify`; its smallest distance
    :math:`\min_k q(k)` (:meth:`FPMeanResults.statistic`) is the detector's statistic, whose null law has no closed
    form (profiling ``k`` takes up part of it): calibrate its threshold on healthy records that were not fitted
    (:class:`tsfdi.EmpiricalThreshold`).

    Parameters
    ----------
    y : list of array_like, DataFrame or DataArray
        The records (at least 2), each ``(nobs, s)`` (a 1-D record is one channel); a named record's channels are
        matched by name to the first record's. Each record's consecutive windows of ``window`` samples are used;
        its last ``nobs % window`` samples fill no window and are not used.
    k : array_like (records,) or (records, d), Series or DataFrame
        The operating point of every record (a DataFrame's columns / a Series' name name the parameters).
    window : int or time span
        Window length: an int counts samples, a time span (``"5s"``) is converted with the first record's time
        index.
    degree : int or sequence of int
        Largest polynomial degree of the basis in each operating parameter.
    basis : {"legendre", "chebyshev"}
    k_range : array_like (d, 2), optional
        The interval of each parameter mapped onto ``[-1, 1]`` and searched for ``k`` (default: the range of ``k``).
    grid : int
        Points per parameter of the search grid of ``k`` (>= 2); the grid's best point is then refined by local
        grids about the best point so far (21 points per parameter for one parameter, 13 for two, fewer for more), each
        spanning +- one spacing of the previous one and bounded by ``k_range``, to ``1e-7`` of the range.

    Raises
    ------
    ValueError
        Fewer than 2 records, a record shorter than ``window`` or with a constant channel or NaN / inf (named
        ``y[i]``), records whose channels differ, ``k`` not one finite point per record, a parameter with fewer
        distinct values than ``degree + 1``, fewer records than basis functions plus channels, no record with two
        windows.
    TypeError
        Non-numeric data or ``k``, a non-integer degree or grid, a ``window`` that is neither an int nor a time span.

    Notes
    -----
    The identification rule of ``benchmarks/fp_hexacopter.py`` (issue 32): one model per class (healthy, each
    failed rotor) of the controller outputs; a window goes to the class of the largest :meth:`~FPMeanResults.loglike`
    (:func:`tsfdi.identify_windows`, ``decide("likelihood")``).
    """

    def __init__(self, y: Any, k: Any, window: Any, degree: Any = 1, *, basis: str = "legendre", k_range: Any = None,
                 grid: int = 11) -> None:
        if not isinstance(y, (list, tuple)) or len(y) < 2:
            raise ValueError("y must be a list of records (at least 2), one per operating point")
        self.basis = option(basis, "basis", tuple(_VANDER))
        self.grid = int_like(grid, "grid", minimum=2)
        recs = [as_signal(r, f"y[{i}]") for i, r in enumerate(y)]
        first = recs[0]
        recs = [first] + [r.match_channels(first.channels, f"y[{i}]", named=first.named,
                                           reference="y[0] has the")
                          for i, r in enumerate(recs[1:], start=1)]
        self.records = tuple(recs)
        rates = [sampling_frequency(r, None, f"y[{i}]") for i, r in enumerate(recs)]
        timed = [(i, f) for i, f in enumerate(rates) if f is not None]
        odd = [i for i, f in timed if abs(f / timed[0][1] - 1.0) > 0.01]
        if odd:
            raise ValueError(f"y[{odd[0]}] is sampled at {rates[odd[0]]:g} Hz but y[{timed[0][0]}] at "
                             f"{timed[0][1]:g} Hz: the windows of the records must span the same time (resample with "
                             "tsfdi.align)")
        self.window = window_samples(window, "window", rates[0], minimum=1)
        short = [i for i, r in enumerate(recs) if r.nobs < self.window]
        if short:
            raise ValueError(f"y[{short[0]}] has {recs[short[0]].nobs} samples, fewer than window={self.window}")
        self.k, self.k_names, self.degree, self.k_range = _operating_setup(k, len(recs), degree, k_range)
        p, s = int(np.prod([g + 1 for g in self.degree])), first.nchan
        if len(recs) < p + s:
            raise ValueError(f"degree {self.degree}: {p} basis functions and {s} channel(s) need at least {p + s} "
                             f"records (the records' covariance has records - basis functions degrees of freedom), "
                             f"y has {len(recs)}")
        if all(r.nobs < 2 * self.window for r in recs):
            raise ValueError(f"y: no record holds two windows of {self.window} samples: the spread of the windows "
                             "about their record's mean cannot be estimated")

    # the archive's common layout
    multi = True
    u_records = None

    @property
    def data(self):
        return self.records[0]

    @property
    def neqs(self) -> int:
        return self.records[0].nchan

    @property
    def n_basis(self) -> int:
        return int(np.prod([g + 1 for g in self.degree]))

    def basis_names(self) -> list[str]:
        """Names of the basis functions (as :meth:`FPAR.basis_names`)."""
        letter = _LETTER[self.basis]
        return [letter + ",".join(map(str, idx)) for idx in itertools.product(*[range(g + 1) for g in self.degree])]

    def window_means(self) -> list[np.ndarray]:
        """The means of every record's consecutive windows, one ``(windows, s)`` array per record."""
        w = self.window
        return [_window_means(r.values, w, np.arange(0, r.nobs - w + 1, w)) for r in self.records]

    def fit(self) -> FPMeanResults:
        """Estimate the surface by pooled least squares over all windows of all records, and the covariance ``S``
        of a window's residual (see the class documentation)."""
        M = self.window_means()
        Gr = fp_basis(self.k, self.degree, self.k_range, self.basis)
        G = np.repeat(Gr, [len(m) for m in M], axis=0)
        B = np.linalg.lstsq(G, np.vstack(M), rcond=None)[0]
        if not np.isfinite(B).all():
            raise ValueError("y: the surface's coefficients leave the floating-point range; rescale y")
        return FPMeanResults(self, B)

    def __repr__(self) -> str:
        return (f"FPMean(records={len(self.records)}, window={self.window}, degree={self.degree}, "
                f"basis={self.basis!r})")


class FPMeanResults(FrozenResults):
    """Results of :meth:`FPMean.fit` (immutable).

    Attributes
    ----------
    params : ndarray or DataFrame, shape (n_basis, s)
        The coefficients ``beta_j`` of the surface, one column per channel (labelled for pandas / xarray records).
    bse, tvalues, pvalues : same shape
        Standard errors with the records as the independent units, ``sqrt(diag(A^-1 (sum_i n_i^2 g_i g_i') A^-1)
        S_rec[c, c])`` with ``A = sum_i n_i g_i g_i'`` (``g_i = G(k_i)``, ``n_i`` windows of record ``i``; the
        ordinary least-squares errors of the record means when every record has as many windows), ``params / bse``
        and the two-sided normal p-values.
    S : ndarray (s, s)
        Covariance of a window mean's residual: ``S_rec + S_within``.
    S_rec : ndarray (s, s)
        Covariance of the records' mean residuals, ``sum_i ebar_i ebar_i' / (records - n_basis)``.
    S_within : ndarray (s, s)
        Covariance of the windows about their record's mean, over ``windows - records`` degrees of freedom.
    nobs : int
        Records (the independent units of the criteria).
    nwindows : int
        Windows of all records.
    llf, bic : float
        Gaussian log-likelihood of the records' mean residuals, ``-N/2 (s ln 2 pi + ln det(sum_i ebar_i ebar_i' / N)
        + s)``, and ``-2 llf + (n_basis s + s (s + 1) / 2) ln N``: compare degrees on the same records.
    """

    def __init__(self, model: FPMean, params: Any) -> None:
        B = np.array(params, dtype=float).reshape(model.n_basis, model.neqs)
        M = model.window_means()
        Gr = fp_basis(model.k, model.degree, model.k_range, model.basis)
        n_rec, p = Gr.shape
        counts = np.array([len(m) for m in M], dtype=float)
        ebar = np.stack([m.mean(axis=0) for m in M]) - Gr @ B
        dev = np.vstack([m - m.mean(axis=0) for m in M])
        S_rec = ebar.T @ ebar / (n_rec - p)
        within = dev.T @ dev / (len(dev) - n_rec)
        S = S_rec + within
        sign, logdet = np.linalg.slogdet(S)
        sign_ml, logdet_ml = np.linalg.slogdet(ebar.T @ ebar / n_rec)
        if sign <= 0 or sign_ml <= 0:
            raise ValueError("y: the covariance of the window means' residuals is singular (channels that are "
                             "collinear, or records that the surface fits exactly)")
        A = (Gr * counts[:, None]).T @ Gr
        Ainv = np.linalg.inv(A)
        V = Ainv @ ((Gr * (counts ** 2)[:, None]).T @ Gr) @ Ainv
        bse = np.sqrt(np.maximum(np.outer(V.diagonal(), S_rec.diagonal()), 0.0))
        axes = [np.linspace(lo, hi, model.grid) for lo, hi in model.k_range]
        k_grid = np.array(list(itertools.product(*axes)))
        for arr in (B, S, S_rec, within, bse, k_grid):
            arr.setflags(write=False)
        s = model.neqs
        llf = -0.5 * n_rec * (s * np.log(2 * np.pi) + logdet_ml + s)
        vals = {"model": model, "_params2d": B, "S": S, "S_rec": S_rec, "S_within": within, "_bse2d": bse,
                "_S_inv": np.linalg.inv(S), "_logdet": float(logdet), "_k_grid": k_grid,
                "_surface": fp_basis(k_grid, model.degree, model.k_range, model.basis) @ B,
                "nobs": n_rec, "nwindows": int(counts.sum()), "llf": float(llf),
                "bic": float(-2 * llf + (p * s + s * (s + 1) // 2) * np.log(n_rec))}
        for name, value in vals.items():
            object.__setattr__(self, name, value)

    # --- parameters
    @property
    def params2d(self) -> np.ndarray:
        """The coefficients (read-only), ``(n_basis, s)``."""
        return self._params2d

    @property
    def neqs(self) -> int:
        return self.model.neqs

    def _labelled(self, values: np.ndarray) -> Any:
        m = self.model
        if m.data.kind == "numpy":
            return values.copy()
        return pd.DataFrame(values.copy(), index=m.basis_names(), columns=list(m.data.channels))

    @property
    def params(self) -> Any:
        return self._labelled(self._params2d)

    @property
    def bse(self) -> Any:
        return self._labelled(self._bse2d)

    @property
    def tvalues(self) -> Any:
        with np.errstate(divide="ignore", invalid="ignore"):
            return self._labelled(self._params2d / self._bse2d)

    @property
    def pvalues(self) -> Any:
        with np.errstate(divide="ignore", invalid="ignore"):
            return self._labelled(2 * stats.norm.sf(np.abs(self._params2d / self._bse2d)))

    # --- new windows
    def _windows(self, signal: Any, step: Any) -> tuple:
        """The signal (its channels matched to the model's), its window starts and their means."""
        m = self.model
        sig = as_signal(signal, "signal", allow_constant=True)
        sig = sig.match_channels(m.data.channels, "signal", named=m.data.named)
        w = m.window
        if sig.nobs < w:
            raise ValueError(f"signal has {sig.nobs} samples, fewer than the model's window ({w})")
        step = w if step is None else window_samples(step, "step", sampling_frequency(sig, None), minimum=1)
        starts = np.arange(0, sig.nobs - w + 1, step)
        return sig, starts, _window_means(sig.values, w, starts)

    def _at(self, signal: Any, step: Any, k: Any) -> tuple:
        """The signal, its window starts and per window ``q(k) = (m - M(k))' S^-1 (m - M(k))`` at the given ``k``."""
        sig, starts, means = self._windows(signal, step)
        dev = means - self._surface_at(_operating_point(k, self.model.k_names))
        return sig, starts, np.einsum("wa,ab,wb->w", dev, self._S_inv, dev)

    def _surface_at(self, k: np.ndarray) -> np.ndarray:
        m = self.model
        return fp_basis(k[None, :], m.degree, m.k_range, m.basis)[0] @ self._params2d

    def predict(self, k: Any) -> Any:
        """The surface at operating point ``k``: the expected window mean ``M(k) = sum_j beta_j G_j(k)`` of every
        channel (a Series over the channels for named records). Outside ``k_range`` the polynomials extrapolate
        (allowed, not advised)."""
        mean = self._surface_at(_operating_point(k, self.model.k_names))
        if self.model.data.kind == "numpy":
            return mean
        return pd.Series(mean, index=list(self.model.data.channels), name="mean")

    def _profile(self, signal: Any, step: Any) -> tuple:
        """The signal, its window starts, and per window the smallest ``q(k)`` and its ``k``: the grid's best point
        refined by local grids (bounded by ``k_range``), each spanning one spacing of the previous one."""
        m = self.model
        sig, starts, means = self._windows(signal, step)
        d = self._k_grid.shape[1]
        q = np.empty(starts.size)
        k_hat = np.empty((starts.size, d))
        lo, hi = self.model.k_range[:, 0], self.model.k_range[:, 1]
        n_loc = min(21, max(5, int(150 ** (1 / d)))) | 1                             # odd: the centre is a candidate
        offs = np.array(list(itertools.product(*[np.linspace(-1.0, 1.0, n_loc)] * d)))      # (n_loc^d, d)
        chunk = max(1, (1 << 20) // (max(self._surface.shape[0], offs.shape[0]) * self.neqs))
        for c in range(0, starts.size, chunk):
            mc = means[c:c + chunk]
            rows = np.arange(len(mc))
            dev = mc[:, None, :] - self._surface[None]
            qg = np.einsum("wka,ab,wkb->wk", dev, self._S_inv, dev)
            best = np.argmin(qg, axis=1)
            kc = self._k_grid[best]
            qc = qg[rows, best]
            # refinement: a local grid of n_loc points per parameter over +- h about the best point so far, h (first
            # one cell of the grid) shrunk to the local grid's spacing every round, until h < _REFINE_TOL * range
            h = (hi - lo) / (m.grid - 1)
            for _ in range(_REFINE):
                if not (h > _REFINE_TOL * (hi - lo)).any():
                    break
                cand = np.clip(kc[:, None, :] + offs[None] * h, lo, hi)                   # (w, n_loc^d, d)
                surf = fp_basis(cand.reshape(-1, d), m.degree, m.k_range, m.basis) @ self._params2d
                dv = mc[:, None, :] - surf.reshape(len(mc), offs.shape[0], -1)
                qq = np.einsum("wka,wka->wk", dv @ self._S_inv, dv)
                j = np.argmin(qq, axis=1)
                better = qq[rows, j] < qc
                kc = np.where(better[:, None], cand[rows, j], kc)
                qc = np.where(better, qq[rows, j], qc)
                h = h * 2 / (n_loc - 1)
            q[c:c + len(mc)] = qc
            k_hat[c:c + len(mc)] = kc
        return sig, starts, q, k_hat

    def _per_window(self, sig: Any, starts: np.ndarray, values: np.ndarray, columns: list | None, name: str) -> Any:
        """Per-window values in the signal's kind: indexed by the time (index label) of each window's first sample."""
        if sig.kind == "numpy":
            return values
        index = sig.index[starts]
        if sig.kind == "pandas":
            if columns is None:
                return pd.Series(values, index=index, name=name)
            return pd.DataFrame(values, index=index, columns=columns)
        import xarray as xr

        if columns is None:
            return xr.DataArray(values, dims=(sig.time_dim,), coords={sig.time_dim: np.asarray(index)}, name=name)
        return xr.DataArray(values, dims=(sig.time_dim, "parameter"),
                            coords={sig.time_dim: np.asarray(index), "parameter": columns}, name=name)

    def statistic(self, signal: Any, step: Any = None, *, k: Any = None) -> Any:
        """The detector's statistic of every window: ``min_k (m - M(k))' S^-1 (m - M(k))`` over ``k_range``, or
        ``(m - M(k))' S^-1 (m - M(k))`` at a given (logged) operating point ``k``.

        Parameters
        ----------
        signal : array_like, Series, DataFrame or DataArray
            A record of the model's channels (matched by name when both are named), at least ``window`` samples.
        step : int or time span, optional
            Samples between window starts (default ``window``: consecutive windows); windows that would pass the
            signal's end are not formed.
        k : float or sequence of float, optional
            The record's operating point (one value per operating parameter), when it is known: the statistic at
            it, a Mahalanobis distance with ``s`` degrees of freedom under the model (chi-square for Gaussian
            windows). Default: profiled over ``k_range`` (:meth:`estimate_k`).

        Returns
        -------
        ndarray (windows,), or a Series / DataArray indexed by the time of each window's first sample
        """
        sig, starts, q = self._at(signal, step, k) if k is not None else self._profile(signal, step)[:3]
        return self._per_window(sig, starts, q, None, "statistic")

    def loglike(self, signal: Any, step: Any = None, *, k: Any = None) -> Any:
        """The Gaussian log-likelihood of every window's mean at its maximum-likelihood ``k`` (or at the given ``k``),
        ``-1/2 (s ln 2 pi + ln det S + q(k))``; parameters and return as :meth:`statistic`."""
        sig, starts, q = self._at(signal, step, k) if k is not None else self._profile(signal, step)[:3]
        return self._per_window(sig, starts, self._loglike(q), None, "loglike")

    def _loglike(self, q: np.ndarray) -> np.ndarray:
        return -0.5 * (self.neqs * np.log(2 * np.pi) + self._logdet + q)

    def estimate_k(self, signal: Any, step: Any = None) -> Any:
        """The maximum-likelihood operating point of every window (the ``k`` of :meth:`statistic`), in ``k_range``.

        Returns
        -------
        ndarray (windows, d), or a DataFrame / DataArray (columns / ``parameter`` the operating parameters)
        indexed by the time of each window's first sample
        """
        sig, starts, _, k_hat = self._profile(signal, step)
        return self._per_window(sig, starts, k_hat, list(self.model.k_names), "k_hat")

    def profile(self, signal: Any, step: Any = None) -> tuple:
        """:meth:`statistic`, :meth:`loglike` and :meth:`estimate_k` of every window from one search over ``k``
        (what :func:`tsfdi.identify` needs of each model); parameters as :meth:`statistic`.

        Returns
        -------
        tuple
            ``(statistic, loglike, k_hat)``, each as its method returns it.
        """
        sig, starts, q, k_hat = self._profile(signal, step)
        return (self._per_window(sig, starts, q, None, "statistic"),
                self._per_window(sig, starts, self._loglike(q), None, "loglike"),
                self._per_window(sig, starts, k_hat, list(self.model.k_names), "k_hat"))

    # --- output
    def summary(self, alpha: float = 0.05) -> Summary:
        """Fit statistics, the coefficient table of every channel and the covariance ``S``."""
        alpha = probability(alpha)
        m = self.model
        header = [("Model", "FPMean"), ("Channels", ", ".join(map(str, m.data.channels))), ("Window", m.window),
                  ("Operating parameters", ", ".join(f"{n} in [{lo:g}, {hi:g}]" for n, (lo, hi)
                                                     in zip(m.k_names, m.k_range))),
                  ("Basis", f"{m.basis}, degree {', '.join(map(str, m.degree))} ({m.n_basis} functions)"),
                  ("Records", self.nobs), ("Windows", self.nwindows), ("Log-likelihood", self.llf),
                  ("BIC", self.bic)]
        q = stats.norm.isf(alpha / 2)
        names = m.basis_names()
        tables = []
        for j, ch in enumerate(m.data.channels):
            coef, bse = self._params2d[:, j], self._bse2d[:, j]
            with np.errstate(divide="ignore", invalid="ignore"):
                z = coef / bse
            tables.append((f"Surface of {ch}", pd.DataFrame(
                {"coef": coef, "std err": bse, "z": z, "P>|z|": 2 * stats.norm.sf(np.abs(z)),
                 f"[{alpha / 2:g}": coef - q * bse, f"{1 - alpha / 2:g}]": coef + q * bse}, index=names)))
        ch = [str(c) for c in m.data.channels]
        tables.append(("Covariance S of a window mean's residual", pd.DataFrame(self.S, index=ch, columns=ch)))
        notes = ["M(k) = sum_j beta_j G_j(k), pooled least squares over all windows; std err with the records as "
                 "the independent units; S = records' mean residuals (records - basis functions) + windows about "
                 "their record's mean; llf and BIC over records."]
        return Summary("FPMean results", header, tables, notes)

    def save(self, path: Any) -> Any:
        """Save the model (records, operating points, options) and its coefficients for
        :func:`tsfdi.models.load`; see :mod:`tsfdi.models.archive`."""
        return save_archive(self, path)

    def __repr__(self) -> str:
        m = self.model
        return (f"FPMeanResults(window={m.window}, degree={m.degree}, records={self.nobs}, "
                f"windows={self.nwindows}, bic={self.bic:.6g})")


FPMean.results_class = FPMeanResults

"""Common machinery of the least-squares time-series models (AR, VAR, ARX).

A model spec validates and stores its data and options; :meth:`fit` estimates by least squares and returns
an immutable results object whose derived quantities are cached properties computed from the model and the
parameter matrix alone. This is what makes :func:`tsfdi.models.load` lossless: a results object is fully
defined by its model (data + options) and its parameters.
"""

from __future__ import annotations

import dataclasses
import warnings
from functools import cached_property, partial
from typing import Any, ClassVar

import numba
import numpy as np
import pandas as pd
from scipy import linalg, stats
from scipy.linalg import lapack

from tsfdi._data import Signal, as_signal, channel_extremes, check_paired, is_xarray
from tsfdi._validation import int_like, option, probability
from tsfdi.exceptions import IllConditionedWarning, UnstableModelWarning
from tsfdi.models.archive import save as save_archive
from tsfdi.models.criteria import EXACT_FIT_RTOL, information_criteria
from tsfdi.models.lstsq import (MAX_VALUES, check_size, cholesky_nested_fits, gram_factor, gram_solve, lag_gram,
                                lag_residual_products, lagged_design, lstsq, nested_fits, triangular_factor)
from tsfdi.summary import Summary

__all__ = ["HeldOutResiduals", "InputOutputResults", "LinearTimeSeriesModel", "LinearTimeSeriesResults",
           "ScalarOutputResults", "VectorOutputResults", "DATA_RANGE", "check_covariance", "gaussian_innovations",
           "simulate_var"]

#: range of a channel's largest magnitude that the models accept: squares (variances) of data inside it stay
#: in the normal floating-point range (1e-304 .. 1e304), with four decades to spare
DATA_RANGE = (1e-152, 1e152)
#: channels whose largest magnitude lies in this band (about 1e-6 .. 1e6) are fitted in their own units (bit for
#: bit as always); the others in units of a power of two near it, which is exact and keeps them comparable with
#: the intercept column of ones (see :attr:`LinearTimeSeriesModel.y_scale`)
_OWN_UNITS = (2.0**-20, 2.0**20)


def _channel_scale(records: list[Signal], name: str, channels: list) -> tuple[np.ndarray, np.ndarray, bool]:
    """Largest magnitude of every channel over all records, checked against :data:`DATA_RANGE`, the unit (a
    power of two, 1 inside the ``_OWN_UNITS`` band) in which the channel is fitted, and whether all are 1."""
    peak = None
    for r in records:
        hi, lo = channel_extremes(r)        # (as_signal's, when it checked the record for constant channels)
        p = np.maximum(hi, -lo)
        peak = p if peak is None else np.maximum(peak, p)
    values = peak.tolist()                  # (a few channels: Python's min / max cost less than numpy's calls)
    lo, hi = min(values), max(values)
    if lo < DATA_RANGE[0] or hi > DATA_RANGE[1]:
        j = int(np.argmin(peak) if lo < DATA_RANGE[0] else np.argmax(peak))
        raise ValueError(f"{name} peaks at {peak[j]:.3g} in channel {channels[j]!r}: the models need every "
                         f"channel's largest magnitude within [{DATA_RANGE[0]:g}, {DATA_RANGE[1]:g}], where "
                         f"variances (squares of the data) stay in the floating-point range; rescale {name}")
    if lo >= _OWN_UNITS[0] and hi <= _OWN_UNITS[1]:
        return peak, np.array([1.0] * len(values)), True     # (np.ones: a Python wrapper, 3x the time)
    own = (peak >= _OWN_UNITS[0]) & (peak <= _OWN_UNITS[1])
    return peak, np.where(own, 1.0, np.ldexp(1.0, np.frexp(peak)[1])), False


def _same_channels(records: list[Signal], name: str) -> tuple[Signal, ...]:
    """The records with the channels of the first: named records (DataFrames, DataArrays with a channel
    coordinate) reordered by name, with a ``ValueError`` naming a missing or extra channel; others by position,
    with their number checked."""
    first = records[0]
    out = [first]
    for i, r in enumerate(records[1:], start=1):
        if not (r.named and first.named) and r.nchan != first.nchan:
            raise ValueError(f"{name}[{i}] has {r.nchan} channel(s) but {name}[0] has {first.nchan}")
        out.append(r.match_channels(first.channels, f"{name}[{i}]", named=first.named,
                                      reference=f"{name}[0] has"))
    return tuple(out)


def _future_index(index: pd.Index, steps: int) -> pd.Index:
    """The ``steps`` time stamps after ``index``, continued at its frequency: a ``RangeIndex``, a datetime,
    timedelta or period index with a frequency that pandas knows or infers, a numeric index with a constant
    spacing. Any other index is continued by the sample positions ``len(index), len(index) + 1, ...``."""
    n, name = len(index), index.name
    if isinstance(index, pd.RangeIndex):
        return pd.RangeIndex(index.stop, index.stop + steps * index.step, index.step, name=name)
    if isinstance(index, pd.PeriodIndex):
        return pd.period_range(index[-1], periods=steps + 1, freq=index.freq, name=name)[1:]
    if isinstance(index, (pd.DatetimeIndex, pd.TimedeltaIndex)):
        freq = index.freq or (pd.infer_freq(index) if n >= 3 else None)
        if freq is not None:
            make = pd.date_range if isinstance(index, pd.DatetimeIndex) else pd.timedelta_range
            return make(index[-1], periods=steps + 1, freq=freq, name=name, unit=index.unit)[1:]
    elif n >= 2 and pd.api.types.is_numeric_dtype(index.dtype) and not pd.api.types.is_bool_dtype(index.dtype):
        t = index.to_numpy(dtype=np.float64)
        step = (t[-1] - t[0]) / (n - 1)
        if step > 0 and np.allclose(np.diff(t), step, rtol=1e-9, atol=0.0):
            return pd.Index(t[-1] + step * np.arange(1, steps + 1), name=name)
    return pd.RangeIndex(n, n + steps, name=name)


class HeldOutResiduals(list):
    """Held-out residual series (:meth:`LinearTimeSeriesModel.held_out_residuals`), a list that knows the model
    order: ``lags`` is how many signal samples precede a record's first residual, so that a test calibrated on
    them (:meth:`tsfdi.LjungBox.calibrate`) counts its ``window`` in signal samples, as :func:`tsfdi.detect`
    does."""

    def __init__(self, series: list, *, lags: int) -> None:
        super().__init__(series)
        self.lags = int(lags)

    def __repr__(self) -> str:
        return f"HeldOutResiduals({len(self)} series, lags={self.lags})"


@numba.njit(cache=True)
def _scalar_stable(a):  # pragma: no cover - compiled
    """Whether every root of ``1 + a[0] z + ... + a[p-1] z^p`` lies strictly outside the unit circle (``False`` for
    non-finite coefficients), by the Schur-Cohn step-down recursion: the roots of ``z^p + a[0] z^(p-1) + ... +
    a[p-1]`` (their inverses) lie inside the circle if and only if every reflection coefficient ``k_m`` (the last
    coefficient of the degree-``m`` polynomial, which steps down to ``(c_i - k_m c_(m-i)) / (1 - k_m^2)``) has
    ``|k_m| < 1``. O(p^2), no eigenvalues; agrees with :attr:`LinearTimeSeriesResults.roots` except for roots
    within rounding of the circle."""
    c = a.copy()
    tmp = np.empty_like(c)
    for m in range(c.shape[0], 0, -1):
        k = c[m - 1]
        if not abs(k) < 1.0:
            return False
        d = 1.0 - k * k
        for i in range(m - 1):
            tmp[i] = (c[i] - k * c[m - 2 - i]) / d
        for i in range(m - 1):              # (a loop: a slice assignment costs seconds to compile)
            c[i] = tmp[i]
    return True


def _is_record_list(y: Any) -> bool:
    """A list / tuple of signals (arrays, Series, DataFrames, DataArrays) is a set of records of one process.

    A list of numbers (or of lists of numbers) is one signal, as numpy reads it.
    """
    return isinstance(y, (list, tuple)) and len(y) > 0 and all(
        isinstance(r, (np.ndarray, pd.Series, pd.DataFrame, Signal)) or is_xarray(r) for r in y)


class LinearTimeSeriesModel:
    """Base of AR, VAR and ARX: ``y[t] + sum A_i y[t-i] = c + sum B_j u[t-nk-j+1] + e[t]``.

    **Input contract** (all three families): ``y`` (and ``u``) finite, real, non-constant in every channel, with
    every channel's largest magnitude within :data:`DATA_RANGE` ``= [1e-152, 1e152]`` (outside it variances
    leave the floating-point range); the order(s) leave at least ``df_eq + 1`` regression rows, and the
    regressor at most :data:`~tsfdi.models.lstsq.MAX_VALUES` values (2 GiB). Anything else raises a
    ``ValueError`` / ``TypeError`` naming the argument, before anything large is allocated.

    Attributes
    ----------
    y_scale : ndarray, shape (s,)
        Unit of each output channel in the fit: 1 for a channel whose largest magnitude lies in
        ``[2**-20, 2**20]`` (about 1e-6 .. 1e6), otherwise the power of two just above it. The fit, its Gram
        matrices and its criteria are computed on the data divided by these units (exact: a power of two) and
        the results are returned in the data's units, so nothing overflows or underflows over
        :data:`DATA_RANGE`, and the results at ``y`` and ``c * y`` correspond: coefficients of the lags
        unchanged, ``sigma2`` times ``c**2``, ``llf`` minus ``nobs * log|c|`` per channel (exactly for a
        power of two ``c``).
    u_scale : ndarray, shape (n_inputs,) or None
        The same for the inputs.
    """

    _vector: ClassVar[bool | None] = None   # False: scalar output required, True: 2-D output required
    #: the results class :meth:`fit` returns (and :func:`tsfdi.models.load` rebuilds)
    results_class: ClassVar[type]

    def __init__(self, y: Any, na: int, *, trend: str = "n", hold_back: int | None = None, u: Any = None,
                 nb: int = 0, nk: int = 0, criterion: str = "logdet", lag_name: str = "lags") -> None:
        self.trend = option(trend, "trend", ("n", "c"))
        self.criterion = option(criterion, "criterion", ("logdet", "trace"))
        self._lag_name = lag_name
        self.na = int_like(na, lag_name, minimum=0)
        self.nb = int_like(nb, "nb", minimum=0)
        self.nk = int_like(nk, "nk", minimum=0)
        self.multi = _is_record_list(y)
        records = list(y) if self.multi else [y]
        self.records = _same_channels([as_signal(r, "y" if not self.multi else f"y[{i}]", vector=self._vector)
                                       for i, r in enumerate(records)], "y")
        self.u_records = None
        if u is not None:
            if self.multi != _is_record_list(u) or (self.multi and len(u) != len(records)):
                raise ValueError("u must be a list of as many records as y when y is a list of records "
                                 "(and a single signal otherwise)")
            u_list = list(u) if self.multi else [u]
            self.u_records = _same_channels([as_signal(r, "u" if not self.multi else f"u[{i}]")
                                             for i, r in enumerate(u_list)], "u")
            for i, (ur, yr) in enumerate(zip(self.u_records, self.records)):
                name = "u" if not self.multi else f"u[{i}]"
                if ur.nobs != yr.nobs:
                    raise ValueError(f"{name} has {ur.nobs} samples but {name.replace('u', 'y', 1)} has {yr.nobs}: "
                                     "they must match")
                check_paired(yr, ur, (name.replace("u", "y", 1), name))
        if self.u_records is None and self.nb:
            raise ValueError("nb > 0 needs an input signal u")
        if self.na + self.nb < 1:
            raise ValueError(f"{lag_name} + nb must be >= 1: the model needs at least one regressor")
        self.max_lag = max(self.na, self.nk + self.nb - 1 if self.nb else 0)
        hold_back = self.max_lag if hold_back is None else int_like(hold_back, "hold_back", minimum=0)
        if hold_back < self.max_lag:
            raise ValueError(f"hold_back must be >= the largest lag ({self.max_lag}), got {hold_back}")
        self.hold_back = hold_back
        nobs = [r.values.shape[0] for r in self.records]
        rows = sum(nobs) - hold_back * len(nobs)
        df_eq = self.df_eq
        cols = df_eq + self.neqs

        def orders() -> str:
            """The orders that set the size (na alone, or with nb / nk when the input's lags reach furthest), for the
            messages: formatted only when one is raised."""
            return f"{lag_name}={self.na}" + (f", nb={self.nb}, nk={self.nk}" if self.nb else "")

        if rows * cols > MAX_VALUES:
            check_size(rows * cols, f"{orders()} on {rows:,} regression rows: the regressor ({rows:,} x {cols:,})")
        minimum = hold_back + df_eq + 1
        if not self.multi and nobs[0] < minimum:
            held = (f"hold back {hold_back}" if hold_back > self.max_lag or not self.nb else
                    f"hold back {hold_back}, the largest lag {lag_name}," if hold_back == self.na else
                    f"hold back {hold_back}, the largest lag nk + nb - 1,")
            raise ValueError(f"y is too short for {orders()}: {nobs[0]} samples, at least "
                             f"{minimum} are needed ({held} + {df_eq} parameters + 1)")
        if self.multi:
            for i, n in enumerate(nobs):
                if n <= hold_back:
                    raise ValueError(f"y[{i}] is too short: {n} samples, at least {hold_back + 1} are needed "
                                     f"(hold back {hold_back} + 1)")
            if rows < df_eq + 1:
                raise ValueError(f"y is too short for {orders()}: {rows} usable samples in all records, "
                                 f"at least {df_eq + 1} are needed ({df_eq} parameters + 1)")
        self._y_peak, self.y_scale, own = _channel_scale(self.records, "y", self.data.channels)
        self.u_scale = None
        if self.u_records is not None:
            _, self.u_scale, own_u = _channel_scale(self.u_records, "u", self.u_data.channels)
            own = own and own_u
        self._rescaled = not own
        self._col_scale = None      # the fit's regressor column j is the data's times _col_scale[j]
        if self._rescaled:
            col = [np.ones(self.k_const)]
            for g in range(1, max(self.na, self.nb) + 1):
                col += ([1.0 / self.y_scale] if g <= self.na else []) + ([1.0 / self.u_scale] if g <= self.nb else [])
            self._col_scale = np.concatenate(col)
        self._gram = None           # gram(), once computed (read-only)

    def at_order(self, order: int) -> LinearTimeSeriesModel:
        """This spec at order ``order`` on the same sample: the same records, options and :attr:`hold_back`, with
        ``lags`` (ARX: ``na`` and ``nb``) set to ``order``; the records are not validated again and the Gram matrix
        (:meth:`gram`) is this spec's restricted to the columns kept (the regressor is grouped by lag). This is how
        :meth:`tsfdi.OrderSelection.fit` fits an order of the selection.

        Parameters
        ----------
        order : int
            ``1 .. lags`` (ARX: ``1 .. min(na, nb)``).

        Returns
        -------
        model
            A spec of the same family, equal to the one its constructor gives with ``hold_back=self.hold_back``.
        """
        top = self.na if not self.nb else min(self.na, self.nb)
        order = int_like(order, "order", minimum=1, maximum=top)
        out = object.__new__(type(self))           # (a shallow copy; copy.copy's reduce protocol costs more)
        out.__dict__.update(self.__dict__)
        out.na, out.nb = order, order if self.nb else 0
        out.max_lag = max(out.na, out.nk + out.nb - 1 if out.nb else 0)
        k = out.df_eq
        if self._rescaled:
            out._col_scale = self._col_scale[:k]
        gram = self.gram()
        n = gram.shape[0]
        keep = np.concatenate((np.arange(k), np.arange(n - self.neqs, n)))   # the lags kept, then the targets
        out._gram = gram.take(keep, axis=0).take(keep, axis=1)
        out._gram.setflags(write=False)
        return out

    @property
    def data(self) -> Signal:
        """The (first) output record; see :attr:`records` for a model fitted on several records."""
        return self.records[0]

    @property
    def u_data(self) -> Signal | None:
        """The (first) input record, or None."""
        return None if self.u_records is None else self.u_records[0]

    @property
    def nobs_records(self) -> list[int]:
        """Number of estimation rows contributed by each record."""
        return [r.nobs - self.hold_back for r in self.records]

    def design_all(self, scaled: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Regressor and target of all records, stacked (each record holds back its own first samples).

        Parameters
        ----------
        scaled : bool
            In the units of the fit (each output channel divided by :attr:`y_scale`, each input by
            :attr:`u_scale`, the intercept column kept at 1) instead of the data's units.

        Returns
        -------
        X : ndarray, shape (sum of nobs_records, df_eq)
            Regressor, columns grouped by lag: ``[const, -y[t-1], u[t-nk], -y[t-2], u[t-nk-1], ...]``.
        Y : ndarray, shape (sum of nobs_records, neqs)
            Target ``y[t]``.
        """
        parts = [self._record_design(i, scaled) for i in range(len(self.records))]
        if len(parts) == 1:
            return parts[0]
        return np.vstack([p[0] for p in parts]), np.vstack([p[1] for p in parts])

    # ----------------------------------------------------------------------------------------------
    @property
    def k_const(self) -> int:
        return int(self.trend == "c")

    @property
    def neqs(self) -> int:
        return self.records[0].values.shape[1]      # (data.nchan without two calls: read several times a fit)

    @property
    def n_inputs(self) -> int:
        return 0 if self.u_records is None else self.u_records[0].values.shape[1]

    @property
    def df_eq(self) -> int:
        """Number of regression coefficients per equation."""
        return self.k_const + self.na * self.neqs + self.nb * self.n_inputs

    def _rows(self) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Parameter rows of each output lag (``-y[t-g]``) and each input lag (``u[t-nk-g+1]``)."""
        pos, ylag, ulag = self.k_const, [], []
        for g in range(1, max(self.na, self.nb) + 1):
            if g <= self.na:
                ylag.append(np.arange(pos, pos + self.neqs))
                pos += self.neqs
            if g <= self.nb:
                ulag.append(np.arange(pos, pos + self.n_inputs))
                pos += self.n_inputs
        return ylag, ulag

    def _design(self, y: np.ndarray, u: np.ndarray | None, start: int) -> tuple[np.ndarray, np.ndarray]:
        return lagged_design(y, self.na, start, const=bool(self.k_const), u=u, nb=self.nb, nk=self.nk)

    # --- units of the fit (y_scale, u_scale) ----------------------------------------------------------
    def _scaled_values(self, i: int) -> tuple[np.ndarray, np.ndarray | None]:
        """Output and input of record ``i`` in the units of the fit (no copy when they are the data's)."""
        y = self.records[i].values
        u = None if self.u_records is None else self.u_records[i].values
        if self._rescaled:
            y = y / self.y_scale
            u = None if u is None else u / self.u_scale
        return y, u

    def _from_fit_units(self, coef: np.ndarray) -> np.ndarray:
        """Coefficients of the scaled regression in the data's units (exact: powers of two)."""
        if not self._rescaled:
            return coef
        with np.errstate(over="ignore"):
            params = coef * self._col_scale[:, None] * self.y_scale[None, :]
        if not np.isfinite(params).all():
            raise ValueError("y: the coefficients leave the floating-point range in the data's units: the channels "
                             f"of y{' and u' if self.nb else ''} differ too much in scale (largest magnitudes "
                             f"{np.r_[self._y_peak].tolist()}); rescale them to comparable units")
        return params

    def _to_fit_units(self, params: np.ndarray) -> np.ndarray:
        if not self._rescaled:
            return params
        return params / self._col_scale[:, None] / self.y_scale[None, :]

    def gram(self) -> np.ndarray:
        """Gram matrix of ``[X | Y]`` (:meth:`design_all` in the units of the fit), summed over the records.

        An AR / VAR reads it from the lag products of the samples (:func:`~tsfdi.models.lstsq.lag_gram`, no
        regressor built), an ARX from its explicit regressor. Rows start at :attr:`hold_back` in every record.
        Computed once and kept by the spec (read-only), for :meth:`fit` and :meth:`at_order`.
        """
        if self._gram is None:
            if self.nb == 0:
                gram = lag_gram(self._lag_records(), self.na, const=bool(self.k_const))
            else:
                gram = sum(Z.T @ Z for Z in (np.hstack(self._record_design(i)) for i in range(len(self.records))))
            gram.setflags(write=False)
            self._gram = gram
        return self._gram

    def nested_fits(self, *, stacklevel: int = 2) -> np.ndarray:
        """Residual cross products ``E'E`` (units of the fit) of the fits of every order ``q = 1 .. top`` on this spec's
        sample: those of ``at_order(q).fit()`` to rounding (``top = lags``; ARX: ``min(na, nb)``, the order setting
        ``na = nb = q``). This is what :func:`tsfdi.select_order` tabulates.

        The regressor is grouped by lag, so one upper-triangular factor ``R`` of ``[X | Y]`` gives every order
        (:func:`~tsfdi.models.lstsq.nested_fits`): the Cholesky factor of :meth:`gram` and the nested fits in
        compiled code (:func:`~tsfdi.models.lstsq.cholesky_nested_fits`). When that factor loses digits (a column
        keeps less than ``GRAM_RELATIVE_FLOOR`` of its energy) ``R`` comes from a QR decomposition of the explicit
        regressor (:func:`~tsfdi.models.lstsq.triangular_factor`), with an
        :class:`~tsfdi.exceptions.IllConditionedWarning` when that is ill-conditioned.

        Parameters
        ----------
        stacklevel : int
            Of that warning, as ``warnings.warn``'s in this method (2: the line that calls it).

        Returns
        -------
        ndarray, shape (top, s, s)
        """
        s = self.neqs
        w, k = s + self.n_inputs, self.k_const
        widths = np.arange(k + w, k + w * min(self.na, self.nb or self.na) + 1, w)    # k_const + q w, q = 1 .. top
        sse = cholesky_nested_fits(self.gram(), s, widths)
        if sse is None:
            sse = nested_fits(triangular_factor(None, lambda: np.hstack(self.design_all(scaled=True)), s,
                                                stacklevel=stacklevel + 1), s, widths)
        return sse

    def criteria(self, sse: np.ndarray, sss: np.ndarray, df_model: np.ndarray) -> dict[str, np.ndarray]:
        """Fit criteria of fits on this spec's estimation sample, in the data's units
        (:func:`~tsfdi.models.criteria.information_criteria` with this spec's units and peaks).

        Parameters
        ----------
        sse : ndarray, shape (q, s, s)
            Residual cross products in the units of the fit.
        sss : ndarray, shape (s,)
            Sum of squares of each channel of the target ``Y`` (same units).
        df_model : array_like, shape (q,)
            Regression coefficients of each fit (all equations).
        """
        return information_criteria(sse, sss, sum(self.nobs_records), df_model, self.neqs, self.criterion,
                                    scale=self.y_scale if self._rescaled else None, peak=self._y_peak)

    def collinear_channels(self) -> list[str]:
        """The output channels that make a fit exact by being proportional to an earlier one (a constant channel
        is refused when the model is made).

        Computed on every record's values about their mean (all records pooled). The warning of an exact fit
        names them; an empty list when the exact fit comes from the dynamics (a deterministic signal) instead.

        Returns
        -------
        list of str
            One phrase per such channel, e.g. ``"'b' is proportional to 'a'"``.
        """
        x = np.concatenate([r.values for r in self.records])
        x = x - x.mean(axis=0)
        unit = x / np.sqrt((x ** 2).sum(axis=0))
        names = [str(c) for c in self.data.channels]
        said = []
        for j in range(len(names)):
            i = next((i for i in range(j) if abs(unit[:, i] @ unit[:, j]) > 1 - 1e-9), None)
            if i is not None:
                said.append(f"{names[j]!r} is proportional to {names[i]!r}")
        return said

    def fit(self) -> LinearTimeSeriesResults:
        """Estimate the parameters by least squares.

        The coefficients solve the normal equations of :meth:`gram` by a Cholesky factor, accepted only when
        every regressor column keeps more than ``GRAM_RELATIVE_FLOOR`` (1e-9) of its energy after projection on
        the columns before it (:func:`~tsfdi.models.lstsq.gram_factor`, the check of :func:`tsfdi.select_order`
        and :meth:`held_out_residuals`); otherwise they are recomputed from the explicit regressor by the SVD
        solver :func:`~tsfdi.models.lstsq.lstsq` (minimum-norm solution, with an
        :class:`~tsfdi.exceptions.IllConditionedWarning` when the regressor is ill-conditioned).

        The fit runs in the units :attr:`y_scale` / :attr:`u_scale` and its coefficients are returned in the
        data's. An exact fit (residuals zero to rounding: a deterministic signal) is a valid result: its
        ``sigma2`` is the actual (possibly zero) residual variance, and ``llf``, ``aic`` and ``bic`` use the
        floor of :func:`~tsfdi.models.criteria.information_criteria` with an
        :class:`~tsfdi.exceptions.IllConditionedWarning` when first computed.
        """
        k = self.df_eq
        if self.nb == 0:                     # AR / VAR: the Gram matrix from lag products, no regressor built
            X = Y = None
            recs = self._lag_records()
            gram = self.gram()
            R, xty = gram_factor(gram, k), gram[:k, k:]
        else:
            X, Y = self.design_all(scaled=True)
            if self._gram is None:
                R = gram_factor(X.T @ X, k)
                xty = None if R is None else X.T @ Y
            else:
                R, xty = gram_factor(self._gram, k), self._gram[:k, k:]
        if R is None:                       # the normal equations would lose digits: SVD of the regressor
            if X is None:
                X, Y = self.design_all(scaled=True)
            coef = lstsq(X, Y)
        else:   # Cholesky solve and one step of refinement on the explicit residual (corrected semi-normal eqs.)
            coef = lapack.dpotrs(R, xty, lower=0)[0]        # scipy.linalg.cho_solve without its wrapper
            resid_products = (X.T @ (Y - X @ coef) if X is not None else
                              lag_residual_products(recs, coef, const=bool(self.k_const)))   # X'(Y - X coef)
            coef += lapack.dpotrs(R, resid_products, lower=0)[0]
        res = self.results_class(self, self._from_fit_units(coef))
        res._warn_unstable()
        return res

    def _lag_records(self) -> list:
        """Each record's samples in the units of the fit from ``hold_back - na`` on: the rows of :meth:`gram` and of
        the AR / VAR fit's refinement (:func:`~tsfdi.models.lstsq.lag_residual_products`, no regressor built)."""
        p, h = self.na, self.hold_back        # (as _scaled_values, without the inputs and the samples held back)
        if self._rescaled:
            return [r.values[h - p:] / self.y_scale for r in self.records]
        return [r.values[h - p:] for r in self.records]

    # --- held-out residuals ------------------------------------------------------------------------
    def held_out_residuals(self, blocks: int | None = None, *, groups: Any = None) -> list:
        """Residuals of each record (or block) through the model fitted on all the *other* records (blocks).

        The in-sample residuals :attr:`~LinearTimeSeriesResults.resid` are those of the data the model was
        fitted on, so they are smaller than the residuals of a new flight: the model has partly fitted their
        noise. A detection threshold taken from the empirical distribution of a statistic in normal
        operation (paper 002, Hansen et al., Fig. 2) must be read on residuals that the baseline has not
        seen. Holding out each record in turn gives that null sample from the normal records alone: record
        ``j`` is filtered by the model fitted on the others, exactly as a baseline filters a new flight.

        With ``X_i``, ``Y_i`` the regressor and target of record ``i`` (:meth:`design_all`; same lags,
        trend and ``hold_back`` as this spec), ``G = sum_i X_i' X_i`` and ``h = sum_i X_i' Y_i``, the
        coefficients without record ``j`` are

        .. math::  B_{(-j)} = \\left(G - X_j' X_j\\right)^{-1} \\left(h - X_j' Y_j\\right),

        so the Gram matrices are accumulated once and each held-out fit costs one ``df_eq x df_eq`` solve,
        not a refit. The result equals ``type(self)(other records, ...).fit().residuals(record_j)``.
        The Gram blocks of an AR / VAR come from the lag products of the signal
        (:func:`~tsfdi.models.lstsq.lag_gram`), of an ARX from its explicit regressor. When a downdated
        Gram matrix is too ill-conditioned for the normal equations (a column keeps less than
        ``GRAM_RELATIVE_FLOOR`` of its energy, see :func:`~tsfdi.models.lstsq.gram_solve`) that one fit is
        redone by the SVD solver on the explicit regressor of the other records, with an
        :class:`~tsfdi.exceptions.IllConditionedWarning` if it is ill-conditioned.

        The residuals are those of :meth:`residuals` (the results class filters the held-out data with the
        held-out coefficients), so they follow the package's sign convention
        ``y[t] + sum_i A_i y[t-i] = c + sum_j B_j u[t-nk-j+1] + e[t]``.

        With one record, or when ``blocks`` is given, the regression rows of each record are cut into
        ``blocks`` contiguous blocks of (nearly) equal size, and each block is held out in turn: its
        residuals are those of its own rows through the fit on all the other rows (of every record). The
        lagged regressors at the start of a block come from the samples before it, as in the full-record
        regression, so the blocks' residuals concatenated cover exactly the rows of :attr:`resid`. Rows
        next to a held-out block keep the block's samples as regressors; leave a margin of a few lags
        out of any statistic if that matters.

        Parameters
        ----------
        blocks : int, optional
            Number of contiguous blocks each record is cut into (``>= 2``). Default: ``None``, one held-out
            series per record when the spec has several records, 10 blocks for a single record. Every
            block must hold at least ``df_eq + 1`` regression rows.
        groups : sequence, optional
            One label per record (``blocks=None`` only): the records sharing a label are held out together,
            e.g. the flights of one log or of one airframe, so that each is filtered by a model fitted on none
            of them.

        Returns
        -------
        HeldOutResiduals
            A list of residual series in record order (blocks in order within a record), in the caller's data
            kind (numpy / pandas / xarray, the record's index kept), with ``lags`` (the model's ``max_lag``) so
            that :meth:`tsfdi.LjungBox.calibrate` counts its ``window`` in signal samples:

            * ``blocks=None`` and several records: one series per record, the residuals of ``residuals()``
              (samples ``max_lag .. nobs - 1`` of the record, index from position ``max_lag``);
            * otherwise one series per block (samples ``hold_back + a .. hold_back + b - 1`` for the block's
              rows ``a .. b - 1``, index from that position).

        Raises
        ------
        ValueError
            ``blocks`` not an integer >= 2; ``groups`` not one label per record, with ``blocks``, or a single
            group; a block with fewer than ``df_eq + 1`` rows; a record (block)
            whose removal leaves a singular regression (fewer rows than coefficients, or collinear
            regressors), named in the message.

        Examples
        --------
        >>> spec = tsfdi.VAR(normal_records, lags=8, trend="c")      # doctest: +SKIP
        >>> baseline = spec.fit()                                    # doctest: +SKIP
        >>> null = spec.held_out_residuals()    # doctest: +SKIP
        """
        if blocks is not None:
            try:
                blocks = int_like(blocks, "blocks", minimum=2)
            except TypeError as exc:
                raise ValueError(str(exc)) from None
        elif len(self.records) == 1:
            blocks = 10
        k = self.df_eq
        nrows = self.nobs_records
        # the held-out parts: (record, first row, end row) in the record's regression rows
        if blocks is None:
            parts = [[(0, n)] for n in nrows]
        else:
            parts = []
            for i, n in enumerate(nrows):
                if n // blocks < k + 1:
                    raise ValueError(
                        f"blocks={blocks} leaves {n // blocks} regression row(s) per block in {self._record_name(i)} "
                        f"({n} rows); each block needs at least df_eq + 1 = {k + 1}: use fewer blocks")
                edges = np.r_[0, np.cumsum([len(c) for c in np.array_split(np.arange(n), blocks)])]
                parts.append(list(zip(edges[:-1].tolist(), edges[1:].tolist())))
        grams = [self._part_grams(i, p) for i, p in enumerate(parts)]
        total = sum(g.sum(axis=0) for g in grams)
        label = self._held_out_groups(groups, blocks)
        out = []
        for i, record_parts in enumerate(parts):
            series = []
            for b, (lo, hi) in enumerate(record_parts):
                if label is None:
                    what = (self._record_name(i) if blocks is None
                            else f"block {b} (rows {lo}..{hi - 1}) of {self._record_name(i)}")
                    removed, gone = grams[i][b], hi - lo
                    design = partial(self._design_without, {i: (lo, hi)})
                else:
                    members = [r for r in range(len(parts)) if label[r] == label[i]]
                    what = f"group {label[i]!r} ({', '.join(self._record_name(r) for r in members)})"
                    removed = sum(grams[r][0] for r in members)
                    gone = sum(nrows[r] for r in members)
                    design = partial(self._design_without, {r: (0, nrows[r]) for r in members})
                coef = None
                if sum(nrows) - gone >= k:
                    coef = gram_solve(total - removed, k, design, what=f"the regressor without {what}",
                                      stacklevel=4)
                if coef is None:
                    raise ValueError(f"removing {what} leaves a singular regression: the other "
                                     f"{'records' if blocks is None else 'rows'} do not determine the {k} "
                                     "coefficients per equation (too few rows or collinear regressors)")
                res = self.results_class(self, self._from_fit_units(coef))
                rec = self.records[i]
                if blocks is None:
                    lo_s, hi_s = self.max_lag, rec.nobs
                else:
                    lo_s, hi_s = self.hold_back + lo, self.hold_back + hi
                a = lo_s - self.max_lag
                u = None if self.u_records is None else self.u_records[i].values[a:hi_s]
                series.append(rec.wrap(res._residuals_array(rec.values[a:hi_s], u), lo_s))
            out.extend(series)
        return HeldOutResiduals(out, lags=self.max_lag)

    def _record_name(self, i: int) -> str:
        return f"y[{i}]" if self.multi else "y"

    def _record_design(self, i: int, scaled: bool = True) -> tuple[np.ndarray, np.ndarray]:
        if scaled:
            y, u = self._scaled_values(i)
        else:
            y, u = self.records[i].values, None if self.u_records is None else self.u_records[i].values
        return self._design(y, u, self.hold_back)

    def _part_grams(self, i: int, parts: list[tuple[int, int]]) -> np.ndarray:
        """Gram matrices of ``[X | Y]`` (units of the fit) over the regression rows ``lo .. hi - 1`` of record
        ``i``, one per part.

        An AR / VAR reads them from the lag products of the samples (:func:`lag_gram`, no regressor built);
        an ARX from its explicit regressor.
        """
        if self.nb == 0:
            y, p, h = self._scaled_values(i)[0], self.na, self.hold_back
            return np.stack([lag_gram(y[h + lo - p:h + hi], p, const=bool(self.k_const)) for lo, hi in parts])
        X, Y = self._record_design(i)
        Z = np.hstack([X, Y])
        return np.stack([Z[lo:hi].T @ Z[lo:hi] for lo, hi in parts])

    def _held_out_groups(self, groups: Any, blocks: int | None) -> list | None:
        """The validated group label of every record (``None`` without groups)."""
        if groups is None:
            return None
        if blocks is not None:
            raise ValueError("groups holds out whole records: it cannot be combined with blocks")
        if isinstance(groups, (str, bytes)) or not hasattr(groups, "__len__"):
            raise ValueError(f"groups must be a sequence of one label per record, got {groups!r}")
        label = list(groups)
        if len(label) != len(self.records):
            raise ValueError(f"groups must hold one label per record ({len(self.records)}), got {len(label)}")
        if len(set(label)) < 2:
            raise ValueError("groups must hold at least two distinct labels: holding out every record leaves "
                             "nothing to fit")
        return label

    def _design_without(self, rows: dict) -> tuple[np.ndarray, np.ndarray]:
        """Stacked regressor and target (units of the fit) of all records without the rows ``rows[i] = (lo, hi)``
        of record ``i``."""
        xs, ys = [], []
        for r in range(len(self.records)):
            X, Y = self._record_design(r)
            lo, hi = rows.get(r, (0, 0))
            keep = np.r_[0:lo, hi:X.shape[0]]
            xs.append(X[keep])
            ys.append(Y[keep])
        return np.vstack(xs), np.vstack(ys)

    def __repr__(self) -> str:
        records = f", records={len(self.records)}" if self.multi else ""
        return (f"{type(self).__name__}(nobs={sum(r.nobs for r in self.records)}{records}, "
                f"{self._lag_name}={self.na}, trend={self.trend!r})")


class FrozenResults:
    """Fitted results are immutable: ``__init__`` sets their attributes once (``object.__setattr__``) and any later
    assignment or deletion raises ``AttributeError`` (cached properties still fill ``__dict__``)."""

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable; fit the model again to change it")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable")


class LinearTimeSeriesResults(FrozenResults):
    """Immutable results of a least-squares time-series fit.

    Attributes are computed on first access and cached. Information criteria follow the likelihood form
    used by statsmodels ``AutoReg`` (Lütkepohl):

    ``llf = -nobs/2 (s ln 2 pi + ln det Sigma + s)``, ``aic = -2 llf + 2 k``, ``bic = -2 llf + k ln nobs``,
    ``hqic = -2 llf + 2 k ln ln nobs``

    with ``Sigma`` the maximum-likelihood residual covariance and ``k = df_model + s (s + 1) / 2`` the
    number of free parameters including the noise covariance. Divided by ``nobs`` the BIC is the papers'
    eq. 5, ``ln sigma_e^2 + d ln N / N``, up to a constant that does not depend on the order.

    **Inference** (``bse``, ``tvalues``, ``pvalues``, ``conf_int``) follows statsmodels for the same model: the
    covariance of the coefficients of equation ``j`` is ``s_j^2 (X'X)^{-1}`` with ``X`` the stacked regressor of
    all records, and ``s_j^2 = RSS_j / nobs`` for a scalar output (statsmodels ``AutoReg``) or
    ``RSS_j / (nobs - df_eq)`` for a VAR (statsmodels ``VAR``'s ``sigma_u``); ``tvalues = params / bse`` are
    referred to the standard normal distribution in both (their ``pvalues``; ``conf_int`` is
    ``params +- z_{1 - alpha/2} bse``). With several records ``nobs`` counts the regression rows of all of them.

    **Labels.** ``params``, ``bse``, ``tvalues``, ``pvalues`` and ``conf_int()`` are bare arrays for a model of
    numpy data and pandas objects labelled with the parameter names (index) and the channel names (columns, or the
    Series name) for pandas or xarray data.
    """

    #: statsmodels' residual variance behind ``bse``: ``RSS / (nobs - df_eq)`` (VAR) or ``RSS / nobs`` (AutoReg)
    _df_adjusted_bse: ClassVar[bool] = True
    _bse_note: ClassVar[str] = ("std err from Sigma = E'E / (nobs - df_eq) per equation (statsmodels VAR); z and "
                                "P>|z| from the normal distribution")

    def __init__(self, model: LinearTimeSeriesModel, params: np.ndarray, *,
                 residual_products: np.ndarray | None = None) -> None:
        """``residual_products``: the residual cross products ``E'E`` (in the fit units of ``model``) that ``sigma``,
        ``llf``, ``bse`` and the criteria read, when they are not those of ``params`` on the model's own records
        (a functionally pooled model at an operating point, :meth:`tsfdi.FPResults.at`); default computed from
        the residuals."""
        params = np.array(params, dtype=float)
        params.setflags(write=False)
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "_params2d", params.reshape(params.shape[0], -1))
        if residual_products is not None:
            sse = np.array(residual_products, dtype=float)
            k = self._params2d.shape[1]
            if sse.shape != (k, k) or not np.all(np.isfinite(sse)):
                raise ValueError(f"residual_products must be a finite ({k}, {k}) matrix, got shape {sse.shape}")
            sse.setflags(write=False)
            self.__dict__["_sse"] = sse                     # the cached_property's value

    # --- in-sample quantities ----------------------------------------------------------------------
    @cached_property
    def _resid_and_sss(self) -> tuple[np.ndarray, np.ndarray]:
        """In-sample residuals and the sum of squares of each channel of the estimation sample, in the units of
        the fit (the regressor is rebuilt here and not kept, so a results object does not hold an
        ``nobs x df_eq`` matrix)."""
        m = self.model
        X, Y = m.design_all(scaled=True)
        e = Y - X @ m._to_fit_units(self._params2d)
        e.setflags(write=False)
        return e, np.ascontiguousarray((Y * Y).T).sum(axis=1)   # (a contiguous reduction: fast for any s)

    @property
    def _resid_array(self) -> np.ndarray:
        return self._resid_and_sss[0]

    @property
    def params2d(self) -> np.ndarray:
        """Parameter matrix (read-only), shape ``(df_eq, neqs)``: one column per equation, rows in regressor
        order ``[const, lag-1 group, lag-2 group, ...]`` (what :meth:`save` stores)."""
        return self._params2d

    @property
    def lags(self) -> int:
        """Autoregressive order."""
        return self.model.na

    @property
    def trend(self) -> str:
        return self.model.trend

    @property
    def nobs(self) -> int:
        """Number of residuals used in estimation (signal length minus the held-back samples)."""
        return self._resid_array.shape[0]

    @property
    def neqs(self) -> int:
        return self.model.neqs

    @property
    def df_model(self) -> int:
        """Number of estimated regression coefficients (all equations)."""
        return self._params2d.size

    @property
    def df_eq(self) -> int:
        """Number of regression coefficients per equation."""
        return self._params2d.shape[0]

    @property
    def df_resid(self) -> int:
        """Residual degrees of freedom per equation, ``nobs - df_eq`` (the ``N_0 - d`` of paper 003 eq. 11)."""
        return self.nobs - self.df_eq

    @cached_property
    def _sse(self) -> np.ndarray:
        e = self._resid_array
        return e.T @ e

    @cached_property
    def _criteria(self) -> dict[str, float]:
        values = self.model.criteria(self._sse[None], self._resid_and_sss[1], [self.df_model])
        if values["exact"][0]:
            said = "".join(f"; {c}" for c in self.model.collinear_channels())
            warnings.warn(f"the {type(self.model).__name__} fits y exactly (a residual RMS below {EXACT_FIT_RTOL:g} "
                          f"times the peak of y, or collinear channels{said}): the likelihood is unbounded, so llf, aic "
                          "and bic use that floor for the residual variance", IllConditionedWarning, stacklevel=4)
        return values

    @property
    def llf(self) -> float:
        """Gaussian log-likelihood at the maximum-likelihood covariance (finite: an exact fit uses the floor of
        :func:`~tsfdi.models.criteria.information_criteria`, with a warning)."""
        return float(self._criteria["llf"][0])

    @property
    def aic(self) -> float:
        """Akaike information criterion ``-2 llf + 2 k``."""
        return float(self._criteria["aic"][0])

    @property
    def bic(self) -> float:
        """Bayesian information criterion ``-2 llf + k ln nobs`` (paper 003 eq. 5 times ``nobs``, plus a constant).

        For a vector model with ``criterion="trace"`` the log-determinant of the residual covariance is
        replaced by the log of its trace, as in paper 003 ("Vector AR Identification Method").
        """
        return float(self._criteria["bic"][0])

    @property
    def rss_sss(self) -> float:
        """Residual sum of squares over signal sum of squares in percent (paper 003 eq. 6).

        ``100 * sum_t e[t]' e[t] / sum_t y[t]' y[t]`` over the estimation sample (raw, not demeaned, signal).
        """
        return float(self._criteria["rss_sss"][0])

    @property
    def spp(self) -> float:
        """Samples per parameter, ``nobs * s / df_model`` (paper 003 Table 2; the paper uses the signal length)."""
        return float(self._criteria["spp"][0])

    @property
    def hqic(self) -> float:
        """Hannan-Quinn information criterion ``-2 llf + 2 k ln ln nobs`` (statsmodels ``AutoReg.hqic``; see
        :func:`~tsfdi.models.criteria.information_criteria` for statsmodels ``VAR``'s per-sample form)."""
        return float(self._criteria["hqic"][0])

    @property
    def resid(self) -> Any:
        """In-sample residuals (one-step prediction errors) in the caller's data kind.

        A model fitted on a list of records gives a list with the residuals of each record.
        """
        return self._per_record(self._resid_array * self.model.y_scale)

    @property
    def fittedvalues(self) -> Any:
        """In-sample one-step predictions ``y[t] - e[t]`` of the estimation sample, in the caller's data kind
        (statsmodels' ``fittedvalues``); a list with those of each record for a model fitted on several."""
        m = self.model
        y = np.vstack([r.values[m.hold_back:] for r in m.records])
        return self._per_record(y - self._resid_array * m.y_scale)

    def _per_record(self, values: np.ndarray) -> Any:
        """Rows of the stacked estimation sample wrapped in the data's kind: one series, or one per record."""
        m = self.model
        if not m.multi:
            return m.data.wrap(values, m.hold_back)
        bounds = np.cumsum([0] + m.nobs_records)
        return [r.wrap(values[a:b].copy(), m.hold_back) for r, a, b in zip(m.records, bounds[:-1], bounds[1:])]

    # --- inference (statsmodels' conventions) ------------------------------------------------------
    @cached_property
    def _bse2d(self) -> np.ndarray:
        """Standard errors ``sqrt(s_j^2 diag((X'X)^-1))``, shape ``(df_eq, neqs)``, in the data's units.

        ``(X'X)^-1 = V S^-2 V'`` from the singular values of the triangular factor of the regressor (units of the
        fit), so nothing is squared before the decomposition; a direction the regressor does not determine gets
        an infinite standard error.
        """
        m = self.model
        X, _ = m.design_all(scaled=True)
        R = linalg.qr(X, mode="r", check_finite=False)[0][: X.shape[1]]
        _, sv, vt = np.linalg.svd(R)
        var = np.diag(self._sse) / (self.df_resid if self._df_adjusted_bse else self.nobs)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            xtx_inv = ((vt / sv[:, None]) ** 2).sum(axis=0)
            bse = np.sqrt(xtx_inv[:, None] * var[None, :])
            if m._rescaled:
                bse = bse * m._col_scale[:, None] * m.y_scale[None, :]
        bse.setflags(write=False)
        return bse

    @cached_property
    def _tvalues2d(self) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            t = self._params2d / self._bse2d
        t.setflags(write=False)
        return t

    @cached_property
    def _pvalues2d(self) -> np.ndarray:
        p = 2.0 * stats.norm.sf(np.abs(self._tvalues2d))
        p.setflags(write=False)
        return p

    def _labelled(self, values: np.ndarray) -> Any:
        """Per-parameter values ``(df_eq, neqs)`` as :attr:`params` gives them: a bare (read-only) array for numpy
        data, 1-D for one output channel; a Series (index: parameter names) or a DataFrame (columns: channels)
        for pandas or xarray data."""
        m = self.model
        out = values if m._vector else values[:, 0]
        if m.data.kind == "numpy":
            return out
        if not m._vector:
            return pd.Series(out.copy(), index=self._param_names(), name=m.data.name)
        return pd.DataFrame(out.copy(), index=self._param_names(), columns=list(m.data.channels))

    @property
    def params(self) -> Any:
        """Regression coefficients in the papers' sign, rows ``[const, lag-1 group, lag-2 group, ...]`` (one
        column per equation for a VAR); labelled for pandas / xarray data (see the class docstring)."""
        return self._labelled(self._params2d)

    @property
    def bse(self) -> Any:
        """Standard errors of :attr:`params` (statsmodels' convention of the model family; class docstring)."""
        return self._labelled(self._bse2d)

    @property
    def tvalues(self) -> Any:
        """``params / bse``."""
        return self._labelled(self._tvalues2d)

    @property
    def pvalues(self) -> Any:
        """Two-sided p-values of ``tvalues`` under the standard normal distribution, ``2 P(Z > |t|)``."""
        return self._labelled(self._pvalues2d)

    def conf_int(self, alpha: float = 0.05) -> Any:
        """Confidence intervals ``params -+ z_{1 - alpha/2} bse`` of level ``1 - alpha`` (normal, as statsmodels'
        ``AutoReg``; statsmodels' ``VAR`` has none but its p-values use the same distribution).

        Parameters
        ----------
        alpha : float
            In (0, 1).

        Returns
        -------
        ndarray or DataFrame
            numpy data: shape ``(df_eq, 2)`` for a scalar output, ``(df_eq, s, 2)`` for a VAR, ``[..., 0]`` the
            lower and ``[..., 1]`` the upper bound. pandas / xarray data: a DataFrame indexed by parameter names
            with columns ``["lower", "upper"]``, or ``(channel, "lower" / "upper")`` for a VAR.
        """
        q = stats.norm.isf(probability(alpha) / 2)
        lo, hi = self._params2d - q * self._bse2d, self._params2d + q * self._bse2d
        m = self.model
        ci = np.stack([lo, hi], axis=-1)
        ci = ci if m._vector else ci[:, 0]
        if m.data.kind == "numpy":
            return ci
        if not m._vector:
            return pd.DataFrame(ci, index=self._param_names(), columns=["lower", "upper"])
        columns = pd.MultiIndex.from_product([list(m.data.channels), ["lower", "upper"]])
        return pd.DataFrame(ci.reshape(ci.shape[0], -1), index=self._param_names(), columns=columns)

    # --- forecasts ----------------------------------------------------------------------------------
    def _forecast_array(self, steps: int, u: np.ndarray | None = None) -> np.ndarray:
        """``steps`` forecasts after the last sample of the (last) fitted record, shape ``(steps, neqs)``.

        ``y[t] = x[t] params`` with the model's regressor ``x[t]``: the lagged outputs (the forecasts once past
        the data) and, for an ARX, the inputs ``u`` of the forecast samples after those of the data.
        """
        m = self.model
        p = m.max_lag
        check_size((p + steps) * (self.neqs + m.n_inputs), f"steps={steps}: the forecast")
        y_past = m.records[-1].values
        y = np.concatenate([y_past[len(y_past) - p:], np.zeros((steps, self.neqs))])
        if u is not None:
            u_past = m.u_records[-1].values
            u = np.concatenate([u_past[len(u_past) - p:], u])
        with np.errstate(over="ignore", invalid="ignore"):
            for h in range(steps):
                X, _ = m._design(y[h:h + p + 1], None if u is None else u[h:h + p + 1], p)
                y[p + h] = X[0] @ self._params2d
        if not np.isfinite(y).all():
            why = "unstable" if not self.is_stable else "driven far beyond its data"
            raise ValueError(f"steps={steps}: the forecasts leave the floating-point range (the fitted "
                             f"{type(m).__name__} is {why}); forecast fewer steps")
        return y[p:]

    def _forecast(self, steps: Any) -> Any:
        """:meth:`_forecast_array` in the kind of the last record, its time index continued (``_future_index``)."""
        steps = int_like(steps, "steps", minimum=1)
        f = self._forecast_array(steps)
        rec = self.model.records[-1]
        if rec.kind == "numpy":
            return f if rec.vector else f[:, 0]
        return dataclasses.replace(rec, index=_future_index(rec.index, steps)).wrap(f)

    # --- stability ------------------------------------------------------------------------------
    def _ar_matrices(self) -> np.ndarray:
        """AR coefficient matrices ``A_1..A_na`` in the papers' sign, shape (na, s, s)."""
        return self._ar_blocks.copy()

    @cached_property
    def _ar_blocks(self) -> np.ndarray:
        m, s = self.model, self.neqs
        if m.nb == 0:       # the lag blocks follow each other: one reshape, no row lists
            A = self._params2d[m.k_const:].reshape(m.na, s, s).transpose(0, 2, 1).copy()
        else:
            rows, _ = m._rows()
            A = np.stack([self._params2d[r].T for r in rows]) if rows else np.empty((0, s, s))
        A.setflags(write=False)
        return A

    @cached_property
    def _ar_blocks_t(self) -> np.ndarray:
        """``A_i'`` as C-contiguous blocks, for the residual recursion."""
        return np.ascontiguousarray(np.swapaxes(self._ar_blocks, 1, 2))

    def _input_matrices(self) -> np.ndarray:
        """Input coefficient matrices ``B_1..B_nb``, shape (nb, s, n_inputs)."""
        _, rows = self.model._rows()
        return (np.stack([self._params2d[r].T for r in rows]) if rows
                else np.empty((0, self.neqs, self.model.n_inputs)))

    @cached_property
    def roots(self) -> np.ndarray:
        """Roots of the characteristic polynomial ``det(I + A_1 z + ... + A_na z^na)``.

        The model is stable when all roots lie outside the unit circle (statsmodels' convention).
        Sorted by modulus.
        """
        A = self._ar_blocks
        na, s = A.shape[0], self.neqs
        if na == 0:
            return np.empty(0, dtype=complex)
        n = na * s
        comp = np.zeros((n, n))
        comp[:s] = -A.transpose(1, 0, 2).reshape(s, n)       # [A_1 ... A_na]
        comp.ravel()[s * n::n + 1] = 1.0                      # the identity below the first block row
        # LAPACK geev called directly (numpy's eigvals wraps it in ~15 us of checks at these sizes, and returns the
        # same); a matrix that is not finite, or a QR iteration that does not converge, goes to numpy's (its error)
        wr, wi, _, _, info = lapack.dgeev(comp, compute_vl=0, compute_vr=0)
        if info == 0 and np.isfinite(wr).all() and np.isfinite(wi).all():
            eig = wr + 1j * wi if wi.any() else wr
        else:
            eig = np.linalg.eigvals(comp)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):   # a zero eigenvalue: a root at inf
            r = 1.0 / eig
        return r[np.argsort(np.abs(r))]

    @property
    def is_stable(self) -> bool:
        """True when every characteristic root lies strictly outside the unit circle."""
        return bool(np.all(np.abs(self.roots) > 1.0))

    def _warn_unstable(self) -> None:
        """Warn when the fit is unstable. A scalar output is decided by the step-down recursion
        (:func:`_scalar_stable`, O(na^2)); the eigenvalues of :attr:`roots` only when it says unstable (for the
        message) and for vector models."""
        A = self._ar_blocks
        if self.model.na and (A.shape[1] > 1 or not _scalar_stable(A[:, 0, 0])) and not self.is_stable:
            warnings.warn(f"the fitted {type(self.model).__name__} is unstable (smallest root modulus "
                          f"{np.abs(self.roots).min():.4f} <= 1)", UnstableModelWarning, stacklevel=4)

    # --- new data --------------------------------------------------------------------------------
    def _new_signal(self, y: Any, name: str = "y") -> Signal:
        """``y`` validated, with the model's channels in the model's order: a named signal (DataFrame, DataArray
        with a channel coordinate) of a model fitted on named data is matched by name, and a missing or extra
        channel raises a ``ValueError`` naming it; otherwise the channels are taken by position."""
        sig = as_signal(y, name, vector=self.model._vector, min_nobs=self.model.max_lag + 1, allow_constant=True)
        data = self.model.data
        return sig.match_channels(data.channels, name, named=data.named)

    def _residuals_array(self, y: np.ndarray, u: np.ndarray | None) -> np.ndarray:
        """One-step prediction errors of ``y`` (and ``u``) through the fixed model, from ``max_lag`` on.

        Raises ``ValueError`` when they leave the floating-point range (a signal far larger than the model's).
        """
        m = self.model
        with np.errstate(over="ignore", invalid="ignore"):
            if m.nb == 0 and self.neqs == 1:   # scalar AR: one FIR pass (e[t] = sum_i a_i y[t-i], t >= max_lag)
                a = np.r_[1.0, self._ar_blocks[:, 0, 0]]
                e = np.convolve(y[:, 0], a, "valid")
                e = (e - (self._params2d[0, 0] if m.k_const else 0.0))[:, None]
            elif m.nb == 0:   # VAR: accumulate the lag terms, no design matrix
                p, n = m.na, y.shape[0]
                e = y[p:] - self._params2d[0] if m.k_const else y[p:].copy()
                At = self._ar_blocks_t
                for i in range(1, p + 1):
                    e += y[p - i:n - i] @ At[i - 1]
            else:
                X, Y = m._design(y, u, m.max_lag)
                e = Y - X @ self._params2d
        if not np.isfinite(e).all():
            raise ValueError(f"y: the residuals through the {type(m).__name__} leave the floating-point range "
                             f"(y peaks at {np.abs(y).max():.3g}); rescale y to the units of the model's data")
        return e

    def save(self, path: Any) -> Any:
        """Save the model (data and options) and its parameters to ``path`` for :func:`tsfdi.models.load`;
        ``.npz`` is appended to a name that does not end with it. Returns the ``pathlib.Path`` written. A time
        index that cannot be stored exactly is refused with a ``ValueError``; see :mod:`tsfdi.models.archive`."""
        return save_archive(self, path)

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({type(self.model).__name__}, {self.model._lag_name}={self.model.na}, "
                f"nobs={self.nobs}, bic={self.bic:.6g})")

    def summary(self, alpha: float = 0.05) -> Summary:
        """Fit statistics and one coefficient table per equation (coef, std err, z, P>|z|, confidence interval).

        Parameters
        ----------
        alpha : float
            The confidence intervals have level ``1 - alpha``.

        Returns
        -------
        tsfdi.summary.Summary
            ``print()`` shows it as text, a notebook as HTML; ``.tables`` holds the numbers.
        """
        alpha = probability(alpha)
        m = self.model
        order = f"{m._lag_name}={m.na}" + (f", nb={m.nb}, nk={m.nk}" if m.nb else "")
        header = [("Model", type(m).__name__), ("Channels", ", ".join(map(str, m.data.channels))),
                  ("Order", order), ("Trend", self.trend)]
        if m.u_data is not None:
            header.append(("Inputs", ", ".join(self._input_names())))
        if m.multi:
            header.append(("Records", len(m.records)))
        header += [("Observations", self.nobs), ("Parameters", self.df_model), ("Log-likelihood", self.llf),
                   ("AIC", self.aic), ("BIC", self.bic), ("HQIC", self.hqic), ("RSS/SSS (%)", self.rss_sss),
                   ("Samples per parameter", self.spp), ("Stable", self.is_stable)]
        q = stats.norm.isf(alpha / 2)
        tables = []
        for j, channel in enumerate(m.data.channels):
            coef, bse = self._params2d[:, j], self._bse2d[:, j]
            table = pd.DataFrame({"coef": coef, "std err": bse, "z": self._tvalues2d[:, j],
                                  "P>|z|": self._pvalues2d[:, j],
                                  f"[{alpha / 2:g}": coef - q * bse, f"{1 - alpha / 2:g}]": coef + q * bse},
                                 index=self._param_names())
            tables.append((f"Equation {channel}" if m._vector else f"Coefficients of {channel}", table))
        a = "A_i" if m._vector else "a_i"
        notes = [f"Coefficients in the papers' sign: y[t] + sum_i {a} y[t-i] = c"
                 + (f" + sum_j {'B_j' if m._vector else 'b_j'} u[t-nk-j+1]" if m.nb else "")
                 + f" + e[t] (statsmodels' phi_i = -{a}).",
                 self._bse_note + "."]
        return Summary(f"{type(m).__name__} results", header, tables, notes)

    def _input_names(self) -> list[str]:
        """Names of the inputs: the caller's (DataFrame columns, channel coordinate, Series / DataArray name),
        else ``u0, u1, ...``."""
        u = self.model.u_data
        if u.named or (not u.vector and u.name is not None):
            return [str(c) for c in u.channels]
        return [f"u{i}" for i in range(u.nchan)]

    def _param_names(self) -> list[str]:
        m = self.model
        names = ["const"] if m.k_const else []
        inputs = self._input_names() if m.nb else []
        for g in range(1, max(m.na, m.nb) + 1):
            if g <= m.na:
                names += [f"a{g}" if self.neqs == 1 else f"A{g}.{c}" for c in m.data.channels]
            if g <= m.nb:
                names += [f"b{g}.{c}" for c in inputs]
        return names


class ScalarOutputResults(LinearTimeSeriesResults):
    """Results of a model with one output channel (AR, ARX): 1-D ``params``, scalar ``sigma2``."""

    _df_adjusted_bse = False
    _bse_note = ("std err from sigma2 = RSS / nobs (statsmodels AutoReg); z and P>|z| from the normal "
                 "distribution")

    @property
    def intercept(self) -> float:
        return float(self._params2d[0, 0]) if self.model.k_const else 0.0

    @property
    def sigma2(self) -> float:
        """Maximum-likelihood residual variance ``RSS / nobs`` (as statsmodels ``AutoReg``); rounding-level (or 0)
        for an exact fit, whose ``llf`` uses a floor instead (see :meth:`LinearTimeSeriesModel.fit`)."""
        scale = self.model.y_scale[0]
        return float(self._sse[0, 0] / self.nobs * scale * scale)


class VectorOutputResults(LinearTimeSeriesResults):
    """Results of a model with a vector output (VAR, VARX): ``(df_eq, s)`` ``params``, the ``(s, s)`` covariance
    ``sigma``, statsmodels ``VAR``'s degrees-of-freedom adjusted ``bse``."""

    @property
    def coefs(self) -> np.ndarray:
        """``A_1..A_lags``, shape ``(lags, s, s)``, in the papers' sign."""
        return self._ar_matrices()

    @property
    def intercept(self) -> np.ndarray:
        return self._params2d[0].copy() if self.model.k_const else np.zeros(self.neqs)

    @property
    def sigma(self) -> np.ndarray:
        """Maximum-likelihood residual covariance ``E'E / nobs`` (statsmodels' ``sigma_u_mle``)."""
        scale = self.model.y_scale
        return self._sse / self.nobs * scale[:, None] * scale[None, :]


class InputOutputResults(LinearTimeSeriesResults):
    """Results of a model with exogenous inputs (ARX, VARX): the residuals and forecasts of the output given the
    input ``u``. The engines that test input-output models (:class:`tsfdi.windows.ResidualWindows`,
    :func:`tsfdi.identify`, :class:`tsfdi.Monitor`) recognise them by this class."""

    def residuals(self, y: Any, u: Any) -> Any:
        """One-step prediction errors of new output ``y`` given new input ``u`` through the fixed model.

        Parameters
        ----------
        y : array_like, Series, DataFrame or DataArray
            Output, with the model's channels (matched by name when both are named).
        u : array_like, Series, DataFrame or DataArray
            Input, as long as ``y`` (with its index when both carry one), with the model's inputs (matched by name
            when both are named).

        Returns
        -------
        ``len(y) - max(lags, nk + nb - 1)`` samples in the kind of ``y``, index from that position.
        """
        sig = self._new_signal(y)
        usig = self._new_input(u, sig.nobs)
        check_paired(sig, usig)
        return sig.wrap(self._residuals_array(sig.values, usig.values), self.model.max_lag)

    def forecast(self, steps: int, u: Any) -> Any:
        """Forecasts of the ``steps`` samples after the end of the fitted data (the last record of a model fitted
        on several), driven by the future inputs ``u``: the model's equation with the forecasts in place of the
        outputs not yet seen and the fitted data's inputs before ``u`` (statsmodels'
        ``AutoRegResults.forecast(steps, exog=...)``).

        Parameters
        ----------
        steps : int
            Number of samples forecast.
        u : array_like (steps,) or (steps, n_inputs), Series, DataFrame or DataArray
            The inputs of the forecast samples (matched by name when the model and ``u`` are named).

        Returns
        -------
        ``steps`` samples in the kind of ``u``, with its index (one column per output channel for a vector model).

        Raises
        ------
        ValueError
            ``steps`` < 1, ``u`` without ``steps`` samples or with other inputs, or forecasts that leave the
            floating-point range.
        """
        steps = int_like(steps, "steps", minimum=1)
        usig = self._new_input(u, steps, "steps is")
        m = self.model
        name = m.data.name if m.data.name is not None else "y"
        return usig.wrap(self._forecast_array(steps, usig.values), 0, vector=m._vector,
                         channels=list(m.data.channels), name=name)

    def _new_input(self, u: Any, nobs: int | None = None, against: str = "y has") -> Signal:
        """``u`` validated, its inputs in the model's order: matched by name when both ``u`` and the model's input
        are named (a missing or extra input raises naming it), else by position."""
        usig = as_signal(u, "u", allow_constant=True)
        fitted = self.model.u_data
        if not (usig.named and fitted.named) and usig.nchan != fitted.nchan:
            raise ValueError(f"u has {usig.nchan} input(s) but the model was fitted with {fitted.nchan}")
        usig = usig.match_channels(fitted.channels, "u", named=fitted.named)
        if nobs is not None and usig.nobs != nobs:
            raise ValueError(f"u has {usig.nobs} samples but {against} {nobs}: they must match")
        return usig


def check_covariance(sigma: object, s: int) -> np.ndarray:
    """``sigma`` as a finite symmetric positive semi-definite ``(s, s)`` matrix, or an error naming it."""
    try:
        cov = np.asarray(sigma, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"sigma must be a real ({s}, {s}) covariance matrix, got {sigma!r}") from None
    if cov.shape != (s, s):
        raise ValueError(f"sigma must be a ({s}, {s}) covariance matrix, got shape {cov.shape}")
    if not np.isfinite(cov).all() or not np.allclose(cov, cov.T, rtol=1e-12, atol=0.0):
        raise ValueError("sigma must be a finite symmetric matrix")
    top = np.abs(cov).max()
    if top > 0 and np.linalg.eigvalsh(cov / top).min() < -1e-12:
        raise ValueError("sigma must be positive semi-definite (it has a negative eigenvalue)")
    return cov


def gaussian_innovations(rng: np.random.Generator, cov: np.ndarray, n: int) -> np.ndarray:
    """``n`` draws ``(n, s)`` of ``N(0, cov)``: through the Cholesky factor, or the eigendecomposition of a positive
    semi-definite but singular ``cov``."""
    try:
        return rng.multivariate_normal(np.zeros(cov.shape[0]), cov, size=n, method="cholesky")
    except np.linalg.LinAlgError:
        return rng.multivariate_normal(np.zeros(cov.shape[0]), cov, size=n, method="eigh")


def simulate_var(coefs: np.ndarray, e: np.ndarray) -> np.ndarray:
    """``y[t] = e[t] - sum_i A_i y[t-i]`` with zero initial conditions."""
    p, s, _ = coefs.shape
    n = e.shape[0]
    y = np.zeros((n + p, s))
    Aflat = np.concatenate(list(coefs[::-1]), axis=1)   # [A_p ... A_1], (s, p s)
    for t in range(n):
        y[t + p] = e[t] - Aflat @ y[t:t + p].ravel()
    return y[p:]

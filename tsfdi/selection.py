"""Model order selection: :func:`select_order` and its result :class:`OrderSelection`.

The information criteria themselves are :func:`tsfdi.models.criteria.information_criteria`, shared with
the results objects of the models.

All candidate orders ``1..max_lags`` are fitted on the **same sample** (the first ``max_lags`` samples are
held back for every order), so ``select_order(...).table.loc[p, "bic"]`` equals the ``bic`` of the model of
order ``p`` fitted on that sample (``OrderSelection.fit(p)``) up to rounding (the table comes from one
triangular factor of the largest order, the fit from a Cholesky solve of its own order's Gram matrix with one
refinement step; they agree to about 1e-9 relative) — statsmodels issue 7143 is
the counter-example, where they are computed on different samples.

Nothing is refitted order by order. The regressor ``[const, -y[t-1], ..., -y[t-max_lags], y[t]]`` is
grouped by lag, so one upper-triangular factor ``R`` of it gives every nested fit (see
:func:`tsfdi.models.lstsq.nested_fits`). For AR and VAR models ``R`` is the Cholesky factor of the lag-product
Gram matrix, computed in ``O(N max_lags)`` from lag products with end corrections, and the Gram matrix, its factor
and the nested fits come from compiled code (the spec's ``nested_fits``); when that factor loses digits
(ill-conditioned regressor) it is recomputed by a QR decomposition of the regressor.

Everything runs in the units of the model spec (:attr:`tsfdi.AR.y_scale`: each channel divided by a power of
two near its peak when it lies outside ``2**-20 .. 2**20``), so the selected order of ``c * y`` is that of
``y`` for any ``c`` that keeps every channel's peak within ``1e-152 .. 1e152``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._data import as_signal
from tsfdi._validation import float_like, int_like, option
from tsfdi.exceptions import ConvergenceWarning, IllConditionedWarning
from tsfdi.models import AR, ARX, VAR, VARX
from tsfdi.models.criteria import EXACT_FIT_RTOL
from tsfdi.summary import Summary

__all__ = ["select_order", "OrderSelection"]


def select_order(data: Any, max_lags: int, model: str = "ar", *, u: Any = None, nk: int = 0, trend: str = "n",
                 criterion: str = "logdet", tol: float = 0.01) -> OrderSelection:
    """Fit all orders ``1..max_lags`` on a common sample and tabulate BIC, AIC, RSS/SSS, SPP.

    Parameters
    ----------
    data : array_like, Series, DataFrame or DataArray, or a list of them
        The output signal ``y`` (scalar for ``"ar"`` / ``"arx"``, ``(nobs, s)`` for ``"var"`` / ``"varx"``), or a
        list of records of the same process (each holds back its own first ``max_lags`` samples; their Gram
        matrices add up).
    max_lags : int
        Largest order tried.
    model : {"ar", "var", "arx", "varx"}
        Model family. For ``"arx"`` / ``"varx"`` the order ``p`` means ``na = nb = p``.
    u : array_like, optional
        Input signal, required for ``"arx"`` / ``"varx"``.
    nk : int
        Input delay of the ARX / VARX model.
    trend : {"n", "c"}
        No intercept or an intercept.
    criterion : {"logdet", "trace"}
        BIC variant for vector models (see :func:`tsfdi.models.criteria.information_criteria`).
    tol : float
        Relative tolerance of :attr:`OrderSelection.stabilized`: the RSS/SSS curve is considered stable
        from the smallest order ``p`` after which no order improves RSS/SSS by more than ``tol`` relative
        to the order before it.

    Returns
    -------
    OrderSelection

    Raises
    ------
    ValueError
        ``max_lags`` too large for the data (the message names the model's ``lags`` / ``na``) or for the memory
        limit, data outside ``[1e-152, 1e152]`` (each channel's largest magnitude), and the errors of the model
        families (:class:`tsfdi.AR`, :class:`tsfdi.VAR`, :class:`tsfdi.ARX`, :class:`tsfdi.VARX`).

    Warns
    -----
    ConvergenceWarning
        The BIC minimum is at the search bound ``max_lags`` (:attr:`OrderSelection.at_bound`): the search did not
        find a minimum inside ``1..max_lags``; the summary says so too.
    IllConditionedWarning
        An ill-conditioned regressor, or orders that fit the data exactly (residual RMS below ``1e-12`` times
        its peak: a deterministic signal); their criteria use the floor of
        :func:`~tsfdi.models.criteria.information_criteria`, so the smallest exact order has the smallest BIC.

    Notes
    -----
    Paper 003 selects the order by the minimum of BIC (eq. 5) together with the stabilisation of RSS/SSS
    (eq. 6, Fig. 8).
    """
    family = option(model, "model", ("ar", "var", "arx", "varx"))
    max_lags = int_like(max_lags, "max_lags", minimum=1)
    tol = float_like(tol, "tol", minimum=0.0)
    if family == "arx":
        if u is None:
            raise ValueError("u is required for model='arx'")
        spec = ARX(data, u, na=max_lags, nb=max_lags, nk=nk, trend=trend)
    elif family == "varx":
        if u is None:
            raise ValueError("u is required for model='varx'")
        spec = VARX(data, u, max_lags, nb=max_lags, nk=nk, trend=trend, criterion=criterion)
    else:
        if u is not None:
            raise ValueError(f"u is only used with model='arx' or 'varx', not model={family!r}")
        if family == "ar":
            try:
                spec = AR(data, max_lags, trend=trend)
            except (ValueError, TypeError):   # the first record checked as before (only on failure: it costs)
                first = data[0] if isinstance(data, (list, tuple)) and data else data
                k = as_signal(first, "data", allow_constant=True).nchan
                if k > 1:
                    raise ValueError(f"data has {k} channels but model='ar' selects the order of one scalar signal: "
                                     f"use model='var' for the vector signal (select_order(data, {max_lags}, "
                                     "model='var')), or select one channel") from None
                raise
        else:
            spec = VAR(data, max_lags, trend=trend, criterion=criterion)
    s = spec.neqs
    w, k = s + spec.n_inputs, spec.k_const
    sse = spec.nested_fits(stacklevel=3)
    sss = spec.gram().diagonal()[-s:]      # diag(Y'Y) (the squared column norms of R's last columns, to rounding)
    # the coefficients of order p (all equations): s (k_const + p w); ARX order p: na = nb = p
    values = spec.criteria(sse, sss, np.arange(s * (k + w), s * (k + w * max_lags) + 1, s * w))
    orders = np.arange(1, max_lags + 1)
    if np.count_nonzero(values["exact"]):     # (ndarray.any goes through a Python wrapper)
        said = "".join(f"; {c}" for c in spec.collinear_channels())
        warnings.warn(f"orders {orders[values['exact']].tolist()} fit the data exactly (a residual RMS below "
                      f"{EXACT_FIT_RTOL:g} times its peak, or collinear channels{said}): their likelihood is "
                      "unbounded, so their criteria use that floor for the residual variance", IllConditionedWarning,
                      stacklevel=2)
    out = OrderSelection(spec=spec, orders=orders, values=values, tol=tol)
    if out.at_bound:
        warnings.warn(f"the BIC minimum is at the search bound max_lags = {max_lags}: a larger order may fit better; "
                      f"search further (select_order(..., max_lags={2 * max_lags}))", ConvergenceWarning, stacklevel=2)
    return out


@dataclass(frozen=True, eq=False)
class OrderSelection:
    """Result of :func:`select_order`.

    Attributes
    ----------
    spec : model
        The model spec at the largest order (data, options, held-back sample).
    orders : ndarray
        Candidate orders ``1..max_lags``.
    values : dict of ndarray
        Criteria per order (see :func:`tsfdi.models.criteria.information_criteria`).
    tol : float
        Relative tolerance of the RSS/SSS stabilisation rule.
    """

    spec: Any
    orders: np.ndarray
    values: dict
    tol: float

    @cached_property
    def table(self) -> pd.DataFrame:
        """Criteria indexed by order: ``bic``, ``aic``, ``hqic``, ``rss_sss`` (%), ``spp``, ``sigma2``, ``llf``."""
        cols = ["bic", "aic", "hqic", "rss_sss", "spp", "sigma2", "llf"]
        return pd.DataFrame({c: self.values[c] for c in cols}, index=pd.Index(self.orders, name="order"))

    @property
    def max_lags(self) -> int:
        return int(self.orders[-1])

    @property
    def selected(self) -> int:
        """Order with the smallest BIC."""
        return int(self.orders[self.values["bic"].argmin()])

    @property
    def at_bound(self) -> bool:
        """Whether the BIC minimum is at the search bound ``max_lags`` (with ``max_lags > 1``): a larger order may
        fit better, search further."""
        return self.max_lags > 1 and self.selected == self.max_lags

    @property
    def stabilized(self) -> int:
        """Smallest order after which RSS/SSS improves by no more than ``tol`` (relative) at any step (an exact
        fit counts as RSS/SSS = 0: nothing left to improve)."""
        r = np.where(self.values["exact"], 0.0, self.values["rss_sss"])   # an exact fit leaves rounding only
        # gain[i]: improvement of order i+2 over order i+1 (none once RSS/SSS is 0)
        gain = np.divide(r[:-1] - r[1:], r[:-1], out=np.zeros(r.size - 1), where=r[:-1] > 0)
        big = np.flatnonzero(gain > self.tol)
        return int(self.orders[big[-1] + 1]) if big.size else int(self.orders[0])

    def fit(self, order: int | None = None):
        """Fit the model of ``order`` (default :attr:`selected`) on the common sample of the selection."""
        order = self.selected if order is None else int_like(order, "order", minimum=1, maximum=self.max_lags)
        return self.spec.at_order(order).fit()

    def summary(self) -> Summary:
        """The criteria per order with the selected orders marked: a :class:`tsfdi.summary.Summary` (text when
        printed, HTML in a notebook) whose table is :attr:`table` plus a column ``selected`` (``min BIC`` at
        :attr:`selected`, ``RSS/SSS stable`` at :attr:`stabilized`)."""
        spec = self.spec
        mark = pd.Series("", index=self.table.index)
        mark[self.selected] = "min BIC (at the search bound)" if self.at_bound else "min BIC"
        mark[self.stabilized] = ", ".join(filter(None, [mark[self.stabilized], "RSS/SSS stable"]))
        header = [("Model", type(spec).__name__), ("Trend", spec.trend), ("Orders", f"1..{self.max_lags}"),
                  ("Observations (common sample)", sum(spec.nobs_records)), ("Selected (min BIC)",
                   f"{self.selected} (at the search bound)" if self.at_bound else self.selected),
                  ("RSS/SSS stable from", self.stabilized), ("RSS/SSS tolerance", self.tol)]
        if spec.multi:
            header.insert(2, ("Records", len(spec.records)))
        if spec.neqs > 1:
            header.insert(2, ("BIC variant", spec.criterion))
        notes = ["Every order is fitted on the same sample (the first max_lags samples of each record held back)."]
        if isinstance(spec, (ARX, VARX)):
            notes.append(f"{type(spec).__name__} order p: na = nb = p.")
        if self.at_bound:
            notes.append(f"The BIC minimum is at the search bound max_lags = {self.max_lags}: a larger order may fit "
                         f"better; search further (max_lags = {2 * self.max_lags}).")
        return Summary("Order selection", header, [("Criteria per order", self.table.assign(selected=mark))], notes)

    def plot(self, ax=None):
        """BIC and RSS/SSS against the order, as paper 003 Fig. 8. Returns the Figure."""
        from tsfdi.plotting.selection import plot_order_selection

        return plot_order_selection(self, ax=ax)

    def __repr__(self) -> str:
        return (f"OrderSelection({type(self.spec).__name__}, max_lags={self.max_lags}, selected={self.selected}, "
                f"stabilized={self.stabilized})")

r"""The windowed engine: every residual test on every sliding window of a record, and the decision rule.

Everything in tsfdi that tests windows (``identify_windows``, ``Monitor``, ``evaluate``,
``Baselines.select_alpha``, the command line) runs through :class:`ResidualWindows` and :func:`decide`.

The split follows a cost fitted once and queried per segment: :meth:`ResidualWindows.fit` drives a record once
through each model and keeps the residuals (with their prefix sums for the likelihood score);
:meth:`ResidualWindows.statistics` then gives, for any window length, step and test, the statistic, threshold,
p-value and rejection of every window, and a Gaussian log-likelihood score, in one frozen
:class:`WindowStatistics`. For a fixed model the residuals of a signal window are a slice of the record's
residuals (samples ``[s + p, s + W)`` of window ``[s, s + W)`` for an order-``p`` model), so the Ljung-Box, F
and mean-shift statistics of all windows come from prefix sums (:func:`~tsfdi.detection.ljungbox_windows`,
:meth:`~tsfdi.FTest.window_statistic`, :meth:`~tsfdi.MeanTest.window_statistic`); other tests are applied
window by window through their ``test`` method.

The decision rule of Dutta et al. (paper 003): a model is *accepted* when its residual test does not reject
(every channel accepts); one accepted model is an identification, several are ambiguous, none is no decision.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import solve_triangular

from tsfdi._data import as_signal, model_input
from tsfdi._validation import boolean, int_like, option
from tsfdi.detection.base import ResidualTest
from tsfdi.detection.combined import AnyOf
from tsfdi.detection.mean import MeanTest
from tsfdi.detection.variance import FTest
from tsfdi.detection.whiteness import LjungBox, LjungBoxWindows
from tsfdi.models import FPResults, InputOutputResults

__all__ = ["RULES", "SEQUENTIAL_RULES", "STATUS", "ResidualWindows", "WindowStatistics", "decide", "status"]

#: Decision rules. ``"paper"``: one accepted model is an identification, several are ambiguous, none is no decision
#: (Dutta et al.). ``"likelihood"``: among the accepted models (all models when none is accepted) the one whose
#: residuals are the most likely on the window under the model's own Gaussian innovation law (see
#: :attr:`WindowStatistics.loglik`), on samples common to every model. ``"pvalue"``: the same with the largest signal-level p-value (the
#: smallest channel p-value of each model).
RULES = ("paper", "likelihood", "pvalue")

#: Sequential rules, beside the windowed ones: ``"sprt"``, the multi-hypothesis sequential probability ratio test
#: (Armitage's rule, :func:`tsfdi.detection.sequential.msprt`) on the per-sample log-likelihoods of the models'
#: residuals (:meth:`ResidualWindows.loglik`): one decision, and its time, per record (not per window).
SEQUENTIAL_RULES = ("sprt",)

#: Label codes of :func:`decide` that are not a model index, and the status of each outcome.
NONE, AMBIGUOUS = -1, -2
STATUS = ("identified", "ambiguous", "none")


def decide(accepted: Any, rule: str = "paper", *, loglik: Any = None, pvalue: Any = None) -> np.ndarray:
    """Label per window from the models' acceptances: the one decision rule of tsfdi (see :data:`RULES`).

    Parameters
    ----------
    accepted : array_like of bool, shape (n_windows, n_models) or (n_models,)
        Whether each model's residual test accepts on each window.
    rule : {"paper", "likelihood", "pvalue"}
    loglik, pvalue : array_like, shape like ``accepted``
        Scores for the ``"likelihood"`` and ``"pvalue"`` rules (see :class:`WindowStatistics`).

    Returns
    -------
    ndarray of int, shape (n_windows,) (or a 0-d array for 1-D input)
        Index of the identified model; ``-1`` no decision, ``-2`` ambiguous (``"paper"`` only).
    """
    rule = option(rule, "rule", RULES)
    acc = np.asarray(accepted, dtype=bool)
    nacc = acc.sum(axis=-1)
    if rule == "paper":
        return np.where(nacc == 1, np.argmax(acc, axis=-1), np.where(nacc == 0, NONE, AMBIGUOUS)).astype(int)
    score = loglik if rule == "likelihood" else pvalue
    if score is None:
        raise ValueError(f"rule {rule!r} needs {'loglik' if rule == 'likelihood' else 'pvalue'}")
    score = np.asarray(score, dtype=float)
    if score.shape != acc.shape:
        raise ValueError(f"the scores of rule {rule!r} must have the shape of accepted {acc.shape}, got {score.shape}")
    score = np.where(np.isnan(score), -np.inf, score)
    masked = np.where(acc | (nacc == 0)[..., None], score, -np.inf)
    out = np.argmax(masked, axis=-1).astype(int)
    return np.where(np.isfinite(masked.max(axis=-1)), out, NONE)


def status(n_accepted: Any) -> np.ndarray:
    """``"identified"`` (one accepted model), ``"ambiguous"`` (several) or ``"none"`` per window, from the number
    of accepted models (the paper's rule, whatever rule picks the label)."""
    n = np.asarray(n_accepted)
    return np.where(n == 1, STATUS[0], np.where(n > 1, STATUS[1], STATUS[2]))


@dataclass(frozen=True, eq=False)
class WindowStatistics:
    r"""Residual test of every model on every sliding window of one record (:meth:`ResidualWindows.statistics`).

    Attributes
    ----------
    models : tuple of str
        Model names, axis 1 of the arrays.
    channels : tuple of str
    starts : ndarray of int, shape (n_windows,)
        Window ``w`` covers signal samples ``[starts[w], starts[w] + window)``.
    window, step : int
        Window length and step in samples.
    nobs : tuple of int
        Residual samples per window of each model (``window`` minus the model's order).
    statistic, threshold, pvalue : ndarray, shape (n_windows, n_models, n_channels)
    channel_reject : ndarray of bool, shape (n_windows, n_models, n_channels)
    reject : ndarray of bool, shape (n_windows, n_models)
        The model rejects the window (some channel rejects).
    loglik : ndarray, shape (n_windows, n_models)
        Gaussian log-likelihood per sample of each model's residuals on the ``m`` samples common to every model,
        under the model's innovation law :math:`N(0, \Sigma)` (:math:`\Sigma` the fit's ML residual covariance,
        ``sigma`` / ``sigma2``): :math:`-\tfrac12(\ln\det\Sigma + \operatorname{tr}(\Sigma^{-1}S) + k\ln 2\pi)`
        with :math:`S = \tfrac1m\sum_t e_t e_t'` (not demeaned), the per-sample form of the Gaussian
        log-likelihood of the innovations (Lütkepohl 2005, Sec. 3.4). A mean shift of the residuals (a new trim)
        and a change of their covariance both lower it; ``-inf`` for a model without a proper law (singular
        :math:`\Sigma`).
    decisions : tuple or None
        For tests applied window by window, the :class:`~tsfdi.Decision` of every window and model
        (``decisions[w][j]``); ``None`` when the statistics come from prefix sums.
    """

    models: tuple
    channels: tuple
    starts: np.ndarray
    window: int
    step: int
    nobs: tuple
    statistic: np.ndarray
    threshold: np.ndarray
    pvalue: np.ndarray
    channel_reject: np.ndarray
    reject: np.ndarray
    loglik: np.ndarray
    decisions: tuple | None = None

    def __len__(self) -> int:
        return int(self.starts.size)

    @property
    def accepted(self) -> np.ndarray:
        """Bool (n_windows, n_models): the model accepts the window."""
        return ~self.reject

    @property
    def min_pvalue(self) -> np.ndarray:
        """Signal-level p-value (smallest channel p-value) per window and model."""
        return self.pvalue.min(axis=2)

    @property
    def status(self) -> np.ndarray:
        """``"identified" | "ambiguous" | "none"`` per window (:func:`status`)."""
        return status(self.accepted.sum(axis=1))

    def labels(self, rule: str = "paper") -> np.ndarray:
        """Model index per window by ``rule`` (:func:`decide`; -1 none, -2 ambiguous)."""
        return decide(self.accepted, rule, loglik=self.loglik, pvalue=self.min_pvalue)

    def __repr__(self) -> str:
        return f"WindowStatistics(windows={len(self)}, window={self.window}, step={self.step}, models={self.models})"


def _sample_loglik(res: Any, e: np.ndarray) -> np.ndarray:
    r"""Gaussian log-likelihood of every residual row ``e_t`` under the model's innovation law :math:`N(0, \Sigma)`:
    :math:`-\tfrac12(\ln\det\Sigma + e_t'\Sigma^{-1}e_t + k\ln 2\pi)`, ``-inf`` everywhere for a model without a
    proper law (singular :math:`\Sigma`)."""
    k = e.shape[1]
    sigma = np.asarray(res.sigma if hasattr(res, "sigma") else res.sigma2, dtype=np.float64).reshape(k, k)
    try:
        chol = np.linalg.cholesky(sigma)
    except np.linalg.LinAlgError:
        chol = None
    if chol is None or not np.all(np.isfinite(chol)) or np.any(np.diag(chol) <= 0):
        return np.full(e.shape[0], -np.inf)            # no proper Gaussian law (an exact fit): never the most likely
    # whitened residuals z_t = L^-1 e_t (L the Cholesky factor of Sigma): the k x k triangular solve once, then one
    # matrix product over the samples (3x faster than a triangular solve with n right-hand sides)
    z = e @ solve_triangular(chol, np.eye(k), lower=True, check_finite=False).T
    logdet = 2.0 * np.log(np.diag(chol)).sum()
    return -0.5 * (logdet + np.einsum("ij,ij->i", z, z) + k * np.log(2 * np.pi))


def _prefix_sums(test: Any) -> bool:
    """Whether the engine computes ``test`` on all windows at once (:meth:`~tsfdi.CalibratedTest.window_statistic`
    from prefix sums): a per-channel Ljung-Box, a mean-shift or a one-sided F test."""
    return ((isinstance(test, LjungBox) and test.multivariate is None) or isinstance(test, MeanTest)
            or (isinstance(test, FTest) and test.alternative == "greater"))


class ResidualWindows:
    r"""One record driven once through every model, then tested on sliding windows of any length.

    Parameters
    ----------
    models : mapping
        Name -> fitted AR / VAR results, all with the same number of channels; or name -> fitted ARX / VARX results
        (input-output models, :class:`~tsfdi.models.InputOutputResults`, e.g. an FP-ARX's point ``.at(k)``), all
        with the same inputs: :meth:`fit` then takes the record's input ``u``. The kinds do not mix (a model with
        inputs and one without take different data).

    Examples
    --------
    >>> rw = ResidualWindows({"healthy": m0, "rotor1": m1}).fit(x)          # doctest: +SKIP
    >>> ws = rw.statistics(tsfdi.LjungBox(lags=20, alpha=1e-3), window=500, step=100)   # doctest: +SKIP
    >>> ws.labels("paper")                                                  # doctest: +SKIP
    """

    def __init__(self, models: Mapping) -> None:
        if not isinstance(models, Mapping) or not models:
            raise TypeError("models must be a non-empty mapping name -> fitted results")
        for name, res in models.items():
            if not hasattr(res, "residuals"):
                raise TypeError(f"models[{name!r}] must be fitted results (AR, VAR, ARX, VARX), got "
                                f"{type(res).__name__}")
            if isinstance(res, FPResults):
                raise TypeError(f"models[{name!r}] is a functionally pooled model (FPResults): give its point model "
                                "at the record's operating point, .at(k) (k logged, or .estimate_k(signal).k_hat)")
        kinds = {isinstance(res, InputOutputResults) for res in models.values()}
        if len(kinds) > 1:
            raise TypeError("models mixes ARX / VARX (input-output) models with AR / VAR models: the ARX / VARX "
                            "residuals are of the output given u, the others of the output alone; test one kind per "
                            "engine")
        #: whether the models take an input ``u`` (ARX / VARX models)
        self.inputs = kinds == {True}
        self.models = dict(models)
        # the first residual is at the largest lag (an ARX's / VARX's input lags nk + nb - 1 may reach beyond na)
        self.orders = {name: int(res.model.max_lag if self.inputs else res.lags) for name, res in self.models.items()}
        nchan = {int(getattr(r, "neqs", 1)) for r in self.models.values()}
        if len(nchan) > 1:
            raise ValueError(f"every model must have the same number of channels, got {sorted(nchan)}")
        self.nchan = nchan.pop()
        # models fitted on named channels: one order for all, so that every statistic and reference lines up
        named = {name: [str(c) for c in r.model.data.channels] for name, r in self.models.items()
                 if r.model.data.named}
        orders = {tuple(c) for c in named.values()}
        if len(orders) > 1:
            raise ValueError("models fitted on named channels must share one channel order, got "
                             + "; ".join(f"{name!r}: {c}" for name, c in named.items()))
        self._channels = list(orders.pop()) if orders else None
        self._inputs = None             # the first model's inputs and whether they are named (matched by name)
        if self.inputs:
            fitted = {name: ([str(c) for c in r.model.u_data.channels], r.model.u_data.named)
                      for name, r in self.models.items()}
            # named inputs: one set (each model takes them by name, in its own order); else one count
            if len({frozenset(c) if named else len(c) for c, named in fitted.values()}) > 1:
                raise ValueError("ARX or VARX models must share one set of inputs, got "
                                 + "; ".join(f"{name!r}: {c}" for name, (c, _) in fitted.items()))
            self._inputs = next(iter(fitted.values()))
        self._resid: dict | None = None
        self.nobs_: int | None = None
        self.channels_: tuple = ()

    def fit(self, signal: Any, *, u: Any = None, channels: Any = None) -> ResidualWindows:
        """Filter the record through every model once and keep the residuals.

        Parameters
        ----------
        signal : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, k)
            The record (``k`` = the models' channels), finite.
        u : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, n_inputs)
            The record's input, for ARX / VARX models only (required for them, refused otherwise): as long as
            ``signal``, with its index when both carry one, its channels matched to the models' inputs by name when
            both are named (else by position). The residuals are the models' ``residuals(signal, u)``.
        channels : sequence of str, optional
            Channel names (default: those of ``signal``).

        Returns
        -------
        self

        Raises
        ------
        TypeError, ValueError
            A ``signal`` that is not numeric, not 1-D / 2-D, holds NaN / inf or masked values, is shorter than a
            model's order + 1 or has another number of channels than the models; ``u`` missing for ARX / VARX models
            or given for others, or (named ``u``) not numeric and finite, of another length or index than ``signal``, or
            without the models' inputs.
        """
        sig = as_signal(signal, "signal", allow_constant=True)
        if sig.nchan != self.nchan:
            raise ValueError(f"signal has {sig.nchan} channel(s) but the models were fitted on {self.nchan}")
        if self._channels is not None:          # a named signal is reordered to the models' channels, by name
            sig = sig.match_channels(self._channels, "signal")
        usig = model_input(u, sig, self._inputs)
        resid = {name: np.asarray(res.residuals(sig) if usig is None else res.residuals(sig, usig),
                                  dtype=np.float64).reshape(-1, self.nchan)
                 for name, res in self.models.items()}
        return self._set(resid, sig.nobs, sig.channels if channels is None else channels)

    def fit_residuals(self, residuals: Mapping, nobs: int, *, channels: Any = None) -> ResidualWindows:
        """Use residuals computed elsewhere (e.g. held-out residuals of a record through a model fitted without
        it) instead of filtering: ``residuals`` maps every name to an array ``(nobs - order, k)``.

        Returns
        -------
        self
        """
        nobs = int_like(nobs, "nobs", minimum=1)
        if not isinstance(residuals, Mapping):
            raise TypeError(f"residuals must be a mapping model name -> residual array, got {type(residuals).__name__}")
        resid = {}
        for name in self.models:
            if name not in residuals:
                raise ValueError(f"residuals has no entry for the model {name!r}")
            shape = (nobs - self.orders[name], self.nchan)
            if shape[0] < 1:
                raise ValueError(f"nobs ({nobs}) must exceed the order ({self.orders[name]}) of the model {name!r}")
            e = as_signal(residuals[name], f"residuals[{name!r}]", allow_constant=True).values
            if e.shape != shape:
                raise ValueError(f"residuals[{name!r}] must have shape {shape}, got {e.shape}")
            resid[name] = e
        return self._set(resid, nobs, channels)

    def _set(self, resid: dict, nobs: int, channels: Any) -> ResidualWindows:
        self._resid = resid
        self._loglik: dict = {}          # name -> per-sample log-likelihood of the residual rows, made when first asked
        self._prefix: dict = {}          # name -> its prefix sums (leading zero): the windows' likelihood scores
        self._lag_products: dict = {}    # (name, lags, demean) -> LjungBoxWindows, shared by every window length
        self.nobs_ = nobs
        self.channels_ = tuple(str(c) for c in channels) if channels is not None else tuple(
            f"y{i}" for i in range(self.nchan))
        if len(self.channels_) != self.nchan:
            raise ValueError(f"channels must name the {self.nchan} channel(s), got {list(self.channels_)}")
        return self

    def _sample_loglik(self, name: str) -> np.ndarray:
        """Per-sample log-likelihood of model ``name``'s residual rows, computed once per record."""
        if name not in self._loglik:
            self._loglik[name] = _sample_loglik(self.models[name], self._resid[name])
        return self._loglik[name]

    def loglik(self, *, common: int | None = None) -> np.ndarray:
        r"""Gaussian log-likelihood of every model's residual at every sample, on the samples common to all models.

        The per-sample series behind :attr:`WindowStatistics.loglik` (a window's score is its mean over the window's
        common samples) and the input of the sequential rules (:func:`tsfdi.detection.sequential.msprt`).

        Parameters
        ----------
        common : int, optional
            First signal sample of the series (default: the largest model order, the first sample every model has a
            residual for); at least that order.

        Returns
        -------
        ndarray, shape (nobs - common, n_models)
            Row ``r`` is signal sample ``common + r``; column ``j`` is model ``j`` (in the order of ``models``):
            :math:`\ell_{t,j} = -\tfrac12(\ln\det\Sigma_j + e_{t,j}'\Sigma_j^{-1}e_{t,j} + k\ln 2\pi)`, with
            :math:`\Sigma_j` the fit's ML residual covariance; ``-inf`` for a model without a proper law
            (singular :math:`\Sigma_j`).

        Raises
        ------
        ValueError
            The engine is not fitted, or ``common`` is below the largest model order or leaves no sample.
        """
        if self._resid is None:
            raise ValueError("ResidualWindows is not fitted: call fit(signal) first")
        pmax = max(self.orders.values())
        common = pmax if common is None else int_like(common, "common", minimum=pmax)
        if common >= self.nobs_:
            raise ValueError(f"common must be below the signal length {self.nobs_}, got {common}")
        return np.column_stack([self._sample_loglik(name)[common - p:] for name, p in self.orders.items()])

    def statistics(self, test: Any, *, window: int, step: int = 1, common: int | None = None,
                   loglik: bool = True) -> WindowStatistics:
        """Every model's residual test on every window of ``window`` samples, ``step`` apart.

        Parameters
        ----------
        test : ResidualTest or mapping
            The test applied to every model's residuals, or a mapping name -> test (each model with its own test,
            e.g. thresholds calibrated on that model's held-out residuals).
        window, step : int
            Window length and step in signal samples.
        common : int, optional
            Largest model order over which the likelihood score is aligned (default: the largest order); the
            score of every model uses signal samples ``[s + common, s + window)``.
        loglik : bool
            Compute the likelihood score (``False``: NaN, saves a determinant per window).

        Returns
        -------
        WindowStatistics
        """
        if self._resid is None:
            raise ValueError("ResidualWindows is not fitted: call fit(signal) first")
        window = int_like(window, "window", minimum=2)
        step = int_like(step, "step", minimum=1)
        loglik = boolean(loglik, "loglik")
        nobs = self.nobs_
        if window > nobs:
            raise ValueError(f"window must be <= the signal length {nobs}, got {window}")
        pmax = max(self.orders.values()) if common is None else int_like(common, "common", minimum=0)
        if window - pmax < 3:
            raise ValueError(f"window ({window}) must exceed the largest model order ({pmax}) by at least 3 samples")
        if isinstance(test, Mapping):
            missing = [name for name in self.models if name not in test]
            if missing:
                raise ValueError(f"test is a mapping but has no test for the model(s) {missing}")
            bad = [name for name in self.models if not isinstance(test[name], ResidualTest)]
        else:
            bad = [] if isinstance(test, ResidualTest) else ["test"]
        if bad:
            raise TypeError(f"test must be a residual test (LjungBox, FTest, GLRT, ...) or a mapping name -> test; "
                            f"not one for {bad}")
        step = min(step, nobs)                  # a step beyond the record: one window
        starts = np.arange(0, nobs - window + 1, step)
        nwin, nmod = starts.size, len(self.models)
        out, decs, nres = (), [], []
        for j, (name, res) in enumerate(self.models.items()):
            p = self.orders[name]
            n = window - p
            pre = False
            if loglik:
                if name not in self._prefix:
                    ll = self._sample_loglik(name)
                    self._prefix[name] = np.concatenate([[0.0], np.cumsum(ll)]) if np.isfinite(ll).all() else None
                pre = self._prefix[name]
            t = test[name] if isinstance(test, Mapping) else test
            lbw = tuple(self._lag_windows(name, part, n) for part in (t.tests if isinstance(t, AnyOf) else (t,)))
            part = self._model(res, self._resid[name], pre, t, starts, n, step, name, p, pmax, window, lbw)
            cols = part[3].shape[1]
            if not out:                         # statistic, p-value, threshold, channel rejection; the score
                out = (*(np.empty((nwin, nmod, cols)) for _ in range(3)), np.empty((nwin, nmod, cols), bool),
                       np.empty((nwin, nmod)))
            elif cols != out[3].shape[2]:
                raise ValueError(f"the tests of the models give {out[3].shape[2]} and {cols} statistics per window "
                                 f"(model {name!r}): test every model per channel, or every one jointly")
            for arr, value in zip(out, part):
                arr[:, j] = value
            decs.append(part[5])
            nres.append(n)
        stat, pv, thr, rej_c, ll = out
        dec = None
        if all(d is not None for d in decs):
            dec = tuple(tuple(d[i] for d in decs) for i in range(nwin))
        return WindowStatistics(models=tuple(self.models), channels=self.channels_, starts=starts, window=window,
                                step=step, nobs=tuple(nres), statistic=stat, threshold=thr, pvalue=pv,
                                channel_reject=rej_c, reject=rej_c.any(axis=2), loglik=ll, decisions=dec)

    def _lag_windows(self, name: str, test: Any, n: int) -> LjungBoxWindows | None:
        """The lag products of model ``name``'s residuals for a per-channel Ljung-Box ``test`` (its own
        ``window_statistic``, not a subclass'), kept across window lengths; ``None`` for another test."""
        if not (isinstance(test, LjungBox) and test.multivariate is None and n > test.lags
                and type(test).window_statistic is LjungBox.window_statistic):
            return None
        key = (name, test.lags, test.demean)
        if key not in self._lag_products:
            self._lag_products[key] = LjungBoxWindows(self._resid[name], test.lags, demean=test.demean)
        return self._lag_products[key]

    @staticmethod
    def _model(res: Any, e: np.ndarray, prefix: Any, test: Any, starts: np.ndarray, n: int, step: int,
               name: str, p: int, pmax: int, window: int, lbw: tuple = (None,)) -> tuple:
        """One fitted model with its record residuals ``e`` on every window: statistic, p-value, threshold, channel
        rejection (n_windows, k), the likelihood score (n_windows,; NaN when ``prefix`` is False, -inf when it is
        None: a model without a proper Gaussian law; else the prefix sums of the per-sample log-likelihood)
        and the window decisions (or None). ``lbw``: per part of the test (one for a single test, one per part of an
        :class:`~tsfdi.AnyOf`), the lag products of ``e`` for a per-channel Ljung-Box test (kept by
        :meth:`statistics` across window lengths) or ``None``."""
        nwin = starts.size
        ref = test.reference(res)
        tests = test.tests if isinstance(test, AnyOf) else (test,)
        refs = ref["references"] if isinstance(test, AnyOf) else (ref,)
        for t in tests:
            if isinstance(t, LjungBox) and t.multivariate is None and n <= t.lags:
                raise ValueError(f"window must exceed lags + the model order ({t.lags} + {p}) for model {name!r}, "
                                 f"got {window}")
        ds = None
        if all(_prefix_sums(t) for t in tests):
            if isinstance(test, AnyOf) and test.correction == "minp" and not test.calibrated:
                raise ValueError("AnyOf(correction='minp') is not calibrated: call calibrate(healthy residuals, "
                                 "window=...) first")
            # every part from prefix sums: its statistic, threshold and p-value of all windows at once
            got = [(s, *t.threshold_pvalue(s, n, **r)) for t, r, lb in zip(tests, refs, lbw)
                   for s in [lb.statistic(n, step) if lb is not None else t.window_statistic(e, n, step, **r)]]
            if isinstance(test, AnyOf):          # the rule of AnyOf.test on every window
                stat, thr, pv, rej_c = test.combine([g[2] for g in got], [g[0] > g[1] for g in got])
            else:
                stat, thr, pv = got[0]
                rej_c = stat > thr
        else:
            ds = [test.test(e[s:s + n], **ref) for s in starts]
            stat = np.array([d.statistic for d in ds]).reshape(nwin, -1)
            pv = np.array([d.pvalue for d in ds]).reshape(nwin, -1)
            thr = np.array([d.threshold for d in ds], dtype=float).reshape(nwin, -1)
            rej_c = np.array([d.channel_reject for d in ds]).reshape(nwin, -1)
        if prefix is False:
            return stat, pv, thr, rej_c, np.full(nwin, np.nan), ds
        if prefix is None:            # no proper Gaussian law (singular Sigma): never the most likely
            return stat, pv, thr, rej_c, np.full(nwin, -np.inf), ds
        # likelihood score: the mean per-sample log-likelihood (ResidualWindows.loglik) on the common samples
        # [s + pmax, s + W), residual rows [s + pmax - p, s + W - p)
        off = pmax - p
        m = window - pmax
        lo = starts + off
        return stat, pv, thr, rej_c, (prefix[lo + m] - prefix[lo]) / m, ds

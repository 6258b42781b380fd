r"""Sequential decisions on residuals: Wald's SPRT and the multi-hypothesis rule (MSPRT).

A windowed test decides on a fixed number of samples. A sequential test accumulates the log-likelihood ratio of
the residuals sample by sample and stops as soon as the evidence crosses a bound set by the error probabilities
asked for, so that each decision comes with its error probabilities and an expected time to decide (the ASN).

* :class:`SPRT`: Wald's sequential probability ratio test of a healthy residual law (H0) against a fault law
  (H1: a residual variance ratio, a mean shift, or a fault model's residuals), with Wald's bounds
  (:func:`wald_bounds`), its operating characteristic (:meth:`SPRT.oc`), average sample number
  (:meth:`SPRT.asn`), a Monte Carlo check (:meth:`SPRT.monte_carlo`) and a scale correction of the per-sample
  log-likelihood ratio for models estimated from real records (:meth:`SPRT.calibrate`).
* :func:`msprt`: Armitage's multi-hypothesis rule on the per-sample log-likelihoods of ``M`` candidate models,
  with the scale correction :func:`msprt_scale`.
* :func:`record_effect`: for records of one state that differ from each other more than their within-record noise
  says, a record-level predictive likelihood (:meth:`RecordEffect.loglik`) whose evidence saturates, as input of
  :func:`msprt`; :func:`aligned_record_effect` the same for records that follow one programme (the same manoeuvres
  at the same sample), its law taken at every sample from the held-out records' running summaries at that sample.

References
----------
Wald, A. (1945). Sequential tests of statistical hypotheses. *Ann. Math. Statist.* 16(2), 117-186.
Wald, A. (1947). *Sequential Analysis*. Wiley (OC and ASN approximations, chapters 3 and 4).
Kopsaftopoulos, F. P., Fassois, S. D. (2015). A vibration model residual-based sequential probability ratio test
framework for structural health monitoring. *Structural Health Monitoring* 14(4), 359-381 (paper 003, ref. 11).
Armitage, P. (1950). Sequential analysis with more than two alternative hypotheses, and its relation to
discriminant function analysis. *J. R. Statist. Soc. B* 12(1), 137-144.
Baum, C. W., Veeravalli, V. V. (1994). A sequential procedure for multihypothesis testing. *IEEE Trans. Inform.
Theory* 40(6), 1994-2007.
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numba
import numpy as np
import pandas as pd
from scipy import linalg, optimize, special, stats

from tsfdi._data import as_signal, sampling_frequency
from tsfdi._validation import MAX_VALUES, boolean, check_rng, float_like, int_like, option, probability
from tsfdi.detection.base import per_channel
from tsfdi.summary import Summary

__all__ = ["SPRT", "AlignedRecordEffect", "RecordEffect", "SequentialDecision", "SequentialIdentification",
           "aligned_record_effect", "msprt", "msprt_scale", "record_effect", "renewal_walk", "wald_bounds"]

_LOG2PI = float(np.log(2.0 * np.pi))


def wald_bounds(alpha: float, beta: float) -> tuple[float, float]:
    r"""Wald's bounds of the sequential probability ratio test.

    Parameters
    ----------
    alpha, beta : float
        Type I (false alarm) and type II (missed fault) error probabilities asked for, each in (0, 1), with
        ``alpha + beta < 1``.

    Returns
    -------
    lower, upper : float
        :math:`B = \ln(\beta / (1 - \alpha))` and :math:`A = \ln((1 - \beta) / \alpha)`: the test accepts H0 when
        the cumulative log-likelihood ratio falls to :math:`B` and rejects it when it reaches :math:`A`.

    Notes
    -----
    Wald (1945, eqs. 3.30-3.31): with these bounds the realised error probabilities :math:`\alpha', \beta'` satisfy
    :math:`\alpha' \le \alpha / (1 - \beta)` and :math:`\beta' \le \beta / (1 - \alpha)` (and
    :math:`\alpha' + \beta' \le \alpha + \beta`) whatever the overshoot of the bounds, provided the per-sample
    log-likelihood ratio is the true one. The overshoot makes the realised rates smaller than ``alpha``, ``beta``.
    """
    alpha = probability(alpha, "alpha")
    beta = probability(beta, "beta")
    if alpha + beta >= 1.0:
        raise ValueError(f"alpha + beta must be < 1, got alpha={alpha:g}, beta={beta:g}")
    return float(np.log(beta) - np.log1p(-alpha)), float(np.log1p(-beta) - np.log(alpha))


def _freeze_arrays(result: Any, **ndmin: int) -> None:
    """Replace each named array field of a frozen result (``None`` left alone) by a read-only float copy of at least
    ``ndmin`` dimensions, so the result cannot be changed through it."""
    for name, nd in ndmin.items():
        value = getattr(result, name)
        if value is not None:
            a = np.array(value, dtype=np.float64, ndmin=nd)
            a.flags.writeable = False
            object.__setattr__(result, name, a)


# ---------------------------------------------------------------------------------------------------- kernels
@numba.njit(cache=True, nogil=True)
def _sprt_paths(z, s0, lower, upper, restart):  # pragma: no cover - compiled
    """Cumulative sums of the rows of ``z`` from ``s0`` (restarted at 0 at each lower crossing when ``restart``);
    per row the first crossing (sample index, -1 none) and its side (+1 upper, -1 lower), and the restarts before
    it."""
    n, m = z.shape
    path = np.empty((n, m))
    first = np.full(n, -1)
    side = np.zeros(n, dtype=np.int8)
    restarts = np.zeros(n, dtype=np.int64)
    for i in range(n):
        s = s0[i]
        for t in range(m):
            s += z[i, t]
            if first[i] < 0:
                if s >= upper:
                    first[i] = t
                    side[i] = 1
                elif s <= lower:
                    if restart:
                        restarts[i] += 1
                        s = 0.0
                    else:
                        first[i] = t
                        side[i] = -1
            elif restart and s <= lower:
                s = 0.0
            path[i, t] = s
    return path, first, side, restarts


@numba.njit(cache=True, nogil=True)
def _renewal_kernel(z, s, start, lower, upper):  # pragma: no cover - compiled
    n = z.shape[0]
    path = np.full(n, np.nan)
    alarm = np.zeros(n, dtype=np.bool_)
    cycle = np.empty(n, dtype=np.int64)
    lowers = 0
    for t in range(n):
        cycle[t] = start
        if not np.isfinite(z[t]):
            continue
        s += z[t]
        path[t] = s
        if s >= upper:
            alarm[t] = True
            s = 0.0
            start = t + 1
        elif s <= lower:
            s = 0.0
            start = t + 1
            lowers += 1
    return path, alarm, cycle, lowers, s, start


def renewal_walk(z: Any, lower: float, upper: float, *, state: float = 0.0, start: int = 0) -> tuple:
    """Wald's SPRT run for monitoring: the statistic restarts at 0 at every crossing of either bound (``lower``:
    H0 accepted; ``upper``: an alarm), so alarms form renewal cycles (the sequential ``Monitor``, the online
    detector's ``statistic="sprt"``).

    Parameters
    ----------
    z : ndarray, shape (n,)
        Per-sample log-likelihood ratios; a non-finite sample is skipped (the statistic and its path left as they
        are, NaN in the path).
    lower, upper : float
        The bounds (:func:`wald_bounds`; ``upper`` may be an alarm threshold of its own).
    state, start : float, int
        The statistic carried from earlier samples and where its cycle began, relative to ``z[0]`` (negative for a
        cycle begun before): what the previous call returned, so a stream fed in chunks walks as the whole record.

    Returns
    -------
    tuple
        ``(path, alarm, cycle, lower_crossings, state, start)``: the statistic at each sample before any restart,
        where it reaches ``upper``, where each sample's cycle began, the number of lower crossings, and the state
        and cycle start after the block (relative to ``z[0]``).
    """
    return _renewal_kernel(np.ascontiguousarray(z, dtype=np.float64), float(state), int(start), float(lower),
                           float(upper))


@numba.njit(cache=True, nogil=True)
def _pairwise_cusum(loglik, w, scale, bound):  # pragma: no cover - compiled
    """Dominance paths of the restarted MSPRT from the pairwise statistics ``w`` (updated in place):
    ``W[j, k] = max(0, W[j, k] + scale (l_j - l_k))`` and ``d_j = min_{k != j} W[j, k]``; the first sample where
    some ``d_j >= bound``."""
    n, m = loglik.shape
    dom = np.empty((n, m))
    first = -1
    for t in range(n):
        for j in range(m):
            lo = np.inf
            for k in range(m):
                if k != j:
                    v = w[j, k] + scale * (loglik[t, j] - loglik[t, k])
                    v = v if v > 0.0 else 0.0
                    w[j, k] = v
                    if v < lo:
                        lo = v
            dom[t, j] = lo
            if first < 0 and lo >= bound:
                first = t
    return dom, first


# ---------------------------------------------------------------------------------------------------- results
def _seconds(n: int, dt: float | None) -> float:
    return float(n * dt) if (dt is not None and n >= 0) else float("nan")


@dataclass(frozen=True)
class SequentialDecision:
    """Outcome of :meth:`SPRT.test`: Wald's sequential decision on one residual record.

    Attributes
    ----------
    reject : bool
        True when the statistic reached the upper bound (H1, fault); False when it reached the lower bound (H0
        accepted) or when the record ended first (see ``decided``).
    decided : bool
        Whether a bound was crossed within the record. With ``restart=True`` only the upper crossing (the alarm)
        decides.
    decision_time : int
        Samples accumulated up to and including the deciding sample (Wald's :math:`N`; the deciding sample is at
        position ``decision_time - 1`` of the residuals); -1 when undecided.
    decision_seconds : float
        ``decision_time`` times the sampling interval, when the residuals carry a time index (or ``fs`` was given);
        else nan.
    statistic : ndarray, shape (nobs,)
        Path of the cumulative (scaled) log-likelihood ratio :math:`S_t`, over the whole record (also after the
        decision); with ``restart=True`` the value after each reset to 0.
    bounds : tuple of float
        ``(lower, upper)``: Wald's :math:`(B, A)` of :func:`wald_bounds`.
    alpha, beta : float
        Error probabilities asked for.
    restarts : int
        Lower crossings (resets to 0) before the decision (``restart=True``), else 0.
    nobs : int
        Residual samples tested.
    alternative : str
        ``"variance"``, ``"mean"`` or ``"model"``.
    scale : float
        Factor applied to the per-sample log-likelihood ratio (1 unless calibrated, :meth:`SPRT.calibrate`).
    channels : tuple of str
        Residual channel names.
    time : ndarray or None
        Seconds since the first residual sample, per sample (None without a time index or ``fs``).
    details : dict
        The test's options (ratio, shift, restart).
    """

    reject: bool
    decided: bool
    decision_time: int
    decision_seconds: float
    statistic: np.ndarray
    bounds: tuple
    alpha: float
    beta: float
    restarts: int = 0
    nobs: int = 0
    alternative: str = ""
    scale: float = 1.0
    channels: tuple = ()
    time: np.ndarray | None = None
    details: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        _freeze_arrays(self, statistic=1, time=1)

    @property
    def test(self) -> str:
        """Name of the test (for the shared decision vocabulary)."""
        return f"SPRT ({self.alternative})"

    def summary(self) -> Summary:
        """The decision, its time and the bounds as a :class:`tsfdi.summary.Summary`."""
        verdict = ("reject H0 (fault)" if self.reject else "accept H0") if self.decided else "undecided"
        header = [("Test", self.test), ("alpha", self.alpha), ("beta", self.beta),
                  ("Bounds (B, A)", f"({self.bounds[0]:.4g}, {self.bounds[1]:.4g})"),
                  ("LLR scale", self.scale), ("Observations", self.nobs), ("Channels", ", ".join(self.channels)),
                  ("Decision", verdict), ("Decision time (samples)", self.decision_time),
                  ("Decision time (s)", self.decision_seconds), ("Restarts", self.restarts)]
        return Summary("Sequential probability ratio test", header, [],
                       ["Wald's bounds: realised error rates alpha' <= alpha / (1 - beta), beta' <= beta / (1 - alpha) "
                        "when the per-sample log-likelihood ratio is exact."])

    def __repr__(self) -> str:
        verdict = ("reject" if self.reject else "accept") if self.decided else "undecided"
        return (f"SequentialDecision({verdict}, alternative={self.alternative!r}, decision_time={self.decision_time}, "
                f"alpha={self.alpha:g}, beta={self.beta:g}, nobs={self.nobs}, restarts={self.restarts})")

    def _repr_html_(self) -> str:
        return self.summary().as_html()

    def plot(self, ax: Any = None, **kwargs: Any) -> Any:
        """The statistic path with its bounds and the decision time; see
        :func:`tsfdi.plotting.sequential.plot_sequential_decision`. Returns the matplotlib ``Figure``."""
        from tsfdi.plotting.sequential import plot_sequential_decision

        return plot_sequential_decision(self, ax=ax, **kwargs)


@dataclass(frozen=True)
class SequentialIdentification:
    """Outcome of :func:`msprt`: the multi-hypothesis sequential decision on one record.

    Attributes
    ----------
    label : int
        Index of the decided model, -1 when undecided at the end of the record.
    decision_time : int
        Samples accumulated from ``start`` up to and including the deciding sample (the deciding sample is at
        position ``start + decision_time - 1`` of the record); -1 when undecided.
    decision_seconds : float
        ``decision_time`` times the sampling interval when known (time index or ``fs``), else nan.
    statistic : ndarray, shape (nobs - start, M)
        Dominance path of every model: :math:`d_j(t) = S_j(t) - \\max_{k \\ne j} S_k(t)` (restarted: the smallest
        pairwise CUSUM ``min_k W_jk(t)``), from ``start`` on; model ``j`` is decided when :math:`d_j` reaches
        ``bound``.
    bound : float
        :math:`\\ln((M - 1) / \\alpha)`.
    alpha : float
        Probability of a wrong decision asked for (per true model).
    models : tuple of str
        Model names (``m0, m1, ...`` when not given).
    start : int
        First accumulated sample.
    scale : float
        Factor applied to the log-likelihoods (:func:`msprt_scale`).
    restart : bool
        Whether the pairwise statistics were restarted (CUSUM form).
    time : ndarray or None
        Seconds since sample ``start`` per accumulated sample, when known.
    state : ndarray, shape (M, M) or None
        The pairwise statistics at the end of the record, :math:`W_{jk}` (restarted) or :math:`S_j - S_k`: what
        ``msprt(next_samples, restart=True, state=...)`` continues from.
    """

    label: int
    decision_time: int
    decision_seconds: float
    statistic: np.ndarray
    bound: float
    alpha: float
    models: tuple
    start: int = 0
    scale: float = 1.0
    restart: bool = False
    time: np.ndarray | None = None
    state: np.ndarray | None = None

    def __post_init__(self) -> None:
        _freeze_arrays(self, statistic=2, time=1, state=2)

    @property
    def decided(self) -> bool:
        """Whether a model was decided within the record."""
        return self.label >= 0

    @property
    def name(self) -> str | None:
        """Name of the decided model, else None."""
        return self.models[self.label] if self.label >= 0 else None

    @property
    def status(self) -> str:
        """``"identified"`` or ``"undecided"``."""
        return "identified" if self.label >= 0 else "undecided"

    def summary(self) -> Summary:
        """The decision, its time, the bound and the final dominance of every model."""
        header = [("Rule", "MSPRT (Armitage 1950)" + (", restarted" if self.restart else "")),
                  ("alpha", self.alpha), ("Bound ln((M-1)/alpha)", self.bound), ("LLR scale", self.scale),
                  ("Status", self.status), ("Model", self.name or "-"),
                  ("Decision time (samples)", self.decision_time), ("Decision time (s)", self.decision_seconds)]
        t = self.decision_time - 1 if self.decided else self.statistic.shape[0] - 1
        table = pd.DataFrame({"dominance": self.statistic[t] if t >= 0 else np.full(len(self.models), np.nan)},
                             index=pd.Index(self.models, name="model"))
        return Summary("Sequential identification", header, [("Dominance at the decision (or the end)", table)],
                       ["A model is decided when its log-likelihood exceeds every other's by the bound; the "
                        "probability of a wrong decision is then at most alpha under each candidate model."])

    def __repr__(self) -> str:
        return (f"SequentialIdentification(status={self.status!r}, model={self.name!r}, "
                f"decision_time={self.decision_time}, alpha={self.alpha:g}, models={len(self.models)})")

    def _repr_html_(self) -> str:
        return self.summary().as_html()

    def plot(self, ax: Any = None, **kwargs: Any) -> Any:
        """Dominance paths with the bound and the decision time; see
        :func:`tsfdi.plotting.sequential.plot_sequential_identification`."""
        from tsfdi.plotting.sequential import plot_sequential_identification

        return plot_sequential_identification(self, ax=ax, **kwargs)


# ---------------------------------------------------------------------------------------------------- helpers
def _covariance(sigma: Any, k: int, name: str) -> tuple[np.ndarray, np.ndarray | None]:
    """``sigma`` as per-channel variances (k,) or a Cholesky factor of a (k, k) covariance; ``(variances, chol)``
    with ``chol`` None for a diagonal law."""
    if sigma is None:
        raise TypeError(f"{name} is required: the residual variance (a number, one per channel, or a covariance "
                        "matrix)")
    if isinstance(sigma, (str, bytes, bool, np.bool_)):
        raise TypeError(f"{name} must be a positive number, one per channel or a covariance matrix, got {sigma!r}")
    try:
        s = np.asarray(sigma, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a positive number, one per channel or a covariance matrix, got "
                        f"{type(sigma).__name__}") from None
    if s.ndim == 2 and s.shape == (1, 1):
        s = s.reshape(1)
    if s.ndim <= 1:
        return per_channel(s, name, k), None
    if s.shape != (k, k):
        raise ValueError(f"{name} must be a ({k}, {k}) covariance matrix for {k} channel(s), got shape {s.shape}")
    if not np.isfinite(s).all() or not np.allclose(s, s.T, rtol=1e-10, atol=0.0):
        raise ValueError(f"{name} must be a finite symmetric covariance matrix")
    try:
        chol = linalg.cholesky(s, lower=True)
    except linalg.LinAlgError:
        raise ValueError(f"{name} must be positive definite") from None
    return np.diag(s).copy(), chol


def _quad_logdet(e: np.ndarray, var: np.ndarray, chol: np.ndarray | None) -> tuple[np.ndarray, float]:
    """Per-sample :math:`e_t' \\Sigma^{-1} e_t` and :math:`\\ln|\\Sigma|`."""
    if chol is None:
        return (e * e / var).sum(axis=1), float(np.log(var).sum())
    w = linalg.solve_triangular(chol, e.T, lower=True)
    return (w * w).sum(axis=0), float(2.0 * np.log(np.diag(chol)).sum())


def _scale_from_walks(walks: list, block: int, what: str) -> float:
    r"""The largest scale :math:`c` for which every walk :math:`c\,S` satisfies Wald's identity
    :math:`E[e^{c S_n}] \approx 1`: per walk (that of a wrong hypothesis against the true one, drifting down), the
    root :math:`h > 0` of :math:`\hat K(h) + \tfrac{h^2}{2} (\hat v_{lr} - \hat v) = 0`, with :math:`\hat K` the
    empirical cumulant generating function of one sample, :math:`\hat v` the sample variance and
    :math:`\hat v_{lr}` the long-run variance per sample (batch means over ``block`` samples); the smallest root."""
    scales = []
    for name, z in walks:
        n = z.shape[0] // block
        if n < 10:
            raise ValueError(f"{what}: {name} holds {n} blocks of {block} samples, at least 10 are needed to "
                             "estimate the long-run variance of the log-likelihood ratio; give longer held-out "
                             "records or a shorter block")
        m = float(z.mean())
        if not m < 0:
            raise ValueError(f"{what}: {name}: the log-likelihood ratio of the wrong hypothesis grows on average "
                             f"(mean {m:.4g} per sample) on the held-out records: the hypotheses do not separate "
                             "there, no scale makes the bounds hold")
        sums = z[: n * block].reshape(n, block).sum(axis=1)
        v_lr = float(((sums - m * block) ** 2).sum() / (n - 1) / block)
        extra = 0.5 * (v_lr - float(z.var()))
        log_n = np.log(z.shape[0])

        def f(h, z=z, extra=extra, log_n=log_n):
            return float(special.logsumexp(h * z) - log_n + h * h * extra)

        h0 = -2.0 * m / v_lr                                # the Gaussian walk's root
        lo, hi = 1e-6 * h0, h0
        while f(hi) <= 0:
            hi *= 2.0
            if hi > 1e6 * h0:                              # pragma: no cover - f grows at least quadratically
                raise ValueError(f"{what}: {name}: no root of the cumulant equation")
        while f(lo) >= 0 and lo > 1e-12 * h0:              # pragma: no cover - f(lo) ~ lo * m < 0
            lo *= 0.01
        scales.append(optimize.brentq(f, lo, hi, rtol=1e-10))
    return float(min(scales))


def _records(resid: Any, name: str) -> list:
    if isinstance(resid, (list, tuple)):
        if not resid:
            raise ValueError(f"{name} must hold at least one record")
        return list(resid)
    return [resid]


# ---------------------------------------------------------------------------------------------------- SPRT
class SPRT:
    r"""Residual-based sequential probability ratio test (Wald 1945; Kopsaftopoulos & Fassois 2015).

    The residuals :math:`e_t` of the healthy model are tested sample by sample: the cumulative log-likelihood
    ratio :math:`S_n = \sum_{t \le n} z_t` of the fault law (H1) against the healthy law (H0) is compared with
    Wald's bounds :math:`B < 0 < A` (:func:`wald_bounds`); the test stops at the first :math:`n` where
    :math:`S_n \ge A` (reject H0: fault) or :math:`S_n \le B` (accept H0).

    Parameters
    ----------
    alternative : {"variance", "mean", "model"}
        The fault hypothesis H1. ``"variance"``: the residual covariance is ``ratio`` times the healthy one
        (:math:`\sigma_1^2 = r \sigma_0^2` per channel, :math:`\Sigma_1 = r \Sigma_0` for vectors; the form of
        Kopsaftopoulos & Fassois). ``"mean"``: the residual mean shifts by ``shift`` healthy standard deviations in
        every channel. ``"model"``: H1 is a fault model whose residuals on the same samples are given to
        :meth:`test`; :math:`z_t` is the difference of the two models' Gaussian log-likelihoods.
    ratio : float
        Variance ratio :math:`r > 0`, :math:`r \ne 1`, of ``"variance"`` (default 2).
    shift : float or array_like
        Mean shift :math:`\delta \ne 0` in healthy standard deviations of ``"mean"``, one number or one per channel
        (default 1).
    alpha, beta : float
        Type I (false alarm) and type II (missed fault) error probabilities per decision, in (0, 1).
    restart : bool
        Monitoring form: the statistic restarts at 0 each time it crosses the lower bound (H0 accepted so far)
        and the test decides only at the first upper crossing (the alarm), like a CUSUM.

    Attributes
    ----------
    scale_ : float
        Factor applied to :math:`z_t` after :meth:`calibrate` (1 otherwise).

    Notes
    -----
    Per-sample log-likelihood ratio :math:`z_t = \ln f_1(e_t) - \ln f_0(e_t)` for Gaussian residuals with healthy
    covariance :math:`\Sigma_0` (``sigma``; a variance per channel treats the channels as independent), ``k``
    channels and :math:`Q_t = e_t' \Sigma_0^{-1} e_t`:

    * variance (Kopsaftopoulos & Fassois 2015, the residual variance form):
      :math:`z_t = \tfrac12 [(1 - 1/r)\, Q_t - k \ln r]`;
    * mean, :math:`\mu_1 = \delta \odot \sqrt{\mathrm{diag}\,\Sigma_0}`:
      :math:`z_t = \mu_1' \Sigma_0^{-1} e_t - \tfrac12 \mu_1' \Sigma_0^{-1} \mu_1`;
    * model: :math:`z_t = -\tfrac12[\ln|\Sigma_1| + e_{1t}' \Sigma_1^{-1} e_{1t}]
      + \tfrac12[\ln|\Sigma_0| + e_{0t}' \Sigma_0^{-1} e_{0t}]`.

    Wald's bounds give realised error probabilities :math:`\alpha' \le \alpha / (1 - \beta)` and
    :math:`\beta' \le \beta / (1 - \alpha)` when :math:`z_t` is the true log-likelihood ratio of independent
    samples. Residuals of a model estimated from real records are neither white nor exactly Gaussian, and the
    bounds may then fail in either direction: :meth:`calibrate` estimates a scale of :math:`z_t` that restores
    them on held-out records.

    Operating characteristic and ASN (Wald 1947, ch. 3-4): for a true law :math:`\theta` let :math:`h(\theta) \ne
    0` solve :math:`E_\theta[e^{h z}] = 1`; then :math:`P_\theta(\text{accept H0}) \approx
    L(\theta) = (e^{hA} - 1) / (e^{hA} - e^{hB})` and
    :math:`E_\theta[N] \approx (L B + (1 - L) A) / E_\theta[z]` (:math:`-AB / E_\theta[z^2]` where
    :math:`E_\theta[z] = 0`); :math:`h = 1` under H0 and :math:`h = -1` under H1. These neglect the overshoot of
    the bounds, so they underestimate :math:`E[N]` by about the mean overshoot over :math:`|E[z]|`: a few percent
    when the per-sample information is small against the bounds (a ratio near 1, a shift below about half a
    standard deviation, small alpha and beta), tens of percent for a large ratio or shift and loose error rates.

    References
    ----------
    Wald (1945), (1947); Kopsaftopoulos & Fassois (2015). See :mod:`tsfdi.detection.sequential`.

    Examples
    --------
    >>> res = tsfdi.AR(healthy, 8).fit()                                       # doctest: +SKIP
    >>> d = SPRT("variance", ratio=2.0).test(res.residuals(flight), sigma=res.sigma2)   # doctest: +SKIP
    >>> d.reject, d.decision_seconds                                           # doctest: +SKIP
    """

    def __init__(self, alternative: str = "variance", *, ratio: float | None = None, shift: Any = None,
                 alpha: float = 0.01, beta: float = 0.01, restart: bool = False) -> None:
        self.alternative = option(alternative, "alternative", ("variance", "mean", "model"))
        if self.alternative != "variance" and ratio is not None:
            raise ValueError(f"ratio is an option of alternative='variance', not {self.alternative!r}")
        if self.alternative != "mean" and shift is not None:
            raise ValueError(f"shift is an option of alternative='mean', not {self.alternative!r}")
        self.ratio = None
        self.shift = None
        if self.alternative == "variance":
            self.ratio = float_like(2.0 if ratio is None else ratio, "ratio", minimum=0.0, strict_min=True)
            if self.ratio == 1.0:
                raise ValueError("ratio must differ from 1 (H1 would be H0)")
        if self.alternative == "mean":
            sh = 1.0 if shift is None else shift
            if isinstance(sh, (str, bytes, bool, np.bool_)):
                raise TypeError(f"shift must be a number or one per channel, got {sh!r}")
            try:
                sh = np.asarray(sh, dtype=np.float64)
            except (TypeError, ValueError):
                raise TypeError(f"shift must be a number or one per channel, got {type(shift).__name__}") from None
            if sh.ndim > 1 or sh.size == 0 or not np.isfinite(sh).all() or not (sh != 0).any():
                raise ValueError(f"shift must be a finite non-zero number or one per channel, got {shift!r}")
            self.shift = float(sh) if sh.ndim == 0 else sh
        self.lower, self.upper = wald_bounds(alpha, beta)
        self.alpha, self.beta = float(alpha), float(beta)
        self.restart = boolean(restart, "restart")
        self.scale_ = 1.0

    def __repr__(self) -> str:
        opt = (f", ratio={self.ratio:g}" if self.alternative == "variance" else
               f", shift={self.shift!r}" if self.alternative == "mean" else "")
        cal = f", scale_={self.scale_:.4g}" if self.scale_ != 1.0 else ""
        return (f"SPRT({self.alternative!r}{opt}, alpha={self.alpha:g}, beta={self.beta:g}, "
                f"restart={self.restart}{cal})")

    # -------------------------------------------------------------------------------------------- LLR
    def _shift(self, k: int) -> np.ndarray:
        sh = np.asarray(self.shift, dtype=np.float64)
        if sh.ndim == 0:
            return np.full(k, float(sh))
        if sh.shape != (k,):
            raise ValueError(f"shift has {sh.shape[0]} values but resid has {k} channel(s)")
        return sh

    def _llr(self, e: np.ndarray, sigma: Any, fault: np.ndarray | None, fault_sigma: Any) -> np.ndarray:
        """Unscaled :math:`z_t` of a validated (n, k) residual array."""
        k = e.shape[1]
        var, chol = _covariance(sigma, k, "sigma")
        if self.alternative == "variance":
            q, _ = _quad_logdet(e, var, chol)
            r = self.ratio
            return 0.5 * ((1.0 - 1.0 / r) * q - k * np.log(r))
        if self.alternative == "mean":
            mu = self._shift(k) * np.sqrt(var)
            if chol is None:
                w = mu / var
            else:
                w = linalg.cho_solve((chol, True), mu)
            return e @ w - 0.5 * float(mu @ w)
        q0, ld0 = _quad_logdet(e, var, chol)
        var1, chol1 = _covariance(fault_sigma, fault.shape[1], "fault_sigma")
        q1, ld1 = _quad_logdet(fault, var1, chol1)
        return 0.5 * ((ld0 - ld1) + (q0 - q1) + (k - fault.shape[1]) * _LOG2PI)

    def _inputs(self, resid: Any, fault_residuals: Any):
        sig = as_signal(resid, "resid", allow_constant=True)
        fault = None
        if self.alternative == "model":
            if fault_residuals is None:
                raise TypeError("fault_residuals is required with alternative='model': the fault model's residuals "
                                "on the same samples as resid")
            fs = as_signal(fault_residuals, "fault_residuals", allow_constant=True)
            if fs.nobs != sig.nobs:
                raise ValueError(f"fault_residuals has {fs.nobs} samples but resid has {sig.nobs}: give both models' "
                                 "residuals on the same samples (cut the longer one where the other starts)")
            if sig.index is not None and fs.index is not None and not sig.index.equals(fs.index):
                raise ValueError("fault_residuals and resid have different time indexes: give both on the same "
                                 "samples")
            fault = fs.values
        elif fault_residuals is not None:
            raise ValueError(f"fault_residuals is an input of alternative='model', not {self.alternative!r}")
        return sig, fault

    def loglik_ratio(self, resid: Any, sigma: Any = None, *, fault_residuals: Any = None,
                     fault_sigma: Any = None) -> np.ndarray:
        r"""Per-sample log-likelihood ratio :math:`z_t` of H1 against H0 (times ``scale_``).

        Parameters
        ----------
        resid : array_like, Series, DataFrame or DataArray
            Residuals of the healthy model, time on axis 0, one column per channel.
        sigma : float, array_like (k,) or (k, k)
            Healthy residual variance: a number, one per channel (channels independent) or a covariance matrix
            (a fitted AR's ``sigma2``, a VAR's ``sigma``).
        fault_residuals : array_like, optional
            ``alternative="model"``: the fault model's residuals on the same samples.
        fault_sigma : float, array_like (k,) or (k, k), optional
            ``alternative="model"``: the fault model's residual variance / covariance.

        Returns
        -------
        ndarray, shape (nobs,)
            :math:`z_t` (see the class Notes).
        """
        sig, fault = self._inputs(resid, fault_residuals)
        return self.scale_ * self._llr(sig.values, sigma, fault, fault_sigma)

    def test(self, resid: Any, sigma: Any = None, *, fault_residuals: Any = None, fault_sigma: Any = None,
             fs: float | None = None) -> SequentialDecision:
        """Run the sequential test over one residual record.

        Parameters
        ----------
        resid, sigma, fault_residuals, fault_sigma :
            As in :meth:`loglik_ratio`.
        fs : float, optional
            Sampling frequency in Hz for ``decision_seconds`` when ``resid`` carries no time index.

        Returns
        -------
        SequentialDecision
            The first crossing of Wald's bounds (see :class:`SequentialDecision`).
        """
        sig, fault = self._inputs(resid, fault_residuals)
        rate = sampling_frequency(sig, fs, "resid")
        z = self.scale_ * self._llr(sig.values, sigma, fault, fault_sigma)
        path, first, side, restarts = _sprt_paths(z[None, :], np.zeros(1), self.lower, self.upper, self.restart)
        t = int(first[0])
        n = t + 1 if t >= 0 else -1
        dt = None if rate is None else 1.0 / rate
        return SequentialDecision(
            reject=bool(side[0] > 0), decided=t >= 0, decision_time=n, decision_seconds=_seconds(n, dt),
            statistic=path[0], bounds=(self.lower, self.upper), alpha=self.alpha, beta=self.beta,
            restarts=int(restarts[0]), nobs=sig.nobs, alternative=self.alternative, scale=self.scale_,
            channels=tuple(str(c) for c in sig.channels), time=None if dt is None else np.arange(sig.nobs) * dt,
            details={"ratio": self.ratio, "shift": self.shift, "restart": self.restart})

    # -------------------------------------------------------------------------------------------- calibration
    def calibrate(self, resid: Any, sigma: Any = None, *, fault_residuals: Any = None, fault_sigma: Any = None,
                  block: int = 64) -> "SPRT":
        r"""Estimate the scale ``scale_`` of :math:`z_t` from held-out healthy residuals so that Wald's bounds hold.

        Parameters
        ----------
        resid : array_like or list of array_like
            Held-out residuals of healthy records (records the model was not fitted on, e.g.
            ``results.model.held_out_residuals()``), one record or a list.
        sigma, fault_residuals, fault_sigma :
            As in :meth:`loglik_ratio` (``fault_residuals``: one per record of ``resid``).
        block : int
            Samples per batch of the long-run variance estimate (much longer than the correlation time of
            :math:`z_t`; at least 10 batches are needed).

        Returns
        -------
        SPRT
            This test, with ``scale_`` set.

        Notes
        -----
        A true log-likelihood ratio of independent samples satisfies Wald's identity: :math:`E_0[e^{S_n}] = 1`
        under H0 and :math:`E_1[e^{-S_n}] = 1` under H1, which is what makes the bounds' error rates hold. When the
        residuals are autocorrelated or not Gaussian (a model estimated from real records) the walk :math:`S_n`
        spreads faster or slower than that and the rates fail. The estimator rescales :math:`z_t` by Wald's
        :math:`h` of the realised walks, :math:`c = \min(h_0, h_1)`, where :math:`h > 0` solves

        .. math:: \hat K(h) + \tfrac{h^2}{2} (\hat v_{lr} - \hat v) = 0

        for the walk of the wrong hypothesis against the true one (:math:`z_t` under H0, :math:`-z_t` under H1):
        :math:`\hat K(h) = \ln \overline{e^{h z_t}}` is the empirical cumulant generating function of one
        sample (the marginal law: non-Gaussian tails, a wrong variance), :math:`\hat v` the sample variance of
        :math:`z_t` and :math:`\hat v_{lr}` its long-run variance per sample (batch means over ``block`` samples),
        whose excess adds the autocorrelation to second order. Then :math:`E[e^{c S_n}] \approx 1` under the
        worse hypothesis and both error rates hold, at the price of a longer decision time for the other. On white
        residuals of the assumed law :math:`c \approx 1`; on AR(1) residuals with coefficient 0.6 tested as white,
        about 0.4 (variance) and 0.25 (mean). Under H1 the residuals are the healthy ones transformed by the fault
        hypothesis: times :math:`\sqrt r` (variance) or plus the shift (mean), so that the healthy records give
        both walks. With ``alternative="model"`` only the H0 walk is available from healthy records
        (:math:`c = h_0`); for both sides use :func:`msprt_scale` on records of both states.
        """
        block = int_like(block, "block", minimum=1)
        recs = _records(resid, "resid")
        faults = [None] * len(recs) if fault_residuals is None else _records(fault_residuals, "fault_residuals")
        if len(faults) != len(recs):
            raise ValueError(f"fault_residuals has {len(faults)} record(s) but resid has {len(recs)}")
        z0, z1 = [], []
        for i, (r, f) in enumerate(zip(recs, faults)):
            sig, fault = self._inputs(r, f)
            e = sig.values
            z0.append(self._llr(e, sigma, fault, fault_sigma))
            if self.alternative == "variance":
                z1.append(self._llr(e * np.sqrt(self.ratio), sigma, None, None))
            elif self.alternative == "mean":
                var, _ = _covariance(sigma, e.shape[1], "sigma")
                z1.append(self._llr(e + self._shift(e.shape[1]) * np.sqrt(var), sigma, None, None))
        walks = [("H0", np.concatenate(z0))]
        if z1:
            walks.append(("H1", -np.concatenate(z1)))
        self.scale_ = _scale_from_walks(walks, block, "SPRT.calibrate")
        return self

    # -------------------------------------------------------------------------------------------- theory
    def _law(self, theta: np.ndarray, nchan: int) -> tuple:
        """Per-sample law of unscaled z under the true parameter ``theta`` (variance ratio or shift)."""
        k = nchan
        if self.alternative == "variance":
            r = self.ratio
            a = 0.5 * (1.0 - 1.0 / r)
            return "variance", a, 0.5 * k * np.log(r)
        if self.alternative == "mean":
            d = self._shift(k)
            return "mean", float(d @ d), float(d.sum())
        raise ValueError("oc and asn have closed forms for alternative='variance' or 'mean' only; use "
                         "monte_carlo for a fault model")

    def _theta(self, theta: Any, name: str = "theta") -> np.ndarray:
        if isinstance(theta, (str, bytes, bool, np.bool_)):
            raise TypeError(f"{name} must be numbers, got {theta!r}")
        try:
            t = np.asarray(theta, dtype=np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be numbers, got {type(theta).__name__}") from None
        if not np.isfinite(t).all():
            raise ValueError(f"{name} must be finite")
        if self.alternative == "variance" and not (t > 0).all():
            raise ValueError(f"{name} (true variance ratios) must be > 0")
        return t

    def _h_moments(self, theta: np.ndarray, nchan: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Wald's h, E[z] and E[z^2] of the scaled z per true ``theta``."""
        kind, a, b = self._law(theta, nchan)
        c = self.scale_
        th = theta.ravel()
        h = np.empty(th.shape)
        if kind == "variance":
            # z = c (a Q - b), Q ~ theta chi2(k): ln E exp(h z) = -h c b - (k/2) ln(1 - 2 h c a theta), convex in h,
            # 0 at h = 0 with slope E z; the other root lies on the side of -E z, before the pole 1 / (2 c a theta)
            k = nchan
            mean = c * (a * k * th - b)
            var = c * c * 2.0 * a * a * k * th ** 2
            m2 = var + mean ** 2
            for i, t in enumerate(th):
                def g(x, t=t):
                    return -x * c * b - 0.5 * k * np.log1p(-2.0 * x * c * a * t)
                if mean[i] == 0.0:
                    h[i] = 0.0
                    continue
                near = -2.0 * mean[i] / var[i] * 1e-6          # a point of g < 0 next to 0 (Gaussian h / 1e6)
                pole = 1.0 / (2.0 * c * a * t)
                far = pole * (1.0 - 1e-12) if pole * near > 0 else _grow(g, near * 1e6)
                h[i] = optimize.brentq(g, min(near, far), max(near, far), xtol=1e-300, rtol=1e-13, maxiter=500)
        else:
            dd, dsum = a, b
            # standardized shift theta per channel: z = c (d'x - d'd/2), x ~ N(theta, I)
            mean = c * (th * dsum - 0.5 * dd)
            var = c * c * dd
            h = -2.0 * mean / var
            m2 = var + mean ** 2
        return h.reshape(theta.shape), mean.reshape(theta.shape), m2.reshape(theta.shape)

    def oc(self, theta: Any, *, nchan: int = 1) -> Any:
        r"""Operating characteristic: Wald's approximation of P(accept H0) under the true parameter ``theta``.

        Parameters
        ----------
        theta : float or array_like
            True variance ratio to the healthy variance (``"variance"``: 1 is H0, ``ratio`` is H1) or true mean
            shift in healthy standard deviations, the same in every channel (``"mean"``: 0 is H0, ``shift`` H1).
        nchan : int
            Number of residual channels (independent, or with the covariance of ``sigma`` for ``"variance"``).

        Returns
        -------
        float or ndarray (shape of ``theta``)
            :math:`L(\theta) = (e^{hA} - 1)/(e^{hA} - e^{hB})` with :math:`h(\theta) \ne 0` solving
            :math:`E_\theta[e^{h z}] = 1` (:math:`A/(A - B)` where :math:`E_\theta z = 0`); Wald (1947), ch. 3.
        """
        nchan = int_like(nchan, "nchan", minimum=1)
        th = self._theta(theta)
        h, _, _ = self._h_moments(th, nchan)
        A, B = self.upper, self.lower
        with np.errstate(over="ignore", invalid="ignore"):
            # (e^{hA} - 1)/(e^{hA} - e^{hB}), written to avoid overflow for large |h|
            num = np.where(h > 0, -np.expm1(-h * A), np.expm1(h * A))
            den = np.where(h > 0, 1.0 - np.exp(h * (B - A)), np.exp(h * A) - np.exp(h * B))
            out = np.where(h == 0, A / (A - B), num / den)
        return float(out) if np.ndim(out) == 0 else out

    def asn(self, theta: Any, *, nchan: int = 1) -> Any:
        r"""Average sample number: Wald's approximation of :math:`E_\theta[N]` (samples to decide).

        Parameters
        ----------
        theta, nchan :
            As in :meth:`oc`. ``asn(1.0)`` / ``asn(ratio)`` (variance) and ``asn(0.0)`` / ``asn(shift)`` (mean) are
            :math:`E_0[N] = ((1-\alpha) B + \alpha A) / E_0[z]` and :math:`E_1[N] = (\beta B + (1-\beta) A) / E_1[z]`.

        Returns
        -------
        float or ndarray (shape of ``theta``)
            :math:`(L B + (1 - L) A) / E_\theta[z]`, or :math:`-AB / E_\theta[z^2]` where :math:`E_\theta z = 0`
            (Wald 1947, ch. 4). It neglects the overshoot of the bounds (see the class Notes); with
            ``restart=True`` it is the length of one cycle, not the alarm time.
        """
        nchan = int_like(nchan, "nchan", minimum=1)
        th = self._theta(theta)
        h, mean, m2 = self._h_moments(th, nchan)
        L = np.asarray(self.oc(th, nchan=nchan))
        A, B = self.upper, self.lower
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.where(h == 0, -A * B / m2, (L * B + (1 - L) * A) / mean)
        return float(out) if np.ndim(out) == 0 else out

    def monte_carlo(self, theta: Any, *, nchan: int = 1, n_rep: int = 1000, max_samples: int = 100_000,
                    rng: Any = None) -> pd.DataFrame:
        """Realised acceptance rate and decision times on simulated white Gaussian residuals.

        Parameters
        ----------
        theta, nchan :
            As in :meth:`oc` (the residuals are drawn standardised, channels independent).
        n_rep : int
            Records per ``theta``.
        max_samples : int
            Longest record: a record undecided after it counts as undecided.
        rng : None, int or numpy.random.Generator

        Returns
        -------
        pandas.DataFrame
            One row per ``theta``: ``accept`` (fraction accepting H0), ``reject``, ``undecided``, ``mean_n`` and
            ``std_n`` (decision times of the decided records), and the theory ``oc`` and ``asn`` (variance / mean).
        """
        if self.alternative == "model":
            raise ValueError("monte_carlo simulates the variance and mean alternatives; for a fault model simulate "
                             "its records and call test")
        nchan = int_like(nchan, "nchan", minimum=1)
        n_rep = int_like(n_rep, "n_rep", minimum=1)
        max_samples = int_like(max_samples, "max_samples", minimum=1)
        gen = check_rng(rng)
        th = np.atleast_1d(self._theta(theta))
        if th.ndim != 1:
            raise ValueError(f"theta must be a number or a 1-D array, got shape {th.shape}")
        chunk = max(1, min(1024, MAX_VALUES // (16 * n_rep * nchan)))
        rows = []
        sigma = np.ones(nchan)
        for t in th:
            s = np.zeros(n_rep)
            n_dec = np.full(n_rep, -1)
            side = np.zeros(n_rep, dtype=np.int8)
            active = np.arange(n_rep)
            done = 0
            while active.size and done < max_samples:
                m = min(chunk, max_samples - done)
                x = gen.standard_normal((active.size, m, nchan))
                if self.alternative == "variance":
                    x *= np.sqrt(t)
                else:
                    x += t
                z = self.scale_ * self._llr(x.reshape(-1, nchan), sigma, None, None).reshape(active.size, m)
                path, first, sd, _ = _sprt_paths(z, s[active], self.lower, self.upper, self.restart)
                hit = first >= 0
                n_dec[active[hit]] = done + first[hit] + 1
                side[active[hit]] = sd[hit]
                s[active] = path[:, -1]
                active = active[~hit]
                done += m
            dec = n_dec >= 0
            rows.append({"theta": float(t), "accept": float(np.mean(side < 0)), "reject": float(np.mean(side > 0)),
                         "undecided": float(np.mean(~dec)),
                         "mean_n": float(n_dec[dec].mean()) if dec.any() else float("nan"),
                         "std_n": float(n_dec[dec].std(ddof=1)) if dec.sum() > 1 else float("nan"),
                         "oc": self.oc(t, nchan=nchan), "asn": self.asn(t, nchan=nchan)})
        return pd.DataFrame(rows).set_index("theta")


def _grow(f, x: float) -> float:
    """A point beyond the root of ``f`` on the side of ``x`` (``f`` < 0 near 0 on that side, growing to +inf)."""
    for _ in range(200):
        if f(x) > 0:
            return x
        x *= 2.0
    raise ValueError("no root of Wald's equation E[exp(h z)] = 1 found")  # pragma: no cover


# ---------------------------------------------------------------------------------------------------- MSPRT
def msprt(loglik: Any, *, alpha: float = 0.01, start: int = 0, restart: bool = False, scale: float = 1.0,
          models: Any = None, fs: float | None = None, state: Any = None) -> SequentialIdentification:
    r"""Multi-hypothesis sequential identification (Armitage 1950; Baum & Veeravalli 1994).

    Parameters
    ----------
    loglik : array_like, DataFrame or DataArray, shape (nobs, M)
        Per-sample log-likelihood of each of ``M >= 2`` candidate models (e.g. each model's Gaussian residual
        log-likelihood on the same samples); the columns name the models.
    alpha : float
        Probability of a wrong decision allowed under each candidate model, in (0, 1).
    start : int
        First sample accumulated (earlier samples are ignored: e.g. the lags of the longest model).
    restart : bool
        CUSUM form for monitoring: every pairwise statistic :math:`W_{jk}` restarts at 0 when it falls below 0, so
        that evidence gathered before a change does not delay the decision after it.
    scale : float
        Factor applied to the log-likelihoods (1: exact models; :func:`msprt_scale` for estimated ones).
    models : sequence of str, optional
        Model names (default: the columns of ``loglik``, else ``m0, m1, ...``).
    fs : float, optional
        Sampling frequency in Hz for ``decision_seconds`` when ``loglik`` carries no time index.
    state : array_like, shape (M, M), optional
        With ``restart=True``: the pairwise statistics :math:`W_{jk}` to continue from (the ``state`` of the result
        of the previous samples, non-negative), so that a stream fed in chunks gives the decision of the whole
        record; default zeros.

    Returns
    -------
    SequentialIdentification

    Notes
    -----
    With :math:`S_j(n) = c \sum_{t = start}^{n} \ell_j(t)` (:math:`c` = ``scale``), model :math:`j` is decided at
    the first :math:`n` where :math:`S_j(n) - S_k(n) \ge a` for every :math:`k \ne j`, with

    .. math:: a = \ln((M - 1) / \alpha).

    Why this bound: under the true model :math:`i`, :math:`\exp(S_k - S_i)` is a non-negative martingale of mean 1
    (a likelihood ratio), so by Ville's (Doob's maximal) inequality :math:`P_i(\sup_n S_k - S_i \ge a) \le e^{-a} =
    \alpha / (M - 1)`; a wrong decision :math:`k \ne i` needs :math:`S_k - S_i \ge a` at some time, hence
    :math:`P_i(\text{wrong decision}) \le (M - 1) \alpha / (M - 1) = \alpha` for every :math:`i`, whatever the
    overshoot and whether or not the record ends first. It holds when the log-likelihoods are those of the true
    laws of the samples (independent given the model); :func:`msprt_scale` corrects estimated models.

    The rule is computed in :math:`O(n M)`: cumulative sums, the two largest :math:`S` per sample, and a vectorised
    first crossing of the margin between them. With ``restart=True`` the pairwise CUSUMs are computed by a compiled
    loop in :math:`O(n M^2)`; the bound then sets the mean time between wrong decisions (of order
    :math:`e^a`) instead of an error probability.
    """
    sig = as_signal(loglik, "loglik", allow_constant=True)
    M = sig.nchan
    if M < 2:
        raise ValueError(f"loglik must have one column per candidate model, at least 2, got {M}")
    alpha = probability(alpha, "alpha")
    start = int_like(start, "start", minimum=0, maximum=sig.nobs - 1)
    restart = boolean(restart, "restart")
    scale = float_like(scale, "scale", minimum=0.0, strict_min=True)
    names = tuple(str(c) for c in sig.channels) if sig.named else tuple(f"m{j}" for j in range(M))
    if models is not None:
        if isinstance(models, (str, bytes)) or len(models) != M:
            raise ValueError(f"models must hold one name per column of loglik ({M}), got {models!r}")
        names = tuple(str(m) for m in models)
    rate = sampling_frequency(sig, fs, "loglik")
    if state is not None:
        if not restart:
            raise ValueError("state is for restart=True (the pairwise CUSUMs of a stream)")
        state = np.array(state, dtype=np.float64)
        if state.shape != (M, M) or not np.all(np.isfinite(state)) or (state < 0).any():
            raise ValueError(f"state must be the finite non-negative ({M}, {M}) pairwise statistics of a previous "
                             f"msprt result, got shape {state.shape}")
    bound = float(np.log(M - 1) - np.log(alpha))
    ll = sig.values[start:]
    if restart:
        w = np.zeros((M, M)) if state is None else state
        dom, first = _pairwise_cusum(np.ascontiguousarray(ll), w, scale, bound)
        label = int(np.argmax(dom[first])) if first >= 0 else -1
    else:
        s = np.cumsum(ll, axis=0)
        if scale != 1.0:
            s *= scale
        top2 = np.partition(s, M - 2, axis=1)[:, M - 2:]
        best, second = top2.max(axis=1), top2.min(axis=1)
        margin = best - second
        hit = margin >= bound
        first = int(np.argmax(hit)) if hit.any() else -1
        label = int(np.argmax(s[first])) if first >= 0 else -1
        dom = s - best[:, None]
        top = s >= best[:, None]
        dom[top] = margin[np.nonzero(top)[0]]
        w = s[-1][:, None] - s[-1][None, :]
    n = first + 1 if first >= 0 else -1
    dt = None if rate is None else 1.0 / rate
    return SequentialIdentification(label=label, decision_time=n, decision_seconds=_seconds(n, dt), statistic=dom,
                                    bound=bound, alpha=alpha, models=names, start=start, scale=scale,
                                    restart=restart, time=None if dt is None else np.arange(ll.shape[0]) * dt,
                                    state=w)


def msprt_scale(loglik: Any, labels: Any, *, block: int = 64) -> float:
    r"""Scale of the log-likelihoods that makes :func:`msprt`'s bound hold for estimated models.

    Parameters
    ----------
    loglik : list of array_like, each shape (nobs_r, M)
        Per-sample log-likelihoods of the ``M`` candidate models on held-out records (records the models were not
        fitted on), one array per record.
    labels : sequence of int
        True model index of each record.
    block : int
        Samples per batch of the long-run variance estimate (at least 10 batches per true model).

    Returns
    -------
    float
        :math:`c = \min_{i, k \ne i} h_{ik}`, Wald's :math:`h` of the walk :math:`S_k - S_i` on the records of
        model :math:`i` (the root of the empirical cumulant equation of :meth:`SPRT.calibrate`); pass it as
        ``msprt(..., scale=c)``.

    Notes
    -----
    For exact models :math:`\exp(S_k - S_i)` is a martingale of mean 1 under model :math:`i`, which gives the
    bound of :func:`msprt`. Estimated models give log-likelihoods that are autocorrelated, not Gaussian or of the
    wrong variance: the walk spreads faster (or slower) than its drift implies and the bound's error rate no longer
    holds. Scaling every log-likelihood by :math:`c` restores :math:`E_i e^{c (S_k - S_i)} \approx 1` for the worst
    pair, hence the bound for every pair (the estimator is described in :meth:`SPRT.calibrate`; the long-run
    variance over blocks of ``block`` samples keeps the autocorrelation: choose the block well beyond the
    correlation time of the log-likelihoods).
    """
    block = int_like(block, "block", minimum=1)
    recs = _records(loglik, "loglik")
    if isinstance(labels, (str, bytes)):
        raise TypeError(f"labels must be one model index per record, got {labels!r}")
    lab = [int_like(v, "labels", minimum=0) for v in np.ravel(np.asarray(labels, dtype=object))]
    if len(lab) != len(recs):
        raise ValueError(f"labels has {len(lab)} entries but loglik has {len(recs)} record(s)")
    arrs = [as_signal(r, f"loglik[{i}]", allow_constant=True).values for i, r in enumerate(recs)]
    M = arrs[0].shape[1]
    if M < 2 or any(a.shape[1] != M for a in arrs):
        raise ValueError(f"loglik: every record must have the same number (>= 2) of model columns, got "
                         f"{[a.shape[1] for a in arrs]}")
    bad = [v for v in lab if v >= M]
    if bad:
        raise ValueError(f"labels must be model indexes below {M}, got {bad[0]}")
    walks = []
    for i in sorted(set(lab)):
        rows = [a for a, v in zip(arrs, lab) if v == i]
        for k in range(M):
            if k != i:
                # one walk per pair; records joined at block boundaries (the tail of each record is left out)
                parts = [(a[:, k] - a[:, i])[: (a.shape[0] // block) * block] for a in rows]
                walks.append((f"true model {i} against model {k}", np.concatenate(parts)))
    return _scale_from_walks(walks, block, "msprt_scale")


# ---------------------------------------------------------------------------------------------------- record effect


def _running_summaries(e: np.ndarray, lags: int, first: int) -> np.ndarray:
    """Running record summaries of a residual record (n, k) over samples ``0..t`` for ``t >= first``: per channel
    the mean, the log RMS and the Fisher z of the autocorrelation at lags ``1..lags`` (running mean removed);
    shape (n - first, (2 + lags) k)."""
    n = e.shape[0]
    cnt = np.arange(1, n + 1, dtype=np.float64)[first:, None]
    mean = np.cumsum(e, axis=0)[first:] / cnt
    sq = np.cumsum(e * e, axis=0)[first:] / cnt
    with np.errstate(divide="ignore", invalid="ignore"):
        out = [mean, 0.5 * np.log(sq)]
        var = sq - mean * mean
        for j in range(1, lags + 1):
            prod = np.vstack([np.zeros((j, e.shape[1])), np.cumsum(e[j:] * e[:-j], axis=0)])[first:] / cnt
            out.append(np.arctanh(np.clip((prod - mean * mean) / var, -0.999999, 0.999999)))
    return np.hstack(out)


def _sample_series(e: np.ndarray, lags: int) -> np.ndarray:
    """Per-sample series whose long-run covariance over ``n`` samples, divided by ``n``, is that of the running
    summaries of :func:`_running_summaries` (delta method), on samples ``lags..n-1``, centred on the record."""
    c = e - e.mean(axis=0)
    v = np.mean(c * c, axis=0)
    sq = np.mean(e * e, axis=0)
    out = [e[lags:], (e * e / (2.0 * sq))[lags:]]
    n = e.shape[0]
    for j in range(1, lags + 1):
        r = np.sum(c[j:] * c[:-j], axis=0) / (n * v)
        x = (c[j:] * c[:-j] - r * c[j:] * c[j:]) / v / (1.0 - r * r)
        out.append(x[lags - j:])
    z = np.hstack(out)
    return z - z.mean(axis=0)           # about the record's own summaries: the record effect is not within noise


def _residual_records(recs: Any, name: str, k: int | None) -> list:
    if isinstance(recs, (str, bytes)) or not isinstance(recs, (list, tuple)) or not recs:
        raise TypeError(f"{name} must be a non-empty list of residual records (arrays of shape (nobs, k)), got "
                        f"{type(recs).__name__}")
    out = []
    for i, r in enumerate(recs):
        v = as_signal(r, f"{name}[{i}]", allow_constant=True).values
        if k is not None and v.shape[1] != k:
            raise ValueError(f"{name}[{i}] has {v.shape[1]} channel(s), the other records {k}")
        k = v.shape[1]
        out.append(v)
    return out


@dataclass(frozen=True)
class RecordEffect:
    r"""Between-record law of every candidate model's residual summaries (fitted by :func:`record_effect`); its
    :meth:`loglik` is the per-sample input of :func:`msprt` for records that differ from each other more than their
    within-record noise says (trims, residual scales).

    Attributes
    ----------
    models : tuple of str
        Candidate model names, in column order.
    center : ndarray, shape (M, q)
        Mean of the record summaries of each model's residuals over its held-out records (named by ``summaries``;
        ``q = (2 + lags) k`` when every summary is kept).
    between : ndarray, shape (M, q, q)
        Scale matrix of the predictive t law of a new record's summaries around ``center``: the between-record
        covariance :math:`S` pooled over the models, times :math:`1 + 1/R_j` (the uncertainty of the centre) and
        :math:`\nu / (\nu - q + 1)` (that of :math:`S`, estimated with :math:`\nu` degrees of freedom).
    within : ndarray, shape (M, q, q)
        Long-run covariance per sample of the summaries' per-sample series on each model's held-out records: a
        running summary over ``n`` samples has within-record covariance ``within / n``.
    df : ndarray, shape (M,)
        Degrees of freedom of the predictive multivariate t law, :math:`\sum_j (R_j - 1) - q + 1`.
    records : tuple of int
        Held-out records per model (:math:`R_j`).
    min_samples : int
        Samples in the first running summary used; the increments before it are 0.
    summaries : tuple of str
        Names of the ``q`` summaries kept (all by default): ``"mean[yi]"``, ``"log_scale[yi]"`` and
        ``"acf<j>[yi]"`` per channel ``i``.
    lags : int
        Residual autocorrelation lags among the summaries.
    nchan : int, optional
        Channels of the residual records (default: every summary kept, ``q / (2 + lags)``).
    """

    models: tuple
    center: np.ndarray
    between: np.ndarray
    within: np.ndarray
    df: np.ndarray
    records: tuple
    min_samples: int
    summaries: tuple
    lags: int = 0
    nchan: int | None = None

    def __repr__(self) -> str:
        return (f"RecordEffect(models={len(self.models)}, summaries={len(self.summaries)}, records={self.records}, "
                f"min_samples={self.min_samples})")

    def loglik(self, resid: Any) -> np.ndarray:
        r"""Per-sample increments of each model's record-level predictive log-likelihood, the input of :func:`msprt`.

        Parameters
        ----------
        resid : sequence or mapping of M array_like, each shape (nobs, k)
            Each candidate model's residuals on the same ``nobs`` samples of one record (in the order of
            ``models``; a mapping is read by model name).

        Returns
        -------
        ndarray, shape (nobs, M)
            Row ``t``: :math:`L_j(t) - L_j(t-1)`, with :math:`L_j(t)` the log density of the running summaries of
            model ``j``'s residuals over samples ``0..t`` under model ``j``'s predictive law (rows before
            ``min_samples - 1`` are 0): the cumulative sum of a column is :math:`L_j(t)`.

        Raises
        ------
        ValueError
            Not one residual array per model, arrays of different lengths or channel counts, non-finite residuals,
            or a channel whose residuals are zero (a log RMS of minus infinity).

        Notes
        -----
        The running summaries :math:`f(n)` (per channel: the mean, the log RMS, the Fisher z of the
        autocorrelations, over the first :math:`n` samples) of model :math:`j`'s residuals are given the law

        .. math:: f(n) = c_j + (B_j + W_j / n)^{1/2}\, T, \qquad T \sim t_{df_j}(0, I_q)

        (``center``, ``between``, ``within``, ``df``): a record effect drawn from the between-record spread plus
        the within-record noise of a running summary, whose long-run covariance keeps autocorrelated residuals from
        counting as independent evidence. As :math:`n` grows the within part vanishes and :math:`L_j` settles at
        the log density of the record's summaries: the evidence saturates at what record-level summaries can
        separate, where the per-sample Gaussian log-likelihood of :meth:`tsfdi.windows.ResidualWindows.loglik`
        grows with every sample and makes :func:`msprt` decide early and wrongly when records of one state differ.
        :math:`L_j(n) - L_k(n)` is the log-likelihood ratio of the summaries at each fixed :math:`n`, not a
        martingale in :math:`n`, so the bound of :func:`msprt` is not guaranteed by Ville's inequality; its error
        rate is checked by Monte Carlo (``tests/detection/test_sequential_mc.py``) and on CrazyPAD
        (``benchmarks/sprt.py``).
        """
        M = len(self.models)
        k = self.center.shape[1] // (2 + self.lags) if self.nchan is None else self.nchan
        keep = [_summary_names(k, self.lags).index(s) for s in self.summaries]
        arrs = _per_model_residuals(resid, self.models, k)
        n = arrs[0].shape[0]
        cum = np.zeros((n, M))
        t0 = self.min_samples - 1
        if n > t0:
            cnt = np.arange(1, n + 1, dtype=np.float64)[t0:, None]
            q = self.center.shape[1]
            rows = max(1, MAX_VALUES // (8 * q * q))     # the (rows, q, q) covariances of one chunk stay bounded
            for j, e in enumerate(arrs):
                f = _running_summaries(e, self.lags, t0)[:, keep] - self.center[j]
                nu = self.df[j]
                const = special.gammaln(0.5 * (nu + q)) - special.gammaln(0.5 * nu) - 0.5 * q * np.log(nu * np.pi)
                for a in range(0, f.shape[0], rows):
                    b = min(a + rows, f.shape[0])
                    chol = np.linalg.cholesky(self.between[j] + self.within[j] / cnt[a:b, :, None])
                    d = np.linalg.solve(chol, f[a:b, :, None])[:, :, 0]
                    cum[t0 + a:t0 + b, j] = (const - np.log(np.diagonal(chol, axis1=1, axis2=2)).sum(axis=1)
                                             - 0.5 * (nu + q) * np.log1p(np.einsum("ij,ij->i", d, d) / nu))
                if not np.isfinite(cum[t0:, j]).all():
                    raise ValueError(f"resid[{self.models[j]!r}]: a channel's residuals are zero over the first "
                                     f"{int(np.argmin(np.isfinite(cum[t0:, j]))) + t0 + 1} samples (log RMS not "
                                     "finite)")
        return np.diff(cum, axis=0, prepend=0.0)



def _per_model_residuals(resid, models, nchan: int) -> list[np.ndarray]:
    """``resid`` (one residual array per model, a list in ``models``' order or a mapping by name) as a list of
    ``(n, nchan)`` float arrays on the same samples; a ``ValueError`` naming the entry otherwise."""
    M = len(models)
    if isinstance(resid, Mapping):
        missing = [m for m in models if m not in resid]
        if missing:
            raise ValueError(f"resid has no entry for the model {missing[0]!r}")
        resid = [resid[m] for m in models]
    if isinstance(resid, (str, bytes)) or not isinstance(resid, (list, tuple)) or len(resid) != M:
        raise ValueError(f"resid must hold one residual array per model ({M}), got "
                         f"{len(resid) if isinstance(resid, (list, tuple)) else type(resid).__name__}")
    arrs = []
    for j, r in enumerate(resid):
        v = as_signal(r, f"resid[{models[j]!r}]", allow_constant=True).values
        if v.shape[1] != nchan:
            raise ValueError(f"resid[{models[j]!r}] has {v.shape[1]} channel(s), the law was fitted on {nchan}")
        if arrs and v.shape[0] != arrs[0].shape[0]:
            raise ValueError(f"resid[{models[j]!r}] has {v.shape[0]} samples, resid[{models[0]!r}] "
                             f"{arrs[0].shape[0]}: give every model's residuals on the same samples")
        arrs.append(v)
    return arrs

def _summary_names(k: int, lags: int) -> list:
    """Names of the running summaries of :func:`_running_summaries`, in its column order."""
    return [f"{s}[y{c}]" for s in ("mean", "log_scale", *(f"acf{j}" for j in range(1, lags + 1))) for c in range(k)]


def _kept_summaries(summaries: Any, k: int, lags: int) -> tuple[list, list, list]:
    """The summary names of ``k``-channel records with ``lags``, the names kept (``summaries``, default all) and
    their columns; a ``TypeError`` / ``ValueError`` naming ``summaries`` otherwise."""
    if summaries is not None and (isinstance(summaries, (str, bytes)) or not isinstance(summaries, (list, tuple))
                                  or not summaries):
        raise TypeError(f"summaries must be a non-empty list of summary names, got {summaries!r}")
    every = _summary_names(k, lags)
    chosen = every if summaries is None else [str(s) for s in summaries]
    unknown = [s for s in chosen if s not in every]
    if unknown or len(set(chosen)) != len(chosen):
        raise ValueError(f"summaries: {unknown[0] if unknown else 'a name given twice'!r} is not one of the "
                         f"{len(every)} summaries of {k}-channel records with lags={lags}: {', '.join(every)}")
    return every, chosen, [every.index(s) for s in chosen]


def record_effect(held_out: Any, *, lags: int = 0, block: int = 64, min_samples: int | None = None,
                  summaries: Any = None) -> RecordEffect:
    r"""Fit the between-record law of every candidate model's residual summaries, for sequential identification
    that survives record-to-record variation (:meth:`RecordEffect.loglik` into :func:`msprt`).

    Parameters
    ----------
    held_out : mapping
        Model name -> list of that model's held-out residual records on its own fitting records (records the
        model was not fitted on: ``spec.held_out_residuals(groups=...)``; the segments of one record, e.g. one
        flight, joined into one array), each shape (nobs_r, k); one record is enough for a model when the others
        give the pooled spread its degrees of freedom. A model name may stand for a model in one operating
        condition (e.g. ``"normal@E8"``: the normal model's residuals on the flights of airframe E8), so that each
        condition has its own centre while the spread is pooled.
    lags : int
        Residual autocorrelation lags among the summaries (0: per channel the mean and the log RMS only).
    block : int
        Samples per batch of the long-run (within-record) covariance of the summaries' per-sample series (at
        least 10 whole blocks per model are needed); much longer than the correlation time of the residuals.
    min_samples : int, optional
        Samples of the first running summary used (default ``block``).
    summaries : sequence of str, optional
        The summaries kept, by name (``"mean[y0]"``, ``"log_scale[y2]"``, ``"acf1[y1]"``, ...; channel ``yi`` is
        column ``i`` of the records), in the order given; default all. Keep the ones that carry the state: e.g. of
        raw signals (the same array given as every model's "residuals") the mean of a command (its trim) and the
        log RMS of a band-passed gyro rate (a vibration band power), so that the degrees of freedom of the
        between-record spread are not spent on summaries that do not vary between the states.

    Returns
    -------
    RecordEffect

    Raises
    ------
    TypeError
        ``held_out`` not a mapping of at least 2 models to lists of records.
    ValueError
        Records with different channel counts or too short; fewer than 10 blocks per model; non-finite summaries;
        fewer degrees of freedom (records minus models) than summaries; a name in ``summaries`` not among the
        record's summaries, or twice.

    Notes
    -----
    Model :math:`j`'s residuals on a record of its own state have a record-specific mean (a trim), scale and
    colour. The summaries :math:`f_{jr}` of its :math:`R_j` held-out records give the centre
    :math:`c_j = \bar f_j` and the between-record covariance pooled over the models,
    :math:`S = \sum_j \sum_r (f_{jr} - \bar f_j)(f_{jr} - \bar f_j)' / \nu` with :math:`\nu = \sum_j (R_j - 1)`
    (a condition with 1-5 records gives no covariance of its own; pooling assumes the record-to-record spread is
    the aircraft's, not the state's; a model with a single record has that record as its centre and adds no degree
    of freedom); a new record's summaries then follow the predictive multivariate t law with
    scale matrix :math:`S (1 + 1/R_j) \nu / (\nu - q + 1)` and :math:`\nu - q + 1` degrees of freedom (Hotelling:
    :math:`d' [S (1 + 1/R_j)]^{-1} d \, (\nu - q + 1) / (q \nu)` is :math:`F(q, \nu - q + 1)` for a new record's
    deviation :math:`d` from the centre), to which
    :meth:`RecordEffect.loglik` adds the within-record noise ``within / n`` of a running summary. ``within`` is the
    batch-means long-run covariance of the per-sample series whose running means are the summaries to first order
    (delta method): :math:`e_t`, :math:`e_t^2 / (2 \overline{e^2})` and the autocorrelation terms. The record
    summaries include the within-record noise of the held-out records, so ``between`` is slightly conservative.
    """
    if not isinstance(held_out, Mapping) or len(held_out) < 2:
        raise TypeError("held_out must be a mapping model name -> list of held-out residual records, with at least "
                        "2 models")
    lags = int_like(lags, "lags", minimum=0)
    block = int_like(block, "block", minimum=1)
    min_samples = block if min_samples is None else int_like(min_samples, "min_samples", minimum=2)
    names = tuple(str(m) for m in held_out)
    k = None
    F, W, R = [], [], []
    for name, recs in held_out.items():
        arrs = _residual_records(recs, f"held_out[{name!r}]", k)
        k = arrs[0].shape[1]
        short = [i for i, e in enumerate(arrs) if e.shape[0] < lags + 2]
        if short:
            raise ValueError(f"held_out[{name!r}][{short[0]}] is shorter than lags + 2 = {lags + 2} samples")
        if not F:                       # the first model's records fix the channels, hence the summaries' names
            every, chosen, keep = _kept_summaries(summaries, k, lags)
        f = np.array([_running_summaries(e, lags, e.shape[0] - 1)[0] for e in arrs])[:, keep]
        if not np.isfinite(f).all():
            raise ValueError(f"held_out[{name!r}]: a record has a constant residual channel (its summaries are not "
                             "finite)")
        # per-sample series whose long-run variance gives the within-record noise of a running summary
        parts = []
        for e in arrs:
            z = _sample_series(e, lags)
            nb = z.shape[0] // block
            if nb:
                parts.append(z[: nb * block])
        z = np.concatenate(parts) if parts else np.empty((0, (2 + lags) * k))
        nb = z.shape[0] // block
        if nb < 10:
            raise ValueError(f"held_out[{name!r}] holds {nb} blocks of {block} samples, at least 10 are needed to "
                             "estimate the within-record long-run variance; give longer records or a shorter block")
        sums = z.reshape(nb, block, -1).sum(axis=1)[:, keep]
        W.append(np.atleast_2d(np.cov(sums.T)) / block)
        F.append(f)
        R.append(len(arrs))
    R = np.array(R)
    dev = np.concatenate([f - f.mean(axis=0) for f in F])
    q = dev.shape[1]
    dof = int((R - 1).sum())
    if dof <= q:
        raise ValueError(f"held_out: {dof} degrees of freedom of the between-record spread (records minus models) "
                         f"for {q} summaries: give more records, fewer lags or fewer summaries")
    S = dev.T @ dev / dof
    sd = np.sqrt(np.diag(S))
    if not (sd > 0).all() or np.linalg.eigvalsh(S / np.outer(sd, sd))[0] <= 1e-10:     # on the correlation scale
        raise ValueError("held_out: the between-record covariance of the summaries is singular (summaries that do "
                         "not vary, or vary together exactly, over the records): give more or more varied records")
    between = np.array([S * ((1.0 + 1.0 / r) * dof / (dof - q + 1)) for r in R])
    df = np.full(len(R), float(dof - q + 1))
    return RecordEffect(models=names, center=np.array([f.mean(axis=0) for f in F]), between=between,
                        within=np.array(W), df=df, records=tuple(int(r) for r in R), min_samples=min_samples,
                        summaries=tuple(chosen), lags=lags, nchan=k)


@dataclass(frozen=True)
class AlignedRecordEffect:
    r"""Time-aligned between-record law of every candidate model's running residual summaries (fitted by
    :func:`aligned_record_effect`); its :meth:`loglik` is the per-sample input of :func:`msprt`.

    Attributes
    ----------
    models : tuple of str
        Candidate model names, in column order.
    center : ndarray, shape (M, n, q)
        At each sample ``t``, the mean over each model's held-out records of their running summaries over samples
        ``0..t`` (NaN before ``min_samples - 1``).
    between : ndarray, shape (n, q, q)
        At each sample, the covariance :math:`S(t)` of the records' running summaries about their model's centre,
        pooled over the models, times :math:`\nu / (\nu - q + 1)` (a spread estimated with :math:`\nu` degrees of
        freedom; NaN before ``min_samples - 1``); model ``j`` predicts with the t law of scale matrix
        ``scale[j] between (1 + 1/R_j)``.
    scale : ndarray, shape (M, n)
        At each sample, the factor of ``between`` for each model: its spread group's own spread relative to the
        pooled one, shrunk towards 1 (1 for every model without ``spread_groups``; NaN before ``min_samples - 1``).
    df : ndarray, shape (M, n)
        At each sample, the degrees of freedom of each model's predictive multivariate t law: :math:`\nu - q + 1`
        with :math:`\nu = \sum_j (R_j - 1)`, or fewer with ``spread_groups`` (NaN before ``min_samples - 1``).
    records : tuple of int
        Held-out records per model (:math:`R_j`).
    min_samples : int
        Samples in the first running summary used; the increments before it are 0.
    summaries : tuple of str
        Names of the ``q`` summaries (as :class:`RecordEffect`'s).
    lags : int
        Residual autocorrelation lags of the summaries named ``acf<j>``.
    nchan : int
        Channels of the records.
    """

    models: tuple
    center: np.ndarray
    between: np.ndarray
    scale: np.ndarray
    df: np.ndarray
    records: tuple
    min_samples: int
    summaries: tuple
    lags: int
    nchan: int

    def __post_init__(self) -> None:
        _freeze_arrays(self, center=3, between=3, scale=2, df=2)

    def __repr__(self) -> str:
        return (f"AlignedRecordEffect(models={len(self.models)}, summaries={len(self.summaries)}, "
                f"samples={self.center.shape[1]}, records={self.records}, min_samples={self.min_samples})")

    def loglik(self, resid: Any) -> np.ndarray:
        r"""Per-sample increments of each model's time-aligned record-level predictive log-likelihood, the input of
        :func:`msprt`.

        Parameters
        ----------
        resid : sequence or mapping of M array_like, each shape (nobs, k)
            Each candidate model's residuals (or, for a law of raw signals, the same signals for every model) on
            the first ``nobs`` samples of one record aligned like the fitting records, ``nobs`` at most the
            samples of the law (a record so far, in a stream).

        Returns
        -------
        ndarray, shape (nobs, M)
            Row ``t``: :math:`L_j(t) - L_j(t-1)`, with :math:`L_j(t)` the log density of model ``j``'s running
            summaries over samples ``0..t`` under model ``j``'s predictive law at ``t`` (rows before
            ``min_samples - 1`` are 0).

        Raises
        ------
        ValueError
            Not one array per model, arrays of different lengths or channel counts, longer than the law, non-finite
            values, or a channel that is zero over the first samples (a log RMS of minus infinity).
        """
        M = len(self.models)
        every = _summary_names(self.nchan, self.lags)
        keep = [every.index(s) for s in self.summaries]
        n_law = self.center.shape[1]
        arrs = _per_model_residuals(resid, self.models, self.nchan)
        n = arrs[0].shape[0]
        if n > n_law:
            raise ValueError(f"resid has {n} samples, the law covers the first {n_law} (the length of its records)")
        q = len(keep)
        cum = np.zeros((n, M))
        t0 = self.min_samples - 1
        if n > t0:
            # one factor of the shared scale matrix: model j's is sqrt(scale_j (1 + 1/R_j)) times it
            inv = np.linalg.inv(np.linalg.cholesky(self.between[t0:n]))
            half_logdet = np.log(np.diagonal(inv, axis1=1, axis2=2)).sum(axis=1)          # of the inverse
            for j, e in enumerate(arrs):
                nu = self.df[j, t0:n]
                const = special.gammaln(0.5 * (nu + q)) - special.gammaln(0.5 * nu) - 0.5 * q * np.log(nu * np.pi)
                with np.errstate(divide="ignore", invalid="ignore"):
                    f = _running_summaries(e, self.lags, t0)[:, keep] - self.center[j, t0:n]
                if not np.isfinite(f).all():
                    raise ValueError(f"resid[{self.models[j]!r}]: a channel is zero over the first "
                                     f"{int(np.argmin(np.isfinite(f).all(axis=1))) + t0 + 1} samples (log RMS not "
                                     "finite)")
                factor = self.scale[j, t0:n] * (1.0 + 1.0 / self.records[j])
                d = np.einsum("tij,tj->ti", inv, f)
                cum[t0:, j] = (const + half_logdet - 0.5 * q * np.log(factor)
                               - 0.5 * (nu + q) * np.log1p(np.einsum("ij,ij->i", d, d) / (nu * factor)))
        return np.diff(cum, axis=0, prepend=0.0)


def aligned_record_effect(held_out: Any, *, lags: int = 0, min_samples: int = 2, summaries: Any = None,
                          spread_groups: Any = None) -> AlignedRecordEffect:
    r"""Fit the time-aligned between-record law of every candidate model's running summaries, for sequential
    identification of records that follow one programme (:meth:`AlignedRecordEffect.loglik` into :func:`msprt`).

    Parameters
    ----------
    held_out : mapping
        Model name -> list of that model's records, each shape (n, k), all of the same length ``n`` and aligned on
        the programme (sample ``t`` of every record at the same point of it: e.g. flights of one manoeuvre
        programme from the same trimmed take-off, each segment cut to a common length): a model's held-out
        residuals on its own records, or raw signals (the same records given as every model's input to
        ``loglik``). A model name may stand for a state in one operating condition (``"normal@E8"``); a model with
        one record has it as its centre and adds no degree of freedom.
    lags : int
        Autocorrelation lags among the summaries (as :func:`record_effect`).
    min_samples : int
        Samples of the first running summary used (at least 2).
    summaries : sequence of str, optional
        The summaries kept, by name (``"mean[y0]"``, ``"log_scale[y2]"``, ...), in the order given; default all.
    spread_groups : mapping, optional
        Model name -> spread group (e.g. the airframe: ``{"normal@E8": "E8", "cut@E9": "E9", ...}``, or each
        model its own group), every model in one: the models of a group predict with the pooled covariance times
        the group's own factor at each sample (its records' spread relative to the pooled one, shrunk towards 1 as
        far as the groups' factors differ no more than their sampling noise says), for records whose spread
        differs by group. A group of one-record models keeps the pooled spread. Default: one spread for every
        model.

    Returns
    -------
    AlignedRecordEffect

    Raises
    ------
    TypeError
        ``held_out`` not a mapping of at least 2 models to lists of records; ``summaries`` not a list of names.
    ValueError
        Records of different lengths or channel counts, shorter than ``min_samples``; non-finite summaries;
        fewer degrees of freedom (records minus models) than summaries; a summary name unknown or given twice; a
        between-record covariance singular at some sample; more values than the library allocates at once;
        ``spread_groups`` missing a model or naming one that is not in ``held_out``.

    Notes
    -----
    At every sample :math:`t` the running summaries :math:`f_{jr}(t)` (over samples :math:`0..t`) of model
    :math:`j`'s records give the centre :math:`c_j(t) = \bar f_j(t)` and the covariance about it pooled over the
    models, :math:`S(t) = \sum_j \sum_r (f_{jr}(t) - c_j(t))(f_{jr}(t) - c_j(t))' / \nu`, :math:`\nu =
    \sum_j (R_j - 1)`; a new record's running summaries at :math:`t` then follow the predictive multivariate t law
    with centre :math:`c_j(t)`, scale matrix :math:`S(t)(1 + 1/R_j) \nu / (\nu - q + 1)` and :math:`\nu - q + 1`
    degrees of freedom (as :func:`record_effect`'s).
    Unlike :func:`record_effect` (one centre, plus a within-record noise ``within / n`` from a long-run variance),
    nothing is modelled within a record: the programme's share of a running summary (a manoeuvre moves a running
    mean the same way on every record), the record-to-record spread and the within-record noise of a summary over
    :math:`t + 1` samples are all in :math:`c_j(t)` and :math:`S(t)` by construction, from the records themselves.
    It needs records aligned on a common programme and as long as the records to be decided.

    With ``spread_groups`` the shape of the spread (the summaries' correlations) stays pooled and its size is the
    group's. At each sample, group :math:`g`'s squared standardised deviations :math:`s_g(t) = \sum_{r \in g}
    d_r(t)' S(t)^{-1} d_r(t)` (:math:`d_r(t)`: a record's deviation from its model's centre) over
    :math:`q \nu_g` degrees of freedom, :math:`\nu_g = \sum_{j \in g} (R_j - 1)`, estimate its factor
    :math:`\hat\lambda_g = s_g / (q \nu_g)` (with :math:`S` known up to its size, :math:`s_g / \lambda_g` is
    :math:`\chi^2_{q \nu_g}`). The factors get a scaled inverse chi-square prior centred on 1 whose weight
    :math:`\nu_0 = 4 + 2 / \tau^2` comes from the groups themselves: :math:`\tau^2` is the mean of
    :math:`(\hat\lambda_g - 1)^2` less the mean sampling variance :math:`2 / (q \nu_g)`, at least 0 (0: one
    spread, :math:`\nu_0 = \infty`). Model :math:`j` of group :math:`g` then predicts with scale matrix
    :math:`\tilde\lambda_g(t) S(t)(1 + 1/R_j) \nu / (\nu - q + 1)`, :math:`\tilde\lambda_g = (\nu_0 + s_g) /
    (\nu_0 + q \nu_g)` (the posterior's), and :math:`\min(\nu - q + 1, \nu_0 + q \nu_g)` degrees of freedom; a
    group without degree of freedom keeps :math:`\tilde\lambda_g = 1`, and one group, or groups that differ no
    more than their noise, give the law without groups. As for
    :func:`record_effect`, :math:`L_j(t) - L_k(t)` is the log-likelihood ratio of the summaries at each fixed
    :math:`t`, not a martingale in :math:`t`: the bound of :func:`msprt` is not guaranteed when it is applied at
    every sample (``tests/detection/test_sequential_mc.py`` checks it by Monte Carlo; ``benchmarks/sprt.py`` on
    CrazyPAD).
    """
    if not isinstance(held_out, Mapping) or len(held_out) < 2:
        raise TypeError("held_out must be a mapping model name -> list of records, with at least 2 models")
    lags = int_like(lags, "lags", minimum=0)
    min_samples = int_like(min_samples, "min_samples", minimum=2)
    names = tuple(str(m) for m in held_out)
    group = _spread_groups(spread_groups, held_out)
    k = n = None
    recs = {}
    for name, v in held_out.items():
        arrs = _residual_records(v, f"held_out[{name!r}]", k)
        k, n = arrs[0].shape[1], arrs[0].shape[0] if n is None else n
        uneven = [i for i, e in enumerate(arrs) if e.shape[0] != n]
        if uneven:
            raise ValueError(f"held_out[{name!r}][{uneven[0]}] has {arrs[uneven[0]].shape[0]} samples, the first "
                             f"record {n}: the records must be aligned and of one length (cut them to a common one)")
        recs[name] = arrs
    every, chosen, keep = _kept_summaries(summaries, k, lags)
    if n < max(min_samples, lags + 2):
        raise ValueError(f"held_out: the records have {n} samples, fewer than min_samples = {min_samples} (or lags "
                         f"+ 2 = {lags + 2})")
    total = sum(len(v) for v in recs.values())
    if n * (len(every) + len(keep) * (len(keep) + total)) > MAX_VALUES:
        raise ValueError(f"held_out: {total} records of {n} samples and {len(keep)} summaries need more values than "
                         f"the library allocates at once ({MAX_VALUES}): give shorter records or fewer summaries")
    F, R = [], []
    for name, arrs in recs.items():
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.array([_running_summaries(e, lags, min_samples - 1)[:, keep] for e in arrs])
        if not np.isfinite(f).all():
            raise ValueError(f"held_out[{name!r}]: a record has a channel that is zero over its first "
                             f"{min_samples} samples or more (its log RMS is not finite)")
        F.append(f)
        R.append(len(arrs))
    R = np.array(R)
    q = len(keep)
    dof = int((R - 1).sum())
    if dof <= q:
        raise ValueError(f"held_out: {dof} degrees of freedom of the between-record spread (records minus models) "
                         f"for {q} summaries: give more records, fewer lags or fewer summaries")
    dev = np.concatenate([f - f.mean(axis=0) for f in F])
    S = np.einsum("rtq,rtp->tqp", dev, dev) / dof
    sd = np.sqrt(np.diagonal(S, axis1=1, axis2=2))
    if not (sd > 0).all() or (np.linalg.eigvalsh(S / (sd[:, :, None] * sd[:, None, :]))[:, 0] <= 1e-10).any():
        raise ValueError("held_out: the between-record covariance of the running summaries is singular at some "
                         "sample (summaries that do not vary, or vary together exactly, over the records): give "
                         "more or more varied records, or a larger min_samples")
    center = np.array([np.concatenate([np.full((min_samples - 1, q), np.nan), f.mean(axis=0)]) for f in F])
    between = np.concatenate([np.full((min_samples - 1, q, q), np.nan), S * (dof / (dof - q + 1))])
    scale = np.ones((len(names), n - min_samples + 1))
    df = np.full((len(names), n - min_samples + 1), float(dof - q + 1))
    if group is not None:
        scale, df = _group_spread(F, R, S, group, dof)
    scale = np.concatenate([np.full((len(names), min_samples - 1), np.nan), scale], axis=1)
    df = np.concatenate([np.full((len(names), min_samples - 1), np.nan), df], axis=1)
    return AlignedRecordEffect(models=names, center=center, between=between, scale=scale, df=df,
                               records=tuple(int(r) for r in R), min_samples=min_samples, summaries=tuple(chosen),
                               lags=lags, nchan=k)


def _group_spread(F: list, R: np.ndarray, S: np.ndarray, group: list, dof: int) -> tuple[np.ndarray, np.ndarray]:
    """Each model's spread factor and t degrees of freedom at every sample, shape (M, n), from its spread group's
    records (``F``: each model's running summaries, (R_j, n, q); ``S``: the pooled covariance, (n, q, q)); see
    :func:`aligned_record_effect`'s notes."""
    q = S.shape[-1]
    inv = np.linalg.inv(S)
    # squared standardised deviations of the records from their model's centre, summed per model: (M, n)
    dev = [f - f.mean(axis=0) for f in F]
    m2 = np.array([np.einsum("tik,rti,rtk->t", inv, d, d, optimize=True) for d in dev])
    labels = list(dict.fromkeys(group))
    member = np.array([[h == g for h in group] for g in labels], dtype=np.float64)       # (G, M)
    nu_g = member @ (R - 1.0)
    ss = member @ m2                                                                       # (G, n)
    has = nu_g > 0
    lam = ss[has] / (q * nu_g[has, None])
    # between-group variance of the factors net of their sampling variance 2 / (q nu_g): the prior's weight
    tau2 = np.maximum(((lam - 1.0) ** 2).mean(axis=0) - np.mean(2.0 / (q * nu_g[has])), 0.0)
    with np.errstate(divide="ignore"):
        nu0 = 4.0 + 2.0 / tau2                                                            # inf: one spread
    w = np.where(np.isfinite(nu0), nu0, 1.0)
    post = np.where(np.isfinite(nu0), (w + ss) / (w + q * nu_g[:, None]), 1.0)             # (G, n)
    dfg = np.minimum(float(dof - q + 1), nu0 + q * nu_g[:, None])
    idx = [labels.index(h) for h in group]
    return post[idx], dfg[idx]


def _spread_groups(spread_groups: Any, held_out: Mapping) -> list | None:
    """The spread group of every model of ``held_out`` in its order (None: no groups); a ``TypeError`` /
    ``ValueError`` naming ``spread_groups`` otherwise."""
    if spread_groups is None:
        return None
    if not isinstance(spread_groups, Mapping):
        raise TypeError(f"spread_groups must be a mapping model name -> group, got {type(spread_groups).__name__}")
    missing = [m for m in held_out if m not in spread_groups]
    if missing:
        raise ValueError(f"spread_groups: the model {missing[0]!r} has no group")
    extra = [m for m in spread_groups if m not in held_out]
    if extra:
        raise ValueError(f"spread_groups: {extra[0]!r} is not a model of held_out")
    bad = [m for m in held_out if not isinstance(spread_groups[m], Hashable)]
    if bad:
        raise TypeError(f"spread_groups[{bad[0]!r}] must be a group label (a str, a number...), got "
                        f"{type(spread_groups[bad[0]]).__name__}")
    return [spread_groups[m] for m in held_out]

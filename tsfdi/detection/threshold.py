"""Data-driven thresholds of a detection statistic (Hansen, Blanke, Adrian, paper 002, Fig. 2).

:class:`EmpiricalThreshold` (the empirical quantile, or a generalised Pareto tail) is shared by the GLRT and the
calibrated residual tests; :class:`ScaledChi2Threshold` fits a scaled chi-square law to a windowed statistic
(Ljung-Box :math:`Q`, F test variance ratio), which reaches small ``alpha`` from a few hundred windows. They depend
on no test, so every detection module may import them.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tsfdi._data import as_signal
from tsfdi._validation import float_like, int_like, option, probability

__all__ = ["EmpiricalThreshold", "ScaledChi2Threshold"]


def _ceil(v: float) -> int:
    """Ceiling that ignores floating-point noise (20 / 1e-4 is 200000, not 200001)."""
    return math.ceil(v * (1 - 1e-12))


class EmpiricalThreshold:
    r"""Threshold of a detection statistic from its distribution on healthy data (Hansen et al., Fig. 2).

    Parameters
    ----------
    false_alarm : float
        Required false-alarm probability :math:`P_F` of one value of the statistic, in (0, 1): per sample
        for a per-sample statistic such as the GLRT's :math:`g(k)`, per tested window (per channel) for a
        windowed statistic (Ljung-Box, F test).
    min_exceedances : int
        The empirical :math:`1 - P_F` quantile is used when the healthy sample holds at least this many
        expected exceedances (``n * P_F >= min_exceedances``).
    tail_fraction : float
        Below that, a generalised Pareto distribution is fitted to the excesses over the
        ``1 - tail_fraction`` quantile :math:`u` and the threshold is extrapolated:
        :math:`\gamma = u + \frac{\sigma}{\xi}\left[(P_F / \zeta)^{-\xi} - 1\right]`, :math:`\zeta` the
        fraction of samples above :math:`u` (:math:`\xi = 0`: :math:`u - \sigma \ln(P_F / \zeta)`).
    min_tail : int
        Minimum number of excesses for the tail fit.
    max_extrapolation : float
        The tail fit may reach :math:`P_F` down to ``min_exceedances / (n * max_extrapolation)``; a smaller
        sample raises an error stating how many samples are needed.
    tail_shape : float or None
        Shape :math:`\xi` of the generalised Pareto tail. ``0`` (default): exponential excesses, the Gumbel
        domain of attraction of a maximum of chi-square variables such as the GLRT statistic; its scale is the
        mean excess. ``None``: :math:`\xi` fitted by maximum likelihood too (for other statistics; with
        strongly dependent samples the fitted :math:`\xi` tends to be negative and the threshold too low).

    Attributes
    ----------
    threshold_ : float
        The calibrated threshold (after :meth:`calibrate`).
    method_ : str
        ``"empirical"`` or ``"gpd"``.
    sample_ : ndarray
        The calibration statistic (sorted), kept for :meth:`plot`.

    Notes
    -----
    The statistic of correlated residuals has no closed-form distribution; Hansen et al. estimate the
    threshold from the empirical distribution of g(k) in normal flight. Consecutive values of a windowed
    statistic are strongly dependent, so the effective sample is smaller than its length: calibrate on long
    healthy records.
    """

    def __init__(self, false_alarm: float = 1e-3, *, min_exceedances: int = 20, tail_fraction: float = 0.05,
                 min_tail: int = 100, max_extrapolation: float = 100.0, tail_shape: float | None = 0.0) -> None:
        self.false_alarm = probability(false_alarm, "false_alarm")
        self.min_exceedances = int_like(min_exceedances, "min_exceedances", minimum=1)
        self.tail_fraction = float_like(tail_fraction, "tail_fraction", minimum=0.0, maximum=0.5, strict_min=True)
        self.min_tail = int_like(min_tail, "min_tail", minimum=10)
        self.max_extrapolation = float_like(max_extrapolation, "max_extrapolation", minimum=1.0)
        self.tail_shape = float_like(tail_shape, "tail_shape", minimum=-1.0, maximum=1.0, optional=True)

    def __repr__(self) -> str:
        fitted = f", threshold_={self.threshold_:.5g} ({self.method_})" if hasattr(self, "threshold_") else ""
        return f"EmpiricalThreshold(false_alarm={self.false_alarm:g}{fitted})"

    def samples_needed(self) -> int:
        """Smallest calibration sample that supports ``false_alarm`` (empirical or tail fit)."""
        emp = _ceil(self.min_exceedances / self.false_alarm)
        gpd = max(_ceil(self.min_tail / self.tail_fraction),
                  _ceil(self.min_exceedances / (self.false_alarm * self.max_extrapolation)))
        return min(emp, gpd)

    def calibrate(self, statistic: Any) -> EmpiricalThreshold:
        """Estimate the threshold from healthy values of the statistic; returns ``self``.

        Parameters
        ----------
        statistic : array_like, Series or DataArray
            Values of the detection statistic under normal operation (all channels pooled).

        Raises
        ------
        ValueError
            If the sample is too small for ``false_alarm`` (the message says how many samples are needed).
        """
        sig = as_signal(statistic, "statistic", allow_constant=True)
        g = np.sort(sig.values.ravel())
        n = g.size
        pf = self.false_alarm
        if n * pf >= self.min_exceedances:
            self.method_ = "empirical"
            self.threshold_ = float(np.quantile(g, 1.0 - pf))
            self.gpd_ = None
        else:
            needed = self.samples_needed()
            if n < needed:
                raise ValueError(
                    f"statistic is too small to calibrate false_alarm={pf:g}: {n} samples, at least {needed} "
                    f"are needed (empirical quantile: {_ceil(self.min_exceedances / pf)}; generalised Pareto "
                    f"tail: {needed})")
            from scipy import stats

            u = float(np.quantile(g, 1.0 - self.tail_fraction))
            exc = g[g > u] - u
            zeta = exc.size / n
            if exc.size < self.min_tail or np.ptp(exc) == 0:
                raise ValueError(f"statistic has only {exc.size} distinct excesses over its "
                                 f"{1 - self.tail_fraction:g} quantile; a longer healthy sample is needed")
            if self.tail_shape is None:
                xi, _, scale = stats.genpareto.fit(exc, floc=0.0)
            elif self.tail_shape == 0.0:
                xi, scale = 0.0, float(exc.mean())           # ML scale of exponential excesses
            else:
                xi = self.tail_shape
                _, _, scale = stats.genpareto.fit(exc, f0=xi, floc=0.0)
            if abs(xi) < 1e-9:
                thr = u - scale * math.log(pf / zeta)
            else:
                thr = u + scale / xi * ((pf / zeta) ** (-xi) - 1.0)
            self.method_ = "gpd"
            self.threshold_ = float(thr)
            self.gpd_ = {"shape": float(xi), "scale": float(scale), "location": u, "zeta": zeta}
        self.sample_ = g
        self.nobs_ = n
        return self

    def pvalue(self, value: Any) -> np.ndarray:
        r"""Empirical p-value of ``value`` against the calibration sample, with the +1 correction:
        :math:`(1 + \#\{s_i \ge s\}) / (n + 1)`."""
        self.check_fitted()
        v = np.asarray(value, dtype=np.float64)
        g = self.sample_
        return (1.0 + g.size - np.searchsorted(g, v, side="left")) / (g.size + 1.0)

    def exceedance(self, value: Any) -> np.ndarray:
        """Estimated probability that the healthy statistic exceeds ``value`` (empirical, or the tail fit
        above its location)."""
        self.check_fitted()
        v = np.asarray(value, dtype=np.float64)
        g = self.sample_
        p = 1.0 - np.searchsorted(g, v, side="right") / g.size
        if self.gpd_ is not None:
            u, xi, sc, z = (self.gpd_[k] for k in ("location", "shape", "scale", "zeta"))
            above = v > u
            t = np.maximum(v - u, 0.0)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                tail = z * (np.exp(-t / sc) if abs(xi) < 1e-9 else np.maximum(1 + xi * t / sc, 0) ** (-1 / xi))
            p = np.where(above, tail, p)
        return p

    def check_fitted(self) -> None:
        """Raise ``ValueError`` unless :meth:`calibrate` has been run (``threshold_`` is set)."""
        if not hasattr(self, "threshold_"):
            raise ValueError("EmpiricalThreshold is not calibrated: call calibrate(healthy statistic) first")

    def plot(self, ax: Any = None, **kwargs: Any) -> Any:
        """Probability plot of the healthy statistic with the chosen threshold (Hansen et al., Fig. 2)."""
        self.check_fitted()
        from tsfdi.plotting.decision import plot_threshold

        return plot_threshold(self, ax=ax, **kwargs)


def _mixture_quantile(scale: np.ndarray, df: np.ndarray, alpha: float) -> np.ndarray:
    """``t`` with ``mean_j P(c_j chi2(nu_j) > t) = alpha`` for every row of ``scale`` / ``df`` (shape (B, M)), by
    bisection on ``log t`` (vectorised over the rows)."""
    from scipy import special

    lo = np.log(np.min(scale * special.chdtri(df, np.minimum(1.0, alpha * scale.shape[1])), axis=1) + 1e-300)
    hi = np.log(np.max(scale * special.chdtri(df, alpha / scale.shape[1]), axis=1))
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        above = special.chdtrc(df, np.exp(mid)[:, None] / scale).mean(axis=1) > alpha
        lo, hi = np.where(above, mid, lo), np.where(above, hi, mid)
    return np.exp(0.5 * (lo + hi))


#: Fewest independent windows every record must hold for :class:`ScaledChi2Threshold` to fit it its own law; with a
#: shorter record the records are pooled into one law.
MIN_RECORD_WINDOWS = 3

#: With ``J`` records the predictive law of a new record's log-scale is a Student t with ``J - 1`` degrees of freedom:
#: :class:`ScaledChi2Threshold` needs the ``J`` whose t quantile at the per-channel ``false_alarm`` is at most this
#: many times the normal one (the spread known): 3 records at 0.01, 4 at 1e-3, 5 at 1e-4.
MAX_RECORD_WIDENING = 4.0

#: Gauss-Legendre nodes on ``ln u`` (``u`` the chi-square probability of the posterior of the records' spread, 1e-14
#: to 1).
_NODES = np.polynomial.legendre.leggauss(40)

#: The predictive law of a new record's statistic, ``exp(X) c_j chi2(nu_j)``, is integrated over each record's
#: chi-square law on this many quantile bins per half (equal steps of ``ln w``, ``w`` its tail probability from 1e-30
#: to 0.5), with the tail of the anchor law ``X`` (a posterior mixture of normals, :func:`_posterior_sd`) in closed
#: form, interpolated from a table of :data:`_TABLE` points: the threshold's tail is within 0.5 % of ``false_alarm``
#: from 4 to 20 records, with or without a between-record spread (``tests/detection/test_threshold_predictive.py``).
#: Gauss-Legendre on 40 quantiles of ``X`` against the chi-square tail missed that tail's step where ``X``'s Student t
#: tail is wide: with 4-5 records at 3.3e-4 the threshold's true tail was 1.15-1.3 times ``false_alarm``.
_WITHIN_BINS, _TABLE = 200, 1500


def records_needed(false_alarm: float) -> int:
    """Fewest records for a predictive record-level threshold at ``false_alarm`` (:data:`MAX_RECORD_WIDENING`)."""
    from scipy import stats

    z = stats.norm.isf(false_alarm)
    j = 3
    while j < 1000 and stats.t.isf(false_alarm, j - 1) > MAX_RECORD_WIDENING * z:
        j += 1
    return j


def _posterior_sd(sa2: float, samp: float, j: int) -> tuple[np.ndarray, np.ndarray]:
    """Standard deviations ``sqrt(max(s2 - samp, 0) + s2 / j)`` of a new record's true anchor about the records'
    mean anchor on Gauss-Legendre nodes of the posterior ``s2 = sa2 (j - 1) / chi2(j - 1)``, and their weights."""
    from scipy import stats

    t, wt = _NODES                                        # Gauss-Legendre on ln u, u the chi2 law's probability
    lu = 0.5 * math.log(1e-14) * (1.0 - t)
    u, wu = np.exp(lu), 0.5 * -math.log(1e-14) * wt * np.exp(lu)
    s2 = sa2 * (j - 1.0) / stats.chi2.ppf(u, j - 1.0)
    return np.sqrt(np.maximum(s2 - samp, 0.0) + s2 / j), wu / wu.sum()


def _anchor_table(sa2: float, samp: float, j: int) -> tuple[np.ndarray, np.ndarray]:
    """The upper tail of the predictive law of a new record's true anchor about the records' mean anchor, tabulated:
    points ``x >= 0`` and ``ln P(X > x)``. ``X`` is normal with variance ``tau2 + s2 / j``, ``tau2 = max(s2 - samp,
    0)`` the between-record part, averaged over the posterior of the anchors' total variance ``s2 = sa2 (j - 1) /
    chi2(j - 1)`` (prior ``1 / s2``; the nodes of :func:`_posterior_sd`). With ``samp = 0`` it is the Student t of
    ``j - 1`` degrees of freedom scaled by ``sqrt(sa2 (1 + 1 / j))``; with ``samp > 0`` a between-record variance
    hidden in the sampling noise of the anchors (estimated as zero) keeps the weight its posterior gives it instead of
    being dropped. The table runs, in steps growing like ``sinh``, to where every node's tail is below ``ndtr(-12)``
    (2e-33; 0 beyond)."""
    from scipy import special

    sd, wu = _posterior_sd(sa2, samp, j)
    lw = np.log(wu)
    if not sd.max() > 0:                                  # records with equal anchors: X is 0
        return np.array([0.0, 1e-300]), np.array([math.log(0.5), -np.inf])
    top = 12.0 * float(sd.max())                          # beyond it every node's tail is below ndtr(-12)
    x = float(sd.min()) * np.sinh(np.linspace(0.0, math.asinh(top / float(sd.min())), _TABLE))
    return x, special.logsumexp(special.log_ndtr(-x[:, None] / sd) + lw, axis=1)


def _within_nodes(scale: np.ndarray, df: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nodes ``ln(c_j q)`` and weights of the equal mixture of the records' laws ``c_j chi2(nu_j)``: per record,
    :data:`_WITHIN_BINS` quantile bins of each half (equal steps of ``ln w``, ``w`` the tail probability from 1e-30 to
    0.5; a bin's node its quantile at the middle of its ``ln w``, its weight its probability)."""
    from scipy import special

    lw = np.linspace(math.log(1e-30), math.log(0.5), _WITHIN_BINS + 1)
    mid, mass = np.exp(0.5 * (lw[1:] + lw[:-1])), np.diff(np.exp(lw))
    # records with the same law (a pooled shape) once, weighted by how many share it
    _, first, count = np.unique(np.round(np.c_[np.log(scale), df], 10), axis=0, return_index=True,
                                return_counts=True)
    y, w = [], []
    for i, k in zip(first, count):
        q = 2.0 * np.concatenate([special.gammaincinv(0.5 * df[i], mid), special.gammainccinv(0.5 * df[i], mid)])
        y.append(math.log(scale[i]) + np.log(np.maximum(q, 1e-300)))     # a quantile 0 (tiny df): as good as 0
        w.append(k * np.concatenate([mass, mass]))
    w = np.concatenate(w)
    return np.concatenate(y), w / w.sum()


def _lognormal_nodes(mu: np.ndarray, sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nodes ``ln s`` and weights of the equal mixture of the records' log-normal laws ``exp(N(mu_j, sigma_j^2))``,
    on the quantile bins of :func:`_within_nodes`."""
    from scipy import special

    lw = np.linspace(math.log(1e-30), math.log(0.5), _WITHIN_BINS + 1)
    mid, mass = np.exp(0.5 * (lw[1:] + lw[:-1])), np.diff(np.exp(lw))
    q = special.ndtri(mid)                                 # lower-half standard normal quantiles
    y = np.concatenate([mu[:, None] + sigma[:, None] * q, mu[:, None] - sigma[:, None] * q], axis=1).ravel()
    w = np.tile(np.concatenate([mass, mass]), mu.size)
    return y, w / w.sum()


def _halves(parts: list, per: np.ndarray) -> tuple:
    """Window sums ``(s1, s2, count, independent)`` of two disjoint halves of every record (``parts``: each record's
    windows in order, ``per`` its independent windows): its first and last windows, a window's worth of windows
    (``count / per``) left out between them, so that no window of one half overlaps one of the other."""
    out = ([], [])
    for p, n in zip(parts, per):
        h = int((p.size - math.ceil(p.size / n)) // 2)
        for k, a in enumerate((p[:h], p[p.size - h:])):
            out[k].append((a.sum(), np.square(a).sum(), a.size, n * a.size / p.size))
    return tuple(tuple(np.array(c, dtype=np.float64) for c in zip(*o)) for o in out)


def _predictive_tail(value: Any, y: np.ndarray, wy: np.ndarray, x: np.ndarray, lt: np.ndarray) -> np.ndarray:
    """``P(S > value)`` for ``S = exp(X) c_j chi2(nu_j)``: the records' laws on the nodes ``y`` / weights ``wy``
    (:func:`_within_nodes`), ``X`` the predictive law of the anchor, tabulated by :func:`_anchor_table` (``x``,
    ``lt``); ``value`` 1-D."""
    with np.errstate(divide="ignore"):
        v = np.log(np.asarray(value, dtype=np.float64).reshape(-1))
    out = np.empty(v.shape)
    for a in range(0, v.size, 16):                       # bounded work arrays: 16 x nodes
        d = v[a:a + 16, None] - y
        with np.errstate(invalid="ignore"):
            up = np.exp(np.interp(np.abs(d), x, lt, right=-np.inf))
        out[a:a + 16] = np.where(d >= 0, up, 1.0 - up) @ wy
    return out


def _predictive_quantile(law: tuple, alpha: float) -> float:
    """``t`` with :func:`_predictive_tail` ``= alpha``, by bisection on ``log t``."""
    y, x = law[0], law[2]
    lo, hi = max(float(y.min() - x[-1]) - 1.0, -700.0), min(float(y.max() + x[-1]) + 1.0, 700.0)
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if _predictive_tail(math.exp(mid), *law)[0] > alpha:
            lo = mid
        else:
            hi = mid
    return math.exp(0.5 * (lo + hi))


class ScaledChi2Threshold:
    r"""Threshold of a windowed statistic from scaled chi-square laws fitted to its null sample, record by record.

    Parameters
    ----------
    false_alarm : float
        Required false-alarm probability per tested window (per channel), in (0, 1).
    min_windows : int
        Fewest *independent* (non-overlapping) windows the null sample must hold (default 30).
    record_effect : {"predictive", "bootstrap"}
        With several records: ``"predictive"`` (default) models a record effect -- each record's law (see
        ``shape``), moved to the anchor (log of the ``false_alarm`` quantile) of a *new* record, predicted from the
        records' anchors as a normal random effect estimated from ``J`` records: normal with variance
        :math:`\tau^2 + \sigma^2 / J`, :math:`\tau^2 = \max(\sigma^2 - v_s, 0)` the between-record part net of the
        anchors' sampling variance :math:`v_s`, averaged over the posterior of the anchors' variance
        :math:`\sigma^2 \sim s^2 (J - 1) / \chi^2_{J-1}` (with :math:`v_s = 0` the Student t of ``J - 1`` degrees
        of freedom, scale :math:`s \sqrt{1 + 1/J}`; a between-record spread hidden in the anchors' sampling noise,
        estimated as 0, keeps the weight its posterior gives it; with ``shape="record"`` log-normal record laws and
        :math:`\tau^2` from two halves of every record, see Notes); the threshold solves
        ``P(statistic > t) = false_alarm`` under that predictive law, so that it
        widens as records get fewer. ``"bootstrap"``: the mixture of the records' laws with the ``confidence``
        bootstrap bound (the behaviour before issue 31; it does not extrapolate the record-to-record spread). Records
        too short to show their own spread (fewer than :data:`MIN_RECORD_WINDOWS` independent windows, degrees of
        freedom fitted): under ``"predictive"`` the log statistic of a new record's window is predicted from all
        their windows as a one-way random effect (a Student t, see Notes), under ``"bootstrap"`` one law is fitted to
        the pooled windows with the bootstrap bound.
    min_records : int, optional
        Fewest records the predictive law accepts; default :func:`records_needed` of ``false_alarm`` (3 at 0.01, 4
        at 1e-3, 5 at 1e-4: the t quantile at most :data:`MAX_RECORD_WIDENING` times the normal one).
    shape : {"record", "pooled"}, optional
        The degrees of freedom under ``record_effect="predictive"`` (when ``df`` is not given): ``"pooled"`` -- one
        shape for every record, estimated from all of them, the record effect a change of scale only (a variance
        ratio: records differ by their noise level; :class:`~tsfdi.FTest` sets it); ``"record"`` -- each record its
        own (a Ljung-Box :math:`Q` of mismatched dynamics: records differ in shape too), a log-normal law with the
        record's two moments and a between-record variance from two disjoint halves of every record (see Notes).
        ``None`` (default): the test's choice when it calibrates, else ``"record"``.
    confidence : float
        With several records: the threshold is the ``confidence`` quantile of its bootstrap distribution over
        records (default 0.9), so that a new record's false-alarm rate exceeds ``false_alarm`` only with
        probability about ``1 - confidence`` over the choice of calibration records.
    n_boot : int
        Bootstrap replicates, 10 to 100,000 (fixed seed: the result is reproducible).

    Attributes
    ----------
    threshold_ : float
        The calibrated threshold, after :meth:`calibrate`.
    scale_, df_ : ndarray
        The fitted :math:`c_j` and :math:`\nu_j` of every record (one entry without records, or pooled; with the
        predictive law every :math:`\nu_j` is the pooled shape).
    pooled_ : bool
        Whether the records were pooled into one law (a record shorter than :data:`MIN_RECORD_WINDOWS`
        independent windows; under ``record_effect="predictive"`` the log-normal one-way law of Notes, whose
        ``scale_`` / ``df_`` are the pooled windows' scaled chi-square, for display).
    point_threshold_ : float
        The threshold of the fitted mixture itself (before the bootstrap bound).
    method_ : str
        ``"scaled-chi2"``.
    sample_ : ndarray
        The null sample (sorted).
    nobs_, independent_, records_ : int
        Windows in the sample, how many of them do not overlap, and the number of records.
    effective_windows_ : float
        Independent windows as evidence of a new record's law: per record ``n_j / (1 + (n_j - 1) rho)`` summed,
        ``n_j`` its non-overlapping windows, ``rho`` the share of the between-record variance (the design effect of
        windows sharing a record); with records too short for a law of their own, the Satterthwaite degrees of
        freedom of the predictive t plus one; ``independent_`` without a record law.
    record_law_ : dict or None
        The predictive law of a new record's anchor, at the point estimates: ``between_sd`` (:math:`\tau`),
        ``scale`` (:math:`\sqrt{\tau^2 + s^2 / J}`) and ``df`` (``J - 1``, of the anchors' variance :math:`s^2`:
        its posterior, or with ``shape="record"`` its point estimate, see Notes); ``None`` with
        ``record_effect="bootstrap"``, one record or pooled records.
    levels_ : ndarray
        With the predictive record law: each record's level, the log mean of its statistic (what
        :meth:`record_pvalue` compares a new record's with).
    empirical_check_ : float or None
        The empirical :math:`1 - P_F` quantile of the sample when it holds at least ``10 / P_F`` independent
        windows (a check of the fitted law), else ``None``.

    Notes
    -----
    Under H0 with a known model the Ljung-Box statistic of a window is :math:`\chi^2(r)` (Dutta et al., paper 003,
    eq. 13) and the F test's variance ratio is :math:`\chi^2(N_u) / N_u` (eq. 9, :math:`N_0 \to \infty`): both are
    scaled chi-square variables :math:`c\,\chi^2(\nu)`. A baseline estimated from other records carries
    estimation error, and the records of one fleet differ a little (paper 002: aircraft "of the same type but with
    small differences"): on a new record the statistic is inflated and more variable than the nominal law, which
    is why paper 003 takes a very small alpha to "compensate" for model uncertainty. Paper 002 (Fig. 2) instead
    takes the threshold from the statistic's distribution in normal operation for a required :math:`P_F`.

    Here that distribution is estimated from held-out windows (records driven through a model not fitted on them)
    without needing :math:`\gg 1 / P_F` of them. Each record :math:`j` gets its own law
    :math:`c_j\,\chi^2(\nu_j)` by the method of moments (Satterthwaite): with the mean :math:`m_j` and variance
    :math:`v_j` of its windows, :math:`c_j = v_j / (2 m_j)` and :math:`\nu_j = 2 m_j^2 / v_j`. When the degrees of
    freedom are known (``df``; one for the mean-shift test's :math:`T`) only the scale is fitted,
    :math:`c_j = m_j / \nu`: a record holds few independent windows, and the sample variance of a one-degree
    statistic from ten of them is far too noisy and biased low (it would give :math:`\nu_j \gg 1`, a light tail). A
    record whose mean is offset makes :math:`T` noncentral; the central law with the same mean has the heavier tail,
    so the fit errs on the safe side. A new record is a draw from the fleet, so the null law is the mixture and the threshold :math:`t` solves

    .. math:: \frac{1}{M} \sum_{j=1}^{M} P\big(\chi^2(\nu_j) > t / c_j\big) = P_F .

    With few records the mixture misses part of the fleet's spread; the records are therefore resampled
    (``n_boot`` bootstrap replicates) and the ``confidence`` quantile of the replicate thresholds is used. The
    p-value of :math:`s` is the mixture's upper tail scaled by :math:`P_F / \bar p(t)`, so that it is below
    :math:`P_F` exactly when :math:`s` exceeds the threshold. Without records (one pooled sample) a single law is
    fitted to all windows and no bound is applied. Overlapping windows are dependent: they leave the moment
    estimates consistent but add no independent information, so the support check counts non-overlapping windows
    only. For the same reason a record's own spread :math:`v_j` needs several non-overlapping windows: the windows of
    a record about one window long all but coincide, their variance is near zero and its law would have a
    far too light tail (on a real PX4 gyro record cut in seven one-window blocks, 29 % false alarms at a
    family-wise 1 %). When a record holds fewer than :data:`MIN_RECORD_WINDOWS` independent windows and the degrees
    of freedom are fitted, the records are therefore pooled into one law fitted to all windows (``pooled_``; the
    spread between the records' means then widens it, as it should), and the bootstrap resamples the records and
    refits that law (``record_effect="bootstrap"``). That pooled law was plug-in: on CrazyPAD a flight's two segments
    hold 2 windows each at 2 s windows, so a baseline of 2 flights fitted a 20-lag Ljung-Box law to 8 windows, and
    Ljung-Box flagged 3 of 12 new windows at 0.01; on simulated records of 2 windows, 4 records, new records
    of the same fleet were flagged at 2.5-7.4 times ``false_alarm`` (``tests/detection/test_record_calibration.py``).
    Under ``record_effect="predictive"`` the records are therefore taken as a one-way random effect on the log scale
    instead: the log statistic of a window of record :math:`j` is :math:`a_j + e`, and a new record's window about
    the mean :math:`\bar l` of the records' mean levels :math:`l_j` is predicted with the variance
    :math:`V = (1 + 1/J) s_b^2 + W` (:math:`s_b^2` the variance of the :math:`l_j`, :math:`W` the mean over the
    records of the mean square of their windows about :math:`l_j`: unbiased for the record effect plus a window's
    own variance plus that of :math:`\bar l`, however much the windows overlap), as a Student t with the
    Satterthwaite degrees of freedom of the two terms (:math:`J - 1` and the independent windows less one per
    record): :math:`t = \exp(\bar l + t_{\nu}^{-1}(1 - P_F) \sqrt{V})`, its p-values that t's tail; the records
    needed are those of the record law (``min_records``). On simulated records of 2 windows (4 records, development
    seeds) it gives 0.78 +- 0.14 (Ljung-Box, dynamics varying between records) and 0.99 +- 0.18 (mean square, noise
    level varying) ``false_alarm`` at 0.01; conservative where the windows' own noise dominates (0.27 on white noise:
    the log of :math:`Q` is a little left-skewed, its normal tail with the law known is 0.76 ``false_alarm``, and
    8 windows leave few degrees of freedom), liberal where the record effect is itself skewed (2.1 with the
    dynamics' spread doubled; 5.9 before), which 4 records cannot show. With known degrees of freedom only each
    record's mean is used, which overlapping windows estimate without that bias: the laws stay per record. Monte
    Carlo checks of the realised size on new records of a simulated fleet are in
    ``tests/detection/test_calibration_mc.py``.

    With ``shape="pooled"`` the predictive law (``record_effect="predictive"``) takes the record effect to be a
    change of scale, so every record shares one shape: :math:`2 / \nu` is pooled over the records (each record's
    estimate weighted by its independent windows less one), and record :math:`j` keeps its own scale
    :math:`c_j = m_j / \nu`. A record's own :math:`\nu_j` from the ~10 independent windows of a typical record is
    so noisy (relative error ~45 %) that the anchors spread more than their stated sampling variance and the mixed
    tails are too heavy: on the ideal case where the answer is known (white-noise records whose log variance is
    normal between records, the F variance ratio against the true reference, 10 windows per record) per-record
    shapes make the threshold conservative and the pooled shape keeps ``false_alarm``
    (``tests/detection/test_record_calibration.py``). Where the between-record spread is of the order of the anchors' sampling noise (the Ljung-Box
    statistic on the simulated fleet, where :math:`\tau^2` is estimated as 0), plugging the estimate in made the
    threshold liberal at 1e-3; the posterior average over :math:`\sigma^2` keeps the
    hidden spread and is conservative with very few records instead. Monte Carlo checks on the simulated fleet are
    in ``tests/detection/test_record_calibration.py``. Integrated over fleets on that ideal case (normal log
    variances of spread 0.3, 10 windows of 198 samples per record), the pooled-shape threshold's expected rate on a
    new record is 0.90 / 0.89 ``false_alarm`` with 5 records at the Sidak shares of 0.01 / 1e-3 over three channels,
    0.95 / 0.93 with 10 and 0.97 / 0.96 with 20 (``tests/detection/test_threshold_predictive.py``): the Student t
    predictive is exact for the record levels alone (1.00 without the windows' own noise), and that noise, known,
    floors the threshold of the fleets whose records happen to agree, which are the fleets that carry the rate. With
    5 records a fleet's rate is heavy-tailed (on the simulated fleet its standard deviation is 3 ``false_alarm`` at
    0.01 and 9 at 1e-3, single fleets up to 300): judge the rate over many fleets, not by a binomial band.

    With ``shape="record"`` (each record its own shape: the Ljung-Box :math:`Q`) that construction failed on both
    ends, by two errors that hid each other: (i) a portmanteau statistic's finite-window law is right-skewed beyond
    the chi-square of its two moments (white noise, 198 samples, 20 lags: skewness 0.94 against 0.68; its
    :math:`3.3 \cdot 10^{-4}` quantile 10 % above the chi-square's), so each record's tail was too light (the
    threshold liberal, twice ``false_alarm`` and more, had the anchors not spread); (ii) a record's anchor carries
    its shape estimated from ~10 windows, whose sampling variance is about twice :math:`v_s` (and not computable
    from the window counts: overlapping windows estimate the spread better than disjoint ones), so the anchors'
    noise was read as a between-record spread, from :math:`J - 1` degrees of freedom (0.6 ``false_alarm`` with 5
    records on the simulated fleet, 0.3 at 1e-3, and on plain white noise). Each record's law is therefore the
    log-normal with its two moments, :math:`\sigma_j^2 = \ln(1 + 2 / \nu_j)` (skewness 1.07 with the white-noise
    moments: its quantiles within 2 % of the statistic's from 0.01 to :math:`3.3 \cdot 10^{-4}`), anchored at
    :math:`\mu_j + z \sigma_j`, and the between-record variance is the covariance, over the records, of the
    anchors of two disjoint halves of every record (its first and last windows, a window's worth left out between
    them): their sampling noises are independent, so it estimates :math:`\tau^2` whatever the anchors' own noise
    (truncated at 0). A new anchor is normal about the records' mean with variance :math:`\tau^2 + s^2 / J`
    (plugged in: the truncated covariance already errs high where :math:`\tau^2` is small beside the anchors'
    noise, and a Student t on top was conservative, 0.5-0.8 ``false_alarm`` with 5 records). Chosen on development
    fleets (``benchmarks/fleet_calibration.py``, its development seeds): the Ljung-Box decision's rate on
    new records 0.99 / 0.97 / 0.97 ``false_alarm`` at 0.01 with 5 / 10 / 20 records and 1.36 / 1.04 / 1.47 at
    1e-3 (before, the same fleets: 0.60 / 0.95 / 1.03 and 0.34 / 0.96 / 1.43); on white noise with 5 records 0.85
    (before 0.70) at 0.01
    (``tests/detection/test_record_calibration.py``). The excess at 1e-3 with 20 records is the fleet's: its
    records' anchors are skewed (mismatched dynamics inflate :math:`Q` one way), which a normal record effect
    does not follow.
    """

    method_ = "scaled-chi2"

    def __init__(self, false_alarm: float = 1e-3, *, min_windows: int = 30, record_effect: str = "predictive",
                 min_records: int | None = None, confidence: float = 0.9, n_boot: int = 200,
                 df: float | None = None, shape: str | None = None) -> None:
        self.false_alarm = probability(false_alarm, "false_alarm")
        self.min_windows = int_like(min_windows, "min_windows", minimum=5)
        self.record_effect = option(record_effect, "record_effect", ("predictive", "bootstrap"))
        self.min_records = int_like(min_records, "min_records", minimum=2, optional=True)
        self.confidence = float_like(confidence, "confidence", minimum=0.5, maximum=1.0, strict_max=True)
        self.n_boot = int_like(n_boot, "n_boot", minimum=10, maximum=100_000)   # a bounded (n_boot, records) array
        self.df = None if df is None else float_like(df, "df", minimum=0.0, strict_min=True, maximum=1e12)
        self.shape = None if shape is None else option(shape, "shape", ("record", "pooled"))

    def __repr__(self) -> str:
        fitted = f", threshold_={self.threshold_:.5g}, records_={self.records_}" if hasattr(self, "threshold_") else ""
        return f"ScaledChi2Threshold(false_alarm={self.false_alarm:g}{fitted})"

    def calibrate(self, statistic: Any, independent: Any = None, groups: Any = None) -> ScaledChi2Threshold:
        """Fit the null law to healthy values of the statistic; returns ``self``.

        Parameters
        ----------
        statistic : array_like
            Values of the windowed statistic under normal operation (one channel), non-negative.
        independent : int or array_like of int, optional
            How many of those windows do not overlap: in all (default: all of them), or one count per record of
            ``groups`` (in the order the records first appear).
        groups : array_like, optional
            The record of every window (same length as ``statistic``): one law per record and a mixture over
            records (see Notes). ``None``: one law for the pooled sample.

        Raises
        ------
        ValueError
            If fewer than ``min_windows`` independent windows are given (the message says how many are needed),
            if a record holds fewer than 3 windows, or if the statistic is negative or does not vary.
        """
        from scipy import special

        stat = np.asarray(as_signal(statistic, "statistic", allow_constant=True).values, dtype=np.float64).ravel()
        n = stat.size
        if stat.min() < 0:
            raise ValueError("statistic must be non-negative (a Ljung-Box Q or a variance ratio)")
        if groups is None:
            parts = [stat]
        else:
            groups = np.asarray(groups).ravel()
            if groups.shape != stat.shape:
                raise ValueError(f"groups must label every window ({n}), got {groups.size} labels")
            parts = [stat[groups == g] for g in dict.fromkeys(groups.tolist())]
            small = [i for i, p in enumerate(parts) if p.size < 3]
            if small:
                raise ValueError(f"records {small} hold fewer than 3 windows: use shorter windows or merge records")
        # independent windows per record: given, or the record's share of the total
        if independent is not None and np.ndim(independent) == 1:
            per = np.asarray(independent, dtype=np.float64)
            if groups is None or per.shape != (len(parts),):
                raise ValueError(f"independent: one count per record of groups ({len(parts)}) is needed, got "
                                 f"{per.size}")
            n_ind = int(per.sum())
        else:
            n_ind = n if independent is None else int_like(independent, "independent", minimum=0, maximum=n)
            per = np.array([p.size for p in parts], dtype=np.float64) * (n_ind / n)
        if n_ind < self.min_windows:
            raise ValueError(f"statistic holds {n_ind} independent (non-overlapping) windows, at least "
                             f"{self.min_windows} are needed to fit the null law: give more or longer healthy "
                             "records")
        # a record shorter than MIN_RECORD_WINDOWS windows cannot show its own spread (its windows overlap): pool
        # (with known degrees of freedom only the mean is fitted per record, which overlapping windows estimate well)
        s1 = np.array([p.sum() for p in parts])
        s2 = np.array([np.square(p).sum() for p in parts])
        cnt = np.array([p.size for p in parts], dtype=np.float64)
        self.sample_ = np.sort(stat)
        self.nobs_ = n
        self.independent_ = n_ind
        self.records_ = len(parts)
        self.empirical_check_ = float(np.quantile(stat, 1.0 - self.false_alarm)) if n_ind * self.false_alarm >= 10 \
            else None
        short = self.df is None and per.min() < MIN_RECORD_WINDOWS      # records that cannot show their own spread
        self._short_law = None
        if self.record_effect == "predictive" and len(parts) > 1:
            if short:
                return self._short_predictive(parts, per)
            own = self.df is None and self.shape != "pooled"               # each record its own shape
            return self._predictive(s1, s2, cnt, per, _halves(parts, per) if own else None)
        self.record_law_ = None
        self.effective_windows_ = float(n_ind)
        self.pooled_ = bool(short and len(parts) > 1)
        if self.pooled_:
            self.scale_, self.df_ = self._laws(s1.sum(keepdims=True), s2.sum(keepdims=True), cnt.sum(keepdims=True))
        else:
            self.scale_, self.df_ = self._laws(s1, s2, cnt)
        pf = self.false_alarm
        self.point_threshold_ = float(_mixture_quantile(self.scale_[None, :], self.df_[None, :], pf)[0])
        if len(parts) > 1:
            rng = np.random.default_rng(0)
            idx = rng.integers(0, len(parts), size=(self.n_boot, len(parts)))
            if self.pooled_:      # resample the records, refit the one pooled law
                c, nu = self._laws(s1[idx].sum(axis=1), s2[idx].sum(axis=1), cnt[idx].sum(axis=1))
                boot = _mixture_quantile(c[:, None], nu[:, None], pf)
            else:
                boot = _mixture_quantile(self.scale_[idx], self.df_[idx], pf)
            self.threshold_ = float(max(self.point_threshold_, np.quantile(boot, self.confidence)))
        else:
            self.threshold_ = self.point_threshold_
        tail = special.chdtrc(self.df_, self.threshold_ / self.scale_).mean()
        self._pvalue_factor = pf / tail if tail > 0 else 1.0
        return self

    def _predictive(self, s1: np.ndarray, s2: np.ndarray, cnt: np.ndarray, per: np.ndarray,
                    halves: tuple | None) -> ScaledChi2Threshold:
        """The record-level predictive law (see Notes) from the records' window sums ``s1``, ``s2``, counts ``cnt``
        and independent windows ``per`` (and, for a shape per record, those of two disjoint halves of every record,
        :func:`_halves`; with fewer than 2 windows in a half, the chi-square laws and the posterior average);
        sets the threshold and the p-value grid."""
        from scipy import special

        j = len(cnt)
        self._records_check(j)
        m = s1 / cnt
        if not np.all(m > 0):
            raise ValueError("statistic is 0 on every window of some healthy record: no null law can be fitted")
        self.pooled_ = False
        self.scale_, self.df_ = self._laws(s1, s2, cnt, per)
        if self.df is None and self.shape == "pooled":
            # the record effect is a change of scale: one shape for every record, its squared coefficient of
            # variation 2 / nu pooled over the records, each weighted by the independent windows behind its variance
            # less one (a record's own nu from ~10 windows is so noisy that the anchors spread and the tails mix
            # too wide: the threshold was conservative, see Notes)
            w = np.maximum(per - 1.0, 1.0)
            nu = float(w.sum() / np.sum(w / self.df_))
            self.scale_, self.df_ = self.scale_ * self.df_ / nu, np.full(j, nu)
        # each record's anchor: the log of its own false_alarm quantile; the anchors' between-record variance tau2,
        # net of their own sampling variance (~ 2 / nu_j per independent window)
        pf = self.false_alarm
        anchor = np.log(self.scale_ * special.chdtri(self.df_, pf))
        law, df = self.scale_, self.df_
        cv2 = float(np.mean(2.0 / df))
        sa2 = float(np.var(anchor, ddof=1))
        samp = float(np.mean(2.0 / df / np.maximum(per, 1.0)))
        tau2 = max(sa2 - samp, 0.0)
        # a new record: a record's law moved to the anchor loc + X, X the predictive law of a new anchor under a
        # normal random effect estimated from J records (variance tau2 + s2 / J over the posterior of s2: Student t
        # tails, J - 1 degrees of freedom)
        loc = float(anchor.mean())
        if halves is not None and min(halves[0][2].min(), halves[1][2].min()) >= 2:
            # each record its own shape: log-normal laws with the records' two moments, the new anchor normal about
            # the records' mean with the between-record variance from the covariance of the anchors of two disjoint
            # halves of every record (their sampling noise is independent) plus that of the mean (see Notes)
            z = -special.ndtri(pf)
            sg = np.sqrt(np.log1p(2.0 / df))                  # (the laws' squared coefficient of variation is 2 / nu)
            anchor = np.log(self.scale_ * self.df_) - 0.5 * sg * sg + z * sg
            half = []
            for h1, h2, hc, hp in halves:
                c, nu = self._laws(h1, h2, hc, hp)
                hs = np.log1p(2.0 / nu)
                half.append(np.log(c * nu) - 0.5 * hs + z * np.sqrt(hs))
            tau2 = max(float(np.cov(half[0], half[1])[0, 1]), 0.0)
            loc, sa2 = float(anchor.mean()), float(np.var(anchor, ddof=1))
            spread = math.sqrt(tau2 + sa2 / j)
            if spread > 0:
                x = spread * np.sinh(np.linspace(0.0, math.asinh(1e3), _TABLE)) * (12.0 / 1e3)
                lt = special.log_ndtr(-x / spread)
            else:                                          # records with equal anchors: X is 0
                x, lt = np.array([0.0, 1e-300]), np.array([math.log(0.5), -np.inf])
            self._predictive_law = (*_lognormal_nodes(loc - z * sg, sg), x, lt)
        else:
            spread = math.sqrt(tau2 + sa2 / j)
            scale = law * np.exp(loc - anchor)
            x, lt = _anchor_table(sa2, samp, j)
            self._predictive_law = (*_within_nodes(scale, df), x, lt)
        self.record_law_ = {"between_sd": math.sqrt(tau2), "scale": spread, "df": j - 1}
        self.levels_ = np.log(m)
        self._level_law = (float(self.levels_.mean()), float(np.var(self.levels_, ddof=1)), samp, cv2)
        icc = tau2 / (tau2 + cv2)
        self.effective_windows_ = float(np.sum(per / (1.0 + (per - 1.0) * icc)))
        self.threshold_ = _predictive_quantile(self._predictive_law, pf)
        self.point_threshold_ = float(_mixture_quantile(self.scale_[None, :], self.df_[None, :], pf)[0])
        # p-values: the predictive tail on a grid following the anchor law's quantiles, interpolated in log-log, through
        # the threshold
        y = self._predictive_law[0]
        q = np.quantile(y - loc, [0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0])       # the records' laws about the anchor
        xs = np.interp(np.linspace(math.log(1e-16), math.log(0.5), 40), lt[::-1], x[::-1])  # its quantiles
        grid = np.unique(np.clip(np.concatenate([-xs, xs])[:, None] + loc + q, -700.0, 700.0))
        grid = np.exp(np.unique(np.append(np.quantile(grid, np.linspace(0, 1, 120)), math.log(self.threshold_))))
        tail = _predictive_tail(grid, *self._predictive_law)
        keep = np.append(np.diff(tail) < 0, True) & (tail > 0)
        at = _predictive_tail(self.threshold_, *self._predictive_law)[0]
        self._pvalue_grid = (np.log(grid[keep]), np.log(tail[keep]) + math.log(pf) - math.log(at))
        return self

    def _records_check(self, j: int) -> None:
        """Refuse fewer records than the predictive law needs for ``false_alarm`` (``min_records``, else
        :func:`records_needed`), saying what is needed."""
        needed = self.min_records if self.min_records is not None else records_needed(self.false_alarm)
        if j < needed:
            raise ValueError(
                f"statistic comes from {j} records, at least {needed} are needed for false_alarm="
                f"{self.false_alarm:g}: a new record's scale is predicted from the spread of the records, and from "
                f"{j} records its {self.false_alarm:g} tail is more than {MAX_RECORD_WIDENING:g} times wider than "
                "with the spread known. Give more healthy records (flights), raise alpha, or set "
                "ScaledChi2Threshold(min_records=...) (record_effect='bootstrap': the per-record mixture, which does "
                "not extrapolate the record-to-record spread)")

    def _short_predictive(self, parts: list, per: np.ndarray) -> ScaledChi2Threshold:
        """The predictive law of a window of a new record from records too short for a law of their own (fewer than
        :data:`MIN_RECORD_WINDOWS` independent windows; see Notes): the log statistic a one-way random effect,
        ``l = a_j + e``, a new record's window about the records' mean level normal with the variance ``(1 + 1/J)
        s_b^2 + W`` (``s_b^2`` the variance of the records' mean levels, ``W`` the mean square of the windows about
        their own record's mean level: unbiased for the record effect plus a window's own variance plus the mean's,
        whatever the overlap of the windows), a Student t with the Satterthwaite degrees of freedom of the two; sets
        the threshold and the p-value law."""
        from scipy import stats

        j = len(parts)
        self._records_check(j)
        if not all(np.all(p > 0) for p in parts):
            raise ValueError("statistic is 0 on some window of a healthy record: its log-normal law cannot be "
                             "fitted (a record too short to show its own spread needs a positive statistic)")
        logs = [np.log(p) for p in parts]
        lev = np.array([x.mean() for x in logs])
        sb2 = float(np.var(lev, ddof=1))
        w = float(np.mean([np.square(x - m).mean() for x, m in zip(logs, lev)]))
        dfw = max(float(np.sum(per - 1.0)), 1.0)      # W rests on the independent windows less one per record
        a = 1.0 + 1.0 / j
        var = a * sb2 + w
        if not var > 0:
            raise ValueError("statistic does not vary on the healthy records: no null law can be fitted")
        df = var * var / ((a * sb2) ** 2 / (j - 1.0) + w * w / dfw)
        loc, sd = float(lev.mean()), math.sqrt(var)
        pf = self.false_alarm
        self._short_law = (loc, sd, float(df))
        self.record_law_ = None
        self.pooled_ = True
        stat = np.concatenate(parts)
        self.scale_, self.df_ = self._laws(np.array([stat.sum()]), np.array([np.square(stat).sum()]),
                                           np.array([float(stat.size)]), np.array([float(per.sum())]))
        self.effective_windows_ = float(df) + 1.0
        self.point_threshold_ = math.exp(loc + stats.norm.isf(pf) * math.sqrt(sb2 + w))
        self.threshold_ = math.exp(loc + stats.t.isf(pf, df) * sd)
        return self

    def record_pvalue(self, statistic: Any, independent: int | None = None) -> tuple[float, float, float]:
        r"""Whether a new record as a whole lies within the predictive record law (the record-level coverage check).

        The record's level -- the log of the mean of its statistic, the log scale of its law -- is compared with the
        fitting records' levels ``l_j``, a normal draw about their mean under the record effect the threshold
        models: the Student t pivot :math:`(l - \bar l) / (s \sqrt{1 + 1/J}) \sim t_{J-1}` (as a posterior
        average of normal laws over the levels' variance, like the threshold's anchors). The levels' spread
        :math:`s^2` holds their own sampling noise; a new record of another length has another, so its variance
        moves by :math:`\overline{2 / \nu} / n_{new} - v_s` (:math:`v_s` the fitting records' mean sampling
        variance :math:`2 / (\nu_j n_j)`, :math:`n` independent windows), at least to :math:`s^2 / J`. With a
        pooled or known shape the level is the threshold's anchor less a constant; with a shape per record (a
        Ljung-Box statistic) the anchor also carries the record's own shape estimate from ~10 windows, whose heavy
        right tail gave twice the nominal rate of small p-values on the simulated fleet, so the level is compared.

        The p-value is the law's *upper* tail: the threshold promises a false-alarm rate of at most
        ``false_alarm`` on a new record, and that promise fails for a record whose statistic lies above the law;
        one below it has fewer false alarms (and less power).

        Parameters
        ----------
        statistic : array_like, shape (n,)
            The statistic on the windows of the new record, one channel, taken as the fitting records' were (the
            same step and length).
        independent : int, optional
            How many of those windows do not overlap (default: all of them), at least
            :data:`MIN_RECORD_WINDOWS`.

        Returns
        -------
        level : float
            The new record's level.
        z : float
            Its distance from the fitting records' mean level in units of the predictive law's standard deviation
            at the posterior mean (a t-like statistic, for display).
        pvalue : float
            The predictive law's probability of a level at least as high.

        Raises
        ------
        ValueError
            Not calibrated with a record law (``record_law_`` is ``None``: ``record_effect="bootstrap"``, one record
            or pooled records); fewer than :data:`MIN_RECORD_WINDOWS` independent windows; a negative, non-finite
            or all-zero statistic.
        """
        from scipy import special

        loc = self._record_law("record_pvalue")[0]
        x = np.asarray(as_signal(statistic, "statistic", allow_constant=True).values, dtype=np.float64).ravel()
        per = x.size if independent is None else int_like(independent, "independent", minimum=0, maximum=x.size)
        if per < MIN_RECORD_WINDOWS:
            raise ValueError(f"statistic holds {per} independent windows, at least {MIN_RECORD_WINDOWS} disjoint "
                             "windows of the new record are needed to estimate its law")
        if not (np.all(np.isfinite(x)) and x.min() >= 0 and x.max() > 0):
            raise ValueError("statistic must be finite, non-negative and not 0 everywhere (a Ljung-Box Q or a "
                             "variance ratio)")
        level = math.log(float(x.mean()))
        sd, w = self._level_sd(per)
        d = level - loc
        return level, float(d / math.sqrt(float(np.square(sd) @ w))), float(special.ndtr(-d / sd) @ w)

    def record_bound(self, level: float, windows: int) -> float:
        """The level of a new record of ``windows`` independent windows that the predictive law of
        :meth:`record_pvalue` exceeds with probability ``level`` (its ``1 - level`` quantile)."""
        from scipy import special

        loc = self._record_law("record_bound")[0]
        level = probability(level, "level")
        windows = int_like(windows, "windows", minimum=1)
        sd, w = self._level_sd(windows)
        lo, hi = -40.0 * float(sd.max()), 40.0 * float(sd.max())
        for _ in range(100):
            mid = 0.5 * (lo + hi)
            if float(special.ndtr(-mid / sd) @ w) > level:
                lo = mid
            else:
                hi = mid
        return loc + 0.5 * (lo + hi)

    def _level_sd(self, windows: int) -> tuple[np.ndarray, np.ndarray]:
        """Standard deviations (and weights) of a new record's level about the fitting records' mean level on the
        nodes of the posterior of their variance ``s2``: ``s2 (1 + 1/J)`` (the t pivot of the levels, whose own
        sampling noise ``s2`` holds) plus the new record's sampling variance less a fitting record's,
        ``cv2 / windows - samp``, at least ``s2 / J``."""
        _, sa2, samp, cv2 = self._level_law
        j = self.records_
        sd, w = _posterior_sd(sa2, 0.0, j)
        var = sd * sd
        return np.sqrt(np.maximum(var + cv2 / windows - samp, var / (j + 1.0))), w

    def _record_law(self, what: str) -> tuple:
        """The record levels' law (mean level, levels' variance, their sampling variance, mean squared coefficient
        of variation of a window); ``ValueError`` naming ``what`` without a predictive record law."""
        self.check_fitted()
        if self.record_law_ is None:
            raise ValueError(f"{what} needs the predictive record law (record_effect='predictive' calibrated on "
                             "several records, each with at least 3 independent windows)")
        return self._level_law

    def _laws(self, s1: np.ndarray, s2: np.ndarray, cnt: np.ndarray,
              per: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Scale and degrees of freedom of ``c chi2(nu)`` by the method of moments from sums of the windows, their
        squares and their counts (one law per entry). With ``per`` (independent windows per entry) the variance of
        overlapping windows about their own mean is corrected for that mean's variance, that of a mean of ``per``
        independent windows: ``ss / cnt * per / (per - 1)`` (``ss / (cnt - 1)`` for disjoint windows)."""
        m = s1 / cnt
        if per is None:
            v = (s2 - cnt * m * m) / np.maximum(cnt - 1.0, 1.0)
        else:
            p = np.maximum(per, 2.0)
            v = (s2 - cnt * m * m) / cnt * (p / (p - 1.0))
        if not (np.all(m > 0) and np.all(v > 0)):
            raise ValueError("statistic does not vary on some healthy record: no null law can be fitted")
        if self.df is None:
            return v / (2.0 * m), 2.0 * m * m / v
        return m / self.df, np.full(m.shape, self.df)

    def check_fitted(self) -> None:
        """Raise ``ValueError`` unless :meth:`calibrate` has been run."""
        if not hasattr(self, "threshold_"):
            raise ValueError("ScaledChi2Threshold is not calibrated: call calibrate(healthy statistic) first")

    def pvalue(self, value: Any) -> np.ndarray:
        """The fitted mixture's upper tail at ``value``, scaled so that it equals ``false_alarm`` at the threshold
        (capped at 1)."""
        from scipy import special

        self.check_fitted()
        v = np.asarray(value, dtype=np.float64)
        if getattr(self, "_short_law", None) is not None:
            from scipy import stats

            loc, sd, df = self._short_law
            with np.errstate(divide="ignore"):
                p = stats.t.sf((np.log(v) - loc) / sd, df)
            return np.where(v == np.inf, 0.0, np.clip(p, np.finfo(np.float64).tiny, 1.0))
        if self.record_law_ is not None:
            with np.errstate(divide="ignore"):
                lv = np.log(v)
            gx, gy = self._pvalue_grid
            # beyond the grid's last point (the records' laws' 1e-30 quantile and more): its last log-log slope
            slope = (gy[-1] - gy[-2]) / (gx[-1] - gx[-2])
            with np.errstate(invalid="ignore"):
                lp = np.where(lv > gx[-1], gy[-1] + slope * (lv - gx[-1]), np.interp(lv, gx, gy))
            p = np.clip(np.exp(lp), np.finfo(np.float64).tiny, 1.0)     # a finite statistic: a p-value above 0
            return np.where(v == np.inf, 0.0, p)
        with np.errstate(over="ignore"):                # beyond the float range: a tail of 0
            tail = special.chdtrc(self.df_, v[..., None] / self.scale_).mean(axis=-1)
        return np.minimum(1.0, tail * self._pvalue_factor)

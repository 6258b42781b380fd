"""Shared base of the residual tests: validation of residuals and options, the fitted-model hook."""

from __future__ import annotations

import copy
from typing import Any

import numba
import numpy as np

from tsfdi._data import Signal, as_signal, runs
from tsfdi._validation import int_like, option, probability
from tsfdi.detection.decision import Decision
from tsfdi.detection.threshold import EmpiricalThreshold, ScaledChi2Threshold

__all__ = ["CalibratedTest", "ReferenceVarianceTest", "ResidualTest"]


def rescale_exponent(x: np.ndarray, axis: int = 0, *, within: int = 256) -> np.ndarray:
    """Exponent ``e`` per column (``axis=0``; per row with ``axis=1``) of a finite 2-D array such that the values
    ``x * 2**-e`` can be squared and multiplied without overflow or underflow: 0 (nothing to do) when ``max |x|`` is
    within [2**-within, 2**within], else the exponent of ``max |x|`` (the rescaled maximum is in [0.5, 1);
    ``within=0``: always that exponent).

    ``np.ldexp(x, -e)`` rescales by a power of two, which is exact: a statistic that does not depend on the scale
    (a correlation, a variance ratio, a Z-score) is bit for bit the one of the original values, while values near
    1e300 or 1e-300 no longer give squares of ``inf`` or 0.
    """
    e = np.frexp(max_abs(x, axis))[1]
    return np.where(np.abs(e) > within, e, 0)


def max_abs(x: np.ndarray, axis: int = 0) -> np.ndarray:
    """``max |x|`` per column (``axis=0``) or row (``axis=1``) of a finite 2-D array, in one pass over memory."""
    if x.size < 4096:                                   # small: numpy, without the compiled call's overhead
        return np.abs(x).max(axis=axis)
    if x.shape[1 - axis] == 1:                          # one column (row): a flat reduction is ~3x faster
        v = x.ravel()
        return np.array([max(v.max(), -v.min())])
    return _max_abs_columns(x if axis == 0 else x.T)


@numba.njit(cache=True, nogil=True)
def _max_abs_columns(x):  # pragma: no cover - compiled
    out = np.zeros(x.shape[1])
    for i in range(x.shape[0]):
        for j in range(x.shape[1]):
            v = abs(x[i, j])
            if v > out[j]:
                out[j] = v
    return out


def scaled_ratio(value: np.ndarray, ref: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """``value * 4**scale / ref`` (a variance ratio of residuals rescaled by ``2**-scale``, :func:`rescale_exponent`)
    without overflow or underflow on the way, exact; a ratio beyond the float range is refused (the reference
    variance cannot be the residual's)."""
    with np.errstate(over="ignore", divide="ignore"):
        if not scale.any():
            f = value / ref                             # a division is exact to rounding, subnormal or not
        else:
            rescaled = np.ldexp(ref, -2 * scale)
            if np.all((rescaled >= np.finfo(np.float64).tiny) & (rescaled <= np.finfo(np.float64).max)):
                f = value / rescaled
            else:
                mant, exp = np.frexp(ref)               # the quotient by the mantissa, then the exponents
                f = np.ldexp(value / mant, 2 * scale - exp)
    if f.size and not np.isfinite(f.max()):
        raise ValueError(f"resid has a variance beyond 1e308 times reference_variance ({ref}): the variance ratio is "
                         "beyond the float range; reference_variance must be the baseline's residual variance")
    return f


class ResidualTest:
    """Base class of residual hypothesis tests.

    A test holds options only; :meth:`test` takes a residual series (numpy, pandas or xarray; time on
    axis 0; one column per channel) and returns a :class:`~tsfdi.detection.decision.Decision`. A test never
    imports a model: what it needs from a fitted baseline (reference variance, degrees of freedom) is passed
    as keyword arguments, and :meth:`reference` extracts those from any results object exposing the
    documented attributes (``sigma2`` or ``sigma``, ``nobs``, ``df_resid``), duck-typed.

    ``alpha`` is a type I risk, but of what depends on the test: per tested window for the windowed tests
    (:class:`~tsfdi.LjungBox`, :class:`~tsfdi.FTest`, :class:`~tsfdi.MeanTest`; of the decision over the channels
    unless ``correction="none"``), per sample and channel for the sequential ones (:class:`~tsfdi.GLRT`,
    :class:`~tsfdi.ZScore`); each test's docstring says which.
    """

    name = "residual test"
    null_hypothesis = ""
    alternative_hypothesis = ""

    def test(self, resid: Any, **kwargs: Any):  # pragma: no cover - abstract
        raise NotImplementedError

    def reference(self, results: Any) -> dict:
        """Keyword arguments for :meth:`test` taken from a fitted baseline model (none by default)."""
        return {}

    # ------------------------------------------------------------------ helpers
    @staticmethod
    def _check_alpha(alpha: Any) -> float:
        return probability(alpha, "alpha")

    @staticmethod
    def _check_correction(correction: Any) -> str:
        if correction is None:
            raise ValueError("correction must be 'sidak' (the default: alpha is the decision's false-alarm rate over "
                             "the channels), 'bonferroni' or 'none' (alpha per channel, paper 003's use), got None")
        return option(correction, "correction", ("sidak", "bonferroni", "none"))

    @staticmethod
    def _resid(resid: Any, min_nobs: int, what: str = "") -> Signal:
        """Validate residuals: finite, at least ``min_nobs`` samples (message says why)."""
        sig = as_signal(resid, "resid", allow_constant=True, min_nobs=1)
        if sig.nobs < min_nobs:
            raise ValueError(f"resid is too short: {sig.nobs} samples, at least {min_nobs} are needed{what}")
        return sig

    @staticmethod
    def _channel_alpha(alpha: float, k: int, correction: str | None) -> float:
        """Per-channel risk: ``alpha`` (``"none"``, or a test without ``correction``), ``alpha / k`` (Bonferroni) or
        ``1 - (1 - alpha)^(1/k)`` (Sidak)."""
        if correction == "bonferroni":
            return alpha / k
        if correction == "sidak":
            return -np.expm1(np.log1p(-alpha) / k)
        return alpha

    def channel_alpha(self, k: int) -> float:
        """The risk at which each of ``k`` channels is tested: ``alpha``, or its ``correction`` share
        (:meth:`family_alpha` of it is the rate of the decision "some channel rejects")."""
        return float(self._channel_alpha(self.alpha, k, getattr(self, "correction", None)))

    @staticmethod
    def family_alpha(channel_alpha: float, k: int) -> tuple[float, float]:
        r"""Size of the signal-level decision "some channel rejects" of ``k`` channels tested at
        ``channel_alpha`` each: :math:`1 - (1 - \alpha_c)^k` when the channels are independent, and the bound
        :math:`\min(1, k \alpha_c)` that holds whatever their dependence (Bonferroni)."""
        return float(-np.expm1(k * np.log1p(-channel_alpha))), float(min(1.0, k * channel_alpha))


class CalibratedTest(ResidualTest):
    """A residual test whose threshold is either its null distribution's quantile or comes from data.

    With ``threshold="theoretical"`` the critical value and p-value come from the statistic's distribution
    under H0 (:meth:`null_threshold`). With ``threshold="empirical"`` (or an :class:`~tsfdi.EmpiricalThreshold`)
    the test must be :meth:`calibrate`-d on statistics from normal operation before :meth:`test`; it then stores
    ``threshold_`` (per channel) and reports empirical p-values (Hansen et al., paper 002, Fig. 2).

    The rules are public so that a windowed engine can apply them to many statistics at once:
    :meth:`threshold_pvalue` (threshold and p-values of any array of statistics), :meth:`null_threshold` (the
    distributional critical value) and :meth:`decision` (the :class:`~tsfdi.Decision` of one statistic per
    channel); :meth:`test` is :meth:`decision` of the statistic of one window.
    """

    threshold: Any = None
    #: known degrees of freedom of the statistic's null law, fixed in the calibrated law (None: fitted)
    null_df: float | None = None
    #: how the records of a calibration differ (ScaledChi2Threshold ``shape``): ``"pooled"`` when only in scale
    null_shape: str = "record"
    alpha: float
    #: Name of the distributional threshold option, the same for every test.
    _theoretical = "theoretical"

    @property
    def min_resid(self) -> int:
        """Fewest residual samples :meth:`test` accepts (1 unless the test needs more); a window of a model of
        order ``p`` needs ``p + min_resid`` samples of the signal, its first ``p`` leaving no residual."""
        return 1

    def _threshold_option(self, threshold: Any) -> Any:
        """Validate the ``threshold`` option: ``"theoretical"``, ``"calibrated"``, ``"empirical"`` or an
        estimator (:class:`~tsfdi.EmpiricalThreshold`, :class:`~tsfdi.ScaledChi2Threshold`)."""
        if isinstance(threshold, (EmpiricalThreshold, ScaledChi2Threshold)):
            if abs(threshold.false_alarm - self.alpha) > 1e-12 * self.alpha:
                raise ValueError(f"threshold.false_alarm ({threshold.false_alarm:g}) must equal alpha "
                                 f"({self.alpha:g}): the calibrated threshold is the 1 - alpha quantile")
            return threshold
        if isinstance(threshold, str):
            return option(threshold, "threshold", (self._theoretical, "calibrated", "empirical"))
        raise TypeError(f"threshold must be {self._theoretical!r}, 'calibrated', 'empirical' or an "
                        f"EmpiricalThreshold / ScaledChi2Threshold, got {type(threshold).__name__}")

    # ------------------------------------------------------------------ rules (public)
    def null_threshold(self, k: int, nobs: int | None = None, **reference: Any) -> np.ndarray:
        """Critical value of the statistic's null distribution per channel, shape (k,) (see the subclasses)."""
        raise NotImplementedError(f"{type(self).__name__} has no null distribution")  # pragma: no cover

    def _null_pvalue(self, statistic: np.ndarray, nobs: int | None = None, **reference: Any) -> np.ndarray:
        """Upper-tail probability of ``statistic`` under the null distribution (same shape)."""
        raise NotImplementedError(f"{type(self).__name__} has no null distribution")  # pragma: no cover

    def _df(self, k: int, nobs: int, **reference: Any) -> np.ndarray:
        """Degrees of freedom per channel for :class:`~tsfdi.Decision` (``df``)."""
        raise NotImplementedError  # pragma: no cover

    def _decision_details(self, k: int, **reference: Any) -> dict:
        """Test-specific entries of ``Decision.details`` (options and per-channel alpha)."""
        return {}

    def threshold_pvalue(self, statistic: Any, nobs: int | None = None,
                         **reference: Any) -> tuple[np.ndarray, np.ndarray]:
        r"""Threshold and p-values of statistics of this test, channels on the last axis.

        The single rule behind :meth:`test` and :meth:`decision`, applicable to a whole array of window
        statistics (e.g. :meth:`window_statistic`) at once.

        Parameters
        ----------
        statistic : array_like, shape (..., k)
            Values of the test statistic (Ljung-Box :math:`Q`, F test variance ratio :math:`F`), one column
            per channel.
        nobs : int, optional
            Number of residual samples behind each statistic (one window). Needed by the F test's
            distributional threshold (:math:`N_u`); not used by the Ljung-Box test nor by a calibrated
            (empirical) threshold.
        **reference :
            What the null distribution needs from the baseline model, as given by :meth:`reference` (the F
            test's ``reference_df``, :math:`N_0 - d`); ignored by the empirical threshold.

        Returns
        -------
        threshold : ndarray, shape (k,)
            Critical value per channel; a channel rejects when its statistic exceeds it.
        pvalue : ndarray, shape of ``statistic``
            p-value of every statistic.

        Raises
        ------
        ValueError
            If ``statistic`` holds NaN; with the empirical threshold, if the test is not calibrated or was calibrated
            on another number of channels.

        Notes
        -----
        ``threshold="theoretical"``: :meth:`null_threshold` and the upper-tail probability of the null
        distribution -- for the Ljung-Box test :math:`\chi^2_{1-\alpha}(r - \text{model\_df})` and
        :math:`P(\chi^2(r - \text{model\_df}) > Q)` (Dutta et al., paper 003, eqs. 13-14); for the F test
        :math:`f_{1-\alpha}(N_u, N_0 - d)` and :math:`P(\mathcal F(N_u, N_0 - d) > F)` (eqs. 9-10, one-sided;
        the two-sided rule is in :meth:`decision`), at each channel's share of ``alpha`` (``correction``: Sidak
        :math:`1 - (1 - \alpha)^{1/k}` by default, ``alpha / k`` with ``"bonferroni"``, ``alpha`` with ``"none"``).

        ``threshold="empirical"``: the calibrated ``threshold_`` and the empirical p-value
        :math:`p = (1 + \#\{s_i \ge s\}) / (n + 1)` of the calibration sample (:meth:`calibrate`; Hansen et
        al., paper 002, Fig. 2).

        A statistic of ``inf`` (the Ljung-Box :math:`Q` of a constant window, a frozen sensor) exceeds every
        threshold and has p-value 0 with either threshold.
        """
        s = statistic_array(statistic)
        if s.ndim == 0 or s.shape[-1] == 0:
            raise ValueError(f"statistic must have one column per channel, got shape {s.shape}")
        if np.isnan(s).any():
            raise ValueError(f"statistic contains {int(np.isnan(s).sum())} NaN value(s)")
        k = s.shape[-1]
        if self.empirical:
            self._check_calibrated(k, nobs)
            return self.threshold_, self.calibrated_pvalue(s)
        return self.null_threshold(k, nobs, **reference), self._null_pvalue(s, nobs, **reference)

    def decision(self, statistic: Any, nobs: int, channels: Any = None, *, details: dict | None = None,
                 **reference: Any) -> Decision:
        r"""The :class:`~tsfdi.Decision` of one statistic per channel (what :meth:`test` returns).

        Parameters
        ----------
        statistic : array_like, shape (k,)
            The test statistic of one window, one value per channel.
        nobs : int
            Number of residual samples it was computed from.
        channels : sequence of str, optional
            Channel names (default ``y0, y1, ...``).
        details : dict, optional
            Extra entries placed first in ``Decision.details`` (e.g. the F test's window variances).
        **reference :
            As for :meth:`threshold_pvalue` (the F test's ``reference_df``; ``reference_variance`` is reported
            in the details).

        Returns
        -------
        Decision
            Channel ``c`` rejects when ``statistic[c] > threshold[c]`` (:meth:`threshold_pvalue`); the signal
            rejects when any channel rejects (a statistic of ``inf``, a constant window, rejects with p-value 0).
            ``details["threshold_method"]`` is ``"theoretical"`` or ``"empirical"`` (then with the calibration's
            details).

        Notes
        -----
        Ljung-Box: accept H0 when :math:`Q \le \chi^2_{1-\alpha}(r - \text{model\_df})` (Dutta et al., paper
        003, eq. 14). F test: accept H0 when :math:`F \le f_{1-\alpha}(N_u, N_0 - d)` (eq. 10).
        """
        stat = np.atleast_1d(statistic_array(statistic))
        if stat.ndim != 1:
            raise ValueError(f"statistic must hold one value per channel, got shape {stat.shape}")
        k = stat.shape[0]
        thr, pv = self.threshold_pvalue(stat, nobs, **reference)
        info = dict(details) if details else {}
        info.update(self._decision_details(k, **reference))
        info.update(self._calibration_details() if self.empirical else {"threshold_method": self._theoretical})
        info["family_alpha"], info["family_alpha_bound"] = self.family_alpha(
            self._channel_alpha(self.alpha, k, getattr(self, "correction", None)), k)
        rej = stat > thr
        return Decision(statistic=stat, threshold=thr, pvalue=pv, alpha=self.alpha, reject=bool(rej.any()),
                        df=self._df(k, nobs, **reference), nobs=nobs, null_hypothesis=self.null_hypothesis,
                        alternative_hypothesis=self.alternative_hypothesis, details=info, channel_reject=rej,
                        channels=tuple(channels) if channels is not None else (), test=type(self).__name__)

    def _threshold_name(self) -> str:
        """The threshold option as a name (an estimator object by its kind)."""
        if isinstance(self.threshold, str):
            return self.threshold
        return "calibrated" if isinstance(self.threshold, ScaledChi2Threshold) else "empirical"

    @property
    def empirical(self) -> bool:
        """Whether the threshold comes from data (``"calibrated"`` or ``"empirical"``, :meth:`calibrate`) rather
        than the null distribution."""
        return not isinstance(self.threshold, str) or self.threshold != self._theoretical

    @property
    def calibrated(self) -> bool:
        """Whether :meth:`calibrate` has been run."""
        return hasattr(self, "threshold_")

    def window_statistic(self, resid: Any, window: int, step: int = 1, **reference: Any) -> np.ndarray:
        """Statistic of every sliding window of a residual record, shape ``(n_windows, k)``."""
        raise NotImplementedError(f"{type(self).__name__} has no windowed statistic")  # pragma: no cover

    def calibrate(self, resid: Any = None, *, window: int | None = None, step: int = 1, statistic: Any = None,
                  independent: int | None = None, **reference: Any) -> ResidualTest:
        r"""Set the per-channel threshold from the statistic under normal operation; returns ``self``.

        Parameters
        ----------
        resid : array_like, Series, DataFrame, DataArray or sequence of them, optional
            Healthy residual records, each ``(nobs, k)``: residuals of records driven through a model that was
            *not* fitted on them, like the data the test will see -- the held-out residuals of
            :meth:`tsfdi.VAR.held_out_residuals` (each record through the model fitted on the others). The
            statistic of every window of every record is the null sample.
        window : int
            Window length. With held-out residuals of a model spec (which carry the model's order ``lags``) it
            counts *signal* samples, as in :func:`tsfdi.detect` (a window of ``window`` signal samples has
            ``window - lags`` residuals); for other residual records it counts residual samples. With
            ``statistic``: the residual samples behind each value (optional). The calibrated threshold holds for
            windows of that length only: :meth:`test` (and :func:`tsfdi.detect`) refuse residuals of another
            length, saying which window to test (:func:`tsfdi.identify_windows`, :class:`tsfdi.Monitor`) or to
            calibrate at.
        step : int
            Samples between calibration windows (1: every window; overlapping windows are dependent, see Notes).
        statistic : array_like, shape (n,) or (n, k), optional
            The null sample itself (instead of ``resid``): values of the test statistic under normal operation,
            one column per channel.
        independent : int, optional
            With ``statistic``: how many of its windows do not overlap (default all).
        **reference :
            Extra keyword arguments of the windowed statistic (the F test's ``reference_variance``).

        Returns
        -------
        self
            With ``threshold_`` (ndarray, shape (k,)), ``thresholds_`` (one fitted estimator per channel),
            ``calibration_`` (the sorted null sample per channel) and ``calibration_window_`` (``(residual samples
            per window, model order)``, ``None`` when unknown: ``statistic`` without ``window``). A test built with ``threshold="theoretical"``
            becomes ``threshold="calibrated"``.

        Raises
        ------
        ValueError
            If the null sample is too small for the per-channel ``alpha`` (the message says how many
            independent windows are needed).

        Notes
        -----
        Hansen et al. (paper 002, Fig. 2) take the threshold from the distribution of the detection statistic in
        normal operation for a required false-alarm probability. Two estimators of the per-channel
        :math:`1 - \alpha` quantile (:meth:`_channel_alpha` with ``correction``):

        - ``threshold="calibrated"`` (or ``"theoretical"`` before calibration): scaled chi-square laws
          :math:`c_j\,\chi^2(\nu_j)` fitted to each record's windows by their first two moments, mixed over the
          records, with a bootstrap bound over records (:class:`~tsfdi.ScaledChi2Threshold`); it reaches
          ``alpha = 1e-3`` from a few hundred windows of a few records;
        - ``threshold="empirical"``: the empirical quantile, or a generalised Pareto tail fit
          (:class:`~tsfdi.EmpiricalThreshold`), with the empirical p-value
          :math:`p = (1 + \#\{s_i \ge s\}) / (n + 1)`; it needs about ``20 / alpha`` windows.

        Windows ``step`` apart overlap when ``step < window``: they are dependent, which leaves the moments and
        quantiles consistent but does not add information, so the support checks count the non-overlapping
        windows (``floor(len / window)`` per record). The signal-level decision "some channel rejects" has size
        ``Decision.details["family_alpha"]`` (:meth:`family_alpha`); ``correction="sidak"`` (the default) or
        ``"bonferroni"`` make it at most ``alpha``, ``"none"`` up to ``1 - (1 - alpha)^k``.
        """
        if getattr(self, "alternative", "greater") != "greater":
            raise ValueError("calibrate needs alternative='greater': the calibrated threshold is one upper quantile")
        if statistic is None:
            if resid is None:
                raise TypeError("calibrate needs resid (healthy residual records) or statistic")
            if window is None:
                raise TypeError("calibrate needs window (samples per window) with resid")
            lags = int(getattr(resid, "lags", 0) or 0)
            recs = list(resid) if isinstance(resid, (list, tuple)) else [resid]
            if not recs:
                raise ValueError("resid is an empty sequence")
            window = int_like(window, "window", minimum=1)
            n = window - lags
            if n < 2:
                raise ValueError(f"window ({window}) must exceed the model order of the held-out residuals ({lags}) "
                                 "by at least 2")
            reference = self._calibration_reference(recs, reference)
            stats_, groups, per_record = [], [], []
            for i, r in enumerate(recs):
                sig = as_signal(r, f"resid[{i}]", allow_constant=True)
                if sig.nobs < n:
                    continue                                   # a record shorter than one window gives none
                refuse_constant_stretch(sig, n, f"resid[{i}]" if isinstance(resid, (list, tuple)) else "resid")
                stats_.append(np.asarray(self.window_statistic(r, n, step, **reference)))
                groups.append(np.full(stats_[-1].shape[0], i))
                per_record.append(sig.nobs // n)
            if not stats_:
                raise ValueError(f"resid: no record holds a window of {n} residual samples")
            cal, names = (n, lags), sig.channels
            stat = np.concatenate(stats_)
            groups = np.concatenate(groups) if len(stats_) > 1 else None
            n_ind = per_record if len(stats_) > 1 else per_record[0]
        else:
            if resid is not None:
                raise TypeError("give resid or statistic, not both")
            sig = as_signal(statistic, "statistic", allow_constant=True)
            stat, names = sig.values, sig.channels
            n_ind = int_like(independent, "independent", minimum=0, optional=True)
            groups = None
            # the statistic's window (residual samples), when given: the threshold then holds for that length only
            cal = None if window is None else (int_like(window, "window", minimum=2), 0)
        stat = np.asarray(stat, dtype=np.float64)
        stat = stat.reshape(stat.shape[0], -1)
        k = stat.shape[1]
        if len(names) != k:                                 # the joint statistic of a multivariate test
            names = ("joint",) if k == 1 else tuple(f"y{c}" for c in range(k))
        if self.threshold == self._theoretical:
            self.threshold = "calibrated"
        a = self._channel_alpha(self.alpha, k, getattr(self, "correction", None))
        if isinstance(self.threshold, (EmpiricalThreshold, ScaledChi2Threshold)):
            tpl = self.threshold
        else:
            tpl = ScaledChi2Threshold(a) if self.threshold == "calibrated" else EmpiricalThreshold(a)
        if isinstance(tpl, ScaledChi2Threshold):
            have = stat.shape[0] if n_ind is None else int(np.sum(n_ind))
            if have < tpl.min_windows:
                held = (f"resid (the healthy records, windows of {cal[0]} residual samples)" if resid is not None
                        else "statistic")
                raise ValueError(
                    f"{held} holds {have} independent (non-overlapping) windows, at least {tpl.min_windows} are needed "
                    f"(min_windows) to fit the calibrated null law of {type(self).__name__}: give more or longer "
                    "healthy records (or shorter windows), or lower the bound with "
                    "threshold=ScaledChi2Threshold(alpha, min_windows=...) (command line: --min-windows), at least 5")
        ths = []
        for c in range(k):
            est = copy.copy(tpl)
            est.false_alarm = a
            if isinstance(est, ScaledChi2Threshold) and est.df is None:
                est.df = self.null_df                  # the statistic's known degrees of freedom, if any
            if isinstance(est, ScaledChi2Threshold) and est.shape is None:
                est.shape = self.null_shape
            for attr in [v for v in vars(est) if v.endswith("_")]:
                est.__dict__.pop(attr, None)
            try:
                if isinstance(est, ScaledChi2Threshold):
                    est.calibrate(stat[:, c], independent=n_ind, groups=groups)
                else:
                    est.calibrate(stat[:, c])
            except ValueError as err:
                raise ValueError(f"{type(self).__name__}.calibrate, channel {names[c]!r}: {err}") from None
            ths.append(est)
        self.thresholds_ = ths
        self.threshold_ = np.array([t.threshold_ for t in ths])
        self.calibration_ = [t.sample_ for t in ths]
        self.calibration_windows_ = (int(stat.shape[0]), int(np.sum(n_ind)) if n_ind is not None else None)
        self.calibration_window_ = cal
        return self

    def calibrated_for(self, models: Any, *, window: int, step: int = 1) -> dict:
        """A copy of this test per fitted model, each calibrated on that model's held-out residuals.

        One threshold per model, so that ``alpha`` holds on new records of every model's state (paper 002,
        Fig. 2): for each model, ``copy.deepcopy(test).calibrate(res.model.held_out_residuals(), window=window,
        step=step)`` -- each record the model was fitted on through the model fitted on the others, a single record
        cut into 10 blocks (:meth:`tsfdi.VAR.held_out_residuals`). The result is the ``test`` mapping of
        :func:`tsfdi.identify_windows` and :class:`tsfdi.Monitor` (what ``tsfdi identify / monitor --threshold
        calibrated`` use).

        Parameters
        ----------
        models : mapping
            Name -> fitted results that carry the records they were fitted on (as fitted, or read by
            :func:`tsfdi.load`): AR, VAR, ARX, or a functionally pooled model's point ``FPResults.at(k)``, whose
            held-out residuals are the FP model's.
        window : int
            Signal samples per tested window (a window of ``window`` samples has ``window - lags`` residuals, see
            :meth:`calibrate`); the thresholds hold for that length only.
        step : int
            Samples between calibration windows.

        Returns
        -------
        dict
            Name -> calibrated copy of this test; this test is not modified.

        Raises
        ------
        ValueError
            ``models['name']: ...`` when a model's held-out residuals hold too few windows, with the size of that
            null sample and the fix (more or longer healthy records, or shorter windows).

        Examples
        --------
        >>> models = {"rotor1": tsfdi.load("rotor1.npz"), "rotor2": tsfdi.load("rotor2.npz")}  # doctest: +SKIP
        >>> tests = tsfdi.LjungBox(lags=20, alpha=1e-3).calibrated_for(models, window=200)     # doctest: +SKIP
        >>> tsfdi.identify_windows(flight, models, tests, window=200, step=100)                 # doctest: +SKIP
        """
        if not hasattr(models, "items"):
            raise TypeError(f"models must be a mapping name -> fitted results, got {type(models).__name__}")
        out = {}
        for name, res in models.items():
            spec = getattr(res, "model", None)
            if not hasattr(spec, "held_out_residuals"):
                raise TypeError(f"models[{name!r}] must be fitted results whose model has held_out_residuals (AR, "
                                f"VAR, ARX, FPResults.at(k)), got {type(res).__name__}")
            try:
                out[name] = copy.deepcopy(self).calibrate(spec.held_out_residuals(), window=window, step=step)
            except ValueError as exc:
                recs = spec.records
                cut = (f"; a single record is cut into 10 blocks of about {recs[0].nobs // 10} samples, each held out "
                       "in turn" if len(recs) == 1 else "")
                raise ValueError(f"models[{name!r}]: {exc} (the null sample: held-out residuals of the {len(recs)} "
                                 f"record(s), {sum(r.nobs for r in recs)} samples, the model was fitted on{cut}); fit "
                                 "the model on more or longer healthy records (several flights), or test shorter "
                                 "windows") from None
        return out

    def _calibration_reference(self, recs: list, reference: dict) -> dict:
        """What the windowed statistic needs on the calibration records (the F test's reference variance)."""
        return reference

    def _check_calibrated(self, k: int, nobs: int | None = None) -> None:
        """A calibrated threshold exists for ``k`` channels and, when the calibration window is known, holds for
        windows of ``nobs`` residual samples (the length it was calibrated at)."""
        if not self.calibrated:
            raise ValueError(f"{type(self).__name__} has threshold='empirical' but is not calibrated: call "
                             "calibrate(healthy residuals, window=...) first")
        if self.threshold_.shape[0] != k:
            raise ValueError(f"resid has {k} channel(s) but the test was calibrated on {self.threshold_.shape[0]}")
        cal = getattr(self, "calibration_window_", None)
        if nobs is not None and cal is not None and int(nobs) != cal[0]:
            n, lags = cal
            name = type(self).__name__
            model = f" of an order-{lags} model, window={n + lags} signal samples" if lags else ""
            raise ValueError(
                f"resid has {int(nobs)} samples but {name} was calibrated on windows of {n} residual samples{model}: "
                "a calibrated threshold holds for windows of its calibrated length only. Test windows of that length "
                f"(tsfdi.identify_windows(..., window={n + lags}) or tsfdi.Monitor(..., window={n + lags}), or detect "
                f"on {n + lags} samples), or calibrate at the tested length ({name}.calibrate(..., "
                f"window={int(nobs) + lags}))")

    def calibrated_pvalue(self, statistic: Any) -> np.ndarray:
        """p-value of ``statistic`` (per channel, last axis) under the calibrated null: the fitted law's upper tail
        (``"calibrated"``) or the empirical exceedance fraction ``(1 + #{s_i >= s}) / (n + 1)`` (``"empirical"``)."""
        s = np.asarray(statistic, dtype=np.float64)
        k = self.threshold_.shape[0]
        s2 = s.reshape(-1, k)
        out = np.empty_like(s2)
        for c, est in enumerate(self.thresholds_):
            out[:, c] = est.pvalue(s2[:, c])
        return np.where(s2 == np.inf, 0.0, out).reshape(s.shape)   # a constant window: beyond any calibration

    def _calibration_details(self) -> dict:
        method = self.thresholds_[0].method_ if isinstance(self.thresholds_[0], ScaledChi2Threshold) else None
        out = {"threshold_method": "calibrated" if method == "scaled-chi2" else "empirical",
               "threshold_estimate": [t.method_ for t in self.thresholds_],
               "calibration_size": int(self.calibration_[0].size),
               "calibration_independent": self.calibration_windows_[1]}
        if method == "scaled-chi2":
            out["null_law"] = [{"scale": t.scale_, "df": t.df_} for t in self.thresholds_]
            out["calibration_records"] = self.thresholds_[0].records_
            out["calibration_effective"] = [t.effective_windows_ for t in self.thresholds_]
            if self.thresholds_[0].record_law_ is not None:
                out["record_law"] = [t.record_law_ for t in self.thresholds_]
                out["pvalue_method"] = ("calibrated: predictive over a new record's log-scale (Student t from the "
                                        "records) of P(exp(L) chi2(nu) / nu > statistic)")
            else:
                out["pvalue_method"] = "calibrated: mixture over records of P(chi2(df_j) > statistic / scale_j)"
        else:
            out["pvalue_method"] = "empirical: (1 + #{calibration >= statistic}) / (n + 1)"
        return out


def refuse_constant_stretch(sig: Signal, length: int, name: str) -> None:
    """Refuse a healthy calibration record holding a constant stretch (a frozen sensor) of at least ``length``
    samples -- a whole window -- in some channel: ``ValueError`` naming the record, the channel and where the stretch
    is. The one rule of every calibrated test (a Ljung-Box :math:`Q` of such a window is ``inf``; the F and mean-shift
    statistics are finite there and would silently lower or shift the calibrated law)."""
    x = sig.values
    if length < 2 or x.shape[0] < length:
        return
    same = x[1:] == x[:-1]              # a run [a, b) of same[:, c] is the stretch [a, b + 1) of equal samples
    found = [next(((a, b + 1, c) for a, b in runs(same[:, c]) if b + 1 - a >= length), None)
             for c in range(x.shape[1])]
    found = [f for f in found if f is not None]
    if found:
        a, b, c = min(found)
        raise ValueError(f"{name} holds a constant stretch (a frozen sensor) of {b - a} samples in channel "
                         f"{sig.channels[c]!r} at samples [{a}, {b}): healthy calibration records must not contain a "
                         f"constant stretch as long as a window ({length} samples); cut it out (split the record "
                         "there) or leave the record out")


def statistic_array(statistic: Any) -> np.ndarray:
    """Values of a test statistic as a float array (``TypeError`` naming ``statistic`` for anything else)."""
    if isinstance(statistic, (str, bytes)):
        raise TypeError(f"statistic must be numbers, got {statistic!r}")
    try:
        return np.asarray(statistic, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"statistic must be numbers, got {type(statistic).__name__}") from None


class ReferenceVarianceTest(CalibratedTest):
    """A calibrated test whose statistic divides by a reference (baseline) residual variance per channel: the F
    test and the mean-shift test. Calibrated on held-out residuals without a baseline variance, it divides by the
    pooled mean square of those residuals (the calibrated law absorbs the scale)."""

    def _calibration_reference(self, recs: list, reference: dict) -> dict:
        """The variance the calibrated test divides by, kept as ``reference_variance_``: the given
        ``reference_variance`` (a baseline's), else the pooled mean square of the calibration residuals per
        channel (held-out residuals need no baseline variance: the calibrated law absorbs the scale)."""
        ref = reference.get("reference_variance")
        sigs = [self._resid(r, 2) for r in recs]
        if ref is None:
            if len({s.nchan for s in sigs}) > 1:
                raise ValueError(f"resid: every record must have the same channels, got {[s.nchan for s in sigs]}")
            scale = np.max([rescale_exponent(s.values) for s in sigs], axis=0)      # exact rescaling, see Notes
            ss = 0.0
            for s in sigs:
                v = np.ldexp(s.values, -scale)
                ss = ss + np.einsum("ij,ij->j", v, v)
            with np.errstate(over="ignore"):
                ref = np.ldexp(ss / sum(s.nobs for s in sigs), 2 * scale)
            if not np.all((ref > 0) & np.isfinite(ref)):
                raise ValueError(f"resid: the mean square of the calibration residuals ({ref}) is 0 or beyond the "
                                 "float range in some channel; give reference_variance or rescale the residuals")
        self.reference_variance_ = per_channel(ref, "reference_variance", sigs[0].nchan)
        return {**reference, "reference_variance": self.reference_variance_}


def baseline_variance(results: Any) -> tuple[np.ndarray, np.ndarray]:
    """Unbiased residual variance per channel and its degrees of freedom from a fitted AR/VAR result.

    Results store the maximum-likelihood variance ``RSS / nobs`` (``sigma2`` for a scalar model, the
    diagonal of ``sigma`` for a vector model). Dutta et al. (eq. 9) need the estimator with
    ``(N0 - d) * sigma00^2 / sigma^2 ~ chi2(N0 - d)``, so it is converted to ``RSS / (N0 - d)`` with
    ``N0 - d = df_resid`` (for a VAR, ``d`` is the number of parameters per equation).
    """
    if hasattr(results, "sigma") and np.ndim(getattr(results, "sigma")) == 2:
        ml = np.diag(np.asarray(results.sigma, dtype=np.float64))
    elif hasattr(results, "sigma2"):
        ml = np.atleast_1d(np.asarray(results.sigma2, dtype=np.float64))
    else:
        raise TypeError("baseline must be fitted results with `sigma2` (scalar) or `sigma` (vector), got "
                        f"{type(results).__name__}")
    nobs = float(results.nobs)
    df_resid = float(results.df_resid)
    if df_resid <= 0:
        raise ValueError(f"baseline has no residual degrees of freedom (df_resid = {df_resid})")
    unbiased = ml * nobs / df_resid
    return unbiased, np.full(ml.shape, df_resid)


def per_channel(value: Any, name: str, k: int) -> np.ndarray:
    """A positive finite scalar or one value per channel, as a ``(k,)`` float array."""
    if type(value) is np.ndarray and value.dtype == np.float64 and value.shape == (k,):
        arr = value                                     # the common case, from a baseline: no conversion
    else:
        if isinstance(value, (str, bytes, bool, np.bool_)):
            raise TypeError(f"{name} must be a positive number or one per channel, got {value!r}")
        try:
            arr = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be a positive number or one per channel, got {value!r}") from None
        if arr.ndim == 0:
            arr = np.full(k, float(arr))
        if arr.shape != (k,):
            raise ValueError(f"{name} must be a scalar or have one value per channel ({k}), got shape {arr.shape}")
    if not ((arr > 0) & (arr < np.inf)).all():          # NaN fails both comparisons
        raise ValueError(f"{name} must be finite and > 0, got {arr}")
    return arr

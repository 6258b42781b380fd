"""Shared base of the residual tests: validation of residuals and options, the fitted-model hook."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from tsfdi._data import Signal, as_signal
from tsfdi._validation import option, probability
from tsfdi.detection.decision import Decision
from tsfdi.detection.threshold import EmpiricalThreshold

__all__ = ["CalibratedTest", "ResidualTest"]


class ResidualTest:
    """Base class of residual hypothesis tests.

    A test holds options only; :meth:`test` takes a residual series (numpy, pandas or xarray; time on
    axis 0; one column per channel) and returns a :class:`~tsfdi.detection.decision.Decision`. A test never
    imports a model: what it needs from a fitted baseline (reference variance, degrees of freedom) is passed
    as keyword arguments, and :meth:`reference` extracts those from any results object exposing the
    documented attributes (``sigma2`` or ``sigma``, ``nobs``, ``df_resid``), duck-typed.

    ``alpha`` is a type I risk, but of what depends on the test: per tested window (per channel) for the windowed
    tests (:class:`~tsfdi.LjungBox`, :class:`~tsfdi.FTest`), per sample for the sequential ones
    (:class:`~tsfdi.GLRT`, :class:`~tsfdi.ZScore`); each test's docstring says which.
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
    def _check_correction(correction: Any) -> str | None:
        if correction is None:
            return None
        return option(correction, "correction", ("bonferroni",))

    @staticmethod
    def _resid(resid: Any, min_nobs: int, what: str = "") -> Signal:
        """Validate residuals: finite, at least ``min_nobs`` samples (message says why)."""
        sig = as_signal(resid, "resid", allow_constant=True, min_nobs=1)
        if sig.nobs < min_nobs:
            raise ValueError(f"resid is too short: {sig.nobs} samples, at least {min_nobs} are needed{what}")
        return sig

    @staticmethod
    def _channel_alpha(alpha: float, k: int, correction: str | None) -> float:
        return alpha / k if correction == "bonferroni" else alpha


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
    alpha: float
    #: Name of the distributional threshold option, the same for every test.
    _theoretical = "theoretical"

    def _threshold_option(self, threshold: Any) -> Any:
        """Validate the ``threshold`` option: ``"theoretical"``, ``"empirical"`` or an EmpiricalThreshold."""
        if isinstance(threshold, EmpiricalThreshold):
            if abs(threshold.false_alarm - self.alpha) > 1e-12 * self.alpha:
                raise ValueError(f"threshold.false_alarm ({threshold.false_alarm:g}) must equal alpha "
                                 f"({self.alpha:g}): the calibrated threshold is the 1 - alpha quantile")
            return threshold
        if isinstance(threshold, str):
            return option(threshold, "threshold", (self._theoretical, "empirical"))
        raise TypeError(f"threshold must be {self._theoretical!r}, 'empirical' or an EmpiricalThreshold, got "
                        f"{type(threshold).__name__}")

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
            With the empirical threshold, if the test is not calibrated or was calibrated on another number
            of channels.

        Notes
        -----
        ``threshold="theoretical"``: :meth:`null_threshold` and the upper-tail probability of the null
        distribution -- for the Ljung-Box test :math:`\chi^2_{1-lpha}(r - 	ext{model\_df})` and
        :math:`P(\chi^2(r - 	ext{model\_df}) > Q)` (Dutta et al., paper 003, eqs. 13-14); for the F test
        :math:`f_{1-lpha}(N_u, N_0 - d)` and :math:`P(\mathcal F(N_u, N_0 - d) > F)` (eqs. 9-10, one-sided;
        the two-sided rule is in :meth:`decision`). ``alpha`` is the type I risk per tested window and channel
        (``alpha / k`` with ``correction="bonferroni"``).

        ``threshold="empirical"``: the calibrated ``threshold_`` and the empirical p-value
        :math:`p = (1 + \#\{s_i \ge s\}) / (n + 1)` of the calibration sample (:meth:`calibrate`; Hansen et
        al., paper 002, Fig. 2).
        """
        s = np.asarray(statistic, dtype=np.float64)
        k = s.shape[-1]
        if self.empirical:
            self._check_calibrated(k)
            return self.threshold_, self.empirical_pvalue(s)
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
            rejects when any channel rejects. ``details["threshold_method"]`` is ``"theoretical"`` or
            ``"empirical"`` (then with the calibration's details).

        Notes
        -----
        Ljung-Box: accept H0 when :math:`Q \le \chi^2_{1-lpha}(r - 	ext{model\_df})` (Dutta et al., paper
        003, eq. 14). F test: accept H0 when :math:`F \le f_{1-lpha}(N_u, N_0 - d)` (eq. 10).
        """
        stat = np.array(statistic, dtype=np.float64, ndmin=1)
        if stat.ndim != 1:
            raise ValueError(f"statistic must hold one value per channel, got shape {stat.shape}")
        k = stat.shape[0]
        thr, pv = self.threshold_pvalue(stat, nobs, **reference)
        info = dict(details) if details else {}
        info.update(self._decision_details(k, **reference))
        info.update(self._empirical_details() if self.empirical else {"threshold_method": self._theoretical})
        rej = stat > thr
        return Decision(statistic=stat, threshold=thr, pvalue=pv, alpha=self.alpha, reject=bool(rej.any()),
                        df=self._df(k, nobs, **reference), nobs=nobs, null_hypothesis=self.null_hypothesis,
                        alternative_hypothesis=self.alternative_hypothesis, details=info, channel_reject=rej,
                        channels=tuple(channels) if channels is not None else (), test=type(self).__name__)

    @property
    def empirical(self) -> bool:
        """Whether the threshold comes from data (:meth:`calibrate`) rather than the null distribution."""
        return not isinstance(self.threshold, str) or self.threshold == "empirical"

    @property
    def calibrated(self) -> bool:
        """Whether :meth:`calibrate` has been run."""
        return hasattr(self, "threshold_")

    def window_statistic(self, resid: Any, window: int, step: int = 1, **reference: Any) -> np.ndarray:
        """Statistic of every sliding window of a residual record, shape ``(n_windows, k)``."""
        raise NotImplementedError(f"{type(self).__name__} has no windowed statistic")  # pragma: no cover

    def calibrate(self, resid: Any = None, *, window: int | None = None, step: int = 1, statistic: Any = None,
                  **reference: Any) -> ResidualTest:
        r"""Estimate the per-channel threshold from the statistic under normal operation; returns ``self``.

        Parameters
        ----------
        resid : array_like, Series, DataFrame, DataArray or sequence of them, optional
            Healthy (in-state) residual records, each ``(nobs, k)``: residuals of *new* records driven through
            the fixed model (out of sample, like the data the test will see). The statistic of every window of
            ``window`` samples, ``step`` apart, of every record is the calibration sample.
        window : int
            Window length in residual samples (required with ``resid``).
        step : int
            Samples between calibration windows.
        statistic : array_like, shape (n,) or (n, k), optional
            The calibration sample itself (instead of ``resid``): values of the test statistic under
            normal operation, one column per channel.
        **reference :
            Extra keyword arguments of the windowed statistic (the F test's ``reference_variance``).

        Returns
        -------
        self
            With ``threshold_`` (ndarray, shape (k,)), ``thresholds_`` (one calibrated
            :class:`~tsfdi.EmpiricalThreshold` per channel) and ``calibration_`` (the sorted sample per
            channel, for the empirical p-value).

        Raises
        ------
        ValueError
            If the test was built with the distributional threshold, or if the sample is too small for the
            per-channel ``alpha`` (the message says how many statistics are needed).

        Notes
        -----
        Hansen et al. (paper 002, Fig. 2) take the threshold from the empirical distribution of the detection
        statistic in normal operation. Channel ``c`` rejects when its statistic exceeds the :math:`1-\alpha`
        quantile of its calibration sample (a generalised Pareto tail fit when the sample holds fewer than
        ``min_exceedances / alpha`` values, see :class:`~tsfdi.EmpiricalThreshold`). The p-value is the
        empirical exceedance fraction with the usual +1 correction,
        :math:`p = (1 + \#\{s_i \ge s\}) / (n + 1)`. Windows that overlap are dependent, so the effective
        sample is smaller than ``n``: calibrate on many records.
        """
        if not self.empirical:
            raise ValueError(f"threshold is {self.threshold!r}: build the test with threshold='empirical' (or an "
                             "EmpiricalThreshold) to calibrate it")
        if statistic is None:
            if resid is None:
                raise TypeError("calibrate needs resid (healthy residual records) or statistic")
            if window is None:
                raise TypeError("calibrate needs window (residual samples per window) with resid")
            recs = list(resid) if isinstance(resid, (list, tuple)) else [resid]
            if not recs:
                raise ValueError("resid is an empty sequence")
            stat = np.concatenate([np.asarray(self.window_statistic(r, window, step, **reference)) for r in recs])
        else:
            if resid is not None:
                raise TypeError("give resid or statistic, not both")
            stat = as_signal(statistic, "statistic", allow_constant=True).values
        stat = np.asarray(stat, dtype=np.float64)
        stat = stat.reshape(stat.shape[0], -1)
        k = stat.shape[1]
        a = self._channel_alpha(self.alpha, k, getattr(self, "correction", None))
        tpl = self.threshold if isinstance(self.threshold, EmpiricalThreshold) else EmpiricalThreshold(a)
        ths = []
        for c in range(k):
            et = copy.copy(tpl)
            et.false_alarm = a
            for attr in ("threshold_", "sample_", "gpd_", "method_", "nobs_"):
                et.__dict__.pop(attr, None)
            try:
                et.calibrate(stat[:, c])
            except ValueError as err:
                raise ValueError(f"statistic (calibration sample of channel {c}) is too small: {err}") from None
            ths.append(et)
        self.thresholds_ = ths
        self.threshold_ = np.array([t.threshold_ for t in ths])
        self.calibration_ = [t.sample_ for t in ths]
        return self

    def _check_calibrated(self, k: int) -> None:
        if not self.calibrated:
            raise ValueError(f"{type(self).__name__} has threshold='empirical' but is not calibrated: call "
                             "calibrate(healthy residuals, window=...) first")
        if self.threshold_.shape[0] != k:
            raise ValueError(f"resid has {k} channel(s) but the test was calibrated on {self.threshold_.shape[0]}")

    def empirical_pvalue(self, statistic: Any) -> np.ndarray:
        """Fraction of calibration statistics at or above ``statistic`` (per channel, last axis), with the +1
        correction: ``(1 + #{s_i >= s}) / (n + 1)``."""
        s = np.asarray(statistic, dtype=np.float64)
        k = self.threshold_.shape[0]
        s2 = s.reshape(-1, k)
        out = np.empty_like(s2)
        for c, g in enumerate(self.calibration_):
            ge = g.size - np.searchsorted(g, s2[:, c], side="left")
            out[:, c] = (1.0 + ge) / (g.size + 1.0)
        return out.reshape(s.shape)

    def _empirical_details(self) -> dict:
        return {"threshold_method": "empirical",
                "threshold_estimate": [t.method_ for t in self.thresholds_],
                "calibration_size": int(self.calibration_[0].size),
                "pvalue_method": "empirical: (1 + #{calibration >= statistic}) / (n + 1)"}


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

"""Combined residual tests: "a part rejects" with the parts sharing ``alpha`` (issue 31)."""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

from tsfdi._data import as_signal
from tsfdi._validation import option
from tsfdi.detection.base import CalibratedTest, ResidualTest, refuse_constant_stretch
from tsfdi.detection.decision import Decision
from tsfdi.detection.threshold import ScaledChi2Threshold

__all__ = ["AnyOf"]

#: the smallest p-value used in ``-2 log p`` (a p-value of 0: a constant window)
_P_FLOOR = 1e-300


class AnyOf(ResidualTest):
    r"""Combined residual test: rejects when one of its parts rejects, the parts sharing ``alpha``.

    ``AnyOf([LjungBox(20, alpha=0.01, correction="sidak"), FTest(alpha=0.01, correction="sidak"),
    MeanTest(alpha=0.01, correction="sidak")])`` flags a window when its residuals are autocorrelated, or their
    variance or mean moved, with the rate of a healthy window's false alarm equal to ``alpha`` (whiteness, variance
    and mean together detect the CrazyPAD propeller damage, ``benchmarks/crazypad.py``).

    Parameters
    ----------
    tests : sequence of CalibratedTest
        At least two windowed tests (:class:`~tsfdi.LjungBox`, :class:`~tsfdi.FTest`, :class:`~tsfdi.MeanTest`),
        all with the same ``alpha`` and the same ``correction``, not yet calibrated. They are copied; the copies
        test at their share of ``alpha`` (``tests``).
    correction : {"sidak", "bonferroni", "minp"}
        How the parts share ``alpha``: ``"sidak"`` (default) tests every part at :math:`1 - (1 - \alpha)^{1/m}` (of
        ``m`` parts; exact for independent parts), ``"bonferroni"`` at :math:`\alpha / m` (at most ``alpha``
        whatever their dependence), ``"minp"`` calibrates the smallest p-value of the parts as one statistic
        (:meth:`calibrate` is then required; it uses the parts' dependence, so it is less conservative when
        they are dependent).

    Attributes
    ----------
    tests : tuple
        The parts as tested: copies of ``tests`` at their share of ``alpha`` (``"minp"``: at ``alpha``).

    Notes
    -----
    ``alpha`` is the false-alarm rate of the decision in the sense of the parts: with the parts' default
    ``correction="sidak"`` the decision over the channels (any channel of any part rejecting) is at ``alpha``; with
    ``correction="none"`` each channel is at ``alpha``; :attr:`alpha` is shared over the parts either way.

    Channel ``c`` of the combined :class:`~tsfdi.Decision` has the statistic :math:`-2 \ln \min_i p_{i,c}` (the
    smallest p-value of the parts at that channel), the p-value :math:`1 - (1 - \min_i p_{i,c})^m` (Sidak),
    :math:`\min(1, m \min_i p_{i,c})` (Bonferroni) or the calibrated law's upper tail of the statistic
    (``"minp"``: a :class:`~tsfdi.ScaledChi2Threshold` with the record-level predictive law fitted to the statistic
    on the held-out windows, each part's p-value from its own calibration), and rejects when a part rejects it
    (``"minp"``: when the statistic exceeds the calibrated threshold); the parts' own decisions are in
    ``details["parts"]``. The Sidak share is exact for independent parts and conservative for positively dependent
    ones; Bonferroni is conservative always.
    """

    name = "any of"
    null_hypothesis = "every part's null hypothesis (healthy / model fits)"
    alternative_hypothesis = "some part's alternative (fault / model does not fit)"

    def __init__(self, tests: Any, correction: str = "sidak") -> None:
        if isinstance(tests, (str, bytes, ResidualTest)) or not hasattr(tests, "__iter__"):
            raise TypeError(f"tests must be a sequence of residual tests, got {type(tests).__name__}")
        tests = list(tests)
        if len(tests) < 2:
            raise ValueError(f"tests must hold at least two tests, got {len(tests)}")
        for i, t in enumerate(tests):
            if not isinstance(t, CalibratedTest) or isinstance(t, AnyOf):
                raise TypeError(f"tests[{i}] must be a windowed residual test (LjungBox, FTest, MeanTest), got "
                                f"{type(t).__name__}")
            if t.calibrated:
                raise ValueError(f"tests[{i}] ({type(t).__name__}) is already calibrated: give the parts "
                                 "uncalibrated and calibrate the AnyOf (each part is calibrated at its share of alpha)")
            if getattr(t, "alternative", "greater") != "greater":
                raise ValueError(f"tests[{i}] ({type(t).__name__}) has alternative={t.alternative!r}: the parts "
                                 "must reject on large statistics (alternative='greater')")
        alphas = [t.alpha for t in tests]
        if any(abs(a - alphas[0]) > 1e-12 * alphas[0] for a in alphas):
            raise ValueError(f"tests must share one alpha (AnyOf divides it among them), got alphas {alphas}")
        corr = [getattr(t, "correction", None) for t in tests]
        if len(set(corr)) > 1:
            raise ValueError(f"tests must have the same correction over channels, got {corr}")
        self.correction = option(correction, "correction", ("sidak", "bonferroni", "minp"))
        self.alpha = float(alphas[0])
        self.tests = tuple(tests)
        share = self.share
        parts = []
        for t in tests:
            part = copy.deepcopy(t)
            part.alpha = share
            if isinstance(part.threshold, ScaledChi2Threshold) or not isinstance(part.threshold, str):
                part.threshold.false_alarm = share          # an estimator template: calibrated at the share
            parts.append(part)
        self.tests = tuple(parts)

    def __repr__(self) -> str:
        parts = ", ".join(type(t).__name__ for t in self.tests)
        return f"AnyOf([{parts}], correction={self.correction!r}, alpha={self.alpha:g})"

    @property
    def share(self) -> float:
        """The ``alpha`` of each part: Sidak or Bonferroni share, or ``alpha`` itself (``"minp"``)."""
        m = len(getattr(self, "tests", ())) or 1
        if self.correction == "sidak":
            return -math.expm1(math.log1p(-self.alpha) / m)
        if self.correction == "bonferroni":
            return self.alpha / m
        return self.alpha

    @property
    def min_resid(self) -> int:
        """Fewest residual samples :meth:`test` accepts: the largest of the parts'."""
        return max(t.min_resid for t in self.tests)

    @property
    def empirical(self) -> bool:
        """Whether a part's threshold comes from data (``"minp"``: always)."""
        return self.correction == "minp" or any(t.empirical for t in self.tests)

    @property
    def calibrated(self) -> bool:
        """Whether :meth:`calibrate` has been run."""
        if self.correction == "minp":
            return hasattr(self, "threshold_")
        return all(t.calibrated for t in self.tests if t.empirical) and any(t.empirical for t in self.tests)

    def channel_alpha(self, k: int) -> float:
        """The risk of each of ``k`` channels of the combined decision (a part rejecting at that channel): ``alpha``
        or its share by the parts' ``correction`` over channels."""
        return float(self._channel_alpha(self.alpha, k, getattr(self.tests[0], "correction", None)))

    def null_threshold(self, k: int, nobs: int | None = None, **reference: Any) -> np.ndarray:
        r"""Critical value of the combined statistic :math:`-2 \ln \min_i p_i` per channel, shape (k,):
        :math:`-2 \ln a` with ``a`` each part's risk at a channel (:attr:`share` of the channel's risk);
        ``"minp"``: the Sidak share's, exact for independent parts (what :meth:`calibrate` replaces)."""
        k = int(k)
        if self.correction != "minp":
            return np.full(k, -2.0 * math.log(self.tests[0].channel_alpha(k)))     # the parts are at their share
        share = -math.expm1(math.log1p(-self.alpha) / len(self.tests))
        return np.full(k, -2.0 * math.log(self._channel_alpha(share, k, getattr(self.tests[0], "correction", None))))

    def reference(self, results: Any) -> dict:
        """Keyword arguments of :meth:`test` from a fitted baseline: each part's (``references``)."""
        return {"references": tuple(t.reference(results) for t in self.tests)}

    def _references(self, references: Any, reference: dict) -> list:
        if references is None:
            return [dict(reference)] * len(self.tests)
        if len(references) != len(self.tests):
            raise ValueError(f"references must hold one mapping per part ({len(self.tests)}), got {len(references)}")
        return [{**reference, **dict(r)} for r in references]

    def calibrate(self, resid: Any, *, window: int, step: int = 1, references: Any = None,
                  **reference: Any) -> AnyOf:
        """Calibrate every part on healthy (held-out) residual records, at its share of ``alpha``; with
        ``"minp"`` also the smallest p-value of the parts, as one statistic (see Notes). Returns ``self``.

        Parameters
        ----------
        resid, window, step, **reference :
            As for :meth:`tsfdi.LjungBox.calibrate` (``resid`` and ``window`` are required).
        references : sequence of dict, optional
            Each part's keyword arguments (:meth:`reference` of a fitted baseline).
        """
        refs = self._references(references, reference)
        for i, (t, ref) in enumerate(zip(self.tests, refs)):
            try:
                t.calibrate(resid, window=window, step=step, **ref)
            except ValueError as err:
                raise ValueError(f"AnyOf part {i} ({type(t).__name__}): {err}") from None
        if self.correction != "minp":
            return self
        lags = int(getattr(resid, "lags", 0) or 0)
        recs = list(resid) if isinstance(resid, (list, tuple)) else [resid]
        n = int(window) - lags
        stats_, groups, per = [], [], []
        for i, r in enumerate(recs):
            sig = as_signal(r, f"resid[{i}]", allow_constant=True)
            if sig.nobs < n:
                continue
            refuse_constant_stretch(sig, n, f"resid[{i}]")
            stats_.append(self._minp_statistic(r, n, step, refs))
            groups.append(np.full(stats_[-1].shape[0], i))
            per.append(sig.nobs // n)
        stat = np.concatenate(stats_)
        k = stat.shape[1]
        a = self.channel_alpha(k)
        ths = []
        for c in range(k):
            est = ScaledChi2Threshold(a, min_windows=getattr(self.tests[0].threshold, "min_windows", 30))
            try:
                if len(stats_) > 1:
                    est.calibrate(stat[:, c], independent=per, groups=np.concatenate(groups))
                else:
                    est.calibrate(stat[:, c], independent=per[0])
            except ValueError as err:
                raise ValueError(f"AnyOf(correction='minp').calibrate, channel {c}: {err}") from None
            ths.append(est)
        self.thresholds_ = ths
        self.threshold_ = np.array([t.threshold_ for t in ths])
        return self

    calibrated_for = CalibratedTest.calibrated_for

    def _minp_statistic(self, resid: Any, n: int, step: int, refs: list) -> np.ndarray:
        """``-2 ln min_i p_i`` of every window (calibrated parts), shape (windows, k)."""
        p = None
        for t, ref in zip(self.tests, refs):
            ref = {**ref, "reference_variance": t.reference_variance_} if hasattr(t, "reference_variance_") else ref
            s = np.asarray(t.window_statistic(resid, n, step, **ref))
            _, pv = t.threshold_pvalue(s, n, **ref)
            p = pv if p is None else np.minimum(p, pv)
        return -2.0 * np.log(np.maximum(p, _P_FLOOR))

    def combine(self, pvalues: Any, rejects: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        r"""The combined statistic, threshold, p-value and channel rejection from the parts' p-values and channel
        rejections (the rule of :meth:`test`, see Notes of the class), for one window or many at once.

        Parameters
        ----------
        pvalues, rejects : sequence of array_like, each of shape (..., k)
            One per part, in the order of :attr:`tests`: the part's p-values and channel rejections (channels on the
            last axis; e.g. every window of a record, as the windowed engine computes them).

        Returns
        -------
        statistic : ndarray, shape (..., k)
            :math:`-2 \ln \min_i p_i`.
        threshold : ndarray, shape (k,)
        pvalue : ndarray, shape (..., k)
        reject : ndarray of bool, shape (..., k)
        """
        if len(pvalues) != len(self.tests) or len(rejects) != len(self.tests):
            raise ValueError(f"pvalues and rejects must hold one array per part ({len(self.tests)}), got "
                             f"{len(pvalues)} and {len(rejects)}")
        ps = [np.asarray(p, dtype=np.float64) for p in pvalues]
        if len({p.shape for p in ps}) > 1:
            raise ValueError(f"the parts' decisions have different channels ({[p.shape for p in ps]}): a joint "
                             "(multivariate) test cannot be combined channel by channel with per-channel tests")
        pmin = np.minimum.reduce(ps)
        stat = -2.0 * np.log(np.maximum(pmin, _P_FLOOR))
        m = len(ps)
        k = pmin.shape[-1]
        if self.correction == "minp":
            thr = self.threshold_
            if thr.shape[0] != k:
                raise ValueError(f"resid has {k} channel(s) but the test was calibrated on {thr.shape[0]}")
            flat = stat.reshape(-1, k)
            pv = np.column_stack([est.pvalue(flat[:, c]) for c, est in enumerate(self.thresholds_)]).reshape(
                stat.shape)
            rej = stat > thr
        else:
            thr = self.null_threshold(k)
            with np.errstate(divide="ignore"):          # a p-value of 1: log1p(-1) = -inf, the adjusted p 1
                pv = -np.expm1(m * np.log1p(-pmin)) if self.correction == "sidak" else np.minimum(1.0, m * pmin)
            rej = np.logical_or.reduce([np.asarray(r, dtype=bool) for r in rejects])
        return stat, thr, pv, rej

    def test(self, resid: Any, references: Any = None, **reference: Any) -> Decision:
        """The combined :class:`~tsfdi.Decision` of a residual window (see Notes of the class).

        Parameters
        ----------
        resid : array_like, Series, DataFrame or DataArray
            Residuals, time on axis 0, one column per channel.
        references : sequence of dict, optional
            Each part's keyword arguments (:meth:`reference` of a fitted baseline).
        **reference :
            Keyword arguments given to every part (e.g. ``reference_variance``).
        """
        refs = self._references(references, reference)
        if self.correction == "minp" and not self.calibrated:
            raise ValueError("AnyOf(correction='minp') is not calibrated: call calibrate(healthy residuals, "
                             "window=...) first")
        parts = [t.test(resid, **ref) for t, ref in zip(self.tests, refs)]
        stat, thr, pv, rej = self.combine([d.pvalue for d in parts], [d.channel_reject for d in parts])
        k = stat.shape[0]
        fam = self.family_alpha(self.channel_alpha(k), k)
        details = {"parts": tuple(parts), "correction": self.correction, "part_alpha": self.share,
                   "family_alpha": fam[0], "family_alpha_bound": fam[1],
                   "threshold_method": "calibrated" if self.empirical else "theoretical"}
        return Decision(statistic=stat, threshold=thr, pvalue=pv, alpha=self.alpha, reject=bool(rej.any()),
                        df=np.full(k, 2.0), nobs=parts[0].nobs, null_hypothesis=self.null_hypothesis,
                        alternative_hypothesis=self.alternative_hypothesis, details=details, channel_reject=rej,
                        channels=parts[0].channels, test="AnyOf")

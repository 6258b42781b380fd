"""Shared base of the residual tests: validation of residuals and options, the fitted-model hook."""

from __future__ import annotations

from typing import Any

import numpy as np

from tsfdi._data import Signal, as_signal
from tsfdi._validation import option, probability

__all__ = ["ResidualTest"]


class ResidualTest:
    """Base class of residual hypothesis tests.

    A test holds options only; :meth:`test` takes a residual series (numpy, pandas or xarray; time on
    axis 0; one column per channel) and returns a :class:`~tsfdi.detection.decision.Decision`. A test never
    imports a model: what it needs from a fitted baseline (reference variance, degrees of freedom) is passed
    as keyword arguments, and :meth:`reference` extracts those from any results object exposing the
    documented attributes (``sigma2`` or ``sigma``, ``nobs``, ``df_resid``), duck-typed.
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

"""Warning and error classes raised by tsfdi."""

from __future__ import annotations

__all__ = ["TsfdiWarning", "IllConditionedWarning", "UnstableModelWarning", "ConvergenceWarning", "CoverageWarning"]


class TsfdiWarning(UserWarning):
    """Base class of every warning tsfdi emits."""


class IllConditionedWarning(TsfdiWarning):
    """The regressor of a least-squares fit is rank deficient or ill-conditioned."""


class UnstableModelWarning(TsfdiWarning):
    """A fitted autoregression has characteristic roots on or outside the unit circle."""


class ConvergenceWarning(TsfdiWarning):
    """An iterative procedure (recursive estimator, simulator) did not settle."""


class CoverageWarning(TsfdiWarning):
    """A record lies outside what a baseline's fitting records cover (:func:`tsfdi.coverage.coverage`): a decision
    on it is not covered by the baseline's calibration."""

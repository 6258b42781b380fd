"""Warning and error classes raised by tsfdi."""

from __future__ import annotations

__all__ = ["TsfdiWarning", "IllConditionedWarning", "UnstableModelWarning", "ConvergenceWarning"]


class TsfdiWarning(UserWarning):
    """Base class of every warning tsfdi emits."""


class IllConditionedWarning(TsfdiWarning):
    """The regressor of a least-squares fit is rank deficient or ill-conditioned."""


class UnstableModelWarning(TsfdiWarning):
    """A fitted autoregression has characteristic roots on or outside the unit circle."""


class ConvergenceWarning(TsfdiWarning):
    """An iterative procedure (recursive estimator, simulator) did not settle."""

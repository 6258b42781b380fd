"""Residual hypothesis tests and the Decision object."""

__all__: list[str] = []
from tsfdi.detection.zscore import ZScore; __all__ += ["ZScore"]  # noqa: E402,E702

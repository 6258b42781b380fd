"""tsfdi: statistical time-series fault detection and identification."""

from tsfdi.exceptions import TsfdiWarning

__version__ = "0.1.0"

__all__ = ["TsfdiWarning", "__version__"]

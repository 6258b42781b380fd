"""Every plot of tsfdi: ``plot_x(..., ax=None) -> Figure``. matplotlib is imported inside each function."""

from tsfdi.plotting.acf import plot_acf
from tsfdi.plotting.selection import plot_order_selection

__all__ = ["plot_acf", "plot_order_selection"]
from tsfdi.plotting.decision import plot_decision, plot_identification, plot_threshold; __all__ += ["plot_decision", "plot_identification", "plot_threshold"]  # noqa: E702,E402

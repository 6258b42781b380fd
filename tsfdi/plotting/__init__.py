"""Every plot of tsfdi: ``plot_x(..., ax=None) -> Figure``. matplotlib is imported inside each function."""

from tsfdi.plotting.acf import plot_acf
from tsfdi.plotting.decision import plot_decision, plot_identification, plot_threshold
from tsfdi.plotting.monitoring import plot_confusion, plot_monitor, plot_variance_evolution
from tsfdi.plotting.selection import plot_order_selection

__all__ = ["plot_acf", "plot_confusion", "plot_decision", "plot_identification", "plot_monitor",
           "plot_order_selection", "plot_threshold", "plot_variance_evolution"]

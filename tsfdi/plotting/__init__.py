"""Every plot of tsfdi: ``plot_x(..., ax=None) -> Figure``. matplotlib is imported inside each function."""

from tsfdi.plotting.acf import plot_acf
from tsfdi.plotting.decision import plot_decision, plot_identification, plot_threshold
from tsfdi.plotting.fp import plot_fp_surface, plot_k_estimate
from tsfdi.plotting.monitoring import plot_confusion, plot_monitor, plot_variance_evolution
from tsfdi.plotting.selection import plot_order_selection
from tsfdi.plotting.sequential import plot_oc_asn, plot_sequential_decision, plot_sequential_identification

__all__ = ["plot_acf", "plot_confusion", "plot_decision", "plot_fp_surface", "plot_identification", "plot_k_estimate",
           "plot_monitor",
           "plot_oc_asn", "plot_order_selection", "plot_sequential_decision", "plot_sequential_identification",
           "plot_threshold", "plot_variance_evolution"]

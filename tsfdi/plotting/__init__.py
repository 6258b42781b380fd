"""Every plot of tsfdi: ``plot_x(..., ax=None) -> Figure``. matplotlib is imported inside each function."""

__all__: list[str] = []

"""Time-series model families: one module per family, shared kernels in ``_lstsq``."""

__all__: list[str] = []

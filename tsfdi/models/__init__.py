"""Time-series model families: one module per family, shared kernels in ``_lstsq``."""

from tsfdi.models.ar import AR, ARResults
from tsfdi.models.arx import ARX, ARXResults
from tsfdi.models.var import VAR, VARResults
from tsfdi.models.recursive import RecursiveARX, RecursiveARXResults

__all__ = ["AR", "ARResults", "ARX", "ARXResults", "VAR", "VARResults", "RecursiveARX", "RecursiveARXResults"]

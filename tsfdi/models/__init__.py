"""Time-series model families: one module per family.

Shared pieces: ``lstsq`` (regressors, least squares, nested fits), ``criteria`` (information criteria),
``archive`` (the ``.npz`` format of ``Results.save`` and :func:`load`).
"""

from tsfdi.models._base import HeldOutResiduals, InputOutputResults
from tsfdi.models.ar import AR, ARResults
from tsfdi.models.archive import load
from tsfdi.models.arx import ARX, ARXResults
from tsfdi.models.emran import EMRAN, EMRANResults
from tsfdi.models.fp import (FPAR, FPARX, FPVAR, FPMean, FPMeanResults, FPOrderSelection, FPResults,
                             OperatingPointEstimate, fp_basis, select_fp_order)
from tsfdi.models.recursive import RecursiveARX, RecursiveARXResults, RecursiveARXState
from tsfdi.models.var import VAR, VARResults
from tsfdi.models.varx import VARX, VARXResults

__all__ = ["AR", "ARResults", "ARX", "ARXResults", "EMRAN", "EMRANResults", "VAR", "VARResults", "VARX", "VARXResults",
           "InputOutputResults", "RecursiveARX",
           "RecursiveARXResults", "RecursiveARXState", "HeldOutResiduals", "load",
           "FPAR", "FPVAR", "FPARX", "FPResults", "FPMean", "FPMeanResults", "OperatingPointEstimate", "FPOrderSelection", "select_fp_order",
           "fp_basis"]

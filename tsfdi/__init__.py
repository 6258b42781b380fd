"""tsfdi: statistical time-series fault detection and identification.

The flow, one module per step: models (:mod:`tsfdi.models`, order selection in :mod:`tsfdi.selection`) ->
residual tests (:mod:`tsfdi.detection`) -> the windowed engine (:mod:`tsfdi.windows`) -> detection and
identification (:mod:`tsfdi.identification`) -> the sliding-window monitor of paper 003 (:mod:`tsfdi.monitoring`)
and the online detectors of papers 001/002 (:mod:`tsfdi.online`), fault isolation by structured residuals
(:mod:`tsfdi.isolation`) -> baselines of many records (:mod:`tsfdi.baselines`) -> evaluation
(:mod:`tsfdi.evaluation`); fleets of records on dask through :mod:`tsfdi.fleet`. :mod:`tsfdi.datasets`,
:mod:`tsfdi.plotting`, :mod:`tsfdi.study` and :mod:`tsfdi.fleet` are imported on first use.
"""

import importlib

from tsfdi.baselines import Baselines, Records, fit_baselines
from tsfdi.coverage import Coverage
from tsfdi.detection import (GLRT, SPRT, AnyOf, Decision, EmpiricalThreshold, FTest, LjungBox, MeanTest, MovingSquaredError,
                             ParameterGLRT, ResidualTest, ScaledChi2Threshold, SequentialDecision,
                             SequentialIdentification, ZScore, msprt)
from tsfdi.evaluation import Evaluation, detection_metrics, evaluate, first_alarm, score_records
from tsfdi.exceptions import CoverageWarning, TsfdiWarning
from tsfdi.identification import Identification, WindowedIdentification, detect, identify, identify_windows
from tsfdi.io import read_records
from tsfdi.isolation import Isolation, IsolationSeries, ResidualSet
from tsfdi.models import (AR, ARX, EMRAN, FPAR, FPARX, FPVAR, VAR, ARResults, ARXResults, EMRANResults, FPMean,
                          FPMeanResults, FPOrderSelection, FPResults, HeldOutResiduals, OperatingPointEstimate,
                          RecursiveARX, RecursiveARXResults, VARResults, VARX, VARXResults, load, select_fp_order)
from tsfdi.monitoring import Monitor, MonitorEvent, MonitorResult
from tsfdi.online import OnlineCalibration, OnlineDetection, OnlineDetector
from tsfdi.selection import OrderSelection, select_order
from tsfdi.windows import ResidualWindows, WindowStatistics

__version__ = "0.1.0"

__all__ = [
    # models and order selection
    "AR", "ARX", "VAR", "VARX", "RecursiveARX", "EMRAN", "ARResults", "ARXResults", "VARResults", "VARXResults",
    "RecursiveARXResults", "EMRANResults",
    "HeldOutResiduals", "OrderSelection", "select_order", "load",
    # functionally pooled models
    "FPAR", "FPVAR", "FPARX", "FPResults", "FPMean", "FPMeanResults", "OperatingPointEstimate", "FPOrderSelection",
    "select_fp_order",
    # residual tests and decisions
    "ResidualTest", "AnyOf", "Decision", "FTest", "LjungBox", "MeanTest", "GLRT", "ParameterGLRT", "MovingSquaredError",
    "EmpiricalThreshold",
    "ScaledChi2Threshold",
    "ZScore",
    # sequential decisions
    "SPRT", "SequentialDecision", "SequentialIdentification", "msprt",
    # windowed engine, detection, identification
    "ResidualWindows", "WindowStatistics", "detect", "identify", "identify_windows", "Identification",
    "WindowedIdentification", "ResidualSet", "Isolation", "IsolationSeries",
    # monitoring, online detection, baselines, evaluation
    "Monitor", "MonitorResult", "MonitorEvent", "OnlineDetector", "OnlineDetection", "OnlineCalibration", "Records", "fit_baselines",
    "Baselines", "Coverage", "evaluate", "Evaluation", "first_alarm", "score_records", "detection_metrics",
    # reading data files
    "read_records",
    # imported on first use
    "datasets", "plotting", "study", "fleet", "plot_acf", "align",
    "TsfdiWarning", "CoverageWarning", "__version__",
]

_LAZY_MODULES = ("datasets", "plotting", "study", "fleet")


def __getattr__(name: str):
    """``tsfdi.datasets``, ``tsfdi.plotting``, ``tsfdi.study`` and ``tsfdi.fleet`` (and ``tsfdi.plot_acf``,
    ``tsfdi.align``) on first use."""
    if name in _LAZY_MODULES:
        return importlib.import_module(f"tsfdi.{name}")
    if name == "plot_acf":
        return importlib.import_module("tsfdi.plotting").plot_acf
    if name == "align":
        return importlib.import_module("tsfdi.datasets").align
    raise AttributeError(f"module 'tsfdi' has no attribute {name!r}")


def __dir__() -> list:
    return sorted(set(globals()) | set(__all__))

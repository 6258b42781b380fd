"""tsfdi: statistical time-series fault detection and identification."""

from tsfdi.detection import GLRT, Decision, EmpiricalThreshold, FTest, LjungBox, ZScore
from tsfdi.evaluation import Baselines, Evaluation, evaluate, fit_baselines, hexacopter_signals
from tsfdi.exceptions import TsfdiWarning
from tsfdi.identification import Identification, detect, identify, identify_windows
from tsfdi.io import load
from tsfdi.models import AR, ARX, VAR, ARResults, ARXResults, RecursiveARX, VARResults
from tsfdi.monitoring import Monitor, MonitorResult, OnlineDetector
from tsfdi.plotting import plot_acf
from tsfdi.selection import OrderSelection, select_order

__version__ = "0.1.0"

__all__ = [
    # models and order selection
    "AR", "ARX", "VAR", "RecursiveARX", "ARResults", "ARXResults", "VARResults", "OrderSelection",
    "select_order", "load",
    # residual tests and decisions
    "Decision", "FTest", "LjungBox", "GLRT", "EmpiricalThreshold", "ZScore",
    # detection, identification, monitoring, evaluation
    "detect", "identify", "identify_windows", "Identification", "Monitor", "MonitorResult", "OnlineDetector",
    "evaluate", "Evaluation", "fit_baselines", "Baselines", "hexacopter_signals",
    "plot_acf", "TsfdiWarning", "__version__",
]

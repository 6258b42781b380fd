"""tsfdi: statistical time-series fault detection and identification."""

from tsfdi.exceptions import TsfdiWarning
from tsfdi.io import load
from tsfdi.models import AR, ARX, VAR, ARResults, ARXResults, VARResults
from tsfdi.models.recursive import RecursiveARX
from tsfdi.plotting import plot_acf
from tsfdi.selection import OrderSelection, select_order

__version__ = "0.1.0"

__all__ = ["AR", "ARX", "VAR", "ARResults", "ARXResults", "VARResults", "RecursiveARX", "OrderSelection", "TsfdiWarning",
           "load", "plot_acf", "select_order", "__version__"]
from tsfdi.detection import GLRT, Decision, EmpiricalThreshold, FTest, LjungBox; from tsfdi.identification import Identification, detect, identify, identify_windows; __all__ += ["Decision", "FTest", "LjungBox", "GLRT", "EmpiricalThreshold", "detect", "identify", "identify_windows", "Identification"]  # noqa: E402,E702,I001
from tsfdi.detection.zscore import ZScore; __all__ += ["ZScore"]  # noqa: E402,E702,I001
from tsfdi.monitoring import OnlineDetector; __all__ += ["OnlineDetector"]  # noqa: E402,E702,I001
from tsfdi.monitoring import Monitor, MonitorResult; from tsfdi.evaluation import Baselines, Evaluation, evaluate, fit_baselines, hexacopter_signals; __all__ += ["Monitor", "MonitorResult", "Baselines", "Evaluation", "evaluate", "fit_baselines", "hexacopter_signals"]  # noqa: E402,E702,I001

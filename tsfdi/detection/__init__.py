"""Residual hypothesis tests and the Decision object."""

from tsfdi.detection.base import ResidualTest
from tsfdi.detection.combined import AnyOf
from tsfdi.detection.decision import Decision
from tsfdi.detection.glrt import GLRT, GLRTScan, GLRTStream, ParameterGLRT, glrt_direct
from tsfdi.detection.mean import MeanTest
from tsfdi.detection.moving import MovingSquaredError, MovingSquaredErrorStream
from tsfdi.detection.sequential import (SPRT, AlignedRecordEffect, RecordEffect, SequentialDecision,
                                       SequentialIdentification, aligned_record_effect, msprt, msprt_scale,
                                       record_effect, renewal_walk, wald_bounds)
from tsfdi.detection.threshold import EmpiricalThreshold, ScaledChi2Threshold
from tsfdi.detection.variance import FTest
from tsfdi.detection.whiteness import LjungBox, LjungBoxWindows, autocovariance, ljungbox_windows
from tsfdi.detection.zscore import ZScore

__all__ = ["AlignedRecordEffect", "AnyOf", "Decision", "EmpiricalThreshold", "FTest", "GLRT", "GLRTScan", "GLRTStream", "LjungBox", "MeanTest",
           "LjungBoxWindows", "MovingSquaredError", "MovingSquaredErrorStream", "ParameterGLRT", "RecordEffect", "ResidualTest",
           "SPRT", "ScaledChi2Threshold", "SequentialDecision", "SequentialIdentification", "ZScore",
           "aligned_record_effect", "autocovariance", "glrt_direct", "ljungbox_windows", "msprt", "msprt_scale", "record_effect", "renewal_walk", "wald_bounds"]

"""Simulators, fault injection, loaders of shipped and public data, flight-log readers and time alignment."""

from tsfdi.datasets._shipped import load_hexacopter
from tsfdi.datasets.alignment import align
from tsfdi.datasets.alfa import list_alfa, load_alfa
from tsfdi.datasets.crazypad import list_crazypad, load_crazypad, read_crazypad_log
from tsfdi.datasets.dryden import DrydenTurbulence, dryden_turbulence
from tsfdi.datasets.faults import FAULT_KINDS, inject_fault
from tsfdi.datasets.hexacopter import (BIDIRECTIONAL_HEXACOPTER, ControllerGains, FleetSpread, HexacopterParameters,
                                       hexacopter_signals, make_hexacopter_dataset, simulate_hexacopter, trim,
                                       write_hexacopter_dataset)
from tsfdi.datasets.sensors import SensorSuite, sensor_log, write_sensor_log
from tsfdi.datasets.ulog import read_ulog

__all__ = ["list_alfa", "load_alfa", "list_crazypad", "load_crazypad", "read_crazypad_log", "DrydenTurbulence",
           "dryden_turbulence", "HexacopterParameters", "BIDIRECTIONAL_HEXACOPTER", "ControllerGains", "FleetSpread",
           "simulate_hexacopter", "make_hexacopter_dataset", "write_hexacopter_dataset", "trim", "load_hexacopter",
           "hexacopter_signals", "SensorSuite", "sensor_log", "write_sensor_log", "read_ulog", "align", "inject_fault",
           "FAULT_KINDS"]

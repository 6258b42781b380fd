"""Simulators, fault injection and loaders of shipped and public data."""

__all__: list[str] = []
from tsfdi.datasets.alfa import list_alfa, load_alfa; __all__ += ["list_alfa", "load_alfa"]  # noqa: E402,E702
from tsfdi.datasets.crazypad import list_crazypad, load_crazypad, read_crazypad_log; __all__ += ["list_crazypad", "load_crazypad", "read_crazypad_log"]  # noqa: E402,E702
from tsfdi.datasets.dryden import DrydenTurbulence, dryden_turbulence; from tsfdi.datasets.hexacopter import REGULAR_HEXACOPTER, ControllerGains, HexacopterParameters, make_hexacopter_dataset, simulate_hexacopter, trim; from tsfdi.datasets._shipped import load_hexacopter; __all__ += ["DrydenTurbulence", "dryden_turbulence", "HexacopterParameters", "REGULAR_HEXACOPTER", "ControllerGains", "simulate_hexacopter", "make_hexacopter_dataset", "trim", "load_hexacopter"]  # noqa: E402,E702

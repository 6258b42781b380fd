"""Simulators, fault injection and loaders of shipped and public data."""

__all__: list[str] = []
from tsfdi.datasets.alfa import list_alfa, load_alfa; __all__ += ["list_alfa", "load_alfa"]  # noqa: E402,E702

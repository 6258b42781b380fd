"""Simulators, fault injection and loaders of shipped and public data."""

__all__: list[str] = []

"""Residual hypothesis tests and the Decision object."""

__all__: list[str] = []

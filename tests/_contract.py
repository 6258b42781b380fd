"""The input contract's check for refusals, shared by the property-based tests (tests/property)."""

from __future__ import annotations

import re

from hypothesis import event


def named(exc: Exception, names) -> None:
    """The error message names one of ``names`` (as a word); the refusal is recorded as a hypothesis event."""
    msg = str(exc)
    event(f"refused: {msg[:70]}")
    assert any(re.search(rf"(?<![\w-]){re.escape(n)}(?![\w])", msg) for n in names), f"{type(exc).__name__}: {msg}"

"""Load a script of the repository (a benchmark, a docs script) as a module for its tests."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]


def load_script(relpath: str) -> ModuleType:
    """A fresh import of ``ROOT / relpath`` (e.g. ``"benchmarks/crazypad.py"``); its ``main()`` is not run.

    The module is registered in ``sys.modules`` under ``<stem>_script`` while it executes (a dataclass of the
    module looks its module up there); each call gives a new module object."""
    path = ROOT / relpath
    spec = importlib.util.spec_from_file_location(f"{path.stem}_script", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod

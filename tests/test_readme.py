"""The README's usage example runs, its quick start is the two lines .ci/run executes, and the user guide's
one-flow example prints what its comments say."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"
WINDOWS_GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "windows.md"


def test_usage_example_runs(capsys):
    text = README.read_text()
    usage = text.split("## Usage", 1)[1]
    code = re.search(r"```python\n(.*?)```", usage, re.S).group(1)
    assert len(code.strip().splitlines()) <= 10
    exec(compile(code, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert out.splitlines()[0] == "identified rotor2"


def test_quick_start_is_two_commands():
    text = README.read_text()
    block = re.search(r"## Quick start\n+```bash\n(.*?)```", text, re.S).group(1)
    lines = [ln for ln in block.splitlines() if ln.strip()]
    assert len(lines) == 2
    assert "tsfdi demo" in lines[0] and "pytest" in lines[1]


def test_windows_guide_example_prints_its_comments(capsys):
    """Every value a ``print`` of docs/guide/windows.md states in its comment is what the code prints."""
    code = re.search(r"```python\n(.*?)```", WINDOWS_GUIDE.read_text(), re.S).group(1)
    exec(compile(code, "windows.md", "exec"), {})
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "False True"
    assert out[1].startswith("WindowStatistics(windows=51,") and out[1].endswith("(51, 2, 1)")
    assert out[2] == "[0 0 1]"
    assert "37.0 fault" in out

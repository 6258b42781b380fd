"""Every Python and shell example of the user guide (docs/guide) runs, so that no example can rot.

Each page is one test: its ```python blocks run in order in one namespace (a page is a story), its ```bash /
```shell / ```console blocks with the virtualenv's ``bin`` on ``PATH`` (the ``tsfdi`` command), in page order,
all in a temporary working folder that holds ``data`` (a link to the repository's ``data/``): an example reads
``data/px4/sample.ulg`` as a user does from the repository root, and writes its outputs into the temporary folder.
The real data are the small samples shipped in ``data/`` (see data/README.md); no example needs ``../shared``.

A block that must not run (installing packages, a cluster address, minutes of simulation) carries a visible
marker on the line before it: ``<!-- not run: reason -->`` in Markdown, ``.. not run: reason`` in reStructuredText.
:func:`test_blocks_not_run_are_few_and_say_why` lists them. Code blocks of ``.rst`` pages are ``.. code-block::``
directives.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guide"
DATA = ROOT / "data"

#: info string of a fence -> how the block runs
LANGUAGES = {"python": "python", "py": "python", "bash": "shell", "shell": "shell", "sh": "shell",
             "console": "console"}
NOT_RUN_MD = re.compile(r"^\s*<!--\s*not run:\s*(?P<reason>.*?)\s*-->\s*$")
NOT_RUN_RST = re.compile(r"^\s*\.\.\s+not run:\s*(?P<reason>.*?)\s*$")
FENCE = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,}|~{3,})\s*(?P<info>[^`]*?)\s*$")
RST_CODE = re.compile(r"^(?P<indent>[ \t]*)\.\.\s+(?:code-block|code|sourcecode)::\s*(?P<lang>\S+)\s*$")
MAX_NOT_RUN = 6


@dataclass(frozen=True)
class Block:
    page: str
    line: int          # 1-based line of the block's first code line
    language: str      # "python", "shell" or "console"
    code: str
    not_run: str | None  # the reason, when the block is marked not to run
    marker: int | None = None   # 1-based line of that marker


def _language(info: str) -> str | None:
    words = info.split()
    if not words:
        return None
    if words[0] in ("{code-block}", "{code-cell}", "{code}") and len(words) > 1:
        words = words[1:]
    return LANGUAGES.get(words[0].lower())


def _marker(lines: list[str], before: int, pattern: re.Pattern) -> tuple[str | None, int | None]:
    """(reason, 1-based line) of a not-run marker on the nearest non-blank line above line index ``before``."""
    for i in range(before - 1, -1, -1):
        if lines[i].strip():
            m = pattern.match(lines[i])
            return ((m.group("reason") or "no reason given"), i + 1) if m else (None, None)
    return None, None


def markdown_blocks(path: Path) -> list[Block]:
    lines = path.read_text().splitlines()
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, indent = m.group("fence"), m.group("indent")
        j = i + 1
        while j < len(lines):
            close = FENCE.match(lines[j])
            if close and close.group("fence")[0] == fence[0] and len(close.group("fence")) >= len(fence) \
                    and not close.group("info"):
                break
            j += 1
        lang = _language(m.group("info"))
        if lang is not None:
            body = [ln[len(indent):] if ln.startswith(indent) else ln.lstrip() for ln in lines[i + 1:j]]
            out.append(Block(path.name, i + 2, lang, "\n".join(body) + "\n", *_marker(lines, i, NOT_RUN_MD)))
        i = j + 1
    return out


def rst_blocks(path: Path) -> list[Block]:
    lines = path.read_text().splitlines()
    out = []
    for i, line in enumerate(lines):
        m = RST_CODE.match(line)
        if not m or m.group("lang").lower() not in LANGUAGES:
            continue
        j = i + 1
        while j < len(lines) and (not lines[j].strip() or lines[j].lstrip().startswith(":")
                                  and len(lines[j]) - len(lines[j].lstrip()) > len(m.group("indent"))):
            j += 1      # options and blank lines before the body
        start = j
        base = len(m.group("indent"))
        while j < len(lines) and (not lines[j].strip() or len(lines[j]) - len(lines[j].lstrip()) > base):
            j += 1
        body = textwrap.dedent("\n".join(lines[start:j])).strip("\n") + "\n"
        out.append(Block(path.name, start + 1, LANGUAGES[m.group("lang").lower()], body,
                         *_marker(lines, i, NOT_RUN_RST)))
    return out


def page_blocks(path: Path) -> list[Block]:
    return markdown_blocks(path) if path.suffix == ".md" else rst_blocks(path)


PAGES = sorted([*GUIDE.glob("*.md"), *GUIDE.glob("*.rst")])
PAGES_WITH_CODE = [p for p in PAGES if page_blocks(p)]


def _commands(block: Block) -> str:
    """The shell text of a block: a ```console block's commands are its lines starting with ``$ ``."""
    if block.language != "console":
        return block.code
    return "\n".join(ln[2:] for ln in block.code.splitlines() if ln.startswith("$ ")) + "\n"


def _run_shell(block: Block, cwd: Path, env: dict) -> None:
    proc = subprocess.run(["bash", "-euo", "pipefail", "-c", _commands(block)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600)
    if proc.returncode != 0:
        pytest.fail(f"{block.page}, shell block at line {block.line} exited {proc.returncode}:\n{block.code}\n"
                    f"--- stdout (end) ---\n{proc.stdout[-3000:]}\n--- stderr (end) ---\n{proc.stderr[-3000:]}",
                    pytrace=False)


@pytest.mark.parametrize("page", PAGES_WITH_CODE, ids=[p.name for p in PAGES_WITH_CODE])
def test_guide_page_runs(page, tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    (tmp_path / "data").symlink_to(DATA, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    env = {**os.environ, "MPLBACKEND": "Agg",
           "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS", "1"),
           "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    namespace = {"__name__": "__main__"}     # a page read as a script: its `if __name__ == "__main__"` runs
    try:
        for block in page_blocks(page):
            if block.not_run is not None:
                continue
            if block.language == "python":
                # padded so that a traceback names the line of the page
                exec(compile("\n" * (block.line - 1) + block.code, str(page), "exec"), namespace)
            else:
                _run_shell(block, tmp_path, env)
    finally:
        plt.close("all")


def test_blocks_not_run_are_few_and_say_why():
    skipped = [b for p in PAGES for b in page_blocks(p) if b.not_run is not None]
    listing = "\n".join(f"{b.page}:{b.line} ({b.language}): {b.not_run}" for b in skipped)
    print(f"{len(skipped)} guide block(s) not run:\n{listing}")
    assert all(b.not_run and b.not_run != "no reason given" for b in skipped), listing
    assert len(skipped) <= MAX_NOT_RUN, f"{len(skipped)} blocks are not run (at most {MAX_NOT_RUN}):\n{listing}"


def test_every_not_run_marker_stands_before_a_block():
    """A marker whose block was moved away (or whose fence has no runnable language) is a stale marker."""
    for page in PAGES:
        pattern = NOT_RUN_MD if page.suffix == ".md" else NOT_RUN_RST
        markers = {i + 1 for i, line in enumerate(page.read_text().splitlines()) if pattern.match(line)}
        used = {b.marker for b in page_blocks(page)}
        assert markers <= used, f"{page.name}: 'not run' marker(s) at line(s) {sorted(markers - used)} not " \
                                "followed by a python / shell code block"


def test_the_collector_finds_blocks(tmp_path):
    """The parser sees indented fences, markers, rst directives and ignores other fences."""
    md = tmp_path / "p.md"
    md.write_text("text\n```python\na = 1\n```\n\n- item\n\n  ```bash\n  echo hi\n  ```\n"
                  "<!-- not run: needs a cluster -->\n```python\nClient('tcp://x')\n```\n"
                  "```text\nnot code\n```\n```{figure} f.png\n```\n")
    blocks = markdown_blocks(md)
    assert [(b.line, b.language, b.code, b.not_run) for b in blocks] == [
        (3, "python", "a = 1\n", None), (9, "shell", "echo hi\n", None),
        (13, "python", "Client('tcp://x')\n", "needs a cluster")]
    rst = tmp_path / "p.rst"
    rst.write_text("Title\n=====\n\n.. not run: slow\n\n.. code-block:: python\n   :caption: x\n\n   b = 2\n"
                   "   c = 3\n\nafter\n\n.. code-block:: text\n\n   no\n")
    assert [(b.line, b.language, b.code, b.not_run) for b in rst_blocks(rst)] == [
        (9, "python", "b = 2\nc = 3\n", "slow")]

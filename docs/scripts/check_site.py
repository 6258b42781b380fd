"""Check the built documentation site: it shows its figures and renders math without a network.

Run by ``docs/build.sh`` after ``sphinx-build``; exits 1 with the reasons when a check fails::

    python docs/scripts/check_site.py [docs/_build/html]

Checks:

- the site exists (``index.html``);
- ``<img>`` counts: the guide pages together, ``results.html``, ``gallery.html`` and every rendered notebook
  (whose figures exist only when it was executed) each hold at least one image, and every local image file
  exists;
- math: every page that holds math loads MathJax from the site's own ``_static/mathjax`` (the file exists), and no
  page loads a script from the network.

The counts are printed, one line per group.
"""

from __future__ import annotations

import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

#: Page groups that must each show at least one image: name -> glob patterns under the site root
IMAGE_GROUPS = {"guide": ["guide/*.html"], "results": ["results.html"], "gallery": ["gallery.html"]}
#: Rendered notebooks: every page must show at least one image (an unexecuted notebook has none)
NOTEBOOKS = "_notebooks/*.html"
MATHJAX = "_static/mathjax/"


class _Page(HTMLParser):
    """The ``<img>`` sources, ``<script>`` sources and whether the page holds math."""

    def __init__(self) -> None:
        super().__init__()
        self.images: list[str] = []
        self.scripts: list[str] = []
        self.math = False

    def handle_starttag(self, tag: str, attrs: list) -> None:
        a = dict(attrs)
        if tag == "img":
            self.images.append(a.get("src") or "")
        elif tag == "script" and a.get("src"):
            self.scripts.append(a["src"])
        if "math" in (a.get("class") or "").split():
            self.math = True


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8", errors="replace"))
    return page


def _local(src: str, page: Path) -> Path | None:
    """The file a relative ``src`` of ``page`` points to (None for a data: or network URL)."""
    parts = urlsplit(src)
    if parts.scheme or parts.netloc:
        return None
    return (page.parent / unquote(parts.path)).resolve()


def check(root: Path) -> tuple[list[str], list[str]]:
    """Check the site under ``root``; returns (report lines, problems)."""
    root = Path(root)
    if not (root / "index.html").is_file():
        return [], [f"{root}: no index.html; build the site first (docs/build.sh)"]
    pages = {p: _parse(p) for p in sorted(root.rglob("*.html"))}
    lines, problems = [], []

    def count(paths: list[Path]) -> int:
        return sum(len(pages[p].images) for p in paths)

    for name, patterns in IMAGE_GROUPS.items():
        paths = sorted({p for pat in patterns for p in root.glob(pat)})
        n = count(paths)
        lines.append(f"{name}: {n} image(s) on {len(paths)} page(s)"
                     + "".join(f"\n  {p.relative_to(root)}: {len(pages[p].images)}" for p in paths))
        if not paths:
            problems.append(f"{name}: no page matches {patterns}")
        elif n == 0:
            problems.append(f"{name}: no <img> on {', '.join(str(p.relative_to(root)) for p in paths)}")
    nbs = sorted(root.glob(NOTEBOOKS))
    lines.append(f"notebooks: {count(nbs)} image(s) on {len(nbs)} page(s)"
                 + "".join(f"\n  {p.relative_to(root)}: {len(pages[p].images)}" for p in nbs))
    problems += [f"{p.relative_to(root)}: no <img> (was the notebook executed?)" for p in nbs if not pages[p].images]
    for p, page in pages.items():
        for src in page.images:
            f = _local(src, p)
            if f is not None and not f.is_file():
                problems.append(f"{p.relative_to(root)}: image {src} does not exist")
    math_pages = [p for p, page in pages.items() if page.math]
    local = 0
    for p in math_pages:
        mj = [s for s in pages[p].scripts if "mathjax" in s.lower()]
        ok = [s for s in mj if MATHJAX in s and (_local(s, p) or Path("/nonexistent")).is_file()]
        local += bool(ok)
        if not ok:
            problems.append(f"{p.relative_to(root)}: holds math but loads no MathJax from {MATHJAX} ({mj or 'none'})")
    for p, page in pages.items():
        remote = [s for s in page.scripts if _local(s, p) is None and not s.startswith("data:")]
        if remote:
            problems.append(f"{p.relative_to(root)}: loads scripts from the network: {remote}")
    lines.append(f"math: {len(math_pages)} page(s) with math, {local} load MathJax from {MATHJAX}")
    return lines, problems


def main(argv: list[str]) -> int:
    root = Path(argv[0]) if argv else Path(__file__).resolve().parents[1] / "_build" / "html"
    lines, problems = check(root)
    print("\n".join(lines))
    if problems:
        print(f"site check FAILED ({len(problems)} problem(s)):\n" + "\n".join(f"- {p}" for p in problems),
              file=sys.stderr)
        return 1
    print("site check passed")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

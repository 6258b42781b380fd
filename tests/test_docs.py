"""The documentation sources: the site check run by docs/build.sh, a complete API reference, a gallery of every
plot, notebooks executed and math rendered offline by the build.

The site itself is built and checked by ``docs/build.sh`` (CI runs it after the tests); here the check script is
run on small hand-made sites, so that it is known to fail when a figure or the local MathJax is missing.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from _scripts import load_script

import tsfdi

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _load_check():
    return load_script("docs/scripts/check_site.py")


check_site = _load_check()

MATH = '<span class="math notranslate nohighlight">\\(x\\)</span>'


def page(body: str = "", scripts: tuple = (), prefix: str = "") -> str:
    tags = "".join(f'<script src="{prefix}{s}"></script>' for s in scripts)
    return f"<html><head>{tags}</head><body>{body}</body></html>"


@pytest.fixture
def site(tmp_path: Path) -> Path:
    """A minimal site that passes: an image in each group and notebook, MathJax from _static/mathjax."""
    (tmp_path / "_static" / "mathjax").mkdir(parents=True)
    (tmp_path / "_static" / "mathjax" / "tex-chtml.js").write_text("")
    for d in ("guide", "_notebooks", "_images"):
        (tmp_path / d).mkdir()
    (tmp_path / "_images" / "a.png").write_bytes(b"png")
    (tmp_path / "index.html").write_text(page())
    img = '<img src="{}_images/a.png">'
    (tmp_path / "guide" / "tests.html").write_text(
        page(MATH + img.format("../"), ["_static/mathjax/tex-chtml.js"], "../"))
    (tmp_path / "guide" / "installation.html").write_text(page("no figure here"))
    (tmp_path / "results.html").write_text(page(img.format("")))
    (tmp_path / "gallery.html").write_text(page(img.format("") * 3))
    (tmp_path / "_notebooks" / "01.html").write_text(page(img.format("../")))
    return tmp_path


def test_check_passes_and_counts(site, capsys):
    assert check_site.main([str(site)]) == 0
    out = capsys.readouterr().out
    assert "guide: 1 image(s) on 2 page(s)" in out and "gallery: 3 image(s) on 1 page(s)" in out
    assert "notebooks: 1 image(s) on 1 page(s)" in out
    assert "math: 1 page(s) with math, 1 load MathJax from _static/mathjax/" in out


def test_check_fails_without_a_build(tmp_path, capsys):
    assert check_site.main([str(tmp_path / "missing")]) == 1
    assert "no index.html; build the site first" in capsys.readouterr().err


@pytest.mark.parametrize("breakage, message", [
    (lambda s: (s / "results.html").write_text(page("text only")), "results: no <img> on results.html"),
    (lambda s: (s / "guide" / "tests.html").write_text(page(MATH, ["_static/mathjax/tex-chtml.js"], "../")),
     "guide: no <img>"),
    (lambda s: (s / "_notebooks" / "01.html").write_text(page()), "no <img> (was the notebook executed?)"),
    (lambda s: (s / "_images" / "a.png").unlink(), "image _images/a.png does not exist"),
    (lambda s: (s / "guide" / "tests.html").write_text(
        page(MATH + '<img src="../_images/a.png">',
             ["https://cdn.jsdelivr.net/npm/mathjax@3/es5/tex-mml-chtml.js"])),
     "holds math but loads no MathJax from _static/mathjax/"),
    (lambda s: (s / "_static" / "mathjax" / "tex-chtml.js").unlink(), "holds math but loads no MathJax"),
    (lambda s: (s / "gallery.html").write_text(page('<img src="a.png">', ["https://example.org/x.js"])),
     "loads scripts from the network"),
])
def test_check_fails_on_each_breakage(site, capsys, breakage, message):
    breakage(site)
    assert check_site.main([str(site)]) == 1
    assert message in capsys.readouterr().err


def test_build_runs_the_check():
    code = [ln for ln in (DOCS / "build.sh").read_text().splitlines() if not ln.lstrip().startswith("#")]
    sphinx = next(i for i, ln in enumerate(code) if "-m sphinx -W" in ln)
    check = next(i for i, ln in enumerate(code) if "docs/scripts/check_site.py" in ln)
    assert sphinx < check and not code[sphinx].lstrip().startswith("exec")


def test_conf_executes_notebooks_and_renders_math_offline():
    conf = (DOCS / "conf.py").read_text()
    assert '"sphinx-mathjax-offline"' in conf
    assert 'nb_execution_mode = "off" if os.environ.get("TSFDI_DOCS_EXECUTE") == "0" else "force"' in conf
    template = (DOCS / "_templates" / "autosummary" / "class.rst").read_text()
    assert ":inherited-members:" in template


def _api_entries() -> set[str]:
    """The autosummary entries of docs/api.rst, as full dotted names."""
    text = (DOCS / "api.rst").read_text()
    names = set()
    for block in re.findall(r"\.\. autosummary::\n((?:   .*\n|\n)+)", text):
        names |= {f"tsfdi.{ln.strip()}" for ln in block.splitlines()
                  if ln.strip() and not ln.strip().startswith(":")}
    return names


def _resolve(dotted: str):
    obj = tsfdi
    for part in dotted.split(".")[1:]:
        obj = getattr(obj, part)
    return obj


def test_api_reference_lists_every_public_name():
    """Every public name of tsfdi, tsfdi.plotting, tsfdi.datasets and tsfdi.study has an API page."""
    import tsfdi.datasets
    import tsfdi.plotting
    import tsfdi.study

    documented = {id(_resolve(n)) for n in _api_entries()}
    missing = []
    for mod in (tsfdi, tsfdi.plotting, tsfdi.datasets, tsfdi.study):
        for name in mod.__all__:
            obj = getattr(mod, name)
            if name.startswith("__") or type(obj).__name__ == "module" or name == "plot_acf" and mod is tsfdi:
                continue
            if id(obj) not in documented and not isinstance(obj, (int, float, str, tuple)):
                missing.append(f"{mod.__name__}.{name}")
    assert not missing, f"no page in docs/api.rst for {missing}"
    for name in ("plot_monitor", "plot_variance_evolution", "plot_confusion"):
        assert f"tsfdi.plotting.{name}" in _api_entries()


def test_gallery_draws_every_plot():
    """docs/gallery.md calls every public plot function, or the ``.plot`` method that draws it."""
    import tsfdi.plotting

    text = (DOCS / "gallery.md").read_text()
    cells = "\n".join(re.findall(r"```\{code-cell\}[^\n]*\n(.*?)```", text, flags=re.S))
    cells = re.sub(r"#.*", "", cells)                # calls, not comments
    for name in tsfdi.plotting.__all__:
        assert f"plotting.{name}(" in cells, f"the gallery does not draw {name}"
    assert "file_format: mystnb" in text        # executed by the build (myst-nb text notebook)
    assert "gallery" in (DOCS / "index.rst").read_text()


def test_guide_and_results_embed_figures_that_exist():
    """Figures referenced by the guide and the results page exist (the site check counts them once built)."""
    refs = []
    for md in [*(DOCS / "guide").glob("*.md"), DOCS / "results.md"]:
        text = md.read_text()
        for src in re.findall(r"```\{figure\} (\S+)", text) + re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text):
            refs.append((md, src))
            assert (md.parent / src).is_file(), f"{md.name}: {src} does not exist"
    pages = {md.name for md, _ in refs}
    assert {"hexacopter.md", "selection.md", "tests.md", "windows.md", "results.md"} <= pages

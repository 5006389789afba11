"""The documentation site (``mkdocs.yml``, ``docs/``): it builds with ``--strict`` (no
broken link or anchor, no docstring the API reference cannot render, no page left out of
the navigation), every public subpackage has its API page, the performance page's tables
are the generator's, and the pages cite papers, not the project's internal notes."""

import importlib.util
import os
import re
import subprocess
import sys

import pytest

from ..conftest import REPO
from ._examples import DOCS, INTERNAL

NEEDED = ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers.python")
MISSING = [m for m in NEEDED if importlib.util.find_spec(m.split(".")[0]) is None]


@pytest.mark.skipif(
    bool(MISSING),
    reason=f"the documentation tools are not installed ({', '.join(MISSING)}): "
    "pip install -e '.[docs]'",
)
def test_site_builds_strictly(tmp_path):
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path)],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    log = proc.stdout + proc.stderr
    assert proc.returncode == 0, log
    assert "WARNING" not in log, log
    # the API reference rendered the docstrings (not just the page titles)
    page = (tmp_path / "api" / "operators" / "index.html").read_text()
    assert "hdrjax.operators.Reinhard2002" in page and "doi.org" in page
    # the command-line reference was generated from the parser
    cli = (tmp_path / "guide" / "cli" / "index.html").read_text()
    assert "hdrjax tonemap" in cli and "usage: hdrjax tonemap" in cli


def _nav_api_pages() -> set[str]:
    return set(re.findall(r"api/([a-z_]+)\.md", (REPO / "mkdocs.yml").read_text()))


def test_every_public_subpackage_has_an_api_page():
    import hdrjax

    for name, module in hdrjax._SUBMODULES.items():
        target = "hdrjax" + module
        text = (DOCS / "api" / f"{name}.md").read_text()
        assert f"::: {target}\n" in text, f"docs/api/{name}.md does not render {target}"
    assert _nav_api_pages() == {*hdrjax._SUBMODULES, "index"}


def test_performance_page_is_the_generators():
    """The tables between the markers of docs/performance.md are what ``benchmarks/report.py
    --readme docs/performance.md`` writes from the committed results (one source)."""
    sys.path.insert(0, str(REPO / "benchmarks"))
    try:
        import report
    finally:
        sys.path.remove(str(REPO / "benchmarks"))
    page = DOCS / "performance.md"
    results_dir = REPO / "benchmarks" / "results"
    section = report.readme_section(
        report.load_results(results_dir), page.parent, results_dir, page
    )
    text = page.read_text()
    inner = text.split(report.BEGIN, 1)[1].split(report.END, 1)[0]
    assert inner.strip() == section.strip()
    # a link outside the site's folder points at the repository
    assert f"]({report.REPO_URL}benchmarks/results/REPORT.md)" in inner


PAGES = sorted(p for p in DOCS.rglob("*.md") if "api" not in p.relative_to(DOCS).parts)


@pytest.mark.parametrize("path", PAGES, ids=lambda p: p.relative_to(DOCS).as_posix())
def test_pages_cite_papers_not_internal_notes(path):
    assert INTERNAL.findall(path.read_text()) == []

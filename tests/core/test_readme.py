"""The README: short (what it is, install, the two commands, one example, links to the
guide), its example runs as written, and its links lead to pages that exist. The guide's
examples and the figures it quotes are checked in ``test_guide.py``."""

import re

import pytest

from ..conftest import REPO
from ._examples import INTERNAL, README, python_blocks, run_block

TEXT = README.read_text()
BLOCKS = python_blocks(README)
SITE = "https://hdrjax.github.io/hdrjax/"


def test_readme_is_short_and_has_the_essentials():
    assert len(BLOCKS) == 1, "one example; the others live in the guide (docs/guide/)"
    for needed in ("make demo", "make test", "pip install", SITE):
        assert needed in TEXT
    assert len(TEXT.splitlines()) < 120


def test_readme_links_lead_to_pages_that_exist():
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", TEXT)
    local = [link for link in links if not link.startswith(("http://", "https://"))]
    assert {"docs/index.md", "docs/guide/tonemapping.md", "docs/guide/cli.md"} <= set(local)
    missing = [link for link in local if not (REPO / link).is_file()]
    assert missing == []


def test_readme_cites_papers_not_internal_notes():
    assert INTERNAL.findall(TEXT) == []


@pytest.mark.parametrize("i", range(len(BLOCKS)))
def test_readme_example_runs(i, monkeypatch, capsys):
    run_block(BLOCKS[i], f"README.md example {i + 1}", monkeypatch, capsys)

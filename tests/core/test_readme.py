"""The README is the user's manual: every Python example in it runs as written."""

import re

import pytest

from ..conftest import REPO

BLOCKS = re.findall(r"```python\n(.*?)```", (REPO / "README.md").read_text(), re.S)


def test_readme_has_examples():
    assert len(BLOCKS) >= 3
    assert "make demo" in (REPO / "README.md").read_text()
    assert "make test" in (REPO / "README.md").read_text()


@pytest.mark.parametrize("i", range(len(BLOCKS)))
def test_readme_example_runs(i, monkeypatch, capsys):
    monkeypatch.chdir(REPO)  # examples use data/ and out/ relative to the repository
    (REPO / "out").mkdir(exist_ok=True)  # as `make demo` creates it; a fresh clone has none
    exec(compile(BLOCKS[i], f"README.md example {i + 1}", "exec"), {"__name__": "__readme__"})
    assert capsys.readouterr().out.strip()  # each example prints what it computed

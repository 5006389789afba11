"""Every notebook runs top to bottom (code cells executed in order, outputs stripped)."""

import json

import pytest

from ..conftest import REPO

NOTEBOOKS = sorted((REPO / "notebooks").glob("*.ipynb"))
DEDICATED = {"vision.ipynb": "tests/vision/test_notebook.py"}  # run there, with assertions


def test_there_are_notebooks():
    assert any(p.name == "quickstart.ipynb" for p in NOTEBOOKS)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs_and_is_stripped(path, monkeypatch, capsys):
    nb = json.loads(path.read_text())
    for i, cell in enumerate(nb["cells"]):
        assert not cell.get("outputs"), f"{path.name} cell {i}: outputs not stripped"
    if path.name in DEDICATED:
        return
    monkeypatch.chdir(REPO)
    scope = {"__name__": "__notebook__"}
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "code":
            continue
        exec(compile("".join(cell["source"]), f"{path.name} cell {i}", "exec"), scope)
    assert capsys.readouterr().out.strip()

"""Every notebook in ``notebooks/`` runs top to bottom in a real Jupyter kernel (nbclient +
ipykernel) and shows what a reader expects: text, and an inline figure wherever it plots.

The committed files have their outputs stripped; each executed copy is written to
``out/notebooks/<name>.ipynb`` (git-ignored) so that the figures can be looked at. A notebook's
own last cell holds the assertions on its results (``lights.ipynb``, ``vision.ipynb``, ...):
a failing one is a cell error here.
"""

import base64
import re

import nbclient
import nbformat
import pytest

from ..conftest import REPO

NOTEBOOKS = sorted((REPO / "notebooks").glob("*.ipynb"))
OUT = REPO / "out" / "notebooks"
CELL_TIMEOUT_S = 600  # one cell; the slowest notebook takes well under a minute
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
# a cell that makes a figure (pyplot, or the benchmark report's figure helpers) must show it
MAKES_FIGURE = re.compile(r"\bplt\.(subplots|figure)\(|\b\w+_figure\(")


def _read(path):
    return nbformat.read(path, as_version=4)


def _code(nb):
    return [c for c in nb.cells if c.cell_type == "code"]


def test_there_are_notebooks():
    assert any(p.name == "quickstart.ipynb" for p in NOTEBOOKS)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_is_stripped(path):
    nb = _read(path)
    for i, cell in enumerate(nb.cells):
        if cell.cell_type == "code":
            assert not cell.outputs, f"{path.name} cell {i}: outputs not stripped"
            assert cell.execution_count is None, f"{path.name} cell {i}: execution count kept"
    # an explicit non-interactive backend shows nothing in Jupyter
    for i, cell in enumerate(_code(nb)):
        assert not re.search(r"matplotlib\.use\(", cell.source), (
            f"{path.name} code cell {i}: selects a matplotlib backend (figures must show inline)"
        )


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs_in_a_kernel(path):
    nb = _read(path)
    client = nbclient.NotebookClient(
        nb,
        timeout=CELL_TIMEOUT_S,
        kernel_name="python3",
        resources={"metadata": {"path": str(REPO)}},
    )
    OUT.mkdir(parents=True, exist_ok=True)
    try:
        client.execute()
    except nbclient.exceptions.CellExecutionError as e:
        bad = [
            f"cell {i} (id {c.get('id')})"
            for i, c in enumerate(nb.cells)
            if any(o.output_type == "error" for o in c.get("outputs", []))
        ]
        pytest.fail(f"{path.name}: {', '.join(bad) or 'a cell'} raised\n{e}", pytrace=False)
    finally:
        nbformat.write(nb, OUT / path.name)

    outputs = [o for c in _code(nb) for o in c.outputs]
    printed = "".join(o.text for o in outputs if o.get("name") == "stdout")
    assert printed.strip(), f"{path.name}: prints nothing"
    errors = [o for o in outputs if o.output_type == "error"]
    assert not errors, f"{path.name}: error outputs {errors}"
    stderr = "".join(o.text for o in outputs if o.get("name") == "stderr")
    assert "Traceback" not in stderr, f"{path.name}: a traceback on stderr:\n{stderr}"

    pngs = {
        i: [
            base64.b64decode(o.data["image/png"])
            for o in c.outputs
            if "image/png" in o.get("data", {})
        ]
        for i, c in enumerate(_code(nb))
    }
    for i, cell in enumerate(_code(nb)):
        for png in pngs[i]:
            assert png.startswith(PNG_MAGIC), f"{path.name} code cell {i}: not a PNG"
        if MAKES_FIGURE.search(cell.source):
            assert pngs[i], f"{path.name} code cell {i}: makes a figure but shows no image/png"

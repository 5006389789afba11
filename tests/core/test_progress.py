"""Progress bars show where a person watches: in a Jupyter kernel too, not only on a
terminal; never in a pipe (the test run itself)."""

import nbformat
from nbclient import NotebookClient

from hdrjax._progress import in_notebook, interactive

from ..conftest import DATA, REPO

CELL = f"""
import shutil, tempfile
from hdrjax._progress import interactive
import hdrjax.batch as hb
print("interactive:", interactive())
folder = tempfile.mkdtemp()
src = {str(DATA / "cornell_box.exr")!r}
frames = [shutil.copy(src, f"{{folder}}/f{{i}}.exr") for i in range(2)]
hb.run(frames, "linear", folder + "/out", progress=True)
"""


def test_not_in_a_pipe(monkeypatch):
    import io
    import sys

    monkeypatch.setattr(sys, "stderr", io.StringIO())  # a pipe or a log, not a terminal
    assert not in_notebook() and not interactive()


def test_batch_shows_its_progress_in_a_notebook():
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(CELL)])
    NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(REPO)}}
    ).execute()
    outputs = nb.cells[0].outputs
    text = "".join(o.get("text", "") for o in outputs if o.get("name") == "stdout")
    assert "interactive: True" in text
    # tqdm.auto: a widget where ipywidgets is installed, else its text bar on stderr
    shown = [o for o in outputs if o.get("name") == "stderr" and "2/2" in o.get("text", "")]
    widgets = [
        o for o in outputs if "application/vnd.jupyter.widget-view+json" in o.get("data", {})
    ]
    assert shown or widgets

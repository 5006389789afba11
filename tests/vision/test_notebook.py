"""notebooks/vision.ipynb runs from top to bottom and shows what it says it shows."""

import json

import matplotlib
import numpy as np

from ..conftest import REPO


def test_vision_notebook_executes(monkeypatch):
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.setattr(plt, "show", lambda *a, **k: None)
    nb = json.loads((REPO / "notebooks" / "vision.ipynb").read_text())
    ns: dict = {"__name__": "__main__"}
    for i, cell in enumerate(c for c in nb["cells"] if c["cell_type"] == "code"):
        exec(compile("".join(cell["source"]), f"vision.ipynb[{i}]", "exec"), ns)
    plt.close("all")
    sel = {name: set(rep.selected) for name, rep in ns["reports"].items()}
    assert sel["daylight"] == set()
    assert {"glare", "colour_loss", "contrast"} <= sel["dusk"] and "acuity" not in sel["dusk"]
    assert {"acuity", "glare", "colour_loss", "blue_shift", "contrast"} == sel["night"]
    assert ns["reports"]["starlight"].glare_variant == "scotopic"
    # the last panel, Budak2005 in starlight, shows a night scene (it was 0.72, the
    # adaptation level at half the display's maximum): see the notebook's text
    starlit = np.asarray(ns["perceptual"])
    assert ns["name"] == "starlight" and starlit.mean() < 0.3

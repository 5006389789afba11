"""The operator gallery: one image through every registered operator, at its defaults.

Writes ``docs/gallery.jpg`` (a labelled grid, sRGB) and ``docs/gallery.json`` (the operators
shown, in order, and how each one's input was scaled), which the README shows so that a
user can choose an operator by looking::

    .venv/bin/python docs/gallery.py

The image is ``data/rooitou_park_1k.hdr`` (a daylight panorama, Radiance units W/(sr·m²)),
box-averaged to 256 × 128. Operators whose parameters are in cd/m² (``drago2003``'s display,
``ward1994``, ``ferwerda1996``, the Tumblin–Rushmeier family, ``budak2005``, …) and the
cone model ``vanhateren2006`` see it in
cd/m² (× 179, Radiance's luminous efficacy); the others see it exposed so that its
log-average luminance is 0.18 (middle grey), as a photographer or a renderer's exposure
would set it. ``tabulated`` is given a three-point table (0.001 → 0, 0.18 → 0.18,
100 → 1). Every other parameter is at its default, estimated ones measured from the image.
"""

import argparse
import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import hdrjax  # noqa: E402
from hdrjax.operators import parameter_info  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
IMAGE = ROOT / "data" / "rooitou_park_1k.hdr"
EFFICACY = 179.0  # cd/m² per W/(sr·m²)
TABLE = {"luminance": [0.001, 0.18, 100.0], "display": [0.0, 0.18, 1.0]}


ABSOLUTE = {"vanhateren2006"}
"""Operators that take cd/m² without a parameter in cd/m² (the cone model's constants)."""


def absolute(name: str) -> bool:
    """Whether the operator's input is absolute luminance: a parameter in cd/m²."""
    info = parameter_info(hdrjax.get_operator(name))
    return name in ABSOLUTE or any(i.unit == "cd/m²" for i in info)


def load(factor: int = 4) -> np.ndarray:
    rgb = np.asarray(hdrjax.io.read(IMAGE).rgb(), np.float64)
    h, w = (s // factor * factor for s in rgb.shape[:2])
    rgb = rgb[:h, :w].reshape(h // factor, factor, w // factor, factor, 3).mean(axis=(1, 3))
    return np.maximum(rgb, 0.0).astype(np.float32)


def render(rgb: np.ndarray) -> tuple[list[str], list[np.ndarray], list[str]]:
    L = rgb @ np.asarray(hdrjax.REC709_WEIGHTS, np.float32)
    exposure = 0.18 / math.exp(float(np.mean(np.log(np.maximum(L, 1e-9)))))
    names, images, inputs = [], [], []
    for name in hdrjax.operator_names():
        if absolute(name):
            x, how = rgb * EFFICACY, "cd/m² (× 179)"
        else:
            x, how = rgb * exposure, f"relative, log-average 0.18 (× {exposure:.3g})"
        out = hdrjax.tonemap(x, name, **(TABLE if name == "tabulated" else {}))
        shown = np.asarray(hdrjax.display.srgb_encode(np.clip(np.asarray(out), 0.0, 1.0)))
        names.append(name)
        images.append(shown)
        inputs.append(how)
    return names, images, inputs


def figure(names: list[str], images: list[np.ndarray], cols: int = 5):
    rows = math.ceil(len(names) / cols)
    h, w = images[0].shape[:2]
    fig, axes = plt.subplots(rows, cols, figsize=(cols * 2.6, rows * 2.6 * h / w + rows * 0.3))
    for ax in np.ravel(axes):
        ax.axis("off")
    for ax, name, img in zip(np.ravel(axes), names, images, strict=False):
        ax.imshow(img, interpolation="nearest")
        ax.set_title(name, fontsize=9, family="monospace")
    fig.tight_layout(pad=0.3)
    return fig


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs")
    args = parser.parse_args()
    names, images, inputs = render(load())
    fig = figure(names, images)
    jpg = args.out / "gallery.jpg"
    fig.savefig(jpg, dpi=100, pil_kwargs={"quality": 85})
    record = {
        "image": IMAGE.name,
        "operators": names,
        "input": dict(zip(names, inputs, strict=True)),
    }
    (args.out / "gallery.json").write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {jpg} ({len(names)} operators)")


if __name__ == "__main__":
    main()

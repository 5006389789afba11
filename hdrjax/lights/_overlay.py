"""Loghin 2019's figures: detected lights drawn over the tone-mapped map (matplotlib, NumPy side).

Blue dots are the lights' local maxima (cluster seeds), cyan crosses their final positions
(energy centroids), red dots the samples that joined a light, each joined to its light by a
line (wrapped across the seam on panoramas); grey dots are the other candidate samples.
"""

from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Float

from .. import _check
from ._result import Lights


def display_image(rgb: Float[ArrayLike, "H W 3"], method: str = "reinhard2002") -> np.ndarray:
    """sRGB-encoded tone-mapped view of a linear map, ``(H, W, 3)`` float in [0, 1].

    Non-finite pixels are shown black.
    """
    _check.real(rgb, "rgb")
    from .. import display, tonemap

    x = np.asarray(rgb, np.float32)
    x = np.where(np.isfinite(x).all(axis=-1, keepdims=True), np.maximum(x, 0), 0)
    return np.asarray(display.encode(tonemap(x, method=method)))


def plot_lights(
    rgb: Float[ArrayLike, "H W 3"],
    lights: Lights,
    *,
    ax: Any = None,
    labels: bool = True,
    method: str = "reinhard2002",
) -> Any:
    """Draw one map's lights over its tone-mapped image; returns the matplotlib Axes.

    Args:
        rgb: the map the lights were detected on (any resolution; positions are scaled).
        lights: the result of :func:`~hdrjax.lights.detect` (or ``detect_image``) for it.
        ax: Axes to draw into (a new figure when ``None``).
        labels: number the lights (largest energy = 0).
        method: tone-mapping operator for the background (:func:`hdrjax.tonemap`).
    """
    import matplotlib.pyplot as plt

    if np.ndim(lights.count) != 0:
        raise ValueError("plot_lights: pass one map's result, not a batch")
    img = display_image(rgb, method)
    h, w = img.shape[:2]
    sx, sy = w / lights.input_shape[1], h / lights.input_shape[0]
    if ax is None:
        _, ax = plt.subplots(figsize=(10, 10 * h / w))
    ax.imshow(img, extent=(-0.5, w - 0.5, h - 0.5, -0.5), interpolation="nearest")
    n = int(lights.count)
    pix = np.asarray(lights.pixel)[:n] * [sx, sy]
    peak = np.asarray(lights.peak_pixel)[:n] * [sx, sy]
    samples = np.asarray(lights.samples) * [sx, sy]
    owner = np.asarray(lights.sample_light)
    used = np.any(samples != 0, axis=1) | (owner >= 0)
    wrap = lights.projection == "equirectangular"
    for s, k in zip(samples[used], owner[used], strict=True):
        if k < 0:
            ax.plot(*s, ".", color="0.6", ms=3)
            continue
        t = peak[k].copy()
        if wrap and abs(t[0] - s[0]) > w / 2:  # draw the short way, across the seam
            t[0] += w if s[0] > t[0] else -w
        ax.plot([s[0], t[0]], [s[1], t[1]], "-", color="red", lw=0.6, alpha=0.7)
        ax.plot(*s, ".", color="red", ms=4)
    ax.plot(peak[:, 0], peak[:, 1], "o", color="blue", ms=5, mfc="none", mew=1.5)
    ax.plot(pix[:, 0], pix[:, 1], "x", color="cyan", ms=8, mew=2)
    if labels:
        for k, (x, y) in enumerate(pix):
            ax.annotate(str(k), (x, y), xytext=(5, -5), textcoords="offset points", color="cyan")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_axis_off()
    return ax


__all__ = ["display_image", "plot_lights"]

"""Images in notebooks: :func:`show`, and the thumbnails objects show of themselves.

Numeric contract: HDR images are linear RGB ``(H, W, 3)`` (or ``(H, W)`` luminance, or a
:class:`~hdrjax.layers.LayeredImage`), tone-mapped for display with a registered operator
(Reinhard et al. 2002 by default) and sRGB-encoded; display images (integer arrays) are
shown as they are.
"""

from typing import Any

import numpy as np

from ._repr import png_data_uri as png_data_uri

THUMBNAIL = 256
"""Longest side of a thumbnail (pixels)."""


def _is_layered(x: Any) -> bool:
    """A :class:`~hdrjax.layers.LayeredImage` (by its interface: this module is imported by
    the layers package, so it does not import it)."""
    return callable(getattr(x, "rgb", None)) and hasattr(x, "channels") and hasattr(x, "name")


def _rgb(x: Any) -> np.ndarray:
    """Linear RGB ``(H, W, 3)`` float32 of an array or a LayeredImage."""
    if _is_layered(x):
        return np.asarray(x.rgb(), np.float32)
    a = np.asarray(x)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=-1)
    if a.ndim != 3 or a.shape[-1] not in (3, 4):
        raise ValueError(f"image: expected (H, W), (H, W, 3) or (H, W, 4), got shape {a.shape}")
    return a[..., :3]


def _box(a: np.ndarray, size: int) -> np.ndarray:
    """Box-average ``a`` so its longest side is at most ``size`` (NaN pixels left out)."""
    f = max(1, -(-max(a.shape[:2]) // size))
    if f == 1:
        return a
    h, w = (a.shape[0] // f) * f, (a.shape[1] // f) * f
    blocks = a[:h, :w].reshape(h // f, f, w // f, f, *a.shape[2:])
    with np.errstate(invalid="ignore"):
        return np.nanmean(blocks.astype(np.float64), axis=(1, 3))


def display_image(x: Any, method: str = "reinhard2002", size: int | None = THUMBNAIL, **params):
    """``(h, w, 3)`` uint8 sRGB of ``x``: integer arrays as they are (8 or 16 bits), HDR
    arrays tone-mapped by ``method`` (its ``params``) after box-averaging to ``size`` on the
    longest side (``None``: full size); NaN/Inf pixels show black."""
    from . import display, operators

    a = _rgb(x)
    if np.issubdtype(a.dtype, np.integer):
        top = 255 if a.dtype == np.uint8 else float(np.iinfo(a.dtype).max)
        small = a if size is None else _box(a, size)
        return np.clip(np.rint(np.asarray(small, np.float64) / top * 255), 0, 255).astype(np.uint8)
    small = np.asarray(a if size is None else _box(a, size), np.float32)
    small = np.where(np.isfinite(small), small, 0.0).astype(np.float32)
    out = operators.tonemap(small, method, **params)
    return np.asarray(display.quantize(display.encode(out), 8))


def show(
    *images: Any,
    titles: list[str] | tuple[str, ...] | None = None,
    method: str = "reinhard2002",
    width: float = 12.0,
    size: int | None = 512,
    **params: Any,
):
    """Show HDR images side by side: a matplotlib :class:`~matplotlib.figure.Figure` (no
    pyplot state) that a notebook displays when it is a cell's value.

    Args:
        images: HDR arrays ``(H, W, 3)`` or ``(H, W)``, LayeredImages (their linear RGB), or
            integer display images (shown as they are).
        titles: one per image (default: the LayeredImage's name, else none).
        method: the operator that maps HDR images for display, with ``params``.
        width: figure width in inches.
        size: longest side each image is box-averaged to first (``None``: full size).

    Raises:
        ValueError: no image, a title count that differs, or an array that is not an image.
    """
    from matplotlib.figure import Figure

    if not images:
        raise ValueError("images: expected at least one image")
    if titles is not None and len(titles) != len(images):
        raise ValueError(f"titles: expected {len(images)} titles, got {len(titles)}")
    shown = [display_image(x, method, size, **params) for x in images]
    if titles is None:
        titles = [x.name if _is_layered(x) else "" for x in images]
    n = len(shown)
    aspect = max(s.shape[0] / s.shape[1] for s in shown)
    fig = Figure(figsize=(width, width / n * aspect + 0.5), layout="constrained")
    axes = fig.subplots(1, n, squeeze=False)[0]
    for ax, img, title in zip(axes, shown, titles, strict=True):
        ax.imshow(img, interpolation="lanczos")
        ax.set_axis_off()
        if title:
            ax.set_title(title, fontsize=10)
    return fig


__all__ = ["THUMBNAIL", "display_image", "png_data_uri", "show"]

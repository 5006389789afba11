"""Plots of operators (matplotlib, imported on first use; NumPy side, never jitted).

:func:`tone_curve` shows how an operator maps an image's world luminance to display
luminance, over the histogram of that image's luminance, so one sees where the pixels fall
on the curve. Sweeps are plotted by :func:`hdrjax.study.plot_sweep`.
:func:`angular_grid` draws a panorama's or view's azimuth/elevation grid onto an Axes,
:func:`with_angular_grid` over a display image.
"""

from typing import Any

import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike, Float

from ._angular_grid import (
    angular_grid as angular_grid,
    with_angular_grid as with_angular_grid,
)
from .operators import make_operator
from .operators._base import AbstractLuminanceCurve, AbstractOperator, as_float_image


def tone_curve(
    operator: AbstractOperator | str,
    image: Float[ArrayLike, "H W 3"],
    ax: Any = None,
    *,
    bins: int = 64,
    points: int = 256,
    max_scatter: int = 4000,
) -> Any:
    """Draw ``operator``'s world → display luminance mapping over the image's histogram.

    The operator's unset (``None``) parameters are first measured from ``image``
    (:meth:`~hdrjax.operators.AbstractOperator.measure`), so the curve is the one
    :func:`hdrjax.tonemap` applies to this image. The x axis is world luminance ``L_w``
    (image units, log scale) from the image's smallest positive to its largest finite
    luminance; the left y axis is display luminance ``L_d`` (display-referred linear, 1 =
    display white, drawn as a dotted line; values above it clip when encoded, so the axis
    stops at 1.2).

    - Operators that map luminance through a curve (:class:`~hdrjax.operators.
      AbstractLuminanceCurve`: ``reinhard2002``, ``linear``, ``tumblin_reinhard``, …): the
      curve ``L_d = curve(L_w)`` at ``points`` log-spaced luminances (one line, gid
      ``"tone_curve"``).
    - Other operators (local ones such as ``reinhard2002_local``, per-channel ones such as
      ``filmic`` or ``simple``), whose ``L_d`` is not a function of ``L_w`` alone: the
      display luminance ``luminance(operator(image))`` of each pixel, as a scatter of at most
      ``max_scatter`` pixels (every n-th, gid ``"pixels"``) and its mean in each histogram
      bin (one line, gid ``"tone_curve"``).

    The histogram (fraction of pixels per bin of ``log10 L_w``, ``bins`` bins) is drawn on a
    twin right axis, behind the curve.

    Args:
        operator: an operator instance or a registered name.
        image: linear RGB ``(H, W, 3)``.
        ax: Axes to draw into (a new figure when ``None``).
        bins: histogram bins (and bins of the binned mean).
        points: curve samples.
        max_scatter: pixels in the scatter of non-curve operators.

    Returns:
        The Axes holding the curve (the histogram's twin shares its x axis).

    Raises:
        ValueError: a malformed image, one without positive finite luminance, or bad counts.
    """
    import matplotlib.pyplot as plt

    op = make_operator(operator) if isinstance(operator, str) else operator
    if not isinstance(op, AbstractOperator):
        raise ValueError(f"operator: expected an operator or a registered name, got {op!r}")
    for n, v in (("bins", bins), ("points", points)):
        if not int(v) >= 2:
            raise ValueError(f"{n}: expected an integer >= 2, got {v!r}")
    rgb = as_float_image(image, "image")
    if rgb.ndim != 3:
        raise ValueError(f"image: expected one image (H, W, 3), got {rgb.shape}")
    w = np.asarray(op.weights_, np.float64)
    L = np.asarray(rgb, np.float64) @ w
    ok = np.isfinite(L) & (L > 0)
    if not np.any(ok):
        raise ValueError("image: no pixel with finite positive luminance to plot")
    lo, hi = float(L[ok].min()), float(L[ok].max())
    if hi <= lo:  # a flat image: widen by a factor 2 each way so the axis has a range
        lo, hi = lo / 2, hi * 2
    op = op.measure(rgb)
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4), layout="constrained")

    edges = np.linspace(np.log10(lo), np.log10(hi), int(bins) + 1)
    counts, _ = np.histogram(np.log10(L[ok]), edges)
    hax = ax.twinx()
    hax.stairs(counts / ok.sum(), 10.0**edges, fill=True, color="0.8", label="pixels")
    hax.set_ylabel("fraction of pixels")
    ax.set_zorder(hax.get_zorder() + 1)  # the curve in front of the histogram
    ax.patch.set_visible(False)

    if isinstance(op, AbstractLuminanceCurve):
        x = np.geomspace(lo, hi, int(points))
        y = np.asarray(op.curve(jnp.asarray(x, rgb.dtype)), np.float64)
        ax.plot(x, y, color="C0", lw=2, label=f"{op.name} curve", gid="tone_curve")
    else:
        Ld = (np.asarray(op(rgb), np.float64) @ w)[ok]
        Lw = L[ok]
        step = max(1, -(-Lw.size // int(max_scatter)))
        ax.scatter(Lw[::step], Ld[::step], s=2, alpha=0.3, color="C1", label="pixels", gid="pixels")
        idx = np.clip(np.digitize(np.log10(Lw), edges) - 1, 0, int(bins) - 1)
        n = np.bincount(idx, minlength=int(bins))
        mean = np.bincount(idx, Ld, minlength=int(bins)) / np.maximum(n, 1)
        centres = 10.0 ** (0.5 * (edges[1:] + edges[:-1]))
        ax.plot(
            centres[n > 0],
            mean[n > 0],
            color="C0",
            lw=2,
            marker=".",
            label=f"{op.name}: mean per bin",
            gid="tone_curve",
        )
    ax.axhline(1.0, color="0.3", ls=":", lw=1, label="display white")
    (line,) = [ln for ln in ax.lines if ln.get_gid() == "tone_curve"]
    y = np.asarray(line.get_ydata(), np.float64)
    y_lo, y_hi = min(float(np.nanmin(y)), 0.0), max(float(np.nanmax(y)), 1.0)
    ax.set_ylim(y_lo - 0.03, min(y_hi, 1.2) + 0.03)
    ax.set_xscale("log")
    ax.set_xlim(lo, hi)
    ax.set_xlabel("world luminance $L_w$ (image units)")
    ax.set_ylabel("display luminance $L_d$")
    ax.set_title(op.name)
    ax.legend(loc="upper left", fontsize="small")
    return ax


__all__ = ["angular_grid", "tone_curve", "with_angular_grid"]

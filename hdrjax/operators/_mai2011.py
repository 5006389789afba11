"""Mai, Mansour, Mantiuk, Nasiopoulos, Ward, Heidrich 2011 tone curve for backward-compatible
HDR compression, as ``pfstmo_mai11`` (pfstools 2.2.0) computes it.

Reference:
    Mai, Mansour, Mantiuk, Nasiopoulos, Ward, Heidrich. "Optimizing a tone curve for
    backward-compatible high dynamic range image and video compression." IEEE Transactions
    on Image Processing 20(6):1558–1571, 2011. https://doi.org/10.1109/TIP.2010.2090531

The curve is piecewise linear in ``l = log10 L`` with nodes ``l_k = l_min + k δ`` (pfstmo:
``l_min = −6``, ``δ = 0.1``, 150 bins up to ``l_max = 9``). With ``p_k`` the fraction of
pixels whose ``log10 L`` lies in bin ``k`` (``[l_k, l_k + δ)``), the slopes that minimise
the expected squared error of the log luminance restored from the 8-bit image are
    ``s_k = p_k^(1/3) / (δ Σ_j p_j^(1/3))``
(the paper's closed form, normalised so that the curve spans the display's range, 0 … 1),
and the curve is their cumulative sum ``v(l_k) = Σ_{j<k} s_j δ``, linear between nodes.
Luminance below ``10^-5`` (black and negative pixels included) counts as ``10^-5``;
pixels at or above ``10^9`` are left out of the histogram (pfstmo's range).
"""

import math
from typing import ClassVar, Literal

import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._interp import table_lerp
from .._srgb import srgb_decode
from .._stats import Statistics, coarse_counts
from ._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    checked_statistics,
    estimated,
    fill,
    parameter,
    register,
    weights_field,
)

REFERENCE = (
    "Mai, Mansour, Mantiuk, Nasiopoulos, Ward, Heidrich 2011, Optimizing a tone curve for"
    " backward-compatible high dynamic range image and video compression, IEEE Transactions"
    " on Image Processing 20(6):1558-1571, https://doi.org/10.1109/TIP.2010.2090531"
)
LOG_MIN = -6.0
"""``log10`` of the histogram's lower end (pfstmo's ``L_min``), image units."""
BIN_WIDTH = 0.1
"""Histogram bin width ``δ`` in ``log10`` units (pfstmo's)."""
BINS = 150
"""Bins from ``10^-6`` to ``10^9`` (pfstmo's)."""
FLOOR = 1e-5
"""Values below this count as it (pfstmo's ``safelog10f``), image units."""
NODES = BINS + 1
"""Nodes of the tone curve, at ``log10 L = LOG_MIN + k δ``, ``k = 0 … BINS``."""


def histogram(stats: Statistics) -> Array:
    """Pixel counts of pfstmo's ``BINS`` bins of ``log10 L`` from the mergeable statistics.

    The fixed grid's bins regrouped (:func:`~hdrjax._stats.coarse_counts`): a grid bin is a
    factor ``1 + 2^-m`` wide (``2^-10`` by default), about 1/340 of pfstmo's bins, so at
    most the pixels of one grid bin at each edge land in the neighbouring bin. Every finite
    pixel below :data:`FLOOR` (zero and negative ones included) counts in the floor's bin, as
    pfstmo puts them at ``log10 L = −5``; those at or above ``10^9`` are left out.
    """
    assert stats.counts is not None and stats.m is not None
    ln10 = math.log(10.0)
    # one more bin above 10^9 to hold the pixels left out
    h = coarse_counts(
        stats.counts, stats.m, LOG_MIN * ln10, (BINS + 1) * BIN_WIDTH * ln10, BINS + 1
    )
    floor_bin = int(round((math.log10(FLOOR) - LOG_MIN) / BIN_WIDTH))
    below = jnp.maximum(jax.lax.stop_gradient(stats.n_finite) - jnp.sum(h[floor_bin:]), 0)
    return jnp.zeros_like(h[:BINS]).at[floor_bin:].set(h[floor_bin:BINS]).at[floor_bin].add(below)


def tone_curve(h: Array, compat: str = "paper") -> Array:
    """The curve's ``NODES`` values from the bin counts ``h`` (module docstring).

    ``compat="pfstmo"``: node ``k`` takes the slopes of bins 1 … k (``v(l_k) = Σ_{1≤j≤k}
    s_j δ``), pfstmo's loop, which puts each bin's slope on the segment below it (one bin,
    0.1 in ``log10 L``, to the left). No pixel in the histogram: equal probabilities."""
    total = jnp.sum(h)
    p = jnp.where(total > 0, h / jnp.where(total > 0, total, 1.0), 1.0 / h.shape[0])
    root = jnp.cbrt(p)
    s_delta = root / jnp.sum(root)  # s_k δ: sums to 1
    zero = jnp.zeros(1, s_delta.dtype)
    if compat == "pfstmo":
        v = jnp.concatenate([zero, jnp.cumsum(s_delta[1:])])
        return jnp.concatenate([v, v[-1:]])
    return jnp.concatenate([zero, jnp.cumsum(s_delta)])


@register("mai2011")
class Mai2011(AbstractOperator):
    """Mai et al. 2011 tone curve (module docstring) with pfstmo's histogram (``pfstmo_mai11``:
    bins of 0.1 in ``log10`` luminance from ``10^-6`` to ``10^9``, floor ``10^-5``; the
    program has no options).

    Input: linear RGB in the image's own units (the histogram's range and floor are
    absolute: relative images with most pixels below ``10^-5`` should be scaled first).
    Output: display-referred linear RGB in [0, 1].

    The curve ``v`` is the paper's (and pfstmo's) 8-bit image value: display-*encoded*
    (pfstmo tags its output ``LUMINANCE=DISPLAY``). As every hdrjax operator returns
    display-linear values, this one returns ``sRGB⁻¹(v)``: encoding it for an sRGB display
    (:mod:`hdrjax.display`) shows ``v``, pfstmo's values. Colour: the histogram is of
    luminance, and the curve maps each of R, G and B on its own, as pfstmo does (hue and
    saturation change where the curve's slope does).

    ``compat="pfstmo"`` reproduces pfstmo's curve, whose nodes take each bin's slope one
    segment too low (:func:`tone_curve`): the curve 0.1 in ``log10 L`` to the left of the
    paper's, with black (everything below ``10^-5``) mapped to the floor bin's step
    ``s δ`` instead of 0 — an all-black image comes out white there. The default
    (``"paper"``) puts the slope of bin ``k`` between nodes ``k`` and ``k + 1``.

    The histogram comes from the mergeable statistics' fixed-grid histogram (pfstmo's bin
    edges to within one grid bin, a factor ``1 + 2^-10``; :func:`histogram`), so tiles,
    chunks and frames measured apart and merged give the whole image's curve. Gradients:
    the counts are constants for ``jax.grad`` (a histogram has no derivative), so the
    gradient with respect to the image is that of each channel's position on the curve
    (the curve's slope ``s_k / (C ln 10)``; 0 below ``10^-5`` and above ``10^9``), and
    with respect to ``curve`` that of the linear interpolation.

    Attributes:
        curve: the curve's values at ``log10 L = −6 + 0.1 k``, ``k = 0 … 150`` (151
            values in [0, 1], non-decreasing); ``None`` → from the image's histogram.
        compat: ``"paper"`` or ``"pfstmo"`` (see above).
        weights: luminance weights of the image's primaries (for the histogram).
    """

    reference: ClassVar[str] = REFERENCE
    default_fit_params: ClassVar[tuple[str, ...]] = ()  # the curve is the image's histogram

    curve: Array | None = estimated(
        "tone curve's values at log10 L = -6 + 0.1 k (k = 0..150); None: from the histogram",
        range="[0, 1]",
        pooling="mean",
        shape=(NODES,),
    )
    compat: Literal["paper", "pfstmo"] = parameter(
        "paper",
        help="paper: bin k's slope from node k to k+1; pfstmo: one node lower (pfstmo_mai11)",
        static=True,
        choices=("paper", "pfstmo"),
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        if self.curve is not None and self.curve.shape != (NODES,):
            raise ValueError(
                f"curve: expected {NODES} values (log10 L = -6 … 9 in steps of 0.1), got"
                f" shape {self.curve.shape}"
            )

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings() if self.curve is None else None

    def bind(self, stats: Statistics | None) -> "Mai2011":
        if self.curve is not None:
            return self
        h = histogram(checked_statistics(self, stats))
        return fill(self, curve=tone_curve(h, self.compat))

    def _apply(self, p: Prepared) -> Array:
        assert self.curve is not None
        rgb = p.rgb
        x = jnp.log10(jnp.maximum(rgb, jnp.asarray(FLOOR, rgb.dtype)))
        v = table_lerp(self.curve.astype(rgb.dtype), (x - LOG_MIN) / BIN_WIDTH)
        return srgb_decode(v).astype(rgb.dtype)


__all__ = ["Mai2011", "histogram", "tone_curve"]

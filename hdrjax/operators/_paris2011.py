"""Paris, Hasinoff & Kautz 2011 local Laplacian filters for tone mapping, computed by the
fast approximation of Aubry, Paris, Hasinoff, Kautz & Durand 2014.

References:
    Paris, Hasinoff, Kautz. "Local Laplacian filters: edge-aware image processing with a
    Laplacian pyramid." ACM Transactions on Graphics 30(4):68, 2011 (Proc. SIGGRAPH).
    https://doi.org/10.1145/2010324.1964963

    Aubry, Paris, Hasinoff, Kautz, Durand. "Fast local Laplacian filters: theory and
    applications." ACM Transactions on Graphics 33(5):167, 2014.
    https://doi.org/10.1145/2629645

The steps, as the authors' published MATLAB code (``lapfilter.m``, Hasinoff 2011) runs its
tone-mapping example (``'lum'``, ``'log'``), with ``I = ln L`` the natural log of the
intensity ``L = (20 R + 40 G + B) / 61``:

1. Pyramids (Burt & Adelson 1983, as the authors' code builds them): the separable 5-tap
   kernel ``[0.05, 0.25, 0.4, 0.25, 0.05]``, zero outside the image and renormalised by its
   sum over the image pixels ("reweighted" borders); downsampling keeps pixels ``0, 2, 4,
   …``; upsampling puts a level on those pixels, blurs and renormalises by the blurred
   mask. As many levels as halving ``min(H, W)`` (rounding up) takes to reach 1.
2. Remapping around a reference ``g`` (paper section 5, with ``d = I − g``):
   ``r(I) = g + sign(d) σ_r f_d(|d| / σ_r)`` for ``|d| ≤ σ_r`` (detail) and ``g + sign(d)
   (β (|d| − σ_r) + σ_r)`` beyond (edges), with ``f_d(x) = x^α``; for ``α < 1``
   ``f_d(x) = τ x^α + (1 − τ) x``, ``τ`` a smooth step of ``|d|`` from 0.01 to 0.02
   (noise is not amplified).
3. Output Laplacian coefficients (Paris et al. 2011: coefficient ``(ℓ, p)`` of the pyramid
   of ``r`` around ``g = G_ℓ(p)``, the input's Gaussian pyramid) by Aubry et al. 2014's
   approximation: ``K`` references ``γ_k`` evenly from ``min I`` to ``max I``; the whole
   image remapped around each and its Laplacian pyramid built; each output coefficient
   interpolated linearly between the two references around ``G_ℓ(p)``. The coarsest
   level is the input's Gaussian residual. Collapsing the pyramid gives ``R`` (log
   luminance).
4. Display (the authors' post-processing): ``L_d = (e^R / e^{R_hi})^c`` with
   ``c = ln(contrast) / (R_hi − R_lo)``, ``R_lo`` and ``R_hi`` the ``p`` and ``100 − p``
   percentiles of ``R`` (``p = 0.5``: the middle 99 % mapped to ``contrast`` 100 : 1),
   and colour by ratios, ``C_d = (C / L) L_d``.

Deviations from the authors' code, each argued:

- Step 3 is Aubry et al. 2014's discretisation (:attr:`Paris2011.references` levels)
  instead of the exact filter, which remaps a window per coefficient (O(N log N) with a
  large constant, and no fixed-shape computation for ``jit``). Against the exact filter
  (the authors' code under GNU Octave, 48 × 64 real images, sRGB-encoded luminance) the
  default 32 references give an SSIM of 0.9999 or more and a mean difference of 0.002 or
  less for the authors' ``α = 1``; detail enhancement (``α < 1``, where ``x^α`` is steep)
  converges more slowly: ``α = 0.5`` needs about 96 references for an SSIM of 0.986
  (tests/operators/test_paris2011.py).
- Intensities ``L ≤ 0`` take the image's smallest positive intensity (the authors add the
  machine epsilon before the log, which stretches the reference range to ``ln 2^-52`` for
  a single black pixel); such pixels stay black through their zero colour ratios.
- The percentiles interpolate as ``numpy.percentile`` (the authors' ``prctile`` as
  ``(k − 0.5) / n``), on ``R`` rather than ``e^R`` (the same order statistics).
- The result is not clipped to [0, 1] nor gamma-encoded: it is display-referred linear
  RGB whose brightest 0.5 % exceed 1 (the display clips them), as the other operators
  return. Its log is capped at :data:`MAX_LOG_OUT`.

Tiles: the pyramid is as deep as the image allows (the residual is the image's mean) and
the references and percentiles are the whole image's, so the operator needs the whole
image (:meth:`Paris2011.halo` is infinite).
"""

import math
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._scale import quotient
from .._stats import percentile_by_selection
from ._base import (
    AbstractOperator,
    Prepared,
    filled_with_first_valid,
    parameter,
    register,
    weights_field,
)

REFERENCE = (
    "Paris, Hasinoff, Kautz 2011, Local Laplacian filters: edge-aware image processing with"
    " a Laplacian pyramid, ACM Transactions on Graphics 30(4):68,"
    " https://doi.org/10.1145/2010324.1964963; fast approximation: Aubry, Paris, Hasinoff,"
    " Kautz, Durand 2014, ACM Transactions on Graphics 33(5):167,"
    " https://doi.org/10.1145/2629645"
)
INTENSITY_WEIGHTS = (20.0 / 61.0, 40.0 / 61.0, 1.0 / 61.0)
"""The authors' intensity ``(20 R + 40 G + B) / 61``."""
KERNEL = (0.05, 0.25, 0.4, 0.25, 0.05)
"""Burt & Adelson 1983's 5-tap low-pass kernel (``a = 0.4``), the authors' choice."""
NOISE_LEVEL = 0.01
"""Below this difference in ln intensity details are not enhanced (the authors' value)."""
MAX_LOG_OUT = 6.0
"""Output log luminance cap (``e^6 ≈ 400`` times display white): a nearly flat image makes
the exponent ``c`` huge, where ``exp`` would overflow."""
MIN_RANGE = 1e-3
"""Smallest ``R_hi − R_lo`` the exponent divides by (flat images)."""


def pyramid_levels(shape: tuple[int, int]) -> int:
    """Levels of the pyramids of an ``(H, W)`` image: 1 plus the number of halvings
    (rounding up) of ``min(H, W)`` down to 1 (7 for 48 × 64)."""
    n, levels = min(shape), 1
    while n > 1:
        n, levels = (n + 1) // 2, levels + 1
    return levels


def _blur_weights(mask: np.ndarray) -> np.ndarray:
    """The kernel's zero-padded correlation of a 1-D ``mask`` (its normalisation)."""
    p = np.pad(mask.astype(np.float64), 2)
    return sum(w * p[k : k + mask.size] for k, w in enumerate(KERNEL))


def _blur(x: Array, stride: int = 1) -> Array:
    """The separable kernel over both axes of ``x``, zero outside it; ``stride`` 2 keeps
    every second output pixel from the first. Shifted slices rather than
    ``lax.conv_general_dilated``: batched through ``vmap`` of the operator's ``lax.cond``
    (clean and masked paths), the convolution mixed frames on XLA:CPU (an infinite pixel
    of one frame made another frame's output NaN)."""

    def axis(x: Array, ax: int) -> Array:
        n = x.shape[ax]
        pad = [(0, 0), (0, 0)]
        pad[ax] = (2, 2)
        p = jnp.pad(x, pad)
        m = -(-n // stride)
        taps = [
            jax.lax.slice_in_dim(p, k, k + stride * (m - 1) + 1, stride=stride, axis=ax)
            for k in range(5)
        ]
        return sum(w * t for w, t in zip(KERNEL, taps, strict=True))

    return axis(axis(x, 0), 1)


def downsample(x: Array) -> Array:
    """Blur (renormalised at the borders) and keep every second pixel from the first:
    ``(ceil(H / 2), ceil(W / 2))``."""
    h, w = x.shape
    z = np.outer(_blur_weights(np.ones(h))[::2], _blur_weights(np.ones(w))[::2])
    return _blur(x, stride=2) / jnp.asarray(z, x.dtype)


def upsample(x: Array, shape: tuple[int, int]) -> Array:
    """``x`` on the even pixels of a ``shape`` grid, blurred and renormalised by the blurred
    mask of those pixels."""
    h, w = shape
    mh, mw = np.zeros(h), np.zeros(w)
    mh[::2], mw[::2] = 1.0, 1.0
    z = np.outer(_blur_weights(mh), _blur_weights(mw))
    up = jnp.zeros(shape, x.dtype).at[::2, ::2].set(x)
    return _blur(up) / jnp.asarray(z, x.dtype)


def gaussian_pyramid(x: Array, levels: int) -> list[Array]:
    """``[x, down(x), down(down(x)), …]``, ``levels`` images."""
    out = [x]
    for _ in range(levels - 1):
        out.append(downsample(out[-1]))
    return out


def laplacian_pyramid(x: Array, levels: int) -> list[Array]:
    """Band-pass levels ``G_ℓ − up(G_ℓ₊₁)`` and the residual ``G_last`` last."""
    g = gaussian_pyramid(x, levels)
    return [g[k] - upsample(g[k + 1], g[k].shape) for k in range(levels - 1)] + [g[-1]]


def collapse(pyramid: list[Array]) -> Array:
    """The image whose Laplacian pyramid is ``pyramid``."""
    out = pyramid[-1]
    for band in reversed(pyramid[:-1]):
        out = band + upsample(out, band.shape)
    return out


def remap(I: Array, g: Array, sigma_r: Array, alpha: Array, beta: Array) -> Array:
    """The paper's point-wise remapping of ``I`` around ``g`` (module docstring, step 2)."""
    d = I - g
    a = jnp.abs(d)
    s = jnp.sign(d)
    x = a / sigma_r
    pos = x > 0
    power = jnp.where(pos, jnp.exp(alpha * jnp.log(jnp.where(pos, x, 1.0))), 0.0)
    t = jnp.clip((a - NOISE_LEVEL) / NOISE_LEVEL, 0.0, 1.0)
    tau = t * t * (t - 2.0) ** 2
    fd = jnp.where(alpha < 1.0, tau * power + (1.0 - tau) * x, power)
    detail = g + s * sigma_r * fd
    edge = g + s * (beta * (a - sigma_r) + sigma_r)
    return jnp.where(a > sigma_r, edge, detail)


def local_laplacian(
    I: Array, sigma_r: Array, alpha: Array, beta: Array, *, references: int
) -> Array:
    """The local Laplacian filter of ``I`` (``(H, W)``, ln intensity) by Aubry et al.
    2014's ``references`` levels (module docstring, step 3)."""
    levels = pyramid_levels(I.shape)
    G = gaussian_pyramid(I, levels)
    if levels == 1:
        return I
    lo, hi = jnp.min(I), jnp.max(I)
    span = hi - lo
    step = jnp.where(span > 0, span / (references - 1), 1.0)

    def body(acc: list[Array], k: Array) -> tuple[list[Array], None]:
        g = lo + k.astype(I.dtype) * step
        bands = laplacian_pyramid(remap(I, g, sigma_r, alpha, beta), levels)[:-1]
        # the hat of width one step around g: the two references around each G_ℓ(p)
        weights = [jnp.maximum(1.0 - jnp.abs(G[n] - g) / step, 0.0) for n in range(levels - 1)]
        return [a + w * b for a, w, b in zip(acc, weights, bands, strict=True)], None

    init = [jnp.zeros_like(G[n]) for n in range(levels - 1)]
    acc, _ = jax.lax.scan(jax.checkpoint(body), init, jnp.arange(references))
    return collapse(acc + [G[-1]])


@register("paris2011")
class Paris2011(AbstractOperator):
    """Paris, Hasinoff & Kautz 2011 local Laplacian tone mapping by Aubry et al. 2014's fast
    approximation (module docstring), with the authors' tone-mapping example's settings
    (``σ_r = ln 2.5``, ``α = 1``, ``β = 0``, contrast 100 : 1).

    Input: linear RGB, relative or absolute (the operator is scale invariant). Output:
    display-referred *linear* RGB: the 0.5th percentile of the filtered luminance at
    ``1 / contrast``, the 99.5th at 1, brighter pixels above 1 (clipped by the display).

    Attributes:
        sigma_r: the paper's ``σ_r``, threshold between detail and edges in natural-log
            intensity (``ln 2.5 ≈ 0.916``: differences within a factor 2.5 are detail).
        alpha: the paper's ``α``, detail exponent: ``< 1`` enhances detail, ``> 1``
            smooths it, 1 keeps it.
        beta: the paper's ``β``, slope of the edges (large differences): 0 compresses
            them to ``σ_r``, 1 keeps them.
        contrast: the display contrast the middle of the result is mapped to (the
            authors' ``DR_desired``, 100 : 1).
        clip_percent: percent of pixels at each end outside that range (the authors'
            ``prc_clip``, 0.5).
        references: Aubry et al. 2014's number of reference intensities (static).
        weights: the intensity's weights (the authors' ``(20, 40, 1) / 61``).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("alpha", "beta")

    sigma_r: Array = parameter(
        math.log(2.5),
        help="the paper's sigma_r: detail/edge threshold in natural-log intensity (ln 2.5)",
        unit="ln intensity",
        range="(0, inf)",
    )
    alpha: Array = parameter(
        1.0,
        help="the paper's alpha: detail exponent (< 1 enhances detail, > 1 smooths it)",
        range="(0, inf)",
    )
    beta: Array = parameter(
        0.0,
        help="the paper's beta: slope of edges beyond sigma_r (0 compresses them, 1 keeps)",
        range="[0, 1]",
    )
    contrast: Array = parameter(
        100.0,
        help="display contrast of the middle of the result (the authors' 100:1)",
        range="(1, inf)",
    )
    clip_percent: float = parameter(
        0.5,
        help="percent of pixels at each end outside the display contrast",
        unit="%",
        range="[0, 50)",
        static=True,
    )
    references: int = parameter(
        32,
        help="reference intensities of Aubry et al. 2014's approximation",
        range="[2, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field(INTENSITY_WEIGHTS)

    def __check_init__(self):
        super().__check_init__()
        if int(self.references) != self.references or self.references < 2:
            raise ValueError(f"references: expected an integer >= 2, got {self.references!r}")
        if not 0.0 <= self.clip_percent < 50.0:
            raise ValueError(
                f"clip_percent: expected a value in [0, 50), got {self.clip_percent!r}"
            )

    def halo(self, shape: tuple[int, ...]) -> tuple[float, float]:
        """The whole image (infinite): the pyramid's residual is the image's mean, and the
        references and percentiles are the whole image's."""
        del shape
        return (math.inf, math.inf)

    def _apply(self, p: Prepared) -> Array:
        dt = p.rgb.dtype
        Y = p.L if p.clean else filled_with_first_valid(p.L, p.valid())
        pos = Y > 0
        smallest = jnp.min(jnp.where(pos, Y, jnp.inf))
        smallest = jnp.where(jnp.isfinite(smallest), smallest, 1.0)
        I = jnp.log(jnp.where(pos, Y, smallest))
        R = local_laplacian(
            I,
            self.sigma_r.astype(dt),
            self.alpha.astype(dt),
            self.beta.astype(dt),
            references=int(self.references),
        )
        # percentiles of a positive shift of R (the selection reads positive values); the
        # shift cancels, so it carries no gradient
        shift = jax.lax.stop_gradient(1.0 - jnp.min(R))
        q = (float(self.clip_percent), 100.0 - float(self.clip_percent))
        lo, hi = percentile_by_selection(R + shift, jnp.asarray(q, dt), select=q) - shift
        c = jnp.log(self.contrast.astype(dt)) / jnp.maximum(hi - lo, MIN_RANGE)
        Ld = jnp.exp(jnp.minimum(c * (R - hi), MAX_LOG_OUT))
        ratio = jnp.maximum(quotient(p.rgb, jnp.where(pos, Y, 1.0)[..., None]), 0.0)
        return jnp.where(pos[..., None], ratio, 0.0) * Ld[..., None]


__all__ = [
    "Paris2011",
    "collapse",
    "gaussian_pyramid",
    "laplacian_pyramid",
    "local_laplacian",
    "pyramid_levels",
    "remap",
]

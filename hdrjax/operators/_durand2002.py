"""Durand & Dorsey 2002 bilateral-filter tone mapping, as ``pfstmo_durand02`` computes it.

Reference:
    Durand, Dorsey. "Fast bilateral filtering for the display of high-dynamic-range
    images." ACM Transactions on Graphics 21(3):257–266, 2002 (Proc. SIGGRAPH).
    https://doi.org/10.1145/566654.566574

Colour correction (pfstmo's default): Mantiuk, Mantiuk, Tomaszewska, Heidrich. "Color
correction for tone mapping." Computer Graphics Forum 28(2):193–202, 2009.
https://doi.org/10.1111/j.1467-8659.2009.01358.x

The steps, with ``I = ln L`` the natural log of the intensity
``L = (20 R + 40 G + B) / 61`` (the paper's; pixels with ``L ≤ 0`` take the smallest
positive ``L`` of the image, ``L_min``):

1. Base layer ``B = bilateral(I)`` by the paper's piecewise-linear scheme:
   ``n = ceil((I_max − I_min) / σ_r)`` segments, nodes ``i_j = I_min + j (I_max − I_min)
   / n``, ``j = 0 … n``; per node ``G_j = exp(−(I − i_j)² / σ_r²)``,
   ``J_j = i_j + f ⊗ (G_j (I − i_j)) / f ⊗ G_j`` with the spatial Gaussian ``f``; each
   pixel's ``B`` interpolates linearly between the ``J_j`` of the two nodes around its
   ``I``. The range kernel is pfstmo's ``exp(−d²/σ_r²)`` (standard deviation
   ``σ_r / √2``).
2. Detail ``D = I − B``; base contrast compressed by ``c = base_contrast / (ln L_high −
   ln L_low)`` and shifted so that ``L_high`` maps to 1 (as pfstmo 2.2.0 does):
   ``ln L_d = c (B − ln L_high) + D``, with pfstmo's robust range, the 1st and 99.5th
   percentiles (``base_contrast`` in natural-log units: the default 5 is a contrast of
   ``e⁵ ≈ 148 : 1``).
3. Colour: ``C_d = max(C / L, 0)^s L_d`` with ``s = (1 + k₁) c^k₂ / (1 + k₁ c^k₂)``,
   ``k₁ = 1.48``, ``k₂ = 0.82`` (Mantiuk et al. 2009), or ``s = 1`` (the paper's colour
   ratios: pfstmo's ``--original``).

Deviations from ``pfstmo_durand02`` (pfstools 2.2.0), each argued:

- Spatial kernel: pfstmo blurs by a circular FFT whose frequency-domain Gaussian uses the
  image *width* on both axes, so its kernel has the standard deviation ``σ_s / π`` pixels
  across and ``σ_s H / (π W)`` down, and wraps around the image edges. Here ``f`` is an
  isotropic Gaussian of standard deviation ``σ_s / π`` pixels (pfstmo's horizontal one, the
  paper's isotropic kernel), truncated at 3 standard deviations and zero-padded at the
  image edges (a normalised convolution: the ratio ``f ⊗ (G I) / f ⊗ G`` sees only image
  pixels). So the result depends only on pixels within :meth:`Durand2002.halo`, and tiles
  give the whole image's result.
- Nodes: pfstmo stops at ``i_{n−1}`` and gives the top segment ``J_{n−1}`` unblended; here
  node ``i_n = I_max`` is included (the paper's scheme).
- Base range: pfstmo takes the 1st and 99.5th percentiles of the *base layer*; here
  those of the intensity itself (``L_low``, ``L_high``, from the mergeable statistics),
  so that tiles, chunks and frames merge to the whole image's value with no second pass
  through the filter (the base's percentiles lie inside the intensity's by about the
  detail's amplitude, which changes ``c`` by a few per cent).
- Colour ratios of negative channels: pfstmo raises ``C / L`` to ``s`` as it is, so a
  channel that is zero in the file (slightly negative after pfstools' XYZ round trip)
  comes out NaN (the whole pixel); here negative ratios are 0.
- ``L_max``, ``L_min`` and the percentiles come from the fixed-grid statistics (exact
  extrema; percentiles within a factor ``1 + 2^-10``), not from a sort.

Tiles and memory: the nodes and the base range are the whole image's (merged statistics,
:meth:`Durand2002.bind`), and each node's blur reads ``3 σ_s / π`` pixels around a pixel,
so :func:`hdrjax.tile.apply` gives the whole image's result to float rounding. The nodes
are visited one at a time (a ``lax.scan`` carrying one image-sized sum), so a window needs
a few image-sized buffers whatever the number of nodes; reverse-mode gradients keep that
carry per node (``max_segments + 1`` of them), which limits ``jax.grad`` to small images.

Speed: each node's blur is two passes of shifted-slice sums, along rows and then along the
columns of 64-pixel strips (:data:`STRIP`), whose window of rows stays in the first-level
cache (2.5× less CPU time for the whole operator than banded block products on one
core at 2048 × 1024). A node that weighs no pixel is skipped by ``lax.cond``; under ``vmap`` that
branch becomes a select and every frame would pay for all ``max_segments + 1`` nodes
(60× a frame's time at 512 × 256), so batches map frame by frame
(:attr:`~hdrjax.operators.AbstractOperator.frames_in_sequence`).
"""

import math
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._fusion import written_out
from .._scale import quotient
from .._stats import Statistics
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
    "Durand, Dorsey 2002, Fast bilateral filtering for the display of high-dynamic-range"
    " images, ACM Transactions on Graphics 21(3):257-266, https://doi.org/10.1145/566654.566574"
)
INTENSITY_WEIGHTS = (20.0 / 61.0, 40.0 / 61.0, 1.0 / 61.0)
"""The paper's intensity ``(20 R + 40 G + B) / 61``."""
LOW, HIGH = 0.01, 0.995
"""The quantiles pfstmo takes as the base layer's range (``L_low``, ``L_high``)."""
K1, K2 = 1.48, 0.82
"""Mantiuk et al. 2009's saturation fit ``s = (1 + k₁) c^k₂ / (1 + k₁ c^k₂)``."""
TRUNCATE = 3.0
"""The spatial Gaussian is cut at this many standard deviations (its halo)."""
MAX_LOG_OUT = 50.0
"""Output log intensities are capped here (``e^50``, display white many times over): only a
nearly flat base range (a huge compression factor ``c``) reaches it, where ``exp`` would
otherwise overflow."""
MIN_RANGE = 1e-3
"""Smallest ``ln L_high − ln L_low`` the compression factor divides by (flat images)."""


def spatial_sigma(sigma_s: float) -> float:
    """Standard deviation in pixels of the spatial Gaussian for pfstmo's ``--sigma-s``:
    ``σ_s / π`` (pfstmo's frequency-domain kernel ``exp(−2 σ_s² k² / W²)`` at frequency
    ``k / W``)."""
    return sigma_s / math.pi


def spatial_radius(sigma_s: float) -> int:
    """Half-width in pixels of the truncated spatial Gaussian (:data:`TRUNCATE` standard
    deviations): 39 for the default ``σ_s = 40``."""
    return max(1, math.ceil(TRUNCATE * spatial_sigma(sigma_s)))


STRIP = 64
"""Width in pixels of the column strips the vertical pass runs along: a strip's rows of the
kernel's window (79 × 256 bytes for the default ``σ_s``) stay in the core's first-level
cache, where whole image rows (79 rows of 8 KiB at 2048 wide) overflow the second level
and made the vertical pass 8× slower than the horizontal one."""


def _taps(sigma_s: float, size: int) -> np.ndarray:
    """The normalised kernel's taps ``k_0 … k_r`` (centre first; it is symmetric) for an
    axis of ``size`` pixels: those that reach past ``size − 1`` pixels are dropped, as they
    only ever weigh the zeros around the image (the same sums, with no term of ``0 · x``:
    an 8 × 8 image needs 15 taps a pass, not 79)."""
    r = spatial_radius(sigma_s)
    x = np.arange(r + 1, dtype=np.float64)
    k = np.exp(-0.5 * (x / spatial_sigma(sigma_s)) ** 2)
    return (k / (k[0] + 2.0 * np.sum(k[1:])))[: max(1, min(r, size - 1) + 1)]


def _strip(width: int) -> int:
    """Width of the vertical pass's column strips for an image ``width`` pixels wide:
    :data:`STRIP`, or the whole width when it is narrower (no columns of zeros)."""
    return min(STRIP, max(1, width))


def _fir(p: Array, taps: np.ndarray, axis: int) -> Array:
    """The symmetric kernel ``taps`` along ``axis`` over the positions where its whole window
    lies in ``p`` (``2r`` fewer), as one fused sum of shifted slices."""
    r = len(taps) - 1
    n = p.shape[axis] - 2 * r

    def at(a: int) -> Array:
        return jax.lax.slice_in_dim(p, a, a + n, axis=axis)

    out = float(taps[0]) * at(r)
    for d in range(1, r + 1):
        out = out + float(taps[d]) * (at(r - d) + at(r + d))
    return out


def _to_strips(x: Array, strip: int) -> Array:
    """``(..., H, W)`` with ``W`` a multiple of ``strip`` → ``(..., W / strip, H, strip)``."""
    *lead, h, w = x.shape
    x = x.reshape(*lead, h, w // strip, strip)
    return jnp.moveaxis(x, -2, -3)


def _from_strips(x: Array) -> Array:
    """The inverse of :func:`_to_strips`."""
    *lead, s, h, strip = x.shape
    return jnp.moveaxis(x, -3, -2).reshape(*lead, h, s * strip)


def _separable(x: Array, taps: tuple[np.ndarray, np.ndarray], strip: int, when: Array) -> Array:
    """The kernel over both image axes of ``x`` (``(..., H + 2 r_v, W' + 2 r_h)``, padded
    with zeros by :func:`_padding`, ``W'`` a multiple of ``strip``; ``taps``: the vertical
    and the horizontal pass's), returned as strips (``(..., W' / strip, H, strip)``): the
    horizontal pass along rows, then the vertical pass along the strips' columns, where
    ``when`` (zeros otherwise). The strips are written out before the vertical pass
    (:func:`~hdrjax._fusion.written_out`): fused into it, their transpose costs a cache miss
    per tap, as slow as whole rows."""
    vertical, horizontal = taps
    rows = _to_strips(_fir(x, horizontal, -1), strip)
    r = len(vertical) - 1
    shape = (*rows.shape[:-2], rows.shape[-2] - 2 * r, rows.shape[-1])
    return written_out(
        when, lambda s: _fir(s, vertical, -2), lambda s: jnp.zeros(shape, s.dtype), rows
    )


def _kernel(sigma_s: float, shape: tuple[int, int]) -> tuple[tuple[np.ndarray, np.ndarray], int]:
    """The vertical and horizontal taps and the strip width for an ``(H, W)`` image."""
    h, w = shape
    return (_taps(sigma_s, h), _taps(sigma_s, w)), _strip(w)


def _padding(
    shape: tuple[int, int], taps: tuple[np.ndarray, np.ndarray], strip: int
) -> tuple[tuple[int, int], tuple[int, int]]:
    """The zero padding of an ``(H, W)`` image for :func:`_separable`."""
    h, w = shape
    rv, rh = len(taps[0]) - 1, len(taps[1]) - 1
    return (rv, rv), (rh, rh + -(-w // strip) * strip - w)


def gaussian_blur(x: Array, sigma_s: float, when: Array | None = None) -> Array:
    """``f ⊗ x`` over the last two axes: the truncated isotropic Gaussian of standard
    deviation ``σ_s / π`` pixels, zero outside the image (a normalised convolution's
    numerator or denominator). ``when``: a traced boolean, zeros where false; traced code
    should pass one (``None`` is a constant true, with which XLA may fuse the column
    strips' transpose into the vertical pass, the slow layout of
    :func:`~hdrjax._fusion.written_out`)."""
    h, w = x.shape[-2:]
    taps, strip = _kernel(sigma_s, (h, w))
    pad = [(0, 0)] * (x.ndim - 2) + list(_padding((h, w), taps, strip))
    on = jnp.asarray(True) if when is None else when
    out = _separable(jnp.pad(x, pad), taps, strip, on)
    return _from_strips(out)[..., :w]


def bilateral_base(
    I: Array,
    valid: Array,
    lo: Array,
    hi: Array,
    sigma_r: Array,
    *,
    sigma_s: float,
    max_segments: int,
) -> Array:
    """The base layer ``B`` of ``I`` (natural log intensity, ``(H, W)``) by the paper's
    piecewise-linear bilateral filter (module docstring, step 1) with nodes from ``lo`` to
    ``hi`` (the whole image's ``ln L_min`` and ``ln L_max``, so that tiles share them).

    Pixels where ``valid`` is False take no part (they are absent, not dark). At most
    ``max_segments`` segments (a static bound for ``jit``): a wider range gets wider
    segments. The nodes are visited by a ``lax.scan``; those beyond ``n`` or next to no
    pixel's ``I`` are skipped."""
    span = jnp.maximum(hi - lo, 0.0)
    n = jnp.clip(jnp.ceil(span / sigma_r), 1, max_segments)
    step = jnp.where(span > 0, span / n, 1.0)
    t = jnp.clip((I - lo) / step, 0.0, n)
    taps, strip = _kernel(sigma_s, I.shape)
    (top, bottom), (left, right) = _padding(I.shape, taps, strip)
    w = I.shape[1]
    # the kernel's inputs padded with absent pixels; the blend's in the blur's strips
    I_pad = jnp.pad(I, ((top, bottom), (left, right)))
    v_pad = jnp.pad(valid.astype(I.dtype), ((top, bottom), (left, right)))
    t_s = _to_strips(jnp.pad(t, ((0, 0), (0, right - left))), strip)
    seg = jnp.clip(jnp.floor(t_s), 0, n - 1)
    frac = t_s - seg

    def node(acc: Array, j: Array, u: Array) -> Array:
        i_j = lo + j * step
        d = I_pad - i_j
        G = jnp.exp(-((d / sigma_r) ** 2)) * v_pad
        KH = _separable(jnp.stack([G, G * d]), taps, strip, u)
        K = KH[0]
        ok = K > jnp.finfo(I.dtype).tiny
        J = i_j + jnp.where(ok, quotient(KH[1], jnp.where(ok, K, 1.0)), 0.0)
        wj = jnp.where(seg == j, 1.0 - frac, 0.0) + jnp.where(seg == j - 1, frac, 0.0)
        return acc + wj * J

    def body(acc: Array, j: Array) -> tuple[Array, None]:
        jf = j.astype(I.dtype)
        # a node that weighs no pixel of this image (or window) adds nothing: skipped
        u = (jf <= n) & jnp.any(jnp.abs(t - jf) < 1.0)
        return jax.lax.cond(u, jax.checkpoint(node), lambda a, *_: a, acc, jf, u), None

    acc, _ = jax.lax.scan(body, jnp.zeros_like(t_s), jnp.arange(max_segments + 1))
    return _from_strips(acc)[:, :w]


def saturation_of(c: Array) -> Array:
    """Mantiuk et al. 2009's colour saturation for a contrast compression factor ``c``."""
    ck = c**K2
    return (1.0 + K1) * ck / (1.0 + K1 * ck)


@register("durand2002")
class Durand2002(AbstractOperator):
    """Durand & Dorsey 2002 fast bilateral filtering (module docstring), ``pfstmo_durand02``'s
    defaults and colour correction.

    Input: linear RGB, relative or absolute (the operator is scale invariant). Output:
    display-referred *linear* RGB (pfstmo tags its output ``LUMINANCE=RELATIVE``: it needs
    gamma correction): the base layer from ``e^−base_contrast`` (at ``L_low``) to 1 (at
    ``L_high``), times the detail, so highlights' detail exceeds 1 (clipped by the
    display).

    Attributes:
        sigma_s: pfstmo's ``--sigma-s`` (40): the spatial Gaussian's standard deviation is
            ``sigma_s / π`` pixels (12.7 px for 40), truncated at 3 of them.
        sigma_r: pfstmo's ``--sigma-r`` (0.4): range kernel ``exp(−(ΔI)² / σ_r²)`` in
            natural-log intensity, also the segment width.
        base_contrast: pfstmo's ``--base-contrast`` (5): the base layer's output range
            ``ln L_low … ln L_high`` spans this many natural-log units.
        saturation: exponent ``s`` of the colour ratios; ``None`` → Mantiuk et al. 2009
            from the compression factor (pfstmo's default), 1 → pfstmo's ``--original``.
        L_min, L_max: smallest positive and largest intensity (the node range);
            ``None`` → measured.
        L_low, L_high: 1st and 99.5th percentiles of the intensity (the base range);
            ``None`` → measured.
        max_segments: most segments of the piecewise-linear filter (a static bound).
        weights: the intensity's weights (the paper's ``(20, 40, 1) / 61``).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    frames_in_sequence: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("base_contrast",)

    sigma_s: float = parameter(
        40.0,
        help="pfstmo's --sigma-s: spatial Gaussian of standard deviation sigma_s/pi pixels",
        unit="pi pixels",
        range="(0, inf)",
        static=True,
    )
    sigma_r: Array = parameter(
        0.4,
        help="pfstmo's --sigma-r: range kernel exp(-dI^2/sigma_r^2), natural-log intensity",
        unit="ln intensity",
        range="(0, inf)",
    )
    base_contrast: Array = parameter(
        5.0,
        help="pfstmo's --base-contrast: the base layer's output range (ln units; 5 is e^5:1)",
        unit="ln intensity",
        range="(0, inf)",
    )
    saturation: Array | None = estimated(
        "colour ratio exponent s; None: Mantiuk et al. 2009 from the compression factor"
        " (1: pfstmo's --original)",
        pooling="mean",
        range="[0, inf)",
    )
    L_min: Array | None = estimated(
        "smallest positive intensity (lowest node; darker pixels take it); None: measured",
        pooling="min",
        unit="image units",
    )
    L_max: Array | None = estimated(
        "largest intensity (highest node); None: measured", pooling="max", unit="image units"
    )
    L_low: Array | None = estimated(
        "1st percentile of the intensity (maps to e^-base_contrast); None: measured",
        pooling="log_mean",
        unit="image units",
    )
    L_high: Array | None = estimated(
        "99.5th percentile of the intensity (maps to 1); None: measured",
        pooling="log_mean",
        unit="image units",
    )
    max_segments: int = parameter(
        512,
        help="most segments of the piecewise-linear bilateral filter (wider ranges get"
        " wider segments)",
        range="[1, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field(INTENSITY_WEIGHTS)

    def __check_init__(self):
        if not self.sigma_s > 0:
            raise ValueError(f"sigma_s: expected a value in (0, inf), got {self.sigma_s!r}")
        if int(self.max_segments) != self.max_segments or self.max_segments < 1:
            raise ValueError(f"max_segments: expected an integer >= 1, got {self.max_segments!r}")

    def halo(self, shape: tuple[int, ...]) -> tuple[int, int]:
        """The spatial kernel's radius, ``ceil(3 σ_s / π)`` (39 pixels for ``σ_s = 40``);
        at most half the image per axis, where every window is the whole image anyway."""
        r = spatial_radius(self.sigma_s)
        return min(r, -(-int(shape[0]) // 2)), min(r, -(-int(shape[1]) // 2))

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings() if self.unset() else None

    def bind(self, stats: Statistics | None) -> "Durand2002":
        if not self.unset():
            return self
        values = {}
        if any(getattr(self, n) is None for n in ("L_min", "L_max", "L_low", "L_high")):
            raw = checked_statistics(self, stats)
            st = raw.luminance_stats()
            lmin = st.min_positive
            # pfstmo's ranks run over every pixel, those with L ≤ 0 at L_min; the
            # histogram holds the positive ones, above those
            n_fin = raw.n_finite.astype(lmin.dtype)
            n_dark = n_fin - raw.n_positive.astype(lmin.dtype)
            rank = jnp.array([LOW, HIGH], lmin.dtype) * n_fin - n_dark
            frac = jnp.clip(rank / jnp.maximum(raw.n_positive, 1).astype(lmin.dtype), 0.0, 1.0)
            q, _ = raw.quantile(jax.lax.stop_gradient(frac))
            q = jnp.where(jnp.isnan(q) | (rank < 0), lmin, q)
            measured = dict(
                L_min=lmin,
                L_max=jnp.maximum(st.max, lmin),
                L_low=jnp.maximum(q[0], lmin),
                L_high=jnp.maximum(q[1], lmin),
            )
            values = {k: v for k, v in measured.items() if getattr(self, k) is None}
        op = fill(self, **values) if values else self
        if op.saturation is None:
            op = fill(op, saturation=saturation_of(op.compression()))
        return op

    def compression(self) -> Array:
        """The base layer's compression factor ``c = base_contrast / (ln L_high −
        ln L_low)`` (parameters set)."""
        assert self.L_low is not None and self.L_high is not None
        span = jnp.log(self.L_high) - jnp.log(self.L_low)
        return self.base_contrast / jnp.maximum(span, MIN_RANGE)

    def _apply(self, p: Prepared) -> Array:
        assert self.L_min is not None and self.L_max is not None
        assert self.L_high is not None and self.saturation is not None
        dt = p.rgb.dtype
        L_min = self.L_min.astype(dt)
        L = jnp.maximum(p.L, L_min)
        I = jnp.log(L)
        lo, hi = jnp.log(L_min), jnp.log(jnp.maximum(self.L_max.astype(dt), L_min))
        B = bilateral_base(
            I,
            p.valid(),
            lo,
            hi,
            self.sigma_r.astype(dt),
            sigma_s=self.sigma_s,
            max_segments=self.max_segments,
        )
        c = self.compression().astype(dt)
        log_out = c * (B - jnp.log(self.L_high.astype(dt))) + (I - B)
        Ld = jnp.exp(jnp.minimum(log_out, MAX_LOG_OUT))
        ratio = jnp.maximum(quotient(p.rgb, L[..., None]), 0.0)
        s = self.saturation.astype(dt)
        pos = ratio > 0
        colour = jnp.where(pos, jnp.exp(s * jnp.log(jnp.where(pos, ratio, 1.0))), 0.0)
        return colour * Ld[..., None]


__all__ = ["Durand2002", "bilateral_base", "gaussian_blur", "saturation_of", "spatial_radius"]

"""Chiu et al. 1993 spatially nonuniform scaling, with HDR Toolbox's clamping, smoothing and
glare.

Reference:
    K. Chiu, M. Herf, P. Shirley, S. Swamy, C. Wang, K. Zimmerman. "Spatially nonuniform
    scaling functions for high contrast images." Proceedings of Graphics Interface '93,
    245–253. (No DOI.)

The steps, with ``L`` the luminance (Rec. 709 weights), any units (the operator is scale
invariant):

1. Scaling function ``s = 1 / (k · L_b)``, ``L_b`` the luminance blurred by a Gaussian of
   standard deviation ``σ`` pixels (the paper's low-pass image; ``s`` is 0 where
   ``L_b = 0``).
2. Clamping (the paper's remedy for the halos around bright regions): ``s ← min(s, 1/L)``
   (no pixel brighter than ``L s = 1``; 0 where ``L = 0``), then ``n`` passes of the 3 × 3
   low-pass filter ``[[0.080, 0.113, 0.080], [0.113, 0.227, 0.113], [0.080, 0.113,
   0.080]]`` with the image's edge pixels replicated. Its taps sum to 0.999, so the passes
   also darken by ``0.999ⁿ`` (0.61 for 500 passes), as in HDR Toolbox.
3. ``L_s = L s``, then glare (the paper's simulation of veiling glare around light
   sources): ``L_d = g L_s + K ⊗ L_s`` with the radial kernel
   ``K(r) ∝ |r − 1|^p`` on the unit disc sampled at ``w + 1`` pixels per radius
   (``w = round(size / 2)``), 0 at its centre and outside the disc, normalised to sum 1,
   the image's edge pixels replicated. The kernel, centre included, sums to ``1 + g``
   (1.8 for the default ``g = 0.8``): HDR Toolbox normalises the ring to 1 and then sets
   the centre to ``g``; kept for parity.
4. Colour kept: ``C_out = C L_d / L`` (0 where ``L = 0``).

Defaults are HDR Toolbox's ``ChiuTMO`` (the reference peer): ``k = 8``,
``σ = round(16 max(H, W) / 1024) + 1`` pixels (the blur is MATLAB's ``fspecial('gaussian',
w, σ)`` with ``w`` the odd number at or above ``round(5 σ)``, edges replicated), ``n = 500``
passes, glare ``g = 0.8``, ``p = 8``, ``size = 121``.

Implementation: the ``n`` passes of a symmetric 3 × 3 filter with replicated edges are one
product in the type-II discrete cosine transform domain (replication by one pixel is the
half-sample symmetric extension that the DCT-II diagonalises): ``s ← DCT⁻¹(DCT(s) Ĥⁿ)``,
``Ĥ(u, v) = 0.227 + 0.226 (cos u + cos v) + 0.32 cos u cos v``, the same values as the
passes to float rounding at any ``n``. Glare is an FFT convolution of the edge-padded image.
Both transforms round relative to the image's largest values: in float32 a dim pixel's
output differs from float64 by up to about 5e-4 of itself (measured on a 512 × 1024 sunset,
1.3e-4 after sRGB encoding).
Pixels whose input is NaN or ±Inf take no part in the blur (a normalised convolution) and
have ``s = 0`` in the passes and ``L_s = 0`` in the glare.

Tiles: with ``sigma`` given, a pixel reads the pixels within the blur's radius plus ``n``
(the passes) plus ``w`` (the glare): :meth:`Chiu1993.halo`, 643 pixels for ``σ = 33``
(HDR Toolbox's value for 2048 columns); the edge replication happens at the true image
edges in every window, so :func:`hdrjax.tile.apply` gives the whole image's result to
float rounding. With ``sigma=None`` the blur depends on the image's size, which a window
does not know: the halo is then the whole image.
"""

import math
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.fft import dctn, idctn
from jaxtyping import Array

from .._scale import inverse_pow2, quotient, saturate_finite
from ._ashikhmin2002 import gaussian_taps, masked_blurs
from ._base import AbstractOperator, Prepared, parameter, register, weights_field

REFERENCE = (
    "Chiu, Herf, Shirley, Swamy, Wang, Zimmerman 1993, Spatially nonuniform scaling functions"
    " for high contrast images, Proceedings of Graphics Interface '93, 245-253"
)
SMOOTHING = (0.227, 0.113, 0.080)
"""The 3 × 3 low-pass filter's centre, edge and corner taps (HDR Toolbox's ``ChiuTMO``)."""


def default_sigma(shape: tuple[int, ...]) -> float:
    """HDR Toolbox's blur for an image of ``shape`` (``(H, W, ...)``):
    ``round(16 max(H, W) / 1024) + 1`` pixels."""
    return float(math.floor(16 * max(int(shape[0]), int(shape[1])) / 1024 + 0.5) + 1)


def glare_radius(size: int) -> int:
    """``w = round(size / 2)``: the glare kernel's radius in pixels (61 for 121)."""
    return int(math.floor(size / 2 + 0.5))


def smooth(s: Array, passes: int) -> Array:
    """``passes`` applications of the 3 × 3 filter :data:`SMOOTHING` to ``s`` (``(H, W)``),
    edge pixels replicated, as one DCT-II product (module docstring)."""
    h0, h1, h2 = SMOOTHING
    H, W = s.shape
    cu = jnp.cos(jnp.pi * jnp.arange(H, dtype=s.dtype) / H)[:, None]
    cv = jnp.cos(jnp.pi * jnp.arange(W, dtype=s.dtype) / W)[None, :]
    gain = (h0 + 2.0 * h1 * (cu + cv) + 4.0 * h2 * cu * cv) ** passes
    return idctn(dctn(s, type=2, norm="ortho") * gain, type=2, norm="ortho")


def glare_kernel(glare: Array, power: Array, size: int) -> Array:
    """The glare kernel (module docstring, step 3), ``(2w + 1, 2w + 1)``, its ring summing
    to 1 and its centre ``glare``."""
    w = glare_radius(size)
    x = np.arange(-w, w + 1) / w
    r = np.hypot(x[:, None], x[None, :])
    d = jnp.asarray(np.abs(r - 1.0), power.dtype)
    inside = jnp.asarray((r <= 1.0) & (r > 0.0))
    pos = inside & (d > 0)
    ring = jnp.where(pos, jnp.exp(power * jnp.log(jnp.where(pos, d, 1.0))), 0.0)
    ring = ring / jnp.sum(ring)
    return ring.at[w, w].set(glare)


def glare_filter(x: Array, kernel: Array) -> Array:
    """``kernel ⊗ x`` (``(H, W)``, odd square kernel), the image's edge pixels replicated,
    by FFT."""
    w = kernel.shape[0] // 2
    H, W = x.shape
    p = jnp.pad(x, w, mode="edge")
    shape = p.shape
    kp = jnp.zeros(shape, x.dtype).at[: 2 * w + 1, : 2 * w + 1].set(kernel.astype(x.dtype))
    kp = jnp.roll(kp, (-w, -w), axis=(0, 1))  # centre at the origin
    out = jnp.fft.irfft2(jnp.fft.rfft2(p) * jnp.fft.rfft2(kp), s=shape)
    return out[w : w + H, w : w + W]


def _reciprocal(x: Array) -> Array:
    """``1 / x`` where it is finite and ``x > 0``, else 0 (HDR Toolbox's
    ``RemoveSpecials(1 ./ x)``)."""
    ok = x * jnp.finfo(x.dtype).max > 1.0
    return jnp.where(ok, quotient(jnp.ones_like(x), jnp.where(ok, x, 1.0)), 0.0)


@jax.custom_vjp
def _bounded_cotangent(x: Array) -> Array:
    """``x``, with its cotangent saturated at ``±finfo.max / 16`` (NaN: 0) in the backward
    pass (so that the sums of a few such cotangents stay finite).

    The derivatives of ``s = 1 / (k L_b)`` and ``L s`` multiply reciprocals of the dimmest
    blurred luminances (``1 / L_b²``), which leave the float range for images spanning
    more than about ``10³⁸`` although the value and most of the gradient are finite; a
    saturated cotangent keeps ``jax.grad`` finite there (such gradients are bounds, not
    values)."""
    return x


def _bounded_fwd(x):
    return x, None


def _bounded_bwd(_, ct):
    top = jnp.finfo(ct.dtype).max / 16
    return (jnp.where(jnp.isnan(ct), 0.0, jnp.clip(ct, -top, top)),)


_bounded_cotangent.defvjp(_bounded_fwd, _bounded_bwd)


def _at_unit_scale(f, x: Array) -> Array:
    """``f(x)`` for a linear ``f``, evaluated on ``x`` scaled by a power of two to a maximum
    near 1 (no sum inside ``f`` overflows), the result saturated at the float maximum."""
    c = inverse_pow2(jnp.max(jnp.abs(x)))
    y = f(x * c)
    top = jnp.finfo(x.dtype).max
    return jnp.where(jnp.abs(y) >= top * c, jnp.sign(y) * top, y / c)


@register("chiu1993")
class Chiu1993(AbstractOperator):
    """Chiu et al. 1993 spatially nonuniform scaling (module docstring) with HDR Toolbox's
    defaults (``ChiuTMO``).

    Input: linear RGB, relative or absolute (scale invariant). Output: display-referred
    linear RGB; a uniform region maps to about ``0.999ⁿ (1 + g) / k`` (0.14 with the
    defaults), bright details above 1 (clipped by the display).

    Attributes:
        k: the scaling function's divisor, ``s = 1 / (k L_b)`` (8).
        sigma: the blur's standard deviation in pixels; ``None`` → HDR Toolbox's
            ``round(16 max(H, W) / 1024) + 1`` from the image's size.
        passes: passes of the 3 × 3 smoothing after the clamping (500); 0 skips both.
        glare: the glare kernel's centre ``g`` (0.8); ``≤ 0`` skips the glare.
        glare_power: the exponent ``p`` of the glare kernel ``|r − 1|^p`` (8).
        glare_size: the glare kernel's width in pixels, ``2 round(size / 2) + 1`` (121).
        weights: the luminance weights (Rec. 709).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("k",)
    forward_mode: ClassVar[bool] = False  # _bounded_cotangent is a custom VJP

    k: Array = parameter(
        8.0, help="divisor of the scaling function s = 1 / (k L_blur)", range="(0, inf)"
    )
    sigma: float | None = parameter(
        None,
        help="blur standard deviation in pixels; None: round(16 max(H, W) / 1024) + 1",
        unit="pixels",
        range="(0, inf)",
        static=True,
    )
    passes: int = parameter(
        500,
        help="passes of the 3x3 smoothing after clamping s to 1/L (0: neither)",
        range="[0, inf)",
        static=True,
    )
    glare: Array = parameter(
        0.8, help="glare kernel's centre weight (<= 0: no glare)", range="[0, 1]"
    )
    glare_power: Array = parameter(
        8.0, help="exponent p of the glare kernel |r - 1|^p", range="(0, inf)"
    )
    glare_size: int = parameter(
        121,
        help="glare kernel width in pixels (2 round(size / 2) + 1)",
        range="[2, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        if self.sigma is not None and not self.sigma > 0:
            raise ValueError(f"sigma: expected None or a value in (0, inf), got {self.sigma!r}")
        if int(self.passes) != self.passes or self.passes < 0:
            raise ValueError(f"passes: expected an integer >= 0, got {self.passes!r}")
        if int(self.glare_size) != self.glare_size or self.glare_size < 2:
            raise ValueError(f"glare_size: expected an integer >= 2, got {self.glare_size!r}")

    def halo(self, shape: tuple[int, ...]) -> tuple[int, int]:
        """The blur's radius plus the passes plus the glare's radius (643 pixels for
        ``σ = 33``), at most half the image per axis (where every window is the whole
        image); half the image with ``sigma=None`` (module docstring)."""
        half = -(-int(shape[0]) // 2), -(-int(shape[1]) // 2)
        if self.sigma is None:
            return half
        r = len(gaussian_taps(5.0 * self.sigma)) // 2 + self.passes + glare_radius(self.glare_size)
        return min(r, half[0]), min(r, half[1])

    def _apply(self, p: Prepared) -> Array:
        dt = p.rgb.dtype
        sigma = default_sigma(p.L.shape[-2:]) if self.sigma is None else self.sigma
        L = _bounded_cotangent(jnp.maximum(p.L, 0.0))
        # a power of two that brings the maximum near 1 (exact): the blur's sums and the
        # reciprocals below stay in range
        c = inverse_pow2(jnp.max(L))
        L_c = L * c
        b = _bounded_cotangent  # on every path through a reciprocal (its docstring)
        mask = None if p.clean else p.valid()
        L_b = masked_blurs(b(L_c), mask, (5.0 * sigma,))[0]
        s = b(_reciprocal(b(self.k.astype(dt) * L_b)))
        if self.passes > 0:
            s = jnp.minimum(s, b(_reciprocal(b(L_c))))
            s = b(_at_unit_scale(lambda v: smooth(v, self.passes), s))
        Ls = b(b(L_c) * s)
        g = self.glare.astype(dt)
        kernel = glare_kernel(g, self.glare_power.astype(dt), self.glare_size)
        Ld = b(jnp.where(g > 0, _at_unit_scale(lambda v: glare_filter(v, kernel), Ls), Ls))
        ok = L_c > 0
        den = b(jnp.where(ok, L_c, 1.0))[..., None]
        ratio = b(jnp.where(ok[..., None], quotient(b(p.rgb * c), den), 0.0))
        return saturate_finite(ratio * Ld[..., None], p.rgb)


__all__ = ["Chiu1993", "default_sigma", "glare_kernel", "smooth"]

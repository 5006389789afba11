"""Night blue shift of Jensen, Durand, Stark, Premoze, Dorsey & Shirley (2001).

Reference: H. W. Jensen, F. Durand, M. M. Stark, S. Premože, J. Dorsey, P. Shirley,
"A Physically-Based Night Sky Model", SIGGRAPH 2001, pp. 399–408,
doi:10.1145/383259.383306; transcribed from brainwagon/knight ``src/tonemap.c``.

Per pixel, with ``Y`` the luminance and ``V`` the scotopic luminance (cd/m²):

- ``s = 3x² - 2x³`` with ``x = clamp((log10 Y + 2)/2.6, 0, 1)`` (0: rods only at or below
  0.01 cd/m²; 1: cones only at or above 10^0.6 = 3.98 cd/m²);
- chromaticity ``x' = (1-s)·0.25 + s·x``, ``y' = (1-s)·0.25 + s·y`` (the blue-shift white
  is (0.25, 0.25));
- luminance ``Y' = 0.4468 (1-s) V + s Y``;
- XYZ rebuilt from ``(x', y', Y')`` and converted back to the image's RGB.
"""

import functools
from collections.abc import Sequence

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._photometry import (
    check_rgb,
    chroma_key,
    headroom,
    largest_component_reciprocal,
    log10_floor,
    restore,
    rgb_to_xyz,
    sanitize,
    scotopic_unscaled,
    xyz_to_rgb,
)
from .._scale import at_scale

BLUE_WHITE = (0.25, 0.25)
"""Chromaticity (x, y) towards which night vision shifts (Jensen et al. 2001)."""
ROD_SCALE = 0.4468
"""Scotopic-to-photopic luminance factor of the rod signal (Jensen et al. 2001)."""
LOG_LOW, LOG_HIGH = -2.0, 0.6
"""log10 luminance limits of the smoothstep (0.01 and 3.98 cd/m²)."""


def blue_shift_weight(Y: Float[ArrayLike, "*shape"]) -> Float[Array, "*shape"]:
    """Jensen et al.'s photopic share ``s``: smoothstep of log10 Y from -2 to 0.6."""
    _check.real(Y, "Y")
    Y = _check.as_float(Y)
    x = jnp.clip((log10_floor(Y, 10.0**LOG_LOW) - LOG_LOW) / (LOG_HIGH - LOG_LOW), 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def blue_shift(
    rgb: Float[ArrayLike, "*batch 3"], *, chromaticities: Sequence[float] | None = None
) -> Float[Array, "*batch 3"]:
    """Night colour loss and blue shift, per pixel (Jensen et al. 2001).

    Args:
        rgb: linear RGB in cd/m², channels last, any leading shape.
        chromaticities: the image's primaries (``None``: Rec.709/D65).

    Returns:
        RGB in cd/m²; non-finite pixels are returned unchanged. A pixel without a defined
        chromaticity (X + Y + Z <= 0) takes the blue-shift white.
    """
    ch = chroma_key(chromaticities)
    return _blue_shift(check_rgb(rgb), ch)


@functools.partial(jax.jit, static_argnums=1)
def _blue_shift(rgb: Array, chromaticities: tuple[float, ...] | None) -> Array:
    x_, ok = sanitize(rgb)
    # linear in the pixel but for s: computed on the pixel × c (exact, 1 below 2^64 cd/m²),
    # whose XYZ cannot overflow (Z of a white is 1.09 RGB; the inverse matrix reaches 3.2);
    # at_scale keeps the backward pass from carrying the cotangent 1/c through it
    out = at_scale(functools.partial(_blue_shift_scaled, chromaticities), x_, headroom(x_))
    return restore(out, rgb, ok)


def _blue_shift_scaled(chromaticities: tuple[float, ...] | None, x_: Array, c: Array) -> Array:
    """Blue shift of the pixels ``x_`` = RGB × ``c`` (``c`` per pixel), times ``c``."""
    X, Y, Z = rgb_to_xyz(x_, chromaticities)
    V = scotopic_unscaled(x_, chromaticities)  # x_ is scaled already
    s = blue_shift_weight(Y / c[..., 0])
    # chromaticity from X, Y, Z over the pixel's largest |X|, |Y|, |Z| (constant under
    # differentiation): d(X/tot)/d tot = -X/tot² would over/underflow tot² at 1e±20 cd/m²
    r = largest_component_reciprocal(X, Y, Z)
    xr, yr = X * r, Y * r
    tot = (xr + yr) + Z * r
    has = tot > 0
    tot_s = jnp.where(has, tot, 1.0)
    cx = jnp.where(has, xr / tot_s, BLUE_WHITE[0])
    cy = jnp.where(has, yr / tot_s, BLUE_WHITE[1])
    cx = (1.0 - s) * BLUE_WHITE[0] + s * cx
    cy = (1.0 - s) * BLUE_WHITE[1] + s * cy
    Yn = ROD_SCALE * (1.0 - s) * V + s * Y
    good = cy > 0  # false only for pixels with negative chromaticity (out-of-gamut noise)
    cys = jnp.where(good, cy, 1.0)
    Xn = jnp.where(good, cx * Yn / cys, X)
    Zn = jnp.where(good, (1.0 - cx - cy) * Yn / cys, Z)
    Yn = jnp.where(good, Yn, Y)
    return xyz_to_rgb(Xn, Yn, Zn, chromaticities)


__all__ = ["BLUE_WHITE", "ROD_SCALE", "blue_shift", "blue_shift_weight"]

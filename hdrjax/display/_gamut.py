"""Gamut mapping: linear RGB brought inside a display's gamut ``[0, upper]³``.

Numeric contract: input is linear RGB ``(..., 3)`` in the display's primaries (after
:func:`hdrjax.spaces.convert`), display-referred (white = 1) or, with ``upper=None``,
unbounded above; output has the same shape and dtype with every channel in ``[0, upper]``
(``[0, ∞)`` for ``upper=None``). NaN channels are taken as 0, −Inf as 0 and +Inf as the
largest value (so they end at ``upper``); the result is never NaN, and gradients are finite
everywhere, black and grey pixels included.

Converting wide-gamut or XYZ data to a smaller display gamut gives negative channels (a
colour the display's primaries cannot mix) and channels above white. The methods:

- ``"clip"``: each channel clipped to ``[0, upper]`` (what encoding did before): exact for
  in-gamut colours, but a clipped channel moves the hue (a saturated orange beyond white
  turns yellow) and a negative one raises the luminance.
- ``"luminance"``: a colour with a negative channel moves along the line to the grey of its
  own luminance ``Y`` (``(Y, Y, Y)``, ``Y = w · RGB`` with the display's weights) just far
  enough that its smallest channel is 0: luminance and hue (the direction from grey) are
  kept, saturation is lost. A colour with ``Y ≤ 0`` has no such grey and becomes black.
  Then a colour whose largest channel exceeds ``upper`` is scaled down to it: hue and
  saturation are kept, luminance is lost (no colour of a luminance above white fits).
  In-gamut colours are left exactly as they are.
- ``"compress"``: the ACES Reference Gamut Compression (Academy of Motion Picture Arts and
  Sciences 2021, ACES 1.3 ``LMT.Academy.ReferenceGamutCompress``): per channel, the
  distance from the achromatic axis ``d = (max(RGB) − c) / max(RGB)`` (``d > 1`` is a
  negative channel) is left alone below a threshold ``t`` and compressed beyond it by
  ``t + s · n / (1 + n^p)^(1/p)``, ``n = (d − t) / s``, with ``s`` chosen so that the
  limit distance ``l`` lands on the gamut boundary (``d = 1``). The Academy's constants
  (cyan, magenta, yellow = the R, G, B distances): ``l = (1.147, 1.264, 1.312)``,
  ``t = (0.815, 0.803, 0.880)``, ``p = 1.2``. Distances beyond what the curve brings
  inside (colours farther out than the limits) are finished by ``"luminance"`` rather than
  clipped; over-range colours are scaled as in ``"luminance"``. Smooth: neighbouring
  out-of-gamut colours stay distinct instead of piling up on the boundary, at the price of
  desaturating the outer part of the gamut too (colours with a channel below 12–20 % of
  their largest, in gamut or not).

Why ``"luminance"`` is the default (:data:`DEFAULT_GAMUT`): it changes only the colours the
display cannot show, and keeps their luminance and hue. Measured on
``Chromaticities/XYZ.exr`` of the OpenEXR sample images (Academy Software Foundation,
``openexr-images``; a photograph stored with CIE XYZ primaries, 610×406) converted to
sRGB: 319 pixels (0.13 %) have a negative channel (by at most 1.6e-4) and 9.8 % a
channel above 1. ``"luminance"`` moves only those and keeps the luminance of the
negative ones to float32 rounding (1.2e-7); ``"compress"`` also moves 4.6 % of the
pixels that were inside the gamut (by up to 0.065) and raises the negative ones'
luminance by 1.2 % on average (24 % at most). On colours of the BT.2020 gamut boundary
converted to sRGB (all outside it, channels down to −0.66), luminance changes by 16 % on
average with ``"clip"`` (hue, the direction from grey in linear RGB, by 5°, at most
20°), by 23 % with ``"compress"`` (4.7°, at most 16°) and not at all with
``"luminance"``. ``"compress"`` is for images with large regions far out of gamut
(wide-gamut renders, camera data), where ``"luminance"`` flattens neighbouring colours
onto the boundary and ``"compress"`` keeps them apart.

Both non-clip methods act per pixel and are continuous in the colour; values below
``1e-15`` in magnitude are taken as 0 (invisible at any bit depth) so that no division in
the gradient overflows.
"""

from collections.abc import Sequence
from typing import Literal

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._colour import REC709_WEIGHTS, channel_max, channel_min

GamutMethod = Literal["clip", "luminance", "compress"]
GAMUT_METHODS: tuple[str, ...] = ("clip", "luminance", "compress")
DEFAULT_GAMUT: GamutMethod = "luminance"
"""The gamut mapping of :func:`hdrjax.display.encode` for a display (see the module doc)."""

RGC_LIMIT = (1.147, 1.264, 1.312)
"""ACES 1.3 Reference Gamut Compression: distances (R, G, B) compressed onto the boundary."""
RGC_THRESHOLD = (0.815, 0.803, 0.880)
"""ACES 1.3 Reference Gamut Compression: distances (R, G, B) left untouched below."""
RGC_POWER = 1.2
"""ACES 1.3 Reference Gamut Compression: the compression curve's exponent."""

LARGEST = 1e30
"""Magnitudes are clipped here (and +Inf is taken as this): beyond any display's range,
and far enough below float32's maximum that a conversion matrix cannot overflow."""
# magnitudes below are 0: then every denominator of the mapping is ≥ 1e-15 and its square
# in a gradient (1e-30) stays a normal float32
_FLUSH = 1e-15
# a distance is computed only where it is below this (farther ones are compressed onto
# the curve's asymptote): (max − c) / max overflows float32 for a tiny max
_MAX_DISTANCE = 1e6


def _rgc_scale() -> np.ndarray:
    # ACES: s = (l − t) / (((1 − t) / (l − t))^(−p) − 1)^(1/p), the y = 1 intersect
    lim, thr = np.asarray(RGC_LIMIT), np.asarray(RGC_THRESHOLD)
    return (lim - thr) / (((1.0 - thr) / (lim - thr)) ** -RGC_POWER - 1.0) ** (1.0 / RGC_POWER)


def method_name(method: str, name: str = "method") -> str:
    """``method`` in canonical form (case and separators do not matter), or ``ValueError``."""
    key = _check.name_key(method) if isinstance(method, str) else None
    if key not in GAMUT_METHODS:
        options = ", ".join(map(repr, GAMUT_METHODS))
        raise ValueError(f"{name}: expected one of {options}, got {method!r}")
    return key


def flush(rgb: Array) -> Array:
    """Magnitudes below 1e-15 as 0."""
    return jnp.where(jnp.abs(rgb) < _FLUSH, 0.0, rgb)


def sanitise(rgb: Array) -> Array:
    """NaN and −Inf as 0, +Inf as :data:`LARGEST`, magnitudes clipped to it, tiny ones 0."""
    x = jnp.nan_to_num(rgb, nan=0.0, posinf=LARGEST, neginf=0.0)
    return flush(jnp.clip(x, -LARGEST, LARGEST))


def _vector(values: Sequence[float], like: Array) -> Array:
    # (1, ..., 1, 3): explicit broadcasting (the tests raise on implicit rank promotion)
    return jnp.asarray(values, like.dtype).reshape((1,) * (like.ndim - 1) + (3,))


def _towards_luminance(rgb: Array, weights: Sequence[float]) -> Array:
    y = rgb @ jnp.asarray(weights, rgb.dtype)
    y = y[..., None]
    lo = channel_min(rgb, keepdims=True)
    move = (lo < 0) & (y > 0)
    # Y + t (c − Y) with t = Y / (Y − min), which puts the smallest channel on 0, written
    # as t (c − min): no cancellation (t is within an ulp of 1 for a bright colour with a
    # slightly negative channel), the smallest channel exactly 0, and no product of two
    # large values to overflow. The denominator is at least |min| ≥ 1e-15 where used, 1
    # elsewhere (finite gradients)
    moved = (rgb - lo) * (y / jnp.where(move, y - lo, 1.0))
    return jnp.where(lo < 0, jnp.where(y > 0, moved, 0.0), rgb)


def _compress(rgb: Array) -> Array:
    ach = channel_max(rgb, keepdims=True)
    gap = ach - rgb
    near = (ach > 0) & (gap <= _MAX_DISTANCE * ach)
    dist = jnp.where(near, gap / jnp.where(near, ach, 1.0), _MAX_DISTANCE)
    thr = _vector(RGC_THRESHOLD, rgb)
    scl = _vector(_rgc_scale(), rgb)
    above = dist > thr
    n = jnp.where(above, (dist - thr) / scl, 1.0)
    squashed = thr + scl * n / jnp.power(1.0 + jnp.power(n, RGC_POWER), 1.0 / RGC_POWER)
    # channels below the threshold are returned as they came (ach − d·ach would round);
    # ACES leaves an achromatic value of 0 alone; ≤ 0 (no positive channel) ends black
    return jnp.where(above & (ach > 0), ach - squashed * ach, rgb)


def fit_below(rgb: Array, upper: float | None, *, clip: bool) -> Array:
    """Non-negative ``rgb`` brought to at most ``upper``: per channel (``clip``) or by
    scaling each pixel whose largest channel exceeds it (hue and saturation kept)."""
    if upper is None:
        return jnp.maximum(rgb, 0.0)
    if not clip:
        hi = channel_max(rgb, keepdims=True)
        over = hi > upper
        rgb = rgb * jnp.where(over, upper / jnp.where(over, hi, 1.0), 1.0)
    # also takes up the rounding of the scaling and of the move towards grey (≈ 1 ulp)
    return jnp.clip(rgb, 0.0, upper)


def map_gamut(rgb: Array, method: str, weights: Sequence[float], upper: float | None) -> Array:
    """:func:`gamut_map` without argument checks, on :func:`sanitise`'d values."""
    if method == "compress":
        rgb = _towards_luminance(_compress(rgb), weights)
    elif method == "luminance":
        rgb = _towards_luminance(rgb, weights)
    return fit_below(rgb, upper, clip=method == "clip")


def check_weights(weights: Sequence[float] | None) -> tuple[float, float, float]:
    """Luminance weights (Rec.709 for ``None``) that sum to 1, as a tuple."""
    _check.weights(weights)
    w = REC709_WEIGHTS if weights is None else tuple(float(v) for v in weights)
    # (Y, Y, Y) has luminance Y only if the weights sum to 1 (white has Y = 1)
    if abs(sum(w) - 1.0) > 1e-3:
        raise ValueError(f"weights: expected three numbers summing to 1, got {weights!r}")
    return w[0], w[1], w[2]


def gamut_map(
    rgb: Float[ArrayLike, "*batch 3"],
    method: GamutMethod = DEFAULT_GAMUT,
    *,
    weights: Sequence[float] | None = None,
    upper: float | None = 1.0,
) -> Float[Array, "*batch 3"]:
    """Bring linear RGB into the gamut ``[0, upper]³`` of its own primaries.

    Args:
        rgb: linear RGB in the display's primaries, channels last; any float dtype
            (float16 and integers are computed in JAX's default float).
        method: ``"clip"``, ``"luminance"`` (default) or ``"compress"`` (ACES Reference
            Gamut Compression, Academy 2021); see the module docstring for each.
        weights: the primaries' luminance weights (Rec.709 by default; summing to 1), for
            the grey of ``"luminance"`` (and ``"compress"``'s last step).
        upper: the white level (1 for display-referred values), or ``None`` to keep values
            above it (scene-referred data that a tone curve or the BT.2390 EETF handles).

    Returns:
        RGB of the same shape with every channel in ``[0, upper]``; never NaN.

    Raises:
        ValueError: not channels-last RGB, an unknown method, bad weights or ``upper``.

    >>> import jax.numpy as jnp
    >>> out = gamut_map(jnp.array([0.5, -0.1, 0.2]), "luminance")  # Y = 0.0492 kept
    >>> [round(v, 4) for v in out.tolist()]
    [0.1979, 0.0, 0.099]
    """
    _check.real(rgb, "rgb")
    x = _check.as_float(rgb)
    if x.ndim < 1 or x.shape[-1] != 3:
        raise ValueError(f"rgb: expected channels-last RGB (..., 3), got shape {x.shape}")
    method = method_name(method)
    w = check_weights(weights)
    if upper is not None:
        _check.positive(upper, "upper")
    return map_gamut(sanitise(x), method, w, upper)


__all__ = ["DEFAULT_GAMUT", "GAMUT_METHODS", "RGC_LIMIT", "RGC_POWER", "RGC_THRESHOLD", "gamut_map"]

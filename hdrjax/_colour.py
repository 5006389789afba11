"""Colour primaries and luminance: the one place where luminance weights come from; and the
per-pixel channel arithmetic (matrices, channel extrema) written as slices for XLA:CPU.

Luminance is the Y row of the RGB→XYZ matrix of the image's primaries and white point
(Rec.709/sRGB with D65 unless the file says otherwise, e.g. an EXR ``chromaticities``
attribute). The matrix is SMPTE RP 177's (:func:`normalised_primary_matrix`), the same
construction as OpenEXR's ``RGBtoXYZ`` and colour-science's, which the tests compare with.
"""

from collections.abc import Sequence

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from . import _check

REC709_CHROMATICITIES: tuple[float, ...] = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290)
"""(x_r, y_r, x_g, y_g, x_b, y_b, x_w, y_w) of Rec.709/sRGB primaries with a D65 white."""

REC709_WEIGHTS: tuple[float, float, float] = (0.2126, 0.7152, 0.0722)
"""Rec.709 luminance weights (ITU-R BT.709-6, item 3.2), as the standard rounds them."""


def normalised_primary_matrix(chromaticities: Sequence[float]) -> np.ndarray:
    """RGB→XYZ matrix of primaries and white ``(x_r, y_r, x_g, y_g, x_b, y_b, x_w, y_w)``.

    SMPTE RP 177-1993 (3.3): the primaries' XYZ (``Y = 1``) as columns, each scaled so that
    RGB = (1, 1, 1) maps to the white point with ``Y_w = 1``. Equal to colour-science's
    ``normalised_primary_matrix`` (tested); written here because ``import colour`` costs
    about 3 s, more than the command line's whole start-up budget.
    """
    c = np.asarray(chromaticities, dtype=np.float64).reshape(4, 2)
    x, y = c[:, 0], c[:, 1]
    # primaries as (x, y, z) columns (Y = y), not divided by y: XYZ-as-RGB files have
    # primaries with y = 0 (red (1, 0)); the solved scales absorb the 1/y
    xyz = np.stack([x, y, 1.0 - x - y])  # columns: r, g, b, white
    white = xyz[:, 3] / xyz[1, 3]  # white with Y_w = 1
    scale = np.linalg.solve(xyz[:, :3], white)
    return xyz[:, :3] * scale


def luminance_weights(chromaticities: Sequence[float] | None = None) -> tuple[float, float, float]:
    """Luminance weights (the Y row of RGB→XYZ) for the given primaries.

    Args:
        chromaticities: ``(x_r, y_r, x_g, y_g, x_b, y_b, x_w, y_w)`` as in an OpenEXR
            ``chromaticities`` attribute. ``None`` means Rec.709/sRGB with D65, for which
            the standard's rounded weights (0.2126, 0.7152, 0.0722) are returned.

    Returns:
        Three floats summing to 1 (up to rounding). They may be negative for wide-gamut
        primaries (ACES AP0 gives a negative blue weight).

    Raises:
        ValueError: if ``chromaticities`` does not hold 8 finite numbers or the primaries are
            degenerate (collinear).
    """
    if chromaticities is None:
        return REC709_WEIGHTS
    c = np.asarray(chromaticities, dtype=np.float64).reshape(-1)
    if c.shape != (8,) or not np.all(np.isfinite(c)):
        raise ValueError(
            f"chromaticities: expected 8 finite numbers (xr, yr, xg, yg, xb, yb, xw, yw), got {c!r}"
        )
    if np.allclose(c, REC709_CHROMATICITIES, atol=1e-4):
        return REC709_WEIGHTS
    try:
        with np.errstate(all="raise"):
            npm = normalised_primary_matrix(c)
    except (np.linalg.LinAlgError, FloatingPointError) as e:
        raise ValueError(f"chromaticities {c.tolist()} are degenerate: {e}") from None
    w = npm[1]
    if not np.all(np.isfinite(w)):
        raise ValueError(f"chromaticities {c.tolist()} are degenerate (non-finite weights)")
    return (float(w[0]), float(w[1]), float(w[2]))


def luminance(
    rgb: Float[ArrayLike, "*batch H W 3"], weights: Sequence[float] | None = None
) -> Float[Array, "*batch H W"]:
    """Per-pixel luminance ``Y = w_r R + w_g G + w_b B`` of a linear RGB image.

    Args:
        rgb: linear RGB, channels last; any float dtype (float16 is computed in float32).
        weights: luminance weights, Rec.709 by default (see :func:`luminance_weights`).

    Returns:
        Luminance in the image's units, shape ``rgb.shape[:-1]``.
    """
    _check.weights(weights)
    rgb = _check.rgb_pixels(rgb)
    w = REC709_WEIGHTS if weights is None else tuple(float(v) for v in weights)
    # Written as three scaled slices: on XLA:CPU this fuses into the consumer and ran
    # 2.7x faster than `rgb @ w` at 4096² (benchmarks/bench_reinhard.py).
    return rgb[..., 0] * w[0] + rgb[..., 1] * w[1] + rgb[..., 2] * w[2]


def apply_matrix(x: Float[Array, "*batch 3"], m: ArrayLike) -> Float[Array, "*batch 3"]:
    """``m @ pixel`` for every pixel of ``x`` (channels last), ``m`` a 3×3 matrix.

    Written as each channel's slice times a column of ``m``: XLA:CPU fuses that into the
    consumer's pass, where a dot (``einsum``, ``x @ m.T``) with its inner dimension of 3
    writes the converted image out first and ran more than ten times slower at 1024². The
    columns are broadcast along the channel axis rather than the three output channels
    concatenated: a concatenation branches on the channel in the fused loop, which made
    tone mapping an XYZ file 1.2–1.5× as slow as the same pixels in sRGB
    (``benchmarks/bench_colour.py``).
    """
    m = jnp.asarray(m, x.dtype)
    col = [m[:, k].reshape((1,) * (x.ndim - 1) + (3,)) for k in range(3)]
    return x[..., 0:1] * col[0] + x[..., 1:2] * col[1] + x[..., 2:3] * col[2]


def channel_max(x: Float[Array, "*batch 3"], keepdims: bool = False) -> Array:
    """The largest of each pixel's three channels, as slices (a reduction over the
    3-wide last axis ran five times slower on XLA:CPU)."""
    m = jnp.maximum(jnp.maximum(x[..., 0:1], x[..., 1:2]), x[..., 2:3])
    return m if keepdims else m[..., 0]


def channel_min(x: Float[Array, "*batch 3"], keepdims: bool = False) -> Array:
    """The smallest of each pixel's three channels (as :func:`channel_max`)."""
    m = jnp.minimum(jnp.minimum(x[..., 0:1], x[..., 1:2]), x[..., 2:3])
    return m if keepdims else m[..., 0]


__all__ = [
    "REC709_CHROMATICITIES",
    "REC709_WEIGHTS",
    "apply_matrix",
    "channel_max",
    "channel_min",
    "luminance",
    "luminance_weights",
]

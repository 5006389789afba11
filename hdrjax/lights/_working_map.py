"""The environment map as the light finders read it: input checks, batch axes, luminance
weights as a compile key, and the map at the working resolution.

Shared by Loghin (2019) light detection (:mod:`hdrjax.lights._loghin2019`, step 1 of its
pipeline) and Debevec (2005) median cut (:mod:`hdrjax.lights._debevec2005`), which reduce the
map the same way so that both see the same pixels.

Numeric contract: input is linear RGB, channels last, any real dtype (float16 and integers are
computed in the default float). A pixel with a NaN/±Inf channel counts as zero, negative
values are clamped to zero.
"""

import functools
import math
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from .. import _check
from .._colour import REC709_WEIGHTS, luminance


def image_shape(image: ArrayLike, name: str) -> tuple[tuple[int, ...], int, int]:
    """``(batch, H, W)`` of a ``(..., H, W, 3)`` image; ValueError otherwise."""
    _check.real(image, name)
    shape = np.shape(image)
    if len(shape) < 3 or shape[-1] != 3:
        raise ValueError(f"{name}: expected channels-last RGB (..., H, W, 3), got shape {shape}")
    _check.nonempty(shape, name)
    batch = tuple(int(v) for v in shape[:-3])  # may be empty (0 frames: 0 light sets)
    h, w = int(shape[-3]), int(shape[-2])
    if h < 2 or w < 4:
        raise ValueError(
            f"{name}: expected at least 2 rows and 4 columns (..., H >= 2, W >= 4, 3),"
            f" got shape {shape}"
        )
    return batch, h, w


def flatten_batch(x: Array, batch: tuple[int, ...]) -> Array:
    """The batch axes ``batch`` (a prefix of ``x.shape``) flattened into one."""
    return x.reshape((math.prod(batch),) + x.shape[len(batch) :])


def flatten_batch_float(x: Array, batch: tuple[int, ...]) -> Array:
    """Batch axes flattened into one; float16/integer input computed in the default float."""
    return _check.as_float(flatten_batch(x, batch))


def weights_key(weights: Sequence[float] | None) -> tuple[float, float, float] | None:
    """Hashable luminance weights; Rec.709 becomes ``None`` so that both share a compile."""
    if weights is None:
        return None
    w = tuple(float(v) for v in weights)
    if len(w) != 3 or not all(math.isfinite(v) for v in w):
        raise ValueError(f"weights: expected three finite numbers, got {weights!r}")
    return None if w == REC709_WEIGHTS else w


def working_size(in_h: int, in_w: int, width: int) -> tuple[int, int, int]:
    """``(factor, h, w)``: reduce by the smallest integer factor that fits ``width``; factor 0
    means "not a divisor: resample to (h, w)"."""
    if int(width) != width or width < 4:
        raise ValueError(f"width: expected an integer >= 4, got {width!r}")
    if in_w <= width:
        return 1, in_h, in_w
    f = -(-in_w // int(width))
    if in_w % f == 0 and in_h % f == 0:
        return f, in_h // f, in_w // f
    w = in_w // f
    return 0, max(2, round(in_h * w / in_w)), w


def working_rgb(
    rgb: Array, factor: int, hw: tuple[int, int], weights: tuple[float, float, float] | None
) -> tuple[Array, Array]:
    """Step 1: the cleaned map at the working resolution and each pixel's peak luminance
    (the largest input pixel it covers; the working luminance itself when not reduced by
    an integer factor)."""
    if factor >= 1:
        return reduce_blocks(rgb, factor, weights)
    small = jax.image.resize(reduce_blocks(rgb, 1, weights)[0], hw + (3,), "linear")
    small = jnp.maximum(small, 0)
    return small, jnp.maximum(luminance(small, weights), 0)


def reduce_blocks(
    rgb: Array, f: int, weights: tuple[float, float, float] | None
) -> tuple[Array, Array]:
    """Clean and box-average ``f × f`` blocks of the input; also each block's peak luminance.

    A pixel with any non-finite channel (its luminance is then non-finite) counts as zero;
    negative values are clamped to zero. The blocks are summed as slices of a
    ``(h, f, w·f·3)`` view, which XLA:CPU runs in one pass (a 5-D reshape-and-reduce, or
    strided slices of the channel axis, ran 3–5x slower).
    """
    lum = luminance(rgb, weights)
    ok = jnp.isfinite(lum)
    clean = jnp.where(ok[..., None], jnp.maximum(rgb, 0), 0)
    lum = jnp.where(ok, jnp.maximum(lum, 0), 0)
    if f == 1:
        return clean, lum
    return block_mean(clean, f), block_max(lum, f)


def block_mean(x: Array, f: int) -> Array:
    """Mean of the ``f × f`` blocks of an ``(H, W, 3)`` image (:func:`reduce_blocks`)."""
    H, W = x.shape[0] // f, x.shape[1] // f
    x = x.reshape(H, f, W * f * 3)
    x = sum(x[:, i] for i in range(f)).reshape(H, W, f, 3)
    return sum(x[:, :, j] for j in range(f)) / (f * f)


def block_max(x: Array, f: int) -> Array:
    """Maximum of the ``f × f`` blocks of an ``(H, W)`` image."""
    H, W = x.shape[0] // f, x.shape[1] // f
    p = x.reshape(H, f, W * f)
    p = functools.reduce(jnp.maximum, [p[:, i] for i in range(f)]).reshape(H, W, f)
    return functools.reduce(jnp.maximum, [p[:, :, j] for j in range(f)])


__all__ = [
    "block_max",
    "block_mean",
    "flatten_batch",
    "flatten_batch_float",
    "image_shape",
    "reduce_blocks",
    "weights_key",
    "working_rgb",
    "working_size",
]

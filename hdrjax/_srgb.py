"""The sRGB transfer function (IEC 61966-2-1), shared by the display encodings and the
operators that reproduce a peer working on sRGB-encoded values."""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from . import _check
from ._scale import positive_power

SRGB_THRESHOLD = 0.0031308


def clip_unit(x: Array) -> Array:
    """NaN → 0, +Inf → 1, −Inf → 0, then clipped to [0, 1]."""
    x = jnp.nan_to_num(x, nan=0.0, posinf=1.0, neginf=0.0)
    return jnp.clip(x, 0.0, 1.0)


def srgb_encode(linear: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """sRGB transfer function (IEC 61966-2-1) after clipping to [0, 1]; differentiable."""
    _check.real(linear, "linear")
    x = clip_unit(jnp.asarray(linear, jnp.result_type(float)))
    hi = x > SRGB_THRESHOLD
    powed = 1.055 * positive_power(jnp.where(hi, x, 1.0), 1.0 / 2.4) - 0.055
    return jnp.where(hi, powed, 12.92 * x)


def srgb_decode(encoded: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """Inverse of :func:`srgb_encode` on [0, 1]."""
    _check.real(encoded, "encoded")
    y = clip_unit(jnp.asarray(encoded, jnp.result_type(float)))
    hi = y > 12.92 * SRGB_THRESHOLD
    return jnp.where(hi, positive_power((jnp.where(hi, y, 1.0) + 0.055) / 1.055, 2.4), y / 12.92)
